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

fn ramp_contact() -> Contact {
    // The surface z = 0.5·x: slope 0.5, |n| = √1.25.
    let expr = Expr::parse("0.5*x", &VarScope { vars: &["x"], params: &[] }).unwrap();
    Contact::new(Profile::Expr { expr, step: 1e-6 }, 1000.0, 10.0, 0.2)
}

#[test]
fn contact_forces_on_a_ramp_by_hand() {
    // Probe at (1, 0.3) moving (2, −1): δ = (0.5 − 0.3)/√1.25, δ' = (0.5·2 + 1)/√1.25,
    // N = k δ + c δ' = 220/√1.25; sliding up the slope (v_t > 0), friction −μN along t.
    // fx = −(N·nx − μN·tx) = 0.7 N/√1.25 = 123.2, fz = N·nz − μN·tz = 0.9 N/√1.25 = 158.4.
    let contact = ramp_contact();
    let (depth, rate, slope) = contact.penetration(1.0, 0.3, 2.0, -1.0);
    let norm = 1.25f64.sqrt();
    assert!((depth - 0.2 / norm).abs() < 1e-9 && (rate - 2.0 / norm).abs() < 1e-9 && (slope - 0.5).abs() < 1e-9);
    let (fx, fz, n, s) = contact.forces(1.0, 0.3, 2.0, -1.0);
    assert!((n - 220.0 / norm).abs() < 1e-6 && (s - 0.5).abs() < 1e-9, "{n} {s}");
    assert!((fx - 123.2).abs() < 1e-6 && (fz - 158.4).abs() < 1e-6, "{fx} {fz}");
    // Sliding down (vx = −2, vz = 0: v_t < 0) turns friction round: δ' = −1/√1.25,
    // N = 190/√1.25, fx = 0.3 N/√1.25, fz = 1.1 N/√1.25.
    let (fx, fz, n, _) = contact.forces(1.0, 0.3, -2.0, 0.0);
    assert!((n - 190.0 / norm).abs() < 1e-6, "{n}");
    assert!((fx - 0.3 * 190.0 / 1.25).abs() < 1e-6 && (fz - 1.1 * 190.0 / 1.25).abs() < 1e-6, "{fx} {fz}");
    // Above the surface, or pulling away faster than the spring pushes: free.
    assert_eq!(contact.forces(1.0, 0.6, 2.0, -1.0), (0.0, 0.0, 0.0, contact.forces(1.0, 0.6, 0.0, 0.0).3));
    // A level surface z = 0.25 pressed straight down at 1 m/s from 5 cm deep:
    // no tangential speed, so no friction; N = 1000·0.05 + 10·1 = 60.
    let expr = Expr::parse("0.25", &VarScope { vars: &["x"], params: &[] }).unwrap();
    let level = Contact::new(Profile::Expr { expr, step: 1e-6 }, 1000.0, 10.0, 0.2);
    let (fx, fz, n, _) = level.forces(1.0, 0.2, 0.0, -1.0);
    assert!(fx == 0.0 && (fz - 60.0).abs() < 1e-12 && (n - 60.0).abs() < 1e-12, "{fx} {fz} {n}");
    // On the surface (δ = 0) and pressing into it: contact begins, no force yet.
    assert_eq!(level.forces(1.0, 0.25, 0.0, -1.0).2, 0.0);
    // (0.45, −1) is just downhill: v_t = (0.45 − 0.5)/√1.25 < 0, friction along +t;
    // N = (200 + 10·1.225)/√1.25, fx = 0.3 N/√1.25 = 50.94, fz = 1.1 N/√1.25 = 186.78.
    let (fx, fz, _, _) = contact.forces(1.0, 0.3, 0.45, -1.0);
    assert!((fx - 50.94).abs() < 1e-6 && (fz - 186.78).abs() < 1e-6, "{fx} {fz}");
    // vx = −50: δ' = −25/√1.25, k δ + c δ' = (200 − 250)/√1.25 < 0.
    assert_eq!(contact.forces(1.0, 0.3, -50.0, 0.0).2, 0.0);
    // Frozen in the pressing mode inside a solver step, N goes negative.
    let (_, _, n, _) = contact.forces_in_mode(1.0, 0.3, -50.0, 0.0, Some(true));
    assert!((n + 50.0 / norm).abs() < 1e-6, "{n}");
}

#[test]
fn the_reference_filter_is_a_second_order_lag() {
    // p'' = ωn²(u − p) − 2ζωn p' = 100·1.5 − 2·0.7·10·3 = 108.
    let f = ReferenceFilter { omega: 10.0, zeta: 0.7, initial: 0.0 };
    assert!((f.accel(2.0, &[0.5, 3.0]) - 108.0).abs() < 1e-12);
}

#[test]
fn the_continuous_impedance_is_its_ode_and_stands_still_when_held() {
    // m x'' + b x' + k x = e: x'' = (3 − 0.5·2 − 4·0.25)/2 = 0.5.
    use ctlgraph_core::block::Port;
    let mut z = Impedance { m: 2.0, b: 0.5, k: 4.0 };
    assert_eq!(z.num_states(), 2);
    let x = [0.25, 2.0];
    let derivatives = |z: &mut Impedance, inputs: &[f64]| {
        let ports: Vec<Port> = (0..inputs.len()).map(|offset| Port { offset, width: 1 }).collect();
        let out = [Port { offset: inputs.len(), width: 1 }];
        let mut signals = inputs.to_vec();
        signals.push(f64::NAN);
        let mut io = Io::new(0.0, false, &x, &mut signals, &ports, &out);
        z.output(&mut io);
        let mut dx = [f64::NAN; 2];
        z.derivatives(&io, &mut dx);
        (signals[inputs.len()], dx)
    };
    assert_eq!(derivatives(&mut z, &[3.0]), (0.25, [2.0, 0.5]));
    assert_eq!(derivatives(&mut z, &[3.0, 0.0]), (0.25, [2.0, 0.5]));
    assert_eq!(derivatives(&mut z, &[3.0, 1.0]), (0.25, [0.0, 0.0]));
}
