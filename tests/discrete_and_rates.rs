//! Discrete blocks' exact sequences, multi-rate hold behaviour and exact
//! landing on sample hits.

mod common;
use common::{max_error, run};

/// Rows whose time is (within 1e-12) a multiple of `period` after `offset`,
/// as (k, row index).
fn hits(t: &[f64], period: f64, offset: f64) -> Vec<(usize, usize)> {
    t.iter()
        .enumerate()
        .filter_map(|(i, &ti)| {
            let k = ((ti - offset) / period).round();
            (k >= 0.0 && (ti - offset - k * period).abs() < 1e-12).then_some((k as usize, i))
        })
        .collect()
}

#[test]
fn unit_delay_and_discrete_tf_give_their_exact_sequences() {
    let yaml = "simulation: { stop: 1.0, solver: { method: rk4, step: 0.01 } }\n\
                blocks:\n  one: { type: constant, value: 1 }\n  c: { type: clock }\n\
                \x20 zoh: { type: zero_order_hold, sample_time: 0.1 }\n\
                \x20 delay: { type: unit_delay, initial: 5, sample_time: 0.1 }\n\
                \x20 dtf: { type: discrete_transfer_function, num: [1], den: [1, -0.5], sample_time: 0.1 }\n\
                wires: [c -> zoh, zoh -> delay, one -> dtf]\nrecord: [zoh, delay, dtf]\n";
    let trace = run(yaml);
    let (zoh, delay, dtf) =
        (trace.column("zoh").unwrap(), trace.column("delay").unwrap(), trace.column("dtf").unwrap());
    let h = hits(trace.t(), 0.1, 0.0);
    assert_eq!(h.len(), 11);
    for &(k, i) in &h {
        let expected_delay = if k == 0 { 5.0 } else { zoh[h[k - 1].1] };
        assert_eq!(delay[i], expected_delay, "delay at k = {k}");
        // 1/(z − 0.5) driven by ones: y(k) = 2(1 − 0.5^k), exact in binary.
        assert_eq!(dtf[i], 2.0 * (1.0 - 0.5f64.powi(k as i32)), "dtf at k = {k}");
    }
}

#[test]
fn discrete_outputs_hold_between_hits_at_several_rates() {
    let yaml = "simulation: { stop: 1.0, solver: { method: rk4, step: 0.01 } }\n\
                blocks:\n  c: { type: clock }\n\
                \x20 fast: { type: zero_order_hold, sample_time: 0.1 }\n\
                \x20 slow: { type: zero_order_hold, sample_time: [0.25, 0.05] }\n\
                wires: [c -> fast, c -> slow]\nrecord: [fast, slow]\n";
    let trace = run(yaml);
    let (fast, slow) = (trace.column("fast").unwrap(), trace.column("slow").unwrap());
    for (i, &t) in trace.t().iter().enumerate() {
        let last_fast = ((t + 1e-9) / 0.1).floor() * 0.1;
        assert!((fast[i] - last_fast).abs() < 1e-12, "fast at t = {t}: {}", fast[i]);
        // Before the first slow hit (t = 0.05) the output is 0.
        let last_slow = if t < 0.05 - 1e-9 { 0.0 } else { ((t - 0.05 + 1e-9) / 0.25).floor() * 0.25 + 0.05 };
        assert!((slow[i] - last_slow).abs() < 1e-12, "slow at t = {t}: {}", slow[i]);
    }
}

#[test]
fn adaptive_solver_lands_exactly_on_every_hit() {
    // Period 0.3 and offset 0.1 are not representable in binary; hits come
    // from offset + k·period, and a major step must sit on each, bit for bit.
    let yaml = "simulation: { stop: 3.0, solver: { method: dopri5, max_step: 0.07 } }\n\
                blocks:\n  s: { type: sine, frequency: 0.7 }\n\
                \x20 plant: { type: transfer_function, num: [1], den: [0.2, 1] }\n\
                \x20 z: { type: zero_order_hold, sample_time: [0.3, 0.1] }\n\
                wires: [s -> plant, plant -> z]\nrecord: [z, plant]\n";
    let trace = run(yaml);
    let t = trace.t();
    for k in 0..10 {
        let hit = 0.1 + k as f64 * 0.3;
        let i = t.iter().position(|&x| x.to_bits() == hit.to_bits());
        let i = i.unwrap_or_else(|| panic!("no major step at {hit}"));
        // The hold samples the plant at exactly that instant.
        assert_eq!(trace.column("z").unwrap()[i], trace.column("plant").unwrap()[i]);
    }
    assert_eq!(*t.last().unwrap(), 3.0);
}

