//! `omnical config`: the values a command would use here, each with where it came from: the command line,
//! the project file (`omnical.toml`, [`crate::project_file`]), the robot description (`robot.toml`,
//! [`crate::robot_file`]) with its line, or the built-in default. Precedence, highest first: command
//! line, omnical.toml (a `[command]` table over its top level), robot.toml, default.

use super::{DataArgs, OutputArgs};
use crate::cli::choice;
use crate::project_file::{self, ProjectFile};
use crate::robot_file::{self, RobotFile, Source};
use omni_ga::calibrate::Preset;
use omni_kin::cost::CostName;
use std::path::{Path, PathBuf};

/// Arguments of `omnical config`. The values shown are those `omnical train` would use with the same
/// options (the project file's `[train]` table included).
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Run files or folders: the robot.toml beside them is looked for as the other commands do.
    pub runs: Vec<PathBuf>,
    /// Training recipe (to see a flag override the files).
    #[arg(long, value_parser = choice::<Preset>())]
    pub preset: Option<Preset>,
    /// Seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Training objective.
    #[arg(long, value_parser = choice::<CostName>())]
    pub objective: Option<CostName>,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
    /// Data options.
    #[command(flatten)]
    pub data: DataArgs,
}

/// One value and where it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The key, as in omnical.toml (`joints_topic`).
    pub key: String,
    /// The value as shown.
    pub value: String,
    /// `command line`, `omnical.toml:3`, `robot.toml:12`, `default`.
    pub source: String,
}

const COMMAND_LINE: &str = "command line";
/// The command whose view is shown: the one that takes the most of these settings.
const SHOWN_FOR: &str = "train";
const DEFAULT: &str = "default";

/// The layers one key is looked up in.
struct Layers<'a> {
    project: Option<&'a ProjectFile>,
    robot: Option<&'a RobotFile>,
}

impl Layers<'_> {
    /// A key's value: the flag, else the project file's (its `[train]` table, else its top level), else
    /// the robot description's value at `field` (a TOML path), else `default`.
    fn row(
        &self,
        key: &str,
        flag: Option<String>,
        robot: Option<(&str, Option<String>)>,
        default: impl Into<String>,
    ) -> Row {
        let row = |value: String, source: String| Row { key: key.to_string(), value, source };
        if let Some(v) = flag {
            return row(v, COMMAND_LINE.into());
        }
        if let Some((p, s)) = self.project.and_then(|p| Some(p).zip(p.get(SHOWN_FOR, key))) {
            return row(s.values.join(", "), p.at(s));
        }
        if let (Some(r), Some((field, Some(v)))) = (self.robot, robot) {
            return row(v, robot_source(r, field));
        }
        row(default.into(), DEFAULT.into())
    }
}

/// `robot.toml:LINE` of a field, or the built-in robot's name.
fn robot_source(r: &RobotFile, field: &str) -> String {
    match &r.source {
        Source::Flag(p) | Source::Discovered(p) => match robot_file::line_of_field(p, field) {
            Some(line) => format!("{}:{line}", p.display()),
            None => p.display().to_string(),
        },
        Source::Builtin => format!("{} (built in)", robot_file::BUILTIN_APR02),
    }
}

/// Which robot description: `--robot`, the project file's `robot`, a robot.toml found, or none.
fn robot_row(flag: Option<&str>, robot: Option<&RobotFile>, project: Option<&ProjectFile>) -> Row {
    let row = |value: String, source: String| Row { key: "robot".into(), value, source };
    if let Some(v) = flag {
        return row(v.to_string(), COMMAND_LINE.into());
    }
    if let Some((p, s)) = project.and_then(|p| Some(p).zip(p.get(SHOWN_FOR, "robot"))) {
        return row(s.values.join(", "), p.at(s));
    }
    match robot.map(|r| &r.source) {
        Some(Source::Discovered(path)) => {
            row(path.display().to_string(), "found beside the data or in the working directory".into())
        }
        Some(source) => row(source.to_string(), DEFAULT.into()),
        None => row("none".into(), DEFAULT.into()),
    }
}

