//! Studies from Python: `quell.Study` (from a file, or from a Scenario and dicts), `quell.sweep` and
//! `Study.sweep` (runs.csv's rows and the drawn values, a pandas DataFrame), `quell.sweep_runs`
//! (picklable `RunSpec`s) and `quell.run_one`, so that dask.distributed or Ray can map the runs over
//! a cluster.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
use std::sync::Arc;

use pyo3::exceptions::{PyIndexError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};
use quell::sim::ChannelFigures;
use quell::study::{self, RunSpec, Shard, StudyMeta, SweepOptions};
use toml::{Table, Value};

use crate::convert::{a_type, as_int, type_name};
use crate::errors::{subscripts, Kind};
use crate::interrupt::{CtrlC, SIGNAL_CHECK};
use crate::scenario::{toml_value, PyScenario};
use crate::simulate::PySimResult;

/// A study: many runs of one scenario, over a grid of its values and Monte Carlo draws of the true
/// plant, with the semantics and checks of a study file (docs/studies.md), whose tables the
/// arguments are.
///
/// Parameters
/// ----------
/// scenario : Scenario
///     The scenario.
/// grid : dict, optional
///     Scenario key path → list of values: the cartesian product, the first key slowest
///     (`{"design.mu[0]": [10.0, 40.0]}`).
/// monte_carlo : dict, optional
///     `{"runs": N, "seed": s, path: {law: spread}}`, laws `relative` (x·(1 + r ξ)),
///     `relative_uniform` (x·(1 + U(−r, r))), `normal` (x + σ ξ), `uniform` (x + U(−a, a)).
/// settle : dict, optional
///     The settling band `{"relative": 0.02, "absolute": 0.0}`.
/// max_steps : int, optional
///     The solver's step budget per run (default: each run's own, derived from its problem as
///     for `quell.simulate`).
/// runaway : dict, optional
///     `{"peak": 100, "steps": 3}`: early ends of draws relative to their nominal run.
/// simulation : dict, optional
///     Overrides of the scenario's simulation settings (`{"t_end": 20.0}`).
///
/// Raises
/// ------
/// TypeError
///     An argument of the wrong type.
/// ScenarioError
///     A value that is not valid; the message names the argument
///     (`grid["design.mu[0]"][1]: …`), `.key` the study key.
///
/// Examples
/// --------
/// >>> study = quell.Study(quell.paper_example(), grid={"design.beta": [1.0, 2.0]},
/// ...                     monte_carlo={"runs": 3, "truth.delays[1]": {"relative_uniform": 0.05}})
/// >>> study
/// Study(runs=6, points=2, draws=3)
#[pyclass(module = "quell", name = "Study", frozen)]
pub struct PyStudy {
    inner: Arc<study::Study>,
}

fn study_error(py: Python<'_>, e: &study::StudyError) -> PyErr {
    let err = Kind::Scenario.err(py, e.to_string());
    let _ = err.value(py).setattr("key", e.key.clone());
    err
}

/// Sections of a study that `quell.Study(...)` takes as dicts.
const DICT_ARGUMENTS: [&str; 5] = ["grid", "monte_carlo", "settle", "runaway", "simulation"];

/// A study key as the Python arguments spell it: `grid."design.mu[0]"[1]` is
/// `grid["design.mu[0]"][1]`, `monte_carlo.runs` is `monte_carlo["runs"]`, and `tune.mu[0]` is
/// `mu[0]` (the keywords of `quell.tune`).
pub fn python_key(key: &str) -> String {
    if let Some(keyword) = key.strip_prefix("tune.") {
        return keyword.to_string();
    }
    match key.split_once('.').filter(|(s, _)| DICT_ARGUMENTS.contains(s)) {
        Some((section, rest)) => format!("{section}{}", subscripts(&format!(".{rest}"))),
        None => key.to_string(),
    }
}

/// A study error of `quell.Study(...)` or `quell.tune(...)`: the message names the Python argument
/// in Python's words, `.key` the study key; a value of the wrong type is a `TypeError`.
pub fn argument_error(py: Python<'_>, e: &study::StudyError) -> PyErr {
    let message = format!("{}: {}", python_key(&e.key), crate::scenario::python_words(e.message.clone()));
    if e.wrong_type {
        return crate::scenario::keyed_type_error(py, message, &e.key);
    }
    let err = Kind::Scenario.err(py, message);
    let _ = err.value(py).setattr("key", e.key.clone());
    err
}

/// A dict argument of `quell.Study(...)` as a TOML table.
fn dict_arg(obj: &Bound<'_, PyAny>, name: &str, what: &str) -> PyResult<Table> {
    let d = obj
        .cast::<PyDict>()
        .map_err(|_| PyTypeError::new_err(format!("{name}: expected a dict ({what}), found {}", a_type(obj))))?;
    let mut t = Table::new();
    for (k, v) in d.iter() {
        let key: String = k.extract().map_err(|_| {
            PyTypeError::new_err(format!("{name}: expected str keys ({what}), found a key of type {}", type_name(&k)))
        })?;
        if !v.is_none() {
            let value = toml_value(&v, &format!("{name}[{key:?}]"))?;
            t.insert(key, value);
        }
    }
    Ok(t)
}

