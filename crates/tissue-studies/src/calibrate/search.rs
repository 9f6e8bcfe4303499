//! The paper's search methods: the hybrid GA+SA (XSA crossover and MSA mutation screened by the
//! Metropolis criterion), the pure GA (no screening) and the pure SA.
//!
//! Choices where the paper is silent (stated here, settable in [`super::Settings`]):
//! parents are drawn by fitness-proportional (roulette) selection, consecutive draws pair up and
//! cross over with probability `crossover` (0.8); a crossover picks two points `i <= j` and the
//! genes `i..=j` of each offspring are random blends `alpha p1 + (1 - alpha) p2`, the others copied
//! from the offspring's own parent; a mutation (probability `mutation` per chromosome) replaces
//! one random gene by a uniform value within its bounds. In XSA an offspring worse than the
//! better parent is kept with probability `exp(-(f(o) - f(p_best)) / T)` and otherwise replaced by
//! its own parent; in MSA a worse mutant is kept with probability `exp(-(f(m) - f(o)) / T)`.
//! Temperatures follow Lundy and Mees, `T <- T / (1 + beta T)`, one step per generation, from
//! `T0` = the standard deviation of the initial population's cost down to `T0 * t_final_ratio`.
//! Pure SA runs one chain for `generations` temperatures of `sa_iterations` moves each; a move
//! perturbs one random gene by a uniform step of up to 10 % of its range (reflected at the
//! bounds), screened by the same Metropolis criterion and schedule.
//!
//! Every random number is drawn on the calling thread in a fixed order; only cost evaluations run
//! in parallel (rayon), and each is a pure function of its genes, so a seed gives the same bytes
//! on any number of threads.

use std::sync::atomic::{AtomicBool, Ordering};

use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt as _, SeedableRng as _};
use rayon::prelude::*;

use super::cost::{Problem, Workspace};
use super::genes::GeneSpace;
use super::{CostMode, GenerationStats, Method, Settings};

/// What a search returns: the best genes, their cost, the per-generation history, evaluations.
#[derive(Debug, Clone)]
pub struct SearchOutcome {
    /// Best genes seen.
    pub best: Vec<f64>,
    /// Their cost.
    pub best_cost: f64,
    /// One entry per generation (per temperature for SA).
    pub history: Vec<GenerationStats>,
    /// Cost evaluations.
    pub evaluations: u64,
    /// Whether the search was cancelled before its last generation.
    pub cancelled: bool,
}

struct Evaluator<'a> {
    problem: &'a Problem,
    space: &'a GeneSpace,
    mode: CostMode,
    evaluations: u64,
    /// One workspace per worker thread, kept from generation to generation (a workspace only
    /// caches factor patterns: a cost is a pure function of its genes).
    workspaces: Vec<std::sync::Mutex<Workspace>>,
}

impl<'a> Evaluator<'a> {
    /// Costs of many chromosomes in parallel. A chromosome whose model cannot be solved (a static
    /// solve that does not converge, say) gets an infinite cost: the search moves on without it.
    fn eval_many(&mut self, genes: &[Vec<f64>]) -> Vec<f64> {
        self.evaluations += genes.len() as u64;
        let (problem, space, mode) = (self.problem, self.space, self.mode);
        let workspaces = &self.workspaces;
        genes
            .par_iter()
            .map(|g| {
                let slot = rayon::current_thread_index().unwrap_or(0) % workspaces.len();
                let mut ws = workspaces[slot].lock().unwrap_or_else(std::sync::PoisonError::into_inner);
                problem.cost_in(mode, &space.params(g), &mut ws).unwrap_or(f64::INFINITY)
            })
            .collect()
    }

    fn new(problem: &'a Problem, space: &'a GeneSpace, mode: CostMode) -> Self {
        let workspaces = (0..rayon::current_num_threads().max(1)).map(|_| Default::default()).collect();
        Self { problem, space, mode, evaluations: 0, workspaces }
    }
}

fn stats(generation: usize, costs: &[f64], best_cost: f64, evaluations: u64, temperature: f64) -> GenerationStats {
    let fit: Vec<f64> = costs.iter().map(|c| 1.0 / c).collect();
    let mean = fit.iter().sum::<f64>() / fit.len() as f64;
    let var = fit.iter().map(|f| (f - mean).powi(2)).sum::<f64>() / fit.len() as f64;
    GenerationStats {
        generation,
        best_cost,
        population_best_cost: costs.iter().copied().fold(f64::INFINITY, f64::min),
        mean_fitness: mean,
        std_fitness: var.sqrt(),
        evaluations,
        temperature,
    }
}

/// Lundy-Mees schedule from `t0` to `t0 * ratio` in `steps` steps: `beta` of `T <- T / (1 + beta T)`.
fn lundy_mees_beta(t0: f64, ratio: f64, steps: usize) -> f64 {
    let t_end = t0 * ratio;
    (1.0 / t_end - 1.0 / t0) / steps.max(1) as f64
}

