//! What the server says about one graph file: the compiler's diagnostics,
//! and, from the file's YAML tree and the block library, hover text,
//! completions, definitions and symbols.

use super::text::{before, path_of, place, span, uri_of, word_at};
use ctlgraph_core::registry::{BlockType, ParamDefault, Registry};
use ctlgraph_core::yaml::{self, Key, Kind, Yaml};
use lsp_types::{
    CompletionItem, CompletionItemKind, Diagnostic, DiagnosticSeverity, DocumentSymbol, Documentation, Hover,
    HoverContents, Location, MarkupContent, MarkupKind, Position, Range, SymbolKind, Uri,
};
use std::sync::{Arc, OnceLock};

/// The block library, built once per server.
fn registry() -> &'static Registry {
    static REGISTRY: OnceLock<Registry> = OnceLock::new();
    REGISTRY.get_or_init(crate::registry)
}

/// The name the loader gives the document: its path, so that subsystem
/// files and tables it names are found beside it.
fn file_name(uri: &Uri) -> Arc<str> {
    path_of(uri).map_or_else(|| uri.as_str().into(), |p| p.display().to_string().into())
}

/// The compiler's verdict, as `ctlgraph check` gives it: its error at its
/// place (an error in another file at the document's start, naming it), or
/// its warnings.
pub fn diagnostics(uri: &Uri, text: &str) -> Vec<Diagnostic> {
    let file = file_name(uri);
    let compiled =
        ctlgraph_core::load_str(text, file.clone(), &[]).and_then(|g| ctlgraph_core::compile(&g, registry()));
    let at_start = Range::default();
    match compiled {
        Ok(model) => {
            model.warnings.iter().map(|w| diagnostic(at_start, DiagnosticSeverity::WARNING, w.clone())).collect()
        }
        Err(d) => {
            let mut message = d.message.clone();
            if let Some(hint) = &d.hint {
                message.push_str(&format!("\nhint: {hint}"));
            }
            let range = match &d.pos {
                Some(p) if p.file == file => {
                    let len = word_at(text, p.line, p.col)
                        .map_or(1, |(w, start)| w.chars().count().saturating_sub(p.col.saturating_sub(start) as usize));
                    span(text, p.line, p.col, len.max(1))
                }
                Some(p) => {
                    message = format!("{p}: {message}");
                    at_start
                }
                None => at_start,
            };
            vec![diagnostic(range, DiagnosticSeverity::ERROR, message)]
        }
    }
}

fn diagnostic(range: Range, severity: DiagnosticSeverity, message: String) -> Diagnostic {
    Diagnostic { range, severity: Some(severity), source: Some("ctlgraph".into()), message, ..Diagnostic::default() }
}

/// A graph file's blocks: name, its key and its entries.
struct Block<'a> {
    key: &'a Key,
    entries: &'a [(Key, Yaml)],
    type_name: Option<&'a str>,
}

fn section<'a>(root: &'a Yaml, name: &str) -> &'a [(Key, Yaml)] {
    match &root.kind {
        Kind::Map(m) => match yaml::lookup(m, name).map(|v| &v.kind) {
            Some(Kind::Map(entries)) => entries,
            _ => &[],
        },
        _ => &[],
    }
}

fn blocks(root: &Yaml) -> Vec<Block<'_>> {
    section(root, "blocks")
        .iter()
        .filter_map(|(key, value)| match &value.kind {
            Kind::Map(entries) => {
                let type_name = yaml::lookup(entries, "type").and_then(Yaml::as_str);
                Some(Block { key, entries, type_name })
            }
            _ => None,
        })
        .collect()
}

/// The document's tree (`None` while it does not parse).
fn tree(uri: &Uri, text: &str) -> Option<Yaml> {
    yaml::parse(text, &file_name(uri)).ok()
}

/// Whether a node or key written at `pos` starts at `line`, `col` (or one
/// column before, inside quotes).
fn starts_at(pos: &ctlgraph_core::Pos, line: u32, col: u32) -> bool {
    pos.line == line && (pos.col == col || pos.col + 1 == col)
}

