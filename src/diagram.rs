//! The block diagram drawn by ctlgraph itself (`ctlgraph diagram`): blocks
//! as boxes labelled with name, type and key parameters, their ports on
//! the left (inputs) and right (outputs), wires left to right, feedback
//! wires drawn back underneath. Subsystems are one box each, or expanded
//! into their blocks. The layered placement is layout-rs's (a Sugiyama
//! layout, as Graphviz's `dot`); the drawing is ours, so that ports,
//! labels and wires look like a block diagram rather than a graph.

use ctlgraph_core::flatten::{INPORT, OUTPORT};
use ctlgraph_core::yaml::Kind;
use ctlgraph_core::{FlatGraph, Model};
use std::collections::HashMap;
use std::fmt::Write;

/// A block (or collapsed subsystem) and where it is drawn.
#[derive(Clone, Debug)]
pub struct Node {
    pub name: String,
    /// Type, then key parameters: the lines under the name.
    pub lines: Vec<String>,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    pub subsystem: bool,
    /// A block with inputs none of which reaches its outputs at once (a
    /// strictly proper plant, a delay): its output wires may be drawn as
    /// feedback.
    pub state_output: bool,
    /// Top-left corner and size [px].
    pub x: f64,
    pub y: f64,
    pub w: f64,
    pub h: f64,
}

/// A wire from output `src_port` of node `src` to input `dst_port` of `dst`.
#[derive(Clone, Debug)]
pub struct Wire {
    pub src: usize,
    pub src_port: usize,
    pub dst: usize,
    pub dst_port: usize,
}

#[derive(Clone, Debug)]
pub struct Diagram {
    pub title: String,
    pub nodes: Vec<Node>,
    pub wires: Vec<Wire>,
    pub width: f64,
    pub height: f64,
}

const CHAR_W: f64 = 7.0;
const LINE_H: f64 = 15.0;
const PORT_H: f64 = 18.0;
const PAD: f64 = 8.0;
const MARGIN: f64 = 30.0;
/// Parameters shown under a block's type, at most.
const SHOWN_PARAMS: usize = 3;

/// The diagram of `flat` (as loaded) compiled as `model`: subsystems
/// collapsed to one box each unless `expand`.
pub fn build(flat: &FlatGraph, model: &Model, expand: bool) -> Diagram {
    // A block inside another (a loop's, a conditional subsystem's) is drawn as itself.
    let members = model.inner_blocks.iter().map(|m| (m.name.as_str(), (&m.input_names[..], &m.output_names[..])));
    let ports: HashMap<&str, (&[String], &[String])> = model
        .meta
        .iter()
        .map(|m| (m.name.as_str(), (&m.input_names[..], &m.output_names[..])))
        .chain(members)
        .collect();
    let top_subsystems: HashMap<&str, &(Vec<String>, Vec<String>)> =
        flat.subsystems.iter().filter(|(s, _)| !s.contains('/')).map(|(s, p)| (s.as_str(), p)).collect();
    let mut nodes: Vec<Node> = Vec::new();
    let mut index: HashMap<String, usize> = HashMap::new();
    for b in &flat.blocks {
        let top = b.path.split('/').next().unwrap_or(&b.path);
        let collapsed = !expand && top_subsystems.contains_key(top) && b.path.contains('/');
        if collapsed {
            if !index.contains_key(top) {
                let (ins, outs) = top_subsystems[top];
                index.insert(top.to_string(), nodes.len());
                let file = subsystem_file(flat, top);
                nodes.push(node(top, vec![format!("subsystem {file}")], ins.clone(), outs.clone(), true));
            }
            continue;
        }
        let ty = b.spec.type_name.as_str();
        // A subsystem's ports pass a signal through; the graph's own
        // (top-level) ports only start or end one.
        let port = || vec![String::new()];
        let (ins, outs) = match ty {
            _ if (ty == INPORT || ty == OUTPORT) && b.path.contains('/') => (port(), port()),
            INPORT => (vec![], port()),
            OUTPORT => (port(), vec![]),
            _ => match ports.get(b.path.as_str()) {
                Some((i, o)) => (i.to_vec(), o.to_vec()),
                None => continue,
            },
        };
        let mut lines = vec![ty.to_string()];
        lines.extend(key_params(b));
        index.insert(b.path.clone(), nodes.len());
        nodes.push(node(&b.path, lines, ins, outs, false));
    }
    // Wires: each end to its node and port (a collapsed subsystem's port
    // by the inport or outport it passes through).
    let end = |path: &str, port: &Option<String>, output: bool| -> Option<(usize, usize)> {
        if let Some(&i) = index.get(path) {
            let names = if output { &nodes[i].outputs } else { &nodes[i].inputs };
            let k = match port {
                Some(p) => names.iter().position(|n| n == p)?,
                None => 0,
            };
            return Some((i, k));
        }
        let (top, inner) = path.split_once('/')?;
        let &i = index.get(top)?;
        let names = if output { &nodes[i].outputs } else { &nodes[i].inputs };
        Some((i, names.iter().position(|n| n == inner)?))
    };
    let mut wires = Vec::new();
    for w in &flat.wires {
        let (Some((src, src_port)), Some((dst, dst_port))) =
            (end(&w.src.block, &w.src.port, true), end(&w.dst.block, &w.dst.port, false))
        else {
            continue;
        };
        if src != dst || !nodes[src].subsystem {
            wires.push(Wire { src, src_port, dst, dst_port });
        }
    }
    // Which blocks' outputs do not depend on their inputs at once.
    let mut feedthrough = vec![None::<bool>; model.meta.len()];
    for e in &model.edges {
        let f = feedthrough[e.dst].get_or_insert(false);
        *f |= e.feedthrough;
    }
    for (m, f) in model.meta.iter().zip(feedthrough) {
        if let (Some(&i), Some(false)) = (index.get(&m.name), f) {
            nodes[i].state_output = true;
        }
    }
    let title = flat.name.clone().unwrap_or_else(|| flat.file.to_string());
    let mut d = Diagram { title, nodes, wires, width: 0.0, height: 0.0 };
    place(&mut d);
    d
}

