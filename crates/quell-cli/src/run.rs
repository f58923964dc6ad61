//! `quell run`: load the scenario and design, check every input, simulate (Ctrl-C stops at the next
//! recorded sample), write the files, report how the run ended.

use std::fmt::Write as _;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant;

use quell::diagnostics::{ChannelDiagnostics, Diagnostics};
use quell::scenario::Scenario;
use quell::sim::{Loop, Method, Outcome, Run, RunSettings, RunStats, SimResult, ROUNDING_SHARE};
use quell::Design;
use quell::TimeUnit;
use serde_json::json;

use crate::interrupt::Interrupt;
use crate::{file_sample_time, load_with, output, plot, report, set_sample_time, Failure};

#[derive(clap::Args, Default)]
pub struct RunArgs {
    /// Scenario file (TOML); the paper's example (Section VIII) when omitted.
    pub scenario: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "quell-out")]
    pub out: PathBuf,
    /// Sampled-data run with the discrete controller at this sample time, in the plant's unit of
    /// time (plant.time_unit); overrides simulation.sample_time.
    #[arg(long, value_name = "T_S", allow_hyphen_values = true, value_parser = crate::parse_real)]
    pub sample_time: Option<f64>,
    /// Simulate to this time, in the plant's unit of time; overrides simulation.t_end.
    #[arg(long, value_name = "T", allow_hyphen_values = true, value_parser = crate::parse_real)]
    pub t_end: Option<f64>,
    /// A row of signals.csv every H, in the plant's unit of time; overrides simulation.output_step.
    #[arg(long, value_name = "H", allow_hyphen_values = true, value_parser = crate::parse_real)]
    pub output_step: Option<f64>,
    /// The continuous loop even where the scenario sets simulation.sample_time: to compare the
    /// sampled-data loop with the one it approximates.
    #[arg(long, conflicts_with = "sample_time")]
    pub continuous: bool,
    /// Skip the PNG/SVG plots.
    #[arg(long)]
    pub no_plots: bool,
    /// Step budget of the continuous loop, and with it the delay history's memory budget (default:
    /// derived from the problem's time scales; see docs/running.md). A run that needs more ends as
    /// failed, its results up to then written.
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = parse_max_steps)]
    pub max_steps: Option<usize>,
    /// Also record the plant state x and the observer state x̂ (columns x1..xn, xhat1..xhatn of
    /// signals.csv).
    #[arg(long)]
    pub states: bool,
    /// The continuous loop's integrator: auto (DOP853, implicit in η̂ while the adaptive law is
    /// stiff), explicit (DOP853 throughout) or imex (implicit in η̂ throughout); overrides
    /// simulation.method.
    #[arg(long, value_name = "METHOD")]
    pub method: Option<String>,
    /// The discrete controller's arithmetic in a sampled-data run: f64, or f32 to see the loop as a
    /// single-precision build (quell export --precision f32) runs it, emulated; overrides
    /// simulation.precision.
    #[arg(long, value_name = "PRECISION", conflicts_with = "continuous")]
    pub precision: Option<String>,
}

