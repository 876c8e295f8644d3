//! Preparation: each run's [`StepPlan`] (for one clock lag), eight runs interleaved to a lane group (struct of
//! arrays), and the wheel-angle increments `u = f h w` of their steps — kept, redone from the runs' wheel
//! columns, or redone from wheel speeds rewritten by wheel-stage effects, always by [`Group::fill`].

use super::features::WheelFeatures;
use super::twist::StepTimes;
use super::{LANES, Lanes};
use crate::odometry::Selection;
use crate::plan::StepPlan;
use crate::pose::Pose2;
use crate::run::Run;
use std::sync::OnceLock;

/// One ground-truth pose to predict: after `step` steps of `lane`, a partial step (its increments in
/// [`Increments::query_u`]).
#[derive(Clone, Debug)]
pub(super) struct Query {
    pub step: usize,
    pub lane: usize,
    /// Output slot within the group (runs' queries are contiguous, in run order).
    pub slot: usize,
    pub truth: Pose2,
    /// Index of the query in its lane's plan.
    source: usize,
}

impl Query {
    /// Index of the query in its lane's plan.
    pub fn source(&self) -> usize {
        self.source
    }
}

/// [`LANES`] runs interleaved.
#[derive(Clone, Debug)]
pub(super) struct Group {
    /// Index of the group's first run.
    pub first_run: usize,
    /// Real runs in the group (the other lanes are padding with zero increments).
    pub lanes: usize,
    /// Wheels per sample.
    pub n_wheels: usize,
    /// Each real lane's steps and queries.
    plans: Vec<StepPlan>,
    /// Step length of each lane. s.
    h: Lanes,
    /// Steps (the longest run's; shorter runs are padded with zero increments).
    pub steps: usize,
    /// Kept wheel-angle increments (empty when not kept), `steps × n_wheels` lane vectors. rad.
    u: Vec<Lanes>,
    /// Largest |increment| per wheel over the group (bounds the step angle). rad.
    u_max: Vec<f64>,
    /// First ground-truth pose of each lane (where odometry starts).
    pub start: [Pose2; LANES],
    /// Last ground-truth pose of each lane (the Eq. 6 reference).
    pub end: [Pose2; LANES],
    /// Queries sorted by step, then lane (path selections only).
    pub queries: Vec<Query>,
    /// Partial-step increments of the queries, `n_wheels` each. rad.
    query_u: Vec<f64>,
    /// The parts of the evaluator's affine wheel-stage effect as increments (taken at first use).
    parts: OnceLock<GroupParts>,
    /// Step lengths and times for twist-stage effects (taken at first use).
    times: OnceLock<StepTimes>,
}

/// One part's increments before interleaving: (parameter, wheel), steps, queries, largest |increment|.
type PartColumn = ((usize, usize), Vec<Lanes>, Vec<f64>, f64);

/// The parts of an affine wheel-stage effect ([`WheelFeatures`]) as increments of a group: `f h Δw` of
/// every step and query for one unit of a parameter, on one wheel; interleaved by step (one pass reads
/// them all).
#[derive(Clone, Debug, Default)]
pub(super) struct GroupParts {
    /// (parameter index in the effect's, wheel) of each part.
    pub keys: Vec<(usize, usize)>,
    /// Increments of the steps: `steps × keys.len()` lane vectors, step-major. rad.
    pub u: Vec<Lanes>,
    /// Increments of the queries: `queries × keys.len()`, query-major. rad.
    pub query_u: Vec<f64>,
    /// Largest |increment| of each part. rad.
    pub u_max: Vec<f64>,
}

/// The increments a walk of a group reads.
pub(super) struct Increments<'g> {
    /// `u[k n_wheels + j][lane]`: increment of wheel `j` at step `k`. rad.
    pub u: &'g [Lanes],
    /// Partial-step increments of the group's queries, `n_wheels` each. rad.
    pub query_u: &'g [f64],
}

