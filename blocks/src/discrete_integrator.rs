//! The discrete-time integrator (Simulink's Discrete-Time Integrator):
//! forward Euler, backward Euler or trapezoidal, with limits and an
//! external reset.

use crate::events::Trigger;
use crate::{SAMPLE_TIME_REQUIRED, table::*};
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};

pub const TYPES: &[BlockType] = &[BlockType {
    name: "discrete_integrator",
    category: "discrete",
    summary: "Discrete-time integrator: forward or backward Euler, or trapezoidal; limits; reset.",
    doc: "With K the gain, T the sample time and x the state (x(0) = initial), as Simulink's \
          Discrete-Time Integrator:\n\
          \x20 forward_euler:  y(k) = x(k),                x(k+1) = x(k) + K·T·u(k)   (no direct feedthrough)\n\
          \x20 backward_euler: y(k) = x(k) + K·T·u(k),     x(k+1) = y(k)\n\
          \x20 trapezoidal:    y(k) = x(k) + K·T/2·u(k),   x(k+1) = y(k) + K·T/2·u(k)\n\
          With limits, y and x are held in [lower, upper]. With `reset` (rising, falling, either, \
          level) an input `reset` sets x(k) = initial at the sample where it fires (an edge since the \
          last sample, or a nonzero level), before the output.\n\
          Bounds: lower <= y <= upper.",
    inputs: &[
        PortDoc { name: "u", doc: "scalar" },
        PortDoc { name: "reset", doc: "scalar; with `reset` other than none" },
    ],
    outputs: &[PortDoc { name: "y", doc: "scalar" }],
    params: &[
        param("method", Word("forward_euler"), "forward_euler | backward_euler | trapezoidal").options(&[
            "forward_euler",
            "backward_euler",
            "trapezoidal",
        ]),
        param("gain", Number(1.0), "K"),
        param("initial", Number(0.0), "x(0), and the state a reset sets"),
        param("lower", Number(f64::NEG_INFINITY), "lower limit of y and x"),
        param("upper", Number(f64::INFINITY), "upper limit of y and x"),
        param("reset", Word("none"), "none, rising, falling, either or level")
            .options(&["none", "rising", "falling", "either", "level"]),
        SAMPLE_TIME_REQUIRED,
    ],
    build: build_discrete_integrator,
}];

#[derive(Clone, Copy, Debug, PartialEq)]
enum Method {
    Forward,
    Backward,
    Trapezoidal,
}

#[derive(Clone)]
pub struct DiscreteIntegrator {
    method: Method,
    /// K·T (forward and backward Euler) or K·T/2 (trapezoidal).
    step: f64,
    initial: f64,
    lower: f64,
    upper: f64,
    reset: Option<Trigger>,
    x: f64,
    /// The reset input at the last sample (NaN before the first).
    reset_before: f64,
}

impl DiscreteIntegrator {
    /// The state this sample starts from: `initial` where the reset fires.
    fn start(&self, io: &Io) -> f64 {
        match self.reset {
            Some(trigger) if trigger.fired(self.reset_before, io.u(1)) => self.initial,
            _ => self.x,
        }
    }

    fn output_from(&self, x: f64, u: f64) -> f64 {
        let y = match self.method {
            Method::Forward => x,
            Method::Backward | Method::Trapezoidal => x + self.step * u,
        };
        y.clamp(self.lower, self.upper)
    }
}

impl Block for DiscreteIntegrator {
    rust_type!(DiscreteIntegrator);
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.x = self.initial.clamp(self.lower, self.upper);
        self.reset_before = f64::NAN;
    }
    fn output(&mut self, io: &mut Io) {
        let y = self.output_from(self.start(io), io.u(0));
        io.set(0, y);
    }
    fn update(&mut self, io: &mut Io) {
        let (x, u) = (self.start(io), io.u(0));
        let next = match self.method {
            Method::Forward => x + self.step * u,
            Method::Backward => self.output_from(x, u),
            Method::Trapezoidal => self.output_from(x, u) + self.step * u,
        };
        self.x = next.clamp(self.lower, self.upper);
        if self.reset.is_some() {
            self.reset_before = io.u(1);
        }
    }
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation(match self.method {
            Method::Forward => "y = x;  x += K T u",
            Method::Backward => "y = x + K T u;  x = y",
            Method::Trapezoidal => "y = x + K T/2 u;  x = y + K T/2 u",
        });
        let x = c.state("x", &[self.initial.clamp(self.lower, self.upper)]);
        let real = c.real();
        // Where the reset fires: the state starts from `initial`.
        let reset = match self.reset {
            None => None,
            Some(trigger) => {
                let before = c.state("reset_before", &[f64::NAN]);
                let r = c.u(1).to_string();
                Some((trigger.c_fired(&before, &r, &c.num(0.0)), format!("{before} = {r};")))
            }
        };
        let start = match &reset {
            Some((fires, _)) => format!("({fires}) ? {} : {x}", c.num(self.initial)),
            None => x.clone(),
        };
        let limited = |c: &mut CBlock, v: String| {
            if self.lower == f64::NEG_INFINITY && self.upper == f64::INFINITY {
                v
            } else {
                format!("{}({v}, {}, {})", c.clamp(), c.num(self.lower), c.num(self.upper))
            }
        };
        let (u, step) = (c.u(0).to_string(), c.num(self.step));
        let y = match self.method {
            Method::Forward => limited(c, "x0".into()),
            Method::Backward | Method::Trapezoidal => limited(c, format!("x0 + {step} * {u}")),
        };
        let next = match self.method {
            Method::Forward => format!("x0 + {step} * {u}"),
            Method::Backward => "y_".to_string(),
            Method::Trapezoidal => format!("y_ + {step} * {u}"),
        };
        let next = limited(c, next);
        c.output(format!("{real} x0 = {start};\n{} = {y};", c.y(0)));
        c.update(format!("{real} x0 = {start};\n{real} y_ = {y};\n(void)y_;\n{x} = {next};"));
        // The reset input remembered after the state has used it.
        if let Some((_, remember)) = reset {
            c.update(remember);
        }
        Ok(())
    }
}

fn build_discrete_integrator(p: &mut Params) -> Result<Built, Diagnostic> {
    let method = match p.choice("method", &["forward_euler", "backward_euler", "trapezoidal"])? {
        "backward_euler" => Method::Backward,
        "trapezoidal" => Method::Trapezoidal,
        _ => Method::Forward,
    };
    let gain = p.number_where("gain", None, f64::is_finite, "a finite gain")?;
    let initial = p.number_where("initial", None, f64::is_finite, "a finite number")?;
    let (lower, upper) = crate::nonlinear::limits(p, "lower", "upper")?;
    let reset = Trigger::reset_of(p)?;
    let (st, period, _) = p.discrete_clock()?;
    let step = if method == Method::Trapezoidal { gain * period / 2.0 } else { gain * period };
    let mut iface = Interface::new(st).input("u", Width::Fixed(1), method != Method::Forward);
    if reset.is_some() {
        iface = iface.input("reset", Width::Fixed(1), true);
    }
    let block = DiscreteIntegrator { method, step, initial, lower, upper, reset, x: initial, reset_before: f64::NAN };
    Ok(Built::new(block, iface.output("y", Width::Fixed(1))))
}
