//! `quell.Plant`: the plant (1), ẋ = A x + B u_f + D ω, y = C x + Q ω, with the adaptive command's
//! delays τ_i.

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use quell::nalgebra::DMatrix;
use quell::TimeUnit;

use crate::convert::{a_type, matrix, to_numpy, type_name, vec_numpy, vector};
use crate::errors::Kind;

/// The plant (1) of the paper: ẋ = A x + B u_f(t) + D ω(t), y = C x + Q ω(t), driven by the
/// decoupling law u_f = −K x̂ + F u_d, where u_d,i(t) = u_i(t − τ_i) is adaptive command i delayed
/// by τ_i (the feedback −K x̂ acts without delay).
///
/// Parameters
/// ----------
/// A : array_like or control.StateSpace or control.TransferFunction
///     The state matrix (n×n); or a python-control system, which gives A, B, C and its signal
///     names (its D, python-control's feedthrough, must be zero; a transfer function is
///     realized minimally with `control.minreal` and `control.ss`).
/// B : array_like, optional
///     The input matrix (n×m); required unless A is a system.
/// C : array_like, optional
///     The output matrix (m×n); required unless A is a system.
/// D : array_like, optional
///     The disturbance-to-state matrix (n×k); None: no disturbance (k = 0).
/// Q : array_like, optional
///     The disturbance-to-output matrix (m×k); default zeros.
/// delays : array_like, optional
///     The input delays τ_i ≥ 0 (m), in the plant's unit of time; default zeros.
/// x0 : array_like, optional
///     The initial state x(0) (n); default zeros.
/// xhat0 : array_like, optional
///     The controller's initial estimate x̂(0) of it, where the observer (6) starts and a reset
///     returns (n); default zeros.
/// inputs, outputs, states : list of str, optional
///     The signals' names (m, m and n distinct names); default a system's labels, else
///     `u_f[i]`, `y[i]`, `x[j]`.
/// time_unit : str, optional
///     The unit of time the matrices and delays are written in: "µs" (or "us"), "ms", "s",
///     "min", "h" or "d", or its name ("minutes", …); it labels results and figures (quell
///     computes in whatever unit A is written in). Default None: seconds.
///
/// Raises
/// ------
/// TypeError
///     An argument of the wrong type (a string for a matrix, complex entries), or B or C
///     missing.
/// ScenarioError
///     A wrong shape, a non-finite entry, a negative delay, or names of the wrong number.
///
/// Examples
/// --------
/// >>> p = quell.Plant([[0.0, 1.0], [2.0, -1.0]], [[0.0], [1.0]], [[1.0, 0.0]], delays=[0.25],
/// ...                 outputs=["angle"])
/// >>> p.n, p.m, p.k, p.outputs, p.inputs
/// (2, 1, 0, ['angle'], ['u_f[1]'])
#[pyclass(module = "quell", name = "Plant", frozen)]
pub struct PyPlant {
    pub inner: quell::Plant,
    pub labels: Labels,
}

/// The names of a plant's signals (`inputs=`, `outputs=`, `states=`, a `control.StateSpace`'s
/// labels, or a scenario file's `[plant]` names); `None` where none were given: `u_f[i]`, `y[i]`,
/// `x[j]`, counting from 1.
pub use quell::scenario::SignalNames as Labels;

impl PyPlant {
    /// A plant without signal names.
    pub fn unlabelled(inner: quell::Plant) -> Self {
        PyPlant { inner, labels: Labels::default() }
    }
}

/// "state" for the states, "channel" for the inputs and outputs: what one name is for.
fn per(name: &str) -> &'static str {
    if name == "states" {
        "state"
    } else {
        "channel"
    }
}

/// `count` distinct names for `name` (a list of str), or None.
fn names(obj: Option<&Bound<'_, PyAny>>, name: &str, count: usize) -> PyResult<Option<Vec<String>>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else { return Ok(None) };
    let py = obj.py();
    let given = crate::convert::strings(obj, name, &format!("a list of {count} names (str)"), "a str (a signal name)")?;
    quell::scenario::check_names(name, &given, count, per(name)).map_err(|e| Kind::Scenario.err(py, e.to_string()))?;
    Ok(Some(given))
}

