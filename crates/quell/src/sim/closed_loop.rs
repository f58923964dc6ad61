//! The continuous closed loop, wired once: plant (1) with input (5),
//! controller [`Equations`], integrated as a delay equation by [`dde::solve`].

use std::cell::Cell;
use std::ops::ControlFlow;
use std::rc::Rc;

use nalgebra::{DMatrix, DVector};

use super::dde::{self, DelaySystem, Options, Past};
use super::divergence::{Peaks, Watched};
use super::result::{Outcome, RunStats, Sample, SimResult};
use super::{check_run, Integrator, Loop, Run, SimError, PROGRESS_EVERY};
use crate::averaged::Averaged;
use crate::controller::{command, mat_vec, packed, swapping_error, Equations};
use crate::design::{Design, RegressorScaling};
use crate::plant::{Plant, PlantError};
use crate::settings::{self, Actuator, KeyError, MeasurementNoise};
use crate::signal::{Signal, SignalBank};

/// Offsets of the loop's state vector [z = (ξ̂, x̂), η̂_1, …, η̂_m, x, filters]. The delayed terms
/// read ξ̂ and η̂_i, within the prefix [z, η̂]; with x, [z, η̂, x] is all the outputs need (the solver
/// keeps dense output of just that).
#[derive(Debug, Clone)]
struct Layout {
    nz: usize,
    q: usize,
    /// Start of x.
    x: usize,
    /// Per channel: start of W_i, Y_i, Ω_i (packed).
    w: Vec<usize>,
    y: Vec<usize>,
    omega: Vec<usize>,
    dim: usize,
}

/// The length of [z, η̂] = [ξ̂, x̂, η̂_1, …, η̂_m], the prefix the delayed terms read: n + q + m·q.
fn delayed_prefix(n: usize, q: usize, m: usize) -> usize {
    n + q + m * q
}

impl Layout {
    fn new(eq: &Equations) -> Layout {
        let q = eq.q;
        let x = delayed_prefix(eq.n, q, eq.m);
        let mut at = x + eq.n;
        let (mut w, mut y, mut omega) = (vec![], vec![], vec![]);
        for i in 0..eq.m {
            w.push(at);
            at += eq.filter_len(i);
            y.push(at);
            at += q;
            omega.push(at);
            at += packed::len(q);
        }
        Layout { nz: eq.nz, q, x, w, y, omega, dim: at }
    }

    fn eta(&self, i: usize) -> usize {
        self.nz + i * self.q
    }

    fn n_delayed(&self) -> usize {
        self.x
    }

    /// z, η̂ and x: what y, u and η̂ are computed from.
    fn n_output(&self, n: usize) -> usize {
        self.x + n
    }
}

/// The closed loop as a [`DelaySystem`]: plant (1), input (5), observers (6), (14), (20), filters and
/// adaptive law (33), control law (25). All buffers are allocated once; `rhs` allocates nothing.
pub struct ContinuousLoop<'a> {
    eq: Equations,
    C: &'a DMatrix<f64>,
    Q: &'a DMatrix<f64>,
    /// The controller's initial estimate x̂(0) (the design plant's `xhat0`).
    xhat0: &'a DVector<f64>,
    /// Plant (1) with input (5) and the core, as one sparse operator (see [`LinearPart`]).
    linear: LinearPart,
    /// g and ω, evaluated together.
    signals: SignalBank,
    layout: Layout,
    delays: Vec<f64>,
    /// The true plant's input delays where one differs from the design's (`[truth]`): the plant
    /// then reads u_i(t − τ_i^true) while the controller keeps τ_i. Empty when all agree, and with
    /// an `actuator` (which reads the true delays itself).
    true_delays: Vec<f64>,
    /// The true plant's actuator, when it delays or limits u_f.
    actuator: Option<ActuatorPath>,
    // Scratch.
    y: Vec<f64>,
    /// e = [g; ω; n; u_d; u_p], the loop's inputs other than the state: the measurement noise n
    /// when there is some, and the true plant's input u_p (u_d at the true delays with
    /// `true_delays`, the whole input with an `actuator`) when it is not the design's.
    e: Vec<f64>,
    eta_d: Vec<f64>,
    xi_d: Vec<f64>,
    Delta: Vec<f64>,
    tmp: Vec<f64>,
    /// The Cholesky factor of I + hγμ_iΩ_i in the implicit stages ([`DelaySystem::solve_implicit`]),
    /// and the power steps' vectors ([`DelaySystem::implicit_rate_below`]).
    factor: Vec<f64>,
    u_d: Vec<f64>,
    /// What [`DelaySystem::observe`] records; `None` for a loop used as a bare [`DelaySystem`].
    record: Option<Record>,
    /// Per row of a filter bank W_i, its place in the state and its scale ω_c^(r−σ_i) against its
    /// input ([`DelaySystem::absolute_tolerances`]); empty for the paper's form of the regressor.
    w_scales: Vec<(std::ops::Range<usize>, f64)>,
}

impl<'a> ContinuousLoop<'a> {
    /// The loop for a design and the true reference and disturbance signals.
    pub fn new(design: &'a Design, reference: &'a Signal, disturbance: &'a Signal) -> Result<Self, KeyError> {
        ContinuousLoop::with_truth(design, design.plant(), reference, disturbance)
    }

    /// [`ContinuousLoop::with_truth`] with the true plant's actuator between u_f and the plant
    /// ([`Actuator`]; `None` or an ideal one: u_f itself) and band-limited measurement noise added
    /// to the y the controller reads ([`MeasurementNoise`] with a bandwidth; the recorded y stays
    /// the plant's).
    pub fn with_physics(
        design: &'a Design,
        truth: &'a Plant,
        reference: &'a Signal,
        disturbance: &'a Signal,
        actuator: Option<&Actuator>,
        noise: Option<&MeasurementNoise>,
    ) -> Result<Self, KeyError> {
        let m = design.plant().m();
        let actuator = actuator.filter(|a| !a.is_ideal());
        if let Some(a) = actuator {
            a.check(m)?;
        }
        let noise = match noise {
            Some(nz) => {
                nz.check(m)?;
                nz.check_continuous()?;
                super::noise::band_limited(nz)
            }
            None => None,
        };
        let mut lp = ContinuousLoop::with_truth(design, truth, reference, disturbance)?;
        if actuator.is_none() && noise.is_none() {
            return Ok(lp);
        }
        let eq = &lp.eq;
        let n_signals = lp.signals.len() + noise.as_ref().map_or(0, Signal::len);
        let path = actuator.map(|a| ActuatorPath::new(truth, a));
        if path.is_some() {
            lp.delays = loop_delays(design.plant(), truth, actuator);
            lp.true_delays.clear();
        }
        let input = match (&path, lp.true_delays.is_empty()) {
            (Some(_), _) => PlantInput::Explicit,
            (None, false) => PlantInput::TrueDelays,
            (None, true) => PlantInput::Design,
        };
        let e_len = n_signals + m + if input == PlantInput::Design { 0 } else { m };
        let at = InputsAt::new(&lp.layout, m, truth.k(), noise.is_some());
        lp.linear = LinearPart::new(design, truth, eq, &lp.layout, at, input);
        let signals: Vec<&Signal> = [reference, disturbance].into_iter().chain(noise.as_ref()).collect();
        lp.signals = SignalBank::new(&signals);
        lp.e = vec![0.0; e_len];
        lp.actuator = path;
        Ok(lp)
    }

    /// The loop whose simulated plant is `truth`; observers, filters and gains keep the design
    /// model. A truth without the design plant's dimensions, or signals without its m reference
    /// and k disturbance components, is an error naming the key.
    pub fn with_truth(
        design: &'a Design,
        truth: &'a Plant,
        reference: &'a Signal,
        disturbance: &'a Signal,
    ) -> Result<Self, KeyError> {
        super::check_truth(design, truth)?;
        crate::signal::check_signals(design.plant(), reference, disturbance)?;
        let eq = Equations::new(design);
        let layout = Layout::new(&eq);
        let p = design.plant();
        let true_delays = if truth.delays == p.delays { Vec::new() } else { truth.delays.clone() };
        let delays = loop_delays(p, truth, None);
        let (m, q, k) = (eq.m, eq.q, p.k());
        let input = if true_delays.is_empty() { PlantInput::Design } else { PlantInput::TrueDelays };
        Ok(ContinuousLoop {
            linear: LinearPart::new(design, truth, &eq, &layout, InputsAt::new(&layout, m, k, false), input),
            actuator: None,
            C: &truth.C,
            Q: &truth.Q,
            xhat0: &design.plant().xhat0,
            signals: SignalBank::new(&[reference, disturbance]),
            delays,
            y: vec![0.0; m],
            e: vec![0.0; 2 * m + k + true_delays.len()],
            true_delays,
            eta_d: vec![0.0; q],
            xi_d: vec![0.0; q],
            Delta: vec![0.0; q],
            tmp: vec![0.0; q],
            factor: vec![0.0; packed::len(q).max(2 * q)],
            u_d: vec![0.0; m],
            record: None,
            w_scales: filter_bank_scales(design, &eq, &layout),
            layout,
            eq,
        })
    }

