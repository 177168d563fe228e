//! The structure of one graph file, before parameters are evaluated or
//! subsystems expanded. Values stay as positioned YAML until the block
//! type that interprets them is known.

use crate::checks::CheckSpec;
use crate::diag::{Diagnostic, Pos};
use crate::scope::{self, ScopeSpec};
use crate::yaml::{self, Key, Kind, Yaml};
use std::sync::Arc;

/// The keys of a graph file.
pub const TOP_KEYS: [&str; 10] =
    ["name", "description", "parameters", "simulation", "blocks", "wires", "record", "checks", "scopes", "analysis"];

/// One graph file.
#[derive(Clone, Debug)]
pub struct GraphFile {
    pub file: Arc<str>,
    pub name: Option<String>,
    pub description: Option<String>,
    /// Parameter definitions in order: name and value (number or expression).
    pub parameters: Vec<(Key, Yaml)>,
    pub simulation: Option<Yaml>,
    /// Shared, so that expanding a subsystem many times copies no specs.
    pub blocks: Vec<Arc<BlockSpec>>,
    pub wires: Vec<WireSpec>,
    pub record: Vec<RecordSpec>,
    /// Log every n-th major step (1 = all).
    pub record_every: Option<(usize, Pos)>,
    /// Acceptance conditions over the recorded signals.
    pub checks: Vec<CheckSpec>,
    /// Plot panels.
    pub scopes: Vec<ScopeSpec>,
    /// What linear analysis looks at (`analysis:`).
    pub analysis: Option<Selection>,
}

/// What a linear analysis looks at: the signal where a perturbation is
/// added, the one measured, where the loop is cut, and the time of the
/// operating point. Signals are `block`, `block.port`, or `name[k]` for an
/// element of a vector. An opening alone selects the loop transfer there.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Selection {
    pub input: Option<String>,
    pub output: Option<String>,
    /// Downstream of this signal the loop is cut: blocks see only the
    /// injected input there; measuring it reads the upstream value.
    pub open: Option<String>,
    /// The operating point is the state the run reaches at this time.
    pub at: f64,
    /// Where the selection was written (the `analysis:` section).
    pub pos: Option<Pos>,
}

/// The keys of `analysis:`.
pub const ANALYSIS_KEYS: [&str; 4] = ["input", "output", "open", "at"];

fn parse_analysis(v: &Yaml) -> Result<Selection, Diagnostic> {
    let map = v.expect_map("`analysis`")?;
    let mut sel = Selection { pos: Some(v.pos.clone()), ..Selection::default() };
    for (k, value) in map {
        let text = || value.expect_str(&format!("analysis `{}`", k.name)).map(|s| Some(s.to_string()));
        match k.name.as_str() {
            "input" => sel.input = text()?,
            "output" => sel.output = text()?,
            "open" => sel.open = text()?,
            "at" => match value.kind {
                Kind::Num(t) if t >= 0.0 && t.is_finite() => sel.at = t,
                _ => return Err(Diagnostic::at(&value.pos, "analysis `at`: a time in seconds from 0")),
            },
            _ => {
                return Err(Diagnostic::at(&k.pos, format!("unknown key `{}` in `analysis`", k.name))
                    .suggest(&k.name, ANALYSIS_KEYS)
                    .or_hint(format!("keys: {}", ANALYSIS_KEYS.join(", "))));
            }
        }
    }
    match (&sel.input, &sel.output, &sel.open) {
        (Some(_), Some(_), _) | (None, None, Some(_)) => Ok(sel),
        _ => Err(Diagnostic::at(&v.pos, "`analysis` names an input and an output signal, or a loop opening alone")
            .with_hint("e.g. `analysis: { open: ctrl.u }` for the loop transfer at the controller output")),
    }
}

#[derive(Clone, Debug)]
pub struct BlockSpec {
    pub name: String,
    pub pos: Pos,
    pub type_name: String,
    pub type_pos: Pos,
    /// All keys of the block's mapping, `type` included.
    pub params: Vec<(Key, Yaml)>,
}

