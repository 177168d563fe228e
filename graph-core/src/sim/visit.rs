//! The sweeps' precomputed visits: which block, when it is due, and, for
//! blocks whose output the step loop computes in place from the [`Kernel`]
//! they name, that kernel (no call through a view); and the plain
//! integrators, whose outputs and derivatives the step loop copies.

use crate::block::Kernel;
use crate::compile::{Model, Rate};

/// One block's turn in a sweep, laid out once so the step loop reads a
/// list front to back instead of looking the block up in three tables.
#[derive(Clone, Copy, Debug)]
pub(super) struct Visit {
    pub(super) block: usize,
    pub(super) rate: Rate,
    /// Run in place of the block's `output`.
    pub(super) kernel: Option<Inline>,
}

impl Visit {
    /// Visits of `blocks`, in their order.
    pub(super) fn list(model: &Model, blocks: impl IntoIterator<Item = usize>) -> Vec<Visit> {
        let visit = |block| Visit { block, rate: model.slots[block].rate, kernel: Inline::of(model, block) };
        blocks.into_iter().map(visit).collect()
    }
}

/// A plain integrator ([`crate::block::Block::is_plain_integrator`]) whose
/// one input and one output are as wide as its states: the scheduler
/// copies its states to its output and its input to its derivatives, in
/// place of the two calls through a view that cost many times the copy.
/// Its output depends on its states alone, so a sweep copies it first and
/// leaves the block out of its visits.
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
        (u.width == width && y.width == width).then_some(Integrand {
            u: u.offset,
            y: y.offset,
            x: slot.states.start,
            width,
        })
    }

    /// y = x (`x` all states, or the solver's integrated part: the
    /// integrator's are in both at the same places).
    #[inline]
    pub(super) fn output(&self, x: &[f64], signals: &mut [f64]) {
        copy(x, self.x, signals, self.y, self.width);
    }

    /// ẋ = u.
    #[inline]
    pub(super) fn derivatives(&self, signals: &[f64], dx: &mut [f64]) {
        copy(signals, self.u, dx, self.x, self.width);
    }
}

/// `to[at..at + width] = from[start..start + width]`, a scalar (the usual
/// integrator) without the slice loop's set-up, which costs several times
/// the copy.
#[inline]
fn copy(from: &[f64], start: usize, to: &mut [f64], at: usize, width: usize) {
    if width == 1 {
        to[at] = from[start];
    } else {
        to[at..at + width].copy_from_slice(&from[start..start + width]);
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
