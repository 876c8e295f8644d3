//! Every setting of `omnical train`, of the data options and of the other commands' options a project may
//! set (`eval --rpe-delta`), `omnical simulate`'s sensors (Python's `simulate` keywords) and `omnical imu`'s
//! options (Python's `imu`), declared once: its command-line option (the
//! clap argument id, the long flag in kebab-case), whether omnical.toml may set it (the project file's
//! keys are this table's), whether `omnical config` shows it, and its Python keyword. The clap `Args`
//! structs, the `omnical config` rows and the Python signatures (`#[pyo3(signature)]`, `_omnical.pyi`) are
//! checked against it by `crates/omni-cli/tests/config.rs`, so a setting added to one front end and not to
//! the others (or not here) fails a test.

use Where::{No, Yes};

/// A setting's Python keywords, each a function (`load`, `train`, `evaluate`) and the keyword's name there;
/// or why it has none.
pub type Python = Result<&'static [(&'static str, &'static str)], &'static str>;

/// Where a setting appears in one front end, or why it does not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Where {
    /// It appears.
    Yes,
    /// It does not, for this reason.
    No(&'static str),
}

/// Which commands take a setting as a command-line option.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flag {
    /// An option of `omnical train`, a global one, or a data option of every command that reads runs.
    Train,
    /// An option of this command only (`eval`).
    Of(&'static str),
    /// None, for this reason.
    No(&'static str),
}

/// One setting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Setting {
    /// The clap argument id, the project file's key and the `omnical config` row's key (`gt_time_offset`);
    /// the long flag is it in kebab-case.
    pub key: &'static str,
    /// What it is, as the project file's key list says it.
    pub about: &'static str,
    /// Which commands take it as an option.
    pub flag: Flag,
    /// A key of omnical.toml.
    pub project_file: Where,
    /// A row of `omnical config`.
    pub config_row: Where,
    /// Its Python keywords.
    pub python: Python,
}

const fn setting(
    key: &'static str,
    about: &'static str,
    project_file: Where,
    config_row: Where,
    python: Python,
) -> Setting {
    Setting { key, about, flag: Flag::Train, project_file, config_row, python }
}

/// Why a data option's Python keyword is `load`'s: the other calls take runs already loaded.
const LOAD: &str = "load";
/// Python's `info` (`omnical info`'s): the data options of `load` describe the read it shows.
const INFO: &str = "info";
/// Python's `imu` (`omnical imu`'s): the data options that reach the wheels, and its own options.
const IMU: &str = "imu";
/// Why an option of `omnical imu` is no project default.
const ONE_IMU_FIT: Where = No("it names this IMU fit's input or output");
/// Python's training call.
const TRAIN: &str = "train";
/// Python's evaluation call (`omnical eval`'s).
const EVALUATE: &str = "evaluate";
/// Python's simulation call (`omnical simulate`'s, its sensors the same keywords as the flags).
const SIMULATE: &str = "simulate";
/// Why a simulated sensor's setting is no project default.
const ONE_SIMULATION: Where = No("a simulated sensor is one simulation's setting");

/// An option of `omnical simulate` that is the same keyword of Python's `omnical.simulate`.
macro_rules! simulate_setting {
    ($key:literal, $about:literal) => {
        Setting {
            key: $key,
            about: $about,
            flag: Flag::Of(SIMULATE),
            project_file: ONE_SIMULATION,
            config_row: NOT_SHOWN,
            python: Ok(&[(SIMULATE, $key)]),
        }
    };
}

/// Settings a project file has no key for.
const NOT_SHOWN: Where = No("`omnical config` shows the settings a user repeats across commands");

