//! The controller's inputs and outputs at every base-rate sample of a
//! simulated run: what `--verify` feeds the C and compares it with.

use ctlgraph_core::codegen::c::Controller;
use ctlgraph_core::{Model, SimError, Simulator};
use std::sync::Arc;

/// Row-major: one row per sample, the terminals' elements in order.
pub struct Samples {
    pub inputs: Vec<f64>,
    pub outputs: Vec<f64>,
    pub count: usize,
}

/// Runs `model` to its stop time and takes, at every major step that is
/// a hit of the controller's base rate, the signals on its inputs and
/// outputs after that step's outputs (the values its blocks read and
/// wrote at that sample).
pub fn record(model: Arc<Model>, controller: &Controller) -> Result<Samples, SimError> {
    let mut sim = Simulator::new(model, None);
    let (mut inputs, mut outputs, mut count) = (Vec::new(), Vec::new(), 0);
    loop {
        sim.outputs()?;
        if sim.sample_hit(controller.base_clock) {
            let signals = sim.signals();
            for t in &controller.inputs {
                inputs.extend_from_slice(&signals[t.port.offset..t.port.offset + t.port.width]);
            }
            for t in &controller.outputs {
                outputs.extend_from_slice(&signals[t.port.offset..t.port.offset + t.port.width]);
            }
            count += 1;
        }
        if sim.finished() {
            return Ok(Samples { inputs, outputs, count });
        }
        sim.advance()?;
    }
}

/// Like [`record`], for a whole graph whose inports the caller drives:
/// before each base-rate sample k the inports take row k of `rows` (every
/// input's elements in the controller's order), as `NAME_in` will.
pub fn drive(model: Arc<Model>, controller: &Controller, rows: &[f64]) -> Result<Samples, String> {
    let width: usize = controller.inputs.iter().map(|t| t.port.width).sum();
    let n = rows.len() / width.max(1);
    let mut sim = Simulator::new(model, None);
    let mut outputs = Vec::new();
    let mut count = 0;
    while count < n {
        let mut at = count * width;
        for t in &controller.inputs {
            sim.set_input(&t.name, &rows[at..at + t.port.width]).map_err(|d| d.to_string())?;
            at += t.port.width;
        }
        sim.outputs().map_err(|e| e.to_string())?;
        if !sim.sample_hit(controller.base_clock) {
            return Err(format!("t = {}: the run's major steps must be the base rate's samples", sim.time()));
        }
        let signals = sim.signals();
        for t in &controller.outputs {
            outputs.extend_from_slice(&signals[t.port.offset..t.port.offset + t.port.width]);
        }
        count += 1;
        if count == n || sim.finished() {
            break;
        }
        sim.advance().map_err(|e| e.to_string())?;
    }
    Ok(Samples { inputs: rows[..count * width].to_vec(), outputs, count })
}

impl Samples {
    /// The input file's bytes: native doubles, one placeholder per sample
    /// for a controller without inputs (the driver reads one).
    pub fn input_bytes(&self) -> Vec<u8> {
        let values: Vec<f64> = if self.inputs.is_empty() { vec![0.0; self.count] } else { self.inputs.clone() };
        values.iter().flat_map(|v| v.to_ne_bytes()).collect()
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_sampled_graph_gives_one_row_per_base_sample() {
        let text = "blocks:\n  r: { type: inport, value: 2 }\n  k: { type: gain, k: 3, sample_time: 0.1 }\n  y: { type: outport }\n\
                    wires:\n  - r -> k\n  - k -> y\nsimulation: { stop: 1.0, solver: { method: rk4, step: 0.05 } }\n";
        let model = crate::compile_str(text, "k.yaml", &[]).unwrap();
        let controller = ctlgraph_core::codegen::c::select(&model, None, "k").unwrap();
        let s = super::record(model.into(), &controller).unwrap();
        assert_eq!(s.count, 11, "t = 0, 0.1, …, 1.0");
        assert!(s.inputs.iter().all(|&u| u == 2.0));
        assert!(s.outputs.iter().all(|&y| y == 6.0));
    }
}
