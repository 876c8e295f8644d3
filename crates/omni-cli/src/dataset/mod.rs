//! Datasets: runs loaded from files (CSV, OptiOdom folders, ROS 2 MCAP bags, rosbag2 recordings in sqlite3
//! or MCAP) and written back.
//!
//! Every error names the file and, where it applies, the line, topic, message, run and field.

pub mod csv;
pub mod end_poses;
mod error;
pub mod ground_truth;
mod input;
mod lidar_reference;
pub use lidar_reference::returns_text;
pub mod mcap;
mod note;
pub mod optiodom;
mod ros;
pub mod ros1;
pub mod rosbag2;
pub(crate) mod sensor_clock;

pub use error::{DatasetError, Skipped};
pub(crate) use error::{check_size, too_large};
use input::{Input, Inputs, Loaded, read_input};
pub use note::Note;
use omni_kin::{RobotGeometry, Run};
use rayon::prelude::*;
pub use ros::{InputKind, Inspected, inspect, recorded_topics, review};
pub(crate) use ros::{feed_ros, inputs, ros_recordings};
use std::path::{Path, PathBuf};

/// A set of runs, with what was skipped and what was noticed while loading.
#[derive(Debug, Default)]
pub struct Dataset {
    /// The runs, in the order their files were given.
    pub runs: Vec<Run>,
    /// Inputs skipped with `--skip-invalid`, with the reason.
    pub skipped: Vec<Skipped>,
    /// Things the user should know (e.g. "velocity empty: differentiated position"), each with the input it
    /// concerns.
    pub notes: Vec<Note>,
    /// The design geometry each input declares (OptiOdom metadata), in input order, with its runs: each run
    /// is evaluated with its own input's design (`crate::design`).
    pub declared: Vec<Declared>,
    /// The robot the runs are of, from the first input that gave runs: every other input must be of the
    /// same kind ([`check_same_robot`]).
    pub robot_kind: Option<RobotKind>,
    /// The robot description the data was read with (`--robot`, or a `robot.toml` found beside it), if any.
    /// Set by the command line, not by [`load`].
    pub robot_file: Option<crate::robot_file::RobotFile>,
    /// The clock offsets of ground truths read from separate files (`--gt`), one per recording.
    pub ground_truth_clocks: Vec<ground_truth::GtClock>,
    /// The Unix second each recording's run times count from, by run name (ROS recordings: exports write
    /// absolute stamps with it, so they line up with the recording).
    pub time_origins_s: std::collections::BTreeMap<String, i64>,
    /// The ROS recording each run was read from, by run name (exports carry its other topics over:
    /// [`recorded_topics`]).
    pub recordings: std::collections::BTreeMap<String, PathBuf>,
    /// Every input file or folder the runs were read from (for the check that no result folder holds one:
    /// [`crate::out_path::Inputs`]).
    pub sources: Vec<PathBuf>,
    /// What the ground truth measures: a relative reference's runs are its windows
    /// ([`omni_kin::reference::windows`]), and a fit adds the sensor's mount.
    pub reference: omni_kin::reference::ReferenceKind,
    /// The measured point's pose in the base frame, when given (`--gt-mount`): the ground truth was moved
    /// to the base by it, and no fit adds a mount.
    pub mount: Option<omni_kin::Pose2>,
    /// A lidar reference (`--gt-scans`) moved to the base by every recording's own static transforms (its
    /// `/tf_static` places the lidar): a fit corrects that mount only where the base model can tell a mount
    /// from the base; a free matrix keeps it as given.
    pub sensor_mount_from_recordings: bool,
    /// Where a fit starts the sensor's mount of a relative reference (`sensor_offset_yaw`): given
    /// (`--gt-mount-start`), else found from the motions ([`omni_kin::hand_eye`]), else (`None`) zero.
    /// When the recordings' static transforms placed the sensor, it is the correction of theirs.
    pub mount_start: Option<omni_kin::Pose2>,
}

/// The design one input declares (an OptiOdom set's metadata), with the runs read from it.
#[derive(Clone, Debug, PartialEq)]
pub struct Declared {
    /// The input (a set folder).
    pub source: PathBuf,
    /// The robot type it names (OptiOdom's `type`: `omni3`, `omni4`, `diff`).
    pub kind: String,
    /// The design geometry.
    pub geometry: RobotGeometry,
    /// The names of its runs.
    pub runs: Vec<String>,
}

