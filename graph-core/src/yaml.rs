//! A YAML document as a tree in which every node and key keeps its position.
//!
//! serde-saphyr parses; its `Spanned<T>` gives each node's line and column.
//! We deserialize into our own tree rather than straight into typed structs
//! because a block's parameters depend on its `type`, which the registry
//! knows and serde does not (internally tagged enums would lose positions),
//! and because unknown keys must be reported with a "did you mean".

use crate::diag::{Diagnostic, Pos};
use serde::de::{Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use serde_saphyr::Spanned;
use std::fmt;
use std::sync::Arc;

/// A YAML node and where it is.
#[derive(Clone, Debug, PartialEq)]
pub struct Yaml {
    pub pos: Pos,
    pub kind: Kind,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    Null,
    Bool(bool),
    Num(f64),
    Str(String),
    Seq(Vec<Yaml>),
    Map(Vec<(Key, Yaml)>),
}

/// A mapping key and where it is.
#[derive(Clone, Debug, PartialEq)]
pub struct Key {
    pub name: String,
    pub pos: Pos,
}

impl Yaml {
    /// What kind of value this is, for messages ("expected a number, found a list").
    pub fn describe(&self) -> &'static str {
        match self.kind {
            Kind::Null => "nothing",
            Kind::Bool(_) => "a boolean",
            Kind::Num(_) => "a number",
            Kind::Str(_) => "a string",
            Kind::Seq(_) => "a list",
            Kind::Map(_) => "a mapping",
        }
    }

    pub fn as_map(&self) -> Option<&[(Key, Yaml)]> {
        match &self.kind {
            Kind::Map(m) => Some(m),
            _ => None,
        }
    }

    pub fn as_str(&self) -> Option<&str> {
        match &self.kind {
            Kind::Str(s) => Some(s),
            _ => None,
        }
    }

    /// The entries of a mapping, or an error naming `what` was expected.
    pub fn expect_map(&self, what: &str) -> Result<&[(Key, Yaml)], Diagnostic> {
        match &self.kind {
            Kind::Map(m) => Ok(m),
            Kind::Null => Ok(&[]),
            _ => Err(Diagnostic::at(&self.pos, format!("{what} must be a mapping, found {}", self.describe()))),
        }
    }

    pub fn expect_str(&self, what: &str) -> Result<&str, Diagnostic> {
        self.as_str()
            .ok_or_else(|| Diagnostic::at(&self.pos, format!("{what} must be a string, found {}", self.describe())))
    }
}

/// Looks up `name` in mapping entries.
pub fn lookup<'a>(map: &'a [(Key, Yaml)], name: &str) -> Option<&'a Yaml> {
    map.iter().find(|(k, _)| k.name == name).map(|(_, v)| v)
}

/// Most YAML nodes (maps, sequences, scalars) a graph file may have: a
/// million blocks in flow style take about ten million.
pub const MAX_YAML_NODES: usize = 20_000_000;

/// serde-saphyr's limits sized for graphs of a million blocks, its alias
/// protections (alias count, alias-to-anchor ratio, replayed events) kept
/// at their defaults, so a billion-laughs file is still refused at once.
fn budget() -> serde_saphyr::Budget {
    let mut budget = serde_saphyr::Budget::default();
    budget.max_nodes = MAX_YAML_NODES;
    budget.max_events = 2 * MAX_YAML_NODES;
    budget.max_total_scalar_bytes = 256 << 20;
    budget
}

/// Parses a YAML document; syntax errors carry their position. Booleans
/// are YAML 1.2's `true`/`false` only: blocks named `y`, `n`, `on` or
/// `off` stay strings, as a control engineer would expect.
pub fn parse(text: &str, file: &Arc<str>) -> Result<Yaml, Diagnostic> {
    let mut options = serde_saphyr::Options::default();
    options.strict_booleans = true;
    // `.inf` is YAML's infinity, as `inf` is the expressions'; a NaN is
    // refused where the number is used, at its position.
    options.non_finite_float_policy = serde_saphyr::NonFiniteFloatPolicy::PassThrough;
    options.budget = Some(budget());
    match serde_saphyr::from_str_with_options::<Spanned<Node>>(text, options) {
        Ok(root) => Ok(convert(root, file)),
        Err(err) => Err(syntax_error(&err, file)),
    }
}

