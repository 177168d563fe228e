//! Building blocks and connecting them: instantiation through the
//! registry, wires resolved to ports (through subsystem ports), widths
//! propagated, recorded columns located.

use super::external::ExternalInput;
use super::{Column, Driver, Node, resolved};
use crate::block::{Block, Interface, Port, SampleTime, Width};
use crate::diag::{Diagnostic, Pos};
use crate::flatten::{FlatBlock, FlatGraph, INPORT, OUTPORT, resolve_sub_port};
use crate::params::Params;
use crate::registry::Registry;
use crate::spec::Endpoint;
use std::collections::{HashMap, HashSet};

pub(super) fn instantiate<'g>(g: &'g FlatGraph, reg: &Registry) -> Result<Vec<Node<'g>>, Diagnostic> {
    let mut nodes = Vec::with_capacity(g.blocks.len());
    for fb in &g.blocks {
        let spec = &fb.spec;
        let Some(ty) = reg.get(&spec.type_name) else {
            return Err(Diagnostic::at(
                &spec.type_pos,
                format!("block `{}`: unknown block type `{}`", fb.path, spec.type_name),
            )
            .suggest(&spec.type_name, reg.names())
            .or_hint("`ctlgraph blocks` lists the block types"));
        };
        let mut params = Params::new(&fb.path, ty.name, &spec.pos, &spec.params, &fb.scope, &fb.dir, ty.params)
            .with_seed(g.sim.seed);
        let top_level = !fb.path.contains('/');
        if ty.name == INPORT && top_level {
            // The graph's own input, set by a host program between steps.
            let (iface, block) = ExternalInput::build(&mut params)?;
            params.finish()?;
            nodes.push(Node {
                flat: fb,
                iface,
                block: Some(Box::new(block)),
                is_virtual: false,
                width: None,
                label: None,
                absorbed: false,
            });
            continue;
        }
        if ty.name == INPORT || ty.name == OUTPORT {
            for key in ["width", "value"] {
                if params.has(key) {
                    return Err(params.error(key, "only a top-level inport (a host program's input) takes it"));
                }
            }
            params.finish()?;
            let iface =
                Interface::new(SampleTime::Inherited).input("in", Width::Common, true).output("out", Width::Common);
            nodes.push(Node {
                flat: fb,
                iface,
                block: None,
                is_virtual: true,
                width: None,
                label: None,
                absorbed: false,
            });
            continue;
        }
        let built = (ty.build)(&mut params)?;
        params.finish()?;
        nodes.push(Node {
            flat: fb,
            iface: built.iface,
            block: Some(built.block),
            is_virtual: false,
            width: None,
            label: None,
            absorbed: false,
        });
    }
    Ok(nodes)
}

pub(super) fn port_index(node: &Node, ep: &Endpoint, input: bool) -> Result<usize, Diagnostic> {
    let (inputs, outputs) = (&node.iface.inputs, &node.iface.outputs);
    let found = |p: &str| match input {
        true => inputs.iter().position(|q| q.name == p),
        false => outputs.iter().position(|q| q.name == p),
    };
    let ports = if input { inputs.len() } else { outputs.len() };
    match &ep.port {
        _ if node.is_virtual => Ok(0),
        Some(p) => found(p).ok_or_else(|| port_error(node, ep, input)),
        None if ports == 1 => Ok(0),
        None => Err(port_error(node, ep, input)),
    }
}

/// Why an endpoint names no port of its block, with the ports it has.
fn port_error(node: &Node, ep: &Endpoint, input: bool) -> Diagnostic {
    let names: Vec<&str> = if input {
        node.iface.inputs.iter().map(|p| p.name.as_str()).collect()
    } else {
        node.iface.outputs.iter().map(|p| p.name.as_str()).collect()
    };
    let side = if input { "input" } else { "output" };
    let what = format!("block `{}` ({})", node.flat.path, node.flat.spec.type_name);
    match &ep.port {
        Some(p) => {
            let listing =
                if names.is_empty() { format!("it has no {side}s") } else { format!("{side}s: {}", names.join(", ")) };
            Diagnostic::at(&ep.pos, format!("{what} has no {side} `{p}`"))
                .suggest(p, names.iter().copied())
                .or_hint(&listing)
        }
        None if names.is_empty() => Diagnostic::at(&ep.pos, format!("{what} has no {side}s")),
        None => Diagnostic::at(&ep.pos, format!("{what} has {} {side}s: name one as `{}.PORT`", names.len(), ep.block))
            .with_hint(format!("{side}s: {}", names.join(", "))),
    }
}

