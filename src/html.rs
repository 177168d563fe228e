//! The self-contained HTML report of a run (`ctlgraph run --html`,
//! `ctlgraph report`): the block diagram (click a block for its
//! parameters and recorded signals), interactive time plots, the checks,
//! the solver's statistics and the run's provenance, in one file that
//! opens without a network.
//!
//! The plots are drawn by a small canvas plotter of our own
//! (`html/report.js`): zoom, pan, a cursor with values, time axes linked
//! across panels, signals toggled, and min/max per pixel column so no peak
//! is lost however long the trace. The recorded data travel as base64
//! arrays: time as 64-bit floats, signals as 32-bit floats (7 significant
//! digits, a third of the size of text).

use crate::diagram::{self, esc};
use crate::plot;
use crate::record::Trace;
use base64::Engine;
use ctlgraph_core::yaml::{Kind, Yaml};
use ctlgraph_core::{FlatGraph, Model};
use serde_json::{Value, json};
use std::fmt::Write;

const SCRIPT: &str = include_str!("html/report.js");
const STYLE: &str = include_str!("html/report.css");

/// What a report shows.
pub struct Report<'a> {
    /// The run report (`report::to_json`): checks, statistics, provenance.
    pub run: &'a Value,
    pub trace: &'a Trace,
    /// The graph as loaded (the diagram, parameters as written).
    pub flat: &'a FlatGraph,
    /// The graph as compiled (ports, recorded columns, scopes).
    pub model: &'a Model,
    /// Remarks shown at the top, e.g. that the graph changed since the run.
    pub notes: &'a [String],
}

/// The report as one HTML document.
pub fn render(r: &Report) -> String {
    let title = r.model.name.clone().unwrap_or_else(|| r.model.file.to_string());
    let collapsed = diagram::build(r.flat, r.model, false);
    let expanded = diagram::build(r.flat, r.model, true);
    let has_subsystems = collapsed.nodes.iter().any(|n| n.subsystem);
    let meta = json!({
        "title": title,
        "headers": r.trace.headers,
        "panels": panels_json(r),
        "blocks": blocks_json(r, &collapsed, &expanded),
    });
    let b64 = base64::engine::general_purpose::STANDARD;
    let t: Vec<u8> = r.trace.t().iter().flat_map(|v| v.to_le_bytes()).collect();
    let y: Vec<u8> =
        r.trace.columns.iter().skip(1).flat_map(|c| c.iter().flat_map(|&v| (v as f32).to_le_bytes())).collect();

    let mut h = String::with_capacity(t.len() * 2 + y.len() * 2 + 200_000);
    let _ = write!(
        h,
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <title>{t}</title>\n<style>{STYLE}</style></head>\n<body>\n<header><h1>{t}</h1><p class=\"sub\">{sub}</p>",
        t = esc(&title),
        sub = esc(&subtitle(r.run)),
    );
    for note in r.notes {
        let _ = write!(h, "<p class=\"note\">{}</p>", esc(note));
    }
    h.push_str(
        "<nav><a href=\"#diagram\">Diagram</a><a href=\"#signals\">Signals</a><a href=\"#checks\">Checks</a>\
         <a href=\"#solver\">Solver</a><a href=\"#provenance\">Provenance</a></nav></header>\n",
    );
    h.push_str("<section id=\"diagram\"><h2>Diagram</h2>");
    if has_subsystems {
        h.push_str("<label class=\"tool\"><input type=\"checkbox\" id=\"expand\"> show subsystems expanded</label>");
    }
    let _ = writeln!(
        h,
        "<div class=\"diagram-row\"><div class=\"diagram-wrap\"><div id=\"diagram-collapsed\">{}</div>\
         <div id=\"diagram-expanded\" hidden>{}</div></div>\
         <aside id=\"block-info\"><p class=\"hint\">Click a block to see its parameters and recorded signals.</p></aside>\
         </div></section>",
        diagram::to_svg(&collapsed),
        if has_subsystems { diagram::to_svg(&expanded) } else { String::new() },
    );
    h.push_str(
        "<section id=\"signals\"><h2>Signals</h2><p class=\"hint\">drag: zoom in · shift-drag: pan · wheel: zoom · \
         double-click: back to the start · click a name: show or hide it; panels with a time window of their own \
         zoom alone</p><div id=\"panels\"></div></section>\n",
    );
    checks_html(&mut h, r.run);
    solver_html(&mut h, r.run);
    provenance_html(&mut h, r.run);
    let meta = serde_json::to_string(&meta).unwrap_or_default().replace("</", "<\\/");
    let _ = write!(
        h,
        "<script type=\"application/json\" id=\"ctlgraph-meta\">{meta}</script>\n\
         <script type=\"application/octet-stream\" id=\"ctlgraph-t\">{}</script>\n\
         <script type=\"application/octet-stream\" id=\"ctlgraph-y\">{}</script>\n\
         <script>{SCRIPT}</script>\n</body></html>\n",
        b64.encode(&t),
        b64.encode(&y),
    );
    h
}

