//! Subcommand implementations: load, call the library, format.

pub mod config;
pub mod demo;
pub mod diagnose;
pub mod eval;
pub mod explore;
pub mod export;
pub mod held_out;
pub mod init;
pub mod plan;
pub mod report;
pub mod shell;
pub mod sim_spec;
pub mod simulate;
pub mod train;

use crate::dataset::{self, Dataset, LoadOptions};
use crate::robot_file;
use omni_kin::FittedModel;
use std::path::PathBuf;

/// Arguments of `omnical fleet`, which the Python wheel's console command runs (omnical.fleet, on Dask);
/// the native binary only says where to find it.
#[derive(Debug, clap::Args)]
pub struct FleetArgs {
    /// FLEET_DIR and the options of the wheel's `omnical fleet --help`.
    #[arg(trailing_var_arg = true, allow_hyphen_values = true, value_name = "ARGS")]
    pub args: Vec<String>,
}

/// The error of a Python-side command asked of the native binary.
pub fn python_only(what: &str) -> anyhow::Error {
    anyhow::anyhow!(
        "{what} runs on Dask from the Python wheel: `pip install \"omnical[fleet]\"` (or `pip install \".[fleet]\"` \
         from the repository) and run the `omnical` command it installs; this native binary has no Python"
    )
}

/// Version of the layout of every `--json` document (docs/json.md): each carries it as `schema_version`,
/// with the command's name as `command`. Raised when a field changes meaning or is removed.
pub const JSON_SCHEMA_VERSION: u32 = 1;

/// Commands that produce no results of their own, so take no `--json`: `fleet` (the Python wheel's),
/// `completions` and `man` (their output is a script and a man page).
/// Every other subcommand flattens [`OutputArgs`]; tests/json.rs checks both lists against the parser.
pub const WITHOUT_RESULTS: &[&str] = &["fleet", "completions", "man"];

/// The output options of every command that produces results (one definition, flattened into each).
#[derive(Debug, Default, Clone, Copy, clap::Args)]
pub struct OutputArgs {
    /// Print the results as one JSON document on stdout instead of text (`schema_version`, `command`, and
    /// the command's fields, SI units: docs/json.md). Notes and progress stay on stderr.
    #[arg(long)]
    pub json: bool,
}

/// Prints `doc` (a JSON object) on stdout, pretty, with `schema_version` and `command` added.
pub fn print_json(command: &str, doc: serde_json::Value) -> anyhow::Result<()> {
    println!("{}", serde_json::to_string_pretty(&json_document(command, doc)?)?);
    Ok(())
}

/// `doc` with `schema_version` ([`JSON_SCHEMA_VERSION`]) and `command` added.
pub fn json_document(command: &str, doc: serde_json::Value) -> anyhow::Result<serde_json::Value> {
    let serde_json::Value::Object(mut fields) = doc else {
        anyhow::bail!("the --json document of {command} is not an object (a bug)");
    };
    fields.insert("schema_version".into(), JSON_SCHEMA_VERSION.into());
    fields.insert("command".into(), command.into());
    Ok(serde_json::Value::Object(fields))
}

/// The help heading of [`DataArgs`].
pub const DATA_OPTIONS: &str = "Data options";

/// The robot the data was recorded on (docs/formats.md, "Robot description").
#[derive(Debug, Default, clap::Args)]
pub struct RobotArgs {
    /// The robot description: a robot.toml file, or `apr02` for the paper's robot. Default: a robot.toml
    /// beside the data (the first RUNS argument's folder) or in the working directory.
    #[arg(long, value_name = "FILE|apr02")]
    pub robot: Option<String>,
}

