//! `ctlgraph schema`: a JSON Schema of the graph file, generated from the
//! block registry and the loader's own key lists, for editors' YAML
//! support (validation, completion and hover with no plugin of ours).
//!
//! Draft-07: the draft the YAML language server (VS Code's, Neovim's and
//! Helix's YAML support) and JetBrains IDEs read completely; its
//! `if`/`then` selects a block's parameters by its `type`. A number may
//! always be an expression of the graph's parameters (a string).

use ctlgraph_core::flatten::{METHODS, SIM_KEYS, SOLVER_KEYS};
use ctlgraph_core::registry::{BlockType, ParamDefault, ParamDoc, ParamKind, Registry};
use serde_json::{Map, Value, json};

/// The schema of a graph file for the block types of `reg`.
pub fn schema(reg: &Registry) -> Value {
    let mut definitions = Map::new();
    definitions.insert(
        "number".into(),
        json!({
            "description": "a number, or an expression of the graph's parameters",
            "type": ["number", "string"]
        }),
    );
    definitions.insert("numbers".into(), json!({
        "anyOf": [{ "$ref": "#/definitions/number" }, { "type": "array", "items": { "$ref": "#/definitions/number" } }]
    }));
    let mut dispatch = Vec::new();
    for t in reg.types() {
        definitions.insert(format!("block_{}", t.name), block(t));
        dispatch.push(json!({
            "if": { "properties": { "type": { "const": t.name } }, "required": ["type"] },
            "then": { "$ref": format!("#/definitions/block_{}", t.name) }
        }));
    }
    let names: Vec<&str> = reg.names().collect();
    definitions.insert(
        "block".into(),
        json!({
            "type": "object",
            "required": ["type"],
            "properties": { "type": { "enum": names, "description": "the block type (`ctlgraph blocks` lists them)" } },
            "allOf": dispatch
        }),
    );
    let signal = json!({ "type": "string", "pattern": r"^\s*[A-Za-z_][A-Za-z0-9_/]*(\.[A-Za-z_][A-Za-z0-9_]*)?(\[[0-9]+\])?\s*$" });
    definitions.insert("records".into(), json!({
        "type": "array",
        "items": {
            "anyOf": [
                signal,
                { "type": "object", "minProperties": 1, "maxProperties": 2, "properties": { "unit": { "type": "string" } } }
            ]
        }
    }));
    json!({
        "$schema": "http://json-schema.org/draft-07/schema#",
        "title": "ctlgraph graph file",
        "description": format!("A ctlgraph block diagram (ctlgraph {}); `ctlgraph check` validates it fully.", env!("CARGO_PKG_VERSION")),
        "type": "object",
        "additionalProperties": false,
        "properties": {
            "name": { "type": "string", "description": "the graph's title" },
            "description": { "type": "string" },
            "parameters": {
                "type": "object",
                "description": "named values: numbers or expressions of the parameters above them (`--set NAME=VALUE` overrides)",
                "additionalProperties": { "$ref": "#/definitions/number" }
            },
            "simulation": simulation(),
            "blocks": {
                "type": "object",
                "description": "the blocks by name: `name: { type: TYPE, parameter: value, … }`",
                "propertyNames": { "pattern": "^[A-Za-z_][A-Za-z0-9_]*$" },
                "additionalProperties": { "$ref": "#/definitions/block" }
            },
            "wires": {
                "type": "array",
                "description": "`source.port -> dest.port, other.port`",
                "items": { "type": "string", "pattern": "->" }
            },
            "record": {
                "description": "the recorded signals: `block.port`, `name: block.port`, `{ name: block.port, unit: mm }`; or `{ signals: […], every: N }`",
                "anyOf": [
                    { "$ref": "#/definitions/records" },
                    {
                        "type": "object",
                        "additionalProperties": false,
                        "required": ["signals"],
                        "properties": {
                            "signals": { "$ref": "#/definitions/records" },
                            "every": { "type": "integer", "minimum": 1, "description": "log every n-th major step" }
                        }
                    }
                ]
            },
            "checks": {
                "type": "array",
                "description": "acceptance conditions: `\"metric(signal, …) < bound\"` or `name: \"…\"`",
                "items": {
                    "anyOf": [
                        { "type": "string" },
                        { "type": "object", "minProperties": 1, "maxProperties": 1, "additionalProperties": { "type": "string" } }
                    ]
                }
            },
            "scopes": {
                "type": "array",
                "description": "plot panels",
                "items": scope()
            },
            "analysis": {
                "type": "object",
                "description": "what linear analysis (`bode`, `poles`, loop checks) looks at",
                "additionalProperties": false,
                "properties": {
                    "input": { "type": "string", "description": "the signal where the input is injected" },
                    "output": { "type": "string", "description": "the signal measured" },
                    "open": { "type": "string", "description": "the signal where the loop is cut" },
                    "at": { "$ref": "#/definitions/number", "description": "the operating point: the state the run reaches at this time [s]" }
                }
            }
        },
        "definitions": definitions
    })
}

