//! Runs a generated step: the simulator's time keeping (the fixed-step
//! grid, clocks counted in ticks, block events, the exact-ZOH hold) around
//! the generated sweeps, so both compute the same numbers to the bit.

use crate::block::{Breakpoint, Kernel, Port};
use crate::compile::{BlockMeta, Model};
use crate::sim::{self, Blame, OnGrid, RunStats, SimError, Timing};
use ctlgraph_solver::{Integrator, OdeSystem, Zoh, ZohSingleInput};

/// What `ctlgraph codegen` writes for a graph: its sweeps unrolled over
/// the graph's blocks. Implemented by generated code only; the methods are
/// the simulator's steps (see [`crate::block`]), called by [`Compiled`].
pub trait GeneratedStep: Sized {
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
/// graphs [`super::generate`] accepts, with the same results.
pub struct Compiled<G: GeneratedStep> {
    step: G,
    x: Vec<f64>,
    integ: Integrator,
    timing: Timing,
    /// The clocks counted in grid steps, when they all fall on the grid.
    on_grid: Option<OnGrid>,
    hit: Vec<bool>,
    t: f64,
    stop: f64,
    first: bool,
    /// Whether every signal was finite after the last output sweep.
    all_finite: bool,
    at_event: bool,
    next_event: f64,
    next_event_generation: u32,
    /// Left limits were handed out at the last major step: the updates may
    /// schedule events (see the simulator's field of that name).
    events_may_change: bool,
    n_integrated: usize,
    major_steps: u64,
    /// Major steps in a row at which time did not advance ([`sim::count_stall`]).
    stalled: u32,
    /// For naming a block in an error.
    meta: Vec<BlockMeta>,
    in_ports: Vec<Port>,
    out_ports: Vec<Port>,
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

impl<G: GeneratedStep> Compiled<G> {
    /// A run of `model` to `stop` (the graph's own when `None`); `Err` when
    /// `G` was generated for a model of another structure.
    pub fn new(model: &Model, stop: Option<f64>) -> Result<Self, String> {
        match super::fingerprint(model) {
            Some(f) if f == G::FINGERPRINT => {}
            Some(_) => {
                return Err(format!(
                    "`{}` is not the graph this step was generated for (its blocks, wiring or \
                     rates differ); regenerate it with `ctlgraph codegen`",
                    model.file
                ));
            }
            None => return Err(format!("`{}`: {}", model.file, super::refusals(model).join("; "))),
        }
        let stop = stop.unwrap_or(model.sim.stop);
        let timing = Timing::new(model, stop);
        let mut run = Compiled {
            step: G::from_model(model)?,
            x: vec![0.0; model.n_states],
            integ: Integrator::new(timing.method, model.between.n_integrated),
            hit: vec![false; timing.clocks.len()],
            on_grid: OnGrid::new(&timing),
            timing,
            t: 0.0,
            stop,
            first: true,
            all_finite: true,
            at_event: true,
            next_event: f64::INFINITY,
            next_event_generation: 0,
            events_may_change: false,
            n_integrated: model.between.n_integrated,
            major_steps: 0,
            stalled: 0,
            meta: model.meta.clone(),
            in_ports: model.in_ports.clone(),
            out_ports: model.out_ports.clone(),
        };
        run.reset();
        Ok(run)
    }

    /// Back to t = 0 with initial states (blocks re-initialised).
    pub fn reset(&mut self) {
        self.t = 0.0;
        self.first = true;
        self.all_finite = true;
        self.at_event = true;
        self.major_steps = 0;
        self.stalled = 0;
        self.timing.grid.set_tick(1);
        self.step.signals_mut().iter_mut().for_each(|s| *s = 0.0);
        self.step.initialize(&mut self.x);
        self.timing.clocks.iter_mut().for_each(|c| c.set_tick(0));
        match &mut self.on_grid {
            Some(on_grid) => on_grid.reset(&mut self.hit),
            None => {
                self.mark_hits();
            }
        }
        (self.next_event, self.next_event_generation) = self.step.next_event(self.t);
        self.events_may_change = false;
        self.integ.reset();
    }

    pub fn signals(&self) -> &[f64] {
        self.step.signals()
    }

    pub fn states(&self) -> &[f64] {
        &self.x
    }

    pub fn time(&self) -> f64 {
        self.t
    }

    pub fn stats(&self) -> RunStats {
        RunStats { major_steps: self.major_steps, solver: self.integ.stats(), events: 0 }
    }

    /// Whether the run counts its discrete rates in grid steps (every
    /// period 1/n_c s dividing the grid's step of 1/n s, no offsets: see
    /// `sim::clock::OnGrid`) rather than keeping a time per clock.
    pub fn clocks_on_grid(&self) -> bool {
        self.on_grid.is_some()
    }

    /// Whether the run has reached its stop time.
    pub fn finished(&self) -> bool {
        self.t >= self.stop - self.timing.tol && !self.first
    }

    /// The clocks due at `self.t`, found by their times (when they are
    /// not all on the grid).
    fn mark_hits(&mut self) -> bool {
        let any = sim::mark_hits(&mut self.timing.clocks, self.t, self.timing.tol);
        for (h, c) in self.hit.iter_mut().zip(&self.timing.clocks) {
            *h = c.hit;
        }
        any
    }

