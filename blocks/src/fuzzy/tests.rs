use super::fis::*;

const NAMES: [&str; 7] = ["NB", "NM", "NS", "ZO", "PS", "PM", "PB"];

/// The paper's k1 rule table (Shi/Zhou/Li 2025), rows e1, columns e2.
const K1: [&str; 7] = [
    "PB PB PM PM PS ZO ZO",
    "PB PB PM PS PS ZO NS",
    "PM PM PM PS ZO NS NS",
    "PM PM PS ZO NS NM NM",
    "PS PS ZO NS NS NM NM",
    "PS ZO NS NM NM NM NB",
    "ZO ZO NM NM NM NB NB",
];

fn paper_k1(methods: Methods) -> Fis {
    let var =
        |name: &str, lo: f64, hi: f64| Variable { name: name.into(), lo, hi, terms: uniform_triangles(lo, hi, &NAMES) };
    let mut rules = Vec::new();
    for (i, row) in K1.iter().enumerate() {
        for (j, cell) in row.split_whitespace().enumerate() {
            let t = NAMES.iter().position(|n| *n == cell).unwrap();
            rules.push(Rule {
                antecedents: vec![(0, i, false), (1, j, false)],
                connective: Connective::And,
                consequents: vec![(0, t)],
            });
        }
    }
    Fis::new(vec![var("e1", -0.1, 0.1), var("e2", -0.1, 0.1)], vec![var("k1", -0.2, 0.2)], rules, methods, false)
}

fn eval(fis: &mut Fis, e1: f64, e2: f64) -> f64 {
    let mut y = [0.0];
    fis.eval(&[e1, e2], &mut y);
    y[0]
}

/// Values computed once with scikit-fuzzy 0.5.0 (trimf, np.fmin/np.fmax,
/// fuzz.defuzz) on np.linspace(-0.2, 0.2, 201), same membership functions.
#[test]
fn matches_scikit_fuzzy() {
    let mut fis = paper_k1(Methods::default());
    let reference = [
        (0.0, 0.0, -1.1338973973348382e-17),
        (0.03, -0.02, -0.018660994178235534),
        (-0.07, 0.05, 0.03333861291096709),
        (0.1, 0.1, -0.17776884623075384),
        (0.2, -0.5, -1.1338973973348382e-17),
        (0.013, 0.047, -0.09516694853829427),
    ];
    for (e1, e2, want) in reference {
        let got = eval(&mut fis, e1, e2);
        assert!((got - want).abs() < 1e-12, "({e1}, {e2}): {got} vs scikit-fuzzy {want}");
    }
    let variants = [
        (Methods { defuzzification: Defuzzification::Bisector, ..Default::default() }, -0.08983050847457631),
        (Methods { defuzzification: Defuzzification::MeanOfMaximum, ..Default::default() }, -0.06700000000000002),
        (Methods { defuzzification: Defuzzification::SmallestOfMaximum, ..Default::default() }, -0.09400000000000001),
        (Methods { defuzzification: Defuzzification::LargestOfMaximum, ..Default::default() }, -0.04000000000000001),
        (
            Methods { implication: Implication::Product, aggregation: Aggregation::Sum, ..Default::default() },
            -0.09662988096562466,
        ),
        (Methods { implication: Implication::Product, ..Default::default() }, -0.09289900665642603),
        (
            Methods {
                and: AndMethod::Product,
                implication: Implication::Product,
                aggregation: Aggregation::Sum,
                ..Default::default()
            },
            -0.09400118811881195,
        ),
    ];
    for (methods, want) in variants {
        let got = eval(&mut paper_k1(methods), 0.013, 0.047);
        assert!((got - want).abs() < 1e-12, "{methods:?}: {got} vs scikit-fuzzy {want}");
    }
}

