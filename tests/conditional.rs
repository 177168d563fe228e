//! Conditionally executed subsystems (`enable:`, `trigger:` on a
//! subsystem block) against closed forms: an enabled integrator whose
//! state is held or reset, a triggered sample-and-hold, a triggered
//! counter, and both combined.

mod common;
use common::{max_error, path};
use std::path::Path;

/// A subsystem file `name` in `dir`.
fn file(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).unwrap();
}

fn run_in(dir: &Path, yaml: &str) -> ctlgraph::record::Trace {
    let graph = dir.join("graph.yaml");
    std::fs::write(&graph, yaml).unwrap();
    let model = ctlgraph::compile_file(&graph, &[]).unwrap_or_else(|d| panic!("{d}"));
    ctlgraph::simulate(model, None).unwrap_or_else(|e| panic!("{e}"))
}

const INTEGRATOR: &str =
    "blocks:\n  u: { type: inport }\n  x: { type: integrator }\n  y: { type: outport }\nwires: [u -> x, x -> y]\n";

/// ẋ = 1 enabled while sin(π/2·t + 0.3) > 0: on until t1 = (π − 0.3)/(π/2),
/// off until t2 = (2π − 0.3)/(π/2), on again. Held: x = t, then t1, then
/// t1 + (t − t2). Reset: 0 while off (outputs: reset), and from t2 on
/// t − t2 (states: reset). The switches are located zero crossings.
#[test]
fn an_enabled_integrator_holds_or_resets() {
    let dir = tempfile::tempdir().unwrap();
    file(dir.path(), "integ.yaml", INTEGRATOR);
    let trace = run_in(
        dir.path(),
        "simulation: { stop: 5.5, solver: { method: dopri5, rtol: 1e-10, atol: 1e-12 } }\nblocks:\n\
         \x20 one: { type: constant, value: 1 }\n  en: { type: sine, frequency: 0.25, phase: 0.3 }\n\
         \x20 held: { type: subsystem, file: integ.yaml, enable: { states: held, outputs: held } }\n\
         \x20 reset: { type: subsystem, file: integ.yaml, enable: { states: reset, outputs: reset } }\n\
         wires: [one -> held.u, en -> held.enable, one -> reset.u, en -> reset.enable]\nrecord: [held, reset]\n",
    );
    let half_pi = std::f64::consts::FRAC_PI_2;
    let (t1, t2) = ((std::f64::consts::PI - 0.3) / half_pi, (2.0 * std::f64::consts::PI - 0.3) / half_pi);
    let near = |t: f64| (t - t1).abs() < 1e-6 || (t - t2).abs() < 1e-6;
    let held = |t: f64| {
        if t < t1 {
            t
        } else if t < t2 {
            t1
        } else {
            t1 + t - t2
        }
    };
    let reset = |t: f64| {
        if t < t1 {
            t
        } else if t < t2 {
            0.0
        } else {
            t - t2
        }
    };
    for (name, f) in [("held", &held as &dyn Fn(f64) -> f64), ("reset", &reset)] {
        let column = trace.column(name).unwrap();
        for (&t, &y) in trace.t().iter().zip(column) {
            if !near(t) {
                assert!((y - f(t)).abs() < 1e-8, "{name} at t = {t}: {y} vs {}", f(t));
            }
        }
    }
}

/// A triggered subsystem wired straight from its inport to its outport is
/// a sample-and-hold: on u = t, triggered by the rising zero crossings of
/// sin(2π·t − π/2) (t = 0.25, 1.25, …, located), it holds 0, then 0.25,
/// 1.25, …; the falling one samples at 0.75, 1.75, ….
#[test]
fn a_triggered_subsystem_samples_and_holds() {
    let dir = tempfile::tempdir().unwrap();
    file(dir.path(), "sh.yaml", "blocks:\n  u: { type: inport }\n  y: { type: outport }\nwires: [u -> y]\n");
    let trace = run_in(
        dir.path(),
        "simulation: { stop: 3.8, solver: { method: dopri5, rtol: 1e-10, atol: 1e-12 } }\nblocks:\n\
         \x20 u: { type: clock }\n  clk: { type: sine, frequency: 1, phase: -1.5707963267948966 }\n\
         \x20 up: { type: subsystem, file: sh.yaml, trigger: rising }\n\
         \x20 down: { type: subsystem, file: sh.yaml, trigger: falling }\n\
         wires: [u -> up.u, clk -> up.trigger, u -> down.u, clk -> down.trigger]\nrecord: [up, down]\n",
    );
    let off_edge = |t: f64| (4.0 * t - (4.0 * t).round()).abs() > 1e-6;
    let sampled = |t: f64, at: f64| if t < at { 0.0 } else { (t - at).floor() + at };
    let (up, down) = (|t: f64| sampled(t, 0.25), |t: f64| sampled(t, 0.75));
    for (i, &t) in trace.t().iter().enumerate() {
        if off_edge(t) {
            assert!((trace.column("up").unwrap()[i] - up(t)).abs() < 1e-9, "up at {t}");
            assert!((trace.column("down").unwrap()[i] - down(t)).abs() < 1e-9, "down at {t}");
        }
    }
}

const COUNTER: &str = "blocks:\n  one: { type: constant, value: 1 }\n  add: { type: sum, signs: \"++\" }\n\
                       \x20 prev: { type: unit_delay, sample_time: 1 }\n  n: { type: outport }\n\
                       wires: [one -> add.u1, prev -> add.u2, add -> prev, add -> n]\n";

