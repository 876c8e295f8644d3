//! `omnical export --robot-config DIR`: put a calibration back on the robot (docs/applying.md).
//!
//! Writes three files:
//! - [`ODOMETRY_YAML`]: the fitted IK matrix as a ROS 2 parameter file (`/**: ros__parameters:`; the matrix
//!   flattened row-major, as ROS parameters hold no nested lists), with the wheel order, the odometry
//!   formula and the integration it was fitted with;
//! - [`ODOMETRY_HEADER`]: the same as a C header (`static const double`, a twist function and one
//!   integration step identical to omnical's), for a custom odometry node or firmware;
//! - [`CONTROLLER_YAML`]: the parameters of the ros2_controllers drive controller that matches the base,
//!   from the nearest parametric fit ([`crate::controller`]), with the accuracy its simpler model gives up
//!   on the runs given.
//!
//! Numbers are written in shortest round-trip form with a decimal point or exponent (`1.0`, not `1`), so
//! the matrix reads back bit for bit and ROS 2 types every value as a double.

use crate::controller::{self, ControllerFit, ControllerKind, ControllerParams, FitOptions};
use anyhow::Context;
use omni_kin::cost::{self, CostKind};
use omni_kin::effect::Effect;
use omni_kin::{FittedModel, IkMatrix, Integration, Model, Run, RunModels, Scheme, StepMode};
use std::fmt::Write as _;
use std::path::Path;

/// The matrix as a ROS 2 parameter file.
pub const ODOMETRY_YAML: &str = "omnical_odometry.yaml";
/// The matrix as a C header.
pub const ODOMETRY_HEADER: &str = "omnical_odometry.h";
/// The drive controller's parameters (controller_manager style).
pub const CONTROLLER_YAML: &str = "ros2_controllers.yaml";

/// Eq. 6 cost and path RMS of one model on the runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Accuracy {
    /// The paper's Eq. 6: mean end-pose error (m and rad mixed).
    pub end_pose: f64,
    /// RMS error over every ground-truth pose (1 m/rad).
    pub path_rms: f64,
}

/// One effect of the model that a plain matrix cannot carry.
#[derive(Clone, Debug, PartialEq)]
pub struct EffectSummary {
    /// Effect id, e.g. `time_offset`.
    pub id: String,
    /// Parameter name, unit and value.
    pub params: Vec<(String, String, f64)>,
}

/// What to export.
#[derive(Debug)]
pub struct Request<'a> {
    /// The fitted model.
    pub model: &'a FittedModel,
    /// Its design (the same structure at its design values): the controller's nominal parameters.
    pub design: &'a FittedModel,
    /// Each run's design (its own input's, `crate::design::designs_for`), for the design's accuracy.
    pub designs: &'a RunModels,
    /// How the model was named on the command line (file path or `design`).
    pub spec: &'a str,
    /// Runs to weight the controller fit with and to measure accuracy on (preferably held out).
    pub runs: &'a [Run],
    /// Joint names in the model's column order.
    pub wheel_names: Vec<String>,
    /// Controller to fit (default: the one that matches the base).
    pub controller: Option<ControllerKind>,
}

/// Everything the files say, computed once.
#[derive(Clone, Debug)]
pub struct RobotConfig {
    /// How the model was named.
    pub spec: String,
    /// Joint names in column order.
    pub wheel_names: Vec<String>,
    /// The fitted matrix (3 × N).
    pub matrix: IkMatrix,
    /// Integration the model was fitted with.
    pub integration: Integration,
    /// The model's effects.
    pub effects: Vec<EffectSummary>,
    /// The nearest controller.
    pub fit: ControllerFit,
    /// The same controller fitted to the design matrix (the nominal values the multipliers scale).
    pub design_fit: Option<ControllerFit>,
    /// Number of runs the accuracy is measured on.
    pub n_runs: usize,
    /// The design model.
    pub design_accuracy: Accuracy,
    /// The full model (matrix and effects).
    pub model_accuracy: Accuracy,
    /// The matrix alone, when the model has effects.
    pub matrix_accuracy: Option<Accuracy>,
    /// The controller's odometry.
    pub controller_accuracy: Accuracy,
}

impl RobotConfig {
    /// The controller.
    pub fn kind(&self) -> ControllerKind {
        self.fit.model.params.kind()
    }

