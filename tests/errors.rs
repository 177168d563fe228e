//! Every kind of mistake in a graph file gets `file:line:col: message`,
//! names the block and key, and offers a hint where one helps.

mod common;
use common::{error, run};

/// Asserts position, a message fragment, and optionally a hint fragment.
fn check(yaml: &str, line: u32, col: u32, message: &str, hint: Option<&str>) {
    let d = error(yaml);
    let pos = d.pos.clone().unwrap_or_else(|| panic!("no position in: {d}"));
    assert_eq!((pos.line, pos.col), (line, col), "position of: {d}");
    assert!(d.to_string().starts_with(&format!("test.yaml:{line}:{col}: ")), "{d}");
    assert!(d.message.contains(message), "message `{}` lacks `{message}`", d.message);
    if let Some(h) = hint {
        let got = d.hint.clone().unwrap_or_default();
        assert!(got.contains(h), "hint `{got}` lacks `{h}`");
    }
}

const PLANT: &str = "  plant: { type: transfer_function, num: [1], den: [1, 1] }\n";

#[test]
fn unknown_block_type_suggests_the_closest() {
    let yaml = "blocks:\n  p: { type: transfer_fuction, num: [1], den: [1, 1] }\n";
    check(yaml, 2, 14, "block `p`: unknown block type `transfer_fuction`", Some("did you mean `transfer_function`?"));
}

#[test]
fn unknown_parameter_names_block_and_key() {
    let yaml =
        format!("blocks:\n  u: {{ type: step }}\n  g: {{ type: gain, gian: 2 }}\n{PLANT}wires: [u -> g, g -> plant]\n");
    check(&yaml, 3, 20, "block `g` (gain): unknown parameter `gian`", Some("gain takes: k, sample_time"));
}

#[test]
fn missing_parameter() {
    let yaml = "blocks:\n  u: { type: step }\n  plant: { type: transfer_function, num: [1] }\nwires: [u -> plant]\n";
    check(
        yaml,
        3,
        3,
        "block `plant` (transfer_function): missing parameter `den`",
        Some("ctlgraph blocks transfer_function"),
    );
}

#[test]
fn wrong_parameter_type_and_shape() {
    let yaml = "blocks:\n  u: { type: step, at: [1, 2] }\n";
    check(yaml, 2, 24, "block `u` (step): `at`: expected a number, found a list", None);
    let yaml = "blocks:\n  u: { type: step }\n  plant: { type: transfer_function, num: { a: 1 }, den: [1, 1] }\nwires: [u -> plant]\n";
    check(yaml, 3, 42, "`num`: expected a list of numbers, found a mapping", None);
    let yaml = "blocks:\n  s: { type: state_space, A: [[0, 1]], B: [[0], [1]], C: [[1, 0]] }\n";
    check(yaml, 2, 30, "A must be square", None);
}

#[test]
fn limits_in_the_wrong_order_are_refused_with_the_hint_to_swap_them() {
    let yaml =
        "blocks:\n  s: { type: sine }\n  r: { type: relay, on_threshold: -0.5, off_threshold: 0.5 }\nwires: [s -> r]\n";
    check(
        yaml,
        3,
        35,
        "`on_threshold` (-0.5) must be >= `off_threshold` (0.5)",
        Some("swap them: `off_threshold: -0.5, on_threshold: 0.5`"),
    );
    let yaml = "blocks:\n  u: { type: step }\n  l: { type: saturation, lower: 1, upper: -1 }\nwires: [u -> l]\n";
    check(yaml, 3, 43, "`upper` (-1) must be >= `lower` (1)", Some("swap them: `lower: -1, upper: 1`"));
}

#[test]
fn expression_errors_point_inside_the_string() {
    let yaml = "parameters:\n  w0: 1000\n  b: \"3*w00\"\n";
    check(yaml, 3, 9, "parameter `b`: unknown name `w00`", Some("did you mean `w0`?"));
    let yaml = "parameters:\n  k: 2\nblocks:\n  g: { type: constant, value: [1, \"k +\"] }\n";
    check(yaml, 4, 39, "block `g` (constant): `value`: expression ends too early", None);
}

