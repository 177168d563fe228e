//! The sweeps' precomputed visits: which block, when it is due, and, for
//! blocks whose output the step loop computes in place from the [`Kernel`]
//! they name, that kernel (no call through a view); and the plain
//! integrators, whose outputs and derivatives the step loop copies.

use crate::block::{Kernel, TimeOnly};
use crate::compile::{Model, Rate};

/// One block's turn in a sweep, laid out once so the step loop reads a
/// list front to back instead of looking the block up in three tables.
#[derive(Clone, Copy, Debug)]
pub(super) struct Visit {
    pub(super) block: usize,
    pub(super) rate: Rate,
    /// Run in place of the block's `output`.
    pub(super) kernel: Option<Inline>,
    /// [`crate::block::Block::time_only`].
    pub(super) time_only: Option<TimeOnly>,
}

impl Visit {
    /// Visits of `blocks`, in their order.
    pub(super) fn list(model: &Model, blocks: impl IntoIterator<Item = usize>) -> Vec<Visit> {
        let visit = |block| Visit {
            block,
            rate: model.slots[block].rate,
            kernel: Inline::of(model, block),
            time_only: model.blocks[block].time_only(),
        };
        blocks.into_iter().map(visit).collect()
    }
}

/// Runs `visits` in order: kernels in place on `signals` (a run of them in
/// one loop, [`Inline::run_from`]), and every other visit `due` says
/// through `call`. The major step's sweep and the solver's stages share it.
#[inline(always)]
pub(super) fn sweep(
    visits: &[Visit],
    signals: &mut [f64],
    due: impl Fn(&Visit) -> bool,
    mut call: impl FnMut(&Visit, &mut [f64]),
) {
    let mut rest = visits;
    while let [v, after @ ..] = rest {
        if v.kernel.is_some() {
            rest = Inline::run_from(rest, signals, &due);
            continue;
        }
        rest = after;
        if due(v) {
            call(v, signals);
        }
    }
}

/// When each time-only block ([`crate::block::Block::time_only`]) last
/// computed its outputs, which stand in the signal buffer until it runs
/// again: the time's bits, and whether it was taken as a left limit (for
/// a sided block). Asked again there, the sweeps skip the block: no view
/// to build, no call.
#[derive(Clone, Debug)]
pub(super) struct ComputedAt(Vec<(u64, bool)>);

impl ComputedAt {
    /// No time's bits are NaN's.
    const NEVER: (u64, bool) = (u64::MAX, false);

    pub(super) fn new(blocks: usize) -> Self {
        ComputedAt(vec![Self::NEVER; blocks])
    }

    /// After the signals or the blocks changed other than by a sweep.
    pub(super) fn forget(&mut self) {
        self.0.fill(Self::NEVER);
    }

    /// Whether `v` must run at `t` (seen as a left limit if `left`): not
    /// when it is time-only and last ran there. Records the time when it
    /// runs.
    #[inline(always)]
    pub(super) fn must_run(&mut self, v: &Visit, t: f64, left: bool) -> bool {
        let Some(kind) = v.time_only else { return true };
        let key = (t.to_bits(), kind == TimeOnly::JumpsAtEvents && left);
        let last = &mut self.0[v.block];
        if *last == key {
            return false;
        }
        *last = key;
        true
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

    /// Runs the kernel of `visits[0]` (when `due` says), or, when a kernel
    /// follows it, the run of kernels from it ([`Inline::run_all`], a call
    /// that pays off from two kernels on); returns the visits after.
    #[inline(always)]
    fn run_from<'v>(visits: &'v [Visit], signals: &mut [f64], due: impl Fn(&Visit) -> bool) -> &'v [Visit] {
        match visits {
            [_, next, ..] if next.kernel.is_some() => &visits[Self::run_all(visits, signals, due)..],
            [v, after @ ..] => {
                if let Some(k) = &v.kernel
                    && due(v)
                {
                    k.run(signals);
                }
                after
            }
            [] => visits,
        }
    }

    /// The kernel on the buffer, its inputs read from it.
    #[inline(always)]
    fn run(&self, signals: &mut [f64]) {
        match self.kernel {
            Kernel::Copy => signals.copy_within(self.u0..self.u0 + self.width, self.y),
            kernel => signals[self.y] = kernel.eval(signals[self.u0], signals[self.u1]),
        }
    }

    /// Runs the kernels of `visits` from the first, up to the first visit
    /// without one (those `due` says; the others keep their outputs), and
    /// returns how many visits it passed.
    ///
    /// The last scalar output stays in a register for the next kernel: in a
    /// chain of small blocks each reads what the one before has just
    /// written, and reading it back from the signal buffer puts a
    /// store-to-load forwarding (a dozen cycles) on every link of the chain
    /// — twice the kernel's own cost. Every signal has one writer, so the
    /// value is the buffer's until the run ends.
    #[inline]
    fn run_all(visits: &[Visit], signals: &mut [f64], due: impl Fn(&Visit) -> bool) -> usize {
        let (mut at, mut last) = (usize::MAX, 0.0);
        for (i, v) in visits.iter().enumerate() {
            let Some(k) = &v.kernel else { return i };
            if !due(v) {
                continue;
            }
            if let Kernel::Copy = k.kernel {
                k.run(signals);
                // Nothing carried over the copy (a call), so nothing to spill.
                (at, last) = (usize::MAX, 0.0);
                continue;
            }
            let read = |u: usize| if u == at { last } else { signals[u] };
            // A gain reads one input (u1 is u0's copy), not two.
            last = match k.kernel {
                Kernel::Scale(_) => k.kernel.eval(read(k.u0), 0.0),
                _ => k.kernel.eval(read(k.u0), read(k.u1)),
            };
            signals[k.y] = last;
            at = k.y;
        }
        visits.len()
    }
}
