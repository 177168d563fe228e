//! `mode: cs`: a co-simulation FMU as a discrete block (Simulink's FMU
//! block in that mode): at each hit t_k its outputs are the FMU's at t_k;
//! then the inputs at t_k are set and `doStep(t_k, T)` runs the FMU's own
//! solver, the inputs held over the step. No direct feedthrough.

use super::binding::Instance;
use super::{Loaded, NOT_YET_RESTORED, copy_of};
use ctlgraph_core::{Block, Io};
use std::sync::{Arc, Mutex};

/// The block: the FMU (shared), the selected variables, and this run's
/// instance.
pub struct FmuBlock {
    pub(super) name: String,
    /// `file:line:col` of the block, for errors at run time.
    pub(super) at: String,
    pub(super) token: String,
    pub(super) can_copy_state: bool,
    pub(super) loaded: Arc<Loaded>,
    /// The selected variables' value references, and how many numbers they hold.
    pub(super) input_refs: Vec<u32>,
    pub(super) input_len: usize,
    pub(super) output_refs: Vec<u32>,
    pub(super) output_len: usize,
    pub(super) parameters: Vec<(u32, Vec<f64>)>,
    pub(super) period: f64,
    pub(super) offset: f64,
    pub(super) report: String,
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

impl Clone for FmuBlock {
    /// A copy with its own FMU instance: for a snapshot of a run, the FMU's
    /// state serialised now and restored into a new instance when the copy
    /// is first used.
    fn clone(&self) -> Self {
        let run = self.run.as_ref().map(|m| {
            let r = m.lock().unwrap_or_else(|e| e.into_inner());
            let (instance, pending) = copy_of(&r.instance, &r.pending, self.can_copy_state);
            Mutex::new(Run { instance, steps: r.steps, pending, inputs: r.inputs.clone(), outputs: r.outputs.clone() })
        });
        FmuBlock {
            name: self.name.clone(),
            at: self.at.clone(),
            token: self.token.clone(),
            can_copy_state: self.can_copy_state,
            loaded: self.loaded.clone(),
            input_refs: self.input_refs.clone(),
            input_len: self.input_len,
            output_refs: self.output_refs.clone(),
            output_len: self.output_len,
            parameters: self.parameters.clone(),
            period: self.period,
            offset: self.offset,
            report: self.report.clone(),
            run,
        }
    }
}

impl FmuBlock {
    /// A new instance, its parameters set and initialised.
    pub(super) fn instantiate(&self) -> Result<Instance, String> {
        let mut i = Instance::new(&self.loaded.binary, &self.name, &self.token, &self.loaded.resources)?;
        i.enter_initialization(self.offset)?;
        for (reference, values) in &self.parameters {
            i.set(&[*reference], values)?;
        }
        i.exit_initialization()?;
        Ok(i)
    }

    /// Makes the run's instance ready: a copy's made and its state
    /// restored on first use.
    fn ready(&mut self) -> Result<(), String> {
        let pending = match self.run.as_mut().map(|m| m.get_mut().unwrap_or_else(|e| e.into_inner())) {
            None => return Err("the block was not initialised (internal error)".to_string()),
            Some(r) => r.pending.take(),
        };
        if let Some(bytes) = pending {
            let made = self.instantiate().and_then(|mut i| i.deserialize(&bytes).map(|()| i));
            if let Some(r) = self.run.as_mut().map(|m| m.get_mut().unwrap_or_else(|e| e.into_inner())) {
                r.instance = made;
            }
        }
        match self.run.as_mut().map(|m| m.get_mut().unwrap_or_else(|e| e.into_inner())).map(|r| &r.instance) {
            Some(Ok(_)) => Ok(()),
            Some(Err(e)) => Err(e.clone()),
            None => Err("no run".to_string()),
        }
    }
}

impl Block for FmuBlock {
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.run = None; // the previous instance is freed first
        let instance = self.instantiate();
        let (inputs, outputs) = (vec![0.0; self.input_len], vec![0.0; self.output_len]);
        self.run = Some(Mutex::new(Run { instance, steps: 0, pending: None, inputs, outputs }));
    }

    /// The FMU's outputs at this hit (NaN once it failed).
    fn output(&mut self, io: &mut Io) {
        let got = self.ready().and_then(|()| {
            match self.run.as_mut().map(|m| m.get_mut().unwrap_or_else(|e| e.into_inner())) {
                Some(Run { instance: Ok(i), outputs, .. }) => i.get(&self.output_refs, outputs),
                _ => Err("no instance".to_string()),
            }
        });
        if let Err(e) = got {
            self.fail(e);
        }
        let Some(run) = self.run.as_mut().map(|m| m.get_mut().unwrap_or_else(|e| e.into_inner())) else { return };
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
        let Some(Run { instance: Ok(i), inputs, steps, .. }) =
            self.run.as_mut().map(|m| m.get_mut().unwrap_or_else(|e| e.into_inner()))
        else {
            return;
        };
        let mut k = 0;
        for port in 0..io.num_inputs() {
            let u = io.input(port);
            inputs[k..k + u.len()].copy_from_slice(u);
            k += u.len();
        }
        let t = offset + *steps as f64 * period;
        match i.set(&self.input_refs, inputs).and_then(|()| i.do_step(t, period)) {
            Ok(()) => *steps += 1,
            Err(e) => self.fail(e),
        }
    }

    fn diagnose(&self) -> Option<String> {
        let run = self.run.as_ref()?.lock().ok()?;
        match &run.instance {
            Err(e) if e != NOT_YET_RESTORED => Some(format!("the FMU ({}): {e}", self.at)),
            _ => None,
        }
    }

    fn not_linearizable(&self) -> Option<&'static str> {
        Some("an FMU in co-simulation is a black box stepped at its sample time")
    }

    fn build_report(&self) -> Option<String> {
        Some(self.report.clone())
    }
}

impl FmuBlock {
    /// Ends the instance with `error`: its outputs are NaN from now on, and
    /// the run stops at them naming the block with this message.
    fn fail(&mut self, error: String) {
        if let Some(r) = self.run.as_mut().map(|m| m.get_mut().unwrap_or_else(|e| e.into_inner())) {
            r.instance = Err(error);
            r.pending = None;
        }
    }
}