    /// Relative loss of the controller against the full model, in % (Eq. 6, path RMS).
    pub fn loss_pct(&self) -> (f64, f64) {
        let pct = |c: f64, m: f64| 100.0 * (c - m) / m;
        (
            pct(self.controller_accuracy.end_pose, self.model_accuracy.end_pose),
            pct(self.controller_accuracy.path_rms, self.model_accuracy.path_rms),
        )
    }

    /// Joint names the controller must see reversed.
    pub fn reversed_joints(&self) -> Vec<&str> {
        let l = &self.fit.model.layout;
        l.columns.iter().zip(&l.reversed).filter(|(_, r)| **r).map(|(c, _)| self.wheel_names[*c].as_str()).collect()
    }
}

/// The design's roller angles, when the model knows its geometry.
fn roller_angles(design: &FittedModel) -> Option<Vec<f64>> {
    let nb = design.model.n_base();
    let g = design.model.kinematics.geometry_at(&design.params[..nb])?.ok()?;
    Some(g.wheels.iter().map(|w| w.roller_angle_rad).collect())
}

fn accuracy(fm: &FittedModel, runs: &[Run]) -> anyhow::Result<Accuracy> {
    accuracy_each(&RunModels::from(fm), runs)
}

/// [`accuracy`] with each run under its own model.
fn accuracy_each(models: &RunModels, runs: &[Run]) -> anyhow::Result<Accuracy> {
    let errors = models.errors(runs, CostKind::PATH.selection())?;
    Ok(Accuracy { end_pose: errors.end_pose_cost(), path_rms: errors.path_cost(CostKind::PATH.heading_weight()) })
}

fn effects_of(fm: &FittedModel) -> Vec<EffectSummary> {
    fm.model
        .effects
        .iter()
        .zip(fm.model.effect_ranges())
        .map(|(e, r)| EffectSummary {
            id: e.id().to_string(),
            params: e.params().into_iter().zip(&fm.params[r]).map(|(s, &v)| (s.name, s.unit.to_string(), v)).collect(),
        })
        .collect()
}

/// Fit the controller and measure every model on the runs.
pub fn build(req: &Request<'_>) -> anyhow::Result<RobotConfig> {
    let model = req.model;
    let n = model.model.n_wheels();
    anyhow::ensure!(req.wheel_names.len() == n, "{} wheel names for a model with {n} wheels", req.wheel_names.len());
    cost::check_runs(&model.model, req.runs)?;
    let matrix = model.ik()?;
    let kind = match req.controller {
        Some(k) => k,
        None => ControllerKind::for_base(n, roller_angles(req.design).as_deref())
            .with_context(|| format!("no ros2_controllers drive controller fits a base with {n} wheel(s)"))?,
    };
    let s = controller::wheel_second_moment(req.runs)?;
    let opts = FitOptions::default();
    let fit = controller::fit(kind, &matrix, &s, &opts)
        .with_context(|| format!("fitting {kind} to the matrix of {}", req.spec))?;
    let design_fit = req.design.ik().ok().and_then(|d| controller::fit(kind, &d, &s, &opts).ok());
    let integration = model.model.integration;
    let plain = |m: &IkMatrix| FittedModel::nominal(Model::ik(m.clone()).with_integration(integration));
    let effects = effects_of(model);
    Ok(RobotConfig {
        spec: req.spec.to_string(),
        wheel_names: req.wheel_names.clone(),
        matrix: matrix.clone(),
        integration,
        design_accuracy: accuracy_each(req.designs, req.runs)?,
        model_accuracy: accuracy(model, req.runs)?,
        matrix_accuracy: if effects.is_empty() { None } else { Some(accuracy(&plain(&matrix), req.runs)?) },
        controller_accuracy: accuracy(&plain(&fit.twist_from_wheels), req.runs)?,
        effects,
        fit,
        design_fit,
        n_runs: req.runs.len(),
    })
}

/// A double in shortest round-trip form that YAML, ROS 2 and C all read as a floating-point number.
pub fn num(x: f64) -> String {
    format!("{x:?}")
}

/// A double-quoted string (JSON escapes are valid in YAML and C for the names we write).
fn quoted(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| format!("\"{s}\""))
}

fn quoted_list(names: &[&str]) -> String {
    let q: Vec<String> = names.iter().map(|n| quoted(n)).collect();
    format!("[{}]", q.join(", "))
}

