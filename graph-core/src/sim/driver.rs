//! The driver: the one loop that keeps a run's time, over a back-end that
//! provides the sweeps. The interpreter ([`crate::Simulator`], which walks
//! the model's blocks) and a generated step ([`crate::codegen::Compiled`],
//! which runs code written for one graph) are the two back-ends; both
//! implement [`Sweeps`], and the functions here are all either has of a
//! major step's time keeping: the fixed-step grid and the clocks, block
//! events, zero crossings located by the back-end, the exact-ZOH hold,
//! landing on a host's time, breakpoints, stall and non-finite detection.
//! ARCHITECTURE.md tells the life of one major step.

use super::clock::{Clock, OnGrid, count_stall, mark_hits, next_major_time};
use super::{SimError, all_finite, breakpoint};
use crate::block::Breakpoint;
use crate::compile::{BlockMeta, Model};
use ctlgraph_solver::{Integrator, Method};

/// What the driver keeps of a run: its time and stop time, the solver,
/// the grid's and the clocks' positions, which clocks are due, the next
/// block event, the counters. Part of the run's state ([`super::RunState`]):
/// a clone continues exactly as the original.
#[derive(Clone)]
pub(crate) struct Clockwork {
    pub(crate) t: f64,
    pub(crate) stop: f64,
    /// No major step has computed outputs yet.
    pub(crate) first: bool,
    /// Whether this major step is at a block event (see `Between::event_only`).
    pub(crate) at_event: bool,
    pub(crate) integ: Integrator,
    /// How many states the solver integrates (the first ones).
    pub(crate) n_integrated: usize,
    /// The fixed-step grid's step (0 for the adaptive methods) and position.
    pub(crate) grid_step: f64,
    pub(crate) grid: Clock,
    pub(crate) clocks: Vec<Clock>,
    /// The clocks counted in grid steps, when they all fall on the grid.
    pub(crate) on_grid: Option<OnGrid>,
    /// Which clocks are due at this major step.
    pub(crate) hit: Vec<bool>,
    /// Times closer than this are the same major step.
    pub(crate) tol: f64,
    /// Earliest block event after `t` and its [`Breakpoint::generation`].
    pub(crate) next_event: f64,
    pub(crate) next_event_generation: u32,
    /// Blocks were handed a breakpoint's left limit: their updates may
    /// schedule events (a delay's arrivals), so `next_event` is recomputed.
    pub(crate) events_may_change: bool,
    /// Where a host's `advance_to` must land (infinite otherwise).
    pub(crate) pause: f64,
    /// A host set an input since the last outputs: the next output sweep
    /// runs every block, as at an event.
    pub(crate) inputs_changed: bool,
    pub(crate) major_steps: u64,
    /// Major steps in a row at which time did not advance ([`count_stall`]).
    pub(crate) stalled: u32,
}

impl Clockwork {
    /// The time keeping of a run of `model` to `stop`, before [`reset`].
    pub(crate) fn new(model: &Model, stop: f64) -> Self {
        let method = match model.sim.method {
            // With a delay on a loop, a step longer than it would take the
            // delay's output from past the newest sample.
            m if model.sim.default_max_step => {
                let delay = model.loop_dead_time.map_or(f64::INFINITY, |(d, _)| d);
                m.with_max_step(m.default_max_step(stop).min(delay))
            }
            m => m,
        };
        let grid_step = if method.is_adaptive() { 0.0 } else { method.max_step() };
        let clocks: Vec<Clock> = model.clocks.iter().map(|&(period, offset)| Clock::new(period, offset)).collect();
        let smallest = clocks
            .iter()
            .map(|c| c.grid.step)
            .chain([stop, method.max_step()])
            .filter(|&p| p > 0.0)
            .fold(f64::INFINITY, f64::min);
        let grid = Clock::new(grid_step, 0.0);
        Clockwork {
            t: 0.0,
            stop,
            first: true,
            at_event: true,
            integ: Integrator::new(method, model.between.n_integrated),
            n_integrated: model.between.n_integrated,
            grid_step,
            on_grid: OnGrid::new(grid_step, &grid, &clocks),
            grid,
            hit: vec![false; clocks.len()],
            clocks,
            tol: 1e-9 * smallest,
            next_event: f64::INFINITY,
            next_event_generation: 0,
            events_may_change: false,
            pause: f64::INFINITY,
            inputs_changed: false,
            major_steps: 0,
            stalled: 0,
        }
    }

