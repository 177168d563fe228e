//! Which blocks of a compiled graph are the controller, what its inputs
//! and outputs are, and when each block runs: the checks that make a part
//! of a graph a sampled controller C can compute step by step.

use crate::block::Port;
use crate::compile::{Model, Rate};
use crate::diag::Diagnostic;

/// The controller: a graph's blocks (all, or one subsystem's) that run at
/// sample times, stepped at the base rate.
#[derive(Clone, Debug)]
pub struct Controller {
    /// The C identifier prefix (`ladrc`).
    pub name: String,
    /// Its blocks in execution order.
    pub members: Vec<Member>,
    pub inputs: Vec<Terminal>,
    pub outputs: Vec<Terminal>,
    /// The base rate's period: `NAME_step` is called every `base_period` s.
    pub base_period: f64,
    /// The base rate's index in the model's clocks.
    pub base_clock: usize,
}

/// One block of the controller.
#[derive(Clone, Debug)]
pub struct Member {
    /// Index into the model's blocks.
    pub index: usize,
    /// Its name inside the controller (the subsystem's prefix removed).
    pub name: String,
    /// When it runs, in base steps: 0 once at `init` (a constant block),
    /// n every n-th step (a sample time n times the base period).
    pub every: u32,
}

/// An input or output of the controller: its port name and the signal.
#[derive(Clone, Debug)]
pub struct Terminal {
    pub name: String,
    pub port: Port,
}

/// The controller `c_name`: a subsystem of `model` by its path (`ctrl`,
/// `loop/ctrl`) with the names of its inports and outports, or the whole
/// graph with its top-level inports and outports (`subsystem` None).
pub fn select(
    model: &Model,
    subsystem: Option<(&str, &[String], &[String])>,
    c_name: &str,
) -> Result<Controller, Diagnostic> {
    let (members, inputs, outputs) = match subsystem {
        Some((sub, ins, outs)) => {
            let prefix = format!("{sub}/");
            let members: Vec<usize> =
                (0..model.meta.len()).filter(|&i| model.meta[i].name.starts_with(&prefix)).collect();
            let terminals = |names: &[String]| -> Result<Vec<Terminal>, Diagnostic> {
                names
                    .iter()
                    .map(|port| {
                        let key = format!("{sub}.{port}");
                        let found = model.subsystem_ports.iter().find(|(n, _)| *n == key);
                        match found {
                            Some((_, p)) => Ok(Terminal { name: port.clone(), port: *p }),
                            None => Err(Diagnostic::plain(format!(
                                "subsystem `{sub}`: port `{port}` is not connected to a signal"
                            ))
                            .with_hint("wire it in the graph: the C step reads every inport")),
                        }
                    })
                    .collect()
            };
            (members, terminals(ins)?, terminals(outs)?)
        }
        None => {
            let inputs: Vec<Terminal> = model
                .external_inputs
                .iter()
                .map(|(name, i)| Terminal { name: name.clone(), port: model.out_ports[model.slots[*i].outputs.start] })
                .collect();
            let external: Vec<usize> = model.external_inputs.iter().map(|&(_, i)| i).collect();
            let members = (0..model.meta.len()).filter(|i| !external.contains(i)).collect();
            let outputs = model
                .external_outputs
                .iter()
                .map(|(name, port)| Terminal { name: name.clone(), port: *port })
                .collect();
            (members, inputs, outputs)
        }
    };
    let whole = || match subsystem {
        Some((sub, ..)) => format!("subsystem `{sub}`"),
        None => format!("{}", model.file),
    };
    if outputs.is_empty() {
        return Err(Diagnostic::plain(format!("{}: the controller has no outport", whole()))
            .with_hint("add an `outport` block: its value is what NAME_step writes to NAME_out"));
    }
    let (base_clock, base_period) = base_rate(model, &members).ok_or_else(|| {
        Diagnostic::plain(format!("{}: no block of the controller has a sample time", whole()))
            .with_hint("give the controller's blocks `sample_time: h`; the C step runs at that rate")
    })?;
    let strip = subsystem.map_or(0, |(sub, ..)| sub.len() + 1);
    let members = members
        .into_iter()
        .map(|i| {
            Ok(Member { index: i, name: model.meta[i].name[strip..].to_string(), every: every(model, i, base_period)? })
        })
        .collect::<Result<_, Diagnostic>>()?;
    Ok(Controller { name: c_name.to_string(), members, inputs, outputs, base_period, base_clock })
}

/// The clock with the smallest period among the blocks' sample times.
fn base_rate(model: &Model, members: &[usize]) -> Option<(usize, f64)> {
    members
        .iter()
        .filter_map(|&i| match model.meta[i].rate {
            Rate::Discrete(c) => Some((c, model.clocks[c].0)),
            _ => None,
        })
        .reduce(|a, b| if b.1 < a.1 { b } else { a })
}

/// How many base steps apart block `i` runs; refuses what a counter cannot
/// step: an offset, a period not a whole multiple of the base, continuous
/// dynamics.
fn every(model: &Model, i: usize, base: f64) -> Result<u32, Diagnostic> {
    let meta = &model.meta[i];
    let block = &model.blocks[i];
    match meta.rate {
        Rate::Constant => Ok(0),
        // A memoryless block fed by the inputs alone: its value at the
        // base rate's samples is all the controller's blocks read.
        Rate::Continuous if block.num_states() == 0 && !block.updates() => Ok(1),
        Rate::Continuous => Err(Diagnostic::at(
            &meta.pos,
            format!("block `{}` ({}) is continuous: C is generated for sampled controllers", meta.name, meta.type_name),
        )
        .with_hint("give it a `sample_time` (a discrete form), or move it out of the controller into the plant")),
        Rate::Discrete(c) => {
            let (period, offset) = model.clocks[c];
            if offset != 0.0 {
                return Err(Diagnostic::at(
                    &meta.pos,
                    format!(
                        "block `{}`: sample time offset {offset} s: the C step runs every sample from t = 0",
                        meta.name
                    ),
                )
                .with_hint("remove the offset; delay the signal with a unit_delay instead"));
            }
            let ratio = period / base;
            let n = ratio.round();
            if (ratio - n).abs() > 1e-9 * n || n > f64::from(u32::MAX) {
                return Err(Diagnostic::at(
                    &meta.pos,
                    format!(
                        "block `{}`: sample time {period} s is not a whole multiple of the base rate {base} s (ratio {ratio})",
                        meta.name
                    ),
                )
                .with_hint("a counter steps the slower rates: choose sample times that are whole multiples of the fastest"));
            }
            Ok(n as u32)
        }
    }
}
