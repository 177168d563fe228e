//! The expression language's lexer and recursive-descent parser: source
//! text to a tree of [`Node`]s, names resolved through a [`Scope`], with
//! positioned errors and limits on length and nesting.

use super::{Binding, Expr, ExprError, FUNC1, FUNC2, MAX_NESTING, MAX_TOKENS, Node, Op, Scope, VARIADIC, fold};
use std::fmt;

/// Parses `src` into a tree (not yet folded).
pub(super) fn parse(src: &str, scope: &dyn Scope) -> Result<Node, ExprError> {
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
    Ok(root)
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
            args.push(Expr::new(fold(self.expr()?)));
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
