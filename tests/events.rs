//! Zero crossings and modes: impacts, relay switching, limited integrators
//! and saturation corners located to the solver's precision, chattering
//! stopped, and modes frozen inside steps.

mod common;
use common::run;

/// Times at which `column` is 1 (a hit_crossing output).
fn hit_times(trace: &ctlgraph::record::Trace, column: &str) -> Vec<f64> {
    let hits = trace.column(column).unwrap();
    trace.t().iter().zip(hits).filter(|&(_, &h)| h == 1.0).map(|(&t, _)| t).collect()
}

#[test]
fn bouncing_ball_impacts_are_exact() {
    let model = ctlgraph::compile_file("graphs/events/bouncing_ball.yaml".as_ref(), &[]).unwrap();
    let trace = ctlgraph::simulate(model, None).unwrap();
    // Closed form: first impact after sqrt(2 h0 / g), then flights 2 e^k v1 / g.
    let (g, e, h0) = (9.81f64, 0.8f64, 10.0f64);
    let v1 = (2.0 * g * h0).sqrt();
    let mut t = (2.0 * h0 / g).sqrt();
    let impacts = hit_times(&trace, "impact");
    assert_eq!(impacts.len(), 7, "impacts before t = 10: {impacts:?}");
    for (k, &ti) in impacts.iter().take(5).enumerate() {
        assert!((ti - t).abs() < 1e-9, "impact {}: {ti} vs {t}", k + 1);
        t += 2.0 * e.powi(k as i32 + 1) * v1 / g;
    }
    // After each impact the velocity is e times the arrival speed, upward.
    let v = trace.column("v").unwrap();
    let at = trace.t().iter().position(|&ti| ti == impacts[0]).unwrap();
    assert!((v[at] - e * v1).abs() < 1e-9, "rebound speed {}", v[at]);
}

#[test]
fn past_a_zeno_point_the_run_stops_or_ignores_the_block() {
    let text = std::fs::read_to_string("graphs/events/bouncing_ball.yaml").unwrap();
    let zeno = text.replace("stop: 10.0", "stop: 15.0");
    let model = ctlgraph::compile_str(&zeno, "zeno.yaml", &[]).unwrap();
    let error = ctlgraph::simulate(model, None).unwrap_err().to_string();
    assert!(error.contains("chatters") && error.contains("Zeno"), "{error}");
    let t: f64 = error.trim_start_matches("t = ").split(':').next().unwrap().parse().unwrap();
    // The impacts accumulate at t1 + 2 e v1 / (g (1 − e)) = 12.8506 s.
    assert!((t - 12.8506).abs() < 1e-3, "stopped at {t}");

    let adaptive = zeno.replace("max_step: 0.05 }", "max_step: 0.05, zero_crossing: adaptive }");
    let model = ctlgraph::compile_str(&adaptive, "zeno.yaml", &[]).unwrap();
    let mut sim = ctlgraph_core::Simulator::new(model, None);
    sim.run(&mut |_, _| {}).unwrap();
    assert!(sim.warnings().iter().any(|w| w.contains("`vel` chattered")), "{:?}", sim.warnings());
}

