//! The overhead the graph runtime owns: the tutorial PID loop run by
//! ctlgraph against the same equations written by hand as a plain Rust
//! loop, integrated by the same RK4 with the same step — and against the
//! graph's own blocks called without the interpreter (`fused_blocks`),
//! which splits the overhead into the interpreter's and the blocks' code —
//! and against the graph's generated step (`compiled`, `ctlgraph codegen`,
//! built by the `ctlgraph-compiled-graphs` crate), and that step as
//! `--accelerate` builds, loads and runs it (`accelerated`).
//!
//!     cargo bench --bench overhead

use criterion::{Criterion, criterion_group, criterion_main};
use ctlgraph_compiled_graphs::benches_pid_loop_rk4::Step;
use ctlgraph_core::Simulator;
use ctlgraph_core::codegen::Compiled;
use ctlgraph_solver::{Integrator, Method, OdeSystem};
use std::hint::black_box;

mod accelerated;
mod fused_pid;
mod paired;
use ctlgraph::accel::AcceleratedRun;
use fused_pid::{Fused, GRAPH, STEP, STEPS};
use paired::Paired;

/// The command line's allocator (src/main.rs), so the benches measure what it does.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// The same loop by hand: plant in controllable canonical form, PID states
/// [I, x_f], clamping anti-windup decided at major steps and held through
/// RK4's stages (as the `pid` block does).
struct HandWritten {
    holding: bool,
}

impl HandWritten {
    /// (ki·e, unlimited v, limited u) at state x.
    fn control(x: &[f64]) -> (f64, f64, f64) {
        let y = 100.0 * x[1];
        let e = 1.0 - y;
        let v = 2.0 * e + x[2] + 0.1 * 200.0 * (e - x[3]);
        (15.0 * e, v, v.clamp(-5.0, 5.0))
    }

    /// The major step: the output, and the clamp decision for the next step.
    fn major_step(&mut self, x: &[f64]) -> f64 {
        let (ki_e, v, u) = Self::control(x);
        self.holding = (v >= 5.0 && ki_e > 0.0) || (v <= -5.0 && ki_e < 0.0);
        u
    }
}

impl OdeSystem for HandWritten {
    fn derivatives(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
        let (ki_e, _, u) = Self::control(x);
        dx[0] = -6.0 * x[0] - 100.0 * x[1] + u;
        dx[1] = x[0];
        dx[2] = if self.holding { 0.0 } else { ki_e };
        dx[3] = 200.0 * (ki_e / 15.0 - x[3]);
    }
}

/// The hand-written run: the sum of the outputs (what the timing keeps
/// alive) and the plant output y at the end.
fn hand_written() -> (f64, f64) {
    let mut integ = Integrator::new(Method::Rk4 { step: STEP }, 4);
    let mut sys = HandWritten { holding: false };
    let mut x = [0.0; 4];
    let mut t = 0.0;
    let mut sink = 0.0;
    for k in 1..=STEPS {
        sink += sys.major_step(&x);
        t = integ.advance(&mut sys, t, k as f64 * STEP, &mut x).unwrap_or(t);
    }
    (sink, 100.0 * x[1])
}

fn graph(sim: &mut Simulator) -> f64 {
    sim.reset();
    let mut sink = 0.0;
    for _ in 0..STEPS {
        let _ = sim.outputs();
        sink += sim.signals()[2];
        let _ = sim.advance();
    }
    sink
}

/// The generated step's run, as `graph`: Σu over the major steps.
fn compiled(run: &mut Compiled<Step>, ctrl: usize) -> f64 {
    run.reset();
    let mut sink = 0.0;
    for _ in 0..STEPS {
        let _ = run.outputs();
        sink += run.signals()[ctrl];
        let _ = run.advance();
    }
    sink
}

/// The accelerated run as `--accelerate` runs it, as `graph`: Σu over
/// the major steps (`ctrl` u's column in the rows).
fn accelerated(run: &mut AcceleratedRun, ctrl: usize) -> f64 {
    accelerated::sum_column(run, ctrl, STEPS as u64).0
}

fn bench(c: &mut Criterion) {
    let model = ctlgraph::compile_str(GRAPH, "bench.yaml", &[]).expect("graph compiles");
    let mut library = accelerated::accelerated(&model, GRAPH, "bench.yaml");
    let offset = |name: &str| model.columns.iter().find(|c| c.name == name).expect("recorded").offset;
    let (plant, ctrl) = (offset("plant"), offset("ctrl"));
    let ctrl_column = accelerated::row_column(&model, "ctrl");
    let mut fused = Fused::new(&model);
    let mut generated = Compiled::<Step>::new(&model, None).expect("generated for this graph");
    let mut sim = Simulator::new(model, None);
    // Same equations, same integrator: the three agree before they are timed.
    let sum_u = fused_pid::interpreted_sum_u(&mut sim, ctrl);
    sim.outputs().expect("finite");
    let (by_graph, by_hand) = (sim.signals()[plant], hand_written().1);
    assert!((by_graph - by_hand).abs() < 1e-12, "graph {by_graph} vs hand {by_hand}");
    assert_eq!(fused.run(), sum_u, "the fused blocks compute what the interpreter does, to the bit");
    assert_eq!(compiled(&mut generated, ctrl), sum_u, "the generated step computes what the interpreter does");
    assert_eq!(accelerated(&mut library, ctrl_column), sum_u, "the accelerated run computes what the interpreter does");
    const GROUP: &str = "pid_loop_10k_rk4_steps";
    const CRITERION_SAMPLES: usize = 100;
    let mut group = c.benchmark_group(GROUP);
    group.sample_size(CRITERION_SAMPLES);
    let mut paired = [
        Paired::new(GROUP, "ctlgraph", "hand_written"),
        Paired::new(GROUP, "fused_blocks", "hand_written"),
        Paired::new(GROUP, "compiled", "hand_written"),
        Paired::new(GROUP, "accelerated", "hand_written"),
    ];
    group.bench_function("hand_written", |b| b.iter(|| black_box(hand_written().0)));
    group.bench_function("ctlgraph", |b| paired[0].run(b, || graph(&mut sim), hand_written));
    group.bench_function("fused_blocks", |b| paired[1].run(b, || fused.run(), hand_written));
    group.bench_function("compiled", |b| paired[2].run(b, || compiled(&mut generated, ctrl), hand_written));
    group.bench_function("accelerated", |b| paired[3].run(b, || accelerated(&mut library, ctrl_column), hand_written));
    group.finish();
    paired.iter().for_each(|p| p.save(CRITERION_SAMPLES));
}

criterion_group!(benches, bench);
criterion_main!(benches);
