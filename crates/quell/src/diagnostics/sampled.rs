//! A sampled-data run against the loop it approximates: the same scenario without its sample time.
//!
//! The rule T_s·ρ ≤ [`COARSE_SAMPLE`] weighs the loop's rates, not its gains, and misses both ways:
//! a maglev's automatic design sampled at the 0.25 ms it advised drove u_f to 282 V against 5.9 V
//! continuous with nothing said, while a DC motor warned at T_s·ρ = 5.7 stayed within 6 % of its
//! continuous loop. So a sampled run is compared with the continuous one ([`against_continuous`]):
//! its departure is named ([`sampled_advice`]), and a coarse warning the run contradicts is
//! answered. Under measurement noise, which the two loops read at different instants, both are
//! compared without it; where the comparison cannot run (a continuous loop past its step budget),
//! the peak heuristic [`sampled_transient`] stands in.

use std::cmp::Ordering;
use std::ops::ControlFlow;

use crate::design::Design;
use crate::settings::{fmt_4, fmt_instant, fmt_ratio, fmt_short};
use crate::sim::{is_coarse, loop_rate, Loop, Outcome, Run, RunSettings, RunStats, SimResult, COARSE_SAMPLE};

/// A completed sampled-data run's peak of u_f over its peak in the tail from which the sampling is
/// suspected when no comparison runs: the continuous loops of `examples` and `tests/data` peak at
/// most 43× their tails (the quadruple tank's first minutes), while the flexible-joint robot of
/// `tests/data` sampled at 0.5 ms, within T_s·ρ ≤ [`COARSE_SAMPLE`], peaked 19,000× (8,637
/// against 0.97 in the continuous loop). A heuristic: a large x(0) against small signals gives the
/// continuous loop such a transient too (the paper's example with x0 = [5, −5, 5] and signals ×
/// 1e-3: 1,164×), and at 0.2 ms the same robot peaked 116× its continuous u_f but only 245× its
/// tail.
pub const SAMPLED_TRANSIENT: f64 = 1000.0;

/// The most solver steps a diagnostic's continuous side run may take (about 2 s of the paper's
/// loop); one that needs more is not compared.
pub const COMPARISON_STEPS: usize = 200_000;

/// A sampled run's comparison with its continuous loop takes up to this many solver steps per
/// controller step of the run, or [`COMPARISON_STEPS`] if more, within the run's own budget: a
/// Furuta pendulum at 1 ms over 55 s (55,000 controller steps) needed 342,727.
pub const COMPARISON_PER_SAMPLE: usize = 10;

/// A sampled run departs from its continuous loop where a channel's y differs from the continuous
/// y by this share of the continuous y's peak at a recorded row, or its u_f peaks [`DEPARTED_UF`]
/// times the continuous u_f's peak. At the sample time T_s·ρ = 0.2 advises, the loops of
/// `examples` and `tests/data` stay within 0.15 of it but four: the quadruple tank (1.6 and 1.9,
/// u_f 1.2×), the magnetic bearing (1.9 and 2.0, u_f 120× and 370×), the flexible-joint robot
/// (9.2, u_f 8,900×) and the VTOL aircraft (0.30 and 0.42, u_f 1.4×), at half of it all but the
/// first three within 0.23.
pub const DEPARTED_Y: f64 = 0.5;
/// See [`DEPARTED_Y`].
pub const DEPARTED_UF: f64 = 2.0;
/// A coarse sample time (T_s·ρ beyond [`COARSE_SAMPLE`]) whose run stays this close to its
/// continuous loop (y within this share of its peak, u_f's peak within [`FOLLOWS_UF`] times) is
/// said to follow it: a DC motor warned at T_s·ρ = 5.7 (an observer pole at −5,690/s) stayed within
/// 5.7 % and 1.0×.
pub const FOLLOWS_Y: f64 = 0.1;
/// See [`FOLLOWS_Y`].
pub const FOLLOWS_UF: f64 = 1.2;
/// A channel with no reference of its own that the continuous loop leaves idle ([`IDLE`]) is
/// measured against this share of the largest channel's peak (of y, of u_f) instead of its own
/// ([`departures`]).
pub const QUIET: f64 = 1e-3;
/// A continuous peak (of y, of u_f) at most this share of the largest channel's is rounding's
/// residue, the channel idle (as the automatic design's peaking caution reads a steady input).
pub const IDLE: f64 = 1e-9;
/// Most rows a run a diagnostic makes beside the user's records (on every k-th of its rows): the
/// comparison of a sampled run with its continuous loop had held a second record as large as the
/// run's own (805 MB for a 398 MB record, n = 200, m = 8), and its halvings a third.
pub const SIDE_ROWS: f64 = 1e5;
/// How many times the comparison halves a departing sample time to find one that agrees…
pub const HALVINGS: u32 = 6;
/// …taking at most this many controller steps in all its runs.
pub const HALVING_STEPS: f64 = 2e6;

/// A run in f32 (emulated) whose u_f or y departs from the same run in f64 by this share of the
/// f64 peak is told to export in f64: a percent of the input is what an actuator limit or a
/// noise floor is commonly set to, as [`crate::export::F32_POLE_SHIFT`]'s heuristic reads it.
pub const F32_DEPARTURE: f64 = 0.01;

/// One channel of a sampled-data run against the continuous loop, over their common rows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelDeparture {
    /// max_k |y_i(t_k) − y_i,c(t_k)| / max_k |y_i,c(t_k)|.
    pub y: f64,
    /// max |u_f,i| of the sampled run and of the continuous loop (or the floor it is measured
    /// against, where that is larger: [`ChannelDeparture::floored`]).
    pub uf: (f64, f64),
    /// Whether `uf.1` is a floor ([`QUIET`]) above the continuous loop's own peak.
    pub floored: bool,
}

