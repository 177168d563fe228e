//! The header and source text: names for every signal, the blocks' C
//! forms collected, then the structs and the two functions written out.

use super::form::{CBlock, Helpers, NoCForm, Real};
use super::select::{Controller, Member};
use super::{CFiles, Options, identifier};
use crate::compile::Model;
use crate::diag::Diagnostic;
use std::collections::{HashMap, HashSet};
use std::fmt::Write;

/// One block's C form as written, with what the step needs to place it.
struct Written<'c> {
    member: &'c Member,
    type_name: &'c str,
    field: String,
    equations: Vec<String>,
    memory: Vec<String>,
    init: Vec<String>,
    output: Vec<String>,
    update: Vec<String>,
}

/// Identifiers handed out in one C scope, made unique by a suffix.
#[derive(Default)]
struct Scope(HashSet<String>);

impl Scope {
    fn take(&mut self, name: &str) -> String {
        let base = identifier(name);
        let mut id = base.clone();
        let mut k = 2;
        while !self.0.insert(id.clone()) {
            id = format!("{base}_{k}");
            k += 1;
        }
        id
    }
}

/// A struct member of the controller's type, an array when wider than one.
fn declaration(real: Real, field: &str, width: usize) -> String {
    match width {
        1 => format!("{} {field};", real.c_type()),
        w => format!("{} {field}[{w}];", real.c_type()),
    }
}

/// The element expressions of a member `field` of `owner` (`in->r`, `s->sig.z[1]`).
fn elements(owner: &str, field: &str, width: usize) -> Vec<String> {
    match width {
        1 => vec![format!("{owner}{field}")],
        w => (0..w).map(|k| format!("{owner}{field}[{k}]")).collect(),
    }
}

pub(super) fn files(model: &Model, ctl: &Controller, options: &Options) -> Result<CFiles, Diagnostic> {
    let real = options.real;
    let name = &ctl.name;
    // Every signal element the controller reads: the inputs, then the blocks' outputs.
    let mut signal: HashMap<usize, String> = HashMap::new();
    let (mut in_scope, mut out_scope, mut sig_scope) = (Scope::default(), Scope::default(), Scope::default());
    let (mut in_fields, mut input_elements) = (Vec::new(), Vec::new());
    for t in &ctl.inputs {
        let field = in_scope.take(&t.name);
        input_elements.extend(elements("", &field, t.port.width));
        for (k, e) in elements("in->", &field, t.port.width).into_iter().enumerate() {
            signal.entry(t.port.offset + k).or_insert(e);
        }
        in_fields.push((declaration(real, &field, t.port.width), format!("inport {}", t.name)));
    }
    let mut sig_fields = Vec::new();
    let mut outputs_of = Vec::new();
    for m in &ctl.members {
        let meta = &model.meta[m.index];
        let ports = model.output_ports(m.index);
        let mut lvalues = Vec::new();
        for (p, port) in ports.iter().enumerate() {
            let label = if ports.len() == 1 { m.name.clone() } else { format!("{}_{}", m.name, meta.output_names[p]) };
            let field = sig_scope.take(&label);
            let e = elements("s->sig.", &field, port.width);
            for (k, e) in e.iter().enumerate() {
                signal.insert(port.offset + k, e.clone());
            }
            sig_fields.push((declaration(real, &field, port.width), format!("{}.{}", m.name, meta.output_names[p])));
            lvalues.push(e);
        }
        outputs_of.push(lvalues);
    }
    // The blocks' forms.
    let mut helpers = Helpers::default();
    let mut block_scope = Scope::default();
    let mut written = Vec::new();
    for (m, outputs) in ctl.members.iter().zip(outputs_of.clone()) {
        let meta = &model.meta[m.index];
        let inputs = model
            .input_ports(m.index)
            .iter()
            .enumerate()
            .map(|(p, port)| {
                (0..port.width)
                    .map(|k| {
                        signal.get(&(port.offset + k)).cloned().ok_or_else(|| {
                            Diagnostic::at(
                                &meta.pos,
                                format!(
                                    "block `{}`: input `{}` comes from outside the controller",
                                    m.name, meta.input_names[p]
                                ),
                            )
                            .with_hint("bring the signal in through an inport of the subsystem")
                        })
                    })
                    .collect::<Result<Vec<_>, _>>()
            })
            .collect::<Result<Vec<_>, _>>()?;
        let field = block_scope.take(&m.name);
        let mut c = CBlock {
            real,
            inputs,
            outputs,
            member: format!("s->{field}"),
            ident: field.clone(),
            equations: Vec::new(),
            memory: Vec::new(),
            init: Vec::new(),
            output: Vec::new(),
            update: Vec::new(),
            helpers: &mut helpers,
        };
        if let Err(why) = model.block(m.index).c_form(&mut c) {
            let message = match why {
                NoCForm::Type => format!("block `{}`: type `{}` has no C form", m.name, meta.type_name),
                NoCForm::Because(reason) => format!("block `{}` ({}): no C form: {reason}", m.name, meta.type_name),
            };
            return Err(Diagnostic::at(&meta.pos, message)
                .with_hint(format!("types with a C form: {}", options.types_with_c_form.join(", "))));
        }
        let CBlock { equations, memory, init, output, update, .. } = c;
        written.push(Written { member: m, type_name: &meta.type_name, field, equations, memory, init, output, update });
    }
    let (mut out_fields, mut output_elements) = (Vec::new(), Vec::new());
    let mut publish = Vec::new();
    for t in &ctl.outputs {
        let field = out_scope.take(&t.name);
        output_elements.extend(elements("", &field, t.port.width));
        out_fields.push((declaration(real, &field, t.port.width), format!("outport {}", t.name)));
        for (k, lvalue) in elements("out->", &field, t.port.width).into_iter().enumerate() {
            let value = signal.get(&(t.port.offset + k)).cloned().ok_or_else(|| {
                Diagnostic::plain(format!("outport `{}` carries a signal from outside the controller", t.name))
            })?;
            publish.push(format!("{lvalue} = {value};"));
        }
    }
    let mut rates: Vec<u32> = ctl.members.iter().map(|m| m.every).filter(|&n| n > 1).collect();
    rates.sort_unstable();
    rates.dedup();
    let clock = helpers.2.then(|| time_of_step(ctl.base_period, real));
    let header = header(name, ctl, options, &in_fields, &out_fields, &sig_fields, &written, &rates, clock.is_some());
    let signals: Vec<String> = outputs_of.iter().flatten().flatten().cloned().collect();
    let source =
        source(name, options, &helpers, &written, &signals, &publish, &rates, ctl.inputs.is_empty(), clock.as_deref());
    Ok(CFiles { header, source, input_elements, output_elements })
}

