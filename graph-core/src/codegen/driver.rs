//! Runs a generated step: the driver's time keeping (`sim/driver.rs`: the
//! grid, clocks counted in ticks, block events, the exact-ZOH hold, every
//! solver) around the generated sweeps, so both back-ends compute the same
//! numbers to the bit.

use crate::block::{Breakpoint, Crossing, Kernel, Port};
use crate::compile::{BlockMeta, Model};
use crate::sim::events::{Crossings, Watch};
use crate::sim::output::{Dense, RowSystem};
use crate::sim::{self, Blame, Clockwork, RunStats, SimError, Sweeps, driver};
use crate::trace::ColumnBatch;
use ctlgraph_solver::{OdeSystem, Zoh, ZohSingleInput};
use std::sync::Arc;

/// What `ctlgraph codegen` writes for a graph: its sweeps unrolled over
/// the graph's blocks. Implemented by generated code only; the methods are
/// the simulator's steps (see [`crate::block`]), called by [`Compiled`].
pub trait GeneratedStep: Sized + Clone {
    /// The structure the code was generated for ([`super::fingerprint`]).
    const FINGERPRINT: u64;
    /// Whether a block keeps its input's past ([`crate::Block::keeps_history`]).
    const KEEPS_HISTORY: bool;
    /// Takes the blocks, with their parameters, from a model of that structure.
    fn from_model(model: &Model) -> Result<Self, String>;
    fn signals(&self) -> &[f64];
    fn signals_mut(&mut self) -> &mut [f64];
    fn initialize(&mut self, x: &mut [f64]);
    /// The output sweep: `first` on the first pass, `all` when every block
    /// runs (first pass, block events), `hit` per clock. Returns whether
    /// every value it wrote is finite ([`super::not_finite_bits`] of each block's
    /// outputs as it writes them).
    fn outputs(&mut self, t: f64, x: &[f64], first: bool, all: bool, hit: &[bool]) -> bool;
    fn updates(&mut self, t: f64, x: &[f64], hit: &[bool]);
    /// Latches the held LTI blocks' inputs at a major step.
    fn hold_inputs(&mut self);
    /// Advances the held LTI blocks' states by `dt`.
    fn step_held(&mut self, dt: f64, x: &mut [f64]);
    /// A solver stage: continuous outputs at (t, x), then derivatives.
    fn derivatives(&mut self, t: f64, left: bool, x: &[f64], dx: &mut [f64]);
    /// A stage's continuous outputs alone (for locating a crossing).
    fn minor_outputs(&mut self, t: f64, left: bool, x: &[f64]);
    /// A row between steps: the continuous outputs (event-only blocks'
    /// held) at (t, x), x all states.
    fn row_outputs(&mut self, t: f64, left: bool, x: &[f64]);
    /// Held LTI block `j`'s latched input.
    fn held_input(&self, j: usize) -> &[f64];
    /// Appends a recorded row — t, then the signals at
    /// [`crate::trace::gather_offsets`], written as constants — to `batch`.
    fn record_row(t: f64, signals: &[f64], batch: &mut ColumnBatch);
    /// Watched block `b`'s zero-crossing functions at (t, x), outputs
    /// computed: at a major step (`major`), or in a stage (modes frozen
    /// as [`GeneratedStep::freeze`] set them). The watched blocks are
    /// `sim::events::watched`'s, in its order.
    fn zero_crossings(&mut self, b: usize, t: f64, left: bool, x: &[f64], major: bool, g: &mut [f64]);
    fn crossing_direction(&self, b: usize, k: usize) -> Crossing;
    fn crossing_located(&mut self, b: usize, k: usize);
    /// Whether watched block `b`'s modes freeze in minor steps.
    fn freeze(&mut self, b: usize, frozen: bool);
    /// The watched blocks' major-step work (mode switches, state resets);
    /// whether any changed something.
    fn major_step_events(&mut self, t: f64, x: &mut [f64]) -> bool;
    fn clamp_states(&mut self, x: &mut [f64]) -> bool;
    /// The earliest block event after `t` and its generation, as
    /// [`crate::sim::earlier`] folds the blocks' events.
    fn next_event(&self, t: f64) -> (f64, u32);
    /// At a breakpoint: the minor step's outputs at (t, x) as a left
    /// limit, handed to the blocks keeping history ([`crate::Block::left_limit`]).
    fn left_limits(&mut self, t: f64, x: &[f64], at: Breakpoint);
    fn diagnose(&self, block: usize) -> Option<String>;
    /// Block `block`'s next event after `t` ([`crate::Block::next_event`]),
    /// to name the block that holds time when a run stalls.
    fn block_event(&self, block: usize, t: f64) -> f64;
    /// The value a host sets of block `block`, when it is a top-level
    /// inport ([`crate::Block::external_input`]).
    fn external_input(&mut self, block: usize) -> Option<&mut [f64]>;
}

