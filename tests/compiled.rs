//! Generated steps (`ctlgraph codegen`) compute what the interpreter
//! computes, to the bit: every bundled graph the generator accepts, built
//! as Rust by the `ctlgraph-compiled-graphs` crate, runs beside the
//! simulator and must give the same time and signals at every major step.

mod common;
use common::{ctlgraph, path, text};
use ctlgraph::compile_file;
use ctlgraph_compiled_graphs::{GENERATED, compiled_graphs_clocks};
use ctlgraph_core::codegen::Compiled;
use ctlgraph_core::{Model, Simulator};
use std::path::Path;

/// Major steps compared per graph (the whole run when it is shorter): the
/// whole LADRC and FLADRC scenarios (20 001, through their events, where
/// the generated step's grid-point path meets a block event).
const STEPS: usize = 25_000;

fn interpreted(path: &str) -> Vec<(f64, Vec<f64>)> {
    interpreted_with(compile_file(Path::new(path), &[]).unwrap())
}

fn interpreted_with(model: Model) -> Vec<(f64, Vec<f64>)> {
    let mut sim = Simulator::new(model, None);
    let mut steps = Vec::new();
    sim.run_while(&mut |t, signals| {
        steps.push((t, signals.to_vec()));
        steps.len() <= STEPS
    })
    .unwrap();
    steps
}

/// The same major steps: times and signals, to the bit.
fn assert_same(what: &str, got: &[(f64, Vec<f64>)], expected: &[(f64, Vec<f64>)]) {
    assert_eq!(got.len(), expected.len(), "{what}: major steps");
    for ((t, s), (t_ref, s_ref)) in got.iter().zip(expected) {
        assert_eq!(t.to_bits(), t_ref.to_bits(), "{what}: time {t} against {t_ref}");
        for (k, (v, r)) in s.iter().zip(s_ref).enumerate() {
            assert_eq!(v.to_bits(), r.to_bits(), "{what}: signal {k} at t = {t}: {v} against {r}");
        }
    }
}

#[test]
fn every_generated_step_equals_the_interpreter_to_the_bit() {
    for (path, trace) in GENERATED {
        let got = trace(&compile_file(Path::new(path), &[]).unwrap(), STEPS).unwrap();
        assert_same(path, &got, &interpreted(path));
    }
}

/// Clocks counted in grid steps where every rate is on the grid, by
/// their own times where one is not, and the same steps either way: an
/// event between grid points, a stop time off the grid, rates of 1, 2,
/// 2.5, 3 and 4 steps, an offset.
#[test]
fn generated_time_keeping_equals_the_interpreters_on_and_off_the_grid() {
    const PATH: &str = "compiled/graphs/clocks.yaml";
    let variants: [(&[(&str, &str)], bool); 5] = [
        (&[], true),
        (&[("T_ref", "0.0025")], false),
        (&[("T_ref", "0.003")], false),
        (&[("offset", "0.001")], false),
        (&[("T_ctrl", "0.001"), ("t_kick", "0.2")], true),
    ];
    for (sets, on_grid) in variants {
        let sets: Vec<(String, String)> = sets.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        let model = compile_file(Path::new(PATH), &sets).unwrap();
        let run = Compiled::<compiled_graphs_clocks::Step>::new(&model, None).unwrap();
        assert_eq!(run.clocks_on_grid(), on_grid, "{sets:?}");
        let (_, trace) = GENERATED.iter().find(|(p, _)| *p == PATH).unwrap();
        let got = trace(&model, usize::MAX).unwrap();
        assert!(got.len() > 250, "{sets:?}: the whole run");
        let expected = interpreted_with(compile_file(Path::new(PATH), &sets).unwrap());
        assert_same(&format!("{PATH} {sets:?}"), &got, &expected);
    }
}