pub fn run(args: &RunArgs) -> Result<(), Failure> {
    let (scenario, design) = load_with(args.scenario.as_deref(), |sim| {
        // --continuous discards a valid sample time before the checks (one beyond a --t-end is no
        // matter); a bad one stays, for them to refuse, so the scenario read has none.
        if args.continuous && file_sample_time(sim).is_some() {
            sim.remove("sample_time");
            sim.remove("precision"); // the discrete controller's, which the continuous loop has not
        }
        set_sample_time(sim, args.sample_time);
        // Any value, for the scenario's checks to name with the flag.
        for (key, value) in [("t_end", args.t_end), ("output_step", args.output_step)] {
            if let Some(v) = value {
                sim.insert(key.into(), toml::Value::Float(v));
            }
        }
        if let Some(name) = &args.precision {
            sim.insert("precision".into(), toml::Value::String(name.clone()));
        }
    })?;
    eprint!("{}", report::warnings_text(&quell::design::warnings(&design, &scenario.design)));
    // A run on [truth] says so up front: its figures are not the design model's.
    let truth = quell::diagnostics::truth_differences(&scenario);
    if !truth.is_empty() {
        eprintln!("simulating the true plant ([truth]), not the design model: {}", truth.join(", "));
    }
    // Every check that can fail on input happens before the output directory is touched.
    let settings = loop_settings(args, &scenario, &design)?;
    if let Loop::Sampled { sample_time } = settings.mode {
        let output_step = settings.output_step_given.then_some(settings.output_step);
        eprint!("{}", report::sample_time_text(&scenario, &design, sample_time, output_step));
    }
    let set_by = if args.method.is_some() { "--method explicit" } else { quell::sim::EXPLICIT_IN_FILE };
    let run = Run::of(&scenario, &design).settings(settings.clone());
    // Before the output directory is touched (one refused for its memory budget had been created).
    run.check().map_err(|e| Failure::Input(e.to_string()))?;
    for w in [
        quell::sim::explicit_stiff_warning(&run, set_by),
        quell::sim::fast_rate_warning(&run),
        csv_size_warning(&design, &settings),
    ]
    .into_iter()
    .flatten()
    {
        eprintln!("⚠ warning: {w}");
    }
    let out = &args.out;
    // The figures' names too: one taken by a directory would fail only after the run.
    let figures: Vec<String> =
        (1..=design.plant().m()).flat_map(|i| ["png", "svg"].map(|e| format!("channel{i}.{e}"))).collect();
    let files: Vec<&str> =
        ["signals.csv", "design.json", "summary.json"].into_iter().chain(figures.iter().map(String::as_str)).collect();
    if let Some(input) = &args.scenario {
        output::not_the_input(input, out, &files)?;
    }
    output::prepare_out(out, &files)?;
    // Ctrl-C or SIGTERM stops the run at its next recorded sample; a second one before that sample
    // (a very stiff run can take long to reach it) quits with no files.
    let ctrl_c = Interrupt::install("interrupted twice; stopped without writing files");
    let started = Instant::now();
    let result = simulate(&scenario, &design, settings, &ctrl_c)?;
    ctrl_c.start_writing();
    let seconds = started.elapsed().as_secs_f64();
    let diagnostics = quell::diagnostics::diagnose_run(&scenario, &design, &result);
    let diagnosed = started.elapsed().as_secs_f64() - seconds;
    let done = Finished {
        scenario: &scenario,
        design: &design,
        result: &result,
        diagnostics: &diagnostics,
        seconds,
        diagnosed,
    };
    write_outputs(out, &done, !args.no_plots).map_err(|e| {
        Failure::Run(format!(
            "writing {}: {e}; none of this run's files replaced those there before: make room or choose another --out, and run again",
            out.display()
        ))
    })?;
    report_outcome(&done, out)
}

/// A run that ended (completed or not): what its files and its report are made of.
struct Finished<'a> {
    scenario: &'a Scenario,
    design: &'a Design,
    result: &'a SimResult,
    diagnostics: &'a Diagnostics,
    /// Wall time of the simulation.
    seconds: f64,
    /// Wall time of the diagnosis after the run (its comparison runs: a sampled run's continuous
    /// loop had taken 22 s of a command that said 0.77 s; helper tryout, 2026-12-07).
    diagnosed: f64,
}

