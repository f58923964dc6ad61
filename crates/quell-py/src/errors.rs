//! The exception classes live in Python (`quell/_errors.py`, so that `ScenarioError` can subclass
//! both `QuellError` and `ValueError`); this raises them with the library's messages.

use pyo3::prelude::*;
use pyo3::types::PyType;

/// Which exception a failed check raises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `quell.ScenarioError`: a plant, scenario or simulation setting.
    Scenario,
    /// `quell.DesignError`: the designer's choices, or no design exists.
    Design,
    /// `quell.ControllerError`: the real-time controller's measurements and state.
    Controller,
    /// `quell.ExportError`: the export's own arguments (prefix, precision, compiler).
    Export,
}

/// `.name`, `."quoted name"` and `[i]` steps as Python subscripts: `.harmonics[0].frequency` is
/// `["harmonics"][0]["frequency"]`.
pub fn subscripts(mut rest: &str) -> String {
    let mut out = String::new();
    while let Some(c) = rest.chars().next() {
        let end = match c {
            '.' if rest[1..].starts_with('"') => {
                let end = rest[2..].find('"').map_or(rest.len(), |i| i + 3);
                out.push_str(&format!("[{}]", &rest[1..end]));
                end
            }
            '.' => {
                let end = rest[1..].find(['.', '[']).map_or(rest.len(), |i| i + 1);
                out.push_str(&format!("[\"{}\"]", &rest[1..end]));
                end
            }
            _ => {
                let end = rest.find(']').map_or(rest.len(), |i| i + 1);
                out.push_str(&rest[..end]);
                end
            }
        };
        rest = &rest[end..];
    }
    out
}

/// A scenario key as the Python argument that sets it: `simulation.t_end` is `t_end` (a keyword of
/// `Scenario` and `simulate`), `design.mu[0]` is `mu[0]`, `reference.components[0].bias` is
/// `reference[0]["bias"]`, `noise.std` is `noise["std"]`; `plant.A` (an attribute of the plant
/// argument) and other keys are left as they are.
pub fn python_key(key: &str) -> String {
    let keyword = key.strip_prefix("simulation.").or_else(|| key.strip_prefix("design."));
    let (head, rest) = if let Some(r) = keyword {
        let end = r.find(['.', '[']).unwrap_or(r.len());
        (&r[..end], &r[end..])
    } else if let Some(r) = key.strip_prefix("reference.components") {
        ("reference", r)
    } else if let Some(r) = key.strip_prefix("disturbance.components") {
        ("disturbance", r)
    } else if let Some(r) = key.strip_prefix("noise") {
        ("noise", r)
    } else {
        return key.to_string();
    };
    format!("{head}{}", subscripts(rest))
}

/// A library message (`key: …`) with its leading key as the Python argument ([`python_key`]).
pub fn in_python(message: String) -> String {
    match message.split_once(": ") {
        Some((key, rest)) if !key.contains(' ') => format!("{}: {rest}", python_key(key)),
        _ => message,
    }
}

/// The exception of `kind` with a library `message` ([`in_python`]) and `.key`, the scenario key
/// path it names (`None`: none).
pub fn keyed(py: Python<'_>, kind: Kind, message: String, key: Option<String>) -> PyErr {
    keyed_as(py, kind, message, key, true)
}

/// [`keyed`], the message's key in the Python spelling only where `python` (a scenario read from a
/// file names its keys as the file writes them, `simulation.sample_time`).
pub fn keyed_as(py: Python<'_>, kind: Kind, message: String, key: Option<String>, python: bool) -> PyErr {
    let err = kind.err(py, if python { in_python(message) } else { message });
    let _ = err.value(py).setattr("key", key);
    err
}

/// `TypeError: {name}: expected {expected}, found a {type of obj}` ("an int").
pub fn type_error(name: &str, expected: &str, obj: &Bound<'_, PyAny>) -> PyErr {
    pyo3::exceptions::PyTypeError::new_err(format!(
        "{name}: expected {expected}, found {}",
        crate::convert::a_type(obj)
    ))
}

