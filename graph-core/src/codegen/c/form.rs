//! What a block writes for its C form ([`crate::Block::c_form`]): its
//! memory, reset, output and update as C99 statements, over names the
//! generator gives it for its ports and its memory.
//!
//! A C form computes what the block's `output` and `update` compute with
//! the same operations in the same order, so that the C, compiled without
//! contraction of multiply-adds (`-ffp-contract=off`), gives the same bits
//! as the simulation in double precision (checked by `--verify`).

/// The C floating-point type the controller computes in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Real {
    Double,
    /// `float`, for an FPU without double support (`--float single`).
    Single,
}

impl Real {
    pub fn c_type(self) -> &'static str {
        match self {
            Real::Double => "double",
            Real::Single => "float",
        }
    }

    /// `v` as a C literal of this type that reads back to the same value
    /// (Rust's shortest round-trip digits; C compilers round decimal
    /// literals correctly).
    pub fn literal(self, v: f64) -> String {
        if v.is_nan() {
            return "NAN".into();
        }
        if v.is_infinite() {
            return if v > 0.0 { "INFINITY".into() } else { "(-INFINITY)".into() };
        }
        let digits = match self {
            Real::Double => format!("{v:?}"),
            Real::Single => format!("{:?}", v as f32),
        };
        // `{:?}` always writes a point or an exponent: a floating literal.
        let text = if self == Real::Single { format!("{digits}f") } else { digits };
        if v.is_sign_negative() { format!("({text})") } else { text }
    }

    /// The `<math.h>` function `name` (`sqrt`) for this type (`sqrtf`).
    pub fn math(self, name: &str) -> String {
        match self {
            Real::Double => name.to_string(),
            Real::Single => format!("{name}f"),
        }
    }
}

/// Why a block has no C form here.
#[derive(Clone, Debug, PartialEq)]
pub enum NoCForm {
    /// Its type has none.
    Type,
    /// Its type has one, but not in this configuration (the reason).
    Because(String),
}

/// The names and the text of one block's C form. The generator fills in
/// the ports; the block declares its memory and writes its statements.
pub struct CBlock<'a> {
    pub(super) real: Real,
    pub(super) inputs: Vec<Vec<String>>,
    pub(super) outputs: Vec<Vec<String>>,
    /// The block's member in the state struct (`s->td`).
    pub(super) member: String,
    /// The block's C name (`td`), prefixing its file-level constants.
    pub(super) ident: String,
    pub(super) equations: Vec<String>,
    pub(super) memory: Vec<String>,
    pub(super) init: Vec<String>,
    pub(super) output: Vec<String>,
    pub(super) update: Vec<String>,
    pub(super) helpers: &'a mut Helpers,
}

