//! Studies from Python: `quell.Study`, `quell.sweep` (a pandas DataFrame of runs.csv's rows),
//! `quell.sweep_runs` (picklable `RunSpec`s) and `quell.run_one`, so that dask.distributed or Ray
//! can map the runs over a cluster.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use quell::study::{self, RunSpec, Shard, StudyMeta, SweepOptions};

use crate::errors::Kind;
use crate::scenario::PyScenario;

/// A study file (`quell sweep`'s input): a scenario, a grid of scenario values and Monte Carlo
/// draws of the true plant.
#[pyclass(module = "quell", name = "Study", frozen)]
pub struct PyStudy {
    inner: Arc<study::Study>,
}

fn study_error(py: Python<'_>, e: &study::StudyError) -> PyErr {
    let err = Kind::Scenario.err(py, e.to_string());
    let _ = err.value(py).setattr("key", e.key.clone());
    err
}

#[pymethods]
impl PyStudy {
    /// Reads a study file; its `scenario` path is relative to the file's directory.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        study::Study::from_path(&path).map(|s| PyStudy { inner: Arc::new(s) }).map_err(|e| study_error(py, &e))
    }

    /// Parses a study; a relative `scenario` path is looked up in `dir` (default: the working
    /// directory).
    #[staticmethod]
    #[pyo3(signature = (text, dir=None))]
    fn from_toml(py: Python<'_>, text: &str, dir: Option<PathBuf>) -> PyResult<Self> {
        study::Study::from_toml(text, dir.as_deref())
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
/// workers as JSON); `quell.run_one(spec)` carries it out.
#[pyclass(module = "quell", name = "RunSpec", frozen)]
pub struct PyRunSpec {
    inner: RunSpec,
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
    fn new(py: Python<'_>, json: &str) -> PyResult<Self> {
        serde_json::from_str(json)
            .map(|inner| PyRunSpec { inner })
            .map_err(|e| Kind::Scenario.err(py, format!("json: not a quell run specification ({e})")))
    }
    /// The JSON form of the specification.
    fn to_json(&self) -> String {
        serde_json::to_string(&self.inner).unwrap_or_default()
    }
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let json = slf.get().to_json();
        PyTuple::new(slf.py(), [slf.get_type().into_any(), PyTuple::new(slf.py(), [json])?.into_any()])
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
    /// The run's scenario: grid values and the draw's perturbations applied.
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
    let get = |i: usize, f: &dyn Fn(&study::ChannelFigures) -> Option<f64>| row.channels.get(i).and_then(f);
    for (name, f) in [
        (
            "tail_max_e",
            &(|c: &study::ChannelFigures| Some(c.tail_max_e)) as &dyn Fn(&study::ChannelFigures) -> Option<f64>,
        ),
        ("tail_rms_e", &|c: &study::ChannelFigures| Some(c.tail_rms_e)),
        ("max_u", &|c: &study::ChannelFigures| Some(c.max_u)),
        ("max_uf", &|c: &study::ChannelFigures| Some(c.max_uf)),
        ("settle_t", &|c: &study::ChannelFigures| c.settle_t),
    ] {
        for i in 0..m {
            d.set_item(format!("{name}{}", i + 1), get(i, f))?;
        }
    }
    d.set_item("steps", row.steps)?;
    d.set_item("wall_ms", row.wall_ms)?;
    Ok(d)
}

/// Carries out one run (releasing the GIL) and returns its runs.csv row as a dict.
#[pyfunction]
pub fn run_one<'py>(py: Python<'py>, spec: PyRef<'py, PyRunSpec>) -> PyResult<Bound<'py, PyDict>> {
    let s = &spec.inner;
    let row = py.detach(|| study::run_one(s));
    row_dict(py, s, &row)
}

/// An iterator over a study's run specifications, in run order.
#[pyclass(module = "quell", name = "RunSpecs")]
pub struct PyRunSpecs {
    study: Arc<study::Study>,
    next: usize,
}

#[pymethods]
impl PyRunSpecs {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }
    fn __next__(&mut self, py: Python<'_>) -> Option<PyRunSpec> {
        // The first spec of a grid point carries out that point's nominal run: without the GIL.
        let (study, index) = (&self.study, self.next);
        let inner = py.detach(|| study.spec(index))?;
        self.next += 1;
        Some(PyRunSpec { inner })
    }
    fn __len__(&self) -> usize {
        usize::try_from(self.study.len()).unwrap_or(usize::MAX).saturating_sub(self.next)
    }
}

