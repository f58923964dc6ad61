//! The exception classes live in Python (`quell/_errors.py`, so that `ScenarioError` can subclass
//! both `QuellError` and `ValueError`); this raises them with the library's messages.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyType;

/// Which exception a failed check raises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `quell.ScenarioError`: a plant, scenario or simulation setting.
    Scenario,
    /// `quell.DesignError`: the designer's choices, or no design exists.
    Design,
    /// Plain `ValueError`: arguments of the real-time controller.
    Value,
    /// `quell.ExportError`: the export's own arguments (prefix, precision, compiler).
    Export,
}

/// The library's keys as the Python arguments that set them, for messages of calls that take them.
pub const ARGUMENTS: [(&str, &str); 1] = [("simulation.sample_time", "sample_time")];

/// A library message whose leading key one of the call's arguments sets, with the argument named.
pub fn in_arguments(message: String) -> String {
    for (key, argument) in ARGUMENTS {
        if let Some(rest) = message.strip_prefix(key).filter(|r| r.starts_with([':', ' '])) {
            return format!("{argument}{rest}");
        }
    }
    message
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
            Kind::Value => return PyValueError::new_err(message),
        };
        match class(py, name) {
            Ok(cls) => PyErr::from_type(cls, message),
            Err(e) => e,
        }
    }
}

/// A library error as the exception of `kind`.
pub fn raise(py: Python<'_>, kind: Kind) -> impl Fn(&dyn std::fmt::Display) -> PyErr + '_ {
    move |e| kind.err(py, e.to_string())
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
        let message = std::ffi::CString::new(w.message.replace('\0', " ")).unwrap_or_default();
        PyErr::warn(py, &py.get_type::<pyo3::exceptions::PyUserWarning>(), &message, 1)?;
    }
    Ok(())
}
