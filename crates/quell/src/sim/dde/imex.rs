//! The implicit–explicit steps: ARK4(3)6L\[2\]SA ([`super::ark`]) with the system's implicit block
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
/// A DOP853 step at least this share of the cap on the adaptive law's rate (`law_h`) was held by it.
const LAW_HELD: f64 = 0.9;
/// The implicit method hands back to DOP853 when its steps fall below this h · rate: DOP853 could
/// then take steps eight times longer before meeting its stability bound, which outweighs its
/// higher cost per step (12–13 right-hand sides against 6 and the block solves).
const NONSTIFF_H_RATE: f64 = STIFF_H_RATE / 8.0;
/// DOP853's steps count as off its stability bound when h times the rate bound is below this: six
/// in a row end a stability-limited stretch ([`Switching`]).
const OFF_H_RATE: f64 = STIFF_H_RATE / 2.0;
/// A stretch is stability-limited when at least this share of its steps exceed [`STIFF_H_RATE`]. At
/// the bound, the step-size controller oscillates: h·rate ran from 1 to 13 on a magnetic bearing
/// whose DOP853 rejected 37 % of its attempts, half of its steps below [`STIFF_H_RATE`]; counting
/// only steps above it, six in a row below reset the count and the run never switched, leaving u_f
/// off by 1 % of its peak at rtol = 1e-8 (the implicit method: 2e-7).
const LIMITED_SHARE: f64 = 1.0 / 3.0;
/// The share of rejected attempts above which DOP853 is taken to thrash at its stability bound
/// (accuracy-limited runs reject 5–15 %): its error estimate then misses the stiff block's errors
/// (a loop at rtol 1e-6 whose u_f peaked 8× too high with 31 % rejected was right on the implicit
/// method). A stability-limited stretch that thrashes over [`THRASH_AFTER`] steps switches at once,
/// and the implicit method is then kept while the loop stays stiff, whatever it costs.
pub(crate) const THRASHING: f64 = 0.25;
/// Steps of a stability-limited stretch over which its rejected share is judged ([`THRASHING`]).
const THRASH_AFTER: usize = 100;
/// Steps of a stability-limited stretch before the first switch. `dop853.f` warns after 15;
/// the switch waits longer, because it pays only on a long stiff stretch: a loop that sits at
/// DOP853's stability bound for a while at a tight tolerance (`examples/three-channel.toml`, up to
/// ~1000 steps) costs about as much on the 4th-order implicit method, and stays on DOP853 with its
/// outputs unchanged, while where the loop is really stiff (DOP853 needing 1e5–1e6 steps) a thousand
/// steps are a small price.
const SWITCH_AFTER: usize = 1000;
/// Implicit steps per trial: after each, the implicit method's progress per right-hand side is
/// compared with DOP853's when it switched. The first trial starts one largest delay after the
/// switch: until then the stages read delayed values from DOP853's steps, and where those carry the
/// errors of a block at DOP853's bound they hold the implicit method to DOP853's step (on the
/// supply vessel of `tests/data`, trials judged earlier failed and the run switched back and forth).
const TRIAL: usize = 30;

/// Beyond this h · rate, the implicit block's slopes in the dense output come from its values at the
/// last step points instead of f_I: there f_I(y) = c − M y multiplies the values' rounding and
/// solve errors by the rate (1e9 h⁻¹ turns an error of 1e-13 into a slope off by 1e-4), whereas the
/// block itself, damped onto its slow solution by the L-stable method, is as smooth as the rest.
const SLOPES_FROM_VALUES: f64 = 100.0;

/// The implicit block's values at the two step points before the current one, for the slopes of its
/// dense output in the very stiff case. Kept across breakpoints: there the derivatives of the
/// components fed by delayed values jump, but a stiff block damped onto its slow solution (the
/// adaptive law's η̂ follows Ω⁻¹Y, both filtered) is smooth to higher order, and the alternative,
/// f_I, is the worse slope at that stiffness.
pub(super) struct Earlier {
    t: [f64; 2],
    /// Two slots of the block's length, oldest first.
    y: Vec<f64>,
    count: usize,
}