#[test]
fn hits_do_not_drift_over_a_million_ticks() {
    // 1e6 steps at 1 µs: tick counting keeps the last hit at exactly 1e6·1e-6.
    let yaml = "simulation: { stop: 1.0, solver: { method: euler, step: 1.0e-6 } }\n\
                blocks:\n  c: { type: clock }\n  z: { type: zero_order_hold, sample_time: 1.0e-6 }\n\
                wires: [c -> z]\nrecord: { every: 100000, signals: [z] }\n";
    let trace = run(yaml);
    assert_eq!(trace.t().len(), 11, "decimated to every 100000th step plus t = 0");
    assert_eq!(*trace.t().last().unwrap(), 1.0);
    assert!((trace.column("z").unwrap().last().unwrap() - 1.0).abs() < 1e-12);
}

#[test]
fn discrete_pid_matches_a_hand_computed_sequence() {
    // e = 1: u(k) = kp + T·ki·k + kd·N·(e − x_f(k)), backward-Euler filter
    // with N·T = 1 gives a derivative part 2.5·0.5^k.
    let yaml = "simulation: { stop: 1.0, solver: { method: rk4, step: 0.05 } }\n\
                blocks:\n  e: { type: constant, value: 1 }\n\
                \x20 pid: { type: pid, kp: 2, ki: 10, kd: 0.5, n: 10, sample_time: 0.1 }\n\
                wires: [e -> pid]\nrecord: [pid]\n";
    let trace = run(yaml);
    let u = trace.column("pid").unwrap();
    for (k, i) in hits(trace.t(), 0.1, 0.0) {
        let expected = 2.0 + k as f64 + 2.5 * 0.5f64.powi(k as i32);
        assert!((u[i] - expected).abs() < 1e-12, "k = {k}: {} vs {expected}", u[i]);
    }
}

#[test]
fn continuous_pid_matches_its_closed_form() {
    // e = 1: u(t) = kp + ki·t + kd·N·e^{−N t}.
    let yaml = "simulation: { stop: 1.0, solver: { method: rk4, step: 1.0e-3 } }\n\
                blocks:\n  e: { type: constant, value: 1 }\n\
                \x20 pid: { type: pid, kp: 2, ki: 10, kd: 0.5, n: 10 }\n\
                wires: [e -> pid]\nrecord: [pid]\n";
    let trace = run(yaml);
    let err = max_error(&trace, "pid", |t| 2.0 + 10.0 * t + 5.0 * (-10.0 * t).exp());
    assert!(err < 1e-9, "max error {err}");
}

fn windup_run(anti_windup: &str) -> ctlgraph::record::Trace {
    let yaml = format!(
        "simulation: {{ stop: 4.0, solver: {{ method: rk4, step: 1.0e-3 }} }}\n\
         blocks:\n  e: {{ type: step, at: 2.0, initial: 1, value: -1 }}\n\
         \x20 pid: {{ type: pid, kp: 0, ki: 1, upper: 0.5, lower: -10, anti_windup: {anti_windup} }}\n\
         wires: [e -> pid]\nrecord: [pid]\n"
    );
    common::run(&yaml)
}

#[test]
fn clamping_anti_windup_recovers_at_once() {
    let trace = windup_run("clamping");
    // Integrator stops at the limit; after e turns negative at t = 2 the
    // output leaves the limit immediately: u = 0.5 − (t − 2). Without
    // zero-crossing detection the fixed-step solver reaches the corner at
    // t = 0.5 within one step (h = 1e-3), hence the O(h) bound.
    let err = max_error(&trace, "pid", |t| {
        if t < 0.5 {
            t
        } else if t <= 2.0 {
            0.5
        } else {
            0.5 - (t - 2.0)
        }
    });
    assert!(err < 1e-3, "max error {err}");
}

#[test]
fn without_anti_windup_the_integrator_winds_up() {
    let trace = windup_run("none");
    // I(2) = 2, so the output stays at 0.5 until I falls to 0.5 at t = 3.5.
    assert_eq!(trace.at("pid", 3.4).unwrap(), 0.5);
    assert!((trace.at("pid", 3.9).unwrap() - 0.1).abs() < 1e-9);
}

