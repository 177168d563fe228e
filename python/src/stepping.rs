//! `ctlgraph.load`: a graph driven step by step from Python, interpreted
//! or in its step library (`ctlgraph::accel::Stepper`).

use crate::{SimulationError, blocks_of, graph_error, prepared};
use ctlgraph::accel::{Stepper, StepperSnapshot};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

/// A compiled graph driven step by step: `set_input`, `advance_to`,
/// `output`, `signal`; `state()` and `restore()` to save and rewind.
///
///     model = ctlgraph.load("graphs/tutorial/controller_io.yaml")
///     model.set_input("y", 0.2)
///     u = model.output("u")
///     model.advance_to(0.001)
///
/// Inputs are the graph's top-level `inport` blocks, outputs its top-level
/// `outport` blocks; both are scalars (float) or vectors (numpy array).
#[pyclass(frozen, name = "Model", module = "ctlgraph")]
pub(crate) struct LoadedModel {
    sim: Mutex<Stepper>,
}

/// A saved instant of a run, for `LoadedModel.restore`.
#[pyclass(frozen, module = "ctlgraph")]
pub(crate) struct Snapshot {
    inner: Mutex<StepperSnapshot>,
    time: f64,
}

#[pymethods]
impl Snapshot {
    /// The time it was taken at [s].
    #[getter]
    fn time(&self) -> f64 {
        self.time
    }
}

/// A signal value for Python: a float for a scalar, an array for a vector.
fn value(py: Python<'_>, v: &[f64]) -> PyResult<Py<PyAny>> {
    Ok(match v {
        [x] => x.into_pyobject(py)?.into_any().unbind(),
        _ => PyArray1::from_slice(py, v).into_any().unbind(),
    })
}

impl LoadedModel {
    /// The simulator (a call that panicked left it usable: the lock is
    /// taken back).
    fn sim(&self) -> MutexGuard<'_, Stepper> {
        self.sim.lock().unwrap_or_else(|e| e.into_inner())
    }
}

#[pymethods]
impl LoadedModel {
    /// The present time [s].
    #[getter]
    fn time(&self) -> f64 {
        self.sim().time()
    }

    /// The graph's inputs (top-level inport blocks).
    #[getter]
    fn inputs(&self) -> Vec<String> {
        self.sim().model().input_names().map(str::to_string).collect()
    }

    /// The graph's outputs (top-level outport blocks).
    #[getter]
    fn outputs(&self) -> Vec<String> {
        self.sim().model().output_names().map(str::to_string).collect()
    }

    /// Sets input `name` to `value` (a float, or a sequence for a vector
    /// input) from now on; it holds until set again.
    fn set_input(&self, py: Python<'_>, name: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let v: Vec<f64> = match value.extract::<f64>() {
            Ok(x) => vec![x],
            Err(_) => value.extract()?,
        };
        self.sim().set_input(name, &v).map_err(|d| graph_error(py, &d))
    }

    /// Simulates up to time `t` [s], landing exactly there (the GIL is
    /// released meanwhile).
    fn advance_to(&self, py: Python<'_>, t: f64) -> PyResult<()> {
        let sim = &self.sim;
        py.detach(|| sim.lock().unwrap_or_else(|e| e.into_inner()).advance_to(t))
            .map_err(|e| SimulationError::new_err(e.to_string()))
    }

    /// The present value of output `name`: a float, or an array.
    fn output(&self, py: Python<'_>, name: &str) -> PyResult<Py<PyAny>> {
        match self.sim().output(name) {
            Ok(v) => value(py, v),
            Err(d) => Err(graph_error(py, &d)),
        }
    }

    /// The present value of any signal: a recorded name, `block`,
    /// `block.port`, `sub.port`, with `[k]` for one element.
    fn signal(&self, py: Python<'_>, name: &str) -> PyResult<Py<PyAny>> {
        match self.sim().signal(name) {
            Ok(v) => value(py, v),
            Err(d) => Err(graph_error(py, &d)),
        }
    }

    /// The blocks in execution order, as dicts (name, type, sample_time).
    fn blocks(&self, py: Python<'_>) -> PyResult<Py<PyList>> {
        blocks_of(py, self.sim().model())
    }

    /// The recorded signal names, then the graph's outputs not among them.
    fn signals(&self) -> Vec<String> {
        let sim = self.sim();
        let mut names: Vec<String> = sim.model().columns.iter().map(|c| c.name.clone()).collect();
        for output in sim.model().output_names() {
            if !names.iter().any(|n| n == output) {
                names.push(output.to_string());
            }
        }
        names
    }

    /// The run as it stands: states, block memory, solver.
    fn state(&self, py: Python<'_>) -> PyResult<Snapshot> {
        let sim = self.sim();
        let saved = sim.state().map_err(|d| graph_error(py, &d))?;
        Ok(Snapshot { time: saved.time(), inner: Mutex::new(saved) })
    }

    /// Whether the steps run in the graph's generated step library
    /// (`load(…, accelerate=True)`) rather than the interpreter.
    #[getter]
    fn accelerated(&self) -> bool {
        self.sim().accelerated()
    }

    /// Returns the run to `snapshot` (taken of this model).
    fn restore(&self, py: Python<'_>, snapshot: &Snapshot) -> PyResult<()> {
        let saved = snapshot.inner.lock().unwrap_or_else(|e| e.into_inner());
        self.sim().restore(&saved).map_err(|d| graph_error(py, &d))
    }

    fn __repr__(&self) -> String {
        let how = if self.accelerated() { ", accelerated" } else { "" };
        format!("Model(t = {}, inputs {:?}, outputs {:?}{how})", self.time(), self.inputs(), self.outputs())
    }
}

/// Compiles the graph file `path` for stepping; see `LoadedModel`.
/// `set` and `seed` as for `run`; `accelerate` (True, False or
/// "require"; default: the graph's `simulation.accelerate`) steps the
/// graph's generated step library, with the interpreter's numbers to the
/// bit. Raises GraphError.
#[pyfunction]
#[pyo3(signature = (path, set = None, seed = None, accelerate = None))]
pub(crate) fn load(
    py: Python<'_>,
    path: PathBuf,
    set: Option<&Bound<'_, PyDict>>,
    seed: Option<u64>,
    accelerate: Option<&Bound<'_, PyAny>>,
) -> PyResult<LoadedModel> {
    let (sets, model, runner) = prepared(py, &path, set, seed, accelerate)?;
    let stepper = py.detach(|| Stepper::new(&runner, model, &sets, seed)).map_err(SimulationError::new_err)?;
    Ok(LoadedModel { sim: Mutex::new(stepper) })
}
