//! Backlash: play between a drive and what it drives (Simulink's Backlash
//! block), the play (stop) operator of hysteresis theory.

use crate::{SAMPLE_TIME_INHERITED, U_ANY, Y_SAME, table::*};
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::registry::{BlockType, Built};
use ctlgraph_core::{Block, Crossing, Diagnostic, Interface, Io, Params, Width};

pub const TYPES: &[BlockType] = &[BlockType {
    name: "backlash",
    category: "nonlinear",
    summary: "Play of width w: the output moves only when the input pushes it (Simulink's Backlash).",
    doc: "The play operator of deadband width w (Krasnosel'skii and Pokrovskii, Systems with \
          Hysteresis, 1989; Simulink's Backlash), element by element:\n\
          \x20 y = min(max(y_prev, u − w/2), u + w/2)\n\
          with y_prev the output at the last major step (a sample hit in a discrete loop), `initial` \
          at the start. While u stays within w/2 of the output, the output holds (disengaged); \
          pushed to an edge of the deadband, it follows the input at that offset (engaged). Exact \
          for an input monotone between major steps; under a continuous input the moments of \
          engagement, u − w/2 = y_prev rising and u + w/2 = y_prev falling, are zero crossings, \
          located by the solver. Bounds: |y − u| <= w/2 after the first step.",
    inputs: U_ANY,
    outputs: Y_SAME,
    params: &[
        param("width", Number(1.0), "w >= 0, the deadband's total width"),
        param("initial", Number(0.0), "the output before the input first pushes it"),
        SAMPLE_TIME_INHERITED,
    ],
    build: build_backlash,
}];

#[derive(Clone)]
pub struct Backlash {
    /// w/2.
    half: f64,
    initial: f64,
    /// Per element, the output at the last major step.
    held: Vec<f64>,
}

/// The play operator's output for input `u` from the held output `y`
/// (written without `f64::clamp`, which panics on a NaN bound).
fn play(y: f64, u: f64, half: f64) -> f64 {
    let (lo, hi) = (u - half, u + half);
    if y < lo {
        lo
    } else if y > hi {
        hi
    } else {
        y
    }
}

impl Block for Backlash {
    rust_type!(Backlash);
    fn set_width(&mut self, width: usize) -> Result<(), String> {
        self.held = vec![self.initial; width];
        Ok(())
    }
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.held.iter_mut().for_each(|y| *y = self.initial);
    }
    fn output(&mut self, io: &mut Io) {
        for k in 0..self.held.len() {
            let y = play(self.held[k], io.u_at(0, k), self.half);
            io.set_at(0, k, y);
        }
    }
    fn update(&mut self, io: &mut Io) {
        for k in 0..self.held.len() {
            self.held[k] = play(self.held[k], io.u_at(0, k), self.half);
        }
    }
    /// Per element: engagement upward, then downward.
    fn num_zero_crossings(&self) -> usize {
        2 * self.held.len()
    }
    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        for (k, y) in self.held.iter().enumerate() {
            let u = io.u_at(0, k);
            g[2 * k] = u - self.half - y;
            g[2 * k + 1] = u + self.half - y;
        }
    }
    fn crossing_direction(&self, k: usize) -> Crossing {
        if k.is_multiple_of(2) { Crossing::Rising } else { Crossing::Falling }
    }
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation("y = clamp(y_prev, u - w/2, u + w/2);  y_prev = y");
        let held = c.state("held", &vec![self.initial; self.held.len()]);
        let (clamp, half) = (c.clamp(), c.num(self.half));
        for k in 0..self.held.len() {
            let prev = if self.held.len() == 1 { held.clone() } else { format!("{held}[{k}]") };
            let u = c.u_at(0, k).to_string();
            let y = c.y_at(0, k).to_string();
            c.output(format!("{y} = {clamp}({prev}, {u} - {half}, {u} + {half});"));
            c.update(format!("{prev} = {clamp}({prev}, {u} - {half}, {u} + {half});"));
        }
        Ok(())
    }
}

fn build_backlash(p: &mut Params) -> Result<Built, Diagnostic> {
    let width = p.number_where("width", None, |w| w >= 0.0 && w.is_finite(), "a width >= 0")?;
    let initial = p.number_where("initial", None, f64::is_finite, "a finite number")?;
    let iface = Interface::new(p.sample_time()?).input("u", Width::Common, true).output("y", Width::Common);
    Ok(Built::new(Backlash { half: width / 2.0, initial, held: vec![initial] }, iface))
}
