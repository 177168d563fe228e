//! Every block type with a C form against its Rust form: random
//! parameters and random input sequences (a random walk with jumps, exact
//! zeros and repeated values, so limits, dead bands and switches are
//! crossed), the C's outputs equal to the simulation's bit for bit.

use crate::{H, away_from_zero, bit_for_bit, bit_for_bit_on, graph, hitting, list, rows};
use proptest::prelude::*;

/// Every type with a C form has a test here: a graph of it (`type: NAME`)
/// or its name quoted (the one test of `min` and `max`), in this folder's
/// sources.
#[test]
fn every_type_with_a_c_form_has_a_property_test_here() {
    let sources =
        [include_str!("main.rs"), include_str!("forms.rs"), include_str!("dynamics.rs"), include_str!("papers.rs")]
            .concat();
    for name in ctlgraph::blocks::TYPES_WITH_C_FORM {
        let tested = sources.contains(&format!("type: {name}")) || sources.contains(&format!("\"{name}\""));
        assert!(tested, "no test of the C form of `{name}` in tests/c_target/");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4, ..ProptestConfig::default() })]

    #[test]
    fn gain_elementwise_and_matrix(k in prop::collection::vec(-5.0..5.0f64, 3), m in prop::collection::vec(-5.0..5.0f64, 6), seed in any::<u64>()) {
        let yaml = graph(&[3], &format!("type: gain, k: {}, sample_time: {H}", list(&k)), &[""], &[""], 200);
        bit_for_bit(&yaml, 3, seed, 200, 1.0)?;
        let matrix = format!("type: gain, k: [{}, {}], sample_time: {H}", list(&m[..3]), list(&m[3..]));
        bit_for_bit(&graph(&[3], &matrix, &[""], &[""], 200), 3, seed, 200, 1.0)?;
    }

    #[test]
    fn sum_of_signed_inputs_and_of_one_input(signs in "[+-]{1,5}", seed in any::<u64>()) {
        let n = signs.len();
        let ports: Vec<String> = (1..=n).map(|i| format!(".u{i}")).collect();
        let ports: Vec<&str> = ports.iter().map(String::as_str).collect();
        let (widths, ports) = if n == 1 { (vec![4], vec![""]) } else { (vec![2; n], ports) };
        let yaml = graph(&widths, &format!("type: sum, signs: '{signs}', sample_time: {H}"), &ports, &[""], 150);
        bit_for_bit(&yaml, widths.iter().sum(), seed, 150, 1.0)?;
    }

    #[test]
    fn mux_demux_and_constant(value in prop::collection::vec(-1e3..1e3f64, 1..4), seed in any::<u64>()) {
        let yaml = graph(&[1, 2], &format!("type: mux, widths: [1, 2], sample_time: {H}"), &[".u1", ".u2"], &[""], 50);
        bit_for_bit(&yaml, 3, seed, 50, 1.0)?;
        let yaml = graph(&[3], &format!("type: demux, widths: [2, 1], sample_time: {H}"), &[""], &[".y1", ".y2"], 50);
        bit_for_bit(&yaml, 3, seed, 50, 1.0)?;
        let yaml = format!(
            "simulation: {{ stop: 0.5, solver: {{ method: rk4, step: {H} }} }}\nblocks:\n  u: {{ type: inport }}\n  c: {{ type: constant, value: {} }}\n  \
             s: {{ type: sum, signs: '+', sample_time: {H} }}\n  k: {{ type: gain, k: 2, sample_time: {H} }}\n  y1: {{ type: outport }}\n  y2: {{ type: outport }}\n\
             wires:\n  - c -> s\n  - u -> k\n  - s -> y1\n  - k -> y2\n", list(&value));
        bit_for_bit(&yaml, 1, seed, 51, 1.0)?;
    }

    #[test]
    fn tracking_differentiator_in_its_three_forms(delta in 1.0..1e4f64, h0_steps in 1.0..10.0f64, form in 0usize..3, initial in -1.0..1.0f64, seed in any::<u64>()) {
        let form = ["fst", "paper", "fhan"][form];
        let block = format!("type: tracking_differentiator, delta: {delta:e}, h0: {:e}, form: {form}, initial: {initial:e}, sample_time: {H}", h0_steps * H);
        let yaml = graph(&[1], &block, &[""], &[".r1", ".r2"], 400);
        bit_for_bit(&yaml, 1, seed, 400, 1.0)?;
    }

    #[test]
    fn leso_of_orders_one_to_three(order in 1usize..4, omega_h in 0.01..1.5f64, b0 in 0.5..100.0f64, seed in any::<u64>()) {
        let block = format!("type: leso, order: {order}, omega: {:e}, b0: {b0:e}, initial: 0.25, sample_time: {H}", omega_h / H);
        let yaml = graph(&[1, 1], &block, &[".y", ".u"], &[""], 300);
        bit_for_bit(&yaml, 2, seed, 300, 1.0)?;
    }

    #[test]
    fn lsef_with_limits_and_tuned_gains(alpha in prop::collection::vec(0.0..10.0f64, 2), b0 in 1.0..100.0f64, limit in 0.1..2.0f64, order in 1usize..3, tuned in any::<bool>(), seed in any::<u64>()) {
        let alpha = if order == 2 { list(&alpha) } else { list(&alpha[..1]) };
        let gains = if tuned && order == 2 { ", gain_inputs: [alpha1, alpha2]" } else if tuned { ", gain_inputs: [alpha1]" } else { "" };
        let block = format!("type: lsef, order: {order}, alpha: {alpha}, b0: {b0:e}, lower: {:e}, upper: {limit:e}{gains}, sample_time: {H}", -limit);
        let mut ports = vec![".r1"];
        let mut widths = vec![1];
        if order == 2 { ports.push(".r2"); widths.push(1); }
        ports.push(".z");
        widths.push(order + 1);
        if tuned {
            ports.push(".alpha1");
            widths.push(1);
            if order == 2 { ports.push(".alpha2"); widths.push(1); }
        }
        let yaml = graph(&widths, &block, &ports, &[""], 200);
        bit_for_bit(&yaml, widths.iter().sum(), seed, 200, 1.0)?;
    }
}

