//! What the paths given to `load` hold, one input at a time: a CSV run, an MCAP bag, a rosbag2 folder, a
//! ROS 1 bag or an OptiOdom set (folders expanded, names repeated noted), and reading one of them into
//! runs, notes and its ground truth's clock.

use super::{
    DatasetError, LoadOptions, Note, SUPPORTED, Skipped, check_size, csv, ground_truth, lidar_reference, mcap,
    optiodom, ros1, rosbag2,
};
use crate::api::settings::named;
use omni_kin::{RobotGeometry, Run};
use std::path::{Path, PathBuf};

/// One thing to read: it gives runs on its own.
#[derive(Clone, Debug)]
pub(super) enum Input {
    /// An omnical CSV run.
    Csv(PathBuf),
    /// A bare MCAP file.
    Mcap(PathBuf),
    /// A bare rosbag2 sqlite3 file.
    Db3(PathBuf),
    /// A rosbag2 recording folder (metadata.yaml).
    Recording(PathBuf),
    /// A ROS 1 bag.
    Ros1(PathBuf),
    /// An OptiOdom set folder.
    OptiOdom(PathBuf),
}

impl Input {
    pub(super) fn path(&self) -> &Path {
        match self {
            Self::Csv(p) | Self::Mcap(p) | Self::Db3(p) | Self::Recording(p) | Self::Ros1(p) | Self::OptiOdom(p) => p,
        }
    }
}

/// What one input gave.
#[derive(Debug, Default)]
pub(super) struct Loaded {
    pub(super) runs: Vec<Run>,
    pub(super) skipped: Vec<Skipped>,
    pub(super) notes: Vec<Note>,
    /// The robot type and design geometry the input declares (an OptiOdom set).
    pub(super) declared: Option<(&'static str, RobotGeometry)>,
    pub(super) clock: Option<ground_truth::GtClock>,
    /// The Unix second a recording's run times count from (`None`: CSV and OptiOdom runs, whose times are
    /// their own).
    pub(super) origin_s: Option<i64>,
    /// With a lidar reference: whether its path was moved to the base by the recording's static transforms.
    pub(super) lidar_mount_from_tf: Option<bool>,
    /// A recording's scans read with its wheels (`--gt-scans`), for [`lidar_reference::with_lidar_path`].
    pub(super) scans: Option<mcap::ScanRead>,
}

/// The recording's name, for matching ground-truth files: a folder's name, a file's stem.
pub(super) fn recording_name(p: &Path, folder: bool) -> String {
    let name = if folder { p.file_name() } else { p.file_stem() };
    name.map_or_else(|| p.display().to_string(), |s| s.to_string_lossy().into_owned())
}

/// The inputs under some paths, in order, each file and folder taken once.
#[derive(Debug, Default)]
pub(super) struct Inputs {
    /// The inputs, and the paths that are none, in their places.
    pub(super) list: Vec<Result<Input, DatasetError>>,
    /// The files and folders taken, by their real path (symbolic links resolved).
    pub(super) seen: std::collections::HashSet<PathBuf>,
    /// Paths passed over because they lead to a file or folder already taken (a symbolic link to a folder
    /// above it, or to a file beside it; a path given twice).
    pub(super) repeated: Vec<PathBuf>,
}

impl Inputs {
    /// The inputs under `paths`, in order.
    pub(super) fn of(paths: &[PathBuf]) -> Self {
        let mut inputs = Self::default();
        for p in paths {
            expand(p, &mut inputs);
        }
        inputs
    }

