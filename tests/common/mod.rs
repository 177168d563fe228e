//! Helpers shared by the integration tests.
#![allow(dead_code)]

use ctlgraph::record::Trace;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `ctlgraph` binary (as CI would: no progress bar), with the
/// accelerated steps cached where `tests/accelerate.rs` caches them.
pub fn ctlgraph(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ctlgraph"))
        .args(args)
        .env("CI", "1")
        .env("CTLGRAPH_CACHE_DIR", accelerate_cache())
        .output()
        .expect("runs")
}

/// The cache of accelerated steps the tests share (kept between test runs).
pub fn accelerate_cache() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("accelerate-cache")
}

pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

pub fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Compiles graph text (named `test.yaml` in messages) and runs it.
pub fn run(yaml: &str) -> Trace {
    let model = ctlgraph::compile_str(yaml, "test.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
    ctlgraph::simulate(model, None).unwrap_or_else(|e| panic!("{e}"))
}

/// The compile error of graph text.
pub fn error(yaml: &str) -> ctlgraph::core::Diagnostic {
    match ctlgraph::compile_str(yaml, "test.yaml", &[]) {
        Ok(_) => panic!("expected an error for:\n{yaml}"),
        Err(d) => d,
    }
}

/// Largest |a - b| over a column against a closed form f(t).
pub fn max_error(trace: &Trace, column: &str, f: impl Fn(f64) -> f64) -> f64 {
    let ys = trace.column(column).unwrap_or_else(|| panic!("no column {column}"));
    trace.t().iter().zip(ys).map(|(&t, &y)| (y - f(t)).abs()).fold(0.0, f64::max)
}

/// Runs one library block on test signals (one per input port, in order)
/// with the property-testing harness; panics with the block and parameters.
pub fn run_block(ty: &str, params: &str, inputs: &[&ctlgraph::blocks::testing::Signal], stop: f64) -> Trace {
    let registry = ctlgraph::registry();
    let mut h = ctlgraph::blocks::testing::Harness::new(&registry, ty, params);
    for s in inputs {
        h = h.input(s);
    }
    h.run(stop).unwrap_or_else(|e| panic!("{ty} {{ {params} }}: {e}"))
}

/// Every graph file under `graphs/` (the libraries' too), sorted.
pub fn bundled_graphs() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "yaml") {
                out.push(path);
            }
        }
    }
    let mut found = Vec::new();
    walk(Path::new("graphs"), &mut found);
    // Not `graphs/fmu/`: its loop needs an FMU exported first, which
    // `tests/checks.rs` does before `ctlgraph test graphs`.
    found.retain(|g| !g.starts_with("graphs/fmu"));
    found.sort();
    found
}
