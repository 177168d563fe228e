//! Conditionally executed subsystems collapsed into one block each
//! ([`crate::conditional::Conditional`]): the subsystem's blocks, their
//! inputs from outside, and its `enable` and `trigger` ports' signals.

use super::wiring::{Source, real_source};
use super::{Driver, Node, absorb, loops::topological, resolved};
use crate::block::SampleTime;
use crate::conditional::Conditional;
use crate::diag::Diagnostic;
use crate::flatten::{Condition, ENABLE_PORT, TRIGGER_PORT};
use std::collections::HashMap;

/// The real signal wired to each conditional subsystem's `enable` and
/// `trigger` ports (through any subsystem ports on the way).
pub(super) fn port_drivers(
    nodes: &[Node],
    direct: &[Vec<Option<Driver>>],
    index: &HashMap<&str, usize>,
    c: &Condition,
) -> Result<[Option<Driver>; 2], Diagnostic> {
    let mut found = [None, None];
    for (k, (wanted, name)) in
        [(c.enable.is_some(), ENABLE_PORT), (c.trigger.is_some(), TRIGGER_PORT)].into_iter().enumerate()
    {
        if !wanted {
            continue;
        }
        let path = format!("{}/{name}", c.path);
        let unwired = || {
            Diagnostic::at(&c.pos, format!("subsystem `{}`: its `{name}` port is not wired", c.path))
                .with_hint(format!("wire a signal to it: `- SIGNAL -> {}.{name}`", c.path))
        };
        let at = *index.get(path.as_str()).ok_or_else(unwired)?;
        let Source::Real(src, port) = real_source(nodes, direct, at) else { return Err(unwired()) };
        let d = Driver { src, port, pos: c.pos.clone() };
        let width = resolved(nodes[d.src].iface.outputs[d.port].width, nodes[d.src].width);
        if width != 1 {
            return Err(Diagnostic::at(
                &d.pos,
                format!("subsystem `{}`: `{name}` takes a scalar, wired to {width} values", c.path),
            ));
        }
        found[k] = Some(d);
    }
    Ok(found)
}

/// Moves the subsystem's blocks into one [`Conditional`] block; `pending`
/// (other subsystems' port drivers) follows the rewiring.
pub(super) fn collapse(
    nodes: &mut Vec<Node>,
    drivers: &mut Vec<Vec<Driver>>,
    c: &Condition,
    ports: [Option<Driver>; 2],
    pending: &mut [[Option<Driver>; 2]],
) -> Result<Option<absorb::Installed>, Diagnostic> {
    let prefix = format!("{}/", c.path);
    let members: Vec<usize> = (0..nodes.len())
        .filter(|&i| !nodes[i].is_virtual && !nodes[i].absorbed && nodes[i].flat.path.starts_with(&prefix))
        .collect();
    if members.is_empty() {
        return Ok(None);
    }
    let what = format!("subsystem `{}`", c.path);
    for &m in &members {
        let block = nodes[m].block.as_ref().ok_or_else(|| Diagnostic::plain("internal: block built twice"))?;
        let path = &nodes[m].flat.path;
        if c.trigger.is_some() && block.num_states() > 0 {
            return Err(Diagnostic::at(
                &nodes[m].flat.spec.pos,
                format!("{what} is triggered: `{path}` has continuous states"),
            )
            .with_hint("a triggered subsystem runs only at its trigger's edges: use discrete blocks inside it"));
        }
        if block.keeps_history() {
            return Err(Diagnostic::at(
                &nodes[m].flat.spec.pos,
                format!(
                    "{what}: `{path}` keeps its input's past, which a conditionally executed subsystem cannot hold"
                ),
            ));
        }
    }
    // The members in an order where each follows those it reads at once.
    let edges = absorb::feedthrough_edges(nodes, drivers, &members);
    let order = topological(members.len(), &edges, &[]);
    if order.len() < members.len() {
        return Err(Diagnostic::at(
            &c.pos,
            format!("{what}: an algebraic loop inside a conditionally executed subsystem is not solved yet"),
        )
        .with_hint("break it with a unit_delay or memory block"));
    }
    let mut layout = absorb::lay_out(nodes, drivers, &members, SampleTime::Continuous);
    let [enable, trigger] = ports;
    let enable_input = enable.map(|d| layout.add_input(ENABLE_PORT, d));
    let trigger_input = trigger.map(|d| layout.add_input(TRIGGER_PORT, d));
    let mut built = Vec::with_capacity(members.len());
    for &k in &order {
        let m = members[k];
        let hits = match nodes[m].iface.sample_time {
            SampleTime::Discrete { period, offset } if c.trigger.is_none() => Some((period, offset)),
            _ => None,
        };
        let mut member = layout.member(nodes, m)?;
        member.hits = hits;
        built.push(member);
    }
    let kind = match (c.enable.is_some(), c.trigger.is_some()) {
        (true, true) => "enabled_triggered_subsystem",
        (true, false) => "enabled_subsystem",
        _ => "triggered_subsystem",
    };
    let block = Conditional::new(
        built,
        layout.external.clone(),
        layout.outputs.clone(),
        layout.buffer_len,
        c.enable.zip(enable_input),
        c.trigger.zip(trigger_input),
    );
    let port_of = layout.port_of.clone();
    let installed = absorb::install(nodes, drivers, &members, layout, Box::new(block), c.path.clone(), kind);
    for d in pending.iter_mut().flatten().flatten() {
        if let Some(&k) = port_of.get(&(d.src, d.port)) {
            (d.src, d.port) = (installed.node, k);
        }
    }
    Ok(Some(installed))
}
