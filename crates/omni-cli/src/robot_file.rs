//! Robot description files (`robot.toml`, schema in docs/formats.md and [`omni_kin::robot`]): reading them
//! with errors that name the file, the line and the field; the built-in `apr02`; finding one beside the
//! data or in the working directory; writing one, with comments.
//!
//! Which robot a command uses, in this order: `--robot FILE|apr02`, the geometry the data declares
//! (OptiOdom metadata), a `robot.toml` found beside the data. A command that needs the design and finds
//! none refuses ([`no_design`]): there is no silent default robot.

use crate::dataset::Dataset;
use crate::dataset::mcap::McapOptions;
use omni_kin::RobotGeometry;
use omni_kin::robot::{BaseKind, RobotDescription, RobotError};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The file name looked for beside the data and in the working directory.
pub const FILE_NAME: &str = "robot.toml";
/// `--robot apr02`: the paper's robot, built in.
pub const BUILTIN_APR02: &str = "apr02";
/// A robot description is a few hundred bytes; anything above this is not one. Bytes.
const MAX_FILE_BYTES: u64 = 1 << 20;

/// Where a robot description came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Source {
    /// `--robot FILE`.
    Flag(PathBuf),
    /// `--robot apr02`.
    Builtin,
    /// A `robot.toml` found beside the data or in the working directory.
    Discovered(PathBuf),
}

impl std::fmt::Display for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Flag(p) => write!(f, "{}", p.display()),
            Self::Builtin => write!(f, "{BUILTIN_APR02} (built in: the paper's APR-02)"),
            Self::Discovered(p) => write!(f, "{} (found beside the data)", p.display()),
        }
    }
}

/// A robot description and where it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotFile {
    /// The description, validated.
    pub description: RobotDescription,
    /// Its source.
    pub source: Source,
}

impl RobotFile {
    /// The file it was read from (`None` for the built-in robot).
    pub fn path(&self) -> Option<&Path> {
        match &self.source {
            Source::Flag(p) | Source::Discovered(p) => Some(p),
            Source::Builtin => None,
        }
    }
}

