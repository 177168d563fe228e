//! The PID loop's own blocks called without the interpreter: the graph,
//! the fused loop, and the interpreter's run it must equal to the bit.
//! Shared by `benches/overhead.rs` (which times it) and `tests/fused.rs`
//! (which checks it in CI): the semantics a compiled step has to keep.

use ctlgraph_blocks::continuous::Lti;
use ctlgraph_blocks::pid::ContinuousPid;
use ctlgraph_core::block::{Io, Port};
use ctlgraph_core::{Block, Model, Simulator};
use ctlgraph_solver::{Integrator, Method, OdeSystem};

/// Steps per second; the step (the graph's `step: 1.0e-4`) is its inverse.
pub const PER_SECOND: f64 = 10_000.0;
pub const STEP: f64 = 1.0 / PER_SECOND;
pub const STEPS: usize = 10_000;

/// The graph (`benches/pid_loop_rk4.yaml`; also generated as Rust by the
/// `ctlgraph-compiled-graphs` crate).
pub const GRAPH: &str = include_str!("../pid_loop_rk4.yaml");

/// The graph's PID and plant blocks as ctlgraph builds them, taken from
/// the compiled graph as their concrete types and called in the graph's
/// order at every stage without dispatch (the sum and the step written
/// out): what a compiled step calling the library's blocks would run.
pub struct Fused {
    pid: ContinuousPid,
    plant: Lti,
    /// Signals: 0 r − y, 1 u, 2 y.
    s: [f64; 3],
}

const ERROR: [Port; 1] = [Port { offset: 0, width: 1 }];
const CONTROL: [Port; 1] = [Port { offset: 1, width: 1 }];
const PLANT_OUT: [Port; 1] = [Port { offset: 2, width: 1 }];

impl Fused {
    pub fn new(model: &Model) -> Self {
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
    pub fn run(&mut self) -> f64 {
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
            let target = k as f64 / PER_SECOND;
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

/// The interpreter's Σu over the same major steps (`ctrl`: the offset of
/// the controller's output).
pub fn interpreted_sum_u(sim: &mut Simulator, ctrl: usize) -> f64 {
    let mut sum_u = 0.0;
    for _ in 0..STEPS {
        sim.outputs().expect("finite");
        sum_u += sim.signals()[ctrl];
        sim.advance().expect("advances");
    }
    sum_u
}
