//! Builds the positioned tree straight from granit-parser's events.
//!
//! One pass, no recursion (a deep document cannot overflow the stack), one
//! allocation per node. Anchors and aliases, merge keys (`<<`) and
//! duplicate keys are handled here; the limits below keep an alias bomb or
//! a pathological file from exhausting memory.

use super::{Key, Kind, Yaml, scalar};
use crate::diag::{Diagnostic, Pos};
use granit_parser::{Event, Parser, ScalarStyle, ScanError, Span};
use std::collections::{HashMap, HashSet};
use std::sync::Arc;

/// Most YAML nodes (maps, sequences, scalars) a graph file may have: a
/// million blocks in flow style take about ten million.
pub const MAX_YAML_NODES: usize = 20_000_000;
/// Deepest nesting of mappings and sequences.
pub const MAX_YAML_DEPTH: usize = 64;
/// Most aliases (`*name`) in a file.
pub const MAX_ALIASES: usize = 50_000;
/// Most nodes that anchors and aliases may copy in all (an anchored value
/// is kept, and each alias copies it): far more than any hand-written
/// sharing, far fewer than an alias bomb (`a: [*b, *b, …]` nested) or
/// anchors nested in anchors make.
pub const MAX_ALIAS_NODES: usize = 1_000_000;

/// A collection being filled.
enum Frame {
    Seq { pos: Pos, anchor: usize, items: Vec<Yaml> },
    Map(MapFrame),
}

struct MapFrame {
    pos: Pos,
    anchor: usize,
    entries: Vec<(Key, Yaml)>,
    /// The key read, waiting for its value.
    key: Option<Key>,
    /// The values of `<<` keys, merged when the mapping ends.
    merges: Vec<Yaml>,
    /// The keys so far, once the mapping is too long to search.
    names: Option<HashSet<String>>,
}

/// A mapping this long or longer finds duplicate keys through a hash set.
const LINEAR_SEARCH: usize = 16;

impl MapFrame {
    fn has(&self, name: &str) -> bool {
        match &self.names {
            Some(names) => names.contains(name),
            None => self.entries.iter().any(|(k, _)| k.name == name),
        }
    }

    fn insert(&mut self, key: Key, value: Yaml) -> Result<(), Diagnostic> {
        if self.has(&key.name) {
            return Err(Diagnostic::at(
                &key.pos,
                format!("duplicate key `{}`: names and keys must be unique within a mapping", key.name),
            ));
        }
        self.push(key, value);
        Ok(())
    }

    /// Adds an entry whose key is not in the mapping yet.
    fn push(&mut self, key: Key, value: Yaml) {
        if let Some(names) = &mut self.names {
            names.insert(key.name.clone());
        } else if self.entries.len() + 1 >= LINEAR_SEARCH {
            let mut names: HashSet<String> = self.entries.iter().map(|(k, _)| k.name.clone()).collect();
            names.insert(key.name.clone());
            self.names = Some(names);
        }
        self.entries.push((key, value));
    }

    /// The mapping with its `<<` merges applied: keys written in the
    /// mapping win, then the first merged mapping that has the key.
    fn finish(mut self) -> Result<Yaml, Diagnostic> {
        let merges = std::mem::take(&mut self.merges);
        for source in merges {
            let maps = match source.kind {
                Kind::Map(entries) => vec![entries],
                Kind::Seq(items) => items
                    .into_iter()
                    .map(|item| match item.kind {
                        Kind::Map(entries) => Ok(entries),
                        _ => Err(merge_error(&item.pos, item.describe())),
                    })
                    .collect::<Result<_, _>>()?,
                _ => return Err(merge_error(&source.pos, source.describe())),
            };
            for (key, value) in maps.into_iter().flatten() {
                if !self.has(&key.name) {
                    self.push(key, value);
                }
            }
        }
        Ok(Yaml { pos: self.pos, kind: Kind::Map(self.entries) })
    }
}

fn merge_error(pos: &Pos, found: &str) -> Diagnostic {
    Diagnostic::at(pos, format!("`<<` merges a mapping or a list of mappings, found {found}"))
        .with_hint("write `<<: *name` where `&name` marks a mapping")
}

struct Anchored {
    node: Yaml,
    /// Its number of nodes, for the alias budget.
    size: usize,
    /// A scalar's text, for an alias used as a key.
    text: Option<String>,
}