/// `simulation:`, its keys those the loader reads.
fn simulation() -> Value {
    let solver_doc = |key: &str| match key {
        "method" => json!({ "enum": METHODS, "description": "the ODE solver; default dopri5" }),
        "step" => json!({ "$ref": "#/definitions/number", "description": "the fixed step [s] (rk4, heun, euler)" }),
        "rtol" => {
            json!({ "$ref": "#/definitions/number", "description": "relative tolerance (dopri5, trbdf2); default 1e-6" })
        }
        "atol" => json!({ "$ref": "#/definitions/number", "description": "absolute tolerance; default 1e-9" }),
        "max_step" => json!({ "$ref": "#/definitions/number", "description": "the largest step [s]" }),
        "initial_step" => json!({ "$ref": "#/definitions/number", "description": "the first step [s]" }),
        "zero_crossing" => {
            json!({ "enum": [true, false, "adaptive"], "description": "locate zero crossings (default: on for adaptive methods)" })
        }
        "exact_lti" => {
            json!({ "type": "boolean", "description": "advance LTI blocks by their exact ZOH transition; default true" })
        }
        other => json!({ "description": other }),
    };
    let sim_doc = |key: &str| match key {
        "stop" => json!({ "$ref": "#/definitions/number", "description": "stop time [s]; default 10" }),
        "seed" => json!({ "type": ["integer", "string"], "description": "the noise sources' seed" }),
        "accelerate" => {
            json!({ "enum": [true, false, "on", "off", "require"], "description": "run the generated step (README, Accelerated runs)" })
        }
        "algebraic_loops" => json!({
            "enum": ["solve", "warn", "error"],
            "description": "a loop of feedthrough blocks: solved (warn, the default, says so once) or refused"
        }),
        "output" => json!({
            "type": "object",
            "additionalProperties": false,
            "description": "rows between major steps: `refine: N`, or a fixed grid `every: DT`",
            "properties": {
                "refine": { "$ref": "#/definitions/number" },
                "every": { "$ref": "#/definitions/number" }
            }
        }),
        "solver" => {
            let props: Map<String, Value> = SOLVER_KEYS.iter().map(|k| (k.to_string(), solver_doc(k))).collect();
            json!({
                "description": "the solver: a method's name, or its settings",
                "anyOf": [
                    { "enum": METHODS },
                    { "type": "object", "additionalProperties": false, "properties": props }
                ]
            })
        }
        other => json!({ "description": other }),
    };
    let props: Map<String, Value> = SIM_KEYS.iter().map(|k| (k.to_string(), sim_doc(k))).collect();
    json!({ "type": "object", "additionalProperties": false, "description": "how the graph is simulated", "properties": props })
}

/// A plot panel, its keys those `scope.rs` reads.
fn scope() -> Value {
    let doc = |key: &str| match key {
        "title" => json!({ "type": "string" }),
        "signals" => json!({ "type": "array", "items": { "type": "string" }, "description": "recorded names" }),
        "y_label" | "unit" => json!({ "type": "string" }),
        "y_limits" | "window" | "band" => {
            json!({ "type": "array", "minItems": 2, "maxItems": 2, "items": { "$ref": "#/definitions/number" } })
        }
        other => json!({ "description": other }),
    };
    let props: Map<String, Value> = ctlgraph_core::scope::KEYS.iter().map(|k| (k.to_string(), doc(k))).collect();
    json!({ "type": "object", "additionalProperties": false, "properties": props })
}

/// One block type: its parameters, and no other keys. No parameter is
/// listed as required: some are required one of two (the LESO's `omega`
/// or `beta`), which only the block knows; `ctlgraph check` says which.
fn block(t: &BlockType) -> Value {
    let mut props = Map::new();
    props.insert("type".into(), json!({ "const": t.name, "description": t.summary }));
    for p in t.params {
        props.insert(p.name.to_string(), parameter(p));
    }
    json!({
        "type": "object",
        "description": format!("{}\n\n{}", t.summary, t.doc),
        "additionalProperties": false,
        "properties": props
    })
}

/// A parameter's value schema, with its doc, unit and default.
fn parameter(p: &ParamDoc) -> Value {
    let v = match p.kind {
        ParamKind::Number => json!({ "$ref": "#/definitions/number" }),
        ParamKind::Numbers => json!({ "$ref": "#/definitions/numbers" }),
        ParamKind::Matrix => json!({
            "anyOf": [{ "$ref": "#/definitions/number" }, { "type": "array", "items": { "$ref": "#/definitions/numbers" } }]
        }),
        ParamKind::Flag => json!({ "type": "boolean" }),
        ParamKind::Word if !p.options.is_empty() => json!({ "enum": p.options }),
        ParamKind::Word => json!({ "type": "string" }),
        ParamKind::Text => json!({ "type": ["string", "number"] }),
        ParamKind::Words => {
            json!({ "anyOf": [{ "type": "string" }, { "type": "array", "items": { "type": "string" } }] })
        }
        ParamKind::SampleTime => json!({
            "anyOf": [{ "$ref": "#/definitions/number" }, { "type": "array", "minItems": 2, "maxItems": 2, "items": { "$ref": "#/definitions/number" } }]
        }),
        ParamKind::Structure => json!({}),
    };
    let mut doc = crate::reference::doc_text(p);
    match p.default {
        ParamDefault::Required => doc.push_str(" (required)"),
        ParamDefault::Described(words) => doc.push_str(&format!(" (default: {words})")),
        other => doc.push_str(&format!(" (default: {other})")),
    }
    // A `$ref` with siblings is ignored by draft-07 readers: wrap it.
    let mut map = match v {
        Value::Object(m) if !m.contains_key("$ref") => m,
        other => Map::from_iter([("allOf".to_string(), json!([other]))]),
    };
    map.insert("description".into(), Value::String(doc));
    match p.default {
        ParamDefault::Number(x) if x.is_finite() => {
            map.insert("default".into(), json!(x));
        }
        ParamDefault::Flag(b) => {
            map.insert("default".into(), json!(b));
        }
        ParamDefault::Word(w) => {
            map.insert("default".into(), json!(w));
        }
        _ => {}
    }
    Value::Object(map)
}