#[test]
fn thermostat_relay_switches_at_its_thresholds() {
    // T' = (heat·u − (T − 10))/5; the relay heats below 19 and stops above 21.
    let yaml = "simulation: { stop: 60.0, solver: { method: dopri5, rtol: 1.0e-9, atol: 1.0e-12, max_step: 1.0 } }\n\
                blocks:\n\
                \x20 relay: { type: relay, on_threshold: -19, off_threshold: -21, on_value: 1, off_value: 0 }\n\
                \x20 neg: { type: gain, k: -1 }\n\
                \x20 heat: { type: gain, k: 15 }\n\
                \x20 loss: { type: sum, signs: \"+-\" }\n\
                \x20 ambient: { type: constant, value: 10 }\n\
                \x20 rate: { type: sum, signs: \"+-\" }\n\
                \x20 room: { type: integrator, initial: 15 }\n\
                \x20 slow: { type: gain, k: 0.2 }\n\
                wires: [room -> neg, neg -> relay, relay -> heat, heat -> rate.u1, room -> loss.u1, ambient -> loss.u2,\n\
                \x20       loss -> rate.u2, rate -> slow, slow -> room]\n\
                record: [T: room, relay]\n";
    let trace = run(yaml);
    let (t, temp, relay) = (trace.t(), trace.column("T").unwrap(), trace.column("relay").unwrap());
    let mut switches = 0;
    for i in 1..t.len() {
        if relay[i] != relay[i - 1] {
            switches += 1;
            // The switching row is the crossing itself: T at a threshold.
            let threshold = if relay[i] == 0.0 { 21.0 } else { 19.0 };
            assert!((temp[i] - threshold).abs() < 1e-9, "switch at t = {} with T = {}", t[i], temp[i]);
        }
    }
    assert!(switches >= 4, "{switches} switches");
    // Starts heating at once (T = 15 < 19) and stays within the band after.
    let first_off = (1..t.len()).find(|&i| relay[i] == 0.0).unwrap();
    assert!(temp[first_off..].iter().all(|&v| (19.0 - 1e-9..=21.0 + 1e-9).contains(&v)));
    // The first switch-off time in closed form: T(t) = 25 − 10 e^{−t/5} reaches 21.
    let expected = -5.0 * (0.4f64).ln();
    assert!((t[first_off] - expected).abs() < 1e-8, "{} vs {expected}", t[first_off]);
}

#[test]
fn limited_integrator_corner_is_exact_under_dopri5() {
    // x' = cos t from 0 hits the limit 0.5 at t = asin(0.5) = π/6 and leaves
    // it when cos t turns negative at π/2 (integrator modes).
    let yaml = "simulation: { stop: 3.0, solver: { method: dopri5, rtol: 1.0e-11, atol: 1.0e-13, max_step: 0.5 } }\n\
                blocks:\n  u: { type: sine, frequency: 1/(2*pi), phase: pi/2 }\n\
                \x20 x: { type: integrator, upper: 0.5 }\n  hit: { type: hit_crossing, level: 0.5, direction: rising }\n\
                wires: [u -> x, x -> hit]\nrecord: [x, hit]\n";
    let trace = run(yaml);
    let corner = hit_times(&trace, "hit");
    assert_eq!(corner.len(), 1, "{corner:?}");
    let exact = std::f64::consts::FRAC_PI_6;
    assert!((corner[0] - exact).abs() < 1e-9, "corner at {} vs {exact}", corner[0]);
    // After leaving at π/2: x = 0.5 + sin t − 1.
    let x = *trace.column("x").unwrap().last().unwrap();
    assert!((x - (3f64.sin() - 0.5)).abs() < 1e-9, "x(3) = {x}");
}

#[test]
fn saturation_corner_is_located_and_each_side_integrates_its_own_formula() {
    // ∫ sat(sin t) with limit 0.5: corners at π/6 and 5π/6; between, the
    // integrand is the constant 0.5. Large max_step: only detection helps.
    let yaml = "simulation: { stop: 3.0, solver: { method: dopri5, rtol: 1.0e-10, atol: 1.0e-12, max_step: 1.0 } }\n\
                blocks:\n  u: { type: sine, frequency: 1/(2*pi) }\n  s: { type: saturation, lower: -0.5, upper: 0.5 }\n\
                \x20 x: { type: integrator }\n  hit: { type: hit_crossing, level: 0.5 }\n\
                wires: [u -> s, s -> x, u -> hit]\nrecord: [x, hit]\n";
    let trace = run(yaml);
    let corners = hit_times(&trace, "hit");
    let pi = std::f64::consts::PI;
    assert_eq!(corners.len(), 2, "{corners:?}");
    assert!((corners[0] - pi / 6.0).abs() < 1e-9 && (corners[1] - 5.0 * pi / 6.0).abs() < 1e-9, "{corners:?}");
    // x(3) = (1 − cos π/6) + 0.5·(5π/6 − π/6) + (cos 5π/6 − cos 3).
    let exact = (1.0 - (pi / 6.0).cos()) + 0.5 * (4.0 * pi / 6.0) + ((5.0 * pi / 6.0).cos() - 3f64.cos());
    let x = *trace.column("x").unwrap().last().unwrap();
    assert!((x - exact).abs() < 1e-8, "x(3) = {x} vs {exact}");
}

