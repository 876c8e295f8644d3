//! `omnical train`: fit a model to training runs.

use super::{DataArgs, OutputArgs};
use crate::api::fit::{FitOptions, check_step};
use crate::api::train::{Fitted, Prepared, Summarized, TrainRequest, fit_prepared, prepare, write_model};
use crate::cli::{choice, effect_help};
use crate::units::{count, std_error_text, value_text};
use crate::{interrupt, out_path, progress};
use omni_ga::calibrate::{Calibration, Preset, Unexcited};
use omni_ga::identify::IdentifyOptions;
use omni_ga::science::text;
use omni_kin::KinematicsKind;
use omni_kin::cost::{CostKind, CostName};
use serde_json::json;
use std::path::PathBuf;

/// Arguments of `omnical train`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Training run files or folders.
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// Base model to fit. Default: `diff` for a differential drive (its three parameters; a 3 × 2 matrix
    /// has a fourth, weakly determined direction that trades the radii's ratio), else, and under
    /// `--preset paper`, `ik` (the paper's matrix).
    #[arg(long, value_parser = choice::<KinematicsKind>())]
    pub model: Option<KinematicsKind>,
    /// Start from this model file instead of the design.
    #[arg(long)]
    pub start: Option<PathBuf>,
    /// Training recipe: search method, objective and limits.
    #[arg(long, value_parser = choice::<Preset>(), default_value_t = Preset::default())]
    pub preset: Preset,
    /// Seed of the genetic algorithm's random search: the same seed gives the same model, whatever
    /// --threads.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Add an effect to fit (an effect id). Repeatable.
    #[arg(long = "effect", value_name = "NAME", help = effect_help("Add an effect to fit. Repeatable."))]
    pub effects: Vec<String>,
    /// Write the fitted model here (TOML; read back by `--model FILE`). Without it the fit is printed and
    /// nothing is written. Its folder must exist (checked before the fit).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Fit and write even when the fit is refused: a preset whose fixed step misses the runs' sampling,
    /// or a fitted model worse than its start on its own training runs (each then a warning).
    #[arg(long)]
    pub force: bool,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
    /// Objective and unconstrained directions.
    #[command(flatten)]
    pub fit: FitArgs,
    /// Data options.
    #[command(flatten)]
    pub data: DataArgs,
}

/// Overrides of a preset's objective and its handling of unconstrained directions.
#[derive(Debug, clap::Args)]
pub struct FitArgs {
    /// Objective (default: the preset's; paper: end-pose, default: path).
    #[arg(long, value_parser = choice::<CostName>())]
    pub objective: Option<CostName>,
    /// Path objective: use every k-th ground-truth pose (odometry is evaluated at its stamp).
    #[arg(long, default_value_t = CostKind::PATH_EVERY, value_name = "K")]
    pub every: usize,
    /// Path objective: weight of heading errors against position errors (m/rad).
    #[arg(long, default_value_t = CostKind::PATH_HEADING_WEIGHT_M_PER_RAD, value_name = "M_PER_RAD")]
    pub heading_weight: f64,
    /// Directions the runs do not constrain: hold them at the start or let them move (default: the
    /// preset's; paper: move, default: hold).
    #[arg(long, value_parser = choice::<Unexcited>())]
    pub unexcited: Option<Unexcited>,
    /// A direction is unconstrained when its standard error exceeds this fraction of the parameters'
    /// scale.
    #[arg(long, default_value_t = IdentifyOptions::default().max_std_error, value_name = "FRACTION")]
    pub max_std_error: f64,
    /// A direction is unconstrained when its singular value (scaled Jacobian) is below this fraction of
    /// the largest.
    #[arg(long, default_value_t = IdentifyOptions::default().min_excitation, value_name = "FRACTION")]
    pub min_excitation: f64,
}

impl FitArgs {
    /// The fit settings these flags give (checked when applied to a plan).
    pub fn options(&self) -> FitOptions {
        FitOptions {
            objective: self.objective,
            every: self.every,
            heading_weight_m_per_rad: self.heading_weight,
            unexcited: self.unexcited,
            max_std_error: self.max_std_error,
            min_excitation: self.min_excitation,
        }
    }
}

