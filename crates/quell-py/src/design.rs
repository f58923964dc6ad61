//! `quell.design`, `quell.Design` and `quell.place`: every gain of Sections III–V.

use std::sync::Arc;

use pyo3::prelude::*;
use pyo3::types::{PyComplex, PyDict, PyList, PyTuple};
use quell::design::{DesignSpec, ObserverChoice};

use crate::convert::{complex_numpy, matrix, number, pole_lists, poles, to_numpy, type_name, vector};
use crate::errors::{in_python, type_error, Kind};
use crate::plant::{plant_arg, Labels, PyPlant};

/// Every gain of Sections III–V (K, F, L, N, the internal models, μ, β) and the assumption checks
/// that were passed to get them; built by `quell.design` or `Scenario.design`.
///
/// Examples
/// --------
/// >>> d = quell.paper_example().design()
/// >>> d
/// Design(n=3, m=2, q=8, sigma=[2, 1], mu=[20.0, 30.0], beta=1.0)
/// >>> d.K.shape, d.F.shape, d.L.shape
/// ((2, 3), (2, 2), (3, 2))
/// >>> bool(np.all(np.real(d.observer_eigenvalues) < 0))
/// True
#[pyclass(module = "quell", name = "Design", frozen)]
pub struct PyDesign {
    pub inner: Arc<quell::Design>,
    /// The choices it was designed with.
    pub spec: DesignSpec,
    /// The plant's signal names.
    pub labels: Labels,
}

/// Poles as Python values: real ones as float, the others as complex.
fn py_poles<'py>(py: Python<'py>, poles: &[quell::nalgebra::Complex<f64>]) -> PyResult<Bound<'py, PyList>> {
    let items: Vec<Bound<'py, PyAny>> = poles
        .iter()
        .map(|z| match z.im {
            0.0 => Ok(z.re.into_pyobject(py)?.into_any()),
            _ => Ok(PyComplex::from_doubles(py, z.re, z.im).into_any()),
        })
        .collect::<PyResult<_>>()?;
    PyList::new(py, items)
}

fn py_pole_lists<'py>(py: Python<'py>, lists: &[Vec<quell::nalgebra::Complex<f64>>]) -> PyResult<Bound<'py, PyList>> {
    PyList::new(py, lists.iter().map(|p| py_poles(py, p)).collect::<PyResult<Vec<_>>>()?)
}

