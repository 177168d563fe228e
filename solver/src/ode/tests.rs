use super::*;

/// Harmonic oscillator x'' = -x, x(0) = 1, x'(0) = 0: x = cos t.
pub(super) struct Oscillator;
impl OdeSystem for Oscillator {
    fn derivatives(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        dx[1] = -x[0];
    }
}

/// Global error at t = 2 with `n` equal steps.
fn global_error(method: Method, n: usize) -> f64 {
    let mut integ = Integrator::new(method, 2);
    let mut x = [1.0, 0.0];
    let h = 2.0 / n as f64;
    let mut t = 0.0;
    for k in 1..=n {
        let limit = k as f64 * h;
        t = integ.advance(&mut Oscillator, t, limit, &mut x).unwrap();
        assert_eq!(t, limit);
    }
    ((x[0] - 2f64.cos()).powi(2) + (x[1] + 2f64.sin()).powi(2)).sqrt()
}

/// Observed order from halving the step: log2(e(h) / e(h/2)).
pub(super) fn observed_order(make: impl Fn(f64) -> Method, n: usize) -> f64 {
    let e1 = global_error(make(2.0 / n as f64), n);
    let e2 = global_error(make(1.0 / n as f64), 2 * n);
    (e1 / e2).log2()
}

#[test]
fn fixed_step_methods_converge_at_their_order() {
    let euler = observed_order(|step| Method::Euler { step }, 400);
    let heun = observed_order(|step| Method::Heun { step }, 100);
    let rk4 = observed_order(|step| Method::Rk4 { step }, 20);
    assert!((euler - 1.0).abs() < 0.05, "euler order {euler}");
    assert!((heun - 2.0).abs() < 0.05, "heun order {heun}");
    assert!((rk4 - 4.0).abs() < 0.1, "rk4 order {rk4}");
}

#[test]
fn dormand_prince_is_fifth_order_at_fixed_step() {
    // Huge tolerances and a pinned step make every step accepted at size h.
    let pinned = |step: f64| Method::DormandPrince { rtol: 1e9, atol: 1e9, max_step: step, initial_step: Some(step) };
    let order = observed_order(pinned, 10);
    assert!((order - 5.0).abs() < 0.25, "dopri5 order {order}");
}

#[test]
fn dormand_prince_meets_tolerance_and_lands_exactly() {
    let method = Method::DormandPrince { rtol: 1e-8, atol: 1e-10, max_step: 1.0, initial_step: None };
    let mut integ = Integrator::new(method, 2);
    let mut x = [1.0, 0.0];
    let mut t = 0.0;
    // Sample hits at multiples of 0.3, which are not representable exactly.
    let hits: Vec<f64> = (1..=10).map(|k| k as f64 * 0.3).collect();
    for &hit in &hits {
        while t < hit {
            t = integ.advance(&mut Oscillator, t, hit, &mut x).unwrap();
        }
        assert_eq!(t.to_bits(), hit.to_bits(), "landed at {t}, hit {hit}");
        integ.invalidate();
    }
    let err = (x[0] - 3f64.cos()).abs().max((x[1] + 3f64.sin()).abs());
    assert!(err < 1e-7, "error {err}");
    let stats = integ.stats();
    assert!(stats.steps >= 10 && stats.evaluations >= 6 * stats.steps, "{stats:?}");
}

#[test]
fn dormand_prince_rejects_steps_across_a_kink() {
    // x' = 1 for t < 1, then x' = -50 x: a discontinuous right-hand side.
    struct Kink;
    impl OdeSystem for Kink {
        fn derivatives(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
            dx[0] = if t < 1.0 { 1.0 } else { -50.0 * x[0] };
        }
    }
    let method = Method::DormandPrince { rtol: 1e-6, atol: 1e-9, max_step: 0.5, initial_step: None };
    let mut integ = Integrator::new(method, 1);
    let (mut t, mut x) = (0.0, [0.0]);
    while t < 2.0 {
        t = integ.advance(&mut Kink, t, 2.0, &mut x).unwrap();
    }
    let exact = (-50.0f64).exp();
    assert!((x[0] - exact).abs() < 1e-6, "x = {} vs {exact}", x[0]);
    assert!(integ.stats().rejected > 0);
}

