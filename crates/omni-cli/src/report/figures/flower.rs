//! End-point errors by command: one polar "flower" per ω, with a legend strip under the panels.

use super::by_command::by_command;
use super::{Area, DrawError, FONT, Figure, colour, colour_name, draw, left_mid};
use crate::report::Report;
use plotters::prelude::*;

/// End-point errors by command: one polar "flower" per ω, radius = mean end position error at angle α.
///
/// long: one plotters drawing (axes, rings, one series per ω, legend) in drawing order.
pub fn flower(r: &Report) -> Result<Figure, DrawError> {
    let (alphas, omegas, mean) = by_command(r);
    // The design's errors are often ten times the fitted models'; leave it out so theirs stay readable.
    let first_shown = usize::from(r.models.len() > 1);
    let nw = omegas.len().clamp(1, 4);
    let rmax = mean
        .iter()
        .skip(first_shown)
        .flatten()
        .flatten()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max)
        .max(1e-6)
        * 1000.0;
    let ring = nice_step(rmax / 3.0);
    let rlim = (rmax / ring).ceil() * ring * 1.12;
    let entries: Vec<(String, RGBColor)> =
        r.models.iter().enumerate().skip(first_shown).map(|(i, m)| (m.label.clone(), colour(i))).collect();
    let svg = draw((300 * nw as u32, 340 + LEGEND_STRIP_PX), |root| {
        let (root, strip) = root.split_vertically(340);
        legend_strip(&strip, "mean end position error of", &entries)?;
        let panels = root.split_evenly((1, nw));
        for (iw, area) in panels.iter().enumerate() {
            let Some(w) = omegas.get(iw) else { break };
            let mut chart = ChartBuilder::on(area)
                .caption(format!("ω = {w:+.2} rad/s"), (FONT, 15))
                .margin(8)
                .build_cartesian_2d(-rlim..rlim, -rlim..rlim)?;
            let grey = RGBColor(210, 210, 210);
            let mut rr = ring;
            while rr < rlim {
                let circle: Vec<(f64, f64)> = (0..=72)
                    .map(|k| {
                        let t = k as f64 / 72.0 * std::f64::consts::TAU;
                        (rr * t.cos(), rr * t.sin())
                    })
                    .collect();
                chart.draw_series(std::iter::once(PathElement::new(circle, grey)))?;
                chart.draw_series(std::iter::once(Text::new(
                    format!("{rr:.0} mm"),
                    (rr * 0.707, rr * 0.707),
                    (FONT, 11).into_font().color(&RGBColor(120, 120, 120)),
                )))?;
                rr += ring;
            }
            for a in &alphas {
                chart.draw_series(std::iter::once(PathElement::new(
                    [(0.0, 0.0), (rlim * 0.95 * a.cos(), rlim * 0.95 * a.sin())],
                    grey,
                )))?;
            }
            for (m, per_w) in mean.iter().enumerate().skip(first_shown) {
                let c = colour(m);
                let mut pts: Vec<(f64, f64)> = alphas
                    .iter()
                    .zip(&per_w[iw])
                    .filter(|(_, e)| e.is_finite())
                    .map(|(a, e)| (e * 1000.0 * a.cos(), e * 1000.0 * a.sin()))
                    .collect();
                if let Some(&first) = pts.first() {
                    pts.push(first);
                }
                chart.draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(2)))?;
                chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))?;
            }
        }
        Ok(())
    })?;
    let legend: Vec<String> = r
        .models
        .iter()
        .enumerate()
        .skip(first_shown)
        .map(|(i, m)| format!("{} ({})", m.label, colour_name(i)))
        .collect();
    Ok(Figure {
        id: "flower".into(),
        title: "End-point error by command".into(),
        caption: format!(
            "For each commanded yaw rate ω, the mean end position error of each command drawn at its translation \
             direction α (distance from the centre = error, rings in mm). Models: {}{}. A round, small flower means \
             the error does not depend on the direction of motion; lobes point at directions the model gets wrong.",
            legend.join(", "),
            if first_shown == 1 { " (the design model is left out: its errors are on another scale)" } else { "" }
        ),
        svg,
    })
}

/// Height of the legend strip under a figure's panels. px.
const LEGEND_STRIP_PX: u32 = 30;

/// A one-line legend across `area`: `lead`, then a line sample and the label of each entry.
fn legend_strip(area: &Area<'_>, lead: &str, entries: &[(String, RGBColor)]) -> Result<(), DrawError> {
    let y = (LEGEND_STRIP_PX / 2) as i32;
    let font = (FONT, 13).into_font().color(&BLACK).pos(left_mid());
    let mut x = 12;
    area.draw(&Text::new(format!("{lead}:"), (x, y), font.clone()))?;
    // A rough advance per character (13 px sans-serif) is enough to space the entries.
    x += 7 * lead.chars().count() as i32 + 18;
    for (label, c) in entries {
        area.draw(&PathElement::new([(x, y), (x + 22, y)], c.stroke_width(2)))?;
        area.draw(&Circle::new((x + 11, y), 3, c.filled()))?;
        area.draw(&Text::new(label.clone(), (x + 28, y), font.clone()))?;
        x += 28 + 7 * label.chars().count() as i32 + 22;
    }
    Ok(())
}

/// 1, 2 or 5 × 10^k at or above `x`.
fn nice_step(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 1.0;
    }
    let p = 10f64.powf(x.log10().floor());
    [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * p).find(|s| *s >= x).unwrap_or(10.0 * p)
}
