//! Building a recording's runs from its channels: the wheels (from JointState, or from the robot's own
//! odometry through the design), the ground truth on the wheel clock (from a topic, or from a `--gt` file
//! whose clock is aligned to the wheels') trimmed to the wheel data's span, the recorded odometry and the
//! command, cut into runs ([`McapOptions::split`]); and reading one MCAP bag into them.

mod gt_file;

pub(crate) use gt_file::truth_for_wheels;

use super::common::{NS_PER_S, seconds_since};
use super::framing::feed_mcap;
use super::joint_state::{self, Wheels};
use super::poses::start_heading_in_half_turn;
use super::recording::{Content, Recording};
use super::selection::{Bag, Truth, WheelSource, localization_note, topic_clock, topic_location};
use super::twist::Commands;
use super::{McapOptions, McapRead, split};
use crate::api::settings::named;
use crate::dataset::ground_truth::ExternalTruth;
use crate::dataset::{DatasetError, Note};
use gt_file::external_file;
use omni_kin::error::Sample;
use omni_kin::{KinError, Run, RunData, StampedPose};
use std::path::Path;

/// The wheels of `bag`'s JointState channel `j` (its content taken), with notes on what was done to them;
/// a topic without the wheel joints says what else could give them ([`Bag::odometry_hint`]).
fn joint_wheels(bag: &mut Bag, j: usize, opts: &McapOptions, notes: &mut Vec<Note>) -> Result<Wheels, DatasetError> {
    let (path, topic, hint) = (bag.path, bag.channels[j].topic.clone(), bag.odometry_hint());
    let Content::Joints(series) = bag.take(j) else { unreachable!("joints() returns JointState channels") };
    if let Some((k, missing)) = series.no_wheel_message() {
        let message = hint.map_or_else(|| missing.clone(), |h| format!("{missing}; {h}"));
        return Err(DatasetError::at(path, format!("topic {topic:?}, message {k}"), message));
    }
    let Some(&first_ns) = series.t_ns.first() else {
        return Err(DatasetError::at(path, topic_location(&topic), "has no messages (empty run)"));
    };
    let origin_s = first_ns.div_euclid(NS_PER_S);
    let t_s: Vec<f64> = series.t_ns.iter().map(|&t| seconds_since(t, origin_s)).collect();
    let wheels = series.finish(&opts.wheel_joints, &t_s, &opts.wheel_data).map_err(|(k, what)| {
        let what = match &hint {
            Some(h) if joint_state::is_missing_wheel(&what) => format!("{what}; {h}"),
            _ => what,
        };
        DatasetError::at(path, format!("topic {topic:?}, message {k}"), what)
    })?;
    notes.extend(wheels.notes.iter().map(|n| Note::about(path, format!("topic {topic:?}: {n}"))));
    if let Some(without) = wheels.differentiated.filter(|&n| n > 0 && opts.wheel_data.source.is_none()) {
        notes.push(Note::about(
            path,
            format!(
                "topic {topic:?}: {without} of {} messages have no velocity: wheel speeds are differences of \
                 position over header.stamp",
                t_s.len()
            ),
        ));
    }
    Ok(wheels)
}

/// The wheels recovered from the robot's own odometry `odometry` on `topic` through the design
/// ([`super::odom_wheels`]), with a note saying so and what a fit can reach from them.
fn odometry_wheels(
    path: &Path,
    odometry: &Content,
    topic: &str,
    opts: &McapOptions,
    notes: &mut Vec<Note>,
) -> Result<Wheels, DatasetError> {
    let (Content::Poses(series), Some(rows)) = (odometry, &opts.wheels_from_twist) else {
        unreachable!("joints() returns an odometry channel only with the design's forward kinematics")
    };
    let wheels = super::odom_wheels::wheels_from_odometry(series, rows)
        .map_err(|(k, what)| DatasetError::at(path, format!("topic {topic:?}, message {k}"), what))?;
    let reach = if rows.len() <= 3 {
        "every parameter of the model is within a fit's reach (as many wheels as the motion has degrees of freedom)"
            .to_string()
    } else {
        format!(
            "with {} wheels and 3 degrees of freedom a fit reaches a 3 × 3 correction of the design, not one \
             wheel's own radius",
            rows.len()
        )
    };
    notes.push(Note::about(
        path,
        format!(
            "no {} topic: the wheel speeds are recovered from topic {topic:?} (the robot's own odometry, {} poses) \
             through the design, as its controller computed them; {reach}",
            joint_state::NAME,
            series.t_ns.len()
        ),
    ));
    Ok(wheels)
}

