//! `ctlgraph blocks [TYPE]` and `ctlgraph schema [--out FILE.json]`: the
//! block library as text, and as the graph file's JSON Schema.

use ctlgraph::suite::Failure;
use ctlgraph_core::Diagnostic;
use std::path::Path;

pub(crate) fn blocks(ty: Option<&str>) -> Result<(), Failure> {
    let reg = ctlgraph::registry();
    let Some(name) = ty else {
        let mut categories: Vec<&str> = reg.types().map(|t| t.category).collect();
        categories.sort();
        categories.dedup();
        for cat in categories {
            println!("{cat}:");
            for t in reg.types().filter(|t| t.category == cat) {
                println!("  {:<28} {}", t.name, t.summary);
            }
        }
        println!("\n`ctlgraph blocks TYPE` documents one type.");
        return Ok(());
    };
    let Some(t) = reg.get(name) else {
        return Err(Diagnostic::plain(format!("no block type `{name}`")).suggest(name, reg.names()).into());
    };
    println!("{} ({})\n\n{}\n\n{}\n", t.name, t.category, t.summary, t.doc);
    if ctlgraph::reference::has_c_form(t.name) {
        println!("C form: yes (ctlgraph codegen --target c)\n");
    }
    for (title, ports) in [("inputs", t.inputs), ("outputs", t.outputs)] {
        println!("{title}:");
        if ports.is_empty() {
            println!("  (none)");
        }
        for p in ports {
            println!("  {:<14} {}", p.name, p.doc);
        }
    }
    println!("parameters:");
    if t.params.is_empty() {
        println!("  (none)");
    }
    for p in t.params {
        let default = match p.default {
            ctlgraph_core::ParamDefault::Required => "required".to_string(),
            value => format!("default {value}"),
        };
        println!("  {:<14} {:<11} {:<18} {}", p.name, p.kind.name(), default, ctlgraph::reference::doc_text(p));
    }
    Ok(())
}

pub(crate) fn schema(out: Option<&Path>) -> Result<(), Failure> {
    let schema = ctlgraph::schema::schema(&ctlgraph::registry());
    let mut text = serde_json::to_string_pretty(&schema).map_err(|e| Failure::Run(e.to_string()))?;
    text.push('\n');
    crate::write_or_print(out, &text)
}
