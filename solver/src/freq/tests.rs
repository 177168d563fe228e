//! The numeric core of the analysis, at its own level: values from
//! python-control 0.10.2 (computed once and written here; the same models
//! are analysed from graph files in the root crate's tests/analysis.rs) and
//! closed forms.

use super::*;
use crate::lti::tf2ss;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1.0)
}

fn tf(num: &[f64], den: &[f64]) -> StateSpace {
    tf2ss(num, den).unwrap()
}

#[test]
fn bode_of_a_second_order_lag_matches_python_control() {
    // control.frequency_response(tf([100], [1, 6, 100]), w): (w, |G|, phase [deg]).
    let g = tf(&[100.0], &[1.0, 6.0, 100.0]);
    let reference = [
        (0.1, 1.0000820050861485, -0.3438049315394798),
        (2.9763514416313175, 1.0767229542868395, -11.086009883662157),
        (7.847599703514611, 1.645596330173825, -50.790426833942874),
        (12.742749857031335, 1.0134375560743691, -129.20957316605706),
        (233.57214690901213, 0.0018357388957031132, -178.52580897119043),
        (1000.0, 0.00010000820050861485, -179.65619506846053),
    ];
    let values: Vec<c64> = reference.iter().map(|r| at_frequency(&g, r.0, None)).collect();
    let phase = unwrapped_phase_deg(&values);
    for (k, &(w, mag, deg)) in reference.iter().enumerate() {
        assert!(close(values[k].norm(), mag, 1e-12), "|G({w})| = {}", values[k].norm());
        assert!((phase[k] - deg).abs() < 1e-9, "∠G({w}) = {}", phase[k]);
    }
    // A pole on the axis: the response there is infinite, not NaN.
    assert_eq!(evaluate(&tf(&[1.0], &[1.0, 0.0]), c64::new(0.0, 0.0)).re, f64::INFINITY);
    assert_eq!(evaluate(&tf(&[2.5], &[1.0]), c64::new(0.0, 7.0)), c64::new(2.5, 0.0));
    // Poles at |s| = 10: two decades either way.
    let (lo, hi) = auto_range(&g, None);
    assert!(close(lo, 0.1, 1e-12) && close(hi, 1000.0, 1e-12), "{lo} {hi}");
    // Discrete: capped at Nyquist, at least four decades shown.
    let (lo, hi) = auto_range(&g, Some(0.01));
    assert!(close(hi, std::f64::consts::PI / 0.01, 1e-15) && close(lo, hi / 1e4, 1e-15), "{lo} {hi}");
    assert_eq!(auto_range(&tf(&[1.0], &[1.0]), None), (1e-2, 1e2));
}

#[test]
fn the_phase_is_unwrapped_through_minus_180() {
    // A third-order lag 1/(s + 1)³ reaches −270°: the principal value would jump to +90°.
    let g = tf(&[1.0], &[1.0, 3.0, 3.0, 1.0]);
    let w = log_grid(0.01, 100.0, 41);
    assert_eq!(w.len(), 41);
    assert!(close(w[0], 0.01, 1e-15) && close(w[20], 1.0, 1e-15) && close(w[40], 100.0, 1e-15));
    let values: Vec<c64> = w.iter().map(|&w| at_frequency(&g, w, None)).collect();
    let phase = unwrapped_phase_deg(&values);
    for (w, p) in w.iter().zip(&phase) {
        assert!((p - (-3.0 * w.atan().to_degrees())).abs() < 1e-9, "∠G({w}) = {p}");
    }
}

#[test]
fn margins_of_pi_loops_match_python_control() {
    // L = (2 + 0.5/s)/(s (s + 1)): stability_margins = (inf, 27.153463058190226,
    // 0.4330127018922193, nan, 1.2645660382007926, 1.414213562373095).
    let m = margins(&tf(&[2.0, 0.5], &[1.0, 1.0, 0.0, 0.0]), None);
    assert_eq!(m.gain_margin, f64::INFINITY);
    assert!(m.gain_crossover_phase_freq.is_nan());
    assert!(close(m.phase_margin, 27.153463058190226, 1e-9), "{m:?}");
    assert!(close(m.gain_crossover_freq, 1.2645660382007926, 1e-9), "{m:?}");
    assert!(close(m.delay_margin, 27.153463058190226f64.to_radians() / 1.2645660382007926, 1e-9), "{m:?}");
    assert!(close(m.peak_sensitivity, 1.0 / 0.4330127018922193, 1e-9), "{m:?}");
    assert!(close(m.peak_sensitivity_freq, std::f64::consts::SQRT_2, 1e-6), "{m:?}");
    // With a lag 1/(0.1 s + 1): (3.9875, 20.06083930498113, 0.32002115810781334,
    // 2.692582403567252, 1.2585650123230092, 1.3654939778317223).
    let l = tf(&[2.0, 0.5], &[0.1, 1.1, 1.0, 0.0, 0.0]);
    let m = margins(&l, None);
    for (got, want) in [
        (m.gain_margin, 3.9875000000000003),
        (m.gain_crossover_phase_freq, 2.692582403567252),
        (m.phase_margin, 20.06083930498113),
        (m.gain_crossover_freq, 1.2585650123230092),
        (m.delay_margin, 20.06083930498113f64.to_radians() / 1.2585650123230092),
        (m.peak_sensitivity, 1.0 / 0.32002115810781334),
    ] {
        assert!(close(got, want, 1e-9), "{got} vs {want}: {m:?}");
    }
    assert!(close(m.peak_sensitivity_freq, 1.3654939778317223, 1e-6), "{m:?}");
    // The closed loop L/(1 + L): bandwidth(feedback(L, 1)) = 2.063782225774107.
    let t = tf(&[2.0, 0.5], &[0.1, 1.1, 1.0, 2.0, 0.5]);
    let bw = bandwidth(|w| at_frequency(&t, w, None), evaluate(&t, c64::new(0.0, 0.0)), 1e-3, 1e3);
    assert!(close(bw, 2.063782225774107, 1e-9), "{bw}");
    assert!(bandwidth(|w| at_frequency(&t, w, None), c64::new(0.0, 0.0), 1e-3, 1e3).is_nan());
    assert_eq!(bandwidth(|_| c64::new(1.0, 0.0), c64::new(1.0, 0.0), 1e-3, 1e3), f64::INFINITY);
}

