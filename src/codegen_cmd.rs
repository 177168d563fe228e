//! `ctlgraph codegen GRAPH [--out FILE.rs]`: the graph's step as Rust; and
//! `ctlgraph codegen --target c GRAPH [--subsystem PATH] --out DIR
//! [--float single] [--verify [--target-cpu cortex-m4] [--tolerance TOL]]`:
//! its sampled controller as C, checked in the loop.

use ctlgraph::suite::Failure;
use ctlgraph::target_c::{Request, generate, samples, verify, write};
use ctlgraph_core::Diagnostic;
use ctlgraph_core::codegen::c::Real;
use ctlgraph_core::flatten::parse_set;
use std::path::Path;

pub(crate) struct Args<'a> {
    pub graph: &'a Path,
    /// `--target c` (else Rust).
    pub c: bool,
    pub out: Option<&'a Path>,
    pub subsystem: Option<&'a str>,
    pub name: Option<&'a str>,
    pub single: bool,
    pub verify: bool,
    pub target_cpu: Option<&'a str>,
    pub tolerance: Option<f64>,
    pub sets: &'a [String],
}

pub(crate) fn codegen(a: Args) -> Result<(), Failure> {
    if a.c {
        return codegen_c(a);
    }
    let c_only = a.subsystem.is_some() || a.name.is_some() || a.single || a.verify || a.target_cpu.is_some();
    if c_only || a.tolerance.is_some() {
        return Err(Diagnostic::plain(
            "--subsystem, --name, --float, --verify, --target-cpu and --tolerance belong to --target c",
        )
        .into());
    }
    if let Some(path) = a.out.filter(|p| crate::run_cmd::same_file(p, a.graph)) {
        return Err(Diagnostic::plain(format!("--out {}: that is the graph file", path.display())).into());
    }
    let model = crate::compile(a.graph, a.sets)?;
    crate::write_or_print(a.out, &ctlgraph_core::codegen::generate(&model))
}

fn codegen_c(a: Args) -> Result<(), Failure> {
    let Some(out) = a.out else {
        return Err(Diagnostic::plain("--target c writes two files: give the folder with --out DIR")
            .with_hint("e.g. --out controller_c (NAME.h and NAME.c are written there)")
            .into());
    };
    if out.is_file() {
        return Err(
            Diagnostic::plain(format!("--out {}: a file; --target c writes into a folder", out.display())).into()
        );
    }
    if (a.target_cpu.is_some() || a.tolerance.is_some()) && !a.verify {
        return Err(Diagnostic::plain("--target-cpu and --tolerance belong to --verify").into());
    }
    if let Some(t) = a.tolerance.filter(|t| !(*t >= 0.0 && t.is_finite())) {
        return Err(Diagnostic::plain(format!("--tolerance {t}: a number >= 0")).into());
    }
    let sets = a.sets.iter().map(|s| parse_set(s)).collect::<Result<Vec<_>, _>>()?;
    let real = if a.single { Real::Single } else { Real::Double };
    let request = Request { graph: a.graph, sets: &sets, subsystem: a.subsystem, real, name: a.name };
    let generated = generate(&request)?;
    let samples = if a.verify {
        Some(
            samples::record(generated.model.clone(), &generated.controller)
                .map_err(|e| Failure::Run(format!("the simulation: {e}")))?,
        )
    } else {
        None
    };
    let [header, source] = write(out, &generated).map_err(|e| Failure::Run(format!("{}: {e}", out.display())))?;
    let ctl = &generated.controller;
    println!(
        "{}, {}: {} blocks, {} inputs, {} outputs, step every {} s",
        header.display(),
        source.display(),
        ctl.members.len(),
        ctl.inputs.len(),
        ctl.outputs.len(),
        ctl.base_period
    );
    let Some(samples) = samples else { return Ok(()) };
    let bound = a.tolerance.unwrap_or(match real {
        Real::Double => 0.0,
        Real::Single => 1e-2 * samples.outputs.iter().fold(0.0f64, |m, y| m.max(y.abs())),
    });
    let sil = verify::software_in_the_loop(&generated, &samples).map_err(Failure::Run)?;
    let mut failed = judge(&sil, "", bound);
    if let Some(cpu) = a.target_cpu {
        let pil = ctlgraph::target_c::target::processor_in_the_loop(&generated, &samples, cpu).map_err(Failure::Run)?;
        failed |= judge(&pil.comparison, &format!(" on {cpu} (QEMU {})", pil.machine), bound);
        println!("{}", pil.footprint());
    }
    if failed { Err(Failure::Run(String::new())) } else { Ok(()) }
}

/// Prints the comparison; whether it exceeds `bound`.
fn judge(c: &verify::Comparison, on: &str, bound: f64) -> bool {
    println!("{}", c.summary(on));
    if c.max_difference > bound {
        eprintln!("error: the C differs from the simulation by more than {bound:e}");
        return true;
    }
    false
}
