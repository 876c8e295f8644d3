//! Choosing a recording's ground truth: the channel (named with `--gt-topic` or found, never the robot's
//! own odometry nor, unless named, a localization), its poses moved to the robot's base frame, and its
//! clock checked against the wheels'.

use super::{Bag, ROBOT_FRAMES, TRUTH_TYPES, schema_or_none, topic_location};
use crate::api::settings::{named, named_with};
use crate::dataset::DatasetError;
use crate::dataset::Note;
use crate::dataset::ground_truth::{GtClock, Kept};
use crate::dataset::mcap::odometry::ODOM_FRAME;
use crate::dataset::mcap::recording::{Content, MsgType};
use crate::dataset::mcap::statics::{StaticTree, base_frames};
use crate::dataset::mcap::{McapOptions, tf};
use omni_kin::clock::SameRecording;
use omni_kin::{Pose2, StampedPose};
use std::path::{Path, PathBuf};

/// Where the ground truth comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(in crate::dataset::mcap) enum Truth {
    /// A pose channel.
    Poses(usize),
    /// A channel's TF pair.
    Tf(usize, usize),
}

impl Truth {
    /// The channel.
    pub(in crate::dataset::mcap) fn channel(self) -> usize {
        match self {
            Self::Poses(i) | Self::Tf(i, _) => i,
        }
    }
}

