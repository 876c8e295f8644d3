//! A room of polygons for the simulated lidar, and the ray casting that measures it.
//!
//! The first polygon is the outer wall (the robot stays inside it); every later one is an obstacle (a box,
//! a pillar: the robot stays outside it). Each polygon is closed (its last vertex joins its first), in
//! metres in the room frame. The robot starts every simulated run at the room's origin, heading +x.
//!
//! A beam's range is the distance to the nearest wall segment it crosses (exact, in float64, before the
//! simulated noise); a beam that crosses nothing within the maximum range is no return (+inf).

use super::Scan;
use crate::error::{KinError, Settings};
use crate::pose::{Pose2, StampedPose};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Distance the robot keeps from every wall and obstacle (its footprint's radius, about). m.
pub const CLEARANCE_M: f64 = 0.25;

/// A room: polygons in metres, the first the outer wall, the others obstacles.
#[derive(Clone, Debug, PartialEq)]
pub struct Room {
    /// The polygons' vertices (x, y). m.
    polygons: Vec<Vec<[f64; 2]>>,
    /// Every wall segment (from, to). m.
    segments: Vec<([f64; 2], [f64; 2])>,
}

/// An axis-aligned rectangle's corners, counter-clockwise. m.
fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<[f64; 2]> {
    vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
}

/// The built-in rooms' names, for help and errors.
pub const BUILTIN_ROOMS: [&str; 2] = ["room", "corridor"];

impl Room {
    /// A room from its polygons (the first the outer wall); each needs three vertices or more, all finite.
    pub fn new(polygons: Vec<Vec<[f64; 2]>>) -> Result<Self, KinError> {
        let bad = |what: String, why: &str| KinError::Invalid { what, why: why.into() };
        if polygons.is_empty() {
            return Err(bad("room".into(), "needs at least one polygon (the outer wall)"));
        }
        for (k, p) in polygons.iter().enumerate() {
            if p.len() < 3 {
                return Err(bad(format!("room polygon {k}"), "needs at least 3 vertices"));
            }
            if p.iter().flatten().any(|v| !v.is_finite()) {
                return Err(bad(format!("room polygon {k}"), "has a vertex that is not finite"));
            }
        }
        let segments = polygons.iter().flat_map(|p| (0..p.len()).map(|i| (p[i], p[(i + 1) % p.len()]))).collect();
        Ok(Self { polygons, segments })
    }

    /// A built-in room by name: `room`, a 10 × 8 m rectangle around the origin with five boxes and pillars
    /// near its walls (scan matching is constrained in every direction); `corridor`, a hallway 40 m long
    /// (x) and 5 m wide (y) around the origin, whose ends lie beyond the lidar's range (a scan does not
    /// constrain motion along it). `None` for another name.
    pub fn builtin(name: &str) -> Option<Self> {
        let polygons = match name {
            "room" => vec![
                rect(-5.0, -4.0, 5.0, 4.0),
                rect(3.0, 2.0, 4.0, 3.0),
                rect(-3.4, 2.4, -3.0, 2.8),
                rect(-4.2, -3.2, -3.0, -2.4),
                rect(2.6, -2.2, 3.0, -1.8),
                rect(-0.2, 3.0, 0.2, 3.4),
            ],
            "corridor" => vec![rect(-20.0, -2.5, 20.0, 2.5)],
            _ => return None,
        };
        Self::new(polygons).ok()
    }

    /// The polygons (x, y), m.
    pub fn polygons(&self) -> &[Vec<[f64; 2]>] {
        &self.polygons
    }

    /// The range along the ray from `origin` (m) in direction `angle_rad` (room frame) to the nearest wall
    /// segment, `None` when it meets none. m.
    pub fn ray_range(&self, origin: [f64; 2], angle_rad: f64) -> Option<f64> {
        let (dy, dx) = angle_rad.sin_cos();
        let mut best: Option<f64> = None;
        for &(a, b) in &self.segments {
            let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
            // origin + t d = a + u e: solve by Cramer's rule.
            let den = dx * ey - dy * ex;
            if den.abs() < 1e-15 {
                continue;
            }
            let (wx, wy) = (a[0] - origin[0], a[1] - origin[1]);
            let t = (wx * ey - wy * ex) / den;
            let u = (wx * dy - wy * dx) / den;
            if t > 0.0 && (0.0..=1.0).contains(&u) && best.is_none_or(|b| t < b) {
                best = Some(t);
            }
        }
        best
    }

    /// Whether `p` (m) lies inside the outer wall, outside every obstacle, and at least `clearance_m` from
    /// every wall segment.
    pub fn is_free(&self, p: [f64; 2], clearance_m: f64) -> bool {
        let inside_outer = contains(&self.polygons[0], p);
        let in_obstacle = self.polygons[1..].iter().any(|poly| contains(poly, p));
        inside_outer && !in_obstacle && self.segments.iter().all(|&(a, b)| segment_distance(p, a, b) >= clearance_m)
    }
}

/// Whether `p` lies inside the closed polygon `poly` (even–odd rule).
fn contains(poly: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut inside = false;
    let mut j = poly.len() - 1;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[j]);
        if (a[1] > p[1]) != (b[1] > p[1]) && p[0] < a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]) {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// Distance from `p` to the segment `a`–`b`. m.
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
    let len2 = ex * ex + ey * ey;
    let u = if len2 > 0.0 { (((p[0] - a[0]) * ex + (p[1] - a[1]) * ey) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (p[0] - a[0] - u * ex).hypot(p[1] - a[1] - u * ey)
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
        }
    }
}

