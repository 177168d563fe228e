//! The graph a step library compiled last, kept parsed and compiled: a
//! sweep's cases, a test's seeds and a Python loop create one run after
//! another from the same text with other values, and each is then built on
//! its structure ([`crate::recompile`]) — what the program's own sweep
//! does — instead of being parsed and compiled from the text again.

use crate::flatten::ParsedGraph;
use crate::registry::Registry;
use crate::{FlatGraph, Model};
use std::sync::{Arc, Mutex};

/// A graph's text parsed, and compiled with its own parameter values.
struct Template {
    text: String,
    file: String,
    parsed: ParsedGraph,
    base: Model,
}

/// One graph: a library serves one structure, and a program runs one
/// graph's cases at a time. Only the lookup holds the lock; runs on other
/// threads compile on the shared template at once.
static LAST: Mutex<Option<Arc<Template>>> = Mutex::new(None);

/// `text` (named `file`) with `sets` and `seed`, compiled with `registry`:
/// on the kept template's structure when it is this graph's, else from the
/// text, keeping the graph as the template. The model is the one
/// [`crate::load_str`] and [`crate::compile`] give, as the sweep's tests
/// hold for [`crate::recompile`].
pub(super) fn compile_case(
    text: &str,
    file: &str,
    sets: &[(String, String)],
    seed: Option<u64>,
    registry: &Registry,
) -> Result<Model, String> {
    let case = |template: &Template| -> Result<Model, String> {
        let flat = seeded(template.parsed.flatten(sets).map_err(|d| d.to_string())?, seed);
        crate::recompile(&template.base, &flat, registry).map_err(|d| d.to_string())
    };
    let kept = LAST.lock().ok().and_then(|last| last.clone()).filter(|t| t.text == text && t.file == file);
    if let Some(template) = kept {
        return case(&template);
    }
    // A graph that does not compile with its own values (an override makes
    // it valid) is compiled as the case alone, and not kept.
    let parsed = ParsedGraph::parse(text, file.into()).map_err(|d| d.to_string())?;
    let Ok(base) = parsed.flatten(&[]).and_then(|flat| crate::compile(&flat, registry)) else {
        let flat = seeded(parsed.flatten(sets).map_err(|d| d.to_string())?, seed);
        return crate::compile(&flat, registry).map_err(|d| d.to_string());
    };
    let template = Arc::new(Template { text: text.to_string(), file: file.to_string(), parsed, base });
    if let Ok(mut last) = LAST.lock() {
        *last = Some(template.clone());
    }
    case(&template)
}

fn seeded(mut flat: FlatGraph, seed: Option<u64>) -> FlatGraph {
    if let Some(seed) = seed {
        flat.sim.seed = seed;
    }
    flat
}
