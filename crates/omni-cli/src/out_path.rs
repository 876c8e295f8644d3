//! Where results go, checked before any work starts: a result file's folder must exist and take files,
//! and a result folder of per-run files (`simulate --out`, `demo --out`, `export --tum`, `export --mcap`)
//! must be new or empty, unless `--force`, which replaces it whole.
//!
//! A result folder is filled in a staging folder beside it (`.NAME.omnical-tmp-PID`) and put in place by
//! [`OutDir::commit`] with renames, so a command that fails leaves the old folder as it was and never a
//! folder that mixes old runs with new ones. Folders of fixed file names that a user may share with other
//! files (`report --png`, `export --robot-config`, `man --out`) are [`prepared`](prepare_dir) instead: the
//! command writes its own file names and leaves the rest alone.
//!
//! A result folder never holds, nor lies inside, anything the command reads ([`Inputs`]): the recordings,
//! the robot file, the commands, the model, the project file. That is refused before any work, with or
//! without `--force`, so `--force` can never delete an input, and an export never lands among the data it
//! would be read back with.

mod error;

pub use error::OutPathError;
use std::path::{Component, Path, PathBuf};
use std::sync::OnceLock;

/// A file or folder a command reads, with what it is for messages (`the data`, `--robot`, `model=`).
#[derive(Clone, Debug)]
pub struct Input {
    /// What the input is, as the user gave it: `the data`, `--robot`, `commands=`.
    pub what: String,
    /// Its path as given.
    pub path: PathBuf,
}

/// Everything a command reads from files, gathered before its result folders are claimed
/// ([`OutDir::claim`]). The project file in force (`--config FILE` or `./omnical.toml`) is always one.
#[derive(Clone, Debug, Default)]
pub struct Inputs(Vec<Input>);

/// The project file in force for this process, set once when it is read (`entry`).
static PROJECT_FILE: OnceLock<PathBuf> = OnceLock::new();

/// Records the project file this process read its defaults from, so that no result folder replaces it.
pub fn note_project_file(path: &Path) {
    let _ = PROJECT_FILE.set(path.to_path_buf());
}

impl Inputs {
    /// No inputs but the project file in force.
    pub fn new() -> Self {
        let inputs = Self(Vec::new());
        match PROJECT_FILE.get() {
            Some(p) => inputs.with("the project file", p),
            None => inputs,
        }
    }

    /// The data paths (files or folders) a command reads.
    pub fn data(paths: &[PathBuf]) -> Self {
        paths.iter().fold(Self::new(), |i, p| i.with("the data", p))
    }

    /// Adds the input `path`, described as `what`.
    #[must_use]
    pub fn with(mut self, what: &str, path: impl AsRef<Path>) -> Self {
        self.0.push(Input { what: what.to_string(), path: path.as_ref().to_path_buf() });
        self
    }

    /// Adds `path` when given.
    #[must_use]
    pub fn with_some(self, what: &str, path: Option<impl AsRef<Path>>) -> Self {
        match path {
            Some(p) => self.with(what, p),
            None => self,
        }
    }

    /// The inputs gathered.
    pub fn iter(&self) -> impl Iterator<Item = &Input> {
        self.0.iter()
    }
}

/// The folder a path's file goes into (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Checks that a file can be created in `folder` (a probe file, removed at once).
fn check_writable(folder: &Path) -> std::io::Result<()> {
    let probe = folder.join(format!(".omnical-write-check-{}", std::process::id()));
    std::fs::OpenOptions::new().write(true).create_new(true).open(&probe)?;
    std::fs::remove_file(&probe)
}

/// Checks, before the work, that the result file `path` (given with `flag`, e.g. `--out`) can be written:
/// it is not a folder, its folder exists and takes files. The file itself is written later, atomically.
pub fn check_file(path: &Path, flag: &str) -> Result<(), OutPathError> {
    let (flag, path_buf) = (flag.to_string(), path.to_path_buf());
    if path.is_dir() {
        return Err(OutPathError::IsFolder { flag, path: path_buf });
    }
    let folder = folder_of(path).to_path_buf();
    if !folder.is_dir() {
        return Err(OutPathError::NoFolder { flag, path: path_buf, folder });
    }
    check_writable(&folder).map_err(|source| OutPathError::CannotWriteIn { flag, path: path_buf, folder, source })
}

