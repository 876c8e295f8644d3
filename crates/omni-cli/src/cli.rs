//! Command-line interface: the global options and the list of subcommands. Each subcommand declares its
//! arguments once, as a clap `Args` struct in its `cmd` module (defaults taken from the library's), loads,
//! calls the library, and formats; no science happens here.

use crate::cmd;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Parser, Subcommand};
use omni_kin::Choice;

/// Calibrate a wheeled robot's odometry from recorded runs, and find out why the model still misses.
///
/// omnical reads runs in which the wheel encoders and a ground-truth pose (motion capture, a total
/// station) were recorded together (ROS 2 MCAP bags, CSV files or OptiOdom folders), fits the robot's
/// kinematic model (the matrix that turns wheel speeds into body velocity, or the wheel radii and
/// positions) so that integrated odometry follows the ground truth, and names the physical effect
/// (a clock offset, slip, backlash, …) that the model still misses.
///
/// A session: `omnical init RECORDING --urdf robot.urdf` (describe the robot once),
/// `omnical train RUNS --out fitted.toml`, `omnical eval --model fitted.toml OTHER_RUNS`,
/// `omnical diagnose --model fitted.toml RUNS --validate OTHER_RUNS`, `omnical report …`,
/// `omnical export …`. `omnical demo` shows the whole story on simulated data.
///
/// Settings you would repeat on every command (joint names, topics, seed, preset) live in robot.toml and
/// omnical.toml: `omnical config` shows the ones in force and where each came from. Results go to stdout,
/// notes and warnings to stderr (`-q` fewer, `-v` more); `omnical completions SHELL` sets up tab
/// completion and `omnical man` writes man pages.
#[derive(Debug, Parser)]
#[command(name = "omnical", version)]
pub struct Cli {
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, global = true, help_heading = GLOBAL_OPTIONS)]
    pub threads: Option<usize>,
    /// Hide progress bars and notes (bars are also hidden when stderr is not a terminal); results and
    /// warnings still print.
    #[arg(long, short, global = true, help_heading = GLOBAL_OPTIONS)]
    pub quiet: bool,
    /// Say more on stderr: -v adds what was read (files, the robot.toml picked up) and timings, -vv
    /// debugging detail. RUST_LOG (e.g. RUST_LOG=debug), when set, overrides -q and -v.
    #[arg(long, short, global = true, help_heading = GLOBAL_OPTIONS, action = clap::ArgAction::Count, conflicts_with = "quiet")]
    pub verbose: u8,
    /// Project defaults (seed, preset, joints, topics, …: docs/formats.md) from this file instead of an
    /// omnical.toml in the working directory. Options given on the command line win.
    #[arg(long, global = true, help_heading = GLOBAL_OPTIONS, value_name = "FILE")]
    pub config: Option<std::path::PathBuf>,
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// The help heading of the options every command takes.
pub const GLOBAL_OPTIONS: &str = "Global options";