#[test]
fn duplicate_names() {
    let yaml = "blocks:\n  u: { type: step }\n  u: { type: clock }\n";
    check(yaml, 3, 3, "duplicate key `u`", None);
}

#[test]
fn wire_to_a_missing_block_or_port() {
    let yaml = format!("blocks:\n  u: {{ type: step }}\n{PLANT}wires:\n  - u -> plnt\n");
    check(&yaml, 5, 10, "no block named `plnt`", Some("did you mean `plant`?"));
    let yaml = format!("blocks:\n  u: {{ type: step }}\n{PLANT}wires:\n  - u.out -> plant\n");
    check(&yaml, 5, 5, "block `u` (step) has no output `out`", Some("outputs: y"));
    let yaml = "blocks:\n  u: { type: step }\n  e: { type: sum, signs: \"+-\" }\nwires:\n  - u -> e\n";
    check(yaml, 5, 10, "has 2 inputs: name one as `e.PORT`", Some("inputs: u1, u2"));
}

#[test]
fn unwired_and_doubly_wired_inputs() {
    let yaml = "blocks:\n  u: { type: step }\n  e: { type: sum, signs: \"+-\" }\nwires:\n  - u -> e.u1\n";
    check(yaml, 3, 3, "input `u2` of block `e` is not wired", None);
    let yaml = format!(
        "blocks:\n  u: {{ type: step }}\n  v: {{ type: step }}\n{PLANT}wires:\n  - u -> plant\n  - v -> plant\n"
    );
    check(&yaml, 7, 10, "input `plant.u` is wired twice", Some("already fed at line 6"));
}

#[test]
fn width_mismatch() {
    let yaml =
        "blocks:\n  c: { type: constant, value: [1, 2, 3] }\n  m: { type: demux, outputs: 2 }\nwires:\n  - c -> m\n";
    check(yaml, 5, 10, "width mismatch: `c.y` carries 3 value(s) but `m.u` takes 2", Some("mux/demux/selector"));
}

#[test]
fn improper_transfer_function() {
    let yaml = "blocks:\n  u: { type: step }\n  d: { type: transfer_function, num: [1, 0, 0], den: [1, 1] }\nwires: [u -> d]\n";
    check(yaml, 3, 38, "improper transfer function: numerator degree 2 exceeds denominator degree 1", None);
}

#[test]
fn bad_sample_time() {
    let yaml = "blocks:\n  u: { type: step }\n  z: { type: unit_delay, sample_time: -2 }\nwires: [u -> z]\n";
    check(yaml, 3, 39, "bad sample time", Some("0 = continuous"));
    let yaml = "blocks:\n  u: { type: step }\n  z: { type: unit_delay, sample_time: [0.1, 0.2] }\nwires: [u -> z]\n";
    check(yaml, 3, 39, "bad sample time [0.1, 0.2]", None);
    let yaml = "blocks:\n  u: { type: step }\n  z: { type: unit_delay }\nwires: [u -> z]\n";
    check(yaml, 3, 3, "missing parameter `sample_time`", None);
}

#[test]
fn yaml_syntax_errors_are_positioned() {
    let d = error("blocks:\n  u: { type: step\n  v: 3\n");
    assert!(d.pos.is_some() && d.message.starts_with("YAML syntax"), "{d}");
}

#[test]
fn structural_mistakes() {
    check(
        "blocks:\n  u: { type: step }\nwire: []\n",
        3,
        1,
        "unknown top-level key `wire`",
        Some("did you mean `wires`?"),
    );
    check("simulation: { solver: { method: rk5, step: 0.1 } }\n", 1, 33, "unknown solver method `rk5`", Some("rk4"));
    check("simulation: { solver: rk4 }\n", 1, 23, "the fixed-step method `rk4` needs a `step`", None);
    check("simulation: { stop: -1 }\n", 1, 21, "must be a positive number", None);
    check("blocks:\n  u: { type: step }\nrecord: [u, u]\n", 3, 13, "`u` is recorded twice", None);
    check("blocks:\n  u: { type: step }\nrecord: [t: u]\n", 3, 13, "`t` is the time column", Some("rename it"));
    check(
        "blocks:\n  u: { type: step }\nrecord: [v]\n",
        3,
        10,
        "record: no block named `v`",
        Some("did you mean `u`?"),
    );
}