/// The designer's choices as keyword arguments of `quell.design` (names as in `[design]`).
#[allow(clippy::too_many_arguments)]
pub fn spec(
    py: Python<'_>,
    channel_poles: &Bound<'_, PyAny>,
    reference_filter_poles: &Bound<'_, PyAny>,
    disturbance_filter_poles: Option<&Bound<'_, PyAny>>,
    mu: &Bound<'_, PyAny>,
    beta: &Bound<'_, PyAny>,
    observer_poles: Option<&Bound<'_, PyAny>>,
    observer_gain: Option<&Bound<'_, PyAny>>,
    relative_degrees: Option<&Bound<'_, PyAny>>,
    regressor_scaling: Option<&Bound<'_, PyAny>>,
    sizes: [Option<&Bound<'_, PyAny>>; 2],
) -> PyResult<DesignSpec> {
    let k = Kind::Design;
    // Both are read first, so that a wrong type is named before a wrong combination.
    let gain = observer_gain.map(|L| matrix(L, "observer_gain", k)).transpose()?;
    let placed = observer_poles.map(|p| poles(p, "observer_poles", k)).transpose()?;
    let observer = match (gain, placed) {
        (Some(L), None) => ObserverChoice::Gain(L),
        (None, Some(p)) => ObserverChoice::Poles(p),
        (Some(_), Some(_)) => return Err(k.err(py, "observer_gain, observer_poles: both are given; give exactly one: the gain L (n×m), or the n poles of A − LC to place")),
        (None, None) => return Err(k.err(py, "observer_gain: missing; give exactly one of observer_gain (the gain L, n×m) and observer_poles (the n poles of A − LC)")),
    };
    Ok(DesignSpec {
        observer,
        channel_poles: pole_lists(channel_poles, "channel_poles", k)?,
        reference_filter_poles: pole_lists(reference_filter_poles, "reference_filter_poles", k)?,
        disturbance_filter_poles: disturbance_filter_poles
            .map(|p| pole_lists(p, "disturbance_filter_poles", k))
            .transpose()?
            .unwrap_or_default(),
        mu: vector(mu, "mu", k)?,
        beta: number(beta, "beta", Kind::Design, "design.beta")?,
        relative_degrees: relative_degrees.map(|s| integers(s, "relative_degrees", k)).transpose()?,
        regressor_scaling: regressor_scaling
            .map(|obj| {
                let name: String = obj.extract().map_err(|_| {
                    crate::errors::type_error("regressor_scaling", "\"paper\", \"normalized\" or \"modal\"", obj)
                })?;
                quell::design::RegressorScaling::from_name(&name)
                    .map_err(|e| k.err(py, format!("regressor_scaling: {e}")))
            })
            .transpose()?
            .unwrap_or_default(),
        reference_sizes: component_sizes(py, sizes[0], "reference_sizes")?,
        disturbance_sizes: component_sizes(py, sizes[1], "disturbance_sizes")?,
    })
}

/// `reference_sizes` or `disturbance_sizes`: none (1 each) or at least one number (an empty list
/// is refused, as in a scenario file).
fn component_sizes(py: Python<'_>, obj: Option<&Bound<'_, PyAny>>, name: &str) -> PyResult<Vec<f64>> {
    let sizes = obj.map(|v| vector(v, name, Kind::Design)).transpose()?.unwrap_or_default();
    if obj.is_some() && sizes.is_empty() {
        return Err(Kind::Design.err(
            py,
            format!("{name}: expected one size per component, found an empty list; leave the argument out for 1 each"),
        ));
    }
    Ok(sizes)
}

/// A sequence of integers ≥ 1 (a bool or float is refused, naming `name[i]`).
fn integers(obj: &Bound<'_, PyAny>, name: &str, kind: Kind) -> PyResult<Vec<usize>> {
    let py = obj.py();
    if obj.is_instance_of::<pyo3::types::PyString>() {
        return Err(type_error(name, "a list of integers ≥ 1", obj));
    }
    let items = obj.try_iter().map_err(|_| type_error(name, "a list of integers ≥ 1", obj))?;
    items
        .enumerate()
        .map(|(i, v)| {
            let v = v?;
            let bad = || {
                kind.err(
                    py,
                    format!(
                        "{name}[{i}]: expected an integer ≥ 1, found {}",
                        v.repr().map_or_else(|_| type_name(&v), |r| r.to_string())
                    ),
                )
            };
            let Some(int) = crate::convert::as_int(&v) else {
                return Err(type_error(&format!("{name}[{i}]"), "an integer ≥ 1", &v));
            };
            match int.extract::<usize>() {
                Ok(s) if s >= 1 => Ok(s),
                _ => Err(bad()),
            }
        })
        .collect()
}

/// Designs every gain for a plant (Sections III–V) and checks the paper's assumptions.
///
/// Parameters
/// ----------
/// plant : Plant
///     The plant (1).
/// channel_poles : list of list of pole
///     Per output i, the σ_i poles λ_ij of the decoupled channel G_ii(s) (Proposition 1). A pole
///     is a number, a complex number (a pair lists both) or [re, im] meaning re ± i·im.
/// reference_filter_poles : list of list of pole
///     Per reference component, the poles of its filter, eq. (10).
/// mu : array_like
///     Adaptation gains μ_i ≥ 0 (m), eq. (33).
/// beta : float
///     β > 0 of H(s) = 1/(βs + 1).
/// disturbance_filter_poles : list of list of pole, optional
///     Per disturbance component, the poles of its filter, eq. (15).
/// observer_poles : list of pole, optional
///     The n poles of A − LC to place; give this or observer_gain.
/// observer_gain : array_like, optional
///     The observer gain L (n×m), eq. (6).
/// relative_degrees : list of int, optional
///     σ_i given instead of decided by eq. (7).
/// regressor_scaling : str, optional
///     "paper" (default: the paper's filters, l = e_q), "normalized" (filters of unit DC gain at
///     their own time scale, so ξ̂ has the signals' size) or "modal" (a block per real pole or
///     complex pair, each of unit gain at its own frequency: resonators for many harmonics).
/// reference_sizes : array_like, optional
///     Per reference component, its size (expected peak, in its own units, > 0): its block of ξ̂
///     is divided by it, so ξ̂ is dimensionless and outputs in different units do not spread the
///     adaptation's rates (default: 1 each, the paper's).
/// disturbance_sizes : array_like, optional
///     Per disturbance component, its size, as reference_sizes.
///
/// Returns
/// -------
/// Design
///     The gains and the checks passed.
///
/// Raises
/// ------
/// TypeError
///     An argument of the wrong type (a string for μ, a plant that is not a `quell.Plant`).
/// DesignError
///     A choice that is not valid, or no design exists (the message says which assumption fails).
///
/// Examples
/// --------
/// >>> p = quell.paper_example().plant
/// >>> d = quell.design(p, channel_poles=[[-6, -2], [-4]], reference_filter_poles=[[-1, -6], [-9]],
/// ...                  disturbance_filter_poles=[[-1, -3], [-1, -2, -3]], mu=[20, 30], beta=1.0,
/// ...                  observer_poles=[-2, -3, -4])
/// >>> np.sort(np.real(d.observer_eigenvalues))
/// array([-4., -3., -2.])
#[pyfunction]
#[pyo3(signature = (plant, *, channel_poles, reference_filter_poles, mu, beta, disturbance_filter_poles=None, observer_poles=None, observer_gain=None, relative_degrees=None, regressor_scaling=None, reference_sizes=None, disturbance_sizes=None))]
#[allow(clippy::too_many_arguments)]
pub fn design(
    py: Python<'_>,
    plant: &Bound<'_, PyAny>,
    channel_poles: &Bound<'_, PyAny>,
    reference_filter_poles: &Bound<'_, PyAny>,
    mu: &Bound<'_, PyAny>,
    beta: &Bound<'_, PyAny>,
    disturbance_filter_poles: Option<&Bound<'_, PyAny>>,
    observer_poles: Option<&Bound<'_, PyAny>>,
    observer_gain: Option<&Bound<'_, PyAny>>,
    relative_degrees: Option<&Bound<'_, PyAny>>,
    regressor_scaling: Option<&Bound<'_, PyAny>>,
    reference_sizes: Option<&Bound<'_, PyAny>>,
    disturbance_sizes: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyDesign> {
    let plant = plant_arg(plant, "plant")?;
    let spec = spec(
        py,
        channel_poles,
        reference_filter_poles,
        disturbance_filter_poles,
        mu,
        beta,
        observer_poles,
        observer_gain,
        relative_degrees,
        regressor_scaling,
        [reference_sizes, disturbance_sizes],
    )?;
    let d = designed(py, &plant, spec)?;
    crate::errors::warn_fragile(py, &d.inner, &d.spec)?;
    Ok(d)
}

/// The design of `plant` with `spec` (Ctrl-C interrupts it), its errors naming the Python
/// arguments (`mu[1]`, not `design.mu[1]`): what `quell.design` and a pickle's rebuild share.
fn designed(py: Python<'_>, plant: &PyPlant, spec: DesignSpec) -> PyResult<PyDesign> {
    let d = crate::interrupt::interruptible(py, || quell::Design::new(&plant.inner, &spec))?
        .map_err(|e| Kind::Design.err(py, in_python(e.to_string())))?;
    Ok(PyDesign { inner: Arc::new(d), spec, labels: plant.labels.clone() })
}

/// The design of `plant` with `choices` (a `Design.choices` dict), without warnings: how a pickled
/// design is rebuilt.
fn restore(py: Python<'_>, plant: &PyPlant, choices: &Bound<'_, PyDict>) -> PyResult<PyDesign> {
    let get = |k: &str| choices.get_item(k);
    let required = |k: &str| get(k)?.ok_or_else(|| Kind::Design.err(py, format!("choices: missing {k}")));
    let spec = spec(
        py,
        &required("channel_poles")?,
        &required("reference_filter_poles")?,
        get("disturbance_filter_poles")?.as_ref(),
        &required("mu")?,
        &required("beta")?,
        get("observer_poles")?.as_ref(),
        get("observer_gain")?.as_ref(),
        get("relative_degrees")?.filter(|v| !v.is_none()).as_ref(),
        get("regressor_scaling")?.as_ref(),
        [get("reference_sizes")?.as_ref(), get("disturbance_sizes")?.as_ref()],
    )?;
    designed(py, plant, spec)
}

/// State feedback K with eig(A − BK) = poles (KNV / Tits–Yang for several inputs), as
/// `control.place`.
///
/// Parameters
/// ----------
/// A : array_like
///     The state matrix (n×n).
/// B : array_like
///     The input matrix (n×m).
/// poles : list of pole
///     The n poles to place: numbers, complex numbers (a pair lists both) or [re, im] pairs.
///
/// Returns
/// -------
/// numpy.ndarray
///     K (m×n).
///
/// Raises
/// ------
/// TypeError
///     An argument of the wrong type.
/// DesignError
///     (A, B) is not controllable, the poles are not conjugate-closed, or not n of them; a pole
///     repeated more than rank(B) times (as `control.place` refuses it: the closed loop would need
///     a Jordan block, whose eigenvalues no gain meets to 1e-6 — spread the poles); or the gain
///     would miss the poles by more than 1e-6 (relative).
///
/// Examples
/// --------
/// >>> K = quell.place([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], [-1.0, -2.0])
/// >>> K
/// array([[2., 3.]])
#[pyfunction]
pub fn place<'py>(
    py: Python<'py>,
    A: &Bound<'py, PyAny>,
    B: &Bound<'py, PyAny>,
    poles: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let k = Kind::Design;
    let (A, B) = (matrix(A, "A", k)?, matrix(B, "B", k)?);
    let p = crate::convert::poles(poles, "poles", k)?;
    let K = crate::interrupt::interruptible(py, || quell::place(&A, &B, &p))?.map_err(|e| match e {
        e @ (quell::PlaceError::Matrix(_) | quell::PlaceError::InputRows { .. }) => k.err(py, e.to_string()),
        e => k.err(py, format!("poles: {e}")),
    })?;
    Ok(to_numpy(py, &K).into_any())
}

#[pymethods]
impl PyDesign {
    /// Decoupling feedback K (m×n), Proposition 1: u_f = −K x̂ + F u_d (5).
    #[getter]
    fn K<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, self.inner.K()).into_any()
    }
    /// Decoupling input gain F (m×m), Proposition 1.
    #[getter]
    fn F<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, self.inner.F()).into_any()
    }
    /// Luenberger observer gain L (n×m), eq. (6).
    #[getter]
    fn L<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, self.inner.L()).into_any()
    }
    /// Disturbance observer gain N (q_ω×n), the minimum-norm solution of N D = L_ω, eq. (20).
    #[getter]
    fn N<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, self.inner.N()).into_any()
    }
    /// A_f = A − BK (n×n), Proposition 1.
    #[getter]
    fn A_f<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, self.inner.A_f()).into_any()
    }
    /// B_f = BF (n×m), Proposition 1.
    #[getter]
    fn B_f<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, self.inner.B_f()).into_any()
    }
    /// B* (m×m), row i = c_i A^(σ_i − 1) B, eq. (7).
    #[getter]
    fn B_star<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, self.inner.B_star()).into_any()
    }
    /// Reference internal model G_g (q_g×q_g), eq. (11).
    #[getter]
    fn G_g<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, self.inner.G_g()).into_any()
    }
    /// Reference internal model input L_g (q_g×m), eq. (11).
    #[getter]
    fn L_g<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, self.inner.L_g()).into_any()
    }
    /// Disturbance internal model G_ω (q_ω×q_ω), eq. (16).
    #[getter]
    fn G_w<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, self.inner.G_w()).into_any()
    }
    /// Disturbance internal model input L_ω (q_ω×k), eq. (16).
    #[getter]
    fn L_w<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_numpy(py, self.inner.L_w()).into_any()
    }
    /// Relative degrees σ_i, eq. (7).
    #[getter]
    fn sigma(&self) -> Vec<usize> {
        self.inner.sigma().to_vec()
    }
    /// eig(A − LC), sorted (complex array).
    #[getter]
    fn observer_eigenvalues<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        complex_numpy(py, self.inner.observer_eigenvalues())
    }
    /// eig(A − BK), sorted (complex array): the Σσ_i channel poles and the plant's zeros.
    #[getter]
    fn decoupled_eigenvalues<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        complex_numpy(py, self.inner.decoupled_eigenvalues())
    }
    /// Adaptation gains μ_i, eq. (33).
    #[getter]
    fn mu(&self) -> Vec<f64> {
        self.inner.mu().to_vec()
    }
    /// β of H(s) = 1/(βs + 1).
    #[getter]
    fn beta(&self) -> f64 {
        self.inner.beta()
    }
    /// How the internal-model filters are realized: "paper" (l = e_q), "normalized" (unit DC
    /// gain, ξ̂ of the signals' size) or "modal" (a block per pole or pair).
    #[getter]
    fn regressor_scaling(&self) -> &'static str {
        self.inner.regressor_scaling().name()
    }
    /// Each reference component's size, which divides its block of ξ̂ (1 where none was given).
    #[getter]
    fn reference_sizes(&self) -> Vec<f64> {
        self.inner.reference_sizes().to_vec()
    }
    /// Each disturbance component's size, which divides its block of ξ̂ (1 where none was given).
    #[getter]
    fn disturbance_sizes(&self) -> Vec<f64> {
        self.inner.disturbance_sizes().to_vec()
    }
    /// Regressor size q = q_g + q_ω (the length of each η̂_i).
    #[getter]
    fn q(&self) -> usize {
        self.inner.q()
    }
    /// The delay-free decoupled plant (Proposition 1, x̂ = x) as a labelled `control.StateSpace`:
    /// ẋ = A_f x + B_f u_d, y = C x, whose transfer matrix is diagonal with entries G_ii(s).
    ///
    /// Returns
    /// -------
    /// control.StateSpace
    ///     Inputs `u_d[i]`, outputs and states named as the plant's (`y[i]`, `x[j]` by default).
    ///
    /// Raises
    /// ------
    /// ImportError
    ///     python-control is not installed.
    ///
    /// Examples
    /// --------
    /// >>> sys = quell.paper_example().design().decoupled_system()
    /// >>> sys.input_labels, sys.output_labels
    /// (['u_d[1]', 'u_d[2]'], ['y[1]', 'y[2]'])
    fn decoupled_system(slf: &Bound<'_, Self>) -> PyResult<Py<PyAny>> {
        Ok(slf.py().import("quell._control")?.call_method1("decoupled_system", (slf,))?.unbind())
    }
    /// The Luenberger observer (6) as a labelled `control.StateSpace`: x̂' = (A − LC) x̂ + B u_f + L y.
    ///
    /// Returns
    /// -------
    /// control.StateSpace
    ///     Inputs the plant's inputs then its outputs (`u_f[i]`, `y[i]` by default), outputs and
    ///     states the estimates (`x_hat[j]`, or `<state>_hat` for a named state).
    ///
    /// Raises
    /// ------
    /// ImportError
    ///     python-control is not installed.
    ///
    /// Examples
    /// --------
    /// >>> d = quell.paper_example().design()
    /// >>> obs = d.observer_system()
    /// >>> obs.input_labels
    /// ['u_f[1]', 'u_f[2]', 'y[1]', 'y[2]']
    /// >>> bool(np.allclose(np.sort_complex(obs.poles()), np.sort_complex(d.observer_eigenvalues)))
    /// True
    fn observer_system(slf: &Bound<'_, Self>) -> PyResult<Py<PyAny>> {
        Ok(slf.py().import("quell._control")?.call_method1("observer_system", (slf,))?.unbind())
    }
    /// The plant the design is for.
    #[getter]
    fn plant(&self) -> PyPlant {
        PyPlant { inner: self.inner.plant().clone(), labels: self.labels.clone() }
    }
    /// The designer's choices, as `quell.design`'s keyword arguments: channel_poles,
    /// reference_filter_poles, disturbance_filter_poles, mu, beta, observer_gain or
    /// observer_poles, relative_degrees when given, regressor_scaling, and reference_sizes and
    /// disturbance_sizes when given.
    #[getter]
    fn choices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.spec;
        let d = PyDict::new(py);
        d.set_item("channel_poles", py_pole_lists(py, &s.channel_poles)?)?;
        d.set_item("reference_filter_poles", py_pole_lists(py, &s.reference_filter_poles)?)?;
        d.set_item("disturbance_filter_poles", py_pole_lists(py, &s.disturbance_filter_poles)?)?;
        d.set_item("mu", s.mu.clone())?;
        d.set_item("beta", s.beta)?;
        match &s.observer {
            ObserverChoice::Gain(L) => d.set_item("observer_gain", to_numpy(py, L))?,
            ObserverChoice::Poles(p) => d.set_item("observer_poles", py_poles(py, p)?)?,
        }
        if let Some(r) = &s.relative_degrees {
            d.set_item("relative_degrees", r.clone())?;
        }
        d.set_item("regressor_scaling", s.regressor_scaling.name())?;
        for (key, sizes) in [("reference_sizes", &s.reference_sizes), ("disturbance_sizes", &s.disturbance_sizes)] {
            if !sizes.is_empty() {
                d.set_item(key, sizes.clone())?;
            }
        }
        Ok(d)
    }
    /// Rebuilds a pickled design.
    #[staticmethod]
    fn _restore(py: Python<'_>, plant: PyRef<'_, PyPlant>, choices: &Bound<'_, PyDict>) -> PyResult<Self> {
        restore(py, &plant, choices)
    }
    /// Pickles as the plant and the choices, designed again when unpickled (the same gains).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let me = slf.get();
        let args = PyTuple::new(py, [Py::new(py, me.plant())?.into_bound(py).into_any(), me.choices(py)?.into_any()])?;
        Ok((slf.get_type().getattr("_restore")?, args))
    }
    /// Equal designs: the same plant (signal names too) and the same choices, so the same gains.
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.cast::<PyDesign>().is_ok_and(|o| {
            let o = o.get();
            o.inner.plant() == self.inner.plant() && o.spec == self.spec && o.labels == self.labels
        })
    }
    /// Per channel: the decoupled transfer function G_ii(s) = q0 / (s^σ + a_{σ−1} s^{σ−1} + … + a_0)
    /// as a dict with `poles`, `denominator` (ascending [a_0, …, a_{σ−1}]) and `q0`.
    #[getter]
    fn channels<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.inner
            .channels()
            .iter()
            .map(|c| {
                let d = PyDict::new(py);
                d.set_item("poles", complex_numpy(py, &c.poles)?)?;
                d.set_item("denominator", c.den.clone())?;
                d.set_item("q0", c.q0())?;
                Ok(d)
            })
            .collect()
    }
    /// The assumption checks passed: the `checks` of `quell design --json`, one figure each. Ranks
    /// and tolerances of Assumption 1; `cond_B_star`, cond₂(B*) of Proposition 1 with B*'s rows and
    /// columns equilibrated (scale-free: not `numpy.linalg.cond(design.B_star)`); `cond_D`; the
    /// scale-free decisions' `tolerance`; per output eq. (7)'s `relative_degree_measures`, whether one
    /// is `relative_degree_close` to the tolerance and `relative_degrees_given`; the largest real
    /// parts of eig(A − BK) and eig(A − LC); `disturbance_rank`, k.
    #[getter]
    fn checks<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = serde_json::to_string(&self.inner.checks()).unwrap_or_default();
        py.import("json")?.call_method1("loads", (text,))
    }

    fn __repr__(&self) -> String {
        let d = &self.inner;
        format!(
            "Design(n={}, m={}, q={}, sigma={:?}, mu={:?}, beta={:?})",
            d.plant().n(),
            d.plant().m(),
            d.q(),
            d.sigma(),
            d.mu(),
            d.beta()
        )
    }
}