/// The ground-truth poses `all` within the wheel data's span `t_s` (a note counts those dropped); none is an
/// error naming the wheels' topic and where the ground truth came from (`names`: the wheels' topic, the
/// ground truth's place and label).
fn within_wheels(
    path: &Path,
    all: &[StampedPose],
    t_s: &[f64],
    names: (&str, &str, &str),
    notes: &mut Vec<Note>,
) -> Result<Vec<StampedPose>, DatasetError> {
    let (joints_topic, truth_where, truth_label) = names;
    let (w0, w1) = (t_s[0], t_s[t_s.len() - 1]);
    let truth: Vec<StampedPose> = all.iter().copied().filter(|p| (w0..=w1).contains(&p.t_s)).collect();
    if truth.is_empty() {
        let span = match (all.first(), all.last()) {
            (Some(a), Some(b)) => format!("spans {}..{} s", a.t_s, b.t_s),
            _ => "has no poses".to_string(),
        };
        return Err(DatasetError::file(
            path,
            format!(
                "wheel data on {joints_topic:?} spans {w0}..{w1} s but the ground truth {truth_where} {span}: \
                 no ground-truth pose lies within the wheel data"
            ),
        ));
    }
    let dropped = all.len() - truth.len();
    if dropped > 0 {
        notes.push(Note::about(
            path,
            format!(
                "{truth_label}: dropped {dropped} ground-truth poses outside the wheel data's time span ({w0}..{w1} s)"
            ),
        ));
    }
    Ok(truth)
}

/// A recording's streams on one time line (s since its origin), ready to be cut into runs.
struct Streams {
    t_s: Vec<f64>,
    wheels: Wheels,
    truth: Vec<StampedPose>,
    odometry: Vec<StampedPose>,
    commands: Option<Commands>,
    joints_topic: String,
    /// The ground truth gives positions only.
    position_only: bool,
}

impl Streams {
    /// The runs: the whole recording as one named `stem`, or with [`McapOptions::split`] its pieces between
    /// standstills named `stem#1`, `stem#2`, …; each with its name, or the error that refuses it.
    fn runs(&self, path: &Path, stem: &str, opts: &McapOptions) -> Vec<(String, Result<Run, DatasetError>)> {
        let (t_s, n_wheels) = (&self.t_s, opts.wheel_joints.len());
        let pieces = match (opts.split, opts.split_every_s) {
            (_, Some(length_s)) => split::fixed_pieces(t_s, length_s),
            (Some(min_s), None) => split::pieces(t_s, &self.wheels.rad_s, n_wheels, &self.truth, min_s),
            (None, None) => vec![(0, t_s.len() - 1)],
        };
        let last_piece = pieces.len() - 1;
        let mut out = Vec::with_capacity(pieces.len());
        for (p, &(lo, hi)) in pieces.iter().enumerate() {
            let split = opts.split.is_some() || opts.split_every_s.is_some();
            let name = if split { format!("{stem}#{}", p + 1) } else { stem.to_string() };
            let span = t_s[lo]..=t_s[hi];
            let within = |poses: &[StampedPose]| {
                let mut v: Vec<StampedPose> = poses.iter().copied().filter(|q| span.contains(&q.t_s)).collect();
                start_heading_in_half_turn(&mut v);
                v
            };
            // Commands tile the whole time line: the first run also takes those before it, the last those after.
            let from_ns = if p == 0 { i64::MIN } else { self.wheels.t_ns[lo] };
            let to_ns = if p == last_piece { i64::MAX } else { self.wheels.t_ns[hi] };
            let data = RunData {
                name: name.clone(),
                wheel_t_s: t_s[lo..=hi].to_vec(),
                wheel_rad_s: self.wheels.rad_s[lo * n_wheels..(hi + 1) * n_wheels].to_vec(),
                n_wheels,
                truth: within(&self.truth),
                command: self.commands.as_ref().and_then(|c| c.first_in(from_ns, to_ns)),
                repetition: None,
                recorded_odometry: within(&self.odometry),
                wheel_start_rad: self
                    .wheels
                    .position
                    .as_ref()
                    .map(|pos| pos[lo * n_wheels..(lo + 1) * n_wheels].to_vec())
                    .unwrap_or_default(),
                truth_position_only: self.position_only,
            };
            out.push((name, Run::new(data).map_err(|e| self.run_error(path, lo, e))));
        }
        out
    }

