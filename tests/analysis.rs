//! Linear analysis from the graph file, against python-control 0.10.2
//! (values computed once and written here): frequency response, margins,
//! bandwidth and poles; perturbation of nonlinear blocks; what cannot be
//! linearised; loop figures in `checks:`.

mod common;
use common::{ctlgraph, path, text};
use ctlgraph::core::linearize::{Linearization, Selection, linearize};
use ctlgraph_solver::freq;

fn lin(yaml: &str, input: Option<&str>, output: Option<&str>, open: Option<&str>) -> Linearization {
    let model = ctlgraph::compile_str(yaml, "test.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
    let sel = Selection {
        input: input.map(Into::into),
        output: output.map(Into::into),
        open: open.map(Into::into),
        ..Selection::default()
    };
    linearize(model, &sel).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1.0)
}

#[test]
fn a_second_order_transfer_function_has_python_controls_bode() {
    let l = lin(
        "blocks:\n  u: { type: step }\n  plant: { type: transfer_function, num: [100], den: [1, 6, 100] }\nwires: [u -> plant]\n",
        Some("u"),
        Some("plant"),
        None,
    );
    assert_eq!(l.exact, ["plant"]);
    // control.frequency_response(tf([100], [1, 6, 100]), logspace(-1, 3, 20)): (w, |G|, phase [deg]).
    let reference = [
        (0.1, 1.0000820050861485, -0.3438049315394798),
        (0.16237767391887217, 1.0002162407339212, -0.5583428696107087),
        (0.26366508987303583, 1.0005703039455245, -0.9069686195874391),
        (0.42813323987193935, 1.0015047538985955, -1.4741910288095676),
        (0.6951927961775606, 1.00397489893635, -2.400098251493819),
        (1.1288378916846888, 1.0105319427020818, -3.924597917511298),
        (1.8329807108324356, 1.028130034999184, -6.492465215887648),
        (2.9763514416313175, 1.0767229542868395, -11.086009883662157),
        (4.832930238571752, 1.220331323532535, -20.72399501578677),
        (7.847599703514611, 1.645596330173825, -50.790426833942874),
        (12.742749857031335, 1.0134375560743691, -129.20957316605706),
        (20.6913808111479, 0.28503540717781056, -159.27600498421322),
        (33.59818286283781, 0.09538331076749453, -168.91399011633786),
        (54.555947811685144, 0.03454330092267849, -173.50753478411235),
        (88.58667904100822, 0.012876955768392564, -176.0754020824887),
        (143.8449888287663, 0.0048521406478365045, -177.59990174850617),
        (233.57214690901213, 0.0018357388957031132, -178.52580897119043),
        (379.26901907322457, 0.0006955892673721223, -179.09303138041255),
        (615.8482110660261, 0.00026372210500557957, -179.4416571303893),
        (1000.0, 0.00010000820050861485, -179.65619506846053),
    ];
    let b = ctlgraph::analysis::bode(&l, Some((0.1, 1000.0)), 20);
    for (k, &(w, mag, phase)) in reference.iter().enumerate() {
        assert!(close(b.w[k], w, 1e-12), "{} vs {w}", b.w[k]);
        assert!((b.magnitude[k] - mag).abs() <= 1e-9 * mag, "|G({w})| = {} vs {mag}", b.magnitude[k]);
        assert!((b.phase_deg[k] - phase).abs() <= 1e-9, "∠G({w}) = {} vs {phase}", b.phase_deg[k]);
    }
}

/// A PI controller (kp 2, ki 0.5) on `plant`, unity negative feedback.
fn pi_loop(plant_den: &str) -> String {
    format!(
        "blocks:\n  r: {{ type: step }}\n  e: {{ type: sum, signs: \"+-\" }}\n  ctrl: {{ type: pid, kp: 2, ki: 0.5 }}\n  \
         plant: {{ type: transfer_function, num: [1], den: {plant_den} }}\n\
         wires: [r -> e.u1, plant -> e.u2, e -> ctrl, ctrl -> plant]\n"
    )
}

