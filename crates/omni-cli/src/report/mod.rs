//! The HTML report: what the models predict against what was measured, figure by figure.
//!
//! [`Report::build`] computes everything from plain data (models and runs; the diagnosis when there is
//! one) — per-run errors, overlay paths, error growth, per-command maps — and [`html::render`] turns it into
//! one self-contained HTML file with inline SVG figures (no scripts, no network fetches). [`png`] renders
//! the same SVG figures to PNG files.
//!
//! Which runs: every figure uses the *held-out* runs (the validation set when given, otherwise the
//! training runs, said so in the report), because a model is judged where it was not fitted.

pub mod explore;
pub mod figures;
pub mod html;
pub mod png;
pub mod trust;
pub mod tum;

use omni_ga::diagnose::{Costs, Diagnosis};
use omni_kin::cost::CostKind;
use omni_kin::odometry::{self, Selection};
use omni_kin::{FittedModel, KinError, Pose2, Run, RunModels, ToRunModels};
use serde::Serialize;

/// Heading weight of the path cost. m/rad.
const HEADING_WEIGHT_M_PER_RAD: f64 = 1.0;
/// Bins of the error-growth curves.
const GROWTH_BINS: usize = 20;

/// A model shown in the report.
#[derive(Clone, Debug)]
pub struct Labelled {
    /// `design`, `fitted matrix`, `+ time_offset`, …
    pub label: String,
    /// The model and its parameters: one for every run, or each run's own (the design, when the robot's
    /// inputs declare different designs; it must know every training and held-out run).
    pub model: RunModels,
    /// The noise model `train` fitted with it (its model file's `[noise]`), when it has one: the figures of
    /// how far to trust the odometry ([`trust::trust`] along the figure runs).
    pub noise: Option<omni_kin::noise::OdometryNoise>,
}

/// Everything the report is made from.
#[derive(Clone, Debug)]
pub struct ReportInput<'a> {
    /// Title line.
    pub title: String,
    /// Models, from the design (first) to the best one (last). At least one.
    pub models: Vec<Labelled>,
    /// Training runs.
    pub train: &'a [Run],
    /// Held-out runs (may be empty: the figures then use the training runs).
    pub held_out: &'a [Run],
    /// The diagnosis of the fitted model, when one was run.
    pub diagnosis: Option<&'a Diagnosis>,
    /// Where the data came from (shown in the summary).
    pub sources: Vec<String>,
}

/// One model's numbers.
#[derive(Clone, Debug, Serialize)]
pub struct ModelSummary {
    /// Label.
    pub label: String,
    /// Costs on training and held-out runs (path RMS m, Eq. 6).
    pub costs: Costs,
    /// IK matrix rows (vx m/s, vy m/s, ω rad/s per wheel rad/s), when it has one.
    pub matrix: Option<Vec<Vec<f64>>>,
    /// Parameters beyond the IK matrix entries: (name, value, unit).
    pub params: Vec<(String, f64, String)>,
}

/// One held-out run's errors under each model.
#[derive(Clone, Debug, Serialize)]
pub struct RunErrors {
    /// Run name.
    pub name: String,
    /// Commanded translation direction. rad.
    pub alpha_rad: Option<f64>,
    /// Commanded yaw rate. rad/s.
    pub omega_rad_s: Option<f64>,
    /// End position error per model. m.
    pub end_position_m: Vec<f64>,
    /// End heading error per model. rad.
    pub end_heading_rad: Vec<f64>,
    /// Path RMS per model (heading at 1 m/rad). m.
    pub path_rms_m: Vec<f64>,
}

/// A path drawn in an overlay.
#[derive(Clone, Debug, Serialize)]
pub struct PathLine {
    /// `ground truth` or a model label.
    pub label: String,
    /// (x, y) in the world frame. m.
    pub xy_m: Vec<(f64, f64)>,
}

/// Ground truth and each model's odometry for one run.
#[derive(Clone, Debug, Serialize)]
pub struct Overlay {
    /// Why this run: `worst` or `typical`.
    pub role: String,
    /// Run name.
    pub run: String,
    /// Ground truth first, then one line per model.
    pub lines: Vec<PathLine>,
}

