//! A hash of the ctlgraph source the native libraries are built from (an
//! accelerated step, an FMU binary): the crates they link (solver,
//! graph-core, blocks, fmi) and the lock file that pins their dependencies. The build script records it for the program
//! (`CTLGRAPH_SOURCE_HASH`); before building a step, the program hashes
//! the source again and builds only when it is unchanged — a library built
//! from other blocks than the program's would compute other numbers.
//! Shared by `build.rs` (through `#[path]`) and `src/toolchain`.

use std::path::{Path, PathBuf};

/// The folders and files hashed, relative to the workspace root (the
/// workspace manifest: the crates take their dependencies' versions and
/// features from it).
pub const HASHED: [&str; 10] = [
    "Cargo.toml",
    "Cargo.lock",
    "solver/Cargo.toml",
    "solver/src",
    "graph-core/Cargo.toml",
    "graph-core/src",
    "blocks/Cargo.toml",
    "blocks/src",
    "fmi/Cargo.toml",
    "fmi/src",
];

/// 64-bit FNV-1a over each hashed file's relative path and bytes, in path
/// order: stable across builds and platforms, unlike std's hasher.
pub fn source_hash(root: &Path) -> std::io::Result<u64> {
    let mut files = Vec::new();
    for entry in HASHED {
        collect(&root.join(entry), &mut files)?;
    }
    files.sort();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |bytes: &[u8]| {
        for &b in bytes {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    for file in files {
        let relative = file.strip_prefix(root).unwrap_or(&file);
        feed(relative.to_string_lossy().as_bytes());
        feed(&std::fs::read(&file)?);
    }
    Ok(h)
}

/// `path` if it is a Rust source or manifest, or the ones under it.
fn collect(path: &Path, files: &mut Vec<PathBuf>) -> std::io::Result<()> {
    if path.is_dir() {
        for entry in std::fs::read_dir(path)? {
            collect(&entry?.path(), files)?;
        }
    } else if path.extension().is_some_and(|e| e == "rs" || e == "toml" || e == "lock") {
        files.push(path.to_path_buf());
    }
    Ok(())
}
