//! One run of a study, its row of figures, and the parallel sweep over many runs.

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::{Nominal, Runaway, Settle, Study};
use crate::hash::{mix64, GOLDEN_GAMMA};
use crate::scenario::Scenario;
use crate::settings::fmt_instant;
use crate::sim::{self, ChannelFigures, Loop, Peaks, Run, RunSettings, SimResult};

/// The seed of Monte Carlo draw `draw` of a study with seed `study_seed`. It depends on nothing
/// else, so a run can be carried out alone (on any machine, in any order), and draw d perturbs the
/// plant the same way at every grid point (common random numbers: differences between grid points
/// are the grid's, not the draws').
pub fn run_seed(study_seed: u64, draw: usize) -> u64 {
    mix64(mix64(study_seed).wrapping_add(GOLDEN_GAMMA.wrapping_mul(draw as u64 + 1)))
}

/// Everything one run needs, self-contained and serializable (for `quell.sweep_runs` and a
/// cluster's workers): [`run_one`] carries it out.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunSpec {
    /// Run index: point × draws + draw.
    pub run: usize,
    pub point: usize,
    pub draw: usize,
    /// The seed of the draw (0 without Monte Carlo).
    pub seed: u64,
    /// The grid point's values, (key as written, value).
    pub grid: Vec<(String, toml::Value)>,
    /// The run's scenario document: grid values and the draw's perturbations applied.
    pub scenario: toml::Table,
    pub settle: Settle,
    /// The solver's step budget of a continuous run ([`Study::max_steps`]); `None`: the run's own
    /// default, derived from its problem ([`sim::default_max_steps`]).
    #[serde(default)]
    pub max_steps: Option<usize>,
    /// The runaway rules ([`Study::runaway`]) and the grid point's nominal run they compare with;
    /// without a nominal run the rules do not apply.
    #[serde(default)]
    pub runaway: Runaway,
    #[serde(default)]
    pub nominal: Option<Nominal>,
    /// The keys the study's draws perturb ([`super::Study::drawn_keys`]): its row's drawn values
    /// are their numbers in `scenario` ([`super::drawn_values`]), so a run carried out alone (a
    /// cluster's worker) has the row a sweep writes.
    #[serde(default)]
    pub drawn_keys: Vec<String>,
}

impl RunSpec {
    /// The numbers of [`RunSpec::drawn_keys`] in its scenario with their columns' names, in
    /// runs.csv's order ([`super::drawn_values`]); none without Monte Carlo.
    pub fn drawn_named(&self) -> Vec<(String, f64)> {
        let grid: Vec<String> = self.grid.iter().map(|(k, _)| k.clone()).collect();
        super::drawn_values(&self.drawn_keys, &grid, &self.scenario)
    }

    /// The row's drawn values ([`RunSpec::drawn_named`] without the names).
    pub fn drawn(&self) -> Vec<Option<f64>> {
        self.drawn_named().into_iter().map(|(_, v)| Some(v)).collect()
    }

    /// The runaway rules' limits of this run against its nominal run (`None` without one): at most
    /// ⌈runaway.steps · (the nominal run's steps, or the floor this run's shortest delay sets
    /// when that is more, + the breakpoints its delays add)⌉ solver steps, and runaway.peak · the
    /// nominal peaks of x, x̂ (at least x's) and η̂ (no bound on a signal that stayed 0 there, nor on
    /// ξ̂). Drawn delays
    /// add breakpoints t = Σ k_i τ_i, each a step the nominal run did not take: the paper's loop
    /// at t_end = 40 with both delays 2 % off lands on 559 instead of 29 and takes 752 steps
    /// instead of 268. A run whose adaptive law is expected stiff where the nominal run's is not
    /// ([`Run::expects_stiff`]: a drawn μ or filter) takes the implicit path from its start, whose
    /// steps the nominal run's say nothing about (the paper's loop with μ₂ = 117 takes 2,187
    /// where μ₂ = 90 takes 704); it keeps its own step budget and the peak rule.
    fn runaway_limits(&self, shape: &StepScale) -> Option<(usize, Peaks)> {
        self.nominal.map(|n| {
            let peaks = n.peaks.runaway(self.runaway.peak, n.xi_bound);
            if shape.expects_stiff && !n.expects_stiff {
                return (usize::MAX, peaks);
            }
            let steps = n.steps.max(shape.delay_floor) + shape.breakpoints.saturating_sub(n.breakpoints);
            ((self.runaway.steps * steps as f64).ceil() as usize, peaks)
        })
    }

