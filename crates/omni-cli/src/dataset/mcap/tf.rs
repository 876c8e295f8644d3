//! `tf2_msgs/msg/TFMessage` (`/tf`): transforms between frames, many per message. Ground truth is one
//! parent → child pair, e.g. `world` → `robot` published by a motion-capture bridge.
//!
//! Each pair is gathered separately, and a problem in one pair (NaN, stamps going backwards) concerns that
//! pair only, so an unrelated transform cannot spoil the ground truth.

use super::common::{Header, Quaternion, RosString, Vector3};
use super::poses::PoseSeries;
use super::statics::{Seen, StaticTree};
use serde::{Deserialize, Serialize};

/// The schema name.
pub(super) const NAME: &str = "tf2_msgs/msg/TFMessage";

/// `geometry_msgs/msg/Transform`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct Transform {
    /// m.
    pub translation: Vector3,
    pub rotation: Quaternion,
}

/// `geometry_msgs/msg/TransformStamped`: `child` in `header.frame_id`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct TransformStamped {
    pub header: Header,
    pub child_frame_id: RosString,
    pub transform: Transform,
}

/// `tf2_msgs/msg/TFMessage`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct TfMessage {
    pub transforms: Vec<TransformStamped>,
}

/// One parent → child pair over time.
#[derive(Debug)]
pub(super) struct Pair {
    /// Parent frame (without a leading `/`).
    pub parent: String,
    /// Child frame (without a leading `/`).
    pub child: String,
    /// The poses of `child` in `parent`.
    pub poses: PoseSeries,
    /// The first problem, as (message index, what); the pair takes nothing after it.
    pub problem: Option<(usize, String)>,
    /// What its messages carried, every one (after a problem too): whether it is a fixed transform.
    pub seen: Seen,
}

/// Every pair of one TF topic.
#[derive(Debug, Default)]
pub(super) struct TfPairs {
    /// In order of first appearance.
    pub pairs: Vec<Pair>,
}

/// Whether `topic` holds static transforms (`/tf_static`, `/robot1/tf_static`).
pub(super) fn is_static_topic(topic: &str) -> bool {
    topic.trim_end_matches('/').ends_with("tf_static")
}

impl TfPairs {
    /// Adds the static transforms of this topic to `tree`: every pair of a static topic, and on another
    /// topic the pairs whose every message carried the same transform ([`StaticTree::take`]).
    pub fn add_statics(&self, is_static_topic: bool, tree: &mut StaticTree) {
        for p in &self.pairs {
            tree.take(&p.seen, is_static_topic);
        }
    }

    /// Takes message `index`.
    pub fn push(&mut self, index: usize, msg: &TfMessage) {
        for (i, tr) in msg.transforms.iter().enumerate() {
            let (parent, child) = (tr.header.frame_id.frame(), tr.child_frame_id.frame());
            let k = match self.pairs.iter().position(|p| p.parent == parent && p.child == child) {
                Some(k) => {
                    self.pairs[k].seen.see(&tr.transform);
                    k
                }
                None => {
                    self.pairs.push(Pair {
                        parent: parent.to_string(),
                        child: child.to_string(),
                        poses: PoseSeries::default(),
                        problem: None,
                        seen: Seen::new(tr),
                    });
                    self.pairs.len() - 1
                }
            };
            let pair = &mut self.pairs[k];
            if pair.problem.is_some() {
                continue;
            }
            let fields = super::poses::Fields {
                stamp: "header.stamp",
                position: "transform.translation",
                orientation: "transform.rotation",
            };
            if let Err(e) =
                pair.poses.push(tr.header.stamp.ns(), &tr.transform.translation, &tr.transform.rotation, &fields)
            {
                pair.problem = Some((index, format!("transforms[{i}] ({parent} → {child}): {e}")));
            }
        }
    }

    /// The pairs that can hold a ground truth: from a root of the TF tree (a frame that is nobody's child)
    /// to a frame other than `odom`, with at least 2 poses; or exactly the given frames, a given child also
    /// through static transforms below the pair's child (`statics`).
    pub fn candidates(&self, parent: Option<&str>, child: Option<&str>, statics: &StaticTree) -> Vec<usize> {
        let is_child = |f: &str| self.pairs.iter().any(|p| p.child == f);
        (0..self.pairs.len())
            .filter(|&k| {
                let p = &self.pairs[k];
                let below = |f: &str| f == p.child || statics.offset(&p.child, f).is_some();
                let frames_ok = match (parent, child) {
                    (None, None) => !is_child(&p.parent),
                    _ => parent.is_none_or(|f| f == p.parent) && child.is_none_or(below),
                };
                frames_ok
                    && p.child != super::odometry::ODOM_FRAME
                    && p.parent != super::odometry::ODOM_FRAME
                    && (p.poses.t_ns.len() >= 2 || p.problem.is_some())
            })
            .collect()
    }
}
