//! Algebraic loops collapsed into one block each: the blocks of a
//! strongly connected component of direct-feedthrough edges move into an
//! [`AlgebraicLoop`], which solves for the loop's cut signals at every
//! evaluation. The rest of the compiler, the driver and the generated step
//! then see one block, whose outputs are its members' (each member's
//! outputs keep their names: records, scopes and wires reach them as
//! before).

use super::schedule::FeedthroughLoop;
use super::{Driver, Node, absorb, resolved};
use crate::algebraic::AlgebraicLoop;
use crate::block::SampleTime;
use crate::diag::Diagnostic;

/// Largest loop whose cut is searched exhaustively for the fewest blocks;
/// beyond it, greedily.
const EXHAUSTIVE_CUT: usize = 16;

/// A loop collapsed into one block, and how `check` names it.
pub(super) struct Collapsed {
    pub installed: absorb::Installed,
    pub description: String,
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
    let edges = absorb::feedthrough_edges(nodes, drivers, members);
    let width = |k: usize| -> usize {
        let m = members[k];
        nodes[m].iface.outputs.iter().map(|p| resolved(p.width, nodes[m].width)).sum()
    };
    let cut = cut_set(members.len(), &edges, width);
    let order = evaluation_order(members.len(), &edges, &cut);
    let layout = absorb::lay_out(nodes, drivers, members, sample_time);
    // The members in evaluation order; the cut ones' outputs are the unknowns.
    let mut built = Vec::with_capacity(members.len());
    let mut unknowns = Vec::new();
    let mut cut_names = Vec::new();
    for &k in &order {
        let m = members[k];
        if cut.contains(&k) {
            unknowns.extend_from_slice(layout.outputs_of(m));
            let ports = &nodes[m].iface.outputs;
            let path = nodes[m].name();
            cut_names.extend(
                ports.iter().map(|p| if ports.len() > 1 { format!("{path}.{}", p.name) } else { path.to_string() }),
            );
        }
        built.push(layout.member(nodes, m)?);
    }
    let n_unknowns: usize = unknowns.iter().map(|p| p.width).sum();
    let description = format!(
        "algebraic loop {text}: solved for {} at every evaluation ({n_unknowns} unknown{})",
        cut_names.join(", "),
        if n_unknowns == 1 { "" } else { "s" }
    );
    let solver = AlgebraicLoop::new(
        text.clone(),
        built,
        cut.len(),
        layout.external.clone(),
        layout.outputs.clone(),
        unknowns,
        layout.buffer_len,
        tolerance,
    );
    let installed = absorb::install(
        nodes,
        drivers,
        members,
        layout,
        Box::new(solver),
        format!("algebraic loop {text}"),
        "algebraic_loop",
    );
    Ok(Collapsed { installed, description })
}

/// How closely an algebraic loop's equations are solved: a thousandth of
/// an adaptive method's relative tolerance (its error control then sees
/// the loop's signals as exact), 1e-12 under a fixed step.
pub(super) fn tolerance(method: &ctlgraph_solver::Method) -> f64 {
    match *method {
        ctlgraph_solver::Method::DormandPrince { rtol, .. } | ctlgraph_solver::Method::Trbdf2 { rtol, .. } => {
            (rtol * 1e-3).clamp(1e-14, 1e-8)
        }
        _ => 1e-12,
    }
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
pub(super) fn topological(n: usize, edges: &[(usize, usize)], cut: &[usize]) -> Vec<usize> {
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