/// A study document from a Scenario and the dict arguments of `quell.Study(...)` (grid,
/// monte_carlo, settle, runaway, simulation, each None for none) and `max_steps`.
pub fn study_document(
    scenario: &Bound<'_, PyAny>,
    dicts: [Option<&Bound<'_, PyAny>>; 5],
    max_steps: Option<&Bound<'_, PyAny>>,
) -> PyResult<Table> {
    let s = scenario.cast::<PyScenario>().map_err(|_| {
        PyTypeError::new_err(format!("scenario: expected a quell.Scenario, found {}", a_type(scenario)))
    })?;
    let mut doc = Table::new();
    doc.insert("scenario".into(), Value::Table(s.get().inner.to_table()));
    let what = [
        "scenario key path: list of values",
        "runs, seed, and scenario key path: {law: spread}",
        "relative, absolute",
        "peak, steps",
        "overrides of the scenario's simulation settings",
    ];
    for ((name, v), what) in DICT_ARGUMENTS.iter().zip(dicts).zip(what) {
        if let Some(v) = v.filter(|v| !v.is_none()) {
            doc.insert(name.to_string(), Value::Table(dict_arg(v, name, what)?));
        }
    }
    if let Some(n) = max_steps.filter(|v| !v.is_none()) {
        let Some(int) = as_int(n) else {
            return Err(PyTypeError::new_err(format!(
                "max_steps: expected an int (a step budget per run), found {}",
                a_type(n)
            )));
        };
        doc.insert("max_steps".into(), toml_value(int.as_any(), "max_steps")?);
    }
    Ok(doc)
}

#[pymethods]
impl PyStudy {
    #[new]
    #[pyo3(signature = (scenario, *, grid=None, monte_carlo=None, settle=None, max_steps=None, runaway=None, simulation=None))]
    #[allow(clippy::too_many_arguments)]
    fn py_new(
        py: Python<'_>,
        scenario: &Bound<'_, PyAny>,
        grid: Option<&Bound<'_, PyAny>>,
        monte_carlo: Option<&Bound<'_, PyAny>>,
        settle: Option<&Bound<'_, PyAny>>,
        max_steps: Option<&Bound<'_, PyAny>>,
        runaway: Option<&Bound<'_, PyAny>>,
        simulation: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let doc = study_document(scenario, [grid, monte_carlo, settle, runaway, simulation], max_steps)?;
        let inner = crate::interrupt::interruptible(py, || study::Study::from_table(&doc, None))?
            .map_err(|e| argument_error(py, &e))?;
        Ok(PyStudy { inner: Arc::new(inner) })
    }

    /// The study as one TOML document, its scenario inline.
    ///
    /// Returns
    /// -------
    /// str
    ///     The document; `Study.from_toml(study.to_toml())` is the same study.
    ///
    /// Raises
    /// ------
    /// This method raises nothing.
    ///
    /// Examples
    /// --------
    /// >>> study = quell.Study(quell.paper_example(), grid={"design.beta": [1.0, 2.0]})
    /// >>> quell.Study.from_toml(study.to_toml()) == study
    /// True
    fn to_toml(&self) -> String {
        toml::to_string(self.inner.to_table()).unwrap_or_default()
    }

    /// Equal studies: the same document (scenario, grid, draws, settings).
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.cast::<PyStudy>().is_ok_and(|o| o.get().inner.to_table() == self.inner.to_table())
    }

    /// Pickles as `Study.from_toml(study.to_toml())`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        Ok((slf.get_type().getattr("_restore")?, (slf.get().to_toml(),)))
    }

    /// Run `run`'s specification (carrying out its grid point's nominal run first, if it has draws).
    ///
    /// Parameters
    /// ----------
    /// run : int
    ///     The run index (point × draws + draw; negative counts from the end).
    ///
    /// Returns
    /// -------
    /// RunSpec
    ///     The run's specification.
    ///
    /// Raises
    /// ------
    /// TypeError
    ///     `run` is not an int.
    /// IndexError
    ///     `run` is not a run of the study.
    ///
    /// Examples
    /// --------
    /// >>> study = quell.Study(quell.paper_example(), grid={"design.beta": [1.0, 2.0]})
    /// >>> study.spec(1).grid
    /// {'design.beta': 2.0}
    fn spec(&self, py: Python<'_>, run: &Bound<'_, PyAny>) -> PyResult<PyRunSpec> {
        let len = self.inner.len();
        let index = run_index(run, len)?;
        let study = &self.inner;
        let inner =
            spec_interruptibly(py, &CtrlC::new(), study, index)?.ok_or_else(|| out_of_range(index as i128, len))?;
        Ok(PyRunSpec { inner })
    }

    /// Every run, in parallel on `jobs` threads with the GIL released; Ctrl-C stops the sweep.
    ///
    /// Parameters
    /// ----------
    /// jobs : int, optional
    ///     Threads, 1 to 1024 (default one per core).
    /// yes : bool, optional
    ///     Run a study of more than 10⁷ runs (whose rows are kept in memory).
    ///
    /// Returns
    /// -------
    /// StudyResult
    ///     The rows (runs.csv's columns, then the drawn values) and the study.
    ///
    /// Raises
    /// ------
    /// TypeError
    ///     An argument of the wrong type.
    /// ScenarioError
    ///     `jobs` out of range, or more than 10⁷ runs without `yes`.
    /// KeyboardInterrupt
    ///     Ctrl-C; its `.result` is the StudyResult of the runs carried out (the frame's
    ///     `attrs["partial"]` True).
    ///
    /// Examples
    /// --------
    /// >>> result = quell.Study(quell.paper_example(), simulation={"t_end": 2.0}).sweep(jobs=1)
    /// >>> result.frame["outcome"].tolist()
    /// ['completed']
    #[pyo3(signature = (*, jobs=None, yes=false))]
    fn sweep(
        slf: &Bound<'_, Self>,
        jobs: Option<&Bound<'_, PyAny>>,
        #[pyo3(from_py_with = crate::convert::argument::yes)] yes: bool,
    ) -> PyResult<Py<PyAny>> {
        let py = slf.py();
        let (frame, interrupt) = sweep_frame(py, &slf.get().inner, jobs, yes)?;
        let result = py.import("quell._study")?.getattr("StudyResult")?.call1((slf, frame))?;
        with_result(py, result, interrupt)
    }

    /// Channels m of the study's scenario.
    #[getter]
    fn m(&self) -> usize {
        self.inner.m
    }

    /// Grid points.
    #[getter]
    fn points(&self) -> usize {
        self.inner.points()
    }

    /// Monte Carlo draws per grid point (1 without draws).
    #[getter]
    fn draws(&self) -> usize {
        self.inner.draws()
    }

    /// Reads a study file; its `scenario` path is relative to the file's directory.
    ///
    /// Parameters
    /// ----------
    /// path : str or os.PathLike
    ///     The study file.
    ///
    /// Returns
    /// -------
    /// Study
    ///     The study.
    ///
    /// Raises
    /// ------
    /// TypeError
    ///     `path` is not a path.
    /// ScenarioError
    ///     The file cannot be read or is not a valid study (the message names the key).
    ///
    /// Examples
    /// --------
    /// >>> import pathlib
    /// >>> _ = pathlib.Path("study.toml").write_text('[grid]\n"design.beta" = [1.0, 2.0]\n')
    /// >>> len(quell.Study.load("study.toml"))
    /// 2
    #[staticmethod]
    fn load(py: Python<'_>, path: &Bound<'_, PyAny>) -> PyResult<Self> {
        let path = crate::convert::path(path, "path")?;
        crate::interrupt::interruptible(py, || study::Study::from_path(&path))?
            .map(|s| PyStudy { inner: Arc::new(s) })
            .map_err(|e| study_error(py, &e))
    }

    /// Parses a study file's text.
    ///
    /// Parameters
    /// ----------
    /// text : str
    ///     The TOML text; without `scenario`, the paper's example.
    /// dir : str or os.PathLike, optional
    ///     Where a relative `scenario` path is looked up (default the working directory).
    ///
    /// Returns
    /// -------
    /// Study
    ///     The study.
    ///
    /// Raises
    /// ------
    /// TypeError
    ///     An argument of the wrong type.
    /// ScenarioError
    ///     The text is not a valid study.
    ///
    /// Examples
    /// --------
    /// >>> quell.Study.from_toml('[monte_carlo]\nruns = 4\n"truth.A" = { relative = 0.01 }\n').draws
    /// 4
    #[staticmethod]
    #[pyo3(signature = (text, dir=None))]
    fn from_toml(py: Python<'_>, text: &Bound<'_, PyAny>, dir: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let text = crate::convert::toml_text(text, "text", "quell.Study.load(path)")?;
        let dir = dir.filter(|d| !d.is_none()).map(|d| crate::convert::path(d, "dir")).transpose()?;
        crate::interrupt::interruptible(py, || study::Study::from_toml(&text, dir.as_deref()))?
            .map(|s| PyStudy { inner: Arc::new(s) })
            .map_err(|e| study_error(py, &e))
    }

    /// A pickled study (`__reduce__`): its text read as `from_toml` does, but not held to a file's
    /// 16 MiB (the text is this package's own).
    #[staticmethod]
    fn _restore(py: Python<'_>, text: &str) -> PyResult<Self> {
        let doc = crate::convert::pickled_document(py, text)?;
        crate::interrupt::interruptible(py, || study::Study::from_table(&doc, None))?
            .map(|s| PyStudy { inner: Arc::new(s) })
            .map_err(|e| study_error(py, &e))
    }

    /// The columns of runs.csv (and of `quell.sweep`'s DataFrame).
    #[getter]
    fn columns(&self) -> Vec<String> {
        study::header(&StudyMeta::new(&self.inner, Shard::ALL))
    }

    fn __len__(&self) -> usize {
        usize::try_from(self.inner.len()).unwrap_or(usize::MAX)
    }

    fn __repr__(&self) -> String {
        format!("Study(runs={}, points={}, draws={})", self.inner.len(), self.inner.points(), self.inner.draws())
    }
}