/// The integration scheme and step in words, one line each.
fn integration_lines(i: &Integration) -> [String; 2] {
    let scheme = match i.scheme {
        Scheme::Euler => "Euler (the paper's Eq. 1): x += h (vx cos θ − vy sin θ), y += h (vx sin θ + vy cos θ), \
                          θ += h ω, heading at the start of the step"
            .to_string(),
        Scheme::ExactArc => "exact arc: the twist held over the step, integrated exactly on SE(2) \
                             (θ' = θ + ω h; x += (vx (sin θ' − sin θ) + vy (cos θ' − cos θ)) / ω; \
                             y += (vx (cos θ − cos θ') + vy (sin θ' − sin θ)) / ω)"
            .to_string(),
    };
    let step = match i.step {
        StepMode::Fixed { dt_s: Some(dt) } => format!("each wheel sample is one step of h = {} s", num(dt)),
        StepMode::Fixed { dt_s: None } => {
            "each wheel sample is one step of h = the recording's median wheel-sample interval".to_string()
        }
        StepMode::Stamps => "each wheel sample is integrated over its measured interval since the previous one".into(),
    };
    [scheme, step]
}

fn effect_lines(effects: &[EffectSummary]) -> Vec<String> {
    effects
        .iter()
        .map(|e| {
            let p: Vec<String> = e.params.iter().map(|(n, u, v)| format!("{n} = {} {u}", num(*v))).collect();
            format!("{}: {}", e.id, p.join(", "))
        })
        .collect()
}

/// `text` cut into lines of at most `width` characters at spaces (longer words stay whole).
pub fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut cur = String::new();
    for word in text.split(' ').filter(|w| !w.is_empty()) {
        if !cur.is_empty() && cur.chars().count() + 1 + word.chars().count() > width {
            lines.push(std::mem::take(&mut cur));
        }
        if !cur.is_empty() {
            cur.push(' ');
        }
        cur.push_str(word);
    }
    if !cur.is_empty() || lines.is_empty() {
        lines.push(cur);
    }
    lines
}

/// Width of comment text in the written files. characters.
const COMMENT_WIDTH: usize = 100;

/// Comment block shared by the matrix files (`prefix` is `# ` or ` * `).
fn formula_comment(c: &RobotConfig, prefix: &str) -> String {
    let [scheme, step] = integration_lines(&c.integration);
    let mut s = String::new();
    let mut line = |t: &str| {
        let indent: String = t.chars().take_while(|ch| *ch == ' ').collect();
        for l in wrap(t, COMMENT_WIDTH - indent.len()) {
            let _ = writeln!(s, "{prefix}{indent}{l}");
        }
    };
    line(&format!("omnical calibration of {}, generated by omnical {}.", c.spec, env!("CARGO_PKG_VERSION")));
    line(&format!(
        "Odometry: twist = twist_from_wheels · wheel_speeds_rad_s in the body frame (REP-103: x forward, y \
         left, yaw anticlockwise); twist = (vx m/s, vy m/s, ω rad/s); wheel speeds = joint velocities in rad/s \
         in the order {}.",
        c.wheel_names.join(", ")
    ));
    line(&format!("Integration the matrix was fitted with: {scheme}; {step}."));
    let effects = effect_lines(&c.effects);
    if !effects.is_empty() {
        let mut w = "WARNING: the model also has effects a plain matrix cannot carry, so odometry from the matrix \
                     alone does not reach the model's accuracy"
            .to_string();
        if let Some(m) = c.matrix_accuracy {
            let _ = write!(
                w,
                " (on {} runs: Eq. 6 {:.5} instead of {:.5}, path RMS {:.5} instead of {:.5})",
                c.n_runs, m.end_pose, c.model_accuracy.end_pose, m.path_rms, c.model_accuracy.path_rms
            );
        }
        line(&format!("{w}:"));
        for e in effects {
            line(&format!("  - {e}"));
        }
    }
    s
}

