//! A graph driven step by step from a program (set an input, advance to
//! a time, read an output, save and rewind), by either back-end: the
//! interpreter ([`Simulator`]) or the graph's step library
//! ([`AcceleratedRun`]). Names are resolved against the program's own
//! compiled model ([`Model::host_input`], [`Model::host_signal_port`]),
//! so both answer a wrong name with the same message, and the library is
//! handed block indices and buffers only.

use super::{AcceleratedRun, AcceleratedSnapshot, Runner};
use ctlgraph_core::block::Port;
use ctlgraph_core::{Diagnostic, Model, SimError, Simulator, Snapshot};
use std::sync::Arc;

/// A graph being stepped, interpreted or accelerated.
pub struct Stepper {
    model: Arc<Model>,
    engine: Engine,
}

enum Engine {
    Interpreted(Box<Simulator>),
    Accelerated(AcceleratedRun),
}

/// A [`Stepper`] at one instant, to return to with [`Stepper::restore`].
pub enum StepperSnapshot {
    Interpreted(Box<Snapshot>),
    Accelerated(AcceleratedSnapshot),
}

impl StepperSnapshot {
    /// The time it was taken at.
    pub fn time(&self) -> f64 {
        match self {
            StepperSnapshot::Interpreted(s) => s.time(),
            StepperSnapshot::Accelerated(s) => s.time(),
        }
    }
}

impl Stepper {
    /// Steps `model` (compiled from the graph with `sets` and `seed`) in
    /// `runner`'s library when it has one, else interpreted. `Err` when the
    /// library cannot make the run (an override that changes the structure).
    pub fn new(runner: &Runner, model: Model, sets: &[(String, String)], seed: Option<u64>) -> Result<Self, String> {
        let model = Arc::new(model);
        let engine = match runner.start(sets, seed, None)? {
            Some(run) => Engine::Accelerated(run),
            None => Engine::Interpreted(Box::new(Simulator::new(Arc::clone(&model), None))),
        };
        Ok(Stepper { model, engine })
    }

    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Whether the steps run in the graph's step library.
    pub fn accelerated(&self) -> bool {
        matches!(self.engine, Engine::Accelerated(_))
    }

    /// The present time.
    pub fn time(&self) -> f64 {
        match &self.engine {
            Engine::Interpreted(sim) => sim.time(),
            Engine::Accelerated(run) => run.time(),
        }
    }

    /// [`Simulator::set_input`].
    pub fn set_input(&mut self, name: &str, value: &[f64]) -> Result<(), Diagnostic> {
        match &mut self.engine {
            Engine::Interpreted(sim) => sim.set_input(name, value),
            Engine::Accelerated(run) => {
                let block = self.model.host_input(name, value)?;
                run.set_input(block, value).map_err(Diagnostic::plain)
            }
        }
    }

    /// [`Simulator::advance_to`].
    pub fn advance_to(&mut self, t: f64) -> Result<(), SimError> {
        match &mut self.engine {
            Engine::Interpreted(sim) => sim.advance_to(t),
            Engine::Accelerated(run) => run.advance_to(t),
        }
    }

    /// [`Simulator::output`].
    pub fn output(&mut self, name: &str) -> Result<&[f64], Diagnostic> {
        let port = self.model.output_port(name)?;
        self.port_now(port)
    }

    /// [`Simulator::signal`].
    pub fn signal(&mut self, name: &str) -> Result<&[f64], Diagnostic> {
        let port = self.model.host_signal_port(name)?;
        self.port_now(port)
    }

    /// The values on `port` at the present time, outputs computed.
    fn port_now(&mut self, port: Port) -> Result<&[f64], Diagnostic> {
        let signals = match &mut self.engine {
            Engine::Interpreted(sim) => sim.signals_now(),
            Engine::Accelerated(run) => run.signals_now(),
        }
        .map_err(|e| Diagnostic::plain(e.to_string()))?;
        Ok(&signals[port.offset..port.offset + port.width])
    }

    /// [`Simulator::state`].
    pub fn state(&self) -> Result<StepperSnapshot, Diagnostic> {
        match &self.engine {
            Engine::Interpreted(sim) => Ok(StepperSnapshot::Interpreted(Box::new(sim.state()))),
            Engine::Accelerated(run) => run.state().map(StepperSnapshot::Accelerated).map_err(Diagnostic::plain),
        }
    }

    /// [`Simulator::restore`].
    pub fn restore(&mut self, snapshot: &StepperSnapshot) -> Result<(), Diagnostic> {
        match (&mut self.engine, snapshot) {
            (Engine::Interpreted(sim), StepperSnapshot::Interpreted(s)) => sim.restore(s),
            (Engine::Accelerated(run), StepperSnapshot::Accelerated(s)) => {
                run.restore(s).map_err(|why| Diagnostic::plain(why).with_hint(RESTORE_HINT))
            }
            _ => Err(Diagnostic::plain("the snapshot was taken of another run").with_hint(RESTORE_HINT)),
        }
    }
}

const RESTORE_HINT: &str = "restore a snapshot into the model whose `state()` made it";
