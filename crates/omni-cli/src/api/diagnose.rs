//! `omnical diagnose` as a request ([`DiagnoseRequest`]): loading, the model, the diagnosis and the model
//! file `--out` writes. The command prints around it; [`diagnose_quietly`] runs it without a terminal.

use crate::api::held_out::SameRecording;
use crate::api::load::{DataOptions, LoadError, load_with_held_out};
use crate::api::{ModelSpec, ResolveError};
use crate::design::designs_for;
use crate::model_file::ModelTextError;
use crate::out_path::OutPathError;
use crate::{atomic, model_file};
use omni_ga::diagnose::{DiagnoseOptions, Diagnosis, diagnose};
use omni_kin::{FittedModel, Run};
use std::path::PathBuf;

/// Why `omnical diagnose` (its loading, the diagnosis or the model file) failed.
#[derive(Debug, thiserror::Error)]
pub enum DiagnoseError {
    /// `--out` cannot take the model file.
    #[error(transparent)]
    Out(#[from] OutPathError),
    /// The runs could not be read.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// `--model` stands for no model.
    #[error(transparent)]
    Model(#[from] ResolveError),
    /// A held-out run is a training run.
    #[error(transparent)]
    SameRecording(#[from] SameRecording),
    /// The diagnosis failed.
    #[error(transparent)]
    Diagnose(#[from] omni_ga::Error),
    /// The final model does not make model file text.
    #[error(transparent)]
    ModelText(#[from] ModelTextError),
    /// The model file could not be written.
    #[error("writing {}", path.display())]
    Write {
        /// The model file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
}

/// What `omnical diagnose` does: the model, the training and held-out runs and how to read them, the
/// diagnosis options, where the final model goes.
#[derive(Clone, Debug)]
pub struct DiagnoseRequest {
    /// The model to diagnose.
    pub model: ModelSpec,
    /// Training run files or folders.
    pub runs: Vec<PathBuf>,
    /// Held-out run files or folders (none: cross-validation over repetitions).
    pub validate: Vec<PathBuf>,
    /// How to read the runs.
    pub data: DataOptions,
    /// `auto`, `min_gain` and `candidates` (empty: all of them).
    pub options: DiagnoseOptions,
    /// Where to write the final model (with effects added by `auto`).
    pub out: Option<PathBuf>,
}

/// `omnical diagnose` without printing (the Python wheel's fleet workers): loads, diagnoses and writes
/// `--out` as the command does, and returns the diagnosis.
pub fn diagnose_quietly(a: &DiagnoseRequest) -> Result<Diagnosis, DiagnoseError> {
    Ok(diagnose_loaded(a)?.0)
}

/// What [`diagnose_loaded`] loaded: the training runs, the held-out runs (if given) and the model.
pub struct Loaded {
    /// The training runs.
    pub train: Vec<Run>,
    /// The held-out runs, when given.
    pub validate: Option<Vec<Run>>,
    /// The model diagnosed.
    pub model: FittedModel,
}

/// Loads, diagnoses and writes `--out`; returns the diagnosis and what it was computed on.
pub fn diagnose_loaded(a: &DiagnoseRequest) -> Result<(Diagnosis, Loaded), DiagnoseError> {
    if let Some(out) = &a.out {
        crate::out_path::check_file(out, "--out")?;
    }
    let (ds, val_ds) = load_with_held_out(&a.runs, &a.validate, &a.data)?;
    let model = a.model.resolve(&ds)?;
    // Each run is compared with its own input's design.
    let design = designs_for(&model, &[Some(&ds), val_ds.as_ref()].into_iter().flatten().collect::<Vec<_>>());
    let val = val_ds.map(|v| v.runs);
    super::held_out::check("diagnose", &a.runs, &ds.runs, val.as_deref().unwrap_or_default())?;
    let d = diagnose(&model, &design, &ds.runs, val.as_deref(), &a.options)?;
    if let (Some(out), Some(fm)) = (&a.out, &d.final_model) {
        // The final model carries its own noise model, fitted as `train` fits one: what the effects added
        // explain is no longer noise (`eval` checks it on held-out runs, `export` writes it).
        let mut file = model_file::ModelFile::from_fitted(fm, None).map_err(ModelTextError::from)?;
        file.noise = super::noise::fit(fm, &ds.runs).map_err(ModelTextError::from)?.ok();
        let text = file.to_toml()?;
        atomic::write_atomic(out, text.as_bytes())
            .map_err(|source| DiagnoseError::Write { path: out.clone(), source })?;
    }
    Ok((d, Loaded { train: ds.runs, validate: val, model }))
}
