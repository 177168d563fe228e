//! A YAML document as a tree in which every node and key keeps its position.
//!
//! granit-parser (the YAML 1.2 parser under serde-saphyr) reads the text
//! into events with their spans; [`load`] builds the tree from them. We
//! build our own tree rather than deserialize typed structs because a
//! block's parameters depend on its `type`, which the registry knows and
//! serde does not, and because unknown keys must be reported with a "did
//! you mean". Building it from the events directly takes half the
//! instructions of serde-saphyr's `Spanned<T>`, which deserialises every
//! node through a synthesised map (callgrind, a 20 000-gain chain: 1.02 G
//! → 0.49 G); what remains is mostly the parser itself.

mod load;
mod scalar;

pub use load::{MAX_ALIAS_NODES, MAX_ALIASES, MAX_YAML_DEPTH, MAX_YAML_NODES};

use crate::diag::{Diagnostic, Pos};
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

/// Parses a YAML document; syntax errors carry their position. Scalars
/// are typed by YAML 1.2's core schema with booleans spelled `true` and
/// `false` only (module `scalar`).
pub fn parse(text: &str, file: &Arc<str>) -> Result<Yaml, Diagnostic> {
    load::load(text, file)
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