impl ChannelDeparture {
    /// Beyond [`DEPARTED_Y`] or [`DEPARTED_UF`] (or not finite).
    pub fn departed(&self) -> bool {
        !(self.y <= DEPARTED_Y && self.uf.0 <= DEPARTED_UF * self.uf.1)
    }

    /// u_f's peak beyond [`DEPARTED_UF`] times the continuous one's (or NaN).
    fn driven(&self) -> bool {
        !matches!(self.uf.0.partial_cmp(&(DEPARTED_UF * self.uf.1)), Some(Ordering::Less | Ordering::Equal))
    }

    /// Within [`FOLLOWS_Y`] and [`FOLLOWS_UF`].
    fn follows(&self) -> bool {
        self.y <= FOLLOWS_Y && self.uf.0 <= FOLLOWS_UF * self.uf.1
    }
}

/// The continuous loop of the sampled run `result` of scenario `s` (its settings without the
/// sample time, at most [`COMPARISON_STEPS`] steps) and each channel's departure over their
/// common rows ([`departures`]). `None` for a continuous run, under measurement noise (white per
/// sample, or the same band-limited noise read at other instants), or when the continuous loop does
/// not complete within its steps.
pub fn against_continuous(
    s: &crate::Scenario,
    design: &Design,
    result: &SimResult,
) -> Option<(SimResult, Vec<ChannelDeparture>)> {
    compared(s, design, result, None)
}

/// [`against_continuous`], the continuous loop capped at [`COMPARISON_STEPS`] or, with `uncapped`,
/// within the run's own budget ([`continuous_loop`]).
fn compared(
    s: &crate::Scenario,
    design: &Design,
    result: &SimResult,
    uncapped: Option<Progress<'_>>,
) -> Option<(SimResult, Vec<ChannelDeparture>)> {
    let RunStats::Sampled { .. } = result.stats else { return None };
    let reach = uncapped.map(|progress| Reach { progress, max_steps: None, t_end: None });
    let continuous = continuous_loop(s, design, reach).ok()?;
    let channels = departures(result, &continuous)?;
    Some((continuous, channels))
}

/// Why a sampled run was not compared with its continuous loop.
enum Skipped {
    /// Measurement noise, which the two loops read differently.
    Noise,
    /// The continuous loop did not complete: past its steps, or diverged.
    Ended(Outcome),
    /// The continuous loop could not be run.
    Failed,
}

/// A run's progress callback (as [`Run::simulate`] takes it), which may stop it.
pub(crate) type Progress<'p> = &'p mut dyn FnMut(f64) -> ControlFlow<()>;

/// How far a comparison's continuous loop runs beyond a [`side_run`]: with `progress`'s callback,
/// within the run's own step budget and at most `max_steps` steps, to `t_end` (`None`: the
/// scenario's).
struct Reach<'p> {
    progress: Progress<'p>,
    max_steps: Option<usize>,
    t_end: Option<f64>,
}

/// The continuous loop of scenario `s` at its settings without the sample time: a [`side_run`]
/// (at most [`COMPARISON_STEPS`] steps), or as far as `reach` says.
fn continuous_loop(s: &crate::Scenario, design: &Design, reach: Option<Reach<'_>>) -> Result<SimResult, Skipped> {
    if s.noise.is_some() {
        return Err(Skipped::Noise);
    }
    let mut continuous = crate::Scenario { simulation: s.simulation.continuous(), ..s.clone() };
    let run = match reach {
        None => side_run(&continuous, design),
        Some(Reach { progress, max_steps, t_end }) => {
            if let Some(t) = t_end {
                continuous.simulation.t_end = t.min(continuous.simulation.t_end);
            }
            let mut settings = side_settings(&continuous);
            let run = Run::of(&continuous, design);
            if let (Loop::Continuous(integrator), Some(cap)) = (&mut settings.mode, max_steps) {
                integrator.max_steps = Some(cap.min(crate::sim::default_max_steps(&run, integrator)));
            }
            run.settings(settings).simulate(progress)
        }
    };
    match run {
        Ok(r) if matches!(r.outcome, None | Some(Outcome::Completed)) => Ok(r),
        Ok(r) => Err(Skipped::Ended(r.outcome.unwrap_or(Outcome::Completed))),
        Err(_) => Err(Skipped::Failed),
    }
}

/// The settings of a run a diagnostic makes beside the user's: scenario `s`'s own, without the
/// states and at most [`SIDE_ROWS`] rows, its output step a whole multiple of `s`'s so that its rows
/// fall on the user's run's ([`departures`] pairs them by time). Peaks between rows are kept as in
/// any run ([`SimResult::max_uf`]).
fn side_settings(s: &crate::Scenario) -> RunSettings {
    let mut settings = RunSettings::of(s);
    settings.record_states = false;
    let rows = settings.t_end / settings.output_step;
    if rows > SIDE_ROWS {
        settings.output_step *= (rows / SIDE_ROWS).ceil();
    }
    settings
}

/// A run a diagnostic makes beside the user's: scenario `s` at [`side_settings`], a continuous loop
/// within [`COMPARISON_STEPS`] steps.
pub(crate) fn side_run(s: &crate::Scenario, design: &Design) -> Result<SimResult, crate::sim::SimError> {
    let mut settings = side_settings(s);
    if let Loop::Continuous(integrator) = &mut settings.mode {
        integrator.max_steps = Some(COMPARISON_STEPS);
    }
    Run::of(s, design).settings(settings).simulate(go_on)
}