    /// Step (1) of a major step: outputs in execution order, then a check
    /// that every signal is finite.
    ///
    /// The step checks what it writes; signals it did not write this time
    /// were checked when they were, unless a step found one not finite
    /// (then the whole buffer is checked again at every step).
    pub fn outputs(&mut self) -> Result<(), SimError> {
        let all = self.first || self.at_event;
        let wrote_finite = self.step.outputs(self.t, &self.x, self.first, all, &self.hit);
        self.first = false;
        if !(wrote_finite && self.all_finite) {
            self.all_finite = sim::all_finite(self.step.signals());
            if !self.all_finite {
                let step = &self.step;
                return Err(self.blame().signal(step.signals(), self.t, |i| step.diagnose(i)));
            }
        }
        Ok(())
    }

    /// What names a block in this run's errors.
    fn blame(&self) -> Blame<'_> {
        Blame { meta: &self.meta, in_ports: &self.in_ports, out_ports: &self.out_ports }
    }

    /// Steps (3) and (4): updates, then integration to the next major step.
    pub fn advance(&mut self) -> Result<(), SimError> {
        self.step.updates(self.t, &self.x, &self.hit);
        if std::mem::take(&mut self.events_may_change) {
            (self.next_event, self.next_event_generation) = self.step.next_event(self.t);
        }
        self.step.hold_inputs();
        if self.on_grid.is_some() && self.n_integrated == 0 && !G::KEEPS_HISTORY {
            let next = self.timing.grid.next;
            if next <= self.stop && self.next_event > next + self.timing.tol {
                return self.advance_to_grid_point(next);
            }
        }
        let target = self.next_major_time();
        let t0 = self.t;
        let x = &mut self.x[..self.n_integrated];
        let t_new = if x.is_empty() {
            target.min(t0 + self.timing.method.max_step())
        } else {
            let mut stage = Stage { step: &mut self.step, t_end: target };
            match self.integ.advance(&mut stage, t0, target, x) {
                Ok(t) => t,
                Err(error) => return Err(self.blame().solver(self.step.signals(), t0, error)),
            }
        };
        let tol = self.timing.tol;
        self.t = if (target - t_new).abs() <= tol { target } else { t_new };
        if self.t > t0 {
            self.step.step_held(self.t - t0, &mut self.x);
        }
        let on_grid = self.timing.grid_step > 0.0 && self.timing.grid.pass(self.t, tol);
        let clamped = self.step.clamp_states(&mut self.x[..self.n_integrated]);
        let hit = match &mut self.on_grid {
            Some(clocks) => clocks.mark_hits(on_grid, &mut self.hit),
            None => self.mark_hits(),
        };
        let block_event = self.t >= self.next_event - tol;
        self.at_event = block_event;
        let event_generation = self.next_event_generation;
        if block_event {
            (self.next_event, self.next_event_generation) = self.step.next_event(self.t);
        }
        if hit || block_event || clamped {
            self.integ.invalidate();
        }
        if G::KEEPS_HISTORY
            && let Some(at) = sim::breakpoint(hit, block_event, clamped, event_generation)
        {
            self.step.left_limits(self.t, &self.x[..self.n_integrated], at);
            self.events_may_change = true;
        }
        self.check_states()?;
        let step = &self.step;
        sim::count_stall(&mut self.stalled, t0, self.t, &self.meta, |i| step.block_event(i, t0))?;
        self.major_steps += 1;
        Ok(())
    }

    /// [`Self::advance`]'s steps after the updates, where they are known to
    /// end at the grid's next point `next`: nothing is integrated (held LTI
    /// blocks are stepped exactly), no block keeps history (so no left
    /// limits are due at hits), the clocks are on the grid, and neither
    /// the stop time nor a block event comes first. The general path then
    /// takes `next` as the major step's time (the integrator's candidate
    /// t0 + h differs from it by rounding only), marks the grid and the
    /// clocks passed, and sees no event; here those same results are set
    /// without computing and comparing the candidates.
    fn advance_to_grid_point(&mut self, next: f64) -> Result<(), SimError> {
        let t0 = self.t;
        self.t = next;
        self.step.step_held(next - t0, &mut self.x);
        self.timing.grid.pass_one();
        if let Some(clocks) = &mut self.on_grid {
            clocks.mark_hits(true, &mut self.hit);
        }
        self.at_event = false;
        self.check_states()?;
        self.major_steps += 1;
        Ok(())
    }

    fn check_states(&self) -> Result<(), SimError> {
        if sim::all_finite(&self.x) { Ok(()) } else { Err(self.blame().state(self.step.signals(), self.t, &self.x)) }
    }

    /// The next major step's time, as the simulator decides it.
    /// With the clocks on the grid, their next hits are grid points no
    /// earlier than the grid's next: the grid alone decides.
    fn next_major_time(&self) -> f64 {
        let timing = &self.timing;
        let grid = (timing.grid_step > 0.0).then_some(&timing.grid);
        let clocks = if self.on_grid.is_some() { &[][..] } else { &timing.clocks[..] };
        sim::next_major_time(clocks, grid, self.stop, self.next_event, timing.tol)
    }

    /// Runs to the stop time, handing the signals to `sink` at every major
    /// step (including t = 0 and the stop time), as [`crate::Simulator::run`].
    /// The sink is a type parameter, not a `dyn` call: it inlines into the
    /// loop, which then keeps its values in registers across it.
    pub fn run(&mut self, mut sink: impl FnMut(f64, &[f64])) -> Result<RunStats, SimError> {
        loop {
            self.outputs()?;
            sink(self.t, self.step.signals());
            if self.finished() {
                return Ok(self.stats());
            }
            self.advance()?;
        }
    }
}
