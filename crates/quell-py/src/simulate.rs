//! `quell.simulate` and `quell.SimResult`: the closed loop, continuous (the delay equation) or
//! sampled-data (the real-time controller), with the GIL released while it runs.

use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use quell::controller::Precision;
use quell::sim::{Loop, Outcome, Peaks, Run, RunSettings, RunStats, SimError, SimResult, Stats};
use quell::TimeUnit;
use toml::Value;

use crate::errors::{keyed, simulation_error, Kind};
use crate::plant::Labels;
use crate::scenario::PyScenario;

/// How often a running simulation looks for Ctrl-C.
const SIGNAL_CHECK: Duration = Duration::from_millis(100);

/// The signals of a run at t = k·output_step, as read-only numpy arrays, and how it ended; what
/// `quell.simulate` returns (equal to `quell run`'s signals.csv).
///
/// Examples
/// --------
/// >>> r = quell.simulate(quell.paper_example(), t_end=1.0)
/// >>> r
/// SimResult(samples=11, m=2, q=8, outcome={'status': 'completed'})
/// >>> r.t.shape, r.y.shape, r.eta.shape
/// ((11,), (11, 2), (11, 2, 8))
/// >>> bool(np.array_equal(r.e, r.y - r.g))
/// True
#[pyclass(module = "quell", name = "SimResult", frozen)]
pub struct PySimResult {
    /// The run without its samples: those were handed to `arrays` and `states` (one copy of a
    /// record in memory, not two), with what is computed from them kept in `of_samples`.
    inner: SimResult,
    of_samples: OfSamples,
    /// t, y, g, e, u, u_f, eta.
    arrays: [Py<PyAny>; 7],
    /// x, x̂ when the run recorded them.
    states: Option<[Py<PyAny>; 2]>,
    /// The run's convergence diagnostics as JSON ([`quell::diagnostics::Diagnostics`]).
    diagnostics: String,
    /// The plant's signal names.
    labels: Labels,
}

/// What the result's methods compute from its samples, computed before the samples move to numpy.
struct OfSamples {
    len: usize,
    commands_held: bool,
    limited_fraction: Vec<f64>,
    summary: Vec<quell::sim::ChannelSummary>,
}

/// Whether a restored result's sizes agree: every signal's length is its rows times its width
/// (m, m·q, n), computed without overflow; per-channel figures at most m long, and m ≤ n within a
/// design's limit. A tampered pickle (q = 100, m = 2^40) had panicked in the
/// summary's slicing.
fn consistent(r: &quell::sim::SimResult) -> Result<(), &'static str> {
    let rows = r.t.len();
    let sized = |v: &[f64], width: usize| rows.checked_mul(width).is_some_and(|n| n == v.len());
    let (m, q, n) = (r.m, r.q, r.n);
    // A design's plant has at most MAX_STATES states and no more inputs than states.
    if m == 0 || q == 0 || n > quell::design::MAX_STATES || m > n {
        return Err("its m, q or n");
    }
    let signals = [&r.y, &r.g, &r.e, &r.u, &r.u_f].iter().all(|v| sized(v, m));
    let eta = m.checked_mul(q).is_some_and(|w| sized(&r.eta, w));
    let states = [&r.x, &r.x_hat].iter().all(|v| v.is_empty() || sized(v, n));
    let per_channel = [
        r.limited.len(),
        r.u_max.len(),
        r.u_min.len(),
        r.peak_u.len(),
        r.peak_uf.len(),
        r.peak_demand.len(),
        r.peak_e.len(),
        r.uf_terms.len(),
    ]
    .iter()
    .all(|&len| len <= m);
    match (signals, eta, states, per_channel) {
        (true, true, true, true) => Ok(()),
        (false, ..) => Err("its signals' lengths are not its rows times m"),
        (_, false, ..) => Err("η̂'s length is not its rows times m·q"),
        (_, _, false, _) => Err("its states' lengths are not its rows times n"),
        _ => Err("a per-channel figure longer than m"),
    }
}

/// `data` as a read-only numpy array of `shape`, owning the vector (no copy). The flat array the
/// shaped one views is frozen first: frozen after, its base stayed writable, so
/// `r.y.flags.writeable = True` was allowed and a write changed the stored result (hostile review).
fn frozen_array(py: Python<'_>, data: Vec<f64>, shape: &[usize]) -> PyResult<Py<PyAny>> {
    let flat = PyArray1::from_vec(py, data);
    let kwargs = PyDict::new(py);
    kwargs.set_item("write", false)?;
    flat.call_method("setflags", (), Some(&kwargs))?;
    Ok(flat.reshape(shape.to_vec())?.into_any().unbind())
}

impl PySimResult {
    /// A run of `scenario` with `design`, its convergence diagnostics computed.
    pub fn from_run(
        py: Python<'_>,
        scenario: &quell::Scenario,
        design: &quell::Design,
        r: SimResult,
        labels: Labels,
    ) -> PyResult<Self> {
        // Without the GIL: a sampled run's diagnostics run its continuous loop too.
        let diagnostics = py.detach(|| quell::diagnostics::diagnose_run(scenario, design, &r));
        PySimResult::new(py, r, serde_json::to_string(&diagnostics).unwrap_or_default(), labels)
    }