/// With a `control.TransferFunction` as A, the keywords that name its states (`D`, `x0`, `states`,
/// `xhat0`)
/// refused: its states are those of the minimal realization, which the user did not choose (a D
/// given with one had been read in the realization's coordinates: a disturbance's DC gain 5e8
/// where 2 was meant; helper tryout, 2026-12-07). Zeros mean the same in any coordinates.
fn refuse_state_keys(py: Python<'_>, [D, x0, states, xhat0]: [Option<&Bound<'_, PyAny>>; 4]) -> PyResult<()> {
    let k = Kind::Scenario;
    let nonzero =
        |values: Option<PyResult<Vec<f64>>>| values.is_some_and(|v| v.map_or(true, |v| v.iter().any(|&x| x != 0.0)));
    fn present<'a, 'py>(v: Option<&'a Bound<'py, PyAny>>) -> Option<&'a Bound<'py, PyAny>> {
        v.filter(|v| !v.is_none())
    }
    let d = nonzero(present(D).map(|v| matrix(v, "D", k).map(|m| m.as_slice().to_vec())));
    let x = nonzero(present(x0).map(|v| vector(v, "x0", k)));
    let xhat = nonzero(present(xhat0).map(|v| vector(v, "xhat0", k)));
    match [("D", d), ("x0", x), ("states", present(states).is_some()), ("xhat0", xhat)].iter().find(|(_, r)| *r) {
        Some((name, _)) => Err(k.err(py, format!("{name}: refers to the plant's states, but with a control.TransferFunction as A the states are those of its minimal realization (control.minreal, then control.ss), which you did not choose; give the plant as a control.StateSpace, or A, B, C, in the coordinates {name} is written in"))),
        None => Ok(()),
    }
}

/// A `control.StateSpace`'s labels of one kind (`<kind>_labels`, `count` of them) for the keyword
/// `name`, unless they are python-control's own (`u[0]`, `u[1]`, …, counting from 0) or quell's
/// (`u_f[1]`, …); checked as
/// the keyword's names are (python-control keeps one of repeated labels, so a repeat shows as a
/// missing name).
fn system_labels(sys: &Bound<'_, PyAny>, kind: &str, name: &str, count: usize) -> PyResult<Option<Vec<String>>> {
    let generic = match kind {
        "input" => "u",
        "output" => "y",
        _ => "x",
    };
    let attribute = format!("{kind}_labels");
    let Some(labels) = sys.getattr(attribute.as_str()).ok().and_then(|l| l.extract::<Vec<String>>().ok()) else {
        return Ok(None);
    };
    // quell's own defaults (u_f[1], y[1], x[1], …, as `to_control` and the loops write them) are
    // no names either: a plant sent to python-control and back is the same plant (`==`).
    let own = match kind {
        "input" => Labels::default().inputs(count),
        "output" => Labels::default().outputs(count),
        _ => Labels::default().states(count),
    };
    if (0..labels.len()).all(|i| labels[i] == format!("{generic}[{i}]")) || labels == own {
        return Ok(None);
    }
    quell::scenario::check_names(&format!("sys.{attribute}"), &labels, count, per(name)).map_err(|e| {
        let merged = if labels.len() < count { " (python-control keeps one of repeated labels)" } else { "" };
        Kind::Scenario.err(sys.py(), format!("{e}{merged}; or name them with quell.Plant(sys, {name}=[...])"))
    })?;
    Ok(Some(labels))
}

/// What a shape error of `key` means for a plant given as a python-control system (`system`) of
/// n states and m inputs: its D is quell's disturbance matrix, not python-control's feedthrough,
/// and inputs beyond the outputs' number may be disturbances, split off by indexing (a system
/// with a load torque as its third input had been told only to "add inputs"; helper tryout,
/// 2026-12-07).
fn system_hint(system: bool, key: &str, (n, m, k): (usize, usize, usize), outputs: usize) -> String {
    match key {
        _ if !system => String::new(),
        "D" => format!("; D here is the disturbance matrix of the plant (1), n×k = {n}×{k} into ẋ, not python-control's feedthrough sys.D"),
        "C" if outputs < m => format!("; where sys's last {} inputs are disturbances, give the first {outputs} alone and the rest as D: Plant(sys[:, :{outputs}], D=sys.B[:, {outputs}:])", m - outputs),
        _ => String::new(),
    }
}