/// Everything one run of a study needs, self-contained and picklable (it travels to a cluster's
/// workers as JSON); `quell.run_one(spec)` carries it out and `spec.simulate()` gives its signals.
///
/// Parameters
/// ----------
/// json : str
///     Its JSON form (`spec.to_json()`).
/// drawn : list of str, optional
///     The keys its study's draws perturb (for `drawn`), where the JSON, from before 2026-12-07, has none.
///
/// Raises
/// ------
/// TypeError
///     An argument of the wrong type.
/// ScenarioError
///     `json` is not a run specification.
///
/// Examples
/// --------
/// >>> spec = quell.Study(quell.paper_example(), monte_carlo={"runs": 2, "seed": 3,
/// ...                    "truth.delays[1]": {"relative_uniform": 0.1}}).spec(1)
/// >>> spec
/// RunSpec(run=1, point=0, draw=1, seed=...)
/// >>> 2.7 <= spec.drawn["truth.delays[1]"] <= 3.3
/// True
#[pyclass(module = "quell", name = "RunSpec", frozen)]
pub struct PyRunSpec {
    /// With the keys its study's draws perturb (`drawn_keys`).
    inner: RunSpec,
}

/// `run` as an index below `len` (an int; negative counts from the end, as in a list).
fn run_index(run: &Bound<'_, PyAny>, len: u64) -> PyResult<usize> {
    let Some(run) = as_int(run) else {
        return Err(PyTypeError::new_err(format!("run: expected an int (a run index), found {}", a_type(run))));
    };
    let i: i128 = run.extract().map_err(|_| out_of_range(i128::MAX, len))?;
    let index = if i < 0 { i + len as i128 } else { i };
    if (0..len as i128).contains(&index) {
        Ok(index as usize)
    } else {
        Err(out_of_range(i, len))
    }
}