    /// Initial state: x(0) = x0, x̂(0) = the design plant's `xhat0` (0 unless given), every other
    /// controller state 0 (the paper's filters and observers start at rest). An x0 that is not n
    /// long is [`PlantError::Length`].
    pub fn initial_state(&self, x0: &DVector<f64>) -> Result<Vec<f64>, PlantError> {
        let n = self.eq.n;
        if x0.len() != n {
            return Err(PlantError::Length { name: "x0", per: "state", expected: n, found: x0.len() });
        }
        let mut s = vec![0.0; self.layout.dim];
        s[self.layout.x..self.layout.x + n].copy_from_slice(x0.as_slice());
        // [z, η̂] = [ξ̂, x̂, …]: x̂ follows ξ̂'s q entries.
        s[self.layout.q..self.layout.q + n].copy_from_slice(self.xhat0.as_slice());
        Ok(s)
    }

    /// Where Ω_i (packed, [`packed`]) sits in the loop's state.
    #[cfg(test)]
    pub(crate) fn omega_range(&self, i: usize) -> std::ops::Range<usize> {
        self.layout.omega[i]..self.layout.omega[i] + packed::len(self.layout.q)
    }

    /// The signals watched for divergence in the state s: ξ̂, x̂, η̂ and x.
    fn watched<'s>(&self, s: &'s [f64]) -> Watched<'s> {
        let (eq, l) = (&self.eq, &self.layout);
        Watched { xi_hat: eq.regressor(s), x_hat: eq.x_hat(s), eta: &s[l.nz..l.x], x: &s[l.x..l.x + eq.n] }
    }

    /// [g; ω] at t and the output y = C x + Q ω (1) in the state s, into the record's buffers.
    fn output(&mut self, t: f64, s: &[f64], rec: &mut Record) {
        self.signals.eval_into_unchecked(t, &mut rec.gw);
        let w = &rec.gw[self.eq.m..];
        let x = self.watched(s).x;
        mat_vec(self.C, x, &mut rec.y, false);
        mat_vec(self.Q, &w[..self.Q.ncols()], &mut rec.y, true);
    }

    /// The commands u_i = −η̂_iᵀ ξ̂ (25) in the state s, into `u`.
    fn commands(&self, s: &[f64], u: &mut [f64]) {
        let (eq, l) = (&self.eq, &self.layout);
        for (i, u) in u.iter_mut().enumerate() {
            *u = command(&s[l.eta(i)..l.eta(i) + l.q], eq.regressor(s));
        }
    }

    /// The plant input u_f = −K x̂(t) + F u_d(t) (5) as the true plant receives it (at its delays,
    /// through its actuator), into `u_f`.
    fn plant_input(&mut self, t: f64, s: &[f64], past: &Past<'_>, u_f: &mut [f64]) {
        let (eq, l) = (&self.eq, &self.layout);
        if let Some(act) = &mut self.actuator {
            act.input(t, s, past, (eq, l), (&mut self.eta_d, &mut self.xi_d), u_f);
            return;
        }
        for i in 0..eq.m {
            let tau = self.true_delays.get(i).copied().unwrap_or(eq.channels[i].delay);
            self.u_d[i] = command_at(eq, l, (t, tau), i, s, past, (&mut self.eta_d, &mut self.xi_d));
        }
        eq.plant_input(s, &self.u_d, u_f);
    }
}

/// What a run records at each output time, and the bounds it watches; kept by the loop, whose
/// [`DelaySystem::observe`] fills it.
struct Record {
    result: SimResult,
    /// Bounds per watched signal (x, x̂, ξ̂, η̂).
    bounds: Peaks,
    /// The run's end when a watched signal crossed its bound.
    diverged: Option<Outcome>,
    /// x and x̂ too ([`super::RunSettings::record_states`]).
    states: bool,
    /// [g; ω] (and the noise n, not read here), y, u, u_f.
    gw: Vec<f64>,
    y: Vec<f64>,
    u: Vec<f64>,
    u_f: Vec<f64>,
    /// −K x̂, u_f's first term.
    kx: Vec<f64>,
}

impl Record {
    /// Ends the run as diverged when a watched signal is beyond its bound at t, otherwise counts
    /// the signals into the peaks.
    fn watch(&mut self, t: f64, watched: Watched<'_>) -> ControlFlow<()> {
        if let Some(diverged) = watched.beyond(t, &self.bounds) {
            self.diverged = Some(diverged);
            return ControlFlow::Break(());
        }
        self.result.peaks.record(&watched);
        ControlFlow::Continue(())
    }
}

