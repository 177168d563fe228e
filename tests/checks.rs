//! Graphs that test themselves: `checks:`, `ctlgraph test`, `ctlgraph prop`.

mod common;
use common::{ctlgraph, text};
use std::path::Path;

/// A first-order lag with gain `k`: y settles at k.
const LAG: &str = "parameters:\n  k: 0.5\n  tau: 0.2\n\
                   simulation: { stop: 10.0, solver: { method: rk4, step: 2.0e-3 } }\n\
                   blocks:\n  u: { type: step }\n  g: { type: transfer_function, num: [k], den: [tau, 1] }\n\
                   wires: [u -> g]\nrecord: [y: g]\n";

fn write_graph(dir: &Path, name: &str, checks: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, format!("{LAG}checks:\n{checks}")).unwrap();
    path.display().to_string()
}

#[test]
fn every_bundled_graph_passes_its_checks() {
    // graphs/fmu/loop.yaml runs the Van der Pol plant as an FMU: exported here.
    let out = ctlgraph(&["fmu", "graphs/fmu/van_der_pol.yaml", "--out", "graphs/fmu/van_der_pol.fmu"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = ctlgraph(&["test", "graphs"]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", text(&out.stderr));
    assert!(stdout.contains("graphs/tutorial/pid_loop.yaml") && stdout.contains(" 0 failed"), "{stdout}");
    assert!(stdout.contains("graphs/fmu/loop.yaml"), "{stdout}");
    assert!(!stdout.contains("lib/pi_controller.yaml"), "subsystem files without checks are skipped");
}

#[test]
fn a_failing_check_fails_the_run_and_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let good = write_graph(dir.path(), "good.yaml", "  - \"abs(final_value(y) - k) < 1.0e-3\"\n");
    let bad =
        write_graph(dir.path(), "bad.yaml", "  - too_slow: \"settling_time(y, k, 0.02) < 0.1\"\n  - \"max(y) < 1\"\n");
    let out = ctlgraph(&["test", dir.path().to_str().unwrap()]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    // 0.2·ln 50 = 0.782 s.
    assert!(stdout.contains("FAIL  too_slow  (measured 0.78240"), "{stdout}");
    assert!(stdout.contains("pass  max(y) < 1"), "{stdout}");
    assert!(stdout.contains("2 graph(s), 3 check(s): 2 passed, 1 failed"), "{stdout}");
    // `run` reports checks too, and a failed check is exit code 1.
    let out = ctlgraph(&["run", &bad]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stdout).contains("FAIL  too_slow"));
    assert!(text(&out.stderr).contains("1 of 2 checks failed"));
    assert_eq!(ctlgraph(&["run", &good]).status.code(), Some(0));
}

#[test]
fn check_errors_are_positioned_and_invalid_graphs_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let bad = write_graph(dir.path(), "typo.yaml", "  - \"peak(yy) < 1\"\n");
    let out = ctlgraph(&["test", &bad]);
    assert_eq!(out.status.code(), Some(2));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("typo.yaml:11:11: check: `peak` takes a recorded signal first: `yy` is not a recorded signal"),
        "{stdout}"
    );
    assert!(stdout.contains("did you mean `y`?"), "{stdout}");
    assert_eq!(ctlgraph(&["test", "no/such/folder"]).status.code(), Some(2));
}

#[test]
fn prop_shrinks_a_planted_failure_to_its_threshold() {
    // final_value(y) = k fails for k >= 0.9; the graph's own k is 0.5. The
    // shrunk counterexample must sit just above the threshold.
    let dir = tempfile::tempdir().unwrap();
    let graph = write_graph(dir.path(), "planted.yaml", "  - \"final_value(y) < 0.9\"\n");
    let out = ctlgraph(&["prop", &graph, "--vary", "k=0..3", "--vary", "tau=0.05..0.3", "--cases", "32"]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    let k: f64 = stdout
        .lines()
        .find_map(|l| l.trim().strip_prefix("k = "))
        .unwrap_or_else(|| panic!("no k in {stdout}"))
        .parse()
        .unwrap();
    assert!((0.9..0.91).contains(&k), "minimal k = {k}\n{stdout}");
    // tau does not matter: shrunk back to the graph's own value.
    assert!(stdout.contains("tau = 0.2\n"), "{stdout}");
    assert!(stdout.contains(&format!("reproduce: ctlgraph run {graph} --set k=")), "{stdout}");

    // Within the safe range the property holds.
    let out = ctlgraph(&["prop", &graph, "--vary", "k=0..0.85", "--cases", "16", "--seed", "3"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stdout));
    assert!(text(&out.stdout).contains("checks hold in 16 cases for k in [0, 0.85]"));
    // Unknown parameters are input errors.
    let out = ctlgraph(&["prop", &graph, "--vary", "kk=0..1"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("did you mean `k`?"));
}

#[test]
fn prop_is_reproducible_for_a_seed() {
    let dir = tempfile::tempdir().unwrap();
    let graph = write_graph(dir.path(), "planted.yaml", "  - \"final_value(y) < 0.9\"\n");
    let run = || text(&ctlgraph(&["prop", &graph, "--vary", "k=0..3", "--cases", "8", "--seed", "11"]).stdout);
    assert_eq!(run(), run());
}