    fn new(py: Python<'_>, mut r: SimResult, diagnostics: String, labels: Labels) -> PyResult<Self> {
        let (k, m, q, n) = (r.len(), r.m, r.q, r.n);
        let of_samples = OfSamples {
            len: k,
            commands_held: r.commands_held(),
            limited_fraction: r.limited_fraction(),
            summary: r.summary(),
        };
        let take = |v: &mut Vec<f64>, shape: &[usize]| frozen_array(py, std::mem::take(v), shape);
        let arrays = [
            take(&mut r.t, &[k])?,
            take(&mut r.y, &[k, m])?,
            take(&mut r.g, &[k, m])?,
            take(&mut r.e, &[k, m])?,
            take(&mut r.u, &[k, m])?,
            take(&mut r.u_f, &[k, m])?,
            take(&mut r.eta, &[k, m, q])?,
        ];
        let states = match r.has_states() {
            true => Some([take(&mut r.x, &[k, n])?, take(&mut r.x_hat, &[k, n])?]),
            false => None,
        };
        Ok(PySimResult { inner: r, of_samples, arrays, states, diagnostics, labels })
    }

    /// The samples t, y, g, e, u, u_f, η̂ and, when recorded, x and x̂ (else empty), as slices of
    /// their numpy arrays.
    fn samples<'py>(&self, py: Python<'py>) -> PyResult<Vec<numpy::PyReadonlyArrayDyn<'py, f64>>> {
        let none: [Py<PyAny>; 2] = [
            PyArray1::<f64>::zeros(py, 0, false).into_any().unbind(),
            PyArray1::<f64>::zeros(py, 0, false).into_any().unbind(),
        ];
        let states = self.states.as_ref().unwrap_or(&none);
        self.arrays.iter().chain(states).map(|a| Ok(a.bind(py).cast::<numpy::PyArrayDyn<f64>>()?.readonly())).collect()
    }
}

fn outcome_dict<'py>(py: Python<'py>, o: &Outcome) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    match o {
        Outcome::Completed => d.set_item("status", "completed")?,
        Outcome::Diverged { t, signal, value } => {
            d.set_item("status", "diverged")?;
            d.set_item("t", t)?;
            d.set_item("signal", signal)?;
            d.set_item("value", value)?;
        }
        Outcome::StepSizeTooSmall { t } => {
            d.set_item("status", "step_size_too_small")?;
            d.set_item("t", t)?;
        }
        Outcome::Interrupted { t } => {
            d.set_item("status", "interrupted")?;
            d.set_item("t", t)?;
        }
        Outcome::TooManySteps { t, max_steps } => {
            d.set_item("status", "too_many_steps")?;
            d.set_item("t", t)?;
            d.set_item("max_steps", max_steps)?;
        }
        Outcome::HistoryTooLarge { t, max_bytes } => {
            d.set_item("status", "history_too_large")?;
            d.set_item("t", t)?;
            d.set_item("max_bytes", max_bytes)?;
        }
    }
    Ok(d)
}

/// An outcome from the `outcome` property's dict.
fn outcome_from(d: &Bound<'_, PyDict>) -> Option<Outcome> {
    let get = |k: &str| d.get_item(k).ok().flatten();
    let t: Option<f64> = get("t").and_then(|v| v.extract().ok());
    let status: String = get("status")?.extract().ok()?;
    Some(match status.as_str() {
        "completed" => Outcome::Completed,
        "diverged" => {
            Outcome::Diverged { t: t?, signal: get("signal")?.extract().ok()?, value: get("value")?.extract().ok()? }
        }
        "step_size_too_small" => Outcome::StepSizeTooSmall { t: t? },
        "interrupted" => Outcome::Interrupted { t: t? },
        "too_many_steps" => Outcome::TooManySteps { t: t?, max_steps: get("max_steps")?.extract().ok()? },
        "history_too_large" => Outcome::HistoryTooLarge { t: t?, max_bytes: get("max_bytes")?.extract().ok()? },
        _ => return None,
    })
}

/// Run statistics from the `stats` property's dict.
fn stats_from(d: &Bound<'_, PyDict>) -> Option<RunStats> {
    let int = |k: &str| d.get_item(k).ok().flatten()?.extract::<usize>().ok();
    Some(match int("controller_steps") {
        Some(controller_steps) => RunStats::Sampled {
            controller_steps,
            sample_time: d.get_item("sample_time").ok().flatten()?.extract().ok()?,
            // A pickle from before precisions were recorded is f64's.
            precision: match d.get_item("precision").ok().flatten() {
                Some(p) => Precision::from_name(&p.extract::<String>().ok()?)?,
                None => Precision::F64,
            },
        },
        None => RunStats::Continuous(Stats {
            steps: int("steps")?,
            rejected: int("rejected_steps")?,
            rhs_evals: int("rhs_evaluations")?,
            breakpoints: int("breakpoints")?,
            max_history_len: int("max_history_len")?,
            implicit_steps: int("implicit_steps").unwrap_or(0),
            switches: int("switches").unwrap_or(0),
            thrashed: d.get_item("thrashed").ok().flatten().and_then(|v| v.extract().ok()),
        }),
    })
}

