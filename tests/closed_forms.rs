//! Simulated responses against closed-form solutions. The bounds are tight
//! enough that a wrong or lower-order solver fails them.

mod common;
use common::{max_error, run};

fn first_order(solver: &str) -> String {
    format!(
        "parameters: {{ tau: 0.5 }}\n\
         simulation: {{ stop: 3.0, solver: {solver} }}\n\
         blocks:\n  u: {{ type: step }}\n  plant: {{ type: transfer_function, num: [1], den: [tau, 1] }}\n\
         wires: [u -> plant]\nrecord: [y: plant]\n"
    )
}

#[test]
fn first_order_step_response_rk4() {
    let trace = run(&first_order("{ method: rk4, step: 1.0e-2 }"));
    // RK4's global error at h = 0.01 is ~1e-10; Euler's would be ~4e-3.
    let err = max_error(&trace, "y", |t| 1.0 - (-t / 0.5).exp());
    assert!(err < 1e-9, "max error {err}");
    assert_eq!(trace.t().len(), 301);
}

#[test]
fn first_order_step_response_dopri5() {
    let trace = run(&first_order("{ method: dopri5, rtol: 1.0e-9, atol: 1.0e-12 }"));
    let err = max_error(&trace, "y", |t| 1.0 - (-t / 0.5).exp());
    assert!(err < 1e-8, "max error {err}");
}

#[test]
fn euler_is_visibly_worse_than_rk4() {
    let trace = run(&first_order("{ method: euler, step: 1.0e-2, exact_lti: false }"));
    let err = max_error(&trace, "y", |t| 1.0 - (-t / 0.5).exp());
    assert!(err > 1e-3 && err < 1e-2, "euler error {err}");
}

#[test]
fn an_lti_block_driven_by_a_step_is_exact_whatever_the_fixed_step_method() {
    // Exact ZOH replaces integration: Euler's coarse step is as exact as RK4's.
    for method in ["euler", "rk4"] {
        let trace = run(&first_order(&format!("{{ method: {method}, step: 1.0e-2 }}")));
        let err = max_error(&trace, "y", |t| 1.0 - (-t / 0.5).exp());
        assert!(err < 1e-14, "{method}: error {err}");
    }
}

#[test]
fn second_order_underdamped_step_response() {
    // G = wn²/(s² + 2ζwn s + wn²): y = 1 − e^{−ζwn t}(cos wd t + ζ/√(1−ζ²) sin wd t).
    let (wn, zeta): (f64, f64) = (10.0, 0.2);
    let yaml = format!(
        "simulation: {{ stop: 2.0, solver: {{ method: rk4, step: 1.0e-3 }} }}\n\
         blocks:\n  u: {{ type: step }}\n  \
         plant: {{ type: transfer_function, num: [{n}], den: [1, {d1}, {n}] }}\n\
         wires: [u -> plant]\nrecord: [y: plant]\n",
        n = wn * wn,
        d1 = 2.0 * zeta * wn
    );
    let trace = run(&yaml);
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let exact =
        |t: f64| 1.0 - (-zeta * wn * t).exp() * ((wd * t).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * t).sin());
    let err = max_error(&trace, "y", exact);
    // RK4 at h = 1e-3: ~2e-10; a second-order method would be ~1e-5 off.
    assert!(err < 1e-9, "max error {err}");
    // Overshoot e^{−πζ/√(1−ζ²)} = 52.66 %.
    let peak = trace.column("y").unwrap().iter().cloned().fold(0.0, f64::max);
    let expected = 1.0 + (-std::f64::consts::PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
    assert!((peak - expected).abs() < 1e-5, "peak {peak} vs {expected}");
}

#[test]
fn integrator_of_a_ramp_is_a_parabola() {
    let yaml = "simulation: { stop: 2.0, solver: { method: rk4, step: 0.1 } }\n\
                blocks:\n  r: { type: ramp, slope: 3.0 }\n  i: { type: integrator, initial: 1.0 }\n\
                wires: [r -> i]\nrecord: [i]\n";
    let trace = run(yaml);
    // RK4 integrates polynomials of degree <= 4 exactly.
    let err = max_error(&trace, "i", |t| 1.0 + 1.5 * t * t);
    assert!(err < 1e-12, "max error {err}");
}

