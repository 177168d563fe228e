//! The generated module's text: the simulator's sweeps (module `sim`)
//! unrolled over one model's execution order, each block visit a direct
//! call with constant ports.

use super::formula::Formula;
use crate::block::{Kernel, Port};
use crate::compile::{Model, Rate};
use crate::sim::visit::Inline;
use std::fmt::Write;

/// Everything after the fingerprint: imports, ports, the `Step` type and
/// its [`super::GeneratedStep`] implementation.
pub(super) fn body(model: &Model) -> String {
    let g = Gen::new(model);
    let mut out = String::new();
    out.push_str(
        "\n#[allow(unused_imports)]\nuse ::ctlgraph_core::block::{Breakpoint, Io, Kernel, Port};\n\
         #[allow(unused_imports)]\nuse ::ctlgraph_core::{Block, Model};\n\
         #[allow(unused_imports)]\nuse ::ctlgraph_core::codegen::{self as cg, Zoh};\n\n",
    );
    g.ports(&mut out);
    g.step_type(&mut out);
    g.implementation(&mut out);
    out
}

/// One block as the generated code sees it.
struct Visit {
    index: usize,
    rate: Rate,
    /// Runs when the sweep runs every block (first pass, events) only.
    event_only: bool,
    inline: Option<Inline>,
    /// Its output as Rust, when it is a formula ([`crate::Block::formula`]).
    formula: Option<Formula>,
    /// The first of its kernel's or formula's constants in `Step::k`.
    constants: usize,
    states: std::ops::Range<usize>,
    updates: bool,
}

struct Gen<'m> {
    model: &'m Model,
    visits: Vec<Visit>,
    n_constants: usize,
    /// The held LTI blocks and their one input, in the simulator's order.
    held: Vec<(usize, Port)>,
    /// The blocks whose zero crossings are watched, in the watch's order
    /// (`sim/events.rs`); their modes freeze in minor steps as `fz` says.
    watched: Vec<usize>,
}

impl<'m> Gen<'m> {
    fn new(model: &'m Model) -> Self {
        let mut n_constants = 0;
        let visits = (0..model.blocks.len())
            .map(|i| {
                let inline = Inline::of(model, i);
                let constants = n_constants;
                let formula = inline.is_none().then(|| Formula::of(model, i, constants)).flatten();
                n_constants +=
                    inline.map_or(0, |k| constants_of(k.kernel)) + formula.as_ref().map_or(0, |f| f.constants);
                Visit {
                    index: i,
                    rate: model.slots[i].rate,
                    event_only: model.between.event_only[i],
                    inline,
                    formula,
                    constants,
                    states: model.slots[i].states.clone(),
                    updates: model.blocks[i].updates(),
                }
            })
            .collect();
        let held = model.between.held.iter().map(|&i| (i, model.in_ports[model.slots[i].inputs.start])).collect();
        Gen { model, visits, n_constants, held, watched: crate::sim::events::watched(model) }
    }

    /// `const IN_i` and `OUT_i` for every block called through a view
    /// (kernels run in place, but may have an update).
    fn ports(&self, out: &mut String) {
        let list = |ports: &[Port]| {
            ports.iter().map(|p| format!("Port {{ offset: {}, width: {} }}", p.offset, p.width)).collect::<Vec<_>>()
        };
        for v in self.visits.iter().filter(|v| (v.inline.is_none() && v.formula.is_none()) || v.updates) {
            let slot = &self.model.slots[v.index];
            for (kind, ports) in [
                ("IN", &self.model.in_ports[slot.inputs.clone()]),
                ("OUT", &self.model.out_ports[slot.outputs.clone()]),
            ] {
                let _ =
                    writeln!(out, "const {kind}_{}: [Port; {}] = [{}];", v.index, ports.len(), list(ports).join(", "));
            }
        }
        out.push('\n');
    }

