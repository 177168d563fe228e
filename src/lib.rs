//! ctlgraph: declarative control graphs. A YAML file describes blocks and
//! wires; ctlgraph validates it, compiles it to a sorted dataflow model and
//! simulates it with Simulink's semantics.
//!
//! ```no_run
//! let model = ctlgraph::compile_file("graphs/tutorial/first_order.yaml".as_ref(), &[]).unwrap();
//! let trace = ctlgraph::simulate(model, None).unwrap();
//! println!("y(end) = {}", trace.column("y").unwrap().last().unwrap());
//! ```

pub mod accel;
pub mod analysis;
pub mod cache;
pub mod diagram;
pub mod dot;
pub mod fmu;
pub mod html;
pub mod lsp;
pub mod plot;
pub mod prop;
pub mod record;
pub mod reference;
pub mod report;
pub mod schema;
pub mod suite;
pub mod sweep;
pub mod sweep_plot;
pub mod target_c;
pub mod toolchain;

pub use ctlgraph_blocks as blocks;
pub use ctlgraph_core as core;
pub use ctlgraph_solver as solver;

pub use ctlgraph_core::trace::simulate;
use ctlgraph_core::{Diagnostic, FlatGraph, Model, Registry};
use std::path::Path;

/// The full block library.
pub fn registry() -> Registry {
    ctlgraph_blocks::registry()
}

/// Loads, expands and compiles a graph file. `sets` are `--set NAME=VALUE`
/// parameter overrides.
pub fn compile_file(path: &Path, sets: &[(String, String)]) -> Result<Model, Diagnostic> {
    compile_file_with(path, sets, &registry())
}

/// Like [`compile_file`] with a registry of your own (the library's types
/// plus custom blocks; see `examples/custom_block.rs`).
pub fn compile_file_with(path: &Path, sets: &[(String, String)], registry: &Registry) -> Result<Model, Diagnostic> {
    compile_flat(&ctlgraph_core::load(path, sets)?, registry)
}

/// Compiles a loaded graph; when its checks read figures of the analysed
/// loop (`phase_margin > 45`), a second copy is compiled and linearised
/// around its initial operating point to provide them.
pub fn compile_flat(flat: &FlatGraph, registry: &Registry) -> Result<Model, Diagnostic> {
    let model = ctlgraph_core::compile(flat, registry)?;
    with_loop_figures(model, || ctlgraph_core::compile(flat, registry))
}

/// Like [`compile_flat`] for a graph loaded with other parameter values
/// than `base`'s (a sweep's case): on `base`'s structure when the graph
/// has the same ([`ctlgraph_core::recompile`]), so only its blocks are built.
pub fn recompile_flat(base: &Model, flat: &FlatGraph, registry: &Registry) -> Result<Model, Diagnostic> {
    let model = ctlgraph_core::recompile(base, flat, registry)?;
    with_loop_figures(model, || ctlgraph_core::recompile(base, flat, registry))
}

/// `model` with the analysed loop's figures, when its checks read them,
/// from a twin linearised around its initial operating point.
fn with_loop_figures(mut model: Model, twin: impl FnOnce() -> Result<Model, Diagnostic>) -> Result<Model, Diagnostic> {
    if model.checks.iter().any(|c| c.needs_loop_figures()) {
        model.loop_figures = Some(analysis::loop_figures(twin()?)?);
    }
    Ok(model)
}

/// Like [`compile_file`] with `simulation.seed` replaced (random blocks
/// derive their streams from it when they are built).
pub fn compile_file_seeded(path: &Path, sets: &[(String, String)], seed: Option<u64>) -> Result<Model, Diagnostic> {
    compile_flat(&load_seeded(path, sets, seed)?, &registry())
}

/// Loads a graph file with `simulation.seed` replaced, for compiling with
/// [`compile_flat`] when the loaded graph is needed too (the HTML report).
pub fn load_seeded(path: &Path, sets: &[(String, String)], seed: Option<u64>) -> Result<FlatGraph, Diagnostic> {
    let mut flat = ctlgraph_core::load(path, sets)?;
    if let Some(s) = seed {
        flat.sim.seed = s;
    }
    Ok(flat)
}

/// Like [`compile_file`] for graph text in memory; `name` stands for the
/// file in messages (and relative paths resolve from its folder).
pub fn compile_str(text: &str, name: &str, sets: &[(String, String)]) -> Result<Model, Diagnostic> {
    let flat = ctlgraph_core::load_str(text, name.into(), sets)?;
    compile_flat(&flat, &registry())
}
