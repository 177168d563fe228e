//! An expression as a flat postfix program, evaluated on a small stack:
//! the step loop's `fcn` blocks run it every step, and a loop over a few
//! instructions costs a fraction of a recursive walk over boxed nodes.
//! The operations and their order are the tree's, so the values are equal
//! to the bit.

use super::{Func1, Node, Op, apply_bin, apply_func1};

/// The deepest stack the program evaluator keeps (zeroed on every call,
/// so kept small); deeper expressions, rare in a formula, are evaluated by
/// walking the tree.
pub(super) const STACK: usize = 8;

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Instr {
    Const(f64),
    Var(usize),
    Neg,
    Bin(Op),
    Call(Func1),
    Atan2,
    /// Min or max of the top `n` values (n ≥ 1), first to last.
    MinMax {
        max: bool,
        n: usize,
    },
}

/// The postfix program of `node` and the deepest stack it needs.
pub(super) fn compile(node: &Node) -> (Vec<Instr>, usize) {
    fn emit(node: &Node, out: &mut Vec<Instr>, depth: usize, deepest: &mut usize) {
        *deepest = (*deepest).max(depth + 1);
        match node {
            Node::Const(v) => out.push(Instr::Const(*v)),
            Node::Var(i) => out.push(Instr::Var(*i)),
            Node::Neg(a) => {
                emit(a, out, depth, deepest);
                out.push(Instr::Neg);
            }
            Node::Call(f, a) => {
                emit(a, out, depth, deepest);
                out.push(Instr::Call(*f));
            }
            Node::Bin(op, a, b) => {
                emit(a, out, depth, deepest);
                emit(b, out, depth + 1, deepest);
                out.push(Instr::Bin(*op));
            }
            Node::Atan2(a, b) => {
                emit(a, out, depth, deepest);
                emit(b, out, depth + 1, deepest);
                out.push(Instr::Atan2);
            }
            Node::MinMax { max, args } => {
                if args.is_empty() {
                    out.push(Instr::Const(f64::NAN));
                    return;
                }
                for (k, a) in args.iter().enumerate() {
                    emit(a, out, depth + k, deepest);
                }
                out.push(Instr::MinMax { max: *max, n: args.len() });
            }
        }
    }
    let (mut out, mut deepest) = (Vec::new(), 0);
    emit(node, &mut out, 0, &mut deepest);
    (out, deepest)
}

/// Runs `program` (its stack at most [`STACK`] deep) with `vars`.
pub(super) fn run(program: &[Instr], vars: &[f64]) -> f64 {
    let mut stack = [0.0f64; STACK];
    let mut top = 0;
    for instr in program {
        match *instr {
            Instr::Const(v) => {
                stack[top] = v;
                top += 1;
            }
            Instr::Var(i) => {
                stack[top] = vars[i];
                top += 1;
            }
            Instr::Neg => stack[top - 1] = -stack[top - 1],
            Instr::Call(f) => stack[top - 1] = apply_func1(f, stack[top - 1]),
            Instr::Bin(op) => {
                top -= 1;
                stack[top - 1] = apply_bin(op, stack[top - 1], stack[top]);
            }
            Instr::Atan2 => {
                top -= 1;
                stack[top - 1] = stack[top - 1].atan2(stack[top]);
            }
            Instr::MinMax { max, n } => {
                let args = &stack[top - n..top];
                let rest = args[1..].iter().copied();
                let v = if max { rest.fold(args[0], f64::max) } else { rest.fold(args[0], f64::min) };
                top -= n - 1;
                stack[top - 1] = v;
            }
        }
    }
    stack[0]
}
