//! From a flat graph to a runnable [`Model`]: build the blocks through the
//! registry, connect the wires (looking through subsystem ports), resolve
//! widths and rates, sort by direct-feedthrough edges and lay out one flat
//! signal buffer with every input resolved to an index.

mod absorb;
mod advice;
mod between;
mod conditional;
mod external;
mod loops;
mod reuse;
mod schedule;
mod wiring;

use crate::block::{Block, Interface, Port, SampleTime, Width};
use crate::diag::{Diagnostic, Pos};
use crate::flatten::{AlgebraicLoops, FlatBlock, FlatGraph, INPORT, MAX_STEPS, SimConfig};
use crate::registry::Registry;
pub(crate) use between::Between;
pub use reuse::{recompile, reuse_structure};
use schedule::{feedthrough_loops, loop_error, resolve_rates, sort};
use std::collections::HashMap;
use std::ops::Range;
use wiring::{connect, instantiate, record_columns, resolve_drivers, resolve_widths};

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
    /// A continuous LTI block advanced by its exact zero-order-hold
    /// transition between major steps instead of being integrated.
    pub exact_zoh: bool,
    /// Its interface declares the outputs constant between major steps
    /// while the inputs are ([`crate::Interface::piecewise_constant`]).
    pub piecewise_constant: bool,
}

/// A block running inside another (an algebraic loop's, a conditionally
/// executed subsystem's): its names, and where its outputs are in the
/// signal buffer.
#[derive(Clone, Debug)]
pub struct InnerBlock {
    pub name: String,
    pub type_name: String,
    /// The block it runs in, an index into [`Model::meta`].
    pub container: usize,
    pub input_names: Vec<String>,
    pub output_names: Vec<String>,
    pub outputs: Vec<Port>,
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

/// A recorded signal: its column name, where it lives, its unit.
#[derive(Clone, Debug, PartialEq)]
pub struct Column {
    pub name: String,
    pub offset: usize,
    pub width: usize,
    pub unit: Option<String>,
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
    /// The graph's acceptance conditions, compiled against `columns`.
    pub checks: Vec<crate::checks::Check>,
    /// Plot panels over `columns` (empty: one panel per recorded name).
    pub scopes: Vec<crate::scope::Scope>,
    pub edges: Vec<Edge>,
    pub sim: SimConfig,
    /// The top-level parameters after `--set` overrides, in file order.
    pub parameters: Vec<(String, f64)>,
    pub name: Option<String>,
    pub file: std::sync::Arc<str>,
    /// What the solver's minor steps evaluate, integrate and hold.
    pub(crate) between: Between,
    /// The `analysis:` section, its signals checked.
    pub analysis: Option<crate::spec::Selection>,
    /// The analysed loop's figures for the checks, indexed by
    /// [`crate::checks::metrics::LoopFigure`] (filled in by whoever can
    /// linearise: `ctlgraph::compile_flat`).
    pub loop_figures: Option<Vec<f64>>,
    /// Subsystem ports by name (`sub.port`, `sub`, `outer/inner.port`) and
    /// the real signal on each (for analysis selections, `Simulator::signal`
    /// and a controller's terminals in `codegen --target c`).
    pub subsystem_ports: Vec<(String, Port)>,
    /// The graph's own inputs, its top-level `inport` blocks: name and
    /// block index (see [`crate::Simulator::set_input`]).
    pub external_inputs: Vec<(String, usize)>,
    /// The graph's own outputs, its top-level `outport` blocks: name and
    /// the signal each carries.
    pub external_outputs: Vec<(String, Port)>,
    /// The smallest dead time on a feedback loop and its block: the
    /// adaptive methods' default `max_step` stays below it.
    pub loop_dead_time: Option<(f64, usize)>,
    /// What `check` and `run` warn about (module `advice`).
    pub warnings: Vec<String>,
    /// Each algebraic loop solved at every evaluation, as `check` lists
    /// it: its blocks and the signals it is solved for.
    pub algebraic_loops: Vec<String>,
    /// The blocks that run inside another block (an algebraic loop's, a
    /// conditionally executed subsystem's), which [`Model::meta`] lists in
    /// their place.
    pub inner_blocks: Vec<InnerBlock>,
    /// What another loaded graph must share to be compiled on this one's
    /// structure ([`recompile`]).
    pub(crate) structure: reuse::Structure,
}

struct Node<'g> {
    flat: &'g FlatBlock,
    iface: Interface,
    block: Option<Box<dyn Block>>,
    is_virtual: bool,
    width: Option<usize>,
    /// A block holding others ([`absorb`]): its name and type (`flat` is
    /// its first member's, for positions).
    label: Option<(String, &'static str)>,
    /// A member of an algebraic loop: it runs inside the loop's block.
    absorbed: bool,
}

impl Node<'_> {
    /// Its name: a containing block's label, else its path.
    fn name(&self) -> &str {
        self.label.as_ref().map_or(self.flat.path.as_str(), |l| l.0.as_str())
    }
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
    let index: HashMap<&str, usize> = nodes.iter().enumerate().map(|(i, n)| (n.flat.path.as_str(), i)).collect();
    let direct = connect(g, &nodes, &index)?;
    let mut drivers = resolve_drivers(&nodes, &direct)?;
    resolve_widths(&mut nodes, &drivers)?;
    // Conditionally executed subsystems, innermost first, then algebraic
    // loops: each becomes one block holding its members.
    let mut pending = g
        .conditions
        .iter()
        .map(|c| conditional::port_drivers(&nodes, &direct, &index, c))
        .collect::<Result<Vec<_>, _>>()?;
    let mut containers = Vec::new();
    for k in (0..g.conditions.len()).rev() {
        let (outer, rest) = pending.split_at_mut(k);
        let ports = rest[0].clone();
        containers.extend(conditional::collapse(&mut nodes, &mut drivers, &g.conditions[k], ports, outer)?);
    }
    let found = feedthrough_loops(&nodes, &drivers);
    if !found.is_empty() && g.sim.algebraic_loops == AlgebraicLoops::Error {
        return Err(loop_error(&nodes, &found));
    }
    let mut loop_descriptions = Vec::with_capacity(found.len());
    for l in &found {
        let collapsed = loops::collapse(&mut nodes, &mut drivers, l, loops::tolerance(&g.sim.method))?;
        loop_descriptions.push(collapsed.description);
        containers.push(collapsed.installed);
    }
    let order = sort(&nodes, &drivers)?;
    let (rates, clocks) = resolve_rates(&nodes, &drivers, &order);
    for (i, node) in nodes.iter().enumerate() {
        let spacing = node.block.as_ref().map_or(f64::INFINITY, |b| b.min_event_spacing());
        let period = match rates.get(&i) {
            Some(Rate::Discrete(c)) => Some(clocks[*c].0),
            _ => None,
        };
        refuse_too_many_steps(node, g.sim.stop, spacing, period)?;
    }

