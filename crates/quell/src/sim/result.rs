//! The one result type every simulation returns and every writer reads.

use serde::{Deserialize, Serialize};

use super::dde::Stats;
use super::divergence::Peaks;
use super::settle::{settling, Settle, Settling};
use crate::settings::TimeUnit;

/// How a run ended.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum Outcome {
    /// Reached t_end.
    Completed,
    /// A state became non-finite or exceeded the divergence bound at time `t`.
    Diverged { t: f64, signal: String, value: f64 },
    /// The solver could not meet the tolerance: its step size underflowed at time `t`.
    StepSizeTooSmall { t: f64 },
    /// The solver needed more than `max_steps` steps by time `t` (`RunSettings::max_steps`).
    TooManySteps { t: f64, max_steps: usize },
    /// The delay history would have held more than `max_bytes` at time `t`
    /// (`Integrator::max_history_bytes`, by default derived from the step budget): the solver's
    /// steps had become tiny, crowded into the last delay.
    HistoryTooLarge { t: f64, max_bytes: usize },
    /// Stopped from outside (e.g. Ctrl-C) at time `t`.
    Interrupted { t: f64 },
}

/// How a run ended, in a phrase: "reached t_end", "diverged at t = 36.75: x2 (plant state) =
/// 1.06e9", …
impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Outcome::Completed => write!(f, "reached t_end"),
            Outcome::Diverged { t, signal, value } => {
                write!(f, "diverged at t = {t}: {signal} = {value:.3e}", t = crate::settings::fmt_instant(*t))
            }
            Outcome::StepSizeTooSmall { t } => {
                write!(f, "the solver's step size underflowed at t = {t}", t = crate::settings::fmt_instant(*t))
            }
            Outcome::TooManySteps { t, max_steps } => {
                write!(
                    f,
                    "the solver needed more than {max_steps} steps by t = {t} (the step budget)",
                    t = crate::settings::fmt_instant(*t)
                )
            }
            Outcome::HistoryTooLarge { t, max_bytes } => {
                write!(
                    f,
                    "the delay history would have exceeded {} MB by t = {t}",
                    max_bytes >> 20,
                    t = crate::settings::fmt_instant(*t)
                )
            }
            Outcome::Interrupted { t } => write!(f, "interrupted at t = {t}", t = crate::settings::fmt_instant(*t)),
        }
    }
}

impl Outcome {
    /// Why a run that did not complete ended, with its likely causes; `raise` names how the step
    /// budget is raised in the front end that started the run; times are in `unit`, the plant's.
    /// `None` for a completed run. Each front end adds where the results up to then are.
    pub fn explain(&self, raise: &str, unit: TimeUnit) -> Option<String> {
        Some(match self {
            Outcome::Completed => return None,
            Outcome::Diverged { t, signal, value } => format!("the closed loop diverged at t = {t} {unit}: {signal} = {value:e}", t = crate::settings::fmt_instant(*t)),
            // Below t = 1e-6 the integrator's absolute floor (1e-14) is near the loop's own steps:
            // that, not the tolerances, is the likely cause (a loop at 5e-12 s a unit; hostile review).
            Outcome::StepSizeTooSmall { t } if t.abs() < 1e-6 => format!(
                "the solver's step size underflowed at t = {t} {unit}: below t = 1 the integrator resolves no step \
                 shorter than 1e-14 {unit}, near the steps of a loop on this time scale; write the model in a longer \
                 unit of time (t → αt: A, B, D, every pole and μ divided by α; delays, β, t_end and output_step \
                 multiplied by it)",
                t = crate::settings::fmt_instant(*t)
            ),
            Outcome::StepSizeTooSmall { t } => format!(
                "the solver's step size underflowed at t = {t} {unit} (the loop is too stiff or blows up there, a signal is \
                 faster than any step can resolve, an input delay is shorter than a step can be, simulation.rtol is tighter \
                 than rounding allows at the loop's stiffness: try it 10× looser, or simulation.atol is too small for a signal \
                 that leaves zero, as the delayed commands do at each delay: give it the smallest size that matters times rtol)",
                t = crate::settings::fmt_instant(*t)
            ),
            Outcome::TooManySteps { t, max_steps } => format!(
                "the solver needed more than {max_steps} steps by t = {t} {unit} (the step budget: the loop turned stiff, as a \
                 loop blowing up does before its states reach the divergence bound, or its adaptation is stiff from the \
                 start, or a signal is faster than a step can follow; raise {raise} if the run is sound)",
                t = crate::settings::fmt_instant(*t)
            ),
            // At the cap no step budget raises it; a stiff loop integrated explicitly lands there.
            Outcome::HistoryTooLarge { t, max_bytes } if *max_bytes >= super::MAX_HISTORY_BYTES => format!(
                "the delay history would have exceeded {} MB by t = {t} {unit} (the memory budget's cap: the solver's steps \
                 had crowded into the last delay, as a loop blowing up does, a stiff loop integrated explicitly \
                 (simulation.method = \"auto\" takes a stiff adaptive law implicitly), or one with a rate far faster \
                 than the rest, such as a small design.beta, which every method's steps follow)",
                max_bytes >> 20,
                t = crate::settings::fmt_instant(*t)
            ),
            Outcome::HistoryTooLarge { t, max_bytes } => format!(
                "the delay history would have exceeded {} MB by t = {t} {unit} (the memory budget: the solver's steps had \
                 crowded into the last delay, as a loop blowing up does; it scales with {raise}, raise that if the run is \
                 sound)",
                max_bytes >> 20,
                t = crate::settings::fmt_instant(*t)
            ),
            Outcome::Interrupted { t } => format!("interrupted at t = {t} {unit}", t = crate::settings::fmt_instant(*t)),
        })
    }
}

