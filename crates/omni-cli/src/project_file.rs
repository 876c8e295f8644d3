//! Project defaults (`omnical.toml`, docs/formats.md "Project defaults"): the options a user would
//! otherwise repeat on every command (seed, preset, objective, joint names, topics, threads…), read from
//! `--config FILE` or an `omnical.toml` in the working directory.
//!
//! Top-level keys apply to every command that has the option; a `[train]` (any command's name) table
//! applies to that command only and wins over the top level. Each value becomes the option's default
//! for the parser, so the command line wins over the file, and the file over a robot.toml
//! (`robot_file`), which fills only what is still open. Unknown keys and values the option refuses are
//! errors naming the file, the line and the key (exit status 2).

use crate::api::settings;
use clap::Command;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use thiserror::Error;
use toml::de::DeTable;

/// The file name looked for in the working directory.
pub const FILE_NAME: &str = "omnical.toml";
/// A project file is a few hundred bytes; anything above this is not one. Bytes.
const MAX_FILE_BYTES: u64 = 1 << 20;

/// Keys whose values are paths: relative ones are relative to the project file's folder.
const PATH_KEYS: &[&str] = &["robot", "gt"];

/// Whether `key`'s value is a path (relative ones are taken from the project file's folder).
pub fn is_path_key(key: &str) -> bool {
    PATH_KEYS.contains(&key)
}

/// One value of the file.
#[derive(Clone, Debug, PartialEq)]
pub struct Setting {
    /// The command it is limited to (`[train]`), or `None` for every command.
    pub command: Option<String>,
    /// The key (`seed`).
    pub key: String,
    /// The value(s) as the command line would give them (`["7"]`, `["fl", "rl", "rr", "fr"]`).
    pub values: Vec<String>,
    /// Line of the key (1-based).
    pub line: usize,
}

/// A project file, read and checked.
#[derive(Clone, Debug, PartialEq)]
pub struct ProjectFile {
    /// Where it was read from.
    pub path: PathBuf,
    /// Its values, in file order.
    pub settings: Vec<Setting>,
}

/// What is wrong with a project file; every variant names the file.
#[derive(Debug, Error)]
pub enum ProjectFileError {
    /// The file could not be read.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        error: std::io::Error,
    },
    /// A problem at a key.
    #[error("{path}: line {line}: {key}: {message}")]
    At {
        /// The file.
        path: PathBuf,
        /// Line of the key (1-based).
        line: usize,
        /// The key, with its table (`train.seed`).
        key: String,
        /// What is wrong.
        message: String,
    },
    /// Not TOML, or too large.
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

impl ProjectFile {
    /// The setting that applies to `command` for `key`: its own table's, else the top level's.
    pub fn get(&self, command: &str, key: &str) -> Option<&Setting> {
        let own = self.settings.iter().find(|s| s.key == key && s.command.as_deref() == Some(command));
        own.or_else(|| self.settings.iter().find(|s| s.key == key && s.command.is_none()))
    }

    /// `path:line` of a setting.
    pub fn at(&self, s: &Setting) -> String {
        format!("{}:{}", self.path.display(), s.line)
    }
}

/// The project file: `flag` (`--config FILE`), else `omnical.toml` in `cwd` if there is one.
pub fn find(flag: Option<&Path>, cwd: &Path) -> Result<Option<ProjectFile>, ProjectFileError> {
    let path = match flag {
        Some(p) => p.to_path_buf(),
        None if cwd.join(FILE_NAME).is_file() => PathBuf::from(FILE_NAME),
        None => return Ok(None),
    };
    let io = |error| ProjectFileError::Io { path: path.clone(), error };
    let len = std::fs::metadata(cwd.join(&path)).map_err(io)?.len();
    if len > MAX_FILE_BYTES {
        let message = format!("{len} bytes is too large for a project file (see docs/formats.md)");
        return Err(ProjectFileError::File { path, message });
    }
    let text = std::fs::read_to_string(cwd.join(&path)).map_err(io)?;
    parse(&text, &path).map(Some)
}

/// Parses the text of a project file (`path` names it in errors and anchors relative paths), checking
/// every key against the project keys of [`settings::SETTINGS`] and every table against the commands of [`crate::cli::Cli`].
pub fn parse(text: &str, path: &Path) -> Result<ProjectFile, ProjectFileError> {
    let file = |message: String| ProjectFileError::File { path: path.to_path_buf(), message };
    let not_toml = |e: toml::de::Error| file(format!("not TOML: {}", crate::toml_error::locate(text, &e)));
    let values: toml::Table = toml::from_str(text).map_err(not_toml)?;
    let spans = DeTable::parse(text).map_err(not_toml)?;
    let line_of = |key: &str, table: Option<&str>| {
        let root = spans.get_ref();
        let span = match table {
            None => root.iter().find(|(k, _)| k.get_ref().as_ref() == key).map(|(k, _)| k.span()),
            Some(t) => root.iter().find(|(k, _)| k.get_ref().as_ref() == t).and_then(|(_, v)| {
                v.get_ref().as_table()?.iter().find(|(k, _)| k.get_ref().as_ref() == key).map(|(k, _)| k.span())
            }),
        };
        text.get(..span.map_or(0, |s| s.start)).map_or(1, |s| s.matches('\n').count() + 1)
    };
    let commands: Vec<String> = {
        use clap::CommandFactory;
        crate::cli::Cli::command().get_subcommands().map(|c| c.get_name().to_string()).collect()
    };
    let base = path.parent().unwrap_or(Path::new(""));
    let mut settings = Vec::new();
    for (key, value) in &values {
        if let toml::Value::Table(table) = value {
            if !commands.iter().any(|c| c == key) {
                return Err(ProjectFileError::At {
                    path: path.to_path_buf(),
                    line: line_of(key, None),
                    key: key.clone(),
                    message: format!("not a command; tables are named after commands: {}", commands.join(", ")),
                });
            }
            for (k, v) in table {
                let at = |message| ProjectFileError::At {
                    path: path.to_path_buf(),
                    line: line_of(k, Some(key)),
                    key: format!("{key}.{k}"),
                    message,
                };
                let values = setting_values(k, v, base).map_err(at)?;
                settings.push(Setting {
                    command: Some(key.clone()),
                    key: k.clone(),
                    values,
                    line: line_of(k, Some(key)),
                });
            }
        } else {
            let at = |message| ProjectFileError::At {
                path: path.to_path_buf(),
                line: line_of(key, None),
                key: key.clone(),
                message,
            };
            let values = setting_values(key, value, base).map_err(at)?;
            settings.push(Setting { command: None, key: key.clone(), values, line: line_of(key, None) });
        }
    }
    settings.sort_by_key(|s| s.line);
    Ok(ProjectFile { path: path.to_path_buf(), settings })
}