    // Lay out outputs, then point every input at its driver's output.
    // Per node, where each output port lives in the signal buffer.
    let mut out_offset: Vec<Vec<Port>> = vec![Vec::new(); nodes.len()];
    let mut signal_len = 0;
    for &i in &order {
        for (p, port) in nodes[i].iface.outputs.iter().enumerate() {
            let width = resolved(port.width, nodes[i].width);
            debug_assert_eq!(out_offset[i].len(), p);
            out_offset[i].push(Port { offset: signal_len, width });
            signal_len += width;
        }
    }
    // Members' outputs are their container's (outer containers first:
    // an inner one is a member of the outer).
    for c in containers.iter().rev() {
        for &((member, port), k) in &c.outputs {
            let at = out_offset[c.node][k];
            let ports = &mut out_offset[member];
            if ports.len() <= port {
                ports.resize(port + 1, at);
            }
            ports[port] = at;
        }
    }
    let mut model_blocks = Vec::with_capacity(order.len());
    let mut meta = Vec::with_capacity(order.len());
    let (mut in_ports, mut out_ports) = (Vec::new(), Vec::new());
    let mut n_states = 0;
    // Node index → place in the execution order.
    let mut position = vec![0; nodes.len()];
    for (k, &i) in order.iter().enumerate() {
        position[i] = k;
    }
    for &i in &order {
        let node = &mut nodes[i];
        let block = node.block.take().ok_or_else(|| Diagnostic::plain("internal: block built twice"))?;
        let in_start = in_ports.len();
        for d in &drivers[i] {
            in_ports.push(out_offset[d.src][d.port]);
        }
        let out_start = out_ports.len();
        out_ports.extend_from_slice(&out_offset[i]);
        let ns = block.num_states();
        let rate = rates[&i];
        meta.push(BlockMeta {
            name: node.name().to_string(),
            type_name: node.label.as_ref().map_or_else(|| node.flat.spec.type_name.clone(), |l| l.1.to_string()),
            pos: node.flat.spec.pos.clone(),
            rate,
            sample_time: match rate {
                Rate::Constant => SampleTime::Constant,
                Rate::Continuous => SampleTime::Continuous,
                Rate::Discrete(c) => SampleTime::Discrete { period: clocks[c].0, offset: clocks[c].1 },
            },
            inputs: in_start..in_ports.len(),
            outputs: out_start..out_ports.len(),
            states: n_states..n_states + ns,
            input_names: node.iface.inputs.iter().map(|p| p.name.clone()).collect(),
            output_names: node.iface.outputs.iter().map(|p| p.name.clone()).collect(),
            exact_zoh: false,
            piecewise_constant: node.iface.piecewise_constant,
        });
        n_states += ns;
        model_blocks.push(block);
    }
    let mut edges = Vec::new();
    for &i in &order {
        for (p, d) in drivers[i].iter().enumerate() {
            edges.push(Edge {
                src: position[d.src],
                src_port: d.port,
                dst: position[i],
                dst_port: p,
                feedthrough: nodes[i].iface.inputs[p].feedthrough,
            });
        }
    }
    let columns = record_columns(g, &nodes, &index, &direct, &out_offset)?;
    let subsystem_ports = wiring::subsystem_ports(g, &nodes, &index, &direct, &out_offset);
    let external_inputs = order
        .iter()
        .enumerate()
        .filter(|&(_, &i)| nodes[i].flat.spec.type_name == INPORT && !nodes[i].flat.path.contains('/'))
        .map(|(k, &i)| (nodes[i].flat.path.clone(), k))
        .collect();
    let external_outputs = wiring::external_outputs(&nodes, &direct, &out_offset)?;
    let slots = meta
        .iter()
        .map(|m| Slot { rate: m.rate, states: m.states.clone(), inputs: m.inputs.clone(), outputs: m.outputs.clone() })
        .collect();
    let checks = crate::checks::compile(&g.checks, &headers(&columns), &g.parameters, g.analysis.is_some())?;
    for scope in &g.scopes {
        for (name, pos) in &scope.signals {
            if !columns.iter().any(|c| &c.name == name) {
                return Err(Diagnostic::at(pos, format!("scope: `{name}` is not recorded"))
                    .suggest(name, columns.iter().map(|c| c.name.as_str()))
                    .or_hint("a scope shows recorded signals by their `record:` names"));
            }
        }
    }
    let mut model = Model {
        checks,
        scopes: g.scopes.clone(),
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
        parameters: g.parameters.clone(),
        name: g.name.clone(),
        file: g.file.clone(),
        between: Between::default(),
        analysis: g.analysis.clone(),
        loop_figures: None,
        subsystem_ports,
        external_inputs,
        external_outputs,
        loop_dead_time: None,
        warnings: Vec::new(),
        algebraic_loops: loop_descriptions,
        inner_blocks: absorb::inner_blocks(&nodes, &containers, &position, &out_offset),
        structure: reuse::Structure::of(g, &nodes, &order),
    };
    plan_and_advise(&mut model);
    if g.sim.algebraic_loops == AlgebraicLoops::Warn {
        let notes = model
            .algebraic_loops
            .iter()
            .map(|d| format!("{d}; `algebraic_loops: solve` under `simulation:` silences this"));
        model.warnings.extend(notes);
    }
    if let Some(sel) = &model.analysis {
        for name in [&sel.input, &sel.output, &sel.open].into_iter().flatten() {
            if let Err(d) = model.signal_offset(name) {
                let pos = sel.pos.clone();
                return Err(Diagnostic { pos, message: format!("analysis: {}", d.message), ..d });
            }
        }
    }
    Ok(model)
}