impl DelaySystem for ContinuousLoop<'_> {
    fn dim(&self) -> usize {
        self.layout.dim
    }

    fn n_delayed(&self) -> usize {
        self.layout.n_delayed()
    }

    fn n_output(&self) -> usize {
        self.layout.n_output(self.eq.n)
    }

    fn delays(&self) -> &[f64] {
        &self.delays
    }

    /// The adaptive law (33), η̂_i' = μ_i (Y_i − Ω_i η̂_i): linear in η̂_i, stiff when μ_i λ_max(Ω_i) is
    /// large.
    fn implicit(&self) -> std::ops::Range<usize> {
        self.layout.nz..self.layout.x
    }

    /// The estimates η̂_i reach the command u_i = −η̂_iᵀ ξ̂ (25), which the filter banks and the
    /// plant read, multiplied by the regressor: an error δ in one entry moves u_i by ξ̂_j δ. Their
    /// absolute tolerance is `atol` / max(1, max_j |ξ̂_j|), so that the command is held to `atol`
    /// whatever the regressor's units (ξ̂ ≈ 1e5 with forces in newtons, where η̂'s errors within
    /// `atol` would be errors of 1e-2 in u).
    ///
    /// With the normalized regressor the filter banks' rows get `atol` in their own units too:
    /// row r of W_i is s^r/den_i(s) of its input, about ω_c^(r−σ_i) times the input's size
    /// (ω_c = |den_i(0)|^(1/σ_i), the geometric mean of G_ii's pole magnitudes), so its absolute
    /// tolerance is `atol`·ω_c^(r−σ_i). The error norm then does not depend on the unit of time:
    /// with `atol` alone, rows of size α^(σ−r) in a loop written in units α times longer are held
    /// to a relative tolerance of `rtol` where a loop in seconds had `atol` (the paper's example
    /// in hours took 12 % more steps at 1e-6).
    fn absolute_tolerances(&self, s: &[f64], atol: f64, out: &mut [f64]) {
        let xi = self.eq.regressor(s).iter().fold(1.0f64, |m, v| m.max(v.abs()));
        out[self.layout.nz..self.layout.x].fill(atol / xi);
        for (row, scale) in &self.w_scales {
            out[row.clone()].fill(atol * scale);
        }
    }

    /// max_i μ_i · (Gershgorin bound of λ_max(Ω_i)).
    fn implicit_rate(&self, s: &[f64]) -> f64 {
        let (l, q) = (&self.layout, self.layout.q);
        self.eq.channels.iter().enumerate().fold(0.0, |rate, (i, ch)| {
            rate.max(ch.mu.abs() * packed::max_row_sum(&s[l.omega[i]..l.omega[i] + packed::len(q)], q))
        })
    }

    /// max_i μ_i · (a Rayleigh quotient of Ω_i after [`POWER_STEPS`] power steps), at most the
    /// adaptive law's fastest rate.
    fn implicit_rate_below(&mut self, s: &[f64]) -> f64 {
        let (l, q) = (&self.layout, self.layout.q);
        let work = &mut self.factor;
        self.eq.channels.iter().enumerate().fold(0.0, |rate, (i, ch)| {
            let omega = &s[l.omega[i]..l.omega[i] + packed::len(q)];
            rate.max(ch.mu.abs() * packed::max_eigenvalue_below(omega, q, POWER_STEPS, work))
        })
    }

    /// Per channel (I + c μ_i Ω_i) η̂_i = r_i + c μ_i Y_i, by Cholesky.
    fn solve_implicit(&mut self, _t: f64, c: f64, z: &mut [f64]) -> bool {
        let (l, q) = (&self.layout, self.layout.q);
        for (i, ch) in self.eq.channels.iter().enumerate() {
            let (c_mu, eta) = (c * ch.mu, l.eta(i));
            let (head, rest) = z.split_at_mut(l.x);
            let (Y, omega) = (&rest[l.y[i] - l.x..l.y[i] - l.x + q], &rest[l.omega[i] - l.x..]);
            let x = &mut head[eta..eta + q];
            for (xj, yj) in x.iter_mut().zip(Y) {
                *xj += c_mu * yj;
            }
            if !packed::solve_shifted(omega, c_mu, x, &mut self.factor) {
                return false;
            }
        }
        true
    }

    /// Per channel err_η̂i ← (I + c μ_i Ω_i)⁻¹ err_η̂i, Ω_i at `y`, by Cholesky.
    fn filter_implicit_error(&mut self, c: f64, y: &[f64], err: &mut [f64]) -> bool {
        let (l, q) = (&self.layout, self.layout.q);
        self.eq.channels.iter().enumerate().all(|(i, ch)| {
            let omega = &y[l.omega[i]..l.omega[i] + packed::len(q)];
            packed::solve_shifted(omega, c * ch.mu, &mut err[l.eta(i)..l.eta(i) + q], &mut self.factor)
        })
    }

    /// Between output times the watch of [`DelaySystem::observe`]: a watched signal beyond its
    /// bound at a step's end ends the run as diverged there, and the peaks ([`SimResult::peaks`])
    /// count the step ends too. With a coarse output step a loop would otherwise blow up between
    /// two rows until a budget ended it, naming no signal. So do the peaks of u and u_f
    /// ([`SimResult::peak_uf`]), which a coarse output step would miss in a fast transient.
    fn accepted(&mut self, t: f64, s: &[f64], past: &Past<'_>) -> ControlFlow<()> {
        let Some(mut rec) = self.record.take() else { return ControlFlow::Continue(()) };
        let flow = rec.watch(t, self.watched(s));
        if flow.is_continue() {
            self.commands(s, &mut rec.u);
            self.plant_input(t, s, past, &mut rec.u_f);
            rec.result.record_input_peaks(&rec.u, &rec.u_f);
            if let Some(act) = &self.actuator {
                rec.result.record_demand(&act.demand);
            }
            self.output(t, s, &mut rec);
            rec.result.record_error_peak(&rec.y, &rec.gw[..self.eq.m]);
        }
        self.record = Some(rec);
        flow
    }

    /// Records y, g, u (25), u_f (5) and η̂ (and x, x̂) at t, unless a watched signal is beyond its
    /// bound: then the run ends as diverged.
    fn observe(&mut self, t: f64, s: &[f64], past: &Past<'_>) -> ControlFlow<()> {
        let Some(mut rec) = self.record.take() else { return ControlFlow::Continue(()) };
        let watched = self.watched(s);
        let (x_hat, eta, x) = (watched.x_hat, watched.eta, watched.x);
        let flow = rec.watch(t, watched);
        if flow.is_continue() {
            self.output(t, s, &mut rec);
            let g = &rec.gw[..self.eq.m];
            self.commands(s, &mut rec.u);
            self.plant_input(t, s, past, &mut rec.u_f);
            let states = rec.states.then_some((x, x_hat));
            let (y, u, u_f) = (&rec.y, &rec.u, &rec.u_f);
            rec.result.push(&Sample { t, y, g, u, u_f, eta, states });
            if let Some(act) = &self.actuator {
                rec.result.count_limited(act.limited.iter().map(Cell::get));
                rec.result.record_demand(&act.demand);
            } else {
                mat_vec(&self.eq.K_neg, x_hat, &mut rec.kx, false);
                rec.result.record_uf_terms(&rec.kx, &rec.u_f);
            }
        }
        self.record = Some(rec);
        flow
    }

    fn rhs(&mut self, t: f64, s: &[f64], past: &Past<'_>, ds: &mut [f64]) {
        let eq = &self.eq;
        let l = &self.layout;
        let (m, q) = (eq.m, eq.q);
        // e = [g; ω; n; u_d; u_p].
        let (gw, u_d) = self.e.split_at_mut(self.signals.len());
        self.signals.eval_into_unchecked(t, gw);

        // Delayed command u_i(t − τ_i) = −η̂_iᵀ(t − τ_i) ξ̂(t − τ_i). The row [u_i(t − τ_i), ξ̂ᵀ(t − τ_i)],
        // the input of channel i's filter bank, goes straight into the last row of W_i' (see below).
        let cols = 1 + q;
        for (i, ch) in eq.channels.iter().enumerate() {
            let input = &mut ds[l.w[i] + (ch.sigma() - 1) * cols..l.w[i] + ch.sigma() * cols];
            let (u_in, xi_d) = input.split_at_mut(1);
            if ch.delay > 0.0 {
                past.eval_ranges(t - ch.delay, [(0, &mut *xi_d), (l.eta(i), &mut self.eta_d[..])]);
                u_d[i] = command(&self.eta_d, xi_d);
            } else {
                xi_d.copy_from_slice(eq.regressor(s));
                u_d[i] = command(&s[l.eta(i)..l.eta(i) + q], xi_d);
            }
            u_in[0] = u_d[i];
        }
        // The true plant's input through its actuator, or reading the command at its own delays
        // (`[truth]`).
        if let Some(act) = &mut self.actuator {
            let at = u_d.len() - m;
            let u_p = &mut u_d[at..];
            act.input(t, s, past, (eq, l), (&mut self.eta_d, &mut self.xi_d), u_p);
        } else if !self.true_delays.is_empty() {
            let at = u_d.len() - 2 * m;
            let (u_d, u_true) = u_d[at..].split_at_mut(m);
            for (i, (&tau, u)) in self.true_delays.iter().zip(u_true.iter_mut()).enumerate() {
                *u = if tau == eq.channels[i].delay {
                    u_d[i]
                } else {
                    command_at(eq, l, (t, tau), i, s, past, (&mut self.eta_d, &mut self.xi_d))
                };
            }
        }

        // Plant (1) with the decoupling law (5), observers (6), (14), (20), and y = C x + Q ω: linear
        // in [s; e].
        self.linear.apply(s, &self.e, ds, &mut self.y);
        let g = &self.e[..m];

        // Per channel: G_ii filter bank, H filters and the adaptive law (33).
        for (i, ch) in eq.channels.iter().enumerate() {
            let (w0, w1) = (l.w[i], l.w[i] + ch.sigma() * cols);
            let W = &s[w0..w1];
            let dW = &mut ds[w0..w1];
            // W' = A_i W + e_σ [u_i(t − τ_i), ξ̂ᵀ(t − τ_i)] with A_i the companion matrix of den_i; the
            // last row already holds the input.
            dW[..(ch.sigma() - 1) * cols].copy_from_slice(&W[cols..]);
            let last = &mut dW[(ch.sigma() - 1) * cols..];
            for (r, &a) in ch.tf.den.iter().enumerate() {
                for (d, w) in last.iter_mut().zip(&W[r * cols..(r + 1) * cols]) {
                    *d -= a * w;
                }
            }
            let eps = swapping_error(ch, W, self.y[i] - g[i], &mut self.Delta);

            let inv_beta = 1.0 / eq.beta;
            let (Y, dY) = (&s[l.y[i]..l.y[i] + q], l.y[i]);
            for j in 0..q {
                ds[dY + j] = (self.Delta[j] * eps - Y[j]) * inv_beta;
            }
            let omega = &s[l.omega[i]..l.omega[i] + packed::len(q)];
            let d_omega = &mut ds[l.omega[i]..l.omega[i] + packed::len(q)];
            let eta = &s[l.eta(i)..l.eta(i) + q];
            // Ω_i' = (Δ_iᵀΔ_i − Ω_i)/β and, for η̂_i' = μ_i (Y_i − Ω_i η̂_i), Ω_i η̂_i.
            packed::filter_rate_and_apply(&self.Delta, omega, inv_beta, eta, d_omega, &mut self.tmp);
            for j in 0..q {
                ds[l.eta(i) + j] = ch.mu * (Y[j] - self.tmp[j]);
            }
        }
    }
}

/// The rows of the filter banks W_i with their scales ω_c^(r−σ_i) for the normalized or modal
/// regressor ([`DelaySystem::absolute_tolerances`]), none for the paper's form: its ξ̂ has a size that
/// depends on the filters' time scale anyway, and its runs keep the tolerances they were made with.
fn filter_bank_scales(design: &Design, eq: &Equations, l: &Layout) -> Vec<(std::ops::Range<usize>, f64)> {
    if design.regressor_scaling() == RegressorScaling::Paper {
        return Vec::new();
    }
    let cols = 1 + eq.q;
    let mut scales = Vec::new();
    for (i, ch) in eq.channels.iter().enumerate() {
        let sigma = ch.sigma() as i32;
        let omega_c = ch.tf.den[0].abs().powf(1.0 / f64::from(sigma));
        for r in 0..sigma {
            let start = l.w[i] + r as usize * cols;
            scales.push((start..start + cols, omega_c.powi(r - sigma)));
        }
    }
    scales
}

/// u_j(t − lag), the command (25) of channel j, from the state (lag = 0) or the history; `at` is
/// (t, lag), `scratch` (η̂_j, ξ̂) at t − lag.
#[inline]
fn command_at(
    eq: &Equations,
    l: &Layout,
    (t, lag): (f64, f64),
    j: usize,
    s: &[f64],
    past: &Past<'_>,
    (eta_d, xi_d): (&mut [f64], &mut [f64]),
) -> f64 {
    if lag > 0.0 {
        past.eval_ranges(t - lag, [(0, &mut *xi_d), (l.eta(j), &mut *eta_d)]);
        command(eta_d, xi_d)
    } else {
        command(&s[l.eta(j)..l.eta(j) + l.q], eq.regressor(s))
    }
}

/// The delays the continuous loop reads, positive, sorted and without repeats: the design's τ_i,
/// the true plant's τ_i^true where they differ, and through a non-ideal `actuator` its τ_a,i and
/// τ_a,i + τ_j^true. Their sums are the loop's breakpoints ([`dde::breakpoints`]).
pub(super) fn loop_delays(design: &Plant, truth: &Plant, actuator: Option<&Actuator>) -> Vec<f64> {
    let true_delays = truth.delays_beside(design);
    let a = actuator.filter(|a| !a.is_ideal()).map_or(&[][..], |a| &a.delays[..]);
    let through_actuator = a.iter().copied().chain(a.iter().flat_map(|ta| truth.delays.iter().map(move |tj| ta + tj)));
    let mut delays: Vec<f64> =
        design.delays.iter().chain(true_delays).copied().chain(through_actuator).filter(|&d| d > 0.0).collect();
    delays.sort_by(f64::total_cmp);
    delays.dedup();
    delays
}

/// The true plant's input through its actuator ([`Actuator`]):
/// u_p,i(t) = sat_i(−K_i x̂(t − τ_a,i) + Σ_j F_ij u_j(t − τ_a,i − τ_j^true)), i.e. input (5) delayed
/// by τ_a,i and clipped to [u_min,i, u_max,i].
struct ActuatorPath {
    actuator: Actuator,
    /// τ_j^true: the true plant's delays of the adaptive command.
    command_delays: Vec<f64>,
    /// Scratch: x̂ and the commands u_j at the delayed times.
    x_hat: Vec<f64>,
    u: Vec<f64>,
    /// Per input: whether the limit clipped it at the latest evaluation (shared with the probe).
    limited: Rc<[Cell<bool>]>,
    /// Per input: the controller's u_f before the limit, at the latest evaluation.
    demand: Vec<f64>,
}

