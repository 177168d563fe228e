//! `ctlgraph fmu GRAPH --out NAME.fmu [--fmi 3|2] [--set NAME=VALUE]…`.

use ctlgraph::accel::Cost;
use ctlgraph::fmu::{ExportError, export};
use ctlgraph::suite::Failure;
use ctlgraph_core::Diagnostic;
use ctlgraph_core::flatten::parse_set;
use ctlgraph_fmi::table::{Causality, Version};
use std::path::Path;

pub(crate) fn fmu(graph: &Path, out: &Path, fmi: &str, sets: &[String]) -> Result<(), Failure> {
    if out.extension().is_none_or(|e| e != "fmu") {
        return Err(Diagnostic::plain(format!("--out {}: an FMU's file name ends in .fmu", out.display()))
            .with_hint("e.g. --out controller.fmu (the name before .fmu becomes its modelIdentifier)")
            .into());
    }
    if crate::run_cmd::same_file(out, graph) {
        return Err(Diagnostic::plain(format!("--out {}: that is the graph file", out.display())).into());
    }
    let version = if fmi == "2" { Version::Fmi2 } else { Version::Fmi3 };
    let sets = sets.iter().map(|s| parse_set(s)).collect::<Result<Vec<_>, _>>()?;
    let done = export(graph, &sets, version, out).map_err(|e| match e {
        ExportError::Graph(d) => Failure::Invalid(d),
        ExportError::Make(message) => Failure::Run(message),
    })?;
    let p = &done.package;
    let count = |c: Causality, one: &str, many: &str| {
        let n = p.count(c);
        format!("{n} {}", if n == 1 { one } else { many })
    };
    let binary = match done.binary {
        Cost::Built(s) => format!("binary built in {s:.1} s"),
        Cost::Loaded(_) => "binary from the cache".to_string(),
    };
    println!(
        "{}: FMI {} co-simulation FMU, {}, {}, {}, {} ({:.1} MB; {binary})",
        out.display(),
        version.text(),
        count(Causality::Input, "input", "inputs"),
        count(Causality::Output, "output", "outputs"),
        count(Causality::Parameter, "parameter", "parameters"),
        count(Causality::Local, "local variable", "local variables"),
        done.bytes as f64 / 1e6,
    );
    Ok(())
}
