//! `ctlgraph check GRAPH`: the graph validated, its execution order with
//! sample times, and what the run will take; a subsystem file checked as
//! one.

use ctlgraph::suite::Failure;
use ctlgraph_core::flatten::{AlgebraicLoops, parse_set};
use ctlgraph_core::{Diagnostic, Simulator};
use std::path::Path;

pub(crate) fn check(graph: &Path, sets: &[String]) -> Result<(), Failure> {
    let parsed_sets = sets.iter().map(|s| parse_set(s)).collect::<Result<Vec<_>, _>>()?;
    let flat = ctlgraph_core::load(graph, &parsed_sets)?;
    let ports = |ty: &str| -> Vec<String> {
        flat.blocks.iter().filter(|b| b.spec.type_name == ty && !b.path.contains('/')).map(|b| b.path.clone()).collect()
    };
    let (inports, outports) = (ports("inport"), ports("outport"));
    // A file with ports runs on its own (they are then its inputs and
    // outputs, for a program driving it) or is a subsystem: when it does
    // not compile alone, check it as one.
    let model = match ctlgraph_core::compile(&flat, &ctlgraph::registry()) {
        Ok(model) => model,
        Err(_) if !inports.is_empty() || !outports.is_empty() => {
            return check_subsystem(graph, &inports, &outports);
        }
        Err(d) => return Err(d.into()),
    };
    println!("{}: ok", graph.display());
    if !inports.is_empty() || !outports.is_empty() {
        let list = |names: &[String]| if names.is_empty() { "(none)".to_string() } else { names.join(", ") };
        println!("inputs:  {} (set by a program driving the graph; a subsystem's inports)", list(&inports));
        println!("outputs: {}", list(&outports));
    }
    for c in &model.checks {
        if let Some(problem) = c.window_problem(model.sim.stop) {
            println!("  warning: check `{}`: {problem}: it will be skipped", c.name);
        }
    }
    for w in &model.warnings {
        println!("  warning: {w}");
    }
    // Under `algebraic_loops: warn` the warnings above list them already.
    if model.sim.algebraic_loops == AlgebraicLoops::Solve {
        for l in &model.algebraic_loops {
            println!("  {l}");
        }
    }
    println!("execution order:");
    let width = model.meta.iter().map(|m| m.name.len()).max().unwrap_or(0);
    for (i, m) in model.meta.iter().enumerate() {
        let zoh = if m.exact_zoh {
            format!(", exact ZOH at {}", ctlgraph::record::Number(model.sim.method.max_step()))
        } else {
            String::new()
        };
        println!("  {:>3}  {:<width$}  {:<26}  {}{zoh}", i + 1, m.name, m.type_name, m.sample_time);
    }
    for (name, report) in model.build_reports() {
        println!("{name}: {report}");
    }
    let solver = model.sim.method;
    let held = model.n_states - model.integrated_states();
    let held = if held > 0 { format!(" ({held} stepped by exact ZOH)") } else { String::new() };
    println!(
        "{} blocks, {} continuous states{held}, {} signal values, {} sample rate(s); solver {}, stop {} s",
        model.meta.len(),
        model.n_states,
        model.signal_len,
        model.clocks.len(),
        solver.name(),
        ctlgraph::record::Number(model.sim.stop)
    );
    let sim = Simulator::new(model, None);
    let floor = if sim.method().is_adaptive() { "at least" } else { "about" };
    println!("{floor} {} major steps to the stop time", ctlgraph::record::Number(sim.expected_major_steps()));
    if let Some(w) = crate::run_cmd::long_run_warning(&sim) {
        println!("warning: {w}");
    }
    Ok(())
}

/// A subsystem file checked on its own: compiled inside a wrapper that
/// feeds each inport a constant, so its interface and insides are
/// validated as an including graph would see them.
fn check_subsystem(graph: &Path, inports: &[String], outports: &[String]) -> Result<(), Failure> {
    let file = graph.canonicalize().map_err(|e| Diagnostic::plain(format!("{}: {e}", graph.display())))?;
    let mut blocks = format!("  sub: {{ type: subsystem, file: \"{}\" }}\n", file.display());
    let mut wires = Vec::new();
    for (k, name) in inports.iter().enumerate() {
        blocks.push_str(&format!("  in{k}: {{ type: constant, value: 0 }}\n"));
        wires.push(format!("in{k} -> sub.{name}"));
    }
    let text = format!("blocks:\n{blocks}wires: [{}]\n", wires.join(", "));
    // The wrapper has a name of its own: the loader must not take it for
    // the subsystem file it includes.
    let model = ctlgraph::compile_str(&text, &format!("{} (as a subsystem)", graph.display()), &[])?;
    println!("{}: ok as a subsystem", graph.display());
    println!("  inports:  {}", if inports.is_empty() { "(none)".into() } else { inports.join(", ") });
    println!("  outports: {}", if outports.is_empty() { "(none)".into() } else { outports.join(", ") });
    println!("{} blocks inside, {} continuous states", model.meta.len() - inports.len(), model.n_states);
    Ok(())
}
