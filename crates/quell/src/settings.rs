//! What a run is asked for, and the limits on it: horizon, output step, tolerances, sample time and
//! measurement noise. Each is checked once, here; the scenario reader ([`crate::scenario`]) and both
//! loops ([`crate::sim`]) call these checks, so the boundary module does not know the simulator and
//! the library refuses what the scenario file would.

use crate::signal::Signal;
use thiserror::Error;

/// A value out of range, named by its scenario key path (`simulation.t_end`, `noise.std[1]`), with
/// what was expected and found. Each front names the key in its own words where it differs (the CLI
/// adds the flag that overrides it, Python the argument).
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{key}: {message}")]
pub struct KeyError {
    pub key: String,
    pub message: String,
}

impl KeyError {
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        KeyError { key: key.into(), message: message.into() }
    }
}

/// The integrator's default relative and absolute tolerance (`simulation.rtol`, `atol`).
pub const DEFAULT_TOLERANCE: f64 = 1e-9;

/// Most rows a run records (t_end / output_step); their bytes are budgeted too
/// ([`MAX_RECORD_BYTES`]).
pub const MAX_OUTPUT_SAMPLES: f64 = 1e7;

/// Most bytes of recorded signals a run keeps in memory (2 GiB): rows × 8·(1 + 5m + m·q, + 2n with
/// the states). Rows of more than 27 numbers reach it before [`MAX_OUTPUT_SAMPLES`]: the SI supply
/// vessel's 52 numbers a row held 837 MB at 2e6 rows, so 1e7 would have taken 4.2 GB (5.1 GB with
/// the states) and written a 10.6 GB signals.csv.
pub const MAX_RECORD_BYTES: f64 = 2.0 * 1024.0 * 1024.0 * 1024.0;

/// Largest scenario or study text read (16 MiB). Parsing TOML takes about 95 bytes of memory per
/// byte of text (a 24 MB array of small numbers took 2 GB before its length was checked), so this
/// bounds the parse at about 1.6 GB. The paper's example is 2 kB, and a plant of n = 500 states
/// (the most a design takes) about 6 MB with every number at full precision; anything longer is
/// the wrong path (`/dev/zero`) or a generated mistake.
pub const MAX_INPUT_BYTES: u64 = 16 << 20;

/// Why a text of `len` bytes is too long to parse ([`MAX_INPUT_BYTES`]), or `None`.
pub fn input_too_long(len: usize) -> Option<String> {
    (len as u64 > MAX_INPUT_BYTES).then(|| {
        format!(
            "longer than {} MiB, the most a scenario or study file may be (is it the right path? a device such as /dev/zero never ends; parsing takes about 100 bytes of memory per byte)",
            MAX_INPUT_BYTES >> 20
        )
    })
}

/// Reads a scenario or study file as text, at most [`MAX_INPUT_BYTES`] of it; the message (without
/// the path, which the caller names) says what is wrong. Only a regular file is read: a FIFO
/// without a writer would block for ever.
pub fn read_input(path: &std::path::Path) -> Result<String, String> {
    use std::io::Read;
    // Before opening: opening a FIFO for reading waits for a writer.
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let kind = std::fs::metadata(path).map_err(|e| e.to_string())?.file_type();
        if kind.is_fifo() || kind.is_socket() {
            return Err("a pipe or socket, not a file; give the path of a scenario or study file".into());
        }
        // A terminal waits for typing that never ends the read (Scenario.load of /dev/pts/N had
        // blocked past Ctrl-C); no device holds a scenario.
        if kind.is_char_device() || kind.is_block_device() {
            return Err("a device, not a file; give the path of a scenario or study file".into());
        }
    }
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    file.take(MAX_INPUT_BYTES + 1).read_to_end(&mut bytes).map_err(|e| e.to_string())?;
    if let Some(e) = input_too_long(bytes.len()) {
        return Err(e);
    }
    // A UTF-16 byte-order mark (Windows editors' "Unicode"): named, with the way out.
    if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
        return Err("UTF-16 text, not UTF-8; save the file as UTF-8".into());
    }
    String::from_utf8(bytes).map_err(|e| {
        format!("not UTF-8 text (invalid byte at offset {}); save the file as UTF-8", e.utf8_error().valid_up_to())
    })
}

/// The candidate nearest to `name` (at most two edits apart, ignoring case): what a message
/// suggests for a misspelt key or name.
pub fn nearest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let lower = name.to_lowercase();
    candidates
        .into_iter()
        .map(|c| (strsim::levenshtein(&c.to_lowercase(), &lower), c))
        .filter(|(d, _)| *d <= 2)
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

/// The integrator of the continuous loop's steps (`simulation.method`), named in scenario files,
/// flags and Python by [`Method::name`]: `"auto"`, `"explicit"`, `"imex"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// `"auto"`: DOP853, switching to [`Method::Implicit`] while the adaptive law (33) limits
    /// DOP853's step by stability, and back when it no longer would.
    #[default]
    Auto,
    /// `"explicit"`: DOP853 throughout.
    Explicit,
    /// `"imex"`: the implicit–explicit pair ARK4(3)6L\[2\]SA throughout, implicit in η̂ (33) only,
    /// explicit in every other component.
    Implicit,
}

