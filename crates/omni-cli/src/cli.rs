//! Command-line interface: argument parsing and the subcommands. Each subcommand loads, calls the library,
//! and formats; no science happens here.

use crate::cmd;
use clap::{Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

/// Calibrate omnidirectional robot kinematics from logs, and find out why the model still misses.
#[derive(Debug, Parser)]
#[command(name = "omnical", version, about, long_about = None)]
pub struct Cli {
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, global = true)]
    pub threads: Option<usize>,
    /// Hide progress bars (they are also hidden when stderr is not a terminal); summaries still print.
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// Dataset file format for writing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// omnical CSV, one file per run (docs/formats.md).
    Csv,
    /// ROS 2 MCAP bag, one file per run.
    Mcap,
}

/// Which base model to fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ModelKind {
    /// Every entry of the IK matrix (the paper).
    Ik,
    /// Wheel radii, distances and angles (the paper's ref. \[17\]).
    Geometry,
    /// A differential drive: both wheel radii and the separation.
    Diff,
    /// Four wheels on a rectangle (mecanum, omni X): per-wheel radius and the half-extents.
    Mecanum,
}

impl From<ModelKind> for omni_kin::KinematicsKind {
    fn from(k: ModelKind) -> Self {
        match k {
            ModelKind::Ik => Self::Ik,
            ModelKind::Geometry => Self::Geometry,
            ModelKind::Diff => Self::Diff,
            ModelKind::Mecanum => Self::Mecanum,
        }
    }
}

/// Calibration recipe.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PresetArg {
    /// The paper's method, reproduced: Eq. 6 end-pose cost, Eq. 1 Euler at 10 ms, MATLAB-default GA, ±10 % box.
    Paper,
    /// Ours: path cost, exact arcs, short GA then Levenberg–Marquardt.
    Default,
}

/// Cost to report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CostArg {
    /// The paper's Eq. 6: mean end-pose error (m and rad mixed).
    EndPose,
    /// RMS error over every ground-truth pose (1 m/rad).
    Path,
}

/// What a fit does along directions the training runs do not constrain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum UnexcitedArg {
    /// Keep the start (design) values there: truncated update (default preset).
    Hold,
    /// Let the optimizer move them (paper preset).
    Move,
}

/// Overrides of a preset's objective and its handling of unconstrained directions.
#[derive(Debug, Default, clap::Args)]
pub struct FitArgs {
    /// Objective (default: the preset's; paper: end-pose, default: path).
    #[arg(long, value_enum)]
    pub objective: Option<CostArg>,
    /// Path objective: use every k-th ground-truth pose (odometry is evaluated at its stamp).
    #[arg(long, default_value_t = 1, value_name = "K")]
    pub every: usize,
    /// Path objective: weight of heading errors against position errors. m/rad.
    #[arg(long, default_value_t = 1.0, value_name = "M_PER_RAD")]
    pub heading_weight: f64,
    /// Directions the runs do not constrain: hold them at the start or let them move (default: the
    /// preset's; paper: move, default: hold).
    #[arg(long, value_enum)]
    pub unexcited: Option<UnexcitedArg>,
    /// A direction is unconstrained when its standard error exceeds this fraction of the parameters'
    /// scale.
    #[arg(long, default_value_t = 0.05, value_name = "FRACTION")]
    pub max_std_error: f64,
    /// A direction is unconstrained when its singular value (scaled Jacobian) is below this fraction of
    /// the largest.
    #[arg(long, default_value_t = 0.01, value_name = "FRACTION")]
    pub min_excitation: f64,
}

/// A base kind (`omnical init --kind`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum KindArg {
    /// N ≥ 3 omni wheels.
    Omni,
    /// Four mecanum wheels.
    Mecanum,
    /// Differential drive.
    Diff,
}

impl From<KindArg> for omni_kin::robot::BaseKind {
    fn from(k: KindArg) -> Self {
        match k {
            KindArg::Omni => Self::Omni,
            KindArg::Mecanum => Self::Mecanum,
            KindArg::Diff => Self::Diff,
        }
    }
}

/// Which run set `plan` proposes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RunSetArg {
    /// D-optimal greedy pick from a library of commands (several speeds, both turn directions).
    Greedy,
    /// The paper's 36 flower commands.
    Flower,
}

/// The robot the data was recorded on (docs/formats.md, "Robot description").
#[derive(Debug, Default, clap::Args)]
pub struct RobotArgs {
    /// The robot description: a robot.toml file, or `apr02` for the paper's robot. Default: a robot.toml
    /// beside the data (the first RUNS argument's folder) or in the working directory.
    #[arg(long, value_name = "FILE|apr02")]
    pub robot: Option<String>,
}

