//! The simulated scanner: how a lidar measures the room ([`super::room`]) — its beams, range, noise,
//! dropouts and sweep ([`ScanSettings`]) — and the scans it writes ([`simulate_scan`], [`simulate_sweep`],
//! [`simulate_scans`]).
//!
//! Besides an ideal scanner (the default: 360°, 1 cm noise, 1 % random dropouts), [`LidarModel`] gives the
//! settings of two real kinds (`ScanSettings::of_model`), made as their scans come out indoors:
//! - **noise that grows with range** (`range_noise_m + range_noise_per_m · r`);
//! - **dropouts in bursts** (a beam follows its neighbour into a dropout: a Markov chain whose bursts last
//!   `dropout_burst_beams` on average, the share of dropped beams `dropout`), on **dark surfaces** (every
//!   third wall segment returns nothing with probability `dark_dropout`) and at **grazing angles** (a beam
//!   meeting a wall farther than `grazing_limit_rad` from its normal returns nothing), so that about half the
//!   beams of a URG-04LX come back empty in the built-in room;
//! - **mixed pixels** at depth jumps: a beam whose footprint (half a beam spacing either side) straddles a
//!   foreground and a background surface more than [`MIXED_JUMP_M`] apart reads a range between them;
//! - **no return written as the driver writes it** ([`NoReturn`]): +inf and NaN (REP-117), 0 (Hokuyo's
//!   urg_node) or the maximum range;
//! - **a sweep**: beam `i` measured `i · time_increment` after the stamp, the mirror turning once per period
//!   (`time_increment = period · angle_increment / 2π`: 0.1 s / 1024 for a URG-04LX, whose 682 beams take
//!   two thirds of the period).

use super::Scan;
use super::room::Room;
use crate::choice;
use crate::error::{KinError, Settings};
use crate::pose::{Pose2, StampedPose};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A foreground and a background farther apart than this within one beam's footprint give a mixed pixel
/// (with [`ScanSettings::mixed_pixels`]). m.
pub const MIXED_JUMP_M: f64 = 0.05;

/// A kind of lidar the simulator imitates (`simulate --lidar-model`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LidarModel {
    /// An ideal scanner: the settings given (defaults: 360°, 720 beams, 12 m, 1 cm noise, 1 % dropouts).
    Ideal,
    /// A Hokuyo URG-04LX: 682 beams over 240° at 10 Hz, 0.02–5.6 m, noise 4 mm + 0.2 % of range, about half
    /// the beams empty (bursts, dark surfaces, grazing), mixed pixels, no return as 0, a 0.1 s sweep.
    Urg04lx,
    /// A Slamtec RPLidar A2: 720 beams over 360° at 10 Hz, 0.15–12 m, noise 3 mm + 0.3 % of range, dropouts
    /// in bursts, on dark surfaces and at grazing angles, mixed pixels, no return as +inf, a 0.1 s sweep.
    Rplidar,
}

choice!(LidarModel, default = Ideal, {
    Ideal => "ideal": "an ideal scanner with the settings given (--lidar-beams, --lidar-noise, …)",
    Urg04lx => "urg04lx": "a Hokuyo URG-04LX: 682 beams over 240°, 5.6 m, noise growing with range, half the beams \
                           empty, mixed pixels, 0 for no return, a 0.1 s sweep",
    Rplidar => "rplidar": "a Slamtec RPLidar A2: 720 beams over 360°, 12 m, noise growing with range, dropouts, \
                           mixed pixels, +inf for no return, a 0.1 s sweep",
});

/// How a driver writes a beam that returned nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NoReturn {
    /// +inf beyond the range, NaN for a dropout (REP-117).
    #[default]
    Infinity,
    /// 0 (Hokuyo's urg_node, many drivers with `range_min` 0).
    Zero,
    /// The maximum range itself.
    MaxRange,
}

