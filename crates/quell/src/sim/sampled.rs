//! Sampled-data simulation: the continuous plant between samples (disturbance acting continuously,
//! input held) with the discrete [`Controller`] in the loop.
//!
//! The plant and the disturbance's exosystem form one linear system, so the plant is advanced
//! *exactly* from sample to sample: [x; w]_{k+1} = Φ [x; w]_k + Γ u_f(k).

use std::ops::ControlFlow;

use nalgebra::{DMatrix, DVector};

use super::divergence::{Peaks, Watched};
use super::input_line::{split_delays, InputLine};
use super::noise::Gaussian;
use super::result::{Outcome, RunStats, Sample, SimResult};
use super::{check_run, Run, SimError, PROGRESS_EVERY};
use crate::controller::discrete;
use crate::controller::{mat_vec, Controller, ControllerError, Precision, SinglePrecision, MAX_MEASUREMENT};
use crate::design::Design;
use crate::linalg::zoh_unchecked;
use crate::plant::Plant;
use crate::settings::{self, KeyError, MeasurementNoise};
use crate::signal::{Signal, SignalBank};

/// T_s·ρ beyond which a sampled-data run gets a warning, ρ the loop's fastest rate
/// ([`super::loop_rate`]): the discrete controller then departs from the continuous design (Åström
/// & Wittenmark's rule of thumb for zero-order-hold control is ω h ≈ 0.1 … 0.6; a maglev at
/// T_s·ρ = 0.34 peaked at 1,186 V against 5.9 V in the continuous loop and did not settle). The
/// adaptation's rate μ_i λ_max(Ω̄_i) is not weighed: T_s times it did not tell the runs apart (a
/// servo at 18 matched its continuous loop, the maglev's automatic design at 0.82 peaked at 85×).
pub const COARSE_SAMPLE: f64 = 0.2;

/// Whether T_s·ρ = `ts_rho` is beyond [`COARSE_SAMPLE`], by more than rounding: T_s = 1 s on a
/// loop of ρ = 0.2 /s (the quadruple tank) gave 0.20000000000000023 and a warning at the bound.
pub fn is_coarse(ts_rho: f64) -> bool {
    ts_rho > COARSE_SAMPLE * (1.0 + 1e-12)
}

/// A warning when `sample_time` is coarse for `design` under g = `reference`, ω = `disturbance`
/// (T_s·ρ > [`COARSE_SAMPLE`]), with the sample time that is not and that a run accepts: every
/// delay whole and, given the `output_step`, dividing it (0.2 s beside an output step of 0.5 s sent
/// the user to a second error).
pub fn coarse_sample_warning(
    design: &Design,
    [reference, disturbance]: [&Signal; 2],
    sample_time: f64,
    output_step: Option<f64>,
) -> Option<String> {
    let rate = super::loop_rate(design, design.plant(), [reference, disturbance]);
    let unit = design.plant().time_unit;
    is_coarse(sample_time * rate).then(|| {
        let slower = match fixed_rate(design, [reference, disturbance], rate) {
            Some(what) if what.starts_with("plant.") => format!("; slower poles cannot lower ρ, which {what} sets"),
            Some(_) => "; slower poles lower ρ little, within twice the signals' highest frequency, which the internal model follows".to_string(),
            None => ", or slower poles: the automatic design chooses them for a sample time set in simulation.sample_time".to_string(),
        };
        format!(
            "simulation.sample_time: T_s = {} {unit} is {}× the loop's fastest time constant 1/ρ (ρ = {} /{unit}: the plant, observer, channel and filter poles, 1/β and the signals' frequencies): the discrete controller may depart from the continuous design; choose {}{slower} (T_s·ρ ≤ {COARSE_SAMPLE} is a bound the sampled loop needs, not one that suffices: compare a sampled run with its continuous loop, as a sampled run's advice does)",
            settings::fmt_time(sample_time),
            settings::fmt_above(sample_time * rate, COARSE_SAMPLE),
            settings::fmt_short(settings::significant(rate, 3)),
            fine_sample_time(design, rate, output_step)
        )
    })
}