/// The matrix as a ROS 2 parameter file.
pub fn odometry_yaml(c: &RobotConfig) -> String {
    let mut s = formula_comment(c, "# ");
    let names: Vec<&str> = c.wheel_names.iter().map(String::as_str).collect();
    let _ = writeln!(s, "/**:\n  ros__parameters:");
    let _ = writeln!(s, "    format: \"omnical-odometry/1\"");
    let _ = writeln!(s, "    source_model: {}", quoted(&c.spec));
    let _ = writeln!(s, "    wheel_names: {}", quoted_list(&names));
    let _ =
        writeln!(s, "    # row-major 3 × {}: rows vx (m/s), vy (m/s), ω (rad/s) per wheel speed (rad/s)", names.len());
    let _ = writeln!(s, "    twist_from_wheels: [");
    for (r, unit) in ["vx, m/s", "vy, m/s", "ω, rad/s"].iter().enumerate() {
        let row: Vec<String> = c.matrix.row(r).iter().map(|v| num(*v)).collect();
        let sep = if r < 2 { "," } else { "" };
        let _ = writeln!(s, "      {}{sep}  # {unit}", row.join(", "));
    }
    let _ = writeln!(s, "    ]");
    let scheme = match c.integration.scheme {
        Scheme::Euler => "euler",
        Scheme::ExactArc => "exact_arc",
    };
    let _ = writeln!(s, "    integration_scheme: \"{scheme}\"");
    match c.integration.step {
        StepMode::Fixed { dt_s: Some(dt) } => {
            let _ = writeln!(s, "    integration_step: \"fixed\"\n    integration_step_s: {}", num(dt));
        }
        StepMode::Fixed { dt_s: None } => {
            let _ = writeln!(s, "    integration_step: \"median_interval\"");
        }
        StepMode::Stamps => {
            let _ = writeln!(s, "    integration_step: \"stamps\"");
        }
    }
    let effects = effect_lines(&c.effects);
    if !effects.is_empty() {
        let e: Vec<&str> = effects.iter().map(String::as_str).collect();
        let _ = writeln!(s, "    effects_not_in_matrix: {}", quoted_list(&e));
    }
    s
}

/// The matrix as a C header.
pub fn odometry_header(c: &RobotConfig) -> String {
    let n = c.wheel_names.len();
    let mut s = String::from("/*\n");
    s.push_str(&formula_comment(c, " * "));
    s.push_str(
        " * omnical_twist() applies the matrix; omnical_step() is one integration step (omnical's formula).\n */\n",
    );
    s.push_str("#ifndef OMNICAL_ODOMETRY_H\n#define OMNICAL_ODOMETRY_H\n\n#include <math.h>\n\n");
    let _ = writeln!(s, "#define OMNICAL_N_WHEELS {n}\n");
    let names: Vec<String> = c.wheel_names.iter().map(|w| quoted(w)).collect();
    let _ = writeln!(s, "/* Joint names in column order. */");
    let _ = writeln!(s, "static const char *const OMNICAL_WHEEL_NAMES[OMNICAL_N_WHEELS] = {{{}}};\n", names.join(", "));
    let _ = writeln!(s, "/* Rows: vx (m/s), vy (m/s), omega (rad/s); columns: wheel speeds (rad/s). */");
    let _ = writeln!(s, "static const double OMNICAL_TWIST_FROM_WHEELS[3][OMNICAL_N_WHEELS] = {{");
    for r in 0..3 {
        let row: Vec<String> = c.matrix.row(r).iter().map(|v| num(*v)).collect();
        let _ = writeln!(s, "    {{{}}},", row.join(", "));
    }
    s.push_str("};\n\n");
    if let StepMode::Fixed { dt_s: Some(dt) } = c.integration.step {
        let _ = writeln!(
            s,
            "/* The fixed step each wheel sample is integrated over. s. */\n#define OMNICAL_STEP_S {}\n",
            num(dt)
        );
    }
    s.push_str(C_FUNCTIONS_TWIST);
    s.push_str(match c.integration.scheme {
        Scheme::Euler => C_STEP_EULER,
        Scheme::ExactArc => C_STEP_EXACT_ARC,
    });
    s.push_str("\n#endif /* OMNICAL_ODOMETRY_H */\n");
    s
}

const C_FUNCTIONS_TWIST: &str = "/* twist = (vx m/s, vy m/s, omega rad/s) from wheel speeds (rad/s, column order). */
static inline void omnical_twist(const double wheel_rad_s[OMNICAL_N_WHEELS], double twist[3]) {
    for (int r = 0; r < 3; ++r) {
        double sum = 0.0;
        for (int c = 0; c < OMNICAL_N_WHEELS; ++c) {
            sum += OMNICAL_TWIST_FROM_WHEELS[r][c] * wheel_rad_s[c];
        }
        twist[r] = sum;
    }
}

";

const C_STEP_EULER: &str =
    "/* pose = (x m, y m, theta rad) advanced by a twist held for h s: Euler, heading at the step start. */