impl ActuatorPath {
    fn new(truth: &Plant, actuator: &Actuator) -> Self {
        let m = truth.m();
        ActuatorPath {
            actuator: actuator.clone(),
            command_delays: truth.delays.clone(),
            x_hat: vec![0.0; truth.n()],
            u: vec![0.0; m],
            limited: (0..m).map(|_| Cell::new(false)).collect(),
            demand: vec![0.0; m],
        }
    }

    /// u_p at time t.
    fn input(
        &mut self,
        t: f64,
        s: &[f64],
        past: &Past<'_>,
        (eq, l): (&Equations, &Layout),
        scratch: (&mut [f64], &mut [f64]),
        u_p: &mut [f64],
    ) {
        let (eta_d, xi_d) = scratch;
        for (i, u_i) in u_p.iter_mut().enumerate() {
            let ta = self.actuator.delays[i];
            if ta > 0.0 {
                past.eval_ranges(t - ta, [(eq.q, &mut self.x_hat[..])]);
            } else {
                self.x_hat.copy_from_slice(eq.x_hat(s));
            }
            for (j, u_j) in self.u.iter_mut().enumerate() {
                *u_j = command_at(eq, l, (t, ta + self.command_delays[j]), j, s, past, (&mut *eta_d, &mut *xi_d));
            }
            // Row i of (5) from the controller's own matrices: (−K)_i x̂ + F_i u.
            let mut v = 0.0;
            for c in 0..self.x_hat.len() {
                v += eq.K_neg[(i, c)] * self.x_hat[c];
            }
            for j in 0..self.u.len() {
                v += eq.F[(i, j)] * self.u[j];
            }
            let (clipped, limited) = self.actuator.clip(i, v);
            self.limited[i].set(limited);
            (*u_i, self.demand[i]) = (clipped, v);
        }
    }
}

/// How the simulated plant's input enters the linear part.
#[derive(Debug, Clone, Copy, PartialEq)]
enum PlantInput {
    /// u_f = −K x̂ + F u_d as the controller computes it.
    Design,
    /// −K x̂ + F u_d at the true delays (the entries u_p of e).
    TrueDelays,
    /// B u_p with u_p the whole input computed in `rhs` (an actuator).
    Explicit,
}

/// Where the loop's inputs sit among the operator's columns (after the state's `dim`): e = [g; ω;
/// n; u_d; u_p].
#[derive(Debug, Clone, Copy)]
struct InputsAt {
    g: usize,
    w: usize,
    noise: Option<usize>,
    u_d: usize,
    u_p: usize,
}

impl InputsAt {
    fn new(l: &Layout, m: usize, k: usize, noise: bool) -> Self {
        let (g, w) = (l.dim, l.dim + m);
        let u_d = w + k + if noise { m } else { 0 };
        InputsAt { g, w, noise: noise.then_some(w + k), u_d, u_p: u_d + m }
    }
}

/// The loop's linear part as a sparse operator: the rows of x (plant (1) with u_f = −K x̂ + F u_d,
/// eq. (5)) and of the core z ([`Equations::A_z`], [`Equations::B_z`] with y = C x + Q ω substituted),
/// and the output y = C x + Q ω itself, over the state and e = [g; ω; u_d]. Built once; the products
/// skip the many zeros of the block-structured matrices.
#[derive(Debug, Clone)]
struct LinearPart {
    /// Per row: the index it writes (in the derivative, or in y for the last m rows), its entries
    /// over the state [start, mid) and over e [mid, end) in `cols`/`vals`.
    rows: Vec<(usize, usize, usize, usize)>,
    /// Rows before this one write the derivative; the rest write y.
    n_state_rows: usize,
    cols: Vec<usize>,
    vals: Vec<f64>,
}

impl LinearPart {
    /// `p` is the simulated plant, `input` how its input enters; `at` places e's entries. The
    /// noise n (when `at` has it) adds to the measured y that the core and the y rows read.
    fn new(design: &Design, p: &Plant, eq: &Equations, l: &Layout, at: InputsAt, input: PlantInput) -> Self {
        let (n, m, nz, dim) = (eq.n, eq.m, eq.nz, l.dim);
        // B F, as the design computed it when the plant is the design model.
        let B_f = if p == design.plant() { design.B_f().clone() } else { &p.B * design.F() };
        let By = eq.B_z.columns(0, m);
        // Each block: (matrix, first row it feeds in the derivative, first column it reads).
        let x_hat = eq.q;
        // Rows of y are numbered after the state's.
        let mut blocks: Vec<(DMatrix<f64>, usize, usize)> = vec![
            (p.A.clone(), l.x, l.x),
            (p.D.clone(), l.x, at.w),
            (eq.A_z.clone(), 0, 0),
            (By * &p.C, 0, l.x),
            (By * &p.Q, 0, at.w),
            (eq.B_z.columns(m, m).into_owned(), 0, at.g),
            (eq.B_z.columns(2 * m, m).into_owned(), 0, at.u_d),
            (p.C.clone(), dim, l.x),
            (p.Q.clone(), dim, at.w),
        ];
        match input {
            PlantInput::Design => blocks.extend([(-(&p.B * design.K()), l.x, x_hat), (B_f, l.x, at.u_d)]),
            PlantInput::TrueDelays => blocks.extend([(-(&p.B * design.K()), l.x, x_hat), (B_f, l.x, at.u_p)]),
            PlantInput::Explicit => blocks.push((p.B.clone(), l.x, at.u_p)),
        }
        if let Some(e_n) = at.noise {
            blocks.extend([(By.into_owned(), 0, e_n), (DMatrix::identity(m, m), dim, e_n)]);
        }
        let mut entries: Vec<(usize, usize, f64)> = Vec::new();
        for (M, row0, col0) in &blocks {
            for r in 0..M.nrows() {
                for c in 0..M.ncols() {
                    if M[(r, c)] != 0.0 {
                        entries.push((row0 + r, col0 + c, M[(r, c)]));
                    }
                }
            }
        }
        // In row order, state columns (< dim) before e's; two blocks on one entry are merged.
        entries.sort_by_key(|&(r, c, _)| (r, c));
        entries.dedup_by(|later, kept| {
            let same = (later.0, later.1) == (kept.0, kept.1);
            if same {
                kept.2 += later.2;
            }
            same
        });
        let targets = (0..nz).chain(l.x..l.x + n).chain(dim..dim + m);
        let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        let mut entries = entries.into_iter().peekable();
        for t in targets {
            let start = cols.len();
            let mut mid = None;
            while let Some((_, c, v)) = entries.next_if(|&(r, _, _)| r == t) {
                if c >= dim {
                    mid.get_or_insert(cols.len());
                }
                cols.push(if c >= dim { c - dim } else { c });
                vals.push(v);
            }
            rows.push((if t < dim { t } else { t - dim }, start, mid.unwrap_or(cols.len()), cols.len()));
        }
        debug_assert!(entries.next().is_none(), "every block feeds a row of the operator");
        LinearPart { rows, n_state_rows: nz + n, cols, vals }
    }

    /// ds[row] (or y[row]) = Σ val·s[col] + Σ val·e[col] for every row of the operator.
    #[inline]
    fn apply(&self, s: &[f64], e: &[f64], ds: &mut [f64], y: &mut [f64]) {
        #[inline(always)]
        fn row(lp: &LinearPart, s: &[f64], e: &[f64], &(_, start, mid, end): &(usize, usize, usize, usize)) -> f64 {
            let mut acc = 0.0;
            for (&c, &v) in lp.cols[start..mid].iter().zip(&lp.vals[start..mid]) {
                acc += v * s[c];
            }
            for (&c, &v) in lp.cols[mid..end].iter().zip(&lp.vals[mid..end]) {
                acc += v * e[c];
            }
            acc
        }
        let (state_rows, y_rows) = self.rows.split_at(self.n_state_rows);
        for r in state_rows {
            ds[r.0] = row(self, s, e, r);
        }
        for r in y_rows {
            y[r.0] = row(self, s, e, r);
        }
    }
}

/// The most memory a continuous run's delay history gets by default, whatever the problem: 1 GiB
/// ([`default_max_history_bytes`]). The recorded rows come on top; they are known before the run (at
/// most [`crate::settings::MAX_OUTPUT_SAMPLES`]).
pub const MAX_HISTORY_BYTES: usize = 1 << 30;

/// The default history bound's margin over the records within τ_max of a run that spends its step
/// budget evenly ([`default_max_history_bytes`]): the legitimate runs of `tests/stiff.rs` hold at
/// most 2.94 times that (the quadruple tank at rtol = 1e-10, its stiff start before the switch to
/// the implicit law), a runaway 19 to 33 times.
pub const HISTORY_MARGIN: f64 = 8.0;

/// Steps of the default budget per unit of ρ·t_end at [`BUDGET_TOLERANCE`] ([`default_max_steps`]).
pub const BUDGET_STEPS_PER_RATE: f64 = 100.0;

/// The default budget's least number of steps.
pub const BUDGET_MIN_STEPS: usize = 10_000;

/// The tolerance at which [`BUDGET_STEPS_PER_RATE`] holds; a tighter one scales it by
/// (BUDGET_TOLERANCE / tol)^(1/p), p the order of the method's error in the step ([`default_max_steps`]).
pub const BUDGET_TOLERANCE: f64 = 1e-9;