/// A side run's progress callback: a stop flag (Ctrl-C in a tune or an automatic design) ends it.
fn go_on(_: f64) -> ControlFlow<()> {
    if crate::cancel::check().is_err() {
        ControlFlow::Break(())
    } else {
        ControlFlow::Continue(())
    }
}

/// The rows of `a` and `b` at the same time (within 1e-9 of it, relative beyond 1, and within a
/// thousandth of either's row spacing), as index pairs in time order: every row of a run at an
/// output step a whole multiple of the other's.
fn common_rows(a: &[f64], b: &[f64]) -> Vec<(usize, usize)> {
    let spacing = |t: &[f64]| if t.len() > 1 { t[1] - t[0] } else { f64::INFINITY };
    let within = 1e-3 * spacing(a).min(spacing(b));
    let mut pairs = Vec::with_capacity(a.len().min(b.len()));
    let mut k = 0;
    for (j, &t) in b.iter().enumerate() {
        let close = |s: f64| (s - t).abs() <= (1e-9 * t.abs().max(1.0)).min(within);
        while k < a.len() && a[k] < t && !close(a[k]) {
            k += 1;
        }
        match a.get(k) {
            Some(&s) if close(s) => pairs.push((k, j)),
            Some(_) => {}
            None => break,
        }
    }
    pairs
}

/// Each channel's departure of `sampled` from `continuous` over the rows at the same times (where
/// one output step is a whole multiple of the other's); `None` when they have none.
pub fn departures(sampled: &SimResult, continuous: &SimResult) -> Option<Vec<ChannelDeparture>> {
    let rows = common_rows(&sampled.t, &continuous.t);
    if rows.is_empty() {
        return None;
    }
    let m = sampled.m;
    let y_peaks: Vec<f64> =
        (0..m).map(|i| continuous.column(&continuous.y, m, i).fold(0.0f64, |a, v| a.max(v.abs()))).collect();
    let uf_peaks: Vec<f64> = (0..m).map(|i| continuous.max_uf(i)).collect();
    // A channel with no reference of its own that the continuous loop leaves at rounding's level
    // beside the largest channel ([`IDLE`]: the paper's y2 at 7.9e-14 with g = [1, 0] and ω = 0) is
    // measured against a thousandth of the largest channel's peak, not its round-off. Only such a
    // channel: the channels' units differ, and a quadrotor's yaw torque (1.9e-5 N·m) measured
    // against a thousandth of its thrust (0.21 N) had read its sampled loop's 2.2× as 0.2×, which
    // hid it from the automatic design's check too (as a regulated channel that ω drives, in units
    // 1e4 smaller than its neighbour's).
    let own = |i: usize| continuous.column(&continuous.g, m, i).any(|g| g != 0.0);
    let floor = |peaks: &[f64], i: usize| {
        let largest = peaks.iter().copied().fold(0.0, f64::max);
        if !own(i) && peaks[i] <= IDLE * largest {
            QUIET * largest
        } else {
            0.0
        }
    };
    let channel = |i: usize| {
        let gap = rows.iter().fold(0.0f64, |a, &(k, j)| {
            let d = (sampled.y[k * m + i] - continuous.y[j * m + i]).abs();
            if d > a {
                d
            } else {
                a
            }
        });
        // A y that is zero in both (no signals, x(0) = 0) has not departed.
        let y = if gap == 0.0 { 0.0 } else { gap / y_peaks[i].max(floor(&y_peaks, i)) };
        let uf_floor = floor(&uf_peaks, i);
        ChannelDeparture { y, uf: (sampled.max_uf(i), uf_peaks[i].max(uf_floor)), floored: uf_floor > uf_peaks[i] }
    };
    Some((0..m).map(channel).collect())
}

/// What [`precision_check`] found: its line, whether the f32 loop departs enough for the advice on
/// the design to be left to the f64 run, and that run.
pub(crate) struct PrecisionCheck {
    pub line: String,
    pub flagged: bool,
    pub reference: SimResult,
}