    /// About how many major steps the run takes: the fixed-step grid plus
    /// the sample hits that fall between its points. For the adaptive
    /// methods a floor: every step is at most `max_step` long and every
    /// sample hit is a step, so the larger of the two counts (not their
    /// sum: hits of several clocks and the solver's steps may coincide).
    pub(crate) fn expected_major_steps(&self) -> f64 {
        if self.method().is_adaptive() {
            let hits = |clock: &Clock| ((self.stop - clock.offset) / clock.grid.step).floor().max(0.0);
            let most_hits = self.clocks.iter().map(hits).fold(0.0, f64::max);
            return (self.stop / self.method().max_step()).ceil().max(most_hits);
        }
        let mut n = self.stop / self.method().max_step();
        for clock in &self.clocks {
            let ratio = clock.grid.step / self.grid_step;
            let on_grid = self.grid_step > 0.0 && ratio >= 0.5 && (ratio - ratio.round()).abs() <= 1e-9 * ratio;
            if !on_grid {
                n += (self.stop - clock.offset).max(0.0) / clock.grid.step;
            }
        }
        n.ceil()
    }

    pub(crate) fn method(&self) -> Method {
        self.integ.method()
    }

    /// Whether the run has reached its stop time.
    pub(crate) fn finished(&self) -> bool {
        self.t >= self.stop - self.tol && !self.first
    }

    /// Marks the clocks due at `t`, reached at a grid point when
    /// `on_grid_point`; returns whether any is.
    #[inline]
    fn mark_hits(&mut self, on_grid_point: bool) -> bool {
        match &mut self.on_grid {
            Some(clocks) => clocks.mark_hits(on_grid_point, &mut self.hit),
            None => mark_hits(&mut self.clocks, self.t, self.tol, &mut self.hit),
        }
    }

    /// The next major step's time ([`next_major_time`]), or a host's
    /// landing point before it. With the clocks on the grid, their next
    /// hits are grid points no earlier than the grid's next: the grid alone
    /// decides.
    fn next_major_time(&self) -> f64 {
        let grid = (self.grid_step > 0.0).then_some(&self.grid);
        let clocks = if self.on_grid.is_some() { &[][..] } else { &self.clocks[..] };
        let next = next_major_time(clocks, grid, self.stop, self.next_event, self.tol);
        // A host's landing point, unless a step of the run's own falls on it.
        if self.pause < next - self.tol { self.pause } else { next }
    }

    /// The grid's next point, when the major step ends there and nothing
    /// but the grid decides it: the clocks are on the grid, nothing is
    /// integrated, and neither the stop time, a block event nor a host's
    /// landing point comes first.
    fn grid_shortcut(&self) -> Option<f64> {
        let next = self.grid.next;
        (self.on_grid.is_some()
            && self.n_integrated == 0
            && next <= self.stop
            && self.next_event > next + self.tol
            && self.pause >= next - self.tol)
            .then_some(next)
    }
}

