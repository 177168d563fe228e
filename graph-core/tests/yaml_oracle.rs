//! The loader against an independent one: serde-saphyr (which ctlgraph
//! used before its own loader) deserialising into the same tree through
//! `Spanned<T>`, over every bundled graph and thousands of mutations of
//! them (bytes changed, lines dropped, doubled, re-indented). Both must
//! accept the same files and build the same tree, positions included, and
//! refuse the same files. The one difference by design: see `has_alias`.

use ctlgraph_core::yaml::{self, Key, Kind, Yaml};
use serde::de::{Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use serde_saphyr::Spanned;
use std::fmt;
use std::path::Path;
use std::sync::Arc;

/// The loader as it was: serde-saphyr with the options ctlgraph used.
fn reference(text: &str, file: &Arc<str>) -> Result<Yaml, String> {
    let mut options = serde_saphyr::Options::default();
    options.strict_booleans = true;
    options.non_finite_float_policy = serde_saphyr::NonFiniteFloatPolicy::PassThrough;
    let mut budget = serde_saphyr::Budget::default();
    budget.max_nodes = yaml::MAX_YAML_NODES;
    budget.max_events = 2 * yaml::MAX_YAML_NODES;
    options.budget = Some(budget);
    serde_saphyr::from_str_with_options::<Spanned<Node>>(text, options)
        .map(|root| convert(root, file, text))
        .map_err(|e| e.without_snippet().to_string())
}

fn pos_of<T>(s: &Spanned<T>, file: &Arc<str>) -> ctlgraph_core::diag::Pos {
    ctlgraph_core::diag::Pos::new(file.clone(), s.referenced.line() as u32, s.referenced.column() as u32)
}

/// The tree, quoted strings placed at their first character as ours are.
fn convert(node: Spanned<Node>, file: &Arc<str>, text: &str) -> Yaml {
    let mut pos = pos_of(&node, file);
    let kind = match node.value {
        Node::Null => Kind::Null,
        Node::Bool(b) => Kind::Bool(b),
        Node::Num(v) => Kind::Num(v),
        Node::Str(s) => {
            let at = node.referenced.span().byte_offset().map(|b| b as usize);
            if at.and_then(|i| text.as_bytes().get(i)).is_some_and(|&b| b == b'"' || b == b'\'') {
                pos = pos.shifted(1);
            }
            Kind::Str(s)
        }
        Node::Seq(items) => Kind::Seq(items.into_iter().map(|n| convert(n, file, text)).collect()),
        Node::Map(entries) => Kind::Map(
            entries
                .into_iter()
                .map(|(k, v)| (Key { pos: pos_of(&k, file), name: k.value }, convert(v, file, text)))
                .collect(),
        ),
    };
    Yaml { pos, kind }
}

enum Node {
    Null,
    Bool(bool),
    Num(f64),
    Str(String),
    Seq(Vec<Spanned<Node>>),
    Map(Vec<(Spanned<String>, Spanned<Node>)>),
}

impl<'de> Deserialize<'de> for Node {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(NodeVisitor)
    }
}

struct NodeVisitor;