#[pymethods]
impl PySimResult {
    /// Sample times (N,).
    #[getter]
    fn t(&self, py: Python<'_>) -> Py<PyAny> {
        self.arrays[0].clone_ref(py)
    }
    /// Outputs y (N, m).
    #[getter]
    fn y(&self, py: Python<'_>) -> Py<PyAny> {
        self.arrays[1].clone_ref(py)
    }
    /// References g (N, m).
    #[getter]
    fn g(&self, py: Python<'_>) -> Py<PyAny> {
        self.arrays[2].clone_ref(py)
    }
    /// Tracking errors e = y − g (N, m).
    #[getter]
    fn e(&self, py: Python<'_>) -> Py<PyAny> {
        self.arrays[3].clone_ref(py)
    }
    /// Adaptive commands u (25), undelayed (N, m).
    #[getter]
    fn u(&self, py: Python<'_>) -> Py<PyAny> {
        self.arrays[4].clone_ref(py)
    }
    /// Plant inputs u_f = −K x̂ + F u_d (5) as the plant receives them (N, m): clipped where
    /// `[truth] u_max` limits them (`summary()`'s `max_uf` is then the demand before the clip).
    #[getter]
    fn u_f(&self, py: Python<'_>) -> Py<PyAny> {
        self.arrays[5].clone_ref(py)
    }
    /// Adaptive parameters η̂_i (N, m, q), eq. (33).
    #[getter]
    fn eta(&self, py: Python<'_>) -> Py<PyAny> {
        self.arrays[6].clone_ref(py)
    }
    /// Plant states x (N, n), or None unless simulated with `states=True`.
    #[getter]
    fn x(&self, py: Python<'_>) -> Option<Py<PyAny>> {
        self.states.as_ref().map(|s| s[0].clone_ref(py))
    }
    /// Observer states x̂ (N, n), eq. (6), or None unless simulated with `states=True`.
    #[getter]
    fn x_hat(&self, py: Python<'_>) -> Option<Py<PyAny>> {
        self.states.as_ref().map(|s| s[1].clone_ref(py))
    }
    /// Plant order n.
    #[getter]
    fn n(&self) -> usize {
        self.inner.n
    }
    /// Channels m.
    #[getter]
    fn m(&self) -> usize {
        self.inner.m
    }
    /// Regressor size q.
    #[getter]
    fn q(&self) -> usize {
        self.inner.q
    }
    /// The unit of t: the plant's `time_unit` ("s" unless the plant gives another).
    #[getter]
    fn time_unit(&self) -> &'static str {
        self.inner.time_unit.symbol()
    }
    /// Whether u and u_f hold their value from one row to the next: a sampled-data run whose
    /// sample time is at least the row spacing (`plot` then draws them as staircases).
    #[getter]
    fn commands_held(&self) -> bool {
        self.of_samples.commands_held
    }
    /// Per input, the fraction of the recorded samples at which the true plant's actuator limit
    /// (`[truth] u_max`) clipped it, as summary.json's `limited_fraction`; None without limits.
    #[getter]
    fn limited_fraction(&self) -> Option<Vec<f64>> {
        (!self.inner.limited.is_empty()).then(|| self.of_samples.limited_fraction.clone())
    }
    /// How the run ended, as in summary.json: {"status": "completed"}, or "diverged" with t,
    /// signal and value, or "step_size_too_small" / "interrupted" with t.
    #[getter]
    fn outcome<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        outcome_dict(py, self.inner.outcome.as_ref().unwrap_or(&Outcome::Completed))
    }
    /// The loop's statistics, as summary.json's `stats`: `loop` ("continuous" or "sampled"); for the continuous loop the delay-equation
    /// solver's steps, rejected_steps, rhs_evaluations, breakpoints, max_history_len,
    /// implicit_steps (accepted on the implicit method), switches (between the methods) and
    /// thrashed ((start, end) of DOP853 thrashing before `auto` switched, else None); for the
    /// sampled-data loop controller_steps and sample_time.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        match self.inner.stats {
            RunStats::Continuous(s) => {
                d.set_item("loop", "continuous")?;
                d.set_item("steps", s.steps)?;
                d.set_item("rejected_steps", s.rejected)?;
                d.set_item("rhs_evaluations", s.rhs_evals)?;
                d.set_item("breakpoints", s.breakpoints)?;
                d.set_item("max_history_len", s.max_history_len)?;
                d.set_item("implicit_steps", s.implicit_steps)?;
                d.set_item("switches", s.switches)?;
                d.set_item("thrashed", s.thrashed)?;
            }
            RunStats::Sampled { controller_steps, sample_time, precision } => {
                d.set_item("loop", "sampled")?;
                d.set_item("controller_steps", controller_steps)?;
                d.set_item("sample_time", sample_time)?;
                d.set_item("precision", precision.name())?;
            }
        }
        Ok(d)
    }
    /// Per channel, the figures of summary.json.
    ///
    /// Returns
    /// -------
    /// list of dict
    ///     Per channel: tail max |e_i| and RMS e_i over the last 10 % of the horizon
    ///     (`tail_max_e`, `tail_rms_e`; None for a run that stopped before t_end), `max_u`, `max_uf` (the plant input as asked: above a clipping `[truth] u_max`),
    ///     `final_eta_norm` (‖η̂_i‖ at the end), `settle_t` (2 % band; None when not settled, or only
    ///     in the last 5 % of the horizon) and `settle_note` (why settle_t is None).
    ///
    /// Raises
    /// ------
    /// This method raises nothing.
    ///
    /// Examples
    /// --------
    /// >>> c = quell.simulate(quell.paper_example(), t_end=20.0).summary()[1]
    /// >>> sorted(c)
    /// ['final_eta_norm', 'max_u', 'max_uf', 'settle_note', 'settle_t', 'tail_max_e', 'tail_rms_e']
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.of_samples
            .summary
            .iter()
            .map(|c| {
                let d = PyDict::new(py);
                let f = &c.figures;
                // NaN (a run stopped before its tail, or a NaN in it) is None, as summary.json's null.
                let number = |v: f64| (!v.is_nan()).then_some(v);
                d.set_item("tail_max_e", number(f.tail_max_e))?;
                d.set_item("tail_rms_e", number(f.tail_rms_e))?;
                d.set_item("max_u", f.max_u)?;
                d.set_item("max_uf", f.max_uf)?;
                d.set_item("final_eta_norm", c.final_eta_norm)?;
                d.set_item("settle_t", f.settle_t)?;
                d.set_item("settle_note", c.settle_note.as_deref())?;
                Ok(d)
            })
            .collect()
    }
    /// Convergence diagnostics, as summary.json's (see docs/tuning.md).
    ///
    /// Returns
    /// -------
    /// dict
    ///     `{"channels": [...], "observer_fidelity": [...], "advice": [...]}`; per channel
    ///     lambda_min_omega, lambda_max_omega, convergence_time, adaptation_rate,
    ///     predicted_final_rms_e, tail_trend, tail_window, excitation and advice.
    ///
    /// Raises
    /// ------
    /// This method raises nothing.
    ///
    /// Examples
    /// --------
    /// >>> d = quell.simulate(quell.paper_example(), t_end=5.0).diagnostics()
    /// >>> len(d["channels"])
    /// 2
    fn diagnostics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py.import("json")?.call_method1("loads", (&self.diagnostics,))
    }
    /// The run as a `control.TimeResponseData`, so python-control's plotting and analysis apply.
    ///
    /// Returns
    /// -------
    /// control.TimeResponseData
    ///     Outputs y (m × samples) labelled with the plant's output names (`y[i]` by default);
    ///     inputs the adaptive commands u (labels `u[i]`); with `states=True` in the run, the
    ///     plant states x (n × samples) labelled with the plant's state names (`x[j]`).
    ///
    /// Raises
    /// ------
    /// ImportError
    ///     python-control is not installed.
    ///
    /// Examples
    /// --------
    /// >>> resp = quell.simulate(quell.paper_example(), t_end=1.0).to_control()
    /// >>> resp.outputs.shape, resp.output_labels
    /// ((2, 11), ['y[1]', 'y[2]'])
    fn to_control(slf: &Bound<'_, Self>) -> PyResult<Py<PyAny>> {
        let (labels, r) = (&slf.get().labels, &slf.get().inner);
        let (outputs, states) = (labels.outputs(r.m), labels.states(r.n));
        Ok(slf.py().import("quell._control")?.call_method1("to_control", (slf, outputs, states))?.unbind())
    }
    /// The columns of signals.csv as a pandas DataFrame.
    ///
    /// Returns
    /// -------
    /// pandas.DataFrame
    ///     One row per sample: t, y1.., g1.., e1.., u1.., uf1.., eta1_1.., and x1.., xhat1.. when
    ///     the run recorded states.
    ///
    /// Raises
    /// ------
    /// ImportError
    ///     pandas is not installed.
    ///
    /// Examples
    /// --------
    /// >>> df = quell.simulate(quell.paper_example(), t_end=1.0).to_pandas()
    /// >>> list(df.columns[:5]), len(df)
    /// (['t', 'y1', 'y2', 'g1', 'g2'], 11)
    fn to_pandas(slf: &Bound<'_, Self>) -> PyResult<Py<PyAny>> {
        Ok(slf.py().import("quell._frames")?.call_method1("to_pandas", (slf,))?.unbind())
    }
    /// The CLI's figure of one channel, like the paper's Figs. 1 and 2: y_i with g_i, e_i, the command
    /// u_i (25), the plant input u_f,i (5), η̂_i and the largest |e_i| from each t on (log scale)
    /// against t, in six panels.
    ///
    /// Parameters
    /// ----------
    /// channel : int, optional
    ///     The channel, from 1 (default 1).
    /// ax : matplotlib Axes or sequence of six, five or four, optional
    ///     One Axes (y_i and g_i only are drawn on it), six (every panel), five (all but the last) or
    ///     four (u_f,i on a second y axis of the third).
    /// figsize : (float, float), optional
    ///     Size of a new figure in inches (default (10, 16.5)).
    /// fig : matplotlib Figure, optional
    ///     A figure to add the six panels to.
    ///
    /// Returns
    /// -------
    /// matplotlib.figure.Figure
    ///     The figure drawn on.
    ///
    /// Raises
    /// ------
    /// TypeError
    ///     An argument of the wrong type.
    /// ValueError
    ///     A channel that is not from 1 to m.
    /// ImportError
    ///     matplotlib is not installed.
    ///
    /// Examples
    /// --------
    /// >>> fig = quell.simulate(quell.paper_example(), t_end=1.0).plot(channel=2, figsize=(6, 8))
    /// >>> len(fig.axes), fig.axes[0].get_title()
    /// (6, 'Channel 2: output and reference')
    #[pyo3(signature = (channel=None, *, ax=None, figsize=None, fig=None))]
    fn plot(
        slf: &Bound<'_, Self>,
        channel: Option<&Bound<'_, PyAny>>,
        ax: Option<&Bound<'_, PyAny>>,
        figsize: Option<&Bound<'_, PyAny>>,
        fig: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Py<PyAny>> {
        let f = slf.py().import("quell._frames")?.getattr("plot")?;
        let me = slf.get();
        let names = (me.labels.inputs.clone(), me.labels.outputs.clone());
        let limits = (me.inner.u_max.clone(), me.inner.u_min.clone());
        Ok(f.call1((slf, channel, fig, ax, figsize, names, limits.0, limits.1))?.unbind())
    }
    fn __len__(&self) -> usize {
        self.of_samples.len
    }
    /// Equal results: the same samples (bit for bit), outcome, statistics, peaks and signal names.
    fn __eq__(&self, py: Python<'_>, other: &Bound<'_, PyAny>) -> PyResult<bool> {
        let Ok(o) = other.cast::<PySimResult>() else { return Ok(false) };
        let (a, b) = (&self.inner, &o.get().inner);
        let same =
            |x: &[f64], y: &[f64]| x.len() == y.len() && x.iter().zip(y).all(|(u, v)| u.to_bits() == v.to_bits());
        let (ours, theirs) = (self.samples(py)?, o.get().samples(py)?);
        Ok((a.m, a.q, a.n) == (b.m, b.q, b.n)
            && ours.iter().zip(&theirs).all(|(x, y)| same(x.as_slice().unwrap_or(&[]), y.as_slice().unwrap_or(&[])))
            && a.outcome.as_ref().unwrap_or(&Outcome::Completed) == b.outcome.as_ref().unwrap_or(&Outcome::Completed)
            && a.stats == b.stats
            && same(&a.peaks.0, &b.peaks.0)
            && a.limited == b.limited
            && a.u_max == b.u_max
            && a.u_min == b.u_min
            && self.labels == o.get().labels
            && a.time_unit == b.time_unit)
    }
    /// Pickles as its samples (raw float64 bytes), outcome, statistics and diagnostics.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyDict>,))> {
        let py = slf.py();
        let me = slf.get();
        let r = &me.inner;
        let d = PyDict::new(py);
        d.set_item("m", r.m)?;
        d.set_item("q", r.q)?;
        d.set_item("n", r.n)?;
        let names = ["t", "y", "g", "e", "u", "u_f", "eta", "x", "x_hat"];
        for (name, v) in names.into_iter().zip(me.samples(py)?) {
            let bytes: Vec<u8> = v.as_slice()?.iter().flat_map(|x| x.to_le_bytes()).collect();
            d.set_item(name, PyBytes::new(py, &bytes))?;
        }
        d.set_item("outcome", me.outcome(py)?)?;
        d.set_item("stats", me.stats(py)?)?;
        d.set_item("peaks", r.peaks.0.to_vec())?;
        d.set_item("limited", r.limited.clone())?;
        d.set_item("u_max", r.u_max.clone())?;
        d.set_item("u_min", r.u_min.clone())?;
        d.set_item("peak_u", r.peak_u.clone())?;
        d.set_item("peak_uf", r.peak_uf.clone())?;
        d.set_item("peak_demand", r.peak_demand.clone())?;
        d.set_item("peak_e", r.peak_e.clone())?;
        d.set_item("uf_terms", r.uf_terms.clone())?;
        d.set_item("diagnostics", &me.diagnostics)?;
        let l = &me.labels;
        let unit = me.inner.time_unit.symbol();
        d.set_item("labels", (l.inputs.clone(), l.outputs.clone(), l.states.clone(), unit))?;
        Ok((slf.get_type().getattr("_restore")?, (d,)))
    }
    /// Rebuilds a pickled result.
    #[staticmethod]
    fn _restore(py: Python<'_>, state: &Bound<'_, PyDict>) -> PyResult<Self> {
        let bad = |what: &str| Kind::Scenario.err(py, format!("state: not a pickled quell.SimResult ({what})"));
        let item = |k: &str| state.get_item(k)?.ok_or_else(|| bad(&format!("no {k}")));
        let floats = |k: &str| -> PyResult<Vec<f64>> {
            let b: Vec<u8> = item(k)?.extract()?;
            Ok(b.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8]))).collect())
        };
        // Results pickled before `time_unit` hold three labels.
        let labels = item("labels")?;
        let (inputs, outputs, states, unit): (_, _, _, String) =
            labels.extract().or_else(|_| labels.extract().map(|(i, o, s)| (i, o, s, "s".to_string())))?;
        let time_unit = TimeUnit::from_name(&unit).map_err(|_| bad("time_unit"))?;
        let peaks: Vec<f64> = item("peaks")?.extract()?;
        let r = SimResult {
            m: item("m")?.extract()?,
            q: item("q")?.extract()?,
            n: item("n")?.extract()?,
            t: floats("t")?,
            y: floats("y")?,
            g: floats("g")?,
            e: floats("e")?,
            u: floats("u")?,
            u_f: floats("u_f")?,
            eta: floats("eta")?,
            x: floats("x")?,
            x_hat: floats("x_hat")?,
            stats: stats_from(&item("stats")?.cast_into::<PyDict>()?).ok_or_else(|| bad("stats"))?,
            outcome: Some(outcome_from(&item("outcome")?.cast_into::<PyDict>()?).ok_or_else(|| bad("outcome"))?),
            peaks: Peaks(peaks.try_into().map_err(|_| bad("peaks"))?),
            limited: item("limited")?.extract()?,
            // Results pickled before `u_max` have none.
            u_max: state.get_item("u_max")?.map_or(Ok(vec![]), |v| v.extract())?,
            // Results pickled before `u_min` have none: the range was −u_max … u_max.
            u_min: match state.get_item("u_min")? {
                Some(v) => v.extract()?,
                None => state
                    .get_item("u_max")?
                    .map_or(Ok(vec![]), |v| v.extract::<Vec<f64>>())?
                    .iter()
                    .map(|u| -u)
                    .collect(),
            },
            // Results pickled before the peaks between rows have none.
            peak_u: state.get_item("peak_u")?.map_or(Ok(vec![]), |v| v.extract())?,
            peak_uf: state.get_item("peak_uf")?.map_or(Ok(vec![]), |v| v.extract())?,
            // Results pickled before the actuator's demand have none.
            peak_demand: state.get_item("peak_demand")?.map_or(Ok(vec![]), |v| v.extract())?,
            // And before the error's.
            peak_e: state.get_item("peak_e")?.map_or(Ok(vec![]), |v| v.extract())?,
            uf_terms: state.get_item("uf_terms")?.map_or(Ok(vec![]), |v| v.extract())?,
            time_unit,
        };
        consistent(&r).map_err(bad)?;
        PySimResult::new(py, r, item("diagnostics")?.extract()?, Labels { inputs, outputs, states })
    }
    /// Python's repr, the outcome as the `outcome` property's dict.
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!(
            "SimResult(samples={}, m={}, q={}, outcome={})",
            self.of_samples.len,
            self.inner.m,
            self.inner.q,
            self.outcome(py)?.repr()?
        ))
    }
}

