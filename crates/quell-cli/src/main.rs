//! `quell`: design, simulate and plot direct adaptive output-feedback controllers.
#![allow(non_snake_case)]
//!
//! Exit codes: 0 success, 1 a run that failed (diverged, solver failure, interrupted),
//! 2 bad input or an infeasible design.

/// `eprint!` and `eprintln!` that drop what a closed or full stderr cannot take: std's panic there
/// (`quell run … 2>&1 | head -1` exited 101 and wrote no output directory). Defined before the
/// modules, so they are the ones every module's `eprint!` names.
macro_rules! eprint {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stderr(), $($arg)*);
    }};
}
/// See [`eprint!`].
macro_rules! eprintln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

mod auto;
mod decimal;
mod export;
mod interrupt;
mod journal;
mod output;
mod pace;
mod plot;
mod report;
mod run;
mod sweep;
mod tune;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use quell::scenario::{Scenario, PAPER_EXAMPLE};
use quell::Design;
use run::RunArgs;

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
    Design(auto::DesignArgs),
    /// Simulate the closed loop; write signals.csv, design.json, summary.json and plots.
    Run(run::RunArgs),
    /// Write the real-time controller as dependency-free C99 (<PREFIX>_controller.h and .c).
    Export(export::ExportArgs),
    /// Run every point of a study's grid and Monte Carlo draws; write runs.csv, summary.json, sweep.png.
    Sweep(sweep::SweepArgs),
    /// Tune μ one channel at a time (the study's [tune]); write the chosen μ and each channel's curve.
    Tune(tune::TuneArgs),
}

/// A failure with its exit code.
pub(crate) enum Failure {
    /// Bad input or an infeasible design: exit 2.
    Input(String),
    /// A run that failed: exit 1.
    Run(String),
}

fn main() -> ExitCode {
    interrupt::ignore_file_size_signal();
    let cli = Cli::parse();
    // Only a flag given is named beside the key its value sets (a file's value had been blamed on
    // the flag).
    let given: Vec<&'static str> = match &cli.command {
        Some(Command::Run(args)) => [
            ("simulation.sample_time", args.sample_time.is_some()),
            ("simulation.t_end", args.t_end.is_some()),
            ("simulation.output_step", args.output_step.is_some()),
            ("simulation.precision", args.precision.is_some()),
        ]
        .into_iter()
        .filter_map(|(key, given)| given.then_some(key))
        .collect(),
        Some(Command::Export(args)) if args.sample_time.is_some() => vec!["simulation.sample_time"],
        _ => vec![],
    };
    let _ = GIVEN_SCENARIO_FLAGS.set(given);
    let result = match cli.command {
        Some(Command::Design(args)) if args.auto => auto::auto(&args),
        Some(Command::Design(args)) => design(&args),
        Some(Command::Run(args)) => run::run(&args),
        Some(Command::Export(args)) => export::run(&args),
        Some(Command::Sweep(args)) => sweep::sweep(&args),
        Some(Command::Tune(args)) => tune::tune(&args),
        None => {
            eprintln!(
                "quell: running the paper's example (Section VIII) into quell-out/; `quell --help` lists the commands"
            );
            run::run(&RunArgs { out: PathBuf::from("quell-out"), ..Default::default() })
        }
    };
    match stdout_failure(result) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Input(msg)) => {
            eprintln!("error: {}", in_flags(msg));
            ExitCode::from(2)
        }
        Err(Failure::Run(msg)) => {
            eprintln!("error: {}", in_flags(msg));
            ExitCode::from(1)
        }
    }
}

/// Library keys that a flag sets, as the CLI names them.
const FLAGS: [(&str, &str); 12] = [
    ("simulation.sample_time", "simulation.sample_time (--sample-time)"),
    ("simulation.precision", "simulation.precision (--precision)"),
    ("simulation.t_end", "simulation.t_end (--t-end)"),
    ("simulation.output_step", "simulation.output_step (--output-step)"),
    ("u_limit", "--u-limit"),
    ("convergence_time", "--convergence-time"),
    ("delay_error", "--delay-error"),
    ("time_scale", "--time-scale"),
    ("prefix", "--prefix"),
    ("precision", "--precision"),
    ("compiler", "--compiler"),
    ("fmi_version", "--fmi-version"),
];

