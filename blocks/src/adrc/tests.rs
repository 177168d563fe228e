use super::*;
use ctlgraph_core::block::Port;

#[test]
fn fst_first_steps_by_hand() {
    // r = 1 from rest, δ = 100, h = h0 = 0.01:
    // k = 0: x1 = −1, x2 = 0, d = 1, d0 = 0.01, c = −1, a0 = √801,
    //        a = −(√801 − 1)/2 < −d, so F = −δ·sign(a) = 100:
    //        r1 = 0 + h·0 = 0, r2 = 0 + h·100 = 1.
    // k = 1: x1 = −1, x2 = 1, c = −0.99, a = 1 − (√793 − 1)/2 < −d, F = 100:
    //        r1 = 0 + h·1 = 0.01, r2 = 1 + 1 = 2.
    let mut td = TrackingDifferentiator::new(100.0, 0.01, 0.01, false, 0.0);
    assert_eq!(td.step(1.0), (0.0, 1.0));
    assert_eq!(td.step(1.0), (0.01, 2.0));
    assert_eq!(fst(-1.0, 0.0, 100.0, 0.01, 0.01), 100.0);
    // Inside the linear zone F = −δ·a/d with a = x2 + c/h0.
    let (x1, x2) = (1e-5, 0.0);
    assert!((fst(x1, x2, 100.0, 0.01, 0.01) - (-100.0 * (x1 / 0.01) / 1.0)).abs() < 1e-12);
}

fn track(form_fhan: bool, target: f64) -> (f64, f64, f64) {
    let (h, delta) = (1e-4, 2.0e4);
    let mut td = TrackingDifferentiator::new(delta, 5.0 * h, h, form_fhan, 0.0);
    let mut peak = f64::NEG_INFINITY;
    let mut last = (0.0, 0.0);
    for _ in 0..10_000 {
        last = td.step(target);
        peak = peak.max(last.0);
    }
    (peak, last.0, last.1)
}

#[test]
fn td_reaches_a_constant_reference_without_overshoot() {
    for fhan in [false, true] {
        let (peak, r1, r2) = track(fhan, 1.0);
        assert!(peak <= 1.0 + 1e-9, "fhan = {fhan}: overshoot to {peak}");
        assert!((r1 - 1.0).abs() < 1e-9 && r2.abs() < 1e-6, "fhan = {fhan}: r1 = {r1}, r2 = {r2}");
    }
    // Time-optimal: with |r̈1| <= δ a 1 mm step needs at least 2·sqrt(1/δ).
    let mut td = TrackingDifferentiator::new(2.0e4, 5e-4, 1e-4, false, 0.0);
    let k = (1..).find(|_| (td.step(1.0).0 - 1.0).abs() < 1e-3).unwrap();
    let t = k as f64 * 1e-4;
    assert!(t > 2.0 * (1.0f64 / 2.0e4).sqrt() && t < 0.03, "reached in {t} s");
}

#[test]
fn bandwidth_gains_are_binomial() {
    assert_eq!(bandwidth_gains(2, 10.0), vec![30.0, 300.0, 1000.0]);
    assert_eq!(bandwidth_gains(1, 10.0), vec![20.0, 100.0]);
    assert_eq!(bandwidth_gains(3, 2.0), vec![8.0, 24.0, 32.0, 16.0]);
}

#[test]
fn discrete_leso_estimates_a_constant_disturbance_on_a_double_integrator() {
    // y'' = f + b0·u with f = 3, u = 0.5: y = (f + b0 u) t²/2.
    let (h, b0, f, u) = (1e-4, 2.0, 3.0, 0.5);
    let mut leso = Leso::new(bandwidth_gains(2, 200.0), b0, h, vec![0.0; 3]);
    for k in 0..20_000 {
        let t = k as f64 * h;
        leso.step((f + b0 * u) * t * t / 2.0, u);
    }
    let t = 20_000.0 * h;
    let z = leso.state();
    assert!((z[2] - f).abs() < 1e-3, "f estimate {}", z[2]);
    assert!((z[1] - (f + b0 * u) * t).abs() < 1e-3, "velocity estimate {}", z[1]);
    assert!((z[0] - (f + b0 * u) * t * t / 2.0).abs() < 1e-4, "position estimate {}", z[0]);
}

