//! Adaptive, error-controlled Runge–Kutta integration of delay differential equations with
//! constant delays by the method of steps, with dense output.
//!
//! The integrator is DOP853 (Dormand–Prince 8(5,3) with 7th-order dense output; Hairer, Nørsett
//! & Wanner, *Solving Ordinary Differential Equations I*, 2nd ed., Sec. II.5 and II.6) applied
//! by the method of steps (Bellen & Zennaro, *Numerical Methods for Delay Differential
//! Equations*, Ch. 3–4):
//!
//! * every step is at most min(delays) long, so each delayed argument falls into an already
//!   accepted step and is read from its dense output — no iteration is needed;
//! * the derivative discontinuities t0 + Σ k_i τ_i (up to total order [`MAX_BREAKPOINT_LEVEL`])
//!   are landed on exactly, and the step after one restarts with a fresh first stage;
//! * the dense output of a step is the Hermite interpolant of the last four step points when it
//!   passes an a-posteriori error check (no extra stages; `dde/hermite.rs`), DOP853's own 7th-order
//!   extension otherwise (three more stages);
//! * the history keeps, in a ring buffer, only the dense-output coefficients of the delayed
//!   state prefix over the last max(delays), so memory stays flat on arbitrarily long runs;
//! * the step loop performs no allocation apart from the amortised growth of that ring; its long
//!   loops run an AVX2 compilation where the CPU has it ([`crate::simd`]).

mod ark;
mod hermite;
mod history;
mod imex;
mod tableau;

use crate::controller::discrete::Grid;
use hermite::Stencil;
use history::{newton, History, Nodes, NCOEF};
pub(crate) use imex::THRASHING;
use std::ops::ControlFlow;
use tableau::{A, C, D, E3, E5, STAGES, STAGES_DENSE};
use thiserror::Error;

/// Breakpoints t0 + Σ k_i τ_i are generated up to total order Σ k_i ≤ this level; beyond it
/// the jumps sit in derivatives of order > 9 and no longer affect the 8th-order method.
pub const MAX_BREAKPOINT_LEVEL: usize = 10;
/// Upper bound on the number of breakpoints (lower levels are kept first).
const MAX_BREAKPOINTS: usize = 20_000;

/// A delay differential equation y'(t) = f(t, y(t), y(t − τ_1), …) with constant delays.
///
/// Only the first [`DelaySystem::n_delayed`] components of the state are ever read at past
/// times; the history keeps just those.
pub trait DelaySystem {
    /// State dimension.
    fn dim(&self) -> usize;
    /// Length of the state prefix whose past values `rhs` reads.
    fn n_delayed(&self) -> usize;
    /// The positive constant delays (derivative discontinuities propagate along them).
    fn delays(&self) -> &[f64];
    /// dy ← f(t, y, past). `past.eval_into(s, first, out)` gives components `first..first+out.len()`
    /// of the state at s ≤ t − min(delays). Must not allocate.
    fn rhs(&mut self, t: f64, y: &[f64], past: &Past<'_>, dy: &mut [f64]);
    /// Length of the state prefix that `on_output` needs (default: the whole state). Outputs between
    /// step ends are interpolated for these components only, so a system whose outputs depend on a
    /// prefix saves the dense output of the rest.
    fn n_output(&self) -> usize {
        self.dim()
    }
    /// Called at each output time t, before `on_output`, with the output prefix `y` of the state and
    /// the past (delayed arguments t − τ read as in [`DelaySystem::rhs`]): for outputs that depend on
    /// delayed values. `Break` stops the run as `on_output`'s does. Default: nothing.
    fn observe(&mut self, _t: f64, _y: &[f64], _past: &Past<'_>) -> ControlFlow<()> {
        ControlFlow::Continue(())
    }
    /// Called at the end t of each accepted step with the whole state `y` there and the past (as in
    /// [`DelaySystem::observe`]), after the outputs in the step: for a watch between outputs.
    /// `Break` stops the run as `on_output`'s does. Default: nothing.
    fn accepted(&mut self, _t: f64, _y: &[f64], _past: &Past<'_>) -> ControlFlow<()> {
        ControlFlow::Continue(())
    }
    /// The components (default: none) whose rate is linear in themselves and may be stiff:
    /// f_I(y) = c(y) − M(y) y_I on this range, with M positive semidefinite and c, M depending
    /// on the other components only. The stiff method integrates them implicitly (see `dde/ark.rs`).
    fn implicit(&self) -> std::ops::Range<usize> {
        0..0
    }
    /// Writes into `out` (one entry per component, initially all `atol`) the absolute tolerance of
    /// the components whose errors the system amplifies on the way to what it reads or outputs, at
    /// the state `y`: `atol` or less. Called at every step point. Default: every component's is `atol`.
    fn absolute_tolerances(&self, _y: &[f64], _atol: f64, _out: &mut [f64]) {}
    /// An upper bound of M(y)'s spectral radius, the rate of the fastest implicit mode.
    fn implicit_rate(&self, _y: &[f64]) -> f64 {
        0.0
    }
    /// A lower estimate of that rate (at most the true one), sharper than [`DelaySystem::implicit_rate`]
    /// and dearer: `auto` holds DOP853's step where h times it would pass
    /// [`DOP853_ACCURATE_H_RATE`], beyond which DOP853's R no longer damps the implicit block.
    /// Default 0: never known to.
    fn implicit_rate_below(&mut self, _y: &[f64]) -> f64 {
        0.0
    }
    /// Solves z_I = r + c·f_I(t, z) for z_I, where on entry z_I holds r and the other components of
    /// z are final: (I + c M) z_I = r + c·c(t, z). f_I is [`DelaySystem::rhs`] on the implicit block,
    /// which must not read the past. `false` when the solve fails (the step is then rejected and
    /// retried shorter). Must not allocate.
    fn solve_implicit(&mut self, _t: f64, _c: f64, _z: &mut [f64]) -> bool {
        true
    }
    /// The implicit block of an error estimate `err`, filtered: err_I ← (I + c M(y))⁻¹ err_I with M
    /// at the state `y` (the filter of Hairer & Wanner's RADAU5, IV.8 (8.19)). The embedded
    /// solution's errors in a stiff block are its rounding and solve residues times h·M, which the
    /// filter returns to their own size. `false` when the solve fails. Must not allocate. Default:
    /// unchanged.
    fn filter_implicit_error(&mut self, _c: f64, _y: &[f64], _err: &mut [f64]) -> bool {
        true
    }
}

/// Read-only view of the dense history, handed to [`DelaySystem::rhs`].
///
/// Besides the history it knows the current stage time and step start, which decides the side
/// of the jump at t0 (history ≠ y0 is allowed): the step never straddles t0 + τ, so for the
/// delay τ = t_stage − s either the whole step reads the initial history (left limit at t0) or
/// the whole step reads the dense output (right limit, y(t0) = y0).
pub struct Past<'a> {
    hist: &'a History,
    initial: &'a [f64],
    y0: &'a [f64],
    t0: f64,
    /// t_step_start − t_stage: the step's first delayed argument for the delay implied by s
    /// is s + lead.
    lead: f64,
    tol: f64,
}

