//! A graph's blocks called in the graph's order by plain Rust compute what
//! the interpreter computes, to the bit: the semantics a compiled step has
//! to keep (docs/compiled-step.md). The fused loop is the one
//! `cargo bench --bench overhead` times.

#[allow(dead_code)]
#[path = "../benches/fused_pid/mod.rs"]
mod fused_pid;

use ctlgraph_core::Simulator;

#[test]
fn the_pid_loops_blocks_fused_compute_what_the_interpreter_does() {
    let model = ctlgraph::compile_str(fused_pid::GRAPH, "pid.yaml", &[]).unwrap();
    let ctrl = model.columns.iter().find(|c| c.name == "ctrl").unwrap().offset;
    let mut fused = fused_pid::Fused::new(&model);
    let by_interpreter = fused_pid::interpreted_sum_u(&mut Simulator::new(model, None), ctrl);
    assert_eq!(fused.run().to_bits(), by_interpreter.to_bits());
}

#[allow(dead_code)]
#[path = "../benches/fused_ladrc/mod.rs"]
mod fused_ladrc;

#[test]
fn the_ladrc_graphs_blocks_fused_compute_what_the_interpreter_does() {
    // Noise off: the fused loop draws its own (the hand-written loop's).
    let sets = [("noise_power".to_string(), "0".to_string())];
    let model = ctlgraph::compile_file(std::path::Path::new("graphs/fladrc/ladrc.yaml"), &sets).unwrap();
    let y = model.columns.iter().find(|c| c.name == "y").unwrap().offset;
    let mut fused = fused_ladrc::Fused::new(&model);
    let mut sum_y = 0.0;
    Simulator::new(model, None).run(&mut |_, s| sum_y += s[y]).unwrap();
    assert_eq!(fused.run(0.0).0.to_bits(), sum_y.to_bits());
}
