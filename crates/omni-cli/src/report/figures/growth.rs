//! Error growth along the runs: mean position and heading error against the fraction of run time.

use super::{DrawError, FONT, Figure, colour, draw, upper_left_legend};
use crate::report::Report;
use plotters::prelude::*;

/// Mean position and heading error against the fraction of run time, per model.
pub fn growth(r: &Report) -> Result<Figure, DrawError> {
    let g = &r.growth;
    let svg = draw((900, 360), |root| {
        let (left, right) = root.split_horizontally(450);
        for (area, data, scale, unit, title) in [
            (&left, &g.position_m, 1000.0, "mm", "position error"),
            (&right, &g.heading_rad, 180.0 / std::f64::consts::PI, "deg", "|heading error|"),
        ] {
            let top = data.iter().flatten().copied().filter(|v| v.is_finite()).fold(0.0, f64::max) * scale * 1.1;
            let top = if top > 0.0 { top } else { 1.0 };
            let mut chart = ChartBuilder::on(area)
                .caption(format!("mean {title} along the runs"), (FONT, 15))
                .margin(10)
                .x_label_area_size(34)
                .y_label_area_size(52)
                .build_cartesian_2d(0.0..1.0, 0.0..top)?;
            chart
                .configure_mesh()
                .light_line_style(RGBColor(240, 240, 240))
                .x_desc("fraction of run time")
                .y_desc(format!("{title} ({unit})"))
                .draw()?;
            for (m, curve) in data.iter().enumerate() {
                let c = colour(m);
                let pts: Vec<(f64, f64)> =
                    g.fraction.iter().zip(curve).filter(|(_, v)| v.is_finite()).map(|(f, v)| (*f, v * scale)).collect();
                chart
                    .draw_series(LineSeries::new(pts, c.stroke_width(2)))?
                    .label(r.models[m].label.clone())
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], c.stroke_width(2)));
            }
            upper_left_legend(&mut chart)?;
        }
        Ok(())
    })?;
    Ok(Figure {
        id: "growth".into(),
        title: "Error growth along the path".into(),
        caption: "Mean error over the held-out runs at each fraction of run time. Odometry errors accumulate: a \
                  wrong scale grows linearly with distance, a wrong rotation rate bends the path and grows faster; \
                  a clock offset shows at the starts and stops."
            .into(),
        svg,
    })
}
