//! Prints the README's performance tables from criterion's last results
//! (the medians in target/criterion/*/new/estimates.json), so the numbers
//! quoted are the ones a run measured, side by side:
//!
//!     cargo bench --bench fladrc --bench overhead --bench scaling --bench sweep
//!     cargo run --release --example perf_table

use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Samples of the FLADRC scenario (2 s at h = 1e-4, both ends) and steps of
/// the PID loop, as the benches run them.
const SCENARIO_SAMPLES: f64 = 20_001.0;
const PID_STEPS: f64 = 10_000.0;
/// Steps per timed run in the scaling bench.
const SCALING_STEPS: f64 = 100.0;

fn main() -> ExitCode {
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| PathBuf::from("target"), PathBuf::from);
    match tables(&target.join("criterion")) {
        Ok(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

/// The median of benchmark `id` in seconds.
fn median(root: &Path, id: &str) -> Result<f64, String> {
    let file = root.join(id).join("new/estimates.json");
    let text = std::fs::read_to_string(&file)
        .map_err(|e| format!("{}: {e} (run the benches first: see this example's doc)", file.display()))?;
    let json: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", file.display()))?;
    let ns = json["median"]["point_estimate"].as_f64().ok_or_else(|| format!("{}: no median", file.display()))?;
    Ok(ns * 1e-9)
}

/// The median of the per-sample ratios of paired benchmark `id` (see
/// benches/paired/mod.rs): each sample times it right after its
/// hand-written reference.
fn paired_ratio(root: &Path, id: &str) -> Result<f64, String> {
    let file = root.join(id).join("paired_ratio.json");
    let text = std::fs::read_to_string(&file)
        .map_err(|e| format!("{}: {e} (run the benches first: see this example's doc)", file.display()))?;
    let json: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", file.display()))?;
    json["median_ratio"].as_f64().ok_or_else(|| format!("{}: no median_ratio", file.display()))
}

/// A duration with three significant digits in a unit that suits it.
fn duration(seconds: f64) -> String {
    let (value, unit) = match seconds {
        s if s >= 1.0 => (s, "s"),
        s if s >= 1e-3 => (s * 1e3, "ms"),
        s if s >= 1e-6 => (s * 1e6, "µs"),
        s => (s * 1e9, "ns"),
    };
    let decimals = if value >= 100.0 {
        0
    } else if value >= 10.0 {
        1
    } else {
        2
    };
    format!("{value:.decimals$} {unit}")
}

/// A whole number with a space between thousands, as the README writes them.
fn grouped(n: f64) -> String {
    let digits = format!("{:.0}", n.round());
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(' ');
        }
        out.push(c);
    }
    out
}

