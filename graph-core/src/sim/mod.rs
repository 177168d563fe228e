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
pub(crate) mod visit;
pub(crate) use blame::Blame;
pub use clock::earlier;
pub(crate) use clock::{Clock, OnGrid, Timing, breakpoint, mark_hits, next_major_time};
pub use error::SimError;
pub use host::Snapshot;

use crate::block::{Io, Port};
use crate::compile::{Model, Rate, Slot};
use ctlgraph_solver::{Integrator, Method, Stats, Zoh};
pub use events::MAX_CONSECUTIVE_EVENTS;
use events::Watch;
use minor::{Minor, stale_at_start};
use output::Dense;
use std::ops::Range;
use visit::{ComputedAt, Integrand, Visit};

/// Counters for the run report.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunStats {
    pub major_steps: u64,
    pub solver: Stats,
    /// Zero crossings located (each ended a step).
    pub events: u64,
}

/// Numbers simulators, so a snapshot is restored only where it was taken.
static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// A model being simulated.
pub struct Simulator {
    model: Model,
    signals: Vec<f64>,
    x: Vec<f64>,
    integ: Integrator,
    clocks: Vec<Clock>,
    /// Fixed-step grid: its step (0 for the adaptive methods) and position.
    grid_step: f64,
    grid: Clock,
    t: f64,
    stop: f64,
    /// Times closer than this are the same major step.
    tol: f64,
    first: bool,
    /// Earliest block event after `t` (see [`Simulator::earliest_event`])
    /// and its [`Breakpoint::generation`].
    next_event: f64,
    next_event_generation: u32,
    /// Blocks were handed a breakpoint's left limit: their updates may
    /// schedule events (a delay's arrivals), so `next_event` is recomputed.
    events_may_change: bool,
    major_steps: u64,
    /// Major steps in a row at which time did not advance.
    stalled: u32,
    /// Zero-crossing functions and their detection.
    watch: Watch,
    /// How many states the solver integrates (from the model's plan,
    /// [`crate::compile::Between`]), and the blocks they belong to: the
    /// plain integrators, and the others (whose `derivatives` and
    /// `clamp_states` are called).
    n_integrated: usize,
    integrands: Vec<Integrand>,
    called: Vec<usize>,
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
    /// Whether this major step is at a block event (see `Between::event_only`).
    at_event: bool,
    /// A host set an input since the last outputs (see [`Simulator::set_input`]).
    inputs_changed: bool,
    /// Where [`Simulator::advance_to`] must land (infinite otherwise).
    pause: f64,
    /// Rows between major steps, when `simulation.output` asks for them.
    dense: Option<Dense>,
    /// Tells this simulator's snapshots from others'.
    id: u64,
}

/// A held LTI block: its exact transitions, its input at the last major
/// step, and where that input and its states are.
#[derive(Clone)]
struct Held {
    zoh: Zoh,
    u: Vec<f64>,
    input: Range<usize>,
    states: Range<usize>,
}

