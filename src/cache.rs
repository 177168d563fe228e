//! Graphs compiled before, kept by file and text, so that running one
//! again with other parameter values — a Python loop over a gain — parses
//! nothing and builds only its blocks ([`ctlgraph_core::recompile`]). The
//! file is read at every call: an edited file is a new entry, and the
//! subsystems it includes are read as they are now.

use ctlgraph_core::files::{MAX_GRAPH_FILE, read_text};
use ctlgraph_core::{Diagnostic, Model, ParsedGraph};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// How many graphs a cache keeps (the most recently compiled).
const KEEP: usize = 8;

/// A graph file as parsed, and a model compiled from it whose structure
/// later loads of it are compiled on.
struct Entry {
    path: PathBuf,
    text: String,
    parsed: Arc<ParsedGraph>,
    base: Arc<Model>,
}

/// Compiled graphs shared between calls (and threads).
#[derive(Default)]
pub struct GraphCache {
    entries: Mutex<Vec<Entry>>,
}

impl GraphCache {
    pub const fn new() -> Self {
        GraphCache { entries: Mutex::new(Vec::new()) }
    }

    /// What [`crate::compile_file_seeded`] gives, on the structure of the
    /// file's model compiled before when the values leave it unchanged.
    pub fn compile(&self, path: &Path, sets: &[(String, String)], seed: Option<u64>) -> Result<Model, Diagnostic> {
        let file: Arc<str> = path.display().to_string().into();
        let text =
            read_text(path, MAX_GRAPH_FILE).map_err(|e| Diagnostic::in_file(&file, format!("cannot read: {e}")))?;
        let cached = self.find(path, &text);
        let parsed = match &cached {
            Some((parsed, _)) => Arc::clone(parsed),
            None => Arc::new(ParsedGraph::parse(&text, file)?),
        };
        let mut flat = parsed.flatten(sets)?;
        if let Some(s) = seed {
            flat.sim.seed = s;
        }
        let registry = crate::registry();
        let base = match cached {
            Some((_, base)) => base,
            None => {
                let base = Arc::new(crate::compile_flat(&flat, &registry)?);
                self.keep(Entry { path: path.to_path_buf(), text, parsed, base: Arc::clone(&base) });
                base
            }
        };
        crate::recompile_flat(&base, &flat, &registry)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<Entry>> {
        // A panic elsewhere while holding it leaves the list whole.
        self.entries.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn find(&self, path: &Path, text: &str) -> Option<(Arc<ParsedGraph>, Arc<Model>)> {
        let entries = self.lock();
        let e = entries.iter().find(|e| e.path == path && e.text == text)?;
        Some((Arc::clone(&e.parsed), Arc::clone(&e.base)))
    }

    fn keep(&self, entry: Entry) {
        let mut entries = self.lock();
        entries.retain(|e| e.path != entry.path);
        if entries.len() == KEEP {
            entries.remove(0);
        }
        entries.push(entry);
    }
}
