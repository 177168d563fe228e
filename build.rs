//! Records what the native libraries (an accelerated step, an FMU binary)
//! must be built with to compute what this program computes (see
//! `src/toolchain`): the compiler's version and a hash of the ctlgraph
//! crates' source.

#[path = "src/toolchain/source.rs"]
mod source;

fn main() {
    let root = std::path::PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".to_string());
    let version = std::process::Command::new(&rustc)
        .arg("-V")
        .output()
        .ok()
        .and_then(|out| String::from_utf8(out.stdout).ok())
        .map(|v| v.trim().to_string())
        .unwrap_or_default();
    println!("cargo::rustc-env=CTLGRAPH_RUSTC_VERSION={version}");
    let hash = source::source_hash(&root).expect("the workspace's crates are readable");
    println!("cargo::rustc-env=CTLGRAPH_SOURCE_HASH={hash:016x}");
    for entry in source::HASHED {
        println!("cargo::rerun-if-changed={}", root.join(entry).display());
    }
}