/// The kernel of the model's block `index`, for generated code reading
/// its constants.
pub fn kernel(model: &Model, index: usize) -> Option<Kernel> {
    model.blocks.get(index)?.kernel()
}

/// The exact transition of the model's LTI block `index`.
pub fn transition(model: &Model, index: usize) -> Result<Zoh, String> {
    let lti = model.blocks.get(index).and_then(|b| b.lti()).ok_or_else(|| mismatch(model, index))?;
    Ok(Zoh::new(lti.clone()))
}

/// The held LTI blocks' states and transitions, in the simulator's order
/// (for rows between steps, which step them over part of a step).
fn held_transitions(model: &Model) -> Result<Vec<(std::ops::Range<usize>, Zoh)>, String> {
    model.between.held.iter().map(|&i| Ok((model.slots[i].states.clone(), transition(model, i)?))).collect()
}

/// [`transition`] of a block of `N` states and one input, stepped at
/// those sizes.
pub fn transition_single_input<const N: usize>(model: &Model, index: usize) -> Result<ZohSingleInput<N>, String> {
    transition(model, index)?.single_input::<N>().ok_or_else(|| mismatch(model, index))
}

/// The error for a block that is not what the generated code expects.
pub fn mismatch(model: &Model, index: usize) -> String {
    match model.meta.get(index) {
        Some(m) => format!("block `{}` ({}) is not the block the generated step was made for", m.name, m.type_name),
        None => format!("the model has no block {index}, which the generated step expects"),
    }
}

/// `values` (a run's states or clock hits) as an array of the length the
/// generated code was made for: one length check per sweep, after which
/// its constant indices and ranges need none. The check cannot fail:
/// [`Compiled`] passes its model's own lengths, and refuses a model whose
/// structure differs from the one the code was generated for.
#[inline(always)]
pub fn fixed<T, const N: usize>(values: &[T]) -> &[T; N] {
    values.try_into().expect("a generated step's states and clocks have the counts it was generated for")
}

/// [`fixed`], writable.
#[inline(always)]
pub fn fixed_mut<T, const N: usize>(values: &mut [T]) -> &mut [T; N] {
    values.try_into().expect("a generated step's states and clocks have the counts it was generated for")
}

/// A zeroed signal buffer of `N` values, on the heap (a large one would
/// not fit on the stack).
pub fn zeros<const N: usize>() -> Box<[f64; N]> {
    let values = vec![0.0; N].into_boxed_slice();
    values.try_into().unwrap_or_else(|_| unreachable!("a boxed slice of N values is a boxed [f64; N]"))
}

