//! `mode: me`: a model-exchange FMU as a continuous block. Its continuous
//! states are the block's states, integrated by ctlgraph's solver (any
//! method; TR-BDF2's Jacobian by finite differences of the derivatives);
//! its event indicators are the block's zero-crossing functions, located
//! like any block's; its time events are block events, landed on as major
//! steps. At every major step the block reports the accepted step
//! (`completedIntegratorStep`) and, after a located crossing, a time event
//! or a request of the FMU, runs the event iteration and takes the states
//! the FMU reset (FMI 3.0 §3.2, FMI 2.0.4 §3.2).
//!
//! Every call sets the time, the states and the inputs first, so each is a
//! function of the values it is given, as the solver's stages need. Inputs
//! are taken to feed through to outputs (a model-exchange FMU's outputs may
//! depend on its inputs directly).

use super::binding::Instance;
use super::{Common, copy_of};
use ctlgraph_core::{Block, Io};
use std::sync::Mutex;

/// The block: what it was built with, and this run's instance.
#[derive(Clone)]
pub struct MeBlock {
    pub(super) shared: Shared,
    /// The FMU's next time event (infinite when none).
    pub(super) next_time: f64,
    /// A crossing was located: the coming major step is an event.
    pub(super) located: bool,
    /// The run's instance (behind a lock: the zero-crossing functions are
    /// read through `&self`).
    pub(super) run: Option<Copied>,
}

/// What the block was built with: the common part, and the FMU's counts
/// of continuous states and event indicators.
#[derive(Clone)]
pub(super) struct Shared {
    pub common: Common,
    pub n_states: usize,
    pub n_indicators: usize,
}

pub(super) struct Run {
    instance: Result<Instance, String>,
    pending: Option<Vec<u8>>,
    inputs: Vec<f64>,
    outputs: Vec<f64>,
}

/// A run whose copies carry the FMU's state: copying serialises it, and
/// the copy restores it into a new instance on first use (as the
/// co-simulation block).
pub(super) struct Copied {
    run: Mutex<Run>,
    can_copy_state: bool,
}

impl Clone for Copied {
    fn clone(&self) -> Self {
        let r = self.run.lock().unwrap_or_else(|e| e.into_inner());
        let (instance, pending) = copy_of(&r.instance, &r.pending, self.can_copy_state);
        let run = Run { instance, pending, inputs: r.inputs.clone(), outputs: r.outputs.clone() };
        Copied { run: Mutex::new(run), can_copy_state: self.can_copy_state }
    }
}

impl Shared {
    /// A new instance, its parameters set, initialised and settled; its
    /// initial states into `x0` (when given) and its next time event.
    pub(super) fn instantiate(&self, x0: Option<&mut [f64]>) -> Result<(Instance, f64), String> {
        let mut i = self.common.instance(0.0)?;
        i.check_counts(self.n_states, self.n_indicators)?;
        // Initialisation ends in event mode (FMI 3.0 §3.2.1; FMI 2 likewise).
        let settled = i.settle()?;
        if settled.terminate {
            return Err("the FMU asked to terminate at its initialisation".to_string());
        }
        if let Some(x0) = x0 {
            i.states(x0)?;
        }
        Ok((i, settled.next_time.unwrap_or(f64::INFINITY)))
    }

    /// Runs `f` on the run's instance after setting the time `t`, the
    /// states `x` and the inputs of `io`; a failure ends the instance (its
    /// outputs are NaN from then on) and is returned.
    fn with<T>(
        &self,
        run: &mut Run,
        io: &Io,
        x: &[f64],
        f: impl FnOnce(&mut Instance, &mut Vec<f64>) -> Result<T, String>,
    ) -> Result<T, String> {
        if let Some(bytes) = run.pending.take() {
            run.instance = self.instantiate(None).map(|(i, _)| i).and_then(|mut i| i.deserialize(&bytes).map(|()| i));
        }
        let mut k = 0;
        for port in 0..io.num_inputs() {
            let u = io.input(port);
            run.inputs[k..k + u.len()].copy_from_slice(u);
            k += u.len();
        }
        let Run { instance, inputs, outputs, .. } = run;
        let result = match instance.as_mut() {
            Ok(i) => i
                .set_time_and_states(io.t, x)
                .and_then(|()| i.set(&self.common.input_refs, inputs))
                .and_then(|()| f(i, outputs)),
            Err(e) => Err(e.clone()),
        };
        if let Err(e) = &result {
            *instance = Err(e.clone());
        }
        result
    }
}

