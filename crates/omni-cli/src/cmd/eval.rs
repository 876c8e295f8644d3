//! `omnical eval`: the cost of a model on runs — the summary first (Eq. 6, path RMS, statistics of the
//! end-position and end-heading errors; the absolute pose error at every ground-truth pose, as evo_ape
//! computes it on the TUM export, without and with its `--align`; the relative pose error over a window of
//! travel or time, as evo_rpe's, and its drift in % of distance), each run's row with `--per-run`.

use super::{DataArgs, OutputArgs};
use crate::api::{ModelSpec, noise};
use omni_kin::cost::CostKind;
use omni_kin::relative::{RelativeErrors, RpeSummary};
use omni_kin::{AbsoluteErrors, ApeSummary, PoseError, RpeDelta, Stats};
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
    /// error (deg); and its relative pose error: pairs, translation RMSE (m), mean drift (%). `--json`
    /// always lists the runs.
    #[arg(long)]
    pub per_run: bool,
    /// Window of the relative pose error (RPE, as evo_rpe's consecutive pairs, taken on the ground truth):
    /// a distance travelled in metres (`1m`, as `evo_rpe --delta 1 --delta_unit m`) or a time in seconds
    /// (`2s`).
    #[arg(long, value_name = "WINDOW", default_value_t = RpeDelta::DEFAULT, allow_hyphen_values = true)]
    pub rpe_delta: RpeDelta,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
    /// Data options.
    #[command(flatten)]
    pub data: DataArgs,
}

/// A statistics object in JSON: `mean`, `median`, `rmse`, `max` (null where there was no value).
fn stats_json(s: Stats) -> serde_json::Value {
    json!({ "mean": s.mean, "median": s.median, "rmse": s.rmse, "max": s.max })
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
    // Every ground-truth pose (the path cost's): the relative errors read the odometry at each.
    let all = models.errors(&ds.runs, CostKind::PATH.selection())?;
    let relative = RelativeErrors::new(&ds.runs, &all, a.rpe_delta)?;
    let absolute = AbsoluteErrors::new(&ds.runs, &all)?;
    let trust = noise_check(&a.model, &models, &ds.runs, &all)?;
    let errors = all.ends();
    let c = all.end_pose_cost();
    let path = all.path_cost(CostKind::PATH.heading_weight());
    let (position, heading) = (position_stats(errors), heading_stats(errors));
    if a.output.json {
        let runs: Vec<_> = ds
            .runs
            .iter()
            .zip(errors)
            .enumerate()
            .map(|(i, (r, e))| {
                json!({
                    "name": r.name(),
                    "command": r.command(),
                    "dx_m": e.dx_m, "dy_m": e.dy_m, "dtheta_rad": e.dtheta_rad,
                    "pos_err_m": e.position_m(), "eq6_term": e.norm(),
                    "rpe": rpe_json(&relative.run_summary(i)),
                    "ape": ape_json(&absolute.run_summary(i)),
                })
            })
            .collect();
        let mut rpe = rpe_json(&relative.summary());
        rpe["delta"] = a.rpe_delta.value().into();
        rpe["delta_unit"] = a.rpe_delta.unit().into();
        let mut out = json!({
            "cost": c, "path_cost": path, "model": model, "runs": runs,
            "end_position_error_m": stats_json(position), "end_heading_error_rad": stats_json(heading),
            "rpe": rpe, "ape": ape_json(&absolute.summary()),
        });
        if let Some((n, checks)) = &trust {
            out["noise"] = serde_json::to_value(n)?;
            out["noise_coverage"] = noise::coverage_json(checks);
            out["noise_verdict"] = json!(noise::verdict(n, &checks[0]));
        }
        if !ds.ground_truth_clocks.is_empty() {
            out["ground_truth_clock"] = ds.ground_truth_clocks.iter().map(|g| g.to_json()).collect();
        }
        return super::print_json("eval", out);
    }
    print_summary(model, ds.runs.len(), c, path, position, heading.scaled(180.0 / std::f64::consts::PI));
    print_ape(&absolute.summary());
    print_rpe(&relative);
    if let Some((n, checks)) = &trust {
        print_noise(n, checks);
    }
    if a.per_run {
        println!();
        print_rows(&ds.runs, errors, &relative, &absolute);
    }
    Ok(())
}