/// Options shared by commands that read runs.
#[derive(Debug, clap::Args)]
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
    /// Clock offset of the `--gt` file: wheel time = ground-truth time + SECONDS. Default: estimated from
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
    /// Cut MCAP files into runs where the robot stands still at least this long. s.
    #[arg(long)]
    pub split: Option<f64>,
    /// Skip runs that fail to load (they are listed) instead of stopping.
    #[arg(long)]
    pub skip_invalid: bool,
    /// Encoder ticks per wheel revolution, for CSV files with tick columns.
    #[arg(long)]
    pub ticks_per_rev: Option<f64>,
    /// Refuse input files (CSV, MCAP) larger than this; each is read into memory whole. MiB.
    #[arg(long, value_name = "MIB", default_value_t = 1024)]
    pub max_file_mb: u64,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Simulate the paper's flower benchmark on a true robot that differs from the design.
    Simulate {
        /// Output folder: writes train/, validation/, truth.json and truth_model.toml.
        #[arg(long)]
        out: PathBuf,
        /// Seed (training uses it, validation seed + 1).
        #[arg(long, default_value_t = 7)]
        seed: u64,
        /// Repetitions of each of the 36 commands.
        #[arg(long, default_value_t = 5)]
        runs_per_command: usize,
        /// Duration of each command. s.
        #[arg(long, default_value_t = 10.0)]
        duration: f64,
        /// Inject an effect into the true robot: NAME=V1,V2,… in the effect's parameter order
        /// (`sample_timing=DROP_PROBABILITY,JITTER_S`). Repeatable.
        #[arg(long = "effect", value_name = "NAME=VALUES")]
        effects: Vec<String>,
        /// True robot: `paper` (Eq. 9, APR-02 only), `design` (the robot's design) or a model file.
        #[arg(long, default_value = "paper")]
        truth: String,
        /// The robot: its design drives the simulated controller and is written as robot.toml beside the
        /// runs. Default: `apr02`, the paper's robot.
        #[arg(long, value_name = "FILE|apr02", default_value = crate::robot_file::BUILTIN_APR02)]
        robot: String,
        /// Output format.
        #[arg(long, value_enum, default_value_t = Format::Mcap)]
        format: Format,
        /// No encoder quantisation and no noise.
        #[arg(long)]
        noise_free: bool,
    },
    /// Evaluate a model on runs: Eq. 6 cost and per-run end-pose errors.
    Eval {
        /// `design` (the data's design model, or the paper's Eq. 7) or a model file.
        #[arg(long, default_value = "design")]
        model: String,
        /// Run files or folders.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Data options.
        #[command(flatten)]
        data: DataArgs,
    },
    /// Fit a model to training runs.
    Train {
        /// Training run files or folders.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Base model to fit.
        #[arg(long, value_enum, default_value_t = ModelKind::Ik)]
        model: ModelKind,
        /// Start from this model file instead of the design.
        #[arg(long)]
        start: Option<PathBuf>,
        /// Recipe.
        #[arg(long, value_enum, default_value_t = PresetArg::Default)]
        preset: PresetArg,
        /// GA seed.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Add effects to fit (catalogue ids). Repeatable.
        #[arg(long = "effect", value_name = "NAME")]
        effects: Vec<String>,
        /// Write the fitted model here (TOML; read back by `--model FILE`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print a JSON summary instead of text.
        #[arg(long)]
        json: bool,
        /// Objective and unconstrained directions.
        #[command(flatten)]
        fit: FitArgs,
        /// Data options.
        #[command(flatten)]
        data: DataArgs,
    },
    /// Compare a model with measurements, find where it fails, and name the missing physical effect.
    Diagnose {
        /// Model file (from `train --out`) or `design`.
        #[arg(long)]
        model: String,
        /// Training runs (the ones the model was fitted on).
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Held-out runs (default: 2-fold cross-validation over repetitions).
        #[arg(long, num_args = 1..)]
        validate: Vec<PathBuf>,
        /// Add effects one at a time while the held-out cost falls, and print the error ladder.
        #[arg(long)]
        auto: bool,
        /// Candidate effects (default: the whole catalogue), comma-separated.
        #[arg(long, value_delimiter = ',')]
        candidates: Vec<String>,
        /// Minimum relative fall of the held-out path cost to recommend an effect.
        #[arg(long, default_value_t = 0.05)]
        min_gain: f64,
        /// Write the final model (with effects added by --auto) here.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print JSON (top-level `verdict`, `ranking`, `ladder`, …).
        #[arg(long)]
        json: bool,
        /// Data options.
        #[command(flatten)]
        data: DataArgs,
    },
    /// Write an HTML report (inline SVG figures): costs, error ladder, trajectory overlays, errors by command,
    /// error growth, and the diagnosis ranking.
    Report {
        /// Model file (from `train --out`) or `design`.
        #[arg(long)]
        model: String,
        /// Training runs (the ones the model was fitted on).
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Held-out runs: the figures use them (default: the training runs, 2-fold cross-validation in the
        /// diagnosis).
        #[arg(long, num_args = 1..)]
        validate: Vec<PathBuf>,
        /// The HTML file to write.
        #[arg(long, default_value = "report.html")]
        out: PathBuf,
        /// Also write each figure as PNG into this folder.
        #[arg(long, value_name = "DIR")]
        png: Option<PathBuf>,
        /// Skip the diagnosis (faster; no ranking, ladder of the given model only).
        #[arg(long)]
        no_diagnose: bool,
        /// Data options.
        #[command(flatten)]
        data: DataArgs,
    },
    /// Export trajectories: TUM files (ground truth, design and calibrated odometry) for evo, and MCAP bags
    /// with the calibrated odometry on `/omnical/odometry` for Foxglove.
    Export {
        /// Model file (from `train --out`) or `design`.
        #[arg(long)]
        model: String,
        /// Run files or folders.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Write `<run>.gt.tum`, `<run>.design.tum` and `<run>.calibrated.tum` into this folder.
        #[arg(long, value_name = "DIR")]
        tum: Option<PathBuf>,
        /// Write one MCAP bag per run into this folder, with the calibrated odometry added.
        #[arg(long, value_name = "DIR")]
        mcap: Option<PathBuf>,
        /// Write the calibration for the robot into this folder: the matrix as ROS 2 parameters
        /// (omnical_odometry.yaml) and as a C header (omnical_odometry.h), and the parameters of the
        /// matching ros2_controllers drive controller (ros2_controllers.yaml) from the nearest parametric fit,
        /// with the accuracy it gives up on the runs (docs/applying.md).
        #[arg(long, value_name = "DIR")]
        robot_config: Option<PathBuf>,
        /// Drive controller for --robot-config: diff_drive_controller, mecanum_drive_controller or
        /// omni_wheel_drive_controller (default: the one that matches the base).
        #[arg(long, value_name = "NAME")]
        controller: Option<omni_kin::controller::ControllerKind>,
        /// Data options.
        #[command(flatten)]
        data: DataArgs,
    },
    /// Propose calibration runs that excite every parameter of a model (and its effects), with the
    /// standard errors they would give for a stated ground-truth noise.
    Plan {
        /// Base model to plan for.
        #[arg(long, value_enum, default_value_t = ModelKind::Ik)]
        model: ModelKind,
        /// Effects to plan for (catalogue ids). Repeatable.
        #[arg(long = "effect", value_name = "NAME")]
        effects: Vec<String>,
        /// Take the robot's geometry from these runs (OptiOdom metadata), when there is no --robot.
        #[arg(long = "robot-from", value_name = "RUNS", num_args = 1..)]
        robot_from: Vec<PathBuf>,
        /// Which set: a D-optimal pick from a library of commands, or the paper's 36 flower commands.
        #[arg(long, value_enum, default_value_t = RunSetArg::Greedy)]
        set: RunSetArg,
        /// Distinct commands to pick (greedy).
        #[arg(long, default_value_t = 12)]
        runs: usize,
        /// Repetitions of each command.
        #[arg(long, default_value_t = 1)]
        repetitions: usize,
        /// Translation speed of the commands. m/s.
        #[arg(long, default_value_t = 0.2, value_name = "M_S")]
        speed: f64,
        /// Turn rate of the commands. rad/s.
        #[arg(long, default_value_t = 0.35, value_name = "RAD_S")]
        omega: f64,
        /// How long each command is held. s.
        #[arg(long, default_value_t = 10.0, value_name = "S")]
        duration: f64,
        /// Ground-truth rate. Hz.
        #[arg(long, default_value_t = 4.0, value_name = "HZ")]
        truth_rate: f64,
        /// Ground-truth position noise per axis. m.
        #[arg(long, default_value_t = 0.002, value_name = "M")]
        truth_noise_m: f64,
        /// Ground-truth heading noise. rad.
        #[arg(long, default_value_t = 0.003, value_name = "RAD")]
        truth_noise_rad: f64,
        /// Write the planned commands as CSV here (v_m_s, alpha_deg, omega_rad_s, repetitions).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print JSON.
        #[arg(long)]
        json: bool,
        /// Data options (for --robot-from).
        #[command(flatten)]
        data: DataArgs,
    },
    /// Draft a robot description (robot.toml) from a recording and the robot's URDF: lists the recording's
    /// topics, reads the wheels (continuous joints with a cylinder) and guesses the base kind; every guess is
    /// a comment in the file.
    Init {
        /// The recording (ROS 2 MCAP).
        recording: PathBuf,
        /// The robot's URDF (default: the recording's /robot_description topic).
        #[arg(long, value_name = "FILE")]
        urdf: Option<PathBuf>,
        /// The file to write.
        #[arg(long, default_value = crate::robot_file::FILE_NAME)]
        out: PathBuf,
        /// The base kind, instead of the guess (2 wheels: diff; 4 named mecanum: mecanum; else omni).
        #[arg(long, value_enum)]
        kind: Option<KindArg>,
        /// Replace an existing file.
        #[arg(long)]
        force: bool,
        /// Refuse a recording larger than this; it is read into memory whole. MiB.
        #[arg(long, value_name = "MIB", default_value_t = 1024)]
        max_file_mb: u64,
    },
    /// The whole story on built-in simulated data with a hidden effect: simulate, train, diagnose, add the
    /// effect, retrain, print the error ladder.
    Demo {
        /// Write the models, the diagnosis and the HTML report (report.html) here.
        #[arg(long, default_value = "omnical-demo")]
        out: PathBuf,
        /// Repetitions of each of the 36 commands.
        #[arg(long, default_value_t = 2)]
        runs_per_command: usize,
        /// The hidden effect, NAME=VALUES as for `simulate --effect`.
        #[arg(long, default_value = "time_offset=0.06")]
        hidden: String,
    },
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new().num_threads(n).build_global()?;
    }
    match cli.command {
        Command::Simulate { out, seed, runs_per_command, duration, effects, truth, robot, format, noise_free } => {
            cmd::simulate::run(&cmd::simulate::Args {
                out,
                seed,
                runs_per_command,
                duration_s: duration,
                effects,
                truth,
                robot,
                format,
                noise_free,
                quiet: cli.quiet,
            })
        }
        Command::Eval { model, runs, json, data } => cmd::eval::run(&model, &runs, json, &data),
        Command::Train { runs, model, start, preset, seed, effects, out, json, fit, data } => {
            cmd::train::run(&cmd::train::Args {
                runs,
                model,
                start,
                preset,
                seed,
                effects,
                out,
                json,
                fit,
                data,
                quiet: cli.quiet,
            })
        }
        Command::Diagnose { model, runs, validate, auto, candidates, min_gain, out, json, data } => {
            cmd::diagnose::run(&cmd::diagnose::Args {
                model,
                runs,
                validate,
                auto,
                json,
                candidates,
                min_gain,
                out,
                data,
            })
        }
        Command::Report { model, runs, validate, out, png, no_diagnose, data } => {
            cmd::report::run(&cmd::report::Args {
                model,
                runs,
                validate,
                out,
                png,
                no_diagnose,
                data,
                quiet: cli.quiet,
            })
        }
        Command::Export { model, runs, tum, mcap, robot_config, controller, data } => {
            cmd::export::run(&cmd::export::Args { model, runs, tum, mcap, robot_config, controller, data })
        }
        Command::Plan {
            model,
            effects,
            robot_from,
            set,
            runs,
            repetitions,
            speed,
            omega,
            duration,
            truth_rate,
            truth_noise_m,
            truth_noise_rad,
            out,
            json,
            data,
        } => cmd::plan::run(&cmd::plan::Args {
            model,
            effects,
            robot_from,
            request: omni_ga::excitation::PlanRequest {
                speed_m_s: speed,
                omega_rad_s: omega,
                duration_s: duration,
                truth_rate_hz: truth_rate,
                truth_noise_m,
                truth_noise_rad,
                runs,
                repetitions,
                set: match set {
                    RunSetArg::Greedy => omni_ga::excitation::RunSet::Greedy,
                    RunSetArg::Flower => omni_ga::excitation::RunSet::Flower,
                },
                ..Default::default()
            },
            out,
            json,
            data,
        }),
        Command::Init { recording, urdf, out, kind, force, max_file_mb } => cmd::init::run(&cmd::init::Args {
            recording,
            urdf,
            out,
            kind: kind.map(Into::into),
            force,
            max_file_bytes: max_file_mb.saturating_mul(1 << 20),
        }),
        Command::Demo { out, runs_per_command, hidden } => cmd::demo::run(&out, runs_per_command, &hidden, cli.quiet),
    }
}
