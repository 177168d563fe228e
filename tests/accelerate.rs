//! `--accelerate` as a user runs it: the generated step built by the real
//! cargo into a cache, loaded and run, giving the interpreter's CSV byte
//! for byte; the cache reused without a toolchain; the fallback and its
//! one line; `require` failing with exit code 2.
//!
//! The cache lives under the test's target folder, so a second `cargo
//! test` reuses it; a clean one (CI) builds ctlgraph's crates into it once
//! (34 s on two cores, and 85 s more with the implicit method for the
//! stiff graph) and each graph in about a second.

mod common;
use common::{accelerate_cache as cache, text};
use std::path::Path;
use std::process::{Command, Output};

/// `ctlgraph ARGS` in the workspace with the given cache and PATH.
fn ctlgraph(args: &[&str], cache: &Path, path: Option<&str>) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_ctlgraph"));
    cmd.args(args).current_dir(env!("CARGO_MANIFEST_DIR")).env("CTLGRAPH_CACHE_DIR", cache).env("CI", "1");
    if let Some(p) = path {
        cmd.env("PATH", p);
    }
    cmd.output().unwrap()
}

/// Runs `graph` interpreted and accelerated (required) and returns both
/// CSVs and the accelerated run's summary.
fn both_ways(graph: &str, dir: &Path) -> (Vec<u8>, Vec<u8>, String) {
    let name = graph.replace('/', "_");
    let (interpreted, accelerated) = (dir.join(format!("{name}.i.csv")), dir.join(format!("{name}.a.csv")));
    let out = ctlgraph(&["run", graph, "--out", interpreted.to_str().unwrap()], &cache(), None);
    assert!(out.status.success(), "{graph}: {}", text(&out.stderr));
    let out = ctlgraph(&["run", graph, "--accelerate=require", "--out", accelerated.to_str().unwrap()], &cache(), None);
    assert!(out.status.success(), "{graph} accelerated: {}", text(&out.stderr));
    (std::fs::read(interpreted).unwrap(), std::fs::read(accelerated).unwrap(), text(&out.stdout))
}

#[test]
fn accelerated_runs_write_the_interpreters_csv_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    // Fixed-step with sample clocks and noise; adaptive; stiff (TR-BDF2);
    // a transport delay under an adaptive method (history, breakpoints);
    // located events (impacts, a relay's switching); rows between steps
    // from dopri5's continuous extension; top-level inports (at the values
    // the graph gives them).
    for graph in [
        "graphs/fladrc/ladrc.yaml",
        "graphs/tutorial/pid_loop.yaml",
        "graphs/stiff/van_der_pol.yaml",
        "graphs/events/dead_time_pi.yaml",
        "graphs/events/bouncing_ball.yaml",
        "graphs/events/thermostat.yaml",
        "graphs/events/antiwindup_dead_time.yaml",
        "graphs/tutorial/controller_io.yaml",
    ] {
        let (interpreted, accelerated, summary) = both_ways(graph, dir.path());
        assert!(interpreted.len() > 1000, "{graph}: a CSV of {} bytes", interpreted.len());
        assert!(interpreted == accelerated, "{graph}: the accelerated CSV differs from the interpreted one");
        assert!(summary.contains(", accelerated (step "), "{graph}: {summary}");
    }
}

#[test]
fn a_cached_step_loads_without_a_toolchain_and_serves_other_parameter_values() {
    let dir = tempfile::tempdir().unwrap();
    let graph = "graphs/tutorial/first_order.yaml";
    let out = ctlgraph(&["run", graph, "--accelerate=require"], &cache(), None);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // With no cargo to call, the run can only be accelerated from the cache;
    // `--set` changes values, not the structure, so the same step serves it.
    let csv = dir.path().join("tau.csv");
    let args = ["run", graph, "--accelerate=require", "--set", "tau=0.25", "--out", csv.to_str().unwrap()];
    let out = ctlgraph(&args, &cache(), Some("/nonexistent"));
    let summary = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(summary.contains("accelerated (step loaded from the cache in "), "{summary}");
    let interpreted = dir.path().join("tau.i.csv");
    let out = ctlgraph(&["run", graph, "--set", "tau=0.25", "--out", interpreted.to_str().unwrap()], &cache(), None);
    assert!(out.status.success());
    assert_eq!(std::fs::read(csv).unwrap(), std::fs::read(interpreted).unwrap());
}

