//! When a run counts as diverged: one bound and the same signals for both loops (and for sweeps).

use serde::{Deserialize, Serialize};

use super::result::Outcome;
use crate::plant::Plant;

/// The default divergence bound: a watched signal above this magnitude ends the run.
pub const DIVERGENCE_BOUND: f64 = 1e9;

/// The signals divergence is judged on, at one instant: the plant state x, the observer state x̂,
/// the regressor ξ̂ and the adaptive parameters η̂ = [η̂_1; …; η̂_m] (each of length q = ξ̂'s).
#[derive(Debug, Clone, Copy)]
pub struct Watched<'a> {
    pub x: &'a [f64],
    pub x_hat: &'a [f64],
    pub xi_hat: &'a [f64],
    pub eta: &'a [f64],
}

impl Watched<'_> {
    /// The signals in the order x, x̂, ξ̂, η̂ (the order of [`Peaks`]).
    fn signals(&self) -> [&[f64]; 4] {
        [self.x, self.x_hat, self.xi_hat, self.eta]
    }

    /// The first watched value (in the order x, x̂, ξ̂, η̂: the plant first) that is non-finite or
    /// above `bound` in magnitude, as the outcome of a run diverged at time `t`.
    pub fn diverged(&self, t: f64, bound: f64) -> Option<Outcome> {
        self.beyond(t, &Peaks([bound; 4]))
    }

    /// [`Watched::diverged`] with a bound per signal: the first value that is non-finite or above
    /// its signal's bound in magnitude, named by its column of signals.csv (1-based, [`WATCHED`]):
    /// `x3 (plant state)`, `xhat7 (observer state)`, `xihat2 (regressor)` (ξ̂ has no column; named
    /// as x̂ is), `eta1_3 (adaptive parameters)`. A scenario's run adds the states' names
    /// (the state's name beside its column name).
    pub fn beyond(&self, t: f64, bounds: &Peaks) -> Option<Outcome> {
        let q = self.xi_hat.len();
        let name = |signal: usize, j: usize| {
            let (column, what) = WATCHED[signal];
            match signal {
                3 => format!("{column}{}_{} ({what})", j / q + 1, j % q + 1),
                _ => format!("{column}{} ({what})", j + 1),
            }
        };
        self.signals().iter().zip(bounds.0).enumerate().find_map(|(signal, (values, bound))| {
            values.iter().position(|&v| beyond(v, bound)).map(|j| Outcome::Diverged {
                t,
                signal: name(signal, j),
                value: values[j],
            })
        })
    }
}

/// The watched signals x, x̂, ξ̂, η̂ (the order of [`Peaks`]): the stem of their entries' names, as
/// signals.csv names its columns (x1, xhat1, eta1_1), and what they are.
pub const WATCHED: [(&str, &str); 4] =
    [("x", "plant state"), ("xhat", "observer state"), ("xihat", "regressor"), ("eta", "adaptive parameters")];

/// A divergence's signal as [`Watched::beyond`] names it, with the state's name where it is an
/// entry of x or x̂ and `states` names it: "xhat6 (observer state dPv2)" (the run had said
/// "x_hat[6] (observer state)", read as 0-based beside the scenario's keys and not the name the
/// user gave). Any other signal as it is.
pub(crate) fn with_state_name(signal: &str, states: &[String]) -> String {
    let named = signal.split_once(" (").and_then(|(column, rest)| {
        let group = Peaks::group(signal).filter(|&g| g <= 1)?;
        let j: usize = column.strip_prefix(WATCHED[group].0)?.parse().ok()?;
        let name = states.get(j.checked_sub(1)?)?;
        Some(format!("{column} ({} {name})", rest.strip_suffix(')')?))
    });
    named.unwrap_or_else(|| signal.to_string())
}

/// The largest magnitude each watched signal reached, in the order x, x̂, ξ̂, η̂ (max over its
/// entries and the recorded samples); also used as one bound per signal ([`Watched::beyond`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Peaks(pub [f64; 4]);

impl Peaks {
    /// Raises each peak to the signal's largest magnitude now.
    pub fn record(&mut self, w: &Watched<'_>) {
        for (p, values) in self.0.iter_mut().zip(w.signals()) {
            *p = values.iter().fold(*p, |a, v| a.max(v.abs()));
        }
    }

