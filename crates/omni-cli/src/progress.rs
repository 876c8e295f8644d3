//! Progress on the terminal (indicatif): a bar for optimizer iterations, a spinner for long steps without
//! a count. Hidden when stderr is not a terminal (CI logs, pipes) or with `--quiet`; summaries are printed
//! by the commands whatever happens here.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use omni_ga::observe::{Control, Iteration, Observer};
use omni_ga::optimizer::Solution;
use std::time::Duration;

fn target(quiet: bool) -> ProgressDrawTarget {
    if quiet { ProgressDrawTarget::hidden() } else { ProgressDrawTarget::stderr() }
}

/// A spinner with a message, ticking on its own until dropped or finished.
pub fn spinner(message: impl Into<String>, quiet: bool) -> ProgressBar {
    let pb = ProgressBar::with_draw_target(None, target(quiet));
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg} [{elapsed}]")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    pb.set_message(message.into());
    pb.enable_steady_tick(Duration::from_millis(120));
    pb
}

/// An [`Observer`] that draws the optimizers' iterations: against the budget each optimizer states (the
/// GA's generations), or growing with them (the polish).
pub struct ProgressObserver {
    bar: ProgressBar,
}

impl ProgressObserver {
    /// A bar, hidden with `quiet`.
    pub fn new(quiet: bool) -> Self {
        let bar = ProgressBar::with_draw_target(Some(0), target(quiet));
        bar.set_style(
            ProgressStyle::with_template("{prefix:>6} [{bar:30}] {pos}/{len} {msg} [{elapsed}]")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        Self { bar }
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Observer for ProgressObserver {
    fn on_start(&mut self, optimizer: &str, _dim: usize, max_iterations: Option<usize>) {
        self.bar.set_prefix(optimizer.to_string());
        self.bar.set_length(max_iterations.unwrap_or(0) as u64);
        self.bar.set_position(0);
    }

    fn on_iteration(&mut self, it: &Iteration) -> Control {
        if it.iteration as u64 > self.bar.length().unwrap_or(0) {
            self.bar.set_length(it.iteration as u64);
        }
        self.bar.set_position(it.iteration as u64);
        self.bar.set_message(format!("best {:.6} · {} evaluations", it.best_cost, it.evaluations));
        Control::Continue
    }

    fn on_finish(&mut self, _solution: &Solution) {}
}

impl Drop for ProgressObserver {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}