/// The scenario's loop ([`RunSettings::of`]), or the sampled-data loop at `--sample-time`, checked
/// (settings, signals, truth; a sampled-data loop's delays whole samples, output step a multiple).
fn loop_settings(args: &RunArgs, scenario: &Scenario, design: &Design) -> Result<RunSettings, Failure> {
    let mut settings = match args.sample_time {
        Some(t) if !(t.is_finite() && t > 0.0) => {
            return Err(Failure::Input(format!(
                "--sample-time: expected a finite sample time > 0 (in the plant model's unit of time), found {t}"
            )))
        }
        Some(sample_time) => RunSettings { mode: Loop::Sampled { sample_time }, ..RunSettings::of(scenario) },
        None => RunSettings::of(scenario),
    };
    if let Loop::Sampled { .. } = settings.mode {
        let run = Run::of(scenario, design).settings(settings.clone());
        run.check().map_err(|e| match args.sample_time {
            // The flag, not the file's key, made the output step no whole number of samples: name
            // both (not for the record's size, also a refusal of output_step, which it had hidden
            // behind "1.000000 samples"; hostile review).
            Some(t)
                if e.to_string().starts_with("simulation.output_step: expected a whole multiple of sample_time") =>
            {
                output_step_error(design, t, scenario.simulation.output_step, args.output_step.is_some())
            }
            _ => Failure::Input(e.to_string()),
        })?;
    }
    settings.record_states = args.states;
    if let Some(name) = &args.method {
        let method = Method::from_name(name).map_err(|e| Failure::Input(format!("--method: {e}")))?;
        match &mut settings.mode {
            Loop::Continuous(integrator) => integrator.method = method,
            Loop::Sampled { sample_time } => {
                return Err(Failure::Input(format!(
                    "--method: the integrator applies to the continuous loop only, and this run is the sampled-data loop at T_s = {} {} (the plant is advanced exactly between samples); remove --method, or run the continuous loop with --continuous (in place of any --sample-time)",
                    short(*sample_time),
                    scenario.plant.time_unit
                )))
            }
        }
    }
    settings.set_max_steps(args.max_steps).map_err(|e| Failure::Input(format!("--max-steps: {}", e.message)))?;
    Ok(settings)
}

/// `--sample-time T` against `simulation.output_step` h (the file's, or `--output-step`'s: `flag`), which is not a whole number ≥ 1
/// of samples (every recorded row is a controller step): the error names the flag and the key,
/// with the nearest fix on either side.
fn output_step_error(design: &Design, T: f64, h: f64, flag: bool) -> Failure {
    let (ratio, s) = (h / T, design.plant().time_unit);
    let (divisor, multiple) = quell::sim::output_step_fixes(design, T, h);
    // Where --output-step gave it, the key is named with the flag ([`crate::in_flags`]); it had
    // said "from the scenario file".
    let from = if flag { "" } else { " (from the scenario file)" };
    let multiple = format!("set simulation.output_step to a multiple of the sample time, e.g. {} {s}", short(multiple));
    // A divisor only where one makes the delays whole too: h/⌈h/T⌉ had been offered where none
    // does, which the delays' check then refused.
    let fixes = match divisor {
        Some(d) => format!("give a --sample-time that divides it, e.g. {} {s}, or {multiple}", short(d)),
        None => format!("{multiple} (no sample time near {} {s} that divides it makes plant.delays whole)", short(T)),
    };
    Failure::Input(format!(
        "--sample-time {}: simulation.output_step = {} {s}{from} is not a whole number of samples of {} {s} ({ratio:.6} samples; each recorded row is a controller step); {fixes}",
        short(T),
        short(h),
        short(T),
    ))
}

/// A magnitude with `decimals` fixed decimals where that shows its digits without a long tail of
/// them (0, or 0.01 to 1e4), in scientific notation otherwise: not an input of 3.7e-5 mA printed as
/// "0.000", nor 790840.023 beside 2.784e6.
pub(crate) fn fixed_or_sci(x: f64, decimals: usize) -> String {
    if x == 0.0 || (1e-2..1e4).contains(&x.abs()) {
        format!("{x:.decimals$}")
    } else {
        format!("{x:.decimals$e}")
    }
}

