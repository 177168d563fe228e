//! Reproduces the FLADRC paper's comparison (Shi, Zhou, Li 2025): runs the
//! four controller graphs of graphs/fladrc/ and prints the metrics table of
//! docs/fladrc.md.
//!
//!     cargo run --release --example fladrc_table

use ctlgraph::core::checks::metrics::{Metric, evaluate};
use std::path::Path;

const GRAPHS: [(&str, &str); 4] = [("FLADRC", "fladrc"), ("LADRC", "ladrc"), ("FPID", "fpid"), ("PID", "pid")];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!(
        "| controller | settling time, 2 % [s] | overshoot [%] | peak \\|e\\| in [0.6, 1.2) [mm] | recovery after 0.6 s, 2 % [s] | peak \\|e\\| in [1.2, 2] [mm] | IAE [mm·s] |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (label, file) in GRAPHS {
        let model = ctlgraph::compile_file(Path::new(&format!("graphs/fladrc/{file}.yaml")), &[])?;
        let trace = ctlgraph::simulate(model, None)?;
        let (t, y, e) = (trace.t(), trace.column("y").ok_or("no y")?, trace.column("e").ok_or("no e")?);
        let settle = evaluate(Metric::SettlingTime, t, y, &[1.0, 0.02, 0.0, 0.6]);
        let overshoot = evaluate(Metric::Overshoot, t, y, &[1.0, 0.0, 0.6]);
        let peak_step = evaluate(Metric::MaxAbs, t, e, &[0.6, 1.2]);
        // Recovery: time after 0.6 s until |e| stays within 0.02 mm (2 % of the depth).
        let recovery = evaluate(Metric::SettlingTime, t, e, &[0.0, 0.02, 0.6, 1.2]);
        let peak_noise = evaluate(Metric::MaxAbs, t, e, &[1.2, 2.0]);
        let iae = evaluate(Metric::Iae, t, e, &[]);
        println!(
            "| {label} | {settle:.4} | {overshoot:.2} | {peak_step:.4} | {recovery:.4} | {peak_noise:.4} | {iae:.4} |"
        );
    }
    Ok(())
}
