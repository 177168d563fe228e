//! Runs that end early — a numeric fault, a step-size collapse, Ctrl-C, a
//! step or wall-time budget — and output into closed pipes: each ends with
//! its exit code, a message naming what went wrong, and whole output files
//! holding what was simulated.

mod common;
use common::{ctlgraph, path, text};
use std::path::Path;
use std::process::{Command, Stdio};

/// The CSV's times (first column), header skipped.
fn csv_times(csv: &Path) -> Vec<f64> {
    let body = std::fs::read_to_string(csv).unwrap();
    body.lines().skip(1).map(|l| l.split(',').next().unwrap().parse().unwrap()).collect()
}

fn report_field(report: &Path, key: &str) -> serde_json::Value {
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(report).unwrap()).unwrap();
    json[key].clone()
}

#[test]
fn a_blow_up_names_block_port_time_and_inputs_and_keeps_the_run_up_to_it() {
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("nan.yaml");
    std::fs::write(
        &graph,
        "simulation: { stop: 1, solver: { method: rk4, step: 0.1 } }\nblocks:\n  one: { type: constant }\n  \
         shifted: { type: fcn, inputs: 0, expr: \"t - 0.5\" }\n  d: { type: divide }\n\
         wires: [one -> d.u1, shifted -> d.u2]\n",
    )
    .unwrap();
    let (csv, report) = (dir.path().join("y.csv"), dir.path().join("y.json"));
    let out = ctlgraph(&["run", path(&graph), "--out", path(&csv), "--report", path(&report)]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stderr).trim(),
        "error: t = 0.5: block `d`: output `y` is inf (inputs: u1 = 1, u2 = 0); the outputs hold the run to t = 0.4"
    );
    assert_eq!(csv_times(&csv), [0.0, 0.1, 0.2, 0.3, 0.4], "every finite step, in a whole file");
    assert_eq!(report_field(&report, "status"), "failed");
    let leftovers = std::fs::read_dir(dir.path())
        .unwrap()
        .filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().starts_with('.'))
        .count();
    assert_eq!(leftovers, 0, "no temporaries");
}

#[test]
fn a_blow_up_inside_an_adaptive_step_names_the_block() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("blow.yaml");
    std::fs::write(
        &g,
        "simulation: { stop: 2.0, solver: { method: dopri5, initial_step: 1.0e-3 } }\n\
         blocks:\n  x: { type: integrator, initial: 1e150 }\n  sq: { type: fcn, expr: \"u^2\" }\nwires: [x -> sq, sq -> x]\n",
    )
    .unwrap();
    let out = ctlgraph(&["run", path(&g)]);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(err.contains("block `x`: state 0 (inside the solver's step) is NaN (inputs: u = "), "{err}");
}

#[test]
fn a_collapsing_step_names_the_state_that_forced_it() {
    // x' = x² from 1 reaches infinity at t = 1; a calm first-order state
    // beside it must not be blamed.
    let dir = tempfile::tempdir().unwrap();
    for method in ["dopri5", "trbdf2"] {
        let g = dir.path().join(format!("{method}.yaml"));
        std::fs::write(
            &g,
            format!(
                "simulation: {{ stop: 2, solver: {{ method: {method} }} }}\nblocks:\n  calm: {{ type: integrator, initial: 1 }}\n  \
                 minus: {{ type: gain, k: -1 }}\n  x: {{ type: integrator, initial: 1 }}\n  sq: {{ type: fcn, expr: \"u^2\" }}\n\
                 wires: [calm -> minus, minus -> calm, x -> sq, sq -> x]\n"
            ),
        )
        .unwrap();
        let out = ctlgraph(&["run", path(&g)]);
        assert_eq!(out.status.code(), Some(1), "{method}");
        let err = text(&out.stderr);
        assert!(err.contains("too small at t = 0.99") || err.contains("too small at t = 1.00"), "{method}: {err}");
        assert!(err.ends_with("the step is forced down by block `x` (state 0)\n"), "{method}: {err}");
    }
}

/// A run of the FLADRC comparison long enough never to finish in a test.
fn long_run(dir: &Path, extra: &[&str]) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_ctlgraph"));
    let (csv, report) = (dir.join("long.csv"), dir.join("long.json"));
    cmd.args([
        "run",
        "graphs/fladrc/compare.yaml",
        "--stop-time",
        "500",
        "--out",
        path(&csv),
        "--report",
        path(&report),
    ])
    .args(extra)
    .env("CI", "1")
    .stdout(Stdio::piped())
    .stderr(Stdio::piped());
    cmd
}