/// Makes the folder `dir` (given with `flag`) for results of fixed file names, and checks that it takes
/// files, before the work: a missing folder is created (with its parents), files already in it stay.
pub fn prepare_dir(dir: &Path, flag: &str) -> Result<(), OutPathError> {
    if dir.exists() && !dir.is_dir() {
        return Err(OutPathError::IsFile { flag: flag.into(), dir: dir.to_path_buf() });
    }
    create_dir_all(dir, flag)?;
    check_writable_dir(dir, flag)
}

/// `dir` and its missing parents created, for the option `flag`.
fn create_dir_all(dir: &Path, flag: &str) -> Result<(), OutPathError> {
    std::fs::create_dir_all(dir).map_err(|source| OutPathError::Create {
        flag: flag.into(),
        dir: dir.to_path_buf(),
        source,
    })
}

/// [`check_writable`] on the result folder `dir` itself, for the option `flag`.
fn check_writable_dir(dir: &Path, flag: &str) -> Result<(), OutPathError> {
    check_writable(dir).map_err(|source| OutPathError::CannotWrite {
        flag: flag.into(),
        dir: dir.to_path_buf(),
        source,
    })
}

/// Up to three entries of a folder, for messages: `train, validation, truth.json, …`.
fn some_entries(dir: &Path) -> std::io::Result<Option<String>> {
    let mut names: Vec<String> = std::fs::read_dir(dir)?
        .map(|e| e.map(|e| e.file_name().to_string_lossy().into_owned()))
        .collect::<Result<_, _>>()?;
    if names.is_empty() {
        return Ok(None);
    }
    names.sort();
    let more = if names.len() > 3 { ", …" } else { "" };
    Ok(Some(format!("{}{more}", names[..names.len().min(3)].join(", "))))
}

/// Refuses to `--force` away a folder that holds the working directory or is the home folder.
fn check_replaceable(dir: &Path, flag: &str) -> Result<(), OutPathError> {
    let (flag, dir) = (flag.to_string(), dir.to_path_buf());
    let canonical = match dir.canonicalize() {
        Ok(c) => c,
        Err(source) => return Err(OutPathError::Canonicalize { flag, dir, source }),
    };
    let cwd = std::env::current_dir().and_then(|d| d.canonicalize()).unwrap_or_default();
    if cwd.starts_with(&canonical) {
        return Err(OutPathError::HoldsWorkingDirectory { flag, dir });
    }
    let home = std::env::var_os("HOME").map(PathBuf::from).and_then(|h| h.canonicalize().ok());
    if home.is_some_and(|h| h == canonical) {
        return Err(OutPathError::Home { flag, dir });
    }
    Ok(())
}

/// `path` made absolute and resolved as far as it exists: its longest existing ancestor canonical (links
/// followed), the rest appended with `.` and `..` taken lexically.
fn resolved(path: &Path) -> PathBuf {
    let cwd = std::env::current_dir().unwrap_or_default();
    let absolute = if path.is_absolute() { path.to_path_buf() } else { cwd.join(path) };
    let mut lexical = PathBuf::new();
    for c in absolute.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                lexical.pop();
            }
            other => lexical.push(other),
        }
    }
    let mut existing = lexical.as_path();
    let mut rest = Vec::new();
    loop {
        if let Ok(c) = existing.canonicalize() {
            return rest.iter().rev().fold(c, |p, n| p.join(n));
        }
        match (existing.parent(), existing.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_os_string());
                existing = parent;
            }
            _ => return lexical,
        }
    }
}

/// Refuses the result folder `dir` (given with `flag`) when it holds or lies inside one of `inputs`.
pub fn check_apart(dir: &Path, flag: &str, inputs: &Inputs) -> Result<(), OutPathError> {
    let out = resolved(dir);
    for input in inputs.iter() {
        let at = resolved(&input.path);
        let relation = if at.starts_with(&out) {
            "this folder holds"
        } else if out.starts_with(&at) {
            "this folder is inside"
        } else {
            continue;
        };
        return Err(OutPathError::OverlapsInput {
            flag: flag.into(),
            dir: dir.to_path_buf(),
            relation,
            what: input.what.clone(),
            input: input.path.clone(),
        });
    }
    Ok(())
}

/// A result folder of per-run files, claimed before the work ([`OutDir::claim`]), filled at
/// [`OutDir::path`] and put in place by [`OutDir::commit`]. Dropped without a commit, it removes what was
/// written and leaves the target as it was.
#[derive(Debug)]
pub struct OutDir {
    /// Where the folder ends up.
    target: PathBuf,
    /// Where it is filled: a sibling of `target`, or `None` to fill `target` itself (the working
    /// directory, `.`, which cannot be renamed; it was checked empty).
    staging: Option<PathBuf>,
}

