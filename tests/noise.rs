//! Noise: reproducible per seed, independent per block, Simulink's power
//! semantics, active windows.

mod common;

fn noise_graph(seed: u64, extra_block: bool) -> String {
    let extra = if extra_block { "  other: { type: gaussian_noise, sample_time: 0.001 }\n" } else { "" };
    format!(
        "simulation: {{ stop: 20.0, seed: {seed}, solver: {{ method: euler, step: 0.004 }} }}\n\
         blocks:\n{extra}  n: {{ type: band_limited_white_noise, power: 1.0e-4, sample_time: 0.004 }}\n\
         \x20 u: {{ type: uniform_noise, amplitude: 2, sample_time: 0.004 }}\nrecord: [n, u]\n"
    )
}

#[test]
fn band_limited_noise_has_variance_power_over_ts() {
    let trace = common::run(&noise_graph(7, false));
    let n = trace.column("n").unwrap();
    let (len, mean) = (n.len() as f64, n.iter().sum::<f64>() / n.len() as f64);
    let var = n.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (len - 1.0);
    // power/T = 1e-4/0.004 = 0.025; 5001 samples: relative standard error of
    // the variance sqrt(2/n) = 2 %.
    assert!((var / 0.025 - 1.0).abs() < 0.08, "variance {var}");
    let u = trace.column("u").unwrap();
    let var_u = u.iter().map(|v| v * v).sum::<f64>() / len;
    assert!((var_u / (4.0 / 3.0) - 1.0).abs() < 0.08, "uniform variance {var_u}");
    assert!(u.iter().all(|v| v.abs() <= 2.0));
}

#[test]
fn noise_is_reproducible_and_independent_per_block() {
    let a = common::run(&noise_graph(7, false));
    let b = common::run(&noise_graph(7, false));
    assert!(a.column("n") == b.column("n"), "same seed, same stream");
    let c = common::run(&noise_graph(8, false));
    assert!(a.column("n") != c.column("n"), "another seed, another stream");
    assert!(a.column("n") != a.column("u"), "blocks have their own streams");
    // With a 1 kHz block added there are more major steps; at every 250 Hz
    // hit the value is the same.
    let d = common::run(&noise_graph(7, true));
    for (k, &t) in a.t().iter().enumerate() {
        let v = d.at("n", t).unwrap();
        assert!(v == a.column("n").unwrap()[k], "adding a block elsewhere changed n at t = {t}");
    }
}

#[test]
fn sources_are_zero_outside_their_active_window() {
    let yaml = "simulation: { stop: 2.0, solver: { method: rk4, step: 0.01 } }\n\
                blocks:\n  n: { type: band_limited_white_noise, power: 1, sample_time: 0.01, active: [0.5, 1.0] }\n\
                \x20 c: { type: constant, value: 3, active: [0.25, 0.75] }\n  i: { type: integrator }\n\
                wires: [c -> i]\nrecord: [n, c, i]\n";
    let trace = common::run(yaml);
    for (k, &t) in trace.t().iter().enumerate() {
        let (n, c) = (trace.column("n").unwrap()[k], trace.column("c").unwrap()[k]);
        assert_eq!(n == 0.0, !(0.5..1.0).contains(&t), "noise at {t}: {n}");
        assert_eq!(c, if (0.25..0.75).contains(&t) { 3.0 } else { 0.0 }, "constant at {t}");
    }
    // The window edges are events: the integral of the windowed constant is exact.
    assert!((trace.column("i").unwrap().last().unwrap() - 1.5).abs() < 1e-12);
}
