//! Blocks that run inside another block, on a signal buffer of its own:
//! an algebraic loop's members ([`crate::algebraic`]), a conditionally
//! executed subsystem's ([`crate::conditional`]).

use crate::block::{Block, Crossing, Io, Port};
use std::ops::Range;
use std::sync::Mutex;

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
fn share(members: &mut [Member]) -> (usize, usize) {
    let (mut n_states, mut n_crossings) = (0, 0);
    for m in members {
        let (s, c) = (m.block.num_states(), m.block.num_zero_crossings());
        m.states = n_states..n_states + s;
        m.crossings = n_crossings..n_crossings + c;
        (n_states, n_crossings) = (n_states + s, n_crossings + c);
    }
    (n_states, n_crossings)
}

/// Members on the buffer they run on, and what every containing block
/// passes through to them alike: states, derivatives, clamps, events,
/// zero crossings, major steps, messages.
pub struct Inner {
    /// In evaluation order.
    pub(crate) members: Vec<Member>,
    pub(crate) buffer: Vec<f64>,
    /// Where the containing block's inputs 0.. are copied in the buffer.
    external: Vec<Port>,
    /// Where each of its outputs (every member's) lies in the buffer.
    pub(crate) outputs: Vec<Port>,
    /// A copy of the buffer for [`Block::zero_crossings`], which takes the
    /// block by shared reference (no allocation: sized at build).
    crossing_buffer: Mutex<Vec<f64>>,
    pub(crate) n_states: usize,
    pub(crate) n_crossings: usize,
}

impl Clone for Inner {
    fn clone(&self) -> Self {
        let copy = self.crossing_buffer.lock().map_or_else(|e| e.into_inner().clone(), |b| b.clone());
        Inner {
            members: self.members.clone(),
            buffer: self.buffer.clone(),
            external: self.external.clone(),
            outputs: self.outputs.clone(),
            crossing_buffer: Mutex::new(copy),
            n_states: self.n_states,
            n_crossings: self.n_crossings,
        }
    }
}

impl Inner {
    /// `members` in evaluation order, their ports on a buffer of `buffer_len`.
    pub fn new(mut members: Vec<Member>, external: Vec<Port>, outputs: Vec<Port>, buffer_len: usize) -> Inner {
        let (n_states, n_crossings) = share(&mut members);
        let buffer = vec![0.0; buffer_len];
        let crossing_buffer = Mutex::new(buffer.clone());
        Inner { members, buffer, external, outputs, crossing_buffer, n_states, n_crossings }
    }

    /// The containing block's inputs into the buffer.
    pub(crate) fn copy_inputs(&mut self, io: &Io) {
        for (k, slot) in self.external.iter().enumerate() {
            self.buffer[slot.offset..slot.offset + slot.width].copy_from_slice(io.input(k));
        }
    }

    pub(crate) fn initialize(&mut self, x0: &mut [f64]) {
        for m in &mut self.members {
            m.block.initialize(&mut x0[m.states.clone()]);
        }
        self.buffer.iter_mut().for_each(|v| *v = 0.0);
    }

    pub(crate) fn derivatives(&mut self, call: Call, x: &[f64], dx: &mut [f64]) {
        for m in self.members.iter_mut().filter(|m| !m.states.is_empty()) {
            let mio = call.io((&m.ins, &m.outs), &x[m.states.clone()], &mut self.buffer);
            m.block.derivatives(&mio, &mut dx[m.states.clone()]);
        }
    }

    pub(crate) fn clamp_states(&self, x: &mut [f64]) -> bool {
        self.members.iter().fold(false, |moved, m| m.block.clamp_states(&mut x[m.states.clone()]) | moved)
    }

    /// The earliest of the members' own events.
    pub(crate) fn next_event(&self, t: f64) -> f64 {
        self.members.iter().map(|m| m.block.next_event(t)).fold(f64::INFINITY, f64::min)
    }

    /// The members' zero-crossing functions, into `g[..n_crossings]`.
    pub(crate) fn zero_crossings(&self, call: Call, x: &[f64], g: &mut [f64]) {
        let mut buffer = self.crossing_buffer.lock().unwrap_or_else(|e| e.into_inner());
        buffer.copy_from_slice(&self.buffer);
        for m in self.members.iter().filter(|m| !m.crossings.is_empty()) {
            let mio = call.io((&m.ins, &m.outs), &x[m.states.clone()], &mut buffer);
            m.block.zero_crossings(&mio, &mut g[m.crossings.clone()]);
        }
    }

    /// The member holding crossing function `k`, and its own index there.
    fn crossing(&self, k: usize) -> Option<(usize, usize)> {
        let m = self.members.iter().position(|m| m.crossings.contains(&k))?;
        Some((m, k - self.members[m].crossings.start))
    }

    pub(crate) fn crossing_direction(&self, k: usize) -> Crossing {
        self.crossing(k).map_or(Crossing::Ignore, |(m, j)| self.members[m].block.crossing_direction(j))
    }

    pub(crate) fn crossing_located(&mut self, k: usize) {
        if let Some((m, j)) = self.crossing(k) {
            self.members[m].block.crossing_located(j);
        }
    }

    /// The members' major steps; whether any changed something.
    pub(crate) fn major_step(&mut self, call: Call, x: &mut [f64]) -> bool {
        let mut changed = false;
        for m in self.members.iter_mut().filter(|m| m.block.needs_major_step()) {
            let mio = call.io((&m.ins, &m.outs), &[], &mut self.buffer);
            changed |= m.block.major_step(&mio, &mut x[m.states.clone()]);
        }
        changed
    }

    /// A member's reason for a NaN, named after it.
    pub(crate) fn diagnose(&self) -> Option<String> {
        self.members.iter().find_map(|m| m.block.diagnose().map(|d| format!("{}: {d}", m.name)))
    }

    pub(crate) fn build_report(&self) -> Option<String> {
        let reports: Vec<String> =
            self.members.iter().filter_map(|m| m.block.build_report().map(|r| format!("{}: {r}", m.name))).collect();
        (!reports.is_empty()).then(|| reports.join("; "))
    }
}
