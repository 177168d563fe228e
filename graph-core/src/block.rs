//! The block trait: what every block in the library implements, and the
//! view of the signal buffer a block gets when it runs.
//!
//! The simulator calls, per major step (Simulink semantics):
//! 1. [`Block::output`] in execution order — continuous blocks at every major
//!    and minor step, discrete blocks only at their sample hits (their
//!    outputs hold in between), constant blocks once;
//! 2. (the recorder samples the signals);
//! 3. [`Block::update`] — discrete blocks at their hits, continuous blocks at
//!    every major step (for memory such as a rate limiter's last output);
//! 4. integration of continuous states via [`Block::derivatives`], the
//!    solver's minor steps calling `output` of continuous blocks again.
//!
//! Blocks with corners or switches have *modes* and *zero crossings*
//! (Simulink's terms). A block switches mode only where [`Io::may_switch`]
//! says so — at major steps; in minor steps its mode is frozen, so each side
//! of a corner integrates its own smooth equation. Its zero-crossing
//! functions ([`Block::zero_crossings`]) tell the simulator where a mode
//! change is due; the simulator locates the sign change inside the step and
//! ends the step there, and the next major step switches. Because of that,
//! `output` must be idempotent within a major step: it may run twice (after
//! a [`Block::major_step`] reset) and must not advance state.

mod io;
pub use io::Io;

use ctlgraph_solver::StateSpace;
use std::fmt;

/// When a block runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SampleTime {
    /// At every major and minor step.
    Continuous,
    /// At `offset + k·period`, k = 0, 1, 2, …; output held in between.
    Discrete { period: f64, offset: f64 },
    /// Takes the rate of the blocks driving it.
    Inherited,
    /// Output computed once, at the start.
    Constant,
}

impl SampleTime {
    /// The period of a discrete sample time.
    pub fn period(&self) -> Option<f64> {
        match *self {
            SampleTime::Discrete { period, .. } => Some(period),
            _ => None,
        }
    }
}

/// A time in its shortest form: plain between 1e-4 and 1e15, else with an
/// exponent (`1e-300`, not three hundred digits).
struct Seconds(f64);

impl fmt::Display for Seconds {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v == 0.0 || (1e-4..1e15).contains(&v.abs()) || !v.is_finite() {
            write!(f, "{v}")
        } else {
            write!(f, "{v:e}")
        }
    }
}

impl fmt::Display for SampleTime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SampleTime::Continuous => f.write_str("continuous"),
            SampleTime::Discrete { period, offset } if *offset == 0.0 => {
                write!(f, "discrete {}", Seconds(*period))
            }
            SampleTime::Discrete { period, offset } => {
                write!(f, "discrete {} offset {}", Seconds(*period), Seconds(*offset))
            }
            SampleTime::Inherited => f.write_str("inherited"),
            SampleTime::Constant => f.write_str("constant"),
        }
    }
}

/// Which sign changes of a zero-crossing function are events.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Crossing {
    /// From negative to positive.
    Rising,
    /// From positive to negative.
    Falling,
    Either,
    /// Not watched in the block's current mode.
    Ignore,
}

impl Crossing {
    /// Whether a change from sign `before` (±1) to the opposite is an event.
    pub fn accepts(self, before: f64) -> bool {
        match self {
            Crossing::Rising => before < 0.0,
            Crossing::Falling => before > 0.0,
            Crossing::Either => true,
            Crossing::Ignore => false,
        }
    }
}

/// The width of a port.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Width {
    Fixed(usize),
    /// The block's common width, resolved from its neighbours at compile
    /// time (elementwise blocks work on any width). An input of common
    /// width also accepts a scalar, which is broadcast.
    Common,
}

#[derive(Clone, Debug, PartialEq)]
pub struct InputPort {
    pub name: String,
    pub width: Width,
    /// Whether the block's output at a step depends on this input at the
    /// same step. Only such edges order blocks and can form algebraic loops.
    pub feedthrough: bool,
}

#[derive(Clone, Debug, PartialEq)]
pub struct OutputPort {
    pub name: String,
    pub width: Width,
}

/// A block's ports and rate, fixed when it is built.
#[derive(Clone, Debug, PartialEq)]
pub struct Interface {
    pub inputs: Vec<InputPort>,
    pub outputs: Vec<OutputPort>,
    pub sample_time: SampleTime,
    /// See [`Interface::piecewise_constant`].
    pub piecewise_constant: bool,
}