    fn step_type(&self, out: &mut String) {
        let m = self.model;
        out.push_str("/// The graph's blocks, signals and held transitions.\n#[derive(Clone)]\npub struct Step {\n");
        let _ = writeln!(out, "    s: Box<[f64; {}]>,", m.signal_len);
        if self.n_constants > 0 {
            let _ = writeln!(out, "    /// The kernels' and formulas' constants.\n    k: [f64; {}],", self.n_constants);
        }
        for v in &self.visits {
            let meta = &m.meta[v.index];
            let _ = writeln!(out, "    /// `{}` ({})", meta.name.escape_debug(), meta.type_name.escape_debug());
            let _ = writeln!(out, "    b{}: {},", v.index, field_type(m, v.index));
        }
        for (j, &(i, input)) in self.held.iter().enumerate() {
            let zoh = match self.single_input_states(i, input) {
                Some(n) => format!("cg::ZohSingleInput<{n}>"),
                None => "Zoh".into(),
            };
            let _ = writeln!(out, "    z{j}: {zoh},\n    u{j}: [f64; {}],", input.width);
        }
        if !self.watched.is_empty() {
            let _ = writeln!(
                out,
                "    /// Per watched block: whether its modes freeze in minor steps.\n    fz: [bool; {}],",
                self.watched.len()
            );
        }
        out.push_str("}\n\n");
    }

    fn implementation(&self, out: &mut String) {
        out.push_str("impl cg::GeneratedStep for Step {\n    const FINGERPRINT: u64 = FINGERPRINT;\n");
        let keeps_history = self.model.blocks.iter().any(|b| b.keeps_history());
        let _ = writeln!(out, "    const KEEPS_HISTORY: bool = {keeps_history};\n");
        self.constructor(out);
        out.push_str(
            "    fn signals(&self) -> &[f64] {\n        &*self.s\n    }\n\n\
             \x20   fn signals_mut(&mut self) -> &mut [f64] {\n        &mut *self.s\n    }\n\n",
        );
        self.initialize(out);
        self.outputs(out);
        self.updates(out);
        self.held(out);
        self.derivatives(out);
        self.rows(out);
        self.record(out);
        self.left_limits(out);
        self.clamp_states(out);
        self.next_event(out);
        self.crossings(out);
        self.diagnose(out);
        out.push_str("}\n");
    }

    fn constructor(&self, out: &mut String) {
        let m = self.model;
        out.push_str("    fn from_model(model: &Model) -> Result<Self, String> {\n");
        if self.n_constants > 0 {
            let _ = writeln!(out, "        let mut k = [0.0; {}];", self.n_constants);
        }
        for v in &self.visits {
            if let Some(f) = v.formula.as_ref().filter(|f| f.constants > 0) {
                let (a, b) = (v.constants, v.constants + f.constants);
                let _ = writeln!(out, "        cg::formula_constants(model, {}, &mut k[{a}..{b}])?;", v.index);
            }
            let Some(inline) = v.inline else { continue };
            let (pattern, stores) = match inline.kernel {
                Kernel::Scale(_) => ("Kernel::Scale(a)", format!("k[{}] = a", v.constants)),
                Kernel::Affine2(..) => {
                    ("Kernel::Affine2(a, b)", format!("(k[{}], k[{}]) = (a, b)", v.constants, v.constants + 1))
                }
                Kernel::Copy => ("Kernel::Copy", "()".into()),
            };
            let _ = writeln!(
                out,
                "        match cg::kernel(model, {}) {{ Some({pattern}) => {stores}, _ => return Err(cg::mismatch(model, {})) }}",
                v.index, v.index
            );
        }
        out.push_str("        Ok(Step {\n");
        out.push_str(if self.n_constants > 0 {
            "            s: cg::zeros(),\n            k,\n"
        } else {
            "            s: cg::zeros(),\n"
        });
        for v in &self.visits {
            let i = v.index;
            let take = match m.blocks[i].rust_type() {
                Some(_) => format!("model.block_at({i})"),
                None => format!("model.block_boxed({i})"),
            };
            let _ = writeln!(out, "            b{i}: {take}.ok_or_else(|| cg::mismatch(model, {i}))?,");
        }
        for (j, &(i, input)) in self.held.iter().enumerate() {
            let take = match self.single_input_states(i, input) {
                Some(_) => "transition_single_input",
                None => "transition",
            };
            let _ =
                writeln!(out, "            z{j}: cg::{take}(model, {i})?,\n            u{j}: [0.0; {}],", input.width);
        }
        if !self.watched.is_empty() {
            let _ = writeln!(out, "            fz: [false; {}],", self.watched.len());
        }
        out.push_str("        })\n    }\n\n");
    }