/// Input i's share `f` of the recorded samples that the true actuator's limit clipped, as a line
/// (its channel's max|u_f| is then what the controller asked for, [`quell::sim::SimResult::peak_demand`]).
pub(crate) fn clipped(i: usize, f: f64, actuator: Option<&quell::settings::Actuator>) -> String {
    format!(
        "input {}: clipped by {} at {} of the recorded samples (max|u_f| is what the controller asked for)",
        i + 1,
        actuator.map_or_else(|| format!("truth.u_max[{i}]"), |a| a.limit_keys(i)),
        quell::settings::fmt_percent(f)
    )
}

/// "max|u_f,i|" (i from 1), with input i's name where the scenario gives one: u_f,i is plant input
/// i, which channel i's line shows without pairing it with output i (a quadrotor's input 1, thrust,
/// drives z, not channel 1's x; the line had read "channel 1 (x_m): … max|u_f| = 0.399").
pub(crate) fn uf_label(inputs: Option<&[String]>, i: usize) -> String {
    match inputs.and_then(|n| n.get(i)) {
        Some(name) => format!("max|u_f,{}| ({name})", i + 1),
        None => format!("max|u_f,{}|", i + 1),
    }
}

/// A time for a message, to 12 significant digits and without trailing zeros.
pub(crate) use quell::settings::fmt_time as short;

/// The continuous or the sampled-data loop on the scenario's true plant, with a progress bar.
fn simulate(
    scenario: &Scenario,
    design: &Design,
    settings: RunSettings,
    ctrl_c: &Interrupt,
) -> Result<SimResult, Failure> {
    let bar = crate::progress_bar(
        (scenario.simulation.t_end * 1000.0) as u64,
        "simulating {bar:40} {percent:>3}% of t_end, {elapsed_precise} elapsed, ETA {eta}",
    );
    let progress = |t: f64| {
        bar.set_position((t * 1000.0) as u64);
        if ctrl_c.interrupted() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    };
    let run = Run::of(scenario, design).settings(settings);
    let result = run.simulate(progress).map_err(|e| Failure::Input(e.to_string()))?;
    bar.finish_and_clear();
    Ok(result)
}

/// signals.csv's size where it passes [`LARGE_CSV`]: rows × numbers × about 20 bytes (the
/// shortest digits that read back, and a comma), which the row and memory limits allow up to many
/// gigabytes (a servo at an output step of 5e-7 s wrote 2.4 GB without a word).
fn csv_size_warning(design: &quell::Design, settings: &quell::sim::RunSettings) -> Option<String> {
    let p = design.plant();
    let rows = (settings.t_end / settings.output_step).floor() + 1.0;
    let (numbers, _) = quell::sim::SimResult::row_len(p.m(), design.q(), p.n(), settings.record_states);
    let bytes = rows * numbers as f64 * 20.0;
    (bytes > LARGE_CSV).then(|| {
        format!(
            "signals.csv will hold {rows:.3e} rows of {numbers} numbers, about {:.1} GB; a longer simulation.output_step (--output-step) writes less",
            bytes / 1e9
        )
    })
}

/// The size of signals.csv beyond which a run warns before it starts.
const LARGE_CSV: f64 = 1e9;

fn write_outputs(dir: &Path, done: &Finished<'_>, plots: bool) -> std::io::Result<()> {
    let r = done.result;
    // Every file in place or none; figures of an earlier run (more channels, or plots now skipped)
    // removed with them, as they must not stand beside the new data.
    let channel_figure = |stem: &str| stem.strip_prefix("channel").is_some_and(|i| i.parse::<usize>().is_ok());
    // summary.json last: a directory without it holds no complete run.
    output::all_or_nothing(dir, "summary.json", channel_figure, || {
        // Figures render on their own threads (one per channel) while the data files are written.
        std::thread::scope(|scope| {
            let figures: Vec<_> = (0..if plots { r.m } else { 0 })
                .map(|i| scope.spawn(move || plot::plot_channel(dir, r, i, &done.scenario.names)))
                .collect();
            let data = write_data(dir, done);
            for figure in figures {
                figure.join().map_err(|_| std::io::Error::other("plotting panicked"))??;
            }
            data
        })
    })
}