impl Past<'_> {
    /// Writes components `first..first + out.len()` of y(s) into `out`. Before t0 this is the
    /// constant initial history; at and after t0, the dense output of the accepted steps.
    ///
    /// # Panics
    /// If `first + out.len()` exceeds [`DelaySystem::n_delayed`].
    #[inline]
    pub fn eval_into(&self, s: f64, first: usize, out: &mut [f64]) {
        self.eval_ranges(s, [(first, out)]);
    }

    /// [`Past::eval_into`] for several component ranges at the same time s, locating the step record
    /// once.
    #[inline(always)]
    pub fn eval_ranges<const R: usize>(&self, s: f64, ranges: [(usize, &mut [f64]); R]) {
        if s + self.lead < self.t0 - self.tol {
            for (first, out) in ranges {
                out.copy_from_slice(&self.initial[first..first + out.len()]);
            }
        } else if self.hist.len() == 0 {
            for (first, out) in ranges {
                out.copy_from_slice(&self.y0[first..first + out.len()]);
            }
        } else {
            let mut ranges = ranges;
            self.hist.eval_at(self.hist.locate(s.max(self.t0)), &mut ranges);
        }
    }
}

/// Tolerances and limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    pub rtol: f64,
    pub atol: f64,
    /// Largest step; the solver also never steps further than the smallest delay.
    pub h_max: f64,
    /// Most accepted steps; a run that needs more ends with [`SolveError::TooManySteps`] (a loop
    /// blowing up turns stiff long before its states reach a divergence bound, and its history
    /// would fill memory).
    pub max_steps: usize,
    /// Most step records the delay history may hold at once (its memory is about
    /// [`record_bytes`] each, twice that while its ring doubles); a run that needs more ends with
    /// [`SolveError::HistoryTooLong`].
    pub max_history_len: usize,
    /// ρ, the fastest rate of the components outside the implicit block (0: none known). Each
    /// method keeps h·ρ within the range where its stability function follows the flow e^(−hρ) on
    /// that rate ([`DOP853_ACCURATE_H_RATE`], [`ARK_ACCURATE_H_RATE`]): nearer its stability bound a
    /// fast decaying mode is hardly damped, its errors pile up step after step, and the error
    /// estimate does not see them (a chemostat at rtol = atol = 1e-6 whose steps sat at DOP853's
    /// bound on its observer poles was 1 % off in y, 3e-8 with the cap).
    pub rate: f64,
    /// Which method integrates the steps.
    pub method: Method,
    /// Under [`Method::Auto`], the implicit block is expected to hold DOP853 at its stability bound
    /// (the closed loop sets it where μλ_max(Ω̄) ≥ [`crate::sim::EXPECT_STIFF_RATIO`]·ρ): the first DOP853 step
    /// beyond it hands over to the implicit method at once, which then keeps the loop to the end,
    /// instead of after a stability-limited stretch and a comparison of costs.
    pub expect_stiff: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            rtol: crate::settings::DEFAULT_TOLERANCE,
            atol: crate::settings::DEFAULT_TOLERANCE,
            h_max: f64::INFINITY,
            rate: 0.0,
            max_steps: usize::MAX,
            max_history_len: usize::MAX,
            method: Method::Auto,
            expect_stiff: false,
        }
    }
}

/// DOP853 keeps h·ρ ≤ this ([`Options::rate`]): up to it its stability function R(−x) follows e^(−x)
/// within 3 % (0.2 % up to 3), beyond it departs (27 % at 4) and reaches |R| = 1 at the stability
/// bound 6.1, where a run on the chemostat of `tests/data` was 1 % off at a tolerance of 1e-6.
pub const DOP853_ACCURATE_H_RATE: f64 = 3.5;

/// The implicit method's explicit part keeps h·ρ ≤ this ([`Options::rate`]): its |R(−x)| is least
/// there (0.12), so a longer step damps the fastest mode less, until |R| = 1 at 4.2.
pub const ARK_ACCURATE_H_RATE: f64 = 2.5;

/// Bytes of one step record of the history for `n_delayed` components: its coefficients, start,
/// length and nodes.
pub fn record_bytes(n_delayed: usize) -> usize {
    (NCOEF * n_delayed + 2 + (NCOEF - 1)) * std::mem::size_of::<f64>()
}

/// The integrator of the steps: a run's `simulation.method` ([`crate::settings::Method`]).
pub use crate::settings::Method;