/// What a back-end provides the driver: the sweeps over its blocks, and
/// what it knows of them. The hooks with a default are capabilities a
/// back-end may lack (zero crossings, rows between steps, hooks around a
/// step).
pub(crate) trait Sweeps {
    fn clockwork(&self) -> &Clockwork;
    fn clockwork_mut(&mut self) -> &mut Clockwork;
    fn signals(&self) -> &[f64];
    /// All continuous states, integrated ones first.
    fn states(&self) -> &[f64];
    /// Zeroes the signals and sets the blocks and their states to their
    /// initial values (at t = 0).
    fn initialize(&mut self);
    /// Step (1): the blocks' outputs in execution order (each due block
    /// once, or again after a block reset its states here; every block at
    /// the first step, an event or after a host set an input), then a
    /// check that every signal is finite. The error is boxed so that the
    /// answer of every major step fits a register (a `SimError` is 80
    /// bytes, copied through the stack at each step otherwise).
    fn output_sweep(&mut self) -> Result<(), Box<SimError>>;
    /// The value a host sets of block `block`, a top-level inport
    /// ([`crate::Block::external_input`]).
    fn external_input(&mut self, block: usize) -> Option<&mut [f64]>;
    /// Step (3): the updates of the blocks due now.
    fn update_sweep(&mut self);
    /// The first block event strictly after the present time, and its
    /// generation ([`super::earlier`] folds the blocks' events).
    fn earliest_event(&self) -> (f64, u32);
    /// Block `block`'s next event after `t`, to name the one holding time.
    fn block_event(&self, block: usize, t: f64) -> f64;
    /// The held LTI blocks latch their inputs (zero-order hold).
    fn latch_held(&mut self);
    /// The held LTI blocks' states jump by their exact transition over `dt`.
    fn step_held(&mut self, dt: f64);
    /// Step (4): the solver integrates the integrated states from `t0`
    /// towards `target`; returns where it got.
    fn integrate(&mut self, t0: f64, target: f64) -> Result<f64, SimError>;
    /// The first zero crossing between `t0` and `t1` (the states at `t1`),
    /// where the step must end instead; the blocks have heard it fired.
    fn locate_crossing(&mut self, _t0: f64, _t1: f64, _target: f64) -> Result<Option<f64>, SimError> {
        Ok(None)
    }
    /// Limited integrators projected back into their limits; whether any was.
    fn clamp_states(&mut self) -> bool;
    /// Whether some block keeps its input's past ([`crate::Block::keeps_history`]).
    fn keeps_history(&self) -> bool;
    /// At a breakpoint: the continuous signals' left limit there, handed
    /// to the blocks that keep their input's past.
    fn left_limits(&mut self, at: Breakpoint);
    /// Whether a major step that ends at the grid's next point may skip
    /// what the general path would find there anyway (no crossings to
    /// watch, no rows between steps, no history kept).
    fn plain_grid_steps(&self) -> bool;
    /// The blocks, to name one in an error.
    fn names(&self) -> &[BlockMeta];
    /// The error for a state that is not finite.
    fn blame_states(&self) -> SimError;
    /// A step starts at `t0`; the solver reached `t` (before a crossing
    /// may end the step sooner); the step ended (for rows inside it).
    fn step_started(&mut self, _t0: f64) {}
    fn solver_reached(&mut self, _t: f64) {}
    fn step_ended(&mut self) {}
    /// The row time a major step at `t` gives (`None`: no row).
    fn major_row(&mut self, t: f64) -> Option<f64> {
        Some(t)
    }
    /// Hands `sink` the rows inside the step just taken; false when the
    /// sink asked to stop.
    fn rows_inside_step(&mut self, _sink: &mut dyn FnMut(f64, &[f64]) -> bool) -> bool {
        true
    }
}

/// Back to t = 0 with initial states (blocks re-initialised).
pub(crate) fn reset(s: &mut impl Sweeps) {
    let c = s.clockwork_mut();
    c.t = 0.0;
    c.first = true;
    c.at_event = true;
    c.major_steps = 0;
    c.stalled = 0;
    c.events_may_change = false;
    c.inputs_changed = false;
    c.grid.set_tick(1);
    c.clocks.iter_mut().for_each(|clock| clock.set_tick(0));
    match &mut c.on_grid {
        Some(on_grid) => on_grid.reset(&mut c.hit),
        None => {
            mark_hits(&mut c.clocks, 0.0, c.tol, &mut c.hit);
        }
    }
    c.integ.reset();
    s.initialize();
    let event = s.earliest_event();
    let c = s.clockwork_mut();
    (c.next_event, c.next_event_generation) = event;
}

/// Step (1) of a major step.
#[inline(always)]
pub(crate) fn outputs(s: &mut impl Sweeps) -> Result<(), SimError> {
    let result = s.output_sweep();
    let c = s.clockwork_mut();
    c.first = false;
    c.inputs_changed = false;
    result.map_err(|e| *e)
}