/// What is wrong with a robot description file. Every variant names the file.
#[derive(Debug, Error)]
pub enum RobotFileError {
    /// The file could not be read.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        error: std::io::Error,
    },
    /// A problem at a field of the file.
    #[error("{path}: line {line}: {field}: {message}")]
    At {
        /// The file.
        path: PathBuf,
        /// Line of the field (1-based).
        line: usize,
        /// The field, as a TOML path (`wheels[2].radius_m`).
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A problem with the file as a whole (not TOML, too large, empty).
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

/// Parse and validate the text of a robot description; `path` names it in errors.
pub fn parse(text: &str, path: &Path) -> Result<RobotDescription, RobotFileError> {
    if let Some((line, field)) = crate::init::skeleton::first_mark(text) {
        return Err(RobotFileError::At {
            path: path.to_path_buf(),
            line,
            field,
            message: format!(
                "is still marked {} (a skeleton from omnical init): measure it, write its value and remove the mark",
                crate::init::skeleton::FILL_IN
            ),
        });
    }
    let d: RobotDescription = toml::from_str(text).map_err(|e| {
        let span = e.span().unwrap_or(0..0);
        match locate::path_at(text, &span) {
            Some(field) => RobotFileError::At {
                path: path.to_path_buf(),
                line: line_of(text, span.start),
                field,
                message: e.message().trim_end().to_string(),
            },
            // A syntax error outside any field: where it is, to the column.
            None => RobotFileError::File {
                path: path.to_path_buf(),
                message: format!("not TOML: {}", crate::toml_error::locate(text, &e)),
            },
        }
    })?;
    d.validate().map_err(|e| at_field(text, path, &e))?;
    Ok(d)
}

/// A validation error located in the text (the field's line, or its nearest enclosing table's).
fn at_field(text: &str, path: &Path, e: &RobotError) -> RobotFileError {
    let start = locate::span_of(text, &e.field).map_or(0, |s| s.start);
    RobotFileError::At {
        path: path.to_path_buf(),
        line: line_of(text, start),
        field: e.field.clone(),
        message: e.problem.to_string(),
    }
}

fn line_of(text: &str, offset: usize) -> usize {
    text.get(..offset).map_or(1, |s| s.matches('\n').count() + 1)
}

/// Read a robot description file.
pub fn read(path: &Path) -> Result<RobotDescription, RobotFileError> {
    let io = |error| RobotFileError::Io { path: path.to_path_buf(), error };
    let len = std::fs::metadata(path).map_err(io)?.len();
    if len > MAX_FILE_BYTES {
        return Err(RobotFileError::File {
            path: path.to_path_buf(),
            message: format!("{len} bytes is too large for a robot description (see docs/formats.md)"),
        });
    }
    let text = std::fs::read_to_string(path).map_err(io)?;
    parse(&text, path)
}

/// The line (1-based) of `field` (a TOML path such as `topics.joint_states` or `wheels[0].joint`) in the
/// robot description file at `path`, if the file reads and has it.
pub fn line_of_field(path: &Path, field: &str) -> Option<usize> {
    let text = std::fs::read_to_string(path).ok()?;
    locate::span_of(&text, field).map(|s| line_of(&text, s.start))
}

/// `--robot VALUE`: the built-in `apr02` or a file.
pub fn from_arg(value: &str) -> Result<RobotFile, RobotFileError> {
    if value == BUILTIN_APR02 {
        return Ok(RobotFile { description: RobotDescription::apr02(), source: Source::Builtin });
    }
    let path = PathBuf::from(value);
    Ok(RobotFile { description: read(&path)?, source: Source::Flag(path) })
}

/// The `robot.toml` for data at `runs`: in the folder of the first run (or that folder itself, when it is
/// one), else in `cwd`. `None` if there is none.
pub fn discover(runs: &[PathBuf], cwd: &Path) -> Option<PathBuf> {
    let beside =
        runs.first().map(|p| if p.is_dir() { p.clone() } else { p.parent().unwrap_or(Path::new("")).to_path_buf() });
    beside.into_iter().chain([cwd.to_path_buf()]).map(|dir| dir.join(FILE_NAME)).find(|p| p.is_file())
}

/// The robot for a command: `--robot` if given, else a discovered `robot.toml` (see [`discover`]).
pub fn resolve(flag: Option<&str>, runs: &[PathBuf]) -> Result<Option<RobotFile>, RobotFileError> {
    if let Some(v) = flag {
        return from_arg(v).map(Some);
    }
    let cwd = std::env::current_dir().unwrap_or_default();
    match discover(runs, &cwd) {
        Some(path) => {
            // Show the path as found (relative to the data or the working directory).
            let shown = path.strip_prefix(&cwd).map(Path::to_path_buf).unwrap_or(path);
            Ok(Some(RobotFile { description: read(&shown)?, source: Source::Discovered(shown) }))
        }
        None => Ok(None),
    }
}

/// Says `robot: PATH (found beside the data)` on stderr for a robot.toml that was picked up without being
/// named, once per file in a command (a command may load several sets). `--robot` is not repeated back
/// but for `-v`.
pub fn announce(source: &Source) {
    let text = source.to_string();
    if !crate::logging::first_in_command(&format!("robot: {text}")) {
        return;
    }
    match source {
        Source::Discovered(_) => crate::note!("robot: {text}"),
        Source::Flag(_) | Source::Builtin => tracing::info!("robot: {text}, named by --robot"),
    }
}

/// Fills what the command line left open from the robot description: the wheel joints (when
/// `joints_open`; without a description, `wheel_a`, `wheel_b`, `wheel_c`), the topics and the frames.
pub fn fill_mcap_options(mcap: &mut McapOptions, joints_open: bool, robot: Option<&RobotFile>) {
    if joints_open {
        mcap.wheel_joints = robot.map_or_else(|| McapOptions::default().wheel_joints, |r| r.description.joints());
    }
    let Some(file) = robot else { return };
    let r = &file.description;
    // Where a key is, for messages that name the value: `robot.toml, line 31`.
    let origin = |table: &str, key: &str| {
        let at = match &file.source {
            Source::Flag(p) | Source::Discovered(p) => match line_of_field(p, &format!("{table}.{key}")) {
                Some(line) => format!("{}, line {line}", p.display()),
                None => p.display().to_string(),
            },
            Source::Builtin => file.source.to_string(),
        };
        crate::dataset::mcap::Origin::RobotFile { key: format!("[{table}] {key}"), at }
    };
    let fill = |slot: &mut Option<String>,
                from: &Option<String>,
                slot_origin: &mut crate::dataset::mcap::Origin,
                table: &str,
                key: &str| {
        if slot.is_none() && from.is_some() {
            slot.clone_from(from);
            *slot_origin = origin(table, key);
        }
    };
    let o = &mut mcap.origins;
    fill(&mut mcap.joints_topic, &r.topics.joint_states, &mut o.joints_topic, "topics", "joint_states");
    fill(&mut mcap.truth_topic, &r.topics.ground_truth, &mut o.truth_topic, "topics", "ground_truth");
    if mcap.command_topic.is_none() {
        mcap.command_topic.clone_from(&r.topics.command);
    }
    fill(
        &mut mcap.truth_parent_frame,
        &r.frames.ground_truth_parent,
        &mut o.truth_parent_frame,
        "frames",
        "ground_truth_parent",
    );
    fill(
        &mut mcap.truth_child_frame,
        &r.frames.ground_truth_child,
        &mut o.truth_child_frame,
        "frames",
        "ground_truth_child",
    );
    if mcap.base_frame.is_none() {
        mcap.base_frame.clone_from(&r.frames.base);
    }
    mcap.wheel_data = r.wheel_data.clone();
    // The design's forward kinematics, for a recording whose wheels come from its own odometry (its rows
    // are the description's wheels, so only when they are the wheels read).
    mcap.wheels_from_twist = r
        .wheels_from_twist()
        .ok()
        .filter(|_| mcap.wheel_joints == r.joints())
        .map(|m| m.row_iter().map(|row| [row[0], row[1], row[2]]).collect());
}

/// Where a command's design comes from.
#[derive(Clone, Copy, Debug)]
pub enum Design<'a> {
    /// A robot description (`--robot`, or found beside the data).
    File(&'a RobotFile),
    /// The geometry the data declares (OptiOdom metadata).
    Data(&'a RobotGeometry),
}

/// The design of a dataset's robot, in this order: `--robot`, the geometry the data declares (when its
/// inputs declare several, the one the most runs declare: [`Dataset::declared_start`]; each run's own is
/// `crate::design::designs`), a `robot.toml` found beside the data. `None` when there is none of them.
pub fn design(ds: &Dataset) -> Option<Design<'_>> {
    match (&ds.robot_file, ds.declared_start().map(|d| &d.geometry)) {
        (Some(f), _) if !matches!(f.source, Source::Discovered(_)) => Some(Design::File(f)),
        (_, Some(g)) => Some(Design::Data(g)),
        (Some(f), None) => Some(Design::File(f)),
        (None, None) => None,
    }
}

/// A command that needs the robot's design found none; the message says how to give one, in the command
/// line's spelling ([`no_design_text`]).
#[derive(Debug, Error)]
#[error("{}", no_design_text(what, &Spelling::COMMAND_LINE))]
pub struct NoDesign {
    /// What needs the design (`--model design`, `plan`).
    pub what: String,
}

/// The error of a command that needs the robot's design and has none: how to give one.
pub fn no_design(what: &str) -> NoDesign {
    NoDesign { what: what.to_string() }
}

/// How a caller names the robot: the command line's `--robot`, Python's `robot=`.
#[derive(Clone, Copy, Debug)]
pub struct Spelling<'a> {
    /// What was not given (`--robot`).
    pub none: &'a str,
    /// How to pass a file (`--robot FILE`).
    pub file: &'a str,
    /// How to pass the built-in APR-02 (`--robot apr02`).
    pub apr02: &'a str,
}

