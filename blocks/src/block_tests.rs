//! The methods the simulator calls — states, outputs, derivatives, modes,
//! zero crossings, major steps — of the dynamic, discrete and force blocks,
//! by hand on a [`Rig`]. Whole-graph behaviour (the solver in the loop) is
//! the integration tests'.

use crate::force::normal_force;
use crate::test_rig::{Rig, build};
use ctlgraph_core::Crossing;

fn rig(ty: &str, params: &str) -> Rig {
    Rig::new(build(ty, params).unwrap_or_else(|d| panic!("{d}")))
}

fn wide(ty: &str, params: &str, width: usize) -> Rig {
    Rig::with_width(build(ty, params).unwrap_or_else(|d| panic!("{d}")), width)
}

#[test]
fn filtered_derivative_by_hand() {
    // Width 2, x(0) = initial_input = 2; y = x' = (u − x)/τ = (3 − 2)/0.5 = 2.
    let mut r = wide("derivative", "tau: 0.5, initial_input: 2", 2);
    assert_eq!(r.x, vec![2.0, 2.0]);
    r.set(&[3.0]);
    assert_eq!(r.output(0.0), vec![2.0, 2.0]);
    assert_eq!(r.derivatives(), vec![2.0, 2.0]);
    assert!(!r.built.block.updates());
}

#[test]
fn state_space_states_outputs_and_derivatives() {
    // x' = [-1 0; 1 -2] x + [1; 0] u, y = [1 1] x + 0.5 u, x(0) = (1, −2), u = 4.
    let mut r = rig("state_space", "A: [[-1, 0], [1, -2]], B: [[1], [0]], C: [[1, 1]], D: [[0.5]], initial: [1, -2]");
    assert_eq!(r.x, vec![1.0, -2.0]);
    r.set(&[4.0]);
    assert_eq!(r.output(0.0), vec![1.0 - 2.0 + 2.0]);
    assert_eq!(r.derivatives(), vec![-1.0 + 4.0, 1.0 + 4.0]);
    assert!(r.built.block.lti().is_some() && !r.built.block.updates());
}

#[test]
fn discrete_transfer_function_steps_and_restarts() {
    // 0.5/(z − 0.5) under a unit step: y(k) = 0, 0.5, 0.75, 0.875.
    let mut r = rig("discrete_transfer_function", "num: [0.5], den: [1, -0.5], sample_time: 0.1");
    let y: Vec<f64> = r.steps(&[1.0], 4).iter().map(|v| v[0]).collect();
    assert_eq!(y, [0.0, 0.5, 0.75, 0.875]);
    let mut x = r.x.clone();
    r.built.block.initialize(&mut x);
    assert_eq!(r.steps(&[1.0], 2).iter().map(|v| v[0]).collect::<Vec<_>>(), [0.0, 0.5]);
    let ss = r.built.block.discrete_lti().expect("a discrete model");
    assert_eq!((ss.a.clone(), ss.b.clone(), ss.c.clone(), ss.d.clone()), (vec![0.5], vec![1.0], vec![0.5], vec![0.0]));
}

#[test]
fn zero_order_hold_passes_its_input() {
    let mut r = wide("zero_order_hold", "sample_time: 0.1", 2);
    r.set_port(0, &[1.5, -2.0]);
    assert_eq!(r.output(0.0), vec![1.5, -2.0]);
    assert!(!r.built.block.updates());
}

#[test]
fn held_impedance_freezes_output_and_state() {
    // Not held, it is the plain discrete filter.
    let mut held = rig("impedance", "m: 1, b: 10, k: 100, sample_time: 0.01, hold_input: true");
    let mut plain = rig("impedance", "m: 1, b: 10, k: 100, sample_time: 0.01");
    let run =
        |r: &mut Rig, hold: f64, n: usize| -> Vec<f64> { r.steps(&[1.0, hold], n).iter().map(|v| v[0]).collect() };
    let a = run(&mut plain, 0.0, 6);
    assert!(a[1..].iter().all(|&v| v > 0.0), "{a:?}");
    let first = run(&mut held, 0.0, 3);
    assert_eq!(first, a[..3]);
    // Held: the last output stays and the filter does not advance …
    let during = run(&mut held, 1.0, 3);
    assert_eq!(during, vec![first[2]; 3]);
    // … so releasing it continues where it stopped.
    assert_eq!(run(&mut held, 0.0, 3), a[3..]);
    // Restarting clears the held value and the filter.
    let mut x = vec![];
    held.built.block.initialize(&mut x);
    assert_eq!(run(&mut held, 1.0, 1), vec![0.0]);
    assert_eq!(run(&mut held, 0.0, 3), a[..3]);
    // The discrete model has the hold input as a second input entering nowhere.
    let ss = held.built.block.discrete_lti().expect("a model");
    assert_eq!(ss.m, 2);
    assert_eq!(ss.b.len(), 2 * ss.n);
    assert!(ss.b.iter().skip(1).step_by(2).all(|&v| v == 0.0) && ss.b.iter().step_by(2).any(|&v| v != 0.0));
    assert_eq!(ss.d.len(), 2);
    assert_eq!(ss.d[1], 0.0);
    assert_ne!(ss.d[0], 0.0);
}