/// Three rates, counters stepping the slower two: a slow block holds its
/// output between its samples and reads its input only at them; a fast
/// block after it sees the held value. A slow TD (memory) and a fast sum.
#[test]
fn slower_rates_hold_their_outputs_between_their_samples() {
    let yaml = format!(
        "simulation: {{ stop: 2.0, solver: {{ method: rk4, step: {H} }} }}\nblocks:\n  u: {{ type: inport }}\n  \
         slow: {{ type: gain, k: 3, sample_time: {} }}\n  td: {{ type: tracking_differentiator, delta: 50, sample_time: {} }}\n  \
         s: {{ type: sum, signs: '++-', sample_time: {H} }}\n  y: {{ type: outport }}\n  y_td: {{ type: outport }}\n\
         wires:\n  - u -> slow, td, s.u3\n  - slow -> s.u1\n  - td.r1 -> s.u2\n  - s -> y\n  - td.r2 -> y_td\n",
        3.0 * H,
        2.0 * H
    );
    let (c, g) = crate::sil(&yaml, &rows(7, 201, 1, 1.0));
    assert_eq!((c.samples, c.differing_bits), (201, 0), "{}", c.summary(""));
    assert!(
        g.files.source.contains("if (s->tick_3 == 0u)") && g.files.source.contains("if (++s->tick_2 == 2u)"),
        "{}",
        g.files.source
    );
}

