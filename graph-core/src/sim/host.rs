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

use super::{RunState, SimError, Simulator, Sweeps};
use crate::block::Breakpoint;
use crate::diag::Diagnostic;

/// A run's complete state at one instant, to return to with
/// [`Simulator::restore`]: the [`RunState`] itself.
pub type Snapshot = RunState;

/// Sets the value of input block `block` (checked by
/// [`crate::Model::host_input`]) from now on. The outputs at this time,
/// with the input before, are a left limit for the blocks keeping
/// history; every block runs at the next output sweep.
pub(crate) fn set_input(s: &mut impl Sweeps, block: usize, value: &[f64]) {
    let c = s.clockwork();
    if !c.first && !c.inputs_changed {
        s.left_limits(Breakpoint { generation: 0, sample_hit_only: false });
        // As after the driver's left limits: updates may schedule events.
        s.clockwork_mut().events_may_change = true;
    }
    if let Some(held) = s.external_input(block) {
        held.copy_from_slice(value);
    }
    s.clockwork_mut().inputs_changed = true;
}

/// Computes the outputs at the present time if nothing has yet, or an
/// input changed since.
pub(crate) fn refresh(s: &mut impl Sweeps) -> Result<(), SimError> {
    let c = s.clockwork();
    if c.first || c.inputs_changed { super::driver::outputs(s) } else { Ok(()) }
}

/// Simulates up to time `t` and stops exactly there (outputs computed
/// at `t`). `t` may lie beyond the stop time, which then moves to `t`;
/// a time before the present is an error.
pub(crate) fn advance_to(s: &mut impl Sweeps, t: f64) -> Result<(), SimError> {
    let c = s.clockwork_mut();
    if !t.is_finite() || t < c.t - c.tol {
        return Err(SimError::Host(format!("cannot advance to t = {t} from t = {}", c.t)));
    }
    c.stop = c.stop.max(t);
    refresh(s)?;
    s.clockwork_mut().pause = t;
    let mut result = Ok(());
    while result.is_ok() && s.clockwork().t < t - s.clockwork().tol {
        result = super::driver::advance(s).and_then(|()| super::driver::outputs(s));
    }
    s.clockwork_mut().pause = f64::INFINITY;
    result
}

impl Simulator {
    /// The graph's inputs (top-level `inport` blocks), in execution order.
    pub fn input_names(&self) -> impl Iterator<Item = &str> {
        self.model.input_names()
    }

    /// The graph's outputs (top-level `outport` blocks).
    pub fn output_names(&self) -> impl Iterator<Item = &str> {
        self.model.output_names()
    }

    /// Sets input `name` (one number per element) from now on: it holds
    /// until set again. The outputs at the present time are recomputed
    /// with it before anything reads them ([`Simulator::output`],
    /// [`Simulator::signal`]) or the run moves on ([`Simulator::advance_to`]),
    /// so a host can set a measurement and read the command it gives at
    /// the same instant.
    pub fn set_input(&mut self, name: &str, value: &[f64]) -> Result<(), Diagnostic> {
        let block = self.model.host_input(name, value)?;
        set_input(self, block, value);
        Ok(())
    }

    /// Simulates up to time `t` and stops exactly there (outputs computed
    /// at `t`). `t` may lie beyond the graph's stop time, which then moves
    /// to `t`; a time before the present is an error.
    pub fn advance_to(&mut self, t: f64) -> Result<(), SimError> {
        advance_to(self, t)
    }

    /// The present value of output `name` (a top-level `outport`).
    pub fn output(&mut self, name: &str) -> Result<&[f64], Diagnostic> {
        let port = self.model.output_port(name)?;
        self.port_now(port)
    }

    /// The present value of any signal: a recorded name, `block`,
    /// `block.port`, `sub.port` of a subsystem, with `[k]` for one element.
    pub fn signal(&mut self, name: &str) -> Result<&[f64], Diagnostic> {
        let port = self.model.host_signal_port(name)?;
        self.port_now(port)
    }

    /// The values on `port` at the present time.
    fn port_now(&mut self, port: crate::block::Port) -> Result<&[f64], Diagnostic> {
        let signals = self.signals_now().map_err(|e| Diagnostic::plain(e.to_string()))?;
        Ok(&signals[port.offset..port.offset + port.width])
    }

    /// The whole signal buffer at the present time (outputs computed if
    /// they are not): for a host that maps its own variables to offsets
    /// once (an FMU's value references) rather than naming a signal at
    /// every read.
    pub fn signals_now(&mut self) -> Result<&[f64], SimError> {
        refresh(self)?;
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
