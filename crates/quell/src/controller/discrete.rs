//! The real-time controller: the equations of [`Equations`] discretized exactly for a zero-order-hold
//! input at sample time T_s, with delay lines for u_i(t − τ_i) and ξ̂(t − τ_i). [`Controller::step`]
//! allocates nothing.

use nalgebra::DMatrix;
use thiserror::Error;

use super::{command, mat_vec, swapping_error, Equations};
use crate::design::Design;
use crate::linalg::zoh_unchecked;
use crate::settings::TimeUnit;

/// Why a controller cannot run at the requested sample time.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ControllerError {
    #[error("simulation.sample_time: expected a finite T_s > 0, found {}", crate::settings::fmt_short(*.value))]
    BadSampleTime { value: f64 },
    /// `nearest` is a sample time that passes this same check, written with the fewest digits that do
    /// (so the printed value works when typed back), or `None` when no τ_c/k near T_s fits every delay.
    /// `output_step`: a run's output step, which `nearest` divides where a sample time near T_s
    /// does, else the message names the output step to set with it (`None` for a controller alone,
    /// or where `nearest` divides it anyway).
    #[error("simulation.sample_time: channel {}'s delay τ = {} {unit} is not a whole number of samples of T_s = {} {unit} ({ratio:.6} samples); {}", .channel + 1, crate::settings::fmt_short(*.delay), crate::settings::fmt_time(*.sample_time), suggestion(*.nearest, *.output_step, *.unit))]
    DelayNotMultiple {
        channel: usize,
        delay: f64,
        sample_time: f64,
        ratio: f64,
        nearest: Option<f64>,
        output_step: Option<f64>,
        unit: TimeUnit,
    },
    /// `nearest` as in `DelayNotMultiple`: the sample time nearest T_s at which every line fits and
    /// every delay is whole.
    #[error("simulation.sample_time: channel {}'s delay τ = {} {unit} is {} samples of T_s = {} {unit}; a delay line holds at most {max:e} samples; {}", .channel + 1, crate::settings::fmt_short(*.delay), crate::settings::fmt_4(*.samples), crate::settings::fmt_time(*.sample_time), longer(*.nearest, *.unit), max = MAX_DELAY_SAMPLES)]
    DelayTooLong { channel: usize, delay: f64, sample_time: f64, samples: f64, nearest: Option<f64>, unit: TimeUnit },
    /// The delay lines together would hold more than [`MAX_DELAY_LINE_BYTES`]; `at_least` is the
    /// shortest sample time at which they would not, `nearest` the shortest round one from there on
    /// that passes, else as in `DelayTooLong`.
    #[error("simulation.sample_time: the delay lines of u_i(t − τ_i) and ξ̂(t − τ_i) would hold {rows:e} rows of {width} numbers at T_s = {} {unit} ({:.3} GiB); at most {} GiB are kept; use a sample time ≥ {} {unit}{}", crate::settings::fmt_time(*.sample_time), *.rows * (8 * *.width) as f64 / 1024f64.powi(3), MAX_DELAY_LINE_BYTES / 1024f64.powi(3), crate::settings::fmt_short(*.at_least), such_as(*.nearest, *.unit))]
    DelayLinesTooLarge {
        rows: f64,
        width: usize,
        sample_time: f64,
        at_least: f64,
        nearest: Option<f64>,
        unit: TimeUnit,
    },
    /// A discretized block is not finite at this sample time.
    #[error("simulation.sample_time: {what} is not finite after discretizing at T_s = {sample_time:e} {unit}; the exact discretization overflowed (the design's eigenvalues or gains times T_s are beyond floating point); choose a shorter sample time or poles of smaller magnitude")]
    NotFinite { what: String, sample_time: f64, unit: TimeUnit },
    /// T_s μ_i is beyond [`MAX_ADAPTATION_STEP`]: I + cΩ of the adaptive step would overflow once
    /// c·Ω does, turning adaptation off.
    #[error("design.mu[{channel}]: expected T_s μ_i ≤ {max:e} (μ_i ≤ {limit:e} at T_s = {sample_time} {unit}), found μ_i = {mu:e}; the sampled adaptation step's I + T_s μ_i Ω_i overflows (Ω_i reaches 1e150) and adaptation stops — choose a smaller μ_i", max = MAX_ADAPTATION_STEP, limit = MAX_ADAPTATION_STEP / .sample_time)]
    AdaptationStepTooLarge { channel: usize, mu: f64, sample_time: f64, unit: TimeUnit },
    /// [`Controller::step`] was given y or g of the wrong length.
    #[error("Controller::step: {name} needs {expected} entries (one per channel), found {found}")]
    InputLength { name: &'static str, expected: usize, found: usize },
    /// [`Controller::step`] was given an entry of y or g that is not finite or beyond
    /// ±[`MAX_MEASUREMENT`]; the step was refused and the state kept.
    #[error("Controller::step: {name}[{index}] = {value:e} is beyond ±{max:e} (or not finite), the largest measurement the controller takes; the step was refused and its state kept (hold the previous input, check the sensor, and call reset() if the fault persisted)", max = MAX_MEASUREMENT)]
    InputOutOfRange { name: &'static str, index: usize, value: f64 },
    /// The step's output u_f or command u is not finite: inputs the design cannot follow (a
    /// growing loop, spikes near the bound) overflowed the state. Every step reports it until
    /// [`Controller::reset`].
    #[error("Controller::step: the controller's state is no longer finite (an output is {value}); the inputs grew beyond what the design can follow — hold a safe input and call reset()")]
    StateNotFinite { value: f64 },
    /// [`Controller::set_state`] was given a state of other than [`Controller::state_len`] numbers.
    #[error("Controller::set_state: the state needs {expected} numbers for this design and sample time (the layout of Controller::state), found {found}; take it from a controller of the same design and T_s (the state was left as it was)")]
    StateLength { expected: usize, found: usize },
    /// [`Controller::set_state`] was given an entry that is not finite, or an Ω_i that is not
    /// exactly symmetric; `part` names where in the layout the entry is.
    #[error("Controller::set_state: state[{index}] ({part}) = {value:e}: expected {expected} (the state was left as it was)")]
    BadState { index: usize, part: String, value: f64, expected: String },
}

impl ControllerError {
    /// The scenario key the error names, the head of its message (`simulation.sample_time`,
    /// `design.mu[i]`), for a controller that cannot be built; `None` for a running controller's
    /// ([`Controller::step`], [`Controller::set_state`]).
    pub fn key(&self) -> Option<String> {
        let message = self.to_string();
        let (key, _) = message.split_once(": ")?;
        (!key.starts_with("Controller::")).then(|| key.to_string())
    }
}

/// Largest |y_i| and |g_i| [`Controller::step`] takes (the generated C in double likewise; in float,
/// 1e12). The adaptive law multiplies two signals (Δ ε̂, Δ Δᵀ, η̂ᵀ ξ̂), so one sample of 1e160
/// overflowed them at once and made η̂, hence u_f, NaN for ever. Such a value is a sensor or wiring
/// fault, not a measurement: it is refused with the state untouched (not clipped). Below the bound
/// the products stay finite for that step; what a loop does with inputs far beyond its design's
/// scale is the design's, and a state that overflows later is reported
/// ([`ControllerError::StateNotFinite`]) until [`Controller::reset`].
pub const MAX_MEASUREMENT: f64 = 1e100;

/// Largest adaptation step c = T_s μ_i: with c and Ω_i both ≤ 1e150 (the plant's and signals'
/// [`crate::plant::MAX_ENTRY`]), I + cΩ_i stays finite.
pub const MAX_ADAPTATION_STEP: f64 = crate::plant::MAX_ENTRY;

/// Longest delay line, in samples (its memory is this many rows of 1 + q numbers per channel).
pub const MAX_DELAY_SAMPLES: f64 = 1e7;

/// Most bytes the delay lines of all channels hold together (1 GiB): each of its 1e7 samples, a
/// line is 8·(1 + q) bytes a row, so three channels of the SI supply vessel (q = 12) at the rows'
/// limit would have held 3.1 GB (and the generated C as many static bytes).
pub const MAX_DELAY_LINE_BYTES: f64 = 1024.0 * 1024.0 * 1024.0;

/// A ring buffer holding the last `d + 1` rows of width w, so that row k − d is available at k.
#[derive(Debug, Clone)]
struct DelayLine {
    width: usize,
    len: usize,
    head: usize,
    data: Vec<f64>,
}

impl DelayLine {
    fn new(samples: usize, width: usize) -> Self {
        DelayLine { width, len: samples + 1, head: 0, data: vec![0.0; (samples + 1) * width] }
    }
    /// Writes the current row [first, rest] (into the slot that held row k − d − 1), then returns
    /// row k − d.
    fn push(&mut self, first: f64, rest: &[f64]) -> &[f64] {
        let w = self.width;
        let slot = &mut self.data[self.head * w..(self.head + 1) * w];
        slot[0] = first;
        for (o, v) in slot[1..].iter_mut().zip(rest) {
            *o = *v;
        }
        self.head += 1;
        if self.head == self.len {
            self.head = 0;
        }
        // After the advance, `head` is the oldest row: k − d.
        &self.data[self.head * w..(self.head + 1) * w]
    }
    /// The row the last push wrote (the others were rounded as they were written, in
    /// [`SinglePrecision`]).
    fn newest(&mut self) -> &mut [f64] {
        let w = self.width;
        let at = (self.head + self.len - 1) % self.len;
        &mut self.data[at * w..(at + 1) * w]
    }
    fn clear(&mut self) {
        self.data.fill(0.0);
        self.head = 0;
    }
}

/// n numbers starting on a 64-byte boundary: [`adapt`] adds into them row after row, and AVX2's
/// 32-byte stores and reloads that straddle cache lines took twice the time of the whole step (the
/// paper's design, `docs/performance.md`). The offset is found on each access, so clones stay aligned.
#[derive(Debug, Clone)]
struct Aligned {
    buf: Vec<f64>,
    n: usize,
}

impl Aligned {
    fn new(n: usize) -> Self {
        Aligned { buf: vec![0.0; n + 7], n }
    }
    fn get(&mut self) -> &mut [f64] {
        let at = self.buf.as_ptr().align_offset(64).min(7);
        &mut self.buf[at..at + self.n]
    }
}

/// One channel's discrete state and matrices.
#[derive(Debug, Clone)]
struct Channel {
    /// G_ii filter bank: W ← Φ W + γ [u_i(k − d_i), ξ̂ᵀ(k − d_i)] (σ × (1 + q), row-major).
    Phi: DMatrix<f64>,
    gamma: Vec<f64>,
    W: Vec<f64>,
    W_next: Vec<f64>,
    /// H filter memories Y_i and Ω_i (q×q, exactly symmetric, see [`adapt`]).
    Y: Vec<f64>,
    Omega: Vec<f64>,
    /// Delay line of the row [u_i, ξ̂ᵀ].
    line: DelayLine,
    /// T_s μ_i.
    c: f64,
}

/// The discrete-time adaptive controller (eqs. (5), (6), (14), (20), (25), (33)).
#[derive(Debug, Clone)]
pub struct Controller {
    eq: Equations,
    T: f64,
    /// Core z_{k+1} = [Φ_z Γ_z] [z_k; y_k; g_k; u_d(k)].
    PhiGamma_z: DMatrix<f64>,
    /// H(s) = 1/(βs + 1) at ZOH: x_{k+1} = a x_k + b v_k, a = e^{−T_s/β}, b = 1 − a (kept, so that
    /// a rounded a does not round b: at a = 1 − 1e-5, f32's rounding of a is 0.6 % of 1 − a).
    a: f64,
    b: f64,
    channels: Vec<Channel>,
    /// [z; y; g; u_d]: the core state and its held inputs, contiguous for one product.
    zv: Vec<f64>,
    z_next: Vec<f64>,
    xi: Vec<f64>,
    Delta: Vec<f64>,
    /// Ω η̂ of [`adapt`].
    Omega_eta: Aligned,
    /// The Uᵀ D U factors of I + cΩ_i in [`adapt`] (q×q).
    ldl: Vec<f64>,
    u: Vec<f64>,
    u_f: Vec<f64>,
    /// η̂_1, …, η̂_m, concatenated.
    eta: Vec<f64>,
    /// x̂ at the start and after [`Controller::reset`] (the design plant's `xhat0`).
    xhat0: Vec<f64>,
}

fn suggestion(nearest: Option<f64>, output_step: Option<f64>, unit: TimeUnit) -> String {
    let fmt = crate::settings::fmt_short;
    match (nearest, output_step) {
        (Some(t), Some(h)) if !divides(h, t) => {
            format!("the nearest valid sample time is {} {unit}{}", fmt(t), output_step_note(t, h, "near it", unit))
        }
        (Some(t), Some(h)) => format!(
            "the nearest valid sample time that also divides simulation.output_step = {} {unit} (a run's rows fall on samples) is {} {unit}",
            fmt(h),
            fmt(t)
        ),
        (Some(t), None) => format!("the nearest valid sample time is {} {unit}", fmt(t)),
        (None, _) => format!(
            "no sample time τ_c/k within {SEARCHED} samples of it makes every delay whole (the delays are not commensurate); \
             change the delays to whole multiples of one sample time"
        ),
    }
}

fn longer(nearest: Option<f64>, unit: TimeUnit) -> String {
    match nearest {
        Some(t) => {
            format!("use a longer sample time: the nearest valid one is {} {unit}", crate::settings::fmt_short(t))
        }
        None => "use a longer sample time".into(),
    }
}

fn such_as(nearest: Option<f64>, unit: TimeUnit) -> String {
    nearest.map_or_else(String::new, |t| {
        format!(" that makes every delay whole, such as {} {unit}", crate::settings::fmt_short(t))
    })
}

/// Whether the output step `h` is a whole number ≥ 1 of samples of `t`, as a run needs.
pub(crate) fn divides(h: f64, t: f64) -> bool {
    whole_multiple(h, t).is_some_and(|k| k >= 1)
}

/// What a run at a sample time `t` offered for its delays needs of its output step `h` where `t`
/// does not divide it and no sample time `near` (a phrase: "near it") does both: the output step
/// to set with it, t·round(h/t) ("", where `t` divides h). Delays of 1/60 min written to six
/// digits beside h = 0.5 min had been offered 0.00833335 min, which the output step's check then
/// refused for 0.008333333333333 min, which the delays' check refused in turn.
pub(crate) fn output_step_note(t: f64, h: f64, near: &str, unit: TimeUnit) -> String {
    if divides(h, t) {
        return String::new();
    }
    format!(
        ", and none {near} also divides simulation.output_step = {} {unit} (a run's rows fall on samples): with it, set output_step to a whole multiple of it, e.g. {} {unit}",
        crate::settings::fmt_short(h),
        crate::settings::fmt_time(t * (h / t).round().max(1.0))
    )
}

/// How many candidate sample counts k on either side of τ_c/T_s the suggestion tries.
const SEARCHED: i64 = 10_000;

/// Relative tolerance of a whole number of samples: x/T within 1e-9·max(x/T, 1) of an integer.
const WHOLE_TOLERANCE: f64 = 1e-9;

/// The times k·T of a uniform grid (samples, output rows), each the double nearest the decimal
/// k·T when T is a decimal of at most 15 digits: with T = 0.1, t_3 = 3/10 reads 0.3, where the
/// product 3 × 0.1 reads 0.30000000000000004. Any other T, or k·M past 2⁵³, gives k·T.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Grid {
    T: f64,
    /// T = M/10^d: (M, 10^d), or (0, 0) when T has no such form.
    mantissa: f64,
    scale: f64,
}

