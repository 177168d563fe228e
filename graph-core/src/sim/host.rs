//! Driving a simulation from a program, step by step: set the graph's
//! inputs (its top-level `inport` blocks), advance to a time, read its
//! outputs (top-level `outport` blocks) or any named signal — for
//! co-simulation, hardware-in-the-loop and real-time use.
//!
//! Stepping is the run loop cut into pieces: `advance_to` takes the same
//! major steps `run` would, plus one landing exactly on the requested
//! time when no step of the run's own falls there (within the simulator's
//! time tolerance). So with a fixed-step method and landing times on its
//! grid, stepping in chunks gives the same numbers as one run, bit for bit.
//! An adaptive method's steps are cut at each landing time, which changes
//! them (within the tolerances).

use super::{RunState, SimError, Simulator};
use crate::diag::Diagnostic;

/// A run's complete state at one instant, to return to with
/// [`Simulator::restore`]: the [`RunState`] itself.
pub type Snapshot = RunState;

impl Simulator {
    /// The graph's inputs (top-level `inport` blocks), in execution order.
    pub fn input_names(&self) -> impl Iterator<Item = &str> {
        self.model.external_inputs.iter().map(|(n, _)| n.as_str())
    }

    /// The graph's outputs (top-level `outport` blocks).
    pub fn output_names(&self) -> impl Iterator<Item = &str> {
        self.model.external_outputs.iter().map(|(n, _)| n.as_str())
    }

    /// Sets input `name` (one number per element) from now on: it holds
    /// until set again. The outputs at the present time are recomputed
    /// with it before anything reads them ([`Simulator::output`],
    /// [`Simulator::signal`]) or the run moves on ([`Simulator::advance_to`]),
    /// so a host can set a measurement and read the command it gives at
    /// the same instant.
    pub fn set_input(&mut self, name: &str, value: &[f64]) -> Result<(), Diagnostic> {
        let Some(&(_, block)) = self.model.external_inputs.iter().find(|(n, _)| n == name) else {
            return Err(Diagnostic::plain(format!("no input `{name}`")).suggest(name, self.input_names()).or_hint(
                if self.model.external_inputs.is_empty() {
                    "the graph has no inputs: add a top-level `inport` block".to_string()
                } else {
                    format!("inputs: {}", self.input_names().collect::<Vec<_>>().join(", "))
                },
            ));
        };
        let Some(width) = self.state.blocks[block].external_input().map(|held| held.len()) else {
            return Err(Diagnostic::plain(format!("input `{name}` holds no value (internal error)")));
        };
        if width != value.len() {
            return Err(Diagnostic::plain(format!("input `{name}` has {width} element(s), given {}", value.len())));
        }
        if let Some(bad) = value.iter().find(|v| !v.is_finite()) {
            return Err(Diagnostic::plain(format!("input `{name}`: {bad} is not a finite number")));
        }
        if !self.state.clockwork.first && !self.state.inputs_changed {
            // The outputs at this time, with the input before, are its left limit.
            self.hand_left_limits(crate::block::Breakpoint { generation: 0, sample_hit_only: false });
            // As after the driver's left limits: updates may schedule events.
            self.state.clockwork.events_may_change = true;
        }
        if let Some(held) = self.state.blocks[block].external_input() {
            held.copy_from_slice(value);
        }
        self.state.inputs_changed = true;
        Ok(())
    }

    /// Simulates up to time `t` and stops exactly there (outputs computed
    /// at `t`). `t` may lie beyond the graph's stop time, which then moves
    /// to `t`; a time before the present is an error.
    pub fn advance_to(&mut self, t: f64) -> Result<(), SimError> {
        let c = &mut self.state.clockwork;
        if !t.is_finite() || t < c.t - c.tol {
            return Err(SimError::Host(format!("cannot advance to t = {t} from t = {}", c.t)));
        }
        c.stop = c.stop.max(t);
        self.refresh()?;
        self.state.clockwork.pause = t;
        let result = self.advance_to_pause(t);
        self.state.clockwork.pause = f64::INFINITY;
        result
    }

    /// Computes the outputs at the present time if nothing has yet, or an
    /// input changed since.
    fn refresh(&mut self) -> Result<(), SimError> {
        if self.state.clockwork.first || self.state.inputs_changed {
            self.outputs()?;
        }
        Ok(())
    }

    fn advance_to_pause(&mut self, t: f64) -> Result<(), SimError> {
        while self.state.clockwork.t < t - self.state.clockwork.tol {
            self.advance()?;
            self.outputs()?;
        }
        Ok(())
    }

    /// The present value of output `name` (a top-level `outport`).
    pub fn output(&mut self, name: &str) -> Result<&[f64], Diagnostic> {
        self.refresh().map_err(|e| Diagnostic::plain(e.to_string()))?;
        let Some(port) = self.external_output(name) else {
            return Err(Diagnostic::plain(format!("no output `{name}`"))
                .suggest(name, self.output_names())
                .or_hint("the graph's outputs are its top-level `outport` blocks"));
        };
        Ok(&self.state.signals[port.offset..port.offset + port.width])
    }

    fn external_output(&self, name: &str) -> Option<crate::block::Port> {
        self.model.external_outputs.iter().find(|(n, _)| n == name).map(|(_, port)| *port)
    }

    /// The present value of any signal: a recorded name, `block`,
    /// `block.port`, `sub.port` of a subsystem, with `[k]` for one element.
    pub fn signal(&mut self, name: &str) -> Result<&[f64], Diagnostic> {
        self.refresh().map_err(|e| Diagnostic::plain(e.to_string()))?;
        let recorded = self.model.columns.iter().find(|c| c.name == name);
        let port = match recorded.map(|c| crate::block::Port { offset: c.offset, width: c.width }) {
            Some(port) => port,
            None => match self.external_output(name) {
                Some(port) => port,
                None => self.model.signal_port(name)?,
            },
        };
        Ok(&self.state.signals[port.offset..port.offset + port.width])
    }

    /// The whole signal buffer at the present time (outputs computed if
    /// they are not): for a host that maps its own variables to offsets
    /// once (an FMU's value references) rather than naming a signal at
    /// every read.
    pub fn signals_now(&mut self) -> Result<&[f64], SimError> {
        self.refresh()?;
        Ok(&self.state.signals)
    }

    /// The run as it stands, to return to later ([`Simulator::restore`]):
    /// a clone of its [`RunState`], every block's memory included, so take
    /// it at the moments to come back to rather than at every step.
    pub fn state(&self) -> Snapshot {
        self.state.clone()
    }

    /// Returns the run to `snapshot`, taken of this simulator.
    pub fn restore(&mut self, snapshot: &Snapshot) -> Result<(), Diagnostic> {
        if snapshot.owner != self.state.owner {
            return Err(Diagnostic::plain("the snapshot was taken of another simulator")
                .with_hint("restore a snapshot into the simulator whose `state()` made it"));
        }
        self.state.clone_from(snapshot);
        self.outputs_current = false;
        self.computed_at.forget();
        Ok(())
    }
}