/// How the simulated lidar scans. Defaults: a 10 Hz, 720-beam, 360° scanner of 12 m range.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScanSettings {
    /// Scans per second. Hz. Default 10.
    pub rate_hz: f64,
    /// Beams per scan, evenly spread over the field of view. Default 720 (0.5° apart over 360°).
    pub beams: usize,
    /// Field of view, centred on the sensor's x axis. rad. Default 2π: beams from −180°, `2π / beams` apart;
    /// a partial one (a 270° Hokuyo) from `−fov / 2` to `+fov / 2` inclusive, `fov / (beams − 1)` apart, as its
    /// driver writes `angle_min`, `angle_max` and `angle_increment`.
    #[serde(default = "full_turn_rad")]
    pub fov_rad: f64,
    /// Shortest valid range. m. Default 0.05.
    pub range_min_m: f64,
    /// Longest valid range: a wall farther away is no return (+inf). m. Default 12.
    pub range_max_m: f64,
    /// Gaussian noise on each range. m. Default 0.01.
    pub range_noise_m: f64,
    /// Share of beams that return nothing (NaN), at random. Default 0.01.
    pub dropout: f64,
    /// The beams are measured one after another over the scan period (1 / `rate_hz`), as a spinning lidar
    /// measures them, so a moving robot bends its scans; false: each scan at one instant. Default false.
    #[serde(default)]
    pub sweeping: bool,
    /// Range noise growing with range: the noise's standard deviation is `range_noise_m` plus this times
    /// the range. Default 0.
    #[serde(default)]
    pub range_noise_per_m: f64,
    /// Mean length of a dropout burst, in beams; 1: each beam drops out on its own. Default 1.
    #[serde(default = "one")]
    pub dropout_burst_beams: f64,
    /// Probability that a beam meeting a dark surface (every third wall segment, [`is_dark`]) returns
    /// nothing. Default 0.
    #[serde(default)]
    pub dark_dropout: f64,
    /// A beam meeting a wall farther than this from its normal returns nothing. rad. Default π/2 (never).
    #[serde(default = "right_angle_rad")]
    pub grazing_limit_rad: f64,
    /// Mixed pixels at depth jumps (see the module docs). Default false.
    #[serde(default)]
    pub mixed_pixels: bool,
    /// How a beam that returned nothing is written. Default +inf / NaN.
    #[serde(default)]
    pub no_return: NoReturn,
}

/// 1.
fn one() -> f64 {
    1.0
}

/// π/2.
fn right_angle_rad() -> f64 {
    0.5 * PI
}

/// Whether wall segment `k` of a room ([`super::room::RayHit::segment`]) is dark: every third one, from the
/// second (the built-in room's right wall and a face of each box).
pub fn is_dark(segment: usize) -> bool {
    segment % 3 == 1
}

/// 2π: a lidar that sees all round.
fn full_turn_rad() -> f64 {
    2.0 * PI
}

impl Default for ScanSettings {
    fn default() -> Self {
        Self {
            rate_hz: 10.0,
            beams: 720,
            fov_rad: full_turn_rad(),
            range_min_m: 0.05,
            range_max_m: 12.0,
            range_noise_m: 0.01,
            dropout: 0.01,
            sweeping: false,
            range_noise_per_m: 0.0,
            dropout_burst_beams: 1.0,
            dark_dropout: 0.0,
            grazing_limit_rad: right_angle_rad(),
            mixed_pixels: false,
            no_return: NoReturn::Infinity,
        }
    }
}

impl ScanSettings {
    /// The settings of a kind of lidar (see [`LidarModel`]); [`LidarModel::Ideal`] is the default.
    pub fn of_model(model: LidarModel) -> Self {
        match model {
            LidarModel::Ideal => Self::default(),
            LidarModel::Urg04lx => Self {
                rate_hz: 10.0,
                beams: 682,
                // 681 steps of 360°/1024: the URG-04LX's encoder, 239.4°.
                fov_rad: 681.0 * 2.0 * PI / 1024.0,
                range_min_m: 0.02,
                range_max_m: 5.6,
                range_noise_m: 0.004,
                range_noise_per_m: 0.002,
                dropout: 0.2,
                dropout_burst_beams: 6.0,
                dark_dropout: 0.8,
                grazing_limit_rad: 70f64.to_radians(),
                mixed_pixels: true,
                no_return: NoReturn::Zero,
                sweeping: true,
            },
            LidarModel::Rplidar => Self {
                rate_hz: 10.0,
                beams: 720,
                fov_rad: full_turn_rad(),
                range_min_m: 0.15,
                range_max_m: 12.0,
                range_noise_m: 0.003,
                range_noise_per_m: 0.003,
                dropout: 0.15,
                dropout_burst_beams: 4.0,
                dark_dropout: 0.7,
                grazing_limit_rad: 70f64.to_radians(),
                mixed_pixels: true,
                no_return: NoReturn::Infinity,
                sweeping: true,
            },
        }
    }

