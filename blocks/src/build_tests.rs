//! Every builder's parameter checks at their boundaries (the value just
//! allowed, the first refused, infinities), and the choices a builder
//! makes from its parameters (a mode, a default, a derived coefficient)
//! seen in the built block's ports and outputs. The positioned messages
//! themselves are the integration tests' (`tests/errors.rs`).

use crate::test_rig::{Rig, build};
use ctlgraph_core::registry::Built;

#[track_caller]
fn ok(ty: &str, params: &str) -> Built {
    build(ty, params).unwrap_or_else(|d| panic!("{ty} {{ {params} }}: {d}"))
}

#[track_caller]
fn refused(ty: &str, params: &str, key: &str) {
    match build(ty, params) {
        Ok(_) => panic!("{ty} {{ {params} }} was accepted"),
        Err(d) => assert!(d.to_string().contains(&format!("`{key}`")), "{ty} {{ {params} }}: {d}"),
    }
}

/// `key` must be finite and positive (or >= 0 with `zero_ok`); `base`
/// holds the block's other parameters.
#[track_caller]
fn positive_only(ty: &str, base: &str, key: &str, zero_ok: bool) {
    let with = |v: &str| if base.is_empty() { format!("{key}: {v}") } else { format!("{base}, {key}: {v}") };
    ok(ty, &with("0.5"));
    for bad in ["-1", ".inf"] {
        refused(ty, &with(bad), key);
    }
    if zero_ok {
        ok(ty, &with("0"));
    } else {
        refused(ty, &with("0"), key);
    }
}

#[test]
fn positive_and_non_negative_parameters() {
    positive_only("derivative", "", "tau", false);
    positive_only("pid", "kp: 1, kd: 1", "n", false);
    positive_only("reference_filter", "omega: 10", "zeta", false);
    positive_only("rls", "n: 2, sample_time: 0.1", "p0", false);
    positive_only("contact", "profile: 0, stiffness: 1e4", "damping", true);
    positive_only("band_limited_white_noise", "sample_time: 0.01", "power", true);
    positive_only("uniform_noise", "sample_time: 0.01", "amplitude", true);
    positive_only("gaussian_noise", "sample_time: 0.01", "variance", true);
    positive_only("smc", "lambda: 1", "k", true);
    positive_only("smc", "lambda: 1, k: 1", "phi", true);
    positive_only("tracking_differentiator", "sample_time: 0.01", "delta", false);
    positive_only("tracking_differentiator", "delta: 10, sample_time: 0.01", "h0", false);
    positive_only("tracking_differentiator", "delta: 10, sample_time: 0.01", "c_step", false);
    positive_only("milling_force", "teeth: 2, rpm: 600, kr: 0.3, ap: 1, ft: 0.1", "kt", true);
    positive_only("milling_force", "teeth: 2, rpm: 600, kt: 700, ap: 1, ft: 0.1", "kr", true);
    positive_only("milling_force", "teeth: 2, rpm: 600, kt: 700, kr: 0.3, ft: 0.1", "ap", true);
    positive_only("milling_force", "teeth: 2, rpm: 600, kt: 700, kr: 0.3, ap: 1", "ft", true);
    positive_only("milling_force", "teeth: 2, kt: 700, kr: 0.3, ap: 1, ft: 0.1", "rpm", false);
}

