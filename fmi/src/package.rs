//! What an FMU of a graph contains besides its binary: the description,
//! the configuration, and the graph with every file it read — found by
//! loading and compiling it once ([`ctlgraph_core::files::reading`]), so
//! subsystem files and data tables come along wherever they are.
//!
//! Layout (FMI 3.0 §2.5, FMI 2.0.4 §2.3):
//! ```text
//! modelDescription.xml
//! binaries/x86_64-linux/<modelIdentifier>.so   (added by `ctlgraph fmu`)
//! resources/ctlgraph.json                       (crate::config)
//! resources/model/…                             (the graph and its files,
//!                                                as they lie relative to
//!                                                the folder holding them all)
//! ```

use crate::config::{self, Config};
use crate::description::{Identity, model_description};
use crate::table::{Causality, Variable, Version, variables};
use ctlgraph_core::{Diagnostic, Model};
use std::path::{Path, PathBuf};

/// An FMU's files but its binary.
pub struct Package {
    /// (path in the archive, contents), the description first.
    pub files: Vec<(String, Vec<u8>)>,
    pub model: Model,
    pub variables: Vec<Variable>,
    pub token: String,
}

impl Package {
    /// How many variables of `causality` it has (arrays counted once).
    pub fn count(&self, causality: Causality) -> usize {
        self.variables.iter().filter(|v| v.causality == causality).count()
    }

    /// Writes the files under `dir` (an FMU unpacked, for tests and tools).
    pub fn write_to(&self, dir: &Path) -> std::io::Result<()> {
        for (name, bytes) in &self.files {
            let path = dir.join(name);
            if let Some(parent) = path.parent() {
                std::fs::create_dir_all(parent)?;
            }
            std::fs::write(path, bytes)?;
        }
        Ok(())
    }
}

/// The platform folder of this machine's binaries (FMI 3.0 §2.5.1.4;
/// FMI 2 names it `linux64`).
pub fn platform_folder(version: Version) -> &'static str {
    match version {
        Version::Fmi3 => "x86_64-linux",
        Version::Fmi2 => "linux64",
    }
}

/// A valid `modelIdentifier` (a C identifier) from a file stem.
pub fn model_identifier(stem: &str) -> String {
    let mut id: String = stem.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    if !id.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') {
        id.insert(0, '_');
    }
    id
}

/// The package of the graph at `graph` with `sets`, for FMI `version`.
pub fn package(
    graph: &Path,
    sets: &[(String, String)],
    version: Version,
    identifier: &str,
    generation_tool: &str,
) -> Result<Package, Diagnostic> {
    let (model, read) = ctlgraph_core::files::reading(|| {
        let flat = ctlgraph_core::load(graph, sets)?;
        ctlgraph_core::compile(&flat, &ctlgraph_blocks::registry())
    });
    let model = model?;
    let in_graph = |e: String| Diagnostic::plain(format!("{}: {e}", graph.display()));
    let variables = variables(&model, version).map_err(in_graph)?;
    let read: Vec<PathBuf> = read.iter().map(|p| p.canonicalize().unwrap_or_else(|_| p.clone())).collect();
    let root = common_folder(&read).ok_or_else(|| in_graph("the graph's files share no folder".to_string()))?;
    let mut files = Vec::new();
    let mut texts: Vec<u8> = Vec::new();
    for path in &read {
        let bytes = std::fs::read(path).map_err(|e| in_graph(format!("cannot read {}: {e}", path.display())))?;
        let rel = path.strip_prefix(&root).unwrap_or(path);
        let name = format!("resources/model/{}", slashed(rel));
        texts.extend_from_slice(name.as_bytes());
        texts.extend_from_slice(&bytes);
        files.push((name, bytes));
    }
    let graph_rel = read.first().map(|g| slashed(g.strip_prefix(&root).unwrap_or(g))).unwrap_or_default();
    for (n, v) in sets {
        texts.extend_from_slice(format!("\n--set {n}={v}").as_bytes());
    }
    texts.extend_from_slice(format!("\n{generation_tool} FMI {}", version.text()).as_bytes());
    let token = token(&texts);
    let config = Config { graph: format!("model/{graph_rel}"), sets: sets.to_vec(), token: token.clone() };
    files.insert(0, (format!("resources/{}", config::FILE), config.to_json().into_bytes()));
    let id = Identity { model_identifier: identifier, token: &token, generation_tool };
    files.insert(
        0,
        ("modelDescription.xml".to_string(), model_description(&model, &variables, &id, version).into_bytes()),
    );
    Ok(Package { files, model, variables, token })
}

/// `path` with `/` between its parts.
fn slashed(path: &Path) -> String {
    path.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("/")
}

/// The deepest folder holding every file of `files`.
fn common_folder(files: &[PathBuf]) -> Option<PathBuf> {
    let mut root = files.first()?.parent()?.to_path_buf();
    for f in &files[1..] {
        while !f.starts_with(&root) {
            root = root.parent()?.to_path_buf();
        }
    }
    Some(root)
}

/// A GUID-shaped token (`{8-4-4-4-12}` hex digits) that changes with the
/// exported files: FNV-1a over them, twice with different seeds.
fn token(bytes: &[u8]) -> String {
    let fnv = |seed: u64| bytes.iter().fold(seed, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
    let (a, b) = (fnv(0xcbf2_9ce4_8422_2325), fnv(0x8422_2325_cbf2_9ce4));
    let hex = format!("{a:016x}{b:016x}");
    format!("{{{}-{}-{}-{}-{}}}", &hex[0..8], &hex[8..12], &hex[12..16], &hex[16..20], &hex[20..32])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers_folders_and_tokens() {
        assert_eq!(model_identifier("ladrc"), "ladrc");
        assert_eq!(model_identifier("my-plant.v2"), "my_plant_v2");
        assert_eq!(model_identifier("2dof"), "_2dof");
        let files = [PathBuf::from("/a/b/c/g.yaml"), PathBuf::from("/a/b/d/s.yaml"), PathBuf::from("/a/b/c/t.csv")];
        assert_eq!(common_folder(&files), Some(PathBuf::from("/a/b")));
        let t = token(b"x");
        assert_eq!(t.len(), 38);
        assert_ne!(t, token(b"y"));
    }
}
