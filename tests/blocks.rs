//! Every library block in a small graph, against values computed by hand;
//! and every block of every registered type keeping the promises of the
//! `Block` trait (ctlgraph_blocks::testing::conformance), checked on every
//! block of the bundled graphs and of `tests/data/every_block.yaml`, which
//! has the types no bundled graph uses.

mod common;
use common::{max_error, run};
use ctlgraph::blocks::testing::conformance::check_model;
use std::collections::BTreeSet;
use std::path::PathBuf;

/// A graph on a fixed 0.01 s grid for 1 s with the given blocks and wires.
fn graph(blocks: &str, wires: &str, record: &str) -> String {
    format!(
        "simulation: {{ stop: 1.0, solver: {{ method: rk4, step: 0.01 }} }}\nblocks:\n{blocks}wires: [{wires}]\nrecord: [{record}]\n"
    )
}

#[test]
fn sources() {
    let yaml = graph(
        "  c: { type: constant, value: 2.5 }\n  r: { type: ramp, slope: 2, start: 0.5, initial: 1 }\n\
         \x20 s: { type: sine, amplitude: 2, frequency: 3, phase: 0.5, bias: 1 }\n  k: { type: clock }\n",
        "",
        "c, r, s, k",
    );
    let trace = run(&yaml);
    assert_eq!(max_error(&trace, "c", |_| 2.5), 0.0);
    assert!(max_error(&trace, "r", |t| if t > 0.5 { 1.0 + 2.0 * (t - 0.5) } else { 1.0 }) < 1e-12);
    assert!(max_error(&trace, "s", |t| 1.0 + 2.0 * (6.0 * std::f64::consts::PI * t + 0.5).sin()) < 1e-12);
    assert_eq!(max_error(&trace, "k", |t| t), 0.0);
}

#[test]
fn elementwise_math_on_vectors_with_scalar_broadcast() {
    let yaml = graph(
        "  v: { type: constant, value: [1, -2, 3] }\n  w: { type: constant, value: [4, 5, -6] }\n\
         \x20 two: { type: constant, value: 2 }\n\
         \x20 g: { type: gain, k: [1, 10, 100] }\n  s: { type: sum, signs: \"+-+\" }\n\
         \x20 p: { type: product, ops: \"**/\" }\n  d: { type: divide }\n  a: { type: abs }\n  sg: { type: sign }\n\
         \x20 mn: { type: min }\n  mx: { type: max, inputs: 1 }\n  tot: { type: sum, signs: \"-\" }\n",
        "v -> g, v -> s.u1, w -> s.u2, two -> s.u3, v -> p.u1, w -> p.u2, two -> p.u3, w -> d.u1, two -> d.u2, \
         v -> a, v -> sg, v -> mn.u1, w -> mn.u2, w -> mx, w -> tot",
        "g, s, p, d, a, sg, mn, mx, tot",
    );
    let trace = run(&yaml);
    let row = |name: &str| -> Vec<f64> {
        let cols: Vec<usize> = trace
            .headers
            .iter()
            .enumerate()
            .filter(|(_, h)| h.starts_with(&format!("{name}[")))
            .map(|(i, _)| i)
            .collect();
        if cols.is_empty() {
            return vec![*trace.column(name).unwrap().last().unwrap()];
        }
        cols.iter().map(|&c| *trace.columns[c].last().unwrap()).collect()
    };
    assert_eq!(row("g"), [1.0, -20.0, 300.0]);
    assert_eq!(row("s"), [1.0 - 4.0 + 2.0, -2.0 - 5.0 + 2.0, 3.0 + 6.0 + 2.0]);
    assert_eq!(row("p"), [2.0, -5.0, -9.0]);
    assert_eq!(row("d"), [2.0, 2.5, -3.0]);
    assert_eq!(row("a"), [1.0, 2.0, 3.0]);
    assert_eq!(row("sg"), [1.0, -1.0, 1.0]);
    assert_eq!(row("mn"), [1.0, -2.0, -6.0]);
    assert_eq!(row("mx"), [5.0]);
    assert_eq!(row("tot"), [-3.0]);
    assert_eq!(trace.headers[1..4], ["g[1]", "g[2]", "g[3]"]);
}

