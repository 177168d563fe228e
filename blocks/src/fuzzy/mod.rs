//! The `fuzzy` block: a Mamdani or zero-order Sugeno fuzzy inference
//! system described in YAML (variables, terms, rules as tables or as
//! sentences), compiled once and evaluated without allocation.

mod c_form;
mod centroid;
pub mod fis;
mod grid;
mod partition;
mod terms;

use crate::{SAMPLE_TIME_INHERITED, table::*};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::yaml::{Key, Kind, Yaml, lookup};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};
use fis::*;

pub const TYPES: &[BlockType] = &[BlockType {
    name: "fuzzy",
    category: "control",
    summary: "Mamdani or zero-order Sugeno fuzzy inference system.",
    doc: "One scalar input port per input variable and one output port per output variable, named \
          after them. Inputs are clipped to their universes. Terms: a number N (3, 5 or 7) gives N \
          uniformly spaced triangles named N Z P / NB NS ZO PS PB / NB NM NS ZO PS PM PB, the end \
          ones half triangles; or a mapping `name: [trimf, a, b, c]`, `[trapmf, a, b, c, d]`, \
          `[gaussmf, sigma, c]`, `[gbellmf, a, b, c]` (MATLAB's parameter order); Sugeno outputs map \
          names to constants. Rules: per output a table (rows: the first input's terms, columns: the \
          second's; `-` for no rule), or a list of sentences `if e1 is NB and e2 is not PS then k1 \
          is PM and k2 is ZO`. Mamdani: firing strength by `and` (min | product) or `or` (max | \
          probor) over the antecedents, `implication` (min | product), `aggregation` (max | sum) on \
          `resolution` points of each output universe, then `defuzzification`: centroid or \
          bisector of the piecewise-linear aggregate (scikit-fuzzy's convention), mom, som or lom. \
          When an output's terms are a triangular partition (each term reaching its neighbours' \
          peaks, as the N-term shorthand makes them) and the method is centroid with min/max, \
          product/max or product/sum, the sampled aggregate's centroid is computed in closed form, \
          piece by linear piece, without visiting the points: the same number to rounding. \
          Sugeno: weighted average of the consequents' constants. With no rule firing an output is \
          the middle of its universe (as MATLAB).\n\
          Bounds: every output stays inside its universe.",
    inputs: &[PortDoc { name: "(inputs)", doc: "one scalar port per input variable" }],
    outputs: &[PortDoc { name: "(outputs)", doc: "one scalar port per output variable" }],
    params: &[
        param("inputs", Required, "mapping name -> { range: [lo, hi], terms: N or { term: [mf, …] } }")
            .kind(ParamKind::Structure),
        param("outputs", Required, "the same for outputs (Sugeno: terms map names to constants)")
            .kind(ParamKind::Structure),
        param("rules", Required, "mapping output -> table, or a list of `if … then …` sentences")
            .kind(ParamKind::Structure),
        param("kind", Word("mamdani"), "mamdani | sugeno").options(&["mamdani", "sugeno"]),
        param("and", Word("min"), "min | product").options(&["min", "product"]),
        param("or", Word("max"), "max | probor").options(&["max", "probor"]),
        param("implication", Word("min"), "min | product").options(&["min", "product"]),
        param("aggregation", Word("max"), "max | sum").options(&["max", "sum"]),
        param("defuzzification", Word("centroid"), "centroid | bisector | mom | som | lom")
            .options(&["centroid", "bisector", "mom", "som", "lom"]),
        param("resolution", Number(201.0), "points on each output universe (Mamdani)"),
        SAMPLE_TIME_INHERITED,
    ],
    build: build_fuzzy,
}];

#[derive(Clone)]
pub struct FuzzyBlock {
    fis: Fis,
    x: Vec<f64>,
    y: Vec<f64>,
}

impl Block for FuzzyBlock {
    rust_type!(FuzzyBlock);
    fn updates(&self) -> bool {
        false
    }
    fn output(&mut self, io: &mut Io) {
        for i in 0..self.x.len() {
            self.x[i] = io.u(i);
        }
        self.fis.eval(&self.x, &mut self.y);
        for (o, &v) in self.y.iter().enumerate() {
            io.set(o, v);
        }
    }
    fn c_form(&self, c: &mut ctlgraph_core::codegen::c::CBlock) -> Result<(), ctlgraph_core::codegen::c::NoCForm> {
        self.fis.c_form(c)
    }
}

