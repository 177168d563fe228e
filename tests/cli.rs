//! The command line as scripts see it: outputs, exit codes 0/1/2, messages
//! on stderr, `--set`, determinism.

mod common;
use common::{ctlgraph, path, text};
use std::path::Path;

const LAG: &str = "graphs/tutorial/first_order.yaml";

#[test]
fn run_writes_csv_plot_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, svg, json) = (dir.path().join("y.csv"), dir.path().join("y.svg"), dir.path().join("r.json"));
    let out = ctlgraph(&["run", LAG, "--out", path(&csv), "--plot", path(&svg), "--report", path(&json)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let summary = text(&out.stdout);
    assert!(summary.contains("3000 steps, 3 s simulated in") && summary.contains("x real time"), "{summary}");
    let csv = std::fs::read_to_string(csv).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("t,u,y"));
    assert_eq!(lines.count(), 3001);
    let svg = std::fs::read_to_string(svg).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("First-order lag") && svg.contains("t [s]"));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    assert_eq!(report["solver"]["method"], "rk4");
    // The lag is stepped by its exact transition: nothing to integrate.
    assert_eq!(report["exact_zoh"], serde_json::json!(["plant"]));
    assert_eq!(report["statistics"]["derivative_evaluations"], 0);
    assert_eq!(report["status"], "ok");
    assert_eq!(report["graph"]["sha256"].as_str().unwrap().len(), 64);
}

#[test]
fn csv_values_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("y.csv");
    assert!(ctlgraph(&["run", LAG, "--out", path(&csv)]).status.success());
    let model = ctlgraph::compile_file(Path::new(LAG), &[]).unwrap();
    let trace = ctlgraph::simulate(model, None).unwrap();
    let text = std::fs::read_to_string(csv).unwrap();
    for (row, line) in text.lines().skip(1).enumerate() {
        for (col, cell) in line.split(',').enumerate() {
            assert_eq!(cell.parse::<f64>().unwrap().to_bits(), trace.columns[col][row].to_bits());
        }
    }
}

#[test]
fn runs_are_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.csv"), dir.path().join("b.csv"));
    for (file, graph) in [(&a, "graphs/tutorial/multirate.yaml"), (&b, "graphs/tutorial/multirate.yaml")] {
        assert!(ctlgraph(&["run", graph, "--out", path(file)]).status.success());
    }
    assert_eq!(std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
}

