//! `quell.tune`: `quell tune` from Python — per-channel searches over μ_i on a Scenario
//! (`quell::study::tune`), with the GIL released and Ctrl-C keeping the points evaluated so far.

use pyo3::prelude::*;
use pyo3::types::PyBool;
use quell::study::{self, TuneOptions};
use toml::{Table, Value};

use crate::errors::type_error;
use crate::scenario::toml_value;
use crate::study::{argument_error, jobs_arg, study_document, thread_pool};

/// `points=` or `refine=`: an int (the library checks its range), or None.
fn count(obj: Option<&Bound<'_, PyAny>>, name: &str) -> PyResult<Option<Value>> {
    match obj.filter(|v| !v.is_none()) {
        None => Ok(None),
        Some(v) => match crate::convert::as_int(v) {
            Some(int) => toml_value(int.as_any(), name).map(Some),
            None => Err(type_error(name, "an int", v)),
        },
    }
}

/// `mu=`, `max_u=`, `max_uf=`: a number or a list (one per channel; `mu` a [μ_min, μ_max] pair or
/// one per channel), or None.
fn numbers(obj: Option<&Bound<'_, PyAny>>, name: &str, expected: &str) -> PyResult<Option<Value>> {
    let Some(v) = obj.filter(|v| !v.is_none()) else { return Ok(None) };
    if v.is_instance_of::<PyBool>()
        || v.is_instance_of::<pyo3::types::PyString>()
        || v.cast::<pyo3::types::PyDict>().is_ok()
    {
        return Err(type_error(name, expected, v));
    }
    toml_value(v, name).map(Some)
}

