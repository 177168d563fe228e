//! A run's state: everything that changes while a graph is simulated, in
//! one value apart from the compiled [`Model`] (shared, immutable) and the
//! simulator's plan (the visit lists it derives from the model once).
//!
//! A snapshot is a clone of it and restoring is an assignment, so a field
//! added here is saved and restored without another line. Block memory is
//! here as the block objects themselves — each run clones the model's
//! built blocks once, at its start — rather than as a layout the blocks
//! declare: a block keeps its parameters beside its memory (a few numbers
//! for most; lookup tables and fuzzy systems share theirs), and the step
//! loop calls it through one pointer, as before.

use super::events::Watch;
use super::output::Dense;
use super::{Clock, NEXT_ID};
use crate::block::Block;
use crate::compile::Model;
use ctlgraph_solver::Integrator;

/// Everything a run changes: time, continuous states, signals, block
/// memory, clocks, the solver's history, the event watch, the held
/// inputs of exactly stepped blocks. Taken with [`crate::Simulator::state`],
/// returned to with [`crate::Simulator::restore`]; restoring and running
/// on gives the same numbers as running on from where it was taken.
#[derive(Clone)]
pub struct RunState {
    /// Which simulator it belongs to (its plan indexes into it).
    pub(super) owner: u64,
    pub(super) t: f64,
    pub(super) stop: f64,
    /// No major step has computed outputs yet.
    pub(super) first: bool,
    pub(super) signals: Vec<f64>,
    pub(super) x: Vec<f64>,
    /// The blocks, with their memory (cloned from the model's).
    pub(super) blocks: Vec<RunBlock>,
    pub(super) integ: Integrator,
    pub(super) clocks: Vec<Clock>,
    /// The fixed-step grid's position.
    pub(super) grid: Clock,
    /// Earliest block event after `t` and its [`crate::Breakpoint::generation`].
    pub(super) next_event: f64,
    pub(super) next_event_generation: u32,
    /// Blocks were handed a breakpoint's left limit: their updates may
    /// schedule events (a delay's arrivals), so `next_event` is recomputed.
    pub(super) events_may_change: bool,
    pub(super) major_steps: u64,
    /// Major steps in a row at which time did not advance.
    pub(super) stalled: u32,
    /// Zero-crossing functions: their signs, the events counted.
    pub(super) watch: Watch,
    /// The held LTI blocks' inputs latched at the last major step (each
    /// block's range in `Simulator::held`).
    pub(super) held_inputs: Vec<f64>,
    /// Whether this major step is at a block event (see `Between::event_only`).
    pub(super) at_event: bool,
    /// A host set an input since the last outputs.
    pub(super) inputs_changed: bool,
    /// Rows between major steps, when `simulation.output` asks for them.
    pub(super) dense: Option<Dense>,
}

/// A block of a run: its own copy, with its memory, and whether its modes
/// are frozen in minor steps (its zero crossings are watched; cleared when
/// it chatters, see `Watch::count_event`) — side by side, as the step loop
/// reads both at every call. Dereferences to the block.
#[derive(Clone)]
pub(crate) struct RunBlock {
    pub block: Box<dyn Block>,
    pub frozen: bool,
}

impl std::ops::Deref for RunBlock {
    type Target = dyn Block;
    fn deref(&self) -> &(dyn Block + 'static) {
        &*self.block
    }
}

impl std::ops::DerefMut for RunBlock {
    fn deref_mut(&mut self) -> &mut (dyn Block + 'static) {
        &mut *self.block
    }
}

impl RunState {
    /// A run of `model` to `stop`, before its initial states are computed.
    pub(super) fn new(
        model: &Model,
        stop: f64,
        integ: Integrator,
        clocks: Vec<Clock>,
        grid: Clock,
        watch: Watch,
    ) -> Self {
        RunState {
            owner: NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            t: 0.0,
            stop,
            first: true,
            signals: vec![0.0; model.signal_len],
            x: vec![0.0; model.n_states],
            blocks: model.blocks.iter().map(|b| RunBlock { block: b.clone(), frozen: false }).collect(),
            integ,
            clocks,
            grid,
            next_event: f64::INFINITY,
            next_event_generation: 0,
            events_may_change: false,
            major_steps: 0,
            stalled: 0,
            watch,
            held_inputs: Vec::new(),
            at_event: true,
            inputs_changed: false,
            dense: None,
        }
    }

    /// The time it is at.
    pub fn time(&self) -> f64 {
        self.t
    }
}
