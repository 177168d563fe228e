//! Exact values of both PID forms, written out from the equations in the
//! block's documentation (the first steps by hand), and the anti-windup
//! modes at and inside the limits.

use super::*;
use ctlgraph_core::block::Port;

const IN: [Port; 1] = [Port { offset: 0, width: 1 }];
const OUT: [Port; 1] = [Port { offset: 1, width: 1 }];

fn law(anti_windup: AntiWindup, lower: f64, upper: f64) -> PidLaw {
    PidLaw { kp: 2.0, ki: 3.0, kd: 0.5, n: 10.0, lower, upper, anti_windup, gain_ports: [None; 3] }
}

/// The continuous PID's output and state derivatives at error `e`, states
/// `x` = [I, x_f], after a major-step update there.
fn continuous(pid: &mut ContinuousPid, e: f64, x: [f64; 2]) -> (f64, [f64; 2]) {
    let mut signals = [e, 0.0];
    let mut io = Io::new(0.0, false, &x, &mut signals, &IN, &OUT);
    pid.update(&mut io);
    pid.output(&mut io);
    let mut dx = [0.0; 2];
    pid.derivatives(&io, &mut dx);
    (signals[1], dx)
}

#[test]
fn continuous_output_and_derivatives_are_the_parallel_form() {
    // v = kp·e + I + kd·N·(e − x_f) = 2·0.4 + 1.5 + 0.5·10·(0.4 − 0.1) = 3.8;
    // I' = ki·e = 1.2; x_f' = N·(e − x_f) = 3.
    for aw in [AntiWindup::Clamping, AntiWindup::BackCalculation { kb: 7.0 }, AntiWindup::None] {
        let mut pid = ContinuousPid { law: law(aw, -10.0, 10.0), initial: 0.0, holding: false };
        let (u, dx) = continuous(&mut pid, 0.4, [1.5, 0.1]);
        assert!(
            (u - 3.8).abs() < 1e-15 && (dx[0] - 1.2).abs() < 1e-15 && (dx[1] - 3.0).abs() < 1e-15,
            "{aw:?}: {u} {dx:?}"
        );
    }
    assert_eq!(ContinuousPid { law: law(AntiWindup::None, -1.0, 1.0), initial: 0.0, holding: false }.num_states(), 2);
    let mut x0 = [9.0; 2];
    ContinuousPid { law: law(AntiWindup::None, -1.0, 1.0), initial: 0.25, holding: true }.initialize(&mut x0);
    assert_eq!(x0, [0.25, 0.0]);
}

#[test]
fn continuous_anti_windup_at_the_limit() {
    // v = 3.8 above upper = 3: u = 3.
    // Clamping: e > 0 pushes further up, I' = 0; with e < 0 it integrates.
    let mut pid = ContinuousPid { law: law(AntiWindup::Clamping, -10.0, 3.0), initial: 0.0, holding: false };
    let (u, dx) = continuous(&mut pid, 0.4, [1.5, 0.1]);
    assert!(u == 3.0 && dx[0] == 0.0 && (dx[1] - 3.0).abs() < 1e-14 && pid.holding, "{u} {dx:?}");
    // v = 2·(−0.1) + 4 + 5·(−0.1 − 0.1) = 2.8 inside: integrates again, I' = −0.3.
    let (u, dx) = continuous(&mut pid, -0.1, [4.0, 0.1]);
    assert!((u - 2.8).abs() < 1e-15 && (dx[0] + 0.3).abs() < 1e-15 && !pid.holding, "{u} {dx:?}");
    // At the lower limit, pushing down.
    let mut pid = ContinuousPid { law: law(AntiWindup::Clamping, -1.0, 10.0), initial: 0.0, holding: false };
    let (u, dx) = continuous(&mut pid, -0.4, [-1.5, -0.1]);
    assert!((u + 1.0).abs() < 1e-15 && dx[0] == 0.0, "{u} {dx:?}");
    // Back-calculation: I' = ki·e + kb·(u − v) = 1.2 + 7·(3 − 3.8) = −4.4.
    let mut pid =
        ContinuousPid { law: law(AntiWindup::BackCalculation { kb: 7.0 }, -10.0, 3.0), initial: 0.0, holding: false };
    let (u, dx) = continuous(&mut pid, 0.4, [1.5, 0.1]);
    assert!(u == 3.0 && (dx[0] + 4.4).abs() < 1e-12, "{u} {dx:?}");
    // None: the integrator winds up.
    let mut pid = ContinuousPid { law: law(AntiWindup::None, -10.0, 3.0), initial: 0.0, holding: false };
    assert!((continuous(&mut pid, 0.4, [1.5, 0.1]).1[0] - 1.2).abs() < 1e-15);
}

