//! Driving a run step by step: chunks equal one run bit for bit, inputs
//! set by the host hold between steps, landing times are exact, and
//! mistakes are errors that name what exists.

use ctlgraph::core::Simulator;
use std::path::Path;

fn simulator(file: &str) -> Simulator {
    Simulator::new(ctlgraph::compile_file(Path::new(file), &[]).unwrap(), None)
}

/// The signal buffer at each multiple of `chunk` [s], by one run and by
/// `advance_to` in chunks: equal, bit for bit.
fn chunks_equal_one_run(file: &str, chunk: f64, stop: f64) {
    let n = (stop / chunk).round() as usize;
    let mut whole = Vec::new();
    let mut sim = simulator(file);
    let mut next = 1;
    sim.run(&mut |t, signals| {
        if next <= n && (t - next as f64 * chunk).abs() < 1e-12 {
            whole.push(signals.to_vec());
            next += 1;
        }
    })
    .unwrap();
    assert_eq!(whole.len(), n, "{file}: the run passed every chunk boundary");
    let mut stepped = simulator(file);
    for (k, expected) in whole.iter().enumerate() {
        let t = (k + 1) as f64 * chunk;
        stepped.advance_to(t).unwrap();
        assert!((stepped.time() - t).abs() < 1e-12, "{file}: landed at {} for {t}", stepped.time());
        let same = stepped.signals().iter().zip(expected).all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(same, "{file}: signals differ at t = {t}");
    }
}

#[test]
fn stepping_in_chunks_is_one_run_bit_for_bit() {
    // Fixed-step graphs with discrete rates, events, zero crossings, delays
    // and exactly held LTI plants; 1 ms chunks fall on their grids.
    chunks_equal_one_run("graphs/fladrc/fladrc.yaml", 1e-3, 2.0);
    chunks_equal_one_run("graphs/milling/hinf.yaml", 1e-3, 0.5);
    chunks_equal_one_run("graphs/tutorial/multirate.yaml", 1e-3, 1.0);
}

#[test]
fn an_adaptive_run_lands_exactly_on_each_time() {
    let mut sim = simulator("graphs/tutorial/pid_loop.yaml");
    for k in 1..=30 {
        let t = k as f64 * 0.0123;
        sim.advance_to(t).unwrap();
        assert_eq!(sim.time(), t);
    }
    // Close to the run's own result at the stop time (the landings cut its steps).
    let mut whole = simulator("graphs/tutorial/pid_loop.yaml");
    whole.run(&mut |_, _| {}).unwrap();
    sim.advance_to(3.0).unwrap();
    let difference = (sim.signal("y").unwrap()[0] - whole.signal("y").unwrap()[0]).abs();
    assert!(difference < 1e-6, "{difference}");
}

const HOSTED: &str = "simulation: { stop: 1.0, solver: { method: rk4, step: 1.0e-3 } }\n\
    blocks:\n  u: { type: inport, value: 2 }\n  k: { type: gain, k: 3 }\n  \
    x: { type: integrator }\n  y: { type: outport }\n  v: { type: inport, width: 2 }\n  \
    w: { type: outport }\n\
    wires: [u -> k, k -> x, x -> y, v -> w]\n";

fn hosted() -> Simulator {
    Simulator::new(ctlgraph::compile_str(HOSTED, "hosted.yaml", &[]).unwrap(), None)
}

#[test]
fn inputs_hold_between_steps_and_reach_the_outputs() {
    let mut sim = hosted();
    assert_eq!(sim.input_names().collect::<Vec<_>>(), ["u", "v"]);
    assert_eq!(sim.output_names().collect::<Vec<_>>(), ["y", "w"]);
    // u = 2 (its `value`) until set: x' = 3u.
    sim.advance_to(0.1).unwrap();
    assert!((sim.output("y").unwrap()[0] - 0.6).abs() < 1e-12);
    sim.set_input("u", &[-1.0]).unwrap();
    sim.advance_to(0.3).unwrap();
    assert!((sim.output("y").unwrap()[0] - (0.6 - 0.6)).abs() < 1e-12);
    // Set between grid points: held from there on, landing exactly.
    sim.advance_to(0.3005).unwrap();
    sim.set_input("u", &[10.0]).unwrap();
    sim.advance_to(0.4).unwrap();
    let expected = -3.0 * 0.0005 + 30.0 * 0.0995;
    assert!((sim.output("y").unwrap()[0] - expected).abs() < 1e-11, "{:?}", sim.output("y"));
    // An input reaches what it feeds through at once, without a step: a
    // host can set a measurement and read the command it gives.
    sim.set_input("v", &[1.5, -2.5]).unwrap();
    sim.set_input("u", &[4.0]).unwrap();
    assert_eq!(sim.output("w").unwrap(), [1.5, -2.5]);
    assert_eq!(sim.signal("k").unwrap(), [12.0]);
    assert_eq!(sim.time(), 0.4);
    assert_eq!(sim.signal("v[2]").unwrap(), [-2.5]);
}