/// What a run did, in the figures its loop has.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "loop", rename_all = "snake_case")]
pub enum RunStats {
    /// The continuous loop: the delay-equation integrator's statistics.
    Continuous(Stats),
    /// The sampled-data loop: controller steps taken, at the sample time, in the run's precision
    /// ([`super::RunSettings::precision`]; a controller given by [`super::Run::controller`] is
    /// recorded as the settings say).
    Sampled { controller_steps: usize, sample_time: f64, precision: crate::controller::Precision },
}

impl RunStats {
    /// Steps taken: the integrator's accepted steps, or the controller's steps.
    pub fn steps(&self) -> usize {
        match *self {
            RunStats::Continuous(Stats { steps, .. }) => steps,
            RunStats::Sampled { controller_steps, .. } => controller_steps,
        }
    }
}

/// Signals at t = k·output_step: rows of y, g, e = y − g, u (the adaptive command (25)), the plant
/// input u_f (5), η̂, and optionally the plant and observer states x, x̂.
#[derive(Debug, Clone)]
pub struct SimResult {
    pub m: usize,
    pub q: usize,
    /// Plant order (the width of `x` and `x_hat`).
    pub n: usize,
    pub t: Vec<f64>,
    /// Row-major, `t.len()` rows of m.
    pub y: Vec<f64>,
    pub g: Vec<f64>,
    pub e: Vec<f64>,
    pub u: Vec<f64>,
    /// The plant input u_f = −K x̂ + F u_d (5) as the simulated plant receives it (with `[truth]`'s
    /// delays): what an actuator must deliver. Row-major, rows of m.
    pub u_f: Vec<f64>,
    /// Row-major, `t.len()` rows of m·q (η̂_1, …, η̂_m).
    pub eta: Vec<f64>,
    /// Plant state x and observer state x̂ (6), rows of n; empty unless the run recorded states
    /// (`record_states` in its settings).
    pub x: Vec<f64>,
    pub x_hat: Vec<f64>,
    /// What the loop did (so far, when it stopped early).
    pub stats: RunStats,
    pub outcome: Option<Outcome>,
    /// The largest magnitude of each watched signal (x, x̂, ξ̂, η̂) at the recorded samples and, in the
    /// continuous loop, at the solver's step ends.
    pub peaks: Peaks,
    /// Per channel, max |u_i| and max |u_f,i| between the recorded rows as well: at every solver
    /// step's end (continuous loop) or controller step (sampled). An actuator's peak in a fast
    /// transient falls between rows (a ball and beam reached |u_f| = 214 V at t = 5 ms where rows
    /// 0.1 apart read 5.6). Empty where a loop tracked none; [`SimResult::figures`] takes the larger.
    pub peak_u: Vec<f64>,
    pub peak_uf: Vec<f64>,
    /// Per input, max |u_f,i| the controller asked for before the true actuator's limit (`[truth]`
    /// u_max) clipped it, at the rows and between them as [`SimResult::peak_uf`]: what an actuator
    /// limit is checked against (`u_f` holds what the plant received, at most u_max). Empty without
    /// an actuator.
    pub peak_demand: Vec<f64>,
    /// Per channel, max |e_i| = |y_i − g_i| at the rows and between them as [`SimResult::peak_uf`]:
    /// the scale of a regulated channel's error (g = 0), which rows a coarse output step apart
    /// would set by where they fall (a boiler's drum level peaked at 6.9e-4 between rows 1 min apart
    /// that read 2.3e-4). Empty where a loop tracked none; [`SimResult::peak_error`] takes the larger.
    pub peak_e: Vec<f64>,
    /// Per channel, the larger magnitude of u_f's two terms, (K x̂)_i and (F u_d)_i, at the recorded
    /// rows: where it is many times u_f's peak, u_f is their small difference and keeps that many
    /// times the states' error (a grid inverter's LCL loop: |K x̂| up to 28× u_f's peak, and u_f
    /// 1e-4 off at rtol = 1e-6 while x̂ was 1e-5). Empty where the loop tracked none (the sampled
    /// loop, a true plant with its own actuator).
    pub uf_terms: Vec<f64>,
    /// Per input, at how many recorded samples the true plant's actuator limit (`[truth]` u_max)
    /// clipped it; empty without an actuator. The continuous loop reads the clipping at the
    /// integrator's latest evaluation of the derivative (within one step of the sample).
    pub limited: Vec<usize>,
    /// Per input, the true plant's actuator limit (`[truth]` u_max, ∞ for none); empty without an
    /// actuator.
    pub u_max: Vec<f64>,
    /// Per input, the true plant's lower actuator limit (`[truth]` u_min, −u_max unless given);
    /// empty without an actuator ([`SimResult::limits`]).
    pub u_min: Vec<f64>,
    /// The plant's unit of time, in which `t` and every time of the run are (a label).
    pub time_unit: TimeUnit,
}

