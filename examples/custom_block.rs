//! A block of your own: a relay with hysteresis, registered beside the
//! library and used from a graph file.
//!
//!     cargo run --example custom_block
//!
//! A block declares its ports and rate in an `Interface` and implements
//! `Block`: `output` computes outputs from inputs and state, `update` moves
//! discrete or major-step memory forward. Here the relay's memory (on/off)
//! changes only at major steps, so the solver's minor steps see it fixed.
//! A block derives `Clone`, so that a snapshot of a run copies its memory.

use ctlgraph::core::ParamDefault::Number;
use ctlgraph::core::registry::{BlockType, Built, ParamDoc, PortDoc};
use ctlgraph::core::{Block, Diagnostic, Interface, Io, Params, SampleTime, Width};

/// Switches on above `on`, off below `off`; output `high` or `low`.
#[derive(Clone)]
struct Relay {
    on: f64,
    off: f64,
    high: f64,
    low: f64,
    state: bool,
}

impl Block for Relay {
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.state = false;
    }
    fn output(&mut self, io: &mut Io) {
        io.set(0, if self.state { self.high } else { self.low });
    }
    fn update(&mut self, io: &mut Io) {
        let u = io.u(0);
        if u >= self.on {
            self.state = true;
        } else if u <= self.off {
            self.state = false;
        }
    }
}

fn build_relay(p: &mut Params) -> Result<Built, Diagnostic> {
    // Defaults come from the parameter table below (written once).
    let on = p.number("on")?;
    let off = p.number_where("off", None, |v| v <= on, "at most `on`")?;
    let (high, low) = (p.number("high")?, p.number("low")?);
    // Output depends only on the stored state: no direct feedthrough, so a
    // relay closes a loop without an algebraic loop.
    let iface = Interface::new(SampleTime::Continuous).input("u", Width::Fixed(1), false).output("y", Width::Fixed(1));
    Ok(Built::new(Relay { on, off, high, low, state: false }, iface))
}

const RELAY: BlockType = BlockType {
    name: "relay",
    category: "nonlinear",
    summary: "On/off relay with hysteresis.",
    doc: "y = high after u >= on, y = low after u <= off; state changes at major steps.",
    inputs: &[PortDoc { name: "u", doc: "scalar" }],
    outputs: &[PortDoc { name: "y", doc: "scalar" }],
    params: &[
        ParamDoc::new("on", Number(0.1), "switch-on threshold"),
        ParamDoc::new("off", Number(-0.1), "switch-off threshold, <= on"),
        ParamDoc::new("high", Number(1.0), "output when on"),
        ParamDoc::new("low", Number(-1.0), "output when off"),
    ],
    build: build_relay,
};

const GRAPH: &str = "
name: Relay temperature control
simulation: { stop: 20.0, solver: { method: rk4, step: 1.0e-3 } }
blocks:
  setpoint: { type: constant, value: 1.0 }
  err:      { type: sum, signs: \"+-\" }
  heater:   { type: relay, on: 0.05, off: -0.05, high: 2.0, low: 0.0 }
  room:     { type: transfer_function, num: [1], den: [3, 1] }
wires: [setpoint -> err.u1, room -> err.u2, err -> heater, heater -> room]
record: [y: room, u: heater]
";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut registry = ctlgraph::registry();
    registry.register(RELAY);
    let flat = ctlgraph::core::load_str(GRAPH, "relay.yaml".into(), &[])?;
    let model = ctlgraph::core::compile(&flat, &registry)?;
    let trace = ctlgraph::simulate(model, None)?;
    let y = trace.column("y").ok_or("no y")?;
    let late: Vec<f64> = trace.t().iter().zip(y).filter(|(t, _)| **t > 10.0).map(|(_, v)| *v).collect();
    let (lo, hi) = late.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    println!("limit cycle after 10 s: y in [{lo:.3}, {hi:.3}] around the set-point 1.0");
    Ok(())
}
