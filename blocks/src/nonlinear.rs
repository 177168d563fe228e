//! Static and slew nonlinearities: saturation, dead zone, rate limiter, and
//! [`Piecewise`], the zero-crossing machinery of elementwise blocks with
//! corners (saturation, dead zone, abs, sign).

use crate::{SAMPLE_TIME_INHERITED, U_ANY, Y_SAME, table::*};
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::registry::{BlockType, Built};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};

/// What every piecewise block's doc says about its modes.
macro_rules! piecewise_doc {
    () => {
        "\nModes (Simulink's): each element's piece is chosen at major steps and frozen in the solver's \
         minor steps, so each side of a corner integrates its own smooth formula; zero crossings of u − \
         breakpoint end the step exactly at the corner. With `zero_crossing: false` the block is a plain \
         function."
    };
}
pub(crate) use piecewise_doc;

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "quantizer",
        category: "nonlinear",
        summary: "Rounds to a multiple of an interval (Simulink's Quantizer).",
        doc: "y = q·round(u/q), elementwise, halves rounded away from zero (round-to-nearest, as \
              Simulink's Quantizer). A staircase: its output changes only where u/q passes a half \
              integer.\n\
              Bounds: |y − u| <= q/2.",
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[param("interval", Number(0.5), "quantization interval q > 0"), SAMPLE_TIME_INHERITED],
        build: build_quantizer,
    },
    BlockType {
        name: "coulomb_viscous_friction",
        category: "nonlinear",
        summary: "Coulomb and viscous friction: y = sign(u)·(gain·|u| + offset) (Simulink's block).",
        doc: concat!(
            "y = sign(u)·(gain·|u| + offset) = gain·u + sign(u)·offset, elementwise: a jump of 2·offset \
             at u = 0 (where y = 0), slope `gain` either side.",
            piecewise_doc!()
        ),
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[
            param("offset", Number(1.0), "Coulomb friction: the jump either side of 0"),
            param("gain", Number(1.0), "viscous friction coefficient: the slope"),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_friction,
    },
    BlockType {
        name: "saturation",
        category: "nonlinear",
        summary: "Limits a signal to [lower, upper].",
        doc: concat!(
            "y = min(max(u, lower), upper), elementwise. NaN in, NaN out (the run then stops).",
            piecewise_doc!(),
            "\nBounds: lower <= y <= upper at major steps."
        ),
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[
            param("lower", Number(-1.0), "lower limit (may be -inf)"),
            param("upper", Number(1.0), "upper limit, >= lower (may be inf)"),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_saturation,
    },
    BlockType {
        name: "dead_zone",
        category: "nonlinear",
        summary: "Zero output inside [start, end], shifted input outside.",
        doc: concat!(
            "y = 0 for start <= u <= end; y = u − end above; y = u − start below (Simulink's Dead Zone).",
            piecewise_doc!()
        ),
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[
            param("start", Number(-0.5), "lower edge of the dead zone"),
            param("end", Number(0.5), "upper edge, >= start"),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_dead_zone,
    },
    BlockType {
        name: "rate_limiter",
        category: "nonlinear",
        summary: "Limits how fast a signal may rise and fall.",
        doc: "With y⁻ and t⁻ the output and time of the last major step (or sample hit): \
              y = y⁻ + clamp((u − y⁻)/(t − t⁻), falling, rising)·(t − t⁻). The output starts at \
              `initial` and slews from there, so |dy/dt| never exceeds the limits. Continuous by \
              default (evaluated at minor steps too); with a sample time it is a discrete limiter. As in \
              Simulink, the slew starts from the previous major step, so a step input at t₀ is already \
              partly passed at t₀.\n\
              Bounds: falling <= dy/dt <= rising between major steps, and |y| <= max(|initial|, sup|u|).",
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[
            param("rising", Number(1.0), "largest rate of increase, > 0").unit("units/s"),
            param("falling", Number(-1.0), "most negative rate, < 0").unit("units/s"),
            param("initial", Number(0.0), "output at t = 0"),
            param("sample_time", Number(0.0), "0 continuous, T > 0 discrete").kind(ParamKind::SampleTime),
        ],
        build: build_rate_limiter,
    },
];

/// An elementwise function made of smooth pieces between sorted
/// breakpoints. Each element's piece (its mode) is chosen at major steps —
/// piece r lies between breakpoint r − 1 and r, a breakpoint itself
/// belonging to the piece below — and frozen in minor steps; the zero
/// crossings are u − breakpoint for every element and breakpoint.
#[derive(Clone)]
pub struct Piecewise {
    breaks: Vec<f64>,
    /// Piece `r` at input `u`, given the breakpoints.
    piece: fn(&[f64], usize, f64) -> f64,
    /// `piece` in C.
    c_piece: CPiece,
    modes: Vec<usize>,
}

/// A [`Piecewise`] block's piece `r` at `u` as a C expression, given a
/// number's literal and the breakpoints' literals.
pub type CPiece = fn(&dyn Fn(f64) -> String, &[String], usize, &str) -> String;

impl Piecewise {
    pub fn new(breaks: Vec<f64>, piece: fn(&[f64], usize, f64) -> f64, c_piece: CPiece) -> Self {
        Piecewise { breaks, piece, c_piece, modes: vec![0] }
    }

    /// Builds the block with one input `u` and output `y` of any width.
    pub fn build(self, p: &mut Params) -> Result<Built, Diagnostic> {
        let iface = Interface::new(p.sample_time()?)
            .piecewise_constant()
            .input("u", Width::Common, true)
            .output("y", Width::Common);
        Ok(Built::new(self, iface))
    }
}

impl Block for Piecewise {
    rust_type!(Piecewise);
    fn updates(&self) -> bool {
        false
    }
    fn set_width(&mut self, width: usize) -> Result<(), String> {
        self.modes = vec![0; width];
        Ok(())
    }

    fn output(&mut self, io: &mut Io) {
        for k in 0..io.output_width(0) {
            let u = io.u_at(0, k);
            if io.may_switch() {
                self.modes[k] = self.breaks.iter().filter(|&&b| u > b).count();
            }
            let v = (self.piece)(&self.breaks, self.modes[k], u);
            io.set_at(0, k, v);
        }
    }

    /// The mode chosen afresh at each sample (a major step): how many
    /// breakpoints u is above, then that piece.
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let breaks: Vec<String> = self.breaks.iter().map(|&b| c.num(b)).collect();
        let real = c.real();
        let num = |v: f64| c.num(v);
        let count: Vec<String> = breaks.iter().map(|b| format!("(u > {b})")).collect();
        let pieces: Vec<String> = (0..=breaks.len()).map(|r| (self.c_piece)(&num, &breaks, r, "u")).collect();
        let choose = (1..pieces.len())
            .rev()
            .fold(pieces[pieces.len() - 1].clone(), |rest, r| format!("r == {} ? {} : {rest}", r - 1, pieces[r - 1]));
        let mut statements = Vec::new();
        for k in 0..c.output_width(0) {
            statements.push(format!(
                "{{\n    {real} u = {};\n    int r = {};\n    {} = {choose};\n}}",
                c.u_at(0, k),
                count.join(" + "),
                c.y_at(0, k)
            ));
        }
        c.equation("r = the number of breakpoints below u; y = piece r of u");
        statements.into_iter().for_each(|s| c.output(s));
        Ok(())
    }

    fn num_zero_crossings(&self) -> usize {
        self.modes.len() * self.breaks.len()
    }

    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        let m = self.breaks.len();
        for k in 0..self.modes.len() {
            for (j, b) in self.breaks.iter().enumerate() {
                g[k * m + j] = io.u_at(0, k) - b;
            }
        }
    }
}