#[test]
fn single_rule_by_hand() {
    // One rule: if x is A then y is B, A = trimf(0, 1, 2), B = trimf(0, 1, 2)
    // on [0, 2]. At x = 0.5 the rule fires at 0.5; min implication clips B at
    // 0.5: a symmetric trapezoid, centroid 1; mom = mean of [0.5, 1.5] = 1;
    // som 0.5, lom 1.5.
    let var =
        |n: &str| Variable { name: n.into(), lo: 0.0, hi: 2.0, terms: vec![("A".into(), Mf::Tri(0.0, 1.0, 2.0))] };
    let rule = Rule { antecedents: vec![(0, 0, false)], connective: Connective::And, consequents: vec![(0, 0)] };
    let run = |d: Defuzzification| {
        let methods = Methods { defuzzification: d, resolution: 2001, ..Default::default() };
        let mut fis = Fis::new(vec![var("x")], vec![var("y")], vec![rule.clone()], methods, false);
        let mut y = [0.0];
        fis.eval(&[0.5], &mut y);
        y[0]
    };
    assert!((run(Defuzzification::Centroid) - 1.0).abs() < 1e-12);
    assert!((run(Defuzzification::Bisector) - 1.0).abs() < 1e-12);
    assert!((run(Defuzzification::MeanOfMaximum) - 1.0).abs() < 1e-12);
    assert!((run(Defuzzification::SmallestOfMaximum) - 0.5).abs() < 1e-12);
    assert!((run(Defuzzification::LargestOfMaximum) - 1.5).abs() < 1e-12);
}

#[test]
fn symmetric_table_gives_zero_at_the_origin_and_stays_in_the_universe() {
    let mut fis = paper_k1(Methods::default());
    assert!(eval(&mut fis, 0.0, 0.0).abs() < 1e-15);
    for i in -20..=20 {
        for j in -20..=20 {
            let y = eval(&mut fis, i as f64 * 0.01, j as f64 * 0.01);
            assert!((-0.2..=0.2).contains(&y));
        }
    }
}

#[test]
fn membership_functions_at_their_corners() {
    assert_eq!(Mf::Tri(0.0, 0.0, 1.0).eval(0.0), 1.0, "half triangle peaks at its edge");
    assert_eq!(Mf::Tri(0.0, 1.0, 2.0).eval(0.5), 0.5);
    assert_eq!(Mf::Trap(0.0, 1.0, 2.0, 4.0).eval(3.0), 0.5);
    assert_eq!(Mf::Trap(0.0, 1.0, 2.0, 4.0).eval(1.5), 1.0);
    assert!((Mf::Gauss(0.5, 1.0).eval(1.5) - (-0.5f64).exp()).abs() < 1e-15);
    assert_eq!(Mf::Bell(2.0, 3.0, 1.0).eval(3.0), 0.5);
    // 1/(1 + |(x − c)/a|^(2b)) = 1/(1 + 0.5⁶).
    assert_eq!(Mf::Bell(2.0, 3.0, 1.0).eval(2.0), 64.0 / 65.0);
    // Shoulders (a = b, c = d) are 1 at their edges, 0 just outside.
    assert_eq!(Mf::Trap(0.0, 0.0, 2.0, 4.0).eval(0.0), 1.0);
    assert_eq!(Mf::Trap(0.0, 1.0, 2.0, 2.0).eval(2.0), 1.0);
    assert_eq!(Mf::Trap(0.0, 0.0, 2.0, 2.0).eval(-1e-12), 0.0);
    assert_eq!(Mf::Trap(0.0, 0.0, 2.0, 2.0).eval(2.0 + 1e-12), 0.0);
}

