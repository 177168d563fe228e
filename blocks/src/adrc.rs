//! Active disturbance rejection control: Han's tracking differentiator,
//! the linear extended state observer (LESO) and linear state error
//! feedback (LSEF). Composed into LADRC by `graphs/lib/ladrc.yaml`.

use crate::math::sign;
use crate::table::*;
use ctlgraph_core::codegen::c::{CBlock, NoCForm, Real};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "tracking_differentiator",
        category: "control",
        summary: "Han's discrete tracking differentiator: smooth reference r1 and its derivative r2.",
        doc: "With h the sample time (Shi/Zhou/Li 2025, eq. 6–7; Han 2009):\n\
              \x20 r1(k+1) = r1(k) + h·r2(k),  r2(k+1) = r2(k) + h·F(r1(k) − r(k), r2(k), δ, h0).\n\
              `form: fst` (default): F = fst(x1, x2, δ, h0), Han's time-optimal synthesis function:\n\
              \x20 d = δ·h0, d0 = h0·d, c = x1 + h0·x2, a0 = sqrt(d² + 8δ|c|),\n\
              \x20 a = x2 + (a0 − d)/2·sign(c) if |c| > d0, else x2 + c/h0,\n\
              \x20 F = −δ·sign(a) if |a| > d, else −δ·a/d.\n\
              The paper prints c = x1 + h·x2 with h the sample time; Han's original, the default here, \
              has c = x1 + h0·x2 (the two agree for h0 = h). `form: paper` is fst with the printed \
              c = x1 + h·x2; in general `c_step` sets the step in c (default h0; `form: paper` makes it h), \
              so a graph can switch forms through a numeric parameter. `form: fhan`: Han's later \
              fhan(x1, x2, δ, h0), exact for the \
              discrete double integrator. δ is the largest acceleration of r1 (speed factor); h0 >= h \
              filters noise on r (filter factor). Outputs are the states: no direct feedthrough.\n\
              Stable region: δ > 0, h0 >= 2h; then r1 reaches a constant r without overshoot and r2 → 0 (with h0 = h both forms can overshoot by a few percent). \
              `form: paper` (c_step = h < h0) converges in the same region but overshoots: by 1.7 % for \
              δ = 1e4, h = 0.1 ms, h0 = 5h, growing with δ·h0² to about 16 % (a sweep over δ in [1e2, \
              1e5], h in [0.1, 10] ms, h0 in [2h, 10h]).",
        inputs: &[PortDoc { name: "r", doc: "reference (scalar)" }],
        outputs: &[PortDoc { name: "r1", doc: "tracked reference" }, PortDoc { name: "r2", doc: "its derivative" }],
        params: &[
            param("delta", Required, "speed factor δ > 0: largest |dr2/dt|").kind(ParamKind::Number).unit("units/s²"),
            param("h0", Described("2·sample_time"), "filter factor h0 > 0; >= 2·sample_time avoids overshoot")
                .kind(ParamKind::Number)
                .unit("s"),
            param("form", Word("fst"), "fst (Han's, c = x1 + h0·x2) | paper (eq. 7 as printed, c = x1 + h·x2) | fhan")
                .options(&["fst", "paper", "fhan"]),
            param("c_step", Described("h0"), "the step in c = x1 + c_step·x2 of fst (paper: h); > 0")
                .kind(ParamKind::Number)
                .unit("s"),
            param("initial", Number(0.0), "r1(0)"),
            crate::SAMPLE_TIME_REQUIRED,
        ],
        build: build_td,
    },
    BlockType {
        name: "leso",
        category: "control",
        summary: "Linear extended state observer of order n+1 for an n-th order plant.",
        doc: "Model y⁽ⁿ⁾ = f + b0·u with the total disturbance f as extra state. With e = z1 − y:\n\
              \x20 z_i' = z_{i+1} − β_i·e (i < n),  z_n' = z_{n+1} − β_n·e + b0·u,  z_{n+1}' = −β_{n+1}·e.\n\
              Gains from the observer bandwidth ω (Gao 2003): β_i = C(n+1, i)·ωⁱ (n = 2: 3ω, 3ω², ω³), \
              or given as `beta`. Continuous (states integrated by the solver) or, with a sample time \
              h, discrete by forward Euler as the paper's eq. 8: z(k+1) = z(k) + h·z'(k). Output z is \
              the state: no direct feedthrough, so the observer closes loops legally.\n\
              Stable region: ω > 0 (continuous); 0 < ω·h < 2 (discrete: error poles at 1 − ω·h). Then \
              z1 → y, z2 → y', …, and z_{n+1} → f for a slowly varying f.",
        inputs: &[
            PortDoc { name: "y", doc: "measured plant output" },
            PortDoc { name: "u", doc: "plant input (control signal)" },
        ],
        outputs: &[PortDoc { name: "z", doc: "estimates [y, y', …, f], width n+1" }],
        params: &[
            param("order", Number(2.0), "plant order n (1, 2 or 3)"),
            param("omega", Required, "observer bandwidth ω (or give `beta`)").kind(ParamKind::Number).unit("rad/s"),
            param("beta", Required, "explicit gains [β1 … β_{n+1}] instead of ω").kind(ParamKind::Numbers),
            param("b0", Required, "input gain estimate b0").kind(ParamKind::Number),
            param("initial", Number(0.0), "z(0): a number or n+1 numbers").kind(ParamKind::Numbers),
            param("sample_time", Number(0.0), "0 continuous, h > 0 discrete (forward Euler)")
                .kind(ParamKind::SampleTime),
        ],
        build: build_leso,
    },
    BlockType {
        name: "lsef",
        category: "control",
        summary: "Linear state error feedback with disturbance compensation (the LADRC control law).",
        doc: "The paper's eq. 9–10: e1 = r1 − z1, e2 = r2 − z2, u0 = α1·e1 + α2·e2, u = u0 − z3/b0 \
              (order 1: u = α1·e1 − z2/b0). The gains act in control units directly; the textbook form \
              u = (kp·e1 + kd·e2 − z3)/b0 is the same law with α = k/b0. `gain_inputs: [alpha1, alpha2]` \
              adds ports whose values replace the gains at every step (fuzzy self-tuning). Optional \
              output limits.\n\
              Bounds: lower <= u <= upper.",
        inputs: &[
            PortDoc { name: "r1", doc: "reference (from the TD)" },
            PortDoc { name: "r2", doc: "reference derivative (order 2 only)" },
            PortDoc { name: "z", doc: "LESO state, width order+1" },
            PortDoc { name: "alpha1, alpha2", doc: "only those listed in `gain_inputs`" },
        ],
        outputs: &[PortDoc { name: "u", doc: "control signal" }],
        params: &[
            param("alpha", Required, "[α1, α2] (order 2) or [α1] (order 1)").kind(ParamKind::Numbers),
            param("b0", Required, "input gain estimate, as in the LESO").kind(ParamKind::Number),
            param("order", Number(2.0), "plant order (1 or 2)"),
            param("lower", Number(f64::NEG_INFINITY), "lower output limit"),
            param("upper", Number(f64::INFINITY), "upper output limit"),
            param("gain_inputs", Described("[]"), "gains read from ports each step: alpha1, alpha2")
                .kind(ParamKind::Words),
            crate::SAMPLE_TIME_INHERITED,
        ],
        build: build_lsef,
    },
];