    /// Simulates the run's scenario within its limits (step budget, [`Runaway`] rules): the
    /// signals behind its row of [`run_one`]. `Err` when its scenario or design is invalid.
    pub fn simulate(&self) -> Result<SimResult, String> {
        self.simulate_until(&|| false)
    }

    /// [`RunSpec::simulate`] that `stop` ends early (checked as the run goes; the result's outcome is
    /// then [`crate::sim::Outcome::Interrupted`]): how a front end lets Ctrl-C stop one run.
    pub fn simulate_until(&self, stop: &dyn Fn() -> bool) -> Result<SimResult, String> {
        self.simulate_within_limits(stop).map(|run| run.result)
    }

    /// [`RunSpec::simulate_until`], with what decided its step budget.
    fn simulate_within_limits(&self, stop: &dyn Fn() -> bool) -> Result<Simulated, String> {
        let s = Scenario::from_document(&self.scenario).map_err(|e| e.to_string())?;
        simulate(&s, self.max_steps, &|shape| self.runaway_limits(shape), stop)
    }
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Reached t_end.
    Completed,
    /// A state left the divergence bound.
    Diverged,
    /// The run could not be carried out: its scenario or design is invalid (a draw or a combination
    /// of grid values made it so) or the solver's step underflowed.
    Failed,
    /// A rule of `[runaway]` ended it early (a signal beyond `peak` × the nominal run's peak, or
    /// more than `steps` × its steps): what a loop that blows up does, and what a converging loop
    /// with a large transient may do too (a maglev 30 % off: 11 of the 13 draws the peak rule ended
    /// converged without it), so not called diverged.
    Stopped,
}

impl Outcome {
    /// The word in runs.csv.
    pub fn as_str(self) -> &'static str {
        match self {
            Outcome::Completed => "completed",
            Outcome::Diverged => "diverged",
            Outcome::Failed => "failed",
            Outcome::Stopped => "stopped",
        }
    }
}

/// One row of runs.csv.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    pub run: usize,
    pub point: usize,
    pub draw: usize,
    pub seed: u64,
    /// The grid values as written in the study file (TOML syntax).
    pub grid: Vec<String>,
    pub outcome: Outcome,
    /// Why a run diverged, failed or was stopped; empty when it completed.
    pub reason: String,
    /// One per channel: the run's figures up to where it ended (a run that stopped early has NaN
    /// tails, written empty, and the peaks |u|, |u_f| it reached); empty where no run took place.
    /// [`Row::completed`] has them only for a completed run.
    pub channels: Vec<ChannelFigures>,
    /// Solver steps (controller steps of a sampled-data run).
    pub steps: u64,
    /// Wall time of the run in ms, to the microsecond.
    pub wall_ms: f64,
    /// The values its draw gave ([`super::StudyMeta::drawn`]'s columns; `None`: written empty);
    /// empty without Monte Carlo.
    #[serde(default)]
    pub drawn: Vec<Option<f64>>,
    /// The run was forced onto DOP853 (`simulation.method = "explicit"`) on an adaptive law it
    /// makes stiff ([`crate::sim::explicit_stiff_warning`]); not in runs.csv, so false for rows
    /// read back ([`super::Study::explicit_stiff_caution`] words it).
    #[serde(skip)]
    pub explicit_stiff: bool,
}

impl Row {
    /// The figures of a completed run; none for a run that diverged, failed or was stopped, whose tails were
    /// never reached and whose peaks are those of a runaway.
    pub fn completed(&self) -> &[ChannelFigures] {
        if self.outcome == Outcome::Completed {
            &self.channels
        } else {
            &[]
        }
    }
}

/// What sets a run's steps beside its nominal run's: what the runaway rules' limits depend on.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct StepScale {
    /// The breakpoints t = Σ k_i τ_i its loop lands on ([`Run::breakpoints`]; 0 when sampled).
    pub breakpoints: usize,
    /// [`Run::delay_floor`].
    pub delay_floor: usize,
    /// [`Run::expects_stiff`] of a continuous run.
    pub expects_stiff: bool,
}

