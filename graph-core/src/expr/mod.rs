//! The expression language of graph files: parameter values, array
//! elements, and the `fcn` block's formula.
//!
//! ```text
//! expr   := term (('+' | '-') term)*
//! term   := unary (('*' | '/') unary)*
//! unary  := ('-' | '+') unary | power
//! power  := atom ('^' unary)?            right-associative: 2^3^2 = 2^9
//! atom   := number | name | name '(' expr (',' expr)* ')' | '(' expr ')'
//! ```
//!
//! `-2^2` is −4 (as in MATLAB and mathematics). Functions: `sqrt exp ln log10
//! sin cos tan asin acos atan sinh cosh tanh abs sign floor ceil` of one
//! argument, `atan2 pow` of two, `min max` of one or more; constants `pi` and `inf`.
//! Parsing resolves every name once, to a constant or to a variable slot, so
//! evaluation does no lookups and allocates nothing.

mod c;
mod rust;

use std::fmt;

/// What a name stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Binding {
    /// A known value (a graph parameter), folded into the expression.
    Value(f64),
    /// Index into the variables passed to [`Expr::eval`].
    Slot(usize),
}

/// The names an expression may use.
pub trait Scope {
    fn lookup(&self, name: &str) -> Option<Binding>;
    /// All names, for "did you mean" hints.
    fn names(&self) -> Vec<String>;

    /// Whether `name` is a signal that functions such as `peak(e, 0.6, 1.2)`
    /// take as first argument (the `checks:` metrics).
    fn is_signal(&self, _name: &str) -> bool {
        false
    }

    /// Whether `function` is a function of a signal.
    fn is_signal_function(&self, _function: &str) -> bool {
        false
    }

    /// The names of the signal functions, for hints.
    fn signal_functions(&self) -> Vec<&'static str> {
        Vec::new()
    }

    /// The signals, for hints.
    fn signals(&self) -> Vec<String> {
        Vec::new()
    }

    /// Registers a call of a signal function, evaluated outside the
    /// expression, and returns the variable slot its value will occupy.
    fn signal_call(&self, function: &str, _signal: &str, _args: Vec<Expr>) -> Result<usize, String> {
        Err(format!("`{function}` is not available here"))
    }
}

/// A parse error at a character offset within the expression text.
#[derive(Clone, Debug, PartialEq)]
pub struct ExprError {
    pub offset: usize,
    pub message: String,
    pub hint: Option<String>,
}

impl fmt::Display for ExprError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Func1 {
    Sqrt,
    Exp,
    Ln,
    Log10,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Abs,
    Sign,
    Floor,
    Ceil,
}

const FUNC1: [(&str, Func1); 17] = [
    ("sqrt", Func1::Sqrt),
    ("exp", Func1::Exp),
    ("ln", Func1::Ln),
    ("log10", Func1::Log10),
    ("sin", Func1::Sin),
    ("cos", Func1::Cos),
    ("tan", Func1::Tan),
    ("asin", Func1::Asin),
    ("acos", Func1::Acos),
    ("atan", Func1::Atan),
    ("sinh", Func1::Sinh),
    ("cosh", Func1::Cosh),
    ("tanh", Func1::Tanh),
    ("abs", Func1::Abs),
    ("sign", Func1::Sign),
    ("floor", Func1::Floor),
    ("ceil", Func1::Ceil),
];
const FUNC2: [&str; 2] = ["atan2", "pow"];
const VARIADIC: [&str; 2] = ["min", "max"];

/// A compiled expression: its tree, and the tree as a postfix program
/// when its stack fits [`program::STACK`].
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    root: Node,
    program: Option<Vec<program::Instr>>,
}

#[derive(Clone, Debug, PartialEq)]
enum Node {
    Const(f64),
    Var(usize),
    Neg(Box<Node>),
    Bin(Op, Box<Node>, Box<Node>),
    Call(Func1, Box<Node>),
    Atan2(Box<Node>, Box<Node>),
    MinMax { max: bool, args: Vec<Node> },
}

impl Expr {
    /// Parses `src`, resolving names through `scope`.
    pub fn parse(src: &str, scope: &dyn Scope) -> Result<Expr, ExprError> {
        Ok(Expr::new(fold(parse::parse(src, scope)?)))
    }

    fn new(root: Node) -> Expr {
        let (program, depth) = program::compile(&root);
        Expr { program: (depth <= program::STACK).then_some(program), root }
    }

    /// The value, if the expression uses no variables.
    pub fn constant(&self) -> Option<f64> {
        match self.root {
            Node::Const(v) => Some(v),
            _ => None,
        }
    }

    /// Whether the expression reads variable slot `slot`.
    pub fn uses_slot(&self, slot: usize) -> bool {
        fn walk(n: &Node, slot: usize) -> bool {
            match n {
                Node::Const(_) => false,
                Node::Var(i) => *i == slot,
                Node::Neg(a) | Node::Call(_, a) => walk(a, slot),
                Node::Bin(_, a, b) | Node::Atan2(a, b) => walk(a, slot) || walk(b, slot),
                Node::MinMax { args, .. } => args.iter().any(|a| walk(a, slot)),
            }
        }
        walk(&self.root, slot)
    }

