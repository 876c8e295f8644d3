//! One model per run: what a robot's runs are evaluated with when its sets declare different designs
//! (OptiOdom set folders whose metadata give other wheel distances, say). Each run is integrated with its
//! own model, and pooled figures are what [`RunErrors`] makes of the runs' own errors: Eq. 6 the mean of
//! the runs' end-pose errors, the path cost `sqrt` of the mean of the runs' path MSEs (each run counting
//! equally), exactly as for one model.
//!
//! Plain data: the caller (omni-cli's design layer) decides which run gets which model; runs are matched by
//! name, so any subset of the runs (a cross-validation fold, the held-out runs) finds its models.

use crate::cost::CostKind;
use crate::error::KinError;
use crate::evaluate::{Evaluator, RunErrors};
use crate::model::FittedModel;
use crate::odometry::Selection;
use crate::run::Run;
use std::collections::BTreeMap;

/// A model for each run, stored once per distinct model.
#[derive(Clone, Debug)]
pub struct RunModels {
    /// The distinct models; the first stands for them all where one model is needed (training's start).
    models: Vec<FittedModel>,
    /// Run name → index in `models`. Empty when there is one model: it serves every run.
    of_run: BTreeMap<String, usize>,
}

impl From<FittedModel> for RunModels {
    /// One model for every run.
    fn from(model: FittedModel) -> Self {
        Self { models: vec![model], of_run: BTreeMap::new() }
    }
}

impl From<&FittedModel> for RunModels {
    /// One model for every run.
    fn from(model: &FittedModel) -> Self {
        Self::from(model.clone())
    }
}

/// Where runs are compared with their designs, either one model for every run (a [`FittedModel`]) or a
/// model per run (a [`RunModels`]): `diagnose(&model, &design, …)` takes both.
pub trait ToRunModels {
    /// The models by run.
    fn to_run_models(&self) -> RunModels;
}

impl ToRunModels for FittedModel {
    fn to_run_models(&self) -> RunModels {
        RunModels::from(self)
    }
}

impl ToRunModels for RunModels {
    fn to_run_models(&self) -> RunModels {
        self.clone()
    }
}

impl RunModels {
    /// Models by run: `groups` pairs each model with the names of its runs. The first group's model stands
    /// for them all ([`Self::first`]). One group is one model for every run, whatever its names. A run
    /// named in two groups is an error (twice in one group is the same run).
    pub fn new(mut groups: Vec<(FittedModel, Vec<String>)>) -> Result<Self, KinError> {
        if groups.is_empty() {
            return Err(KinError::Invalid { what: "models by run".into(), why: "no model given".into() });
        }
        if groups.len() == 1 {
            let (model, _) = groups.swap_remove(0);
            return Ok(Self::from(model));
        }
        let mut of_run = BTreeMap::new();
        let mut models = Vec::with_capacity(groups.len());
        for (i, (model, names)) in groups.into_iter().enumerate() {
            for name in names {
                if of_run.insert(name.clone(), i).is_some_and(|j| j != i) {
                    return Err(KinError::Invalid {
                        what: format!("run {name}"),
                        why: "two inputs hold a run of this name and declare different designs; rename one".into(),
                    });
                }
            }
            models.push(model);
        }
        Ok(Self { models, of_run })
    }

    /// The distinct models, the first standing for them all.
    pub fn models(&self) -> &[FittedModel] {
        &self.models
    }

    /// The model that stands for them all where one is needed: the first given.
    pub fn first(&self) -> &FittedModel {
        &self.models[0]
    }

    /// The model, when every run has the same one.
    pub fn single(&self) -> Option<&FittedModel> {
        (self.models.len() == 1).then(|| &self.models[0])
    }

    /// The model of `run`; a run this map does not know (with several models) is an error naming it.
    pub fn for_run(&self, run: &Run) -> Result<&FittedModel, KinError> {
        Ok(&self.models[self.index_of(run)?])
    }

    fn index_of(&self, run: &Run) -> Result<usize, KinError> {
        if self.models.len() == 1 {
            return Ok(0);
        }
        self.of_run.get(run.name()).copied().ok_or_else(|| KinError::Invalid {
            what: format!("run {}", run.name()),
            why: "no design for this run (it was not loaded with the runs whose designs are known)".into(),
        })
    }

    /// Each model with `f` applied (same runs).
    pub fn map(&self, f: impl Fn(&FittedModel) -> FittedModel) -> Self {
        Self { models: self.models.iter().map(f).collect(), of_run: self.of_run.clone() }
    }

