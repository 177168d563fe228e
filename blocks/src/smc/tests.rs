//! Exact values of the sliding-mode laws, written out from the equations
//! in the blocks' documentation.

use super::*;
use ctlgraph_core::block::Port;

/// Inputs xr, xr', xr'', x, x' at offsets 0–4; outputs u, S, d̂ at 5–7.
const IN: [Port; 5] = [
    Port { offset: 0, width: 1 },
    Port { offset: 1, width: 1 },
    Port { offset: 2, width: 1 },
    Port { offset: 3, width: 1 },
    Port { offset: 4, width: 1 },
];
const OUT: [Port; 3] = [Port { offset: 5, width: 1 }, Port { offset: 6, width: 1 }, Port { offset: 7, width: 1 }];
const INPUTS: [f64; 5] = [1.0, 0.5, 2.0, 0.8, 0.1];

fn block(period: f64, upper: f64) -> SlidingMode {
    SlidingMode {
        lambda: 200.0,
        ks: 0.3,
        rho: 30.0,
        je: 0.002,
        be: 0.004,
        d_min: -1.0,
        d_max: 1.0,
        lower: f64::NEG_INFINITY,
        upper,
        period,
        d_hat: 0.0,
    }
}

#[test]
fn the_papers_law_by_hand() {
    // S = 200·(1 − 0.8) + (0.5 − 0.1) = 40.4;
    // u = 0.002·(200·0.4 + 2) + 0.004·0.1 + d̂ + 0.3·40.4 = 0.164 + 0.0004 + 0.05 + 12.12.
    let b = block(1e-3, f64::INFINITY);
    let (u, s) = b.law(INPUTS, 0.05);
    assert!((s - 40.4).abs() < 1e-12 && (u - 12.3344).abs() < 1e-12, "{u} {s}");
    assert_eq!(block(1e-3, 10.0).law(INPUTS, 0.05).0, 10.0);
    let mut low = block(1e-3, f64::INFINITY);
    low.lower = 20.0;
    assert_eq!(low.law(INPUTS, 0.05).0, 20.0);
}

fn run(b: &mut SlidingMode, x: &[f64]) -> [f64; 3] {
    let mut signals = [0.0; 8];
    signals[..5].copy_from_slice(&INPUTS);
    let mut io = Io::new(0.0, false, x, &mut signals, &IN, &OUT);
    b.output(&mut io);
    b.update(&mut io);
    [signals[5], signals[6], signals[7]]
}

#[test]
fn discrete_adaptation_is_forward_euler_held_in_its_bounds() {
    // d̂(k+1) = d̂(k) + ρ·S·T: 0 + 30·40.4·1e-4 = 0.1212, then 0.2424, …
    let mut b = block(1e-4, f64::INFINITY);
    b.initialize(&mut []);
    let out = run(&mut b, &[]);
    assert!(
        (out[0] - (0.164 + 0.0004 + 12.12)).abs() < 1e-12 && (out[1] - 40.4).abs() < 1e-12 && out[2] == 0.0,
        "{out:?}"
    );
    assert!((b.d_hat - 0.1212).abs() < 1e-15, "{}", b.d_hat);
    let out = run(&mut b, &[]);
    assert!((out[2] - 0.1212).abs() < 1e-15 && (b.d_hat - 0.2424).abs() < 1e-15);
    // The bound d_max = 1 holds.
    for _ in 0..20 {
        run(&mut b, &[]);
    }
    assert_eq!(b.d_hat, 1.0);
    assert_eq!(b.discrete_state().map(|z| z.to_vec()), Some(vec![1.0]));
    assert_eq!(block(0.0, 1.0).discrete_state(), None);
}