static inline void omnical_step(double pose[3], const double twist[3], double h) {
    const double s = sin(pose[2]), c = cos(pose[2]);
    pose[0] += h * (c * twist[0] - s * twist[1]);
    pose[1] += h * (s * twist[0] + c * twist[1]);
    pose[2] += h * twist[2];
}
";

const C_STEP_EXACT_ARC: &str =
    "/* pose = (x m, y m, theta rad) advanced by a twist held for h s: exact arc on SE(2). */
static inline void omnical_step(double pose[3], const double twist[3], double h) {
    const double a = twist[2] * h;
    double ss, cc;
    if (fabs(a) < 1e-4) {
        const double a2 = a * a;
        ss = h * (1.0 - a2 / 6.0);
        cc = h * a * (0.5 - a2 / 24.0);
    } else {
        ss = sin(a) / twist[2];
        cc = (1.0 - cos(a)) / twist[2];
    }
    const double bx = ss * twist[0] - cc * twist[1];
    const double by = cc * twist[0] + ss * twist[1];
    const double s = sin(pose[2]), c = cos(pose[2]);
    pose[0] += c * bx - s * by;
    pose[1] += s * bx + c * by;
    pose[2] += a;
}
";

/// Write the three files into `dir` (created if needed).
pub fn write(dir: &Path, c: &RobotConfig) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let files = [
        (ODOMETRY_YAML, odometry_yaml(c)),
        (ODOMETRY_HEADER, odometry_header(c)),
        (CONTROLLER_YAML, controller_yaml(c)),
    ];
    for (name, text) in files {
        let path = dir.join(name);
        crate::atomic::write_atomic(&path, text.as_bytes()).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// The controller's parameters in SI units as `(name, value)`, for messages.
pub fn params_text(p: &ControllerParams) -> String {
    match *p {
        ControllerParams::DiffDrive { wheel_separation_m, left_wheel_radius_m, right_wheel_radius_m } => format!(
            "separation {wheel_separation_m:.5} m, left radius {left_wheel_radius_m:.5} m, right radius {right_wheel_radius_m:.5} m"
        ),
        ControllerParams::MecanumDrive { wheels_radius_m, lx_plus_ly_m } => {
            format!("wheel radius {wheels_radius_m:.5} m, lx + ly {lx_plus_ly_m:.5} m")
        }
        ControllerParams::OmniWheelDrive { wheel_radius_m, robot_radius_m, wheel_offset_rad } => format!(
            "wheel radius {wheel_radius_m:.5} m, robot radius {robot_radius_m:.5} m, wheel offset {wheel_offset_rad:.5} rad ({:.2}°)",
            wheel_offset_rad.to_degrees()
        ),
    }
}

/// How the controller counts a positive wheel speed.
fn convention(kind: ControllerKind) -> &'static str {
    match kind {
        ControllerKind::DiffDrive | ControllerKind::MecanumDrive => "drives the robot forward",
        ControllerKind::OmniWheelDrive => "turns the robot clockwise seen from above",
    }
}

/// Where each ros2_controllers version has the controller, and the parameter file its names come from.
fn availability(kind: ControllerKind) -> &'static str {
    match kind {
        ControllerKind::DiffDrive => {
            "every ROS 2 distribution (Humble, Jazzy, Kilted, Rolling); names from \
             diff_drive_controller/src/diff_drive_controller_parameter.yaml"
        }
        ControllerKind::MecanumDrive => {
            "Humble from 2.43.0, Jazzy (4.x), Kilted and Rolling; names from \
             mecanum_drive_controller/src/mecanum_drive_controller.yaml (pre-release versions used \
             command_joint_names and kinematics.wheels_k)"
        }
        ControllerKind::OmniWheelDrive => {
            "Jazzy from 4.30.0, Kilted (5.x) and Rolling, not Humble; names from \
             omni_wheel_drive_controller/src/omni_wheel_drive_controller_parameters.yaml"
        }
    }
}

fn pct_text(c: f64, m: f64) -> String {
    if m > 0.0 {
        format!("{:+.1} %", 100.0 * (c - m) / m)
    } else if c == m {
        "+0.0 %".into()
    } else {
        "n/a".into()
    }
}