#[test]
fn set_of_an_unknown_parameter() {
    let yaml = "parameters: { tau: 1 }\nblocks:\n  u: { type: step }\n";
    let sets = [("tua".to_string(), "2".to_string())];
    let Err(d) = ctlgraph::compile_str(yaml, "test.yaml", &sets) else { panic!("accepted --set tua") };
    assert_eq!(d.message, "--set tua: test.yaml has no parameter `tua`");
    assert_eq!(d.hint.as_deref(), Some("did you mean `tau`?"));
}

#[test]
fn subsystem_errors_name_the_file_they_are_in() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("inner.yaml"),
        "parameters: { k: 1 }\nblocks:\n  x: { type: inport }\n  g: { type: gain, k: k, bogus: 1 }\n  y: { type: outport }\nwires: [x -> g, g -> y]\n",
    )
    .unwrap();
    let outer = dir.path().join("outer.yaml");
    std::fs::write(
        &outer,
        "blocks:\n  u: { type: step }\n  s: { type: subsystem, file: inner.yaml }\nwires: [u -> s]\n",
    )
    .unwrap();
    let d = ctlgraph::compile_file(&outer, &[]).err().expect("error inside the subsystem");
    let pos = d.pos.clone().unwrap();
    assert!(pos.file.ends_with("inner.yaml"), "{d}");
    assert_eq!((pos.line, pos.col), (4, 26));
    assert!(d.message.contains("block `s/g` (gain): unknown parameter `bogus`"), "{d}");

    std::fs::write(&outer, "blocks:\n  u: { type: step }\n  s: { type: subsystem, file: inner.yaml, parameters: { kk: 2 } }\nwires: [u -> s]\n")
        .unwrap();
    let d = ctlgraph::compile_file(&outer, &[]).err().unwrap();
    assert!(d.to_string().contains("outer.yaml:3:57: block `s` (subsystem)"), "{d}");
    assert_eq!(d.hint.as_deref(), Some("did you mean `k`?"));

    std::fs::write(
        &outer,
        "blocks:\n  u: { type: step }\n  s: { type: subsystem, file: missing.yaml }\nwires: [u -> s.z]\n",
    )
    .unwrap();
    let d = ctlgraph::compile_file(&outer, &[]).err().unwrap();
    assert!(d.to_string().contains("outer.yaml:3:31: block `s` (subsystem): cannot read"), "{d}");
}

#[test]
fn nothing_a_user_writes_panics() {
    // A grab bag of malformed inputs: every one must come back as an error.
    let cases = [
        "",
        "[]",
        "blocks: 3",
        "blocks: { a: 3 }",
        "blocks: { a: { type: 3 } }",
        "wires: [3]",
        "wires: [\"a -> \"]",
        "record: { every: 0, signals: [] }",
        "parameters: { a: [1] }",
        "simulation: 5",
        "blocks: { s: { type: selector, indices: [0] } }",
        "blocks: { m: { type: mux, widths: [0] } }",
        "blocks: { p: { type: pulse, duty: 1.5 } }",
        "blocks: { l: { type: lookup_table_1d, x: [1, 1], y: [1, 2] } }",
        "blocks: { f: { type: fcn, expr: \"u1 +* 2\" } }",
        "blocks: { i: { type: inport, width: 0 } }",
    ];
    for yaml in cases {
        let result = std::panic::catch_unwind(|| ctlgraph::compile_str(yaml, "test.yaml", &[]).err());
        match result {
            Ok(Some(_)) => {}
            Ok(None) if yaml.is_empty() || yaml == "[]" => panic!("`{yaml}` accepted"),
            Ok(None) => panic!("`{yaml}` accepted"),
            Err(_) => panic!("`{yaml}` panicked"),
        }
    }
}

/// The 1-based column of `needle` in line `line` of `yaml`.
fn col(yaml: &str, line: usize, needle: &str) -> u32 {
    let text = yaml.lines().nth(line - 1).unwrap();
    text.find(needle).unwrap_or_else(|| panic!("`{needle}` not in `{text}`")) as u32 + 1
}