/// What kind of robot an input's runs are of: what one command's inputs must share.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotKind {
    /// The input.
    pub source: PathBuf,
    /// The robot type the input declares (OptiOdom's `type`), if it declares one.
    pub declared: Option<String>,
    /// Wheels of its runs.
    pub n_wheels: usize,
}

impl std::fmt::Display for RobotKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.declared {
            Some(k) => write!(f, "{} is an OptiOdom {k} set ({} wheels)", self.source.display(), self.n_wheels),
            None => write!(f, "{} holds runs of a {}-wheel robot", self.source.display(), self.n_wheels),
        }
    }
}

impl RobotKind {
    /// Whether `other` is of another kind: another wheel count, or another declared type.
    fn differs(&self, other: &RobotKind) -> bool {
        self.n_wheels != other.n_wheels || matches!((&self.declared, &other.declared), (Some(a), Some(b)) if a != b)
    }
}

/// Refuses robots of different kinds in one command (OptiOdom omni3 with diff, 3 wheels with 4), naming both
/// inputs and their kinds: `first` is the kind seen first, `next` the one that differs.
pub fn check_same_robot(first: Option<&RobotKind>, next: Option<&RobotKind>) -> Result<(), DatasetError> {
    match (first, next) {
        (Some(a), Some(b)) if a.differs(b) => Err(DatasetError::file(
            &b.source,
            format!(
                "runs of robots of different kinds in one command: {a}, and {b}; give one robot's runs (train and \
                 validate one robot at a time)"
            ),
        )),
        _ => Ok(()),
    }
}

impl Dataset {
    /// The declared design that stands for all where one design is needed (training's start): the one the
    /// most runs declare (inputs with equal geometry counted together), the first given on a tie.
    pub fn declared_start(&self) -> Option<&Declared> {
        group_designs(&self.declared).into_iter().next().and_then(|g| g.inputs.first().copied())
    }
}

/// Inputs that declare one design geometry.
#[derive(Clone, Debug)]
pub struct DesignGroup<'a> {
    /// The geometry.
    pub geometry: &'a RobotGeometry,
    /// The inputs that declare it, in the order given.
    pub inputs: Vec<&'a Declared>,
}

impl DesignGroup<'_> {
    /// Runs of its inputs.
    pub fn n_runs(&self) -> usize {
        self.inputs.iter().map(|d| d.runs.len()).sum()
    }
}

/// The distinct designs `declared` holds, the one of the most runs first (the first given on a tie), the
/// others in the order given.
pub fn group_designs<'a>(declared: impl IntoIterator<Item = &'a Declared>) -> Vec<DesignGroup<'a>> {
    let mut out: Vec<DesignGroup<'a>> = Vec::new();
    for d in declared {
        match out.iter_mut().find(|g| *g.geometry == d.geometry) {
            Some(g) => g.inputs.push(d),
            None => out.push(DesignGroup { geometry: &d.geometry, inputs: vec![d] }),
        }
    }
    let mut start = 0;
    for (i, g) in out.iter().enumerate() {
        if g.n_runs() > out[start].n_runs() {
            start = i;
        }
    }
    if start > 0 {
        let first = out.remove(start);
        out.insert(0, first);
    }
    out
}

/// The default cap on one input file's size (`--max-file-mb`). Bytes: 1 GiB.
pub const DEFAULT_MAX_FILE_BYTES: u64 = 1 << 30;

/// Passes over a storage file's messages (an MCAP, sqlite3 or ROS 1 bag file) since the process started.
static MESSAGE_PASSES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// How many times this process has gone through a storage file's messages (an MCAP, sqlite3 or ROS 1 bag
/// file, each file of a split recording counted): a test checks that a load reads each recording once,
/// its lidar's scans included.
pub fn message_passes() -> usize {
    MESSAGE_PASSES.load(std::sync::atomic::Ordering::Relaxed)
}

/// Counts one pass over a storage file's messages ([`message_passes`]).
pub(crate) fn count_message_pass() {
    MESSAGE_PASSES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
}