/// Below this tolerance rounding, not the tolerance, sets the steps: the budget counts no tighter one.
const BUDGET_TOLERANCE_FLOOR: f64 = 1e-14;

/// DOP853 is stable on the negative real axis for h|λ| ≤ 6.1 (the bound of `dop853.f`'s own
/// stiffness test): on a rate λ it needs at least |λ| t / 6.1 steps.
pub const DOP853_STABLE_H_RATE: f64 = 6.1;

/// On [`Method::Explicit`](dde::Method::Explicit) DOP853 keeps h·μλ_max(Ω̄) ≤ this
/// ([`dde::Options::rate`]): R(−x) follows e^(−x) within 0.2 % up to 3 (3 % at
/// [`dde::DOP853_ACCURATE_H_RATE`], the cap on the loop's other rates), a margin for a run's Ω above its
/// average Ω̄. A grid inverter's LCL loop (μλ_max = 4.7ρ) at rtol = atol = 1e-6 was 11 % of u_f's
/// peak off with its steps at DOP853's stability bound, 9.4e-4 with h·μλ_max ≤ 3.5, 5.5e-8 with 3.
pub const EXPLICIT_ADAPTATION_H_RATE: f64 = 3.0;

/// The rate whose DOP853 steps (h·rate ≤ [`dde::DOP853_ACCURATE_H_RATE`]) are those of the cap
/// h·μλ_max ≤ [`EXPLICIT_ADAPTATION_H_RATE`] on the adaptation rate `rate`.
fn explicit_capped_rate(rate: f64) -> f64 {
    rate * dde::DOP853_ACCURATE_H_RATE / EXPLICIT_ADAPTATION_H_RATE
}

/// A run forced to [`Method::Explicit`](dde::Method::Explicit) may take this many times the steps
/// its cap on the adaptive law's rate sets ([`EXPLICIT_ADAPTATION_H_RATE`]).
pub const BUDGET_STABILITY_MARGIN: f64 = 2.0;

/// How [`explicit_stiff_warning`] names the setting where the scenario (or a study's
/// `[simulation]`) holds it; a front end's flag or argument names itself.
pub const EXPLICIT_IN_FILE: &str = "simulation.method = \"explicit\"";

/// The caution before a continuous run forced onto DOP853 ([`Method::Explicit`](dde::Method::Explicit))
/// whose adaptive law is stiff (beyond [`STIFF_RATIO`]·ρ, or from [`EXPECT_STIFF_RATIO`]·ρ): its
/// steps are capped at h·μλ_max ≤ [`EXPLICIT_ADAPTATION_H_RATE`] whatever the accuracy needs, and
/// the caution says how many that takes (a magnetic bearing at 1e5 times the stiffness threshold
/// advanced 1.3 ms a second with nothing said, its budget allowing ~45 minutes). `None` otherwise. `set_by` names the setting as the user gave it (`simulation.method = "explicit"`, or
/// a front end's own flag or argument), which the caution starts with.
pub fn explicit_stiff_warning(run: &Run<'_>, set_by: &str) -> Option<String> {
    if !explicit_on_stiff_law(run) {
        return None;
    }
    let (rate, rho) = run.rates();
    let unit = run.design.plant().time_unit;
    let steps = rate * run.settings.t_end / EXPLICIT_ADAPTATION_H_RATE;
    // Whether the history of the longest delay can hold those steps (the quadruple tank at μ = 1
    // cannot).
    let history = history_beyond_budget(run, explicit_capped_rate(rate));
    Some(format!(
        "{set_by} on a stiff adaptive law: μλ_max = {rate:.3e}/{unit} is {}× the loop's fastest other rate ρ = {rho:.3e}/{unit}, and DOP853 keeps h·μλ_max ≤ {EXPLICIT_ADAPTATION_H_RATE} to follow it accurately (its stability bound is {DOP853_STABLE_H_RATE}), so the run takes about {steps:.1e} steps (at the rate Ω settles to){history}; the default method, \"auto\", takes the adaptive law implicitly",
        settings::fmt_ratio(rate / rho)
    ))
}

/// Whether `run` is continuous, forced onto DOP853, and its adaptive law stiff: beyond
/// [`STIFF_RATIO`]·ρ, or expected at DOP853's bound ([`Run::expects_stiff`]); what
/// [`explicit_stiff_warning`] words. The averaged law it needs is computed on DOP853 runs only.
pub fn explicit_on_stiff_law(run: &Run<'_>) -> bool {
    let Loop::Continuous(integrator) = &run.settings.mode else { return false };
    if integrator.method != dde::Method::Explicit {
        return false;
    }
    let (rate, rho) = run.rates();
    rate > STIFF_RATIO * rho || run.expects_stiff()
}

/// The rate ρ that caps a continuous run's steps ([`dde::Options::rate`]): the loop's fastest rate
/// ([`loop_rate`]), and on [`Method::Explicit`](dde::Method::Explicit) the adaptive law's
/// μλ_max(Ω̄) too, scaled so that h·μλ_max ≤ [`EXPLICIT_ADAPTATION_H_RATE`], as DOP853 then
/// integrates it alone.
pub fn step_rate(run: &Run<'_>, method: dde::Method) -> f64 {
    match method {
        dde::Method::Explicit => {
            let (rate, rho) = run.rates();
            explicit_capped_rate(rate).max(rho)
        }
        _ => run.loop_rate(),
    }
}

/// The default step budget of a continuous run, from the problem's time scales, its adaptation
/// rate, the method and the tolerance tol = min(rtol, atol):
///
/// N = [`BUDGET_MIN_STEPS`] + [`BUDGET_STEPS_PER_RATE`]·(ρ·t_end + t_end/τ_min)·f·g + S,
///
/// ρ = [`loop_rate`], τ_min the shortest positive delay (a step is at most τ_min long),
/// f = max(1, ([`BUDGET_TOLERANCE`]/tol)^(1/3)) (3: ARK4(3)6L\[2\]SA's error order on a stiff
/// block, measured: 10.6× the steps for 1000× the tolerance; DOP853's steps, which follow
/// tol^(−1/8) while accuracy sets them, grow as fast near rounding: a ball and beam at 1e-12 took
/// 18.7 M steps on either method, and DOP853 alone had ended at the history's budget of p = 8) and,
/// with r = [`adaptation_rate`]:
/// * [`Method::Explicit`](dde::Method::Explicit) (DOP853 alone): g = 1 and
///   S = [`BUDGET_STABILITY_MARGIN`]·r·t_end/[`EXPLICIT_ADAPTATION_H_RATE`], the steps its cap on
///   the adaptive law's rate takes;
/// * the automatic and the implicit method: S = 0 and
///   g = 1 + ½·log10(max(1, r / ([`STIFF_RATIO`]·ρ))): the implicit steps do not follow the rate,
///   but grow by up to 0.6× per decade of stiffness (measured 1.16× to 2.7× over three decades).
///
/// A healthy run takes a few steps per unit of ρ·t (the paper's example about 2 at rtol = 1e-9,
/// 41 on the implicit path at 1000 times its stiffness onset), so the budget leaves a margin of 2.5
/// or more; a loop that turns stiff as it blows up spends it in seconds. The delay history's own
/// budget follows from N ([`default_max_history_bytes`]).
pub fn default_max_steps(run: &Run<'_>, integrator: &Integrator) -> usize {
    let (design, truth, t_end) = (run.design, run.truth, run.settings.t_end);
    let delays = design.plant().delays.iter().chain(&truth.delays).filter(|&&d| d > 0.0);
    let tau_min = delays.fold(f64::INFINITY, |a, &d| a.min(d));
    let (rate, rho) = run.rates();
    let scale = rho * t_end + if tau_min.is_finite() { t_end / tau_min } else { 0.0 };
    let tol = integrator.rtol.min(integrator.atol).max(BUDGET_TOLERANCE_FLOOR);
    let (g, stability) = match integrator.method {
        dde::Method::Explicit => (1.0, BUDGET_STABILITY_MARGIN * rate * t_end / EXPLICIT_ADAPTATION_H_RATE),
        dde::Method::Auto | dde::Method::Implicit => {
            let stiffness = if rho > 0.0 { rate / (STIFF_RATIO * rho) } else { 0.0 };
            (1.0 + 0.5 * stiffness.max(1.0).log10(), 0.0)
        }
    };
    let f = (BUDGET_TOLERANCE / tol).cbrt().max(1.0);
    let steps = BUDGET_MIN_STEPS as f64 + BUDGET_STEPS_PER_RATE * scale * f * g + stability;
    if steps.is_finite() && steps < usize::MAX as f64 {
        steps as usize
    } else {
        usize::MAX
    }
}

/// The default memory budget of a continuous run's delay history, in bytes, from its step budget N
/// (`max_steps`, the default [`default_max_steps`] or the one given), its longest delay τ_max, its
/// horizon t_end and the bytes of one history record (8·(8·n_d + 9) for n_d delayed states: ξ̂, x̂
/// and every η̂_i):
///
/// H = max([`BUDGET_MIN_STEPS`], ⌈[`HISTORY_MARGIN`]·N·τ_max/t_end⌉) records,
/// bytes = min([`MAX_HISTORY_BYTES`], 2·H·`record_bytes`).
///
/// N·τ_max/t_end is what the history holds (the records of the last τ_max) when a run spends its
/// whole budget evenly; the floor lets any run spend the budget's least number of steps within one
/// delay, and the factor 2 is the ring's doubling. A runaway concentrates its steps where it blows
/// up and ends with `history_too_large` at a fraction of the 1 GiB cap.
pub fn default_max_history_bytes(max_steps: usize, tau_max: f64, t_end: f64, record_bytes: usize) -> usize {
    let even = if tau_max > 0.0 { max_steps as f64 * tau_max / t_end } else { 0.0 };
    let records = (HISTORY_MARGIN * even).ceil().max(BUDGET_MIN_STEPS as f64);
    let bytes = 2.0 * records * record_bytes as f64;
    if bytes < MAX_HISTORY_BYTES as f64 {
        bytes as usize
    } else {
        MAX_HISTORY_BYTES
    }
}