fn write_data(dir: &Path, done: &Finished<'_>) -> std::io::Result<()> {
    let Finished { scenario, design, result: r, diagnostics, seconds, .. } = *done;
    output::write_signals(&dir.join("signals.csv"), r)?;
    output::write_json(&dir.join("design.json"), &crate::pace::design_json(scenario, design))?;
    let summary = json!({
        "scenario": scenario.name,
        "time_unit": scenario.plant.time_unit.symbol(),
        "truth_differs": scenario.truth_differs(),
        "limited_fraction": (!r.limited.is_empty()).then(|| r.limited_fraction()),
        "outcome": r.outcome,
        "channels": r.summary(),
        "stats": r.stats,
        "samples": r.len(),
        "wall_time_s": seconds,
        "diagnostics": diagnostics.channels,
        "observer_fidelity": diagnostics.observer_fidelity,
        "advice": diagnostics.advice,
    });
    output::write_json(&dir.join("summary.json"), &summary)
}

/// Channel i's convergence figures and advice, under its line of figures.
fn report_diagnostics(d: &ChannelDiagnostics, time: TimeUnit, text: &mut String) {
    let trend = d.tail_trend.zip(d.tail_window).map_or(String::new(), |(r, w)| {
        format!(", tail RMS ratio (last two windows of {} {time}) {r:.2}", quell::settings::fmt_4(w))
    });
    // A singular Ω̄ (fewer excited directions than q) gives 1/(μλ_min) = ∞; the error does not depend
    // on the unexcited directions, so the excited ones' slowest time is the one that matters.
    let convergence = if d.convergence_time.is_finite() {
        format!("{:.3e} {time}", d.convergence_time)
    } else {
        "∞ (Ω̄ singular)".into()
    };
    let excited = if d.excited_rank == 0 {
        "; no direction is excited (g and ω are zero): nothing to adapt to".to_string()
    } else if d.convergence_time_excited != d.convergence_time && d.convergence_time_excited.is_finite() {
        format!(
            "; the {} excited directions (the error depends on these alone) converge in 1/(μλ_min,excited) = {:.3e} {time}",
            d.excited_rank, d.convergence_time_excited
        )
    } else {
        String::new()
    };
    let _ = writeln!(
        text,
        "  Ω̄: λ_min = {:.3e}, λ_max = {:.3e}; averaged-law convergence time 1/(μλ_min) = {convergence}, adaptation rate μλ_max = {:.3e}/{time}{excited}{trend}",
        d.lambda_min_omega, d.lambda_max_omega, d.adaptation_rate
    );
    for line in &d.advice {
        let _ = writeln!(text, "  advice: {line}");
    }
}