/// A sampled-data run in f32 (`simulation.precision = "f32"`, emulated) against the same run in
/// f64: how far its y, u_f and η̂ depart, per channel, relative to the f64 run's peaks, said always
/// (the user asked for it). Flagged, with the advice to export in f64, beyond [`F32_DEPARTURE`],
/// where the f32 loop ends early and the f64 one does not, or where η̂ drifts: rounding moves η̂
/// along directions the signals do not excite (Ω̄'s null space, where nothing pulls it back), so
/// its departure grows with the run (a turbofan's η̂₂ departed 3.3× its peak over 120 s, its f32
/// loop diverging at 96 s at T_s = 1 ms and a haemodynamic model's after days, as their compiled
/// f32 C did; helper tryout, 2026-12-07). The emulation ([`crate::sim::RunSettings::precision`])
/// rounds the core's operations, the constants, inputs and states, not the adaptive law's
/// operations: compiled f32 C in the same loops departed 0.4–6.2× as far (the paper's example, a
/// disk servo, a PMSM, a flexible satellite, a piezo stage, a two-link arm, a power system's
/// generator as an FMU; `tests/export_c.rs`).
pub(crate) fn precision_check(s: &crate::Scenario, design: &Design, result: &SimResult) -> Option<PrecisionCheck> {
    use crate::controller::Precision;
    let RunStats::Sampled { precision: Precision::F32, .. } = result.stats else { return None };
    // An interrupted run, or one its budget ended, is no verdict on the precision.
    if matches!(result.outcome, Some(Outcome::Interrupted { .. } | Outcome::TooManySteps { .. })) {
        return None;
    }
    let f64_scenario = crate::Scenario {
        simulation: crate::scenario::Simulation { precision: Precision::F64, ..s.simulation },
        ..s.clone()
    };
    let reference = side_run(&f64_scenario, design).ok()?;
    let what = "precision f32 (emulated: the observers' products and u_f in float, constants, inputs and states rounded to float)";
    let ended = |r: &SimResult| !matches!(r.outcome, None | Some(Outcome::Completed));
    if ended(result) && !ended(&reference) {
        let how = result.outcome.as_ref().map_or(String::new(), |o| o.to_string());
        let line =
            format!("{what}: the f32 loop ended early ({how}) where the same run in f64 completes: export in f64");
        return Some(PrecisionCheck { line, flagged: true, reference });
    }
    let departures = precision_departures(result, &reference);
    let listed: Vec<String> = departures
        .iter()
        .enumerate()
        .map(|(i, d)| {
            format!(
                "y[{}] by {:.1e} of its peak, u_f[{}] by {:.1e}, η̂_{} by {:.1e}",
                i + 1,
                d.y,
                i + 1,
                d.uf,
                i + 1,
                d.eta
            )
        })
        .collect();
    let beyond = |x: f64| x > F32_DEPARTURE || x.is_nan();
    let drifting: Vec<String> = (departures.iter().enumerate())
        .filter(|(_, d)| beyond(d.eta) && d.growth > DRIFT_GROWTH)
        .map(|(i, d)| format!("η̂_{} ({}× over the last tenth of the run)", i + 1, crate::settings::fmt_ratio(d.growth)))
        .collect();
    let verdict = if !drifting.is_empty() {
        let verb = if drifting.len() == 1 { "drifts" } else { "drift" };
        format!("; {} {verb}: rounding moves η̂ along directions the signals do not excite (Ω̄'s null space, where nothing pulls it back), so a longer run departs further and can diverge (a turbofan's f32 loop did at 96 s): export in f64", drifting.join(", "))
    } else if departures.iter().any(|d| beyond(d.y) || beyond(d.uf)) {
        format!(
            "; beyond {} of a peak: export in f64, or choose poles nearer the plant's own (the design report's κ₂)",
            percent(F32_DEPARTURE)
        )
    } else {
        String::new()
    };
    let line = format!(
        "{what}: against the same run in f64, {}{verdict}; compiled f32 builds departed 0.4–6.2× as far as this emulation in the loops measured (docs/deployment.md)",
        listed.join("; ")
    );
    Some(PrecisionCheck { line, flagged: !verdict.is_empty(), reference })
}

/// The most controller steps of [`export_check`]'s runs (a million steps of the paper's loop take
/// about 0.5 s, of a 12-hour wind turbine's about 13 s): an export's horizon may be any length.
pub const EXPORT_CHECK_SAMPLES: f64 = 1e6;

/// The fewest controller steps over which [`export_check`] measures a loop.
pub const EXPORT_MIN_SAMPLES: f64 = 100.0;

/// Before an export at `sample_time` in `precision`: the scenario's sampled-data loop, as the
/// exported controller runs it, against its continuous loop (the comparison of a sampled run,
/// without `[noise]`) and, in f32, against the same sampled loop in f64. The sample-time bound
/// T_s·ρ ≤ 0.2 does not stand in for the first: an aircraft exported at the 5 ms it suggested
/// asked 362× its continuous loop's u_f, its adaptation running at 64/s beside ρ = 22/s; nor the
/// design report's κ₂ bound for the second: a quadrotor's poles moved at most 0.19 % in f32 while
/// its u_f departed 4.6× its peak, and its compiled f32 C asked 17 N of a rotor against 2.8 N in
/// f64 (helper tryouts, 2026-12-07).
///
/// A horizon beyond [`EXPORT_CHECK_SAMPLES`] samples is cut there, with 1,000 rows; the output
/// step is a whole number of samples (the export's T_s need not divide the scenario's), with at
/// least 20 rows where the samples allow. `Err` says why the runs could not be made: a horizon of
/// fewer than [`EXPORT_MIN_SAMPLES`] samples (an export at a T_s near t_end had reported one
/// sample's "departure" of 0), delays that are not whole samples.
pub fn export_check(
    s: &crate::Scenario,
    design: &Design,
    (sample_time, precision): (f64, crate::controller::Precision),
) -> Result<ExportCheck, String> {
    let samples = (s.simulation.t_end / sample_time).floor();
    if samples < EXPORT_MIN_SAMPLES {
        return Err(format!(
            "the scenario's t_end holds fewer than {EXPORT_MIN_SAMPLES:.0} samples of T_s ({})",
            crate::settings::count(samples as usize, "sample", "samples")
        ));
    }
    let (cut, samples) = (samples > EXPORT_CHECK_SAMPLES, samples.min(EXPORT_CHECK_SAMPLES));
    let per_row = if cut { samples / 1000.0 } else { (s.simulation.output_step / sample_time).round() };
    let per_row = per_row.clamp(1.0, (samples / DRIFT_ROWS as f64).floor().max(1.0));
    let t_end = if cut { samples * sample_time } else { s.simulation.t_end };
    let simulation = crate::scenario::Simulation {
        precision,
        sample_time: Some(sample_time),
        t_end,
        output_step: per_row * sample_time,
        ..s.simulation
    };
    let sampled = crate::Scenario { simulation, noise: None, ..s.clone() };
    let result = side_run(&sampled, design).map_err(|e| e.to_string())?;
    let diverged = match &result.outcome {
        Some(Outcome::Diverged { t, .. }) => Some(*t),
        _ => None,
    };
    let mut lines = Vec::new();
    // In f32, the sampling is judged on the same loop in f64, which the precision check runs.
    let measured = precision_check(&sampled, design, &result);
    let precision_measured = measured.is_some();
    let double = match measured {
        Some(check) => {
            lines.push((check.line, check.flagged));
            check.reference
        }
        None => result,
    };
    let f64_scenario = crate::Scenario {
        simulation: crate::scenario::Simulation { precision: crate::controller::Precision::F64, ..sampled.simulation },
        ..sampled
    };
    let (sampling, compared) = sampled_lines(&f64_scenario, design, &double, None);
    // Not compared, and nothing said of it (the continuous loop or the sampled one ended early):
    // said, as a warning, not read as following (a diverging true plant had read "follows").
    let unsaid = compared == Compared::Not && sampling.is_empty();
    let follows = compared == Compared::Follows;
    lines.extend(sampling.into_iter().map(|l| (l, !follows)));
    if unsaid {
        let ended = match &double.outcome {
            None | Some(Outcome::Completed) => "completes".to_string(),
            Some(o) => format!("ended early ({o})"),
        };
        lines.push((format!("the sampled-data loop {ended} and was not compared with its continuous loop, which did not run to t_end (a run of the scenario without its sample time says why)"), true));
    }
    Ok(ExportCheck { lines, follows, horizon: t_end, cut, precision_measured, diverged })
}

