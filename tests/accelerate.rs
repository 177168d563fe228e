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
use ctlgraph::accel::{Accelerate, Runner, Stepper};
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

/// What `ctlgraph run GRAPH ARGS… ACCELERATE --out DIR/NAME` gives: its
/// exit code, stdout, stderr and the CSV it wrote.
struct Ran {
    code: Option<i32>,
    stdout: String,
    stderr: String,
    csv: Vec<u8>,
}

fn run_csv(graph: &str, args: &[&str], accelerate: &str, dir: &Path, name: &str) -> Ran {
    let csv = dir.join(name);
    let mut all = vec!["run", graph];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", csv.to_str().unwrap(), accelerate]);
    let out = ctlgraph(&all, &cache(), None);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    Ran { code: out.status.code(), stdout, stderr, csv: std::fs::read(csv).unwrap_or_default() }
}

/// Runs `graph` interpreted and accelerated (required) and returns both
/// CSVs and the accelerated run's summary. What the two print after the
/// summary — the checks, measured on the trace each kept — is the same.
fn both_ways(graph: &str, dir: &Path) -> (Vec<u8>, Vec<u8>, String) {
    let name = graph.replace('/', "_");
    let interpreted = run_csv(graph, &[], "--accelerate=off", dir, &format!("{name}.i.csv"));
    assert_eq!(interpreted.code, Some(0), "{graph}: {}", interpreted.stderr);
    let accelerated = run_csv(graph, &[], "--accelerate=require", dir, &format!("{name}.a.csv"));
    assert_eq!(accelerated.code, Some(0), "{graph} accelerated: {}", accelerated.stderr);
    let after_summary = |out: &str| out.lines().skip(1).map(str::to_string).collect::<Vec<_>>();
    assert_eq!(after_summary(&interpreted.stdout), after_summary(&accelerated.stdout), "{graph}: the checks");
    (interpreted.csv, accelerated.csv, accelerated.stdout)
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

/// Runs of one graph in one process: the library builds the second and
/// later ones on the structure of the graph it compiled first (other
/// values, other seeds), and a graph whose own values do not compile —
/// an override makes it valid — case by case from its text. Each run's
/// trace is the interpreter's, to the bit.
#[test]
fn runs_after_the_first_are_built_on_the_kept_structure_and_equal_the_interpreters() {
    cache_in_process();
    const GRAPH: &str = "name: kept structure
parameters: { z: 2.0, w: 3.0 }
simulation: { stop: 0.5, seed: 4, solver: { method: rk4, step: 0.001 } }
blocks:
  wave:  { type: sine, frequency: w }
  noise: { type: uniform_noise, sample_time: 0.01 }
  k:     { type: gain, k: 1/z }
  sum:   { type: sum, signs: \"++\" }
  f:     { type: fcn, expr: \"z*u^2 - w\" }
  x:     { type: integrator }
wires:
  - wave -> sum.u1
  - noise -> sum.u2
  - sum -> k
  - k -> f
  - f -> x
record: [sum, k, f, x]
";
    let file = Path::new("kept_structure.yaml");
    let sets = |pairs: &[(&str, &str)]| -> Vec<(String, String)> {
        pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
    };
    let same = |text: &str, runner: &Runner, pairs: &[(&str, &str)], seed: Option<u64>| {
        let sets = sets(pairs);
        let model = || ctlgraph::compile_str(text, file.to_str().unwrap(), &sets).unwrap();
        let mut seeded = model();
        if let Some(s) = seed {
            seeded =
                ctlgraph::compile_str(&text.replace("seed: 4", &format!("seed: {s}")), file.to_str().unwrap(), &sets)
                    .unwrap();
        }
        let (fast, _) = runner.simulate(model(), &sets, seed, None).unwrap();
        let (slow, _) = ctlgraph_core::trace::simulate_with_stats(seeded, None).unwrap();
        let bits = |t: &ctlgraph::record::Trace| {
            t.columns.iter().flat_map(|c| c.iter().map(|v| v.to_bits())).collect::<Vec<_>>()
        };
        assert!(slow.t().len() > 400, "{pairs:?}: the whole run");
        assert_eq!(bits(&fast), bits(&slow), "{pairs:?}, seed {seed:?}");
    };
    let model = ctlgraph::compile_str(GRAPH, file.to_str().unwrap(), &[]).unwrap();
    let (runner, _) = Runner::choose(Accelerate::Require, &model, file, GRAPH).unwrap();
    same(GRAPH, &runner, &[], None);
    same(GRAPH, &runner, &[("z", "5"), ("w", "7.5")], None);
    same(GRAPH, &runner, &[("z", "0.5")], Some(11));
    same(GRAPH, &runner, &[], None);
    // z = 0 makes the gain infinite: the graph compiles only with an override.
    let broken = GRAPH.replace("z: 2.0", "z: 0.0");
    assert!(ctlgraph::compile_str(&broken, file.to_str().unwrap(), &[]).is_err());
    let model = ctlgraph::compile_str(&broken, file.to_str().unwrap(), &sets(&[("z", "2")])).unwrap();
    let (runner, _) = Runner::choose(Accelerate::Require, &model, file, &broken).unwrap();
    same(&broken, &runner, &[("z", "2")], None);
    same(&broken, &runner, &[("z", "3"), ("w", "1")], None);
}

/// Points this process's accelerated runs at the tests' cache. Every test
/// here uses that one cache (the subprocesses are told it explicitly), and
/// std orders `set_var` with its own reads of the environment.
fn cache_in_process() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    // SAFETY: no C code of this test process reads the environment
    // concurrently; std's reads take the same lock as `set_var`.
    ONCE.call_once(|| unsafe { std::env::set_var("CTLGRAPH_CACHE_DIR", cache()) });
}

/// The graph `text` (at `file`) stepped by both back-ends.
fn steppers(file: &Path, text: &str) -> (Stepper, Stepper) {
    cache_in_process();
    let compile = || ctlgraph::compile_str(text, file.to_str().unwrap(), &[]).unwrap();
    let (runner, note) = Runner::choose(Accelerate::Require, &compile(), file, text).unwrap();
    assert!(note.is_none() && runner.cost().is_some());
    let fast = Stepper::new(&runner, compile(), &[], None).unwrap();
    let slow = Stepper::new(&Runner::Interpreted, compile(), &[], None).unwrap();
    assert!(fast.accelerated() && !slow.accelerated());
    (fast, slow)
}

/// Every recorded signal and output of both, equal to the bit.
fn same_signals(fast: &mut Stepper, slow: &mut Stepper, at: &str) {
    let names: Vec<String> = slow.model().columns.iter().map(|c| c.name.clone()).collect();
    let outputs: Vec<String> = slow.model().output_names().map(str::to_string).collect();
    for name in names.iter().chain(&outputs) {
        let (a, b) = (fast.signal(name).unwrap().to_vec(), slow.signal(name).unwrap().to_vec());
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a), bits(&b), "{at}: `{name}` accelerated {a:?}, interpreted {b:?}");
    }
    assert_eq!(fast.time().to_bits(), slow.time().to_bits(), "{at}");
}

