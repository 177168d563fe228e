//! The step loop allocates nothing: a counting global allocator watches a
//! compiled graph with a transfer function, PIDs, discrete blocks, noise,
//! the ADRC blocks and a fuzzy system step thousands of times, recorder
//! included; and another with events, modes and delays under the explicit
//! and the implicit solver.

use ctlgraph::record::Recorder;
use ctlgraph_core::Simulator;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    static ENABLED: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // `try_with`: thread-locals may be gone while a thread shuts down.
        let _ = ENABLED.try_with(|on| {
            if on.get() {
                let _ = COUNT.try_with(|c| c.set(c.get() + 1));
            }
        });
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ENABLED.try_with(|on| {
            if on.get() {
                let _ = COUNT.try_with(|c| c.set(c.get() + 1));
            }
        });
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

const GRAPH: &str = "
simulation: { stop: 1000.0, solver: SOLVER }
blocks:
  r:     { type: pulse, period: 0.5 }
  e:     { type: sum, signs: \"+-\" }
  pid:   { type: pid, kp: 2, ki: 5, kd: 0.05, n: 100, lower: -3, upper: 3 }
  dpid:  { type: pid, kp: 1, ki: 2, sample_time: 1.0e-3 }
  plant: { type: transfer_function, num: [100], den: [1, 10, 100] }
  delay: { type: unit_delay, sample_time: 2.0e-3 }
  dtf:   { type: discrete_transfer_function, num: [0.1], den: [1, -0.9], sample_time: 5.0e-3 }
  f:     { type: fcn, inputs: 2, expr: \"u1 + 0.1*sin(u2)\" }
  sat:   { type: saturation, lower: -2, upper: 2 }
  rl:    { type: rate_limiter, rising: 50, falling: -50 }
  noise: { type: band_limited_white_noise, power: 1.0e-6, sample_time: 1.0e-3, active: [0.2, 0.8] }
  td:    { type: tracking_differentiator, delta: 100, sample_time: 1.0e-3 }
  leso:  { type: leso, omega: 200, b0: 100, sample_time: 1.0e-3 }
  lsef:  { type: lsef, alpha: [1, 0.1], b0: 100, gain_inputs: [alpha1] }
  z:     { type: demux, outputs: 3 }
  tune:
    type: fuzzy
    inputs: { a: { range: [-1, 1], terms: 7 }, b: { range: [-1, 1], terms: 3 } }
    outputs: { k: { range: [-0.2, 0.2], terms: 5 } }
    rules:
      - if a is NB and b is N then k is NB
      - if a is ZO or b is Z then k is ZO
      - if a is PB and b is not N then k is PB
  k1:    { type: fcn, expr: \"1 + u\" }
wires: [r -> e.u1, plant -> e.u2, e -> pid, pid -> f.u1, plant -> f.u2, f -> sat, sat -> rl, rl -> plant,
        e -> dpid, plant -> delay, delay -> dtf, r -> td, td.r1 -> lsef.r1, td.r2 -> lsef.r2, plant -> leso.y,
        lsef -> leso.u, leso -> lsef.z, leso -> z, z.y1 -> tune.a, noise -> tune.b, tune -> k1, k1 -> lsef.alpha1]
record: [r, y: plant, u: pid, dpid, dtf, lsef, tune]
";

fn allocations_while_stepping(solver: &str, steps: usize) -> usize {
    let yaml = GRAPH.replace("SOLVER", solver);
    let model = ctlgraph::compile_str(&yaml, "alloc.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
    count_allocations(model, 1, steps)
}

/// Events, modes and delays: a relay limit cycle through a transport delay
/// (whose history starts small and grows during the warm-up), a reset
/// integrator, saturation and a discrete delay.
const EVENTS: &str = "
simulation: { stop: 1000.0, solver: SOLVER }
blocks:
  relay: { type: relay, on_threshold: 0.1, off_threshold: -0.1, on_value: -1, off_value: 1 }
  dead:  { type: transport_delay, delay: 0.05, buffer: 4 }
  vdead: { type: variable_transport_delay, max_delay: 0.1, buffer: 4 }
  tau:   { type: constant, value: 0.03 }
  plant: { type: transfer_function, num: [20], den: [1, 2] }
  sat:   { type: saturation, lower: -0.5, upper: 0.5 }
  saw:   { type: integrator, reset: rising, state_port: true }
  lvl:   { type: sum, signs: \"+-\" }
  one:   { type: constant, value: 1 }
  zd:    { type: delay, samples: 4, sample_time: 1.0e-3 }
  hit:   { type: hit_crossing }
wires: [relay -> dead, dead -> plant, plant -> relay, plant -> vdead.u, tau -> vdead.delay, vdead -> sat,
        sat -> saw.u, saw.state -> lvl.u1, one -> lvl.u2, lvl -> saw.reset, plant -> zd, plant -> hit]
record: [y: plant, sat, saw: saw.y, zd, hit]
";

fn count_allocations(model: ctlgraph_core::Model, warm_up: usize, steps: usize) -> usize {
    COUNT.with(|c| c.set(0));
    let mut sim = Simulator::new(model, None);
    let mut recorder = Recorder::new(sim.model());
    let mut sum = 0.0;
    let mut sink = |row: &[f64]| sum += row[1];
    // Warm up outside the counted region (lazy statics, first-step paths,
    // history buffers growing to their working size).
    for _ in 0..warm_up {
        sim.outputs().unwrap();
        sim.advance().unwrap();
    }
    ENABLED.with(|on| on.set(true));
    for _ in 0..steps {
        sim.outputs().unwrap();
        recorder.sample(sim.time(), sim.signals(), &mut sink);
        sim.advance().unwrap();
    }
    ENABLED.with(|on| on.set(false));
    assert!(sim.time() > 0.1, "the run advanced: t = {}", sim.time());
    assert!(sum.is_finite());
    COUNT.with(|c| c.get())
}

#[test]
fn stepping_allocates_nothing() {
    assert_eq!(allocations_while_stepping("{ method: rk4, step: 1.0e-4 }", 20_000), 0, "rk4");
    assert_eq!(allocations_while_stepping("{ method: dopri5, max_step: 1.0e-3 }", 5_000), 0, "dopri5");
    // The paper graphs: contact, normal force, impedance, sliding mode, feed
    // drive, reference filter; RLS; the milling force with its tooth events,
    // chip crossings and delays, and the cascade-realised controller; the
    // mirror-milling pair (feed plan, servo axes, noise, compensation).
    let graphs = [
        ("graphs/contact-force/compare.yaml", 1_500),
        ("graphs/contact-force/identify.yaml", 1_500),
        ("graphs/milling/compare.yaml", 12_000),
        ("graphs/mirror-milling/compensation.yaml", 4_000),
    ];
    for (graph, steps) in graphs {
        let model = ctlgraph::compile_file(graph.as_ref(), &[]).unwrap_or_else(|d| panic!("{d}"));
        assert_eq!(count_allocations(model, 1, steps), 0, "{graph}");
    }
}

/// An LTI block stepped exactly, its steps cut by a pulse whose edges fall
/// between grid points: step lengths keep changing, so the transition is
/// recomputed inside the counted region, in the block's own work space.
#[test]
fn exact_zoh_with_changing_steps_allocates_nothing() {
    let yaml = "
simulation: { stop: 100.0, solver: { method: rk4, step: 1.0e-3 } }
blocks:
  r:     { type: pulse, period: 3.7e-3, duty: 0.3 }
  d:     { type: step, at: 0.00123, value: 0.5 }
  u:     { type: sum, signs: \"++\" }
  plant: { type: transfer_function, num: [100], den: [1, 10, 100] }
wires: [r -> u.u1, d -> u.u2, u -> plant]
record: [y: plant]
";
    let model = ctlgraph::compile_str(yaml, "zoh.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
    assert!(model.meta.iter().any(|m| m.exact_zoh), "the plant is held");
    assert_eq!(count_allocations(model, 1, 5_000), 0);
    let model = ctlgraph::compile_file("graphs/fladrc/fladrc.yaml".as_ref(), &[]).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(count_allocations(model, 1, 5_000), 0, "fladrc");
}

/// Algebraic loops: Newton's iterations, the Jacobian's columns and the
/// line search work in space sized at build — under dopri5 (the diode),
/// and under TR-BDF2 through a stiff plant with feedthrough; enabled and
/// triggered subsystems; the Kalman filter's covariance recursion.
#[test]
fn algebraic_loops_conditional_subsystems_and_the_kalman_filter_allocate_nothing() {
    // The diode's 40 ms made a second, to pass the harness's 0.1 s.
    let diode =
        std::fs::read_to_string("graphs/tutorial/algebraic_loop.yaml").unwrap().replace("stop: 0.04", "stop: 1");
    let model = ctlgraph::compile_str(&diode, "algebraic_loop.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(model.algebraic_loops.len(), 1);
    assert_eq!(count_allocations(model, 1, 5_000), 0, "the diode");
    let model =
        ctlgraph::compile_file("graphs/estimation/kalman_cart.yaml".as_ref(), &[]).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(count_allocations(model, 1, 900), 0, "kalman_cart");
    let stiff = "simulation: { stop: 100, solver: { method: trbdf2, max_step: 1.0e-3 } }\nblocks:\n  r: { type: pulse, period: 0.5 }\n\
                 \x20 e: { type: sum, signs: \"+-\" }\n  k: { type: fcn, expr: \"5*u + 0.1*u^3\" }\n\
                 \x20 plant: { type: state_space, A: [[0, 1], [-10000, -10001]], B: [[0], [1]], C: [[10000, 0]], D: 0.5 }\n\
                 wires: [r -> e.u1, e -> k, k -> plant, plant -> e.u2]\nrecord: [y: plant]\n";
    let model = ctlgraph::compile_str(stiff, "stiff_loop.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(count_allocations(model, 200, 2_000), 0, "a nonlinear loop through a stiff plant");
}

#[test]
fn events_modes_and_delays_allocate_nothing_once_warm() {
    for (solver, warm_up) in
        [("{ method: dopri5, max_step: 1.0e-3 }", 2_000), ("{ method: rk4, step: 1.0e-4, zero_crossing: true }", 2_000)]
    {
        let yaml = EVENTS.replace("SOLVER", solver);
        let model = ctlgraph::compile_str(&yaml, "events.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
        let stop_events = count_events(&yaml);
        assert!(stop_events > 0, "the relay cycles: {stop_events} events");
        assert_eq!(count_allocations(model, warm_up, 10_000), 0, "{solver}");
    }
    // trbdf2's steps shrink at the relay's switches and their arrivals at the
    // delay's output (breakpoints): the histories reach their working size later.
    let stiff = EVENTS.replace("SOLVER", "{ method: trbdf2, max_step: 1.0e-3 }");
    let model = ctlgraph::compile_str(&stiff, "events.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(count_allocations(model, 6_000, 5_000), 0, "trbdf2");
}

/// Events located in the first two seconds.
fn count_events(yaml: &str) -> u64 {
    let model = ctlgraph::compile_str(yaml, "events.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
    let mut sim = Simulator::new(model, Some(2.0));
    sim.run(&mut |_, _| {}).unwrap().events
}

#[test]
fn the_motion_blocks_allocate_nothing() {
    // S-curve → Taylor interpolation → fitted path with a paired axis curve
    // → mirror offset; and the offline feed plan's lookups.
    let yaml = "
simulation: { stop: 12, solver: { method: rk4, step: 2.0e-3 } }
blocks:
  plan:   { type: s_curve, length: 209.43951023931956, feed: 20, accel: 100, jerk: 1000, radius: 400, accel_normal: 2 }
  path:   { type: bspline_path, curve: [\"400*cos(v)\", \"400*sin(v)\", \"0\"], range: [0, \"pi/6\"], samples: 60,
            axis_curve: [\"400*cos(v)\", \"400*sin(v)\", \"50\"] }
  interp: { type: path_interpolator, sample_time: 2.0e-3 }
  axis:   { type: sum, signs: \"+-\" }
  mirror: { type: mirror_offset, thickness: 5, depth: 1 }
  both:   { type: mirror_feed_plan, curve: [\"400*cos(v)\", \"400*sin(v)\"], support_curve: [\"500*cos(v)\", \"500*sin(v)\"],
            range: [0, \"pi/6\"], feed: 20, accel: 100, jerk: 1000, sample_time: 2.0e-3 }
wires: [plan.f -> interp.f, plan.a -> interp.a, path.dp -> interp.dp, path.ddp -> interp.ddp, interp -> path,
        path.o -> axis.u1, path.p -> axis.u2, path.p -> mirror.p, axis -> mirror.n]
record: [q: mirror, f2: both.f2]
";
    let model = ctlgraph::compile_str(yaml, "motion.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(count_allocations(model, 1, 5_000), 0);
}
