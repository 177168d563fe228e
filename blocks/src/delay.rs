//! Time delays: `transport_delay` (fixed dead time), `variable_transport_delay`
//! (the delay is an input) and the discrete `delay` (z^-N). The continuous
//! ones keep the input's history at major steps in a [`History`] ring
//! buffer and interpolate it, as Simulink's Transport Delay does.

use crate::continuous::initial_vector;
use crate::{SAMPLE_TIME_REQUIRED, U_ANY, Y_SAME, param};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, SampleTime, Width};

const HISTORY_PARAMS: [ctlgraph_core::ParamDoc; 4] = [
    param("initial", Some("0"), "output until the delay has elapsed (t < delay)"),
    param("order", Some("1"), "interpolation of the history: 1 linear (Simulink's), 3 cubic Hermite"),
    param("buffer", Some("1024"), "initial history capacity in samples; it doubles when full"),
    param("max_buffer", Some("1e7"), "the most samples the history may hold; beyond, the run stops"),
];

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "transport_delay",
        category: "dynamics",
        summary: "y(t) = u(t − delay): a dead time (Simulink's Transport Delay).",
        doc: "y(t) = initial for t < delay, u(t − delay) after; elementwise. The input is stored at every \
              major step (events included) in a ring buffer and the output interpolated in it — linearly \
              (order 1, Simulink's default) or by cubic Hermite with three-point slopes (order 3). The \
              jump from `initial` to u(0) at t = delay is a major step. No direct feedthrough when delay > \
              0, so it breaks algebraic loops. When the delay is shorter than the step, t − delay lies \
              past the last stored sample: the output is extrapolated linearly from the last two \
              (Simulink does the same); keep max_step below the delay for accuracy. The buffer grows by \
              doubling up to `max_buffer` samples, then the run stops with an error; once grown it never \
              reallocates.\n\
              Bounds: |y| <= max(|initial|, sup|u|) with order 1 (cubic interpolation may overshoot \
              between samples).",
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[
            param("delay", None, "dead time [s], >= 0"),
            HISTORY_PARAMS[0],
            HISTORY_PARAMS[1],
            HISTORY_PARAMS[2],
            HISTORY_PARAMS[3],
        ],
        build: build_transport_delay,
    },
    BlockType {
        name: "variable_transport_delay",
        category: "dynamics",
        summary: "y(t) = u(t − τ(t)) with the delay τ an input (Simulink's Variable Transport Delay).",
        doc: "Like transport_delay with τ(t) read from the `delay` input, clamped to [0, max_delay]; the \
              history covers max_delay. y = initial while t − τ < 0. The `delay` input has direct \
              feedthrough, `u` none.\n\
              Bounds: |y| <= max(|initial|, sup|u|) with order 1.",
        inputs: &[PortDoc { name: "u", doc: "any width" }, PortDoc { name: "delay", doc: "τ(t) [s], scalar" }],
        outputs: Y_SAME,
        params: &[
            param("max_delay", None, "largest delay [s], > 0"),
            HISTORY_PARAMS[0],
            HISTORY_PARAMS[1],
            HISTORY_PARAMS[2],
            HISTORY_PARAMS[3],
        ],
        build: build_variable_delay,
    },
    BlockType {
        name: "delay",
        category: "discrete",
        summary: "y(k) = u(k − N): N samples of delay (z^-N).",
        doc: "y(k) = u(k − N) for k >= N, initial before; elementwise, at its sample time. `unit_delay` is \
              the case N = 1. No direct feedthrough.\n\
              Bounds: |y| <= max(|initial|, sup|u|), for any period.",
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[
            param("samples", Some("1"), "N, a whole number >= 1"),
            param("initial", Some("0"), "output of the first N samples: a number or one per element"),
            SAMPLE_TIME_REQUIRED,
        ],
        build: build_delay,
    },
];

