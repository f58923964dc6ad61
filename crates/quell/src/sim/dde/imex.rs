//! The implicit–explicit steps: ARK4(3)6L[2]SA ([`super::ark`]) with the system's implicit block
//! ([`DelaySystem::implicit`]) taken by the ESDIRK part and every other component by the explicit
//! part, and the switch between it and DOP853.
//!
//! Stage i's value is z_i = y_n + h Σ_{j<i} a^E_ij f(z_j) in the explicit components; in the implicit
//! block it solves z_I = y_n,I + h Σ_{j<i} a^I_ij f_I(z_j) + hγ f_I(z_i), a linear system because the
//! block's rate is linear in itself given the other components ([`DelaySystem::solve_implicit`]).
//! Each stage reads the delayed history like a DOP853 stage (every c_i ≤ 1 and h ≤ min τ), so the
//! method of steps is unchanged. The dense output is the cubic Hermite interpolant of the step's
//! end points: an error O(h⁴) against the method's local O(h⁵), which keeps the global order 4 of
//! the method of steps (Bellen & Zennaro, Thm. 4.1.7, with interpolation order 3).

use super::ark::{self, A_E, A_I, B, E, GAMMA};
use super::history::Nodes;
use super::{all_finite, combine, error_sums, eval_rhs, lincomb, DelaySystem, Method, Step, Steps};

/// The Newton nodes of the cubic Hermite interpolant p(θ) = c_0 + θ(c_1 + θ(c_2 + (θ − 1) c_3))
/// (the remaining coefficients are zero).
const HERMITE3_NODES: Nodes = [0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0];

/// DOP853 is stable on the negative real axis for h|λ| ≤ 6.1 (the bound of `dop853.f`'s own
/// stiffness test). Its steps count as stability-limited when h times the implicit block's rate
/// bound exceeds this: the bound may exceed λ_max by up to √q, so a step accuracy-limited at
/// h λ_max ≈ 1 does not qualify.
const STIFF_H_RATE: f64 = 4.0;
/// The implicit method hands back to DOP853 when its steps stay below this h · rate. A DOP853 step
/// costs 12–13 evaluations of the right-hand side against the implicit method's 6 (and its block
/// solves), so DOP853 pays when its stable step, [`STIFF_H_RATE`] / rate, is at least twice the
/// implicit method's accurate one.
const NONSTIFF_H_RATE: f64 = STIFF_H_RATE / 2.0;
/// Consecutive accepted steps beyond a threshold before switching (`dop853.f` counts 15).
const SWITCH_AFTER: usize = 15;

