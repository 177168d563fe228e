//! Any bytes as a graph file: loading and compiling must return a model or
//! a positioned error, never panic, abort or hang; a model that compiles is
//! run for a bounded number of major steps.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(model) = ctlgraph::compile_str(text, "fuzz.yaml", &[]) else { return };
    let mut sim = ctlgraph::core::Simulator::new(model, None);
    for _ in 0..2000 {
        if sim.outputs().is_err() || sim.finished() || sim.advance().is_err() {
            break;
        }
    }
});
