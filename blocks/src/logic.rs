//! Comparison and logic (Simulink's Relational Operator and Logical
//! Operator): outputs 0 or 1, elementwise; an input is true when nonzero.

use crate::{SAMPLE_TIME_INHERITED, table::*};
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "relational_operator",
        category: "logic",
        summary: "Compares two inputs (or one with a constant): 1 where the relation holds, else 0.",
        doc: "y = 1 if u1 op u2 else 0, elementwise, op one of < <= > >= == != (Simulink's Relational \
              Operator); with `constant: c`, one input u1 and y = 1 if u1 op c. NaN compares false.\n\
              Modes: the result is decided at major steps and frozen in the solver's minor steps; the \
              zero crossings of u1 − u2 end a step exactly where the result can switch, so under an \
              adaptive solver the output switches at the crossing time, not a step later.\n\
              Bounds: y is 0 or 1.",
        inputs: &[
            PortDoc { name: "u1", doc: "left-hand side, any width" },
            PortDoc { name: "u2", doc: "right-hand side (without `constant`); a scalar broadcasts" },
        ],
        outputs: &[PortDoc { name: "y", doc: "0 or 1, width of the widest input" }],
        params: &[
            param("op", Word("<"), "< | <= | > | >= | == | !=").options(&["<", "<=", ">", ">=", "==", "!="]),
            param("constant", Described("none: two inputs"), "compare u1 with this number instead of u2")
                .kind(ParamKind::Number),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_relational,
    },
    BlockType {
        name: "logical_operator",
        category: "logic",
        summary: "and, or, not, xor, nand, nor of its inputs (true: nonzero): 1 or 0.",
        doc: "Each input is true where nonzero; y = 1 where the operation holds, else 0, elementwise \
              (Simulink's Logical Operator): and (all true), or (any), xor (an odd number true), nand \
              (not all), nor (none), not (one input: true where it is zero). NaN is nonzero: true.\n\
              Bounds: y is 0 or 1.",
        inputs: &[PortDoc { name: "u1 … un", doc: "any widths; scalars broadcast (`not`: one input `u1`)" }],
        outputs: &[PortDoc { name: "y", doc: "0 or 1" }],
        params: &[
            param("op", Word("and"), "and | or | not | xor | nand | nor")
                .options(&["and", "or", "not", "xor", "nand", "nor"]),
            param("inputs", Number(2.0), "number of inputs (1 for not)"),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_logical,
    },
];

/// A relation between two numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Relation {
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
}

impl Relation {
    pub fn holds(self, a: f64, b: f64) -> bool {
        match self {
            Relation::Lt => a < b,
            Relation::Le => a <= b,
            Relation::Gt => a > b,
            Relation::Ge => a >= b,
            Relation::Eq => a == b,
            Relation::Ne => a != b,
        }
    }

    /// The C (and the graph's) operator.
    fn symbol(self) -> &'static str {
        match self {
            Relation::Lt => "<",
            Relation::Le => "<=",
            Relation::Gt => ">",
            Relation::Ge => ">=",
            Relation::Eq => "==",
            Relation::Ne => "!=",
        }
    }
}

#[derive(Clone)]
pub struct Relational {
    relation: Relation,
    constant: Option<f64>,
    /// Per element, whether the relation held at the last major step (the mode).
    holds: Vec<bool>,
}

impl Relational {
    fn sides(&self, io: &Io, k: usize) -> (f64, f64) {
        (io.u_at(0, k), self.constant.unwrap_or_else(|| io.u_at(1, k)))
    }
}

impl Block for Relational {
    rust_type!(Relational);
    fn updates(&self) -> bool {
        false
    }
    fn set_width(&mut self, width: usize) -> Result<(), String> {
        self.holds = vec![false; width];
        Ok(())
    }
    fn output(&mut self, io: &mut Io) {
        for k in 0..io.output_width(0) {
            if io.may_switch() {
                let (a, b) = self.sides(io, k);
                self.holds[k] = self.relation.holds(a, b);
            }
            io.set_at(0, k, if self.holds[k] { 1.0 } else { 0.0 });
        }
    }
    fn num_zero_crossings(&self) -> usize {
        self.holds.len()
    }
    /// u1 − u2 per element: where the relation can switch.
    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        for (k, g) in g.iter_mut().enumerate().take(self.holds.len()) {
            let (a, b) = self.sides(io, k);
            *g = a - b;
        }
    }
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation(format!("y = (u1 {} u2) ? 1 : 0", self.relation.symbol()));
        let (one, zero) = (c.num(1.0), c.num(0.0));
        for k in 0..c.output_width(0) {
            let b = self.constant.map_or_else(|| c.u_at(1, k).to_string(), |x| c.num(x));
            let test = format!("{} {} {b}", c.u_at(0, k), self.relation.symbol());
            c.output(format!("{} = ({test}) ? {one} : {zero};", c.y_at(0, k)));
        }
        Ok(())
    }
}