/// The model file's noise model (`None` for `design`, `paper` and files without one) and its check on the
/// runs beside the stock defaults.
fn noise_check(
    spec: &ModelSpec,
    models: &omni_kin::RunModels,
    runs: &[omni_kin::Run],
    errors: &omni_kin::evaluate::RunErrors,
) -> anyhow::Result<Option<(omni_kin::noise::OdometryNoise, Vec<omni_kin::noise::Coverage>)>> {
    let ModelSpec::File(path) = spec else { return Ok(None) };
    let Some(n) = crate::model_file::read_noise(path)? else { return Ok(None) };
    let checks = noise::check(&n, models.first(), runs, errors)?;
    Ok(Some((n, checks)))
}

/// How far to trust the odometry: the share of windows inside the noise model's 95 % ellipse and the NEES
/// at each horizon, for the model and the stock defaults; a coverage outside 90–98 % says why.
fn print_noise(n: &omni_kin::noise::OdometryNoise, checks: &[omni_kin::noise::Coverage]) {
    println!();
    println!("{}", noise::describe(n));
    let Some(first) = checks.first() else { return };
    let heads: Vec<String> = first.horizons.iter().map(|h| noise::horizon_text(h.horizon)).collect();
    print!("{:<34}", "inside the 95 % ellipse (NEES)");
    for h in &heads {
        print!(" {h:>20}");
    }
    println!();
    for c in checks {
        print!("{:<34}", c.predictor);
        for h in &c.horizons {
            let cell =
                if h.windows == 0 { "-".to_string() } else { format!("{:.1} % ({:.2})", 100.0 * h.coverage, h.nees) };
            print!(" {cell:>20}");
        }
        println!();
    }
    println!("(NEES: mean eᵀ Σ⁻¹ e of the position error, 2 for a true model)");
    if let Some(v) = noise::verdict(n, first) {
        tracing::warn!("{v}");
    }
}

/// The relative pose error of some pairs in JSON: SI units (m, rad), drift in %.
fn rpe_json(s: &RpeSummary) -> serde_json::Value {
    json!({
        "pairs": s.pairs,
        "translation_m": stats_json(s.translation_m),
        "rotation_rad": stats_json(s.rotation_rad),
        "drift_pairs": s.drift_pairs,
        "drift_pct": stats_json(s.drift_pct),
    })
}

/// The absolute pose error of some runs in JSON (m): evo_ape's translation part, without and with
/// `--align`.
fn ape_json(s: &ApeSummary) -> serde_json::Value {
    json!({
        "poses": s.poses,
        "translation_m": stats_json(s.translation_m),
        "aligned_translation_m": stats_json(s.aligned_translation_m),
    })
}

/// The absolute pose error at every ground-truth pose: evo_ape's figure on the TUM export.
fn print_ape(s: &ApeSummary) {
    println!();
    println!(
        "absolute pose error at {} (evo_ape tum GT EST: translation part, poses matched by stamp; \
         aligned: its --align, a rigid Umeyama fit per run)",
        crate::units::count(s.poses, "ground-truth pose")
    );
    print_stats(
        "APE translation m",
        &[("evo_ape default", s.translation_m), ("evo_ape --align", s.aligned_translation_m)],
    );
}

/// The summary: the costs, then the statistics of the end-position (m) and end-heading (deg) errors.
fn print_summary(model: &str, runs: usize, cost: f64, path: f64, position_m: Stats, heading_deg: Stats) {
    println!("model {model}: {}", crate::units::count(runs, "run"));
    println!("cost (Eq. 6) {cost:.5} (mean of sqrt(dx² + dy² + dθ²), m and rad with weight 1); path RMS {path:.5} m");
    print_stats("end-pose error", &[("position m", position_m), ("heading deg (|dθ|)", heading_deg)]);
}

