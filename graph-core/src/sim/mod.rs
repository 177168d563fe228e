//! The hybrid simulator: Simulink's major-step semantics over a compiled
//! [`Model`], with continuous states integrated by a `ctlgraph-solver`
//! method between major steps.
//!
//! Major step times are the union of the fixed-step grid (fixed-step
//! methods), every clock's sample hits, block events (a step's switching
//! time) and the stop time; the adaptive method adds its own accepted steps.
//! Hits are computed from integer tick counts (`offset + k·period`), never
//! by accumulating floating-point time. Zero crossings end a step where a
//! block's mode must change (module `events`). After `initialize`, stepping
//! allocates nothing.

mod blame;
mod breakpoints;
mod clock;
mod error;
mod events;
mod host;
mod minor;
mod output;
mod state;
pub(crate) mod visit;
pub(crate) use blame::Blame;
pub use clock::earlier;
pub(crate) use clock::{Clock, OnGrid, Timing, breakpoint, count_stall, mark_hits, next_major_time};
pub use error::SimError;
pub use host::Snapshot;
pub(crate) use state::RunBlock;
pub use state::RunState;

use crate::block::{Io, Port};
use crate::compile::{Model, Rate, Slot};
use ctlgraph_solver::{Integrator, Method, Stats, Zoh};
pub use events::MAX_CONSECUTIVE_EVENTS;
use events::Watch;
use minor::{Minor, stale_at_start};
use output::Dense;
use std::ops::Range;
use std::sync::Arc;
use visit::{ComputedAt, Integrand, Visit};

/// Counters for the run report.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunStats {
    pub major_steps: u64,
    pub solver: Stats,
    /// Zero crossings located (each ended a step).
    pub events: u64,
}

/// Numbers run states, so a snapshot is restored only where it was taken.
static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// A model being simulated: the compiled model (shared), the plan this
/// simulator derives from it once (which blocks each sweep visits), the
/// run's state ([`RunState`], everything that changes) and scratch.
pub struct Simulator {
    model: Arc<Model>,
    state: RunState,
    /// Fixed-step grid step (0 for the adaptive methods).
    grid_step: f64,
    /// Times closer than this are the same major step.
    tol: f64,
    /// How many states the solver integrates (from the model's plan,
    /// [`crate::compile::Between`]), and the blocks they belong to: the
    /// plain integrators, and the others, called for their derivatives
    /// and `clamp_states` (`stateful`).
    n_integrated: usize,
    integrands: Vec<Integrand>,
    stateful: Vec<usize>,
    /// LTI blocks stepped exactly (see [`crate::compile::Between`]).
    held: Vec<Held>,
    /// Blocks with an `update` to run (execution order).
    updating: Vec<Visit>,
    /// Blocks that keep their input's past ([`crate::Block::keeps_history`]).
    history: Vec<usize>,
    /// The blocks in execution order; those a major step without an event
    /// runs (or runs at its clock's hits): neither constant nor event-only.
    every: Vec<Visit>,
    regular: Vec<Visit>,
    /// The blocks whose outputs minor steps recompute (`Between::minor`).
    minor: Vec<Visit>,
    /// Those of them the first stage recomputes when the signals hold the
    /// major step's outputs ([`stale_at_start`]), and whether they do:
    /// set by a major step's outputs, cleared by anything that could
    /// change a signal or state before the step is taken.
    stale_at_start: Vec<Visit>,
    /// When the time-only blocks last ran, to skip them at the same time.
    computed_at: ComputedAt,
    outputs_current: bool,
    /// Where [`Simulator::advance_to`] must land (infinite otherwise).
    pause: f64,
}

/// A run where it stands, for linearisation ([`Simulator::operating_point`]).
pub(crate) struct OperatingPoint<'a> {
    pub model: &'a Model,
    pub blocks: &'a mut [RunBlock],
    pub signals: &'a mut [f64],
    pub x: &'a mut [f64],
}

/// A held LTI block: its exact transitions, and where its input, its
/// latched copy (in [`RunState::held_inputs`]) and its states are.
#[derive(Clone)]
struct Held {
    zoh: Zoh,
    input: Range<usize>,
    latched: Range<usize>,
    states: Range<usize>,
}