#[test]
fn sugeno_is_a_weighted_average() {
    // x = 0.25 on two triangles N = trimf(0,0,1), P = trimf(0,1,1): weights
    // 0.75 and 0.25, outputs −1 and 3: y = (−0.75 + 0.75)/1 = 0.
    let input = Variable { name: "x".into(), lo: 0.0, hi: 1.0, terms: uniform_triangles(0.0, 1.0, &["N", "P"]) };
    let output = Variable {
        name: "y".into(),
        lo: -1.0,
        hi: 3.0,
        terms: vec![("lo".into(), Mf::Const(-1.0)), ("hi".into(), Mf::Const(3.0))],
    };
    let rules = vec![
        Rule { antecedents: vec![(0, 0, false)], connective: Connective::And, consequents: vec![(0, 0)] },
        Rule { antecedents: vec![(0, 1, false)], connective: Connective::And, consequents: vec![(0, 1)] },
    ];
    let mut fis = Fis::new(vec![input], vec![output], rules, Methods::default(), true);
    let mut y = [f64::NAN];
    fis.eval(&[0.25], &mut y);
    assert!(y[0].abs() < 1e-15);
    fis.eval(&[1.0], &mut y);
    assert_eq!(y[0], 3.0);
    // Terms that do not sum to 1: N = trimf(0, 0, 0.8), P = trimf(0.6, 1, 1) at
    // 0.7 weigh 0.125 and 0.25, y = (−0.125 + 0.75)/0.375 = 5/3. With a gap
    // between them (N ends at 0.4) nothing fires at 0.5: the output's midpoint, 1.
    let sugeno = |n_end: f64| {
        let mut fis = fis.clone();
        fis.inputs[0].terms = vec![("N".into(), Mf::Tri(0.0, 0.0, n_end)), ("P".into(), Mf::Tri(0.6, 1.0, 1.0))];
        Fis::new(fis.inputs, fis.outputs, fis.rules, Methods::default(), true)
    };
    sugeno(0.8).eval(&[0.7], &mut y);
    assert!((y[0] - 5.0 / 3.0).abs() < 1e-14, "{}", y[0]);
    let mut gap = sugeno(0.4);
    gap.eval(&[0.5], &mut y);
    assert_eq!(y[0], 1.0);
    gap.eval(&[0.3], &mut y);
    assert_eq!(y[0], -1.0);
}

/// Negation, OR (max and probabilistic), sum aggregation of min implication
/// and the empty case, against an independent transcription (Python/numpy,
/// trimf and scikit-fuzzy's trapezoid centroid on 201 points; values
/// recorded). Rules on a, b ∈ [−1, 1] (N, Z, P) to k ∈ [0, 1] (L, M, H):
/// a is N and b is not P → L; a is Z or b is Z → M; a is P and b is P → H.
/// At (−0.8, 0.7) the negated term binds rule 1 (1 − 0.7 < 0.8) and the OR
/// of 0.2 and 0.3 differs between max and probor.
#[test]
fn negation_or_and_sum_aggregation_match_an_independent_transcription() {
    let three = |lo: f64, hi: f64, names: &[&str]| uniform_triangles(lo, hi, names);
    let var =
        |n: &str, lo: f64, hi: f64, names: &[&str]| Variable { name: n.into(), lo, hi, terms: three(lo, hi, names) };
    let rule = |antecedents: Vec<(usize, usize, bool)>, connective, term| Rule {
        antecedents,
        connective,
        consequents: vec![(0, term)],
    };
    let rules = vec![
        rule(vec![(0, 0, false), (1, 2, true)], Connective::And, 0),
        rule(vec![(0, 1, false), (1, 1, false)], Connective::Or, 1),
        rule(vec![(0, 2, false), (1, 2, false)], Connective::And, 2),
    ];
    let run = |methods: Methods, a: f64, b: f64| {
        let inputs = vec![var("a", -1.0, 1.0, &["N", "Z", "P"]), var("b", -1.0, 1.0, &["N", "Z", "P"])];
        let mut fis = Fis::new(inputs, vec![var("k", 0.0, 1.0, &["L", "M", "H"])], rules.clone(), methods, false);
        let mut y = [f64::NAN];
        fis.eval(&[a, b], &mut y);
        y[0]
    };
    let m = Methods { resolution: 201, ..Default::default() };
    let cases = [
        (m, 0.46351351351351344),
        (Methods { or: OrMethod::ProbOr, ..m }, 0.4723133716160792),
        (Methods { aggregation: Aggregation::Sum, ..m }, 0.40490196078431384),
    ];
    for (methods, want) in cases {
        let got = run(methods, -0.8, 0.7);
        assert!((got - want).abs() < 1e-12, "{methods:?}: {got} vs {want}");
    }
    // Sum aggregation of min implication where rules share a term: the
    // paper's k1 table at (0.013, 0.047) fires NS twice and NM twice, so
    // Σ_r min(w_r, μ) differs from min(Σ_r w_r, μ) (same transcription).
    let sum = Methods { aggregation: Aggregation::Sum, ..Default::default() };
    let got = eval(&mut paper_k1(sum), 0.013, 0.047);
    assert!((got - (-0.09780946123521687)).abs() < 1e-12, "min/sum: {got}");
    // PB, the last term (its support ends at the grid's end), mirrors NB.
    let mut fis = paper_k1(Methods::default());
    let (pb, nb) = (eval(&mut fis, -0.1, -0.1), eval(&mut fis, 0.1, 0.1));
    assert!((pb + nb).abs() < 1e-15 && nb < -0.17, "PB {pb}, NB {nb}");
    // No rule fires: MATLAB's convention, the middle of the output range.
    let x = Variable { name: "x".into(), lo: 0.0, hi: 2.0, terms: vec![("A".into(), Mf::Tri(0.0, 0.5, 1.0))] };
    let y = Variable { name: "y".into(), lo: 1.0, hi: 3.0, terms: vec![("B".into(), Mf::Tri(1.0, 2.0, 3.0))] };
    let one = Rule { antecedents: vec![(0, 0, false)], connective: Connective::And, consequents: vec![(0, 0)] };
    let mut fis = Fis::new(vec![x], vec![y], vec![one], Methods::default(), false);
    let mut out = [f64::NAN];
    fis.eval(&[1.5], &mut out);
    assert_eq!(out[0], 2.0);
}

