use super::*;
use std::f64::consts::PI;

fn sampled(f: impl Fn(f64) -> f64, t_end: f64, n: usize) -> (Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..=n).map(|i| t_end * i as f64 / n as f64).collect();
    let y = t.iter().map(|&t| f(t)).collect();
    (t, y)
}

fn close(a: f64, b: f64, tol: f64) {
    assert!((a - b).abs() <= tol, "{a} vs {b}");
}

#[test]
fn first_order_step_response() {
    // y = 1 − e^{−t/τ}: 2 % settling at τ·ln 50, 10–90 % rise τ·ln 9.
    let tau = 0.5;
    let (t, y) = sampled(|t| 1.0 - (-t / tau).exp(), 10.0, 100_000);
    close(evaluate(Metric::SettlingTime, &t, &y, &[1.0, 0.02]), tau * 50f64.ln(), 1e-6);
    close(evaluate(Metric::RiseTime, &t, &y, &[1.0]), tau * 9f64.ln(), 1e-6);
    assert_eq!(evaluate(Metric::Overshoot, &t, &y, &[1.0]), 0.0);
    close(evaluate(Metric::FinalValue, &t, &y, &[]), 1.0 - (-20.0f64).exp(), 1e-12);
    // The error e = 1 − y = e^{−t/τ}: IAE = ISE·2 = τ, ITAE = τ².
    let e: Vec<f64> = y.iter().map(|v| 1.0 - v).collect();
    close(evaluate(Metric::Iae, &t, &e, &[]), tau, 1e-6);
    close(evaluate(Metric::Ise, &t, &e, &[]), tau / 2.0, 1e-6);
    close(evaluate(Metric::Itae, &t, &e, &[]), tau * tau, 1e-6);
}

#[test]
fn settling_from_a_window_start_and_never_settling() {
    // A step applied at t = 1: measured from the window start.
    let (t, y) = sampled(|t| if t < 1.0 { 0.0 } else { 1.0 - (-(t - 1.0)).exp() }, 12.0, 120_000);
    close(evaluate(Metric::SettlingTime, &t, &y, &[1.0, 0.05, 1.0]), 20f64.ln(), 1e-6);
    let (t, y) = sampled(|t| t, 1.0, 10);
    assert_eq!(evaluate(Metric::SettlingTime, &t, &y, &[5.0, 0.02]), f64::INFINITY);
    assert_eq!(evaluate(Metric::RiseTime, &t, &y, &[5.0]), f64::INFINITY);
}

#[test]
fn underdamped_overshoot() {
    let (zeta, wn): (f64, f64) = (0.5, 2.0);
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let phi = (1.0 - zeta * zeta).sqrt().atan2(zeta);
    let step = |t: f64| 1.0 - (-zeta * wn * t).exp() / (1.0 - zeta * zeta).sqrt() * (wd * t + phi).sin();
    let (t, y) = sampled(step, 10.0, 100_000);
    let expected = 100.0 * (-PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
    close(evaluate(Metric::Overshoot, &t, &y, &[1.0]), expected, 1e-4);
    // A falling step overshoots downward.
    let down: Vec<f64> = y.iter().map(|v| 1.0 - v).collect();
    close(evaluate(Metric::Overshoot, &t, &down, &[0.0]), expected, 1e-4);
}

#[test]
fn sine_integrals() {
    let (t, y) = sampled(f64::sin, 2.0 * PI, 200_000);
    close(evaluate(Metric::Iae, &t, &y, &[]), 4.0, 1e-8);
    close(evaluate(Metric::Ise, &t, &y, &[]), PI, 1e-8);
    close(evaluate(Metric::Rms, &t, &y, &[]), 0.5f64.sqrt(), 1e-9);
    close(evaluate(Metric::Mean, &t, &y, &[0.0, PI]), 2.0 / PI, 1e-9);
    // ∫₀^π t·sin t dt = π.
    close(evaluate(Metric::Itae, &t, &y, &[0.0, PI]), PI, 1e-8);
    close(evaluate(Metric::Max, &t, &y, &[]), 1.0, 1e-9);
    close(evaluate(Metric::Min, &t, &y, &[]), -1.0, 1e-9);
    close(evaluate(Metric::MaxAbs, &t, &y, &[PI, 2.0 * PI]), 1.0, 1e-9);
}

#[test]
fn windows_interpolate_their_edges() {
    let (t, y) = (vec![0.0, 1.0, 2.0], vec![0.0, 1.0, -1.0]);
    assert_eq!(evaluate(Metric::Max, &t, &y, &[0.25, 0.75]), 0.75);
    assert_eq!(evaluate(Metric::Min, &t, &y, &[0.25, 1.5]), 0.0);
    assert_eq!(evaluate(Metric::FinalValue, &t, &y, &[0.0, 1.5]), 0.0);
    assert_eq!(evaluate(Metric::Mean, &t, &y, &[0.0, 1.0]), 0.5);
    // |y| on [1, 2] is two triangles of height 1 and 1 around t = 1.5.
    assert_eq!(evaluate(Metric::Iae, &t, &y, &[1.0, 2.0]), 0.5);
    assert!(evaluate(Metric::Max, &t, &y, &[3.0, 2.0]).is_nan(), "empty window");
}