/// What [`export_check`] found: its lines, each with whether it warns (the loop departs, or was not
/// compared), whether the sampled loop stays within the departure bounds of its continuous loop
/// (y within half its peak, u_f's peak within twice: `follows`), and the horizon run (`cut`:
/// shorter than the scenario's t_end), and whether an f32 loop was measured against f64
/// (`precision_measured`: not where either run was stopped or failed), and when the exported
/// loop (its precision, sampled) diverged (`diverged`: the time; `quell export` then fails).
#[derive(Debug, Clone, PartialEq)]
pub struct ExportCheck {
    pub lines: Vec<(String, bool)>,
    pub follows: bool,
    pub horizon: f64,
    pub cut: bool,
    pub precision_measured: bool,
    pub diverged: Option<f64>,
}

/// One channel's departure of an f32 run from its f64 run ([`precision_check`]), each relative to
/// the f64 run's peak over their common rows; `growth` is η̂'s largest departure over the last
/// tenth of the rows against the tenth before (NaN with fewer than [`DRIFT_ROWS`] rows).
struct PrecisionDeparture {
    y: f64,
    uf: f64,
    eta: f64,
    growth: f64,
}

/// η̂'s departure growing by more than this over a tenth of the run is a drift: a departure that
/// grows linearly from t = 0 grows by 1.11 over the last tenth; rounding's noise about a steady
/// departure, by less than this.
const DRIFT_GROWTH: f64 = 1.05;
/// The fewest common rows over which a growth is judged (two tenths of at least two rows each).
const DRIFT_ROWS: usize = 20;

fn precision_departures(single: &SimResult, double: &SimResult) -> Vec<PrecisionDeparture> {
    let (m, q) = (single.m, single.q);
    let rows = common_rows(&single.t, &double.t);
    // The largest over `rows` of a block's (`w` columns at `at`, rows of `width`) departure's norm,
    // and of the f64 block's norm.
    let gaps = |(a, b): (&[f64], &[f64]), (width, at, w): (usize, usize, usize), rows: &[(usize, usize)]| {
        rows.iter().fold((0.0f64, 0.0f64), |(dev, peak), &(k, j)| {
            let (x, y) = (&a[k * width + at..k * width + at + w], &b[j * width + at..j * width + at + w]);
            let d = x.iter().zip(y).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
            (dev.max(d), peak.max(y.iter().map(|y| y * y).sum::<f64>().sqrt()))
        })
    };
    let share = |(dev, peak): (f64, f64)| if dev == 0.0 { 0.0 } else { dev / peak };
    let tenth = rows.len() / 10;
    let (last, before) = (&rows[rows.len() - tenth..], &rows[rows.len() - 2 * tenth..rows.len() - tenth]);
    (0..m)
        .map(|i| {
            let eta = ((&single.eta[..], &double.eta[..]), (m * q, i * q, q));
            let growth = if rows.len() < DRIFT_ROWS {
                f64::NAN
            } else {
                gaps(eta.0, eta.1, last).0 / gaps(eta.0, eta.1, before).0
            };
            PrecisionDeparture {
                y: share(gaps((&single.y, &double.y), (m, i, 1), &rows)),
                uf: share(gaps((&single.u_f, &double.u_f), (m, i, 1), &rows)),
                eta: share(gaps(eta.0, eta.1, &rows)),
                growth,
            }
        })
        .collect()
}

/// The longest of T_s/2, T_s/4, … ([`HALVINGS`] at most, within [`HALVING_STEPS`] in all) whose
/// completed run agrees with `continuous` on every channel, with its departures.
fn agreeing_sample_time(
    s: &crate::Scenario,
    design: &Design,
    sample_time: f64,
    continuous: &SimResult,
) -> Result<(f64, Vec<ChannelDeparture>), u32> {
    let t_end = s.simulation.t_end;
    // The halvings' steps add up: T_s/2 … T_s/2^k take t_end/T_s·(2^(k+1) − 2) in all.
    let total = |k: u32| t_end / sample_time * f64::from((1u32 << (k + 1)) - 2);
    let tried = (1..=HALVINGS).take_while(|&k| total(k) <= HALVING_STEPS).count() as u32;
    (1..=tried)
        .map(|k| sample_time / f64::from(1u32 << k))
        .find_map(|T| {
            let settings = RunSettings { mode: Loop::Sampled { sample_time: T }, ..side_settings(s) };
            let r = Run::of(s, design).settings(settings).simulate(|_| ControlFlow::Continue(())).ok()?;
            let channels =
                departures(&r, continuous).filter(|_| matches!(r.outcome, None | Some(Outcome::Completed)))?;
            channels.iter().all(|c| !c.departed()).then_some((T, channels))
        })
        .ok_or(tried)
}

