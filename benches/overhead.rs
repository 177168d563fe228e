//! The overhead the graph runtime owns: the tutorial PID loop run by
//! ctlgraph against the same equations written by hand as a plain Rust
//! loop, integrated by the same RK4 with the same step — and against the
//! graph's own blocks called without the interpreter (`fused_blocks`),
//! which splits the overhead into the interpreter's and the blocks' code.
//!
//!     cargo bench --bench overhead

use criterion::{Criterion, criterion_group, criterion_main};
use ctlgraph_blocks::continuous::Lti;
use ctlgraph_blocks::pid::ContinuousPid;
use ctlgraph_core::block::{Io, Port};
use ctlgraph_core::{Block, Model, Simulator};
use ctlgraph_solver::{Integrator, Method, OdeSystem};
use std::hint::black_box;

mod paired;
use paired::Paired;

/// The command line's allocator (src/main.rs), so the benches measure what it does.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

const STEP: f64 = 1.0e-4;
const STEPS: usize = 10_000;

const GRAPH: &str = "
simulation: { stop: 100.0, solver: { method: rk4, step: 1.0e-4 } }
blocks:
  r:     { type: step, at: 0.0 }
  err:   { type: sum, signs: \"+-\" }
  ctrl:  { type: pid, kp: 2.0, ki: 15.0, kd: 0.1, n: 200, lower: -5, upper: 5 }
  plant: { type: transfer_function, num: [100], den: [1, 6, 100] }
wires: [r -> err.u1, plant -> err.u2, err -> ctrl, ctrl -> plant]
";

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

/// The graph's PID and plant blocks as ctlgraph builds them, taken from
/// the compiled graph as their concrete types and called in the graph's
/// order at every stage without dispatch (the sum and the step written
/// out): what a compiled step calling the library's blocks would run.
struct Fused {
    pid: ContinuousPid,
    plant: Lti,
    /// Signals: 0 r − y, 1 u, 2 y.
    s: [f64; 3],
}

const ERROR: [Port; 1] = [Port { offset: 0, width: 1 }];
const CONTROL: [Port; 1] = [Port { offset: 1, width: 1 }];
const PLANT_OUT: [Port; 1] = [Port { offset: 2, width: 1 }];

impl Fused {
    fn new(model: &Model) -> Self {
        let pid = model.block_as("ctrl").expect("ctrl is a continuous PID");
        Fused { pid, plant: model.block_as("plant").expect("plant is an Lti"), s: [0.0; 3] }
    }

    /// The outputs at state x = [PID's 2, plant's 2].
    #[inline]
    fn outputs(&mut self, t: f64, x: &[f64]) {
        let (xc, xp) = x.split_at(2);
        self.plant.output(&mut Io::new(t, false, xp, &mut self.s, &[], &PLANT_OUT));
        self.s[0] = 1.0 - self.s[2];
        self.pid.output(&mut Io::new(t, false, xc, &mut self.s, &ERROR, &CONTROL));
    }

    /// The run: Σu over the major steps, as `hand_written`.
    fn run(&mut self) -> f64 {
        let mut integ = Integrator::new(Method::Rk4 { step: STEP }, 4);
        let mut x = [0.0; 4];
        self.pid.initialize(&mut x[..2]);
        self.plant.initialize(&mut x[2..]);
        let (mut t, mut sink) = (0.0, 0.0);
        for k in 1..=STEPS {
            self.outputs(t, &x);
            sink += self.s[1];
            self.pid.update(&mut Io::new(t, false, &x[..2], &mut self.s, &ERROR, &CONTROL));
            // The step's end as the simulator's time grid has it: for a
            // step of 1/n s, k/n (exact at decimal times), not k·step.
            let target = k as f64 / 10_000.0;
            integ.advance(self, t, target, &mut x).expect("finite");
            t = target;
        }
        sink
    }
}

impl OdeSystem for Fused {
    fn derivatives(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        self.outputs(t, x);
        let ((xc, xp), (dc, dp)) = (x.split_at(2), dx.split_at_mut(2));
        self.pid.derivatives(&Io::new(t, false, xc, &mut self.s, &ERROR, &CONTROL).in_minor_step(false), dc);
        self.plant.derivatives(&Io::new(t, false, xp, &mut self.s, &CONTROL, &PLANT_OUT).in_minor_step(false), dp);
    }
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

fn bench(c: &mut Criterion) {
    let model = ctlgraph::compile_str(GRAPH, "bench.yaml", &[]).expect("graph compiles");
    let offset = |name: &str| model.columns.iter().find(|c| c.name == name).expect("recorded").offset;
    let (plant, ctrl) = (offset("plant"), offset("ctrl"));
    let mut fused = Fused::new(&model);
    let mut sim = Simulator::new(model, None);
    // Same equations, same integrator: the three agree before they are timed.
    let mut sum_u = 0.0;
    for _ in 0..STEPS {
        sim.outputs().expect("finite");
        sum_u += sim.signals()[ctrl];
        sim.advance().expect("advances");
    }
    sim.outputs().expect("finite");
    let (by_graph, by_hand) = (sim.signals()[plant], hand_written().1);
    assert!((by_graph - by_hand).abs() < 1e-12, "graph {by_graph} vs hand {by_hand}");
    assert_eq!(fused.run(), sum_u, "the fused blocks compute what the interpreter does, to the bit");
    const GROUP: &str = "pid_loop_10k_rk4_steps";
    const CRITERION_SAMPLES: usize = 100;
    let mut group = c.benchmark_group(GROUP);
    group.sample_size(CRITERION_SAMPLES);
    let mut paired =
        [Paired::new(GROUP, "ctlgraph", "hand_written"), Paired::new(GROUP, "fused_blocks", "hand_written")];
    group.bench_function("hand_written", |b| b.iter(|| black_box(hand_written().0)));
    group.bench_function("ctlgraph", |b| paired[0].run(b, || graph(&mut sim), hand_written));
    group.bench_function("fused_blocks", |b| paired[1].run(b, || fused.run(), hand_written));
    group.finish();
    paired.iter().for_each(|p| p.save(CRITERION_SAMPLES));
}

criterion_group!(benches, bench);
criterion_main!(benches);
