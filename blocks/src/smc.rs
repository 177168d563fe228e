//! Sliding-mode control: the contact-force paper's position controller
//! with an adaptive disturbance estimate, and a general first-order
//! sliding-mode law with a boundary layer.

use crate::table::*;
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "sliding_mode",
        category: "control",
        summary: "Sliding-mode position control of Je·x'' + Be·x' = u − d with an adaptive d̂.",
        doc: "The contact-force paper's eq. 14–20:\n\
              \x20 S = λ(xr − x) + (xr' − x'),\n\
              \x20 u = Je·[λ(xr' − x') + xr''] + Be·x' + d̂ + Ks·S,\n\
              \x20 d̂(k) = d̂(k−1) + ρ·κ·S·T, held in [d_min, d_max] (κ = 0 when the step would leave them).\n\
              With d constant, Je·S' = −Ks·S − (d̂ − d) and V = Je·S²/2 + (d̂ − d)²/(2ρ) gives \
              V' = −Ks·S² (continuous form): S → 0 and x → xr. Discrete with a sample time T \
              (d̂ by forward Euler, as the paper), or continuous (sample_time 0: d̂' = ρκS integrated \
              by the solver). Optional output limits on u.\n\
              Stable region: λ, Ks, ρ > 0, Je, Be > 0 matching the plant, d_min <= d <= d_max; \
              discrete: ρ·T small against Ks/Je (T·Ks/Je < 1). Bounds: d̂ stays in [d_min, d_max].",
        inputs: &[
            PortDoc { name: "xr", doc: "reference position" },
            PortDoc { name: "dxr", doc: "reference velocity xr'" },
            PortDoc { name: "ddxr", doc: "reference acceleration xr''" },
            PortDoc { name: "x", doc: "measured position" },
            PortDoc { name: "dx", doc: "measured velocity" },
        ],
        outputs: &[
            PortDoc { name: "u", doc: "control voltage" },
            PortDoc { name: "s", doc: "sliding variable S" },
            PortDoc { name: "d_hat", doc: "disturbance estimate" },
        ],
        params: &[
            param("lambda", Required, "sliding-surface slope λ > 0").kind(ParamKind::Number).unit("1/s"),
            param("ks", Required, "reaching gain Ks > 0").kind(ParamKind::Number).unit("V/(length/s)"),
            param("rho", Required, "adaptation gain ρ > 0").kind(ParamKind::Number).unit("V/length"),
            param("je", Required, "plant inertia Je (as feed_drive)").kind(ParamKind::Number),
            param("be", Required, "plant damping Be (as feed_drive)").kind(ParamKind::Number),
            param("d_min", Required, "lower bound of d̂").kind(ParamKind::Number),
            param("d_max", Required, "upper bound of d̂").kind(ParamKind::Number),
            param("lower", Number(f64::NEG_INFINITY), "lower limit of u"),
            param("upper", Number(f64::INFINITY), "upper limit of u"),
            param("sample_time", Number(0.0), "0 continuous, T > 0 discrete").kind(ParamKind::SampleTime),
        ],
        build: build_sliding_mode,
    },
    BlockType {
        name: "smc",
        category: "control",
        summary: "First-order sliding-mode law u = u_eq + k·sat(S/φ) with a boundary layer.",
        doc: "S = λ·e + e' for a tracking error e; u = u_eq + k·sat(S/φ), sat the unit saturation; \
              φ = 0 is the discontinuous k·sign(S). A boundary layer φ > 0 trades chattering for a \
              residual |S| <= φ. `u_eq` is an input port (the model-based equivalent control) when \
              `equivalent_input: true`, else 0.\n\
              Bounds: |u − u_eq| <= k.",
        inputs: &[
            PortDoc { name: "e", doc: "tracking error" },
            PortDoc { name: "de", doc: "its derivative" },
            PortDoc { name: "u_eq", doc: "equivalent control (with equivalent_input: true)" },
        ],
        outputs: &[PortDoc { name: "u", doc: "control" }, PortDoc { name: "s", doc: "sliding variable" }],
        params: &[
            param("lambda", Required, "surface slope λ > 0").kind(ParamKind::Number),
            param("k", Required, "switching gain k >= 0").kind(ParamKind::Number),
            param("phi", Number(0.0), "boundary-layer width φ >= 0 (0: sign)"),
            param("equivalent_input", Flag(false), "add the input port u_eq"),
            crate::SAMPLE_TIME_INHERITED,
        ],
        build: build_smc,
    },
];

