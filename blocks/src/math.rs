//! Memoryless math: gain, sum, product, divide, abs, sign, min, max, and
//! `fcn` (an expression of the inputs and time). All elementwise on any
//! width, scalar inputs broadcast.

pub mod fcn;

use crate::nonlinear::Piecewise;
use crate::{SAMPLE_TIME_INHERITED, U_ANY, Y_SAME, Y_SCALAR, table::*};
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::yaml::Kind;
use ctlgraph_core::{Block, Crossing, Diagnostic, Interface, Io, Kernel, Params, Width};
use fcn::build_fcn;

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
            param("k", Number(1.0), "number, list (elementwise) or list of rows (matrix)").kind(ParamKind::Matrix),
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
    Piecewise::new(
        vec![0.0],
        |_, r, u| if r == 0 { -u } else { u },
        |_, _, r, u| {
            if r == 0 { format!("(-{u})") } else { u.to_string() }
        },
    )
    .build(p)
}

/// sign(0) = 0, as MATLAB: the expression language's, so a block and an
/// `fcn` formula agree.
pub use ctlgraph_core::expr::sign;

fn build_sign(p: &mut Params) -> Result<Built, Diagnostic> {
    Piecewise::new(
        vec![0.0],
        |_, r, u| {
            if u == 0.0 {
                0.0
            } else if r == 0 {
                -1.0
            } else {
                1.0
            }
        },
        |num, _, r, u| format!("({u} == {} ? {} : {})", num(0.0), num(0.0), num(if r == 0 { -1.0 } else { 1.0 })),
    )
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
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        match self {
            Gain::Elementwise(k) => {
                c.equation("y_i = k_i u_i");
                for (i, &ki) in k.iter().enumerate() {
                    c.output(format!("{} = {} * {};", c.y_at(0, i), c.num(ki), c.u_at(0, i)));
                }
            }
            Gain::Matrix { k, cols } => {
                c.equation("y = K u: y_r = sum over c of K_rc u_c, left to right");
                for r in 0..c.output_width(0) {
                    let terms: Vec<String> =
                        (0..*cols).map(|j| format!("{} * {}", c.num(k[r * *cols + j]), c.u_at(0, j))).collect();
                    c.output(format!("{} = {};", c.y_at(0, r), terms.join(" + ")));
                }
            }
        }
        Ok(())
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
    /// ±1·u is exact and a + (−b) is a − b, so the signed terms added
    /// left to right are the block's sum to the bit.
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let signed = |terms: Vec<(f64, String)>| {
            let mut text = String::new();
            for (i, (s, u)) in terms.into_iter().enumerate() {
                text.push_str(match (i, s > 0.0) {
                    (0, true) => "",
                    (0, false) => "-",
                    (_, true) => " + ",
                    (_, false) => " - ",
                });
                text.push_str(&u);
            }
            text
        };
        if let [s] = self.signs[..] {
            c.equation("y = sign * (u_1 + u_2 + ...), the elements of the one input");
            let all = (0..c.input_width(0)).map(|j| (1.0, c.u_at(0, j).to_string())).collect();
            c.output(format!("{} = {} * ({});", c.y(0), c.num(s), signed(all)));
            return Ok(());
        }
        c.equation("y = s_1 u_1 + s_2 u_2 + ..., element by element, left to right");
        for k in 0..c.output_width(0) {
            let terms = self.signs.iter().enumerate().map(|(i, &s)| (s, c.u_at(i, k).to_string())).collect();
            c.output(format!("{} = {};", c.y_at(0, k), signed(terms)));
        }
        Ok(())
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
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation("y = 1 op u1 op u2 ..., op * or /, left to right, element by element");
        for k in 0..c.output_width(0) {
            let mut e = c.num(1.0);
            for (i, &div) in self.divide.iter().enumerate() {
                e = format!("{e} {} {}", if div { "/" } else { "*" }, c.u_at(i, k));
            }
            c.output(format!("{} = {e};", c.y_at(0, k)));
        }
        Ok(())
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

    /// The mode chosen afresh at each sample (a major step): the first
    /// input attaining the extremum.
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let (f, op) = if self.max { (c.math("fmax"), ">") } else { (c.math("fmin"), "<") };
        if self.inputs == 1 {
            c.equation("y = the extremum of u's elements");
            let all: Vec<String> = (0..c.input_width(0)).map(|j| c.u_at(0, j).to_string()).collect();
            let v = all[1..].iter().fold(all[0].clone(), |a, b| format!("{f}({a}, {b})"));
            c.output(format!("{} = {v};", c.y(0)));
            return Ok(());
        }
        c.equation("y = the first input attaining the extremum, element by element");
        for k in 0..c.output_width(0) {
            let mut text = format!("{{\n    {} v = {};\n", c.real(), c.u_at(0, k));
            for i in 1..self.inputs {
                text.push_str(&format!("    if ({u} {op} v) v = {u};\n", u = c.u_at(i, k)));
            }
            text.push_str(&format!("    {} = v;\n}}", c.y_at(0, k)));
            c.output(text);
        }
        Ok(())
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