fn out_of_range(i: i128, len: u64) -> PyErr {
    PyIndexError::new_err(format!(
        "run: expected a run index from 0 to {} (the study has {}; from −{len} to −1 counting from the end, as in a list), found {i}",
        len.saturating_sub(1),
        if len == 1 { "1 run".to_string() } else { format!("{len} runs") }
    ))
}

/// A TOML value as a Python value.
fn py_value<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(x) => x.into_pyobject(py)?.into_any(),
        toml::Value::Boolean(b) => b.into_pyobject(py)?.to_owned().into_any(),
        toml::Value::String(s) => s.into_pyobject(py)?.into_any(),
        toml::Value::Array(a) => {
            PyList::new(py, a.iter().map(|x| py_value(py, x)).collect::<PyResult<Vec<_>>>()?)?.into_any()
        }
        toml::Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, py_value(py, x)?)?;
            }
            d.into_any()
        }
        toml::Value::Datetime(d) => d.to_string().into_pyobject(py)?.into_any(),
    })
}

/// A grid value as runs.csv's reader (pandas) sees it: a number, or the value as written.
fn grid_cell<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    match v {
        toml::Value::Integer(_) | toml::Value::Float(_) => py_value(py, v),
        other => Ok(other.to_string().into_pyobject(py)?.into_any()),
    }
}