/// Han's time-optimal synthesis function fst(x1, x2, δ, h0) with
/// c = x1 + c_step·x2: Han's original has c_step = h0, the paper prints
/// the sample time h (see the block doc).
#[inline]
pub fn fst(x1: f64, x2: f64, delta: f64, h0: f64, c_step: f64) -> f64 {
    let d = delta * h0;
    let d0 = h0 * d;
    let c = x1 + c_step * x2;
    let a0 = (d * d + 8.0 * delta * c.abs()).sqrt();
    let a = if c.abs() > d0 { x2 + (a0 - d) / 2.0 * sign(c) } else { x2 + c / h0 };
    if a.abs() > d { -delta * sign(a) } else { -delta * a / d }
}

/// Han's fhan(x1, x2, r, h0) (Han 2009, eq. 21).
pub fn fhan(x1: f64, x2: f64, r: f64, h0: f64) -> f64 {
    let d = r * h0 * h0;
    let a0 = h0 * x2;
    let y = x1 + a0;
    let a1 = (d * (d + 8.0 * y.abs())).sqrt();
    let a2 = a0 + sign(y) * (a1 - d) / 2.0;
    let sy = (sign(y + d) - sign(y - d)) / 2.0;
    let a = (a0 + y - a2) * sy + a2;
    let sa = (sign(a + d) - sign(a - d)) / 2.0;
    -r * (a / d - sign(a)) * sa - r * sign(a)
}