#[test]
fn ranges_with_two_ends() {
    // RLS forgetting factor in (0, 1].
    for good in ["1", "0.5"] {
        ok("rls", &format!("n: 1, sample_time: 0.1, lambda: {good}"));
    }
    for bad in ["0", "-0.5", "1.5"] {
        refused("rls", &format!("n: 1, sample_time: 0.1, lambda: {bad}"), "lambda");
    }
    // Noise seeds are whole numbers >= 0.
    for good in ["0", "3"] {
        ok("gaussian_noise", &format!("sample_time: 0.1, seed: {good}"));
    }
    for bad in ["-1", "1.5"] {
        refused("gaussian_noise", &format!("sample_time: 0.1, seed: {bad}"), "seed");
    }
    // The sliding-mode bounds may coincide (a fixed estimate), not cross.
    let smc = "lambda: 1, ks: 1, rho: 1, je: 1, be: 1";
    ok("sliding_mode", &format!("{smc}, d_min: 0.5, d_max: 0.5"));
    ok("sliding_mode", &format!("{smc}, d_min: -1, d_max: 1"));
    refused("sliding_mode", &format!("{smc}, d_min: 1, d_max: 0"), "d_max");
    // An integrator's initial value inside its limits, ends included.
    ok("integrator", "lower: -1, upper: 1, initial: 1");
    refused("integrator", "lower: -1, upper: 1, initial: 2", "initial");
    // Milling: whole teeth from 1 to 64, ae/D in (0, 1], one turn of cut at most.
    let mill = "rpm: 600, kt: 700, kr: 0.3, ap: 1, ft: 0.1";
    for good in ["1", "64"] {
        ok("milling_force", &format!("{mill}, teeth: {good}"));
    }
    for bad in ["0", "65", "2.5"] {
        refused("milling_force", &format!("{mill}, teeth: {bad}"), "teeth");
    }
    ok("milling_force", &format!("{mill}, teeth: 2, immersion: 1"));
    for bad in ["0", "1.5"] {
        refused("milling_force", &format!("{mill}, teeth: 2, immersion: {bad}"), "immersion");
    }
    ok("milling_force", &format!("{mill}, teeth: 2, entry: 0, exit: 360"));
    refused("milling_force", &format!("{mill}, teeth: 2, entry: 90, exit: 90"), "exit");
    refused("milling_force", &format!("{mill}, teeth: 2, entry: 10, exit: 371"), "exit");
    refused("milling_force", &format!("{mill}, teeth: 2, entry: 360, exit: 400"), "entry");
    refused("milling_force", &format!("{mill}, teeth: 2, milling: down, entry: 0, exit: 90"), "milling");
    refused("milling_force", &format!("{mill}, teeth: 2, immersion: 0.5, entry: 0, exit: 90"), "immersion");
    refused("milling_force", "rpm: 600, kt: 700, kr: 0.3, krc: 210, ap: 1, ft: 0.1, teeth: 2", "krc");
    refused("milling_force", "rpm: 600, kt: 0, krc: 210, ap: 1, ft: 0.1, teeth: 2", "krc");
}

#[test]
fn transfer_function_errors_name_the_polynomial_at_fault() {
    let improper = build("transfer_function", "num: [1, 0, 0], den: [1, 1]").err().expect("improper");
    assert!(improper.to_string().contains("`num`") && improper.hint.unwrap_or_default().contains("poles"));
    refused("transfer_function", "num: [1], den: [0]", "den");
    refused("zpk", "zeros: [-1]", "poles");
    ok("zpk", "zeros: [-1], poles: [-2, -3]");
}

#[test]
fn transfer_function_gain_and_factors() {
    let dc = |params: &str| {
        let b = ok("transfer_function", params);
        let ss = b.block.lti().expect("an LTI block");
        (ss.n, ctlgraph_solver::freq::at_frequency(ss, 0.0, None).re)
    };
    let close = |(n, g): (usize, f64), (n0, g0): (usize, f64)| n == n0 && (g - g0).abs() < 1e-12 * g0.abs();
    // 2/(s + 1) times 3; one factor over two; two factors over one polynomial.
    assert!(close(dc("num: [2], den: [1, 1], gain: 3"), (1, 6.0)));
    assert!(close(dc("num: [1], den: [[1, 3], [1, 4]]"), (2, 1.0 / 12.0)));
    assert!(close(dc("num: [[1, 1], [1, 2]], den: [1, 3, 5], gain: 2"), (2, 0.8)));
    assert!(close(dc("num: [[1, 1]], den: [[1, 3]], gain: -1"), (1, -1.0 / 3.0)));
}

#[test]
fn initial_vectors_broadcast_or_match_the_states() {
    let ss = "A: [[-1, 0], [0, -2]], B: [[1], [1]], C: [[1, 1]]";
    assert_eq!(Rig::new(ok("state_space", &format!("{ss}, initial: [3, -4]"))).x, vec![3.0, -4.0]);
    assert_eq!(Rig::new(ok("state_space", &format!("{ss}, initial: 2"))).x, vec![2.0, 2.0]);
    refused("state_space", &format!("{ss}, initial: [1, 2, 3]"), "initial");
}

