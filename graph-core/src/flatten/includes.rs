//! Subsystem files while a graph expands: parsed once each, their
//! flattened sizes known before they are expanded.

use super::{MAX_DEPTH, SUBSYSTEM, canonical};
use crate::diag::Diagnostic;
use crate::spec::GraphFile;
use crate::yaml::{self, Kind};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The subsystem files met while expanding: each is read and parsed once,
/// and its flattened size is known before it is expanded, so an include
/// chain that doubles at every level is refused at once rather than after
/// building a million blocks.
#[derive(Default)]
pub(super) struct Includes {
    /// The chain of files being expanded (canonical paths), for cycles.
    pub stack: Vec<PathBuf>,
    parsed: HashMap<PathBuf, Arc<GraphFile>>,
    /// Flattened block count per file (saturating).
    sizes: HashMap<PathBuf, usize>,
}

pub(super) enum IncludeError {
    Read(std::io::Error),
    Parse(Diagnostic),
}

impl Includes {
    /// Expansion starting from the top-level file `top` (canonical path).
    pub fn new(top: PathBuf) -> Self {
        Includes { stack: vec![top], ..Includes::default() }
    }

    pub fn parse(&mut self, path: &Path, canon: &Path) -> Result<Arc<GraphFile>, IncludeError> {
        if let Some(g) = self.parsed.get(canon) {
            return Ok(g.clone());
        }
        let text = crate::files::read_text(path, crate::files::MAX_GRAPH_FILE).map_err(IncludeError::Read)?;
        let g = Arc::new(GraphFile::parse(&text, path.display().to_string().into()).map_err(IncludeError::Parse)?);
        self.parsed.insert(canon.to_path_buf(), g.clone());
        Ok(g)
    }

    /// How many blocks `g` (the file at `path`) flattens to; `None` when an
    /// include below it cannot be read, parsed or is cyclic or too deep —
    /// expanding it then reports that error at its position.
    pub fn expanded_size(&mut self, g: &GraphFile, canon: &Path, path: &Path) -> Option<usize> {
        if let Some(&n) = self.sizes.get(canon) {
            return Some(n);
        }
        if self.stack.len() >= MAX_DEPTH || self.stack.iter().any(|p| p == canon) {
            return None;
        }
        self.stack.push(canon.to_path_buf());
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut total = 0usize;
        for b in &g.blocks {
            let n = if b.type_name == SUBSYSTEM {
                let rel = yaml::lookup(&b.params, "file").and_then(|v| match &v.kind {
                    Kind::Str(s) => Some(s.clone()),
                    _ => None,
                });
                let sub = rel.and_then(|rel| {
                    let p = dir.join(rel);
                    let c = canonical(&p);
                    let sub = self.parse(&p, &c).ok()?;
                    self.expanded_size(&sub, &c, &p)
                });
                match sub {
                    Some(n) => n,
                    None => {
                        self.stack.pop();
                        return None;
                    }
                }
            } else {
                1
            };
            total = total.saturating_add(n);
        }
        self.stack.pop();
        self.sizes.insert(canon.to_path_buf(), total);
        Some(total)
    }
}