impl Method {
    /// Every method with its name and what it does, as messages list them.
    const ALL: [(Method, &'static str, &'static str); 3] = [
        (Method::Auto, "auto", "DOP853, implicit in η̂ while the adaptive law is stiff; the default"),
        (Method::Explicit, "explicit", "DOP853 throughout"),
        (Method::Implicit, "imex", "ARK4(3)6L[2]SA throughout, implicit in η̂"),
    ];

    /// The name scenario files, the CLI and Python use.
    pub fn name(self) -> &'static str {
        Self::ALL.iter().find(|(m, ..)| *m == self).map_or("auto", |(_, n, _)| n)
    }

    /// The method named `name`, or the message (without a key) listing the names, with the
    /// nearest one (also for the enum's own names, so `"implicit"` suggests `"imex"`).
    pub fn from_name(name: &str) -> Result<Method, String> {
        if let Some((m, ..)) = Self::ALL.iter().find(|(_, n, _)| *n == name) {
            return Ok(*m);
        }
        let aliases = Self::ALL.iter().map(|(_, n, _)| *n).chain(["implicit", "dop853"]);
        let hint = nearest(name, aliases)
            .map(|n| match n {
                "implicit" => "imex",
                "dop853" => "explicit",
                n => n,
            })
            .map(|n| format!(" (did you mean \"{n}\"?)"))
            .unwrap_or_default();
        let list: Vec<String> = Self::ALL.iter().map(|(_, n, what)| format!("\"{n}\" ({what})")).collect();
        Err(format!("expected {} or {}, found \"{name}\"{hint}", list[..2].join(", "), list[2]))
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The unit of time of a plant model (`[plant] time_unit`), as MATLAB's `TimeUnit`: the unit of
/// t, of the delays τ_i, of 1/λ for every pole and of 2π/ω for every frequency. quell computes in
/// whatever unit the matrices are written in; this only labels the results.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TimeUnit {
    Microseconds,
    Milliseconds,
    #[default]
    Seconds,
    Minutes,
    Hours,
    Days,
}

impl TimeUnit {
    /// Every unit with its symbol (what files hold and labels show) and its name.
    const ALL: [(TimeUnit, &'static str, &'static str); 6] = [
        (TimeUnit::Microseconds, "µs", "microseconds"),
        (TimeUnit::Milliseconds, "ms", "milliseconds"),
        (TimeUnit::Seconds, "s", "seconds"),
        (TimeUnit::Minutes, "min", "minutes"),
        (TimeUnit::Hours, "h", "hours"),
        (TimeUnit::Days, "d", "days"),
    ];

    /// One unit in seconds: 1e-6 … 86400.
    pub fn seconds(self) -> f64 {
        match self {
            TimeUnit::Microseconds => 1e-6,
            TimeUnit::Milliseconds => 1e-3,
            TimeUnit::Seconds => 1.0,
            TimeUnit::Minutes => 60.0,
            TimeUnit::Hours => 3600.0,
            TimeUnit::Days => 86400.0,
        }
    }

    /// The symbol: `"µs"`, `"ms"`, `"s"`, `"min"`, `"h"`, `"d"`.
    pub fn symbol(self) -> &'static str {
        Self::ALL.iter().find(|(u, ..)| *u == self).map_or("s", |(_, s, _)| s)
    }

    /// The name: `"seconds"`, `"minutes"`, ….
    pub fn name(self) -> &'static str {
        Self::ALL.iter().find(|(u, ..)| *u == self).map_or("seconds", |(.., n)| n)
    }

    /// The unit given by its symbol or its name (`"us"` for µs too), or the message (without a
    /// key) listing the symbols, with the nearest one.
    pub fn from_name(given: &str) -> Result<TimeUnit, String> {
        let found = Self::ALL.iter().find(|(_, s, n)| given == *s || given == *n || (*s == "µs" && given == "us"));
        if let Some((u, ..)) = found {
            return Ok(*u);
        }
        // The nearest symbol or name, said as the list says its unit ("day": "d" (days)).
        let names = Self::ALL.iter().flat_map(|(_, s, n)| [*s, *n]);
        let unit = |near: &str| Self::ALL.iter().find(|(_, s, n)| near == *s || near == *n).map(|(_, s, n)| (*s, *n));
        // Spaces around a unit: that unit, said so (" s" had been offered "µs", one edit away).
        let trimmed = given.trim();
        let hint = match unit(trimmed).filter(|_| trimmed != given) {
            Some((s, n)) => format!(" (did you mean \"{s}\" ({n}), without the spaces?)"),
            None => (nearest(trimmed, names).and_then(unit))
                .map(|(s, n)| format!(" (did you mean \"{s}\" ({n})?)"))
                .unwrap_or_default(),
        };
        let list: Vec<String> = Self::ALL.iter().map(|(_, s, n)| format!("\"{s}\" ({n})")).collect();
        Err(format!("expected one of {}, found \"{given}\"{hint}", list.join(", ")))
    }
}