fn class<'py>(py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyType>> {
    Ok(py.import("quell._errors")?.getattr(name)?.cast_into::<PyType>()?)
}

impl Kind {
    /// The exception of this kind with `message`.
    pub fn err(self, py: Python<'_>, message: impl Into<String>) -> PyErr {
        let message = message.into();
        let name = match self {
            Kind::Scenario => "ScenarioError",
            Kind::Design => "DesignError",
            Kind::Export => "ExportError",
            Kind::Controller => "ControllerError",
        };
        // A ScenarioError's `.key`: the key or argument its message starts with, unless the caller
        // sets the file's key ([`keyed`]); it was None for `Plant(A)` with a NaN and `jobs=0`.
        let head = message.split_once(": ").map(|(k, _)| k.to_string()).filter(|k| !k.contains(' '));
        match class(py, name) {
            Ok(cls) => {
                let err = PyErr::from_type(cls, message);
                if let (Kind::Scenario, Some(key)) = (self, head) {
                    let _ = err.value(py).setattr("key", key);
                }
                err
            }
            Err(e) => e,
        }
    }
}

/// A library error as the exception of `kind`, the real-time controller's methods named as Python
/// calls them (the library's messages name `Controller::step`, `Controller::set_state` and
/// `Controller::state`).
pub fn raise(py: Python<'_>, kind: Kind) -> impl Fn(&dyn std::fmt::Display) -> PyErr + '_ {
    move |e| {
        let message = e.to_string();
        let message = match kind {
            Kind::Controller => message
                .replace("Controller::step", "Controller.step")
                .replace("Controller::set_state", "Controller.__setstate__")
                .replace("Controller::state", "Controller.__getstate__()"),
            _ => message,
        };
        kind.err(py, message)
    }
}

/// `quell.SimulationError(message)` with `.t`, `.signal`, `.value` and `.result`.
pub fn simulation_error(
    py: Python<'_>,
    message: String,
    t: f64,
    signal: Option<String>,
    value: Option<f64>,
    result: Py<PyAny>,
) -> PyErr {
    let build = || -> PyResult<PyErr> {
        let e = class(py, "SimulationError")?.call1((message.clone(),))?;
        e.setattr("t", t)?;
        e.setattr("signal", signal.clone())?;
        e.setattr("value", value)?;
        e.setattr("result", result.clone_ref(py))?;
        Ok(PyErr::from_value(e))
    };
    build().unwrap_or_else(|e| e)
}

/// Issues each fragile-gain warning of a design ([`quell::design::warnings`]) as a Python
/// `UserWarning`, with its message (figures and what to do).
pub fn warn_fragile(py: Python<'_>, design: &quell::Design, spec: &quell::DesignSpec) -> PyResult<()> {
    for w in quell::design::warnings(design, spec) {
        warn(py, &w.message)?;
    }
    Ok(())
}

/// The warning of a sample time coarse for `design` ([`quell::sim::coarse_sample_warning`]), as a
/// `UserWarning` naming the argument.
pub fn warn_coarse_sample(
    py: Python<'_>,
    design: &quell::Design,
    reference: &quell::Signal,
    disturbance: &quell::Signal,
    sample_time: f64,
    output_step: Option<f64>,
) -> PyResult<()> {
    match quell::sim::coarse_sample_warning(design, [reference, disturbance], sample_time, output_step) {
        Some(w) => warn(py, &in_python(w)),
        None => Ok(()),
    }
}

/// Issues `message` as a Python `UserWarning`.
pub fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    let message = std::ffi::CString::new(message.replace('\0', " ")).unwrap_or_default();
    PyErr::warn(py, &py.get_type::<pyo3::exceptions::PyUserWarning>(), &message, 1)
}
