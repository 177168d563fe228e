use super::*;

/// Response of 1/(m s² + b s + k) to the smooth input u(t) = 1 − cos 3t
/// (u and u' vanish at 0, so zero initial history is consistent), at `at`,
/// by the discrete difference equation with period t.
fn discrete_response(m: f64, b: f64, k: f64, t: f64, bilinear: bool, at: f64) -> f64 {
    let (num, den) = discrete_impedance(m, b, k, t, bilinear);
    let steps = (at / t).round() as usize;
    let u = |n: usize| if n < 2 { 0.0 } else { 1.0 - (3.0 * (n - 2) as f64 * t).cos() };
    let mut y = vec![0.0; steps + 3];
    for n in 2..steps + 3 {
        // den·y = num·u in descending powers of z, i.e. delays 0, 1, 2.
        y[n] = (num[0] * u(n) + num[1] * u(n - 1) + num[2] * u(n - 2) - den[1] * y[n - 1] - den[2] * y[n - 2]) / den[0];
    }
    y[steps + 2]
}

/// The continuous response, by RK4 at a step 100 times finer than any
/// period tested.
fn continuous_response(m: f64, b: f64, k: f64, at: f64) -> f64 {
    struct Sys(f64, f64, f64);
    impl ctlgraph_solver::OdeSystem for Sys {
        fn derivatives(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
            dx[0] = x[1];
            dx[1] = (1.0 - (3.0 * t).cos() - self.1 * x[1] - self.2 * x[0]) / self.0;
        }
    }
    let h = 1e-6;
    let mut integ = ctlgraph_solver::Integrator::new(ctlgraph_solver::Method::Rk4 { step: h }, 2);
    let (mut t, mut x) = (0.0, [0.0, 0.0]);
    for n in 1..=(at / h).round() as usize {
        t = integ.advance(&mut Sys(m, b, k), t, n as f64 * h, &mut x).unwrap();
    }
    x[0]
}

#[test]
fn discrete_impedance_converges_to_the_continuous_one() {
    let (m, b, k) = (0.5, 0.5, 2.0);
    let exact = continuous_response(m, b, k, 1.0);
    for bilinear in [true, false] {
        let err = |t: f64| (discrete_response(m, b, k, t, bilinear, 1.0) - exact).abs();
        let (e1, e2) = (err(4e-3), err(2e-3));
        let order = (e1 / e2).log2();
        let expected = if bilinear { 2.0 } else { 1.0 };
        assert!((order - expected).abs() < 0.2, "bilinear = {bilinear}: order {order} ({e1}, {e2})");
    }
    // Both forms keep the DC gain 1/k for any period.
    for bilinear in [true, false] {
        let (num, den) = discrete_impedance(m, b, k, 0.05, bilinear);
        assert!((num.iter().sum::<f64>() / den.iter().sum::<f64>() - 1.0 / k).abs() < 1e-12);
    }
}

#[test]
fn normal_force_by_hand() {
    // Climbing a 20° slope at N = 50, μ = 0.2: fz = N(cos θ − μ sin θ),
    // fx = N(sin θ + μ cos θ).
    let (n, mu, th) = (50.0, 0.2, 20f64.to_radians());
    let (fz, fx) = (n * (th.cos() - mu * th.sin()), n * (th.sin() + mu * th.cos()));
    assert!((normal_force(fx, fz, true, mu, mu) - n).abs() < 1e-12);
    // Descending: fz = N(cos θ + μ sin θ), fx = N(μ cos θ − sin θ).
    let (fz, fx) = (n * (th.cos() + mu * th.sin()), n * (mu * th.cos() - th.sin()));
    assert!((normal_force(fx, fz, false, mu, mu) - n).abs() < 1e-12);
    // Frictionless: the magnitude of the measured force.
    let (fx, fz): (f64, f64) = (12.0, 35.0);
    assert!((normal_force(fx, fz, true, 0.0, 0.0) - fx.hypot(fz)).abs() < 1e-12);
    assert!((normal_force(-fx, fz, false, 0.0, 0.0) - fx.hypot(fz)).abs() < 1e-12);
    assert_eq!(normal_force(3.0, 0.0, true, 0.2, 0.2), 0.0);
}

fn flat_contact(stiffness: f64, mu: f64) -> Contact {
    let scope: Vec<(String, f64)> = Vec::new();
    let vs = VarScope { vars: &["x"], params: &scope };
    let expr = Expr::parse("0.1*x", &vs).unwrap();
    Contact::new(Profile::Expr { expr, step: 1e-6 }, stiffness, 0.0, mu)
}

#[test]
fn contact_is_zero_when_apart_and_linear_in_penetration() {
    let c = flat_contact(100.0, 0.0);
    assert_eq!(c.forces(10.0, 1.5, 1.0, 0.0).2, 0.0, "above the surface z = 1");
    let norm = (1.0f64 + 0.01).sqrt();
    let (_, _, n1, slope) = c.forces(10.0, 0.9, 0.0, 0.0);
    let (_, _, n2, _) = c.forces(10.0, 0.8, 0.0, 0.0);
    assert!((slope - 0.1).abs() < 1e-8);
    assert!((n1 - 100.0 * 0.1 / norm).abs() < 1e-9 && (n2 - 2.0 * n1).abs() < 1e-9);
}

#[test]
fn friction_opposes_the_motion_and_normal_force_recovers_n() {
    let c = flat_contact(100.0, 0.2);
    for vx in [1.0, -1.0] {
        let (fx, fz, n, slope) = c.forces(10.0, 0.9, vx, 0.0);
        // fx is the force against +x: moving +x it resists (positive part
        // from friction); moving −x friction pushes +x.
        let (_, _, _, _) = (fx, fz, n, slope);
        let frictionless = flat_contact(100.0, 0.0).forces(10.0, 0.9, vx, 0.0).0;
        assert!((fx - frictionless) * vx > 0.0, "friction against the motion, vx = {vx}");
        let climbing = vx > 0.0;
        assert!((normal_force(fx, fz, climbing, 0.2, 0.2) - n).abs() < 1e-9, "vx = {vx}");
    }
}
