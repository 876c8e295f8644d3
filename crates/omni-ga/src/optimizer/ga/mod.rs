//! A bounded genetic algorithm over `f64` vectors, shaped after MATLAB's `ga` (which the paper used).
//!
//! Each generation: the population's costs are evaluated in parallel ([`Problem::costs`]); the `elite`
//! best survive unchanged; parents are chosen by stochastic-uniform sampling of rank-scaled fitness
//! (∝ 1/√rank, as MATLAB `fitscalingrank`); a `crossover_fraction` of the remaining children come from
//! scattered crossover (a random mask picks each gene from one of two parents, MATLAB
//! `crossoverscattered`), the rest from Gaussian mutation.
//!
//! Differences from MATLAB, by necessity or on purpose:
//! - Mutation: MATLAB's bounded default `mutationadaptfeasible` searches feasible directions; here the
//!   mutation is Gaussian with a per-gene scale of `mutation_scale × box width`, reflected into the box;
//!   the scale grows ×1.2 after a generation that improved the best and shrinks ×0.8 otherwise (within
//!   [1e-6, 0.5]). Every child is inside the bounds.
//! - Creation: individual 0 is the start point (the paper seeds the design matrix); the others are uniform
//!   in the box shrunk around the start by `initial_spread` (1 = the whole box, MATLAB
//!   `gacreationuniform`).
//!
//! Stopping: generation, evaluation or time caps, the observer, or the stall rule over the last
//! `stall_generations` generations: the weighted mean (weights 0.5^age) of the change of the best cost,
//! divided by `max(1, |best|)` ([`StallRule::Matlab`]: at costs ≈ 0.02 this is in effect an absolute test,
//! which stops early — reproduced on purpose in the `paper` preset) or by `|best|`
//! ([`StallRule::Relative`], scale-aware), at most `function_tolerance`.
//!
//! Determinism: one `ChaCha8Rng::seed_from_u64(seed)` on the calling thread, drawn in a fixed order; the
//! only parallel step collects costs in order. Same seed ⇒ bit-identical result whatever the thread count.

use crate::optimizer::bounds::Bounds;
use crate::optimizer::error::OptimizeError;
use crate::optimizer::observe::{Control, Iteration, Observer};
use crate::optimizer::problem::Problem;
use crate::optimizer::{Optimizer, Solution, Termination, check_start};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// How the stall test scales the change of the best cost.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StallRule {
    /// `|Δbest| / max(1, |best|)` (MATLAB).
    Matlab,
    /// `|Δbest| / |best|` (scale-aware).
    Relative,
}

/// GA settings. Field docs: meaning, unit, MATLAB default.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GaConfig {
    /// Individuals per generation. MATLAB: 50 for ≤ 5 variables, else 200.
    pub population: usize,
    /// Best individuals copied unchanged. MATLAB: ceil(0.05 × population).
    pub elite: usize,
    /// Share of non-elite children made by crossover. MATLAB: 0.8.
    pub crossover_fraction: f64,
    /// Window of the stall rule. generations. MATLAB: 50.
    pub stall_generations: usize,
    /// Tolerance of the stall rule. MATLAB: 1e-6.
    pub function_tolerance: f64,
    /// Scaling of the stall rule. MATLAB: `Matlab`.
    pub stall_rule: StallRule,
    /// Generation cap. MATLAB: 100 × variables.
    pub max_generations: usize,
    /// Evaluation cap (None: none).
    pub max_evaluations: Option<usize>,
    /// Time cap. s. (None: none.)
    pub max_seconds: Option<f64>,
    /// Seed.
    pub seed: u64,
    /// Fraction of the box (around the start) the first population fills. 1 = whole box.
    pub initial_spread: f64,
    /// Initial mutation scale as a fraction of each box width. Default 0.1.
    pub mutation_scale: f64,
}

impl GaConfig {
    /// MATLAB `ga` defaults for `nvars` variables.
    pub fn matlab_defaults(nvars: usize) -> Self {
        let population = if nvars <= 5 { 50 } else { 200 };
        Self {
            population,
            elite: population.div_ceil(20),
            crossover_fraction: 0.8,
            stall_generations: 50,
            function_tolerance: 1e-6,
            stall_rule: StallRule::Matlab,
            max_generations: 100 * nvars.max(1),
            max_evaluations: None,
            max_seconds: None,
            seed: 0,
            initial_spread: 1.0,
            mutation_scale: 0.1,
        }
    }

