//! Blocks moved into one containing block — an algebraic loop's
//! ([`super::loops`]), a conditionally executed subsystem's
//! ([`super::conditional`]): its inputs are the members' inputs wired from
//! outside, its outputs every member's outputs, and the members run on a
//! buffer of its own. Wires from a member then leave the containing block.

use super::{Driver, InnerBlock, Node, resolved};
use crate::block::{Block, InputPort, Interface, Port, SampleTime, Width};
use crate::composite::Member;
use crate::diag::Diagnostic;
use std::collections::{HashMap, HashSet};

/// Where everything lies on the containing block's buffer.
pub(super) struct Layout {
    pub iface: Interface,
    /// The containing block's drivers, one per input.
    pub drivers: Vec<Driver>,
    /// Where each input is copied in the buffer.
    pub external: Vec<Port>,
    /// Where each output is in the buffer.
    pub outputs: Vec<Port>,
    /// (member node, its output port) → the containing block's output.
    pub port_of: HashMap<(usize, usize), usize>,
    pub buffer_len: usize,
    ins: HashMap<usize, Vec<Port>>,
    outs: HashMap<usize, Vec<Port>>,
}

/// The feedthrough wires between `members`, as (from, to) positions in
/// `members`: the order the members must run in within one evaluation.
pub(super) fn feedthrough_edges(nodes: &[Node], drivers: &[Vec<Driver>], members: &[usize]) -> Vec<(usize, usize)> {
    let position: HashMap<usize, usize> = members.iter().enumerate().map(|(k, &m)| (m, k)).collect();
    let mut edges = Vec::new();
    for (k, &m) in members.iter().enumerate() {
        for (p, d) in drivers[m].iter().enumerate() {
            if let Some(&from) = position.get(&d.src).filter(|_| nodes[m].iface.inputs[p].feedthrough) {
                edges.push((from, k));
            }
        }
    }
    edges
}

pub(super) fn lay_out(nodes: &[Node], drivers: &[Vec<Driver>], members: &[usize], sample_time: SampleTime) -> Layout {
    let inside: HashSet<usize> = members.iter().copied().collect();
    let mut iface = Interface::new(sample_time);
    let mut buffer_len = 0;
    let mut place = |width: usize| {
        buffer_len += width;
        Port { offset: buffer_len - width, width }
    };
    let (mut outer, mut external) = (Vec::new(), Vec::new());
    let mut input_place: HashMap<(usize, usize), Port> = HashMap::new();
    for &m in members {
        for (p, d) in drivers[m].iter().enumerate().filter(|(_, d)| !inside.contains(&d.src)) {
            let port = &nodes[m].iface.inputs[p];
            let width = resolved(port.width, nodes[m].width);
            iface =
                iface.input(&format!("{}.{}", nodes[m].flat.path, port.name), Width::Fixed(width), port.feedthrough);
            outer.push(d.clone());
            let slot = place(width);
            external.push(slot);
            input_place.insert((m, p), slot);
        }
    }
    let (mut outputs, mut port_of, mut outs) = (Vec::new(), HashMap::new(), HashMap::new());
    for &m in members {
        let mut own = Vec::new();
        for (q, port) in nodes[m].iface.outputs.iter().enumerate() {
            let width = resolved(port.width, nodes[m].width);
            iface = iface.output(&format!("{}.{}", nodes[m].flat.path, port.name), Width::Fixed(width));
            let slot = place(width);
            port_of.insert((m, q), outputs.len());
            outputs.push(slot);
            own.push(slot);
        }
        outs.insert(m, own);
    }
    let ins = members
        .iter()
        .map(|&m| {
            let ports = drivers[m]
                .iter()
                .enumerate()
                .map(|(p, d)| input_place.get(&(m, p)).copied().unwrap_or_else(|| outs[&d.src][d.port]))
                .collect();
            (m, ports)
        })
        .collect();
    Layout { iface, drivers: outer, external, outputs, port_of, buffer_len, ins, outs }
}

