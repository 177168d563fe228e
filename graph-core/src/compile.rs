//! From a flat graph to a runnable [`Model`]: build the blocks through the
//! registry, connect the wires (looking through subsystem ports), resolve
//! widths and rates, sort by direct-feedthrough edges and lay out one flat
//! signal buffer with every input resolved to an index.

use crate::block::{Block, Interface, Port, SampleTime, Width};
use crate::diag::{Diagnostic, Pos};
use crate::flatten::{FlatBlock, FlatGraph, INPORT, OUTPORT, SimConfig, resolve_sub_port};
use crate::params::Params;
use crate::registry::Registry;
use crate::spec::Endpoint;
use petgraph::graph::{DiGraph, NodeIndex};
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};
use std::ops::Range;

/// When a compiled block runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rate {
    Constant,
    Continuous,
    /// Index into [`Model::clocks`].
    Discrete(usize),
}

/// What the simulator and the tools need to know of a block.
#[derive(Clone, Debug)]
pub struct BlockMeta {
    pub name: String,
    pub type_name: String,
    pub pos: Pos,
    pub rate: Rate,
    /// The sample time after inheritance is resolved.
    pub sample_time: SampleTime,
    pub inputs: Range<usize>,
    pub outputs: Range<usize>,
    pub states: Range<usize>,
    pub input_names: Vec<String>,
    pub output_names: Vec<String>,
}

/// The part of [`BlockMeta`] the step loop reads, kept compact and
/// contiguous so stepping touches little memory.
#[derive(Clone, Debug)]
pub(crate) struct Slot {
    pub rate: Rate,
    pub states: Range<usize>,
    pub inputs: Range<usize>,
    pub outputs: Range<usize>,
}

/// A recorded signal: its column name and where it lives.
#[derive(Clone, Debug, PartialEq)]
pub struct Column {
    pub name: String,
    pub offset: usize,
    pub width: usize,
}

/// A wire as drawn, for `ctlgraph dot`: (source block, port) → (dest block, port).
#[derive(Clone, Debug, PartialEq)]
pub struct Edge {
    pub src: usize,
    pub src_port: usize,
    pub dst: usize,
    pub dst_port: usize,
    pub feedthrough: bool,
}

/// A compiled graph, blocks in execution order.
pub struct Model {
    pub(crate) blocks: Vec<Box<dyn Block>>,
    pub meta: Vec<BlockMeta>,
    pub(crate) slots: Vec<Slot>,
    pub(crate) in_ports: Vec<Port>,
    pub(crate) out_ports: Vec<Port>,
    pub signal_len: usize,
    pub n_states: usize,
    /// Distinct discrete sample times as (period, offset).
    pub clocks: Vec<(f64, f64)>,
    pub columns: Vec<Column>,
    pub record_every: usize,
    pub edges: Vec<Edge>,
    pub sim: SimConfig,
    pub name: Option<String>,
    pub file: std::sync::Arc<str>,
}

struct Node<'g> {
    flat: &'g FlatBlock,
    iface: Interface,
    block: Option<Box<dyn Block>>,
    is_virtual: bool,
    width: Option<usize>,
}

/// Where a real input gets its value: a real block's output port, and the
/// position of the wire that delivers it.
#[derive(Clone)]
struct Driver {
    src: usize,
    port: usize,
    pos: Pos,
}