impl Simulator {
    /// Prepares a run of `model` to `stop` (the graph's own stop time when
    /// `None`) and computes the initial states. A model in an [`Arc`] is
    /// shared, not copied: many runs (threads, sweep cases) may use one.
    pub fn new(model: impl Into<Arc<Model>>, stop: Option<f64>) -> Self {
        let model: Arc<Model> = model.into();
        let stop = stop.unwrap_or(model.sim.stop);
        let Timing { method, grid_step, grid, clocks, tol } = Timing::new(&model, stop);
        let continuous: Vec<usize> =
            (0..model.meta.len()).filter(|&i| model.meta[i].rate == Rate::Continuous).collect();
        let watch = Watch::new(&model, &continuous, model.sim.zero_crossing);
        let mut latched = 0;
        let held = model
            .between
            .held
            .iter()
            .filter_map(|&block| {
                let ss = model.blocks[block].lti()?.clone();
                let slot = &model.slots[block];
                let port = model.in_ports[slot.inputs.start];
                let input = port.offset..port.offset + port.width;
                latched += ss.m;
                let latched = latched - ss.m..latched;
                Some(Held { zoh: Zoh::new(ss), input, latched, states: slot.states.clone() })
            })
            .collect();
        let n = model.blocks.len();
        // The integrated blocks: plain integrators, copied, and the others, called.
        let (mut integrands, mut stateful, mut plain) = (Vec::new(), Vec::new(), vec![false; n]);
        for &i in &model.between.integrated {
            match Integrand::of(&model, i) {
                Some(integrand) => {
                    integrands.push(integrand);
                    plain[i] = true;
                }
                None => stateful.push(i),
            }
        }
        // The output sweeps' visits; the plain integrators' outputs are copied apart.
        let visits = |blocks: &mut dyn Iterator<Item = usize>| Visit::list(&model, blocks.filter(|&i| !plain[i]));
        let minor = visits(&mut model.between.minor.iter().copied());
        let stale = stale_at_start(&model, &minor);
        let varying =
            visits(&mut (0..n).filter(|&i| model.slots[i].rate == Rate::Continuous && !model.between.event_only[i]));
        let mut state =
            RunState::new(&model, stop, Integrator::new(method, model.between.n_integrated), clocks, grid, watch);
        state.held_inputs = vec![0.0; latched];
        let mut sim = Simulator {
            grid_step,
            tol,
            held,
            integrands,
            stateful,
            n_integrated: model.between.n_integrated,
            updating: Visit::list(&model, (0..n).filter(|&i| model.blocks[i].updates())),
            history: (0..n).filter(|&i| model.blocks[i].keeps_history()).collect(),
            every: visits(&mut (0..n)),
            regular: visits(
                &mut (0..n).filter(|&i| model.slots[i].rate != Rate::Constant && !model.between.event_only[i]),
            ),
            minor,
            stale_at_start: stale,
            computed_at: ComputedAt::new(n),
            outputs_current: false,
            pause: f64::INFINITY,
            state,
            model,
        };
        sim.state.dense = Dense::new(&sim, sim.model.sim.output, varying);
        sim.reset();
        sim
    }

    /// Back to t = 0 with initial states (blocks re-initialised).
    pub fn reset(&mut self) {
        self.state.t = 0.0;
        self.state.first = true;
        self.outputs_current = false;
        self.state.major_steps = 0;
        self.state.stalled = 0;
        self.state.grid.set_tick(1);
        self.state.signals.iter_mut().for_each(|s| *s = 0.0);
        self.computed_at.forget();
        for (b, m) in self.state.blocks.iter_mut().zip(&self.model.slots) {
            b.initialize(&mut self.state.x[m.states.clone()]);
        }
        for c in &mut self.state.clocks {
            c.set_tick(0);
        }
        self.mark_hits();
        (self.state.next_event, self.state.next_event_generation) = self.earliest_event();
        self.state.events_may_change = false;
        self.state.integ.reset();
        self.state.watch.reset(&mut self.state.blocks);
        if let Some(dense) = &mut self.state.dense {
            dense.reset();
        }
    }

    pub fn model(&self) -> &Model {
        &self.model
    }

    pub fn time(&self) -> f64 {
        self.state.t
    }

    pub fn stop_time(&self) -> f64 {
        self.state.stop
    }

    pub fn method(&self) -> Method {
        self.state.integ.method()
    }

    /// The compiled model, shared: another run of it needs no compiling.
    pub fn shared_model(&self) -> Arc<Model> {
        Arc::clone(&self.model)
    }