/// Subcommands: each holds its own arguments (`cmd::<name>::Args`).
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Write simulated runs of a robot that differs from its design, to try every command without a robot
    /// (the paper's "flower": 12 directions × 3 turn rates, each repeated), with optional hidden effects.
    Simulate(cmd::simulate::Args),
    /// Measure a model on runs: how far its odometry ends from the ground truth (the mean end-pose error,
    /// the paper's Eq. 6 cost), overall and per run.
    Eval(cmd::eval::Args),
    /// Fit the robot's kinematic model (and any effects added with --effect) to training runs, so that its
    /// odometry follows the ground truth; writes the fitted model.
    Train(cmd::train::Args),
    /// Compare a model with measurements, find where it fails, and name the missing physical effect.
    Diagnose(cmd::diagnose::Args),
    /// Find which family of physical features (wheel, body, world, time, ground truth) explains the error a
    /// model leaves: each fitted on the training runs, judged on the held-out runs.
    Explore(cmd::explore::Args),
    /// Write an HTML report (inline SVG figures): costs, error ladder, trajectory overlays, errors by command,
    /// error growth, and the diagnosis ranking.
    Report(cmd::report::Args),
    /// Export trajectories: TUM files (ground truth, design and calibrated odometry) for evo, and MCAP bags
    /// with the calibrated odometry on `/omnical/odometry` for Foxglove.
    Export(cmd::export::Args),
    /// A lidar's own path from its LaserScan messages (scan-to-scan point-to-line ICP): matches accepted and
    /// rejected, their quality, and the path as a TUM file.
    ScanOdometry(cmd::scan_odometry::Args),
    /// An IMU's yaw rate as a rotation reference: the wheel matrix's rotation row and the gyro's bias (the
    /// translation rows need a reference that senses translation).
    Imu(cmd::imu::Args),
    /// What an input holds (a ROS recording's topics, types, counts, rates, joints; a CSV run; an OptiOdom
    /// set's declared robot) and what omnical makes of it: each topic's role and why, the runs a read gives
    /// (samples, rates, gaps, the ground truth's clock), its notes, or the error that stops it.
    Info(cmd::info::Args),
    /// Propose calibration runs that excite every parameter of a model (and its effects), with the
    /// standard errors they would give for a stated ground-truth noise.
    Plan(cmd::plan::Args),
    /// Draft a robot description (robot.toml) from a recording and the robot's URDF: lists the recording's
    /// topics, reads the wheels (continuous joints with a cylinder) and guesses the base kind; every guess is
    /// a comment in the file.
    Init(cmd::init::Args),
    /// The whole story on built-in simulated data with a hidden effect: simulate, train, diagnose, add the
    /// effect, retrain, print the error ladder.
    Demo(cmd::demo::Args),
    /// Calibrate every robot-session of a fleet (`FLEET_DIR/<robot>/<session>/`) on Dask and write the fleet
    /// view: the Python wheel's `omnical` only (`pip install "omnical[fleet]"`).
    ///
    /// On Dask: a local cluster of N worker processes (--workers), or the scheduler at ADDRESS
    /// (--scheduler); each session's model is `omnical train`'s, byte for byte.
    Fleet(cmd::FleetArgs),
    /// Show the settings a command would use here (joints, topics, ground truth, frames, preset, seed,
    /// threads, …), each with where it came from: the command line, omnical.toml, robot.toml (with the
    /// line) or the default.
    Config(cmd::config::Args),
    /// Print a shell completion script (bash, zsh, fish, elvish, powershell) on stdout.
    Completions(cmd::shell::CompletionsArgs),
    /// Print the manual page (roff) on stdout, or write one page per command with `--out DIR`.
    Man(cmd::shell::ManArgs),
}

/// The effect ids, for help texts: the built-in catalogue (`sensor_offset, sensor_offset_yaw, time_offset,
/// …`), then the explorer's learned corrections (`learned:wheel, …`).
pub fn effect_ids() -> String {
    omni_kin::effect::ids().join(", ")
}

/// The help of an option that takes effect ids: `lead`, then the ids.
pub fn effect_help(lead: &str) -> String {
    format!("{lead} Effect ids: {}.", effect_ids())
}

/// The value parser of a library [`Choice`] (a preset, an objective, …): its ids in kebab-case, each
/// listed in `--help` with its line from [`Choice::describe`].
pub fn choice<T: Choice>() -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(
        T::ALL
            .iter()
            .map(|v| PossibleValue::new(v.flag_value()).help(v.describe()).aliases(v.aliases().iter().copied())),
    )
    .try_map(|s| T::from_id(&s))
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    crate::logging::init(crate::logging::Verbosity::from_flags(cli.quiet, cli.verbose));
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new().num_threads(n).build_global()?;
    }
    tracing::debug!("{} worker threads", rayon::current_num_threads());
    let started = std::time::Instant::now();
    let result = run_command(cli);
    tracing::info!("finished in {:.2} s", started.elapsed().as_secs_f64());
    result
}

fn run_command(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Simulate(a) => cmd::simulate::run(&a, cli.quiet),
        Command::Eval(a) => cmd::eval::run(&a),
        Command::Train(a) => cmd::train::run(&a, cli.quiet),
        Command::Diagnose(a) => cmd::diagnose::run(&a),
        Command::Explore(a) => cmd::explore::run(&a),
        Command::Report(a) => cmd::report::run(&a, cli.quiet),
        Command::Export(a) => cmd::export::run(&a),
        Command::ScanOdometry(a) => cmd::scan_odometry::run(&a),
        Command::Imu(a) => cmd::imu::run(&a),
        Command::Info(a) => cmd::info::run(&a),
        Command::Plan(a) => cmd::plan::run(&a),
        Command::Init(a) => cmd::init::run(&a),
        Command::Demo(a) => cmd::demo::run(&a, cli.quiet),
        Command::Fleet(_) => Err(cmd::python_only("omnical fleet")),
        Command::Config(a) => cmd::config::run(&a, cli.threads, cli.config.as_deref()),
        Command::Completions(a) => cmd::shell::completions(&a),
        Command::Man(a) => cmd::shell::man(&a),
    }
}
