//! The cutting force by hand at known angles and chips, the cut's edges as
//! events, and the mean force against Altintas' closed form.

use super::*;
use ctlgraph_core::block::Port;

/// Inputs x, y, x_τ, y_τ at 0–3; outputs fx, fy at 4, 5, then h, ft, fr
/// (width `TEETH` each).
const TEETH: usize = 3;
const IN: [Port; 4] = [
    Port { offset: 0, width: 1 },
    Port { offset: 1, width: 1 },
    Port { offset: 2, width: 1 },
    Port { offset: 3, width: 1 },
];
const OUT: [Port; 5] = [
    Port { offset: 4, width: 1 },
    Port { offset: 5, width: 1 },
    Port { offset: 6, width: TEETH },
    Port { offset: 6 + TEETH, width: TEETH },
    Port { offset: 6 + 2 * TEETH, width: TEETH },
];

fn cutter(teeth: usize, entry_deg: f64, exit_deg: f64, phase_deg: f64) -> Cutter {
    Cutter {
        teeth,
        omega: TAU * 6000.0 / 60.0,
        kt: 700.0,
        kr: 0.3,
        ap: 2.0,
        feed: 0.05,
        entry: entry_deg.to_radians(),
        exit: exit_deg.to_radians(),
        phase: phase_deg.to_radians(),
    }
}

fn block(cutter: Cutter, zero_crossing: bool) -> MillingForce {
    let n = cutter.teeth;
    MillingForce {
        cutter,
        zero_crossing,
        tooth_outputs: n == TEETH,
        in_cut: vec![false; n],
        chip_positive: vec![false; n],
    }
}

/// The outputs at `t` for inputs [x, y, x_τ, y_τ]: (fx, fy, h of each tooth).
fn eval(b: &mut MillingForce, t: f64, inputs: [f64; 4], minor: bool) -> (f64, f64, Vec<f64>) {
    let mut signals = [0.0; 6 + 3 * TEETH];
    signals[..4].copy_from_slice(&inputs);
    let n = b.cutter.teeth;
    let mut io = Io::new(t, false, &[], &mut signals, &IN, &OUT[..if n == TEETH { 5 } else { 2 }]);
    if minor {
        io = io.in_minor_step(true);
    }
    b.output(&mut io);
    (signals[4], signals[5], signals[6..6 + n].to_vec())
}

#[test]
fn one_tooth_at_sixty_degrees_by_hand() {
    // Slotting (0°–180°), tooth at 60°: h = 0.05·sin 60° = 0.0433013;
    // Ft = 700·2·h = 60.62178, Fr = 0.3·Ft = 18.18653,
    // Fx = −Ft·cos 60° − Fr·sin 60° = −46.06089, Fy = Ft·sin 60° − Fr·cos 60° = 43.40673.
    let mut b = block(cutter(1, 0.0, 180.0, 60.0), false);
    let (fx, fy, _) = eval(&mut b, 0.0, [0.0; 4], false);
    assert!((fx + 46.06088913245536).abs() < 1e-11 && (fy - 43.40673326026339).abs() < 1e-11, "{fx} {fy}");
    // With vibration: x − x_τ = 0.01 − 0.004 = 0.006, y − y_τ = −0.002 − 0.001 = −0.003:
    // h = 0.056·sin 60° − 0.003·cos 60° = 0.0469974, Ft = 65.79639, Fr = 19.73892.
    let (fx, fy, _) = eval(&mut b, 0.0, [0.01, -0.002, 0.004, 0.001], false);
    assert!((fx + 49.9925998239658).abs() < 1e-11 && (fy - 47.111887903547675).abs() < 1e-11, "{fx} {fy}");
}

#[test]
fn tooth_angles_advance_with_the_spindle() {
    // 6000 rpm = 100 rev/s: 1 ms later tooth 0 has turned 36°; tooth j leads by 120°·j.
    let c = cutter(3, 0.0, 90.0, 10.0);
    let deg = |j: usize, t: f64| c.angle(j, t).to_degrees();
    assert!((deg(0, 1e-3) - 46.0).abs() < 1e-9 && (deg(2, 0.0) - 250.0).abs() < 1e-9);
    assert!((c.tooth_period() - 1.0 / 300.0).abs() < 1e-18);
}