impl OutDir {
    /// Claims `target` (given with `flag`, e.g. `--out`): a folder that holds or lies inside one of the
    /// command's `inputs` is refused, whatever `force`; a folder that already holds files is refused
    /// unless `force` (then it is replaced whole at the commit); missing parent folders are created; the
    /// staging folder is made now, so a folder that takes no files fails before the work.
    pub fn claim(target: &Path, flag: &str, force: bool, inputs: &Inputs) -> Result<Self, OutPathError> {
        check_apart(target, flag, inputs)?;
        if target.exists() && !target.is_dir() {
            return Err(OutPathError::IsFile { flag: flag.into(), dir: target.to_path_buf() });
        }
        if target.is_dir() {
            let held = some_entries(target).map_err(|source| OutPathError::Read {
                flag: flag.into(),
                dir: target.to_path_buf(),
                source,
            })?;
            match held {
                Some(entries) if !force => {
                    return Err(OutPathError::NotEmpty { flag: flag.into(), dir: target.to_path_buf(), entries });
                }
                Some(_) => check_replaceable(target, flag)?,
                None => {}
            }
        }
        let name = target.file_name().filter(|_| !is_working_directory(target));
        let Some(name) = name else {
            create_dir_all(target, flag)?;
            check_writable_dir(target, flag)?;
            return Ok(Self { target: target.to_path_buf(), staging: None });
        };
        let parent = folder_of(target);
        create_dir_all(parent, flag)?;
        let staging = parent.join(format!(".{}.omnical-tmp-{}", name.to_string_lossy(), std::process::id()));
        if staging.exists() {
            std::fs::remove_dir_all(&staging)
                .map_err(|source| OutPathError::RemoveStaging { staging: staging.clone(), source })?;
        }
        std::fs::create_dir(&staging).map_err(|source| OutPathError::CannotWriteIn {
            flag: flag.into(),
            path: target.to_path_buf(),
            folder: parent.to_path_buf(),
            source,
        })?;
        Ok(Self { target: target.to_path_buf(), staging: Some(staging) })
    }

    /// Where to write the folder's contents now.
    pub fn path(&self) -> &Path {
        self.staging.as_deref().unwrap_or(&self.target)
    }

    /// Where the folder ends up (for messages and JSON).
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// A path written under [`OutDir::path`], as it will be after the commit.
    pub fn shown(&self, written: &Path) -> PathBuf {
        match &self.staging {
            Some(s) => written.strip_prefix(s).map_or_else(|_| written.to_path_buf(), |rel| self.target.join(rel)),
            None => written.to_path_buf(),
        }
    }

    /// Puts the folder in place: the old one (if any) is moved aside, the new one renamed to the target,
    /// and the old one removed.
    pub fn commit(mut self) -> Result<(), OutPathError> {
        let Some(staging) = self.staging.take() else { return Ok(()) };
        let result = swap_in(&staging, &self.target);
        if result.is_err() {
            let _ = std::fs::remove_dir_all(&staging);
        }
        result
    }
}

impl Drop for OutDir {
    fn drop(&mut self) {
        if let Some(s) = self.staging.take() {
            let _ = std::fs::remove_dir_all(s);
        }
    }
}

/// True when `p` names the working directory (`.`, `./`, or its own path).
fn is_working_directory(p: &Path) -> bool {
    let cwd = std::env::current_dir().and_then(|d| d.canonicalize()).ok();
    p.as_os_str().is_empty() || (p.canonicalize().ok().is_some() && p.canonicalize().ok() == cwd)
}

/// Renames `staging` to `target`, replacing an existing `target` folder (moved aside first, then removed;
/// moved back if the rename fails).
fn swap_in(staging: &Path, target: &Path) -> Result<(), OutPathError> {
    let move_in = |source| OutPathError::MoveIn { target: target.to_path_buf(), source };
    if !target.exists() {
        return std::fs::rename(staging, target).map_err(move_in);
    }
    let name = target.file_name().map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    let old = folder_of(target).join(format!(".{name}.omnical-old-{}", std::process::id()));
    std::fs::rename(target, &old).map_err(|source| OutPathError::MoveAside { target: target.to_path_buf(), source })?;
    if let Err(e) = std::fs::rename(staging, target) {
        let _ = std::fs::rename(&old, target);
        return Err(move_in(e));
    }
    std::fs::remove_dir_all(&old).map_err(|source| OutPathError::RemoveOld {
        target: target.to_path_buf(),
        old,
        source,
    })
}

#[cfg(test)]
mod tests;
