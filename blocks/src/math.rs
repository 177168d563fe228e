//! Memoryless math: gain, sum, product, divide, abs, sign, min, max, and
//! `fcn` (an expression of the inputs and time). All elementwise on any
//! width, scalar inputs broadcast.

use crate::nonlinear::Piecewise;
use crate::{SAMPLE_TIME_INHERITED, U_ANY, Y_SAME, Y_SCALAR, table::*};
use ctlgraph_core::expr::Expr;
use ctlgraph_core::params::{VarScope, expr_diagnostic};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::yaml::Kind;
use ctlgraph_core::{Block, Crossing, Diagnostic, Interface, Io, Kernel, Params, SampleTime, Width};

const UN: &[PortDoc] = &[PortDoc { name: "u1 … un", doc: "any widths; scalars broadcast" }];
const Y_ELEMENTWISE: &[PortDoc] = &[PortDoc { name: "y", doc: "width of the widest input" }];

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "gain",
        category: "math",
        summary: "Multiplication by a constant: elementwise, or a matrix gain.",
        doc: "y = k·u. A scalar `k` scales every element; a list applies elementwise (length = input \
              width); a list of rows is a matrix K and y = K u (width rows(K)).",
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[
            param("k", Number(1.0), "number, list (elementwise) or list of rows (matrix)"),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_gain,
    },
    BlockType {
        name: "sum",
        category: "math",
        summary: "Adds and subtracts inputs: signs like `+-+`.",
        doc: "y = Σ sᵢ·uᵢ with sᵢ from `signs` (one character per input port u1 … un). With a single \
              sign the block sums the elements of its one (vector) input into a scalar.",
        inputs: UN,
        outputs: Y_ELEMENTWISE,
        params: &[param("signs", Word("++"), "one + or - per input"), SAMPLE_TIME_INHERITED],
        build: build_sum,
    },
    BlockType {
        name: "product",
        category: "math",
        summary: "Multiplies (and divides) inputs elementwise.",
        doc: "y = u1 ∘ u2 ∘ … with ∘ from `ops` (`*` multiply, `/` divide), e.g. `**/` = u1·u2/u3. \
              Division by zero gives ±inf, which stops the run naming this block.",
        inputs: UN,
        outputs: Y_ELEMENTWISE,
        params: &[param("ops", Word("**"), "one * or / per input"), SAMPLE_TIME_INHERITED],
        build: build_product,
    },
    BlockType {
        name: "divide",
        category: "math",
        summary: "y = u1 / u2, elementwise.",
        doc: "y = u1 / u2. Division by zero gives ±inf or NaN, which stops the run naming this block.",
        inputs: &[PortDoc { name: "u1", doc: "numerator" }, PortDoc { name: "u2", doc: "denominator" }],
        outputs: Y_ELEMENTWISE,
        params: &[SAMPLE_TIME_INHERITED],
        build: build_divide,
    },
    BlockType {
        name: "abs",
        category: "math",
        summary: "Absolute value, elementwise.",
        doc: concat!("y = |u|; pieces −u and u either side of 0.", crate::nonlinear::piecewise_doc!()),
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[SAMPLE_TIME_INHERITED],
        build: build_abs,
    },
    BlockType {
        name: "sign",
        category: "math",
        summary: "Signum, elementwise: -1, 0 or 1.",
        doc: concat!(
            "y = sign(u), with sign(0) = 0 (as MATLAB); pieces −1 and 1 either side of 0.",
            crate::nonlinear::piecewise_doc!()
        ),
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[SAMPLE_TIME_INHERITED],
        build: build_sign,
    },
    BlockType {
        name: "min",
        category: "math",
        summary: "Elementwise minimum of the inputs (or of one vector's elements).",
        doc: "y = min(u1, …, un) elementwise; with `inputs: 1`, the smallest element of u1.\nModes: the selected input is chosen at major steps and frozen in minor steps; zero crossings of \
              uj − u_selected locate where another input takes over (for the multi-input form).",
        inputs: UN,
        outputs: Y_ELEMENTWISE,
        params: &[param("inputs", Number(2.0), "number of input ports"), SAMPLE_TIME_INHERITED],
        build: build_min,
    },
    BlockType {
        name: "max",
        category: "math",
        summary: "Elementwise maximum of the inputs (or of one vector's elements).",
        doc: "y = max(u1, …, un) elementwise; with `inputs: 1`, the largest element of u1.\nModes: the selected input is chosen at major steps and frozen in minor steps; zero crossings of \
              uj − u_selected locate where another input takes over (for the multi-input form).",
        inputs: UN,
        outputs: Y_ELEMENTWISE,
        params: &[param("inputs", Number(2.0), "number of input ports"), SAMPLE_TIME_INHERITED],
        build: build_max,
    },
    BlockType {
        name: "fcn",
        category: "math",
        summary: "y = an expression of the inputs u1 … un and time t.",
        doc: "The expression language of parameters (+ - * / ^, sqrt exp ln sin cos tan atan2 abs min \
              max …, pi) over the scalar inputs `u1` … `un` (`u` when there is one), the time `t` and \
              the graph's parameters. Compiled once; evaluation allocates nothing. Runs continuously \
              when it reads `t`, else at the rate of its inputs.",
        inputs: &[PortDoc { name: "u1 … un", doc: "scalars (`u` when inputs: 1)" }],
        outputs: Y_SCALAR,
        params: &[
            param("expr", Required, "the formula, e.g. \"u1 * sin(2*pi*t)\""),
            param("inputs", Number(1.0), "number of input ports (0: a function of time only)"),
            param(
                "sample_time",
                Described("0 when expr reads t, else -1"),
                "-1 inherit from inputs, 0 continuous, T > 0 every T seconds, [T, offset]",
            )
            .kind(ParamKind::SampleTime),
        ],
        build: build_fcn,
    },
];

