//! Zero-crossing detection: after every solver step the watched functions'
//! signs are compared with their signs at the step's start; a change in a
//! direction the block accepts is located inside the step on the solver's
//! dense output by the Illinois variant of regula falsi (bracketing,
//! superlinear), to a time tolerance of a few ulps of t. The step then ends
//! at the first such crossing — its right side, where the sign has changed —
//! and the next major step lets blocks switch mode there.
//!
//! Chattering (Simulink's "consecutive zero crossings"): more than
//! [`MAX_CONSECUTIVE_EVENTS`] events each within 1e-12·max(1, |t|) of the
//! last, or a run of ever closer events (a Zeno point), stop the run, or
//! with `zero_crossing: adaptive` turn that block's detection off with a
//! warning. Either way a Zeno model cannot hang.

use super::SimError;
use crate::block::Crossing;
use crate::compile::{Model, Rate};
use crate::flatten::ZeroCrossing;
use ctlgraph_solver::{Integrator, OdeSystem};
use std::ops::Range;

/// What the watch evaluates inside a step, from either back-end: the
/// solver's system (for the dense output) that also computes the
/// continuous outputs at (t, x), modes frozen, and a watched block's
/// functions there. `b` is the block's entry in [`Watch::blocks`], `i`
/// its index in the model.
pub(crate) trait Crossings: OdeSystem {
    fn outputs(&mut self, t: f64, x: &[f64]);
    /// Block `i`'s functions at (t, x), the outputs computed.
    fn zero_crossings(&mut self, b: usize, i: usize, t: f64, x: &[f64], g: &mut [f64]);
    /// Which sign changes of block `i`'s function `k` are events.
    fn direction(&self, b: usize, i: usize, k: usize) -> Crossing;
}

/// The blocks whose zero crossings are watched: continuous ones that
/// need major steps, in model order.
pub(crate) fn watched(model: &Model) -> Vec<usize> {
    (0..model.blocks.len())
        .filter(|&i| model.meta[i].rate == Rate::Continuous && model.blocks[i].needs_major_step())
        .collect()
}

/// Events in a row at nearly one time before the run counts as chattering
/// (Simulink's default for "Number of consecutive zero crossings").
pub const MAX_CONSECUTIVE_EVENTS: u32 = 1000;

/// Root-finding iterations per crossing before settling for the bracket.
const MAX_ITERATIONS: usize = 200;

/// How far after an event, in location tolerances, a function that fired
/// there is probed for the side it leaves to: far enough that the
/// location error is outgrown when the function leaves at 1/16 of the
/// speed it arrived with, well inside the chattering window.
const PROBE: f64 = 16.0;

/// Two events closer than this (relative to max(1, |t|)) are consecutive.
const CONSECUTIVE: f64 = 1e-12;

/// A Zeno point: this many events in a row, each closer to the last than
/// the one before and closer than `ZENO_SCALE`·max(1, |t|). Geometric
/// accumulation (a ball bouncing with restitution 0.8 has 47 impacts from
/// 1e-9 s apart to where they can no longer be told apart) outruns the
/// consecutive-events rule, which catches only the final pile-up.
const ZENO_EVENTS: u32 = 20;
const ZENO_SCALE: f64 = 1e-9;

/// The width to which a crossing near time `t` is located: a few ulps.
fn tolerance(t: f64) -> f64 {
    8.0 * f64::EPSILON * t.abs().max(1.0)
}