/// A value as command-line strings, or why it cannot be one.
fn setting_values(key: &str, value: &toml::Value, base: &Path) -> Result<Vec<String>, String> {
    if !settings::project_keys().any(|s| s.key == key) {
        let known: Vec<&str> = settings::project_keys().map(|s| s.key).collect();
        return Err(format!("unknown key; known keys: {}", known.join(", ")));
    }
    let scalar = |v: &toml::Value| match v {
        toml::Value::String(s) => Ok(s.clone()),
        toml::Value::Integer(i) => Ok(i.to_string()),
        toml::Value::Float(f) => Ok(f.to_string()),
        toml::Value::Boolean(b) => Ok(b.to_string()),
        other => Err(format!("expected a string, number or boolean, found {}", other.type_str())),
    };
    let mut values = match value {
        toml::Value::Array(a) if key == "joints" => a.iter().map(scalar).collect::<Result<Vec<_>, _>>()?,
        v => vec![scalar(v)?],
    };
    if PATH_KEYS.contains(&key) {
        for v in &mut values {
            if v != crate::robot_file::BUILTIN_APR02 && Path::new(v).is_relative() {
                *v = base.join(&v).display().to_string();
            }
        }
    }
    Ok(values)
}

/// The command line's parser with the project's values as the options' defaults, after checking each
/// value with its option's own parser (`preset = "fast"` is refused here, naming the file and line).
pub fn apply(mut cli: Command, project: &ProjectFile) -> Result<Command, ProjectFileError> {
    let names: Vec<String> = cli.get_subcommands().map(|c| c.get_name().to_string()).collect();
    // `--threads` is the one global option: set on the top command, it reaches every subcommand.
    if let Some(s) = project.settings.iter().find(|s| s.key == "threads" && s.command.is_none()) {
        check(&cli, project, s)?;
        cli = cli.mut_arg("threads", |a| a.default_values(&s.values));
    }
    let mut keys: Vec<&str> = project.settings.iter().map(|s| s.key.as_str()).collect();
    keys.sort_unstable();
    keys.dedup();
    for name in names {
        let Some(sub) = cli.find_subcommand(&name) else { continue };
        let mut fixed = Vec::new();
        for &key in &keys {
            let applies = |s: &&Setting| {
                has_arg(sub, key) && !(s.command.is_none() && crate::cmd::imu::ignores_project_wide(&name, key))
            };
            if let Some(s) = project.get(&name, key).filter(applies) {
                check(sub, project, s)?;
                fixed.push(s.clone());
            } else if let Some(s) =
                project.settings.iter().find(|s| s.key == key && s.command.as_deref() == Some(&name))
            {
                return Err(ProjectFileError::At {
                    path: project.path.clone(),
                    line: s.line,
                    key: format!("{name}.{key}"),
                    message: format!("`omnical {name}` has no --{}", key.replace('_', "-")),
                });
            }
        }
        cli = cli.mut_subcommand(&name, |mut c| {
            for s in &fixed {
                c = c.mut_arg(s.key.as_str(), |a| a.default_values(&s.values));
            }
            c
        });
    }
    Ok(cli)
}

fn has_arg(cmd: &Command, id: &str) -> bool {
    cmd.get_arguments().any(|a| a.get_id() == id && !a.is_positional())
}

/// Checks a setting with its option's value parser (the option alone, in a parser of its own).
fn check(cmd: &Command, project: &ProjectFile, s: &Setting) -> Result<(), ProjectFileError> {
    let Some(arg) = cmd.get_arguments().find(|a| a.get_id() == s.key.as_str()) else { return Ok(()) };
    let Some(long) = arg.get_long() else { return Ok(()) };
    let alone = Command::new("omnical")
        .no_binary_name(true)
        .arg(arg.clone().action(clap::ArgAction::Append).num_args(1).value_delimiter(None).allow_hyphen_values(true));
    for v in &s.values {
        let flag = format!("--{long}");
        if let Err(e) = alone.clone().try_get_matches_from([OsStr::new(&flag), OsStr::new(v)]) {
            let text = e.to_string();
            let first = text.lines().next().unwrap_or_default().trim_start_matches("error: ");
            let hint = text.lines().find(|l| l.trim_start().starts_with("[possible values")).map(str::trim);
            return Err(ProjectFileError::At {
                path: project.path.clone(),
                line: s.line,
                key: s.command.as_ref().map_or_else(|| s.key.clone(), |c| format!("{c}.{}", s.key)),
                message: hint.map_or_else(|| first.to_string(), |h| format!("{first} {h}")),
            });
        }
    }
    Ok(())
}
