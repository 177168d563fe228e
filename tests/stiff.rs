//! The implicit solver on whole graphs: the paper's plant under trbdf2
//! against dopri5, and the stiff demonstration graphs' statistics.

/// The LADRC scenario with its solver replaced by `solver`.
fn ladrc_with(solver: &str) -> ctlgraph::record::Trace {
    let path = "graphs/fladrc/ladrc.yaml";
    let text = std::fs::read_to_string(path).unwrap();
    let text = text.replace("solver: { method: rk4, step: 1.0e-4 }", solver);
    assert!(text.contains(solver), "the scenario's solver line changed");
    let model = ctlgraph::compile_str(&text, path, &[]).unwrap_or_else(|d| panic!("{d}"));
    ctlgraph::simulate(model, None).unwrap()
}

#[test]
fn implicit_run_of_the_fladrc_plant_equals_the_explicit_one() {
    let implicit = ladrc_with("solver: { method: trbdf2, rtol: 1.0e-10, atol: 1.0e-12 }");
    let explicit = ladrc_with("solver: { method: dopri5, rtol: 1.0e-10, atol: 1.0e-12 }");
    // Both land on every 0.1 ms sample hit of the discrete controller.
    let mut compared = 0;
    for (k, &t) in explicit.t().iter().enumerate() {
        let Some(y) = implicit.at("y", t) else { continue };
        let reference = explicit.column("y").unwrap()[k];
        assert!((y - reference).abs() < 1e-6, "t = {t}: trbdf2 {y} vs dopri5 {reference}");
        compared += 1;
    }
    assert!(compared > 19_000, "{compared} samples compared");
}

#[test]
fn stiff_graphs_take_few_steps_and_report_their_newton_work() {
    for (graph, most_steps) in [("graphs/stiff/van_der_pol.yaml", 20_000), ("graphs/stiff/robertson.yaml", 2_000)] {
        let model = ctlgraph::compile_file(graph.as_ref(), &[]).unwrap();
        let mut sim = ctlgraph_core::Simulator::new(model, None);
        let stats = sim.run(&mut |_, _| {}).unwrap();
        assert!(stats.solver.steps < most_steps, "{graph}: {stats:?}");
        assert!(
            stats.solver.jacobians > 0 && stats.solver.factorizations >= stats.solver.jacobians,
            "{graph}: {stats:?}"
        );
    }
}