/// What sets the loop's rate `rate` where slower poles do not lower it: the plant itself, or the
/// signals' highest frequency with poles within twice it (the internal model's filters sit near the
/// frequencies, and the automatic design's rules start the channel poles at twice them); `None`
/// where poles the design chooses set it beyond that. A converter's 6th harmonic at 2.262 rad/ms
/// set ρ = 4.524 through its channel poles, and the warning had still offered slower poles
/// (helper tryout, 2026-12-07).
fn fixed_rate(design: &Design, signals: [&Signal; 2], rate: f64) -> Option<&'static str> {
    let rates = super::loop_rates(design, design.plant(), signals);
    let frequency = rates.iter().find(|(what, _)| what.starts_with("the signals")).map_or(0.0, |r| r.1);
    let (what, _) = rates.into_iter().find(|&(_, r)| r == rate)?;
    if what.starts_with("plant.") {
        Some(what)
    } else {
        (rate <= 2.0 * frequency * (1.0 + 1e-9)).then_some("the signals' highest frequency")
    }
}

/// What a sampled-data controller of `design` needs, as `quell design` reports it before any
/// sampled run: "T_s ≤ bound (T_s·ρ ≤ [`COARSE_SAMPLE`]), e.g. t …" for the loop's fastest rate ρ
/// under g = `reference`, ω = `disturbance`, and ρ (an automatic design's poles at ρ = 900 /s
/// had needed T_s ≤ 0.22 ms, said only when a run at 0.5 ms departed from its continuous loop).
/// Where t makes a run over `t_end` more than ten million samples, it says how many, and
/// where the delays rather than ρ set t, that (µs delays had offered 5e-7 s for a 100 s run).
/// t divides `output_step` too, where one is given and one within the bound does, else the output
/// step to set with it is named (0.00833335 min had been offered beside 0.5 min, which it does not
/// divide); a default output step follows the sample time and asks nothing of it.
pub fn sample_time_need(
    design: &Design,
    [reference, disturbance]: [&Signal; 2],
    (t_end, output_step): (f64, Option<f64>),
) -> (String, f64) {
    let rate = super::loop_rate(design, design.plant(), [reference, disturbance]);
    let (bound, whole) = sample_time_choice(design, rate, output_step);
    // Delays that only a sample time far below the bound makes whole, at more samples than a run
    // takes in a minute (rounded FOPDT dead times,
    // 0.28333 and 0.26667 min, had offered 1e-5 min for T_s ≤ 0.0338 min; helper tryout): the
    // delays to round, not that sample time to take.
    if let Some(t) = whole.filter(|t| *t < bound / 100.0 && t_end / t > MANY_SAMPLES) {
        let unit = design.plant().time_unit;
        return (
            format!(
                "T_s ≤ {} {unit} (T_s·ρ ≤ {COARSE_SAMPLE}), but the longest that makes plant.delays whole is {} {unit} ({:.1e} samples over t_end = {} {unit}): round plant.delays to whole multiples (0 included) of a sample time near the bound",
                settings::fmt_short(bound),
                settings::fmt_short(t),
                t_end / t,
                settings::fmt_short(t_end)
            ),
            rate,
        );
    }
    let mut need = fine_sample_time_text(design, bound, whole, output_step);
    if let Some(t) = whole.filter(|t| t_end / t > MANY_SAMPLES) {
        // Where the delays, not ρ, set t (well below the bound), what would lengthen it.
        let why = if t < bound / 2.0 {
            ": a sample time nearer the bound needs delays nearer its whole multiples"
        } else {
            ""
        };
        need += &format!(
            " ({:.1e} samples over t_end = {} {}{why})",
            t_end / t,
            settings::fmt_short(t_end),
            design.plant().time_unit
        );
    }
    (need, rate)
}