    fn initialize(&self, out: &mut String) {
        out.push_str("    #[allow(unused_variables)]\n    fn initialize(&mut self, x: &mut [f64]) {\n");
        fix_states(out, true, self.model.n_states);
        for v in &self.visits {
            let states = if v.states.is_empty() { "[]".to_string() } else { format!("x[{}]", range(&v.states)) };
            let _ = writeln!(out, "        self.b{}.initialize(&mut {states});", v.index);
        }
        out.push_str("    }\n\n");
    }

    /// The simulator's output sweep: constant blocks on the first pass,
    /// event-only blocks when every block runs, discrete ones at hits.
    fn outputs(&self, out: &mut String) {
        out.push_str(
            "    #[allow(unused_variables)]\n    #[inline(always)]\n    fn outputs(&mut self, t: f64, x: &[f64], first: bool, all: bool, hit: &[bool]) -> bool {\n",
        );
        fix_states(out, false, self.model.n_states);
        self.fix_hits(out);
        bind_signals(out);
        out.push_str("        let mut bad = 0u64;\n");
        for v in &self.visits {
            let due = match v.rate {
                Rate::Constant => "first".to_string(),
                Rate::Continuous if v.event_only => "all".into(),
                Rate::Continuous => String::new(),
                Rate::Discrete(c) if v.event_only => format!("all && hit[{c}]"),
                Rate::Discrete(c) => format!("hit[{c}]"),
            };
            let call = self.output_call(v, "false", false);
            let check = self.check_written(v.index);
            if due.is_empty() {
                let _ = writeln!(out, "        {call}\n        {check}");
            } else {
                let _ = writeln!(out, "        if {due} {{\n            {call}\n            {check}\n        }}");
            }
        }
        out.push_str("        bad == 0\n    }\n\n");
    }

    /// Adds the non-finite bits of what block `i` just wrote to `bad`:
    /// read right after the write, so the compiler takes the values from
    /// the registers that hold them instead of loading them back (a
    /// vector load of two values just stored one by one waits for both
    /// stores to retire).
    fn check_written(&self, i: usize) -> String {
        let ports = &self.model.out_ports[self.model.slots[i].outputs.clone()];
        let ranges =
            ports.iter().map(|p| format!("bad |= cg::not_finite_bits(&s[{}..{}]);", p.offset, p.offset + p.width));
        ranges.collect::<Vec<_>>().join(" ")
    }

    /// Block `v`'s output: its kernel in place, or a call through a view.
    fn output_call(&self, v: &Visit, left: &str, minor: bool) -> String {
        let i = v.index;
        match v.inline {
            Some(k) => match k.kernel {
                Kernel::Copy => format!("s.copy_within({}..{}, {});", k.u0, k.u0 + k.width, k.y),
                Kernel::Scale(_) => {
                    format!("s[{}] = Kernel::Scale(self.k[{}]).eval(s[{}], s[{}]);", k.y, v.constants, k.u0, k.u1)
                }
                Kernel::Affine2(..) => format!(
                    "s[{}] = Kernel::Affine2(self.k[{}], self.k[{}]).eval(s[{}], s[{}]);",
                    k.y,
                    v.constants,
                    v.constants + 1,
                    k.u0,
                    k.u1
                ),
            },
            None => match &v.formula {
                Some(f) => format!("s[{}] = {};", f.y, f.code),
                None => format!("self.b{i}.output(&mut {});", self.io(i, left, minor)),
            },
        }
    }

    /// The update sweep: continuous blocks always, discrete ones at hits.
    fn updates(&self, out: &mut String) {
        out.push_str("    #[allow(unused_variables)]\n    #[inline(always)]\n    fn updates(&mut self, t: f64, x: &[f64], hit: &[bool]) {\n");
        fix_states(out, false, self.model.n_states);
        self.fix_hits(out);
        bind_signals(out);
        for v in self.visits.iter().filter(|v| v.updates) {
            let call = format!("self.b{}.update(&mut {});", v.index, self.io(v.index, "false", false));
            match v.rate {
                Rate::Constant => {}
                Rate::Continuous => {
                    let _ = writeln!(out, "        {call}");
                }
                Rate::Discrete(c) => {
                    let _ = writeln!(out, "        if hit[{c}] {{\n            {call}\n        }}");
                }
            }
        }
        out.push_str("    }\n\n");
    }