/// The tables, from the medians under `root` (target/criterion).
pub fn tables(root: &Path) -> Result<String, String> {
    let m = |id: &str| median(root, id);
    let mut out = String::new();
    let paired = |id: &str| paired_ratio(root, id);
    out.push_str(
        "| scenario (`cargo bench --bench …`) | hand-written | ctlgraph | ratio | paired ratio |\n|---|---|---|---|---|\n",
    );
    let per = |total: f64, count: f64, what: &str| format!("{} ({}/{what})", duration(total), duration(total / count));
    let rows = [
        (
            "FLADRC paper, 2 s at h = 1e-4, 20 001 samples (`fladrc`)",
            "fladrc_scenario_20k_samples/fladrc",
            SCENARIO_SAMPLES,
            "sample",
        ),
        ("LADRC paper, same scenario (`fladrc`)", "fladrc_scenario_20k_samples/ladrc", SCENARIO_SAMPLES, "sample"),
        ("tutorial PID loop, RK4, 10 000 steps (`overhead`)", "pid_loop_10k_rk4_steps/", PID_STEPS, "step"),
    ];
    for (name, prefix, count, what) in rows {
        let sep = if prefix.ends_with('/') { "" } else { "_" };
        let (hand, graph) = (m(&format!("{prefix}{sep}hand_written"))?, m(&format!("{prefix}{sep}ctlgraph"))?);
        let (hand_cell, graph_cell) = (per(hand, count, what), per(graph, count, what));
        let pair = paired(&format!("{prefix}{sep}ctlgraph"))?;
        out.push_str(&format!("| {name} | {hand_cell} | {graph_cell} | {:.2}× | {pair:.2}× |\n", graph / hand));
    }
    let (hand, fis) = (m("fuzzy_7x7_two_outputs/hand_written")?, m("fuzzy_7x7_two_outputs/ctlgraph_fis")?);
    out.push_str(&format!(
        "| the paper's 7×7 two-output fuzzy system, one evaluation (`fladrc`) | {} | {} | {:.2}× | — |\n",
        duration(hand),
        duration(fis),
        fis / hand
    ));
    // What the interpreter's overhead becomes without it: the graphs'
    // generated steps, and their blocks called in order by hand.
    let beside_hand = |out: &mut String, heading: &str, rows: &[(&str, &str, &str, f64, &str)]| {
        out.push_str(&format!(
            "\n| {heading} | hand-written | {heading} | ratio | paired ratio |\n|---|---|---|---|---|\n"
        ));
        for &(name, hand_id, id, count, what) in rows {
            let (hand, subject) = (m(hand_id)?, m(id)?);
            let (hand_cell, cell) = (per(hand, count, what), per(subject, count, what));
            out.push_str(&format!(
                "| {name} | {hand_cell} | {cell} | {:.2}× | {:.2}× |\n",
                subject / hand,
                paired(id)?
            ));
        }
        Ok::<(), String>(())
    };
    let (fladrc, ladrc, pid) = (
        "fladrc_scenario_20k_samples/fladrc_hand_written",
        "fladrc_scenario_20k_samples/ladrc_hand_written",
        "pid_loop_10k_rk4_steps/hand_written",
    );
    beside_hand(
        &mut out,
        "generated step",
        &[
            (
                "FLADRC paper (`fladrc`)",
                fladrc,
                "fladrc_scenario_20k_samples/fladrc_compiled",
                SCENARIO_SAMPLES,
                "sample",
            ),
            ("LADRC paper (`fladrc`)", ladrc, "fladrc_scenario_20k_samples/ladrc_compiled", SCENARIO_SAMPLES, "sample"),
            ("tutorial PID loop (`overhead`)", pid, "pid_loop_10k_rk4_steps/compiled", PID_STEPS, "step"),
        ],
    )?;
    beside_hand(
        &mut out,
        "accelerated (`--accelerate`)",
        &[
            (
                "FLADRC paper (`fladrc`)",
                fladrc,
                "fladrc_scenario_20k_samples/fladrc_accelerated",
                SCENARIO_SAMPLES,
                "sample",
            ),
            (
                "LADRC paper (`fladrc`)",
                ladrc,
                "fladrc_scenario_20k_samples/ladrc_accelerated",
                SCENARIO_SAMPLES,
                "sample",
            ),
            ("tutorial PID loop (`overhead`)", pid, "pid_loop_10k_rk4_steps/accelerated", PID_STEPS, "step"),
        ],
    )?;
    beside_hand(
        &mut out,
        "blocks fused by hand",
        &[
            (
                "LADRC paper (`fladrc`)",
                ladrc,
                "fladrc_scenario_20k_samples/ladrc_fused_blocks",
                SCENARIO_SAMPLES,
                "sample",
            ),
            ("tutorial PID loop (`overhead`)", pid, "pid_loop_10k_rk4_steps/fused_blocks", PID_STEPS, "step"),
        ],
    )?;
    out.push_str(
        "\n| n | compile, chain | compile, fan-out (2n blocks) | ns per block-step, chain (RK4) | the chain by hand \
         | ns per gain past the fixed part | by hand |\n|---|---|---|---|---|---|---|\n",
    );
    // ns a step of the chain of n gains, by the graph and by hand.
    let step = |n: u32| -> Result<(f64, f64), String> {
        let per_step = |run: f64| run / SCALING_STEPS * 1e9;
        Ok((per_step(m(&format!("chain_100_steps/{n}"))?), per_step(m(&format!("chain_by_hand_100_steps/{n}"))?)))
    };
    let fixed = step(0)?;
    for n in [10u32, 1_000, 100_000] {
        let (chain, fan) = (m(&format!("chain_compile/{n}"))?, m(&format!("fan_out_compile/{n}"))?);
        let ((graph, hand), k) = (step(n)?, f64::from(n));
        let (past, past_by_hand) = ((graph - fixed.0) / k, (hand - fixed.1) / k);
        let (n, chain, fan) = (grouped(k), duration(chain), duration(fan));
        out.push_str(&format!(
            "| {n} | {chain} | {fan} | {:.0} | {:.1} | {past:.1} | {past_by_hand:.1} |\n",
            graph / k,
            hand / k
        ));
    }
    out.push_str(&format!(
        "\nThe step's fixed part (the chain of no gains, the sine into the integrator): {:.0} ns, by hand {:.0} ns.\n",
        fixed.0, fixed.1
    ));
    let (one, two) = (m("pid_loop_sweep_400_cases/jobs_1")?, m("pid_loop_sweep_400_cases/jobs_2")?);
    out.push_str(&format!(
        "\nSweep of 400 cases (`sweep`): {} on one job ({} cases/s), {} on two ({} cases/s), a {:.1}× speed-up.\n",
        duration(one),
        grouped(400.0 / one),
        duration(two),
        grouped(400.0 / two),
        one / two
    ));
    let (interpreted, accelerated) =
        (m("fladrc_sweep_200_seeds/interpreted")?, m("fladrc_sweep_200_seeds/accelerated")?);
    out.push_str(&format!(
        "\nThe FLADRC scenario over 200 seeds on two jobs (`sweep`): {} interpreted, {} accelerated, a {:.2}× speed-up.\n",
        duration(interpreted),
        duration(accelerated),
        interpreted / accelerated
    ));
    Ok(out)
}