#[test]
fn normal_force_selects_climbing_by_slope_or_flag() {
    let (fx, fz) = (10.0, 40.0);
    let n = |climbing| normal_force(fx, fz, climbing, 0.2, 0.3);
    assert_ne!(n(true), n(false));
    let mut by_slope = rig("normal_force", "mu_u: 0.2, mu_d: 0.3, select: slope");
    for (slope, climbing) in [(0.1, true), (0.0, false), (-0.1, false)] {
        by_slope.set(&[fx, fz, slope]);
        assert_eq!(by_slope.output(0.0), vec![n(climbing)], "slope {slope}");
    }
    let mut by_flag = rig("normal_force", "mu_u: 0.2, mu_d: 0.3");
    for (flag, climbing) in [(0.5, true), (0.49, false), (1.0, true)] {
        by_flag.set(&[fx, fz, flag]);
        assert_eq!(by_flag.output(0.0), vec![n(climbing)], "flag {flag}");
    }
    assert!(!by_flag.built.block.updates());
}

#[test]
fn contact_modes_are_chosen_at_major_steps() {
    // A level surface at z = 0, k = 100, c = 10: the probe 0.01 deep, sinking at 0.1.
    let mut r = rig("contact", "profile: 0, stiffness: 100, damping: 10");
    r.set(&[0.0, -0.01, 0.0, -0.1]);
    // N = k·depth + c·rate = 1 + 1 = 2, straight up.
    assert_eq!(r.output(0.0), vec![-0.0, 2.0, 2.0, 0.0]);
    assert_eq!(r.zero_crossings(), vec![0.01, 2.0]);
    // Pressing is frozen in a solver stage: out of the surface the push goes negative.
    r.set(&[0.0, 0.01, 0.0, 0.0]);
    assert_eq!(r.output_minor(0.0)[2], -1.0);
    assert_eq!(r.output(0.0)[2], 0.0);
    // Not pressing (chosen at a major step with N = 0) is frozen too.
    r.set(&[0.0, -0.01, 0.0, 0.0]);
    assert_eq!(r.output_minor(0.0)[2], 0.0);
    assert_eq!(r.output(0.0)[2], 1.0);
    // Restarting forgets the mode.
    let mut x = [];
    r.built.block.initialize(&mut x);
    assert_eq!(r.output_minor(0.0)[2], 0.0);
}

#[test]
fn tabulated_contact_surface_slope() {
    // A ridge 0 → 1 → 0 over x = 0 … 2: slope 1 on the way up, −1 down.
    let mut r = rig("contact", "profile_x: [0, 1, 2], profile_z: [0, 1, 0], stiffness: 100");
    for (x, slope) in [(0.5, 1.0), (1.5, -1.0)] {
        r.set(&[x, 5.0, 0.0, 0.0]);
        let s = r.output(0.0)[3];
        assert!((s - slope).abs() < 1e-6, "slope at {x}: {s}");
    }
    // The difference step grows with |x| (1e-9·|x|), so far out it still resolves the slope.
    let mut far = rig("contact", "profile_x: [0, 2e6], profile_z: [0, 2e5], stiffness: 100");
    far.set(&[1e6, 1e6, 0.0, 0.0]);
    let s = far.output(0.0)[3];
    assert!((s - 0.1).abs() < 1e-6, "{s}");
}

#[test]
fn feed_drive_and_reference_filter_by_hand() {
    // Je = 2, Be = 4 at v = 2: x'' = (u − d − Be·v)/Je = (5 − 1 − 8)/2 = −2 with d = 1, −1 with d = −1.
    let mut fd = rig("feed_drive", "je: 2, be: 4, initial: [3, 2], disturbance_input: true");
    assert_eq!(fd.x, vec![3.0, 2.0]);
    fd.set(&[5.0, 1.0]);
    assert_eq!(fd.derivatives(), vec![2.0, -2.0]);
    fd.set(&[5.0, -1.0]);
    assert_eq!(fd.derivatives(), vec![2.0, -1.0]);
    assert_eq!(fd.output(0.0), vec![3.0, 2.0]);
    // p'' = ωn²(u − p) − 2ζωn·p' from p = 1 at rest, u = 2, ωn = 10, ζ = 0.7: 100.
    let mut rf = rig("reference_filter", "omega: 10, zeta: 0.7, initial: 1");
    assert_eq!(rf.x, vec![1.0, 0.0]);
    rf.set(&[2.0]);
    assert_eq!(rf.output(0.0), vec![1.0, 0.0, 100.0]);
    assert_eq!(rf.derivatives(), vec![0.0, 100.0]);
    rf.x[1] = 1.0;
    assert_eq!(rf.derivatives(), vec![1.0, 100.0 - 14.0]);
}