/// A table of statistics, one row per error.
fn print_stats(title: &str, rows: &[(&str, Stats)]) {
    println!("{title:<22} {:>9} {:>9} {:>9} {:>9}", "mean", "median", "rmse", "max");
    for (name, s) in rows {
        println!("{name:<22} {:>9.4} {:>9.4} {:>9.4} {:>9.4}", s.mean, s.median, s.rmse, s.max);
    }
}

/// The relative pose error over all pairs: translation (m), rotation (deg) and drift (% of distance).
fn print_rpe(relative: &RelativeErrors) {
    let delta = relative.delta();
    let over = match delta {
        RpeDelta::DistanceM(d) => format!("{d} m of travel"),
        RpeDelta::TimeS(t) => format!("{t} s"),
    };
    let s = relative.summary();
    println!();
    if s.pairs == 0 {
        println!("relative pose error over {over}: no pair (no run spans {over}; see --rpe-delta)");
        return;
    }
    println!(
        "relative pose error over {over}: {} (evo_rpe's consecutive pairs, on the ground truth)",
        crate::units::count(s.pairs, "pair")
    );
    let rows =
        [("translation m", s.translation_m), ("rotation deg", s.rotation_rad.scaled(180.0 / std::f64::consts::PI))];
    print_stats("RPE per window", &rows);
    if s.drift_pairs == 0 {
        println!("drift: no pair travels {} m or more", delta.drift_min_distance_m());
        return;
    }
    let (d, counted) = (s.drift_pct, s.drift_pairs);
    let of = if counted == s.pairs {
        String::new()
    } else {
        format!(" ({counted} pairs of {:.1} m or more)", delta.drift_min_distance_m())
    };
    println!("{:<22} {:>9.4} {:>9.4} {:>9.4} {:>9.4}{of}", "drift % of distance", d.mean, d.median, d.rmse, d.max);
}

/// One row per run: the end-pose error in m and deg, the RPE's pairs, translation RMSE (m) and mean drift
/// (%), and the APE's RMSE (m) without and with alignment.
fn print_rows(runs: &[omni_kin::Run], errors: &[PoseError], relative: &RelativeErrors, absolute: &AbsoluteErrors) {
    println!(
        "{:<28} {:>18} {:>9} {:>9} {:>10} {:>12} {:>9} {:>11} {:>9} {:>11} {:>13}",
        "run",
        "command",
        "dx_m",
        "dy_m",
        "pos_err_m",
        "yaw_err_deg",
        "rpe_pairs",
        "rpe_rmse_m",
        "drift_pct",
        "ape_rmse_m",
        "ape_aligned_m"
    );
    for (i, (r, e)) in runs.iter().zip(errors).enumerate() {
        let cmd = r.command().map(|c| c.label()).unwrap_or_else(|| "-".into());
        let rpe = relative.run_summary(i);
        let ape = absolute.run_summary(i);
        let (t, d) = (rpe.translation_m.rmse, rpe.drift_pct.mean);
        let cell = |v: f64, prec: usize| if v.is_nan() { "-".to_string() } else { format!("{v:.prec$}") };
        println!(
            "{:<28} {:>18} {:>9.4} {:>9.4} {:>10.4} {:>12.3} {:>9} {:>11} {:>9} {:>11} {:>13}",
            r.name(),
            cmd,
            e.dx_m,
            e.dy_m,
            e.position_m(),
            e.dtheta_rad.to_degrees(),
            rpe.pairs,
            cell(t, 4),
            cell(d, 2),
            cell(ape.translation_m.rmse, 4),
            cell(ape.aligned_translation_m.rmse, 4)
        );
    }
}