/// Compiles a flat graph with the block types of `reg`.
pub fn compile(g: &FlatGraph, reg: &Registry) -> Result<Model, Diagnostic> {
    let mut nodes = instantiate(g, reg)?;
    let index: HashMap<&str, usize> = nodes
        .iter()
        .enumerate()
        .map(|(i, n)| (n.flat.path.as_str(), i))
        .collect();
    let direct = connect(g, &nodes, &index)?;
    let drivers = resolve_drivers(&nodes, &direct)?;
    resolve_widths(&mut nodes, &drivers)?;
    let order = sort(&nodes, &drivers)?;
    let (rates, clocks) = resolve_rates(&nodes, &drivers, &order);

    // Lay out outputs, then point every input at its driver's output.
    let mut out_offset: HashMap<(usize, usize), Port> = HashMap::new();
    let mut signal_len = 0;
    for &i in &order {
        for (p, port) in nodes[i].iface.outputs.iter().enumerate() {
            let width = resolved(port.width, nodes[i].width);
            out_offset.insert(
                (i, p),
                Port {
                    offset: signal_len,
                    width,
                },
            );
            signal_len += width;
        }
    }
    let mut model_blocks = Vec::with_capacity(order.len());
    let mut meta = Vec::with_capacity(order.len());
    let (mut in_ports, mut out_ports) = (Vec::new(), Vec::new());
    let mut n_states = 0;
    let position: HashMap<usize, usize> = order.iter().enumerate().map(|(k, &i)| (i, k)).collect();
    for &i in &order {
        let node = &mut nodes[i];
        let block = node
            .block
            .take()
            .ok_or_else(|| Diagnostic::plain("internal: block built twice"))?;
        let in_start = in_ports.len();
        for d in &drivers[i] {
            in_ports.push(out_offset[&(d.src, d.port)]);
        }
        let out_start = out_ports.len();
        for p in 0..node.iface.outputs.len() {
            out_ports.push(out_offset[&(i, p)]);
        }
        let ns = block.num_states();
        let rate = rates[&i];
        meta.push(BlockMeta {
            name: node.flat.path.clone(),
            type_name: node.flat.spec.type_name.clone(),
            pos: node.flat.spec.pos.clone(),
            rate,
            sample_time: match rate {
                Rate::Constant => SampleTime::Constant,
                Rate::Continuous => SampleTime::Continuous,
                Rate::Discrete(c) => SampleTime::Discrete {
                    period: clocks[c].0,
                    offset: clocks[c].1,
                },
            },
            inputs: in_start..in_ports.len(),
            outputs: out_start..out_ports.len(),
            states: n_states..n_states + ns,
            input_names: node.iface.inputs.iter().map(|p| p.name.clone()).collect(),
            output_names: node.iface.outputs.iter().map(|p| p.name.clone()).collect(),
        });
        n_states += ns;
        model_blocks.push(block);
    }
    let mut edges = Vec::new();
    for &i in &order {
        for (p, d) in drivers[i].iter().enumerate() {
            edges.push(Edge {
                src: position[&d.src],
                src_port: d.port,
                dst: position[&i],
                dst_port: p,
                feedthrough: nodes[i].iface.inputs[p].feedthrough,
            });
        }
    }
    let columns = record_columns(g, &nodes, &index, &direct, &out_offset)?;
    let slots = meta
        .iter()
        .map(|m| Slot {
            rate: m.rate,
            states: m.states.clone(),
            inputs: m.inputs.clone(),
            outputs: m.outputs.clone(),
        })
        .collect();
    Ok(Model {
        blocks: model_blocks,
        meta,
        slots,
        in_ports,
        out_ports,
        signal_len,
        n_states,
        clocks,
        columns,
        record_every: g.record_every,
        edges,
        sim: g.sim.clone(),
        name: g.name.clone(),
        file: g.file.clone(),
    })
}

fn resolved(w: Width, common: Option<usize>) -> usize {
    match w {
        Width::Fixed(n) => n,
        Width::Common => common.unwrap_or(1),
    }
}

fn instantiate<'g>(g: &'g FlatGraph, reg: &Registry) -> Result<Vec<Node<'g>>, Diagnostic> {
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
        let mut params = Params::new(
            &fb.path,
            ty.name,
            &spec.pos,
            &spec.params,
            &fb.scope,
            &fb.dir,
            ty.params,
        );
        if ty.name == INPORT || ty.name == OUTPORT {
            params.finish()?;
            if ty.name == INPORT && !fb.path.contains('/') {
                return Err(Diagnostic::at(
                    &spec.type_pos,
                    format!("block `{}`: an inport only makes sense inside a subsystem", fb.path),
                )
                .with_hint("a top-level graph gets its inputs from source blocks (constant, step, from_csv, …)"));
            }
            let iface = Interface::new(SampleTime::Inherited)
                .input("in", Width::Common, true)
                .output("out", Width::Common);
            nodes.push(Node {
                flat: fb,
                iface,
                block: None,
                is_virtual: true,
                width: None,
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
        });
    }
    Ok(nodes)
}

