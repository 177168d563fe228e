//! Continuous dynamics: filtered derivative and linear systems given as
//! transfer function, zeros-poles-gain or state space (the integrator has
//! its own module). States are integrated by the simulation's solver.

use crate::{U_ANY, U_SCALAR, Y_SAME, Y_SCALAR, table::*};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, SampleTime, Width};
use ctlgraph_solver::lti::LtiError;
use ctlgraph_solver::{StateSpace, factored_tf2ss, tf2ss, zpk2tf};
use nalgebra::Complex;

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "derivative",
        category: "dynamics",
        summary: "Filtered derivative y = s/(τs + 1)·u.",
        doc: "A realisable derivative: y = (u − x)/τ with x' = (u − x)/τ, i.e. Y(s) = s/(τs + 1)·U(s). \
              It differentiates frequencies below 1/τ rad/s. x(0) = `initial_input`, so a signal that \
              starts at that value gives no kick at t = 0.\n\
              Stable region: τ > 0; then |y| <= 2·sup|u|/τ.",
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[
            param("tau", Number(1e-3), "filter time constant τ, > 0").unit("s"),
            param("initial_input", Number(0.0), "the input assumed before t = 0"),
        ],
        build: build_derivative,
    },
    BlockType {
        name: "transfer_function",
        category: "dynamics",
        summary: "Continuous transfer function num(s)/den(s).",
        doc: "Coefficients in descending powers of s (MATLAB's tf): num [1.639e4], den [1, 154.8, \
              2.242e4] is 1.639e4/(s² + 154.8 s + 2.242e4), times `gain`. Must be proper (deg num <= deg \
              den). Realised in controllable canonical form (MATLAB's tf2ss), zero initial state. Direct \
              feedthrough only when deg num = deg den.\n\
              Factored form: `num` and `den` may each be a list of factors, a product written as printed — \
              num [[1, 1200], [1, 225.4, 3.169e7]] is (s + 1200)(s² + 225.4 s + 3.169e7). It is realised \
              as a cascade of sections, one per denominator factor in the order written, each numerator \
              factor placed (highest degree first) in the first section with room, each section scaled to \
              unit DC gain and `gain` applied at the output: a high-order product keeps the coefficients \
              it was written with (the milling paper's sixth-order controller spreads over 1e14 this way, \
              over 6e26 expanded). When a numerator factor fits no section the product is expanded.\n\
              Under a fixed-step method, when its input is piecewise constant (driven by discrete, constant \
              or step-like blocks) and nothing reads it inside a step, it is advanced by its exact \
              zero-order-hold transition exp([A B; 0 0]·Δ) instead of being integrated (`ctlgraph check` \
              says \"exact ZOH\"; `solver: { exact_lti: false }` integrates it, as Simulink does).\n\
              Stable region: every root of den in the open left half-plane; then |y| <= ‖g‖₁·sup|u|.",
        inputs: U_SCALAR,
        outputs: Y_SCALAR,
        params: &[
            param("num", Required, "numerator coefficients, descending powers of s").kind(ParamKind::Matrix),
            param("den", Required, "denominator coefficients, descending powers of s").kind(ParamKind::Matrix),
            param("gain", Number(1.0), "a factor multiplying num/den"),
        ],
        build: build_tf,
    },
    BlockType {
        name: "zpk",
        category: "dynamics",
        summary: "Continuous transfer function from zeros, poles and gain.",
        doc: "G(s) = gain·Π(s − zᵢ)/Π(s − pᵢ). A complex root is written [re, im] and stands for the \
              conjugate pair re ± j·im (listing both conjugates, as MATLAB does, is reported as an error; \
              write a pair twice for a repeated pair). Realised like transfer_function.\n\
              Under a fixed-step method, when its input is piecewise constant (driven by discrete, constant \
              or step-like blocks) and nothing reads it inside a step, it is advanced by its exact \
              zero-order-hold transition exp([A B; 0 0]·Δ) instead of being integrated (`ctlgraph check` \
              says \"exact ZOH\"; `solver: { exact_lti: false }` integrates it, as Simulink does).\n\
              Stable region: every pole with negative real part; then |y| <= ‖g‖₁·sup|u| and a unit step settles at the DC gain G(0).",
        inputs: U_SCALAR,
        outputs: Y_SCALAR,
        params: &[
            param("zeros", Described("[]"), "list of zeros: numbers or [re, im] pairs").kind(ParamKind::Matrix),
            param("poles", Required, "list of poles: numbers or [re, im] pairs").kind(ParamKind::Matrix),
            param("gain", Number(1.0), "k"),
        ],
        build: build_zpk,
    },
    BlockType {
        name: "state_space",
        category: "dynamics",
        summary: "x' = A x + B u, y = C x + D u.",
        doc: "Matrices as lists of rows. Input width = columns of B, output width = rows of C. D \
              defaults to zero (no direct feedthrough).\n\
              Under a fixed-step method, when its input is piecewise constant (driven by discrete, constant \
              or step-like blocks) and nothing reads it inside a step, it is advanced by its exact \
              zero-order-hold transition exp([A B; 0 0]·Δ) instead of being integrated (`ctlgraph check` \
              says \"exact ZOH\"; `solver: { exact_lti: false }` integrates it, as Simulink does).\n\
              Stable region: A Hurwitz (every eigenvalue with negative real part).",
        inputs: &[PortDoc { name: "u", doc: "width = columns of B" }],
        outputs: &[PortDoc { name: "y", doc: "width = rows of C" }],
        params: &[
            param("A", Required, "n×n").kind(ParamKind::Matrix),
            param("B", Required, "n×m").kind(ParamKind::Matrix),
            param("C", Required, "p×n").kind(ParamKind::Matrix),
            param("D", Number(0.0), "p×m").kind(ParamKind::Matrix),
            param("initial", Number(0.0), "x(0): a number or n numbers").kind(ParamKind::Numbers),
        ],
        build: build_state_space,
    },
];