    /// A run's validation error, for the run starting at wheel sample `lo`: a bad wheel sample is named as
    /// the wheel topic's message of the same index.
    fn run_error(&self, path: &Path, lo: usize, source: KinError) -> DatasetError {
        let joints_topic = &self.joints_topic;
        match &source {
            KinError::NonFinite { what: Sample::Wheel, index, .. }
            | KinError::NotIncreasing { what: Sample::Wheel, index, .. } => {
                DatasetError::at(path, format!("topic {joints_topic:?}, message {}", lo + index), source.to_string())
            }
            // No wheel turns at 10⁴ rad/s: the joints are in another unit.
            KinError::Implausible { what: Sample::Wheel, index, .. } => DatasetError::at(
                path,
                format!("topic {joints_topic:?}, message {}", lo + index),
                format!(
                    "{source}: are the joints in encoder counts, rpm or degrees? Declare their units in \
                     robot.toml's [wheel_data] (docs/formats.md)"
                ),
            ),
            _ => DatasetError::Run { path: path.to_path_buf(), error: source },
        }
    }
}

/// The file of a `--gt` folder that covers most of the wheel data's span `t_s` (s since `origin_s`), for a
/// recording no file is named after, with a note saying which and how much it covers.
fn overlapping_file(
    path: &Path,
    folder: &ExternalTruth,
    origin_s: i64,
    t_s: &[f64],
    notes: &mut Vec<Note>,
) -> Result<ExternalTruth, DatasetError> {
    let at = |t: f64| origin_s * NS_PER_S + (t * 1e9).round() as i64;
    let (ext, share) = folder
        .overlapping(at(t_s[0]), at(t_s[t_s.len() - 1]))
        .map_err(|e| DatasetError::file(path, format!("{} folder {}: {e}", named("gt"), folder.path.display())))?;
    notes.push(Note::about(
        path,
        format!(
            "no file of the {} folder is named after it: {} covers {:.0} % of its span and is its ground truth",
            named("gt"),
            ext.path.display(),
            100.0 * share
        ),
    ));
    Ok(ext)
}

/// The runs of a recording whose messages are all in `rec`; `path` names it in messages, `stem` names its
/// runs (`stem`, or `stem#1`, `stem#2`, … when split). See the module docs of [`super`].
///
/// With `external`, the ground truth comes from that file (its clock aligned to the wheels', see
/// [`external_truth`](gt_file::external_truth)) and the recording needs no ground-truth topic.
pub(crate) fn runs(
    path: &Path,
    stem: &str,
    rec: Recording,
    opts: &McapOptions,
    external: Option<&ExternalTruth>,
) -> Result<McapRead, DatasetError> {
    let (channels, scans) = rec.into_parts();
    let mut read = wheel_runs(path, stem, channels, opts, external)?;
    read.scans = scans.map(|s| s.finish(path)).transpose()?;
    Ok(read)
}

/// [`runs`] from the recording's channels, without its scans.
fn wheel_runs(
    path: &Path,
    stem: &str,
    channels: Vec<super::recording::Channel>,
    opts: &McapOptions,
    external: Option<&ExternalTruth>,
) -> Result<McapRead, DatasetError> {
    let mut bag = Bag { path, channels };
    let mut notes = Vec::new();

    let source = bag.joints(opts)?;
    let j = source.channel();
    bag.check_wheels(j)?;
    let truth_src = match external {
        Some(_) => None,
        None if opts.wheels_only => None,
        None => Some(bag.truth(opts)?),
    };
    let truth_ch = truth_src.map(Truth::channel);
    if let Some(i) = truth_ch {
        bag.check(i)?;
        notes.extend(localization_note(path, &bag.channels[i].topic));
    }
    let odom = if opts.recorded_odometry { bag.recorded_odometry(&mut notes) } else { None };
    let odom = odom.filter(|&i| Some(i) != truth_ch);
    let cmd = bag.commands(opts.command_topic.as_deref(), &mut notes);

    // Wheels.
    let joints_topic = bag.channels[j].topic.clone();
    let wheels = match source {
        WheelSource::Joints(_) => joint_wheels(&mut bag, j, opts, &mut notes)?,
        WheelSource::Odometry(_) => odometry_wheels(path, &bag.channels[j].content, &joints_topic, opts, &mut notes)?,
    };
    let origin_s = wheels.t_ns[0].div_euclid(NS_PER_S);
    let t_s: Vec<f64> = wheels.t_ns.iter().map(|&t| seconds_since(t, origin_s)).collect();

    // Ground truth, trimmed to the wheel data's span.
    let n_wheels = opts.wheel_joints.len();
    let (all_truth, truth_where, truth_label, clock) = match (truth_src, truth_ch, external) {
        (Some(src), Some(ch), _) => {
            let (truth_topic, mut poses) = bag.truth_poses(src, ch, origin_s, opts, &mut notes)?;
            let forced = opts.truth_time_offset_s;
            let clock = topic_clock(path, stem, &truth_topic, forced, &mut poses, &t_s, &wheels.rad_s, n_wheels);
            (poses, format!("on {truth_topic:?}"), format!("topic {truth_topic:?}"), clock)
        }
        (_, _, Some(ext)) if !ext.by_time.is_empty() => {
            let ext = overlapping_file(path, ext, origin_s, &t_s, &mut notes)?;
            external_file(&ext, stem, origin_s, &t_s, &wheels.rad_s, n_wheels)?
        }
        (_, _, Some(ext)) => external_file(ext, stem, origin_s, &t_s, &wheels.rad_s, n_wheels)?,
        _ if opts.wheels_only => {
            let at = |t_s: f64| StampedPose { t_s, pose: omni_kin::Pose2::IDENTITY };
            let placeholder = vec![at(t_s[0]), at(t_s[t_s.len() - 1])];
            (placeholder, "measured at the end".to_string(), "the measured end pose".to_string(), None)
        }
        _ => unreachable!("the ground truth comes from a topic or a file"),
    };
    let truth = within_wheels(path, &all_truth, &t_s, (&joints_topic, &truth_where, &truth_label), &mut notes)?;
    let odometry: Vec<StampedPose> = match odom.map(|i| bag.take(i)) {
        Some(Content::Poses(p)) => p.stamped(origin_s),
        _ => Vec::new(),
    };
    let commands = match cmd.map(|i| bag.take(i)) {
        Some(Content::Commands(c)) => Some(c),
        _ => None,
    };

    // Runs.
    let position_only = external.is_some_and(|e| e.position_only)
        || truth_ch.is_some() && positions_only_topic(path, &truth_label, &truth, &mut notes);
    let streams = Streams { t_s, wheels, truth, odometry, commands, joints_topic, position_only };
    let out =
        McapRead { runs: Vec::new(), notes, skipped: Vec::new(), origin_s, ground_truth_clock: clock, scans: None };
    with_runs(out, &streams, (path, stem), opts)
}

