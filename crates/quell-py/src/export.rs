//! `quell.export`: the C controller and its FMU, as `quell export` writes them (`quell::export`).

use std::borrow::Cow;
use std::path::PathBuf;

use pyo3::prelude::*;
use quell::controller::Precision;
use quell::export::{generate, generate_fmu, ExportError, ExportOptions, FmiVersion};

use crate::convert::{a_type, number};
use crate::design::PyDesign;
use crate::errors::{in_python, Kind};
use crate::scenario::PyScenario;

/// The library's message, its key named as this function's argument.
fn message(e: &ExportError) -> String {
    in_python(e.to_string())
}

/// The FMI version an int names; `Err(None)` for another type (a bool is not an int here).
fn fmi_version_of(v: &Bound<'_, PyAny>) -> Result<FmiVersion, Option<ExportError>> {
    if v.is_instance_of::<pyo3::types::PyBool>() {
        return Err(None);
    }
    let n: i64 = v.extract().map_err(|_| None)?;
    n.to_string().parse().map_err(Some)
}

/// With `fmu`, the FMU's version and its compiler (`None`: sources only; default `$CC`, else `cc`).
/// Without it, `fmi_version` and `compiler` are refused (after their types are checked), as the CLI
/// refuses `--fmi-version` and `--compiler` without `--fmu`: an FMU option alone writes no FMU.
fn fmu_arguments(
    py: Python<'_>,
    fmu: bool,
    fmi_version: Option<&Bound<'_, PyAny>>,
    compiler: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<(FmiVersion, Option<String>)>> {
    let fmi_version = fmi_version.filter(|v| !v.is_none());
    let version = match fmi_version {
        None => FmiVersion::default(),
        Some(v) => fmi_version_of(v).map_err(|e| match e {
            // An int beyond i64 is an int still: a wrong value, not a wrong type.
            None if crate::convert::as_int(v).is_some() => Kind::Export.err(
                py,
                format!(
                    "fmi_version: expected 2 or 3, found an integer of {} digits",
                    crate::convert::decimal_digits(v)
                ),
            ),
            None => crate::errors::type_error("fmi_version", "2 or 3 (an int)", v),
            Some(e) => Kind::Export.err(py, message(&e)),
        })?,
    };
    let compiler = compiler.filter(|c| !c.is_none()).map(|c| crate::convert::text(c, "compiler")).transpose()?;
    if !fmu {
        let stray = [("fmi_version", fmi_version.is_some()), ("compiler", compiler.is_some())];
        return match stray.iter().find(|(_, given)| *given) {
            Some((name, _)) => Err(Kind::Export
                .err(py, format!("{name}: applies to the FMU only; pass fmu=True as well, or leave {name} out"))),
            None => Ok(None),
        };
    }
    Ok(Some((version, quell::export::compiler_choice(compiler).0)))
}

/// Writes the real-time controller of a design as C99 (`<prefix>_controller.h` and `.c`), and
/// optionally as an FMI 2.0 or 3.0 co-simulation FMU, like `quell export`; files are written to a
/// temporary name, then renamed.
///
/// Parameters
/// ----------
/// source : Scenario or Design
///     What to export (a scenario gives its design, name and sample time).
/// sample_time : float, optional
///     T_s, in the plant's unit of time; default the scenario's.
/// out : str or os.PathLike, optional
///     The directory (created; default the working directory).
/// prefix : str, optional
///     The C identifiers' prefix (default "quell").
/// precision : str, optional
///     "f64" or "f32"; default: a scenario's simulation.precision, else "f64".
/// fmu : bool, optional
///     Also write `<prefix>.fmu`.
/// fmi_version : int, optional
///     The FMU's FMI version: 2 (default, FMI 2.0) or 3 (FMI 3.0).
/// compiler : str, optional
///     The C compiler for the FMU's binary (default $CC or cc; "none": sources only).
/// check : bool, optional
///     Measure a scenario's loop first (default True): sampled at `sample_time` against its
///     continuous loop, and in f32 against f64, a warning where it departs.
///
/// Returns
/// -------
/// list of pathlib.Path
///     The files written.
///
/// Raises
/// ------
/// TypeError
///     An argument of the wrong type.
/// ScenarioError
///     A sample time that is missing, not > 0 or does not divide the delays.
/// ExportError
///     A prefix, precision, FMI version or compiler that is not valid, or `fmi_version` or
///     `compiler` without `fmu=True`.
/// OSError
///     The directory cannot be written.
///
/// Examples
/// --------
/// >>> paths = quell.export(quell.paper_example().design(), 1e-3, out="c", prefix="loop")
/// >>> [p.name for p in paths]
/// ['loop_controller.h', 'loop_controller.c']
/// >>> paths = quell.export(quell.paper_example(), 1e-3, out="fmu3", fmu=True, fmi_version=3, compiler="none")
/// >>> [p.name for p in paths]
/// ['quell_controller.h', 'quell_controller.c', 'quell.fmu']
#[pyfunction]
#[pyo3(
    signature = (source, sample_time=None, *, out=None, prefix=Cow::Borrowed("quell"), precision=None, fmu=false, fmi_version=None, compiler=None, check=true),
    text_signature = "(source, sample_time=None, *, out=None, prefix='quell', precision=None, fmu=False, fmi_version=2, compiler=None, check=True)"
)]
#[allow(clippy::too_many_arguments)]
pub fn export(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    sample_time: Option<&Bound<'_, PyAny>>,
    out: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = crate::convert::argument::prefix)] prefix: Cow<'static, str>,
    precision: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = crate::convert::argument::fmu)] fmu: bool,
    fmi_version: Option<&Bound<'_, PyAny>>,
    compiler: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = crate::convert::argument::check)] check: bool,
) -> PyResult<Vec<PathBuf>> {
    // A scenario's sample time and precision (`simulation.precision`, its runs') are the defaults.
    let (design, (scenario_name, names), (scenario_T, scenario_precision), signals, scenario) =
        if let Ok(s) = source.cast::<PyScenario>() {
            let s = s.get();
            let signals = (s.inner.reference.clone(), s.inner.disturbance.clone());
            let labels = (s.inner.name.clone(), s.inner.names.clone());
            let sim = &s.inner.simulation;
            (s.design_arc(py)?, labels, (sim.sample_time, sim.precision), signals, Some(s.inner.clone()))
        } else if let Ok(d) = source.cast::<PyDesign>() {
            (d.get().inner.clone(), Default::default(), (None, Default::default()), Default::default(), None)
        } else {
            return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                "source: expected a quell.Scenario or quell.Design, found {}",
                a_type(source)
            )));
        };
    let T = match sample_time {
        Some(v) => number(v, "sample_time", Kind::Scenario, "simulation.sample_time")?,
        None => scenario_T.ok_or_else(|| {
            Kind::Scenario.err(py, "sample_time: missing; pass the controller's sample time T_s, in the plant model's unit of time (or set simulation.sample_time in the scenario)")
        })?,
    };
    let precision = match precision {
        None => scenario_precision,
        Some(p) => p
            .extract::<String>()
            .map_err(|_| {
                pyo3::exceptions::PyTypeError::new_err(format!(
                    "precision: expected \"f64\" or \"f32\", found {}",
                    a_type(p)
                ))
            })?
            .parse()
            .map_err(|e: ExportError| Kind::Export.err(py, message(&e)))?,
    };
    let fmu = fmu_arguments(py, fmu, fmi_version, compiler)?;
    let options = ExportOptions { prefix: prefix.into_owned(), precision, scenario_name, names };
    let raise = |e: ExportError| match e {
        ExportError::Controller(c) => crate::errors::keyed(py, Kind::Scenario, c.to_string(), c.key()),
        ExportError::NotFinite { .. } => Kind::Scenario.err(py, message(&e)),
        _ => Kind::Export.err(py, message(&e)),
    };
    let out = out.filter(|o| !o.is_none()).map(|o| crate::convert::path(o, "out")).transpose()?;
    // Ctrl-C stops the compiler with what it started and raises KeyboardInterrupt.
    let (code, archive) = crate::interrupt::interruptible(py, || -> Result<_, ExportError> {
        let code = generate(&design, T, &options)?;
        let archive = fmu.as_ref().map(|(v, cc)| generate_fmu(&design, T, &options, cc.as_deref(), *v)).transpose()?;
        Ok((code, archive))
    })?
    .map_err(raise)?;
    crate::errors::warn_coarse_sample(py, &design, &signals.0, &signals.1, T, None)?;
    let unit = archive.as_ref().and_then(|a| quell::export::time_unit_warning(&design, T, a.version));
    for w in code.warnings().chain(unit) {
        crate::errors::warn(py, &w)?;
    }
    scenario.filter(|_| check).map_or(Ok(()), |s| warn_loop_check(py, &s, &design, (T, precision)))?;
    let out = out.unwrap_or_else(|| PathBuf::from("."));
    let mut files = vec![(code.header_name, code.header.into_bytes()), (code.source_name, code.source.into_bytes())];
    files.extend(archive.map(|a| (a.file_name, a.bytes)));
    let written = write(py, &out, &files)?;
    if let Some(w) =
        fmu.is_none().then(|| quell::export::earlier_fmu_warning(&out, &options.prefix, "pass fmu=True")).flatten()
    {
        crate::errors::warn(py, &format!("out: {w}"))?;
    }
    Ok(written)
}