/// The present sample's time from the step count `s->k`, computed as the
/// simulator's clock computes its hits (`sim::clock`): k/n when the base
/// period is 1/n s for a whole n, else k·period.
fn time_of_step(period: f64, real: Real) -> String {
    let ty = real.c_type();
    match crate::sim::clock::per_unit(period) {
        Some(n) => format!("({ty})s->k / {}", real.literal(n)),
        None => format!("({ty})s->k * {}", real.literal(period)),
    }
}

/// `typedef struct { … } NAME;` with a comment after each member.
fn typedef(out: &mut String, doc: &str, type_name: &str, fields: &[(String, String)], empty: &str) {
    let _ = writeln!(out, "/* {doc} */\ntypedef struct {{");
    for (decl, comment) in fields {
        let _ = writeln!(out, "    {decl:<28} /* {} */", comment.replace("*/", "* /"));
    }
    if fields.is_empty() {
        let _ = writeln!(out, "    {empty}");
    }
    let _ = writeln!(out, "}} {type_name};\n");
}

#[allow(clippy::too_many_arguments)]
fn header(
    name: &str,
    ctl: &Controller,
    options: &Options,
    ins: &[(String, String)],
    outs: &[(String, String)],
    sigs: &[(String, String)],
    written: &[Written],
    rates: &[u32],
    keeps_time: bool,
) -> String {
    let guard = format!("{}_H", name.to_ascii_uppercase());
    let mut h = format!(
        "/* {name}.h: generated by ctlgraph {} from {}. Do not edit; regenerate.\n\
         \x20* Call {name}_init once, then {name}_step every {} s (the base rate), in that order. */\n\
         #ifndef {guard}\n#define {guard}\n\n#include <stdint.h>\n\n\
         /* The base rate's period [s]. */\n#define {}_BASE_PERIOD {}\n\n",
        env!("CARGO_PKG_VERSION"),
        options.origin.replace("*/", "* /"),
        ctl.base_period,
        name.to_ascii_uppercase(),
        Real::Double.literal(ctl.base_period),
    );
    typedef(
        &mut h,
        "The controller's inputs: set before each step.",
        &format!("{name}_in"),
        ins,
        "char none; /* no inputs */",
    );
    typedef(&mut h, "The controller's outputs: written by each step.", &format!("{name}_out"), outs, "char none;");
    let _ = writeln!(
        h,
        "/* The controller's state: the blocks' memory, the signals held between samples,\n   the slower rates' counters. */\ntypedef struct {{"
    );
    for w in written.iter().filter(|w| !w.memory.is_empty()) {
        let _ = writeln!(h, "    struct {{");
        for m in &w.memory {
            let _ = writeln!(h, "        {m}");
        }
        let _ = writeln!(
            h,
            "    }} {};{:<w$}/* {} ({}) */",
            w.field,
            "",
            w.member.name,
            w.type_name,
            w = 20usize.saturating_sub(w.field.len())
        );
    }
    if !sigs.is_empty() {
        let _ = writeln!(h, "    struct {{");
        for (decl, comment) in sigs {
            let _ = writeln!(h, "        {decl:<24} /* {} */", comment.replace("*/", "* /"));
        }
        let _ = writeln!(h, "    }} sig;{:<17}/* the blocks' outputs */", "");
    }
    for n in rates {
        let _ = writeln!(
            h,
            "    uint32_t tick_{n};{:<w$}/* base steps since the 1/{n} rate's last sample */",
            "",
            w = 15usize.saturating_sub(n.to_string().len())
        );
    }
    if keeps_time {
        let _ = writeln!(h, "    uint64_t k;                 /* base steps since init: the time t */");
    }
    let _ = writeln!(h, "}} {name}_state;\n");
    let _ = writeln!(
        h,
        "/* Resets the state: the blocks' initial memory, the parameters as the graph resolved them. */\n\
         void {name}_init({name}_state *s);\n\n\
         /* One base-rate sample: the blocks due compute their outputs in execution order,\n\
         \x20  `out` is written, then the blocks due update their memory. */\n\
         void {name}_step({name}_state *s, const {name}_in *in, {name}_out *out);\n\n#endif"
    );
    h
}

