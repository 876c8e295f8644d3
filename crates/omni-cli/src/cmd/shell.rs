//! `omnical completions SHELL` and `omnical man`: shell completions (clap_complete) and roff man pages
//! (clap_mangen), made from the same clap definitions as the parser and `--help`, so they never drift.

use crate::atomic;
use crate::cli::Cli;
use anyhow::Context;
use clap::CommandFactory;
use clap_complete::Shell;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `omnical completions`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Install, e.g.:\n  \
    bash: mkdir -p ~/.local/share/bash-completion/completions && \
    omnical completions bash > ~/.local/share/bash-completion/completions/omnical\n  \
    zsh:  mkdir -p ~/.zfunc && omnical completions zsh > ~/.zfunc/_omnical   \
    (with fpath+=~/.zfunc before compinit in ~/.zshrc)\n  \
    fish: mkdir -p ~/.config/fish/completions && omnical completions fish > ~/.config/fish/completions/omnical.fish")]
pub struct CompletionsArgs {
    /// The shell to complete for.
    #[arg(value_enum)]
    pub shell: Shell,
}

/// Arguments of `omnical man`.
#[derive(Debug, clap::Args)]
pub struct ManArgs {
    /// Write one page per command into this folder (`omnical.1`, `omnical-train.1`, …) instead of the
    /// top page to stdout. Read one with `man -l DIR/omnical-train.1`. Other files in the folder stay.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// The command line as the generators see it (no `help` subcommand: `--help` is the help).
fn command() -> clap::Command {
    let mut cmd = Cli::command().disable_help_subcommand(true);
    cmd.build();
    cmd
}

/// Runs `omnical completions`: the script on stdout.
pub fn completions(a: &CompletionsArgs) -> anyhow::Result<()> {
    let mut cmd = command();
    let mut script = Vec::new();
    clap_complete::generate(a.shell, &mut cmd, "omnical", &mut script);
    std::io::stdout().lock().write_all(&script)?;
    Ok(())
}

/// The man pages: the top page first, then one per subcommand (`omnical-train.1`), as (file name, roff).
pub fn man_pages() -> anyhow::Result<Vec<(String, Vec<u8>)>> {
    let top = command();
    let mut pages = Vec::new();
    for cmd in std::iter::once(&top).chain(top.get_subcommands().filter(|s| !s.is_hide_set())) {
        let man = clap_mangen::Man::new(cmd.clone());
        let mut roff = Vec::new();
        man.render(&mut roff)?;
        pages.push((man.get_filename(), roff));
    }
    Ok(pages)
}

/// Runs `omnical man`: the top page on stdout, or every page into `--out`.
pub fn man(a: &ManArgs) -> anyhow::Result<()> {
    let pages = man_pages()?;
    let Some(dir) = &a.out else {
        let (_, top) = &pages[0];
        std::io::stdout().lock().write_all(top)?;
        return Ok(());
    };
    crate::out_path::prepare_dir(dir, "--out")?;
    for (name, roff) in &pages {
        let path = dir.join(name);
        atomic::write_atomic(&path, roff).with_context(|| format!("writing {}", path.display()))?;
    }
    println!(
        "wrote {} man pages to {} (read one with `man -l {}`)",
        pages.len(),
        dir.display(),
        dir.join("omnical.1").display()
    );
    Ok(())
}