pub fn hover(uri: &Uri, text: &str, at: Position) -> Option<Hover> {
    let (line, col) = place(text, at);
    let (word, start) = word_at(text, line, col)?;
    let root = tree(uri, text)?;
    let reg = registry();
    let blocks = blocks(&root);
    let markdown = |value: String| Hover {
        contents: HoverContents::Markup(MarkupContent { kind: MarkupKind::Markdown, value }),
        range: Some(span(text, line, start, word.chars().count())),
    };
    for b in &blocks {
        let ty = b.type_name.and_then(|t| reg.get(t));
        if starts_at(&b.key.pos, line, start) && b.key.name == word {
            let what = ty.map_or(String::new(), |t| format!(" — `{}`: {}", t.name, t.summary));
            return Some(markdown(format!("block `{}`{what}", b.key.name)));
        }
        for (k, v) in b.entries {
            if k.name == "type" && starts_at(&v.pos, line, start) && Some(word.as_str()) == b.type_name {
                return ty.map(|t| markdown(type_doc(t)));
            }
            if starts_at(&k.pos, line, start) && k.name == word {
                let p = ty.and_then(|t| t.params.iter().find(|p| p.name == word))?;
                let default = match p.default {
                    ParamDefault::Required => "required".to_string(),
                    other => format!("default `{other}`"),
                };
                let unit = if p.unit.is_empty() { String::new() } else { format!(" [{}]", p.unit) };
                return Some(markdown(format!("`{}` ({}, {default}){unit}: {}", p.name, p.kind.name(), p.doc)));
            }
        }
    }
    for (k, v) in section(&root, "parameters") {
        if starts_at(&k.pos, line, start) && k.name == word {
            let value = ctlgraph_core::load_str(text, file_name(uri), &[])
                .ok()
                .and_then(|g| g.parameters.iter().find(|(n, _)| *n == word).map(|(_, x)| *x));
            let written = written(v);
            return Some(markdown(match value {
                Some(x) if written != x.to_string() => format!("parameter `{word}` = `{written}` = {x}"),
                Some(x) => format!("parameter `{word}` = {x}"),
                None => format!("parameter `{word}` = `{written}`"),
            }));
        }
    }
    // A signal in a wire or a record: `block` or `block.port`.
    let (name, port) = word.split_once('.').map_or((word.as_str(), None), |(b, p)| (b, Some(p)));
    let b = blocks.iter().find(|b| b.key.name == name)?;
    let t = reg.get(b.type_name?)?;
    let port_doc = port
        .and_then(|p| t.inputs.iter().chain(t.outputs).find(|d| d.name == p))
        .map_or(String::new(), |d| format!(", port `{}`: {}", d.name, d.doc));
    Some(markdown(format!("block `{name}` (`{}`: {}){port_doc}", t.name, t.summary)))
}

/// A block type's documentation, as `ctlgraph blocks TYPE` prints it.
fn type_doc(t: &BlockType) -> String {
    let ports = |ports: &[ctlgraph_core::registry::PortDoc]| {
        ports.iter().map(|p| format!("- `{}`: {}", p.name, p.doc)).collect::<Vec<_>>().join("\n")
    };
    let params: Vec<String> =
        t.params.iter().map(|p| format!("- `{}`: {}", p.name, crate::reference::doc_text(p))).collect();
    format!(
        "**{}** ({})\n\n{}\n\n{}\n\n**inputs**\n{}\n\n**outputs**\n{}\n\n**parameters**\n{}",
        t.name,
        t.category,
        t.summary,
        t.doc,
        ports(t.inputs),
        ports(t.outputs),
        params.join("\n")
    )
}