    fn validate(&self) -> Result<(), OptimizeError> {
        let bad = |what, why: &str| Err(OptimizeError::BadConfig { what, why: why.into() });
        if self.population < 2 {
            return bad("population", "must be at least 2");
        }
        if self.elite >= self.population {
            return bad("elite", "must be smaller than the population");
        }
        if !(0.0..=1.0).contains(&self.crossover_fraction) {
            return bad("crossover_fraction", "must be within [0, 1]");
        }
        if !(self.initial_spread > 0.0 && self.initial_spread <= 1.0) {
            return bad("initial_spread", "must be within (0, 1]");
        }
        if self.mutation_scale.is_nan() || self.mutation_scale <= 0.0 || self.stall_generations == 0 {
            return bad("mutation_scale / stall_generations", "must be > 0");
        }
        Ok(())
    }
}

/// The genetic algorithm.
#[derive(Clone, Debug)]
pub struct Ga {
    /// Settings.
    pub config: GaConfig,
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// Reflect `v` into `[lo, hi]`.
fn reflect(mut v: f64, lo: f64, hi: f64) -> f64 {
    if lo == hi {
        return lo;
    }
    for _ in 0..4 {
        if v < lo {
            v = 2.0 * lo - v;
        } else if v > hi {
            v = 2.0 * hi - v;
        } else {
            return v;
        }
    }
    v.clamp(lo, hi)
}

/// The stall measure over the last `window` generations of `best` (None until enough history).
pub fn stall_measure(best: &[f64], window: usize, rule: StallRule) -> Option<f64> {
    if best.len() <= window {
        return None;
    }
    let g = best.len() - 1;
    let (mut sum, mut wsum) = (0.0, 0.0);
    for age in 0..window {
        let (now, before) = (best[g - age], best[g - age - 1]);
        let denom = match rule {
            StallRule::Matlab => now.abs().max(1.0),
            StallRule::Relative => now.abs().max(1e-300),
        };
        let w = 0.5f64.powi(age as i32);
        sum += w * (before - now).abs() / denom;
        wsum += w;
    }
    Some(sum / wsum)
}

impl GaConfig {
    /// Why the run stops after a generation, by the caps and the stall rule (the observer is asked
    /// first); `None` to go on. `next_evaluations` is the count after one more generation.
    fn stop_rule(
        &self,
        history: &[f64],
        generation: usize,
        next_evaluations: usize,
        t0: Instant,
    ) -> Option<Termination> {
        if stall_measure(history, self.stall_generations, self.stall_rule).is_some_and(|m| m <= self.function_tolerance)
        {
            return Some(Termination::Converged);
        }
        if generation >= self.max_generations {
            return Some(Termination::MaxIterations);
        }
        if self.max_evaluations.is_some_and(|m| next_evaluations > m) {
            return Some(Termination::MaxEvaluations);
        }
        if self.max_seconds.is_some_and(|s| t0.elapsed().as_secs_f64() >= s) {
            return Some(Termination::MaxTime);
        }
        None
    }
}

/// A cost as a sort key: NaN ranks last.
fn key(c: f64) -> f64 {
    if c.is_nan() { f64::INFINITY } else { c }
}

/// Mean of the finite costs (`inf` when none is finite).
fn mean_finite(costs: &[f64]) -> f64 {
    let finite: Vec<f64> = costs.iter().copied().filter(|c| c.is_finite()).collect();
    if finite.is_empty() { f64::INFINITY } else { finite.iter().sum::<f64>() / finite.len() as f64 }
}

/// Individual 0 is `x0`; the others are uniform in the box shrunk around `x0` by `initial_spread`.
fn initial_population(cfg: &GaConfig, b: &Bounds, x0: &[f64], width: &[f64], rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    let mut pop: Vec<Vec<f64>> = Vec::with_capacity(cfg.population);
    pop.push(x0.to_vec());
    while pop.len() < cfg.population {
        let ind = (0..x0.len())
            .map(|i| {
                if b.is_fixed(i) {
                    return b.lower[i];
                }
                let half = 0.5 * width[i] * cfg.initial_spread;
                let lo = (x0[i] - half).max(b.lower[i]);
                let hi = (x0[i] + half).min(b.upper[i]);
                if hi > lo { rng.random_range(lo..hi) } else { lo }
            })
            .collect();
        pop.push(ind);
    }
    pop
}

/// `count` parents (indices into the population) by stochastic-uniform sampling of rank-scaled fitness
/// (∝ 1/√rank) over `order` (best first), then shuffled.
fn select_parents(order: &[usize], count: usize, rng: &mut ChaCha8Rng) -> Vec<usize> {
    let n = order.len();
    let weights: Vec<f64> = (0..n).map(|r| 1.0 / ((r + 1) as f64).sqrt()).collect();
    let total: f64 = weights.iter().sum();
    let step = total / count.max(1) as f64;
    let mut pointer = rng.random_range(0.0..step);
    let mut parents = Vec::with_capacity(count);
    let (mut acc, mut r) = (weights[0], 0);
    for _ in 0..count {
        while pointer > acc && r + 1 < n {
            r += 1;
            acc += weights[r];
        }
        parents.push(order[r]);
        pointer += step;
    }
    for i in (1..parents.len()).rev() {
        let j = rng.random_range(0..=i);
        parents.swap(i, j);
    }
    parents
}

/// One generation's breeding state: the current population ranked, the box and the mutation size.
struct Breeding<'a> {
    cfg: &'a GaConfig,
    b: &'a Bounds,
    width: &'a [f64],
    pop: &'a [Vec<f64>],
    costs: &'a [f64],
    /// Population indices, best first.
    order: &'a [usize],
    /// Mutation scale, as a fraction of each width.
    sigma: f64,
}

