//! `quell export`: the real-time controller as dependency-free C99 (`quell::export`).

use std::path::{Path, PathBuf};

use quell::controller::Precision;
use quell::diagnostics::ExportCheck;
use quell::export::{generate, generate_fmu, CCode, ExportError, ExportOptions, FmiVersion, Fmu};

use crate::{file_sample_time, load_with, output, set_sample_time, sim_number, Failure};

#[derive(clap::Args)]
pub struct ExportArgs {
    /// Scenario file (TOML).
    scenario: PathBuf,
    /// Sample time T_s, in the plant model's unit of time; every input delay must be a whole number of samples.
    /// Defaults to the scenario's simulation.sample_time.
    #[arg(long, value_name = "T_S", allow_hyphen_values = true, value_parser = crate::parse_real)]
    pub(crate) sample_time: Option<f64>,
    /// Output directory for <PREFIX>_controller.h and <PREFIX>_controller.c.
    #[arg(long, default_value = ".")]
    out: PathBuf,
    /// Prefix of every generated name, so several controllers can share one firmware.
    #[arg(long, default_value = "quell")]
    prefix: String,
    /// Floating-point type of the generated code: f64 (double) or f32 (float, for single-precision
    /// FPUs); default: the scenario's simulation.precision, else f64.
    #[arg(long, value_parser = ["f64", "f32"])]
    precision: Option<String>,
    /// Also write <PREFIX>.fmu: an FMI co-simulation FMU of the same C (inputs y, g; outputs u_f,
    /// u), with its sources and a binary for this machine built by --compiler.
    #[arg(long)]
    fmu: bool,
    /// The FMU's FMI version: 2 (FMI 2.0) or 3 (FMI 3.0).
    #[arg(long, value_name = "VERSION", default_value = "2", value_parser = ["2", "3"], requires = "fmu")]
    fmi_version: String,
    /// C compiler for the FMU's binary (gcc's flags); defaults to $CC, else cc. "none" writes a
    /// source-only FMU.
    #[arg(long, value_name = "COMPILER", requires = "fmu")]
    compiler: Option<String>,
    /// Skip the check of the exported loop (the scenario sampled at T_s against its continuous
    /// loop, and in f32 against f64), which runs up to 1e6 controller steps before writing.
    #[arg(long)]
    no_loop_check: bool,
}