impl ScanSettings {
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

    /// Time between beams: the scan period over the beams when sweeping, else 0. s.
    pub fn time_increment_s(&self) -> f64 {
        if self.sweeping { 1.0 / (self.rate_hz * self.beams as f64) } else { 0.0 }
    }
}

/// One scan at `t_s` from a sensor at `room_from_sensor` in `room`: each beam's exact range plus Gaussian
/// noise (`range_noise_m`), a dropout (NaN) with probability `dropout`, +inf beyond `range_max_m`. Draws
/// two numbers per beam from `rng`, whatever happens to the beam, so streams stay aligned.
pub fn simulate_scan(
    room: &Room,
    room_from_sensor: &Pose2,
    t_s: f64,
    settings: &ScanSettings,
    rng: &mut ChaCha8Rng,
) -> Scan {
    simulate_sweep(room, |_| *room_from_sensor, t_s, 0.0, settings, rng)
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
    let ranges_m = (0..settings.beams)
        .map(|i| {
            let beam = angle_min_rad + i as f64 * inc;
            let noise: f64 = StandardNormal.sample(rng);
            let dropped = rng.random_range(0.0..1.0) < settings.dropout;
            let sensor = room_from_sensor_at(i as f64 * time_increment_s);
            let exact = room.ray_range([sensor.x_m, sensor.y_m], sensor.theta_rad + beam);
            match exact.map(|r| r + settings.range_noise_m * noise) {
                _ if dropped => f32::NAN,
                Some(r) if r < settings.range_max_m => r.max(0.0) as f32,
                _ => f32::INFINITY,
            }
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

/// The first base pose (room frame) closer than `clearance_m` to a wall or obstacle, or outside the room.
pub fn first_collision(room: &Room, base: &[StampedPose], clearance_m: f64) -> Option<StampedPose> {
    base.iter().find(|b| !room.is_free([b.pose.x_m, b.pose.y_m], clearance_m)).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 270° lidar of 1081 beams (a Hokuyo UTM-30LX) spans −135° to +135° inclusive, 0.25° apart, and
    /// sees nothing behind it; 360° keeps the all-round layout (−180°, 0.5° apart for 720 beams).
    #[test]
    fn a_partial_field_of_view_spans_it_inclusive_and_sees_nothing_behind() {
        let s = ScanSettings { beams: 1081, fov_rad: 270f64.to_radians(), dropout: 0.0, ..ScanSettings::default() };
        s.check().unwrap();
        assert!((s.angle_min_rad().to_degrees() + 135.0).abs() < 1e-12);
        assert!((s.angle_increment_rad().to_degrees() - 0.25).abs() < 1e-12);
        let all = ScanSettings::default();
        assert_eq!((all.angle_min_rad(), all.angle_increment_rad()), (-PI, 2.0 * PI / 720.0));
        let room = Room::builtin("room").unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let scan = simulate_scan(&room, &Pose2::IDENTITY, 0.0, &s, &mut rng);
        let p = scan.points();
        assert!(p.xy_m.len() > 1000 && p.xy_m.iter().all(|q| q[1].atan2(q[0]).abs() < 2.357), "{}", p.xy_m.len());
        for fov_deg in [0.0, 361.0, f64::NAN] {
            assert!(ScanSettings { fov_rad: fov_deg.to_radians(), ..all.clone() }.check().is_err(), "{fov_deg}");
        }
    }

    #[test]
    fn ray_casting_gives_exact_ranges_in_the_room() {
        let room = Room::builtin("room").unwrap();
        // From the origin: +x meets the wall at 5 m, −x at 5 m, −y at 4 m; +y meets the pillar at y = 3.
        assert_eq!(room.ray_range([0.0, 0.0], 0.0), Some(5.0));
        assert_eq!(room.ray_range([0.0, 0.0], PI), Some(5.0));
        assert!((room.ray_range([0.0, 0.0], -0.5 * PI).unwrap() - 4.0).abs() < 1e-12);
        assert!((room.ray_range([0.0, 0.0], 0.5 * PI).unwrap() - 3.0).abs() < 1e-12);
        // Towards the corner (5, 4) of the free wall: the diagonal's length, past nothing.
        let to_corner = room.ray_range([1.0, 0.0], (4.0f64).atan2(2.0)).unwrap();
        assert!((to_corner - 20f64.sqrt()).abs() < 1e-12, "{to_corner}");
        // The box x 3..4, y 2..3 from (1, 2.5) along +x: its face at x = 3.
        assert!((room.ray_range([1.0, 2.5], 0.0).unwrap() - 2.0).abs() < 1e-12);
    }

    #[test]
    fn noise_free_scan_matches_the_ray_cast_and_the_max_range() {
        let room = Room::builtin("corridor").unwrap();
        let settings = ScanSettings { range_noise_m: 0.0, dropout: 0.0, ..ScanSettings::default() };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let scan = simulate_scan(&room, &Pose2::new(0.0, 0.5, 0.0), 0.0, &settings, &mut rng);
        // Beam 360 looks along +x: the far end is 20 m away, beyond 12 m: no return.
        assert_eq!(scan.ranges_m[360], f32::INFINITY);
        // Beam 540 looks along +y (90°): the wall at y = 2.5, 2 m away; beam 180 along −y: 3 m.
        assert!((f64::from(scan.ranges_m[540]) - 2.0).abs() < 1e-6);
        assert!((f64::from(scan.ranges_m[180]) - 3.0).abs() < 1e-6);
    }

    #[test]
    fn free_space_keeps_the_clearance() {
        let room = Room::builtin("room").unwrap();
        assert!(room.is_free([0.0, 0.0], CLEARANCE_M));
        assert!(!room.is_free([4.9, 0.0], CLEARANCE_M));
        assert!(!room.is_free([3.5, 2.5], CLEARANCE_M)); // inside the box
        assert!(!room.is_free([6.0, 0.0], 0.0)); // outside the walls
    }

    #[test]
    fn same_seed_same_scan_and_noise_has_its_sigma() {
        let room = Room::builtin("room").unwrap();
        let s = ScanSettings::default();
        let pose = Pose2::new(0.3, -0.2, 0.4);
        let a = simulate_scan(&room, &pose, 0.0, &s, &mut ChaCha8Rng::seed_from_u64(9));
        let b = simulate_scan(&room, &pose, 0.0, &s, &mut ChaCha8Rng::seed_from_u64(9));
        assert_eq!(format!("{:?}", a.ranges_m), format!("{:?}", b.ranges_m));
        let exact = simulate_scan(
            &room,
            &pose,
            0.0,
            &ScanSettings { range_noise_m: 0.0, dropout: 0.0, ..s.clone() },
            &mut ChaCha8Rng::seed_from_u64(9),
        );
        let d: Vec<f64> = a
            .ranges_m
            .iter()
            .zip(&exact.ranges_m)
            .filter(|(r, _)| r.is_finite())
            .map(|(r, e)| f64::from(*r) - f64::from(*e))
            .collect();
        let sigma = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
        assert!((sigma - 0.01).abs() < 0.001, "sigma {sigma}");
        let dropped = a.ranges_m.iter().filter(|r| r.is_nan()).count();
        assert!((1..=20).contains(&dropped), "{dropped} dropouts of 720");
    }
}
