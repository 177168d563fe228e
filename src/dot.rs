//! Graphviz rendering of a compiled diagram: one node per block (grouped
//! in clusters per subsystem), one edge per wire, dashed where the input
//! has no direct feedthrough (those edges do not constrain the order).

use ctlgraph_core::Model;
use std::fmt::Write;

pub fn to_dot(model: &Model) -> String {
    let mut s = String::new();
    let title = model.name.as_deref().unwrap_or("ctlgraph");
    let _ = writeln!(s, "digraph \"{}\" {{", escape(title));
    let _ = writeln!(
        s,
        "  rankdir=LR;\n  node [shape=box, fontname=\"sans-serif\"];\n  edge [fontname=\"sans-serif\", fontsize=10];"
    );
    // Blocks grouped by subsystem path (everything before the last `/`).
    let mut clusters: Vec<(&str, Vec<usize>)> = Vec::new();
    for (i, m) in model.meta.iter().enumerate() {
        let prefix = m.name.rsplit_once('/').map_or("", |(p, _)| p);
        match clusters.iter_mut().find(|(p, _)| *p == prefix) {
            Some((_, v)) => v.push(i),
            None => clusters.push((prefix, vec![i])),
        }
    }
    for (k, (prefix, blocks)) in clusters.iter().enumerate() {
        let indent = if prefix.is_empty() { "  " } else { "    " };
        if !prefix.is_empty() {
            let _ = writeln!(s, "  subgraph cluster_{k} {{\n    label=\"{}\"; style=rounded;", escape(prefix));
        }
        for &i in blocks {
            let m = &model.meta[i];
            let _ = writeln!(
                s,
                "{indent}b{i} [label=\"{}\\n({}, {})\"];",
                escape(&m.name),
                escape(&m.type_name),
                m.sample_time
            );
        }
        if !prefix.is_empty() {
            let _ = writeln!(s, "  }}");
        }
    }
    for e in &model.edges {
        let (src, dst) = (&model.meta[e.src], &model.meta[e.dst]);
        let label = format!("{} → {}", src.output_names[e.src_port], dst.input_names[e.dst_port]);
        let style = if e.feedthrough { "" } else { ", style=dashed" };
        let _ = writeln!(s, "  b{} -> b{} [label=\"{}\"{style}];", e.src, e.dst, escape(&label));
    }
    s.push_str("}\n");
    s
}

fn escape(s: &str) -> String {
    s.replace('\\', "\\\\").replace('"', "\\\"")
}
