//! Test signals as Simulink's Sources library has them: the Signal
//! Generator (sine, square, sawtooth), the Chirp Signal and the Repeating
//! Sequence. Their jumps and corners are events, so the simulator steps
//! exactly onto them.

use crate::sources::{scalar_source, windowed};
use crate::{ACTIVE, SAMPLE_TIME_CONTINUOUS, Y_SCALAR, table::*};
use ctlgraph_core::registry::{BlockType, Built};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, TimeOnly, Width};

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "signal_generator",
        category: "sources",
        summary: "A sine, square or sawtooth wave (Simulink's Signal Generator).",
        doc: "With A the amplitude and f the frequency in Hz, as Simulink's Signal Generator on the \
              simulation time:\n\
              \x20 sine:     y = A·sin(2π·f·t)\n\
              \x20 square:   y = A while frac(f·t) < 1/2, else −A (A from t = 0)\n\
              \x20 sawtooth: y = 2A·(f·t − floor(f·t + 1/2)): 0 at t = 0, rising at slope 2A·f, jumping \
              from A to −A at t = (k + 1/2)/f\n\
              The jumps of the square and sawtooth waves are events: the simulator puts a major step \
              exactly on each, the left limit on one side and the new value on the other.",
        inputs: &[],
        outputs: Y_SCALAR,
        params: &[
            param("waveform", Word("sine"), "sine | square | sawtooth").options(&["sine", "square", "sawtooth"]),
            param("amplitude", Number(1.0), "A, the peak value (negative: the wave shifted by half a period)"),
            param("frequency", Number(1.0), "f, > 0").unit("Hz"),
            SAMPLE_TIME_CONTINUOUS,
            ACTIVE,
        ],
        build: build_signal_generator,
    },
    BlockType {
        name: "chirp",
        category: "sources",
        summary: "A sine wave whose frequency rises linearly with time (Simulink's Chirp Signal).",
        doc: "y = A·sin(2π·(f0·t + (f1 − f0)·t²/(2·T))): the instantaneous frequency f0 + (f1 − f0)·t/T \
              is f0 at t = 0 and f1 at the target time T, and keeps changing at that rate after it \
              (as Simulink's Chirp Signal, whose defaults these are).",
        inputs: &[],
        outputs: Y_SCALAR,
        params: &[
            param("initial_frequency", Number(0.1), "f0, the frequency at t = 0").unit("Hz"),
            param("target_frequency", Number(1.0), "f1, the frequency at the target time").unit("Hz"),
            param("target_time", Number(100.0), "T > 0, when the frequency reaches f1").unit("s"),
            param("amplitude", Number(1.0), "A"),
            SAMPLE_TIME_CONTINUOUS,
            ACTIVE,
        ],
        build: build_chirp,
    },
    BlockType {
        name: "repeating_sequence",
        category: "sources",
        summary: "A periodic piecewise-linear signal through (time, value) points (Simulink's Repeating Sequence).",
        doc: "y(t) = the linear interpolation of (times[i], values[i]) at t mod P, with the period P the \
              last time (as Simulink's Repeating Sequence). `times` start at 0 and do not decrease; a \
              repeated time is a jump. Every breakpoint of every period is an event — the simulator \
              steps onto each corner and jump, so what integrates the signal sees each segment whole.",
        inputs: &[],
        outputs: Y_SCALAR,
        params: &[
            param("times", Required, "breakpoint times, from 0, non-decreasing; the last is the period")
                .kind(ParamKind::Numbers)
                .unit("s"),
            param("values", Required, "the value at each time").kind(ParamKind::Numbers),
            SAMPLE_TIME_CONTINUOUS,
            ACTIVE,
        ],
        build: build_repeating_sequence,
    },
];

#[derive(Clone, Copy, Debug, PartialEq)]
enum Shape {
    Sine,
    Square,
    Sawtooth,
}