impl Grid {
    pub(crate) fn new(T: f64) -> Grid {
        let decimal = (1..=15).map(|d| 10f64.powi(d)).find_map(|scale| {
            let mantissa = (T * scale).round();
            (mantissa < 2f64.powi(53) && mantissa / scale == T).then_some((mantissa, scale))
        });
        let (mantissa, scale) = decimal.unwrap_or((0.0, 0.0));
        Grid { T, mantissa, scale }
    }

    /// (M, 10^d) with T = M/10^d, or (0, 0) when T has no such form: for generated code that
    /// computes the same t_k.
    pub(crate) fn decimal(&self) -> (f64, f64) {
        (self.mantissa, self.scale)
    }

    /// t_k: k·M/10^d, one rounding of the exact decimal (k·M exact below 2⁵³), or k·T.
    pub(crate) fn at(&self, k: usize) -> f64 {
        let km = k as f64 * self.mantissa;
        if self.scale > 0.0 && km < 2f64.powi(53) {
            km / self.scale
        } else {
            k as f64 * self.T
        }
    }
}

/// x/T rounded, when it is a whole number of samples of T (to [`WHOLE_TOLERANCE`] relative).
pub(crate) fn whole_multiple(x: f64, T: f64) -> Option<usize> {
    whole_within(x, T, WHOLE_TOLERANCE)
}

