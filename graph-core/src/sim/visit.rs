//! The sweeps' precomputed visits: which block, when it is due, and how
//! its output is computed — through a view and a dynamic call, or in
//! place for the blocks that name a [`Kernel`] and for plain integrators.

use crate::block::Kernel;
use crate::compile::{Model, Rate};

/// One block's turn in a sweep, laid out once so the step loop reads a
/// list front to back instead of looking the block up in three tables.
#[derive(Clone, Copy, Debug)]
pub(super) struct Visit {
    pub(super) block: usize,
    pub(super) rate: Rate,
    pub(super) run: Run,
}

impl Visit {
    /// Visits of `blocks`, in their order.
    pub(super) fn list(model: &Model, blocks: impl IntoIterator<Item = usize>) -> Vec<Visit> {
        let visit = |block| Visit { block, rate: model.slots[block].rate, run: Run::of(model, block) };
        blocks.into_iter().map(visit).collect()
    }
}

/// How a visit computes the block's outputs.
#[derive(Clone, Copy, Debug)]
pub(super) enum Run {
    /// The block's `output`, through a view.
    Call,
    /// The block's kernel, on the signal buffer.
    Kernel(Inline),
    /// A plain integrator's y = x: its states copied to its output.
    States(Integrand),
}

impl Run {
    fn of(model: &Model, block: usize) -> Run {
        match (Inline::of(model, block), Integrand::of(model, block)) {
            (Some(kernel), _) => Run::Kernel(kernel),
            (None, Some(integrand)) => Run::States(integrand),
            (None, None) => Run::Call,
        }
    }
}

/// A plain integrator ([`crate::block::Block::is_plain_integrator`]) whose
/// one input and one output are as wide as its states: the scheduler
/// copies its states to its output and its input to its derivatives, in
/// place of the two calls through a view that cost many times the copy.
#[derive(Clone, Copy, Debug)]
pub(super) struct Integrand {
    u: usize,
    y: usize,
    x: usize,
    width: usize,
}

impl Integrand {
    pub(super) fn of(model: &Model, i: usize) -> Option<Integrand> {
        if !model.blocks[i].is_plain_integrator() {
            return None;
        }
        let slot = &model.slots[i];
        let width = slot.states.len();
        let (ins, outs) = (&model.in_ports[slot.inputs.clone()], &model.out_ports[slot.outputs.clone()]);
        let ([u], [y]) = (ins, outs) else { return None };
        (u.width == width && y.width == width).then_some(Integrand { u: u.offset, y: y.offset, x: slot.states.start, width })
    }

    /// y = x (`x` all states, or the solver's integrated part: the
    /// integrator's are in both at the same places).
    #[inline]
    pub(super) fn output(&self, x: &[f64], signals: &mut [f64]) {
        let (x, y) = (&x[self.x..self.x + self.width], &mut signals[self.y..self.y + self.width]);
        // An element loop: for a few values cheaper than copy_from_slice's memmove.
        for (y, &x) in y.iter_mut().zip(x) {
            *y = x;
        }
    }

    /// ẋ = u.
    #[inline]
    pub(super) fn derivatives(&self, signals: &[f64], dx: &mut [f64]) {
        for (d, &u) in dx[self.x..self.x + self.width].iter_mut().zip(&signals[self.u..self.u + self.width]) {
            *d = u;
        }
    }
}

/// A block whose output the step loop computes in place: its
/// [`Kernel`] and where its inputs and output are in the signal buffer.
/// Worth it for the small blocks (sums, gains, demuxes) that make up much
/// of a diagram: a call through a view costs several times their arithmetic.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Inline {
    pub(crate) kernel: Kernel,
    pub(crate) u0: usize,
    pub(crate) u1: usize,
    pub(crate) y: usize,
    /// Elements copied (`Kernel::Copy`).
    pub(crate) width: usize,
}

impl Inline {
    /// Block `i`'s kernel, when it has one and its ports suit it: all
    /// scalar for a scalar kernel; for `Copy` one input, as wide as the
    /// outputs, which lie end to end.
    pub(crate) fn of(model: &Model, i: usize) -> Option<Inline> {
        let kernel = model.blocks[i].kernel()?;
        let slot = &model.slots[i];
        let (ins, outs) = (&model.in_ports[slot.inputs.clone()], &model.out_ports[slot.outputs.clone()]);
        let (first, last) = (ins.first()?, ins.last()?);
        let y = outs.first()?.offset;
        let width = outs.iter().map(|p| p.width).sum::<usize>();
        let suits = match kernel {
            Kernel::Copy => {
                let end_to_end = outs.windows(2).all(|w| w[1].offset == w[0].offset + w[0].width);
                ins.len() == 1 && first.width == width && end_to_end
            }
            _ => {
                let scalar = ins.iter().chain(outs).all(|p| p.width == 1);
                scalar && ins.len() == kernel.arity() && outs.len() == 1
            }
        };
        suits.then_some(Inline { kernel, u0: first.offset, u1: last.offset, y, width })
    }

    #[inline]
    pub(super) fn run(&self, signals: &mut [f64]) {
        match self.kernel {
            Kernel::Copy => signals.copy_within(self.u0..self.u0 + self.width, self.y),
            kernel => signals[self.y] = kernel.eval(signals[self.u0], signals[self.u1]),
        }
    }
}