#[test]
fn event_stiff_and_delay_settings_are_checked() {
    let stepped = "simulation: { solver: { method: trbdf2, step: 0.1 } }\n";
    check(stepped, 1, col(stepped, 1, "0.1"), "trbdf2 chooses its own steps", None);
    let zc = "simulation: { solver: { method: dopri5, zero_crossing: maybe } }\n";
    check(zc, 1, col(zc, 1, "maybe"), "`zero_crossing` must be true, false or adaptive", None);
    let typo = "simulation: { solver: { method: trbdf3 } }\n";
    check(typo, 1, col(typo, 1, "trbdf3"), "unknown solver method `trbdf3`", Some("trbdf2"));
    let delay = |params: &str| {
        format!("blocks:\n  u: {{ type: sine }}\n  d: {{ type: transport_delay, {params} }}\nwires: [u -> d]\n")
    };
    let negative = delay("delay: -1");
    check(&negative, 3, col(&negative, 3, "-1"), "block `d` (transport_delay): `delay`", None);
    let order = delay("delay: 1, order: 2");
    check(&order, 3, col(&order, 3, "2 }"), "must be 1 (linear), 3 (cubic) or 5 (quintic)", None);
    let relay =
        "blocks:\n  u: { type: sine }\n  r: { type: relay, on_threshold: -1, off_threshold: 1 }\nwires: [u -> r]\n";
    check(relay, 3, col(relay, 3, "-1"), "`on_threshold` (-1) must be >= `off_threshold` (1)", None);
    let reset = "blocks:\n  u: { type: sine }\n  i: { type: integrator, reset: raising }\nwires: [u -> i]\n";
    check(
        reset,
        3,
        col(reset, 3, "raising"),
        "`raising` is not one of: none, rising, falling, either, level",
        Some("rising"),
    );
}

#[test]
fn scope_and_unit_mistakes_are_positioned() {
    let base = "blocks:\n  u: { type: step }\nrecord:\n  - { u, unit: V }\nscopes:\n";
    let unknown = format!("{base}  - {{ signals: [u, v] }}\n");
    check(&unknown, 6, col(&unknown, 6, "v]"), "scope: `v` is not recorded", Some("did you mean `u`?"));
    let key = format!("{base}  - {{ signals: [u], ylabel: x }}\n");
    check(&key, 6, col(&key, 6, "ylabel"), "unknown key `ylabel` in a scope", Some("y_label"));
    let limits = format!("{base}  - {{ signals: [u], y_limits: [1, 0] }}\n");
    check(&limits, 6, col(&limits, 6, "[1, 0]"), "scope `y_limits` must be finite with low < high", None);
    let empty = format!("{base}  - {{ title: x }}\n");
    check(&empty, 6, col(&empty, 6, "{ title"), "a scope needs `signals:", None);
    let two = "blocks:\n  u: { type: step }\nrecord:\n  - { a: u, b: u }\n";
    check(two, 4, col(two, 4, "{ a"), "a record entry names one signal", None);
}

#[test]
fn zpk_conjugates_written_twice_are_reported() {
    let yaml = "blocks:\n  u: { type: step }\n  g: { type: zpk, poles: [[-1, 2], [-1, -2]] }\nwires: [u -> g]\n";
    check(
        yaml,
        3,
        col(yaml, 3, "[-1, -2]"),
        "block `g`: `poles`: [-1, -2] is the conjugate of [-1, 2], which already stands for the pair -1 ± 2j",
        Some("write each conjugate pair once"),
    );
    // A repeated pair is written twice with the same sign, and is fine.
    let repeated = "blocks:\n  u: { type: step }\n  g: { type: zpk, poles: [[-1, 2], [-1, 2]] }\nwires: [u -> g]\n";
    assert!(ctlgraph::compile_str(repeated, "test.yaml", &[]).is_ok());
}