#[test]
fn limited_integrator_stops_at_its_limit_and_leaves_it_at_once() {
    // The adaptive solver's error control resolves the corners at the limits.
    let yaml = "simulation: { stop: 2.0, solver: { method: dopri5, rtol: 1.0e-10, atol: 1.0e-12 } }\n\
                blocks:\n  u: { type: step, at: 1.0, initial: 1, value: -1 }\n\
                \x20 i: { type: integrator, upper: 0.5, lower: -0.2 }\n\
                wires: [u -> i]\nrecord: [i]\n";
    let trace = run(yaml);
    let err = max_error(&trace, "i", |t| {
        if t < 0.5 {
            t
        } else if t <= 1.0 {
            0.5
        } else {
            (1.5 - t).max(-0.2)
        }
    });
    assert!(err < 1e-6, "max error {err}");
    let i = trace.column("i").unwrap();
    assert!(i.iter().all(|v| (-0.2..=0.5).contains(v)), "never beyond the limits");
}

#[test]
fn rate_limiter_slews_a_step() {
    let yaml = "simulation: { stop: 1.0, solver: { method: rk4, step: 1.0e-2 } }\n\
                blocks:\n  u: { type: step, at: 0.2 }\n  rl: { type: rate_limiter, rising: 2, falling: -1 }\n\
                wires: [u -> rl]\nrecord: [rl]\n";
    let trace = run(yaml);
    // Like Simulink, the limiter slews from its output at the previous major
    // step (t = 0.19), so the ramp starts one step before the input's jump.
    let err = max_error(&trace, "rl", |t| if t < 0.2 { 0.0 } else { (2.0 * (t - 0.19)).min(1.0) });
    assert!(err < 1e-12, "max error {err}");
}

#[test]
fn pulse_edges_are_events() {
    let yaml = "simulation: { stop: 1.0 }\n\
                blocks:\n  p: { type: pulse, period: 0.3, duty: 0.25, delay: 0.1, amplitude: 2 }\n\
                \x20 i: { type: integrator }\nwires: [p -> i]\nrecord: [p, i]\n";
    let trace = run(yaml);
    // The integral of the pulse is piecewise linear; exact with events.
    let exact = |t: f64| {
        let mut total: f64 = 0.0;
        for k in 0..4 {
            let rise = 0.1 + k as f64 * 0.3;
            total += 2.0 * (t - rise).clamp(0.0, 0.075);
        }
        total
    };
    let err = max_error(&trace, "i", exact);
    assert!(err < 1e-12, "max error {err}");
}

#[test]
fn reset_reruns_identically() {
    use ctlgraph::record::Recorder;
    let model = ctlgraph::compile_file("graphs/tutorial/multirate.yaml".as_ref(), &[]).unwrap();
    let mut sim = ctlgraph_core::Simulator::new(model, None);
    let mut runs: Vec<Vec<f64>> = Vec::new();
    for _ in 0..2 {
        let mut rows = Vec::new();
        let mut recorder = Recorder::new(sim.model());
        sim.run(&mut |t, s| recorder.sample(t, s, &mut |row| rows.extend_from_slice(row))).unwrap();
        runs.push(rows);
        sim.reset();
    }
    assert_eq!(runs[0], runs[1]);
    assert!(runs[0].len() > 2000);
}

#[test]
fn grid_times_read_as_the_grid() {
    // 47 steps of 0.01 are 0.47, not 47·0.01 = 0.47000000000000003; the
    // same for sample hits of a clock.
    let yaml = "simulation: { stop: 1.0, solver: { method: rk4, step: 0.01 } }\n\
                blocks:\n  c: { type: clock }\n  z: { type: zero_order_hold, sample_time: 0.01 }\n\
                wires: [c -> z]\nrecord: [z]\n";
    let trace = run(yaml);
    let t = trace.t();
    assert_eq!(t[47], 0.47);
    assert_eq!(trace.column("z").unwrap()[47], 0.47);
    assert!(t.iter().enumerate().all(|(k, &tk)| tk == k as f64 / 100.0));
}

/// A unit step through an FIR filter: y(k) = b_0 + … + b_k, then Σ b;
/// through a moving average of N: y(k) = (k + 1)/N, then 1 — and both
/// start from their initial inputs (here 0).
#[test]
fn fir_and_moving_average_step_responses() {
    let trace = common::run(
        "simulation: { stop: 0.1, solver: { method: rk4, step: 0.01 } }\nblocks:\n  u: { type: step }\n\
         \x20 f: { type: discrete_fir, coefficients: [0.5, 0.25, -0.125, 2], sample_time: 0.01 }\n\
         \x20 m: { type: moving_average, window: 4, sample_time: 0.01 }\n\
         wires:\n  - u -> f, m\nrecord: [f, m]\n",
    );
    let (f, m) = (trace.column("f").unwrap(), trace.column("m").unwrap());
    let partial = [0.5, 0.75, 0.625, 2.625];
    for k in 0..11 {
        assert_eq!(f[k], partial[k.min(3)], "fir at sample {k}");
        assert_eq!(m[k], ((k + 1).min(4) as f64) / 4.0, "moving average at sample {k}");
    }
}