/// A host's session: inputs set between steps, a snapshot taken halfway
/// and restored at the end, the second half stepped again.
fn host_session(graph: &str, text: &str, input: &str, width: usize, dt: f64, steps: usize) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join(graph);
    std::fs::write(&file, text).unwrap();
    let (mut fast, mut slow) = steppers(&file, text);
    let mut saved = None;
    let mut second_half = Vec::new();
    for k in 1..=steps {
        let value: Vec<f64> = (0..width).map(|i| (0.37 * k as f64 + i as f64).sin()).collect();
        for s in [&mut fast, &mut slow] {
            s.set_input(input, &value).unwrap();
        }
        same_signals(&mut fast, &mut slow, &format!("{graph}: input set at step {k}"));
        for s in [&mut fast, &mut slow] {
            s.advance_to(k as f64 * dt).unwrap();
        }
        same_signals(&mut fast, &mut slow, &format!("{graph}: t = {}", k as f64 * dt));
        if k == steps / 2 {
            saved = Some((fast.state().unwrap(), slow.state().unwrap()));
        }
        if k > steps / 2 {
            second_half.push(fast.output(slow.model().output_names().next().unwrap()).unwrap().to_vec());
        }
    }
    let (fast_saved, slow_saved) = saved.unwrap();
    fast.restore(&fast_saved).unwrap();
    slow.restore(&slow_saved).unwrap();
    assert_eq!(fast.time(), (steps / 2) as f64 * dt);
    let output = slow.model().output_names().next().unwrap().to_string();
    for (k, before) in (steps / 2 + 1..=steps).zip(&second_half) {
        let value: Vec<f64> = (0..width).map(|i| (0.37 * k as f64 + i as f64).sin()).collect();
        fast.set_input(input, &value).unwrap();
        fast.advance_to(k as f64 * dt).unwrap();
        assert_eq!(fast.output(&output).unwrap(), &before[..], "{graph}: restored, step {k}");
    }
    // A snapshot of one back-end is not the other's, and mistakes are named alike.
    assert!(fast.restore(&slow_saved).unwrap_err().to_string().contains("another run"));
    let (a, b) = (fast.set_input("nope", &[1.0]).unwrap_err(), slow.set_input("nope", &[1.0]).unwrap_err());
    assert_eq!(a.to_string(), b.to_string());
    assert!(fast.advance_to(0.0).is_err() && slow.advance_to(0.0).is_err());
}