fn subtitle(run: &Value) -> String {
    let s = |k: &str| run[k].as_str().unwrap_or("").to_string();
    format!(
        "{} · status: {} · {} s of {} s simulated · ctlgraph {}",
        run["graph"]["file"].as_str().unwrap_or(""),
        s("status"),
        run["simulated_time"],
        run["stop_time"],
        s("ctlgraph_version")
    )
}

/// The plot panels, with the units of their signals.
fn panels_json(r: &Report) -> Value {
    let panels = plot::panels(r.trace, &r.model.scopes, &r.model.columns);
    let list: Vec<Value> = panels
        .iter()
        .map(|p| {
            json!({
                "title": p.title, "y_label": p.y_desc, "columns": p.columns,
                "y_limits": p.y_limits, "window": p.window, "band": p.band,
            })
        })
        .collect();
    Value::Array(list)
}

/// Per diagram box: its type, parameters as written and recorded columns.
fn blocks_json(r: &Report, collapsed: &diagram::Diagram, expanded: &diagram::Diagram) -> Value {
    let mut out = serde_json::Map::new();
    // Each recorded column's block, and the trace headers of a record
    // (`x[1]`, `x[2]` for a vector).
    let owners: Vec<(&str, &str)> = r
        .model
        .columns
        .iter()
        .filter_map(|c| Some((r.model.meta[r.model.signal_owner(c.offset)?.0].name.as_str(), c.name.as_str())))
        .collect();
    let recorded = |prefix: &str, exact: bool| -> Vec<String> {
        let inside = |block: &str| {
            if exact { block == prefix } else { block.strip_prefix(prefix).is_some_and(|rest| rest.starts_with('/')) }
        };
        owners
            .iter()
            .filter(|(block, _)| inside(block))
            .flat_map(|(_, name)| plot::trace_columns(r.trace, name))
            .map(|k| r.trace.headers[k].clone())
            .collect()
    };
    for node in collapsed.nodes.iter().chain(&expanded.nodes) {
        if out.contains_key(&node.name) {
            continue;
        }
        let info = if node.subsystem {
            let inner: Vec<&str> = r
                .flat
                .blocks
                .iter()
                .filter_map(|b| b.path.strip_prefix(&format!("{}/", node.name)))
                .filter(|p| !p.contains('/'))
                .collect();
            json!({ "type": node.lines.first(), "params": [["blocks", inner.join(", ")]],
                    "signals": recorded(&node.name, false) })
        } else {
            let block = r.flat.blocks.iter().find(|b| b.path == node.name);
            let params: Vec<(String, String)> = block
                .map(|b| {
                    b.spec
                        .params
                        .iter()
                        .filter(|(k, _)| k.name != "type")
                        .map(|(k, v)| (k.name.clone(), text(v)))
                        .collect()
                })
                .unwrap_or_default();
            json!({ "type": block.map(|b| b.spec.type_name.clone()), "params": params,
                    "signals": recorded(&node.name, true) })
        };
        out.insert(node.name.clone(), info);
    }
    Value::Object(out)
}

/// A parameter's value as written.
fn text(v: &Yaml) -> String {
    match &v.kind {
        Kind::Null => "null".into(),
        Kind::Bool(b) => b.to_string(),
        Kind::Num(x) => x.to_string(),
        Kind::Str(s) => s.clone(),
        Kind::Seq(items) => format!("[{}]", items.iter().map(text).collect::<Vec<_>>().join(", ")),
        Kind::Map(entries) => {
            format!(
                "{{{}}}",
                entries.iter().map(|(k, v)| format!("{}: {}", k.name, text(v))).collect::<Vec<_>>().join(", ")
            )
        }
    }
}

