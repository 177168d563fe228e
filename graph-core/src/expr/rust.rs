//! An expression as Rust, for a generated step (an `fcn` block inlined
//! where the step computes its output): the tree written out with the
//! operations `eval` performs, in its order, parenthesised, and the same
//! `f64` methods — so the value is the interpreter's, to the bit. The
//! constants are not written in: the step reads them from the block's
//! values at run time ([`Expr::constants`]), so one build serves every
//! value a sweep or `--set` gives them, and the code (and its
//! fingerprint) depends on the formula's shape alone.

use super::{Expr, FUNC1, Func1, Node, Op};

impl Expr {
    /// The Rust expression, with variable slot i written `vars[i]` and
    /// the j-th of [`Expr::constants`] written `constant(j)`.
    pub fn to_rust(&self, vars: &[String], constant: &dyn Fn(usize) -> String) -> String {
        let mut next = 0;
        bare(node(&self.root, vars, constant, &mut next))
    }

    /// The constants in the order [`Expr::to_rust`] numbers them.
    pub fn constants(&self) -> Vec<f64> {
        fn walk(n: &Node, out: &mut Vec<f64>) {
            match n {
                Node::Const(v) => out.push(*v),
                Node::Var(_) => {}
                Node::Neg(a) | Node::Call(_, a) => walk(a, out),
                Node::Bin(_, a, b) | Node::Atan2(a, b) => {
                    walk(a, out);
                    walk(b, out);
                }
                Node::MinMax { args, .. } => args.iter().for_each(|a| walk(a, out)),
            }
        }
        let mut out = Vec::new();
        walk(&self.root, &mut out);
        out
    }
}

/// An operation's text is parenthesised (an operand of another); as a
/// whole value or a function's argument, where the compiler would warn of
/// the parentheses, it goes without them.
fn bare(text: String) -> String {
    match text.strip_prefix('(').and_then(|t| t.strip_suffix(')')) {
        Some(inner) if encloses(&text) => inner.to_string(),
        _ => text,
    }
}

/// Whether `text`'s first parenthesis closes at its end: `(a) + (b)` is
/// not enclosed.
fn encloses(text: &str) -> bool {
    let mut depth = 0;
    for (i, c) in text.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            _ => {}
        }
        if depth == 0 {
            return i == text.len() - 1;
        }
    }
    false
}

fn node(n: &Node, vars: &[String], constant: &dyn Fn(usize) -> String, next: &mut usize) -> String {
    let mut sub = |a: &Node| node(a, vars, constant, next);
    match n {
        Node::Const(_) => {
            *next += 1;
            constant(*next - 1)
        }
        Node::Var(i) => vars[*i].clone(),
        Node::Neg(a) => format!("(-{})", sub(a)),
        Node::Bin(op, a, b) => {
            let (a, b) = (sub(a), sub(b));
            match op {
                Op::Add => format!("({a} + {b})"),
                Op::Sub => format!("({a} - {b})"),
                Op::Mul => format!("({a} * {b})"),
                Op::Div => format!("({a} / {b})"),
                Op::Pow => format!("f64::powf({}, {})", bare(a), bare(b)),
            }
        }
        Node::Call(Func1::Sign, a) => format!("::ctlgraph_core::expr::sign({})", bare(sub(a))),
        Node::Call(f, a) => {
            // The language's names are the `f64` methods' (sign excepted).
            let name = FUNC1.iter().find(|(_, g)| g == f).map_or("", |(name, _)| name);
            format!("f64::{name}({})", bare(sub(a)))
        }
        Node::Atan2(a, b) => {
            let (a, b) = (bare(sub(a)), bare(sub(b)));
            format!("f64::atan2({a}, {b})")
        }
        Node::MinMax { max, args } => {
            // Folded from the first, as `eval` does.
            let f = if *max { "f64::max" } else { "f64::min" };
            let mut args = args.iter();
            let first = args.next().map_or_else(|| "f64::NAN".to_string(), |a| bare(sub(a)));
            args.fold(first, |acc, a| format!("{f}({acc}, {})", bare(sub(a))))
        }
    }
}