impl Simulator {
    /// Prepares a run of `model` to `stop` (the graph's own stop time when
    /// `None`) and computes the initial states.
    pub fn new(model: Model, stop: Option<f64>) -> Self {
        let stop = stop.unwrap_or(model.sim.stop);
        let Timing { method, grid_step, grid, clocks, tol } = Timing::new(&model, stop);
        let continuous: Vec<usize> =
            (0..model.meta.len()).filter(|&i| model.meta[i].rate == Rate::Continuous).collect();
        let watch = Watch::new(&model, &continuous, model.sim.zero_crossing);
        let held = model
            .between
            .held
            .iter()
            .filter_map(|&block| {
                let ss = model.blocks[block].lti()?.clone();
                let (slot, u) = (&model.slots[block], vec![0.0; ss.m]);
                let port = model.in_ports[slot.inputs.start];
                let input = port.offset..port.offset + port.width;
                Some(Held { zoh: Zoh::new(ss), u, input, states: slot.states.clone() })
            })
            .collect();
        let n = model.blocks.len();
        // The integrated blocks: plain integrators, copied, and the others, called.
        let (mut integrands, mut called, mut plain) = (Vec::new(), Vec::new(), vec![false; n]);
        for &i in &model.between.integrated {
            match Integrand::of(&model, i) {
                Some(integrand) => {
                    integrands.push(integrand);
                    plain[i] = true;
                }
                None => called.push(i),
            }
        }
        // The output sweeps' visits; the plain integrators' outputs are copied apart.
        let visits = |blocks: &mut dyn Iterator<Item = usize>| Visit::list(&model, blocks.filter(|&i| !plain[i]));
        let minor = visits(&mut model.between.minor.iter().copied());
        let stale = stale_at_start(&model, &minor);
        let varying =
            visits(&mut (0..n).filter(|&i| model.slots[i].rate == Rate::Continuous && !model.between.event_only[i]));
        let output_times = model.sim.output;
        let mut sim = Simulator {
            signals: vec![0.0; model.signal_len],
            x: vec![0.0; model.n_states],
            integ: Integrator::new(method, model.between.n_integrated),
            clocks,
            grid_step,
            grid,
            t: 0.0,
            stop,
            tol,
            first: true,
            next_event: f64::INFINITY,
            next_event_generation: 0,
            events_may_change: false,
            major_steps: 0,
            stalled: 0,
            watch,
            held,
            integrands,
            called,
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
            at_event: true,
            inputs_changed: false,
            pause: f64::INFINITY,
            dense: None,
            id: NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            model,
        };
        sim.dense = Dense::new(&sim, output_times, varying);
        sim.reset();
        sim
    }

    /// Back to t = 0 with initial states (blocks re-initialised).
    pub fn reset(&mut self) {
        self.t = 0.0;
        self.first = true;
        self.outputs_current = false;
        self.major_steps = 0;
        self.grid.set_tick(1);
        self.signals.iter_mut().for_each(|s| *s = 0.0);
        self.computed_at.forget();
        for (b, m) in self.model.blocks.iter_mut().zip(&self.model.slots) {
            b.initialize(&mut self.x[m.states.clone()]);
        }
        for c in &mut self.clocks {
            c.set_tick(0);
        }
        self.mark_hits();
        (self.next_event, self.next_event_generation) = self.earliest_event();
        self.events_may_change = false;
        self.integ.reset();
        self.watch.reset(&mut self.model.slots);
        if let Some(dense) = &mut self.dense {
            dense.reset();
        }
    }

    pub fn model(&self) -> &Model {
        &self.model
    }

    pub fn time(&self) -> f64 {
        self.t
    }

    pub fn stop_time(&self) -> f64 {
        self.stop
    }

    pub fn method(&self) -> Method {
        self.integ.method()
    }

    /// The model, signals and states as they stand (for linearisation
    /// around the point the run has reached).
    pub(crate) fn operating_point(&mut self) -> (&mut Model, &mut [f64], &mut [f64]) {
        self.outputs_current = false;
        (&mut self.model, &mut self.signals, &mut self.x)
    }

    /// The signal buffer (index with [`crate::compile::Column`] offsets).
    pub fn signals(&self) -> &[f64] {
        &self.signals
    }

    pub fn states(&self) -> &[f64] {
        &self.x
    }

    pub fn stats(&self) -> RunStats {
        RunStats { major_steps: self.major_steps, solver: self.integ.stats(), events: self.watch.events }
    }

    /// What the run has to say beyond its numbers (blocks whose chattering
    /// crossings `zero_crossing: adaptive` ignored).
    pub fn warnings(&self) -> &[String] {
        &self.watch.warnings
    }

    /// About how many major steps the run takes: the fixed-step grid plus
    /// the sample hits that fall between its points. For the adaptive
    /// methods, whose steps `max_step` bounds, it is a floor.
    pub fn expected_major_steps(&self) -> f64 {
        let mut n = self.stop / self.integ.method().max_step();
        for c in &self.clocks {
            let ratio = c.grid.step / self.grid_step;
            let on_grid = self.grid_step > 0.0 && ratio >= 0.5 && (ratio - ratio.round()).abs() <= 1e-9 * ratio;
            if !on_grid {
                n += (self.stop - c.offset).max(0.0) / c.grid.step;
            }
        }
        n.ceil()
    }