fn port_index(node: &Node, ep: &Endpoint, input: bool) -> Result<usize, Diagnostic> {
    let names: Vec<&str> = if input {
        node.iface.inputs.iter().map(|p| p.name.as_str()).collect()
    } else {
        node.iface.outputs.iter().map(|p| p.name.as_str()).collect()
    };
    let side = if input { "input" } else { "output" };
    let what = format!("block `{}` ({})", node.flat.path, node.flat.spec.type_name);
    match &ep.port {
        _ if node.is_virtual => Ok(0),
        Some(p) => names.iter().position(|n| n == p).ok_or_else(|| {
            let listing = if names.is_empty() {
                format!("it has no {side}s")
            } else {
                format!("{side}s: {}", names.join(", "))
            };
            Diagnostic::at(&ep.pos, format!("{what} has no {side} `{p}`"))
                .suggest(p, names.iter().copied())
                .or_hint(&listing)
        }),
        None if names.len() == 1 => Ok(0),
        None if names.is_empty() => Err(Diagnostic::at(&ep.pos, format!("{what} has no {side}s"))),
        None => Err(Diagnostic::at(
            &ep.pos,
            format!("{what} has {} {side}s: name one as `{}.PORT`", names.len(), ep.block),
        )
        .with_hint(format!("{side}s: {}", names.join(", ")))),
    }
}

/// Per node and input port, the wire that feeds it (source may be virtual).
fn connect(
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
            let port = &nodes[d].iface.inputs[dp].name;
            return Err(Diagnostic::at(
                &w.dst.pos,
                format!("input `{}.{port}` is wired twice", nodes[d].flat.path),
            )
            .with_hint(format!(
                "it is already fed at line {}; use a `sum` block to add signals",
                prev.pos.line
            )));
        }
        direct[d][dp] = Some(Driver {
            src: s,
            port: sp,
            pos: w.dst.pos.clone(),
        });
    }
    Ok(direct)
}

/// Follows wires through inport/outport blocks to the real source of each
/// real block's inputs. Virtual blocks get no drivers of their own.
fn resolve_drivers(nodes: &[Node], direct: &[Vec<Option<Driver>>]) -> Result<Vec<Vec<Driver>>, Diagnostic> {
    let unwired = |n: usize, p: usize| {
        let node = &nodes[n];
        let message = if node.is_virtual {
            format!("subsystem port `{}` is not wired", node.flat.path)
        } else {
            format!(
                "input `{}` of block `{}` is not wired",
                node.iface.inputs[p].name, node.flat.path
            )
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
                    return Err(Diagnostic::at(
                        &node.flat.spec.pos,
                        "subsystem ports are wired in a circle",
                    ));
                }
            }
            ports.push(d);
        }
        out.push(ports);
    }
    Ok(out)
}

fn resolve_widths(nodes: &mut [Node], drivers: &[Vec<Driver>]) -> Result<(), Diagnostic> {
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
            block.set_width(w).map_err(|m| {
                Diagnostic::at(
                    &node.flat.spec.pos,
                    format!("block `{}` ({}): {m}", node.flat.path, node.flat.spec.type_name),
                )
            })?;
        }
    }
    Ok(())
}