impl std::fmt::Display for TimeUnit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.symbol())
    }
}

/// Most controller steps of a sampled-data run (t_end / sample_time).
pub const MAX_SAMPLING_STEPS: f64 = 1e10;

/// Gaussian measurement noise on y: standard deviation per output and a seed. Without a
/// `bandwidth` it is white at the sample rate (sampled-data runs only); with one it is band-limited
/// to `bandwidth` cycles per unit of the plant's time (Hz for a plant in seconds;
/// [`crate::sim::noise::band_limited`]), the same n(t) in both loops.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasurementNoise {
    pub std: Vec<f64>,
    pub seed: u64,
    /// Highest frequency of the band-limited noise, in cycles per unit of time; `None`: white at the sample rate.
    pub bandwidth: Option<f64>,
}

impl MeasurementNoise {
    /// White noise at the sample rate.
    pub fn white(std: Vec<f64>, seed: u64) -> Self {
        MeasurementNoise { std, seed, bandwidth: None }
    }

    /// One finite standard deviation ≥ 0 per output (m of them); a bandwidth > 0 and finite.
    pub fn check(&self, m: usize) -> Result<(), KeyError> {
        if self.std.len() != m {
            return Err(KeyError::new(
                "noise.std",
                format!("expected {} (one per output), found {}", entries(m), self.std.len()),
            ));
        }
        if let Some(b) = self.bandwidth {
            positive("noise.bandwidth", "a bandwidth in cycles per unit of time (Hz for a plant in seconds)", b)?;
        }
        if let Some((i, s)) = self.std.iter().enumerate().find(|(_, s)| !(**s >= 0.0 && s.is_finite())) {
            let finite = if *s >= 0.0 { "finite " } else { "" };
            return Err(KeyError::new(
                format!("noise.std[{i}]"),
                format!("expected a {finite}standard deviation ≥ 0, found {}", fmt_short(*s)),
            ));
        }
        // The noise enters y as a signal does: bounded as a signal's amplitudes are.
        for (i, &s) in self.std.iter().enumerate() {
            crate::signal::moderate(&format!("noise.std[{i}]"), "a standard deviation", s, "the outputs' units")?;
        }
        Ok(())
    }

    /// The continuous loop needs band-limited noise (white noise has no value at a time t).
    pub fn check_continuous(&self) -> Result<(), KeyError> {
        match self.bandwidth {
            Some(_) => Ok(()),
            None => Err(KeyError::new(
                "noise.bandwidth",
                "missing; noise in the continuous loop is band-limited: set noise.bandwidth (cycles per unit \
                 of time, e.g. 10 times the loop's bandwidth), or set simulation.sample_time for white noise at the sample rate",
            )),
        }
    }
}

/// The true plant's actuator beyond the model (1) (`[truth]` `actuator_delays`, `u_max`, `u_min`):
/// the plant receives sat(u_f(t − τ_a,i)) on input i, where u_f = −K x̂ + F u_d is the controller's
/// input (5), sat clips input i to [u_min,i, u_max,i] (u_min = −u_max unless given). The controller
/// knows neither.
#[derive(Debug, Clone, PartialEq)]
pub struct Actuator {
    /// τ_a,i ≥ 0 per input: a delay on the whole u_f,i (actuator or network), not only on u_i.
    pub delays: Vec<f64>,
    /// u_max,i > 0 per input (∞: no limit).
    pub limits: Vec<f64>,
    /// u_min,i < 0 per input (−∞: no limit) where the range is not symmetric: u_f is the deviation
    /// from the operating point, so a heater at P₀ of 0 … P has u_min = −P₀ and u_max = P − P₀.
    /// `None`: u_min = −u_max.
    pub lower: Option<Vec<f64>>,
}

impl Actuator {
    /// m delays ≥ 0 and finite, m limits > 0 (∞ allowed).
    pub fn check(&self, m: usize) -> Result<(), KeyError> {
        for (name, v) in [("actuator_delays", &self.delays), ("u_max", &self.limits)] {
            if v.len() != m {
                return Err(KeyError::new(
                    format!("truth.{name}"),
                    format!("expected {} (one per input), found {}", entries(m), v.len()),
                ));
            }
        }
        if let Some((i, d)) = self.delays.iter().enumerate().find(|(_, d)| !(d.is_finite() && **d >= 0.0)) {
            return Err(KeyError::new(
                format!("truth.actuator_delays[{i}]"),
                format!("expected a finite delay ≥ 0 (in the plant model's unit of time), found {}", fmt_short(*d)),
            ));
        }
        if let Some((i, u)) = self.limits.iter().enumerate().find(|(_, u)| u.is_nan() || **u <= 0.0) {
            return Err(KeyError::new(
                format!("truth.u_max[{i}]"),
                format!("expected a limit > 0 (inf for none), found {}", fmt_short(*u)),
            ));
        }
        let Some(lower) = &self.lower else { return Ok(()) };
        if lower.len() != m {
            return Err(KeyError::new(
                "truth.u_min",
                format!("expected {} (one per input), found {}", entries(m), lower.len()),
            ));
        }
        // u_min = 0 is refused as u_max = 0 is: the loop needs room on both sides of its operating
        // point, and a run pinned there had read "peak 0.0 % of the limits" (review, 2026-12-08).
        match lower.iter().enumerate().find(|(_, u)| u.is_nan() || **u >= 0.0) {
            Some((i, u)) => Err(KeyError::new(
                format!("truth.u_min[{i}]"),
                format!(
                    "expected a lower limit < 0 (-inf for none), found {}; u_f is the deviation from the operating point (u_f = 0), which the actuator's range must hold with room on both sides: a heater run at P₀ within 0 … P has u_min = −P₀ and u_max = P − P₀",
                    fmt_short(*u)
                ),
            )),
            None => Ok(()),
        }
    }

