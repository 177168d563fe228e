//! Block events and breakpoints: the earliest event a block reports (and
//! its generation), and the left limits handed, at a major step where
//! signals may jump, to the blocks that keep their input's past
//! ([`crate::Block::keeps_history`]: transport delays).

use super::{Simulator, earlier, io_for};
use crate::block::Breakpoint;

impl Simulator {
    /// The first block event strictly after `t`, and its generation (the
    /// lowest of the blocks' whose event it is). The driver caches it and
    /// asks again only when time reaches it.
    pub(super) fn earliest_event_after(&self, t: f64) -> (f64, u32) {
        self.state
            .blocks
            .iter()
            .fold((f64::INFINITY, 0), |best, b| earlier(best, b.next_event(t), || b.event_generation(t)))
    }

    /// [`Block::left_limit`] of the blocks keeping history, with the
    /// signals as they stand.
    pub(super) fn hand_left_limits(&mut self, at: Breakpoint) {
        let (m, s) = (&*self.model, &mut self.state);
        for &i in &self.history {
            let io = io_for(&m.slots[i], s.clockwork.t, true, &s.x, &mut s.signals, &m.in_ports, &m.out_ports)
                .in_minor_step(s.blocks[i].frozen);
            s.blocks[i].left_limit(&io, at);
        }
    }
}