/// Steps (3) and (4): the updates, then integration to the next major
/// step — or to the first zero crossing before it.
// Inlined into each loop that calls it (a run, a host's `advance_to`):
// a call per major step would cost the generated steps a tenth.
#[inline(always)]
pub(crate) fn advance(s: &mut impl Sweeps) -> Result<(), SimError> {
    s.update_sweep();
    if std::mem::take(&mut s.clockwork_mut().events_may_change) {
        let event = s.earliest_event();
        let c = s.clockwork_mut();
        (c.next_event, c.next_event_generation) = event;
    }
    s.latch_held();
    if let Some(next) = s.clockwork().grid_shortcut()
        && s.plain_grid_steps()
    {
        return advance_to_grid_point(s, next);
    }
    let c = s.clockwork();
    let (t0, target, tol) = (c.t, c.next_major_time(), c.tol);
    let (integrates, max_step) = (c.n_integrated > 0, c.method().max_step());
    s.step_started(t0);
    let mut t_new = if !integrates {
        // Nothing to integrate; max_step still bounds the adaptive
        // method's major steps so continuous sources are sampled finely.
        target.min(t0 + max_step)
    } else {
        s.integrate(t0, target)?
    };
    s.solver_reached(t_new);
    let crossing = s.locate_crossing(t0, t_new, target)?;
    if let Some(t_crossing) = crossing {
        t_new = t_crossing;
        s.clockwork_mut().integ.invalidate();
    }
    // Land exactly on the target when the solver reached it.
    let t = if (target - t_new).abs() <= tol { target } else { t_new };
    s.clockwork_mut().t = t;
    if t > t0 {
        s.step_held(t - t0);
    }
    let c = s.clockwork_mut();
    let on_grid_point = c.grid_step > 0.0 && c.grid.pass(t, tol);
    s.step_ended();
    let clamped = s.clamp_states();
    let c = s.clockwork_mut();
    let hit = c.mark_hits(on_grid_point);
    let block_event = t >= c.next_event - tol;
    c.at_event = block_event;
    let event_generation = c.next_event_generation;
    if block_event {
        let event = s.earliest_event();
        let c = s.clockwork_mut();
        (c.next_event, c.next_event_generation) = event;
    }
    if hit || block_event || clamped {
        s.clockwork_mut().integ.invalidate();
    }
    if s.keeps_history()
        && let Some(at) = breakpoint(hit, block_event, clamped || crossing.is_some(), event_generation)
    {
        s.left_limits(at);
        s.clockwork_mut().events_may_change = true;
    }
    end_major_step(s, t0)
}

/// [`advance`]'s steps after the updates, where they are known to end at
/// the grid's next point `next` ([`Clockwork::grid_shortcut`],
/// [`Sweeps::plain_grid_steps`]). The general path then takes `next` as
/// the major step's time (its candidate t0 + h differs from it by
/// rounding only), marks the grid and the clocks passed, and sees no
/// event; here those same results are set without computing and comparing
/// the candidates.
#[inline(always)]
fn advance_to_grid_point(s: &mut impl Sweeps, next: f64) -> Result<(), SimError> {
    let c = s.clockwork_mut();
    let t0 = c.t;
    c.t = next;
    c.grid.pass_one();
    c.mark_hits(true);
    c.at_event = false;
    s.step_held(next - t0);
    end_major_step(s, t0)
}

/// Every major step's end: states finite, time not standing still too long.
#[inline(always)]
fn end_major_step(s: &mut impl Sweeps, t0: f64) -> Result<(), SimError> {
    if !all_finite(s.states()) {
        return Err(s.blame_states());
    }
    let c = s.clockwork();
    let (mut stalled, t) = (c.stalled, c.t);
    count_stall(&mut stalled, t0, t, s.names(), |i| s.block_event(i, t0))?;
    let c = s.clockwork_mut();
    c.stalled = stalled;
    c.major_steps += 1;
    Ok(())
}

/// Runs to the stop time, handing the signals to `sink` at every major
/// step (including t = 0 and the stop time) and the rows between, until
/// the sink returns false (an interrupt, a budget); returns whether the
/// stop time was reached. The sink is a type parameter, not a `dyn` call:
/// for a generated step it inlines into the loop.
pub(crate) fn run_while<S: Sweeps>(s: &mut S, mut sink: impl FnMut(f64, &[f64]) -> bool) -> Result<bool, SimError> {
    loop {
        outputs(s)?;
        // With `output: { every: DT }`, only a major step on the grid is a row.
        let t = s.clockwork().t;
        let go_on = match s.major_row(t) {
            Some(t) => sink(t, s.signals()),
            None => true,
        };
        if s.clockwork().finished() {
            return Ok(true);
        }
        if !go_on {
            return Ok(false);
        }
        advance(s)?;
        if !s.rows_inside_step(&mut sink) {
            return Ok(false);
        }
    }
}
