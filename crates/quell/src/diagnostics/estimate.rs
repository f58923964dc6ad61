//! The adaptive law's pace before a run (the design report): per channel, from the averaged Ω̄_i
//! ([`super::averaged`]), the rate μ_i λ_max(Ω̄_i) against the loop's other rates ([`loop_rate`]),
//! λ_min(Ω̄_i) and the predicted convergence time, with a flag for a stiff and for a weakly excited
//! channel.

use serde::Serialize;

use crate::averaged::Averaged;
use crate::design::Design;
use crate::plant::Plant;
use crate::signal::Signal;
use crate::sim::loop_rate;
pub use crate::sim::STIFF_RATIO;

/// One channel's pace (`quell design` → `adaptation`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RateEstimate {
    /// 1-based.
    pub channel: usize,
    pub mu: f64,
    /// λ_max(Ω̄_i) and λ_min(Ω̄_i).
    pub lambda_max_omega: f64,
    pub lambda_min_omega: f64,
    /// How many directions of η̂_i the signals excite (eigenvalues of Ω̄_i above 1e-13 λ_max), of q;
    /// the error does not depend on the others.
    pub excited_rank: usize,
    /// The smallest excited eigenvalue.
    pub lambda_min_excited_omega: f64,
    /// μ_i λ_max(Ω̄_i) in 1/s: the adaptive law's fastest rate.
    pub adaptation_rate: f64,
    /// ρ in 1/s ([`loop_rate`]): the loop's fastest rate besides the adaptive law.
    pub loop_rate: f64,
    /// 1/(μ_i λ_min) over the excited directions, in s (∞, null in JSON, for μ_i = 0).
    pub convergence_time: f64,
    /// μ_i λ_max(Ω̄_i) > [`STIFF_RATIO`]·ρ.
    pub stiff: bool,
    /// The slowest excited direction does not converge within the horizon: μ_i λ_min t_end < 1.
    pub weakly_excited: bool,
    /// One line per flag: what it means and which knob to turn.
    pub advice: Vec<String>,
}

/// Each channel's [`RateEstimate`] for `design` run on the plant `truth` under g = `reference`,
/// ω = `disturbance` for `t_end` seconds.
pub fn estimate(
    design: &Design,
    truth: &Plant,
    reference: &Signal,
    disturbance: &Signal,
    t_end: f64,
) -> Vec<RateEstimate> {
    let rho = loop_rate(design, truth, [reference, disturbance]);
    let avg = Averaged::new(design, reference, disturbance);
    let unit = design.plant().time_unit;
    let remedy = super::ObserverRemedy::new(design, [reference, disturbance], None);
    let transient = super::slow_transient_advice(design, t_end);
    avg.channels
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let mu = design.mu()[i];
            let lambda_max = c.lambda_max();
            // 0 when the signals excite nothing.
            let lambda_min_excited = c.excited().reduce(f64::min).unwrap_or(0.0);
            let rate = mu * lambda_max;
            let slowest = mu * lambda_min_excited;
            let stiff = rate > STIFF_RATIO * rho;
            let rank = c.excited().count();
            // The run's own criterion ([`super::slow_direction_advice`]): a relevant direction of
            // Ω̄ that has not converged by t_end (μλ t_end < 5).
            let slow = (rank > 0 && mu > 0.0)
                .then(|| super::slow_direction_advice(c, (i, mu), &avg.fidelity, (t_end, STIFF_RATIO * rho), unit, &remedy))
                .flatten();
            let weakly_excited = slow.is_some();
            let mut advice = Vec::new();
            if stiff {
                advice.push(stiff_advice(design, (i, mu), c, (rho, t_end, false), [reference, disturbance]));
            }
            if rank == 0 {
                advice.push(format!(
                    "channel {}: the signals excite no direction of the regressor (g and ω are zero): η̂_{} stays at 0, there is nothing to adapt to",
                    i + 1,
                    i + 1
                ));
            }
            advice.extend(slow);
            advice.extend(transient.clone());
            RateEstimate {
                channel: i + 1,
                mu,
                lambda_max_omega: lambda_max,
                lambda_min_omega: c.lambda_min(),
                excited_rank: rank,
                lambda_min_excited_omega: lambda_min_excited,
                adaptation_rate: rate,
                loop_rate: rho,
                convergence_time: 1.0 / slowest,
                stiff,
                weakly_excited,
                advice,
            }
        })
        .collect()
}