/// [`fst`] in C, the same operations in the same order.
fn c_fst(c: &mut CBlock) -> &'static str {
    let sign = c.sign();
    c.helper("ctl_fst", |r: Real| {
        let (t, abs, sqrt) = (r.c_type(), r.math("fabs"), r.math("sqrt"));
        let (two, eight) = (r.literal(2.0), r.literal(8.0));
        format!(
            "/* Han's time-optimal synthesis function fst(x1, x2, delta, h0), c = x1 + c_step x2 */\n\
             static {t} ctl_fst({t} x1, {t} x2, {t} delta, {t} h0, {t} c_step)\n{{\n\
             \x20   {t} d = delta * h0;\n    {t} d0 = h0 * d;\n    {t} c = x1 + c_step * x2;\n\
             \x20   {t} a0 = {sqrt}(d * d + {eight} * delta * {abs}(c));\n\
             \x20   {t} a = {abs}(c) > d0 ? x2 + (a0 - d) / {two} * {sign}(c) : x2 + c / h0;\n\
             \x20   return {abs}(a) > d ? -delta * {sign}(a) : -delta * a / d;\n}}\n"
        )
    })
}

/// [`fhan`] in C, the same operations in the same order.
fn c_fhan(c: &mut CBlock) -> &'static str {
    let sign = c.sign();
    c.helper("ctl_fhan", |r: Real| {
        let (t, abs, sqrt) = (r.c_type(), r.math("fabs"), r.math("sqrt"));
        let (two, eight) = (r.literal(2.0), r.literal(8.0));
        format!(
            "/* Han's fhan(x1, x2, r, h0) (Han 2009, eq. 21) */\n\
             static {t} ctl_fhan({t} x1, {t} x2, {t} r, {t} h0)\n{{\n\
             \x20   {t} d = r * h0 * h0;\n    {t} a0 = h0 * x2;\n    {t} y = x1 + a0;\n\
             \x20   {t} a1 = {sqrt}(d * (d + {eight} * {abs}(y)));\n\
             \x20   {t} a2 = a0 + {sign}(y) * (a1 - d) / {two};\n\
             \x20   {t} sy = ({sign}(y + d) - {sign}(y - d)) / {two};\n\
             \x20   {t} a = (a0 + y - a2) * sy + a2;\n\
             \x20   {t} sa = ({sign}(a + d) - {sign}(a - d)) / {two};\n\
             \x20   return -r * (a / d - {sign}(a)) * sa - r * {sign}(a);\n}}\n"
        )
    })
}

/// The discrete tracking differentiator.
#[derive(Clone)]
pub struct TrackingDifferentiator {
    pub delta: f64,
    pub h0: f64,
    pub h: f64,
    pub fhan: bool,
    /// The step in c = x1 + c_step·x2 of fst.
    pub c_step: f64,
    pub initial: f64,
    r1: f64,
    r2: f64,
}