    /// u_min,i: the lower limit on input i (−u_max,i unless `u_min` is given).
    pub fn lower_limit(&self, i: usize) -> f64 {
        self.lower.as_ref().map_or(-self.limits[i], |l| l[i])
    }

    /// min(u_max,i, −u_min,i): the largest |u_f,i| that neither limit clips, what a judgment of
    /// max |u_f,i| alone can be held to.
    pub fn magnitude_limit(&self, i: usize) -> f64 {
        self.limits[i].min(-self.lower_limit(i))
    }

    /// Input i's limits as keys: `truth.u_max[i] = 12`, or `truth.u_min[i] … u_max[i] = −2 … 10`
    /// where the range is not symmetric.
    pub fn limits_text(&self, i: usize) -> String {
        match self.asymmetric(i) {
            None => format!("{} = {}", self.limit_keys(i), fmt_short(self.limits[i])),
            Some(l) => format!("{} = {} … {}", self.limit_keys(i), fmt_short(l), fmt_short(self.limits[i])),
        }
    }

    /// Input i's limits' keys: `truth.u_max[i]`, or `truth.u_min[i] … u_max[i]` where the range
    /// is not symmetric.
    pub fn limit_keys(&self, i: usize) -> String {
        limit_keys(i, self.symmetric(i))
    }

    /// Whether input i's range is symmetric, u_min,i = −u_max,i.
    pub fn symmetric(&self, i: usize) -> bool {
        self.lower_limit(i) == -self.limits[i]
    }

    /// u_min,i where it is not −u_max,i.
    fn asymmetric(&self, i: usize) -> Option<f64> {
        Some(self.lower_limit(i)).filter(|_| !self.symmetric(i))
    }

    /// sat_i(v): input i clipped to [u_min,i, u_max,i], and whether a limit was active.
    pub(crate) fn clip(&self, i: usize, v: f64) -> (f64, bool) {
        let (lo, hi) = (self.lower_limit(i), self.limits[i]);
        (v.clamp(lo, hi), v > hi || v < lo)
    }

    /// True when the actuator changes nothing (no delay, no finite limit).
    pub fn is_ideal(&self) -> bool {
        self.delays.iter().all(|&d| d == 0.0)
            && self.limits.iter().all(|u| u.is_infinite())
            && self.lower.iter().flatten().all(|u| u.is_infinite())
    }
}

/// Input i's actuator limits' keys: `truth.u_max[i]` for a `symmetric` range, else
/// `truth.u_min[i] … u_max[i]`.
pub fn limit_keys(i: usize, symmetric: bool) -> String {
    if symmetric {
        format!("truth.u_max[{i}]")
    } else {
        format!("truth.u_min[{i}] … u_max[{i}]")
    }
}

/// `x` if it is finite and > 0; otherwise an error on `key` describing it as `what`.
pub(crate) fn positive(key: &str, what: &str, x: f64) -> Result<f64, KeyError> {
    if x > 0.0 && x.is_finite() {
        Ok(x)
    } else {
        let finite = if x.is_infinite() { " and finite" } else { "" };
        Err(KeyError::new(key, format!("expected {what} > 0{finite}, found {}", fmt_short(x))))
    }
}

/// The `[simulation]` numbers that must be finite and > 0 on their own, with what each is.
pub(crate) const POSITIVE_SIMULATION: [(&str, &str); 3] =
    [("t_end", "a final time"), ("output_step", "an output step"), ("sample_time", "a sampling period")];

/// `simulation.<key>` = `x` as [`POSITIVE_SIMULATION`] requires it.
pub(crate) fn check_positive(key: &str, x: f64) -> Result<f64, KeyError> {
    let what = POSITIVE_SIMULATION.iter().find(|(k, _)| *k == key).map_or("a number", |(_, what)| what);
    positive(&format!("simulation.{key}"), what, x)
}