fn study_arg(py: Python<'_>, study: &Bound<'_, PyAny>) -> PyResult<Arc<study::Study>> {
    if let Ok(s) = study.extract::<PyRef<'_, PyStudy>>() {
        return Ok(s.inner.clone());
    }
    let path: PathBuf = study.extract().map_err(|_| {
        Kind::Scenario.err(
            py,
            format!(
                "study: expected a quell.Study or the path of a study file, found a {}",
                crate::convert::type_name(study)
            ),
        )
    })?;
    study::Study::from_path(&path).map(Arc::new).map_err(|e| study_error(py, &e))
}

/// The study's run specifications (picklable), for `run_one` on a cluster.
#[pyfunction]
pub fn sweep_runs(py: Python<'_>, study: &Bound<'_, PyAny>) -> PyResult<PyRunSpecs> {
    Ok(PyRunSpecs { study: study_arg(py, study)?, next: 0 })
}

/// Every run of a study, in parallel on `jobs` threads (default: every core), with the GIL
/// released; returns runs.csv's rows as a pandas DataFrame. Ctrl-C stops the sweep.
#[pyfunction]
#[pyo3(signature = (study, *, jobs=None, yes=false))]
pub fn sweep(
    py: Python<'_>,
    study: &Bound<'_, PyAny>,
    jobs: Option<&Bound<'_, PyAny>>,
    yes: bool,
) -> PyResult<Py<PyAny>> {
    let study = study_arg(py, study)?;
    let jobs = match jobs {
        None => None,
        Some(j) => match j.extract::<i128>() {
            Ok(n) if !j.is_instance_of::<pyo3::types::PyBool>() && (1..=study::MAX_JOBS as i128).contains(&n) => {
                Some(n as usize)
            }
            _ => {
                return Err(Kind::Scenario.err(
                    py,
                    format!(
                        "jobs: expected a number of threads from 1 to {} (None for one per core), found {}",
                        study::MAX_JOBS,
                        j.repr().map_or_else(|_| "?".to_string(), |r| r.to_string())
                    ),
                ))
            }
        },
    };
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
    let runs = usize::try_from(study.len()).unwrap_or(usize::MAX);
    let threads = jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.min(runs).max(1))
        .build()
        .map_err(|e| Kind::Scenario.err(py, format!("jobs: cannot start the threads ({e})")))?;
    let stop = AtomicBool::new(false);
    let mut interrupt = None;
    let swept = py.detach(|| {
        std::thread::scope(|scope| {
            let opts = SweepOptions { stop: Some(&stop), ..SweepOptions::default() };
            let (pool, study) = (&pool, &study);
            let worker = scope.spawn(move || pool.install(|| study::sweep(study, &opts)));
            while !worker.is_finished() {
                std::thread::sleep(Duration::from_millis(50));
                if let Err(e) = Python::attach(|py| py.check_signals()) {
                    stop.store(true, Ordering::Relaxed);
                    interrupt = Some(e);
                }
            }
            worker.join()
        })
    });
    if let Some(e) = interrupt {
        return Err(e);
    }
    let swept = swept.map_err(|_| pyo3::exceptions::PyRuntimeError::new_err("the sweep's threads panicked"))?;
    let meta = StudyMeta::new(&study, Shard::ALL);
    let mut text = Vec::new();
    study::write_runs_csv(&mut text, &meta, &swept.rows, swept.partial)
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    let text = String::from_utf8_lossy(&text).into_owned();
    Ok(py.import("quell._frames")?.call_method1("runs_frame", (text,))?.unbind())
}