impl TrackingDifferentiator {
    /// Han's forms (fst with c_step = h0, or fhan).
    pub fn new(delta: f64, h0: f64, h: f64, fhan: bool, initial: f64) -> Self {
        TrackingDifferentiator { delta, h0, h, fhan, c_step: h0, initial, r1: initial, r2: 0.0 }
    }

    /// One step with reference `r`; returns the new (r1, r2).
    #[inline]
    pub fn step(&mut self, r: f64) -> (f64, f64) {
        let x1 = self.r1 - r;
        let f = if self.fhan {
            fhan(x1, self.r2, self.delta, self.h0)
        } else {
            fst(x1, self.r2, self.delta, self.h0, self.c_step)
        };
        self.r1 += self.h * self.r2;
        self.r2 += self.h * f;
        (self.r1, self.r2)
    }
}

impl Block for TrackingDifferentiator {
    rust_type!(TrackingDifferentiator);
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.r1 = self.initial;
        self.r2 = 0.0;
    }
    #[inline(always)]
    fn output(&mut self, io: &mut Io) {
        io.set(0, self.r1);
        io.set(1, self.r2);
    }
    #[inline(always)]
    fn update(&mut self, io: &mut Io) {
        self.step(io.u(0));
    }
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let f = if self.fhan { c_fhan(c) } else { c_fst(c) };
        c.equation("r1(k+1) = r1(k) + h r2(k),  r2(k+1) = r2(k) + h F(r1(k) - r(k), r2(k))");
        c.equation(if self.fhan {
            "F = fhan(x1, x2, delta, h0)"
        } else {
            "F = fst(x1, x2, delta, h0), c = x1 + c_step x2"
        });
        let r1 = c.state("r1", &[self.initial]);
        let r2 = c.state("r2", &[0.0]);
        c.output(format!("{} = {r1};", c.y(0)));
        c.output(format!("{} = {r2};", c.y(1)));
        let args = if self.fhan {
            format!("{}, {}", c.num(self.delta), c.num(self.h0))
        } else {
            format!("{}, {}, {}", c.num(self.delta), c.num(self.h0), c.num(self.c_step))
        };
        let h = c.num(self.h);
        c.update(format!("{real} f = {f}({r1} - {u}, {r2}, {args});", real = c.real(), u = c.u(0)));
        c.update(format!("{r1} += {h} * {r2};"));
        c.update(format!("{r2} += {h} * f;"));
        Ok(())
    }
}

fn build_td(p: &mut Params) -> Result<Built, Diagnostic> {
    let delta = p.number_where("delta", None, |v| v > 0.0 && v.is_finite(), "a positive speed factor")?;
    let (st, h, _) = p.discrete_clock()?;
    let h0 = p.number_where("h0", Some(2.0 * h), |v| v > 0.0 && v.is_finite(), "a positive filter factor")?;
    let form = p.choice("form", &["fst", "paper", "fhan"])?;
    let c_default = if form == "paper" { h } else { h0 };
    let c_step = p.number_where("c_step", Some(c_default), |v| v > 0.0 && v.is_finite(), "a positive step [s]")?;
    if form == "fhan" && p.has("c_step") {
        return Err(p.error("c_step", "`c_step` belongs to fst (form: fst or paper), not to fhan"));
    }
    let initial = p.number("initial")?;
    let iface = Interface::new(st)
        .input("r", Width::Fixed(1), false)
        .output("r1", Width::Fixed(1))
        .output("r2", Width::Fixed(1));
    let mut td = TrackingDifferentiator::new(delta, h0, h, form == "fhan", initial);
    td.c_step = c_step;
    Ok(Built::new(td, iface))
}