    /// Checks the settings; the error names the field.
    pub fn check(&self) -> Result<(), KinError> {
        let bad = |f: &str, why: &str| Err(KinError::Setting { of: Settings::Lidar, field: f.into(), why: why.into() });
        if !(self.rate_hz > 0.0 && self.rate_hz.is_finite()) {
            return bad("rate_hz", "must be finite and > 0");
        }
        if self.beams < 3 {
            return bad("beams", "must be at least 3");
        }
        if !(self.fov_rad > 0.0 && self.fov_rad <= 2.0 * PI) {
            return bad("fov_rad", "must be in (0, 2π] (a field of view of up to 360°)");
        }
        if !(self.range_min_m >= 0.0 && self.range_max_m > self.range_min_m && self.range_max_m.is_finite()) {
            return bad("range_max_m", "need 0 ≤ range_min_m < range_max_m, finite");
        }
        if !(self.range_noise_m >= 0.0 && self.range_noise_m.is_finite()) {
            return bad("range_noise_m", "must be finite and ≥ 0");
        }
        if !(0.0..1.0).contains(&self.dropout) {
            return bad("dropout", "must be in [0, 1)");
        }
        if !(self.range_noise_per_m >= 0.0 && self.range_noise_per_m.is_finite()) {
            return bad("range_noise_per_m", "must be finite and ≥ 0");
        }
        if !(self.dropout_burst_beams >= 1.0 && self.dropout_burst_beams.is_finite()) {
            return bad("dropout_burst_beams", "must be finite and ≥ 1");
        }
        if !(0.0..=1.0).contains(&self.dark_dropout) {
            return bad("dark_dropout", "must be in [0, 1]");
        }
        if !(self.grazing_limit_rad > 0.0 && self.grazing_limit_rad <= right_angle_rad()) {
            return bad("grazing_limit_rad", "must be in (0, π/2]");
        }
        Ok(())
    }

    /// Whether the beams go all round (the last one is not repeated by a first at +180°).
    fn all_round(&self) -> bool {
        self.fov_rad >= 2.0 * PI
    }

    /// Angle of the first beam: −180° all round, else −fov / 2. rad.
    pub fn angle_min_rad(&self) -> f64 {
        if self.all_round() { -PI } else { -0.5 * self.fov_rad }
    }

    /// Angle between beams. rad.
    pub fn angle_increment_rad(&self) -> f64 {
        if self.all_round() { 2.0 * PI / self.beams as f64 } else { self.fov_rad / (self.beams - 1) as f64 }
    }

    /// Time between beams when sweeping (the mirror turns once per scan period: the period times the
    /// beams' spacing over a full turn; the period over the beams all round), else 0. s.
    pub fn time_increment_s(&self) -> f64 {
        if self.sweeping { self.angle_increment_rad() / (2.0 * PI * self.rate_hz) } else { 0.0 }
    }

    /// Whether a beam needs more than the ideal scanner's two draws (noise, dropout).
    fn realistic(&self) -> bool {
        self.dropout_burst_beams > 1.0
            || self.dark_dropout > 0.0
            || self.grazing_limit_rad < right_angle_rad()
            || self.mixed_pixels
    }

    /// What a beam that returned nothing reads: `dropped` (a dropout) or beyond the range.
    fn no_return_value(&self, dropped: bool) -> f32 {
        match self.no_return {
            NoReturn::Infinity if dropped => f32::NAN,
            NoReturn::Infinity => f32::INFINITY,
            NoReturn::Zero => 0.0,
            NoReturn::MaxRange => self.range_max_m as f32,
        }
    }
}

/// One scan at `t_s` from a sensor at `room_from_sensor` in `room`: each beam's exact range plus Gaussian
/// noise (`range_noise_m`), a dropout (NaN) with probability `dropout`, +inf beyond `range_max_m` (see the
/// module docs for the realistic settings). Draws two numbers per beam from `rng` (four with the realistic
/// settings), whatever happens to the beam, so streams stay aligned.
pub fn simulate_scan(
    room: &Room,
    room_from_sensor: &Pose2,
    t_s: f64,
    settings: &ScanSettings,
    rng: &mut ChaCha8Rng,
) -> Scan {
    simulate_sweep(room, |_| *room_from_sensor, t_s, 0.0, settings, rng)
}

/// The random draws of one beam.
struct Draws {
    /// Standard normal: the range noise.
    noise: f64,
    /// Uniform: a dark surface's dropout.
    dark: f64,
    /// Uniform: where a mixed pixel lies between its surfaces.
    mix: f64,
}

