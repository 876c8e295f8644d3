//! `omnical train` and `omnical diagnose` argument lists read into requests, for callers that take them as
//! such (the Python wheel's `train_files` / `diagnose_files`, run by the fleet's workers): the command's own
//! parser, so a list means what it means on the command line.

use super::diagnose::DiagnoseRequest;
use super::train::TrainRequest;
use crate::cli::{Cli, Command};

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
