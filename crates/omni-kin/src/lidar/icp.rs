//! Scan-to-scan matching: point-to-line ICP (Censi, "An ICP variant using a point-to-line metric", ICRA
//! 2008), solved by Gauss–Newton on the point-to-line residuals.
//!
//! The reference scan's returns become lines: each point with the neighbours of its beam window that lie
//! within `line_radius_m` gets a least-squares line (centroid `c`, normal `n`), kept when its points lie
//! within `line_rms_max_m` of it (corners and lone points are left out). The current scan's points `p`,
//! moved by the estimate `T = (t, θ)` of the current sensor pose in the reference sensor frame, are paired
//! with the line of their nearest reference point (a `kiddo` k-d tree; pairs farther than
//! `max_correspondence_m` are dropped), giving residuals `e = n · (R(θ) p + t − c)`. Each iteration weighs
//! the residuals robustly — those beyond `trim_sigmas` robust standard deviations (1.4826 × the median
//! absolute residual, at least `sigma_floor_m`) are trimmed — and takes the Gauss–Newton step
//! `H δ = −g`, `H = Σ J Jᵀ`, `J = [n_x, n_y, n · R'(θ) p]`, until the step is below 10 µm and 10 µrad (or the estimates cycle, pairs flipping between lines: then the cycle's mean).
//!
//! Quality of a match ([`MatchQuality`]): the inliers' residual RMS, the inlier share of the current
//! scan's returns, and the condition number of the normal matrix `H` with the angle measured in metres at
//! the inliers' RMS range (so translation and rotation weigh alike). A match is rejected ([`Rejection`])
//! with too few inliers, a poor inlier share (little overlap, or a scene that changed), an ill-conditioned
//! `H` (a corridor: nothing constrains motion along it), a large residual, or no convergence.

use super::{Scan, ScanPoints};
use crate::pose::Pose2;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use serde::{Deserialize, Serialize};

/// How scans are matched and when a match is trusted. Defaults suit a 360° indoor lidar at 10 Hz.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MatchSettings {
    /// Gauss–Newton iterations at most. Default 30.
    pub max_iterations: usize,
    /// Points on a line within this angle of their beam are dropped before matching (mixed pixels at depth
    /// jumps, the edges they join, grazing walls: [`super::ScanPoints::without_edges`]); 0 keeps them. rad.
    /// Default 0.17 (10°).
    #[serde(default = "edge_angle_rad")]
    pub edge_angle_rad: f64,
    /// A current point farther than this from its nearest reference point is not paired. m. Default 0.3.
    pub max_correspondence_m: f64,
    /// Beams either side of a reference point that may join its line (a real lidar's empty beams and its
    /// noise, growing with range, need the longer lines). Default 8.
    pub line_window: usize,
    /// Neighbours farther than this from the point do not join its line. m. Default 0.5.
    pub line_radius_m: f64,
    /// A line whose points lie farther than this (RMS) from it is not used (a corner). m. Default 0.03.
    pub line_rms_max_m: f64,
    /// Residuals beyond this many robust standard deviations are trimmed. Default 3.
    pub trim_sigmas: f64,
    /// The robust standard deviation is at least this (the range noise of a good lidar). m. Default 0.005.
    pub sigma_floor_m: f64,

    /// Fewer inlier pairs than this reject the match. Default 60.
    pub min_inliers: usize,
    /// A smaller inlier share of the current scan's returns rejects the match. Default 0.5.
    pub min_inlier_share: f64,
    /// A larger condition number of the (scaled) normal matrix rejects the match. Default 100.
    pub max_condition: f64,
    /// A larger inlier residual RMS rejects the match. m. Default 0.05.
    pub max_rms_m: f64,
    /// A scan this far from the keyframe (by the scan-to-scan chain) becomes the next keyframe
    /// ([`super::path`]). m. Default 0.3.
    pub keyframe_distance_m: f64,
    /// A scan turned this much from the keyframe becomes the next keyframe. rad. Default 0.26 (15°).
    pub keyframe_angle_rad: f64,
    /// A rejected interval is skipped (the next scan is matched against the last accepted one) until the
    /// last accepted scan is this old; then the path's segment ends. s. Default 1.
    pub max_gap_s: f64,
}