#[test]
fn values_that_cannot_be_right_are_refused_where_written() {
    // A coefficient 1/0 (NaN-free but infinite) in a denominator or a gain.
    let tau = "parameters: { tau: \"1/0\" }\nblocks:\n  u: { type: step }\n  p: { type: transfer_function, num: [1], den: [tau, 1] }\nwires: [u -> p]\n";
    check(
        tau,
        4,
        col(tau, 4, "tau, 1"),
        "block `p` (transfer_function): `den`: inf is not finite",
        Some("must be finite"),
    );
    let gain = "blocks:\n  u: { type: step }\n  g: { type: gain, k: \"1/0\" }\nwires: [u -> g]\n";
    check(gain, 3, col(gain, 3, "1/0"), "block `g` (gain): `k`: inf is not finite", None);
    // YAML's .nan is refused, its .inf accepted like the expressions' inf.
    let nan = "blocks:\n  u: { type: step }\n  g: { type: gain, k: .nan }\nwires: [u -> g]\n";
    check(nan, 3, col(nan, 3, ".nan"), "block `g` (gain): `k` is not a number (NaN)", None);
    let inf = "blocks:\n  u: { type: step }\n  s: { type: saturation, upper: .inf, lower: -.inf }\nwires: [u -> s]\n";
    assert!(ctlgraph::compile_str(inf, "test.yaml", &[]).is_ok());
    // Reserved names.
    for name in ["pi", "inf", "t"] {
        let yaml = format!("parameters: {{ {name}: 3 }}\nblocks:\n  u: {{ type: step }}\n");
        check(&yaml, 1, col(&yaml, 1, &format!("{name}:")), &format!("parameter `{name}`: the name is reserved"), None);
    }
    // A transfer function beyond the order limit says what to use instead.
    let den: Vec<String> = (0..=120).map(|_| "1".to_string()).collect();
    let big = format!(
        "blocks:\n  u: {{ type: step }}\n  p: {{ type: transfer_function, num: [1], den: [{}] }}\nwires: [u -> p]\n",
        den.join(", ")
    );
    let d = error(&big);
    assert!(d.message.contains("order 120 is above the limit of 100") && d.message.contains("state_space"), "{d}");
}

#[test]
fn data_files_must_be_regular_finite_and_interpolable() {
    let dir = tempfile::tempdir().unwrap();
    let graph = |file: &str| format!("blocks:\n  s: {{ type: from_csv, file: \"{file}\", column: y }}\n");
    // A device never ends: refused before reading.
    let d = error(&graph("/dev/zero"));
    assert!(d.to_string().contains("`/dev/zero` is not a regular file"), "{d}");
    // Neighbouring values whose difference overflows would interpolate to NaN.
    let csv = dir.path().join("big.csv");
    std::fs::write(&csv, "t,y\n0,-1e308\n1,1e308\n").unwrap();
    let d = error(&graph(csv.to_str().unwrap()));
    assert!(d.to_string().contains("points 1 and 2 are too far apart to interpolate"), "{d}");
    // Read a row at a time: the first malformed row ends it, with its
    // number, however much follows (here 300 MiB of a sparse file).
    let long = dir.path().join("long.csv");
    std::fs::write(&long, "t,y\n0,1\n0.1,2\n0.2,x\n").unwrap();
    std::fs::OpenOptions::new().append(true).open(&long).unwrap().set_len(300 << 20).unwrap();
    let with_limit = |file: &std::path::Path, mib: u32| {
        format!("blocks:\n  s: {{ type: from_csv, file: \"{}\", column: y, max_file_mib: {mib} }}\n", file.display())
    };
    let d = error(&with_limit(&long, 400));
    assert!(d.to_string().contains("long.csv` row 4: `y` is `x`, not a number"), "{d}");
    // Above the limit (256 MiB by default, `max_file_mib` to change it):
    // refused before reading, with the way out.
    let d = error(&graph(long.to_str().unwrap()));
    assert!(
        d.to_string().contains("is 300 MiB, above the limit of 256 MiB for data files (raise `max_file_mib`"),
        "{d}"
    );
    let small = dir.path().join("small.csv");
    std::fs::write(&small, "t,y\n0,1\n1,2\n").unwrap();
    std::fs::OpenOptions::new().append(true).open(&small).unwrap().set_len((1 << 20) + 1).unwrap();
    let d = error(&with_limit(&small, 1));
    assert!(d.to_string().contains("is 2 MiB, above the limit of 1 MiB"), "{d}");
    assert!(d.to_string().contains("max_file_mib"), "the key is named: {d}");
}

