//! Drives a bundled graph through the library API: compile with a parameter
//! override, simulate, and read signals back from the in-memory trace.
//!
//!     cargo run --example run_graph

use std::path::Path;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let sets = [("kp".to_string(), "3.0".to_string())];
    let model = ctlgraph::compile_file(Path::new("graphs/tutorial/pid_loop.yaml"), &sets)?;
    println!("{} blocks, {} states", model.meta.len(), model.n_states);
    let trace = ctlgraph::simulate(model, None)?;
    let y = trace.column("y").ok_or("no column y")?;
    let peak = y.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    println!(
        "kp = 3: peak y = {peak:.4}, y(1 s) = {:.4}, y(end) = {:.6}",
        trace.at("y", 1.0).unwrap_or(f64::NAN),
        y[y.len() - 1]
    );
    Ok(())
}