/// A sampled run's length beyond which [`sample_time_need`] counts its samples: about a minute of
/// simulation at ~10 million samples a minute.
const MANY_SAMPLES: f64 = 1e7;

/// "T_s ≤ bound (T_s·ρ ≤ [`COARSE_SAMPLE`]), e.g. t …": the sample times fine for a loop of rate
/// `rate`, with one that makes the design's delays whole (and divides `output_step`, when given,
/// or else names the output step to set with it); a `[truth]`'s own delays are not seen here, and
/// the run that refuses them names the nearest sample time that makes them whole too.
pub(crate) fn fine_sample_time(design: &Design, rate: f64, output_step: Option<f64>) -> String {
    let (bound, whole) = sample_time_choice(design, rate, output_step);
    fine_sample_time_text(design, bound, whole, output_step)
}

/// The bound T_s ≤ [`COARSE_SAMPLE`]/`rate` (three digits, rounded down) and a sample time within
/// it that makes the design's delays whole and divides `output_step`, when given, where one does;
/// else one that makes the delays whole, if any.
fn sample_time_choice(design: &Design, rate: f64, output_step: Option<f64>) -> (f64, Option<f64>) {
    let bound = settings::three_digits_down(COARSE_SAMPLE / rate);
    // A sample time beyond the bound is no example of one within it (β = 1e-7 had offered 3e-7 s
    // for T_s ≤ 2e-8 s: no shorter one keeps the delay lines within their limit).
    let within = |t: Option<f64>| t.filter(|t| *t < bound);
    let dividing = output_step.and_then(|h| within(discrete::sample_time_dividing(design, bound, h)));
    (bound, dividing.or_else(|| within(discrete::valid_sample_time_at_most(design, bound))))
}

/// [`fine_sample_time`]'s text: `whole` divides `output_step` (when given), or the output step
/// to set with it is named.
fn fine_sample_time_text(design: &Design, bound: f64, whole: Option<f64>, output_step: Option<f64>) -> String {
    let unit = design.plant().time_unit;
    let whole = whole.map_or(String::new(), |t| {
        let also = match output_step {
            Some(h) if discrete::divides(h, t) => " and divides simulation.output_step".to_string(),
            Some(h) => discrete::output_step_note(t, h, "within the bound", unit),
            None => String::new(),
        };
        format!(", e.g. {} {unit}, which makes plant.delays whole{also}", settings::fmt_short(t))
    });
    format!("T_s ≤ {} {unit} (T_s·ρ ≤ {COARSE_SAMPLE}){whole}", settings::fmt_short(bound))
}

/// What the sampled-data loop needs of a discrete controller. [`Controller`] is one; another
/// implementation of the same equations (generated C through FFI, say) can stand in for it in
/// a [`Run`](super::Run) ([`Run::controller`](super::Run::controller)).
pub trait SampledController {
    /// One sample: reads y(k) and g(k), returns the plant input u_f(k) (m entries) to hold until the
    /// next sample, or why it cannot.
    fn step(&mut self, y: &[f64], g: &[f64]) -> Result<&[f64], ControllerError>;
    /// The adaptive command u(k) (25) of the last step.
    fn command(&self) -> &[f64];
    /// ξ̂, x̂ and η̂ after the last step (`x` is left empty: the loop fills in the plant's).
    fn watched(&self) -> Watched<'_>;
    /// The largest |y_i|, |g_i| `step` takes ([`MAX_MEASUREMENT`] unless the controller says less):
    /// a run beyond it ends as diverged, naming the bound where it is below that.
    fn input_bound(&self) -> f64 {
        MAX_MEASUREMENT
    }
}

impl SampledController for SinglePrecision {
    fn step(&mut self, y: &[f64], g: &[f64]) -> Result<&[f64], ControllerError> {
        SinglePrecision::step(self, y, g)
    }
    fn command(&self) -> &[f64] {
        self.controller().command()
    }
    fn watched(&self) -> Watched<'_> {
        self.controller().watched()
    }
    fn input_bound(&self) -> f64 {
        Precision::F32.input_bound()
    }
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

