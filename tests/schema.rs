//! `ctlgraph schema` checked by a JSON Schema validator (the `jsonschema`
//! crate, draft-07): every bundled graph validates, and the faults a schema
//! can see — an unknown key, a value of the wrong type, an unknown block
//! type or option — are rejected, each from the bad-input cases of
//! `tests/errors.rs` that is one of those.

mod common;
use common::{bundled_graphs, ctlgraph, text};
use ctlgraph::core::yaml::{Kind, Yaml};
use serde_json::{Value, json};
use std::sync::Arc;

/// The graph file's tree as JSON, as an editor's YAML support reads it.
fn to_json(y: &Yaml) -> Value {
    match &y.kind {
        Kind::Null => Value::Null,
        Kind::Bool(b) => json!(b),
        Kind::Num(x) if x.is_finite() => json!(x),
        Kind::Num(x) => json!(x.to_string()),
        Kind::Str(s) => json!(s),
        Kind::Seq(items) => Value::Array(items.iter().map(to_json).collect()),
        Kind::Map(m) => Value::Object(m.iter().map(|(k, v)| (k.name.clone(), to_json(v))).collect()),
    }
}

fn parse(text: &str) -> Value {
    to_json(&ctlgraph::core::yaml::parse(text, &Arc::from("test.yaml")).unwrap())
}

fn validator() -> jsonschema::Validator {
    let schema = ctlgraph::schema::schema(&ctlgraph::registry());
    jsonschema::draft7::new(&schema).expect("the schema is a valid draft-07 schema")
}

#[test]
fn every_bundled_graph_and_subsystem_file_validates() {
    let v = validator();
    let graphs = bundled_graphs();
    assert!(graphs.len() > 40, "{} graphs", graphs.len());
    for g in &graphs {
        let doc = parse(&std::fs::read_to_string(g).unwrap());
        let errors: Vec<String> = v.iter_errors(&doc).map(|e| format!("{} at {}", e, e.instance_path())).collect();
        assert!(errors.is_empty(), "{}: {}", g.display(), errors.join("\n"));
    }
}

/// Faults from `tests/errors.rs` a schema can see, each rejected; and the
/// same graphs, corrected, accepted.
#[test]
fn schema_level_faults_are_rejected() {
    let v = validator();
    let cases = [
        // (fault, corrected)
        (
            "blocks:\n  p: { type: transfer_fuction, num: [1], den: [1, 1] }\n",
            "blocks:\n  p: { type: transfer_function, num: [1], den: [1, 1] }\n",
        ),
        ("blocks:\n  g: { type: gain, gian: 2 }\n", "blocks:\n  g: { type: gain, k: 2 }\n"),
        ("blocks:\n  u: { type: step, at: { t: 1 } }\n", "blocks:\n  u: { type: step, at: 1 }\n"),
        (
            "blocks:\n  p: { type: transfer_function, num: { a: 1 }, den: [1, 1] }\n",
            "blocks:\n  p: { type: transfer_function, num: [1], den: [1, 1] }\n",
        ),
        ("blocks:\n  c: { type: pid, anti_windup: clamp }\n", "blocks:\n  c: { type: pid, anti_windup: clamping }\n"),
        (
            "blocks:\n  i: { type: integrator, state_port: 1 }\n",
            "blocks:\n  i: { type: integrator, state_port: true }\n",
        ),
        (
            "simulation: { stop: 1, solver: { method: rk45 } }\n",
            "simulation: { stop: 1, solver: { method: dopri5 } }\n",
        ),
        ("simulation: { stpo: 1 }\n", "simulation: { stop: 1 }\n"),
        ("blokcs:\n  u: { type: step }\n", "blocks:\n  u: { type: step }\n"),
        (
            "blocks:\n  u: { type: step }\nwires:\n  - u plant\n",
            "blocks:\n  u: { type: step }\nwires:\n  - u -> plant\n",
        ),
        ("scopes:\n  - { title: y, signal: [y] }\n", "scopes:\n  - { title: y, signals: [y] }\n"),
        ("analysis: { opne: u }\n", "analysis: { open: u }\n"),
        ("blocks:\n  1u: { type: step }\n", "blocks:\n  u1: { type: step }\n"),
    ];
    for (bad, good) in cases {
        assert!(!v.is_valid(&parse(bad)), "accepted:\n{bad}");
        let errors: Vec<String> = v.iter_errors(&parse(good)).map(|e| e.to_string()).collect();
        assert!(errors.is_empty(), "refused:\n{good}\n{}", errors.join("\n"));
    }
}

/// What an editor shows: the type's summary and each parameter's doc,
/// unit and default; a word's options as the enum.
#[test]
fn the_schema_carries_the_documentation() {
    let schema = ctlgraph::schema::schema(&ctlgraph::registry());
    let pid = &schema["definitions"]["block_pid"];
    assert_eq!(pid["additionalProperties"], json!(false));
    assert!(pid["description"].as_str().unwrap().starts_with("PID controller"));
    assert_eq!(pid["properties"]["anti_windup"]["enum"], json!(["clamping", "back_calculation", "none"]));
    assert_eq!(pid["properties"]["anti_windup"]["default"], json!("clamping"));
    let ki = pid["properties"]["ki"]["description"].as_str().unwrap();
    assert!(ki.contains("integral gain [1/s]") && ki.contains("(default: 0)"), "{ki}");
    let types = schema["definitions"]["block"]["properties"]["type"]["enum"].as_array().unwrap().len();
    assert_eq!(types, ctlgraph::registry().names().count());
}

#[test]
fn the_command_writes_what_the_library_generates() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ctlgraph.schema.json");
    let run = ctlgraph(&["schema", "--out", out.to_str().unwrap()]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let written: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(written, ctlgraph::schema::schema(&ctlgraph::registry()));
    assert_eq!(written["$schema"], json!("http://json-schema.org/draft-07/schema#"));
}