impl<'de> Visitor<'de> for NodeVisitor {
    type Value = Node;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("any YAML value")
    }
    fn visit_unit<E>(self) -> Result<Node, E> {
        Ok(Node::Null)
    }
    fn visit_none<E>(self) -> Result<Node, E> {
        Ok(Node::Null)
    }
    fn visit_bool<E>(self, b: bool) -> Result<Node, E> {
        Ok(Node::Bool(b))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Node, E> {
        Ok(Node::Num(v as f64))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Node, E> {
        Ok(Node::Num(v as f64))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Node, E> {
        Ok(Node::Num(v))
    }
    fn visit_str<E>(self, v: &str) -> Result<Node, E> {
        Ok(Node::Str(v.to_string()))
    }
    fn visit_string<E>(self, v: String) -> Result<Node, E> {
        Ok(Node::Str(v))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Node, A::Error> {
        let mut items = Vec::new();
        while let Some(item) = seq.next_element()? {
            items.push(item);
        }
        Ok(Node::Seq(items))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Node, A::Error> {
        let mut entries = Vec::new();
        while let Some(key) = map.next_key()? {
            entries.push((key, map.next_value()?));
        }
        Ok(Node::Map(entries))
    }
}

/// Trees equal, positions included (unless `copied`), NaN equal to NaN.
fn same(a: &Yaml, b: &Yaml, copied: bool) -> bool {
    (copied || a.pos == b.pos)
        && match (&a.kind, &b.kind) {
            (Kind::Num(x), Kind::Num(y)) => x == y || (x.is_nan() && y.is_nan()),
            (Kind::Seq(x), Kind::Seq(y)) => x.len() == y.len() && x.iter().zip(y).all(|(a, b)| same(a, b, copied)),
            (Kind::Map(x), Kind::Map(y)) => {
                x.len() == y.len()
                    && x.iter().zip(y).all(|((ka, a), (kb, b))| {
                        ka.name == kb.name && (copied || ka.pos == kb.pos) && same(a, b, copied)
                    })
            }
            (x, y) => x == y,
        }
}

/// Inside what an alias copies, serde-saphyr places every node at the
/// alias; ours keep the positions where they are written (where a mistake
/// in them is). With aliases about, only the trees' shapes and values are
/// compared.
fn has_alias(text: &str) -> bool {
    text.as_bytes().windows(2).any(|w| w[0] == b'*' && w[1].is_ascii_alphabetic())
}

fn graphs() -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut todo = vec![Path::new(env!("CARGO_MANIFEST_DIR")).join("../graphs")];
    while let Some(dir) = todo.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                todo.push(path);
            } else if path.extension().is_some_and(|e| e == "yaml") {
                out.push((path.display().to_string(), std::fs::read_to_string(&path).unwrap()));
            }
        }
    }
    out.sort();
    out
}

/// A small deterministic generator (xorshift), so a failure reproduces.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const ALPHABET: &[u8] = b" :-[]{},#&*!|>'\"\n\tab01.e<";

fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut bytes = text.as_bytes().to_vec();
    let mut lines: Vec<&str> = text.lines().collect();
    match rng.below(5) {
        0 => {
            let i = rng.below(bytes.len());
            bytes[i] = ALPHABET[rng.below(ALPHABET.len())];
            String::from_utf8_lossy(&bytes).into_owned()
        }
        1 => {
            let i = rng.below(bytes.len());
            bytes.insert(i, ALPHABET[rng.below(ALPHABET.len())]);
            String::from_utf8_lossy(&bytes).into_owned()
        }
        2 => {
            lines.remove(rng.below(lines.len()));
            lines.join("\n")
        }
        3 => {
            let i = rng.below(lines.len());
            lines.insert(i, lines[i]);
            lines.join("\n")
        }
        _ => {
            let i = rng.below(lines.len());
            let indented = format!("  {}", lines[i]);
            lines[i] = &indented;
            lines.join("\n")
        }
    }
}

fn compare(name: &str, text: &str, failures: &mut Vec<String>) {
    let file: Arc<str> = "g.yaml".into();
    let ours = yaml::parse(text, &file);
    let theirs = reference(text, &file);
    match (&ours, &theirs) {
        (Ok(_), Ok(_)) | (Err(_), Err(_)) => {}
        _ => failures.push(format!("{name}: ours {}, serde-saphyr {}", outcome(&ours), outcome(&theirs))),
    }
    if let (Ok(a), Ok(b)) = (&ours, &theirs)
        && !same(a, b, has_alias(text))
        && let Some(d) = first_difference(a, b)
    {
        failures.push(format!("{name}: {d}"));
    }
}

fn outcome<E: fmt::Display>(r: &Result<Yaml, E>) -> String {
    match r {
        Ok(_) => "accepts".into(),
        Err(e) => format!("refuses ({e})"),
    }
}