/// The least factor by which the stiff line's μ must differ from the design's to be offered: a
/// headbox at μ = 50 had been told to lower it "at most to about 49".
pub(crate) const WORTH_CHANGING: f64 = 1.25;

/// The μ below the design's `mu` that [`stiff_advice`] offers to lower a stiff channel's gain to,
/// "at most to about": what its slowest relevant direction needs by t_end ([`super::horizon_mu`]),
/// where that is above the stiffness threshold's μ and below `mu` by [`WORTH_CHANGING`]; `None`
/// otherwise. It is the averaged law's, which a run checks ([`super::diagnose_run`]).
pub(crate) fn lower_offer(c: &crate::averaged::ChannelAverage, mu: f64, (rho, t_end): (f64, f64)) -> Option<f64> {
    let relevant = c.slowest_relevant(super::RELEVANT_SHARE);
    let (wanted, fastest) = super::horizon_mu(relevant, c.lambda_max(), (t_end, STIFF_RATIO * rho));
    let needed = crate::settings::round_up_2(wanted);
    (relevant.is_finite() && wanted > fastest && needed * WORTH_CHANGING < mu).then_some(needed)
}

/// What ends every [`lower_offer_text`]: a run's diagnostics look for it before checking an offer.
pub(crate) const LOWER_OFFER_WORDS: &str = "where max|u_f| allows (the averaged law's figure, not yet run: a run of this scenario checks it and says whether it holds)";

/// How [`stiff_advice`] offers [`lower_offer`]'s μ, which [`super::diagnose_run`] replaces where a
/// run at it misses the tail bound.
pub(crate) fn lower_offer_text(i: usize, mu: f64) -> String {
    format!("lower design.mu[{i}] at most to about {} {LOWER_OFFER_WORDS}", crate::settings::fmt_short(mu))
}