/// Solver statistics, as a run's summary.json writes them (the names after `rename`; `thrashed`
/// only when there was such a stretch).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Stats {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected step attempts (error test failed or non-finite result).
    #[serde(rename = "rejected_steps")]
    pub rejected: usize,
    /// Evaluations of [`DelaySystem::rhs`].
    #[serde(rename = "rhs_evaluations")]
    pub rhs_evals: usize,
    /// Breakpoints (derivative discontinuities) landed on exactly.
    pub breakpoints: usize,
    /// Largest number of step records the dense history held at once.
    pub max_history_len: usize,
    /// Accepted steps taken by the implicit method (ARK4(3)6L\[2\]SA).
    pub implicit_steps: usize,
    /// Switches between the explicit and the implicit method.
    pub switches: usize,
    /// The first stretch [start, end] over which DOP853 thrashed at its stability bound before
    /// [`Method::Auto`] switched to the implicit method: its error estimate misses the stiff block's
    /// errors there, and they may exceed the tolerance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub thrashed: Option<(f64, f64)>,
}

/// Why the integration stopped early.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SolveError {
    /// With the statistics up to then.
    #[error("step size underflow at t = {t}: the step shrank to {h:e} without meeting the tolerance")]
    StepSizeTooSmall { t: f64, h: f64, stats: Stats },
    /// More than [`Options::max_steps`] accepted steps were needed by time `t`.
    #[error("more than {} steps by t = {t}", .stats.steps)]
    TooManySteps { t: f64, stats: Stats },
    /// The history would have held more than [`Options::max_history_len`] step records at time `t`.
    #[error("more than {} step records in the delay history at t = {t}", .stats.max_history_len)]
    HistoryTooLong { t: f64, stats: Stats },
    /// An argument of [`solve`] (or the system's [`DelaySystem::delays`]) of the wrong length or
    /// value; nothing was integrated.
    #[error("dde::solve: {argument}: expected {expected}, found {found}")]
    Input { argument: &'static str, expected: String, found: String },
}

/// Constant context of a run, shared by all RHS evaluations.
struct Ctx<'a> {
    initial: &'a [f64],
    /// The delayed prefix of y(t0).
    y0: Vec<f64>,
    t0: f64,
    tol: f64,
}

impl Ctx<'_> {
    /// The past as read at time t within the step that starts at t_n: lead = t_n − t.
    fn past<'p>(&'p self, hist: &'p History, lead: f64) -> Past<'p> {
        Past { hist, initial: self.initial, y0: &self.y0, t0: self.t0, lead, tol: self.tol }
    }
}

/// One RHS evaluation at stage time `t` of the step starting at `t_n`.
#[inline]
#[allow(clippy::too_many_arguments)]
fn eval_rhs<S: DelaySystem>(
    sys: &mut S,
    ctx: &Ctx<'_>,
    hist: &History,
    stats: &mut Stats,
    t_n: f64,
    t: f64,
    y: &[f64],
    dy: &mut [f64],
) {
    sys.rhs(t, y, &ctx.past(hist, t_n - t), dy);
    stats.rhs_evals += 1;
}

/// Sorted, deduplicated breakpoints t0 + Σ k_i τ_i, 1 ≤ Σ k_i ≤ [`MAX_BREAKPOINT_LEVEL`],
/// strictly inside (t0, t_end) (Bellen & Zennaro, Sec. 4.1: discontinuity propagation).
/// Points closer than ~1e-12 (relative) are merged.
pub fn breakpoints(t0: f64, delays: &[f64], t_end: f64) -> Vec<f64> {
    let span = t_end - t0;
    let scale = t0.abs().max(t_end.abs()).max(1.0);
    let tol = 1e-12 * scale;
    let dedup = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.dedup_by(|b, a| *b - *a <= tol);
    };
    let mut all: Vec<f64> = Vec::new();
    let mut level = vec![0.0];
    for _ in 0..MAX_BREAKPOINT_LEVEL {
        let mut next = Vec::with_capacity(level.len() * delays.len());
        for &x in &level {
            for &d in delays {
                let v = x + d;
                if v < span - tol {
                    next.push(v);
                }
            }
        }
        dedup(&mut next);
        if next.is_empty() || all.len() + next.len() > MAX_BREAKPOINTS {
            break;
        }
        all.extend_from_slice(&next);
        level = next;
    }
    dedup(&mut all);
    all.into_iter().map(|v| t0 + v).filter(|&b| b > t0 && b < t_end).collect()
}

/// Error-control constants of `dop853.f`.
const SAFE: f64 = 0.9;
/// Smallest step-size ratio h_new / h.
const FAC_MIN: f64 = 0.333;
/// Largest step-size ratio h_new / h.
const FAC_MAX: f64 = 6.0;

#[inline]
fn tiny(t: f64) -> f64 {
    16.0 * f64::EPSILON * t.abs().max(1.0)
}

#[inline]
fn h_min(t: f64) -> f64 {
    1e-14 * t.abs().max(1.0)
}

/// Integrates from `t0` (state `y0`, constant history `history` for t < t0, length `n_delayed`)
/// to `t_end`, calling `on_output(t, y)` at t = t0 + k·output_step, k = 0, 1, … (the last one at
/// t_end when the span is a whole number of output steps, to the relative tolerance of
/// `controller::discrete::whole_samples`, the sampled loop's count). `on_output` returning `Break`
/// stops the run early (the stats so far are returned).
///
/// y(t0) = `y0` may differ from `history` (a jump at t0). A non-positive or non-finite
/// `output_step` reports only t0 and t_end.
///
/// # Errors
/// [`SolveError::StepSizeTooSmall`] when the step shrinks below ~1e-14·max(1, |t|), e.g. at a
/// finite-time blow-up or when the right-hand side keeps producing non-finite values.
///
/// Inconsistent dimensions, a non-finite t0 or t_end, or a delay that is not positive and finite
/// are [`SolveError::Input`].
#[allow(clippy::too_many_arguments)]
pub fn solve<S: DelaySystem>(
    sys: &mut S,
    t0: f64,
    y0: &[f64],
    history: &[f64],
    t_end: f64,
    output_step: f64,
    opts: &Options,
    mut on_output: impl FnMut(f64, &[f64]) -> ControlFlow<()>,
) -> Result<Stats, SolveError> {
    solve_events(sys, t0, y0, history, t_end, output_step, opts, |event| match event {
        Event::Output(t, y) => on_output(t, y),
        Event::Step(_) => ControlFlow::Continue(()),
    })
}