#[test]
fn detection_off_keeps_plain_functions_and_counts_no_events() {
    let yaml = "simulation: { stop: 3.0, solver: { method: dopri5, max_step: 1.0, zero_crossing: false } }\n\
                blocks:\n  u: { type: sine, frequency: 1/(2*pi) }\n  s: { type: saturation, lower: -0.5, upper: 0.5 }\n\
                \x20 x: { type: integrator }\nwires: [u -> s, s -> x]\nrecord: [s]\n";
    let model = ctlgraph::compile_str(yaml, "off.yaml", &[]).unwrap();
    let mut sim = ctlgraph_core::Simulator::new(model, None);
    let mut max_s: f64 = 0.0;
    let stats = sim.run(&mut |_, s| max_s = max_s.max(s[1])).unwrap();
    assert_eq!(stats.events, 0);
    assert!(max_s <= 0.5);
}

#[test]
fn integrator_reset_levels_and_edges() {
    // A sawtooth: x' = 1, reset to 0 whenever x reaches 1 (rising edge of x − 1).
    let yaml = "simulation: { stop: 3.5, solver: { method: dopri5, max_step: 0.3 } }\n\
                blocks:\n  one: { type: constant, value: 1 }\n\
                \x20 x: { type: integrator, reset: rising, state_port: true }\n  level: { type: sum, signs: \"+-\" }\n\
                wires: [one -> x.u, x.state -> level.u1, one -> level.u2, level -> x.reset]\nrecord: [x: x.y]\n";
    let trace = run(yaml);
    for t in [0.5, 1.5, 2.25, 3.4] {
        let x = trace.at("x", t).unwrap();
        assert!((x - t.fract()).abs() < 1e-9, "x({t}) = {x}");
    }
    // Level reset holds the state at its initial value while the input is nonzero.
    let yaml = "simulation: { stop: 2.0, solver: { method: rk4, step: 0.01 } }\n\
                blocks:\n  one: { type: constant, value: 1 }\n  gate: { type: pulse, period: 2, duty: 0.5, amplitude: 1 }\n\
                \x20 x: { type: integrator, initial: 0.25, reset: level }\n\
                wires: [one -> x.u, gate -> x.reset]\nrecord: [x]\n";
    let trace = run(yaml);
    assert!((trace.at("x", 0.9).unwrap() - 0.25).abs() < 1e-12, "held during the gate");
    let after = trace.at("x", 1.9).unwrap();
    assert!((after - 1.15).abs() < 1e-9, "integrates after the gate: {after}");
    assert!((trace.at("x", 2.0).unwrap() - 0.25).abs() < 1e-12, "reset again when the next gate opens");
}

#[test]
fn min_max_and_switch_hand_over_at_the_crossing() {
    // ∫ max(sin t, 0.5): the handover at π/6 and 5π/6 is located like a saturation corner.
    let yaml = "simulation: { stop: 3.0, solver: { method: dopri5, rtol: 1.0e-10, atol: 1.0e-12, max_step: 1.0 } }\n\
                blocks:\n  u: { type: sine, frequency: 1/(2*pi) }\n  half: { type: constant, value: 0.5 }\n\
                \x20 m: { type: min }\n  x: { type: integrator }\n\
                \x20 sw: { type: switch, threshold: 0.5 }\n  y: { type: integrator }\n\
                wires: [u -> m.u1, half -> m.u2, m -> x, half -> sw.u1, u -> sw.control, u -> sw.u2, sw -> y]\n\
                record: [x, y]\n";
    let trace = run(yaml);
    let pi = std::f64::consts::PI;
    let exact = (1.0 - (pi / 6.0).cos()) + 0.5 * (4.0 * pi / 6.0) + ((5.0 * pi / 6.0).cos() - 3f64.cos());
    let x = *trace.column("x").unwrap().last().unwrap();
    let y = *trace.column("y").unwrap().last().unwrap();
    assert!((x - exact).abs() < 1e-8, "min: x(3) = {x} vs {exact}");
    assert!((y - exact).abs() < 1e-8, "switch: y(3) = {y} vs {exact}");
}

