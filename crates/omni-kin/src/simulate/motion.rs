//! One simulated run on its own random stream: the controller's lag, the true body motion (wheel- and
//! twist-stage effects, exact arcs on the fine step), the encoder samples, the noisy ground truth and the
//! robot's own odometry.

use super::{Leg, SampledRun, SimConfig};
use crate::effect::WheelContext;
use crate::error::KinError;
use crate::model::{FittedModel, Scheme};
use crate::odometry::step;
use crate::pose::{Pose2, StampedPose};
use crate::run::{Command, Run, RunData};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::f64::consts::PI;

/// `after` (a fine step from `before` at twist `tw` for `h` s) moved by the slip noise `q`: along and across
/// the motion (across only on a `holonomic` base) and in heading, with the variances of the step's distance
/// and turn. Three draws per step.
fn slipped(
    rng: &mut ChaCha8Rng,
    q: &crate::noise::NoiseRates,
    holonomic: bool,
    before: Pose2,
    after: Pose2,
    tw: crate::pose::Twist2,
    h: f64,
) -> Pose2 {
    let d = tw.vx_m_s.hypot(tw.vy_m_s) * h;
    let phi = tw.omega_rad_s.abs() * h;
    let along = gauss(rng, (q.trans_per_m * d + q.trans_per_rad * phi).sqrt());
    let across_var = if holonomic { q.strafe_per_m * d + q.trans_per_rad * phi } else { 0.0 };
    let across = gauss(rng, across_var.sqrt());
    let heading = gauss(rng, (q.rot_per_rad * phi + q.rot_per_m * d).sqrt());
    let (s, c) = (before.theta_rad + tw.vy_m_s.atan2(tw.vx_m_s)).sin_cos();
    Pose2::new(after.x_m + c * along - s * across, after.y_m + s * along + c * across, after.theta_rad + heading)
}

/// Zero-mean Gaussian noise of standard deviation `sigma` (one draw, always, so streams stay aligned).
fn gauss(rng: &mut ChaCha8Rng, sigma: f64) -> f64 {
    let z: f64 = StandardNormal.sample(rng);
    sigma * z
}

