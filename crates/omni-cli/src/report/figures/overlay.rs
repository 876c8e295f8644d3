//! Ground truth against each model's odometry for one run, with a zoom on the end point.

use super::{Area, DrawError, FONT, Figure, TRUTH, colour, draw, span, upper_left_legend};
use crate::report::{Overlay, Report};
use plotters::prelude::*;

/// Ground truth against each model's odometry for one run, with a zoom on the end point.
pub fn overlay(r: &Report, which: usize) -> Result<Figure, DrawError> {
    let o = &r.overlays[which];
    let svg = draw((900, 430), |root| {
        let (left, right) = root.split_horizontally(520);
        // Whole path, equal axes.
        let (x0, x1) = span(o.lines.iter().flat_map(|l| l.xy_m.iter().map(|p| p.0)), 0.08);
        let (y0, y1) = span(o.lines.iter().flat_map(|l| l.xy_m.iter().map(|p| p.1)), 0.08);
        let half = ((x1 - x0).max(y1 - y0)) / 2.0;
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        path_panel(
            &left,
            &format!("{} ({} run)", o.run, o.role),
            o,
            (cx - half, cx + half),
            (cy - half, cy + half),
            true,
        )?;
        // End-point zoom: a box around every line's last point.
        let ends: Vec<(f64, f64)> = o.lines.iter().filter_map(|l| l.xy_m.last().copied()).collect();
        let (ex0, ex1) = span(ends.iter().map(|p| p.0), 0.0);
        let (ey0, ey1) = span(ends.iter().map(|p| p.1), 0.0);
        let half = ((ex1 - ex0).max(ey1 - ey0) * 0.65).max(0.005);
        let (cx, cy) = ((ex0 + ex1) / 2.0, (ey0 + ey1) / 2.0);
        path_panel(&right, "end point (zoom)", o, (cx - half, cx + half), (cy - half, cy + half), false)?;
        Ok(())
    })?;
    let ends: (String, String) = r
        .runs
        .iter()
        .find(|x| x.name == o.run)
        .map(|x| {
            let per_model = |v: &[f64]| -> Vec<String> {
                r.models.iter().zip(v).map(|(m, e)| format!("{} {:.1} mm", m.label, e * 1000.0)).collect()
            };
            (per_model(&x.path_rms_m).join(", "), per_model(&x.end_position_m).join(", "))
        })
        .unwrap_or_default();
    let set = if r.held_out_runs > 0 { "held-out" } else { "training" };
    let judged = &r.models[r.models.len().min(2) - 1].label;
    Ok(Figure {
        id: format!("overlay-{}", o.role),
        title: format!("Trajectory overlay: {} run", o.role),
        caption: format!(
            "Run {} — the {} {set} run by the path RMS of the {judged} (path RMS: {}; end position error: {}). \
             Left: the whole path (black: motion-capture ground truth); right: a zoom on where each model ends, \
             as in the paper's Figs. 6–7.",
            o.run,
            if o.role == "worst" { "worst" } else { "median" },
            ends.0,
            ends.1
        ),
        svg,
    })
}

fn path_panel(
    area: &Area<'_>,
    title: &str,
    o: &Overlay,
    xr: (f64, f64),
    yr: (f64, f64),
    legend: bool,
) -> Result<(), DrawError> {
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FONT, 15))
        .margin(10)
        .x_label_area_size(34)
        .y_label_area_size(56)
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)?;
    chart
        .configure_mesh()
        .light_line_style(RGBColor(240, 240, 240))
        .x_desc("x (m)")
        .y_desc("y (m)")
        .x_labels(6)
        .y_labels(6)
        .draw()?;
    for (i, line) in o.lines.iter().enumerate() {
        let c = if i == 0 { TRUTH } else { colour(i - 1) };
        let width = if i == 0 { 3 } else { 2 };
        let pts = line.xy_m.iter().copied().filter(|p| p.0 >= xr.0 && p.0 <= xr.1 && p.1 >= yr.0 && p.1 <= yr.1);
        let s = chart.draw_series(LineSeries::new(pts, c.stroke_width(width)))?;
        if legend {
            s.label(line.label.clone())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], c.stroke_width(width)));
        }
        if let Some(&end) = line.xy_m.last() {
            chart.draw_series(std::iter::once(Circle::new(end, 5, c.filled())))?;
        }
    }
    if legend {
        upper_left_legend(&mut chart)?;
    }
    Ok(())
}