/// An export of a scenario: its loop at T_s, against its continuous loop and, in f32, against
/// f64, as `quell export` measures it ([`quell::diagnostics::export_check`]), warned of where it
/// departs or cannot be measured.
fn warn_loop_check(
    py: Python<'_>,
    s: &quell::Scenario,
    design: &quell::Design,
    (T, precision): (f64, Precision),
) -> PyResult<()> {
    match crate::interrupt::interruptible(py, || quell::diagnostics::export_check(s, design, (T, precision)))? {
        Ok(c) => {
            let cut = if c.cut { " (over its first 1e6 controller steps)" } else { "" };
            for (line, _) in c.lines.iter().filter(|(_, warns)| *warns) {
                crate::errors::warn(py, &format!("{line}{cut}"))?;
            }
            Ok(())
        }
        Err(why) => crate::errors::warn(py, &format!("the exported loop could not be measured ({why}): measure it with quell.simulate(scenario, sample_time=…), t_end a few hundred samples or more, before deploying it")),
    }
}

/// Writes `files` (name, bytes) into `out`, created if need be, all renamed into place once every
/// one is written, as `quell export` does: a failed write leaves the old files together, never a
/// new header beside an old source. Returns their paths.
fn write(py: Python<'_>, out: &std::path::Path, files: &[(String, Vec<u8>)]) -> PyResult<Vec<PathBuf>> {
    quell::files::check_dir(out).and_then(|()| std::fs::create_dir_all(out)).map_err(|e| {
        Kind::Export.err(py, format!("out: cannot create {} ({e}); choose a writable directory", out.display()))
    })?;
    let files: Vec<(PathBuf, &[u8])> = files.iter().map(|(name, bytes)| (out.join(name), bytes.as_slice())).collect();
    // Held until the files are in place: another export into `out` meanwhile is refused.
    let _lock = quell::files::lock_dir(out).map_err(|e| Kind::Export.err(py, format!("out: {e}")))?;
    quell::files::write_atomic_all(&files)
        .map_err(|e| pyo3::exceptions::PyOSError::new_err(format!("out: writing in {} failed ({e})", out.display())))?;
    Ok(files.into_iter().map(|(path, _)| path).collect())
}