fn port_names(n: usize) -> Vec<String> {
    (1..=n).map(|i| format!("u{i}")).collect()
}

/// An elementwise block over n inputs of common width.
fn nary(p: &mut Params, n: usize, block: impl Block + 'static) -> Result<Built, Diagnostic> {
    let mut iface = Interface::new(p.sample_time()?).piecewise_constant();
    for name in port_names(n) {
        iface = iface.input(&name, Width::Common, true);
    }
    Ok(Built::new(block, iface.output("y", Width::Common)))
}

fn build_abs(p: &mut Params) -> Result<Built, Diagnostic> {
    Piecewise::new(vec![0.0], |_, r, u| if r == 0 { -u } else { u }).build(p)
}

/// sign(0) = 0, as MATLAB.
pub fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

fn build_sign(p: &mut Params) -> Result<Built, Diagnostic> {
    Piecewise::new(vec![0.0], |_, r, u| {
        if u == 0.0 {
            0.0
        } else if r == 0 {
            -1.0
        } else {
            1.0
        }
    })
    .build(p)
}

#[derive(Clone)]
pub enum Gain {
    Elementwise(Vec<f64>),
    /// Row-major, `rows × cols`.
    Matrix {
        k: Vec<f64>,
        cols: usize,
    },
}

impl Block for Gain {
    rust_type!(Gain);
    fn updates(&self) -> bool {
        false
    }
    fn set_width(&mut self, width: usize) -> Result<(), String> {
        match self {
            Gain::Elementwise(k) if k.len() == 1 => {
                let v = k[0];
                *k = vec![v; width];
                Ok(())
            }
            Gain::Elementwise(k) if k.len() != width => {
                Err(format!("`k` has {} elements but the signal has width {width}", k.len()))
            }
            _ => Ok(()),
        }
    }

    fn kernel(&self) -> Option<Kernel> {
        match self {
            Gain::Elementwise(k) if k.len() == 1 => Some(Kernel::Scale(k[0])),
            _ => None,
        }
    }

