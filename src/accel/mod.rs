//! `--accelerate`: runs through the graph's generated step instead of the
//! interpreter — Simulink's Accelerator mode, for ctlgraph.
//!
//! ctlgraph generates the step ([`ctlgraph_core::codegen`]), builds it into
//! a shared library with cargo and the compiler that built ctlgraph
//! ([`toolchain`]), caches the library by a hash of the code, loads it
//! ([`library`]) and runs it: the library compiles the graph from the same
//! text, overrides and seed, and runs it through the same driver as the
//! interpreter, so the results are the interpreter's, to the bit. Where it
//! cannot — no toolchain, a graph the generated step does not cover — the
//! run is interpreted and says why in one line; `--accelerate=require`
//! makes that an error.

mod library;
mod source;
mod toolchain;

pub use library::{AcceleratedRun, Library};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// Whether a run is accelerated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Mode {
    /// Interpreted.
    #[default]
    Off,
    /// Accelerated when it can be, else interpreted with a note why.
    On,
    /// Accelerated, or an error.
    Require,
}

impl Mode {
    /// `--accelerate=VALUE`: `on` (the bare flag), `require`, `off`.
    pub fn parse(value: &str) -> Result<Mode, String> {
        match value {
            "on" | "true" => Ok(Mode::On),
            "require" => Ok(Mode::Require),
            "off" | "false" => Ok(Mode::Off),
            other => Err(format!("`{other}`: expected on, require or off")),
        }
    }
}

/// What making a library ready cost: a build (cold cache) or only a load.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cost {
    /// Seconds to build it with cargo and load it.
    Built(f64),
    /// Seconds to load it from the cache.
    Loaded(f64),
}

impl std::fmt::Display for Cost {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Cost::Built(s) => write!(f, "step built in {s:.1} s"),
            Cost::Loaded(s) => write!(f, "step loaded from the cache in {:.1} ms", s * 1e3),
        }
    }
}

/// The step library for `model`'s structure, from the cache or built now;
/// `Err` says in one sentence why there is none.
pub fn library(model: &ctlgraph_core::Model) -> Result<(Arc<Library>, Cost), String> {
    let start = Instant::now();
    let code = ctlgraph_core::codegen::generate(model)
        .map_err(|why| format!("the generated step does not cover this graph: {}", why.join("; ")))?;
    let fingerprint = ctlgraph_core::codegen::fingerprint(model).unwrap_or_default();
    let dir = toolchain::cache_dir()?;
    let key = toolchain::key(&code);
    let path = toolchain::library_path(&dir, &key);
    if path.is_file() {
        let lib = Library::open(&path, fingerprint)?;
        return Ok((lib, Cost::Loaded(start.elapsed().as_secs_f64())));
    }
    toolchain::build(&dir, &key, &code)?;
    let lib = Library::open(&path, fingerprint)?;
    Ok((lib, Cost::Built(start.elapsed().as_secs_f64())))
}

/// An accelerated run of the graph file `graph` as the program compiled it
/// into `model` (with `sets`, `seed` and `stop`), and what preparing it cost.
pub fn run(
    model: &ctlgraph_core::Model,
    graph: &Path,
    sets: &[(String, String)],
    seed: Option<u64>,
    stop: Option<f64>,
) -> Result<(AcceleratedRun, Cost), String> {
    let (lib, cost) = library(model)?;
    let text = ctlgraph_core::files::read_text(graph, ctlgraph_core::files::MAX_GRAPH_FILE)
        .map_err(|e| format!("cannot read {}: {e}", graph.display()))?;
    let start = Instant::now();
    let run = lib.create(&text, &graph.display().to_string(), sets, seed, stop)?;
    let cost = match cost {
        Cost::Built(s) => Cost::Built(s + start.elapsed().as_secs_f64()),
        Cost::Loaded(s) => Cost::Loaded(s + start.elapsed().as_secs_f64()),
    };
    Ok((run, cost))
}