#[test]
fn an_unstable_loop_has_a_negative_phase_margin_and_no_delay_margin() {
    // L = k/(s (s + 1)(s + 2)) is unstable closed for k > 6: its phase
    // crossover is at √2, where |L| = k/6, so GM = 6/k < 1.
    let m = margins(&tf(&[12.0], &[1.0, 3.0, 2.0, 0.0]), None);
    assert!(close(m.gain_margin, 0.5, 1e-9) && close(m.gain_crossover_phase_freq, 2f64.sqrt(), 1e-9), "{m:?}");
    assert!(m.phase_margin < 0.0 && m.delay_margin == 0.0, "{m:?}");
}

#[test]
fn a_discrete_integrator_loop_has_closed_form_margins() {
    // L(z) = K/(z − 1) at z = e^{jθ}, θ = ωT: |L| = K/(2 sin(θ/2)), ∠L = −θ/2 − 90°,
    // so |L| = 1 at θc = 2 asin(K/2) and PM = 90° − θc/2.
    let (k, t) = (0.5, 0.01);
    let l = tf(&[k], &[1.0, -1.0]);
    let m = margins(&l, Some(t));
    let theta = 2.0 * (k / 2.0).asin();
    assert!(close(m.gain_crossover_freq, theta / t, 1e-9), "{m:?}");
    assert!(close(m.phase_margin, 90.0 - (theta / 2.0).to_degrees(), 1e-9), "{m:?}");
    assert!(close(m.delay_margin, m.phase_margin.to_radians() / m.gain_crossover_freq, 1e-12), "{m:?}");
    // |1 + L| = |z − 1 + K|/|z − 1| is smallest at Nyquist: (2 − K)/2.
    assert!(close(m.peak_sensitivity, 2.0 / (2.0 - k), 1e-9), "{m:?}");
}

#[test]
fn poles_damping_and_natural_frequency() {
    // control.poles(feedback(L, 1)) for the lagged PI loop above.
    let t = tf(&[2.0, 0.5], &[0.1, 1.1, 1.0, 2.0, 0.5]);
    let p = poles(&t).unwrap();
    let want = [
        (-10.207583304635051, 0.0),
        (-0.27696357010089656, 0.0),
        (-0.2577265626320331, -1.304666950297896),
        (-0.2577265626320331, 1.304666950297896),
    ];
    for (p, (re, im)) in p.iter().zip(want) {
        assert!(close(p.re, re, 1e-9) && close(p.im, im, 1e-9), "{p} vs {re}{im:+}j");
    }
    assert_eq!(poles(&tf(&[3.0], &[1.0])).unwrap(), Vec::new());
    // s = −3 ± 4j: ωn = 5, ζ = 0.6; the same pole sampled at T is z = e^{sT}.
    let (wn, zeta) = natural_frequency_and_damping(c64::new(-3.0, 4.0), None);
    assert!(close(wn, 5.0, 1e-15) && close(zeta, 0.6, 1e-15));
    let z = (c64::new(-3.0, 4.0) * 0.1).exp();
    let (wn, zeta) = natural_frequency_and_damping(z, Some(0.1));
    assert!(close(wn, 5.0, 1e-14) && close(zeta, 0.6, 1e-14), "{wn} {zeta}");
    assert_eq!(natural_frequency_and_damping(c64::new(0.0, 0.0), Some(0.1)), (f64::INFINITY, 1.0));
    assert_eq!(natural_frequency_and_damping(c64::new(0.0, 0.0), None), (0.0, -1.0));
    assert_eq!(natural_frequency_and_damping(c64::new(2.0, 0.0), None), (2.0, -1.0));
}

#[test]
fn balancing_scales_rows_and_columns_by_powers_of_two() {
    // Row 0 against column 0: c = 1e-4, r = 1e4; c·4^k ≥ r/2 first at k = 13,
    // so row 0 is divided and column 0 multiplied by 2^13 = 8192.
    let mut a = [1.0, 1e4, 1e-4, 1.0];
    balance(&mut a, 2);
    assert_eq!(a, [1.0, 1e4 / 8192.0, 1e-4 * 8192.0, 1.0]);
    // The other way round, and a matrix already balanced is left alone.
    let mut a = [1.0, 1e-4, 1e4, 1.0];
    balance(&mut a, 2);
    assert_eq!(a, [1.0, 1e-4 * 8192.0, 1e4 / 8192.0, 1.0]);
    let mut a = [1.0, 3.0, 2.0, 1.0];
    balance(&mut a, 2);
    assert_eq!(a, [1.0, 3.0, 2.0, 1.0]);
    // A zero row or column is skipped (nothing to balance against).
    let mut a = [1.0, 0.0, 5e6, 2.0];
    balance(&mut a, 2);
    assert_eq!(a, [1.0, 0.0, 5e6, 2.0]);
}
