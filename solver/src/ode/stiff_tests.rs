//! The implicit method on smooth, stiff and very stiff problems, and the
//! dense output of every method. Reference values were computed once with
//! SciPy 1.x `solve_ivp(method="Radau", rtol=1e-12, atol=1e-12)` (and
//! checked against LSODA to 1e-9) and are recorded here.

use super::tests::{Oscillator, observed_order};
use super::*;

fn trbdf2(rtol: f64, atol: f64, max_step: f64) -> Method {
    Method::Trbdf2 { rtol, atol, max_step, initial_step: None }
}

/// Runs `sys` from `x0` to each time in `ts`, landing on it; returns the
/// states there and the integrator.
fn run_to(sys: &mut dyn OdeSystem, method: Method, x0: &[f64], ts: &[f64]) -> (Vec<Vec<f64>>, Integrator) {
    let mut integ = Integrator::new(method, x0.len());
    let mut x = x0.to_vec();
    let mut t = 0.0;
    let mut out = Vec::new();
    for &target in ts {
        while t < target {
            t = integ.advance(sys, t, target, &mut x).unwrap();
        }
        out.push(x.clone());
    }
    (out, integ)
}

#[test]
fn trbdf2_is_second_order_at_fixed_step() {
    let pinned = |step: f64| Method::Trbdf2 { rtol: 1e9, atol: 1e9, max_step: step, initial_step: Some(step) };
    let order = observed_order(pinned, 40);
    assert!((order - 2.0).abs() < 0.1, "trbdf2 order {order}");
}

#[test]
fn trbdf2_meets_its_tolerance_on_a_smooth_problem() {
    let (xs, integ) = run_to(&mut Oscillator, trbdf2(1e-6, 1e-9, 1.0), &[1.0, 0.0], &[1.0, 2.0, 3.0]);
    let err = (xs[2][0] - 3f64.cos()).abs().max((xs[2][1] + 3f64.sin()).abs());
    assert!(err < 1e-4, "error {err}");
    let s = integ.stats();
    assert!(s.jacobians >= 1 && s.factorizations >= 1, "{s:?}");
}

struct VanDerPol(f64);
impl OdeSystem for VanDerPol {
    fn derivatives(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        dx[1] = self.0 * (1.0 - x[0] * x[0]) * x[1] - x[0];
    }
}

#[test]
fn van_der_pol_mu_1000_matches_a_tight_reference() {
    let ts = [500.0, 1000.0, 1500.0, 2000.0, 3000.0];
    let reference =
        [1.5967689510556762, -1.863646254810875, -1.3547459194977518, 1.7061677321789899, -1.5106069367598454];
    let (xs, integ) = run_to(&mut VanDerPol(1000.0), trbdf2(1e-7, 1e-9, 3000.0), &[2.0, 0.0], &ts);
    for (k, x) in xs.iter().enumerate() {
        assert!((x[0] - reference[k]).abs() < 1e-4, "t = {}: x = {} vs {}", ts[k], x[0], reference[k]);
    }
    // 8 285 steps here; dopri5 at the same tolerances needs 1 690 945.
    let s = integ.stats();
    assert!(s.steps < 20_000, "{s:?}");
}

struct Robertson;
impl OdeSystem for Robertson {
    fn derivatives(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
        let r1 = 0.04 * y[0];
        let r2 = 3e7 * y[1] * y[1];
        let r3 = 1e4 * y[1] * y[2];
        dy[0] = -r1 + r3;
        dy[1] = r1 - r2 - r3;
        dy[2] = r2;
    }
}

#[test]
fn robertson_kinetics_conserves_mass_to_1e5() {
    let ts = [0.4, 40.0, 4e3, 1e5];
    let reference = [
        [0.9851721138609887, 3.386395378974875e-05, 0.014794022185221484],
        [0.7158270687194139, 9.185534764558688e-06, 0.2841637457458208],
        [0.18320225777694943, 8.94237125277748e-07, 0.8167968479859254],
        [0.017865921142322484, 7.274751468528749e-08, 0.9821340061101643],
    ];
    let (ys, integ) = run_to(&mut Robertson, trbdf2(1e-6, 1e-10, 1e5), &[1.0, 0.0, 0.0], &ts);
    for (k, y) in ys.iter().enumerate() {
        let mass = y[0] + y[1] + y[2];
        assert!((mass - 1.0).abs() < 1e-6, "t = {}: y1 + y2 + y3 = {mass}", ts[k]);
        for i in 0..3 {
            let rel = (y[i] - reference[k][i]).abs() / reference[k][i];
            assert!(rel < 2e-4, "t = {}: y{} = {} vs {}", ts[k], i + 1, y[i], reference[k][i]);
        }
    }
    // 513 steps here; dopri5 at the same tolerances needs 286 440 081.
    let s = integ.stats();
    assert!(s.steps < 2000, "{s:?}");
}