    /// The note on paths passed over because they repeat a file or folder already read.
    pub(super) fn repeated_note(&self) -> Option<Note> {
        let first = self.repeated.first()?;
        Some(Note::general(format!(
            "{} path{} lead{} to files or folders already read (symbolic links, or a path given twice), first {}: \
             each file is read once",
            self.repeated.len(),
            if self.repeated.len() == 1 { "" } else { "s" },
            if self.repeated.len() == 1 { "s" } else { "" },
            first.display()
        )))
    }
}

/// The inputs under `p`, in order: a folder's entries sorted by name, recursively; a recording folder or an
/// OptiOdom set is one input. A path that is no input is an error in its place; a file or folder already
/// taken (through a symbolic link, or given twice) is passed over and listed in [`Inputs::repeated`].
pub(super) fn expand(p: &Path, out: &mut Inputs) {
    let meta = match std::fs::metadata(p) {
        Ok(m) => m,
        Err(e) => return out.list.push(Err(DatasetError::io(p, e))),
    };
    if let Ok(real) = std::fs::canonicalize(p)
        && !out.seen.insert(real)
    {
        return out.repeated.push(p.to_path_buf());
    }
    if meta.is_dir() {
        if optiodom::metadata_file(p).is_some() {
            return out.list.push(Ok(Input::OptiOdom(p.to_path_buf())));
        }
        if rosbag2::is_recording(p) {
            return out.list.push(Ok(Input::Recording(p.to_path_buf())));
        }
        let entries = match std::fs::read_dir(p) {
            Ok(entries) => entries,
            Err(e) => return out.list.push(Err(DatasetError::io(p, e))),
        };
        let mut entries: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|q| {
                q.is_dir() || q.extension().is_some_and(|e| e == "csv" || e == "mcap" || e == "db3" || e == "bag")
            })
            .collect();
        entries.sort();
        for e in entries {
            expand(&e, out);
        }
        return;
    }
    out.list.push(match p.extension().and_then(|e| e.to_str()) {
        Some("csv") => Ok(Input::Csv(p.to_path_buf())),
        Some("mcap") => Ok(Input::Mcap(p.to_path_buf())),
        Some("db3") => Ok(Input::Db3(p.to_path_buf())),
        Some("bag") => Ok(Input::Ros1(p.to_path_buf())),
        _ => Err(DatasetError::file(p, format!("unsupported input (expected {SUPPORTED})"))),
    });
}

/// A ROS recording's read as a [`Loaded`].
pub(super) fn from_bag(r: mcap::McapRead) -> Loaded {
    Loaded {
        runs: r.runs,
        skipped: r.skipped.into_iter().map(|(source, reason)| Skipped { source, reason }).collect(),
        notes: r.notes,
        declared: None,
        clock: r.ground_truth_clock,
        origin_s: Some(r.origin_s),
        lidar_mount_from_tf: None,
        scans: r.scans,
    }
}

/// Reads one input. The outer error always stops the load (a file above the size cap); the inner one is
/// the input's own failure, which [`merge`] lists as skipped under `skip_invalid`.
pub(super) fn read_input(input: &Input, opts: &LoadOptions) -> Result<Result<Loaded, DatasetError>, DatasetError> {
    let mo = mcap::McapOptions {
        skip_invalid: opts.skip_invalid,
        recorded_odometry: opts.recorded_odometry,
        // The scans are read in the same pass as the wheels.
        scan_topic: opts.scans.as_ref().map(|(topic, _)| topic.clone()),
        ..opts.mcap.clone()
    };
    // The lidar's path as a ROS recording's ground truth, when --gt-scans is given.
    let lidar = |p: &Path, l: Loaded| match &opts.scans {
        Some((topic, settings)) => {
            let mount =
                if opts.scan_mount_given { lidar_reference::Mount::Given } else { lidar_reference::Mount::Stated };
            lidar_reference::with_lidar_path(p, (topic, settings), mount, l)
        }
        None => Ok(l),
    };
    // The ground-truth file of a ROS recording, when --gt is given.
    let truth = |p: &Path, folder: bool| -> Result<Option<ground_truth::ExternalTruth>, DatasetError> {
        opts.ground_truth.as_ref().map(|g| ground_truth::read_for(g, p, &recording_name(p, folder))).transpose()
    };
    refuse_foreign_reference(input, opts)?;
    match input {
        Input::Csv(p) if opts.ground_truth.is_some() => {
            check_size(p, opts.max_file_bytes)?;
            Ok(csv_with_gt(p, opts))
        }
        Input::Csv(p) => {
            check_size(p, opts.max_file_bytes)?;
            Ok(csv::read_run_for(p, opts.ticks_per_rev, &opts.csv_joints).map(|r| Loaded {
                runs: vec![if opts.recorded_odometry { r } else { r.without_recorded_odometry() }],
                ..Default::default()
            }))
        }
        Input::Mcap(p) => {
            check_size(p, opts.max_file_bytes)?;
            Ok(truth(p, false)
                .and_then(|t| mcap::read_file_with_truth(p, &mo, t.as_ref()))
                .map(from_bag)
                .and_then(|l| lidar(p, l)))
        }
        Input::Db3(p) => Ok(truth(p, false)
            .and_then(|t| rosbag2::read_db3(p, &mo, opts.max_file_bytes, t.as_ref()))
            .map(from_bag)
            .and_then(|l| lidar(p, l))),
        Input::Ros1(p) => {
            check_size(p, opts.max_file_bytes)?;
            Ok(truth(p, false).and_then(|t| ros1::read_bag(p, &mo, t.as_ref())).map(from_bag).and_then(|l| lidar(p, l)))
        }
        Input::Recording(p) => Ok(truth(p, true)
            .and_then(|t| rosbag2::read_recording(p, &mo, opts.max_file_bytes, t.as_ref()))
            .map(from_bag)
            .and_then(|l| lidar(p, l))),
        Input::OptiOdom(p) => {
            // The set's runs are checked one by one (skipped under skip_invalid); a failure of the set
            // itself stops the load.
            let mut skipped = Vec::new();
            let set = optiodom::read_set(p, |e| {
                if opts.skip_invalid {
                    skipped.push(Skipped { source: p.display().to_string(), reason: e.to_string() });
                    Ok(())
                } else {
                    Err(e)
                }
            })?;
            let declared = Some((set.kind, set.robot));
            Ok(Ok(Loaded { runs: set.runs, skipped, declared, ..Default::default() }))
        }
    }
}