/// The share of a loop's largest output or reference below which a regulated channel's error is
/// taken for rounding ([`SimResult::error_scale`]): far above double's accumulated rounding (the
/// canal's 2e-17) and below any error an engineer weighs, but a ratio across the outputs' units, so
/// beside an output of 1e5 Pa a regulation error in metres below 1e-5 m counts as rounding. An f32
/// run's own rounding (about 1e-7) lies above it: there the precision check judges the loop.
pub const ROUNDING_SHARE: f64 = 1e-10;

/// One recorded instant, as the loops hand it to [`SimResult::push`]: y, g, u, u_f (m each), η̂
/// (m·q) and, when states are recorded, (x, x̂).
#[derive(Debug, Clone, Copy)]
pub struct Sample<'a> {
    pub t: f64,
    pub y: &'a [f64],
    pub g: &'a [f64],
    pub u: &'a [f64],
    pub u_f: &'a [f64],
    pub eta: &'a [f64],
    pub states: Option<(&'a [f64], &'a [f64])>,
}

/// Channel i's figures of merit, under the names every output shares (`summary.json`, runs.csv,
/// Python, a study's quantiles and tune objectives).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ChannelFigures {
    /// max |e_i| over the last 10 % of the recorded horizon; NaN (`null` in JSON) when the run
    /// stopped before t_end (diverged, failed, interrupted): the tail was never reached.
    pub tail_max_e: f64,
    /// RMS of e_i over the last 10 % of the recorded horizon; NaN like `tail_max_e`.
    pub tail_rms_e: f64,
    /// max |u_i| over the run (the adaptive command (25)).
    pub max_u: f64,
    /// max |u_f,i| over the run: the plant input (5), what the actuator must deliver; where the
    /// true actuator's limit (`[truth]` u_max) clipped it, the largest the controller asked for.
    pub max_uf: f64,
    /// First recorded t after which |e_i| stays within the settling band ([`Settle`],
    /// [`crate::sim::settle`]); `None` when the channel did not settle, or only in the last 5 % of
    /// the horizon.
    pub settle_t: Option<f64>,
}