    /// Bounds `factor` times each peak, as [`Watched::beyond`] takes them; +∞ for a signal whose
    /// peak is 0 (or not finite), which gives no scale.
    pub fn bounds(&self, factor: f64) -> Peaks {
        Peaks(self.0.map(|p| if p > 0.0 && p.is_finite() { factor * p } else { f64::INFINITY }))
    }

    /// The runaway rule's bounds of a run against a reference run of these peaks (a study's nominal
    /// run, the automatic design's verified one): `factor` times them, but ξ̂ at `xi_bound` (its
    /// divergence bound), and x̂ at least as x is.
    ///
    /// ξ̂ only at its divergence bound: the disturbance observer (20) reads a true plant's mismatch
    /// as disturbance, so ξ̂_ω of a converging run can pass 100× a reference run's whose observer
    /// was exact (an aircraft pitch loop with truth.A, B 10 % off: 28 of 50 draws stopped at its
    /// nominal delay, all of which converge, tails 1.7e-9 to 4e-5 against 2.5e-3). A ξ̂ that runs
    /// away drives u, so x̂ and η̂ follow it past theirs. x̂ estimates x in x's coordinates: a
    /// mismatch moves x̂ towards x, so it is bounded as x is (the same pitch loop's observer,
    /// nominally at 0.26 beside an x of 5.3e6 in an unobserved integrator, reached 27 in 11
    /// converging draws).
    pub(crate) fn runaway(&self, factor: f64, xi_bound: f64) -> Peaks {
        let mut peaks = self.bounds(factor);
        peaks.0[Peaks::index_of("xihat")] = xi_bound;
        let (x, x_hat) = (Peaks::index_of("x"), Peaks::index_of("xhat"));
        peaks.0[x_hat] = peaks.0[x_hat].max(peaks.0[x]);
        peaks
    }

    /// The watched signal nearest its bound in `bounds` (by its share of it), as "by then xhat
    /// (observer state) had reached 3.20e9 in magnitude, 3.2e-3 of its divergence bound": what a run a budget
    /// ended was doing, blowing up or not. `None` before any peak was recorded.
    pub fn nearest_bound(&self, bounds: &Peaks) -> Option<String> {
        let share = |k: usize| self.0[k] / bounds.0[k];
        let k = (0..4)
            .filter(|&k| share(k).is_finite() && self.0[k] > 0.0)
            .max_by(|&a, &b| share(a).total_cmp(&share(b)))?;
        Some(format!(
            "by then {} ({}) had reached {:.2e} in magnitude, {:.1e} of its divergence bound",
            WATCHED[k].0,
            WATCHED[k].1,
            self.0[k],
            share(k)
        ))
    }

    /// The index (0: x, 1: x̂, 2: ξ̂, 3: η̂) of the signal an [`Outcome::Diverged`] names ("xhat7
    /// (observer state)", or a stem of [`WATCHED`] alone); 0 for any other signal.
    pub fn index_of(signal: &str) -> usize {
        Peaks::group(signal).unwrap_or(0)
    }

    /// [`Peaks::index_of`]; `None` for a signal that is none of x, x̂, ξ̂, η̂ (a controller input).
    fn group(signal: &str) -> Option<usize> {
        let column = signal.split(' ').next().unwrap_or_default();
        let stem = column.trim_end_matches(|c: char| c.is_ascii_digit() || c == '_');
        WATCHED.iter().position(|&(s, _)| s == stem)
    }
}

/// The plant state's scale in its own coordinates, by which the divergence bound on x and x̂ is
/// multiplied: max(1, |x(0)|∞, |x̂(0)|∞, 1/σ_min(C)), σ_min(C) C's smallest nonzero singular value. An output
/// of size 1 needs a state of at least 1/σ_min(C), so the bound is one on the outputs' scale:
/// states in 1e9 times the outputs' units (C = 1e-9 I) are judged as states in those units are,
/// and a plant whose outputs read its states with gains of 1 or more (the paper's) keeps 1.
pub(crate) fn state_scale(plant: &Plant) -> f64 {
    // x̂ starts at xhat0, which a run may give beside an x0 left at 0 ([truth] x0 holding the
    // plant's own): 2e9 there had read as diverged at t = 0 (diff review, 2026-12-07).
    [1.0 / smallest_gain(&plant.C), plant.x0.amax(), plant.xhat0.amax()]
        .into_iter()
        .filter(|v| v.is_finite())
        .fold(1.0, f64::max)
}

