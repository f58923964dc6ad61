//! Simulation of the closed loop, through one door: a [`Run`] of a design on its (true) plant
//! with a reference and a disturbance, in the loop its [`RunSettings`] name ([`Loop`]): the
//! continuous loop (the delay equation, integrated as [`Integrator`] says) or the sampled-data loop
//! with the discrete [`Controller`](crate::Controller). Either returns one [`SimResult`], whose
//! [`Outcome`] says how the run ended.

pub(crate) mod closed_loop;
pub(crate) mod dde;
mod divergence;
mod input_line;
pub(crate) mod memory;
pub(crate) mod noise;
mod result;
mod sampled;
mod scenario;
pub mod settle;

use std::ops::ControlFlow;

use crate::averaged::Averaged;
use crate::controller::{ControllerError, Precision};
use crate::design::Design;
use crate::plant::Plant;
use crate::settings::{self, Actuator, KeyError};
use crate::signal::{check_signals, Signal};

pub use crate::settings::MeasurementNoise;
pub use closed_loop::{
    adaptation_rate, budget_culprit, default_max_history_bytes, default_max_steps, delay_beyond_horizon,
    explicit_on_stiff_law, explicit_stiff_warning, fast_rate_culprit, fast_rate_warning, loop_rate, loop_rates,
    step_rate, BUDGET_MIN_STEPS, BUDGET_STABILITY_MARGIN, BUDGET_STEPS_PER_RATE, BUDGET_TOLERANCE,
    DOP853_STABLE_H_RATE, EXPECT_STIFF_RATIO, EXPLICIT_ADAPTATION_H_RATE, EXPLICIT_IN_FILE, FAST_RATE_STEPS,
    HISTORY_MARGIN, MAX_HISTORY_BYTES, STIFF_RATIO,
};
pub use dde::{Method, Stats};
pub(crate) use divergence::smallest_gain;
pub use divergence::{Peaks, Watched, DIVERGENCE_BOUND, WATCHED};
pub use memory::{runs_memory_bytes, Held, MIN_RUNS_MEMORY_BYTES};
pub use noise::{band_limited, NOISE_SINES};
pub use result::{ChannelFigures, ChannelSummary, Outcome, RunStats, Sample, SimResult, ROUNDING_SHARE};
pub(crate) use sampled::fine_sample_time;
pub use sampled::{
    coarse_sample_warning, is_coarse, output_step_fixes, sample_time_need, SampledController, COARSE_SAMPLE,
};
pub use settle::{Settle, Settling};

/// The front door as `docs/running.md` shows it, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../../../../docs/running.md")]
struct RunningDoc;

/// Why a run cannot start: a setting or signal out of range (named by its scenario key), or a
/// controller that cannot run at the sample time.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    #[error(transparent)]
    Input(#[from] KeyError),
    #[error(transparent)]
    Controller(#[from] ControllerError),
}

/// Which closed loop a run simulates.
#[derive(Debug, Clone, PartialEq)]
pub enum Loop {
    /// The continuous loop: plant (1), controller (5)–(33), integrated as a delay equation.
    Continuous(Integrator),
    /// The sampled-data loop: the discrete controller every `sample_time` seconds, the plant advanced
    /// exactly between samples with its input held.
    Sampled { sample_time: f64 },
}

/// How the continuous loop is integrated: tolerances, method and budgets.
#[derive(Debug, Clone, PartialEq)]
pub struct Integrator {
    pub rtol: f64,
    pub atol: f64,
    /// [`Method::Auto`] by default: DOP853, implicit in η̂ while it is stiff.
    pub method: Method,
    /// Most solver steps ([`Outcome::TooManySteps`] beyond); `None`: [`default_max_steps`], derived
    /// from the problem.
    pub max_steps: Option<usize>,
    /// Most bytes the delay history may hold ([`Outcome::HistoryTooLarge`] beyond); `None`:
    /// [`default_max_history_bytes`], derived from the step budget and the problem (at most
    /// [`MAX_HISTORY_BYTES`]).
    pub max_history_bytes: Option<usize>,
}

impl Integrator {
    /// Tolerances `rtol`, `atol`, the automatic method, the default budgets.
    pub fn new(rtol: f64, atol: f64) -> Self {
        Integrator { rtol, atol, method: Method::Auto, max_steps: None, max_history_bytes: None }
    }
}

/// What a run is asked for: its horizon, its loop and what the true plant adds to the model.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSettings {
    pub t_end: f64,
    /// Time between recorded samples; in the sampled-data loop a whole multiple of `sample_time`.
    pub output_step: f64,
    /// Whether `output_step` was chosen (a scenario's default is not: a sample time offered need
    /// not divide it, since the default follows the sample time; [`crate::scenario::Simulation`]).
    pub output_step_given: bool,
    /// The continuous loop (with its integrator) or the sampled-data loop (with its sample time).
    pub mode: Loop,
    /// A watched signal above this magnitude counts as divergence ([`Watched`]).
    pub divergence_bound: f64,
    /// Bounds per watched signal (x, x̂, ξ̂, η̂) below `divergence_bound`: a signal beyond its bound
    /// counts as divergence too. Studies set these to a factor times the nominal run's
    /// [`SimResult::peaks`] (docs/studies.md, "Runaway"); `None` by default.
    pub runaway: Option<Peaks>,
    /// Measurement noise on the y the controller reads: white per sample (sampled-data loop only),
    /// or band-limited with a bandwidth (the same n(t) in both loops).
    pub noise: Option<MeasurementNoise>,
    /// The true plant's actuator (delay on u_f, limits; in fractions of a sample in the sampled-data loop);
    /// `None`: the plant receives u_f.
    pub actuator: Option<Actuator>,
    /// Record the plant state x and the observer state x̂ too ([`SimResult::x`]); off by default.
    pub record_states: bool,
    /// The discrete controller's arithmetic in the sampled-data loop: f64, or a single-precision
    /// build's, emulated ([`Precision::F32`]: constants, inputs and states rounded to f32); the
    /// continuous loop has none other than f64. A controller given by [`Run::controller`] keeps its
    /// own.
    pub precision: Precision,
}

