//! Sources: constant, step, ramp, sine, pulse, clock.

use crate::{ACTIVE, SAMPLE_TIME_CONTINUOUS, Y_SCALAR, table::*};
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, SampleTime, TimeOnly, Width};

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "constant",
        category: "sources",
        summary: "A constant value (scalar or vector).",
        doc: "y = value. Computed once, at the start of the run.",
        inputs: &[],
        outputs: &[PortDoc { name: "y", doc: "the value; width = number of elements of `value`" }],
        params: &[param("value", Number(1.0), "a number or a list of numbers").kind(ParamKind::Numbers), ACTIVE],
        build: build_constant,
    },
    BlockType {
        name: "step",
        category: "sources",
        summary: "A step from `initial` to `value` at time `at`.",
        doc: "y = initial for t < at, y = value for t >= at. The simulator puts a major step exactly \
              at `at`; the solver's stages before it see `initial`, after it `value`.",
        inputs: &[],
        outputs: Y_SCALAR,
        params: &[
            param("at", Number(0.0), "switching time").unit("s"),
            param("initial", Number(0.0), "value before `at`"),
            param("value", Number(1.0), "value from `at` on"),
            SAMPLE_TIME_CONTINUOUS,
            ACTIVE,
        ],
        build: build_step,
    },
    BlockType {
        name: "ramp",
        category: "sources",
        summary: "A ramp of given slope starting at time `start`.",
        doc: "y = initial for t < start, y = initial + slope·(t − start) for t >= start.",
        inputs: &[],
        outputs: Y_SCALAR,
        params: &[
            param("slope", Number(1.0), "units per second"),
            param("start", Number(0.0), "start time").unit("s"),
            param("initial", Number(0.0), "output before `start`"),
            SAMPLE_TIME_CONTINUOUS,
            ACTIVE,
        ],
        build: build_ramp,
    },
    BlockType {
        name: "sine",
        category: "sources",
        summary: "A sine wave.",
        doc: "y = bias + amplitude·sin(2π·frequency·t + phase). `frequency` is in Hz (not rad/s).",
        inputs: &[],
        outputs: Y_SCALAR,
        params: &[
            param("amplitude", Number(1.0), "peak value"),
            param("frequency", Number(1.0), "").unit("Hz"),
            param("phase", Number(0.0), "").unit("rad"),
            param("bias", Number(0.0), "offset added to the wave"),
            SAMPLE_TIME_CONTINUOUS,
            ACTIVE,
        ],
        build: build_sine,
    },
    BlockType {
        name: "pulse",
        category: "sources",
        summary: "A periodic rectangular pulse train.",
        doc: "y = amplitude during the first `duty`·period of every period from `delay` on, else 0. \
              Every edge is an event: the simulator steps exactly onto it.",
        inputs: &[],
        outputs: Y_SCALAR,
        params: &[
            param("amplitude", Number(1.0), "pulse height"),
            param("period", Number(1.0), ", > 0").unit("s"),
            param("duty", Number(0.5), "fraction of the period the pulse is high, in (0, 1)"),
            param("delay", Number(0.0), "time of the first rising edge").unit("s"),
            SAMPLE_TIME_CONTINUOUS,
            ACTIVE,
        ],
        build: build_pulse,
    },
    BlockType {
        name: "clock",
        category: "sources",
        summary: "The simulation time.",
        doc: "y = t.",
        inputs: &[],
        outputs: Y_SCALAR,
        params: &[SAMPLE_TIME_CONTINUOUS, ACTIVE],
        build: build_clock,
    },
];

/// A source whose output is a function of time only.
#[derive(Clone)]
struct TimeFn<F: Fn(&Io) -> f64 + Send + Sync + Clone> {
    f: F,
    events: Vec<f64>,
    /// The last evaluation: its time's bits, whether that time was seen as
    /// a left limit ([`Io::reached`]; only a source with events can jump
    /// there), and the value. A source is asked for the same time several
    /// times a step — RK4's two middle stages share one, its last stage's
    /// is the next major step's — and f may be costly (a `sin`): RK4 then
    /// evaluates it twice a step instead of five times. The interpreter's
    /// sweeps skip the call itself at a time already seen
    /// ([`Block::time_only`]); this serves the callers that do not, a
    /// generated step's.
    last: (u64, bool, f64),
}