/// σ_min(C): C's smallest singular value above 1e-12 of its largest (+∞ for C = 0).
pub(crate) fn smallest_gain(C: &nalgebra::DMatrix<f64>) -> f64 {
    let sv = C.singular_values();
    let largest = sv.max();
    sv.iter().copied().filter(|&s| s > largest * 1e-12).fold(f64::INFINITY, f64::min)
}

/// How far above its nominal size a regressor or parameter vector may go before it counts as
/// diverged, where that size raises its bound ([`regressor_scales`]).
pub(crate) const NOMINAL_MARGIN: f64 = 1e3;

/// The factors by which the divergence bound on ξ̂ and η̂ is multiplied, from their nominal sizes
/// in their own units: max(1, [`NOMINAL_MARGIN`]·s/[`DIVERGENCE_BOUND`]) with s the steady-state
/// regressor's bound [`Averaged::xi_peak`](crate::averaged::Averaged), and with s = max_i |η*_i|∞,
/// η*_i = Ω̄_i⁺ Ȳ_i what η̂_i settles to. A vector of nominal size up to 1e6 keeps the bound 1e9;
/// a larger one (the paper's form of ξ̂ carries the signals' units divided by the filters' ∏|p_j|:
/// a vessel's yaw disturbance of 2e7 N·m makes |ξ̂| ≈ 1.6e9) may grow a thousandfold before it
/// counts as diverged, not a billionfold (a blow-up of that vessel reached |ξ̂| = 1e18 within a
/// bound of 1e9 times its size). A size that is not finite counts as 0.
pub(crate) fn regressor_scales(avg: &crate::averaged::Averaged) -> (f64, f64) {
    let eta = avg.channels.iter().map(|c| c.eta_star().amax()).fold(0.0, f64::max);
    (nominal_factor(avg.xi_peak), nominal_factor(eta))
}

/// max(1, [`NOMINAL_MARGIN`]·size/[`DIVERGENCE_BOUND`]); 1 for a size that is not finite. The same
/// rule raises the bound on x and x̂ by their nominal size [`Averaged::x_peak`](crate::averaged::Averaged)
/// (a reference of 7e12 J is not a divergence of a heat store's state).
pub(crate) fn nominal_factor(size: f64) -> f64 {
    if size.is_finite() {
        (NOMINAL_MARGIN * size / DIVERGENCE_BOUND).max(1.0)
    } else {
        1.0
    }
}

/// Whether v is outside [−bound, bound] or not finite (so NaN is always beyond).
pub(crate) fn beyond(v: f64, bound: f64) -> bool {
    !(v.is_finite() && v.abs() <= bound)
}