#[test]
fn empty_system_jumps_to_the_limit() {
    let mut integ = Integrator::new(Method::Rk4 { step: 0.1 }, 0);
    let t = integ.advance(&mut Oscillator, 0.0, 0.1, &mut []).unwrap();
    assert_eq!(t, 0.1);
    assert_eq!(integ.stats().evaluations, 0);
}

#[test]
fn blow_up_is_reported_not_looped_on() {
    struct Blow;
    impl OdeSystem for Blow {
        fn derivatives(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
            dx[0] = x[0] * x[0];
        }
    }
    let method = Method::DormandPrince { rtol: 1e-6, atol: 1e-9, max_step: 1.0, initial_step: None };
    let mut integ = Integrator::new(method, 1);
    let (mut t, mut x) = (0.0, [1.0]);
    let mut result = Ok(0.0);
    while t < 2.0 && result.is_ok() {
        result = integ.advance(&mut Blow, t, 2.0, &mut x);
        if let Ok(tn) = result {
            t = tn;
        }
    }
    assert!(result.is_err(), "x = 1/(1-t) must blow up near t = 1, got t = {t}");
    assert!(t < 1.001, "t = {t}, x = {:?}, {result:?}", x);
}

#[test]
fn method_step_limits_and_names() {
    let dopri = Method::DormandPrince { rtol: 1e-6, atol: 1e-9, max_step: 0.25, initial_step: None };
    let trbdf2 = Method::Trbdf2 { rtol: 1e-6, atol: 1e-9, max_step: 0.5, initial_step: None };
    assert_eq!((Method::Rk4 { step: 1e-3 }.max_step(), dopri.max_step(), trbdf2.max_step()), (1e-3, 0.25, 0.5));
    // Defaults for a 4 s run: dopri5 200 samples, trbdf2 10, fixed steps their own.
    assert_eq!((dopri.default_max_step(4.0), trbdf2.default_max_step(4.0)), (0.02, 0.4));
    assert_eq!(Method::Euler { step: 0.1 }.default_max_step(4.0), 0.1);
    assert_eq!(dopri.with_max_step(0.125).max_step(), 0.125);
    assert_eq!(Method::Heun { step: 0.1 }.with_max_step(0.125).max_step(), 0.1);
    assert!(dopri.is_adaptive() && trbdf2.is_adaptive() && !Method::Rk4 { step: 1e-3 }.is_adaptive());
    let names = [Method::Euler { step: 0.1 }, Method::Heun { step: 0.1 }, Method::Rk4 { step: 0.1 }, dopri, trbdf2]
        .map(|m| m.name());
    assert_eq!(names, ["euler", "heun", "rk4", "dopri5", "trbdf2"]);
}

#[test]
fn solver_errors_say_what_and_where() {
    let small = SolverError::StepTooSmall { t: 0.5, step: 1e-17, state: Some(2) };
    assert_eq!(
        small.to_string(),
        "step size 1e-17 too small at t = 0.5: the system is too stiff or discontinuous for the tolerances"
    );
    assert_eq!(small.state(), Some(2));
    let blown = SolverError::NonFinite { t: 1.25, state: Some(3) };
    assert_eq!((blown.to_string(), blown.state()), ("state 3 is not finite at t = 1.25".to_string(), Some(3)));
    let unknown = SolverError::NonFinite { t: 1.25, state: None };
    assert_eq!((unknown.to_string(), unknown.state()), ("state is not finite at t = 1.25".to_string(), None));
    let singular = SolverError::Singular { t: 2.0 };
    assert_eq!((singular.to_string(), singular.state()), ("the Newton matrix is singular at t = 2".to_string(), None));
}

/// x' = p·t^(p−1), x(0) = 0: x(1) = 1, the rate depending on t only.
struct Power(i32);
impl OdeSystem for Power {
    fn derivatives(&mut self, t: f64, _x: &[f64], dx: &mut [f64]) {
        dx[0] = self.0 as f64 * t.powi(self.0 - 1);
    }
}

