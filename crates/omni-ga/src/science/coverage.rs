//! Motion coverage: which motions the held-out runs contain that the training runs never do.
//!
//! A fit can only learn what its runs show. Squares (sides, then turns on the spot) never translate and
//! rotate at once, so no fit on them can see a turn rate that depends on both; judged on circles, such a
//! model fails however well it fits the squares. This module says so before anyone reads the held-out
//! error as a missing effect.
//!
//! Every wheel sample of every run becomes a body twist through the model (`(vx, vy, ω)`, its IK matrix at
//! its parameters); samples where the robot stands still ([`omni_kin::effect::moving`]) are left out. Each
//! moving sample falls in a bin of
//! - translation speed `|v|`: below [`STILL_SHARE`] of the reference speed (not translating), then three
//!   equal bins up to the reference, and one above;
//! - turn rate `ω`, signed, binned the same way against the reference turn rate;
//! - direction of travel `atan2(vy, vx)`, in eight 45° sectors (none when not translating).
//!
//! The references are the larger of the two sets' 95th percentiles of `|v|` and `|ω|` over moving
//! samples. A bin is **covered** when the training runs spend at least [`MIN_COVER_SHARE`] of their moving
//! samples in it. The held-out samples in uncovered bins, grouped by kind (translating, rotating,
//! translating while rotating), are the **gaps** when a kind holds at least [`MIN_GAP_SHARE`] of the
//! held-out moving samples; each gap proposes commands to record (its median speed and turn rate, in the
//! directions and turn senses it contains).
//!
//! **Unseen effects**: a catalogued wheel- or twist-stage effect, at a test value (a quarter of the way
//! from its null to its upper bound), changes the body twist on every sample; when its RMS change on the
//! training runs is below [`UNSEEN_RESPONSE`] of that on the held-out runs, the training runs cannot see
//! it (e.g. `turn_scrub` and `rotation_slip` on squares).
//!
//! No I/O; the words are made in [`crate::science::text`].

use crate::error::Error;
use omni_kin::effect::{self, Effect, EffectKind, Stage, WheelContext};
use omni_kin::{Command, FittedModel, Run, Twist2};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// Share of the reference speed (turn rate) below which a moving sample does not count as translating
/// (turning). 0.1.
pub const STILL_SHARE: f64 = 0.1;
/// Equal-width magnitude bins between [`STILL_SHARE`] and the reference (one more above it). 3.
const MAGNITUDE_BINS: f64 = 3.0;
/// Sectors of the direction of travel. 8 (45° each).
const SECTORS: usize = 8;
/// Percentile of `|v|` and `|ω|` over moving samples that sets the references. 0.95.
const REFERENCE_PERCENTILE: f64 = 0.95;
/// Share of the training runs' moving samples from which a bin counts as covered. 0.002.
pub const MIN_COVER_SHARE: f64 = 0.002;
/// Share of the held-out moving samples from which an uncovered kind of motion is a gap. 0.05.
pub const MIN_GAP_SHARE: f64 = 0.05;
/// Share of a gap's samples from which a direction sector or turn sense gets its own command. 0.2.
const RECORD_SHARE: f64 = 0.2;
/// At most this many commands proposed per gap. 8.
const MAX_RECORD: usize = 8;
/// An effect whose response on the training runs is below this share of its response on the held-out
/// runs is unseen by the training runs. 0.1.
pub const UNSEEN_RESPONSE: f64 = 0.1;
/// An effect's test value: this share of the way from its null value to its upper bound. 0.25.
const TEST_SHARE: f64 = 0.25;

/// What a moving sample does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MotionKind {
    /// Translates without turning (a side of a square, a straight line).
    Translating,
    /// Turns without translating (on the spot).
    Rotating,
    /// Translates and turns at once (an arc, a circle, free driving).
    TranslatingWhileRotating,
}

/// One set's motions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotionProfile {
    /// Runs.
    pub runs: usize,
    /// Wheel samples.
    pub samples: usize,
    /// Samples where the robot moves.
    pub moving_samples: usize,
    /// Shares of the moving samples that translate only, rotate only, and translate while rotating (the
    /// rest creep slower than [`STILL_SHARE`] of both references).
    pub translating: f64,
    /// See `translating`.
    pub rotating: f64,
    /// See `translating`.
    pub translating_while_rotating: f64,
    /// 95th percentile of `|v|` over moving samples. m/s.
    pub speed_p95_m_s: f64,
    /// 95th percentile of `|ω|` over moving samples. rad/s.
    pub turn_rate_p95_rad_s: f64,
}

