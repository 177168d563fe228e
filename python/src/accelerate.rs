//! `accelerate=` of `run()` and `sweep()`: the argument, and the runner it
//! asks for (a graph that runs interpreted instead says why in a
//! RuntimeWarning, as the command line prints a note).

use crate::{SimulationError, graph_error};
use ctlgraph::accel::{Accelerate, Runner};
use ctlgraph::core::Model;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// `accelerate=True | False | "require"` (None: the graph's own setting).
pub(crate) fn accelerate_arg(value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Accelerate>> {
    let Some(value) = value.filter(|v| !v.is_none()) else { return Ok(None) };
    if let Ok(b) = value.extract::<bool>() {
        return Ok(Some(if b { Accelerate::On } else { Accelerate::Off }));
    }
    match value.extract::<String>() {
        Ok(s) if s == "require" => Ok(Some(Accelerate::Require)),
        _ => Err(PyValueError::new_err("accelerate: True, False or \"require\"")),
    }
}

/// The runner `accelerate` asks for the graph `path` compiled into `model`;
/// a graph that runs interpreted instead says why in a RuntimeWarning.
pub(crate) fn runner(
    py: Python<'_>,
    accelerate: Option<Accelerate>,
    model: &Model,
    path: &std::path::Path,
) -> PyResult<Runner> {
    let (runner, note) = py.detach(|| ctlgraph::suite::runner_for(accelerate, model, path)).map_err(|e| match e {
        ctlgraph::suite::Failure::Invalid(d) => graph_error(py, &d),
        other => SimulationError::new_err(other.to_string()),
    })?;
    if let Some(why) = note {
        let message = std::ffi::CString::new(format!("running interpreted, not accelerated: {why}"))
            .unwrap_or_else(|_| c"running interpreted, not accelerated".to_owned());
        PyErr::warn(py, &py.get_type::<pyo3::exceptions::PyRuntimeWarning>(), &message, 1)?;
    }
    Ok(runner)
}