/// A run of a generated step `G`: like [`crate::Simulator`] for the
/// graphs [`super::generate`] accepts, with the same results. Its time
/// keeping is the driver's ([`crate::sim::Sweeps`]); the generated step
/// provides the sweeps. A clone is a snapshot ([`Compiled::state`]).
#[derive(Clone)]
pub struct Compiled<G: GeneratedStep> {
    step: G,
    x: Vec<f64>,
    clockwork: Clockwork,
    /// The zero-crossing watch (`sim/events.rs`), as the interpreter's.
    watch: Watch,
    /// Rows between steps (`sim/output.rs`), as the interpreter's.
    dense: Option<Dense>,
    /// Whether every signal was finite after the last output sweep.
    all_finite: bool,
    /// Which run this is (a snapshot is restored only into its own).
    owner: u64,
    /// For naming a block in an error.
    names: Arc<Names>,
}

/// What a run keeps of its model to name a block in an error and to
/// check a host's input: shared by the run and its snapshots.
struct Names {
    meta: Vec<BlockMeta>,
    in_ports: Vec<Port>,
    out_ports: Vec<Port>,
    /// The top-level inports (block index) and their widths.
    inputs: Vec<(usize, usize)>,
}

/// A generated run at one instant, to return to with [`Compiled::restore`].
pub struct CompiledSnapshot<G: GeneratedStep>(Compiled<G>);

impl<G: GeneratedStep> CompiledSnapshot<G> {
    /// The time it was taken at.
    pub fn time(&self) -> f64 {
        self.0.time()
    }
}

/// The solver stage the integrator sees.
struct Stage<'a, G> {
    step: &'a mut G,
    t_end: f64,
}

impl<G: GeneratedStep> OdeSystem for Stage<'_, G> {
    fn derivatives(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        self.step.derivatives(t, t >= self.t_end, x, dx);
    }
}

impl<G: GeneratedStep> RowSystem for Stage<'_, G> {
    fn set_step_end(&mut self, t_end: f64) {
        self.t_end = t_end;
    }

    fn row_outputs(&mut self, t: f64, x: &[f64]) {
        self.step.row_outputs(t, t >= self.t_end, x);
    }

    fn signals(&self) -> &[f64] {
        self.step.signals()
    }

    fn latched(&self, j: usize) -> &[f64] {
        self.step.held_input(j)
    }
}

impl<G: GeneratedStep> Crossings for Stage<'_, G> {
    fn outputs(&mut self, t: f64, x: &[f64]) {
        self.step.minor_outputs(t, t >= self.t_end, x);
    }

    fn zero_crossings(&mut self, b: usize, _i: usize, t: f64, x: &[f64], g: &mut [f64]) {
        self.step.zero_crossings(b, t, t >= self.t_end, x, false, g);
    }

    fn direction(&self, b: usize, _i: usize, k: usize) -> Crossing {
        self.step.crossing_direction(b, k)
    }
}

impl<G: GeneratedStep> Compiled<G> {
    /// A run of `model` to `stop` (the graph's own when `None`); `Err` when
    /// `G` was generated for a model of another structure.
    pub fn new(model: &Model, stop: Option<f64>) -> Result<Self, String> {
        if super::fingerprint(model) != G::FINGERPRINT {
            return Err(format!(
                "`{}` is not the graph this step was generated for (its blocks, wiring or \
                 rates differ); regenerate it with `ctlgraph codegen`",
                model.file
            ));
        }
        let mut run = Compiled {
            step: G::from_model(model)?,
            x: vec![0.0; model.n_states],
            clockwork: Clockwork::new(model, stop.unwrap_or(model.sim.stop)),
            watch: Watch::new(model, model.sim.zero_crossing),
            dense: Dense::new(model.sim.output, model.n_states, model.between.n_integrated, held_transitions(model)?),
            all_finite: true,
            owner: sim::next_run_id(),
            names: Arc::new(Names {
                meta: model.meta.clone(),
                in_ports: model.in_ports.clone(),
                out_ports: model.out_ports.clone(),
                inputs: model
                    .external_inputs
                    .iter()
                    .map(|&(_, b)| (b, model.out_ports[model.slots[b].outputs.start].width))
                    .collect(),
            }),
        };
        run.reset();
        Ok(run)
    }