/// The adaptive law's fastest rate max_i μ_i λ_max(Ω̄_i) in 1/s, Ω̄_i the mean that Ω_i of (33)
/// settles to under the signals (`averaged`, [`crate::averaged`]); 0 where that is not finite.
pub fn adaptation_rate(design: &Design, averaged: &Averaged) -> f64 {
    let rate = averaged.channels.iter().zip(design.mu()).fold(0.0, |r: f64, (c, mu)| r.max(mu * c.lambda_max()));
    if rate.is_finite() {
        rate
    } else {
        0.0
    }
}

/// Power steps of [`DelaySystem::implicit_rate_below`].
const POWER_STEPS: usize = 8;

/// Where the adaptation rate max_i μ_i λ_max(Ω̄_i) is at least this many times ρ, the automatic
/// method hands η̂ to the implicit method at DOP853's first step beyond its stability bound, for the
/// rest of the run ([`dde::Options::expect_stiff`]). DOP853's accuracy-limited steps resolve ρ (h·ρ ≈ 1), so such a
/// loop sits at the bound once Ω has filled, where DOP853 is 10–1000× less accurate than its
/// tolerance (docs/performance.md, "DOP853 at its stability bound"). Measured on the plants of
/// `examples/` and `crates/quell/tests/data`: every loop at 5.8ρ or more reached h·rate 4, none at
/// 0.95ρ or less went past 2.6 (the paper's example: 0.37ρ and 0.95ρ); and loops at 3–5ρ that
/// reached it were as far off (a servo in ms at 3ρ 270× its implicit run's error, a 747's lateral
/// loop at 4.99ρ 50×).
pub const EXPECT_STIFF_RATIO: f64 = 3.0;

/// A channel whose adaptation rate μ_i λ_max(Ω̄_i) exceeds this many times the loop's fastest other
/// rate ρ is flagged stiff: an explicit integrator's steps are then bounded by the adaptive law's
/// stability (|h μ λ| ≲ 5 for DOP853), not by the accuracy the signals need, which takes steps of a
/// fraction of 1/ρ; at 100 ρ the adaptive law sets the step and costs tens of times the steps the
/// signals need.
pub const STIFF_RATIO: f64 = 100.0;

/// ρ, the fastest rate the loop is built from besides the adaptive law: the largest of
/// [`loop_rates`].
pub fn loop_rate(design: &Design, truth: &Plant, signals: [&Signal; 2]) -> f64 {
    loop_rates(design, truth, signals).iter().map(|&(_, r)| r).filter(|r| r.is_finite()).fold(0.0, f64::max)
}