fn build_fuzzy(p: &mut Params) -> Result<Built, Diagnostic> {
    let sugeno = p.choice("kind", &["mamdani", "sugeno"])? == "sugeno";
    let Some(inputs_v) = p.raw("inputs") else { return Err(p.block_error("missing parameter `inputs`")) };
    let Some(outputs_v) = p.raw("outputs") else { return Err(p.block_error("missing parameter `outputs`")) };
    let Some(rules_v) = p.raw("rules") else { return Err(p.block_error("missing parameter `rules`")) };
    let inputs = variables(p, inputs_v, "inputs", false)?;
    let outputs = variables(p, outputs_v, "outputs", sugeno)?;
    let rules = parse_rules(rules_v, &inputs, &outputs)?;
    let methods = Methods {
        and: if p.choice("and", &["min", "product"])? == "min" { AndMethod::Min } else { AndMethod::Product },
        or: if p.choice("or", &["max", "probor"])? == "max" { OrMethod::Max } else { OrMethod::ProbOr },
        implication: if p.choice("implication", &["min", "product"])? == "min" {
            Implication::Min
        } else {
            Implication::Product
        },
        aggregation: if p.choice("aggregation", &["max", "sum"])? == "max" {
            Aggregation::Max
        } else {
            Aggregation::Sum
        },
        defuzzification: match p.choice("defuzzification", &["centroid", "bisector", "mom", "som", "lom"])? {
            "bisector" => Defuzzification::Bisector,
            "mom" => Defuzzification::MeanOfMaximum,
            "som" => Defuzzification::SmallestOfMaximum,
            "lom" => Defuzzification::LargestOfMaximum,
            _ => Defuzzification::Centroid,
        },
        resolution: p.count("resolution", 100_000)?.max(2),
    };
    let mut iface = Interface::new(p.sample_time()?).piecewise_constant();
    for v in &inputs {
        iface = iface.input(&v.name, Width::Fixed(1), true);
    }
    for v in &outputs {
        iface = iface.output(&v.name, Width::Fixed(1));
    }
    let (n_in, n_out) = (inputs.len(), outputs.len());
    let fis = Fis::new(inputs, outputs, rules, methods, sugeno);
    Ok(Built::new(FuzzyBlock { fis, x: vec![0.0; n_in], y: vec![0.0; n_out] }, iface))
}

fn entries<'a>(v: &'a Yaml, what: &str) -> Result<&'a [(Key, Yaml)], Diagnostic> {
    match &v.kind {
        Kind::Map(m) if !m.is_empty() => Ok(m),
        _ => Err(Diagnostic::at(&v.pos, format!("{what} must be a non-empty mapping, found {}", v.describe()))),
    }
}

fn num(p: &Params, v: &Yaml, what: &str) -> Result<f64, Diagnostic> {
    p.number_value(what, v)
}

/// Parses `name: { range: [lo, hi], terms: … }` entries.
fn variables(p: &Params, v: &Yaml, what: &str, sugeno_consts: bool) -> Result<Vec<Variable>, Diagnostic> {
    let mut out = Vec::new();
    for (key, spec) in entries(v, &format!("`{what}`"))? {
        let fields = entries(spec, &format!("variable `{}`", key.name))?;
        for (k, _) in fields {
            if k.name != "range" && k.name != "terms" {
                return Err(Diagnostic::at(&k.pos, format!("variable `{}`: unknown key `{}`", key.name, k.name))
                    .suggest(&k.name, ["range", "terms"]));
            }
        }
        let range = lookup(fields, "range")
            .ok_or_else(|| Diagnostic::at(&key.pos, format!("variable `{}` needs `range: [lo, hi]`", key.name)))?;
        let (lo, hi) = match &range.kind {
            Kind::Seq(r) if r.len() == 2 => (num(p, &r[0], "range")?, num(p, &r[1], "range")?),
            _ => return Err(Diagnostic::at(&range.pos, "`range` is [lo, hi]")),
        }; // (NaN was refused as it was read)
        if lo >= hi {
            return Err(Diagnostic::at(&range.pos, format!("`range`: lo ({lo}) must be below hi ({hi})")));
        }
        let terms_v = lookup(fields, "terms")
            .ok_or_else(|| Diagnostic::at(&key.pos, format!("variable `{}` needs `terms`", key.name)))?;
        let terms = match &terms_v.kind {
            Kind::Num(n) => {
                let names = standard_names(*n as usize).filter(|_| n.fract() == 0.0).ok_or_else(|| {
                    Diagnostic::at(&terms_v.pos, format!("{n} uniform terms have no standard names"))
                        .with_hint("use 2, 3, 5 or 7, or list the terms by name")
                })?;
                if sugeno_consts {
                    let step = (hi - lo) / (names.len() - 1) as f64;
                    names.iter().enumerate().map(|(i, n)| (n.to_string(), Mf::Const(lo + i as f64 * step))).collect()
                } else {
                    uniform_triangles(lo, hi, names)
                }
            }
            Kind::Map(m) => m
                .iter()
                .map(|(k, t)| Ok((k.name.clone(), membership(p, t, sugeno_consts)?)))
                .collect::<Result<_, Diagnostic>>()?,
            _ => {
                return Err(Diagnostic::at(
                    &terms_v.pos,
                    "`terms` is a number of uniform triangles or a mapping of terms",
                ));
            }
        };
        out.push(Variable { name: key.name.clone(), lo, hi, terms });
    }
    Ok(out)
}

