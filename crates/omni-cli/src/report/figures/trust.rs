//! How far to trust the odometry (issue 46): the noise model's 95 % ellipses along one run, and the
//! position error against the distance driven with the model's 95 % band.

use super::{DrawError, FONT, Figure, TRUTH, colour, draw, span, upper_left_legend};
use crate::report::Report;
use crate::report::trust::{Trust, TrustRun};
use plotters::prelude::*;

/// Points on the ellipse `x Σ⁻¹ x = χ²` around `centre` (Σ: xx, xy, yy), drawn `scale` times its size.
fn ellipse(centre: [f64; 2], cov: [f64; 3], chi2: f64, scale: f64) -> Vec<(f64, f64)> {
    let [xx, xy, yy] = cov;
    // Cholesky of Σ: L = [[a, 0], [b, c]].
    let a = xx.max(0.0).sqrt();
    let b = if a > 0.0 { xy / a } else { 0.0 };
    let c = (yy - b * b).max(0.0).sqrt();
    let k = scale * chi2.sqrt();
    (0..=48)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / 48.0;
            let (u, v) = (k * t.cos(), k * t.sin());
            (centre[0] + a * u, centre[1] + b * u + c * v)
        })
        .collect()
}

/// The smallest of 1, 2, 5, 10, 20, 50, … that makes `radius` at least `visible`.
fn magnification(radius: f64, visible: f64) -> f64 {
    if radius.is_nan() || radius <= 0.0 {
        return 1.0;
    }
    (0..6).flat_map(|n| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(n))).find(|m| m * radius >= visible).unwrap_or(1e6)
}

/// The run that drives furthest (the ellipses have the most to show there).
fn longest(t: &Trust) -> Option<&TrustRun> {
    t.runs.iter().max_by(|a, b| {
        let d = |r: &TrustRun| r.distance_m.last().copied().unwrap_or(0.0);
        d(a).total_cmp(&d(b))
    })
}

/// About a dozen poses of `run` for ellipses, one every so many metres driven, and that distance (m).
fn marks(run: &TrustRun) -> (Vec<usize>, f64) {
    let total = run.distance_m.last().copied().unwrap_or(0.0);
    let every = (total / 12.0).max(0.05);
    let mut marks = Vec::new();
    let mut next = every;
    for (k, d) in run.distance_m.iter().enumerate() {
        if *d >= next {
            marks.push(k);
            next += every;
        }
    }
    (marks, every)
}

/// The 95 % ellipses along the run that drives furthest, with its ground truth and the calibrated odometry.
pub fn trust_ellipses(r: &Report, t: &Trust) -> Result<Figure, DrawError> {
    let Some(run) = longest(t) else {
        return Ok(Figure {
            id: "trust-ellipses".into(),
            title: String::new(),
            caption: String::new(),
            svg: String::new(),
        });
    };
    let total = run.distance_m.last().copied().unwrap_or(0.0);
    let (marks, every) = marks(run);
    let fitted = colour(1);
    let all = run.truth_xy_m.iter().chain(&run.odometry_xy_m);
    let (x0, x1) = span(all.clone().map(|p| p[0]), 0.12);
    let (y0, y1) = span(all.map(|p| p[1]), 0.12);
    let half = ((x1 - x0).max(y1 - y0)) / 2.0;
    // Millimetre ellipses on a path of metres are drawn larger (1, 2, 5 × 10ⁿ times), and the title says so.
    let largest = marks.iter().map(|&k| run.radius_95_m(k)).fold(0.0, f64::max);
    let scale = magnification(largest, 0.06 * half);
    let svg = draw((620, 560), |root| {
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        let mut chart = ChartBuilder::on(root)
            .caption(
                if scale > 1.0 {
                    format!("{}: 95 % ellipses every {:.2} m driven, drawn {scale}× their size", run.name, every)
                } else {
                    format!("{}: 95 % ellipses every {:.2} m driven", run.name, every)
                },
                (FONT, 15),
            )
            .margin(10)
            .x_label_area_size(34)
            .y_label_area_size(52)
            .build_cartesian_2d(cx - half..cx + half, cy - half..cy + half)?;
        chart.configure_mesh().light_line_style(RGBColor(240, 240, 240)).x_desc("x (m)").y_desc("y (m)").draw()?;
        for &k in &marks {
            let pts = ellipse(run.odometry_xy_m[k], run.covariance_m2[k], crate::report::trust::CHI2_2D_95, scale);
            chart.draw_series(std::iter::once(Polygon::new(pts.clone(), fitted.mix(0.12))))?;
            chart.draw_series(std::iter::once(PathElement::new(pts, fitted.stroke_width(1))))?;
        }
        let xy = |v: &[[f64; 2]]| v.iter().map(|p| (p[0], p[1])).collect::<Vec<_>>();
        chart
            .draw_series(LineSeries::new(xy(&run.truth_xy_m), TRUTH.stroke_width(2)))?
            .label("ground truth")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], TRUTH.stroke_width(2)));
        chart
            .draw_series(LineSeries::new(xy(&run.odometry_xy_m), fitted.stroke_width(2)))?
            .label(r.models[r.models.len().min(2) - 1].label.clone())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], fitted.stroke_width(2)));
        upper_left_legend(&mut chart)?;
        Ok(())
    })?;
    Ok(Figure {
        id: "trust-ellipses".into(),
        title: "How far to trust the odometry: 95 % ellipses".into(),
        caption: format!(
            "Run {} ({:.1} m driven): the calibrated odometry (blue) and the ground truth (black), with the noise \
             model's 95 % ellipse of the position error every {:.2} m, centred on the odometry. The ground truth \
             should lie inside 95 % of them; on this run {:.0} % of its poses do. The model is the one `train` \
             fitted with the calibration (the model file's [noise]).{}",
            run.name,
            total,
            every,
            100.0 * run.inside_share(),
            if scale > 1.0 {
                format!(" The ellipses are drawn {scale}× their size so that they show; the paths are not.")
            } else {
                String::new()
            }
        ),
        svg,
    })
}