/// The paper's SMC law; d̂ kept in the block (discrete) or in the state.
#[derive(Clone)]
pub struct SlidingMode {
    pub lambda: f64,
    pub ks: f64,
    pub rho: f64,
    pub je: f64,
    pub be: f64,
    pub d_min: f64,
    pub d_max: f64,
    pub lower: f64,
    pub upper: f64,
    /// Discrete period (0: continuous d̂ state).
    pub period: f64,
    d_hat: f64,
}

impl SlidingMode {
    /// (u, S) for inputs [xr, xr', xr'', x, x'] and estimate d̂.
    pub fn law(&self, inp: [f64; 5], d_hat: f64) -> (f64, f64) {
        let [xr, dxr, ddxr, x, dx] = inp;
        let s = self.lambda * (xr - x) + (dxr - dx);
        let u = self.je * (self.lambda * (dxr - dx) + ddxr) + self.be * dx + d_hat + self.ks * s;
        (u.clamp(self.lower, self.upper), s)
    }

    fn inputs(io: &Io) -> [f64; 5] {
        std::array::from_fn(|i| io.u(i))
    }

    fn estimate(&self, io: &Io) -> f64 {
        if self.period > 0.0 { self.d_hat } else { io.x[0] }
    }
}

impl Block for SlidingMode {
    rust_type!(SlidingMode);
    fn num_states(&self) -> usize {
        if self.period > 0.0 { 0 } else { 1 }
    }
    fn initialize(&mut self, x0: &mut [f64]) {
        self.d_hat = 0.0f64.clamp(self.d_min, self.d_max);
        if let Some(x) = x0.first_mut() {
            *x = self.d_hat;
        }
    }
    fn output(&mut self, io: &mut Io) {
        let d_hat = self.estimate(io);
        let (u, s) = self.law(Self::inputs(io), d_hat);
        io.set(0, u);
        io.set(1, s);
        io.set(2, d_hat);
    }
    fn discrete_state(&mut self) -> Option<&mut [f64]> {
        (self.period > 0.0).then(|| std::slice::from_mut(&mut self.d_hat))
    }
    fn update(&mut self, io: &mut Io) {
        if self.period > 0.0 {
            let (_, s) = self.law(Self::inputs(io), self.d_hat);
            self.d_hat = (self.d_hat + self.rho * s * self.period).clamp(self.d_min, self.d_max);
        }
    }
    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        let (_, s) = self.law(Self::inputs(io), io.x[0]);
        let rate = self.rho * s;
        // κ: no integration out of the bounds.
        let blocked = (io.x[0] >= self.d_max && rate > 0.0) || (io.x[0] <= self.d_min && rate < 0.0);
        dx[0] = if blocked { 0.0 } else { rate };
    }
    fn clamp_states(&self, x: &mut [f64]) -> bool {
        let before = x[0];
        x[0] = x[0].clamp(self.d_min, self.d_max);
        x[0] != before
    }
    /// The discrete law ([`SlidingMode::law`]) and its forward-Euler estimate.
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        if self.period <= 0.0 {
            return Err(NoCForm::Because("a continuous estimate d_hat: give it a sample_time".into()));
        }
        c.equation("S = lambda (xr - x) + (xr' - x');  u = Je (lambda (xr' - x') + xr'') + Be x' + d_hat + Ks S");
        c.equation("d_hat(k+1) = clamp(d_hat + rho S T, d_min, d_max)");
        let d_hat = c.state("d_hat", &[0.0f64.clamp(self.d_min, self.d_max)]);
        let [xr, dxr, ddxr, x, dx] = [0, 1, 2, 3, 4].map(|i| c.u(i).to_string());
        let real = c.real();
        let kind = c.kind();
        let n = |v: f64| kind.literal(v);
        let law = format!(
            "{real} s_ = {lambda} * ({xr} - {x}) + ({dxr} - {dx});\n\
             {real} u_ = {je} * ({lambda} * ({dxr} - {dx}) + {ddxr}) + {be} * {dx} + {d_hat} + {ks} * s_;",
            lambda = n(self.lambda),
            je = n(self.je),
            be = n(self.be),
            ks = n(self.ks),
        );
        let u = if self.lower == f64::NEG_INFINITY && self.upper == f64::INFINITY {
            "u_".to_string()
        } else {
            format!("{}(u_, {}, {})", c.clamp(), n(self.lower), n(self.upper))
        };
        let clamp = c.clamp();
        c.output(format!("{law}\n{} = {u};\n{} = s_;\n{} = {d_hat};", c.y(0), c.y(1), c.y(2)));
        c.update(format!(
            "{law}\n(void)u_;\n{d_hat} = {clamp}({d_hat} + {rho} * s_ * {period}, {lo}, {hi});",
            rho = n(self.rho),
            period = n(self.period),
            lo = n(self.d_min),
            hi = n(self.d_max)
        ));
        Ok(())
    }
}

