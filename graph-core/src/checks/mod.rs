//! A graph's own acceptance conditions: `checks:` entries such as
//! `settling_time(y, 1.0, 0.02) < 0.15` or
//! `peak(e_fladrc, 0.6, 1.2) < 0.2 * peak(e_fpid, 0.6, 1.2)`, compiled
//! against the recorded signals and evaluated after a run.
//!
//! A check is `expression OP expression` with OP one of `< <= > >=`; the
//! left side is reported as the measured value, the right as the bound.
//! Both sides use the expression language with the graph's parameters and
//! the metrics of [`metrics::METRICS`], whose first argument is a recorded
//! signal and whose last two optional arguments are a time window.

pub mod metrics;

use crate::diag::{Diagnostic, Pos};
use crate::expr::{Binding, Constants, Expr, Scope};
use crate::params::expr_diagnostic;
use metrics::{LOOP_FIGURES, LoopFigure, Metric};
use std::cell::RefCell;

/// A check as written: optional name, text, position of the text.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckSpec {
    pub name: Option<String>,
    pub text: String,
    pub pos: Pos,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Comparison {
    Less,
    LessEqual,
    Greater,
    GreaterEqual,
}

impl Comparison {
    pub fn symbol(self) -> &'static str {
        match self {
            Comparison::Less => "<",
            Comparison::LessEqual => "<=",
            Comparison::Greater => ">",
            Comparison::GreaterEqual => ">=",
        }
    }

    fn holds(self, a: f64, b: f64) -> bool {
        match self {
            Comparison::Less => a < b,
            Comparison::LessEqual => a <= b,
            Comparison::Greater => a > b,
            Comparison::GreaterEqual => a >= b,
        }
    }
}

/// One value a check needs: a metric of a recorded signal (metric, trace
/// column, arguments), or a figure of the analysed loop.
#[derive(Clone, Debug)]
enum MetricCall {
    Signal { metric: Metric, column: usize, args: Vec<Expr> },
    Loop(LoopFigure),
}

/// A compiled check.
#[derive(Clone, Debug)]
pub struct Check {
    /// The given name, or the text itself.
    pub name: String,
    pub text: String,
    pub pos: Pos,
    lhs: Expr,
    op: Comparison,
    rhs: Expr,
    calls: Vec<MetricCall>,
}

/// The outcome of one check.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckResult {
    pub name: String,
    pub measured: f64,
    pub op: Comparison,
    pub bound: f64,
    pub passed: bool,
}

impl std::fmt::Display for CheckResult {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let verdict = if self.passed { "pass" } else { "FAIL" };
        let (mut m, b) = (significant(self.measured), significant(self.bound));
        // Six digits would hide why a value at its bound passed or failed:
        // give it in full there.
        if m == b && self.measured != self.bound {
            m = self.measured.to_string();
        }
        write!(f, "{verdict}  {}  (measured {m}, bound {} {b})", self.name, self.op.symbol())
    }
}

/// A number to six significant digits, in its shortest form.
fn significant(v: f64) -> String {
    if !v.is_finite() || v == 0.0 {
        return v.to_string();
    }
    let rounded: f64 = format!("{v:.5e}").parse().unwrap_or(v);
    if (1e-4..1e6).contains(&rounded.abs()) { rounded.to_string() } else { format!("{rounded:e}") }
}

/// Names the expressions of a check may use: parameters, and recorded
/// signals inside metric calls.
struct CheckScope<'a> {
    params: &'a [(String, f64)],
    headers: &'a [String],
    calls: RefCell<Vec<MetricCall>>,
}

impl Scope for CheckScope<'_> {
    fn lookup(&self, name: &str) -> Option<Binding> {
        Constants(self.params).lookup(name).or_else(|| {
            let figure = LoopFigure::from_name(name)?;
            let mut calls = self.calls.borrow_mut();
            calls.push(MetricCall::Loop(figure));
            Some(Binding::Slot(calls.len() - 1))
        })
    }

    fn names(&self) -> Vec<String> {
        let signals = self.headers.iter().skip(1).filter(|h| !h.contains('['));
        let figures = LOOP_FIGURES.iter().map(|(n, _, _)| n.to_string());
        Constants(self.params).names().into_iter().chain(signals.cloned()).chain(figures).collect()
    }

    fn is_signal(&self, name: &str) -> bool {
        self.headers.iter().skip(1).any(|h| h == name)
    }

    fn is_signal_function(&self, function: &str) -> bool {
        Metric::from_name(function).is_some()
    }

    fn signal_functions(&self) -> Vec<&'static str> {
        metrics::METRICS.iter().map(|(n, _, _)| *n).collect()
    }

    fn signals(&self) -> Vec<String> {
        self.headers.iter().skip(1).filter(|h| !h.contains('[')).cloned().collect()
    }

    fn signal_call(&self, function: &str, signal: &str, args: Vec<Expr>) -> Result<usize, String> {
        let (metric, own) = Metric::from_name(function).ok_or_else(|| format!("unknown metric `{function}`"))?;
        if args.len() < own.len() || args.len() > own.len() + 2 {
            let mut form = vec!["signal".to_string()];
            form.extend(own.iter().map(|a| a.to_string()));
            return Err(format!(
                "`{function}` takes ({}[, t_from[, t_to]]), got {} argument(s)",
                form.join(", "),
                args.len() + 1
            ));
        }
        let column = self.headers.iter().position(|h| h == signal).ok_or_else(|| format!("no signal `{signal}`"))?;
        let mut calls = self.calls.borrow_mut();
        calls.push(MetricCall::Signal { metric, column, args });
        Ok(calls.len() - 1)
    }
}