/// The watched zero-crossing functions of a model and their state.
#[derive(Clone)]
pub(crate) struct Watch {
    mode: ZeroCrossing,
    /// Continuous blocks with zero crossings, execution order: their
    /// `major_step` runs at every major step whatever the mode.
    pub blocks: Vec<usize>,
    /// Each block's functions in `sign`, `g0`, `g`.
    ranges: Vec<Range<usize>>,
    /// Per entry of `blocks`: whether its crossings are located.
    active: Vec<bool>,
    /// Sign of each function at the last major step where it was nonzero.
    sign: Vec<f64>,
    /// Values at the last major step.
    g0: Vec<f64>,
    /// Values at the end of the current step.
    g1: Vec<f64>,
    /// Scratch: values at a trial time.
    g: Vec<f64>,
    x_trial: Vec<f64>,
    pub events: u64,
    consecutive: u32,
    last_event: f64,
    /// Events in a row each closer to the last than the one before.
    shrinking: u32,
    last_interval: f64,
    /// Entry of `blocks` whose crossing ended the last step.
    last_block: usize,
    /// Per function: whether it fired at the event that ended the last
    /// step (then `restart`: whether it fired at the step's start).
    fired: Vec<bool>,
    restart: Vec<bool>,
    /// Per function: the side it started the step on, when it crossed.
    start_sign: Vec<f64>,
    pub warnings: Vec<String>,
}

impl Watch {
    pub fn new(model: &Model, mode: ZeroCrossing) -> Self {
        let blocks = watched(model);
        let mut ranges = Vec::new();
        let mut n = 0;
        for &i in &blocks {
            let count = model.blocks[i].num_zero_crossings();
            ranges.push(n..n + count);
            n += count;
        }
        Watch {
            mode,
            active: vec![mode != ZeroCrossing::Off; blocks.len()],
            blocks,
            ranges,
            sign: vec![0.0; n],
            g0: vec![0.0; n],
            g1: vec![0.0; n],
            g: vec![0.0; n],
            x_trial: vec![0.0; model.between.n_integrated],
            events: 0,
            consecutive: 0,
            last_event: f64::NEG_INFINITY,
            shrinking: 0,
            last_interval: f64::INFINITY,
            last_block: 0,
            fired: vec![false; n],
            restart: vec![false; n],
            start_sign: vec![0.0; n],
            warnings: Vec::new(),
        }
    }

    /// Whether the watched blocks' modes are frozen in minor steps (at
    /// the start of a run: whether crossings are located).
    pub fn freezes(&self) -> bool {
        self.mode != ZeroCrossing::Off
    }

    /// Back to the start of a run (detection re-enabled; the back-end
    /// freezes the watched blocks' modes again when [`Watch::freezes`]).
    pub fn reset(&mut self) {
        let on = self.freezes();
        self.active.iter_mut().for_each(|a| *a = on);
        self.sign.iter_mut().for_each(|s| *s = 0.0);
        self.events = 0;
        self.consecutive = 0;
        self.last_event = f64::NEG_INFINITY;
        self.shrinking = 0;
        self.last_interval = f64::INFINITY;
        self.fired.iter_mut().for_each(|f| *f = false);
        self.restart.iter_mut().for_each(|f| *f = false);
        self.warnings.clear();
    }

    /// At a major step, after the outputs: the functions' values and signs
    /// that the next step's end is compared with; `eval(b, i, g)` gives
    /// block `i`'s (entry `b`) functions at the major step.
    /// Inlined, so a graph without watched blocks pays one test, not a call.
    #[inline]
    pub fn record_signs(&mut self, eval: impl FnMut(usize, usize, &mut [f64])) {
        if !self.blocks.is_empty() {
            self.record_watched_signs(eval);
        }
    }

    fn record_watched_signs(&mut self, mut eval: impl FnMut(usize, usize, &mut [f64])) {
        for (b, &i) in self.blocks.iter().enumerate() {
            if !self.active[b] {
                continue;
            }
            let r = self.ranges[b].clone();
            eval(b, i, &mut self.g0[r.clone()]);
            for k in r {
                if self.g0[k] != 0.0 {
                    self.sign[k] = self.g0[k].signum();
                }
            }
        }
    }

