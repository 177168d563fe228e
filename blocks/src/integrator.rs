//! The integrator: Simulink's Integrator block with limits (saturation
//! modes), reset on an edge or level of a reset input, an external initial
//! condition and a state port.

use crate::continuous::initial_vector;
use crate::events::Trigger;
use crate::table::*;
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Crossing, Diagnostic, Interface, Io, Params, SampleTime, Width};

pub const TYPES: &[BlockType] = &[BlockType {
    name: "integrator",
    category: "dynamics",
    summary: "y = ∫u dt, with limits, resets, an external initial condition and a state port.",
    doc: "x' = u, y = x, elementwise. No direct feedthrough from any input: it closes loops legally.\n\
          Limits (Simulink's limited integrator): x stays in [lower, upper]. The block has three modes per \
          element — free, at the lower limit, at the upper limit; on a limit x' = 0 while u pushes outward. \
          With zero-crossing detection the step ends exactly where x reaches a limit (x − limit crosses 0) \
          or where u turns back inward (u crosses 0), so the corner is located, not stepped over; without \
          it, the mode is chosen at every evaluation and x is projected back after each step.\n\
          Reset (`reset: rising|falling|either|level`, adds the scalar `reset` input): on a rising edge \
          (from < 0 to >= 0, or from 0 to > 0), a falling edge (mirror image), either, or — `level` — while \
          the input is nonzero, x is set to the initial condition: the `initial` parameter, or with \
          `initial_source: external` the `initial` input (also read at t = 0). Edges are located by zero \
          crossing on the reset input. Reset and initial inputs are read after every block's output at a \
          major step, then outputs are computed again, so y already shows the reset value at the reset \
          time.\n\
          `state_port: true` adds the `state` output, equal to x. Simulink needs it to feed x back to the \
          reset or initial input without an algebraic loop; here y would do too, since those inputs have no \
          feedthrough, but the port keeps translated diagrams one-to-one. A bouncing ball is four blocks: \
          v' = −g with reset: falling on x.state and initial: −e·v.state, x' = v.\n\
          Bounds: with limits, y stays in [lower, upper] for any input; without, \
          |y(t) − x(0)| <= t·sup|u| between resets (not BIBO stable).",
    inputs: &[
        PortDoc { name: "u", doc: "any width" },
        PortDoc { name: "reset", doc: "scalar; with `reset` other than none" },
        PortDoc { name: "initial", doc: "width of u; with `initial_source: external`" },
    ],
    outputs: &[
        PortDoc { name: "y", doc: "same width as u" },
        PortDoc { name: "state", doc: "x; with `state_port: true`" },
    ],
    params: &[
        param("initial", Number(0.0), "x(0) and the reset value: a number or one per element").kind(ParamKind::Numbers),
        param(
            "initial_source",
            Word("internal"),
            "internal (the `initial` parameter) or external (the `initial` input)",
        )
        .options(&["internal", "external"]),
        param("lower", Number(f64::NEG_INFINITY), "lower limit of x"),
        param("upper", Number(f64::INFINITY), "upper limit of x"),
        param("reset", Word("none"), "none, rising, falling, either or level")
            .options(&["none", "rising", "falling", "either", "level"]),
        param("state_port", Flag(false), "true adds the `state` output"),
    ],
    build: build_integrator,
}];

/// Per element: free, or held on a limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Free,
    AtLower,
    AtUpper,
}

/// Elementwise integrator; see the type's doc.
#[derive(Clone)]
pub struct Integrator {
    initial: Vec<f64>,
    x0: Vec<f64>,
    lower: f64,
    upper: f64,
    limited: bool,
    modes: Vec<Mode>,
    reset: Option<Trigger>,
    /// Input port of the reset signal and of the external initial condition.
    reset_port: usize,
    initial_port: Option<usize>,
    /// The reset input at the last major step (NaN before the first).
    last_reset: f64,
    /// The simulator located the reset input's crossing: reset now.
    located: bool,
    /// Whether the first major step (which reads an external x(0)) is done.
    started: bool,
}

impl Integrator {
    /// The mode element `k` takes at a major step, from its state and input.
    fn mode_for(&self, x: f64, u: f64) -> Mode {
        if x >= self.upper && u > 0.0 {
            Mode::AtUpper
        } else if x <= self.lower && u < 0.0 {
            Mode::AtLower
        } else {
            Mode::Free
        }
    }