    /// Back to t = 0 with initial states (blocks re-initialised).
    pub fn reset(&mut self) {
        driver::reset(self);
    }

    pub fn signals(&self) -> &[f64] {
        self.step.signals()
    }

    pub fn states(&self) -> &[f64] {
        &self.x
    }

    pub fn time(&self) -> f64 {
        self.clockwork.t
    }

    pub fn stats(&self) -> RunStats {
        let events = self.watch.events;
        RunStats { major_steps: self.clockwork.major_steps, solver: self.clockwork.integ.stats(), events }
    }

    /// What the run has to say beyond its numbers, as
    /// [`crate::Simulator::warnings`].
    pub fn warnings(&self) -> &[String] {
        &self.watch.warnings
    }

    /// Whether the run counts its discrete rates in grid steps (every
    /// period 1/n_c s dividing the grid's step of 1/n s, no offsets: see
    /// `sim::clock::OnGrid`) rather than keeping a time per clock.
    pub fn clocks_on_grid(&self) -> bool {
        self.clockwork.on_grid.is_some()
    }

    /// Whether the run has reached its stop time.
    pub fn finished(&self) -> bool {
        self.clockwork.finished()
    }

    /// Step (1) of a major step: outputs in execution order, then a check
    /// that every signal is finite.
    pub fn outputs(&mut self) -> Result<(), SimError> {
        driver::outputs(self)
    }

    /// Steps (3) and (4): updates, then integration to the next major step.
    pub fn advance(&mut self) -> Result<(), SimError> {
        driver::advance(self)
    }

    /// Runs to the stop time, handing the signals to `sink` at every major
    /// step (including t = 0 and the stop time), as [`crate::Simulator::run`].
    /// The sink is a type parameter, not a `dyn` call: it inlines into the
    /// loop, which then keeps its values in registers across it.
    pub fn run(&mut self, mut sink: impl FnMut(f64, &[f64])) -> Result<RunStats, SimError> {
        self.run_while(|t, signals| {
            sink(t, signals);
            true
        })?;
        Ok(self.stats())
    }

    /// Like [`Compiled::run`], but `sink` may end the run early by
    /// returning `false`, as [`crate::Simulator::run_while`]. Returns
    /// whether the stop time was reached.
    pub fn run_while(&mut self, sink: impl FnMut(f64, &[f64]) -> bool) -> Result<bool, SimError> {
        driver::run_while(self, sink)
    }

    /// Sets the value of input block `block` (a top-level inport, index
    /// into the model's blocks) from now on, as [`crate::Simulator::set_input`]
    /// does by name ([`crate::Model::host_input`] finds the block and
    /// checks the value). `Err` when `block` is no input of that width.
    pub fn set_input(&mut self, block: usize, value: &[f64]) -> Result<(), String> {
        match self.names.inputs.iter().find(|&&(b, _)| b == block) {
            Some(&(_, width)) if width == value.len() && value.iter().all(|v| v.is_finite()) => {
                crate::sim::host::set_input(self, block, value);
                Ok(())
            }
            _ => Err(format!("block {block} is no input taking {} finite value(s)", value.len())),
        }
    }

    /// Simulates up to time `t` and stops exactly there, as
    /// [`crate::Simulator::advance_to`].
    pub fn advance_to(&mut self, t: f64) -> Result<(), SimError> {
        crate::sim::host::advance_to(self, t)
    }

    /// The signal buffer at the present time, outputs computed if they are
    /// not, as [`crate::Simulator::signals_now`].
    pub fn signals_now(&mut self) -> Result<&[f64], SimError> {
        crate::sim::host::refresh(self)?;
        Ok(self.step.signals())
    }

    /// The run as it stands, to return to later: every block's memory, the
    /// solver's history, the clocks.
    pub fn state(&self) -> CompiledSnapshot<G> {
        CompiledSnapshot(self.clone())
    }

