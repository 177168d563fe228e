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
pub(crate) mod clock;
pub(crate) mod driver;
mod error;
pub(crate) mod events;
pub(crate) mod host;
mod interpret;
mod minor;
pub(crate) mod output;
mod state;
pub(crate) mod visit;
pub(crate) use blame::Blame;
pub(crate) use clock::breakpoint;
pub use clock::earlier;
pub(crate) use driver::{Clockwork, Sweeps};
pub use error::SimError;
pub use host::Snapshot;
pub(crate) use state::RunBlock;
pub use state::RunState;

use crate::block::{Io, Port};
use crate::compile::{Model, Rate, Slot};
use ctlgraph_solver::{Method, Stats, Zoh};
pub use events::MAX_CONSECUTIVE_EVENTS;
use events::Watch;
use minor::{Minor, stale_at_start};
use output::Dense;
use std::ops::Range;
use std::sync::Arc;
use visit::{ComputedAt, Integrand, Visit};

/// Counters for the run report. `repr(C)`, like the solver's: they cross
/// the C interface of an accelerated run as they are
/// ([`crate::codegen::export`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunStats {
    pub major_steps: u64,
    pub solver: Stats,
    /// Zero crossings located (each ended a step).
    pub events: u64,
}

/// About how many major steps a run of `model` to `stop` (its own stop
/// time when `None`) takes, without preparing one: as
/// [`Simulator::expected_major_steps`], for the back-ends that are not a
/// [`Simulator`] (an accelerated run).
pub fn expected_major_steps(model: &Model, stop: Option<f64>) -> f64 {
    driver::Clockwork::new(model, stop.unwrap_or(model.sim.stop)).expected_major_steps()
}

/// Numbers run states, so a snapshot is restored only where it was taken.
static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// A number no other run of this process has ([`NEXT_ID`]).
pub(crate) fn next_run_id() -> u64 {
    NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

/// A model being simulated: the compiled model (shared), the plan this
/// simulator derives from it once (which blocks each sweep visits), the
/// run's state ([`RunState`], everything that changes) and scratch.
pub struct Simulator {
    model: Arc<Model>,
    state: RunState,
    /// The blocks whose states the solver integrates (the model's plan,
    /// [`crate::compile::Between`]): the plain integrators, and the
    /// others, called for their derivatives and `clamp_states` (`stateful`).
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
    /// The blocks a row between steps recomputes: the continuous ones but
    /// the plain integrators (copied) and event-only blocks (constant
    /// between events).
    row_visits: Vec<Visit>,
    /// Those of them the first stage recomputes when the signals hold the
    /// major step's outputs ([`stale_at_start`]), and whether they do:
    /// set by a major step's outputs, cleared by anything that could
    /// change a signal or state before the step is taken.
    stale_at_start: Vec<Visit>,
    /// When the time-only blocks last ran, to skip them at the same time.
    computed_at: ComputedAt,
    outputs_current: bool,
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
pub(super) struct Held {
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
        let watch = Watch::new(&model, model.sim.zero_crossing);
        let mut latched = 0;
        let held: Vec<Held> = model
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
        let row_visits =
            visits(&mut (0..n).filter(|&i| model.slots[i].rate == Rate::Continuous && !model.between.event_only[i]));
        let mut state = RunState::new(&model, Clockwork::new(&model, stop), watch);
        state.held_inputs = vec![0.0; latched];
        let held_zoh = held.iter().map(|h| (h.states.clone(), h.zoh.clone())).collect();
        state.dense = Dense::new(model.sim.output, state.x.len(), state.clockwork.n_integrated, held_zoh);
        let mut sim = Simulator {
            held,
            integrands,
            stateful,
            updating: Visit::list(&model, (0..n).filter(|&i| model.blocks[i].updates())),
            history: (0..n).filter(|&i| model.blocks[i].keeps_history()).collect(),
            every: visits(&mut (0..n)),
            regular: visits(
                &mut (0..n).filter(|&i| model.slots[i].rate != Rate::Constant && !model.between.event_only[i]),
            ),
            minor,
            row_visits,
            stale_at_start: stale,
            computed_at: ComputedAt::new(n),
            outputs_current: false,
            state,
            model,
        };
        sim.reset();
        sim
    }

    /// Back to t = 0 with initial states (blocks re-initialised).
    pub fn reset(&mut self) {
        driver::reset(self);
    }

    pub fn model(&self) -> &Model {
        &self.model
    }

    pub fn time(&self) -> f64 {
        self.state.clockwork.t
    }

    pub fn stop_time(&self) -> f64 {
        self.state.clockwork.stop
    }

    pub fn method(&self) -> Method {
        self.state.clockwork.method()
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
        let c = &self.state.clockwork;
        RunStats { major_steps: c.major_steps, solver: c.integ.stats(), events: self.state.watch.events }
    }

    /// What the run has to say beyond its numbers (blocks whose chattering
    /// crossings `zero_crossing: adaptive` ignored).
    pub fn warnings(&self) -> &[String] {
        &self.state.watch.warnings
    }

    /// About how many major steps the run takes
    /// ([`Clockwork::expected_major_steps`]).
    pub fn expected_major_steps(&self) -> f64 {
        self.state.clockwork.expected_major_steps()
    }

    /// Whether the current major step is a sample hit of the discrete rate
    /// `clock` (an index into [`Model::clocks`]): what a sampled part of
    /// the graph sees at this step (recorded for `codegen --target c --verify`).
    pub fn sample_hit(&self, clock: usize) -> bool {
        self.state.clockwork.hit.get(clock).copied().unwrap_or(false)
    }

    /// Whether the run has reached its stop time.
    pub fn finished(&self) -> bool {
        self.state.clockwork.finished()
    }

    /// Step (1) of a major step: outputs in execution order (again after a
    /// block reset its states here), the zero-crossing signs for the next
    /// step, then a check that every signal is finite.
    pub fn outputs(&mut self) -> Result<(), SimError> {
        driver::outputs(self)
    }

    /// Steps (3) and (4): discrete updates at hits (and major-step updates
    /// of continuous blocks), then integration to the next major step — or
    /// to the first zero crossing before it.
    pub fn advance(&mut self) -> Result<(), SimError> {
        driver::advance(self)
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
        driver::run_while(self, sink)
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