/// Refuses a reference that does not go with `input`: end poses or lidar scans for a CSV run or an OptiOdom
/// set, a `--gt` file for an OptiOdom set (which has its own).
pub(super) fn refuse_foreign_reference(input: &Input, opts: &LoadOptions) -> Result<(), DatasetError> {
    if opts.mcap.wheels_only && matches!(input, Input::Csv(_) | Input::OptiOdom(_)) {
        return Err(DatasetError::file(
            input.path(),
            "measured end poses (--gt-kind end-pose) and lidar scans (--gt-scans) go with ROS recordings (.mcap, \
             .db3, rosbag2 folders, .bag); this input carries its own ground truth",
        ));
    }
    if opts.ground_truth.is_some() && matches!(input, Input::OptiOdom(_)) {
        return Err(DatasetError::file(
            input.path(),
            format!(
                "{} gives the ground truth of ROS recordings (.mcap, .db3, rosbag2 folders, .bag) and of CSV runs \
                 without pose columns; an OptiOdom set has its own",
                named("gt")
            ),
        ));
    }
    Ok(())
}

/// A CSV run without pose columns with its ground truth from `--gt` (the file named after it, or the
/// folder's file that covers it), on the wheel clock as a recording's ([`mcap::assembly::truth_for_wheels`]).
pub(super) fn csv_with_gt(p: &Path, opts: &LoadOptions) -> Result<Loaded, DatasetError> {
    let Some(gt) = opts.ground_truth.as_ref() else {
        return Err(DatasetError::file(p, format!("no {} given", named("gt"))));
    };
    let stem = recording_name(p, false);
    let ext = ground_truth::read_for(gt, p, &stem)?;
    let (mut notes, mut clock) = (Vec::new(), None);
    let mut attach = |t_s: &[f64], rad_s: &[f64], n: usize| {
        let (poses, c) = mcap::assembly::truth_for_wheels(p, &ext, &stem, t_s, rad_s, n, &mut notes)?;
        clock = Some(c);
        Ok(poses)
    };
    let mut run = csv::read_run_with_truth(p, opts.ticks_per_rev, &opts.csv_joints, &mut attach)?;
    if ext.position_only {
        let data = omni_kin::RunData { truth_position_only: true, ..run.into_data() };
        run = omni_kin::Run::new(data).map_err(|e| DatasetError::file(p, e.to_string()))?;
    }
    let run = if opts.recorded_odometry { run } else { run.without_recorded_odometry() };
    Ok(Loaded { runs: vec![run], notes, clock, ..Default::default() })
}