    /// Whether the run has reached its stop time.
    pub fn finished(&self) -> bool {
        self.t >= self.stop - self.tol && !self.first
    }

    /// Takes clocks whose next hit is (within tolerance) now.
    fn mark_hits(&mut self) -> bool {
        mark_hits(&mut self.clocks, self.t, self.tol)
    }

    /// Runs `output` of every block due now, in execution order:
    /// continuous blocks always (those that change only at events, only
    /// at events), discrete blocks at their hits, constant blocks on the
    /// first pass only.
    fn sweep(&mut self) {
        let m = &mut self.model;
        let all = self.first || self.at_event || self.inputs_changed;
        let order = if all { &self.every } else { &self.regular };
        for integrator in &self.integrands {
            integrator.output(&self.x, &mut self.signals);
        }
        let (clocks, first, t, x) = (&self.clocks, self.first, self.t, &self.x);
        let computed_at = &mut self.computed_at;
        visit::sweep(
            order,
            &mut self.signals,
            |v| due(v.rate, clocks, first),
            #[inline(always)]
            |v, signals| {
                if computed_at.must_run(v, t, false) {
                    let slot = &m.slots[v.block];
                    let mut io = io_for(slot, t, false, x, signals, &m.in_ports, &m.out_ports);
                    m.blocks[v.block].output(&mut io);
                }
            },
        );
    }

