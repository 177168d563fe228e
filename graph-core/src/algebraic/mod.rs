//! The block an algebraic loop becomes ([`crate::compile`] collapses each
//! loop of direct-feedthrough blocks into one): its members run on a
//! buffer of their own, and at every evaluation of its outputs the loop's
//! cut signals z are solved for so that the members' equations hold,
//! F(z) = z ([`newton`]). Everything else a block does — states,
//! derivatives, updates, zero crossings, events — is its members', passed
//! through with their ports on that buffer.

mod newton;

use crate::block::{Block, Breakpoint, Crossing, Io, Port};
use crate::composite::{Call, Member};
use newton::Newton;
use std::sync::Mutex;

/// An algebraic loop as one block.
pub struct AlgebraicLoop {
    /// `a -> b -> a`, for messages.
    name: String,
    /// In evaluation order: the members not cut in dependency order, then
    /// the `n_cut` whose outputs are the unknowns.
    members: Vec<Member>,
    n_cut: usize,
    /// Where each of the loop block's inputs is copied in the buffer.
    external: Vec<Port>,
    /// Where each of its outputs (its members') lies in the buffer.
    outputs: Vec<Port>,
    buffer: Vec<f64>,
    newton: Newton,
    /// A copy of the buffer for [`Block::zero_crossings`], which takes the
    /// block by shared reference (no allocation: sized at build).
    crossing_buffer: Mutex<Vec<f64>>,
    n_states: usize,
    n_crossings: usize,
}

impl Clone for AlgebraicLoop {
    fn clone(&self) -> Self {
        let crossing_buffer =
            Mutex::new(self.crossing_buffer.lock().map_or_else(|e| e.into_inner().clone(), |b| b.clone()));
        AlgebraicLoop {
            name: self.name.clone(),
            members: self.members.clone(),
            n_cut: self.n_cut,
            external: self.external.clone(),
            outputs: self.outputs.clone(),
            buffer: self.buffer.clone(),
            newton: self.newton.clone(),
            crossing_buffer,
            n_states: self.n_states,
            n_crossings: self.n_crossings,
        }
    }
}

impl AlgebraicLoop {
    /// `members` in evaluation order, the last `n_cut` cut; `unknowns` the
    /// cut members' outputs in the buffer; `tolerance` the residual's bound
    /// relative to the unknowns' size.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        name: String,
        mut members: Vec<Member>,
        n_cut: usize,
        external: Vec<Port>,
        outputs: Vec<Port>,
        unknowns: Vec<Port>,
        buffer_len: usize,
        tolerance: f64,
    ) -> AlgebraicLoop {
        let (n_states, n_crossings) = crate::composite::share(&mut members);
        AlgebraicLoop {
            name,
            members,
            n_cut,
            external,
            outputs,
            buffer: vec![0.0; buffer_len],
            newton: Newton::new(unknowns, tolerance),
            crossing_buffer: Mutex::new(vec![0.0; buffer_len]),
            n_states,
            n_crossings,
        }
    }

    /// The member holding zero-crossing function `k` of the loop, and its own index.
    fn crossing(&self, k: usize) -> Option<(usize, usize)> {
        let m = self.members.iter().position(|m| m.crossings.contains(&k))?;
        Some((m, k - self.members[m].crossings.start))
    }
}

/// The loop's equations for the solver: with the unknowns written into the
/// cut members' outputs, the members run in order and the cut ones' own
/// outputs come back as F(z).
struct Equations<'a> {
    members: &'a mut [Member],
    n_cut: usize,
    buffer: &'a mut [f64],
    call: Call,
    x: &'a [f64],
}

impl newton::Equations for Equations<'_> {
    fn evaluate(&mut self, unknowns: &[Port], z: &[f64], f: &mut [f64]) {
        newton::scatter(unknowns, z, self.buffer);
        let first_cut = self.members.len() - self.n_cut;
        for (k, m) in self.members.iter_mut().enumerate() {
            let mut io = self.call.io((&m.ins, &m.outs), &self.x[m.states.clone()], self.buffer);
            m.block.output(&mut io);
            if k >= first_cut {
                // F's share, then z back where the next cut member reads it.
                newton::gather(&m.outs, self.buffer, unknowns, f);
                newton::scatter_ports(&m.outs, unknowns, z, self.buffer);
            }
        }
    }
}

impl Block for AlgebraicLoop {
    fn num_states(&self) -> usize {
        self.n_states
    }

    fn initialize(&mut self, x0: &mut [f64]) {
        for m in &mut self.members {
            m.block.initialize(&mut x0[m.states.clone()]);
        }
        self.buffer.iter_mut().for_each(|v| *v = 0.0);
        self.newton.reset();
    }