fn build_sliding_mode(p: &mut Params) -> Result<Built, Diagnostic> {
    let (lambda, ks, rho) = (p.positive("lambda")?, p.positive("ks")?, p.positive("rho")?);
    let (je, be) = (p.positive("je")?, p.positive("be")?);
    let (d_min, d_max) = (p.number("d_min")?, p.number("d_max")?);
    if d_min > d_max {
        return Err(p.error("d_max", format!("`d_max` ({d_max}) must be >= `d_min` ({d_min})")));
    }
    let (lower, upper) = crate::nonlinear::limits(p, "lower", "upper")?;
    let (st, period) = p.continuous_or_discrete()?;
    let period = period.unwrap_or(0.0);
    let mut iface = Interface::new(st);
    for name in ["xr", "dxr", "ddxr", "x", "dx"] {
        iface = iface.input(name, Width::Fixed(1), true);
    }
    let iface = iface.output("u", Width::Fixed(1)).output("s", Width::Fixed(1)).output("d_hat", Width::Fixed(1));
    let block = SlidingMode { lambda, ks, rho, je, be, d_min, d_max, lower, upper, period, d_hat: 0.0 };
    Ok(Built::new(block, iface))
}

#[derive(Clone)]
pub struct Smc {
    lambda: f64,
    k: f64,
    phi: f64,
    equivalent: bool,
}

impl Block for Smc {
    rust_type!(Smc);
    fn output(&mut self, io: &mut Io) {
        let s = self.lambda * io.u(0) + io.u(1);
        let switching = if self.phi > 0.0 { (s / self.phi).clamp(-1.0, 1.0) } else { crate::math::sign(s) };
        let u_eq = if self.equivalent { io.u(2) } else { 0.0 };
        io.set(0, u_eq + self.k * switching);
        io.set(1, s);
    }
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation(if self.phi > 0.0 {
            "S = lambda e + e';  u = u_eq + k sat(S / phi)"
        } else {
            "S = lambda e + e';  u = u_eq + k sign(S)"
        });
        let real = c.real();
        let switching = if self.phi > 0.0 {
            format!("{}(s_ / {}, {}, {})", c.clamp(), c.num(self.phi), c.num(-1.0), c.num(1.0))
        } else {
            format!("{}(s_)", c.sign())
        };
        // u_eq = 0 without the port: 0 + k·sw, as the block adds it.
        let u_eq = if self.equivalent { c.u(2).to_string() } else { c.num(0.0) };
        c.output(format!(
            "{real} s_ = {} * {} + {};\n{} = {u_eq} + {} * {switching};\n{} = s_;",
            c.num(self.lambda),
            c.u(0),
            c.u(1),
            c.y(0),
            c.num(self.k),
            c.y(1)
        ));
        Ok(())
    }
}

fn build_smc(p: &mut Params) -> Result<Built, Diagnostic> {
    let lambda = p.positive("lambda")?;
    let k = p.number_where("k", None, |v| v >= 0.0 && v.is_finite(), "a gain >= 0")?;
    let phi = p.number_where("phi", None, |v| v >= 0.0 && v.is_finite(), "a width >= 0")?;
    let equivalent = p.flag("equivalent_input")?;
    let mut iface = Interface::new(p.sample_time()?).piecewise_constant().input("e", Width::Fixed(1), true).input(
        "de",
        Width::Fixed(1),
        true,
    );
    if equivalent {
        iface = iface.input("u_eq", Width::Fixed(1), true);
    }
    let iface = iface.output("u", Width::Fixed(1)).output("s", Width::Fixed(1));
    Ok(Built::new(Smc { lambda, k, phi, equivalent }, iface))
}

#[cfg(test)]
mod tests;
