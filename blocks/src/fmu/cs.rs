//! `mode: cs`: a co-simulation FMU as a discrete block (Simulink's FMU
//! block in that mode): at each hit t_k its outputs are the FMU's at t_k;
//! then the inputs at t_k are set and `doStep(t_k, T)` runs the FMU's own
//! solver, the inputs held over the step. No direct feedthrough.

use super::binding::Instance;
use super::{Common, copy_of};
use ctlgraph_core::{Block, Io};
use std::sync::Mutex;

/// The block: what it was built with, its communication step, and this
/// run's instance.
pub struct FmuBlock {
    pub(super) common: Common,
    pub(super) period: f64,
    pub(super) offset: f64,
    /// The run's instance, once initialised; `None` in the compiled model.
    /// Behind a lock only so that a copy (`&self`) may read the FMU's state;
    /// the run's own calls go through `get_mut`, without locking.
    pub(super) run: Option<Mutex<Run>>,
}

/// One run's FMU instance and where it is.
pub(super) struct Run {
    /// The instance, or why there is none (and the run must stop).
    instance: Result<Instance, String>,
    /// The communication steps taken: the FMU is at offset + steps·T.
    steps: u64,
    /// A copy's FMU state, applied when the copy is first used.
    pending: Option<Vec<u8>>,
    /// The values exchanged at a hit (allocated once, with the run).
    inputs: Vec<f64>,
    outputs: Vec<f64>,
}

/// The run behind its lock, from `&mut` (no locking).
fn run_mut(run: &mut Option<Mutex<Run>>) -> Option<&mut Run> {
    run.as_mut().map(|m| m.get_mut().unwrap_or_else(|e| e.into_inner()))
}

impl Clone for FmuBlock {
    /// A copy with its own FMU instance: for a snapshot of a run, the FMU's
    /// state serialised now and restored into a new instance when the copy
    /// is first used.
    fn clone(&self) -> Self {
        let run = self.run.as_ref().map(|m| {
            let r = m.lock().unwrap_or_else(|e| e.into_inner());
            let (instance, pending) = copy_of(&r.instance, &r.pending, self.common.can_copy_state);
            Mutex::new(Run { instance, steps: r.steps, pending, inputs: r.inputs.clone(), outputs: r.outputs.clone() })
        });
        FmuBlock { common: self.common.clone(), period: self.period, offset: self.offset, run }
    }
}

impl FmuBlock {
    /// Makes the run's instance ready: a copy's made and its state
    /// restored on first use.
    fn ready(&mut self) -> Result<(), String> {
        let Some(r) = run_mut(&mut self.run) else {
            return Err("the block was not initialised (internal error)".to_string());
        };
        if let Some(bytes) = r.pending.take() {
            r.instance = self.common.instance(self.offset).and_then(|mut i| i.deserialize(&bytes).map(|()| i));
        }
        r.instance.as_ref().map(|_| ()).map_err(|e| e.clone())
    }
}

impl Block for FmuBlock {
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.run = None; // the previous instance is freed first
        let instance = self.common.instance(self.offset);
        let (inputs, outputs) = (vec![0.0; self.common.input_len], vec![0.0; self.common.output_len]);
        self.run = Some(Mutex::new(Run { instance, steps: 0, pending: None, inputs, outputs }));
    }

    /// The FMU's outputs at this hit (NaN once it failed).
    fn output(&mut self, io: &mut Io) {
        let got = self.ready().and_then(|()| match run_mut(&mut self.run) {
            Some(Run { instance: Ok(i), outputs, .. }) => i.get(&self.common.output_refs, outputs),
            _ => Err("no instance".to_string()),
        });
        if let Err(e) = got {
            self.fail(e);
        }
        let Some(run) = run_mut(&mut self.run) else { return };
        let mut k = 0;
        for port in 0..io.num_outputs() {
            for j in 0..io.output_width(port) {
                let v = if run.instance.is_ok() { run.outputs[k] } else { f64::NAN };
                io.set_at(port, j, v);
                k += 1;
            }
        }
    }

    /// The inputs at this hit set, and one communication step from
    /// offset + k·T (counted, not accumulated).
    fn update(&mut self, io: &mut Io) {
        if let Err(e) = self.ready() {
            self.fail(e);
            return;
        }
        let (period, offset) = (self.period, self.offset);
        let Some(Run { instance: Ok(i), inputs, steps, .. }) = run_mut(&mut self.run) else {
            return;
        };
        let mut k = 0;
        for port in 0..io.num_inputs() {
            let u = io.input(port);
            inputs[k..k + u.len()].copy_from_slice(u);
            k += u.len();
        }
        let t = offset + *steps as f64 * period;
        match i.set(&self.common.input_refs, inputs).and_then(|()| i.do_step(t, period)) {
            Ok(()) => *steps += 1,
            Err(e) => self.fail(e),
        }
    }

    fn diagnose(&self) -> Option<String> {
        self.common.diagnose(&self.run.as_ref()?.lock().ok()?.instance)
    }

    fn not_linearizable(&self) -> Option<&'static str> {
        Some("an FMU in co-simulation is a black box stepped at its sample time")
    }

    fn build_report(&self) -> Option<String> {
        Some(self.common.report.clone())
    }
}

impl FmuBlock {
    /// Ends the instance with `error`: its outputs are NaN from now on, and
    /// the run stops at them naming the block with this message.
    fn fail(&mut self, error: String) {
        if let Some(r) = run_mut(&mut self.run) {
            r.instance = Err(error);
            r.pending = None;
        }
    }
}
