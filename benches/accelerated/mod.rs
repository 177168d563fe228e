//! The graph's step as `--accelerate` runs it: generated, built by cargo
//! into the step cache (on the first run only) and loaded, so that the
//! benches time what a user's accelerated run does, interface included.

use ctlgraph::accel::AcceleratedRun;
use ctlgraph_core::Model;

/// A run of the graph `text` (named `file`), compiled into `model`, in its
/// step library.
pub fn accelerated(model: &Model, text: &str, file: &str) -> AcceleratedRun {
    let (lib, cost) = ctlgraph::accel::library(model).expect("the step library builds (cargo on PATH)");
    eprintln!("{file}: {cost}");
    lib.create(text, file, &[], None, None).expect("the library runs the graph")
}