struct Loader {
    file: Arc<str>,
    stack: Vec<Frame>,
    /// Anchored nodes by the parser's anchor id.
    anchors: HashMap<usize, Anchored>,
    root: Option<Yaml>,
    documents: usize,
    nodes: usize,
    aliases: usize,
    /// Nodes copied for anchors and aliases.
    copied: usize,
}

/// Parses one YAML document into the positioned tree.
pub fn load(text: &str, file: &Arc<str>) -> Result<Yaml, Diagnostic> {
    let mut loader = Loader {
        file: file.clone(),
        stack: Vec::new(),
        anchors: HashMap::new(),
        root: None,
        documents: 0,
        nodes: 0,
        aliases: 0,
        copied: 0,
    };
    let mut end = Pos::new(file.clone(), 1, 1);
    for event in Parser::new_from_str(text) {
        let (event, span) = event.map_err(|e| loader.syntax_error(&e))?;
        if let Event::StreamEnd = event {
            end = loader.pos(&span);
        }
        loader.event(event, &span, text)?;
    }
    // An empty document is null, placed at its end.
    Ok(loader.root.unwrap_or(Yaml { pos: end, kind: Kind::Null }))
}

impl Loader {
    fn pos(&self, span: &Span) -> Pos {
        Pos::new(self.file.clone(), span.start.line() as u32, span.start.col() as u32 + 1)
    }

    fn syntax_error(&self, e: &ScanError) -> Diagnostic {
        let m = e.marker();
        Diagnostic::at(
            &Pos::new(self.file.clone(), m.line() as u32, m.col() as u32 + 1),
            format!("YAML syntax: {}", e.info()),
        )
    }

    /// Whether the next node is a mapping's key.
    fn wants_key(&self) -> bool {
        matches!(self.stack.last(), Some(Frame::Map(m)) if m.key.is_none())
    }

    fn event(&mut self, event: Event, span: &Span, text: &str) -> Result<(), Diagnostic> {
        match event {
            Event::DocumentStart(..) => {
                self.documents += 1;
                if self.documents > 1 {
                    return Err(Diagnostic::at(
                        &self.pos(span),
                        "a graph file holds one YAML document; a second starts here",
                    )
                    .with_hint("remove the `---` (or split the file)"));
                }
            }
            Event::Scalar(value, style, anchor, tag) => {
                let pos = self.pos(span);
                self.count(1, &pos)?;
                if self.wants_key() {
                    if style == ScalarStyle::Plain && scalar::is_null(&value) {
                        return Err(Diagnostic::at(&pos, "a mapping key is missing (empty, `~` or `null`)")
                            .with_hint("write a name before the `:`"));
                    }
                    self.key(Key { name: value.into_owned(), pos }, anchor);
                    return Ok(());
                }
                let kind = scalar::resolve(&value, style, tag.as_deref()).map_err(|m| Diagnostic::at(&pos, m))?;
                // Point at a quoted string's first character, not its quote,
                // so that positions inside an expression line up.
                let pos = if starts_with_quote(span, text) { pos.shifted(1) } else { pos };
                if anchor != 0 {
                    self.copy(1, &pos)?;
                    let node = Yaml { pos: pos.clone(), kind: kind.clone() };
                    self.anchors.insert(anchor, Anchored { node, size: 1, text: Some(value.into_owned()) });
                }
                self.value(Yaml { pos, kind }, 0)?;
            }
            Event::SequenceStart(_, anchor, _) | Event::MappingStart(_, anchor, _) => {
                let pos = self.pos(span);
                if self.wants_key() {
                    return Err(Diagnostic::at(&pos, "a mapping key must be a name, not a list or a mapping"));
                }
                self.count(1, &pos)?;
                if self.stack.len() >= MAX_YAML_DEPTH {
                    return Err(Diagnostic::at(&pos, format!("YAML nested too deeply (limit {MAX_YAML_DEPTH})")));
                }
                self.stack.push(match event {
                    Event::SequenceStart(..) => Frame::Seq { pos, anchor, items: Vec::new() },
                    _ => Frame::Map(MapFrame {
                        pos,
                        anchor,
                        entries: Vec::new(),
                        key: None,
                        merges: Vec::new(),
                        names: None,
                    }),
                });
            }
            Event::SequenceEnd | Event::MappingEnd => {
                let (node, anchor) = match self.stack.pop() {
                    Some(Frame::Seq { pos, anchor, items }) => (Yaml { pos, kind: Kind::Seq(items) }, anchor),
                    Some(Frame::Map(map)) => {
                        let anchor = map.anchor;
                        (map.finish()?, anchor)
                    }
                    None => return Ok(()),
                };
                self.value(node, anchor)?;
            }
            Event::Alias(id) => self.alias(id, span)?,
            _ => {}
        }
        Ok(())
    }

