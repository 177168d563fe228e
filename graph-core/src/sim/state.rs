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

use super::driver::Clockwork;
use super::events::Watch;
use super::output::Dense;
use crate::block::Block;
use crate::compile::Model;

/// Everything a run changes: time, continuous states, signals, block
/// memory, clocks, the solver's history, the event watch, the held
/// inputs of exactly stepped blocks. Taken with [`crate::Simulator::state`],
/// returned to with [`crate::Simulator::restore`]; restoring and running
/// on gives the same numbers as running on from where it was taken.
#[derive(Clone)]
pub struct RunState {
    /// Which simulator it belongs to (its plan indexes into it).
    pub(super) owner: u64,
    /// Time, the solver, clocks, block events: the driver's part.
    pub(super) clockwork: Clockwork,
    pub(super) signals: Vec<f64>,
    pub(super) x: Vec<f64>,
    /// The blocks, with their memory (cloned from the model's).
    pub(super) blocks: Vec<RunBlock>,
    /// Zero-crossing functions: their signs, the events counted.
    pub(super) watch: Watch,
    /// The held LTI blocks' inputs latched at the last major step (each
    /// block's range in `Simulator::held`).
    pub(super) held_inputs: Vec<f64>,
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
    pub(super) fn new(model: &Model, clockwork: Clockwork, watch: Watch) -> Self {
        RunState {
            owner: super::next_run_id(),
            clockwork,
            signals: vec![0.0; model.signal_len],
            x: vec![0.0; model.n_states],
            blocks: model.blocks.iter().map(|b| RunBlock { block: b.clone(), frozen: false }).collect(),
            watch,
            held_inputs: Vec::new(),
            dense: None,
        }
    }

    /// The time it is at.
    pub fn time(&self) -> f64 {
        self.clockwork.t
    }
}