impl Args {
    /// What these flags ask `omnical train` to do.
    pub fn request(&self) -> TrainRequest {
        TrainRequest {
            runs: self.runs.clone(),
            data: self.data.options(),
            model: self.model,
            start: self.start.clone(),
            preset: self.preset,
            seed: self.seed,
            effects: self.effects.clone(),
            out: self.out.clone(),
            force: self.force,
            fit: self.fit.options(),
        }
    }
}

/// Exit status of a refused fit ([`crate::api::fit::Refused`]): 1 (an error in the input is 2).
pub const EXIT_REFUSED: i32 = 1;

/// Runs `omnical train`; `quiet` hides the progress display.
pub fn run(a: &Args, quiet: bool) -> anyhow::Result<()> {
    // Ctrl-C while loading ends the command; during the fit it stops the GA at its next generation and the
    // best model so far is reported and written.
    interrupt::install();
    if let Some(out) = &a.out {
        out_path::check_file(out, "--out")?;
    }
    let prepared = prepare(&a.request());
    if interrupt::requested() {
        // Ctrl-C while loading: nothing was fitted, whatever the preparation gave.
        return Err(interrupt::Interrupted.into());
    }
    let prepared = prepared?;
    let preset_name = a.preset.id();
    if let Some(w) = check_step(&prepared.plan, &prepared.ds.runs, a.force)? {
        tracing::warn!("{w}");
    }
    let mut bar = progress::ProgressObserver::new(quiet);
    crate::note!(
        "training on {}: preset {preset_name}, seed {} (Ctrl-C stops early and keeps the best so far)",
        count(prepared.ds.runs.len(), "run"),
        a.seed
    );
    let recipe = a.request().recipe();
    let fitted = fit_prepared(&prepared, recipe, a.force, &mut interrupt::StopOnInterrupt(&mut bar))?;
    bar.finish();
    let Fitted { calibration: c, summarized: Summarized { summary: mut s, designs, mount }, warning } = fitted;
    if let Some(w) = warning {
        tracing::warn!("{w}");
    }
    let interrupted = interrupt::requested();
    let Prepared { ds, priors, .. } = prepared;
    if interrupted {
        s["interrupted"] = json!(true);
    }
    if let Some(out) = &a.out {
        write_model(&c.fitted, &s, out)?;
    }
    if a.output.json {
        if !ds.ground_truth_clocks.is_empty() {
            s["ground_truth_clock"] = ds.ground_truth_clocks.iter().map(|g| g.to_json()).collect();
        }
        s["out"] = json!(a.out.as_ref().map(|p| p.display().to_string()));
        super::print_json("train", s)?;
    } else {
        print_text(&c, (&s, preset_name, ds.runs.len()), designs.as_ref(), &priors, (a.out.as_deref(), interrupted));
    }
    if let Some(w) = &mount {
        tracing::warn!("{w}");
    }
    let position_only = ds.runs.iter().filter(|r| r.truth_position_only()).count();
    if position_only > 0 {
        crate::note!("note: {}", position_only_text(position_only, ds.runs.len()));
    }
    if a.out.is_none() {
        crate::note!("note: the fitted model was not written (no --out FILE)");
    }
    if interrupted {
        return Err(interrupt::Interrupted.into());
    }
    Ok(())
}

/// What a reference of positions only (`n` of `total` runs) leaves undetermined.
pub fn position_only_text(n: usize, total: usize) -> String {
    format!(
        "{n} of {total} runs have a reference of positions only (no heading): each run's start heading is fitted \
         with the model and headings are not compared. Such a reference cannot see the orientation of the body \
         frame (one rotation of the vx and vy rows, which turns every path about its start as a start heading \
         does): the fit holds it at the start's forward direction. Turning in place tells nothing either; turning \
         while driving determines the rotation row"
    )
}

