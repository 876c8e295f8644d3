//! `omnical plan`: propose calibration runs that excite every parameter.

use super::{DataArgs, OutputArgs};
use crate::cli::{choice, effect_help};
use crate::{atomic, design, robot_file};
use anyhow::Context;
use omni_ga::excitation::{self, PlanRequest, RunPlan, RunSet};
use omni_kin::simulate::SimConfig;
use omni_kin::{EffectKind, FittedModel, KinematicsKind, Model, RobotGeometry};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `omnical plan`: what to plan for (defaults: [`PlanRequest::default`]) and where.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Base model to plan for.
    #[arg(long, value_parser = choice::<KinematicsKind>(), default_value_t = KinematicsKind::default())]
    pub model: KinematicsKind,
    /// An effect to plan for (an effect id). Repeatable.
    #[arg(long = "effect", value_name = "NAME", help = effect_help("An effect to plan for. Repeatable."))]
    pub effects: Vec<String>,
    /// Take the robot's geometry from these runs (OptiOdom metadata), when there is no --robot: a file or
    /// folder; repeat for more (`--robot-from A --robot-from B`).
    #[arg(long = "robot-from", value_name = "RUNS")]
    pub robot_from: Vec<PathBuf>,
    /// Which set: a D-optimal pick from a library of commands, or the paper's 36 flower commands.
    #[arg(long, value_parser = choice::<RunSet>(), default_value_t = RunSet::default())]
    pub set: RunSet,
    /// Distinct commands to pick (greedy).
    #[arg(long, default_value_t = PlanRequest::default().runs)]
    pub runs: usize,
    /// Repetitions of each command.
    #[arg(long, default_value_t = PlanRequest::default().repetitions)]
    pub repetitions: usize,
    /// Translation speed of the commands (m/s).
    #[arg(long = "speed", default_value_t = PlanRequest::default().speed_m_s, value_name = "M_S")]
    pub speed_m_s: f64,
    /// Turn rate of the commands (rad/s).
    #[arg(long = "omega", default_value_t = PlanRequest::default().omega_rad_s, value_name = "RAD_S")]
    pub omega_rad_s: f64,
    /// How long each command is held (s).
    #[arg(long = "duration", default_value_t = PlanRequest::default().duration_s, value_name = "S")]
    pub duration_s: f64,
    /// Ground-truth rate (Hz).
    #[arg(long = "truth-rate", default_value_t = PlanRequest::default().truth_rate_hz, value_name = "HZ")]
    pub truth_rate_hz: f64,
    /// Ground-truth position noise per axis (m).
    #[arg(long, default_value_t = PlanRequest::default().truth_noise_m, value_name = "M")]
    pub truth_noise_m: f64,
    /// Ground-truth heading noise (rad).
    #[arg(long, default_value_t = PlanRequest::default().truth_noise_rad, value_name = "RAD")]
    pub truth_noise_rad: f64,
    /// Plan runs for a tape measure instead (no motion capture): UMBmark's square paths of SIDE metres,
    /// 5 clockwise and 5 counter-clockwise, and 2 straight runs of SIDE metres for the wheels' scale; prints
    /// the protocol, and with --out writes the end-pose table to fill in (`train --gt-kind end-pose`).
    #[arg(long, value_name = "SIDE_M")]
    pub umbmark: Option<f64>,
    /// Write the planned commands as CSV here (v_m_s, alpha_deg, omega_rad_s, repetitions); with
    /// --umbmark, the end-pose table to fill in.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
    /// Data options (for --robot-from).
    #[command(flatten)]
    pub data: DataArgs,
}

impl Args {
    /// The library's request: these arguments over [`PlanRequest::default`].
    pub fn request(&self) -> PlanRequest {
        PlanRequest {
            speed_m_s: self.speed_m_s,
            omega_rad_s: self.omega_rad_s,
            duration_s: self.duration_s,
            truth_rate_hz: self.truth_rate_hz,
            truth_noise_m: self.truth_noise_m,
            truth_noise_rad: self.truth_noise_rad,
            runs: self.runs,
            repetitions: self.repetitions,
            set: self.set,
            ..PlanRequest::default()
        }
    }
}