/// Formulas written in place (`fcn`: every operation and function of the
/// expression language, the time, dopri5's minor steps) compute what the
/// interpreter's program does, with the graph's values and with others on
/// the same step: it reads the values from the blocks, so their sweep is
/// one build. A formula of another shape is another structure.
#[test]
fn formulas_written_in_place_equal_the_interpreters_for_any_values() {
    const PATH: &str = "compiled/graphs/formulas.yaml";
    let (_, trace) = GENERATED.iter().find(|(p, _)| *p == PATH).unwrap();
    let compile = |sets: &[(&str, &str)]| {
        let sets: Vec<(String, String)> = sets.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        compile_file(Path::new(PATH), &sets).unwrap()
    };
    let others = [("a", "-3"), ("b", "0.125"), ("w", "40")];
    for sets in [&[][..], &others] {
        let got = trace(&compile(sets), usize::MAX).unwrap();
        assert!(got.len() > 100, "{sets:?}: the whole run");
        assert_same(&format!("{PATH} {sets:?}"), &got, &interpreted_with(compile(sets)));
    }
    let fingerprint = ctlgraph_core::codegen::fingerprint;
    assert_eq!(fingerprint(&compile(&[])), fingerprint(&compile(&others)));
    let reshaped = std::fs::read_to_string(PATH).unwrap().replace("a*u1 - ", "a + u1 - ");
    let flat = ctlgraph_core::load_str(&reshaped, PATH.into(), &[]).unwrap();
    let reshaped = ctlgraph::compile_flat(&flat, &ctlgraph::registry()).unwrap();
    assert_ne!(fingerprint(&compile(&[])), fingerprint(&reshaped));
}

#[test]
fn a_generated_step_whose_signal_overflows_stops_as_the_interpreter_does_and_stays_stopped() {
    const PATH: &str = "compiled/graphs/clocks.yaml";
    let sets = [("kick", "1e300"), ("kick_gain", "1e300")].map(|(k, v)| (k.to_string(), v.to_string()));
    let model = || compile_file(Path::new(PATH), &sets).unwrap();
    let expected = Simulator::new(model(), None).run(&mut |_, _| {}).unwrap_err().to_string();
    assert!(expected.contains("block `scale`") && expected.contains("inf"), "{expected}");
    let mut run = Compiled::<compiled_graphs_clocks::Step>::new(&model(), None).unwrap();
    let error = loop {
        if let Err(e) = run.outputs() {
            break e.to_string();
        }
        run.advance().unwrap();
    };
    assert_eq!(error, expected);
    // The infinite signal is not written again, yet it is still there:
    // the next step says so too (at its own time).
    run.advance().unwrap();
    let again = run.outputs().unwrap_err().to_string();
    assert_eq!(again.split_once(": ").map(|(_, what)| what), expected.split_once(": ").map(|(_, what)| what));
}

#[test]
fn every_bundled_graph_is_generated() {
    let generated: Vec<&str> = GENERATED.iter().map(|(p, _)| *p).collect();
    // The papers' loops, with the contact and cutting forces' crossings;
    // adaptive runs: dopri5 (with a transport delay's breakpoints in
    // dead_time_pi) and the stiff TR-BDF2; located events (an impact, a
    // relay), which the one driver and the one watch handle for a
    // generated step as for the interpreter.
    for path in [
        "graphs/fladrc/ladrc.yaml",
        "graphs/fladrc/fladrc.yaml",
        "graphs/milling/hinf.yaml",
        "graphs/contact-force/impedance_pid.yaml",
        "benches/pid_loop_rk4.yaml",
        "graphs/tutorial/pid_loop.yaml",
        "graphs/events/dead_time_pi.yaml",
        "graphs/events/bouncing_ball.yaml",
        "graphs/events/thermostat.yaml",
        "graphs/stiff/van_der_pol.yaml",
        "graphs/stiff/robertson.yaml",
        "graphs/tutorial/controller_io.yaml",
        "graphs/events/antiwindup_dead_time.yaml",
        "compiled/graphs/rows.yaml",
        "compiled/graphs/formulas.yaml",
    ] {
        assert!(generated.contains(&path), "{path} has no generated step");
    }
}

/// Rows between steps, from the dense output: RK4's Hermite interpolant
/// with a held LTI block stepped over part of a step (`refine`), and a
/// grid of rows that falls between and on steps (`every`); dopri5's
/// continuous extension in `antiwindup_dead_time` is compared with every
/// bundled graph.
#[test]
fn generated_rows_between_steps_equal_the_interpreters() {
    use ctlgraph_compiled_graphs::compiled_graphs_rows::Step;
    const PATH: &str = "compiled/graphs/rows.yaml";
    let text = std::fs::read_to_string(PATH).unwrap();
    for output in ["refine: 4", "every: 0.0033", "every: 0.01"] {
        let text = text.replace("refine: 4", output);
        let model = || ctlgraph::compile_str(&text, PATH, &[]).unwrap();
        let mut got = Vec::new();
        Compiled::<Step>::new(&model(), None).unwrap().run(|t, s| got.push((t, s.to_vec()))).unwrap();
        let expected = interpreted_with(model());
        assert!(expected.len() > 50, "{output}: {} rows", expected.len());
        assert_same(&format!("{PATH} {output}"), &got, &expected);
    }
}