#[test]
fn defuzzification_of_piecewise_linear_memberships_by_hand() {
    // Exact areas of trapezoids (checked against a 400 000-point midpoint
    // integration): μ = [0, 1, 0.5, 0] on [0, 1, 2, 3] has area 1.5 and
    // moment 2, so the centroid is 4/3; half the area, 0.75, is reached in
    // the falling segment μ = 1 − (x − 1)/2 at x = 3 − √3.
    use Defuzzification::*;
    let d = |x: &[f64], mu: &[f64], m| defuzzify(x, mu, m).unwrap();
    let (x, mu) = ([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 0.5, 0.0]);
    assert!((d(&x, &mu, Centroid) - 4.0 / 3.0).abs() < 1e-15);
    assert!((d(&x, &mu, Bisector) - (3.0 - 3f64.sqrt())).abs() < 1e-15);
    // Rising then falling: area 2, centroid 89/60, the bisector at 1 + (1 − √0.76)/0.3.
    let (x3, mu3) = ([0.0, 1.0, 3.0], [0.2, 1.0, 0.4]);
    assert!((d(&x3, &mu3, Centroid) - 89.0 / 60.0).abs() < 1e-15);
    assert!((d(&x3, &mu3, Bisector) - (1.0 + (1.0 - 0.76f64.sqrt()) / 0.3)).abs() < 1e-14);
    // A plateau: centroid 9/5; the bisector falls on the flat top (x1 + need/μ).
    let (x, mu) = ([0.0, 1.0, 2.0, 3.0, 4.0], [0.0, 1.0, 1.0, 0.5, 0.0]);
    assert!((d(&x, &mu, Centroid) - 1.8).abs() < 1e-15);
    assert!((d(&x, &mu, Bisector) - 1.75).abs() < 1e-15);
    assert_eq!(
        [d(&x, &mu, SmallestOfMaximum), d(&x, &mu, LargestOfMaximum), d(&x, &mu, MeanOfMaximum)],
        [1.0, 2.0, 1.5]
    );
    assert_eq!(defuzzify(&x, &[0.0; 5], Centroid), None);
    // A segment with no area adds nothing (not 0/0): centroid (5/3 + 7/3)/2 = 2.
    assert_eq!(d(&[0.0, 1.0, 2.0, 3.0], &[0.0, 0.0, 1.0, 0.0], Centroid), 2.0);
    // The bisector inside a segment starting below 1: μ = 0.5 + x/2 on [0, 1],
    // area to u = u/2 + u²/4 = 0.625 at u = 2√0.875 − 1.
    let b = d(&[0.0, 1.0, 2.0], &[0.5, 1.0, 0.0], Bisector);
    assert!((b - (2.0 * 0.875f64.sqrt() - 1.0)).abs() < 1e-15, "{b}");
}