impl Spelling<'_> {
    /// The command line's: `--robot FILE`, `--robot apr02`.
    pub const COMMAND_LINE: Spelling<'static> =
        Spelling { none: "--robot", file: "--robot FILE", apr02: "--robot apr02" };
}

/// [`no_design`]'s message, with `spelling`'s names for the robot argument.
pub fn no_design_text(what: &str, spelling: &Spelling<'_>) -> String {
    let Spelling { none, file, apr02 } = spelling;
    format!(
        "{what} needs the robot's design (its wheel geometry), and none is given: no {none}, no geometry in the \
         data, no {FILE_NAME} beside the data or in the working directory. Describe the robot once in a \
         {FILE_NAME} (docs/formats.md, \"Robot description\"; `omnical init RECORDING --urdf FILE` drafts one \
         from a recording and the robot's URDF) and put it beside the data or pass {file}; for the paper's \
         APR-02 robot pass {apr02}"
    )
}

/// Comments to write into a robot description: a header, and lines above each wheel (or the `[diff]` table).
#[derive(Clone, Debug, Default)]
pub struct Comments {
    /// Lines at the top of the file.
    pub header: Vec<String>,
    /// Lines above wheel `i`'s `[[wheels]]` table (or, for `diff`, index 0 above `[diff]`).
    pub wheels: Vec<Vec<String>>,
}

