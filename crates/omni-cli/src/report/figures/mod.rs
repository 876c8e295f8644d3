//! The report's figures, drawn as SVG with plotters. Each function takes the computed [`Report`] and
//! returns a [`Figure`]; figures that the data cannot support (no commands, no diagnosis) are skipped by
//! [`all`] with a note.
//!
//! # Submodules
//! - `ladder.rs`: [`ladder`], held-out path RMS per rung of the error ladder.
//! - `overlay.rs`: [`overlay`], one run's ground truth and odometry, with a zoom on the end point.
//! - `by_command.rs`: the end position errors per (α, ω) command that the flower and the heat map draw.
//! - `flower.rs`: [`flower`], one polar plot per ω, with its legend strip.
//! - `heat_map.rs`: [`heat_map`], the errors over α × ω.
//! - `growth.rs`: [`growth`], the errors along the runs.
//! - `ranking.rs`: [`ranking`], the diagnosis' candidate effects.
//! - `trust.rs`: [`trust_ellipses`], [`trust_growth`], how far to trust the odometry (the noise model).

mod by_command;
mod flower;
mod growth;
mod heat_map;
mod ladder;
mod overlay;
mod ranking;
mod trust;

pub use flower::flower;
pub use growth::growth;
pub use heat_map::heat_map;
pub use ladder::ladder;
pub use overlay::overlay;
pub use ranking::ranking;
pub use trust::{trust_ellipses, trust_growth};

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
    match &r.trust {
        Some(t) if !t.runs.is_empty() => {
            figs.push(trust_ellipses(r, t)?);
            figs.push(trust_growth(t)?);
        }
        _ => notes.push(
            "The model has no odometry noise model (a model file written by `omnical train` carries one as \
             [noise]), so the figures of how far to trust the odometry are left out."
                .to_string(),
        ),
    }
    match diagnosis {
        Some(d) if !d.ranking.is_empty() => figs.push(ranking(d)?),
        _ => notes.push("No diagnosis was run, so the effect ranking is left out.".to_string()),
    }
    Ok((figs, notes))
}

/// The figures' legend: upper left, on a white box with a black border.
fn upper_left_legend<'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, SVGBackend<'a>, CT>,
) -> Result<(), DrawError> {
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
}

fn colour_name(i: usize) -> &'static str {
    ["grey", "blue", "green", "red", "purple", "orange"][i % MODEL_COLOURS.len()]
}

fn text_centre() -> plotters::style::text_anchor::Pos {
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    Pos::new(HPos::Center, VPos::Bottom)
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
