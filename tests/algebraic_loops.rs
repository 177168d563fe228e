//! Algebraic loops solved at every evaluation (`simulation: {
//! algebraic_loops: solve | warn | error }`): closed forms, a nonlinear
//! loop against SciPy's root finder, a loop through a stiff plant under
//! TR-BDF2 against the same loop solved by hand, the failure that names
//! the loop, and what `check` and `run` say.

mod common;
use common::{ctlgraph, error, max_error, run, text};

/// y = u − k·y through a sum and a gain: y = u/(1 + k).
const LINEAR: &str = "simulation: { stop: 1, solver: SOLVER }\nblocks:\n  u: { type: sine, amplitude: 2 }\n\
                      \x20 s: { type: sum, signs: \"+-\" }\n  k: { type: gain, k: 3 }\n\
                      wires: [u -> s.u1, s -> k, k -> s.u2]\nrecord: [u, y: s]\n";

#[test]
fn a_linear_loop_gives_its_closed_form() {
    for solver in ["{ method: rk4, step: 0.01 }", "{ method: dopri5 }", "{ method: trbdf2 }"] {
        let trace = run(&LINEAR.replace("SOLVER", solver));
        let u = |t: f64| 2.0 * (2.0 * std::f64::consts::PI * t).sin();
        let err = max_error(&trace, "y", |t| u(t) / 4.0);
        assert!(err < 1e-14, "{solver}: {err}");
    }
}

/// y + y³ = u with u = t + t³ has the root y = t, through a sum and an
/// `fcn` (y³) in a loop; solved to the loop's tolerance, a thousandth of rtol.
#[test]
fn a_nonlinear_loop_finds_its_known_root() {
    let trace = run("simulation: { stop: 2, solver: { method: dopri5, rtol: 1e-9 } }\nblocks:\n\
         \x20 u: { type: fcn, inputs: 0, expr: \"t + t^3\" }\n  s: { type: sum, signs: \"+-\" }\n\
         \x20 cube: { type: fcn, expr: \"u^3\" }\nwires: [u -> s.u1, s -> cube, cube -> s.u2]\nrecord: [y: s]\n");
    let err = max_error(&trace, "y", |t| t);
    assert!(err < 1e-11, "{err}");
}

/// Two coupled nonlinear equations, a = cos(b) + u and b = 0.5·sin(a) +
/// 0.2·a, against SciPy 1.17.1's `scipy.optimize.root` (hybr, tol 1e-15)
/// at u = 0, 0.5, …, 2 (values recorded).
#[test]
fn a_coupled_nonlinear_loop_matches_scipy() {
    let trace = run("simulation: { stop: 2, solver: { method: rk4, step: 0.5 } }\nblocks:\n\
         \x20 u: { type: ramp }\n  a: { type: fcn, inputs: 2, expr: \"cos(u2) + u1\" }\n\
         \x20 b: { type: fcn, expr: \"0.5*sin(u) + 0.2*u\" }\n\
         wires: [u -> a.u1, b -> a.u2, a -> b]\nrecord: [a, b]\n");
    let scipy = [
        (0.8537605744778999, 0.5476306162941443),
        (1.2490591180639974, 0.7241555827308466),
        (1.6733651047955438, 0.8320452373841364),
        (2.1618224260222227, 0.8475491652766446),
        (2.7353196097482493, 0.7446581711595692),
    ];
    let (a, b) = (trace.column("a").unwrap(), trace.column("b").unwrap());
    assert_eq!(a.len(), 5);
    for (k, (want_a, want_b)) in scipy.iter().enumerate() {
        assert!(
            (a[k] - want_a).abs() < 1e-12 && (b[k] - want_b).abs() < 1e-12,
            "u = {}: ({}, {})",
            k as f64 / 2.0,
            a[k],
            b[k]
        );
    }
}

