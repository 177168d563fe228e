//! The C forms of blocks with memory against their Rust forms, bit for
//! bit on random inputs: delays, holds, discrete transfer functions, the
//! rate limiter and the relay, and the control laws (PID with each
//! anti-windup mode, limits and tuned gains; the sliding-mode laws).

use crate::{H, bit_for_bit, bit_for_bit_on, graph, hitting, list, rows};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig { cases: 4, ..ProptestConfig::default() })]

    #[test]
    fn delays_of_one_and_more_samples(samples in 1usize..6, width in 1usize..4, initial in -1.0..1.0f64, seed in any::<u64>()) {
        let yaml = graph(&[width], &format!("type: delay, samples: {samples}, initial: {initial:e}, sample_time: {H}"), &[""], &[""], 100);
        bit_for_bit(&yaml, width, seed, 100, 1.0)?;
        let yaml = graph(&[width], &format!("type: unit_delay, initial: {initial:e}, sample_time: {H}"), &[""], &[""], 100);
        bit_for_bit(&yaml, width, seed, 100, 1.0)?;
    }

    /// A hold at a slower rate read by a block at the base rate: held between its samples.
    #[test]
    fn a_slower_hold_holds(every in 2usize..5, seed in any::<u64>()) {
        let yaml = format!(
            "simulation: {{ stop: 1.99, solver: {{ method: rk4, step: {H} }} }}\nblocks:\n  u: {{ type: inport }}\n  \
             zoh: {{ type: zero_order_hold, sample_time: {} }}\n  s: {{ type: sum, signs: '+-', sample_time: {H} }}\n  y: {{ type: outport }}\n\
             wires:\n  - u -> zoh, s.u2\n  - zoh -> s.u1\n  - s -> y\n",
            every as f64 * H
        );
        bit_for_bit(&yaml, 1, seed, 200, 1.0)?;
    }

    #[test]
    fn discrete_transfer_functions(poles in prop::collection::vec(-0.95..0.95f64, 1..4), num in prop::collection::vec(-2.0..2.0f64, 4), proper in any::<bool>(), seed in any::<u64>()) {
        // den from real poles inside the unit circle; num of the same degree (feedthrough) or one less.
        let mut den = vec![1.0];
        for p in &poles {
            let mut next = vec![0.0; den.len() + 1];
            for (i, d) in den.iter().enumerate() {
                next[i] += d;
                next[i + 1] -= p * d;
            }
            den = next;
        }
        let num = if proper { &num[..den.len()] } else { &num[..den.len() - 1] };
        let block = format!("type: discrete_transfer_function, num: {}, den: {}, sample_time: {H}", list(num), list(&den));
        bit_for_bit(&graph(&[1], &block, &[""], &[""], 200), 1, seed, 200, 1.0)?;
    }

    #[test]
    fn rate_limiter_and_relay(rising in 0.5..50.0f64, falling in -50.0..-0.5f64, on in -0.5..1.0f64, band in 0.0..1.0f64, start_on in any::<bool>(), seed in any::<u64>()) {
        let block = format!("type: rate_limiter, rising: {rising:e}, falling: {falling:e}, initial: 0.3, sample_time: {H}");
        bit_for_bit(&graph(&[2], &block, &[""], &[""], 200), 2, seed, 200, 1.0)?;
        let initial = if start_on { "on" } else { "off" };
        let off = on - band;
        let block = format!("type: relay, on_threshold: {on:e}, off_threshold: {off:e}, on_value: 2.5, off_value: -1, initial: {initial}, sample_time: {H}");
        bit_for_bit_on(&graph(&[1], &block, &[""], &[""], 300), &hitting(rows(seed, 300, 1, 1.0), &[on, off], seed))?;
    }

    /// Every anti-windup mode, limited and not, in each case.
    #[test]
    fn pid_with_limits_each_anti_windup_and_tuned_gains(kp in 0.0..5.0f64, ki in 0.0..50.0f64, kd in 0.0..0.5f64, n in 5.0..500.0f64, limit in 0.2..3.0f64, tuned in 0usize..3, seed in any::<u64>()) {
        let (gains, ports, widths): (&str, Vec<&str>, Vec<usize>) = match tuned {
            0 => ("", vec![".e"], vec![1]),
            1 => (", gain_inputs: [ki]", vec![".e", ".ki"], vec![1, 1]),
            _ => (", gain_inputs: [kp, ki, kd]", vec![".e", ".kp", ".ki", ".kd"], vec![1, 1, 1, 1]),
        };
        for mode in ["clamping", "back_calculation", "none"] {
            for limits in [format!(", lower: {:e}, upper: {limit:e}", -limit), String::new()] {
                let block = format!("type: pid, kp: {kp:e}, ki: {ki:e}, kd: {kd:e}, n: {n:e}, kb: 2, initial: 0.1, anti_windup: {mode}{limits}{gains}, sample_time: {H}");
                let yaml = graph(&widths, &block, &ports, &[""], 300);
                bit_for_bit(&yaml, widths.len(), seed, 300, 2.0)?;
            }
        }
    }

    /// The boundary layer and the sign, with and without u_eq; the
    /// contact-force law limited and not.
    #[test]
    fn sliding_mode_laws(lambda in 1.0..300.0f64, k in 0.0..3.0f64, phi in 0.01..0.5f64, seed in any::<u64>()) {
        for (phi, equivalent) in [(phi, false), (phi, true), (0.0, false), (0.0, true)] {
            let (ports, widths) = if equivalent { (vec![".e", ".de", ".u_eq"], 3) } else { (vec![".e", ".de"], 2) };
            let block = format!("type: smc, lambda: {lambda:e}, k: {k:e}, phi: {phi:e}, equivalent_input: {equivalent}, sample_time: {H}");
            bit_for_bit(&graph(&vec![1; widths], &block, &ports, &[".u", ".s"], 200), widths, seed, 200, 1.0)?;
        }
        for limits in [", lower: -0.5, upper: 0.5", ""] {
            let block = format!("type: sliding_mode, lambda: {lambda:e}, ks: 0.3, rho: 30, je: 1.6e-3, be: 4e-3, d_min: -0.2, d_max: 0.2{limits}, sample_time: {H}");
            let ports = [".xr", ".dxr", ".ddxr", ".x", ".dx"];
            bit_for_bit(&graph(&[1; 5], &block, &ports, &[".u", ".s", ".d_hat"], 300), 5, seed, 300, 1.0)?;
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3, ..ProptestConfig::default() })]

    /// FIR filters and moving averages of several lengths; the quantizer
    /// on inputs at its half steps; friction on inputs through zero.
    #[test]
    fn fir_moving_average_quantizer_and_friction(b in prop::collection::vec(-2.0..2.0f64, 1..6), window in 1usize..6, q in 0.05..1.0f64, seed in any::<u64>()) {
        let block = format!("type: discrete_fir, coefficients: {}, initial: 0.5, sample_time: {H}", list(&b));
        bit_for_bit(&graph(&[1], &block, &[""], &[""], 100), 1, seed, 100, 1.0)?;
        let block = format!("type: moving_average, window: {window}, initial: -0.25, sample_time: {H}");
        bit_for_bit(&graph(&[1], &block, &[""], &[""], 100), 1, seed, 100, 1.0)?;
        let halves: Vec<f64> = (-4..=4).map(|k| (k as f64 + 0.5) * q).collect();
        let block = format!("type: quantizer, interval: {q:e}, sample_time: {H}");
        bit_for_bit_on(&graph(&[2], &block, &[""], &[""], 100), &hitting(rows(seed, 100, 2, 2.0), &halves, seed))?;
        let block = format!("type: coulomb_viscous_friction, offset: {q:e}, gain: 1.5, sample_time: {H}");
        bit_for_bit_on(&graph(&[2], &block, &[""], &[""], 100), &hitting(rows(seed, 100, 2, 1.0), &[0.0, -0.0], seed))?;
    }

    /// Backlash of several widths on a vector, the input walking back and
    /// forth through the dead band.
    #[test]
    fn backlash_holds_and_follows(width in 0.0..1.5f64, initial in -0.5..0.5f64, seed in any::<u64>()) {
        let block = format!("type: backlash, width: {width:e}, initial: {initial:e}, sample_time: {H}");
        bit_for_bit(&graph(&[2], &block, &[""], &[""], 150), 2, seed, 150, 1.0)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2, ..ProptestConfig::default() })]

    /// Each method, with limits and each kind of reset, the reset input
    /// crossing zero exactly.
    #[test]
    fn discrete_integrator_methods_limits_and_resets(gain in -3.0..3.0f64, limit in 0.1..2.0f64, seed in any::<u64>()) {
        for method in ["forward_euler", "backward_euler", "trapezoidal"] {
            for reset in ["none", "rising", "falling", "either", "level"] {
                let block = format!(
                    "type: discrete_integrator, method: {method}, gain: {gain:e}, initial: 0.25, lower: {:e}, upper: {limit:e}, reset: {reset}, sample_time: {H}",
                    -limit
                );
                let (ports, width) = if reset == "none" { (vec![".u"], 1) } else { (vec![".u", ".reset"], 2) };
                let yaml = graph(&vec![1; width], &block, &ports, &[""], 150);
                bit_for_bit_on(&yaml, &hitting(rows(seed, 150, width, 2.0), &[0.0, -0.0], seed))?;
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2, ..ProptestConfig::default() })]

    /// Memory at a sample time is one sample of delay; ground is zero; a
    /// terminator writes nothing.
    #[test]
    fn memory_ground_and_terminator(initial in -1.0..1.0f64, seed in any::<u64>()) {
        let block = format!("type: memory, initial: {initial:e}, sample_time: {H}");
        bit_for_bit(&graph(&[2], &block, &[""], &[""], 100), 2, seed, 100, 1.0)?;
        let yaml = format!(
            "simulation: {{ stop: 0.5, solver: {{ method: rk4, step: {H} }} }}\nblocks:\n  u: {{ type: inport }}\n  g: {{ type: ground }}\n\
             \x20 s: {{ type: sum, signs: '++', sample_time: {H} }}\n  end: {{ type: terminator, sample_time: {H} }}\n  y: {{ type: outport }}\n\
             wires:\n  - u -> s.u1, end\n  - g -> s.u2\n  - s -> y\n"
        );
        bit_for_bit(&yaml, 1, seed, 51, 1.0)?;
    }
}
