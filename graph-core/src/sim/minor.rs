//! The system the ODE solver integrates between major steps: continuous
//! outputs recomputed at each stage, discrete outputs held.

use super::events::Crossings;
use super::io_for;
use super::state::RunBlock;
use super::visit::{ComputedAt, Integrand, Visit, sweep};
use crate::block::Crossing;
use crate::compile::Model;
use ctlgraph_solver::OdeSystem;

/// The ODE the solver sees: set states, recompute continuous outputs (modes
/// frozen where zero crossings are watched), ask stateful blocks for
/// derivatives. Discrete outputs hold.
pub(super) struct Minor<'a> {
    pub(super) model: &'a Model,
    pub(super) blocks: &'a mut [RunBlock],
    pub(super) signals: &'a mut [f64],
    pub(super) continuous: &'a [Visit],
    /// Set when the signals hold the major step's outputs at the step's
    /// start: the continuous visits the first stage must still run there
    /// ([`stale_at_start`]). Taken by that stage.
    pub(super) at_start: Option<&'a [Visit]>,
    /// The integrated blocks: those called for their derivatives
    /// (`stateful`), and the plain integrators, whose derivatives are
    /// their inputs (`integrands`).
    pub(super) stateful: &'a [usize],
    pub(super) integrands: &'a [Integrand],
    pub(super) computed_at: &'a mut ComputedAt,
    pub(super) t_end: f64,
}

impl Minor<'_> {
    /// Continuous outputs at (t, x), modes frozen.
    #[inline(always)]
    pub(super) fn outputs(&mut self, t: f64, x: &[f64]) {
        for integrator in self.integrands {
            integrator.output(x, self.signals);
        }
        self.run(self.continuous, t, x);
    }

    /// The outputs of `visits` at (t, x), modes frozen (the plain
    /// integrators' already copied).
    #[inline(always)]
    fn run(&mut self, visits: &[Visit], t: f64, x: &[f64]) {
        let (m, blocks, computed_at) = (self.model, &mut *self.blocks, &mut *self.computed_at);
        let left = t >= self.t_end;
        sweep(
            visits,
            self.signals,
            |_| true,
            #[inline(always)]
            |v, signals| {
                if computed_at.must_run(v, t, left) {
                    let (slot, block) = (&m.slots[v.block], &mut blocks[v.block]);
                    let mut io =
                        io_for(slot, t, left, x, signals, &m.in_ports, &m.out_ports).in_minor_step(block.frozen);
                    block.output(&mut io);
                }
            },
        );
    }

    /// The stateful blocks' derivatives at (t, x), outputs computed.
    #[inline(always)]
    fn stateful_derivatives(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        let m = self.model;
        let left = t >= self.t_end;
        for &i in self.stateful {
            let (slot, block) = (&m.slots[i], &mut self.blocks[i]);
            let io = io_for(slot, t, left, x, self.signals, &m.in_ports, &m.out_ports).in_minor_step(block.frozen);
            block.derivatives(&io, &mut dx[slot.states.clone()]);
        }
        for integrator in self.integrands {
            integrator.derivatives(self.signals, dx);
        }
    }
}

impl Crossings for Minor<'_> {
    fn outputs(&mut self, t: f64, x: &[f64]) {
        Minor::outputs(self, t, x);
    }

    fn zero_crossings(&mut self, _b: usize, i: usize, t: f64, x: &[f64], g: &mut [f64]) {
        let (m, block) = (self.model, &self.blocks[i]);
        let io = io_for(&m.slots[i], t, t >= self.t_end, x, self.signals, &m.in_ports, &m.out_ports)
            .in_minor_step(block.frozen);
        block.zero_crossings(&io, g);
    }

    fn direction(&self, _b: usize, i: usize, k: usize) -> Crossing {
        self.blocks[i].crossing_direction(k)
    }
}

impl OdeSystem for Minor<'_> {
    fn derivatives(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        self.outputs(t, x);
        self.stateful_derivatives(t, x, dx);
    }

    /// At the step's start the major step has just computed every output
    /// at this (t, x), the plain integrators' too; only the stale ones are
    /// run again.
    fn derivatives_at_start(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        match self.at_start.take() {
            Some(stale) => self.run(stale, t, x),
            None => self.outputs(t, x),
        }
        self.stateful_derivatives(t, x, dx);
    }
}

/// The continuous visits whose outputs at a step's start, where the major
/// step has just computed them, may differ in the solver's first stage:
/// blocks with memory their `update` changes after the major step's
/// outputs (a clamped PID, a delay's history), blocks with modes or
/// zero crossings (frozen in minor steps), and every block that reads one
/// through a direct-feedthrough input, directly or not. The others would
/// compute the same values again: a block without `update` or zero
/// crossings computes its outputs from t, its states and its inputs alone
/// ([`crate::block::Block::updates`]).
pub(super) fn stale_at_start(model: &Model, continuous: &[Visit]) -> Vec<Visit> {
    // Inputs without direct feedthrough do not reach the outputs.
    let mut feeds = vec![true; model.in_ports.len()];
    for e in model.edges.iter().filter(|e| !e.feedthrough) {
        feeds[model.slots[e.dst].inputs.start + e.dst_port] = false;
    }
    // Marks spread in execution order, which every feedthrough edge follows.
    let mut stale = vec![false; model.signal_len];
    let mut runs = |v: &&Visit| {
        let (block, slot) = (&model.blocks[v.block], &model.slots[v.block]);
        let own = block.updates() || block.num_zero_crossings() > 0 || block.needs_major_step();
        let reads_stale = slot.inputs.clone().any(|k| {
            let p = model.in_ports[k];
            feeds[k] && stale[p.offset..p.offset + p.width].contains(&true)
        });
        if own || reads_stale {
            for p in &model.out_ports[slot.outputs.clone()] {
                stale[p.offset..p.offset + p.width].fill(true);
            }
        }
        own || reads_stale
    };
    continuous.iter().filter(&mut runs).copied().collect()
}
