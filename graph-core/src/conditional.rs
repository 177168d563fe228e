//! Conditionally executed subsystems (Simulink's Enabled, Triggered, and
//! Enabled and Triggered Subsystems, "Conditionally Executed Subsystems
//! Overview" in the Simulink documentation): the subsystem's blocks run
//! inside one block ([`crate::compile`] moves them there) that decides
//! when they run.
//!
//! - **Enabled**: the blocks run while the `enable` input is > 0. The
//!   transitions are zero crossings of that input, located by the solver.
//!   While disabled, continuous states are held (their derivatives are 0),
//!   discrete ones too, and the outputs hold their last value or read 0
//!   (`outputs: reset`); on enabling again the states resume or restart
//!   from their initial values (`states: reset`).
//! - **Triggered**: the blocks run once per edge of the `trigger` input
//!   (rising: from negative to zero or positive, or from zero to positive;
//!   falling the mirror image; either), at the major step of the edge —
//!   located as a zero crossing when the input is continuous. Their
//!   outputs hold between edges; their own sample times give way to the
//!   trigger (memory advances once per edge). No continuous states.
//! - **Both**: an edge runs them only while enabled.

use crate::block::{Block, Crossing, Io, Port};
use crate::composite::{Call, Inner, Member};
use crate::flatten::{Edge, Enable};

/// A conditionally executed subsystem as one block.
#[derive(Clone)]
pub struct Conditional {
    /// The subsystem's blocks; its inputs 0.. are theirs from outside.
    inner: Inner,
    /// The enable mode and the input it reads.
    enable: Option<(Enable, usize)>,
    /// The trigger's edge and the input it reads.
    trigger: Option<(Edge, usize)>,
    /// The run's state: whether enabled; the trigger input at the last
    /// major step (NaN before the first: no edge at t = 0); whether it
    /// fired at this major step; which own crossing was located.
    enabled: bool,
    trigger_before: f64,
    trigger_after: Option<f64>,
    fired: bool,
    enable_located: bool,
    trigger_located: bool,
    /// The outputs as last computed, shown while the blocks do not run.
    held: Vec<f64>,
}

/// Whether `t` is a sample hit `offset + k·period` (the expression
/// [`Conditional::next_event`] steps onto).
fn is_hit(t: f64, (period, offset): (f64, f64)) -> bool {
    let k = ((t - offset) / period).round();
    k >= 0.0 && offset + k * period == t
}

impl Conditional {
    /// `members` in evaluation order; the first `external.len()` inputs go
    /// to them, then come `enable` and `trigger` at the indices given.
    pub fn new(
        members: Vec<Member>,
        external: Vec<Port>,
        outputs: Vec<Port>,
        buffer_len: usize,
        enable: Option<(Enable, usize)>,
        trigger: Option<(Edge, usize)>,
    ) -> Conditional {
        let held = vec![0.0; outputs.iter().map(|p| p.width).sum()];
        Conditional {
            inner: Inner::new(members, external, outputs, buffer_len),
            enable,
            trigger,
            enabled: enable.is_none(),
            trigger_before: f64::NAN,
            trigger_after: None,
            fired: false,
            enable_located: false,
            trigger_located: false,
            held,
        }
    }

    /// Whether the blocks run at every evaluation now (enabled, untriggered).
    fn running(&self) -> bool {
        self.trigger.is_none() && self.enabled
    }

    /// The members' outputs (or, `update`, updates): those due now — a
    /// triggered subsystem's all, an enabled one's of own discrete rate at
    /// their hits only; the outputs are kept to hold.
    fn run(&mut self, call: Call, x: &[f64], update: bool) {
        let triggered = self.trigger.is_some();
        let inner = &mut self.inner;
        for m in &mut inner.members {
            if triggered || m.hits.is_none_or(|h| call.major && is_hit(call.t, h)) {
                let mut mio = call.io((&m.ins, &m.outs), &x[m.states.clone()], &mut inner.buffer);
                if update {
                    m.block.update(&mut mio);
                } else {
                    m.block.output(&mut mio);
                }
            }
        }
        if update {
            return;
        }
        let mut k = 0;
        for slot in &inner.outputs {
            self.held[k..k + slot.width].copy_from_slice(&inner.buffer[slot.offset..slot.offset + slot.width]);
            k += slot.width;
        }
    }

    /// Whether the outputs read 0 now (disabled, with `outputs: reset`).
    fn reset_outputs(&self) -> bool {
        matches!(self.enable, Some((e, _)) if e.reset_outputs && !self.enabled)
    }

    /// Own zero-crossing functions: the enable input's, then the trigger's.
    fn own_crossings(&self) -> usize {
        usize::from(self.enable.is_some()) + usize::from(self.trigger.is_some())
    }
}

impl Block for Conditional {
    fn num_states(&self) -> usize {
        self.inner.n_states
    }

    fn initialize(&mut self, x0: &mut [f64]) {
        self.inner.initialize(x0);
        self.held.iter_mut().for_each(|v| *v = 0.0);
        self.enabled = self.enable.is_none();
        self.trigger_before = f64::NAN;
        self.trigger_after = None;
        self.fired = false;
        self.enable_located = false;
        self.trigger_located = false;
    }

