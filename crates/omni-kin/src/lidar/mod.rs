//! A planar (2D) lidar: scans as `sensor_msgs/LaserScan` carries them, simulated by ray casting in a room
//! of polygons ([`room`]), and matched scan to scan ([`icp`]) into the sensor's own path ([`path`]) — a
//! relative reference for calibration when no motion-capture system is at hand (issue 28).
//!
//! Frames: a scan's points are in the sensor frame (`laser`: x along the beam at angle 0, y left, REP-103);
//! the sensor sits at `base_from_sensor` on the robot (the `/tf_static` base_link → laser). Units: m, rad,
//! s. No I/O: recordings are read by `omni_cli::lidar`.

pub mod icp;
pub mod path;
pub mod room;
pub mod scanner;

#[cfg(test)]
mod real_lidars;

use crate::pose::Pose2;
pub use icp::{MatchQuality, MatchSettings, Rejection, ScanMatch, match_points, match_scans};
pub use path::{SensorPath, sensor_path};
pub use room::{CLEARANCE_M, RayHit, Room, first_collision};
pub use scanner::{LidarModel, NoReturn, ScanSettings, simulate_scan, simulate_scans, simulate_sweep};

/// One scan, as `sensor_msgs/msg/LaserScan` carries it: beam `i` points at `angle_min_rad + i ·
/// angle_increment_rad` in the sensor frame and measured `ranges_m[i]`. A range that is not finite or lies
/// outside [`range_min_m`, `range_max_m`) is no return (REP-117: +inf nothing in range, NaN an erroneous
/// reading). Beam `i` is measured `i · time_increment_s` after `t_s` (REP-117 / LaserScan: the stamp is
/// the first beam's time); 0 is a scan taken at one instant. A robot that moves during the sweep bends the
/// scan; [`path::sensor_path`] undoes that ([`ScanPoints::deskewed`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Scan {
    /// When the first beam was measured (`header.stamp`). s (since the reader's origin).
    pub t_s: f64,
    /// Time between beams (`time_increment`); 0: every beam at `t_s`. s.
    pub time_increment_s: f64,
    /// Angle of the first beam. rad.
    pub angle_min_rad: f64,
    /// Angle between beams (counter-clockwise when positive). rad.
    pub angle_increment_rad: f64,
    /// Shortest valid range. m.
    pub range_min_m: f64,
    /// Longest valid range (a range at or beyond it is no return). m.
    pub range_max_m: f64,
    /// One range per beam. m. Single precision, as the message carries them.
    pub ranges_m: Vec<f32>,
}

impl Scan {
    /// Whether beam `i`'s range is a return: finite, in [`range_min_m`, `range_max_m`) and not 0. A range of
    /// exactly 0 is many drivers' "no return" (Hokuyo's urg_node, SICK's, RPLIDAR's with `range_min` 0), never
    /// a point at the sensor.
    ///
    /// [`range_min_m`]: Self::range_min_m
    /// [`range_max_m`]: Self::range_max_m
    pub fn is_return(&self, i: usize) -> bool {
        let r = f64::from(self.ranges_m[i]);
        r.is_finite() && r > 0.0 && r >= self.range_min_m && r < self.range_max_m
    }

    /// The returns as points in the sensor frame (m), in beam order, with their beam indices.
    pub fn points(&self) -> ScanPoints {
        let mut out = ScanPoints { xy_m: Vec::with_capacity(self.ranges_m.len()), beam: Vec::new() };
        out.beam.reserve(self.ranges_m.len());
        for (i, &r) in self.ranges_m.iter().enumerate() {
            if self.is_return(i) {
                let a = self.angle_min_rad + i as f64 * self.angle_increment_rad;
                let (s, c) = a.sin_cos();
                let r = f64::from(r);
                out.xy_m.push([r * c, r * s]);
                out.beam.push(i);
            }
        }
        out
    }
}

/// A scan's returns as points in the sensor frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ScanPoints {
    /// Point `k` (x, y). m.
    pub xy_m: Vec<[f64; 2]>,
    /// The beam index of point `k` (increasing).
    pub beam: Vec<usize>,
}

/// Neighbours whose ranges differ by less than this are never an edge ([`ScanPoints::without_edges`]):
/// range noise alone. m.
pub const EDGE_JUMP_M: f64 = 0.05;

impl ScanPoints {
    /// The points without those at depth jumps: point `k` is dropped when a neighbour (the return before or
    /// after it, at most two beams away) lies more than [`EDGE_JUMP_M`] nearer or farther and the line to it
    /// runs within `min_angle_rad` of `k`'s beam. That line is a surface seen edge-on: a **mixed pixel**
    /// (a beam whose footprint straddled a foreground and a background reads a range between them, a point
    /// in mid-air), the edges it joins, and walls at grazing incidence, whose ranges real lidars read
    /// poorly. None of them lies where the next scan sees it again. `min_angle_rad` 0 keeps every point.
    pub fn without_edges(&self, min_angle_rad: f64) -> Self {
        if min_angle_rad <= 0.0 {
            return self.clone();
        }
        let sin_min = min_angle_rad.sin();
        // Whether the line from point k to point j runs within the angle of k's beam.
        let edge_on = |k: usize, j: usize| {
            let (p, q) = (self.xy_m[k], self.xy_m[j]);
            let r = p[0].hypot(p[1]);
            let v = [q[0] - p[0], q[1] - p[1]];
            let across = (p[0] * v[1] - p[1] * v[0]).abs() / r;
            self.beam[k].abs_diff(self.beam[j]) <= 2
                && (q[0].hypot(q[1]) - r).abs() > EDGE_JUMP_M
                && across < sin_min * v[0].hypot(v[1])
        };
        let n = self.xy_m.len();
        let keep: Vec<usize> =
            (0..n).filter(|&k| !(k > 0 && edge_on(k, k - 1) || k + 1 < n && edge_on(k, k + 1))).collect();
        Self { xy_m: keep.iter().map(|&k| self.xy_m[k]).collect(), beam: keep.iter().map(|&k| self.beam[k]).collect() }
    }