#[pymethods]
impl PyRunSpec {
    /// A run specification from its JSON form (`spec.to_json()`); this is how pickle rebuilds it.
    #[new]
    #[pyo3(signature = (json, drawn=None))]
    fn new(py: Python<'_>, json: &Bound<'_, PyAny>, drawn: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let json = crate::convert::text(json, "json")?;
        let drawn = drawn
            .filter(|d| !d.is_none())
            .map(|d| crate::convert::strings(d, "drawn", "a list of study keys (str)", "a str (a study key)"));
        let drawn = drawn.transpose()?;
        // `drawn` given (a pickle before 2026-12-07, whose JSON had no drawn_keys) sets them.
        serde_json::from_str(&json)
            .map(|inner: RunSpec| PyRunSpec {
                inner: RunSpec { drawn_keys: drawn.unwrap_or(inner.drawn_keys.clone()), ..inner },
            })
            .map_err(|e| Kind::Scenario.err(py, format!("json: not a quell run specification ({e})")))
    }
    /// The values the run's draw gave each perturbed key, flattened (`truth.A[0][1]`), as the
    /// study's DataFrame columns; empty without Monte Carlo.
    #[getter]
    fn drawn<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (k, v) in self.inner.drawn_named() {
            d.set_item(k, v)?;
        }
        Ok(d)
    }
    /// Simulates the run as the sweep does (its scenario, step budget and runaway rules); Ctrl-C
    /// stops it.
    ///
    /// Returns
    /// -------
    /// SimResult
    ///     The signals, however the run ended (a diverged run is returned, not raised).
    ///
    /// Raises
    /// ------
    /// ScenarioError
    ///     The run's scenario is not valid (a draw made it so).
    /// DesignError
    ///     No design exists for the run's scenario.
    ///
    /// Examples
    /// --------
    /// >>> spec = quell.Study(quell.paper_example(), simulation={"t_end": 2.0}).spec(0)
    /// >>> spec.simulate().outcome
    /// {'status': 'completed'}
    fn simulate(&self, py: Python<'_>) -> PyResult<PySimResult> {
        let scenario = quell::Scenario::from_document(&self.inner.scenario)
            .map_err(|e| crate::scenario::scenario_error(py, &e))?;
        let design = scenario.design().map_err(|e| crate::errors::raise(py, Kind::Design)(&e))?;
        let run = quell::sim::Run::of(&scenario, &design);
        if let Some(w) = quell::sim::explicit_stiff_warning(&run, quell::sim::EXPLICIT_IN_FILE) {
            crate::errors::warn(py, &crate::errors::in_python(w))?;
        }
        let spec = &self.inner;
        let result = crate::interrupt::interruptible_with(py, |stop| spec.simulate_until(&|| stop.load(Relaxed)))?
            .map_err(|e| Kind::Scenario.err(py, e))?;
        PySimResult::from_run(py, &scenario, &design, result, scenario.names.clone())
    }
    /// Equal specifications: the same run of the same study.
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.cast::<PyRunSpec>().is_ok_and(|o| o.get().inner == self.inner)
    }
    /// The JSON form of the specification.
    ///
    /// Returns
    /// -------
    /// str
    ///     JSON; `quell.RunSpec(spec.to_json())` rebuilds it.
    ///
    /// Raises
    /// ------
    /// This method raises nothing.
    ///
    /// Examples
    /// --------
    /// >>> spec = quell.Study(quell.paper_example()).spec(0)
    /// >>> quell.RunSpec(spec.to_json()) == spec
    /// True
    fn to_json(&self) -> String {
        serde_json::to_string(&self.inner).unwrap_or_default()
    }
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let args = PyTuple::new(py, [slf.get().to_json().into_pyobject(py)?.into_any()])?;
        PyTuple::new(py, [slf.get_type().into_any(), args.into_any()])
    }
    /// Run index (point × draws + draw).
    #[getter]
    fn run(&self) -> usize {
        self.inner.run
    }
    /// Grid point index.
    #[getter]
    fn point(&self) -> usize {
        self.inner.point
    }
    /// Monte Carlo draw index.
    #[getter]
    fn draw(&self) -> usize {
        self.inner.draw
    }
    /// The draw's seed (0 without Monte Carlo).
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.seed
    }
    /// The grid point's values, by key as written in the study file.
    #[getter]
    fn grid<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (k, v) in &self.inner.grid {
            d.set_item(k, py_value(py, v)?)?;
        }
        Ok(d)
    }
    /// The run's scenario: its grid values and draws applied.
    ///
    /// Returns
    /// -------
    /// Scenario
    ///     The scenario.
    ///
    /// Raises
    /// ------
    /// ScenarioError
    ///     The run's scenario is not valid (a draw made it so).
    ///
    /// Examples
    /// --------
    /// >>> spec = quell.Study(quell.paper_example(), grid={"design.beta": [1.0, 2.0]}).spec(1)
    /// >>> spec.scenario().design().beta
    /// 2.0
    fn scenario(&self, py: Python<'_>) -> PyResult<PyScenario> {
        quell::Scenario::from_document(&self.inner.scenario)
            .map(PyScenario::new)
            .map_err(|e| crate::scenario::scenario_error(py, &e))
    }
    fn __repr__(&self) -> String {
        format!(
            "RunSpec(run={}, point={}, draw={}, seed={})",
            self.inner.run, self.inner.point, self.inner.draw, self.inner.seed
        )
    }
}

/// Channels of a run's scenario document (columns of plant.B), for the row of a run that failed.
fn channels(spec: &RunSpec) -> usize {
    let b = spec.scenario.get("plant").and_then(|p| p.get("B")).and_then(|b| b.as_array());
    b.and_then(|rows| rows.first()).and_then(|r| r.as_array()).map_or(0, Vec::len)
}