/// The whole samples of T in x: ⌊x/T⌋, with x/T counted as the integer it is within
/// [`WHOLE_TOLERANCE`] of (t_end = 100 s at T = 0.1 s is 1000 samples, though 100/0.1 rounds below).
pub(crate) fn whole_samples(x: f64, T: f64) -> usize {
    whole_multiple(x, T).unwrap_or((x / T).floor() as usize)
}

/// True when τ/T is a whole number (to [`WHOLE_TOLERANCE`]) of at most [`MAX_DELAY_SAMPLES`] samples.
pub(crate) fn whole(tau: f64, T: f64) -> bool {
    delay_within(tau, T, WHOLE_TOLERANCE)
}

/// τ/T a whole number of samples to `tol` and at most [`MAX_DELAY_SAMPLES`]. A delay within `tol`
/// of 0 samples is 0, as one within `tol` of 3 is 3: 1e-300 s at T_s = 1 ms, or 0.05 s at
/// T_s = 1e10 s (5e-12 samples), is no delay a controller at that T_s can hold.
fn delay_within(tau: f64, T: f64, tol: f64) -> bool {
    tau / T <= MAX_DELAY_SAMPLES && whole_within(tau, T, tol).is_some()
}

fn whole_within(x: f64, T: f64, tol: f64) -> Option<usize> {
    let r = x / T;
    ((r - r.round()).abs() <= tol * r.max(1.0)).then(|| r.round() as usize)
}

/// The delays τ_i in whole samples of T, each line within [`MAX_DELAY_SAMPLES`] and all of them,
/// Σ (τ_i/T + 1) rows of `width` numbers, within [`MAX_DELAY_LINE_BYTES`]; else the error with the
/// nearest sample time that passes every check ([`valid_sample_time`]).
fn delay_samples(delays: &[f64], T: f64, width: usize, unit: TimeUnit) -> Result<Vec<usize>, ControllerError> {
    let nearest = || valid_sample_time(delays, T, width);
    for (channel, &delay) in delays.iter().enumerate() {
        let samples = delay / T;
        if samples.is_nan() || samples > MAX_DELAY_SAMPLES {
            return Err(ControllerError::DelayTooLong {
                channel,
                delay,
                sample_time: T,
                samples,
                nearest: nearest(),
                unit,
            });
        }
        if !whole(delay, T) {
            let nearest = nearest();
            return Err(ControllerError::DelayNotMultiple {
                channel,
                delay,
                sample_time: T,
                ratio: samples,
                nearest,
                output_step: None,
                unit,
            });
        }
    }
    let d: Vec<usize> = delays.iter().map(|d| (d / T).round() as usize).collect();
    let rows: f64 = d.iter().map(|&d| d as f64 + 1.0).sum();
    if rows > row_limit(width) {
        let at_least = lines_at_least(delays, width);
        return Err(ControllerError::DelayLinesTooLarge {
            rows,
            width,
            sample_time: T,
            at_least,
            nearest: round_at_least(delays, width, at_least).or_else(nearest),
            unit,
        });
    }
    Ok(d)
}

/// Most rows of `width` numbers within [`MAX_DELAY_LINE_BYTES`].
fn row_limit(width: usize) -> f64 {
    MAX_DELAY_LINE_BYTES / (8 * width) as f64
}

/// The shortest sample time (three digits, rounded up) at which Σ τ_i/T_s ≤ limit − m.
fn lines_at_least(delays: &[f64], width: usize) -> f64 {
    crate::settings::step_at_least(delays.iter().sum(), row_limit(width) - delays.len() as f64)
}

/// The sample time τ_max/k nearest T (k within [`SEARCHED`] of τ_max/T, no shorter than the lines'
/// limits allow) at which every delay is whole to a tenth of [`WHOLE_TOLERANCE`] (a nonzero one at
/// least one sample) and the lines fit,
/// written with the fewest significant digits that still pass, so that the printed value works
/// when typed back, and not by a hair. `None` when no such k is near (incommensurate delays).
fn valid_sample_time(delays: &[f64], T: f64, width: usize) -> Option<f64> {
    sample_time_near(delays, T, width, false)
}

/// [`valid_sample_time`] for every delay of a run (the model's, the truth's, the actuator's) and
/// its output step `h`, which must be whole samples too; else for the delays alone (the offer for
/// the delays alone, 0.000699790063 s for the paper at 0.0007 s, was then refused by the output
/// step's check).
pub(crate) fn valid_sample_time_near(delays: &[f64], h: f64, T: f64, width: usize) -> Option<f64> {
    let nonzero: Vec<f64> = delays.iter().copied().filter(|&d| d > 0.0).collect();
    let with_h: Vec<f64> = nonzero.iter().copied().chain([h]).collect();
    valid_sample_time(&with_h, T, width).or_else(|| valid_sample_time(&nonzero, T, width))
}

/// A sample time at most `T` (what a bound on T_s asks for, as the coarse-sample advice gives
/// one) that makes every delay whole: the longest round one (1, 2, 2.5 or 5 times a power of ten,
/// down to a thousandth of T), else the longest τ_max/k of [`valid_sample_time`]'s kind; `None`
/// when neither exists.
pub(crate) fn valid_sample_time_at_most(design: &Design, T: f64) -> Option<f64> {
    sample_time_at_most(&design.plant().delays, 1 + design.q(), T)
}

/// [`valid_sample_time_at_most`] for `delays` and delay-line rows of `width`.
fn sample_time_at_most(delays: &[f64], width: usize, T: f64) -> Option<f64> {
    round_at_most(delays, width, T).or_else(|| sample_time_near(delays, T, width, true))
}

/// The longest round sample time (as [`round_times`], down to three decades below `T`) at most `T`
/// at which every delay is whole and the lines fit.
fn round_at_most(delays: &[f64], width: usize, T: f64) -> Option<f64> {
    let top = T.log10().floor() as i32;
    (top - 3..=top).rev().flat_map(|e| round_times(e).into_iter().rev()).find(|&t| t <= T && fits(delays, width, t))
}

/// A sample time at most `T` that divides the output step `h` and at which every delay of
/// `design` is whole and the lines fit: h/⌈h/T⌉, the longest that divides h, where it has at most
/// six significant digits (0.9, not 0.5/3 = 0.16666…, whose rows print as 0.5000000000001);
/// else the longest round one; else the one [`valid_sample_time`] finds with h among the delays
/// (counting h as a line too: a little conservative). `None` when none exists.
pub(crate) fn sample_time_dividing(design: &Design, T: f64, h: f64) -> Option<f64> {
    let (delays, width) = (&design.plant().delays, 1 + design.q());
    let below = h / (h / T).ceil().max(1.0);
    let short = crate::settings::significant(below, 6) == below;
    if short && fits(delays, width, below) {
        return Some(below);
    }
    let with_h: Vec<f64> = delays.iter().copied().chain([h]).collect();
    round_at_most(&with_h, width, T)
        .or_else(|| fits(delays, width, below).then_some(below))
        .or_else(|| valid_sample_time(&with_h, T, width))
}

/// The shortest round sample time (as [`round_times`], up to three decades above `at_least`) from
/// `at_least` on at which every delay is whole and the lines fit: what a message offers where any
/// sample time from `at_least` on will do (5e-7 rather than τ/k = 2.910000099e-7).
fn round_at_least(delays: &[f64], width: usize, at_least: f64) -> Option<f64> {
    let bottom = at_least.log10().floor() as i32;
    (bottom..=bottom + 3).flat_map(round_times).find(|&t| t >= at_least && fits(delays, width, t))
}

/// 1, 2, 2.5 and 5 times 10^e, parsed from their decimal form (so 2.5e-7 is the double nearest it).
fn round_times(e: i32) -> [f64; 4] {
    [1.0, 2.0, 2.5, 5.0].map(|d| format!("{d}e{e}").parse::<f64>().unwrap_or(f64::NAN))
}