#[test]
fn dense_output_reproduces_each_method_inside_a_step() {
    // Over one step of the oscillator, the interpolant at the midpoint is
    // as accurate as the method's own interpolation order allows.
    for (method, tol) in [
        (Method::Rk4 { step: 0.1 }, 1e-6),
        (Method::Heun { step: 0.1 }, 1e-3),
        (Method::DormandPrince { rtol: 1e-9, atol: 1e-12, max_step: 0.1, initial_step: Some(0.1) }, 1e-9),
        (Method::Trbdf2 { rtol: 1e-9, atol: 1e-12, max_step: 0.1, initial_step: Some(0.1) }, 1e-6),
    ] {
        let mut integ = Integrator::new(method, 2);
        let mut x = [1.0, 0.0];
        let t1 = integ.advance(&mut Oscillator, 0.0, 0.1, &mut x).unwrap();
        let mid = 0.5 * t1;
        let mut out = [0.0; 2];
        integ.interpolate(&mut Oscillator, mid, &x, &mut out);
        let err = (out[0] - mid.cos()).abs().max((out[1] + mid.sin()).abs());
        assert!(err < tol, "{}: dense output error {err} at t = {mid}", method.name());
        integ.interpolate(&mut Oscillator, t1, &x, &mut out);
        assert!((out[0] - x[0]).abs() < 1e-14, "{}: the interpolant ends at the step's end", method.name());
    }
}

#[test]
fn trbdf2_counts_its_work_and_restarts_cleanly() {
    // Van der Pol at μ = 1000 from a first step far too long: steps are rejected, Jacobians
    // and LU factorisations are counted.
    let method = Method::Trbdf2 { rtol: 1e-6, atol: 1e-9, max_step: 100.0, initial_step: Some(50.0) };
    let mut integ = Integrator::new(method, 2);
    let mut x = [2.0, 0.0];
    let mut t = 0.0;
    let mut advances = 0;
    while t < 10.0 {
        t = integ.advance(&mut VanDerPol(1000.0), t, 10.0, &mut x).unwrap();
        advances += 1;
    }
    let s = integ.stats();
    assert_eq!(s.steps, advances);
    assert!(s.rejected > 0 && s.jacobians > 0 && s.factorizations > 0, "{s:?}");
    assert!(s.evaluations > 2 * s.steps, "{s:?}");
    // After reset() the run repeats exactly, statistics included.
    integ.reset();
    let (mut y, mut t2) = ([2.0, 0.0], 0.0);
    while t2 < 10.0 {
        t2 = integ.advance(&mut VanDerPol(1000.0), t2, 10.0, &mut y).unwrap();
    }
    assert_eq!((y, integ.stats()), (x, s));
}

#[test]
fn trbdf2_one_linear_step_is_its_stability_function() {
    // x' = λx: the trapezoidal stage gives z = x0·(1 + dhλ)/(1 − dhλ) with d = γ/2, the BDF2
    // stage y = [z − (1 − γ)²·x0] / (γ(2 − γ)(1 − dhλ)). With λ = −50, h = 0.1.
    struct Decay;
    impl OdeSystem for Decay {
        fn derivatives(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
            dx[0] = -50.0 * x[0];
        }
    }
    let gamma = 2.0 - std::f64::consts::SQRT_2;
    let (d, hl) = (gamma / 2.0, -5.0);
    let z = (1.0 + d * hl) / (1.0 - d * hl);
    let y = (z - (1.0 - gamma).powi(2)) / (gamma * (2.0 - gamma) * (1.0 - d * hl));
    let method = Method::Trbdf2 { rtol: 10.0, atol: 10.0, max_step: 0.1, initial_step: Some(0.1) };
    let mut integ = Integrator::new(method, 1);
    let mut x = [1.0];
    assert_eq!(integ.advance(&mut Decay, 0.0, 0.1, &mut x), Ok(0.1));
    assert!((x[0] - y).abs() < 1e-9, "{} vs {y}", x[0]);
}

#[test]
fn trbdf2_blow_up_names_the_component() {
    let err = super::tests::blow_up_error(Method::Trbdf2 { rtol: 1e-3, atol: 1e-6, max_step: 0.5, initial_step: None });
    assert_eq!(err.state(), Some(1), "{err}");
}