/// A counter (n = n⁻ + 1 through a unit delay) triggered by a pulse train's
/// rising edges at t = 1, 2, … (its jumps, stepped onto): n(t) = floor(t),
/// the delay advancing once per edge whatever its own sample time. Enabled
/// as well, by a step at 2.5, it counts only the edges from then on.
#[test]
fn a_triggered_counter_counts_edges_and_an_enabled_one_only_while_enabled() {
    let dir = tempfile::tempdir().unwrap();
    file(dir.path(), "counter.yaml", COUNTER);
    let trace = run_in(
        dir.path(),
        "simulation: { stop: 5.5, solver: { method: rk4, step: 0.1 } }\nblocks:\n\
         \x20 clk: { type: pulse, period: 1, duty: 0.5 }\n  gate: { type: step, at: 2.5, initial: -1, value: 1 }\n\
         \x20 all: { type: subsystem, file: counter.yaml, trigger: rising }\n\
         \x20 gated: { type: subsystem, file: counter.yaml, trigger: rising, enable: true }\n\
         wires: [clk -> all.trigger, clk -> gated.trigger, gate -> gated.enable]\nrecord: [all, gated]\n",
    );
    assert!(max_error(&trace, "all", |t| (t + 1e-9).floor()) < 1e-12);
    assert!(max_error(&trace, "gated", |t| if t < 3.0 - 1e-9 { 0.0 } else { (t + 1e-9).floor() - 2.0 }) < 1e-12);
}

/// What cannot be conditional is refused, naming the block and the key.
#[test]
fn refusals_name_the_subsystem_and_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    file(dir.path(), "integ.yaml", INTEGRATOR);
    let graph = dir.path().join("graph.yaml");
    let compile = |yaml: &str| {
        std::fs::write(&graph, yaml).unwrap();
        ctlgraph::compile_file(&graph, &[]).err().map(|d| d.to_string()).unwrap_or_default()
    };
    let triggered_state = compile(
        "blocks:\n  one: { type: constant }\n  c: { type: pulse }\n  s: { type: subsystem, file: integ.yaml, trigger: rising }\n\
         wires: [one -> s.u, c -> s.trigger]\n",
    );
    assert!(triggered_state.contains("subsystem `s` is triggered: `s/x` has continuous states"), "{triggered_state}");
    let unwired = compile(
        "blocks:\n  one: { type: constant }\n  s: { type: subsystem, file: integ.yaml, enable: true }\nwires: [one -> s.u]\n",
    );
    assert!(unwired.contains("its `enable` port is not wired"), "{unwired}");
    let typo = compile("blocks:\n  s: { type: subsystem, file: integ.yaml, trigger: rise }\n");
    assert!(
        typo.contains(":2:") && typo.contains("expected rising, falling or either") && typo.contains("rising"),
        "{typo}"
    );
    let _ = path(&graph);
    // An `enable` fed from inside the subsystem closes a loop through it: solved, named after the subsystem.
    file(
        dir.path(),
        "gain.yaml",
        "blocks:\n  u: { type: inport }\n  g: { type: gain, k: 2 }\n  y: { type: outport }\nwires: [u -> g, g -> y]\n",
    );
    std::fs::write(&graph, "blocks:\n  r: { type: sine }\n  s: { type: subsystem, file: gain.yaml, enable: true }\nwires: [r -> s.u, s -> s.enable]\n").unwrap();
    let model = ctlgraph::compile_file(&graph, &[]).unwrap_or_else(|d| panic!("{d}"));
    assert!(model.algebraic_loops[0].starts_with("algebraic loop s -> s: solved for s"), "{:?}", model.algebraic_loops);
}

/// A discrete block inside an enabled subsystem keeps its own rate: the
/// counter's unit delay (T = 0.1 s) advances at its hits while enabled
/// (0.25 ≤ t < 0.75 and 1.25 ≤ t < 1.75) and holds while disabled. Its
/// output n = n⁻ + 1 reads 1 from the enabling on, then one more at each
/// hit after the first: 2 at 0.4, …, 5 at 0.7, held; 6 at 1.3, …, 10 at 1.7.
#[test]
fn a_discrete_block_in_an_enabled_subsystem_keeps_its_hits() {
    let dir = tempfile::tempdir().unwrap();
    file(dir.path(), "counter.yaml", &COUNTER.replace("sample_time: 1", "sample_time: 0.1"));
    let trace = run_in(
        dir.path(),
        "simulation: { stop: 2, solver: { method: dopri5 } }\nblocks:\n\
         \x20 en: { type: pulse, period: 1, duty: 0.5, delay: 0.25 }\n\
         \x20 c: { type: subsystem, file: counter.yaml, enable: true }\nwires: [en -> c.enable]\nrecord: [c]\n",
    );
    let want = |t: f64| {
        let hits = |from: f64, to: f64| ((to.min(t) - from) / 0.1 + 1e-9).floor().max(0.0);
        if t < 0.25 - 1e-12 {
            0.0
        } else if t < 1.25 - 1e-12 {
            1.0 + hits(0.3, 0.7)
        } else {
            5.0 + hits(1.2, 1.7)
        }
    };
    assert!(max_error(&trace, "c", want) < 1e-12, "{}", max_error(&trace, "c", want));
}