/// The settings, in the order of the project file's key list.
pub const SETTINGS: &[Setting] = &[
    setting("threads", "worker threads", Yes, Yes, Err("RAYON_NUM_THREADS sets rayon's pool in Python")),
    setting(
        "robot",
        "robot description: a robot.toml path or apr02",
        Yes,
        Yes,
        Ok(&[(LOAD, "robot"), (INFO, "robot"), (TRAIN, "robot"), (EVALUATE, "robot"), (IMU, "robot")]),
    ),
    setting(
        "joints",
        "wheel joint names in wheel order",
        Yes,
        Yes,
        Ok(&[(LOAD, "joints"), (INFO, "joints"), (IMU, "joints")]),
    ),
    setting(
        "joints_topic",
        "MCAP topic of the wheel JointState",
        Yes,
        Yes,
        Ok(&[(LOAD, "joints_topic"), (INFO, "joints_topic"), (IMU, "joints_topic")]),
    ),
    setting("gt_topic", "MCAP topic of the ground truth", Yes, Yes, Ok(&[(LOAD, "gt_topic"), (INFO, "gt_topic")])),
    setting(
        "gt_parent_frame",
        "parent frame of the ground truth in a TF topic",
        Yes,
        Yes,
        Ok(&[(LOAD, "gt_parent_frame"), (INFO, "gt_parent_frame")]),
    ),
    setting(
        "gt_child_frame",
        "child frame of the ground truth in a TF topic",
        Yes,
        Yes,
        Ok(&[(LOAD, "gt_child_frame"), (INFO, "gt_child_frame")]),
    ),
    setting("gt", "ground truth from a separate file or folder", Yes, Yes, Ok(&[(LOAD, "gt"), (INFO, "gt")])),
    setting(
        "gt_time_offset",
        "clock offset of the gt file (s)",
        Yes,
        Yes,
        Ok(&[(LOAD, "gt_time_offset"), (INFO, "gt_time_offset")]),
    ),
    setting(
        "gt_kind",
        "what the ground truth measures: absolute (motion capture) or relative (a sensor's own motion)",
        Yes,
        Yes,
        Ok(&[(LOAD, "gt_kind"), (INFO, "gt_kind")]),
    ),
    setting(
        "gt_window",
        "window of a relative reference (s)",
        Yes,
        Yes,
        Ok(&[(LOAD, "gt_window_s"), (INFO, "gt_window_s")]),
    ),
    setting(
        "gt_mount",
        "the measured point's pose in the base frame: x, y (m), yaw (degrees)",
        Yes,
        Yes,
        Ok(&[(LOAD, "gt_mount"), (INFO, "gt_mount")]),
    ),
    setting(
        "gt_mount_start",
        "where the fit starts a relative reference's sensor mount: x, y (m), yaw (degrees)",
        Yes,
        Yes,
        Ok(&[(LOAD, "gt_mount_start"), (INFO, "gt_mount_start")]),
    ),
    setting(
        "gt_scans",
        "ground truth from a 2D lidar: its LaserScan topic, matched scan to scan",
        Yes,
        NOT_SHOWN,
        Ok(&[(LOAD, "gt_scans"), (INFO, "gt_scans")]),
    ),
    setting(
        "split",
        "cut recordings at standstills at least this long (s)",
        Yes,
        Yes,
        Ok(&[(LOAD, "split_s"), (INFO, "split_s")]),
    ),
    setting(
        "skip_invalid",
        "skip runs that fail to load",
        Yes,
        NOT_SHOWN,
        Ok(&[(LOAD, "skip_invalid"), (INFO, "skip_invalid"), (IMU, "skip_invalid")]),
    ),
    setting(
        "ticks_per_rev",
        "encoder ticks per wheel revolution",
        Yes,
        NOT_SHOWN,
        Ok(&[(LOAD, "ticks_per_rev"), (INFO, "ticks_per_rev")]),
    ),
    setting(
        "max_file_mb",
        "largest input file (MiB)",
        Yes,
        NOT_SHOWN,
        Ok(&[(LOAD, "max_file_mb"), (INFO, "max_file_mb"), (IMU, "max_file_mb")]),
    ),
    setting("preset", "training recipe", Yes, Yes, Ok(&[(TRAIN, "preset")])),
    setting("seed", "seed", Yes, Yes, Ok(&[(TRAIN, "seed")])),
    setting("objective", "training objective", Yes, Yes, Ok(&[(TRAIN, "objective")])),
    setting("every", "path objective: every k-th ground-truth pose", Yes, NOT_SHOWN, Ok(&[(TRAIN, "every")])),
    setting(
        "heading_weight",
        "path objective: heading weight (m/rad)",
        Yes,
        NOT_SHOWN,
        Ok(&[(TRAIN, "heading_weight")]),
    ),
    setting("unexcited", "unconstrained directions: hold or move", Yes, NOT_SHOWN, Ok(&[(TRAIN, "unexcited")])),
    Setting {
        key: "rpe_delta",
        about: "eval: window of the relative pose error, a distance (1m) or a time (2s)",
        flag: Flag::Of("eval"),
        project_file: Yes,
        config_row: NOT_SHOWN,
        python: Ok(&[(EVALUATE, "rpe_delta")]),
    },
    setting(
        "gt_columns",
        "CSV columns of the gt file",
        No("a robot.toml's [ground_truth] columns table holds them for a robot"),
        NOT_SHOWN,
        Ok(&[(LOAD, "gt_columns"), (INFO, "gt_columns")]),
    ),
    setting(
        "gt_units",
        "units of the gt file's CSV columns",
        No("a robot.toml's [ground_truth] units table holds them for a robot"),
        NOT_SHOWN,
        Ok(&[(LOAD, "gt_units"), (INFO, "gt_units")]),
    ),
    setting(
        "max_std_error",
        "largest standard error of a constrained direction (fraction of the scale)",
        No("a per-fit threshold"),
        NOT_SHOWN,
        Ok(&[(TRAIN, "max_std_error")]),
    ),
    setting(
        "min_excitation",
        "smallest singular value of a constrained direction (fraction of the largest)",
        No("a per-fit threshold"),
        NOT_SHOWN,
        Ok(&[(TRAIN, "min_excitation")]),
    ),
    setting(
        "model",
        "base model to fit",
        No(PER_RUN),
        NOT_SHOWN,
        Ok(&[(TRAIN, "model"), (EVALUATE, "model"), (IMU, "model")]),
    ),
    setting("start", "start model file", No(PER_RUN), NOT_SHOWN, Err("an omnical.Model as model= is the start")),
    setting("effects", "effects to add to the fit", No(PER_RUN), NOT_SHOWN, Ok(&[(TRAIN, "effects")])),
    // Python's `train` returns the model (Model.save writes it); `imu` writes `omnical imu --out`'s file.
    setting("out", "fitted model file", No(PER_RUN), NOT_SHOWN, Ok(&[(IMU, "out")])),
    setting("force", "fit and write a refused fit", No(PER_RUN), NOT_SHOWN, Ok(&[(TRAIN, "force")])),
    setting("json", "results as JSON", No(PER_RUN), NOT_SHOWN, Err("results are Python objects")),
    setting("quiet", "fewer notes", No(PER_RUN), NOT_SHOWN, Err(NO_TERMINAL)),
    setting("verbose", "more notes", No(PER_RUN), NOT_SHOWN, Err(NO_TERMINAL)),
    setting("config", "the project file", No("it names the project file"), NOT_SHOWN, Err(NO_TERMINAL)),
    Setting {
        key: "command_topic",
        about: "MCAP topic of the velocity command",
        flag: Flag::No("a robot.toml's [topics] command sets it"),
        project_file: No("a robot.toml's [topics] command sets it"),
        config_row: Yes,
        python: Err("a robot.toml's [topics] command sets it"),
    },
    Setting {
        key: "recorded_odometry",
        about: "keep the runs' recorded odometry",
        flag: Flag::No("`omnical export` keeps it, the other commands do not need it"),
        project_file: No("not an option of the command line"),
        config_row: NOT_SHOWN,
        python: Ok(&[(LOAD, "recorded_odometry")]),
    },
    Setting {
        key: "progress",
        about: "a callback per optimizer iteration",
        flag: Flag::No("the command line shows a progress bar (-q hides it)"),
        project_file: No("not an option of the command line"),
        config_row: NOT_SHOWN,
        python: Ok(&[(TRAIN, "progress")]),
    },
    simulate_setting!("lidar", "simulate: a 2D lidar in this room (room, corridor or a room file)"),
    simulate_setting!("lidar_mount", "simulate: the lidar's pose on the base: x, y (m), yaw (degrees)"),
    simulate_setting!("lidar_tf", "simulate: the lidar mount /tf_static states (default: the true one), or none"),
    simulate_setting!("lidar_rate", "simulate: lidar scans per second (Hz)"),
    simulate_setting!("lidar_beams", "simulate: beams per lidar scan, evenly over its field of view"),
    simulate_setting!("lidar_fov", "simulate: the lidar's field of view (degrees), centred on its x axis"),
    simulate_setting!("lidar_max_range", "simulate: longest lidar range (m)"),
    simulate_setting!("lidar_noise", "simulate: Gaussian lidar range noise (m)"),
    simulate_setting!("lidar_dropout", "simulate: share of lidar beams that return nothing"),
    simulate_setting!("lidar_sweep", "simulate: measure each scan's beams one after another over its period"),
    simulate_setting!("lidar_model", "simulate: the kind of lidar: ideal, or scans as a urg04lx's or an rplidar's"),
    simulate_setting!("imu", "simulate: an IMU's yaw rate beside the wheels"),
    simulate_setting!("imu_rate", "simulate: IMU messages per second (Hz)"),
    simulate_setting!("imu_bias", "simulate: the gyro's bias (rad/s)"),
    simulate_setting!("imu_noise", "simulate: Gaussian noise of each yaw-rate sample (rad/s)"),
    simulate_setting!("imu_mount", "simulate: the IMU's mount on the base: roll, pitch, yaw (degrees)"),
    simulate_setting!("imu_tf", "simulate: the IMU mount /tf_static states (default: the true one), or none"),
    Setting {
        key: "topic",
        about: "imu: the IMU's sensor_msgs/msg/Imu topic",
        flag: Flag::Of(IMU),
        project_file: ONE_IMU_FIT,
        config_row: NOT_SHOWN,
        python: Ok(&[(IMU, "topic")]),
    },
    Setting {
        key: "window",
        about: "imu: window of the rotation row's fit (s)",
        flag: Flag::Of(IMU),
        project_file: ONE_IMU_FIT,
        config_row: NOT_SHOWN,
        python: Ok(&[(IMU, "window_s")]),
    },
    Setting {
        key: "mount",
        about: "imu: the IMU's mount on the base: roll, pitch, yaw (degrees); default from /tf_static",
        flag: Flag::Of(IMU),
        project_file: ONE_IMU_FIT,
        config_row: NOT_SHOWN,
        python: Ok(&[(IMU, "mount")]),
    },
];

