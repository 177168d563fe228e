//! `--accelerate`: runs through the graph's generated step instead of the
//! interpreter — Simulink's Accelerator mode, for ctlgraph.
//!
//! ctlgraph generates the step ([`ctlgraph_core::codegen`]), builds it into
//! a shared library with cargo and the compiler that built ctlgraph
//! ([`crate::toolchain`]), caches the library by a hash of the code, loads it
//! (`library.rs`) and runs it: the library compiles the graph from the same
//! text, overrides and seed, and runs it through the same driver as the
//! interpreter, so the results are the interpreter's, to the bit. Where it
//! cannot — no toolchain, another compiler, ctlgraph's source changed — the
//! run is interpreted and says why in one line; `--accelerate=require`
//! makes that an error.

mod library;
mod stepper;

use crate::toolchain;
pub use ctlgraph_core::Accelerate;
use ctlgraph_core::trace::Trace;
use ctlgraph_core::{Model, RunStats, SimError};
pub use library::{AcceleratedRun, AcceleratedSnapshot, Library};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;
pub use stepper::{Stepper, StepperSnapshot};

/// How many rows an accelerated run hands over at a time
/// ([`AcceleratedRun::run_rows`]): few enough that a program hears of an
/// interrupt soon, many enough that the call costs nothing per step.
pub const ROWS_PER_BATCH: usize = 256;

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
pub fn library(model: &Model) -> Result<(Arc<Library>, Cost), String> {
    let start = Instant::now();
    let module = ctlgraph_core::codegen::module(model);
    let (code, fingerprint) = (module.code, module.fingerprint);
    let dir = toolchain::cache_dir()?;
    let features = toolchain::Features { implicit: matches!(model.sim.method, ctlgraph_solver::Method::Trbdf2 { .. }) };
    let key = toolchain::key(&code, features);
    let path = toolchain::library_path(&dir, &key);
    if path.is_file() {
        // Marked first: another ctlgraph's prune leaves it alone from now on.
        toolchain::mark_used(&path);
        match Library::open(&path, fingerprint) {
            Ok(lib) => return Ok((lib, Cost::Loaded(start.elapsed().as_secs_f64()))),
            // Removed by another ctlgraph's prune just before: built again.
            Err(_) if !path.is_file() => {}
            Err(e) => return Err(e),
        }
    }
    toolchain::build(&dir, &key, &code, features)?;
    let lib = Library::open(&path, fingerprint)?;
    Ok((lib, Cost::Built(start.elapsed().as_secs_f64())))
}

/// How the runs of one graph are made: by its step library, or
/// interpreted.
pub enum Runner {
    Interpreted,
    Accelerated {
        lib: Arc<Library>,
        /// The graph's text and file name, which the library compiles.
        text: Arc<str>,
        file: String,
        cost: Cost,
    },
}

impl Runner {
    /// The runner `mode` asks for the graph `text` read from `file`,
    /// compiled (with its overrides' values) into `model`. Under
    /// [`Accelerate::On`] a graph that cannot be accelerated is interpreted
    /// and the second value says why; under [`Accelerate::Require`] that
    /// reason is the error.
    pub fn choose(
        mode: Accelerate,
        model: &Model,
        file: &Path,
        text: &str,
    ) -> Result<(Runner, Option<String>), String> {
        if mode == Accelerate::Off {
            return Ok((Runner::Interpreted, None));
        }
        let prepared = library(model).map(|(lib, cost)| Runner::Accelerated {
            lib,
            text: text.into(),
            file: file.display().to_string(),
            cost,
        });
        match (prepared, mode) {
            (Ok(runner), _) => Ok((runner, None)),
            (Err(why), Accelerate::Require) => Err(why),
            (Err(why), _) => Ok((Runner::Interpreted, Some(why))),
        }
    }

    /// What preparing the library cost, when runs are accelerated.
    pub fn cost(&self) -> Option<Cost> {
        match self {
            Runner::Interpreted => None,
            Runner::Accelerated { cost, .. } => Some(*cost),
        }
    }

    /// A run in the library of the graph compiled with `sets` and `seed`,
    /// to `stop`; `None` when runs are interpreted. `Err` when the library
    /// cannot run it (overrides that change the graph's structure).
    pub fn start(
        &self,
        sets: &[(String, String)],
        seed: Option<u64>,
        stop: Option<f64>,
    ) -> Result<Option<AcceleratedRun>, String> {
        match self {
            Runner::Interpreted => Ok(None),
            Runner::Accelerated { lib, text, file, .. } => lib.create(text, file, sets, seed, stop).map(Some),
        }
    }

    /// [`ctlgraph_core::trace::simulate_with_stats`] of `model`, compiled
    /// from this graph with `sets` and `seed`: in the library when it can
    /// run it, else (the overrides changed the structure) interpreted.
    pub fn simulate(
        &self,
        model: Model,
        sets: &[(String, String)],
        seed: Option<u64>,
        stop: Option<f64>,
    ) -> Result<(Trace, RunStats), SimError> {
        match self.start(sets, seed, stop) {
            Ok(Some(mut run)) => {
                let mut trace = Trace::for_run(&model, ctlgraph_core::sim::expected_major_steps(&model, stop));
                run.run_rows(u64::MAX, ROWS_PER_BATCH, &mut |batch| {
                    trace.push_columns(batch);
                    true
                })?;
                Ok((trace, run.stats()))
            }
            _ => ctlgraph_core::trace::simulate_with_stats(model, stop),
        }
    }
}