impl Earlier {
    pub(super) fn new(len: usize) -> Self {
        Earlier { t: [0.0; 2], y: vec![0.0; 2 * len], count: 0 }
    }

    pub(super) fn clear(&mut self) {
        self.count = 0;
    }

    /// Appends the point (t, y), dropping the oldest beyond two.
    pub(super) fn push(&mut self, t: f64, y: &[f64]) {
        let len = y.len();
        if self.count == 2 {
            self.t[0] = self.t[1];
            self.y.copy_within(len.., 0);
            self.count = 1;
        }
        self.t[self.count] = t;
        self.y[self.count * len..(self.count + 1) * len].copy_from_slice(y);
        self.count += 1;
    }
}

/// Weights w0, w1 such that h p'(t) at θ = 0 and θ = 1 is Σ_j w_j y_j, p the polynomial through the
/// values y_j at the nodes θ_j (up to four, distinct): w_j = h L_j'(θ), with
/// L_j'(θ) = Σ_{m≠j} 1/(θ_j − θ_m) Π_{l≠j,m} (θ − θ_l)/(θ_j − θ_l).
fn slope_weights(nodes: &[f64]) -> ([f64; 4], [f64; 4]) {
    let (mut w0, mut w1) = ([0.0; 4], [0.0; 4]);
    for (j, &tj) in nodes.iter().enumerate() {
        for (m, &tm) in nodes.iter().enumerate().filter(|&(m, _)| m != j) {
            let (mut p0, mut p1) = (1.0 / (tj - tm), 1.0 / (tj - tm));
            for (_, &tl) in nodes.iter().enumerate().filter(|&(l, _)| l != j && l != m) {
                p0 *= (0.0 - tl) / (tj - tl);
                p1 *= (1.0 - tl) / (tj - tl);
            }
            w0[j] += p0;
            w1[j] += p1;
        }
    }
    (w0, w1)
}

/// The switching state of [`Method::Auto`]: the implicit method is tried when DOP853 has been
/// stability-limited for `patience` steps, and kept while it advances faster per evaluation of the
/// right-hand side than DOP853 did (a mildly stiff loop may be cheaper on DOP853 at its stability
/// bound than on a 4th-order method at a tight tolerance); after a failed trial, DOP853 must be
/// limited four times as long before the next one.
#[derive(Debug, Clone, Copy)]
pub(super) struct Switching {
    /// Steps counted towards the next decision: on DOP853, the steps of the present stretch.
    run: usize,
    /// Of DOP853's stretch, the steps beyond [`STIFF_H_RATE`].
    limited: usize,
    /// DOP853 steps in a row below [`OFF_H_RATE`].
    off: usize,
    /// Rejected attempts when the present stretch began.
    rejected_since: usize,
    /// DOP853 thrashed before the switch ([`THRASHING`]): the implicit method is not measured
    /// against its cost.
    thrashed: bool,
    /// Time and right-hand-side evaluations at the start of the measured window.
    since: (f64, usize),
    /// DOP853's time per evaluation over its last stability-limited steps.
    explicit_rate: f64,
    patience: usize,
    /// Until this time (one largest delay after a switch) the implicit method reads delayed values
    /// DOP853 computed, and is not measured.
    settle: f64,
    /// The loop is expected to reach DOP853's bound ([`super::Options::expect_stiff`]).
    expected: bool,
}