#[test]
fn zpk_and_state_space_match_the_transfer_function() {
    let yaml = "simulation: { stop: 1.0, solver: { method: rk4, step: 1.0e-3 } }\n\
                blocks:\n  u: { type: sine, frequency: 2.0 }\n\
                \x20 tf: { type: transfer_function, num: [2, 10], den: [1, 3, 25] }\n\
                \x20 zp: { type: zpk, zeros: [-5], poles: [[-1.5, 4.769696007084728]], gain: 2 }\n\
                \x20 ss: { type: state_space, A: [[0, 1], [-25, -3]], B: [[0], [1]], C: [[10, 2]] }\n\
                wires: [u -> tf, u -> zp, u -> ss]\nrecord: [tf, zp, ss]\n";
    let trace = run(yaml);
    let (tf, zp, ss) = (trace.column("tf").unwrap(), trace.column("zp").unwrap(), trace.column("ss").unwrap());
    for i in 0..tf.len() {
        assert!((tf[i] - zp[i]).abs() < 1e-9 && (tf[i] - ss[i]).abs() < 1e-9, "row {i}");
    }
    assert!(tf.iter().any(|v| v.abs() > 0.1));
}

#[test]
fn pid_loop_settles_without_steady_state_error() {
    let yaml = std::fs::read_to_string("graphs/tutorial/pid_loop.yaml").unwrap();
    let trace = run(&yaml);
    let y = trace.column("y").unwrap();
    assert!((y.last().unwrap() - 1.0).abs() < 1e-3, "integral action removes the error");
    let u = trace.column("u").unwrap();
    assert!(u.iter().all(|v| v.abs() <= 5.0), "output limits hold");
    assert!(u.contains(&5.0), "the limit is reached at the step");
}

#[test]
fn step_switches_exactly_at_its_time() {
    // With dopri5 the step time is an event: a major step lands on it, the
    // value before is 0 and from it on 1.
    let yaml = "simulation: { stop: 1.0 }\nblocks:\n  s: { type: step, at: 0.3 }\n  i: { type: integrator }\n\
                wires: [s -> i]\nrecord: [s, i]\n";
    let trace = run(yaml);
    let k = trace.t().iter().position(|&t| t == 0.3).expect("a major step at exactly 0.3");
    assert_eq!(trace.column("s").unwrap()[k], 1.0);
    assert_eq!(trace.column("s").unwrap()[k - 1], 0.0);
    let err = max_error(&trace, "i", |t| (t - 0.3).max(0.0));
    assert!(err < 1e-12, "integral of the step {err}");
}

/// A pulse train whose edges fall between the grid points (period 37 ms,
/// duty 30 %, grid 10 ms) into a first-order lag: the steps around each
/// edge are shorter than the grid's, the held transfer function is stepped
/// by the exact transition of each length, and y matches the piecewise
/// exponential solution at every sample.
#[test]
fn exact_zoh_follows_a_pulse_train_with_off_grid_edges() {
    let yaml = "simulation: { stop: 1.0, solver: { method: rk4, step: 1.0e-2 } }\n\
                blocks:\n  u: { type: pulse, period: 0.037, duty: 0.3 }\n  \
                plant: { type: transfer_function, num: [1], den: [0.05, 1] }\n\
                wires: [u -> plant]\nrecord: [y: plant]\n";
    let trace = run(yaml);
    assert!(trace.t().len() > 101, "edges add major steps: {}", trace.t().len());
    // Exact: y relaxes towards u with tau = 0.05 between the edges.
    let exact = |t: f64| {
        let (mut y, mut s) = (0.0f64, 0.0f64);
        let mut k = 0.0f64;
        while s < t {
            let (rise, fall) = (k * 0.037, k * 0.037 + 0.3 * 0.037);
            for (start, end, u) in [(rise, fall, 1.0f64), (fall, (k + 1.0) * 0.037, 0.0)] {
                let end = end.min(t);
                if end > s.max(start) {
                    y = u + (y - u) * (-(end - s.max(start)) / 0.05).exp();
                    s = end;
                }
            }
            k += 1.0;
        }
        y
    };
    let err = max_error(&trace, "y", exact);
    assert!(err < 1e-12, "max error {err}");
}