/// Generates, then writes the header, the source and, with `--fmu`, the FMU (each to a temporary
/// name, all renamed once every one is written).
pub fn run(args: &ExportArgs) -> Result<(), Failure> {
    // The sample time is the controller's, not a run's: export runs nothing, so the horizon is
    // capped where a run's step budget would refuse the sample time, and raised to one sample where
    // a run would end before its first step (T_s = 1000 s had been refused by the 100 s of t_end).
    let (scenario, design) = load_with(Some(&args.scenario), |sim| {
        // The flag's sample time, or the file's.
        let from_file = file_sample_time(sim);
        if let Some(t) = set_sample_time(sim, args.sample_time).or(from_file) {
            let t_end = sim_number(sim, "t_end").unwrap_or(Some(quell::scenario::Simulation::default().t_end));
            // A t_end that is not a number stays, for the reader to name; the output step stays within it.
            let cap = t * quell::settings::MAX_SAMPLING_STEPS;
            if let Some(horizon) = t_end.filter(|t_end| *t_end > cap || *t_end < t).map(|t_end| t_end.clamp(t, cap)) {
                sim.insert("t_end".into(), toml::Value::Float(horizon));
                sim.insert("output_step".into(), toml::Value::Float(horizon));
            }
        }
    })?;
    let sample_time = args.sample_time.or(scenario.simulation.sample_time).ok_or_else(|| {
        Failure::Input(
            "--sample-time: missing; the controller runs at a sample time T_s, in the plant model's unit of time (or set simulation.sample_time in the scenario)".into(),
        )
    })?;
    let options = ExportOptions {
        prefix: args.prefix.clone(),
        // The file's simulation.precision, which its sampled runs measured, unless the flag says.
        precision: match &args.precision {
            Some(name) => name.parse().map_err(export_failure)?,
            None => scenario.simulation.precision,
        },
        scenario_name: scenario.name.clone(),
        names: scenario.names.clone(),
    };
    let code = generate(&design, sample_time, &options).map_err(export_failure)?;
    eprint!("{}", crate::report::sample_time_text(&scenario, &design, sample_time, None));
    let check = (!args.no_loop_check).then(|| loop_check(&scenario, &design, (sample_time, options.precision)));
    let mut ctrl_c = None;
    let fmu = if args.fmu {
        let (compiler, from_env) = quell::export::compiler_choice(args.compiler.clone());
        let version: FmiVersion = args.fmi_version.parse().map_err(export_failure)?;
        // A signal stops the compiler with what it started, and its temporary directory goes.
        let c = crate::interrupt::Interrupt::install("interrupted twice; stopped without writing");
        let fmu = quell::cancel::with_stop(c.shared_flag(), || {
            generate_fmu(&design, sample_time, &options, compiler.as_deref(), version)
        });
        ctrl_c = Some(c);
        Some(fmu.map_err(|e| failure_naming(e, from_env))?)
    } else {
        None
    };
    if ctrl_c.as_ref().is_some_and(|c| c.interrupted()) {
        return Err(Failure::Run("interrupted; nothing was written".into()));
    }
    // From here a signal waits for the files (a second one quits without writing).
    if let Some(c) = &ctrl_c {
        c.start_writing();
    }
    let out = &args.out;
    let earlier = write((out, &args.scenario), &code, fmu.as_ref(), &options.prefix)?;
    eprintln!(
        "wrote {} and {} in {} (T_s = {sample_time} {}, {}; {} bytes of constants, {} bytes of state)",
        code.header_name,
        code.source_name,
        out.display(),
        scenario.plant.time_unit,
        options.precision.c_type(),
        code.constant_bytes,
        code.state_bytes
    );
    let unit = fmu.as_ref().and_then(|f| quell::export::time_unit_warning(&design, sample_time, f.version));
    let precision = code.precision_warning.clone().filter(|_| !matches!(&check, Some(Ok(c)) if c.precision_measured));
    print_warnings(
        code.size_warning().into_iter().chain(precision).chain(unit).chain(earlier),
        args.precision.is_none(),
    );
    let diverged = check.as_ref().and_then(|c| c.as_ref().ok()).and_then(|c| c.diverged);
    if let Some(check) = check {
        print_check(check, scenario.plant.time_unit);
    }
    diverged.map_or(Ok(()), |t| Err(diverged_failure(t, scenario.plant.time_unit)))
}

/// The export's failure where its loop check's sampled loop diverged at `t`: written (nothing
/// lost), but a loop that diverges is a failed check, not a warning to skim (a build that trusts the
/// exit code had shipped one; helper tryout, 2026-12-07).
fn diverged_failure(t: f64, unit: quell::TimeUnit) -> Failure {
    Failure::Run(format!(
        "the exported controller's loop diverged at t = {} {unit} (above): the files are written, but do not deploy them; choose a shorter --sample-time or slower poles (quell run SCENARIO --sample-time T_S shows the run), or pass --no-loop-check to export without measuring",
        quell::settings::fmt_instant(t)
    ))
}

/// The export's warnings, in the flags' terms (`from_file`: the file's simulation.precision, not
/// the flag, chose the precision). The κ₂ estimate of f32's pole shift is among them only where
/// the loop check did not measure f32 against f64 in the loop itself (a hydraulic actuator had
/// been warned of poles moving 1.3e5× of themselves where the check measured y within 1.7e-4 of
/// f64's; helper tryout, 2026-12-07).
fn print_warnings(warnings: impl Iterator<Item = String>, from_file: bool) {
    for w in warnings {
        let w = crate::in_flags(w);
        let w = if from_file { w.replacen("--precision:", "simulation.precision:", 1) } else { w };
        eprintln!("⚠ warning: {w}");
    }
}

