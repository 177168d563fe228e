//! The s_curve block in graphs: its feed integrates to its length, the
//! curvature limits lower the feed, mistakes are named, and (property) the
//! limits hold for any path and limits.

mod common;
use common::{error, run};
use proptest::prelude::*;

fn graph(params: &str, stop: f64) -> String {
    format!(
        "simulation: {{ stop: {stop}, solver: {{ method: rk4, step: 1.0e-3 }} }}\n\
         blocks:\n  plan: {{ type: s_curve, {params} }}\n  x: {{ type: integrator }}\n\
         wires: [plan.f -> x]\nrecord: [f: plan.f, a: plan.a, s: plan.s, x]\n"
    )
}

#[test]
fn the_feed_integrates_to_the_travelled_length() {
    // A 30° arc of radius 400 mm at up to 20 mm/s, as the paper's test.
    let length = 400.0 * std::f64::consts::PI / 6.0;
    let trace = run(&graph(&format!("length: {length}, feed: 20, accel: 100, jerk: 1000, start: 0.5"), 12.0));
    let (f, s, x) = (trace.column("f").unwrap(), trace.column("s").unwrap(), trace.column("x").unwrap());
    // RK4 integrates the piecewise-cubic s exactly between events.
    for (k, (&si, &xi)) in s.iter().zip(x).enumerate() {
        assert!((si - xi).abs() < 1e-9, "t = {}: s {si} vs ∫f {xi}", trace.t()[k]);
    }
    assert_eq!(f.iter().copied().fold(0.0, f64::max), 20.0);
    assert_eq!(*s.last().unwrap(), length);
    assert!(trace.at("s", 0.5).unwrap() == 0.0 && trace.at("f", 0.4).unwrap() == 0.0);
}

#[test]
fn curvature_limits_lower_the_feed() {
    // Normal acceleration 0.5 mm/s² on ρ = 400 mm: f <= sqrt(200) mm/s.
    let trace = run(&graph("length: 100, feed: 20, accel: 100, jerk: 1000, radius: 400, accel_normal: 0.5", 12.0));
    let peak = trace.column("f").unwrap().iter().copied().fold(0.0, f64::max);
    assert!((peak - 200f64.sqrt()).abs() < 1e-12, "{peak}");
}

#[test]
fn mistakes_are_named_at_their_key() {
    let e = error(&graph("length: 1, feed: 1, accel: 1, jerk: 1, omega: 0.1", 1.0));
    assert!(e.to_string().contains("`omega`: a curvature limit needs the path's `radius`"), "{e}");
    let e = error(&graph("length: 1, feed: 1, accel: 1, jerk: 1, radius: 5, tc: 0.002", 1.0));
    assert!(e.to_string().contains("`tc`: the chord-error limit needs both `tc` and `chord_error`"), "{e}");
    let e = error(&graph("length: 1, feed: 1, accel: 1, jerk: 1, radius: 5, tc: 0.002, chord_error: 5", 1.0));
    assert!(e.to_string().contains("`chord_error`: must be less than the radius 5"), "{e}");
    let e = error(&graph("length: 0, feed: 1, accel: 1, jerk: 1", 1.0));
    assert!(e.to_string().contains("`length`: must be a positive number"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    /// Any path and limits: feed, acceleration within their limits, the
    /// length travelled monotonically and reached exactly, at rest at the end.
    #[test]
    fn the_limits_hold(length in 0.01..500.0f64, feed in 0.5..50.0f64, accel in 1.0..500.0f64, jerk in 5.0..5000.0f64) {
        let p = ctlgraph::blocks::motion::SCurve::plan(length, feed, accel, jerk);
        let stop = p.duration + 0.01;
        let trace = run(&graph(&format!("length: {length:e}, feed: {feed:e}, accel: {accel:e}, jerk: {jerk:e}"), stop));
        let (f, a, s) = (trace.column("f").unwrap(), trace.column("a").unwrap(), trace.column("s").unwrap());
        prop_assert!(f.iter().all(|&v| (0.0..=feed * (1.0 + 1e-12)).contains(&v)));
        prop_assert!(a.iter().all(|&v| v.abs() <= accel * (1.0 + 1e-12)));
        prop_assert!(s.windows(2).all(|w| w[1] >= w[0] - 1e-12 * length));
        prop_assert_eq!(*s.last().unwrap(), length);
        prop_assert_eq!(*f.last().unwrap(), 0.0);
        // Time-optimal for its peak: the duration is the rest-to-rest minimum.
        let ramp = if p.peak_feed <= accel * accel / jerk { 2.0 * (p.peak_feed / jerk).sqrt() } else { p.peak_feed / accel + accel / jerk };
        prop_assert!((p.duration - (length / p.peak_feed + ramp)).abs() < 1e-9 * p.duration);
    }
}
