//! Excitation planning: which calibration runs to record so that every parameter of a model (and its
//! effects) is determined, and how well, before any data exists.
//!
//! Candidate runs are simulated noise-free with the robot's design geometry (one constant command
//! `(v, α, ω)` each, between rests). For each, the Jacobian of the path residuals with respect to the
//! model's parameters at their design/null values is computed and whitened by the stated ground-truth
//! noise (position per axis `σ_p` m, heading `σ_θ` rad): its information matrix is `J_gᵀ J_g`. A plan's
//! expected covariance is the inverse of the summed information (times the repetitions).
//!
//! - `flower`: the paper's 36 commands (12 directions × ω ∈ {−ω, 0, +ω}); on a differential drive, its
//!   benchmark of forward/backward arcs and turns on the spot ([`omni_kin::simulate::diff_commands`]).
//! - `greedy` (default): D-optimal selection from a library (12 directions × ω ∈ {−ω, 0, +ω} × speeds
//!   {v, v/2}, plus rotations on the spot at ±ω and ±ω/2): repeatedly add the candidate that most
//!   increases `log det` of the scaled information, so few runs excite every direction, including the
//!   effects' (both turning directions, several speeds). Only commands the base can drive are candidates
//!   (a differential drive: directions 0° and 180°).
//!
//! Expected standard errors count ground-truth noise only: wheel-speed noise integrates along a path
//! into correlated drift, which makes real standard errors larger (on the simulator's defaults, 3–4×:
//! see [`crate::science::identify`]).

use crate::error::Error;
use crate::fit::CalibrationProblem;
use crate::optimizer::problem::Bounds;
use crate::science::diagnose::differentiable_start;
use crate::science::identify::{self, Identifiability, IdentifyOptions};
use nalgebra::DMatrix;
use omni_kin::cost::CostKind;
use omni_kin::simulate::{SimConfig, UNREACHABLE_TOL, benchmark_commands, simulate, unreachable_twists};
use omni_kin::{Command, FittedModel, RobotGeometry, Run};
use serde::{Deserialize, Serialize};

/// Which set of runs to propose.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunSet {
    /// The paper's 36 flower commands.
    Flower,
    /// D-optimal greedy selection from a candidate library.
    Greedy,
}

omni_kin::choice!(RunSet, default = Greedy, {
    Greedy => "greedy": "D-optimal greedy pick from a library of commands (several speeds, both turn directions)",
    Flower => "flower": "The paper's 36 flower commands",
});

/// What to plan for.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PlanRequest {
    /// Translation speed of the commands. m/s. Default 0.2 (paper).
    pub speed_m_s: f64,
    /// Turn rate of the commands. rad/s. Default 0.35 (paper).
    pub omega_rad_s: f64,
    /// How long each command is held. s. Default 10.
    pub duration_s: f64,
    /// Ground-truth rate. Hz. Default 4 (the paper's LIDAR, 200–300 ms).
    pub truth_rate_hz: f64,
    /// Ground-truth position noise per axis. m. Default 0.002.
    pub truth_noise_m: f64,
    /// Ground-truth heading noise. rad. Default 0.003.
    pub truth_noise_rad: f64,
    /// Distinct commands to pick (greedy). Default 12.
    pub runs: usize,
    /// Repetitions of each picked command. Default 1.
    pub repetitions: usize,
    /// Which set.
    pub set: RunSet,
    /// When a direction counts as unconstrained.
    pub identify: IdentifyOptions,
}

impl Default for PlanRequest {
    fn default() -> Self {
        Self {
            speed_m_s: 0.2,
            omega_rad_s: 0.35,
            duration_s: 10.0,
            truth_rate_hz: 4.0,
            truth_noise_m: 0.002,
            truth_noise_rad: 0.003,
            runs: 12,
            repetitions: 1,
            set: RunSet::default(),
            identify: IdentifyOptions::default(),
        }
    }
}

/// One planned command.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PlannedRun {
    /// The command.
    pub command: Command,
    /// How many times to record it.
    pub repetitions: usize,
}

/// A proposed set of calibration runs and what it would determine.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunPlan {
    /// The set it came from.
    pub set: RunSet,
    /// The runs, in the order they were picked.
    pub runs: Vec<PlannedRun>,
    /// Total runs to record.
    pub total_runs: usize,
    /// Expected identifiability (standard errors for the stated noise).
    pub expected: Identifiability,
}

/// The candidate library of the greedy set.
pub fn candidate_commands(speed_m_s: f64, omega_rad_s: f64) -> Vec<Command> {
    let mut v = Vec::new();
    for speed in [speed_m_s, 0.5 * speed_m_s] {
        for omega in [-omega_rad_s, 0.0, omega_rad_s] {
            for a in 0..12 {
                v.push(Command { v_m_s: speed, alpha_rad: (30.0 * a as f64).to_radians(), omega_rad_s: omega });
            }
        }
    }
    for omega in [omega_rad_s, -omega_rad_s, 0.5 * omega_rad_s, -0.5 * omega_rad_s] {
        v.push(Command { v_m_s: 0.0, alpha_rad: 0.0, omega_rad_s: omega });
    }
    v
}

/// The flower's turn rate, against which the benchmark's turn rates are scaled to the request's. rad/s.
const FLOWER_OMEGA: f64 = 0.35;

/// The candidates the base can drive (a differential drive: no sideways ones).
fn performable(design: &RobotGeometry, candidates: Vec<Command>) -> Result<Vec<Command>, Error> {
    let misses = unreachable_twists(design, &candidates)?;
    Ok(candidates
        .into_iter()
        .zip(misses)
        .filter(|(_, m)| m.iter().all(|x| x.abs() <= UNREACHABLE_TOL))
        .map(|(c, _)| c)
        .collect())
}