    /// The cost `kind` over `runs`, each under its own model ([`crate::cost::cost`] for one model): Eq. 6 the
    /// mean of the runs' end-pose errors, a path cost the root of the mean of their path MSEs.
    pub fn cost(&self, runs: &[Run], kind: CostKind) -> Result<f64, KinError> {
        let errors = self.errors(runs, kind.selection())?;
        Ok(match kind {
            CostKind::EndPose => errors.end_pose_cost(),
            CostKind::Path { heading_weight_m_per_rad: w, .. } => errors.path_cost(w),
        })
    }

    /// Errors of every run under its own model at the poses of `selection`, in run order, through
    /// [`Evaluator::for_report`] (one evaluator per model, over that model's runs).
    pub fn errors(&self, runs: &[Run], selection: Selection) -> Result<RunErrors, KinError> {
        if let Some(m) = self.single() {
            return Ok(Evaluator::for_report(&m.model, runs, selection)?.errors(&m.model.resolve(&m.params)?));
        }
        let mut groups: Vec<Vec<usize>> = vec![Vec::new(); self.models.len()];
        for (i, r) in runs.iter().enumerate() {
            groups[self.index_of(r)?].push(i);
        }
        let mut parts = Vec::new();
        for (m, idx) in self.models.iter().zip(groups).filter(|(_, idx)| !idx.is_empty()) {
            let subset: Vec<Run> = idx.iter().map(|&i| runs[i].clone()).collect();
            let errors = Evaluator::for_report(&m.model, &subset, selection)?.errors(&m.model.resolve(&m.params)?);
            parts.push((idx, errors));
        }
        Ok(RunErrors::interleave(runs.len(), &parts))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::ik::IkMatrix;
    use crate::model::Model;
    use crate::simulate::{SimConfig, flower_commands, simulate};

    /// Simulated runs of the paper's robot (Eq. 9), named `{prefix}/…`.
    fn runs(seed: u64, prefix: &str) -> Vec<Run> {
        let config = SimConfig {
            commands: flower_commands().into_iter().step_by(4).collect(),
            runs_per_command: 1,
            duration_s: 2.0,
            seed,
            ..SimConfig::default()
        };
        let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
        simulate(&config, &truth, &format!("{prefix}/")).unwrap()
    }

    /// Two models on two halves: every run's errors are its own model's, and the pooled costs are the
    /// run-weighted means of the halves' (Eq. 6 the mean, the path cost the root of the mean MSE).
    #[test]
    fn each_run_is_evaluated_with_its_own_model() {
        let (a, b) = (runs(1, "a"), runs(2, "b")[..3].to_vec());
        let design = FittedModel::paper_design();
        let paper = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
        let names = |r: &[Run]| r.iter().map(|r| r.name().to_string()).collect::<Vec<_>>();
        let both = RunModels::new(vec![(design.clone(), names(&a)), (paper.clone(), names(&b))]).unwrap();
        let mut all = a.clone();
        all.extend(b.clone());
        let sel = CostKind::PATH.selection();
        let pooled = both.errors(&all, sel).unwrap();
        let ea = RunModels::from(&design).errors(&a, sel).unwrap();
        let eb = RunModels::from(&paper).errors(&b, sel).unwrap();
        for i in 0..a.len() {
            assert_eq!(pooled.run(i), ea.run(i));
        }
        for i in 0..b.len() {
            assert_eq!(pooled.run(a.len() + i), eb.run(i));
        }
        let (na, nb) = (a.len() as f64, b.len() as f64);
        let eq6 = (na * ea.end_pose_cost() + nb * eb.end_pose_cost()) / (na + nb);
        assert!((pooled.end_pose_cost() - eq6).abs() < 1e-12, "{} vs {eq6}", pooled.end_pose_cost());
        let mse = |c: f64| c * c;
        let path = ((na * mse(ea.path_cost(1.0)) + nb * mse(eb.path_cost(1.0))) / (na + nb)).sqrt();
        assert!((pooled.path_cost(1.0) - path).abs() < 1e-12, "{} vs {path}", pooled.path_cost(1.0));
        assert!(ea.end_pose_cost() > 2.0 * eb.end_pose_cost(), "the halves differ, so the test can fail");
    }

    #[test]
    fn unknown_and_twice_named_runs_are_refused() {
        let a = runs(1, "a");
        let d = FittedModel::paper_design();
        let two = RunModels::new(vec![(d.clone(), vec!["a/x".into()]), (d.clone(), vec!["a/y".into()])]).unwrap();
        let e = two.errors(&a, Selection::End).unwrap_err().to_string();
        assert!(e.starts_with(&format!("run {}: no design for this run", a[0].name())), "{e}");
        let e = RunModels::new(vec![(d.clone(), vec!["x".into()]), (d, vec!["x".into()])]).unwrap_err().to_string();
        assert_eq!(e, "run x: two inputs hold a run of this name and declare different designs; rename one");
    }
}