/// Every check of a sampled-data run, in this order: the settings (horizon, sample time, signals
/// for the design's plant, noise, actuator, divergence bound), the truth, the true plant's delay
/// lines ([`true_delay_lines`]), the controller (a
/// new [`Controller`] at `sample_time` when the run brings none: delays whole numbers of samples),
/// the output step (a whole multiple of `sample_time`). Returns that controller and the controller steps
/// per recorded sample.
pub(super) fn check(run: &Run<'_>, sample_time: f64) -> Result<(Option<Controller>, usize), SimError> {
    let st = &run.settings;
    let m = run.design.plant().m();
    check_run(run)?;
    settings::check_sample_time(st.t_end, sample_time)?;
    if let Some(noise) = &st.noise {
        noise.check(m)?;
    }
    if let Some(a) = &st.actuator {
        a.check(m)?;
    }
    super::check_truth(run.design, run.truth)?;
    true_delay_lines(run, sample_time)?;
    let own = match run.controller {
        Some(_) => None,
        None => Some(Controller::new(run.design, sample_time).map_err(|e| {
            if st.output_step_given {
                dividing_output_step(e, run.design, st.output_step)
            } else {
                e
            }
        })?),
    };
    let (T, h, unit) = (sample_time, st.output_step, run.design.plant().time_unit);
    let every = discrete::whole_multiple(h, T).filter(|&k| k >= 1).ok_or_else(|| {
        let (divisor, multiple) = output_step_fixes(run.design, T, h);
        let short = crate::settings::fmt_time;
        let divisor = match divisor {
            Some(d) => format!(", or sample_time to one that divides it, e.g. {} {unit}", short(d)),
            None => format!(" (no sample time near {} {unit} that divides it makes plant.delays whole)", short(T)),
        };
        KeyError::new(
            "simulation.output_step",
            format!(
                "expected a whole multiple of sample_time = {} {unit}, found {} {unit} ({:.6} samples; each recorded row is a controller step); set output_step to a multiple of the sample time, e.g. {} {unit}{divisor}",
                short(T),
                short(h),
                h / T,
                short(multiple),
            ),
        )
    })?;
    Ok((own, every))
}

/// The delay check's offer ([`ControllerError::DelayNotMultiple`], `DelayTooLong`,
/// `DelayLinesTooLarge`) made to divide the output step `h` too, where one near T_s (near the
/// lines' shortest sample time for the last) does ([`discrete::valid_sample_time_near`]); a delay
/// that is not whole is else told with the output step to set beside it. The controller's own
/// check knows no output step: a delay line too long at 3e-8 s had offered 3.0000003e-7 s, which
/// the output step of 0.1 s then refused.
fn dividing_output_step(e: ControllerError, design: &Design, h: f64) -> ControllerError {
    let offer = |near: f64, t: f64| {
        discrete::valid_sample_time_near(&design.plant().delays, h, near, 1 + design.q()).or(Some(t))
    };
    match e {
        ControllerError::DelayNotMultiple { channel, delay, sample_time, ratio, nearest: Some(t), unit, .. }
            if !discrete::divides(h, t) =>
        {
            let nearest = offer(sample_time, t);
            ControllerError::DelayNotMultiple {
                channel,
                delay,
                sample_time,
                ratio,
                nearest,
                output_step: Some(h),
                unit,
            }
        }
        ControllerError::DelayTooLong { channel, delay, sample_time, samples, nearest: Some(t), unit }
            if !discrete::divides(h, t) =>
        {
            ControllerError::DelayTooLong { channel, delay, sample_time, samples, nearest: offer(t, t), unit }
        }
        ControllerError::DelayLinesTooLarge { rows, width, sample_time, at_least, nearest: Some(t), unit }
            if !discrete::divides(h, t) =>
        {
            ControllerError::DelayLinesTooLarge { rows, width, sample_time, at_least, nearest: offer(t, t), unit }
        }
        e => e,
    }
}

