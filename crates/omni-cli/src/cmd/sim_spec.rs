//! What `simulate --effect` and `--commands` and `demo --hidden` say about the simulated robot: effect
//! specs (`NAME=V1,…`, one wheel's `NAME:WHEEL=V`), true-robot deviations from the design
//! (`wheel_radius:WHEEL=E`, `wheel_separation=E`, a skid-steer base's `icr_shift=DYL,DYR,DX`), and
//! command lists (a `plan` CSV).
//!
//! A wheel is named by its letter in the model's column order (`a`, `b`, …: the letters of the per-wheel
//! parameter names, e.g. `backlash.b_c`) or by its joint name; how many there are is the robot's.

use anyhow::{Context, bail};
use omni_kin::effect::Effect;
use omni_kin::simulate::{SimConfig, UNREACHABLE_TOL, unreachable_message, unreachable_twists};
use omni_kin::{Command, EffectKind, FittedModel, Model, RobotGeometry};
use std::path::Path;

/// `wheel_radius:WHEEL=E`: the true wheel's radius is `1 + E` times the design's.
pub const WHEEL_RADIUS: &str = "wheel_radius";
/// `wheel_separation=E`: the true axle of a two-wheel base is `1 + E` times the design's.
pub const WHEEL_SEPARATION: &str = "wheel_separation";
/// `icr_shift=DYL,DYR,DX`: a skid-steer base's instantaneous centres of rotation moved from the design's
/// (m): the left tread's to the left by DYL, the right tread's to the left by DYR (negative: outwards), the
/// robot's forward by DX.
pub const ICR_SHIFT: &str = "icr_shift";

/// The letter of wheel `i` in parameter names (`a`, `b`, …), as the effects name them.
fn letter(i: usize) -> char {
    char::from(b'a' + (i % 26) as u8)
}

/// The wheels as `a (joint)`, for messages.
fn wheel_list(wheels: &[String]) -> String {
    wheels.iter().enumerate().map(|(i, w)| format!("{} ({w})", letter(i))).collect::<Vec<_>>().join(", ")
}

/// The index of the wheel named `name` (its letter or its joint name) among `wheels`.
fn wheel_index(spec: &str, name: &str, wheels: &[String]) -> anyhow::Result<usize> {
    let by_letter = (0..wheels.len()).find(|&i| name.len() == 1 && name.starts_with(letter(i)));
    match by_letter.or_else(|| wheels.iter().position(|w| w == name)) {
        Some(i) => Ok(i),
        None => bail!(
            "--effect {spec}: no wheel {name:?}: the robot has {} wheels: {} (name one by its letter or joint)",
            wheels.len(),
            wheel_list(wheels)
        ),
    }
}

fn numbers(spec: &str, values: &str) -> anyhow::Result<Vec<f64>> {
    values
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| {
            let v = s.trim().parse::<f64>().with_context(|| format!("--effect {spec}: {s:?} is not a number"))?;
            if !v.is_finite() {
                bail!("--effect {spec}: {s:?} is not finite");
            }
            Ok(v)
        })
        .collect()
}

/// Parse `NAME[:WHEEL]=V1,V2,…` and apply it: an effect is added to `truth` (or, for `sample_timing`, also
/// to the simulator config); `wheel_radius` and `wheel_separation` change the true base. `wheels` are the
/// robot's joint names in column order.
pub fn apply_effect_spec(
    spec: &str,
    truth: &mut FittedModel,
    config: &mut SimConfig,
    wheels: &[String],
) -> anyhow::Result<()> {
    let (head, values) = spec.split_once('=').unwrap_or((spec, ""));
    // `learned:world=…` is an effect id with a colon; `learned:wheel:b=…` one wheel of it.
    let learned = head.starts_with(omni_kin::effect::learned::PREFIX);
    let split = if learned { head.rsplit_once(':').filter(|(n, _)| n.contains(':')) } else { head.split_once(':') };
    let (name, wheel) = match split {
        Some((n, w)) => (n, Some(wheel_index(spec, w, wheels)?)),
        None => (head, None),
    };
    let values = numbers(spec, values)?;
    match name {
        WHEEL_RADIUS | WHEEL_SEPARATION => deviate_base(spec, name, wheel, &values, truth, wheels),
        ICR_SHIFT => shift_icr(spec, wheel, &values, truth, &config.design),
        _ => match wheel {
            Some(i) => add_wheel_effect(spec, name, i, &values, truth),
            None => add_effect(spec, name, &values, truth, config),
        },
    }
}

