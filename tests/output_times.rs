//! `simulation: { output: { refine: N } }` and `{ every: DT }`: rows from
//! the solver's dense output between major steps, the solution unchanged.

mod common;
use common::run;

/// A first-order lag's step response, y = 1 − e^(−t/τ), τ = 0.5, with
/// `output` and `solver` as given.
fn lag(solver: &str, output: &str) -> ctlgraph::record::Trace {
    run(&format!(
        "simulation: {{ stop: 3.0, solver: {solver}{output} }}\n\
         blocks:\n  u: {{ type: step, at: 0.2 }}\n  plant: {{ type: transfer_function, num: [1], den: [0.5, 1] }}\n\
         wires: [u -> plant]\nrecord: [u, y: plant]\n"
    ))
}

fn exact(t: f64) -> f64 {
    if t < 0.2 { 0.0 } else { 1.0 - (-(t - 0.2) / 0.5).exp() }
}

#[test]
fn refine_adds_rows_inside_each_step_and_keeps_the_steps_values() {
    for solver in ["{ method: dopri5, rtol: 1.0e-9, atol: 1.0e-12 }", "{ method: rk4, step: 0.01 }"] {
        let plain = lag(solver, "");
        let refined = lag(solver, ", output: { refine: 4 }");
        let steps = plain.t().len() - 1;
        assert_eq!(refined.t().len(), 4 * steps + 1, "{solver}");
        // Every fourth row is a major step, to the bit.
        for (k, (&t, &y)) in plain.t().iter().zip(plain.column("y").unwrap()).enumerate() {
            assert_eq!((refined.t()[4 * k], refined.column("y").unwrap()[4 * k]), (t, y), "{solver} row {k}");
        }
        // The rows between are the solution there, to the tolerance (rk4
        // holds the lag by its exact transition: to rounding).
        let worst = refined.t().iter().zip(refined.column("y").unwrap()).map(|(&t, &y)| (y - exact(t)).abs());
        let worst = worst.fold(0.0, f64::max);
        assert!(worst < 1e-8, "{solver}: {worst}");
    }
}

#[test]
fn every_gives_exactly_the_grid() {
    let trace = lag("{ method: dopri5, rtol: 1.0e-9, atol: 1.0e-12 }", ", output: { every: 0.01 }");
    let grid: Vec<f64> = (0..=300).map(|k| k as f64 * 0.01).collect();
    assert_eq!(trace.t(), grid);
    let worst = grid.iter().zip(trace.column("y").unwrap()).map(|(&t, &y)| (y - exact(t)).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-8, "{worst}");
    // The step source's jump is a major step on the grid: its row is the value after.
    assert_eq!(trace.column("u").unwrap()[20], 1.0);
}

#[test]
fn a_bad_output_setting_is_refused_where_it_is_written() {
    for (output, message) in [
        ("{ refine: 2.5 }", "`output.refine` must be a whole number from 1 to 1000, got 2.5"),
        ("{ every: -1 }", "`output.every` must be a positive number, got -1"),
        ("{ refine: 2, every: 0.1 }", "`output` takes `refine` or `every`, not both"),
        ("{ refin: 2 }", "unknown key `refin` in `simulation.output`"),
    ] {
        let yaml = format!("simulation: {{ output: {output} }}\nblocks:\n  c: {{ type: constant }}\nrecord: [c]\n");
        let error = common::error(&yaml);
        assert!(error.message.contains(message), "{output}: {error}");
        assert_eq!(error.pos.as_ref().map(|p| p.line), Some(1), "{output}: {error}");
    }
}