/// Reads `lower`/`upper`-style limit pairs, checking their order.
/// y = q·round(u/q).
#[derive(Clone)]
pub struct Quantizer {
    interval: f64,
}

impl Block for Quantizer {
    rust_type!(Quantizer);
    fn updates(&self) -> bool {
        false
    }
    fn output(&mut self, io: &mut Io) {
        for k in 0..io.output_width(0) {
            let v = self.interval * (io.u_at(0, k) / self.interval).round();
            io.set_at(0, k, v);
        }
    }
    /// C99's `round` rounds halves away from zero, as Rust's `f64::round`.
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation("y = q round(u / q)");
        let (q, round) = (c.num(self.interval), c.math("round"));
        for k in 0..c.output_width(0) {
            c.output(format!("{} = {q} * {round}({} / {q});", c.y_at(0, k), c.u_at(0, k)));
        }
        Ok(())
    }
}

fn build_quantizer(p: &mut Params) -> Result<Built, Diagnostic> {
    let interval = p.number_where("interval", None, |q| q > 0.0 && q.is_finite(), "a positive interval")?;
    let iface = Interface::new(p.sample_time()?).piecewise_constant().input("u", Width::Common, true);
    Ok(Built::new(Quantizer { interval }, iface.output("y", Width::Common)))
}

