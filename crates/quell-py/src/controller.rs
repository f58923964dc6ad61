//! `quell.Controller`: the real-time controller, discretized exactly for a zero-order hold.

use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};

use crate::convert::{number, type_name, vec_numpy, vector};
use crate::design::PyDesign;
use crate::errors::{in_arguments, raise, Kind};

/// The discrete-time adaptive controller of a design at sample time T_s (eqs. (5), (6), (14),
/// (20), (25), (33)). `step` allocates nothing in Rust and costs about 1 µs from Python.
#[pyclass(module = "quell", name = "Controller")]
pub struct PyController {
    inner: quell::Controller,
    y: Vec<f64>,
    g: Vec<f64>,
}

/// Reads a length-m vector into `out`: a float64 numpy vector or a list of numbers directly,
/// anything else through numpy. Wrong length or a non-finite entry is a ValueError naming `name`.
fn read(obj: &Bound<'_, PyAny>, name: &str, out: &mut [f64]) -> PyResult<()> {
    let py = obj.py();
    let m = out.len();
    let check = |v: &[f64], out: &mut [f64]| -> PyResult<()> {
        if v.len() != m {
            return Err(
                Kind::Value.err(py, format!("{name}: expected {m} entries (one per output), found {}", v.len()))
            );
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(Kind::Value.err(py, format!("{name}[{i}]: expected a finite number, found {}", v[i])));
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
        if let Ok(v) = obj.extract::<Vec<f64>>() {
            return check(&v, out);
        }
    }
    check(&vector(obj, name, Kind::Value)?, out)
}

#[pymethods]
impl PyController {
    #[new]
    fn new(design: &Bound<'_, PyAny>, sample_time: &Bound<'_, PyAny>) -> PyResult<Self> {
        let py = design.py();
        let d: PyRef<'_, PyDesign> = design.extract().map_err(|_| {
            Kind::Value.err(py, format!("design: expected a quell.Design, found a {}", type_name(design)))
        })?;
        let T = number(sample_time, "sample_time", Kind::Scenario)?;
        let inner =
            quell::Controller::new(&d.inner, T).map_err(|e| Kind::Scenario.err(py, in_arguments(e.to_string())))?;
        let (m, _) = inner.dims();
        Ok(PyController { inner, y: vec![0.0; m], g: vec![0.0; m] })
    }

    /// One sample: reads y(k) and g(k) (m each) and returns the plant input u_f(k) = −K x̂ + F u_d (5)
    /// to hold until the next sample.
    fn step<'py>(&mut self, y: &Bound<'py, PyAny>, g: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        read(y, "y", &mut self.y)?;
        read(g, "g", &mut self.g)?;
        let u_f = self.inner.step(&self.y, &self.g).map_err(|e| raise(y.py(), Kind::Value)(&e))?;
        Ok(PyArray1::from_slice(y.py(), u_f))
    }

    /// The adaptive command u(k) (25) of the last step, undelayed (m,).
    fn command<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_numpy(py, self.inner.command())
    }

    /// η̂_i after the last step (m, q), eq. (33).
    fn eta<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let (m, q) = self.inner.dims();
        Ok(vec_numpy(py, self.inner.eta()).reshape([m, q])?.into_any())
    }

    /// The observer's estimate x̂ (n,) that the next step starts from, eq. (6).
    fn x_hat<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_numpy(py, self.inner.x_hat())
    }

    /// The regressor ξ̂ = [ξ̂_g; ξ̂_ω] (q,) that the next step starts from, eqs. (14), (20).
    fn xi_hat<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_numpy(py, self.inner.xi_hat())
    }

    /// Back to the initial state: every controller state and delay line zero.
    fn reset(&mut self) {
        self.inner.reset();
    }

    /// Sample time T_s.
    #[getter]
    fn sample_time(&self) -> f64 {
        self.inner.sample_time()
    }

    fn __repr__(&self) -> String {
        let (m, q) = self.inner.dims();
        format!("Controller(m={m}, q={q}, sample_time={})", self.inner.sample_time())
    }
}