/// Mean errors against the fraction of run time, per model.
#[derive(Clone, Debug, Serialize)]
pub struct GrowthCurves {
    /// Bin centres (0…1).
    pub fraction: Vec<f64>,
    /// Mean position error per model and bin. m.
    pub position_m: Vec<Vec<f64>>,
    /// Mean |heading error| per model and bin. rad.
    pub heading_rad: Vec<Vec<f64>>,
}

/// The report's content, ready to draw.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Title.
    pub title: String,
    /// Data sources.
    pub sources: Vec<String>,
    /// Number of training runs.
    pub train_runs: usize,
    /// Number of held-out runs shown (0 when the figures fall back to training runs).
    pub held_out_runs: usize,
    /// What the figures' runs are: `validation runs` or `training runs (no validation set given)`.
    pub figure_runs: String,
    /// Per model.
    pub models: Vec<ModelSummary>,
    /// Per figure run.
    pub runs: Vec<RunErrors>,
    /// Worst and typical runs of the fitted model.
    pub overlays: Vec<Overlay>,
    /// Error growth along the runs.
    pub growth: GrowthCurves,
    /// Noise floor path RMS, when the diagnosis estimated one. m.
    pub noise_floor_m: Option<f64>,
    /// Error ladder (label, held-out path RMS m, held-out Eq. 6), from the diagnosis or the models.
    pub ladder: Vec<(String, f64, f64)>,
    /// How far to trust the odometry along the figure runs (drawn, not in the JSON).
    #[serde(skip)]
    pub trust: Option<trust::Trust>,
}

