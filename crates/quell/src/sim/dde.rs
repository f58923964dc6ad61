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

mod hermite;
mod history;
mod tableau;

use hermite::Stencil;
use history::{newton, History, Nodes, NCOEF};
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
    #[inline]
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
}

impl Default for Options {
    fn default() -> Self {
        Options { rtol: 1e-9, atol: 1e-9, h_max: f64::INFINITY }
    }
}

/// Solver statistics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected step attempts (error test failed or non-finite result).
    pub rejected: usize,
    /// Evaluations of [`DelaySystem::rhs`].
    pub rhs_evals: usize,
    /// Breakpoints (derivative discontinuities) landed on exactly.
    pub breakpoints: usize,
    /// Largest number of step records the dense history held at once.
    pub max_history_len: usize,
}

/// Why the integration stopped early.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SolveError {
    /// With the statistics up to then.
    #[error("step size underflow at t = {t}: the step shrank to {h:e} without meeting the tolerance")]
    StepSizeTooSmall { t: f64, h: f64, stats: Stats },
}

/// Constant context of a run, shared by all RHS evaluations.
struct Ctx<'a> {
    initial: &'a [f64],
    y0: &'a [f64],
    t0: f64,
    tol: f64,
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
    let past = Past { hist, initial: ctx.initial, y0: ctx.y0, t0: ctx.t0, lead: t_n - t, tol: ctx.tol };
    sys.rhs(t, y, &past, dy);
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
/// t_end when it is a whole multiple). `on_output` returning `Break` stops the run early
/// (the stats so far are returned).
///
/// y(t0) = `y0` may differ from `history` (a jump at t0). A non-positive or non-finite
/// `output_step` reports only t0 and t_end.
///
/// # Errors
/// [`SolveError::StepSizeTooSmall`] when the step shrinks below ~1e-14·max(1, |t|), e.g. at a
/// finite-time blow-up or when the right-hand side keeps producing non-finite values.
///
/// # Panics
/// On inconsistent dimensions, or on a delay that is not positive and finite.
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
    let n = sys.dim();
    let nd = sys.n_delayed();
    assert_eq!(y0.len(), n, "y0 has length {}, the system dimension is {n}", y0.len());
    assert!(t0.is_finite() && t_end.is_finite(), "t0 and t_end must be finite");
    assert!(nd <= n, "n_delayed = {nd} exceeds the dimension {n}");
    assert_eq!(history.len(), nd, "history must have length n_delayed = {nd}");
    let delays: Vec<f64> = sys.delays().to_vec();
    assert!(delays.iter().all(|&d| d > 0.0 && d.is_finite()), "delays must be positive and finite: {delays:?}");
    let tau_min = delays.iter().copied().fold(f64::INFINITY, f64::min);
    let tau_max = delays.iter().copied().fold(0.0, f64::max);

    let mut stats = Stats::default();
    if on_output(t0, &y0[..sys.n_output().min(n)]).is_break() || t_end <= t0 {
        return Ok(stats);
    }
    let span = t_end - t0;
    let h_cap = opts.h_max.min(tau_min).min(span);
    if h_cap.is_nan() || h_cap < h_min(t_end) {
        // A delay (or h_max) below rounding level of t would force steps that do not advance t.
        return Err(SolveError::StepSizeTooSmall { t: t0, h: h_cap, stats });
    }
    let bps = breakpoints(t0, &delays, t_end);
    let (dt_out, n_out) = if output_step > 0.0 && output_step.is_finite() {
        let out_tol = 1e-9 * output_step;
        (output_step, ((span + out_tol) / output_step).floor() as usize)
    } else {
        (span, 1)
    };

    // Setup: every buffer of the step loop is allocated here.
    let y0_prefix = y0[..nd].to_vec();
    let ctx = Ctx { initial: history, y0: &y0_prefix, t0, tol: tiny(t_end) };
    let est_records = if tau_max > 0.0 { (tau_max / h_cap.max(1e-300)).min(4096.0) as usize + 8 } else { 4 };
    let mut hist = History::new(nd, est_records);
    let mut k = vec![0.0; STAGES_DENSE * n];
    let mut y = y0.to_vec();
    let mut y_new = vec![0.0; n];
    let mut y_stage = vec![0.0; n];
    let n_o = sys.n_output().min(n);
    // The interpolated prefix: the history's and the outputs'.
    let n_i = nd.max(n_o);
    let mut y_out = vec![0.0; n_o];
    let mut dense = vec![0.0; NCOEF * n_i];
    let mut stencil = Stencil::new(n_i);
    let (mut err5, mut err3) = (vec![0.0; n], vec![0.0; n]);

    let mut t = t0;
    let mut next_out = 1usize;
    eval_rhs(sys, &ctx, &hist, &mut stats, t, t, &y, &mut k[..n]);
    stencil.restart(t, &y, &k[..n]);
    let mut h = initial_step(sys, &ctx, &hist, &mut stats, t, &y, &k[..n], &mut y_stage, &mut y_new, opts, h_cap);
    let mut bp_idx = 0usize;
    let mut last_rejected = false;

    while t < t_end - tiny(t_end) {
        while bp_idx < bps.len() && bps[bp_idx] <= t + tiny(t) {
            bp_idx += 1;
        }
        let (stop, stop_is_bp) = if bp_idx < bps.len() { (bps[bp_idx], true) } else { (t_end, false) };
        let h_prop = h;
        let mut h_try = h.min(h_cap);
        let mut lands = false;
        // Land on `stop` if the step would reach it or leave only a sliver (a sliver below
        // rounding level may make the step exceed h_cap by a few ulps, which is harmless).
        let gap = stop - (t + h_try);
        if gap <= tiny(stop) || (gap < 0.01 * h_try && stop - t <= h_cap) {
            h_try = stop - t;
            lands = true;
        }
        let t_new = if lands { stop } else { t + h_try };

        // Stages 1..=11.
        for s in 1..STAGES {
            combine(&y, &k, &A[s][..s], h_try, n, &mut y_stage);
            let ts = if C[s] == 1.0 { t_new } else { t + C[s] * h_try };
            eval_rhs(sys, &ctx, &hist, &mut stats, t, ts, &y_stage, &mut k[s * n..(s + 1) * n]);
        }
        combine(&y, &k, &A[12][..STAGES], h_try, n, &mut y_new);

        // Error estimate (combined 5th/3rd-order norm of dop853.f).
        err5.fill(0.0);
        lincomb(&mut err5, &k, n, &E5, 1.0, 0..n);
        err3.fill(0.0);
        lincomb(&mut err3, &k, n, &E3, 1.0, 0..n);
        let (s5, s3) = error_sums(&err5, &err3, &y, &y_new, opts.rtol, opts.atol);
        let mut deno = s5 + 0.01 * s3;
        if deno <= 0.0 {
            deno = 1.0;
        }
        let mut err = h_try * s5 * (1.0 / (n.max(1) as f64 * deno)).sqrt();
        if !err.is_finite() || !all_finite(&y_new) {
            err = f64::INFINITY;
        }
        // Tentatively accepted: FSAL evaluation and, when a dense output is needed, its polynomial:
        // the Hermite interpolant of the last four step points, or DOP853's own (three more
        // stages). A non-finite value there rejects the step as well.
        let mut out_here = false;
        let mut nodes = None;
        if err <= 1.0 {
            eval_rhs(sys, &ctx, &hist, &mut stats, t, t_new, &y_new, &mut k[12 * n..13 * n]);
            out_here = next_out <= n_out && {
                let t_k = t0 + next_out as f64 * dt_out;
                t_k <= t_new || (t_new == t_end && t_k <= t_end + 1e-9 * dt_out)
            };
            let mut last = 13;
            if nd > 0 || out_here {
                let len = if out_here { n_i } else { nd };
                nodes = stencil.interpolate(h_try, &y_new, &k[12 * n..13 * n], len, (opts.rtol, opts.atol), &mut dense);
                if nodes.is_none() {
                    for s in 13..STAGES_DENSE {
                        combine(&y, &k, &A[s][..s], h_try, n, &mut y_stage);
                        let ts = t + C[s] * h_try;
                        eval_rhs(sys, &ctx, &hist, &mut stats, t, ts, &y_stage, &mut k[s * n..(s + 1) * n]);
                    }
                    last = STAGES_DENSE;
                    dense_coefficients(&y, &y_new, &k, h_try, n, 0..len, &mut dense);
                    nodes = Some(DOP853_NODES);
                }
            }
            if !all_finite(&k[12 * n..last * n]) {
                err = f64::INFINITY;
            }
        }
        let fac11 = err.powf(0.125);

        if err > 1.0 {
            stats.rejected += 1;
            last_rejected = true;
            h = h_try / (1.0 / FAC_MIN).min(fac11 / SAFE);
            if h < h_min(t) {
                return Err(SolveError::StepSizeTooSmall { t, h, stats });
            }
            continue;
        }

        // Accepted.
        stats.steps += 1;
        let fac = (fac11 / SAFE).clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
        let mut h_next = h_try / fac;
        if last_rejected {
            h_next = h_next.min(h_try);
        } else if lands && h_try < h_prop {
            h_next = h_next.max(h_prop);
        }
        last_rejected = false;
        h = h_next;

        if let Some(z) = &nodes {
            let len = if out_here { n_i } else { nd };
            if nd > 0 {
                let slot = hist.push(t, h_try, z);
                for (r, row) in slot.chunks_exact_mut(nd).enumerate() {
                    row.copy_from_slice(&dense[r * len..r * len + nd]);
                }
            }
            while out_here && next_out <= n_out {
                let t_k = t0 + next_out as f64 * dt_out;
                let t_k = if next_out == n_out && t_new == t_end { t_k.min(t_end) } else { t_k };
                if t_k > t_new {
                    break;
                }
                let out: &[f64] = if t_k == t_new {
                    &y_new[..n_o]
                } else {
                    newton(&dense, len, z, (t_k - t) / h_try, &mut [(0, &mut y_out[..])]);
                    &y_out
                };
                next_out += 1;
                if on_output(t_k, out).is_break() {
                    stats.max_history_len = hist.max_len();
                    return Ok(stats);
                }
            }
        }
        hist.prune(t_new - tau_max);

        t = t_new;
        std::mem::swap(&mut y, &mut y_new);
        if lands && stop_is_bp {
            // Restart: the derivative may jump at a breakpoint, so FSAL does not apply.
            stats.breakpoints += 1;
            eval_rhs(sys, &ctx, &hist, &mut stats, t, t, &y, &mut k[..n]);
            stencil.restart(t, &y, &k[..n]);
        } else {
            k.copy_within(12 * n..13 * n, 0);
            stencil.push(t, &y, &k[..n]);
        }
    }
    stats.max_history_len = hist.max_len();
    Ok(stats)
}

/// out ← y + h Σ_j a_j k_j (zero coefficients skipped).
#[inline]
fn combine(y: &[f64], k: &[f64], a: &[f64], h: f64, n: usize, out: &mut [f64]) {
    out.copy_from_slice(y);
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
    /// dop853.f's error sums Σ (e5_i/sk_i)² and Σ (e3_i/sk_i)², sk_i = atol + rtol·max(|y_i|, |y_new_i|),
    /// in four interleaved partial sums (which the compiler may keep in vector lanes).
    fn error_sums(err5: &[f64], err3: &[f64], y: &[f64], y_new: &[f64], rtol: f64, atol: f64) -> (f64, f64) {
        let n = err5.len();
        let (err3, y, y_new) = (&err3[..n], &y[..n], &y_new[..n]);
        let (mut s5, mut s3) = ([0.0; 4], [0.0; 4]);
        for i in 0..n {
            let sk = 1.0 / (atol + rtol * y[i].abs().max(y_new[i].abs()));
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