fn headers(columns: &[Column]) -> Vec<String> {
    let mut h = vec!["t".to_string()];
    for c in columns {
        if c.width == 1 {
            h.push(c.name.clone());
        } else {
            h.extend((1..=c.width).map(|k| format!("{}[{k}]", c.name)));
        }
    }
    h
}

fn resolved(w: Width, common: Option<usize>) -> usize {
    match w {
        Width::Fixed(n) => n,
        Width::Common => common.unwrap_or(1),
    }
}

impl Model {
    /// Block `i` as compiled: its parameters and initial memory (each run
    /// works on its own copy, see [`crate::RunState`]).
    pub fn block(&self, i: usize) -> &dyn Block {
        &*self.blocks[i]
    }

    /// Where block `i`'s inputs are in the signal buffer, in port order.
    pub fn input_ports(&self, i: usize) -> &[Port] {
        &self.in_ports[self.meta[i].inputs.clone()]
    }

    /// Where block `i`'s outputs are in the signal buffer, in port order.
    pub fn output_ports(&self, i: usize) -> &[Port] {
        &self.out_ports[self.meta[i].outputs.clone()]
    }

    /// Column headers: `t`, then each recorded name (`name[k]`, 1-based, for
    /// vector signals).
    pub fn headers(&self) -> Vec<String> {
        headers(&self.columns)
    }