impl Report {
    /// Computes the report's content. Fails only when a model cannot be evaluated on the runs (wrong wheel
    /// count, singular geometry).
    ///
    /// long: assembles every section of the page from already computed parts, in page order.
    pub fn build(input: &ReportInput<'_>) -> Result<Report, KinError> {
        let fig_runs = if input.held_out.is_empty() { input.train } else { input.held_out };
        let figure_runs = if input.held_out.is_empty() {
            "training runs (no validation set given)".to_string()
        } else {
            "validation runs".to_string()
        };
        let path = CostKind::Path { every: 1, heading_weight_m_per_rad: HEADING_WEIGHT_M_PER_RAD };
        let mut models = Vec::with_capacity(input.models.len());
        let mut fig_errors = Vec::with_capacity(input.models.len());
        for m in &input.models {
            let (train, held_out) =
                (m.model.errors(input.train, path.selection())?, m.model.errors(fig_runs, path.selection())?);
            let w = path.heading_weight();
            let costs = Costs {
                train_path: train.path_cost(w),
                held_out_path: held_out.path_cost(w),
                train_end_pose: train.end_pose_cost(),
                held_out_end_pose: held_out.end_pose_cost(),
            };
            fig_errors.push(held_out);
            // Runs with designs of their own show no one matrix: the first stands for its parameters.
            let (first, one) = (m.model.first(), m.model.single().is_some());
            let specs = first.model.params();
            // The matrix shows base parameters that are its entries (all of an `ik` model's, structural zeros
            // aside); list the others.
            let is_matrix = first.model.kinematics.kind() == omni_kin::KinematicsKind::Ik;
            let nb = if is_matrix { first.model.n_base() } else { 0 };
            let params =
                specs.iter().zip(&first.params).skip(nb).map(|(s, v)| (s.name.clone(), *v, s.unit.to_string()));
            models.push(ModelSummary {
                label: m.label.clone(),
                costs,
                matrix: first.ik().ok().filter(|_| one).map(|k| k.rows()),
                params: params.collect(),
            });
        }

        // The first model with a noise model, through the errors just computed on the figure runs.
        let trust = input
            .models
            .iter()
            .zip(&fig_errors)
            .find_map(|(m, errors)| m.noise.as_ref().map(|n| trust::trust(fig_runs, errors, n)))
            .transpose()?;

        let mut runs = Vec::with_capacity(fig_runs.len());
        let mut growth_sum = vec![vec![(0.0, 0.0, 0usize); GROWTH_BINS]; input.models.len()];
        for (ri, run) in fig_runs.iter().enumerate() {
            let mut e = RunErrors {
                name: run.name().to_string(),
                alpha_rad: run.command().map(|c| c.alpha_rad),
                omega_rad_s: run.command().map(|c| c.omega_rad_s),
                end_position_m: Vec::new(),
                end_heading_rad: Vec::new(),
                path_rms_m: Vec::new(),
            };
            let (t0, t1) = (run.start().t_s, run.end().t_s);
            for (mi, errors) in fig_errors.iter().enumerate() {
                let r = errors.run(ri);
                let mut sq = 0.0;
                for (x, ti) in r.iter().zip(Selection::Path(1).indices(run.truth().len())) {
                    let pos = x.position_m();
                    sq += pos * pos + (HEADING_WEIGHT_M_PER_RAD * x.dtheta_rad).powi(2);
                    let f = if t1 > t0 { (run.truth()[ti].t_s - t0) / (t1 - t0) } else { 0.0 };
                    let b = ((f * GROWTH_BINS as f64) as usize).min(GROWTH_BINS - 1);
                    let cell = &mut growth_sum[mi][b];
                    cell.0 += pos;
                    cell.1 += x.dtheta_rad.abs();
                    cell.2 += 1;
                }
                let last = r.last().copied().unwrap_or_default();
                e.end_position_m.push(last.position_m());
                e.end_heading_rad.push(last.dtheta_rad.abs());
                e.path_rms_m.push(if r.is_empty() { 0.0 } else { (sq / r.len() as f64).sqrt() });
            }
            runs.push(e);
        }
        let mean = |v: f64, n: usize| if n == 0 { f64::NAN } else { v / n as f64 };
        let growth = GrowthCurves {
            fraction: (0..GROWTH_BINS).map(|b| (b as f64 + 0.5) / GROWTH_BINS as f64).collect(),
            position_m: growth_sum.iter().map(|g| g.iter().map(|c| mean(c.0, c.2)).collect()).collect(),
            heading_rad: growth_sum.iter().map(|g| g.iter().map(|c| mean(c.1, c.2)).collect()).collect(),
        };

        // Worst and typical held-out runs of the fitted model (the second one; the design when alone), by
        // path RMS: the measure by which the diagnosis names its worst (training) run.
        let judge = input.models.len().min(2) - 1;
        let mut order: Vec<usize> = (0..runs.len()).collect();
        order.sort_by(|&a, &b| runs[a].path_rms_m[judge].total_cmp(&runs[b].path_rms_m[judge]));
        let mut overlays = Vec::new();
        if let Some(&worst) = order.last() {
            overlays.push(overlay("worst", &fig_runs[worst], &input.models)?);
            let typical = order[order.len() / 2];
            if typical != worst {
                overlays.push(overlay("typical", &fig_runs[typical], &input.models)?);
            }
        }

        let ladder = match input.diagnosis {
            Some(d) if !d.ladder.is_empty() => {
                d.ladder.iter().map(|r| (r.label.clone(), r.costs.held_out_path, r.costs.held_out_end_pose)).collect()
            }
            _ => models.iter().map(|m| (m.label.clone(), m.costs.held_out_path, m.costs.held_out_end_pose)).collect(),
        };
        Ok(Report {
            title: input.title.clone(),
            sources: input.sources.clone(),
            train_runs: input.train.len(),
            held_out_runs: input.held_out.len(),
            figure_runs,
            models,
            runs,
            overlays,
            growth,
            noise_floor_m: input.diagnosis.and_then(|d| d.noise_floor.as_ref().map(|n| n.path_rms)),
            ladder,
            trust,
        })
    }
}

fn overlay(role: &str, run: &Run, models: &[Labelled]) -> Result<Overlay, KinError> {
    let mut lines = vec![PathLine {
        label: "ground truth".into(),
        xy_m: run.truth().iter().map(|p| (p.pose.x_m, p.pose.y_m)).collect(),
    }];
    for m in models {
        let fm = m.model.for_run(run)?;
        let res = fm.model.resolve(&fm.params)?;
        let tr = odometry::integrate(&res, run);
        lines.push(PathLine { label: m.label.clone(), xy_m: thin(&tr.poses) });
    }
    Ok(Overlay { role: role.into(), run: run.name().into(), lines })
}