/// Why a setting of one run is not a project default.
const PER_RUN: &str = "it names this run's inputs or outputs";
/// Why a terminal setting has no Python keyword.
const NO_TERMINAL: &str = "Python prints nothing (logging is the host's)";

/// The settings omnical.toml may set.
pub fn project_keys() -> impl Iterator<Item = &'static Setting> {
    SETTINGS.iter().filter(|s| s.project_file == Where::Yes)
}

/// The setting of `key`.
pub fn get(key: &str) -> Option<&'static Setting> {
    SETTINGS.iter().find(|s| s.key == key)
}

// ---- Settings named in library text ----------------------------------------------------------------------
//
// The library names a setting by its key in backticks, [`named`] (`` `gt_scans` ``), or with a value,
// [`named_with`] (`` `preset=default` ``): never by a front end's spelling. Each front end renders the
// names in one place: the command line as its flags ([`as_flags`]: `--gt-scans`, `--preset default`),
// Python as keywords ([`as_keywords`]: `gt_scans=`, `preset="default"`). A backticked word that is no
// setting's key is left as written.

/// The settings whose long flag is not their key in kebab-case: (key, long flag without `--`).
const LONG_FLAGS: &[(&str, &str)] = &[("effects", "effect")];

/// The settings given without a value (a switch): Python names them `key=True`, as a flag names itself.
pub const SWITCHES: &[&str] = &["force", "skip_invalid"];

