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

mod spline {
    use super::super::bspline::{BSpline, chord_parameters};

    fn arc(n: usize, radius: f64, angle: f64) -> Vec<f64> {
        (0..n)
            .flat_map(|k| {
                let a = angle * k as f64 / (n - 1) as f64;
                [radius * a.cos(), radius * a.sin(), 0.0]
            })
            .collect()
    }

    #[test]
    fn interpolation_passes_through_every_point() {
        let pts = arc(9, 10.0, 1.0);
        let u = chord_parameters(&pts, 3).unwrap();
        let s = BSpline::fit(&pts, 3, &u, 9).unwrap();
        let mut out = [0.0; 9];
        for (k, &uk) in u.iter().enumerate() {
            s.eval(uk, &mut out);
            for c in 0..3 {
                assert!((out[c] - pts[3 * k + c]).abs() < 1e-10, "point {k}: {:?}", &out[..3]);
            }
        }
    }

    #[test]
    fn points_on_a_line_give_that_line() {
        let pts: Vec<f64> = (0..20).flat_map(|k| [1.0 + 2.0 * k as f64, -3.0 * k as f64]).collect();
        let u = chord_parameters(&pts, 2).unwrap();
        let s = BSpline::fit(&pts, 2, &u, 6).unwrap();
        let mut out = [0.0; 6];
        for k in 0..=50 {
            let v = k as f64 / 50.0;
            s.eval(v, &mut out);
            // Uniform points: chord-length parameters are arc length / L, so C(u) = p0 + u·(p_end − p0).
            assert!((out[0] - (1.0 + 38.0 * v)).abs() < 1e-10 && (out[1] + 57.0 * v).abs() < 1e-10, "{out:?}");
            assert!((out[2] - 38.0).abs() < 1e-8 && (out[3] + 57.0).abs() < 1e-8 && out[4].abs() < 1e-6, "{out:?}");
        }
    }

    #[test]
    fn derivatives_match_differences() {
        let pts = arc(40, 400.0, std::f64::consts::PI / 6.0);
        let u = chord_parameters(&pts, 3).unwrap();
        let s = BSpline::fit(&pts, 3, &u, 12).unwrap();
        let (mut a, mut b, mut c) = ([0.0; 9], [0.0; 9], [0.0; 9]);
        let h = 1e-5;
        for k in 1..20 {
            let v = k as f64 / 20.0 + 0.013;
            s.eval(v - h, &mut a);
            s.eval(v, &mut b);
            s.eval(v + h, &mut c);
            for d in 0..3 {
                let first = (c[d] - a[d]) / (2.0 * h);
                let second = (c[3 + d] - a[3 + d]) / (2.0 * h);
                assert!((first - b[3 + d]).abs() < 1e-6 * (1.0 + b[3 + d].abs()), "u {v}: {first} vs {}", b[3 + d]);
                assert!((second - b[6 + d]).abs() < 1e-4 * (1.0 + b[6 + d].abs()), "u {v}: {second} vs {}", b[6 + d]);
            }
        }
    }

    #[test]
    fn an_arc_fit_keeps_radius_length_and_curvature() {
        // The paper's machining-side arc: ρ = 400 mm over 30°, 50 samples, 12 control points.
        let (r, angle) = (400.0, std::f64::consts::PI / 6.0);
        let pts = arc(50, r, angle);
        let u = chord_parameters(&pts, 3).unwrap();
        let s = BSpline::fit(&pts, 3, &u, 12).unwrap();
        let mut out = [0.0; 9];
        for k in 0..=200 {
            s.eval(k as f64 / 200.0, &mut out);
            let radius = (out[0] * out[0] + out[1] * out[1]).sqrt();
            assert!((radius - r).abs() < 1e-5, "radius {radius}"); // 10 nm
            // |C'| = the chord length of the samples; curvature |C' × C''| / |C'|³ = 1/ρ.
            let speed = (out[3] * out[3] + out[4] * out[4]).sqrt();
            let chord = 49.0 * 2.0 * r * (angle / 98.0).sin();
            assert!((speed - chord).abs() < 1e-3 * chord, "speed {speed} vs {chord}");
            let cross = out[3] * out[7] - out[4] * out[6];
            assert!((cross / speed.powi(3) - 1.0 / r).abs() < 1e-3 / r, "curvature {}", cross / speed.powi(3));
        }
        assert!(BSpline::fit(&pts, 3, &u, 3).is_err() && BSpline::fit(&pts, 3, &u, 51).is_err());
        assert!(chord_parameters(&[1.0, 1.0, 1.0, 1.0], 2).is_err());
    }
}

mod interpolation {
    use super::super::interpolator::taylor_step;

    #[test]
    fn on_a_line_u_advances_by_the_travelled_fraction() {
        // |P'| = L = 50, P'' = 0: Δu = (f·Tc + a·Tc²/2)/L.
        let u = taylor_step(0.2, 10.0, 40.0, &[30.0, 40.0], &[0.0, 0.0], 0.002);
        assert!((u - (0.2 + (10.0 * 0.002 + 40.0 * 0.002f64.powi(2) / 2.0) / 50.0)).abs() < 1e-15);
    }

    #[test]
    fn the_curvature_term_corrects_a_non_arc_length_parameter() {
        // P(u) = (u, u²): at u = 1, P' = (1, 2), P'' = (0, 2), P'·P'' = 4, |P'|² = 5.
        let (f, a, tc) = (3.0, 0.0, 0.01);
        let u = taylor_step(1.0 - 0.5, f, a, &[1.0, 1.0], &[0.0, 2.0], tc);
        // At u = 0.5: P' = (1, 1), P'' = (0, 2): u̇ = f/√2, ü = −f²·2/4.
        let expected = 0.5 + tc * f / 2f64.sqrt() - tc * tc / 2.0 * f * f * 2.0 / 4.0;
        assert!((u - expected).abs() < 1e-15, "{u} vs {expected}");
        assert_eq!(taylor_step(0.999, 100.0, 0.0, &[1.0, 0.0], &[0.0, 0.0], 0.01), 1.0);
    }
}