impl RunSettings {
    /// Settings of a run in loop `mode`: no noise, an ideal actuator, the default divergence bound
    /// [`DIVERGENCE_BOUND`], no runaway bounds, no states recorded.
    pub fn new(t_end: f64, output_step: f64, mode: Loop) -> Self {
        RunSettings {
            t_end,
            output_step,
            output_step_given: true,
            mode,
            divergence_bound: DIVERGENCE_BOUND,
            runaway: None,
            noise: None,
            actuator: None,
            record_states: false,
            precision: Precision::F64,
        }
    }

    /// The continuous loop at tolerances `rtol`, `atol` ([`Integrator::new`]).
    pub fn continuous(t_end: f64, output_step: f64, rtol: f64, atol: f64) -> Self {
        RunSettings::new(t_end, output_step, Loop::Continuous(Integrator::new(rtol, atol)))
    }

    /// The sampled-data loop at `sample_time`.
    pub fn sampled(t_end: f64, output_step: f64, sample_time: f64) -> Self {
        RunSettings::new(t_end, output_step, Loop::Sampled { sample_time })
    }

    /// The continuous loop's step budget (`None`: [`default_max_steps`], derived from the problem).
    /// A sampled-data run takes t_end / sample_time controller steps, known before it starts; a
    /// budget for it is an error naming `max_steps`.
    pub fn set_max_steps(&mut self, max_steps: Option<usize>) -> Result<(), KeyError> {
        match (&mut self.mode, max_steps) {
            (Loop::Continuous(integrator), _) => integrator.max_steps = max_steps,
            (Loop::Sampled { .. }, None) => {}
            (Loop::Sampled { sample_time }, Some(_)) => {
                return Err(KeyError::new("max_steps", {
                    let after = crate::controller::discrete::whole_samples(self.t_end, *sample_time);
                    format!(
                            "a step budget applies to the continuous loop; this sampled-data run takes {} controller steps (one at t = 0, then t_end / sample_time = {after}), known before it starts: leave max_steps out",
                            after + 1
                        )
                }))
            }
        }
        Ok(())
    }
}

/// Between recorded samples, a run reports its progress (and can be interrupted) every this many
/// solver or controller steps ([`Run::simulate`]): about 2 ms of the paper's loop, so an output step
/// as long as the run still leaves Ctrl-C prompt.
pub const PROGRESS_EVERY: usize = 256;

