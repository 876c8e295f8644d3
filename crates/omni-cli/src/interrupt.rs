//! Ctrl-C (SIGINT) during `omnical train`: the first press asks the optimizer to stop at its next
//! iteration and keep the best parameters so far (the command then prints them, writes the model file
//! atomically and exits with [`EXIT_INTERRUPTED`]); a second press exits at once. Either way no output
//! file is ever half written: files are only replaced by a rename ([`crate::atomic`]).

use omni_ga::observe::{Control, Iteration, Observer};
use omni_ga::optimizer::Solution;
use std::sync::atomic::{AtomicBool, Ordering};

/// The exit status after an interruption: 128 + SIGINT, as shells report it.
pub const EXIT_INTERRUPTED: i32 = 130;

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Installs the Ctrl-C handler (once per process; later calls, or a handler the host process already set,
/// leave things as they are). Returns whether Ctrl-C is now handled here.
pub fn install() -> bool {
    ctrlc::set_handler(|| {
        if REQUESTED.swap(true, Ordering::SeqCst) {
            // The second Ctrl-C: the user does not want to wait for the current iteration.
            std::process::exit(EXIT_INTERRUPTED);
        }
    })
    .is_ok()
}

/// Whether Ctrl-C was pressed.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

/// An observer that passes everything on to `inner` and stops the optimizer after Ctrl-C.
pub struct StopOnInterrupt<'a>(pub &'a mut dyn Observer);

impl Observer for StopOnInterrupt<'_> {
    fn on_start(&mut self, optimizer: &str, dim: usize, max_iterations: Option<usize>) {
        self.0.on_start(optimizer, dim, max_iterations);
    }

    fn on_iteration(&mut self, it: &Iteration) -> Control {
        let inner = self.0.on_iteration(it);
        if requested() { Control::Stop } else { inner }
    }

    fn on_finish(&mut self, solution: &Solution) {
        self.0.on_finish(solution);
    }
}

/// The error a command returns after it was interrupted and has reported what it had; the entry point
/// turns it into [`EXIT_INTERRUPTED`].
#[derive(Debug, thiserror::Error)]
#[error("interrupted (Ctrl-C)")]
pub struct Interrupted;