/// Binomial coefficient C(n, k) as f64 (small n).
fn binomial(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

/// Observer bandwidth gains β_i = C(n+1, i)·ωⁱ, i = 1 … n+1.
pub fn bandwidth_gains(order: usize, omega: f64) -> Vec<f64> {
    (1..=order + 1).map(|i| binomial(order + 1, i) * omega.powi(i as i32)).collect()
}

/// The LESO; discrete when `h > 0`.
#[derive(Clone)]
pub struct Leso {
    beta: Vec<f64>,
    b0: f64,
    h: f64,
    initial: Vec<f64>,
    z: Vec<f64>,
    dz: Vec<f64>,
}

impl Leso {
    pub fn new(beta: Vec<f64>, b0: f64, h: f64, initial: Vec<f64>) -> Self {
        let n = beta.len();
        Leso { beta, b0, h, z: initial.clone(), initial, dz: vec![0.0; n] }
    }

    /// z' for state `z`, output `y`, input `u`.
    pub fn derivative(&self, z: &[f64], y: f64, u: f64, dz: &mut [f64]) {
        let n = z.len() - 1;
        let e = z[0] - y;
        for i in 0..n {
            dz[i] = z[i + 1] - self.beta[i] * e;
        }
        dz[n - 1] += self.b0 * u;
        dz[n] = -self.beta[n] * e;
    }

    /// The discrete state (for tests).
    pub fn state(&self) -> &[f64] {
        &self.z
    }

    /// One forward-Euler step (discrete form). The observer orders the
    /// block accepts (1–3) step in fixed-size loops the compiler unrolls:
    /// the same operations in the same order as the general loop, without
    /// its bounds checks (tested bit for bit).
    #[inline]
    pub fn step(&mut self, y: f64, u: f64) {
        self.step_sized(self.z.len(), y, u);
    }

    /// [`Leso::step`] for an observer of `n` = order + 1 states (a
    /// mismatch takes the general loop).
    #[inline]
    fn step_sized(&mut self, n: usize, y: f64, u: f64) {
        match n {
            2 => self.step_fixed::<2>(y, u),
            3 => self.step_fixed::<3>(y, u),
            4 => self.step_fixed::<4>(y, u),
            _ => self.step_general(y, u),
        }
    }

    #[inline]
    fn step_fixed<const N: usize>(&mut self, y: f64, u: f64) {
        let (Ok(z), Ok(beta)) = (<&mut [f64; N]>::try_from(&mut self.z[..]), <&[f64; N]>::try_from(&self.beta[..]))
        else {
            return self.step_general(y, u);
        };
        let e = z[0] - y;
        let mut dz = [0.0; N];
        for i in 0..N - 1 {
            dz[i] = z[i + 1] - beta[i] * e;
        }
        dz[N - 2] += self.b0 * u;
        dz[N - 1] = -beta[N - 1] * e;
        for i in 0..N {
            z[i] += self.h * dz[i];
        }
    }

    fn step_general(&mut self, y: f64, u: f64) {
        let mut dz = std::mem::take(&mut self.dz);
        self.derivative(&self.z, y, u, &mut dz);
        for (z, d) in self.z.iter_mut().zip(&dz) {
            *z += self.h * d;
        }
        self.dz = dz;
    }
}

impl Block for Leso {
    rust_type!(Leso);
    /// The Euler step as matrices: z⁺ = (I + h·Ac) z + h·Bc [y, u], y = z,
    /// with Ac the observer matrix (shift, minus β in the first column).
    fn discrete_lti(&self) -> Option<ctlgraph_solver::StateSpace> {
        if self.h <= 0.0 {
            return None;
        }
        let n = self.beta.len();
        let (mut a, mut b) = (vec![0.0; n * n], vec![0.0; n * 2]);
        for i in 0..n {
            a[i * n + i] = 1.0;
            a[i * n] -= self.h * self.beta[i];
            if i + 1 < n {
                a[i * n + i + 1] += self.h;
            }
            b[i * 2] = self.h * self.beta[i];
        }
        b[(n - 2) * 2 + 1] = self.h * self.b0;
        let c = (0..n * n).map(|k| if k / n == k % n { 1.0 } else { 0.0 }).collect();
        Some(ctlgraph_solver::StateSpace { n, m: 2, p: n, a, b, c, d: vec![0.0; n * 2] })
    }

    fn num_states(&self) -> usize {
        if self.h > 0.0 { 0 } else { self.beta.len() }
    }
    fn initialize(&mut self, x0: &mut [f64]) {
        self.z.copy_from_slice(&self.initial);
        x0.copy_from_slice(if self.h > 0.0 { &[] } else { &self.initial[..] });
    }
    /// Discrete (h > 0) exactly when the block has no continuous states,
    /// and its order is its output's width less one: both asked of the
    /// view, where a generated step knows them (see [`Io::output_width`]).
    #[inline(always)]
    fn output(&mut self, io: &mut Io) {
        let z = if io.x.is_empty() { &self.z[..] } else { io.x };
        io.set_all(0, z);
    }
    #[inline(always)]
    fn update(&mut self, io: &mut Io) {
        if io.x.is_empty() {
            self.step_sized(io.output_width(0), io.u(0), io.u(1));
        }
    }
    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        self.derivative(io.x, io.u(0), io.u(1), dx);
    }
    /// The forward-Euler step of [`Leso::step`], unrolled.
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        if self.h <= 0.0 {
            return Err(NoCForm::Because("a continuous LESO: give it a sample_time".into()));
        }
        let n = self.beta.len();
        c.equation(
            "e = z1 - y;  z_i += h (z_{i+1} - beta_i e) (i < n, plus b0 u at i = n);  z_{n+1} += h (-beta_{n+1} e)",
        );
        let z = c.state("z", &self.initial);
        for k in 0..n {
            c.output(format!("{} = {z}[{k}];", c.y_at(0, k)));
        }
        let real = c.real();
        c.update(format!("{real} e = {z}[0] - {};", c.u(0)));
        for i in 0..n - 1 {
            let mut d = format!("{z}[{}] - {} * e", i + 1, c.num(self.beta[i]));
            if i == n - 2 {
                // dz[n-2] += b0·u: the sum's rounding, then the addition's.
                d = format!("({d}) + {} * {}", c.num(self.b0), c.u(1));
            }
            c.update(format!("{real} d{i} = {d};"));
        }
        c.update(format!("{real} d{} = -{} * e;", n - 1, c.num(self.beta[n - 1])));
        let h = c.num(self.h);
        for i in 0..n {
            c.update(format!("{z}[{i}] += {h} * d{i};"));
        }
        Ok(())
    }
}

