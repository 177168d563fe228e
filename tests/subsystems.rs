//! Subsystems flatten to exactly the graph one would write by hand, with
//! per-instance parameters and `outer/inner` names.

mod common;

#[test]
fn subsystem_runs_bit_for_bit_like_its_flat_equivalent() {
    let nested = ctlgraph::compile_file("graphs/tutorial/subsystem.yaml".as_ref(), &[]).unwrap();
    let names: Vec<&str> = nested.meta.iter().map(|m| m.name.as_str()).collect();
    assert!(names.contains(&"soft/i_part") && names.contains(&"stiff/p_gain"), "{names:?}");
    let nested = ctlgraph::simulate(nested, None).unwrap();

    // The `soft` instance written out flat: kp = 1, ki = 2, b = 0.5.
    let flat = "parameters: { tau: 0.5 }\n\
                simulation: { stop: 4.0, solver: { method: rk4, step: 1.0e-3 } }\n\
                blocks:\n  r: { type: step, at: 0.5 }\n  e: { type: sum, signs: \"+-\" }\n\
                \x20 ep: { type: fcn, inputs: 2, expr: \"0.5*u1 - u2\" }\n  p_gain: { type: gain, k: 1 }\n\
                \x20 i_part: { type: integrator }\n  i_gain: { type: gain, k: 2 }\n  total: { type: sum }\n\
                \x20 plant: { type: transfer_function, num: [1], den: [tau, 1] }\n\
                wires: [r -> e.u1, r -> ep.u1, plant -> e.u2, plant -> ep.u2, ep -> p_gain, e -> i_gain,\n\
                \x20       i_gain -> i_part, p_gain -> total.u1, i_part -> total.u2, total -> plant]\n\
                record: [y: plant, u: total]\n";
    let flat = common::run(flat);
    assert_eq!(nested.column("y_soft").unwrap(), flat.column("y").unwrap());
    assert_eq!(nested.column("u_soft").unwrap(), flat.column("u").unwrap());
    // The stiffer instance is faster: closer to 1 at t = 1.5.
    let (soft, stiff) = (nested.at("y_soft", 1.5).unwrap(), nested.at("y_stiff", 1.5).unwrap());
    assert!(stiff > soft && stiff < 1.1, "soft {soft}, stiff {stiff}");
}

#[test]
fn records_default_to_every_top_level_output() {
    let trace = common::run(
        "simulation: { stop: 0.1, solver: { method: rk4, step: 0.05 } }\n\
         blocks:\n  u: { type: step }\n  d: { type: demux }\n  c: { type: constant, value: [1, 2] }\n\
         wires: [c -> d]\n",
    );
    assert_eq!(trace.headers, ["t", "u", "d.y1", "d.y2", "c[1]", "c[2]"]);
}

#[test]
fn set_reaches_derived_parameters() {
    // --set replaces a definition before later parameters are evaluated.
    let yaml = "parameters:\n  tau: 1\n  pole: \"-1/tau\"\n\
                simulation: { stop: 1.0, solver: { method: rk4, step: 1.0e-3 } }\n\
                blocks:\n  u: { type: step }\n  g: { type: zpk, poles: [pole], gain: \"-pole\" }\n\
                wires: [u -> g]\nrecord: [g]\n";
    let sets = [("tau".to_string(), "0.25".to_string())];
    let model = ctlgraph::compile_str(yaml, "test.yaml", &sets).unwrap();
    let trace = ctlgraph::simulate(model, None).unwrap();
    let err = common::max_error(&trace, "g", |t| 1.0 - (-4.0 * t).exp());
    assert!(err < 1e-10, "tau = 0.25 took effect: {err}");
}
