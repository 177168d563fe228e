//! Time delays: `transport_delay` (fixed dead time), `variable_transport_delay`
//! (the delay is an input) and the discrete `delay` (z^-N). The continuous
//! ones keep the input's history at major steps in a [`History`] ring
//! buffer and interpolate it, as Simulink's Transport Delay does.

use crate::continuous::initial_vector;
use crate::{SAMPLE_TIME_REQUIRED, U_ANY, Y_SAME, table::*};
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Breakpoint, Diagnostic, Interface, Io, Params, SampleTime, Width};
use std::collections::VecDeque;

const HISTORY_PARAMS: [ctlgraph_core::ParamDoc; 4] = [
    param("initial", Number(0.0), "output until the delay has elapsed (t < delay)"),
    param(
        "order",
        Number(3.0),
        "degree of the polynomial through the nearest stored samples: 1 (linear, Simulink's), 3 or 5",
    ),
    param("buffer", Number(1024.0), "initial history capacity in samples; it doubles when full"),
    param("max_buffer", Number(1e7), "the most samples the history may hold; beyond, the run stops"),
];

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "transport_delay",
        category: "dynamics",
        summary: "y(t) = u(t − delay): a dead time (Simulink's Transport Delay).",
        doc: "y(t) = initial for t < delay, u(t − delay) after; elementwise. The input is stored at every \
              major step in a ring buffer and the output interpolated in it by the polynomial of degree \
              `order` through the nearest samples (Lagrange form): 1 is Simulink's linear interpolation, \
              whose error h²/8·|u''| no solver tolerance bounds; 3 (the default) errs by at most \
              0.0234·h⁴·|u⁽⁴⁾| between samples h apart (9/16·h⁴/4!), 5 by 0.0049·h⁶·|u⁽⁶⁾| \
              (225/64·h⁶/6!), up to h⁴/4! and 0.024·h⁶ next to a breakpoint, where all samples lie on \
              one side — below what rk4 and dopri5 commit at steps that resolve u (5 matches dopri5's \
              order best). Where fewer samples lie between a breakpoint and the newest (a delay under \
              `order` steps) the degree drops to what is there, down to linear. A jump no breakpoint \
              marks (an `fcn` switching, a solver stepping over it) turns the stencil away: each sample \
              is taken on the nearer side unless the divided difference it adds is over twice the other \
              side's (ENO interpolation, Harten, Engquist, Osher & Chakravarthy 1987, with Shu's central \
              bias), so the polynomial does not overshoot beside the jump when `order` steps of samples \
              lie on each side of it.\n\
              Breakpoints (as in Hairer's RETARD and MATLAB's dde23): at every major step where the \
              signals may be discontinuous — t = 0, a sample hit, a source's jump, a located zero \
              crossing, a clamped state, a host's input — the input's left limit is stored beside its \
              value after, and no interpolating polynomial reaches across the pair. The discontinuity \
              arrives at the output `delay` later, where the delay puts a major step, so the solver \
              integrates each side by its own smooth equation. Arrivals pass the discontinuity on \
              (in a loop it comes back one derivative smoother through each integrator) for 5 \
              generations, dopri5's order; a jump in value is passed on always; the kinks that sample \
              hits leave (one per hit) are left to the solver.\n\
              When the delay is in a loop, the adaptive methods' default `max_step` is at most the \
              delay, so the output never comes from past the newest sample; beyond it (a step longer \
              than the delay: `ctlgraph check` warns) it is extrapolated linearly from the last two, as \
              Simulink does. No direct feedthrough when delay > 0, so it breaks algebraic loops. The \
              buffer grows by doubling up to `max_buffer` samples, then the run stops with an error; \
              once grown it never reallocates.\n\
              Bounds: |y| <= max(|initial|, sup|u|) with order 1; higher orders may pass it by their \
              interpolation error (a crest between samples).",
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[
            param("delay", Required, "dead time, >= 0").kind(ParamKind::Number).unit("s"),
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
              history covers max_delay. y = initial while t − τ < 0. The input's breakpoints are stored \
              (no interpolation reaches across one), but their arrival at the output, where t − τ(t) \
              meets them, is not stepped to: the solver's error control finds it. The `delay` input has \
              direct feedthrough, `u` none.\n\
              Bounds: |y| <= max(|initial|, sup|u|) with order 1.",
        inputs: &[PortDoc { name: "u", doc: "any width" }, PortDoc { name: "delay", doc: "τ(t) [s], scalar" }],
        outputs: Y_SAME,
        params: &[
            param("max_delay", Required, "largest delay, > 0").kind(ParamKind::Number).unit("s"),
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
            param("samples", Number(1.0), "N, a whole number >= 1"),
            param("initial", Number(0.0), "output of the first N samples: a number or one per element")
                .kind(ParamKind::Numbers),
            SAMPLE_TIME_REQUIRED,
        ],
        build: build_delay,
    },
];