/// The horizon of a run: 0 < output_step ≤ t_end, both finite, and at most [`MAX_OUTPUT_SAMPLES`]
/// rows.
pub(crate) fn check_horizon(t_end: f64, output_step: f64) -> Result<(), KeyError> {
    check_positive("t_end", t_end)?;
    check_positive("output_step", output_step)?;
    if output_step > t_end {
        return Err(KeyError::new(
            "simulation.output_step",
            format!("expected an output step ≤ t_end = {}, found {}", fmt_short(t_end), fmt_short(output_step)),
        ));
    }
    let samples = t_end / output_step;
    if samples > MAX_OUTPUT_SAMPLES {
        return Err(KeyError::new(
            "simulation.output_step",
            format!(
                "t_end / output_step = {samples:.3e} rows of signals.csv; at most {MAX_OUTPUT_SAMPLES:e} are kept; choose output_step ≥ {}, or a shorter simulation.t_end",
                at_least(t_end, MAX_OUTPUT_SAMPLES)
            ),
        ));
    }
    Ok(())
}

/// The shortest horizon of the continuous loop, in the model's unit of time: the integrator resolves
/// t to 1e-14·max(1, |t|) (its least step, `dde::h_min`), so shorter horizons leave it fewer than
/// 10⁴ distinguishable steps (t_end = 1e-15 had ended as "the solver's step size underflowed", a
/// run failure, exit 1).
pub const MIN_INTEGRATOR_T_END: f64 = 1e-10;

/// [`MIN_INTEGRATOR_T_END`] ≤ t_end: `simulation.t_end` of the continuous loop.
pub(crate) fn check_integrator_horizon((t_end, unit): (f64, TimeUnit)) -> Result<(), KeyError> {
    if t_end >= MIN_INTEGRATOR_T_END {
        return Ok(());
    }
    Err(KeyError::new(
        "simulation.t_end",
        format!(
            "expected t_end ≥ {MIN_INTEGRATOR_T_END:e} {unit} in the continuous loop (its integrator resolves time to 1e-14 of max(1, |t|), so a shorter horizon leaves too few distinguishable steps), found {}; write the model in a time unit in which its horizon is at least that (t → αt: A, B, D, every pole and μ divided by α; delays, β, t_end and output_step multiplied by it), or run the sampled-data loop (simulation.sample_time)",
            fmt_short(t_end)
        ),
    ))
}

/// The continuous loop's delays against its horizon: the integrator's steps are at most min τ long
/// (over the nonzero delays), so t_end / τ must not exceed [`MAX_SAMPLING_STEPS`], the limit of a
/// sampled-data run. `key` names the delays (`plant.delays`, `truth.delays`).
pub(crate) fn check_integrator_delays(
    key: &str,
    delays: &[f64],
    (t_end, unit): (f64, TimeUnit),
) -> Result<(), KeyError> {
    match delays.iter().enumerate().find(|(_, &tau)| tau > 0.0 && t_end / tau > MAX_SAMPLING_STEPS) {
        None => Ok(()),
        Some((i, &tau)) => Err(KeyError::new(
            format!("{key}[{i}]"),
            format!(
                "τ = {tau:e} {unit} caps the integrator's steps at τ, so t_end = {t_end} {unit} needs more than {:.3e} steps; at most {MAX_SAMPLING_STEPS:e} are run (as in a sampled-data run); expected 0 (no delay) or τ ≥ {}",
                t_end / tau,
                at_least(t_end, MAX_SAMPLING_STEPS)
            ),
        )),
    }
}

/// The continuous loop's signals against its horizon: resolving a harmonic of ω rad/s takes at
/// least two steps a period, so ω·t_end/π must not exceed [`MAX_SAMPLING_STEPS`] (a reference at
/// 1e15 rad/s over 100 s ran 3.5 s into the history's memory budget). `key` names the signal
/// (`reference`, `disturbance`).
pub(crate) fn check_integrator_signal(
    key: &str,
    signal: &Signal,
    (t_end, unit): (f64, TimeUnit),
) -> Result<(), KeyError> {
    let harmonics = signal
        .components
        .iter()
        .enumerate()
        .flat_map(|(c, comp)| comp.harmonics.iter().enumerate().map(move |(h, w)| (c, h, w)));
    for (c, h, w) in harmonics {
        let steps = w.frequency * t_end / std::f64::consts::PI;
        if steps > MAX_SAMPLING_STEPS {
            return Err(KeyError::new(
                format!("{key}.components[{c}].harmonics[{h}].frequency"),
                format!(
                    "ω = {} rad/{unit} needs at least ω·t_end/π = {steps:.3e} integrator steps over t_end = {} {unit} (two a period); at most {MAX_SAMPLING_STEPS:e} are run; expected ω ≤ {} (frequencies are in rad per unit of the plant's time, not Hz) or simulation.t_end ≤ {} {unit}",
                    fmt_short(w.frequency),
                    fmt_short(t_end),
                    fmt_short(three_digits_down(std::f64::consts::PI * MAX_SAMPLING_STEPS / t_end)),
                    fmt_short(three_digits_down(std::f64::consts::PI * MAX_SAMPLING_STEPS / w.frequency))
                ),
            ));
        }
    }
    Ok(())
}

