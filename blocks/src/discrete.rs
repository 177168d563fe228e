//! Discrete-time dynamics: discrete transfer function, unit delay,
//! zero-order hold. They run at their sample hits and hold in between.

use crate::continuous::lti_error;
use crate::{SAMPLE_TIME_INHERITED, SAMPLE_TIME_REQUIRED, U_ANY, U_SCALAR, Y_SAME, Y_SCALAR, table::*};
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::registry::{BlockType, Built};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};
use ctlgraph_solver::{StateSpace, tf2ss};

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "discrete_fir",
        category: "discrete",
        summary: "Finite impulse response filter: y(k) = Σ b_i·u(k−i).",
        doc: "y(k) = b_0·u(k) + b_1·u(k−1) + … + b_(n−1)·u(k−n+1) (Simulink's Discrete FIR Filter), \
              the past inputs before the start taken as `initial`. Its impulse response is the \
              coefficients; a unit step settles at Σ b_i after n samples.\n\
              Bounds: |y| <= Σ|b_i|·sup|u| once the initial inputs are out.",
        inputs: U_SCALAR,
        outputs: Y_SCALAR,
        params: &[
            param("coefficients", Required, "b_0 … b_(n−1)").kind(ParamKind::Numbers),
            param("initial", Number(0.0), "the inputs before the start"),
            SAMPLE_TIME_REQUIRED,
        ],
        build: build_fir,
    },
    BlockType {
        name: "memory",
        category: "discrete",
        summary: "The input at the previous major step (Simulink's Memory).",
        doc: "y = u at the last major step before this one (`initial` at the first), held in between: \
              one step of delay at whatever steps the solver takes — at a sample time, one sample. No \
              direct feedthrough, so it breaks a loop of feedthrough blocks.\n\
              Bounds: |y| <= max(|initial|, sup|u|).",
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[
            param("initial", Number(0.0), "y at the first step: a number or one per element").kind(ParamKind::Numbers),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_memory,
    },
    BlockType {
        name: "moving_average",
        category: "discrete",
        summary: "The mean of the last N samples of the input.",
        doc: "y(k) = (u(k) + u(k−1) + … + u(k−N+1)) / N, the inputs before the start taken as \
              `initial`: an FIR filter of N equal coefficients, summed first and divided once.\n\
              Bounds: min u <= y <= max u over the window.",
        inputs: U_SCALAR,
        outputs: Y_SCALAR,
        params: &[
            param("window", Required, "N, the number of samples averaged").kind(ParamKind::Number),
            param("initial", Number(0.0), "the inputs before the start"),
            SAMPLE_TIME_REQUIRED,
        ],
        build: build_moving_average,
    },
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
        params: &[
            param("initial", Number(0.0), "y(0): a number or one per element").kind(ParamKind::Numbers),
            SAMPLE_TIME_REQUIRED,
        ],
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
    /// `StateSpace::output` and `derivative` written out: each row's sums
    /// left to right, every term (zeros too: 0·x can be −0 or NaN).
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let ss = &self.ss;
        c.equation("y = C x + D u;  x(k+1) = A x + B u  (controllable canonical form of num/den)");
        let x = c.state("x", &vec![0.0; ss.n.max(1)]);
        let xs: Vec<String> = (0..ss.n).map(|j| if ss.n == 1 { x.clone() } else { format!("{x}[{j}]") }).collect();
        let us: Vec<String> = (0..ss.m).map(|j| c.u_at(0, j).to_string()).collect();
        let dot = |c: &CBlock, m: &[f64], cols: usize, i: usize, v: &[String]| {
            let terms: Vec<String> = (0..cols).map(|j| format!("{} * {}", c.num(m[i * cols + j]), v[j])).collect();
            c.sum_of(&terms)
        };
        for i in 0..ss.p {
            let y = format!("{} + {}", dot(c, &ss.c, ss.n, i, &xs), dot(c, &ss.d, ss.m, i, &us));
            c.output(format!("{} = {y};", c.y_at(0, i)));
        }
        let real = c.real();
        for i in 0..ss.n {
            let next = format!("{} + {}", dot(c, &ss.a, ss.n, i, &xs), dot(c, &ss.b, ss.m, i, &us));
            c.update(format!("{real} next{i} = {next};"));
        }
        for (i, xi) in xs.iter().enumerate() {
            c.update(format!("{xi} = next{i};"));
        }
        Ok(())
    }
}

fn build_dtf(p: &mut Params) -> Result<Built, Diagnostic> {
    let (num, den) = (p.vector("num")?, p.vector("den")?);
    let ss = tf2ss(&num, &den).map_err(|e| lti_error(p, e))?;
    let st = p.discrete_sample_time()?;
    let iface = Interface::new(st).input("u", Width::Fixed(1), ss.has_feedthrough()).output("y", Width::Fixed(1));
    Ok(Built::new(DiscreteLti::new(ss), iface))
}

/// An FIR filter over the last inputs (`past[0]` the newest): the
/// coefficients' sum, or the window's mean.
#[derive(Clone)]
pub struct Fir {
    /// b_0 … b_(n−1); `None`: a moving average of `past.len() + 1` samples.
    coefficients: Option<Vec<f64>>,
    initial: f64,
    past: Vec<f64>,
}