/// Whether every delay is a whole number of samples of `t` to a tenth of [`WHOLE_TOLERANCE`] (a
/// nonzero one at least half a sample) and the delay lines of rows of `width` fit.
fn fits(delays: &[f64], width: usize, t: f64) -> bool {
    let rows: f64 = delays.iter().map(|d| (d / t).round() + 1.0).sum();
    rows <= row_limit(width) && delays.iter().all(|&d| delay_within(d, t, 1e-10) && (d == 0.0 || d / t >= 0.5))
}

/// [`valid_sample_time`]; with `at_most`, only sample times ≤ T.
fn sample_time_near(delays: &[f64], T: f64, width: usize, at_most: bool) -> Option<f64> {
    let tau = delays.iter().copied().fold(0.0, f64::max);
    let shortest = (tau / MAX_DELAY_SAMPLES).max(lines_at_least(delays, width));
    let fits = |t: f64| fits(delays, width, t);
    let (target, k_max) = (T.max(shortest), (tau / shortest).floor());
    // τ/k ≤ target from k_short on, ≥ target up to k_short − 1 (k = round(τ/target) on one side
    // only had offered 150 µs for T = 100 µs and τ = 150 µs, where 75 µs is nearer).
    let k_short = (tau / target).ceil().clamp(1.0, k_max.max(1.0) + 1.0) as i64;
    // The first fit on either side, then the one nearer T (not nearer in k: with τ = 0.12 and
    // 0.05 at T = 0.007, k = 12 is nearer 17 than k = 24, but 0.005 is nearer T than 0.01).
    let first = |ks: &mut dyn Iterator<Item = i64>| {
        ks.filter(|&k| k >= 1 && k as f64 <= k_max).map(|k| tau / k as f64).find(|&t| fits(t))
    };
    let shorter = first(&mut (k_short..k_short + SEARCHED).filter(|&k| !at_most || tau / k as f64 <= T));
    let longer = first(&mut (k_short - SEARCHED..k_short).rev().filter(|&k| !at_most || tau / k as f64 <= T));
    let nearest = match (shorter, longer) {
        (Some(a), Some(b)) => Some(if (a - target).abs() <= (b - target).abs() { a } else { b }),
        (a, b) => a.or(b),
    };
    let within = |r: f64| fits(r) && (!at_most || r <= T);
    nearest
        .and_then(|t| (1..17).map(|p| format!("{t:.p$e}").parse::<f64>().unwrap_or(t)).chain([t]).find(|&r| within(r)))
}

impl Controller {
    /// Discretizes every linear block exactly for ZOH inputs at `sample_time` (matrix exponentials,
    /// computed once here). Delays must be whole numbers of samples.
    pub fn new(design: &Design, sample_time: f64) -> Result<Controller, ControllerError> {
        let T = sample_time;
        if !(T.is_finite() && T > 0.0) {
            return Err(ControllerError::BadSampleTime { value: T });
        }
        let eq = Equations::new(design);
        let (m, q, nz) = (eq.m, eq.q, eq.nz);
        let unit = design.plant().time_unit;
        let d = delay_samples(&design.plant().delays, T, 1 + q, unit)?;
        let (Phi_z, Gamma_z) = zoh_unchecked(&eq.A_z, &eq.B_z, T);
        let mut PhiGamma_z = DMatrix::zeros(nz, nz + 3 * m);
        PhiGamma_z.view_mut((0, 0), (nz, nz)).copy_from(&Phi_z);
        PhiGamma_z.view_mut((0, nz), (nz, 3 * m)).copy_from(&Gamma_z);
        let finite = |values: &[f64], what: &dyn Fn() -> String| match values.iter().all(|v| v.is_finite()) {
            true => Ok(()),
            false => Err(ControllerError::NotFinite { what: what(), sample_time: T, unit }),
        };
        finite(PhiGamma_z.as_slice(), &|| "the observers' [Φ_z Γ_z] (eqs. (6), (14), (20))".into())?;
        let channels = eq
            .channels
            .iter()
            .zip(&d)
            .enumerate()
            .map(|(i, (ch, &d))| {
                let mut e = DMatrix::zeros(ch.sigma(), 1);
                e[(ch.sigma() - 1, 0)] = 1.0;
                let (Phi, gamma) = zoh_unchecked(&ch.A, &e, T);
                let channel = |what: &str| format!("channel {}'s {what}", i + 1);
                finite(Phi.as_slice(), &|| channel("G_ii filter Φ_i"))?;
                finite(gamma.as_slice(), &|| channel("G_ii filter γ_i"))?;
                finite(&[T * ch.mu], &|| channel("adaptation step T_s μ_i"))?;
                if T * ch.mu > MAX_ADAPTATION_STEP {
                    return Err(ControllerError::AdaptationStepTooLarge {
                        channel: i,
                        mu: ch.mu,
                        sample_time: T,
                        unit,
                    });
                }
                let len = ch.sigma() * (1 + q);
                Ok(Channel {
                    Phi,
                    gamma: gamma.iter().copied().collect(),
                    W: vec![0.0; len],
                    W_next: vec![0.0; len],
                    Y: vec![0.0; q],
                    Omega: vec![0.0; q * q],
                    line: DelayLine::new(d, 1 + q),
                    c: T * ch.mu,
                })
            })
            .collect::<Result<_, _>>()?;
        let a = (-T / eq.beta).exp();
        let xhat0 = design.plant().xhat0.as_slice().to_vec();
        let mut zv = vec![0.0; nz + 3 * m];
        zv[q..nz].copy_from_slice(&xhat0);
        Ok(Controller {
            T,
            PhiGamma_z,
            a,
            b: 1.0 - a,
            channels,
            zv,
            xhat0,
            z_next: vec![0.0; nz],
            xi: vec![0.0; q],
            Delta: vec![0.0; q],
            Omega_eta: Aligned::new(q),
            ldl: vec![0.0; q * q],
            u: vec![0.0; m],
            u_f: vec![0.0; m],
            eta: vec![0.0; m * q],
            eq,
        })
    }

    /// One sample: reads y(k) and g(k), returns the plant input u_f(k) = −K x̂ + F u_d (5) to hold
    /// until the next sample. Allocates nothing. y or g of other than m entries
    /// ([`ControllerError::InputLength`]), or with an entry not finite or beyond ±[`MAX_MEASUREMENT`]
    /// ([`ControllerError::InputOutOfRange`]), is an error, and the state is left as it was.
    pub fn step(&mut self, y: &[f64], g: &[f64]) -> Result<&[f64], ControllerError> {
        let (m, q) = (self.eq.m, self.eq.q);
        check_inputs((y, g), m, MAX_MEASUREMENT)?;
        let cols = 1 + q;
        // ξ̂(k) = C_ξ z_k.
        let (nz, zv) = (self.eq.nz, &mut self.zv);
        self.xi.copy_from_slice(self.eq.regressor(&zv[..nz]));
        let (one_minus_a, a) = (self.b, self.a);
        for ((i, ch), eta) in self.channels.iter_mut().enumerate().zip(self.eta.chunks_exact_mut(q)) {
            // Control law (25) with η̂_i(k), then the delay line gives [u_i(k − d_i), ξ̂ᵀ(k − d_i)].
            self.u[i] = command(eta, &self.xi);
            let delayed = ch.line.push(self.u[i], &self.xi);
            zv[nz + 2 * m + i] = delayed[0];

            // Swapping error and filtered regressor from W_i(k) (eq. (33)).
            let eps = swapping_error(&self.eq.channels[i], &ch.W, y[i] - g[i], &mut self.Delta);
            // H filters at ZOH: Y ← aY + (1 − a)Δ ε̂,  Ω ← aΩ + (1 − a)(ΔΔᵀ).
            for (Yj, dj) in ch.Y.iter_mut().zip(&self.Delta) {
                *Yj = a * *Yj + one_minus_a * dj * eps;
            }
            // Adaptive law (33): one step, implicit where it is stiff (see `adapt`).
            let scratch = (self.Omega_eta.get(), &mut self.ldl[..]);
            adapt(ch.c, &mut ch.Omega, (a, one_minus_a), (&self.Delta, &ch.Y), eta, scratch);

            // G_ii filter bank: W ← Φ W + γ [u_i(k − d_i), ξ̂ᵀ(k − d_i)].
            let sigma = self.eq.channels[i].sigma();
            for r in 0..sigma {
                let out = &mut ch.W_next[r * cols..(r + 1) * cols];
                for (o, d) in out.iter_mut().zip(delayed) {
                    *o = ch.gamma[r] * d;
                }
                for s in 0..sigma {
                    let p = ch.Phi[(r, s)];
                    for (o, w) in out.iter_mut().zip(&ch.W[s * cols..(s + 1) * cols]) {
                        *o += p * w;
                    }
                }
            }
            std::mem::swap(&mut ch.W, &mut ch.W_next);
        }
        // Plant input (5) and the core's ZOH step with v = [y; g; u_d].
        zv[nz..nz + m].copy_from_slice(y);
        zv[nz + m..nz + 2 * m].copy_from_slice(g);
        let (z, u_d) = (&zv[..nz], &zv[nz + 2 * m..]);
        self.eq.plant_input(z, u_d, &mut self.u_f);
        mat_vec(&self.PhiGamma_z, zv, &mut self.z_next, false);
        zv[..nz].copy_from_slice(&self.z_next);
        // u = −η̂ᵀ ξ̂ is non-finite once η̂ or ξ̂ is, and u_f once x̂ or the delayed u is.
        match self.u_f.iter().chain(&self.u).find(|v| !v.is_finite()) {
            Some(&value) => Err(ControllerError::StateNotFinite { value }),
            None => Ok(&self.u_f),
        }
    }

