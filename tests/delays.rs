//! Transport delays against closed forms and the method of steps, the
//! discrete z^-N, and the history's limit.

mod common;
use common::{max_error, run};
use std::f64::consts::PI;

/// Largest error of a 0.25 s transport delay of sin(2πt) under rk4 at step `h`.
fn delayed_sine_error(order: u32, h: f64) -> f64 {
    let yaml = format!(
        "simulation: {{ stop: 2.0, solver: {{ method: rk4, step: {h} }} }}\n\
         blocks:\n  u: {{ type: sine, frequency: 1 }}\n\
         \x20 d: {{ type: transport_delay, delay: 0.25, initial: 0.5, order: {order} }}\n\
         wires: [u -> d]\nrecord: [d]\n"
    );
    let trace = run(&yaml);
    max_error(&trace, "d", |t| if t < 0.25 { 0.5 } else { (2.0 * PI * (t - 0.25)).sin() })
}

#[test]
fn delayed_sine_is_exact_to_interpolation_order() {
    // 0.25 is no multiple of these steps, so every output is interpolated.
    let (l1, l2) = (delayed_sine_error(1, 3e-3), delayed_sine_error(1, 1.5e-3));
    let (c1, c2) = (delayed_sine_error(3, 3e-3), delayed_sine_error(3, 1.5e-3));
    // Linear: within h²/8·max|u''| and second order; cubic Hermite: third order.
    assert!(l1 <= (2.0 * PI).powi(2) * 3e-3f64.powi(2) / 8.0, "linear error {l1}");
    let (linear, cubic) = ((l1 / l2).log2(), (c1 / c2).log2());
    assert!((linear - 2.0).abs() < 0.1, "linear interpolation order {linear}");
    assert!((cubic - 3.0).abs() < 0.2, "cubic interpolation order {cubic}");
    assert!(c1 < 1e-7, "cubic error {c1}");
}

#[test]
fn dead_time_pi_loop_matches_the_method_of_steps() {
    // y(t) of graphs/events/dead_time_pi.yaml, from the delay differential
    // equation solved interval by interval (SciPy DOP853, rtol 1e-13).
    let reference = [
        (1.0, 0.25),
        (2.0, 0.6276041666666663),
        (3.0, 0.8177164713541145),
        (5.0, 0.9563604809093679),
        (10.0, 0.9987762332673696),
    ];
    for (t, y) in reference {
        let model = ctlgraph::compile_file("graphs/events/dead_time_pi.yaml".as_ref(), &[]).unwrap();
        let trace = ctlgraph::simulate(model, Some(t)).unwrap();
        let got = *trace.column("y").unwrap().last().unwrap();
        assert!((got - y).abs() < 1e-6, "y({t}) = {got} vs {y}");
    }
}

#[test]
fn variable_delay_follows_its_input() {
    // τ(t) = 0.2 + 0.1·sin(t): y = sin(2π(t − τ(t))) once t > τ.
    let yaml = "simulation: { stop: 3.0, solver: { method: rk4, step: 1.0e-3 } }\n\
                blocks:\n  u: { type: sine, frequency: 1 }\n\
                \x20 tau: { type: sine, amplitude: 0.1, frequency: 1/(2*pi), bias: 0.2 }\n\
                \x20 d: { type: variable_transport_delay, max_delay: 0.5 }\n\
                wires: [u -> d.u, tau -> d.delay]\nrecord: [d]\n";
    let trace = run(yaml);
    // The jump at t = τ(t) falls between samples: judge from t = 0.3 on.
    let late = trace.t().iter().position(|&t| t > 0.3).unwrap();
    let tail: f64 = trace.column("d").unwrap()[late..]
        .iter()
        .zip(&trace.t()[late..])
        .map(|(&y, &t)| (y - (2.0 * PI * (t - 0.2 - 0.1 * t.sin())).sin()).abs())
        .fold(0.0, f64::max);
    assert!(tail < 1e-5, "variable delay error {tail}");
}

#[test]
fn discrete_delay_gives_its_exact_sequence() {
    let yaml = "simulation: { stop: 1.0, solver: { method: rk4, step: 0.1 } }\n\
                blocks:\n  c: { type: clock }\n  z: { type: zero_order_hold, sample_time: 0.1 }\n\
                \x20 d: { type: delay, samples: 3, initial: -1, sample_time: 0.1 }\n\
                wires: [c -> z, z -> d]\nrecord: [z, d]\n";
    let trace = run(yaml);
    let (z, d) = (trace.column("z").unwrap(), trace.column("d").unwrap());
    for k in 0..z.len() {
        let expected = if k < 3 { -1.0 } else { z[k - 3] };
        assert_eq!(d[k], expected, "k = {k}");
    }
}

#[test]
fn a_full_history_stops_the_run_with_its_reason() {
    let yaml = "simulation: { stop: 1.0, solver: { method: rk4, step: 1.0e-3 } }\n\
                blocks:\n  u: { type: sine }\n  d: { type: transport_delay, delay: 0.5, buffer: 8, max_buffer: 64 }\n\
                wires: [u -> d]\nrecord: [d]\n";
    let model = ctlgraph::compile_str(yaml, "full.yaml", &[]).unwrap();
    let error = ctlgraph::simulate(model, None).unwrap_err().to_string();
    assert!(
        error.contains("block `d`") && error.contains("history is full") && error.contains("max_buffer"),
        "{error}"
    );
}

#[test]
fn milling_regeneration_is_delayed_exactly_one_tooth_period() {
    // The milling process's delayed x, y against its own x, y one tooth
    // period τ = 60/(N·rpm) earlier. At 10 000 rpm τ = 2 ms is 200 steps
    // and the tooth events (entries every τ, exits a quarter turn later at
    // ae/D = 0.5) fall on the grid, so each sample of the delay output
    // meets a recorded sample τ earlier: no interpolation, equal to rounding
    // (one step off would differ by several per cent of the amplitude).
    let yaml = "simulation: { stop: 0.05, solver: { method: rk4, step: 1.0e-5 } }\n\
                blocks:\n  zero: { type: constant, value: 0 }\n  \
                mill: { type: subsystem, file: lib/milling_process.yaml, parameters: { rpm: 10000, immersion: 0.5 } }\n\
                wires: [zero -> mill.ux, zero -> mill.uy]\n\
                record: [x: mill.x, y: mill.y, xd: mill/x_prev, yd: mill/y_prev]\n";
    let model = ctlgraph::compile_str(yaml, "graphs/milling/delay_check.yaml", &[]).unwrap();
    let trace = ctlgraph::simulate(model, None).unwrap();
    let t = trace.t();
    let tau = 60.0 / (3.0 * 10_000.0);
    let mut compared = 0;
    for (now, delayed) in [("x", "xd"), ("y", "yd")] {
        let (v, d) = (trace.column(now).unwrap(), trace.column(delayed).unwrap());
        let scale = v.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 1e-4, "{now} never moves");
        for k in 0..t.len() {
            let j = t.partition_point(|&s| s < t[k] - tau - 1e-12);
            if j >= t.len() || (t[j] - (t[k] - tau)).abs() > 1e-12 {
                continue;
            }
            assert!((d[k] - v[j]).abs() <= 1e-10 * scale, "{delayed} at {}: {} vs {}", t[k], d[k], v[j]);
            compared += 1;
        }
    }
    assert!(compared > 2 * 4000, "{compared} samples compared");
}