/// A loop through a stiff plant with feedthrough (poles −1 and −10⁴, D =
/// 0.5) and a gain k = 5, under TR-BDF2: the same as the closed loop
/// solved by hand, y = k·(r − C x)/(1 + k·D), as one state-space block.
#[test]
fn a_loop_through_a_stiff_plant_under_trbdf2_equals_its_solution_by_hand() {
    let solver = "{ method: trbdf2, rtol: 1e-9, atol: 1e-12 }";
    let looped = run(&format!(
        "simulation: {{ stop: 8, solver: {solver} }}\nblocks:\n  r: {{ type: step, at: 0.1 }}\n\
         \x20 e: {{ type: sum, signs: \"+-\" }}\n  k: {{ type: gain, k: 5 }}\n\
         \x20 plant: {{ type: state_space, A: [[0, 1], [-10000, -10001]], B: [[0], [1]], C: [[10000, 0]], D: 0.5 }}\n\
         wires: [r -> e.u1, e -> k, k -> plant, plant -> e.u2]\nrecord: [z: plant]\n"
    ));
    // ẋ = (A − B·k/(1+kD)·C) x + B·k/(1+kD)·r,  z = C/(1+kD)·x + kD/(1+kD)·r.
    let g = 5.0 / 3.5;
    let by_hand = run(&format!(
        "simulation: {{ stop: 8, solver: {solver} }}\nblocks:\n  r: {{ type: step, at: 0.1 }}\n\
         \x20 plant: {{ type: state_space, A: [[0, 1], [{a:e}, -10001]], B: [[0], [{g:e}]], C: [[{c:e}, 0]], D: {d:e} }}\n\
         wires: [r -> plant]\nrecord: [z: plant]\n",
        a = -10000.0 - g * 10000.0,
        c = 10000.0 / 3.5,
        d = 2.5 / 3.5
    ));
    // Both at the same times, by linear interpolation between rows (the
    // signal is slow there: the fast pole has died out).
    let at = |trace: &ctlgraph::record::Trace, time: f64| {
        let (t, z) = (trace.t(), trace.column("z").unwrap());
        let i = t.partition_point(|&s| s < time).clamp(1, t.len() - 1);
        z[i - 1] + (z[i] - z[i - 1]) * (time - t[i - 1]) / (t[i] - t[i - 1])
    };
    for time in [0.05, 0.3, 0.5, 1.0, 2.0, 3.0] {
        let (want, got) = (at(&by_hand, time), at(&looped, time));
        assert!((got - want).abs() < 1e-6, "t = {time}: {got} vs {want}");
    }
    let zl = looped.column("z").unwrap();
    // The steady state: z = k·(1·1 + 0.5)/(1 + 5·1.5) → DC gain 1 + D = 1.5: z = 7.5/8.5.
    assert!((zl[zl.len() - 1] - 7.5 / 8.5).abs() < 1e-7, "{}", zl[zl.len() - 1]);
}

#[test]
fn warn_says_so_once_solve_is_silent_and_error_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("loop.yaml");
    std::fs::write(&file, LINEAR.replace("SOLVER", "{ method: rk4, step: 0.01 }")).unwrap();
    let out = ctlgraph(&["run", common::path(&file)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let said = text(&out.stdout) + &text(&out.stderr);
    assert_eq!(
        said.matches("algebraic loop s -> k -> s: solved for s at every evaluation (1 unknown)").count(),
        1,
        "{said}"
    );
    // `check` lists the loop and its cut signal in every mode.
    let silent =
        LINEAR.replace("SOLVER", "{ method: rk4, step: 0.01 }").replace("stop: 1,", "stop: 1, algebraic_loops: solve,");
    std::fs::write(&file, &silent).unwrap();
    let out = ctlgraph(&["run", common::path(&file)]);
    assert!(!(text(&out.stdout) + &text(&out.stderr)).contains("algebraic loop"));
    let out = ctlgraph(&["check", common::path(&file)]);
    assert!(text(&out.stdout).contains("algebraic loop s -> k -> s: solved for s"), "{}", text(&out.stdout));
    // `error` refuses, naming the cycle in order, at its first block.
    let yaml = "simulation: { algebraic_loops: error }\nblocks:\n  r: { type: step }\n  e: { type: sum, signs: \"+-\" }\n\
                \x20 k: { type: gain, k: 2 }\n  f: { type: gain, k: 0.5 }\nwires: [r -> e.u1, e -> k, k -> f, f -> e.u2]\n";
    let d = error(yaml);
    assert_eq!(d.message, "algebraic loop: e -> k -> f -> e");
    assert_eq!(d.pos.map(|p| (p.line, p.col)), Some((4, 3)));
    assert!(d.hint.unwrap().contains("unit_delay"));
}

/// s = u + s has no solution for u ≠ 0: the run stops with exit 1, naming
/// the loop and how close the solver came.
#[test]
fn a_loop_without_a_solution_stops_the_run_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("no_root.yaml");
    let yaml = "simulation: { stop: 1, solver: { method: rk4, step: 0.1 }, algebraic_loops: solve }\nblocks:\n\
                \x20 u: { type: constant, value: 1 }\n  s: { type: sum, signs: \"++\" }\n\
                wires: [u -> s.u1, s -> s.u2]\n";
    std::fs::write(&file, yaml).unwrap();
    let out = ctlgraph(&["run", common::path(&file)]);
    assert_eq!(out.status.code(), Some(1));
    let said = text(&out.stderr);
    assert!(said.contains("algebraic loop s -> s: no solution found: residual 1.000e0"), "{said}");
}