fn build_leso(p: &mut Params) -> Result<Built, Diagnostic> {
    let order = p.count("order", 3)?;
    let beta = match (p.opt_number("omega")?, p.opt_vector("beta")?) {
        (Some(w), None) if w > 0.0 && w.is_finite() => bandwidth_gains(order, w),
        (Some(w), None) => return Err(p.error("omega", format!("must be a positive bandwidth, got {w}"))),
        (None, Some(b)) if b.len() == order + 1 => b,
        (None, Some(b)) => {
            return Err(p.error("beta", format!("needs {} gains for order {order}, got {}", order + 1, b.len())));
        }
        (Some(_), Some(_)) => return Err(p.error("beta", "give either `omega` or `beta`, not both")),
        (None, None) => return Err(p.block_error("missing parameter `omega` (or `beta`)")),
    };
    let b0 = p.number_where("b0", None, |v| v != 0.0 && v.is_finite(), "a nonzero input gain")?;
    let initial = p.vector("initial")?;
    let initial = crate::continuous::initial_vector(&initial, order + 1).map_err(|m| p.error("initial", m))?;
    let (st, h) = p.continuous_or_discrete()?;
    let h = h.unwrap_or(0.0);
    let iface = Interface::new(st)
        .input("y", Width::Fixed(1), false)
        .input("u", Width::Fixed(1), false)
        .output("z", Width::Fixed(order + 1));
    Ok(Built::new(Leso::new(beta, b0, h, initial), iface))
}