/// The true plant's delay lines at T: its own delays of the commands and its actuator's, each
/// within [`discrete::MAX_DELAY_SAMPLES`] samples ([`InputLine`] takes fractions of a sample; the model's
/// delays are the controller's, checked by it).
fn true_delay_lines(run: &Run<'_>, T: f64) -> Result<(), KeyError> {
    let unit = run.design.plant().time_unit;
    split_delays("truth.delays", run.truth.delays_beside(run.design.plant()), (T, unit))?;
    let actuator = run.settings.actuator.as_ref().map_or(&[][..], |a| &a.delays[..]);
    split_delays("truth.actuator_delays", actuator, (T, unit)).map(|_| ())
}

/// The nearest fixes of an output step h that is not a whole number ≥ 1 of samples of T: a sample
/// time that divides h and at which `design`'s delays are whole and fit (the largest ≤ T that
/// divides h, h/⌈h/T⌉, where it passes; an offer that failed the delays' check sent a user back
/// and forth), `None` where none near T does (delays of 1/60 min to six digits beside h = 0.5
/// min: h/60 had been offered all the same), and the multiple of T nearest h, T·round(h/T) (at
/// least T).
pub fn output_step_fixes(design: &Design, T: f64, h: f64) -> (Option<f64>, f64) {
    (discrete::sample_time_dividing(design, T, h), T * (h / T).round().max(1.0))
}

/// The sampled-data loop of `run` ([`Run::simulate`]) at `sample_time`, with the run's controller
/// or a new [`Controller`].
pub(super) fn simulate(
    run: Run<'_>,
    sample_time: f64,
    on_progress: impl FnMut(f64) -> ControlFlow<()>,
) -> Result<SimResult, SimError> {
    let (own, every) = check(&run, sample_time)?;
    let mut run = run;
    let steps = (sample_time, every);
    match (run.controller.take(), own, run.settings.precision) {
        (Some(ctrl), ..) => sampled_loop(&run, ctrl, steps, on_progress),
        (None, Some(mut ctrl), Precision::F64) => sampled_loop(&run, &mut ctrl, steps, on_progress),
        (None, Some(ctrl), Precision::F32) => sampled_loop(&run, &mut SinglePrecision::new(ctrl), steps, on_progress),
        (None, None, _) => unreachable!("check builds a controller for a run without one"),
    }
}

/// An upper estimate of the sampled loop's memory beyond its record ([`Run::memory_bound`]): over
/// the longest delay in samples, the controller's delay lines (1 + q numbers a channel) and the
/// plant's past commands (2 a channel).
pub(super) fn delay_line_bound(run: &Run<'_>, sample_time: f64) -> usize {
    let (p, q) = (run.design.plant(), run.design.q());
    let delays = super::closed_loop::loop_delays(p, run.truth, run.settings.actuator.as_ref());
    let samples = delays.iter().copied().fold(0.0, f64::max) / sample_time + 2.0;
    (samples * (8 * p.m() * (q + 3)) as f64).min(usize::MAX as f64) as usize
}

/// The plant and the disturbance's exosystem as one linear system sampled exactly:
/// [x; w]_{k+1} = Φ [x; w]_k + Σ_r Γ_r u_r(k), y_k = C_y [x; w]_k, from [x; w]_0 = s0, with the
/// input u_r(k) held over segment [s_r T, s_{r+1} T) of the sample ([`InputLine`]) and
/// Γ_r = Φ((1 − s_{r+1})T) Γ((s_{r+1} − s_r)T), Γ(t) = ∫₀ᵗ e^{Ms} ds B (Åström & Wittenmark,
/// Computer-Controlled Systems, §2.3): one segment, Γ(T).
struct ExactPlant {
    Phi: DMatrix<f64>,
    Gamma: Vec<DMatrix<f64>>,
    Cy: DMatrix<f64>,
    s0: DVector<f64>,
}