impl Fir {
    fn value(&self, u: f64) -> f64 {
        match &self.coefficients {
            Some(b) => b[0] * u + b[1..].iter().zip(&self.past).map(|(b, x)| b * x).sum::<f64>(),
            None => (u + self.past.iter().sum::<f64>()) / (self.past.len() + 1) as f64,
        }
    }
}

impl Block for Fir {
    rust_type!(Fir);
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.past.iter_mut().for_each(|x| *x = self.initial);
    }
    fn output(&mut self, io: &mut Io) {
        let y = self.value(io.u(0));
        io.set(0, y);
    }
    fn update(&mut self, io: &mut Io) {
        if !self.past.is_empty() {
            self.past.rotate_right(1);
            self.past[0] = io.u(0);
        }
    }
    /// The sums as [`Fir::value`] makes them: the past terms summed on
    /// their own (from −0.0), then added.
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let n = self.past.len();
        let past = c.state("past", &vec![self.initial; n.max(1)]);
        let at = |i: usize| if n == 1 { past.clone() } else { format!("{past}[{i}]") };
        let u = c.u(0).to_string();
        let y = match &self.coefficients {
            Some(b) => {
                c.equation("y = b0 u(k) + b1 u(k-1) + ...");
                let terms: Vec<String> = (0..n).map(|i| format!("{} * {}", c.num(b[i + 1]), at(i))).collect();
                format!("{} * {u} + {}", c.num(b[0]), c.sum_of(&terms))
            }
            None => {
                c.equation(format!("y = (u(k) + u(k-1) + ... + u(k-{n})) / {}", n + 1));
                let terms: Vec<String> = (0..n).map(at).collect();
                format!("({u} + {}) / {}", c.sum_of(&terms), c.num((n + 1) as f64))
            }
        };
        c.output(format!("{} = {y};", c.y(0)));
        for i in (1..n).rev() {
            c.update(format!("{} = {};", at(i), at(i - 1)));
        }
        if n > 0 {
            c.update(format!("{} = {u};", at(0)));
        }
        Ok(())
    }
}

fn build_fir(p: &mut Params) -> Result<Built, Diagnostic> {
    let b = p.vector("coefficients")?;
    if b.is_empty() {
        return Err(p.error("coefficients", "needs at least one coefficient"));
    }
    let initial = p.number("initial")?;
    let st = p.discrete_sample_time()?;
    let past = vec![initial; b.len() - 1];
    let iface = Interface::new(st).input("u", Width::Fixed(1), true).output("y", Width::Fixed(1));
    Ok(Built::new(Fir { coefficients: Some(b), initial, past }, iface))
}

fn build_moving_average(p: &mut Params) -> Result<Built, Diagnostic> {
    let window = p.count("window", 1_000_000)?;
    if window == 0 {
        return Err(p.error("window", "must be at least 1 sample"));
    }
    let initial = p.number("initial")?;
    let st = p.discrete_sample_time()?;
    let iface = Interface::new(st).input("u", Width::Fixed(1), true).output("y", Width::Fixed(1));
    Ok(Built::new(Fir { coefficients: None, initial, past: vec![initial; window - 1] }, iface))
}

/// The input of the last major step.
#[derive(Clone)]
pub struct Memory {
    initial: Vec<f64>,
    held: Vec<f64>,
}

impl Block for Memory {
    rust_type!(Memory);
    fn set_width(&mut self, width: usize) -> Result<(), String> {
        self.initial = crate::continuous::initial_vector(&self.initial, width)?;
        self.held = self.initial.clone();
        Ok(())
    }
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.held.copy_from_slice(&self.initial);
    }
    fn output(&mut self, io: &mut Io) {
        io.set_all(0, &self.held);
    }
    fn update(&mut self, io: &mut Io) {
        for (k, h) in self.held.iter_mut().enumerate() {
            *h = io.u_at(0, k);
        }
    }
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation("y(k) = u(k-1)");
        let held = c.state("held", &self.initial);
        let w = self.initial.len();
        for k in 0..w {
            let h = if w == 1 { held.clone() } else { format!("{held}[{k}]") };
            c.output(format!("{} = {h};", c.y_at(0, k)));
            c.update(format!("{h} = {};", c.u_at(0, k)));
        }
        Ok(())
    }
}

fn build_memory(p: &mut Params) -> Result<Built, Diagnostic> {
    let initial = p.vector("initial")?;
    let iface = Interface::new(p.sample_time()?).piecewise_constant().input("u", Width::Common, false);
    Ok(Built::new(Memory { held: initial.clone(), initial }, iface.output("y", Width::Common)))
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
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation("y = u, sampled at the block's rate and held");
        for k in 0..c.output_width(0) {
            c.output(format!("{} = {};", c.y_at(0, k), c.u_at(0, k)));
        }
        Ok(())
    }
}

fn build_zoh(p: &mut Params) -> Result<Built, Diagnostic> {
    let st = p.discrete_sample_time()?;
    Ok(Built::new(Hold, Interface::new(st).input("u", Width::Common, true).output("y", Width::Common)))
}
