//! Algebraic loops collapsed into one block each: the blocks of a
//! strongly connected component of direct-feedthrough edges move into an
//! [`AlgebraicLoop`], which solves for the loop's cut signals at every
//! evaluation. The rest of the compiler, the driver and the generated step
//! then see one block, whose outputs are its members' (each member's
//! outputs keep their names: records, scopes and wires reach them as
//! before).

use super::schedule::FeedthroughLoop;
use super::{Driver, Node, resolved};
use crate::algebraic::{AlgebraicLoop, Member};
use crate::block::{Interface, Port, SampleTime, Width};
use crate::diag::Diagnostic;
use std::collections::HashMap;

/// Largest loop whose cut is searched exhaustively for the fewest blocks;
/// beyond it, greedily.
const EXHAUSTIVE_CUT: usize = 16;

/// A loop collapsed into node `node`: where each member's outputs went
/// (member, its port → the loop block's port), and how `check` names it.
pub(super) struct Collapsed {
    pub node: usize,
    pub outputs: Vec<((usize, usize), usize)>,
    pub description: String,
    pub members: Vec<usize>,
}

/// Moves the loop's blocks into a new node (pushed onto `nodes`, its
/// drivers onto `drivers`), and points every wire from a member at it.
pub(super) fn collapse(
    nodes: &mut Vec<Node>,
    drivers: &mut Vec<Vec<Driver>>,
    found: &FeedthroughLoop,
    tolerance: f64,
) -> Result<Collapsed, Diagnostic> {
    let members = &found.members;
    let text = found.text(nodes);
    let at = |nodes: &[Node], message: String| Diagnostic::at(&nodes[members[0]].flat.spec.pos, message);
    let sample_time = common_rate(nodes, members).map_err(|m| at(nodes, format!("algebraic loop {text}: {m}")))?;
    if let Some(&m) = members.iter().find(|&&m| nodes[m].block.as_ref().is_some_and(|b| b.keeps_history())) {
        let message =
            format!("algebraic loop {text}: `{}` keeps its input's past and cannot be solved for", nodes[m].flat.path);
        return Err(at(nodes, message).with_hint("break the loop with a block without feedthrough"));
    }
    let is_member: HashMap<usize, usize> = members.iter().enumerate().map(|(k, &m)| (m, k)).collect();
    // Feedthrough edges inside the loop, as member positions.
    let mut edges = Vec::new();
    for (k, &m) in members.iter().enumerate() {
        for (p, d) in drivers[m].iter().enumerate() {
            if let Some(&from) = is_member.get(&d.src).filter(|_| nodes[m].iface.inputs[p].feedthrough) {
                edges.push((from, k));
            }
        }
    }
    let widths = |nodes: &[Node], m: usize| -> Vec<usize> {
        nodes[m].iface.outputs.iter().map(|p| resolved(p.width, nodes[m].width)).collect()
    };
    let cut = cut_set(members.len(), &edges, |k| widths(nodes, members[k]).iter().sum());
    let order = evaluation_order(members.len(), &edges, &cut);

    // The loop block's inputs: each member input driven from outside.
    let mut iface = Interface::new(sample_time);
    let mut outer_drivers = Vec::new();
    let mut buffer_len = 0;
    let mut place = |width: usize| {
        buffer_len += width;
        Port { offset: buffer_len - width, width }
    };
    let mut external = Vec::new();
    let mut input_place: HashMap<(usize, usize), Port> = HashMap::new();
    for &m in members {
        for (p, d) in drivers[m].iter().enumerate() {
            if is_member.contains_key(&d.src) {
                continue;
            }
            let port = &nodes[m].iface.inputs[p];
            let width = resolved(port.width, nodes[m].width);
            let name = format!("{}.{}", nodes[m].flat.path, port.name);
            iface = iface.input(&name, Width::Fixed(width), port.feedthrough);
            outer_drivers.push(d.clone());
            let slot = place(width);
            external.push(slot);
            input_place.insert((m, p), slot);
        }
    }
    // Its outputs: every member's, in member order.
    let mut output_place: HashMap<(usize, usize), Port> = HashMap::new();
    let mut outputs = Vec::new();
    let mut loop_outputs = Vec::new();
    for &m in members {
        for (q, w) in widths(nodes, m).into_iter().enumerate() {
            let name = format!("{}.{}", nodes[m].flat.path, nodes[m].iface.outputs[q].name);
            iface = iface.output(&name, Width::Fixed(w));
            let slot = place(w);
            output_place.insert((m, q), slot);
            outputs.push(((m, q), loop_outputs.len()));
            loop_outputs.push(slot);
        }
    }
    // The members, in evaluation order, their ports in the loop's buffer.
    let mut built = Vec::with_capacity(members.len());
    let mut unknowns = Vec::new();
    for &k in &order {
        let m = members[k];
        let ins = drivers[m]
            .iter()
            .enumerate()
            .map(|(p, d)| input_place.get(&(m, p)).copied().unwrap_or_else(|| output_place[&(d.src, d.port)]))
            .collect();
        let outs: Vec<Port> = (0..nodes[m].iface.outputs.len()).map(|q| output_place[&(m, q)]).collect();
        if cut.contains(&k) {
            unknowns.extend(outs.iter().copied());
        }
        let block = nodes[m].block.take().ok_or_else(|| Diagnostic::plain("internal: block built twice"))?;
        built.push(Member::new(nodes[m].flat.path.clone(), block, ins, outs));
    }
    let cut_names: Vec<String> = order
        .iter()
        .filter(|k| cut.contains(k))
        .flat_map(|&k| {
            let m = members[k];
            let many = nodes[m].iface.outputs.len() > 1;
            nodes[m].iface.outputs.iter().map(move |p| (m, many, p.name.clone()))
        })
        .map(|(m, many, port)| if many { format!("{}.{port}", nodes[m].flat.path) } else { nodes[m].flat.path.clone() })
        .collect();
    let n_unknowns: usize = unknowns.iter().map(|p| p.width).sum();
    let description = format!(
        "algebraic loop {text}: solved for {} at every evaluation ({n_unknowns} unknown{})",
        cut_names.join(", "),
        if n_unknowns == 1 { "" } else { "s" }
    );
    let solver = AlgebraicLoop::new(text, built, cut.len(), external, loop_outputs, unknowns, buffer_len, tolerance);

    // Wires from the members now leave the loop block.
    let node = nodes.len();
    let port_of: HashMap<(usize, usize), usize> = outputs.iter().copied().collect();
    for ds in drivers.iter_mut() {
        for d in ds.iter_mut().filter(|d| is_member.contains_key(&d.src)) {
            d.port = port_of[&(d.src, d.port)];
            d.src = node;
        }
    }
    for &m in members {
        drivers[m].clear();
        nodes[m].absorbed = true;
    }
    let first = nodes[members[0]].flat;
    let label = Some(format!("algebraic loop {}", found.text(nodes)));
    nodes.push(Node {
        flat: first,
        iface,
        block: Some(Box::new(solver)),
        is_virtual: false,
        width: None,
        label,
        absorbed: false,
    });
    drivers.push(outer_drivers);
    Ok(Collapsed { node, outputs, description, members: members.clone() })
}