#[test]
fn scalar_sums_and_gains_run_in_place_as_their_blocks_would() {
    // The scheduler runs scalar sums and gains from their kernels (no call
    // into the block), in major and minor steps; vector ones go through
    // `output`. x' = 3t - 1 is read in RK4's stages, which integrate it
    // exactly (to rounding).
    let yaml = graph(
        "  k: { type: clock }\n  one: { type: constant, value: 1 }\n  g: { type: gain, k: 3 }\n\
         \x20 s: { type: sum, signs: \"+-\" }\n  x: { type: integrator }\n\
         \x20 two: { type: constant, value: [1, 2] }\n  v: { type: sum, signs: \"-+\" }\n",
        "k -> g, g -> s.u1, one -> s.u2, s -> x, two -> v.u1, s -> v.u2",
        "s, x, v",
    );
    let trace = run(&yaml);
    assert_eq!(max_error(&trace, "s", |t| 3.0 * t - 1.0), 0.0);
    assert!(max_error(&trace, "x", |t| 1.5 * t * t - t) < 1e-12);
    assert_eq!(max_error(&trace, "v[1]", |t| 3.0 * t - 1.0 - 1.0), 0.0);
    assert_eq!(max_error(&trace, "v[2]", |t| 3.0 * t - 1.0 - 2.0), 0.0);
}

#[test]
fn a_run_of_kernels_carries_each_output_to_the_next() {
    // Consecutive kernels run in one loop that hands each output to the
    // next in a register (`Inline::run_all`): a sum reading the gain before
    // it as its first input, a sum reading the sum before it as its second,
    // a gain after them, and a demux's copy inside a later run. Every value
    // is exact (doublings and halvings of t), in major and minor steps.
    let yaml = graph(
        "  k: { type: clock }\n  g1: { type: gain, k: 2 }\n  s1: { type: sum, signs: \"+-\" }\n\
         \x20 s2: { type: sum, signs: \"++\" }\n  g2: { type: gain, k: -0.5 }\n\
         \x20 m: { type: mux, widths: [1, 1] }\n  d: { type: demux, widths: [1, 1] }\n\
         \x20 g3: { type: gain, k: 4 }\n  x: { type: integrator }\n",
        "k -> g1, g1 -> s1.u1, k -> s1.u2, k -> s2.u1, s1 -> s2.u2, s2 -> g2, g2 -> m.u1, k -> m.u2, m -> d, \
         d.y1 -> g3, g3 -> x",
        "s1, s2, g2, g3, x",
    );
    let trace = run(&yaml);
    assert_eq!(max_error(&trace, "s1", |t| t), 0.0);
    assert_eq!(max_error(&trace, "s2", |t| 2.0 * t), 0.0);
    assert_eq!(max_error(&trace, "g2", |t| -t), 0.0);
    assert_eq!(max_error(&trace, "g3", |t| -4.0 * t), 0.0);
    assert!(max_error(&trace, "x", |t| -2.0 * t * t) < 1e-12);
}

#[test]
fn demuxes_copy_in_place_in_major_and_minor_steps() {
    // A demux runs as a copy on the signal buffer (`Kernel::Copy`), also
    // in RK4's stages, where the integrator reads its second output: x' = 3t
    // is integrated exactly (to rounding). Outputs of widths 2 and 1.
    let yaml = graph(
        "  k: { type: clock }\n  g: { type: gain, k: 3 }\n  one: { type: constant, value: 1 }\n\
         \x20 m: { type: mux, widths: [1, 1, 1] }\n  d: { type: demux, widths: [2, 1] }\n\
         \x20 x: { type: integrator }\n",
        "k -> g, k -> m.u1, one -> m.u2, g -> m.u3, m -> d, d.y2 -> x",
        "d.y1, d.y2, x",
    );
    let trace = run(&yaml);
    assert_eq!(max_error(&trace, "d.y1[1]", |t| t), 0.0);
    assert_eq!(max_error(&trace, "d.y1[2]", |_| 1.0), 0.0);
    assert_eq!(max_error(&trace, "d.y2", |t| 3.0 * t), 0.0);
    assert!(max_error(&trace, "x", |t| 1.5 * t * t) < 1e-12);
}

