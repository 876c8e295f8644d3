//! Subcommand implementations: load, call the library, format.

pub mod demo;
pub mod diagnose;
pub mod eval;
pub mod simulate;
pub mod train;

use crate::cli::DataArgs;
use crate::dataset::{self, Dataset, LoadOptions};
use anyhow::Context;
use omni_kin::{FittedModel, IkMatrix, Model};
use std::path::{Path, PathBuf};

/// Load runs from files/folders, printing what was skipped or noticed on stderr.
pub fn load_runs(paths: &[PathBuf], data: &DataArgs) -> anyhow::Result<Dataset> {
    let opts = LoadOptions { skip_invalid: data.skip_invalid, ticks_per_rev: data.ticks_per_rev };
    let ds = dataset::load(paths, &opts)?;
    for n in &ds.notes {
        eprintln!("note: {n}");
    }
    for s in &ds.skipped {
        eprintln!("skipped {}: {}", s.source, s.reason);
    }
    Ok(ds)
}

/// The design IK matrix of a dataset: the geometry it declares, else the paper's Eq. 7.
pub fn design_ik(ds: &Dataset) -> anyhow::Result<IkMatrix> {
    match &ds.robot {
        Some(g) => Ok(g.twist_from_wheels()?),
        None => Ok(IkMatrix::paper_design()),
    }
}

/// `design` / `paper` or a model file.
pub fn resolve_model(spec: &str, ds: &Dataset) -> anyhow::Result<FittedModel> {
    match spec {
        "design" => Ok(match &ds.robot {
            Some(g) => FittedModel::nominal(Model::geometry(g.clone())),
            None => FittedModel::paper_design(),
        }),
        "paper" => Ok(FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()))),
        path => crate::model_file::read(Path::new(path)).context("reading the model"),
    }
}