    fn count(&mut self, n: usize, pos: &Pos) -> Result<(), Diagnostic> {
        self.nodes += n;
        if self.nodes > MAX_YAML_NODES {
            return Err(Diagnostic::at(pos, format!("more than {MAX_YAML_NODES} YAML nodes")));
        }
        Ok(())
    }

    /// Counts `n` nodes copied for an anchor or an alias.
    fn copy(&mut self, n: usize, pos: &Pos) -> Result<(), Diagnostic> {
        self.copied += n;
        if self.copied > MAX_ALIAS_NODES {
            return Err(copy_error(pos));
        }
        Ok(())
    }

    fn key(&mut self, key: Key, anchor: usize) {
        if anchor != 0 {
            let node = Yaml { pos: key.pos.clone(), kind: Kind::Str(key.name.clone()) };
            self.anchors.insert(anchor, Anchored { node, size: 1, text: Some(key.name.clone()) });
        }
        if let Some(Frame::Map(map)) = self.stack.last_mut() {
            map.key = Some(key);
        }
    }

    /// Places a finished node in the collection being filled (or as the document).
    fn value(&mut self, node: Yaml, anchor: usize) -> Result<(), Diagnostic> {
        if anchor != 0 {
            let size = size(&node);
            self.copy(size, &node.pos)?;
            self.anchors.insert(anchor, Anchored { node: node.clone(), size, text: None });
        }
        match self.stack.last_mut() {
            Some(Frame::Seq { items, .. }) => items.push(node),
            Some(Frame::Map(map)) => {
                // Values reach a mapping only after their key (see `wants_key`).
                let Some(key) = map.key.take() else {
                    return Err(Diagnostic::at(&node.pos, "YAML syntax: a value without a key"));
                };
                if key.name == "<<" {
                    map.merges.push(node);
                } else {
                    map.insert(key, node)?;
                }
            }
            None => self.root = Some(node),
        }
        Ok(())
    }

    /// `*name`: a copy of the anchored node, placed where the alias is.
    fn alias(&mut self, id: usize, span: &Span) -> Result<(), Diagnostic> {
        let pos = self.pos(span);
        let Some(anchored) = self.anchors.get(&id) else {
            return Err(Diagnostic::at(&pos, "YAML syntax: unknown anchor"));
        };
        let size = anchored.size;
        self.aliases += 1;
        if self.aliases > MAX_ALIASES {
            return Err(copy_error(&pos));
        }
        self.copy(size, &pos)?;
        let anchored = &self.anchors[&id];
        if self.wants_key() {
            let Some(name) = anchored.text.clone() else {
                return Err(Diagnostic::at(&pos, "a mapping key must be a name, not a list or a mapping"));
            };
            self.key(Key { name, pos }, 0);
            return Ok(());
        }
        // The copy sits at the alias; the nodes inside keep the positions
        // where they are written, which is where a mistake in them is.
        let kind = anchored.node.kind.clone();
        self.count(size, &pos)?;
        self.value(Yaml { pos, kind }, 0)
    }
}

fn copy_error(pos: &Pos) -> Diagnostic {
    Diagnostic::at(
        pos,
        format!("YAML anchors and aliases copy too much (limit {MAX_ALIASES} aliases, {MAX_ALIAS_NODES} copied nodes)"),
    )
    .with_hint("an alias copies its anchor's whole value; nested aliases multiply")
}

/// Whether a scalar's source starts with a quote.
fn starts_with_quote(span: &Span, text: &str) -> bool {
    span.start.byte_offset().and_then(|i| text.as_bytes().get(i)).is_some_and(|&b| b == b'"' || b == b'\'')
}