#[test]
fn a_plain_run_sees_the_inputs_value() {
    let trace = ctlgraph::simulate(ctlgraph::compile_str(HOSTED, "hosted.yaml", &[]).unwrap(), None).unwrap();
    let y = trace.column("x").unwrap();
    assert!((y[y.len() - 1] - 6.0).abs() < 1e-9, "{}", y[y.len() - 1]);
}

#[test]
fn mistakes_name_what_exists() {
    let mut sim = hosted();
    let e = sim.set_input("uu", &[1.0]).unwrap_err();
    assert_eq!(e.message, "no input `uu`");
    assert_eq!(e.hint.as_deref(), Some("did you mean `u`?"));
    let e = sim.set_input("v", &[1.0]).unwrap_err();
    assert_eq!(e.message, "input `v` has 2 element(s), given 1");
    let e = sim.set_input("u", &[f64::NAN]).unwrap_err();
    assert_eq!(e.message, "input `u`: NaN is not a finite number");
    assert_eq!(sim.output("z").unwrap_err().message, "no output `z`");
    sim.advance_to(0.5).unwrap();
    assert_eq!(sim.advance_to(0.25).unwrap_err().to_string(), "cannot advance to t = 0.25 from t = 0.5");
    // Beyond the graph's stop time the run goes on.
    sim.advance_to(1.5).unwrap();
    assert_eq!(sim.time(), 1.5);
    let no_inputs = simulator("graphs/tutorial/first_order.yaml").set_input("u", &[1.0]).unwrap_err();
    assert_eq!(no_inputs.hint.as_deref(), Some("the graph has no inputs: add a top-level `inport` block"));
}

#[test]
fn only_a_top_level_inport_takes_a_width() {
    let sub = "blocks:\n  a: { type: inport, width: 2 }\n  b: { type: outport }\nwires: [a -> b]\n";
    let dir = std::env::temp_dir().join(format!("ctlgraph-stepping-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("sub.yaml"), sub).unwrap();
    let top =
        "blocks:\n  c: { type: constant, value: 1 }\n  s: { type: subsystem, file: sub.yaml }\nwires: [c -> s.a]\n";
    let Err(e) = ctlgraph::compile_str(top, dir.join("top.yaml").to_str().unwrap(), &[]) else { panic!("compiled") };
    assert!(e.message.contains("`width`: only a top-level inport"), "{}", e.message);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_restored_snapshot_runs_on_as_the_original() {
    // Noise streams, transport-delay histories, tooth events and zero
    // crossings, fuzzy and observer memory: all in the snapshot.
    for (file, at, to) in [("graphs/fladrc/fladrc.yaml", 1.1, 1.7), ("graphs/milling/hinf.yaml", 0.1, 0.2)] {
        let mut sim = simulator(file);
        sim.advance_to(at).unwrap();
        let snapshot = sim.state();
        assert_eq!(snapshot.time(), sim.time());
        sim.advance_to(to).unwrap();
        let first: Vec<f64> = sim.signals().to_vec();
        let steps = sim.stats().major_steps;
        sim.restore(&snapshot).unwrap();
        assert_eq!(sim.time(), snapshot.time());
        sim.advance_to(to).unwrap();
        assert!(sim.signals().iter().zip(&first).all(|(a, b)| a.to_bits() == b.to_bits()), "{file}");
        assert_eq!(sim.stats().major_steps, steps, "{file}");
        // A snapshot fits only the simulator it was taken of.
        let e = simulator(file).restore(&snapshot).unwrap_err();
        assert_eq!(e.message, "the snapshot was taken of another simulator");
    }
}

#[test]
fn a_snapshot_keeps_the_inputs() {
    let mut sim = hosted();
    sim.set_input("u", &[1.0]).unwrap();
    sim.advance_to(0.2).unwrap();
    let snapshot = sim.state();
    sim.set_input("u", &[-5.0]).unwrap();
    sim.advance_to(0.4).unwrap();
    sim.restore(&snapshot).unwrap();
    sim.advance_to(0.4).unwrap();
    assert!((sim.output("y").unwrap()[0] - 3.0 * 0.4).abs() < 1e-12, "{:?}", sim.output("y"));
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 16, ..Default::default() })]

    /// Any cut of a fixed-step run into chunks on its grid — and a detour
    /// through a snapshot taken at any of the cuts — gives the numbers of
    /// one run, bit for bit (the LADRC graph: discrete observer and
    /// controller, the plant stepped by its exact transition; 0.4 s at
    /// h = 1e-4).
    #[test]
    fn any_chunking_and_any_snapshot_give_one_run(
        cuts in proptest::collection::vec(1usize..4000, 1..12),
        rewind in 0usize..12,
    ) {
        let file = "graphs/fladrc/ladrc.yaml";
        let stop = 0.4;
        let mut whole = simulator(file);
        whole.advance_to(stop).unwrap();
        let mut cuts: Vec<f64> = cuts.iter().map(|&k| k as f64 * 1e-4).collect();
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        let mut stepped = simulator(file);
        let mut snapshot = None;
        for (k, &t) in cuts.iter().enumerate() {
            stepped.advance_to(t).unwrap();
            if k == rewind % cuts.len() {
                snapshot = Some(stepped.state());
                // Wander off, then come back.
                stepped.advance_to(t + 0.05).unwrap();
                stepped.restore(snapshot.as_ref().unwrap()).unwrap();
            }
        }
        stepped.advance_to(stop).unwrap();
        proptest::prop_assert!(snapshot.is_some());
        let same = stepped.signals().iter().zip(whole.signals()).all(|(a, b)| a.to_bits() == b.to_bits());
        proptest::prop_assert!(same, "cuts {:?}", cuts);
    }
}