#[test]
fn limited_integrator_functions_directions_and_clamping() {
    // Width 2 in [−1, 1], x = (0.5, −0.2), free: per element [x − upper, x − lower].
    let mut r = wide("integrator", "lower: -1, upper: 1, initial: [0.5, -0.2]", 2);
    assert_eq!(r.x, vec![0.5, -0.2]);
    r.set(&[1.0]);
    assert_eq!(r.zero_crossings(), vec![-0.5, 1.5, -1.2, 0.8]);
    let dirs = |r: &Rig| (0..4).map(|k| r.built.block.crossing_direction(k)).collect::<Vec<_>>();
    assert_eq!(dirs(&r), [Crossing::Rising, Crossing::Falling, Crossing::Rising, Crossing::Falling]);
    assert_eq!(r.derivatives(), vec![1.0, 1.0]);
    assert!(r.built.block.needs_major_step() && !r.built.block.updates());
    // At the upper limit pushing up: held there (derivative 0, functions = u, upper watched
    // falling), the other element free; pushing down at the lower limit holds it there.
    // At a major step the mode follows the state before major_step has run.
    r.x = vec![1.0, -0.2];
    assert_eq!(r.derivatives(), vec![0.0, 1.0]);
    assert!(!r.major_step());
    assert_eq!(r.derivatives(), vec![0.0, 1.0]);
    assert_eq!(r.zero_crossings(), vec![1.0, 1.0, -1.2, 0.8]);
    assert_eq!(dirs(&r), [Crossing::Falling, Crossing::Ignore, Crossing::Rising, Crossing::Falling]);
    r.x = vec![0.0, -1.0];
    r.set(&[-1.0]);
    r.major_step();
    assert_eq!(dirs(&r)[2..], [Crossing::Ignore, Crossing::Rising]);
    // In a solver stage the modes chosen at the major step hold.
    let io_minor = |r: &mut Rig| {
        let mut dx = vec![0.0; 2];
        let io = ctlgraph_core::Io::new(0.0, false, &r.x, &mut r.signals, &r.ins, &r.outs).in_minor_step(true);
        r.built.block.derivatives(&io, &mut dx);
        dx
    };
    r.set(&[1.0]);
    assert_eq!(io_minor(&mut r), vec![1.0, 0.0]);
    // A state past a limit is clamped back, and says so.
    let mut x = vec![1.5, 0.0];
    assert!(r.built.block.clamp_states(&mut x));
    assert_eq!(x, vec![1.0, 0.0]);
    assert!(!r.built.block.clamp_states(&mut x));
    // A major step that only clamps reports the change.
    r.x = vec![1.5, 0.0];
    assert!(r.major_step());
    assert_eq!(r.x, vec![1.0, 0.0]);
    // Unlimited and without ports it needs no major step.
    assert!(!wide("integrator", "", 2).built.block.needs_major_step());
    assert_eq!(wide("integrator", "", 3).x.len(), 3);
}

#[test]
fn external_initial_values_per_element_and_resets() {
    let mut r = wide("integrator", "initial_source: external, reset: rising", 2);
    assert_eq!(r.input_names(), ["u", "reset", "initial"]);
    r.set_port(2, &[3.0, 4.0]);
    // The first major step reads x(0) from the port, element by element.
    assert!(r.major_step());
    assert_eq!(r.x, vec![3.0, 4.0]);
    r.x = vec![7.0, 8.0];
    assert!(!r.major_step());
    // A located rising crossing of the reset resets to the port's values.
    assert_eq!(r.built.block.num_zero_crossings(), 1);
    assert_eq!(r.built.block.crossing_direction(0), Crossing::Rising);
    r.set_port(1, &[1.0]);
    r.built.block.crossing_located(0);
    assert!(r.major_step());
    assert_eq!(r.x, vec![3.0, 4.0]);
    // A located limit crossing is not a reset.
    let mut lim = wide("integrator", "lower: -1, upper: 1, reset: rising", 1);
    lim.set(&[0.0, 0.0]);
    lim.major_step();
    lim.x = vec![0.5];
    lim.built.block.crossing_located(0);
    assert!(!lim.major_step());
    assert_eq!(lim.x, vec![0.5]);
    lim.built.block.crossing_located(2);
    assert!(lim.major_step());
    assert_eq!(lim.x, vec![0.0]);
    // A scalar initial value broadcasts.
    let mut s = wide("integrator", "initial_source: external", 2);
    s.ins[1].width = 1;
    s.set_port(1, &[5.0]);
    assert!(s.major_step());
    assert_eq!(s.x, vec![5.0, 5.0]);
}
