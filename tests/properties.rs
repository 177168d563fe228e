//! Property tests of every stateful block over its documented stable
//! parameter region (`ctlgraph blocks TYPE` states the region), using the
//! strategies and harness of `ctlgraph_blocks::testing`.

mod common;
use common::run_block as run;
use ctlgraph::blocks::testing::{self, Signal, StableZpk};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn saturation_is_the_clamped_input(u in testing::signal(8.0), (lo, hi) in testing::limits(5.0)) {
        let trace = run("saturation", &format!("lower: {lo:e}, upper: {hi:e}"), &[&u], 3.0);
        for (&t, &y) in trace.t().iter().zip(trace.column("y").unwrap()) {
            prop_assert!(y >= lo && y <= hi);
            prop_assert!((y - u.eval(t).clamp(lo, hi)).abs() < 1e-9, "t = {t}");
        }
    }

    #[test]
    fn rate_limiter_respects_its_slopes(u in testing::signal(5.0), rising in 0.1..50.0f64, falling in -50.0..-0.1f64) {
        let trace = run("rate_limiter", &format!("rising: {rising:e}, falling: {falling:e}"), &[&u], 3.0);
        let (t, y) = (trace.t(), trace.column("y").unwrap());
        for i in 1..t.len() {
            let rate = (y[i] - y[i - 1]) / (t[i] - t[i - 1]);
            prop_assert!(rate <= rising * (1.0 + 1e-9) && rate >= falling * (1.0 + 1e-9), "rate {rate}");
            prop_assert!(y[i].abs() <= u.bound() + 1e-12);
        }
    }

    #[test]
    fn limited_integrator_stays_within_its_limits(u in testing::signal(10.0), (lo, hi) in testing::limits(2.0)) {
        let x0 = (lo + hi) / 2.0;
        let params = format!("initial: {x0:e}, lower: {lo:e}, upper: {hi:e}");
        let trace = run("integrator", &params, &[&u], 3.0);
        prop_assert!(trace.column("y").unwrap().iter().all(|y| *y >= lo && *y <= hi));
    }

    #[test]
    fn unlimited_integrator_grows_at_most_linearly(u in testing::signal(3.0), x0 in -1.0..1.0f64) {
        let trace = run("integrator", &format!("initial: {x0:e}"), &[&u], 2.0);
        for (&t, &y) in trace.t().iter().zip(trace.column("y").unwrap()) {
            prop_assert!((y - x0).abs() <= u.bound() * t + 1e-9);
        }
    }

    #[test]
    fn filtered_derivative_is_bounded_by_2u_over_tau(u in testing::signal(2.0), tau in 1.0e-3..0.5f64) {
        // y = (u − x)/τ with x a low-pass of u, so |y| <= 2·sup|u|/τ.
        let trace = run("derivative", &format!("tau: {tau:e}"), &[&u], 2.0);
        prop_assert!(trace.column("y").unwrap().iter().all(|y| y.abs() <= 2.0 * u.bound() / tau * (1.0 + 1e-6)));
    }

    #[test]
    fn stable_zpk_follows_its_exact_step_response(sys in testing::stable_zpk()) {
        let trace = run("zpk", &sys.params(), &[&Signal::constant(1.0)], 14.0 * sys.slowest());
        let scale = sys.l1_bound().max(1.0);
        for (&t, &y) in trace.t().iter().zip(trace.column("y").unwrap()) {
            prop_assert!((y - sys.step_response(t)).abs() <= 1e-6 * scale, "t = {t}");
        }
        prop_assert!((trace.column("y").unwrap().last().unwrap() - sys.dc_gain()).abs() <= 1e-5 * scale);
    }

    #[test]
    fn stable_transfer_function_is_bibo(sys in testing::stable_zpk(), u in testing::signal(1.0)) {
        // The same system as num/den coefficients, driven by a bounded input:
        // |y| <= ‖g‖₁·sup|u|.
        let trace = run("zpk", &sys.params(), &[&u], 5.0);
        let bound = sys.l1_bound() * u.bound();
        prop_assert!(trace.column("y").unwrap().iter().all(|y| y.abs() <= bound * (1.0 + 1e-6) + 1e-9));
    }

    #[test]
    fn hurwitz_state_space_is_bibo(a in testing::hurwitz_matrix(3), b in prop::collection::vec(-2.0..2.0f64, 3),
                                   c in prop::collection::vec(-2.0..2.0f64, 3), u in testing::signal(1.0)) {
        // A = K − P with P >= I/2 gives d|x|/dt <= −|x|/2 + ‖B‖|u|, so
        // |x| <= 2‖B‖·sup|u| from x(0) = 0, and |y| <= ‖C‖·|x|.
        let rows = |m: &[Vec<f64>]| m.iter().map(|r| format!("[{}]", r.iter().map(|v| format!("{v:e}")).collect::<Vec<_>>().join(", "))).collect::<Vec<_>>().join(", ");
        let col: Vec<Vec<f64>> = b.iter().map(|v| vec![*v]).collect();
        let params = format!("A: [{}], B: [{}], C: [{}]", rows(&a), rows(&col), rows(std::slice::from_ref(&c)));
        let trace = run("state_space", &params, &[&u], 5.0);
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let bound = norm(&c) * 2.0 * norm(&b) * u.bound();
        prop_assert!(trace.column("y").unwrap().iter().all(|y| y.abs() <= bound * (1.0 + 1e-6) + 1e-9));
    }

    #[test]
    fn schur_stable_discrete_tf_is_bibo_and_reaches_dc_gain(den in testing::schur_polynomial(),
                                                             gain in -3.0..3.0f64, u in testing::signal(1.0)) {
        // num = gain·z^(n−1): strictly proper. ‖h‖₁ from the impulse response.
        let n = den.len() - 1;
        let mut num = vec![0.0; n];
        num[0] = gain;
        let list = |v: &[f64]| v.iter().map(|x| format!("{x:e}")).collect::<Vec<_>>().join(", ");
        let params = format!("num: [{}], den: [{}], sample_time: 0.01", list(&num), list(&den));
        let mut h = vec![0.0; 3000];
        for k in 0..h.len() {
            // y(k) = Σ num_j u(k−1−j) − Σ den_j y(k−j), u the unit impulse.
            let mut v = if k >= 1 { num.get(k - 1).copied().unwrap_or(0.0) } else { 0.0 };
            for j in 1..=n {
                if k >= j {
                    v -= den[j] * h[k - j];
                }
            }
            h[k] = v;
        }
        let l1: f64 = h.iter().map(|v| v.abs()).sum();
        let trace = run("discrete_transfer_function", &params, &[&u], 5.0);
        prop_assert!(trace.column("y").unwrap().iter().all(|y| y.abs() <= l1 * u.bound() * (1.0 + 1e-9) + 1e-12));
        let step = run("discrete_transfer_function", &params, &[&Signal::constant(1.0)], 30.0);
        let dc = gain / den.iter().sum::<f64>();
        prop_assert!((step.column("y").unwrap().last().unwrap() - dc).abs() <= 1e-6 * l1.max(1.0));
    }

    #[test]
    fn unit_delay_and_hold_pass_samples_on(u in testing::signal(4.0), period in 0.01..0.5f64) {
        let held = run("zero_order_hold", &format!("sample_time: {period:e}"), &[&u], 2.0);
        let delayed = run("unit_delay", &format!("sample_time: {period:e}, initial: 0"), &[&u], 2.0);
        let (t, yh, yd) = (held.t(), held.column("y").unwrap(), delayed.column("y").unwrap());
        for i in 0..t.len() {
            let k = ((t[i] + 1e-9 * period) / period).floor();
            // Sampled at the last hit k·T; the delay shows the hit before.
            prop_assert!((yh[i] - u.eval(k * period)).abs() < 1e-9, "hold at {}", t[i]);
            let before = if k >= 1.0 { u.eval((k - 1.0) * period) } else { 0.0 };
            prop_assert!((yd[i] - before).abs() < 1e-9, "delay at {}", t[i]);
        }
    }

    #[test]
    fn pid_output_never_leaves_its_limits(e in testing::signal(5.0), (lo, hi) in testing::limits(3.0),
                                          kp in 0.0..10.0f64, ki in 0.0..50.0f64, kd in 0.0..0.5f64,
                                          aw in prop::sample::select(vec!["clamping", "back_calculation", "none"]),
                                          discrete in any::<bool>()) {
        let st = if discrete { ", sample_time: 0.002" } else { "" };
        let params = format!("kp: {kp:e}, ki: {ki:e}, kd: {kd:e}, n: 50, lower: {lo:e}, upper: {hi:e}, anti_windup: {aw}{st}");
        let trace = run("pid", &params, &[&e], 3.0);
        prop_assert!(trace.column("u").unwrap().iter().all(|u| *u >= lo && *u <= hi));
    }
}

