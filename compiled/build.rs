//! Generates the step of every bundled graph (`graphs/**/*.yaml`,
//! `benches/*.yaml`, and `compiled/graphs/*.yaml`, which exist to test the
//! generator) into `OUT_DIR`, and an index of them (`graphs.rs`) for
//! `src/lib.rs` to include.

use std::fmt::Write;
use std::path::{Path, PathBuf};

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("the crate sits in the workspace");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let mut files = Vec::new();
    for dir in ["graphs", "benches", "compiled/graphs"] {
        collect(&root.join(dir), &mut files);
        println!("cargo::rerun-if-changed={}", root.join(dir).display());
    }
    // Not graphs/fmu/loop.yaml: it needs an FMU exported first (by the tests),
    // and whether it exists must not change what this crate is.
    files.retain(|f| !f.starts_with(root.join("graphs/fmu")) || f.ends_with("van_der_pol.yaml"));
    files.sort();
    let registry = ctlgraph_blocks::registry();
    let (mut modules, mut generated) = (String::new(), String::new());
    for file in files {
        let relative = file.strip_prefix(root).expect("under the root").to_string_lossy().replace('\\', "/");
        // A file that does not compile on its own (a part of a
        // subsystem) is not a run.
        let Ok(model) = ctlgraph_core::load(&file, &[]).and_then(|flat| ctlgraph_core::compile(&flat, &registry))
        else {
            continue;
        };
        let code = ctlgraph_core::codegen::generate(&model);
        let module = relative.trim_end_matches(".yaml").replace(['/', '-', '.'], "_");
        std::fs::write(out.join(format!("{module}.rs")), code).expect("OUT_DIR is writable");
        let _ = writeln!(
            modules,
            "#[allow(clippy::all, clippy::pedantic)]\npub mod {module} {{\n    include!(concat!(env!(\"OUT_DIR\"), \"/{module}.rs\"));\n}}"
        );
        let _ = writeln!(generated, "    (\"{relative}\", trace::<{module}::Step>),");
    }
    let index = format!(
        "{modules}\n/// Every bundled graph's generated step, and its run.\n\
         pub const GENERATED: &[(&str, Trace)] = &[\n{generated}];\n"
    );
    std::fs::write(out.join("graphs.rs"), index).expect("OUT_DIR is writable");
}

/// The YAML files under `dir`, recursively.
fn collect(dir: &Path, files: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            collect(&path, files);
        } else if path.extension().is_some_and(|e| e == "yaml") {
            files.push(path);
        }
    }
}