#[test]
fn set_overrides_a_parameter_and_rejects_unknown_ones() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("y.csv");
    let out = ctlgraph(&["run", LAG, "--set", "tau=1.0", "--stop-time", "1", "--out", path(&csv)]);
    // The graph's checks are written for tau = 0.5 and 3 s: they fail (exit
    // 1), but the run itself succeeded and its CSV is complete.
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("checks failed"));
    let last = std::fs::read_to_string(&csv).unwrap().lines().last().unwrap().to_string();
    let y: f64 = last.split(',').nth(2).unwrap().parse().unwrap();
    assert!((y - (1.0 - (-1.0f64).exp())).abs() < 1e-9, "y(1) with tau = 1: {y}");

    let out = ctlgraph(&["run", LAG, "--set", "tua=1.0"]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(err.contains("--set tua") && err.contains("did you mean `tau`?"), "{err}");
    let out = ctlgraph(&["run", LAG, "--set", "tau"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn invalid_graph_exits_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("bad.yaml");
    std::fs::write(&graph, "blocks:\n  u: { type: stp }\n").unwrap();
    let csv = dir.path().join("y.csv");
    let out = ctlgraph(&["run", path(&graph), "--out", path(&csv)]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(err.starts_with(&format!("error: {}:2:14: block `u`: unknown block type `stp`", graph.display())), "{err}");
    assert!(err.contains("did you mean `step`?"));
    assert!(!csv.exists());
    assert_eq!(ctlgraph(&["run", "no/such/file.yaml"]).status.code(), Some(2));
}

#[test]
fn check_prints_the_execution_order() {
    let out = ctlgraph(&["check", "graphs/tutorial/multirate.yaml"]);
    assert!(out.status.success());
    let s = text(&out.stdout);
    let pos = |name: &str| s.find(&format!("  {name} ")).unwrap_or_else(|| panic!("{name} missing in\n{s}"));
    assert!(pos("plant") < pos("err") && pos("err") < pos("ctrl"), "{s}");
    assert!(s.contains("discrete 0.001") && s.contains("discrete 0.02"), "{s}");
}

#[test]
fn dot_and_blocks() {
    let out = ctlgraph(&["dot", "graphs/tutorial/subsystem.yaml"]);
    let s = text(&out.stdout);
    assert!(out.status.success() && s.starts_with("digraph") && s.contains("cluster_") && s.contains("style=dashed"));
    let s = text(&ctlgraph(&["blocks"]).stdout);
    assert!(s.contains("transfer_function") && s.contains("pid") && s.contains("sources:"));
    let s = text(&ctlgraph(&["blocks", "pid"]).stdout);
    assert!(s.contains("anti_windup") && s.contains("default clamping"), "{s}");
    let out = ctlgraph(&["blocks", "pdi"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("did you mean `pid`?"));
}

#[test]
fn events_and_newton_work_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("ball.json");
    let out = ctlgraph(&["run", "graphs/events/bouncing_ball.yaml", "--report", path(&json)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("steps, 7 events located, 10 s simulated"), "{}", text(&out.stdout));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["statistics"]["events"], 7);

    let json = dir.path().join("robertson.json");
    let out = ctlgraph(&["run", "graphs/stiff/robertson.yaml", "--report", path(&json)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["solver"]["method"], "trbdf2");
    let stats = &report["statistics"];
    assert!(stats["jacobian_evaluations"].as_u64().unwrap() > 0, "{stats}");
    assert!(stats["lu_factorizations"].as_u64().unwrap() >= stats["jacobian_evaluations"].as_u64().unwrap());
    assert!(stats["newton_failures"].is_u64(), "{stats}");

    // Past the Zeno point the run fails with the block named, exit 1.
    let zeno = dir.path().join("zeno.yaml");
    let text_in = std::fs::read_to_string("graphs/events/bouncing_ball.yaml").unwrap();
    std::fs::write(&zeno, text_in.replace("stop: 10.0", "stop: 15.0")).unwrap();
    let out = ctlgraph(&["run", path(&zeno)]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("chatters") && text(&out.stderr).contains("adaptive"), "{}", text(&out.stderr));
}

#[test]
fn scopes_draw_their_panels_with_units_and_the_csv_gets_its_units() {
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("scoped.yaml");
    std::fs::write(
        &graph,
        "simulation: { stop: 1.0, solver: { method: rk4, step: 1.0e-3 } }\n\
         blocks:\n  u: { type: step, at: 0.1 }\n  plant: { type: transfer_function, num: [1], den: [0.1, 1] }\n\
         wires: [u -> plant]\n\
         record:\n  - { u, unit: V }\n  - { y: plant, unit: mm }\n\
         scopes:\n  - { title: Command panel, signals: [u], y_label: command }\n\
         \x20 - { title: Response panel, signals: [u, y], y_label: position, unit: mm, band: [0.9, 1.1], window: [0, 0.5] }\n",
    )
    .unwrap();
    let (csv, svg) = (dir.path().join("run.csv"), dir.path().join("run.svg"));
    let out = ctlgraph(&["run", path(&graph), "--out", path(&csv), "--plot", path(&svg)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let svg = std::fs::read_to_string(&svg).unwrap();
    for expected in [
        "Command panel",
        "Response panel",
        "command [V]",
        "position [mm]",
        "band [0.9, 1.1]",
        "\nu\n</text>",
        "\ny\n</text>",
    ] {
        assert!(svg.contains(expected), "the SVG lacks `{expected}`");
    }
    // Two panels: two time axes.
    assert_eq!(svg.matches("t [s]").count(), 2);
    // Okabe–Ito colours, first blue then vermillion; tick labels in shortest form.
    assert!(svg.contains("stroke=\"#0072B2\"") && svg.contains("stroke=\"#D55E00\""));
    assert!(!svg.contains("\n0.0\n") && !svg.contains("\n-0\n") && svg.contains("\n0.5\n"), "tick labels");
    let units = std::fs::read_to_string(dir.path().join("run.units.csv")).unwrap();
    assert_eq!(units, "t,u,y\ns,V,mm\n");
    // Without scopes or units: one panel per name, no units file.
    let plain = dir.path().join("plain.csv");
    let out = ctlgraph(&["run", LAG, "--out", path(&plain)]);
    assert_eq!(out.status.code(), Some(0));
    assert!(!dir.path().join("plain.units.csv").exists());
}

#[test]
fn papercuts_negative_stop_time_and_help_examples() {
    let out = ctlgraph(&["run", LAG, "--stop-time", "-1"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("--stop-time -1: must be a positive number"), "{}", text(&out.stderr));
    for sub in ["run", "test", "prop", "check", "dot", "blocks"] {
        let out = ctlgraph(&[sub, "--help"]);
        assert_eq!(out.status.code(), Some(0));
        let help = text(&out.stdout);
        assert!(
            help.contains("Example") && help.contains(&format!("ctlgraph {sub} ")),
            "`{sub} --help` shows no example:\n{help}"
        );
    }
}

#[test]
fn first_day_papercuts() {
    // `--set` of an unknown name lists the graph's parameters.
    let out = ctlgraph(&["run", "graphs/tutorial/pid_loop.yaml", "--set", "foo=1"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("its parameters: wn, zeta, kp, ki, kd, u_max"), "{}", text(&out.stderr));
    // One step is "1 step", and a run too short to time gives no ratio.
    let dir = tempfile::tempdir().unwrap();
    let tiny = dir.path().join("tiny.yaml");
    std::fs::write(
        &tiny,
        "simulation: { stop: 0.1, solver: { method: rk4, step: 0.1 } }\nblocks:\n  c: { type: constant }\n",
    )
    .unwrap();
    let out = ctlgraph(&["run", path(&tiny)]);
    let line = text(&out.stdout);
    assert!(line.contains(": 1 step, 0.1 s simulated in "), "{line}");
    // `--out -` writes the CSV to stdout and the summary to stderr.
    let out = ctlgraph(&["run", LAG, "--out", "-"]);
    assert_eq!(out.status.code(), Some(0));
    let csv = text(&out.stdout);
    assert!(csv.starts_with("t,u,y\n0,1,0\n") && csv.lines().count() == 3002, "{}", &csv[..60]);
    assert!(text(&out.stderr).contains("3000 steps"));
    // A plot is SVG: another extension is refused, not filled with SVG bytes.
    let png = dir.path().join("p.png");
    let out = ctlgraph(&["run", LAG, "--plot", path(&png)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("ctlgraph draws SVG") && !png.exists());
    // The report records the overrides, the resolved parameters and the command.
    let report = |set: &str| {
        let json = dir.path().join(format!("{set}.json"));
        let out = ctlgraph(&["run", "graphs/tutorial/pid_loop.yaml", "--set", set, "--report", path(&json)]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(json).unwrap()).unwrap()
    };
    let (a, b) = (report("kp=2.5"), report("kp=3"));
    assert_eq!(a["overrides"][0]["value"], "2.5");
    let kp = |r: &serde_json::Value| {
        r["parameters"].as_array().unwrap().iter().find(|p| p["name"] == "kp").unwrap()["value"].clone()
    };
    assert_eq!((kp(&a), kp(&b)), (serde_json::json!(2.5), serde_json::json!(3.0)));
    assert!(b["command_line"].as_array().unwrap().iter().any(|w| w == "kp=3"));
}

#[test]
fn a_check_window_after_the_stop_time_is_skipped_with_its_reason() {
    let out = ctlgraph(&["run", "graphs/tutorial/pid_loop.yaml", "--stop-time", "1"]);
    let stdout = text(&out.stdout);
    assert!(stdout.contains("  skip  steady  (its window starts at 2 s, after the stop time 1 s)"), "{stdout}");
    assert!(!stdout.contains("FAIL  steady"), "{stdout}");
    // `check` knows the file's stop time and says so before any run.
    let dir = tempfile::tempdir().unwrap();
    let short = dir.path().join("short.yaml");
    let text_in = std::fs::read_to_string("graphs/tutorial/pid_loop.yaml").unwrap().replace("stop: 3.0", "stop: 1.5");
    std::fs::write(&short, text_in).unwrap();
    let out = ctlgraph(&["check", path(&short)]);
    assert_eq!(out.status.code(), Some(0));
    assert!(
        text(&out.stdout).contains("warning: check `steady`: its window starts at 2 s, after the stop time 1.5 s"),
        "{}",
        text(&out.stdout)
    );
}

#[test]
fn a_subsystem_file_checks_on_its_own_and_its_ports_are_named_as_written() {
    let out = ctlgraph(&["check", "graphs/lib/ladrc.yaml"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("inputs:  r, y (") && stdout.contains("outputs: u"), "{stdout}");
    // Its inports hold `value`s for a program: that is a graph of its own too.
    let out = ctlgraph(&["check", "graphs/tutorial/controller_io.yaml"]);
    assert!(text(&out.stdout).contains("inputs:  y (set by a program"), "{}", text(&out.stderr));
    // A mistake inside is reported in the subsystem file, exit 2.
    let dir = tempfile::tempdir().unwrap();
    let inner = dir.path().join("inner.yaml");
    std::fs::write(
        &inner,
        "blocks:\n  F: { type: inport }\n  g: { type: gain, k: 2 }\n  y: { type: outport }\nwires: [F -> g, g -> yy]\n",
    )
    .unwrap();
    let out = ctlgraph(&["check", path(&inner)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("inner.yaml:5:22: wire: no block named `yy`"), "{}", text(&out.stderr));
    // A subsystem port wired twice is named `sub.port`, as written.
    std::fs::write(
        &inner,
        "blocks:\n  F: { type: inport }\n  g: { type: gain, k: 2 }\n  y: { type: outport }\nwires: [F -> g, g -> y]\n",
    )
    .unwrap();
    let outer = dir.path().join("outer.yaml");
    std::fs::write(&outer, "blocks:\n  a: { type: constant }\n  b: { type: constant }\n  plant: { type: subsystem, file: inner.yaml }\nwires: [a -> plant.F, b -> plant.F]\n").unwrap();
    let out = ctlgraph(&["check", path(&outer)]);
    assert!(text(&out.stderr).contains("input `plant.F` is wired twice"), "{}", text(&out.stderr));
}

#[test]
fn limits_follow_the_run_not_the_file() {
    // The default max_step follows --stop-time (stop/200), not the file's stop.
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("short.yaml");
    std::fs::write(&g, "simulation: { stop: 1.0e-4 }\nblocks:\n  u: { type: sine }\n  p: { type: transfer_function, num: [1], den: [1, 1] }\nwires: [u -> p]\n").unwrap();
    let json = dir.path().join("r.json");
    let out = ctlgraph(&["run", path(&g), "--stop-time", "1", "--report", path(&json)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["solver"]["max_step"], 0.005);
    assert!(report["statistics"]["major_steps"].as_u64().unwrap() < 1000, "{}", report["statistics"]);
    // Tiny sample times print in short form.
    let tiny = dir.path().join("tiny.yaml");
    std::fs::write(
        &tiny,
        "simulation: { stop: 1.0e-3 }\nblocks:\n  u: { type: step }\n  z: { type: zero_order_hold, sample_time: 1.0e-12 }\nwires: [u -> z]\n",
    )
    .unwrap();
    let out = ctlgraph(&["check", path(&tiny)]);
    assert!(text(&out.stdout).contains("discrete 1e-12"), "{}{}", text(&out.stdout), text(&out.stderr));
    // prop refuses a range with an infinite span and a parameter given twice.
    let out = ctlgraph(&["prop", "graphs/tutorial/pid_loop.yaml", "--vary", "ki=-1e308..1e308"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("finite span"), "{}", text(&out.stderr));
    let out = ctlgraph(&["prop", "graphs/tutorial/pid_loop.yaml", "--vary", "kp=1..2", "--vary", "kp=2..3"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("--vary kp: given twice"), "{}", text(&out.stderr));
}

#[test]
fn plotting_values_near_the_largest_double_returns() {
    // The axis range of ±1.7e308 overflowed to infinity and the plot never
    // returned; a guard of a minute stands in for "never".
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("big.yaml");
    std::fs::write(
        &g,
        "simulation: { stop: 0.01, solver: { method: rk4, step: 1.0e-3 } }\nblocks:\n  c: { type: constant, value: 1.7e308 }\n  d: { type: constant, value: -1.7e308 }\nrecord: [c, d]\nscopes:\n  - { signals: [c, d] }\n",
    )
    .unwrap();
    let svg = dir.path().join("big.svg");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_ctlgraph"))
        .args(["run", path(&g), "--plot", path(&svg)])
        .env("CI", "1")
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > std::time::Duration::from_secs(60) {
            let _ = child.kill();
            panic!("ctlgraph run --plot did not return");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    assert!(status.success() && svg.exists());
}

#[test]
fn runs_that_cannot_finish_and_outputs_that_would_clobber_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("g.yaml");
    std::fs::write(
        &g,
        "simulation: { stop: 1.0, solver: { method: rk4, step: 1.0e-320 } }\nblocks:\n  c: { type: constant }\n",
    )
    .unwrap();
    let out = ctlgraph(&["check", path(&g)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("steps to reach the stop time 1 s (limit 1e10)"), "{}", text(&out.stderr));
    std::fs::write(
        &g,
        "blocks:\n  u: { type: step }\n  z: { type: zero_order_hold, sample_time: 1.0e-300 }\nwires: [u -> z]\n",
    )
    .unwrap();
    let out = ctlgraph(&["run", path(&g)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("block `z`: a sample time of 1e-300 s gives"), "{}", text(&out.stderr));
    // --out onto the graph, or the same file for two outputs.
    let out = ctlgraph(&["run", LAG, "--out", LAG]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("that is the graph file"), "{}", text(&out.stderr));
    let f = dir.path().join("x.svg");
    let out = ctlgraph(&["run", LAG, "--out", path(&f), "--plot", path(&f)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("also given to --out"), "{}", text(&out.stderr));
    assert!(std::fs::read_to_string(LAG).unwrap().contains("First-order lag"), "the graph is intact");
}

#[test]
fn outputs_never_replace_what_is_not_a_regular_writable_file() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    // Through a symbolic link: the target gets the CSV, the link stays a link.
    let real = dir.path().join("real.csv");
    std::fs::write(&real, "old").unwrap();
    let link = dir.path().join("link.csv");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    assert_eq!(ctlgraph(&["run", LAG, "--out", path(&link)]).status.code(), Some(0));
    assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
    assert!(std::fs::read_to_string(&real).unwrap().starts_with("t,u,y\n"));
    // A dangling link: its target is created, the link stays a link.
    let (dangling, missing) = (dir.path().join("dangling.csv"), dir.path().join("new.csv"));
    std::os::unix::fs::symlink("new.csv", &dangling).unwrap();
    assert_eq!(ctlgraph(&["run", LAG, "--out", path(&dangling)]).status.code(), Some(0));
    assert!(std::fs::symlink_metadata(&dangling).unwrap().file_type().is_symlink());
    assert!(std::fs::read_to_string(&missing).unwrap().starts_with("t,u,y\n"));
    // A read-only file is not silently replaced.
    let ro = dir.path().join("ro.csv");
    std::fs::write(&ro, "keep").unwrap();
    let mut perms = std::fs::metadata(&ro).unwrap().permissions();
    perms.set_readonly(true);
    std::fs::set_permissions(&ro, perms).unwrap();
    let out = ctlgraph(&["run", LAG, "--out", path(&ro)]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("read-only") && std::fs::read_to_string(&ro).unwrap() == "keep");
    // A device node stays a device node.
    let out = ctlgraph(&["run", LAG, "--out", "/dev/full"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("not a regular file"));
    assert!(std::fs::metadata("/dev/full").unwrap().file_type().is_char_device());
}

#[test]
fn a_pulse_too_fast_for_its_run_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("pulse.yaml");
    std::fs::write(&g, "simulation: { stop: 0.05 }\nblocks:\n  p: { type: pulse, period: 1e-300 }\n").unwrap();
    let out = ctlgraph(&["check", path(&g)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("block `p`: events 5e-301 s apart give 1e299 steps"), "{}", text(&out.stderr));
}

/// A device or FIFO named as a graph, an include or a run's file is
/// refused before reading (reading /dev/zero never ends and exhausted
/// memory; a FIFO waited forever).
#[test]
fn devices_and_fifos_are_refused_not_read() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo.yaml");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let including = dir.path().join("top.yaml");
    std::fs::write(&including, "blocks:\n  s: { type: subsystem, file: /dev/zero }\n").unwrap();
    let html = dir.path().join("r.html");
    for args in [
        vec!["run", "/dev/zero"],
        vec!["check", path(&fifo)],
        vec!["sweep", "/dev/zero", "--vary", "k=1..2:2", "--out", "s.csv"],
        vec!["report", "/dev/zero", "--json", "/dev/zero", "--html", path(&html)],
    ] {
        let out = ctlgraph(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(
            text(&out.stderr).contains("not a regular file (a device, FIFO or folder)"),
            "{args:?}: {}",
            text(&out.stderr)
        );
    }
    let out = ctlgraph(&["check", path(&including)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("cannot read `/dev/zero`: not a regular file"), "{}", text(&out.stderr));
}

/// `check`'s count of major steps is a floor for the adaptive methods: no
/// bundled adaptive run takes fewer (multirate.yaml's run takes 2 005
/// steps, which a sum of its clocks' counts put at 2 300 at least).
#[test]
fn the_major_steps_check_promises_are_a_floor_for_adaptive_runs() {
    for graph in common::bundled_graphs() {
        let Ok(model) = ctlgraph::compile_file(&graph, &[]) else { continue };
        if !model.sim.method.is_adaptive() {
            continue;
        }
        let mut sim = ctlgraph_core::Simulator::new(model, None);
        let floor = sim.expected_major_steps();
        if floor > 1e5 {
            continue;
        }
        let Ok(stats) = sim.run(&mut |_, _| {}) else { continue };
        assert!(stats.major_steps as f64 >= floor, "{}: {} steps, floor {floor}", graph.display(), stats.major_steps);
    }
}

/// An optional parameter is not listed as required: mux's and demux's
/// `widths` default to one scalar port per `inputs`/`outputs`.
#[test]
fn blocks_lists_optional_parameters_with_their_default() {
    for ty in ["mux", "demux"] {
        let s = text(&ctlgraph(&["blocks", ty]).stdout);
        let line = s.lines().find(|l| l.trim_start().starts_with("widths")).unwrap_or_else(|| panic!("{s}"));
        assert!(!line.contains("required") && line.contains("default 1 for each of"), "{line}");
    }
}

#[test]
fn watch_serves_only_a_report_it_writes() {
    let out = ctlgraph(&["watch", "graphs/tutorial/pid_loop.yaml", "--serve", "0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("--serve serves the HTML report: give --html FILE.html too"),
        "{}",
        text(&out.stderr)
    );
}