/// `block` or `block.port` in a wire or record entry.
#[derive(Clone, Debug, PartialEq)]
pub struct Endpoint {
    pub block: String,
    pub port: Option<String>,
    pub pos: Pos,
}

impl std::fmt::Display for Endpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.port {
            Some(p) => write!(f, "{}.{p}", self.block),
            None => f.write_str(&self.block),
        }
    }
}

/// `src -> dst[, dst…]`.
#[derive(Clone, Debug)]
pub struct WireSpec {
    pub src: Endpoint,
    pub dsts: Vec<Endpoint>,
}

/// A recorded signal, its column name and optional unit.
#[derive(Clone, Debug)]
pub struct RecordSpec {
    pub name: String,
    pub signal: Endpoint,
    pub unit: Option<String>,
}

impl GraphFile {
    /// Parses the text of a graph file named `file`.
    pub fn parse(text: &str, file: Arc<str>) -> Result<GraphFile, Diagnostic> {
        let root = yaml::parse(text, &file)?;
        let top = match &root.kind {
            Kind::Map(m) => m.as_slice(),
            _ => {
                return Err(Diagnostic::at(&root.pos, "a graph file must be a mapping with `blocks:`, `wires:`, …"));
            }
        };
        for (key, _) in top {
            if !TOP_KEYS.contains(&key.name.as_str()) {
                return Err(Diagnostic::at(&key.pos, format!("unknown top-level key `{}`", key.name))
                    .suggest(&key.name, TOP_KEYS)
                    .or_hint(format!("top-level keys: {}", TOP_KEYS.join(", "))));
            }
        }
        let text_of = |k: &str| -> Result<Option<String>, Diagnostic> {
            yaml::lookup(top, k).map(|v| v.expect_str(&format!("`{k}`")).map(str::to_string)).transpose()
        };
        let parameters = match yaml::lookup(top, "parameters") {
            Some(p) => p.expect_map("`parameters`")?.to_vec(),
            None => Vec::new(),
        };
        let blocks = match yaml::lookup(top, "blocks") {
            Some(b) => {
                b.expect_map("`blocks`")?.iter().map(|e| parse_block(e).map(Arc::new)).collect::<Result<_, _>>()?
            }
            None => Vec::new(),
        };
        let wires = match yaml::lookup(top, "wires") {
            Some(w) => seq(w, "`wires`")?.iter().map(parse_wire).collect::<Result<_, _>>()?,
            None => Vec::new(),
        };
        let (record, record_every) = match yaml::lookup(top, "record") {
            Some(r) => parse_record(r)?,
            None => (Vec::new(), None),
        };
        let checks = match yaml::lookup(top, "checks") {
            Some(c) => seq(c, "`checks`")?.iter().map(parse_check).collect::<Result<_, _>>()?,
            None => Vec::new(),
        };
        let scopes = match yaml::lookup(top, "scopes") {
            Some(v) => scope::parse(v)?,
            None => Vec::new(),
        };
        let analysis = yaml::lookup(top, "analysis").map(parse_analysis).transpose()?;
        Ok(GraphFile {
            checks,
            scopes,
            analysis,
            name: text_of("name")?,
            description: text_of("description")?,
            parameters,
            simulation: yaml::lookup(top, "simulation").cloned(),
            blocks,
            wires,
            record,
            record_every,
            file,
        })
    }
}

fn seq<'a>(v: &'a Yaml, what: &str) -> Result<&'a [Yaml], Diagnostic> {
    match &v.kind {
        Kind::Seq(items) => Ok(items),
        Kind::Null => Ok(&[]),
        _ => Err(Diagnostic::at(&v.pos, format!("{what} must be a list, found {}", v.describe()))),
    }
}

fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    chars.next().is_some_and(|c| c.is_alphabetic() || c == '_') && chars.all(|c| c.is_alphanumeric() || c == '_')
}

fn parse_block((key, value): &(Key, Yaml)) -> Result<BlockSpec, Diagnostic> {
    if !is_identifier(&key.name) {
        return Err(Diagnostic::at(&key.pos, format!("`{}` is not a valid block name", key.name))
            .with_hint("block names are letters, digits and `_`, starting with a letter or `_`"));
    }
    let entries = match &value.kind {
        Kind::Map(m) => m,
        _ => {
            return Err(Diagnostic::at(
                &value.pos,
                format!(
                    "block `{}` must be a mapping like `{{ type: gain, k: 2 }}`, found {}",
                    key.name,
                    value.describe()
                ),
            ));
        }
    };
    let Some(ty) = yaml::lookup(entries, "type") else {
        return Err(Diagnostic::at(&key.pos, format!("block `{}` has no `type`", key.name))
            .with_hint("`ctlgraph blocks` lists the block types"));
    };
    let type_name = ty.expect_str(&format!("block `{}`: `type`", key.name))?.to_string();
    Ok(BlockSpec {
        name: key.name.clone(),
        pos: key.pos.clone(),
        type_name,
        type_pos: ty.pos.clone(),
        params: entries.clone(),
    })
}

/// Parses `block` or `block.port` (block may be a `sub/inner` path)
/// written at `pos`.
pub fn parse_endpoint(text: &str, pos: Pos) -> Result<Endpoint, Diagnostic> {
    let text = text.trim();
    let (block, port) = match text.rsplit_once('.') {
        Some((b, p)) => (b, Some(p)),
        None => (text, None),
    };
    let ok = block.split('/').all(is_identifier) && port.is_none_or(is_identifier);
    if !ok {
        return Err(Diagnostic::at(&pos, format!("`{text}` is not a signal: expected `block` or `block.port`")));
    }
    Ok(Endpoint { block: block.to_string(), port: port.map(str::to_string), pos })
}

fn parse_wire(v: &Yaml) -> Result<WireSpec, Diagnostic> {
    let text = v.expect_str("a wire")?;
    let Some((src, dsts)) = text.split_once("->") else {
        return Err(Diagnostic::at(&v.pos, format!("`{text}` is not a wire: expected `source.port -> dest.port`")));
    };
    // Positions of the parts within the line, for precise messages.
    let offset_of = |part: &str| {
        let start = part.as_ptr() as usize - text.as_ptr() as usize;
        let leading = part.len() - part.trim_start().len();
        text[..start + leading].chars().count()
    };
    let src_ep = parse_endpoint(src, v.pos.shifted(offset_of(src)))?;
    let dsts =
        dsts.split(',').map(|d| parse_endpoint(d, v.pos.shifted(offset_of(d)))).collect::<Result<Vec<_>, _>>()?;
    Ok(WireSpec { src: src_ep, dsts })
}

/// A check: `"text"` or `name: "text"`.
fn parse_check(item: &Yaml) -> Result<CheckSpec, Diagnostic> {
    match &item.kind {
        Kind::Str(s) => Ok(CheckSpec { name: None, text: s.clone(), pos: item.pos.clone() }),
        Kind::Map(m) if m.len() == 1 => {
            let (k, v) = &m[0];
            let text = v.expect_str(&format!("check `{}`", k.name))?;
            Ok(CheckSpec { name: Some(k.name.clone()), text: text.to_string(), pos: v.pos.clone() })
        }
        _ => Err(Diagnostic::at(&item.pos, "a check is `\"metric(...) < bound\"` or `name: \"metric(...) < bound\"`")),
    }
}

type Records = (Vec<RecordSpec>, Option<(usize, Pos)>);