#[test]
fn contact_onset_is_located() {
    // A probe descending at 1 m/s onto the flat surface z = 0 touches it at t = 1.
    let yaml = "simulation: { stop: 1.5, solver: { method: dopri5, max_step: 0.2 } }\n\
                blocks:\n  x: { type: constant, value: 0 }\n  vx: { type: constant, value: 0 }\n\
                \x20 vz: { type: constant, value: -1 }\n  z: { type: integrator, initial: 1 }\n\
                \x20 c: { type: contact, profile: \"0\", stiffness: 1000, damping: 10 }\n\
                wires: [vz -> z, x -> c.x, z -> c.z, vx -> c.vx, vz -> c.vz]\nrecord: [fn: c.fn]\n";
    let trace = run(yaml);
    let fn_ = trace.column("fn").unwrap();
    let first = fn_.iter().position(|&f| f > 0.0).unwrap();
    let t = trace.t()[first];
    assert!((t - 1.0).abs() < 1e-12, "contact starts at t = {t}");
    // At onset the damper alone pushes: N = c_e·δ' = 10.
    assert!((fn_[first] - 10.0).abs() < 1e-6, "N at onset {}", fn_[first]);
    assert_eq!(fn_[first - 1], 0.0);
}

#[test]
fn fixed_step_methods_locate_crossings_when_asked() {
    // rk4 integrates the ball's parabola exactly; with detection on, the
    // impacts fall between grid points at their exact times.
    let text = std::fs::read_to_string("graphs/events/bouncing_ball.yaml").unwrap();
    let rk4 = text.replace(
        "solver: { method: dopri5, rtol: 1.0e-10, atol: 1.0e-12, max_step: 0.05 }",
        "solver: { method: rk4, step: 0.01, zero_crossing: true }",
    );
    assert_ne!(rk4, text);
    let trace = ctlgraph::simulate(ctlgraph::compile_str(&rk4, "rk4.yaml", &[]).unwrap(), None).unwrap();
    let impacts = hit_times(&trace, "impact");
    let (g, h0) = (9.81f64, 10.0f64);
    let first = (2.0 * h0 / g).sqrt();
    assert!((impacts[0] - first).abs() < 1e-12, "{} vs {first}", impacts[0]);
    assert_eq!(impacts.len(), 7);
    // Off (the fixed-step default), the impact is seen a step late.
    let off = rk4.replace(", zero_crossing: true", "");
    let trace = ctlgraph::simulate(ctlgraph::compile_str(&off, "off.yaml", &[]).unwrap(), None).unwrap();
    let late = hit_times(&trace, "impact");
    assert!(late[0] > first && late[0] - first < 0.01 + 1e-12, "{}", late[0]);
}

/// A relational operator under an adaptive solver switches where its
/// inputs cross, located as a zero crossing: sin(2π·0.5·t) > 0.5 first
/// holds at t = asin(0.5)/π = 1/6 s and stops at 5/6 s; `and` with
/// t < 0.6 (a ramp against 0.6) ends the window at 0.6 s.
#[test]
fn relational_and_logical_operators_switch_at_the_crossings() {
    let trace = run("simulation: { stop: 1.0, solver: { method: dopri5, rtol: 1e-9, max_step: 0.05 } }\n\
                     blocks:\n  s: { type: sine, frequency: 0.5 }\n  above: { type: relational_operator, op: '>', constant: 0.5 }\n\
                     \x20 t: { type: ramp, slope: 1 }\n  early: { type: relational_operator, op: '<', constant: 0.6 }\n\
                     \x20 both: { type: logical_operator, op: and }\n\
                     wires:\n  - s -> above\n  - t -> early\n  - above -> both.u1\n  - early -> both.u2\n\
                     record: [above, both]\n");
    let switches = |column: &str| -> Vec<f64> {
        let y = trace.column(column).unwrap();
        trace.t().windows(2).zip(y.windows(2)).filter(|(_, v)| v[0] != v[1]).map(|(t, _)| t[1]).collect()
    };
    let above = switches("above");
    assert_eq!(above.len(), 2, "{above:?}");
    assert!((above[0] - 1.0 / 6.0).abs() < 1e-9 && (above[1] - 5.0 / 6.0).abs() < 1e-9, "{above:?}");
    let both = switches("both");
    assert_eq!(both.len(), 2, "{both:?}");
    assert!((both[0] - 1.0 / 6.0).abs() < 1e-9 && (both[1] - 0.6).abs() < 1e-9, "{both:?}");
}