impl ExactPlant {
    /// The true plant `p` and the disturbance's exosystem sampled exactly at `T`, the input held
    /// over the `segments` of a sample (fractions of it).
    fn new(p: &Plant, disturbance: &Signal, T: f64, segments: impl Iterator<Item = (f64, f64)>) -> Self {
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
        let (Phi, whole) = zoh_unchecked(&M, &Bu, T);
        let segments: Vec<(f64, f64)> = segments.collect();
        let Gamma = if segments.len() == 1 {
            vec![whole]
        } else {
            let after = |end: f64| zoh_unchecked(&M, &Bu, (1.0 - end) * T).0;
            segments.iter().map(|&(start, end)| after(end) * zoh_unchecked(&M, &Bu, (end - start) * T).1).collect()
        };
        // y = [C, Q H] [x; w].
        let mut Cy = DMatrix::zeros(m, n + nw);
        Cy.view_mut((0, 0), (m, n)).copy_from(&p.C);
        Cy.view_mut((0, n), (m, nw)).copy_from(&(&p.Q * &H));
        let mut s0 = DVector::zeros(n + nw);
        s0.rows_mut(0, n).copy_from(&p.x0);
        s0.rows_mut(n, nw).copy_from(&w0);
        ExactPlant { Phi, Gamma, Cy, s0 }
    }
}

/// The plant's side of the sampled-data loop: the plant and the disturbance sampled exactly
/// ([`ExactPlant`]), the true delays, the actuator and the measurement noise, with the signals of
/// one sample.
struct PlantSide {
    /// The plant's order: [x; w] holds x first.
    n: usize,
    Phi: DMatrix<f64>,
    Gamma: Vec<DMatrix<f64>>,
    Cy: DMatrix<f64>,
    /// [x; w] at this sample, and at the next.
    s: DVector<f64>,
    s_next: DVector<f64>,
    line: InputLine,
    noise: Option<Noise>,
    /// y(k), its measurement y(k) + n(t), g(k) and the controller's output u_f(k).
    y: Vec<f64>,
    y_meas: Vec<f64>,
    g: Vec<f64>,
    held: Vec<f64>,
}

impl PlantSide {
    fn new(run: &Run<'_>, T: f64) -> Result<Self, KeyError> {
        let (truth, settings) = (run.truth, &run.settings);
        let model = run.design.plant();
        let delays = (&model.delays[..], truth.delays_beside(model));
        let line = InputLine::new(delays, run.design.F(), settings.actuator.as_ref(), (T, model.time_unit))?;
        let ExactPlant { Phi, Gamma, Cy, s0 } = ExactPlant::new(truth, run.disturbance, T, line.segments());
        let m = truth.m();
        let noise = settings.noise.as_ref().map(|nz| Noise::new(nz, m));
        let (y, y_meas, g, held) = (vec![0.0; m], vec![0.0; m], vec![0.0; m], vec![0.0; m]);
        Ok(PlantSide { n: truth.n(), Phi, Gamma, Cy, s_next: s0.clone(), s: s0, line, noise, y, y_meas, g, held })
    }

    /// y(k), g(k) and the measurement y(k) + n(t) at t = kT.
    fn measure(&mut self, t: f64, reference: &Signal) {
        mat_vec(&self.Cy, self.s.as_slice(), &mut self.y, false);
        reference.eval_into_unchecked(t, &mut self.g);
        self.y_meas.copy_from_slice(&self.y);
        if let Some(noise) = self.noise.as_mut() {
            noise.add(t, &mut self.y_meas);
        }
    }

    /// Takes the controller's output `v`: the plant input u_f(k) at the design's delays.
    fn hold(&mut self, v: &[f64]) {
        self.held.copy_from_slice(v);
    }

    /// The plant's input over sample k from the held output and the step's command `u` (25):
    /// moved to the true delays, then through the actuator ([`InputLine`]); its peaks counted in
    /// `result` over every segment.
    fn input(&mut self, k: usize, u: &[f64], result: &mut SimResult) {
        self.line.apply(k, &self.held, u);
        let m = self.held.len();
        for (held, demand) in self.line.values.chunks(m).zip(self.line.demand.chunks(m)) {
            result.record_input_peaks(u, held);
            if self.line.has_actuator() {
                result.record_demand(demand);
            }
        }
    }