/// A block's comment and statements, indented, under its rate's condition.
fn block_text(out: &mut String, w: &Written, statements: &[String], equations: bool) {
    let _ = writeln!(
        out,
        "    /* {} ({}){} */",
        w.member.name.replace("*/", "* /"),
        w.type_name,
        if equations { "" } else { ": update" }
    );
    if equations {
        for e in &w.equations {
            let _ = writeln!(out, "    /*   {e} */");
        }
    }
    let (open, indent) = match w.member.every {
        0 | 1 => ("{".to_string(), "        "),
        n => (format!("if (s->tick_{n} == 0u) {{"), "        "),
    };
    let _ = writeln!(out, "    {open}");
    for s in statements {
        for line in s.lines() {
            let _ = writeln!(out, "{indent}{line}");
        }
    }
    let _ = writeln!(out, "    }}");
}

#[allow(clippy::too_many_arguments)]
fn source(
    name: &str,
    options: &Options,
    helpers: &Helpers,
    written: &[Written],
    signals: &[String],
    publish: &[String],
    rates: &[u32],
    no_inputs: bool,
    clock: Option<&str>,
) -> String {
    let mut c = format!(
        "/* {name}.c: generated by ctlgraph {} from {}. Do not edit; regenerate.\n\
         \x20* Computes in {}; compile with -ffp-contract=off to keep the simulation's roundings. */\n\
         #include <math.h>\n#include <stdint.h>\n#include \"{name}.h\"\n\n",
        env!("CARGO_PKG_VERSION"),
        options.origin.replace("*/", "* /"),
        options.real.c_type(),
    );
    for text in helpers.0.iter().map(|(_, text)| text).chain(&helpers.1) {
        let _ = writeln!(c, "{text}");
    }
    let _ = writeln!(c, "void {name}_init({name}_state *s)\n{{");
    for w in written {
        for line in &w.init {
            let _ = writeln!(c, "    {line}");
        }
    }
    let zero = options.real.literal(0.0);
    for e in signals {
        let _ = writeln!(c, "    {e} = {zero};");
    }
    for n in rates {
        let _ = writeln!(c, "    s->tick_{n} = 0u;");
    }
    if clock.is_some() {
        let _ = writeln!(c, "    s->k = 0u;");
    }
    for w in written.iter().filter(|w| w.member.every == 0) {
        block_text(&mut c, w, &w.output, true);
    }
    let _ = writeln!(c, "}}\n\nvoid {name}_step({name}_state *s, const {name}_in *in, {name}_out *out)\n{{");
    if no_inputs {
        let _ = writeln!(c, "    (void)in;");
    }
    if let Some(t) = clock {
        let _ = writeln!(
            c,
            "    /* the sample's time, as the simulator counts it */\n    const {} t = {t};",
            options.real.c_type()
        );
    }
    for w in written.iter().filter(|w| w.member.every != 0 && !w.output.is_empty()) {
        block_text(&mut c, w, &w.output, true);
    }
    let _ = writeln!(c, "    /* the outputs */");
    for line in publish {
        let _ = writeln!(c, "    {line}");
    }
    for w in written.iter().filter(|w| w.member.every != 0 && !w.update.is_empty()) {
        block_text(&mut c, w, &w.update, false);
    }
    if !rates.is_empty() {
        let _ = writeln!(c, "    /* the slower rates' counters */");
    }
    for n in rates {
        let _ = writeln!(c, "    if (++s->tick_{n} == {n}u) s->tick_{n} = 0u;");
    }
    if clock.is_some() {
        let _ = writeln!(c, "    s->k++;");
    }
    let _ = writeln!(c, "}}");
    c
}