/// The input's past at major steps: times and values in a ring buffer that
/// doubles when full, up to a limit.
#[derive(Clone)]
pub struct History {
    width: usize,
    times: Vec<f64>,
    values: Vec<f64>,
    /// Index of the oldest sample and the number held.
    head: usize,
    len: usize,
    limit: usize,
    /// Samples before this index (logical) are searched past; speeds up
    /// the monotone queries of a run.
    cursor: usize,
    cubic: bool,
    /// The buffer hit its limit: why the output became NaN.
    pub overflow: Option<String>,
}

impl History {
    pub fn new(width: usize, capacity: usize, limit: usize, cubic: bool) -> Self {
        let capacity = capacity.clamp(4, limit.max(4));
        History {
            width,
            times: vec![0.0; capacity],
            values: vec![0.0; capacity * width],
            head: 0,
            len: 0,
            limit,
            cursor: 0,
            cubic,
            overflow: None,
        }
    }

    pub fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
        self.cursor = 0;
        self.overflow = None;
    }

    fn slot(&self, i: usize) -> usize {
        (self.head + i) % self.times.len()
    }

    fn time(&self, i: usize) -> f64 {
        self.times[self.slot(i)]
    }

    fn value(&self, i: usize, k: usize) -> f64 {
        self.values[self.slot(i) * self.width + k]
    }

    /// Appends the sample (t, u), first dropping samples older than
    /// `keep_from` except the two last before it (to interpolate at
    /// `keep_from`, with a slope there).
    pub fn push(&mut self, t: f64, u: impl Fn(usize) -> f64, keep_from: f64) {
        while self.len >= 3 && self.time(2) <= keep_from {
            self.head = (self.head + 1) % self.times.len();
            self.len -= 1;
            self.cursor = self.cursor.saturating_sub(1);
        }
        if self.len > 0 && t <= self.time(self.len - 1) {
            // Same major step again (a restart at an event): replace.
            self.len -= 1;
        }
        if self.len == self.times.len() && !self.grow() {
            return;
        }
        let s = self.slot(self.len);
        self.times[s] = t;
        for k in 0..self.width {
            self.values[s * self.width + k] = u(k);
        }
        self.len += 1;
    }

    /// Doubles the buffer (unrolled so the oldest sample is first again).
    fn grow(&mut self) -> bool {
        let capacity = self.times.len();
        if capacity >= self.limit {
            self.overflow = Some(format!(
                "its history is full: {capacity} samples cover {:.6} s, less than the delay needs; \
                 raise `max_buffer` or the solver's step",
                self.time(self.len - 1) - self.time(0)
            ));
            return false;
        }
        let new_capacity = (2 * capacity).min(self.limit);
        let mut times = vec![0.0; new_capacity];
        let mut values = vec![0.0; new_capacity * self.width];
        for i in 0..self.len {
            times[i] = self.time(i);
            for k in 0..self.width {
                values[i * self.width + k] = self.value(i, k);
            }
        }
        (self.times, self.values, self.head) = (times, values, 0);
        true
    }

    /// The interpolated input at `t` into `out` (NaN after an overflow).
    pub fn at(&mut self, t: f64, out: &mut [f64]) {
        if self.overflow.is_some() || self.len == 0 {
            let v = if self.overflow.is_some() { f64::NAN } else { 0.0 };
            out.iter_mut().for_each(|o| *o = v);
            return;
        }
        if self.len == 1 || t <= self.time(0) {
            for (k, o) in out.iter_mut().enumerate() {
                *o = self.value(if t <= self.time(0) { 0 } else { self.len - 1 }, k);
            }
            return;
        }
        // The interval [time(i), time(i + 1)] holding t (or the last one,
        // extrapolated, when t is past the newest sample).
        let mut i = self.cursor.min(self.len - 2);
        while i > 0 && self.time(i) > t {
            i -= 1;
        }
        while i + 2 < self.len && self.time(i + 1) < t {
            i += 1;
        }
        self.cursor = i;
        let (t0, t1) = (self.time(i), self.time(i + 1));
        let h = t1 - t0;
        let th = (t - t0) / h;
        let cubic = self.cubic && t <= t1;
        for (k, o) in out.iter_mut().enumerate() {
            let (y0, y1) = (self.value(i, k), self.value(i + 1, k));
            *o = if cubic {
                let (m0, m1) = (self.slope(i, k), self.slope(i + 1, k));
                let (t2, t3) = (th * th, th * th * th);
                (2.0 * t3 - 3.0 * t2 + 1.0) * y0
                    + (t3 - 2.0 * t2 + th) * h * m0
                    + (3.0 * t2 - 2.0 * t3) * y1
                    + (t3 - t2) * h * m1
            } else {
                y0 + th * (y1 - y0)
            };
        }
    }

    /// The slope at sample `i`: the derivative of the parabola through it
    /// and its neighbours (one-sided at the ends).
    fn slope(&self, i: usize, k: usize) -> f64 {
        let diff = |a: usize, b: usize| (self.value(b, k) - self.value(a, k)) / (self.time(b) - self.time(a));
        if i == 0 {
            diff(0, 1)
        } else if i + 1 == self.len {
            diff(i - 1, i)
        } else {
            let (hl, hr) = (self.time(i) - self.time(i - 1), self.time(i + 1) - self.time(i));
            (diff(i, i + 1) * hl + diff(i - 1, i) * hr) / (hl + hr)
        }
    }
}

