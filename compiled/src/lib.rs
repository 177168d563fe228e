//! The bundled graphs' steps, generated as Rust at build time
//! (`ctlgraph_core::codegen`, see `build.rs`): what `ctlgraph codegen`
//! writes, compiled as a user's crate would compile it. The tests run each
//! beside the interpreter and require the same numbers to the bit; the
//! benchmarks time them against the hand-written loops.

use ctlgraph_core::Model;
use ctlgraph_core::codegen::{Compiled, GeneratedStep};

/// Runs a generated step on `model` for at most `rows` rows; returns
/// each row's time and signals as `Simulator::run_while` hands them to its
/// sink (a row at every major step, and between steps under
/// `simulation.output`).
pub type Trace = fn(model: &Model, rows: usize) -> Result<Vec<(f64, Vec<f64>)>, String>;

fn trace<G: GeneratedStep>(model: &Model, rows: usize) -> Result<Vec<(f64, Vec<f64>)>, String> {
    let mut run = Compiled::<G>::new(model, None)?;
    let mut steps = Vec::new();
    run.run_while(|t, signals| {
        steps.push((t, signals.to_vec()));
        steps.len() <= rows
    })
    .map_err(|e| e.to_string())?;
    Ok(steps)
}

include!(concat!(env!("OUT_DIR"), "/graphs.rs"));
