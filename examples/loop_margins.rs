//! Linear analysis through the library API: the tutorial PID loop opened at
//! the controller output, its margins for three proportional gains, and
//! the closed loop's poles.
//!
//!     cargo run --example loop_margins

use ctlgraph::core::linearize::{Selection, linearize};
use ctlgraph::solver::freq;
use std::path::Path;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let graph = Path::new("graphs/tutorial/pid_loop.yaml");
    let at_controller = Selection { open: Some("ctrl".into()), ..Selection::default() };
    for kp in [1.0, 2.0, 4.0] {
        let model = ctlgraph::compile_file(graph, &[("kp".into(), kp.to_string())])?;
        let loop_transfer = linearize(model, &at_controller)?;
        let m = ctlgraph::analysis::figures(&loop_transfer).margins;
        println!(
            "kp = {kp}: phase margin {:.2} deg at {:.2} rad/s, peak sensitivity {:.3}",
            m.phase_margin, m.gain_crossover_freq, m.peak_sensitivity
        );
    }
    let closed = linearize(ctlgraph::compile_file(graph, &[])?, &Selection::default())?;
    for p in freq::poles(&closed.system).ok_or("no eigenvalues")? {
        let (wn, zeta) = freq::natural_frequency_and_damping(p, None);
        println!("pole {:.3}{:+.3}j: wn {wn:.3} rad/s, damping {zeta:.3}", p.re, p.im);
    }
    Ok(())
}