impl Interface {
    pub fn new(sample_time: SampleTime) -> Self {
        Interface { inputs: Vec::new(), outputs: Vec::new(), sample_time, piecewise_constant: false }
    }

    /// Declares that the outputs stay constant between major steps whenever
    /// the inputs do: a function of the inputs and of modes or memory that
    /// change only at major steps (a sum, a saturation, a fuzzy system), or
    /// a source that changes only at its events (a step). Not for blocks
    /// that read `io.t` or have continuous states. The simulator then skips
    /// the block in the solver's minor steps where nothing there reads it,
    /// and LTI blocks it drives can be stepped exactly (Simulink calls such
    /// signals "fixed in minor step").
    pub fn piecewise_constant(mut self) -> Self {
        self.piecewise_constant = true;
        self
    }

    /// Adds an input port.
    pub fn input(mut self, name: &str, width: Width, feedthrough: bool) -> Self {
        self.inputs.push(InputPort { name: name.to_string(), width, feedthrough });
        self
    }

    /// Adds an output port.
    pub fn output(mut self, name: &str, width: Width) -> Self {
        self.outputs.push(OutputPort { name: name.to_string(), width });
        self
    }

    /// Whether any port takes the common width.
    pub fn has_common_width(&self) -> bool {
        self.inputs.iter().any(|p| p.width == Width::Common) || self.outputs.iter().any(|p| p.width == Width::Common)
    }
}

/// Where a port's values live in the signal buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Port {
    pub offset: usize,
    pub width: usize,
}

/// A major step at which signals may be discontinuous: a sample hit, a
/// block event, a located zero crossing, a clamped state, a host's input.
/// Blocks that keep their input's past ([`Block::keeps_history`]) receive
/// the signals' left limit there ([`Block::left_limit`]), so that what
/// they interpolate never straddles a jump or a kink, and may schedule the
/// discontinuity's arrival at their output as an event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Breakpoint {
    /// How many delays the discontinuity has passed through: 0 where it
    /// arose, one more at each delay's output (the lowest of the causes
    /// when several coincide).
    pub generation: u32,
    /// Only sample hits fall here: discrete outputs may have jumped, but
    /// the kinks they leave in continuous signals are many (one per hit)
    /// and left to the solver.
    pub sample_hit_only: bool,
}

/// A memoryless computation that a block's `output` performs, simple
/// enough for the scheduler to run in place of [`Block::output`] on the
/// signal buffer, so the common sums, gains and demuxes of a diagram skip
/// the view and the dynamic call that cost several times their arithmetic.
/// `Scale` and `Affine2` run so when the block's ports are all scalar,
/// `Copy` whatever the widths.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kernel {
    /// y = k·u0
    Scale(f64),
    /// y = a·u0 + b·u1
    Affine2(f64, f64),
    /// The one input's elements, in order, to the outputs end to end (a
    /// demux: the outputs lie side by side in the signal buffer).
    Copy,
}

impl Kernel {
    /// How many inputs it reads.
    pub fn arity(&self) -> usize {
        match self {
            Kernel::Scale(_) | Kernel::Copy => 1,
            Kernel::Affine2(..) => 2,
        }
    }

    /// y from scalar inputs (`u1` unused by `Scale` and `Copy`). Blocks with
    /// a scalar kernel compute their scalar output through this, so both
    /// paths agree to the bit.
    #[inline]
    pub fn eval(&self, u0: f64, u1: f64) -> f64 {
        match *self {
            Kernel::Scale(k) => k * u0,
            Kernel::Affine2(a, b) => a * u0 + b * u1,
            Kernel::Copy => u0,
        }
    }
}

/// How the outputs of a block that is a function of time alone change
/// ([`Block::time_only`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeOnly {
    /// Continuously: one evaluation per time.
    Smooth,
    /// With jumps at the block's events ([`Io::reached`]): a time's left
    /// limit counts as another time.
    JumpsAtEvents,
}

/// A block of the library. See the module docs for when each method runs.
/// Blocks are `Clone` (derive it): each run works on its own copies of the
/// compiled model's blocks, kept in its [`crate::RunState`], and a snapshot
/// of a run ([`crate::Simulator::state`]) is a clone of that. They are
/// `Sync`, so one compiled model can be shared by runs on many threads. They are
/// `Any` (every `'static` type is), so code that knows a graph's block
/// types — a fused step, generated or written for a benchmark — can take
/// a compiled model's blocks back as their concrete types
/// (`Box<dyn Block>` → `Box<dyn Any>` → `downcast`) and call them without
/// dynamic dispatch.
pub trait Block: std::any::Any + Send + Sync + dyn_clone::DynClone {
    /// Receives the resolved common width (only called for blocks with a
    /// [`Width::Common`] port), before any other call. Allocate here.
    fn set_width(&mut self, _width: usize) -> Result<(), String> {
        Ok(())
    }

