//! `omnical diagnose` as a request ([`DiagnoseRequest`]): loading, the model, the diagnosis and the model
//! file `--out` writes. The command prints around it; [`diagnose_quietly`] runs it without a terminal.

use crate::api::ModelSpec;
use crate::api::load::{DataOptions, load_with_held_out};
use crate::design::designs_for;
use crate::{atomic, model_file};
use anyhow::Context;
use omni_ga::diagnose::{DiagnoseOptions, Diagnosis, diagnose};
use omni_kin::{FittedModel, Run};
use std::path::PathBuf;

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
pub fn diagnose_quietly(a: &DiagnoseRequest) -> anyhow::Result<Diagnosis> {
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
pub fn diagnose_loaded(a: &DiagnoseRequest) -> anyhow::Result<(Diagnosis, Loaded)> {
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
        let text = model_file::to_toml(fm, None).map_err(anyhow::Error::msg)?;
        atomic::write_atomic(out, text.as_bytes()).with_context(|| format!("writing {}", out.display()))?;
    }
    Ok((d, Loaded { train: ds.runs, validate: val, model }))
}
