//! The sweeps' precomputed visits: which block, when it is due, and, for
//! blocks whose output the step loop computes in place from the [`Kernel`]
//! they name, that kernel (no call through a view).

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