/// Fixed or variable transport delay.
#[derive(Clone)]
pub struct TransportDelay {
    /// The fixed delay, or (variable) the largest.
    delay: f64,
    variable: bool,
    initial: f64,
    history: History,
}

impl TransportDelay {
    /// The delay in force: the parameter, or the clamped input.
    fn delay_now(&self, io: &Io) -> f64 {
        if self.variable { io.u(1).clamp(0.0, self.delay) } else { self.delay }
    }
}

impl Block for TransportDelay {
    rust_type!(TransportDelay);
    fn not_linearizable(&self) -> Option<&'static str> {
        Some("a transport delay e^(-sτ) has no finite-dimensional linear model (read the loop's delay margin instead)")
    }

    fn set_width(&mut self, width: usize) -> Result<(), String> {
        self.history = History::new(width, self.history.times.len(), self.history.limit, self.history.cubic);
        Ok(())
    }

    fn initialize(&mut self, _x0: &mut [f64]) {
        self.history.clear();
    }

    fn output(&mut self, io: &mut Io) {
        if !self.variable && self.delay == 0.0 {
            // No delay: direct feedthrough (declared so at build).
            for k in 0..io.output_width(0) {
                let v = io.u_at(0, k);
                io.set_at(0, k, v);
            }
            return;
        }
        let t = io.t - self.delay_now(io);
        // A fixed delay jumps at t = delay exactly (a major step there).
        let before = if self.variable { t < 0.0 } else { !io.reached(self.delay) };
        if before {
            io.output(0).iter_mut().for_each(|o| *o = self.initial);
        } else {
            self.history.at(t, io.output(0));
        }
    }

    fn update(&mut self, io: &mut Io) {
        let keep_from = io.t - self.delay;
        self.history.push(io.t, |k| io.u_at(0, k), keep_from);
    }

    fn next_event(&self, t: f64) -> f64 {
        if !self.variable && t < self.delay { self.delay } else { f64::INFINITY }
    }

    fn diagnose(&self) -> Option<String> {
        self.history.overflow.clone()
    }
}

fn history(p: &mut Params) -> Result<(f64, History), Diagnostic> {
    let initial = p.number_or("initial", 0.0)?;
    let cubic = match p.number_or("order", 1.0)? {
        1.0 => false,
        3.0 => true,
        other => return Err(p.error("order", format!("must be 1 (linear) or 3 (cubic), got {other}"))),
    };
    let capacity = p.count_or("buffer", 1024, 10_000_000)?;
    let limit =
        p.number_where("max_buffer", Some(1e7), |v| (4.0..=1e9).contains(&v), "a number of samples in [4, 1e9]")?;
    Ok((initial, History::new(1, capacity, limit as usize, cubic)))
}