/// The per-channel figures on stdout and what was written on stderr (exit 0), or why the run did not reach t_end
/// (exit 1; the files hold the samples up to then). A channel is named by its output where the
/// scenario names them (`channel 1 (pitch): …`).
fn report_outcome(done: &Finished<'_>, out: &Path) -> Result<(), Failure> {
    let Finished { scenario, result, diagnostics, seconds, diagnosed, .. } = *done;
    let outputs = scenario.names.outputs.as_deref();
    let out = out.display();
    let clipping: String = result
        .limited_fraction()
        .iter()
        .enumerate()
        .filter(|(_, &f)| f > 0.0)
        .map(|(i, &f)| clipped(i, f, scenario.actuator.as_ref()) + "\n")
        .collect();
    match result.outcome.as_ref().unwrap_or(&Outcome::Completed) {
        Outcome::Completed => {
            let mut text = String::new();
            for (i, c) in result.summary().iter().enumerate() {
                let settle = match (c.figures.settle_t, &c.settle_note) {
                    // Regulation (g_i = 0): the band is 2 % of the error's own peak, which a
                    // two-area power system's 0.098 pu tail "settled" within, 5× its load step.
                    (Some(t), _) => {
                        let regulated = result.column(&result.g, result.m, i).all(|g| g == 0.0);
                        let of = if regulated {
                            format!(
                                " of its peak error, at least {:e} of the loop's signals, g being 0",
                                ROUNDING_SHARE
                            )
                        } else {
                            String::new()
                        };
                        format!("settled (2 % band{of}) at t = {} {}", quell::settings::fmt_4(t), result.time_unit)
                    }
                    (None, Some(note)) => note.clone(),
                    (None, None) => "not settled".into(),
                };
                let name = outputs.and_then(|o| o.get(i)).map_or(String::new(), |n| format!(" ({n})"));
                let _ = writeln!(
                    text,
                    "channel {}{name}: tail max|e| = {:.3e}, tail RMS e = {:.3e}, max|u| = {}, {} = {}, ‖η̂‖ = {:.4e}, {settle}",
                    i + 1,
                    c.figures.tail_max_e,
                    c.figures.tail_rms_e,
                    fixed_or_sci(c.figures.max_u, 3),
                    uf_label(scenario.names.inputs.as_deref(), i),
                    fixed_or_sci(c.figures.max_uf, 3),
                    c.final_eta_norm
                );
                if let Some(d) = diagnostics.channels.get(i) {
                    report_diagnostics(d, scenario.plant.time_unit, &mut text);
                }
            }
            // The whole loop's advice after the channels, not indented under the last one.
            for line in &diagnostics.advice {
                let _ = writeln!(text, "advice (the whole loop): {line}");
            }
            text.push_str(&clipping);
            crate::print_stdout(&text);
            let steps = match result.stats {
                RunStats::Continuous(stats) => format!("{} solver steps", stats.steps),
                RunStats::Sampled { controller_steps, .. } => format!("{controller_steps} controller steps"),
            };
            let diagnosis = diagnosis_time(diagnosed);
            eprintln!("wrote {out} ({} samples, {steps}, in {seconds:.3} s of wall time{diagnosis})", result.len());
            Ok(())
        }
        outcome => {
            let mut why = outcome.explain("--max-steps", result.time_unit).unwrap_or_default();
            let run = quell::sim::Run::of(done.scenario, done.design);
            if let Some(culprit) = quell::sim::budget_culprit(&run, result) {
                why = format!("{why}; {culprit}");
            }
            // A true actuator that clipped may be why: the clipping, and the advice on the whole
            // loop (which names it as the likely cause), are said before the failure.
            let advice: String = diagnostics.advice.iter().map(|a| format!("advice: {a}\n")).collect();
            crate::print_stdout(&(clipping + &advice));
            Err(Failure::Run(format!("{why}; results up to then are in {out}")))
        }
    }
}

/// `--max-steps N`: a step budget, N ≥ 1 (as `max_steps` in a study and `max_steps=` in Python); clap
/// prints the message after the flag's name.
fn parse_max_steps(text: &str) -> Result<usize, String> {
    match text.trim().parse::<i128>() {
        Ok(n) if n >= 1 && n <= usize::MAX as i128 => Ok(n as usize),
        _ => Err(format!(
            "expected a step budget, an integer from 1 to {}, found {text}; omit --max-steps for the run's own budget",
            usize::MAX
        )),
    }
}

/// The diagnosis's wall time after the run's own, where it is worth saying (half a second or more).
fn diagnosis_time(diagnosed: f64) -> String {
    if diagnosed >= 0.5 {
        format!(", and {diagnosed:.3} s more for its diagnosis, the runs it is compared with")
    } else {
        String::new()
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn magnitudes_print_fixed_between_a_hundredth_and_ten_thousand() {
        for (x, text) in [
            (0.0, "0.000"),
            (21.674, "21.674"),
            (9999.1234, "9999.123"),
            (790840.023, "7.908e5"),
            (2.784e6, "2.784e6"),
            (3.7e-5, "3.700e-5"),
            (-0.5, "-0.500"),
        ] {
            assert_eq!(super::fixed_or_sci(x, 3), text);
        }
    }
}