/// The members keep their names: records, wires out of the loop and
/// `--set` reach them as before; a loop's states (a transfer function
/// with feedthrough) integrate with the others.
#[test]
fn signals_inside_a_loop_keep_their_names() {
    let trace = run("simulation: { stop: 2, solver: { method: dopri5, rtol: 1e-10, atol: 1e-12 } }\nblocks:\n\
         \x20 r: { type: step }\n  e: { type: sum, signs: \"+-\" }\n\
         \x20 g: { type: transfer_function, num: [1, 2], den: [1, 1] }\n  out: { type: gain, k: 10 }\n\
         wires: [r -> e.u1, e -> g, g -> e.u2, g -> out]\nrecord: [e, y: g, out]\n");
    // G = (s+2)/(s+1) in unit feedback: Y/R = (s+2)/(2s+3), y(t) = 2/3 − (1/6)·e^(−1.5t) for t ≥ 0.
    let y = |t: f64| 2.0 / 3.0 - (-1.5 * t).exp() / 6.0;
    assert!(max_error(&trace, "y", y) < 1e-9, "{}", max_error(&trace, "y", y));
    assert!(max_error(&trace, "e", |t| 1.0 - y(t)) < 1e-9);
    assert!(max_error(&trace, "out", |t| 10.0 * y(t)) < 1e-8);
}

/// Linearised through a loop by perturbation, as any block: y = k·(r − y)
/// gives r → y the gain k/(1 + k) into a first-order plant (B = 0.75 for
/// k = 3), and the diode's small-signal conductance at V = 0 is
/// 1/(R + Vt/Is), its resistance at zero bias Vt/Is = 2.59e10 Ω.
#[test]
fn linearisation_passes_through_a_solved_loop() {
    use ctlgraph::core::linearize::Selection;
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("loop.yaml");
    std::fs::write(
        &file,
        "blocks:\n  r: { type: step }\n  e: { type: sum, signs: \"+-\" }\n  k: { type: gain, k: 3 }\n\
         \x20 plant: { type: transfer_function, num: [1], den: [1, 2] }\nwires: [r -> e.u1, e -> k, k -> e.u2, k -> plant]\n",
    )
    .unwrap();
    let select = |input: &str, output: &str| Selection {
        input: Some(input.into()),
        output: Some(output.into()),
        open: None,
        at: 0.0,
        pos: None,
    };
    let lin = ctlgraph::analysis::linearize_file(&file, &[], &select("r", "plant")).unwrap_or_else(|e| panic!("{e:?}"));
    let ss = &lin.system;
    assert_eq!((ss.a.clone(), ss.c.clone(), ss.d.clone()), (vec![-2.0], vec![1.0], vec![0.0]));
    assert!((ss.b[0] - 0.75).abs() < 1e-9, "{}", ss.b[0]);
    let diode = std::path::Path::new("graphs/tutorial/algebraic_loop.yaml");
    let lin = ctlgraph::analysis::linearize_file(diode, &[], &select("V", "diode")).unwrap_or_else(|e| panic!("{e:?}"));
    let want = 1.0 / (1000.0 + 0.025852 / 1e-12);
    assert!((lin.system.d[0] - want).abs() < 1e-6 * want, "{} vs {want}", lin.system.d[0]);
}
