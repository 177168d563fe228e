//! Reading a fuzzy system from YAML: variables and their terms, membership
//! functions at the edges of what they accept, rule tables and sentences,
//! and each inference setting reaching the system that is built.

use super::*;
use crate::test_rig::{Rig, build, with_params};

/// `variables()` on the `inputs` of a fuzzy block written with `inputs: <yaml>`.
fn read_variables(yaml: &str, sugeno: bool) -> Result<Vec<Variable>, Diagnostic> {
    with_params("fuzzy", &format!("inputs: {yaml}"), |p| {
        let v = p.raw("inputs").expect("inputs");
        variables(p, v, "inputs", sugeno)
    })
}

fn membership_of(yaml: &str, sugeno: bool) -> Result<Mf, Diagnostic> {
    // Any key of the type's table holds the value; `inputs` is one.
    with_params("fuzzy", &format!("inputs: {yaml}"), |p| {
        let v = p.raw("inputs").expect("inputs");
        membership(p, v, sugeno)
    })
}

#[track_caller]
fn error_of<T: std::fmt::Debug>(r: Result<T, Diagnostic>, fragment: &str) -> Diagnostic {
    let d = r.expect_err("an error");
    assert!(d.message.contains(fragment), "`{}` lacks `{fragment}`", d.message);
    d
}

#[test]
fn variables_with_uniform_and_named_terms() {
    let vars =
        read_variables("{ e: { range: [-1, 1], terms: 3 }, d: { range: [0, 2], terms: { lo: [trimf, 0, 0, 1], hi: [gaussmf, 0.5, 2] } } }", false)
            .unwrap();
    assert_eq!(vars.len(), 2);
    assert_eq!((vars[0].name.as_str(), vars[0].lo, vars[0].hi), ("e", -1.0, 1.0));
    assert_eq!(vars[0].terms, uniform_triangles(-1.0, 1.0, &["N", "Z", "P"]));
    assert_eq!(
        vars[1].terms,
        vec![("lo".to_string(), Mf::Tri(0.0, 0.0, 1.0)), ("hi".to_string(), Mf::Gauss(0.5, 2.0))]
    );
    // Sugeno outputs: N uniform constants from lo to hi (1, 3, 5), or constants by name.
    let consts = read_variables("{ u: { range: [1, 5], terms: 3 } }", true).unwrap();
    assert_eq!(
        consts[0].terms.iter().map(|t| t.1).collect::<Vec<_>>(),
        [Mf::Const(1.0), Mf::Const(3.0), Mf::Const(5.0)]
    );
    let named = read_variables("{ u: { range: [0, 9], terms: { a: 2, b: -4 } } }", true).unwrap();
    assert_eq!(named[0].terms, vec![("a".to_string(), Mf::Const(2.0)), ("b".to_string(), Mf::Const(-4.0))]);
}

#[test]
fn variable_mistakes() {
    error_of(read_variables("{ e: { range: [0, 1], terms: 3, rnage: 1 } }", false), "unknown key `rnage`");
    error_of(read_variables("{ e: { terms: 3 } }", false), "needs `range");
    error_of(read_variables("{ e: { range: [0, 1] } }", false), "needs `terms`");
    error_of(read_variables("{ e: { range: [0, 1, 2], terms: 3 } }", false), "`range` is [lo, hi]");
    for range in ["[1, 1]", "[2, 1]"] {
        error_of(read_variables(&format!("{{ e: {{ range: {range}, terms: 3 }} }}"), false), "must be below hi");
    }
    for n in ["4", "2.5"] {
        error_of(read_variables(&format!("{{ e: {{ range: [0, 1], terms: {n} }} }}"), false), "no standard names");
    }
    error_of(read_variables("{ e: { range: [0, 1], terms: [1, 2] } }", false), "`terms` is a number");
    error_of(read_variables("{}", false), "non-empty mapping");
    error_of(read_variables("{ e: {} }", false), "non-empty mapping");
}

#[test]
fn membership_functions_at_the_edges_of_what_they_accept() {
    // Degenerate shapes (equal breakpoints) are accepted; out of order, not.
    assert_eq!(membership_of("[trimf, 0, 1, 2]", false).unwrap(), Mf::Tri(0.0, 1.0, 2.0));
    assert_eq!(membership_of("[trimf, 1, 1, 1]", false).unwrap(), Mf::Tri(1.0, 1.0, 1.0));
    for bad in ["[trimf, 1, 0, 2]", "[trimf, 0, 2, 1]"] {
        error_of(membership_of(bad, false), "needs a <= b <= c");
    }
    assert_eq!(membership_of("[trapmf, 0, 1, 2, 3]", false).unwrap(), Mf::Trap(0.0, 1.0, 2.0, 3.0));
    assert_eq!(membership_of("[trapmf, 1, 1, 1, 1]", false).unwrap(), Mf::Trap(1.0, 1.0, 1.0, 1.0));
    for bad in ["[trapmf, 1, 0, 2, 3]", "[trapmf, 0, 2, 1, 3]", "[trapmf, 0, 1, 3, 2]"] {
        error_of(membership_of(bad, false), "needs a <= b <= c <= d");
    }
    assert_eq!(membership_of("[gaussmf, 0.1, 0]", false).unwrap(), Mf::Gauss(0.1, 0.0));
    for bad in ["[gaussmf, 0, 0]", "[gaussmf, -1, 0]"] {
        error_of(membership_of(bad, false), "needs sigma > 0");
    }
    assert_eq!(membership_of("[gbellmf, -1, 2, 0]", false).unwrap(), Mf::Bell(-1.0, 2.0, 0.0));
    error_of(membership_of("[gbellmf, 0, 2, 0]", false), "needs a != 0");
    for bad in ["[trimf, 0, 1]", "[trapmf, 0, 1, 2]", "[gaussmf, 1]", "[gbellmf, 1, 2]"] {
        error_of(membership_of(bad, false), "wrong number of parameters");
    }
    error_of(membership_of("[trimff, 0, 1, 2]", false), "unknown membership function `trimff`");
    error_of(membership_of("3", false), "a term is [trimf");
    assert_eq!(membership_of("3", true).unwrap(), Mf::Const(3.0));
}