    /// Returns the run to `snapshot`, taken of this run.
    pub fn restore(&mut self, snapshot: &CompiledSnapshot<G>) -> Result<(), String> {
        if snapshot.0.owner != self.owner {
            return Err("the snapshot was taken of another run".to_string());
        }
        self.clone_from(&snapshot.0);
        Ok(())
    }

    /// The first watched crossing between `t0` and `t1`, located ([`Sweeps::locate_crossing`]).
    #[inline(never)]
    fn locate_watched(&mut self, t0: f64, t1: f64, target: f64) -> Result<Option<f64>, SimError> {
        let mut stage = Stage { step: &mut self.step, t_end: target };
        let x = &mut self.x[..self.clockwork.n_integrated];
        let Some(t) = self.watch.locate(&mut stage, &mut self.clockwork.integ, t0, t1, x) else { return Ok(None) };
        for (b, _, k) in self.watch.fired() {
            self.step.crossing_located(b, k);
        }
        if let Some((b, _)) = self.watch.count_event(t, &self.names.meta)? {
            self.step.freeze(b, false);
        }
        Ok(Some(t))
    }

    /// [`Sweeps::output_sweep`]: the step checks what it writes; signals
    /// it did not write this time were checked when they were, unless a
    /// step found one not finite (then the whole buffer is checked again
    /// at every step).
    #[inline(always)]
    pub(super) fn sweep_outputs(&mut self) -> Result<(), Box<SimError>> {
        let c = &self.clockwork;
        let all = c.first || c.at_event || c.inputs_changed;
        let mut wrote_finite = self.step.outputs(c.t, &self.x, c.first, all, &c.hit);
        if !self.watch.blocks.is_empty() {
            if self.step.major_step_events(c.t, &mut self.x) {
                wrote_finite = self.step.outputs(c.t, &self.x, c.first, all, &c.hit);
            }
            let (step, t, x) = (&mut self.step, c.t, &self.x);
            self.watch.record_signs(|b, _, g| step.zero_crossings(b, t, false, x, true, g));
        }
        if !(wrote_finite && self.all_finite) {
            self.all_finite = sim::all_finite(self.step.signals());
            if !self.all_finite {
                let step = &self.step;
                return Err(Box::new(self.blame().signal(step.signals(), c.t, |i| step.diagnose(i))));
            }
        }
        Ok(())
    }

    /// [`Sweeps::update_sweep`].
    #[inline(always)]
    pub(super) fn sweep_updates(&mut self) {
        self.step.updates(self.clockwork.t, &self.x, &self.clockwork.hit);
    }

    /// What names a block in this run's errors.
    fn blame(&self) -> Blame<'_> {
        let n = &*self.names;
        Blame { meta: &n.meta, in_ports: &n.in_ports, out_ports: &n.out_ports }
    }
}

/// The generated step's sweeps, for the driver.
impl<G: GeneratedStep> Sweeps for Compiled<G> {
    #[inline(always)]
    fn clockwork(&self) -> &Clockwork {
        &self.clockwork
    }

    #[inline(always)]
    fn clockwork_mut(&mut self) -> &mut Clockwork {
        &mut self.clockwork
    }

    #[inline(always)]
    fn signals(&self) -> &[f64] {
        self.step.signals()
    }

    #[inline(always)]
    fn states(&self) -> &[f64] {
        &self.x
    }

    fn initialize(&mut self) {
        self.all_finite = true;
        self.step.signals_mut().iter_mut().for_each(|s| *s = 0.0);
        self.step.initialize(&mut self.x);
        self.watch.reset();
        if let Some(dense) = &mut self.dense {
            dense.reset();
        }
        for b in 0..self.watch.blocks.len() {
            self.step.freeze(b, self.watch.freezes());
        }
    }

