//! The parametric interpolator of a CNC or robot controller: every period
//! Tc, the path parameter u advances by its second-order Taylor expansion
//! in time (the mirror-milling paper's eq. 8).

use crate::table::*;
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};

pub const PATH_INTERPOLATOR: BlockType = BlockType {
    name: "path_interpolator",
    category: "motion",
    summary: "Advances a path parameter u every Tc by the second-order Taylor expansion of u(t) (eq. 8).",
    doc: "At each sample hit t_j (period Tc = `sample_time`), with the feed f and tangential acceleration \
          a wanted along the path and the path's derivatives P′ = dP/du, P″ at u_j (wire them from the \
          `bspline_path` the output u drives):\n\
          \x20 u_{j+1} = u_j + Tc·f/|P′| + (Tc²/2)·(a/|P′| − f²·(P′·P″)/|P′|⁴),\n\
          u̇ = f/|P′| and ü its time derivative (the paper's eq. 8; Yeh & Hsu's interpolator). u starts \
          at `initial`, never moves back (a step's increment is at least 0: at a stop the quadratic term \
          would undo a little of the last advance) and is held in [0, 1]. The interpolated point is the path's P at this u: the path \
          block evaluates P, P′ and P″ once for both. The inputs are read at the update only, so the \
          loop u → path → P′, P″ → interpolator is no algebraic loop.",
    inputs: &[
        PortDoc { name: "f", doc: "feed along the path [length/s]" },
        PortDoc { name: "a", doc: "tangential acceleration [length/s²]" },
        PortDoc { name: "dp", doc: "P′(u), width 2 or 3 (or 1)" },
        PortDoc { name: "ddp", doc: "P″(u), same width" },
    ],
    outputs: &[PortDoc { name: "u", doc: "path parameter u_j in [0, 1]" }],
    params: &[
        param("sample_time", Required, "interpolation period Tc (required)").kind(ParamKind::SampleTime).unit("s"),
        param("initial", Number(0.0), "u at the start, in [0, 1]"),
    ],
    build: build_path_interpolator,
};

#[derive(Clone)]
pub struct PathInterpolator {
    tc: f64,
    initial: f64,
    u: f64,
}

/// One step of eq. 8: u after a period `tc` at feed `f` and acceleration
/// `a`, with the path's derivatives `d1`, `d2` at `u`.
pub fn taylor_step(u: f64, f: f64, a: f64, d1: &[f64], d2: &[f64], tc: f64) -> f64 {
    let speed2: f64 = d1.iter().map(|v| v * v).sum();
    let speed = speed2.sqrt();
    let dot: f64 = d1.iter().zip(d2).map(|(x, y)| x * y).sum();
    let rate = f / speed;
    let accel = a / speed - f * f * dot / (speed2 * speed2);
    // Never backwards: at a stop (f → 0 while decelerating) the quadratic
    // term would move u back a little.
    (u + (tc * rate + tc * tc / 2.0 * accel).max(0.0)).clamp(0.0, 1.0)
}

impl Block for PathInterpolator {
    rust_type!(PathInterpolator);
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.u = self.initial;
    }

    fn output(&mut self, io: &mut Io) {
        io.set(0, self.u);
    }

    fn update(&mut self, io: &mut Io) {
        let (f, a) = (io.input(0)[0], io.input(1)[0]);
        self.u = taylor_step(self.u, f, a, io.input(2), io.input(3), self.tc);
    }

    fn discrete_state(&mut self) -> Option<&mut [f64]> {
        Some(std::slice::from_mut(&mut self.u))
    }
}

fn build_path_interpolator(p: &mut Params) -> Result<Built, Diagnostic> {
    let (st, tc, _) = p.discrete_clock()?;
    let initial = p.number_where("initial", None, |u| (0.0..=1.0).contains(&u), "in [0, 1]")?;
    let iface = Interface::new(st)
        .input("f", Width::Fixed(1), false)
        .input("a", Width::Fixed(1), false)
        .input("dp", Width::Common, false)
        .input("ddp", Width::Common, false)
        .output("u", Width::Fixed(1));
    Ok(Built::new(PathInterpolator { tc, initial, u: initial }, iface))
}