impl Breeding<'_> {
    /// The next population: the elite (with their known costs), then crossover children, then mutants
    /// (costs `None`: still to evaluate).
    fn next(&self, rng: &mut ChaCha8Rng) -> (Vec<Vec<f64>>, Vec<Option<f64>>) {
        let (cfg, order, dim) = (self.cfg, self.order, self.b.len());
        let children = self.pop.len() - cfg.elite;
        let n_cross = ((cfg.crossover_fraction * children as f64).round() as usize).min(children);
        let n_mut = children - n_cross;
        let mut p = select_parents(order, 2 * n_cross + n_mut, rng).into_iter();
        let mut next: Vec<Vec<f64>> = order[..cfg.elite].iter().map(|&i| self.pop[i].clone()).collect();
        let mut next_costs: Vec<Option<f64>> = order[..cfg.elite].iter().map(|&i| Some(self.costs[i])).collect();
        for _ in 0..n_cross {
            let (a, c) = (p.next().unwrap_or(order[0]), p.next().unwrap_or(order[0]));
            let (pa, pc) = (&self.pop[a], &self.pop[c]);
            next.push((0..dim).map(|i| if rng.random_range(0.0..1.0) < 0.5 { pa[i] } else { pc[i] }).collect());
            next_costs.push(None);
        }
        for _ in 0..n_mut {
            let a = p.next().unwrap_or(order[0]);
            next.push(self.mutant(&self.pop[a], rng));
            next_costs.push(None);
        }
        (next, next_costs)
    }

    /// Gaussian mutation of `parent`, reflected into the box; fixed genes stay.
    fn mutant(&self, parent: &[f64], rng: &mut ChaCha8Rng) -> Vec<f64> {
        let b = self.b;
        (0..b.len())
            .map(|i| {
                if b.is_fixed(i) {
                    return b.lower[i];
                }
                reflect(parent[i] + self.sigma * self.width[i] * gauss(rng), b.lower[i], b.upper[i])
            })
            .collect()
    }
}