fn check(req: &PlanRequest) -> Result<(), Error> {
    let bad = |what, why| Err(Error::BadPlanRequest { what, why });
    let pos = |x: f64| x.is_finite() && x > 0.0;
    if !(pos(req.speed_m_s) && pos(req.omega_rad_s) && pos(req.duration_s) && pos(req.truth_rate_hz)) {
        return bad("speeds/duration/rate", "speed, ω, duration and ground-truth rate must be finite and > 0");
    }
    if !(pos(req.truth_noise_m) && pos(req.truth_noise_rad)) {
        return bad("noise", "ground-truth noise must be finite and > 0 (it sets the expected standard errors)");
    }
    if req.runs == 0 || req.repetitions == 0 {
        return bad("runs", "need at least one run and one repetition");
    }
    Ok(())
}

/// Plan calibration runs for `model` (its parameters at their design/null values) on a robot whose
/// controller uses `sim.design`. `sim` supplies the robot and timing; its noise settings are ignored.
pub fn plan(model: &FittedModel, sim: &SimConfig, req: &PlanRequest) -> Result<RunPlan, Error> {
    check(req)?;
    let commands = match req.set {
        // The robot's benchmark (the flower; a diff drive's arcs), at the requested speed and turn rate.
        RunSet::Flower => benchmark_commands(&sim.design)
            .into_iter()
            .map(|c| Command {
                v_m_s: if c.v_m_s == 0.0 { 0.0 } else { req.speed_m_s },
                omega_rad_s: if c.omega_rad_s == 0.0 { 0.0 } else { req.omega_rad_s * (c.omega_rad_s / FLOWER_OMEGA) },
                ..c
            })
            .collect(),
        RunSet::Greedy => performable(&sim.design, candidate_commands(req.speed_m_s, req.omega_rad_s))?,
    };
    let dt = 1.0 / req.truth_rate_hz;
    let cfg = SimConfig {
        commands: commands.clone(),
        runs_per_command: 1,
        duration_s: req.duration_s,
        truth_interval_s: (dt, dt),
        ..sim.clone().noise_free()
    };
    let runs = simulate(&cfg, model, "candidate/")?;
    let x = differentiable_start(model);
    let blocks = information_blocks(model, &x, &runs, req)?;
    let n = x.len();
    let scales = identify::param_scales(&model.model);
    let picked: Vec<usize> = match req.set {
        RunSet::Flower => (0..runs.len()).collect(),
        RunSet::Greedy => greedy(&blocks, &scales, req.runs),
    };
    // Information of the picked runs (each repeated), for the expected analysis.
    let mut info = DMatrix::zeros(n, n);
    for &g in &picked {
        info += &blocks[g].info * req.repetitions as f64;
    }
    let expected = identify::expected(&model.model, &x, &info, None, &req.identify);
    let mut planned: Vec<PlannedRun> = Vec::new();
    for &g in &picked {
        match planned.iter_mut().find(|p| p.command == commands[g]) {
            Some(p) => p.repetitions += req.repetitions,
            None => planned.push(PlannedRun { command: commands[g], repetitions: req.repetitions }),
        }
    }
    Ok(RunPlan { set: req.set, total_runs: picked.len() * req.repetitions, runs: planned, expected })
}

/// One candidate's information matrix, in parameter units and scaled.
struct Block {
    info: DMatrix<f64>,
    info_scaled: DMatrix<f64>,
}

fn information_blocks(model: &FittedModel, x: &[f64], runs: &[Run], req: &PlanRequest) -> Result<Vec<Block>, Error> {
    let n = x.len();
    let problem = CalibrationProblem::new(&model.model, runs, CostKind::PATH, Bounds::unbounded(n))?;
    let scales = identify::param_scales(&model.model);
    let g = runs.len() as f64;
    let mut out = Vec::with_capacity(runs.len());
    problem.for_each_run_block(x, &mut |b| {
        let rows = b.residuals.len();
        // Undo the cost's 1/sqrt(runs · poses) scaling, then whiten by the noise of each component.
        let unscale = (g * (rows / 3) as f64).sqrt();
        let jw = DMatrix::from_fn(rows, n, |r, c| {
            let sigma = if r % 3 == 2 { req.truth_noise_rad } else { req.truth_noise_m };
            b.jacobian[(r, c)] * unscale / sigma
        });
        let info = jw.transpose() * &jw;
        let info_scaled = DMatrix::from_fn(n, n, |a, c| info[(a, c)] * scales[a] * scales[c]);
        out.push(Block { info, info_scaled });
    });
    Ok(out)
}

/// Greedy D-optimal selection of `count` candidates (repeats allowed).
fn greedy(blocks: &[Block], scales: &[f64], count: usize) -> Vec<usize> {
    let n = scales.len();
    // A small ridge so the first picks are comparable while the information is still singular.
    let total: f64 = blocks.iter().map(|b| b.info_scaled.trace()).sum::<f64>() / blocks.len().max(1) as f64;
    let ridge = 1e-6 * total.max(f64::MIN_POSITIVE);
    let mut info = DMatrix::identity(n, n) * ridge;
    let mut picked = Vec::with_capacity(count);
    for _ in 0..count {
        let mut best: Option<(usize, f64)> = None;
        for (i, b) in blocks.iter().enumerate() {
            let m = &info + &b.info_scaled;
            let logdet = match m.cholesky() {
                Some(c) => c.l().diagonal().iter().map(|d| 2.0 * d.ln()).sum::<f64>(),
                None => f64::NEG_INFINITY,
            };
            if best.is_none_or(|(_, v)| logdet > v) {
                best = Some((i, logdet));
            }
        }
        let Some((i, _)) = best else { break };
        info += &blocks[i].info_scaled;
        picked.push(i);
    }
    picked
}