/// Broadcasts a scalar initial condition, or checks a vector's length.
pub(crate) fn initial_vector(v: &[f64], n: usize) -> Result<Vec<f64>, String> {
    match v.len() {
        1 => Ok(vec![v[0]; n]),
        len if len == n => Ok(v.to_vec()),
        len => Err(format!("`initial` has {len} values but the block has {n} states")),
    }
}

/// s/(τs + 1), elementwise.
#[derive(Clone)]
pub struct Derivative {
    tau: f64,
    initial_input: f64,
    width: usize,
}

impl Block for Derivative {
    rust_type!(Derivative);
    fn updates(&self) -> bool {
        false
    }
    fn set_width(&mut self, width: usize) -> Result<(), String> {
        self.width = width;
        Ok(())
    }
    fn num_states(&self) -> usize {
        self.width
    }
    fn initialize(&mut self, x0: &mut [f64]) {
        x0.iter_mut().for_each(|x| *x = self.initial_input);
    }
    fn output(&mut self, io: &mut Io) {
        for k in 0..self.width {
            let v = (io.u_at(0, k) - io.x[k]) / self.tau;
            io.set_at(0, k, v);
        }
    }
    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        for (k, d) in dx.iter_mut().enumerate() {
            *d = (io.u_at(0, k) - io.x[k]) / self.tau;
        }
    }
}

fn build_derivative(p: &mut Params) -> Result<Built, Diagnostic> {
    let tau = p.number_where("tau", None, |v| v > 0.0 && v.is_finite(), "a positive time constant")?;
    let initial_input = p.number("initial_input")?;
    let iface = Interface::new(SampleTime::Continuous).input("u", Width::Common, true).output("y", Width::Common);
    Ok(Built::new(Derivative { tau, initial_input, width: 1 }, iface))
}

/// A continuous LTI system; `y` is scratch so output needs no aliasing.
#[derive(Clone)]
pub struct Lti {
    ss: StateSpace,
    x0: Vec<f64>,
    y: Vec<f64>,
    feedthrough: bool,
}

impl Lti {
    pub fn new(ss: StateSpace, x0: Vec<f64>) -> Self {
        let feedthrough = ss.has_feedthrough();
        Lti { y: vec![0.0; ss.p], x0, ss, feedthrough }
    }

    /// The block with its interface: input/output widths from the matrices.
    pub fn built(self) -> Built {
        let iface = Interface::new(SampleTime::Continuous)
            .input("u", Width::Fixed(self.ss.m), self.feedthrough)
            .output("y", Width::Fixed(self.ss.p));
        Built::new(self, iface)
    }