#[test]
fn matrix_gain_and_routing() {
    let yaml = graph(
        "  a: { type: constant, value: 1 }\n  b: { type: constant, value: [2, 3] }\n\
         \x20 m: { type: mux, widths: [1, 2] }\n  k: { type: gain, k: [[1, 0, 0], [0, 1, 1]] }\n\
         \x20 d: { type: demux, widths: [2, 1] }\n  sel: { type: selector, indices: [3, 1, 3] }\n\
         \x20 c: { type: step, at: 0.5, initial: -1, value: 1 }\n  sw: { type: switch, threshold: 0 }\n",
        "a -> m.u1, b -> m.u2, m -> k, m -> d, m -> sel, b -> sw.u1, c -> sw.control, sel -> sw.u2",
        "k, d.y1, d.y2, sel, sw",
    );
    let err = common::error(&yaml);
    assert!(err.message.contains("width mismatch"), "u2 of the switch is 3 wide: {err}");
    let yaml = yaml.replace("sel -> sw.u2", "k -> sw.u2");
    let trace = run(&yaml);
    let last = |h: &str| *trace.column(h).unwrap().last().unwrap();
    assert_eq!([last("k[1]"), last("k[2]")], [1.0, 5.0]);
    assert_eq!([last("d.y1[1]"), last("d.y1[2]"), last("d.y2")], [1.0, 2.0, 3.0]);
    assert_eq!([last("sel[1]"), last("sel[2]"), last("sel[3]")], [3.0, 1.0, 3.0]);
    // Before 0.5 the control is -1 < 0: u2 (= k); from 0.5 on u1 (= b).
    assert_eq!(trace.at("sw[2]", 0.25), Some(5.0));
    assert_eq!(last("sw[2]"), 3.0);
}

#[test]
fn static_nonlinearities_and_tables() {
    let yaml = graph(
        "  r: { type: ramp, slope: 4, initial: -2 }\n  dz: { type: dead_zone, start: -0.5, end: 1 }\n\
         \x20 lut: { type: lookup_table_1d, x: [-1, 0, 1], y: [2, 0, 4] }\n\
         \x20 lin: { type: lookup_table_1d, x: [-1, 0, 1], y: [2, 0, 4], extrapolation: linear }\n\
         \x20 f: { type: fcn, inputs: 2, expr: \"u1^2 + max(u2, 0) + t\" }\n  one: { type: constant, value: 1 }\n",
        "r -> dz, r -> lut, r -> lin, r -> f.u1, one -> f.u2",
        "r, dz, lut, lin, f",
    );
    let trace = run(&yaml);
    let u = |t: f64| -2.0 + 4.0 * t;
    assert!(
        max_error(&trace, "dz", |t| if u(t) > 1.0 {
            u(t) - 1.0
        } else if u(t) < -0.5 {
            u(t) + 0.5
        } else {
            0.0
        }) < 1e-12
    );
    let table = |x: f64| if x < 0.0 { -2.0 * x } else { 4.0 * x };
    assert!(max_error(&trace, "lut", |t| table(u(t).clamp(-1.0, 1.0))) < 1e-12);
    assert!(max_error(&trace, "lin", |t| table(u(t))) < 1e-12);
    assert!(max_error(&trace, "f", |t| u(t).powi(2) + 1.0 + t) < 1e-12);
}

#[test]
fn filtered_derivative_of_a_ramp() {
    // s/(τs + 1) of a ramp of slope 3: y = 3(1 − e^{−t/τ}).
    let yaml = "simulation: { stop: 0.5, solver: { method: rk4, step: 1.0e-4 } }\n\
                blocks:\n  r: { type: ramp, slope: 3 }\n  d: { type: derivative, tau: 0.01 }\n\
                wires: [r -> d]\nrecord: [d]\n";
    let trace = run(yaml);
    assert!(max_error(&trace, "d", |t| 3.0 * (1.0 - (-t / 0.01).exp())) < 1e-9);
}