    fn output(&mut self, io: &mut Io) {
        if self.running() {
            self.inner.copy_inputs(io);
            self.run(Call::of(io), io.x, false);
        }
        let zero = self.reset_outputs();
        let mut k = 0;
        for port in 0..self.inner.outputs.len() {
            let out = io.output(port);
            let n = out.len();
            if zero {
                out.iter_mut().for_each(|v| *v = 0.0);
            } else {
                out.copy_from_slice(&self.held[k..k + n]);
            }
            k += n;
        }
    }

    /// Switches enabled and disabled, and fires on the trigger's edges.
    fn major_step(&mut self, io: &Io, x: &mut [f64]) -> bool {
        let mut changed = false;
        if let Some((mode, input)) = self.enable {
            let now = if std::mem::take(&mut self.enable_located) { !self.enabled } else { io.u(input) > 0.0 };
            if now != self.enabled {
                if now && mode.reset_states {
                    for m in &mut self.inner.members {
                        m.block.initialize(&mut x[m.states.clone()]);
                    }
                }
                self.enabled = now;
                changed = true;
            }
        }
        if self.running() {
            changed |= self.inner.major_step(Call::of(io), x);
        }
        if let Some((edge, input)) = self.trigger
            && !self.fired
        {
            let now = io.u(input);
            let located = std::mem::take(&mut self.trigger_located);
            if located {
                // At the crossing the input is within ulps of 0, on either
                // side: the side it leaves to is the edge's.
                let rising = match edge {
                    Edge::Rising => true,
                    Edge::Falling => false,
                    Edge::Either => self.trigger_before.is_nan() || self.trigger_before <= 0.0,
                };
                self.trigger_after = Some(if rising { f64::MIN_POSITIVE } else { -f64::MIN_POSITIVE });
            }
            if (located || edge.between(self.trigger_before, now)) && self.enabled {
                self.inner.copy_inputs(io);
                self.run(Call::of(io), &[], false);
                self.fired = true;
                changed = true;
            }
        }
        changed
    }

    fn update(&mut self, io: &mut Io) {
        let call = Call::of(io);
        if let Some((_, input)) = self.trigger {
            if std::mem::take(&mut self.fired) {
                self.run(call, &[], true);
            }
            self.trigger_before = self.trigger_after.take().unwrap_or_else(|| io.u(input));
        } else if self.enabled {
            self.run(call, io.x, true);
        }
    }

    /// Held while disabled: the states stand still.
    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        if self.running() {
            self.inner.derivatives(Call::of(io), io.x, dx);
        } else {
            dx.iter_mut().for_each(|d| *d = 0.0);
        }
    }

    fn clamp_states(&self, x: &mut [f64]) -> bool {
        self.inner.clamp_states(x)
    }

    /// The members' own events while they run continuously, and the sample
    /// hits of those that keep a discrete rate.
    fn next_event(&self, t: f64) -> f64 {
        if self.trigger.is_some() {
            return f64::INFINITY;
        }
        let hits = self.inner.members.iter().filter_map(|m| m.hits).map(|(period, offset)| {
            let k = ((t - offset) / period).floor().max(0.0);
            [k - 1.0, k, k + 1.0, k + 2.0]
                .into_iter()
                .filter(|&k| k >= 0.0)
                .map(|k| offset + k * period)
                .find(|&e| e > t)
                .unwrap_or(f64::INFINITY)
        });
        hits.fold(self.inner.next_event(t), f64::min)
    }

    fn num_zero_crossings(&self) -> usize {
        self.inner.n_crossings + self.own_crossings()
    }

    fn needs_major_step(&self) -> bool {
        true
    }

    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        let own = self.inner.n_crossings;
        if self.running() {
            self.inner.zero_crossings(Call::of(io), io.x, g);
        } else {
            // Not running: no member's event.
            g[..own].iter_mut().for_each(|v| *v = 1.0);
        }
        let mut k = own;
        if let Some((_, input)) = self.enable {
            g[k] = io.u(input);
            k += 1;
        }
        if let Some((_, input)) = self.trigger {
            g[k] = io.u(input);
        }
    }

    fn crossing_direction(&self, k: usize) -> Crossing {
        if k < self.inner.n_crossings {
            return if self.running() { self.inner.crossing_direction(k) } else { Crossing::Ignore };
        }
        let own = k - self.inner.n_crossings;
        match (own, self.enable.is_some(), self.trigger) {
            (0, true, _) => Crossing::Either,
            (_, _, Some((Edge::Rising, _))) => Crossing::Rising,
            (_, _, Some((Edge::Falling, _))) => Crossing::Falling,
            _ => Crossing::Either,
        }
    }

    fn crossing_located(&mut self, k: usize) {
        if k < self.inner.n_crossings {
            self.inner.crossing_located(k);
            return;
        }
        match (k - self.inner.n_crossings, self.enable.is_some()) {
            (0, true) => self.enable_located = true,
            _ => self.trigger_located = true,
        }
    }

    fn not_linearizable(&self) -> Option<&'static str> {
        Some("a conditionally executed subsystem has no linear model in ctlgraph yet")
    }

    fn diagnose(&self) -> Option<String> {
        self.inner.diagnose()
    }

    fn build_report(&self) -> Option<String> {
        self.inner.build_report()
    }
}