/// The discrete integrator's three methods on a ramp u = t, K = 2, T =
/// 0.1: forward Euler y(k) = K·T·Σ_{i<k} u(i) = K·T²·k(k−1)/2, backward
/// y(k) = K·T²·k(k+1)/2, trapezoidal the exact K·t²/2; a limit holds y and
/// the state (no wind-up: it leaves the limit as soon as u turns); a
/// rising reset sets the state back to its initial value at that sample.
#[test]
fn discrete_integrator_methods_limits_and_reset() {
    let trace = common::run(
        "simulation: { stop: 1.0, solver: { method: rk4, step: 0.1 } }\nblocks:\n  u: { type: ramp, slope: 1 }\n\
         \x20 f: { type: discrete_integrator, method: forward_euler, gain: 2, sample_time: 0.1 }\n\
         \x20 b: { type: discrete_integrator, method: backward_euler, gain: 2, sample_time: 0.1 }\n\
         \x20 tr: { type: discrete_integrator, method: trapezoidal, gain: 2, sample_time: 0.1 }\n\
         \x20 one: { type: constant, value: 1 }\n  turn: { type: step, at: 0.55, value: -2 }\n  v: { type: sum, signs: '++' }\n\
         \x20 lim: { type: discrete_integrator, upper: 0.35, sample_time: 0.1 }\n\
         \x20 kick: { type: step, at: 0.55 }\n\
         \x20 re: { type: discrete_integrator, initial: 1, reset: rising, sample_time: 0.1 }\n\
         wires:\n  - u -> f, b, tr\n  - one -> v.u1\n  - turn -> v.u2\n  - v -> lim, re.u\n  - kick -> re.reset\n\
         record: [f, b, tr, lim, re]\n",
    );
    // One row per sample k (the steps at 0.55 s add a row between samples).
    let t = trace.t();
    let rows: Vec<usize> =
        (0..=10).map(|k| t.iter().rposition(|&t| (t - 0.1 * k as f64).abs() < 1e-9).unwrap()).collect();
    let col = |c: &str| rows.iter().map(|&i| trace.column(c).unwrap()[i]).collect::<Vec<f64>>();
    let (f, b, tr, lim, re) = (col("f"), col("b"), col("tr"), col("lim"), col("re"));
    for k in 0..=10 {
        let k_ = k as f64;
        assert!((f[k] - 0.02 * k_ * (k_ - 1.0) / 2.0).abs() < 1e-12, "forward at {k}: {}", f[k]);
        assert!((b[k] - 0.02 * k_ * (k_ + 1.0) / 2.0).abs() < 1e-12, "backward at {k}: {}", b[k]);
        assert!((tr[k] - (0.1 * k_).powi(2)).abs() < 1e-12, "trapezoidal at {k}: {}", tr[k]);
    }
    // u = 1 until 0.55, then -1: 0, 0.1, 0.2, 0.3, 0.35 (held), 0.35, then down at once.
    let want = [0.0, 0.1, 0.2, 0.3, 0.35, 0.35, 0.35, 0.25, 0.15, 0.05, -0.05];
    for (k, w) in want.iter().enumerate() {
        assert!((lim[k] - w).abs() < 1e-12, "limited at {k}: {} vs {w}", lim[k]);
    }
    // From 1, +0.1 a sample; the kick's rising edge at 0.6 sets it back to 1, then down by 0.1.
    let want = [1.0, 1.1, 1.2, 1.3, 1.4, 1.5, 1.0, 0.9, 0.8, 0.7, 0.6];
    for (k, w) in want.iter().enumerate() {
        assert!((re[k] - w).abs() < 1e-12, "reset at {k}: {} vs {w}", re[k]);
    }
}

/// Memory: the input of the previous major step, whatever the steps (the
/// adaptive solver's, cut at a pulse's edges), `initial` at the first;
/// ground gives zeros and a terminator ends a signal.
#[test]
fn memory_holds_the_previous_major_steps_input() {
    let trace = common::run(
        "simulation: { stop: 1.0, solver: { method: dopri5, max_step: 0.03 } }\nblocks:\n  u: { type: sine, frequency: 1.3 }\n\
         \x20 p: { type: pulse, period: 0.3, duty: 0.5, delay: 0.05 }\n  s: { type: sum, signs: '++' }\n\
         \x20 m: { type: memory, initial: 7 }\n  g: { type: ground, width: 2 }\n  end: { type: terminator }\n\
         wires:\n  - u -> s.u1\n  - p -> s.u2\n  - s -> m\n  - g -> end\nrecord: [s, m, g]\n",
    );
    let (s, m) = (trace.column("s").unwrap(), trace.column("m").unwrap());
    assert_eq!(m[0], 7.0);
    for k in 1..s.len() {
        assert_eq!(m[k], s[k - 1], "row {k}");
    }
    assert!(trace.t().len() > 30, "{} rows", trace.t().len());
    assert!(trace.column("g[1]").unwrap().iter().chain(trace.column("g[2]").unwrap()).all(|&v| v == 0.0));
}