/// What [`solve_events`] reports as it goes.
#[derive(Debug, Clone, Copy)]
pub enum Event<'y> {
    /// An output time and the output prefix of the state there, as [`solve`]'s `on_output` takes them.
    Output(f64, &'y [f64]),
    /// An accepted step ended at this time (after its outputs): a point to stop at between outputs.
    Step(f64),
}

/// [`solve`] reporting each accepted step as well as the outputs ([`Event`]); `Break` on either
/// stops the run. For a caller that must be able to stop between outputs an hour of run apart.
#[allow(clippy::too_many_arguments)]
pub fn solve_events<S: DelaySystem>(
    sys: &mut S,
    t0: f64,
    y0: &[f64],
    history: &[f64],
    t_end: f64,
    output_step: f64,
    opts: &Options,
    mut on_event: impl FnMut(Event<'_>) -> ControlFlow<()>,
) -> Result<Stats, SolveError> {
    let n = sys.dim();
    let nd = sys.n_delayed();
    let input = |argument, expected: String, found: String| Err(SolveError::Input { argument, expected, found });
    if y0.len() != n {
        return input("y0", format!("{} (the system's dim())", crate::settings::entries(n)), y0.len().to_string());
    }
    for (argument, t) in [("t0", t0), ("t_end", t_end)] {
        if !t.is_finite() {
            return input(argument, "a finite time".into(), t.to_string());
        }
    }
    if nd > n {
        return input("n_delayed()", format!("at most dim() = {n}"), nd.to_string());
    }
    if history.len() != nd {
        return input(
            "history",
            format!("{} (the system's n_delayed())", crate::settings::entries(nd)),
            history.len().to_string(),
        );
    }
    let delays: Vec<f64> = sys.delays().to_vec();
    if let Some(d) = delays.iter().find(|&&d| !(d > 0.0 && d.is_finite())) {
        return input("delays()", "positive, finite delays".into(), d.to_string());
    }
    let tau_min = delays.iter().copied().fold(f64::INFINITY, f64::min);

    let y_out0 = &y0[..sys.n_output().min(n)];
    let past0 = Past { hist: &History::new(nd, 0), initial: history, y0: &y0[..nd], t0, lead: 0.0, tol: tiny(t_end) };
    if sys.observe(t0, y_out0, &past0).is_break() || on_event(Event::Output(t0, y_out0)).is_break() || t_end <= t0 {
        return Ok(Stats::default());
    }
    let h_cap = opts.h_max.min(tau_min).min(t_end - t0);
    if h_cap.is_nan() || h_cap < h_min(t_end) {
        // A delay (or h_max) below rounding level of t would force steps that do not advance t.
        return Err(SolveError::StepSizeTooSmall { t: t0, h: h_cap, stats: Stats::default() });
    }
    // attempt → (reject | accept → record and emit → advance), until t_end.
    if sys.implicit().end > n {
        return input("implicit()", format!("a range within 0..{n}"), format!("{:?}", sys.implicit()));
    }
    let mut steps = Steps::new(sys, t0, y0, history, t_end, output_step, opts, h_cap, &delays);
    while steps.t < t_end - tiny(t_end) {
        let step = steps.propose();
        let attempted = if steps.stiff { steps.attempt_implicit(&step) } else { steps.attempt(&step) };
        let Some(len) = attempted else {
            steps.reject(&step)?;
            continue;
        };
        steps.accept(&step)?;
        if steps.record_and_emit(&step, len, &mut |t, y| on_event(Event::Output(t, y))).is_break()
            || steps.accepted(&step).is_break()
            || on_event(Event::Step(step.t_new)).is_break()
        {
            return Ok(steps.finish());
        }
        steps.advance(&step);
    }
    Ok(steps.finish())
}

/// The output schedule t0 + t_k (t_k = k·dt as [`Grid`] reads it), k = 1…n, n the whole output steps in the span (the last one
/// clamped to t_end when it lands there).
struct Schedule {
    t0: f64,
    dt: Grid,
    n: usize,
    /// The next k to emit.
    next: usize,
}

impl Schedule {
    /// The next output time if it lies in (·, t_new]. The last one is at most t_end once the run
    /// lands there: the count n may round t0 + n·dt up past t_end by the tolerance of a whole
    /// number of steps, and an earlier one lies a whole step before it.
    fn due(&self, t_new: f64, t_end: f64) -> Option<f64> {
        if self.next > self.n {
            return None;
        }
        let t_k = self.t0 + self.dt.at(self.next);
        let t_k = if self.next == self.n && t_new == t_end { t_k.min(t_end) } else { t_k };
        (t_k <= t_new).then_some(t_k)
    }
}

/// One step's plan: from t to `t_new` = t + `h`, landing exactly on the next breakpoint or t_end
/// when it would (nearly) reach it.
struct Step {
    h: f64,
    t_new: f64,
    lands: bool,
    at_breakpoint: bool,
    /// The step size the controller proposed before capping or landing.
    h_proposed: f64,
}

/// The state the steps of [`solve`] share: the current point, the stages, the dense output and its
/// history, the step-size control and the output schedule. Every buffer is allocated in `new`.
struct Steps<'a, S: DelaySystem> {
    sys: &'a mut S,
    opts: &'a Options,
    ctx: Ctx<'a>,
    hist: History,
    stats: Stats,
    /// State dimension, delayed prefix, output prefix, interpolated prefix (max of the two).
    n: usize,
    nd: usize,
    n_o: usize,
    n_i: usize,
    t_end: f64,
    tau_max: f64,
    h_cap: f64,
    /// The longest DOP853 step on the adaptive law's rate at the last step point (`law_h` in
    /// `imex.rs`; ∞ where it sets none).
    h_law: f64,
    t: f64,
    y: Vec<f64>,
    /// Stage derivatives k_1, …, k_16, n each (k_1 = f(t, y); k_13 = f(t_new, y_new), the FSAL stage).
    k: Vec<f64>,
    y_new: Vec<f64>,
    y_stage: Vec<f64>,
    err5: Vec<f64>,
    err3: Vec<f64>,
    /// Each component's absolute tolerance at the step start ([`DelaySystem::absolute_tolerances`]).
    atol: Vec<f64>,
    /// The step's dense output: Newton coefficients, coefficient-major over the `len` components it
    /// covers (the delayed prefix, or the interpolated prefix when an output falls in the step),
    /// and their nodes.
    dense: Vec<f64>,
    nodes: Nodes,
    y_out: Vec<f64>,
    stencil: Stencil,
    /// Proposed next step size, and whether the last attempt was rejected.
    h: f64,
    last_rejected: bool,
    breakpoints: Vec<f64>,
    next_breakpoint: usize,
    schedule: Schedule,
    /// The error norm of the last attempt (≤ 1: accepted).
    err: f64,
    /// The system's implicit block ([`DelaySystem::implicit`]).
    implicit: std::ops::Range<usize>,
    /// Whether the steps are taken by the implicit method (ARK4(3)6L\[2\]SA) rather than DOP853.
    stiff: bool,
    /// When to switch method under [`Method::Auto`] ([`Steps::watch_stiffness`]).
    switching: imex::Switching,
    /// The implicit block at the step points before the current one, while on the implicit method.
    earlier: imex::Earlier,
    /// The Hermite stencil must restart at the next step point (after a switch back to DOP853).
    fresh_stencil: bool,
}