    /// Held LTI blocks: their inputs latched at the major step, their
    /// states advanced by the exact transition.
    fn held(&self, out: &mut String) {
        out.push_str("    #[inline(always)]\n    fn hold_inputs(&mut self) {\n");
        for (j, (_, p)) in self.held.iter().enumerate() {
            let _ = writeln!(out, "        self.u{j}.copy_from_slice(&self.s[{}..{}]);", p.offset, p.offset + p.width);
        }
        out.push_str(
            "    }\n\n    #[allow(unused_variables)]\n    #[inline(always)]\n    fn step_held(&mut self, dt: f64, x: &mut [f64]) {\n",
        );
        if !self.held.is_empty() {
            fix_states(out, true, self.model.n_states);
        }
        for (j, &(i, input)) in self.held.iter().enumerate() {
            let states = range(&self.visits[i].states);
            let _ = match self.single_input_states(i, input) {
                Some(_) => writeln!(out, "        self.z{j}.step(dt, cg::fixed_mut(&mut x[{states}]), self.u{j}[0]);"),
                None => writeln!(out, "        self.z{j}.step(dt, &mut x[{states}], &self.u{j});"),
            };
        }
        out.push_str("    }\n\n");
    }

    /// The state count of held block `i` when it has one input and some
    /// states: its transition is then stepped at sizes fixed in the code.
    fn single_input_states(&self, i: usize, input: Port) -> Option<usize> {
        let n = self.visits[i].states.len();
        (input.width == 1 && n > 0).then_some(n)
    }

    /// A solver stage: the minor step's outputs, then the derivatives.
    fn derivatives(&self, out: &mut String) {
        let m = self.model;
        out.push_str(
            "    #[allow(unused_variables)]\n    #[inline]\n    fn derivatives(&mut self, t: f64, left: bool, x: &[f64], dx: &mut [f64]) {\n",
        );
        let n = m.between.n_integrated;
        if n > 0 {
            fix_states(out, false, n);
            let _ = writeln!(out, "        let dx: &mut [f64; {n}] = cg::fixed_mut(dx);");
        }
        bind_signals(out);
        self.minor_outputs(out, "left");
        for &i in &m.between.integrated {
            let states = &self.visits[i].states;
            let _ = writeln!(
                out,
                "        self.b{i}.derivatives(&{}, &mut dx[{}]);",
                self.io(i, "left", true),
                range(states)
            );
        }
        out.push_str("    }\n\n");
        out.push_str(
            "    #[allow(unused_variables)]\n    fn minor_outputs(&mut self, t: f64, left: bool, x: &[f64]) {\n",
        );
        if n > 0 {
            fix_states(out, false, n);
        }
        bind_signals(out);
        self.minor_outputs(out, "left");
        out.push_str("    }\n\n");
    }

    /// A row between steps (`simulation.output`): the continuous blocks'
    /// outputs but the event-only ones, at (t, x) over all states, as the
    /// simulator's rows compute them; and the held blocks' latched inputs.
    fn rows(&self, out: &mut String) {
        let m = self.model;
        out.push_str(
            "    #[allow(unused_variables)]\n    fn row_outputs(&mut self, t: f64, left: bool, x: &[f64]) {\n",
        );
        fix_states(out, false, m.n_states);
        bind_signals(out);
        for v in self.visits.iter().filter(|v| v.rate == Rate::Continuous && !v.event_only) {
            let _ = writeln!(out, "        {}", self.output_call(v, "left", true));
        }
        out.push_str("    }\n\n    #[allow(unused_variables)]\n    fn held_input(&self, j: usize) -> &[f64] {\n        match j {\n");
        for j in 0..self.held.len() {
            let _ = writeln!(out, "            {j} => &self.u{j},");
        }
        out.push_str("            _ => &[],\n        }\n    }\n\n");
    }

    /// A recorded row with the record list's offsets as constants: the
    /// Recorder's gather loop, bounds checks and all, is most of what
    /// recording costs a small step.
    fn record(&self, out: &mut String) {
        let gather = crate::trace::gather_offsets(self.model);
        let values: Vec<String> =
            std::iter::once("t".to_string()).chain(gather.iter().map(|i| format!("s[{i}]"))).collect();
        let _ = write!(
            out,
            "    #[inline(always)]\n    fn record_row(t: f64, signals: &[f64], batch: &mut cg::ColumnBatch) {{\n        \
             let s: &[f64; {}] = cg::fixed(signals);\n        batch.push([{}]);\n    }}\n\n",
            self.model.signal_len,
            values.join(", ")
        );
    }