impl<S: DelaySystem> Steps<'_, S> {
    /// The exponent of the step-size controller: 1/(p̂ + 1) with p̂ the embedded order (DOP853's
    /// error is O(h⁸) in `dop853.f`'s combined norm, ARK4(3)'s O(h⁴)).
    pub(super) fn exponent(&self) -> f64 {
        if self.stiff {
            0.25
        } else {
            0.125
        }
    }

    /// An ARK4(3)6L[2]SA attempt: stages 2…6, y_new, the embedded error estimate and, for a step
    /// within tolerance, f(t_new, y_new) and the dense output. Like [`Steps::attempt`]: `None` when
    /// rejected (error above 1, a failed implicit solve, or a non-finite value), otherwise the
    /// number of components the dense output covers.
    pub(super) fn attempt_implicit(&mut self, step: &Step) -> Option<usize> {
        let (n, t, h) = (self.n, self.t, step.h);
        let imp = self.implicit.clone();
        for s in 1..ark::STAGES {
            combine(&self.y, &self.k, &A_E[s][..s], h, n, &mut self.y_stage);
            let z_i = &mut self.y_stage[imp.clone()];
            z_i.copy_from_slice(&self.y[imp.clone()]);
            lincomb(z_i, &self.k, n, &A_I[s][..s], h, imp.clone());
            if !self.sys.solve_implicit(h * GAMMA, &mut self.y_stage) {
                self.err = f64::INFINITY;
                return None;
            }
            let ts = if s == ark::STAGES - 1 { step.t_new } else { t + ark::C[s] * h };
            let k_s = &mut self.k[s * n..(s + 1) * n];
            eval_rhs(self.sys, &self.ctx, &self.hist, &mut self.stats, t, ts, &self.y_stage, k_s);
        }
        combine(&self.y, &self.k, &B, h, n, &mut self.y_new);
        self.err5.fill(0.0);
        lincomb(&mut self.err5, &self.k, n, &E, h, 0..n);
        let (s2, _) = error_sums(&self.err5, &self.err5, &self.y, &self.y_new, self.opts.rtol, self.opts.atol);
        self.err = (s2 / n.max(1) as f64).sqrt();
        if !self.err.is_finite() || !all_finite(&self.y_new) {
            self.err = f64::INFINITY;
        }
        if self.err > 1.0 {
            return None;
        }
        let (y_new, k_new) = (&self.y_new, &mut self.k[12 * n..13 * n]);
        eval_rhs(self.sys, &self.ctx, &self.hist, &mut self.stats, t, step.t_new, y_new, k_new);
        // The implicit block's rate at t_new is taken from the last stage, whose implicit components
        // are y_new's (the ESDIRK part is stiffly accurate) and were solved against that stage's
        // explicit components. f_I(y_new) would read y_new's explicit components instead, which differ
        // by O(h⁴): negligible in a mild block, but multiplied by the block's rate (up to 1e9 h⁻¹)
        // in a stiff one, where it would spoil the next step's first stage and the dense output.
        self.k.copy_within(5 * n + imp.start..5 * n + imp.end, 12 * n + imp.start);
        let outputs = self.schedule.due(step.t_new, self.t_end).is_some();
        let len = if outputs { self.n_i } else { self.nd };
        self.hermite3(h, len);
        if !all_finite(&self.k[12 * n..13 * n]) {
            self.err = f64::INFINITY;
        }
        (self.err <= 1.0).then_some(len)
    }

    /// The cubic Hermite interpolant through (y, h f(t, y)) and (y_new, h f(t_new, y_new)) of the
    /// first `len` components, coefficient-major into the dense output.
    fn hermite3(&mut self, h: f64, len: usize) {
        let n = self.n;
        let (f0, f1) = (&self.k[..len], &self.k[12 * n..12 * n + len]);
        let (c, rest) = self.dense.split_at_mut(4 * len);
        rest[..4 * len].fill(0.0);
        let (c0, c) = c.split_at_mut(len);
        let (c1, c) = c.split_at_mut(len);
        let (c2, c3) = c.split_at_mut(len);
        for i in 0..len {
            let dy = self.y_new[i] - self.y[i];
            c0[i] = self.y[i];
            c1[i] = h * f0[i];
            c2[i] = dy - h * f0[i];
            c3[i] = h * (f0[i] + f1[i]) - 2.0 * dy;
        }
        self.nodes = HERMITE3_NODES;
    }

    /// After an accepted step under [`Method::Auto`]: counts the steps for which the other method
    /// would serve better (DOP853 limited by the implicit block's stability, or the implicit method's
    /// steps far inside DOP853's stability bound) and switches after [`SWITCH_AFTER`] in a row.
    pub(super) fn watch_stiffness(&mut self, step: &Step) {
        if self.implicit.is_empty() || self.opts.method != Method::Auto {
            return;
        }
        let h_rate = step.h * self.sys.implicit_rate(&self.y_new);
        let argues = if self.stiff { h_rate < NONSTIFF_H_RATE } else { h_rate > STIFF_H_RATE };
        self.stiff_run = if argues { self.stiff_run + 1 } else { 0 };
        if self.stiff_run >= SWITCH_AFTER {
            self.stiff = !self.stiff;
            self.stiff_run = 0;
            self.stats.switches += 1;
            // Back on DOP853, the Hermite stencil starts from the next step point: its earlier points
            // carry the implicit method's (lower-order) errors.
            self.fresh_stencil = !self.stiff;
        }
    }
}
