//! Static transforms, planar: the fixed offsets between a tracked frame (a motion-capture marker, a lidar)
//! and the robot's base, through any number of frames. The ground truth of a TF pair is moved along them to
//! the frame the wheels move, and a lidar's path likewise.
//!
//! Which pairs are static ([`StaticTree::take`]), as real recordings hold them: every pair of a `…tf_static`
//! topic (ROS 2, ROS 1's tf2 `static_transform_publisher`), and a pair of another TF topic when every one of
//! its messages carries the same transform ([`Seen`]): ROS 1's tf `static_transform_publisher` and
//! robot_state_publisher (Indigo) republish fixed joints on `/tf`, and a pair published once is fixed too.
//! A pair whose value changes (odom → base_link) never is. The ground truth's, the lidar's and the IMU's
//! readers take them by this one rule. Each static transform keeps its full 3D rotation too
//! ([`StaticTree::add_transform`]), for a sensor that is not upright (an IMU upside down or on its side).

use super::tf::{TfMessage, Transform, TransformStamped};
use nalgebra::{Quaternion, UnitQuaternion};
use omni_kin::Pose2;
use std::collections::BTreeMap;

/// The static transforms of a recording: each child frame's parent and its pose in it.
#[derive(Debug, Default)]
pub(super) struct StaticTree {
    parent_of: BTreeMap<String, (String, Pose2)>,
    /// Child frames whose transform turns z downwards (a lidar mounted upside down): seen from above, such a
    /// frame is mirrored, its y axis opposite to what its yaw says.
    flipped: std::collections::BTreeSet<String>,
    /// Each child's full rotation in its parent, where a transform gave one ([`StaticTree::add_transform`]);
    /// a child added planar turns about z by its pose's yaw.
    rotation_of: BTreeMap<String, UnitQuaternion<f64>>,
}

/// Longest chain followed (a TF tree is shallow; this stops a cycle).
const MAX_DEPTH: usize = 64;

/// The robot frames searched for by default, in this order, for the base (the frame the wheels move): REP-105's
/// `base_link`, else `base_footprint` (a TurtleBot's `base_footprint → base_link → base_scan`; some robots
/// hang the laser from `base_footprint` directly).
pub(super) const BASE_FRAMES: [&str; 2] = ["base_link", "base_footprint"];

/// The base frames to search: the one a robot description names (`[frames] base`, without a leading `/`),
/// else [`BASE_FRAMES`].
pub(super) fn base_frames(named: Option<&str>) -> Vec<&str> {
    named.map_or_else(|| BASE_FRAMES.to_vec(), |f| vec![f.trim_start_matches('/')])
}

/// Two transforms of one pair are the same when no translation (m) or quaternion component differs by more.
/// A publisher that repeats a fixed transform sends the same numbers each time (bit for bit; recomputed from
/// a URDF, within round-off, about 1e-16), while a pair that moves changes by far more between two messages
/// (1 mm/s over 10 ms is 1e-5 m); a robot that stands still a whole recording leaves its odom → base_link
/// fixed, which is true of that recording and concerns no frame below the base.
pub(super) const SAME_TOLERANCE: f64 = 1e-9;

/// What one TF pair's messages carried: its first transform, and whether every later one was the same.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Seen {
    /// The first message's transform.
    first: TransformStamped,
    /// Every transform was finite and within [`SAME_TOLERANCE`] of the first.
    same: bool,
    /// How many messages carried the pair.
    pub messages: usize,
}

/// A transform's seven numbers.
fn numbers(t: &Transform) -> [f64; 7] {
    let (p, q) = (&t.translation, &t.rotation);
    [p.x, p.y, p.z, q.x, q.y, q.z, q.w]
}

impl Seen {
    /// The pair's first message.
    pub fn new(t: &TransformStamped) -> Self {
        let same = numbers(&t.transform).iter().all(|v| v.is_finite());
        Self { first: t.clone(), same, messages: 1 }
    }