impl<'a, S: DelaySystem> Steps<'a, S> {
    /// Allocates every buffer, evaluates f(t0, y0) and chooses the initial step.
    #[allow(clippy::too_many_arguments)]
    fn new(
        sys: &'a mut S,
        t0: f64,
        y0: &[f64],
        history: &'a [f64],
        t_end: f64,
        output_step: f64,
        opts: &'a Options,
        h_cap: f64,
        delays: &[f64],
    ) -> Self {
        let (n, nd) = (sys.dim(), sys.n_delayed());
        let tau_max = delays.iter().copied().fold(0.0, f64::max);
        let span = t_end - t0;
        let (dt, n_out) = if output_step > 0.0 && output_step.is_finite() {
            (output_step, crate::controller::discrete::whole_samples(span, output_step))
        } else {
            (span, 1)
        };
        let est_records = if tau_max > 0.0 { (tau_max / h_cap.max(1e-300)).min(4096.0) as usize + 8 } else { 4 };
        let n_o = sys.n_output().min(n);
        let n_i = nd.max(n_o);
        let mut steps = Steps {
            ctx: Ctx { initial: history, y0: y0[..nd].to_vec(), t0, tol: tiny(t_end) },
            hist: History::new(nd, est_records),
            stats: Stats::default(),
            n,
            nd,
            n_o,
            n_i,
            t_end,
            tau_max,
            h_cap,
            h_law: f64::INFINITY,
            t: t0,
            y: y0.to_vec(),
            k: vec![0.0; STAGES_DENSE * n],
            y_new: vec![0.0; n],
            y_stage: vec![0.0; n],
            err5: vec![0.0; n],
            err3: vec![0.0; n],
            atol: vec![opts.atol; n],
            dense: vec![0.0; NCOEF * n_i],
            nodes: DOP853_NODES,
            y_out: vec![0.0; n_o],
            stencil: Stencil::new(n_i),
            h: 0.0,
            last_rejected: false,
            breakpoints: breakpoints(t0, delays, t_end),
            next_breakpoint: 0,
            schedule: Schedule { t0, dt: Grid::new(dt), n: n_out, next: 1 },
            err: 0.0,
            implicit: sys.implicit(),
            stiff: opts.method == Method::Implicit,
            switching: imex::Switching::new(opts.expect_stiff),
            earlier: imex::Earlier::new(sys.implicit().len()),
            fresh_stencil: false,
            sys,
            opts,
        };
        steps.sys.absolute_tolerances(&steps.y, opts.atol, &mut steps.atol);
        steps.restart();
        let (t, n, h_first) = (steps.t, steps.n, h_cap.min(steps.accurate_h()));
        steps.h = initial_step(
            steps.sys,
            &steps.ctx,
            &steps.hist,
            &mut steps.stats,
            t,
            &steps.y,
            &steps.k[..n],
            &mut steps.y_stage,
            &mut steps.y_new,
            opts,
            h_first,
        );
        steps
    }

    /// k_1 = f(t, y) afresh and a new Hermite stencil: at t0 and after a breakpoint, where the
    /// derivative may jump so FSAL does not apply.
    fn restart(&mut self) {
        let (t, n) = (self.t, self.n);
        eval_rhs(self.sys, &self.ctx, &self.hist, &mut self.stats, t, t, &self.y, &mut self.k[..n]);
        self.stencil.restart(t, &self.y, &self.k[..n]);
    }

    /// The longest step the current method takes: on the rate ρ ([`Options::rate`]) and, on
    /// DOP853, on the adaptive law's (`h_law`, ∞ on the implicit method: reset at each switch and
    /// set on DOP853's steps only).
    fn accurate_h(&self) -> f64 {
        let bound = if self.stiff { ARK_ACCURATE_H_RATE } else { DOP853_ACCURATE_H_RATE };
        self.on_rho(bound).min(self.h_law)
    }

    /// The longest step with h·ρ ≤ `bound` ([`Options::rate`]); ∞ without a rate.
    fn on_rho(&self, bound: f64) -> f64 {
        if self.opts.rate > 0.0 {
            bound / self.opts.rate
        } else {
            f64::INFINITY
        }
    }