/// The advice on a sampled-data run of scenario `s`: where it departs from its continuous loop
/// ([`against_continuous`]) or diverged where that completes, by how much and the halved sample
/// time that agrees, if one does (T_s/2 … T_s/64, within [`HALVING_STEPS`]); where T_s·ρ is beyond
/// [`COARSE_SAMPLE`] (warned before the run) but the run follows its continuous loop, that it
/// does. Without a comparison, the heuristic [`sampled_transient`].
pub fn sampled_advice(s: &crate::Scenario, design: &Design, result: &SimResult) -> Vec<String> {
    let quiet = super::noise::without_noise(s, design);
    sampled_lines(s, design, result, quiet.as_ref()).0
}

/// What the comparison of a sampled-data run with its continuous loop found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Compared {
    /// Not compared (a continuous run, one that ended early, a comparison that could not run).
    Not,
    /// The sampled loop departs from its continuous loop, or diverged where that completes.
    Departs,
    /// It follows its continuous loop, coarse sample time or not: its errors are the design's.
    Follows,
}

/// A run that diverged under its noise and completes without it, said first: what the comparison
/// with the continuous loop offers (a sample time) is for the noise-free loop (a bicycle under 0.2
/// mrad of noise had been told only to sample faster, and diverged as fast there).
fn noise_drove(result: &SimResult, quiet: Option<&super::noise::Quiet>) -> Vec<String> {
    match quiet {
        Some((_, qr))
            if matches!(result.outcome, Some(Outcome::Diverged { .. }))
                && matches!(qr.outcome, None | Some(Outcome::Completed)) =>
        {
            vec!["the run diverged under its [noise] and completes without it at the same sample time: the noise drives it away, whatever the sampling below adds; reduce the noise (a sensor filter, noise.std) or slow the loop that amplifies it (slower design.observer_poles and design.channel_poles)".to_string()]
        }
        _ => Vec::new(),
    }
}

/// The continuous loop of scenario `s` for the sampled run `result`, within the run's own step
/// budget and [`COMPARISON_PER_SAMPLE`] steps per controller step, up to where a diverged run
/// ended: a Furuta pendulum's (342,727 steps, 1.4 s) had been cut at a fixed 200,000 and not
/// compared, while its sampled loop and compiled f32 C asked 25.6 V against 4.1 V (helper tryout,
/// 2026-12-07). Where it cannot be run, [`sampled_lines`]'s answer: what stopped it, or the
/// heuristic.
fn continuous_within_budget(
    s: &crate::Scenario,
    design: &Design,
    result: &SimResult,
) -> Result<SimResult, (Vec<String>, Compared)> {
    // As far as the sampled run went (one that diverged in 4 s of a 15,000 s horizon had been
    // compared over the whole horizon, 7 minutes), and at most COMPARISON_PER_SAMPLE solver steps
    // per controller step of it (past the budget of the run, not of its comparison: a 3,000 s
    // wind turbine at 10 ms had cost 35 s more).
    let RunStats::Sampled { controller_steps, .. } = result.stats else { return Err((Vec::new(), Compared::Not)) };
    // To the row at or after the divergence (its last row comes before it).
    let t_end = match result.outcome {
        Some(Outcome::Diverged { t, .. }) => {
            let h = s.simulation.output_step;
            Some(((t / h).ceil() * h).max(h).min(s.simulation.t_end))
        }
        _ => None,
    };
    let max_steps = Some(COMPARISON_STEPS.max(COMPARISON_PER_SAMPLE * controller_steps));
    match continuous_loop(s, design, Some(Reach { progress: &mut go_on, max_steps, t_end })) {
        Ok(c) => Ok(c),
        Err(Skipped::Ended(Outcome::TooManySteps { t, max_steps })) => {
            let which = format!("needed more than its step budget of {max_steps} by t = {}", fmt_instant(t));
            Err(not_compared(result, &which, "run that, with a larger step budget, to compare"))
        }
        Err(Skipped::Ended(Outcome::HistoryTooLarge { t, max_bytes })) => {
            let which = format!(
                "would have held more than its history budget of {} MB by t = {}",
                max_bytes >> 20,
                fmt_instant(t)
            );
            Err(not_compared(result, &which, "a run of it says why"))
        }
        Err(_) => Err((sampled_transient(result), Compared::Not)),
    }
}

/// A sampled run whose continuous loop ran out of its budget (`which` did, by t): said, with
/// `what_to_do` and the heuristic [`sampled_transient`] beside it.
fn not_compared(result: &SimResult, which: &str, what_to_do: &str) -> (Vec<String>, Compared) {
    let mut lines = vec![format!(
        "this sampled-data run was not compared with its continuous loop (the same scenario without its sample time), which {which} {}: {what_to_do}",
        result.time_unit
    )];
    lines.extend(sampled_transient(result));
    (lines, Compared::Not)
}