/// Splits `a OP b` at its comparison; OP's character offset and kind.
fn split_comparison(text: &str) -> Option<(usize, usize, Comparison)> {
    let (i, c) = text.char_indices().find(|(_, c)| *c == '<' || *c == '>')?;
    let eq = text[i + 1..].starts_with('=');
    let op = match (c, eq) {
        ('<', false) => Comparison::Less,
        ('<', true) => Comparison::LessEqual,
        ('>', false) => Comparison::Greater,
        _ => Comparison::GreaterEqual,
    };
    Some((i, if eq { 2 } else { 1 }, op))
}

/// Compiles checks against the recorded column `headers` (first is `t`);
/// loop figures may be used when the graph has an `analysis:` section.
pub fn compile(
    specs: &[CheckSpec],
    headers: &[String],
    params: &[(String, f64)],
    has_analysis: bool,
) -> Result<Vec<Check>, Diagnostic> {
    specs.iter().map(|spec| compile_one(spec, headers, params, has_analysis)).collect()
}

fn compile_one(
    spec: &CheckSpec,
    headers: &[String],
    params: &[(String, f64)],
    has_analysis: bool,
) -> Result<Check, Diagnostic> {
    let text = spec.text.as_str();
    let Some((at, len, op)) = split_comparison(text) else {
        return Err(Diagnostic::at(&spec.pos, format!("check `{text}` compares nothing"))
            .with_hint("a check is `expression < bound` (or <=, >, >=), e.g. `max_abs(e, 1.0) < 0.01`"));
    };
    if split_comparison(&text[at + len..]).is_some() {
        return Err(Diagnostic::at(&spec.pos, format!("check `{text}` has more than one comparison"))
            .with_hint("write one check per condition"));
    }
    let scope = CheckScope { params, headers, calls: RefCell::new(Vec::new()) };
    let chars_before = |byte: usize| text[..byte].chars().count();
    let side = |from: usize, to: usize| -> Result<Expr, Diagnostic> {
        let part = &text[from..to];
        let pos = spec.pos.shifted(chars_before(from));
        if part.trim().is_empty() {
            return Err(Diagnostic::at(&pos, "this side of the comparison is empty"));
        }
        Expr::parse(part, &scope).map_err(|e| {
            let d = expr_diagnostic(&e, &pos);
            let d = Diagnostic { message: format!("check: {}", d.message), ..d };
            if e.message.starts_with("unknown name") {
                d.or_hint("signals are read through metrics, e.g. final_value(y); only recorded signals count")
            } else {
                d
            }
        })
    };
    let lhs = side(0, at)?;
    let rhs = side(at + len, text.len())?;
    let name = spec.name.clone().unwrap_or_else(|| text.trim().to_string());
    let calls = scope.calls.into_inner();
    if let (false, Some(figure)) = (has_analysis, calls.iter().find_map(MetricCall::figure)) {
        let name = LOOP_FIGURES.iter().find(|(_, f, _)| *f == figure).map_or("", |(n, _, _)| *n);
        return Err(Diagnostic::at(
            &spec.pos,
            format!("check: `{name}` is a figure of the analysed loop, and the graph has no `analysis:` section"),
        )
        .with_hint("add e.g. `analysis: { open: ctrl.u }` to say which loop (the signal where it is cut)"));
    }
    Ok(Check { name, text: text.to_string(), pos: spec.pos.clone(), lhs, op, rhs, calls })
}

impl MetricCall {
    fn figure(&self) -> Option<LoopFigure> {
        match self {
            MetricCall::Loop(f) => Some(*f),
            MetricCall::Signal { .. } => None,
        }
    }
}

impl Check {
    /// Whether the check reads figures of the analysed loop.
    pub fn needs_loop_figures(&self) -> bool {
        self.calls.iter().any(|c| c.figure().is_some())
    }

    /// Why the check cannot measure anything in a run that ends at `stop`:
    /// a metric window (given as constants) that starts after the stop time.
    pub fn window_problem(&self, stop: f64) -> Option<String> {
        self.calls.iter().find_map(|call| {
            let MetricCall::Signal { metric, args, .. } = call else { return None };
            let own = metrics::METRICS.iter().find(|(_, m, _)| m == metric).map_or(0, |(_, _, a)| a.len());
            let from = args.get(own).and_then(Expr::constant)?;
            (from > stop).then(|| format!("its window starts at {from} s, after the stop time {stop} s"))
        })
    }