/// The row of runs.csv for one run, as a dict keyed by runs.csv's columns.
fn row_dict<'py>(py: Python<'py>, spec: &RunSpec, row: &study::Row) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("run", row.run)?;
    d.set_item("point", row.point)?;
    d.set_item("draw", row.draw)?;
    d.set_item("seed", row.seed)?;
    for (k, v) in &spec.grid {
        d.set_item(k, grid_cell(py, v)?)?;
    }
    d.set_item("outcome", row.outcome.as_str())?;
    // As runs.csv reads back (pandas): an empty reason is a missing value.
    d.set_item("reason", Some(&row.reason).filter(|r| !r.is_empty()))?;
    let m = if row.channels.is_empty() { channels(spec) } else { row.channels.len() };
    let get = |i: usize, f: &dyn Fn(&ChannelFigures) -> Option<f64>| row.channels.get(i).and_then(f);
    for (name, f) in [
        ("tail_max_e", &(|c: &ChannelFigures| Some(c.tail_max_e)) as &dyn Fn(&ChannelFigures) -> Option<f64>),
        ("tail_rms_e", &|c: &ChannelFigures| Some(c.tail_rms_e)),
        ("max_u", &|c: &ChannelFigures| Some(c.max_u)),
        ("max_uf", &|c: &ChannelFigures| Some(c.max_uf)),
        ("settle_t", &|c: &ChannelFigures| c.settle_t),
    ] {
        // A missing figure is NaN, as runs.csv's empty cell reads back: None made a column of
        // them object-typed in a DataFrame of rows (a Dask map's).
        for i in 0..m {
            d.set_item(format!("{name}{}", i + 1), get(i, f).unwrap_or(f64::NAN))?;
        }
    }
    d.set_item("steps", row.steps)?;
    d.set_item("wall_ms", row.wall_ms)?;
    Ok(d)
}

/// Carries out one run (releasing the GIL; Ctrl-C stops it) and returns its row of runs.csv.
///
/// Parameters
/// ----------
/// spec : RunSpec
///     The run.
///
/// Returns
/// -------
/// dict
///     The row, keyed by runs.csv's columns, then the drawn values; a run that diverged or
///     failed is a row too, never an error. A missing figure (no tail, never settled) is NaN, as
///     runs.csv's empty cell reads back.
///
/// Raises
/// ------
/// TypeError
///     `spec` is not a RunSpec.
/// KeyboardInterrupt
///     Ctrl-C stopped the run.
///
/// Examples
/// --------
/// >>> spec = quell.Study(quell.paper_example(), simulation={"t_end": 2.0}).spec(0)
/// >>> quell.run_one(spec)["outcome"]
/// 'completed'
#[pyfunction]
pub fn run_one<'py>(py: Python<'py>, spec: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyDict>> {
    let spec = spec.cast::<PyRunSpec>().map_err(|_| crate::errors::type_error("spec", "a quell.RunSpec", spec))?.get();
    let s = &spec.inner;
    let row = crate::interrupt::interruptible_with(py, |stop| study::run_one_until(s, &|| stop.load(Relaxed)))?
        .ok_or_else(|| pyo3::exceptions::PyKeyboardInterrupt::new_err("the run was stopped"))?;
    let d = row_dict(py, s, &row)?;
    for (k, v) in s.drawn_named() {
        d.set_item(k, v)?;
    }
    Ok(d)
}

/// An iterator over a study's run specifications, in run order; threads may share it (each spec
/// goes to one of them; a thread waits for another's nominal run without the GIL).
#[pyclass(module = "quell", name = "RunSpecs", frozen)]
pub struct PyRunSpecs {
    study: Arc<study::Study>,
    next: Turn,
}

/// The next run's index, held by one thread at a time: [`Turn::take`] waits (without the GIL) while
/// another thread holds it; the [`Held`] turn ends when dropped, advanced or not.
#[derive(Default)]
struct Turn {
    /// (the next index, a thread holds it)
    state: std::sync::Mutex<(usize, bool)>,
    free: std::sync::Condvar,
}

impl Turn {
    fn lock(&self) -> std::sync::MutexGuard<'_, (usize, bool)> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The turn, or the KeyboardInterrupt of a Ctrl-C `ctrl_c` sees while waiting for it (a thread
    /// had waited out another's nominal run, 9 s, deaf to Ctrl-C; diff review, 2026-12-06).
    fn take(&self, py: Python<'_>, ctrl_c: &CtrlC) -> PyResult<Held<'_>> {
        let index = py.detach(|| loop {
            let mut state = self.lock();
            if state.1 {
                state = self.free.wait_timeout(state, SIGNAL_CHECK).unwrap_or_else(|e| e.into_inner()).0;
            }
            if !state.1 {
                state.1 = true;
                return Ok::<usize, PyErr>(state.0);
            }
            drop(state);
            ctrl_c.check()?;
        })?;
        Ok(Held { turn: self, index, advanced: false })
    }
}

/// A thread's turn at [`Turn`]: `index` is its run; `advanced` moves the next one on.
struct Held<'a> {
    turn: &'a Turn,
    index: usize,
    advanced: bool,
}