/// The costs of a new population: known ones kept, the others evaluated in one parallel batch.
fn fill_costs<P: Problem + ?Sized>(problem: &P, pop: &[Vec<f64>], known: Vec<Option<f64>>) -> (Vec<f64>, usize) {
    let fresh: Vec<Vec<f64>> = pop.iter().zip(&known).filter(|(_, c)| c.is_none()).map(|(x, _)| x.clone()).collect();
    let mut fc = problem.costs(&fresh).into_iter();
    let costs = known.into_iter().map(|c| c.unwrap_or_else(|| fc.next().unwrap_or(f64::INFINITY))).collect();
    (costs, fresh.len())
}

impl<P: Problem + ?Sized> Optimizer<P> for Ga {
    fn name(&self) -> &'static str {
        "ga"
    }

    fn minimize(&mut self, problem: &P, start: &[f64], observer: &mut dyn Observer) -> Result<Solution, OptimizeError> {
        let cfg = &self.config;
        cfg.validate()?;
        let b = problem.bounds();
        let dim = b.len();
        check_start(start, dim)?;
        let t0 = Instant::now();
        let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
        observer.on_start("ga", dim, Some(cfg.max_generations));
        let x0 = b.clamp(start);
        // Scales: box widths (or a size from the start value where the box is unbounded).
        let width: Vec<f64> =
            (0..dim).map(|i| if b.width(i).is_finite() { b.width(i) } else { 0.2 * x0[i].abs().max(1.0) }).collect();
        let mut pop = initial_population(cfg, b, &x0, &width, &mut rng);
        let mut costs = problem.costs(&pop);
        let mut evaluations = pop.len();
        let (mut best_x, mut best_c) = (x0, f64::INFINITY);
        let mut history: Vec<f64> = Vec::new();
        let mut sigma = cfg.mutation_scale;
        let mut generation = 0;
        let termination = loop {
            generation += 1;
            let mut order: Vec<usize> = (0..pop.len()).collect();
            order.sort_by(|&a, &b| key(costs[a]).total_cmp(&key(costs[b])));
            let improved = key(costs[order[0]]) < best_c;
            if improved {
                best_c = key(costs[order[0]]);
                best_x = pop[order[0]].clone();
            }
            history.push(best_c);
            let it = Iteration {
                optimizer: "ga",
                iteration: generation,
                best_cost: best_c,
                mean_cost: mean_finite(&costs),
                evaluations,
                elapsed_s: t0.elapsed().as_secs_f64(),
                best_params: best_x.clone(),
            };
            if observer.on_iteration(&it) == Control::Stop {
                break Termination::Stopped;
            }
            if let Some(t) = cfg.stop_rule(&history, generation, evaluations + pop.len(), t0) {
                break t;
            }
            sigma = if improved { (sigma * 1.2).min(0.5) } else { (sigma * 0.8).max(1e-6) };
            let breeding = Breeding { cfg, b, width: &width, pop: &pop, costs: &costs, order: &order, sigma };
            let (next, known) = breeding.next(&mut rng);
            let (next_costs, fresh) = fill_costs(problem, &next, known);
            evaluations += fresh;
            (pop, costs) = (next, next_costs);
        };
        let solution = Solution {
            params: best_x,
            cost: best_c,
            iterations: generation,
            evaluations,
            termination,
            seconds: t0.elapsed().as_secs_f64(),
        };
        observer.on_finish(&solution);
        Ok(solution)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimizer::observe::{FnObserver, NoopObserver};
    use crate::optimizer::problem::Bounds;
    use std::sync::Mutex;

    struct Sphere {
        b: Bounds,
        centre: Vec<f64>,
        seen: Mutex<Vec<Vec<f64>>>,
    }
    impl Problem for Sphere {
        fn bounds(&self) -> &Bounds {
            &self.b
        }
        fn cost(&self, x: &[f64]) -> f64 {
            self.seen.lock().unwrap().push(x.to_vec());
            x.iter().zip(&self.centre).map(|(a, c)| (a - c) * (a - c)).sum()
        }
    }

    fn sphere(centre: Vec<f64>, lo: f64, hi: f64) -> Sphere {
        let n = centre.len();
        Sphere { b: Bounds::new(vec![lo; n], vec![hi; n]).unwrap(), centre, seen: Mutex::new(Vec::new()) }
    }

    #[test]
    fn finds_the_minimum_and_respects_bounds() {
        let p = sphere(vec![0.3, -0.2, 0.1, 0.05, -0.4, 0.25, 0.0, 0.15, -0.1], -1.0, 1.0);
        let mut ga = Ga { config: GaConfig { stall_rule: StallRule::Relative, ..GaConfig::matlab_defaults(9) } };
        let s = ga.minimize(&p, &[0.0; 9], &mut NoopObserver).unwrap();
        assert!(s.cost < 1e-4, "cost {}", s.cost);
        assert!(p.seen.lock().unwrap().iter().all(|x| p.b.contains(x)));
    }

    #[test]
    fn minimum_outside_the_box_ends_on_the_bound() {
        let p = sphere(vec![2.0, 0.0], -1.0, 1.0);
        let mut ga = Ga { config: GaConfig::matlab_defaults(2) };
        let s = ga.minimize(&p, &[0.0, 0.0], &mut NoopObserver).unwrap();
        assert!((s.params[0] - 1.0).abs() < 1e-3, "{:?}", s.params);
    }

    #[test]
    fn fixed_variables_never_move() {
        let mut p = sphere(vec![0.5, 0.5, 0.5], -1.0, 1.0);
        p.b = Bounds::new(vec![-1.0, 0.0, -1.0], vec![1.0, 0.0, 1.0]).unwrap();
        let mut ga = Ga { config: GaConfig { max_generations: 20, ..GaConfig::matlab_defaults(3) } };
        ga.minimize(&p, &[0.0; 3], &mut NoopObserver).unwrap();
        assert!(p.seen.lock().unwrap().iter().all(|x| x[1] == 0.0));
    }

    #[test]
    fn observer_can_stop() {
        let p = sphere(vec![0.1; 4], -1.0, 1.0);
        let mut ga = Ga { config: GaConfig::matlab_defaults(4) };
        let mut obs = FnObserver(|it: &Iteration| if it.iteration >= 3 { Control::Stop } else { Control::Continue });
        let s = ga.minimize(&p, &[0.0; 4], &mut obs).unwrap();
        assert_eq!(s.termination, Termination::Stopped);
        assert_eq!(s.iterations, 3);
    }

    #[test]
    fn matlab_rule_stops_earlier_at_small_costs() {
        // Cost plateaus near 0.02: the max(1, |best|) denominator makes MATLAB's test absolute.
        struct Plateau(Bounds);
        impl Problem for Plateau {
            fn bounds(&self) -> &Bounds {
                &self.0
            }
            fn cost(&self, x: &[f64]) -> f64 {
                0.02 + x.iter().map(|v| (v - 0.3) * (v - 0.3)).sum::<f64>()
            }
        }
        let p = Plateau(Bounds::new(vec![-1.0; 5], vec![1.0; 5]).unwrap());
        let run = |rule| {
            let cfg = GaConfig { stall_rule: rule, stall_generations: 10, ..GaConfig::matlab_defaults(5) };
            Ga { config: cfg }.minimize(&p, &[0.0; 5], &mut NoopObserver).unwrap()
        };
        let (m, r) = (run(StallRule::Matlab), run(StallRule::Relative));
        assert!(m.iterations < r.iterations, "matlab {} vs relative {}", m.iterations, r.iterations);
        assert!(r.cost <= m.cost);
    }

    #[test]
    fn bit_identical_across_thread_counts() {
        let p = sphere(vec![0.3, -0.2, 0.1, 0.05, -0.4], -1.0, 1.0);
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut ga = Ga { config: GaConfig { max_generations: 30, seed: 5, ..GaConfig::matlab_defaults(5) } };
                ga.minimize(&p, &[0.0; 5], &mut NoopObserver).unwrap()
            })
        };
        let (a, b) = (run(1), run(4));
        assert_eq!(
            a.params.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            b.params.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(a.cost.to_bits(), b.cost.to_bits());
    }

    #[test]
    fn dimension_errors_are_clear() {
        let p = sphere(vec![0.0; 9], -1.0, 1.0);
        let mut ga = Ga { config: GaConfig::matlab_defaults(9) };
        let e = ga.minimize(&p, &[0.0; 12], &mut NoopObserver).unwrap_err();
        assert_eq!(e.to_string(), "start point has 12 parameters but bounds have 9");
    }
}