/// The LSEF law; `alpha_ports` are input indices of tuned gains.
#[derive(Clone)]
pub struct Lsef {
    alpha: [f64; 2],
    alpha_ports: [Option<usize>; 2],
    b0: f64,
    order: usize,
    z_port: usize,
    lower: f64,
    upper: f64,
}

impl Block for Lsef {
    rust_type!(Lsef);
    fn updates(&self) -> bool {
        false
    }
    #[inline(always)]
    fn output(&mut self, io: &mut Io) {
        let a: [f64; 2] = std::array::from_fn(|i| self.alpha_ports[i].map_or(self.alpha[i], |p| io.u(p)));
        let z = io.input(self.z_port);
        let e1 = io.u(0) - z[0];
        let u = if self.order == 2 {
            let e2 = io.u(1) - z[1];
            a[0] * e1 + a[1] * e2 - z[2] / self.b0
        } else {
            a[0] * e1 - z[1] / self.b0
        };
        io.set(0, u.clamp(self.lower, self.upper));
    }
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let a: Vec<String> =
            (0..2).map(|i| self.alpha_ports[i].map_or(c.num(self.alpha[i]), |p| c.u(p).to_string())).collect();
        let z: Vec<String> = (0..=self.order).map(|k| c.u_at(self.z_port, k).to_string()).collect();
        let b0 = c.num(self.b0);
        let u = if self.order == 2 {
            c.equation("u = alpha1 (r1 - z1) + alpha2 (r2 - z2) - z3 / b0, limited to [lower, upper]");
            format!("{} * ({} - {}) + {} * ({} - {}) - {} / {b0}", a[0], c.u(0), z[0], a[1], c.u(1), z[1], z[2])
        } else {
            c.equation("u = alpha1 (r1 - z1) - z2 / b0, limited to [lower, upper]");
            format!("{} * ({} - {}) - {} / {b0}", a[0], c.u(0), z[0], z[1])
        };
        let u = if self.lower == f64::NEG_INFINITY && self.upper == f64::INFINITY {
            u
        } else {
            let clamp = c.clamp();
            format!("{clamp}({u}, {}, {})", c.num(self.lower), c.num(self.upper))
        };
        c.output(format!("{} = {u};", c.y(0)));
        Ok(())
    }
}

fn build_lsef(p: &mut Params) -> Result<Built, Diagnostic> {
    let order = p.count("order", 3)?;
    if order > 2 {
        return Err(p.error("order", format!("orders 1 and 2 are supported, got {order}")));
    }
    let alpha = p.vector("alpha")?;
    if alpha.len() != order {
        return Err(p.error("alpha", format!("needs {order} gain(s) for order {order}, got {}", alpha.len())));
    }
    let b0 = p.number_where("b0", None, |v| v != 0.0 && v.is_finite(), "a nonzero input gain")?;
    let (lower, upper) = crate::nonlinear::limits(p, "lower", "upper")?;
    let mut iface = Interface::new(p.sample_time()?).piecewise_constant().input("r1", Width::Fixed(1), true);
    if order == 2 {
        iface = iface.input("r2", Width::Fixed(1), true);
    }
    let z_port = iface.inputs.len();
    iface = iface.input("z", Width::Fixed(order + 1), true);
    let alpha_ports = if order == 2 {
        crate::gain_inputs(p, ["alpha1", "alpha2"], &mut iface)?
    } else {
        let [a1] = crate::gain_inputs(p, ["alpha1"], &mut iface)?;
        [a1, None]
    };
    let alpha = [alpha[0], alpha.get(1).copied().unwrap_or(0.0)];
    let block = Lsef { alpha, alpha_ports, b0, order, z_port, lower, upper };
    Ok(Built::new(block, iface.output("u", Width::Fixed(1))))
}

#[cfg(test)]
mod tests;