impl Drop for Held<'_> {
    fn drop(&mut self) {
        let mut state = self.turn.lock();
        state.0 += usize::from(self.advanced);
        state.1 = false;
        self.turn.free.notify_one();
    }
}

/// Run `index`'s spec: the first of a grid point carries out that point's nominal run, without the
/// GIL and stopped by Ctrl-C (since `ctrl_c` was made: a KeyboardInterrupt; nothing of the run is
/// kept). `None` past the end.
fn spec_interruptibly(
    py: Python<'_>,
    ctrl_c: &CtrlC,
    study: &study::Study,
    index: usize,
) -> PyResult<Option<study::RunSpec>> {
    let work = |stop: Arc<AtomicBool>| study.spec_with_nominal_until(index, &|| stop.load(Relaxed));
    match crate::interrupt::interruptible_since(py, ctrl_c, work)? {
        (_, Some(e)) => Err(e),
        (spec, None) => Ok(spec),
    }
}

#[pymethods]
impl PyRunSpecs {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }
    fn __next__(&self, py: Python<'_>) -> PyResult<Option<PyRunSpec>> {
        // A &mut self had raised "Already borrowed" in a second thread while the first's nominal
        // run had the GIL released. An interrupted spec is not consumed.
        let ctrl_c = CtrlC::new();
        let mut turn = self.next.take(py, &ctrl_c)?;
        let Some(inner) = spec_interruptibly(py, &ctrl_c, &self.study, turn.index)? else { return Ok(None) };
        turn.advanced = true;
        Ok(Some(PyRunSpec { inner }))
    }
    fn __len__(&self) -> usize {
        let next = self.next.lock().0;
        usize::try_from(self.study.len()).unwrap_or(usize::MAX).saturating_sub(next)
    }
}

fn study_arg(py: Python<'_>, study: &Bound<'_, PyAny>) -> PyResult<Arc<study::Study>> {
    if let Ok(s) = study.extract::<PyRef<'_, PyStudy>>() {
        return Ok(s.inner.clone());
    }
    if study.is_instance_of::<PyString>() || study.hasattr("__fspath__")? {
        let path: PathBuf = study.extract()?;
        let read = crate::interrupt::interruptible(py, || study::Study::from_path(&path))?;
        return read.map(Arc::new).map_err(|e| study_error(py, &e));
    }
    Err(PyTypeError::new_err(format!(
        "study: expected a quell.Study or the path of a study file, found {}",
        a_type(study)
    )))
}

/// The study's run specifications, in run order (picklable), for `run_one` on a cluster.
///
/// Parameters
/// ----------
/// study : Study or str or os.PathLike
///     The study, or a study file's path.
///
/// Returns
/// -------
/// iterator of RunSpec
///     One per run; building the first of a grid point with draws carries out its nominal run.
///
/// Raises
/// ------
/// TypeError
///     `study` is neither.
/// ScenarioError
///     The file cannot be read or is not a valid study.
///
/// Examples
/// --------
/// >>> specs = list(quell.sweep_runs(quell.Study(quell.paper_example(), grid={"design.beta": [1.0, 2.0]})))
/// >>> [s.run for s in specs]
/// [0, 1]
#[pyfunction]
pub fn sweep_runs(py: Python<'_>, study: &Bound<'_, PyAny>) -> PyResult<PyRunSpecs> {
    let study = study_arg(py, study)?;
    study::check_sweep(&study).map_err(|e| study_error(py, &e))?;
    Ok(PyRunSpecs { study, next: Turn::default() })
}

/// Every run of a study, in parallel on `jobs` threads (default: every core), with the GIL
/// released; Ctrl-C stops the sweep. `Study.sweep` returns the same rows with the study.
///
/// Parameters
/// ----------
/// study : Study or str or os.PathLike
///     The study, or a study file's path.
/// jobs : int, optional
///     Threads, 1 to 1024 (default one per core).
/// yes : bool, optional
///     Run a study of more than 10⁷ runs.
///
/// Returns
/// -------
/// pandas.DataFrame
///     runs.csv's rows, then the drawn values.
///
/// Raises
/// ------
/// TypeError
///     An argument of the wrong type.
/// ScenarioError
///     The study is not valid, `jobs` is out of range, or more than 10⁷ runs without `yes`.
/// KeyboardInterrupt
///     Ctrl-C; its `.result` is the DataFrame of the runs carried out (`attrs["partial"]` True).
///
/// Examples
/// --------
/// >>> frame = quell.sweep(quell.Study(quell.paper_example(), simulation={"t_end": 2.0}), jobs=1)
/// >>> list(frame.columns[:5])
/// ['run', 'point', 'draw', 'seed', 'outcome']
#[pyfunction]
#[pyo3(signature = (study, *, jobs=None, yes=false))]
pub fn sweep(
    py: Python<'_>,
    study: &Bound<'_, PyAny>,
    jobs: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = crate::convert::argument::yes)] yes: bool,
) -> PyResult<Py<PyAny>> {
    let (frame, interrupt) = sweep_frame(py, &study_arg(py, study)?, jobs, yes)?;
    with_result(py, frame.into_bound(py), interrupt)
}