/// Runs `omnical plan`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    if let Some(out) = &a.out {
        crate::out_path::check_file(out, "--out")?;
    }
    if let Some(side_m) = a.umbmark {
        return umbmark(side_m, a);
    }
    check_pace(a)?;
    let robot = plan_robot(a)?;
    let mut model = FittedModel::nominal(Model::design(a.model, Some(&robot))?);
    for id in &a.effects {
        model = model
            .with_effect(EffectKind::from_id(id, model.model.n_wheels()).with_context(|| format!("--effect {id}"))?);
    }
    let req = &a.request();
    let sim = SimConfig { design: robot, ..SimConfig::default() };
    let plan = excitation::plan(&model, &sim, req)?;
    // The paper's flower set beside a greedy plan, for comparison.
    let flower = match req.set {
        RunSet::Greedy => Some(excitation::plan(&model, &sim, &PlanRequest { set: RunSet::Flower, ..req.clone() })?),
        RunSet::Flower => None,
    };
    if let Some(out) = &a.out {
        atomic::write_atomic(out, plan_csv(&plan).as_bytes()).with_context(|| format!("writing {}", out.display()))?;
    }
    if a.output.json {
        let out = a.out.as_ref().map(|p| p.display().to_string());
        return super::print_json("plan", serde_json::json!({"plan": plan, "flower": flower, "out": out}));
    }
    print_plan(&plan, flower.as_ref(), req, benchmark_name(&sim.design));
    if let Some(out) = &a.out {
        println!("plan written to {}", out.display());
    }
    Ok(())
}

/// The fastest commands a plan is made for: a wheeled robot's calibration runs (a warehouse robot drives
/// 2 m/s; a plan is driven at a calibration run's pace, 0.2 m/s by default). m/s and rad/s (two turns a
/// second).
const MAX_PLAN_SPEED_M_S: f64 = 5.0;
const MAX_PLAN_OMEGA_RAD_S: f64 = 4.0 * std::f64::consts::PI;

/// Refuses a speed or turn rate no robot's calibration run is driven at (m/s taken for km/h or mm/s, deg/s
/// for rad/s), naming the flag and the unit.
fn check_pace(a: &Args) -> anyhow::Result<()> {
    anyhow::ensure!(
        a.speed_m_s <= MAX_PLAN_SPEED_M_S || a.speed_m_s.is_nan(),
        "--speed {} m/s: faster than the calibration runs of a wheeled robot are driven (at most \
         {MAX_PLAN_SPEED_M_S} m/s; the default is {} m/s); give the runs' translation speed in m/s (not km/h or \
         mm/s)",
        a.speed_m_s,
        PlanRequest::default().speed_m_s
    );
    anyhow::ensure!(
        a.omega_rad_s <= MAX_PLAN_OMEGA_RAD_S || a.omega_rad_s.is_nan(),
        "--omega {} rad/s: {:.0}°/s, faster than the calibration runs of a wheeled robot turn (at most {:.1} rad/s, \
         two turns a second; the default is {} rad/s); give the turn rate in rad/s (not deg/s)",
        a.omega_rad_s,
        a.omega_rad_s.to_degrees(),
        MAX_PLAN_OMEGA_RAD_S,
        PlanRequest::default().omega_rad_s
    );
    Ok(())
}

/// UMBmark's runs per direction (Borenstein and Feng, 1996).
const UMBMARK_RUNS: usize = 5;
/// Straight runs for the wheels' scale, which closed squares leave undetermined.
const STRAIGHT_RUNS: usize = 2;

/// The runs of `plan --umbmark`: `umbmark-cw-1` … `umbmark-ccw-5`, `umbmark-straight-1`, ….
fn umbmark_runs() -> Vec<String> {
    let square = |dir: &'static str| (1..=UMBMARK_RUNS).map(move |k| format!("umbmark-{dir}-{k}"));
    square("cw").chain(square("ccw")).chain((1..=STRAIGHT_RUNS).map(|k| format!("umbmark-straight-{k}"))).collect()
}

/// `omnical plan --umbmark SIDE_M`: the protocol in words, the end-pose table to fill in with `--out`.
fn umbmark(side_m: f64, a: &Args) -> anyhow::Result<()> {
    anyhow::ensure!(
        side_m.is_finite() && (0.5..=50.0).contains(&side_m),
        "--umbmark {side_m}: the side of the square must be between 0.5 and 50 m (UMBmark uses 4 m; take what the \
         floor allows, the longer the better)"
    );
    let runs = umbmark_runs();
    let table: String = std::iter::once("run,x_mm,y_mm,yaw_deg".to_string())
        .chain(runs.iter().map(|r| format!("{r},,,")))
        .map(|l| l + "\n")
        .collect();
    if let Some(out) = &a.out {
        atomic::write_atomic(out, table.as_bytes()).with_context(|| format!("writing {}", out.display()))?;
    }
    if a.output.json {
        let out = a.out.as_ref().map(|p| p.display().to_string());
        return super::print_json("plan", serde_json::json!({"umbmark": {"side_m": side_m, "runs": runs}, "out": out}));
    }
    let n_square = 2 * UMBMARK_RUNS;
    println!(
        "UMBmark for a tape measure: {} runs, {n_square} squares of {side_m} m sides ({UMBMARK_RUNS} clockwise, \
         {UMBMARK_RUNS} counter-clockwise) and {STRAIGHT_RUNS} straight runs of {side_m} m",
        runs.len()
    );
    println!("  1. Mark the start on the floor: the robot's centre, and its heading by a second mark along its side.");
    println!(
        "  2. Record each run as its own recording named after it ({} … {}): start at rest on the mark; for a \
         square drive {side_m} m straight and turn 90° on the spot, four times (right for cw, left for ccw); for a \
         straight run drive {side_m} m straight; stop.",
        runs[0],
        runs[runs.len() - 1]
    );
    println!(
        "  3. Measure where it stopped, in the start's frame: x along the start heading and y to its left (mm), and \
         how much its heading turned (degrees, counter-clockwise positive)."
    );
    println!(
        "  4. Fill the table{} and train: omnical train umbmark-*.mcap --gt-kind end-pose --gt TABLE",
        a.out.as_ref().map_or_else(String::new, |p| format!(" ({})", p.display()))
    );
    println!(
        "The squares' end poses determine the radius ratio and the wheel separation (UMBmark's type A and B errors); \
         a closed square hides the wheels' common scale, which the straight runs give."
    );
    if let Some(out) = &a.out {
        println!("table written to {}", out.display());
    }
    Ok(())
}

