//! The s_curve block in graphs: its feed integrates to its length, the
//! curvature limits lower the feed, mistakes are named, and (property) the
//! limits hold for any path and limits.

mod common;
use common::{ctlgraph, error, run, text};
use proptest::prelude::*;

fn graph(params: &str, stop: f64) -> String {
    format!(
        "simulation: {{ stop: {stop}, solver: {{ method: rk4, step: 1.0e-3 }} }}\n\
         blocks:\n  plan: {{ type: s_curve, {params} }}\n  x: {{ type: integrator }}\n\
         wires: [plan.f -> x]\nrecord: [f: plan.f, a: plan.a, s: plan.s, x]\n"
    )
}

#[test]
fn the_feed_integrates_to_the_travelled_length() {
    // A 30° arc of radius 400 mm at up to 20 mm/s, as the paper's test.
    let length = 400.0 * std::f64::consts::PI / 6.0;
    let trace = run(&graph(&format!("length: {length}, feed: 20, accel: 100, jerk: 1000, start: 0.5"), 12.0));
    let (f, s, x) = (trace.column("f").unwrap(), trace.column("s").unwrap(), trace.column("x").unwrap());
    // RK4 integrates the piecewise-cubic s exactly between events.
    for (k, (&si, &xi)) in s.iter().zip(x).enumerate() {
        assert!((si - xi).abs() < 1e-9, "t = {}: s {si} vs ∫f {xi}", trace.t()[k]);
    }
    assert_eq!(f.iter().copied().fold(0.0, f64::max), 20.0);
    assert_eq!(*s.last().unwrap(), length);
    assert!(trace.at("s", 0.5).unwrap() == 0.0 && trace.at("f", 0.4).unwrap() == 0.0);
}

#[test]
fn curvature_limits_lower_the_feed() {
    // Normal acceleration 0.5 mm/s² on ρ = 400 mm: f <= sqrt(200) mm/s.
    let trace = run(&graph("length: 100, feed: 20, accel: 100, jerk: 1000, radius: 400, accel_normal: 0.5", 12.0));
    let peak = trace.column("f").unwrap().iter().copied().fold(0.0, f64::max);
    assert!((peak - 200f64.sqrt()).abs() < 1e-12, "{peak}");
}