/// A kind of motion the held-out runs contain and the training runs do not.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotionGap {
    /// What the missing samples do.
    pub kind: MotionKind,
    /// Share of the held-out moving samples of this kind in bins the training runs never visit.
    pub held_out_share: f64,
    /// Share of the training runs' moving samples of this kind (in any bin).
    pub train_share: f64,
    /// Median `|v|` of the missing samples. m/s.
    pub speed_m_s: f64,
    /// Median `|ω|` of the missing samples. rad/s.
    pub turn_rate_rad_s: f64,
    /// Commands to record that contain them (most common first).
    pub record: Vec<Command>,
}

/// The training runs' motions against the held-out runs'.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotionCoverage {
    /// The training runs.
    pub train: MotionProfile,
    /// The held-out runs.
    pub held_out: MotionProfile,
    /// Reference speed of the bins. m/s.
    pub reference_speed_m_s: f64,
    /// Reference turn rate of the bins. rad/s.
    pub reference_turn_rate_rad_s: f64,
    /// Share of the held-out moving samples in bins the training runs cover.
    pub covered: f64,
    /// What the training runs lack, largest first.
    pub gaps: Vec<MotionGap>,
    /// Catalogued effects the held-out runs excite and the training runs cannot see (ids).
    pub unseen_effects: Vec<String>,
}

impl MotionCoverage {
    /// The training runs lack motions the held-out runs contain.
    pub fn lacking(&self) -> bool {
        !self.gaps.is_empty()
    }
}

/// One moving sample's body twist, with the wheel speeds it came from.
struct Sample {
    twist: Twist2,
}

/// Bin of a sample: (speed bin, signed turn-rate bin, direction sector or [`SECTORS`]).
type Bin = (u8, i8, u8);

/// The references of the bins.
#[derive(Clone, Copy)]
struct Scale {
    speed_m_s: f64,
    turn_rad_s: f64,
}

impl Scale {
    fn speed_bin(&self, v: f64) -> u8 {
        magnitude_bin(v / self.speed_m_s)
    }
    fn turn_bin(&self, w: f64) -> i8 {
        magnitude_bin(w.abs() / self.turn_rad_s) as i8 * if w < 0.0 { -1 } else { 1 }
    }
    fn bin(&self, t: &Twist2) -> Bin {
        let v = t.vx_m_s.hypot(t.vy_m_s);
        let s = self.speed_bin(v);
        (s, self.turn_bin(t.omega_rad_s), if s == 0 { SECTORS as u8 } else { sector(t) })
    }
    fn kind(&self, t: &Twist2) -> Option<MotionKind> {
        let (s, w, _) = self.bin(t);
        match (s > 0, w != 0) {
            (true, true) => Some(MotionKind::TranslatingWhileRotating),
            (true, false) => Some(MotionKind::Translating),
            (false, true) => Some(MotionKind::Rotating),
            (false, false) => None,
        }
    }
}

/// 0 below [`STILL_SHARE`], then 1…[`MAGNITUDE_BINS`] up to 1, and one more above.
fn magnitude_bin(share: f64) -> u8 {
    if share < STILL_SHARE { 0 } else { (1.0 + (share * MAGNITUDE_BINS).floor()).min(MAGNITUDE_BINS + 1.0) as u8 }
}

/// The 45° sector of the direction of travel (0: forward, 2: left, 4: backward, 6: right).
fn sector(t: &Twist2) -> u8 {
    let a = t.vy_m_s.atan2(t.vx_m_s);
    ((a / (2.0 * PI / SECTORS as f64)).round() as i64).rem_euclid(SECTORS as i64) as u8
}

/// The moving samples of `runs` as body twists through `model`'s IK matrix.
fn moving_samples(model: &FittedModel, runs: &[Run]) -> Result<(Vec<Sample>, usize), Error> {
    let res = model.model.resolve(&model.params)?;
    let mut out = Vec::new();
    let mut samples = 0;
    for r in runs {
        samples += r.n_samples();
        for k in 0..r.n_samples() {
            let twist = res.ik.twist(r.wheel_sample(k));
            if effect::moving(&twist) {
                out.push(Sample { twist });
            }
        }
    }
    Ok((out, samples))
}

