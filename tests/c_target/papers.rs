//! The papers' controllers as users generate them: the command line,
//! SIL bit for bit over the paper's scenario, PIL on the emulated Cortex-M4.

use crate::common::{ctlgraph, path, text};

/// `ctlgraph codegen --target c GRAPH --subsystem ctrl …` into a fresh folder; its output lines.
fn generate(graph: &str, name: &str, extra: &[&str]) -> (Vec<String>, tempfile::TempDir) {
    generate_from(graph, "ctrl", name, extra)
}

fn generate_from(graph: &str, subsystem: &str, name: &str, extra: &[&str]) -> (Vec<String>, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let mut args =
        vec!["codegen", "--target", "c", graph, "--subsystem", subsystem, "--name", name, "--out", path(dir.path())];
    args.extend_from_slice(extra);
    let out = ctlgraph(&args);
    assert!(out.status.success(), "{}{}", text(&out.stdout), text(&out.stderr));
    (text(&out.stdout).lines().map(str::to_string).collect(), dir)
}

#[test]
fn ladrc_controller_is_bit_for_bit_in_software_in_the_loop() {
    let (lines, dir) = generate("graphs/fladrc/ladrc.yaml", "ladrc", &["--verify"]);
    assert_eq!(lines[1], "verify: 20001 samples, 1 outputs, max |difference| = 0 (bit for bit)");
    let header = std::fs::read_to_string(dir.path().join("ladrc.h")).unwrap();
    for part in
        ["double r;", "double y;", "double u;", "void ladrc_init(ladrc_state *s);", "#define LADRC_BASE_PERIOD 0.0001"]
    {
        assert!(header.contains(part), "{part} in\n{header}");
    }
    let source = std::fs::read_to_string(dir.path().join("ladrc.c")).unwrap();
    for banned in ["malloc", "static double s", "#include <stdio.h>"] {
        assert!(!source.contains(banned), "{banned} in\n{source}");
    }
}

#[test]
fn fladrc_controller_with_its_fuzzy_tuning_is_bit_for_bit_in_software_in_the_loop() {
    let (lines, dir) = generate("graphs/fladrc/fladrc.yaml", "fladrc", &["--verify"]);
    assert_eq!(lines[0].split(": ").nth(1).unwrap(), "9 blocks, 2 inputs, 1 outputs, step every 0.0001 s");
    assert_eq!(lines[1], "verify: 20001 samples, 1 outputs, max |difference| = 0 (bit for bit)");
    let source = std::fs::read_to_string(dir.path().join("fladrc.c")).unwrap();
    assert!(
        source.contains("static const double tune_peaks_0[7]") && source.contains("/* tune (fuzzy) */"),
        "{source}"
    );
}

/// The footprint line's number after `key`.
fn number(footprint: &str, key: &str) -> f64 {
    let at = footprint.find(key).unwrap_or_else(|| panic!("{key} in {footprint}")) + key.len();
    footprint[at..].split_whitespace().next().unwrap().parse().unwrap()
}

#[test]
fn the_adrc_controllers_run_bit_for_bit_on_an_emulated_cortex_m4() {
    if !crate::pil_tools() {
        return;
    }
    // (graph, name, flash, RAM, instructions per step): ranges around today's 0.9 kB / 112 B / 3.8k
    // and 6.0 kB / 184 B / 28.8k, soft double on the M4F's single-precision FPU.
    let cases = [
        ("graphs/fladrc/ladrc.yaml", "ladrc", 500.0..2000.0, 64.0..256.0, 2000.0..8000.0),
        ("graphs/fladrc/fladrc.yaml", "fladrc", 3000.0..12000.0, 128.0..512.0, 15000.0..60000.0),
    ];
    for (graph, name, flash, ram, per_step) in cases {
        let (lines, _dir) = generate(graph, name, &["--verify", "--target-cpu", "cortex-m4"]);
        assert_eq!(
            lines[2],
            "verify on cortex-m4 (QEMU mps2-an386): 20001 samples, 1 outputs, max |difference| = 0 (bit for bit)"
        );
        let footprint = &lines[3];
        assert!(flash.contains(&number(footprint, "flash ")), "{footprint}");
        assert!(ram.contains(&number(footprint, "RAM ")), "{footprint}");
        assert!(per_step.contains(&number(footprint, "B stack, ")), "{footprint}");
    }
}

/// The contact-force paper's sliding-mode law, a subsystem inside the
/// force loop's subsystem, over the 10 s scan at 1 kHz: its three outputs
/// (u, S, the disturbance estimate) bit for bit, on the host and the M4.
#[test]
fn the_contact_force_sliding_mode_law_is_bit_for_bit_on_host_and_target() {
    let target: &[&str] = if crate::pil_tools() { &["--target-cpu", "cortex-m4"] } else { &[] };
    let mut args = vec!["--verify"];
    args.extend_from_slice(target);
    let (lines, dir) = generate_from("graphs/contact-force/impedance_smc.yaml", "loop/ctrl", "smc", &args);
    assert_eq!(lines[0].split(": ").nth(1).unwrap(), "1 blocks, 5 inputs, 3 outputs, step every 0.001 s");
    assert_eq!(lines[1], "verify: 10001 samples, 3 outputs, max |difference| = 0 (bit for bit)");
    if !target.is_empty() {
        assert_eq!(
            lines[2],
            "verify on cortex-m4 (QEMU mps2-an386): 10001 samples, 3 outputs, max |difference| = 0 (bit for bit)"
        );
        assert!((300.0..3000.0).contains(&number(&lines[3], "B stack, ")), "{lines:?}");
    }
    let header = std::fs::read_to_string(dir.path().join("smc.h")).unwrap();
    for field in ["double xr;", "double ddxr;", "double dx;", "double u;", "double s;", "double d_hat;"] {
        assert!(header.contains(field), "{field} in\n{header}");
    }
}

/// Single precision (`--float single`): the FPU's own type, some twenty
/// times fewer instructions, and outputs within 1 % of their range.
#[test]
fn single_precision_is_checked_against_a_bound() {
    if !crate::pil_tools() {
        return;
    }
    let (lines, dir) =
        generate("graphs/fladrc/ladrc.yaml", "ladrc", &["--verify", "--target-cpu", "cortex-m4", "--float", "single"]);
    let header = std::fs::read_to_string(dir.path().join("ladrc.h")).unwrap();
    assert!(header.contains("float r;") && !header.contains("double r;"), "{header}");
    assert!(lines[1].starts_with("verify: 20001 samples, 1 outputs, max |difference| = "), "{lines:?}");
    assert!(number(&lines[3], "B stack, ") < 400.0, "{lines:?}");
}

/// A difference above the bound fails the command (exit 1) and says by how much.
#[test]
fn a_difference_above_the_bound_exits_1() {
    let dir = tempfile::tempdir().unwrap();
    let out = ctlgraph(&[
        "codegen",
        "--target",
        "c",
        "graphs/fladrc/ladrc.yaml",
        "--subsystem",
        "ctrl",
        "--out",
        path(dir.path()),
        "--verify",
        "--float",
        "single",
        "--tolerance",
        "1e-6",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("verify: 20001 samples, 1 outputs, max |difference| = 4.563e-3"),
        "{}",
        text(&out.stdout)
    );
    assert!(
        text(&out.stderr).contains("error: the C differs from the simulation by more than 1e-6"),
        "{}",
        text(&out.stderr)
    );
}