/// How to load.
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// Skip runs that fail (listed in [`Dataset::skipped`]) instead of stopping.
    pub skip_invalid: bool,
    /// Encoder ticks per wheel revolution for CSV tick columns (overrides the file).
    pub ticks_per_rev: Option<f64>,
    /// How to read MCAP bags (topics, joint names, frames, splitting).
    pub mcap: mcap::McapOptions,
    /// Keep the robot's recorded odometry (MCAP `/odom`, CSV odometry columns) in the runs; overrides
    /// [`mcap::McapOptions::recorded_odometry`]. Calibration never reads it and it takes as much memory as
    /// the wheel data. Default true.
    pub recorded_odometry: bool,
    /// Refuse a CSV or MCAP file larger than this: each is read into memory whole (MCAP chunks are then
    /// decompressed one at a time), so the cap keeps a huge or mistaken input from exhausting memory.
    /// Bytes. Default [`DEFAULT_MAX_FILE_BYTES`].
    pub max_file_bytes: u64,
    /// Ground truth from separate files (`--gt`) instead of a topic of the recordings. Default none.
    pub ground_truth: Option<ground_truth::GroundTruthOptions>,
    /// The wheel joints, in the model's column order, that CSV runs must have (`<joint>_rad_s` or
    /// `<joint>_ticks` columns, read in this order): a robot description's or `--joints`. Default empty:
    /// each file's own column order.
    pub csv_joints: Vec<String>,
    /// A ROS recording's ground truth from its 2D lidar: the LaserScan topic, matched scan to scan with these
    /// settings (`--gt-scans`); the recording is read wheels only. Default none.
    pub scans: Option<(String, omni_kin::lidar::MatchSettings)>,
    /// The lidar's mount is given (`--gt-mount`, `--gt-mount-start`): the recordings' static transforms do
    /// not move its path. Default false.
    pub scan_mount_given: bool,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            skip_invalid: false,
            ticks_per_rev: None,
            mcap: mcap::McapOptions::default(),
            recorded_odometry: true,
            max_file_bytes: DEFAULT_MAX_FILE_BYTES,
            ground_truth: None,
            csv_joints: Vec::new(),
            scans: None,
            scan_mount_given: false,
        }
    }
}

/// Supported inputs, for messages.
pub const SUPPORTED: &str = ".csv (omnical run), .mcap (ROS 2 bag), .db3 (rosbag2 sqlite3), .bag (ROS 1), a rosbag2 recording \
                             folder (metadata.yaml), or a folder of them / an OptiOdom set folder";

/// Load runs from files and folders, in the order given (folders: files sorted by name).
pub fn load(paths: &[PathBuf], opts: &LoadOptions) -> Result<Dataset, DatasetError> {
    let found = Inputs::of(paths);
    let repeated = found.repeated_note();
    let inputs = found.list;
    // The inputs are read in parallel (one file or recording per task) and merged in their order, so the
    // dataset, its notes and the first error are those of a serial load whatever the thread count.
    let mut reads: Vec<_> = inputs.par_iter().map(|i| i.as_ref().ok().map(|i| read_input(i, opts))).collect();
    let shared_clock = shared_clock_retry(&inputs, &mut reads, opts);
    let mut ds = Dataset::default();
    let mut read_from = Vec::new();
    for (input, read) in inputs.into_iter().zip(reads) {
        // A path that is no input (unreadable, unsupported) stops the load where it stands in the order.
        let input = input?;
        if let Some(read) = read {
            let before = ds.runs.len();
            merge(&mut ds, opts, input.path(), read?)?;
            read_from.push((input.path().to_path_buf(), ds.runs.len() - before));
        }
    }
    for line in read_lines(&read_from) {
        tracing::info!("{line}");
    }
    ds.notes.extend(designs_note(&ds));
    ds.notes.extend(shared_clock);
    ds.notes.extend(repeated);
    if ds.runs.is_empty() {
        let what = paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ");
        return Err(match ds.skipped.first() {
            Some(s) => DatasetError::file(
                Path::new(&what),
                format!("no valid runs ({} skipped; first: {}: {})", ds.skipped.len(), s.source, s.reason),
            ),
            None => DatasetError::file(Path::new(&what), format!("no runs found (expected {SUPPORTED})")),
        });
    }
    Ok(ds)
}

/// Inputs of one folder beyond which `-v` says one line for the folder instead of one per input.
pub const READ_LINES_PER_FOLDER: usize = 4;