/// Blocks that change only at events (steps, a pulse, a sum of them) are
/// not re-run between events; at and after every edge they still read right.
#[test]
fn event_only_blocks_switch_exactly_at_their_events() {
    let yaml = "simulation: { stop: 1.0, solver: { method: rk4, step: 0.1 } }\n\
                blocks:\n  a: { type: step, at: 0.25 }\n  b: { type: step, at: 0.5, value: 2 }\n  \
                p: { type: pulse, period: 0.3, duty: 0.5, amplitude: 10 }\n  \
                s: { type: sum, signs: \"+++\" }\nwires: [a -> s.u1, b -> s.u2, p -> s.u3]\nrecord: [s]\n";
    let trace = run(yaml);
    let s = trace.column("s").expect("s recorded");
    for (&t, &v) in trace.t().iter().zip(s) {
        // High for the first half of each 0.3 s period (edges at k·0.3 and k·0.3 + 0.15).
        let phase = t - ((t + 1e-12) / 0.3).floor() * 0.3;
        let pulse = if phase < 0.15 - 1e-12 { 10.0 } else { 0.0 };
        let want = f64::from(u8::from(t >= 0.25)) + 2.0 * f64::from(u8::from(t >= 0.5)) + pulse;
        assert!((v - want).abs() < 1e-12, "t = {t}: s = {v}, expected {want}");
    }
    assert!(trace.t().contains(&0.25) && trace.t().contains(&0.15), "events are major steps");
}

/// The quantizer is q·round(u/q) on a ramp (halves away from zero); the
/// Coulomb and viscous friction gain·u + sign(u)·offset on a sine, its
/// jump located at the sine's zero (t = 0.5 s) under an adaptive solver.
#[test]
fn quantizer_and_friction_closed_forms() {
    let trace = common::run(
        "simulation: { stop: 1.0, solver: { method: dopri5, rtol: 1e-9, max_step: 0.01 } }\nblocks:\n  r: { type: ramp, slope: 3, start: 0 }\n\
         \x20 off: { type: constant, value: -1.5 }\n  shifted: { type: sum, signs: '++' }\n\
         \x20 q: { type: quantizer, interval: 0.5 }\n  s: { type: sine, frequency: 1 }\n\
         \x20 fr: { type: coulomb_viscous_friction, offset: 0.2, gain: 2 }\n\
         wires:\n  - r -> shifted.u1\n  - off -> shifted.u2\n  - shifted -> q\n  - s -> fr\nrecord: [shifted, q, s, fr]\n",
    );
    let (u, q) = (trace.column("shifted").unwrap(), trace.column("q").unwrap());
    for (u, q) in u.iter().zip(q) {
        assert_eq!(*q, 0.5 * (u / 0.5).round(), "u = {u}");
    }
    let (t, s, fr) = (trace.t(), trace.column("s").unwrap(), trace.column("fr").unwrap());
    for k in 1..t.len() {
        // A located step ends at the zero, where the new sign is taken: check the steps' values.
        let sign = if s[k] > 0.0 {
            1.0
        } else if s[k] < 0.0 {
            -1.0
        } else {
            0.0
        };
        if (t[k] - 0.5).abs() > 1e-6 {
            assert!(
                (fr[k] - (2.0 * s[k] + sign * 0.2)).abs() < 1e-12,
                "t = {}: {} vs {}",
                t[k],
                fr[k],
                2.0 * s[k] + sign * 0.2
            );
        }
    }
    // (Not the start: sin 0 = 0 gives 0, the first step then +0.2.)
    let jump = t
        .windows(2)
        .zip(fr.windows(2))
        .find(|(t, f)| t[0] > 0.1 && (f[1] - f[0]).abs() > 0.3)
        .map(|(t, _)| t[1])
        .unwrap();
    assert!((jump - 0.5).abs() < 1e-9, "the jump at {jump}");
}