impl<F: Fn(&Io) -> f64 + Send + Sync + Clone> TimeFn<F> {
    /// No time's bits are NaN's: the first call evaluates f.
    const NONE: (u64, bool, f64) = (u64::MAX, false, 0.0);
}

impl<F: Fn(&Io) -> f64 + Send + Sync + Clone + 'static> Block for TimeFn<F> {
    fn updates(&self) -> bool {
        false
    }
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.last = Self::NONE;
    }
    fn time_only(&self) -> Option<TimeOnly> {
        Some(if self.events.is_empty() { TimeOnly::Smooth } else { TimeOnly::JumpsAtEvents })
    }
    fn output(&mut self, io: &mut Io) {
        let key = (io.t.to_bits(), !self.events.is_empty() && !io.reached(io.t));
        if (self.last.0, self.last.1) != key {
            self.last = (key.0, key.1, (self.f)(io));
        }
        io.set(0, self.last.2);
    }

    fn next_event(&self, t: f64) -> f64 {
        self.events.iter().copied().find(|&e| e > t).unwrap_or(f64::INFINITY)
    }
}

/// A source y = f(t). `piecewise` declares that f changes only at `events`.
pub(crate) fn scalar_source<F: Fn(&Io) -> f64 + Send + Sync + Clone + 'static>(
    p: &mut Params,
    events: Vec<f64>,
    piecewise: bool,
    f: F,
) -> Result<Built, Diagnostic> {
    let st = p.sample_time()?;
    let mut iface = Interface::new(st).output("y", Width::Fixed(1));
    iface.piecewise_constant = piecewise;
    windowed(p, Built::new(TimeFn { f, events, last: TimeFn::<F>::NONE }, iface))
}

/// Zero outside an active window [on, off); the window's edges are events.
#[derive(Clone)]
pub struct Windowed {
    inner: Box<dyn Block>,
    on: f64,
    off: f64,
}

impl Block for Windowed {
    rust_type!(Windowed);
    fn updates(&self) -> bool {
        self.inner.updates()
    }
    fn set_width(&mut self, width: usize) -> Result<(), String> {
        self.inner.set_width(width)
    }
    fn num_states(&self) -> usize {
        self.inner.num_states()
    }
    fn initialize(&mut self, x0: &mut [f64]) {
        self.inner.initialize(x0);
    }
    /// The window's edges are events.
    fn time_only(&self) -> Option<TimeOnly> {
        self.inner.time_only().map(|_| TimeOnly::JumpsAtEvents)
    }
    fn output(&mut self, io: &mut Io) {
        if io.reached(self.on) && !io.reached(self.off) {
            self.inner.output(io);
        } else {
            for port in 0..io.num_outputs() {
                io.output(port).iter_mut().for_each(|v| *v = 0.0);
            }
        }
    }
    fn update(&mut self, io: &mut Io) {
        self.inner.update(io);
    }
    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        self.inner.derivatives(io, dx);
    }
    fn clamp_states(&self, x: &mut [f64]) -> bool {
        self.inner.clamp_states(x)
    }
    fn next_event(&self, t: f64) -> f64 {
        let own = [self.on, self.off].into_iter().filter(|&e| e > t).fold(f64::INFINITY, f64::min);
        own.min(self.inner.next_event(t))
    }
}

/// Applies the optional `active: [t_on, t_off]` window to a built source.
/// A windowed constant is no longer constant: it runs continuously.
pub(crate) fn windowed(p: &mut Params, built: Built) -> Result<Built, Diagnostic> {
    let Some(window) = p.opt_vector("active")? else { return Ok(built) };
    let [on, off] = window[..] else {
        return Err(p.error("active", format!("expected [t_on, t_off], got {} numbers", window.len())));
    };
    if on.is_nan() || off.is_nan() || off <= on {
        return Err(p.error("active", format!("t_off ({off}) must be after t_on ({on})")));
    }
    let mut iface = built.iface;
    if iface.sample_time == SampleTime::Constant {
        iface.sample_time = SampleTime::Continuous;
        iface.piecewise_constant = true;
    }
    Ok(Built { block: Box::new(Windowed { inner: built.block, on, off }), iface })
}