/// Per node and input port, the wire that feeds it (source may be virtual).
pub(super) fn connect(
    g: &FlatGraph,
    nodes: &[Node],
    index: &HashMap<&str, usize>,
) -> Result<Vec<Vec<Option<Driver>>>, Diagnostic> {
    let mut direct: Vec<Vec<Option<Driver>>> = nodes.iter().map(|n| vec![None; n.iface.inputs.len()]).collect();
    let find = |ep: &Endpoint| -> Result<usize, Diagnostic> {
        index.get(ep.block.as_str()).copied().ok_or_else(|| {
            Diagnostic::at(&ep.pos, format!("no block named `{}`", ep.block)).suggest(&ep.block, index.keys().copied())
        })
    };
    for w in &g.wires {
        let (s, d) = (find(&w.src)?, find(&w.dst)?);
        let sp = port_index(&nodes[s], &w.src, false)?;
        let dp = port_index(&nodes[d], &w.dst, true)?;
        if let Some(prev) = &direct[d][dp] {
            // As the user wrote it: a subsystem's port is `sub.port`, not its inport block.
            let path = &nodes[d].flat.path;
            let shown = match path.rsplit_once('/') {
                Some((sub, port)) if nodes[d].is_virtual => format!("{sub}.{port}"),
                _ => format!("{path}.{}", nodes[d].iface.inputs[dp].name),
            };
            return Err(Diagnostic::at(&w.dst.pos, format!("input `{shown}` is wired twice"))
                .with_hint(format!("it is already fed at line {}; use a `sum` block to add signals", prev.pos.line)));
        }
        direct[d][dp] = Some(Driver { src: s, port: sp, pos: w.dst.pos.clone() });
    }
    Ok(direct)
}

/// Follows wires through inport/outport blocks to the real source of each
/// real block's inputs. Virtual blocks get no drivers of their own.
pub(super) fn resolve_drivers(nodes: &[Node], direct: &[Vec<Option<Driver>>]) -> Result<Vec<Vec<Driver>>, Diagnostic> {
    let unwired = |n: usize, p: usize| {
        let node = &nodes[n];
        let message = if node.is_virtual {
            format!("subsystem port `{}` is not wired", node.flat.path)
        } else {
            format!("input `{}` of block `{}` is not wired", node.iface.inputs[p].name, node.flat.path)
        };
        Diagnostic::at(&node.flat.spec.pos, message).with_hint("every input needs exactly one wire")
    };
    let mut out = Vec::with_capacity(nodes.len());
    for (i, node) in nodes.iter().enumerate() {
        if node.is_virtual {
            out.push(Vec::new());
            continue;
        }
        let mut ports = Vec::with_capacity(direct[i].len());
        for p in 0..direct[i].len() {
            let mut d = direct[i][p].clone().ok_or_else(|| unwired(i, p))?;
            let mut hops = 0;
            while nodes[d.src].is_virtual {
                let pos = d.pos.clone();
                let src = d.src;
                d = direct[src][0].clone().ok_or_else(|| unwired(src, 0))?;
                d.pos = pos;
                hops += 1;
                if hops > nodes.len() {
                    return Err(Diagnostic::at(&node.flat.spec.pos, "subsystem ports are wired in a circle"));
                }
            }
            ports.push(d);
        }
        out.push(ports);
    }
    Ok(out)
}

