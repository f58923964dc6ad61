//! Sampled-data simulation: the continuous plant between samples (disturbance acting continuously,
//! input held) with the discrete [`Controller`] in the loop.
//!
//! The plant and the disturbance's exosystem form one linear system, so the plant is advanced
//! *exactly* from sample to sample: [x; w]_{k+1} = Φ [x; w]_k + Γ u_f(k).

use std::ops::ControlFlow;

use nalgebra::{DMatrix, DVector};

use super::divergence::{Watched, DIVERGENCE_BOUND};
use super::noise::Gaussian;
use super::result::{Outcome, RunStats, Sample, SimResult};
use super::{check_run, SimError};
use crate::controller::{mat_vec, Controller, ControllerError};
use crate::design::Design;
use crate::linalg::zoh_unchecked;
use crate::plant::Plant;
use crate::settings::{self, Actuator, KeyError, MeasurementNoise};
use crate::signal::{Signal, SignalBank};

/// Settings of a sampled-data run.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledSettings {
    pub t_end: f64,
    /// A whole multiple of `sample_time`.
    pub output_step: f64,
    pub sample_time: f64,
    /// Measurement noise on the y the controller reads: white per sample, or band-limited with a
    /// bandwidth (the continuous loop's n(t) at the sample times).
    pub noise: Option<MeasurementNoise>,
    /// A watched signal above this magnitude counts as divergence ([`Watched`]).
    pub divergence_bound: f64,
    /// Record the plant state x and the observer state x̂ too ([`SimResult::x`]); off by default.
    pub record_states: bool,
    /// The true plant's actuator (delay on u_f in whole samples, limits); `None`: the plant
    /// receives u_f.
    pub actuator: Option<Actuator>,
}

/// What the sampled-data loop needs of a discrete controller. [`Controller`] is one; another
/// implementation of the same equations (generated C through FFI, say) can stand in for it in
/// [`simulate_sampled_with`].
pub trait SampledController {
    /// One sample: reads y(k) and g(k), returns the plant input u_f(k) (m entries) to hold until the
    /// next sample, or why it cannot.
    fn step(&mut self, y: &[f64], g: &[f64]) -> Result<&[f64], ControllerError>;
    /// The adaptive command u(k) (25) of the last step.
    fn command(&self) -> &[f64];
    /// ξ̂, x̂ and η̂ after the last step (`x` is left empty: the loop fills in the plant's).
    fn watched(&self) -> Watched<'_>;
}

impl SampledController for Controller {
    fn step(&mut self, y: &[f64], g: &[f64]) -> Result<&[f64], ControllerError> {
        Controller::step(self, y, g)
    }
    fn command(&self) -> &[f64] {
        Controller::command(self)
    }
    fn watched(&self) -> Watched<'_> {
        Watched { xi_hat: self.xi_hat(), x_hat: self.x_hat(), eta: self.eta(), x: &[] }
    }
}

impl SampledSettings {
    /// Settings without noise and with the default divergence bound.
    pub fn new(t_end: f64, output_step: f64, sample_time: f64) -> Self {
        SampledSettings {
            t_end,
            output_step,
            sample_time,
            noise: None,
            divergence_bound: DIVERGENCE_BOUND,
            record_states: false,
            actuator: None,
        }
    }

    /// Checks everything the run needs (horizon, sample time, signals for the design's plant, noise,
    /// divergence bound), that the controller can run at `sample_time` (delays whole numbers of
    /// samples) and that `output_step` is a whole multiple of it; returns the controller.
    pub fn check(&self, design: &Design, reference: &Signal, disturbance: &Signal) -> Result<Controller, SimError> {
        self.check_settings(design, reference, disturbance)?;
        let ctrl = Controller::new(design, self.sample_time)?;
        self.samples_per_output()?;
        Ok(ctrl)
    }

    /// Every check but the controller's.
    fn check_settings(&self, design: &Design, reference: &Signal, disturbance: &Signal) -> Result<(), SimError> {
        check_run(design, reference, disturbance, self.t_end, self.output_step, self.divergence_bound)?;
        settings::check_sample_time(self.t_end, self.sample_time)?;
        if let Some(noise) = &self.noise {
            noise.check(design.plant().m())?;
        }
        if let Some(a) = &self.actuator {
            a.check(design.plant().m())?;
        }
        Ok(())
    }

