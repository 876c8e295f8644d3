//! The `omnical` command's entry point as a library function, so the native binary and the Python
//! wheel's console script (`omnical._omnical.cli_main`) run the same code.

use crate::cli::{Cli, run};
use clap::error::{ContextKind, ContextValue, Error, ErrorKind};
use clap::{CommandFactory, FromArgMatches, Parser};
use std::ffi::OsString;

/// Caps the cost kernel's lane arithmetic at `OMNICAL_SIMD` (`avx512`, `avx2` or `portable`) when it is
/// set: for comparing paths on one machine (the results are the same bits on each).
fn simd_from_env() -> Result<(), String> {
    let Some(value) = std::env::var_os("OMNICAL_SIMD") else { return Ok(()) };
    let value = value.to_string_lossy();
    if value.trim().is_empty() {
        return Ok(());
    }
    let path = omni_kin::fast::SimdPath::from_name(&value)
        .ok_or_else(|| format!("OMNICAL_SIMD={value}: expected avx512, avx2 or portable"))?;
    omni_kin::fast::limit_simd_path(path);
    Ok(())
}

/// Parses `args` (the program name first, as `std::env::args_os`) and runs the command. Returns the exit
/// status: 0 on success and for `--help`/`--version` and a closed pipe, 2 on errors (printed on stderr as
/// `error: {e:#}`), 1 for a refused fit (`train`: its step, or a fit worse than its start; `--force`), 130
/// after Ctrl-C stopped a training, clap's own status for usage errors.
pub fn main_with_args(args: impl IntoIterator<Item = OsString>) -> i32 {
    let args: Vec<OsString> = args.into_iter().collect();
    let cli = match Cli::try_parse_from(&args) {
        Ok(cli) => cli,
        Err(e) => {
            // `--help` and `--version` arrive here too; clap prints them on stdout and exits 0.
            let mut e = nearest_flag_error(e, &args);
            if let Some(tip) = validate_tip(&e, &args).or_else(|| robot_from_tip(&e, &args)) {
                e.insert(ContextKind::Suggested, ContextValue::StyledStrs(vec![tip.into()]));
            }
            let _ = e.print();
            return e.exit_code();
        }
    };
    if let Err(e) = simd_from_env() {
        eprintln!("error: {e}");
        return 2;
    }
    let (cli, project) = match with_project_defaults(cli, &args) {
        Ok(found) => found,
        Err(status) => return status,
    };
    if let Some(p) = &project {
        crate::out_path::note_project_file(&p.path);
    }
    match run_quiet_on_closed_pipe(cli) {
        Ok(()) => 0,
        Err(e) => match Failure::of(&e) {
            // A closed pipe (`omnical eval … | head`) is not a failure.
            Failure::ClosedPipe => 0,
            Failure::Refused => {
                eprintln!("error: {}", said(&e));
                crate::cmd::train::EXIT_REFUSED
            }
            Failure::Interrupted => {
                eprintln!("omnical: {}", said(&e));
                crate::interrupt::EXIT_INTERRUPTED
            }
            Failure::Error => {
                let text = said(&e);
                eprintln!(
                    "error: {}",
                    project.map_or_else(|| text.clone(), |p| with_project_origins(&text, &p, &args))
                );
                2
            }
        },
    }
}

/// A failed command's error and its sources (`{e:#}`) with the settings the library names as the command
/// line's flags ([`crate::api::settings::as_flags`]).
fn said(e: &anyhow::Error) -> String {
    crate::api::settings::as_flags(&format!("{e:#}"))
}

/// How a failed command ends, from the first error among `e`'s sources that has an exit status of its own
/// (so a `.context(…)` around one keeps its status). A `#[error(transparent)]` wrapper hides its inner error
/// from `source()`, so the library returns these at the top of its own error, never inside one.
#[derive(Debug, PartialEq)]
enum Failure {
    /// Writing into a closed pipe: exit 0.
    ClosedPipe,
    /// A fit refused ([`crate::api::fit::Refused`]): [`crate::cmd::train::EXIT_REFUSED`].
    Refused,
    /// Ctrl-C ([`crate::interrupt::Interrupted`]): [`crate::interrupt::EXIT_INTERRUPTED`].
    Interrupted,
    /// Any other error: exit 2.
    Error,
}

impl Failure {
    fn of(e: &anyhow::Error) -> Self {
        let closed_pipe = |c: &(dyn std::error::Error + 'static)| {
            c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
        };
        if e.chain().any(closed_pipe) {
            Self::ClosedPipe
        } else if e.chain().any(|c| {
            // A refusal, or the training's error holding one (transparent: it is not in the chain of its own).
            c.is::<crate::api::fit::Refused>()
                || matches!(c.downcast_ref(), Some(crate::api::train::TrainError::Refused(_)))
        }) {
            Self::Refused
        } else if e.chain().any(|c| c.is::<crate::interrupt::Interrupted>()) {
            Self::Interrupted
        } else {
            Self::Error
        }
    }
}

