//! Building ctlgraph's native libraries with cargo, and the cache that
//! keeps them: the step libraries of accelerated runs (`crate::accel`)
//! and the binaries of FMUs (`ctlgraph fmu`, the `ctlgraph-fmi` crate).
//!
//! The cache (`$CTLGRAPH_CACHE_DIR`, else `$XDG_CACHE_HOME/ctlgraph`, else
//! `~/.cache/ctlgraph`) holds, under `libraries/`:
//! - `lib/<key>.so`: one library per product, `key` hashing what it is
//!   built from (a step's generated code, or the FMU binary's name),
//!   ctlgraph's version, the compiler's and the source's hash — a graph
//!   whose structure is unchanged finds its library there and loads it
//!   without calling cargo;
//! - `crates/<key>/`: the crate each library was built from: a short
//!   `lib.rs` (and a step's generated code), and a manifest depending on
//!   ctlgraph's crates by path (the source this program was built from);
//! - `target/`: one cargo target directory for all of them, so ctlgraph's
//!   crates and their dependencies are compiled once (the first build on a
//!   machine) and each later library compiles only its own crate.
//!
//! The libraries beyond the 64 used last are removed after each build
//! (`prune.rs`).

mod prune;
pub mod source;

pub use prune::mark_used;

use std::path::{Path, PathBuf};
use std::process::Command;

/// The compiler that built this program (`rustc -V`), recorded by `build.rs`.
pub const RUSTC_VERSION: &str = env!("CTLGRAPH_RUSTC_VERSION");
/// The hash of the source of ctlgraph's crates this program was built from.
const SOURCE_HASH: &str = env!("CTLGRAPH_SOURCE_HASH");
/// The workspace this program was built from: its crates are the library's.
const SOURCE_DIR: &str = env!("CARGO_MANIFEST_DIR");

/// The cache's folder for the libraries ctlgraph builds.
pub fn cache_dir() -> Result<PathBuf, String> {
    Ok(ctlgraph_core::files::cache_base()?.join("libraries"))
}

/// What a library is built with besides its code: whether it has the
/// implicit method (TR-BDF2, over faer), which only a stiff graph needs;
/// without it the first build on a machine is much shorter.
#[derive(Clone, Copy)]
pub struct Features {
    pub implicit: bool,
}

impl Features {
    /// What the key hashes of them.
    fn tag(self) -> &'static str {
        if self.implicit { "implicit" } else { "" }
    }
}

/// The library's name in the cache for `code` (a step's generated code,
/// or what names another product).
pub fn key(code: &str, features: Features) -> String {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    for part in [code, features.tag(), env!("CARGO_PKG_VERSION"), RUSTC_VERSION, SOURCE_HASH] {
        h.update(part.as_bytes());
        h.update([0]);
    }
    h.finalize().iter().take(8).map(|b| format!("{b:02x}")).collect()
}

/// Where the library for `key` lives in the cache `dir`.
pub fn library_path(dir: &Path, key: &str) -> PathBuf {
    dir.join("lib").join(dll(key))
}

/// The file name of a shared library called `stem` on this platform.
fn dll(stem: &str) -> String {
    format!("{}{stem}{}", std::env::consts::DLL_PREFIX, std::env::consts::DLL_SUFFIX)
}

/// Why this machine cannot build a library now, if it cannot: no cargo,
/// another compiler than the one that built ctlgraph, or ctlgraph's source
/// gone or changed since.
fn unable() -> Option<String> {
    let version = |tool: &str| {
        Command::new(tool)
            .arg("-V")
            .output()
            .ok()
            .filter(|out| out.status.success())
            .map(|out| String::from_utf8_lossy(&out.stdout).trim().to_string())
    };
    if version("cargo").is_none() {
        return Some("no Rust toolchain: `cargo` is not on PATH".to_string());
    }
    match version("rustc") {
        None => return Some("no Rust toolchain: `rustc` is not on PATH".to_string()),
        Some(v) if v != RUSTC_VERSION => {
            return Some(format!("the Rust compiler on PATH is `{v}`, ctlgraph was built by `{RUSTC_VERSION}`"));
        }
        Some(_) => {}
    }
    match source::source_hash(Path::new(SOURCE_DIR)) {
        Err(e) => Some(format!("ctlgraph's source is not at {SOURCE_DIR} ({e}): the step is built against it")),
        Ok(h) if format!("{h:016x}") != SOURCE_HASH => Some(format!(
            "ctlgraph's source at {SOURCE_DIR} changed since this program was built: rebuild ctlgraph first"
        )),
        Ok(_) => None,
    }
}

/// Builds the step library for `key` from the generated `code` into the cache `dir`.
pub fn build(dir: &Path, key: &str, code: &str, features: Features) -> Result<(), String> {
    let name = format!("ctlgraph_step_{key}");
    let dependencies = format!(
        "ctlgraph-core = {}\nctlgraph-blocks = {}\n",
        dependency("graph-core", features, &[]),
        dependency("blocks", features, &[])
    );
    let files = [("lib.rs", STEP_LIB_RS.to_string()), ("step.rs", code.to_string())];
    build_crate(dir, key, &name, &dependencies, &files)
}