/// The Signal Generator's waves at every row (a jump's own row may show
/// either side), and integrated: with every jump a step boundary, dopri5
/// integrates a square wave to its triangle and a sawtooth to its
/// parabolas at the rounding level.
#[test]
fn signal_generator_waves_and_their_integrals() {
    let trace = run("simulation: { stop: 2.1, solver: { method: dopri5, rtol: 1e-10, atol: 1e-12 } }\nblocks:\n\
         \x20 sq: { type: signal_generator, waveform: square, amplitude: 1.5, frequency: 2 }\n\
         \x20 saw: { type: signal_generator, waveform: sawtooth, amplitude: 2, frequency: 2 }\n\
         \x20 sine: { type: signal_generator, amplitude: 3, frequency: 0.5 }\n\
         \x20 isq: { type: integrator }\n  isaw: { type: integrator }\n\
         wires: [sq -> isq, saw -> isaw]\nrecord: [sq, saw, sine, isq, isaw]\n");
    let frac = |x: f64| x - x.floor();
    let near_jump = |t: f64| (4.0 * t - (4.0 * t).round()).abs() < 1e-9;
    for (i, &t) in trace.t().iter().enumerate() {
        let sine = 3.0 * (std::f64::consts::PI * t).sin();
        assert!((trace.column("sine").unwrap()[i] - sine).abs() < 1e-12, "sine at {t}");
        if near_jump(t) {
            continue;
        }
        let sq = if frac(2.0 * t) < 0.5 { 1.5 } else { -1.5 };
        assert_eq!(trace.column("sq").unwrap()[i], sq, "square at {t}");
        let saw = 4.0 * (2.0 * t - (2.0 * t + 0.5).floor());
        assert!((trace.column("saw").unwrap()[i] - saw).abs() < 1e-12, "sawtooth at {t}");
    }
    // ∫ square: a triangle 0 → 0.375 (at 0.25) → 0 (at 0.5), period 0.5.
    let triangle = |t: f64| {
        let s = frac(2.0 * t) / 2.0;
        if s < 0.25 { 1.5 * s } else { 1.5 * (0.5 - s) }
    };
    assert!(max_error(&trace, "isq", triangle) < 1e-11, "{}", max_error(&trace, "isq", triangle));
    // ∫ sawtooth 4·(2t − n) over its tooth: 4t² − 4nt + const, continuous: F(t) = (saw² − 4)/16 + 1/4.
    let parabola = |t: f64| {
        let saw = 4.0 * (2.0 * t - (2.0 * t + 0.5).floor());
        saw * saw / 16.0
    };
    assert!(max_error(&trace, "isaw", parabola) < 1e-11, "{}", max_error(&trace, "isaw", parabola));
}

/// The chirp y = sin(2π(f0·t + (f1 − f0)·t²/(2T))) at every row, and its
/// phase: 2·(f0·T + (f1 − f0)·T/2) sign changes by the target time.
#[test]
fn chirp_follows_its_phase() {
    let trace = run("simulation: { stop: 4, solver: { method: rk4, step: 1e-4 } }\nblocks:\n\
         \x20 c: { type: chirp, initial_frequency: 1, target_frequency: 5, target_time: 4, amplitude: 2 }\n\
         record: [c]\n");
    let phase = |t: f64| t + 4.0 * t * t / 8.0;
    let want = |t: f64| 2.0 * (2.0 * std::f64::consts::PI * phase(t)).sin();
    assert!(max_error(&trace, "c", want) < 1e-11);
    // Before t = 3.99 (phase 11.95 cycles): the zeros at phase k/2, k = 1..=23.
    let y = trace.column("c").unwrap();
    let n = trace.t().iter().take_while(|&&t| t <= 3.99).count();
    let changes = y[..n].windows(2).filter(|w| w[0] * w[1] < 0.0).count();
    assert_eq!(changes, 23);
}

/// A repeating sequence with a jump: rows on the interpolation, and its
/// integral exact at the rounding level (every corner is a step boundary).
#[test]
fn repeating_sequence_interpolates_and_repeats() {
    let trace = run("simulation: { stop: 7.5, solver: { method: dopri5, rtol: 1e-10, atol: 1e-12 } }\nblocks:\n\
         \x20 s: { type: repeating_sequence, times: [0, 1, 1, 2, 3], values: [0, 2, -1, -1, 0] }\n\
         \x20 i: { type: integrator }\nwires: [s -> i]\nrecord: [s, i]\n");
    let within = |t: f64| t - 3.0 * (t / 3.0).floor();
    let value = |t: f64| {
        let tau = within(t);
        if tau < 1.0 {
            2.0 * tau
        } else if tau < 2.0 {
            -1.0
        } else {
            tau - 3.0
        }
    };
    // ∫ over a period: 1 − 1 − 0.5 = −0.5.
    let integral = |t: f64| {
        let tau = within(t);
        let part = if tau < 1.0 {
            tau * tau
        } else if tau < 2.0 {
            1.0 - (tau - 1.0)
        } else {
            0.5 * (tau - 3.0).powi(2) - 0.5
        };
        -0.5 * (t / 3.0).floor() + part
    };
    for (i, &t) in trace.t().iter().enumerate() {
        if (within(t) - 1.0).abs() < 1e-9 {
            continue;
        }
        assert!((trace.column("s").unwrap()[i] - value(t)).abs() < 1e-12, "s at {t}");
    }
    assert!(max_error(&trace, "i", integral) < 1e-11, "{}", max_error(&trace, "i", integral));
}