#[test]
fn no_force_outside_the_cut_and_none_from_a_negative_chip() {
    // Up-milling at half immersion: the cut spans 0°–90°. Teeth at 130°, 250° and 370° = 10°:
    // only tooth 2 cuts, h = 0.05·sin 10° + (y − y_τ)·cos 10° = 0.0185305 with y − y_τ = 0.01;
    // Ft = 1400·h, Fr = 0.3·Ft, Fx = −Ft·cos 10° − Fr·sin 10°, Fy = Ft·sin 10° − Fr·cos 10°.
    let mut b = block(cutter(3, 0.0, 90.0, 130.0), false);
    let (fx, fy, h) = eval(&mut b, 0.0, [0.0, 0.01, 0.0, 0.0], false);
    assert_eq!(h[..2], [0.0, 0.0]);
    assert!((h[2] - 0.0185304864134686).abs() < 1e-15, "{h:?}");
    assert!((fx + 26.90002314463163).abs() < 1e-11 && (fy + 3.1596667327970422).abs() < 1e-11, "{fx} {fy}");
    // The tooth pulled out of the material (y − y_τ = −0.02, h = −0.011): no chip, no force.
    let (fx, fy, h) = eval(&mut b, 0.0, [0.0, -0.02, 0.0, 0.0], false);
    assert_eq!((fx, fy), (0.0, 0.0));
    assert_eq!(h, vec![0.0; 3]);
}

#[test]
fn under_zero_crossing_the_chip_sign_is_frozen_in_minor_steps() {
    let mut b = block(cutter(3, 0.0, 90.0, 130.0), true);
    // Major step: tooth 2 cuts a positive chip.
    eval(&mut b, 0.0, [0.0, 0.01, 0.0, 0.0], false);
    // A solver stage where the chip went negative keeps the cutting formula:
    // h = 0.05·sin 10° − 0.02·cos 10° = −0.0110137 …
    let (_, _, h) = eval(&mut b, 0.0, [0.0, -0.02, 0.0, 0.0], true);
    assert!((h[2] + 0.011013746176897644).abs() < 1e-15, "{h:?}");
    // … and the crossing function says so: g = the unclipped chip, watched only for tooth 2.
    let mut signals = [0.0, -0.02, 0.0, 0.0, 0.0, 0.0];
    let io = Io::new(0.0, false, &[], &mut signals, &IN, &OUT[..2]);
    let mut g = [1.0; 3];
    b.zero_crossings(&io, &mut g);
    assert_eq!(g[..2], [0.0, 0.0]);
    assert!((g[2] + 0.011013746176897644).abs() < 1e-15);
    assert_eq!(
        [b.crossing_direction(0), b.crossing_direction(1), b.crossing_direction(2)],
        [Crossing::Ignore, Crossing::Ignore, Crossing::Either]
    );
    // The next major step switches it off.
    let (fx, fy, h) = eval(&mut b, 0.0, [0.0, -0.02, 0.0, 0.0], false);
    assert_eq!((fx, fy, h[2]), (0.0, 0.0, 0.0));
    assert_eq!(b.num_zero_crossings(), 3);
    assert_eq!(block(cutter(3, 0.0, 90.0, 0.0), false).num_zero_crossings(), 0);
}

#[test]
fn entries_and_exits_are_the_events_one_tooth_period_apart() {
    // 3 teeth at 100 rev/s, cut 0°–90°, tooth 0 at 0° at t = 0. Tooth 0 leaves at 2.5 ms;
    // tooth 2 (at 240°) enters at 120°/Ω = 3.333 ms and leaves 2.5 ms later; tooth 1 enters
    // at 6.667 ms: entries τ = 1/300 s apart, each exit 2.5 ms after its entry.
    let b = block(cutter(3, 0.0, 90.0, 0.0), true);
    let tau = 1.0 / 300.0;
    let mut expected = vec![];
    for m in 0..6 {
        expected.push(m as f64 * tau + 2.5e-3);
        expected.push((m + 1) as f64 * tau);
    }
    expected.sort_by(f64::total_cmp);
    let mut t = 0.0;
    for e in expected {
        t = b.next_event(t);
        assert!((t - e).abs() < 1e-15, "{t} vs {e}");
    }
    assert!((b.min_event_spacing() - (tau - 2.5e-3)).abs() < 1e-15);
    // Slotting with two teeth: each exit coincides with the other tooth's entry.
    let slot = block(cutter(2, 0.0, 180.0, 0.0), true);
    assert!((slot.min_event_spacing() - slot.cutter.tooth_period()).abs() < 1e-15);
}