/// Inputs e (N Z P) and d (N P), outputs u (N Z P) and v (N P).
fn two_by_two() -> (Vec<Variable>, Vec<Variable>) {
    let var = |name: &str, names: &'static [&'static str]| Variable {
        name: name.into(),
        lo: -1.0,
        hi: 1.0,
        terms: uniform_triangles(-1.0, 1.0, names),
    };
    (vec![var("e", &["N", "Z", "P"]), var("d", &["N", "P"])], vec![var("u", &["N", "Z", "P"]), var("v", &["N", "P"])])
}

fn read_rules(yaml: &str) -> Result<Vec<Rule>, Diagnostic> {
    let (inputs, outputs) = two_by_two();
    with_params("fuzzy", &format!("rules: {yaml}"), |p| parse_rules(p.raw("rules").expect("rules"), &inputs, &outputs))
}

fn rule(antecedents: &[(usize, usize, bool)], connective: Connective, consequents: &[(usize, usize)]) -> Rule {
    Rule { antecedents: antecedents.to_vec(), connective, consequents: consequents.to_vec() }
}

#[test]
fn sentences_become_rules() {
    let rules = read_rules(
        "[\"if e is not N and d is P then u is Z and v is N\", \"IF e IS P OR d IS N THEN v IS P\", \"if e is Z then u is P\"]",
    )
    .unwrap();
    assert_eq!(
        rules,
        vec![
            rule(&[(0, 0, true), (1, 1, false)], Connective::And, &[(0, 1), (1, 0)]),
            rule(&[(0, 2, false), (1, 0, false)], Connective::Or, &[(1, 1)]),
            rule(&[(0, 1, false)], Connective::And, &[(0, 2)]),
        ]
    );
}

#[test]
fn sentence_mistakes_point_at_the_word() {
    // (rule, message, column of the offending word inside the quoted rule)
    for (text, message, word) in [
        ("when e is N then u is Z", "expected `if`", "when"),
        ("if x is N then u is Z", "`x` is not an input variable", "x"),
        ("if e was N then u is Z", "expected `is`", "was"),
        ("if e is Q then u is Z", "`e` has no term `Q`", "Q"),
        ("if e is not Q then u is Z", "`e` has no term `Q`", "Q"),
        ("if e is N and d is P or e is Z then u is Z", "either `and` or `or`", "or"),
        ("if e is N d is P then u is Z", "expected `and`, `or` or `then`", "d"),
        ("if e is N then w is Z", "`w` is not an output variable", "w"),
        ("if e is N then u be Z", "expected `is`", "be"),
        ("if e is N then u is Q", "`u` has no term `Q`", "Q"),
        ("if e is N then u is Z or v is N", "expected `and` or the end", "or"),
        ("if e is N then u is Z and v is Q", "`v` has no term `Q`", "Q"),
    ] {
        let d = error_of(read_rules(&format!("[\"{text}\"]")), message);
        // The rule's text starts at column 30 of `  b: { type: fuzzy, rules: ["…`.
        let col = text
            .match_indices(word)
            .map(|(i, _)| i)
            .find(|&i| text[i..].starts_with(word) && (i == 0 || text.as_bytes()[i - 1] == b' '));
        let expected = 30 + col.unwrap() as u32;
        assert_eq!(d.pos.as_ref().map(|p| p.col), Some(expected), "{text}: {d}");
    }
}