/// The `q`-th quantile (0…1) of `values` (0 when empty).
fn quantile(mut values: Vec<f64>, q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let i = ((values.len() - 1) as f64 * q).round() as usize;
    values[i]
}

fn speeds(samples: &[Sample]) -> Vec<f64> {
    samples.iter().map(|s| s.twist.vx_m_s.hypot(s.twist.vy_m_s)).collect()
}

fn turn_rates(samples: &[Sample]) -> Vec<f64> {
    samples.iter().map(|s| s.twist.omega_rad_s.abs()).collect()
}

fn profile(runs: usize, samples: usize, moving: &[Sample], scale: &Scale) -> MotionProfile {
    let n = moving.len().max(1) as f64;
    let share = |k: MotionKind| moving.iter().filter(|s| scale.kind(&s.twist) == Some(k)).count() as f64 / n;
    MotionProfile {
        runs,
        samples,
        moving_samples: moving.len(),
        translating: share(MotionKind::Translating),
        rotating: share(MotionKind::Rotating),
        translating_while_rotating: share(MotionKind::TranslatingWhileRotating),
        speed_p95_m_s: quantile(speeds(moving), REFERENCE_PERCENTILE),
        turn_rate_p95_rad_s: quantile(turn_rates(moving), REFERENCE_PERCENTILE),
    }
}

/// Compare the motions of the training runs with those of the held-out runs, through `model` (see the
/// module docs).
pub fn motion_coverage(model: &FittedModel, train: &[Run], held_out: &[Run]) -> Result<MotionCoverage, Error> {
    let (train_moving, train_samples) = moving_samples(model, train)?;
    let (held_moving, held_samples) = moving_samples(model, held_out)?;
    let reference = |f: fn(&[Sample]) -> Vec<f64>, floor: f64| {
        let a = quantile(f(&train_moving), REFERENCE_PERCENTILE);
        a.max(quantile(f(&held_moving), REFERENCE_PERCENTILE)).max(floor)
    };
    let scale = Scale {
        speed_m_s: reference(speeds, effect::MOVING_SPEED_M_S),
        turn_rad_s: reference(turn_rates, effect::MOVING_OMEGA_RAD_S),
    };
    let mut visits: BTreeMap<Bin, usize> = BTreeMap::new();
    for s in &train_moving {
        *visits.entry(scale.bin(&s.twist)).or_default() += 1;
    }
    let least = (MIN_COVER_SHARE * train_moving.len() as f64).max(1.0);
    let covered = |s: &Sample| visits.get(&scale.bin(&s.twist)).is_some_and(|&c| c as f64 >= least);
    let missing: Vec<&Sample> = held_moving.iter().filter(|s| !covered(s)).collect();
    let train_profile = profile(train.len(), train_samples, &train_moving, &scale);
    let gaps = gaps(&missing, held_moving.len(), &train_profile, &scale);
    Ok(MotionCoverage {
        held_out: profile(held_out.len(), held_samples, &held_moving, &scale),
        train: train_profile,
        reference_speed_m_s: scale.speed_m_s,
        reference_turn_rate_rad_s: scale.turn_rad_s,
        covered: 1.0 - missing.len() as f64 / held_moving.len().max(1) as f64,
        gaps,
        unseen_effects: unseen_effects(model, train, held_out, &scale)?,
    })
}

/// The kinds of motion among the `missing` held-out samples (of `held_moving`) that reach
/// [`MIN_GAP_SHARE`], largest first.
fn gaps(missing: &[&Sample], held_moving: usize, train: &MotionProfile, scale: &Scale) -> Vec<MotionGap> {
    let kinds = [MotionKind::TranslatingWhileRotating, MotionKind::Translating, MotionKind::Rotating];
    let mut out: Vec<MotionGap> = kinds
        .into_iter()
        .filter_map(|kind| {
            let of_kind: Vec<&Sample> =
                missing.iter().copied().filter(|s| scale.kind(&s.twist) == Some(kind)).collect();
            let held_out_share = of_kind.len() as f64 / held_moving.max(1) as f64;
            (held_out_share >= MIN_GAP_SHARE).then(|| {
                let owned: Vec<Sample> = of_kind.iter().map(|s| Sample { twist: s.twist }).collect();
                let speed_m_s = quantile(speeds(&owned), 0.5);
                let turn_rate_rad_s = quantile(turn_rates(&owned), 0.5);
                MotionGap {
                    kind,
                    held_out_share,
                    train_share: match kind {
                        MotionKind::Translating => train.translating,
                        MotionKind::Rotating => train.rotating,
                        MotionKind::TranslatingWhileRotating => train.translating_while_rotating,
                    },
                    speed_m_s,
                    turn_rate_rad_s,
                    record: record(kind, &owned, speed_m_s, turn_rate_rad_s, scale),
                }
            })
        })
        .collect();
    out.sort_by(|a, b| b.held_out_share.total_cmp(&a.held_out_share));
    out
}