/// One run of the closed loop: a design, the plant simulated (its model unless [`Run::truth`]
/// gives the true one), the reference g and disturbance ω, and the settings; [`Run::simulate`]
/// carries it out. Built by [`Run::new`], or from a scenario by [`Run::of`].
///
/// ```
/// use std::ops::ControlFlow;
/// use quell::scenario::{Scenario, PAPER_EXAMPLE};
/// use quell::sim::{Run, RunSettings};
///
/// let s = Scenario::from_toml(PAPER_EXAMPLE)?;
/// let design = s.design()?;
/// // 20 s of the continuous loop at rtol = atol = 1e-9, then 20 s sampled every 10 ms.
/// let settings = RunSettings::continuous(20.0, 0.1, 1e-9, 1e-9);
/// let r = Run::new(&design, &s.reference, &s.disturbance, settings).simulate(|_| ControlFlow::Continue(()))?;
/// assert_eq!(r.len(), 201);
/// let sampled = RunSettings::sampled(20.0, 0.1, 0.01);
/// let r = Run::of(&s, &design).settings(sampled).simulate(|_| ControlFlow::Continue(()))?;
/// assert_eq!(r.stats.steps(), 2001);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct Run<'a> {
    design: &'a Design,
    truth: &'a Plant,
    reference: &'a Signal,
    disturbance: &'a Signal,
    settings: RunSettings,
    controller: Option<&'a mut dyn SampledController>,
    /// The states' names (a scenario's `[plant] states`), which a divergence of x or x̂ is named
    /// by too ([`divergence::with_state_name`]).
    state_names: Option<&'a [String]>,
    /// The adaptive law's steady state under the signals, computed once when first needed (by the
    /// step budget and the divergence bounds).
    averaged: std::cell::OnceCell<Averaged>,
    /// ρ ([`loop_rate`]), computed once when first needed (by the step budget, the method and the
    /// noise check).
    rho: std::cell::OnceCell<f64>,
}

impl<'a> Run<'a> {
    /// A run of `design` on its own plant model.
    pub fn new(design: &'a Design, reference: &'a Signal, disturbance: &'a Signal, settings: RunSettings) -> Self {
        Run {
            design,
            truth: design.plant(),
            reference,
            disturbance,
            settings,
            controller: None,
            state_names: None,
            averaged: Default::default(),
            rho: Default::default(),
        }
    }

    /// The simulated plant `truth` in place of the design model (`[truth]`): the plant is
    /// ẋ = A x + B u_p + D ω, y = C x + Q ω with truth's matrices, x(0) = truth.x0, and
    /// u_p = u_f = −K x̂ + F [u_1(t − τ_1^true), …] (through the settings' actuator when there is
    /// one); the observers (6), (20) and the filters of the adaptive law keep the design's matrices
    /// and delays. A truth without the design plant's dimensions is an error naming the key.
    pub fn truth(self, truth: &'a Plant) -> Self {
        Run { truth, ..self }
    }

    /// The plant's states named `names` (n of them) in what the run reports: a divergence of an
    /// entry of x or x̂ names its state, "xhat6 (observer state dPv2)".
    pub fn state_names(self, names: Option<&'a [String]>) -> Self {
        Run { state_names: names, ..self }
    }

    /// These settings in place of the ones given before.
    pub fn settings(self, settings: RunSettings) -> Self {
        Run { settings, ..self }
    }

    /// In the sampled-data loop, `controller` from its current state in place of a new
    /// [`Controller`](crate::Controller) (another implementation of the same equations, e.g.
    /// generated C through FFI); it must run at the settings' sample time. Ignored by the
    /// continuous loop.
    pub fn controller(self, controller: &'a mut dyn SampledController) -> Self {
        Run { controller: Some(controller), ..self }
    }

    /// How many breakpoints t = Σ k_i τ_i up to t_end ([`dde::breakpoints`]) the continuous loop
    /// lands on: the design's, the true plant's and its actuator's delays together
    /// (`closed_loop::loop_delays`), counted without building the loop. 0 for a sampled-data loop.
    pub fn breakpoints(&self) -> usize {
        match &self.settings.mode {
            Loop::Continuous(_) => dde::breakpoints(0.0, &self.loop_delays(), self.settings.t_end).len(),
            Loop::Sampled { .. } => 0,
        }
    }

    /// The least number of steps the continuous loop takes whatever its tolerance: a step is at
    /// most the shortest delay τ_min long (the method of steps), so ⌈t_end/τ_min⌉; 0 for a loop
    /// without delays and for a sampled-data loop.
    pub fn delay_floor(&self) -> usize {
        self.shortest_delay().map_or(0, |tau_min| (self.settings.t_end / tau_min).ceil() as usize)
    }