    /// The adaptive command u(k) (25) of the last step, undelayed.
    pub fn command(&self) -> &[f64] {
        &self.u
    }

    /// η̂_1, …, η̂_m after the last step, concatenated (m·q).
    pub fn eta(&self) -> &[f64] {
        &self.eta
    }

    /// The regressor ξ̂ after the last step (q).
    pub fn xi_hat(&self) -> &[f64] {
        self.eq.regressor(&self.zv)
    }

    /// The observer state x̂ after the last step (n).
    pub fn x_hat(&self) -> &[f64] {
        self.eq.x_hat(&self.zv)
    }

    /// Sample time T_s.
    pub fn sample_time(&self) -> f64 {
        self.T
    }

    /// Number of channels m and regressor size q.
    pub fn dims(&self) -> (usize, usize) {
        (self.eq.m, self.eq.q)
    }

    /// Back to the initial state: every controller state and delay line zero but x̂, which starts
    /// at the design plant's `xhat0` (0 unless given), and so the last step's u and u_f (all of
    /// [`Controller::state`]).
    pub fn reset(&mut self) {
        self.zv.fill(0.0);
        let (q, nz) = (self.eq.q, self.eq.nz);
        self.zv[q..nz].copy_from_slice(&self.xhat0);
        self.eta.fill(0.0);
        self.u.fill(0.0);
        self.u_f.fill(0.0);
        for ch in &mut self.channels {
            ch.W.fill(0.0);
            ch.Y.fill(0.0);
            ch.Omega.fill(0.0);
            ch.line.clear();
        }
    }
}

/// A part of [`Controller::state`], named in [`ControllerError::BadState`].
#[derive(Debug, Clone, Copy)]
enum Part {
    Z,
    W(usize),
    Y(usize),
    Omega(usize),
    Line(usize),
    U,
    UF,
    Eta,
}

impl std::fmt::Display for Part {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Part::Z => write!(f, "z, the observers' state of eqs. (6), (14), (20)"),
            Part::W(i) => write!(f, "channel {}'s G_ii filter bank W_i", i + 1),
            Part::Y(i) => write!(f, "channel {}'s H filter Y_i (33)", i + 1),
            Part::Omega(i) => write!(f, "channel {}'s H filter Ω_i (33)", i + 1),
            Part::Line(i) => write!(f, "channel {}'s delay line of [u_i, ξ̂ᵀ]", i + 1),
            Part::U => write!(f, "the command u (25)"),
            Part::UF => write!(f, "the plant input u_f (5)"),
            Part::Eta => write!(f, "η̂ (33)"),
        }
    }
}

impl Controller {
    /// The parts of [`Controller::state`] in its order; a delay line from its oldest row, u_i(k − d_i).
    fn state_parts(&self) -> Vec<(Part, &[f64])> {
        let mut parts = vec![(Part::Z, &self.zv[..self.eq.nz])];
        for (i, ch) in self.channels.iter().enumerate() {
            let oldest = ch.line.head * ch.line.width;
            parts.extend([
                (Part::W(i), &ch.W[..]),
                (Part::Y(i), &ch.Y[..]),
                (Part::Omega(i), &ch.Omega[..]),
                (Part::Line(i), &ch.line.data[oldest..]),
                (Part::Line(i), &ch.line.data[..oldest]),
            ]);
        }
        parts.extend([(Part::U, &self.u[..]), (Part::UF, &self.u_f[..]), (Part::Eta, &self.eta[..])]);
        parts
    }

    /// Everything that evolves from step to step, a checkpoint for [`Controller::set_state`]:
    /// z (the observers of eqs. (6), (14), (20), n_z); then per channel i the G_ii filter bank
    /// W_i (σ_i × (1 + q), row-major), the H filters Y_i (q) and Ω_i (q × q, row-major) of (33) and
    /// the delay line's d_i + 1 rows [u_i, ξ̂ᵀ], oldest first; then u (25) and u_f (5) of the last
    /// step (m each) and η̂_1, …, η̂_m (33, m·q). Allocates the vector.
    pub fn state(&self) -> Vec<f64> {
        self.state_parts().into_iter().flat_map(|(_, p)| p).copied().collect()
    }

    /// The length of [`Controller::state`].
    pub fn state_len(&self) -> usize {
        self.state_parts().iter().map(|(_, p)| p.len()).sum()
    }

    /// Continues from a checkpoint: `state` from [`Controller::state`] of a controller of the same
    /// design and sample time, after which this one steps bit for bit as that one would have. A state
    /// of another length ([`ControllerError::StateLength`]), with an entry that is not finite, or
    /// with an Ω_i that is not exactly symmetric ([`ControllerError::BadState`]) is an error, and
    /// the state is left as it was.
    pub fn set_state(&mut self, state: &[f64]) -> Result<(), ControllerError> {
        let (q, parts) = (self.eq.q, self.state_parts());
        let expected = parts.iter().map(|(_, p)| p.len()).sum();
        if state.len() != expected {
            return Err(ControllerError::StateLength { expected, found: state.len() });
        }
        let mut at = 0;
        for (part, p) in parts {
            let bad = |index: usize, expected: String| {
                let part = part.to_string();
                Err(ControllerError::BadState { index, part, value: state[index], expected })
            };
            let s = &state[at..at + p.len()];
            if let Some(k) = s.iter().position(|v| !v.is_finite()) {
                return bad(at + k, "a finite number".into());
            }
            let asymmetric = |&(r, c): &(usize, usize)| s[r * q + c].to_bits() != s[c * q + r].to_bits();
            if let Part::Omega(_) = part {
                if let Some((r, c)) = (0..q * q).map(|k| (k / q, k % q)).find(asymmetric) {
                    return bad(at + r * q + c, format!("Ω_i exactly symmetric, equal to state[{}]", at + c * q + r));
                }
            }
            at += p.len();
        }
        // The order of `state_parts`, with each delay line's oldest row moved to the front.
        let mut rest = state;
        let mut fill = |into: &mut [f64]| {
            let (head, tail) = rest.split_at(into.len());
            into.copy_from_slice(head);
            rest = tail;
        };
        fill(&mut self.zv[..self.eq.nz]);
        for ch in &mut self.channels {
            fill(&mut ch.W);
            fill(&mut ch.Y);
            fill(&mut ch.Omega);
            fill(&mut ch.line.data);
            ch.line.head = 0;
        }
        fill(&mut self.u);
        fill(&mut self.u_f);
        fill(&mut self.eta);
        Ok(())
    }
}

/// The discretized matrices of a [`Controller`], read-only, for code generation ([`crate::export`]).
pub(crate) struct Discretized<'c> {
    /// The continuous-time equations (dimensions, −K, F, each channel's σ_i and q_i0).
    pub eq: &'c Equations,
    /// [Φ_z Γ_z]: z_{k+1} = Φ_z z_k + Γ_z [y_k; g_k; u_d(k)].
    pub PhiGamma_z: &'c DMatrix<f64>,
    /// a = e^{−T_s/β} and b = 1 − a of H(s) at ZOH.
    pub a: f64,
    pub b: f64,
    /// Per channel: its G_ii filter bank and delay line.
    pub channels: Vec<DiscreteChannel<'c>>,
    /// x̂ at the start and after a reset.
    pub xhat0: &'c [f64],
}