#[test]
fn at_an_event_the_left_limit_is_before_it() {
    // Tooth 0 leaves at t_exit: the solver's last stage (left limit) still sees it cutting,
    // the major step at t_exit does not.
    let mut b = block(cutter(3, 0.0, 90.0, 0.0), false);
    let t_exit = b.next_event(0.0);
    let mut signals = [0.0; 6 + 3 * TEETH];
    let mut io = Io::new(t_exit, true, &[], &mut signals, &IN, &OUT);
    b.output(&mut io);
    assert!(signals[6] > 0.049, "left limit: h = {}", signals[6]);
    let mut io = Io::new(t_exit, false, &[], &mut signals, &IN, &OUT);
    b.output(&mut io);
    assert_eq!(signals[6], 0.0);
}

#[test]
fn mean_force_over_a_tooth_period_is_altintas() {
    // Slotting: F̄x = −N·ap·ft·Krc/4, F̄y = N·ap·ft·Kt/4 (the closed form at 0 and π).
    let slot = cutter(3, 0.0, 180.0, 0.0);
    let (fx, fy) = slot.mean_force();
    assert!((fx + 3.0 * 2.0 * 0.05 * 210.0 / 4.0).abs() < 1e-12 && (fy - 3.0 * 2.0 * 0.05 * 700.0 / 4.0).abs() < 1e-12);
    // The block's own force, averaged over a tooth period by the midpoint rule, for up- and
    // down-milling at partial immersion (the closed form holds while sin φ >= 0 in the cut).
    for (entry, exit) in [(0.0, 75.0), (110.0, 180.0), (0.0, 180.0), (30.0, 150.0)] {
        let mut b = block(cutter(TEETH, entry, exit, 7.0), false);
        let n = 20_000;
        let tau = b.cutter.tooth_period();
        let (mut sx, mut sy) = (0.0, 0.0);
        for i in 0..n {
            let (fx, fy, _) = eval(&mut b, (i as f64 + 0.5) * tau / n as f64, [0.0; 4], false);
            sx += fx / n as f64;
            sy += fy / n as f64;
        }
        let (mx, my) = b.cutter.mean_force();
        let scale = mx.abs().max(my.abs());
        assert!(
            (sx - mx).abs() < 1e-3 * scale && (sy - my).abs() < 1e-3 * scale,
            "{entry}–{exit}: ({sx}, {sy}) vs ({mx}, {my})"
        );
    }
}

/// Whether tooth `j` cuts at `t`, from its angle (away from the cut's edges).
fn cuts(c: &Cutter, j: usize, t: f64) -> bool {
    (c.angle(j, t) - c.entry).rem_euclid(TAU) < c.exit - c.entry
}

#[test]
fn far_into_the_run_every_event_is_an_edge_and_each_side_is_right() {
    // Ten seconds in (about 1000 revolutions), 300 events of a 3-tooth cutter with an odd
    // phase, up-milling-like (20°–110°) and down-milling (150°–180°, 200°–300°): at each event
    // time the major step sees the state just after it, the solver's left limit the state
    // just before, tooth by tooth.
    for (entry, exit) in [(20.0, 110.0), (150.0, 180.0), (200.0, 300.0)] {
        let b = block(cutter(3, entry, exit, 17.0), true);
        let c = &b.cutter;
        let tiny = 1e-6 * c.tooth_period();
        let mut t = 10.0;
        for _ in 0..300 {
            let e = b.next_event(t);
            assert!(e > t && e - t <= c.tooth_period(), "{t} -> {e}");
            let mut changed = false;
            for j in 0..3 {
                let (before, after) = (cuts(c, j, e - tiny), cuts(c, j, e + tiny));
                changed |= before != after;
                let mut signals = [0.0; 6];
                let left = Io::new(e, true, &[], &mut signals, &IN, &OUT[..2]);
                assert_eq!(c.cutting(j, &left), before, "{entry}–{exit}: tooth {j} before {e}");
                let major = Io::new(e, false, &[], &mut signals, &IN, &OUT[..2]);
                assert_eq!(c.cutting(j, &major), after, "{entry}–{exit}: tooth {j} at {e}");
            }
            assert!(changed, "{entry}–{exit}: nothing happens at {e}");
            t = e;
        }
    }
    // Cut 90° of a 120° pitch: exits 90° after entries, 30° before the next entry.
    let b = block(cutter(3, 20.0, 110.0, 17.0), true);
    assert!((b.min_event_spacing() - 30f64.to_radians() / b.cutter.omega).abs() < 1e-15);
}