fn metropolis(rng: &mut Xoshiro256PlusPlus, delta: f64, t: f64) -> bool {
    // Draw unconditionally so that the random stream does not depend on the comparison.
    let u: f64 = rng.random();
    delta < 0.0 || (t > 0.0 && u < (-delta / t).exp())
}

fn random_genes(rng: &mut Xoshiro256PlusPlus, space: &GeneSpace) -> Vec<f64> {
    (0..space.len()).map(|i| space.lo[i] + rng.random::<f64>() * (space.hi[i] - space.lo[i])).collect()
}

fn roulette(rng: &mut Xoshiro256PlusPlus, fitness: &[f64], total: f64) -> usize {
    let mut x = rng.random::<f64>() * total;
    for (i, f) in fitness.iter().enumerate() {
        x -= f;
        if x < 0.0 {
            return i;
        }
    }
    fitness.len() - 1
}

fn initial_temperature(costs: &[f64]) -> f64 {
    let finite: Vec<f64> = costs.iter().copied().filter(|c| c.is_finite()).collect();
    if finite.is_empty() {
        return 1.0;
    }
    let mean = finite.iter().sum::<f64>() / finite.len() as f64;
    let sd = (finite.iter().map(|c| (c - mean).powi(2)).sum::<f64>() / finite.len() as f64).sqrt();
    if sd > 0.0 { sd } else { mean.abs().max(1e-12) * 0.1 }
}

/// What the GA and SA begin with: the generator seeded by `settings.seed`, the evaluator, a
/// sample of random genes (drawn in order) with their costs, and the history to come.
struct Start<'a> {
    rng: Xoshiro256PlusPlus,
    eval: Evaluator<'a>,
    sample: Vec<Vec<f64>>,
    cost: Vec<f64>,
    history: Vec<GenerationStats>,
}

impl<'a> Start<'a> {
    fn new(problem: &'a Problem, space: &'a GeneSpace, settings: &Settings, size: usize) -> Self {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(settings.seed);
        let mut eval = Evaluator::new(problem, space, settings.cost);
        let sample: Vec<Vec<f64>> = (0..size).map(|_| random_genes(&mut rng, space)).collect();
        let cost = eval.eval_many(&sample);
        Self { rng, eval, sample, cost, history: Vec::with_capacity(settings.generations + 1) }
    }
}

/// The initial temperature from a sample's costs, and the Lundy-Mees rate that cools it to
/// `t_final_ratio` of itself over the generations.
fn cooling(costs: &[f64], settings: &Settings) -> (f64, f64) {
    let t = initial_temperature(costs);
    (t, lundy_mees_beta(t, settings.t_final_ratio, settings.generations))
}

