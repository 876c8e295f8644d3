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

/// An [`Observer`] that draws the optimizers' iterations: the GA's generations against its limit, then
/// the polish.
pub struct ProgressObserver {
    bar: ProgressBar,
    max_generations: u64,
}

impl ProgressObserver {
    /// A bar for a GA of at most `max_generations` generations.
    pub fn new(max_generations: usize, quiet: bool) -> Self {
        let bar = ProgressBar::with_draw_target(Some(max_generations as u64), target(quiet));
        bar.set_style(
            ProgressStyle::with_template("{prefix:>6} [{bar:30}] {pos}/{len} {msg} [{elapsed}]")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        Self { bar, max_generations: max_generations as u64 }
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Observer for ProgressObserver {
    fn on_start(&mut self, optimizer: &str, _dim: usize) {
        self.bar.set_prefix(optimizer.to_string());
        if optimizer == "ga" {
            self.bar.set_length(self.max_generations);
        } else {
            self.bar.set_length(0);
        }
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