    /// The points as the sensor would have seen them all at the scan's stamp, for a sensor moving at the
    /// constant body twist `per_s` (vx, vy m/s and ω rad/s as a [`Pose2`] per second) while beam `i` is
    /// measured `i · time_increment_s` after it: each point is moved by the sensor's motion from the stamp
    /// to its beam's time (first order in the sweep's duration, a tenth of a second).
    pub fn deskewed(&self, time_increment_s: f64, per_s: Pose2) -> Self {
        let xy_m = self
            .xy_m
            .iter()
            .zip(&self.beam)
            .map(|(p, &i)| {
                let tau = i as f64 * time_increment_s;
                let (s, c) = (per_s.theta_rad * tau).sin_cos();
                [c * p[0] - s * p[1] + per_s.x_m * tau, s * p[0] + c * p[1] + per_s.y_m * tau]
            })
            .collect();
        Self { xy_m, beam: self.beam.clone() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_skip_every_kind_of_no_return() {
        let scan = Scan {
            t_s: 0.0,
            time_increment_s: 0.0,
            angle_min_rad: 0.0,
            angle_increment_rad: std::f64::consts::FRAC_PI_2,
            range_min_m: 0.1,
            range_max_m: 10.0,
            ranges_m: vec![2.0, f32::INFINITY, f32::NAN, 0.05, 10.0, 3.0],
        };
        let p = scan.points();
        assert_eq!(p.beam, vec![0, 5]);
        assert_eq!(p.xy_m[0], [2.0, 0.0]);
        // Beam 5 at 5 · 90° = 450° ≡ 90°.
        assert!((p.xy_m[1][0]).abs() < 1e-12 && (p.xy_m[1][1] - 3.0).abs() < 1e-12);
        // With range_min 0 (as many drivers declare it), a range of 0 is still no return; a small one is one.
        let zero_min = Scan { range_min_m: 0.0, ranges_m: vec![0.0, 0.02, -0.0, 1.0], ..scan };
        assert_eq!(zero_min.points().beam, vec![1, 3]);
    }

    /// A wall at 2 m ends at beam 4; beam 5 is a mixed pixel at 2.9 m, half-way to the background at 4 m
    /// behind it (beams 6 on). The mixed pixel and the two points it joins are dropped; the points on
    /// either surface stay. A wall seen head-on keeps every point.
    #[test]
    fn a_mixed_pixel_and_the_edge_it_joins_are_dropped() {
        let scan = Scan {
            t_s: 0.0,
            time_increment_s: 0.0,
            angle_min_rad: 0.0,
            angle_increment_rad: 0.5f64.to_radians(),
            range_min_m: 0.02,
            range_max_m: 10.0,
            ranges_m: vec![2.0, 2.0, 2.0, 2.0, 2.0, 2.9, 4.0, 4.0, 4.0, 4.0],
        };
        let kept = scan.points().without_edges(10f64.to_radians());
        assert_eq!(kept.beam, vec![0, 1, 2, 3, 7, 8, 9]);
        assert_eq!(scan.points().without_edges(0.0).beam.len(), 10);
        // A wall 1 m ahead across the beams (x = 1): no edge, however close the points.
        let wall = Scan {
            angle_min_rad: -0.3,
            ranges_m: (0..10).map(|i| (1.0 / (-0.3 + i as f64 * 0.5f64.to_radians()).cos()) as f32).collect(),
            ..scan
        };
        assert_eq!(wall.points().without_edges(10f64.to_radians()).beam.len(), 10);
    }

    /// A 270° scan as a Hokuyo UTM-30LX's driver writes it, clockwise (negative `angle_increment`, from
    /// +135° to −135°): the points lie where the beams point.
    #[test]
    fn a_partial_clockwise_scan_puts_its_points_where_the_beams_point() {
        let beams = 1081;
        let inc = -(270f64.to_radians()) / (beams - 1) as f64;
        let scan = Scan {
            t_s: 0.0,
            time_increment_s: 0.0,
            angle_min_rad: 135f64.to_radians(),
            angle_increment_rad: inc,
            range_min_m: 0.0,
            range_max_m: 30.0,
            ranges_m: vec![2.0; beams],
        };
        let p = scan.points();
        assert_eq!(p.xy_m.len(), beams);
        let at = |k: usize| p.xy_m[k][1].atan2(p.xy_m[k][0]).to_degrees();
        assert!((at(0) - 135.0).abs() < 1e-9 && (at(540)).abs() < 1e-9 && (at(1080) + 135.0).abs() < 1e-9);
    }
}