/// A catalogue effect with every parameter given, in its order.
fn add_effect(
    spec: &str,
    name: &str,
    values: &[f64],
    truth: &mut FittedModel,
    config: &mut SimConfig,
) -> anyhow::Result<()> {
    let n_wheels = truth.model.n_wheels();
    use omni_kin::effect::{SampleTiming, SensorOffset};
    let id = if name == SensorOffset::ID && values.len() == 3 { SensorOffset::ID_YAW } else { name };
    let effect = EffectKind::from_id(id, n_wheels).with_context(|| format!("--effect {spec}"))?;
    if id == SampleTiming::ID {
        if values.is_empty() || values.len() > 2 {
            bail!("--effect {spec}: sample_timing takes DROP_PROBABILITY[,JITTER_S], e.g. sample_timing=0.05,0.002");
        }
        config.sample_drop_probability = values[0];
        config.sample_jitter_s = values.get(1).copied().unwrap_or(0.0);
        *truth = truth.with_effect(effect);
        return Ok(());
    }
    let specs = effect.params();
    if values.len() != specs.len() {
        let names: Vec<String> = specs.iter().map(|p| format!("{} ({})", p.name, p.unit)).collect();
        bail!("--effect {spec}: {id} takes {} values: {}", specs.len(), names.join(", "));
    }
    let start = truth.params.len();
    *truth = truth.with_effect(effect);
    truth.params[start..].copy_from_slice(values);
    Ok(())
}

/// One wheel's parameters of a per-wheel effect (`backlash:c=0.05`; `wheel_eccentricity:b=C,S`); the
/// other wheels keep theirs (null unless an earlier spec set them).
fn add_wheel_effect(
    spec: &str,
    name: &str,
    wheel: usize,
    values: &[f64],
    truth: &mut FittedModel,
) -> anyhow::Result<()> {
    let n_wheels = truth.model.n_wheels();
    let effect = EffectKind::from_id(name, n_wheels).with_context(|| format!("--effect {spec}"))?;
    let suffix = format!("_{}", letter(wheel));
    let own: Vec<String> = effect
        .params()
        .into_iter()
        .map(|p| p.name)
        .filter(|n| n.ends_with(&suffix) && n.len() > suffix.len())
        .collect();
    if own.is_empty() {
        bail!("--effect {spec}: {name} has no per-wheel parameters; give all of them as {name}=V1,…");
    }
    if values.len() != own.len() {
        bail!("--effect {spec}: {name} takes {} values for one wheel: {}", own.len(), own.join(", "));
    }
    if !truth.model.effects.iter().any(|e| e.id() == name) {
        *truth = truth.with_effect(effect);
    }
    for (p, v) in own.iter().zip(values) {
        truth.set(&format!("{name}.{p}"), *v).with_context(|| format!("--effect {spec}"))?;
    }
    Ok(())
}

/// The true base deviates from the design: one wheel's radius (`wheel_radius:WHEEL=E`, its matrix column
/// times `1 + E`) or a two-wheel base's axle (`wheel_separation=E`, the ω row divided by `1 + E`). The true
/// base becomes its twist-from-wheels matrix; its effects stay.
fn deviate_base(
    spec: &str,
    name: &str,
    wheel: Option<usize>,
    values: &[f64],
    truth: &mut FittedModel,
    wheels: &[String],
) -> anyhow::Result<()> {
    let [e] = values else {
        bail!("--effect {spec}: {name} takes one value, the relative change E (0.015: 1.5 % larger)");
    };
    if *e <= -0.5 || *e >= 0.5 {
        bail!("--effect {spec}: {name} changes by {e}, outside (−0.5, 0.5): a relative change, 0.015 is 1.5 %");
    }
    let ik = truth.ik().context("--effect: the true base")?;
    let ik = match (name, wheel) {
        (WHEEL_RADIUS, Some(i)) => ik.with_column_scaled(i, 1.0 + e),
        (WHEEL_RADIUS, None) => {
            bail!("--effect {spec}: name the wheel, wheel_radius:WHEEL=E, one of {}", wheel_list(wheels))
        }
        (_, Some(_)) => bail!("--effect {spec}: wheel_separation belongs to the axle, not a wheel: wheel_separation=E"),
        _ if wheels.len() != 2 => bail!(
            "--effect {spec}: wheel_separation is a two-wheel (diff) base's axle; this robot has {} wheels (change a \
             wheel with wheel_radius:WHEEL=E)",
            wheels.len()
        ),
        _ => ik.with_row_scaled(2, 1.0 / (1.0 + e)),
    };
    // The new base at its own value (an IK model holds a row that is zero throughout, a diff drive's vy,
    // out of its parameters), then the effects' values as they were.
    let effects = truth.params[truth.model.n_base()..].to_vec();
    let mut model = Model::ik(ik);
    model.effects = std::mem::take(&mut truth.model.effects);
    model.integration = truth.model.integration;
    let params = model.nominal()[..model.n_base()].iter().copied().chain(effects).collect();
    *truth = FittedModel::new(model, params).with_context(|| format!("--effect {spec}"))?;
    Ok(())
}

