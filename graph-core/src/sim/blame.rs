//! The errors of a run that produced a value that is not finite: which
//! block, which output or state, and the block's inputs at that moment.
//! Shared by the simulator and a generated step
//! ([`crate::codegen::Compiled`]), which must report the same errors.

use super::SimError;
use crate::block::Port;
use crate::compile::{BlockMeta, signal_owner};
use ctlgraph_solver::SolverError;

/// What names a block in an error: the model's metadata and ports.
#[derive(Clone, Copy)]
pub(crate) struct Blame<'m> {
    pub(crate) meta: &'m [BlockMeta],
    pub(crate) in_ports: &'m [Port],
    pub(crate) out_ports: &'m [Port],
}

impl<'m> Blame<'m> {
    /// What names `model`'s blocks.
    pub(crate) fn of(model: &'m crate::compile::Model) -> Self {
        Blame { meta: &model.meta, in_ports: &model.in_ports, out_ports: &model.out_ports }
    }

    /// A signal that is not finite at `t` (called once a check found
    /// one): its block and output, with `diagnose`'s reason for that block.
    pub(crate) fn signal(&self, signals: &[f64], t: f64, diagnose: impl Fn(usize) -> Option<String>) -> SimError {
        let k = signals.iter().position(|v| !v.is_finite()).unwrap_or(0);
        let owner = signal_owner(self.meta, self.out_ports, k);
        let what = match owner {
            Some((i, port)) => match diagnose(i) {
                Some(why) => format!("output `{port}`: {why}"),
                None => format!("output `{port}`"),
            },
            None => "a signal".into(),
        };
        self.non_finite(signals, t, owner.map(|(i, _)| i), what, signals.get(k).copied().unwrap_or(f64::NAN))
    }

    /// A state that is not finite after a step ending at `t`.
    pub(crate) fn state(&self, signals: &[f64], t: f64, x: &[f64]) -> SimError {
        let k = x.iter().position(|v| !v.is_finite()).unwrap_or(0);
        let owner = self.state_owner(k);
        let what = format!("state {}", owner.map_or(k, |(_, j)| j));
        self.non_finite(signals, t, owner.map(|(i, _)| i), what, x.get(k).copied().unwrap_or(f64::NAN))
    }

    /// The solver's failure in the step from `t0`: a state that blew up
    /// inside it names its block, as a blow-up at a major step does.
    pub(crate) fn solver(&self, signals: &[f64], t0: f64, error: SolverError) -> SimError {
        if let SolverError::NonFinite { t, state: Some(k) } = error {
            let owner = self.state_owner(k);
            let what = format!("state {} (inside the solver's step)", owner.map_or(k, |(_, j)| j));
            return self.non_finite(signals, t, owner.map(|(i, _)| i), what, f64::NAN);
        }
        let culprit = error.state().and_then(|k| self.state_owner(k));
        let culprit = culprit.map(|(i, j)| (self.meta[i].name.clone(), j));
        SimError::Solver { t: t0, error, culprit }
    }

    /// The block owning state `k`, and the state's index within the block.
    fn state_owner(&self, k: usize) -> Option<(usize, usize)> {
        let i = self.meta.iter().position(|m| m.states.contains(&k))?;
        Some((i, k - self.meta[i].states.start))
    }

    /// The error for block `owner` having produced `value` (not finite) as
    /// `what`, with its inputs as they are in `signals` (block `?` when
    /// unknown).
    fn non_finite(&self, signals: &[f64], t: f64, owner: Option<usize>, what: String, value: f64) -> SimError {
        let Some(i) = owner else {
            return SimError::NonFinite { t, block: "?".into(), what, value, inputs: vec![] };
        };
        let meta = &self.meta[i];
        let mut inputs = Vec::new();
        for (name, p) in meta.input_names.iter().zip(meta.inputs.clone()) {
            let port = self.in_ports[p];
            let values = &signals[port.offset..port.offset + port.width];
            match values {
                [v] => inputs.push((name.clone(), *v)),
                _ => inputs.extend(values.iter().enumerate().map(|(k, v)| (format!("{name}[{k}]"), *v))),
            }
        }
        SimError::NonFinite { t, block: meta.name.clone(), what, value, inputs }
    }
}