/// `train`'s text on stdout: the fit's summary, its noise model, the designs, the priors and where the
/// model went (`out`, and whether the fit was `interrupted`).
fn print_text(
    c: &Calibration,
    (s, preset_name, runs): (&serde_json::Value, &str, usize),
    designs: Option<&crate::api::train::DesignsFigure>,
    priors: &[crate::api::fit::PriorUse],
    (out, interrupted): (Option<&std::path::Path>, bool),
) {
    if interrupted {
        println!("interrupted (Ctrl-C): the best model found so far (the GA stopped early; no polish)");
    }
    print_summary(c, preset_name, runs);
    if let Some(n) = crate::api::noise::from_summary(s) {
        println!("{}", crate::api::noise::describe(&n));
    }
    if let Some(d) = designs {
        println!("{}", d.describe());
    }
    for p in priors {
        println!("{}", p.describe(&c.fitted));
    }
    if let Some(out) = out {
        let what = if interrupted { "best-so-far model" } else { "model" };
        println!("{what} written to {}", out.display());
    }
}

/// Human-readable fit summary on stdout; its warnings and notes go to stderr.
pub fn print_summary(c: &Calibration, preset: &str, runs: usize) {
    // The integration belongs to the figures: the same design costs a little differently under another
    // preset's integration (the paper's Euler steps of 10 ms, the default's exact arcs).
    println!(
        "preset {preset}: {}, objective {}, integration {}",
        count(runs, "training run"),
        c.objective.name(),
        integration_text(c.fitted.model.integration)
    );
    println!(
        "cost (Eq. 6)  design {:.5}  fitted {:.5}  improvement {:.1} %",
        c.end_pose_start,
        c.end_pose_fitted,
        c.improvement_pct()
    );
    println!("objective     design {:.5}  fitted {:.5}", c.objective_start, c.objective_fitted);
    if let Ok(m) = c.fitted.ik() {
        println!("fitted IK matrix (rows vx m/s, vy m/s, ω rad/s per wheel rad/s):");
        for r in m.rows() {
            println!("  [{}]", r.iter().map(|v| format!("{v:>14.10}")).collect::<Vec<_>>().join(" "));
        }
    }
    let nb = c.fitted.model.n_base();
    let specs = c.fitted.model.params();
    // The matrix above shows base parameters that are its entries (all of an `ik` model's, also when some
    // entries are structural zeros, as a diff base's vy row); print the others.
    let base_shown = c.fitted.model.kinematics.kind() == KinematicsKind::Ik;
    if !base_shown || specs.len() > nb {
        for (i, s) in specs.iter().enumerate() {
            if i >= nb || !base_shown {
                println!("  {:<28} {}", s.name, value_text(c.fitted.params[i], &s.unit));
            }
        }
    }
    println!("{} evaluations, {:.2} s", c.evaluations, c.seconds);
    if let Some(text) = crate::api::train::start_rescaled_text(c) {
        crate::note!("{text}");
    }
    if !c.at_bound.is_empty() {
        tracing::warn!("ended on a bound of the GA box: {}", c.at_bound.join(", "));
    }
    if !c.outside_box.is_empty() {
        // Nothing to do: the polish is not bound by the GA's box, and its result is the fit above.
        tracing::info!(
            "the polish moved {} beyond the GA's search box (the polish is not bound by it; the fit above is its result)",
            c.outside_box.join(", ")
        );
    }
    print_identifiability(c);
}

/// How a model integrates: `exact arcs, each run's median step`, `Euler, fixed 0.010 s steps`.
pub fn integration_text(i: omni_kin::Integration) -> String {
    let scheme = match i.scheme {
        omni_kin::Scheme::Euler => "Euler",
        omni_kin::Scheme::ExactArc => "exact arcs",
    };
    let step = match i.step {
        omni_kin::StepMode::Fixed { dt_s: Some(dt) } => format!("fixed {dt:.3} s steps"),
        omni_kin::StepMode::Fixed { dt_s: None } => "each run's median step".into(),
        omni_kin::StepMode::Stamps => "the measured stamps".into(),
    };
    format!("{scheme}, {step}")
}

