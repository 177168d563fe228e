//! Block events and breakpoints: the earliest event a block reports (and
//! its generation), and the left limits handed, at a major step where
//! signals may jump, to the blocks that keep their input's past
//! ([`crate::Block::keeps_history`]: transport delays).

use super::{Minor, Simulator, earlier, io_for};
use crate::block::Breakpoint;

impl Simulator {
    /// The first block event strictly after the current time, and its
    /// generation (the lowest of the blocks' whose event it is). Cached in
    /// `next_event` and recomputed only when time reaches it.
    pub(super) fn earliest_event(&self) -> (f64, u32) {
        let t = self.t;
        self.model
            .blocks
            .iter()
            .fold((f64::INFINITY, 0), |best, b| earlier(best, b.next_event(t), || b.event_generation(t)))
    }

    /// At a breakpoint (the step just taken ends where signals may jump):
    /// the continuous signals' left limit there, handed to the blocks that
    /// keep their input's past, before the major step's outputs replace it.
    pub(super) fn left_limits(&mut self, at: Breakpoint) {
        if self.history.is_empty() {
            return;
        }
        let t = self.t;
        let mut sys = Minor {
            model: &mut self.model,
            signals: &mut self.signals,
            continuous: &self.minor,
            at_start: None,
            stateful: &self.called,
            integrands: &self.integrands,
            computed_at: &mut self.computed_at,
            t_end: t,
        };
        sys.outputs(t, &self.x);
        self.hand_left_limits(at);
    }

    /// [`Block::left_limit`] of the blocks keeping history, with the
    /// signals as they stand.
    pub(super) fn hand_left_limits(&mut self, at: Breakpoint) {
        self.events_may_change = true;
        let m = &mut self.model;
        for &i in &self.history {
            let slot = &m.slots[i];
            let io = io_for(slot, self.t, true, &self.x, &mut self.signals, &m.in_ports, &m.out_ports)
                .in_minor_step(slot.frozen);
            m.blocks[i].left_limit(&io, at);
        }
    }
}