/// A constant estimated from noisy samples (A = 1, C = 1, Q = 0): the
/// Kalman filter is the recursive weighted mean, x̂(k) = (x0/P0 +
/// Σ_{i<=k} y(i)/R)/(1/P0 + (k+1)/R), its innovation y(k) − x̂(k−1).
#[test]
fn kalman_filter_of_a_constant_is_the_weighted_mean() {
    let trace = common::run(
        "simulation: { stop: 2, solver: { method: rk4, step: 0.1 } }\nblocks:\n\
         \x20 y: { type: sine, amplitude: 0.7, frequency: 1.3, bias: 2 }\n\
         \x20 k: { type: kalman_filter, A: 1, C: 1, Q: 0, R: 0.5, P0: 4, x0: 1, sample_time: 0.1 }\n\
         wires: [y -> k.y]\nrecord: [y, xhat: k.xhat, e: k.innovation]\n",
    );
    let (y, xhat, e) = (trace.column("y").unwrap(), trace.column("xhat").unwrap(), trace.column("e").unwrap());
    let (mut weight, mut sum, mut before) = (1.0 / 4.0, 1.0 / 4.0, 1.0);
    for k in 0..=20 {
        weight += 1.0 / 0.5;
        sum += y[k] / 0.5;
        let want = sum / weight;
        assert!((xhat[k] - want).abs() < 1e-14 * want.abs().max(1.0) * 100.0, "x̂ at {k}: {} vs {want}", xhat[k]);
        assert!((e[k] - (y[k] - before)).abs() < 1e-12, "innovation at {k}");
        before = want;
    }
}

/// The stationary gain against SciPy 1.17.1's `solve_discrete_are` for a
/// position-velocity plant (values recorded: P = solve_discrete_are(Aᵀ,
/// Cᵀ, Q, R), K = P Cᵀ (C P Cᵀ + R)⁻¹): from x0 = 0 the first estimate of
/// a unit measurement is K itself; and the time-varying filter's estimate
/// on the same noisy measurements converges to the stationary one's.
#[test]
fn kalman_steady_state_gain_matches_scipy_and_the_time_varying_filter() {
    let plant = "A: [[1, 0.1], [0, 0.95]], C: [[1, 0]], Q: [[1e-4, 0], [0, 1e-2]], R: 0.04, sample_time: 0.1";
    let trace = common::run(&format!(
        "simulation: {{ stop: 300, seed: 7, solver: {{ method: rk4, step: 0.1 }} }}\nblocks:\n\
         \x20 one: {{ type: constant, value: 1 }}\n\
         \x20 n: {{ type: gaussian_noise, variance: 0.04, sample_time: 0.1 }}\n\
         \x20 ss: {{ type: kalman_filter, {plant}, gain: steady_state }}\n\
         \x20 tv: {{ type: kalman_filter, {plant}, P0: [[1, 0], [0, 1]] }}\n\
         \x20 first: {{ type: kalman_filter, {plant}, gain: steady_state }}\n\
         wires: [n -> ss.y, n -> tv.y, one -> first.y]\nrecord: [first: first.xhat, ss: ss.xhat, tv: tv.xhat]\n"
    ));
    let k = [0.24251509343868227, 0.3144541179247563];
    for (i, want) in k.iter().enumerate() {
        let got = trace.column(&format!("first[{}]", i + 1)).unwrap()[0];
        assert!((got - want).abs() < 1e-12, "K[{i}] = {got}, SciPy {want}");
    }
    for i in 1..=2 {
        let (ss, tv) = (trace.column(&format!("ss[{i}]")).unwrap(), trace.column(&format!("tv[{i}]")).unwrap());
        let gap = (ss[ss.len() - 1] - tv[tv.len() - 1]).abs();
        assert!(gap < 1e-9, "x̂[{i}]: time-varying and stationary differ by {gap} after 3000 samples");
        assert!((ss[5] - tv[5]).abs() > 1e-6, "they differ early on, while the gain settles");
    }
}