/// y = gain·u + s·offset with s = sign(u) the mode.
#[derive(Clone)]
pub struct Friction {
    offset: f64,
    gain: f64,
    /// Per element, sign(u) at the last major step.
    sign: Vec<f64>,
}

impl Block for Friction {
    rust_type!(Friction);
    fn updates(&self) -> bool {
        false
    }
    fn set_width(&mut self, width: usize) -> Result<(), String> {
        self.sign = vec![0.0; width];
        Ok(())
    }
    fn output(&mut self, io: &mut Io) {
        for k in 0..io.output_width(0) {
            let u = io.u_at(0, k);
            if io.may_switch() {
                self.sign[k] = crate::math::sign(u);
            }
            io.set_at(0, k, self.gain * u + self.sign[k] * self.offset);
        }
    }
    fn num_zero_crossings(&self) -> usize {
        self.sign.len()
    }
    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        for (k, g) in g.iter_mut().enumerate().take(self.sign.len()) {
            *g = io.u_at(0, k);
        }
    }
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation("y = gain u + sign(u) offset");
        let (gain, offset, sign) = (c.num(self.gain), c.num(self.offset), c.sign());
        for k in 0..c.output_width(0) {
            let u = c.u_at(0, k).to_string();
            c.output(format!("{} = {gain} * {u} + {sign}({u}) * {offset};", c.y_at(0, k)));
        }
        Ok(())
    }
}

fn build_friction(p: &mut Params) -> Result<Built, Diagnostic> {
    let finite = |v: f64| v.is_finite();
    let offset = p.number_where("offset", None, finite, "a finite number")?;
    let gain = p.number_where("gain", None, finite, "a finite number")?;
    let iface = Interface::new(p.sample_time()?).piecewise_constant().input("u", Width::Common, true);
    Ok(Built::new(Friction { offset, gain, sign: vec![0.0] }, iface.output("y", Width::Common)))
}

pub(crate) fn limits(p: &mut Params, lo: &str, hi: &str) -> Result<(f64, f64), Diagnostic> {
    let (lower, upper) = (p.number(lo)?, p.number(hi)?);
    if lower > upper || lower.is_nan() || upper.is_nan() {
        return Err(p
            .error(hi, format!("`{hi}` ({upper}) must be >= `{lo}` ({lower})"))
            .with_hint(format!("swap them: `{lo}: {upper}, {hi}: {lower}`")));
    }
    Ok((lower, upper))
}

/// Saturation: below `lower`, between, above `upper`.
pub fn saturation(lower: f64, upper: f64) -> Piecewise {
    Piecewise::new(
        vec![lower, upper],
        |b, r, u| match r {
            0 => b[0],
            1 => u,
            _ => b[1],
        },
        |_, b, r, u| match r {
            0 => b[0].clone(),
            1 => u.to_string(),
            _ => b[1].clone(),
        },
    )
}

fn build_saturation(p: &mut Params) -> Result<Built, Diagnostic> {
    let (lower, upper) = limits(p, "lower", "upper")?;
    saturation(lower, upper).build(p)
}

