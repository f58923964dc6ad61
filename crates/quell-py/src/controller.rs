//! `quell.Controller`: the real-time controller, discretized exactly for a zero-order hold.

use numpy::{PyArray1, PyArrayMethods};
use std::sync::{Mutex, MutexGuard};

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyList, PyTuple};

use crate::convert::{number, vec_numpy, vector};
use crate::design::PyDesign;
use crate::errors::{raise, Kind};

/// The discrete-time adaptive controller of a design at sample time T_s, discretized exactly for a
/// zero-order hold (eqs. (5), (6), (14), (20), (25), (33)); `step` costs about 1 µs from Python. One
/// controller may be shared between threads: its calls are serialized by a lock held only while
/// Rust steps it. It pickles and copies with its state (a checkpoint: the copy continues bit for bit
/// as the original would), and two controllers are equal when their designs, sample times and states
/// are.
///
/// Parameters
/// ----------
/// design : Design
///     The design.
/// sample_time : float
///     T_s, in the plant's unit of time; every delay must be a whole number of samples.
///
/// Raises
/// ------
/// TypeError
///     An argument of the wrong type.
/// ScenarioError
///     A sample time that is not > 0 or does not divide the delays (the message names
///     `sample_time` and the nearest valid one).
///
/// Examples
/// --------
/// >>> c = quell.Controller(quell.paper_example().design(), 1e-3)
/// >>> c
/// Controller(m=2, q=8, sample_time=0.001)
/// >>> c.step([0.0, 0.0], [0.0, 2.0]).shape
/// (2,)
/// >>> import pickle
/// >>> copy = pickle.loads(pickle.dumps(c))
/// >>> copy == c
/// True
/// >>> bool(np.array_equal(copy.step([0.1, 0.0], [0.0, 2.0]), c.step([0.1, 0.0], [0.0, 2.0])))
/// True
#[pyclass(module = "quell", name = "Controller", frozen)]
pub struct PyController {
    inner: Mutex<quell::Controller>,
    m: usize,
    /// The design it was built from, for pickling and `==`.
    design: Py<PyDesign>,
}

impl PyController {
    /// The controller, locked (a panic cannot poison it: no Rust code here panics while holding it).
    fn lock(&self) -> MutexGuard<'_, quell::Controller> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// A copy of one of the controller's vectors, taken under the lock (numpy arrays are built
    /// after it is released).
    fn copy(&self, part: impl FnOnce(&quell::Controller) -> &[f64]) -> Vec<f64> {
        part(&self.lock()).to_vec()
    }
}

/// Reads a length-m vector into `out`: a float64 numpy vector or a list of numbers directly,
/// anything else through numpy. Wrong length or a non-finite entry is a ValueError naming `name`.
fn read(obj: &Bound<'_, PyAny>, name: &str, out: &mut [f64]) -> PyResult<()> {
    let py = obj.py();
    let m = out.len();
    let check = |v: &[f64], out: &mut [f64]| -> PyResult<()> {
        if v.len() != m {
            return Err(Kind::Controller.err(
                py,
                format!("{name}: expected {} (one per output), found {}", quell::settings::entries(m), v.len()),
            ));
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(Kind::Controller.err(py, format!("{name}[{i}]: expected a finite number, found {}", v[i])));
        }
        out.copy_from_slice(v);
        Ok(())
    };
    if let Ok(a) = obj.cast::<PyArray1<f64>>() {
        // SAFETY: the slice is read at once, while this thread is attached (abi3 builds have a
        // GIL, so no other thread can write the array meanwhile), and not kept. This skips
        // rust-numpy's borrow tracking, which costs more than the rest of a step.
        if let Ok(s) = unsafe { a.as_slice() } {
            return check(s, out);
        }
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        // Too long, refused before it is read: a list subclass reporting 10^12 entries had aborted
        // the interpreter allocating room for them (a short one keeps its own message: [[0, 0]]
        // is not 1-D).
        if let Some(n) = obj.len().ok().filter(|&n| n > m) {
            let expected = quell::settings::entries(m);
            return Err(Kind::Controller.err(py, format!("{name}: expected {expected} (one per output), found {n}")));
        }
        // Booleans (numpy's too: np.True_ had been read as 1) are refused as `Plant` refuses a
        // boolean array, not read as 0 and 1.
        let boolean = |x: &Bound<'_, PyAny>| x.is_instance_of::<PyBool>() || crate::convert::is_numpy_bool(x);
        if obj.try_iter().is_ok_and(|mut items| items.any(|x| x.is_ok_and(|x| boolean(&x)))) {
            return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                "{name}: expected real numbers, found booleans"
            )));
        }
        if let Ok(v) = obj.extract::<Vec<f64>>() {
            return check(&v, out);
        }
    }
    check(&vector(obj, name, Kind::Controller)?, out)
}