/// Whether a ground-truth topic's poses (`label`) give positions only: a heading that never changes while
/// they move (a tracker, UWB or GNSS that writes a fixed orientation); a note says so.
fn positions_only_topic(path: &Path, label: &str, truth: &[StampedPose], notes: &mut Vec<Note>) -> bool {
    let xy_theta = truth.iter().map(|p| (p.pose.x_m, p.pose.y_m, p.pose.theta_rad));
    if !omni_kin::position_only::heading_never_changes(xy_theta) {
        return false;
    }
    notes.push(Note::about(
        path,
        format!(
            "{label}: its heading never changes while it moves (a fixed orientation beside the positions: a \
             tracker, UWB or GNSS): read as positions only; each run's start heading is fitted with the model"
        ),
    ));
    true
}

/// `out` with the runs cut from `streams` (those refused listed as skipped under `skip_invalid`) and the
/// note on a fixed-length cut.
fn with_runs(
    mut out: McapRead,
    streams: &Streams,
    (path, stem): (&Path, &str),
    opts: &McapOptions,
) -> Result<McapRead, DatasetError> {
    for (name, run) in streams.runs(path, stem, opts) {
        match run {
            Ok(run) => out.runs.push(run),
            Err(e) if opts.skip_invalid => out.skipped.push((name, e.to_string())),
            Err(e) => return Err(e),
        }
    }
    out.notes.extend(split_note(path, opts, out.runs.len() + out.skipped.len()));
    Ok(out)
}

/// The note on a recording cut into `pieces` runs of a fixed length (`--split 20s`).
fn split_note(path: &Path, opts: &McapOptions, pieces: usize) -> Option<Note> {
    let length_s = opts.split_every_s?;
    Some(Note::about(
        path,
        format!(
            "cut into {pieces} runs of {length_s} s (--split {length_s}s; the last takes up to half a length more; a \
             bare number, --split N, cuts at standstills instead)"
        ),
    ))
}

/// Reads one bag. See the module docs of [`super`].
pub(super) fn read_file(
    path: &Path,
    opts: &McapOptions,
    external: Option<&ExternalTruth>,
) -> Result<McapRead, DatasetError> {
    let buf = std::fs::read(path).map_err(|e| DatasetError::io(path, e))?;
    read_bytes(path, &buf, opts, external)
}

/// Reads one bag from its bytes; `path` only names it in messages and runs.
pub(super) fn read_bytes(
    path: &Path,
    buf: &[u8],
    opts: &McapOptions,
    external: Option<&ExternalTruth>,
) -> Result<McapRead, DatasetError> {
    let mut rec = Recording::for_read(opts);
    feed_mcap(path, buf, &mut rec)?;
    let stem = path.file_stem().map_or_else(|| path.display().to_string(), |s| s.to_string_lossy().into_owned());
    runs(path, &stem, rec, opts, external)
}