/// Runs the hybrid GA+SA or the pure GA. `screen` enables XSA/MSA.
#[allow(clippy::too_many_lines, reason = "numeric kernel: one GA+SA generation loop, read best in one piece")]
pub fn genetic(
    problem: &Problem,
    space: &GeneSpace,
    settings: &Settings,
    cancel: &AtomicBool,
    on_generation: &mut dyn FnMut(&GenerationStats),
) -> SearchOutcome {
    let screen = settings.method == Method::Hybrid;
    let np = settings.population.max(2);
    let Start { mut rng, mut eval, sample: mut pop, mut cost, mut history } = Start::new(problem, space, settings, np);
    let (mut best, mut best_cost) = best_of(&pop, &cost);
    let (mut t, beta) = cooling(&cost, settings);
    let mut cancelled = false;
    for generation in 0..=settings.generations {
        let s = stats(generation, &cost, best_cost, eval.evaluations, t);
        on_generation(&s);
        history.push(s);
        if generation == settings.generations {
            break;
        }
        if cancel.load(Ordering::Relaxed) {
            cancelled = true;
            break;
        }
        // Selection and crossover (offspring generated first, evaluated together).
        let fitness: Vec<f64> = cost.iter().map(|c| 1.0 / c).collect();
        let total: f64 = fitness.iter().sum();
        let parents: Vec<usize> = (0..np.next_multiple_of(2)).map(|_| roulette(&mut rng, &fitness, total)).collect();
        let mut children: Vec<Vec<f64>> = Vec::with_capacity(parents.len());
        let mut crossed = Vec::with_capacity(parents.len() / 2);
        for pair in parents.chunks_exact(2) {
            let (p1, p2) = (&pop[pair[0]], &pop[pair[1]]);
            let cross = rng.random::<f64>() < settings.crossover;
            crossed.push(cross);
            if cross {
                let (mut i, mut j) = (rng.random_range(0..space.len()), rng.random_range(0..space.len()));
                if i > j {
                    std::mem::swap(&mut i, &mut j);
                }
                let (mut o1, mut o2) = (p1.clone(), p2.clone());
                for g in i..=j {
                    let (a1, a2): (f64, f64) = (rng.random(), rng.random());
                    o1[g] = a1 * p1[g] + (1.0 - a1) * p2[g];
                    o2[g] = a2 * p1[g] + (1.0 - a2) * p2[g];
                }
                children.push(o1);
                children.push(o2);
            } else {
                children.push(p1.clone());
                children.push(p2.clone());
            }
        }
        let fresh: Vec<usize> = (0..children.len()).filter(|&c| crossed[c / 2]).collect();
        let fresh_cost = eval.eval_many(&fresh.iter().map(|&c| children[c].clone()).collect::<Vec<_>>());
        let mut child_cost: Vec<f64> = parents.iter().map(|&p| cost[p]).collect();
        for (&c, &f) in fresh.iter().zip(&fresh_cost) {
            child_cost[c] = f;
        }
        // XSA: screen each offspring against the better parent.
        for (pair_idx, pair) in parents.chunks_exact(2).enumerate() {
            if !crossed[pair_idx] {
                continue;
            }
            let best_parent = cost[pair[0]].min(cost[pair[1]]);
            for side in 0..2 {
                let c = 2 * pair_idx + side;
                let accept = !screen || metropolis(&mut rng, child_cost[c] - best_parent, t);
                if !accept {
                    children[c] = pop[pair[side]].clone();
                    child_cost[c] = cost[pair[side]];
                }
            }
        }
        children.truncate(np);
        child_cost.truncate(np);
        // Mutation, screened by MSA.
        let mut mutated = Vec::new();
        let mut mutants = Vec::new();
        for (c, genes) in children.iter().enumerate() {
            if rng.random::<f64>() < settings.mutation {
                let g = rng.random_range(0..space.len());
                let mut m = genes.clone();
                m[g] = space.lo[g] + rng.random::<f64>() * (space.hi[g] - space.lo[g]);
                mutated.push(c);
                mutants.push(m);
            }
        }
        let mutant_cost = eval.eval_many(&mutants);
        for ((c, m), mc) in mutated.into_iter().zip(mutants).zip(mutant_cost) {
            let accept = !screen || metropolis(&mut rng, mc - child_cost[c], t);
            if accept {
                children[c] = m;
                child_cost[c] = mc;
            }
        }
        pop = children;
        cost = child_cost;
        let (b, bc) = best_of(&pop, &cost);
        if bc < best_cost {
            (best, best_cost) = (b, bc);
        }
        t /= 1.0 + beta * t;
    }
    SearchOutcome { best, best_cost, history, evaluations: eval.evaluations, cancelled }
}

/// Runs the pure simulated annealing baseline.
pub fn annealing(
    problem: &Problem,
    space: &GeneSpace,
    settings: &Settings,
    cancel: &AtomicBool,
    on_generation: &mut dyn FnMut(&GenerationStats),
) -> SearchOutcome {
    // The start, then a sample of moves around it: T0 from the sample, as the GA takes it from
    // its population.
    let Start { mut rng, mut eval, sample, cost, mut history } =
        Start::new(problem, space, settings, 1 + settings.sa_iterations.max(2));
    let (mut x, mut fx) = (sample[0].clone(), cost[0]);
    let (mut best, mut best_cost) = (x.clone(), fx);
    let probe_cost = &cost[1..];
    let (mut t, beta) = cooling(probe_cost, settings);
    history.push(stats(
        0,
        probe_cost,
        best_cost.min(probe_cost.iter().copied().fold(f64::INFINITY, f64::min)),
        eval.evaluations,
        t,
    ));
    on_generation(&history[0]);
    let mut cancelled = false;
    for generation in 1..=settings.generations {
        if cancel.load(Ordering::Relaxed) {
            cancelled = true;
            break;
        }
        let mut visited = Vec::with_capacity(settings.sa_iterations);
        for _ in 0..settings.sa_iterations {
            let g = rng.random_range(0..space.len());
            let range = space.hi[g] - space.lo[g];
            let mut y = x.clone();
            let mut v = y[g] + (2.0 * rng.random::<f64>() - 1.0) * 0.1 * range;
            if v < space.lo[g] {
                v = 2.0 * space.lo[g] - v;
            }
            if v > space.hi[g] {
                v = 2.0 * space.hi[g] - v;
            }
            y[g] = v.clamp(space.lo[g], space.hi[g]);
            let fy = eval.eval_many(std::slice::from_ref(&y))[0];
            if metropolis(&mut rng, fy - fx, t) {
                (x, fx) = (y, fy);
            }
            if fx < best_cost {
                (best, best_cost) = (x.clone(), fx);
            }
            visited.push(fx);
        }
        let s = stats(generation, &visited, best_cost, eval.evaluations, t);
        on_generation(&s);
        history.push(s);
        t /= 1.0 + beta * t;
    }
    SearchOutcome { best, best_cost, history, evaluations: eval.evaluations, cancelled }
}

fn best_of(pop: &[Vec<f64>], cost: &[f64]) -> (Vec<f64>, f64) {
    let mut i = 0;
    for (j, c) in cost.iter().enumerate() {
        if *c < cost[i] {
            i = j;
        }
    }
    (pop[i].clone(), cost[i])
}
