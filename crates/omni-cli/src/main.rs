//! The `omnical` command.

/// mimalloc instead of the system allocator: the science commands build and drop a Jacobian block of a few
/// MB per run and refit (glibc maps and unmaps each, and the kernel zeroes its pages every time), which cost
/// `explore` on the OptiOdom omni4 sets 17 % of its time (benches/README.md, issue 25).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    std::process::exit(omni_cli::entry::main_with_args(std::env::args_os()));
}