    fn output(&mut self, io: &mut Io) {
        match self {
            Gain::Elementwise(k) => {
                for (i, &ki) in k.iter().enumerate() {
                    let v = Kernel::Scale(ki).eval(io.u_at(0, i), 0.0);
                    io.set_at(0, i, v);
                }
            }
            Gain::Matrix { k, cols } => {
                for r in 0..io.output_width(0) {
                    let v: f64 = (0..*cols).map(|c| k[r * *cols + c] * io.u_at(0, c)).sum();
                    io.set_at(0, r, v);
                }
            }
        }
    }
}

fn build_gain(p: &mut Params) -> Result<Built, Diagnostic> {
    let is_matrix = matches!(p.raw("k").map(|v| &v.kind), Some(Kind::Seq(rows)) if rows.iter().any(|r| matches!(r.kind, Kind::Seq(_))));
    let st = p.sample_time()?;
    if is_matrix {
        let rows = p.matrix("k")?;
        let cols = rows[0].len();
        if cols == 0 || rows.iter().any(|r| r.len() != cols) {
            return Err(p.error("k", "matrix rows must all have the same, nonzero length"));
        }
        let iface = Interface::new(st)
            .piecewise_constant()
            .input("u", Width::Fixed(cols), true)
            .output("y", Width::Fixed(rows.len()));
        return Ok(Built::new(Gain::Matrix { k: rows.concat(), cols }, iface));
    }
    let k = p.vector("k")?;
    if k.is_empty() {
        return Err(p.error("k", "needs at least one number"));
    }
    let iface = Interface::new(st).piecewise_constant().input("u", Width::Common, true).output("y", Width::Common);
    Ok(Built::new(Gain::Elementwise(k), iface))
}

/// Σ sᵢ uᵢ elementwise, or the sum of one input's elements.
#[derive(Clone)]
pub struct Sum {
    signs: Vec<f64>,
}

impl Block for Sum {
    rust_type!(Sum);
    fn updates(&self) -> bool {
        false
    }
    fn kernel(&self) -> Option<Kernel> {
        match self.signs[..] {
            [a, b] => Some(Kernel::Affine2(a, b)),
            _ => None,
        }
    }
    fn output(&mut self, io: &mut Io) {
        if self.signs.len() == 1 {
            let s: f64 = io.input(0).iter().sum();
            io.set(0, self.signs[0] * s);
            return;
        }
        if let [a, b] = self.signs[..]
            && io.output_width(0) == 1
        {
            // The common two-input case, the same sum as below.
            io.set(0, Kernel::Affine2(a, b).eval(io.u(0), io.u(1)));
            return;
        }
        if io.output_width(0) == 1 {
            let v: f64 = self.signs.iter().enumerate().map(|(i, s)| s * io.u(i)).sum();
            io.set(0, v);
            return;
        }
        for k in 0..io.output_width(0) {
            let v: f64 = self.signs.iter().enumerate().map(|(i, s)| s * io.u_at(i, k)).sum();
            io.set_at(0, k, v);
        }
    }
}

fn build_sum(p: &mut Params) -> Result<Built, Diagnostic> {
    let text = p.string("signs")?;
    let signs: Vec<f64> = text
        .chars()
        .filter(|c| *c != '|' && !c.is_whitespace())
        .map(|c| match c {
            '+' => Ok(1.0),
            '-' => Ok(-1.0),
            other => Err(p.error("signs", format!("`{other}` is not a sign: use + and -"))),
        })
        .collect::<Result<_, _>>()?;
    if signs.is_empty() {
        return Err(p.error("signs", "needs at least one sign"));
    }
    if signs.len() == 1 {
        let iface = Interface::new(p.sample_time()?)
            .piecewise_constant()
            .input("u1", Width::Common, true)
            .output("y", Width::Fixed(1));
        return Ok(Built::new(Sum { signs }, iface));
    }
    let n = signs.len();
    nary(p, n, Sum { signs })
}

/// u1 ∘ u2 ∘ … with ∘ ∈ {·, /}.
#[derive(Clone)]
pub struct Product {
    divide: Vec<bool>,
}

