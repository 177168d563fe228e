//! `ctlgraph sweep`: the cases a command designs, determinism over jobs and
//! shards, failing cases as rows, and the merge's checks; and each case
//! compiled on the structure of the model before it (what a sweep and
//! Python's graph cache do): bit for bit a full compile.

mod common;
use common::{ctlgraph, path, text};
use ctlgraph_core::{load, load_str, recompile, reuse_structure, trace::simulate};

const PID: &str = "graphs/tutorial/pid_loop.yaml";

#[test]
fn cases_cross_grids_lists_draws_and_seeds_in_a_fixed_order() {
    use ctlgraph::sweep::{SweepSpec, Vary, cases};
    let spec = |vary: Vec<&str>, random, seeds| SweepSpec {
        vary: vary.into_iter().map(|v| Vary::parse(v).unwrap()).collect(),
        random,
        seeds,
        draw_seed: 7,
        shard: None,
    };
    let grid = cases(&spec(vec!["a=0..1:3", "b=5,6"], None, Some((1, 2)))).unwrap();
    let got: Vec<(f64, f64, u64)> = grid.iter().map(|c| (c.values[0], c.values[1], c.seed.unwrap())).collect();
    let mut want = Vec::new();
    for a in [0.0, 0.5, 1.0] {
        for b in [5.0, 6.0] {
            want.extend([(a, b, 1), (a, b, 2)]);
        }
    }
    assert_eq!(got, want);
    assert!(grid.iter().enumerate().all(|(i, c)| c.index == i));
    // Random draws: within the range, and the same for the same draw seed.
    let drawn = cases(&spec(vec!["k=2..3"], Some(50), None)).unwrap();
    assert_eq!(drawn.len(), 50);
    assert!(drawn.iter().all(|c| (2.0..3.0).contains(&c.values[0])));
    assert_eq!(drawn, cases(&spec(vec!["k=2..3"], Some(50), None)).unwrap());
    // Mistakes.
    assert!(Vary::parse("k=3..2:4").is_err() && Vary::parse("k=1..2:1").is_err() && Vary::parse("k=a,b").is_err());
    assert!(cases(&spec(vec!["k=2..3"], None, None)).is_err(), "a range needs --random");
    assert!(cases(&spec(vec!["k=1,2", "k=3,4"], None, None)).is_err(), "a parameter given twice");
}