fn quoted(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

fn comment_lines(out: &mut String, lines: &[String]) {
    for l in lines {
        if l.is_empty() {
            out.push_str("#\n");
        }
        for part in l.lines() {
            let _ = writeln!(out, "# {part}");
        }
    }
}

/// A robot description as commented TOML that [`parse`] reads back to the same description.
pub fn to_toml(d: &RobotDescription, comments: &Comments) -> String {
    let mut s = String::new();
    comment_lines(&mut s, &comments.header);
    if let Some(n) = &d.name {
        let _ = writeln!(s, "name = {}", quoted(n));
    }
    let _ = writeln!(s, "kind = {}", quoted(d.kind.name()));
    let num = |s: &mut String, key: &str, v: Option<f64>| {
        if let Some(v) = v {
            let _ = writeln!(s, "{key} = {v:?}");
        }
    };
    let text = |s: &mut String, key: &str, v: &Option<String>| {
        if let Some(v) = v {
            let _ = writeln!(s, "{key} = {}", quoted(v));
        }
    };
    for (i, w) in d.wheels.iter().enumerate() {
        s.push('\n');
        comment_lines(&mut s, comments.wheels.get(i).map_or(&[], Vec::as_slice));
        let _ = writeln!(s, "[[wheels]]\njoint = {}", quoted(&w.joint));
        num(&mut s, "x_m", w.x_m);
        num(&mut s, "y_m", w.y_m);
        num(&mut s, "distance_m", w.distance_m);
        num(&mut s, "angle_deg", w.angle_deg);
        num(&mut s, "drive_deg", w.drive_deg);
        num(&mut s, "radius_m", Some(w.radius_m));
        num(&mut s, "roller_angle_deg", w.roller_angle_deg);
    }
    if let (BaseKind::Diff, Some(x)) = (d.kind, &d.diff) {
        s.push('\n');
        comment_lines(&mut s, comments.wheels.first().map_or(&[], Vec::as_slice));
        let _ = writeln!(s, "[diff]");
        num(&mut s, "wheel_separation_m", Some(x.wheel_separation_m));
        let _ = writeln!(s, "left_joint = {}\nright_joint = {}", quoted(&x.left_joint), quoted(&x.right_joint));
        num(&mut s, "left_radius_m", Some(x.left_radius_m));
        num(&mut s, "right_radius_m", Some(x.right_radius_m));
    }
    let t = &d.topics;
    if t.joint_states.is_some() || t.ground_truth.is_some() || t.command.is_some() {
        s.push_str("\n[topics]\n");
        text(&mut s, "joint_states", &t.joint_states);
        text(&mut s, "ground_truth", &t.ground_truth);
        text(&mut s, "command", &t.command);
    }
    let f = &d.frames;
    if f.ground_truth_parent.is_some() || f.ground_truth_child.is_some() || f.base.is_some() {
        s.push_str("\n[frames]\n");
        text(&mut s, "ground_truth_parent", &f.ground_truth_parent);
        text(&mut s, "ground_truth_child", &f.ground_truth_child);
        text(&mut s, "base", &f.base);
    }
    if let Some(g) = &d.ground_truth {
        s.push_str("\n[ground_truth]\n");
        text(&mut s, "file", &g.file);
        num(&mut s, "time_offset_s", g.time_offset_s);
        for (key, map) in [("columns", &g.columns), ("units", &g.units)] {
            if !map.is_empty() {
                let items: Vec<String> = map.iter().map(|(k, v)| format!("{k} = {}", quoted(v))).collect();
                let _ = writeln!(s, "{key} = {{ {} }}", items.join(", "));
            }
        }
    }
    if let Some(p) = &d.priors {
        s.push_str("\n[priors]\n");
        num(&mut s, "radius_std_m", p.radius_std_m);
        num(&mut s, "position_std_m", p.position_std_m);
        num(&mut s, "angle_std_deg", p.angle_std_deg);
        num(&mut s, "separation_std_m", p.separation_std_m);
    }
    s
}

/// Finding fields in the TOML text: the field at an error's byte offset, and the bytes of a field path.
mod locate;

#[cfg(test)]
mod tests;