    /// A later message of the pair.
    pub fn see(&mut self, t: &Transform) {
        self.messages += 1;
        let first = numbers(&self.first.transform);
        self.same &= numbers(t).iter().zip(&first).all(|(a, b)| (a - b).abs() <= SAME_TOLERANCE);
    }

    /// Whether every message carried the same transform (finite).
    pub fn is_fixed(&self) -> bool {
        self.same
    }
}

/// The pairs of one TF topic as [`Seen`], for a reader that needs only the static transforms (a sensor's
/// mount), not the poses of every pair.
#[derive(Debug, Default)]
pub(super) struct SeenPairs {
    /// (parent, child, what its messages carried), frames without a leading `/`, in order of first appearance.
    pairs: Vec<(String, String, Seen)>,
}

impl SeenPairs {
    /// Takes one message of the topic.
    pub fn push(&mut self, msg: &TfMessage) {
        for t in &msg.transforms {
            let (parent, child) = (t.header.frame_id.frame(), t.child_frame_id.frame());
            match self.pairs.iter_mut().find(|(p, c, _)| p == parent && c == child) {
                Some((_, _, seen)) => seen.see(&t.transform),
                None => self.pairs.push((parent.to_string(), child.to_string(), Seen::new(t))),
            }
        }
    }

    /// Adds the static ones to `tree` (see [`StaticTree::take`]).
    pub fn add_statics(&self, on_static_topic: bool, tree: &mut StaticTree) {
        for (_, _, seen) in &self.pairs {
            tree.take(seen, on_static_topic);
        }
    }
}

impl StaticTree {
    /// Takes `child` at `pose` in `parent` (the first one given for a child wins: a latched topic repeats).
    pub fn add(&mut self, parent: &str, child: &str, pose: Pose2) {
        self.parent_of.entry(child.to_string()).or_insert_with(|| (parent.to_string(), pose));
    }

    /// Takes a TF pair as its messages carried it (`seen`): on a static topic (`…tf_static`) always, on
    /// another TF topic only when every message carried the same transform (see the module docs); whole
    /// ([`StaticTree::add_transform`]).
    pub fn take(&mut self, seen: &Seen, on_static_topic: bool) {
        if on_static_topic || seen.is_fixed() {
            self.add_transform(&seen.first);
        }
    }

    /// Takes one `geometry_msgs/TransformStamped` whole: its planar pose, its full rotation, and whether it
    /// turns z downwards. A transform with a non-finite field or a zero quaternion is left out (`false`).
    pub fn add_transform(&mut self, t: &TransformStamped) -> bool {
        let (p, q) = (&t.transform.translation, &t.transform.rotation);
        let rotation = Quaternion::new(q.w, q.x, q.y, q.z);
        let finite = [p.x, p.y, q.x, q.y, q.z, q.w].iter().all(|v| v.is_finite());
        if !finite || rotation.norm() == 0.0 {
            return false;
        }
        let (parent, child) = (t.header.frame_id.frame(), t.child_frame_id.frame());
        if self.parent_of.contains_key(child) {
            return true;
        }
        self.add(parent, child, Pose2::new(p.x, p.y, q.yaw_rad()));
        let rotation = UnitQuaternion::from_quaternion(rotation);
        // The child's z axis in the parent: R₂₂ = w² − x² − y² + z².
        if (rotation * nalgebra::Vector3::z()).z < 0.0 {
            self.mark_flipped(child);
        }
        self.rotation_of.insert(child.to_string(), rotation);
        true
    }

    /// The 3D rotation of frame `to` in frame `from` through the static transforms down from `from` (a link
    /// added planar turns about z by its yaw); `None` when `to` does not hang from `from`.
    pub fn rotation(&self, from: &str, to: &str) -> Option<UnitQuaternion<f64>> {
        let (_, frames) = self.offset(from, to)?;
        let mut r = UnitQuaternion::identity();
        for f in &frames {
            let local = match self.rotation_of.get(f) {
                Some(q) => *q,
                None => UnitQuaternion::from_euler_angles(0.0, 0.0, self.parent_of.get(f)?.1.theta_rad),
            };
            r *= local;
        }
        Some(r)
    }