pub(super) fn resolve_widths(nodes: &mut [Node], drivers: &[Vec<Driver>]) -> Result<(), Diagnostic> {
    let out_width = |nodes: &[Node], d: &Driver| match nodes[d.src].iface.outputs[d.port].width {
        Width::Fixed(n) => Some(n),
        Width::Common => nodes[d.src].width,
    };
    let mut changed = true;
    while changed {
        changed = false;
        for i in 0..nodes.len() {
            for (p, d) in drivers[i].iter().enumerate() {
                let sw = out_width(nodes, d);
                match (nodes[i].iface.inputs[p].width, sw) {
                    (Width::Common, Some(sw)) if nodes[i].width.is_none_or(|w| sw > w) => {
                        nodes[i].width = Some(sw);
                        changed = true;
                    }
                    (Width::Fixed(n), None) if nodes[d.src].iface.outputs[d.port].width == Width::Common => {
                        nodes[d.src].width = Some(n);
                        changed = true;
                    }
                    _ => {}
                }
            }
        }
    }
    for i in 0..nodes.len() {
        for (p, d) in drivers[i].iter().enumerate() {
            let sw = out_width(nodes, d).unwrap_or(1);
            let port = &nodes[i].iface.inputs[p];
            let ok = match port.width {
                Width::Fixed(n) => n == sw,
                Width::Common => sw == 1 || Some(sw) == nodes[i].width,
            };
            if !ok {
                let want = resolved(port.width, nodes[i].width);
                let src = &nodes[d.src];
                return Err(Diagnostic::at(
                    &d.pos,
                    format!(
                        "width mismatch: `{}.{}` carries {sw} value(s) but `{}.{}` takes {want}",
                        src.flat.path, src.iface.outputs[d.port].name, nodes[i].flat.path, port.name
                    ),
                )
                .with_hint("use mux/demux/selector to change widths"));
            }
        }
    }
    for node in nodes.iter_mut().filter(|n| !n.is_virtual && n.iface.has_common_width()) {
        let w = *node.width.get_or_insert(1);
        if let Some(block) = node.block.as_mut() {
            set_common_width(node.flat, &mut **block, w)?;
        }
    }
    Ok(())
}

/// Gives `flat`'s built block its resolved common width; a refusal names the block.
pub(super) fn set_common_width(flat: &FlatBlock, block: &mut dyn Block, width: usize) -> Result<(), Diagnostic> {
    block
        .set_width(width)
        .map_err(|m| Diagnostic::at(&flat.spec.pos, format!("block `{}` ({}): {m}", flat.path, flat.spec.type_name)))
}

/// The columns of the output: the `record:` list, or by default every
/// output of every top-level block.
/// What a subsystem port or outport (a virtual node) passes on.
pub(super) enum Source {
    /// This output port of this real block.
    Real(usize, usize),
    Unwired,
    /// The ports' wires come back to one of them.
    Circle,
}

/// The real block output behind virtual node `start` (through any chain
/// of subsystem ports and outports), bounded so a circle ends.
pub(super) fn real_source(nodes: &[Node], direct: &[Vec<Option<Driver>>], start: usize) -> Source {
    let (mut src, mut port) = (start, 0);
    for _ in 0..=nodes.len() {
        if !nodes[src].is_virtual {
            return Source::Real(src, port);
        }
        let Some(Some(d)) = direct[src].first() else { return Source::Unwired };
        (src, port) = (d.src, d.port);
    }
    Source::Circle
}

/// The real signal on each port of a subsystem, by the names a user
/// writes: `sub.port` (an inport: the signal wired to it; an outport: the
/// signal it exports), and `sub` for a subsystem with one outport; a
/// nested subsystem by its path (`loop/ctrl.u`).
pub(super) fn subsystem_ports(
    g: &FlatGraph,
    nodes: &[Node],
    index: &HashMap<&str, usize>,
    direct: &[Vec<Option<Driver>>],
    out_offset: &[Vec<Port>],
) -> Vec<(String, Port)> {
    let mut named = Vec::new();
    for (sub, (ins, outs)) in &g.subsystems {
        for port in ins.iter().chain(outs) {
            let Some(&start) = index.get(format!("{sub}/{port}").as_str()) else { continue };
            let Source::Real(src, p) = real_source(nodes, direct, start) else { continue };
            named.push((format!("{sub}.{port}"), out_offset[src][p]));
            if outs.len() == 1 && outs.contains(port) {
                named.push((sub.clone(), out_offset[src][p]));
            }
        }
    }
    named.sort_by(|a, b| a.0.cmp(&b.0));
    named
}

