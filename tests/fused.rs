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