impl Layout {
    /// Member `m`'s block, taken out of its node, with its ports on the buffer.
    pub fn member(&self, nodes: &mut [Node], m: usize) -> Result<Member, Diagnostic> {
        let block = nodes[m].block.take().ok_or_else(|| Diagnostic::plain("internal: block built twice"))?;
        Ok(Member::new(nodes[m].flat.path.clone(), block, self.ins[&m].clone(), self.outs[&m].clone()))
    }

    /// Adds a scalar input the containing block reads itself (not a
    /// member's), fed by `driver`; returns its index.
    pub fn add_input(&mut self, name: &str, driver: Driver) -> usize {
        self.iface.inputs.push(InputPort { name: name.to_string(), width: Width::Fixed(1), feedthrough: true });
        self.drivers.push(driver);
        self.drivers.len() - 1
    }

    /// Where member `m`'s outputs are in the buffer.
    pub fn outputs_of(&self, m: usize) -> &[Port] {
        &self.outs[&m]
    }
}

/// A containing block put in place: its node, where each member's
/// outputs went ((member, port) → its output), and its members.
pub(super) struct Installed {
    pub node: usize,
    pub outputs: Vec<((usize, usize), usize)>,
    pub members: Vec<usize>,
}

/// Puts the containing block in the graph as a new node named `label`, of
/// type `kind`:
/// the members absorbed, the wires from them leaving it. Returns its index.
pub(super) fn install(
    nodes: &mut Vec<Node>,
    drivers: &mut Vec<Vec<Driver>>,
    members: &[usize],
    mut layout: Layout,
    block: Box<dyn Block>,
    label: String,
    kind: &'static str,
) -> Installed {
    let node = nodes.len();
    let outputs = layout.port_of.iter().map(|(&k, &v)| (k, v)).collect();
    // Its own drivers too: a conditional subsystem's `enable` may come from inside it.
    for ds in drivers.iter_mut().chain([&mut layout.drivers]) {
        for d in ds.iter_mut() {
            if let Some(&k) = layout.port_of.get(&(d.src, d.port)) {
                (d.src, d.port) = (node, k);
            }
        }
    }
    for &m in members {
        drivers[m].clear();
        nodes[m].absorbed = true;
    }
    let flat = nodes[members[0]].flat;
    nodes.push(Node {
        flat,
        iface: layout.iface,
        block: Some(block),
        is_virtual: false,
        width: None,
        label: Some((label, kind)),
        absorbed: false,
    });
    drivers.push(layout.drivers);
    Installed { node, outputs, members: members.to_vec() }
}

/// The blocks inside containers, each with the outermost container it
/// runs in (the one in the execution order).
pub(super) fn inner_blocks(
    nodes: &[Node],
    containers: &[Installed],
    position: &[usize],
    out_offset: &[Vec<Port>],
) -> Vec<InnerBlock> {
    let parent: HashMap<usize, usize> =
        containers.iter().flat_map(|c| c.members.iter().map(|&m| (m, c.node))).collect();
    let outermost = |mut n: usize| {
        while let Some(&p) = parent.get(&n) {
            n = p;
        }
        n
    };
    let mut inner: Vec<InnerBlock> = containers
        .iter()
        .flat_map(|c| c.members.iter().copied())
        .filter(|&m| nodes[m].label.is_none())
        .map(|m| InnerBlock {
            name: nodes[m].flat.path.clone(),
            type_name: nodes[m].flat.spec.type_name.clone(),
            container: position[outermost(m)],
            input_names: nodes[m].iface.inputs.iter().map(|p| p.name.clone()).collect(),
            output_names: nodes[m].iface.outputs.iter().map(|p| p.name.clone()).collect(),
            outputs: out_offset[m].clone(),
        })
        .collect();
    inner.sort_by(|a, b| a.name.cmp(&b.name));
    inner
}