#[test]
fn uniform_terms_reach_their_neighbours_peaks() {
    assert_eq!(standard_names(3), Some(&["N", "Z", "P"][..]));
    assert_eq!(standard_names(2), Some(&["N", "P"][..]));
    assert_eq!(standard_names(5).map(|n| n[2]), Some("ZO"));
    assert_eq!(standard_names(7), Some(&NAMES[..]));
    assert_eq!(standard_names(4), None);
    let terms = uniform_triangles(-1.0, 3.0, &["N", "Z", "P"]);
    let mfs: Vec<Mf> = terms.iter().map(|t| t.1).collect();
    assert_eq!(mfs, [Mf::Tri(-1.0, -1.0, 1.0), Mf::Tri(-1.0, 1.0, 3.0), Mf::Tri(1.0, 3.0, 3.0)]);
    // The last peak is the upper edge itself, not −0.3 + 6·0.2 = 0.8999999999999999.
    let terms = uniform_triangles(-0.3, 0.9, &NAMES);
    assert!(matches!(terms[6].1, Mf::Tri(_, 0.9, 0.9)) && matches!(terms[5].1, Mf::Tri(_, _, 0.9)));
}

/// The rule table's shortcut (inputs that are triangular partitions, rules
/// one term per input) fires the same rules with the same strengths as the
/// general path: outputs equal to the bit (to rounding where the order of a
/// sum or a product of three memberships differs), over uniform and uneven
/// partitions, two and three inputs, empty and shared cells, two outputs,
/// every method, Sugeno, and inputs on peaks and outside the universes.
#[test]
fn rule_table_shortcut_fires_as_the_general_path() {
    use rand_chacha::ChaCha8Rng;
    use rand_chacha::rand_core::{Rng, SeedableRng};
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut uniform = move || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    assert!(paper_k1(Methods::default()).uses_rule_grid());
    let mut checked = 0;
    for system in 0..40 {
        let n_inputs = 2 + system % 2;
        let inputs: Vec<Variable> = (0..n_inputs)
            .map(|i| {
                let n = [3, 5, 7][(system + i) % 3];
                let names: Vec<String> = (0..n).map(|k| format!("T{k}")).collect();
                let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
                let mut terms = uniform_triangles(-1.0, 1.0, &names);
                if system % 4 >= 2 {
                    // Uneven peaks, same chaining.
                    let mut peaks: Vec<f64> = (0..n)
                        .map(|k| {
                            if k == 0 {
                                -1.0
                            } else if k == n - 1 {
                                1.0
                            } else {
                                2.0 * uniform() - 1.0
                            }
                        })
                        .collect();
                    peaks.sort_by(f64::total_cmp);
                    for k in 0..n {
                        terms[k].1 = Mf::Tri(peaks[k.saturating_sub(1)], peaks[k], peaks[(k + 1).min(n - 1)]);
                    }
                }
                Variable { name: format!("x{i}"), lo: -1.0, hi: 1.0, terms }
            })
            .collect();
        let out = |name: &str| Variable {
            name: name.into(),
            lo: 0.0,
            hi: 1.0,
            terms: uniform_triangles(0.0, 1.0, &["L", "M", "H"]),
        };
        let mut rules = Vec::new();
        let cells: usize = inputs.iter().map(|v| v.terms.len()).product();
        for cell in 0..cells {
            for _ in 0..[0, 1, 1, 2][(uniform() * 4.0) as usize % 4] {
                let mut c = cell;
                let antecedents = inputs
                    .iter()
                    .enumerate()
                    .map(|(i, v)| {
                        let k = c % v.terms.len();
                        c /= v.terms.len();
                        (i, k, false)
                    })
                    .rev()
                    .collect();
                let consequents = vec![((uniform() * 2.0) as usize % 2, (uniform() * 3.0) as usize % 3)];
                rules.push(Rule { antecedents, connective: Connective::And, consequents });
            }
        }
        for (and, imp, agg, sugeno) in [
            (AndMethod::Min, Implication::Min, Aggregation::Max, false),
            (AndMethod::Product, Implication::Product, Aggregation::Max, false),
            (AndMethod::Min, Implication::Min, Aggregation::Sum, false),
            (AndMethod::Product, Implication::Product, Aggregation::Sum, false),
            (AndMethod::Min, Implication::Min, Aggregation::Max, true),
        ] {
            let methods = Methods { and, implication: imp, aggregation: agg, ..Default::default() };
            let outputs = if sugeno {
                let consts = |n: &str| Variable {
                    name: n.into(),
                    lo: 0.0,
                    hi: 1.0,
                    terms: vec![
                        ("L".into(), Mf::Const(0.1)),
                        ("M".into(), Mf::Const(0.5)),
                        ("H".into(), Mf::Const(0.8)),
                    ],
                };
                vec![consts("a"), consts("b")]
            } else {
                vec![out("a"), out("b")]
            };
            let build = || Fis::new(inputs.clone(), outputs.clone(), rules.clone(), methods, sugeno);
            let (mut fast, mut general) = (build(), build().without_rule_grid());
            assert!(fast.uses_rule_grid(), "system {system}");
            let exact = !sugeno && agg == Aggregation::Max && (and == AndMethod::Min || n_inputs == 2);
            for s in 0..60 {
                let mut x: Vec<f64> = (0..n_inputs).map(|_| 2.6 * uniform() - 1.3).collect();
                if s % 5 == 0 {
                    // On a peak.
                    let Mf::Tri(_, b, _) = inputs[0].terms[s % inputs[0].terms.len()].1 else { unreachable!() };
                    x[0] = b;
                }
                let (mut y1, mut y2) = ([f64::NAN; 2], [f64::NAN; 2]);
                fast.eval(&x, &mut y1);
                general.eval(&x, &mut y2);
                for o in 0..2 {
                    let close = if exact { y1[o] == y2[o] } else { (y1[o] - y2[o]).abs() <= 1e-15 };
                    assert!(close, "system {system} {methods:?} sugeno {sugeno} at {x:?}: {y1:?} vs {y2:?}");
                }
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 40 * 5 * 60);
    // A negated antecedent, an OR, or a rule missing an input: the general path.
    let inputs = || {
        vec![Variable { name: "a".into(), lo: -1.0, hi: 1.0, terms: uniform_triangles(-1.0, 1.0, &["N", "Z", "P"]) }; 2]
    };
    let output =
        || vec![Variable { name: "y".into(), lo: 0.0, hi: 1.0, terms: uniform_triangles(0.0, 1.0, &["L", "H"]) }];
    for antecedents in [vec![(0, 0, true), (1, 0, false)], vec![(0, 0, false)], vec![(0, 0, false), (0, 1, false)]] {
        let rule = Rule { antecedents, connective: Connective::And, consequents: vec![(0, 0)] };
        assert!(!Fis::new(inputs(), output(), vec![rule], Methods::default(), false).uses_rule_grid());
    }
    let or =
        Rule { antecedents: vec![(0, 0, false), (1, 0, false)], connective: Connective::Or, consequents: vec![(0, 0)] };
    assert!(!Fis::new(inputs(), output(), vec![or], Methods::default(), false).uses_rule_grid());
    // Terms that are not a partition (a gap between feet and peaks).
    let mut gap = inputs();
    gap[1].terms[1].1 = Mf::Tri(-0.9, 0.0, 1.0);
    let rule = Rule {
        antecedents: vec![(0, 0, false), (1, 0, false)],
        connective: Connective::And,
        consequents: vec![(0, 0)],
    };
    assert!(!Fis::new(gap, output(), vec![rule], Methods::default(), false).uses_rule_grid());
}

/// The output grid's last point is the universe's upper edge itself (as
/// numpy's linspace, which scikit-fuzzy uses): lo + (hi − lo)·6/6 lands an
/// ulp past hi on this universe, where a right-shoulder term Tri(lo, hi, hi)
/// is 0, and the centroid of the term alone moved from 2/3 of the way
/// along the universe to 0.61 of it at resolution 7.
#[test]
fn the_output_grid_ends_on_the_upper_edge() {
    let (lo, hi) = (-1.2012497033478038, 1.7151805398233817);
    assert!(lo + (hi - lo) * 6.0 / 6.0 > hi);
    let input = Variable { name: "a".into(), lo: 0.0, hi: 1.0, terms: uniform_triangles(0.0, 1.0, &["N", "P"]) };
    let output = Variable { name: "y".into(), lo, hi, terms: uniform_triangles(lo, hi, &["L", "H"]) };
    let rule = Rule { antecedents: vec![(0, 1, false)], connective: Connective::And, consequents: vec![(0, 1)] };
    let mut fis =
        Fis::new(vec![input], vec![output], vec![rule], Methods { resolution: 7, ..Default::default() }, false);
    let mut y = [f64::NAN];
    fis.eval(&[1.0], &mut y);
    // μ_j = j/6 on x_j = lo + j·(hi − lo)/6, the last one 1.
    let x: Vec<f64> = (0..7).map(|j| if j == 6 { hi } else { lo + (hi - lo) * j as f64 / 6.0 }).collect();
    let mu: Vec<f64> = (0..7).map(|j| j as f64 / 6.0).collect();
    let want = defuzzify(&x, &mu, Defuzzification::Centroid).unwrap();
    assert!((y[0] - want).abs() < 1e-12, "{} vs {want}", y[0]);
}

/// Which outputs get the closed form: triangular partitions with centroid
/// defuzzification and a method pair it covers; and there the system gives
/// what aggregating on the grid gives.
#[test]
fn closed_form_centroid_is_used_where_it_applies() {
    let mut fis = paper_k1(Methods::default());
    assert!(fis.has_exact_centroid(0));
    let mut sampled = paper_k1(Methods::default()).on_the_grid();
    assert!(!sampled.has_exact_centroid(0));
    for k in 0..500 {
        let (e1, e2) = (0.25 * ((k as f64) * 0.37).sin(), 0.12 * ((k as f64) * 0.91).cos());
        let (a, b) = (eval(&mut fis, e1, e2), eval(&mut sampled, e1, e2));
        assert!((a - b).abs() < 1e-14, "({e1}, {e2}): {a} vs {b}");
    }
    let min_sum = Methods { aggregation: Aggregation::Sum, ..Default::default() };
    let bisector = Methods { defuzzification: Defuzzification::Bisector, ..Default::default() };
    for methods in [min_sum, bisector] {
        assert!(!paper_k1(methods).has_exact_centroid(0), "{methods:?}");
    }
    let mut gauss = paper_k1(Methods::default());
    gauss.outputs[0].terms[3].1 = Mf::Gauss(0.05, 0.0);
    let rebuilt = Fis::new(gauss.inputs, gauss.outputs, gauss.rules, gauss.methods, false);
    assert!(!rebuilt.has_exact_centroid(0));
}

/// The shortcuts take a variable for a triangular partition only when its
/// peaks strictly increase and reach both ends of its universe: equal
/// neighbouring peaks (both terms are 1 there, where a partition has one),
/// or a universe reaching past the outer peaks (no term is nonzero there),
/// and the input table and the closed-form centroid are off.
#[test]
fn partitions_must_increase_and_cover_their_universe() {
    let chain = |name: &str, peaks: &[f64]| {
        let n = peaks.len();
        let terms = (0..n)
            .map(|k| (format!("T{k}"), Mf::Tri(peaks[k.saturating_sub(1)], peaks[k], peaks[(k + 1).min(n - 1)])))
            .collect();
        Variable { name: name.into(), lo: -1.0, hi: 1.0, terms }
    };
    let system = |peaks: &[f64]| {
        let rule = |t: usize| Rule {
            antecedents: vec![(0, t, false)],
            connective: Connective::And,
            consequents: vec![(0, t)],
        };
        let rules = (0..peaks.len()).map(rule).collect();
        Fis::new(vec![chain("x", peaks)], vec![chain("y", peaks)], rules, Methods::default(), false)
    };
    let fis = system(&[-1.0, 0.0, 1.0]);
    assert!(fis.uses_rule_grid() && fis.has_exact_centroid(0));
    for peaks in [[-1.0, 0.0, 0.0, 1.0], [-0.5, 0.0, 0.5, 1.0], [-1.0, -0.5, 0.0, 0.5]] {
        let fis = system(&peaks);
        assert!(!fis.uses_rule_grid() && !fis.has_exact_centroid(0), "{peaks:?}");
    }
}