fn membership(p: &Params, v: &Yaml, sugeno_consts: bool) -> Result<Mf, Diagnostic> {
    if sugeno_consts {
        return Ok(Mf::Const(num(p, v, "terms")?));
    }
    let Kind::Seq(items) = &v.kind else {
        return Err(Diagnostic::at(
            &v.pos,
            "a term is [trimf, a, b, c], [trapmf, a, b, c, d], [gaussmf, sigma, c] or [gbellmf, a, b, c]",
        ));
    };
    let name = items.first().and_then(Yaml::as_str).unwrap_or("");
    let args = items.iter().skip(1).map(|a| num(p, a, "terms")).collect::<Result<Vec<f64>, _>>()?;
    let bad = |msg: &str| Err(Diagnostic::at(&v.pos, format!("{name}: {msg}")));
    match (name, args.as_slice()) {
        ("trimf", &[a, b, c]) if a <= b && b <= c => Ok(Mf::Tri(a, b, c)),
        ("trimf", &[_, _, _]) => bad("needs a <= b <= c"),
        ("trapmf", &[a, b, c, d]) if a <= b && b <= c && c <= d => Ok(Mf::Trap(a, b, c, d)),
        ("trapmf", &[_, _, _, _]) => bad("needs a <= b <= c <= d"),
        ("gaussmf", &[s, c]) if s > 0.0 => Ok(Mf::Gauss(s, c)),
        ("gaussmf", &[_, _]) => bad("needs sigma > 0"),
        ("gbellmf", &[a, b, c]) if a != 0.0 => Ok(Mf::Bell(a, b, c)),
        ("gbellmf", &[_, _, _]) => bad("needs a != 0"),
        ("trimf" | "trapmf" | "gaussmf" | "gbellmf", _) => bad(&format!("wrong number of parameters ({})", args.len())),
        _ => Err(Diagnostic::at(&v.pos, format!("unknown membership function `{name}`"))
            .suggest(name, ["trimf", "trapmf", "gaussmf", "gbellmf"])),
    }
}

fn term_index(var: &Variable, name: &str, pos: &ctlgraph_core::Pos) -> Result<usize, Diagnostic> {
    var.terms.iter().position(|(n, _)| n == name).ok_or_else(|| {
        Diagnostic::at(pos, format!("`{}` has no term `{name}`", var.name))
            .suggest(name, var.terms.iter().map(|(n, _)| n.as_str()))
    })
}

fn parse_rules(v: &Yaml, inputs: &[Variable], outputs: &[Variable]) -> Result<Vec<Rule>, Diagnostic> {
    match &v.kind {
        Kind::Seq(items) => items.iter().map(|s| sentence(s, inputs, outputs)).collect(),
        Kind::Map(tables) => {
            let mut rules = Vec::new();
            for (key, table) in tables {
                let o = outputs.iter().position(|x| x.name == key.name).ok_or_else(|| {
                    Diagnostic::at(&key.pos, format!("rules for `{}`, which is not an output", key.name))
                        .suggest(&key.name, outputs.iter().map(|x| x.name.as_str()))
                })?;
                rules.extend(table_rules(table, o, inputs, &outputs[o])?);
            }
            Ok(rules)
        }
        _ => Err(Diagnostic::at(&v.pos, "`rules` is a mapping output -> table, or a list of `if … then …`")),
    }
}