/// `result`, or the KeyboardInterrupt `interrupt` carrying it as `.result` (the rows carried out).
fn with_result(py: Python<'_>, result: Bound<'_, PyAny>, interrupt: Option<PyErr>) -> PyResult<Py<PyAny>> {
    match interrupt {
        None => Ok(result.unbind()),
        Some(e) => {
            e.value(py).setattr("result", result)?;
            Err(e)
        }
    }
}

/// `jobs=`: None, or a number of threads from 1 to [`study::MAX_JOBS`].
pub fn jobs_arg(py: Python<'_>, jobs: Option<&Bound<'_, PyAny>>) -> PyResult<Option<usize>> {
    let Some(j) = jobs.filter(|j| !j.is_none()) else { return Ok(None) };
    let Some(j) = as_int(j) else {
        return Err(PyTypeError::new_err(format!(
            "jobs: expected an int (a number of threads) or None, found {}",
            a_type(j)
        )));
    };
    match j.extract::<i128>() {
        Ok(n) if (1..=study::MAX_JOBS as i128).contains(&n) => Ok(Some(n as usize)),
        _ => Err(Kind::Scenario.err(
            py,
            format!(
                "jobs: expected a number of threads from 1 to {} (None for one per core), found {}",
                study::MAX_JOBS,
                j.repr().map_or_else(|_| "?".to_string(), |r| r.to_string())
            ),
        )),
    }
}

/// A pool of `jobs` threads (default one per core), never more than `tasks`.
pub fn thread_pool(py: Python<'_>, jobs: Option<usize>, tasks: usize) -> PyResult<rayon::ThreadPool> {
    let threads = jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.min(tasks).max(1))
        .build()
        .map_err(|e| Kind::Scenario.err(py, format!("jobs: cannot start the threads ({e})")))
}

/// The sweep of `study` as a DataFrame: runs.csv's columns, then the drawn values; with the
/// KeyboardInterrupt that stopped it (the frame then holds the runs carried out).
fn sweep_frame(
    py: Python<'_>,
    study: &Arc<study::Study>,
    jobs: Option<&Bound<'_, PyAny>>,
    yes: bool,
) -> PyResult<(Py<PyAny>, Option<PyErr>)> {
    let jobs = jobs_arg(py, jobs)?;
    study::check_sweep(study).map_err(|e| study_error(py, &e))?;
    if study.len() > study::CONFIRM_RUNS && !yes {
        return Err(Kind::Scenario.err(
            py,
            format!(
                "the study has {} runs ({} grid points × {} draws), more than {:e}, and sweep keeps every row in memory (~200 bytes each); check the grid, pass yes=True to run it, or iterate quell.sweep_runs(study) with quell.run_one",
                study.len(),
                study.points(),
                study.draws(),
                study::CONFIRM_RUNS as f64
            ),
        ));
    }
    let pool = thread_pool(py, jobs, usize::try_from(study.len()).unwrap_or(usize::MAX))?;
    // Ctrl-C during the check raises KeyboardInterrupt before any run.
    let caution = crate::interrupt::interruptible_with(py, |stop| study.fast_rate_caution(&|| stop.load(Relaxed)))?;
    if let Some(w) = caution {
        crate::errors::warn(py, &crate::errors::in_python(w))?;
    }
    let (swept, interrupt) = crate::interrupt::interruptible_keeping(py, |stop| {
        let opts = SweepOptions { stop: Some(&stop), ..SweepOptions::default() };
        pool.install(|| study::sweep(study, &opts))
    })?;
    if let Some(w) = study.explicit_stiff_caution(&swept.rows) {
        crate::errors::warn(py, &crate::errors::in_python(w))?;
    }
    let meta = StudyMeta::new(study, Shard::ALL);
    let mut text = Vec::new();
    study::write_runs_csv(&mut text, &meta, &swept.rows, swept.partial)
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    let text = String::from_utf8_lossy(&text).into_owned();
    // runs.csv's last columns are the drawn values.
    let frame = py.import("quell._frames")?.call_method1("runs_frame", (text,))?;
    frame.getattr("attrs")?.set_item("partial", swept.partial)?;
    // Said as `quell sweep` says it: a bare KeyboardInterrupt left the rows kept unmentioned.
    let interrupt = interrupt.map(|_| {
        pyo3::exceptions::PyKeyboardInterrupt::new_err(format!(
            "interrupted after {} of {} runs; their rows are in the exception's .result (partial)",
            swept.rows.len(),
            study.len()
        ))
    });
    Ok((frame.unbind(), interrupt))
}