#[test]
fn fst_outside_the_linear_band_uses_a0_exactly() {
    // |c| > d0 but |a| <= d: F = −δ·a/d with a = x2 + (a0 − d)/2·sign(c),
    // a0 = sqrt(d² + 8δ|c|). Value from an independent transcription of
    // Han's fst (Python, recorded): a constant other than 8 in a0 gives −100.
    let f = fst(-1.0, 13.6, 100.0, 0.01, 0.01);
    assert!((f - (-94.51529845459615)).abs() < 1e-9, "fst = {f}");
    // The same branch and the linear band with d = δ·h0 = 5, not 1 (at d = 1,
    // d·d = d/d and h0·d = h0/d: cargo-mutants found those unasserted). The
    // paper's δ = 1e4, h0 = 5h.
    let f = fst(-0.01, 10.0, 1e4, 5e-4, 5e-4);
    assert!((f - (-4384.471871911696)).abs() < 1e-9, "fst = {f}");
    let f = fst(-0.001, 1.0, 1e4, 5e-4, 1e-4);
    assert!((f - 1599.9999999999995).abs() < 1e-9, "fst = {f}");
}

#[test]
fn discrete_leso_first_steps_by_hand() {
    // Eq. 8 by forward Euler, ω = 200 (β = 600, 1.2e5, 8e6), b0 = 2,
    // h = 1 ms, y = 1 and u = 0.5 from z = 0; values from an independent
    // transcription of eq. 8 (Python, recorded). Every gain shows in them.
    let mut leso = Leso::new(bandwidth_gains(2, 200.0), 2.0, 1e-3, vec![0.0; 3]);
    let expected = [
        [0.6, 120.001, 8000.0],
        [0.9600009999999999, 176.002, 11200.0],
        [1.1600024, 192.00288000000003, 11519.992],
        [1.25600384, 184.32358400000004, 10239.9728],
    ];
    for (k, want) in expected.iter().enumerate() {
        leso.step(1.0, 0.5);
        for (i, (&z, &w)) in leso.state().iter().zip(want).enumerate() {
            assert!((z - w).abs() <= 1e-9 * w.abs().max(1.0), "step {}: z{} = {z}, expected {w}", k + 1, i + 1);
        }
    }
}

#[test]
fn fhan_matches_hans_equation_in_every_zone() {
    // Han (2009) eq. 21 transcribed independently (Python, values recorded):
    // (x1, x2, r, h0) → fhan, covering |y| > d and |y| <= d, |a| > d and |a| <= d.
    let cases = [
        ((-1.0, 0.0, 100.0, 0.01), 100.0),                // |y| > d, saturated
        ((1e-4, 0.02, 100.0, 0.1), -0.4099999999999966),  // |y| <= d, linear in a
        ((-2e-4, 0.003, 1e4, 5e-4), 788.0),               // |y| <= d
        ((-0.01, 5.3566, 1e4, 5e-4), 8999.873463250175),  // |y| > d, |a2| <= d: a1 = √(d(d + 8|y|))
        ((0.01, -5.3566, 1e4, 5e-4), -8999.873463250175), // the same, mirrored
        ((0.5, -3.0, 1e4, 5e-4), -1e4),
        ((0.0, 0.0, 1e4, 5e-4), 0.0), // a = 0: sign(a) = 0 in both terms
    ];
    for ((x1, x2, r, h0), want) in cases {
        let f = fhan(x1, x2, r, h0);
        assert!((f - want).abs() <= 1e-9 * want.abs().max(1.0), "fhan({x1}, {x2}, {r}, {h0}) = {f}, expected {want}");
    }
}

