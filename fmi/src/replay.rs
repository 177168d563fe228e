//! FMU states: a saved instance ([`Saved`]), and its serialised form.
//!
//! Getting and setting a state (`fmi3GetFMUState`/`fmi3SetFMUState`) is a
//! clone of the run state ([`ctlgraph_core::Snapshot`]): every block's
//! memory, the solver's history, the clocks. Serialising one cannot write
//! that clone out — the blocks' memory has no byte layout — so the bytes
//! hold what made it instead: the parameter values and inputs the run
//! started from and every input set and communication point reached since
//! (its log). Deserialising rebuilds the run and replays the log through
//! the same driver, which is deterministic (random sources are seeded), so
//! the state it gives continues bit for bit as the original would. The
//! cost is a rerun to the saved time; the bytes grow by 8 per step and by
//! 24 + 8 per element for each input set.

use crate::instance::{Instance, Mode, Run};

/// What happened to a run: the times it advanced to, in order, and the
/// inputs set between (8 bytes a step: a long co-simulation's log stays
/// small beside its run).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Log {
    pub advances: Vec<f64>,
    pub inputs: Vec<InputSet>,
}

/// Input `index` set to `value` after the first `after` advances.
#[derive(Clone, Debug, PartialEq)]
pub struct InputSet {
    pub after: usize,
    pub index: usize,
    pub value: Vec<f64>,
}

impl Log {
    pub fn advance(&mut self, t: f64) {
        self.advances.push(t);
    }

    pub fn input(&mut self, index: usize, value: Vec<f64>) {
        self.inputs.push(InputSet { after: self.advances.len(), index, value });
    }
}

/// An instance's state.
#[derive(Clone)]
pub struct Saved {
    pub(crate) mode: Mode,
    pub(crate) parameters: Vec<f64>,
    pub(crate) inputs: Vec<Vec<f64>>,
    pub(crate) stop: Option<f64>,
    pub(crate) run: Option<SavedRun>,
}

#[derive(Clone)]
pub(crate) struct SavedRun {
    /// The run state itself, when the state was taken (not deserialised).
    pub snapshot: Option<ctlgraph_core::Snapshot>,
    pub parameters: Vec<f64>,
    pub initial_inputs: Vec<Vec<f64>>,
    pub log: Log,
}

const MAGIC: &[u8] = b"ctlgraph FMU state 1\n";

impl Saved {
    /// The bytes of this state for an FMU whose token is `token`.
    pub fn serialize(&self, token: &str) -> Vec<u8> {
        let mut w = Writer(Vec::new());
        w.bytes(MAGIC);
        w.text(token);
        w.u64(match self.mode {
            Mode::Instantiated => 0,
            Mode::Initialization => 1,
            Mode::Step => 2,
            Mode::Terminated => 3,
            Mode::Failed => 4,
        });
        w.numbers(&self.parameters);
        w.lists(&self.inputs);
        w.f64(self.stop.unwrap_or(f64::NAN));
        match &self.run {
            None => w.u64(0),
            Some(run) => {
                w.u64(1);
                w.numbers(&run.parameters);
                w.lists(&run.initial_inputs);
                w.numbers(&run.log.advances);
                w.u64(run.log.inputs.len() as u64);
                for set in &run.log.inputs {
                    w.u64(set.after as u64);
                    w.u64(set.index as u64);
                    w.numbers(&set.value);
                }
            }
        }
        w.0
    }

    /// Reads bytes written by [`Saved::serialize`] for the FMU `token`.
    pub fn deserialize(bytes: &[u8], token: &str) -> Result<Saved, String> {
        let mut r = Reader { bytes, at: 0 };
        if r.take(MAGIC.len())? != MAGIC {
            return Err("not a serialised ctlgraph FMU state".to_string());
        }
        if r.text()? != token {
            return Err("the serialised state was taken of another FMU".to_string());
        }
        let mode = match r.u64()? {
            0 => Mode::Instantiated,
            1 => Mode::Initialization,
            2 => Mode::Step,
            3 => Mode::Terminated,
            4 => Mode::Failed,
            m => return Err(format!("serialised state: unknown mode {m}")),
        };
        let parameters = r.numbers()?;
        let inputs = r.lists()?;
        let stop = Some(r.f64()?).filter(|s| !s.is_nan());
        let run = match r.u64()? {
            0 => None,
            _ => {
                let parameters = r.numbers()?;
                let initial_inputs = r.lists()?;
                let advances = r.numbers()?;
                let n = r.count(24)?;
                let mut inputs = Vec::with_capacity(n);
                for _ in 0..n {
                    let (after, index) = (r.u64()? as usize, r.u64()? as usize);
                    inputs.push(InputSet { after, index, value: r.numbers()? });
                }
                let log = Log { advances, inputs };
                Some(SavedRun { snapshot: None, parameters, initial_inputs, log })
            }
        };
        if r.at != bytes.len() {
            return Err("serialised state: bytes left over".to_string());
        }
        Ok(Saved { mode, parameters, inputs, stop, run })
    }
}