/// [`sampled_advice`], with `quiet` the run without `s`'s noise where it has some
/// ([`super::noise::without_noise`]), and what the comparison with its continuous loop found.
pub(crate) fn sampled_lines(
    s: &crate::Scenario,
    design: &Design,
    result: &SimResult,
    quiet: Option<&super::noise::Quiet>,
) -> (Vec<String>, Compared) {
    let not = (Vec::new(), Compared::Not);
    let RunStats::Sampled { sample_time, .. } = result.stats else { return not };
    if matches!(result.outcome, Some(Outcome::Interrupted { .. } | Outcome::TooManySteps { .. })) {
        return not;
    }
    // Under noise, which the two loops read at different instants, both are compared without it (a
    // flexible joint whose u_f reached 8,646 under 1e-4 rad of noise had been compared with
    // nothing, and its tail's noise hid the transient from the heuristic).
    let noise_drove = noise_drove(result, quiet);
    let (s, result, without) = match (&s.noise, quiet) {
        (None, _) => (s, result, ""),
        (Some(_), Some((qs, qr))) => (qs, qr, "; both without [noise]"),
        (Some(_), None) => return (sampled_transient(result), Compared::Not),
    };
    let continuous = match continuous_within_budget(s, design, result) {
        Ok(c) => c,
        Err(lines) => return lines,
    };
    let Some(channels) = departures(result, &continuous) else { return (sampled_transient(result), Compared::Not) };
    let (unit, coarse) = (result.time_unit, coarse(s, design, sample_time));
    // On a [truth] both loops run the true plant: said, beside the advice that is for the model.
    let loop_of = if super::truth_differences(s).is_empty() {
        format!("the same scenario without its sample time{without}")
    } else {
        format!("the same scenario and true plant without its sample time{without}")
    };
    let at = format!("T_s = {} {unit}", fmt_short(sample_time));
    let what = match &result.outcome {
        Some(Outcome::Diverged { t, .. }) => {
            let peaks: Vec<String> = (0..result.m).map(|i| fmt_4(continuous.max_uf(i))).collect();
            format!(
                "the sampled-data loop at {at} diverged at t = {} {unit}, where its continuous loop ({loop_of}) runs to that time with max|u_f| = {}",
                fmt_instant(*t),
                peaks.join(", ")
            )
        }
        _ if channels.iter().any(ChannelDeparture::departed) => {
            let how = departed(&channels, ChannelDeparture::departed);
            format!("the sampled-data loop at {at} departs from its continuous loop ({loop_of}): {how}")
        }
        _ if coarse && channels.iter().all(ChannelDeparture::follows) => {
            let worst = channels.iter().map(|c| c.y).fold(0.0, f64::max);
            let ratio = channels.iter().map(|c| c.uf.0 / c.uf.1).fold(0.0, f64::max);
            return (vec![format!(
                "T_s·ρ is beyond {COARSE_SAMPLE} (the warning before the run), yet this run at {at} follows its continuous loop: y within {} of its peak, u_f's peaks at most {}× the continuous ones",
                percent(worst),
                fmt_ratio(ratio)
            )], Compared::Follows);
        }
        _ => return (Vec::new(), Compared::Follows),
    };
    let within = if coarse { "" } else { ", even within T_s·ρ ≤ 0.2" };
    // The automatic design checks a sampled run's u_f against its continuous loop's, not its y: it
    // is offered where u_f departs or the run diverged (a design it had verified, departing in y
    // alone, had been sent back to it).
    let effort =
        !matches!(result.outcome, None | Some(Outcome::Completed)) || channels.iter().any(ChannelDeparture::driven);
    let remedy = remedy(s, design, (sample_time, effort), &continuous);
    let mut lines = noise_drove;
    lines.push(format!("{what}; the sampling makes it{within}: {remedy}"));
    (lines, Compared::Departs)
}

/// The channels of `channels` that `which` picks, each with its figures: "y[i] by X % of its
/// continuous peak, max|u_f[i]| A against B (N×)", joined by "; ".
fn departed(channels: &[ChannelDeparture], which: impl Fn(&ChannelDeparture) -> bool) -> String {
    let line = |(i, c): (usize, &ChannelDeparture)| {
        format!(
            "y[{}] by {} of its continuous peak, max|u_f[{}]| {} against {}{} ({}×)",
            i + 1,
            percent(c.y),
            i + 1,
            fmt_4(c.uf.0),
            fmt_4(c.uf.1),
            if c.floored { " (a floor: the continuous loop holds it near zero)" } else { "" },
            // Three digits: 2.04× had read "2×" beside "beyond twice".
            fmt_short(crate::settings::significant(c.uf.0 / c.uf.1, 3))
        )
    };
    let lines: Vec<String> = channels.iter().enumerate().filter(|(_, c)| which(c)).map(line).collect();
    lines.join("; ")
}

/// Where the completed sampled-data run `result` of scenario `s` (under measurement noise, both
/// loops without it) drives u_f beyond [`DEPARTED_UF`] times its continuous loop's peak
/// ([`against_continuous`]), how ([`departed`]); `None` where it does not or the comparison cannot
/// run. What the automatic design's verification asks of a sampled-data candidate besides its
/// tails (a Wardle–Wood column's, sampled at 1 min, had passed with u_f about 1e4 against about 20
/// in its continuous loop, and the run's advice then sent the user back to the automatic design);
/// a transient of y that differs but converges within the tail bound at no more effort (the
/// maglev's first proposal: y by 69 %, u_f 0.83×) is the tail's to judge. `progress` is the side
/// runs' callback (a stop ends them; the caller tells).
pub(crate) fn effort_departure(
    s: &crate::Scenario,
    design: &Design,
    result: &SimResult,
    progress: Progress<'_>,
) -> Option<String> {
    if !matches!(result.outcome, None | Some(Outcome::Completed)) {
        return None;
    }
    // Under measurement noise, which the two loops read at different instants, both without it,
    // as the run's comparison does (a noisy scenario had been verified with no comparison at all).
    let quiet;
    let (s, result, without) = match s.noise {
        None => (s, result, ""),
        Some(_) => {
            let q = crate::Scenario { noise: None, ..s.clone() };
            let r = Run::of(&q, design).settings(side_settings(&q)).simulate(&mut *progress).ok()?;
            quiet = (q, r);
            (&quiet.0, &quiet.1, "; both without [noise]")
        }
    };
    // Within the run's own step budget: the verification is the design's, and a loop past the
    // comparison's cap (a suspension over 1,700 s) had passed unchecked at 4× its continuous u_f.
    let (_, channels) = compared(s, design, result, Some(progress))?;
    let driven = ChannelDeparture::driven;
    channels.iter().any(driven).then(|| departed(&channels, driven) + without)
}