#[test]
fn choices_select_their_mode() {
    // The integrator's reset kinds each add the reset port; an external initial value its own.
    for kind in ["rising", "falling", "either", "level"] {
        assert_eq!(Rig::new(ok("integrator", &format!("reset: {kind}"))).input_names(), ["u", "reset"]);
    }
    assert_eq!(Rig::new(ok("integrator", "reset: none")).input_names(), ["u"]);
    assert_eq!(Rig::new(ok("integrator", "initial_source: external")).input_names(), ["u", "initial"]);
    assert_eq!(Rig::new(ok("integrator", "initial_source: internal")).input_names(), ["u"]);
    // Limits are watched (two functions per element) when either is finite.
    for (limits, watched) in [("", 0), ("lower: 0", 2), ("upper: 0", 2), ("lower: -1, upper: 1", 2)] {
        let rig = Rig::new(ok("integrator", limits));
        assert_eq!(rig.built.block.num_zero_crossings(), watched, "{limits}");
    }
    // The normal-force selector port follows `select`.
    assert_eq!(Rig::new(ok("normal_force", "mu_u: 0.1")).input_names(), ["fx", "fz", "climbing"]);
    assert_eq!(Rig::new(ok("normal_force", "mu_u: 0.1, select: slope")).input_names(), ["fx", "fz", "slope"]);
    // Impedance discretisation: the step response is the difference equation of
    // discrete_impedance with the method asked for, bilinear by default.
    for (method, bilinear) in [("", true), (", method: bilinear", true), (", method: backward_euler", false)] {
        let mut r = Rig::new(ok("impedance", &format!("m: 1, b: 10, k: 100, sample_time: 0.01{method}")));
        let got: Vec<f64> = r.steps(&[1.0], 5).iter().map(|y| y[0]).collect();
        let (num, den) = crate::force::discrete_impedance(1.0, 10.0, 100.0, 0.01, bilinear);
        let mut y = [0.0; 7];
        for n in 2..7 {
            // A unit step from sample 0 (index 2): den·y = num·u in powers of z^-1.
            let u = |k: usize| if k >= 2 { 1.0 } else { 0.0 };
            y[n] = (num[0] * u(n) + num[1] * u(n - 1) + num[2] * u(n - 2) - den[1] * y[n - 1] - den[2] * y[n - 2])
                / den[0];
        }
        for (a, b) in got.iter().zip(&y[2..]) {
            assert!((a - b).abs() < 1e-15, "{method}: {got:?} vs {:?}", &y[2..]);
        }
    }
}

#[test]
fn pid_anti_windup_modes_differ_under_saturation() {
    // ki = 10, T = 0.1, |u| <= 1: three samples of e = 1 then one of e = −1.
    let run = |mode: &str| {
        let mut rig = Rig::new(ok("pid", &format!("kp: 0, ki: 10, lower: -1, upper: 1, sample_time: 0.1{mode}")));
        rig.steps(&[1.0], 3);
        let after: Vec<f64> = rig.steps(&[-1.0], 5).iter().map(|y| y[0]).collect();
        after
    };
    let (clamping, back, none) =
        (run(", anti_windup: clamping"), run(", anti_windup: back_calculation"), run(", anti_windup: none"));
    assert_eq!(run(""), clamping);
    // After the error turns: clamping held the integral at the limit, so u leaves it at once
    // (1, 0, −1); without anti-windup the integral ran on and u stays at 1 for three samples;
    // back-calculation bleeds the excess off in between (1, 1, 0.639, −0.361).
    assert_eq!(clamping[..3], [1.0, 0.0, -1.0]);
    assert_eq!(none[..4], [1.0, 1.0, 1.0, 0.0]);
    assert!((back[2] - 0.639).abs() < 1e-9 && (back[3] + 0.361).abs() < 1e-9, "{back:?}");
}

#[test]
fn a_td_paper_form_steps_by_h_and_the_others_by_h0() {
    // c_step defaults to h for form: paper and to h0 otherwise; giving it to fhan is refused.
    let outputs = |params: &str| Rig::new(ok("tracking_differentiator", params)).steps(&[0.01], 30);
    let base = "delta: 100, sample_time: 0.01, h0: 0.05";
    assert_eq!(outputs(&format!("{base}, form: paper")), outputs(&format!("{base}, form: paper, c_step: 0.01")));
    assert_ne!(outputs(&format!("{base}, form: paper")), outputs(&format!("{base}, form: paper, c_step: 0.05")));
    assert_eq!(outputs(&format!("{base}, form: fst")), outputs(&format!("{base}, form: fst, c_step: 0.05")));
    assert_ne!(outputs(&format!("{base}, form: fst")), outputs(&format!("{base}, form: fst, c_step: 0.01")));
    refused("tracking_differentiator", &format!("{base}, form: fhan, c_step: 0.01"), "c_step");
    // h0 defaults to 2h.
    assert_eq!(outputs("delta: 100, sample_time: 0.01"), outputs("delta: 100, sample_time: 0.01, h0: 0.02"));
}