    /// Runs `update` of the blocks that have one (see [`crate::block::Block::updates`])
    /// and are due now: continuous ones always, discrete ones at hits.
    fn update_sweep(&mut self) {
        let m = &mut self.model;
        for v in &self.updating {
            if due(v.rate, &self.clocks, false) {
                let slot = &m.slots[v.block];
                let mut io = io_for(slot, self.t, false, &self.x, &mut self.signals, &m.in_ports, &m.out_ports);
                m.blocks[v.block].update(&mut io);
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
        self.first = false;
        self.inputs_changed = false;
        self.watch.record_signs(&mut self.model, &mut self.signals, &self.x, self.t);
        if !all_finite(&self.signals) {
            let m = &self.model;
            return Err(self.blame().signal(&self.signals, self.t, |i| m.blocks[i].diagnose()));
        }
        self.outputs_current = true;
        Ok(())
    }

    /// What names a block in this model's errors.
    fn blame(&self) -> Blame<'_> {
        Blame { meta: &self.model.meta, in_ports: &self.model.in_ports, out_ports: &self.model.out_ports }
    }

    /// Blocks with zero crossings may reset their states at a major step;
    /// returns whether any did.
    fn major_step_events(&mut self) -> bool {
        let m = &mut self.model;
        let mut changed = false;
        for &i in &self.watch.blocks {
            let slot = &m.slots[i];
            let (inputs, outputs) = (&m.in_ports[slot.inputs.clone()], &m.out_ports[slot.outputs.clone()]);
            let io = Io::new(self.t, false, &[], &mut self.signals, inputs, outputs);
            changed |= m.blocks[i].major_step(&io, &mut self.x[slot.states.clone()]);
        }
        changed
    }

    /// Steps (3) and (4): discrete updates at hits (and major-step updates
    /// of continuous blocks), then integration to the next major step — or
    /// to the first zero crossing before it.
    pub fn advance(&mut self) -> Result<(), SimError> {
        self.update_sweep();
        if std::mem::take(&mut self.events_may_change) {
            (self.next_event, self.next_event_generation) = self.earliest_event();
        }
        for h in &mut self.held {
            for (u, &s) in h.u.iter_mut().zip(&self.signals[h.input.clone()]) {
                *u = s;
            }
        }
        let target = self.next_major_time();
        let t0 = self.t;
        if let Some(dense) = &mut self.dense {
            dense.start(t0, &self.x);
        }
        let current = std::mem::take(&mut self.outputs_current) && !self.inputs_changed;
        let mut sys = Minor {
            model: &mut self.model,
            signals: &mut self.signals,
            continuous: &self.minor,
            at_start: current.then_some(&self.stale_at_start[..]),
            stateful: &self.called,
            integrands: &self.integrands,
            computed_at: &mut self.computed_at,
            t_end: target,
        };
        let x = &mut self.x[..self.n_integrated];
        let mut t_new = if x.is_empty() {
            // Nothing to integrate; max_step still bounds the adaptive
            // method's major steps so continuous sources are sampled finely.
            target.min(t0 + self.integ.method().max_step())
        } else {
            match self.integ.advance(&mut sys, t0, target, x) {
                Ok(t) => t,
                Err(error) => return Err(self.blame().solver(&self.signals, t0, error)),
            }
        };
        if let Some(dense) = &mut self.dense {
            dense.solver_end(t_new, x);
        }
        let event = self.watch.locate(&mut sys, &mut self.integ, t0, t_new, x);
        if let Some(t_event) = event {
            t_new = t_event;
            for (block, k) in self.watch.fired() {
                self.model.blocks[block].crossing_located(k);
            }
            self.integ.invalidate();
            if let Some(block) = self.watch.count_event(t_event, &self.model)? {
                self.model.slots[block].frozen = false;
            }
        }
        // Land exactly on the target when the solver reached it.
        self.t = if (target - t_new).abs() <= self.tol { target } else { t_new };
        for h in &mut self.held {
            if self.t > t0 {
                h.zoh.step(self.t - t0, &mut self.x[h.states.clone()], &h.u);
            }
        }
        if self.grid_step > 0.0 {
            self.grid.pass(self.t, self.tol);
        }
        if let Some(dense) = &mut self.dense {
            dense.end(self.t);
        }
        let mut clamped = false;
        for &i in &self.called {
            let meta = &self.model.slots[i];
            clamped |= self.model.blocks[i].clamp_states(&mut self.x[meta.states.clone()]);
        }
        let hit = self.mark_hits();
        let block_event = self.t >= self.next_event - self.tol;
        self.at_event = block_event;
        let event_generation = self.next_event_generation;
        if block_event {
            (self.next_event, self.next_event_generation) = self.earliest_event();
        }
        if hit || block_event || clamped {
            self.integ.invalidate();
        }
        if let Some(at) = breakpoint(hit, block_event, clamped || event.is_some(), event_generation) {
            self.left_limits(at);
        }
        if !all_finite(&self.x) {
            return Err(self.blame().state(&self.signals, self.t, &self.x));
        }
        self.stalled = if self.t > t0 { 0 } else { self.stalled + 1 };
        if self.stalled > 1000 {
            let (i, _) = self
                .model
                .blocks
                .iter()
                .enumerate()
                .map(|(i, b)| (i, b.next_event(t0)))
                .fold((0, f64::INFINITY), |best, (i, e)| if e < best.1 { (i, e) } else { best });
            return Err(SimError::Stalled { t: t0, block: self.model.meta[i].name.clone() });
        }
        self.major_steps += 1;
        Ok(())
    }

    /// The next major step's time ([`next_major_time`]), or a host's
    /// landing point before it.
    fn next_major_time(&self) -> f64 {
        let grid = (self.grid_step > 0.0).then_some(&self.grid);
        let next = next_major_time(&self.clocks, grid, self.stop, self.next_event, self.tol);
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
            let go_on = match self.dense.as_mut().map_or(Some(self.t), |dense| dense.major_row(self.t)) {
                Some(t) => sink(t, &self.signals),
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

pub(crate) fn io_for<'a>(
    meta: &Slot,
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
        &x[meta.states.clone()],
        signals,
        &in_ports[meta.inputs.clone()],
        &out_ports[meta.outputs.clone()],
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
