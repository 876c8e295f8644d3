//! `omnical eval`: the cost of a model on runs — the summary first (Eq. 6, path RMS, statistics of the
//! end-position and end-heading errors, as evo_ape prints them), each run's row with `--per-run`.

use super::{DataArgs, OutputArgs};
use crate::api::ModelSpec;
use omni_kin::PoseError;
use omni_kin::cost::CostKind;
use serde_json::json;
use std::path::PathBuf;

/// Arguments of `omnical eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// `design` (the data's design model, each run its own input's when the inputs declare different
    /// designs), `paper` (the paper's Eq. 9) or a model file.
    #[arg(long, default_value = "design")]
    pub model: ModelSpec,
    /// Run files or folders.
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// Also print each run's end-pose error (after the summary): dx, dy, position error (m) and heading
    /// error (deg). `--json` always lists the runs.
    #[arg(long)]
    pub per_run: bool,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
    /// Data options.
    #[command(flatten)]
    pub data: DataArgs,
}

/// Summary statistics of one error over the runs (of its absolute values), in the error's unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stats {
    /// Mean.
    pub mean: f64,
    /// Median (the mean of the two middle values for an even count).
    pub median: f64,
    /// Root mean square.
    pub rmse: f64,
    /// Largest.
    pub max: f64,
}

impl Stats {
    /// The statistics of `values`' absolute values (NaN for none).
    pub fn of(values: impl IntoIterator<Item = f64>) -> Self {
        let mut v: Vec<f64> = values.into_iter().map(f64::abs).collect();
        if v.is_empty() {
            return Self { mean: f64::NAN, median: f64::NAN, rmse: f64::NAN, max: f64::NAN };
        }
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median = if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) };
        Self {
            mean: v.iter().sum::<f64>() / n as f64,
            median,
            rmse: (v.iter().map(|x| x * x).sum::<f64>() / n as f64).sqrt(),
            max: v[n - 1],
        }
    }

    /// Every statistic times `k` (a change of unit).
    fn scaled(self, k: f64) -> Self {
        Self { mean: k * self.mean, median: k * self.median, rmse: k * self.rmse, max: k * self.max }
    }

    fn to_json(self) -> serde_json::Value {
        json!({ "mean": self.mean, "median": self.median, "rmse": self.rmse, "max": self.max })
    }
}

/// End-position error of each run (m) and its statistics.
fn position_stats(errors: &[PoseError]) -> Stats {
    Stats::of(errors.iter().map(PoseError::position_m))
}

/// End-heading error of each run (rad) and its statistics.
fn heading_stats(errors: &[PoseError]) -> Stats {
    Stats::of(errors.iter().map(|e| e.dtheta_rad))
}

/// Runs `omnical eval`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    let spelled = a.model.to_string();
    let model = spelled.as_str();
    let ds = a.data.request(&a.runs).load()?;
    // `design`: each run its own input's design (the pooled figures are the run-weighted means).
    let models = a.model.resolve_each(&[&ds])?;
    let all = models.errors(&ds.runs, CostKind::PATH.selection())?;
    let errors = all.ends();
    let c = all.end_pose_cost();
    let path = all.path_cost(CostKind::PATH.heading_weight());
    let (position, heading) = (position_stats(errors), heading_stats(errors));
    if a.output.json {
        let runs: Vec<_> = ds
            .runs
            .iter()
            .zip(errors)
            .map(|(r, e)| {
                json!({
                    "name": r.name(),
                    "command": r.command(),
                    "dx_m": e.dx_m, "dy_m": e.dy_m, "dtheta_rad": e.dtheta_rad,
                    "pos_err_m": e.position_m(), "eq6_term": e.norm(),
                })
            })
            .collect();
        let mut out = json!({
            "cost": c, "path_cost": path, "model": model, "runs": runs,
            "end_position_error_m": position.to_json(), "end_heading_error_rad": heading.to_json(),
        });
        if !ds.ground_truth_clocks.is_empty() {
            out["ground_truth_clock"] = ds.ground_truth_clocks.iter().map(|g| g.to_json()).collect();
        }
        return super::print_json("eval", out);
    }
    print_summary(model, ds.runs.len(), c, path, position, heading.scaled(180.0 / std::f64::consts::PI));
    if a.per_run {
        println!();
        print_rows(&ds.runs, errors);
    }
    Ok(())
}

/// The summary: the costs, then the statistics of the end-position (m) and end-heading (deg) errors.
fn print_summary(model: &str, runs: usize, cost: f64, path: f64, position_m: Stats, heading_deg: Stats) {
    println!("model {model}: {}", crate::units::count(runs, "run"));
    println!("cost (Eq. 6) {cost:.5} (mean of sqrt(dx² + dy² + dθ²), m and rad with weight 1); path RMS {path:.5} m");
    println!("{:<22} {:>9} {:>9} {:>9} {:>9}", "end-pose error", "mean", "median", "rmse", "max");
    for (name, s) in [("position m", position_m), ("heading deg (|dθ|)", heading_deg)] {
        println!("{name:<22} {:>9.4} {:>9.4} {:>9.4} {:>9.4}", s.mean, s.median, s.rmse, s.max);
    }
}

/// One row per run: the end-pose error in m and deg.
fn print_rows(runs: &[omni_kin::Run], errors: &[PoseError]) {
    println!("{:<28} {:>18} {:>9} {:>9} {:>10} {:>12}", "run", "command", "dx_m", "dy_m", "pos_err_m", "yaw_err_deg");
    for (r, e) in runs.iter().zip(errors) {
        let cmd = r.command().map(|c| c.label()).unwrap_or_else(|| "-".into());
        println!(
            "{:<28} {:>18} {:>9.4} {:>9.4} {:>10.4} {:>12.3}",
            r.name(),
            cmd,
            e.dx_m,
            e.dy_m,
            e.position_m(),
            e.dtheta_rad.to_degrees()
        );
    }
}