/// One channel of [`Discretized`].
pub(crate) struct DiscreteChannel<'c> {
    /// G_ii filter bank at ZOH: W ← Φ_i W + γ_i [u_i(k − d_i), ξ̂ᵀ(k − d_i)].
    pub Phi: &'c DMatrix<f64>,
    pub gamma: &'c [f64],
    /// The adaptation step c_i = T_s μ_i (33).
    pub c: f64,
    /// d_i = τ_i / T_s, in samples.
    pub delay_samples: usize,
}

impl Controller {
    /// The read-only view of every discretized matrix.
    pub(crate) fn discretized(&self) -> Discretized<'_> {
        Discretized {
            eq: &self.eq,
            PhiGamma_z: &self.PhiGamma_z,
            a: self.a,
            b: self.b,
            channels: self
                .channels
                .iter()
                .map(|ch| DiscreteChannel { Phi: &ch.Phi, gamma: &ch.gamma, c: ch.c, delay_samples: ch.line.len - 1 })
                .collect(),
            xhat0: &self.xhat0,
        }
    }
}

/// y and g of `m` entries each, none NaN or beyond ±`bound`: [`Controller::step`]'s checks, with
/// its bound or the f32 step's ([`SinglePrecision`]).
fn check_inputs((y, g): (&[f64], &[f64]), m: usize, bound: f64) -> Result<(), ControllerError> {
    for (name, v) in [("y", y), ("g", g)] {
        if v.len() != m {
            return Err(ControllerError::InputLength { name, expected: m, found: v.len() });
        }
        if let Some(index) = v.iter().position(|x| x.is_nan() || x.abs() > bound) {
            return Err(ControllerError::InputOutOfRange { name, index, value: v[index] });
        }
    }
    Ok(())
}

/// The discrete controller as a single-precision build computes it, emulated: every constant
/// rounded to f32 once, as the f32 export writes them; y and g rounded to f32; the
/// core's products (the observers' update and u_f = −K x̂ + F u_d, sums whose terms can cancel far
/// above their result) in f32 arithmetic, in the generated C's order; and every state rounded to
/// f32 after each step. The adaptive law's and the filters' operations stay f64, their results
/// rounded. `tests/export_c.rs` holds it to the compiled f32 C in closed loop: the C's departure
/// from f64 was 0.4–2.8× the emulation's on six plants (up to 6.2× on a seventh, a power system's generator), among them a disk servo whose u_f departs
/// 18 % of its peak (the emulation without the core's products in f32 had read 0.15 %).
#[derive(Debug, Clone)]
pub(crate) struct SinglePrecision {
    ctrl: Controller,
    y: Vec<f64>,
    g: Vec<f64>,
    /// [z_k; y_k; g_k; u_d(k)], z_k kept from before the step, for the core's products in f32.
    zv: Vec<f64>,
}

/// out = M x (out += M x when `add`) in f32 arithmetic, each product and sum rounded to float, in
/// the order of [`mat_vec`] and the generated C (column by column).
fn mat_vec_f32(M: &DMatrix<f64>, x: &[f64], out: &mut [f64], add: bool) {
    for (i, o) in out.iter_mut().enumerate() {
        let mut sum = if add { *o as f32 } else { 0.0 };
        for (j, &xj) in x.iter().enumerate() {
            sum += M[(i, j)] as f32 * xj as f32;
        }
        *o = f64::from(sum);
    }
}

/// Each entry rounded to the nearest f32 (±∞ beyond its range, as an f32 build overflows).
fn to_f32(values: &mut [f64]) {
    for v in values {
        *v = f64::from(*v as f32);
    }
}

impl SinglePrecision {
    /// `ctrl` with its constants rounded to f32.
    pub(crate) fn new(mut ctrl: Controller) -> SinglePrecision {
        to_f32(ctrl.PhiGamma_z.as_mut_slice());
        to_f32(ctrl.eq.K_neg.as_mut_slice());
        to_f32(ctrl.eq.F.as_mut_slice());
        let mut ab = [ctrl.a, ctrl.b];
        to_f32(&mut ab);
        [ctrl.a, ctrl.b] = ab;
        for (ch, filter) in ctrl.channels.iter_mut().zip(&mut ctrl.eq.channels) {
            to_f32(ch.Phi.as_mut_slice());
            to_f32(&mut ch.gamma);
            to_f32(std::slice::from_mut(&mut ch.c));
            // q_i0 = a_0 of G_ii's denominator; the rest served the discretization, done already.
            to_f32(&mut filter.tf.den[..1]);
        }
        let (m, width) = (ctrl.eq.m, ctrl.zv.len());
        SinglePrecision { ctrl, y: vec![0.0; m], g: vec![0.0; m], zv: vec![0.0; width] }
    }

    /// [`Controller::step`] on y, g rounded to f32, its core's products (the observers' update and
    /// u_f, sums of terms that can cancel) done again in f32, then every state rounded to f32.
    pub(crate) fn step(&mut self, y: &[f64], g: &[f64]) -> Result<&[f64], ControllerError> {
        let nz = self.ctrl.eq.nz;
        check_inputs((y, g), self.ctrl.eq.m, super::Precision::F32.input_bound())?;
        self.zv[..nz].copy_from_slice(&self.ctrl.zv[..nz]);
        self.y.copy_from_slice(y);
        self.g.copy_from_slice(g);
        to_f32(&mut self.y);
        to_f32(&mut self.g);
        self.ctrl.step(&self.y, &self.g)?;
        let c = &mut self.ctrl;
        // The step left [z_{k+1}; y_k; g_k; u_d(k)]: the held inputs beside z_k.
        self.zv[nz..].copy_from_slice(&c.zv[nz..]);
        let (z, u_d) = (&self.zv[..nz], &self.zv[nz + 2 * c.eq.m..]);
        mat_vec_f32(&c.eq.K_neg, c.eq.x_hat(z), &mut c.u_f, false);
        mat_vec_f32(&c.eq.F, u_d, &mut c.u_f, true);
        mat_vec_f32(&c.PhiGamma_z, &self.zv, &mut c.zv[..nz], false);
        for v in [&mut c.zv[..], &mut c.u, &mut c.u_f, &mut c.eta] {
            to_f32(v);
        }
        for ch in &mut c.channels {
            for v in [&mut ch.W[..], &mut ch.Y, &mut ch.Omega, ch.line.newest()] {
                to_f32(v);
            }
        }
        // Beyond float's range the rounding gives ±∞, which the f32 C's own check returns as 2.
        match c.u_f.iter().chain(&c.u).find(|v| !v.is_finite()) {
            Some(&value) => Err(ControllerError::StateNotFinite { value }),
            None => Ok(&self.ctrl.u_f),
        }
    }

    /// The controller, for its command and watched states.
    pub(crate) fn controller(&self) -> &Controller {
        &self.ctrl
    }
}

/// c·tr Ω up to which [`adapt`] takes the O(q²) explicit Euler step η̂ ← η̂ + c (Y − Ω η̂): every
/// direction contracts by 1 − cλ ∈ [0.95, 1] (λ ≤ tr Ω), nonexpansive, at its own continuous rate to
/// first order in T_s, for a tenth of the factorization at q = 8 (the paper's example at T_s = 1 ms
/// peaks at c·tr Ω = 0.021).
pub(crate) const IMPLICIT_FROM: f64 = 0.05;