/// A study run's result, its [`StepScale`] and the runaway rules' step budget when that was the run's
/// budget.
pub(crate) struct Simulated {
    pub result: SimResult,
    /// The run's memory bound, reserved ([`sim::Run::reserve_memory`]) until its row is made.
    pub memory: Option<sim::Held<'static>>,
    /// How long the run waited for that memory (not part of its `wall_ms`).
    pub waited: std::time::Duration,
    pub shape: StepScale,
    pub runaway_steps: Option<usize>,
    /// Forced onto DOP853 on a stiff adaptive law (looked at only on `explicit`, which alone pays
    /// for the averaged law it needs).
    pub explicit_stiff: bool,
    /// For a run its step budget or the history's cap ended, [`sim::budget_culprit`]: how large its
    /// signals had grown, and a rate far faster than the loop.
    pub budget_note: Option<String>,
    /// A run ended as diverged within its divergence bounds ([`Run::divergence_bounds`]): a
    /// `[runaway]` peak limit stopped it.
    pub peak_rule: bool,
}

/// Simulates a scenario as its `[simulation]` says ([`Run::of`]), a continuous run within the
/// step budget `max_steps` (`None`: the run's own, [`sim::default_max_steps`]) and, given its
/// [`StepScale`], `runaway` = (steps, peaks): within at most that many steps and those peaks per
/// watched signal; `Err` when it cannot start.
pub(crate) fn simulate(
    s: &Scenario,
    max_steps: Option<usize>,
    runaway: &dyn Fn(&StepScale) -> Option<(usize, Peaks)>,
    stop: &dyn Fn() -> bool,
) -> Result<Simulated, String> {
    let design = s.design().map_err(|e| e.to_string())?;
    let mut settings = RunSettings::of(s);
    let run = Run::of(s, &design);
    let explicit_stiff = sim::explicit_on_stiff_law(&run);
    let mut shape = StepScale { breakpoints: run.breakpoints(), delay_floor: run.delay_floor(), expects_stiff: false };
    let mut runaway_steps = None;
    if let Loop::Continuous(integrator) = &mut settings.mode {
        // The loop computes it anyway (`dde::Options::expect_stiff`); `run` keeps it.
        shape.expects_stiff = run.expects_stiff();
        let given = integrator.clone();
        let own = || max_steps.unwrap_or_else(|| sim::default_max_steps(&run, &given));
        let limits = runaway(&shape);
        let budget = match limits {
            // The default is never below BUDGET_MIN_STEPS: a runaway budget within it decides alone
            // (and a Monte Carlo draw skips the averaged law the default needs).
            Some((steps, _)) if max_steps.is_none() && steps <= sim::BUDGET_MIN_STEPS => steps,
            Some((steps, _)) => own().min(steps),
            None => own(),
        };
        integrator.max_steps = Some(budget);
        runaway_steps = limits.map(|l| l.0).filter(|&l| l == budget && max_steps.is_none_or(|given| l < given));
        settings.runaway = limits.map(|(_, peaks)| peaks);
    }
    let limits_set = settings.runaway.is_some();
    let progress = |_t: f64| if stop() { ControlFlow::Break(()) } else { ControlFlow::Continue(()) };
    let run = run.settings(settings);
    // A stop while waiting for memory lets the run start and end at its first progress check.
    let waiting = Instant::now();
    let memory = run.reserve_memory(stop);
    let waited = waiting.elapsed();
    let result = run.simulate(progress).map_err(|e| e.to_string())?;
    // A run its own budget or the history's cap ended (not the runaway rule's budget): a rate far
    // faster than the loop may be why.
    let by_runaway = matches!(result.outcome, Some(sim::Outcome::TooManySteps { max_steps, .. }) if runaway_steps == Some(max_steps));
    let budget_note = (!by_runaway).then(|| sim::budget_culprit(&Run::of(s, &design), &result)).flatten();
    // Which limit ended a diverged run, by its absolute bounds (computed only here: a Monte Carlo
    // draw skips the averaged law they need). A fixed 1e9 had called a rule's stop on a plant in
    // small units a divergence.
    let peak_rule = match &result.outcome {
        Some(sim::Outcome::Diverged { signal, value, .. }) if limits_set => {
            value.is_finite() && value.abs() <= Run::of(s, &design).divergence_bounds().0[Peaks::index_of(signal)]
        }
        _ => false,
    };
    Ok(Simulated { result, memory, waited, shape, runaway_steps, explicit_stiff, budget_note, peak_rule })
}