#[test]
fn integrator_on_a_vector_signal() {
    let yaml = "simulation: { stop: 1.0, solver: { method: rk4, step: 0.01 } }\n\
                blocks:\n  c: { type: constant, value: [1, -2] }\n  i: { type: integrator, initial: [0, 5] }\n\
                wires: [c -> i]\nrecord: [i]\n";
    let trace = run(yaml);
    assert!(max_error(&trace, "i[1]", |t| t) < 1e-12);
    assert!(max_error(&trace, "i[2]", |t| 5.0 - 2.0 * t) < 1e-12);
}

#[test]
fn from_csv_interpolates_a_time_series() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("data.csv"), "t,force\n0,0\n0.5,1\n0.5,3\n1,2\n").unwrap();
    let graph_file = dir.path().join("g.yaml");
    std::fs::write(
        &graph_file,
        "simulation: { stop: 1.5, solver: { method: rk4, step: 0.05 } }\n\
         blocks:\n  f: { type: from_csv, file: data.csv, column: force }\n\
         \x20 z: { type: from_csv, file: data.csv, column: force, extrapolation: zero }\nrecord: [f, z]\n",
    )
    .unwrap();
    let model = ctlgraph::compile_file(&graph_file, &[]).unwrap();
    let trace = ctlgraph::simulate(model, None).unwrap();
    assert_eq!(trace.at("f", 0.25), Some(0.5));
    assert_eq!(trace.at("f", 0.75), Some(2.5));
    assert_eq!(*trace.column("f").unwrap().last().unwrap(), 2.0, "held after the data");
    assert_eq!(*trace.column("z").unwrap().last().unwrap(), 0.0, "zero after the data");

    std::fs::write(&graph_file, "blocks:\n  f: { type: from_csv, file: data.csv, column: forse }\n").unwrap();
    let d = ctlgraph::compile_file(&graph_file, &[]).err().unwrap();
    assert!(d.message.contains("has no column `forse` (columns: t, force)"), "{d}");
}

#[test]
fn pid_gains_from_input_ports() {
    // kp arrives on a port and doubles at t = 0.5; ki on a port too. With
    // e = 1: u = kp(t) + ∫ki dt, and the integral does not jump when ki does.
    let yaml = graph(
        "  e: { type: constant, value: 1 }\n  kp: { type: step, at: 0.5, initial: 1, value: 2 }\n\
         \x20 ki: { type: step, at: 0.5, initial: 4, value: 0 }\n\
         \x20 pid: { type: pid, gain_inputs: [kp, ki], kp: 100, ki: 100 }\n",
        "e -> pid.e, kp -> pid.kp, ki -> pid.ki",
        "pid",
    );
    let trace = run(&yaml);
    let err = max_error(&trace, "pid", |t| if t < 0.5 { 1.0 + 4.0 * t } else { 2.0 + 2.0 });
    assert!(err < 1e-12, "max error {err}");
}

#[test]
fn a_block_whose_events_stop_time_is_reported_not_looped_on() {
    use ctlgraph::core::registry::{BlockType, Built};
    use ctlgraph::core::{Block, Diagnostic, Interface, Io, Params, SampleTime, Width};
    // Events every 1e-300 s from t = 1: not representable there, so time
    // would stand still.
    #[derive(Clone)]
    struct Stuck;
    impl Block for Stuck {
        fn output(&mut self, io: &mut Io) {
            io.set(0, 0.0);
        }
        fn next_event(&self, t: f64) -> f64 {
            if t < 1.0 { 1.0 } else { t + 1e-300 }
        }
    }
    fn build(_: &mut Params) -> Result<Built, Diagnostic> {
        Ok(Built::new(Stuck, Interface::new(SampleTime::Continuous).output("y", Width::Fixed(1))))
    }
    let mut reg = ctlgraph::registry();
    reg.register(BlockType {
        name: "stuck",
        category: "test",
        summary: "events that do not advance",
        doc: "test",
        inputs: &[],
        outputs: &[],
        params: &[],
        build,
    });
    let flat = ctlgraph::core::load_str(
        "simulation: { stop: 2.0 }\nblocks:\n  s: { type: stuck }\n",
        "stuck.yaml".into(),
        &[],
    )
    .unwrap();
    let model = ctlgraph::core::compile(&flat, &reg).unwrap();
    let error = ctlgraph::simulate(model, None).unwrap_err().to_string();
    assert!(error.contains("t = 1: time does not advance: block `s`"), "{error}");
}