    /// After a step from `t0` to `t1` that ended in state `x`: the time of
    /// the first accepted crossing inside it, with `x` moved there; or
    /// `None` when no watched function changed sign. [`Watch::fired`] then
    /// lists the functions that crossed there.
    ///
    /// A function that crossed at `t0` sits within a few ulps of zero there,
    /// on either side; what counts is the side it leaves to (a bouncing
    /// ball's height is −1e-14 at the impact but rising). Its starting sign
    /// is therefore read just after `t0` (CVODE does the same), so that it
    /// leaving and coming back within one step is still an event.
    #[inline]
    pub fn locate(
        &mut self,
        sys: &mut impl Crossings,
        integ: &mut Integrator,
        t0: f64,
        t1: f64,
        x: &mut [f64],
    ) -> Option<f64> {
        if self.blocks.is_empty() { None } else { self.locate_watched(sys, integ, t0, t1, x) }
    }

    fn locate_watched(
        &mut self,
        sys: &mut impl Crossings,
        integ: &mut Integrator,
        t0: f64,
        t1: f64,
        x: &mut [f64],
    ) -> Option<f64> {
        std::mem::swap(&mut self.restart, &mut self.fired);
        self.fired.iter_mut().for_each(|f| *f = false);
        if !self.active.iter().any(|&a| a) || t1 <= t0 {
            return None;
        }
        sys.outputs(t1, x);
        for (b, &i) in self.blocks.iter().enumerate() {
            if self.active[b] {
                sys.zero_crossings(b, i, t1, x, &mut self.g1[self.ranges[b].clone()]);
            }
        }
        // The earliest crossing: each later candidate is searched only up
        // to the earliest found so far.
        let mut first: Option<f64> = None;
        for b in 0..self.blocks.len() {
            if !self.active[b] {
                continue;
            }
            for k in self.ranges[b].clone() {
                let mut start = (t0, self.g0[k]);
                let mut s = self.sign[k];
                if self.restart[k] {
                    let t = t0 + (PROBE * tolerance(t1)).min(0.5 * (t1 - t0));
                    let g = self.value(sys, integ, x, b, k, t);
                    if g != 0.0 {
                        (start, s) = ((t, g), g.signum());
                    }
                }
                self.start_sign[k] = 0.0;
                let direction = sys.direction(b, self.blocks[b], k - self.ranges[b].start);
                if s == 0.0 || self.g1[k] * s >= 0.0 || !direction.accepts(s) {
                    continue;
                }
                self.start_sign[k] = s;
                let end = first.unwrap_or(t1);
                let g_end = if end == t1 { self.g1[k] } else { self.value(sys, integ, x, b, k, end) };
                if g_end * s < 0.0 && end > start.0 {
                    first = Some(self.root(sys, integ, x, b, k, s, start, (end, g_end)));
                }
            }
        }
        let t = first?;
        if !x.is_empty() {
            integ.interpolate(sys, t, x, &mut self.x_trial);
            x.copy_from_slice(&self.x_trial);
        }
        // Every candidate that has crossed by t fired there.
        sys.outputs(t, x);
        for (b, &i) in self.blocks.iter().enumerate() {
            if !self.active[b] {
                continue;
            }
            sys.zero_crossings(b, i, t, x, &mut self.g[self.ranges[b].clone()]);
            for k in self.ranges[b].clone() {
                if self.start_sign[k] != 0.0 && self.g[k] * self.start_sign[k] <= 0.0 {
                    self.fired[k] = true;
                    self.last_block = b;
                }
            }
        }
        Some(t)
    }