/// `precision=`: "f64" or "f32", for a sampled-data run only.
fn precision_argument(py: Python<'_>, value: &Bound<'_, PyAny>, sampled: bool) -> PyResult<Precision> {
    let name: String =
        value.extract().map_err(|_| crate::errors::type_error("precision", "\"f64\" or \"f32\"", value))?;
    let key = Some("simulation.precision".to_string());
    let Some(precision) = Precision::from_name(&name) else {
        return Err(keyed(py, Kind::Scenario, format!("precision: expected \"f64\" or \"f32\", found {name:?}"), key));
    };
    if precision != Precision::F64 && !sampled {
        let msg = format!("precision: {name} is the discrete controller's, and this run is the continuous loop; pass sample_time (or a scenario with simulation.sample_time), or leave precision out");
        return Err(keyed(py, Kind::Scenario, msg, key));
    }
    Ok(precision)
}

/// The cautions before a run, as Python warnings: DOP853 forced on a stiff law (`set_by` says
/// where), a rate or a delay that makes it costly, a delay beyond its horizon.
fn warn_before_run(py: Python<'_>, run: &quell::sim::Run<'_>, set_by: &str) -> PyResult<()> {
    let cautions = [
        quell::sim::explicit_stiff_warning(run, set_by),
        quell::sim::fast_rate_warning(run),
        quell::sim::delay_beyond_horizon(run),
    ];
    for w in cautions.into_iter().flatten() {
        crate::errors::warn(py, &crate::errors::in_python(w))?;
    }
    Ok(())
}