#[test]
fn mistakes_are_named_at_their_key() {
    let e = error(&graph("length: 1, feed: 1, accel: 1, jerk: 1, omega: 0.1", 1.0));
    assert!(e.to_string().contains("`omega`: a curvature limit needs the path's `radius`"), "{e}");
    let e = error(&graph("length: 1, feed: 1, accel: 1, jerk: 1, radius: 5, tc: 0.002", 1.0));
    assert!(e.to_string().contains("`tc`: the chord-error limit needs both `tc` and `chord_error`"), "{e}");
    let e = error(&graph("length: 1, feed: 1, accel: 1, jerk: 1, radius: 5, tc: 0.002, chord_error: 5", 1.0));
    assert!(e.to_string().contains("`chord_error`: must be less than the radius 5"), "{e}");
    let e = error(&graph("length: 0, feed: 1, accel: 1, jerk: 1", 1.0));
    assert!(e.to_string().contains("`length`: must be a positive number"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    /// Any path and limits: feed, acceleration within their limits, the
    /// length travelled monotonically and reached exactly, at rest at the end.
    #[test]
    fn the_limits_hold(length in 0.01..500.0f64, feed in 0.5..50.0f64, accel in 1.0..500.0f64, jerk in 5.0..5000.0f64) {
        let p = ctlgraph::blocks::motion::SCurve::plan(length, feed, accel, jerk);
        let stop = p.duration + 0.01;
        let trace = run(&graph(&format!("length: {length:e}, feed: {feed:e}, accel: {accel:e}, jerk: {jerk:e}"), stop));
        let (f, a, s) = (trace.column("f").unwrap(), trace.column("a").unwrap(), trace.column("s").unwrap());
        prop_assert!(f.iter().all(|&v| (0.0..=feed * (1.0 + 1e-12)).contains(&v)));
        prop_assert!(a.iter().all(|&v| v.abs() <= accel * (1.0 + 1e-12)));
        prop_assert!(s.windows(2).all(|w| w[1] >= w[0] - 1e-12 * length));
        prop_assert_eq!(*s.last().unwrap(), length);
        prop_assert_eq!(*f.last().unwrap(), 0.0);
        // Time-optimal for its peak: the duration is the rest-to-rest minimum.
        let ramp = if p.peak_feed <= accel * accel / jerk { 2.0 * (p.peak_feed / jerk).sqrt() } else { p.peak_feed / accel + accel / jerk };
        prop_assert!((p.duration - (length / p.peak_feed + ramp)).abs() < 1e-9 * p.duration);
    }
}

#[test]
fn the_support_point_is_across_the_wall_along_the_axis() {
    // p = (400, 0, 10), n = (3, 4, 0) (not unit), H = 5, d = 1: q = p + 4·(0.6, 0.8, 0).
    let yaml = "simulation: { stop: 0.01, solver: { method: rk4, step: 1.0e-3 } }\n\
                blocks:\n  p: { type: constant, value: [400, 0, 10] }\n  n: { type: constant, value: [3, 4, 0] }\n  \
                q: { type: mirror_offset, thickness: 5, depth: 1 }\n\
                wires: [p -> q.p, n -> q.n]\nrecord: [q]\n";
    let trace = run(yaml);
    let q: Vec<f64> = (1..=3).map(|k| *trace.column(&format!("q[{k}]")).unwrap().last().unwrap()).collect();
    assert_eq!(q, [402.4, 3.2, 10.0]);
    let stopped = ctlgraph::simulate(
        ctlgraph::compile_str(&yaml.replace("[3, 4, 0]", "[0, 0, 0]"), "t.yaml", &[]).unwrap(),
        None,
    );
    let message = stopped.unwrap_err().to_string();
    assert!(message.contains("block `q`") && message.contains("the tool axis n has zero length"), "{message}");
    let e = error(&yaml.replace("depth: 1", "depth: 5"));
    assert!(e.to_string().contains("`depth`: must be in [0, thickness)"), "{e}");
}

#[test]
fn a_fitted_arc_and_its_paired_axis_curve() {
    // The paper's machining-side arc (ρ = 400 mm, 30°) and a point 50 mm up
    // the tool axis on a 450 mm arc: P and O stay paired at every u.
    let yaml = "simulation: { stop: 1.0, solver: { method: rk4, step: 1.0e-2 } }\n\
                blocks:\n  u: { type: ramp, slope: 1 }\n  \
                path: { type: bspline_path, curve: [\"400*cos(v)\", \"400*sin(v)\", \"0\"], range: [0, \"pi/6\"],\n          \
                axis_curve: [\"450*cos(v)\", \"450*sin(v)\", \"50\"], samples: 60, control_points: 15 }\n\
                wires: [u -> path]\nrecord: [p: path.p, dp: path.dp, o: path.o]\n";
    let trace = run(yaml);
    let col = |name: &str| trace.column(name).unwrap().to_vec();
    let (px, py, ox, oy, oz) = (col("p[1]"), col("p[2]"), col("o[1]"), col("o[2]"), col("o[3]"));
    for k in 0..px.len() {
        assert!(((px[k] * px[k] + py[k] * py[k]).sqrt() - 400.0).abs() < 1e-5, "k {k}");
        assert!((py[k].atan2(px[k]) - oy[k].atan2(ox[k])).abs() < 1e-7, "paired at k {k}");
        assert!((oz[k] - 50.0).abs() < 1e-9);
    }
    assert!(
        py[0].abs() < 1e-12
            && (py.last().unwrap().atan2(*px.last().unwrap()) - std::f64::consts::PI / 6.0).abs() < 1e-12
    );
    // dP/du is the chord length of the samples along the tangent.
    let (dx, dy) = (col("dp[1]"), col("dp[2]"));
    let arc = 400.0 * std::f64::consts::PI / 6.0;
    assert!(dx.iter().zip(&dy).all(|(a, b)| ((a * a + b * b).sqrt() - arc).abs() < 1e-3 * arc));
}

#[test]
fn path_mistakes_are_named() {
    let base =
        "blocks:\n  u: { type: constant, value: 0.5 }\n  path: { type: bspline_path, PARAMS }\nwires: [u -> path]\n";
    let e = error(&base.replace("PARAMS", "points: [[0, 0], [1, 1], [2, 0], [3, 1]], curve: [\"v\", \"v\"]"));
    assert!(e.to_string().contains("`curve`: give one of `points`, `curve`, `csv`"), "{e}");
    let e = error(&base.replace("PARAMS", "points: [[0], [1], [2], [3]]"));
    assert!(e.to_string().contains("every point needs 2 or 3 coordinates"), "{e}");
    let e = error(&base.replace("PARAMS", "points: [[0, 0], [1, 1], [2, 0], [3, 1]], axis_points: [[0, 1], [1, 2]]"));
    assert!(e.to_string().contains("`axis_points`: give 4 points of 2 coordinates"), "{e}");
    let e = error(&base.replace("PARAMS", "curve: [\"cos(w)\", \"v\"]"));
    assert!(e.to_string().contains("`curve`: `cos(w)`"), "{e}");
    let e = error(&base.replace("PARAMS", "points: [[0, 0], [0, 0], [2, 0], [3, 1]]"));
    assert!(e.to_string().contains("two consecutive points are equal"), "{e}");
}

/// The paper's chain on its machining-side arc: S-curve feed → Taylor
/// interpolation of u every Tc = 2 ms → the fitted path.
const ARC_CHAIN: &str = "simulation: { stop: 12, solver: { method: rk4, step: 2.0e-3 } }\n\
    parameters: { radius: 400, angle: 0.5235987755982988 }\n\
    blocks:\n  plan: { type: s_curve, length: \"radius*angle\", feed: 20, accel: 100, jerk: 1000 }\n  \
    path: { type: bspline_path, curve: [\"radius*cos(v)\", \"radius*sin(v)\", \"0\"], range: [0, angle], samples: 60, control_points: 15 }\n  \
    interp: { type: path_interpolator, sample_time: 2.0e-3 }\n\
    wires: [plan.f -> interp.f, plan.a -> interp.a, path.dp -> interp.dp, path.ddp -> interp.ddp, interp -> path]\n\
    record: [s: plan.s, u: interp, p: path.p]\n";

#[test]
fn the_interpolated_point_follows_the_planned_length() {
    let trace = run(ARC_CHAIN);
    let (s, u) = (trace.column("s").unwrap(), trace.column("u").unwrap());
    let (x, y) = (trace.column("p[1]").unwrap(), trace.column("p[2]").unwrap());
    // The arc length travelled (angle × radius) against the planned s, at
    // the interpolator's hits (between them u holds while s moves on; the
    // feed profile's own events add major steps there).
    let mut worst: f64 = 0.0;
    for (k, &t) in trace.t().iter().enumerate() {
        if ((t / 2.0e-3).round() * 2.0e-3 - t).abs() < 1e-12 {
            worst = worst.max((400.0 * y[k].atan2(x[k]) - s[k]).abs());
        }
    }
    // 7e-5 mm: the third-order term the expansion drops, J·Tc³/6 = 1.3e-6 mm
    // a step, summed over a jerk phase of 50 steps (elsewhere some 1e-8 mm).
    assert!(worst < 1e-4, "{worst} mm");
    assert!((1.0 - u.last().unwrap()).abs() < 1e-6, "u ends at {}", u.last().unwrap());
    assert!(u.windows(2).all(|w| w[1] >= w[0]));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// On a straight path at constant feed, u advances by f·Tc/L a period
    /// and stops at 1; for any feed and acceleration signs it stays in
    /// [0, 1] and never moves back.
    #[test]
    fn the_interpolator_advances_monotonically(
        (dx, dy) in (-50.0..50.0f64, 1.0..50.0f64),
        feed in 0.1..40.0f64,
        accel in -50.0..50.0f64,
        tc in 1.0e-3..1.0e-2f64,
    ) {
        let yaml = format!(
            "simulation: {{ stop: 1.0, solver: {{ method: rk4, step: {tc:e} }} }}\n\
             blocks:\n  f: {{ type: constant, value: {feed:e} }}\n  a: {{ type: constant, value: 0 }}\n  \
             d1: {{ type: constant, value: [{dx:e}, {dy:e}] }}\n  d2: {{ type: constant, value: [0, 0] }}\n  \
             i: {{ type: path_interpolator, sample_time: {tc:e} }}\n\
             wires: [f -> i.f, a -> i.a, d1 -> i.dp, d2 -> i.ddp]\nrecord: [u: i]\n"
        );
        let trace = run(&yaml);
        let length = (dx * dx + dy * dy).sqrt();
        for (&t, &u) in trace.t().iter().zip(trace.column("u").unwrap()) {
            let j = (t / tc + 1e-9).floor();
            prop_assert!((u - (j * feed * tc / length).min(1.0)).abs() < 1e-9, "t {t}: u {u}");
        }
        let varying = yaml.replace("a: { type: constant, value: 0 }", &format!("a: {{ type: sine, amplitude: {accel:e}, frequency: 3 }}"));
        let u = run(&varying).column("u").unwrap().to_vec();
        prop_assert!(u.iter().all(|v| (0.0..=1.0).contains(v)) && u.windows(2).all(|w| w[1] >= w[0]));
    }
}

/// The paper's synchronisation test: arcs of 400 mm (machining) and 500 mm
/// (support) over 30°, the machining feed up to 20 mm/s.
fn mirror_plan(extra: &str) -> String {
    format!(
        "simulation: {{ stop: 12, solver: {{ method: rk4, step: 2.0e-3 }} }}\n\
         blocks:\n  plan: {{ type: mirror_feed_plan, range: [0, \"pi/6\"], samples: 60, control_points: 15,\n    \
         curve: [\"400*cos(v)\", \"400*sin(v)\", \"0\"], support_curve: [\"500*cos(v)\", \"500*sin(v)\", \"0\"],\n    \
         feed: 20, accel: 100, jerk: 1000, sample_time: 2.0e-3{extra} }}\n\
         record: [u: plan.u, f1: plan.f1, f2: plan.f2, lambda: plan.lambda, p: plan.p, q: plan.q]\n"
    )
}

#[test]
fn mirrored_arcs_feed_in_the_ratio_of_their_radii_and_finish_together() {
    let trace = run(&mirror_plan(""));
    let col = |n: &str| trace.column(n).unwrap().to_vec();
    let (f1, f2, lambda, u) = (col("f1"), col("f2"), col("lambda"), col("u"));
    let peak = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    assert!((peak(&f1) - 20.0).abs() < 1e-12 && (peak(&f2) - 25.0).abs() < 0.25, "{} {}", peak(&f1), peak(&f2));
    assert!(lambda.iter().all(|l| (l - 1.25).abs() < 1e-4), "λ within 1e-4 of 500/400");
    // The same u on both sides: mirrored points at the same angle, and both
    // reach the end (u = 1) in the same period.
    let (px, py, qx, qy) = (col("p[1]"), col("p[2]"), col("q[1]"), col("q[2]"));
    for k in 0..u.len() {
        assert!((py[k].atan2(px[k]) - qy[k].atan2(qx[k])).abs() < 1e-7);
    }
    // Where the machining side stops, u is at the end and the support side stops too.
    let end = (1..f1.len()).find(|&k| f1[k] == 0.0).expect("stops");
    assert!((1.0 - u[end]).abs() < 1e-6 && f2[end..].iter().all(|&f| f == 0.0), "u {}", u[end]);
}

#[test]
fn a_support_feed_limit_lowers_the_machining_feed() {
    // f2 <= 22 mm/s with λ = 1.25: f1 at most 17.6.
    let trace = run(&mirror_plan(", support_feed: 22"));
    let peak = |n: &str| trace.column(n).unwrap().iter().copied().fold(0.0, f64::max);
    let (f1, f2) = (peak("f1"), peak("f2"));
    assert!(f2 <= 22.0 * (1.0 + 1e-12) && f2 > 22.0 * 0.99 * 0.999, "f2 {f2}");
    assert!(f1 <= 17.6 * 1.0001 && f1 > 17.6 * 0.99 * 0.999, "f1 {f1}");
    let e = error(&mirror_plan(", support_feed: 1e-9"));
    assert!(e.to_string().contains("keeps the support side within its limits"), "{e}");
}

#[test]
fn check_reports_what_the_planners_decided() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("plan.yaml");
    let yaml = mirror_plan(", support_feed: 22").replace(
        "blocks:\n",
        "blocks:\n  feed: { type: s_curve, length: 100, feed: 20, accel: 100, jerk: 1000, radius: 400, accel_normal: 0.5 }\n",
    );
    std::fs::write(&file, yaml).unwrap();
    let out = ctlgraph(&["check", file.to_str().unwrap()]);
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("feed: peak feed 14.142136 (the curvature limits lower `feed` 20 to 14.142136)"),
        "{stdout}"
    );
    assert!(
        stdout.contains("plan: machining feed limit lowered to 17.6 in 1 re-plan(s) for the support side's limits; f1 peaks at 17.6, f2 at 22;"),
        "{stdout}"
    );
}