    /// Number of continuous states (after `set_width`).
    fn num_states(&self) -> usize {
        0
    }

    /// Resets discrete state and writes the initial continuous states.
    /// Called on each run's own copy of the block (a clone of the compiled
    /// model's, which keeps no spare capacity): reserve working space that
    /// grows during a run here, not at build.
    fn initialize(&mut self, _x0: &mut [f64]) {}

    /// Computes the outputs from the inputs, `io.x` and discrete state.
    fn output(&mut self, io: &mut Io);

    /// The memoryless computation `output` performs, if it is one (see
    /// [`Kernel`]); asked after `set_width`. A block that returns one must
    /// have no state and compute exactly it (for scalar ports, when the
    /// kernel is scalar).
    fn kernel(&self) -> Option<Kernel> {
        None
    }

    /// The formula `output` computes, if it is one: its one scalar output
    /// from its scalar inputs (variable slots 0 … n − 1) and the time (slot
    /// n), with no state. A generated step writes it in place
    /// ([`crate::expr::Expr::to_rust`]) instead of calling `output`.
    fn formula(&self) -> Option<&crate::expr::Expr> {
        None
    }

    /// `Some` when the outputs are a function of time alone (no inputs,
    /// states or memory that changes): the scheduler then calls `output`
    /// once per time and keeps its outputs while it is asked again at that
    /// time (RK4's two middle stages share one; its last stage's is the
    /// next major step's). [`TimeOnly`] says whether they jump at events.
    fn time_only(&self) -> Option<TimeOnly> {
        None
    }

    /// Advances discrete state (or major-step memory) after outputs.
    fn update(&mut self, _io: &mut Io) {}

    /// Whether [`Block::update`] does anything. A block without discrete
    /// state or major-step memory returns false, and the scheduler then
    /// skips it in the update pass (a call saved per block and step).
    /// Returning false also promises that `output` depends on t, the
    /// states and the inputs alone (besides modes under zero crossings):
    /// a solver step's first stage, at the (t, x) the major step has just
    /// computed, then reuses the block's outputs instead of calling it.
    fn updates(&self) -> bool {
        true
    }

    /// Writes the derivatives of the continuous states.
    fn derivatives(&mut self, _io: &Io, _dx: &mut [f64]) {}

    /// Whether the block is a plain integrator: its output is its states
    /// and their derivatives are its one input, element by element (ẋ = u,
    /// y = x), with no limits, resets, modes or memory besides. The
    /// scheduler then copies both in place of calling `output` and
    /// `derivatives` (which must still compute exactly that), and skips
    /// `clamp_states`.
    fn is_plain_integrator(&self) -> bool {
        false
    }

    /// Projects continuous states back into their admissible set (limited
    /// integrators) after an accepted step; returns whether anything moved.
    fn clamp_states(&self, _x: &mut [f64]) -> bool {
        false
    }

    /// The first time strictly after `t` at which the output jumps, so the
    /// simulator can put a major step exactly there.
    fn next_event(&self, _t: f64) -> f64 {
        f64::INFINITY
    }

    /// The shortest time between two of the block's events (a pulse's high
    /// or low phase), so that the compiler can refuse a graph whose events
    /// could not all be stepped to before the stop time.
    fn min_event_spacing(&self) -> f64 {
        f64::INFINITY
    }

    /// Number of zero-crossing functions (after `set_width`), fixed for the
    /// run. Only continuous-rate blocks are watched.
    fn num_zero_crossings(&self) -> usize {
        0
    }

    /// Whether [`Block::major_step`] must run (by default: when the block
    /// has zero crossings).
    fn needs_major_step(&self) -> bool {
        self.num_zero_crossings() > 0
    }

    /// Writes the zero-crossing functions at `io.t`: continuous in time while
    /// the block's mode is frozen; a sign change accepted by
    /// [`Block::crossing_direction`] is an event.
    fn zero_crossings(&self, _io: &Io, _g: &mut [f64]) {}

    /// Which sign changes of function `k` are events, in the current mode.
    fn crossing_direction(&self, _k: usize) -> Crossing {
        Crossing::Either
    }

