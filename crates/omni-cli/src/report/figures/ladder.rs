//! The error ladder: held-out path RMS per rung, with the noise floor.

use super::{DrawError, FONT, Figure, MODEL_COLOURS, colour, draw, text_centre};
use crate::report::Report;
use plotters::prelude::*;

/// The error ladder: held-out path RMS per rung, with the noise floor.
pub fn ladder(r: &Report) -> Result<Figure, DrawError> {
    let n = r.ladder.len();
    let top = r.ladder.iter().map(|x| x.1 * 1000.0).chain(r.noise_floor_m.map(|f| f * 1000.0)).fold(0.0, f64::max);
    let top = if top > 0.0 && top.is_finite() { top * 1.15 } else { 1.0 };
    let labels: Vec<String> = r.ladder.iter().map(|x| x.0.clone()).collect();
    let svg = draw((900, 380), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption("Error ladder: held-out path RMS", (FONT, 18))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(64)
            .build_cartesian_2d((0..n - 1).into_segmented(), 0.0..top)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .light_line_style(TRANSPARENT)
            .y_desc("path RMS (mm, heading 1 m/rad)")
            .x_label_formatter(&|v| match v {
                SegmentValue::CenterOf(i) => labels.get(*i).cloned().unwrap_or_default(),
                _ => String::new(),
            })
            .draw()?;
        for (i, (label, path_m, eq6)) in r.ladder.iter().enumerate() {
            let c = colour(i.min(MODEL_COLOURS.len() - 1));
            chart.draw_series(Histogram::vertical(&chart).style(c.filled()).margin(40).data([(i, path_m * 1000.0)]))?;
            chart.draw_series(std::iter::once(Text::new(
                format!("{:.2} mm · Eq.6 {:.4}", path_m * 1000.0, eq6),
                (SegmentValue::CenterOf(i), path_m * 1000.0 + top * 0.03),
                (FONT, 13).into_font().color(&BLACK).pos(text_centre()),
            )))?;
            let _ = label;
        }
        if let Some(f) = r.noise_floor_m {
            let y = f * 1000.0;
            chart
                .draw_series(DashedLineSeries::new(
                    [(SegmentValue::Exact(0), y), (SegmentValue::Exact(n), y)],
                    6,
                    4,
                    RED.stroke_width(2),
                ))?
                .label(format!("noise floor {y:.2} mm"))
                .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], RED.stroke_width(2)));
            chart.configure_series_labels().background_style(WHITE.mix(0.85)).border_style(BLACK).draw()?;
        }
        Ok(())
    })?;
    Ok(Figure {
        id: "ladder".into(),
        title: "Error ladder".into(),
        caption: format!(
            "Path RMS on the {} after each step (design → fitted matrix → each added effect); Eq. 6 is the \
             paper's end-pose cost. The red dashed line is the noise floor seen at standstill: a bar well above \
             it means a physical effect is still missing.",
            r.figure_runs
        ),
        svg,
    })
}
