//! When a run counts as diverged: one bound and the same signals for both loops (and for sweeps).

use super::result::Outcome;

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
    /// The first watched value (in the order x, x̂, ξ̂, η̂: the plant first) that is non-finite or
    /// above `bound` in magnitude, as the outcome of a run diverged at time `t`.
    pub fn diverged(&self, t: f64, bound: f64) -> Option<Outcome> {
        let q = self.xi_hat.len();
        let name = |signal: usize, j: usize| match signal {
            0 => format!("x[{}] (plant state)", j + 1),
            1 => format!("x_hat[{}] (observer state)", j + 1),
            2 => format!("xi_hat[{}] (regressor)", j + 1),
            _ => format!("eta{}[{}] (adaptive parameters)", j / q + 1, j % q + 1),
        };
        [self.x, self.x_hat, self.xi_hat, self.eta].iter().enumerate().find_map(|(signal, values)| {
            values.iter().position(|&v| !(v.is_finite() && v.abs() <= bound)).map(|j| Outcome::Diverged {
                t,
                signal: name(signal, j),
                value: values[j],
            })
        })
    }
}

/// Whether v is outside [−bound, bound] or not finite (so NaN is always beyond).
pub fn beyond(v: f64, bound: f64) -> bool {
    !(v.is_finite() && v.abs() <= bound)
}

/// A divergence bound: > 0, not NaN (+∞ watches only for non-finite values).
pub(crate) fn check_bound(bound: f64) -> Result<(), crate::settings::KeyError> {
    if bound > 0.0 {
        Ok(())
    } else {
        Err(crate::settings::KeyError::new(
            "divergence_bound",
            format!("expected a bound > 0 (or +inf for none; default {DIVERGENCE_BOUND:e}), found {bound}"),
        ))
    }
}