    /// The model, the blocks, signals and states as they stand (for
    /// linearisation around the point the run has reached).
    pub(crate) fn operating_point(&mut self) -> OperatingPoint<'_> {
        self.outputs_current = false;
        let s = &mut self.state;
        OperatingPoint { model: &self.model, blocks: &mut s.blocks, signals: &mut s.signals, x: &mut s.x }
    }

    /// The signal buffer (index with [`crate::compile::Column`] offsets).
    pub fn signals(&self) -> &[f64] {
        &self.state.signals
    }

    pub fn states(&self) -> &[f64] {
        &self.state.x
    }

    pub fn stats(&self) -> RunStats {
        RunStats {
            major_steps: self.state.major_steps,
            solver: self.state.integ.stats(),
            events: self.state.watch.events,
        }
    }

    /// What the run has to say beyond its numbers (blocks whose chattering
    /// crossings `zero_crossing: adaptive` ignored).
    pub fn warnings(&self) -> &[String] {
        &self.state.watch.warnings
    }

    /// About how many major steps the run takes: the fixed-step grid plus
    /// the sample hits that fall between its points. For the adaptive
    /// methods, whose steps `max_step` bounds, it is a floor.
    pub fn expected_major_steps(&self) -> f64 {
        let mut n = self.state.stop / self.state.integ.method().max_step();
        for c in &self.state.clocks {
            let ratio = c.grid.step / self.grid_step;
            let on_grid = self.grid_step > 0.0 && ratio >= 0.5 && (ratio - ratio.round()).abs() <= 1e-9 * ratio;
            if !on_grid {
                n += (self.state.stop - c.offset).max(0.0) / c.grid.step;
            }
        }
        n.ceil()
    }

    /// Whether the run has reached its stop time.
    pub fn finished(&self) -> bool {
        self.state.t >= self.state.stop - self.tol && !self.state.first
    }

    /// Takes clocks whose next hit is (within tolerance) now.
    fn mark_hits(&mut self) -> bool {
        mark_hits(&mut self.state.clocks, self.state.t, self.tol)
    }

    /// Runs `output` of every block due now, in execution order:
    /// continuous blocks always (those that change only at events, only
    /// at events), discrete blocks at their hits, constant blocks on the
    /// first pass only.
    fn sweep(&mut self) {
        let (m, s) = (&*self.model, &mut self.state);
        let all = s.first || s.at_event || s.inputs_changed;
        let order = if all { &self.every } else { &self.regular };
        for integrator in &self.integrands {
            integrator.output(&s.x, &mut s.signals);
        }
        let (clocks, first, t, x, blocks) = (&s.clocks, s.first, s.t, &s.x, &mut s.blocks);
        let computed_at = &mut self.computed_at;
        visit::sweep(
            order,
            &mut s.signals,
            |v| due(v.rate, clocks, first),
            #[inline(always)]
            |v, signals| {
                if computed_at.must_run(v, t, false) {
                    let slot = &m.slots[v.block];
                    let mut io = io_for(slot, t, false, x, signals, &m.in_ports, &m.out_ports);
                    blocks[v.block].output(&mut io);
                }
            },
        );
    }

    /// Runs `update` of the blocks that have one (see [`crate::block::Block::updates`])
    /// and are due now: continuous ones always, discrete ones at hits.
    fn update_sweep(&mut self) {
        let (m, s) = (&*self.model, &mut self.state);
        for v in &self.updating {
            if due(v.rate, &s.clocks, false) {
                let slot = &m.slots[v.block];
                let mut io = io_for(slot, s.t, false, &s.x, &mut s.signals, &m.in_ports, &m.out_ports);
                s.blocks[v.block].update(&mut io);
            }
        }
    }

    /// Step (1) of a major step: outputs in execution order (again after a
    /// block reset its states here), the zero-crossing signs for the next
    /// step, then a check that every signal is finite.
    pub fn outputs(&mut self) -> Result<(), SimError> {
        self.sweep();
        if self.major_step_events() {
            self.sweep();
        }
        let s = &mut self.state;
        s.first = false;
        s.inputs_changed = false;
        s.watch.record_signs(&self.model, &mut s.blocks, &mut s.signals, &s.x, s.t);
        if !all_finite(&s.signals) {
            let s = &self.state;
            return Err(Blame::of(&self.model).signal(&s.signals, s.t, |i| s.blocks[i].diagnose()));
        }
        self.outputs_current = true;
        Ok(())
    }

    /// Blocks with zero crossings may reset their states at a major step;
    /// returns whether any did.
    fn major_step_events(&mut self) -> bool {
        let (m, s) = (&*self.model, &mut self.state);
        let mut changed = false;
        for &i in &s.watch.blocks {
            let slot = &m.slots[i];
            let (inputs, outputs) = (&m.in_ports[slot.inputs.clone()], &m.out_ports[slot.outputs.clone()]);
            let io = Io::new(s.t, false, &[], &mut s.signals, inputs, outputs);
            changed |= s.blocks[i].major_step(&io, &mut s.x[slot.states.clone()]);
        }
        changed
    }

    /// Steps (3) and (4): discrete updates at hits (and major-step updates
    /// of continuous blocks), then integration to the next major step — or
    /// to the first zero crossing before it.
    pub fn advance(&mut self) -> Result<(), SimError> {
        self.update_sweep();
        if std::mem::take(&mut self.state.events_may_change) {
            (self.state.next_event, self.state.next_event_generation) = self.earliest_event();
        }
        let target = self.next_major_time();
        let (m, s) = (&*self.model, &mut self.state);
        for h in &self.held {
            // Element by element: one or two values, where copy_from_slice calls memcpy.
            for (u, &v) in s.held_inputs[h.latched.clone()].iter_mut().zip(&s.signals[h.input.clone()]) {
                *u = v;
            }
        }
        let t0 = s.t;
        if let Some(dense) = &mut s.dense {
            dense.start(t0, &s.x);
        }
        let current = std::mem::take(&mut self.outputs_current) && !s.inputs_changed;
        let mut sys = Minor {
            model: m,
            blocks: &mut s.blocks,
            signals: &mut s.signals,
            continuous: &self.minor,
            at_start: current.then_some(&self.stale_at_start[..]),
            stateful: &self.stateful,
            integrands: &self.integrands,
            computed_at: &mut self.computed_at,
            t_end: target,
        };
        let x = &mut s.x[..self.n_integrated];
        let mut t_new = if x.is_empty() {
            // Nothing to integrate; max_step still bounds the adaptive
            // method's major steps so continuous sources are sampled finely.
            target.min(t0 + s.integ.method().max_step())
        } else {
            match s.integ.advance(&mut sys, t0, target, x) {
                Ok(t) => t,
                Err(error) => return Err(Blame::of(m).solver(sys.signals, t0, error)),
            }
        };
        if let Some(dense) = &mut s.dense {
            dense.solver_end(t_new, x);
        }
        let event = s.watch.locate(&mut sys, &mut s.integ, t0, t_new, x);
        if let Some(t_event) = event {
            t_new = t_event;
            for (block, k) in s.watch.fired() {
                s.blocks[block].crossing_located(k);
            }
            s.integ.invalidate();
            if let Some(block) = s.watch.count_event(t_event, m)? {
                s.blocks[block].frozen = false;
            }
        }
        // Land exactly on the target when the solver reached it.
        s.t = if (target - t_new).abs() <= self.tol { target } else { t_new };
        if s.t > t0 {
            for h in &mut self.held {
                h.zoh.step(s.t - t0, &mut s.x[h.states.clone()], &s.held_inputs[h.latched.clone()]);
            }
        }
        if self.grid_step > 0.0 {
            s.grid.pass(s.t, self.tol);
        }
        if let Some(dense) = &mut s.dense {
            dense.end(s.t);
        }
        let mut clamped = false;
        for &i in &self.stateful {
            clamped |= s.blocks[i].clamp_states(&mut s.x[m.slots[i].states.clone()]);
        }
        let hit = self.mark_hits();
        let block_event = self.state.t >= self.state.next_event - self.tol;
        self.state.at_event = block_event;
        let event_generation = self.state.next_event_generation;
        if block_event {
            (self.state.next_event, self.state.next_event_generation) = self.earliest_event();
        }
        if hit || block_event || clamped {
            self.state.integ.invalidate();
        }
        if let Some(at) = breakpoint(hit, block_event, clamped || event.is_some(), event_generation) {
            self.left_limits(at);
        }
        let s = &mut self.state;
        if !all_finite(&s.x) {
            return Err(Blame::of(&self.model).state(&s.signals, s.t, &s.x));
        }
        let blocks = &s.blocks;
        count_stall(&mut s.stalled, t0, s.t, &self.model.meta, |i| blocks[i].next_event(t0))?;
        s.major_steps += 1;
        Ok(())
    }

    /// The next major step's time ([`next_major_time`]), or a host's
    /// landing point before it.
    fn next_major_time(&self) -> f64 {
        let grid = (self.grid_step > 0.0).then_some(&self.state.grid);
        let next = next_major_time(&self.state.clocks, grid, self.state.stop, self.state.next_event, self.tol);
        // A host's landing point, unless a step of the run's own falls on it.
        if self.pause < next - self.tol { self.pause } else { next }
    }

    /// Runs to the stop time, handing the signals to `sink` at every major
    /// step (including t = 0 and the stop time).
    pub fn run(&mut self, sink: &mut dyn FnMut(f64, &[f64])) -> Result<RunStats, SimError> {
        self.run_while(&mut |t, signals| {
            sink(t, signals);
            true
        })?;
        Ok(self.stats())
    }

    /// Like [`Simulator::run`], but `sink` may end the run early by
    /// returning `false` (an interrupt, a step or wall-time budget): the
    /// run then stops after that major step. Returns whether the stop time
    /// was reached.
    pub fn run_while(&mut self, sink: &mut dyn FnMut(f64, &[f64]) -> bool) -> Result<bool, SimError> {
        loop {
            self.outputs()?;
            // With `output: { every: DT }`, only a major step on the grid is a row.
            let go_on =
                match self.state.dense.as_mut().map_or(Some(self.state.t), |dense| dense.major_row(self.state.t)) {
                    Some(t) => sink(t, &self.state.signals),
                    None => true,
                };
            if self.finished() {
                return Ok(true);
            }
            if !go_on {
                return Ok(false);
            }
            self.advance()?;
            if !self.dense_rows(sink) {
                return Ok(false);
            }
        }
    }
}