#[test]
fn continuous_adaptation_stops_at_the_bounds() {
    let mut b = block(0.0, f64::INFINITY);
    let mut x0 = [5.0];
    b.initialize(&mut x0);
    assert_eq!(x0, [0.0]);
    let derivative_at = |b: &mut SlidingMode, inputs: &[f64; 5], d_hat: f64| {
        let mut signals = [0.0; 8];
        signals[..5].copy_from_slice(inputs);
        let x = [d_hat];
        let io = Io::new(0.0, false, &x, &mut signals, &IN, &OUT);
        let mut dx = [0.0];
        b.derivatives(&io, &mut dx);
        dx[0]
    };
    let derivative = |b: &mut SlidingMode, d_hat: f64| derivative_at(b, &INPUTS, d_hat);
    // d̂' = ρ·S = 1212 inside and at d_min pushing up; 0 at d_max pushing up.
    assert!((derivative(&mut b, 0.5) - 1212.0).abs() < 1e-9);
    assert!((derivative(&mut b, -1.0) - 1212.0).abs() < 1e-9);
    assert_eq!(derivative(&mut b, 1.0), 0.0);
    // With x past the reference, S = 200·(1 − 1.2) + 0.4 = −39.6, ρS = −1188:
    // 0 at d_min, integrating down from d_max.
    let past = [1.0, 0.5, 2.0, 1.2, 0.1];
    assert_eq!(derivative_at(&mut b, &past, -1.0), 0.0);
    assert!((derivative_at(&mut b, &past, 1.0) + 1188.0).abs() < 1e-9);
    assert!((derivative_at(&mut b, &past, 0.0) + 1188.0).abs() < 1e-9);
    // The continuous block reads d̂ from its state, and has one.
    let mut signals = [0.0; 8];
    signals[..5].copy_from_slice(&INPUTS);
    b.output(&mut Io::new(0.0, false, &[0.3], &mut signals, &IN, &OUT));
    assert_eq!(signals[7], 0.3);
    assert_eq!((b.num_states(), block(1e-3, 1.0).num_states()), (1, 0));
    let mut clamped = [1.5];
    assert!(b.clamp_states(&mut clamped) && clamped == [1.0]);
    let mut inside = [0.5];
    assert!(!b.clamp_states(&mut inside) && inside == [0.5]);
    let mut below = [-3.0];
    assert!(b.clamp_states(&mut below) && below == [-1.0]);
}

#[test]
fn first_order_law_with_and_without_boundary_layer() {
    let out = |smc: &mut Smc, e: f64, de: f64, u_eq: f64| {
        let inputs = [Port { offset: 0, width: 1 }, Port { offset: 1, width: 1 }, Port { offset: 2, width: 1 }];
        let outputs = [Port { offset: 3, width: 1 }, Port { offset: 4, width: 1 }];
        let mut signals = [e, de, u_eq, 0.0, 0.0];
        let mut io = Io::new(0.0, false, &[], &mut signals, &inputs, &outputs);
        smc.output(&mut io);
        (signals[3], signals[4])
    };
    // S = 4·0.1 + 0.2 = 0.6; inside φ = 2: u = 3·0.3 = 0.9; with u_eq 1: 1.9.
    let mut smc = Smc { lambda: 4.0, k: 3.0, phi: 2.0, equivalent: true };
    let (u, s) = out(&mut smc, 0.1, 0.2, 1.0);
    assert!((s - 0.6).abs() < 1e-15 && (u - 1.9).abs() < 1e-15, "{u} {s}");
    // Outside the layer: u = u_eq ± k.
    assert!((out(&mut smc, 1.0, 0.0, 1.0).0 - 4.0).abs() < 1e-15);
    assert!((out(&mut smc, -1.0, 0.0, 1.0).0 + 2.0).abs() < 1e-15);
    // φ = 0: k·sign(S); without the port, u_eq = 0.
    let mut sign = Smc { lambda: 4.0, k: 3.0, phi: 0.0, equivalent: false };
    assert_eq!(out(&mut sign, 0.1, 0.2, 7.0).0, 3.0);
    assert_eq!(out(&mut sign, -0.1, 0.2, 7.0).0, -3.0);
    // On the surface, S = 0: no switching (not 0/0).
    assert_eq!(out(&mut sign, 0.0, 0.0, 7.0), (0.0, 0.0));
}