#[test]
fn margins_of_a_pi_loop_opened_at_the_controller_output_match_python_control() {
    // First-order plus integrator 1/(s(s + 1)): control.stability_margins(C*P)
    // = (inf, 27.153463058190226, 0.4330127018922193, nan, 1.2645660382007926, 1.414213562373095).
    let l = lin(&pi_loop("[1, 1, 0]"), None, None, Some("ctrl"));
    assert!(l.loop_transfer);
    let m = freq::margins(&l.system, None);
    assert_eq!(m.gain_margin, f64::INFINITY);
    assert!(m.gain_crossover_phase_freq.is_nan());
    assert!(close(m.phase_margin, 27.153463058190226, 1e-6), "{m:?}");
    assert!(close(m.gain_crossover_freq, 1.2645660382007926, 1e-6), "{m:?}");
    assert!(close(m.peak_sensitivity, 1.0 / 0.4330127018922193, 1e-6), "{m:?}");
    assert!(close(m.peak_sensitivity_freq, std::f64::consts::SQRT_2, 1e-6), "{m:?}"); // 1.414213562373095
    assert!(close(m.delay_margin, 27.153463058190226f64.to_radians() / 1.2645660382007926, 1e-6), "{m:?}");

    // With a lag, 1/(s(s + 1)(0.1 s + 1)): (3.9875, 20.06083930498113,
    // 0.32002115810781334, 2.692582403567252, 1.2585650123230092,
    // 1.3654939778317223); bandwidth(feedback(L, 1)) = 2.063782225774107.
    let l = lin(&pi_loop("[0.1, 1.1, 1, 0]"), None, None, Some("ctrl"));
    let f = ctlgraph::analysis::figures(&l);
    let m = f.margins;
    for (got, want) in [
        (m.gain_margin, 3.9875000000000003),
        (m.gain_crossover_phase_freq, 2.692582403567252),
        (m.phase_margin, 20.06083930498113),
        (m.gain_crossover_freq, 1.2585650123230092),
        (m.peak_sensitivity, 1.0 / 0.32002115810781334),
        (m.peak_sensitivity_freq, 1.3654939778317223),
        (f.closed_loop_bandwidth, 2.063782225774107),
    ] {
        assert!(close(got, want, 1e-6), "{got} vs {want}: {m:?}");
    }
    // The closed loop's poles: control.poles(feedback(L, 1)), and the PID's
    // derivative filter, −N = −100, there though kd = 0 (unobservable).
    let closed = lin(&pi_loop("[0.1, 1.1, 1, 0]"), None, None, None);
    let mut poles = freq::poles(&closed.system).unwrap();
    poles.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
    let want: [(f64, f64); 5] = [
        (-100.0, 0.0),
        (-10.207583304635051, 0.0),
        (-0.27696357010089656, 0.0),
        (-0.2577265626320331, -1.304666950297896),
        (-0.2577265626320331, 1.304666950297896),
    ];
    let mut want = want.to_vec();
    want.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    for (p, (re, im)) in poles.iter().zip(want) {
        assert!(close(p.re, re, 1e-9) && close(p.im, im, 1e-9), "{p} vs {re}{im:+}j");
    }
}

