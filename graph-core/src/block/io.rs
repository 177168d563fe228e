//! A block's view of the run for one call ([`Io`]).

use super::Port;

/// A block's window on the simulation: time, its continuous states, its
/// inputs and outputs. Built by the simulator for each call; holds only
/// borrowed slices.
pub struct Io<'a> {
    /// Simulation time.
    pub t: f64,
    /// This block's continuous states (empty for blocks without any).
    pub x: &'a [f64],
    left_limit: bool,
    major: bool,
    frozen: bool,
    signals: &'a mut [f64],
    inputs: &'a [Port],
    outputs: &'a [Port],
}

impl<'a> Io<'a> {
    pub fn new(
        t: f64,
        left_limit: bool,
        x: &'a [f64],
        signals: &'a mut [f64],
        inputs: &'a [Port],
        outputs: &'a [Port],
    ) -> Self {
        Io { t, x, left_limit, major: true, frozen: false, signals, inputs, outputs }
    }

    /// Marks the call as a solver stage (minor step), with the block's
    /// modes frozen when its zero crossings are watched.
    pub fn in_minor_step(mut self, frozen: bool) -> Self {
        self.major = false;
        self.frozen = frozen;
        self
    }

    /// Whether this is a major step (the pass whose outputs are recorded),
    /// not a solver stage.
    #[inline]
    pub fn is_major(&self) -> bool {
        self.major
    }

    /// Whether `t` is seen as a left limit: the solver's last stage at the
    /// end of a step, or a [`super::Block::left_limit`] call.
    #[inline]
    pub fn is_left_limit(&self) -> bool {
        self.left_limit
    }

    /// Whether a block with modes may switch mode now: at major steps, and
    /// at every evaluation when zero-crossing detection is off (the block
    /// then acts as a plain function). False in the solver's minor steps
    /// under detection: the mode chosen at the last major step holds.
    #[inline]
    pub fn may_switch(&self) -> bool {
        !self.frozen
    }

    /// All elements of input `port`.
    #[inline]
    pub fn input(&self, port: usize) -> &[f64] {
        let p = self.inputs[port];
        &self.signals[p.offset..p.offset + p.width]
    }

    /// The first (for scalars: the only) element of input `port`.
    #[inline]
    pub fn u(&self, port: usize) -> f64 {
        self.signals[self.inputs[port].offset]
    }

    /// Element `k` of input `port`, broadcasting a scalar input.
    #[inline]
    pub fn u_at(&self, port: usize, k: usize) -> f64 {
        let p = self.inputs[port];
        self.signals[p.offset + if p.width == 1 { 0 } else { k }]
    }

    pub fn num_inputs(&self) -> usize {
        self.inputs.len()
    }

    #[inline]
    pub fn input_width(&self, port: usize) -> usize {
        self.inputs[port].width
    }

    /// All elements of output `port`, to write.
    #[inline]
    pub fn output(&mut self, port: usize) -> &mut [f64] {
        let p = self.outputs[port];
        &mut self.signals[p.offset..p.offset + p.width]
    }

    /// Sets the first (for scalars: the only) element of output `port`.
    #[inline]
    pub fn set(&mut self, port: usize, value: f64) {
        self.signals[self.outputs[port].offset] = value;
    }

    /// Writes all elements of output `port` (an element loop: for the few
    /// values of a port it is cheaper than `copy_from_slice`'s memmove).
    #[inline]
    pub fn set_all(&mut self, port: usize, values: &[f64]) {
        let out = self.output(port);
        // Counted by the port's width, which a generated step knows: a
        // few moves, where counting by the shorter of the two is a call
        // to memcpy.
        match values.get(..out.len()) {
            Some(values) => out.iter_mut().zip(values).for_each(|(o, &v)| *o = v),
            None => set_leading(out, values),
        }
    }

    /// Sets element `k` of output `port`.
    #[inline]
    pub fn set_at(&mut self, port: usize, k: usize, value: f64) {
        self.signals[self.outputs[port].offset + k] = value;
    }

    pub fn num_outputs(&self) -> usize {
        self.outputs.len()
    }

    /// The width of output `port`. Like every part of the view's
    /// structure (port widths, `x.len()`), a constant in a generated step
    /// once the block's method is inlined there: a block that branches on
    /// these rather than on its own fields has the branch removed.
    #[inline]
    pub fn output_width(&self, port: usize) -> usize {
        self.outputs[port].width
    }

    /// Whether time has reached `t_event`. At the end of an integration
    /// interval that lands on an event, the solver's last stage sees the
    /// left limit (not yet reached); the major step at the event sees it
    /// reached. Sources with discontinuities (step, pulse) use this so that
    /// the jump falls exactly between two steps.
    #[inline]
    pub fn reached(&self, t_event: f64) -> bool {
        self.t > t_event || (self.t == t_event && !self.left_limit)
    }
}

/// The first elements of `out` from `values`, shorter than it: out of line,
/// so that [`Io::set_all`]'s copy of a whole port stays a copy of a known
/// length.
#[cold]
#[inline(never)]
fn set_leading(out: &mut [f64], values: &[f64]) {
    out.iter_mut().zip(values).for_each(|(o, &v)| *o = v);
}

#[cfg(test)]
mod tests {
    use super::{Io, Port};

    /// A whole port is written from values of its width (or longer); from
    /// fewer values, their count of leading elements, the rest untouched.
    #[test]
    fn set_all_writes_the_port_from_the_values_it_is_given() {
        let outputs = [Port { offset: 1, width: 3 }];
        let mut signals = [9.0; 5];
        Io::new(0.0, false, &[], &mut signals, &[], &outputs).set_all(0, &[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(signals, [9.0, 1.0, 2.0, 3.0, 9.0]);
        Io::new(0.0, false, &[], &mut signals, &[], &outputs).set_all(0, &[5.0]);
        assert_eq!(signals, [9.0, 5.0, 2.0, 3.0, 9.0]);
    }
}
