//! The bundled graphs' steps, generated as Rust at build time
//! (`ctlgraph_core::codegen`, see `build.rs`): what `ctlgraph codegen`
//! writes, compiled as a user's crate would compile it. The tests run each
//! beside the interpreter and require the same numbers to the bit; the
//! benchmarks time them against the hand-written loops.

use ctlgraph_core::Model;
use ctlgraph_core::codegen::{Compiled, GeneratedStep};

/// Runs a generated step on `model` for at most `major_steps` major
/// steps; returns each major step's time and signals (as
/// `Simulator::run` hands them to its sink).
pub type Trace = fn(model: &Model, major_steps: usize) -> Result<Vec<(f64, Vec<f64>)>, String>;

fn trace<G: GeneratedStep>(model: &Model, major_steps: usize) -> Result<Vec<(f64, Vec<f64>)>, String> {
    let mut run = Compiled::<G>::new(model, None)?;
    let mut steps = Vec::new();
    loop {
        run.outputs().map_err(|e| e.to_string())?;
        steps.push((run.time(), run.signals().to_vec()));
        if run.finished() || steps.len() > major_steps {
            return Ok(steps);
        }
        run.advance().map_err(|e| e.to_string())?;
    }
}

include!(concat!(env!("OUT_DIR"), "/graphs.rs"));