    /// How many continuous states the solver integrates; the others belong
    /// to LTI blocks stepped by their exact zero-order-hold transition.
    pub fn integrated_states(&self) -> usize {
        self.between.n_integrated
    }

    /// The signal buffer offset of `name`: `block`, `block.port`, with `[k]`
    /// (1-based) for an element of a vector signal.
    pub fn signal_offset(&self, name: &str) -> Result<usize, Diagnostic> {
        let port = self.signal_port(name)?;
        match port.width {
            1 => Ok(port.offset),
            w => Err(Diagnostic::plain(format!("signal `{name}` has {w} elements"))
                .with_hint(format!("analyse one: `{name}[1]` … `{name}[{w}]`"))),
        }
    }

    /// Where signal `name` lives in the signal buffer: `block`,
    /// `block.port`, `sub.port` of a top-level subsystem, the whole vector
    /// or, with `[k]` (1-based), one element.
    pub fn signal_port(&self, name: &str) -> Result<Port, Diagnostic> {
        let model = self;
        let (base, element) = match name.strip_suffix(']').and_then(|n| n.split_once('[')) {
            Some((b, k)) => {
                let k: usize = k.parse().ok().filter(|k| *k >= 1).ok_or_else(|| {
                    Diagnostic::plain(format!("signal `{name}`: `[{k}]` is not an element number (1, 2, …)"))
                })?;
                (b, Some(k))
            }
            None => (name, None),
        };
        let port = match model.subsystem_ports.binary_search_by(|(n, _)| n.as_str().cmp(base)) {
            Ok(k) => model.subsystem_ports[k].1,
            Err(_) => model.block_output(name, base)?,
        };
        match element {
            None => Ok(port),
            Some(k) if k <= port.width => Ok(Port { offset: port.offset + k - 1, width: 1 }),
            Some(k) => Err(Diagnostic::plain(format!("signal `{name}`: element {k} of {}", port.width))),
        }
    }

    /// The output port `base` names (`block` or `block.port`); `name` is
    /// the whole signal name, for messages.
    fn block_output(&self, name: &str, base: &str) -> Result<Port, Diagnostic> {
        let model = self;
        if let Some(port) = self.inner_block_output(name, base)? {
            return Ok(port);
        }
        let (block, port) = match model.meta.iter().position(|m| m.name == base) {
            Some(i) => (i, None),
            None => match base.rsplit_once('.') {
                Some((b, p)) => {
                    let i = model.meta.iter().position(|m| m.name == b).ok_or_else(|| {
                        Diagnostic::plain(format!("signal `{name}`: no block `{b}`"))
                            .suggest(b, model.meta.iter().map(|m| m.name.as_str()))
                    })?;
                    (i, Some(p))
                }
                None => {
                    return Err(Diagnostic::plain(format!("signal `{name}`: no block `{base}`"))
                        .suggest(base, model.meta.iter().map(|m| m.name.as_str())));
                }
            },
        };
        let meta = &model.meta[block];
        let k = match port {
            Some(p) => meta.output_names.iter().position(|n| n == p).ok_or_else(|| {
                Diagnostic::plain(format!("signal `{name}`: block `{}` has no output `{p}`", meta.name))
                    .with_hint(format!("its outputs: {}", meta.output_names.join(", ")))
            })?,
            None if meta.output_names.len() == 1 => 0,
            None => {
                return Err(Diagnostic::plain(format!("signal `{name}`: block `{}` has several outputs", meta.name))
                    .with_hint(format!(
                        "name one: {}",
                        meta.output_names.iter().map(|p| format!("{base}.{p}")).collect::<Vec<_>>().join(", ")
                    )));
            }
        };
        Ok(model.out_ports[meta.outputs.start + k])
    }