/// The true base is a skid-steer base (the ICR-based extended differential drive,
/// [`omni_kin::kinematics::SkidKinematics`]) at the design's radii with its ICRs moved by
/// `DYL,DYR,DX` (m); the effects stay.
fn shift_icr(
    spec: &str,
    wheel: Option<usize>,
    values: &[f64],
    truth: &mut FittedModel,
    design: &RobotGeometry,
) -> anyhow::Result<()> {
    let [dyl, dyr, dx] = values else {
        bail!("--effect {spec}: icr_shift takes three lengths in m, DYL,DYR,DX (e.g. icr_shift=0.12,-0.12,0.04)");
    };
    if wheel.is_some() {
        bail!("--effect {spec}: icr_shift belongs to the base, not a wheel: icr_shift=DYL,DYR,DX");
    }
    let skid = omni_kin::kinematics::SkidKinematics::new(design.clone()).map_err(|e| {
        anyhow::anyhow!("--effect {spec}: icr_shift is a skid-steer base's (robot.toml kind = \"skid\"): {e}")
    })?;
    let mut p = skid.design_params()?;
    p[2] += dyl;
    p[3] += dyr;
    p[4] += dx;
    let effects = truth.params[truth.model.n_base()..].to_vec();
    let model = Model {
        kinematics: omni_kin::kinematics::Kinematics::Skid(skid),
        effects: std::mem::take(&mut truth.model.effects),
        integration: truth.model.integration,
    };
    *truth =
        FittedModel::new(model, p.into_iter().chain(effects).collect()).with_context(|| format!("--effect {spec}"))?;
    Ok(())
}

/// Reads a command list: a `plan --out` CSV (`v_m_s,alpha_deg,omega_rad_s[,repetitions]`, a header line;
/// a row with `repetitions` k is listed k times) and checks that the base `design` can drive each (a
/// differential drive cannot move sideways). Errors name the file, line and field.
pub fn read_commands(path: &Path, design: &RobotGeometry) -> anyhow::Result<Vec<Command>> {
    let text = crate::dataset::read_text(path).context("reading --commands")?;
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
    let header: Vec<&str> = match lines.next() {
        Some((_, h)) => h.split(',').map(str::trim).collect(),
        None => bail!("{}: no commands (expected a header v_m_s,alpha_deg,omega_rad_s[,repetitions])", path.display()),
    };
    let column = |name: &str| header.iter().position(|h| *h == name);
    let (Some(v), Some(a), Some(w)) = (column("v_m_s"), column("alpha_deg"), column("omega_rad_s")) else {
        bail!(
            "{}: line 1: the header must name v_m_s, alpha_deg and omega_rad_s (got {})",
            path.display(),
            header.join(",")
        );
    };
    let reps = column("repetitions");
    let mut out = Vec::new();
    for (i, line) in lines {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let at = |field: &str| format!("{}: line {}: {field}", path.display(), i + 1);
        let num = |c: usize, field: &str| -> anyhow::Result<f64> {
            let s = cells.get(c).copied().unwrap_or("");
            match s.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => bail!("{}: {s:?} is not a finite number", at(field)),
            }
        };
        let command = Command {
            v_m_s: num(v, "v_m_s")?,
            alpha_rad: num(a, "alpha_deg")?.to_radians(),
            omega_rad_s: num(w, "omega_rad_s")?,
        };
        let k = match reps {
            Some(r) => {
                let k = num(r, "repetitions")?;
                if k < 1.0 || k.fract() != 0.0 || k > 1000.0 {
                    bail!("{}: {k} is not a whole number from 1 to 1000", at("repetitions"));
                }
                k as usize
            }
            None => 1,
        };
        let miss = unreachable_twists(design, std::slice::from_ref(&command))?[0];
        if miss.iter().any(|m| m.abs() > UNREACHABLE_TOL) {
            bail!("{}: {}", at("alpha_deg"), unreachable_message(design.n_wheels(), &command, &miss));
        }
        out.extend(std::iter::repeat_n(command, k));
    }
    if out.is_empty() {
        bail!("{}: no commands after the header", path.display());
    }
    Ok(out)
}