/// Whether `obj` looks like a `control.StateSpace` (has A, B, C, D and nstates).
fn is_state_space(obj: &Bound<'_, PyAny>) -> bool {
    ["A", "B", "C", "D", "nstates"].iter().all(|a| obj.hasattr(*a).unwrap_or(false))
}

fn required<'a, 'py>(
    py: Python<'py>,
    v: Option<&'a Bound<'py, PyAny>>,
    name: &str,
    what: &str,
) -> PyResult<&'a Bound<'py, PyAny>> {
    let _ = py;
    v.ok_or_else(|| {
        PyTypeError::new_err(format!(
            "{name}: missing; required: {what} (or pass a control.StateSpace as the first argument)"
        ))
    })
}

/// A, B and C of a python-control state-space system `sys` (continuous, no feedthrough); `given_bc`
/// when B or C were passed besides it.
fn system_matrices(sys: &Bound<'_, PyAny>, given_bc: bool) -> PyResult<(DMatrix<f64>, DMatrix<f64>, DMatrix<f64>)> {
    let (py, k) = (sys.py(), Kind::Scenario);
    if given_bc {
        return Err(k.err(py, "B: the first argument is a state-space system, which gives A, B and C, so B and C are not passed beside it; pass D and Q (the disturbance matrices) as keywords: Plant(sys, D=..., Q=..., delays=...)"));
    }
    let dt = sys.getattr("dt").ok().filter(|d| !d.is_none());
    if let Some(dt) = dt {
        if dt.extract::<f64>().map_or(true, |v| v != 0.0) {
            return Err(k.err(py, format!("sys: expected a continuous-time system (dt = 0), found dt = {}; quell designs for continuous plants (sample the controller with Controller(design, sample_time)); a dead time is not dt: give it as the input delays, Plant(sys, delays=[...]) with a continuous sys", dt.str()?)));
        }
    }
    let (A, B, C) =
        (matrix(&sys.getattr("A")?, "A", k)?, matrix(&sys.getattr("B")?, "B", k)?, matrix(&sys.getattr("C")?, "C", k)?);
    let feedthrough = matrix(&sys.getattr("D")?, "sys.D", k)?;
    let rounding = feedthrough_rounding(&A, &B, &C);
    let nonzero = (0..feedthrough.nrows())
        .flat_map(|r| (0..feedthrough.ncols()).map(move |c| (r, c)))
        .find(|&at| feedthrough[at].abs() > rounding);
    if let Some((r, c)) = nonzero {
        return Err(k.err(py, format!("sys.D[{r}][{c}]: python-control's D is the feedthrough from u to y, which the plant (1) does not have; expected 0 (within rounding, {}), found {}; give the disturbance matrices as Plant(sys, D=..., Q=...)", quell::fmt_number(rounding), quell::fmt_number(feedthrough[(r, c)]))));
    }
    Ok((A, B, C))
}

/// The largest feedthrough entry taken for rounding's: 1e3·ε·‖C‖‖B‖/‖A‖ (Frobenius norms;
/// ‖C‖‖B‖ where A is 0), the size of C (sI − A)⁻¹ B's high-frequency scale to a thousand roundings
/// (`control.ss` of a realization had left 1e-17 there, refused as a feedthrough).
fn feedthrough_rounding(A: &DMatrix<f64>, B: &DMatrix<f64>, C: &DMatrix<f64>) -> f64 {
    let gain = C.norm() * B.norm();
    1e3 * f64::EPSILON * if A.norm() > 0.0 { gain / A.norm() } else { gain }
}

