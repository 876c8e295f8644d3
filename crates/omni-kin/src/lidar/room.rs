//! A room of polygons for the simulated lidar, and the ray casting that measures it.
//!
//! The first polygon is the outer wall (the robot stays inside it); every later one is an obstacle (a box,
//! a pillar: the robot stays outside it). Each polygon is closed (its last vertex joins its first), in
//! metres in the room frame. The robot starts every simulated run at the room's origin, heading +x.
//!
//! A beam's range is the distance to the nearest wall segment it crosses (exact, in float64, before the
//! simulated noise); a beam that crosses nothing within the maximum range is no return (+inf).

use crate::error::KinError;
use crate::pose::StampedPose;

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

/// Where a ray meets a wall ([`Room::ray_hit`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Distance along the ray. m.
    pub range_m: f64,
    /// The wall segment met: polygon after polygon, vertex `i` to vertex `i + 1` of each.
    pub segment: usize,
    /// Cosine of the angle of incidence (between the ray and the wall's normal): 1 head-on, 0 grazing.
    pub cos_incidence: f64,
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
        self.ray_hit(origin, angle_rad).map(|h| h.range_m)
    }

    /// Where the ray from `origin` (m) in direction `angle_rad` (room frame) first meets a wall segment:
    /// its range, the segment's index (polygon after polygon, vertex after vertex) and how squarely it
    /// meets it; `None` when it meets none.
    pub fn ray_hit(&self, origin: [f64; 2], angle_rad: f64) -> Option<RayHit> {
        let (dy, dx) = angle_rad.sin_cos();
        let mut best: Option<RayHit> = None;
        for (k, &(a, b)) in self.segments.iter().enumerate() {
            let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
            // origin + t d = a + u e: solve by Cramer's rule.
            let den = dx * ey - dy * ex;
            if den.abs() < 1e-15 {
                continue;
            }
            let (wx, wy) = (a[0] - origin[0], a[1] - origin[1]);
            let t = (wx * ey - wy * ex) / den;
            let u = (wx * dy - wy * dx) / den;
            if t > 0.0 && (0.0..=1.0).contains(&u) && best.is_none_or(|b| t < b.range_m) {
                // |d × e| / |e|: the cosine of the angle between the ray and the segment's normal.
                let cos_incidence = den.abs() / ex.hypot(ey);
                best = Some(RayHit { range_m: t, segment: k, cos_incidence });
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

/// The first base pose (room frame) closer than `clearance_m` to a wall or obstacle, or outside the room.
pub fn first_collision(room: &Room, base: &[StampedPose], clearance_m: f64) -> Option<StampedPose> {
    base.iter().find(|b| !room.is_free([b.pose.x_m, b.pose.y_m], clearance_m)).copied()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

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
        // Head-on the right wall (segment 1: (5, −4) to (5, 4)); at −60° the bottom wall (segment 0), 30°
        // from its normal.
        let hit = room.ray_hit([0.0, 0.0], 0.0).unwrap();
        assert_eq!((hit.segment, hit.cos_incidence), (1, 1.0));
        let oblique = room.ray_hit([0.0, 0.0], (-60f64).to_radians()).unwrap();
        assert_eq!(oblique.segment, 0);
        assert!((oblique.cos_incidence - 0.75f64.sqrt()).abs() < 1e-12, "{oblique:?}");
    }

    #[test]
    fn free_space_keeps_the_clearance() {
        let room = Room::builtin("room").unwrap();
        assert!(room.is_free([0.0, 0.0], CLEARANCE_M));
        assert!(!room.is_free([4.9, 0.0], CLEARANCE_M));
        assert!(!room.is_free([3.5, 2.5], CLEARANCE_M)); // inside the box
        assert!(!room.is_free([6.0, 0.0], 0.0)); // outside the walls
    }
}
