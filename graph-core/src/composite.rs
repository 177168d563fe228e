//! Blocks that run inside another block, on a signal buffer of its own:
//! an algebraic loop's members ([`crate::algebraic`]), a conditionally
//! executed subsystem's ([`crate::conditional`]).

use crate::block::{Block, Io, Port};
use std::ops::Range;

/// A block inside another, with its ports on the containing block's buffer.
#[derive(Clone)]
pub struct Member {
    pub(crate) name: String,
    pub(crate) block: Box<dyn Block>,
    pub(crate) ins: Vec<Port>,
    pub(crate) outs: Vec<Port>,
    /// Its share of the containing block's states and zero-crossing functions.
    pub(crate) states: Range<usize>,
    pub(crate) crossings: Range<usize>,
    /// Its own sample hits, `offset + k·period`, where it keeps its rate
    /// inside the containing block.
    pub(crate) hits: Option<(f64, f64)>,
}

impl Member {
    pub fn new(name: String, block: Box<dyn Block>, ins: Vec<Port>, outs: Vec<Port>) -> Member {
        Member { name, block, ins, outs, states: 0..0, crossings: 0..0, hits: None }
    }
}

/// How the containing block was called, for its members' calls.
#[derive(Clone, Copy)]
pub(crate) struct Call {
    pub(crate) t: f64,
    left_limit: bool,
    pub(crate) major: bool,
    frozen: bool,
}

impl Call {
    pub(crate) fn of(io: &Io) -> Call {
        Call { t: io.t, left_limit: io.is_left_limit(), major: io.is_major(), frozen: !io.may_switch() }
    }

    pub(crate) fn io<'a>(self, (ins, outs): (&'a [Port], &'a [Port]), x: &'a [f64], buffer: &'a mut [f64]) -> Io<'a> {
        let io = Io::new(self.t, self.left_limit, x, buffer, ins, outs);
        if self.major { io } else { io.in_minor_step(self.frozen) }
    }
}

/// Gives each member its share of the containing block's states and
/// crossing functions, in order; returns the totals.
pub(crate) fn share(members: &mut [Member]) -> (usize, usize) {
    let (mut n_states, mut n_crossings) = (0, 0);
    for m in members {
        let (s, c) = (m.block.num_states(), m.block.num_zero_crossings());
        m.states = n_states..n_states + s;
        m.crossings = n_crossings..n_crossings + c;
        (n_states, n_crossings) = (n_states + s, n_crossings + c);
    }
    (n_states, n_crossings)
}
