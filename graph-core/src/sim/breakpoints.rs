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
        let t = self.state.t;
        self.state
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
        let s = &mut self.state;
        let t = s.t;
        let mut sys = Minor {
            model: &self.model,
            blocks: &mut s.blocks,
            signals: &mut s.signals,
            continuous: &self.minor,
            at_start: None,
            stateful: &self.stateful,
            integrands: &self.integrands,
            computed_at: &mut self.computed_at,
            t_end: t,
        };
        sys.outputs(t, &s.x);
        self.hand_left_limits(at);
    }

    /// [`Block::left_limit`] of the blocks keeping history, with the
    /// signals as they stand.
    pub(super) fn hand_left_limits(&mut self, at: Breakpoint) {
        let (m, s) = (&*self.model, &mut self.state);
        s.events_may_change = true;
        for &i in &self.history {
            let io = io_for(&m.slots[i], s.t, true, &s.x, &mut s.signals, &m.in_ports, &m.out_ports)
                .in_minor_step(s.blocks[i].frozen);
            s.blocks[i].left_limit(&io, at);
        }
    }
}