fn checks_html(h: &mut String, run: &Value) {
    h.push_str("<section id=\"checks\"><h2>Checks</h2>");
    let checks = run["checks"].as_array().map(Vec::as_slice).unwrap_or_default();
    if checks.is_empty() {
        h.push_str("<p class=\"hint\">This graph has no checks (or the run ended before they could be evaluated).</p>");
    } else {
        h.push_str("<table><tr><th>check</th><th>measured</th><th></th><th>bound</th><th>result</th></tr>");
        for c in checks {
            let passed = c["passed"].as_bool().unwrap_or(false);
            let _ = write!(
                h,
                "<tr class=\"{cls}\"><td>{}</td><td class=\"num\">{}</td><td>{}</td><td class=\"num\">{}</td><td>{}</td></tr>",
                esc(c["name"].as_str().unwrap_or("")),
                number(&c["measured"]),
                esc(c["op"].as_str().unwrap_or("")),
                number(&c["bound"]),
                if passed { "pass" } else { "FAIL" },
                cls = if passed { "pass" } else { "fail" },
            );
        }
        h.push_str("</table>");
    }
    h.push_str("</section>\n");
}

fn solver_html(h: &mut String, run: &Value) {
    h.push_str("<section id=\"solver\"><h2>Solver</h2><table>");
    if let Some(solver) = run["solver"].as_object() {
        for (k, v) in solver {
            let _ = write!(h, "<tr><th>{}</th><td>{}</td></tr>", esc(k), esc(&plain(v)));
        }
    }
    if let Some(stats) = run["statistics"].as_object() {
        for (k, v) in stats {
            let _ = write!(h, "<tr><th>{}</th><td class=\"num\">{}</td></tr>", esc(&k.replace('_', " ")), plain(v));
        }
    }
    let exact: Vec<String> =
        run["exact_zoh"].as_array().into_iter().flatten().filter_map(|v| v.as_str().map(String::from)).collect();
    if !exact.is_empty() {
        let _ = write!(h, "<tr><th>exact ZOH blocks</th><td>{}</td></tr>", esc(&exact.join(", ")));
    }
    let _ = write!(h, "<tr><th>wall time</th><td class=\"num\">{} s</td></tr>", plain(&run["wall_time_seconds"]));
    h.push_str("</table></section>\n");
}

fn provenance_html(h: &mut String, run: &Value) {
    h.push_str("<section id=\"provenance\"><h2>Provenance</h2><table>");
    let rows = [
        ("graph file", plain(&run["graph"]["file"])),
        ("graph SHA-256", plain(&run["graph"]["sha256"])),
        ("ctlgraph version", plain(&run["ctlgraph_version"])),
        ("seed", plain(&run["seed"])),
        ("command line", run["command_line"].as_array().into_iter().flatten().map(plain).collect::<Vec<_>>().join(" ")),
        ("parameters set", pairs(&run["overrides"])),
        ("parameters", pairs(&run["parameters"])),
    ];
    for (k, v) in rows {
        let _ = write!(h, "<tr><th>{k}</th><td>{}</td></tr>", esc(if v.is_empty() { "—" } else { &v }));
    }
    if let Some(e) = run["error"].as_str() {
        let _ = write!(h, "<tr><th>error</th><td>{}</td></tr>", esc(e));
    }
    h.push_str("</table></section>\n");
}

/// `[{name, value}, …]` as `name = value, …`.
fn pairs(v: &Value) -> String {
    v.as_array()
        .into_iter()
        .flatten()
        .map(|p| format!("{} = {}", plain(&p["name"]), plain(&p["value"])))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A JSON value as text, strings without quotes.
fn plain(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Null => String::new(),
        other => other.to_string(),
    }
}

/// A number rounded to 1e-6, in exponent form outside 1e-4 … 1e6 (JSON null: NaN or infinite).
fn number(v: &Value) -> String {
    match v.as_f64() {
        Some(x) if x != 0.0 && !(1e-4..1e6).contains(&x.abs()) => format!("{x:.5e}"),
        Some(x) => format!("{}", (x * 1e6).round() / 1e6),
        None => "—".into(),
    }
}
