//! `ctlgraph codegen --target c`: the generated C against the simulation,
//! on the host (SIL) and on an emulated Cortex-M4 (PIL), the papers'
//! controllers bit for bit; every block's C form against its Rust form on
//! random inputs (`forms`); what is refused, and where.

#[path = "../common/mod.rs"]
mod common;
mod dynamics;
mod forms;
mod papers;
mod refusals;

use ctlgraph::target_c::{Generated, from_model, samples, verify};
use ctlgraph_core::codegen::c::Real;
use proptest::prelude::*;

/// The C of a whole graph (its inports and outports the controller's).
pub fn generated(yaml: &str, real: Real) -> Generated {
    let model = ctlgraph::compile_str(yaml, "test.yaml", &[]).unwrap_or_else(|d| panic!("{d}\n{yaml}"));
    from_model(model, None, "ctl", real, "test.yaml").unwrap_or_else(|d| panic!("{d}\n{yaml}"))
}

/// SIL of `yaml` with its inports driven by `rows` (one row per sample).
pub fn sil(yaml: &str, rows: &[f64]) -> (verify::Comparison, Generated) {
    let g = generated(yaml, Real::Double);
    let expected = samples::drive(g.model.clone(), &g.controller, rows).unwrap_or_else(|e| panic!("{e}\n{yaml}"));
    let c = verify::software_in_the_loop(&g, &expected).unwrap_or_else(|e| panic!("{e}\n{yaml}"));
    (c, g)
}

/// Whether the PIL tools are installed; `CTLGRAPH_REQUIRE_PIL=1` (CI)
/// makes their absence a failure instead of a skip.
pub fn pil_tools() -> bool {
    let found =
        |tool: &str| std::process::Command::new(tool).arg("--version").output().is_ok_and(|o| o.status.success());
    let present = found("arm-none-eabi-gcc") && found("qemu-system-arm");
    if !present {
        assert!(
            std::env::var_os("CTLGRAPH_REQUIRE_PIL").is_none(),
            "CTLGRAPH_REQUIRE_PIL is set but the PIL tools are missing"
        );
        eprintln!("skipped: arm-none-eabi-gcc or qemu-system-arm not installed");
    }
    present
}

/// The sample time of every test graph.
pub const H: f64 = 0.01;

/// `samples` rows of `width` inputs from `seed`.
pub fn rows(seed: u64, samples: usize, width: usize, scale: f64) -> Vec<f64> {
    let mut state = seed | 1;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut value = vec![0.0; width];
    let mut out = Vec::with_capacity(samples * width);
    for _ in 0..samples {
        for v in value.iter_mut() {
            let r = next();
            *v = match (r * 20.0) as u32 {
                0 if r < 0.025 => 0.0,
                0 => -0.0,
                1 => *v,
                2 => (next() - 0.5) * 4.0 * scale,
                _ => *v + (next() - 0.5) * 0.2 * scale,
            };
        }
        out.extend_from_slice(&value);
    }
    out
}

/// A graph of inports `u1…` (widths `inputs`), `block` (its YAML mapping
/// body) named `b`, and outports `y1…` on its outputs `ports`.
pub fn graph(inputs: &[usize], block: &str, in_ports: &[&str], out_ports: &[&str], samples: usize) -> String {
    let mut y = format!(
        "simulation: {{ stop: {}, solver: {{ method: rk4, step: {H} }} }}\nblocks:\n",
        (samples - 1) as f64 * H
    );
    for (i, w) in inputs.iter().enumerate() {
        y.push_str(&format!("  u{}: {{ type: inport, width: {w} }}\n", i + 1));
    }
    y.push_str(&format!("  b: {{ {block} }}\n"));
    for i in 0..out_ports.len() {
        y.push_str(&format!("  y{}: {{ type: outport }}\n", i + 1));
    }
    y.push_str("wires:\n");
    for (i, p) in in_ports.iter().enumerate() {
        y.push_str(&format!("  - u{} -> b{p}\n", i + 1));
    }
    for (i, p) in out_ports.iter().enumerate() {
        y.push_str(&format!("  - b{p} -> y{}\n", i + 1));
    }
    y
}

/// SIL of `yaml` on random rows: bit for bit.
pub fn bit_for_bit(yaml: &str, width: usize, seed: u64, samples: usize, scale: f64) -> Result<(), TestCaseError> {
    let (c, _) = sil(yaml, &rows(seed, samples, width, scale));
    prop_assert_eq!(c.samples, samples);
    prop_assert!(c.differing_bits == 0, "{}\n{}", c.summary(""), yaml);
    Ok(())
}

/// `rows` with one value in eight replaced by one of `specials` (a
/// block's thresholds, limits, breakpoints: where `>` and `>=` differ).
pub fn hitting(rows: Vec<f64>, specials: &[f64], seed: u64) -> Vec<f64> {
    let mut state = seed | 1;
    rows.into_iter()
        .map(|v| {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let r = (state >> 33) as usize;
            if r.is_multiple_of(8) { specials[(r / 8) % specials.len()] } else { v }
        })
        .collect()
}

/// SIL of `yaml` on `rows`: bit for bit.
pub fn bit_for_bit_on(yaml: &str, rows: &[f64]) -> Result<(), TestCaseError> {
    let (c, _) = sil(yaml, rows);
    prop_assert!(c.differing_bits == 0, "{}\n{}", c.summary(""), yaml);
    Ok(())
}

/// `rows` kept at least `floor` away from zero (divisors).
pub fn away_from_zero(rows: Vec<f64>, floor: f64) -> Vec<f64> {
    rows.into_iter().map(|v| if v.abs() < floor { floor + v.abs() } else { v }).collect()
}

pub fn list(values: &[f64]) -> String {
    format!("[{}]", values.iter().map(|v| format!("{v:e}")).collect::<Vec<_>>().join(", "))
}
