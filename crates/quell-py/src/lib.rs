//! The `quell` Python package's native module (`quell._quell`): the library's plant, design,
//! scenario, simulation and real-time controller, with numpy arrays in and out.
//!
//! Nothing here panics into Python: every argument is checked and every library error becomes
//! `quell.ScenarioError`, `quell.DesignError` (both `ValueError`) or `quell.SimulationError`
//! (`RuntimeError`), with the library's message.
#![allow(non_snake_case)]

mod controller;
mod convert;
mod design;
mod errors;
mod export;
mod interrupt;
mod plant;
mod scenario;
mod simulate;
mod study;
mod tune;

use pyo3::prelude::*;

#[pymodule]
fn _quell(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<plant::PyPlant>()?;
    m.add_class::<design::PyDesign>()?;
    m.add_class::<scenario::PyScenario>()?;
    m.add_class::<simulate::PySimResult>()?;
    m.add_class::<controller::PyController>()?;
    m.add_function(wrap_pyfunction!(design::design, m)?)?;
    m.add_function(wrap_pyfunction!(design::place, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::paper_example, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::auto_design, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_class::<study::PyStudy>()?;
    m.add_class::<study::PyRunSpec>()?;
    m.add_class::<study::PyRunSpecs>()?;
    m.add_function(wrap_pyfunction!(study::sweep, m)?)?;
    m.add_function(wrap_pyfunction!(study::sweep_runs, m)?)?;
    m.add_function(wrap_pyfunction!(study::run_one, m)?)?;
    m.add_function(wrap_pyfunction!(export::export, m)?)?;
    m.add_function(wrap_pyfunction!(tune::tune, m)?)?;
    m.add_function(wrap_pyfunction!(interrupt::note_interrupt, m)?)?;
    Ok(())
}