    /// Never inlined, while the generated sweep is always inlined into it:
    /// one copy of the graph's code, called from every loop (a host's
    /// step, a refresh, a run with a sink per step), costs a call per
    /// major step; a copy inlined into each was instead left a call by the
    /// compiler once there were several (the step library's entries). The
    /// one loop that runs whole runs has its own copy ([`super::inlined`]).
    #[inline(never)]
    fn output_sweep(&mut self) -> Result<(), Box<SimError>> {
        self.sweep_outputs()
    }

    #[inline(always)]
    fn external_input(&mut self, block: usize) -> Option<&mut [f64]> {
        self.step.external_input(block)
    }

    /// Never inlined, the generated sweep always into it (as `output_sweep`).
    #[inline(never)]
    fn update_sweep(&mut self) {
        self.sweep_updates();
    }

    #[inline(always)]
    fn earliest_event(&self) -> (f64, u32) {
        self.step.next_event(self.clockwork.t)
    }

    fn block_event(&self, block: usize, t: f64) -> f64 {
        self.step.block_event(block, t)
    }

    #[inline(always)]
    fn latch_held(&mut self) {
        self.step.hold_inputs();
    }

    #[inline(always)]
    fn step_held(&mut self, dt: f64) {
        self.step.step_held(dt, &mut self.x);
    }

    fn integrate(&mut self, t0: f64, target: f64) -> Result<f64, SimError> {
        let mut stage = Stage { step: &mut self.step, t_end: target };
        let x = &mut self.x[..self.clockwork.n_integrated];
        match self.clockwork.integ.advance(&mut stage, t0, target, x) {
            Ok(t) => Ok(t),
            Err(error) => Err(self.blame().solver(self.step.signals(), t0, error)),
        }
    }

    /// As the interpreter's: a graph without watched crossings (most)
    /// answers without a call per step.
    #[inline(always)]
    fn locate_crossing(&mut self, t0: f64, t1: f64, target: f64) -> Result<Option<f64>, SimError> {
        if self.watch.blocks.is_empty() { Ok(None) } else { self.locate_watched(t0, t1, target) }
    }

    #[inline(always)]
    fn clamp_states(&mut self) -> bool {
        self.step.clamp_states(&mut self.x[..self.clockwork.n_integrated])
    }

    #[inline(always)]
    fn keeps_history(&self) -> bool {
        G::KEEPS_HISTORY
    }

    fn left_limits(&mut self, at: Breakpoint) {
        self.step.left_limits(self.clockwork.t, &self.x[..self.clockwork.n_integrated], at);
    }

    #[inline(always)]
    fn plain_grid_steps(&self) -> bool {
        !G::KEEPS_HISTORY && self.watch.blocks.is_empty() && self.dense.is_none()
    }

    fn names(&self) -> &[BlockMeta] {
        &self.names.meta
    }

    fn blame_states(&self) -> SimError {
        self.blame().state(self.step.signals(), self.clockwork.t, &self.x)
    }

    #[inline(always)]
    fn step_started(&mut self, t0: f64) {
        if let Some(dense) = &mut self.dense {
            dense.start(t0, &self.x);
        }
    }

    #[inline(always)]
    fn solver_reached(&mut self, t: f64) {
        if let Some(dense) = &mut self.dense {
            dense.solver_end(t, &self.x[..self.clockwork.n_integrated]);
        }
    }

    #[inline(always)]
    fn step_ended(&mut self) {
        if let Some(dense) = &mut self.dense {
            dense.end(self.clockwork.t);
        }
    }

    #[inline(always)]
    fn major_row(&mut self, t: f64) -> Option<f64> {
        self.dense.as_mut().map_or(Some(t), |dense| dense.major_row(t))
    }

    #[inline(always)]
    fn rows_inside_step(&mut self, sink: &mut dyn FnMut(f64, &[f64]) -> bool) -> bool {
        let Some(dense) = &mut self.dense else { return true };
        let mut stage = Stage { step: &mut self.step, t_end: 0.0 };
        dense.rows(&mut self.clockwork.integ, &mut stage, sink)
    }
}