/// The accuracy table (model, matrix alone, controller, loss), one line per row.
pub fn accuracy_lines(c: &RobotConfig) -> Vec<String> {
    let row = |label: &str, a: &Accuracy| format!("  {label:<34} {:>10.5} {:>10.5}", a.end_pose, a.path_rms);
    let title = format!("accuracy on the {} runs given:", c.n_runs);
    let mut v = vec![format!("{title:<36} {:>10} {:>10}", "Eq. 6", "path RMS")];
    v.push(row("design (uncalibrated)", &c.design_accuracy));
    v.push(row("calibrated model", &c.model_accuracy));
    if let Some(m) = &c.matrix_accuracy {
        v.push(row("its matrix alone (the header)", m));
    }
    v.push(row(c.kind().id(), &c.controller_accuracy));
    let (m, k) = (&c.model_accuracy, &c.controller_accuracy);
    v.push(format!(
        "  {:<34} {:>10} {:>10}",
        "given up by the controller",
        pct_text(k.end_pose, m.end_pose),
        pct_text(k.path_rms, m.path_rms)
    ));
    v
}

/// Largest distance of the omni wheels' angles (read off the matrix) from the equal spacing the
/// controller assumes. rad.
fn spacing_error_rad(c: &RobotConfig) -> Option<f64> {
    let ControllerParams::OmniWheelDrive { wheel_offset_rad, .. } = c.fit.model.params else { return None };
    let n = c.fit.slot_angles_rad.len();
    c.fit
        .slot_angles_rad
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let d = a - wheel_offset_rad - std::f64::consts::TAU * i as f64 / n as f64;
            omni_kin::pose::wrap_angle(d).abs()
        })
        .reduce(f64::max)
}

/// Warnings about using the controller, one sentence each.
pub fn warning_lines(c: &RobotConfig) -> Vec<String> {
    let kind = c.kind();
    let mut v = Vec::new();
    let reversed = c.reversed_joints();
    if !reversed.is_empty() {
        v.push(format!(
            "{kind} counts a wheel speed positive when it {}; these joints count the other way: {}. Negate their \
             position and velocity in the hardware interface (or a transmission with a negative reduction) before \
             loading these parameters; the accuracy above assumes you do.",
            convention(kind),
            reversed.join(", ")
        ));
    }
    if let Some(e) = spacing_error_rad(c).filter(|e| e.to_degrees() > 1.0) {
        v.push(format!(
            "the wheels sit up to {:.1}° from the equal spacing {kind} assumes; its odometry cannot follow that.",
            e.to_degrees()
        ));
    }
    if kind == ControllerKind::DiffDrive && c.design_fit.is_none() {
        v.push("no design to scale: wheel_separation and wheel_radius are the fitted values, multipliers 1.0.".into());
    }
    if !c.effects.is_empty() {
        let ids: Vec<&str> = c.effects.iter().map(|e| e.id.as_str()).collect();
        v.push(format!("the controller cannot carry the model's effects ({}).", ids.join(", ")));
    }
    v
}

fn comment_block(c: &RobotConfig) -> String {
    let kind = c.kind();
    let t = c.fit.twist_rms;
    let lines = [
        format!("ros2_control parameters for {kind} ({}),", kind.plugin()),
        format!("generated by omnical {} from {}.", env!("CARGO_PKG_VERSION"), c.spec),
        format!("Available in {}.", availability(kind)),
        format!(
            "Nearest parametric fit: the controller's parameters whose odometry best reproduces the calibrated \
             matrix's body twists over the wheel speeds of the {} runs given (least squares weighted by their \
             second moments, ω weighted 1 m/rad). Twist RMS difference: vx {:.2e} m/s, vy {:.2e} m/s, ω {:.2e} rad/s.",
            c.n_runs, t.vx_m_s, t.vy_m_s, t.omega_rad_s
        ),
    ];
    let mut lines: Vec<String> = lines.iter().flat_map(|l| wrap(l, COMMENT_WIDTH)).collect();
    lines.extend(accuracy_lines(c));
    for w in warning_lines(c) {
        lines.extend(wrap(&format!("WARNING: {w}"), COMMENT_WIDTH));
    }
    lines.iter().map(|l| format!("# {l}\n")).collect()
}

