//! Switching blocks driven by zero crossings: the hysteretic `relay` and
//! `hit_crossing`, and [`Trigger`], the edge logic they share with the
//! integrator's reset.

use crate::{SAMPLE_TIME_INHERITED, U_SCALAR, Y_SCALAR, table::*};
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::registry::{BlockType, Built};
use ctlgraph_core::{Block, Crossing, Diagnostic, Interface, Io, Params, Width};

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "relay",
        category: "nonlinear",
        summary: "Two-level switch with hysteresis (Simulink's Relay).",
        doc: "y = on_value while on, off_value while off. Off → on when u >= on_threshold; on → off when \
              u <= off_threshold; otherwise the state holds (hysteresis band [off_threshold, on_threshold]). \
              The state switches only at major steps; with zero-crossing detection the step ends exactly \
              where u reaches the threshold that applies (u − on_threshold rising while off, u − \
              off_threshold falling while on), so a thermostat switches at its thresholds, not a step \
              later. Starts off unless `initial: on`.\n\
              Bounds: y is on_value or off_value.",
        inputs: U_SCALAR,
        outputs: Y_SCALAR,
        params: &[
            param("on_threshold", Number(0.5), "switch-on point"),
            param("off_threshold", Number(-0.5), "switch-off point, <= on_threshold"),
            param("on_value", Number(1.0), "output while on"),
            param("off_value", Number(0.0), "output while off"),
            param("initial", Word("off"), "off or on").options(&["off", "on"]),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_relay,
    },
    BlockType {
        name: "hit_crossing",
        category: "nonlinear",
        summary: "Outputs 1 at the step where its input crosses a level (Simulink's Hit Crossing).",
        doc: "y = 1 at the major step where u has crossed `level` in the given direction since the last \
              major step, 0 elsewhere. With zero-crossing detection that step is the crossing itself, \
              located to a few ulps of t; the block also forces the step to end there, so a crossing is \
              hit exactly even when nothing else depends on it. Directions as the integrator's reset: \
              rising (from < level to >= level, or from level to above), falling, either.",
        inputs: U_SCALAR,
        outputs: Y_SCALAR,
        params: &[
            param("level", Number(0.0), "the level watched"),
            param("direction", Word("either"), "rising, falling or either").options(&["either", "rising", "falling"]),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_hit_crossing,
    },
];

/// What makes a signal fire: an edge through zero, or a nonzero level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Trigger {
    /// From < 0 to >= 0, or from 0 to > 0.
    Rising,
    /// From > 0 to <= 0, or from 0 to < 0.
    Falling,
    Either,
    /// While nonzero.
    Level,
}

impl Trigger {
    /// Whether the signal fires going from `before` (NaN: no history) to `now`.
    pub fn fired(self, before: f64, now: f64) -> bool {
        let rising = (before < 0.0 && now >= 0.0) || (before == 0.0 && now > 0.0);
        let falling = (before > 0.0 && now <= 0.0) || (before == 0.0 && now < 0.0);
        match self {
            Trigger::Rising => rising,
            Trigger::Falling => falling,
            Trigger::Either => rising || falling,
            Trigger::Level => now != 0.0,
        }
    }

    /// [`Trigger::fired`] in C, over the C expressions `before`, `now`
    /// and the literal `zero` (the same comparisons: NaN fires nothing).
    pub fn c_fired(self, before: &str, now: &str, zero: &str) -> String {
        let rising = format!("({before} < {zero} && {now} >= {zero}) || ({before} == {zero} && {now} > {zero})");
        let falling = format!("({before} > {zero} && {now} <= {zero}) || ({before} == {zero} && {now} < {zero})");
        match self {
            Trigger::Rising => rising,
            Trigger::Falling => falling,
            Trigger::Either => format!("{rising} || {falling}"),
            Trigger::Level => format!("{now} != {zero}"),
        }
    }

    /// The `reset` parameter of a block that integrates (none, rising,
    /// falling, either or level): what resets it, if anything.
    pub fn reset_of(p: &mut Params) -> Result<Option<Trigger>, Diagnostic> {
        Ok(match p.choice("reset", &["none", "rising", "falling", "either", "level"])? {
            "rising" => Some(Trigger::Rising),
            "falling" => Some(Trigger::Falling),
            "either" => Some(Trigger::Either),
            "level" => Some(Trigger::Level),
            _ => None,
        })
    }

    /// The zero-crossing direction that locates it.
    pub fn direction(self) -> Crossing {
        match self {
            Trigger::Rising => Crossing::Rising,
            Trigger::Falling => Crossing::Falling,
            Trigger::Either | Trigger::Level => Crossing::Either,
        }
    }
}

/// Relay with hysteresis; see the type's doc.
#[derive(Clone)]
pub struct Relay {
    pub on_threshold: f64,
    pub off_threshold: f64,
    pub on_value: f64,
    pub off_value: f64,
    pub initial_on: bool,
    /// The state committed at the last major step.
    on: bool,
    /// The state this major step's output used, committed by `update`.
    next: bool,
}