mod history;
pub use history::{History, Side};

/// Breakpoint generations a fixed delay passes on: a discontinuity of
/// the input arrives at the output `delay` later, where the solver lands; in
/// a loop it comes back smoother by one derivative per pass through an
/// integrator, and past the fifth derivative (dopri5's order) a 5th-order
/// method no longer sees it. Jumps in value are passed on whatever their
/// generation.
pub const MAX_GENERATION: u32 = 5;

/// Fixed or variable transport delay.
#[derive(Clone)]
pub struct TransportDelay {
    /// The fixed delay, or (variable) the largest.
    delay: f64,
    variable: bool,
    initial: f64,
    history: History,
    /// Breakpoints of the input still to arrive at the output (fixed delay
    /// only): their time at the input and their generation at the output,
    /// oldest first. Grows by doubling like the history, then never
    /// reallocates.
    arrivals: VecDeque<(f64, u32)>,
    /// The breakpoint whose left limit was taken, until its right value is.
    pending: Option<(f64, Breakpoint)>,
}

impl TransportDelay {
    fn new(delay: f64, variable: bool, initial: f64, history: History) -> Self {
        TransportDelay { delay, variable, initial, history, arrivals: VecDeque::new(), pending: None }
    }

    /// The delay in force: the parameter, or the clamped input.
    fn delay_now(&self, io: &Io) -> f64 {
        if self.variable { io.u(1).clamp(0.0, self.delay) } else { self.delay }
    }

    /// The arrivals after `t`.
    fn arrivals_after(&self, t: f64) -> impl Iterator<Item = (f64, u32)> + '_ {
        self.arrivals.iter().map(|&(s, g)| (s + self.delay, g)).skip_while(move |&(e, _)| e <= t)
    }

    /// The input time of the breakpoint arriving exactly at `t`, if one
    /// does (t − delay may round off it by an ulp).
    fn arriving_at(&self, t: f64) -> Option<f64> {
        self.arrivals
            .iter()
            .take_while(|&&(s, _)| s + self.delay <= t)
            .find(|&&(s, _)| s + self.delay == t)
            .map(|&(s, _)| s)
    }
}

impl Block for TransportDelay {
    rust_type!(TransportDelay);
    fn not_linearizable(&self) -> Option<&'static str> {
        Some("a transport delay e^(-sτ) has no finite-dimensional linear model (read the loop's delay margin instead)")
    }

    fn set_width(&mut self, width: usize) -> Result<(), String> {
        self.history = self.history.with_width(width);
        Ok(())
    }

    fn initialize(&mut self, _x0: &mut [f64]) {
        self.history.clear();
        self.arrivals.clear();
        // Here, not at build: a run's blocks are clones, which keep no spare capacity.
        self.arrivals.reserve(16);
        self.pending = None;
        if !self.variable && self.delay > 0.0 {
            // The start is a breakpoint: the output jumps from `initial` at t = delay.
            self.arrivals.push_back((0.0, 1));
        }
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
            return;
        }
        let side = if io.is_left_limit() { Side::Left } else { Side::Right };
        let t = if self.variable { t } else { self.arriving_at(io.t).unwrap_or(t) };
        self.history.at(t, side, io.output(0));
    }

    fn update(&mut self, io: &mut Io) {
        let keep_from = io.t - self.delay;
        while self.arrivals.front().is_some_and(|&(s, _)| s + self.delay < io.t) {
            self.arrivals.pop_front();
        }
        let jumped = self.history.push(io.t, |k| io.u_at(0, k), keep_from);
        if let Some((t, at)) = self.pending.take()
            && t == io.t
            && !self.variable
            && (jumped || (!at.sample_hit_only && at.generation < MAX_GENERATION))
        {
            self.arrivals.push_back((t, at.generation + 1));
        }
    }

    fn keeps_history(&self) -> bool {
        self.variable || self.delay > 0.0
    }

    fn left_limit(&mut self, io: &Io, at: Breakpoint) {
        self.history.push_left(io.t, |k| io.u_at(0, k), io.t - self.delay);
        self.pending = Some((io.t, at));
    }

    fn next_event(&self, t: f64) -> f64 {
        self.arrivals_after(t).next().map_or(f64::INFINITY, |(e, _)| e)
    }

    fn event_generation(&self, t: f64) -> u32 {
        self.arrivals_after(t).next().map_or(0, |(_, g)| g)
    }

    fn dead_time(&self) -> Option<f64> {
        (!self.variable && self.delay > 0.0).then_some(self.delay)
    }

    fn diagnose(&self) -> Option<String> {
        self.history.overflow.clone()
    }
}