/// What `Controller.__reduce__` returns: the class, its arguments (design, T_s) and the state.
type Reduced<'py> = (Bound<'py, PyAny>, (Py<PyDesign>, f64), Bound<'py, PyArray1<f64>>);

#[pymethods]
impl PyController {
    #[new]
    fn new(design: &Bound<'_, PyAny>, sample_time: &Bound<'_, PyAny>) -> PyResult<Self> {
        let py = design.py();
        let d = design.cast::<PyDesign>().map_err(|_| crate::errors::type_error("design", "a quell.Design", design))?;
        let T = number(sample_time, "sample_time", Kind::Scenario, "sample_time")?;
        let inner = quell::Controller::new(&d.get().inner, T)
            .map_err(|e| crate::errors::keyed(py, Kind::Scenario, e.to_string(), e.key()))?;
        let (m, _) = inner.dims();
        // A design carries no signals: ρ from its poles alone.
        let none = quell::Signal::default();
        crate::errors::warn_coarse_sample(py, &d.get().inner, &none, &none, T, None)?;
        Ok(PyController { inner: Mutex::new(inner), m, design: d.clone().unbind() })
    }

    /// One sample: reads y(k) and g(k) and returns the plant input u_f(k) = −K x̂ + F u_d (5) to hold
    /// until the next sample.
    ///
    /// Parameters
    /// ----------
    /// y : array_like
    ///     The measured outputs y(k) (m).
    /// g : array_like
    ///     The reference g(k) (m).
    ///
    /// Returns
    /// -------
    /// numpy.ndarray
    ///     u_f(k) (m).
    ///
    /// Raises
    /// ------
    /// TypeError
    ///     An argument that is not an array of real numbers.
    /// ControllerError
    ///     A wrong length, an entry not finite or beyond ±1e100 (the state is kept), or a state that
    ///     overflowed.
    ///
    /// Examples
    /// --------
    /// >>> c = quell.Controller(quell.paper_example().design(), 1e-3)
    /// >>> u_f = c.step(np.zeros(2), np.array([0.0, 2.0]))
    /// >>> bool(np.all(np.isfinite(u_f)))
    /// True
    fn step<'py>(&self, y: &Bound<'py, PyAny>, g: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        // Read first (reading may call into Python), then step under the lock.
        let (mut y_k, mut g_k) = (vec![0.0; self.m], vec![0.0; self.m]);
        read(y, "y", &mut y_k)?;
        read(g, "g", &mut g_k)?;
        let u_f = self.lock().step(&y_k, &g_k).map(|u| u.to_vec()).map_err(|e| raise(y.py(), Kind::Controller)(&e))?;
        Ok(PyArray1::from_vec(y.py(), u_f))
    }

    /// The adaptive command u(k) (25) of the last step, undelayed.
    ///
    /// Returns
    /// -------
    /// numpy.ndarray
    ///     u(k) (m).
    ///
    /// Raises
    /// ------
    /// This method raises nothing.
    ///
    /// Examples
    /// --------
    /// >>> c = quell.Controller(quell.paper_example().design(), 1e-3)
    /// >>> c.command()
    /// array([0., 0.])
    fn command<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_numpy(py, &self.copy(|c| c.command()))
    }

    /// The adaptive parameters η̂_i after the last step, eq. (33).
    ///
    /// Returns
    /// -------
    /// numpy.ndarray
    ///     η̂ (m, q).
    ///
    /// Raises
    /// ------
    /// This method raises nothing.
    ///
    /// Examples
    /// --------
    /// >>> quell.Controller(quell.paper_example().design(), 1e-3).eta().shape
    /// (2, 8)
    fn eta<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let (m, q) = self.lock().dims();
        Ok(vec_numpy(py, &self.copy(|c| c.eta())).reshape([m, q])?.into_any())
    }

    /// The observer's estimate x̂ that the next step starts from, eq. (6).
    ///
    /// Returns
    /// -------
    /// numpy.ndarray
    ///     x̂ (n).
    ///
    /// Raises
    /// ------
    /// This method raises nothing.
    ///
    /// Examples
    /// --------
    /// >>> quell.Controller(quell.paper_example().design(), 1e-3).x_hat()
    /// array([0., 0., 0.])
    fn x_hat<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_numpy(py, &self.copy(|c| c.x_hat()))
    }

    /// The regressor ξ̂ = [ξ̂_g; ξ̂_ω] that the next step starts from, eqs. (14), (20).
    ///
    /// Returns
    /// -------
    /// numpy.ndarray
    ///     ξ̂ (q).
    ///
    /// Raises
    /// ------
    /// This method raises nothing.
    ///
    /// Examples
    /// --------
    /// >>> quell.Controller(quell.paper_example().design(), 1e-3).xi_hat().shape
    /// (8,)
    fn xi_hat<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_numpy(py, &self.copy(|c| c.xi_hat()))
    }

    /// Back to the initial state: every controller state and delay line zero.
    ///
    /// Returns
    /// -------
    /// None
    ///
    /// Raises
    /// ------
    /// This method raises nothing.
    ///
    /// Examples
    /// --------
    /// >>> c = quell.Controller(quell.paper_example().design(), 1e-3)
    /// >>> _ = c.step([1.0, 1.0], [0.0, 2.0])
    /// >>> c.reset()
    /// >>> c.x_hat()
    /// array([0., 0., 0.])
    fn reset(&self) {
        self.lock().reset();
    }

    /// Sample time T_s.
    #[getter]
    fn sample_time(&self) -> f64 {
        self.lock().sample_time()
    }

    /// Everything that evolves from step to step (the layout of Rust's `Controller::state`): the
    /// observers' state z (eqs. (6), (14), (20)); per channel its G_ii filter bank W_i, the H filters
    /// Y_i and Ω_i of (33) and its delay line, oldest row first; u (25) and u_f (5) of the last step;
    /// η̂ (33). What pickling saves with the design and the sample time.
    ///
    /// Returns
    /// -------
    /// numpy.ndarray
    ///     The state, a float64 vector.
    ///
    /// Raises
    /// ------
    /// This method raises nothing.
    ///
    /// Examples
    /// --------
    /// >>> c = quell.Controller(quell.paper_example().design(), 1e-2)
    /// >>> c.__getstate__().shape
    /// (3820,)
    fn __getstate__<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let state = self.lock().state();
        PyArray1::from_vec(py, state)
    }

    /// Continues from a state of `__getstate__` taken from a controller of the same design and
    /// sample time: the next steps equal that controller's to the last bit.
    ///
    /// Parameters
    /// ----------
    /// state : array_like
    ///     The state, as `__getstate__` returned it.
    ///
    /// Returns
    /// -------
    /// None
    ///
    /// Raises
    /// ------
    /// TypeError
    ///     A state that is not an array of real numbers.
    /// ControllerError
    ///     A state of the wrong length, with an entry that is not finite, or with an Ω_i that is not
    ///     exactly symmetric (the message names the entry); the controller is left as it was.
    ///
    /// Examples
    /// --------
    /// >>> d = quell.paper_example().design()
    /// >>> a, b = quell.Controller(d, 1e-2), quell.Controller(d, 1e-2)
    /// >>> _ = a.step([0.5, 0.0], [1.0, 2.0])
    /// >>> b.__setstate__(a.__getstate__())
    /// >>> a == b
    /// True
    fn __setstate__(&self, state: &Bound<'_, PyAny>) -> PyResult<()> {
        let py = state.py();
        // bytes iterate as ints: b"garbage" was read as 7 numbers, bytes(n) as n zeros.
        if state.is_instance_of::<pyo3::types::PyBytes>()
            || state.is_instance_of::<pyo3::types::PyByteArray>()
            || state.is_instance_of::<pyo3::types::PyString>()
        {
            return Err(crate::errors::type_error("state", "an array of real numbers", state));
        }
        // A numpy array of another shape is named by its dimensions, not as "a ndarray".
        let ndim = state.getattr("ndim").ok().and_then(|n| n.extract::<usize>().ok());
        if let Some(d) = ndim.filter(|&d| d != 1) {
            return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                "state: expected a 1-D array of real numbers (Controller.__getstate__()'s), found a {d}-D array"
            )));
        }
        // The length first: range(10**12) had aborted the interpreter allocating its entries.
        let expected = self.lock().state_len();
        if let Some(n) = state.len().ok().filter(|&n| n != expected) {
            let e = quell::ControllerError::StateLength { expected, found: n };
            return Err(raise(py, Kind::Controller)(&e));
        }
        let values = match state.cast::<PyArray1<f64>>() {
            Ok(a) => a.readonly().as_array().to_vec(),
            Err(_) => state
                .extract::<Vec<f64>>()
                .map_err(|_| crate::errors::type_error("state", "an array of real numbers", state))?,
        };
        self.lock().set_state(&values).map_err(|e| raise(py, Kind::Controller)(&e))
    }

    /// Pickles as the design, the sample time and the state: the copy continues where this one is.
    /// A controller whose state is no longer finite (after `StateNotFinite`) is refused: its copy
    /// could not be restored (a checkpoint taken at a fault had pickled, then failed to load).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Reduced<'py>> {
        let py = slf.py();
        let me = slf.get();
        if let Some(k) = me.lock().state().iter().position(|v| !v.is_finite()) {
            return Err(Kind::Controller.err(
                py,
                format!(
                    "Controller: its state is no longer finite (state[{k}]; the fault a step reported as StateNotFinite), so a pickle or copy of it could not be restored; reset() it first, or keep a checkpoint taken before the fault"
                ),
            ));
        }
        let T = me.lock().sample_time();
        Ok((slf.get_type().into_any(), (me.design.clone_ref(py), T), me.__getstate__(py)))
    }

    /// Equal controllers: equal designs and sample times, and the same state to the last bit (they
    /// step alike from here on).
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> PyResult<bool> {
        let Ok(o) = other.cast::<PyController>() else { return Ok(false) };
        let o = o.get();
        // Each lock is released before the next is taken (`c == c` takes the same one twice).
        let (T, state) = {
            let c = self.lock();
            (c.sample_time(), c.state())
        };
        let (T_o, state_o) = {
            let c = o.lock();
            (c.sample_time(), c.state())
        };
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        Ok(T.to_bits() == T_o.to_bits()
            && bits(&state) == bits(&state_o)
            && self.design.bind(other.py()).eq(o.design.bind(other.py()))?)
    }

    fn __repr__(&self) -> String {
        let c = self.lock();
        let (m, q) = c.dims();
        format!("Controller(m={m}, q={q}, sample_time={:?})", c.sample_time())
    }
}
