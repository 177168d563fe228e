//! Graphs generated for the benches (and `examples/instructions.rs`,
//! which counts a chain's instructions per step).

use std::fmt::Write;

/// The settings and the source every generated graph starts with.
pub const HEADER: &str =
    "simulation: { stop: 1.0, solver: { method: rk4, step: 0.01 } }\nblocks:\n  u: { type: sine }\n";

/// `u → g1 → g2 → … → gn → integrator` (`u → integrator` for n = 0).
pub fn chain(n: usize) -> String {
    let mut g = String::from(HEADER);
    g.push_str("  x: { type: integrator }\n");
    for i in 1..=n {
        writeln!(g, "  g{i}: {{ type: gain, k: 1.0 }}").unwrap();
    }
    g.push_str("wires:\n");
    let names: Vec<String> = std::iter::once("u".into()).chain((1..=n).map(|i| format!("g{i}"))).collect();
    for pair in names.windows(2) {
        writeln!(g, "  - {} -> {}", pair[0], pair[1]).unwrap();
    }
    writeln!(g, "  - {} -> x", names[n]).unwrap();
    g
}