#[test]
fn deep_input_is_refused_not_a_stack_overflow() {
    let with =
        |expr: &str| format!("blocks:\n  g: {{ type: gain, k: \"{expr}\" }}\n  u: {{ type: step }}\nwires: [u -> g]\n");
    // The campaign's inputs: refused by length or depth, never a crash.
    let refused = |m: &str| m.contains("nested too deeply") || m.contains("expression too long");
    for deep in [
        format!("{}1{}", "(".repeat(10_000), ")".repeat(10_000)),
        format!("{}1{}", "abs(".repeat(10_000), ")".repeat(10_000)),
        format!("{}1", "-".repeat(100_000)),
        vec!["1"; 100_000].join("+"),
    ] {
        let d = error(&with(&deep));
        assert!(refused(&d.message), "{}", d.message);
    }
    // Depth alone, within the length limit.
    for deep in [
        format!("{}1{}", "(".repeat(300), ")".repeat(300)),
        format!("{}1{}", "abs(".repeat(300), ")".repeat(300)),
        format!("{}1", "-".repeat(300)),
    ] {
        assert!(error(&with(&deep)).message.contains("nested too deeply (limit 256)"));
    }
    // Within the limits, deep is fine.
    let ok = format!("{}1{}", "(".repeat(200), ")".repeat(200));
    assert!(ctlgraph::compile_str(&with(&ok), "test.yaml", &[]).is_ok());
    // Subsystems that include each other a hundred levels deep.
    let dir = tempfile::tempdir().unwrap();
    for k in 0..100 {
        let body = if k < 99 {
            format!(
                "blocks:\n  i: {{ type: inport }}\n  s: {{ type: subsystem, file: s{}.yaml }}\n  o: {{ type: outport }}\nwires: [i -> s, s -> o]\n",
                k + 1
            )
        } else {
            "blocks:\n  i: { type: inport }\n  o: { type: outport }\nwires: [i -> o]\n".to_string()
        };
        std::fs::write(dir.path().join(format!("s{k}.yaml")), body).unwrap();
    }
    let top = dir.path().join("top.yaml");
    std::fs::write(
        &top,
        "blocks:\n  c: { type: constant }\n  s: { type: subsystem, file: s0.yaml }\nwires: [c -> s]\n",
    )
    .unwrap();
    let d = ctlgraph::compile_file(&top, &[]).err().expect("refused");
    assert!(d.message.contains("subsystems nested too deeply (limit 64)"), "{d}");
}

#[test]
fn an_include_chain_that_doubles_is_refused_before_it_expands() {
    // Thirty files, each including the next twice: 2^30 blocks if expanded.
    // The flattened size is known from the (cached) parse of each file, so
    // the refusal comes at once and names where the chain starts.
    let dir = tempfile::tempdir().unwrap();
    for k in 0..30 {
        let body = if k < 29 {
            format!(
                "blocks:\n  i: {{ type: inport }}\n  a: {{ type: subsystem, file: b{n}.yaml }}\n  \
                 b: {{ type: subsystem, file: b{n}.yaml }}\n  s: {{ type: sum, signs: \"++\" }}\n  \
                 o: {{ type: outport }}\nwires: [i -> a, i -> b, a -> s.in1, b -> s.in2, s -> o]\n",
                n = k + 1
            )
        } else {
            "blocks:\n  i: { type: inport }\n  o: { type: outport }\nwires: [i -> o]\n".to_string()
        };
        std::fs::write(dir.path().join(format!("b{k}.yaml")), body).unwrap();
    }
    let top = dir.path().join("top.yaml");
    std::fs::write(
        &top,
        "blocks:\n  c: { type: constant }\n  s: { type: subsystem, file: b0.yaml }\nwires: [c -> s]\n",
    )
    .unwrap();
    let d = ctlgraph::compile_file(&top, &[]).err().expect("refused");
    assert!(d.message.contains("block `s` (subsystem)"), "{d}");
    assert!(d.message.contains("expands to 2684354557 blocks, past the limit of 1000000"), "{d}");
    assert!(d.to_string().contains("top.yaml:3:"), "{d}");
    // Level k holds three blocks and two copies of level k + 1, the last one
    // two blocks: 5·2^(29−k) − 3 in all. Nineteen levels are refused too.
    std::fs::write(
        &top,
        "blocks:\n  c: { type: constant }\n  s: { type: subsystem, file: b11.yaml }\nwires: [c -> s]\n",
    )
    .unwrap();
    let d = ctlgraph::compile_file(&top, &[]).err().expect("refused");
    assert!(d.message.contains("expands to 1310717 blocks"), "{d}");
}