    /// Controller steps per recorded sample: output_step / sample_time, a whole number ≥ 1.
    fn samples_per_output(&self) -> Result<usize, KeyError> {
        let (T, h) = (self.sample_time, self.output_step);
        let ratio = h / T;
        if (ratio - ratio.round()).abs() > 1e-9 * ratio.max(1.0) || ratio.round() < 1.0 {
            return Err(KeyError::new(
                "simulation.output_step",
                format!("expected a whole multiple of sample_time = {T} s, found {h} s ({ratio:.6} samples)"),
            ));
        }
        Ok(ratio.round() as usize)
    }
}

/// Runs the sampled-data loop with [`Controller`] from t = 0 to `t_end`; `on_progress(t)` at each
/// recorded sample, `Break` interrupts. The result always holds what was computed.
pub fn simulate_sampled(
    design: &Design,
    reference: &Signal,
    disturbance: &Signal,
    settings: &SampledSettings,
    on_progress: impl FnMut(f64) -> ControlFlow<()>,
) -> Result<SimResult, SimError> {
    simulate_sampled_with_truth(design, design.plant(), reference, disturbance, settings, on_progress)
}

/// [`simulate_sampled`] with any [`SampledController`] in the loop, from its current state; the
/// controller must run at `settings.sample_time` (its own constructor checks the delays).
pub fn simulate_sampled_with(
    design: &Design,
    ctrl: &mut impl SampledController,
    reference: &Signal,
    disturbance: &Signal,
    settings: &SampledSettings,
    on_progress: impl FnMut(f64) -> ControlFlow<()>,
) -> Result<SimResult, SimError> {
    sampled_loop(design, design.plant(), ctrl, reference, disturbance, settings, on_progress)
}

/// [`simulate_sampled`] with the simulated plant `truth` in place of the design model (`[truth]`):
/// the plant advances with truth's matrices from truth.x0 and its input is
/// u_f = −K x̂ + F [u_1(k − d_1^true), …] with the true delays (whole samples), through
/// `settings.actuator` when there is one (u_f,i(k − d_a,i) clipped to ±u_max,i); the controller
/// keeps the design's matrices and delays.
pub fn simulate_sampled_with_truth(
    design: &Design,
    truth: &Plant,
    reference: &Signal,
    disturbance: &Signal,
    settings: &SampledSettings,
    on_progress: impl FnMut(f64) -> ControlFlow<()>,
) -> Result<SimResult, SimError> {
    let mut ctrl = settings.check(design, reference, disturbance)?;
    sampled_loop(design, truth, &mut ctrl, reference, disturbance, settings, on_progress)
}

/// The actuator in whole samples: u_p,i(k) = sat_i(u_f,i(k − d_a,i)), u_f = 0 before k = 0.
struct ActuatorLine {
    d: Vec<usize>,
    actuator: Actuator,
    /// Row k mod len: u_f(k).
    past: Vec<f64>,
    len: usize,
    u_p: Vec<f64>,
    limited: Vec<bool>,
}

impl ActuatorLine {
    fn new(actuator: &Actuator, T: f64) -> Result<Self, KeyError> {
        let d = whole_samples("truth.actuator_delays", &actuator.delays, T)?;
        let m = d.len();
        let len = d.iter().max().map_or(1, |x| x + 1);
        Ok(ActuatorLine {
            d,
            actuator: actuator.clone(),
            past: vec![0.0; len * m],
            len,
            u_p: vec![0.0; m],
            limited: vec![false; m],
        })
    }

    /// Records u_f(k) and returns u_p(k).
    fn apply(&mut self, k: usize, u_f: &[f64]) -> &[f64] {
        let m = u_f.len();
        self.past[(k % self.len) * m..(k % self.len + 1) * m].copy_from_slice(u_f);
        for i in 0..m {
            let d = self.d[i];
            let v = if k >= d { self.past[((k - d) % self.len) * m + i] } else { 0.0 };
            (self.u_p[i], self.limited[i]) = self.actuator.clip(i, v);
        }
        &self.u_p
    }
}