#[test]
fn accelerated_stepping_is_the_interpreters_bit_for_bit() {
    let read = |p: &str| std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(p)).unwrap();
    // Adaptive (dopri5) with an input in a nonlinear equation; a vector input.
    host_session("van_der_pol.yaml", &read("graphs/fmu/van_der_pol.yaml"), "u", 1, 0.05, 60);
    host_session("plant_io.yaml", &read("tests/fmu/plant_io.yaml"), "u", 2, 0.01, 60);
    // An input into a transport delay (history and its left limits, which
    // setting an input hands over) under an adaptive method, off its grid.
    let delayed = "simulation: { stop: 1, solver: { method: dopri5, rtol: 1.0e-9 } }\n\
                   blocks:\n  u: { type: inport }\n  d: { type: transport_delay, delay: 0.013 }\n  \
                   x: { type: integrator }\n  y: { type: outport }\n\
                   wires: [u -> d, d -> x, x -> y]\nrecord: [d, x]\n";
    host_session("delayed.yaml", delayed, "u", 1, 0.0071, 90);
}

#[test]
fn a_step_budget_cuts_an_accelerated_run_where_it_cuts_the_interpreted_one() {
    // The library records the rows and counts the steps itself; the cut,
    // the outputs kept and the message are the interpreter's.
    let dir = tempfile::tempdir().unwrap();
    let graph = "graphs/tutorial/controller_io.yaml";
    let cut = |name: &str, accelerate: &str| {
        let ran = run_csv(graph, &["--max-steps", "1234"], accelerate, dir.path(), name);
        (ran.code, ran.stderr, ran.csv)
    };
    let (interpreted, accelerated) = (cut("i.csv", "--accelerate=off"), cut("a.csv", "--accelerate=require"));
    assert_eq!(interpreted.0, Some(1));
    assert!(interpreted.1.contains("--max-steps 1234 reached"), "{}", interpreted.1);
    assert_eq!(interpreted.2.iter().filter(|&&b| b == b'\n').count(), 1 + 1235);
    assert_eq!(interpreted, accelerated);
}

#[test]
fn decimated_rows_end_at_the_stop_time_in_the_library_too() {
    // `record: { every: 4 }`, stopped between two logged steps: the last
    // step is a row of its own, recorded in the library as in the program.
    let dir = tempfile::tempdir().unwrap();
    let graph = "graphs/mirror-milling/compensation.yaml";
    let csv = |name: &str, accelerate: &str| {
        let ran = run_csv(graph, &["--stop-time", "0.0107"], accelerate, dir.path(), name);
        assert_eq!(ran.code, Some(0), "{}", ran.stderr);
        String::from_utf8(ran.csv).unwrap()
    };
    let (interpreted, accelerated) = (csv("i.csv", "--accelerate=off"), csv("a.csv", "--accelerate=require"));
    assert_eq!(interpreted, accelerated);
    let times: Vec<&str> = interpreted.lines().skip(1).map(|l| l.split(',').next().unwrap()).collect();
    assert_eq!(times.first(), Some(&"0"));
    assert_eq!(times.last(), Some(&"0.0107"));
    assert_eq!(times.len(), 1 + 22 / 4 + 1, "{times:?}");
}
