//! The S-curve against its closed forms: durations, peaks, the limits
//! held on a dense grid, and the curvature limits by hand.

use super::*;

/// Largest |a| and |jerk| (by differences of a) on a grid of `n` points.
fn observed(p: &SCurve, n: usize) -> (f64, f64, f64) {
    let dt = p.duration / n as f64;
    let (mut f_max, mut a_max, mut j_max) = (0.0f64, 0.0f64, 0.0f64);
    let mut last = p.at(0.0);
    for k in 1..=n {
        let now = p.at(k as f64 * dt);
        f_max = f_max.max(now[1].abs());
        a_max = a_max.max(now[2].abs());
        j_max = j_max.max(((now[2] - last[2]) / dt).abs());
        assert!(now[0] >= last[0] - 1e-12, "s decreases at {}", k as f64 * dt);
        last = now;
    }
    (f_max, a_max, j_max)
}

#[test]
fn a_long_path_cruises_at_the_feed_limit() {
    // F = 20, A = 100, J = 1000: A is reached (F > A²/J = 10); the
    // duration is L/F + F/A + A/J.
    let p = SCurve::plan(209.44, 20.0, 100.0, 1000.0);
    assert_eq!((p.peak_feed, p.peak_accel), (20.0, 100.0));
    let want = 209.44 / 20.0 + 20.0 / 100.0 + 100.0 / 1000.0;
    assert!((p.duration - want).abs() < 1e-12, "{}", p.duration);
    let (f, a, j) = observed(&p, 200_000);
    assert!((f - 20.0).abs() < 1e-9 && (a - 100.0).abs() < 1e-9 && j <= 1000.0 * (1.0 + 1e-6), "{f} {a} {j}");
    // Half-way through the cruise: s = L/2 by symmetry.
    let mid = p.at(p.duration / 2.0);
    assert!((mid[0] - 209.44 / 2.0).abs() < 1e-9 && mid[1] == 20.0 && mid[2] == 0.0);
    // The segments' own end state is the length (the closed forms agree).
    let end = p.segments[6];
    let reached = advance(end.2, end.1, p.duration - end.0);
    assert!((reached[0] - 209.44).abs() < 1e-9 && reached[1].abs() < 1e-9 && reached[2].abs() < 1e-9);
}

#[test]
fn a_short_path_peaks_below_the_feed_limit() {
    // Acceleration limit reached, feed not: L = v²/A + v·A/J.
    let p = SCurve::plan(3.0, 20.0, 100.0, 1000.0);
    let v = p.peak_feed;
    assert!(v < 20.0 && (v * v / 100.0 + v * 100.0 / 1000.0 - 3.0).abs() < 1e-12, "{v}");
    assert_eq!(p.peak_accel, 100.0);
    // Neither reached: L = 2·v^{3/2}/sqrt(J), peak acceleration sqrt(v·J) < A.
    let q = SCurve::plan(0.5, 20.0, 100.0, 1000.0);
    let v = q.peak_feed;
    assert!((2.0 * v.powf(1.5) / 1000f64.sqrt() - 0.5).abs() < 1e-12, "{v}");
    assert!((q.peak_accel - (v * 1000.0).sqrt()).abs() < 1e-9 && q.peak_accel < 100.0);
    for p in [p, q] {
        let end = p.segments[6];
        let reached = advance(end.2, end.1, p.duration - end.0);
        assert!((reached[0] - p.length).abs() < 1e-9 && reached[1].abs() < 1e-9, "{reached:?}");
        let (f, a, j) = observed(&p, 100_000);
        assert!(f <= p.peak_feed + 1e-12 && a <= p.peak_accel + 1e-9 && j <= 1000.0 * (1.0 + 1e-6));
    }
}

#[test]
fn at_rest_before_and_after() {
    let p = SCurve::plan(10.0, 5.0, 20.0, 100.0);
    assert_eq!(p.at(-1.0), [0.0; 3]);
    assert_eq!(p.at(p.duration), [10.0, 0.0, 0.0]);
    assert_eq!(p.at(p.duration + 5.0), [10.0, 0.0, 0.0]);
    let b: Vec<f64> = p.boundaries().collect();
    assert_eq!(b.len(), 7);
    assert!(b.windows(2).all(|w| w[0] <= w[1]) && *b.last().unwrap() == p.duration);
}

#[test]
fn curvature_limits_by_hand() {
    // ρ = 400: chord error 0.001 over Tc = 2 ms allows (2/Tc)·sqrt(ρ² − (ρ − δ)²).
    let chord = CurvatureLimits { radius: 400.0, chord: Some((0.002, 0.001)), ..Default::default() };
    assert!((chord.feed_limit() - 1000.0 * (400.0f64.powi(2) - 399.999f64.powi(2)).sqrt()).abs() < 1e-9);
    let normal = CurvatureLimits { radius: 400.0, accel_normal: Some(1.0), ..Default::default() };
    assert!((normal.feed_limit() - 20.0).abs() < 1e-12);
    let jerk = CurvatureLimits { radius: 400.0, jerk_normal: Some(0.125), ..Default::default() };
    assert!((jerk.feed_limit() - (0.125f64 * 160_000.0).cbrt()).abs() < 1e-12);
    let omega = CurvatureLimits { radius: 400.0, omega: Some(0.05), ..Default::default() };
    assert_eq!(omega.feed_limit(), 20.0);
    let all = CurvatureLimits { radius: 400.0, accel_normal: Some(1.0), omega: Some(0.04), ..Default::default() };
    assert_eq!(all.feed_limit(), 16.0);
    assert_eq!(CurvatureLimits { radius: 1.0, ..Default::default() }.feed_limit(), f64::INFINITY);
}