/// What the search of [`agreeing_sample_time`] tried before it gave up: `tried` halvings of
/// `sample_time`, fewer than [`HALVINGS`] where [`HALVING_STEPS`] cut it short (a maglev told
/// "halving up to 6 times did not bring the two together (or took more than 2e6 controller
/// steps)" had been tried 3 times, and one fewer from T_s/2 found the sample time).
fn halvings_tried(tried: u32, sample_time: f64, unit: crate::settings::TimeUnit) -> String {
    let reached = fmt_short(sample_time / f64::from(1u32 << tried.min(31)));
    match tried {
        0 => format!("a halved T_s would take more than {HALVING_STEPS:.0e} controller steps, so none was tried"),
        k if k < HALVINGS => format!(
            "halving T_s {k} times, to {reached} {unit}, did not bring the two together (a shorter one would take more than {HALVING_STEPS:.0e} controller steps, so none was tried)"
        ),
        k => format!("halving T_s {k} times, to {reached} {unit}, did not bring the two together"),
    }
}

/// What to do about a departure at `sample_time`: the halved sample time that agrees
/// ([`agreeing_sample_time`]), or a design for that sample time.
fn remedy(s: &crate::Scenario, design: &Design, (sample_time, effort): (f64, bool), continuous: &SimResult) -> String {
    let unit = continuous.time_unit;
    let design_for = if effort {
        "or let the automatic design choose poles for that sample time (the scenario with that simulation.sample_time and its [design] poles left out)"
    } else {
        "or give slower design.channel_poles and design.observer_poles"
    };
    match agreeing_sample_time(s, design, sample_time, continuous) {
        Ok((T, c)) => format!(
            "at T_s = {} {unit} it stays within half of y's peak and twice u_f's (y within {}, u_f's peaks at most {}× the continuous ones): sample that fast, {design_for}",
            fmt_short(T),
            percent(c.iter().map(|c| c.y).fold(0.0, f64::max)),
            fmt_ratio(c.iter().map(|c| c.uf.0 / c.uf.1).fold(0.0, f64::max))
        ),
        Err(tried) => format!(
            "{}: {}",
            halvings_tried(tried, sample_time, unit),
            if effort {
                "let the automatic design choose poles for the sample time (the scenario with its simulation.sample_time and its [design] poles left out), or design the continuous loop and judge the sampled one by its own tail and effort"
            } else {
                "give slower design.channel_poles and design.observer_poles, or judge the sampled loop by its own tail and effort"
            }
        ),
    }
}

/// T_s·ρ beyond [`COARSE_SAMPLE`] for the run's true plant and signals.
fn coarse(s: &crate::Scenario, design: &Design, sample_time: f64) -> bool {
    is_coarse(sample_time * loop_rate(design, s.true_plant(), [&s.reference, &s.disturbance]))
}

/// A share as a percentage to two significant digits ("5.7 %", "540 %").
fn percent(share: f64) -> String {
    format!("{} %", fmt_short(crate::settings::significant(100.0 * share, 2)))
}

/// Per channel of a completed sampled-data run whose u_f peaked [`SAMPLED_TRANSIENT`] times its
/// tail's peak or more: what to compare it with and which way to move T_s. Empty otherwise.
pub fn sampled_transient(result: &SimResult) -> Vec<String> {
    let RunStats::Sampled { sample_time, .. } = result.stats else { return Vec::new() };
    let (Some(from), None | Some(Outcome::Completed)) = (result.tail_from(), &result.outcome) else {
        return Vec::new();
    };
    let unit = result.time_unit;
    let lines = (0..result.m).filter_map(|i| {
        let rows = result.t.iter().zip(result.column(&result.u_f, result.m, i));
        let tail = rows.filter(|(t, _)| **t >= from).fold(0.0f64, |a, (_, u)| a.max(u.abs()));
        // What the plant received, as the tail is (a clipping actuator's demand is not its input).
        let peak = result.max_uf_applied(i);
        (peak >= SAMPLED_TRANSIENT * tail).then(|| {
            format!(
                "u_f[{}] peaked at {}, {}× its peak over the tail ({}): where the continuous loop (the run without its sample time) does not, the sampling at T_s = {} {unit} makes it, even within T_s·ρ ≤ {}; then shorten T_s until the peak comes near the continuous one",
                i + 1,
                fmt_4(peak),
                fmt_ratio(peak / tail),
                fmt_4(tail),
                fmt_short(sample_time),
                COARSE_SAMPLE
            )
        })
    });
    lines.collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The search says how far it went, and why it stopped there.
    #[test]
    fn the_halvings_tried_are_named() {
        let ms = crate::settings::TimeUnit::from_name("ms").unwrap();
        assert_eq!(
            halvings_tried(0, 0.02, ms),
            "a halved T_s would take more than 2e6 controller steps, so none was tried"
        );
        assert_eq!(
            halvings_tried(3, 0.02, ms),
            "halving T_s 3 times, to 0.0025 ms, did not bring the two together (a shorter one would take more than 2e6 controller steps, so none was tried)"
        );
        assert_eq!(
            halvings_tried(HALVINGS, 0.64, ms),
            "halving T_s 6 times, to 0.01 ms, did not bring the two together"
        );
    }
}
