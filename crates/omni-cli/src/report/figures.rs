//! The report's figures, drawn as SVG with plotters. Each function takes the computed [`Report`] and
//! returns a [`Figure`]; figures that the data cannot support (no commands, no diagnosis) are skipped by
//! [`all`] with a note.

use super::Report;
use omni_ga::diagnose::Diagnosis;
use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Serialize;

/// One SVG figure.
#[derive(Clone, Debug, Serialize)]
pub struct Figure {
    /// Stable id (file name of `--png`, HTML anchor): `ladder`, `overlay-worst`, …
    pub id: String,
    /// Heading.
    pub title: String,
    /// What to look at, in a sentence or two.
    pub caption: String,
    /// The SVG document.
    pub svg: String,
}

/// Ground truth colour.
const TRUTH: RGBColor = RGBColor(20, 20, 20);
/// One colour per model: design grey, fitted blue, then effects.
const MODEL_COLOURS: [RGBColor; 6] = [
    RGBColor(150, 150, 150),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
];
const FONT: &str = "sans-serif";

fn colour(i: usize) -> RGBColor {
    MODEL_COLOURS[i % MODEL_COLOURS.len()]
}

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// Why a figure could not be drawn: plotters' error for its SVG backend.
pub type DrawError = DrawingAreaErrorKind<std::io::Error>;

fn draw(size: (u32, u32), f: impl FnOnce(&Area<'_>) -> Result<(), DrawError>) -> Result<String, DrawError> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE)?;
        f(&root)?;
        root.present()?;
    }
    Ok(svg)
}

/// A finite range around the values, never empty.
fn span(values: impl IntoIterator<Item = f64>, pad: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.into_iter().filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let w = (hi - lo).max(1e-9);
    (lo - pad * w, hi + pad * w)
}

/// Every figure the report's data supports, in reading order, and notes on the ones left out.
pub fn all(r: &Report, diagnosis: Option<&Diagnosis>) -> Result<(Vec<Figure>, Vec<String>), DrawError> {
    let mut figs = vec![ladder(r)?];
    let mut notes = Vec::new();
    for o in 0..r.overlays.len() {
        figs.push(overlay(r, o)?);
    }
    if r.runs.iter().any(|x| x.omega_rad_s.is_some()) {
        figs.push(flower(r)?);
        figs.push(heat_map(r)?);
    } else {
        notes.push(
            "The runs carry no (v, α, ω) command, so the per-command flower and heat-map figures are left out."
                .to_string(),
        );
    }
    figs.push(growth(r)?);
    match diagnosis {
        Some(d) if !d.ranking.is_empty() => figs.push(ranking(d)?),
        _ => notes.push("No diagnosis was run, so the effect ranking is left out.".to_string()),
    }
    Ok((figs, notes))
}

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

fn text_centre() -> plotters::style::text_anchor::Pos {
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    Pos::new(HPos::Center, VPos::Bottom)
}

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
    o: &super::Overlay,
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
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
    }
    Ok(())
}

/// Distinct values, rounded to `tol`, in increasing order.
fn distinct(values: impl IntoIterator<Item = f64>, tol: f64) -> Vec<f64> {
    let mut v: Vec<f64> = Vec::new();
    for x in values {
        if !v.iter().any(|y| (x - y).abs() < tol) {
            v.push(x);
        }
    }
    v.sort_by(f64::total_cmp);
    v
}

/// Mean end position error (m) per model for each (α, ω) command.
fn by_command(r: &Report) -> (Vec<f64>, Vec<f64>, Vec<Vec<Vec<f64>>>) {
    let alphas = distinct(r.runs.iter().filter_map(|x| x.alpha_rad.map(|a| a.rem_euclid(std::f64::consts::TAU))), 1e-3);
    let omegas = distinct(r.runs.iter().filter_map(|x| x.omega_rad_s), 1e-3);
    let nm = r.models.len();
    let mut sum = vec![vec![vec![(0.0, 0usize); alphas.len()]; omegas.len()]; nm];
    for x in &r.runs {
        let (Some(a), Some(w)) = (x.alpha_rad, x.omega_rad_s) else { continue };
        let a = a.rem_euclid(std::f64::consts::TAU);
        let (Some(ia), Some(iw)) =
            (alphas.iter().position(|v| (v - a).abs() < 1e-3), omegas.iter().position(|v| (v - w).abs() < 1e-3))
        else {
            continue;
        };
        for (m, e) in x.end_position_m.iter().enumerate() {
            sum[m][iw][ia].0 += e;
            sum[m][iw][ia].1 += 1;
        }
    }
    let mean = sum
        .into_iter()
        .map(|w| {
            w.into_iter()
                .map(|a| a.into_iter().map(|(s, n)| if n == 0 { f64::NAN } else { s / n as f64 }).collect())
                .collect()
        })
        .collect();
    (alphas, omegas, mean)
}

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

fn colour_name(i: usize) -> &'static str {
    ["grey", "blue", "green", "red", "purple", "orange"][i % MODEL_COLOURS.len()]
}

/// 1, 2 or 5 × 10^k at or above `x`.
fn nice_step(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 1.0;
    }
    let p = 10f64.powf(x.log10().floor());
    [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * p).find(|s| *s >= x).unwrap_or(10.0 * p)
}

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

fn mid() -> plotters::style::text_anchor::Pos {
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    Pos::new(HPos::Center, VPos::Center)
}

fn right_mid() -> plotters::style::text_anchor::Pos {
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    Pos::new(HPos::Right, VPos::Center)
}

fn left_mid() -> plotters::style::text_anchor::Pos {
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    Pos::new(HPos::Left, VPos::Center)
}

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
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()?;
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