pub fn completion(uri: &Uri, text: &str, at: Position) -> Vec<CompletionItem> {
    let (line, col) = place(text, at);
    let prefix = before(text, line, col);
    let reg = registry();
    // After `type:`: the block types.
    if prefix.trim_end_matches(|c: char| c.is_alphanumeric() || c == '_').trim_end().ends_with("type:") {
        return reg.types().map(|t| item(t.name, CompletionItemKind::CLASS, t.summary, Some(type_doc(t)))).collect();
    }
    // `block.` in a wire, a record or a scope: the block's ports.
    if let Some((block, _)) = signal_prefix(&prefix) {
        let Some(root) = tree(uri, text) else { return Vec::new() };
        let blocks = blocks(&root);
        let Some(b) = blocks.iter().find(|b| b.key.name == block) else { return Vec::new() };
        let into = prefix.contains("->");
        return ports_of(uri, text, line, block, b.type_name, into);
    }
    let section = section_of(text, line);
    // In a check: the metrics and the analysed loop's figures.
    if section.as_deref() == Some("checks") {
        use ctlgraph_core::checks::metrics::{LOOP_FIGURES, METRICS};
        let metrics = METRICS.iter().map(|(name, _, args)| {
            let args = ["signal"].iter().chain(args.iter()).copied().collect::<Vec<_>>().join(", ");
            item(name, CompletionItemKind::FUNCTION, &format!("{name}({args}[, t0, t1])"), None)
        });
        let figures = LOOP_FIGURES.iter().map(|(name, _, doc)| item(name, CompletionItemKind::CONSTANT, doc, None));
        return metrics.chain(figures).collect();
    }
    // A key inside a block's `{ type: T, … }`: T's parameters not yet written.
    if let Some(open) = prefix.rfind('{') {
        let inside = &prefix[open + 1..];
        let typing_key = !inside.rsplit(',').next().unwrap_or("").contains(':');
        let full = text.lines().nth(line as usize - 1).unwrap_or("");
        if typing_key && let Some(t) = type_in(full).and_then(|t| reg.get(t)) {
            let written: Vec<&str> = inside.split(',').filter_map(|kv| kv.split(':').next()).map(str::trim).collect();
            return t
                .params
                .iter()
                .filter(|p| !written.contains(&p.name))
                .map(|p| item(p.name, CompletionItemKind::PROPERTY, &crate::reference::doc_text(p), None))
                .collect();
        }
    }
    // A value being written (after `key:`): the graph's parameters, as an
    // expression may name them.
    let value = prefix.rsplit([',', '{']).next().unwrap_or("");
    if (value.contains(':') || section.as_deref() == Some("parameters")) && section.as_deref() != Some("wires") {
        let Some(root) = tree(uri, text) else { return Vec::new() };
        let defined = section_keys(&root, "parameters");
        return defined
            .into_iter()
            .map(|(name, value)| item(&name, CompletionItemKind::CONSTANT, &value, None))
            .collect();
    }
    Vec::new()
}

/// The top-level section (`blocks`, `wires`, `checks`, …) line `line` is in.
fn section_of(text: &str, line: u32) -> Option<String> {
    let lines: Vec<&str> = text.lines().take(line as usize).collect();
    lines.iter().rev().find_map(|l| {
        let starts_key = l.chars().next().is_some_and(|c| c.is_alphabetic() || c == '_');
        starts_key.then(|| l.split(':').next().unwrap_or("").trim().to_string())
    })
}

/// A top-level mapping's keys and their values as written.
fn section_keys(root: &Yaml, name: &str) -> Vec<(String, String)> {
    section(root, name).iter().map(|(k, v)| (k.name.clone(), written(v))).collect()
}

/// A value as the file writes it: a number, an expression, else its kind.
fn written(v: &Yaml) -> String {
    match &v.kind {
        Kind::Num(x) => x.to_string(),
        Kind::Str(s) => s.clone(),
        _ => v.describe().to_string(),
    }
}

/// The `type: T` written on a line.
fn type_in(line: &str) -> Option<&str> {
    let at = line.find("type:")? + "type:".len();
    let rest = line[at..].trim_start();
    let end = rest.find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(rest.len());
    (end > 0).then(|| &rest[..end])
}

/// `block.` (and what follows) at the end of `prefix`, in a wire or a list.
fn signal_prefix(prefix: &str) -> Option<(&str, &str)> {
    let tail = prefix.rsplit(|c: char| c.is_whitespace() || c == ',' || c == '[' || c == '>').next()?;
    let (block, port) = tail.rsplit_once('.')?;
    let ok = !block.is_empty() && block.chars().all(|c| c.is_alphanumeric() || c == '_' || c == '/');
    ok.then_some((block, port))
}