#[test]
fn strategies_produce_what_they_promise() {
    use proptest::strategy::ValueTree;
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    for _ in 0..200 {
        let s = testing::signal(2.5).new_tree(&mut runner).unwrap().current();
        assert!(s.bound() <= 2.5 + 1e-12);
        let sys: StableZpk = testing::stable_zpk().new_tree(&mut runner).unwrap().current();
        assert!(sys.poles.iter().all(|p| p.re < 0.0) && sys.zeros.len() <= sys.poles.len());
        let den = testing::schur_polynomial().new_tree(&mut runner).unwrap().current();
        assert_eq!(den[0], 1.0);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn td_reaches_a_constant_reference_without_overshoot(r in -5.0..5.0f64, delta in 1.0e2..1.0e5f64,
            h in 1.0e-4..1.0e-2f64, k in 2.0..10.0f64, form in prop::sample::select(vec!["fst", "paper", "fhan"])) {
        prop_assume!(r.abs() > 1e-3);
        // Region: δ > 0, h0 = k·h >= 2h (with h0 = h both forms can overshoot by
        // several percent: proptest found r = −1.61, δ = 100, h = 5.2 ms).
        // Time-optimal reach ~2·sqrt(|r|/δ).
        let params = format!("delta: {delta:e}, h0: {:e}, sample_time: {h:e}, form: {form}", k * h);
        let stop = 6.0 * (r.abs() / delta).sqrt() + 400.0 * k * h;
        let trace = run("tracking_differentiator", &params, &[&Signal::constant(r)], stop);
        let (r1, r2) = (trace.column("r1").unwrap(), trace.column("r2").unwrap());
        // The paper's printed c = x1 + h·x2 overshoots (up to 15.8 % over this
        // region in a 3000-case sweep; 1.7 % at the FLADRC graphs' δ = 1e4,
        // h0 = 5h); Han's forms do not.
        let allowed = if form == "paper" { 0.17 } else { 1e-9 };
        for v in r1 {
            prop_assert!(v * r.signum() <= r.abs() * (1.0 + allowed), "overshoot: {v} past {r}");
        }
        prop_assert!((r1.last().unwrap() - r).abs() <= 1e-6 * r.abs().max(1.0), "r1 ends at {}", r1.last().unwrap());
        prop_assert!(r2.last().unwrap().abs() <= 1e-3 * (delta * r.abs()).sqrt(), "r2 ends at {}", r2.last().unwrap());
    }

    #[test]
    fn leso_tracks_a_slowly_varying_disturbance(w0 in 200.0..2000.0f64, amp in 0.1..10.0f64,
            freq in 0.1..5.0f64, b0 in 0.5..5.0f64, discrete in any::<bool>()) {
        // Double integrator y'' = f(t) + b0·u with f = amp·sin(2π·freq·t) and a
        // bounded input u. Region: ω0 > 0 (continuous), ω0·h < 2 (discrete,
        // here h = 1e-4). For a disturbance of slope at most s = 2π·freq·amp
        // the z3 error settles below 3s/ω0 (plus a transient of e^{-ω0 t}).
        let st = if discrete { ", sample_time: 1.0e-4" } else { "" };
        let yaml = format!(
            "simulation: {{ stop: 1.0, solver: {{ method: rk4, step: 1.0e-4 }} }}\n\
             blocks:\n  f: {{ type: sine, amplitude: {amp:e}, frequency: {freq:e} }}\n\
             \x20 u: {{ type: sine, amplitude: 0.5, frequency: 3 }}\n  bu: {{ type: gain, k: {b0:e} }}\n\
             \x20 acc: {{ type: sum }}\n  v: {{ type: integrator }}\n  y: {{ type: integrator }}\n\
             \x20 leso: {{ type: leso, omega: {w0:e}, b0: {b0:e}{st} }}\n  z: {{ type: demux, outputs: 3 }}\n\
             wires: [f -> acc.u1, u -> bu, bu -> acc.u2, acc -> v, v -> y, y -> leso.y, u -> leso.u, leso -> z]\n\
             record: [f, y, z1: z.y1, z3: z.y3]\n");
        let model = ctlgraph::compile_str(&yaml, "leso.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
        let trace = ctlgraph::simulate(model, None).unwrap();
        let slope = 2.0 * std::f64::consts::PI * freq * amp;
        // Discrete: the observer holds u over h while the plant sees it vary,
        // a model error of up to b0·|u'|·h (u = 0.5 sin 6πt), and Euler lags
        // the disturbance by about a step.
        let sampling = if discrete { b0 * 0.5 * 6.0 * std::f64::consts::PI * 1e-4 + slope * 1e-4 } else { 0.0 };
        let bound = 3.0 * slope / w0 * 1.5 + 1e-3 * amp + 2.0 * sampling;
        for (k, &t) in trace.t().iter().enumerate() {
            if t < 30.0 / w0 {
                continue;
            }
            let (f, z3) = (trace.column("f").unwrap()[k], trace.column("z3").unwrap()[k]);
            prop_assert!((f - z3).abs() <= bound, "t = {t}: f = {f}, z3 = {z3}, bound {bound}");
            let (y, z1) = (trace.column("y").unwrap()[k], trace.column("z1").unwrap()[k]);
            prop_assert!((y - z1).abs() <= bound / w0 + 1e-9, "t = {t}: y = {y}, z1 = {z1}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    /// The play operator never lets the output leave the dead band, and
    /// moves it only the way the input moves.
    #[test]
    fn backlash_stays_in_its_band_and_moves_with_the_input(u in testing::signal(4.0), width in 0.0..2.0f64, initial in -1.0..1.0f64) {
        let trace = run("backlash", &format!("width: {width:e}, initial: {initial:e}"), &[&u], 3.0);
        let y = trace.column("y").unwrap();
        let t = trace.t();
        for i in 1..t.len() {
            let uu = u.eval(t[i]);
            prop_assert!((y[i] - uu).abs() <= width / 2.0 + 1e-9, "t = {}: y {} u {uu}", t[i], y[i]);
            let (dy, du) = (y[i] - y[i - 1], uu - u.eval(t[i - 1]));
            prop_assert!(dy == 0.0 || dy * du > 0.0, "t = {}: the output moved against the input", t[i]);
        }
    }

    /// A limited discrete integrator stays within its limits; a moving
    /// average within its input's range.
    #[test]
    fn discrete_integrator_and_moving_average_stay_bounded(u in testing::signal(5.0), (lo, hi) in testing::limits(2.0), window in 1usize..8) {
        let params = format!("method: trapezoidal, gain: 3, initial: {:e}, lower: {lo:e}, upper: {hi:e}, sample_time: 0.01", (lo + hi) / 2.0);
        let trace = run("discrete_integrator", &params, &[&u], 2.0);
        prop_assert!(trace.column("y").unwrap().iter().all(|y| *y >= lo && *y <= hi));
        let trace = run("moving_average", &format!("window: {window}, sample_time: 0.01"), &[&u], 2.0);
        let bound = u.bound().max(0.0);
        prop_assert!(trace.column("y").unwrap().iter().all(|y| y.abs() <= bound + 1e-12));
    }

    /// Whatever the noise levels and the plant's pole, the time-varying
    /// Kalman filter's estimate converges to the stationary filter's (its
    /// gain to the Riccati equation's solution), on the same measurements.
    #[test]
    fn kalman_time_varying_converges_to_the_stationary_filter(q in 1e-3..1.0f64, r in 1e-2..1.0f64, pole in -0.9..0.99f64, freq in 0.1..3.0f64) {
        let plant = format!("A: [[1, 0.1], [0, {pole:e}]], C: [[1, 0]], Q: [[{:e}, 0], [0, {q:e}]], R: {r:e}, sample_time: 0.1", q / 10.0);
        let yaml = format!(
            "simulation: {{ stop: 100, solver: {{ method: rk4, step: 0.1 }} }}\nblocks:\n  y: {{ type: sine, frequency: {freq:e}, amplitude: 2 }}\n\
             \x20 ss: {{ type: kalman_filter, {plant}, gain: steady_state }}\n  tv: {{ type: kalman_filter, {plant}, P0: [[10, 0], [0, 10]] }}\n\
             wires: [y -> ss.y, y -> tv.y]\nrecord: [ss: ss.xhat, tv: tv.xhat]\n"
        );
        let trace = common::run(&yaml);
        for i in 1..=2 {
            let (ss, tv) = (trace.column(&format!("ss[{i}]")).unwrap(), trace.column(&format!("tv[{i}]")).unwrap());
            let n = ss.len() - 1;
            prop_assert!((ss[n] - tv[n]).abs() < 1e-6 * (1.0 + ss[n].abs()), "x̂[{}]: {} vs {}", i, ss[n], tv[n]);
        }
    }
}