/// Commands that contain a gap's samples: its median speed and turn rate, in each direction sector and
/// turn sense holding at least [`RECORD_SHARE`] of them (most common first, at most [`MAX_RECORD`]).
fn record(kind: MotionKind, samples: &[Sample], speed_m_s: f64, turn_rad_s: f64, scale: &Scale) -> Vec<Command> {
    let mut counts: BTreeMap<(u8, i8), usize> = BTreeMap::new();
    for s in samples {
        let (_, w, sector) = scale.bin(&s.twist);
        *counts.entry((sector, w.signum())).or_default() += 1;
    }
    let mut common: Vec<((u8, i8), usize)> =
        counts.into_iter().filter(|&(_, c)| c as f64 >= RECORD_SHARE * samples.len() as f64).collect();
    common.sort_by_key(|c| std::cmp::Reverse(c.1));
    common
        .into_iter()
        .take(MAX_RECORD)
        .map(|((sector, sign), _)| {
            let translating = kind != MotionKind::Rotating;
            Command {
                v_m_s: if translating { speed_m_s } else { 0.0 },
                alpha_rad: if translating { sector as f64 * 2.0 * PI / SECTORS as f64 } else { 0.0 },
                omega_rad_s: if kind == MotionKind::Translating { 0.0 } else { sign as f64 * turn_rad_s },
            }
        })
        .collect()
}

/// The catalogued wheel- and twist-stage effects that the held-out runs excite and the training runs do
/// not (module docs).
fn unseen_effects(model: &FittedModel, train: &[Run], held_out: &[Run], scale: &Scale) -> Result<Vec<String>, Error> {
    let n = model.model.n_wheels();
    let res = model.model.resolve(&model.params)?;
    let mut out = Vec::new();
    for id in effect::CATALOGUE {
        let e = EffectKind::from_id(id, n)?;
        if !matches!(e.stage(), Stage::Wheel | Stage::Twist) {
            continue;
        }
        let p: Vec<f64> = e.params().iter().map(|s| s.null + TEST_SHARE * (s.upper - s.null)).collect();
        let response = |runs: &[Run]| response(&e, &p, &res.ik, runs, scale);
        let held = response(held_out);
        if held > 0.0 && response(train) < UNSEEN_RESPONSE * held {
            out.push(id.to_string());
        }
    }
    Ok(out)
}

/// RMS change of the moving samples' body twist (each component over its reference) when the effect `e`
/// at `p` acts on `runs`.
fn response(e: &EffectKind, p: &[f64], ik: &omni_kin::IkMatrix, runs: &[Run], scale: &Scale) -> f64 {
    let n = ik.n_wheels();
    let (mut sum, mut count) = (0.0, 0usize);
    for r in runs {
        let mut wheels = r.wheel_rad_s().to_vec();
        if e.stage() == Stage::Wheel {
            let t = r.wheel_t_s();
            let dt: Vec<f64> = (0..t.len()).map(|k| if k == 0 { r.median_dt_s() } else { t[k] - t[k - 1] }).collect();
            let ctx = WheelContext { n_wheels: n, t_s: t, dt_s: &dt, start_angle_rad: r.wheel_start_rad() };
            e.wheel_rates(p, &ctx, &mut wheels);
        }
        for k in 0..r.n_samples() {
            let before = ik.twist(r.wheel_sample(k));
            if !effect::moving(&before) {
                continue;
            }
            let w = &wheels[k * n..(k + 1) * n];
            let after = e.twist(p, ik.twist(w), w);
            let dv = (after.vx_m_s - before.vx_m_s).hypot(after.vy_m_s - before.vy_m_s) / scale.speed_m_s;
            let dw = (after.omega_rad_s - before.omega_rad_s) / scale.turn_rad_s;
            sum += dv * dv + dw * dw;
            count += 1;
        }
    }
    if count == 0 { 0.0 } else { (sum / count as f64).sqrt() }
}
