//! `ctlgraph fmu` as a user runs it: the archive's layout (the graph with
//! its subsystem and data files, the description, the binary), the real
//! binary loaded with `libloading` and stepped through its FMI 3 functions
//! to `ctlgraph run`'s numbers, and the errors. FMPy checks the same FMUs
//! as an importer (`tests/fmu/test_fmpy.py`, run by `.ci/run`).

mod common;
use common::{ctlgraph, text};
use std::ffi::{CStr, CString, c_char, c_void};
use std::io::Read;
use std::path::Path;

/// The files of the zip archive at `path`, by name.
fn unzip(path: &Path) -> Vec<(String, Vec<u8>)> {
    let mut archive = zip::ZipArchive::new(std::fs::File::open(path).unwrap()).unwrap();
    (0..archive.len())
        .map(|i| {
            let mut f = archive.by_index(i).unwrap();
            let mut bytes = Vec::new();
            f.read_to_end(&mut bytes).unwrap();
            (f.name().unwrap().to_string(), bytes)
        })
        .collect()
}

/// A graph in a folder of its own, with a subsystem file in `lib/` and a
/// data table in `data/`, as users lay projects out.
fn project(dir: &Path) -> std::path::PathBuf {
    std::fs::create_dir_all(dir.join("lib")).unwrap();
    std::fs::create_dir_all(dir.join("data")).unwrap();
    std::fs::write(dir.join("data/ref.csv"), "t,r\n0,0\n1,1\n2,1\n").unwrap();
    std::fs::write(
        dir.join("lib/lag.yaml"),
        "parameters: { tau: 1 }\nblocks:\n  u: { type: inport }\n  d: { type: sum, signs: \"+-\" }\n  \
         g: { type: gain, k: 1/tau }\n  x: { type: integrator }\n  y: { type: outport }\n\
         wires: [u -> d.u1, x -> d.u2, d -> g, g -> x, x -> y]\n",
    )
    .unwrap();
    let graph = dir.join("main.yaml");
    std::fs::write(
        &graph,
        "name: table into a lag\nparameters: { tau: 0.5 }\nsimulation: { stop: 2, solver: { method: rk4, step: 0.01 } }\n\
         blocks:\n  r: { type: from_csv, file: data/ref.csv, column: r }\n  \
         lag: { type: subsystem, file: lib/lag.yaml, parameters: { tau: tau } }\n\
         wires: [r -> lag]\nrecord: [r, y: lag]\n",
    )
    .unwrap();
    graph
}