/// Per-channel searches over μ_i, as `quell tune`: the channels are decoupled (Proposition 1), so
/// μ is tuned by m one-dimensional searches (log-spaced points, then golden-section steps around
/// the best; the least μ within the solver's error of the best is chosen), the other μ_j held at
/// the scenario's values, and the joint run with every tuned μ_i is checked to reproduce each channel's figure (docs/tuning.md). The GIL is released; Ctrl-C
/// stops the searches and raises KeyboardInterrupt whose `.result` holds the points so far.
///
/// Parameters
/// ----------
/// scenario : Scenario
///     The scenario; its μ is the starting point of the channels not searched yet.
/// mu : list
///     The search interval [μ_min, μ_max] (0 < μ_min ≤ μ_max) of every channel, or one per
///     channel (`[[1, 200], [1, 50]]`).
/// objective : str, optional
///     What each search minimizes: "settle_t" (default), "tail_rms_e" or "tail_max_e".
/// max_u, max_uf : float or list of float, optional
///     Limits on max |u_i| (the adaptive command) and max |u_f,i| (the plant input as asked), one for all
///     channels or one per channel; a point beyond one is infeasible.
/// points : int, optional
///     Log-spaced values per channel before refining (default 13).
/// refine : int, optional
///     Golden-section steps around the best of them (default 8).
/// settle : dict, optional
///     The settling band `{"relative": 0.02, "absolute": 0.0}`.
/// max_steps : int, optional
///     The solver's step budget per run (default: each run's own, derived from its problem as
///     for `quell.simulate`).
/// simulation : dict, optional
///     Overrides of the scenario's simulation settings (`{"t_end": 20.0}`).
/// jobs : int, optional
///     Threads, 1 to 1024 (default one per core).
///
/// Returns
/// -------
/// TuneResult
///     Every evaluation (`frame`), the chosen point of each channel (`best`), the tuned `mu` and
///     the joint run's check (`reproduced`).
///
/// Raises
/// ------
/// TypeError
///     An argument of the wrong type.
/// ScenarioError
///     A value that is not valid (the message names the argument: `mu[0]: …`; `.key` is the
///     study file's key `tune.mu[0]`).
/// KeyboardInterrupt
///     Ctrl-C; its `.result` is the TuneResult of the points evaluated so far (`partial` True).
///
/// Examples
/// --------
/// >>> r = quell.tune(quell.paper_example(), mu=[5.0, 80.0], objective="tail_rms_e", points=3,
/// ...                refine=0, simulation={"t_end": 10.0}, jobs=1)
/// >>> r
/// TuneResult(objective='tail_rms_e', mu=[...], evaluations=7, partial=False)
/// >>> list(r.best["channel"]), bool(r.best["chosen"].all())
/// ([1, 2], True)
#[pyfunction]
#[pyo3(signature = (scenario, *, mu, objective=None, max_u=None, max_uf=None, points=None, refine=None, settle=None, max_steps=None, simulation=None, jobs=None))]
#[allow(clippy::too_many_arguments)]
pub fn tune(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    mu: &Bound<'_, PyAny>,
    objective: Option<&Bound<'_, PyAny>>,
    max_u: Option<&Bound<'_, PyAny>>,
    max_uf: Option<&Bound<'_, PyAny>>,
    points: Option<&Bound<'_, PyAny>>,
    refine: Option<&Bound<'_, PyAny>>,
    settle: Option<&Bound<'_, PyAny>>,
    max_steps: Option<&Bound<'_, PyAny>>,
    simulation: Option<&Bound<'_, PyAny>>,
    jobs: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyAny>> {
    let mut doc = study_document(scenario, [None, None, settle, None, simulation], max_steps)?;
    let limit = "a limit > 0, or one per channel";
    let mut table = Table::new();
    for (key, value) in [
        ("mu", numbers(Some(mu), "mu", "[μ_min, μ_max], or one such pair per channel")?),
        (
            "objective",
            objective
                .filter(|o| !o.is_none())
                .map(|o| crate::convert::text(o, "objective"))
                .transpose()?
                .map(Value::String),
        ),
        ("max_u", numbers(max_u, "max_u", limit)?),
        ("max_uf", numbers(max_uf, "max_uf", limit)?),
        ("points", count(points, "points")?),
        ("refine", count(refine, "refine")?),
    ] {
        if let Some(v) = value {
            table.insert(key.into(), v);
        }
    }
    doc.insert("tune".into(), Value::Table(table));
    let jobs = jobs_arg(py, jobs)?;
    let study = crate::interrupt::interruptible(py, || study::Study::from_table(&doc, None))?
        .map_err(|e| argument_error(py, &e))?;
    let channels = study.m;
    let pool = thread_pool(py, jobs, channels * study.tune.as_ref().map_or(1, |t| t.points))?;
    for w in py.detach(|| study::tune_cautions(&study)) {
        crate::errors::warn(py, &crate::errors::in_python(w))?;
    }
    let (result, interrupt) = crate::interrupt::interruptible_keeping(py, |stop| {
        pool.install(|| study::tune(&study, &TuneOptions { stop: Some(&stop), on_point: None }))
    })?;
    let result = result.map_err(|e| argument_error(py, &e))?;
    warn_choices(py, &study, &result)?;
    let json = serde_json::to_string(&result).map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    let evaluations: usize = result.channels.iter().map(|c| c.curve.len()).sum();
    let result = py.import("quell._tune")?.getattr("TuneResult")?.call1((json,))?;
    match interrupt {
        None => Ok(result.unbind()),
        Some(_) => {
            // Said as an interrupted sweep says it: a bare KeyboardInterrupt left the kept curve unmentioned.
            let e = pyo3::exceptions::PyKeyboardInterrupt::new_err(format!(
                "interrupted after {evaluations} evaluations; they are in the exception's .result (partial)"
            ));
            e.value(py).setattr("result", result)?;
            Err(e)
        }
    }
}

/// The warnings of `quell tune`'s report: a channel without a feasible μ (which keeps the
/// scenario's; the CLI exits 2), and a choice at an end of the bounds.
fn warn_choices(py: Python<'_>, study: &study::Study, result: &study::TuneResult) -> PyResult<()> {
    let spec = study.tune.as_ref().expect("a tuning study has its [tune]");
    // As `quell tune`'s exit status 2: a channel without a feasible μ keeps the scenario's.
    for c in result.channels.iter().filter(|c| c.chosen.is_none() && !result.partial) {
        let i = c.channel;
        crate::errors::warn(
            py,
            &format!(
                "channel {}: {}; mu[{i}] is the scenario's, {} (feasible[{i}] is False; the curve is in .frame)",
                i + 1,
                c.why_none(spec, "", (study.u_max(c.channel), study.steady_input_peak(c.channel))),
                result.mu[i]
            ),
        )?;
    }
    // As `quell tune`'s exit status 2, and its "does NOT reproduce it".
    let searched = result.searched_note("");
    let joint = searched.into_iter().chain(result.joint_limits_caution(spec, "")).chain(result.unreproduced_cautions());
    for w in joint {
        crate::errors::warn(py, &w)?;
    }
    for c in result.channels.iter().filter(|_| !result.partial) {
        if let Some(note) = c.bound_note(&format!("mu[{}]", c.channel)) {
            crate::errors::warn(py, &format!("channel {}: {note}", c.channel + 1))?;
        }
    }
    Ok(())
}