/// The setting `key` as library text names it: `` `gt_scans` ``, for `format!`. Each front end renders it
/// as its own spelling ([`as_flags`], [`as_keywords`]).
pub fn named(key: &str) -> String {
    debug_assert!(get(key).is_some(), "{key} is no setting");
    format!("`{key}`")
}

/// The setting `key` with a value as library text names it: `` `preset=default` `` (the value as the
/// command line writes it), which the command line renders `--preset default` and Python `preset="default"`.
pub fn named_with(key: &str, value: impl std::fmt::Display) -> String {
    debug_assert!(get(key).is_some(), "{key} is no setting");
    format!("`{key}={value}`")
}

/// The long flag of a setting that has one: `--gt-scans`.
pub fn long_flag(s: &Setting) -> Option<String> {
    if let Flag::No(_) = s.flag {
        return None;
    }
    let long =
        LONG_FLAGS.iter().find(|(k, _)| *k == s.key).map_or_else(|| s.key.replace('_', "-"), |(_, l)| (*l).into());
    Some(format!("--{long}"))
}

/// The Python keyword of a setting that has one (the same in every function that takes it): `split_s`.
pub fn keyword(s: &Setting) -> Option<&'static str> {
    s.python.ok()?.first().map(|(_, k)| *k)
}

/// `text` with every named setting as the command line's flag: `` `gt_scans` `` → `--gt-scans`,
/// `` `preset=default` `` → `--preset default`. The one mapping of the command line (its error and warning
/// printers call it).
pub fn as_flags(text: &str) -> String {
    render(text, |s, value| {
        let flag = long_flag(s)?;
        Some(value.map_or_else(|| flag.clone(), |v| format!("{flag} {v}")))
    })
}

