//! The block an algebraic loop becomes ([`crate::compile`] collapses each
//! loop of direct-feedthrough blocks into one): its members run on a
//! buffer of their own, and at every evaluation of its outputs the loop's
//! cut signals z are solved for so that the members' equations hold,
//! F(z) = z ([`newton`]). Everything else a block does — states,
//! derivatives, updates, zero crossings, events — is its members', passed
//! through with their ports on that buffer.

mod newton;

use crate::block::{Block, Crossing, Io, Port};
use crate::composite::{Call, Inner, Member};
use newton::Newton;

/// An algebraic loop as one block.
#[derive(Clone)]
pub struct AlgebraicLoop {
    /// `a -> b -> a`, for messages.
    name: String,
    /// In evaluation order: the members not cut in dependency order, then
    /// the `n_cut` whose outputs are the unknowns.
    inner: Inner,
    n_cut: usize,
    newton: Newton,
}

impl AlgebraicLoop {
    /// `members` in evaluation order, the last `n_cut` cut; `unknowns` the
    /// cut members' outputs in the buffer; `tolerance` the residual's bound
    /// relative to the unknowns' size.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        name: String,
        members: Vec<Member>,
        n_cut: usize,
        external: Vec<Port>,
        outputs: Vec<Port>,
        unknowns: Vec<Port>,
        buffer_len: usize,
        tolerance: f64,
    ) -> AlgebraicLoop {
        let inner = Inner::new(members, external, outputs, buffer_len);
        AlgebraicLoop { name, inner, n_cut, newton: Newton::new(unknowns, tolerance) }
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
        self.inner.n_states
    }

    fn initialize(&mut self, x0: &mut [f64]) {
        self.inner.initialize(x0);
        self.newton.reset();
    }

    /// Solves the loop at this evaluation (from the last major step's
    /// solution, so the result depends on the inputs and states alone),
    /// and outputs every member's outputs. A loop that cannot be solved
    /// outputs NaN: the run stops there, naming the loop ([`Block::diagnose`]).
    fn output(&mut self, io: &mut Io) {
        self.inner.copy_inputs(io);
        let inner = &mut self.inner;
        let call = Call::of(io);
        let mut eq =
            Equations { members: &mut inner.members, n_cut: self.n_cut, buffer: &mut inner.buffer, call, x: io.x };
        let solved = self.newton.solve(&mut eq);
        for (k, slot) in inner.outputs.iter().enumerate() {
            let out = io.output(k);
            if solved {
                out.copy_from_slice(&inner.buffer[slot.offset..slot.offset + slot.width]);
            } else {
                out.iter_mut().for_each(|v| *v = f64::NAN);
            }
        }
    }

    fn update(&mut self, io: &mut Io) {
        let call = Call::of(io);
        let inner = &mut self.inner;
        for m in &mut inner.members {
            let mut mio = call.io((&m.ins, &m.outs), &io.x[m.states.clone()], &mut inner.buffer);
            m.block.update(&mut mio);
        }
        self.newton.remember(&inner.buffer);
    }

    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        self.inner.derivatives(Call::of(io), io.x, dx);
    }

    fn clamp_states(&self, x: &mut [f64]) -> bool {
        self.inner.clamp_states(x)
    }

    fn next_event(&self, t: f64) -> f64 {
        self.inner.next_event(t)
    }

    fn event_generation(&self, t: f64) -> u32 {
        let members = &self.inner.members;
        members.iter().filter(|m| m.block.next_event(t) == t).map(|m| m.block.event_generation(t)).min().unwrap_or(0)
    }

    fn min_event_spacing(&self) -> f64 {
        self.inner.members.iter().map(|m| m.block.min_event_spacing()).fold(f64::INFINITY, f64::min)
    }

    fn num_zero_crossings(&self) -> usize {
        self.inner.n_crossings
    }

    fn needs_major_step(&self) -> bool {
        self.inner.members.iter().any(|m| m.block.needs_major_step())
    }

    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        self.inner.zero_crossings(Call::of(io), io.x, g);
    }

    fn crossing_direction(&self, k: usize) -> Crossing {
        self.inner.crossing_direction(k)
    }

    fn crossing_located(&mut self, k: usize) {
        self.inner.crossing_located(k);
    }

    fn major_step(&mut self, io: &Io, x: &mut [f64]) -> bool {
        self.inner.major_step(Call::of(io), x)
    }

    fn diagnose(&self) -> Option<String> {
        match self.newton.failure() {
            Some(failure) => Some(format!("algebraic loop {}: {failure}", self.name)),
            None => self.inner.diagnose(),
        }
    }

    fn build_report(&self) -> Option<String> {
        self.inner.build_report()
    }
}
