//! The solver's first stage reuses the outputs the major step has just
//! computed at the same (t, x), recomputing only the blocks whose outputs
//! may differ there (memory changed by `update`, modes, zero crossings,
//! and whatever reads them). That must change nothing: every bundled graph
//! runs the same, to the bit, as when each step's first stage recomputes
//! every output — forced here by restoring a snapshot between a major
//! step's outputs and its advance, which leaves nothing to reuse.

mod common;
use common::bundled_graphs;
use ctlgraph::compile_file;
use ctlgraph_core::{Model, Simulator};

/// Major steps compared per graph (the whole run when it is shorter).
const STEPS: usize = 3_000;

/// Graphs whose first stage must recompute a block: a dead time shorter
/// than the step reads, at a step's start, the sample its `update` has
/// just stored (the major step's output extrapolated past the history).
const STALE: &[(&str, &str)] = &[(
    "a dead time shorter than the step",
    "simulation: { stop: 2, solver: { method: rk4, step: 0.01 } }\n\
         blocks:\n  u: { type: sine, frequency: 3 }\n  d: { type: transport_delay, delay: 0.004 }\n  \
         g: { type: gain, k: 2 }\n  x: { type: integrator }\nwires:\n  - u -> d\n  - d -> g\n  - g -> x\n",
)];

/// (t, signals) at each major step, with the first stage's reuse or without.
fn trace(model: Model, reuse: bool) -> Vec<(u64, Vec<u64>)> {
    let mut sim = Simulator::new(model, None);
    let mut steps = Vec::new();
    loop {
        sim.outputs().unwrap();
        steps.push((sim.time().to_bits(), sim.signals().iter().map(|v| v.to_bits()).collect()));
        if sim.finished() || steps.len() > STEPS {
            return steps;
        }
        if !reuse {
            let snapshot = sim.state();
            sim.restore(&snapshot).unwrap();
        }
        sim.advance().unwrap();
    }
}

#[test]
fn reusing_the_first_stage_changes_no_bundled_graphs_result() {
    let found = bundled_graphs();
    let mut compared = 0;
    for path in &found {
        let model = || compile_file(path, &[]);
        let Ok(first) = model() else { continue }; // a comparison or sweep file, not one graph
        assert_same(&path.display().to_string(), &trace(first, true), &trace(model().unwrap(), false));
        compared += 1;
    }
    // Events (resets, relays, hit crossings), delays, the stiff solver,
    // Dormand–Prince, sampled controllers, the papers' loops.
    assert!(compared >= 20, "only {compared} graphs compared of {}", found.len());
}

#[test]
fn a_block_whose_output_its_update_changes_is_recomputed_at_the_steps_start() {
    for (what, yaml) in STALE {
        let model = || ctlgraph::compile_str(yaml, "stale.yaml", &[]).unwrap();
        assert_same(what, &trace(model(), true), &trace(model(), false));
    }
}

fn assert_same(what: &str, with: &[(u64, Vec<u64>)], without: &[(u64, Vec<u64>)]) {
    assert_eq!(with.len(), without.len(), "{what}: major steps");
    for (k, (a, b)) in with.iter().zip(without).enumerate() {
        assert_eq!(a, b, "{what}: major step {k} differs");
    }
}