    /// y = C·x (+ D·u) into the scratch. Out of line, and given slices
    /// rather than the view: a view passed to an outlined call would have
    /// to be built in memory on the common path too.
    #[inline(never)]
    fn output_general(&mut self, x: &[f64], u: &[f64]) {
        if self.feedthrough {
            self.ss.output(x, u, &mut self.y);
        } else {
            self.ss.output_state_only(x, &mut self.y);
        }
    }

    /// dx = A·x + B·u for several inputs, out of line like `output_general`.
    #[inline(never)]
    fn derivatives_general(&self, x: &[f64], u: &[f64], dx: &mut [f64]) {
        self.ss.derivative(x, u, dx);
    }
}

impl Block for Lti {
    rust_type!(Lti);
    fn updates(&self) -> bool {
        false
    }
    fn num_states(&self) -> usize {
        self.ss.n
    }
    fn initialize(&mut self, x0: &mut [f64]) {
        x0.copy_from_slice(&self.x0);
    }
    /// Sizes are asked of the view (its widths and `x.len()`), where a
    /// generated step knows them (see [`Io::output_width`]).
    #[inline(always)]
    fn output(&mut self, io: &mut Io) {
        if !self.feedthrough && io.output_width(0) == 1 {
            // A transfer function: y = C·x straight to the port (the
            // common case, kept free of the general case's registers).
            return io.set(0, self.ss.output_state_only_scalar(io.x));
        }
        self.output_general(io.x, io.input(0));
        io.set_all(0, &self.y);
    }
    #[inline(always)]
    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        if io.input_width(0) == 1 {
            return self.ss.derivative_single_input(io.x, io.u(0), dx);
        }
        self.derivatives_general(io.x, io.input(0), dx);
    }
    fn lti(&self) -> Option<&StateSpace> {
        Some(&self.ss)
    }
}

/// Maps realisation errors onto the parameter they concern.
pub(crate) fn lti_error(p: &Params, e: LtiError) -> Diagnostic {
    let key = match e {
        LtiError::Improper { .. } => "num",
        LtiError::ZeroDenominator => "den",
        _ => "poles",
    };
    let d = p.error(key, &e);
    match e {
        LtiError::Improper { .. } => d.with_hint("a physical system needs at least as many poles as zeros"),
        _ => d,
    }
}

fn build_tf(p: &mut Params) -> Result<Built, Diagnostic> {
    let (num, den) = (p.polynomial_factors("num")?, p.polynomial_factors("den")?);
    let gain = p.number_where("gain", None, f64::is_finite, "a finite number")?;
    let ss = factored_tf2ss(&num, &den, gain).map_err(|e| lti_error(p, e))?;
    let n = ss.n;
    Ok(Lti::new(ss, vec![0.0; n]).built())
}

fn build_zpk(p: &mut Params) -> Result<Built, Diagnostic> {
    let to_c = |v: Vec<(f64, f64)>| v.into_iter().map(|(re, im)| Complex::new(re, im)).collect::<Vec<_>>();
    let zeros = to_c(p.roots("zeros")?);
    if !p.has("poles") {
        return Err(p.block_error("missing parameter `poles`"));
    }
    let poles = to_c(p.roots("poles")?);
    let gain = p.number("gain")?;
    let (num, den) = zpk2tf(&zeros, &poles, gain).map_err(|e| lti_error(p, e))?;
    let ss = tf2ss(&num, &den).map_err(|e| match e {
        LtiError::Improper { .. } => p.error("zeros", format!("{e}: more zeros than poles")),
        other => lti_error(p, other),
    })?;
    let n = ss.n;
    Ok(Lti::new(ss, vec![0.0; n]).built())
}

fn build_state_space(p: &mut Params) -> Result<Built, Diagnostic> {
    let (a, b, c) = (p.matrix("A")?, p.matrix("B")?, p.matrix("C")?);
    let d = if p.has("D") {
        p.matrix("D")?
    } else {
        let m = b.first().map_or(0, Vec::len);
        vec![vec![0.0; m]; c.len()]
    };
    let ss = StateSpace::new(a, b, c, d).map_err(|e| p.error("A", e))?;
    let initial = p.vector("initial")?;
    let x0 = initial_vector(&initial, ss.n).map_err(|m| p.error("initial", m))?;
    Ok(Lti::new(ss, x0).built())
}
