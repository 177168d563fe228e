//! Property tests of the event-driven and delay blocks (relay, hit
//! crossing, resettable integrator, transport delays, discrete delay) with
//! the strategies and harness of `ctlgraph_blocks::testing`.

mod common;
use common::run_block as run;
use ctlgraph::blocks::testing::{self, Signal};
use proptest::prelude::*;

/// The most the default cubic interpolation between samples h = 0.01
/// apart may err on `u`'s sines: h⁴/4!·max|u⁽⁴⁾| with the stencil
/// one-sided (beside a breakpoint or a jump), and where fewer samples lie
/// between a breakpoint and the newest (a delay under three steps) the
/// quadratic's h³/12·max|u'''| or the line's h²/8·max|u''|. A 16 Hz sine
/// has six samples a period; its interpolant may pass its crest by that.
fn interpolation_error(u: &Signal) -> f64 {
    let derivative =
        |p: i32| -> f64 { u.sines.iter().map(|&(a, f, _)| a.abs() * (2.0 * std::f64::consts::PI * f).powi(p)).sum() };
    let h = 0.01f64;
    let line = h.powi(2) / 8.0 * derivative(2);
    let quadratic = h.powi(3) / 12.0 * derivative(3);
    let cubic = h.powi(4) / 24.0 * derivative(4);
    line.max(quadratic).max(cubic) + 1e-9
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    #[test]
    fn relay_switches_only_past_its_thresholds(u in testing::signal(3.0), (off, on) in testing::limits(2.0)) {
        let params = format!("on_threshold: {on:e}, off_threshold: {off:e}, on_value: 2, off_value: -1");
        let trace = run("relay", &params, &[&u], 3.0);
        let (t, y) = (trace.t(), trace.column("y").unwrap());
        for i in 0..t.len() {
            prop_assert!(y[i] == 2.0 || y[i] == -1.0);
            let before = if i == 0 { -1.0 } else { y[i - 1] };
            // Turning on needs u >= on, turning off u <= off (up to the
            // location tolerance); otherwise the state holds.
            if y[i] == 2.0 && before == -1.0 {
                prop_assert!(u.eval(t[i]) >= on - 1e-9, "on at t = {} with u = {}", t[i], u.eval(t[i]));
            }
            if y[i] == -1.0 && before == 2.0 {
                prop_assert!(u.eval(t[i]) <= off + 1e-9, "off at t = {} with u = {}", t[i], u.eval(t[i]));
            }
        }
    }

    #[test]
    fn hit_crossing_fires_only_where_the_input_crossed(u in testing::signal(2.0), level in -1.0..1.0f64) {
        let trace = run("hit_crossing", &format!("level: {level:e}"), &[&u], 3.0);
        let (t, y) = (trace.t(), trace.column("y").unwrap());
        for i in 1..t.len() {
            prop_assert!(y[i] == 0.0 || y[i] == 1.0);
            if y[i] == 1.0 {
                // The input is at the level there (located) or crossed it by a step.
                let (a, b) = (u.eval(t[i - 1]) - level, u.eval(t[i]) - level);
                prop_assert!(b.abs() < 1e-6 || a * b <= 0.0, "hit at t = {} without a crossing", t[i]);
            }
        }
    }

    #[test]
    fn resettable_integrator_restarts_from_its_initial_value(u in testing::signal(2.0), gate in testing::signal(1.0),
            x0 in -1.0..1.0f64) {
        // Between resets |x − x0| grows at most like sup|u|·(t − last reset).
        let trace = run("integrator", &format!("initial: {x0:e}, reset: either"), &[&u, &gate], 3.0);
        let (t, y) = (trace.t(), trace.column("y").unwrap());
        for i in 0..t.len() {
            prop_assert!((y[i] - x0).abs() <= u.bound() * t[i] + 1e-9);
        }
    }

    #[test]
    fn transport_delay_shifts_smooth_inputs_within_the_interpolation_bound(u in testing::signal(2.0),
            delay in prop_oneof![Just(0.0), 0.02..0.5f64], initial in -1.0..1.0f64) {
        // Delays shorter than the step (0.01) are extrapolated (documented),
        // outside this bound; zero is plain feedthrough.
        let smooth = Signal { steps: Vec::new(), ..u.clone() };
        let trace = run("transport_delay", &format!("delay: {delay:e}, initial: {initial:e}"), &[&smooth], 2.0);
        let (t, y) = (trace.t(), trace.column("y").unwrap());
        let bound = interpolation_error(&smooth);
        for i in 0..t.len() {
            prop_assert!(y[i].abs() <= initial.abs().max(smooth.bound()) + bound);
            if t[i] < delay {
                prop_assert_eq!(y[i], initial);
            } else {
                prop_assert!((y[i] - smooth.eval(t[i] - delay)).abs() <= bound, "t = {}: {} vs {}", t[i], y[i], smooth.eval(t[i] - delay));
            }
        }
        // Steps no breakpoint marks (an `fcn`'s) do not make it overshoot,
        // given the three steps of samples past the query a cubic needs on
        // one side of the jump (documented).
        if delay == 0.0 || delay >= 0.03 {
            let trace = run("transport_delay", &format!("delay: {delay:e}, initial: {initial:e}"), &[&u], 2.0);
            for y in trace.column("y").unwrap() {
                prop_assert!(y.abs() <= initial.abs().max(u.bound()) + interpolation_error(&u));
            }
        }
    }

    #[test]
    fn variable_transport_delay_is_bounded(u in testing::signal(2.0), tau in testing::signal(0.2), initial in -1.0..1.0f64) {
        let tau = Signal { bias: tau.bias + 0.25, ..tau };
        let trace = run("variable_transport_delay", &format!("max_delay: 0.5, initial: {initial:e}"), &[&u, &tau], 2.0);
        for y in trace.column("y").unwrap() {
            prop_assert!(y.abs() <= initial.abs().max(u.bound()) + interpolation_error(&u));
        }
    }

    #[test]
    fn discrete_delay_shifts_by_n_samples(u in testing::signal(3.0), n in 1usize..6, period in 0.01..0.2f64) {
        let params = format!("samples: {n}, initial: 7, sample_time: {period:e}");
        let trace = run("delay", &params, &[&u], 2.0);
        let (t, y) = (trace.t(), trace.column("y").unwrap());
        // Rows at sample hits, one per hit.
        let mut hits = Vec::new();
        for (i, &ti) in t.iter().enumerate() {
            let k = (ti / period).round();
            if (ti - k * period).abs() < 1e-12 && k as usize == hits.len() {
                hits.push(i);
            }
        }
        for (k, &i) in hits.iter().enumerate() {
            let expected = if k < n { 7.0 } else { u.eval(t[hits[k - n]]) };
            prop_assert!((y[i] - expected).abs() < 1e-12, "k = {k}: {} vs {expected}", y[i]);
        }
    }

    #[test]
    fn milling_force_is_bounded_by_its_chips(x in testing::signal(0.02), y in testing::signal(0.02), teeth in 1usize..5,
            rpm in 600.0..12000.0f64, entry in 0.0..180.0f64, sweep in 10.0..180.0f64, zero_crossing in any::<bool>()) {
        // Chips never negative at a major step; |Fx|, |Fy| <= N·Kt·ap·(1 + Kr)·max h, and
        // h <= ft + |x − x_τ| + |y − y_τ| with the delayed inputs the same signals shifted.
        let (kt, kr, ap, ft) = (800.0, 0.3, 2.0, 0.05);
        let params = format!(
            "teeth: {teeth}, rpm: {rpm:e}, kt: {kt}, kr: {kr}, ap: {ap}, ft: {ft}, entry: {entry:e}, \
             exit: {:e}, zero_crossing: {zero_crossing}, tooth_outputs: true", entry + sweep);
        let shifted = |s: &Signal| Signal { bias: s.bias + 0.01, ..s.clone() };
        let (xd, yd) = (shifted(&x), shifted(&y));
        let trace = run("milling_force", &params, &[&x, &y, &xd, &yd], 0.2);
        let h_max = ft + 2.0 * (x.bound() + y.bound()) + 0.02;
        let f_max = teeth as f64 * kt * ap * (1.0 + kr) * h_max;
        for i in 0..trace.t().len() {
            for j in 1..=teeth {
                let name = if teeth == 1 { "h".to_string() } else { format!("h[{j}]") };
                let h = trace.column(&name).unwrap()[i];
                prop_assert!((0.0..=h_max).contains(&h), "h[{j}] = {h}");
            }
            for f in ["fx", "fy"] {
                prop_assert!(trace.column(f).unwrap()[i].abs() <= f_max);
            }
        }
    }
}
