//! The README's performance tables come from `examples/perf_table.rs`:
//! it must read criterion's medians and divide them as the table says.

#[allow(dead_code)]
#[path = "../examples/perf_table.rs"]
mod perf_table;

use std::path::Path;

fn write_median(root: &Path, id: &str, ns: f64) {
    let dir = root.join(id).join("new");
    std::fs::create_dir_all(&dir).unwrap();
    let estimates = format!(r#"{{"mean":{{"point_estimate":1.0}},"median":{{"point_estimate":{ns}}}}}"#);
    std::fs::write(dir.join("estimates.json"), estimates).unwrap();
}

#[test]
fn tables_divide_the_medians_as_they_say() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    let ms = 1e6;
    for (id, ns) in [
        ("fladrc_scenario_20k_samples/fladrc_hand_written", 5.0 * ms),
        ("fladrc_scenario_20k_samples/fladrc_ctlgraph", 10.0 * ms),
        ("fladrc_scenario_20k_samples/ladrc_hand_written", 0.3 * ms),
        ("fladrc_scenario_20k_samples/ladrc_ctlgraph", 3.0 * ms),
        ("pid_loop_10k_rk4_steps/hand_written", 0.5 * ms),
        ("pid_loop_10k_rk4_steps/ctlgraph", 1.5 * ms),
        ("fladrc_scenario_20k_samples/ladrc_fused_blocks", 0.6 * ms),
        ("pid_loop_10k_rk4_steps/fused_blocks", 1.0 * ms),
        ("fladrc_scenario_20k_samples/fladrc_compiled", 6.0 * ms),
        ("fladrc_scenario_20k_samples/ladrc_compiled", 0.9 * ms),
        ("pid_loop_10k_rk4_steps/compiled", 1.25 * ms),
        ("fladrc_scenario_20k_samples/fladrc_accelerated", 4.0 * ms),
        ("fladrc_scenario_20k_samples/ladrc_accelerated", 0.45 * ms),
        ("pid_loop_10k_rk4_steps/accelerated", 0.6 * ms),
        ("fladrc_sweep_200_seeds/interpreted", 2000.0 * ms),
        ("fladrc_sweep_200_seeds/accelerated", 1600.0 * ms),
        ("fuzzy_7x7_two_outputs/hand_written", 300.0),
        ("fuzzy_7x7_two_outputs/ctlgraph_fis", 150.0),
        ("chain_compile/10", 0.2 * ms),
        ("chain_compile/1000", 20.0 * ms),
        ("chain_compile/100000", 2000.0 * ms),
        ("fan_out_compile/10", 0.3 * ms),
        ("fan_out_compile/1000", 30.0 * ms),
        ("fan_out_compile/100000", 3000.0 * ms),
        ("chain_100_steps/0", 0.01 * ms),
        ("chain_100_steps/10", 0.05 * ms),
        ("chain_100_steps/1000", 5.0 * ms),
        ("chain_100_steps/100000", 1000.0 * ms),
        ("chain_by_hand_100_steps/0", 0.001 * ms),
        ("chain_by_hand_100_steps/10", 0.004 * ms),
        ("chain_by_hand_100_steps/1000", 0.35 * ms),
        ("chain_by_hand_100_steps/100000", 30.0 * ms),
        ("pid_loop_sweep_400_cases/jobs_1", 200.0 * ms),
        ("pid_loop_sweep_400_cases/jobs_2", 100.0 * ms),
    ] {
        write_median(root, id, ns);
    }
    for (id, ratio) in [
        ("fladrc_scenario_20k_samples/fladrc_ctlgraph", 1.5),
        ("fladrc_scenario_20k_samples/ladrc_ctlgraph", 8.0),
        ("fladrc_scenario_20k_samples/ladrc_fused_blocks", 2.5),
        ("pid_loop_10k_rk4_steps/ctlgraph", 3.25),
        ("pid_loop_10k_rk4_steps/fused_blocks", 2.25),
        ("fladrc_scenario_20k_samples/fladrc_compiled", 1.25),
        ("fladrc_scenario_20k_samples/ladrc_compiled", 3.5),
        ("pid_loop_10k_rk4_steps/compiled", 2.75),
        ("fladrc_scenario_20k_samples/fladrc_accelerated", 0.75),
        ("fladrc_scenario_20k_samples/ladrc_accelerated", 1.4),
        ("pid_loop_10k_rk4_steps/accelerated", 1.1),
    ] {
        let json = format!(r#"{{"median_ratio":{ratio},"samples":30,"reference":"x"}}"#);
        std::fs::write(root.join(id).join("paired_ratio.json"), json).unwrap();
    }
    let text = perf_table::tables(root).unwrap();
    // 10 ms over 20 001 samples is 500 ns a sample; twice the hand-written
    // (the ratio of the medians), then the paired benchmark's own ratio.
    assert!(text.contains("| 5.00 ms (250 ns/sample) | 10.0 ms (500 ns/sample) | 2.00× | 1.50× |"), "{text}");
    assert!(text.contains("| 300 µs (15.0 ns/sample) | 3.00 ms (150 ns/sample) | 10.00× | 8.00× |"), "{text}");
    assert!(text.contains("| 500 µs (50.0 ns/step) | 1.50 ms (150 ns/step) | 3.00× | 3.25× |"), "{text}");
    assert!(text.contains("| 300 ns | 150 ns | 0.50× | — |"), "{text}");
    let fused = "| LADRC paper (`fladrc`) | 300 µs (15.0 ns/sample) | 600 µs (30.0 ns/sample) | 2.00× | 2.50× |";
    assert!(text.contains(fused), "{text}");
    assert!(text.contains("| 500 µs (50.0 ns/step) | 1.00 ms (100 ns/step) | 2.00× | 2.25× |"), "{text}");
    // The generated steps' table: each beside its own hand-written loop.
    let generated = "| FLADRC paper (`fladrc`) | 5.00 ms (250 ns/sample) | 6.00 ms (300 ns/sample) | 1.20× | 1.25× |";
    assert!(text.contains(generated), "{text}");
    assert!(text.contains("| 300 µs (15.0 ns/sample) | 900 µs (45.0 ns/sample) | 3.00× | 3.50× |"), "{text}");
    assert!(text.contains("| 500 µs (50.0 ns/step) | 1.25 ms (125 ns/step) | 2.50× | 2.75× |"), "{text}");
    // The accelerated runs' table, likewise.
    let accelerated = "| FLADRC paper (`fladrc`) | 5.00 ms (250 ns/sample) | 4.00 ms (200 ns/sample) | 0.80× | 0.75× |";
    assert!(text.contains("| accelerated (`--accelerate`) | hand-written |"), "{text}");
    assert!(text.contains(accelerated), "{text}");
    assert!(text.contains("| 300 µs (15.0 ns/sample) | 450 µs (22.5 ns/sample) | 1.50× | 1.40× |"), "{text}");
    assert!(text.contains("| 500 µs (50.0 ns/step) | 600 µs (60.0 ns/step) | 1.20× | 1.10× |"), "{text}");
    assert!(
        text.contains(
            "over 200 seeds on two jobs (`sweep`): 2.00 s interpreted, 1.60 s accelerated, a 1.25× speed-up."
        ),
        "{text}"
    );
    // 1 s for 100 steps of 100 000 blocks: 100 ns a block-step; by hand
    // 30 ms: 3 ns. Past the fixed part (the chain of none: 100 ns a step,
    // by hand 10 ns), at 10 gains: (500 − 100)/10 and (40 − 10)/10.
    assert!(text.contains("| 100 000 | 2.00 s | 3.00 s | 100 | 3.0 | 100.0 | 3.0 |"), "{text}");
    assert!(text.contains("| 1 000 | 20.0 ms | 30.0 ms | 50 | 3.5 | 49.9 | 3.5 |"), "{text}");
    assert!(text.contains("| 10 | 200 µs | 300 µs | 50 | 4.0 | 40.0 | 3.0 |"), "{text}");
    assert!(text.contains("the sine into the integrator): 100 ns, by hand 10 ns."), "{text}");
    assert!(
        text.contains("200 ms on one job (2 000 cases/s), 100 ms on two (4 000 cases/s), a 2.0× speed-up"),
        "{text}"
    );
    // A bench not run yet is named, with what to do.
    std::fs::remove_dir_all(root.join("pid_loop_sweep_400_cases")).unwrap();
    let err = perf_table::tables(root).unwrap_err();
    assert!(err.contains("pid_loop_sweep_400_cases/jobs_1") && err.contains("run the benches first"), "{err}");
}
