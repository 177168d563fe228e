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
    let (q1, q2) = (delayed_sine_error(5, 3e-3), delayed_sine_error(5, 1.5e-3));
    // Linear: within h²/8·max|u''| and second order; cubic: within
    // h⁴/4!·max|u''''| (one-sided next to the breakpoints the start sends
    // through, 9/16 of it elsewhere) and fourth order (rk4's own error in
    // the sine's samples is nil: the sine is a source); quintic: sixth order.
    assert!(l1 <= (2.0 * PI).powi(2) * 3e-3f64.powi(2) / 8.0, "linear error {l1}");
    assert!(c1 <= (2.0 * PI).powi(4) * 3e-3f64.powi(4) / 24.0, "cubic error {c1}");
    let (linear, cubic, quintic) = ((l1 / l2).log2(), (c1 / c2).log2(), (q1 / q2).log2());
    assert!((linear - 2.0).abs() < 0.1, "linear interpolation order {linear}");
    assert!((cubic - 4.0).abs() < 0.1, "cubic interpolation order {cubic}");
    assert!((quintic - 6.0).abs() < 0.3, "quintic interpolation order {quintic}: {q1} {q2}");
    assert!(q1 <= 17.0 / 720.0 * (2.0 * PI).powi(6) * 3e-3f64.powi(6), "quintic error {q1}");
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

/// The actuator signal of graphs/events/antiwindup_dead_time.yaml with the
/// delay's `order` set (`None`: the default), and its largest distance
/// from the method-of-steps reference (tests/data/antiwindup_delay.csv,
/// made by tests/reference/antiwindup_delay.py) on the 0.25 s grid.
fn antiwindup_error(order: Option<u32>) -> f64 {
    let mut text = std::fs::read_to_string("graphs/events/antiwindup_dead_time.yaml").unwrap();
    if let Some(order) = order {
        text = text.replace("delay: L }", &format!("delay: L, order: {order} }}"));
    }
    let model = ctlgraph::compile_str(&text, "antiwindup_dead_time.yaml", &[]).unwrap();
    let trace = ctlgraph::simulate(model, None).unwrap();
    let reference: Vec<(f64, f64)> = std::fs::read_to_string("tests/data/antiwindup_delay.csv")
        .unwrap()
        .lines()
        .skip(1)
        .map(|line| {
            let mut fields = line.split(',').map(|f| f.parse::<f64>().unwrap());
            (fields.next().unwrap(), fields.next().unwrap())
        })
        .collect();
    // `output: { every: 0.25 }` records exactly the reference's grid.
    assert_eq!(trace.t(), reference.iter().map(|r| r.0).collect::<Vec<_>>());
    let a = trace.column("a").unwrap();
    a.iter().zip(&reference).map(|(a, r)| (a - r.1).abs()).fold(0.0, f64::max)
}

#[test]
fn a_dead_time_in_a_loop_is_accurate_to_the_tolerance_asked() {
    // PathSim's anti-windup PID with a 2 s dead time, dopri5 at rtol 1e-10
    // and max_step 0.05. Measured: 6.4e-9 (order 3, the default), 4.6e-10
    // (order 5); linear interpolation between steps (Simulink's), with
    // the breakpoints, 1.7e-4 — 1.9e-4 before breakpoints were kept.
    let (default, cubic, quintic, linear) =
        (antiwindup_error(None), antiwindup_error(Some(3)), antiwindup_error(Some(5)), antiwindup_error(Some(1)));
    assert_eq!(default, cubic);
    assert!(cubic < 1e-8, "order 3: {cubic}");
    assert!(quintic < 1e-9, "order 5: {quintic}");
    assert!(linear > 1e-5, "linear interpolation is not to the tolerance: {linear}");
}

