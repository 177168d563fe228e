//! Force-control blocks in graphs: impedance against its closed form, the
//! sliding-mode controller on the feed drive (S → 0, d̂ within bounds).

mod common;
use common::max_error;
use proptest::prelude::*;

#[test]
fn continuous_impedance_step_matches_the_closed_form() {
    // m x'' + b x' + k x = 1 (m = 0.5, b = 0.5, k = 2): underdamped.
    let yaml = "simulation: { stop: 5.0, solver: { method: rk4, step: 1.0e-3 } }\n\
                blocks:\n  e: { type: step }\n  imp: { type: impedance, m: 0.5, b: 0.5, k: 2 }\n\
                wires: [e -> imp]\nrecord: [imp]\n";
    let trace = common::run(yaml);
    let (m, b, k): (f64, f64, f64) = (0.5, 0.5, 2.0);
    let (wn, zeta) = ((k / m).sqrt(), b / (2.0 * (k * m).sqrt()));
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let exact = |t: f64| (1.0 - (-zeta * wn * t).exp() * ((wd * t).cos() + zeta * wn / wd * (wd * t).sin())) / k;
    assert!(max_error(&trace, "imp", exact) < 1e-9);
}

/// The paper's SMC on the paper's feed drive, tracking a smooth reference
/// with a constant load d the controller does not know.
fn smc_run(d: f64, lambda: f64, ks: f64, rho: f64, sample_time: f64) -> ctlgraph::record::Trace {
    let yaml = format!(
        "parameters:\n  je: \"7.8715e-3/(6.4898*0.4769*1.5915)\"\n  be: \"19.8e-3/(6.4898*0.4769*1.5915)\"\n\
         simulation: {{ stop: 3.0, solver: {{ method: rk4, step: 1.0e-4 }} }}\n\
         blocks:\n  raw: {{ type: sine, amplitude: 5, frequency: 0.5 }}\n\
         \x20 ref: {{ type: reference_filter, omega: 50 }}\n  load: {{ type: constant, value: {d:e} }}\n\
         \x20 smc: {{ type: sliding_mode, lambda: {lambda:e}, ks: {ks:e}, rho: {rho:e}, je: je, be: be, d_min: -1, d_max: 1, sample_time: {sample_time:e} }}\n\
         \x20 axis: {{ type: feed_drive, j: 7.8715e-3, b: 19.8e-3, ka: 6.4898, kt: 0.4769, rg: 1.5915, disturbance_input: true }}\n\
         \x20 err: {{ type: sum, signs: \"+-\" }}\n\
         wires: [raw -> ref, ref.x -> smc.xr, ref.dx -> smc.dxr, ref.ddx -> smc.ddxr, axis.x -> smc.x, axis.v -> smc.dx,\n\
         \x20       smc.u -> axis.u, load -> axis.d, ref.x -> err.u1, axis.x -> err.u2]\n\
         record: [s: smc.s, d_hat: smc.d_hat, e: err]\n"
    );
    common::run(&yaml)
}

#[test]
fn sliding_mode_drives_s_and_the_error_to_zero_and_learns_the_load() {
    for sample_time in [0.0, 1.0e-3] {
        let trace = smc_run(0.4, 200.0, 0.3, 30.0, sample_time);
        let late = |c: &str| {
            ctlgraph::core::checks::metrics::evaluate(
                ctlgraph::core::checks::metrics::Metric::MaxAbs,
                trace.t(),
                trace.column(c).unwrap(),
                &[2.0, 3.0],
            )
        };
        assert!(late("s") < 0.05, "T = {sample_time}: |S| = {}", late("s"));
        assert!(late("e") < 5e-4, "T = {sample_time}: |e| = {} mm", late("e"));
        let d_hat = *trace.column("d_hat").unwrap().last().unwrap();
        assert!((d_hat - 0.4).abs() < 0.02, "T = {sample_time}: d̂ = {d_hat}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    #[test]
    fn sliding_mode_keeps_d_hat_in_bounds_and_reaches_s_zero(d in -0.9..0.9f64, lambda in 50.0..400.0f64,
            ks in 0.1..1.0f64, rho in 5.0..100.0f64, discrete in any::<bool>()) {
        // Region: λ, Ks, ρ > 0 with the plant's Je, Be, d inside [d_min, d_max];
        // discrete at T = 1 ms (T·Ks/Je < 1).
        let trace = smc_run(d, lambda, ks, rho, if discrete { 1.0e-3 } else { 0.0 });
        prop_assert!(trace.column("d_hat").unwrap().iter().all(|v| (-1.0..=1.0).contains(v)));
        let s_end = ctlgraph::core::checks::metrics::evaluate(
            ctlgraph::core::checks::metrics::Metric::MaxAbs, trace.t(), trace.column("s").unwrap(), &[2.5, 3.0]);
        prop_assert!(s_end < 0.2, "|S| at the end {s_end}");
    }
}