/// Each delay as a whole number of samples of T, or an error on `key[i]`.
fn whole_samples(key: &str, delays: &[f64], T: f64) -> Result<Vec<usize>, KeyError> {
    delays
        .iter()
        .enumerate()
        .map(|(i, &tau)| {
            let r = tau / T;
            if !crate::controller::discrete::whole(tau, T) {
                return Err(KeyError::new(
                    format!("{key}[{i}]"),
                    format!("τ = {tau} s is {r:.6} samples of T_s = {T} s; a sampled-data run needs whole numbers of samples (at most 1e7)"),
                ));
            }
            Ok(r.round() as usize)
        })
        .collect()
}

/// The plant input at the true delays: u_f + F (u(k − d^true) − u(k − d)), from the commands of
/// the last max d + 1 samples.
struct TrueInput {
    d: Vec<usize>,
    d_true: Vec<usize>,
    F: DMatrix<f64>,
    /// Row k mod len: u(k).
    past: Vec<f64>,
    len: usize,
    du: Vec<f64>,
    u_f: Vec<f64>,
}

impl TrueInput {
    /// `None` when the true delays are the design's.
    fn new(design: &Design, truth: &Plant, T: f64) -> Result<Option<TrueInput>, KeyError> {
        let p = design.plant();
        if truth.delays == p.delays {
            return Ok(None);
        }
        let (d, d_true) =
            (whole_samples("plant.delays", &p.delays, T)?, whole_samples("truth.delays", &truth.delays, T)?);
        let m = d.len();
        let len = d.iter().chain(&d_true).max().map_or(1, |x| x + 1);
        Ok(Some(TrueInput {
            d,
            d_true,
            F: design.F().clone(),
            past: vec![0.0; len * m],
            len,
            du: vec![0.0; m],
            u_f: vec![0.0; m],
        }))
    }

    /// Records u(k) and returns the true plant input from the controller's `u_f` (in `self.u_f`).
    fn apply(&mut self, k: usize, u: &[f64]) -> &[f64] {
        let m = u.len();
        self.past[(k % self.len) * m..(k % self.len + 1) * m].copy_from_slice(u);
        let at = |d: usize, i: usize| if k >= d { self.past[((k - d) % self.len) * m + i] } else { 0.0 };
        for i in 0..m {
            self.du[i] = at(self.d_true[i], i) - at(self.d[i], i);
        }
        mat_vec(&self.F, &self.du, &mut self.u_f, true);
        &self.u_f
    }
}

