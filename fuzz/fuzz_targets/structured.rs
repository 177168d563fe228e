//! Graph files built from the block registry: real block types with their
//! own parameter names (values drawn from defaults, edge numbers, lists and
//! expressions) and wires between their real port names, so the fuzzer
//! spends its time in the compiler, the block builders and the simulator
//! rather than in the YAML parser. Every refusal must carry a position in
//! the file; a graph that compiles is run for a bounded number of steps.
#![no_main]

use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;
use ctlgraph::core::ParamDefault;
use std::fmt::Write;

#[derive(Arbitrary, Debug)]
struct Graph {
    solver: u8,
    step: u8,
    stop: u8,
    blocks: Vec<BlockGen>,
    wires: Vec<(u8, u8, u8, u8)>,
}

#[derive(Arbitrary, Debug)]
struct BlockGen {
    ty: u16,
    params: Vec<(u8, Value)>,
    /// Whether required parameters are left out (exercises the messages).
    omit_required: bool,
}

#[derive(Arbitrary, Debug)]
enum Value {
    Default,
    Edge(u8),
    Number(f64),
    List(Vec<u8>),
    Expr(u8),
}

/// Numbers at the edges of what blocks accept.
const EDGES: &[&str] = &[
    "0", "1", "-1", "0.5", "2", "1e-3", "1e-9", "100", "1e6", "1e300", "-1e300", "5e-324", ".inf", "-.inf", ".nan",
    "3", "7", "1000", "0.01", "-0.5",
];
const EXPRS: &[&str] = &["\"t\"", "\"sin(t)\"", "\"u1 + u2\"", "\"1/0\"", "\"u^2\"", "\"k\"", "\"max(u, 0)\"", "\"x\""];
const SOLVERS: &[&str] = &["rk4", "euler", "heun", "dopri5", "trbdf2"];
const STEPS: &[&str] = &["1e-3", "0.01", "0.1", "1e-5", "0.05"];

/// A parameter's default as a graph writes it, if it has one the parser reads.
fn written(default: ParamDefault) -> Option<String> {
    match default {
        ParamDefault::Required | ParamDefault::Described(_) => None,
        other => Some(other.to_string()),
    }
}

fn value(v: &Value, default: Option<String>) -> String {
    match v {
        Value::Default => default.unwrap_or_else(|| "1".to_string()),
        Value::Edge(k) => EDGES[*k as usize % EDGES.len()].to_string(),
        Value::Number(x) if x.is_finite() => format!("{x:e}"),
        Value::Number(_) => ".nan".to_string(),
        Value::List(items) => {
            let items: Vec<&str> = items.iter().take(8).map(|k| EDGES[*k as usize % EDGES.len()]).collect();
            format!("[{}]", items.join(", "))
        }
        Value::Expr(k) => EXPRS[*k as usize % EXPRS.len()].to_string(),
    }
}

fn render(g: &Graph, registry: &ctlgraph::core::Registry) -> String {
    let types: Vec<_> = registry.types().collect();
    let mut text = format!(
        "parameters: {{ k: 2 }}\nsimulation: {{ stop: {}, solver: {{ method: {}, step: {} }} }}\nblocks:\n",
        1 + g.stop % 4,
        SOLVERS[g.solver as usize % SOLVERS.len()],
        STEPS[g.step as usize % STEPS.len()]
    );
    let chosen: Vec<_> = g.blocks.iter().take(12).map(|b| (b, types[b.ty as usize % types.len()])).collect();
    for (i, (b, t)) in chosen.iter().enumerate() {
        let mut params = Vec::new();
        if !b.omit_required {
            for p in t.params.iter().filter(|p| matches!(p.default, ParamDefault::Required)) {
                params.push(format!("{}: 1", p.name));
            }
        }
        for (k, v) in b.params.iter().take(6) {
            if t.params.is_empty() {
                break;
            }
            let p = &t.params[*k as usize % t.params.len()];
            params.retain(|q: &String| !q.starts_with(&format!("{}:", p.name)));
            params.push(format!("{}: {}", p.name, value(v, written(p.default))));
        }
        let _ = writeln!(text, "  b{i}: {{ type: {}{}{} }}", t.name, if params.is_empty() { "" } else { ", " }, params.join(", "));
    }
    let port = |names: &[ctlgraph::core::registry::PortDoc], k: u8| match names.len() {
        0 => format!("u{}", k % 4 + 1),
        n => names[k as usize % n].name.to_string(),
    };
    let wires: Vec<String> = g
        .wires
        .iter()
        .take(24)
        .filter(|_| !chosen.is_empty())
        .map(|&(from, out, to, input)| {
            let (a, ta) = (from as usize % chosen.len(), chosen[from as usize % chosen.len()].1);
            let (b, tb) = (to as usize % chosen.len(), chosen[to as usize % chosen.len()].1);
            format!("b{a}.{} -> b{b}.{}", port(ta.outputs, out), port(tb.inputs, input))
        })
        .collect();
    if !wires.is_empty() {
        let _ = writeln!(text, "wires: [{}]", wires.join(", "));
    }
    text
}

fuzz_target!(|g: Graph| {
    let registry = ctlgraph::registry();
    let text = render(&g, &registry);
    match ctlgraph::compile_str(&text, "fuzz.yaml", &[]) {
        Err(d) => assert!(d.pos.is_some(), "an unpositioned error for\n{text}\n{d}"),
        Ok(model) => {
            let mut sim = ctlgraph::core::Simulator::new(model, None);
            for _ in 0..2000 {
                if sim.outputs().is_err() || sim.finished() || sim.advance().is_err() {
                    break;
                }
            }
        }
    }
});