/// `-v`'s lines on what was read: one per input (`read sim/a.mcap: 1 run`), or, for a folder of more than
/// [`READ_LINES_PER_FOLDER`] inputs, one for the folder (`read 180 files in sim/train (00-r0.mcap …
/// 35-r4.mcap): 180 runs`), in the order read.
fn read_lines(read: &[(PathBuf, usize)]) -> Vec<String> {
    let runs = |n: usize| format!("{n} run{}", if n == 1 { "" } else { "s" });
    let mut lines = Vec::new();
    let mut rest = read;
    while let Some((first, _)) = rest.first() {
        let folder = first.parent();
        let same = rest.iter().take_while(|(p, _)| p.parent() == folder).count();
        let (group, after) = rest.split_at(same);
        match (group, folder) {
            ([.., (last, _)], Some(folder)) if group.len() > READ_LINES_PER_FOLDER => {
                let name =
                    |p: &Path| p.file_name().map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into());
                lines.push(format!(
                    "read {} inputs in {} ({} … {}): {}",
                    group.len(),
                    folder.display(),
                    name(first),
                    name(last),
                    runs(group.iter().map(|(_, n)| n).sum())
                ));
            }
            _ => lines.extend(group.iter().map(|(p, n)| format!("read {}: {}", p.display(), runs(*n)))),
        }
        rest = after;
    }
    lines
}

/// The reads of [`load`], one per input.
type Reads = Vec<Option<Result<Result<Loaded, DatasetError>, DatasetError>>>;

/// Recordings read with one `--gt` source (a file covering them all, or a folder of takes) share its clock:
/// a recording whose own alignment failed (a short, still or sparsely tracked one), is not clear
/// ([`omni_kin::clock::ClockAlignment::is_clear`]), or lands more than
/// [`mcap::selection::SAME_CLOCK_MAX_OFFSET_S`] from the others (another stretch of a long take matched) is read
/// again at the median offset of the clear estimates, and a note per such recording says so. A few
/// milliseconds of drift between clear estimates is kept: each recording keeps its own. Nothing changes when
/// the offset is forced or no estimate is clear.
fn shared_clock_retry(inputs: &[Result<Input, DatasetError>], reads: &mut Reads, opts: &LoadOptions) -> Vec<Note> {
    let Some(gt) = opts.ground_truth.as_ref().filter(|g| g.time_offset_s.is_none()) else { return vec![] };
    let estimate = |r: &Option<Result<Result<Loaded, DatasetError>, DatasetError>>| {
        r.as_ref()?.as_ref().ok()?.as_ref().ok()?.clock.as_ref()?.estimate
    };
    let clear = |a: &omni_kin::clock::ClockAlignment| a.is_clear();
    let mut offsets: Vec<f64> = reads.iter().filter_map(estimate).filter(clear).map(|a| a.offset_s).collect();
    if offsets.is_empty() {
        return vec![];
    }
    offsets.sort_by(f64::total_cmp);
    let median = offsets[offsets.len() / 2];
    // Why a read is taken again at the median, if it is.
    let retry = |r: &Option<Result<Result<Loaded, DatasetError>, DatasetError>>| -> Option<String> {
        if let Some(Ok(Err(e @ DatasetError::Clock { .. }))) = r {
            return Some(e.to_string());
        }
        let a = estimate(r)?;
        let own = format!("its own alignment gives {:+.4} s ± {:.1} ms", a.offset_s, a.std_error_s * 1e3);
        if !clear(&a) {
            return Some(format!("{own}, explaining {:.0} % of the motion: not clear", a.r_squared * 100.0));
        }
        let off = a.offset_s - median;
        (off.abs() > mcap::selection::SAME_CLOCK_MAX_OFFSET_S && offsets.len() >= 2)
            .then(|| format!("{own}, {off:+.3} s from the other recordings' (another stretch of the take matched)"))
    };
    let forced = LoadOptions {
        ground_truth: Some(ground_truth::GroundTruthOptions { time_offset_s: Some(median), ..gt.clone() }),
        ..opts.clone()
    };
    let mut notes = Vec::new();
    for (input, read) in inputs.iter().zip(reads.iter_mut()) {
        let (Ok(input), Some(why)) = (input, retry(read)) else { continue };
        notes.push(Note::about(
            input.path(),
            format!(
                "{why}; the ground truth is read at {median:+.4} s, the median offset of the {} recording(s) aligned \
                 clearly with the same {} (one clock)",
                offsets.len(),
                crate::api::settings::named("gt")
            ),
        ));
        *read = Some(read_input(input, &forced));
    }
    notes
}