fn build_dead_zone(p: &mut Params) -> Result<Built, Diagnostic> {
    let (start, end) = limits(p, "start", "end")?;
    Piecewise::new(
        vec![start, end],
        |b, r, u| match r {
            0 => u - b[0],
            1 => 0.0,
            _ => u - b[1],
        },
        |num, b, r, u| match r {
            0 => format!("({u} - {})", b[0]),
            1 => num(0.0),
            _ => format!("({u} - {})", b[1]),
        },
    )
    .build(p)
}

/// Slew-rate limiter; see the type's doc for the equation.
#[derive(Clone)]
pub struct RateLimiter {
    pub rising: f64,
    pub falling: f64,
    pub initial: f64,
    /// Output and time at the last major step.
    last: Vec<f64>,
    last_t: f64,
    /// Output computed at the current major step, committed by `update`.
    current: Vec<f64>,
}

impl RateLimiter {
    pub fn new(rising: f64, falling: f64, initial: f64) -> Self {
        RateLimiter { rising, falling, initial, last: vec![initial], last_t: 0.0, current: vec![initial] }
    }
}

impl Block for RateLimiter {
    rust_type!(RateLimiter);
    fn set_width(&mut self, width: usize) -> Result<(), String> {
        self.last = vec![self.initial; width];
        self.current = vec![self.initial; width];
        Ok(())
    }

    fn initialize(&mut self, _x0: &mut [f64]) {
        self.last.iter_mut().for_each(|v| *v = self.initial);
        self.current.iter_mut().for_each(|v| *v = self.initial);
        self.last_t = 0.0;
    }

    fn output(&mut self, io: &mut Io) {
        let dt = io.t - self.last_t;
        for k in 0..self.last.len() {
            let y = if dt > 0.0 {
                let rate = ((io.u_at(0, k) - self.last[k]) / dt).clamp(self.falling, self.rising);
                self.last[k] + rate * dt
            } else {
                self.last[k]
            };
            self.current[k] = y;
            io.set_at(0, k, y);
        }
    }

    fn update(&mut self, io: &mut Io) {
        self.last.copy_from_slice(&self.current);
        self.last_t = io.t;
    }
    /// The discrete limiter (a continuous one is refused as continuous:
    /// it updates at every major step).
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation("dt = t - t_last;  y = y_last + clamp((u - y_last)/dt, falling, rising) dt  (y_last when dt = 0)");
        let w = self.last.len();
        let last = c.state("last", &vec![self.initial; w]);
        let current = c.state("current", &vec![self.initial; w]);
        let last_t = c.state("last_t", &[0.0]);
        let (t, clamp, real) = (c.time(), c.clamp(), c.real());
        let at = |name: &str, k: usize| if w == 1 { name.to_string() } else { format!("{name}[{k}]") };
        c.output(format!("{real} dt = {t} - {last_t};"));
        for k in 0..w {
            let (l, cur) = (at(&last, k), at(&current, k));
            c.output(format!(
                "{cur} = dt > {zero} ? {l} + {clamp}(({u} - {l}) / dt, {falling}, {rising}) * dt : {l};\n{y} = {cur};",
                zero = c.num(0.0),
                u = c.u_at(0, k),
                falling = c.num(self.falling),
                rising = c.num(self.rising),
                y = c.y_at(0, k)
            ));
            c.update(format!("{l} = {cur};"));
        }
        c.update(format!("{last_t} = {t};"));
        Ok(())
    }
}

fn build_rate_limiter(p: &mut Params) -> Result<Built, Diagnostic> {
    let rising = p.number_where("rising", None, |v| v > 0.0, "positive")?;
    let falling = p.number_where("falling", None, |v| v < 0.0, "negative")?;
    let initial = p.number("initial")?;
    let st = p.sample_time()?;
    let iface = Interface::new(st).input("u", Width::Common, true).output("y", Width::Common);
    Ok(Built::new(RateLimiter::new(rising, falling, initial), iface))
}
