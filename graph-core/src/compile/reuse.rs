//! Compiling a graph again with other parameter values (a sweep's cases)
//! without redoing what its structure decides. When the loaded graph has
//! the same blocks, wires and records as a compiled model, and every block
//! builds with the same interface (ports, widths, feedthrough, sample
//! time) and state count, the execution order, port layout, rates, clocks
//! and columns are the model's: only the blocks are built anew, and what
//! depends on their values is redone — the minor-step plan (`Between`),
//! the checks, the advice, the refusals of too many events or hits.
//! Anything else compiles whole, so the result is always what
//! [`super::compile`] gives.

use super::between::Between;
use super::wiring::instantiate;
use super::wiring::set_common_width;
use super::{Model, Node, Rate, compile, headers, plan_and_advise, refuse_too_many_steps};
use crate::block::SampleTime;
use crate::diag::Diagnostic;
use crate::flatten::FlatGraph;
use crate::registry::Registry;
use std::collections::hash_map::DefaultHasher;
use std::fmt::Write;
use std::hash::{Hash, Hasher};

/// What a model keeps of its structure to recognise it in another loaded graph.
#[derive(Clone, Debug)]
pub(crate) struct Structure {
    /// Hash of the blocks' names and types, the wires, the records.
    shape: u64,
    /// Per loaded block: hash of its built interface.
    signatures: Vec<u64>,
    /// Execution position → loaded block.
    order: Vec<usize>,
    /// Per loaded block: the common width it was given.
    widths: Vec<Option<usize>>,
}

impl Structure {
    pub(super) fn of(g: &FlatGraph, nodes: &[Node], order: &[usize]) -> Self {
        Structure {
            shape: shape(g),
            signatures: nodes.iter().map(signature).collect(),
            order: order.to_vec(),
            widths: nodes.iter().map(|n| n.width).collect(),
        }
    }
}

/// Hashed field by field: one pass over the blocks and wires (a graph's
/// bulk), the few records and the analysis section through their `Debug`
/// text, written into the hasher without a string in between.
fn shape(g: &FlatGraph) -> u64 {
    let mut h = DefaultHasher::new();
    for b in &g.blocks {
        (&b.path, &b.spec.type_name).hash(&mut h);
    }
    for end in g.wires.iter().flat_map(|w| [&w.src, &w.dst]) {
        (&end.block, &end.port, end.pos.line, end.pos.col).hash(&mut h);
    }
    let mut subsystems: Vec<_> = g.subsystems.iter().collect();
    subsystems.sort_by_key(|(path, _)| path.as_str());
    let _ = write!(Hashing(&mut h), "{:?}{:?}{:?}", g.records, g.analysis, subsystems);
    g.record_every.hash(&mut h);
    h.finish()
}

fn signature(node: &Node) -> u64 {
    let mut h = DefaultHasher::new();
    let iface = &node.iface;
    for p in &iface.inputs {
        (&p.name, p.width, p.feedthrough).hash(&mut h);
    }
    for p in &iface.outputs {
        (&p.name, p.width).hash(&mut h);
    }
    match iface.sample_time {
        SampleTime::Discrete { period, offset } => (1u8, period.to_bits(), offset.to_bits()).hash(&mut h),
        SampleTime::Continuous => 2u8.hash(&mut h),
        SampleTime::Inherited => 3u8.hash(&mut h),
        SampleTime::Constant => 4u8.hash(&mut h),
    }
    (iface.inputs.len(), iface.piecewise_constant, node.is_virtual).hash(&mut h);
    h.finish()
}

/// A hasher taking formatted text.
struct Hashing<'a>(&'a mut DefaultHasher);

impl std::fmt::Write for Hashing<'_> {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.0.write(s.as_bytes());
        Ok(())
    }
}

/// Compiles `g`, reusing `base`'s structure where `g` has the same.
pub fn recompile(base: &Model, g: &FlatGraph, reg: &Registry) -> Result<Model, Diagnostic> {
    match reuse_structure(base, g, reg)? {
        Some(model) => Ok(model),
        None => compile(g, reg),
    }
}

/// `g` compiled on `base`'s structure, or `None` when its structure differs.
pub fn reuse_structure(base: &Model, g: &FlatGraph, reg: &Registry) -> Result<Option<Model>, Diagnostic> {
    let s = &base.structure;
    if shape(g) != s.shape {
        return Ok(None);
    }
    let mut nodes = instantiate(g, reg)?;
    if nodes.len() != s.signatures.len() || nodes.iter().zip(&s.signatures).any(|(n, &sig)| signature(n) != sig) {
        return Ok(None);
    }
    let mut blocks = Vec::with_capacity(s.order.len());
    for (k, &i) in s.order.iter().enumerate() {
        let node = &mut nodes[i];
        let Some(mut block) = node.block.take() else { return Ok(None) };
        if node.iface.has_common_width() {
            set_common_width(node.flat, &mut *block, s.widths[i].unwrap_or(1))?;
        }
        if block.num_states() != base.meta[k].states.len() {
            return Ok(None);
        }
        let period = match base.meta[k].rate {
            Rate::Discrete(c) => Some(base.clocks[c].0),
            _ => None,
        };
        refuse_too_many_steps(node, g.sim.stop, block.min_event_spacing(), period)?;
        blocks.push(block);
    }
    let checks = crate::checks::compile(&g.checks, &headers(&base.columns), &g.parameters, g.analysis.is_some())?;
    let mut model = Model {
        blocks,
        meta: base.meta.iter().map(|m| super::BlockMeta { exact_zoh: false, ..m.clone() }).collect(),
        slots: base.slots.clone(),
        in_ports: base.in_ports.clone(),
        out_ports: base.out_ports.clone(),
        signal_len: base.signal_len,
        n_states: base.n_states,
        clocks: base.clocks.clone(),
        columns: base.columns.clone(),
        record_every: base.record_every,
        checks,
        scopes: g.scopes.clone(),
        edges: base.edges.clone(),
        sim: g.sim.clone(),
        parameters: g.parameters.clone(),
        name: g.name.clone(),
        file: g.file.clone(),
        between: Between::default(),
        analysis: g.analysis.clone(),
        loop_figures: None,
        subsystem_ports: base.subsystem_ports.clone(),
        external_inputs: base.external_inputs.clone(),
        external_outputs: base.external_outputs.clone(),
        loop_dead_time: None,
        warnings: Vec::new(),
        algebraic_loops: base.algebraic_loops.clone(),
        inner_blocks: base.inner_blocks.clone(),
        structure: base.structure.clone(),
    };
    plan_and_advise(&mut model);
    Ok(Some(model))
}