/// The play operator on u = 2·sin t with w = 1: engaged upward (y = u − ½)
/// to the peak 1.5, held until u = 1 (t = 5π/6), engaged downward (y =
/// u + ½) to −1.5, held until u = −1 (t = 11π/6), and so on. The
/// engagements are located zero crossings; at a reversal the held value is
/// the input's extreme among major steps, within ½·|ü|·max_step² of it.
#[test]
fn backlash_is_the_play_operator() {
    let trace = run(
        "simulation: { stop: 12, solver: { method: dopri5, rtol: 1e-10, atol: 1e-12, max_step: 1e-3 } }\nblocks:\n\
         \x20 u: { type: sine, amplitude: 2, frequency: 0.15915494309189535 }\n\
         \x20 b: { type: backlash, width: 1 }\nwires: [u -> b]\nrecord: [u, b]\n",
    );
    use std::f64::consts::PI;
    let play = |t: f64| {
        let u = 2.0 * t.sin();
        let phase = t % (2.0 * PI);
        if t < PI / 2.0 {
            (u - 0.5).max(0.0)
        } else if !(PI / 2.0..11.0 * PI / 6.0).contains(&phase) {
            // Rising from the trough: held at −1.5 until engaged.
            (u - 0.5).max(-1.5)
        } else if phase < 5.0 * PI / 6.0 {
            1.5
        } else if phase < 3.0 * PI / 2.0 {
            u + 0.5
        } else {
            -1.5
        }
    };
    let err = max_error(&trace, "b", play);
    assert!(err < 1e-6, "max error {err}");
    let (u, b) = (trace.column("u").unwrap(), trace.column("b").unwrap());
    assert!(u.iter().zip(b).all(|(u, b)| (u - b).abs() <= 0.5 + 1e-12), "the output leaves the dead band");
}

/// A bilinear function is reproduced exactly inside the table, and outside
/// it by linear extrapolation; `clip` holds each input at its end.
#[test]
fn lookup_table_2d_reproduces_a_bilinear_function() {
    let f = |u1: f64, u2: f64| 1.0 + 2.0 * u1 - 3.0 * u2 + 0.5 * u1 * u2;
    let (rows, cols) = ([-1.0, 0.0, 0.5, 2.0], [0.0, 1.0, 3.0]);
    let table: Vec<String> = rows
        .iter()
        .map(|&r| format!("[{}]", cols.iter().map(|&c| f(r, c).to_string()).collect::<Vec<_>>().join(", ")))
        .collect();
    let yaml = format!(
        "simulation: {{ stop: 4, solver: {{ method: rk4, step: 0.01 }} }}\nblocks:\n\
         \x20 a: {{ type: ramp, slope: 1.2, initial: -1.8 }}\n  b: {{ type: sine, amplitude: 2.5, frequency: 0.3, bias: 1 }}\n\
         \x20 lin: {{ type: lookup_table_2d, breakpoints1: [-1, 0, 0.5, 2], breakpoints2: [0, 1, 3], table: [{}], extrapolation: linear }}\n\
         \x20 clip: {{ type: lookup_table_2d, breakpoints1: [-1, 0, 0.5, 2], breakpoints2: [0, 1, 3], table: [{}] }}\n\
         wires:\n  - a -> lin.u1, clip.u1\n  - b -> lin.u2, clip.u2\nrecord: [a, b, lin, clip]\n",
        table.join(", "),
        table.join(", ")
    );
    let trace = run(&yaml);
    let (a, b) = (trace.column("a").unwrap(), trace.column("b").unwrap());
    for (i, &t) in trace.t().iter().enumerate() {
        let lin = trace.column("lin").unwrap()[i];
        assert!((lin - f(a[i], b[i])).abs() < 1e-12, "linear at {t}: {lin}");
        let clip = trace.column("clip").unwrap()[i];
        assert!((clip - f(a[i].clamp(-1.0, 2.0), b[i].clamp(0.0, 3.0))).abs() < 1e-12, "clip at {t}: {clip}");
    }
}