fn node(name: &str, lines: Vec<String>, inputs: Vec<String>, outputs: Vec<String>, subsystem: bool) -> Node {
    let text = lines.iter().map(String::len).chain([name.len()]).max().unwrap_or(0) as f64 * CHAR_W;
    let label = |ps: &[String]| ps.iter().map(String::len).max().unwrap_or(0) as f64 * CHAR_W * 0.85;
    let w = (text + label(&inputs) + label(&outputs) + 3.0 * PAD).max(60.0);
    let h = ((lines.len() + 1) as f64 * LINE_H + 2.0 * PAD).max(inputs.len().max(outputs.len()) as f64 * PORT_H + PAD);
    Node { name: name.to_string(), lines, inputs, outputs, subsystem, state_output: false, x: 0.0, y: 0.0, w, h }
}

fn subsystem_file(flat: &FlatGraph, sub: &str) -> String {
    let spec = flat
        .blocks
        .iter()
        .find(|b| b.path.starts_with(&format!("{sub}/")))
        .map(|b| b.spec.pos.file.to_string())
        .unwrap_or_default();
    spec.rsplit('/').next().unwrap_or(&spec).to_string()
}

/// Up to [`SHOWN_PARAMS`] parameters: numbers, short texts, short lists;
/// an expression of the graph's parameters as written and its value
/// (`kp = kp (2)`), a list of up to four numbers by its values.
fn key_params(b: &ctlgraph_core::flatten::FlatBlock) -> Vec<String> {
    let mut shown = Vec::new();
    for (key, value) in &b.spec.params {
        if key.name == "type" || shown.len() == SHOWN_PARAMS {
            continue;
        }
        let text = match &value.kind {
            Kind::Num(v) => format!("{v}"),
            Kind::Str(s) => match resolved(b, value) {
                Some(v) if v.to_string() != *s => format!("{s} ({v})"),
                _ => s.clone(),
            },
            Kind::Bool(v) => v.to_string(),
            Kind::Seq(items) => {
                let values: Option<Vec<String>> =
                    items.iter().map(|item| resolved(b, item).map(|v| v.to_string())).collect();
                match values {
                    Some(values) if items.len() <= 4 => format!("[{}]", values.join(", ")),
                    _ => format!("[{} values]", items.len()),
                }
            }
            Kind::Map(_) | Kind::Null => continue,
        };
        let text =
            if text.chars().count() > 24 { format!("{}…", text.chars().take(23).collect::<String>()) } else { text };
        shown.push(format!("{} = {text}", key.name));
    }
    shown
}

/// A number, or an expression of the graph's parameters evaluated in the
/// block's scope; `None` for anything else (a formula in the block's own
/// variables, a word, a file).
fn resolved(b: &ctlgraph_core::flatten::FlatBlock, value: &ctlgraph_core::yaml::Yaml) -> Option<f64> {
    match &value.kind {
        Kind::Num(v) => Some(*v),
        Kind::Str(s) => ctlgraph_core::params::eval_number(s, &value.pos, &b.scope).ok(),
        _ => None,
    }
}