#[test]
fn without_a_toolchain_the_run_is_interpreted_and_says_why_in_one_line() {
    let empty = tempfile::tempdir().unwrap();
    let graph = "graphs/fladrc/ladrc.yaml";
    let out = ctlgraph(&["run", graph, "--accelerate"], empty.path(), Some("/nonexistent"));
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stderr),
        "note: running interpreted, not accelerated: no Rust toolchain: `cargo` is not on PATH\n"
    );
    assert!(!text(&out.stdout).contains("accelerated"));
    let out = ctlgraph(&["run", graph, "--accelerate=require"], empty.path(), Some("/nonexistent"));
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("--accelerate=require: cannot accelerate: no Rust toolchain"));
}

#[test]
fn an_accelerated_sweep_tabulates_what_the_interpreted_one_does_with_one_build() {
    let dir = tempfile::tempdir().unwrap();
    let graph = "graphs/tutorial/pid_loop.yaml";
    let table = |name: &str, accelerate: &str| {
        let out = dir.path().join(name);
        let args =
            ["sweep", graph, "--vary", "kp=1..4:3", "--vary", "kd=0,0.1", "--out", out.to_str().unwrap(), accelerate];
        let done = ctlgraph(&args, &cache(), None);
        assert!(done.status.success(), "{}", text(&done.stderr));
        (std::fs::read(out).unwrap(), text(&done.stdout))
    };
    let (interpreted, _) = table("i.csv", "--accelerate=off");
    let (accelerated, summary) = table("a.csv", "--accelerate=require");
    assert_eq!(interpreted, accelerated);
    // One library for the six cases: one line for it.
    assert_eq!(summary.matches("accelerated (step ").count(), 1, "{summary}");
}

#[test]
fn the_graph_file_can_ask_for_acceleration_and_the_report_records_it() {
    let dir = tempfile::tempdir().unwrap();
    // The tutorial's first graph with `accelerate: require` added: its
    // structure is the graph's, so its step is the one cached for it.
    let source =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("graphs/tutorial/first_order.yaml"))
            .unwrap();
    let edited = source.replacen("simulation:\n", "simulation:\n  accelerate: require\n", 1);
    assert_ne!(edited, source);
    let graph = dir.path().join("first_order.yaml");
    std::fs::write(&graph, edited).unwrap();
    let report = dir.path().join("report.json");
    let warm = ctlgraph(&["run", graph.to_str().unwrap()], &cache(), None);
    assert!(warm.status.success(), "{}", text(&warm.stderr));
    let out = ctlgraph(&["run", graph.to_str().unwrap(), "--report", report.to_str().unwrap()], &cache(), None);
    assert!(text(&out.stdout).contains("accelerated (step loaded from the cache in "));
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(json["acceleration"]["step"], "loaded");
    assert!(json["acceleration"]["seconds"].as_f64().unwrap() > 0.0);
    // The flag overrides the file.
    let out = ctlgraph(&["run", graph.to_str().unwrap(), "--accelerate=off"], &cache(), None);
    assert!(!text(&out.stdout).contains("accelerated"));
    // `ctlgraph test` says how each graph ran.
    let out = ctlgraph(
        &["test", "graphs/tutorial/pid_loop.yaml", "graphs/events/antiwindup_dead_time.yaml", "--accelerate"],
        &cache(),
        None,
    );
    let listing = text(&out.stdout);
    assert!(listing.contains("graphs/tutorial/pid_loop.yaml\n  accelerated (step "), "{listing}");
    assert!(listing.contains("graphs/events/antiwindup_dead_time.yaml\n  accelerated (step "), "{listing}");
    // Without a toolchain and with an empty cache, each graph says why it ran interpreted.
    let empty = tempfile::tempdir().unwrap();
    let out = ctlgraph(&["test", "graphs/tutorial/pid_loop.yaml", "--accelerate"], empty.path(), Some("/nonexistent"));
    let listing = text(&out.stdout);
    assert!(
        listing.contains("pid_loop.yaml\n  note: running interpreted, not accelerated: no Rust toolchain"),
        "{listing}"
    );
}
