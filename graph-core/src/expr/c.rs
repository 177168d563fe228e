//! An expression as C (the `fcn` block's C form): the tree written out
//! with the operations `eval` performs, in its order, parenthesised.
//! `+ - * /` and `sqrt`, `abs`, `floor`, `ceil` round as Rust's; the other
//! functions are the C library's, which on the host is the one Rust's
//! `f64` methods call (glibc), on a microcontroller its own (newlib).

use super::{Expr, Func1, Node, Op};
use crate::codegen::c::CBlock;

impl Expr {
    /// The C expression, with variable slot i written `vars[i]`.
    pub fn to_c(&self, c: &mut CBlock, vars: &[String]) -> String {
        node(&self.root, c, vars)
    }
}

fn node(n: &Node, c: &mut CBlock, vars: &[String]) -> String {
    match n {
        Node::Const(v) => c.num(*v),
        Node::Var(i) => vars[*i].clone(),
        Node::Neg(a) => format!("(-{})", node(a, c, vars)),
        Node::Bin(Op::Pow, a, b) => {
            let (a, b) = (node(a, c, vars), node(b, c, vars));
            format!("{}({a}, {b})", c.math("pow"))
        }
        Node::Bin(op, a, b) => {
            let (a, b) = (node(a, c, vars), node(b, c, vars));
            let op = match op {
                Op::Add => "+",
                Op::Sub => "-",
                Op::Mul => "*",
                Op::Div => "/",
                Op::Pow => unreachable!("matched above"),
            };
            format!("({a} {op} {b})")
        }
        Node::Call(Func1::Sign, a) => {
            let a = node(a, c, vars);
            format!("{}({a})", c.sign())
        }
        Node::Call(f, a) => {
            let a = node(a, c, vars);
            let name = match f {
                Func1::Sqrt => "sqrt",
                Func1::Exp => "exp",
                Func1::Ln => "log",
                Func1::Log10 => "log10",
                Func1::Sin => "sin",
                Func1::Cos => "cos",
                Func1::Tan => "tan",
                Func1::Asin => "asin",
                Func1::Acos => "acos",
                Func1::Atan => "atan",
                Func1::Sinh => "sinh",
                Func1::Cosh => "cosh",
                Func1::Tanh => "tanh",
                Func1::Abs => "fabs",
                Func1::Floor => "floor",
                Func1::Ceil => "ceil",
                Func1::Sign => unreachable!("matched above"),
            };
            format!("{}({a})", c.math(name))
        }
        Node::Atan2(a, b) => {
            let (a, b) = (node(a, c, vars), node(b, c, vars));
            format!("{}({a}, {b})", c.math("atan2"))
        }
        Node::MinMax { max, args } => {
            // Folded from the first, as `eval` does (fmax/fmin skip a NaN as f64::max/min do).
            let f = c.math(if *max { "fmax" } else { "fmin" });
            let mut args = args.iter();
            let first = args.next().map_or_else(|| "NAN".to_string(), |a| node(a, c, vars));
            args.fold(first, |acc, a| format!("{f}({acc}, {})", node(a, c, vars)))
        }
    }
}