/// Positions by layout-rs's layered placement (left to right); if it
/// fails, one column per node in file order.
fn place(d: &mut Diagram) {
    use layout::backends::svg::SVGWriter;
    use layout::core::base::Orientation;
    use layout::core::geometry::Point;
    use layout::core::style::StyleAttr;
    use layout::std_shapes::shapes::{Arrow, Element, ShapeKind};
    use layout::topo::layout::VisualGraph;
    let sizes: Vec<(f64, f64)> = d.nodes.iter().map(|n| (n.w, n.h)).collect();
    let pairs = forward_wires(d);
    let placed = std::panic::catch_unwind(move || {
        let mut vg = VisualGraph::new(Orientation::LeftToRight);
        let handles: Vec<_> = sizes
            .iter()
            .map(|&(w, h)| {
                let shape = ShapeKind::Box(String::new());
                vg.add_node(Element::create(shape, StyleAttr::simple(), Orientation::LeftToRight, Point::new(w, h)))
            })
            .collect();
        for (s, t) in pairs {
            vg.add_edge(Arrow::simple(""), handles[s], handles[t]);
        }
        vg.do_it(false, false, false, &mut SVGWriter::new());
        handles.iter().map(|&h| vg.pos(h).bbox(false).0).map(|p| (p.x, p.y)).collect::<Vec<_>>()
    });
    match placed {
        Ok(corners) => {
            for (n, (x, y)) in d.nodes.iter_mut().zip(corners) {
                (n.x, n.y) = (x, y);
            }
        }
        Err(_) => {
            let mut x = 0.0;
            for n in &mut d.nodes {
                (n.x, n.y) = (x, 0.0);
                x += n.w + 2.0 * MARGIN;
            }
        }
    }
    let min_x = d.nodes.iter().map(|n| n.x).fold(f64::INFINITY, f64::min);
    let min_y = d.nodes.iter().map(|n| n.y).fold(f64::INFINITY, f64::min);
    for n in &mut d.nodes {
        n.x += MARGIN - min_x;
        n.y += MARGIN + 30.0 - min_y;
    }
    d.width = d.nodes.iter().map(|n| n.x + n.w).fold(0.0, f64::max) + MARGIN;
    // Room below for the feedback wires' lanes (see `to_svg`), not one per wire.
    let lanes = d.wires.iter().filter(|w| is_feedback(d, w)).count().min(10);
    d.height = d.nodes.iter().map(|n| n.y + n.h).fold(0.0, f64::max) + MARGIN + 12.0 * lanes as f64;
}

/// The wires that run left to right, as a cycle-free set: first every
/// wire not leaving a block with a state output, then those that do where
/// they close no cycle — so a loop is cut at the plant's output and drawn
/// back from there, as in a hand-drawn block diagram.
fn forward_wires(d: &Diagram) -> Vec<(usize, usize)> {
    let n = d.nodes.len();
    let mut succ: Vec<Vec<usize>> = vec![Vec::new(); n];
    let reaches = |succ: &[Vec<usize>], from: usize, to: usize| {
        let (mut seen, mut stack) = (vec![false; n], vec![from]);
        while let Some(i) = stack.pop() {
            if i == to {
                return true;
            }
            if !std::mem::replace(&mut seen[i], true) {
                stack.extend(&succ[i]);
            }
        }
        false
    };
    let mut kept = Vec::new();
    for late in [false, true] {
        for w in d.wires.iter().filter(|w| d.nodes[w.src].state_output == late) {
            let (s, t) = (w.src, w.dst);
            if s != t && !succ[s].contains(&t) && !reaches(&succ, t, s) {
                succ[s].push(t);
                kept.push((s, t));
            }
        }
    }
    kept
}

/// Whether wire `w` runs back (its input port is not right of its output
/// port): drawn below every block, in a lane of its own.
fn is_feedback(d: &Diagram, w: &Wire) -> bool {
    let (x0, _) = d.nodes[w.src].out_port(w.src_port);
    let (x1, _) = d.nodes[w.dst].in_port(w.dst_port);
    x1 <= x0 + 10.0
}

impl Node {
    fn in_port(&self, k: usize) -> (f64, f64) {
        (self.x, self.y + self.h * (k as f64 + 0.5) / self.inputs.len().max(1) as f64)
    }
    fn out_port(&self, k: usize) -> (f64, f64) {
        (self.x + self.w, self.y + self.h * (k as f64 + 0.5) / self.outputs.len().max(1) as f64)
    }
}