fn syntax_error(err: &serde_saphyr::Error, file: &Arc<str>) -> Diagnostic {
    let text = err.without_snippet().to_string();
    // The library's text reads "error: line L column C: message".
    let message = text
        .split_once(": ")
        .and_then(|(_, rest)| rest.strip_prefix("line "))
        .and_then(|rest| rest.split_once(": ").map(|(_, msg)| msg))
        .unwrap_or(&text)
        .trim();
    let message = match message.strip_prefix("duplicate mapping key: ") {
        Some(rest) => {
            let key = rest.split(',').next().unwrap_or(rest);
            format!("duplicate key `{key}`: names and keys must be unique within a mapping")
        }
        None => format!("YAML syntax: {message}"),
    };
    match err.location() {
        Some(loc) => Diagnostic::at(&Pos::new(file.clone(), loc.line() as u32, loc.column() as u32), message),
        None => Diagnostic::in_file(file, message),
    }
}

fn pos_of<T>(s: &Spanned<T>, file: &Arc<str>) -> Pos {
    Pos::new(file.clone(), s.referenced.line() as u32, s.referenced.column() as u32)
}

fn convert(node: Spanned<Node>, file: &Arc<str>) -> Yaml {
    let mut pos = pos_of(&node, file);
    let kind = match node.value {
        Node::Null => Kind::Null,
        Node::Bool(b) => Kind::Bool(b),
        Node::Num(v) => Kind::Num(v),
        Node::Str(s) => {
            // Point at the first character of a quoted string, not its quote,
            // so positions inside an expression line up.
            if node.referenced.span().len() as usize == s.chars().count() + 2 {
                pos = pos.shifted(1);
            }
            Kind::Str(s)
        }
        Node::Seq(items) => Kind::Seq(items.into_iter().map(|n| convert(n, file)).collect()),
        Node::Map(entries) => Kind::Map(
            entries
                .into_iter()
                .map(|(k, v)| (Key { pos: pos_of(&k, file), name: k.value }, convert(v, file)))
                .collect(),
        ),
    };
    Yaml { pos, kind }
}

/// The raw node serde-saphyr fills in; children keep their spans.
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

#[cfg(test)]
mod tests {
    use super::*;

    fn file() -> Arc<str> {
        "t.yaml".into()
    }

    #[test]
    fn positions_of_nested_values() {
        let y = parse("blocks:\n  g: { type: gain, k: \"2*a\" }\n  v: [1, 2]\n", &file()).unwrap();
        let blocks = lookup(y.as_map().unwrap(), "blocks").unwrap().as_map().unwrap();
        let (key, g) = &blocks[0];
        assert_eq!((key.name.as_str(), key.pos.line, key.pos.col), ("g", 2, 3));
        let k = lookup(g.as_map().unwrap(), "k").unwrap();
        assert_eq!(k.kind, Kind::Str("2*a".into()));
        assert_eq!((k.pos.line, k.pos.col), (2, 24), "points inside the quotes");
        let v = lookup(blocks, "v").unwrap();
        let Kind::Seq(items) = &v.kind else { panic!() };
        assert_eq!((items[1].pos.line, items[1].pos.col), (3, 10));
    }

    #[test]
    fn yaml_1_1_booleans_are_strings() {
        let y = parse("[y, n, on, off, yes, true]", &file()).unwrap();
        let Kind::Seq(items) = y.kind else { panic!() };
        let kinds: Vec<&Kind> = items.iter().map(|i| &i.kind).collect();
        assert_eq!(kinds[..2], [&Kind::Str("y".into()), &Kind::Str("n".into())]);
        assert_eq!(kinds[5], &Kind::Bool(true));
    }

    #[test]
    fn syntax_and_duplicate_errors_are_positioned() {
        let e = parse("a: [1, 2\nb: 3\n", &file()).unwrap_err();
        assert!(e.pos.is_some() && e.message.starts_with("YAML syntax"), "{e}");
        let e = parse("a: 1\nb: 2\na: 3\n", &file()).unwrap_err();
        assert_eq!(e.to_string(), "t.yaml:3:1: duplicate key `a`: names and keys must be unique within a mapping");
    }
}