/// A grid value as runs.csv writes it: numbers in [`super::csv_number`]'s shortest round-trip form
/// (a grid value of 1e300 was written as its 301 digits), a whole float with its `.0` (so that
/// pandas reads 1.0 as the float it is, not the integer 1), lists of them in brackets.
pub(super) fn grid_text(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(x) => {
            let text = super::csv_number(*x);
            if text.contains(['.', 'e', 'i', 'N']) {
                text
            } else {
                text + ".0"
            }
        }
        toml::Value::Array(a) => format!("[{}]", a.iter().map(grid_text).collect::<Vec<_>>().join(", ")),
        other => other.to_string(),
    }
}

/// Carries out one run; `None` when `stop` interrupted it.
pub(super) fn execute(spec: &RunSpec, stop: &dyn Fn() -> bool) -> Option<Row> {
    let mut started = Instant::now();
    let mut row = Row {
        run: spec.run,
        point: spec.point,
        draw: spec.draw,
        seed: spec.seed,
        grid: spec.grid.iter().map(|(_, v)| grid_text(v)).collect(),
        outcome: Outcome::Failed,
        reason: String::new(),
        channels: Vec::new(),
        steps: 0,
        wall_ms: 0.0,
        drawn: spec.drawn(),
        explicit_stiff: false,
    };
    match spec.simulate_within_limits(stop) {
        Err(reason) => row.reason = reason,
        // `_memory` stays held until the row is made.
        Ok(Simulated {
            result: r,
            runaway_steps,
            shape: StepScale { breakpoints, delay_floor, .. },
            memory: _memory,
            waited,
            explicit_stiff,
            budget_note,
            peak_rule,
        }) => {
            // The wait for memory is not the run's time.
            started += waited;
            row.explicit_stiff = explicit_stiff;
            row.steps = r.stats.steps() as u64;
            // A run that diverged keeps the actuator peaks it reached on the way.
            row.channels = r.figures(&spec.settle);
            match r.outcome.as_ref().unwrap_or(&sim::Outcome::Completed) {
                sim::Outcome::Completed => row.outcome = Outcome::Completed,
                sim::Outcome::Diverged { t, signal, value } => {
                    row.outcome = Outcome::Diverged;
                    row.reason = format!("{signal} = {value:e} at t = {} {}", fmt_instant(*t), r.time_unit);
                    if let (Some(n), true) = (spec.nominal, peak_rule) {
                        row.outcome = Outcome::Stopped;
                        // x̂ is bounded as x is where x's peak is the larger.
                        let group = match Peaks::index_of(signal) {
                            1 if n.peaks.0[0] > n.peaks.0[1] => 0,
                            g => g,
                        };
                        row.reason += &format!(
                            ": beyond {} × the peak of {} in the nominal run, {:.4e} (over its entries; runaway.peak)",
                            spec.runaway.peak,
                            sim::WATCHED[group].0,
                            n.peaks.0[group]
                        );
                    }
                }
                sim::Outcome::TooManySteps { t, max_steps } if runaway_steps == Some(*max_steps) => {
                    row.outcome = Outcome::Stopped;
                    let scale = step_rule_scale(spec, breakpoints, delay_floor);
                    row.reason = format!(
                        "step budget: more than {} × {scale} ({max_steps}) by t = {} {} (the loop turned stiff: its signals grew well beyond the nominal run's; raise the study's runaway.steps if the run is sound)",
                        spec.runaway.steps,
                        fmt_instant(*t),
                        r.time_unit
                    );
                }
                sim::Outcome::Interrupted { .. } => return None,
                other => row.reason = other.explain("the study's max_steps", r.time_unit).unwrap_or_default(),
            }
            if let Some(w) = budget_note {
                row.reason += &format!("; {w}");
            }
        }
    }
    // Whole microseconds, as runs.csv writes them, so a row reads back exactly.
    row.wall_ms = started.elapsed().as_micros() as f64 / 1e3;
    Some(row)
}