    /// The check over recorded columns: `columns[0]` is time, the others
    /// in the order of the headers the check was compiled against; loop
    /// figures from `figures`, indexed by [`LoopFigure`] (NaN, and the
    /// check fails, without them). (`Trace::check` is the usual entry.)
    pub fn evaluate(&self, columns: &[Vec<f64>], figures: Option<&[f64]>) -> CheckResult {
        let t = &columns[0];
        let mut vars = vec![f64::NAN; self.calls.len()];
        for (k, call) in self.calls.iter().enumerate() {
            vars[k] = match call {
                MetricCall::Signal { metric, column, args } => {
                    let args: Vec<f64> = args.iter().map(|a| a.eval(&vars)).collect();
                    metrics::evaluate(*metric, t, &columns[*column], &args)
                }
                MetricCall::Loop(f) => figures.and_then(|v| v.get(*f as usize)).copied().unwrap_or(f64::NAN),
            };
        }
        let (measured, bound) = (self.lhs.eval(&vars), self.rhs.eval(&vars));
        CheckResult { name: self.name.clone(), measured, op: self.op, bound, passed: self.op.holds(measured, bound) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Headers and columns of y = t², e = 1 − t on [0, 1].
    fn trace() -> (Vec<String>, Vec<Vec<f64>>) {
        let t: Vec<f64> = (0..=100).map(|i| i as f64 / 100.0).collect();
        let y = t.iter().map(|t| t * t).collect();
        let e = t.iter().map(|t| 1.0 - t).collect();
        (vec!["t".into(), "y".into(), "e".into()], vec![t, y, e])
    }

    fn spec(text: &str) -> CheckSpec {
        CheckSpec { name: None, text: text.into(), pos: Pos::new("g.yaml".into(), 7, 5) }
    }

    fn run(text: &str) -> CheckResult {
        let (headers, columns) = trace();
        let params = vec![("k".to_string(), 2.0)];
        compile(&[spec(text)], &headers, &params, false).unwrap()[0].evaluate(&columns, None)
    }

    #[test]
    fn measured_bound_and_verdict() {
        let r = run("final_value(y) >= 0.5 * k");
        assert_eq!((r.measured, r.bound, r.passed), (1.0, 1.0, true));
        let r = run("max(e, 0.5) < max(y, 0, 0.5)");
        assert_eq!((r.measured, r.bound, r.passed), (0.5, 0.25, false));
        assert_eq!(r.to_string(), "FAIL  max(e, 0.5) < max(y, 0, 0.5)  (measured 0.5, bound < 0.25)");
        // The built-in max of numbers still works beside the metric.
        assert!(run("max(1, 2) <= 2").passed);
        let r = run("settling_time(y, final_value(y), 0.02) < 1");
        assert!(r.passed && (r.measured - 0.98f64.sqrt()).abs() < 1e-3, "{r:?}");
    }

    #[test]
    fn errors_point_into_the_check() {
        let (headers, _) = trace();
        let err = |text: &str| compile(&[spec(text)], &headers, &[], false).unwrap_err();
        let d = err("peak(ee, 0.6) < 1");
        let message = "check: `peak` takes a recorded signal first: `ee` is not a recorded signal";
        assert_eq!((d.pos.clone().unwrap().col, d.message.as_str()), (10, message));
        assert_eq!(d.hint.as_deref(), Some("did you mean `e`?"));
        // A misspelt metric is an unknown function, not an unknown signal.
        let d = err("maxabs(y) < 1");
        assert_eq!((d.pos.clone().unwrap().col, d.message.as_str()), (5, "check: unknown function `maxabs`"));
        assert_eq!(d.hint.as_deref(), Some("did you mean `max_abs`?"));
        // A parameter where a signal belongs is said to be one.
        let d = compile(&[spec("max_abs(k) < 3")], &headers, &[("k".into(), 1.0)], false).unwrap_err();
        assert_eq!(
            d.message,
            "check: `max_abs` takes a recorded signal first: `k` is a parameter, not a recorded signal"
        );
        // An expression of signals where one signal belongs: say so, not "did you mean".
        let d = err("max_abs(y - e) < 1");
        assert_eq!(
            d.message,
            "check: `max_abs` takes a recorded signal first: a signal's name alone, not an expression of signals"
        );
        assert!(d.hint.unwrap().starts_with("record the expression as a signal of its own"));
        // max/min of numbers stay the built-ins.
        assert!(compile(&[spec("max(k, 1) < 3")], &headers, &[("k".into(), 1.0)], false).is_ok());
        let d = err("final_value(y) = 1");
        assert!(d.message.contains("compares nothing"), "{d}");
        let d = err("overshoot(y) < 5");
        assert_eq!(d.message, "check: `overshoot` takes (signal, target[, t_from[, t_to]]), got 1 argument(s)");
        let d = err("0 < final_value(y) < 1");
        assert!(d.message.contains("more than one comparison"), "{d}");
        let d = err("peak(e) < ");
        assert_eq!((d.pos.unwrap().col, d.message.as_str()), (14, "this side of the comparison is empty"));
    }
}
