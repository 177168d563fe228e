//! The solver's first stage reuses the outputs the major step has just
//! computed at the same (t, x), recomputing only the blocks whose outputs
//! may differ there (memory changed by `update`, modes, zero crossings,
//! and whatever reads them). That must change nothing: every bundled graph
//! runs the same, to the bit, as when each step's first stage recomputes
//! every output — forced here by restoring a snapshot between a major
//! step's outputs and its advance, which leaves nothing to reuse. Blocks
//! whose outputs are a function of time alone run once per time.

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

/// A time-only block (`Block::time_only`) runs once per time: under RK4 at
/// t + h/2 (the two middle stages) and at t + h (the last stage, whose
/// outputs the next major step keeps) — unless it is sided, when the last
/// stage's left limit and the major step's time are two times.
#[test]
fn a_time_only_block_runs_once_per_time() {
    use ctlgraph::core::registry::{BlockType, Built};
    use ctlgraph::core::{Block, Diagnostic, Interface, Io, Params, SampleTime, TimeOnly, Width};
    use std::sync::atomic::{AtomicUsize, Ordering};
    /// y = t, counting its calls.
    #[derive(Clone)]
    struct Counted(&'static AtomicUsize, bool);
    impl Block for Counted {
        fn output(&mut self, io: &mut Io) {
            self.0.fetch_add(1, Ordering::Relaxed);
            io.set(0, io.t);
        }
        fn time_only(&self) -> Option<TimeOnly> {
            Some(if self.1 { TimeOnly::JumpsAtEvents } else { TimeOnly::Smooth })
        }
    }
    /// The two blocks' counters: unsided, sided.
    static CALLS: [AtomicUsize; 2] = [AtomicUsize::new(0), AtomicUsize::new(0)];
    fn counted(sided: bool) -> Result<Built, Diagnostic> {
        let block = Counted(&CALLS[usize::from(sided)], sided);
        Ok(Built::new(block, Interface::new(SampleTime::Continuous).output("y", Width::Fixed(1))))
    }
    let mut reg = ctlgraph::registry();
    for (name, build) in [
        ("counted", (|_: &mut Params| counted(false)) as fn(&mut Params) -> Result<Built, Diagnostic>),
        ("counted_sided", |_: &mut Params| counted(true)),
    ] {
        reg.register(BlockType {
            name,
            category: "test",
            summary: "y = t, counting its calls",
            doc: "test",
            inputs: &[],
            outputs: &[],
            params: &[],
            build,
        });
    }
    for (sided, per_step) in [(false, 2), (true, 3)] {
        let yaml = format!(
            "simulation: {{ stop: 1.0, solver: {{ method: rk4, step: 0.01 }} }}\n\
             blocks:\n  u: {{ type: {} }}\n  x: {{ type: integrator }}\nwires:\n  - u -> x\n",
            if sided { "counted_sided" } else { "counted" }
        );
        let flat = ctlgraph::core::load_str(&yaml, "counted.yaml".into(), &[]).unwrap();
        let model = ctlgraph::core::compile(&flat, &reg).unwrap();
        let mut sim = Simulator::new(model, None);
        let calls = &CALLS[usize::from(sided)];
        calls.store(0, Ordering::Relaxed);
        let mut steps = 0;
        loop {
            sim.outputs().unwrap();
            if sim.finished() {
                break;
            }
            sim.advance().unwrap();
            steps += 1;
        }
        assert_eq!(steps, 100);
        assert_eq!(calls.load(Ordering::Relaxed), 1 + per_step * steps, "sided: {sided}");
        // x = t²/2, which RK4 integrates exactly.
        assert!((sim.states()[0] - 0.5).abs() < 1e-14, "x(1) = {}", sim.states()[0]);
    }
}