/// The scenario's keys (`simulation.*`) that the command's flags set: only a message on one of
/// them names the flag beside the key. Unset (library tests) counts every flag as given.
static GIVEN_SCENARIO_FLAGS: std::sync::OnceLock<Vec<&'static str>> = std::sync::OnceLock::new();

/// A library message whose leading key a flag of the command sets, with the flag named; an
/// argument named in parentheses within it ("raise the limits (u_limit)") is its flag there too.
pub(crate) fn in_flags(msg: String) -> String {
    let mut msg = msg.replace(quell::scenario::AUTO_DESIGN, "`quell design SCENARIO --auto --write OUT.toml`");
    for (key, flag) in FLAGS.iter().filter(|(_, flag)| flag.starts_with("--")) {
        msg = msg.replace(&format!("({key})"), &format!("({flag})"));
    }
    let given =
        |key: &str| !key.starts_with("simulation.") || GIVEN_SCENARIO_FLAGS.get().is_none_or(|g| g.contains(&key));
    // A given flag's key in the message's prose ("or a shorter simulation.t_end") names it too; not
    // a key that heads a message of its own ("FILE: simulation.sample_time: …" is the file's).
    for (key, flag) in FLAGS.iter().filter(|(key, _)| key.starts_with("simulation.") && given(key)) {
        let pattern = format!(" {key}");
        let mut named = String::with_capacity(msg.len());
        let mut rest = msg.as_str();
        while let Some(at) = rest.find(&pattern) {
            let after = &rest[at + pattern.len()..];
            let prose = !after.starts_with(':') && !after.starts_with(" (");
            named.push_str(&rest[..at]);
            named.push_str(&if prose { format!(" {flag}") } else { pattern.clone() });
            rest = after;
        }
        named.push_str(rest);
        msg = named;
    }
    for (key, flag) in FLAGS.iter().filter(|(key, _)| given(key)) {
        if let Some(rest) = msg.strip_prefix(key).filter(|r| r.starts_with([':', ' '])) {
            return format!("{flag}{rest}");
        }
    }
    // The file's output step or sample time refused against a --t-end: the fix is a flag too.
    let by_t_end = GIVEN_SCENARIO_FLAGS.get().is_some_and(|g| g.contains(&"simulation.t_end"));
    match ["output_step", "sample_time"].iter().find(|k| msg.starts_with(&format!("simulation.{k}:"))) {
        Some(k) if by_t_end => format!("{msg} (the file's {k}, against --t-end: give --{} too)", k.replace('_', "-")),
        _ => msg,
    }
}

pub(crate) fn print_json(value: &serde_json::Value) {
    print_stdout(&format!("{}\n", serde_json::to_string_pretty(value).unwrap_or_default()));
}

/// A real-valued flag's value as Rust reads a float ("0.001", "1e-3", "-inf", "nan"); clap names
/// the flag around the message.
pub(crate) fn parse_real(text: &str) -> Result<f64, String> {
    text.parse::<f64>().map_err(|_| format!("expected a decimal number such as 0.001 or 1e-3, found {text:?}"))
}

/// The scenario at `path` (the paper's example without one) and its design; with `sample_time`
/// (a `--sample-time` > 0) as its `simulation.sample_time`, so that the file is checked as the
/// sampled-data scenario the flag makes of it (white noise needs no bandwidth there).
pub(crate) fn load(path: Option<&Path>, sample_time: Option<f64>) -> Result<(Scenario, Design), Failure> {
    load_with(path, |sim| {
        set_sample_time(sim, sample_time);
    })
}

/// `[simulation]` `sim` with `sample_time` (a `--sample-time` > 0) as its `sample_time`; the value
/// set, if any (a bad one is left to the controller's check).
pub(crate) fn set_sample_time(sim: &mut toml::Table, sample_time: Option<f64>) -> Option<f64> {
    let t = sample_time.filter(|t| t.is_finite() && *t > 0.0)?;
    sim.insert("sample_time".into(), toml::Value::Float(t));
    Some(t)
}

