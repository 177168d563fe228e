//! Static and slew nonlinearities: saturation, dead zone, rate limiter, and
//! [`Piecewise`], the zero-crossing machinery of elementwise blocks with
//! corners (saturation, dead zone, abs, sign).

use crate::{SAMPLE_TIME_INHERITED, U_ANY, Y_SAME, table::*};
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
    modes: Vec<usize>,
}

impl Piecewise {
    pub fn new(breaks: Vec<f64>, piece: fn(&[f64], usize, f64) -> f64) -> Self {
        Piecewise { breaks, piece, modes: vec![0] }
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
    Piecewise::new(vec![lower, upper], |b, r, u| match r {
        0 => b[0],
        1 => u,
        _ => b[1],
    })
}

fn build_saturation(p: &mut Params) -> Result<Built, Diagnostic> {
    let (lower, upper) = limits(p, "lower", "upper")?;
    saturation(lower, upper).build(p)
}

fn build_dead_zone(p: &mut Params) -> Result<Built, Diagnostic> {
    let (start, end) = limits(p, "start", "end")?;
    Piecewise::new(vec![start, end], |b, r, u| match r {
        0 => u - b[0],
        1 => 0.0,
        _ => u - b[1],
    })
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
}

fn build_rate_limiter(p: &mut Params) -> Result<Built, Diagnostic> {
    let rising = p.number_where("rising", None, |v| v > 0.0, "positive")?;
    let falling = p.number_where("falling", None, |v| v < 0.0, "negative")?;
    let initial = p.number("initial")?;
    let st = p.sample_time()?;
    let iface = Interface::new(st).input("u", Width::Common, true).output("y", Width::Common);
    Ok(Built::new(RateLimiter::new(rising, falling, initial), iface))
}