impl Bag<'_> {
    /// Why channel `i` cannot be the ground truth under `opts`, if it cannot.
    pub(in crate::dataset::mcap) fn truth_mismatch(&self, i: usize, opts: &McapOptions) -> Option<String> {
        let c = &self.channels[i];
        let Content::Poses(s) = &c.content else { return None };
        let frame = s.frame.as_deref()?;
        if c.is_wheel_odometry() {
            return Some(format!(
                "is the robot's own wheel odometry (frame {ODOM_FRAME:?}, REP-105): the model under test, never \
                 ground truth; choose a map, world or motion-capture source"
            ));
        }
        if let Some(p) = &opts.truth_parent_frame
            && p != frame
        {
            return Some(format!("has frame {frame:?}, but {}", opts.origins.truth_parent_frame.naming(p)));
        }
        if let (Some(want), Some(child)) = (&opts.truth_child_frame, &s.child)
            && want != child
        {
            return Some(format!("has child frame {child:?}, but {}", opts.origins.truth_child_frame.naming(want)));
        }
        None
    }

    /// long: the ground-truth channel, named (`--gt-topic`) or found, with errors that list every
    /// transform or pose topic seen; kept together so the messages can name them.
    pub(in crate::dataset::mcap) fn truth(&self, opts: &McapOptions) -> Result<Truth, DatasetError> {
        let (parent, child) = (opts.truth_parent_frame.as_deref(), opts.truth_child_frame.as_deref());
        let statics = self.statics();
        if let Some(topic) = &opts.truth_topic {
            let i = self.find(topic, &opts.origins.truth_topic)?;
            let c = &self.channels[i];
            return match (&c.content, c.msg_type) {
                (Content::Tf(pairs), _) => {
                    self.check(i)?;
                    let found = pairs.candidates(parent, child, &statics);
                    match found[..] {
                        [k] => Ok(Truth::Tf(i, k)),
                        _ => {
                            let all: Vec<String> = pairs
                                .pairs
                                .iter()
                                .map(|p| format!("{} → {} ({} poses)", p.parent, p.child, p.poses.t_ns.len()))
                                .collect();
                            let what = if found.is_empty() { "no transform" } else { "several transforms" };
                            Err(DatasetError::at(
                                self.path,
                                topic_location(topic),
                                format!(
                                    "{what} could be the ground truth (transforms: {}); choose one with {} and {}",
                                    if all.is_empty() { "none".into() } else { all.join(", ") },
                                    named("gt_parent_frame"),
                                    named("gt_child_frame")
                                ),
                            ))
                        }
                    }
                }
                (Content::Poses(_), _) => match self.truth_mismatch(i, opts) {
                    Some(why) => Err(DatasetError::at(self.path, topic_location(topic), why)),
                    None => Ok(Truth::Poses(i)),
                },
                _ => Err(DatasetError::at(
                    self.path,
                    topic_location(topic),
                    format!("type {} cannot be ground truth (supported: {TRUTH_TYPES})", schema_or_none(&c.schema)),
                )),
            };
        }
        let mut found: Vec<(Truth, String)> = Vec::new();
        let mut points: Vec<(Truth, String)> = Vec::new();
        let mut localizations: Vec<&str> = Vec::new();
        for (i, c) in self.channels.iter().enumerate() {
            if c.messages == 0 {
                continue;
            }
            match &c.content {
                Content::Poses(_) if is_localization(&c.topic) => localizations.push(&c.topic),
                // omnical's own calibrated odometry (export --mcap) is in the ground truth's frame to overlay
                // it, but it is a model's output: never a measurement, unless --gt-topic names it.
                Content::Poses(_) if c.topic == crate::dataset::mcap::write::CALIBRATED_TOPIC => {}
                Content::Poses(_) => {
                    // A GNSS fix's frame is its antenna's (often base_link); its positions are geographic.
                    let geodetic = c.msg_type == MsgType::NavSatFix;
                    let robot_frame = !geodetic && c.frame().is_some_and(|f| ROBOT_FRAMES.contains(&f));
                    if !robot_frame && self.truth_mismatch(i, opts).is_none() {
                        // Positions alone (a tracker, GNSS, or RViz's /clicked_point) only where nothing gives a
                        // pose.
                        let positions = geodetic || c.msg_type == MsgType::PointStamped;
                        let list = if positions { &mut points } else { &mut found };
                        list.push((Truth::Poses(i), c.candidate()));
                    }
                }
                Content::Tf(_) if tf::is_static_topic(&c.topic) => {}
                Content::Tf(pairs) => {
                    for k in pairs.candidates(parent, child, &statics) {
                        let p = &pairs.pairs[k];
                        found.push((Truth::Tf(i, k), format!("{} ({} → {})", c.topic, p.parent, p.child)));
                    }
                }
                _ => {}
            }
        }
        if found.is_empty() {
            found = points;
        }
        match &found[..] {
            [(t, _)] => Ok(*t),
            [] => Err(DatasetError::file(
                self.path,
                format!(
                    "no ground truth: no {TRUTH_TYPES} source outside the robot's frames ({}){}; topics: {}",
                    ROBOT_FRAMES.join(", "),
                    match (parent, child) {
                        (None, None) => String::new(),
                        _ => format!(
                            " matching --gt-parent-frame {:?} --gt-child-frame {:?}",
                            parent.unwrap_or("(any)"),
                            child.unwrap_or("(any)")
                        ),
                    },
                    self.listing()
                ) + &localization_hint(&localizations)
                    + &self.without_motion_capture(),
            )),
            _ => {
                let list: Vec<&str> = found.iter().map(|(_, d)| d.as_str()).collect();
                Err(DatasetError::file(
                    self.path,
                    format!(
                        "several ground-truth sources: {}; choose one with {} (for a TF topic, also {} and {})",
                        list.join(", "),
                        named("gt_topic"),
                        named("gt_parent_frame"),
                        named("gt_child_frame")
                    ),
                ))
            }
        }
    }

    /// The ground truth `src` on channel `ch` (taken out of the bag): its topic and its poses in seconds
    /// since `origin_s`; a TF pair's problem is an error naming the message.
    pub(in crate::dataset::mcap) fn truth_poses(
        &mut self,
        src: Truth,
        ch: usize,
        origin_s: i64,
        opts: &McapOptions,
        notes: &mut Vec<Note>,
    ) -> Result<(String, Vec<StampedPose>), DatasetError> {
        let topic = self.channels[ch].topic.clone();
        let statics = self.statics();
        let poses = match (src, self.take(ch)) {
            (Truth::Tf(_, k), Content::Tf(mut pairs)) => {
                let mut pair = pairs.pairs.swap_remove(k);
                if let Some((m, what)) = pair.problem {
                    return Err(DatasetError::at(self.path, format!("topic {topic:?}, message {m}"), what));
                }
                if let Some(note) =
                    to_base_frame(&mut pair, &statics, opts.truth_child_frame.as_deref(), opts.base_frame.as_deref())
                {
                    notes.push(Note::about(self.path, format!("topic {topic:?}: {note}")));
                }
                pair.poses
            }
            (_, Content::Poses(p)) => p,
            _ => unreachable!("truth() returns pose channels or TF pairs"),
        };
        Ok((topic, poses.stamped(origin_s)))
    }
}

