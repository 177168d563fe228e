//! What a compiled graph's author should hear before running it: settings
//! that run but mislead. Warnings, not errors: `check` and `run` print them.

use super::Model;
use petgraph::graph::{DiGraph, NodeIndex};

impl Model {
    /// Per block: whether it lies on a feedback loop (its output reaches
    /// its own input through the wiring, delays and integrators included).
    pub fn on_loops(&self) -> Vec<bool> {
        let n = self.blocks.len();
        let mut graph = DiGraph::<(), ()>::with_capacity(n, self.edges.len());
        for _ in 0..n {
            graph.add_node(());
        }
        for e in &self.edges {
            graph.add_edge(NodeIndex::new(e.src), NodeIndex::new(e.dst), ());
        }
        let mut on = vec![false; n];
        for scc in petgraph::algo::tarjan_scc(&graph) {
            let cyclic = scc.len() > 1 || graph.contains_edge(scc[0], scc[0]);
            for node in scc.into_iter().filter(|_| cyclic) {
                on[node.index()] = true;
            }
        }
        on
    }
}

/// The smallest dead time of a block on a feedback loop, and that block.
pub(super) fn loop_dead_time(model: &Model) -> Option<(f64, usize)> {
    let delays: Vec<(f64, usize)> =
        (0..model.blocks.len()).filter_map(|i| Some((model.blocks[i].dead_time()?, i))).collect();
    if delays.is_empty() {
        return None;
    }
    let on = model.on_loops();
    delays.into_iter().filter(|&(_, i)| on[i]).min_by(|a, b| a.0.total_cmp(&b.0))
}

/// The warnings for `model`.
pub(super) fn warnings(model: &Model) -> Vec<String> {
    let mut out = Vec::new();
    let method = model.sim.method;
    if let Some((delay, i)) = model.loop_dead_time {
        let step = method.max_step();
        let fixed = !method.is_adaptive();
        if (fixed || !model.sim.default_max_step) && step > delay {
            let meta = &model.meta[i];
            out.push(format!(
                "block `{}` ({}) delays by {delay} s on a feedback loop, less than the solver's {} {step} s: \
                 its output comes from extrapolating past the newest sample; set the {} to at most {delay}{}",
                meta.name,
                meta.type_name,
                if fixed { "step" } else { "max_step" },
                if fixed { "step" } else { "max_step" },
                if fixed { "" } else { " (or leave it out: its default stays below the delay)" },
            ));
        }
    }
    for c in &model.columns {
        if model.parameters.iter().any(|(p, _)| *p == c.name) {
            out.push(format!(
                "parameter `{0}` and the recorded signal `{0}` share a name: in a check, a bare `{0}` is the \
                 parameter's value and `{0}` as a metric's first argument the signal; rename one",
                c.name
            ));
        }
    }
    out
}