/// 10°: the default [`MatchSettings::edge_angle_rad`].
fn edge_angle_rad() -> f64 {
    10f64.to_radians()
}

impl Default for MatchSettings {
    fn default() -> Self {
        Self {
            max_iterations: 30,
            edge_angle_rad: edge_angle_rad(),
            max_correspondence_m: 0.3,
            line_window: 8,
            line_radius_m: 0.5,
            line_rms_max_m: 0.03,
            trim_sigmas: 3.0,
            sigma_floor_m: 0.005,
            min_inliers: 60,
            min_inlier_share: 0.5,
            max_condition: 100.0,
            max_rms_m: 0.05,
            keyframe_distance_m: 0.3,
            keyframe_angle_rad: 0.26,
            max_gap_s: 1.0,
        }
    }
}

/// How well a match fits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MatchQuality {
    /// RMS of the inliers' point-to-line residuals. m.
    pub rms_m: f64,
    /// Inlier pairs.
    pub inliers: usize,
    /// Inliers over the current scan's returns.
    pub inlier_share: f64,
    /// Condition number (largest over smallest eigenvalue) of the normal matrix, the angle in metres at
    /// the inliers' RMS range. 1 is ideal; a corridor's is in the hundreds or more.
    pub condition: f64,
    /// Gauss–Newton iterations taken.
    pub iterations: usize,
}

/// Why a match was not trusted.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum Rejection {
    /// Too few inlier pairs (a scan with few returns, or little overlap).
    TooFewPoints {
        /// Inliers found.
        inliers: usize,
        /// Needed ([`MatchSettings::min_inliers`]).
        needed: usize,
    },
    /// Too small a share of the current scan's returns fit the reference.
    PoorOverlap {
        /// The share.
        inlier_share: f64,
    },
    /// The scene does not constrain the motion in some direction (a corridor, one wall).
    IllConditioned {
        /// The normal matrix's condition number.
        condition: f64,
    },
    /// The residuals stay large (a bad fit, a moving scene).
    LargeResidual {
        /// The inliers' RMS. m.
        rms_m: f64,
    },
    /// The iterations ran out before the step became small.
    NotConverged,
}

impl Rejection {
    /// A stable id per kind, for counts: `too_few_points`, `poor_overlap`, `ill_conditioned`,
    /// `large_residual`, `not_converged`.
    pub fn id(&self) -> &'static str {
        match self {
            Self::TooFewPoints { .. } => "too_few_points",
            Self::PoorOverlap { .. } => "poor_overlap",
            Self::IllConditioned { .. } => "ill_conditioned",
            Self::LargeResidual { .. } => "large_residual",
            Self::NotConverged => "not_converged",
        }
    }
}

/// One match: the current sensor pose in the reference sensor frame (`reference_from_current`, the
/// sensor's motion between the two scans), its quality and, when it is not trusted, why.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanMatch {
    /// The sensor's motion from the reference scan to the current one (m, rad).
    pub reference_from_current: Pose2,
    /// How well it fits.
    pub quality: MatchQuality,
    /// Why it is not trusted; `None` for an accepted match.
    pub rejected: Option<Rejection>,
}

/// A step smaller than this ends the iterations (the trimmed set may still flip a pair or two). m.
const CONVERGED_M: f64 = 1e-5;
/// A step smaller than this ends the iterations. rad.
const CONVERGED_RAD: f64 = 1e-5;

/// A reference scan ready to be matched against: its lines and a k-d tree of their points.
pub struct Reference {
    /// The k-d tree over the points that have a line (items index `lines`).
    tree: Option<ImmutableKdTree<f64, 2>>,
    /// Per tree item: the line's centroid and unit normal. m.
    lines: Vec<([f64; 2], [f64; 2])>,
}

impl Reference {
    /// The lines of `scan`'s returns (see the module docs) and their k-d tree.
    pub fn new(scan: &Scan, s: &MatchSettings) -> Self {
        Self::from_points(&scan.points().without_edges(s.edge_angle_rad), s)
    }