    /// The continuous loop's shortest delay τ_min, which caps its steps; `None` for a loop without
    /// delays and for a sampled-data loop.
    fn shortest_delay(&self) -> Option<f64> {
        match &self.settings.mode {
            Loop::Continuous(_) => self.loop_delays().first().copied().filter(|tau| tau.is_finite()),
            Loop::Sampled { .. } => None,
        }
    }

    /// The delays the continuous loop reads, ascending (`closed_loop::loop_delays`).
    fn loop_delays(&self) -> Vec<f64> {
        closed_loop::loop_delays(self.design.plant(), self.truth, self.settings.actuator.as_ref())
    }

    /// The bound per watched signal (x, x̂, ξ̂, η̂) without `runaway`'s: `divergence_bound`, times
    /// the state's scale in its coordinates for x and x̂ (max(1, |x(0)|, 1/σ_min(C)), or 1e-6 ×
    /// their nominal size under the signals where that is larger) and the regressor's and the
    /// parameters' nominal sizes beyond 1e6 for ξ̂ and η̂ (a thousandfold margin over them;
    /// docs/errors.md, "Faults during a run"). A watched value within these that ended a run was
    /// stopped by a `runaway` limit, not by divergence.
    pub fn divergence_bounds(&self) -> Peaks {
        let b = self.settings.divergence_bound;
        let avg = self.averaged();
        let (xi, eta) = divergence::regressor_scales(avg);
        let x = b * divergence::nominal_factor(avg.x_peak);
        let scale = divergence::state_scale;
        Peaks([(b * scale(self.truth)).max(x), (b * scale(self.design.plant())).max(x), b * xi, b * eta])
    }

    /// [`Run::divergence_bounds`], at most `runaway`'s; where `runaway` bounds every signal below
    /// `divergence_bound`, the averaged law they need is not computed (a Monte Carlo draw's).
    fn bounds(&self) -> Peaks {
        let b = self.settings.divergence_bound;
        match self.settings.runaway {
            // Every absolute bound is at least b, so the runaway limits decide alone.
            Some(r) if r.0.iter().all(|&r| r <= b) => r,
            Some(r) => {
                let d = self.divergence_bounds();
                Peaks(std::array::from_fn(|k| d.0[k].min(r.0[k])))
            }
            None => self.divergence_bounds(),
        }
    }

    /// The averaged law of the design under the run's signals ([`crate::averaged`]).
    fn averaged(&self) -> &Averaged {
        self.averaged.get_or_init(|| Averaged::new(self.design, self.reference, self.disturbance))
    }

    /// ρ, the loop's fastest rate besides the adaptive law, with the true plant ([`loop_rate`]).
    fn loop_rate(&self) -> f64 {
        *self.rho.get_or_init(|| loop_rate(self.design, self.truth, [self.reference, self.disturbance]))
    }

    /// The adaptation rate max_i μ_i λ_max(Ω̄_i) ([`adaptation_rate`]) and ρ ([`loop_rate`]).
    pub fn rates(&self) -> (f64, f64) {
        (adaptation_rate(self.design, self.averaged()), self.loop_rate())
    }

    /// Whether the adaptive law is expected to hold DOP853 at its stability bound: an adaptation
    /// rate of [`EXPECT_STIFF_RATIO`]·ρ or more (`dde::Options::expect_stiff`).
    pub fn expects_stiff(&self) -> bool {
        let (rate, rho) = self.rates();
        rho > 0.0 && rate >= EXPECT_STIFF_RATIO * rho
    }

    /// Every check the run makes before it starts (settings, signals, truth; in the sampled-data
    /// loop also that the controller can run at the sample time), without running it.
    pub fn check(&self) -> Result<(), SimError> {
        match &self.settings.mode {
            Loop::Continuous(integrator) => closed_loop::check(self, integrator).map(|_| ()),
            Loop::Sampled { sample_time } => {
                sampled::check(self, *sample_time)?;
                crate::Controller::new(self.design, *sample_time)?;
                Ok(())
            }
        }
    }