#[test]
fn rule_tables_in_every_form() {
    // Rows e (N Z P), columns d (N P); `-` is no rule.
    let expected = vec![
        rule(&[(0, 0, false), (1, 0, false)], Connective::And, &[(0, 0)]),
        rule(&[(0, 0, false), (1, 1, false)], Connective::And, &[(0, 1)]),
        rule(&[(0, 1, false), (1, 1, false)], Connective::And, &[(0, 2)]),
        rule(&[(0, 2, false), (1, 0, false)], Connective::And, &[(0, 1)]),
        rule(&[(0, 2, false), (1, 1, false)], Connective::And, &[(0, 0)]),
    ];
    for table in ["\"N Z\\n\\n- P\\nZ N\\n\"", "[\"N Z\", \"- P\", \"Z N\"]", "[[N, Z], [\"-\", P], [Z, N]]"] {
        assert_eq!(read_rules(&format!("{{ u: {table} }}")).unwrap(), expected, "{table}");
    }
    // Tables for two outputs, in the order written.
    let both = read_rules("{ v: [\"N P\", \"- -\", \"- -\"], u: [\"- -\", \"- -\", \"P -\"] }").unwrap();
    assert_eq!(both.iter().map(|r| r.consequents[0]).collect::<Vec<_>>(), [(1, 0), (1, 1), (0, 2)]);
    error_of(read_rules("{ w: [\"N Z\", \"- P\", \"Z N\"] }"), "rules for `w`, which is not an output");
    error_of(read_rules("{ u: [\"N Z\", \"- P\"] }"), "the table has 2 rows, `e` has 3 terms");
    error_of(read_rules("{ u: [\"N Z\", \"- P Z\", \"Z N\"] }"), "row 2 has 3 cells, `d` has 2 terms");
    error_of(read_rules("{ u: [\"N Z\", \"- Q\", \"Z N\"] }"), "`u` has no term `Q`");
    error_of(read_rules("{ u: [\"N Z\", 3, \"Z N\"] }"), "a table row is");
    error_of(read_rules("{ u: 3 }"), "a rule table is");
    error_of(read_rules("3"), "`rules` is a mapping");
    // A table needs exactly two inputs.
    let (mut inputs, outputs) = two_by_two();
    inputs.truncate(1);
    let one = with_params("fuzzy", "rules: { u: [\"N\", \"Z\", \"P\"] }", |p| {
        parse_rules(p.raw("rules").unwrap(), &inputs, &outputs)
    });
    error_of(one, "exactly two inputs");
}

/// A two-input Mamdani system with every setting as given.
fn fuzzy_block(settings: &str) -> Rig {
    let spec = "inputs: { e: { range: [-1, 1], terms: 3 }, d: { range: [-1, 1], terms: 3 } }, \
                outputs: { u: { range: [-1, 1], terms: 3 } }, \
                rules: [\"if e is N or d is Z then u is P\", \"if e is Z and d is P then u is N\", \"if e is Z and d is Z then u is Z\"]";
    Rig::new(build("fuzzy", &format!("{spec}{settings}")).unwrap_or_else(|d| panic!("{d}")))
}

#[test]
fn each_inference_setting_reaches_the_system() {
    let (inputs, outputs) = {
        let v = |name: &str| Variable {
            name: name.into(),
            lo: -1.0,
            hi: 1.0,
            terms: uniform_triangles(-1.0, 1.0, &["N", "Z", "P"]),
        };
        (vec![v("e"), v("d")], vec![v("u")])
    };
    let rules = vec![
        rule(&[(0, 0, false), (1, 1, false)], Connective::Or, &[(0, 2)]),
        rule(&[(0, 1, false), (1, 2, false)], Connective::And, &[(0, 0)]),
        rule(&[(0, 1, false), (1, 1, false)], Connective::And, &[(0, 1)]),
    ];
    let (e, d) = (-0.2, 0.3);
    let direct = |m: Methods| {
        let mut fis = Fis::new(inputs.clone(), outputs.clone(), rules.clone(), m, false);
        let mut y = [0.0];
        fis.eval(&[e, d], &mut y);
        y[0]
    };
    let via_yaml = |settings: &str| {
        let mut rig = fuzzy_block(settings);
        rig.set(&[e, d]);
        rig.output(0.0)[0]
    };
    let base = Methods { resolution: 201, ..Methods::default() };
    let cases = [
        ("", base),
        (", and: product", Methods { and: AndMethod::Product, ..base }),
        (", or: probor", Methods { or: OrMethod::ProbOr, ..base }),
        (", implication: product", Methods { implication: Implication::Product, ..base }),
        (", aggregation: sum", Methods { aggregation: Aggregation::Sum, ..base }),
        (", defuzzification: bisector", Methods { defuzzification: Defuzzification::Bisector, ..base }),
        (", defuzzification: mom", Methods { defuzzification: Defuzzification::MeanOfMaximum, ..base }),
        (", defuzzification: som", Methods { defuzzification: Defuzzification::SmallestOfMaximum, ..base }),
        (", defuzzification: lom", Methods { defuzzification: Defuzzification::LargestOfMaximum, ..base }),
        (", resolution: 11", Methods { resolution: 11, ..base }),
    ];
    let values: Vec<f64> = cases
        .iter()
        .map(|(s, m)| {
            let (a, b) = (via_yaml(s), direct(*m));
            assert_eq!(a, b, "{s}");
            a
        })
        .collect();
    // Every setting changes the answer here, so none can be read as another.
    for i in 0..values.len() {
        for j in 0..i {
            assert_ne!(values[i], values[j], "{} and {}", cases[i].0, cases[j].0);
        }
    }
    assert!(!fuzzy_block("").built.block.updates());
}