    /// Whether the reset input holds or fires a reset now: its located
    /// crossing, or (without detection) its change since the last major step.
    fn resetting(&self, now: f64) -> bool {
        self.located || self.reset.is_some_and(|trigger| trigger.fired(self.last_reset, now))
    }

    /// Index of the reset input's zero-crossing function.
    fn reset_function(&self) -> usize {
        if self.limited { 2 * self.x0.len() } else { 0 }
    }
}

impl Block for Integrator {
    rust_type!(Integrator);
    fn updates(&self) -> bool {
        false
    }
    fn set_width(&mut self, width: usize) -> Result<(), String> {
        self.x0 = initial_vector(&self.initial, width)?;
        self.modes = vec![Mode::Free; width];
        Ok(())
    }

    fn num_states(&self) -> usize {
        self.x0.len()
    }

    fn initialize(&mut self, x0: &mut [f64]) {
        x0.copy_from_slice(&self.x0);
        self.modes.iter_mut().for_each(|m| *m = Mode::Free);
        self.last_reset = f64::NAN;
        self.located = false;
        self.started = false;
    }

    fn output(&mut self, io: &mut Io) {
        let x = io.x;
        io.set_all(0, x);
        if io.num_outputs() > 1 {
            io.set_all(1, x);
        }
    }

    fn is_plain_integrator(&self) -> bool {
        !self.limited && self.reset.is_none() && self.initial_port.is_none()
    }

    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        let held = self.reset == Some(Trigger::Level) && io.u(self.reset_port) != 0.0;
        for (k, d) in dx.iter_mut().enumerate() {
            let (x, u) = (io.x[k], io.u_at(0, k));
            let mode = if !self.limited || !io.may_switch() { self.modes[k] } else { self.mode_for(x, u) };
            *d = if held || mode != Mode::Free { 0.0 } else { u };
        }
    }

    fn clamp_states(&self, x: &mut [f64]) -> bool {
        let mut moved = false;
        for v in x {
            let c = v.clamp(self.lower, self.upper);
            moved |= c != *v;
            *v = c;
        }
        moved
    }

    fn num_zero_crossings(&self) -> usize {
        let limits = if self.limited { 2 * self.x0.len() } else { 0 };
        limits + usize::from(self.reset.is_some())
    }

    fn needs_major_step(&self) -> bool {
        self.limited || self.reset.is_some() || self.initial_port.is_some()
    }

    /// Per element: [upper, lower] functions (x − limit when free, u when
    /// held), then the reset input.
    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        let n = if self.limited { self.x0.len() } else { 0 };
        for k in 0..n {
            let (x, u) = (io.x[k], io.u_at(0, k));
            let held = self.modes[k] != Mode::Free;
            g[2 * k] = if held { u } else { x - self.upper };
            g[2 * k + 1] = if held { u } else { x - self.lower };
        }
        if self.reset.is_some() {
            g[2 * n] = io.u(self.reset_port);
        }
    }

    fn crossing_direction(&self, k: usize) -> Crossing {
        let n = if self.limited { self.x0.len() } else { 0 };
        if k < 2 * n {
            let upper = k.is_multiple_of(2);
            return match (self.modes[k / 2], upper) {
                (Mode::Free, true) => Crossing::Rising,
                (Mode::Free, false) => Crossing::Falling,
                (Mode::AtUpper, true) => Crossing::Falling,
                (Mode::AtLower, false) => Crossing::Rising,
                _ => Crossing::Ignore,
            };
        }
        match (k == 2 * n, self.reset) {
            (true, Some(trigger)) => trigger.direction(),
            _ => Crossing::Ignore,
        }
    }

    fn crossing_located(&mut self, k: usize) {
        self.located |= self.reset.is_some() && k == self.reset_function();
    }

    fn major_step(&mut self, io: &Io, x: &mut [f64]) -> bool {
        let mut changed = false;
        let external = self.initial_port.map(|p| io.input(p));
        if !self.started {
            self.started = true;
            if let Some(init) = external {
                for (k, xk) in x.iter_mut().enumerate() {
                    *xk = init[if init.len() == 1 { 0 } else { k }];
                }
                changed = true;
            }
        }
        if self.reset.is_some() {
            let now = io.u(self.reset_port);
            if self.resetting(now) {
                for (k, xk) in x.iter_mut().enumerate() {
                    *xk = match external {
                        Some(init) => init[if init.len() == 1 { 0 } else { k }],
                        None => self.x0[k],
                    };
                }
                changed = true;
            }
            // A located crossing leaves the input within ulps of zero, on
            // either side: no edge may be read from that sample.
            self.last_reset = if self.located { f64::NAN } else { now };
            self.located = false;
        }
        if self.limited {
            changed |= self.clamp_states(x);
            for (k, &xk) in x.iter().enumerate() {
                self.modes[k] = self.mode_for(xk, io.u_at(0, k));
            }
        }
        changed
    }
}