/// The fuzzy block's C form: random rule tables over 1 to 3 inputs of 3,
/// 5 or 7 terms, Mamdani (each method pair the closed-form centroid
/// covers, several resolutions) or Sugeno, some rules missing so that
/// nothing fires in places.
#[test]
fn fuzzy_rule_tables_mamdani_and_sugeno() {
    let names = |n: usize| -> &'static [&'static str] {
        match n {
            3 => &["N", "Z", "P"],
            5 => &["NB", "NS", "ZO", "PS", "PB"],
            _ => &["NB", "NM", "NS", "ZO", "PS", "PM", "PB"],
        }
    };
    let methods =
        [("min", "min", "max"), ("product", "product", "max"), ("min", "product", "sum"), ("product", "min", "max")];
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut pick = |n: usize| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % n as u64) as usize
    };
    for case in 0..24 {
        let n_in = 1 + case % 3;
        let sugeno = case % 4 == 3;
        let sizes: Vec<usize> = (0..n_in).map(|_| [3, 5, 7][pick(3)]).collect();
        let out_terms = [3, 5, 7][pick(3)];
        let (and, imp, agg) = methods[case / 3 % 4];
        let resolution = [11, 101, 201, 301][pick(4)];
        let mut inputs = String::new();
        for (i, n) in sizes.iter().enumerate() {
            inputs.push_str(&format!("x{i}: {{ range: [-{0}, {0}], terms: {n} }}, ", 1 + i));
        }
        let outputs = if sugeno {
            let consts: Vec<String> =
                names(out_terms).iter().map(|t| format!("{t}: {}", pick(9) as f64 * 0.25 - 1.0)).collect();
            format!(
                "k: {{ range: [-1, 1], terms: {{ {} }} }}, m: {{ range: [0, 2], terms: {{ {} }} }}",
                consts.join(", "),
                consts.join(", ")
            )
        } else {
            format!("k: {{ range: [-1, 1], terms: {out_terms} }}, m: {{ range: [0, 2], terms: {out_terms} }}")
        };
        // Every cell of the table as a sentence, one in six left out.
        let mut rules = Vec::new();
        let cells: usize = sizes.iter().product();
        for cell in 0..cells {
            if pick(6) == 0 {
                continue;
            }
            let mut at = cell;
            let parts: Vec<String> = sizes
                .iter()
                .enumerate()
                .map(|(i, &n)| {
                    let t = names(n)[at % n];
                    at /= n;
                    format!("x{i} is {t}")
                })
                .collect();
            let (k, m) = (names(out_terms)[pick(out_terms)], names(out_terms)[pick(out_terms)]);
            rules.push(format!("\"if {} then k is {k} and m is {m}\"", parts.join(" and ")));
        }
        let kind = if sugeno { ", kind: sugeno" } else { "" };
        let block = format!(
            "type: fuzzy{kind}, inputs: {{ {inputs} }}, outputs: {{ {outputs} }}, rules: [{}], and: {and}, implication: {imp}, \
             aggregation: {agg}, resolution: {resolution}, sample_time: {H}",
            rules.join(", ")
        );
        let ports: Vec<String> = (0..n_in).map(|i| format!(".x{i}")).collect();
        let ports: Vec<&str> = ports.iter().map(String::as_str).collect();
        let yaml = graph(&vec![1; n_in], &block, &ports, &[".k", ".m"], 300);
        let (c, _) = crate::sil(&yaml, &rows(case as u64 + 1, 300, n_in, 2.0));
        assert_eq!(c.differing_bits, 0, "case {case}: {}\n{yaml}", c.summary(""));
    }
}