/// A run's report on channel i: its [`ChannelFigures`] with the default band ([`Settle::default`],
/// 2 % of the reference's peak), ‖η̂_i‖ at the end and why it did not settle.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelSummary {
    #[serde(flatten)]
    pub figures: ChannelFigures,
    /// ‖η̂_i‖ at the last sample.
    pub final_eta_norm: f64,
    /// Why `settle_t` is empty; `None` when settled.
    pub settle_note: Option<String>,
}

impl SimResult {
    /// The numbers one recorded row holds (t, y, g, e, u, u_f, η̂, and x, x̂ with `states`) for m
    /// channels, regressor size q and plant order n, and their names.
    pub fn row_len(m: usize, q: usize, n: usize, states: bool) -> (usize, &'static str) {
        if states {
            (1 + 5 * m + m * q + 2 * n, "t, y, g, e, u, u_f, η̂, x, x̂")
        } else {
            (1 + 5 * m + m * q, "t, y, g, e, u, u_f, η̂")
        }
    }

    /// An empty result for m channels, regressor size q and plant order n, with the loop's
    /// statistics so far.
    pub fn new(m: usize, q: usize, n: usize, stats: RunStats) -> Self {
        let (t, y, g, e, u, u_f, eta, x, x_hat) = Default::default();
        SimResult {
            m,
            q,
            n,
            t,
            y,
            g,
            e,
            u,
            u_f,
            eta,
            x,
            x_hat,
            stats,
            outcome: None,
            peaks: Peaks::default(),
            peak_u: Vec::new(),
            peak_uf: Vec::new(),
            peak_demand: Vec::new(),
            peak_e: Vec::new(),
            uf_terms: Vec::new(),
            limited: Vec::new(),
            u_max: Vec::new(),
            u_min: Vec::new(),
            time_unit: TimeUnit::default(),
        }
    }

    /// Raises [`SimResult::peak_u`] and [`SimResult::peak_uf`] to |u| and |u_f| now (NaN stays).
    pub(crate) fn record_input_peaks(&mut self, u: &[f64], u_f: &[f64]) {
        raise(&mut self.peak_u, u);
        raise(&mut self.peak_uf, u_f);
    }

    /// Raises [`SimResult::peak_e`] to |y − g| now.
    pub(crate) fn record_error_peak(&mut self, y: &[f64], g: &[f64]) {
        self.peak_e.resize(y.len(), 0.0);
        for ((p, y), g) in self.peak_e.iter_mut().zip(y).zip(g) {
            *p = max_or_nan(*p, (y - g).abs());
        }
    }

    /// Raises [`SimResult::peak_demand`] to |u_f| before the actuator's limit now.
    pub(crate) fn record_demand(&mut self, demand: &[f64]) {
        raise(&mut self.peak_demand, demand);
    }

    /// Raises [`SimResult::uf_terms`] to the terms of u_f = −K x̂ + F u_d now, from −K x̂ (`kx`) and
    /// u_f.
    pub(crate) fn record_uf_terms(&mut self, kx: &[f64], u_f: &[f64]) {
        self.uf_terms.resize(kx.len(), 0.0);
        for ((p, k), f) in self.uf_terms.iter_mut().zip(kx).zip(u_f) {
            *p = p.max(k.abs()).max((f - k).abs());
        }
    }

    /// Counts, per input, whether its actuator limit clipped it at the sample just recorded.
    pub(crate) fn count_limited(&mut self, clipped: impl ExactSizeIterator<Item = bool>) {
        self.limited.resize(clipped.len(), 0);
        for (c, on) in self.limited.iter_mut().zip(clipped) {
            *c += usize::from(on);
        }
    }

    /// Input i's true actuator limits [u_min, u_max] ([`SimResult::u_min`], [`SimResult::u_max`]);
    /// [−∞, ∞] without an actuator.
    pub fn limits(&self, i: usize) -> [f64; 2] {
        [self.u_min.get(i).copied().unwrap_or(f64::NEG_INFINITY), self.u_max.get(i).copied().unwrap_or(f64::INFINITY)]
    }

    /// Per input, the fraction of the recorded samples at which its limit clipped it; empty when
    /// the true plant has no limits.
    pub fn limited_fraction(&self) -> Vec<f64> {
        self.limited.iter().map(|&c| c as f64 / self.len().max(1) as f64).collect()
    }