fn history(p: &mut Params) -> Result<(f64, History), Diagnostic> {
    let initial = p.number("initial")?;
    let degree = match p.number("order")? {
        1.0 => 1,
        3.0 => 3,
        5.0 => 5,
        other => return Err(p.error("order", format!("must be 1 (linear), 3 (cubic) or 5 (quintic), got {other}"))),
    };
    let capacity = p.count("buffer", 10_000_000)?;
    let limit = p.number_where("max_buffer", None, |v| (4.0..=1e9).contains(&v), "a number of samples in [4, 1e9]")?;
    Ok((initial, History::new(1, capacity, limit as usize, degree)))
}

fn build_transport_delay(p: &mut Params) -> Result<Built, Diagnostic> {
    let delay = p.number_where("delay", None, |v| (0.0..1e300).contains(&v), "a delay >= 0 in seconds")?;
    let (initial, history) = history(p)?;
    let iface =
        Interface::new(SampleTime::Continuous).input("u", Width::Common, delay == 0.0).output("y", Width::Common);
    Ok(Built::new(TransportDelay::new(delay, false, initial, history), iface))
}

fn build_variable_delay(p: &mut Params) -> Result<Built, Diagnostic> {
    let delay = p.positive("max_delay")?;
    let (initial, history) = history(p)?;
    let iface = Interface::new(SampleTime::Continuous)
        .input("u", Width::Common, false)
        .input("delay", Width::Fixed(1), true)
        .output("y", Width::Common);
    Ok(Built::new(TransportDelay::new(delay, true, initial, history), iface))
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
    /// A ring of `samples` entries per element: the oldest out, the input in its place.
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let (w, n) = (self.initial.len(), self.samples);
        c.equation(format!("y(k) = u(k - {n})  (a ring buffer of {n} samples)"));
        let initial: Vec<f64> = (0..n).flat_map(|_| self.initial.iter().copied()).collect();
        let ring = c.state("ring", &initial);
        let head = c.counter("head", 0);
        let at = |k: usize| if n * w == 1 { ring.clone() } else { format!("{ring}[{head} * {w}u + {k}u]") };
        for k in 0..w {
            c.output(format!("{} = {};", c.y_at(0, k), at(k)));
            c.update(format!("{} = {};", at(k), c.u_at(0, k)));
        }
        c.update(format!("if (++{head} == {n}u) {head} = 0u;"));
        Ok(())
    }
}

/// A discrete delay of `samples` samples (also `unit_delay`'s implementation).
pub(crate) fn build_delay_of(p: &mut Params, samples: usize) -> Result<Built, Diagnostic> {
    let initial = p.vector("initial")?;
    let st = p.discrete_sample_time()?;
    let iface = Interface::new(st).input("u", Width::Common, false).output("y", Width::Common);
    Ok(Built::new(Delay { samples, initial, ring: Vec::new(), head: 0 }, iface))
}

fn build_delay(p: &mut Params) -> Result<Built, Diagnostic> {
    let samples = p.count("samples", 10_000_000)?;
    build_delay_of(p, samples)
}
