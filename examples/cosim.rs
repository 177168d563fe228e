//! A graph as the controller of a plant written in plain Rust, in
//! lock-step at 1 kHz: every millisecond the program measures the plant,
//! sets the graph's input `y`, reads the command `u` at the same instant,
//! applies it for a millisecond, and advances the graph.
//!
//!     cargo run --release --example cosim
//!
//! The graph (graphs/tutorial/controller_io.yaml) is a sampled PID with a
//! top-level `inport` y and `outport` u; the plant is the tutorial's
//! y'' + 2ζωn·y' + ωn²·y = ωn²·u, integrated here by RK4 with ten substeps
//! per tick. A snapshot taken at 1 s is restored to replay the last two
//! seconds with a load on the plant.

use ctlgraph::core::Simulator;
use std::path::Path;

/// The plant's state (y, y') and its constants.
#[derive(Clone, Copy)]
struct Plant {
    y: f64,
    v: f64,
    wn: f64,
    zeta: f64,
}

impl Plant {
    /// (y', y'') under the command `u` and an input disturbance `load`.
    fn derivatives(&self, (y, v): (f64, f64), u: f64, load: f64) -> (f64, f64) {
        (v, self.wn * self.wn * (u + load - y) - 2.0 * self.zeta * self.wn * v)
    }

    /// Advances `dt` with `u` held, by RK4 in `n` substeps.
    fn step(&mut self, u: f64, load: f64, dt: f64, n: usize) {
        let h = dt / n as f64;
        for _ in 0..n {
            let s = (self.y, self.v);
            let k1 = self.derivatives(s, u, load);
            let k2 = self.derivatives((s.0 + 0.5 * h * k1.0, s.1 + 0.5 * h * k1.1), u, load);
            let k3 = self.derivatives((s.0 + 0.5 * h * k2.0, s.1 + 0.5 * h * k2.1), u, load);
            let k4 = self.derivatives((s.0 + h * k3.0, s.1 + h * k3.1), u, load);
            self.y += h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
            self.v += h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
        }
    }
}

const TICK: f64 = 1e-3;

/// Runs ticks `from..to` of the loop; returns the largest |y − 1| after 1 s.
fn run(
    sim: &mut Simulator,
    plant: &mut Plant,
    from: usize,
    to: usize,
    load: f64,
) -> Result<f64, Box<dyn std::error::Error>> {
    let mut worst: f64 = 0.0;
    for k in from..to {
        sim.set_input("y", &[plant.y])?;
        let u = sim.output("u")?[0];
        plant.step(u, load, TICK, 10);
        sim.advance_to((k + 1) as f64 * TICK)?;
        if k >= 1000 {
            worst = worst.max((plant.y - 1.0).abs());
        }
        if (k + 1) % 500 == 0 {
            println!("t = {:.1} s: y = {:+.5}, u = {:+.5}", sim.time(), plant.y, u);
        }
    }
    Ok(worst)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let model = ctlgraph::compile_file(Path::new("graphs/tutorial/controller_io.yaml"), &[])?;
    let mut sim = Simulator::new(model, None);
    let mut plant = Plant { y: 0.0, v: 0.0, wn: 10.0, zeta: 0.3 };
    let start = std::time::Instant::now();
    run(&mut sim, &mut plant, 0, 1000, 0.0)?;
    let (snapshot, plant_at_1s) = (sim.state(), plant);
    let worst = run(&mut sim, &mut plant, 1000, 3000, 0.0)?;
    let per_tick = start.elapsed().as_secs_f64() / 3000.0;
    println!("after 1 s: max |y - 1| = {worst:.2e}; {:.2} us per tick (graph and plant)\n", per_tick * 1e6);

    println!("replayed from the snapshot at t = {} s with a load of 0.5 on the plant:", snapshot.time());
    sim.restore(&snapshot)?;
    plant = plant_at_1s;
    let worst = run(&mut sim, &mut plant, 1000, 3000, 0.5)?;
    println!("after 1 s: max |y - 1| = {worst:.2e} (the integral action removes the load)");
    Ok(())
}
