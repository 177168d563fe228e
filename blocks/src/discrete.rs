//! Discrete-time dynamics: discrete transfer function, unit delay,
//! zero-order hold. They run at their sample hits and hold in between.

use crate::continuous::lti_error;
use crate::{SAMPLE_TIME_REQUIRED, U_ANY, U_SCALAR, Y_SAME, Y_SCALAR, table::*};
use ctlgraph_core::registry::{BlockType, Built};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};
use ctlgraph_solver::{StateSpace, tf2ss};

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "discrete_transfer_function",
        category: "discrete",
        summary: "Discrete transfer function num(z)/den(z) at a sample time.",
        doc: "Coefficients in descending powers of z (Simulink's Discrete Transfer Fcn): num [1], den \
              [1, -0.5] is 1/(z − 0.5), i.e. y(k) = 0.5·y(k−1) + u(k−1). Realised as x(k+1) = A x(k) + \
              B u(k), y(k) = C x(k) + D u(k) in controllable canonical form; zero initial state. Must \
              be proper; direct feedthrough only when deg num = deg den.\n\
              Stable region: every root of den strictly inside the unit circle; then |y| <= ‖h‖₁·sup|u| and a unit step settles at num(1)/den(1).",
        inputs: U_SCALAR,
        outputs: Y_SCALAR,
        params: &[
            param("num", Required, "numerator, descending powers of z").kind(ParamKind::Numbers),
            param("den", Required, "denominator, descending powers of z").kind(ParamKind::Numbers),
            SAMPLE_TIME_REQUIRED,
        ],
        build: build_dtf,
    },
    BlockType {
        name: "unit_delay",
        category: "discrete",
        summary: "y(k) = u(k−1): one sample of delay.",
        doc: "y(k) = x(k), x(k+1) = u(k), x(0) = initial. No direct feedthrough: it closes loops legally.\n\
              Bounds: |y| <= max(|initial|, sup|u|), for any period.",
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[param("initial", Number(0.0), "y(0): a number or one per element"), SAMPLE_TIME_REQUIRED],
        build: build_unit_delay,
    },
    BlockType {
        name: "zero_order_hold",
        category: "discrete",
        summary: "Samples its input every T seconds and holds it.",
        doc: "y(t) = u(t_k) for t_k <= t < t_k + T.\n\
              Bounds: |y| <= sup|u|, for any period.",
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[SAMPLE_TIME_REQUIRED],
        build: build_zoh,
    },
];

/// A discrete LTI system: state advanced in `update`, at sample hits.
#[derive(Clone)]
pub struct DiscreteLti {
    ss: StateSpace,
    x: Vec<f64>,
    next: Vec<f64>,
    y: Vec<f64>,
}

impl DiscreteLti {
    pub fn new(ss: StateSpace) -> Self {
        DiscreteLti { x: vec![0.0; ss.n], next: vec![0.0; ss.n], y: vec![0.0; ss.p], ss }
    }
}

impl Block for DiscreteLti {
    rust_type!(DiscreteLti);
    fn discrete_lti(&self) -> Option<StateSpace> {
        Some(self.ss.clone())
    }

    fn initialize(&mut self, _x0: &mut [f64]) {
        self.x.iter_mut().for_each(|v| *v = 0.0);
    }
    fn output(&mut self, io: &mut Io) {
        self.ss.output(&self.x, io.input(0), &mut self.y);
        io.set_all(0, &self.y);
    }
    fn update(&mut self, io: &mut Io) {
        self.ss.derivative(&self.x, io.input(0), &mut self.next);
        std::mem::swap(&mut self.x, &mut self.next);
    }
}

fn build_dtf(p: &mut Params) -> Result<Built, Diagnostic> {
    let (num, den) = (p.vector("num")?, p.vector("den")?);
    let ss = tf2ss(&num, &den).map_err(|e| lti_error(p, e))?;
    let st = p.discrete_sample_time()?;
    let iface = Interface::new(st).input("u", Width::Fixed(1), ss.has_feedthrough()).output("y", Width::Fixed(1));
    Ok(Built::new(DiscreteLti::new(ss), iface))
}

fn build_unit_delay(p: &mut Params) -> Result<Built, Diagnostic> {
    crate::delay::build_delay_of(p, 1)
}

#[derive(Clone)]
pub struct Hold;

impl Block for Hold {
    rust_type!(Hold);
    fn updates(&self) -> bool {
        false
    }
    fn output(&mut self, io: &mut Io) {
        for k in 0..io.output_width(0) {
            let v = io.u_at(0, k);
            io.set_at(0, k, v);
        }
    }
}

fn build_zoh(p: &mut Params) -> Result<Built, Diagnostic> {
    let st = p.discrete_sample_time()?;
    Ok(Built::new(Hold, Interface::new(st).input("u", Width::Common, true).output("y", Width::Common)))
}