/// An error message with the project file's values named where they came from: a flag the file set
/// (`--joints-topic /js`) becomes the file's key with its line (`joints_topic = "/js" (omnical.toml, line
/// 2)`), and a path it set that the message names gets a note giving the key and line. Values given on the
/// command line itself are left alone.
pub fn with_project_origins(text: &str, project: &crate::project_file::ProjectFile, args: &[OsString]) -> String {
    let cli = Cli::command();
    let Some(command) = args.iter().skip(1).find_map(|a| cli.find_subcommand(a).map(|c| c.get_name().to_string()))
    else {
        return text.to_string();
    };
    let mut text = text.to_string();
    let mut notes = Vec::new();
    let mut keys: Vec<&str> = project.settings.iter().map(|s| s.key.as_str()).collect();
    keys.sort_unstable();
    keys.dedup();
    for key in keys {
        let Some(s) = project.get(&command, key) else { continue };
        let flag = format!("--{}", key.replace('_', "-"));
        let on_command_line =
            args.iter().any(|a| a.to_str().is_some_and(|a| a == flag || a.starts_with(&format!("{flag}="))));
        if on_command_line {
            continue;
        }
        let value = s.values.join(",");
        let (file, line) = (project.path.display(), s.line);
        let origin = format!("{key} = {value:?} ({file}, line {line})");
        let as_flag = format!("{flag} {value}");
        if text.contains(&as_flag) {
            text = text.replace(&as_flag, &origin);
        } else if crate::project_file::is_path_key(key) && text.contains(&value) {
            notes.push(format!("\n  note: {key} = {value:?} is set in {file}, line {line}"));
        }
    }
    text + &notes.concat()
}

/// The command line parsed again with the project file's values (`--config FILE` or ./omnical.toml) as
/// the options' defaults; unchanged without one, and for `omnical config`, which shows the layers itself.
/// `Err` is the exit status after the error was printed (2 for a bad project file).
fn with_project_defaults(cli: Cli, args: &[OsString]) -> Result<(Cli, Option<crate::project_file::ProjectFile>), i32> {
    if matches!(cli.command, crate::cli::Command::Config(_)) {
        return Ok((cli, None));
    }
    let cwd = std::env::current_dir().unwrap_or_default();
    let project = match crate::project_file::find(cli.config.as_deref(), &cwd) {
        Ok(Some(p)) => p,
        Ok(None) => return Ok((cli, None)),
        Err(e) => {
            eprintln!("error: {e}");
            return Err(2);
        }
    };
    let command = crate::project_file::apply(Cli::command(), &project).map_err(|e| {
        eprintln!("error: {e}");
        2
    })?;
    let cli = command.try_get_matches_from(args).and_then(|m| Cli::from_arg_matches(&m)).map_err(|e| {
        let _ = e.print();
        e.exit_code()
    })?;
    Ok((cli, Some(project)))
}

/// When the positional runs are missing from a command line that has `--validate` (an older spelling gave
/// it several paths, and the runs were taken for held-out ones), the spelling that works.
fn validate_tip(e: &Error, args: &[OsString]) -> Option<String> {
    if e.kind() != ErrorKind::MissingRequiredArgument
        || !args.iter().any(|a| a.to_string_lossy().starts_with("--validate"))
    {
        return None;
    }
    let cli = Cli::command();
    let command = args.iter().skip(1).find_map(|a| cli.find_subcommand(a).map(|c| c.get_name().to_string()))?;
    Some(format!(
        "--validate takes one path (repeat it for more) and the training runs come without a flag: \
         omnical {command} --model MODEL TRAIN_RUNS... --validate HELD_OUT [--validate HELD_OUT]..."
    ))
}

/// An unknown `--flag` with the suggestion (and usage line) of [`nearest_flag`] instead of clap's, whose
/// similarity measure takes `--ot` for `--joints-topic` rather than `--out`; other errors unchanged.
fn nearest_flag_error(e: Error, args: &[OsString]) -> Error {
    let Some(ContextValue::String(invalid)) = e.get(ContextKind::InvalidArg) else { return e };
    let Some(typed) = invalid.strip_prefix("--") else { return e };
    if e.kind() != ErrorKind::UnknownArgument {
        return e;
    }
    let mut cli = Cli::command();
    cli.build();
    let Some(sub) = args.iter().skip(1).find_map(|a| cli.find_subcommand(a)) else { return e };
    let longs: Vec<&str> = sub.get_arguments().chain(cli.get_arguments()).filter_map(|a| a.get_long()).collect();
    let mut fixed = Error::new(ErrorKind::UnknownArgument).with_cmd(sub);
    for (kind, value) in e.context().filter(|(k, _)| !matches!(k, ContextKind::SuggestedArg | ContextKind::Usage)) {
        fixed.insert(kind, value.clone());
    }
    if let Some(flag) = nearest_flag(typed.split('=').next().unwrap_or(typed), &longs) {
        fixed.insert(ContextKind::SuggestedArg, ContextValue::String(format!("--{flag}")));
    }
    fixed.insert(ContextKind::Usage, ContextValue::StyledStr(sub.clone().render_usage()));
    fixed
}