/// At most ~600 points per line (the SVG stays small), always keeping the last one.
fn thin(poses: &[Pose2]) -> Vec<(f64, f64)> {
    let step = poses.len().div_ceil(600).max(1);
    let mut v: Vec<(f64, f64)> = poses.iter().step_by(step).map(|p| (p.x_m, p.y_m)).collect();
    if let Some(last) = poses.last()
        && !(poses.len() - 1).is_multiple_of(step)
    {
        v.push((last.x_m, last.y_m));
    }
    v
}

/// Why the report could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The models could not be evaluated on the runs.
    #[error("evaluating the models for the report")]
    Evaluate(#[source] KinError),
    /// A figure could not be drawn.
    #[error("drawing the figures")]
    Draw(#[source] figures::DrawError),
    /// The page's folder could not be created.
    #[error("creating {}", dir.display())]
    CreateDir {
        /// The folder.
        dir: std::path::PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The page could not be written.
    #[error("writing {}", path.display())]
    Write {
        /// The HTML file.
        path: std::path::PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The PNG figures could not be written.
    #[error(transparent)]
    Png(#[from] png::PngError),
}

/// What [`write()`] produced.
#[derive(Clone, Debug)]
pub struct Written {
    /// The computed content.
    pub report: Report,
    /// Ids of the figures in the page.
    pub figures: Vec<String>,
    /// PNG files written (with `png_dir`).
    pub png: Vec<std::path::PathBuf>,
}

/// Builds the report, writes the HTML page to `html_path` (atomically) and, with `png_dir`, each figure as
/// PNG.
pub fn write(
    input: &ReportInput<'_>,
    html_path: &std::path::Path,
    png_dir: Option<&std::path::Path>,
) -> Result<Written, ReportError> {
    write_with(input, html_path, png_dir, "")
}

/// [`write()`] with `extra` HTML sections (e.g. [`explore::section`]) at the end of the page, before `</body>`.
pub fn write_with(
    input: &ReportInput<'_>,
    html_path: &std::path::Path,
    png_dir: Option<&std::path::Path>,
    extra: &str,
) -> Result<Written, ReportError> {
    let report = Report::build(input).map_err(ReportError::Evaluate)?;
    let (figs, notes) = figures::all(&report, input.diagnosis).map_err(ReportError::Draw)?;
    let mut page = html::render(&report, &figs, &notes, input.diagnosis);
    if !extra.is_empty()
        && let Some(at) = page.rfind("</body>")
    {
        page.insert_str(at, extra);
    }
    if let Some(dir) = html_path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| ReportError::CreateDir { dir: dir.to_path_buf(), source })?;
    }
    crate::atomic::write_atomic(html_path, page.as_bytes())
        .map_err(|source| ReportError::Write { path: html_path.to_path_buf(), source })?;
    let png = match png_dir {
        Some(dir) => png::write_all(&figs, dir)?,
        None => Vec::new(),
    };
    Ok(Written { report, figures: figs.into_iter().map(|f| f.id).collect(), png })
}

/// The models a report shows for a fitted model (with the noise model `train` fitted with it, if any) and
/// its diagnosis: the design (one, or each run's own), the model itself, and the model with the effects the
/// diagnosis added (when it added any).
pub fn models_for(
    design: &impl ToRunModels,
    fitted: &FittedModel,
    noise: Option<omni_kin::noise::OdometryNoise>,
    diagnosis: Option<&Diagnosis>,
) -> Vec<Labelled> {
    let base = format!("fitted {}", fitted.model.kinematics.noun());
    let with_effects = |m: &FittedModel, base: &str| {
        let ids: Vec<&str> = m.model.effects.iter().map(omni_kin::effect::Effect::id).collect();
        if ids.is_empty() { base.to_string() } else { format!("{base} + {}", ids.join(" + ")) }
    };
    let mut v = vec![
        Labelled { label: "design".into(), model: design.to_run_models(), noise: None },
        Labelled { label: with_effects(fitted, &base), model: fitted.into(), noise },
    ];
    if let Some(f) = diagnosis.and_then(|d| d.final_model.as_ref())
        && f.model.effects.len() > fitted.model.effects.len()
    {
        v.push(Labelled { label: with_effects(f, &base), model: f.into(), noise: None });
    }
    v
}

#[cfg(test)]
mod tests;
