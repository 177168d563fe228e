//! The system the ODE solver integrates between major steps: continuous
//! outputs recomputed at each stage, discrete outputs held.

use super::io_for;
use super::visit::Visit;
use crate::compile::Model;
use ctlgraph_solver::OdeSystem;

/// The ODE the solver sees: set states, recompute continuous outputs (modes
/// frozen where zero crossings are watched), ask stateful blocks for
/// derivatives. Discrete outputs hold.
pub(super) struct Minor<'a> {
    pub(super) model: &'a mut Model,
    pub(super) signals: &'a mut [f64],
    pub(super) continuous: &'a [Visit],
    pub(super) stateful: &'a [usize],
    pub(super) t_end: f64,
}

impl Minor<'_> {
    /// Continuous outputs at (t, x), modes frozen.
    pub(super) fn outputs(&mut self, t: f64, x: &[f64]) {
        let m = &mut *self.model;
        let left = t >= self.t_end;
        for v in self.continuous {
            if let Some(kernel) = &v.kernel {
                kernel.run(self.signals);
                continue;
            }
            let meta = &m.slots[v.block];
            let mut io = io_for(meta, t, left, x, self.signals, &m.in_ports, &m.out_ports).in_minor_step(meta.frozen);
            m.blocks[v.block].output(&mut io);
        }
    }

    /// Block `i`'s zero-crossing functions at (t, x), outputs computed.
    pub(super) fn zero_crossings(&mut self, i: usize, t: f64, x: &[f64], g: &mut [f64]) {
        let m = &mut *self.model;
        let meta = &m.slots[i];
        let io =
            io_for(meta, t, t >= self.t_end, x, self.signals, &m.in_ports, &m.out_ports).in_minor_step(meta.frozen);
        m.blocks[i].zero_crossings(&io, g);
    }
}

impl OdeSystem for Minor<'_> {
    fn derivatives(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        self.outputs(t, x);
        let m = &mut *self.model;
        let left = t >= self.t_end;
        for &i in self.stateful {
            let meta = &m.slots[i];
            let io = io_for(meta, t, left, x, self.signals, &m.in_ports, &m.out_ports).in_minor_step(meta.frozen);
            m.blocks[i].derivatives(&io, &mut dx[meta.states.clone()]);
        }
    }
}