/// Whether a block of `rate` runs now: continuous ones always, discrete
/// ones at their clock's hits, constant ones when `constant_too`.
fn due(rate: Rate, clocks: &[Clock], constant_too: bool) -> bool {
    match rate {
        Rate::Continuous => true,
        Rate::Constant => constant_too,
        Rate::Discrete(c) => clocks[c].hit,
    }
}

/// Whether every value is finite, without a branch per value.
#[inline]
pub(crate) fn all_finite(values: &[f64]) -> bool {
    not_finite_bits(values) == 0
}

/// Zero exactly when every value is finite: v − v is +0 (all bits clear)
/// for a finite v and NaN for ±inf and NaN, and the bits are OR-ed
/// together. One subtraction and one OR per value, independent per value,
/// where a floating-point sum would chain one addition's latency to the
/// next. Generated steps OR these bits over each block's outputs as it
/// writes them ([`crate::codegen::GeneratedStep::outputs`]).
#[inline(always)]
#[allow(clippy::eq_op)] // v − v is the test, not a mistake
pub fn not_finite_bits(values: &[f64]) -> u64 {
    values.iter().fold(0, |bad, &v| bad | (v - v).to_bits())
}

/// Block `slot`'s view of the run: its states, inputs and outputs.
pub(crate) fn io_for<'a>(
    slot: &Slot,
    t: f64,
    left_limit: bool,
    x: &'a [f64],
    signals: &'a mut [f64],
    in_ports: &'a [Port],
    out_ports: &'a [Port],
) -> Io<'a> {
    Io::new(
        t,
        left_limit,
        &x[slot.states.clone()],
        signals,
        &in_ports[slot.inputs.clone()],
        &out_ports[slot.outputs.clone()],
    )
}

#[cfg(test)]
mod tests {
    use super::all_finite;

    #[test]
    fn all_finite_finds_any_infinity_or_nan_anywhere() {
        let mut values = [0.0, -0.0, 1.5, f64::MAX, f64::MIN, f64::MIN_POSITIVE, 5e-324, -3.0, 7.0];
        assert!(all_finite(&values) && all_finite(&[]));
        for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN, -f64::NAN] {
            for k in 0..values.len() {
                let kept = values[k];
                values[k] = bad;
                assert!(!all_finite(&values), "{bad} at {k}");
                values[k] = kept;
            }
        }
    }
}
