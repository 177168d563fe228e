//! The mirror-milling graphs (graphs/mirror-milling, graphs/lib/servo_axis):
//! a servo axis follows a smooth command to a fraction of a micrometre;
//! standing still, the uncompensated synchronisation error is the robots'
//! geometry in closed form and the compensation removes it to the noise;
//! a compensation gain the servos cannot follow makes the loop diverge.

mod common;
use common::run;
use ctlgraph::core::Simulator;
use std::path::Path;

fn simulator(file: &str, sets: &[(&str, &str)]) -> Simulator {
    let sets: Vec<(String, String)> = sets.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
    Simulator::new(ctlgraph::compile_file(Path::new(file), &sets).unwrap(), None)
}

#[test]
fn a_servo_axis_follows_a_smooth_command_between_the_ticks() {
    // p = 10 t², v = 20 t, a = 20 sent every Tc = 2 ms: the axis reaches
    // 20 mm/s within a micrometre's tenth of the path, where a held
    // (staircase) command would lag by up to v·Tc = 40 um.
    let yaml = "simulation: { stop: 1, solver: { method: rk4, step: 5.0e-4 } }\n\
        blocks:\n  clock: { type: clock }\n  \
        p: { type: fcn, expr: \"10*u^2\", sample_time: 0.002 }\n  \
        v: { type: fcn, expr: \"20*u\", sample_time: 0.002 }\n  \
        a: { type: constant, value: 20 }\n  \
        axis: { type: subsystem, file: graphs/lib/servo_axis.yaml }\n\
        wires: [clock -> p, clock -> v, p -> axis.p, v -> axis.v, a -> axis.a]\n\
        record: [x: axis.x, xv: axis.xv]\n";
    let trace = run(yaml);
    let worst = common::max_error(&trace, "x", |t| 10.0 * t * t);
    assert!(worst < 1e-4, "largest error {worst} mm");
    assert!((trace.column("xv").unwrap().last().unwrap() - 20.0).abs() < 1e-2);
}

/// The geometric error of lib/robot_side.yaml, g(x) = offset + scale·x +
/// rotation·(z × x), with the values lib/mirror_pair.yaml gives each robot.
fn end_effector(x: [f64; 3], offset: [f64; 3], scale: f64, rotation: f64) -> [f64; 3] {
    [
        x[0] + offset[0] + scale * x[0] - rotation * x[1],
        x[1] + offset[1] + scale * x[1] + rotation * x[0],
        x[2] + offset[2] + scale * x[2],
    ]
}

#[test]
fn standing_still_the_error_is_the_geometry_and_compensation_removes_it() {
    let mut sim = simulator("graphs/mirror-milling/compensation.yaml", &[]);
    sim.advance_to(0.4).unwrap(); // the motion starts at 0.5 s
    let y1 = end_effector([400.0, 0.0, 0.0], [0.020, -0.030, -0.020], 1.0e-4, 1.0e-4);
    let y2 = end_effector([500.0, 0.0, 0.0], [-0.030, 0.015, -0.040], -0.6e-4, 0.5e-4);
    let r = (y1[0] * y1[0] + y1[1] * y1[1] + y1[2] * y1[2]).sqrt();
    let sync = sim.signal("sync_off").unwrap().to_vec();
    for k in 0..3 {
        let mirrored = y1[k] + 100.0 * y1[k] / r; // eq. 3, the tool axis along y1
        let expected = 1000.0 * (y2[k] - mirrored);
        assert!((sync[k] - expected).abs() < 1e-9, "axis {k}: {} um, expected {expected} um", sync[k]);
    }
    // Compensated: what is left is the gratings' noise (1 um per axis),
    // filtered by the compensation's k/(2 − k) = 0.05 of its variance.
    let on = sim.signal("error_on").unwrap()[0];
    let off = sim.signal("error_off").unwrap()[0];
    assert!(off > 100.0 && on < 3.0, "without {off} um, with {on} um");
}

#[test]
fn a_compensation_faster_than_the_servos_diverges() {
    // k_comp = 0.1 converges; 0.3 integrates the error faster (k/Tc = 150 /s)
    // than the 200 rad/s servos follow, and the loop oscillates ever wider.
    for (k, diverges) in [("0.1", false), ("0.3", true)] {
        let mut sim = simulator("graphs/mirror-milling/arc_sync.yaml", &[("k_comp", k)]);
        sim.advance_to(4.0).unwrap();
        let error = sim.signal("error").unwrap()[0];
        assert_eq!(error > 1000.0, diverges, "k_comp {k}: {error} um at 4 s");
        assert!(diverges || error < 30.0, "k_comp {k}: {error} um");
    }
}