#[test]
fn stage_times_integrate_polynomials_in_t_exactly() {
    // A method of order p is a quadrature exact for t^(p−1) only if its
    // stages are evaluated at the tableau's times c·h (an autonomous test
    // problem cannot tell wrong c from right ones).
    let pinned = |step: f64| Method::DormandPrince { rtol: 1e9, atol: 1e9, max_step: step, initial_step: Some(step) };
    let trbdf2 = Method::Trbdf2 { rtol: 1e9, atol: 1e9, max_step: 0.25, initial_step: Some(0.25) };
    for (method, p) in
        [(Method::Heun { step: 0.25 }, 2), (Method::Rk4 { step: 0.25 }, 4), (pinned(0.25), 5), (trbdf2, 2)]
    {
        let mut integ = Integrator::new(method, 1);
        let (mut t, mut x) = (0.0, [0.0]);
        for k in 1..=4 {
            t = integ.advance(&mut Power(p), t, k as f64 * 0.25, &mut x).unwrap();
        }
        assert!(t == 1.0 && (x[0] - 1.0).abs() < 1e-13, "{} on t^{}: x(1) = {}", method.name(), p - 1, x[0]);
    }
}

#[test]
fn a_step_lands_on_the_limit_rather_than_leave_a_sliver() {
    let trial = |h: f64| {
        let mut h = h;
        let (lands, end) = trial_step(1.0, 2.0, &mut h, None).unwrap();
        (lands, end, h)
    };
    // Within 1 % of the span (0.995: 0.005 left over < 1 % of h) it stretches to land.
    assert_eq!(trial(0.995), (true, 2.0, 1.0));
    assert_eq!(trial(1.5), (true, 2.0, 1.0));
    // 0.98 leaves 0.02, more than 1 % of the step: taken as is.
    assert_eq!(trial(0.98), (false, 1.98, 0.98));
    let mut tiny = 1e-300;
    assert!(matches!(trial_step(1.0, 2.0, &mut tiny, Some(3)), Err(SolverError::StepTooSmall { state: Some(3), .. })));
}

/// x1' = −x1 + t, x2' = −3·x2: linear, and depending on t.
struct Mixed;
impl OdeSystem for Mixed {
    fn derivatives(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        dx[0] = -x[0] + t;
        dx[1] = -3.0 * x[1];
    }
}

/// x' = t·x.
struct Growth;
impl OdeSystem for Growth {
    fn derivatives(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        dx[0] = t * x[0];
    }
}

fn dopri(rtol: f64, atol: f64, max_step: f64, initial_step: Option<f64>) -> Method {
    Method::DormandPrince { rtol, atol, max_step, initial_step }
}

#[test]
fn starting_step_and_one_dopri5_step_match_scipy() {
    // SciPy 1.17.1: select_initial_step(f, 1, [1, 2], inf, inf, f(1, [1, 2]), 1, 4, 1e-3, 1e-6).
    let mut integ = Integrator::new(dopri(1e-3, 1e-6, f64::INFINITY, None), 2);
    let x = [1.0, 2.0];
    Mixed.derivatives(1.0, &x, &mut integ.k[0]);
    let h = integ.initial_step(&mut Mixed, 1.0, &x, 1e-3, 1e-6, f64::INFINITY);
    assert!((h - 0.06898673034921078).abs() < 1e-15, "{h}");
    // SciPy's RK45 (the same tableau, fifth order propagated): one step of 0.1 of x' = t·x from x(1) = 1.
    let mut integ = Integrator::new(dopri(1e-3, 1e-6, 0.1, Some(0.1)), 1);
    let mut x = [1.0];
    assert_eq!(integ.advance(&mut Growth, 1.0, 1.1, &mut x), Ok(1.1));
    assert!((x[0] - 1.11071061065378).abs() < 1e-14, "{}", x[0]);
    assert_eq!((integ.stats().steps, integ.stats().rejected), (1, 0));
}

#[test]
fn hermite_dense_output_and_its_extra_evaluation() {
    // One RK4 step of x' = t from x(1) = 0 to t = 2 (exact: x = (t² − 1)/2). The cubic
    // Hermite interpolant through x0 = 0, x1 = 1.5, f0 = 1, f1 = 2 is exact for it:
    // at t = 1.5, 0.125·1 + 0.5·1.5 − 0.125·2 = 0.625.
    struct Ramp;
    impl OdeSystem for Ramp {
        fn derivatives(&mut self, t: f64, _x: &[f64], dx: &mut [f64]) {
            dx[0] = t;
        }
    }
    let mut integ = Integrator::new(Method::Rk4 { step: 1.0 }, 1);
    let mut x = [0.0];
    integ.advance(&mut Ramp, 1.0, 2.0, &mut x).unwrap();
    assert_eq!(x[0], 1.5);
    let before = integ.stats().evaluations;
    let mut out = [0.0];
    integ.interpolate(&mut Ramp, 1.5, &x, &mut out);
    assert!((out[0] - 0.625).abs() < 1e-15, "{}", out[0]);
    assert_eq!(integ.stats().evaluations, before + 1);
    integ.interpolate(&mut Ramp, 1.25, &x, &mut out);
    assert!((out[0] - (1.25f64 * 1.25 - 1.0) / 2.0).abs() < 1e-15, "{}", out[0]);
    assert_eq!(integ.stats().evaluations, before + 1);
    assert_eq!(integ.stats().steps, 1);
}