/// The diagram as a standalone SVG document.
pub fn to_svg(d: &Diagram) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0}\" height=\"{:.0}\" viewBox=\"0 0 {:.0} {:.0}\" \
         font-family=\"sans-serif\" font-size=\"12\">",
        d.width, d.height, d.width, d.height
    );
    let _ = writeln!(
        s,
        "<defs><marker id=\"arrow\" markerWidth=\"8\" markerHeight=\"8\" refX=\"8\" refY=\"4\" orient=\"auto\">\
         <path d=\"M0,0 L8,4 L0,8 z\" fill=\"#333\"/></marker></defs>\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>"
    );
    let _ = writeln!(s, "<text x=\"{MARGIN}\" y=\"24\" font-size=\"15\" font-weight=\"bold\">{}</text>", esc(&d.title));
    let bottom = d.nodes.iter().map(|n| n.y + n.h).fold(0.0, f64::max);
    let mut lane = 0;
    for w in &d.wires {
        let (a, b) = (&d.nodes[w.src], &d.nodes[w.dst]);
        let ((x0, y0), (x1, y1)) = (a.out_port(w.src_port), b.in_port(w.dst_port));
        let feedback = is_feedback(d, w);
        let path = if !feedback {
            let c = (x1 - x0) / 2.0;
            format!("M{x0:.1},{y0:.1} C{:.1},{y0:.1} {:.1},{y1:.1} {x1:.1},{y1:.1}", x0 + c, x1 - c)
        } else {
            // Feedback: out to the right, down below every block, back left, up into the port.
            lane += 1;
            let below = bottom + 12.0 * (lane.min(10) as f64);
            format!(
                "M{x0:.1},{y0:.1} H{:.1} V{below:.1} H{:.1} V{y1:.1} H{x1:.1}",
                x0 + 10.0 + 2.0 * lane as f64,
                x1 - 10.0 - 2.0 * lane as f64
            )
        };
        let class = if feedback { "wire feedback" } else { "wire" };
        let _ = writeln!(
            s,
            "<path class=\"{class}\" d=\"{path}\" fill=\"none\" stroke=\"#333\" stroke-width=\"1.3\" \
             marker-end=\"url(#arrow)\"/>"
        );
    }
    for n in &d.nodes {
        let fill = if n.subsystem { "#eef3fb" } else { "#fbfbf5" };
        let _ = writeln!(
            s,
            "<g class=\"block\" data-name=\"{}\"><rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\" rx=\"4\" \
             fill=\"{fill}\" stroke=\"#333\" stroke-width=\"{}\"/>",
            esc(&n.name),
            n.x,
            n.y,
            n.w,
            n.h,
            if n.subsystem { 2 } else { 1 }
        );
        let cx = n.x + n.w / 2.0;
        let top = n.y + (n.h - (n.lines.len() + 1) as f64 * LINE_H) / 2.0 + 11.0;
        let _ = writeln!(
            s,
            "<text x=\"{cx:.1}\" y=\"{top:.1}\" text-anchor=\"middle\" font-weight=\"bold\">{}</text>",
            esc(&n.name)
        );
        for (k, line) in n.lines.iter().enumerate() {
            let _ = writeln!(
                s,
                "<text x=\"{cx:.1}\" y=\"{:.1}\" text-anchor=\"middle\" font-size=\"11\" fill=\"#444\">{}</text>",
                top + (k + 1) as f64 * LINE_H,
                esc(line)
            );
        }
        let labelled =
            |ports: &[String]| ports.len() > 1 || ports.iter().any(|p| !p.is_empty() && p != "u" && p != "y");
        for (k, p) in n.inputs.iter().enumerate().filter(|_| labelled(&n.inputs)) {
            let (x, y) = n.in_port(k);
            let _ = writeln!(
                s,
                "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"9\" fill=\"#666\">{}</text>",
                x + 3.0,
                y + 3.0,
                esc(p)
            );
        }
        for (k, p) in n.outputs.iter().enumerate().filter(|_| labelled(&n.outputs)) {
            let (x, y) = n.out_port(k);
            let _ = writeln!(
                s,
                "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"9\" fill=\"#666\" text-anchor=\"end\">{}</text>",
                x - 3.0,
                y + 3.0,
                esc(p)
            );
        }
        s.push_str("</g>\n");
    }
    s.push_str("</svg>\n");
    s
}

/// Text escaped for XML and HTML content and attribute values.
pub(crate) fn esc(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}