/// The Signal Generator. Its jump times are `k·half` (half a period),
/// computed by the same expression in `output` and `next_event`, so that
/// [`Io::reached`] compares equal numbers at a jump.
#[derive(Clone)]
pub struct Waveform {
    shape: Shape,
    amplitude: f64,
    frequency: f64,
    half: f64,
}

impl Waveform {
    /// The index k of the last half-period boundary `k·half` reached.
    fn boundary(&self, io: &Io) -> f64 {
        let k = (io.t / self.half).floor().max(0.0);
        [k + 1.0, k, k - 1.0].into_iter().find(|&c| c >= 0.0 && io.reached(c * self.half)).unwrap_or(0.0)
    }

    /// Whether half-period boundary `k` is a jump.
    fn jumps_at(&self, k: f64) -> bool {
        match self.shape {
            Shape::Sine => false,
            Shape::Square => k >= 1.0,
            Shape::Sawtooth => k % 2.0 == 1.0,
        }
    }
}

impl Block for Waveform {
    rust_type!(Waveform);
    fn updates(&self) -> bool {
        false
    }
    fn time_only(&self) -> Option<TimeOnly> {
        Some(if self.shape == Shape::Sine { TimeOnly::Smooth } else { TimeOnly::JumpsAtEvents })
    }
    fn output(&mut self, io: &mut Io) {
        let a = self.amplitude;
        let y = match self.shape {
            Shape::Sine => a * (2.0 * std::f64::consts::PI * self.frequency * io.t).sin(),
            Shape::Square => {
                if self.boundary(io) % 2.0 == 0.0 {
                    a
                } else {
                    -a
                }
            }
            // floor(f·t + 1/2) counted by the jumps reached: (k + 1) div 2.
            Shape::Sawtooth => 2.0 * a * (self.frequency * io.t - ((self.boundary(io) + 1.0) / 2.0).floor()),
        };
        io.set(0, y);
    }
    fn next_event(&self, t: f64) -> f64 {
        if self.shape == Shape::Sine {
            return f64::INFINITY;
        }
        let k = (t / self.half).floor().max(0.0);
        [k - 1.0, k, k + 1.0, k + 2.0, k + 3.0]
            .into_iter()
            .filter(|&c| self.jumps_at(c))
            .map(|c| c * self.half)
            .find(|&e| e > t)
            .unwrap_or(f64::INFINITY)
    }
    fn min_event_spacing(&self) -> f64 {
        match self.shape {
            Shape::Sine => f64::INFINITY,
            Shape::Square => self.half,
            Shape::Sawtooth => 2.0 * self.half,
        }
    }
}

fn build_signal_generator(p: &mut Params) -> Result<Built, Diagnostic> {
    let shape = match p.choice("waveform", &["sine", "square", "sawtooth"])? {
        "square" => Shape::Square,
        "sawtooth" => Shape::Sawtooth,
        _ => Shape::Sine,
    };
    let amplitude = p.number_where("amplitude", None, f64::is_finite, "a finite number")?;
    let frequency = p.number_where("frequency", None, |f| f > 0.0 && f.is_finite(), "a positive frequency")?;
    let st = p.sample_time()?;
    let block = Waveform { shape, amplitude, frequency, half: 0.5 / frequency };
    let mut iface = Interface::new(st).output("y", Width::Fixed(1));
    iface.piecewise_constant = shape == Shape::Square;
    windowed(p, Built::new(block, iface))
}

fn build_chirp(p: &mut Params) -> Result<Built, Diagnostic> {
    let f0 = p.number_where("initial_frequency", None, f64::is_finite, "a finite frequency")?;
    let f1 = p.number_where("target_frequency", None, f64::is_finite, "a finite frequency")?;
    let target = p.number_where("target_time", None, |t| t > 0.0 && t.is_finite(), "a positive time")?;
    let amplitude = p.number_where("amplitude", None, f64::is_finite, "a finite number")?;
    // The phase's t² coefficient, in cycles per second squared.
    let sweep = (f1 - f0) / (2.0 * target);
    let tau = 2.0 * std::f64::consts::PI;
    scalar_source(p, Vec::new(), false, move |io| amplitude * (tau * (f0 * io.t + sweep * io.t * io.t)).sin())
}