fn build_relational(p: &mut Params) -> Result<Built, Diagnostic> {
    let relation = match p.choice("op", &["<", "<=", ">", ">=", "==", "!="])? {
        "<" => Relation::Lt,
        "<=" => Relation::Le,
        ">" => Relation::Gt,
        ">=" => Relation::Ge,
        "==" => Relation::Eq,
        _ => Relation::Ne,
    };
    let constant = p.opt_number("constant")?;
    let mut iface = Interface::new(p.sample_time()?).piecewise_constant().input("u1", Width::Common, true);
    if constant.is_none() {
        iface = iface.input("u2", Width::Common, true);
    }
    let block = Relational { relation, constant, holds: vec![false] };
    Ok(Built::new(block, iface.output("y", Width::Common)))
}

/// A logical operation over n truths.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Logic {
    And,
    Or,
    Not,
    Xor,
    Nand,
    Nor,
}

impl Logic {
    /// The operation on `truths` (each input nonzero or not).
    pub fn eval(self, truths: impl Iterator<Item = bool>) -> bool {
        let (mut count, mut n) = (0usize, 0usize);
        for t in truths {
            count += usize::from(t);
            n += 1;
        }
        match self {
            Logic::And => count == n,
            Logic::Or => count > 0,
            Logic::Not => count == 0,
            Logic::Xor => count % 2 == 1,
            Logic::Nand => count < n,
            Logic::Nor => count == 0,
        }
    }
}

#[derive(Clone)]
pub struct Logical {
    op: Logic,
    inputs: usize,
}

impl Block for Logical {
    rust_type!(Logical);
    fn updates(&self) -> bool {
        false
    }
    fn output(&mut self, io: &mut Io) {
        for k in 0..io.output_width(0) {
            let holds = self.op.eval((0..self.inputs).map(|i| io.u_at(i, k) != 0.0));
            io.set_at(0, k, if holds { 1.0 } else { 0.0 });
        }
    }
    /// The count of true inputs, then the operation on it (as [`Logic::eval`]).
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let n = self.inputs;
        c.equation("count = the number of nonzero inputs; y = the operation on the count ? 1 : 0");
        let (one, zero) = (c.num(1.0), c.num(0.0));
        for k in 0..c.output_width(0) {
            let count: Vec<String> = (0..n).map(|i| format!("({} != {zero})", c.u_at(i, k))).collect();
            let count = format!("({})", count.join(" + "));
            let test = match self.op {
                Logic::And => format!("{count} == {n}"),
                Logic::Or => format!("{count} > 0"),
                Logic::Not | Logic::Nor => format!("{count} == 0"),
                Logic::Xor => format!("{count} % 2 == 1"),
                Logic::Nand => format!("{count} < {n}"),
            };
            c.output(format!("{} = ({test}) ? {one} : {zero};", c.y_at(0, k)));
        }
        Ok(())
    }
}

fn build_logical(p: &mut Params) -> Result<Built, Diagnostic> {
    let op = match p.choice("op", &["and", "or", "not", "xor", "nand", "nor"])? {
        "and" => Logic::And,
        "or" => Logic::Or,
        "not" => Logic::Not,
        "xor" => Logic::Xor,
        "nand" => Logic::Nand,
        _ => Logic::Nor,
    };
    let inputs = if op == Logic::Not && !p.has("inputs") { 1 } else { p.count("inputs", 10_000)? };
    if op == Logic::Not && inputs != 1 {
        return Err(p.error("inputs", format!("`not` takes one input, given {inputs}")).with_hint("inputs: 1"));
    }
    let mut iface = Interface::new(p.sample_time()?).piecewise_constant();
    for i in 1..=inputs {
        iface = iface.input(&format!("u{i}"), Width::Common, true);
    }
    Ok(Built::new(Logical { op, inputs }, iface.output("y", Width::Common)))
}

#[cfg(test)]
mod tests {
    use super::{Logic, Relation};

    #[test]
    fn truth_tables() {
        let all = |n: usize| (0..1usize << n).map(move |bits| (0..n).map(move |i| bits >> i & 1 == 1));
        for truths in all(3) {
            let v: Vec<bool> = truths.collect();
            let count = v.iter().filter(|&&t| t).count();
            let eval = |op: Logic| op.eval(v.iter().copied());
            assert_eq!(eval(Logic::And), v.iter().all(|&t| t));
            assert_eq!(eval(Logic::Or), v.iter().any(|&t| t));
            assert_eq!(eval(Logic::Xor), v.iter().fold(false, |a, &t| a ^ t), "{v:?}");
            assert_eq!(eval(Logic::Nand), !eval(Logic::And));
            assert_eq!(eval(Logic::Nor), count == 0);
        }
        assert!(Logic::Not.eval([false].into_iter()) && !Logic::Not.eval([true].into_iter()));
        // NaN compares false, whatever the relation but `!=`.
        for r in [Relation::Lt, Relation::Le, Relation::Gt, Relation::Ge, Relation::Eq] {
            assert!(!r.holds(f64::NAN, 0.0));
        }
        assert!(Relation::Ne.holds(f64::NAN, f64::NAN));
        assert!(Relation::Le.holds(1.0, 1.0) && !Relation::Lt.holds(1.0, 1.0));
    }
}