/// Runs `block` as the simulator would at one major step: output, then
/// update, with `inputs` followed by the outputs in one signal vector.
fn major_step(block: &mut dyn Block, inputs: &[f64], widths: (&[usize], &[usize])) -> Vec<f64> {
    let mut offset = 0;
    let mut ports = |ws: &[usize]| -> Vec<Port> {
        ws.iter()
            .map(|&width| {
                offset += width;
                Port { offset: offset - width, width }
            })
            .collect()
    };
    let (ins, outs) = (ports(widths.0), ports(widths.1));
    let mut signals = inputs.to_vec();
    signals.resize(offset, f64::NAN);
    block.output(&mut Io::new(0.0, false, &[], &mut signals, &ins, &outs));
    block.update(&mut Io::new(0.0, false, &[], &mut signals, &ins, &outs));
    signals[inputs.len()..].to_vec()
}

#[test]
fn the_td_and_leso_blocks_output_their_state_then_step() {
    let mut td = TrackingDifferentiator::new(100.0, 0.01, 0.01, false, 0.25);
    td.step(3.0);
    td.initialize(&mut []);
    // From the initial value at rest: outputs (0.25, 0), then the fst step.
    assert_eq!(major_step(&mut td, &[1.0], (&[1], &[1, 1])), [0.25, 0.0]);
    let mut by_hand = TrackingDifferentiator::new(100.0, 0.01, 0.01, false, 0.25);
    let next = by_hand.step(1.0);
    assert_eq!(major_step(&mut td, &[1.0], (&[1], &[1, 1])), [next.0, next.1]);

    let mut leso = Leso::new(bandwidth_gains(2, 200.0), 2.0, 1e-3, vec![0.5, 0.0, 0.0]);
    leso.step(9.0, 9.0);
    assert_eq!(leso.num_states(), 0);
    leso.initialize(&mut []);
    assert_eq!(major_step(&mut leso, &[1.0, 0.5], (&[1, 1], &[3])), [0.5, 0.0, 0.0]);
    let mut by_hand = Leso::new(bandwidth_gains(2, 200.0), 2.0, 1e-3, vec![0.5, 0.0, 0.0]);
    by_hand.step(1.0, 0.5);
    assert_eq!(major_step(&mut leso, &[1.0, 0.5], (&[1, 1], &[3])), by_hand.state());
    assert_eq!(Leso::new(vec![1.0; 3], 1.0, 0.0, vec![0.0; 3]).num_states(), 3);
}

#[test]
fn the_lesos_discrete_model_steps_like_the_observer() {
    // z⁺ = A z + B [y, u] from discrete_lti against Leso::step, orders 1 and 2.
    for order in [1, 2] {
        let n = order + 1;
        let mut leso = Leso::new(bandwidth_gains(order, 150.0), 3.0, 2e-3, vec![0.0; n]);
        let ss = leso.discrete_lti().unwrap();
        assert_eq!((ss.n, ss.m, ss.p), (n, 2, n));
        let mut z = vec![0.0; n];
        for k in 0..6 {
            let (y, u) = (1.0 + 0.3 * k as f64, 0.7 - 0.2 * k as f64);
            leso.step(y, u);
            z = (0..n)
                .map(|i| (0..n).map(|j| ss.a[i * n + j] * z[j]).sum::<f64>() + ss.b[i * 2] * y + ss.b[i * 2 + 1] * u)
                .collect();
            for i in 0..n {
                let out: f64 = (0..n).map(|j| ss.c[i * n + j] * z[j]).sum();
                assert!((out - leso.state()[i]).abs() <= 1e-12 * out.abs().max(1.0), "order {order}, step {k}");
            }
        }
        assert!(ss.d.iter().all(|&d| d == 0.0));
    }
    assert!(Leso::new(vec![1.0; 3], 1.0, 0.0, vec![0.0; 3]).discrete_lti().is_none());
}