/// What the step rule of `[runaway]` multiplies, in words: the nominal run's steps, or the steps
/// this draw's shortest delay forces where more (`delay_floor`), plus the breakpoints its delays add
/// beyond the nominal run's.
fn step_rule_scale(spec: &RunSpec, breakpoints: usize, delay_floor: usize) -> String {
    let (n, extra) = spec.nominal.map_or((0, 0), |n| (n.steps, breakpoints.saturating_sub(n.breakpoints)));
    let base = if delay_floor > n {
        format!("the {delay_floor} steps this draw's shortest delay needs at least (a step is at most that delay)")
    } else {
        format!("the nominal run's {n} solver steps")
    };
    match extra {
        0 => base,
        _ => format!("({base} + the {extra} breakpoints this draw's delays add)"),
    }
}

/// Carries out one run: its row (a diverging or invalid run is a row too, never an error).
pub fn run_one(spec: &RunSpec) -> Row {
    execute(spec, &|| false).expect("a run without a stop signal is never interrupted")
}

/// [`run_one`] that `stop` ends early (checked as the run goes): `None` when it did.
pub fn run_one_until(spec: &RunSpec, stop: &dyn Fn() -> bool) -> Option<Row> {
    execute(spec, stop)
}

/// Runs with index ≡ `index` (mod `count`): machine `index` of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    /// Every run.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Parses `I/N` with 0 ≤ I < N; the message says what is wrong.
    pub fn parse(text: &str) -> Result<Shard, String> {
        let bad = || format!("expected I/N with 0 ≤ I < N (machine I of N, counting from 0), e.g. 0/4; found `{text}`");
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let (index, count) =
            (i.trim().parse::<usize>().map_err(|_| bad())?, n.trim().parse::<usize>().map_err(|_| bad())?);
        if count == 0 {
            return Err(format!("expected N ≥ 1 shards, found `{text}`"));
        }
        if index >= count {
            return Err(format!(
                "shard index {index} ≥ N = {count}: shards count from 0, so the last is {}/{count}",
                count - 1
            ));
        }
        Ok(Shard { index, count })
    }

    /// The run indices of this shard among `runs`.
    pub fn runs(self, runs: usize) -> impl Iterator<Item = usize> {
        (self.index..runs).step_by(self.count)
    }

    /// How many of `runs` this shard holds.
    pub fn len(self, runs: usize) -> usize {
        runs.saturating_sub(self.index).div_ceil(self.count)
    }

    /// True when this shard holds none of `runs`.
    pub fn is_empty(self, runs: usize) -> bool {
        self.len(runs) == 0
    }
}

/// How [`sweep`] runs.
#[derive(Clone, Copy)]
pub struct SweepOptions<'a> {
    pub shard: Shard,
    /// Set (e.g. by Ctrl-C) to stop: runs under way are abandoned, no new one starts.
    pub stop: Option<&'a AtomicBool>,
    /// Called after each run (from the worker threads).
    pub on_row: Option<&'a (dyn Fn(&Row) + Sync)>,
    /// Runs of the shard already done, by their place k in it (run index + k·count): skipped, as
    /// when an interrupted sweep is resumed. Empty: none.
    pub done: &'a [bool],
}

impl Default for SweepOptions<'_> {
    fn default() -> Self {
        SweepOptions { shard: Shard::ALL, stop: None, on_row: None, done: &[] }
    }
}

/// The rows of a sweep, in run order.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    pub rows: Vec<Row>,
    /// True when stopped before every run of the shard was carried out.
    pub partial: bool,
}