#[test]
fn a_relay_loop_with_a_dead_time_keeps_its_period_on_default_settings() {
    // graphs/events/thermostat_dead_time.yaml, dopri5's defaults (stop/200
    // = 6 s would exceed the 2 s delay; the default max_step stays below it).
    let (tau, t_out, heat, t_low, t_high, l) = (20.0f64, 10.0, 15.0, 19.0, 21.0, 2.0);
    let a = t_out + heat;
    let t1 = a + (t_high - a) * (-l / tau).exp();
    let t2 = t_out + (t_low - t_out) * (-l / tau).exp();
    let period = 2.0 * l + tau * ((t1 - t_out) / (t_low - t_out)).ln() + tau * ((a - t2) / (a - t_high)).ln();
    let model = ctlgraph::compile_file("graphs/events/thermostat_dead_time.yaml".as_ref(), &[]).unwrap();
    let trace = ctlgraph::simulate(model, None).unwrap();
    let (t, q) = (trace.t(), trace.column("heating").unwrap());
    let on: Vec<f64> = (1..t.len()).filter(|&i| q[i] == 1.0 && q[i - 1] == 0.0).map(|i| t[i]).collect();
    assert!(on.len() > 50, "{} cycles", on.len());
    for w in on[on.len() - 10..].windows(2) {
        let measured = w[1] - w[0];
        assert!(((measured - period) / period).abs() < 1e-6, "period {measured} vs {period}");
    }
}

#[test]
fn breakpoints_arrive_as_major_steps_and_pass_on_for_five_generations() {
    // A step at t = 1 into a 0.5 s delay on a loop with an integrator:
    // major steps at 1.5, 2.0, …, 3.5 (generations 1 to 5), none at 4.0.
    let yaml = "simulation: { stop: 5.0, solver: { method: dopri5, max_step: 0.3 } }\n\
                blocks:\n  r: { type: step, at: 1 }\n  e: { type: sum, signs: \"+-\" }\n\
                \x20 i: { type: integrator }\n  d: { type: transport_delay, delay: 0.5 }\n\
                wires: [r -> e.u1, e -> i, i -> d, d -> e.u2]\nrecord: [i]\n";
    let trace = run(yaml);
    let at = |time: f64| trace.t().contains(&time);
    for time in [1.5, 2.0, 2.5, 3.0, 3.5] {
        assert!(at(time), "no major step at {time}");
    }
    assert!(!at(4.0), "a sixth generation at 4.0");
}

#[test]
fn a_step_longer_than_a_delay_on_a_loop_is_warned_about_and_the_default_stays_below_it() {
    let graph = |solver: &str| {
        format!(
            "parameters: {{ r: 1 }}\nsimulation: {{ stop: 10.0, solver: {solver} }}\n\
             blocks:\n  r: {{ type: constant }}\n  e: {{ type: sum, signs: \"+-\" }}\n\
             \x20 i: {{ type: integrator }}\n  d: {{ type: transport_delay, delay: 0.5 }}\n\
             wires: [r -> e.u1, e -> i, i -> d, d -> e.u2]\nrecord: [r, i]\n"
        )
    };
    let warnings = |solver: &str| ctlgraph::compile_str(&graph(solver), "test.yaml", &[]).unwrap().warnings;
    let fixed = warnings("{ method: rk4, step: 1.0 }");
    assert!(
        fixed.iter().any(|w| w.contains(
            "block `d` (transport_delay) delays by 0.5 s on a feedback loop, less than the solver's step 1 s"
        )),
        "{fixed:?}"
    );
    let adaptive = warnings("{ method: dopri5, max_step: 0.8 }");
    assert!(adaptive.iter().any(|w| w.contains("max_step 0.8 s") && w.contains("or leave it out")), "{adaptive:?}");
    // A parameter named like a recorded signal: what a bare name means.
    assert!(fixed.iter().any(|w| w.contains("parameter `r` and the recorded signal `r` share a name")), "{fixed:?}");
    // dopri5's default (stop/200 = 0.05 here) and trbdf2's (stop/10 = 1 s) stay at most 0.5 s, unwarned.
    for solver in ["dopri5", "trbdf2"] {
        let model = ctlgraph::compile_str(&graph(solver), "test.yaml", &[]).unwrap();
        assert!(!model.warnings.iter().any(|w| w.contains("delays by")), "{solver}: {:?}", model.warnings);
        let sim = ctlgraph::core::Simulator::new(model, None);
        assert!(sim.method().max_step() <= 0.5, "{solver}: {}", sim.method().max_step());
    }
    // `check` and `run` print them.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("loop.yaml");
    std::fs::write(&file, graph("{ method: rk4, step: 1.0 }")).unwrap();
    for command in ["check", "run"] {
        let out = common::ctlgraph(&[command, common::path(&file)]);
        assert!(
            common::text(&out.stdout).contains("warning: block `d` (transport_delay) delays by 0.5 s"),
            "{command}"
        );
    }
}
