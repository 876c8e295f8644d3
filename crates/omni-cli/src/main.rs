//! The `omnical` command.

fn main() {
    std::process::exit(omni_cli::entry::main_with_args(std::env::args_os()));
}