/// The rates the loop is built from besides the adaptive law, each with what sets it: the largest
/// |λ| of the true plant's A, of A − BK, A − LC, G_g, G_ω and the channels' G_ii(s), 1/β, and the
/// signals' highest frequency (1/s). NaN where an eigenvalue solver refuses the matrix.
pub fn loop_rates(design: &Design, truth: &Plant, signals: [&Signal; 2]) -> [(&'static str, f64); 8] {
    // The balanced QR of `linalg` (nalgebra's Schur iterates forever on a non-finite matrix);
    // a matrix it refuses gives NaN, left out below.
    let radius = |M: &DMatrix<f64>| {
        crate::linalg::eigenvalues(M).map_or(f64::NAN, |e| e.iter().fold(0.0, |r: f64, z| r.max(z.norm())))
    };
    let largest = |e: &[nalgebra::Complex<f64>]| e.iter().fold(0.0, |r: f64, z| r.max(z.norm()));
    let channels = design.channels().iter().fold(0.0, |r: f64, c| r.max(largest(&c.poles)));
    let frequency = signals
        .iter()
        .flat_map(|s| s.components.iter().flat_map(|c| c.harmonics.iter().map(|h| h.frequency.abs())))
        .fold(0.0, f64::max);
    let plant = if truth.A == design.plant().A { "plant.A" } else { "truth.A" };
    [
        (plant, radius(&truth.A)),
        ("design.channel_poles (A − BK)", largest(design.decoupled_eigenvalues())),
        ("the observer (A − LC)", largest(design.observer_eigenvalues())),
        ("design.reference_filter_poles", radius(design.G_g())),
        ("design.disturbance_filter_poles", radius(design.G_w())),
        ("design.channel_poles (G_ii)", channels),
        ("1/design.beta", 1.0 / design.beta()),
        ("the signals' highest frequency", frequency),
    ]
}

/// The rate of a run's band-limited measurement noise, 2π·bandwidth (rad per unit of time); 0
/// without noise or band limit.
fn noise_rate(run: &Run<'_>) -> f64 {
    run.settings.noise.as_ref().and_then(|n| n.bandwidth).map_or(0.0, |b| std::f64::consts::TAU * b)
}

/// Steps beyond which [`fast_rate_warning`] cautions: about ten seconds of a run.
pub const FAST_RATE_STEPS: f64 = 1e6;

/// A rate this many times the next fastest (from another key) is named as the culprit.
const FAST_RATE_OUTLIER: f64 = 100.0;

/// A caution before a continuous run whose fastest rate ρ ([`loop_rates`], the adaptive law aside,
/// and band-limited noise) makes it take more than [`FAST_RATE_STEPS`] steps on any method, or
/// hold more records in its delay history than its memory budget allows (`budgets`):
/// DOP853's steps are at most [`dde::DOP853_ACCURATE_H_RATE`]/ρ (the implicit method's shorter),
/// and the implicit method takes only η̂ implicitly. Names the rate's source and, where it is a hundred times the next, says to bring
/// it to the loop's time scale (β = 1e-7 on the paper's example: 1/β = 1e7/s against 9/s, 2 s took
/// 3.7 s and 646 MB before the history's cap ended it, with nothing said of β; β = 1e-6 over 5 s
/// filled the 1 GiB cap at t = 2.9 s). Beside it, a shortest delay that caps the steps. `None`
/// otherwise.
pub fn fast_rate_warning(run: &Run<'_>) -> Option<String> {
    let rate = FastRate::of(run).filter(|f| f.steps > FAST_RATE_STEPS || f.history_over(run)).map(|f| f.text(run));
    let cautions: Vec<String> = rate.into_iter().chain(short_delay_warning(run)).collect();
    (!cautions.is_empty()).then(|| cautions.join("; "))
}

/// A caution before a run whose delay τ_i (the truth's where it has its own, or the actuator's) is
/// at least the horizon t_end: channel i's command, or input i altogether, never reaches the plant
/// in the run, which then "completes" with no adaptation at all (a delay of 1e300 s had run
/// silently; helper tryout, 2026-12-07), as a delay typed in the wrong unit does. For a front end
/// that shows no run's advice before it ends (Python); not a study's: a short horizon is a cheap
/// sweep's choice.
pub fn delay_beyond_horizon(run: &Run<'_>) -> Option<String> {
    let (plant, t_end) = (run.design.plant(), run.settings.t_end);
    let unit = plant.time_unit;
    // The delays the run simulates: the truth's where it has its own.
    let key = if run.truth.delays != plant.delays { "truth.delays" } else { "plant.delays" };
    let actuator: &[f64] = run.settings.actuator.as_ref().map_or(&[], |a| &a.delays);
    let commands = run.truth.delays.iter().enumerate().map(|(i, &tau)| (key, "'s adaptive command", i, tau));
    let inputs = actuator.iter().enumerate().map(|(i, &tau)| ("truth.actuator_delays", "'s whole input u_f", i, tau));
    let (key, what, i, tau) = commands.chain(inputs).find(|&(.., tau)| tau >= t_end)?;
    Some(format!(
        "{key}[{i}] = {} {unit} is at least t_end = {} {unit}: channel {}{what} never reaches the plant in this run; check the delay's unit (plant.time_unit = \"{unit}\") or lengthen simulation.t_end",
        settings::fmt_short(tau),
        settings::fmt_short(t_end),
        i + 1,
    ))
}

/// A shortest delay τ_min that caps the steps at τ_min so that t_end takes more than
/// [`FAST_RATE_STEPS`] ([`Run::delay_floor`]) and more than the loop's fastest rate takes
/// ([`FastRate`]): delays [1e-6, 0.1] on the paper's loop took 10 s for 2.35 of its 100 s, with
/// nothing said (a history too long for such steps is refused instead). A τ_min shorter than the
/// loop's fastest time constant 1/ρ is said to be best set to 0; a longer one is no approximation
/// to drop (a 1 s delay in a loop of ρ = 71/s had been told so, where the rate bound the steps).
fn short_delay_warning(run: &Run<'_>) -> Option<String> {
    // From τ_min itself: ⌈t_end/τ_min⌉ as a count saturates (1e-300 s had been named 5.4e-19 s).
    let tau_min = run.shortest_delay()?;
    let floor = (run.settings.t_end / tau_min).ceil();
    let rate = FastRate::of(run);
    let binding = rate.as_ref().is_none_or(|r| floor > r.steps);
    (floor > FAST_RATE_STEPS && binding).then(|| {
        let unit = run.design.plant().time_unit;
        let drop = match rate {
            Some(r) if tau_min * r.rho < 1.0 => format!(
                "; a delay this short beside the loop's fastest time constant 1/ρ = {} {unit} is best set to 0",
                settings::fmt_4(1.0 / r.rho)
            ),
            _ => String::new(),
        };
        format!(
            "the shortest delay, {} {unit}, caps every step at its length, so t_end = {} {unit} takes at least {floor:.1e} steps{drop}",
            settings::fmt_4(tau_min),
            settings::fmt_short(run.settings.t_end)
        )
    })
}

/// For a run that its step budget or the history's cap ended: the caution of
/// [`fast_rate_warning`] where one rate is a hundred times the next, whatever the steps (a study's
/// β = 1e-5 at a budget of 1,000); `None` where no rate stands out (a runaway is then the likelier
/// cause).
pub fn fast_rate_culprit(run: &Run<'_>) -> Option<String> {
    let fast = FastRate::of(run)?;
    fast.outlier().then(|| fast.text(run))
}

/// For a run that its step budget or the history's cap ended (`result`'s outcome): the rate far
/// faster than the loop that may be why ([`fast_rate_culprit`]), so that `quell run` and Python
/// name it as a study's row does (observer poles at −1e4 on the paper's loop filled the cap in
/// 1.8 s, and the message named only a small design.beta among its causes), and the watched signal
/// nearest its divergence bound by then ([`Peaks::nearest_bound`]: a loop blowing up, or not; the
/// outcome names no signal). `None` otherwise.
pub fn budget_culprit(run: &Run<'_>, result: &SimResult) -> Option<String> {
    let Some(Outcome::TooManySteps { .. } | Outcome::HistoryTooLarge { .. }) = &result.outcome else { return None };
    let growth = result.peaks.nearest_bound(&run.divergence_bounds());
    let parts: Vec<String> = [growth, fast_rate_culprit(run)].into_iter().flatten().collect();
    (!parts.is_empty()).then(|| parts.join("; "))
}

/// The fastest of a run's rates, its source, the steps it sets over t_end, and the next fastest
/// from another key (the channel poles set both A − BK and G_ii).
struct FastRate {
    name: &'static str,
    rho: f64,
    steps: f64,
    next: Option<(&'static str, f64)>,
}

impl FastRate {
    fn of(run: &Run<'_>) -> Option<FastRate> {
        let Loop::Continuous(_) = &run.settings.mode else { return None };
        let mut rates = loop_rates(run.design, run.truth, [run.reference, run.disturbance]).to_vec();
        rates.push(("2π·noise.bandwidth", noise_rate(run)));
        rates.sort_by(|a, b| b.1.total_cmp(&a.1));
        let mut finite = rates.into_iter().filter(|r| r.1.is_finite());
        let (name, rho) = finite.next()?;
        let key = |n: &str| n.split(" (").next().unwrap_or(n).to_string();
        let next = finite.find(|r| key(r.0) != key(name)).filter(|r| r.1 > 0.0);
        Some(FastRate { name, rho, steps: rho * run.settings.t_end / dde::DOP853_ACCURATE_H_RATE, next })
    }

    fn outlier(&self) -> bool {
        self.next.is_some_and(|(_, r)| self.rho > FAST_RATE_OUTLIER * r)
    }

    fn history_over(&self, run: &Run<'_>) -> bool {
        let (_, bytes, budget) = history_at(run, self.rho);
        bytes > budget as f64
    }

    fn text(&self, run: &Run<'_>) -> String {
        let (name, rho, unit) = (self.name, self.rho, run.design.plant().time_unit);
        let outlier = self.next.filter(|_| self.outlier());
        let ratio = outlier.map_or(String::new(), |(next_name, r)| {
            format!(", {}× the next fastest ({next_name}, {r:.3e}/{unit})", settings::fmt_ratio(rho / r))
        });
        // A plant's own rate is not a choice: only the controller's are brought to its scale.
        let advice = match outlier {
            Some(_) if !name.ends_with(".A") => "; bring it to the loop's time scale",
            _ => "",
        };
        format!(
            "{name} sets the loop's fastest rate, {rho:.3e}/{unit}{ratio}: every method's steps follow it (DOP853 takes steps up to {} over it, where it still integrates it accurately, and the implicit method takes only η̂ implicitly), so t_end = {} {unit} takes at least {:.1e} steps{}{advice}",
            dde::DOP853_ACCURATE_H_RATE,
            crate::settings::fmt_short(run.settings.t_end),
            self.steps,
            history_beyond_budget(run, self.rho)
        )
    }
}

/// For DOP853 steps at h·`rho` = [`dde::DOP853_ACCURATE_H_RATE`]: the longest delay τ_max, the
/// bytes of the records those steps put within it (twice that: the history's ring doubles), and
/// the run's history budget.
fn history_at(run: &Run<'_>, rho: f64) -> (f64, f64, usize) {
    let Loop::Continuous(integrator) = &run.settings.mode else { return (0.0, 0.0, usize::MAX) };
    let (p, q) = (run.design.plant(), run.design.q());
    let delays = loop_delays(p, run.truth, run.settings.actuator.as_ref());
    let tau_max = delays.iter().copied().fold(0.0, f64::max).min(run.settings.t_end);
    let record = dde::record_bytes(delayed_prefix(p.n(), q, p.m()));
    let budget = budgets(run, integrator, record, &delays).1;
    (tau_max, 2.0 * rho * tau_max / dde::DOP853_ACCURATE_H_RATE * record as f64, budget)
}

/// Where the delay history of steps at rate `rho` ([`history_at`]) outgrows the run's memory
/// budget: by how much, as a clause of a caution; empty otherwise.
fn history_beyond_budget(run: &Run<'_>, rho: f64) -> String {
    let (tau_max, bytes, budget) = history_at(run, rho);
    if bytes <= budget as f64 {
        return String::new();
    }
    format!(
        " and its delay history (the steps of the last τ_max = {} {}) at least {} MB, beyond the run's budget of {} MB, where the run would end",
        crate::settings::fmt_4(tau_max),
        run.design.plant().time_unit,
        mib(bytes),
        mib(budget as f64)
    )
}

/// Every check of a continuous run (the settings, the signals, the truth, the delays against the
/// horizon); the loop, ready to run.
pub(super) fn check<'a>(run: &Run<'a>, integrator: &Integrator) -> Result<ContinuousLoop<'a>, SimError> {
    let (st, truth) = (&run.settings, run.truth);
    check_run(run)?;
    settings::check_tolerances(integrator.rtol, integrator.atol)?;
    if st.precision != crate::controller::Precision::F64 {
        return Err(KeyError::new(
            "simulation.precision",
            format!(
                "{} applies to the discrete controller of a sampled-data run; give simulation.sample_time, or leave precision out for the continuous loop",
                st.precision.name()
            ),
        )
        .into());
    }
    let (actuator, noise) = (st.actuator.as_ref(), st.noise.as_ref());
    let sys = ContinuousLoop::with_physics(run.design, truth, run.reference, run.disturbance, actuator, noise)?;
    let horizon = (st.t_end, run.design.plant().time_unit);
    settings::check_integrator_horizon(horizon)?;
    settings::check_integrator_signal("reference", run.reference, horizon)?;
    settings::check_integrator_signal("disturbance", run.disturbance, horizon)?;
    if let Some(b) = noise.and_then(|n| n.bandwidth) {
        check_noise_bandwidth(b, run.loop_rate(), horizon.1)?;
    }
    // The history's memory first: its least τ is usually the larger (delays [1e-12, 2] s over
    // 20 s were told τ ≥ 2e-9 by the step limit, then τ ≥ 6.95e-6 by the history).
    check_history_span(run, integrator, dde::record_bytes(sys.n_delayed()), sys.delays())?;
    settings::check_integrator_delays("plant.delays", &run.design.plant().delays, horizon)?;
    settings::check_integrator_delays("truth.delays", &truth.delays, horizon)?;
    if let Some(a) = actuator {
        settings::check_integrator_delays("truth.actuator_delays", &a.delays, horizon)?;
    }
    Ok(sys)
}

/// Bytes in whole MiB, as the history's own message counts them (its 1 GiB cap is "1024 MB"); three
/// significant digits beyond a million (a 1e-300 s delay's history printed 1.02996826171875e298).
fn mib(bytes: f64) -> String {
    let m = (bytes / 1048576.0).round().max(1.0);
    settings::fmt_short(if m < 1e6 { m } else { settings::significant(m, 3) })
}