#[allow(clippy::too_many_arguments)]
fn sampled_loop(
    design: &Design,
    truth: &Plant,
    ctrl: &mut impl SampledController,
    reference: &Signal,
    disturbance: &Signal,
    settings: &SampledSettings,
    mut on_progress: impl FnMut(f64) -> ControlFlow<()>,
) -> Result<SimResult, SimError> {
    settings.check_settings(design, reference, disturbance)?;
    super::check_truth(design, truth)?;
    let every = settings.samples_per_output()?;
    let T = settings.sample_time;
    let mut shift = TrueInput::new(design, truth, T)?;
    let mut actuator = match settings.actuator.as_ref().filter(|a| !a.is_ideal()) {
        Some(a) => Some(ActuatorLine::new(a, T)?),
        None => None,
    };
    let p = truth;
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
    let (Phi, Gamma) = zoh_unchecked(&M, &Bu, T);
    // y = [C, Q H] [x; w].
    let mut Cy = DMatrix::zeros(m, n + nw);
    Cy.view_mut((0, 0), (m, n)).copy_from(&p.C);
    Cy.view_mut((0, n), (m, nw)).copy_from(&(&p.Q * &H));

    let mut s = DVector::zeros(n + nw);
    s.rows_mut(0, n).copy_from(&p.x0);
    s.rows_mut(n, nw).copy_from(&w0);
    let mut s_next = s.clone();
    let (mut y, mut y_meas, mut g) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
    let mut noise = settings.noise.as_ref().map(|nz| Noise::new(nz, m));
    let stats = |controller_steps| RunStats::Sampled { controller_steps, sample_time: T };
    let mut result = SimResult::new(m, design.q(), n, stats(0));
    // u_f(k) and, when states are recorded, x̂(k) (read before the step moves it to x̂(k + 1)).
    let (mut u_f, mut x_hat) = (vec![0.0; m], vec![0.0; n]);
    let steps = (settings.t_end / T + 1e-9).floor() as usize;
    let mut outcome = Outcome::Completed;
    let mut taken = 0;
    for k in 0..=steps {
        let t = k as f64 * T;
        mat_vec(&Cy, s.as_slice(), &mut y, false);
        reference.eval_into_unchecked(t, &mut g);
        y_meas.copy_from_slice(&y);
        if let Some(noise) = noise.as_mut() {
            noise.add(t, &mut y_meas);
        }
        if settings.record_states && k % every == 0 {
            x_hat.copy_from_slice(ctrl.watched().x_hat);
        }
        // A measurement beyond the controller's bound, or a state gone non-finite, ends the run
        // as diverged (as the next record's check would have), not as an error.
        let stepped = match ctrl.step(&y_meas, &g) {
            Err(ControllerError::InputOutOfRange { name, index, value }) => {
                Err(Outcome::Diverged { t, signal: format!("{name}[{}] (controller input)", index + 1), value })
            }
            Err(ControllerError::StateNotFinite { value }) => {
                Err(Outcome::Diverged { t, signal: "u_f (controller output)".to_string(), value })
            }
            other => Ok(other?),
        };
        match (stepped, shift.as_mut()) {
            (Err(diverged), _) => {
                outcome = diverged;
                break;
            }
            (Ok(v), None) => u_f.copy_from_slice(v),
            (Ok(v), Some(sh)) => {
                sh.u_f.copy_from_slice(v);
                u_f.copy_from_slice(sh.apply(k, ctrl.command()));
            }
        }
        if let Some(a) = actuator.as_mut() {
            let applied = a.apply(k, &u_f);
            u_f.copy_from_slice(applied);
        }
        taken += 1;
        mat_vec(&Phi, s.as_slice(), s_next.as_mut_slice(), false);
        mat_vec(&Gamma, &u_f, s_next.as_mut_slice(), true);
        if k % every == 0 {
            let watched = Watched { x: &s.as_slice()[..n], ..ctrl.watched() };
            if let Some(diverged) = watched.diverged(t, settings.divergence_bound) {
                outcome = diverged;
                break;
            }
            result.peaks.record(&watched);
            let states = settings.record_states.then_some((watched.x, &x_hat[..]));
            let (u, eta) = (ctrl.command(), watched.eta);
            result.push(&Sample { t, y: &y, g: &g, u, u_f: &u_f, eta, states });
            if let Some(a) = &actuator {
                result.count_limited(a.limited.iter().copied());
            }
            if on_progress(t).is_break() {
                outcome = Outcome::Interrupted { t };
                break;
            }
        }
        std::mem::swap(&mut s, &mut s_next);
    }
    result.stats = stats(taken);
    result.outcome = Some(outcome);
    Ok(result)
}

/// The sampled loop's measurement noise: white samples, or the band-limited n(t) at the sample
/// times.
enum Noise {
    White { rng: Gaussian, std: Vec<f64> },
    Band { bank: SignalBank, n: Vec<f64> },
}

impl Noise {
    fn new(noise: &MeasurementNoise, m: usize) -> Self {
        match super::noise::band_limited(noise) {
            Some(signal) => Noise::Band { bank: SignalBank::new(&[&signal]), n: vec![0.0; m] },
            None => Noise::White { rng: Gaussian::new(noise.seed), std: noise.std.clone() },
        }
    }

    /// y ← y + n(t).
    fn add(&mut self, t: f64, y: &mut [f64]) {
        match self {
            Noise::White { rng, std } => {
                for (v, sd) in y.iter_mut().zip(std.iter()) {
                    *v += sd * rng.sample();
                }
            }
            Noise::Band { bank, n } => {
                bank.eval_into_unchecked(t, n);
                for (v, x) in y.iter_mut().zip(n.iter()) {
                    *v += x;
                }
            }
        }
    }
}
