//! Static transforms (`/tf_static`, as robot_state_publisher and mocap setups publish them), planar: the
//! fixed offsets between a tracked frame (a motion-capture marker) and the robot's base, through any
//! number of frames. The ground truth of a TF pair is moved along them to the frame the wheels move.

use omni_kin::Pose2;
use std::collections::BTreeMap;

/// The static transforms of a recording: each child frame's parent and its pose in it.
#[derive(Debug, Default)]
pub(super) struct StaticTree {
    parent_of: BTreeMap<String, (String, Pose2)>,
    /// Child frames whose transform turns z downwards (a lidar mounted upside down): seen from above, such a
    /// frame is mirrored, its y axis opposite to what its yaw says.
    flipped: std::collections::BTreeSet<String>,
}

/// Longest chain followed (a TF tree is shallow; this stops a cycle).
const MAX_DEPTH: usize = 64;

impl StaticTree {
    /// Takes `child` at `pose` in `parent` (the first one given for a child wins: a latched topic repeats).
    pub fn add(&mut self, parent: &str, child: &str, pose: Pose2) {
        self.parent_of.entry(child.to_string()).or_insert_with(|| (parent.to_string(), pose));
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
}
