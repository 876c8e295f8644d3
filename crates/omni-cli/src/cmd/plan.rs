//! `omnical plan`: propose calibration runs that excite every parameter.

use super::{design_geometry, load_runs};
use crate::cli::{DataArgs, ModelKind};
use crate::{atomic, robot_file};
use anyhow::Context;
use omni_ga::excitation::{self, PlanRequest, RunPlan, RunSet};
use omni_kin::simulate::SimConfig;
use omni_kin::{EffectKind, FittedModel, Model, RobotGeometry};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `omnical plan`.
#[derive(Debug)]
pub struct Args {
    /// Base model.
    pub model: ModelKind,
    /// Effect ids.
    pub effects: Vec<String>,
    /// Runs whose robot geometry to use.
    pub robot_from: Vec<PathBuf>,
    /// What to plan for: set, runs, speeds, duration, ground-truth rate and noise.
    pub request: PlanRequest,
    /// CSV output.
    pub out: Option<PathBuf>,
    /// JSON output.
    pub json: bool,
    /// Data options.
    pub data: DataArgs,
}

/// Runs `omnical plan`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    let robot = plan_robot(a)?;
    let mut model = FittedModel::nominal(Model::design(a.model.into(), Some(&robot))?);
    for id in &a.effects {
        model = model
            .with_effect(EffectKind::from_id(id, model.model.n_wheels()).with_context(|| format!("--effect {id}"))?);
    }
    let req = &a.request;
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
    if a.json {
        let v = serde_json::json!({"plan": plan, "flower": flower});
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    print_plan(&plan, flower.as_ref(), req, benchmark_name(model.model.n_wheels()));
    if let Some(out) = &a.out {
        println!("plan written to {}", out.display());
    }
    Ok(())
}

/// The robot to plan for: `--robot`, else the geometry of the `--robot-from` runs, else a robot.toml beside
/// them or in the working directory. Plan needs it to turn commands into wheel speeds.
fn plan_robot(a: &Args) -> anyhow::Result<RobotGeometry> {
    if !a.robot_from.is_empty() {
        return design_geometry(&load_runs(&a.robot_from, &a.data)?);
    }
    match robot_file::resolve(a.data.robot.robot.as_deref(), &[])? {
        Some(r) => {
            robot_file::announce(&r.source);
            r.description.to_geometry().with_context(|| format!("robot {}", r.source))
        }
        None => Err(robot_file::no_design("plan")),
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

/// What `--set flower` is on a robot of `n_wheels` wheels: the paper's flower, or a differential drive's
/// own benchmark (it cannot drive the flower's sideways petals).
fn benchmark_name(n_wheels: usize) -> &'static str {
    if n_wheels == 2 {
        "the diff benchmark set (forward/backward arcs, turns on the spot)"
    } else {
        "the paper's flower set"
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
        println!("warning: {w}");
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