/// The loop check's lines ([`loop_check`]): warnings where the loop departs or could not be measured.
fn print_check(check: Result<ExportCheck, String>, unit: quell::TimeUnit) {
    match check {
        Ok(c) => {
            let cut = if c.cut { " (cut at 1e6 controller steps)" } else { "" };
            let over = format!("over {} {unit}{cut}", quell::settings::fmt_time(c.horizon));
            if c.follows {
                eprintln!("{over}: the sampled-data loop stays within its continuous loop's departure bounds (y within half its peak, u_f's peak within twice; a sampled run's advice gives the figures)");
            }
            for (line, warns) in c.lines {
                eprintln!("{}{over}: {line}", if warns { "⚠ warning: " } else { "" });
            }
        }
        Err(why) => eprintln!(
            "⚠ warning: the exported loop could not be measured ({why}): measure it with a sampled run of the scenario (quell run SCENARIO --sample-time T_S, at a T_s the scenario accepts, over a few hundred samples or more) before deploying it"
        ),
    }
}

/// The exported controller's loop, measured: the scenario sampled at T_s in the export's precision
/// against its continuous loop, and in f32 against f64 ([`quell::diagnostics::export_check`]).
fn loop_check(
    scenario: &quell::Scenario,
    design: &quell::Design,
    (sample_time, precision): (f64, Precision),
) -> Result<ExportCheck, String> {
    let against = match precision {
        Precision::F32 => "in float against the same run in double, which is held to its continuous loop",
        Precision::F64 => "against its continuous loop",
    };
    let steps = (scenario.simulation.t_end / sample_time).floor().min(quell::diagnostics::EXPORT_CHECK_SAMPLES);
    eprintln!(
        "measuring the exported loop (--no-loop-check skips it): the scenario sampled at T_s = {} {} {against}, {steps:.0} controller steps …",
        quell::settings::fmt_time(sample_time),
        scenario.plant.time_unit,
    );
    quell::diagnostics::export_check(scenario, design, (sample_time, precision))
}

/// Writes the header, the source and the FMU (when there is one) into `out` (not over the `input`
/// scenario), all renamed into place
/// once every one is written: a failed write never leaves a new header beside an old source (a
/// mismatched pair would not compile anyway: LAYOUT_ID), nor an FMU of another sample time beside
/// them. Returns the warning on an earlier export's FMU of `prefix` that the C alone left as it was.
fn write(
    (out, input): (&Path, &Path),
    code: &CCode,
    fmu: Option<&Fmu>,
    prefix: &str,
) -> Result<Option<String>, Failure> {
    let mut names = vec![code.header_name.as_str(), code.source_name.as_str()];
    names.extend(fmu.map(|f| f.file_name.as_str()));
    output::not_the_input(input, out, &names)?;
    output::prepare_out(out, &names)?;
    let mut files = vec![
        (out.join(&code.header_name), code.header.as_bytes()),
        (out.join(&code.source_name), code.source.as_bytes()),
    ];
    files.extend(fmu.map(|f| (out.join(&f.file_name), f.bytes.as_slice())));
    output::write_atomic_all(&files).map_err(|e| {
        let what = format!("writing {} in {}: {e}", names.join(", "), out.display());
        output::write_failure(what, &e)
    })?;
    Ok(match fmu {
        Some(fmu) => {
            let binary = fmu.platform.map(|p| format!("binary for {p}")).unwrap_or_else(|| "sources only".into());
            eprintln!(
                "wrote {} in {} (FMI {} co-simulation, {binary})",
                fmu.file_name,
                out.display(),
                fmu.version.name()
            );
            None
        }
        None => quell::export::earlier_fmu_warning(out, prefix, "add --fmu"),
    })
}

/// An export error as the CLI reports it: a compiler that runs and fails or an archive that cannot
/// be built is a failed run (1), the rest bad input (2), a compiler that cannot be started included.
fn export_failure(e: ExportError) -> Failure {
    failure_naming(e, false)
}

/// [`export_failure`], the compiler named `$CC` where it came from there.
fn failure_naming(e: ExportError, from_env: bool) -> Failure {
    let message = quell::export::compiler_message(&e, from_env);
    match e {
        ExportError::Compiler { .. } | ExportError::Archive { .. } | ExportError::Interrupted => Failure::Run(message),
        _ => Failure::Input(message),
    }
}