    /// Marks `child`'s transform as turning z downwards (see [`StaticTree::flipped`]).
    pub fn mark_flipped(&mut self, child: &str) {
        self.flipped.insert(child.to_string());
    }

    /// Whether frame `to`, seen from above in frame `from`, is mirrored: an odd number of the transforms
    /// between them turn z downwards. `None` when `to` does not hang from `from`.
    pub fn mirrored(&self, from: &str, to: &str) -> Option<bool> {
        let (_, frames) = self.offset(from, to)?;
        Some(frames.iter().filter(|f| self.flipped.contains(*f)).count() % 2 == 1)
    }

    /// The pose of frame `to` in frame `from` through static transforms in either direction: up from `from`
    /// to a frame both hang from (a marker that a URDF places below `base_link`, which has a parent of its
    /// own), then down to `to`; and the frames crossed after `from`, ending with `to`. `None` when no
    /// static transforms join them.
    pub fn between(&self, from: &str, to: &str) -> Option<(Pose2, Vec<String>)> {
        let mut up = Pose2::IDENTITY; // `from` in the frame reached going up
        let mut crossed = Vec::new();
        let mut at = from.to_string();
        for _ in 0..MAX_DEPTH {
            if at == to {
                return (!crossed.is_empty()).then(|| (up.inverse(), crossed));
            }
            if let Some((down, frames)) = self.offset(&at, to) {
                crossed.extend(frames);
                return Some((up.inverse().compose(&down), crossed));
            }
            let (parent, local) = self.parent_of.get(&at)?;
            up = local.compose(&up);
            crossed.push(parent.clone());
            at = parent.clone();
        }
        None
    }

    /// Whether any static transform names `frame`, as child or parent.
    pub fn names(&self, frame: &str) -> bool {
        self.parent_of.iter().any(|(child, (parent, _))| child == frame || parent == frame)
    }