#[test]
fn lsef_is_the_papers_control_law_within_its_limits() {
    // Order 2: u = α1 (r1 − z1) + α2 (r2 − z2) − z3/b0 = 4·0.5 + 0.5·2 − 6/2 = 0.
    let mut lsef =
        Lsef { alpha: [4.0, 0.5], alpha_ports: [None, None], b0: 2.0, order: 2, z_port: 2, lower: -1.0, upper: 2.5 };
    assert!(!lsef.updates());
    let u = |lsef: &mut Lsef, inputs: &[f64], widths: &[usize]| major_step(lsef, inputs, (widths, &[1]))[0];
    assert_eq!(u(&mut lsef, &[1.5, 3.0, 1.0, 1.0, 6.0], &[1, 1, 3]), 0.0);
    // 4·1 + 0.5·1 − 1/2 = 4 → the upper limit; −4 − 0.5 − 0.5 = −5 → the lower.
    assert_eq!(u(&mut lsef, &[2.0, 2.0, 1.0, 1.0, 1.0], &[1, 1, 3]), 2.5);
    assert_eq!(u(&mut lsef, &[0.0, 0.0, 1.0, 1.0, 1.0], &[1, 1, 3]), -1.0);
    // A tuned gain from its port replaces α1: 1·1 + 0.5·1 − 0.5 = 1.
    lsef.alpha_ports[0] = Some(3);
    assert_eq!(u(&mut lsef, &[2.0, 2.0, 1.0, 1.0, 1.0, 1.0], &[1, 1, 3, 1]), 1.0);
    // Order 1: u = α1 (r1 − z1) − z2/b0 = 4·0.5 − 1/2 = 1.5.
    let mut lsef =
        Lsef { alpha: [4.0, 0.0], alpha_ports: [None, None], b0: 2.0, order: 1, z_port: 1, lower: -9.0, upper: 9.0 };
    assert_eq!(u(&mut lsef, &[1.5, 1.0, 1.0], &[1, 2]), 1.5);
}

#[test]
fn the_continuous_leso_outputs_its_states_and_their_derivatives() {
    // Eq. 8: z1' = z2 − β1 e, z2' = z3 − β2 e + b0 u, z3' = −β3 e, e = z1 − y.
    let mut leso = Leso::new(vec![3.0, 5.0, 7.0], 2.0, 0.0, vec![0.1, 0.2, 0.3]);
    let mut x0 = [0.0; 3];
    leso.initialize(&mut x0);
    assert_eq!(x0, [0.1, 0.2, 0.3]);
    let (x, ins, outs) = (
        [1.5, -2.0, 4.0],
        [Port { offset: 0, width: 1 }, Port { offset: 1, width: 1 }],
        [Port { offset: 2, width: 3 }],
    );
    let mut signals = [1.0, 0.5, 0.0, 0.0, 0.0];
    let mut io = Io::new(0.0, false, &x, &mut signals, &ins, &outs);
    leso.output(&mut io);
    leso.update(&mut io);
    let mut dz = [0.0; 3];
    leso.derivatives(&io, &mut dz);
    // e = 0.5: dz = (−2 − 1.5, 4 − 2.5 + 1, −3.5).
    assert_eq!(dz, [-3.5, 2.5, -3.5]);
    assert_eq!(signals[2..], x);
}

#[test]
fn fixed_size_leso_steps_as_the_general_loop_does() {
    // Orders 1–3 take the unrolled path; bit for bit the general loop's.
    for order in 1..=3 {
        let n = order + 1;
        let initial: Vec<f64> = (0..n).map(|i| 0.1 * i as f64 - 0.05).collect();
        let mut fixed = Leso::new(bandwidth_gains(order, 150.0), 3.0, 2e-3, initial.clone());
        let mut general = fixed.clone();
        for k in 0..200 {
            let (y, u) = ((0.37 * k as f64).sin(), 0.5 - (0.11 * k as f64).cos());
            fixed.step(y, u);
            general.step_general(y, u);
            assert_eq!(fixed.state(), general.state(), "order {order}, step {k}");
        }
        assert!(fixed.state().iter().any(|&z| z != 0.0));
    }
}