#[test]
fn the_tutorial_pid_loop_has_python_controls_margins_and_bandwidth() {
    // C = 2 + 15/s + 0.1·200 s/(s + 200), P = 100/(s² + 6 s + 100):
    // stability_margins(C*P) = (inf, 49.233871734432086, 0.7915683435169248,
    // nan, 17.538736120173148, 20.390490792728762); bandwidth(feedback) = 24.086409010958864.
    let out = ctlgraph(&["bode", "graphs/tutorial/pid_loop.yaml", "--open", "ctrl"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let model = ctlgraph::compile_file("graphs/tutorial/pid_loop.yaml".as_ref(), &[]).unwrap();
    let l = linearize(model, &Selection { open: Some("ctrl".into()), ..Selection::default() }).unwrap();
    let f = ctlgraph::analysis::figures(&l);
    for (got, want) in [
        (f.margins.phase_margin, 49.233871734432086),
        (f.margins.gain_crossover_freq, 17.538736120173148),
        (f.margins.peak_sensitivity, 1.0 / 0.7915683435169248),
        (f.margins.peak_sensitivity_freq, 20.390490792728762),
        (f.closed_loop_bandwidth, 24.086409010958864),
    ] {
        assert!(close(got, want, 1e-6), "{got} vs {want}");
    }
    assert_eq!(l.states, ["plant.x1", "plant.x2", "ctrl.x1", "ctrl.x2"]);
}

#[test]
fn nonlinear_blocks_give_their_local_gain_and_a_kink_is_named() {
    // u² at u = 3 has slope 6; a saturation inside its limits passes 1:1.
    let yaml = |value: f64| {
        format!(
            "blocks:\n  u: {{ type: constant, value: {value} }}\n  sq: {{ type: fcn, expr: \"u^2\" }}\n  \
             sat: {{ type: saturation, lower: -10, upper: 10 }}\n  y: {{ type: gain, k: 1 }}\nwires: [u -> sq, sq -> sat, sat -> y]\n"
        )
    };
    let l = lin(&yaml(3.0), Some("u"), Some("y"), None);
    assert!(close(l.system.d[0], 6.0, 1e-9), "{:?}", l.system);
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    assert_eq!(l.perturbed, ["sq", "sat", "y"]);
    // At the limit (u² = 10) the saturation is not smooth: its slopes are
    // 0 and 1 on the two sides; the mean is used, and the block named.
    let l = lin(&yaml(10f64.sqrt()), Some("u"), Some("y"), None);
    assert!(close(l.system.d[0], 0.5 * 2.0 * 10f64.sqrt(), 1e-5), "{:?}", l.system);
    assert_eq!(l.warnings.len(), 1);
    assert!(
        l.warnings[0].starts_with("block `sat` (saturation) is not smooth at the operating point"),
        "{:?}",
        l.warnings
    );
}

#[test]
fn the_operating_point_is_where_the_run_is_at_the_given_time() {
    // x' = -x + 1 from 0, y = x²: at t = 1, x = 1 − e⁻¹ and dy/dx = 2x.
    let yaml = "simulation: { stop: 2, solver: { method: dopri5, rtol: 1e-10, atol: 1e-12 } }\nblocks:\n  \
                one: { type: constant }\n  s: { type: sum, signs: \"+-\" }\n  x: { type: integrator }\n  y: { type: fcn, expr: \"u^2\" }\n\
                wires: [one -> s.u1, x -> s.u2, s -> x, x -> y]\n";
    let model = ctlgraph::compile_str(yaml, "test.yaml", &[]).unwrap();
    let sel = Selection { input: Some("s".into()), output: Some("y".into()), at: 1.0, ..Selection::default() };
    let l = linearize(model, &sel).unwrap();
    let x = 1.0 - (-1.0f64).exp();
    assert_eq!((l.system.n, l.at), (1, 1.0));
    assert!(close(l.system.a[0], -1.0, 1e-9) && close(l.system.b[0], 1.0, 1e-9), "{:?}", l.system);
    assert!(close(l.system.c[0], 2.0 * x, 1e-6), "{} vs {}", l.system.c[0], 2.0 * x);
}

#[test]
fn delays_mixed_rates_and_opaque_discrete_memory_are_refused_with_the_reason() {
    let sel = Selection { input: Some("u".into()), output: Some("p".into()), ..Selection::default() };
    let with = |block: &str, extra: &str| {
        format!(
            "blocks:\n  u: {{ type: step }}\n  b: {block}\n  p: {{ type: transfer_function, num: [1], den: [1, 1] }}{extra}\nwires: [u -> b, b -> p{}]\n",
            if extra.is_empty() { "" } else { ", p -> c" }
        )
    };
    let error = |yaml: String| {
        let model = ctlgraph::compile_str(&yaml, "test.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
        linearize(model, &sel).unwrap_err().to_string()
    };
    let e = error(with("{ type: transport_delay, delay: 0.1 }", ""));
    assert!(
        e.contains("test.yaml:3:")
            && e.contains("block `b` (transport_delay) is on the analysed path: a transport delay"),
        "{e}"
    );
    let td = "blocks:\n  u: { type: step }\n  b: { type: tracking_differentiator, delta: 10, h0: 0.01, sample_time: 0.01 }\n  \
              p: { type: transfer_function, num: [1], den: [1, 1] }\nwires: [u -> b, b.r1 -> p]\n";
    let e = error(td.to_string());
    assert!(
        e.contains("block `b` (tracking_differentiator) is on the analysed path: it is discrete")
            && e.contains("has no linear model"),
        "{e}"
    );
    let e = error(with("{ type: unit_delay, sample_time: 0.01 }", "\n  c: { type: unit_delay, sample_time: 0.02 }"));
    assert!(e.contains("several sample times (0.01, 0.02 s)"), "{e}");
}

#[test]
fn a_discrete_pid_loop_has_the_hand_derived_sampled_data_model() {
    // Plant 1/(s + a) held over T: x⁺ = Φ x + Γ u, Φ = e^(−aT), Γ = (1 − Φ)/a.
    // Discrete PID (forward-Euler integral I, backward-Euler filter F,
    // c = 1/(1 + N T)) on e = −x: I⁺ = I − T ki x, F⁺ = c F − (1 − c) x,
    // u = I − kd N c F − (kp + kd N c) x. Opened at u, L = −u/u_injected.
    let (a, t, kp, ki, kd, n) = (2.0, 0.05, 3.0, 4.0, 0.2, 50.0);
    let yaml = format!(
        "simulation: {{ stop: 1, solver: {{ method: rk4, step: {t} }} }}\nblocks:\n  r: {{ type: constant, value: 0 }}\n  \
         e: {{ type: sum, signs: \"+-\" }}\n  ctrl: {{ type: pid, kp: {kp}, ki: {ki}, kd: {kd}, n: {n}, sample_time: {t} }}\n  \
         plant: {{ type: transfer_function, num: [1], den: [1, {a}] }}\nwires: [r -> e.u1, plant -> e.u2, e -> ctrl, ctrl -> plant]\n"
    );
    let l = lin(&yaml, None, None, Some("ctrl"));
    assert_eq!(l.sample_time, Some(t));
    assert_eq!(l.states, ["plant", "ctrl.z1", "ctrl.z2"]);
    let (phi, c) = ((-a * t).exp(), 1.0 / (1.0 + n * t));
    let gamma = (1.0 - phi) / a;
    let want_a = [phi, 0.0, 0.0, -t * ki, 1.0, 0.0, -(1.0 - c), 0.0, c];
    let want_b = [gamma, 0.0, 0.0];
    let want_c = [kp + kd * n * c, -1.0, kd * n * c];
    let ss = &l.system;
    for (got, want) in ss.a.iter().zip(want_a).chain(ss.b.iter().zip(want_b)).chain(ss.c.iter().zip(want_c)) {
        assert!((got - want).abs() <= 1e-12 * want.abs().max(1.0), "{got} vs {want}: {ss:?}");
    }
    assert_eq!(ss.d, [0.0]);
}

#[test]
fn the_ladrc_loop_matches_an_independent_sampled_data_model() {
    // python-control: plant c2d(…, 1e-4, 'zoh'), the Euler LESO (β = 3ω0,
    // ω0², ω0³) and the LSEF u = α1 e1 + α2 e2 − z3/b0 assembled by hand,
    // opened at u: poles (eigvals) and stability_margins (frd method).
    let model = ctlgraph::compile_file("graphs/fladrc/ladrc.yaml".as_ref(), &[]).unwrap();
    let l = linearize(model, &Selection { open: Some("ctrl".into()), ..Selection::default() }).unwrap();
    assert_eq!(l.sample_time, Some(1e-4));
    let poles = freq::poles(&l.system).unwrap();
    // numpy.linalg.eigvals; the first three also mpmath's to 17 digits.
    let want: [(f64, f64); 5] = [
        (0.7230707645761356, 0.0),
        (0.9884646177119318, -0.0589742805022203),
        (0.9884646177119318, 0.0589742805022203),
        (0.9922083649418254, -0.012718485690632142),
        (0.9922083649418254, 0.012718485690632142),
    ];
    for (re, im) in want {
        assert!(
            poles.iter().any(|p| (p.re - re).abs() < 1e-11 && (p.im - im).abs() < 1e-11),
            "{re}{im:+}j not in {poles:?}"
        );
    }
    let f = ctlgraph::analysis::figures(&l);
    // python-control's frd fallback interpolates: agreement to 1e-5.
    assert!(close(f.margins.phase_margin, 80.11968758556122, 1e-5), "{:?}", f.margins);
    assert!(close(f.margins.gain_crossover_freq, 1420.4416013551488, 1e-5), "{:?}", f.margins);
    assert!(close(f.margins.peak_sensitivity, 1.0695520294916638, 1e-6), "{:?}", f.margins);
}

#[test]
fn the_analysis_section_feeds_the_commands_and_the_checks() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("loop.yaml");
    let graph = |check: &str| {
        format!("{}analysis: {{ open: ctrl }}\nrecord: [plant]\nchecks:\n  - \"{check}\"\n", pi_loop("[1, 1, 0]"))
    };
    std::fs::write(&g, graph("phase_margin > 25")).unwrap();
    let out = ctlgraph(&["test", path(&g)]);
    assert!(out.status.success(), "{}", text(&out.stdout));
    assert!(
        text(&out.stdout).contains("pass  phase_margin > 25  (measured 27.1535, bound > 25)"),
        "{}",
        text(&out.stdout)
    );
    std::fs::write(&g, graph("delay_margin > 0.5")).unwrap();
    let out = ctlgraph(&["run", path(&g)]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stdout).contains("FAIL  delay_margin > 0.5  (measured 0.374"), "{}", text(&out.stdout));
    // The commands read the section when no signal is named.
    let (csv, svg, json) = (dir.path().join("b.csv"), dir.path().join("b.svg"), dir.path().join("b.json"));
    let out = ctlgraph(&["bode", path(&g), "--csv", path(&csv), "--svg", path(&svg), "--out", path(&json)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("loop transfer at `ctrl`")
            && text(&out.stdout).contains("phase margin       27.15346 deg at 1.264566 rad/s"),
        "{}",
        text(&out.stdout)
    );
    assert!(std::fs::read_to_string(&csv).unwrap().starts_with("w,f,magnitude,magnitude_db,phase_deg\n"));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("phase margin 27.1535"));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["states"], serde_json::json!(["plant.x1", "plant.x2", "ctrl.x1", "ctrl.x2"]));
    assert!(close(report["margins"]["phase_margin_deg"].as_f64().unwrap(), 27.153463058190226, 1e-6));
    // A loop figure without a section, and a section naming no signal, are positioned errors.
    std::fs::write(&g, format!("{}record: [plant]\nchecks:\n  - \"phase_margin > 25\"\n", pi_loop("[1, 1, 0]")))
        .unwrap();
    let out = ctlgraph(&["check", path(&g)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains(":9:6: check: `phase_margin` is a figure of the analysed loop"),
        "{}",
        text(&out.stderr)
    );
    std::fs::write(&g, format!("{}analysis: {{ open: ctrll }}\n", pi_loop("[1, 1, 0]"))).unwrap();
    let out = ctlgraph(&["check", path(&g)]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains(":7:11: analysis: signal `ctrll`: no block `ctrll`") && err.contains("did you mean `ctrl`?"),
        "{err}"
    );
}

/// Each discrete block's linear model, stepped as a recursion, gives the
/// block's own simulated response to a unit step (checks `discrete_lti`
/// against the blocks' `output`/`update`).
#[test]
fn discrete_linear_models_step_like_their_blocks() {
    let t = 0.01;
    for block in [
        format!("{{ type: unit_delay, sample_time: {t} }}"),
        format!("{{ type: delay, samples: 3, sample_time: {t} }}"),
        format!("{{ type: discrete_transfer_function, num: [0.5, 0.2], den: [1, -0.6, 0.08], sample_time: {t} }}"),
        format!("{{ type: impedance, m: 0.5, b: 2, k: 20, hold_input: true, sample_time: {t} }}"),
        format!("{{ type: impedance, m: 0.5, b: 2, k: 20, method: backward_euler, sample_time: {t} }}"),
        format!("{{ type: pid, kp: 2, ki: 3, kd: 0.1, n: 40, sample_time: {t} }}"),
        format!("{{ type: leso, order: 2, omega: 30, b0: 2, sample_time: {t} }}"),
    ] {
        let wires = if block.contains("impedance") && block.contains("hold_input") {
            "wires: [u -> b.e, zero -> b.hold]"
        } else if block.contains("leso") {
            "wires: [u -> b.y, u -> b.u]"
        } else {
            "wires: [u -> b]"
        };
        let (output, column) = if block.contains("leso") { ("b[2]", "y[2]") } else { ("b", "y") };
        let yaml = format!(
            "simulation: {{ stop: 0.2, solver: {{ method: rk4, step: {t} }} }}\nblocks:\n  u: {{ type: step }}\n  \
             zero: {{ type: constant, value: 0 }}\n  b: {block}\n{wires}\nrecord: [y: b]\n"
        );
        let l = lin(&yaml, Some("u"), Some(output), None);
        assert_eq!(l.sample_time, Some(t), "{block}");
        let trace = common::run(&yaml);
        let ss = &l.system;
        let mut x = vec![0.0; ss.n];
        for (k, &y) in trace.column(column).unwrap().iter().enumerate() {
            let model = (0..ss.n).map(|j| ss.c[j] * x[j]).sum::<f64>() + ss.d[0];
            assert!((model - y).abs() <= 1e-9 * y.abs().max(1.0), "{block}: step {k}: model {model} vs block {y}");
            x = (0..ss.n).map(|i| (0..ss.n).map(|j| ss.a[i * ss.n + j] * x[j]).sum::<f64>() + ss.b[i]).collect();
        }
    }
}

#[test]
fn an_analysis_with_nothing_selected_or_no_path_is_refused_not_faked() {
    // Without --input/--output/--open and without an `analysis:` section,
    // the whole model's "transfer" has B = C = 0: a gain margin of inf and a
    // peak sensitivity of 1 that mean nothing.
    for command in ["bode", "linearize"] {
        let out = ctlgraph(&[command, "graphs/tutorial/pid_loop.yaml"]);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{command}: {stderr}");
        assert!(stderr.contains("nothing to analyse: give --input and --output, or --open"), "{stderr}");
        assert!(stderr.contains("--open: `plant`, `err`, `ctrl`"), "{stderr}");
        assert!(out.stdout.is_empty(), "{command} printed figures");
    }
    // Poles need no transfer: the whole model's stay.
    assert_eq!(ctlgraph(&["poles", "graphs/tutorial/pid_loop.yaml"]).status.code(), Some(0));
    // The reference feeds nothing back from the plant: no path from y to r.
    let out = ctlgraph(&["bode", "graphs/tutorial/pid_loop.yaml", "--input", "plant", "--output", "r"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("no path leads from `plant` to `r`"), "{}", text(&out.stderr));
}