/// Execution order: a topological order of the direct-feedthrough edges,
/// ties broken by declaration order so listings read like the file.
fn sort(nodes: &[Node], drivers: &[Vec<Driver>]) -> Result<Vec<usize>, Diagnostic> {
    let mut graph = DiGraph::<usize, ()>::new();
    let ids: Vec<NodeIndex> = (0..nodes.len()).map(|i| graph.add_node(i)).collect();
    for (i, ds) in drivers.iter().enumerate() {
        for (p, d) in ds.iter().enumerate() {
            if nodes[i].iface.inputs[p].feedthrough {
                graph.update_edge(ids[d.src], ids[i], ());
            }
        }
    }
    let mut indegree: Vec<usize> = ids
        .iter()
        .map(|&n| graph.neighbors_directed(n, petgraph::Direction::Incoming).count())
        .collect();
    let mut ready: BinaryHeap<Reverse<usize>> = (0..nodes.len())
        .filter(|&i| indegree[i] == 0 && !nodes[i].is_virtual)
        .map(Reverse)
        .collect();
    let mut order = Vec::with_capacity(nodes.len());
    while let Some(Reverse(i)) = ready.pop() {
        order.push(i);
        for next in graph.neighbors(ids[i]) {
            let j = graph[next];
            indegree[j] -= 1;
            if indegree[j] == 0 {
                ready.push(Reverse(j));
            }
        }
    }
    let real = nodes.iter().filter(|n| !n.is_virtual).count();
    if order.len() == real {
        return Ok(order);
    }
    // Every strongly connected component with a cycle is an algebraic loop.
    let mut loops = Vec::new();
    for scc in petgraph::algo::tarjan_scc(&graph) {
        let first = scc.iter().map(|&n| graph[n]).min().unwrap_or(0);
        let self_loop = scc.len() == 1 && graph.contains_edge(scc[0], scc[0]);
        if scc.len() > 1 || self_loop {
            let cycle = cycle_through(&graph, ids[first], &scc);
            loops.push(
                cycle
                    .iter()
                    .map(|&n| nodes[graph[n]].flat.path.as_str())
                    .collect::<Vec<_>>(),
            );
        }
    }
    loops.sort();
    let first_block = loops.first().and_then(|l| l.first()).copied().unwrap_or("");
    let pos = nodes
        .iter()
        .find(|n| n.flat.path == first_block)
        .map(|n| n.flat.spec.pos.clone());
    let text: Vec<String> = loops
        .iter()
        .map(|l| format!("{} -> {}", l.join(" -> "), l[0]))
        .collect();
    let message = format!("algebraic loop: {}", text.join("; "));
    let hint = "every block on the loop has direct feedthrough; break it with a block that has none \
                (unit_delay, integrator, a strictly proper transfer_function, an observer)";
    Err(match pos {
        Some(p) => Diagnostic::at(&p, message),
        None => Diagnostic::plain(message),
    }
    .with_hint(hint))
}

/// A simple cycle from `start` back to itself inside one component.
fn cycle_through(graph: &DiGraph<usize, ()>, start: NodeIndex, scc: &[NodeIndex]) -> Vec<NodeIndex> {
    let mut parent: HashMap<NodeIndex, NodeIndex> = HashMap::new();
    let mut queue = std::collections::VecDeque::from([start]);
    while let Some(n) = queue.pop_front() {
        let mut succ: Vec<NodeIndex> = graph.neighbors(n).filter(|s| scc.contains(s)).collect();
        succ.sort_by_key(|s| graph[*s]);
        for s in succ {
            if s == start {
                let mut path = vec![n];
                while let Some(&p) = parent.get(path.last().unwrap_or(&start)) {
                    path.push(p);
                }
                path.reverse();
                return path;
            }
            if let std::collections::hash_map::Entry::Vacant(e) = parent.entry(s) {
                e.insert(n);
                queue.push_back(s);
            }
        }
    }
    vec![start]
}

/// Sample times after inheritance: an inherited block runs at the rate of
/// its drivers if they agree (constants aside), continuously otherwise.
fn resolve_rates(nodes: &[Node], drivers: &[Vec<Driver>], order: &[usize]) -> (HashMap<usize, Rate>, Vec<(f64, f64)>) {
    let mut clocks: Vec<(f64, f64)> = Vec::new();
    let mut rates: HashMap<usize, Rate> = HashMap::new();
    let mut clock = |period: f64, offset: f64| match clocks.iter().position(|&c| c == (period, offset)) {
        Some(c) => c,
        None => {
            clocks.push((period, offset));
            clocks.len() - 1
        }
    };
    for &i in order {
        let has_states = nodes[i].block.as_ref().is_some_and(|b| b.num_states() > 0);
        let rate = match nodes[i].iface.sample_time {
            _ if has_states => Rate::Continuous,
            SampleTime::Continuous => Rate::Continuous,
            SampleTime::Constant => Rate::Constant,
            SampleTime::Discrete { period, offset } => Rate::Discrete(clock(period, offset)),
            SampleTime::Inherited => {
                let mut acc = Rate::Constant;
                for d in &drivers[i] {
                    let r = rates.get(&d.src).copied().unwrap_or(Rate::Continuous);
                    acc = match (acc, r) {
                        (a, Rate::Constant) => a,
                        (Rate::Constant, r) => r,
                        (a, r) if a == r => a,
                        _ => Rate::Continuous,
                    };
                }
                acc
            }
        };
        rates.insert(i, rate);
    }
    (rates, clocks)
}

