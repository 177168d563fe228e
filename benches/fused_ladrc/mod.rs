//! The LADRC scenario's own blocks called without the interpreter, and
//! the scenario's noise. Shared by `benches/fladrc.rs` (which times the
//! fused loop beside the hand-written one) and `tests/fused.rs` (which
//! checks in CI that it computes what the interpreter computes, to the
//! bit): the semantics a compiled step has to keep for discrete blocks and
//! a plant stepped by its exact ZOH transition.

use ctlgraph_blocks::adrc::{Leso, Lsef, TrackingDifferentiator};
use ctlgraph_blocks::continuous::Lti;
use ctlgraph_core::block::{Io, Port};
use ctlgraph_core::{Block, Model};
use ctlgraph_solver::Zoh;

/// The sample time and the samples after t = 0 (2 s).
pub const H: f64 = 1.0e-4;
pub const SAMPLES: usize = 20_000;

/// SplitMix64 and Box–Muller: the band-limited noise, drawn every 4 ms.
pub struct Noise(pub u64);

impl Noise {
    pub fn normal(&mut self) -> f64 {
        let mut next = || {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
        };
        let (u1, u2) = (1.0 - next(), next());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

/// The LADRC graph's controller and plant as ctlgraph builds them, taken
/// from the compiled graph as their concrete types and called in the
/// graph's order without dispatch; sources, sums and noise as in the
/// hand-written loop. What a compiled step (generated Rust calling the
/// library's blocks) would run: the blocks' own code, without the
/// interpreter's dispatch and bookkeeping.
pub struct Fused {
    td: TrackingDifferentiator,
    leso: Leso,
    lsef: Lsef,
    plant: Lti,
    zoh: Zoh,
}

const fn port(offset: usize, width: usize) -> Port {
    Port { offset, width }
}

/// The fused loop's signals: 0 r, 1 r1, 2 r2, 3..6 z, 6 u, 7 y.
mod fused_ports {
    use super::{Port, port};
    pub const TD_IN: [Port; 1] = [port(0, 1)];
    pub const TD_OUT: [Port; 2] = [port(1, 1), port(2, 1)];
    pub const LESO_IN: [Port; 2] = [port(7, 1), port(6, 1)];
    pub const LESO_OUT: [Port; 1] = [port(3, 3)];
    pub const LSEF_IN: [Port; 3] = [port(1, 1), port(2, 1), port(3, 3)];
    pub const LSEF_OUT: [Port; 1] = [port(6, 1)];
    pub const PLANT_OUT: [Port; 1] = [port(7, 1)];
}

impl Fused {
    pub fn new(model: &Model) -> Self {
        let plant: Lti = model.block_as("plant").expect("plant is an Lti");
        let zoh = Zoh::new(plant.lti().expect("plant is LTI").clone());
        Fused {
            td: model.block_as("ctrl/td").expect("ctrl/td is a tracking differentiator"),
            leso: model.block_as("ctrl/leso").expect("ctrl/leso is a LESO"),
            lsef: model.block_as("ctrl/lsef").expect("ctrl/lsef is an LSEF"),
            plant,
            zoh,
        }
    }

    /// The scenario: Σy over the samples and y at the end, as `hand_written`.
    pub fn run(&mut self, sigma: f64) -> (f64, f64) {
        use fused_ports::*;
        let (mut s, mut x) = ([0.0f64; 8], [0.0f64; 2]);
        self.td.initialize(&mut []);
        self.leso.initialize(&mut []);
        let (mut noise, mut held_noise, mut sink) = (Noise(1), 0.0, 0.0);
        for k in 0..=SAMPLES {
            let t = k as f64 * H;
            let d = if k >= 6000 { 0.5 } else { 0.0 } + if (12_000..16_000).contains(&k) { held_noise } else { 0.0 };
            s[0] = 1.0;
            self.td.output(&mut Io::new(t, false, &[], &mut s, &[], &TD_OUT));
            self.leso.output(&mut Io::new(t, false, &[], &mut s, &[], &LESO_OUT));
            self.lsef.output(&mut Io::new(t, false, &[], &mut s, &LSEF_IN, &LSEF_OUT));
            self.plant.output(&mut Io::new(t, false, &x, &mut s, &[], &PLANT_OUT));
            sink += s[7];
            if k == SAMPLES {
                break;
            }
            self.td.update(&mut Io::new(t, false, &[], &mut s, &TD_IN, &TD_OUT));
            self.leso.update(&mut Io::new(t, false, &[], &mut s, &LESO_IN, &LESO_OUT));
            if k % 40 == 0 {
                held_noise = sigma * noise.normal();
            }
            self.zoh.step(H, &mut x, &[s[6] + d]);
        }
        (sink, s[7])
    }
}