#[test]
fn size_parameters_have_stated_limits() {
    let rls = "blocks:\n  u: { type: step }\n  r: { type: rls, n: 100000 }\nwires: [u -> r.phi, u -> r.y]\n";
    let d = error(rls);
    assert!(d.message.contains("`n`: must be a whole number from 1 to 100, got 100000"), "{d}");
    let mux = "blocks:\n  u: { type: step }\n  m: { type: mux, widths: [100000000] }\nwires: [u -> m]\n";
    let d = error(mux);
    assert!(d.message.contains("whole numbers from 1 to 1e6"), "{d}");
}

#[test]
fn anchors_and_merge_keys_share_block_settings() {
    // The README's example ("The graph file", YAML): `fast` is `slow` with kp = 4.
    let trace = run("simulation: { stop: 0.01, solver: { method: rk4, step: 0.001 } }
blocks:
  e:    { type: constant, value: 1 }
  slow: &pi { type: pid, kp: 2, ki: 15 }
  fast: { <<: *pi, kp: 4 }
wires: [e -> slow, e -> fast]
");
    assert_eq!((trace.at("slow", 0.0), trace.at("fast", 0.0)), (Some(2.0), Some(4.0)));
    // A key merged where it does not fit is reported where it is written.
    let d = error("blocks:\n  a: &p { type: gain, k: 2 }\n  b: { <<: *p, type: integrator }\nwires: []\n");
    assert_eq!(d.pos.as_ref().map(|p| (p.line, p.col)), Some((2, 23)), "{d}");
}

#[test]
fn large_graphs_load_and_alias_bombs_do_not() {
    // 60 000 gains in a chain: past the parser's default node budget
    // (250 000 nodes), which stopped such a file at block 41 668. (A million
    // blocks load too; that takes longer than a test should.)
    let n = 60_000;
    let mut g =
        String::from("simulation: { stop: 0.01, solver: { method: rk4, step: 0.01 } }\nblocks:\n  u: { type: step }\n");
    for i in 1..=n {
        g.push_str(&format!("  g{i}: {{ type: gain, k: 1.0 }}\n"));
    }
    g.push_str("wires:\n  - u -> g1\n");
    for i in 1..n {
        g.push_str(&format!("  - g{i} -> g{}\n", i + 1));
    }
    let model = ctlgraph::compile_str(&g, "big.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(model.meta.len(), n + 1);
    // A billion laughs: nine levels of ten aliases each.
    let mut bomb = String::from("a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n");
    for k in 1..10 {
        let refs = vec![format!("*a{}", k - 1); 10].join(", ");
        bomb.push_str(&format!("a{k}: &a{k} [{refs}]\n"));
    }
    bomb.push_str("blocks:\n  c: { type: constant }\n");
    let d = error(&bomb);
    assert!(d.message.contains("YAML") && d.pos.is_some(), "{d}");
}

/// An outport wired to itself (found by the structured fuzzer: it hung,
/// following the wire around) is refused at its line.
#[test]
fn ports_wired_in_a_circle_are_refused_not_followed_forever() {
    let d = error("blocks:\n  b0: { type: outport }\nwires: [b0 -> b0]\n");
    assert!(d.message.contains("comes back to it through ports only"), "{d}");
    assert_eq!(d.pos.map(|p| (p.line, p.col)), Some((2, 3)));
    let d = error(
        "blocks:\n  u: { type: step }\n  a: { type: outport }\n  b: { type: outport }\nwires: [a -> b, b -> a]\nrecord: [a]\n",
    );
    assert!(d.message.contains("comes back to it"), "{d}");
}

/// A path of no points (found by the structured fuzzer: it indexed the
/// first point) is refused at its key.
#[test]
fn a_path_without_points_is_refused() {
    let d = error("blocks:\n  p: { type: bspline_path, points: [] }\n");
    assert!(d.message.contains("every point needs 2 or 3 coordinates"), "{d}");
}