    /// Records sample k at t, unless the loop diverged there or is stopped: `Some` ends the run.
    fn record<C: SampledController + ?Sized>(
        &self,
        t: f64,
        ctrl: &C,
        x_hat: Option<&[f64]>,
        bounds: &Peaks,
        result: &mut SimResult,
        on_progress: &mut impl FnMut(f64) -> ControlFlow<()>,
    ) -> Option<Outcome> {
        if let Some(diverged) = self.watch(t, ctrl, bounds, result) {
            return Some(diverged);
        }
        let watched = Watched { x: &self.s.as_slice()[..self.n], ..ctrl.watched() };
        let states = x_hat.map(|x_hat| (watched.x, x_hat));
        // The plant's input at the sample: the first segment's.
        let u_f = &self.line.values[..self.held.len()];
        result.push(&Sample { t, y: &self.y, g: &self.g, u: ctrl.command(), u_f, eta: watched.eta, states });
        if self.line.has_actuator() {
            result.count_limited(self.line.limited.iter().copied());
        }
        on_progress(t).is_break().then_some(Outcome::Interrupted { t })
    }

    /// The watch at every controller step, rows or not: a watched signal beyond its bound ends the
    /// run as diverged at t (`Some`), else the peaks count it. Checked only at the rows, a run with
    /// an output step of 50 s diverged at 11 s and was named at 35 s, by a controller input of 1e100.
    fn watch<C: SampledController + ?Sized>(
        &self,
        t: f64,
        ctrl: &C,
        bounds: &Peaks,
        result: &mut SimResult,
    ) -> Option<Outcome> {
        let watched = Watched { x: &self.s.as_slice()[..self.n], ..ctrl.watched() };
        let diverged = watched.beyond(t, bounds);
        if diverged.is_none() {
            result.peaks.record(&watched);
        }
        diverged
    }

    /// s ← Φ s + Σ_r Γ_r u_r ([`ExactPlant`]): the next sample's state.
    fn advance(&mut self) {
        mat_vec(&self.Phi, self.s.as_slice(), self.s_next.as_mut_slice(), false);
        for (Gamma, u) in self.Gamma.iter().zip(self.line.values.chunks(self.held.len())) {
            mat_vec(Gamma, u, self.s_next.as_mut_slice(), true);
        }
        std::mem::swap(&mut self.s, &mut self.s_next);
    }
}

/// One controller step at t. A measurement beyond the controller's bound, or a state gone
/// non-finite, ends the run as diverged (as the next record's check would have), not as an error.
fn step_controller<'c, C: SampledController + ?Sized>(
    ctrl: &'c mut C,
    y: &[f64],
    g: &[f64],
    t: f64,
) -> Result<Result<&'c [f64], Outcome>, SimError> {
    // An f32 controller's ±1e12 is far below what a loop diverging reaches: named (a reference of
    // 2e12 had read as a divergence at t = 0).
    let bound = ctrl.input_bound();
    match ctrl.step(y, g) {
        Err(ControllerError::InputOutOfRange { name, index, value }) => {
            let beyond =
                if bound < MAX_MEASUREMENT { format!(", beyond its bound ±{bound:e}") } else { String::new() };
            Ok(Err(Outcome::Diverged { t, signal: format!("{name}{} (controller input{beyond})", index + 1), value }))
        }
        Err(ControllerError::StateNotFinite { value }) => {
            Ok(Err(Outcome::Diverged { t, signal: "u_f (controller output)".to_string(), value }))
        }
        other => Ok(Ok(other?)),
    }
}

