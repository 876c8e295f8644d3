//! The diagnosis ranking: held-out gain of each candidate effect.

use super::{DrawError, FONT, Figure, draw, span};
use omni_ga::diagnose::Diagnosis;
use plotters::prelude::*;

/// The diagnosis ranking: held-out gain of each candidate effect.
pub fn ranking(d: &Diagnosis) -> Result<Figure, DrawError> {
    let n = d.ranking.len();
    let gains: Vec<f64> = d.ranking.iter().map(|c| 100.0 * c.held_out_gain).collect();
    let (lo, hi) = span(gains.iter().copied().chain([0.0]), 0.1);
    let names: Vec<String> = d.ranking.iter().map(|c| c.effect.clone()).collect();
    let svg = draw((900, 60 + 30 * n as u32), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption("Candidate effects: fall of the held-out path cost when added (%)", (FONT, 15))
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(150)
            .build_cartesian_2d(lo.min(0.0)..hi.max(1.0), (0..n - 1).into_segmented())?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .light_line_style(TRANSPARENT)
            .x_desc("held-out gain (%)")
            .y_labels(n)
            .y_label_formatter(&|v| match v {
                SegmentValue::CenterOf(i) => names.get(n - 1 - *i).cloned().unwrap_or_default(),
                _ => String::new(),
            })
            .draw()?;
        for (k, c) in d.ranking.iter().enumerate() {
            let i = n - 1 - k;
            let col = if c.absorbed {
                RGBColor(190, 190, 190)
            } else if d.verdict.as_deref() == Some(c.effect.as_str()) {
                RGBColor(44, 160, 44)
            } else {
                RGBColor(31, 119, 180)
            };
            chart.draw_series(Histogram::horizontal(&chart).style(col.filled()).margin(5).data([(i, gains[k])]))?;
        }
        Ok(())
    })?;
    Ok(Figure {
        id: "ranking".into(),
        title: "Which effect is missing".into(),
        caption: format!(
            "Each catalogued effect refitted with the model on the training runs and judged on held-out runs ({}). \
             Green: the verdict; grey: absorbed (the model already expresses it). Verdict: {}",
            d.held_out, d.verdict_text
        ),
        svg,
    })
}
