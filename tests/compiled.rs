//! Generated steps (`ctlgraph codegen`) compute what the interpreter
//! computes, to the bit: every bundled graph the generator accepts, built
//! as Rust by the `ctlgraph-compiled-graphs` crate, runs beside the
//! simulator and must give the same time and signals at every major step.

mod common;
use common::{ctlgraph, path, text};
use ctlgraph::compile_file;
use ctlgraph_compiled_graphs::{GENERATED, REFUSED};
use ctlgraph_core::Simulator;
use std::path::Path;

/// Major steps compared per graph (the whole run when it is shorter).
const STEPS: usize = 3_000;

fn interpreted(path: &str) -> Vec<(f64, Vec<f64>)> {
    let mut sim = Simulator::new(compile_file(Path::new(path), &[]).unwrap(), None);
    let mut steps = Vec::new();
    sim.run_while(&mut |t, signals| {
        steps.push((t, signals.to_vec()));
        steps.len() <= STEPS
    })
    .unwrap();
    steps
}

#[test]
fn every_generated_step_equals_the_interpreter_to_the_bit() {
    for (path, trace) in GENERATED {
        let expected = interpreted(path);
        let got = trace(&compile_file(Path::new(path), &[]).unwrap(), STEPS).unwrap();
        assert_eq!(got.len(), expected.len(), "{path}: major steps");
        for ((t, s), (t_ref, s_ref)) in got.iter().zip(&expected) {
            assert_eq!(t.to_bits(), t_ref.to_bits(), "{path}: time {t} against {t_ref}");
            for (k, (v, r)) in s.iter().zip(s_ref).enumerate() {
                assert_eq!(v.to_bits(), r.to_bits(), "{path}: signal {k} at t = {t}: {v} against {r}");
            }
        }
    }
}

#[test]
fn the_papers_fixed_step_loops_are_generated_and_the_rest_refused_with_a_reason() {
    let generated: Vec<&str> = GENERATED.iter().map(|(p, _)| *p).collect();
    for path in ["graphs/fladrc/ladrc.yaml", "graphs/fladrc/fladrc.yaml", "benches/pid_loop_rk4.yaml"] {
        assert!(generated.contains(&path), "{path} has no generated step; refused: {REFUSED:?}");
    }
    let (_, why) = REFUSED.iter().find(|(p, _)| *p == "graphs/tutorial/pid_loop.yaml").expect("dopri5 is refused");
    assert!(why.contains("adaptive"), "{why}");
    let (_, why) = REFUSED.iter().find(|(p, _)| *p == "graphs/events/bouncing_ball.yaml").expect("events are refused");
    assert!(why.contains("zero crossings"), "{why}");
}

#[test]
fn a_step_refuses_a_graph_of_another_structure() {
    let (_, trace) = GENERATED.iter().find(|(p, _)| *p == "graphs/fladrc/ladrc.yaml").unwrap();
    let other = compile_file(Path::new("graphs/fladrc/fladrc.yaml"), &[]).unwrap();
    let error = trace(&other, 1).unwrap_err();
    assert!(error.contains("not the graph this step was generated for"), "{error}");
}

#[test]
fn codegen_writes_the_module_or_says_why_it_cannot() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("ladrc.rs");
    let out = ctlgraph(&["codegen", "graphs/fladrc/ladrc.yaml", "--out", path(&file)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let model = compile_file(Path::new("graphs/fladrc/ladrc.yaml"), &[]).unwrap();
    let code = std::fs::read_to_string(&file).unwrap();
    assert_eq!(code, ctlgraph_core::codegen::generate(&model).unwrap());
    assert!(code.contains("pub struct Step") && code.contains("::ctlgraph_blocks::adrc::Leso"), "{code}");
    // An adaptive solver: exit 1, the reason, and no file.
    let refused = dir.path().join("pid.rs");
    let out = ctlgraph(&["codegen", "graphs/tutorial/pid_loop.yaml", "--out", path(&refused)]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("cannot generate a step") && stderr.contains("fixed-step method"), "{stderr}");
    assert!(!refused.exists());
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