with_avx2! {
    /// The H filter Ω ← aΩ + bΔΔᵀ (ZOH of H(s)), then one step of η̂' = μ (Y − Ω η̂) (33) with
    /// c = T_s μ and Y, Ω held over the sample. Beyond c·tr Ω = [`IMPLICIT_FROM`] the implicit Euler
    /// step (I + cΩ) δ = c (Y − Ω η̂), η̂ ← η̂ + δ, solved by I + cΩ = Uᵀ D U (U unit upper
    /// triangular; no square root, so the generated C needs no libm): along an eigendirection of Ω
    /// with eigenvalue λ it contracts by 1/(1 + cλ) (the continuous law: e^(−cλ)), so it is
    /// nonexpansive for every μ ≥ 0 and T_s, its fixed points are those of (33), and a direction the
    /// sample time resolves (cλ ≪ 1) adapts at the continuous rate however stiff the others are.
    /// Up to it, explicit Euler, η̂ ← η̂ + c (Y − Ω η̂), with the same properties at O(q²): each
    /// direction contracts by 1 − cλ ∈ [0.95, 1]. (The step implicit in ρI = (tr Ω) I taken there
    /// until 2026-12-05 divided every direction's rate by 1 + c tr Ω, up to 5 % at the switch
    /// whatever T_s: on a reactor with μ ≈ 2e4 the sampled loop then did not approach the continuous
    /// one at first order in T_s, docs/sampled-data.md.) The pivots of I + cΩ
    /// are ≥ λ_min(I + cΩ) ≥ 1; one rounded below 1 is taken as 1, and one lost to rounding (below
    /// 64 q ε of its diagonal, where cΩ exceeds 1/ε along a null direction of Ω, whose exact
    /// right-hand side is below the rounding too) leaves that direction still, as the continuous law
    /// does along null(Ω).
    ///
    /// `Omega` is the full q×q matrix (row-major), kept exactly symmetric: b (Δ_i Δ_j) rounds as
    /// b (Δ_j Δ_i). One pass over its rows updates it and sums (Ω η̂)_j = Σ_i Ω_ij η̂_i over i in order
    /// and tr Ω into `tmp`, as the generated C does ([`crate::export`], which keeps the triangle
    /// only); false, with the step not taken, beyond [`IMPLICIT_FROM`] ([`adapt`] takes it then, out
    /// of line, so that this loop stays as lean as before). The continuous loop keeps Ω packed
    /// (`controller/packed.rs`), because there it is integrated state; here full rows make the pass
    /// contiguous (`docs/performance.md`).
    ///
    /// `signals` are (Δ, Y); the buffers must fit q = eta.len() (Omega q·q, Δ, Y and tmp q; `ldl`
    /// of [`adapt`] q·q): the controller builds them to size.
    fn filter_and_step(
        c: f64,
        Omega: &mut [f64],
        ab: (f64, f64),
        signals: (&[f64], &[f64]),
        eta: &mut [f64],
        tmp: &mut [f64],
    ) -> bool {
        let ((a, b), q, (Delta, Y)) = (ab, eta.len(), signals);
        assert!(Omega.len() == q * q && Delta.len() == q && Y.len() == q && tmp.len() == q, "adapt: dimension mismatch");
        tmp.fill(0.0);
        let mut trace = 0.0;
        for (i, (row, &eta_i)) in Omega.chunks_exact_mut(q).zip(eta.iter()).enumerate() {
            let d_i = Delta[i];
            for ((o, d_j), t) in row.iter_mut().zip(Delta).zip(tmp.iter_mut()) {
                *o = a * *o + b * (d_i * d_j);
                *t += *o * eta_i;
            }
            trace += row[i];
        }
        if c * trace > IMPLICIT_FROM {
            return false;
        }
        for ((e, y), w) in eta.iter_mut().zip(Y).zip(tmp.iter()) {
            *e += c * (y - w);
        }
        true
    }
}

/// [`filter_and_step`], then the implicit step where it declined (`tmp` holds Ω η̂ then).
pub(crate) fn adapt(
    c: f64,
    Omega: &mut [f64],
    ab: (f64, f64),
    signals: (&[f64], &[f64]),
    eta: &mut [f64],
    (tmp, ldl): (&mut [f64], &mut [f64]),
) {
    if !filter_and_step(c, Omega, ab, signals, eta, tmp) {
        implicit_step(c, Omega, signals.1, eta, (tmp, ldl));
    }
}