/// [`simulate_scan`] for beams measured one after another: beam `i` from the sensor pose
/// `room_from_sensor_at(i · time_increment_s)` (s after `t_s`).
pub fn simulate_sweep(
    room: &Room,
    room_from_sensor_at: impl Fn(f64) -> Pose2,
    t_s: f64,
    time_increment_s: f64,
    settings: &ScanSettings,
    rng: &mut ChaCha8Rng,
) -> Scan {
    let angle_min_rad = settings.angle_min_rad();
    let inc = settings.angle_increment_rad();
    let realistic = settings.realistic();
    // A burst of dropouts ends at each beam with probability `exit`, and starts with `enter` (so that the
    // share of dropped beams is `dropout`).
    let exit = 1.0 / settings.dropout_burst_beams;
    let enter = settings.dropout * exit / (1.0 - settings.dropout);
    let mut in_burst = false;
    let ranges_m = (0..settings.beams)
        .map(|i| {
            let noise: f64 = StandardNormal.sample(rng);
            let dropout = rng.random_range(0.0..1.0);
            let (dark, mix) =
                if realistic { (rng.random_range(0.0..1.0), rng.random_range(0.0..1.0)) } else { (1.0, 0.0) };
            let draws = Draws { noise, dark, mix };
            in_burst = if settings.dropout_burst_beams <= 1.0 {
                dropout < settings.dropout
            } else if in_burst {
                dropout >= exit
            } else {
                dropout < enter
            };
            let sensor = room_from_sensor_at(i as f64 * time_increment_s);
            let beam_rad = sensor.theta_rad + angle_min_rad + i as f64 * inc;
            beam_range(room, [sensor.x_m, sensor.y_m], beam_rad, in_burst, &draws, settings)
        })
        .collect();
    Scan {
        t_s,
        time_increment_s,
        angle_min_rad,
        angle_increment_rad: inc,
        range_min_m: settings.range_min_m,
        range_max_m: settings.range_max_m,
        ranges_m,
    }
}

/// One beam's reading from `origin` along `beam_rad` (room frame), `dropped` or not, with its draws.
fn beam_range(room: &Room, origin: [f64; 2], beam_rad: f64, dropped: bool, d: &Draws, s: &ScanSettings) -> f32 {
    if dropped {
        return s.no_return_value(true);
    }
    let Some(hit) = room.ray_hit(origin, beam_rad) else { return s.no_return_value(false) };
    if hit.cos_incidence < s.grazing_limit_rad.cos() || is_dark(hit.segment) && d.dark < s.dark_dropout {
        return s.no_return_value(true);
    }
    let mut exact = hit.range_m;
    if s.mixed_pixels {
        // The footprint's two edges: a jump between them mixes the surfaces.
        let half = 0.5 * s.angle_increment_rad();
        let edges = [room.ray_range(origin, beam_rad - half), room.ray_range(origin, beam_rad + half)];
        if let [Some(a), Some(b)] = edges
            && (a - b).abs() > MIXED_JUMP_M
        {
            exact = a.min(b) + d.mix * (a - b).abs();
        }
    }
    let r = exact + (s.range_noise_m + s.range_noise_per_m * exact) * d.noise;
    if r < s.range_max_m { r.max(0.0) as f32 } else { s.no_return_value(false) }
}

/// Salt mixed into the simulator's seed for the lidar's draws, so that adding a lidar leaves every other
/// draw of a simulated dataset as it was.
const LIDAR_SEED_SALT: u64 = 0x6c69_6461_7220_3238;

/// The scans of a sensor at `base_from_sensor` on a robot whose true base poses (`room_from_base`, the
/// run starting at the room's origin) are `base`, one scan per pose at its time: random stream `stream` of
/// `seed` (the run's own, as the simulator's), so the same seed gives the same scans whatever the thread
/// count.
pub fn simulate_scans(
    room: &Room,
    base: &[StampedPose],
    base_from_sensor: &Pose2,
    settings: &ScanSettings,
    seed: u64,
    stream: u64,
) -> Vec<Scan> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ LIDAR_SEED_SALT);
    rng.set_stream(stream);
    let tau = settings.time_increment_s();
    (0..base.len())
        .map(|k| {
            // While sweeping, the base between this scan's pose and the next's (linear; the last extrapolates).
            let (a, b) = if k + 1 < base.len() { (base[k], base[k + 1]) } else { (base[k.max(1) - 1], base[k]) };
            let dt = b.t_s - a.t_s;
            let at = |offset_s: f64| {
                if offset_s == 0.0 {
                    return base[k].pose.compose(base_from_sensor);
                }
                let f = if dt > 0.0 { (base[k].t_s + offset_s - a.t_s) / dt } else { 0.0 };
                let lerp = |x: f64, y: f64| x + f * (y - x);
                let (p, q) = (a.pose, b.pose);
                // The heading the short way round (poses may be wrapped to (−π, π]).
                let theta = p.theta_rad + f * crate::pose::wrap_angle(q.theta_rad - p.theta_rad);
                Pose2::new(lerp(p.x_m, q.x_m), lerp(p.y_m, q.y_m), theta).compose(base_from_sensor)
            };
            simulate_sweep(room, at, base[k].t_s, tau, settings, &mut rng)
        })
        .collect()
}

#[cfg(test)]
mod tests;