/// The run of `saved`, rebuilt in `instance` and replayed.
pub(crate) fn replay(instance: &Instance, saved: &SavedRun) -> Result<Run, String> {
    let stale = || "the state does not fit this FMU's graph".to_string();
    if saved.parameters.len() != instance.parameters.len() || saved.initial_inputs.len() != instance.inputs.len() {
        return Err(stale());
    }
    let mut sim = instance.simulator(&saved.parameters)?;
    for (i, value) in saved.initial_inputs.iter().enumerate() {
        sim.set_input(instance.input_name(i), value).map_err(|d| d.to_string())?;
    }
    let mut sets = saved.log.inputs.iter().peekable();
    for k in 0..=saved.log.advances.len() {
        while let Some(set) = sets.next_if(|s| s.after <= k) {
            if set.index >= instance.inputs.len() || set.after != k {
                return Err(stale());
            }
            sim.set_input(instance.input_name(set.index), &set.value).map_err(|d| d.to_string())?;
        }
        if let Some(&t) = saved.log.advances.get(k) {
            sim.advance_to(t).map_err(|e| format!("replaying the state: {e}"))?;
        }
    }
    Ok(Run {
        sim,
        parameters: saved.parameters.clone(),
        initial_inputs: saved.initial_inputs.clone(),
        log: saved.log.clone(),
    })
}

struct Writer(Vec<u8>);

impl Writer {
    fn bytes(&mut self, b: &[u8]) {
        self.0.extend_from_slice(b);
    }
    fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn text(&mut self, s: &str) {
        self.u64(s.len() as u64);
        self.bytes(s.as_bytes());
    }
    fn numbers(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        v.iter().for_each(|x| self.f64(*x));
    }
    fn lists(&mut self, v: &[Vec<f64>]) {
        self.u64(v.len() as u64);
        v.iter().for_each(|x| self.numbers(x));
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len()).ok_or("serialised state: cut short")?;
        let b = &self.bytes[self.at..end];
        self.at = end;
        Ok(b)
    }
    fn u64(&mut self) -> Result<u64, String> {
        let b = self.take(8)?;
        Ok(u64::from_le_bytes(b.try_into().map_err(|_| "serialised state: cut short")?))
    }
    fn f64(&mut self) -> Result<f64, String> {
        self.u64().map(f64::from_bits)
    }
    /// A count of items of at least `size` bytes each that the rest can hold.
    fn count(&mut self, size: usize) -> Result<usize, String> {
        let n = self.u64()? as usize;
        if n.saturating_mul(size) > self.bytes.len() - self.at {
            return Err("serialised state: cut short".to_string());
        }
        Ok(n)
    }
    fn text(&mut self) -> Result<String, String> {
        let n = self.count(1)?;
        String::from_utf8(self.take(n)?.to_vec()).map_err(|_| "serialised state: not UTF-8".to_string())
    }
    fn numbers(&mut self) -> Result<Vec<f64>, String> {
        let n = self.count(8)?;
        (0..n).map(|_| self.f64()).collect()
    }
    fn lists(&mut self) -> Result<Vec<Vec<f64>>, String> {
        let n = self.count(8)?;
        (0..n).map(|_| self.numbers()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_state_reads_back_as_written_and_refuses_damage() {
        let saved = Saved {
            mode: Mode::Step,
            parameters: vec![1.5, -2.0],
            inputs: vec![vec![0.25, 3.0]],
            stop: Some(2.0),
            run: Some(SavedRun {
                snapshot: None,
                parameters: vec![1.5, -2.0],
                initial_inputs: vec![vec![0.0, 0.0]],
                log: Log {
                    advances: vec![0.1, 0.2],
                    inputs: vec![InputSet { after: 1, index: 0, value: vec![0.25, 3.0] }],
                },
            }),
        };
        let bytes = saved.serialize("{tok}");
        let back = Saved::deserialize(&bytes, "{tok}").unwrap();
        assert_eq!(back.serialize("{tok}"), bytes);
        assert_eq!(back.run.as_ref().unwrap().log, saved.run.as_ref().unwrap().log);
        assert!(Saved::deserialize(&bytes, "{other}").err().unwrap().contains("another FMU"));
        for cut in [0, 10, bytes.len() - 1] {
            assert!(Saved::deserialize(&bytes[..cut], "{tok}").is_err(), "cut at {cut}");
        }
        let mut huge = bytes.clone();
        // A count claiming more items than the bytes hold is refused, not allocated.
        let at = MAGIC.len() + 8 + 5 + 8;
        huge[at..at + 8].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(Saved::deserialize(&huge, "{tok}").is_err());
    }
}