#[test]
fn leso_and_lsef_gains_are_checked() {
    positive_only("leso", "b0: 1", "omega", false);
    ok("leso", "order: 1, beta: [1, 2], b0: 1");
    ok("leso", "order: 3, omega: 10, b0: 1");
    refused("leso", "order: 1, beta: [1, 2, 3], b0: 1", "beta");
    refused("leso", "omega: 10, beta: [1, 2, 3], b0: 1", "beta");
    for bad in ["0", ".inf"] {
        refused("leso", &format!("omega: 10, b0: {bad}"), "b0");
        refused("lsef", &format!("alpha: [1, 2], b0: {bad}"), "b0");
    }
    ok("leso", "omega: 10, b0: -2");
    ok("lsef", "alpha: [1, 2], b0: -2");
    ok("lsef", "order: 1, alpha: [3], b0: 1");
    refused("lsef", "order: 1, alpha: [1, 2], b0: 1", "alpha");
    refused("lsef", "order: 3, alpha: [1, 2, 3], b0: 1", "order");
    // The bandwidth gains for order 2: β = (3ω, 3ω², ω³).
    // The ports: an observer of order n outputs n + 1 estimates; the LSEF takes r2 at order 2 only.
    let mut rig = Rig::new(ok("leso", "order: 2, omega: 10, b0: 1, sample_time: 0.001"));
    assert_eq!(rig.outs[0].width, 3);
    let lsef = |params: &str| {
        let r = Rig::new(ok("lsef", params));
        (
            r.input_names().iter().map(|s| s.to_string()).collect::<Vec<_>>(),
            r.ins.iter().map(|p| p.width).collect::<Vec<_>>(),
        )
    };
    assert_eq!(
        lsef("order: 1, alpha: [3], b0: 1, gain_inputs: [alpha1]"),
        (vec!["r1".into(), "z".into(), "alpha1".into()], vec![1, 2, 1])
    );
    assert_eq!(
        lsef("alpha: [1, 2], b0: 1, gain_inputs: [alpha1, alpha2]"),
        (vec!["r1".into(), "r2".into(), "z".into(), "alpha1".into(), "alpha2".into()], vec![1, 1, 3, 1, 1])
    );
    assert_eq!(rig.built.block.discrete_lti().map(|s| s.n), Some(3));
    rig.set(&[1.0, 0.0]);
    rig.update(0.0);
    // One Euler step of z' = β·e from z = 0 with y = 1: z = h·(30, 300, 1000).
    let z = rig.output(0.001);
    let expected = [0.03, 0.3, 1.0];
    for (a, b) in z.iter().zip(expected) {
        assert!((a - b).abs() < 1e-12, "{z:?}");
    }
}

#[test]
fn feed_drive_parameters_scale_by_the_drive_chain() {
    // Je = J/(ka·kt·rg), Be = B/(ka·kt·rg): x'' = (u − Be·x')/Je.
    let mut rig = Rig::new(ok("feed_drive", "j: 6, b: 12, ka: 2, kt: 0.5, rg: 3, initial: [0, 1]"));
    rig.set(&[5.0]);
    // Je = 6/3 = 2, Be = 12/3 = 4: x'' = (5 − 4)/2.
    assert_eq!(rig.derivatives(), vec![1.0, 0.5]);
    let mut direct = Rig::new(ok("feed_drive", "je: 2, be: 4, initial: [0, 1]"));
    direct.set(&[5.0]);
    assert_eq!(direct.derivatives(), vec![1.0, 0.5]);
    refused("feed_drive", "je: 2, initial: [0, 1]", "be");
}

#[test]
fn band_limited_noise_has_variance_power_over_t() {
    // power 0.04 at T = 0.01 is a Gaussian of variance 4: the same draws from the same stream.
    let draws =
        |params: &str| Rig::new(ok(params.split(':').next().unwrap(), params.split_once(':').unwrap().1)).steps(&[], 5);
    let a = draws("band_limited_white_noise: power: 0.04, sample_time: 0.01, seed: 2");
    let b = draws("gaussian_noise: variance: 4, sample_time: 0.01, seed: 2");
    assert_eq!(a, b);
    assert!(a.iter().any(|y| y[0] != 0.0));
}

#[test]
fn contact_profiles_are_expressions_or_numbers() {
    // z = 0.5 (a number) and z = "0.1 * x" (an expression): the probe at x = 2, z = 0 is
    // 0.5 and 0.2 deep; the normal force is stiffness × depth × cos θ-free here (fn output).
    let depth = |profile: &str| {
        let mut rig = Rig::new(ok("contact", &format!("profile: {profile}, stiffness: 100")));
        rig.set(&[2.0, 0.0, 0.0, 0.0]);
        rig.output(0.0)[2]
    };
    assert!((depth("0.5") - 50.0).abs() < 1e-9, "{}", depth("0.5"));
    let sloped = depth("\"0.1 * x\"");
    // Depth 0.2 measured along the normal of a 0.1 slope: 0.2·cos(atan 0.1).
    assert!((sloped - 100.0 * 0.2 / (1.0f64 + 0.01).sqrt()).abs() < 1e-6, "{sloped}");
    refused("contact", "profile: [1, 2], stiffness: 100", "profile");
}