fn parse_record(v: &Yaml) -> Result<Records, Diagnostic> {
    let (list, every) = match &v.kind {
        Kind::Map(m) => {
            for (k, _) in m {
                if k.name != "signals" && k.name != "every" {
                    return Err(Diagnostic::at(&k.pos, format!("unknown key `{}` in `record`", k.name))
                        .suggest(&k.name, ["signals", "every"]));
                }
            }
            let every = match yaml::lookup(m, "every") {
                Some(e) => match e.kind {
                    Kind::Num(n) if n >= 1.0 && n.fract() == 0.0 => Some((n as usize, e.pos.clone())),
                    _ => {
                        return Err(Diagnostic::at(&e.pos, "`every` must be a positive whole number of steps"));
                    }
                },
                None => None,
            };
            let Some(list) = yaml::lookup(m, "signals") else {
                return Err(Diagnostic::at(&v.pos, "`record` needs `signals: [...]`"));
            };
            (seq(list, "`record.signals`")?, every)
        }
        _ => (seq(v, "`record`")?, None),
    };
    let mut out = Vec::new();
    for item in list {
        match &item.kind {
            Kind::Str(s) => out.push(RecordSpec {
                name: s.trim().to_string(),
                signal: parse_endpoint(s, item.pos.clone())?,
                unit: None,
            }),
            // `name: block.port`, `{ name: block.port, unit: mm }` or `{ block.port, unit: mm }`.
            Kind::Map(m) if !m.is_empty() && m.len() <= 2 => {
                let unit = match yaml::lookup(m, "unit") {
                    Some(u) => Some(u.expect_str("a unit")?.to_string()),
                    None => None,
                };
                let entries: Vec<_> = m.iter().filter(|(k, _)| k.name != "unit").collect();
                let [(k, sig)] = entries.as_slice() else {
                    return Err(Diagnostic::at(
                        &item.pos,
                        "a record entry names one signal (and optionally its `unit`)",
                    ));
                };
                let (s, pos) = match &sig.kind {
                    Kind::Null => (k.name.as_str(), k.pos.clone()),
                    _ => (sig.expect_str("a recorded signal")?, sig.pos.clone()),
                };
                let name = if sig.kind == Kind::Null { s.trim().to_string() } else { k.name.clone() };
                out.push(RecordSpec { name, signal: parse_endpoint(s, pos)?, unit });
            }
            _ => {
                return Err(Diagnostic::at(
                    &item.pos,
                    "a record entry is `block.port`, `name: block.port` or `{ name: block.port, unit: mm }`",
                ));
            }
        }
    }
    Ok((out, every))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wires_and_records() {
        let text =
            "blocks:\n  a: {type: constant}\nwires:\n  - a.y -> b.u1, c\nrecord:\n  every: 2\n  signals: [a, y: b.y]\n";
        let g = GraphFile::parse(text, "g.yaml".into()).unwrap();
        let w = &g.wires[0];
        assert_eq!(w.src.to_string(), "a.y");
        assert_eq!((w.dsts[0].to_string(), w.dsts[0].pos.col), ("b.u1".to_string(), 12));
        assert_eq!((w.dsts[1].to_string(), w.dsts[1].pos.col), ("c".to_string(), 18));
        assert_eq!(g.record[1].name, "y");
        assert_eq!(g.record_every.map(|e| e.0), Some(2));
    }

    #[test]
    fn structural_errors() {
        let e = GraphFile::parse("blocs: {}\n", "g.yaml".into()).unwrap_err();
        assert_eq!(e.message, "unknown top-level key `blocs`");
        assert_eq!(e.hint.as_deref(), Some("did you mean `blocks`?"));
        let e = GraphFile::parse("blocks:\n  a: {k: 1}\n", "g.yaml".into()).unwrap_err();
        assert_eq!((e.pos.unwrap().line, e.message.as_str()), (2, "block `a` has no `type`"));
        let e = GraphFile::parse("wires:\n  - a => b\n", "g.yaml".into()).unwrap_err();
        assert!(e.message.contains("is not a wire"), "{e}");
    }
}
