//! A graph's own inputs and outputs, for a program that drives it step by
//! step ([`crate::Simulator::set_input`], [`crate::Simulator::output`]):
//! a top-level `inport` is a value the host sets and that holds between
//! major steps (a zero-order hold, as an FMU's or Simulink's root inport);
//! a top-level `outport` names a signal the host reads.

use crate::block::{Block, Interface, Io, SampleTime, Width};
use crate::diag::Diagnostic;
use crate::params::Params;

/// A top-level inport: writes the value the host last set (or `value`).
#[derive(Clone)]
pub(crate) struct ExternalInput {
    value: Vec<f64>,
}

impl ExternalInput {
    /// Reads `width` (default 1) and `value` (the value before the host
    /// sets one, default 0, one number for every element).
    pub(crate) fn build(p: &mut Params) -> Result<(Interface, ExternalInput), Diagnostic> {
        let width = p.number_where(
            "width",
            Some(1.0),
            |w| (1.0..=1e6).contains(&w) && w.fract() == 0.0,
            "a whole number from 1",
        )?;
        let value = p.number_where("value", Some(0.0), f64::is_finite, "a finite number")?;
        // Piecewise constant: it changes only when the host sets it, between
        // major steps (the simulator then runs it at the next major step).
        let iface =
            Interface::new(SampleTime::Continuous).output("out", Width::Fixed(width as usize)).piecewise_constant();
        Ok((iface, ExternalInput { value: vec![value; width as usize] }))
    }
}

impl Block for ExternalInput {
    fn output(&mut self, io: &mut Io) {
        io.output(0).copy_from_slice(&self.value);
    }

    fn external_input(&mut self) -> Option<&mut [f64]> {
        Some(&mut self.value)
    }
}
