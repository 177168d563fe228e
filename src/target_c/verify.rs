//! Software in the loop: the generated C, with a generated driver,
//! compiled by the host's C compiler and fed the recorded inputs of every
//! sample; its outputs compared with the simulation's.

use super::Generated;
use super::samples::Samples;
use ctlgraph_core::codegen::c::harness;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The flags the generated C must compile under without a warning, and
/// the one that keeps its roundings the simulation's (no fused multiply-add).
pub const STRICT_FLAGS: &[&str] = &["-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-ffp-contract=off"];

/// How the C's outputs compare with the simulation's.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    pub samples: usize,
    /// Output values per sample.
    pub outputs: usize,
    pub max_difference: f64,
    /// Values whose bits differ (a zero of the other sign counts).
    pub differing_bits: usize,
}

impl Comparison {
    /// `verify: N samples, M outputs, max |difference| = …`.
    pub fn summary(&self, on: &str) -> String {
        let (difference, exact) = match (self.max_difference, self.differing_bits) {
            (0.0, 0) => ("0".to_string(), " (bit for bit)".to_string()),
            (d, n) => (
                if d == 0.0 { "0".to_string() } else { format!("{d:.3e}") },
                format!(" ({n} values differ in their bits)"),
            ),
        };
        format!(
            "verify{on}: {} samples, {} outputs, max |difference| = {difference}{exact}",
            self.samples, self.outputs
        )
    }
}

/// Compares the C's outputs with the simulation's, value by value (NaN
/// equals NaN; NaN against a number is an infinite difference).
pub fn compare(expected: &Samples, got: &[f64]) -> Result<Comparison, String> {
    if got.len() != expected.outputs.len() {
        return Err(format!(
            "the C wrote {} output values, the simulation {} ({} samples)",
            got.len(),
            expected.outputs.len(),
            expected.count
        ));
    }
    let mut max_difference: f64 = 0.0;
    let mut differing_bits = 0;
    for (&a, &b) in expected.outputs.iter().zip(got) {
        if a.to_bits() != b.to_bits() && !(a.is_nan() && b.is_nan()) {
            differing_bits += 1;
        }
        let d = if a.is_nan() || b.is_nan() {
            if a.is_nan() == b.is_nan() { 0.0 } else { f64::INFINITY }
        } else {
            (a - b).abs()
        };
        max_difference = max_difference.max(d);
    }
    let outputs = expected.outputs.len().checked_div(expected.count).unwrap_or(0);
    Ok(Comparison { samples: expected.count, outputs, max_difference, differing_bits })
}

/// Writes the controller, its driver and the inputs into `dir`; returns
/// the C files to compile (driver first).
pub fn stage(dir: &Path, generated: &Generated, samples: &Samples) -> Result<Vec<PathBuf>, String> {
    let io = |e: std::io::Error| format!("{}: {e}", dir.display());
    let [_, source] = super::write(dir, generated).map_err(io)?;
    let driver = dir.join(format!("{}_driver.c", generated.controller.name));
    let name = &generated.controller.name;
    std::fs::write(&driver, harness(name, &generated.files, generated.real)).map_err(io)?;
    std::fs::write(dir.join("inputs.bin"), samples.input_bytes()).map_err(io)?;
    Ok(vec![driver, source])
}

/// Reads the driver's output file.
pub fn read_outputs(path: &Path) -> Result<Vec<f64>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(bytes.chunks_exact(8).map(|c| f64::from_ne_bytes(c.try_into().expect("8 bytes"))).collect())
}

/// Runs `command`; its standard error in the message when it fails.
pub fn run(command: &mut Command, what: &str) -> Result<String, String> {
    let program = command.get_program().to_string_lossy().into_owned();
    let out = command.output().map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => format!("{what}: `{program}` not found"),
        _ => format!("{what}: {program}: {e}"),
    })?;
    if !out.status.success() {
        let mut text = String::from_utf8_lossy(&out.stderr).into_owned();
        text.push_str(&String::from_utf8_lossy(&out.stdout));
        return Err(format!("{what} failed ({}):\n{}", out.status, text.trim_end()));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// SIL: compiles with `$CC` (default `cc`) under [`STRICT_FLAGS`] and
/// `-O2`, runs, compares.
pub fn software_in_the_loop(generated: &Generated, samples: &Samples) -> Result<Comparison, String> {
    let dir =
        tempfile::Builder::new().prefix("ctlgraph-sil-").tempdir().map_err(|e| format!("a temporary folder: {e}"))?;
    let sources = stage(dir.path(), generated, samples)?;
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let program = dir.path().join("sil");
    let mut compile = Command::new(&cc);
    compile.args(STRICT_FLAGS).arg("-O2").args(&sources).arg("-lm").arg("-o").arg(&program);
    run(&mut compile, "compiling the generated C for the host")
        .map_err(|e| if e.contains("not found") { format!("{e}: install a C compiler (gcc), or set CC") } else { e })?;
    let outputs = dir.path().join("outputs.bin");
    run(Command::new(&program).arg(dir.path().join("inputs.bin")).arg(&outputs), "running the generated C")?;
    compare(samples, &read_outputs(&outputs)?)
}