/// η̂ ← η̂ + δ with (I + cΩ) δ = c (Y − Ω η̂), `tmp` holding Ω η̂ on entry and δ on return, by
/// I + cΩ = Uᵀ D U, U unit upper triangular, in `ldl` (q×q by rows, the upper triangle used: d_j on
/// the diagonal, U_jt after it). Row j is final once rows 0 … j − 1 are eliminated from it;
/// U_jt = s_jt·(1/d_j), and row j is eliminated from each later row l by s_lt −= (U_jl d_j) U_jt
/// (t ≥ l). A pivot within rounding of 0 against its diagonal (cΩ beyond 1/ε along a null direction
/// of Ω, where the exact pivot 1 and right-hand side are below the rounding of cΩ) is stored as 0
/// with its row of U: that direction does not move. Out of line, so that [`filter_and_step`] stays
/// lean; the generated C does the same operations in the same order ([`crate::export`]).
#[inline(never)]
fn implicit_step(c: f64, Omega: &[f64], Y: &[f64], eta: &mut [f64], (r, factor): (&mut [f64], &mut [f64])) {
    let q = eta.len();
    assert!(factor.len() == q * q, "adapt: dimension mismatch");
    for (t, y) in r.iter_mut().zip(Y) {
        *t = c * (y - *t);
    }
    for (i, (f, o)) in factor.chunks_exact_mut(q).zip(Omega.chunks_exact(q)).enumerate() {
        for (f, o) in f[i..].iter_mut().zip(&o[i..]) {
            *f = c * o;
        }
        f[i] += 1.0;
    }
    let negligible = 64.0 * q as f64 * f64::EPSILON;
    for j in 0..q {
        let (head, later) = factor.split_at_mut((j + 1) * q);
        let u = &mut head[j * q..];
        let scale = c * Omega[j * q + j] + 1.0;
        let kept = u[j] > negligible * scale;
        let d = match (kept, u[j] >= 1.0) {
            (false, _) => 0.0,
            (true, true) => u[j],
            (true, false) => 1.0,
        };
        let inverse = if kept { 1.0 / d } else { 0.0 };
        u[j] = d;
        for x in &mut u[j + 1..] {
            *x = if kept { *x * inverse } else { 0.0 };
        }
        for (l, row) in (j + 1..q).zip(later.chunks_exact_mut(q)) {
            let wl = u[l] * d;
            for (x, ut) in row[l..].iter_mut().zip(&u[l..]) {
                *x -= wl * ut;
            }
        }
    }
    // Uᵀ z = r (by rows of U), then D w = z, then U δ = w, in place; η̂ ← η̂ + δ.
    for (k, u) in factor.chunks_exact(q).enumerate() {
        let zk = r[k];
        for (x, ukj) in r[k + 1..].iter_mut().zip(&u[k + 1..]) {
            *x -= ukj * zk;
        }
    }
    for (j, u) in factor.chunks_exact(q).enumerate() {
        r[j] = if u[j] == 0.0 { 0.0 } else { r[j] / u[j] };
    }
    for (j, u) in factor.chunks_exact(q).enumerate().rev() {
        r[j] = u[j + 1..].iter().zip(&r[j + 1..]).fold(r[j], |s, (ujt, x)| s - ujt * x);
    }
    for (e, d) in eta.iter_mut().zip(r.iter()) {
        *e += d;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::noise::Gaussian;

    #[test]
    fn the_sample_time_within_a_bound_is_round_where_one_divides_the_delays() {
        // The paper's delays 1 and 3 under 0.0222: 0.02 (not 1/46 = 0.0217…, the longest τ/k).
        assert_eq!(sample_time_at_most(&[1.0, 3.0], 9, 0.0222), Some(0.02));
        // 0.05 ms under 0.00265: 0.0025 (20 samples).
        assert_eq!(sample_time_at_most(&[0.05], 9, 0.00265), Some(0.0025));
        // No round value divides 1/3: the longest τ/k below the bound, 1/3/16 = 0.0208…, is whole.
        let t = sample_time_at_most(&[1.0 / 3.0], 9, 0.0222).unwrap();
        assert!(t <= 0.0222 && whole(1.0 / 3.0, t) && (t - 1.0 / 48.0).abs() < 1e-9, "{t}");
    }

    /// Uniform on (lo, hi].
    fn between(rng: &mut Gaussian, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * rng.uniform()
    }

    /// Uniform on {0, …, n − 1}.
    fn below(rng: &mut Gaussian, n: usize) -> usize {
        ((rng.uniform() * n as f64) as usize).min(n - 1)
    }

    /// Whole samples counted to the relative tolerance, where ⌊x/T⌋ alone loses one: 0.3/0.1 is
    /// 2.9999999999999996, and 8564884.1/0.1 is 85648840.99999999 (1e-8 below, beyond an absolute
    /// 1e-9); a ratio that is not whole is floored.
    #[test]
    fn grid_times_are_the_nearest_doubles_to_the_decimals() {
        // Against Rust's own decimal parser (correctly rounded): t_k is "k·T" written in decimal.
        let grid = Grid::new(0.1);
        for k in 0..100_000usize {
            let decimal = format!("{}.{}", k / 10, k % 10);
            assert_eq!(grid.at(k), decimal.parse::<f64>().unwrap(), "k = {k}");
        }
        assert_eq!(format!("{}", Grid::new(0.1).at(3)), "0.3");
        assert_eq!(format!("{}", Grid::new(1e-4).at(7)), "0.0007");
        assert_eq!(format!("{}", Grid::new(0.05).at(2_000_001)), "100000.05");
        // A step of no short decimal form, and integers, keep k·T.
        let third = 1.0 / 3.0;
        assert_eq!(Grid::new(third).at(1000), 1000.0 * third);
        assert_eq!(Grid::new(2.0).at(7), 14.0);
        assert_eq!(Grid::new(0.1).at(0), 0.0);
    }

    #[test]
    fn whole_samples_counts_a_ratio_rounded_below_an_integer_as_that_integer() {
        assert_eq!(whole_samples(0.3, 0.1), 3);
        assert_eq!(whole_samples(8564884.1, 0.1), 85_648_841);
        assert_eq!(whole_samples(100.0, 0.1), 1000);
        assert_eq!(whole_samples(1.05, 0.1), 10);
        assert_eq!(whole_samples(0.0, 0.1), 0);
    }

    #[test]
    fn adaptive_step_is_nonexpansive_for_any_gain() {
        // With Y = 0, η ↦ (I + cΩ)⁻¹ η must not grow for any PSD Ω and any c = T_s μ ≥ 0, including
        // huge ones where explicit Euler (factor 1 − cλ) would blow up.
        let mut rng = Gaussian::new(11);
        for _ in 0..2000 {
            let q = 1 + below(&mut rng, 12);
            let rank = 1 + below(&mut rng, q);
            let V = DMatrix::from_fn(q, rank, |_, _| between(&mut rng, -1.0, 1.0)) * between(&mut rng, 0.0, 30.0);
            let Om = &V * V.transpose();
            let mut omega: Vec<f64> = Om.iter().copied().collect();
            let c = 10f64.powf(between(&mut rng, -4.0, 8.0));
            let mut eta: Vec<f64> = (0..q).map(|_| between(&mut rng, -1.0, 1.0)).collect();
            let before: f64 = eta.iter().map(|v| v * v).sum::<f64>().sqrt();
            let (mut tmp, mut ldl) = (vec![0.0; q], vec![0.0; q * q]);
            adapt(c, &mut omega, (1.0, 0.0), (&vec![0.0; q], &vec![0.0; q]), &mut eta, (&mut tmp, &mut ldl));
            let after: f64 = eta.iter().map(|v| v * v).sum::<f64>().sqrt();
            assert!(after <= before * (1.0 + 1e-12), "grew from {before} to {after} (c = {c})");
        }
    }

    #[test]
    fn adaptive_step_keeps_omega_exactly_symmetric_and_solves_the_implicit_step() {
        // The C export keeps Ω's triangle only, so the Controller's full Ω must stay symmetric to the
        // last bit; and the step is (I + cΩ) δ = c (Y − Ω η̂), checked against nalgebra's LU solve of
        // the same system to 1e-12 of |δ| (the factors' rounding, cond(I + cΩ) ≤ 1 + c tr Ω ≈ 1e3 here),
        // or the explicit Euler step c (Y − Ω η̂) while c tr Ω ≤ IMPLICIT_FROM (the first few steps).
        let mut rng = Gaussian::new(5);
        for q in [1, 2, 3, 5, 8, 13, 16, 32] {
            let mut omega = vec![0.0; q * q];
            let (mut eta, mut tmp, mut ldl) = (vec![0.0; q], vec![0.0; q], vec![0.0; q * q]);
            let a = between(&mut rng, 0.5, 1.0);
            for _ in 0..50 {
                let Delta: Vec<f64> = (0..q).map(|_| between(&mut rng, -3.0, 3.0)).collect();
                let Y: Vec<f64> = (0..q).map(|_| between(&mut rng, -1.0, 1.0)).collect();
                let eta_before = eta.clone();
                adapt(0.7, &mut omega, (a, 1.0 - a), (&Delta, &Y), &mut eta, (&mut tmp, &mut ldl));
                for i in 0..q {
                    for j in 0..i {
                        assert_eq!(omega[i * q + j].to_bits(), omega[j * q + i].to_bits(), "q {q}: Ω[{i}][{j}]");
                    }
                }
                let Om = DMatrix::from_row_slice(q, q, &omega);
                let before = nalgebra::DVector::from_row_slice(&eta_before);
                let rhs = (nalgebra::DVector::from_row_slice(&Y) - &Om * &before) * 0.7;
                let trace = 0.7 * Om.trace();
                let want = match trace <= IMPLICIT_FROM {
                    true => rhs,
                    false => (DMatrix::identity(q, q) + Om * 0.7).lu().solve(&rhs).unwrap(),
                };
                let got = nalgebra::DVector::from_row_slice(&eta) - before;
                assert!((&got - &want).norm() <= 1e-12 * want.norm().max(1e-300), "q {q}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn the_implicit_step_adapts_a_resolved_direction_at_the_continuous_rate() {
        // Ω = diag(1e6, 1e-2), Y = 0, c = 1e-3: the stiff direction contracts by 1/(1 + 1e3), the slow
        // one by 1/(1 + 1e-5) ≈ e^(−1e-5), the continuous law's factor to 5e-11; a step normalized
        // by 1 + c tr Ω would slow the latter a thousandfold (1 − 1e-5/1001).
        let mut omega = [1e6, 0.0, 0.0, 1e-2];
        let (mut eta, mut tmp, mut ldl) = ([1.0, 1.0], [0.0; 2], [0.0; 4]);
        adapt(1e-3, &mut omega, (1.0, 0.0), (&[0.0; 2], &[0.0; 2]), &mut eta, (&mut tmp, &mut ldl));
        assert!((eta[0] - 1.0 / 1001.0).abs() < 1e-15, "{eta:?}");
        assert!((eta[1] - (-1e-5f64).exp()).abs() < 5e-11, "{eta:?}");
    }

    #[test]
    fn adaptive_step_converges_to_the_least_squares_fixed_point() {
        // For constant PD Ω and Y, repeated steps converge to Ω⁻¹ Y (the fixed point of (33)).
        let Om = DMatrix::from_row_slice(2, 2, &[2.0, 0.5, 0.5, 1.0]);
        let mut omega = [2.0, 0.5, 0.5, 1.0];
        let Y = [1.0, -1.0];
        let want = Om.try_inverse().unwrap() * nalgebra::DVector::from_row_slice(&Y);
        let (mut eta, mut tmp, mut ldl) = (vec![0.0; 2], vec![0.0; 2], vec![0.0; 4]);
        for _ in 0..2000 {
            adapt(0.1, &mut omega, (1.0, 0.0), (&[0.0; 2], &Y), &mut eta, (&mut tmp, &mut ldl));
        }
        assert!((eta[0] - want[0]).abs() < 1e-12 && (eta[1] - want[1]).abs() < 1e-12, "{eta:?} vs {want}");
    }

    #[test]
    fn adaptive_step_applies_the_h_filter_to_omega_first() {
        // Ω ← aΩ + bΔΔᵀ with Ω = I, a = 0.5, b = 0.25, Δ = [1, 2]: [[0.75, 0.5], [0.5, 1.5]] (by hand);
        // with c = 0 the parameters do not move.
        let mut omega = [1.0, 0.0, 0.0, 1.0];
        let (mut eta, mut tmp, mut ldl) = ([0.3, -0.7], [0.0; 2], [0.0; 4]);
        adapt(0.0, &mut omega, (0.5, 0.25), (&[1.0, 2.0], &[1.0, 1.0]), &mut eta, (&mut tmp, &mut ldl));
        assert_eq!(omega, [0.75, 0.5, 0.5, 1.5]);
        assert_eq!(eta, [0.3, -0.7]);
    }
}