    /// The minor step's output sweep, `left` the left-limit flag's expression.
    fn minor_outputs(&self, out: &mut String, left: &str) {
        for &i in &self.model.between.minor {
            let _ = writeln!(out, "        {}", self.output_call(&self.visits[i], left, true));
        }
    }

    /// At a breakpoint: the minor step's outputs as a left limit, handed
    /// to the blocks that keep history (the simulator's `left_limits`).
    fn left_limits(&self, out: &mut String) {
        let m = self.model;
        out.push_str(
            "    #[allow(unused_variables)]\n    fn left_limits(&mut self, t: f64, x: &[f64], at: Breakpoint) {\n",
        );
        let keeping: Vec<usize> = (0..m.blocks.len()).filter(|&i| m.blocks[i].keeps_history()).collect();
        if !keeping.is_empty() {
            let n = m.between.n_integrated;
            if n > 0 {
                fix_states(out, false, n);
            }
            bind_signals(out);
            self.minor_outputs(out, "true");
            for i in keeping {
                let _ = writeln!(out, "        self.b{i}.left_limit(&{}, at);", self.io(i, "true", true));
            }
        }
        out.push_str("    }\n\n");
    }

    fn clamp_states(&self, out: &mut String) {
        out.push_str("    #[allow(unused_variables)]\n    fn clamp_states(&mut self, x: &mut [f64]) -> bool {\n");
        if !self.model.between.integrated.is_empty() {
            fix_states(out, true, self.model.between.n_integrated);
        }
        out.push_str("        false");
        for &i in &self.model.between.integrated {
            let _ = write!(out, "\n            | self.b{i}.clamp_states(&mut x[{}])", range(&self.visits[i].states));
        }
        out.push_str("\n    }\n\n");
    }

    /// Rebinds `hit` as an array of one flag per clock (when a sweep
    /// reads them).
    fn fix_hits(&self, out: &mut String) {
        if !self.model.clocks.is_empty() {
            let _ = writeln!(out, "        let hit: &[bool; {}] = cg::fixed(hit);", self.model.clocks.len());
        }
    }

    /// The earliest block event after `t`, blocks in order as the simulator
    /// folds them.
    fn next_event(&self, out: &mut String) {
        out.push_str(
            "    #[allow(unused_variables)]\n    fn next_event(&self, t: f64) -> (f64, u32) {\n        let mut next = (f64::INFINITY, 0);\n",
        );
        for v in &self.visits {
            let i = v.index;
            let _ = writeln!(
                out,
                "        next = cg::earlier(next, self.b{i}.next_event(t), || self.b{i}.event_generation(t));"
            );
        }
        out.push_str("        next\n    }\n\n");
    }

    /// The watched blocks' zero crossings, by their entry `b` in the
    /// watch: functions, directions, located crossings, the major-step
    /// work and the frozen flags (what `sim/events.rs` asks of a back-end).
    fn crossings(&self, out: &mut String) {
        let arms = |out: &mut String, call: &dyn Fn(usize, usize) -> String, default: &str| {
            out.push_str("        match b {\n");
            for (b, &i) in self.watched.iter().enumerate() {
                let _ = writeln!(out, "            {b} => {},", call(b, i));
            }
            let _ = writeln!(out, "            _ => {default},\n        }}\n    }}\n");
        };
        out.push_str(
            "    #[allow(unused_variables)]\n    fn zero_crossings(&mut self, b: usize, t: f64, left: bool, x: &[f64], major: bool, g: &mut [f64]) {\n",
        );
        if !self.watched.is_empty() {
            bind_signals(out);
        }
        arms(
            out,
            &|_, i| {
                let (major, minor) = (self.io(i, "left", false), self.io(i, "left", true));
                format!(
                    "if major {{ self.b{i}.zero_crossings(&{major}, g) }} else {{ self.b{i}.zero_crossings(&{minor}, g) }}"
                )
            },
            "{}",
        );
        out.push_str("    #[allow(unused_variables)]\n    fn crossing_direction(&self, b: usize, k: usize) -> ::ctlgraph_core::Crossing {\n");
        arms(out, &|_, i| format!("self.b{i}.crossing_direction(k)"), "::ctlgraph_core::Crossing::Either");
        out.push_str("    #[allow(unused_variables)]\n    fn crossing_located(&mut self, b: usize, k: usize) {\n");
        arms(out, &|_, i| format!("self.b{i}.crossing_located(k)"), "{}");
        out.push_str("    #[allow(unused_variables)]\n    fn freeze(&mut self, b: usize, frozen: bool) {\n");
        arms(out, &|b, _| format!("self.fz[{b}] = frozen"), "{}");
        out.push_str(
            "    #[allow(unused_variables)]\n    fn major_step_events(&mut self, t: f64, x: &mut [f64]) -> bool {\n",
        );
        if !self.watched.is_empty() {
            bind_signals(out);
        }
        out.push_str("        false");
        for &i in &self.watched {
            let states = &self.visits[i].states;
            let x = if states.is_empty() { "&mut []".to_string() } else { format!("&mut x[{}]", range(states)) };
            let _ = write!(
                out,
                "\n            | self.b{i}.major_step(&Io::new(t, false, &[], &mut *s, &IN_{i}, &OUT_{i}), {x})"
            );
        }
        out.push_str("\n    }\n\n");
    }

