//! Runs one graph for a given number of major steps in the interpreter,
//! alone, so callgrind can count the instructions a step takes — the
//! figures docs/performance-history.md records:
//!
//! ```text
//! cargo build --release --example instructions
//! valgrind --tool=callgrind --toggle-collect='instructions::measured' \
//!     target/release/examples/instructions pid 1000     # then 11000
//! ```
//!
//! A step's count is the difference of the two totals over 10 000 steps
//! (set-up and first steps drop out). Graphs: `pid` (benches/pid_loop_rk4.yaml),
//! `ladrc` (graphs/fladrc/ladrc.yaml), `chain10` (the scaling bench's
//! sine → 10 gains → integrator at RK4 h = 0.01).

#[path = "../benches/graphs/mod.rs"]
mod graphs;
use graphs::chain;

/// The run callgrind counts: `steps` major steps after t = 0.
#[inline(never)]
fn measured(sim: &mut ctlgraph_core::Simulator) -> f64 {
    let mut sum = 0.0;
    sim.run(&mut |_, s| sum += s[0]).expect("runs");
    sum
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (graph, steps) = match args.as_slice() {
        [_, graph, steps] => (graph.as_str(), steps.parse::<f64>().expect("a number of steps")),
        _ => {
            eprintln!("usage: instructions pid|ladrc|chain10 STEPS");
            std::process::exit(2);
        }
    };
    let (model, h) = match graph {
        "pid" => (ctlgraph::compile_file("benches/pid_loop_rk4.yaml".as_ref(), &[]), 1e-4),
        "ladrc" => (ctlgraph::compile_file("graphs/fladrc/ladrc.yaml".as_ref(), &[]), 1e-4),
        "chain10" => (ctlgraph::compile_str(&chain(10), "chain10.yaml", &[]), 0.01),
        other => {
            eprintln!("no graph `{other}`: pid, ladrc or chain10");
            std::process::exit(2);
        }
    };
    let mut sim = ctlgraph_core::Simulator::new(model.expect("compiles"), Some(steps * h));
    println!("{}", measured(&mut sim));
}