impl Relay {
    pub fn new(on_threshold: f64, off_threshold: f64, on_value: f64, off_value: f64, initial_on: bool) -> Self {
        Relay { on_threshold, off_threshold, on_value, off_value, initial_on, on: initial_on, next: initial_on }
    }

    fn switched(&self, u: f64) -> bool {
        if self.on { u > self.off_threshold } else { u >= self.on_threshold }
    }
}

impl Block for Relay {
    rust_type!(Relay);
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.on = self.initial_on;
        self.next = self.initial_on;
    }

    fn output(&mut self, io: &mut Io) {
        let on = if io.may_switch() { self.switched(io.u(0)) } else { self.on };
        if io.is_major() {
            self.next = on;
        }
        io.set(0, if on { self.on_value } else { self.off_value });
    }

    fn update(&mut self, _io: &mut Io) {
        self.on = self.next;
    }

    /// At every sample (a major step) the state may switch.
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation("on = was on ? u > off_threshold : u >= on_threshold;  y = on ? on_value : off_value");
        let on = c.counter("on", u32::from(self.initial_on));
        let next = c.counter("next", u32::from(self.initial_on));
        let (u, y) = (c.u(0).to_string(), c.y(0).to_string());
        c.output(format!(
            "{next} = {on} ? ({u} > {}) : ({u} >= {});\n{y} = {next} ? {} : {};",
            c.num(self.off_threshold),
            c.num(self.on_threshold),
            c.num(self.on_value),
            c.num(self.off_value)
        ));
        c.update(format!("{on} = {next};"));
        Ok(())
    }

    fn num_zero_crossings(&self) -> usize {
        2
    }

    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        g[0] = io.u(0) - self.on_threshold;
        g[1] = io.u(0) - self.off_threshold;
    }

    fn crossing_direction(&self, k: usize) -> Crossing {
        match (k, self.on) {
            (0, false) => Crossing::Rising,
            (1, true) => Crossing::Falling,
            _ => Crossing::Ignore,
        }
    }
}

fn build_relay(p: &mut Params) -> Result<Built, Diagnostic> {
    let (off, on) = crate::nonlinear::limits(p, "off_threshold", "on_threshold")?;
    let on_value = p.number("on_value")?;
    let off_value = p.number("off_value")?;
    let initial_on = p.choice("initial", &["off", "on"])? == "on";
    let iface = Interface::new(p.sample_time()?)
        .piecewise_constant()
        .input("u", Width::Fixed(1), true)
        .output("y", Width::Fixed(1));
    Ok(Built::new(Relay::new(on, off, on_value, off_value, initial_on), iface))
}

/// Hit crossing; see the type's doc.
#[derive(Clone)]
pub struct HitCrossing {
    level: f64,
    trigger: Trigger,
    /// u − level at the last major step (NaN before the first).
    last: f64,
    /// This major step's u − level, committed by `update`.
    current: f64,
    /// The output of the last major step, held in minor steps.
    hit: f64,
    /// The simulator located the crossing: this major step is the hit.
    located: bool,
}

impl Block for HitCrossing {
    rust_type!(HitCrossing);
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.last = f64::NAN;
        self.current = f64::NAN;
        self.hit = 0.0;
        self.located = false;
    }

    fn output(&mut self, io: &mut Io) {
        if io.is_major() {
            self.current = io.u(0) - self.level;
            let hit = self.located || self.trigger.fired(self.last, self.current);
            self.hit = if hit { 1.0 } else { 0.0 };
        }
        io.set(0, self.hit);
    }

    fn update(&mut self, _io: &mut Io) {
        // A located crossing leaves u − level within ulps of zero, on either
        // side: no edge may be read from that sample.
        self.last = if self.located { f64::NAN } else { self.current };
        self.located = false;
    }

    fn num_zero_crossings(&self) -> usize {
        1
    }

    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        g[0] = io.u(0) - self.level;
    }

    fn crossing_located(&mut self, _k: usize) {
        self.located = true;
    }

    fn crossing_direction(&self, _k: usize) -> Crossing {
        self.trigger.direction()
    }
}

fn build_hit_crossing(p: &mut Params) -> Result<Built, Diagnostic> {
    let level = p.number("level")?;
    let trigger = match p.choice("direction", &["either", "rising", "falling"])? {
        "rising" => Trigger::Rising,
        "falling" => Trigger::Falling,
        _ => Trigger::Either,
    };
    let iface = Interface::new(p.sample_time()?)
        .piecewise_constant()
        .input("u", Width::Fixed(1), true)
        .output("y", Width::Fixed(1));
    let block = HitCrossing { level, trigger, last: f64::NAN, current: f64::NAN, hit: 0.0, located: false };
    Ok(Built::new(block, iface))
}