#[pymethods]
impl PyPlant {
    #[new]
    #[pyo3(signature = (A, B=None, C=None, D=None, Q=None, delays=None, x0=None, inputs=None, outputs=None, states=None, time_unit=None, xhat0=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        A: &Bound<'_, PyAny>,
        B: Option<&Bound<'_, PyAny>>,
        C: Option<&Bound<'_, PyAny>>,
        D: Option<&Bound<'_, PyAny>>,
        Q: Option<&Bound<'_, PyAny>>,
        delays: Option<&Bound<'_, PyAny>>,
        x0: Option<&Bound<'_, PyAny>>,
        inputs: Option<&Bound<'_, PyAny>>,
        outputs: Option<&Bound<'_, PyAny>>,
        states: Option<&Bound<'_, PyAny>>,
        time_unit: Option<&Bound<'_, PyAny>>,
        xhat0: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let py = A.py();
        let k = Kind::Scenario;
        if type_name(A) == "FrequencyResponseData" {
            return Err(PyTypeError::new_err("A: expected a matrix, a control.StateSpace or a control.TransferFunction, found a FrequencyResponseData (a frequency response holds no state-space model: fit one to it first, e.g. a transfer function)"));
        }
        // A control.TransferFunction becomes its minimal state-space realization, whose states no
        // D, x0 or state name can refer to.
        let realized;
        let A = if type_name(A) == "TransferFunction" {
            refuse_state_keys(py, [D, x0, states, xhat0])?;
            realized = py.import("quell._control")?.call_method1("state_space", (A,))?;
            &realized
        } else {
            A
        };
        let system = is_state_space(A).then_some(A);
        let (A, B, C) = if let Some(sys) = system {
            system_matrices(sys, B.is_some() || C.is_some())?
        } else {
            (
                matrix(A, "A", k)?,
                matrix(required(py, B, "B", "the n×m input matrix")?, "B", k)?,
                matrix(required(py, C, "C", "the m×n output matrix")?, "C", k)?,
            )
        };
        let (n, m) = (A.nrows(), B.ncols());
        let empty = |v: &Bound<'_, PyAny>| v.len().is_ok_and(|l| l == 0);
        let D = match D {
            Some(D) if !empty(D) => matrix(D, "D", k)?,
            _ => DMatrix::zeros(n, 0),
        };
        let Q = match Q {
            Some(Q) if !empty(Q) => matrix(Q, "Q", k)?,
            _ => DMatrix::zeros(m, D.ncols()),
        };
        let delays = match delays {
            Some(d) => vector(d, "delays", k)?,
            None => vec![0.0; m],
        };
        let x0 = x0.map(|x| vector(x, "x0", k)).transpose()?.map(quell::nalgebra::DVector::from_vec);
        let xhat0 = xhat0
            .filter(|v| !v.is_none())
            .map(|x| vector(x, "xhat0", k))
            .transpose()?
            .map(quell::nalgebra::DVector::from_vec);
        let (dims, measured) = ((n, m, D.ncols()), C.nrows());
        let inner = quell::Plant::new(A, B, C, D, Q, delays, x0).and_then(|p| p.with_xhat0(xhat0)).map_err(|e| {
            let (key, message) = e.explained(dims, "");
            k.err(py, format!("{key}: {message}{}", system_hint(system.is_some(), &key, dims, measured)))
        })?;
        let (n, m) = (inner.n(), inner.m());
        // A keyword's names, else the system's labels (checked only where no keyword overrides them).
        let label =
            |given: Option<&Bound<'_, PyAny>>, name: &str, kind: &str, count: usize| match names(given, name, count)? {
                Some(v) => Ok(Some(v)),
                None => system.map_or(Ok(None), |sys| system_labels(sys, kind, name, count)),
            };
        let labels = Labels {
            inputs: label(inputs, "inputs", "input", m)?,
            outputs: label(outputs, "outputs", "output", m)?,
            states: label(states, "states", "state", n)?,
        };
        Ok(PyPlant { inner: inner.with_time_unit(time_unit_arg(time_unit)?), labels })
    }

    /// State matrix A (n×n).
    #[getter]
    fn A<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, &self.inner.A).into_any()
    }
    /// Input matrix B (n×m).
    #[getter]
    fn B<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, &self.inner.B).into_any()
    }
    /// Output matrix C (m×n).
    #[getter]
    fn C<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, &self.inner.C).into_any()
    }
    /// Disturbance-to-state matrix D (n×k); not python-control's feedthrough.
    #[getter]
    fn D<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, &self.inner.D).into_any()
    }
    /// Disturbance-to-output matrix Q (m×k).
    #[getter]
    fn Q<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, &self.inner.Q).into_any()
    }
    /// Input delays τ_i (m,).
    #[getter]
    fn delays<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_numpy(py, &self.inner.delays).into_any()
    }
    /// Initial state x(0) (n,).
    #[getter]
    fn x0<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_numpy(py, self.inner.x0.as_slice()).into_any()
    }
    /// The controller's initial estimate x̂(0) (n,), where the observer starts.
    #[getter]
    fn xhat0<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_numpy(py, self.inner.xhat0.as_slice()).into_any()
    }
    /// State dimension n.
    #[getter]
    fn n(&self) -> usize {
        self.inner.n()
    }
    /// Channels m (inputs = outputs).
    #[getter]
    fn m(&self) -> usize {
        self.inner.m()
    }
    /// Disturbance components k.
    #[getter]
    fn k(&self) -> usize {
        self.inner.k()
    }

    /// Names of the inputs u_f (m): `inputs=`, a `control.StateSpace`'s input labels, or `u_f[i]`.
    #[getter]
    fn inputs(&self) -> Vec<String> {
        self.labels.inputs(self.inner.m())
    }
    /// Names of the outputs y (m): `outputs=`, a `control.StateSpace`'s output labels, or `y[i]`.
    #[getter]
    fn outputs(&self) -> Vec<String> {
        self.labels.outputs(self.inner.m())
    }
    /// Names of the states x (n): `states=`, a `control.StateSpace`'s state labels, or `x[j]`.
    #[getter]
    fn states(&self) -> Vec<String> {
        self.labels.states(self.inner.n())
    }
    /// The unit of time of A and the delays: `time_unit=`, or "s".
    #[getter]
    fn time_unit(&self) -> &'static str {
        self.inner.time_unit.symbol()
    }

    fn __repr__(&self) -> String {
        let p = &self.inner;
        format!("Plant(n={}, m={}, k={}, delays={:?})", p.n(), p.m(), p.k(), p.delays)
    }
    /// Equal plants: the same matrices, delays, x0, x̂0 and signal names, entry for entry.
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.cast::<PyPlant>().is_ok_and(|o| o.get().inner == self.inner && o.get().labels == self.labels)
    }
    /// Pickles as `Plant(A, B, C, D, Q, delays, x0, inputs, outputs, states, time_unit, xhat0)` (D and
    /// Q omitted without a disturbance, names and unit without them).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let (p, me) = (&slf.get().inner, slf.get());
        let disturbance = p.k() > 0;
        let l = &me.labels;
        let args = PyTuple::new(
            py,
            [
                me.A(py),
                me.B(py),
                me.C(py),
                if disturbance { me.D(py) } else { py.None().into_bound(py) },
                if disturbance { me.Q(py) } else { py.None().into_bound(py) },
                me.delays(py),
                me.x0(py),
                l.inputs.clone().into_pyobject(py)?,
                l.outputs.clone().into_pyobject(py)?,
                l.states.clone().into_pyobject(py)?,
                p.time_unit.symbol().into_pyobject(py)?.into_any(),
                me.xhat0(py),
            ],
        )?;
        Ok((slf.get_type().into_any(), args))
    }
}

/// `time_unit=`: a unit's symbol or name, or None.
fn time_unit_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<TimeUnit> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else { return Ok(TimeUnit::Seconds) };
    let given: String = obj.extract().map_err(|_| {
        PyTypeError::new_err(format!("time_unit: expected a str such as \"min\", found {}", a_type(obj)))
    })?;
    TimeUnit::from_name(&given).map_err(|e| Kind::Scenario.err(obj.py(), format!("time_unit: {e}")))
}

/// `obj` as a Plant, or a ScenarioError naming `name`.
pub fn plant_arg<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<PyRef<'py, PyPlant>> {
    obj.extract::<PyRef<'py, PyPlant>>().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name}: expected a quell.Plant, found {}; build one with quell.Plant(A, B, C, D, Q, delays=...)",
            a_type(obj)
        ))
    })
}