/// Channel i adapting at μ λ_max beyond [`STIFF_RATIO`] times the loop's rate ρ: what it means and
/// the μ to lower it to where u_f is more than the actuator takes (the integrator handles the
/// stiffness: a tryout's Wardle–Wood column design over 14,400 min, μ = [8.7, 3.5] against the
/// threshold's 0.87, ended with tails 3e4–8e5× smaller than at
/// it, in 5 % more steps). That is the threshold's μ unless the slowest relevant direction would then
/// not converge by t_end ([`super::horizon_mu`]): there the stiffness is the price of Ω̄'s spread,
/// and the advice names the μ that direction needs, to keep or approach (the quadruple tank at μ = 1,
/// told to lower μ to the threshold's 7.3e-6, ends with a tail max|e| of 9.0e-3, at that μ of 0.16).
/// The design report and the run's diagnostics share it; a run whose tail missed its bound against
/// that law's word (`missed`) is not told to keep μ on it ([`super::diagnose_run`]).
pub(crate) fn stiff_advice(
    design: &Design,
    (i, mu): (usize, f64),
    c: &crate::averaged::ChannelAverage,
    (rho, t_end, missed): (f64, f64, bool),
    signals: [&Signal; 2],
) -> String {
    let (lambda_max, unit) = (c.lambda_max(), design.plant().time_unit);
    let rate = mu * lambda_max;
    // Many harmonics: the modal form (normalizing alone left a building's λ_min(Ω̄) at 1e-10).
    let scaling_hint = match design.regressor_scaling() {
        _ if crate::auto::many_harmonics(signals, design) => {
            ", or set design.regressor_scaling = \"modal\" with a resonator −b ± jω per harmonic as filter poles (the companion forms' Ω̄ is singular to rounding with many harmonics) and choose μ anew"
        }
        crate::design::RegressorScaling::Paper => {
            ", or set design.regressor_scaling = \"normalized\" (ξ̂ of the signals' size, which also narrows the spread where the filters' poles differ in scale) and choose μ anew"
        }
        crate::design::RegressorScaling::Normalized | crate::design::RegressorScaling::Modal => "",
    };
    let relevant = c.slowest_relevant(super::RELEVANT_SHARE);
    let (wanted, fastest) = super::horizon_mu(relevant, lambda_max, (t_end, STIFF_RATIO * rho));
    let fmt = crate::settings::fmt_short;
    let lower = if !(relevant.is_finite() && wanted > fastest) {
        format!(
            "where max|u_f| is more than the actuator takes, lower design.mu[{i}] to about {} (slower adaptation: a larger tail){scaling_hint}",
            fmt(crate::settings::round_down_2(fastest))
        )
    } else {
        let needed = crate::settings::round_up_2(wanted);
        let keep = if lower_offer(c, mu, (rho, t_end)).is_some() && !missed {
            lower_offer_text(i, needed)
        } else if needed > WORTH_CHANGING * mu && needed <= super::RAISE_AT_MOST * mu {
            format!("raise design.mu[{i}] toward {} where max|u_f| allows (or keep it)", fmt(needed))
        } else if missed {
            format!("choose design.mu[{i}] by runs, not by that law's figure (this run's tail misses its bound)")
        } else {
            format!("keep design.mu[{i}] where max|u_f| allows")
        };
        format!(
            "lowered to the stiffness threshold (μ λ_max = {STIFF_RATIO:.0}ρ), about {}, its slowest relevant direction would not converge by t_end (that needs μ ≥ {}: Ω̄'s eigenvalues spread {}-fold), so {keep}{scaling_hint}",
            fmt(crate::settings::round_down_2(fastest)),
            fmt(needed),
            crate::settings::fmt_ratio(lambda_max / relevant),
        )
    };
    format!(
        "channel {} adapts at μ λ_max = {rate:.3e}/{unit}, {}× the loop's fastest other rate ({rho:.3e}/{unit}): the adaptive law is stiff (the continuous loop's automatic integrator and the discrete controller's implicit step take it stably; an explicit integrator crawls), and a gain this high can drive u_f hard; {lower}",
        i + 1,
        crate::settings::fmt_ratio(rate / rho),
    )
}

#[cfg(test)]
mod tests {
    use std::ops::ControlFlow;

    use nalgebra::{DMatrix, SymmetricEigen};

    use super::*;
    use crate::scenario::{Scenario, PAPER_EXAMPLE};
    use crate::sim::closed_loop::ContinuousLoop;
    use crate::sim::dde::{self, DelaySystem, Options, Past};