/// Options shared by commands that read runs, listed under "Data options" in every command's help.
#[derive(Debug, clap::Args)]
#[command(next_help_heading = DATA_OPTIONS)]
pub struct DataArgs {
    /// The robot description (design geometry, joint names, topics).
    #[command(flatten)]
    pub robot: RobotArgs,
    /// Wheel joint names in wheel order (MCAP JointState), comma-separated. Default: the robot
    /// description's joints, else wheel_a,wheel_b,wheel_c.
    #[arg(long, value_delimiter = ',')]
    pub joints: Option<Vec<String>>,
    /// MCAP topic of the wheel JointState (default: the only one).
    #[arg(long)]
    pub joints_topic: Option<String>,
    /// MCAP topic of the ground truth (default: the only map/world-frame pose source).
    #[arg(long)]
    pub gt_topic: Option<String>,
    /// Parent frame of the ground truth in a TF topic (MCAP), e.g. `map`.
    #[arg(long)]
    pub gt_parent_frame: Option<String>,
    /// Child frame of the ground truth in a TF topic (MCAP), e.g. `base_link`.
    #[arg(long)]
    pub gt_child_frame: Option<String>,
    /// Ground truth from a separate file instead of a topic: a TUM (`t x y z qx qy qz qw`) or CSV file for
    /// one recording, or a folder of files named after the recordings (`rec.tum`, `rec.csv`). Default: the
    /// robot description's `[ground_truth] file`, else a topic of the recording.
    #[arg(long, value_name = "FILE|DIR")]
    pub gt: Option<PathBuf>,
    /// Clock offset of the `--gt` file: wheel time = ground-truth time + SECONDS (s). Default: estimated from
    /// the data (reported with its standard error).
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true)]
    pub gt_time_offset: Option<f64>,
    /// CSV columns of the `--gt` file, e.g. `t=stamp_ns,x=pos_x_mm,y=pos_y_mm,yaw=heading_deg` (default t, x,
    /// y, yaw, or a quaternion qx, qy, qz, qw).
    #[arg(long, value_delimiter = ',', value_name = "KEY=COLUMN")]
    pub gt_columns: Vec<String>,
    /// Units of the `--gt` CSV columns, e.g. `time=ns,length=mm,angle=deg` (default s, m, rad).
    #[arg(long, value_delimiter = ',', value_name = "KEY=UNIT")]
    pub gt_units: Vec<String>,
    /// Cut MCAP files into runs where the robot stands still at least this long (s).
    #[arg(long)]
    pub split: Option<f64>,
    /// Skip runs that fail to load (they are listed) instead of stopping.
    #[arg(long)]
    pub skip_invalid: bool,
    /// Encoder ticks per wheel revolution, for CSV files with tick columns.
    #[arg(long)]
    pub ticks_per_rev: Option<f64>,
    /// Refuse input files (CSV, MCAP) larger than this (MiB); each is read into memory whole.
    #[arg(long, value_name = "MIB", default_value_t = dataset::DEFAULT_MAX_FILE_BYTES >> 20)]
    pub max_file_mb: u64,
}

impl Default for DataArgs {
    /// No flag given: what the command line parses from no data options.
    fn default() -> Self {
        Self {
            robot: RobotArgs::default(),
            joints: None,
            joints_topic: None,
            gt_topic: None,
            gt_parent_frame: None,
            gt_child_frame: None,
            gt: None,
            gt_time_offset: None,
            gt_columns: Vec::new(),
            gt_units: Vec::new(),
            split: None,
            skip_invalid: false,
            ticks_per_rev: None,
            max_file_mb: dataset::DEFAULT_MAX_FILE_BYTES >> 20,
        }
    }
}

/// Load runs from files/folders, printing what was skipped or noticed on stderr. The runs' recorded
/// odometry is left out (no command but `export` shows it, and it would take as much memory as the wheel
/// data).
pub fn load_runs(paths: &[PathBuf], data: &DataArgs) -> anyhow::Result<Dataset> {
    let ds = load(paths, data, false)?;
    say_load_notes(&[&ds]);
    Ok(ds)
}

/// [`load_runs`], keeping the runs' recorded odometry.
pub fn load_runs_with_odometry(paths: &[PathBuf], data: &DataArgs) -> anyhow::Result<Dataset> {
    let ds = load(paths, data, true)?;
    say_load_notes(&[&ds]);
    Ok(ds)
}

