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

/// A compiled expression.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    root: Node,
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
        let tokens = lex(src)?;
        if tokens.len() > MAX_TOKENS {
            return Err(ExprError {
                offset: tokens[MAX_TOKENS].offset,
                message: format!("expression too long (limit {MAX_TOKENS} numbers, names and symbols)"),
                hint: Some("compute it in steps: parameters, or several blocks".into()),
            });
        }
        let mut p = Parser { tokens, at: 0, scope, len: src.chars().count(), nesting: 0 };
        let root = p.expr()?;
        if let Some(tok) = p.peek() {
            return Err(p.error_at(tok.offset, format!("unexpected {} after the end of the expression", tok.kind)));
        }
        Ok(Expr { root: fold(root) })
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
        eval(&self.root, vars)
    }
}

fn eval(node: &Node, vars: &[f64]) -> f64 {
    match node {
        Node::Const(v) => *v,
        Node::Var(i) => vars[*i],
        Node::Neg(a) => -eval(a, vars),
        Node::Bin(op, a, b) => {
            let (a, b) = (eval(a, vars), eval(b, vars));
            match op {
                Op::Add => a + b,
                Op::Sub => a - b,
                Op::Mul => a * b,
                Op::Div => a / b,
                Op::Pow => a.powf(b),
            }
        }
        Node::Call(f, a) => {
            let a = eval(a, vars);
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
                // sign(0) = 0, as in MATLAB (f64::signum gives 1).
                Func1::Sign => {
                    if a > 0.0 {
                        1.0
                    } else if a < 0.0 {
                        -1.0
                    } else {
                        0.0
                    }
                }
                Func1::Floor => a.floor(),
                Func1::Ceil => a.ceil(),
            }
        }
        Node::Atan2(a, b) => eval(a, vars).atan2(eval(b, vars)),
        Node::MinMax { max, args } => {
            let mut it = args.iter().map(|a| eval(a, vars));
            let first = it.next().unwrap_or(f64::NAN);
            if *max { it.fold(first, f64::max) } else { it.fold(first, f64::min) }
        }
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
    if is_const { Node::Const(eval(&folded, &[])) } else { folded }
}

#[derive(Clone, Debug, PartialEq)]
enum TokKind {
    Num(f64),
    Name(String),
    Sym(char),
}

impl fmt::Display for TokKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TokKind::Num(v) => write!(f, "number {v}"),
            TokKind::Name(n) => write!(f, "name `{n}`"),
            TokKind::Sym(c) => write!(f, "`{c}`"),
        }
    }
}

struct Tok {
    kind: TokKind,
    offset: usize,
}

fn lex(src: &str) -> Result<Vec<Tok>, ExprError> {
    let chars: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() || (c == '.' && chars.get(i + 1).is_some_and(char::is_ascii_digit)) {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            // Exponent: 1e-4, 2.5E+3 (only when digits follow).
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut j = i + 1;
                if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    i = j;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            let text: String = chars[start..i].iter().collect();
            let v = text.parse::<f64>().map_err(|_| ExprError {
                offset: start,
                message: format!("`{text}` is not a number"),
                hint: None,
            })?;
            out.push(Tok { kind: TokKind::Num(v), offset: start });
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push(Tok { kind: TokKind::Name(chars[start..i].iter().collect()), offset: start });
        } else if "+-*/^(),".contains(c) {
            out.push(Tok { kind: TokKind::Sym(c), offset: i });
            i += 1;
        } else {
            return Err(ExprError { offset: i, message: format!("unexpected character `{c}`"), hint: None });
        }
    }
    Ok(out)
}

/// The most tokens an expression may have: its tree, evaluated
/// recursively, then stays a few thousand levels deep at most.
pub const MAX_TOKENS: usize = 4096;

/// The deepest nesting of parentheses, calls, signs and powers.
pub const MAX_NESTING: usize = 256;