impl CBlock<'_> {
    /// The floating-point type (`double` or `float`).
    pub fn real(&self) -> &'static str {
        self.real.c_type()
    }

    /// The controller's type, to write literals while `self` is borrowed.
    pub fn kind(&self) -> Real {
        self.real
    }

    /// `v` as a literal of the controller's type.
    pub fn num(&self, v: f64) -> String {
        self.real.literal(v)
    }

    /// The `<math.h>` function `name` for the controller's type.
    pub fn math(&self, name: &str) -> String {
        self.real.math(name)
    }

    pub fn num_inputs(&self) -> usize {
        self.inputs.len()
    }

    pub fn input_width(&self, port: usize) -> usize {
        self.inputs[port].len()
    }

    pub fn output_width(&self, port: usize) -> usize {
        self.outputs[port].len()
    }

    /// Input `port`'s first (a scalar's only) element, as an expression.
    pub fn u(&self, port: usize) -> &str {
        &self.inputs[port][0]
    }

    /// Element `k` of input `port`, a scalar broadcast (as [`crate::Io::u_at`]).
    pub fn u_at(&self, port: usize, k: usize) -> &str {
        let p = &self.inputs[port];
        &p[if p.len() == 1 { 0 } else { k }]
    }

    /// Output `port`'s first element, to assign.
    pub fn y(&self, port: usize) -> &str {
        &self.outputs[port][0]
    }

    /// Element `k` of output `port`, to assign.
    pub fn y_at(&self, port: usize, k: usize) -> &str {
        &self.outputs[port][k]
    }

    /// `terms` added left to right as Rust's `f64` `Sum` adds them (from
    /// −0.0, which leaves the first term as it is; −0.0 for none).
    pub fn sum_of(&self, terms: &[String]) -> String {
        match terms {
            [] => self.num(-0.0),
            _ => format!("({})", terms.join(" + ")),
        }
    }

    /// Declares memory `field` of the controller's type with one element
    /// per value of `initial` (an array when there are several), reset to
    /// those values by `init`; returns its name (`s->td.r1`), to index
    /// when it is an array.
    pub fn state(&mut self, field: &str, initial: &[f64]) -> String {
        let name = format!("{}.{field}", self.member);
        let real = self.real();
        match initial {
            [v] => {
                self.memory.push(format!("{real} {field};"));
                self.init.push(format!("{name} = {};", self.num(*v)));
            }
            _ => {
                self.memory.push(format!("{real} {field}[{}];", initial.len().max(1)));
                for (k, v) in initial.iter().enumerate() {
                    self.init.push(format!("{name}[{k}] = {};", self.num(*v)));
                }
            }
        }
        name
    }

    /// Declares an unsigned counter `field` (a ring buffer's position, a
    /// first-sample flag) reset to `initial`; returns its name.
    pub fn counter(&mut self, field: &str, initial: u32) -> String {
        let name = format!("{}.{field}", self.member);
        self.memory.push(format!("uint32_t {field};"));
        self.init.push(format!("{name} = {initial}u;"));
        name
    }

    /// A line of the comment above the block's statements: its equation.
    pub fn equation(&mut self, text: impl Into<String>) {
        self.equations.push(text.into().replace("*/", "* /"));
    }

    /// A statement of the block's output (computed at its sample hits,
    /// after the blocks it reads in execution order).
    pub fn output(&mut self, statement: impl Into<String>) {
        self.output.push(statement.into());
    }

    /// A statement of the block's update (after every output of the step).
    pub fn update(&mut self, statement: impl Into<String>) {
        self.update.push(statement.into());
    }

    /// A file-level C function `name` the statements call, written once
    /// per file however many blocks use it: `text(real)` gives its
    /// definition for the controller's type. Returns `name`.
    pub fn helper(&mut self, name: &'static str, text: impl FnOnce(Real) -> String) -> &'static str {
        if !self.helpers.0.iter().any(|(n, _)| *n == name) {
            let code = text(self.real);
            self.helpers.0.push((name, code));
        }
        name
    }

    /// The time of the present sample, `t` (as the simulator keeps it:
    /// counted in base steps, k/n for a period of 1/n s, else k·period).
    pub fn time(&mut self) -> &'static str {
        self.helpers.2 = true;
        "t"
    }

    /// A file-level constant table of the block (`static const`, in flash
    /// on a microcontroller: no mutable globals): `element` the C type of
    /// its elements, `values` its initialisers. Returns its name
    /// (`tune_peaks_0`).
    pub fn table(&mut self, field: &str, element: &str, values: &[String]) -> String {
        let name = format!("{}_{field}", self.ident);
        let mut text = format!("static const {element} {name}[{}] = {{", values.len().max(1));
        for (k, v) in values.iter().enumerate() {
            text.push_str(if k % 6 == 0 { "\n    " } else { " " });
            text.push_str(v);
            text.push(',');
        }
        if values.is_empty() {
            text.push_str(" 0");
        }
        text.push_str("\n};\n");
        self.helpers.1.push(text);
        name
    }

    /// `ctl_sign(v)`: 1, −1 or 0 (MATLAB's sign, the library's `sign`).
    pub fn sign(&mut self) -> &'static str {
        self.helper("ctl_sign", |r| {
            let t = r.c_type();
            let (one, zero) = (r.literal(1.0), r.literal(0.0));
            format!(
                "/* sign(v) = 1, -1 or 0 (MATLAB's) */\n\
                 static {t} ctl_sign({t} v)\n{{\n    return v > {zero} ? {one} : (v < {zero} ? -{one} : {zero});\n}}\n"
            )
        })
    }

    /// `ctl_clamp(v, lo, hi)`: Rust's `f64::clamp` (a NaN stays NaN).
    pub fn clamp(&mut self) -> &'static str {
        self.helper("ctl_clamp", |r| {
            let t = r.c_type();
            format!(
                "/* v limited to [lo, hi]; NaN passes through */\n\
                 static {t} ctl_clamp({t} v, {t} lo, {t} hi)\n{{\n    if (v < lo) v = lo;\n    if (v > hi) v = hi;\n    return v;\n}}\n"
            )
        })
    }
}

/// The file-level functions the blocks' statements call, in first use,
/// the blocks' constant tables, and whether a block reads the time.
#[derive(Default)]
pub struct Helpers(pub(super) Vec<(&'static str, String)>, pub(super) Vec<String>, pub(super) bool);

#[cfg(test)]
mod tests {
    use super::Real;

    #[test]
    fn literals_read_back_as_the_value() {
        assert_eq!(Real::Double.literal(5.0), "5.0");
        assert_eq!(Real::Double.literal(1e-4), "0.0001");
        assert_eq!(Real::Double.literal(1.64e4), "16400.0");
        assert_eq!(Real::Double.literal(-0.1), "(-0.1)");
        assert_eq!(Real::Double.literal(-0.0), "(-0.0)");
        assert_eq!(Real::Double.literal(1e300), "1e300");
        assert_eq!(Real::Double.literal(f64::NEG_INFINITY), "(-INFINITY)");
        assert_eq!(Real::Single.literal(0.1), "0.1f");
        assert_eq!(Real::Single.literal(1e-40), "1e-40f");
        for v in [0.1, 1.0 / 3.0, 2.0f64.sqrt(), 6.02214076e23, 5e-324] {
            let text = Real::Double.literal(v);
            assert_eq!(text.trim_matches(['(', ')']).parse::<f64>().unwrap(), v);
        }
    }
}