/// Moves a TF pair's poses from its child frame (a motion-capture marker) along static transforms to
/// `target` (`--gt-child-frame`), or by default to the robot's base (`base`, `[frames] base`; else the first
/// of [`crate::dataset::mcap::statics::BASE_FRAMES`] they reach); says so.
fn to_base_frame(
    pair: &mut tf::Pair,
    statics: &StaticTree,
    target: Option<&str>,
    base: Option<&str>,
) -> Option<String> {
    let bases = base_frames(base);
    let found = match target {
        Some(t) => statics.between(&pair.child, t).map(|o| (t, o)),
        None if bases.contains(&pair.child.as_str()) => return None,
        None => bases.iter().find_map(|&t| statics.between(&pair.child, t).map(|o| (t, o))),
    };
    let Some((to, (offset, frames))) = found else {
        // Static transforms that name the tracked frame but reach no base: said, not silently passed over.
        let wanted = target.map_or_else(|| bases.join(" or "), str::to_string);
        return statics.names(&pair.child).then(|| {
            format!(
                "the ground truth tracks {:?}, which the static transforms name, but they do not join it to {wanted}: \
                 the ground truth is left where it was measured (give --gt-mount X,Y,YAW_DEG, or record the \
                 transform between them)",
                pair.child
            )
        });
    };
    for p in &mut pair.poses.xy_yaw {
        let moved = Pose2::new(p[0], p[1], p[2]).compose(&offset);
        *p = [moved.x_m, moved.y_m, omni_kin::pose::wrap_angle(moved.theta_rad)];
    }
    Some(format!(
        "the ground truth tracks {:?}; it is moved to {to:?} through static transforms ({} → {}: x {:.4} m, \
         y {:.4} m, yaw {:.2}°)",
        pair.child,
        pair.child,
        frames.join(" → "),
        offset.x_m,
        offset.y_m,
        offset.theta_rad.to_degrees()
    ))
}

/// Words in a topic's name that mark a localization (AMCL, slam_toolbox, cartographer, robot_localization's
/// EKF/UKF `odometry/filtered`, …): its poses may fuse the very wheel odometry being calibrated, so it is
/// never taken as ground truth unless named.
const LOCALIZATION_WORDS: [&str; 8] = ["amcl", "locali", "slam", "cartographer", "ekf", "ukf", "filtered", "fused"];

/// Whether `topic` names a localization ([`LOCALIZATION_WORDS`], case-insensitive).
pub(in crate::dataset::mcap) fn is_localization(topic: &str) -> bool {
    let t = topic.to_ascii_lowercase();
    LOCALIZATION_WORDS.iter().any(|w| t.contains(w))
}

/// The note for a ground-truth topic named although it looks like a localization.
pub(in crate::dataset::mcap) fn localization_note(path: &Path, topic: &str) -> Option<Note> {
    is_localization(topic).then(|| {
        Note::about(
            path,
            format!(
                "topic {topic:?} is taken as ground truth as named, but it looks like a localization: if it fuses \
                 the wheel odometry being calibrated, the fit measures the wheels against themselves"
            ),
        )
    })
}

/// Whether `schema` is the ROS type `package/Name` (ROS 2's `package/msg/Name` or ROS 1's).
fn is_type(schema: &str, package: &str, name: &str) -> bool {
    schema == format!("{package}/msg/{name}") || schema == format!("{package}/{name}")
}

impl Bag<'_> {
    /// The end of the "no ground truth" message: the references that need no motion capture, naming the
    /// recording's own lidar and IMU topics when it has them.
    fn without_motion_capture(&self) -> String {
        let topics = |name: &str| -> Vec<&str> {
            let of = self.channels.iter().filter(|c| c.messages > 0 && is_type(&c.schema, "sensor_msgs", name));
            of.map(|c| c.topic.as_str()).collect()
        };
        let mut ways = Vec::new();
        match topics("LaserScan").first() {
            Some(t) => ways.push(format!("its lidar's scans as the reference: {}", named_with("gt_scans", t))),
            None => ways.push(format!("a lidar's scans ({})", named_with("gt_scans", "TOPIC"))),
        }
        ways.push(format!(
            "a sensor's or a localization's own path ({} with {} or {})",
            named_with("gt_kind", "relative"),
            named("gt_topic"),
            named("gt")
        ));
        ways.push("tape-measured end poses (--gt-kind end-pose --gt TABLE; omnical plan --umbmark)".into());
        if let Some(t) = topics("Imu").first() {
            ways.push(format!("its IMU for the rotation row alone: omnical imu RECORDING --topic {t}"));
        }
        format!(". Without motion capture: {}", ways.join("; "))
    }
}