    /// The pose of frame `to` in frame `from` through static transforms down from `from`, and the frames
    /// crossed after `from` (ending with `to`); `None` when `to` does not hang from `from` by them.
    pub fn offset(&self, from: &str, to: &str) -> Option<(Pose2, Vec<String>)> {
        let mut pose = Pose2::IDENTITY;
        let mut frames = vec![to.to_string()];
        let mut at = to;
        for _ in 0..MAX_DEPTH {
            if at == from {
                frames.pop();
                frames.reverse();
                return (!frames.is_empty()).then_some((pose, frames));
            }
            let (parent, local) = self.parent_of.get(at)?;
            pose = local.compose(&pose);
            frames.push(parent.clone());
            at = parent;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A marker that a URDF places below base_link (base_link → marker), base_link under base_footprint:
    /// the base's pose in the marker's frame is the inverse of the marker's on the base, and a frame on
    /// another branch is reached through the frame both hang from.
    #[test]
    fn the_tree_is_followed_up_and_down() {
        let mut tree = StaticTree::default();
        tree.add("base_footprint", "base_link", Pose2::new(0.0, 0.0, 0.0));
        tree.add("base_link", "marker", Pose2::new(0.1, 0.05, 0.3));
        tree.add("base_link", "laser", Pose2::new(0.2, 0.0, 0.0));
        assert_eq!(tree.offset("marker", "base_link"), None);
        let (p, frames) = tree.between("marker", "base_link").unwrap();
        let back = Pose2::new(0.1, 0.05, 0.3).compose(&p);
        assert!(back.x_m.abs() < 1e-12 && back.y_m.abs() < 1e-12 && back.theta_rad.abs() < 1e-12, "{back:?}");
        assert_eq!(frames, ["base_link"]);
        let (p, frames) = tree.between("marker", "laser").unwrap();
        let want = Pose2::new(0.1, 0.05, 0.3).inverse().compose(&Pose2::new(0.2, 0.0, 0.0));
        assert!((p.x_m - want.x_m).abs() < 1e-12 && (p.y_m - want.y_m).abs() < 1e-12, "{p:?} vs {want:?}");
        assert_eq!(frames, ["base_link", "laser"]);
        assert_eq!(tree.between("base_link", "marker").map(|(_, f)| f), Some(vec!["marker".to_string()]));
        assert_eq!(tree.between("marker", "odom"), None);
        assert!(tree.names("marker") && !tree.names("odom"));
    }

    #[test]
    fn a_chain_of_static_transforms_composes_to_the_offset_of_its_end() {
        let mut tree = StaticTree::default();
        tree.add("marker", "mount", Pose2::new(-0.1, 0.0, 0.0));
        tree.add("mount", "base_link", Pose2::new(0.0, 0.05, std::f64::consts::FRAC_PI_2));
        tree.add("base_link", "laser", Pose2::new(0.2, 0.0, 0.0));
        let (p, frames) = tree.offset("marker", "base_link").unwrap();
        assert_eq!(frames, ["mount", "base_link"]);
        assert!((p.x_m + 0.1).abs() < 1e-15 && (p.y_m - 0.05).abs() < 1e-15, "{p:?}");
        assert!((p.theta_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-15, "{p:?}");
        // laser is 0.2 m along base_link's x, which points along marker's y.
        let (p, frames) = tree.offset("marker", "laser").unwrap();
        assert_eq!(frames, ["mount", "base_link", "laser"]);
        assert!((p.x_m + 0.1).abs() < 1e-12 && (p.y_m - 0.25).abs() < 1e-12, "{p:?}");
        assert_eq!(tree.offset("base_link", "marker"), None);
        assert_eq!(tree.offset("marker", "marker"), None);
        tree.add("laser", "marker", Pose2::IDENTITY);
        assert_eq!(tree.offset("odom", "marker"), None, "a cycle ends");
    }

    /// The ground truth's reader (TfPairs) and the lidar's (SeenPairs) take the same pairs as static from a
    /// `/tf` topic: a fixed pair republished with every message (ROS 1), and one published once; never the
    /// moving pair, nor one that changes by a micrometre once.
    #[test]
    fn fixed_pairs_on_tf_are_static_for_both_readers() {
        use super::super::common::{Header, RosString, Time};
        use super::super::laser_scan::static_transform;
        let tf = |k: i32, pairs: &[(&str, &str, f64)]| TfMessage {
            transforms: pairs
                .iter()
                .flat_map(|&(parent, child, x)| {
                    let header = Header { stamp: Time { sec: k, nanosec: 0 }, frame_id: RosString(parent.into()) };
                    static_transform(header, child, &Pose2::new(x, 0.0, 0.0)).transforms
                })
                .collect(),
        };
        let messages: Vec<TfMessage> = (1..=4)
            .map(|k| {
                let jitter = if k == 2 { 1e-6 } else { 0.0 };
                let mut pairs = vec![("/world", "/marker", 0.1 * f64::from(k)), ("/marker", "/base_link", -0.1)];
                pairs.push(("/base_link", "/laser", 0.2 + jitter));
                if k == 1 {
                    pairs.push(("/base_link", "/imu", 0.05));
                }
                tf(k, &pairs)
            })
            .collect();
        let (mut pairs, mut seen) = (super::super::tf::TfPairs::default(), SeenPairs::default());
        for (k, m) in messages.iter().enumerate() {
            pairs.push(k, m);
            seen.push(m);
        }
        let (mut a, mut b) = (StaticTree::default(), StaticTree::default());
        pairs.add_statics(false, &mut a);
        seen.add_statics(false, &mut b);
        for tree in [&a, &b] {
            assert_eq!(tree.offset("marker", "base_link").map(|(p, _)| p.x_m), Some(-0.1));
            assert_eq!(tree.offset("base_link", "imu").map(|(p, _)| p.x_m), Some(0.05));
            assert_eq!(tree.offset("base_link", "laser"), None, "changed once");
            assert_eq!(tree.offset("world", "marker"), None, "moves");
        }
    }

    #[test]
    fn a_frame_under_an_odd_number_of_flips_is_mirrored() {
        let mut tree = StaticTree::default();
        tree.add("base_link", "plate", Pose2::new(0.1, 0.0, 0.0));
        tree.add("plate", "laser", Pose2::new(0.05, 0.0, 0.0));
        assert_eq!(tree.mirrored("base_link", "laser"), Some(false));
        tree.mark_flipped("laser");
        assert_eq!(tree.mirrored("base_link", "laser"), Some(true));
        tree.mark_flipped("plate");
        assert_eq!(tree.mirrored("base_link", "laser"), Some(false));
        assert_eq!(tree.mirrored("laser", "base_link"), None);
    }

    /// `child` in `parent` at (x, 0) turned by the quaternion (x, y, z, w).
    fn transform(parent: &str, child: &str, x_m: f64, q: [f64; 4]) -> TransformStamped {
        use super::super::common::{Header, Quaternion as Q, RosString, Vector3};
        use super::super::tf::Transform;
        TransformStamped {
            header: Header { frame_id: RosString(parent.into()), ..Header::default() },
            child_frame_id: RosString(child.into()),
            transform: Transform {
                translation: Vector3 { x: x_m, y: 0.0, z: 0.0 },
                rotation: Q { x: q[0], y: q[1], z: q[2], w: q[3] },
            },
        }
    }

    #[test]
    fn the_rotation_of_a_chain_composes_its_links_in_3d() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let mut tree = StaticTree::default();
        // A plate turned 90° about z (planar), the IMU on it upside down (roll π, a quaternion of 2 × 90°).
        tree.add("base_link", "plate", Pose2::new(0.1, 0.0, std::f64::consts::FRAC_PI_2));
        assert!(tree.add_transform(&transform("/plate", "imu_link", 0.02, [2.0 * h, 0.0, 0.0, 0.0])));
        assert!(!tree.add_transform(&transform("plate", "bad", 0.0, [0.0; 4])), "a zero quaternion");
        assert!(!tree.add_transform(&transform("plate", "bad", f64::NAN, [0.0, 0.0, 0.0, 1.0])));
        let r = tree.rotation("base_link", "imu_link").unwrap();
        // The IMU's x axis along the base's y (the plate's yaw), its z axis down (the roll).
        let (x, z) = (r * nalgebra::Vector3::x(), r * nalgebra::Vector3::z());
        assert!((x - nalgebra::Vector3::y()).norm() < 1e-12 && (z + nalgebra::Vector3::z()).norm() < 1e-12, "{r:?}");
        assert_eq!(tree.mirrored("base_link", "imu_link"), Some(true));
        assert_eq!(tree.rotation("imu_link", "base_link"), None);
    }

    #[test]
    fn a_tf_pair_that_never_moves_is_static_and_one_that_moves_is_not() {
        let up = [0.0, 0.0, 0.0, 1.0];
        let mut pairs = SeenPairs::default();
        for k in 0..5 {
            let odom = transform("odom", "base_link", 0.1 * k as f64, up);
            pairs.push(&TfMessage {
                transforms: vec![odom, transform("base_link", "imu_link", 0.05, [1.0, 0.0, 0.0, 0.0])],
            });
        }
        let mut tree = StaticTree::default();
        // /tf_static's own base_link → laser stays; /tf's constant pair is added beside it.
        tree.add_transform(&transform("base_link", "laser", 0.2, up));
        pairs.add_statics(false, &mut tree);
        let r = tree.rotation("base_link", "imu_link").unwrap();
        assert!((r.angle() - std::f64::consts::PI).abs() < 1e-12, "{r:?}");
        assert_eq!(tree.offset("odom", "base_link"), None, "odom → base_link moves: not static");
        assert!(tree.offset("base_link", "laser").is_some());
    }
}