/// Standard errors and condition number on stdout. Directions the runs do not constrain: when the fit
/// held them at the start (the default), one note says so and what they are (each one's description with
/// `-v`), and the standard errors are those with them held, marked; when the fit let them move, a warning
/// per direction says what to do.
pub fn print_identifiability(c: &Calibration) {
    let id = &c.identifiability;
    let held = !c.held.is_empty();
    println!(
        "identifiability: condition number {:.3e} (scaled), residual RMS {:.4} m, standard errors {}{}",
        id.condition_number,
        id.residual_rms,
        text::covariance(id),
        if held && id.params.iter().any(|p| p.std_error.is_none()) {
            format!("; * = with the {} held at the start", count(c.held.len(), "direction"))
        } else {
            String::new()
        }
    );
    // The IK matrix's ω row is in rad per wheel rad, a ratio and not an angle: it keeps its unit.
    let model = &c.fitted.model;
    let ik_entries: Vec<String> = if model.kinematics.kind() == KinematicsKind::Ik {
        model.params().into_iter().take(model.n_base()).map(|s| s.name).collect()
    } else {
        Vec::new()
    };
    // A parameter that carries a held direction has no standard error of its own; with the held directions
    // fixed (what the fit did) it has one: the covariance over the constrained directions.
    let with_held = |i: usize| id.covariance.get(i).and_then(|row| row.get(i)).map(|v| v.max(0.0).sqrt());
    let se: Vec<String> = id
        .params
        .iter()
        .enumerate()
        .map(|(i, p)| match (p.std_error, with_held(i).filter(|_| held)) {
            (Some(s), _) if ik_entries.contains(&p.name) => format!("{} ±{:.2e} {}", p.name, s, p.unit),
            (Some(s), _) => format!("{} {}", p.name, std_error_text(s, &p.unit)),
            (None, Some(s)) if ik_entries.contains(&p.name) => format!("{} ±{:.2e} {}*", p.name, s, p.unit),
            (None, Some(s)) => format!("{} {}*", p.name, std_error_text(s, &p.unit)),
            (None, None) => format!("{} undetermined", p.name),
        })
        .collect();
    for chunk in se.chunks(3) {
        println!("  {}", chunk.join(" · "));
    }
    // A held direction leaves the fit as the start has it: a warning only where the command itself could
    // do better (an end-pose objective on runs whose paths would constrain it); the others are in the note,
    // each described with -v. Directions the fit let move are each a warning.
    let end_pose = matches!(c.objective, CostKind::EndPose);
    for w in &id.weak {
        let actionable = !held || (end_pose && w.remedy == omni_ga::identify::Advice::PathObjective);
        let line = text::warning(w);
        match (actionable, end_pose) {
            (true, _) => tracing::warn!("{line}"),
            (false, true) => tracing::info!("{line}"),
            (false, false) => {
                tracing::info!("{}", line.replace(PATH_OBJECTIVE_ADVICE, "add runs along different paths"))
            }
        }
    }
    if held {
        crate::note!("note: {}", held_text(c));
    }
}

/// The advice of a direction the residuals barely see, whose first half is moot under the path objective.
const PATH_OBJECTIVE_ADVICE: &str =
    "fit the path objective (every ground-truth pose), or add runs along different paths";

/// The note on the directions the fit held at the start: how many, which of them no run can excite
/// (nothing to do) and which are poorly constrained (with what would determine them).
fn held_text(c: &Calibration) -> String {
    let nowhere = c.held.iter().filter(|w| w.remedy == omni_ga::identify::Advice::HeldAtDesign).count();
    let poorly: Vec<String> = c
        .held
        .iter()
        .filter(|w| w.remedy != omni_ga::identify::Advice::HeldAtDesign)
        .map(|w| w.std_error.map_or_else(|| "not excited".to_string(), |s| format!("±{:.1} %", 100.0 * s)))
        .collect();
    let mut parts = Vec::new();
    if nowhere > 0 {
        parts.push(format!(
            "{nowhere} that no run can excite (the wheels fighting each other, which moves the robot nowhere: nothing to do)"
        ));
    }
    if !poorly.is_empty() {
        parts.push(format!(
            "{} poorly constrained by these runs ({} of scale; runs along other paths would determine them)",
            poorly.len(),
            poorly.join(", ")
        ));
    }
    format!(
        "{} direction(s) held at the start values (truncated update; `--unexcited move` lets them move): {}; `-v` \
         describes each",
        c.held.len(),
        parts.join("; ")
    )
}
