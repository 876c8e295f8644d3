//! `omnical train`, `omnical diagnose` and `omnical fleet` argument lists read into requests, for callers
//! that take them as such (the Python wheel's `train_files` / `diagnose_files`, run by the fleet's workers,
//! and its `omnical fleet` command): the command line's own parser, so a list means what it means there and
//! each option is declared once.

//!
//! A front end beside `cmd/` and the Python keywords, not part of [`crate::api`]: the API takes typed
//! requests and never a command line.

use crate::api::diagnose::DiagnoseRequest;
use crate::api::train::TrainRequest;
use crate::cli::{Cli, Command};
use std::path::PathBuf;

/// An argument list that is not one of the command's.
#[derive(Debug, thiserror::Error)]
pub enum ArgvError {
    /// The parser's message (what `omnical COMMAND ARGS...` would print).
    #[error("{0}")]
    Parse(String),
    /// The list parsed as another command.
    #[error("the arguments did not parse as `omnical {0}`")]
    OtherCommand(&'static str),
}

/// `omnical COMMAND ARGS...` parsed (`args` without the program and subcommand names).
fn parse(command: &'static str, args: &[String]) -> Result<Command, ArgvError> {
    let argv = ["omnical", command].into_iter().map(String::from).chain(args.iter().cloned());
    let cli = <Cli as clap::Parser>::try_parse_from(argv).map_err(|e| ArgvError::Parse(e.render().to_string()))?;
    Ok(cli.command)
}

/// The request of `omnical train ARGS...` (`args` without the program and subcommand names, e.g.
/// `["rec/", "--seed", "3", "--out", "model.toml"]`).
pub fn train_request(args: &[String]) -> Result<TrainRequest, ArgvError> {
    match parse("train", args)? {
        Command::Train(a) => Ok(a.request()),
        _ => Err(ArgvError::OtherCommand("train")),
    }
}

/// The request of `omnical diagnose ARGS...` (`args` without the program and subcommand names, e.g.
/// `["--model", "model.toml", "rec/"]`).
pub fn diagnose_request(args: &[String]) -> Result<DiagnoseRequest, ArgvError> {
    match parse("diagnose", args)? {
        Command::Diagnose(a) => Ok(a.request()),
        _ => Err(ArgvError::OtherCommand("diagnose")),
    }
}

/// The request of `omnical diagnose ARGS...` reading its runs as `omnical train TRAIN_ARGS...` reads them:
/// the data options of `train_args` (`--robot`, `--gt-scans`, `--gt-kind`, `--gt-mount`, …) replace
/// `args`' own. The fleet diagnoses each session so, with the `-- ARGS` its sessions were trained with: a
/// session trained on its lidar is diagnosed on its lidar.
pub fn diagnose_request_reading_as(args: &[String], train_args: &[String]) -> Result<DiagnoseRequest, ArgvError> {
    let mut request = diagnose_request(args)?;
    request.data = train_request(train_args)?.data;
    Ok(request)
}

/// What `omnical fleet` does (the Python wheel's `omnical.fleet.main` runs it on Dask).
#[derive(Clone, Debug, PartialEq)]
pub struct FleetRequest {
    /// The fleet folder (`FLEET_DIR/<robot>/<session>/`).
    pub fleet_dir: PathBuf,
    /// The output folder.
    pub out: PathBuf,
    /// A Dask scheduler's address (`None`: a local cluster).
    pub scheduler: Option<String>,
    /// Local worker processes.
    pub workers: usize,
    /// Train's recipe.
    pub preset: String,
    /// GA seed of every session.
    pub seed: u64,
    /// Base model to fit.
    pub model: String,
    /// Which sessions to diagnose: `auto`, `all` or `none`.
    pub diagnose: String,
    /// Arguments for every `omnical train`.
    pub train_args: Vec<String>,
    /// No progress bar (`-q`).
    pub quiet: bool,
}

/// `omnical fleet ARGS...` (`args` without the program and subcommand names) parsed with the command
/// line's own parser: the request, or clap's error (`--help` is one: its text and exit status 0).
pub fn fleet_request(args: &[String]) -> Result<FleetRequest, clap::Error> {
    let argv = ["omnical", "fleet"].into_iter().map(String::from).chain(args.iter().cloned());
    let cli = <Cli as clap::Parser>::try_parse_from(argv)?;
    let Command::Fleet(a) = cli.command else {
        return Err(clap::Error::raw(clap::error::ErrorKind::InvalidSubcommand, "not `omnical fleet` (a bug)\n"));
    };
    Ok(FleetRequest {
        fleet_dir: a.fleet_dir,
        out: a.out,
        scheduler: a.scheduler,
        workers: a.workers,
        preset: a.preset,
        seed: a.seed,
        model: a.model,
        diagnose: a.diagnose,
        train_args: a.train_args,
        quiet: cli.quiet,
    })
}