/// The controller's parameters in controller_manager style.
pub fn controller_yaml(c: &RobotConfig) -> String {
    let kind = c.kind();
    let mut s = comment_block(c);
    let _ = writeln!(s, "controller_manager:\n  ros__parameters:\n    {}:\n      type: {}\n", kind.id(), kind.plugin());
    let _ = writeln!(s, "{}:\n  ros__parameters:", kind.id());
    let name = |slot: usize| quoted(&c.wheel_names[c.fit.model.layout.columns[slot]]);
    match c.fit.model.params {
        ControllerParams::DiffDrive { wheel_separation_m, left_wheel_radius_m, right_wheel_radius_m } => {
            let (s0, r0) = match c.design_fit.as_ref().map(|d| d.model.params) {
                Some(ControllerParams::DiffDrive {
                    wheel_separation_m: s,
                    left_wheel_radius_m: l,
                    right_wheel_radius_m: r,
                }) => (s, (l + r) / 2.0),
                _ => (wheel_separation_m, (left_wheel_radius_m + right_wheel_radius_m) / 2.0),
            };
            let _ = writeln!(s, "    left_wheel_names: [{}]\n    right_wheel_names: [{}]", name(0), name(1));
            let _ = writeln!(
                s,
                "    wheel_separation: {}  # design, m\n    wheel_radius: {}  # design, m",
                num(s0),
                num(r0)
            );
            let _ = writeln!(
                s,
                "    wheel_separation_multiplier: {}  # fitted {} m",
                num(wheel_separation_m / s0),
                num(wheel_separation_m)
            );
            let _ = writeln!(
                s,
                "    left_wheel_radius_multiplier: {}  # fitted {} m",
                num(left_wheel_radius_m / r0),
                num(left_wheel_radius_m)
            );
            let _ = writeln!(
                s,
                "    right_wheel_radius_multiplier: {}  # fitted {} m",
                num(right_wheel_radius_m / r0),
                num(right_wheel_radius_m)
            );
        }
        ControllerParams::MecanumDrive { wheels_radius_m, lx_plus_ly_m } => {
            for (slot, key) in ["front_left", "front_right", "rear_left", "rear_right"].iter().enumerate() {
                let _ = writeln!(s, "    {key}_wheel_command_joint_name: {}", name(slot));
            }
            let _ = writeln!(s, "    kinematics:\n      wheels_radius: {}  # m", num(wheels_radius_m));
            let _ =
                writeln!(s, "      sum_of_robot_center_projection_on_X_Y_axis: {}  # lx + ly, m", num(lx_plus_ly_m));
        }
        ControllerParams::OmniWheelDrive { wheel_radius_m, robot_radius_m, wheel_offset_rad } => {
            let names: Vec<String> = (0..c.wheel_names.len()).map(name).collect();
            let _ = writeln!(s, "    wheel_names: [{}]  # anticlockwise from wheel_offset", names.join(", "));
            let offset = omni_kin::pose::wrap_angle(wheel_offset_rad);
            let _ = writeln!(s, "    wheel_offset: {}  # rad ({:.3}°)", num(offset), offset.to_degrees());
            let _ = writeln!(
                s,
                "    robot_radius: {}  # m\n    wheel_radius: {}  # m",
                num(robot_radius_m),
                num(wheel_radius_m)
            );
        }
    }
    s
}

/// What `omnical export` prints about the robot configuration (on stdout; [`warning_lines`] go to stderr).
pub fn summary(c: &RobotConfig, dir: &Path) -> String {
    let t = c.fit.twist_rms;
    let mut s = format!(
        "wrote {ODOMETRY_YAML}, {ODOMETRY_HEADER} and {CONTROLLER_YAML} to {}\n{}: {} (nearest fit; twist RMS \
         difference vx {:.2e} m/s, vy {:.2e} m/s, ω {:.2e} rad/s)\n",
        dir.display(),
        c.kind(),
        params_text(&c.fit.model.params),
        t.vx_m_s,
        t.vy_m_s,
        t.omega_rad_s
    );
    for l in accuracy_lines(c) {
        let _ = writeln!(s, "{l}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_doubles_that_round_trip() {
        assert_eq!(num(1.0), "1.0");
        assert_eq!(num(-0.0854478398400646), "-0.0854478398400646");
        assert_eq!(num(1e-7), "1e-7");
        assert_eq!(num(0.1 + 0.2).parse::<f64>().unwrap(), 0.1 + 0.2);
    }

    #[test]
    fn wrap_cuts_at_spaces() {
        assert_eq!(wrap("aa bb cc dd", 5), ["aa bb", "cc dd"]);
        assert_eq!(wrap("a verylongword b", 4), ["a", "verylongword", "b"]);
        assert_eq!(wrap("", 10), [""]);
    }
}