impl MeBlock {
    fn run_mut(&mut self) -> Option<(&Shared, &mut Run)> {
        let run = self.run.as_mut()?.run.get_mut().unwrap_or_else(|e| e.into_inner());
        Some((&self.shared, run))
    }
}

impl Block for MeBlock {
    fn num_states(&self) -> usize {
        self.shared.n_states
    }

    fn initialize(&mut self, x0: &mut [f64]) {
        self.run = None; // the previous instance is freed first
        self.located = false;
        let (instance, next) = match self.shared.instantiate(Some(x0)) {
            Ok((i, next)) => (Ok(i), next),
            Err(e) => (Err(e), f64::INFINITY),
        };
        self.next_time = next;
        let (inputs, outputs) = (vec![0.0; self.shared.common.input_len], vec![0.0; self.shared.common.output_len]);
        let run = Mutex::new(Run { instance, pending: None, inputs, outputs });
        self.run = Some(Copied { run, can_copy_state: self.shared.common.can_copy_state });
    }

    fn output(&mut self, io: &mut Io) {
        let Some((shared, run)) = self.run_mut() else { return };
        let refs = &shared.common.output_refs;
        let ok = shared.with(run, io, io.x, |i, outputs| i.get(refs, outputs)).is_ok();
        let mut k = 0;
        for port in 0..io.num_outputs() {
            for j in 0..io.output_width(port) {
                io.set_at(port, j, if ok { run.outputs[k] } else { f64::NAN });
                k += 1;
            }
        }
    }

    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        let Some((shared, run)) = self.run_mut() else { return };
        if shared.with(run, io, io.x, |i, _| i.derivatives(dx)).is_err() {
            dx.fill(f64::NAN);
        }
    }

    fn num_zero_crossings(&self) -> usize {
        self.shared.n_indicators
    }

    fn needs_major_step(&self) -> bool {
        true
    }

    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        let Some(copied) = self.run.as_ref() else { return };
        let mut run = copied.run.lock().unwrap_or_else(|e| e.into_inner());
        if self.shared.with(&mut run, io, io.x, |i, _| i.event_indicators(g)).is_err() {
            g.fill(f64::NAN);
        }
    }

    fn crossing_located(&mut self, _k: usize) {
        self.located = true;
    }

    fn next_event(&self, t: f64) -> f64 {
        if self.next_time > t { self.next_time } else { f64::INFINITY }
    }

    /// The accepted step reported; an event (a located crossing, a time
    /// event reached, or the FMU's request) iterated to rest, the states
    /// it reset taken into `x`. Returns whether an event was handled.
    fn major_step(&mut self, io: &Io, x: &mut [f64]) -> bool {
        let (located, next_time) = (std::mem::take(&mut self.located), self.next_time);
        let MeBlock { shared, run, next_time: next_slot, .. } = self;
        let Some(run) = run.as_mut().map(|c| c.run.get_mut().unwrap_or_else(|e| e.into_inner())) else { return false };
        let handled = shared.with(run, io, x, |i, _| {
            let asked = i.completed_integrator_step()?;
            // A time event is due at its own major step (landed on exactly).
            if !(located || asked || io.t >= next_time) {
                return Ok(None);
            }
            i.enter_event_mode()?;
            let settled = i.settle()?;
            if settled.terminate {
                return Err(format!("the FMU asked to terminate the simulation at t = {}", io.t));
            }
            Ok(Some(settled))
        });
        match handled {
            Ok(Some(settled)) => {
                *next_slot = settled.next_time.filter(|&n| n > io.t).unwrap_or(f64::INFINITY);
                if settled.states_changed
                    && let Ok(i) = run.instance.as_mut()
                    && let Err(e) = i.states(x)
                {
                    run.instance = Err(e);
                }
                true
            }
            Ok(None) => false,
            // The instance has failed: its outputs, computed again, are NaN.
            Err(_) => true,
        }
    }

    fn diagnose(&self) -> Option<String> {
        self.shared.common.diagnose(&self.run.as_ref()?.run.lock().ok()?.instance)
    }

    fn build_report(&self) -> Option<String> {
        Some(self.shared.common.report.clone())
    }
}