/// A rule table: rows the first input's terms, columns the second's.
fn table_rules(v: &Yaml, o: usize, inputs: &[Variable], out: &Variable) -> Result<Vec<Rule>, Diagnostic> {
    if inputs.len() != 2 {
        return Err(Diagnostic::at(
            &v.pos,
            format!("a rule table needs exactly two inputs, there are {}", inputs.len()),
        )
        .with_hint("write the rules as `if … then …` sentences"));
    }
    let rows: Vec<(Vec<&str>, ctlgraph_core::Pos)> = match &v.kind {
        Kind::Str(s) => s
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| (l.split_whitespace().collect(), v.pos.clone()))
            .collect(),
        Kind::Seq(items) => items
            .iter()
            .map(|r| match &r.kind {
                Kind::Str(s) => Ok((s.split_whitespace().collect(), r.pos.clone())),
                Kind::Seq(cells) => cells
                    .iter()
                    .map(|c| c.expect_str("a table cell"))
                    .collect::<Result<_, _>>()
                    .map(|c| (c, r.pos.clone())),
                _ => Err(Diagnostic::at(&r.pos, "a table row is a string of terms or a list of terms")),
            })
            .collect::<Result<_, _>>()?,
        _ => return Err(Diagnostic::at(&v.pos, "a rule table is a block of rows (one string) or a list of rows")),
    };
    let (a, b) = (&inputs[0], &inputs[1]);
    if rows.len() != a.terms.len() {
        return Err(Diagnostic::at(
            &v.pos,
            format!("the table has {} rows, `{}` has {} terms", rows.len(), a.name, a.terms.len()),
        ));
    }
    let mut rules = Vec::new();
    for (i, (cells, pos)) in rows.iter().enumerate() {
        if cells.len() != b.terms.len() {
            return Err(Diagnostic::at(
                pos,
                format!("row {} has {} cells, `{}` has {} terms", i + 1, cells.len(), b.name, b.terms.len()),
            ));
        }
        for (j, cell) in cells.iter().enumerate() {
            if *cell == "-" {
                continue;
            }
            let t = term_index(out, cell, pos)?;
            rules.push(Rule {
                antecedents: vec![(0, i, false), (1, j, false)],
                connective: Connective::And,
                consequents: vec![(o, t)],
            });
        }
    }
    Ok(rules)
}

/// `if a is X and b is not Y then c is Z and d is W`.
fn sentence(v: &Yaml, inputs: &[Variable], outputs: &[Variable]) -> Result<Rule, Diagnostic> {
    let text = v.expect_str("a rule")?;
    let words: Vec<(usize, &str)> =
        text.split_whitespace().map(|w| (w.as_ptr() as usize - text.as_ptr() as usize, w)).collect();
    let at = |k: usize| v.pos.shifted(words.get(k).map_or(text.chars().count(), |w| text[..w.0].chars().count()));
    let word = |k: usize| words.get(k).map(|w| w.1.to_ascii_lowercase());
    let expect = |k: usize, w: &str| -> Result<(), Diagnostic> {
        if word(k).as_deref() == Some(w) {
            Ok(())
        } else {
            Err(Diagnostic::at(&at(k), format!("expected `{w}` in rule `{text}`")))
        }
    };
    let var = |k: usize, vars: &[Variable], side: &str| -> Result<usize, Diagnostic> {
        let name = words.get(k).map_or("", |w| w.1);
        vars.iter().position(|x| x.name == name).ok_or_else(|| {
            Diagnostic::at(&at(k), format!("`{name}` is not an {side} variable"))
                .suggest(name, vars.iter().map(|x| x.name.as_str()))
        })
    };
    expect(0, "if")?;
    let mut k = 1;
    let mut antecedents = Vec::new();
    let mut connective = None;
    loop {
        let i = var(k, inputs, "input")?;
        expect(k + 1, "is")?;
        let negated = word(k + 2).as_deref() == Some("not");
        let tk = k + 2 + negated as usize;
        let term = term_index(&inputs[i], words.get(tk).map_or("", |w| w.1), &at(tk))?;
        antecedents.push((i, term, negated));
        k = tk + 1;
        match word(k).as_deref() {
            Some("then") => break,
            Some(c @ ("and" | "or")) => {
                let c = if c == "and" { Connective::And } else { Connective::Or };
                if connective.is_some_and(|p| p != c) {
                    return Err(Diagnostic::at(&at(k), "a rule uses either `and` or `or`, not both")
                        .with_hint("split it into several rules"));
                }
                connective = Some(c);
                k += 1;
            }
            _ => return Err(Diagnostic::at(&at(k), format!("expected `and`, `or` or `then` in rule `{text}`"))),
        }
    }
    k += 1;
    let mut consequents = Vec::new();
    loop {
        let o = var(k, outputs, "output")?;
        expect(k + 1, "is")?;
        let term = term_index(&outputs[o], words.get(k + 2).map_or("", |w| w.1), &at(k + 2))?;
        consequents.push((o, term));
        k += 3;
        match word(k).as_deref() {
            None => break,
            Some("and") => k += 1,
            Some(_) => return Err(Diagnostic::at(&at(k), format!("expected `and` or the end of rule `{text}`"))),
        }
    }
    Ok(Rule { antecedents, connective: connective.unwrap_or(Connective::And), consequents })
}

#[cfg(test)]
mod parse_tests;
#[cfg(test)]
mod tests;