impl Group {
    /// Group of `chunk` (at most [`LANES`] runs, the first being run `first_run`) with fixed steps of
    /// `fixed_dt_s` (`None`: each run's median interval) and a wheel-clock lag of `lag_s`; keeps the
    /// increments when `keep`.
    pub fn new(
        first_run: usize,
        chunk: &[Run],
        fixed_dt_s: Option<f64>,
        selection: Selection,
        lag_s: f64,
        keep: bool,
    ) -> Self {
        let n_wheels = chunk.first().map_or(0, Run::n_wheels);
        let plans: Vec<StepPlan> = chunk
            .iter()
            .map(|r| {
                let idx = match selection {
                    Selection::End => Vec::new(),
                    Selection::Path(_) => selection.indices(r.truth().len()),
                };
                StepPlan::new(r, lag_s, &idx)
            })
            .collect();
        let (mut start, mut end, mut h) = ([Pose2::IDENTITY; LANES], [Pose2::IDENTITY; LANES], [0.0; LANES]);
        let mut queries = Vec::new();
        for (lane, (r, plan)) in chunk.iter().zip(&plans).enumerate() {
            start[lane] = r.start().pose;
            end[lane] = r.end().pose;
            h[lane] = fixed_dt_s.unwrap_or(r.median_dt_s());
            for (source, q) in plan.queries.iter().enumerate() {
                let truth = r.truth()[q.truth_index].pose;
                queries.push(Query { step: q.step, lane, slot: queries.len(), truth, source });
            }
        }
        queries.sort_by_key(|q| (q.step, q.lane));
        let steps = plans.iter().map(|p| p.steps).max().unwrap_or(0);
        let mut g = Group {
            first_run,
            lanes: chunk.len(),
            n_wheels,
            plans,
            h,
            steps,
            u: Vec::new(),
            u_max: Vec::new(),
            start,
            end,
            queries,
            query_u: Vec::new(),
            parts: OnceLock::new(),
            times: OnceLock::new(),
        };
        let wheels: Vec<&[f64]> = chunk.iter().map(Run::wheel_rad_s).collect();
        let mut u = Vec::new();
        g.fill_steps(&wheels, &mut u);
        g.u_max = max_per_wheel(&u, n_wheels);
        g.query_u = g.fill_queries(&wheels);
        if keep {
            g.u = u;
        }
        g
    }

    /// Each real lane's plan.
    pub fn plans(&self) -> &[StepPlan] {
        &self.plans
    }

    /// Step length of each lane. s.
    pub fn h(&self) -> &Lanes {
        &self.h
    }

    /// The step times twist-stage effects read ([`StepTimes`]) of this group, whose runs are `chunk`,
    /// taken at the first call.
    pub fn times(&self, chunk: &[Run]) -> &StepTimes {
        self.times.get_or_init(|| StepTimes::new(self, chunk))
    }