/// The Repeating Sequence. Its events are `k·period + times[j]`, computed
/// by that expression in `output` and `next_event` alike (see [`Waveform`]).
#[derive(Clone)]
pub struct Sequence {
    times: Vec<f64>,
    values: Vec<f64>,
    period: f64,
}

impl Sequence {
    /// The first time of the period `t` lies in, as a multiple of the period.
    fn period_start(&self, io: &Io) -> f64 {
        let k = (io.t / self.period).floor().max(0.0);
        let k = [k + 1.0, k, k - 1.0].into_iter().find(|&c| c >= 0.0 && io.reached(c * self.period));
        k.unwrap_or(0.0) * self.period
    }
}

impl Block for Sequence {
    rust_type!(Sequence);
    fn updates(&self) -> bool {
        false
    }
    fn time_only(&self) -> Option<TimeOnly> {
        Some(TimeOnly::JumpsAtEvents)
    }
    fn output(&mut self, io: &mut Io) {
        let (times, values, n) = (&self.times, &self.values, self.times.len());
        let start = self.period_start(io);
        // Segment i: the interior breakpoints reached, in order (a repeated
        // time is reached with its twin, so a jump's segment has length).
        let i = times[1..n - 1].partition_point(|&tj| io.reached(start + tj));
        let span = times[i + 1] - times[i];
        let y = if span > 0.0 {
            let along = (io.t - start - times[i]).clamp(0.0, span);
            values[i] + (values[i + 1] - values[i]) * along / span
        } else {
            values[i + 1]
        };
        io.set(0, y);
    }
    fn next_event(&self, t: f64) -> f64 {
        let k = (t / self.period).floor().max(0.0);
        for c in [k - 1.0, k, k + 1.0, k + 2.0] {
            if c < 0.0 {
                continue;
            }
            let start = c * self.period;
            let j = self.times[..self.times.len() - 1].partition_point(|&tj| start + tj <= t);
            if let Some(&tj) = self.times[..self.times.len() - 1].get(j) {
                return start + tj;
            }
        }
        f64::INFINITY
    }
    fn min_event_spacing(&self) -> f64 {
        self.times.windows(2).map(|w| w[1] - w[0]).filter(|&d| d > 0.0).fold(f64::INFINITY, f64::min)
    }
}

fn build_repeating_sequence(p: &mut Params) -> Result<Built, Diagnostic> {
    let times = p.vector("times")?;
    let values = p.vector("values")?;
    if times.len() < 2 {
        return Err(p.error("times", "needs at least two times: the first is 0, the last the period"));
    }
    if times.len() != values.len() {
        let message = format!("{} values for {} times: give one value per time", values.len(), times.len());
        return Err(p.error("values", message));
    }
    if let Some(v) = times.iter().chain(&values).find(|v| !v.is_finite()) {
        return Err(p.error("times", format!("{v} in the data: every time and value must be a finite number")));
    }
    if times[0] != 0.0 {
        return Err(p.error("times", format!("the first time is {}: a period starts at 0", times[0])));
    }
    if let Some(i) = times.windows(2).position(|w| w[1] < w[0]) {
        return Err(p.error("times", format!("times must not decrease: {} then {}", times[i], times[i + 1])));
    }
    let period = times[times.len() - 1];
    if period <= 0.0 {
        return Err(p.error("times", "the last time, the period, must be positive"));
    }
    let st = p.sample_time()?;
    let block = Sequence { times, values, period };
    windowed(p, Built::new(block, Interface::new(st).output("y", Width::Fixed(1))))
}