/// The robot to plan for: `--robot`, else the geometry of the `--robot-from` runs, else a robot.toml beside
/// them or in the working directory. Plan needs it to turn commands into wheel speeds.
fn plan_robot(a: &Args) -> anyhow::Result<RobotGeometry> {
    if !a.robot_from.is_empty() {
        return Ok(design::geometry(&a.data.request(&a.robot_from).load()?)?);
    }
    match robot_file::resolve(a.data.robot.robot.as_deref(), &[])? {
        Some(r) => {
            robot_file::announce(&r.source);
            r.description.to_geometry().with_context(|| format!("robot {}", r.source))
        }
        None => Err(robot_file::no_design("plan").into()),
    }
}

/// The planned commands as CSV.
pub fn plan_csv(plan: &RunPlan) -> String {
    let mut s = String::from("v_m_s,alpha_deg,omega_rad_s,repetitions\n");
    for r in &plan.runs {
        let _ = writeln!(
            s,
            "{},{},{},{}",
            r.command.v_m_s,
            r.command.alpha_rad.to_degrees().round(),
            r.command.omega_rad_s,
            r.repetitions
        );
    }
    s
}

fn worst_relative_se(plan: &RunPlan) -> Option<f64> {
    plan.expected.params.iter().map(|p| p.std_error.map(|s| s / p.scale)).try_fold(0.0f64, |m, s| s.map(|s| m.max(s)))
}

/// What `--set flower` is on the robot `design` ([`benchmark_commands`]): the paper's flower, or, for a base
/// that cannot move sideways, a differential drive's own benchmark (it cannot drive the flower's petals).
fn benchmark_name(design: &RobotGeometry) -> &'static str {
    if design.is_omnidirectional() {
        "the paper's flower set"
    } else {
        "the diff benchmark set (forward/backward arcs, turns on the spot)"
    }
}

fn print_plan(plan: &RunPlan, flower: Option<&RunPlan>, req: &PlanRequest, benchmark: &str) {
    let name = match plan.set {
        RunSet::Greedy => "D-optimal pick",
        RunSet::Flower => benchmark,
    };
    println!(
        "{name}: {} runs of {:.0} s ({} distinct commands), ground truth at {} Hz with σ {} m / {} rad",
        plan.total_runs,
        req.duration_s,
        plan.runs.len(),
        req.truth_rate_hz,
        req.truth_noise_m,
        req.truth_noise_rad
    );
    println!("  {:>8} {:>8} {:>10} {:>5}", "v m/s", "α °", "ω rad/s", "reps");
    for r in &plan.runs {
        println!(
            "  {:>8.3} {:>8.0} {:>10.3} {:>5}",
            r.command.v_m_s,
            r.command.alpha_rad.to_degrees(),
            r.command.omega_rad_s,
            r.repetitions
        );
    }
    let id = &plan.expected;
    println!("expected standard errors (ground-truth noise only; wheel noise makes real ones larger):");
    for p in &id.params {
        match p.std_error {
            Some(se) => println!("  {:<26} ±{:.3e} {:<4} ({:.3} % of scale)", p.name, se, p.unit, 100.0 * se / p.scale),
            None => println!("  {:<26} undetermined", p.name),
        }
    }
    println!("condition number {:.3e} (scaled)", id.condition_number);
    for w in id.warnings() {
        tracing::warn!("{w}");
    }
    if let Some(f) = flower {
        match (worst_relative_se(plan), worst_relative_se(f)) {
            (Some(a), Some(b)) => println!(
                "for comparison, {benchmark} ({} runs): worst standard error {:.3} % of scale vs {:.3} % here",
                f.total_runs,
                100.0 * b,
                100.0 * a
            ),
            (Some(_), None) => {
                println!("for comparison, {benchmark} ({} runs) leaves some parameters undetermined", f.total_runs)
            }
            _ => {}
        }
    }
}
