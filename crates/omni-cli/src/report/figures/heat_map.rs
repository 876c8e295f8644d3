//! Mean end position error over α × ω, on a perceptually ordered colour scale.

use super::by_command::by_command;
use super::{DrawError, FONT, Figure, draw, left_mid, mid, right_mid};
use crate::report::Report;
use plotters::prelude::*;

/// A perceptually ordered colour for `t` in 0…1 (dark blue → yellow, after viridis' end points).
fn heat(t: f64) -> RGBColor {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.0, [68.0, 1.0, 84.0]),
        (0.25, [59.0, 82.0, 139.0]),
        (0.5, [33.0, 145.0, 140.0]),
        (0.75, [94.0, 201.0, 98.0]),
        (1.0, [253.0, 231.0, 37.0]),
    ];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let k = STOPS.iter().position(|s| s.0 >= t).unwrap_or(STOPS.len() - 1).max(1);
    let (t0, c0) = STOPS[k - 1];
    let (t1, c1) = STOPS[k];
    let f = (t - t0) / (t1 - t0);
    let ch = |i: usize| (c0[i] + f * (c1[i] - c0[i])).round().clamp(0.0, 255.0) as u8;
    RGBColor(ch(0), ch(1), ch(2))
}

/// Mean end position error over α × ω, one panel per model after the design.
pub fn heat_map(r: &Report) -> Result<Figure, DrawError> {
    let (alphas, omegas, mean) = by_command(r);
    let shown: Vec<usize> = if r.models.len() > 1 { (1..r.models.len()).collect() } else { vec![0] };
    let vmax = shown
        .iter()
        .flat_map(|&m| mean[m].iter().flatten().copied())
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max)
        .max(1e-9)
        * 1000.0;
    let (na, nw) = (alphas.len().max(1) as f64, omegas.len().max(1) as f64);
    let panel_h = 90 + 34 * omegas.len() as u32;
    let svg = draw((900, panel_h * shown.len() as u32), |root| {
        let panels = root.split_evenly((shown.len(), 1));
        for (area, &m) in panels.iter().zip(&shown) {
            let mut chart = ChartBuilder::on(area)
                .caption(format!("{}: mean end position error (mm)", r.models[m].label), (FONT, 15))
                .margin(8)
                .build_cartesian_2d(-1.3..na + 1.6, -0.9..nw)?;
            for (iw, row) in mean[m].iter().enumerate() {
                for (ia, v) in row.iter().enumerate() {
                    let (x, y) = (ia as f64, iw as f64);
                    let c = if v.is_finite() { heat(v * 1000.0 / vmax) } else { RGBColor(235, 235, 235) };
                    chart.draw_series(std::iter::once(Rectangle::new(
                        [(x + 0.03, y + 0.05), (x + 0.97, y + 0.95)],
                        c.filled(),
                    )))?;
                    if v.is_finite() {
                        let text_colour = if v * 1000.0 / vmax > 0.6 { BLACK } else { WHITE };
                        chart.draw_series(std::iter::once(Text::new(
                            format!("{:.0}", v * 1000.0),
                            (x + 0.5, y + 0.5),
                            (FONT, 11).into_font().color(&text_colour).pos(mid()),
                        )))?;
                    }
                }
                chart.draw_series(std::iter::once(Text::new(
                    format!("ω {:+.2}", omegas[iw]),
                    (-0.1, iw as f64 + 0.5),
                    (FONT, 12).into_font().color(&BLACK).pos(right_mid()),
                )))?;
            }
            for (ia, a) in alphas.iter().enumerate() {
                chart.draw_series(std::iter::once(Text::new(
                    format!("{:.0}°", a.to_degrees()),
                    (ia as f64 + 0.5, -0.45),
                    (FONT, 11).into_font().color(&BLACK).pos(mid()),
                )))?;
            }
            // Colour bar.
            for k in 0..20 {
                let y = k as f64 / 20.0 * nw;
                chart.draw_series(std::iter::once(Rectangle::new(
                    [(na + 0.3, y), (na + 0.7, y + nw / 20.0)],
                    heat(k as f64 / 19.0).filled(),
                )))?;
            }
            for (v, y) in [(0.0, 0.0), (vmax, nw)] {
                chart.draw_series(std::iter::once(Text::new(
                    format!("{v:.0}"),
                    (na + 0.8, y.clamp(0.2, nw - 0.2)),
                    (FONT, 11).into_font().color(&BLACK).pos(left_mid()),
                )))?;
            }
        }
        Ok(())
    })?;
    Ok(Figure {
        id: "heat-map".into(),
        title: "Error over α × ω".into(),
        caption: "Mean end position error (mm) of each command: translation direction α across, yaw rate ω down, \
                  one panel per fitted model on a shared colour scale. A pattern along α or a row that stays \
                  bright points at a missing effect; a uniform low map is what a complete model looks like."
            .into(),
        svg,
    })
}