/// The first node where two trees differ, for the failure message.
fn first_difference(a: &Yaml, b: &Yaml) -> Option<String> {
    let here = || Some(format!("ours {:?} at {}, serde-saphyr {:?} at {}", short(a), a.pos, short(b), b.pos));
    match (&a.kind, &b.kind) {
        (Kind::Seq(x), Kind::Seq(y)) if x.len() == y.len() => {
            x.iter().zip(y).find_map(|(a, b)| first_difference(a, b)).or_else(|| (a.pos != b.pos).then(here).flatten())
        }
        (Kind::Map(x), Kind::Map(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .find_map(|((ka, a), (kb, b))| {
                if ka != kb {
                    Some(format!("key ours {} at {}, serde-saphyr {} at {}", ka.name, ka.pos, kb.name, kb.pos))
                } else {
                    first_difference(a, b)
                }
            })
            .or_else(|| (a.pos != b.pos).then(here).flatten()),
        _ => (!same(a, b, false)).then(here).flatten(),
    }
}

fn short(y: &Yaml) -> String {
    match &y.kind {
        Kind::Seq(x) => format!("list of {}", x.len()),
        Kind::Map(x) => format!("map of {}", x.len()),
        k => format!("{k:?}"),
    }
}

/// What the bundled graphs do not exercise.
const EDGES: &[&str] = &[
    "a: &x { k: 1, m: [1, 2] }\nb: *x\n",
    "base: &b { type: gain, k: 2 }\ng: { <<: *b, k: 3 }\n",
    "a: &a { x: 1 }\nb: &b { y: 2, x: 5 }\nc: { <<: [*a, *b], z: 3 }\n",
    "a: 1\nb: 2\na: 3\n",
    "a: !!str 12\nb: !!float 3\nc: !!int 0x10\nd: !!null x\ne: !custom 5\nf: ! 7\n",
    "a: !!int abc\n",
    "a: !!bool yes\n",
    "[y, n, on, off, yes, true, True, TRUE, false, null, ~, '', \"\"]",
    "[0, -0, +1, 0127, -0127, 1_000, 0x1F, 0o17, 0b101, 1.5, .5, -2e-3, 1e999, -.inf, .NaN, inf, nan, 1__0, 0x]",
    "[18446744073709551615, 18446744073709551616, -9223372036854775808, -9223372036854775809]",
    "k: \"a\\tb\"\nl: 'it''s'\nm: \"two\n  lines\"\n",
    "k: |\n  literal\n  text\nl: >\n  folded\n  text\n",
    "---\na: 1\n---\nb: 2\n",
    "---\na: 1\n...\n",
    "",
    "# only a comment\n",
    "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]",
    "? [a, b]\n: 1\n",
    "{ [a]: 1 }",
    "a: *nope\n",
    "&k key: 1\n*k : 2\n",
    "a: &v 1\n*v : 2\n",
    "a: [1, 2\nb: 3\n",
    "a:\n\t- 1\n",
    "a: 'unterminated\n",
    ": 1\n",
    "null: 1\n",
    "1: one\n2.5: two\ntrue: three\n",
    "a: { b: 1, b: 2 }\n",
    "<<: 5\n",
    "a: [ &x 1, *x, *x ]\n",
    "\u{feff}a: 1\nb: [x, y]\n",
    "a: 1\r\nb:\r\n  - x\r\n  - \"y\"\r\n",
    "---\n",
    "a:\n  b: 1\n c: 2\n",
    "a: \"\\u00e9t\u{e9}\" # comment\nb: '\u{3c9}\u{2080}'\n",
    "\"quoted key\": 1\n'single': 2\n",
];

#[test]
fn the_loader_agrees_with_serde_saphyr() {
    let mut failures = Vec::new();
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    for (name, text) in graphs() {
        compare(&name, &text, &mut failures);
        for k in 0..300 {
            let mut t = text.clone();
            for _ in 0..1 + k % 3 {
                t = mutate(&t, &mut rng);
            }
            compare(&format!("{name} mutation {k}"), &t, &mut failures);
        }
    }
    for (k, text) in EDGES.iter().enumerate() {
        compare(&format!("edge case {k}"), text, &mut failures);
    }
    assert!(
        failures.is_empty(),
        "{} differences; first:\n{}",
        failures.len(),
        failures[..failures.len().min(40)].join("\n\n")
    );
}