    /// Block `i`'s view at time `t` over its states in `x` (a stage's
    /// when `minor`: modes frozen when it is watched and `fz` says so).
    fn io(&self, i: usize, left: &str, minor: bool) -> String {
        let states = &self.visits[i].states;
        let x = if states.is_empty() { "&[]".to_string() } else { format!("&x[{}]", range(states)) };
        let view = format!("Io::new(t, {left}, {x}, &mut *s, &IN_{i}, &OUT_{i})");
        match (minor, self.watched.iter().position(|&w| w == i)) {
            (false, _) => view,
            (true, Some(b)) => format!("{view}.in_minor_step(self.fz[{b}])"),
            (true, None) => format!("{view}.in_minor_step(false)"),
        }
    }

    fn diagnose(&self, out: &mut String) {
        out.push_str("    fn diagnose(&self, block: usize) -> Option<String> {\n        match block {\n");
        for v in &self.visits {
            let _ = writeln!(out, "            {} => self.b{}.diagnose(),", v.index, v.index);
        }
        out.push_str("            _ => None,\n        }\n    }\n\n");
        out.push_str("    fn block_event(&self, block: usize, t: f64) -> f64 {\n        match block {\n");
        for v in &self.visits {
            let _ = writeln!(out, "            {} => self.b{}.next_event(t),", v.index, v.index);
        }
        out.push_str("            _ => f64::INFINITY,\n        }\n    }\n\n");
        out.push_str("    fn external_input(&mut self, block: usize) -> Option<&mut [f64]> {\n        match block {\n");
        for &(_, i) in &self.model.external_inputs {
            if self.visits.iter().any(|v| v.index == i) {
                let _ = writeln!(out, "            {i} => self.b{i}.external_input(),");
            }
        }
        out.push_str("            _ => None,\n        }\n    }\n");
    }
}

/// Rebinds `x` as an array of `n` states, so that the sweep's constant
/// ranges of it are not bounds-checked.
fn fix_states(out: &mut String, writable: bool, n: usize) {
    let _ = match writable {
        true => writeln!(out, "        let x: &mut [f64; {n}] = cg::fixed_mut(x);"),
        false => writeln!(out, "        let x: &[f64; {n}] = cg::fixed(x);"),
    };
}

/// Binds `s` to the signal buffer for a sweep. Its address then sits in
/// a register, so the compiler sees that a kernel reads the very value a
/// block has just written and passes it on; through `self.s` it reloads
/// the buffer after every store, and may read two adjacent signals with
/// one vector load that waits for the narrower store before it
/// (store-forwarding stall: a quarter of the PID loop's stage time).
fn bind_signals(out: &mut String) {
    out.push_str("        let s = &mut *self.s;\n");
}

/// How many of `Step::k` a kernel's constants take.
fn constants_of(kernel: Kernel) -> usize {
    match kernel {
        Kernel::Scale(_) => 1,
        Kernel::Affine2(..) => 2,
        Kernel::Copy => 0,
    }
}

/// The field type of block `i`: its own type, or a box called dynamically.
fn field_type(model: &Model, i: usize) -> String {
    match model.blocks[i].rust_type() {
        Some(path) => format!("::{path}"),
        None => "Box<dyn Block>".into(),
    }
}

fn range(r: &std::ops::Range<usize>) -> String {
    format!("{}..{}", r.start, r.end)
}
