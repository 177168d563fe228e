//! `ctlgraph fmu`: a graph as a co-simulation FMU (FMI 3.0 or 2.0).
//!
//! The archive holds what [`ctlgraph_fmi::package`] gathers — the
//! description, the configuration, the graph and the files it reads —
//! and the FMU binary: the `ctlgraph-fmi` crate built as a shared library
//! by cargo into ctlgraph's library cache ([`crate::toolchain`]), once per
//! machine and ctlgraph version (every FMU shares it: the graph is data
//! it loads at instantiation).

use crate::accel::Cost;
use crate::toolchain::{self, Features};
use ctlgraph_core::Diagnostic;
use ctlgraph_fmi::package::{Package, model_identifier, package, platform_folder};
use ctlgraph_fmi::table::Version;
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// Why an export failed: the graph (exit 2) or the making of the FMU (exit 1).
pub enum ExportError {
    Graph(Diagnostic),
    Make(String),
}

/// An FMU written.
pub struct Exported {
    pub package: Package,
    /// What the binary cost: built now, or taken from the cache.
    pub binary: Cost,
    pub bytes: usize,
}

/// Writes the FMU of the graph at `graph` (with `sets`) to `out`.
pub fn export(graph: &Path, sets: &[(String, String)], version: Version, out: &Path) -> Result<Exported, ExportError> {
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let identifier = model_identifier(&stem);
    let tool = format!("ctlgraph {}", env!("CARGO_PKG_VERSION"));
    let package = package(graph, sets, version, &identifier, &tool).map_err(ExportError::Graph)?;
    let implicit = matches!(package.model.sim.method, ctlgraph_solver::Method::Trbdf2 { .. });
    let (binary, cost) = fmu_binary(Features { implicit }).map_err(ExportError::Make)?;
    let mut files: Vec<(String, Vec<u8>)> = package.files.clone();
    files.push((format!("binaries/{}/{identifier}.so", platform_folder(version)), binary));
    let zipped = zip(&files).map_err(|e| ExportError::Make(format!("cannot write the archive: {e}")))?;
    crate::record::write_atomic(out, &zipped)
        .map_err(|e| ExportError::Make(format!("{}: cannot write: {e}", out.display())))?;
    Ok(Exported { package, binary: cost, bytes: zipped.len() })
}

/// The FMU binary's bytes, from the cache or built now.
fn fmu_binary(features: Features) -> Result<(Vec<u8>, Cost), String> {
    let start = Instant::now();
    let dir = toolchain::cache_dir()?;
    let key = toolchain::fmu_key(features);
    let path = toolchain::library_path(&dir, &key);
    if path.is_file() {
        toolchain::mark_used(&path);
    }
    let built = !path.is_file();
    if built {
        toolchain::build_fmu(&dir, &key, features).map_err(|e| format!("the FMU binary: {e}"))?;
    }
    let bytes = std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let seconds = start.elapsed().as_secs_f64();
    Ok((bytes, if built { Cost::Built(seconds) } else { Cost::Loaded(seconds) }))
}

/// A zip archive of `files`, deflated, in the order given.
fn zip(files: &[(String, Vec<u8>)]) -> zip::result::ZipResult<Vec<u8>> {
    let mut archive = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .unix_permissions(0o644);
    for (name, bytes) in files {
        archive.start_file(name.as_str(), options)?;
        archive.write_all(bytes)?;
    }
    Ok(archive.finish()?.into_inner())
}