/// Carries out the shard's runs in parallel on rayon's current pool (set its size with
/// `rayon::ThreadPool::install`), every run from its own [`RunSpec`].
pub fn sweep(study: &Study, opts: &SweepOptions<'_>) -> Sweep {
    let runs = usize::try_from(study.len()).unwrap_or(usize::MAX);
    let stopped = || opts.stop.is_some_and(|s| s.load(Ordering::Relaxed));
    let shard = opts.shard;
    let done = |k: usize| opts.done.get(k).copied().unwrap_or(false);
    // `None` only when stopped, which ends the iteration: the runs not started are not visited (a
    // Ctrl-C on a study of 1e9 runs had taken 4.6 s to skip them one by one).
    let rows: Vec<Row> = (0..shard.len(runs))
        .into_par_iter()
        .filter(|&k| !done(k))
        .map(|k| shard.index + k * shard.count)
        .map(|i| {
            if stopped() {
                return None;
            }
            let row = execute(&study.spec_with_nominal_until(i, &stopped)?, &stopped)?;
            if let Some(f) = opts.on_row {
                f(&row);
            }
            Some(row)
        })
        .while_some()
        .collect();
    let kept = opts.done.iter().take(shard.len(runs)).filter(|&&d| d).count();
    let partial = rows.len() < shard.len(runs) - kept;
    Sweep { rows, partial }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The peak rule bounds x, x̂ (at least as x) and η̂ by runaway.peak × their nominal peaks, and
    /// not ξ̂, which a true plant's mismatch inflates through the disturbance observer in draws that
    /// converge (an aircraft pitch loop: 28 of 50 draws at its nominal delay had been stopped).
    #[test]
    fn the_peak_rule_bounds_the_states_and_the_parameters_not_the_regressor() {
        let study =
            crate::study::Study::from_toml("[monte_carlo]\nruns = 2\n\"truth.A\" = { relative = 0.01 }\n", None)
                .unwrap();
        let mut spec = study.spec_with_nominal(1).unwrap();
        let n = spec.nominal.as_mut().unwrap();
        n.peaks = Peaks([2.0, 0.5, 3.0, 4.0]);
        let shape = StepScale { breakpoints: 0, delay_floor: 0, expects_stiff: false };
        let (_, bounds) = spec.runaway_limits(&shape).unwrap();
        let xi = spec.nominal.unwrap().xi_bound;
        assert!(xi >= crate::sim::DIVERGENCE_BOUND, "ξ̂ at its divergence bound: {xi}");
        assert_eq!(bounds, Peaks([200.0, 200.0, xi, 400.0]));
        spec.nominal.as_mut().unwrap().peaks = Peaks([2.0, 5.0, 3.0, 0.0]);
        assert_eq!(spec.runaway_limits(&shape).unwrap().1, Peaks([200.0, 500.0, xi, f64::INFINITY]));
    }

    #[test]
    fn a_nan_in_the_reference_means_never_settled() {
        use crate::sim::{RunStats, Sample, SimResult};
        let time = |g: [f64; 5], s: &Settle| {
            let stats = RunStats::Sampled { controller_steps: 0, sample_time: 1.0, precision: Default::default() };
            let mut r = SimResult::new(1, 1, 1, stats);
            for (k, (e, g)) in [1.0, 0.5, 0.01, 0.01, 0.01].into_iter().zip(g).enumerate() {
                r.push(&Sample {
                    t: k as f64,
                    y: &[g + e],
                    g: &[g],
                    u: &[0.0],
                    u_f: &[0.0],
                    eta: &[0.0],
                    states: None,
                });
            }
            r.figures(s)[0].settle_t
        };
        let s = Settle { relative: 0.02, absolute: 0.0 };
        // Band 0.02 · 1 = 0.02: settled from t = 2.
        assert_eq!(time([1.0; 5], &s), Some(2.0));
        // Was Some(2.0): the NaN sample was dropped by f64::max.
        assert_eq!(time([1.0, f64::NAN, 1.0, 1.0, 1.0], &s), None);
        let s = Settle { relative: 0.02, absolute: 0.05 };
        assert_eq!(time([1.0, f64::NAN, 1.0, 1.0, 1.0], &s), None);
    }

    /// A draw's seed is mix(mix(seed) + γ (d + 1)) (docs/studies.md), values from an independent
    /// Python implementation of that formula; run_seed(0, 0) is SplitMix64's first output from
    /// seed 0, the published e220a8397b1dcdaf. The seeds of existing studies stay the same.
    #[test]
    fn run_seeds_are_the_documented_splitmix64_formula() {
        assert_eq!(run_seed(0, 0), 0xe220_a839_7b1d_cdaf);
        assert_eq!(run_seed(7, 0), 0x863b_891f_4c0a_bd4f);
        assert_eq!(run_seed(7, 1), 0x4d58_fbd2_82ea_f415);
        assert_eq!(run_seed(u64::MAX, 12345), 0xe4a3_5de0_820f_043f);
    }
}
