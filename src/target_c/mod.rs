//! `ctlgraph codegen --target c`: a graph's sampled controller as C99
//! (`ctlgraph_core::codegen::c`), and its check in the loop against the
//! simulation — compiled for the host (SIL, [`verify`]) or for an emulated
//! Cortex-M4 under QEMU (PIL, [`target`]).

pub mod samples;
pub mod target;
pub mod verify;

use ctlgraph_core::codegen::c::{self, CFiles, Controller, Options, Real};
use ctlgraph_core::{Diagnostic, Model};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What to generate.
pub struct Request<'a> {
    pub graph: &'a Path,
    pub sets: &'a [(String, String)],
    /// A subsystem of the graph by its path (`ctrl`, `loop/ctrl`); the whole graph when `None`.
    pub subsystem: Option<&'a str>,
    pub real: Real,
    /// The C prefix; the subsystem's name or the graph file's stem by default.
    pub name: Option<&'a str>,
}

/// The generated controller and what it was generated from.
pub struct Generated {
    pub model: Arc<Model>,
    pub controller: Controller,
    pub files: CFiles,
    pub real: Real,
}

/// Loads and compiles the graph and generates its controller's C.
pub fn generate(request: &Request) -> Result<Generated, Diagnostic> {
    let flat = ctlgraph_core::load(request.graph, request.sets)?;
    let model = crate::compile_flat(&flat, &crate::registry())?;
    let stem = request.graph.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let default_name = request.subsystem.map_or(stem, str::to_string);
    let name = request.name.unwrap_or(&default_name);
    let ports;
    let subsystem = match request.subsystem {
        Some(sub) => {
            ports = flat.subsystems.get(sub).ok_or_else(|| {
                let mut all: Vec<&str> = flat.subsystems.keys().map(String::as_str).collect();
                all.sort_unstable();
                Diagnostic::plain(format!("--subsystem {sub}: {} has no subsystem `{sub}`", request.graph.display()))
                    .suggest(sub, all.iter().copied())
                    .or_hint(if all.is_empty() {
                        "it has none: give the subsystem's own file as the graph".to_string()
                    } else {
                        format!("its subsystems: {}", all.join(", "))
                    })
            })?;
            Some((sub, &ports.0[..], &ports.1[..]))
        }
        None => None,
    };
    let origin = match request.subsystem {
        Some(sub) => format!("{}, subsystem {sub}", request.graph.display()),
        None => request.graph.display().to_string(),
    };
    from_model(model, subsystem, name, request.real, &origin)
}

/// The C of `model`'s controller: `subsystem` names a top-level subsystem
/// and its inports and outports, `None` takes the whole graph.
pub fn from_model(
    model: Model,
    subsystem: Option<(&str, &[String], &[String])>,
    name: &str,
    real: Real,
    origin: &str,
) -> Result<Generated, Diagnostic> {
    let controller = c::select(&model, subsystem, &c::identifier(name))?;
    let options = Options { real, origin, types_with_c_form: ctlgraph_blocks::TYPES_WITH_C_FORM };
    let files = c::generate(&model, &controller, &options)?;
    Ok(Generated { model: Arc::new(model), controller, files, real })
}

/// Writes `NAME.h` and `NAME.c` into `dir` (created if missing), each
/// whole or not at all; returns their paths.
pub fn write(dir: &Path, generated: &Generated) -> std::io::Result<[PathBuf; 2]> {
    std::fs::create_dir_all(dir)?;
    let name = &generated.controller.name;
    let header = dir.join(format!("{name}.h"));
    let source = dir.join(format!("{name}.c"));
    crate::record::write_atomic(&header, generated.files.header.as_bytes())?;
    crate::record::write_atomic(&source, generated.files.source.as_bytes())?;
    Ok([header, source])
}