#[test]
fn a_subsystems_ports_are_signals_by_name() {
    // `soft.y` is the signal wired to the inport y, `soft.u` the outport.
    let mut sim = simulator("graphs/tutorial/subsystem.yaml");
    sim.advance_to(1.0).unwrap();
    let plant = sim.signal("plant_soft").unwrap().to_vec();
    assert_eq!(sim.signal("soft.y").unwrap(), plant.as_slice());
    assert_eq!(sim.signal("soft.r").unwrap(), [1.0]);
    let recorded = sim.signal("u_soft").unwrap().to_vec();
    assert_eq!(sim.signal("soft.u").unwrap(), recorded.as_slice());
    // The same names select signals for linearisation: from the
    // controller's measurement input to its output.
    let model = ctlgraph::compile_file(Path::new("graphs/tutorial/subsystem.yaml"), &[]).unwrap();
    let sel = ctlgraph::core::linearize::Selection {
        input: Some("soft.y".into()),
        output: Some("soft.u".into()),
        ..Default::default()
    };
    let lin = ctlgraph::core::linearize::linearize(model, &sel).unwrap();
    assert_eq!(lin.input, "soft.y");
}

/// A compiled graph's block comes back as its concrete type, built with
/// the graph's parameters (what a fused step starts from); a wrong type or
/// name gives none.
#[test]
fn a_compiled_block_comes_back_as_its_type() {
    use ctlgraph_blocks::adrc::{Leso, TrackingDifferentiator};
    use ctlgraph_blocks::continuous::Lti;
    use ctlgraph_core::Block;
    let model = ctlgraph::compile_file(Path::new("graphs/fladrc/ladrc.yaml"), &[]).unwrap();
    let plant: Lti = model.block_as("plant").expect("the plant is an Lti");
    // 1.639e4 / (s² + 154.8 s + 2.242e4) in controllable canonical form.
    let ss = plant.lti().unwrap();
    assert_eq!((ss.a.as_slice(), ss.c.as_slice()), (&[-154.8, -2.242e4, 1.0, 0.0][..], &[0.0, 1.639e4][..]));
    let leso: Leso = model.block_as("ctrl/leso").expect("a subsystem's block by its flattened name");
    assert_eq!(leso.state(), &[0.0, 0.0, 0.0]);
    assert!(model.block_as::<Leso>("ctrl/td").is_none(), "ctrl/td is not a LESO");
    assert!(model.block_as::<TrackingDifferentiator>("ctrl/td").is_some());
    assert!(model.block_as::<Lti>("no_such_block").is_none());
}