#[test]
fn an_fmu_carries_the_graph_its_files_and_a_binary_that_steps_it_as_ctlgraph_runs_it() {
    let dir = tempfile::tempdir().unwrap();
    let graph = project(&dir.path().join("proj"));
    let fmu = dir.path().join("lag-table.fmu");
    let out = ctlgraph(&["fmu", graph.to_str().unwrap(), "--out", fmu.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let summary = text(&out.stdout);
    assert!(
        summary.contains("FMI 3.0 co-simulation FMU, 0 inputs, 2 outputs, 1 parameter, 0 local variables"),
        "{summary}"
    );
    let files = unzip(&fmu);
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "modelDescription.xml",
            "resources/ctlgraph.json",
            "resources/model/main.yaml",
            "resources/model/lib/lag.yaml",
            "resources/model/data/ref.csv",
            "binaries/x86_64-linux/lag_table.so"
        ]
    );
    let description = text(&files[0].1);
    assert!(description.contains("modelIdentifier=\"lag_table\""), "{description}");
    assert!(description.contains("<DefaultExperiment startTime=\"0\" stopTime=\"2\" stepSize=\"0.01\"/>"));

    // The binary, unpacked and loaded as an importer loads it.
    let unpacked = dir.path().join("unpacked");
    for (name, bytes) in &files {
        let path = unpacked.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, bytes).unwrap();
    }
    let reference = dir.path().join("ref.csv");
    let out = ctlgraph(&["run", graph.to_str().unwrap(), "--out", reference.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let rows: Vec<Vec<f64>> = text(&std::fs::read(&reference).unwrap())
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let token = description.split("instantiationToken=\"").nth(1).unwrap().split('"').next().unwrap();
    let y = step_through_fmi3(&unpacked, "lag_table", token, 0.1, 20);
    for (k, value) in y.iter().enumerate() {
        let row = &rows[(k + 1) * 10];
        assert!((row[0] - (k + 1) as f64 * 0.1).abs() < 1e-12);
        assert_eq!(value.to_bits(), row[2].to_bits(), "y at t = {}", row[0]);
    }
}

type Instantiate = unsafe extern "C" fn(
    *const c_char,
    *const c_char,
    *const c_char,
    bool,
    bool,
    bool,
    bool,
    *const u32,
    usize,
    *mut c_void,
    *const c_void,
    *const c_void,
) -> *mut c_void;
type Init = unsafe extern "C" fn(*mut c_void, bool, f64, f64, bool, f64) -> i32;
type Exit = unsafe extern "C" fn(*mut c_void) -> i32;
type DoStep = unsafe extern "C" fn(*mut c_void, f64, f64, bool, *mut bool, *mut bool, *mut bool, *mut f64) -> i32;
type Get = unsafe extern "C" fn(*mut c_void, *const u32, usize, *mut f64, usize) -> i32;
type Free = unsafe extern "C" fn(*mut c_void);
type Version = unsafe extern "C" fn() -> *const c_char;

/// Output 2 (`y`) after each of `n` steps of `h` through the FMU's own
/// binary, unpacked in `dir`.
fn step_through_fmi3(dir: &Path, id: &str, token: &str, h: f64, n: usize) -> Vec<f64> {
    // SAFETY: the FMU's binary, called by the FMI 3 signatures it exports.
    unsafe {
        let lib = libloading::Library::new(dir.join(format!("binaries/x86_64-linux/{id}.so"))).unwrap();
        for name in FMI3_FUNCTIONS.iter().chain(FMI2_FUNCTIONS) {
            assert!(lib.get::<*const c_void>(name.as_bytes()).is_ok(), "the binary exports no `{name}`");
        }
        let version: libloading::Symbol<Version> = lib.get(b"fmi3GetVersion").unwrap();
        assert_eq!(CStr::from_ptr(version()).to_str().unwrap(), "3.0");
        let instantiate: libloading::Symbol<Instantiate> = lib.get(b"fmi3InstantiateCoSimulation").unwrap();
        let init: libloading::Symbol<Init> = lib.get(b"fmi3EnterInitializationMode").unwrap();
        let exit: libloading::Symbol<Exit> = lib.get(b"fmi3ExitInitializationMode").unwrap();
        let step: libloading::Symbol<DoStep> = lib.get(b"fmi3DoStep").unwrap();
        let get: libloading::Symbol<Get> = lib.get(b"fmi3GetFloat64").unwrap();
        let free: libloading::Symbol<Free> = lib.get(b"fmi3FreeInstance").unwrap();
        let (name, token) = (CString::new("test").unwrap(), CString::new(token).unwrap());
        let resources = CString::new(format!("{}/resources/", dir.display())).unwrap();
        let null = std::ptr::null_mut();
        let c = instantiate(
            name.as_ptr(),
            token.as_ptr(),
            resources.as_ptr(),
            false,
            false,
            false,
            false,
            std::ptr::null(),
            0,
            null,
            std::ptr::null(),
            std::ptr::null(),
        );
        assert!(!c.is_null());
        assert_eq!(init(c, false, 0.0, 0.0, true, 2.0), 0);
        assert_eq!(exit(c), 0);
        let mut out = Vec::new();
        for k in 0..n {
            let (mut a, mut b, mut e, mut last) = (false, false, false, 0.0);
            assert_eq!(step(c, k as f64 * h, h, true, &mut a, &mut b, &mut e, &mut last), 0);
            let mut y = 0.0;
            assert_eq!(get(c, [2u32].as_ptr(), 1, &mut y, 1), 0);
            out.push(y);
        }
        free(c);
        out
    }
}

const FMI3_FUNCTIONS: [&str; 12] = [
    "fmi3GetVersion",
    "fmi3InstantiateCoSimulation",
    "fmi3FreeInstance",
    "fmi3EnterInitializationMode",
    "fmi3ExitInitializationMode",
    "fmi3DoStep",
    "fmi3GetFloat64",
    "fmi3SetFloat64",
    "fmi3GetFMUState",
    "fmi3SerializeFMUState",
    "fmi3GetContinuousStates",
    "fmi3ActivateModelPartition",
];
const FMI2_FUNCTIONS: &[&str] = &[
    "fmi2GetVersion",
    "fmi2Instantiate",
    "fmi2DoStep",
    "fmi2GetReal",
    "fmi2DeSerializeFMUstate",
    "fmi2GetDerivatives",
];

#[test]
fn fmi2_archives_name_their_platform_folder_linux64_and_carry_a_guid() {
    let dir = tempfile::tempdir().unwrap();
    let fmu = dir.path().join("ladrc.fmu");
    let out = ctlgraph(&["fmu", "graphs/fladrc/ladrc.yaml", "--out", fmu.to_str().unwrap(), "--fmi", "2"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("FMI 2.0 co-simulation FMU, 0 inputs, 5 outputs"), "{}", text(&out.stdout));
    let files = unzip(&fmu);
    assert!(files.iter().any(|(n, _)| n == "binaries/linux64/ladrc.so"));
    let description = text(&files[0].1);
    assert!(description.contains("fmiVersion=\"2.0\"") && description.contains(" guid=\"{"), "{description}");
}

#[test]
fn bad_requests_are_refused_with_exit_2_and_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let zip = dir.path().join("x.zip");
    let out = ctlgraph(&["fmu", "graphs/fladrc/ladrc.yaml", "--out", zip.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("an FMU's file name ends in .fmu"), "{}", text(&out.stderr));
    // A graph error, positioned; a name given to two variables.
    let bad = dir.path().join("bad.yaml");
    std::fs::write(&bad, "blocks:\n  g: { type: gian }\n").unwrap();
    let fmu = dir.path().join("bad.fmu");
    let out = ctlgraph(&["fmu", bad.to_str().unwrap(), "--out", fmu.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("bad.yaml:2:"), "{}", text(&out.stderr));
    std::fs::write(&bad, "parameters: { s: 1 }\nblocks:\n  c: { type: constant, value: s }\nrecord: [s: c]\n").unwrap();
    let out = ctlgraph(&["fmu", bad.to_str().unwrap(), "--out", fmu.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("two variables named `s`"), "{}", text(&out.stderr));
    assert!(!fmu.exists() && !zip.exists());
}

// The `fmu` block, on FMUs these tests export from tests/fmu/plant_io.yaml.

/// `tests/fmu/plant_io.yaml` exported as `name` (FMI `version`) into `dir`.
fn exported_plant(dir: &Path, name: &str, version: &str) -> std::path::PathBuf {
    let fmu = dir.join(name);
    let out = ctlgraph(&["fmu", "tests/fmu/plant_io.yaml", "--out", fmu.to_str().unwrap(), "--fmi", version]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    fmu
}

/// The plant as an FMU block (FMI 3: the vector port `u`; FMI 2: `u_1_`, `u_2_`).
fn graph_with_fmu(dir: &Path, fmu: &str, version: &str, extra: &str) -> std::path::PathBuf {
    let (mux, wires, record) = match version {
        "3" => ("  m: { type: mux }\n", "[src -> m.u1, src2 -> m.u2, m -> plant.u]", "[y: plant.y]"),
        _ => ("", "[src -> plant.u_1_, src2 -> plant.u_2_]", "[y1: plant.y_1_, y2: plant.y_2_]"),
    };
    let graph = dir.join(format!("with_{fmu}.yaml"));
    std::fs::write(
        &graph,
        format!(
            "name: plant as an FMU\nparameters: {{ g: 3 }}\nsimulation: {{ stop: 5, solver: {{ method: rk4, step: 0.01 }} }}\n\
             blocks:\n  src: {{ type: sine, amplitude: 1, frequency: 0.5 }}\n  src2: {{ type: step, at: 1.02, value: -1 }}\n\
             {mux}  plant: {{ type: fmu, file: {fmu}, sample_time: 0.05, parameters: {{ gain: g }}{extra} }}\n\
             wires: {wires}\nrecord: {record}\n"
        ),
    )
    .unwrap();
    graph
}

/// The same plant written in the graph, behind a hold on its input and
/// one on its output at the FMU block's sample time: what co-simulation
/// of it means.
const NATIVE: &str = "name: the plant in the graph, behind holds
parameters: { gain: 3, tau: 0.5 }
simulation: { stop: 5, solver: { method: rk4, step: 0.01 } }
blocks:
  src:  { type: sine, amplitude: 1, frequency: 0.5 }
  src2: { type: step, at: 1.02, value: -1 }
  m:    { type: mux }
  hold: { type: zero_order_hold, sample_time: 0.05 }
  k:    { type: gain, k: gain }
  diff: { type: sum, signs: \"+-\" }
  rate: { type: gain, k: 1/tau }
  x:    { type: integrator, initial: [0, 1] }
  out:  { type: zero_order_hold, sample_time: 0.05 }
wires: [src -> m.u1, src2 -> m.u2, m -> hold, hold -> k, k -> diff.u1, x -> diff.u2, diff -> rate, rate -> x, x -> out]
record: [y: out]
";

/// A run's CSV rows, the header dropped.
fn rows(graph: &Path, csv: &Path) -> Vec<String> {
    let out = ctlgraph(&["run", graph.to_str().unwrap(), "--out", csv.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    text(&std::fs::read(csv).unwrap()).lines().skip(1).map(str::to_string).collect()
}

#[test]
fn an_fmu_block_co_simulates_an_exported_plant_as_the_graph_runs_it_behind_holds() {
    let dir = tempfile::tempdir().unwrap();
    let native = dir.path().join("native.yaml");
    std::fs::write(&native, NATIVE).unwrap();
    let expected = rows(&native, &dir.path().join("native.csv"));
    assert_eq!(expected.len(), 501);
    for version in ["3", "2"] {
        exported_plant(dir.path(), &format!("plant{version}.fmu"), version);
        let graph = graph_with_fmu(dir.path(), &format!("plant{version}.fmu"), version, "");
        let got = rows(&graph, &dir.path().join(format!("fmu{version}.csv")));
        // The same numbers, to the bit: the FMU runs the plant with the same
        // method and step over each communication step, its input held.
        assert_eq!(got, expected, "FMI {version}");
    }
}

#[test]
fn fmu_block_mistakes_are_positioned_and_named() {
    let dir = tempfile::tempdir().unwrap();
    exported_plant(dir.path(), "plant3.fmu", "3");
    let check = |extra: &str| {
        let graph = graph_with_fmu(dir.path(), "plant3.fmu", "3", extra);
        let out = ctlgraph(&["check", graph.to_str().unwrap()]);
        (out.status.code(), text(&out.stderr), text(&out.stdout))
    };
    // `check` lists the FMU's variables.
    let (code, _, stdout) = check("");
    assert_eq!(code, Some(0));
    assert!(stdout.contains("FMU `Two lags` (FMI 3.0, co-simulation, step 0.05 s)"), "{stdout}");
    assert!(stdout.contains("u[2]: input Float64, start [0.5, 0.5]"), "{stdout}");
    // A parameter the FMU does not have: did you mean, at its key.
    let graph = graph_with_fmu(dir.path(), "plant3.fmu", "3", "");
    let text_of = std::fs::read_to_string(&graph).unwrap().replace("gain: g", "gian: g");
    std::fs::write(&graph, &text_of).unwrap();
    let out = ctlgraph(&["check", graph.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains(":8:") && err.contains("no real parameter `gian`") && err.contains("did you mean `gain`?"),
        "{err}"
    );
    // An input it does not have; a missing file; model exchange of a co-simulation FMU.
    let (code, err, _) = check(", inputs: [v]");
    assert_eq!(code, Some(2));
    assert!(err.contains("the FMU has no input `v`") && err.contains("did you mean `u`?"), "{err}");
    let graph = graph_with_fmu(dir.path(), "missing.fmu", "3", "");
    let out = ctlgraph(&["check", graph.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("missing.fmu`: cannot read"), "{}", text(&out.stderr));
    let (code, err, _) = check(", mode: me");
    assert_eq!(code, Some(2));
    assert!(err.contains("no model-exchange interface (for co-simulation: `mode: cs`)"), "{err}");
    // An FMU without a binary for this platform.
    let stripped = dir.path().join("source_only.fmu");
    let mut writer = zip::ZipWriter::new(std::fs::File::create(&stripped).unwrap());
    for (name, bytes) in unzip(&dir.path().join("plant3.fmu")).into_iter().filter(|(n, _)| !n.starts_with("binaries/"))
    {
        writer.start_file(name, zip::write::SimpleFileOptions::default()).unwrap();
        std::io::Write::write_all(&mut writer, &bytes).unwrap();
    }
    writer.finish().unwrap();
    let graph = graph_with_fmu(dir.path(), "source_only.fmu", "3", "");
    let out = ctlgraph(&["check", graph.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("no binary for this platform (x86_64-linux/plant3.so)"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn an_fmu_that_does_not_initialise_is_reported_at_the_block_with_what_the_fmu_said() {
    let dir = tempfile::tempdir().unwrap();
    exported_plant(dir.path(), "plant3.fmu", "3");
    // tau = 0 makes the exported graph invalid: its initialisation fails,
    // found when the graph is built (instantiated once there).
    let graph = graph_with_fmu(dir.path(), "plant3.fmu", "3", "");
    let with_tau = std::fs::read_to_string(&graph).unwrap().replace("gain: g", "gain: g, tau: 0");
    std::fs::write(&graph, with_tau).unwrap();
    let out = ctlgraph(&["check", graph.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    assert!(
        err.contains(":8:") && err.contains("block `plant` (fmu): `parameters`: the FMU does not initialise"),
        "{err}"
    );
    assert!(
        err.contains("exiting initialisation mode returned error (the FMU said:") && err.contains("plant_io.yaml"),
        "{err}"
    );
}

// `mode: me`, on a model-exchange FMU these tests build from C
// (tests/fmu/bouncing_ball_me.c) with the system's C compiler.

/// The bouncing ball FMU for FMI `version`, compiled and packed in `dir`.
fn built_ball(dir: &Path, version: &str) -> std::path::PathBuf {
    let (platform, xml) = match version {
        "3" => ("x86_64-linux", "tests/fmu/bouncing_ball_me.xml"),
        _ => ("linux64", "tests/fmu/bouncing_ball_me2.xml"),
    };
    let so = dir.join(format!("bouncing_ball{version}.so"));
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".to_string());
    let out = std::process::Command::new(&cc)
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-shared", "-fPIC", "-O2", "-o"])
        .arg(&so)
        .arg("tests/fmu/bouncing_ball_me.c")
        .output()
        .unwrap_or_else(|e| panic!("the C compiler `{cc}`: {e}"));
    assert!(out.status.success(), "{}", text(&out.stderr));
    let fmu = dir.join(format!("ball{version}.fmu"));
    let mut writer = zip::ZipWriter::new(std::fs::File::create(&fmu).unwrap());
    let options = zip::write::SimpleFileOptions::default();
    for (name, bytes) in [
        ("modelDescription.xml".to_string(), std::fs::read(xml).unwrap()),
        (format!("binaries/{platform}/bouncing_ball.so"), std::fs::read(&so).unwrap()),
    ] {
        writer.start_file(name, options).unwrap();
        std::io::Write::write_all(&mut writer, &bytes).unwrap();
    }
    writer.finish().unwrap();
    fmu
}

/// A graph running `fmu` in model exchange under `solver`, with `parameters`.
fn ball_graph(dir: &Path, fmu: &str, solver: &str, parameters: &str) -> std::path::PathBuf {
    let graph = dir.join(format!("{}.yaml", fmu.replace('.', "_")));
    std::fs::write(
        &graph,
        format!(
            "name: a ball as an FMU\nsimulation: {{ stop: 10, solver: {solver} }}\nblocks:\n  a: {{ type: constant, value: 0 }}\n  \
             ball: {{ type: fmu, file: {fmu}, mode: me, parameters: {{ {parameters} }} }}\n\
             wires: [a -> ball.a]\nrecord: [h: ball.h, v: ball.v]\n"
        ),
    )
    .unwrap();
    graph
}

/// Rows (t, h, v) of a run.
fn ball_rows(graph: &Path) -> Vec<[f64; 3]> {
    let csv = graph.with_extension("csv");
    rows(graph, &csv)
        .iter()
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

const DOPRI: &str = "{ method: dopri5, rtol: 1.0e-10, atol: 1.0e-12, max_step: 0.05 }";

/// The times v turns from falling to rising: the located impacts.
fn impacts(rows: &[[f64; 3]]) -> Vec<f64> {
    rows.windows(2).filter(|w| w[0][2] < 0.0 && w[1][2] > 0.0).map(|w| w[1][0]).collect()
}

#[test]
fn a_model_exchange_fmu_bounces_where_the_closed_form_says_its_states_in_ctlgraphs_solver() {
    let dir = tempfile::tempdir().unwrap();
    let (g, e, h0) = (9.81f64, 0.8f64, 10.0f64);
    // Impacts: t1 = √(2 h0 / g), then each flight 2 eᵏ v1 / g with v1 = g t1.
    let t1 = (2.0 * h0 / g).sqrt();
    let closed: Vec<f64> = (0..4)
        .scan(t1, |t, k| {
            let now = *t;
            *t += 2.0 * e.powi(k + 1) * g * t1 / g;
            Some(now)
        })
        .collect();
    let mut by_version = Vec::new();
    for version in ["3", "2"] {
        built_ball(dir.path(), version);
        let graph = ball_graph(dir.path(), &format!("ball{version}.fmu"), DOPRI, "e: 0.8");
        let rows = ball_rows(&graph);
        let found = impacts(&rows);
        assert!(found.len() >= 4, "FMI {version}: impacts {found:?}");
        for (t, want) in found.iter().zip(&closed) {
            assert!((t - want).abs() < 1e-9, "FMI {version}: an impact at {t}, the closed form {want}");
        }
        assert!(rows.iter().all(|r| r[1] > -1e-9), "FMI {version}: the floor holds");
        // Right after the first impact, v = e·v1 (the FMU's event reset, taken into the solver's state).
        let rebound = rows.iter().find(|r| r[0] == found[0]).unwrap()[2];
        assert!((rebound - e * g * t1).abs() < 1e-7, "FMI {version}: rebound at {rebound}");
        by_version.push(rows);
    }
    // One C model behind both interfaces: the same numbers.
    assert_eq!(by_version[0], by_version[1]);
    // The same FMU under TR-BDF2 (its Jacobian by finite differences).
    let graph = ball_graph(
        dir.path(),
        "ball3.fmu",
        "{ method: trbdf2, rtol: 1.0e-8, atol: 1.0e-10, max_step: 0.05 }",
        "e: 0.8",
    );
    let first = impacts(&ball_rows(&graph))[0];
    assert!((first - closed[0]).abs() < 1e-6, "TR-BDF2: the first impact at {first}");
}

#[test]
fn a_model_exchange_fmus_time_event_is_a_major_step_and_its_state_jump_is_taken() {
    let dir = tempfile::tempdir().unwrap();
    built_ball(dir.path(), "3");
    // At t = 0.5 the FMU adds 3 m/s to v (a time event it schedules).
    let graph = ball_graph(dir.path(), "ball3.fmu", DOPRI, "kick: 3, t_kick: 0.5");
    let rows = ball_rows(&graph);
    let at = rows.iter().position(|r| r[0] == 0.5).expect("a major step exactly at the time event");
    let (before, after) = (rows[at - 1], rows[at]);
    assert!((after[2] - (-9.81 * 0.5 + 3.0)).abs() < 1e-9, "v after the kick: {after:?} (before {before:?})");
    assert!((after[1] - (10.0 - 0.5 * 9.81 * 0.25)).abs() < 1e-9, "h is continuous: {after:?}");
}

#[test]
fn an_fmu_that_fails_in_a_step_stops_the_run_at_the_block_with_what_it_said() {
    let dir = tempfile::tempdir().unwrap();
    // A plant whose output is 1/(u − 1): infinite, inside the FMU, once u = 1.
    let plant = dir.path().join("pole.yaml");
    std::fs::write(
        &plant,
        "simulation: { stop: 5, solver: { method: rk4, step: 0.01 } }\nblocks:\n  u: { type: inport }\n  \
         f: { type: fcn, inputs: 1, expr: \"1/(u1 - 1)\" }\n  y: { type: outport }\nwires: [u -> f, f -> y]\n",
    )
    .unwrap();
    let fmu = dir.path().join("pole.fmu");
    let out = ctlgraph(&["fmu", plant.to_str().unwrap(), "--out", fmu.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let graph = dir.path().join("drive.yaml");
    std::fs::write(
        &graph,
        "simulation: { stop: 3, solver: { method: rk4, step: 0.01 } }\nblocks:\n  r: { type: ramp, slope: 1 }\n  \
         p: { type: fmu, file: pole.fmu, sample_time: 0.1 }\nwires: [r -> p]\nrecord: [p]\n",
    )
    .unwrap();
    let out = ctlgraph(&["run", graph.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    assert!(err.contains("block `p`") && err.contains("drive.yaml:4:3)"), "{err}");
    assert!(err.contains("returned error (the FMU said:") && err.contains("fmi3DoStep"), "{err}");
}