impl Switching {
    pub(super) fn new(expected: bool) -> Self {
        Switching {
            run: 0,
            limited: 0,
            off: 0,
            rejected_since: 0,
            thrashed: false,
            since: (0.0, 0),
            explicit_rate: 0.0,
            patience: SWITCH_AFTER,
            settle: 0.0,
            expected,
        }
    }
}

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

    /// An ARK4(3)6L\[2\]SA attempt: stages 2…6, y_new, the embedded error estimate and, for a step
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
            let ts = if s == ark::STAGES - 1 { step.t_new } else { t + ark::C[s] * h };
            if !self.sys.solve_implicit(ts, h * GAMMA, &mut self.y_stage) {
                self.err = f64::INFINITY;
                return None;
            }
            let k_s = &mut self.k[s * n..(s + 1) * n];
            eval_rhs(self.sys, &self.ctx, &self.hist, &mut self.stats, t, ts, &self.y_stage, k_s);
        }
        combine(&self.y, &self.k, &B, h, n, &mut self.y_new);
        self.err5.fill(0.0);
        lincomb(&mut self.err5, &self.k, n, &E, h, 0..n);
        if !self.sys.filter_implicit_error(h * GAMMA, &self.y_new, &mut self.err5) {
            self.err = f64::INFINITY;
            return None;
        }
        let (s2, _) = error_sums(&self.err5, &self.err5, &self.y, &self.y_new, self.opts.rtol, &self.atol);
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
    /// first `len` components, coefficient-major into the dense output. Beyond [`SLOPES_FROM_VALUES`],
    /// the implicit block's slopes are those of the polynomial through its values at the last (up to)
    /// four step points ([`Earlier`]): O(h³) accurate, so the interpolant stays O(h⁴).
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
        let imp = self.implicit.start..self.implicit.end.min(len);
        if imp.is_empty() || h * self.sys.implicit_rate(&self.y_new) <= SLOPES_FROM_VALUES {
            return;
        }
        let (e, b) = (&self.earlier, imp.len());
        let mut nodes = [0.0; 4];
        let k = e.count;
        for (node, &t) in nodes.iter_mut().zip(&e.t[..k]) {
            *node = (t - self.t) / h;
        }
        nodes[k] = 0.0;
        nodes[k + 1] = 1.0;
        let (w0, w1) = slope_weights(&nodes[..k + 2]);
        for (r, i) in imp.enumerate() {
            let value = |j: usize| {
                if j < k {
                    e.y[j * b + r]
                } else if j == k {
                    self.y[i]
                } else {
                    self.y_new[i]
                }
            };
            let (s0, s1) = (0..k + 2).fold((0.0, 0.0), |(a, c), j| (a + w0[j] * value(j), c + w1[j] * value(j)));
            let dy = self.y_new[i] - self.y[i];
            c1[i] = s0;
            c2[i] = dy - s0;
            c3[i] = s0 + s1 - 2.0 * dy;
        }
    }

    /// The longest DOP853 step on the adaptive law's rate λ at the new step point, `bound` ≥ λ its
    /// Gershgorin bound: [`super::DOP853_ACCURATE_H_RATE`]/λ, where the next step (the proposal
    /// within the cap on ρ) would pass it (λ from [`DelaySystem::implicit_rate_below`]); ∞ where
    /// even the bound keeps it within. The cap on ρ keeps every other mode there; this one keeps
    /// the law's. Between h·λ = 4.4 and DOP853's stability bound 6.1 its R hardly damps (0.06 at 5
    /// against e⁻⁵ = 0.007, 0.5 at 6): a two-mass spring at 1.83ρ averaged rose to h·λ = 5.9 in its
    /// transient and was 1.2e-3 of u_f's peak off at rtol 1e-7, with one rejected attempt in 760
    /// steps (helper tryout, 2026-12-06).
    fn law_h(&mut self, bound: f64) -> f64 {
        if self.h.min(self.on_rho(super::DOP853_ACCURATE_H_RATE)) * bound <= super::DOP853_ACCURATE_H_RATE {
            return f64::INFINITY;
        }
        let rate = self.sys.implicit_rate_below(&self.y_new);
        if rate > 0.0 {
            super::DOP853_ACCURATE_H_RATE / rate
        } else {
            f64::INFINITY
        }
    }

    /// After an accepted step under [`Method::Auto`]: on DOP853, counts the steps of a stretch that no
    /// six in a row below [`OFF_H_RATE`] interrupt, and switches to the implicit method after
    /// `patience` of them when [`LIMITED_SHARE`] of them exceed [`STIFF_H_RATE`], or after
    /// [`THRASH_AFTER`] when it thrashes ([`THRASHING`]); on the implicit method, one largest
    /// delay after the switch and then after each [`TRIAL`] steps, switches back when it advanced
    /// more slowly per evaluation than a DOP853 that did not thrash had, or when its steps sit far
    /// inside DOP853's stability bound ([`Switching`]).
    pub(super) fn watch_stiffness(&mut self, step: &Step) {
        if self.implicit.is_empty() || self.opts.method != Method::Auto {
            return;
        }
        let bound = self.sys.implicit_rate(&self.y_new);
        let h_rate = step.h * bound;
        // A step the cap on the law's rate held counts as stability-limited, as one beyond
        // STIFF_H_RATE does: held there, DOP853 crawls on a stiff law until the switch.
        let held = step.h >= LAW_HELD * self.h_law;
        if !self.stiff {
            self.h_law = self.law_h(bound);
        }
        let now = (step.t_new, self.stats.rhs_evals);
        let sw = &mut self.switching;
        let rate = |since: (f64, usize)| (now.0 - since.0) / (now.1 - since.1).max(1) as f64;
        if !self.stiff {
            // As `dop853.f` counts: six steps in a row off the bound end a stretch.
            sw.off = if h_rate > OFF_H_RATE { 0 } else { sw.off + 1 };
            if sw.off >= 6 {
                (sw.run, sw.limited) = (0, 0);
                return;
            }
            sw.run += 1;
            sw.limited += usize::from(h_rate > STIFF_H_RATE || held);
            if sw.run == 1 {
                (sw.since, sw.rejected_since) = (now, self.stats.rejected);
            }
            let expected = sw.expected && h_rate > STIFF_H_RATE;
            if (sw.limited as f64) < LIMITED_SHARE * sw.run as f64 && !expected {
                return;
            }
            let rejected = (self.stats.rejected - sw.rejected_since) as f64;
            sw.thrashed = sw.run >= THRASH_AFTER && rejected > THRASHING * (rejected + sw.run as f64);
            if sw.run < sw.patience && !sw.thrashed && !expected {
                return;
            }
            sw.explicit_rate = rate(sw.since);
        } else {
            // An expected stiff loop stays: its accuracy-limited implicit steps may sit well inside
            // DOP853's bound (a magnetic bearing at 3.2ρ switched 47 times and kept DOP853's errors).
            if sw.expected || step.t_new < sw.settle {
                sw.since = now;
                return;
            }
            sw.run += 1;
            if sw.run < TRIAL {
                return;
            }
            let slower = !sw.thrashed && rate(sw.since) < sw.explicit_rate;
            if !slower && h_rate >= NONSTIFF_H_RATE {
                *sw = Switching { run: 0, since: now, ..*sw };
                return;
            }
            sw.patience = if slower { 4 * sw.patience } else { SWITCH_AFTER };
        }
        if sw.thrashed && !self.stiff {
            self.stats.thrashed.get_or_insert((sw.since.0, step.t_new));
        }
        (sw.run, sw.limited) = (0, 0);
        sw.since = now;
        sw.settle = step.t_new + self.tau_max;
        self.stiff = !self.stiff;
        self.stats.switches += 1;
        // Back on DOP853 the law's rate is measured afresh (the cap set before the switch is stale).
        self.h_law = f64::INFINITY;
        // Back on DOP853, the Hermite stencil starts from the next step point: its earlier points
        // carry the implicit method's (lower-order) errors.
        self.fresh_stencil = !self.stiff;
    }
}