    /// [`Model::block_output`] of a block inside another.
    fn inner_block_output(&self, name: &str, base: &str) -> Result<Option<Port>, Diagnostic> {
        let by_name = |n: &str| self.inner_blocks.iter().find(|m| m.name == n);
        if let Some(m) = by_name(base) {
            return match m.outputs[..] {
                [port] => Ok(Some(port)),
                _ => Err(Diagnostic::plain(format!("signal `{name}`: block `{base}` has several outputs")).with_hint(
                    format!(
                        "name one: {}",
                        m.output_names.iter().map(|p| format!("{base}.{p}")).collect::<Vec<_>>().join(", ")
                    ),
                )),
            };
        }
        let Some((b, p)) = base.rsplit_once('.') else { return Ok(None) };
        let Some(m) = by_name(b) else { return Ok(None) };
        match m.output_names.iter().position(|n| n == p) {
            Some(k) => Ok(Some(m.outputs[k])),
            None => Err(Diagnostic::plain(format!("signal `{name}`: block `{b}` has no output `{p}`"))
                .with_hint(format!("its outputs: {}", m.output_names.join(", ")))),
        }
    }

    /// Each block's report of what it decided when built (see
    /// [`Block::build_report`]), in execution order.
    pub fn build_reports(&self) -> impl Iterator<Item = (&str, String)> {
        self.meta.iter().zip(&self.blocks).filter_map(|(m, b)| b.build_report().map(|r| (m.name.as_str(), r)))
    }

    /// A copy of block `name` (flattened: `ctrl/td`) as its concrete type
    /// `T`, in its built state; `None` when there is no such block or it
    /// is not a `T`. Where a fused step starts: code that knows the
    /// graph's block types calls them without dynamic dispatch, with the
    /// parameters the graph gave them.
    pub fn block_as<T: Block + Clone>(&self, name: &str) -> Option<T> {
        self.block_at(self.meta.iter().position(|m| m.name == name)?)
    }

    /// A copy of the block at `index` (execution order) as its concrete
    /// type `T`; `None` when there is none or it is not a `T`.
    pub fn block_at<T: Block + Clone>(&self, index: usize) -> Option<T> {
        let block: &dyn std::any::Any = &**self.blocks.get(index)?;
        block.downcast_ref::<T>().cloned()
    }

    /// A copy of the block at `index` (execution order), for code that
    /// calls it without knowing its type.
    pub fn block_boxed(&self, index: usize) -> Option<Box<dyn Block>> {
        self.blocks.get(index).map(|b| dyn_clone::clone_box(&**b))
    }

    /// The block owning signal `offset` and the name of its output port.
    pub fn signal_owner(&self, offset: usize) -> Option<(usize, &str)> {
        signal_owner(&self.meta, &self.out_ports, offset)
    }
}

/// The block (index into `meta`) owning signal `offset`, and the name of
/// its output port.
pub(crate) fn signal_owner<'m>(meta: &'m [BlockMeta], out_ports: &[Port], offset: usize) -> Option<(usize, &'m str)> {
    meta.iter().enumerate().find_map(|(i, m)| {
        m.outputs.clone().find_map(|p| {
            let port = out_ports[p];
            (port.offset..port.offset + port.width)
                .contains(&offset)
                .then(|| (i, m.output_names[p - m.outputs.start].as_str()))
        })
    })
}

/// Refuses a block whose events (`event_spacing` apart) or sample hits
/// (`period` apart) would need more than [`MAX_STEPS`] to reach the stop
/// time (the run would never end in practice).
fn refuse_too_many_steps(node: &Node, stop: f64, event_spacing: f64, period: Option<f64>) -> Result<(), Diagnostic> {
    let refuse = |interval: f64, what: &dyn Fn(f64) -> String| {
        let steps = stop / interval;
        if steps <= MAX_STEPS {
            return Ok(());
        }
        Err(Diagnostic::at(
            &node.flat.spec.pos,
            format!("block `{}`: {} before the stop time {stop} s (limit {MAX_STEPS:e})", node.flat.path, what(steps)),
        ))
    };
    refuse(event_spacing, &|n| format!("events {event_spacing:e} s apart give {n:e} steps"))?;
    match period {
        Some(period) => refuse(period, &|n| format!("a sample time of {period:e} s gives {n:e} hits")),
        None => Ok(()),
    }
}

/// The plan between major steps and the advice, from the model's blocks
/// as they are built (after a full compile, or new blocks on a structure).
fn plan_and_advise(model: &mut Model) {
    between::plan(model);
    model.loop_dead_time = advice::loop_dead_time(model);
    model.warnings = advice::warnings(model);
}