/// The rows `omnical config` shows.
///
/// long: a flat table, one row per setting in the order `omnical config` prints them, each naming its layers.
pub fn rows(a: &Args, threads: Option<usize>, project: Option<&ProjectFile>) -> anyhow::Result<Vec<Row>> {
    let d = &a.data;
    let from_project = |key: &str| project.and_then(|p| p.get(SHOWN_FOR, key)).map(|s| s.values.join(", "));
    let robot_flag = d.robot.robot.clone().or_else(|| from_project("robot"));
    let robot = robot_file::resolve(robot_flag.as_deref(), &a.runs)?;
    let layers = Layers { project, robot: robot.as_ref() };
    let desc = robot.as_ref().map(|r| &r.description);
    let topic = |f: fn(&omni_kin::robot::Topics) -> &Option<String>| desc.and_then(|r| f(&r.topics).clone());
    let frame = |f: fn(&omni_kin::robot::Frames) -> &Option<String>| desc.and_then(|r| f(&r.frames).clone());
    let gt = desc.and_then(|r| r.ground_truth.as_ref());
    let joints_field = match desc.map(|r| r.kind) {
        Some(omni_kin::robot::BaseKind::Diff) => "diff.left_joint",
        _ => "wheels[0].joint",
    };
    let mut rows = vec![
        robot_row(d.robot.robot.as_deref(), robot.as_ref(), project),
        layers.row(
            "joints",
            d.joints.as_ref().map(|j| j.join(", ")),
            Some((joints_field, desc.map(|r| r.joints().join(", ")))),
            "wheel_a, wheel_b, wheel_c",
        ),
        layers.row(
            "joints_topic",
            d.joints_topic.clone(),
            Some(("topics.joint_states", topic(|t| &t.joint_states))),
            "the only JointState topic",
        ),
        layers.row(
            "gt_topic",
            d.gt_topic.clone(),
            Some(("topics.ground_truth", topic(|t| &t.ground_truth))),
            "the only map/world-frame pose source",
        ),
        layers.row(
            "command_topic",
            None,
            Some(("topics.command", topic(|t| &t.command))),
            "/cmd_vel, else the only Twist/TwistStamped topic",
        ),
        layers.row(
            "gt_parent_frame",
            d.gt_parent_frame.clone(),
            Some(("frames.ground_truth_parent", frame(|f| &f.ground_truth_parent))),
            "any",
        ),
        layers.row(
            "gt_child_frame",
            d.gt_child_frame.clone(),
            Some(("frames.ground_truth_child", frame(|f| &f.ground_truth_child))),
            "any",
        ),
        layers.row(
            "gt",
            d.gt.as_ref().map(|p| p.display().to_string()),
            Some(("ground_truth.file", gt.and_then(|g| g.file.clone()))),
            "a topic of the recording",
        ),
        layers.row(
            "gt_time_offset",
            d.gt_time_offset.map(|s| format!("{s} s")),
            Some(("ground_truth.time_offset_s", gt.and_then(|g| g.time_offset_s).map(|s| format!("{s} s")))),
            "estimated from the data",
        ),
    ];
    rows.extend(reference_rows(&layers, d));
    rows.extend([
        layers.row("split", d.split.map(|s| s.to_string()), None, "none: one file is one run"),
        layers.row("preset", a.preset.map(|p| p.id().to_string()), None, Preset::default().id()),
        layers.row("seed", a.seed.map(|s| s.to_string()), None, "0 (train), 7 (simulate)"),
        layers.row("objective", a.objective.map(|o| o.id().to_string()), None, "the preset's"),
        layers.row(
            "threads",
            threads.map(|n| n.to_string()),
            None,
            format!("all cores ({})", rayon::current_num_threads()),
        ),
    ]);
    // What the project file sets for one command only.
    for s in project.iter().flat_map(|p| p.settings.iter().filter(|s| s.command.is_some()).map(move |s| (p, s))) {
        let (p, s) = s;
        let key = format!("{}.{}", s.command.as_deref().unwrap_or_default(), s.key);
        rows.push(Row { key, value: s.values.join(", "), source: p.at(s) });
    }
    Ok(rows)
}

/// The rows of what the ground truth measures: its kind, a relative reference's window, the mount.
fn reference_rows(layers: &Layers<'_>, d: &super::DataArgs) -> [Row; 4] {
    [
        layers.row("gt_kind", d.gt_kind.map(|k| k.id().to_string()), None, "absolute"),
        layers.row("gt_window", d.gt_window.map(|s| format!("{s} s")), None, "4 s (relative references)"),
        layers.row(
            "gt_mount",
            d.gt_mount.map(|m| format!("{} m, {} m, {}°", m.x_m, m.y_m, m.theta_rad.to_degrees())),
            None,
            "fitted (relative references)",
        ),
        layers.row(
            "gt_mount_start",
            d.gt_mount_start.map(|m| format!("{} m, {} m, {}°", m.x_m, m.y_m, m.theta_rad.to_degrees())),
            None,
            "found from the motions (relative references)",
        ),
    ]
}

/// Runs `omnical config`: the rows as a table on stdout.
pub fn run(a: &Args, threads: Option<usize>, config: Option<&Path>) -> anyhow::Result<()> {
    let cwd = std::env::current_dir().unwrap_or_default();
    let project = project_file::find(config, &cwd)?;
    if let Some(p) = &project {
        // The same checks as every other command makes (each value against its option).
        use clap::CommandFactory;
        project_file::apply(crate::cli::Cli::command(), p)?;
    }
    let rows = rows(a, threads, project.as_ref())?;
    if a.output.json {
        let settings: Vec<_> =
            rows.iter().map(|r| serde_json::json!({"key": r.key, "value": r.value, "source": r.source})).collect();
        let file = project.as_ref().map(|p| p.path.display().to_string());
        return super::print_json("config", serde_json::json!({"settings": settings, "project_file": file}));
    }
    let w_key = rows.iter().map(|r| r.key.len()).max().unwrap_or(0).max(3);
    let w_value = rows.iter().map(|r| r.value.chars().count()).max().unwrap_or(0).max(5);
    println!("{:w_key$}  {:w_value$}  from", "key", "value");
    for r in &rows {
        let pad = w_value.saturating_sub(r.value.chars().count());
        println!("{:w_key$}  {}{}  {}", r.key, r.value, " ".repeat(pad), r.source);
    }
    match &project {
        Some(p) => {
            println!("\nproject file: {} (command line > omnical.toml > robot.toml > default)", p.path.display())
        }
        None => println!(
            "\nno project file ({} in the working directory or --config FILE); command line > robot.toml > default",
            project_file::FILE_NAME
        ),
    }
    Ok(())
}