/// Simulates a scenario's closed loop: the continuous-time controller on the delay equation, or,
/// with a sample time, the sampled-data loop with the real-time controller; the plant simulated is
/// the scenario's truth where it has one. The GIL is released; Ctrl-C stops the run.
///
/// Parameters
/// ----------
/// scenario : Scenario
///     The scenario.
/// t_end, output_step, rtol, atol, sample_time : float, optional
///     Override the scenario's simulation settings.
/// continuous : bool, optional
///     Run the continuous loop even where the scenario sets simulation.sample_time (to compare the
///     sampled-data loop with the one it approximates); not with sample_time.
/// method : str, optional
///     The continuous loop's integrator, overriding the scenario's: "auto" (DOP853, implicit in the
///     adaptive parameters η̂ while their law is stiff; the default), "explicit" (DOP853
///     throughout) or "imex" (the implicit–explicit ARK4(3)6L[2]SA throughout, implicit in η̂).
///     Not for a sampled-data run.
/// max_steps : int, optional
///     The continuous solver's step budget, and with it the delay history's memory budget
///     (default: both derived from the problem; docs/running.md, "Every run is bounded").
/// states : bool, optional
///     Record the plant and observer states x, x̂ too.
/// check : bool, optional
///     Raise SimulationError when the run does not reach t_end (default True); False returns
///     the result whatever its outcome.
/// precision : str, optional
///     The discrete controller's arithmetic in a sampled-data run, overriding the scenario's:
///     "f64" (the default) or "f32", the loop as a single-precision build (`quell export
///     --precision f32`) runs it, emulated (constants, inputs and states rounded to float).
///
/// Returns
/// -------
/// SimResult
///     The signals and how the run ended.
///
/// Raises
/// ------
/// TypeError
///     An argument of the wrong type.
/// ScenarioError
///     An override that is not valid (named as the argument: `sample_time`, not
///     `simulation.sample_time`; an unknown `method` with the nearest name).
/// DesignError
///     No design exists for the scenario.
/// SimulationError
///     With check, a run that diverged or failed; its `.result` holds the samples up to then.
/// KeyboardInterrupt
///     Ctrl-C; its `.result` holds the samples up to then (outcome "interrupted").
///
/// Examples
/// --------
/// >>> r = quell.simulate(quell.paper_example(), t_end=2.0, sample_time=1e-3)
/// >>> r.stats
/// {'loop': 'sampled', 'controller_steps': 2001, 'sample_time': 0.001, 'precision': 'f64'}
/// >>> explicit = quell.simulate(quell.paper_example(), t_end=5.0, method="explicit")
/// >>> imex = quell.simulate(quell.paper_example(), t_end=5.0, method="imex")
/// >>> bool(np.abs(explicit.y - imex.y).max() < 1e-6)
/// True
#[pyfunction]
#[pyo3(signature = (scenario, *, t_end=None, output_step=None, rtol=None, atol=None, sample_time=None, continuous=false, method=None, max_steps=None, states=false, check=true, precision=None))]
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    t_end: Option<&Bound<'_, PyAny>>,
    output_step: Option<&Bound<'_, PyAny>>,
    rtol: Option<&Bound<'_, PyAny>>,
    atol: Option<&Bound<'_, PyAny>>,
    sample_time: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = crate::convert::argument::continuous)] continuous: bool,
    method: Option<&Bound<'_, PyAny>>,
    max_steps: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = crate::convert::argument::states)] states: bool,
    #[pyo3(from_py_with = crate::convert::argument::check)] check: bool,
    precision: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PySimResult>> {
    let s: PyRef<'_, PyScenario> =
        scenario.extract().map_err(|_| crate::errors::type_error("scenario", "a quell.Scenario", scenario))?;
    let design = s.design_arc(py)?;
    let method = method.filter(|v| !v.is_none());
    let sample_time = sample_time.filter(|v| !v.is_none());
    if continuous && sample_time.is_some() {
        return Err(keyed(py, Kind::Scenario, BOTH_LOOPS.into(), Some("continuous".into())));
    }
    let mut edited = with_overrides(py, &s.inner, [t_end, output_step, rtol, atol, sample_time], method)?;
    if continuous && s.inner.simulation.sample_time.is_some() {
        let scn = edited.get_or_insert_with(|| s.inner.clone());
        scn.simulation = scn.simulation.continuous();
    }
    if let Some(p) = precision.filter(|v| !v.is_none()) {
        let sampled = edited.as_ref().unwrap_or(&s.inner).simulation.sample_time.is_some();
        let precision = precision_argument(py, p, sampled)?;
        edited.get_or_insert_with(|| s.inner.clone()).simulation.precision = precision;
    }
    let scn = edited.as_ref().unwrap_or(&s.inner);
    let mut settings = RunSettings::of(scn);
    settings.record_states = states;
    if let (Some(_), Loop::Sampled { sample_time }) = (&method, &settings.mode) {
        let msg = format!("method: the integrator applies to the continuous loop only, and this run is the sampled-data loop at sample_time = {sample_time} {}; leave method out, or pass continuous=True (in place of any sample_time)", scn.plant.time_unit);
        return Err(keyed(py, Kind::Scenario, msg, Some("simulation.method".into())));
    }
    settings
        .set_max_steps(step_budget(py, max_steps)?)
        .map_err(|e| keyed(py, Kind::Scenario, e.to_string(), Some(e.key.clone())))?;
    let sampled = match settings.mode {
        Loop::Sampled { sample_time } => Some((sample_time, settings.output_step)),
        Loop::Continuous(_) => None,
    };
    let set_by = if method.is_some() { "method=\"explicit\"" } else { quell::sim::EXPLICIT_IN_FILE };
    let run = quell::sim::Run::of(scn, &design).settings(settings.clone());
    warn_before_run(py, &run, set_by)?;
    let given = set_here([t_end, output_step, rtol, atol, sample_time, method, precision]);
    let (result, interrupt) = run_released(py, scn, &design, settings, (s.from_values, &given))?;
    // After the run's own checks (a sample time they refuse gets no warning).
    if let Some((t, h)) = sampled {
        crate::errors::warn_coarse_sample(py, &design, &scn.reference, &scn.disturbance, t, Some(h))?;
    }
    let (outcome, unit) = (result.outcome.clone().unwrap_or(Outcome::Completed), result.time_unit);
    let culprit = quell::sim::budget_culprit(&run, &result);
    let result = Py::new(py, PySimResult::from_run(py, scn, &design, result, s.labels.clone())?)?;
    if let Some(e) = interrupt {
        // Ctrl-C keeps the samples up to it, as sweeps and tunings keep their rows.
        e.value(py).setattr("result", result)?;
        return Err(e);
    }
    match failure(outcome, unit) {
        Some((message, t, signal, value)) if check => {
            let message = match culprit {
                Some(c) => format!("{message}; {c}"),
                None => message,
            };
            Err(simulation_error(py, message, t, signal, value, result.into_any()))
        }
        _ => Ok(result),
    }
}