    /// Simulates the loop from t = 0 to t_end, recording every output step; `on_progress(t)` is
    /// called at each recorded sample and every [`PROGRESS_EVERY`] solver or controller steps
    /// between them, and returning `Break` interrupts the run. The result always
    /// holds what was computed; [`SimResult::outcome`] says how the run ended. The settings and
    /// signals are checked first (horizon, tolerances or sample time, divergence bound, noise,
    /// actuator, m reference and k disturbance components with finite parameters, the truth's
    /// dimensions).
    /// The most bytes this run holds, known before it starts: its record (rows × the numbers of a
    /// row) and the continuous loop's delay history budget, or the sampled loop's delay lines. A
    /// study reserves it before each run ([`runs_memory_bytes`]).
    pub fn memory_bound(&self) -> usize {
        let st = &self.settings;
        let (row_bytes, _) = self.record_row();
        let record = (st.t_end / st.output_step + 1.0) * row_bytes as f64;
        let rest = match &st.mode {
            Loop::Continuous(integrator) => closed_loop::history_bound(self, integrator),
            Loop::Sampled { sample_time } => sampled::delay_line_bound(self, *sample_time),
        };
        (record + rest as f64).min(usize::MAX as f64) as usize
    }

    /// Reserves [`Run::memory_bound`] from the budget that runs under way share
    /// ([`runs_memory_bytes`]), waiting while other runs hold it, until the [`Held`] is dropped;
    /// `None` when `stop` returns true while waiting. Study runs hold it, and so does Python's
    /// `quell.simulate`, which threads may call at once.
    pub fn reserve_memory(&self, stop: &dyn Fn() -> bool) -> Option<Held<'static>> {
        memory::RUNS.hold(self.memory_bound(), stop)
    }

    /// The bytes of one recorded row and what it holds ([`SimResult::row_len`]).
    fn record_row(&self) -> (usize, &'static str) {
        let p = self.design.plant();
        let (width, what) = SimResult::row_len(p.m(), self.design.q(), p.n(), self.settings.record_states);
        (8 * width, what)
    }

    pub fn simulate(self, on_progress: impl FnMut(f64) -> ControlFlow<()>) -> Result<SimResult, SimError> {
        let actuator = self.settings.actuator.as_ref();
        let u_max = actuator.map_or(vec![], |a| a.limits.clone());
        let u_min = actuator.map_or(vec![], |a| (0..a.limits.len()).map(|i| a.lower_limit(i)).collect());
        let names = self.state_names;
        let mut result = match self.settings.mode.clone() {
            Loop::Continuous(integrator) => closed_loop::simulate(&self, &integrator, on_progress),
            Loop::Sampled { sample_time } => sampled::simulate(self, sample_time, on_progress),
        }?;
        (result.u_max, result.u_min) = (u_max, u_min);
        if let (Some(Outcome::Diverged { signal, .. }), Some(names)) = (&mut result.outcome, names) {
            *signal = divergence::with_state_name(signal, names);
        }
        Ok(result)
    }
}

/// The checks both loops make: the horizon, the divergence bound, and the signals against the
/// design's plant (m reference components, k disturbance components, finite parameters).
fn check_run(run: &Run<'_>) -> Result<(), KeyError> {
    let st = &run.settings;
    settings::check_horizon(st.t_end, st.output_step)?;
    let (row_bytes, what) = run.record_row();
    settings::check_record(st.t_end, st.output_step, row_bytes, what)?;
    divergence::check_bound(st.divergence_bound)?;
    check_signals(run.design.plant(), run.reference, run.disturbance)
}

/// A true plant (`[truth]`) must have the design plant's dimensions n, m, k.
pub(crate) fn check_truth(design: &Design, truth: &Plant) -> Result<(), KeyError> {
    let p = design.plant();
    for (name, a, b) in [
        ("A", &truth.A, &p.A),
        ("B", &truth.B, &p.B),
        ("C", &truth.C, &p.C),
        ("D", &truth.D, &p.D),
        ("Q", &truth.Q, &p.Q),
    ] {
        if a.shape() != b.shape() {
            return Err(KeyError::new(
                format!("truth.{name}"),
                format!(
                    "expected {}×{} (the shape of plant.{name}), found {}×{}",
                    b.nrows(),
                    b.ncols(),
                    a.nrows(),
                    a.ncols()
                ),
            ));
        }
    }
    if truth.delays.len() != p.delays.len() || truth.x0.len() != p.x0.len() {
        let (name, a, b) = if truth.delays.len() != p.delays.len() {
            ("delays", truth.delays.len(), p.delays.len())
        } else {
            ("x0", truth.x0.len(), p.x0.len())
        };
        return Err(KeyError::new(
            format!("truth.{name}"),
            format!("expected {} (as plant.{name}), found {a}", crate::settings::entries(b)),
        ));
    }
    truth.validate().map_err(|e| KeyError::new("truth", e.to_string()))
}