#[test]
fn the_table_is_the_same_whatever_the_jobs_and_shards() {
    let dir = tempfile::tempdir().unwrap();
    let out = |name: &str| dir.path().join(name);
    let args = ["sweep", PID, "--vary", "kp=1..4:5", "--vary", "kd=0,0.1,0.3"];
    let run = |extra: &[&str]| {
        let mut all: Vec<&str> = args.to_vec();
        all.extend_from_slice(extra);
        let o = ctlgraph(&all);
        assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
        o
    };
    let one = out("one.csv");
    let printed = run(&["--jobs", "1", "--out", path(&one)]);
    assert!(text(&printed.stdout).starts_with("15 case(s): 15 ran, 0 failed to run"), "{}", text(&printed.stdout));
    let two = out("two.csv");
    run(&["--jobs", "2", "--out", path(&two)]);
    let whole = std::fs::read(&one).unwrap();
    assert_eq!(whole, std::fs::read(&two).unwrap(), "jobs change nothing");
    let shards: Vec<_> = (0..4).map(|k| out(&format!("s{k}.csv"))).collect();
    for (k, s) in shards.iter().enumerate() {
        run(&["--shard", &format!("{k}/4"), "--out", path(s)]);
    }
    let merged = out("merged.csv");
    let mut merge = vec!["sweep", "merge"];
    merge.extend(shards.iter().map(|s| path(s)));
    merge.extend(["--out", path(&merged)]);
    assert_eq!(ctlgraph(&merge).status.code(), Some(0));
    assert_eq!(std::fs::read(&merged).unwrap(), whole, "4 shards merged = the unsharded table, byte for byte");
    // A missing shard or one given twice is refused.
    let o = ctlgraph(&[
        "sweep",
        "merge",
        path(&shards[0]),
        path(&shards[1]),
        path(&shards[1]),
        "--out",
        path(&out("bad.csv")),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("is twice"), "{}", text(&o.stderr));
    let o = ctlgraph(&["sweep", "merge", path(&shards[0]), path(&shards[1]), "--out", path(&out("bad.csv"))]);
    assert!(text(&o.stderr).contains("is missing"), "{}", text(&o.stderr));
    // The table has the parameters, each check measured and its verdict.
    let table = String::from_utf8(whole).unwrap();
    let header = table.lines().next().unwrap();
    assert!(
        header.starts_with("case,kp,kd,seed,\"overshoot(y, 1.0, 0.1) < 15\",")
            && header.ends_with(",status,error,cases")
    );
    assert_eq!(table.lines().count(), 16);
}

#[test]
fn a_failing_case_is_a_row_not_the_end() {
    // x' = a·x from 1 for 1 s: a = 1000 overflows, a = 1 does not.
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("growth.yaml");
    let yaml = r#"
parameters: { a: 1 }
simulation: { stop: 1.0, solver: { method: rk4, step: 1.0e-3 } }
blocks:
  x: { type: integrator, initial: 1 }
  k: { type: gain, k: a }
wires: [x -> k, k -> x]
record: [x]
checks:
  - "final_value(x) < 3"
"#;
    std::fs::write(&graph, yaml).unwrap();
    let out = dir.path().join("t.csv");
    let o = ctlgraph(&["sweep", path(&graph), "--vary", "a=1000,1", "--out", path(&out)]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let table = std::fs::read_to_string(&out).unwrap();
    let rows: Vec<&str> = table.lines().skip(1).collect();
    assert_eq!(rows.len(), 2, "{table}");
    assert!(
        rows[0].starts_with("0,1000,,,,failed,t = ") && rows[0].contains("block `x`: state 0 is inf"),
        "{}",
        rows[0]
    );
    assert!(rows[1].starts_with("1,1,,2.718"), "{}", rows[1]);
    assert!(text(&o.stdout).contains("2 case(s): 1 ran, 1 failed to run"), "{}", text(&o.stdout));
}

/// Exact to the bit (Debug prints each f64's shortest round-trip form).
fn bits(model: ctlgraph_core::Model, stop: f64) -> String {
    format!("{:?}", simulate(model, Some(stop)).expect("runs"))
}

#[test]
fn a_value_changed_compiles_on_the_structure_and_runs_as_a_full_compile() {
    let registry = ctlgraph::registry();
    let mut reused = 0;
    for graph in common::bundled_graphs().iter().filter(|g| !g.components().any(|c| c.as_os_str() == "lib")) {
        let base = ctlgraph::compile_file(graph, &[]).unwrap_or_else(|d| panic!("{}: {d}", graph.display()));
        let Some((name, value)) = base.parameters.first().cloned() else { continue };
        let changed = if value == 0.0 { 0.5 } else { value * 1.25 };
        let flat = load(graph, &[(name.clone(), format!("{changed:e}"))]).unwrap();
        let Ok(full) = ctlgraph_core::compile(&flat, &registry) else { continue };
        let stop = (base.sim.stop).min(0.05);
        if reuse_structure(&base, &flat, &registry).unwrap().is_some() {
            reused += 1;
        }
        let on_structure = recompile(&base, &flat, &registry).unwrap();
        assert_eq!(bits(on_structure, stop), bits(full, stop), "{} with {name} = {changed}", graph.display());
    }
    assert!(reused >= 10, "only {reused} graphs compiled on their structure");
}

#[test]
fn a_value_that_changes_the_structure_compiles_whole() {
    let text = "parameters: { ts: 0.01, k: 2 }\nsimulation: { stop: 0.2 }\nblocks:\n  u: { type: sine }\n  \
                h: { type: zero_order_hold, sample_time: ts }\n  g: { type: gain, k: k }\nwires: [u -> h, h -> g]\n";
    let registry = ctlgraph::registry();
    let base = ctlgraph_core::compile(&load_str(text, "s.yaml".into(), &[]).unwrap(), &registry).unwrap();
    let gain = load_str(text, "s.yaml".into(), &[("k".into(), "3".into())]).unwrap();
    assert!(reuse_structure(&base, &gain, &registry).unwrap().is_some(), "a gain's value keeps the structure");
    let rate = load_str(text, "s.yaml".into(), &[("ts".into(), "0.02".into())]).unwrap();
    assert!(reuse_structure(&base, &rate, &registry).unwrap().is_none(), "a sample time changes it");
    let full = ctlgraph_core::compile(&rate, &registry).unwrap();
    assert_eq!(bits(recompile(&base, &rate, &registry).unwrap(), 0.2), bits(full, 0.2));
}

#[test]
fn the_graph_cache_gives_what_a_fresh_compile_gives_and_sees_an_edited_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("loop.yaml");
    let graph = |den: &str| {
        format!(
            "parameters: {{ k: 2 }}\nsimulation: {{ stop: 1 }}\nblocks:\n  r: {{ type: step }}\n  e: {{ type: sum, signs: \"+-\" }}\n  \
             c: {{ type: gain, k: k }}\n  p: {{ type: transfer_function, num: [1], den: {den} }}\n\
             wires: [r -> e.u1, p -> e.u2, e -> c, c -> p]\nrecord: [y: p]\n"
        )
    };
    std::fs::write(&path, graph("[1, 1]")).unwrap();
    let cache = ctlgraph::cache::GraphCache::new();
    for (k, den) in [("2", "[1, 1]"), ("3", "[1, 1]"), ("3", "[1, 2, 1]")] {
        std::fs::write(&path, graph(den)).unwrap();
        let sets = [("k".to_string(), k.to_string())];
        let cached = cache.compile(&path, &sets, None).unwrap();
        let fresh = ctlgraph::compile_file_seeded(&path, &sets, None).unwrap();
        assert_eq!(cached.n_states, fresh.n_states, "den {den}");
        assert_eq!(bits(cached, 1.0), bits(fresh, 1.0), "k = {k}, den {den}");
    }
}