#[test]
fn an_interrupted_run_writes_what_it_simulated_and_clears_stale_temporaries() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("long.csv");
    // A stale temporary of a process that no longer exists (pid beyond pid_max).
    let stale = dir.path().join(".long.csv.999999999.tmp");
    std::fs::write(&stale, "half").unwrap();
    for signal in ["-INT", "-TERM"] {
        let child = long_run(dir.path(), &[]).spawn().unwrap();
        let live = dir.path().join(format!(".long.csv.{}.tmp", child.id()));
        let start = std::time::Instant::now();
        while std::fs::metadata(&live).map_or(true, |m| m.len() < 10_000) && start.elapsed().as_secs() < 60 {
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        assert!(!stale.exists(), "the stale temporary was removed");
        Command::new("kill").args([signal, &child.id().to_string()]).status().unwrap();
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(130), "{signal}");
        let err = text(&out.stderr);
        assert!(err.contains("interrupted at t = ") && err.contains("the outputs hold the run to t = "), "{err}");
        let times = csv_times(&csv);
        let last = *times.last().unwrap();
        assert!(times.len() > 100 && last < 500.0, "{signal}: a whole CSV up to t = {last}");
        assert!(err.contains(&format!("the outputs hold the run to t = {last}")), "{err}");
        assert_eq!(report_field(&dir.path().join("long.json"), "status"), "interrupted");
        assert!(!live.exists(), "the temporary became the output");
    }
}

#[test]
fn step_and_wall_budgets_end_a_run_with_its_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let out = long_run(dir.path(), &["--max-steps", "1000"]).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(err.contains("error: stopped at t = 0.1 of 500 s: --max-steps 1000 reached"), "{err}");
    assert_eq!(csv_times(&dir.path().join("long.csv")).len(), 1001, "t = 0 and 1000 steps");
    assert_eq!(report_field(&dir.path().join("long.json"), "status"), "stopped");
    assert!(text(&out.stdout).contains("checks not evaluated: the run ended before its stop time"));

    let out = long_run(dir.path(), &["--max-wall", "0.2"]).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains(": --max-wall 0.2 s reached"), "{}", text(&out.stderr));
    let simulated = report_field(&dir.path().join("long.json"), "simulated_time").as_f64().unwrap();
    assert!(simulated > 0.0 && simulated < 500.0, "{simulated}");

    for bad in [["--max-steps", "0"], ["--max-wall", "-1"]] {
        assert_eq!(long_run(dir.path(), &bad).output().unwrap().status.code(), Some(2), "{bad:?}");
    }
}

#[test]
fn check_states_the_expected_steps_and_warns_of_a_long_run() {
    let out = ctlgraph(&["check", "graphs/fladrc/fladrc.yaml"]);
    assert!(text(&out.stdout).contains("\nabout 20000 major steps to the stop time\n"), "{}", text(&out.stdout));
    assert!(!text(&out.stdout).contains("warning"));
    let out = ctlgraph(&["check", "graphs/tutorial/multirate.yaml"]);
    // A floor: its clocks' hits coincide (1 kHz and 50 Hz), so the larger count, not their sum (2 300).
    assert!(text(&out.stdout).contains("\nat least 2000 major steps to the stop time\n"), "{}", text(&out.stdout));
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("year.yaml");
    std::fs::write(
        &g,
        "simulation: { stop: 3.2e6, solver: { method: rk4, step: 1.0e-3 } }\nblocks:\n  u: { type: step }\n",
    )
    .unwrap();
    let out = ctlgraph(&["check", path(&g)]);
    assert!(
        text(&out.stdout)
            .contains("warning: this run takes about 3200000000 major steps with 1 block (minutes or more)"),
        "{}",
        text(&out.stdout)
    );
}

/// Each subcommand, its stdout (or stderr) closed before it writes, ends
/// quietly: no panic, no backtrace — like cat or git, by SIGPIPE.
#[test]
fn output_into_a_closed_pipe_ends_quietly() {
    use std::os::unix::process::ExitStatusExt;
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("sweep.csv");
    let lag = "graphs/tutorial/first_order.yaml";
    let commands: Vec<Vec<&str>> = vec![
        vec!["run", lag],
        vec!["run", lag, "--out", "-"],
        vec!["check", lag],
        vec!["dot", lag],
        vec!["test", "graphs/tutorial"],
        vec!["blocks"],
        vec!["blocks", "pid"],
        vec!["blocks", "--markdown"],
        vec!["prop", "graphs/tutorial/pid_loop.yaml", "--vary", "kp=2..3", "--cases", "2"],
        vec!["sweep", lag, "--vary", "tau=0.1..0.2:2", "--out", path(&table)],
        vec!["--help"],
        vec!["run", "no/such/graph.yaml"],
    ];
    for args in &commands {
        for closed in ["stdout", "stderr"] {
            let mut cmd = Command::new(env!("CARGO_BIN_EXE_ctlgraph"));
            cmd.args(args).env("RUST_BACKTRACE", "1").stdin(Stdio::null());
            let (out, err) =
                if closed == "stdout" { (Stdio::piped(), Stdio::piped()) } else { (Stdio::null(), Stdio::piped()) };
            let mut child = cmd.stdout(out).stderr(err).spawn().unwrap();
            // Close the pipe before the child writes to it.
            let message = if closed == "stdout" {
                drop(child.stdout.take());
                let mut text = String::new();
                std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut text).unwrap();
                text
            } else {
                drop(child.stderr.take());
                String::new()
            };
            let status = child.wait().unwrap();
            let quiet = status.code().is_some_and(|c| [0, 1, 2].contains(&c)) || status.signal() == Some(libc::SIGPIPE);
            assert!(quiet, "{args:?} with {closed} closed: {status:?}");
            assert!(!message.contains("panicked") && !message.contains("Broken pipe"), "{args:?}: {message}");
        }
    }
}
