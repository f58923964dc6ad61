//! Sampled-data simulation: the continuous plant between samples (disturbance acting continuously,
//! input held) with the discrete [`Controller`] in the loop.
//!
//! The plant and the disturbance's exosystem form one linear system, so the plant is advanced
//! *exactly* from sample to sample: [x; w]_{k+1} = Φ [x; w]_k + Γ u_f(k).

use std::ops::ControlFlow;

use nalgebra::{DMatrix, DVector};

use super::noise::Gaussian;
use super::result::{Outcome, SimResult};
use crate::controller::{mat_vec, Controller, ControllerError};
use crate::design::Design;
use crate::linalg::zoh;
use crate::signal::Signal;

/// White Gaussian measurement noise on y: standard deviation per output and a seed.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasurementNoise {
    pub std: Vec<f64>,
    pub seed: u64,
}

/// Most controller steps of a sampled-data run (t_end / sample_time).
pub const MAX_SAMPLING_STEPS: f64 = 1e10;

/// Settings of a sampled-data run.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledSettings {
    pub t_end: f64,
    /// A whole multiple of `sample_time`.
    pub output_step: f64,
    pub sample_time: f64,
    pub noise: Option<MeasurementNoise>,
    /// A state above this magnitude counts as divergence.
    pub divergence_bound: f64,
}

/// Why a sampled-data run cannot start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SampledError {
    #[error(transparent)]
    Controller(#[from] ControllerError),
    #[error("simulation.sample_time (--sample-time): t_end / T_s = {steps:.3e} controller steps; at most {max:e} are run; choose a sample time ≥ {min_sample_time:e} s")]
    TooManySteps { steps: f64, max: f64, min_sample_time: f64 },
    #[error("simulation.output_step: expected a whole multiple of sample_time = {sample_time} s, found {output_step} s ({ratio:.6} samples)")]
    OutputStep { output_step: f64, sample_time: f64, ratio: f64 },
}

impl SampledSettings {
    /// Checks that the controller can run at `sample_time` (delays whole numbers of samples) and
    /// that `output_step` is a whole multiple of it; returns the controller and the samples per output.
    pub fn check(&self, design: &Design) -> Result<(Controller, usize), SampledError> {
        let T = self.sample_time;
        let max = MAX_SAMPLING_STEPS;
        if self.t_end / T > max {
            return Err(SampledError::TooManySteps { steps: self.t_end / T, max, min_sample_time: self.t_end / max });
        }
        let ctrl = Controller::new(design, T)?;
        let ratio = self.output_step / T;
        if (ratio - ratio.round()).abs() > 1e-9 * ratio.max(1.0) || ratio.round() < 1.0 {
            return Err(SampledError::OutputStep { output_step: self.output_step, sample_time: T, ratio });
        }
        Ok((ctrl, ratio.round() as usize))
    }
}

/// Runs the sampled-data loop from t = 0 to `t_end`; `on_progress(t)` at each recorded sample,
/// `Break` interrupts. The result always holds what was computed.
pub fn simulate_sampled(
    design: &Design,
    reference: &Signal,
    disturbance: &Signal,
    settings: &SampledSettings,
    mut on_progress: impl FnMut(f64) -> ControlFlow<()>,
) -> Result<SimResult, SampledError> {
    let T = settings.sample_time;
    let (mut ctrl, every) = settings.check(design)?;
    let p = design.plant();
    let (n, m) = (p.n(), p.m());
    let (S, H, w0) = disturbance.exosystem();
    let nw = S.nrows();
    // [x; w]' = [[A, D H], [0, S]] [x; w] + [B; 0] u_f.
    let mut M = DMatrix::zeros(n + nw, n + nw);
    M.view_mut((0, 0), (n, n)).copy_from(&p.A);
    M.view_mut((0, n), (n, nw)).copy_from(&(&p.D * &H));
    M.view_mut((n, n), (nw, nw)).copy_from(&S);
    let mut Bu = DMatrix::zeros(n + nw, m);
    Bu.view_mut((0, 0), (n, m)).copy_from(&p.B);
    let (Phi, Gamma) = zoh(&M, &Bu, T);
    // y = [C, Q H] [x; w].
    let mut Cy = DMatrix::zeros(m, n + nw);
    Cy.view_mut((0, 0), (m, n)).copy_from(&p.C);
    Cy.view_mut((0, n), (m, nw)).copy_from(&(&p.Q * &H));

    let mut s = DVector::zeros(n + nw);
    s.rows_mut(0, n).copy_from(&p.x0);
    s.rows_mut(n, nw).copy_from(&w0);
    let mut s_next = s.clone();
    let (mut y, mut y_meas, mut g) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
    let mut noise = settings.noise.as_ref().map(|nz| (Gaussian::new(nz.seed), nz.std.clone()));
    let mut result = SimResult::new(m, design.q());
    let steps = (settings.t_end / T + 1e-9).floor() as usize;
    let mut outcome = Outcome::Completed;
    for k in 0..=steps {
        let t = k as f64 * T;
        mat_vec(&Cy, s.as_slice(), &mut y, false);
        reference.eval_into(t, &mut g);
        y_meas.copy_from_slice(&y);
        if let Some((rng, std)) = noise.as_mut() {
            for (v, sd) in y_meas.iter_mut().zip(std.iter()) {
                *v += sd * rng.sample();
            }
        }
        let u_f = ctrl.step(&y_meas, &g);
        mat_vec(&Phi, s.as_slice(), s_next.as_mut_slice(), false);
        mat_vec(&Gamma, u_f, s_next.as_mut_slice(), true);
        if k % every == 0 {
            let bound = settings.divergence_bound;
            let bad = (0..n).find(|&j| super::runaway(s[j], bound)).map(|j| (super::plant_state_name(j), s[j]));
            let eta = ctrl.eta();
            let bad = bad.or_else(|| {
                eta.iter().position(|&v| super::runaway(v, bound)).map(|j| (super::eta_name(j, design.q()), eta[j]))
            });
            if let Some((signal, value)) = bad {
                outcome = Outcome::Diverged { t, signal, value };
                break;
            }
            result.push(t, &y, &g, ctrl.command(), eta);
            if on_progress(t).is_break() {
                outcome = Outcome::Interrupted { t };
                break;
            }
        }
        std::mem::swap(&mut s, &mut s_next);
    }
    result.stats.steps = steps + 1;
    result.outcome = Some(outcome);
    Ok(result)
}
