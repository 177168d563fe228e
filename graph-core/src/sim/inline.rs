//! Blocks whose output the step loop computes in place, from the
//! [`Kernel`] they name, instead of calling them through a view.

use crate::block::Kernel;
use crate::compile::Model;

/// A block whose output the step loop computes in place: its
/// [`Kernel`] and where its scalar inputs and output are in the signal
/// buffer. Worth it for the small blocks (sums, gains) that make up much of
/// a diagram: a call through a view costs several times their arithmetic.
#[derive(Clone, Copy, Debug)]
pub(super) struct Inline {
    kernel: Kernel,
    u0: usize,
    u1: usize,
    y: usize,
}

impl Inline {
    /// Block `i`'s kernel, when it has one and its ports are scalar.
    pub(super) fn of(model: &Model, i: usize) -> Option<Inline> {
        let kernel = model.blocks[i].kernel()?;
        let slot = &model.slots[i];
        let (ins, outs) = (&model.in_ports[slot.inputs.clone()], &model.out_ports[slot.outputs.clone()]);
        let scalar = ins.iter().chain(outs).all(|p| p.width == 1);
        (scalar && ins.len() == kernel.arity() && outs.len() == 1).then(|| Inline {
            kernel,
            u0: ins[0].offset,
            u1: ins[ins.len() - 1].offset,
            y: outs[0].offset,
        })
    }

    #[inline]
    pub(super) fn run(&self, signals: &mut [f64]) {
        signals[self.y] = self.kernel.eval(signals[self.u0], signals[self.u1]);
    }
}
