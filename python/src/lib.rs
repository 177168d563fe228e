//! ctlgraph's Python extension (`ctlgraph._native`): runs graph files and
//! drives compiled graphs step by step, at Rust speed, with numpy arrays
//! back. The package `ctlgraph` (ctlgraph/__init__.py) re-exports it.

use ctlgraph::accel::Runner;
use ctlgraph::core::checks::CheckResult;
use ctlgraph::core::trace::Trace;
use ctlgraph::core::{Diagnostic, Model};
use numpy::{PyArray1, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyKeyError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

mod accelerate;
mod stepping;
use accelerate::{accelerate_arg, runner};
use stepping::{LoadedModel, Snapshot, load};

/// The command line's allocator (see src/main.rs): compiling a graph
/// allocates per node, and mimalloc makes it ~1.4x faster. Only the
/// extension's own (Rust) allocations use it; Python's objects do not.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

create_exception!(
    ctlgraph,
    GraphError,
    PyException,
    "A graph file is invalid. Attributes: message, file, line, column (1-based; None when the error has no \
     position) and hint (None when there is none). str() gives `file:line:col: message` as the CLI prints it."
);
create_exception!(
    ctlgraph,
    SimulationError,
    PyException,
    "A run stopped early: a signal became NaN or infinite, the solver gave up, time stopped advancing, or a \
     step-by-step call asked for the impossible."
);

/// A `Diagnostic` as a `GraphError` with its position and hint as attributes.
fn graph_error(py: Python<'_>, d: &Diagnostic) -> PyErr {
    let err = GraphError::new_err(d.to_string());
    let value = err.value(py);
    let pos = d.pos.as_ref();
    let file = pos.map(|p| p.file.to_string()).or_else(|| d.file.as_ref().map(|f| f.to_string()));
    let set = |name: &str, v: Py<PyAny>| value.setattr(name, v);
    let attrs = (|| -> PyResult<()> {
        set("message", d.message.clone().into_pyobject(py)?.into_any().unbind())?;
        set("file", file.into_pyobject(py)?.into_any().unbind())?;
        set("line", pos.map(|p| p.line).into_pyobject(py)?.into_any().unbind())?;
        set("column", pos.map(|p| p.col).into_pyobject(py)?.into_any().unbind())?;
        set("hint", d.hint.clone().into_pyobject(py)?.into_any().unbind())
    })();
    match attrs {
        Ok(()) => err,
        Err(e) => e,
    }
}

/// `set={"kp": 3.0}` as the loader's overrides (values may be numbers or
/// expressions over the graph's parameters, as with `--set`).
fn overrides(set: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, String)>> {
    let Some(set) = set else { return Ok(Vec::new()) };
    set.iter()
        .map(|(k, v)| {
            let name: String = k.extract()?;
            let value = match v.extract::<f64>() {
                Ok(x) => format!("{x:e}"),
                Err(_) => v.extract::<String>().map_err(|_| {
                    PyValueError::new_err(format!("set[{name:?}]: give a number or an expression string"))
                })?,
            };
            Ok((name, value))
        })
        .collect()
}

/// One check of a graph, evaluated on a run.
#[pyclass(frozen, get_all, module = "ctlgraph")]
struct Check {
    /// The check's name (its text when unnamed).
    name: String,
    /// The value of its expression on the run.
    measured: f64,
    /// "<", "<=", ">" or ">=".
    op: &'static str,
    bound: f64,
    passed: bool,
}

#[pymethods]
impl Check {
    fn __repr__(&self) -> String {
        let verdict = if self.passed { "pass" } else { "FAIL" };
        format!("Check({verdict} {:?}: measured {} {} {})", self.name, self.measured, self.op, self.bound)
    }
}

impl From<&CheckResult> for Check {
    fn from(c: &CheckResult) -> Self {
        Check { name: c.name.clone(), measured: c.measured, op: c.op.symbol(), bound: c.bound, passed: c.passed }
    }
}

/// The recorded signals of a run (numpy arrays, one per recorded column),
/// its checks and its statistics.
///
/// `result.t` is the time column; `result["y"]` a recorded signal (vector
/// signals as `"name[1]"` …); `result.names` lists them; `result.checks`
/// the graph's checks as `Check` objects (name, measured, op, bound,
/// passed); `result.stats` a dict (major_steps, solver_steps, rejected,
/// evaluations, events, wall_seconds); `result.to_pandas()` a DataFrame
/// indexed by t, when pandas is installed.
#[pyclass(frozen, name = "Result", module = "ctlgraph")]
struct RunResult {
    names: Vec<String>,
    columns: Vec<Py<PyArray1<f64>>>,
    #[pyo3(get)]
    checks: Vec<Py<Check>>,
    #[pyo3(get)]
    stats: Py<PyDict>,
}

#[pymethods]
impl RunResult {
    /// The time column [s].
    #[getter]
    fn t(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
        self.columns[0].clone_ref(py)
    }

    /// The recorded names, in the CSV's column order (without `t`).
    #[getter]
    fn names(&self) -> Vec<String> {
        self.names[1..].to_vec()
    }

    fn __getitem__(&self, py: Python<'_>, name: &str) -> PyResult<Py<PyArray1<f64>>> {
        match self.names.iter().position(|n| n == name) {
            Some(k) => Ok(self.columns[k].clone_ref(py)),
            None => Err(PyKeyError::new_err(format!("{name:?} is not recorded; recorded: {}", self.names.join(", ")))),
        }
    }

    fn __contains__(&self, name: &str) -> bool {
        self.names.iter().any(|n| n == name)
    }

    fn __len__(&self) -> usize {
        self.names.len() - 1
    }

    /// Whether every check passed (True for a graph without checks).
    #[getter]
    fn passed(&self, py: Python<'_>) -> bool {
        self.checks.iter().all(|c| c.bind(py).get().passed)
    }

    /// The recorded signals as a pandas DataFrame indexed by t (needs
    /// pandas; the arrays are shared, not copied, where pandas allows).
    fn to_pandas(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let pandas = py.import("pandas").map_err(|e| {
            pyo3::exceptions::PyImportError::new_err(format!("to_pandas needs pandas (pip install pandas): {e}"))
        })?;
        let data = PyDict::new(py);
        for (name, column) in self.names.iter().zip(&self.columns).skip(1) {
            data.set_item(name, column.clone_ref(py))?;
        }
        let index = pandas.call_method1("Index", (self.columns[0].clone_ref(py), py.None(), false, "t"))?;
        let kwargs = PyDict::new(py);
        kwargs.set_item("index", index)?;
        Ok(pandas.getattr("DataFrame")?.call((data,), Some(&kwargs))?.unbind())
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let samples = self.columns[0].bind(py).len();
        format!("Result({} samples of {})", samples, self.names[1..].join(", "))
    }
}

/// Runs `model` (compiled from its graph with `sets` and `seed`) to its
/// stop time (or `stop`) by `runner`, recording as the CLI does.
fn simulate(
    runner: &Runner,
    model: Model,
    sets: &[(String, String)],
    seed: Option<u64>,
    stop: Option<f64>,
) -> std::result::Result<(Trace, Vec<CheckResult>, [u64; 5], f64), String> {
    let start = std::time::Instant::now();
    let checks = model.checks.clone();
    let (trace, s) = runner.simulate(model, sets, seed, stop).map_err(|e| e.to_string())?;
    let results = checks.iter().map(|c| trace.check(c)).collect();
    let counts = [s.major_steps, s.solver.steps, s.solver.rejected, s.solver.evaluations, s.events];
    Ok((trace, results, counts, start.elapsed().as_secs_f64()))
}

/// Runs the graph file `path` and returns its recorded signals.
///
///     result = ctlgraph.run("graphs/tutorial/pid_loop.yaml", set={"kp": 3.0})
///     result.t, result["y"], result.checks, result.stats
///
/// `set` overrides graph parameters (numbers, or expressions over the
/// graph's parameters as strings), `stop` the stop time [s], `seed` the
/// noise seed, `accelerate` (True, False or "require"; default: the
/// graph's `simulation.accelerate`) runs the generated step as
/// `--accelerate` does. The numbers are the CLI's (`ctlgraph run … --out`),
/// bit for bit. The GIL is released while the graph runs, so threads can
/// run graphs in parallel. Raises GraphError for an invalid file and
/// SimulationError when the run stops early.
#[pyfunction]
#[pyo3(signature = (path, set = None, stop = None, seed = None, accelerate = None))]
fn run(
    py: Python<'_>,
    path: PathBuf,
    set: Option<&Bound<'_, PyDict>>,
    stop: Option<f64>,
    seed: Option<u64>,
    accelerate: Option<&Bound<'_, PyAny>>,
) -> PyResult<RunResult> {
    let (sets, model, runner) = prepared(py, &path, set, seed, accelerate)?;
    let (trace, checks, counts, wall) =
        py.detach(|| simulate(&runner, model, &sets, seed, stop)).map_err(SimulationError::new_err)?;
    let Trace { headers, columns, .. } = trace;
    let columns = columns.into_iter().map(|c| PyArray1::from_vec(py, c).unbind()).collect();
    let checks = checks.iter().map(|c| Py::new(py, Check::from(c))).collect::<PyResult<_>>()?;
    let stats = PyDict::new(py);
    for (name, v) in ["major_steps", "solver_steps", "rejected", "evaluations", "events"].iter().zip(counts) {
        stats.set_item(name, v)?;
    }
    stats.set_item("wall_seconds", wall)?;
    match runner.cost() {
        Some(ctlgraph::accel::Cost::Built(s)) => stats.set_item("build_seconds", s)?,
        Some(ctlgraph::accel::Cost::Loaded(s)) => stats.set_item("load_seconds", s)?,
        None => {}
    }
    Ok(RunResult { names: headers, columns, checks, stats: stats.unbind() })
}

/// Graphs run before: a run of one with other values compiles on its structure.
/// A graph's overrides, its compiled model and the runner asked for.
type Prepared = (Vec<(String, String)>, Model, Runner);

/// What `run()` and `load()` start from: the graph `path` with `set`'s
/// overrides and `seed`, compiled (cached), and the runner `accelerate`
/// asks for.
pub(crate) fn prepared(
    py: Python<'_>,
    path: &std::path::Path,
    set: Option<&Bound<'_, PyDict>>,
    seed: Option<u64>,
    accelerate: Option<&Bound<'_, PyAny>>,
) -> PyResult<Prepared> {
    let sets = overrides(set)?;
    let accelerate = accelerate_arg(accelerate)?;
    let model = py.detach(|| GRAPHS.compile(path, &sets, seed)).map_err(|d| graph_error(py, &d))?;
    let runner = runner(py, accelerate, &model, path)?;
    Ok((sets, model, runner))
}

static GRAPHS: ctlgraph::cache::GraphCache = ctlgraph::cache::GraphCache::new();

/// Validates the graph file `path` and returns its blocks in execution
/// order, as dicts (name, type, sample_time). Raises GraphError.
#[pyfunction]
#[pyo3(signature = (path, set = None))]
fn check(py: Python<'_>, path: PathBuf, set: Option<&Bound<'_, PyDict>>) -> PyResult<Py<PyList>> {
    let sets = overrides(set)?;
    let model = py.detach(|| ctlgraph::compile_file(&path, &sets)).map_err(|d| graph_error(py, &d))?;
    blocks_of(py, &model)
}

fn blocks_of(py: Python<'_>, model: &Model) -> PyResult<Py<PyList>> {
    let list = PyList::empty(py);
    for m in &model.meta {
        let d = PyDict::new(py);
        d.set_item("name", &m.name)?;
        d.set_item("type", &m.type_name)?;
        d.set_item("sample_time", m.sample_time.to_string())?;
        list.append(d)?;
    }
    Ok(list.unbind())
}

/// The linear model of a graph around an operating point, as
/// `ctlgraph linearize` computes it: a dict with A, B, C, D (numpy 2-D
/// arrays), states (names), sample_time (None: continuous), input, output,
/// loop_transfer, at, poles (complex) and, for a loop transfer (`open`),
/// margins (gain_margin, phase_margin [deg], gain_crossover_freq,
/// delay_margin [s], peak_sensitivity, …).
///
///     lin = ctlgraph.linearize("graphs/tutorial/pid_loop.yaml", open="ctrl.u")
///     lin["margins"]["phase_margin"]
///
/// `input`/`output`/`open` name signals (`block`, `block.port`, `name[k]`);
/// left out, the file's `analysis:` section decides. Raises GraphError.
#[pyfunction]
#[pyo3(signature = (path, input = None, output = None, open = None, at = 0.0, set = None))]
fn linearize(
    py: Python<'_>,
    path: PathBuf,
    input: Option<String>,
    output: Option<String>,
    open: Option<String>,
    at: f64,
    set: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyDict>> {
    use ctlgraph::core::linearize::{AnalysisError, Selection};
    let sets = overrides(set)?;
    let sel = Selection { input, output, open, at, pos: None };
    let lin = py.detach(|| ctlgraph::analysis::linearize_file(&path, &sets, &sel)).map_err(|e| match e {
        AnalysisError::Invalid(d) => graph_error(py, &d),
        AnalysisError::Run(e) => SimulationError::new_err(format!("reaching the operating point: {e}")),
    })?;
    let ss = &lin.system;
    let matrix = |v: &[f64], rows: usize, cols: usize| -> PyResult<Py<PyAny>> {
        Ok(PyArray1::from_slice(py, v).reshape([rows, cols])?.into_any().unbind())
    };
    let d = PyDict::new(py);
    d.set_item("A", matrix(&ss.a, ss.n, ss.n)?)?;
    d.set_item("B", matrix(&ss.b, ss.n, ss.m)?)?;
    d.set_item("C", matrix(&ss.c, ss.p, ss.n)?)?;
    d.set_item("D", matrix(&ss.d, ss.p, ss.m)?)?;
    d.set_item("states", &lin.states)?;
    d.set_item("sample_time", lin.sample_time)?;
    d.set_item("input", &lin.input)?;
    d.set_item("output", &lin.output)?;
    d.set_item("loop_transfer", lin.loop_transfer)?;
    d.set_item("at", lin.at)?;
    let poles = ctlgraph::solver::freq::poles(ss).unwrap_or_default();
    let poles: Vec<_> = poles.iter().map(|p| pyo3::types::PyComplex::from_doubles(py, p.re, p.im)).collect();
    d.set_item("poles", poles)?;
    if lin.loop_transfer {
        let m = ctlgraph::analysis::figures(&lin).margins;
        let margins = PyDict::new(py);
        for (name, v) in [
            ("gain_margin", m.gain_margin),
            ("gain_crossover_phase_freq", m.gain_crossover_phase_freq),
            ("phase_margin", m.phase_margin),
            ("gain_crossover_freq", m.gain_crossover_freq),
            ("delay_margin", m.delay_margin),
            ("peak_sensitivity", m.peak_sensitivity),
            ("peak_sensitivity_freq", m.peak_sensitivity_freq),
        ] {
            margins.set_item(name, v)?;
        }
        d.set_item("margins", margins)?;
    }
    Ok(d.unbind())
}

/// Runs a designed set of cases of a graph in parallel, as `ctlgraph
/// sweep`, and returns its table as a dict of columns: `case`, each varied
/// parameter (numpy arrays), `seed`, each check's measured value (an
/// array, NaN where the case failed) and `"<check> passed"` (bools),
/// `status` ("ok", "checks failed", "failed") and `error`.
///
///     table = ctlgraph.sweep("graphs/tutorial/pid_loop.yaml",
///                            vary={"kp": "1..4:20", "kd": [0.0, 0.1, 0.2]})
///
/// `vary` maps a parameter to a list of values, `"LO..HI:N"` (a grid) or
/// `"LO..HI"` (with `random=N` draws); `seeds=(A, B)` runs every case
/// with each seed A..B; `seed` seeds the draws; `jobs` threads (default:
/// all cores; the GIL is released); `accelerate` as in `run` (one step
/// library serves every case). Raises GraphError.
#[pyfunction]
#[pyo3(signature = (path, vary, random = None, seeds = None, seed = 0, jobs = None, accelerate = None))]
#[allow(clippy::too_many_arguments)]
fn sweep(
    py: Python<'_>,
    path: PathBuf,
    vary: &Bound<'_, PyDict>,
    random: Option<usize>,
    seeds: Option<(u64, u64)>,
    seed: u64,
    jobs: Option<usize>,
    accelerate: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyDict>> {
    let accelerate = accelerate_arg(accelerate)?;
    use ctlgraph::sweep::{Keep, SweepSpec, Vary};
    let mut varied = Vec::new();
    for (k, v) in vary.iter() {
        let name: String = k.extract()?;
        let spec = match v.extract::<String>() {
            Ok(text) => format!("{name}={text}"),
            Err(_) => {
                let values: Vec<f64> = v.extract().map_err(|_| {
                    PyValueError::new_err(format!("vary[{name:?}]: a list of numbers, \"LO..HI:N\" or \"LO..HI\""))
                })?;
                format!("{name}={}", values.iter().map(|x| format!("{x:e}")).collect::<Vec<_>>().join(","))
            }
        };
        varied.push(Vary::parse(&spec).map_err(|d| graph_error(py, &d))?);
    }
    let names: Vec<String> = varied.iter().map(|v| v.name().to_string()).collect();
    let spec = SweepSpec { vary: varied, random, seeds, draw_seed: seed, shard: None };
    let cases = ctlgraph::sweep::cases(&spec).map_err(|d| graph_error(py, &d))?;
    let text = std::fs::read_to_string(&path)
        .map_err(|e| graph_error(py, &Diagnostic::in_file(&path.display().to_string(), format!("cannot read: {e}"))))?;
    let jobs = jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let keep = Keep { traces_dir: None, in_memory: &|_| false };
    let stop = std::sync::atomic::AtomicBool::new(false);
    let model = py.detach(|| ctlgraph::compile_file(&path, &[])).map_err(|d| graph_error(py, &d))?;
    let runner = runner(py, accelerate, &model, &path)?;
    let rows = py
        .detach(|| ctlgraph::sweep::run(&runner, &text, &path, &names, &cases, jobs, &keep, &stop, &|| {}))
        .map_err(|e| match e {
            ctlgraph::suite::Failure::Invalid(d) => graph_error(py, &d),
            other => SimulationError::new_err(other.to_string()),
        })?;
    let table = PyDict::new(py);
    table.set_item("case", PyArray1::from_vec(py, rows.iter().map(|r| r.case.index as u64).collect()))?;
    for (k, name) in names.iter().enumerate() {
        table.set_item(name, PyArray1::from_vec(py, rows.iter().map(|r| r.case.values[k]).collect()))?;
    }
    table.set_item("seed", rows.iter().map(|r| r.case.seed).collect::<Vec<_>>())?;
    let checks: Vec<String> = rows
        .iter()
        .find_map(|r| r.result.as_ref().ok())
        .map(|checks| checks.iter().map(|c| c.name.clone()).collect())
        .unwrap_or_default();
    for (k, name) in checks.iter().enumerate() {
        let measured = rows.iter().map(|r| r.result.as_ref().map_or(f64::NAN, |c| c[k].measured)).collect();
        let passed: Vec<bool> = rows.iter().map(|r| r.result.as_ref().is_ok_and(|c| c[k].passed)).collect();
        table.set_item(name, PyArray1::from_vec(py, measured))?;
        table.set_item(format!("{name} passed"), passed)?;
    }
    table.set_item("status", rows.iter().map(|r| r.status()).collect::<Vec<_>>())?;
    let errors: Vec<Option<&str>> = rows.iter().map(|r| r.result.as_ref().err().map(String::as_str)).collect();
    table.set_item("error", errors)?;
    Ok(table.unbind())
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("GraphError", py.get_type::<GraphError>())?;
    m.add("SimulationError", py.get_type::<SimulationError>())?;
    m.add_class::<RunResult>()?;
    m.add_class::<Check>()?;
    m.add_class::<LoadedModel>()?;
    m.add_class::<Snapshot>()?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_function(wrap_pyfunction!(linearize, m)?)?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