/// The one rate of the loop's blocks: a loop through different sample
/// times has no instant at which all its equations hold.
fn common_rate(nodes: &[Node], members: &[usize]) -> Result<SampleTime, String> {
    let mut rate = SampleTime::Inherited;
    let mut from = "";
    for &m in members {
        let own = nodes[m].iface.sample_time;
        let own =
            if nodes[m].block.as_ref().is_some_and(|b| b.num_states() > 0) { SampleTime::Continuous } else { own };
        match (rate, own) {
            (_, SampleTime::Inherited | SampleTime::Constant) => {}
            (SampleTime::Inherited, _) => (rate, from) = (own, nodes[m].flat.path.as_str()),
            (a, b) if a == b => {}
            (a, b) => {
                return Err(format!(
                    "`{from}` runs {a} and `{}` {b}: a loop through different sample times has no instant at \
                     which all its equations hold; break it with a unit_delay or memory",
                    nodes[m].flat.path
                ));
            }
        }
    }
    Ok(rate)
}

/// A smallest set of members whose outputs, taken as unknowns, leave the
/// rest acyclic (a minimum feedback vertex set): by increasing size, the
/// fewest unknown values among equals, for loops up to
/// [`EXHAUSTIVE_CUT`] blocks; beyond, greedily by the most edges in and out.
fn cut_set(n: usize, edges: &[(usize, usize)], width: impl Fn(usize) -> usize) -> Vec<usize> {
    if n <= EXHAUSTIVE_CUT {
        for size in 1..=n {
            let mut best: Option<(usize, Vec<usize>)> = None;
            for set in subsets(n, size) {
                if acyclic_without(n, edges, &set) {
                    let cost = set.iter().map(|&k| width(k)).sum();
                    if best.as_ref().is_none_or(|(c, _)| cost < *c) {
                        best = Some((cost, set));
                    }
                }
            }
            if let Some((_, set)) = best {
                return set;
            }
        }
    }
    let mut cut = Vec::new();
    while !acyclic_without(n, edges, &cut) {
        let live = |(a, b): &&(usize, usize)| !cut.contains(a) && !cut.contains(b);
        let degree = |k: usize| {
            let ins = edges.iter().filter(live).filter(|e| e.1 == k).count();
            let outs = edges.iter().filter(live).filter(|e| e.0 == k).count();
            ins * outs
        };
        let Some(k) = (0..n).filter(|k| !cut.contains(k)).max_by_key(|&k| (degree(k), std::cmp::Reverse(k))) else {
            break;
        };
        cut.push(k);
    }
    cut.sort_unstable();
    cut
}