#[test]
fn points_from_a_csv_file_fit_as_inline_points() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("arc.csv");
    let rows: Vec<String> = (0..30)
        .map(|k| {
            let a = std::f64::consts::PI / 6.0 * k as f64 / 29.0;
            format!("{},{},{}", 400.0 * a.cos(), 400.0 * a.sin(), 1.5)
        })
        .collect();
    std::fs::write(&csv, format!("x,y,z\n{}\n", rows.join("\n"))).unwrap();
    let inline: Vec<String> = rows.iter().map(|r| format!("[{r}]")).collect();
    let graph = |source: &str| {
        format!(
            "simulation: {{ stop: 1, solver: {{ method: rk4, step: 0.05 }} }}\n\
             blocks:\n  u: {{ type: ramp }}\n  path: {{ type: bspline_path, {source}, control_points: 10 }}\n\
             wires: [u -> path]\nrecord: [p: path.p, dp: path.dp]\n"
        )
    };
    let from_csv = run(&graph(&format!("csv: \"{}\"", csv.display())));
    let from_list = run(&graph(&format!("points: [{}]", inline.join(", "))));
    for name in ["p[1]", "p[2]", "p[3]", "dp[1]", "dp[2]"] {
        assert_eq!(from_csv.column(name).unwrap(), from_list.column(name).unwrap(), "{name}");
    }
    let e = error(&graph(&format!("csv: \"{}\", columns: [x, y, w]", csv.display())));
    assert!(e.to_string().contains("has no column `w` (columns: x, y, z)"), "{e}");
}