fn build_integrator(p: &mut Params) -> Result<Built, Diagnostic> {
    let initial = p.vector("initial")?;
    let (lower, upper) = crate::nonlinear::limits(p, "lower", "upper")?;
    if let Some(v) = initial.iter().find(|v| !(lower..=upper).contains(*v)) {
        return Err(p.error("initial", format!("{v} is outside [{lower}, {upper}]")));
    }
    let reset = Trigger::reset_of(p)?;
    let external = p.choice("initial_source", &["internal", "external"])? == "external";
    let state_port = p.flag("state_port")?;
    let mut iface = Interface::new(SampleTime::Continuous).input("u", Width::Common, false).output("y", Width::Common);
    let reset_port = iface.inputs.len();
    if reset.is_some() {
        iface = iface.input("reset", Width::Fixed(1), false);
    }
    let initial_port = external.then_some(iface.inputs.len());
    if external {
        iface = iface.input("initial", Width::Common, false);
    }
    if state_port {
        iface = iface.output("state", Width::Common);
    }
    let block = Integrator {
        initial,
        x0: Vec::new(),
        lower,
        upper,
        limited: lower > f64::NEG_INFINITY || upper < f64::INFINITY,
        modes: Vec::new(),
        reset,
        reset_port,
        initial_port,
        last_reset: f64::NAN,
        located: false,
        started: false,
    };
    Ok(Built::new(block, iface))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limited(n: usize, reset: Option<Trigger>) -> Integrator {
        Integrator {
            initial: vec![0.0; n],
            x0: vec![0.0; n],
            lower: -1.0,
            upper: 2.0,
            limited: true,
            modes: vec![Mode::Free; n],
            reset,
            reset_port: 1,
            initial_port: None,
            last_reset: f64::NAN,
            located: false,
            started: false,
        }
    }

    #[test]
    fn an_element_holds_on_a_limit_only_while_pushed_into_it() {
        let b = limited(1, None);
        assert_eq!(b.mode_for(2.0, 0.5), Mode::AtUpper);
        assert_eq!(b.mode_for(2.5, 0.5), Mode::AtUpper);
        assert_eq!(b.mode_for(2.0, 0.0), Mode::Free);
        assert_eq!(b.mode_for(2.0, -0.5), Mode::Free);
        assert_eq!(b.mode_for(1.9, 0.5), Mode::Free);
        assert_eq!(b.mode_for(-1.0, -0.5), Mode::AtLower);
        assert_eq!(b.mode_for(-1.5, -0.5), Mode::AtLower);
        assert_eq!(b.mode_for(-1.0, 0.0), Mode::Free);
        assert_eq!(b.mode_for(-1.0, 0.5), Mode::Free);
        assert_eq!(b.mode_for(-0.9, -0.5), Mode::Free);
    }

    #[test]
    fn the_reset_crossing_follows_the_limit_crossings() {
        // Two crossing functions per limited element come first.
        assert_eq!(limited(3, Some(Trigger::Rising)).reset_function(), 6);
        let mut free = limited(3, Some(Trigger::Rising));
        free.limited = false;
        assert_eq!(free.reset_function(), 0);
        // A located crossing resets whatever the trigger; without one, the
        // trigger judges the change since the last major step.
        let mut b = limited(1, None);
        assert!(!b.resetting(1.0));
        b.located = true;
        assert!(b.resetting(1.0));
        let mut rising = limited(1, Some(Trigger::Rising));
        rising.last_reset = -1.0;
        assert!(rising.resetting(1.0) && !rising.resetting(-2.0));
    }
}