fn build_transport_delay(p: &mut Params) -> Result<Built, Diagnostic> {
    let delay = p.number_where("delay", None, |v| (0.0..1e300).contains(&v), "a delay >= 0 in seconds")?;
    let (initial, history) = history(p)?;
    let iface =
        Interface::new(SampleTime::Continuous).input("u", Width::Common, delay == 0.0).output("y", Width::Common);
    Ok(Built::new(TransportDelay { delay, variable: false, initial, history }, iface))
}

fn build_variable_delay(p: &mut Params) -> Result<Built, Diagnostic> {
    let delay = p.positive("max_delay")?;
    let (initial, history) = history(p)?;
    let iface = Interface::new(SampleTime::Continuous)
        .input("u", Width::Common, false)
        .input("delay", Width::Fixed(1), true)
        .output("y", Width::Common);
    Ok(Built::new(TransportDelay { delay, variable: true, initial, history }, iface))
}

/// z^-N, elementwise: a ring of N samples per element.
#[derive(Clone)]
pub struct Delay {
    samples: usize,
    initial: Vec<f64>,
    ring: Vec<f64>,
    /// Index (in samples) of the oldest entry, which is the output.
    head: usize,
}

impl Block for Delay {
    rust_type!(Delay);
    /// A shift register of `samples` entries per element: y = oldest,
    /// each update shifts by one and takes u (state k·w + j: element j,
    /// k samples before the output; for samples = 1, z⁺ = u).
    fn discrete_lti(&self) -> Option<ctlgraph_solver::StateSpace> {
        let (w, s) = (self.initial.len(), self.samples);
        let n = w * s;
        let (mut a, mut b, mut c) = (vec![0.0; n * n], vec![0.0; n * w], vec![0.0; w * n]);
        for j in 0..w {
            c[j * n + j] = 1.0;
            for k in 0..s - 1 {
                a[(k * w + j) * n + (k + 1) * w + j] = 1.0;
            }
            b[((s - 1) * w + j) * w + j] = 1.0;
        }
        Some(ctlgraph_solver::StateSpace { n, m: w, p: w, a, b, c, d: vec![0.0; w * w] })
    }

    fn set_width(&mut self, width: usize) -> Result<(), String> {
        self.initial = initial_vector(&self.initial, width)?;
        self.ring = vec![0.0; self.samples * width];
        Ok(())
    }

    fn initialize(&mut self, _x0: &mut [f64]) {
        let w = self.initial.len();
        for s in 0..self.samples {
            self.ring[s * w..(s + 1) * w].copy_from_slice(&self.initial);
        }
        self.head = 0;
    }

    fn output(&mut self, io: &mut Io) {
        let w = self.initial.len();
        io.set_all(0, &self.ring[self.head * w..(self.head + 1) * w]);
    }

    fn update(&mut self, io: &mut Io) {
        let w = self.initial.len();
        for k in 0..w {
            self.ring[self.head * w + k] = io.u_at(0, k);
        }
        self.head = (self.head + 1) % self.samples;
    }
}

/// A discrete delay of `samples` samples (also `unit_delay`'s implementation).
pub(crate) fn build_delay_of(p: &mut Params, samples: usize) -> Result<Built, Diagnostic> {
    let initial = p.opt_vector("initial")?.unwrap_or_else(|| vec![0.0]);
    let st = p.discrete_sample_time()?;
    let iface = Interface::new(st).input("u", Width::Common, false).output("y", Width::Common);
    Ok(Built::new(Delay { samples, initial, ring: Vec::new(), head: 0 }, iface))
}

fn build_delay(p: &mut Params) -> Result<Built, Diagnostic> {
    let samples = p.count_or("samples", 1, 10_000_000)?;
    build_delay_of(p, samples)
}