/// `text` with every named setting as Python's keyword: `` `gt_scans` `` → `gt_scans=`, `` `force` `` →
/// `force=True`, `` `preset=default` `` → `preset="default"` (a number unquoted). The one mapping of the
/// Python binding (its exceptions and warnings call it).
pub fn as_keywords(text: &str) -> String {
    render(text, |s, value| {
        let keyword = keyword(s)?;
        Some(match value {
            None if SWITCHES.contains(&s.key) => format!("{keyword}=True"),
            None => format!("{keyword}="),
            Some(v) if v.parse::<f64>().is_ok() => format!("{keyword}={v}"),
            Some(v) => format!("{keyword}={v:?}"),
        })
    })
}

/// `text` with each `` `key` `` or `` `key=value` `` of a setting replaced by `spell(setting, value)`; a
/// backticked word that is no setting's key, or that `spell` has no spelling for, is left as written.
fn render(text: &str, spell: impl Fn(&Setting, Option<&str>) -> Option<String>) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(open) = rest.find('`') {
        out.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        let spelled = after.find('`').and_then(|close| {
            let inner = &after[..close];
            let (key, value) = inner.split_once('=').map_or((inner, None), |(k, v)| (k, Some(v)));
            let s = get(key).filter(|_| !key.is_empty())?;
            Some((spell(s, value)?, close))
        });
        match spelled {
            Some((words, close)) => {
                out.push_str(&words);
                rest = &after[close + 1..];
            }
            None => {
                out.push('`');
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn every_named_setting_is_its_flag_on_the_command_line_and_its_keyword_in_python() {
        let mut cli = crate::cli::Cli::command();
        cli.build();
        let args: Vec<clap::Arg> =
            cli.get_arguments().chain(cli.get_subcommands().flat_map(|c| c.get_arguments())).cloned().collect();
        for s in SETTINGS {
            let text = format!("give {}.", named(s.key));
            match s.flag {
                Flag::No(_) => assert_eq!(as_flags(&text), text, "{}", s.key),
                _ => {
                    let arg = args.iter().find(|a| a.get_id() == s.key);
                    let long = arg.and_then(|a| a.get_long()).unwrap_or_else(|| panic!("no flag {}", s.key));
                    assert_eq!(as_flags(&text), format!("give --{long}."));
                    assert_eq!(as_flags(&named_with(s.key, "v 1")), format!("--{long} v 1"));
                }
            }
            match s.python {
                Ok(functions) => {
                    let kw = functions[0].1;
                    assert!(functions.iter().all(|(_, k)| *k == kw), "{}: one keyword", s.key);
                    let value = if SWITCHES.contains(&s.key) { "True" } else { "" };
                    assert_eq!(as_keywords(&text), format!("give {kw}={value}."));
                    assert_eq!(as_keywords(&named_with(s.key, "0.5")), format!("{kw}=0.5"));
                    assert_eq!(as_keywords(&named_with(s.key, "/scan")), format!("{kw}=\"/scan\""));
                }
                Err(_) => assert_eq!(as_keywords(&text), text, "{}", s.key),
            }
        }
    }

    #[test]
    fn other_backticks_are_left_alone() {
        for text in ["`omnical plan --umbmark` and `gt_scan`", "`` and `", "`=x` `gt_scans", "no ticks `"] {
            assert_eq!(as_flags(text), text);
            assert_eq!(as_keywords(text), text);
        }
        assert_eq!(as_flags("see `omnical plan` or `every`"), "see `omnical plan` or --every");
        assert_eq!(as_keywords("`preset=default`; `force` keeps it"), "preset=\"default\"; force=True keeps it");
    }
}