    /// Solves the loop at this evaluation (from the last major step's
    /// solution, so the result depends on the inputs and states alone),
    /// and outputs every member's outputs. A loop that cannot be solved
    /// outputs NaN: the run stops there, naming the loop ([`Block::diagnose`]).
    fn output(&mut self, io: &mut Io) {
        for (k, slot) in self.external.iter().enumerate() {
            self.buffer[slot.offset..slot.offset + slot.width].copy_from_slice(io.input(k));
        }
        let call = Call::of(io);
        let mut eq =
            Equations { members: &mut self.members, n_cut: self.n_cut, buffer: &mut self.buffer, call, x: io.x };
        let solved = self.newton.solve(&mut eq);
        for (k, slot) in self.outputs.iter().enumerate() {
            let values = &self.buffer[slot.offset..slot.offset + slot.width];
            let out = io.output(k);
            if solved {
                out.copy_from_slice(values);
            } else {
                out.iter_mut().for_each(|v| *v = f64::NAN);
            }
        }
    }

    fn update(&mut self, io: &mut Io) {
        let call = Call::of(io);
        for m in &mut self.members {
            let mut mio = call.io((&m.ins, &m.outs), &io.x[m.states.clone()], &mut self.buffer);
            m.block.update(&mut mio);
        }
        self.newton.remember(&self.buffer);
    }

    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        let call = Call::of(io);
        for m in self.members.iter_mut().filter(|m| !m.states.is_empty()) {
            let mio = call.io((&m.ins, &m.outs), &io.x[m.states.clone()], &mut self.buffer);
            m.block.derivatives(&mio, &mut dx[m.states.clone()]);
        }
    }

    fn clamp_states(&self, x: &mut [f64]) -> bool {
        self.members.iter().fold(false, |moved, m| m.block.clamp_states(&mut x[m.states.clone()]) | moved)
    }

    fn next_event(&self, t: f64) -> f64 {
        self.members.iter().map(|m| m.block.next_event(t)).fold(f64::INFINITY, f64::min)
    }

    fn event_generation(&self, t: f64) -> u32 {
        self.members
            .iter()
            .filter(|m| m.block.next_event(t) == t)
            .map(|m| m.block.event_generation(t))
            .min()
            .unwrap_or(0)
    }

    fn min_event_spacing(&self) -> f64 {
        self.members.iter().map(|m| m.block.min_event_spacing()).fold(f64::INFINITY, f64::min)
    }

    fn num_zero_crossings(&self) -> usize {
        self.n_crossings
    }

    fn needs_major_step(&self) -> bool {
        self.members.iter().any(|m| m.block.needs_major_step())
    }

    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        let call = Call::of(io);
        let mut buffer = self.crossing_buffer.lock().unwrap_or_else(|e| e.into_inner());
        buffer.copy_from_slice(&self.buffer);
        for m in self.members.iter().filter(|m| !m.crossings.is_empty()) {
            let mio = call.io((&m.ins, &m.outs), &io.x[m.states.clone()], &mut buffer);
            m.block.zero_crossings(&mio, &mut g[m.crossings.clone()]);
        }
    }

    fn crossing_direction(&self, k: usize) -> Crossing {
        self.crossing(k).map_or(Crossing::Ignore, |(m, j)| self.members[m].block.crossing_direction(j))
    }

    fn crossing_located(&mut self, k: usize) {
        if let Some((m, j)) = self.crossing(k) {
            self.members[m].block.crossing_located(j);
        }
    }

    fn major_step(&mut self, io: &Io, x: &mut [f64]) -> bool {
        let call = Call::of(io);
        let mut changed = false;
        for m in self.members.iter_mut().filter(|m| m.block.needs_major_step()) {
            let mio = call.io((&m.ins, &m.outs), &[], &mut self.buffer);
            changed |= m.block.major_step(&mio, &mut x[m.states.clone()]);
        }
        changed
    }

    fn left_limit(&mut self, io: &Io, at: Breakpoint) {
        let call = Call::of(io);
        for m in &mut self.members {
            let mio = call.io((&m.ins, &m.outs), &io.x[m.states.clone()], &mut self.buffer);
            m.block.left_limit(&mio, at);
        }
    }

    fn diagnose(&self) -> Option<String> {
        if let Some(failure) = self.newton.failure() {
            return Some(format!("algebraic loop {}: {failure}", self.name));
        }
        self.members.iter().find_map(|m| m.block.diagnose().map(|d| format!("{}: {d}", m.name)))
    }

    fn build_report(&self) -> Option<String> {
        let reports: Vec<String> =
            self.members.iter().filter_map(|m| m.block.build_report().map(|r| format!("{}: {r}", m.name))).collect();
        (!reports.is_empty()).then(|| reports.join("; "))
    }
}
