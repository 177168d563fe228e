//! `ctlgraph report`: the HTML report of an earlier run, from the CSV it
//! recorded and its JSON report. The graph named in the JSON is loaded
//! again (with the parameters and seed the run used) for the diagram,
//! the blocks' parameters and the plot panels; if the file changed since
//! the run (its SHA-256 differs), the report says so at the top.

use ctlgraph::html::Report;
use ctlgraph::record::{Trace, write_atomic};
use ctlgraph::report::sha256_hex;
use ctlgraph::suite::Failure;
use ctlgraph_core::Diagnostic;
use ctlgraph_core::files::{MAX_GRAPH_FILE, read_text};
use serde_json::Value;
use std::path::{Path, PathBuf};

pub(crate) fn report(csv: &Path, json: &Path, html: &Path) -> Result<(), Failure> {
    for (flag, input) in [("the CSV", csv), ("--json", json)] {
        if html == input {
            return Err(Diagnostic::plain(format!("--html {}: that is {flag}", html.display())).into());
        }
    }
    let read = |p: &Path| {
        read_text(p, MAX_GRAPH_FILE).map_err(|e| Failure::Invalid(Diagnostic::plain(format!("{}: {e}", p.display()))))
    };
    let run: Value = serde_json::from_str(&read(json)?).map_err(|e| {
        Diagnostic::plain(format!("{}: not a run report: {e}", json.display()))
            .with_hint("write one with `ctlgraph run GRAPH --report run.json`")
    })?;
    let Some(file) = run["graph"]["file"].as_str() else {
        return Err(Diagnostic::plain(format!("{}: not a run report: no `graph.file`", json.display())).into());
    };
    let graph = locate(file, json).ok_or_else(|| {
        Diagnostic::plain(format!("{}: the run's graph {file} is not found", json.display()))
            .with_hint("run `ctlgraph report` from the folder the run was made in")
    })?;
    let text = read(&graph)?;
    let mut notes = Vec::new();
    if run["graph"]["sha256"].as_str().is_some_and(|h| h != sha256_hex(text.as_bytes())) {
        notes.push(format!(
            "{} changed since the run (its SHA-256 differs): the diagram and parameters shown are today's",
            graph.display()
        ));
    }
    let sets: Vec<(String, String)> = run["overrides"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|o| Some((o["name"].as_str()?.to_string(), o["value"].as_str()?.to_string())))
        .collect();
    let flat = ctlgraph::load_seeded(&graph, &sets, run["seed"].as_u64())?;
    let model = ctlgraph::compile_flat(&flat, &ctlgraph::registry())?;
    let trace = read_trace(csv)?;
    let missing: Vec<String> = model.headers().into_iter().filter(|h| !trace.headers.contains(h)).collect();
    if !missing.is_empty() {
        notes.push(format!("the graph records {} which the CSV does not hold", missing.join(", ")));
    }
    let page = ctlgraph::html::render(&Report { run: &run, trace: &trace, flat: &flat, model: &model, notes: &notes });
    write_atomic(html, page.as_bytes()).map_err(|e| Failure::Run(format!("cannot write {}: {e}", html.display())))?;
    println!(
        "{}: report of {} ({} samples of {} signals)",
        html.display(),
        graph.display(),
        trace.t().len(),
        trace.headers.len() - 1
    );
    Ok(())
}

/// The graph file as the JSON names it: as given (relative to where the
/// run was made), else relative to the JSON's folder.
fn locate(file: &str, json: &Path) -> Option<PathBuf> {
    let given = PathBuf::from(file);
    if given.is_file() {
        return Some(given);
    }
    let beside = json.parent()?.join(file);
    beside.is_file().then_some(beside)
}

/// A CSV written by `run --out`: header `t` then the recorded names, one
/// row per logged step.
fn read_trace(path: &Path) -> Result<Trace, Failure> {
    let bad = |m: String| Failure::Invalid(Diagnostic::plain(format!("{}: {m}", path.display())));
    // Read as a stream, so any size of run; but a device never ends.
    ctlgraph_core::files::regular_file(path).map_err(|e| bad(e.to_string()))?;
    let mut reader = csv::Reader::from_path(path).map_err(|e| bad(e.to_string()))?;
    let headers: Vec<String> = reader.headers().map_err(|e| bad(e.to_string()))?.iter().map(String::from).collect();
    if headers.first().map(String::as_str) != Some("t") {
        return Err(bad("not a run's CSV: the first column must be `t`".into()));
    }
    let mut trace = Trace::new(headers);
    let mut row = Vec::new();
    for (line, record) in reader.records().enumerate() {
        let record = record.map_err(|e| bad(e.to_string()))?;
        row.clear();
        for field in &record {
            row.push(
                field.trim().parse::<f64>().map_err(|_| bad(format!("row {}: `{field}` is not a number", line + 2)))?,
            );
        }
        if row.len() != trace.headers.len() {
            return Err(bad(format!("row {}: {} values under {} columns", line + 2, row.len(), trace.headers.len())));
        }
        trace.push(&row);
    }
    if trace.t().is_empty() {
        return Err(bad("no samples".into()));
    }
    Ok(trace)
}