/// The columns of the output: the `record:` list, or by default every
/// output of every top-level block.
fn record_columns(
    g: &FlatGraph,
    nodes: &[Node],
    index: &HashMap<&str, usize>,
    direct: &[Vec<Option<Driver>>],
    out_offset: &HashMap<(usize, usize), Port>,
) -> Result<Vec<Column>, Diagnostic> {
    let mut columns: Vec<Column> = Vec::new();
    let mut push = |name: String, port: Port, pos: Option<&Pos>| -> Result<(), Diagnostic> {
        if columns.iter().any(|c| c.name == name) {
            let message = format!("`{name}` is recorded twice");
            return Err(match pos {
                Some(p) => Diagnostic::at(p, message).with_hint("rename one: `other_name: block.port`"),
                None => Diagnostic::plain(message),
            });
        }
        columns.push(Column {
            name,
            offset: port.offset,
            width: port.width,
        });
        Ok(())
    };
    if g.records.is_empty() {
        for (i, n) in nodes.iter().enumerate() {
            if n.is_virtual || n.flat.path.contains('/') {
                continue;
            }
            for (p, port) in n.iface.outputs.iter().enumerate() {
                let name = if n.iface.outputs.len() == 1 {
                    n.flat.path.clone()
                } else {
                    format!("{}.{}", n.flat.path, port.name)
                };
                push(name, out_offset[&(i, p)], None)?;
            }
        }
        return Ok(columns);
    }
    for (name, ep) in &g.records {
        let mut target = ep.clone();
        if let Some((_, outs)) = g.subsystems.get(&ep.block) {
            let port = resolve_sub_port(ep, outs, "outport")?;
            target = Endpoint {
                block: format!("{}/{port}", ep.block),
                port: None,
                pos: ep.pos.clone(),
            };
        }
        let Some(&i) = index.get(target.block.as_str()) else {
            return Err(
                Diagnostic::at(&ep.pos, format!("record: no block named `{}`", ep.block))
                    .suggest(&ep.block, index.keys().copied()),
            );
        };
        let (mut src, mut port) = (i, port_index(&nodes[i], &target, false)?);
        while nodes[src].is_virtual {
            let Some(d) = &direct[src][0] else {
                return Err(Diagnostic::at(
                    &ep.pos,
                    format!("record: `{}` is not wired", nodes[src].flat.path),
                ));
            };
            (src, port) = (d.src, d.port);
        }
        push(name.clone(), out_offset[&(src, port)], Some(&ep.pos))?;
    }
    Ok(columns)
}

impl Model {
    /// Column headers: `t`, then each recorded name (`name[k]`, 1-based, for
    /// vector signals).
    pub fn headers(&self) -> Vec<String> {
        let mut h = vec!["t".to_string()];
        for c in &self.columns {
            if c.width == 1 {
                h.push(c.name.clone());
            } else {
                h.extend((1..=c.width).map(|k| format!("{}[{k}]", c.name)));
            }
        }
        h
    }

    /// The block owning signal `offset` and the name of its output port.
    pub fn signal_owner(&self, offset: usize) -> Option<(&BlockMeta, &str)> {
        self.meta.iter().find_map(|m| {
            m.outputs.clone().find_map(|p| {
                let port = self.out_ports[p];
                (port.offset..port.offset + port.width)
                    .contains(&offset)
                    .then(|| (m, m.output_names[p - m.outputs.start].as_str()))
            })
        })
    }
}