    /// The continuous loop with its whole state as output, so that Ω_i can be read at output times.
    struct WholeState<'a>(ContinuousLoop<'a>);

    impl DelaySystem for WholeState<'_> {
        fn dim(&self) -> usize {
            self.0.dim()
        }
        fn n_delayed(&self) -> usize {
            self.0.n_delayed()
        }
        fn delays(&self) -> &[f64] {
            self.0.delays()
        }
        fn rhs(&mut self, t: f64, y: &[f64], past: &Past<'_>, dy: &mut [f64]) {
            self.0.rhs(t, y, past, dy)
        }
        fn implicit(&self) -> std::ops::Range<usize> {
            self.0.implicit()
        }
        fn implicit_rate(&self, y: &[f64]) -> f64 {
            self.0.implicit_rate(y)
        }
        fn solve_implicit(&mut self, t: f64, c: f64, z: &mut [f64]) -> bool {
            self.0.solve_implicit(t, c, z)
        }
    }

    /// Per channel, the mean of the simulated Ω_i over [t_end − window, t_end] (trapezoid rule on
    /// samples `dt` apart): the run's own answer to what Ω̄_i is.
    fn simulated_mean(s: &Scenario, design: &Design, t_end: f64, window: f64, dt: f64) -> Vec<DMatrix<f64>> {
        let lp = ContinuousLoop::new(design, &s.reference, &s.disturbance).unwrap();
        let (m, q) = (design.plant().m(), design.q());
        let ranges: Vec<_> = (0..m).map(|i| lp.omega_range(i)).collect();
        let mut sys = WholeState(lp);
        let y0 = sys.0.initial_state(&s.plant.x0).unwrap();
        let history = vec![0.0; sys.n_delayed()];
        let (rtol, atol) = (s.simulation.rtol, s.simulation.atol);
        let opts = Options { rtol, atol, max_steps: 1_000_000, ..Options::default() };
        let mut sums = vec![DMatrix::<f64>::zeros(q, q); m];
        let samples = (window / dt).round();
        dde::solve(&mut sys, 0.0, &y0, &history, t_end, dt, &opts, |t, y| {
            let k = ((t_end - t) / dt).round();
            if k <= samples {
                let weight = if k == 0.0 || k == samples { 0.5 } else { 1.0 } / samples;
                for (sum, r) in sums.iter_mut().zip(&ranges) {
                    let packed = &y[r.clone()];
                    let mut at = 0;
                    for a in 0..q {
                        for b in a..q {
                            sum[(a, b)] += weight * packed[at];
                            sum[(b, a)] = sum[(a, b)];
                            at += 1;
                        }
                    }
                }
            }
            ControlFlow::Continue(())
        })
        .unwrap();
        sums
    }

    /// The estimate's λ_max, λ_min (excited) and rate against the eigenvalues of the simulated Ω_i
    /// averaged over whole periods of every frequency in the loop, on the paper's example (g and ω
    /// at 0, 1, 2 rad/s: period 2π) and on the quadruple-tank process with normalized filters
    /// (0, 0.01, 0.02, 0.03 rad/s: period 200π s).
    #[test]
    fn estimate_matches_the_simulated_omega() {
        let tank = include_str!("../../tests/data/quadruple-tank.toml")
            .replace("beta = 10.0", "beta = 10.0\nregressor_scaling = \"normalized\"");
        let tau = std::f64::consts::TAU;
        // (scenario, horizon, averaging window: whole periods after the transients)
        for (toml, t_end, window) in [(PAPER_EXAMPLE, 16.0 * tau, 8.0 * tau), (tank.as_str(), 300.0 * tau, 200.0 * tau)]
        {
            let s = Scenario::from_toml(toml).unwrap();
            let d = s.design().unwrap();
            let estimates = estimate(&d, s.true_plant(), &s.reference, &s.disturbance, t_end);
            let means = simulated_mean(&s, &d, t_end, window, window / 1600.0);
            for (e, mean) in estimates.iter().zip(means) {
                let mut lambda: Vec<f64> = SymmetricEigen::new(mean).eigenvalues.iter().copied().collect();
                lambda.sort_by(f64::total_cmp);
                let top = lambda[lambda.len() - 1];
                let excited = lambda[lambda.len() - e.excited_rank];
                // The simulated mean differs from Ω̄ by the solver's error (its Ω_i is a filtered
                // quadratic of states integrated to rtol 1e-9 / 1e-6 and errors partly average out),
                // by the transients left at t_end − window (e^(−8) of H's decay on the paper,
                // e^(−60) of the filters' on the tank) and by the trapezoid rule, exact on whole
                // periods of a trigonometric polynomial sampled above its highest frequency. Found:
                // 1e-11 of λ_max; 1e-8 leaves room for other platforms' rounding.
                let tol = 1e-8 * e.lambda_max_omega;
                assert!((top - e.lambda_max_omega).abs() <= tol, "λ_max {top} vs {}", e.lambda_max_omega);
                assert!(
                    (excited - e.lambda_min_excited_omega).abs() <= tol,
                    "λ_min {excited} vs {}",
                    e.lambda_min_excited_omega
                );
                assert!((e.adaptation_rate - e.mu * e.lambda_max_omega).abs() <= 1e-12 * e.adaptation_rate);
            }
        }
    }
}