/// A curve over the distance driven: (m, mm).
type Curve = Vec<(f64, f64)>;

/// Over 20 bins of the distance driven: the furthest distance (m), the model's 95 % radius per bin (the
/// mean over the poses in it) and the errors' 95th percentile per bin (bins of at least 5 poses), as
/// (bin centre m, mm).
fn bands(t: &Trust) -> (f64, Curve, Curve) {
    const BINS: usize = 20;
    let far = t.runs.iter().filter_map(|r| r.distance_m.last()).copied().fold(0.0, f64::max).max(1e-6);
    let width = far / BINS as f64;
    let mut radius = vec![Vec::new(); BINS];
    let mut errors = vec![Vec::new(); BINS];
    for r in &t.runs {
        for k in 0..r.error_m.len() {
            let b = ((r.distance_m[k] / width) as usize).min(BINS - 1);
            radius[b].push(r.radius_95_m(k));
            errors[b].push(r.error_m[k]);
        }
    }
    let centre = |b: usize| (b as f64 + 0.5) * width;
    let band = (0..BINS)
        .filter(|&b| !radius[b].is_empty())
        .map(|b| (centre(b), 1000.0 * radius[b].iter().sum::<f64>() / radius[b].len() as f64))
        .collect();
    let p95 = (0..BINS)
        .filter(|&b| errors[b].len() >= 5)
        .map(|b| {
            let mut e = errors[b].clone();
            e.sort_by(f64::total_cmp);
            (centre(b), 1000.0 * e[((0.95 * e.len() as f64) as usize).min(e.len() - 1)])
        })
        .collect();
    (far, band, p95)
}

/// The position error of every run against the distance driven, with the noise model's 95 % band.
pub fn trust_growth(t: &Trust) -> Result<Figure, DrawError> {
    let (far, band, p95) = bands(t);
    let top = t
        .runs
        .iter()
        .flat_map(|r| r.error_m.iter().map(|e| e * 1000.0))
        .chain(band.iter().map(|p| p.1))
        .fold(0.0, f64::max)
        * 1.1;
    let fitted = colour(1);
    let svg = draw((900, 380), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption("position error against distance driven", (FONT, 15))
            .margin(10)
            .x_label_area_size(34)
            .y_label_area_size(56)
            .build_cartesian_2d(0.0..far, 0.0..top.max(1e-3))?;
        chart
            .configure_mesh()
            .light_line_style(RGBColor(240, 240, 240))
            .x_desc("distance driven (m)")
            .y_desc("position error (mm)")
            .draw()?;
        let mut area = vec![(0.0, 0.0)];
        area.extend(band.iter().copied());
        area.push((band.last().map_or(0.0, |p| p.0), 0.0));
        chart
            .draw_series(std::iter::once(Polygon::new(area, fitted.mix(0.15))))?
            .label("noise model: 95 % radius")
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], fitted.mix(0.3).filled()));
        for r in &t.runs {
            let pts: Vec<(f64, f64)> = r.distance_m.iter().zip(&r.error_m).map(|(d, e)| (*d, e * 1000.0)).collect();
            chart.draw_series(LineSeries::new(pts, RGBColor(170, 170, 170).stroke_width(1)))?;
        }
        chart.draw_series(LineSeries::new(band.clone(), fitted.stroke_width(2)))?;
        chart
            .draw_series(LineSeries::new(p95, TRUTH.stroke_width(2)))?
            .label("measured: 95th percentile of the errors")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], TRUTH.stroke_width(2)));
        upper_left_legend(&mut chart)?;
        Ok(())
    })?;
    let inside: f64 = t.runs.iter().map(|r| r.inside_share() * r.error_m.len() as f64).sum::<f64>()
        / t.runs.iter().map(|r| r.error_m.len()).sum::<usize>().max(1) as f64;
    Ok(Figure {
        id: "trust-growth".into(),
        title: "How far to trust the odometry: error growth".into(),
        caption: format!(
            "Grey: each run's position error (calibrated odometry against the ground truth) as it drives. Blue: \
             the noise model's 95 % radius (the ellipse's longest axis), averaged per distance bin; black: the \
             errors' measured 95th percentile per bin. Where black runs above blue the model trusts the \
             odometry too much (a systematic error the model still misses, which `omnical diagnose` names); \
             well below, too little. Over these {} runs, {:.1} % of the poses lie inside their ellipse (`omnical \
             eval` gives the coverage at 1 m and 5 m).",
            t.runs.len(),
            100.0 * inside
        ),
        svg,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ellipses_are_magnified_by_a_round_factor_until_they_show() {
        assert_eq!(magnification(0.004, 0.05), 20.0);
        assert_eq!(magnification(0.06, 0.05), 1.0);
        assert_eq!(magnification(0.0, 0.05), 1.0);
        // A circle of σ = 1 m at 95 %: radius √5.991 m.
        let pts = ellipse([1.0, 2.0], [1.0, 0.0, 1.0], crate::report::trust::CHI2_2D_95, 1.0);
        for (x, y) in pts {
            assert!(((x - 1.0).hypot(y - 2.0) - crate::report::trust::CHI2_2D_95.sqrt()).abs() < 1e-12);
        }
    }
}