/// A divergence bound: > 0, not NaN (+∞ watches only for non-finite values).
pub(crate) fn check_bound(bound: f64) -> Result<(), crate::settings::KeyError> {
    if bound > 0.0 {
        Ok(())
    } else {
        Err(crate::settings::KeyError::new(
            "divergence_bound",
            format!(
                "expected a bound > 0 (or +inf for none; default {DIVERGENCE_BOUND:e}), found {}",
                crate::settings::fmt_short(bound)
            ),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{dmatrix, dvector, DMatrix};

    /// The signal with the largest share of its bound is named; a signal without a bound (∞) or
    /// without a peak is not; nothing recorded names nothing.
    #[test]
    fn the_signal_nearest_its_bound_is_named_with_its_share() {
        let bounds = Peaks([1e9, 1e9, 1e4, f64::INFINITY]);
        let text = Peaks([2e6, 3e6, 50.0, 1e20]).nearest_bound(&bounds).unwrap();
        assert_eq!(text, "by then xihat (regressor) had reached 5.00e1 in magnitude, 5.0e-3 of its divergence bound");
        assert_eq!(Peaks([0.0; 4]).nearest_bound(&bounds), None);
        assert!(Peaks([1.0, f64::NAN, 0.0, 0.0])
            .nearest_bound(&bounds)
            .unwrap()
            .starts_with("by then x (plant state)"));
    }

    #[test]
    fn the_state_scale_is_the_state_a_unit_output_needs() {
        let plant = |c: f64, x0: f64| {
            let C = dmatrix![c, 0.0, 0.0; 0.0, 2.0 * c, 0.0];
            let (A, B, D, Q) = (DMatrix::zeros(3, 3), DMatrix::zeros(3, 2), DMatrix::zeros(3, 1), DMatrix::zeros(2, 1));
            Plant::new(A, B, C, D, Q, vec![0.0, 0.0], Some(dvector![x0, 0.0, 0.0])).unwrap()
        };
        // σ_min(C) = c.
        assert!((state_scale(&plant(1e-9, 0.0)) / 1e9 - 1.0).abs() < 1e-12);
        assert!((state_scale(&plant(0.25, 0.0)) - 4.0).abs() < 1e-12);
        assert_eq!(state_scale(&plant(1e3, 0.0)), 1.0, "never below 1");
        assert_eq!(state_scale(&plant(1.0, -7.0)), 7.0, "nor below |x(0)|");
    }

    #[test]
    fn peaks_record_the_largest_magnitudes_and_bound_each_signal() {
        let w = Watched { x: &[1.0, -3.0], x_hat: &[0.5], xi_hat: &[-0.25, 0.125], eta: &[2.0, -4.0, 1.0, 0.0] };
        let mut p = Peaks::default();
        p.record(&w);
        assert_eq!(p, Peaks([3.0, 0.5, 0.25, 4.0]));
        p.record(&Watched { x: &[-5.0, 0.0], ..w });
        assert_eq!(p, Peaks([5.0, 0.5, 0.25, 4.0]), "a later, larger value raises its peak only");
        // Per-signal bounds: ξ̂[2] = 0.125 is within 0.2, ξ̂[1] = −0.25 is not.
        let bounds = Peaks([10.0, 10.0, 0.2, 10.0]);
        assert_eq!(
            w.beyond(7.0, &bounds),
            Some(Outcome::Diverged { t: 7.0, signal: "xihat1 (regressor)".into(), value: -0.25 })
        );
        assert_eq!(w.beyond(7.0, &p.bounds(1.0)), None, "every value is within its own peak");
        assert_eq!(Peaks([2.0, 0.0, 1.0, f64::NAN]).bounds(10.0), Peaks([20.0, f64::INFINITY, 10.0, f64::INFINITY]));
        for (i, signal) in
            ["x1 (plant state)", "xhat2 (observer state)", "xihat3 (regressor)", "eta2_1 (adaptive parameters)"]
                .iter()
                .enumerate()
        {
            assert_eq!(Peaks::index_of(signal), i);
        }
        assert_eq!(Peaks::index_of("y2 (controller input)"), 0);
        assert_eq!(w.diverged(7.0, 3.5), w.beyond(7.0, &Peaks([3.5; 4])));
        assert!(
            matches!(w.diverged(7.0, 3.5), Some(Outcome::Diverged { ref signal, .. }) if signal == "eta1_2 (adaptive parameters)")
        );
    }

    /// Each watched signal is named by its column of signals.csv, counted from 1, and an entry of
    /// x or x̂ by the state's name too where the scenario gives one.
    #[test]
    fn a_diverged_signal_is_named_by_its_column_and_state() {
        let w = Watched { x: &[0.0, 0.0], x_hat: &[0.0, 5.0], xi_hat: &[0.0; 3], eta: &[0.0; 6] };
        let signal = |w: Watched<'_>| match w.diverged(1.0, 1.0) {
            Some(Outcome::Diverged { signal, .. }) => signal,
            other => panic!("{other:?}"),
        };
        assert_eq!(signal(w), "xhat2 (observer state)");
        assert_eq!(signal(Watched { x: &[0.0, f64::NAN], ..w }), "x2 (plant state)");
        assert_eq!(signal(Watched { x_hat: &[0.0; 2], xi_hat: &[0.0, 0.0, -2.0], ..w }), "xihat3 (regressor)");
        let eta = [0.0, 0.0, 0.0, 0.0, 3.0, 0.0];
        assert_eq!(signal(Watched { x_hat: &[0.0; 2], eta: &eta, ..w }), "eta2_2 (adaptive parameters)");
        let states = ["dw1".to_string(), "dP12".to_string()];
        assert_eq!(with_state_name("xhat2 (observer state)", &states), "xhat2 (observer state dP12)");
        assert_eq!(with_state_name("x1 (plant state)", &states), "x1 (plant state dw1)");
        for other in ["xihat2 (regressor)", "eta1_2 (adaptive parameters)", "y2 (controller input)", "x3 (plant state)"]
        {
            assert_eq!(with_state_name(other, &states), other, "no state of that name");
        }
    }
}