/// Simulate one run of `legs` in a row (their durations sum to `config.duration_s`) on random stream
/// `stream`; the run carries `label` (its command and repetition) when there is one; the true base pose
/// every `base_period_s` over [0, total] comes with it (none without).
///
/// long: one fine-step loop applying every effect stage in order (clock, wheel speeds, twist, integration,
/// measurement) on shared per-step state; to split into stage helpers (issue 15 leftover).
pub(super) fn simulate_motion(
    config: &SimConfig,
    truth: &FittedModel,
    legs: &[Leg],
    label: Option<(Command, usize)>,
    stream: u64,
    name: String,
    base_period_s: Option<f64>,
) -> Result<SampledRun, KinError> {
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    rng.set_stream(stream);
    let res = truth.model.resolve(&truth.params)?;
    // A base whose wheels can push it sideways slips sideways too.
    let holonomic = res.ik.row(1).iter().any(|v| v.abs() > 1e-12);
    let n_w = config.design.n_wheels();
    let fwd = config.design.wheels_from_twist();
    // Each leg's wheel-speed targets and when it ends (since the motion started). s.
    let mut leg_end_s = 0.0;
    let targets: Vec<(f64, Vec<f64>)> = legs
        .iter()
        .map(|leg| {
            let c = leg.command;
            let (s, co) = c.alpha_rad.sin_cos();
            leg_end_s += leg.duration_s;
            let wheels = (0..n_w)
                .map(|i| fwd[(i, 0)] * c.v_m_s * co + fwd[(i, 1)] * c.v_m_s * s + fwd[(i, 2)] * c.omega_rad_s)
                .collect();
            (leg_end_s, wheels)
        })
        .collect();
    let target_at = |since_start_s: f64| -> &[f64] {
        let i = targets.iter().position(|(end, _)| since_start_s < *end).unwrap_or(targets.len() - 1);
        &targets[i].1
    };

    // Time line (true clock): the robot moves in [rest, rest + duration]; we simulate a margin either side.
    let total = 2.0 * config.rest_s + config.duration_s;
    let margin = 0.5;
    let h = config.fine_step_s;
    let t0 = -margin;
    let n_fine = ((total + 2.0 * margin) / h).ceil() as usize + 1;
    let fine_t: Vec<f64> = (0..n_fine).map(|k| t0 + k as f64 * h).collect();

    // True wheel (motor) speeds through the first-order controller; exact discretisation of the lag.
    let alpha = 1.0 - (-h / config.controller_tau_s).exp();
    let mut speed = vec![0.0; n_w];
    let mut motor_rad_s = vec![0.0; n_fine * n_w];
    for (k, &t) in fine_t.iter().enumerate() {
        let on = t >= config.rest_s && t < config.rest_s + config.duration_s;
        let target = target_at(t - config.rest_s);
        for i in 0..n_w {
            let goal = if on { target[i] } else { 0.0 };
            speed[i] += alpha * (goal - speed[i]);
            motor_rad_s[k * n_w + i] = speed[i];
        }
    }
    let start_angle: Vec<f64> = (0..n_w).map(|_| rng.random_range(0.0..2.0 * PI)).collect();

    // True body motion: wheel effects on the true speeds, then IK, twist effects, exact arcs.
    let mut effective = motor_rad_s.clone();
    if !res.wheel_effects.is_empty() {
        let dts = vec![h; n_fine];
        let ctx = WheelContext { n_wheels: n_w, t_s: &fine_t, dt_s: &dts, start_angle_rad: &start_angle };
        for (e, p) in &res.wheel_effects {
            crate::effect::Effect::wheel_rates(*e, p, &ctx, &mut effective);
        }
    }
    let mut body = vec![Pose2::IDENTITY; n_fine];
    let mut pose = Pose2::IDENTITY;
    for k in 0..n_fine {
        // Speed held over (t_{k-1}, t_k]: pose[k] is the pose at t_k.
        if k > 0 {
            let w = &effective[k * n_w..(k + 1) * n_w];
            let mut tw = res.ik.twist(w);
            // Ground truth starts at t = 0 on the true clock.
            let at = crate::effect::TwistAt { pose, since_start_s: (fine_t[k] - 0.5 * h).max(0.0) };
            for (e, p) in &res.twist_effects {
                tw = crate::effect::Effect::twist_at(*e, p, tw, w, &at);
            }
            let before = pose;
            pose = step(Scheme::ExactArc, pose, tw, h);
            if let Some(q) = &config.slip_noise {
                pose = slipped(&mut rng, q, holonomic, before, pose, tw, h);
            }
        }
        body[k] = pose;
    }
    let body_at = |t: f64| -> Pose2 {
        let x = ((t - t0) / h).clamp(0.0, (n_fine - 1) as f64);
        let k = (x.floor() as usize).min(n_fine - 2);
        let f = x - k as f64;
        let (a, b) = (body[k], body[k + 1]);
        Pose2::new(
            a.x_m + f * (b.x_m - a.x_m),
            a.y_m + f * (b.y_m - a.y_m),
            a.theta_rad + f * (b.theta_rad - a.theta_rad),
        )
    };
    // Motor angle at any true time (trapezoid on the fine grid is exact enough at 1 ms).
    let mut motor_angle = vec![0.0; n_fine * n_w];
    for i in 0..n_w {
        let mut a = start_angle[i];
        for k in 0..n_fine {
            if k > 0 {
                a += motor_rad_s[k * n_w + i] * h;
            }
            motor_angle[k * n_w + i] = a;
        }
    }
    let angle_at = |t: f64, i: usize| -> f64 {
        let x = ((t - t0) / h).clamp(0.0, (n_fine - 1) as f64);
        let k = (x.floor() as usize).min(n_fine - 2);
        let f = x - k as f64;
        motor_angle[k * n_w + i] + f * (motor_angle[(k + 1) * n_w + i] - motor_angle[k * n_w + i])
    };

    // Encoder samples on the true clock, from just after the margin start to the end.
    let dt = 1.0 / config.wheel_rate_hz;
    let first = t0 + dt;
    let last = total + margin - dt;
    let n_nominal = ((last - first) / dt).floor() as usize + 1;
    let lag = res.clock_lag_s;
    let quantise = |a: f64| match config.ticks_per_rev {
        Some(tpr) => (a * tpr / (2.0 * PI)).floor() * 2.0 * PI / tpr,
        None => a,
    };
    let mut wheel_t_s = Vec::with_capacity(n_nominal);
    let mut wheel_rad_s = Vec::with_capacity(n_nominal * n_w);
    let mut prev_t = t0;
    let mut prev_counts: Vec<f64> = (0..n_w).map(|i| quantise(angle_at(t0, i))).collect();
    let wheel_start_rad = prev_counts.clone();
    for k in 0..n_nominal {
        let nominal = first + k as f64 * dt;
        let jitter = if config.sample_jitter_s > 0.0 { rng.random_range(0.0..config.sample_jitter_s) } else { 0.0 };
        let t = nominal + jitter;
        let dropped = config.sample_drop_probability > 0.0
            && k + 1 < n_nominal
            && rng.random_range(0.0..1.0) < config.sample_drop_probability;
        if dropped {
            continue;
        }
        let counts: Vec<f64> = (0..n_w).map(|i| quantise(angle_at(t, i))).collect();
        let interval = t - prev_t;
        for i in 0..n_w {
            wheel_rad_s.push((counts[i] - prev_counts[i]) / interval + gauss(&mut rng, config.wheel_noise_rad_s));
        }
        wheel_t_s.push(t + lag);
        prev_t = t;
        prev_counts = counts;
    }

    // Ground truth: sensor pose at irregular intervals over [0, total], with noise.
    let (lo, hi) = config.truth_interval_s;
    let mut times = vec![0.0];
    loop {
        let next = times[times.len() - 1] + if hi > lo { rng.random_range(lo..hi) } else { lo };
        if next >= total {
            break;
        }
        times.push(next);
    }
    if total - times[times.len() - 1] < 0.5 * lo {
        times.pop();
    }
    times.push(total);
    let truth_poses = times
        .iter()
        .map(|&t| {
            let p = body_at(t).compose(&res.sensor_from_body);
            StampedPose {
                t_s: t,
                pose: Pose2::new(
                    p.x_m + gauss(&mut rng, config.truth_noise_m),
                    p.y_m + gauss(&mut rng, config.truth_noise_m),
                    p.theta_rad + gauss(&mut rng, config.truth_noise_rad),
                ),
            }
        })
        .collect();

    // The robot's own odometry: the design matrix, Eq. 1 at the nominal step, from the odom origin.
    let design_ik = config.design.twist_from_wheels()?;
    let mut odom = Pose2::IDENTITY;
    let recorded_odometry = wheel_t_s
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            odom = step(Scheme::Euler, odom, design_ik.twist(&wheel_rad_s[k * n_w..(k + 1) * n_w]), dt);
            StampedPose { t_s: t, pose: odom }
        })
        .collect();

    let base = base_period_s.map_or_else(Vec::new, |p| {
        (0..)
            .map(|k| k as f64 * p)
            .take_while(|&t| t <= total + 1e-9 * p)
            .map(|t| StampedPose { t_s: t, pose: body_at(t) })
            .collect()
    });
    let run = Run::new(RunData {
        name,
        wheel_t_s,
        wheel_rad_s,
        n_wheels: n_w,
        truth: truth_poses,
        command: label.map(|(c, _)| c),
        repetition: label.map(|(_, r)| r as u32),
        recorded_odometry,
        wheel_start_rad,
        truth_position_only: false,
    })?;
    Ok(SampledRun { run, base })
}