/// The shortest delay τ_min caps the integrator's steps at τ_min while the delay history holds
/// the records of the last τ_max (of the whole run when t_end is shorter): at least τ_max/τ_min
/// of them, twice that with the ring's doubling, must fit the run's history budget
/// ([`budgets`]), unless a step budget given below that count ends the run first. A CSTR with
/// delays [1e-7, 0.1] min passed every check, ran 2.2 s into 808 MB and failed at the cap, blamed
/// on a blow-up.
fn check_history_span(run: &Run<'_>, integrator: &Integrator, record: usize, delays: &[f64]) -> Result<(), KeyError> {
    let (tau_min, tau_max) = delays.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &d| (a.min(d), b.max(d)));
    // Over a run shorter than τ_max the history holds the whole run.
    let tau_max = tau_max.min(run.settings.t_end);
    let budget = budgets(run, integrator, record, delays).1 as f64;
    let records = (tau_max / tau_min).ceil();
    let bytes = 2.0 * records * record as f64;
    // A step budget given below the records ends the run first, as its giver chose.
    let cut = integrator.max_steps.is_some_and(|n| (n as f64) < records);
    if !(tau_min > 0.0 && tau_min.is_finite()) || bytes <= budget || cut {
        return Ok(());
    }
    let (p, truth, unit) = (run.design.plant(), run.truth, run.design.plant().time_unit);
    let found = |key: &str, d: &[f64]| d.iter().position(|&x| x == tau_min).map(|i| format!("{key}[{i}]"));
    let actuator = run.settings.actuator.as_ref().map_or(&[][..], |a| &a.delays[..]);
    let key = found("plant.delays", &p.delays)
        .or_else(|| found("truth.delays", &truth.delays))
        .unwrap_or_else(|| found("truth.actuator_delays", actuator).unwrap_or("truth.actuator_delays".into()));
    let fits = settings::significant(2.0 * tau_max * record as f64 / budget * 1.001, 3);
    Err(KeyError::new(
        key,
        format!(
            "τ = {} {unit} caps the integrator's steps at τ while the delay history holds the last τ_max = {} {unit}: at least {:.1e} records of {record} bytes, {} MB with the ring's doubling, beyond the run's memory budget of {} MB; expected 0 (no delay) or τ ≥ {} {unit} (over t_end = {} {unit}, at least {:.1e} steps), or a shorter longest delay",
            settings::fmt_short(tau_min),
            settings::fmt_4(tau_max),
            records,
            mib(bytes),
            mib(budget),
            settings::fmt_4(fits),
            settings::fmt_short(run.settings.t_end),
            (run.settings.t_end / fits).ceil()
        ),
    ))
}

/// Band-limited noise beyond this many times the loop's fastest rate ρ (in cycles, ρ/2π) is refused:
/// the loop filters it out, and the integrator resolves it at several steps a cycle (a bandwidth of
/// 1e6 on a loop at 1e2 ran out of memory as a blow-up does). At 100 the noise takes at most about
/// 27 steps per unit of ρ·t (0.27 steps a radian measured at 1,000 Hz on the paper's loop), within
/// the default budget's 100 ([`BUDGET_STEPS_PER_RATE`]); at 1,000 a healthy run at 1,400 Hz failed
/// that budget, and a budget raised for the noise let a noisy runaway fill the history's cap.
const MAX_NOISE_OVER_RATE: f64 = 1e2;

/// `noise.bandwidth` (cycles per unit of time) within [`MAX_NOISE_OVER_RATE`] × ρ/2π.
fn check_noise_bandwidth(bandwidth: f64, rho: f64, unit: crate::settings::TimeUnit) -> Result<(), KeyError> {
    let max = MAX_NOISE_OVER_RATE * rho / std::f64::consts::TAU;
    if bandwidth <= max || !max.is_finite() {
        return Ok(());
    }
    let per = match unit {
        crate::settings::TimeUnit::Seconds => "Hz".to_string(),
        _ => format!("cycles per {unit}"),
    };
    Err(KeyError::new(
        "noise.bandwidth",
        format!(
            "expected at most {} {per} ({}× the loop's fastest rate ρ = {} rad/{unit}, over 2π: the loop filters out noise beyond its bandwidth, and the integrator would resolve it at several steps a cycle), found {}; about 10× the loop's bandwidth is the usual choice",
            settings::fmt_short(crate::settings::three_digits_down(max)),
            settings::fmt_ratio(MAX_NOISE_OVER_RATE),
            settings::fmt_4(rho),
            settings::fmt_short(bandwidth)
        ),
    ))
}

/// The step budget and the delay history's byte budget of `run`, with history records of `record`
/// bytes and the loop's `delays`: the integrator's, or [`default_max_steps`] and
/// [`default_max_history_bytes`].
fn budgets(run: &Run<'_>, integrator: &Integrator, record: usize, delays: &[f64]) -> (usize, usize) {
    let max_steps = integrator.max_steps.unwrap_or_else(|| default_max_steps(run, integrator));
    let tau_max = delays.iter().copied().fold(0.0, f64::max);
    let history = integrator
        .max_history_bytes
        .unwrap_or_else(|| default_max_history_bytes(max_steps, tau_max, run.settings.t_end, record));
    (max_steps, history)
}

/// The most bytes the continuous loop of `run` holds beyond its record: its delay history's budget
/// ([`budgets`]); the history's records carry the n_d = n + q + m·q delayed states z = (ξ̂, x̂) and η̂.
pub(super) fn history_bound(run: &Run<'_>, integrator: &Integrator) -> usize {
    let (p, q) = (run.design.plant(), run.design.q());
    let record = dde::record_bytes(delayed_prefix(p.n(), q, p.m()));
    budgets(run, integrator, record, &loop_delays(p, run.truth, run.settings.actuator.as_ref())).1
}

/// The continuous loop of `run` ([`Run::simulate`]), integrated as `integrator` says: the plant
/// (the truth) with input u_f (5) delayed by τ_i^true, or through the settings' actuator, and the
/// controller's observers and filters reading y plus the settings' noise. [`SimResult::limited`]
/// reports how often each actuator limit clipped.
pub(super) fn simulate(
    run: &Run<'_>,
    integrator: &Integrator,
    mut on_progress: impl FnMut(f64) -> ControlFlow<()>,
) -> Result<SimResult, SimError> {
    let mut sys = check(run, integrator)?;
    let (st, truth) = (&run.settings, run.truth);
    let Integrator { rtol, atol, method, .. } = *integrator;
    // with_truth has checked x0's length (check_truth).
    let s0 = sys.initial_state(&truth.x0).map_err(|e| KeyError::new("truth.x0", e.to_string()))?;
    let history = vec![0.0; sys.n_delayed()];
    let (m, q, n) = (sys.eq.m, sys.eq.q, sys.eq.n);
    sys.record = Some(Record {
        result: SimResult {
            time_unit: run.design.plant().time_unit,
            ..SimResult::new(m, q, n, RunStats::Continuous(dde::Stats::default()))
        },
        bounds: run.bounds(),
        diverged: None,
        states: st.record_states,
        gw: vec![0.0; sys.signals.len()],
        y: vec![0.0; m],
        u: vec![0.0; m],
        u_f: vec![0.0; m],
        kx: vec![0.0; m],
    });
    let record = dde::record_bytes(sys.n_delayed());
    let (max_steps, max_history_bytes) = budgets(run, integrator, record, sys.delays());
    // The history's ring may double past its length: half the budget in records.
    let max_history_len = max_history_bytes / (2 * record);
    let opts = Options {
        rtol,
        atol,
        max_steps,
        max_history_len,
        method,
        expect_stiff: run.expects_stiff(),
        rate: step_rate(run, method),
        ..Options::default()
    };
    let mut outcome = Outcome::Completed;
    // The loop records each sample (observe); here only the progress and an interruption, at each
    // sample and every PROGRESS_EVERY steps between them.
    let mut since = 0;
    let solved = dde::solve_events(&mut sys, 0.0, &s0, &history, st.t_end, st.output_step, &opts, |event| {
        let t = match event {
            dde::Event::Output(t, _) => t,
            dde::Event::Step(t) => {
                since += 1;
                if since < PROGRESS_EVERY {
                    return ControlFlow::Continue(());
                }
                t
            }
        };
        since = 0;
        if on_progress(t).is_break() {
            outcome = Outcome::Interrupted { t };
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    });
    let Record { mut result, diverged, .. } = sys.record.take().expect("the loop keeps its record");
    if let Some(diverged) = diverged {
        outcome = diverged;
    }
    let (stats, ended) = match solved {
        Ok(stats) => (stats, None),
        Err(dde::SolveError::TooManySteps { t, stats }) => (stats, Some(Outcome::TooManySteps { t, max_steps })),
        Err(dde::SolveError::HistoryTooLong { t, stats }) => {
            (stats, Some(Outcome::HistoryTooLarge { t, max_bytes: max_history_bytes }))
        }
        Err(dde::SolveError::StepSizeTooSmall { t, stats, .. }) => (stats, Some(Outcome::StepSizeTooSmall { t })),
        // The loop's own state, history and delays (positive: zero delays are filtered out).
        Err(e @ dde::SolveError::Input { .. }) => return Err(KeyError::new("simulation", e.to_string()).into()),
    };
    result.stats = RunStats::Continuous(stats);
    result.outcome = Some(ended.unwrap_or(outcome));
    Ok(result)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_loop_refuses_signals_and_a_state_of_the_wrong_lengths() {
        let s = crate::Scenario::from_toml(crate::scenario::PAPER_EXAMPLE).unwrap();
        let d = s.design().unwrap();
        // Signals without m = 2 and k = 2 components, and a short x0, are errors naming the key.
        let mut one = s.reference.clone();
        one.components.pop();
        let e = ContinuousLoop::new(&d, &one, &s.disturbance).map(|_| ()).unwrap_err();
        assert_eq!(e.key, "reference.components");
        let e = ContinuousLoop::new(&d, &s.reference, &one).map(|_| ()).unwrap_err();
        assert_eq!(e.key, "disturbance.components");
        let sys = ContinuousLoop::new(&d, &s.reference, &s.disturbance).unwrap();
        let e = sys.initial_state(&DVector::zeros(2)).unwrap_err();
        assert_eq!(e, PlantError::Length { name: "x0", per: "state", expected: 3, found: 2 });
        let s0 = sys.initial_state(&DVector::from_vec(vec![1.0, 2.0, 3.0])).unwrap();
        assert_eq!(s0.iter().filter(|&&v| v != 0.0).copied().collect::<Vec<_>>(), [1.0, 2.0, 3.0]);
    }
}
