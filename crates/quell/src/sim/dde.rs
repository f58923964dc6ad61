//! Adaptive, error-controlled Runge–Kutta integration of delay differential equations with
//! constant delays by the method of steps, with dense output.
//! STUB: owned by the integrator helper; the API below is the contract.

use std::ops::ControlFlow;
use thiserror::Error;

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
}

/// Read-only view of the dense history, handed to [`DelaySystem::rhs`].
pub struct Past<'a> {
    _p: std::marker::PhantomData<&'a ()>,
}

impl Past<'_> {
    /// Writes components `first..first + out.len()` of y(s) into `out`. Before t0 this is the
    /// constant initial history; at and after t0, the dense output of the accepted steps.
    pub fn eval_into(&self, s: f64, first: usize, out: &mut [f64]) {
        let _ = (s, first, out);
        todo!()
    }
}

/// Tolerances and limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    pub rtol: f64,
    pub atol: f64,
    /// Largest step; the solver also never steps further than the smallest delay.
    pub h_max: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options { rtol: 1e-9, atol: 1e-9, h_max: f64::INFINITY }
    }
}

/// Solver statistics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    pub steps: usize,
    pub rejected: usize,
    pub rhs_evals: usize,
}

/// Why the integration stopped early.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SolveError {
    #[error("step size underflow at t = {t}: the step shrank to {h:e} without meeting the tolerance")]
    StepSizeTooSmall { t: f64, h: f64 },
}

/// Integrates from `t0` (state `y0`, constant history `history` for t < t0, length `n_delayed`)
/// to `t_end`, calling `on_output(t, y)` at t = t0 + k·output_step, k = 0, 1, … (the last one at
/// t_end when it is a whole multiple). `on_output` returning `Break` stops the run early
/// (the stats so far are returned).
pub fn solve<S: DelaySystem>(
    sys: &mut S,
    t0: f64,
    y0: &[f64],
    history: &[f64],
    t_end: f64,
    output_step: f64,
    opts: &Options,
    on_output: impl FnMut(f64, &[f64]) -> ControlFlow<()>,
) -> Result<Stats, SolveError> {
    let _ = (sys, t0, y0, history, t_end, output_step, opts, on_output);
    todo!()
}
