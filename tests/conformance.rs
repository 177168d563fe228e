//! Every registered block type keeps the promises of the `Block` trait
//! (ctlgraph_blocks::testing::conformance), checked on every block of the
//! bundled graphs and of `tests/data/every_block.yaml`, which has the types
//! no bundled graph uses.

mod common;
use ctlgraph::blocks::testing::conformance::check_model;
use std::collections::BTreeSet;
use std::path::PathBuf;

#[test]
fn every_block_of_every_registered_type_keeps_its_promises() {
    // Not the subsystem libraries (`lib/`): their blocks are checked where they are used.
    let mut graphs: Vec<PathBuf> =
        common::bundled_graphs().into_iter().filter(|g| !g.components().any(|c| c.as_os_str() == "lib")).collect();
    graphs.push(PathBuf::from("tests/data/every_block.yaml"));
    let (mut broken, mut seen) = (Vec::new(), BTreeSet::new());
    for graph in &graphs {
        let model = ctlgraph::compile_file(graph, &[]).unwrap_or_else(|d| panic!("{}: {d}", graph.display()));
        seen.extend(model.meta.iter().map(|m| m.type_name.clone()));
        broken.extend(check_model(&model).into_iter().map(|b| format!("{}: {b}", graph.display())));
    }
    assert!(broken.is_empty(), "{}", broken.join("\n"));
    let registry = ctlgraph::registry();
    // Structure, not blocks: subsystems are flattened, their ports are wires.
    let structural = ["subsystem", "inport", "outport"];
    let unchecked: Vec<&str> = registry.names().filter(|n| !seen.contains(*n) && !structural.contains(n)).collect();
    assert!(unchecked.is_empty(), "no checked graph has a block of type {unchecked:?}");
}
