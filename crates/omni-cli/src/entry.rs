//! The `omnical` command's entry point as a library function, so the native binary and the Python
//! wheel's console script (`omnical._omnical.cli_main`) run the same code.

use crate::cli::{Cli, run};
use clap::Parser;
use std::ffi::OsString;

/// Parses `args` (the program name first, as `std::env::args_os`) and runs the command. Returns the exit
/// status: 0 on success and for `--help`/`--version` and a closed pipe, 2 on errors (printed on stderr as
/// `error: {e:#}`), 130 after Ctrl-C stopped a training, clap's own status for usage errors.
pub fn main_with_args(args: impl IntoIterator<Item = OsString>) -> i32 {
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            // `--help` and `--version` arrive here too; clap prints them on stdout and exits 0.
            let _ = e.print();
            return e.exit_code();
        }
    };
    match run(cli) {
        Ok(()) => 0,
        Err(e) => {
            // A closed pipe (`omnical eval … | head`) is not a failure.
            if e.chain().any(|c| {
                c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            }) {
                return 0;
            }
            if e.downcast_ref::<crate::interrupt::Interrupted>().is_some() {
                eprintln!("omnical: {e:#}");
                return crate::interrupt::EXIT_INTERRUPTED;
            }
            eprintln!("error: {e:#}");
            2
        }
    }
}