/// The subsets of 0..n of `size` elements, in lexicographic order.
fn subsets(n: usize, size: usize) -> impl Iterator<Item = Vec<usize>> {
    (0u32..1 << n)
        .filter(move |bits| bits.count_ones() as usize == size)
        .map(move |bits| (0..n).filter(|k| bits & (1 << k) != 0).collect::<Vec<usize>>())
}

/// Whether the edges not leaving a cut member form no cycle.
fn acyclic_without(n: usize, edges: &[(usize, usize)], cut: &[usize]) -> bool {
    topological(n, edges, cut).len() == n - cut.len()
}

/// The members not cut, in an order where each follows those it reads
/// (ties by position); a cycle's members are missing.
fn topological(n: usize, edges: &[(usize, usize)], cut: &[usize]) -> Vec<usize> {
    let kept: Vec<&(usize, usize)> = edges.iter().filter(|(a, b)| !cut.contains(a) && !cut.contains(b)).collect();
    let mut indegree = vec![0; n];
    kept.iter().for_each(|&&(_, b)| indegree[b] += 1);
    let mut ready: Vec<usize> = (0..n).filter(|k| !cut.contains(k) && indegree[*k] == 0).collect();
    let mut order = Vec::new();
    while let Some(k) = ready.iter().copied().min() {
        ready.retain(|&r| r != k);
        order.push(k);
        for &&(_, b) in kept.iter().filter(|e| e.0 == k) {
            indegree[b] -= 1;
            if indegree[b] == 0 {
                ready.push(b);
            }
        }
    }
    order
}

/// The members not cut in dependency order, then the cut ones.
fn evaluation_order(n: usize, edges: &[(usize, usize)], cut: &[usize]) -> Vec<usize> {
    let mut order = topological(n, edges, cut);
    order.extend_from_slice(cut);
    order
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ring_is_cut_once_at_its_narrowest_block() {
        // 0 -> 1 -> 2 -> 0, block 0 three wide, the others scalar.
        let edges = [(0, 1), (1, 2), (2, 0)];
        assert_eq!(cut_set(3, &edges, |k| if k == 0 { 3 } else { 1 }), vec![1]);
        assert_eq!(evaluation_order(3, &edges, &[1]), vec![2, 0, 1]);
    }

    #[test]
    fn two_rings_sharing_a_block_are_cut_there() {
        // 0 -> 1 -> 0 and 1 -> 2 -> 1: block 1 alone breaks both.
        let edges = [(0, 1), (1, 0), (1, 2), (2, 1)];
        assert_eq!(cut_set(3, &edges, |_| 1), vec![1]);
    }

    #[test]
    fn large_loops_are_cut_greedily_into_an_acyclic_rest() {
        // A ring of 20 with chords: the greedy cut still breaks every cycle.
        let mut edges: Vec<(usize, usize)> = (0..20).map(|k| (k, (k + 1) % 20)).collect();
        edges.extend((0..20).step_by(5).map(|k| (k, (k + 7) % 20)));
        let cut = cut_set(20, &edges, |_| 1);
        assert!(acyclic_without(20, &edges, &cut), "{cut:?}");
    }
}