/// Nodes in a tree (for the alias budget).
fn size(node: &Yaml) -> usize {
    let mut n = 0;
    let mut todo = vec![node];
    while let Some(y) = todo.pop() {
        n += 1;
        match &y.kind {
            Kind::Seq(items) => todo.extend(items),
            Kind::Map(entries) => todo.extend(entries.iter().map(|(_, v)| v)),
            _ => {}
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::yaml::lookup;

    fn parse(text: &str) -> Result<Yaml, Diagnostic> {
        load(text, &"t.yaml".into())
    }

    fn error(text: &str) -> String {
        parse(text).unwrap_err().to_string()
    }

    fn keys(y: &Yaml) -> Vec<&str> {
        y.as_map().unwrap().iter().map(|(k, _)| k.name.as_str()).collect()
    }

    #[test]
    fn merge_keys_written_keys_win_then_the_first_merged() {
        let y = parse("a: &a { x: 1, w: 0 }\nb: &b { y: 2, x: 5 }\nc: { <<: [*a, *b], z: 3, w: 9 }\n").unwrap();
        let c = lookup(y.as_map().unwrap(), "c").unwrap();
        assert_eq!(keys(c), ["z", "w", "x", "y"]);
        let num = |k| lookup(c.as_map().unwrap(), k).unwrap().kind.clone();
        assert_eq!((num("x"), num("w")), (Kind::Num(1.0), Kind::Num(9.0)));
        // A long merged mapping is merged in linear time.
        let long: String = (0..30_000).map(|i| format!("k{i}: {i}, ")).collect();
        let y = parse(&format!("a: &a {{ {long} }}\nb: {{ <<: *a, k7: 0 }}\n")).unwrap();
        assert_eq!(lookup(y.as_map().unwrap(), "b").unwrap().as_map().unwrap().len(), 30_000);
        assert!(
            error("a: { <<: 5 }\n")
                .contains("t.yaml:1:10: `<<` merges a mapping or a list of mappings, found a number")
        );
    }

    #[test]
    fn an_alias_sits_where_it_is_used_and_its_insides_where_they_are_written() {
        let y = parse("base: &b { k: 2 }\ng: *b\n").unwrap();
        let g = lookup(y.as_map().unwrap(), "g").unwrap();
        assert_eq!((g.pos.line, g.pos.col), (2, 4));
        let (key, k) = &g.as_map().unwrap()[0];
        assert_eq!((key.pos.line, key.pos.col, k.pos.col), (1, 12, 15));
        assert_eq!(keys(&parse("a: &v 1\n*v : 2\n").unwrap()), ["a", "1"]);
        assert!(error("a: *nope\n").starts_with("t.yaml:1:4: YAML syntax"), "{}", error("a: *nope\n"));
    }

    #[test]
    fn aliases_within_the_budget() {
        // (An alias bomb is refused: tests/errors.rs.)
        let shared: String = (0..1000).map(|i| format!("g{i}: *k\n")).collect();
        assert!(parse(&format!("k: &k {{ type: gain, k: 2 }}\n{shared}")).is_ok());
        let many: String = (0..MAX_ALIASES).map(|i| format!("g{i}: *k\n")).collect();
        assert!(parse(&format!("k: &k 1\n{many}")).is_ok());
        assert!(error(&format!("k: &k 1\n{many}x: *k\n")).contains("YAML anchors and aliases copy too much"));
        // Anchors nested in anchors each keep a copy: counted too.
        let nested = format!("{}1{}", "&a [".repeat(60), "]".repeat(60));
        let wide: String = (0..20_000).map(|i| format!("{i}, ")).collect();
        assert!(error(&nested.replace('1', &format!("[{wide}]"))).contains("copy too much"));
    }

    #[test]
    fn depth_duplicates_documents_and_keys() {
        let deep = |n| format!("{}1{}", "[".repeat(n), "]".repeat(n));
        assert!(parse(&deep(MAX_YAML_DEPTH)).is_ok());
        assert!(error(&deep(MAX_YAML_DEPTH + 1)).contains("YAML nested too deeply (limit 64)"));
        // Past the linear search: the hash set finds the duplicate.
        let long: String = (0..100).map(|i| format!("k{i}: {i}\n")).collect();
        assert_eq!(
            error(&format!("{long}k42: 0\n")),
            "t.yaml:101:1: duplicate key `k42`: names and keys must be unique within a mapping"
        );
        assert!(error("a: 1\n---\nb: 2\n").starts_with("t.yaml:2:1: a graph file holds one YAML document"));
        assert!(error(": 1\n").contains("a mapping key is missing"));
        assert!(error("? [a]\n: 1\n").contains("a mapping key must be a name"));
        assert_eq!(parse("# nothing\n").unwrap().kind, Kind::Null);
    }
}