    /// The next step: the proposed size capped at h_cap and the method's [`Steps::accurate_h`], landing on the next breakpoint or t_end
    /// if it would reach it or leave only a sliver (a sliver below rounding level may make the step
    /// exceed h_cap by a few ulps, which is harmless).
    fn propose(&mut self) -> Step {
        let (t, bps) = (self.t, &self.breakpoints);
        while self.next_breakpoint < bps.len() && bps[self.next_breakpoint] <= t + tiny(t) {
            self.next_breakpoint += 1;
        }
        let (stop, at_breakpoint) = match bps.get(self.next_breakpoint) {
            Some(&b) => (b, true),
            None => (self.t_end, false),
        };
        let h_cap = self.h_cap.min(self.accurate_h());
        let mut h = self.h.min(h_cap);
        let gap = stop - (t + h);
        let lands = gap <= tiny(stop) || (gap < 0.01 * h && stop - t <= h_cap);
        if lands {
            h = stop - t;
        }
        Step {
            h,
            t_new: if lands { stop } else { t + h },
            lands,
            at_breakpoint: lands && at_breakpoint,
            h_proposed: self.h,
        }
    }

    /// Stages 2…12 and y_new, the error norm (the combined 5th/3rd-order norm of `dop853.f`), and
    /// for a step within tolerance its tentative acceptance: the FSAL stage and, when the history or
    /// an output needs one, the dense output. `None` when the step is rejected (error above 1, or a
    /// non-finite value in y_new or those stages); otherwise the number of components the dense
    /// output covers.
    fn attempt(&mut self, step: &Step) -> Option<usize> {
        let (n, t, h) = (self.n, self.t, step.h);
        for s in 1..STAGES {
            combine(&self.y, &self.k, &A[s][..s], h, n, &mut self.y_stage);
            let ts = if C[s] == 1.0 { step.t_new } else { t + C[s] * h };
            eval_rhs(
                self.sys,
                &self.ctx,
                &self.hist,
                &mut self.stats,
                t,
                ts,
                &self.y_stage,
                &mut self.k[s * n..(s + 1) * n],
            );
        }
        combine(&self.y, &self.k, &A[12][..STAGES], h, n, &mut self.y_new);

        self.err5.fill(0.0);
        lincomb(&mut self.err5, &self.k, n, &E5, 1.0, 0..n);
        self.err3.fill(0.0);
        lincomb(&mut self.err3, &self.k, n, &E3, 1.0, 0..n);
        let (s5, s3) = error_sums(&self.err5, &self.err3, &self.y, &self.y_new, self.opts.rtol, &self.atol);
        let mut deno = s5 + 0.01 * s3;
        if deno <= 0.0 {
            deno = 1.0;
        }
        self.err = h * s5 * (1.0 / (n.max(1) as f64 * deno)).sqrt();
        if !self.err.is_finite() || !all_finite(&self.y_new) {
            self.err = f64::INFINITY;
        }
        if self.err > 1.0 {
            return None;
        }
        let dense = self.tentatively_accept(step);
        (self.err <= 1.0).then_some(dense)
    }

    /// The FSAL evaluation k_13 = f(t_new, y_new) and, when needed, the step's dense output: the
    /// Hermite interpolant of the last four step points, or DOP853's own (three more stages). A
    /// non-finite value there rejects the step after all (sets the error to ∞).
    fn tentatively_accept(&mut self, step: &Step) -> usize {
        let (n, t, h) = (self.n, self.t, step.h);
        eval_rhs(
            self.sys,
            &self.ctx,
            &self.hist,
            &mut self.stats,
            t,
            step.t_new,
            &self.y_new,
            &mut self.k[12 * n..13 * n],
        );
        let outputs = self.schedule.due(step.t_new, self.t_end).is_some();
        let len = if outputs { self.n_i } else { self.nd };
        let mut last = 13;
        if self.nd > 0 || outputs {
            let tol = (self.opts.rtol, &self.atol[..]);
            match self.stencil.interpolate(h, &self.y_new, &self.k[12 * n..13 * n], len, tol, &mut self.dense) {
                Some(nodes) => self.nodes = nodes,
                None => {
                    for s in 13..STAGES_DENSE {
                        combine(&self.y, &self.k, &A[s][..s], h, n, &mut self.y_stage);
                        let ts = t + C[s] * h;
                        let k_s = &mut self.k[s * n..(s + 1) * n];
                        eval_rhs(self.sys, &self.ctx, &self.hist, &mut self.stats, t, ts, &self.y_stage, k_s);
                    }
                    last = STAGES_DENSE;
                    dense_coefficients(&self.y, &self.y_new, &self.k, h, n, 0..len, &mut self.dense);
                    self.nodes = DOP853_NODES;
                }
            }
        }
        if !all_finite(&self.k[12 * n..last * n]) {
            self.err = f64::INFINITY;
        }
        len
    }

    /// A rejected attempt: a smaller step, or the end of the run when it falls below ~1e-14·|t|.
    fn reject(&mut self, step: &Step) -> Result<(), SolveError> {
        self.stats.rejected += 1;
        self.last_rejected = true;
        self.h = step.h / (1.0 / FAC_MIN).min(self.err.powf(self.exponent()) / SAFE);
        // A landing the smaller step would stretch back to (it ends within tiny(t_new) of the
        // breakpoint) would be tried as it was, for ever: a loop at 5e-12 s a unit of time had
        // rejected 1.79e-14 s, proposed 1.52e-14 s and landed on 1.79e-14 s again without end,
        // deaf to signals (hostile review, 2026-12-06). Half the landing step does not land.
        if step.lands && step.t_new - (self.t + self.h) <= tiny(step.t_new) {
            self.h = 0.5 * step.h;
        }
        if self.h < h_min(self.t) {
            return Err(SolveError::StepSizeTooSmall { t: self.t, h: self.h, stats: self.finish() });
        }
        Ok(())
    }

