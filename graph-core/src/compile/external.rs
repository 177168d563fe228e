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

/// The names a host uses, resolved once against the model: the same
/// answers (and messages) for every back-end that runs it.
impl crate::Model {
    /// The graph's inputs (top-level `inport` blocks), in execution order.
    pub fn input_names(&self) -> impl Iterator<Item = &str> {
        self.external_inputs.iter().map(|(n, _)| n.as_str())
    }

    /// The graph's outputs (top-level `outport` blocks).
    pub fn output_names(&self) -> impl Iterator<Item = &str> {
        self.external_outputs.iter().map(|(n, _)| n.as_str())
    }

    /// The block behind input `name`, once `value` is checked to fit it:
    /// one finite number per element.
    pub fn host_input(&self, name: &str, value: &[f64]) -> Result<usize, Diagnostic> {
        let Some(&(_, block)) = self.external_inputs.iter().find(|(n, _)| n == name) else {
            return Err(Diagnostic::plain(format!("no input `{name}`")).suggest(name, self.input_names()).or_hint(
                if self.external_inputs.is_empty() {
                    "the graph has no inputs: add a top-level `inport` block".to_string()
                } else {
                    format!("inputs: {}", self.input_names().collect::<Vec<_>>().join(", "))
                },
            ));
        };
        let width = self.out_ports[self.slots[block].outputs.start].width;
        if width != value.len() {
            return Err(Diagnostic::plain(format!("input `{name}` has {width} element(s), given {}", value.len())));
        }
        match value.iter().find(|v| !v.is_finite()) {
            Some(bad) => Err(Diagnostic::plain(format!("input `{name}`: {bad} is not a finite number"))),
            None => Ok(block),
        }
    }

    /// Where output `name` (a top-level `outport`) is in the signal buffer.
    pub fn output_port(&self, name: &str) -> Result<crate::block::Port, Diagnostic> {
        self.external_output(name).ok_or_else(|| {
            Diagnostic::plain(format!("no output `{name}`"))
                .suggest(name, self.output_names())
                .or_hint("the graph's outputs are its top-level `outport` blocks")
        })
    }

    fn external_output(&self, name: &str) -> Option<crate::block::Port> {
        self.external_outputs.iter().find(|(n, _)| n == name).map(|(_, port)| *port)
    }

    /// Where any signal a host may read is: a recorded name, an output,
    /// `block`, `block.port`, `sub.port` of a subsystem, with `[k]` for
    /// one element ([`crate::Model::signal_port`]).
    pub fn host_signal_port(&self, name: &str) -> Result<crate::block::Port, Diagnostic> {
        if let Some(c) = self.columns.iter().find(|c| c.name == name) {
            return Ok(crate::block::Port { offset: c.offset, width: c.width });
        }
        match self.external_output(name) {
            Some(port) => Ok(port),
            None => self.signal_port(name),
        }
    }
}
