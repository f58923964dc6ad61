//! `quell`: design, simulate and plot direct adaptive output-feedback controllers.
#![allow(non_snake_case)]
//!
//! Exit codes: 0 success, 1 a run that failed (diverged, solver failure, interrupted),
//! 2 bad input or an infeasible design.

mod export;
mod output;
mod plot;
mod report;
mod sweep;
mod tune;

use std::io::IsTerminal;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use quell::scenario::{Scenario, PAPER_EXAMPLE};
use quell::sim::{
    simulate_sampled_with_truth, simulate_with_truth, Outcome, RunSettings, RunStats, SampledSettings, SimResult,
};
use quell::Design;
use serde_json::json;

#[derive(Parser)]
#[command(
    name = "quell",
    version,
    about = "Direct adaptive output-feedback control of MIMO plants with distinct input delays"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Compute every gain from a scenario file and check the paper's assumptions.
    Design {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Simulate the closed loop; write signals.csv, design.json, summary.json and plots.
    Run(RunArgs),
    /// Write the real-time controller as dependency-free C99 (<PREFIX>_controller.h and .c).
    Export(export::ExportArgs),
    /// Run every point of a study's grid and Monte Carlo draws; write runs.csv, summary.json, sweep.png.
    Sweep(sweep::SweepArgs),
    /// Tune μ one channel at a time (the study's [tune]); write the chosen μ and each channel's curve.
    Tune(tune::TuneArgs),
}

#[derive(clap::Args, Default)]
struct RunArgs {
    /// Scenario file (TOML); the paper's example (Section VIII) when omitted.
    scenario: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "quell-out")]
    out: PathBuf,
    /// Sampled-data run with the discrete controller at this sample time (s); overrides
    /// simulation.sample_time.
    #[arg(long, value_name = "T_S", allow_negative_numbers = true)]
    sample_time: Option<f64>,
    /// Skip the PNG/SVG plots.
    #[arg(long)]
    no_plots: bool,
}

/// Phases of a run, for the Ctrl-C handler.
const RUNNING: u8 = 0;
const INTERRUPTED: u8 = 1;
const QUITTING: u8 = 2;
const WRITING: u8 = 3;

/// A failure with its exit code.
pub(crate) enum Failure {
    /// Bad input or an infeasible design: exit 2.
    Input(String),
    /// A run that failed: exit 1.
    Run(String),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Design { scenario, json }) => design(&scenario, json),
        Some(Command::Run(args)) => run(&args),
        Some(Command::Export(args)) => export::run(&args),
        Some(Command::Sweep(args)) => sweep::sweep(&args),
        Some(Command::Tune(args)) => tune::tune(&args),
        None => {
            eprintln!(
                "quell: running the paper's example (Section VIII) into quell-out/; `quell --help` lists the commands"
            );
            run(&RunArgs { out: PathBuf::from("quell-out"), ..Default::default() })
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Input(msg)) => {
            eprintln!("error: {msg}");
            ExitCode::from(2)
        }
        Err(Failure::Run(msg)) => {
            eprintln!("error: {msg}");
            ExitCode::from(1)
        }
    }
}

fn load(path: Option<&Path>) -> Result<(Scenario, Design), Failure> {
    let scenario = match path {
        Some(p) => Scenario::from_path(p),
        None => Scenario::from_toml(PAPER_EXAMPLE),
    }
    .map_err(|e| Failure::Input(e.to_string()))?;
    let design = scenario.design().map_err(|e| Failure::Input(e.to_string()))?;
    Ok((scenario, design))
}

fn design(path: &Path, as_json: bool) -> Result<(), Failure> {
    let (_, d) = load(Some(path))?;
    if as_json {
        print_stdout(&format!("{}\n", serde_json::to_string_pretty(&report::design_json(&d)).unwrap_or_default()));
    } else {
        print_stdout(&report::design_text(&d));
    }
    Ok(())
}