    /// An accepted step: the next step size (`dop853.f`'s controller, no growth right after a
    /// rejection, and not shrunk by a landing); the end of the run beyond `max_steps`.
    fn accept(&mut self, step: &Step) -> Result<(), SolveError> {
        // A step beyond a budget is not taken: the statistics count the steps the run kept.
        if self.stats.steps >= self.opts.max_steps {
            return Err(SolveError::TooManySteps { t: self.t, stats: self.finish() });
        }
        if self.nd > 0 && self.hist.len() >= self.opts.max_history_len {
            return Err(SolveError::HistoryTooLong { t: self.t, stats: self.finish() });
        }
        self.stats.steps += 1;
        let fac = (self.err.powf(self.exponent()) / SAFE).clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
        let mut h_next = step.h / fac;
        if self.last_rejected {
            h_next = h_next.min(step.h);
        } else if step.lands && step.h < step.h_proposed {
            h_next = h_next.max(step.h_proposed);
        }
        self.last_rejected = false;
        self.h = h_next;
        if self.stiff {
            self.stats.implicit_steps += 1;
        }
        self.watch_stiffness(step);
        Ok(())
    }

    /// Stores the step's dense output of the delayed prefix in the history and emits the outputs
    /// that fall in (t, t_new]; `Break` when `on_output` asks to stop.
    fn record_and_emit(
        &mut self,
        step: &Step,
        len: usize,
        on_output: &mut impl FnMut(f64, &[f64]) -> ControlFlow<()>,
    ) -> ControlFlow<()> {
        let nd = self.nd;
        if nd > 0 {
            let slot = self.hist.push(self.t, step.h, &self.nodes);
            for (r, row) in slot.chunks_exact_mut(nd).enumerate() {
                row.copy_from_slice(&self.dense[r * len..r * len + nd]);
            }
        }
        // Outputs are due here exactly when `tentatively_accept` interpolated for them.
        while let Some(t_k) = self.schedule.due(step.t_new, self.t_end) {
            let out: &[f64] = if t_k == step.t_new {
                &self.y_new[..self.n_o]
            } else {
                newton(&self.dense, len, &self.nodes, (t_k - self.t) / step.h, &mut [(0, &mut self.y_out[..])]);
                &self.y_out
            };
            self.schedule.next += 1;
            // The step is in the history, and t_k − τ ≤ t_new − min τ ≤ t: the past is all known.
            self.sys.observe(t_k, out, &self.ctx.past(&self.hist, self.t - t_k))?;
            on_output(t_k, out)?;
        }
        ControlFlow::Continue(())
    }

    /// [`DelaySystem::accepted`] at the end of `step`, which the history already holds.
    fn accepted(&mut self, step: &Step) -> ControlFlow<()> {
        self.sys.accepted(step.t_new, &self.y_new, &self.ctx.past(&self.hist, self.t - step.t_new))
    }

    /// Moves to t_new: prunes the history to the last max τ, then restarts at a breakpoint or
    /// carries the FSAL stage over.
    fn advance(&mut self, step: &Step) {
        self.hist.prune(step.t_new - self.tau_max);
        if self.stiff {
            self.earlier.push(self.t, &self.y[self.implicit.clone()]);
        } else {
            self.earlier.clear();
        }
        self.t = step.t_new;
        std::mem::swap(&mut self.y, &mut self.y_new);
        self.sys.absolute_tolerances(&self.y, self.opts.atol, &mut self.atol);
        if step.at_breakpoint {
            self.fresh_stencil = false;
            self.stats.breakpoints += 1;
            self.restart();
        } else {
            let n = self.n;
            self.k.copy_within(12 * n..13 * n, 0);
            if std::mem::take(&mut self.fresh_stencil) {
                self.stencil.restart(self.t, &self.y, &self.k[..n]);
            } else {
                self.stencil.push(self.t, &self.y, &self.k[..n]);
            }
        }
    }

    /// The statistics, with the history's peak length.
    fn finish(&self) -> Stats {
        Stats { max_history_len: self.hist.max_len(), ..self.stats }
    }
}

/// out ← y + h Σ_j a_j k_j (zero coefficients skipped).
#[inline]
fn combine(y: &[f64], k: &[f64], a: &[f64], h: f64, n: usize, out: &mut [f64]) {
    match (&mut *out, y) {
        // One component (the scalar `dde` bench): a call to memcpy costs more than the copy.
        ([o], [v]) => *o = *v,
        _ => out.copy_from_slice(y),
    }
    lincomb(out, k, n, a, h, 0..n);
}

/// out += scale·Σ_j c_j k_j[range] over the nonzero c_j, fusing up to four stages per pass so the
/// loop over components vectorizes and `out` is loaded and stored once per four terms.
#[inline]
fn lincomb(out: &mut [f64], k: &[f64], n: usize, c: &[f64], scale: f64, range: std::ops::Range<usize>) {
    // A few components are cheaper inline than through the AVX2 dispatch.
    if range.len() >= 8 {
        lincomb_wide(out, k, n, c, scale, range)
    } else {
        lincomb_inline(out, k, n, c, scale, range)
    }
}

with_avx2! {
    /// [`lincomb`] for many components.
    fn lincomb_wide(out: &mut [f64], k: &[f64], n: usize, c: &[f64], scale: f64, range: std::ops::Range<usize>) {
        lincomb_inline(out, k, n, c, scale, range)
    }
}

#[inline(always)]
fn lincomb_inline(out: &mut [f64], k: &[f64], n: usize, c: &[f64], scale: f64, range: std::ops::Range<usize>) {
    let mut terms = c
        .iter()
        .enumerate()
        .filter(|(_, &cj)| cj != 0.0)
        .map(|(j, &cj)| (scale * cj, &k[j * n + range.start..j * n + range.end]));
    loop {
        match (terms.next(), terms.next(), terms.next(), terms.next()) {
            (Some((a, ka)), Some((b, kb)), Some((c, kc)), Some((d, kd))) => {
                for ((((o, x), y), z), w) in out.iter_mut().zip(ka).zip(kb).zip(kc).zip(kd) {
                    *o += a * x + b * y + c * z + d * w;
                }
            }
            (Some((a, ka)), Some((b, kb)), Some((c, kc)), None) => {
                for (((o, x), y), z) in out.iter_mut().zip(ka).zip(kb).zip(kc) {
                    *o += a * x + b * y + c * z;
                }
                return;
            }
            (Some((a, ka)), Some((b, kb)), None, _) => {
                for ((o, x), y) in out.iter_mut().zip(ka).zip(kb) {
                    *o += a * x + b * y;
                }
                return;
            }
            (Some((a, ka)), None, _, _) => {
                for (o, x) in out.iter_mut().zip(ka) {
                    *o += a * x;
                }
                return;
            }
            _ => return,
        }
    }
}