/// The scenario with the given `[simulation]` overrides ([`crate::scenario::write_simulation`]),
/// read again through the scenario's own checks; `None` when nothing is overridden.
fn with_overrides(
    py: Python<'_>,
    s: &quell::Scenario,
    numbers: [Option<&Bound<'_, PyAny>>; 5],
    method: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<quell::Scenario>> {
    if method.is_none() && numbers.iter().all(Option::is_none) {
        return Ok(None);
    }
    let mut doc = s.to_table();
    if let Some(Value::Table(sim)) = doc.get_mut("simulation") {
        crate::scenario::write_simulation(sim, numbers, method)?;
    }
    quell::Scenario::from_document(&doc).map(Some).map_err(|e| crate::scenario::argument_error(py, &e))
}

/// `max_steps=`: None, or an int ≥ 1.
fn step_budget(py: Python<'_>, max_steps: Option<&Bound<'_, PyAny>>) -> PyResult<Option<usize>> {
    match max_steps.filter(|v| !v.is_none()) {
        None => Ok(None),
        Some(v) => match crate::convert::as_int(v).map(|n| n.extract::<usize>()) {
            None => Err(crate::errors::type_error("max_steps", "an int (a step budget) or None", v)),
            Some(Ok(n)) if n >= 1 => Ok(Some(n)),
            _ => {
                let found = v.repr().map_or_else(|_| "?".to_string(), |r| r.to_string());
                let msg =
                    format!("max_steps: expected a step budget, an integer from 1 to {}, found {found}", usize::MAX);
                Err(keyed(py, Kind::Scenario, msg, Some("max_steps".into())))
            }
        },
    }
}

/// `simulate(continuous=True, sample_time=…)`.
const BOTH_LOOPS: &str =
    "continuous: True asks for the continuous loop and sample_time for the sampled-data loop; give one of them";

/// The `[simulation]` keys this call of `simulate` set, by the keyword's name (which is the key's
/// last name): a file's scenario names the others as the file does.
fn set_here(values: [Option<&Bound<'_, PyAny>>; 7]) -> Vec<&'static str> {
    let names = ["t_end", "output_step", "rtol", "atol", "sample_time", "method", "precision"];
    names.into_iter().zip(values).filter(|(_, v)| v.is_some_and(|v| !v.is_none())).map(|(n, _)| n).collect()
}

/// The run with the GIL released, looking for Ctrl-C every [`SIGNAL_CHECK`]: its result, and the
/// KeyboardInterrupt that stopped it (the result then holds the samples up to it). The run first
/// reserves its memory bound from the budget that runs under way share ([`Run::reserve_memory`]),
/// so that threads calling `quell.simulate` at once wait rather than take the machine's memory; a
/// Ctrl-C while it waits ends the run at its first progress check. Its errors name keys in
/// Python's spelling where the scenario is Python's values (`from_values`) or the call set that
/// key (`given`, [`set_here`]); a file's scenario names the others as the file does.
fn run_released(
    py: Python<'_>,
    scn: &quell::Scenario,
    design: &quell::Design,
    settings: RunSettings,
    (from_values, given): (bool, &[&str]),
) -> PyResult<(SimResult, Option<PyErr>)> {
    // A Mutex, not a RefCell: the closures run with the GIL released, so must be Send.
    let interrupt: std::sync::Mutex<Option<PyErr>> = std::sync::Mutex::new(None);
    let ctrl_c = crate::interrupt::CtrlC::new();
    let seen = || interrupt.lock().unwrap_or_else(std::sync::PoisonError::into_inner).is_some();
    let interrupted = || {
        if !seen() {
            if let Err(e) = ctrl_c.check() {
                *interrupt.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = Some(e);
            }
        }
        seen()
    };
    let result = py.detach(|| {
        let run = Run::of(scn, design).settings(settings);
        let _memory = run.reserve_memory(&interrupted);
        let mut last = Instant::now();
        let progress = |_t: f64| {
            if !seen() && last.elapsed() < SIGNAL_CHECK {
                return ControlFlow::Continue(());
            }
            last = Instant::now();
            if interrupted() {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        };
        run.simulate(progress)
    });
    let interrupt = interrupt.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner);
    let result = result.map_err(|e| {
        // `.key` as for the same setting refused when the scenario is read (argument_error).
        let key = match &e {
            SimError::Input(k) => Some(k.key.clone()),
            SimError::Controller(c) => c.key(),
        };
        let set_here = key.as_deref().and_then(|k| k.strip_prefix("simulation.")).is_some_and(|k| given.contains(&k));
        crate::errors::keyed_as(py, Kind::Scenario, e.to_string(), key, from_values || set_here)
    });
    match (result, interrupt) {
        (Ok(r), interrupt) => Ok((r, interrupt)),
        (Err(_), Some(e)) | (Err(e), None) => Err(e),
    }
}

/// Why a run that did not complete failed, for SimulationError: message, time, signal and value.
fn failure(outcome: Outcome, unit: quell::TimeUnit) -> Option<(String, f64, Option<String>, Option<f64>)> {
    let why = outcome.explain("max_steps=", unit)?;
    Some(match outcome {
        Outcome::Interrupted { t } => (why, t, None, None),
        Outcome::Diverged { t, signal, value } => (with_result(why), t, Some(signal), Some(value)),
        Outcome::StepSizeTooSmall { t } | Outcome::TooManySteps { t, .. } | Outcome::HistoryTooLarge { t, .. } => {
            (with_result(why), t, None, None)
        }
        Outcome::Completed => return None,
    })
}

fn with_result(why: String) -> String {
    why + "; the samples up to then are in the exception's .result"
}