/// Training runs and held-out runs (`None` when `held_out` is empty), read as [`load_runs`] does, with the
/// notes of both said once: a note both sets raise is one line with the count of every file.
pub fn load_with_held_out(
    runs: &[PathBuf],
    held_out: &[PathBuf],
    data: &DataArgs,
) -> anyhow::Result<(Dataset, Option<Dataset>)> {
    let train = load(runs, data, false)?;
    let held = if held_out.is_empty() { None } else { Some(load(held_out, data, false)?) };
    if let Some(h) = &held {
        dataset::check_same_robot(train.robot_kind.as_ref(), h.robot_kind.as_ref())?;
    }
    say_load_notes(&[Some(&train), held.as_ref()].into_iter().flatten().collect::<Vec<_>>());
    Ok((train, held))
}

fn load(paths: &[PathBuf], data: &DataArgs, recorded_odometry: bool) -> anyhow::Result<Dataset> {
    let started = std::time::Instant::now();
    let robot = robot_file::resolve(data.robot.robot.as_deref(), paths)?;
    if let Some(r) = &robot {
        robot_file::announce(&r.source);
    }
    let ds = load_for_robot(paths, data, recorded_odometry, robot)?;
    tracing::info!(
        "read {} run{} from {} in {:.2} s",
        ds.runs.len(),
        if ds.runs.len() == 1 { "" } else { "s" },
        paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "),
        started.elapsed().as_secs_f64()
    );
    Ok(ds)
}

/// Reads runs as [`load_runs`] does for the robot `robot` (resolved from `data` by
/// [`robot_file::resolve`]: its joints, topics and ground-truth file fill what `data` leaves open), printing
/// nothing: notes, skipped inputs and ground-truth clocks stay in the dataset. The Python binding's `load`.
pub fn load_for_robot(
    paths: &[PathBuf],
    data: &DataArgs,
    recorded_odometry: bool,
    robot: Option<robot_file::RobotFile>,
) -> anyhow::Result<Dataset> {
    let mut mcap = dataset::mcap::McapOptions {
        wheel_joints: data.joints.clone().unwrap_or_default(),
        joints_topic: data.joints_topic.clone(),
        truth_topic: data.gt_topic.clone(),
        truth_parent_frame: data.gt_parent_frame.clone(),
        truth_child_frame: data.gt_child_frame.clone(),
        split: data.split,
        skip_invalid: data.skip_invalid,
        recorded_odometry,
        ..Default::default()
    };
    robot_file::fill_mcap_options(&mut mcap, data.joints.is_none(), robot.as_ref().map(|r| &r.description));
    let opts = LoadOptions {
        skip_invalid: data.skip_invalid,
        ticks_per_rev: data.ticks_per_rev,
        mcap,
        recorded_odometry,
        max_file_bytes: data.max_file_mb.saturating_mul(1 << 20),
        ground_truth: ground_truth_options(data, robot.as_ref())?,
        csv_joints: csv_joints(data, robot.as_ref()),
    };
    let mut ds = dataset::load(paths, &opts)?;
    ds.robot_file = robot;
    Ok(ds)
}

/// The joints CSV runs are read by: `--joints`, else a robot description file's. The built-in `apr02`'s
/// names are the simulator's placeholders, so with it each file keeps its own column order.
fn csv_joints(data: &DataArgs, robot: Option<&robot_file::RobotFile>) -> Vec<String> {
    let from_file = robot.filter(|r| r.source != robot_file::Source::Builtin).map(|r| r.description.joints());
    data.joints.clone().or(from_file).unwrap_or_default()
}

