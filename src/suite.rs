//! Graphs as regression tests: run a graph and evaluate its `checks:`;
//! find every graph with checks under some paths and run them in parallel
//! (`ctlgraph test`).

use crate::accel::{Accelerate, Runner};
use crate::record::Trace;
use ctlgraph_core::checks::CheckResult;
use ctlgraph_core::spec::GraphFile;
use ctlgraph_core::{Diagnostic, Model};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// Why a graph produced no verdicts.
#[derive(Clone, Debug, PartialEq)]
pub enum Failure {
    /// The input is invalid (exit code 2).
    Invalid(Diagnostic),
    /// The run failed (exit code 1).
    Run(String),
    /// SIGINT or SIGTERM ended the command early (exit code 130).
    Interrupted(String),
}

impl Failure {
    pub fn exit_code(&self) -> u8 {
        match self {
            Failure::Invalid(_) => 2,
            Failure::Run(_) => 1,
            Failure::Interrupted(_) => 130,
        }
    }
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Failure::Invalid(d) => write!(f, "{d}"),
            Failure::Run(m) | Failure::Interrupted(m) => f.write_str(m),
        }
    }
}

impl From<Diagnostic> for Failure {
    fn from(d: Diagnostic) -> Self {
        Failure::Invalid(d)
    }
}

/// Simulates a compiled model and evaluates its checks.
pub fn run_checks(model: Model, stop: Option<f64>) -> Result<(Trace, Vec<CheckResult>), Failure> {
    run_checks_by(&Runner::Interpreted, model, &[], None, stop)
}

/// [`run_checks`] for a model `runner`'s graph compiled with `sets` and
/// `seed` (which an accelerated runner's library compiles likewise).
pub fn run_checks_by(
    runner: &Runner,
    model: Model,
    sets: &[(String, String)],
    seed: Option<u64>,
    stop: Option<f64>,
) -> Result<(Trace, Vec<CheckResult>), Failure> {
    let checks = model.checks.clone();
    let (trace, _) = runner.simulate(model, sets, seed, stop).map_err(|e| Failure::Run(e.to_string()))?;
    let results = checks.iter().map(|c| trace.check(c)).collect();
    Ok((trace, results))
}

/// One graph's outcome in a test run.
pub struct GraphOutcome {
    pub path: PathBuf,
    pub result: Result<Vec<CheckResult>, Failure>,
    /// Under `--accelerate`: what preparing the step cost, or why the graph
    /// ran interpreted.
    pub accelerated: Option<Result<crate::accel::Cost, String>>,
}

/// Graph files (`.yaml`, `.yml`) under `paths`, sorted, that have checks.
/// Files named directly are kept even without checks, so that naming one
/// by mistake is visible.
pub fn discover(paths: &[PathBuf]) -> Result<Vec<PathBuf>, Diagnostic> {
    let mut found = Vec::new();
    for p in paths {
        if p.is_dir() {
            let mut files = Vec::new();
            walk(p, &mut files).map_err(|e| Diagnostic::in_file(&p.display().to_string(), e.to_string()))?;
            files.retain(|f| has_checks(f));
            found.extend(files);
        } else if p.is_file() {
            found.push(p.clone());
        } else {
            return Err(Diagnostic::in_file(&p.display().to_string(), "no such file or folder"));
        }
    }
    found.sort();
    found.dedup();
    Ok(found)
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        if path.is_dir() {
            walk(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "yaml" || e == "yml") {
            out.push(path);
        }
    }
    Ok(())
}

/// Whether a file parses as a graph with a non-empty `checks:` list. Files
/// that do not parse count as having checks, so their errors are reported.
fn has_checks(path: &Path) -> bool {
    let Ok(text) = ctlgraph_core::files::read_text(path, ctlgraph_core::files::MAX_GRAPH_FILE) else { return true };
    GraphFile::parse(&text, path.display().to_string().into()).map_or(true, |g| !g.checks.is_empty())
}

/// Runs every graph (in parallel) and evaluates its checks; `accelerate`
/// (when given) overrides each graph's `simulation.accelerate`.
pub fn run_all(graphs: &[PathBuf], accelerate: Option<Accelerate>) -> Vec<GraphOutcome> {
    graphs
        .par_iter()
        .map(|path| {
            let mut accelerated = None;
            let result = crate::compile_file(path, &[])
                .map_err(Failure::from)
                .and_then(|model| {
                    if model.checks.is_empty() {
                        return Err(Failure::Invalid(Diagnostic::in_file(
                            &path.display().to_string(),
                            "has no `checks:` to test",
                        )));
                    }
                    let (runner, note) = runner_for(accelerate, &model, path)?;
                    accelerated = match (runner.cost(), note) {
                        (Some(cost), _) => Some(Ok(cost)),
                        (None, Some(why)) => Some(Err(why)),
                        (None, None) => None,
                    };
                    run_checks_by(&runner, model, &[], None, None)
                })
                .map(|(_, results)| results);
            GraphOutcome { path: path.clone(), result, accelerated }
        })
        .collect()
}

/// The runner for the graph file `path` compiled into `model`: `flag` or
/// else the graph's `simulation.accelerate`, with the note why a graph that
/// asked to be accelerated is not; under `require`, that reason is an error.
pub fn runner_for(flag: Option<Accelerate>, model: &Model, path: &Path) -> Result<(Runner, Option<String>), Failure> {
    let mode = flag.unwrap_or(model.sim.accelerate);
    if mode == Accelerate::Off {
        return Ok((Runner::Interpreted, None));
    }
    let text = ctlgraph_core::files::read_text(path, ctlgraph_core::files::MAX_GRAPH_FILE)
        .map_err(|e| Failure::Run(format!("cannot read {}: {e}", path.display())))?;
    Runner::choose(mode, model, path, &text).map_err(|why| {
        Diagnostic::in_file(&path.display().to_string(), format!("--accelerate=require: cannot accelerate: {why}"))
            .into()
    })
}