    /// Why the block's output became NaN at run time (a buffer limit, say),
    /// asked when the run stops on a non-finite value.
    fn diagnose(&self) -> Option<String> {
        None
    }

    /// Function `k`'s crossing ended the step: the coming major step is at
    /// the crossing. A block whose reaction depends on the side of zero
    /// (an edge-triggered reset) must not re-derive it from values there,
    /// which lie within a few ulps of zero on either side.
    fn crossing_located(&mut self, _k: usize) {}

    /// Why the block has no linear model at an instant, if it has none:
    /// memory in continuous time that the solver does not integrate (a
    /// transport delay's history). Linearisation refuses a path through it.
    fn not_linearizable(&self) -> Option<&'static str> {
        None
    }

    /// The block's linear model per sample hit when it is a discrete block
    /// with memory that is linear (around where it stands): state z kept
    /// by the block, z⁺ = A z + B u at the update, y = C z + D u at the
    /// output, u and y all input and output elements in port order.
    /// Linearisation of sampled-data paths needs it of every such block on
    /// the path.
    fn discrete_lti(&self) -> Option<StateSpace> {
        None
    }

    /// The numbers a discrete block's `update` changes (its memory), for
    /// linearising a nonlinear discrete block by perturbing them; blocks
    /// with a [`Block::discrete_lti`] need not give it.
    fn discrete_state(&mut self) -> Option<&mut [f64]> {
        None
    }

    /// The block's matrices when it is a continuous LTI system whose states
    /// are exactly the system's (transfer functions, zpk, state space): the
    /// simulator may then advance it by its exact zero-order-hold transition
    /// instead of integrating it, where its inputs are piecewise constant.
    fn lti(&self) -> Option<&StateSpace> {
        None
    }

    /// The block's Rust type as generated code names it
    /// (`ctlgraph_blocks::pid::ContinuousPid`), for a generated step
    /// ([`crate::codegen`]) that calls the block without dynamic dispatch.
    /// `None` (the default) keeps the call dynamic: right for types that
    /// cannot be named, such as blocks built around a closure.
    fn rust_type(&self) -> Option<&'static str> {
        None
    }

    /// The block's C form for `ctlgraph codegen --target c` ([`crate::codegen::c`]):
    /// its memory, reset, output and update as C99 statements written into
    /// `c`, the same operations in the same order as `output` and `update`
    /// (so the C gives the simulation's bits). The default: the type has none.
    fn c_form(&self, _c: &mut crate::codegen::c::CBlock) -> Result<(), crate::codegen::c::NoCForm> {
        Err(crate::codegen::c::NoCForm::Type)
    }

    /// Runs at every major step after all outputs, for continuous blocks
    /// that [`Block::needs_major_step`]: the block may switch modes that
    /// depend on inputs without feedthrough, and reset its continuous states
    /// `x` (`io.x` is empty here). Returns whether anything changed, so that outputs are
    /// computed again with the new states.
    fn major_step(&mut self, _io: &Io, _x: &mut [f64]) -> bool {
        false
    }

    /// What the block decided when it was built that a user should see in
    /// `ctlgraph check` (a planned profile's peak and duration, a limit
    /// that lowered a parameter), if anything.
    fn build_report(&self) -> Option<String> {
        None
    }

    /// The value a host program sets, for the compiler's top-level inports
    /// only; library blocks keep the default.
    fn external_input(&mut self) -> Option<&mut [f64]> {
        None
    }

    /// Whether the block keeps its first input's past to interpolate in
    /// (transport delays). The simulator then evaluates that input in the
    /// solver's minor steps and calls [`Block::left_limit`] at breakpoints.
    fn keeps_history(&self) -> bool {
        false
    }

    /// At a [`Breakpoint`], before the major step's outputs: `io` shows the
    /// signals' left limit there (continuous signals at the step's end,
    /// modes as in the step, discrete outputs and inputs not yet changed).
    /// The block's `update` at the same time then sees the right limit.
    fn left_limit(&mut self, _io: &Io, _at: Breakpoint) {}

    /// The [`Breakpoint::generation`] of the event [`Block::next_event`]
    /// reports for `t`: 0 for a source's own jump, more for a
    /// discontinuity a delay passes on.
    fn event_generation(&self, _t: f64) -> u32 {
        0
    }

    /// The fixed time by which the output lags the input (a transport
    /// delay's dead time), for the solver's default `max_step` and the
    /// warnings about steps longer than a delay in a loop.
    fn dead_time(&self) -> Option<f64> {
        None
    }
}

dyn_clone::clone_trait_object!(Block);
