//! Diagnostics on stderr through `tracing`: notes, warnings, and with `-v`/`-vv` what was loaded and how
//! long it took. Results go to stdout and never through here.
//!
//! | flags | shown |
//! |---|---|
//! | `-q` | warnings (and skipped inputs) |
//! | none | notes and warnings |
//! | `-v` | also `info:` lines: files read, the robot description picked up, timings |
//! | `-vv` | also `debug:` lines (`-vvv`: `trace:`) |
//!
//! `RUST_LOG` (`tracing-subscriber`'s `EnvFilter` syntax, e.g. `RUST_LOG=debug`), when set, replaces the
//! level the flags choose. Notes are `INFO` events on the target [`NOTE`], printed as written (`note: …`,
//! `robot: …`); other events get their level as a prefix (`warning: …`, `info: …`).
//!
//! The subscriber is installed once per process ([`init`] may be called for every command: the Python
//! wheel's console entry runs many commands in one interpreter); later calls only change its level. The
//! core crates (omni-kin, omni-ga) print nothing: they return notes as data, and the CLI says them here.

use std::sync::{Mutex, OnceLock, PoisonError};
use tracing::{Event, Level, Subscriber};
use tracing_subscriber::fmt::format::Writer;
use tracing_subscriber::fmt::{FmtContext, FormatEvent, FormatFields};
use tracing_subscriber::prelude::*;
use tracing_subscriber::registry::LookupSpan;
use tracing_subscriber::{EnvFilter, Registry, reload};

/// The target of notes: printed verbatim at the default level, hidden by `-q`.
pub const NOTE: &str = "omnical::note";

/// A note on stderr, e.g. `note!("note: {text}")`: shown by default, hidden by `-q`; the text is printed
/// as given.
#[macro_export]
macro_rules! note {
    ($($arg:tt)*) => { ::tracing::info!(target: $crate::logging::NOTE, $($arg)*) };
}

/// How much to say on stderr: `-q` (-1), nothing (0), `-v` (1), `-vv` (2), `-vvv` (3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Verbosity(pub i8);

impl Verbosity {
    /// From the command line's `--quiet` and the number of `-v`.
    pub fn from_flags(quiet: bool, verbose: u8) -> Self {
        if quiet { Self(-1) } else { Self(i8::try_from(verbose).unwrap_or(i8::MAX)) }
    }

    /// The filter directives of this level.
    pub fn directives(self) -> &'static str {
        match self.0 {
            ..0 => "warn",
            0 => "warn,omnical::note=info",
            1 => "info",
            2 => "debug",
            _ => "trace",
        }
    }
}

type Handle = reload::Handle<EnvFilter, Registry>;

/// Installs the stderr subscriber at `verbosity` (or `RUST_LOG`), or sets the level of the one installed
/// by an earlier call; and starts a new command for [`first_in_command`]. Never fails: when another
/// global subscriber was installed by the host program, that one is left in charge.
pub fn init(verbosity: Verbosity) {
    let from_env = std::env::var("RUST_LOG").ok().filter(|s| !s.trim().is_empty());
    let (filter, bad_env) = match from_env.as_deref().map(EnvFilter::try_new) {
        Some(Ok(f)) => (f, None),
        Some(Err(e)) => (EnvFilter::new(verbosity.directives()), Some(e)),
        None => (EnvFilter::new(verbosity.directives()), None),
    };
    static HANDLE: OnceLock<Option<Handle>> = OnceLock::new();
    let mut pending = Some(filter);
    let handle = HANDLE.get_or_init(|| {
        let (layer, handle) = reload::Layer::new(pending.take().unwrap_or_default());
        let fmt = tracing_subscriber::fmt::layer().with_writer(std::io::stderr).event_format(Plain);
        tracing_subscriber::registry().with(layer).with(fmt).try_init().ok().map(|()| handle)
    });
    if let (Some(h), Some(filter)) = (handle, pending) {
        // Fails only when the subscriber is gone, and then there is nothing to set.
        let _ = h.reload(filter);
    }
    if let Some(e) = bad_env {
        tracing::warn!("RUST_LOG={:?} is not a filter ({e}); using the level of -q/-v", from_env.unwrap_or_default());
    }
    SAID.lock().unwrap_or_else(PoisonError::into_inner).clear();
}

/// What was said in this command ([`first_in_command`]).
static SAID: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// True the first time `key` is asked about in the current command (since the last [`init`]): for lines
/// said once per command however often their cause comes up (a robot description found for two sets of
/// runs).
pub fn first_in_command(key: &str) -> bool {
    let mut said = SAID.lock().unwrap_or_else(PoisonError::into_inner);
    if said.iter().any(|k| k == key) {
        return false;
    }
    said.push(key.to_string());
    true
}

/// One line per event: notes as written, others after their level (`warning: …`), then any fields; the
/// settings the library names are spelled as flags ([`crate::api::settings::as_flags`]).
struct Plain;

impl<S, N> FormatEvent<S, N> for Plain
where
    S: Subscriber + for<'a> LookupSpan<'a>,
    N: for<'a> FormatFields<'a> + 'static,
{
    fn format_event(&self, ctx: &FmtContext<'_, S, N>, mut w: Writer<'_>, event: &Event<'_>) -> std::fmt::Result {
        let meta = event.metadata();
        if meta.target() != NOTE {
            let label = match *meta.level() {
                Level::ERROR => "error",
                Level::WARN => "warning",
                Level::INFO => "info",
                Level::DEBUG => "debug",
                Level::TRACE => "trace",
            };
            write!(w, "{label}: ")?;
        }
        // The library's words for its settings become the command line's flags here, once for every line.
        let mut text = String::new();
        ctx.field_format().format_fields(Writer::new(&mut text), event)?;
        writeln!(w, "{}", crate::api::settings::as_flags(&text))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_choose_the_level() {
        assert_eq!(Verbosity::from_flags(true, 0).directives(), "warn");
        assert_eq!(Verbosity::from_flags(false, 0).directives(), "warn,omnical::note=info");
        assert_eq!(Verbosity::from_flags(false, 1).directives(), "info");
        assert_eq!(Verbosity::from_flags(false, 2).directives(), "debug");
        assert_eq!(Verbosity::from_flags(false, 200).directives(), "trace");
    }

    #[test]
    fn a_key_is_first_once_per_command() {
        init(Verbosity::default());
        assert!(first_in_command("robot.toml"));
        assert!(!first_in_command("robot.toml"));
        assert!(first_in_command("other/robot.toml"));
        // Installing again (a second command in the same process) is no error and starts afresh.
        init(Verbosity(1));
        assert!(first_in_command("robot.toml"));
    }
}