/// Builds the FMU binary (the `ctlgraph-fmi` crate with its C symbols)
/// into the cache `dir`, under the key [`fmu_key`] gives.
pub fn build_fmu(dir: &Path, key: &str, features: Features) -> Result<(), String> {
    let name = format!("ctlgraph_fmu_{key}");
    let dependencies = format!("ctlgraph-fmi = {}\n", dependency("fmi", features, &["symbols"]));
    build_crate(dir, key, &name, &dependencies, &[("lib.rs", FMU_LIB_RS.to_string())])
}

/// The cache key of the FMU binary built with `features`.
pub fn fmu_key(features: Features) -> String {
    key("the FMU binary: the ctlgraph-fmi crate with its symbols", features)
}

/// A manifest's dependency on the workspace crate in `folder`.
fn dependency(folder: &str, features: Features, more: &[&str]) -> String {
    let path = Path::new(SOURCE_DIR).join(folder).display().to_string().replace('\\', "/");
    let mut list: Vec<String> = more.iter().map(|f| format!("\"{f}\"")).collect();
    if features.implicit {
        list.push("\"implicit\"".to_string());
    }
    format!("{{ path = \"{path}\", default-features = false, features = [{}] }}", list.join(", "))
}

/// Builds the crate `name` (its `dependencies` lines and `files`) with
/// cargo and copies the library into the cache `dir` as `key`.
fn build_crate(dir: &Path, key: &str, name: &str, dependencies: &str, files: &[(&str, String)]) -> Result<(), String> {
    if let Some(why) = unable() {
        return Err(why);
    }
    let krate = dir.join("crates").join(key);
    std::fs::create_dir_all(&krate).map_err(io(&krate))?;
    let source = Path::new(SOURCE_DIR);
    let manifest = manifest(name, dependencies);
    for (file, text) in files.iter().map(|(f, t)| (*f, t.as_str())).chain([("Cargo.toml", manifest.as_str())]) {
        std::fs::write(krate.join(file), text).map_err(io(&krate.join(file)))?;
    }
    // The versions ctlgraph was built and tested with, so the library's
    // dependencies are those and no index is needed (`--offline`).
    let lock = krate.join("Cargo.lock");
    std::fs::copy(source.join("Cargo.lock"), &lock).map_err(io(&lock))?;
    let target = dir.join("target");
    let out = Command::new("cargo")
        .args(["build", "--release", "--offline", "--lib", "--quiet", "--manifest-path"])
        .arg(krate.join("Cargo.toml"))
        .env("CARGO_TARGET_DIR", &target)
        .env_remove("CARGO_BUILD_TARGET_DIR")
        .output()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !out.status.success() {
        let stderr = String::from_utf8_lossy(&out.stderr);
        let last: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        let tail = last[last.len().saturating_sub(3)..].join(" / ");
        return Err(format!("cargo could not build the library (in {}): {tail}", krate.display()));
    }
    let built = target.join("release").join(dll(name));
    let dest = library_path(dir, key);
    let lib_dir = dest.parent().unwrap_or(dir);
    std::fs::create_dir_all(lib_dir).map_err(io(lib_dir))?;
    // Copied under a temporary name and renamed: a library in `lib/` is
    // always whole, also for another ctlgraph building the same one.
    let partial = lib_dir.join(format!(".{key}.{}.partial", std::process::id()));
    std::fs::copy(&built, &partial).map_err(io(&partial))?;
    std::fs::rename(&partial, &dest).map_err(io(&dest))?;
    prune::prune(dir, std::time::SystemTime::now());
    Ok(())
}

/// The error for a file that cannot be written.
fn io(what: &Path) -> impl FnOnce(std::io::Error) -> String + '_ {
    move |e| format!("cannot write {}: {e}", what.display())
}

/// A step library's `lib.rs`: the generated step, exported.
const STEP_LIB_RS: &str = "#[allow(clippy::all, unused)]\nmod step;\n\
                           ctlgraph_core::export_accelerated!(step::Step, ctlgraph_blocks::registry);\n";

/// The FMU binary's `lib.rs`: the crate whose `symbols` feature exports
/// the FMI functions, linked in.
const FMU_LIB_RS: &str = "extern crate ctlgraph_fmi;\n";

/// A library crate's manifest. Its own workspace (a cache inside another
/// project's folder must not join that workspace); one codegen unit, so
/// a step's calls into the blocks inline as in a crate of the workspace.
fn manifest(name: &str, dependencies: &str) -> String {
    format!(
        "[package]\nname = \"{name}\"\nversion = \"0.0.0\"\nedition = \"2024\"\npublish = false\n\n\
         [lib]\npath = \"lib.rs\"\ncrate-type = [\"cdylib\"]\n\n\
         [dependencies]\n{dependencies}\n\
         [profile.release]\ndebug = false\n\n\
         [profile.release.package.{name}]\ncodegen-units = 1\n\n\
         [workspace]\n"
    )
}