/// The recorded signals' memory: (t_end / output_step) rows of `row_bytes` within
/// [`MAX_RECORD_BYTES`]; `what` names a row's entries.
pub(crate) fn check_record(t_end: f64, output_step: f64, row_bytes: usize, what: &str) -> Result<(), KeyError> {
    let rows = t_end / output_step;
    let limit = MAX_RECORD_BYTES / row_bytes as f64;
    if rows <= limit {
        return Ok(());
    }
    Err(KeyError::new(
        "simulation.output_step",
        format!(
            "t_end / output_step = {rows:.3e} rows of {row_bytes} bytes ({what}) = {:.3} GiB of recorded signals; at most {} GiB are kept in memory; choose output_step ≥ {}",
            rows * row_bytes as f64 / 1024f64.powi(3),
            MAX_RECORD_BYTES / 1024f64.powi(3),
            at_least(t_end, limit)
        ),
    ))
}

/// [`step_at_least`], written as Rust's shortest form ([`fmt_short`]).
fn at_least(t_end: f64, limit: f64) -> String {
    fmt_short(step_at_least(t_end, limit))
}

/// A step h to suggest so that t_end / h ≤ `limit`: the number nearest x = t_end / limit with three
/// significant digits, raised in its third digit until it passes, so that the value typed back
/// passes the check.
pub(crate) fn step_at_least(t_end: f64, limit: f64) -> f64 {
    let (x, passes) = (t_end / limit, |h: f64| t_end / h <= limit);
    let e = (x.log10().floor() as i32).saturating_sub(2);
    let mut digits = (x / 10f64.powi(e)).round();
    for _ in 0..1000 {
        let v: f64 = format!("{digits}e{e}").parse().unwrap_or(f64::NAN);
        if v.is_finite() && passes(v) {
            return v;
        }
        digits += 1.0;
    }
    x
}

/// `x` > 0 rounded down to three significant digits, so that the value typed back is within a
/// bound of x.
pub(crate) fn three_digits_down(x: f64) -> f64 {
    let e = x.log10().floor() as i32 - 2;
    // Through the decimal text, so that 291e-6 is the double nearest 0.000291.
    let digits = (x / 10f64.powi(e)).floor();
    format!("{digits}e{e}").parse::<f64>().map_or(x, |v| if v <= x { v } else { (digits - 1.0) * 10f64.powi(e) })
}

/// A time for a message, to 12 significant digits and without trailing zeros: 119.57, not the
/// 119.57000000000001 of k·output_step.
pub fn fmt_time(x: f64) -> String {
    let s = format!("{x:.12e}");
    s.parse::<f64>().map_or(s, fmt_short)
}

/// The time of an event (a divergence, a budget's end) in a message: seven significant digits in
/// `fmt_short`'s form (36.75, 808080; not 808080.0000).
pub fn fmt_instant(t: f64) -> String {
    fmt_short(significant(t, 7))
}

/// `x` > `bound` with two decimals, or as many more as show it above the bound (T_s·ρ =
/// 0.2003 against 0.2 had printed "0.20 > 0.2").
pub(crate) fn fmt_above(x: f64, bound: f64) -> String {
    (2..=6)
        .map(|d| format!("{x:.d$}"))
        .find(|s| s.parse::<f64>().is_ok_and(|v| v > bound))
        .unwrap_or_else(|| x.to_string())
}

/// `x` rounded to `digits` significant digits (≥ 1), through its decimal form.
pub(crate) fn significant(x: f64, digits: usize) -> f64 {
    format!("{x:.*e}", digits.max(1) - 1).parse().unwrap_or(x)
}

/// `v` to four significant digits, `{}` between 1e-4 and 1e6 and `{:e}` beyond: a figure in
/// advice (6.283 rad/s, not 6.283185307179586), where the digits say how much, not what to type.
pub fn fmt_4(v: f64) -> String {
    fmt_short(significant(v, 4))
}

/// How many times, `x`, to two significant digits in [`fmt_short`]'s form: 3 (not 3.0e0), 47,
/// 1.1e6.
pub(crate) fn fmt_ratio(x: f64) -> String {
    fmt_short(significant(x, 2))
}

/// A fraction as a percentage for a message: one decimal from 0.1 %, two significant digits below
/// (0.043 %, 1.8e-5 %; "0.0 %" had hidden one clipped sample in 2,301).
pub fn fmt_percent(fraction: f64) -> String {
    let p = 100.0 * fraction;
    if p > 0.0 && p < 0.1 {
        format!("{} %", fmt_ratio(p))
    } else {
        format!("{p:.1} %")
    }
}

/// Numbers in [`fmt_short`]'s form, comma-separated.
pub(crate) fn fmt_short_list(v: &[f64]) -> String {
    v.iter().map(|&x| fmt_short(x)).collect::<Vec<_>>().join(", ")
}

/// What a key that holds an integer expects, by its last name (`seed`, `runs`, `points`, …);
/// `None` for a key that holds a real number, which may be written as a float.
pub fn integer_key(name: &str) -> Option<&'static str> {
    match name {
        "seed" => Some("a seed, an integer from 0 to 2**63 - 1"),
        "runs"
        | "points"
        | "refine"
        | "max_steps"
        | "relative_degrees"
        | "reference_filter_orders"
        | "disturbance_filter_orders" => Some("an integer within 2**63 - 1"),
        _ => None,
    }
}