/// The loop itself, on checked settings: `T` the sample time, `every` controller steps per
/// recorded sample.
fn sampled_loop<C: SampledController + ?Sized>(
    run: &Run<'_>,
    ctrl: &mut C,
    (T, every): (f64, usize),
    mut on_progress: impl FnMut(f64) -> ControlFlow<()>,
) -> Result<SimResult, SimError> {
    let settings = &run.settings;
    let mut plant = PlantSide::new(run, T)?;
    let n = run.truth.n();
    let precision = settings.precision;
    let stats = |controller_steps| RunStats::Sampled { controller_steps, sample_time: T, precision };
    let mut result = SimResult::new(run.truth.m(), run.design.q(), n, stats(0));
    result.time_unit = run.design.plant().time_unit;
    // x̂(k) at the rows (read before the step moves it to x̂(k + 1)): recorded with the states, and
    // what u_f(k)'s terms are formed from.
    let mut x_hat = vec![0.0; n];
    let mut terms = (!plant.line.has_actuator()).then(|| UfTerms::new(run.design));
    let bounds = run.bounds();
    let mut outcome = Outcome::Completed;
    let mut taken = 0;
    let (grid, rows) = (discrete::Grid::new(T), discrete::Grid::new(settings.output_step));
    for k in 0..=discrete::whole_samples(settings.t_end, T) {
        // The last sample at t_end when t_end is within the whole-number tolerance below k·T, as
        // the continuous loop's last row (t_end = 99.99999999 at T = 0.1 ended at 100).
        let t = grid.at(k).min(settings.t_end);
        plant.measure(t, run.reference);
        let row = k % every == 0;
        if row {
            x_hat.copy_from_slice(ctrl.watched().x_hat);
        }
        match step_controller(ctrl, &plant.y_meas, &plant.g, t)? {
            Ok(v) => {
                if let Some(terms) = terms.as_mut().filter(|_| row) {
                    terms.record(&x_hat, v, &mut result);
                }
                plant.hold(v)
            }
            Err(diverged) => {
                outcome = diverged;
                break;
            }
        }
        plant.input(k, ctrl.command(), &mut result);
        taken += 1;
        if k % every == 0 {
            // Rows at k·output_step, which every sample time accepted as dividing it meets to the
            // whole-number tolerance: T = 0.008333333333 h (τ/2 to ten digits) at an output step of
            // 0.05 h had put rows at 0.049999999998, …, 399.999999984.
            let t_row = rows.at(k / every).min(settings.t_end);
            let x_hat = settings.record_states.then_some(&x_hat[..]);
            if let Some(end) = plant.record(t_row, ctrl, x_hat, &bounds, &mut result, &mut on_progress) {
                outcome = end;
                break;
            }
        } else if let Some(diverged) = plant.watch(t, ctrl, &bounds, &mut result) {
            outcome = diverged;
            break;
        } else if k % PROGRESS_EVERY == 0 && on_progress(t).is_break() {
            outcome = Outcome::Interrupted { t };
            break;
        }
        // After the watch, as the continuous loop's step ends: a sample at which the run diverged
        // is no error of the loop's (and a NaN there would spoil the scale).
        result.record_error_peak(&plant.y, &plant.g);
        plant.advance();
    }
    result.stats = stats(taken);
    result.outcome = Some(outcome);
    Ok(result)
}

/// u_f(k)'s terms at the rows, −K x̂(k) and F u_d(k) = u_f(k) + K x̂(k), for
/// [`SimResult::uf_cancellation`], as the continuous loop records them (a sampled design's report
/// had said 0 where its terms were 350× u_f); not through a true actuator, whose u_f is not the
/// controller's.
struct UfTerms {
    K_neg: DMatrix<f64>,
    kx: Vec<f64>,
}

impl UfTerms {
    fn new(design: &Design) -> Self {
        UfTerms { K_neg: -design.K(), kx: vec![0.0; design.K().nrows()] }
    }

    fn record(&mut self, x_hat: &[f64], u_f: &[f64], result: &mut SimResult) {
        crate::controller::mat_vec(&self.K_neg, x_hat, &mut self.kx, false);
        result.record_uf_terms(&self.kx, u_f);
    }
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