    /// The functions that fired at the event [`Watch::locate`] found:
    /// (entry in [`Watch::blocks`], model block, function of the block).
    pub fn fired(&self) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        self.blocks
            .iter()
            .zip(&self.ranges)
            .enumerate()
            .flat_map(move |(b, (&i, r))| r.clone().filter(|&k| self.fired[k]).map(move |k| (b, i, k - r.start)))
    }

    /// Function `k` (of block entry `b`) at time `t` inside the last step.
    fn value(
        &mut self,
        sys: &mut impl Crossings,
        integ: &mut Integrator,
        x1: &[f64],
        b: usize,
        k: usize,
        t: f64,
    ) -> f64 {
        let xt: &[f64] = if x1.is_empty() {
            x1
        } else {
            integ.interpolate(sys, t, x1, &mut self.x_trial);
            &self.x_trial
        };
        sys.outputs(t, xt);
        sys.zero_crossings(b, self.blocks[b], t, xt, &mut self.g[self.ranges[b].clone()]);
        self.g[k]
    }

    /// The Illinois method on s·g_k between `lo` and `hi` (times and values
    /// of g_k), where s·g_k(hi) < 0: returns the right end of a bracket no
    /// wider than [`tolerance`], where s·g_k is still strictly negative. A
    /// start that is not strictly on the `s` side (g exactly 0) falls back
    /// to bisection until one is.
    #[allow(clippy::too_many_arguments)]
    fn root(
        &mut self,
        sys: &mut impl Crossings,
        integ: &mut Integrator,
        x1: &[f64],
        b: usize,
        k: usize,
        s: f64,
        lo: (f64, f64),
        hi: (f64, f64),
    ) -> f64 {
        let ((mut lo, g_lo), (mut hi, g_hi)) = (lo, hi);
        let (mut g_lo, mut g_hi) = (s * g_lo, s * g_hi);
        let tol = tolerance(hi);
        let mut last_moved = 0i8;
        for _ in 0..MAX_ITERATIONS {
            if hi - lo <= tol {
                break;
            }
            let secant = if g_lo > 0.0 { hi - g_hi * (hi - lo) / (g_hi - g_lo) } else { f64::NAN };
            let c = if secant > lo && secant < hi { secant } else { 0.5 * (lo + hi) };
            let gc = s * self.value(sys, integ, x1, b, k, c);
            // `hi` stays strictly past zero, so blocks that switch by
            // comparing their input with the same level see the new side.
            if gc >= 0.0 {
                lo = c;
                g_lo = gc;
                if last_moved == 1 {
                    g_hi *= 0.5;
                }
                last_moved = 1;
            } else {
                hi = c;
                g_hi = gc;
                if last_moved == -1 {
                    g_lo *= 0.5;
                }
                last_moved = -1;
            }
        }
        hi
    }

    /// Counts a located event at `t`; past the chattering limit, an error
    /// or (adaptive) the block's detection switched off, returning the
    /// block whose modes must no longer be frozen (entry `b`, model block).
    pub fn count_event(
        &mut self,
        t: f64,
        names: &[crate::compile::BlockMeta],
    ) -> Result<Option<(usize, usize)>, SimError> {
        self.events += 1;
        let scale = t.abs().max(1.0);
        let interval = t - self.last_event;
        self.consecutive = if interval <= CONSECUTIVE * scale { self.consecutive + 1 } else { 0 };
        self.shrinking =
            if interval <= ZENO_SCALE * scale && interval < self.last_interval { self.shrinking + 1 } else { 0 };
        self.last_event = t;
        self.last_interval = interval;
        let what = if self.consecutive >= MAX_CONSECUTIVE_EVENTS {
            format!("{} zero crossings in a row at nearly the same time", self.consecutive)
        } else if self.shrinking >= ZENO_EVENTS {
            format!("{} zero crossings in a row, ever closer (a Zeno point)", self.shrinking)
        } else {
            return Ok(None);
        };
        let b = self.last_block;
        let block = self.blocks[b];
        let name = names[block].name.clone();
        if self.mode != ZeroCrossing::Adaptive {
            return Err(SimError::Chattering { t, block: name, what });
        }
        self.active[b] = false;
        self.consecutive = 0;
        self.shrinking = 0;
        self.warnings
            .push(format!("t = {t}: block `{name}` chattered ({what}); its crossings are ignored from here on"));
        Ok(Some((b, block)))
    }
}