fn build_constant(p: &mut Params) -> Result<Built, Diagnostic> {
    let value = p.vector("value")?;
    if value.is_empty() {
        return Err(p.error("value", "needs at least one number"));
    }
    #[derive(Clone)]
    struct Constant(Vec<f64>);
    impl Block for Constant {
        fn updates(&self) -> bool {
            false
        }
        fn output(&mut self, io: &mut Io) {
            io.set_all(0, &self.0);
        }
        fn time_only(&self) -> Option<TimeOnly> {
            Some(TimeOnly::Smooth)
        }
        fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
            c.equation("y = value (computed once, in init)");
            for (k, v) in self.0.iter().enumerate() {
                c.output(format!("{} = {};", c.y_at(0, k), c.num(*v)));
            }
            Ok(())
        }
    }
    let iface = Interface::new(SampleTime::Constant).output("y", Width::Fixed(value.len()));
    windowed(p, Built::new(Constant(value), iface))
}

fn build_step(p: &mut Params) -> Result<Built, Diagnostic> {
    let at = p.number("at")?;
    let (initial, value) = (p.number("initial")?, p.number("value")?);
    scalar_source(p, vec![at], true, move |io| if io.reached(at) { value } else { initial })
}

fn build_ramp(p: &mut Params) -> Result<Built, Diagnostic> {
    let (slope, start, initial) = (p.number("slope")?, p.number("start")?, p.number("initial")?);
    scalar_source(
        p,
        vec![start],
        false,
        move |io| if io.t > start { initial + slope * (io.t - start) } else { initial },
    )
}

fn build_sine(p: &mut Params) -> Result<Built, Diagnostic> {
    let amplitude = p.number("amplitude")?;
    let w = 2.0 * std::f64::consts::PI * p.number("frequency")?;
    let (phase, bias) = (p.number("phase")?, p.number("bias")?);
    scalar_source(p, Vec::new(), false, move |io| bias + amplitude * (w * io.t + phase).sin())
}

fn build_clock(p: &mut Params) -> Result<Built, Diagnostic> {
    scalar_source(p, Vec::new(), false, |io| io.t)
}

fn build_pulse(p: &mut Params) -> Result<Built, Diagnostic> {
    let amplitude = p.number("amplitude")?;
    let period = p.number_where("period", None, |v| v > 0.0 && v.is_finite(), "a positive number")?;
    let duty = p.number_where("duty", None, |v| v > 0.0 && v < 1.0, "strictly between 0 and 1")?;
    let delay = p.number("delay")?;
    let st = p.sample_time()?;
    let pulse = Pulse { amplitude, period, high: duty * period, delay };
    windowed(p, Built::new(pulse, Interface::new(st).piecewise_constant().output("y", Width::Fixed(1))))
}

/// Edges are computed as `delay + k·period` (and `+ high`), the same
/// expressions `next_event` hands the simulator, so `reached` compares equal
/// floating-point values at the edges.
#[derive(Clone)]
pub struct Pulse {
    amplitude: f64,
    period: f64,
    high: f64,
    delay: f64,
}

impl Pulse {
    fn index(&self, t: f64) -> f64 {
        ((t - self.delay) / self.period).floor()
    }
}

impl Block for Pulse {
    rust_type!(Pulse);
    fn updates(&self) -> bool {
        false
    }
    fn time_only(&self) -> Option<TimeOnly> {
        Some(TimeOnly::JumpsAtEvents)
    }
    fn output(&mut self, io: &mut Io) {
        let k = self.index(io.t);
        let mut y = 0.0;
        for cand in [k + 1.0, k, k - 1.0] {
            let rise = self.delay + cand * self.period;
            if cand >= 0.0 && io.reached(rise) {
                y = if io.reached(rise + self.high) { 0.0 } else { self.amplitude };
                break;
            }
        }
        io.set(0, y);
    }

    fn min_event_spacing(&self) -> f64 {
        self.high.min(self.period - self.high)
    }

    fn next_event(&self, t: f64) -> f64 {
        let k = self.index(t).max(0.0);
        let mut best = f64::INFINITY;
        for cand in [k - 1.0, k, k + 1.0, k + 2.0] {
            if cand < 0.0 {
                continue;
            }
            let rise = self.delay + cand * self.period;
            for e in [rise, rise + self.high] {
                if e > t && e < best {
                    best = e;
                }
            }
        }
        best
    }
}