/// The long flag a mistyped `typed` (without `--`) most likely meant: the only one it begins, else the
/// nearest by edit distance (at most 1 for up to four letters, 2 beyond; ties go to the one with the same
/// first letter, then to the first declared).
pub fn nearest_flag<'a>(typed: &str, longs: &[&'a str]) -> Option<&'a str> {
    let prefixed: Vec<&str> = longs.iter().copied().filter(|l| l.starts_with(typed)).collect();
    if let [only] = prefixed[..] {
        return Some(only);
    }
    let limit = if typed.chars().count() <= 4 { 1 } else { 2 };
    longs
        .iter()
        .map(|l| (edit_distance(typed, l), !l.starts_with(typed.get(..1).unwrap_or("")), *l))
        .filter(|(d, _, _)| *d <= limit)
        .min_by_key(|(d, other_initial, _)| (*d, *other_initial))
        .map(|(_, _, l)| l)
}

/// Levenshtein distance (insertions, deletions, substitutions) between two strings, by characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let substitute = diagonal + usize::from(ca != cb);
            diagonal = row[j + 1];
            row[j + 1] = substitute.min(row[j] + 1).min(row[j + 1] + 1);
        }
    }
    row[b.len()]
}

/// When `plan` got paths it takes none of (an older spelling gave `--robot-from` several), the spelling that
/// works.
fn robot_from_tip(e: &Error, args: &[OsString]) -> Option<String> {
    let plan = args.iter().skip(1).any(|a| a == "plan");
    let robot_from = args.iter().any(|a| a.to_string_lossy().starts_with("--robot-from"));
    (e.kind() == ErrorKind::UnknownArgument && plan && robot_from).then(|| {
        "--robot-from takes one path (repeat it for more): omnical plan --robot-from RUNS [--robot-from RUNS]..."
            .to_string()
    })
}

/// The panic message of `print!`/`println!` when stdout is a closed pipe.
const CLOSED_PIPE_PANIC: &str = "failed printing to stdout";

/// Runs the command; a `print!` into a closed pipe (`omnical eval … | head -1`) ends it quietly as
/// `Ok(())` instead of a panic, the way `cat` or `ls` end when `head` stops reading. Other panics go on
/// unchanged (their message is printed by the previous hook).
fn run_quiet_on_closed_pipe(cli: Cli) -> anyhow::Result<()> {
    install_closed_pipe_hook();
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(cli))) {
        Ok(result) => result,
        Err(payload) if is_closed_pipe_panic(payload.as_ref()) => Ok(()),
        Err(payload) => std::panic::resume_unwind(payload),
    }
}

fn is_closed_pipe_panic(payload: &(dyn std::any::Any + Send)) -> bool {
    let message = payload
        .downcast_ref::<String>()
        .map(String::as_str)
        .or_else(|| payload.downcast_ref::<&str>().copied())
        .unwrap_or("");
    message.starts_with(CLOSED_PIPE_PANIC) && message.contains("Broken pipe")
}

/// Silences the panic hook for the closed-pipe panic only (once per process).
fn install_closed_pipe_hook() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !is_closed_pipe_panic(info.payload()) {
                previous(info);
            }
        }));
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exit_statuses_are_found_among_the_sources() {
        use crate::api::fit::Refused;
        use crate::interrupt::Interrupted;
        let refused = anyhow::Error::from(Refused("worse than its start".into()));
        assert_eq!(Failure::of(&refused), Failure::Refused);
        assert_eq!(Failure::of(&refused.context("training")), Failure::Refused);
        let in_training = crate::api::train::TrainError::Refused(Refused("implausible".into()));
        assert_eq!(Failure::of(&anyhow::Error::from(in_training)), Failure::Refused);
        assert_eq!(Failure::of(&anyhow::Error::from(Interrupted).context("loading")), Failure::Interrupted);
        let pipe = std::io::Error::from(std::io::ErrorKind::BrokenPipe);
        assert_eq!(Failure::of(&anyhow::Error::from(pipe).context("writing")), Failure::ClosedPipe);
        assert_eq!(Failure::of(&anyhow::anyhow!("bad input")), Failure::Error);
    }

    #[test]
    fn a_mistyped_flag_gets_the_nearest_one() {
        let train = ["model", "start", "preset", "seed", "effect", "out", "json", "joints", "joints-topic", "gt"];
        assert_eq!(nearest_flag("ot", &train), Some("out"));
        assert_eq!(nearest_flag("oot", &train), Some("out"));
        assert_eq!(nearest_flag("pres", &train), Some("preset"));
        assert_eq!(nearest_flag("joints-topc", &train), Some("joints-topic"));
        assert_eq!(nearest_flag("gt-topic", &["gt", "gt-topic"]), Some("gt-topic"));
        assert_eq!(nearest_flag("xyz", &train), None);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("", "abc"), 3);
    }
}