    /// The lines of a scan's returns `pts` (as [`Scan::points`] gives them, or de-skewed) and their k-d
    /// tree.
    pub fn from_points(pts: &ScanPoints, s: &MatchSettings) -> Self {
        let mut anchors = Vec::with_capacity(pts.xy_m.len());
        let mut lines = Vec::with_capacity(pts.xy_m.len());
        for k in 0..pts.xy_m.len() {
            if let Some(line) = fit_line(pts, k, s) {
                anchors.push(pts.xy_m[k]);
                lines.push(line);
            }
        }
        let tree = ImmutableKdTree::new_from_slice(&anchors).ok().filter(|_| !anchors.is_empty());
        Self { tree, lines }
    }
}

/// The line through point `k` and its neighbours (beam window, within the radius): centroid and unit
/// normal, when at least 3 points lie within `line_rms_max_m` (RMS) of it.
fn fit_line(pts: &ScanPoints, k: usize, s: &MatchSettings) -> Option<([f64; 2], [f64; 2])> {
    let p = pts.xy_m[k];
    let lo = k.saturating_sub(s.line_window);
    let hi = (k + s.line_window).min(pts.xy_m.len() - 1);
    let r2 = s.line_radius_m * s.line_radius_m;
    let near = || {
        (lo..=hi)
            .filter(move |&j| pts.beam[j].abs_diff(pts.beam[k]) <= s.line_window)
            .map(|j| pts.xy_m[j])
            .filter(move |q| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) <= r2)
    };
    let (mut n, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for q in near() {
        n += 1.0;
        cx += q[0];
        cy += q[1];
    }
    if n < 3.0 {
        return None;
    }
    (cx, cy) = (cx / n, cy / n);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for q in near() {
        let (dx, dy) = (q[0] - cx, q[1] - cy);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    // The line's direction is the covariance's major axis; the normal is perpendicular to it.
    let phi = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let normal = [-phi.sin(), phi.cos()];
    let off_line = (normal[0] * normal[0] * sxx + 2.0 * normal[0] * normal[1] * sxy + normal[1] * normal[1] * syy) / n;
    (off_line.sqrt() <= s.line_rms_max_m).then_some(([cx, cy], normal))
}

/// One Gauss–Newton system over the inlier pairs.
struct System {
    h: Matrix3<f64>,
    g: Vector3<f64>,
    inliers: usize,
    sum_e2: f64,
    /// Σ |p|² over inliers, for the angle's length scale. m².
    sum_r2: f64,
    /// Per-inlier Jacobian rows, kept for the condition number.
    rows: Vec<[f64; 3]>,
}

/// The residuals and Jacobian rows of the current points at `t`, trimmed, as a normal system.
fn build_system(
    reference: &Reference,
    tree: &ImmutableKdTree<f64, 2>,
    current: &[[f64; 2]],
    t: &Pose2,
    s: &MatchSettings,
) -> System {
    let (sn, cs) = t.theta_rad.sin_cos();
    let gate2 = s.max_correspondence_m * s.max_correspondence_m;
    let mut pairs: Vec<(f64, [f64; 3], f64)> = Vec::with_capacity(current.len());
    for p in current {
        let q = [cs * p[0] - sn * p[1] + t.x_m, sn * p[0] + cs * p[1] + t.y_m];
        let nn = tree.query(&q).nearest_one::<SquaredEuclidean<f64>>().execute();
        if nn.distance > gate2 {
            continue;
        }
        let (c, n) = reference.lines[nn.item as usize];
        let e = n[0] * (q[0] - c[0]) + n[1] * (q[1] - c[1]);
        // d(R p)/dθ = (−sin θ px − cos θ py, cos θ px − sin θ py).
        let j_theta = n[0] * (-sn * p[0] - cs * p[1]) + n[1] * (cs * p[0] - sn * p[1]);
        pairs.push((e, [n[0], n[1], j_theta], p[0] * p[0] + p[1] * p[1]));
    }
    let mut abs: Vec<f64> = pairs.iter().map(|(e, _, _)| e.abs()).collect();
    let sigma = if abs.is_empty() {
        s.sigma_floor_m
    } else {
        let mid = abs.len() / 2;
        (1.4826 * *abs.select_nth_unstable_by(mid, f64::total_cmp).1).max(s.sigma_floor_m)
    };
    let limit = s.trim_sigmas * sigma;
    let mut sys = System {
        h: Matrix3::zeros(),
        g: Vector3::zeros(),
        inliers: 0,
        sum_e2: 0.0,
        sum_r2: 0.0,
        rows: Vec::with_capacity(pairs.len()),
    };
    for (e, j, r2) in pairs.into_iter().filter(|(e, _, _)| e.abs() <= limit) {
        let jv = Vector3::from(j);
        sys.h += jv * jv.transpose();
        sys.g += jv * e;
        sys.inliers += 1;
        sys.sum_e2 += e * e;
        sys.sum_r2 += r2;
        sys.rows.push(j);
    }
    sys
}

/// Whether two estimates are the same (to 1 nm and 1 nrad): a cycle closed.
fn same_estimate(a: &Pose2, b: &Pose2) -> bool {
    (a.x_m - b.x_m).abs() < 1e-9 && (a.y_m - b.y_m).abs() < 1e-9 && (a.theta_rad - b.theta_rad).abs() < 1e-9
}

/// The component-wise mean of nearby estimates.
fn mean_pose(poses: &[Pose2]) -> Pose2 {
    let n = poses.len() as f64;
    let sum = poses.iter().fold([0.0; 3], |a, p| [a[0] + p.x_m, a[1] + p.y_m, a[2] + p.theta_rad]);
    Pose2::new(sum[0] / n, sum[1] / n, sum[2] / n)
}

/// The condition number of `Σ J Jᵀ` with the angle column divided by `length_m`.
fn condition(rows: &[[f64; 3]], length_m: f64) -> f64 {
    let mut h = Matrix3::zeros();
    for j in rows {
        let v = Vector3::new(j[0], j[1], j[2] / length_m);
        h += v * v.transpose();
    }
    let eig = SymmetricEigen::new(h).eigenvalues;
    let (lo, hi) = (eig.min(), eig.max());
    if lo > 0.0 { hi / lo } else { f64::INFINITY }
}

/// Matches `current` against `reference`, starting from `guess` (the current sensor pose in the reference
/// frame: the previous motion, or the identity). See the module docs.
pub fn match_scans(reference: &Reference, current: &Scan, guess: Pose2, s: &MatchSettings) -> ScanMatch {
    match_points(reference, &current.points().without_edges(s.edge_angle_rad).xy_m, guess, s)
}

/// [`match_scans`] for a scan's returns `points` (sensor frame, m) as [`Scan::points`] gives them, or
/// de-skewed.
pub fn match_points(reference: &Reference, points: &[[f64; 2]], guess: Pose2, s: &MatchSettings) -> ScanMatch {
    let mut t = guess;
    let mut quality = MatchQuality::default();
    let Some(tree) = &reference.tree else {
        let rejected = Some(Rejection::TooFewPoints { inliers: 0, needed: s.min_inliers });
        return ScanMatch { reference_from_current: t, quality, rejected };
    };
    let mut converged = false;
    let mut sys = build_system(reference, tree, points, &t, s);
    // Every estimate so far: pairs flipping between two lines can make the steps cycle (δ₁, δ₂, …, back to
    // an estimate seen before); the fixed point then lies at the cycle's mean.
    let mut visited = vec![t];
    while quality.iterations < s.max_iterations && sys.inliers >= 3 {
        let Some(step) = sys.h.cholesky().map(|c| c.solve(&(-sys.g))) else { break };
        quality.iterations += 1;
        t = Pose2::new(t.x_m + step[0], t.y_m + step[1], t.theta_rad + step[2]);
        if step[0].hypot(step[1]) < CONVERGED_M && step[2].abs() < CONVERGED_RAD {
            converged = true;
        } else if let Some(j) = visited.iter().rposition(|v| same_estimate(v, &t)) {
            t = mean_pose(&visited[j..]);
            converged = true;
        }
        sys = build_system(reference, tree, points, &t, s);
        if converged {
            break;
        }
        visited.push(t);
    }
    quality.inliers = sys.inliers;
    quality.inlier_share = if points.is_empty() { 0.0 } else { sys.inliers as f64 / points.len() as f64 };
    quality.rms_m = if sys.inliers > 0 { (sys.sum_e2 / sys.inliers as f64).sqrt() } else { f64::INFINITY };
    let length_m = if sys.inliers > 0 { (sys.sum_r2 / sys.inliers as f64).sqrt().max(1e-3) } else { 1.0 };
    quality.condition = condition(&sys.rows, length_m);
    let rejected = if sys.inliers < s.min_inliers {
        Some(Rejection::TooFewPoints { inliers: sys.inliers, needed: s.min_inliers })
    } else if quality.inlier_share < s.min_inlier_share {
        Some(Rejection::PoorOverlap { inlier_share: quality.inlier_share })
    } else if quality.condition > s.max_condition {
        Some(Rejection::IllConditioned { condition: quality.condition })
    } else if quality.rms_m > s.max_rms_m {
        Some(Rejection::LargeResidual { rms_m: quality.rms_m })
    } else if !converged {
        Some(Rejection::NotConverged)
    } else {
        None
    };
    ScanMatch { reference_from_current: t, quality, rejected }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lidar::{Room, ScanSettings, simulate_scan};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Two noisy scans from `a` and `b` in `room`; the match of b against a.
    fn matched(room: &str, a: Pose2, b: Pose2, guess: Pose2) -> ScanMatch {
        let room = Room::builtin(room).unwrap();
        let settings = ScanSettings::default();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let sa = simulate_scan(&room, &a, 0.0, &settings, &mut rng);
        let sb = simulate_scan(&room, &b, 0.1, &settings, &mut rng);
        let s = MatchSettings::default();
        match_scans(&Reference::new(&sa, &s), &sb, guess, &s)
    }

    #[test]
    fn icp_recovers_a_known_increment_within_a_millimetre_and_005_degrees() {
        let a = Pose2::new(0.4, -0.3, 0.2);
        for (dx, dy, dth_deg) in [(0.02, 0.0, 0.0), (0.015, -0.01, 2.0), (0.0, 0.0, -3.5), (-0.03, 0.02, 1.0)] {
            let b = a.compose(&Pose2::new(dx, dy, f64::to_radians(dth_deg)));
            let m = matched("room", a, b, Pose2::IDENTITY);
            let truth = a.inverse().compose(&b);
            let e = m.reference_from_current.error_to(&truth);
            eprintln!(
                "increment ({dx}, {dy}, {dth_deg}°): error {:.3} mm, {:.4}°, condition {:.2}",
                1e3 * e.dx_m.hypot(e.dy_m),
                e.dtheta_rad.to_degrees(),
                m.quality.condition
            );
            assert!(m.rejected.is_none(), "{m:?}");
            assert!(e.dx_m.hypot(e.dy_m) < 1e-3, "position error {e:?} for {truth:?}");
            assert!(e.dtheta_rad.abs().to_degrees() < 0.05, "heading error {e:?}");
            assert!(m.quality.rms_m < 0.015 && m.quality.inlier_share > 0.8, "{:?}", m.quality);
            assert!(m.quality.condition < 20.0, "{:?}", m.quality);
        }
    }

    #[test]
    fn a_corridor_is_rejected_as_ill_conditioned() {
        let a = Pose2::new(0.0, 0.3, 0.0);
        let b = a.compose(&Pose2::new(0.02, 0.0, 0.01));
        let m = matched("corridor", a, b, Pose2::IDENTITY);
        eprintln!("corridor: condition {:.0}", m.quality.condition);
        assert!(matches!(m.rejected, Some(Rejection::IllConditioned { .. })), "{m:?}");
        assert!(m.quality.condition > 100.0, "{:?}", m.quality);
    }

    #[test]
    fn an_empty_scan_is_too_few_points() {
        let s = MatchSettings::default();
        let empty = Scan {
            t_s: 0.0,
            time_increment_s: 0.0,
            angle_min_rad: 0.0,
            angle_increment_rad: 0.01,
            range_min_m: 0.1,
            range_max_m: 10.0,
            ranges_m: vec![f32::INFINITY; 100],
        };
        let m = match_scans(&Reference::new(&empty, &s), &empty, Pose2::IDENTITY, &s);
        assert_eq!(m.rejected, Some(Rejection::TooFewPoints { inliers: 0, needed: 60 }));
    }
}