/// Writes to stdout; a closed pipe (`quell design … | head`) ends the output quietly.
fn print_stdout(text: &str) {
    use std::io::Write;
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

fn run(args: &RunArgs) -> Result<(), Failure> {
    let (scenario, design) = load(args.scenario.as_deref())?;
    let sim = &scenario.simulation;
    let sample_time = match args.sample_time {
        Some(t) if !(t.is_finite() && t > 0.0) => {
            return Err(Failure::Input(format!("--sample-time: expected a sample time > 0 in seconds, found {t}")))
        }
        Some(t) => Some(t),
        None => sim.sample_time,
    };
    // Every check that can fail on input happens before the output directory is touched.
    let sampled = match sample_time {
        None => None,
        Some(sample_time) => {
            let settings = SampledSettings {
                noise: scenario.noise.clone(),
                ..SampledSettings::new(sim.t_end, sim.output_step, sample_time)
            };
            settings
                .check(&design, &scenario.reference, &scenario.disturbance)
                .map_err(|e| Failure::Input(e.to_string()))?;
            Some(settings)
        }
    };
    let out = &args.out;
    output::prepare_dir(out).map_err(|e| {
        Failure::Input(format!("--out {}: cannot write there ({e}); choose a writable directory", out.display()))
    })?;

    // Ctrl-C: the first stops the run at its next recorded sample, and the files are written. A
    // second one before that sample (a very stiff run can take long to reach it) quits at once,
    // with no files; once writing has begun, further Ctrl-Cs are ignored so no file is cut short.
    let phase = Arc::new(AtomicU8::new(RUNNING));
    {
        let phase = phase.clone();
        let _ = ctrlc::set_handler(move || {
            if phase.compare_exchange(RUNNING, INTERRUPTED, Ordering::SeqCst, Ordering::SeqCst).is_err()
                && phase.compare_exchange(INTERRUPTED, QUITTING, Ordering::SeqCst, Ordering::SeqCst).is_ok()
            {
                eprintln!("error: interrupted twice before the next sample; stopped without writing files");
                std::process::exit(1);
            }
        });
    }
    let bar = progress_bar(sim.t_end);
    let progress = |t: f64| {
        bar.set_position((t * 1000.0) as u64);
        if phase.load(Ordering::SeqCst) != RUNNING {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    };
    let started = std::time::Instant::now();
    let result = match &sampled {
        None => {
            let settings = RunSettings::new(sim.t_end, sim.output_step, sim.rtol, sim.atol);
            simulate_with_truth(
                &design,
                scenario.true_plant(),
                &scenario.reference,
                &scenario.disturbance,
                &settings,
                progress,
            )
        }
        Some(settings) => simulate_sampled_with_truth(
            &design,
            scenario.true_plant(),
            &scenario.reference,
            &scenario.disturbance,
            settings,
            progress,
        ),
    }
    .map_err(|e| Failure::Input(e.to_string()))?;
    bar.finish_and_clear();
    // From here on Ctrl-C is ignored (unless a second one is already quitting the process).
    if phase.swap(WRITING, Ordering::SeqCst) == QUITTING {
        loop {
            std::thread::park();
        }
    }
    let elapsed = started.elapsed();

    write_outputs(out, &scenario, &design, &result, elapsed.as_secs_f64(), !args.no_plots)
        .map_err(|e| Failure::Run(format!("writing {}: {e}", out.display())))?;
    match result.outcome.as_ref().unwrap_or(&Outcome::Completed) {
        Outcome::Completed => {
            for (i, c) in result.summary().iter().enumerate() {
                eprintln!("channel {}: tail max|e| = {:.3e}, tail RMS e = {:.3e}, max|u| = {:.3}, ‖η̂‖ = {:.4}", i + 1, c.tail_max_abs_e, c.tail_rms_e, c.max_abs_u, c.final_eta_norm);
            }
            let steps = match result.stats {
                RunStats::Continuous { steps, .. } => format!("{steps} solver steps"),
                RunStats::Sampled { controller_steps, .. } => format!("{controller_steps} controller steps"),
            };
            eprintln!("wrote {} ({} samples, {steps}, {:.3} s)", out.display(), result.len(), elapsed.as_secs_f64());
            Ok(())
        }
        Outcome::Diverged { t, signal, value } => Err(Failure::Run(format!(
            "the closed loop diverged at t = {t:.4}: {signal} = {value:e}; results up to then are in {}",
            out.display()
        ))),
        Outcome::StepSizeTooSmall { t } => Err(Failure::Run(format!(
            "the solver's step size underflowed at t = {t:.6} (the loop is too stiff or blows up there, simulation.rtol/atol are tighter than floating point allows, or an input delay is shorter than a step can be); results up to then are in {}",
            out.display()
        ))),
        Outcome::Interrupted { t } => Err(Failure::Run(format!("interrupted at t = {t:.3}; results up to then are in {}", out.display()))),
        Outcome::TooManySteps { t, max_steps } => Err(Failure::Run(format!("the solver needed more than {max_steps} steps by t = {t:.6}; results up to then are in {}", out.display()))),
    }
}

fn progress_bar(t_end: f64) -> ProgressBar {
    let bar = ProgressBar::new((t_end * 1000.0) as u64);
    if std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::stderr());
        if let Ok(style) = ProgressStyle::with_template(
            "simulating {bar:40} {percent:>3}% of t_end, {elapsed_precise} elapsed, ETA {eta}",
        ) {
            bar.set_style(style);
        }
    } else {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar
}

fn write_outputs(
    dir: &Path,
    scenario: &Scenario,
    design: &Design,
    r: &SimResult,
    seconds: f64,
    plots: bool,
) -> std::io::Result<()> {
    // Figures render on their own threads (one per channel) while the data files are written.
    std::thread::scope(|scope| {
        let figures: Vec<_> =
            (0..if plots { r.m } else { 0 }).map(|i| scope.spawn(move || plot::plot_channel(dir, r, i))).collect();
        let data = write_data(dir, scenario, design, r, seconds);
        for figure in figures {
            figure.join().map_err(|_| std::io::Error::other("plotting panicked"))??;
        }
        data
    })
}

fn write_data(dir: &Path, scenario: &Scenario, design: &Design, r: &SimResult, seconds: f64) -> std::io::Result<()> {
    output::write_signals(&dir.join("signals.csv"), r)?;
    output::write_json(&dir.join("design.json"), &report::design_json(design))?;
    let summary = json!({
        "scenario": scenario.name,
        "truth_differs": scenario.truth_differs(),
        "outcome": r.outcome,
        "channels": r.summary(),
        "stats": r.stats,
        "samples": r.len(),
        "wall_time_s": seconds,
    });
    output::write_json(&dir.join("summary.json"), &summary)
}