    /// Appends one sample.
    pub fn push(&mut self, s: &Sample<'_>) {
        self.t.push(s.t);
        self.y.extend_from_slice(s.y);
        self.g.extend_from_slice(s.g);
        self.e.extend(s.y.iter().zip(s.g).map(|(a, b)| a - b));
        self.u.extend_from_slice(s.u);
        self.u_f.extend_from_slice(s.u_f);
        self.eta.extend_from_slice(s.eta);
        if let Some((x, x_hat)) = s.states {
            self.x.extend_from_slice(x);
            self.x_hat.extend_from_slice(x_hat);
        }
    }

    /// Whether x and x̂ were recorded.
    pub fn has_states(&self) -> bool {
        !self.x.is_empty()
    }

    /// Whether u and u_f hold their value from one row to the next: a sampled-data run whose
    /// zero-order hold (T_s) lasts at least the row spacing. Figures then draw them as staircases;
    /// with rows sparser than T_s, a row is a point sample of a finer staircase.
    pub fn commands_held(&self) -> bool {
        match (self.stats, self.t.as_slice()) {
            (RunStats::Sampled { sample_time, .. }, [t0, t1, ..]) => sample_time >= (t1 - t0) * (1.0 - 1e-9),
            _ => false,
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True when no sample was recorded.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Column `i` of a row-major signal with `width` columns.
    pub fn column<'a>(&'a self, signal: &'a [f64], width: usize, i: usize) -> impl Iterator<Item = f64> + 'a {
        signal.iter().skip(i).step_by(width).copied()
    }

    /// max |e_i| over samples with t in [from, to]; `None` when no sample lies in the window (a run
    /// that stopped early, or a window past the horizon), so that it cannot pass for a zero error.
    /// A NaN error in the window gives NaN.
    pub fn max_abs_error(&self, i: usize, from: f64, to: f64) -> Option<f64> {
        self.t
            .iter()
            .zip(self.column(&self.e, self.m, i))
            .filter(|(t, _)| **t >= from && **t <= to)
            .map(|(_, e)| e.abs())
            .reduce(max_or_nan)
    }

    /// max |e_i| over the whole run, at the rows and between them ([`SimResult::peak_e`]); `None`
    /// without a row.
    pub fn peak_error(&self, i: usize) -> Option<f64> {
        self.max_abs_error(i, f64::NEG_INFINITY, f64::INFINITY).map(|e| max_or_nan(e, peak(&self.peak_e, i)))
    }

    /// Channel i's scale, of which its tail bound, settling band and advice take a share: the peak
    /// of |g_i| over the run (NaN with a NaN in g), or for a reference that is 0 throughout (a
    /// regulated output) [`SimResult::error_scale`].
    pub fn scale(&self, i: usize) -> f64 {
        match self.column(&self.g, self.m, i).fold(0.0, |p, v| max_or_nan(p, v.abs())) {
            0.0 => self.error_scale(i),
            g => g,
        }
    }

    /// Channel i's error peak ([`SimResult::peak_error`]), but at least [`ROUNDING_SHARE`] of the
    /// loop's largest output or reference. An output that nothing drives (no reference or
    /// disturbance, exact decoupling) has an error of rounding alone, which a share of its own peak
    /// cannot judge (an irrigation canal's middle pool: 8e-19 m, beside a 0.05 m set-point, failed a
    /// bound of 1 % of it).
    pub fn error_scale(&self, i: usize) -> f64 {
        let signals = self.g.iter().chain(&self.y).fold(0.0f64, |p, v| p.max(v.abs()));
        max_or_nan(self.peak_error(i).unwrap_or(0.0), ROUNDING_SHARE * signals)
    }

    /// RMS of e_i over the recorded samples in [from, to]; `None` when there are none.
    pub fn rms_error(&self, i: usize, from: f64, to: f64) -> Option<f64> {
        let (n, sum) = self
            .t
            .iter()
            .zip(self.column(&self.e, self.m, i))
            .filter(|(t, _)| **t >= from && **t <= to)
            .fold((0usize, 0.0), |(n, s), (_, e)| (n + 1, s + e * e));
        (n > 0).then(|| (sum / n as f64).sqrt())
    }

    /// How channel i's error met the band `settle` (of its [`SimResult::scale`]): the one
    /// definition of [`crate::sim::settle`].
    pub fn settling(&self, i: usize, settle: &Settle) -> Settling {
        let e: Vec<f64> = self.column(&self.e, self.m, i).collect();
        settling(&self.t, &e, settle.band(self.scale(i)))
    }

    /// Figures of merit per channel, settled within the band `settle`; the tail is the last 10 %
    /// of the recorded horizon.
    pub fn figures(&self, settle: &Settle) -> Vec<ChannelFigures> {
        (0..self.m).filter_map(|i| self.channel(i, settle)).map(|(f, _)| f).collect()
    }

    /// Figures of merit per channel with the default settling band, ‖η̂_i‖ at the end and why a
    /// channel did not settle.
    pub fn summary(&self) -> Vec<ChannelSummary> {
        (0..self.m)
            .filter_map(|i| {
                let (figures, settling) = self.channel(i, &Settle::default())?;
                let last = &self.eta[self.eta.len() - self.m * self.q..];
                let final_eta_norm = last[i * self.q..(i + 1) * self.q].iter().map(|v| v * v).sum::<f64>().sqrt();
                let settle_note = match self.t.last() {
                    Some(&t) if !self.reached_end() => Some(format!(
                        "no tail: the run stopped at t = {} {} (see its outcome)",
                        crate::settings::fmt_short(t),
                        self.time_unit
                    )),
                    _ => settling.reason(self.time_unit),
                };
                Some(ChannelSummary { figures, final_eta_norm, settle_note })
            })
            .collect()
    }

    /// The ratio of u_f,i's terms (−K x̂ and F u_d, [`SimResult::uf_terms`]) to its peak: how many
    /// times larger than u_f the terms it is the difference of are; 0 where none were recorded.
    pub fn uf_cancellation(&self, i: usize) -> f64 {
        self.uf_terms.get(i).map_or(0.0, |terms| terms / self.max_uf(i))
    }

    /// max |u_f,i| over the rows and between them ([`SimResult::peak_uf`]), and where the true
    /// actuator's limit clipped it, what the controller asked for ([`SimResult::peak_demand`]); NaN
    /// where u_f was.
    pub fn max_uf(&self, i: usize) -> f64 {
        max_or_nan(self.max_uf_applied(i), peak(&self.peak_demand, i))
    }

    /// max |u_f,i| the plant received, over the rows and between them ([`SimResult::peak_uf`]): at
    /// most the true actuator's limit, unlike [`SimResult::max_uf`].
    pub fn max_uf_applied(&self, i: usize) -> f64 {
        self.column(&self.u_f, self.m, i).fold(peak(&self.peak_uf, i), |a, u| max_or_nan(a, u.abs()))
    }

    /// Whether the run reached t_end (its outcome is completed, or not set yet).
    fn reached_end(&self) -> bool {
        matches!(self.outcome, None | Some(Outcome::Completed))
    }

    /// Where the tail begins, the last 10 % of the recorded horizon: t1 − 0.1 (t1 − t0), the one
    /// bound every tail figure uses (the automatic design's 0.9·t_end left out the row at 23.4 of a
    /// 26 s run that `quell run`'s summary counted); `None` without samples.
    pub fn tail_from(&self) -> Option<f64> {
        let (Some(&t0), Some(&t1)) = (self.t.first(), self.t.last()) else {
            return None;
        };
        Some(t1 - 0.1 * (t1 - t0))
    }

    /// max |e_i| over the tail, from [`SimResult::tail_from`] to the last row; `None` without
    /// samples.
    pub fn tail_max_abs_error(&self, i: usize) -> Option<f64> {
        let (from, &t1) = self.tail_from().zip(self.t.last())?;
        self.max_abs_error(i, from, t1)
    }

    /// RMS of e_i over the tail, from [`SimResult::tail_from`] to the last row; `None` without
    /// samples.
    pub fn tail_rms_error(&self, i: usize) -> Option<f64> {
        let (from, &t1) = self.tail_from().zip(self.t.last())?;
        self.rms_error(i, from, t1)
    }

    /// Channel i's figures and how it settled; `None` without samples.
    fn channel(&self, i: usize, settle: &Settle) -> Option<(ChannelFigures, Settling)> {
        let from = self.tail_from()?;
        let tail: Vec<f64> =
            self.t.iter().zip(self.column(&self.e, self.m, i)).filter(|(t, _)| **t >= from).map(|(_, e)| e).collect();
        let settling = self.settling(i, settle);
        // A run stopped early has no tail of its horizon, and settled in none of it.
        let reached = self.reached_end();
        let (tail_max_e, tail_rms_e) = match reached {
            true => (
                tail.iter().fold(0.0, |a, e| max_or_nan(a, e.abs())),
                (tail.iter().map(|e| e * e).sum::<f64>() / tail.len().max(1) as f64).sqrt(),
            ),
            false => (f64::NAN, f64::NAN),
        };
        let figures = ChannelFigures {
            tail_max_e,
            tail_rms_e,
            max_u: self.column(&self.u, self.m, i).fold(peak(&self.peak_u, i), |a, u| max_or_nan(a, u.abs())),
            max_uf: self.max_uf(i),
            settle_t: settling.time().filter(|_| reached),
        };
        Some((figures, settling))
    }
}

/// Raises each of `peaks` to |v| of `now`'s entry (NaN stays), sized to `now`.
fn raise(peaks: &mut Vec<f64>, now: &[f64]) {
    peaks.resize(now.len(), 0.0);
    for (p, v) in peaks.iter_mut().zip(now) {
        *p = max_or_nan(*p, v.abs());
    }
}

/// Entry i of a per-channel peak, 0 where none was tracked.
fn peak(peaks: &[f64], i: usize) -> f64 {
    peaks.get(i).copied().unwrap_or(0.0)
}

/// max(a, b), but NaN when either is NaN (`f64::max` returns the other one), so that a NaN in a
/// run shows in its figures instead of passing for a finite value.
pub(crate) fn max_or_nan(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn max_abs_error_is_none_for_an_empty_window_and_nan_propagates() {
        let mut r = SimResult::new(
            1,
            1,
            1,
            RunStats::Sampled { controller_steps: 0, sample_time: 0.1, precision: Default::default() },
        );
        let push = |r: &mut SimResult, t: f64, y: f64| {
            r.push(&Sample { t, y: &[y], g: &[1.0], u: &[0.0], u_f: &[0.0], eta: &[0.0], states: None })
        };
        assert_eq!(r.max_abs_error(0, 0.0, 1.0), None, "no sample at all");
        // e = y − g at t = 0, 1, 2: −0.5, 2, −3.
        for (t, y) in [(0.0, 0.5), (1.0, 3.0), (2.0, -2.0)] {
            push(&mut r, t, y);
        }
        assert_eq!(r.max_abs_error(0, 0.0, 1.0), Some(2.0));
        assert_eq!(r.max_abs_error(0, 0.0, 2.0), Some(3.0));
        assert_eq!(r.max_abs_error(0, 0.5, 0.9), None, "window between samples");
        assert_eq!(r.max_abs_error(0, 90.0, 100.0), None, "window past the horizon (a run that stopped early)");
        push(&mut r, 3.0, f64::NAN);
        assert!(r.max_abs_error(0, 0.0, 3.0).unwrap().is_nan(), "a NaN error is not hidden by max");
    }

    #[test]
    fn a_run_stopped_early_has_no_tail_and_no_settling_time() {
        let mut r = SimResult::new(
            1,
            1,
            1,
            RunStats::Sampled { controller_steps: 0, sample_time: 1.0, precision: Default::default() },
        );
        for k in 0..=10 {
            // e = 0 from t = 0 on: settled at once, with a tail of zeros.
            r.push(&Sample { t: k as f64, y: &[1.0], g: &[1.0], u: &[2.0], u_f: &[-3.0], eta: &[0.0], states: None });
        }
        let completed = r.summary()[0].figures;
        assert_eq!((completed.tail_max_e, completed.tail_rms_e, completed.settle_t), (0.0, 0.0, Some(0.0)));
        r.outcome = Some(Outcome::Diverged { t: 10.5, signal: "x1 (plant state)".into(), value: 2e9 });
        let stopped = r.summary()[0].figures;
        assert!(
            stopped.tail_max_e.is_nan() && stopped.tail_rms_e.is_nan() && stopped.settle_t.is_none(),
            "{stopped:?}"
        );
        assert_eq!((stopped.max_u, stopped.max_uf), (2.0, 3.0), "the peaks of what ran are kept");
    }

    #[test]
    fn commands_are_held_when_the_sample_time_spans_a_row() {
        let rows = |stats: RunStats, dt: f64| {
            let mut r = SimResult::new(1, 1, 1, stats);
            for k in 0..3 {
                r.push(&Sample {
                    t: k as f64 * dt,
                    y: &[0.0],
                    g: &[0.0],
                    u: &[0.0],
                    u_f: &[0.0],
                    eta: &[0.0],
                    states: None,
                });
            }
            r.commands_held()
        };
        let sampled =
            |sample_time| RunStats::Sampled { controller_steps: 0, sample_time, precision: Default::default() };
        assert!(rows(sampled(0.1), 0.1), "a row per sample");
        assert!(rows(sampled(0.5), 0.1), "five rows per sample");
        assert!(!rows(sampled(0.001), 0.1), "a hundred samples per row: a row is a point sample");
        assert!(!rows(RunStats::Continuous(Default::default()), 0.1), "the continuous loop's u is not held");
    }

    #[test]
    fn summary_shows_a_nan_in_the_error_or_the_input() {
        // Two channels; channel 0's error is NaN at t = 9.5 (in the last 10 %), channel 1's input
        // is NaN at t = 0 (outside the tail, but max |u| is over the whole run).
        let mut r = SimResult::new(
            2,
            1,
            1,
            RunStats::Sampled { controller_steps: 0, sample_time: 0.5, precision: Default::default() },
        );
        for k in 0..=20 {
            let t = 0.5 * k as f64;
            let y0 = if k == 19 { f64::NAN } else { 1.0 };
            let u1 = if k == 0 { f64::NAN } else { -4.0 };
            let (u, u_f) = ([3.0, u1], [-5.0, 2.0 * k as f64]);
            r.push(&Sample { t, y: &[y0, 2.0], g: &[1.0, 1.0], u: &u, u_f: &u_f, eta: &[0.0, 0.0], states: None });
        }
        let s = r.figures(&Settle::default());
        assert!(s[0].tail_max_e.is_nan() && s[0].tail_rms_e.is_nan(), "{:?}", s[0]);
        assert_eq!(s[0].max_u, 3.0);
        assert_eq!((s[1].tail_max_e, s[1].tail_rms_e), (1.0, 1.0));
        assert!(s[1].max_u.is_nan(), "{:?}", s[1]);
        // max |u_f| is the plant input's, not the command's: 5 and 2·20.
        assert_eq!((s[0].max_uf, s[1].max_uf), (5.0, 40.0));
        let in_summary: Vec<ChannelFigures> = r.summary().iter().map(|c| c.figures).collect();
        assert_eq!(
            format!("{in_summary:?}"),
            format!("{s:?}"),
            "summary() holds figures() (NaN != NaN, so compared as text)"
        );
    }

    /// A regulated channel's scale is its error's peak, but not below 1e-10 of the loop's largest
    /// output or reference: an output nothing drives, whose error is rounding (1e-19 beside a 0.05
    /// set-point), then settles at once and meets a 1 % tail bound.
    #[test]
    fn an_error_of_rounding_alone_is_judged_against_the_loops_signals() {
        let run = |precision, e2: f64| {
            let stats = RunStats::Sampled { controller_steps: 0, sample_time: 1.0, precision };
            let mut r = SimResult::new(2, 1, 1, stats);
            for k in 0..=10 {
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                let (y, g) = ([0.05, sign * e2], [0.05, 0.0]);
                r.push(&Sample {
                    t: k as f64,
                    y: &y,
                    g: &g,
                    u: &[0.0; 2],
                    u_f: &[0.0; 2],
                    eta: &[0.0; 2],
                    states: None,
                });
            }
            r
        };
        let r = run(crate::controller::Precision::F64, 1e-19);
        assert_eq!(r.scale(0), 0.05, "a tracked channel's scale is its reference's peak");
        assert_eq!(r.scale(1), 1e-10 * 0.05);
        assert!(r.figures(&Settle::default())[1].settle_t == Some(0.0));
        // Not by the precision: an f32 run's regulation error of 1e-9 is its own scale.
        assert_eq!(run(crate::controller::Precision::F32, 1e-9).scale(1), 1e-9);
        // A genuine regulation error is its own scale, and a tail at its peak is outside its band.
        let r = run(crate::controller::Precision::F64, 1e-3);
        assert_eq!(r.scale(1), 1e-3);
        assert_eq!(r.figures(&Settle::default())[1].settle_t, None);
    }
}
