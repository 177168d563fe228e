//! The `fcn` block: a formula of its inputs and t, compiled once by the
//! expression language (`ctlgraph_core::expr`), and its C form.

use super::port_names;
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::expr::Expr;
use ctlgraph_core::params::{VarScope, expr_diagnostic};
use ctlgraph_core::registry::Built;
use ctlgraph_core::yaml::Kind;
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, SampleTime, Width};

/// A compiled expression over `[u1, …, un, t]`.
#[derive(Clone)]
pub struct Fcn {
    expr: Expr,
    vars: Vec<f64>,
}

impl Block for Fcn {
    rust_type!(Fcn);
    fn updates(&self) -> bool {
        false
    }
    fn output(&mut self, io: &mut Io) {
        let n = self.vars.len() - 1;
        for i in 0..n {
            self.vars[i] = io.u(i);
        }
        self.vars[n] = io.t;
        let v = self.expr.eval(&self.vars);
        io.set(0, v);
    }
    fn formula(&self) -> Option<&Expr> {
        Some(&self.expr)
    }
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let n = self.vars.len() - 1;
        let mut vars: Vec<String> = (0..n).map(|i| c.u(i).to_string()).collect();
        vars.push(if self.expr.uses_slot(n) { c.time().to_string() } else { String::new() });
        let value = self.expr.to_c(c, &vars);
        c.equation("y = the formula, operation by operation");
        c.output(format!("{} = {value};", c.y(0)));
        Ok(())
    }
}

pub(super) fn build_fcn(p: &mut Params) -> Result<Built, Diagnostic> {
    let n = p.number_where("inputs", None, |v| v >= 0.0 && v.fract() == 0.0 && v < 1e4, "a whole number")?;
    let n = n as usize;
    let Some(src) = p.raw("expr") else {
        return Err(p.block_error("missing parameter `expr`"));
    };
    let (text, pos) = match &src.kind {
        Kind::Str(s) => (s.clone(), src.pos.clone()),
        Kind::Num(v) => (v.to_string(), src.pos.clone()),
        _ => {
            return Err(p.error("expr", format!("expected a formula, found {}", src.describe())));
        }
    };
    let names = port_names(n);
    let mut vars: Vec<&str> = names.iter().map(String::as_str).collect();
    if n == 1 {
        // `u` and `u1` both name the single input: slot 0 either way.
        vars = vec!["u1"];
    }
    vars.push("t");
    struct Alias<'a>(VarScope<'a>);
    impl ctlgraph_core::expr::Scope for Alias<'_> {
        fn lookup(&self, name: &str) -> Option<ctlgraph_core::expr::Binding> {
            let name = if name == "u" && self.0.vars.len() == 2 { "u1" } else { name };
            self.0.lookup(name)
        }
        fn names(&self) -> Vec<String> {
            self.0.names()
        }
    }
    let scope = Alias(VarScope { vars: &vars, params: p.scope() });
    let expr = Expr::parse(&text, &scope).map_err(|e| {
        let d = expr_diagnostic(&e, &pos);
        Diagnostic { message: format!("block `{}` (fcn): `expr`: {}", p.block_name(), d.message), ..d }
    })?;
    let reads_time = expr.uses_slot(n);
    let default = if reads_time { SampleTime::Continuous } else { SampleTime::Inherited };
    let mut iface = Interface::new(p.sample_time_or(default)?);
    if !reads_time {
        iface = iface.piecewise_constant();
    }
    for name in &names {
        iface = iface.input(name, Width::Fixed(1), true);
    }
    Ok(Built::new(Fcn { expr, vars: vec![0.0; n + 1] }, iface.output("y", Width::Fixed(1))))
}