/// When the inputs declare different designs, the note that says so: each run is evaluated with its own
/// input's design, and which one stands for all where one is needed.
fn designs_note(ds: &Dataset) -> Option<Note> {
    let groups = group_designs(&ds.declared);
    if groups.len() < 2 {
        return None;
    }
    let name = |d: &Declared| {
        d.source.file_name().map_or_else(|| d.source.display().to_string(), |n| n.to_string_lossy().into_owned())
    };
    let names = |g: &DesignGroup<'_>| g.inputs.iter().map(|d| name(d)).collect::<Vec<_>>().join(" + ");
    let list: Vec<String> = groups
        .iter()
        .map(|g| format!("{} ({} run{})", names(g), g.n_runs(), if g.n_runs() == 1 { "" } else { "s" }))
        .collect();
    let why = if groups[1].n_runs() == groups[0].n_runs() { "the most runs, the first given" } else { "the most runs" };
    Some(Note::general(format!(
        "the inputs declare {} different designs: {}; each run is evaluated with its own input's design, and \
         where one design is needed (training's start, --model design) it is that of {} ({why})",
        groups.len(),
        list.join(", "),
        names(&groups[0])
    )))
}

/// The text of a file a user writes by hand or a spreadsheet exports (a table, a ground-truth file, a
/// plan), without the UTF-8 byte-order mark Excel and Notepad put in front, as the run CSV reader takes it.
pub fn read_text(path: &Path) -> Result<String, DatasetError> {
    let text = std::fs::read_to_string(path).map_err(|e| DatasetError::io(path, e))?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

/// Adds what one input gave to the dataset; a failed input stops the load, or is listed as skipped with
/// `skip_invalid`.
fn merge(
    ds: &mut Dataset,
    opts: &LoadOptions,
    source: &Path,
    read: Result<Loaded, DatasetError>,
) -> Result<(), DatasetError> {
    ds.sources.push(source.to_path_buf());
    match read {
        Ok(l) => {
            for r in &l.runs {
                tracing::debug!(
                    "run {}: {} wheel samples over {:.3} s, {} ground-truth poses",
                    r.name(),
                    r.n_samples(),
                    r.wheel_t_s().last().unwrap_or(&0.0) - r.wheel_t_s().first().unwrap_or(&0.0),
                    r.truth().len()
                );
            }
            if let Some(first) = l.runs.first() {
                let kind = RobotKind {
                    source: source.to_path_buf(),
                    declared: l.declared.as_ref().map(|(k, _)| k.to_string()),
                    n_wheels: first.n_wheels(),
                };
                check_same_robot(ds.robot_kind.as_ref(), Some(&kind))?;
                ds.robot_kind.get_or_insert(kind);
            }
            if let Some((kind, geometry)) = l.declared {
                let runs = l.runs.iter().map(|r| r.name().to_string()).collect();
                ds.declared.push(Declared { source: source.to_path_buf(), kind: kind.into(), geometry, runs });
            }
            if let Some(origin_s) = l.origin_s {
                ds.time_origins_s.extend(l.runs.iter().map(|r| (r.name().to_string(), origin_s)));
                ds.recordings.extend(l.runs.iter().map(|r| (r.name().to_string(), source.to_path_buf())));
            }
            if let Some(from_tf) = l.lidar_mount_from_tf {
                ds.sensor_mount_from_recordings = from_tf && (ds.runs.is_empty() || ds.sensor_mount_from_recordings);
            }
            ds.runs.extend(l.runs);
            ds.skipped.extend(l.skipped);
            ds.notes.extend(l.notes);
            ds.ground_truth_clocks.extend(l.clock);

            Ok(())
        }
        Err(e) if opts.skip_invalid => {
            ds.skipped.push(Skipped { source: source.display().to_string(), reason: e.to_string() });
            Ok(())
        }
        Err(e) => Err(e),
    }
}
