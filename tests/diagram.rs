//! `ctlgraph diagram`: every bundled graph, collapsed and expanded, shows
//! every block once, with no two boxes overlapping, and wires between
//! the right ports.

mod common;
use common::bundled_graphs;
use ctlgraph::diagram::{Diagram, build, to_svg};
use std::path::Path;

fn overlapping(d: &Diagram) -> Option<(String, String)> {
    for (i, a) in d.nodes.iter().enumerate() {
        for b in &d.nodes[i + 1..] {
            let apart = a.x + a.w <= b.x || b.x + b.w <= a.x || a.y + a.h <= b.y || b.y + b.h <= a.y;
            if !apart {
                return Some((a.name.clone(), b.name.clone()));
            }
        }
    }
    None
}

#[test]
fn every_bundled_graph_is_drawn_whole_without_overlaps() {
    let files = bundled_graphs();
    let mut drawn = 0;
    for file in &files {
        let Ok(flat) = ctlgraph::core::load(file, &[]) else { continue };
        let Ok(model) = ctlgraph::core::compile(&flat, &ctlgraph::registry()) else { continue };
        for expand in [false, true] {
            let d = build(&flat, &model, expand);
            if let Some((a, b)) = overlapping(&d) {
                panic!("{}: boxes `{a}` and `{b}` overlap (expand: {expand})", file.display());
            }
            // Every block once: expanded, every block of the file; collapsed,
            // every top-level block and subsystem.
            let mut expected: Vec<String> = flat
                .blocks
                .iter()
                .map(|b| if expand { b.path.clone() } else { b.path.split('/').next().unwrap().to_string() })
                .collect();
            expected.sort();
            expected.dedup();
            let mut names: Vec<String> = d.nodes.iter().map(|n| n.name.clone()).collect();
            names.sort();
            assert_eq!(names, expected, "{}", file.display());
            let svg = to_svg(&d);
            for n in &d.nodes {
                assert!(svg.contains(&format!("data-name=\"{}\"", n.name)), "{}: {}", file.display(), n.name);
            }
            for w in &d.wires {
                assert!(
                    w.src_port < d.nodes[w.src].outputs.len() && w.dst_port < d.nodes[w.dst].inputs.len(),
                    "{}: {} -> {} ({w:?})",
                    file.display(),
                    d.nodes[w.src].name,
                    d.nodes[w.dst].name
                );
            }
            drawn += 1;
        }
    }
    assert!(drawn >= 60, "only {drawn} diagrams drawn");
}

#[test]
fn a_collapsed_subsystem_is_one_box_wired_at_its_ports() {
    let flat = ctlgraph::core::load(Path::new("graphs/tutorial/subsystem.yaml"), &[]).unwrap();
    let model = ctlgraph::core::compile(&flat, &ctlgraph::registry()).unwrap();
    let d = build(&flat, &model, false);
    let soft = d.nodes.iter().position(|n| n.name == "soft").unwrap();
    assert!(d.nodes[soft].subsystem);
    assert_eq!(
        (d.nodes[soft].inputs.clone(), d.nodes[soft].outputs.clone()),
        (vec!["r".into(), "y".into()], vec!["u".into()])
    );
    let into_soft: Vec<(&str, &str)> = d
        .wires
        .iter()
        .filter(|w| w.dst == soft)
        .map(|w| (d.nodes[w.src].name.as_str(), d.nodes[soft].inputs[w.dst_port].as_str()))
        .collect();
    assert_eq!(into_soft, [("r", "r"), ("plant_soft", "y")]);
    // The loop is cut at the plant's output: drawn back, everything else forward.
    let plant = d.nodes.iter().position(|n| n.name == "plant_soft").unwrap();
    assert!(d.nodes[plant].x > d.nodes[soft].x, "the plant is drawn after its controller");
}

#[test]
fn the_cli_writes_the_svg() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d.svg");
    let done = std::process::Command::new(env!("CARGO_BIN_EXE_ctlgraph"))
        .args(["diagram", "graphs/tutorial/pid_loop.yaml", "--svg", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(done.status.success(), "{}", String::from_utf8_lossy(&done.stderr));
    assert_eq!(String::from_utf8_lossy(&done.stdout), format!("{}: 4 boxes, 4 wires\n", out.display()));
    assert!(std::fs::read_to_string(&out).unwrap().starts_with("<svg "));
}

/// A box shows a parameter written as an expression with its value, and a
/// short list by its values (`kp = kp (2)`, `den = [1, 14, 100]`), not
/// `[3 values]`.
#[test]
fn boxes_show_expressions_with_their_values() {
    let flat = ctlgraph::core::load(Path::new("graphs/tutorial/pid_loop.yaml"), &[]).unwrap();
    let model = ctlgraph::core::compile(&flat, &ctlgraph::registry()).unwrap();
    let d = build(&flat, &model, false);
    let lines = |name: &str| d.nodes.iter().find(|n| n.name == name).unwrap().lines.clone();
    assert!(lines("ctrl").contains(&"kp = kp (2)".to_string()), "{:?}", lines("ctrl"));
    let plant = lines("plant");
    assert!(plant.iter().any(|l| l.starts_with("den = [1, ") && !l.contains("values")), "{plant:?}");
}

/// The room below the boxes is the feedback wires' lanes (12 px each) and
/// a margin, not a lane for every wire (which left a quarter of a diagram
/// blank).
#[test]
fn the_drawing_ends_below_its_last_feedback_lane() {
    for file in ["graphs/tutorial/pid_loop.yaml", "graphs/fladrc/ladrc.yaml"] {
        let flat = ctlgraph::core::load(Path::new(file), &[]).unwrap();
        let model = ctlgraph::core::compile(&flat, &ctlgraph::registry()).unwrap();
        let d = build(&flat, &model, false);
        let feedback = to_svg(&d).matches("class=\"wire feedback\"").count();
        let bottom = d.nodes.iter().map(|n| n.y + n.h).fold(0.0, f64::max);
        let below = d.height - bottom;
        assert!(below <= 30.0 + 12.0 * feedback.min(10) as f64, "{file}: {below} px below the boxes, {feedback} lanes");
        assert!(below >= 12.0 * feedback.min(10) as f64, "{file}: the lanes fit");
    }
}