/// The ports of `block`: inputs after `->`, outputs before; from the
/// compiled graph (the ports that exist, a subsystem's from its file) when
/// the graph compiles without the line being typed, else from the type's
/// documentation.
fn ports_of(
    uri: &Uri,
    text: &str,
    line: u32,
    block: &str,
    type_name: Option<&str>,
    inputs: bool,
) -> Vec<CompletionItem> {
    let without: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| if i + 1 == line as usize { "" } else { l })
        .collect::<Vec<_>>()
        .join("\n");
    if let Ok(flat) = ctlgraph_core::load_str(&without, file_name(uri), &[]) {
        if let Some((ins, outs)) = flat.subsystems.get(block) {
            let names = if inputs { ins } else { outs };
            return names.iter().map(|n| item(n, CompletionItemKind::FIELD, "subsystem port", None)).collect();
        }
        if let Ok(model) = ctlgraph_core::compile(&flat, registry())
            && let Some(m) = model.meta.iter().find(|m| m.name == block)
        {
            let names = if inputs { &m.input_names } else { &m.output_names };
            return names.iter().map(|n| item(n, CompletionItemKind::FIELD, &m.type_name, None)).collect();
        }
    }
    let Some(t) = type_name.and_then(|t| registry().get(t)) else { return Vec::new() };
    let docs = if inputs { t.inputs } else { t.outputs };
    docs.iter().map(|p| item(p.name, CompletionItemKind::FIELD, p.doc, None)).collect()
}

fn item(label: &str, kind: CompletionItemKind, detail: &str, doc: Option<String>) -> CompletionItem {
    CompletionItem {
        label: label.to_string(),
        kind: Some(kind),
        detail: Some(detail.to_string()),
        documentation: doc
            .map(|value| Documentation::MarkupContent(MarkupContent { kind: MarkupKind::Markdown, value })),
        ..CompletionItem::default()
    }
}

/// Where the word under the cursor is defined: a block named in a wire or
/// a record, a subsystem's or an FMU's `file:`, a graph parameter.
pub fn definition(uri: &Uri, text: &str, at: Position) -> Option<Location> {
    let (line, col) = place(text, at);
    let (word, start) = word_at(text, line, col)?;
    let root = tree(uri, text)?;
    let blocks = blocks(&root);
    for b in &blocks {
        if let Some(file) = yaml::lookup(b.entries, "file").filter(|v| starts_at(&v.pos, line, start))
            && let Some(rel) = file.as_str()
        {
            let dir = path_of(uri)?.parent()?.to_path_buf();
            let target = dir.join(rel);
            let target = target.canonicalize().unwrap_or(target);
            return Some(Location { uri: uri_of(&target)?, range: Range::default() });
        }
    }
    let name = word.split('.').next()?;
    let here =
        |k: &Key| Location { uri: uri.clone(), range: span(text, k.pos.line, k.pos.col, k.name.chars().count()) };
    if let Some(b) = blocks.iter().find(|b| b.key.name == name && !starts_at(&b.key.pos, line, start)) {
        return Some(here(b.key));
    }
    section(&root, "parameters")
        .iter()
        .find(|(k, _)| k.name == word && !starts_at(&k.pos, line, start))
        .map(|(k, _)| here(k))
}

/// The document's parameters and blocks.
pub fn symbols(text: &str) -> Vec<DocumentSymbol> {
    let Ok(root) = yaml::parse(text, &Arc::from("document")) else { return Vec::new() };
    let symbol = |k: &Key, kind: SymbolKind, detail: Option<String>| {
        let range = span(text, k.pos.line, k.pos.col, k.name.chars().count());
        #[allow(deprecated)]
        DocumentSymbol {
            name: k.name.clone(),
            detail,
            kind,
            tags: None,
            deprecated: None,
            range,
            selection_range: range,
            children: None,
        }
    };
    let params = section(&root, "parameters").iter().map(|(k, _)| symbol(k, SymbolKind::CONSTANT, None));
    let blocks = blocks(&root).into_iter().map(|b| symbol(b.key, SymbolKind::OBJECT, b.type_name.map(str::to_string)));
    params.chain(blocks).collect()
}