/// A number of `[simulation]` `sim` (an integer read as one): `None` where the key is absent,
/// `Some(None)` where it is not a number (left for the reader to name).
pub(crate) fn sim_number(sim: &toml::Table, key: &str) -> Option<Option<f64>> {
    sim.get(key).map(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
}

/// The sample time of `[simulation]` `sim` where it is a finite number > 0.
pub(crate) fn file_sample_time(sim: &toml::Table) -> Option<f64> {
    sim_number(sim, "sample_time").flatten().filter(|t| t.is_finite() && *t > 0.0)
}

/// [`load`] with `[simulation]` changed by `adjust` first (a table, empty where the file has none).
pub(crate) fn load_with(
    path: Option<&Path>,
    adjust: impl FnOnce(&mut toml::Table),
) -> Result<(Scenario, Design), Failure> {
    let parsed = match path {
        Some(p) => quell::scenario::read_document(p),
        None => quell::scenario::parse_document(PAPER_EXAMPLE),
    };
    // The file's own [simulation] values first where a flag overrides some: it must not hide a bad
    // one (a study's are its own, and the reading below says what to run it with).
    let overridden: Vec<&str> =
        GIVEN_SCENARIO_FLAGS.get().into_iter().flatten().filter_map(|k| k.strip_prefix("simulation.")).collect();
    if let (Some(p), Ok(doc), false) = (path, &parsed, overridden.is_empty()) {
        if !doc.contains_key("scenario") {
            quell::scenario::check_simulation(doc, &overridden).map_err(|e| {
                Failure::Input(format!(
                    "{}: {e} (the file's value must be valid even where a flag overrides it)",
                    p.display()
                ))
            })?;
        }
    }
    let scenario = parsed
        .and_then(|mut doc| {
            if let Some(sim) = doc.entry("simulation").or_insert(toml::Table::new().into()).as_table_mut() {
                adjust(sim);
            }
            Scenario::from_document(&doc)
        })
        .map_err(|e| match path {
            Some(p) if e.is_a_study() => {
                // A study with [tune] is tuned, not swept.
                let tuned = quell::scenario::read_document(p).is_ok_and(|doc| doc.contains_key("tune"));
                let command = if tuned { "tune" } else { "sweep" };
                Failure::Input(format!(
                    "{e}\n{} is a study, not a scenario: run it with `quell {command} {} --out DIR`",
                    p.display(),
                    p.display()
                ))
            }
            _ => Failure::Input(e.to_string()),
        })?;
    let design = scenario.design().map_err(|e| Failure::Input(e.to_string()))?;
    Ok((scenario, design))
}

fn design(args: &auto::DesignArgs) -> Result<(), Failure> {
    if let Some(flag) = args.auto_only_flag() {
        return Err(Failure::Input(format!(
            "{flag}: only with --auto (the automatic design); add --auto or remove {flag}"
        )));
    }
    interrupt::Interrupt::quit_with("interrupted during the design; nothing was printed");
    let (s, d) = load(Some(&args.scenario), None)?;
    // The scenario's run must be able to start (its sample time against the delays, its signals
    // against t_end), or `quell run` and `quell export` would refuse what the design accepted.
    quell::sim::Run::of(&s, &d).check().map_err(|e| Failure::Input(e.to_string()))?;
    if args.json {
        print_json(&pace::design_json(&s, &d));
    } else {
        print_stdout(&pace::design_text(&s, &d));
    }
    Ok(())
}

/// Why writing to stdout failed, other than a closed pipe: the command then exits 1.
static STDOUT_FAILED: std::sync::OnceLock<String> = std::sync::OnceLock::new();

/// Writes to stdout; a closed pipe (`quell design … | head`) ends the output quietly, any other
/// failure (a full disk under `> design.json`) makes the command exit 1 ([`stdout_failure`]).
pub(crate) fn print_stdout(text: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        if e.kind() != std::io::ErrorKind::BrokenPipe {
            let _ = STDOUT_FAILED.set(e.to_string());
        }
    }
}

/// A command that succeeded but whose printed report was cut short, as a failure.
fn stdout_failure(result: Result<(), Failure>) -> Result<(), Failure> {
    match (result, STDOUT_FAILED.get()) {
        (Ok(()), Some(e)) => Err(Failure::Run(format!(
            "cannot write to standard output ({e}): what it printed is incomplete (the files it wrote are whole)"
        ))),
        (result, _) => result,
    }
}

/// A progress bar of `len` steps drawn on stderr with `template` when stderr is a terminal, hidden
/// otherwise.
pub(crate) fn progress_bar(len: u64, template: &str) -> indicatif::ProgressBar {
    use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
    use std::io::IsTerminal;
    let bar = ProgressBar::new(len);
    if std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::stderr());
        if let Ok(style) = ProgressStyle::with_template(template) {
            bar.set_style(style);
        }
    } else {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar
}