    /// The kept increments; `None` when they were not kept.
    pub fn kept(&self) -> Option<Increments<'_>> {
        (self.u.len() == self.steps * self.n_wheels).then_some(Increments { u: &self.u, query_u: &self.query_u })
    }

    /// Largest |increment| per wheel of the runs' own wheel speeds. rad.
    pub fn u_max(&self) -> &[f64] {
        &self.u_max
    }

    /// Increments `u` redone from the lanes' wheel speeds (the same numbers as kept ones).
    pub fn redone<'g>(&'g self, u: &'g [Lanes]) -> Increments<'g> {
        Increments { u, query_u: &self.query_u }
    }

    /// The runs of the group among `runs` (`None` when `runs` are not the prepared runs).
    pub fn runs<'r>(&self, runs: &'r [Run]) -> Option<&'r [Run]> {
        let chunk = runs.get(self.first_run..self.first_run + self.lanes)?;
        let same = chunk.iter().zip(&self.plans).all(|(r, p)| r.n_samples() >= p.first_sample + p.steps);
        same.then_some(chunk)
    }

    /// Writes the increments of the group's steps into `u` (`u[k n + j][lane] = f h w`, from each lane's
    /// wheel speeds `wheels[lane]` and its plan's fractions, zero past a lane's last step). With
    /// [`Self::fill_queries`], the one place increments are taken.
    pub fn fill_steps(&self, wheels: &[&[f64]], u: &mut Vec<Lanes>) {
        self.fill_steps_of(wheels, self.n_wheels, u);
    }

    /// [`Self::fill_steps`] of `n` columns per sample.
    fn fill_steps_of(&self, wheels: &[&[f64]], n: usize, u: &mut Vec<Lanes>) {
        // Each lane's wheel speeds over its steps (none for padding lanes).
        let mut w: [&[f64]; LANES] = [&[]; LANES];
        for (lane, (plan, speeds)) in self.plans.iter().zip(wheels).enumerate() {
            w[lane] = &speeds[plan.first_sample * n..(plan.first_sample + plan.steps) * n];
        }
        let h = self.h;
        u.clear();
        u.reserve(self.steps * n);
        // Whole steps: f = 1, and (1 · h) · w = h · w exactly; every lane at once while all have steps.
        let common = w.iter().map(|s| s.len()).min().unwrap_or(0);
        u.extend((0..common).map(|i| -> Lanes { std::array::from_fn(|l| h[l] * w[l][i]) }));
        for i in common..self.steps * n {
            u.push(std::array::from_fn(|l| w[l].get(i).map_or(0.0, |v| h[l] * v)));
        }
        // Partial steps: their fraction of the step.
        for (lane, plan) in self.plans.iter().enumerate() {
            for &(k, f) in &plan.partial {
                for j in 0..n {
                    u[k * n + j][lane] = f * h[lane] * w[lane][k * n + j];
                }
            }
        }
    }

    /// The queries' partial-step increments `f h w` from each lane's wheel speeds `wheels[lane]` (zero
    /// where the robot is at rest), `n_wheels` per query. rad.
    pub fn fill_queries(&self, wheels: &[&[f64]]) -> Vec<f64> {
        self.fill_queries_of(wheels, self.n_wheels)
    }

    /// The parts of `features` (the affine wheel-stage effect of every evaluation of these runs) as
    /// increments of this group, taken at the first call.
    pub fn parts(&self, features: &WheelFeatures) -> &GroupParts {
        self.parts.get_or_init(|| self.make_parts(features))
    }

    /// The parts of `features` as increments of this group (see [`Self::parts`]).
    pub fn make_parts(&self, features: &WheelFeatures) -> GroupParts {
        let columns: Vec<PartColumn> = {
            let lanes: Vec<Vec<(usize, usize, &[f64])>> =
                (0..self.lanes).map(|l| features.run_parts(self.first_run + l).collect()).collect();
            let mut keys: Vec<(usize, usize)> = lanes.iter().flatten().map(|&(p, w, _)| (p, w)).collect();
            keys.sort_unstable();
            keys.dedup();
            let zeros: Vec<Vec<f64>> = self.plans.iter().map(|p| vec![0.0; p.first_sample + p.steps + 1]).collect();
            keys.into_iter()
                .map(|(param, wheel)| {
                    let cols: Vec<&[f64]> = (0..self.lanes)
                        .map(|l| {
                            let own = lanes[l].iter().find(|&&(p, w, _)| (p, w) == (param, wheel));
                            own.map_or(zeros[l].as_slice(), |&(_, _, c)| c)
                        })
                        .collect();
                    let mut u = Vec::new();
                    self.fill_steps_of(&cols, 1, &mut u);
                    let u_max = max_per_wheel(&u, 1)[0];
                    ((param, wheel), u, self.fill_queries_of(&cols, 1), u_max)
                })
                .collect()
        };
        let mut parts = GroupParts::default();
        for k in 0..self.steps {
            parts.u.extend(columns.iter().map(|c| c.1[k]));
        }
        for q in 0..self.queries.len() {
            parts.query_u.extend(columns.iter().map(|c| c.2[q]));
        }
        parts.keys = columns.iter().map(|c| c.0).collect();
        parts.u_max = columns.iter().map(|c| c.3).collect();
        parts
    }

    /// [`Self::fill_queries`] of `n` columns per sample.
    fn fill_queries_of(&self, wheels: &[&[f64]], n: usize) -> Vec<f64> {
        let mut query_u = Vec::with_capacity(self.queries.len() * n);
        for q in &self.queries {
            let (plan, h) = (&self.plans[q.lane], self.h[q.lane]);
            let at = &plan.queries[q.source];
            let k = plan.first_sample + at.step;
            match at.fraction {
                Some(f) => query_u.extend(wheels[q.lane][k * n..(k + 1) * n].iter().map(|w| f * h * w)),
                None => query_u.extend(std::iter::repeat_n(0.0, n)),
            }
        }
        query_u
    }
}

/// Largest |increment| of each wheel over lane vectors `u` (`n` per step). rad.
pub(super) fn max_per_wheel(u: &[Lanes], n: usize) -> Vec<f64> {
    let mut u_max = vec![0.0f64; n];
    for step in u.chunks_exact(n.max(1)) {
        for (m, v) in u_max.iter_mut().zip(step) {
            *m = v.iter().fold(*m, |a, x| a.max(x.abs()));
        }
    }
    u_max
}