#[test]
fn restart_and_invalidation() {
    let mut integ = Integrator::new(dopri(1e-6, 1e-9, 0.1, None), 2);
    let mut x = [1.0, 2.0];
    let mut t = 0.0;
    for _ in 0..3 {
        t = integ.advance(&mut Mixed, t, 1.0, &mut x).unwrap();
    }
    assert_eq!(integ.stats().steps, 3);
    // First-same-as-last: a step after an accepted one reuses its last derivative (6 new
    // evaluations); after invalidate() the start is evaluated again (7).
    let e = integ.stats().evaluations;
    t = integ.advance(&mut Mixed, t, 1.0, &mut x).unwrap();
    let plain = integ.stats().evaluations - e;
    integ.invalidate();
    let e = integ.stats().evaluations;
    integ.advance(&mut Mixed, t, 1.0, &mut x).unwrap();
    assert_eq!((plain, integ.stats().evaluations - e), (6, 7));
    integ.reset();
    assert_eq!(integ.stats(), Stats::default());
    // After reset the starting step is chosen again: the same first step as a new integrator.
    let (mut a, mut b) = ([1.0, 2.0], [1.0, 2.0]);
    let ta = integ.advance(&mut Mixed, 0.0, 1.0, &mut a).unwrap();
    let tb = Integrator::new(dopri(1e-6, 1e-9, 0.1, None), 2).advance(&mut Mixed, 0.0, 1.0, &mut b).unwrap();
    assert_eq!((ta, a), (tb, b));
}

#[test]
fn error_norm_and_the_component_to_blame() {
    // Errors (1e-3, 5e-3, 2e-3) on a scale of atol + rtol·max(|a|, |b|) = 1e-3 + 0 each:
    // scaled (1, 5, 2): RMS √(30/3) = √10, worst component 1.
    let zero = [0.0; 3];
    let (rms, worst) = scaled_rms([1e-3, 5e-3, 2e-3].into_iter(), &zero, &zero, 1.0, 1e-3);
    assert!((rms - 10f64.sqrt()).abs() < 1e-12 && worst == 1, "{rms} {worst}");
    // The scale takes the larger of the two states.
    let (rms, _) = scaled_rms([2e-3].into_iter(), &[1.0], &[-3.0], 1e-3, 1e-3);
    assert!((rms - 0.5).abs() < 1e-12, "{rms}");
}

/// x1 stays put, x2' = x2²: x2 = 1/(1 − t) blows up at t = 1. The error `method` stops with.
pub(super) fn blow_up_error(method: Method) -> SolverError {
    struct Blow;
    impl OdeSystem for Blow {
        fn derivatives(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
            dx[0] = 0.0;
            dx[1] = x[1] * x[1];
        }
    }
    let mut integ = Integrator::new(method, 2);
    let mut x = [1.0, 1.0];
    let mut t = 0.0;
    loop {
        match integ.advance(&mut Blow, t, 2.0, &mut x) {
            Ok(t_new) if t_new < 2.0 => t = t_new,
            Ok(_) => panic!("passed the blow-up"),
            Err(e) => return e,
        }
    }
}

#[test]
fn blow_up_names_the_component_and_tiny_steps_are_refused() {
    let err = blow_up_error(dopri(1e-3, 1e-6, 0.5, None));
    assert_eq!(err.state(), Some(1), "{err}");
    // A step that no longer moves t (1 + 6e-17 == 1, while 1 − 6e-17 != 1) is refused,
    // blaming the component given.
    let mut h = 6e-17;
    assert_eq!(
        trial_step(1.0, 2.0, &mut h, Some(3)),
        Err(SolverError::StepTooSmall { t: 1.0, step: 6e-17, state: Some(3) })
    );
}
