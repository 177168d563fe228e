//! The `fuzzy` block from YAML: tables and sentences, errors, bounds.

mod common;
use proptest::prelude::*;

const K1_TABLE: &str = "
      PB PB PM PM PS ZO ZO
      PB PB PM PS PS ZO NS
      PM PM PM PS ZO NS NS
      PM PM PS ZO NS NM NM
      PS PS ZO NS NS NM NM
      PS ZO NS NM NM NM NB
      ZO ZO NM NM NM NB NB";

fn graph(e1: f64, e2: f64, rules: &str, extra: &str) -> String {
    format!(
        "simulation: {{ stop: 0.01, solver: {{ method: euler, step: 0.01 }} }}\n\
         blocks:\n  a: {{ type: constant, value: {e1:e} }}\n  b: {{ type: constant, value: {e2:e} }}\n\
         \x20 f:\n    type: fuzzy\n{extra}    inputs:\n      e1: {{ range: [-0.1, 0.1], terms: 7 }}\n\
         \x20     e2: {{ range: [-0.1, 0.1], terms: 7 }}\n    outputs:\n      k1: {{ range: [-0.2, 0.2], terms: 7 }}\n\
         \x20   rules:\n{rules}\nwires: [a -> f.e1, b -> f.e2]\nrecord: [k1: f.k1]\n"
    )
}

fn table_rules() -> String {
    format!("      k1: |{}", K1_TABLE.replace('\n', "\n    "))
}

#[test]
fn table_in_yaml_matches_scikit_fuzzy() {
    let trace = common::run(&graph(0.013, 0.047, &table_rules(), ""));
    let k1 = trace.column("k1").unwrap()[0];
    assert!((k1 - -0.09516694853829427).abs() < 1e-12, "{k1}");
}

#[test]
fn sentences_equal_the_table() {
    let names = ["NB", "NM", "NS", "ZO", "PS", "PM", "PB"];
    let mut sentences = String::new();
    for (i, row) in K1_TABLE.lines().filter(|l| !l.trim().is_empty()).enumerate() {
        for (j, cell) in row.split_whitespace().enumerate() {
            sentences.push_str(&format!("      - if e1 is {} and e2 is {} then k1 is {cell}\n", names[i], names[j]));
        }
    }
    for (e1, e2) in [(0.03, -0.02), (-0.07, 0.05), (0.05, 0.0)] {
        let a = common::run(&graph(e1, e2, &table_rules(), "")).column("k1").unwrap()[0];
        let b = common::run(&graph(e1, e2, sentences.trim_end(), "")).column("k1").unwrap()[0];
        assert_eq!(a, b, "({e1}, {e2})");
    }
}

#[test]
fn rule_errors_point_at_the_word() {
    let bad = "      - if e1 is NB and e2 is PZ then k1 is PM";
    let d = common::error(&graph(0.0, 0.0, bad, ""));
    assert!(d.message.contains("`e2` has no term `PZ`"), "{d}");
    assert_eq!(d.hint.as_deref(), Some("did you mean `PS`?"));
    assert_eq!(d.pos.unwrap().col, 31);
    let d = common::error(&graph(0.0, 0.0, "      - if e3 is NB then k1 is PM", ""));
    assert!(d.message.contains("`e3` is not an input variable"), "{d}");
    let short = "      k1: |\n        PB PB\n        PB PB";
    let d = common::error(&graph(0.0, 0.0, short, ""));
    assert!(d.message.contains("the table has 2 rows, `e1` has 7 terms"), "{d}");
    let d = common::error(&graph(0.0, 0.0, &table_rules(), "    defuzzification: centroids\n"));
    assert_eq!(d.hint.as_deref(), Some("did you mean `centroid`?"));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    #[test]
    fn outputs_stay_inside_their_universe(e1 in -1.0..1.0f64, e2 in -1.0..1.0f64,
            defuzz in prop::sample::select(vec!["centroid", "bisector", "mom", "som", "lom"]),
            agg in prop::sample::select(vec!["max", "sum"]), imp in prop::sample::select(vec!["min", "product"])) {
        let extra = format!("    defuzzification: {defuzz}\n    aggregation: {agg}\n    implication: {imp}\n");
        let k1 = common::run(&graph(e1, e2, &table_rules(), &extra)).column("k1").unwrap()[0];
        prop_assert!((-0.2..=0.2).contains(&k1), "{k1}");
    }
}