/// Past the bouncing ball's Zeno point: the chattering error, or with
/// `zero_crossing: adaptive` the warning and the run on, with the same
/// steps, events and words from both back-ends.
#[test]
fn a_generated_step_chatters_and_ignores_chattering_as_the_interpreter_does() {
    use ctlgraph_compiled_graphs::graphs_events_bouncing_ball::Step;
    const PATH: &str = "graphs/events/bouncing_ball.yaml";
    let text = std::fs::read_to_string(PATH).unwrap();
    for adaptive in [false, true] {
        let text = if adaptive {
            text.replace("max_step: 0.05 }", "max_step: 0.05, zero_crossing: adaptive }")
        } else {
            text.clone()
        };
        let model = || ctlgraph::compile_str(&text, PATH, &[]).unwrap();
        let (mut sim, mut run) =
            (Simulator::new(model(), Some(14.0)), Compiled::<Step>::new(&model(), Some(14.0)).unwrap());
        let (mut expected, mut got) = (Vec::new(), Vec::new());
        let interpreted = sim.run(&mut |t, s| expected.push((t, s.to_vec()))).map_err(|e| e.to_string());
        let generated = run.run(|t, s| got.push((t, s.to_vec()))).map_err(|e| e.to_string());
        assert_same(&format!("{PATH} adaptive: {adaptive}"), &got, &expected);
        assert_eq!(generated, interpreted);
        assert_eq!(run.warnings(), sim.warnings());
        assert_eq!(run.stats().events, sim.stats().events);
        assert!(sim.stats().events > 40, "{:?}", sim.stats());
        match adaptive {
            false => assert!(interpreted.unwrap_err().contains("block `impact` chatters")),
            true => assert!(interpreted.is_ok() && sim.warnings()[0].contains("block `impact` chattered")),
        }
    }
}

#[test]
fn a_step_refuses_a_graph_of_another_structure() {
    let (_, trace) = GENERATED.iter().find(|(p, _)| *p == "graphs/fladrc/ladrc.yaml").unwrap();
    let other = compile_file(Path::new("graphs/fladrc/fladrc.yaml"), &[]).unwrap();
    let error = trace(&other, 1).unwrap_err();
    assert!(error.contains("not the graph this step was generated for"), "{error}");
}

#[test]
fn codegen_writes_the_module_and_never_over_the_graph() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("ladrc.rs");
    let out = ctlgraph(&["codegen", "graphs/fladrc/ladrc.yaml", "--out", path(&file)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let model = compile_file(Path::new("graphs/fladrc/ladrc.yaml"), &[]).unwrap();
    let code = std::fs::read_to_string(&file).unwrap();
    assert_eq!(code, ctlgraph_core::codegen::generate(&model));
    assert!(code.contains("pub struct Step") && code.contains("::ctlgraph_blocks::adrc::Leso"), "{code}");
    // The graph file itself is never the output.
    let out = ctlgraph(&["codegen", "graphs/fladrc/ladrc.yaml", "--out", "graphs/fladrc/ladrc.yaml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("that is the graph file"), "{}", text(&out.stderr));
}

#[test]
fn a_generated_step_that_blows_up_says_what_the_interpreter_says() {
    // An unstable plant (tau < 0): the PI's integrator overflows at t = 1.909.
    let path = "graphs/tutorial/subsystem.yaml";
    let sets = [("tau".to_string(), "-0.01".to_string())];
    let mut sim = Simulator::new(compile_file(Path::new(path), &sets).unwrap(), None);
    let expected = sim.run(&mut |_, _| {}).unwrap_err().to_string();
    assert!(expected.contains("block `stiff/i_part`: state 0 is inf"), "{expected}");
    let (_, trace) = GENERATED.iter().find(|(p, _)| *p == path).unwrap();
    let got = trace(&compile_file(Path::new(path), &sets).unwrap(), 10_000).unwrap_err();
    assert_eq!(got, expected);
}
