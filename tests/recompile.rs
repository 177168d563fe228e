//! A graph loaded with other parameter values is compiled on the
//! structure of the model compiled before (what a sweep does for each
//! case): the result runs bit for bit as a full compile of it, and a value
//! that changes the structure (a sample time) compiles whole.

mod common;
use ctlgraph_core::{load, load_str, recompile, reuse_structure, trace::simulate};

/// Exact to the bit (Debug prints each f64's shortest round-trip form).
fn bits(model: ctlgraph_core::Model, stop: f64) -> String {
    format!("{:?}", simulate(model, Some(stop)).expect("runs"))
}

#[test]
fn a_value_changed_compiles_on_the_structure_and_runs_as_a_full_compile() {
    let registry = ctlgraph::registry();
    let mut reused = 0;
    for graph in common::bundled_graphs().iter().filter(|g| !g.components().any(|c| c.as_os_str() == "lib")) {
        let base = ctlgraph::compile_file(graph, &[]).unwrap_or_else(|d| panic!("{}: {d}", graph.display()));
        let Some((name, value)) = base.parameters.first().cloned() else { continue };
        let changed = if value == 0.0 { 0.5 } else { value * 1.25 };
        let flat = load(graph, &[(name.clone(), format!("{changed:e}"))]).unwrap();
        let Ok(full) = ctlgraph_core::compile(&flat, &registry) else { continue };
        let stop = (base.sim.stop).min(0.05);
        if reuse_structure(&base, &flat, &registry).unwrap().is_some() {
            reused += 1;
        }
        let on_structure = recompile(&base, &flat, &registry).unwrap();
        assert_eq!(bits(on_structure, stop), bits(full, stop), "{} with {name} = {changed}", graph.display());
    }
    assert!(reused >= 10, "only {reused} graphs compiled on their structure");
}

#[test]
fn a_value_that_changes_the_structure_compiles_whole() {
    let text = "parameters: { ts: 0.01, k: 2 }\nsimulation: { stop: 0.2 }\nblocks:\n  u: { type: sine }\n  \
                h: { type: zero_order_hold, sample_time: ts }\n  g: { type: gain, k: k }\nwires: [u -> h, h -> g]\n";
    let registry = ctlgraph::registry();
    let base = ctlgraph_core::compile(&load_str(text, "s.yaml".into(), &[]).unwrap(), &registry).unwrap();
    let gain = load_str(text, "s.yaml".into(), &[("k".into(), "3".into())]).unwrap();
    assert!(reuse_structure(&base, &gain, &registry).unwrap().is_some(), "a gain's value keeps the structure");
    let rate = load_str(text, "s.yaml".into(), &[("ts".into(), "0.02".into())]).unwrap();
    assert!(reuse_structure(&base, &rate, &registry).unwrap().is_none(), "a sample time changes it");
    let full = ctlgraph_core::compile(&rate, &registry).unwrap();
    assert_eq!(bits(recompile(&base, &rate, &registry).unwrap(), 0.2), bits(full, 0.2));
}

#[test]
fn the_graph_cache_gives_what_a_fresh_compile_gives_and_sees_an_edited_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("loop.yaml");
    let graph = |den: &str| {
        format!(
            "parameters: {{ k: 2 }}\nsimulation: {{ stop: 1 }}\nblocks:\n  r: {{ type: step }}\n  e: {{ type: sum, signs: \"+-\" }}\n  \
             c: {{ type: gain, k: k }}\n  p: {{ type: transfer_function, num: [1], den: {den} }}\n\
             wires: [r -> e.u1, p -> e.u2, e -> c, c -> p]\nrecord: [y: p]\n"
        )
    };
    std::fs::write(&path, graph("[1, 1]")).unwrap();
    let cache = ctlgraph::cache::GraphCache::new();
    for (k, den) in [("2", "[1, 1]"), ("3", "[1, 1]"), ("3", "[1, 2, 1]")] {
        std::fs::write(&path, graph(den)).unwrap();
        let sets = [("k".to_string(), k.to_string())];
        let cached = cache.compile(&path, &sets, None).unwrap();
        let fresh = ctlgraph::compile_file_seeded(&path, &sets, None).unwrap();
        assert_eq!(cached.n_states, fresh.n_states, "den {den}");
        assert_eq!(bits(cached, 1.0), bits(fresh, 1.0), "k = {k}, den {den}");
    }
}