impl Block for Product {
    rust_type!(Product);
    fn updates(&self) -> bool {
        false
    }
    fn output(&mut self, io: &mut Io) {
        for k in 0..io.output_width(0) {
            let mut v = 1.0;
            for (i, &div) in self.divide.iter().enumerate() {
                let u = io.u_at(i, k);
                if div { v /= u } else { v *= u }
            }
            io.set_at(0, k, v);
        }
    }
}

fn build_product(p: &mut Params) -> Result<Built, Diagnostic> {
    let text = p.string("ops")?;
    let divide: Vec<bool> = text
        .chars()
        .filter(|c| !c.is_whitespace())
        .map(|c| match c {
            '*' => Ok(false),
            '/' => Ok(true),
            other => Err(p.error("ops", format!("`{other}` is not an operation: use * and /"))),
        })
        .collect::<Result<_, _>>()?;
    if divide.len() < 2 {
        return Err(p.error("ops", "needs at least two inputs, e.g. \"**\""));
    }
    let n = divide.len();
    nary(p, n, Product { divide })
}

fn build_divide(p: &mut Params) -> Result<Built, Diagnostic> {
    nary(p, 2, Product { divide: vec![false, true] })
}

/// Elementwise extremum over inputs, or over the elements of one input.
#[derive(Clone)]
pub struct Extremum {
    max: bool,
    inputs: usize,
    /// Multi-input form: the selected input per element (the mode).
    selected: Vec<usize>,
}

impl Block for Extremum {
    rust_type!(Extremum);
    fn updates(&self) -> bool {
        false
    }
    fn set_width(&mut self, width: usize) -> Result<(), String> {
        self.selected = vec![0; width];
        Ok(())
    }

    fn output(&mut self, io: &mut Io) {
        let pick = |a: f64, b: f64| if self.max { a.max(b) } else { a.min(b) };
        if self.inputs == 1 {
            let u = io.input(0);
            let v = u[1..].iter().fold(u[0], |a, &b| pick(a, b));
            io.set(0, v);
            return;
        }
        for k in 0..io.output_width(0) {
            if io.may_switch() {
                // The first input attaining the extremum.
                let better = |a: f64, b: f64| if self.max { b > a } else { b < a };
                self.selected[k] =
                    (1..self.inputs).fold(0, |s, i| if better(io.u_at(s, k), io.u_at(i, k)) { i } else { s });
            }
            let v = io.u_at(self.selected[k], k);
            io.set_at(0, k, v);
        }
    }

    fn num_zero_crossings(&self) -> usize {
        if self.inputs == 1 { 0 } else { self.selected.len() * self.inputs }
    }

    /// uj − u_selected per element and input.
    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        for (k, &s) in self.selected.iter().enumerate() {
            for j in 0..self.inputs {
                g[k * self.inputs + j] = io.u_at(j, k) - io.u_at(s, k);
            }
        }
    }

    fn crossing_direction(&self, k: usize) -> Crossing {
        if self.selected[k / self.inputs] == k % self.inputs {
            Crossing::Ignore
        } else if self.max {
            Crossing::Rising
        } else {
            Crossing::Falling
        }
    }
}

fn build_extremum(p: &mut Params, max: bool) -> Result<Built, Diagnostic> {
    let inputs = p.count("inputs", 10_000)?;
    if inputs == 1 {
        let iface = Interface::new(p.sample_time()?)
            .piecewise_constant()
            .input("u1", Width::Common, true)
            .output("y", Width::Fixed(1));
        return Ok(Built::new(Extremum { max, inputs, selected: Vec::new() }, iface));
    }
    nary(p, inputs, Extremum { max, inputs, selected: vec![0] })
}

fn build_min(p: &mut Params) -> Result<Built, Diagnostic> {
    build_extremum(p, false)
}

fn build_max(p: &mut Params) -> Result<Built, Diagnostic> {
    build_extremum(p, true)
}

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
}

fn build_fcn(p: &mut Params) -> Result<Built, Diagnostic> {
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