/// "1 entry" or "n entries", for the messages that count a list's entries.
pub fn entries(n: usize) -> String {
    count(n, "entry", "entries")
}

/// "1 copy" or "n copies": `n` with the noun's singular or plural.
pub(crate) fn count(n: usize, one: &str, many: &str) -> String {
    if n == 1 {
        format!("1 {one}")
    } else {
        format!("{n} {many}")
    }
}

/// `x` > 0 rounded up to two significant digits (a value to propose: a horizon, a gain).
pub(crate) fn round_up_2(x: f64) -> f64 {
    round_2(x, f64::ceil)
}

/// `x` > 0 rounded down to two significant digits (a bound to propose: "at most").
pub(crate) fn round_down_2(x: f64) -> f64 {
    round_2(x, f64::floor)
}

fn round_2(x: f64, direction: fn(f64) -> f64) -> f64 {
    let unit = 10f64.powf(x.log10().floor() - 1.0);
    // Through the shortest decimal, so that 0.1·unit·ceil prints as 0.11, not 0.11000000000000001.
    format!("{:.1e}", direction(x / unit) * unit).parse().unwrap_or(x)
}

/// Rust's shortest form of `v`: `{}` for 0 and between 1e-4 and 1e6, otherwise `{:e}`, so that
/// 1e293 does not print as 294 digits (nor 1e-300 as 300 zeros).
pub(crate) fn fmt_short(v: f64) -> String {
    if v == 0.0 || (1e-4..1e6).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// The tightest relative tolerance accepted: 100 ε ≈ 2.2e-14. Below it no step size meets the
/// error test in double precision (SciPy raises a smaller rtol to this; Hairer's `dop853.f` refuses
/// rtol ≤ 10 u): such a run crawls in ever smaller steps until a budget or the step size's
/// underflow ends it, which says nothing of the loop.
pub const MIN_RTOL: f64 = 100.0 * f64::EPSILON;

/// The integrator's tolerances: atol finite and > 0, rtol in [[`MIN_RTOL`], 1) (from 1 on the error
/// test allows errors as large as the signals).
pub(crate) fn check_tolerances(rtol: f64, atol: f64) -> Result<(), KeyError> {
    positive("simulation.rtol", "a relative tolerance", rtol)?;
    if !(MIN_RTOL..1.0).contains(&rtol) {
        return Err(KeyError::new(
            "simulation.rtol",
            format!(
                "expected a relative tolerance from 100 ε = {MIN_RTOL:.5e} (the tightest double precision can meet) to below 1 (errors as large as the signals), found {}; 1e-9 is the default, 1e-6 a quick look",
                fmt_short(rtol)
            ),
        ));
    }
    positive("simulation.atol", "an absolute tolerance", atol)?;
    Ok(())
}

/// A sampling period: finite, > 0, and at most [`MAX_SAMPLING_STEPS`] controller steps to t_end.
pub(crate) fn check_sample_time(t_end: f64, sample_time: f64) -> Result<(), KeyError> {
    const KEY: &str = "simulation.sample_time";
    check_positive("sample_time", sample_time)?;
    if sample_time > t_end {
        return Err(KeyError::new(
            KEY,
            format!(
                "expected a sample time ≤ t_end = {}, found {}: the run would end before the controller's first step; choose a shorter sample time or a longer simulation.t_end",
                fmt_short(t_end),
                fmt_short(sample_time)
            ),
        ));
    }
    let steps = t_end / sample_time;
    if steps > MAX_SAMPLING_STEPS {
        return Err(KeyError::new(
            KEY,
            format!("t_end / sample_time = {steps:.3e} controller steps; at most {MAX_SAMPLING_STEPS:e} are run; choose sample_time ≥ {}", at_least(t_end, MAX_SAMPLING_STEPS)),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit with spaces around it is named without them (" s" had been offered "µs", one edit
    /// away; helper tryout, 2026-12-07); a misspelt one still gets its nearest.
    #[test]
    fn a_time_unit_with_spaces_is_named_without_them() {
        assert!(TimeUnit::from_name(" s")
            .unwrap_err()
            .ends_with("found \" s\" (did you mean \"s\" (seconds), without the spaces?)"));
        assert!(TimeUnit::from_name("min ")
            .unwrap_err()
            .ends_with("(did you mean \"min\" (minutes), without the spaces?)"));
        assert!(TimeUnit::from_name("mins").unwrap_err().ends_with("(did you mean \"min\" (minutes)?)"));
        assert_eq!(TimeUnit::from_name("s"), Ok(TimeUnit::Seconds));
    }

    /// One decimal from 0.1 %, two significant digits below it, and 0 as 0.0 %.
    #[test]
    fn shares_below_a_tenth_of_a_percent_keep_two_digits() {
        let cases = [(0.5, "50.0 %"), (0.001, "0.1 %"), (0.000999, "0.1 %"), (0.00043478, "0.043 %")];
        for (fraction, text) in cases.into_iter().chain([(1.8e-7, "1.8e-5 %"), (0.0, "0.0 %")]) {
            assert_eq!(fmt_percent(fraction), text, "{fraction}");
        }
    }

    /// Text that is not UTF-8 is refused with the way out; UTF-16 (a byte-order mark) is named.
    #[test]
    fn a_file_that_is_not_utf8_says_how_to_save_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.toml");
        let utf16: Vec<u8> =
            [0xFF, 0xFE].into_iter().chain("t = 1".encode_utf16().flat_map(u16::to_le_bytes)).collect();
        std::fs::write(&path, utf16).unwrap();
        assert_eq!(read_input(&path).unwrap_err(), "UTF-16 text, not UTF-8; save the file as UTF-8");
        std::fs::write(&path, b"t = \xE9").unwrap();
        assert_eq!(read_input(&path).unwrap_err(), "not UTF-8 text (invalid byte at offset 4); save the file as UTF-8");
    }

    /// T_s·ρ at the bound by rounding alone is no coarse sample (the quadruple tank at 1 s:
    /// 0.20000000000000023 had been warned of as "0.20 > 0.2"); one truly beyond prints the digits
    /// that show it.
    #[test]
    fn a_sample_at_the_bound_by_rounding_is_not_coarse_and_one_beyond_shows_it() {
        let bound = crate::sim::COARSE_SAMPLE;
        assert!(!crate::sim::is_coarse(0.20000000000000023));
        assert!(crate::sim::is_coarse(0.2003) && crate::sim::is_coarse(0.45));
        assert_eq!((fmt_above(0.2003, bound), fmt_above(0.45, bound)), ("0.2003".to_string(), "0.45".to_string()));
        assert_eq!(fmt_above(0.2000001, bound), "0.2000001");
    }

    /// A proposed value is at least the value asked for, at most 10 % above it (one unit of its
    /// second digit), and prints short; a value already of two digits stays.
    #[test]
    fn values_round_up_to_two_significant_digits() {
        for (x, want) in [
            (9.949, "10"),
            (11290.3, "12000"),
            (5.304, "5.4"),
            (0.1, "0.1"),
            (0.10000001, "0.11"),
            (99.0, "99"),
            (3.7e-7, "3.7e-7"),
            (1.2e12, "1.2e12"),
        ] {
            let r = round_up_2(x);
            assert_eq!(fmt_short(r), want, "{x}");
            assert!(r >= x && r <= 1.1 * x, "{x} → {r}");
        }
    }

    /// A time prints without the rounding error of k·h (11,957 steps of 0.01 is 119.57000000000001),
    /// and a count of entries agrees in number.
    #[test]
    fn times_print_to_twelve_digits_and_counts_agree() {
        assert_eq!(11957.0 * 0.01, 119.57000000000001);
        assert_eq!(fmt_time(11957.0 * 0.01), "119.57");
        assert_eq!(fmt_time(1e-300), "1e-300");
        assert_eq!(fmt_time(2.5), "2.5");
        assert_eq!((entries(1), entries(0), entries(3)), ("1 entry".into(), "0 entries".into(), "3 entries".into()));
        assert_eq!((count(1, "copy", "copies"), count(2, "copy", "copies")), ("1 copy".into(), "2 copies".into()));
        assert_eq!(
            (fmt_4(std::f64::consts::TAU), fmt_4(2.16701e7), fmt_4(0.0), fmt_4(f64::NAN)),
            ("6.283".into(), "2.167e7".into(), "0".into(), "NaN".into())
        );
    }

    #[test]
    fn suggested_output_step_and_sample_time_are_short_and_pass() {
        // t_end = 1e300 printed "choose output_step ≥ 1000000000000000100…" (294 digits).
        for (t_end, step) in [(1e300, 0.1), (100.0, 1e-6), (3.0, 1e-7), (1e20, 1e-300)] {
            let e = check_horizon(t_end, step).unwrap_err();
            let rest = e.message.rsplit("choose output_step ≥ ").next().unwrap();
            // No horizon is named: the recorded signals' memory, checked later, may ask for a
            // shorter one (t_end = 10 s at output_step = 1e-6 s is 2.01 GiB of rows).
            let suggested = rest.strip_suffix(", or a shorter simulation.t_end").unwrap();
            assert!(suggested.len() <= 8, "{e}");
            let h: f64 = suggested.parse().unwrap();
            assert!(check_horizon(t_end, h).is_ok(), "{e}");
            let e = check_sample_time(t_end, step * 1e-4).unwrap_err();
            let suggested = e.message.rsplit("choose sample_time ≥ ").next().unwrap();
            assert!(suggested.len() <= 8, "{e}");
            assert!(check_sample_time(t_end, suggested.parse().unwrap()).is_ok(), "{e}");
        }
        // 1e300 / 1e293 rounds to just above 1e7, so the suggestion is the next 3-digit value.
        let e = check_horizon(1e300, 0.1).unwrap_err();
        assert!(e.message.ends_with("choose output_step ≥ 1.01e293, or a shorter simulation.t_end"), "{e}");
        assert!(check_horizon(1e300, 1e293).is_err());
    }
}