with_avx2! {
    /// dop853.f's error sums Σ (e5_i/sk_i)² and Σ (e3_i/sk_i)², sk_i = atol_i + rtol·max(|y_i|, |y_new_i|),
    /// in four interleaved partial sums (which the compiler may keep in vector lanes).
    fn error_sums(err5: &[f64], err3: &[f64], y: &[f64], y_new: &[f64], rtol: f64, atol: &[f64]) -> (f64, f64) {
        let n = err5.len();
        let (err3, y, y_new, atol) = (&err3[..n], &y[..n], &y_new[..n], &atol[..n]);
        let (mut s5, mut s3) = ([0.0; 4], [0.0; 4]);
        for i in 0..n {
            let sk = 1.0 / (atol[i] + rtol * y[i].abs().max(y_new[i].abs()));
            let (e5, e3) = (err5[i] * sk, err3[i] * sk);
            s5[i % 4] += e5 * e5;
            s3[i % 4] += e3 * e3;
        }
        ((s5[0] + s5[1]) + (s5[2] + s5[3]), (s3[0] + s3[1]) + (s3[2] + s3[3]))
    }
}

with_avx2! {
    /// True when no entry is infinite or NaN (a scan without early exit, so it vectorizes).
    fn all_finite(v: &[f64]) -> bool {
        const EXPONENT: u64 = 0x7ff0_0000_0000_0000;
        v.iter().fold(0u64, |bad, x| bad | u64::from(x.to_bits() & EXPONENT == EXPONENT)) == 0
    }
}

/// The Newton nodes of DOP853's dense output: `contd8` of `dop853.f` evaluates
/// r0 + θ(r1 + (1 − θ)(r2 + θ(r3 + (1 − θ)(r4 + θ(r5 + (1 − θ)(r6 + θ r7)))))), which is the Newton
/// form over these nodes with r2, r3, r6 and r7 negated.
const DOP853_NODES: Nodes = [0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0];

/// Dense-output coefficients (`rcont1..rcont8` of `dop853.f`) of the components in `range`, in the
/// Newton form over [`DOP853_NODES`], written coefficient-major into `out`
/// (`out[r * len + (i − range.start)]`, len = range length).
fn dense_coefficients(
    y: &[f64],
    y_new: &[f64],
    k: &[f64],
    h: f64,
    n: usize,
    range: std::ops::Range<usize>,
    out: &mut [f64],
) {
    let len = range.len();
    let (first, last) = (range.start, range.end);
    let (c0, rest) = out.split_at_mut(len);
    let (c1, rest) = rest.split_at_mut(len);
    let (c2, rest) = rest.split_at_mut(len);
    let (c3, rest) = rest.split_at_mut(len);
    let (y, y_new, k1, k13) =
        (&y[first..last], &y_new[first..last], &k[first..last], &k[12 * n + first..12 * n + last]);
    for i in 0..len {
        let ydiff = y_new[i] - y[i];
        let bspl = h * k1[i] - ydiff;
        c0[i] = y[i];
        c1[i] = ydiff;
        c2[i] = -bspl;
        c3[i] = bspl + h * k13[i] - ydiff;
    }
    for (r, drow) in D.iter().enumerate() {
        let row = &mut rest[r * len..(r + 1) * len];
        row.fill(0.0);
        // rcont5, rcont6 keep their sign; rcont7, rcont8 flip.
        lincomb(row, k, n, drow, if r < 2 { h } else { -h }, first..last);
    }
}

/// Initial step by Hairer's heuristic (`hinit` in `dop853.f`, RMS norms), capped at `h_cap`.
#[allow(clippy::too_many_arguments)]
fn initial_step<S: DelaySystem>(
    sys: &mut S,
    ctx: &Ctx<'_>,
    hist: &History,
    stats: &mut Stats,
    t: f64,
    y: &[f64],
    f0: &[f64],
    y1: &mut [f64],
    f1: &mut [f64],
    opts: &Options,
    h_cap: f64,
) -> f64 {
    let n = y.len().max(1) as f64;
    let (mut dnf, mut dny) = (0.0, 0.0);
    for (yi, fi) in y.iter().zip(f0) {
        let sk = opts.atol + opts.rtol * yi.abs();
        dnf += (fi / sk) * (fi / sk);
        dny += (yi / sk) * (yi / sk);
    }
    let (dnf, dny) = ((dnf / n).sqrt(), (dny / n).sqrt());
    let mut h = if dnf <= 1e-5 || dny <= 1e-5 { 1e-6 } else { 0.01 * dny / dnf };
    h = h.min(h_cap);
    for ((o, yi), fi) in y1.iter_mut().zip(y).zip(f0) {
        *o = yi + h * fi;
    }
    eval_rhs(sys, ctx, hist, stats, t, t + h, y1, f1);
    let mut der2 = 0.0;
    for ((yi, a), b) in y.iter().zip(f0).zip(f1.iter()) {
        let sk = opts.atol + opts.rtol * yi.abs();
        der2 += ((b - a) / sk) * ((b - a) / sk);
    }
    let der2 = (der2 / n).sqrt() / h;
    let der12 = der2.abs().max(dnf);
    let h1 = if der12 <= 1e-15 { (h * 1e-3).max(1e-6) } else { (0.01 / der12).powf(1.0 / 8.0) };
    let h = (100.0 * h).min(h1).min(h_cap);
    if h.is_finite() && h > 0.0 {
        h
    } else {
        h_cap.min(1e-6)
    }
}