struct Parser<'a> {
    tokens: Vec<Tok>,
    at: usize,
    scope: &'a dyn Scope,
    len: usize,
    /// Current depth of recursive descent into nested constructs.
    nesting: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Tok> {
        self.tokens.get(self.at)
    }

    fn eat(&mut self, sym: char) -> bool {
        if self.peek().is_some_and(|t| t.kind == TokKind::Sym(sym)) {
            self.at += 1;
            true
        } else {
            false
        }
    }

    fn error_at(&self, offset: usize, message: String) -> ExprError {
        ExprError { offset, message, hint: None }
    }

    fn end_offset(&self) -> usize {
        self.peek().map_or(self.len, |t| t.offset)
    }

    fn require(&mut self, sym: char) -> Result<(), ExprError> {
        if self.eat(sym) {
            return Ok(());
        }
        let found = self.peek().map_or("the end".to_string(), |t| t.kind.to_string());
        Err(self.error_at(self.end_offset(), format!("expected `{sym}`, found {found}")))
    }

    fn expr(&mut self) -> Result<Node, ExprError> {
        let mut lhs = self.term()?;
        loop {
            let op = if self.eat('+') {
                Op::Add
            } else if self.eat('-') {
                Op::Sub
            } else {
                return Ok(lhs);
            };
            lhs = Node::Bin(op, Box::new(lhs), Box::new(self.term()?));
        }
    }

    fn term(&mut self) -> Result<Node, ExprError> {
        let mut lhs = self.unary()?;
        loop {
            let op = if self.eat('*') {
                Op::Mul
            } else if self.eat('/') {
                Op::Div
            } else {
                return Ok(lhs);
            };
            lhs = Node::Bin(op, Box::new(lhs), Box::new(self.unary()?));
        }
    }

    /// Runs `inner` one nesting level deeper, refusing to go past
    /// [`MAX_NESTING`] (deep input must not overflow the stack).
    fn nested<T>(&mut self, inner: impl FnOnce(&mut Self) -> Result<T, ExprError>) -> Result<T, ExprError> {
        if self.nesting >= MAX_NESTING {
            return Err(self.error_at(self.end_offset(), format!("nested too deeply (limit {MAX_NESTING})")));
        }
        self.nesting += 1;
        let result = inner(self);
        self.nesting -= 1;
        result
    }

    fn unary(&mut self) -> Result<Node, ExprError> {
        self.nested(Self::unary_inner)
    }

    fn unary_inner(&mut self) -> Result<Node, ExprError> {
        if self.eat('-') {
            return Ok(Node::Neg(Box::new(self.unary()?)));
        }
        if self.eat('+') {
            return self.unary();
        }
        let base = self.atom()?;
        if self.eat('^') {
            return Ok(Node::Bin(Op::Pow, Box::new(base), Box::new(self.unary()?)));
        }
        Ok(base)
    }

    fn atom(&mut self) -> Result<Node, ExprError> {
        let Some(tok) = self.tokens.get(self.at) else {
            return Err(self.error_at(self.len, "expression ends too early".into()));
        };
        let offset = tok.offset;
        match tok.kind.clone() {
            TokKind::Num(v) => {
                self.at += 1;
                Ok(Node::Const(v))
            }
            TokKind::Sym('(') => {
                self.at += 1;
                let inner = self.expr()?;
                self.require(')')?;
                Ok(inner)
            }
            TokKind::Name(name) => {
                self.at += 1;
                if self.eat('(') { self.call(&name, offset) } else { self.name(&name, offset) }
            }
            other => Err(self.error_at(offset, format!("expected a number, a name or `(`, found {other}"))),
        }
    }

    fn name(&self, name: &str, offset: usize) -> Result<Node, ExprError> {
        match self.scope.lookup(name) {
            Some(Binding::Value(v)) => Ok(Node::Const(v)),
            Some(Binding::Slot(i)) => Ok(Node::Var(i)),
            None if name == "pi" => Ok(Node::Const(std::f64::consts::PI)),
            None if name == "inf" => Ok(Node::Const(f64::INFINITY)),
            None => {
                let names = self.scope.names();
                let hint = crate::diag::closest(name, names.iter().map(String::as_str).chain(["pi", "inf"]))
                    .map(|c| format!("did you mean `{c}`?"))
                    .or_else(|| (!names.is_empty()).then(|| format!("known names here: {}", names.join(", "))));
                Err(ExprError { offset, message: format!("unknown name `{name}`"), hint })
            }
        }
    }

    fn call(&mut self, name: &str, offset: usize) -> Result<Node, ExprError> {
        if let Some(signal) = self.signal_argument(name) {
            return self.signal_call(name, &signal, offset);
        }
        let builtin = FUNC1.iter().any(|(n, _)| *n == name) || FUNC2.contains(&name) || VARIADIC.contains(&name);
        if !builtin {
            return Err(self.not_a_function(name, offset));
        }
        let mut args = vec![self.expr()?];
        while self.eat(',') {
            args.push(self.expr()?);
        }
        self.require(')')?;
        let n = args.len();
        let arity_error =
            |want: &str| ExprError { offset, message: format!("`{name}` takes {want}, got {n}"), hint: None };
        if let Some(&(_, f)) = FUNC1.iter().find(|(n, _)| *n == name) {
            if args.len() != 1 {
                return Err(arity_error("one argument"));
            }
            return Ok(Node::Call(f, Box::new(args.remove(0))));
        }
        if FUNC2.contains(&name) {
            if args.len() != 2 {
                return Err(arity_error("two arguments"));
            }
            let (b, a) = (args.pop(), args.pop());
            let (Some(a), Some(b)) = (a, b) else {
                return Err(arity_error("two arguments"));
            };
            return Ok(if name == "atan2" {
                Node::Atan2(Box::new(a), Box::new(b))
            } else {
                Node::Bin(Op::Pow, Box::new(a), Box::new(b))
            });
        }
        Ok(Node::MinMax { max: name == "max", args })
    }

    /// Why `name(` cannot be called: a signal function whose first argument
    /// is not a recorded signal, or no function at all.
    fn not_a_function(&self, name: &str, offset: usize) -> ExprError {
        if self.scope.is_signal_function(name) {
            let signals = self.scope.signals();
            let (what, hint) = match self.tokens.get(self.at).map(|t| &t.kind) {
                Some(TokKind::Name(arg)) if self.scope.lookup(arg).is_some() => {
                    (format!("`{arg}` is a parameter, not a recorded signal"), None)
                }
                Some(TokKind::Name(arg)) if signals.iter().any(|s| s == arg) => (
                    "a signal's name alone, not an expression of signals".to_string(),
                    Some("record the expression as a signal of its own (a `sum` or `fcn` block) and name that".into()),
                ),
                Some(TokKind::Name(arg)) => (
                    format!("`{arg}` is not a recorded signal"),
                    crate::diag::closest(arg, signals.iter().map(String::as_str))
                        .map(|c| format!("did you mean `{c}`?")),
                ),
                _ => ("its first argument must be a recorded signal's name".to_string(), None),
            };
            let hint =
                hint.or_else(|| (!signals.is_empty()).then(|| format!("recorded signals: {}", signals.join(", "))));
            // Point at the argument that is wrong.
            let offset = self.tokens.get(self.at).map_or(offset, |t| t.offset);
            return ExprError { offset, message: format!("`{name}` takes a recorded signal first: {what}"), hint };
        }
        let metrics = self.scope.signal_functions();
        let all: Vec<&str> = FUNC1
            .iter()
            .map(|(n, _)| *n)
            .chain(FUNC2.iter().copied())
            .chain(VARIADIC)
            .chain(metrics.iter().copied())
            .collect();
        let hint = crate::diag::closest(name, all.iter().copied())
            .map(|c| format!("did you mean `{c}`?"))
            .or_else(|| (!metrics.is_empty()).then(|| format!("metrics: {}", metrics.join(", "))));
        ExprError { offset, message: format!("unknown function `{name}`"), hint }
    }

    /// The signal named by the first argument of `function(`, when the
    /// scope has such a function and such a signal (`max(y, 0, 1)` is the
    /// metric; `max(a, b)` of numbers stays the built-in).
    fn signal_argument(&self, function: &str) -> Option<String> {
        if !self.scope.is_signal_function(function) {
            return None;
        }
        let (Some(first), Some(next)) = (self.tokens.get(self.at), self.tokens.get(self.at + 1)) else { return None };
        match (&first.kind, &next.kind) {
            (TokKind::Name(sig), TokKind::Sym(',' | ')')) if self.scope.is_signal(sig) => Some(sig.clone()),
            _ => None,
        }
    }

    fn signal_call(&mut self, function: &str, signal: &str, offset: usize) -> Result<Node, ExprError> {
        self.at += 1;
        let mut args = Vec::new();
        while self.eat(',') {
            args.push(Expr { root: fold(self.expr()?) });
        }
        self.require(')')?;
        let slot = self.scope.signal_call(function, signal, args).map_err(|message| ExprError {
            offset,
            message,
            hint: None,
        })?;
        Ok(Node::Var(slot))
    }
}

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

#[cfg(test)]
mod tests;