/// The real signal behind each top-level outport, by the outport's name.
pub(super) fn external_outputs(
    nodes: &[Node],
    direct: &[Vec<Option<Driver>>],
    out_offset: &[Vec<Port>],
) -> Result<Vec<(String, Port)>, Diagnostic> {
    let mut named = Vec::new();
    for (i, node) in nodes.iter().enumerate() {
        if node.flat.spec.type_name != OUTPORT || node.flat.path.contains('/') {
            continue;
        }
        match real_source(nodes, direct, i) {
            Source::Real(src, p) => named.push((node.flat.path.clone(), out_offset[src][p])),
            Source::Unwired => {}
            Source::Circle => return Err(circle(node)),
        }
    }
    Ok(named)
}

fn circle(node: &Node) -> Diagnostic {
    Diagnostic::at(&node.flat.spec.pos, format!("`{}`: its wire comes back to it through ports only", node.flat.path))
        .with_hint("an outport or a subsystem port passes a signal on: wire a block's output to it")
}

pub(super) fn record_columns(
    g: &FlatGraph,
    nodes: &[Node],
    index: &HashMap<&str, usize>,
    direct: &[Vec<Option<Driver>>],
    out_offset: &[Vec<Port>],
) -> Result<Vec<Column>, Diagnostic> {
    let mut columns: Vec<Column> = Vec::new();
    let mut names: HashSet<String> = HashSet::new();
    let mut push = |name: String, port: Port, pos: Option<&Pos>, unit: Option<String>| -> Result<(), Diagnostic> {
        if name == "t" {
            let message = "`t` is the time column: record this signal under another name".to_string();
            return Err(match pos {
                Some(p) => Diagnostic::at(p, message).with_hint("rename it: `name: block.port`"),
                None => Diagnostic::plain(message),
            });
        }
        if !names.insert(name.clone()) {
            let message = format!("`{name}` is recorded twice");
            return Err(match pos {
                Some(p) => Diagnostic::at(p, message).with_hint("rename one: `other_name: block.port`"),
                None => Diagnostic::plain(message),
            });
        }
        columns.push(Column { name, offset: port.offset, width: port.width, unit });
        Ok(())
    };
    if g.records.is_empty() {
        for (i, n) in nodes.iter().enumerate() {
            if n.is_virtual || n.label.is_some() || n.flat.path.contains('/') {
                continue;
            }
            for (p, port) in n.iface.outputs.iter().enumerate() {
                let name = if n.iface.outputs.len() == 1 {
                    n.flat.path.clone()
                } else {
                    format!("{}.{}", n.flat.path, port.name)
                };
                push(name, out_offset[i][p], None, None)?;
            }
        }
        return Ok(columns);
    }
    for rec in &g.records {
        let (name, ep) = (&rec.name, &rec.signal);
        let mut target = ep.clone();
        if let Some((_, outs)) = g.subsystems.get(&ep.block) {
            let port = resolve_sub_port(ep, outs, "outport")?;
            target = Endpoint { block: format!("{}/{port}", ep.block), port: None, pos: ep.pos.clone() };
        }
        let Some(&i) = index.get(target.block.as_str()) else {
            return Err(Diagnostic::at(&ep.pos, format!("record: no block named `{}`", ep.block))
                .suggest(&ep.block, index.keys().copied()));
        };
        let port = port_index(&nodes[i], &target, false)?;
        let (src, port) = match real_source(nodes, direct, i) {
            _ if !nodes[i].is_virtual => (i, port),
            Source::Real(src, port) => (src, port),
            Source::Unwired => {
                return Err(Diagnostic::at(&ep.pos, format!("record: `{}` is not wired", nodes[i].flat.path)));
            }
            Source::Circle => return Err(circle(&nodes[i])),
        };
        push(name.clone(), out_offset[src][port], Some(&ep.pos), rec.unit.clone())?;
    }
    Ok(columns)
}