#[test]
fn a_chip_of_exactly_zero_starts_clear() {
    // Up-milling, tooth 0 entering at t = 0: h = ft·sin 0 + (y − y_τ)·cos 0 = 0 at the major step,
    // so the tooth is not cutting until a major step sees a positive chip.
    let mut b = block(cutter(3, 0.0, 90.0, 0.0), true);
    let (_, _, h) = eval(&mut b, 0.0, [0.0; 4], false);
    assert_eq!(h[0], 0.0);
    let (_, _, h) = eval(&mut b, 0.0, [0.0, 0.01, 0.0, 0.0], true);
    assert_eq!(h[0], 0.0);
    assert!(!b.updates());
    assert!(b.not_linearizable().is_some_and(|why| why.contains("periodic")));
}

#[test]
fn immersion_from_milling_mode_or_angles() {
    let angles = |params: &str| crate::test_rig::with_params("milling_force", params, immersion_angles);
    let deg = |r: Result<(f64, f64), Diagnostic>| r.map(|(a, b)| (a.to_degrees(), b.to_degrees())).unwrap();
    for (params, (entry, exit)) in [
        ("immersion: 0.5", (0.0, 90.0)),
        ("milling: down, immersion: 0.5", (90.0, 180.0)),
        ("immersion: 0.25", (0.0, 60.0)),
        ("milling: down, immersion: 0.25", (120.0, 180.0)),
        ("", (0.0, 180.0)),
        ("entry: 30, exit: 100", (30.0, 100.0)),
    ] {
        let (a, b) = deg(angles(params));
        assert!((a - entry).abs() < 1e-9 && (b - exit).abs() < 1e-9, "{params}: {a} {b}");
    }
    let only_exit = angles("exit: 90").unwrap_err();
    assert!(only_exit.to_string().contains("`entry`"), "{only_exit}");
}

#[test]
fn built_from_yaml_speed_and_radial_coefficient() {
    use crate::test_rig::{Rig, build};
    // One tooth at 600 rpm (10 rev/s) cutting 0°–90°, at 60° at t = 0: it leaves 30° later, at 1/120 s.
    let base = "teeth: 1, rpm: 600, kt: 700, ap: 2, ft: 0.05, entry: 0, exit: 90, phase: 60";
    let mut by_ratio = Rig::new(build("milling_force", &format!("{base}, kr: 0.3")).unwrap());
    let mut by_coefficient = Rig::new(build("milling_force", &format!("{base}, krc: 210")).unwrap());
    assert!((by_ratio.built.block.next_event(0.0) - (30.0 / 360.0) / 10.0).abs() < 1e-15);
    // Kr = krc/kt = 0.3: the force of `one_tooth_at_sixty_degrees_by_hand`.
    let (a, b) = (by_ratio.output(0.0), by_coefficient.output(0.0));
    assert!((a[0] + 46.06088913245536).abs() < 1e-11 && (a[1] - 43.40673326026339).abs() < 1e-11, "{a:?}");
    assert!((a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12, "{a:?} {b:?}");
}

#[test]
fn a_full_turn_of_cut_never_lets_go() {
    // entry 0°, exit 360°: each exit would be the next entry, computed by another formula and
    // possibly an ulp apart. Such a cut has no edges at all: always cutting, no events.
    let b = block(cutter(1, 0.0, 360.0, 0.0), false);
    assert_eq!((b.next_event(1.0), b.min_event_spacing()), (f64::INFINITY, f64::INFINITY));
    let c = &b.cutter;
    for k in 0..50 {
        let t = c.entry_time(0, 100.0 + k as f64);
        for left in [true, false] {
            let mut signals = [0.0; 6];
            let io = Io::new(t, left, &[], &mut signals, &IN, &OUT[..2]);
            assert!(c.cutting(0, &io), "t = {t}, left limit {left}");
        }
    }
    // A cut one degree short of a turn still has its edges.
    let short = block(cutter(1, 0.0, 359.0, 0.0), false);
    assert!(short.next_event(1.0) < 1.0 + short.cutter.tooth_period());
}