/// The end of the "no ground truth" message when localizations were passed over.
fn localization_hint(localizations: &[&str]) -> String {
    if localizations.is_empty() {
        return String::new();
    }
    format!(
        "; {} looks like a localization, which may fuse the wheel odometry being calibrated, so it is not taken \
         as ground truth unless named with {}",
        localizations.join(", "),
        named("gt_topic")
    )
}

/// The same-clock band: a lag up to this is physics the `time_offset` effect models (its range) and
/// diagnose names; beyond it the topic runs on another clock (a motion-capture bridge stamping with its own).
/// s.
pub(crate) const SAME_CLOCK_MAX_OFFSET_S: f64 = omni_kin::clock::SAME_CLOCK_MAX_OFFSET_S;
/// The share of the ground truth's motion the wheels must explain at offset 0 for its clock to be taken as
/// the wheels' without a search.
const TOPIC_CLOCK_SEARCH_BELOW_R2: f64 = 0.98;

/// The clock of a ground-truth topic: `forced_s` when given (`--gt-time-offset`), else checked against the
/// wheels' ([`omni_kin::clock::align_clocks`]). An estimate beyond [`SAME_CLOCK_MAX_OFFSET_S`] and three
/// standard errors moves the poses onto the wheel clock when it is clear
/// ([`omni_kin::clock::ClockAlignment::is_clear`]) and no longer than the recording; otherwise the stamps
/// stay as recorded and the clock returned says why (a note). Within the band, or when no estimate is
/// possible (too little motion), the stamps stay as recorded without a word.
#[allow(clippy::too_many_arguments)] // the topic's names, its poses and the wheel data they are checked against
pub(in crate::dataset::mcap) fn topic_clock(
    path: &Path,
    recording: &str,
    topic: &str,
    forced_s: Option<f64>,
    poses: &mut [StampedPose],
    t_s: &[f64],
    rad_s: &[f64],
    n_wheels: usize,
) -> Option<GtClock> {
    let clock = |offset_s: f64, estimate, kept| GtClock {
        recording: recording.to_string(),
        file: PathBuf::from(format!("{}, topic {topic:?}", path.display())),
        offset_s,
        estimate,
        kept,
    };
    if let Some(offset_s) = forced_s {
        poses.iter_mut().for_each(|p| p.t_s += offset_s);
        return Some(clock(offset_s, None, None));
    }
    // Positions only (a heading that never changes): the estimate needs a heading; as recorded.
    if omni_kin::position_only::heading_never_changes(poses.iter().map(|p| (p.pose.x_m, p.pose.y_m, p.pose.theta_rad)))
    {
        return None;
    }
    // On the wheels' clock, or off it by a small lag (nearly always): the wheels explain nearly all the
    // truth's motion at offset 0, and no search is needed. (Half of it is not enough: slow, smooth motion
    // 0.8 s off is still 60 % explained.)
    if omni_kin::clock::explained_at(t_s, rad_s, n_wheels, poses, 0.0)
        .is_none_or(|r2| r2 >= TOPIC_CLOCK_SEARCH_BELOW_R2)
    {
        return None;
    }
    let a = omni_kin::clock::align_clocks(t_s, rad_s, n_wheels, poses).ok()?;
    match a.same_recording(t_s[t_s.len() - 1] - t_s[0]) {
        // A lag within the band is the `time_offset` effect's, which diagnose names.
        SameRecording::Agree | SameRecording::Lag | SameRecording::UnclearLag => return None,
        SameRecording::Unclear => return Some(clock(0.0, Some(a), Some(Kept::Unclear))),
        SameRecording::Implausible => return Some(clock(0.0, Some(a), Some(Kept::Implausible))),
        SameRecording::Move => {}
    }
    poses.iter_mut().for_each(|p| p.t_s += a.offset_s);
    Some(clock(a.offset_s, Some(a), None))
}
