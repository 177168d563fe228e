//! Execution order and rates: a topological sort over direct-feedthrough
//! edges (algebraic loops reported from strongly connected components) and
//! inherited sample times resolved along that order.

use super::{Driver, Node, Rate};
use crate::block::SampleTime;
use crate::diag::Diagnostic;
use petgraph::graph::{DiGraph, NodeIndex};
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap, HashSet};

/// The graph of direct-feedthrough edges between real blocks.
fn feedthrough_graph(nodes: &[Node], drivers: &[Vec<Driver>]) -> (DiGraph<usize, ()>, Vec<NodeIndex>) {
    let mut graph = DiGraph::<usize, ()>::new();
    let ids: Vec<NodeIndex> = (0..nodes.len()).map(|i| graph.add_node(i)).collect();
    // One edge per pair (two wires between the same blocks order them once);
    // a set, not petgraph's update_edge, which scans the source's edges and
    // makes a fan-out of n quadratic.
    let mut seen = HashSet::new();
    for (i, ds) in drivers.iter().enumerate() {
        for (p, d) in ds.iter().enumerate() {
            if nodes[i].iface.inputs[p].feedthrough && seen.insert((d.src, i)) {
                graph.add_edge(ids[d.src], ids[i], ());
            }
        }
    }
    (graph, ids)
}

/// An algebraic loop: the blocks of a strongly connected component of
/// feedthrough edges (node indices, ascending), and one cycle through it
/// from its first block, for messages.
pub(super) struct FeedthroughLoop {
    pub members: Vec<usize>,
    pub cycle: Vec<usize>,
}

impl FeedthroughLoop {
    /// `a -> b -> a`.
    pub fn text(&self, nodes: &[Node]) -> String {
        let names: Vec<&str> = self.cycle.iter().map(|&i| nodes[i].name()).collect();
        format!("{} -> {}", names.join(" -> "), names[0])
    }
}

/// Every algebraic loop, in the order of their first blocks. A graph
/// without one is found so by a topological pass alone; components are
/// searched (Kosaraju's, iterative: a 100 000-block chain must not
/// overflow the stack) only where that pass leaves blocks unsorted.
pub(super) fn feedthrough_loops(nodes: &[Node], drivers: &[Vec<Driver>]) -> Vec<FeedthroughLoop> {
    let (graph, ids) = feedthrough_graph(nodes, drivers);
    let mut indegree: Vec<usize> =
        ids.iter().map(|&n| graph.neighbors_directed(n, petgraph::Direction::Incoming).count()).collect();
    let mut ready: Vec<usize> = (0..nodes.len()).filter(|&i| indegree[i] == 0).collect();
    let mut sorted = 0;
    while let Some(i) = ready.pop() {
        sorted += 1;
        for next in graph.neighbors(ids[i]) {
            let j = graph[next];
            indegree[j] -= 1;
            if indegree[j] == 0 {
                ready.push(j);
            }
        }
    }
    if sorted == nodes.len() {
        return Vec::new();
    }
    let mut loops = Vec::new();
    for scc in petgraph::algo::kosaraju_scc(&graph) {
        let self_loop = scc.len() == 1 && graph.contains_edge(scc[0], scc[0]);
        if scc.len() > 1 || self_loop {
            let mut members: Vec<usize> = scc.iter().map(|&n| graph[n]).collect();
            members.sort_unstable();
            let cycle = cycle_through(&graph, ids[members[0]], &scc).iter().map(|&n| graph[n]).collect();
            loops.push(FeedthroughLoop { members, cycle });
        }
    }
    loops.sort_by_key(|l| l.members[0]);
    loops
}

/// The refusal of `algebraic_loops: error`: every loop, at the first one's block.
pub(super) fn loop_error(nodes: &[Node], loops: &[FeedthroughLoop]) -> Diagnostic {
    let text: Vec<String> = loops.iter().map(|l| l.text(nodes)).collect();
    let message = format!("algebraic loop: {}", text.join("; "));
    let hint = "every block on the loop has direct feedthrough; break it with a block that has none \
                (unit_delay, memory, integrator, a strictly proper transfer_function, an observer), \
                or let ctlgraph solve it: `simulation: { algebraic_loops: warn }`";
    let first = loops.first().map(|l| l.members[0]);
    match first {
        Some(i) => Diagnostic::at(&nodes[i].flat.spec.pos, message),
        None => Diagnostic::plain(message),
    }
    .with_hint(hint)
}

/// Execution order: a topological order of the direct-feedthrough edges,
/// ties broken by declaration order so listings read like the file. The
/// graph has no algebraic loop left (see [`feedthrough_loops`]).
pub(super) fn sort(nodes: &[Node], drivers: &[Vec<Driver>]) -> Result<Vec<usize>, Diagnostic> {
    let (graph, ids) = feedthrough_graph(nodes, drivers);
    let mut indegree: Vec<usize> =
        ids.iter().map(|&n| graph.neighbors_directed(n, petgraph::Direction::Incoming).count()).collect();
    let mut ready: BinaryHeap<Reverse<usize>> =
        (0..nodes.len()).filter(|&i| indegree[i] == 0 && runs(&nodes[i])).map(Reverse).collect();
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
    let real = nodes.iter().filter(|n| runs(n)).count();
    if order.len() == real { Ok(order) } else { Err(loop_error(nodes, &feedthrough_loops(nodes, drivers))) }
}

/// Whether a node takes a place in the execution order.
fn runs(node: &Node) -> bool {
    !node.is_virtual && !node.absorbed
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
pub(super) fn resolve_rates(
    nodes: &[Node],
    drivers: &[Vec<Driver>],
    order: &[usize],
) -> (HashMap<usize, Rate>, Vec<(f64, f64)>) {
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