#[test]
fn the_plans_feed_forward_is_tangent_and_centripetal() {
    let yaml = mirror_plan("").replace("record: [", "record: [pv: plan.pv, pa: plan.pa, qv: plan.qv, qa: plan.qa, ");
    let trace = run(&yaml);
    let col = |n: &str| trace.column(n).unwrap().to_vec();
    let (f1, f2, px, py, qx, qy) = (col("f1"), col("f2"), col("p[1]"), col("p[2]"), col("q[1]"), col("q[2]"));
    let (vx, vy, ax, ay) = (col("pv[1]"), col("pv[2]"), col("pa[1]"), col("pa[2]"));
    let (wx, wy, bx, by) = (col("qv[1]"), col("qv[2]"), col("qa[1]"), col("qa[2]"));
    for k in 0..f1.len() {
        // |v| is the feed, along the arc (perpendicular to the radius).
        assert!(((vx[k] * vx[k] + vy[k] * vy[k]).sqrt() - f1[k]).abs() < 1e-9);
        assert!(((wx[k] * wx[k] + wy[k] * wy[k]).sqrt() - f2[k]).abs() < 1e-9);
        let (r1, r2) = ((px[k] * px[k] + py[k] * py[k]).sqrt(), (qx[k] * qx[k] + qy[k] * qy[k]).sqrt());
        assert!((vx[k] * px[k] + vy[k] * py[k]).abs() < 1e-6 * r1 * (1.0 + f1[k]));
        // The radial acceleration is centripetal: −f²/ρ.
        let radial1 = (ax[k] * px[k] + ay[k] * py[k]) / r1;
        let radial2 = (bx[k] * qx[k] + by[k] * qy[k]) / r2;
        assert!((radial1 + f1[k] * f1[k] / 400.0).abs() < 1e-4 * (1.0 + f1[k] * f1[k] / 400.0), "k {k}: {radial1}");
        assert!((radial2 + f2[k] * f2[k] / 500.0).abs() < 1e-4 * (1.0 + f2[k] * f2[k] / 500.0), "k {k}: {radial2}");
        // Tangentially, ḟ2 = λ·ḟ1 with λ = 1.25 on concentric arcs (0 at rest).
        let (tangential1, tangential2) = ((ay[k] * px[k] - ax[k] * py[k]) / r1, (by[k] * qx[k] - bx[k] * qy[k]) / r2);
        assert!((tangential2 - 1.25 * tangential1).abs() < 1e-3 * (1.0 + tangential1.abs()), "k {k}");
    }
}

#[test]
fn a_plan_that_starts_later_is_the_same_plan_shifted() {
    // 0.1 s = 50 periods: both sides hold their first points until then.
    let now = run(&mirror_plan(""));
    let later = run(&mirror_plan(", start: 0.1"));
    let shift = 50;
    for name in ["u", "f1", "f2", "p[1]", "q[2]"] {
        let (a, b) = (now.column(name).unwrap(), later.column(name).unwrap());
        assert!(b[..=shift].iter().all(|&v| v == a[0]), "{name} held before the start");
        assert_eq!(&b[shift..], &a[..a.len() - shift], "{name} shifted by 50 periods");
    }
    let e = error(&mirror_plan(", start: 0.003"));
    assert!(e.to_string().contains("not a whole number of periods of 0.002 s"), "{e}");
}