#[test]
fn every_block_of_every_registered_type_keeps_its_promises() {
    // Not the subsystem libraries (`lib/`): their blocks are checked where they are used.
    let mut graphs: Vec<PathBuf> =
        common::bundled_graphs().into_iter().filter(|g| !g.components().any(|c| c.as_os_str() == "lib")).collect();
    graphs.push(PathBuf::from("tests/data/every_block.yaml"));
    // The `fmu` block, on a plant `ctlgraph fmu` exports (FMUs are not kept in the repository).
    let dir = tempfile::tempdir().unwrap();
    graphs.push(graph_with_an_fmu(dir.path()));
    let (mut broken, mut seen) = (Vec::new(), BTreeSet::new());
    for graph in &graphs {
        let model = ctlgraph::compile_file(graph, &[]).unwrap_or_else(|d| panic!("{}: {d}", graph.display()));
        seen.extend(model.meta.iter().map(|m| m.type_name.clone()));
        broken.extend(check_model(&model).into_iter().map(|b| format!("{}: {b}", graph.display())));
        broken.extend(undocumented_ports(&model).into_iter().map(|b| format!("{}: {b}", graph.display())));
    }
    assert!(broken.is_empty(), "{}", broken.join("\n"));
    let registry = ctlgraph::registry();
    // Structure, not blocks: subsystems are flattened, their ports are wires.
    let structural = ["subsystem", "inport", "outport"];
    let unchecked: Vec<&str> = registry.names().filter(|n| !seen.contains(*n) && !structural.contains(n)).collect();
    assert!(unchecked.is_empty(), "no checked graph has a block of type {unchecked:?}");
}

/// A graph with an `fmu` block in `dir`, its FMU exported there from
/// `tests/fmu/plant_io.yaml`; this process unpacks it into the tests' cache.
fn graph_with_an_fmu(dir: &std::path::Path) -> PathBuf {
    let fmu = dir.join("plant.fmu");
    let out = common::ctlgraph(&["fmu", "tests/fmu/plant_io.yaml", "--out", fmu.to_str().unwrap()]);
    assert!(out.status.success(), "{}", common::text(&out.stderr));
    ctlgraph::core::files::set_cache_base(common::accelerate_cache());
    let graph = dir.join("fmu.yaml");
    let text = "simulation: { stop: 1, solver: { method: rk4, step: 0.01 } }\n\
                blocks:\n  u: { type: constant, value: [1, 2] }\n  plant: { type: fmu, file: plant.fmu, sample_time: 0.05 }\n\
                wires: [u -> plant.u]\n";
    std::fs::write(&graph, text).unwrap();
    graph
}

/// The ports of `model`'s blocks that their type's documentation does not
/// name: each built port must be one the type's port table lists (a name
/// written `u1 … un` stands for its numbered family, one in parentheses
/// for ports the graph names, as a fuzzy system's). The table and the
/// constructor both name ports; this keeps them saying the same.
fn undocumented_ports(model: &ctlgraph::core::Model) -> Vec<String> {
    let registry = ctlgraph::registry();
    let documented = |docs: &[ctlgraph::core::PortDoc], name: &str| {
        docs.iter().any(|d| {
            d.name == name
                || d.name.starts_with('(')
                || d.name.split(|c: char| c == ',' || c.is_whitespace()).any(|n| n == name)
                || (d.name.contains('…') && {
                    let stem: String = d.name.chars().take_while(|c| c.is_alphabetic()).collect();
                    name.strip_prefix(stem.as_str()).is_some_and(|k| k.chars().all(|c| c.is_ascii_digit()))
                })
        })
    };
    let mut missing = Vec::new();
    for m in &model.meta {
        let Some(t) = registry.get(&m.type_name) else { continue };
        for (side, names, docs) in [("input", &m.input_names, t.inputs), ("output", &m.output_names, t.outputs)] {
            for name in names.iter().filter(|n| !documented(docs, n)) {
                missing.push(format!("block `{}` ({}): {side} `{name}` is not in its port table", m.name, m.type_name));
            }
        }
    }
    missing
}
