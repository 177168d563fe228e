//! The HTML report from the command line: `run --html` and `report` (from
//! the run's CSV and JSON) give the same page; the page carries the run's
//! data exactly (time as f64, signals as f32), every block and check, and
//! the provenance; names cannot break out of the page's scripts; a graph
//! changed since the run is said to be; bad inputs are errors (exit 2).

mod common;
use base64::Engine;
use common::{ctlgraph, path, text};
use std::path::Path;

/// The content of `<script … id="ID">…</script>`.
fn script<'a>(page: &'a str, id: &str) -> &'a str {
    let open = page.find(&format!("id=\"{id}\">")).unwrap_or_else(|| panic!("no script {id}")) + id.len() + 6;
    &page[open..open + page[open..].find("</script>").unwrap()]
}

fn decode(b64: &str) -> Vec<u8> {
    base64::engine::general_purpose::STANDARD.decode(b64.trim()).unwrap()
}

#[test]
fn run_and_report_give_the_same_page_with_the_runs_data() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, json, html, again) = (
        dir.path().join("run.csv"),
        dir.path().join("run.json"),
        dir.path().join("run.html"),
        dir.path().join("again.html"),
    );
    let graph = "graphs/tutorial/pid_loop.yaml";
    let out =
        ctlgraph(&["run", graph, "--set", "kp=3", "--out", path(&csv), "--report", path(&json), "--html", path(&html)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = ctlgraph(&["report", path(&csv), "--json", path(&json), "--html", path(&again)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let page = std::fs::read_to_string(&html).unwrap();
    assert_eq!(page, std::fs::read_to_string(&again).unwrap(), "report from CSV + JSON = run --html");

    // The data: every sample, time exactly, signals to f32.
    let table = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<f64>> =
        table.lines().skip(1).map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    let t: Vec<f64> =
        decode(script(&page, "ctlgraph-t")).chunks(8).map(|b| f64::from_le_bytes(b.try_into().unwrap())).collect();
    let y: Vec<f32> =
        decode(script(&page, "ctlgraph-y")).chunks(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
    assert_eq!(t.len(), rows.len());
    let columns = rows[0].len() - 1;
    assert_eq!(y.len(), columns * rows.len());
    for (i, row) in rows.iter().enumerate() {
        assert_eq!(t[i], row[0]);
        for c in 0..columns {
            assert_eq!(y[c * rows.len() + i], row[c + 1] as f32, "row {i}, column {c}");
        }
    }
    // Blocks, checks and provenance.
    let meta: serde_json::Value = serde_json::from_str(script(&page, "ctlgraph-meta")).unwrap();
    let flat = ctlgraph_core::load(Path::new(graph), &[]).unwrap();
    for b in &flat.blocks {
        let top = b.path.split('/').next().unwrap();
        assert!(page.contains(&format!("data-name=\"{top}\"")), "block {top} in the diagram");
        assert!(meta["blocks"][top].is_object(), "block {top} described");
    }
    // Each block lists the signals recorded from its outputs, and only those.
    for (block, signals) in [("r", vec!["r"]), ("plant", vec!["y"]), ("ctrl", vec!["u"]), ("err", vec!["e"])] {
        assert_eq!(meta["blocks"][block]["signals"], serde_json::json!(signals), "block {block}");
    }
    assert!(page.contains("<tr class=\"pass\">"), "the checks table");
    let sha = ctlgraph::report::sha256_hex(&std::fs::read(graph).unwrap());
    assert!(page.contains(&sha) && page.contains("kp = 3") && page.contains(env!("CARGO_PKG_VERSION")));
}

#[test]
fn names_cannot_close_the_pages_scripts() {
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("g.yaml");
    std::fs::write(
        &graph,
        "name: \"A </script><b>bold</b> name\"\nsimulation: { stop: 0.1, solver: { method: rk4, step: 0.01 } }\n\
         blocks:\n  s: { type: sine }\n",
    )
    .unwrap();
    let html = dir.path().join("g.html");
    let out = ctlgraph(&["run", path(&graph), "--html", path(&html)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let page = std::fs::read_to_string(&html).unwrap();
    assert_eq!(page.matches("</script>").count(), 4, "the page's own four scripts only");
    assert!(page.contains("A &lt;/script&gt;&lt;b&gt;bold&lt;/b&gt; name"));
    let meta: serde_json::Value = serde_json::from_str(script(&page, "ctlgraph-meta")).unwrap();
    assert_eq!(meta["title"], "A </script><b>bold</b> name");
}

#[test]
fn a_graph_changed_since_the_run_is_said_to_be() {
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("lag.yaml");
    let yaml = "simulation: { stop: 1, solver: { method: rk4, step: 0.01 } }\n\
                blocks:\n  u: { type: step }\n  y: { type: transfer_function, num: [1], den: [0.5, 1] }\nwires: [u -> y]\n";
    std::fs::write(&graph, yaml).unwrap();
    let (csv, json, html) = (dir.path().join("r.csv"), dir.path().join("r.json"), dir.path().join("r.html"));
    assert!(ctlgraph(&["run", path(&graph), "--out", path(&csv), "--report", path(&json)]).status.success());
    std::fs::write(&graph, yaml.replace("0.5", "0.25")).unwrap();
    let out = ctlgraph(&["report", path(&csv), "--json", path(&json), "--html", path(&html)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("changed since the run (its SHA-256 differs)"), "the note");
}

#[test]
fn bad_inputs_to_report_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, json, html) = (dir.path().join("r.csv"), dir.path().join("r.json"), dir.path().join("r.html"));
    std::fs::write(&csv, "x,y\n1,2\n").unwrap();
    std::fs::write(&json, "{\"graph\": {\"file\": \"no/such/graph.yaml\"}}").unwrap();
    let out = ctlgraph(&["report", path(&csv), "--json", path(&json), "--html", path(&html)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("the run's graph no/such/graph.yaml is not found"), "{}", text(&out.stderr));
    std::fs::write(&json, "{\"graph\": {\"file\": \"graphs/tutorial/pid_loop.yaml\"}}").unwrap();
    let out = ctlgraph(&["report", path(&csv), "--json", path(&json), "--html", path(&html)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("the first column must be `t`"), "{}", text(&out.stderr));
    std::fs::write(&json, "not json").unwrap();
    let out = ctlgraph(&["report", path(&csv), "--json", path(&json), "--html", path(&html)]);
    assert!(text(&out.stderr).contains("not a run report"), "{}", text(&out.stderr));
    assert!(!html.exists(), "no page written");
}

#[test]
fn the_reports_the_docs_link_to_are_todays() {
    // Regenerate with `ctlgraph run graphs/G/compare.yaml --html docs/G-report.html`.
    let script = std::fs::read_to_string("src/html/report.js").unwrap();
    let style = std::fs::read_to_string("src/html/report.css").unwrap();
    for doc in ["fladrc", "contact-force"] {
        let page = std::fs::read_to_string(format!("docs/{doc}-report.html")).unwrap();
        assert!(page.contains(&script) && page.contains(&style), "docs/{doc}-report.html is stale");
        assert!(std::fs::read_to_string(format!("docs/{doc}.md")).unwrap().contains(&format!("({doc}-report.html)")));
    }
}