/// Says the datasets' notes on stderr, each distinct note once with the count of the files that raised it
/// (the same note from many files differs only in the file name before its first `: `), then skipped
/// inputs (shown even with `-q`) and ground-truth clocks.
fn say_load_notes(sets: &[&Dataset]) {
    let mut seen: Vec<(&str, &str, usize)> = Vec::new();
    for n in sets.iter().flat_map(|ds| &ds.notes) {
        let key = n.split_once(": ").map_or(n.as_str(), |(_, rest)| rest);
        match seen.iter_mut().find(|(k, _, _)| *k == key) {
            Some(entry) => entry.2 += 1,
            None => seen.push((key, n, 1)),
        }
    }
    for (_, first, count) in seen {
        match count {
            1 => crate::note!("note: {first}"),
            2 => crate::note!("note: {first} (and 1 more file)"),
            _ => crate::note!("note: {first} (and {} more files)", count - 1),
        }
    }
    for s in sets.iter().flat_map(|ds| &ds.skipped) {
        tracing::warn!(target: crate::logging::NOTE, "skipped {}: {}", s.source, s.reason);
    }
    for c in sets.iter().flat_map(|ds| &ds.ground_truth_clocks) {
        crate::note!("{}", c.describe());
    }
}

/// `--gt` and its options, over the robot description's `[ground_truth]` (its `file` relative to the
/// description's folder).
fn ground_truth_options(
    data: &DataArgs,
    robot: Option<&robot_file::RobotFile>,
) -> anyhow::Result<Option<dataset::ground_truth::GroundTruthOptions>> {
    let from_robot = robot.and_then(|r| r.description.ground_truth.as_ref().map(|g| (r, g)));
    let path = match (&data.gt, from_robot.and_then(|(r, g)| g.file.as_ref().map(|f| (r, f)))) {
        (Some(p), _) => p.clone(),
        (None, Some((r, file))) => match &r.source {
            robot_file::Source::Flag(p) | robot_file::Source::Discovered(p) => {
                p.parent().unwrap_or(std::path::Path::new("")).join(file)
            }
            robot_file::Source::Builtin => PathBuf::from(file),
        },
        (None, None) => return Ok(None),
    };
    let mut csv = dataset::ground_truth::CsvColumns::default();
    let settings = |list: &[String]| -> Vec<(String, String)> {
        list.iter()
            .filter_map(|kv| kv.split_once('=').map(|(k, v)| (k.trim().to_string(), v.trim().to_string())))
            .collect()
    };
    let (mut columns, mut units) = (Vec::new(), Vec::new());
    if let Some((_, g)) = from_robot {
        columns.extend(g.columns.iter().map(|(k, v)| (k.clone(), v.clone())));
        units.extend(g.units.iter().map(|(k, v)| (k.clone(), v.clone())));
    }
    for kv in data.gt_columns.iter().chain(&data.gt_units) {
        anyhow::ensure!(kv.contains('='), "--gt-columns/--gt-units {kv:?}: expected KEY=VALUE");
    }
    columns.extend(settings(&data.gt_columns));
    units.extend(settings(&data.gt_units));
    for (k, v) in &columns {
        csv.set_column(k, v).map_err(anyhow::Error::msg)?;
    }
    for (k, v) in &units {
        csv.set_unit(k, v).map_err(anyhow::Error::msg)?;
    }
    let time_offset_s = data.gt_time_offset.or(from_robot.and_then(|(_, g)| g.time_offset_s));
    Ok(Some(dataset::ground_truth::GroundTruthOptions { path, time_offset_s, csv }))
}

/// `design` / `paper` or a model file ([`crate::design::resolve`]), for the data's robot.
pub fn resolve_model(spec: &str, ds: &Dataset) -> anyhow::Result<FittedModel> {
    crate::design::resolve(spec, ds)
}

/// The wheel joint names the runs were read with: `--joints`, else the robot description's, else the
/// default `wheel_a`, `wheel_b`, `wheel_c`.
pub fn wheel_joints(data: &DataArgs, ds: &Dataset) -> Vec<String> {
    let mut mcap =
        dataset::mcap::McapOptions { wheel_joints: data.joints.clone().unwrap_or_default(), ..Default::default() };
    robot_file::fill_mcap_options(&mut mcap, data.joints.is_none(), ds.robot_file.as_ref().map(|r| &r.description));
    mcap.wheel_joints
}