    /// Evaluates with `vars` bound to the slots handed out by the scope.
    pub fn eval(&self, vars: &[f64]) -> f64 {
        match &self.program {
            Some(program) => program::run(program, vars),
            None => eval(&self.root, vars),
        }
    }
}

fn eval(node: &Node, vars: &[f64]) -> f64 {
    match node {
        Node::Const(v) => *v,
        Node::Var(i) => vars[*i],
        Node::Neg(a) => -eval(a, vars),
        Node::Bin(op, a, b) => apply_bin(*op, eval(a, vars), eval(b, vars)),
        Node::Call(f, a) => apply_func1(*f, eval(a, vars)),
        Node::Atan2(a, b) => eval(a, vars).atan2(eval(b, vars)),
        Node::MinMax { max, args } => {
            let mut it = args.iter().map(|a| eval(a, vars));
            let first = it.next().unwrap_or(f64::NAN);
            if *max { it.fold(first, f64::max) } else { it.fold(first, f64::min) }
        }
    }
}

fn apply_bin(op: Op, a: f64, b: f64) -> f64 {
    match op {
        Op::Add => a + b,
        Op::Sub => a - b,
        Op::Mul => a * b,
        Op::Div => a / b,
        Op::Pow => a.powf(b),
    }
}

fn apply_func1(f: Func1, a: f64) -> f64 {
    match f {
        Func1::Sqrt => a.sqrt(),
        Func1::Exp => a.exp(),
        Func1::Ln => a.ln(),
        Func1::Log10 => a.log10(),
        Func1::Sin => a.sin(),
        Func1::Cos => a.cos(),
        Func1::Tan => a.tan(),
        Func1::Asin => a.asin(),
        Func1::Acos => a.acos(),
        Func1::Atan => a.atan(),
        Func1::Sinh => a.sinh(),
        Func1::Cosh => a.cosh(),
        Func1::Tanh => a.tanh(),
        Func1::Abs => a.abs(),
        Func1::Sign => sign(a),
        Func1::Floor => a.floor(),
        Func1::Ceil => a.ceil(),
    }
}

/// The expression language's `sign`: sign(0) = 0 as in MATLAB
/// (`f64::signum` gives 1), and sign(NaN) = 0.
#[inline]
pub fn sign(a: f64) -> f64 {
    if a > 0.0 {
        1.0
    } else if a < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Folds constant subtrees so parameter expressions become plain numbers.
fn fold(node: Node) -> Node {
    let folded = match node {
        Node::Neg(a) => Node::Neg(Box::new(fold(*a))),
        Node::Bin(op, a, b) => Node::Bin(op, Box::new(fold(*a)), Box::new(fold(*b))),
        Node::Call(f, a) => Node::Call(f, Box::new(fold(*a))),
        Node::Atan2(a, b) => Node::Atan2(Box::new(fold(*a)), Box::new(fold(*b))),
        Node::MinMax { max, args } => Node::MinMax { max, args: args.into_iter().map(fold).collect() },
        leaf => leaf,
    };
    let is_const = match &folded {
        Node::Const(_) => return folded,
        Node::Var(_) => false,
        Node::Neg(a) | Node::Call(_, a) => matches!(**a, Node::Const(_)),
        Node::Bin(_, a, b) | Node::Atan2(a, b) => {
            matches!((&**a, &**b), (Node::Const(_), Node::Const(_)))
        }
        Node::MinMax { args, .. } => args.iter().all(|a| matches!(a, Node::Const(_))),
    };
    if is_const {
        return Node::Const(eval(&folded, &[]));
    }
    match folded {
        // x^2 as x·x: C compilers fold `pow(x, 2.0)` into that product (gcc
        // at any optimisation level), so evaluating it so keeps the
        // generated C (`codegen --target c`) equal to the simulation to the
        // bit — and x·x is correctly rounded, which the C library's `pow`
        // need not be.
        Node::Bin(Op::Pow, a, b) if *b == Node::Const(2.0) => Node::Bin(Op::Mul, a.clone(), a),
        other => other,
    }
}

/// The most tokens an expression may have: its tree, evaluated
/// recursively, then stays a few thousand levels deep at most.
pub const MAX_TOKENS: usize = 4096;

/// The deepest nesting of parentheses, calls, signs and powers.
pub const MAX_NESTING: usize = 256;

/// A scope of fixed named values (graph parameters).
pub struct Constants<'a>(pub &'a [(String, f64)]);

impl Scope for Constants<'_> {
    fn lookup(&self, name: &str) -> Option<Binding> {
        self.0.iter().rev().find(|(n, _)| n == name).map(|&(_, v)| Binding::Value(v))
    }
    fn names(&self) -> Vec<String> {
        self.0.iter().map(|(n, _)| n.clone()).collect()
    }
}

mod parse;
mod program;
#[cfg(test)]
mod tests;