/// Outputs of the discrete PID for the errors `es`, one hit each.
fn discrete(pid: &mut DiscretePid, es: &[f64]) -> Vec<f64> {
    pid.initialize(&mut []);
    es.iter()
        .map(|&e| {
            let mut signals = [e, 0.0];
            let mut io = Io::new(0.0, false, &[], &mut signals, &IN, &OUT);
            pid.output(&mut io);
            pid.update(&mut io);
            signals[1]
        })
        .collect()
}

#[test]
fn discrete_first_steps_by_hand() {
    // T = 0.1, N·T = 1: x_f(k) = (x_f(k−1) + e(k))/2; I(k+1) = I(k) + 0.3·e(k).
    // k = 0: e = 1, x_f = 0.5, u = 2 + 0.25 + 5·0.5 = 4.75;  I → 0.55
    // k = 1: e = 1, x_f = 0.75, u = 2 + 0.55 + 5·0.25 = 3.8;  I → 0.85
    // k = 2: e = −1, x_f = −0.125, u = −2 + 0.85 + 5·(−0.875) = −5.525;  I → 0.55
    let mut pid =
        DiscretePid { law: law(AntiWindup::None, -10.0, 10.0), period: 0.1, initial: 0.25, integral: 0.0, filter: 0.0 };
    let u = discrete(&mut pid, &[1.0, 1.0, -1.0]);
    for (got, want) in u.iter().zip([4.75, 3.8, -5.525]) {
        assert!((got - want).abs() < 1e-14, "{u:?}");
    }
    assert!((pid.integral - 0.55).abs() < 1e-15 && (pid.filter + 0.125).abs() < 1e-15);
}

#[test]
fn discrete_anti_windup_modes() {
    // Same errors, upper = 4: the first output is limited (v = 4.75, u = 4).
    let run = |aw| {
        let mut pid = DiscretePid { law: law(aw, -10.0, 4.0), period: 0.1, initial: 0.25, integral: 0.0, filter: 0.0 };
        let u = discrete(&mut pid, &[1.0, 1.0]);
        (u, pid.integral)
    };
    // Clamping: no integration at k = 0 (e > 0 at the upper limit):
    // k = 1: u = 2 + 0.25 + 1.25 = 3.5, then I = 0.25 + 0.3 = 0.55.
    let (u, i) = run(AntiWindup::Clamping);
    assert!(u[0] == 4.0 && (u[1] - 3.5).abs() < 1e-14 && (i - 0.55).abs() < 1e-15, "{u:?} {i}");
    // Back-calculation kb = 2: I(1) = 0.25 + 0.1·(3 + 2·(4 − 4.75)) = 0.4;
    // k = 1: u = 2 + 0.4 + 1.25 = 3.65.
    let (u, _) = run(AntiWindup::BackCalculation { kb: 2.0 });
    assert!((u[1] - 3.65).abs() < 1e-14, "{u:?}");
    // None: I(1) = 0.55, u = 3.8.
    let (u, _) = run(AntiWindup::None);
    assert!((u[1] - 3.8).abs() < 1e-14, "{u:?}");
}

#[test]
fn the_discrete_linear_model_steps_like_the_block() {
    let mut pid = DiscretePid {
        law: law(AntiWindup::None, f64::NEG_INFINITY, f64::INFINITY),
        period: 0.1,
        initial: 0.0,
        integral: 0.0,
        filter: 0.0,
    };
    let ss = pid.discrete_lti().unwrap();
    let es = [1.0, 0.5, -2.0, 0.25, 3.0];
    let u = discrete(&mut pid, &es);
    let mut z = [0.0, 0.0];
    for (k, &e) in es.iter().enumerate() {
        let y = ss.c[0] * z[0] + ss.c[1] * z[1] + ss.d[0] * e;
        assert!((y - u[k]).abs() < 1e-13, "k = {k}: {y} vs {}", u[k]);
        z = [ss.a[0] * z[0] + ss.a[1] * z[1] + ss.b[0] * e, ss.a[2] * z[0] + ss.a[3] * z[1] + ss.b[1] * e];
    }
    // A gain from a port has no fixed model.
    pid.law.gain_ports = [Some(1), None, None];
    assert!(pid.discrete_lti().is_none());
}

#[test]
fn clamping_is_decided_at_major_steps_not_in_the_solver_stages() {
    // Not holding (no major step has seen the limit): a stage beyond the
    // limit still integrates, I' = ki·e = 1.2, so the right-hand side does
    // not switch inside a step; the next major step decides to hold.
    let mut pid = ContinuousPid { law: law(AntiWindup::Clamping, -10.0, 3.0), initial: 0.0, holding: false };
    let mut signals = [0.4, 0.0];
    let x = [1.5, 0.1];
    let io = Io::new(0.0, false, &x, &mut signals, &IN, &OUT);
    let mut dx = [0.0; 2];
    pid.derivatives(&io, &mut dx);
    assert!((dx[0] - 1.2).abs() < 1e-15, "{dx:?}");
}