#[test]
fn fuzzy_systems_outside_the_c_form_are_refused_with_what_it_covers() {
    let block = format!(
        "type: fuzzy, inputs: {{ e: {{ range: [-1, 1], terms: {{ lo: [gaussmf, 0.5, -1], hi: [gaussmf, 0.5, 1] }} }} }}, \
         outputs: {{ u: {{ range: [-1, 1], terms: 3 }} }}, rules: [\"if e is lo then u is N\", \"if e is hi then u is P\"], sample_time: {H}"
    );
    let model = ctlgraph::compile_str(&graph(&[1], &block, &[""], &[""], 10), "test.yaml", &[]).unwrap();
    let e = ctlgraph::target_c::from_model(model, None, "ctl", ctlgraph_core::codegen::c::Real::Double, "test.yaml")
        .err()
        .unwrap();
    assert!(e.to_string().contains("its C form covers a rule table"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]

    #[test]
    fn fcn_formulas(a in -3.0..3.0f64, b in 0.1..4.0f64, which in 0usize..6, seed in any::<u64>()) {
        let expr = [
            format!("{a}*u1 + u2/{b} - u1*u2"),
            format!("sqrt(abs(u1)) * sign(u2) + floor(u1*{b}) - ceil(u2)"),
            format!("max(u1, u2, {a}) - min(u1, {a})"),
            format!("sin(u1)*cos(u2) + exp(-u1^2) + atan2(u2, {b})"),
            format!("u1^2 + pow(abs(u2), {b}) - tanh(u1)"),
            format!("-(u1 - {a})*(u2 + {b}) / (1 + u1^2)"),
        ][which].clone();
        let yaml = graph(&[1, 1], &format!("type: fcn, inputs: 2, expr: \"{expr}\", sample_time: {H}"), &[".u1", ".u2"], &[""], 100);
        bit_for_bit(&yaml, 2, seed, 100, 2.0)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4, ..ProptestConfig::default() })]

    #[test]
    fn product_and_divide(ops in "[*/]{2,4}", seed in any::<u64>()) {
        let n = ops.len();
        let ports: Vec<String> = (1..=n).map(|i| format!(".u{i}")).collect();
        let ports: Vec<&str> = ports.iter().map(String::as_str).collect();
        let yaml = graph(&vec![2; n], &format!("type: product, ops: '{ops}', sample_time: {H}"), &ports, &[""], 150);
        let (c, _) = crate::sil(&yaml, &away_from_zero(rows(seed, 150, 2 * n, 2.0), 0.05));
        prop_assert!(c.differing_bits == 0, "{}", c.summary(""));
        let yaml = graph(&[1, 1], &format!("type: divide, sample_time: {H}"), &[".u1", ".u2"], &[""], 150);
        let (c, _) = crate::sil(&yaml, &away_from_zero(rows(seed, 150, 2, 2.0), 0.05));
        prop_assert!(c.differing_bits == 0, "{}", c.summary(""));
    }

    #[test]
    fn abs_sign_saturation_and_dead_zone(lower in -2.0..0.5f64, width in 0.0..2.0f64, infinite in 0usize..3, seed in any::<u64>()) {
        // Exact zeros of both signs in the input: abs(+0) is -0 here, as the block's pieces give.
        for block in ["type: abs".to_string(), "type: sign".to_string()] {
            bit_for_bit(&graph(&[3], &format!("{block}, sample_time: {H}"), &[""], &[""], 200), 3, seed, 200, 1.0)?;
        }
        let upper = lower + width;
        let (lo, hi) = match infinite { 0 => (format!("{lower:e}"), format!("{upper:e}")), 1 => ("-inf".into(), format!("{upper:e}")), _ => (format!("{lower:e}"), "inf".into()) };
        let edges = hitting(rows(seed, 200, 2, 2.0), &[lower, upper], seed);
        let sat = format!("type: saturation, lower: {lo}, upper: {hi}, sample_time: {H}");
        bit_for_bit_on(&graph(&[2], &sat, &[""], &[""], 200), &edges)?;
        let dz = format!("type: dead_zone, start: {lower:e}, end: {upper:e}, sample_time: {H}");
        bit_for_bit_on(&graph(&[2], &dz, &[""], &[""], 200), &edges)?;
    }

    #[test]
    fn min_and_max_of_inputs_and_of_elements(n in 1usize..5, max in any::<bool>(), seed in any::<u64>()) {
        let ty = if max { "max" } else { "min" };
        let ports: Vec<String> = (1..=n).map(|i| format!(".u{i}")).collect();
        let ports: Vec<&str> = if n == 1 { vec![""] } else { ports.iter().map(String::as_str).collect() };
        let widths = if n == 1 { vec![4] } else { vec![2; n] };
        let yaml = graph(&widths, &format!("type: {ty}, inputs: {n}, sample_time: {H}"), &ports, &[""], 200);
        bit_for_bit(&yaml, widths.iter().sum(), seed, 200, 1.0)?;
    }

    #[test]
    fn switch_on_each_criterion_and_selector(criterion in 0usize..3, threshold in -1.0..1.0f64, seed in any::<u64>()) {
        let criterion = [">=", ">", "!=0"][criterion];
        let yaml = graph(&[2, 1, 2], &format!("type: switch, criterion: '{criterion}', threshold: {threshold:e}, sample_time: {H}"), &[".u1", ".control", ".u2"], &[""], 200);
        bit_for_bit_on(&yaml, &hitting(rows(seed, 200, 5, 1.0), &[threshold, 0.0], seed))?;
        let yaml = graph(&[4], &format!("type: selector, indices: [3, 1, 3], sample_time: {H}"), &[""], &[""], 50);
        bit_for_bit(&yaml, 4, seed, 50, 1.0)?;
    }

    #[test]
    fn lookup_table_clamped_and_extrapolated(steps in prop::collection::vec(0.05..1.0f64, 2..8), y in prop::collection::vec(-3.0..3.0f64, 8), linear in any::<bool>(), seed in any::<u64>()) {
        let x: Vec<f64> = steps.iter().scan(-1.5, |at, s| { *at += s; Some(*at) }).collect();
        let extrapolation = if linear { "linear" } else { "clamp" };
        let block = format!("type: lookup_table_1d, x: {}, y: {}, extrapolation: {extrapolation}, sample_time: {H}", list(&x), list(&y[..x.len()]));
        bit_for_bit_on(&graph(&[2], &block, &[""], &[""], 200), &hitting(rows(seed, 200, 2, 2.0), &x, seed))?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2, ..ProptestConfig::default() })]

    /// Every relation, two inputs and one against a constant, on inputs
    /// that tie exactly; every logical operation on 0/1 and other values.
    #[test]
    fn relational_and_logical_operators(constant in -1.0..1.0f64, n in 2usize..5, seed in any::<u64>()) {
        for op in ["<", "<=", ">", ">=", "==", "!="] {
            let yaml = graph(&[2, 2], &format!("type: relational_operator, op: '{op}', sample_time: {H}"), &[".u1", ".u2"], &[""], 100);
            // Ties: one in three samples the two inputs equal.
            let mut tied = rows(seed, 100, 4, 1.0);
            for (k, r) in tied.chunks_mut(4).enumerate() {
                if k % 3 == 0 { r[2] = r[0]; r[3] = r[1]; }
            }
            bit_for_bit_on(&yaml, &tied)?;
            let yaml = graph(&[1], &format!("type: relational_operator, op: '{op}', constant: {constant:e}, sample_time: {H}"), &[""], &[""], 100);
            bit_for_bit_on(&yaml, &hitting(rows(seed, 100, 1, 1.0), &[constant], seed))?;
        }
        for op in ["and", "or", "xor", "nand", "nor"] {
            let ports: Vec<String> = (1..=n).map(|i| format!(".u{i}")).collect();
            let ports: Vec<&str> = ports.iter().map(String::as_str).collect();
            let yaml = graph(&vec![1; n], &format!("type: logical_operator, op: {op}, inputs: {n}, sample_time: {H}"), &ports, &[""], 100);
            bit_for_bit_on(&yaml, &hitting(rows(seed, 100, n, 1.0), &[0.0, 1.0, 0.0], seed))?;
        }
        let yaml = graph(&[2], &format!("type: logical_operator, op: not, sample_time: {H}"), &[""], &[""], 50);
        bit_for_bit_on(&yaml, &hitting(rows(seed, 50, 2, 1.0), &[0.0], seed))?;
    }
}
