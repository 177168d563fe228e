//! Force control: target impedance, the contact-force geometry of a probe
//! on a surface (normal force from a force sensor; a penalty-contact
//! environment), a current-controlled feed drive, and a second-order
//! reference filter that supplies smooth derivatives.

use crate::discrete::DiscreteLti;
use crate::table::*;
use ctlgraph_core::expr::Expr;
use ctlgraph_core::params::{VarScope, expr_diagnostic};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::yaml::Kind;
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, SampleTime, Width};
use ctlgraph_solver::tf2ss;

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "impedance",
        category: "force",
        summary: "Target impedance m·x'' + b·x' + k·x = e: force error in, position correction out.",
        doc: "Continuous (sample_time 0): states [x, x'] integrated by the solver, no direct \
              feedthrough. Discrete (sample_time T > 0), derived with the period T from \
              X/E = 1/(m s² + b s + k):\n\
              \x20 backward_euler (s = (1 − z⁻¹)/T): (m/T² + b/T + k)·x(k) = e(k) + (2m/T² + b/T)·x(k−1) − (m/T²)·x(k−2);\n\
              \x20 bilinear (s = (2/T)(1 − z⁻¹)/(1 + z⁻¹), the default): X/E = (1 + 2z⁻¹ + z⁻²)/(a0 + a1 z⁻¹ + a2 z⁻²), \
              a0 = m c² + b c + k, a1 = 2k − 2m c², a2 = m c² − b c + k, c = 2/T.\n\
              The contact-force paper's eq. 11–12 drops T and has sign slips; these are the forms \
              derived properly. Both discrete forms have direct feedthrough. Units: x in the length \
              unit of k (k in N/mm gives x in mm).\n\
              `hold_input: true` adds a `hold` input: while it is nonzero the filter's state stands \
              still and its output holds its last value (conditional integration: anti-windup while \
              the drive saturates, or a force loop kept open until contact).\n\
              Stable region: m, b, k > 0 (every form; bilinear preserves stability for every T, \
              backward Euler too). The step response settles at e/k.",
        inputs: &[
            PortDoc { name: "e", doc: "force error (scalar)" },
            PortDoc { name: "hold", doc: "with `hold_input: true`: nonzero freezes the filter" },
        ],
        outputs: &[PortDoc { name: "x", doc: "position correction" }],
        params: &[
            param("m", Required, "target mass, > 0").kind(ParamKind::Number),
            param("b", Required, "target damping, > 0").kind(ParamKind::Number),
            param("k", Required, "target stiffness, > 0").kind(ParamKind::Number),
            param("method", Word("bilinear"), "discrete form: bilinear | backward_euler")
                .options(&["bilinear", "backward_euler"]),
            param("hold_input", Flag(false), "true adds the `hold` input (conditional integration)"),
            param("sample_time", Number(0.0), "0 continuous, T > 0 discrete").kind(ParamKind::SampleTime),
        ],
        build: build_impedance,
    },
    BlockType {
        name: "normal_force",
        category: "force",
        summary: "Normal contact force from a force sensor's fx, fz with Coulomb friction.",
        doc: "The contact-force paper's eq. 1–4, with ρ = fx/fz:\n\
              \x20 climbing:   θ = atan((ρ − μu)/(ρ·μu + 1)),  fn = fz/(cos θ − μu·sin θ)\n\
              \x20 descending: θ = atan((μd − ρ)/(ρ·μd + 1)),  fn = fz/(cos θ + μd·sin θ)\n\
              θ is the surface angle: atan(ρ) is the direction of the measured force, atan(μ) the \
              friction angle. fx is the horizontal force against the scanning direction, fz the \
              vertical (pressing) force. Climbing or descending is chosen by the `climbing` input \
              (>= 0.5: climbing) or, with `select: slope`, by the sign of the `slope` input (> 0: \
              climbing, as the `contact` block's slope output). With μ = 0, fn = sqrt(fx² + fz²). \
              fz <= 0 (no contact) gives 0.",
        inputs: &[
            PortDoc { name: "fx", doc: "horizontal force against the motion [N]" },
            PortDoc { name: "fz", doc: "vertical force [N]" },
            PortDoc { name: "climbing | slope", doc: "see `select`" },
        ],
        outputs: &[PortDoc { name: "fn", doc: "normal force [N]" }],
        params: &[
            param("mu_u", Required, "friction coefficient when climbing").kind(ParamKind::Number),
            param("mu_d", Described("mu_u"), "friction coefficient when descending").kind(ParamKind::Number),
            param("select", Word("climbing"), "climbing (a 0/1 input) | slope (a surface-slope input)")
                .options(&["climbing", "slope"]),
            crate::SAMPLE_TIME_INHERITED,
        ],
        build: build_normal_force,
    },
    BlockType {
        name: "contact",
        category: "force",
        summary: "Penalty contact of a probe with a surface z = profile(x), with Coulomb friction.",
        doc: "Probe at (x, z) moving with (vx, vz); surface z_s = p(x) with slope p'. Normal \
              penetration δ = (p(x) − z)/sqrt(1 + p'²) and its rate δ' = (p'·vx − vz)/sqrt(1 + p'²); \
              normal force N = max(0, k_e·δ + c_e·δ') when δ > 0, else 0 (the damper never pulls: \
              no sticking when contact opens). Friction μ·N along the tangent, against the tangential \
              sliding velocity (zero when it is zero). Outputs the force sensor's view: fz = vertical \
              force on the probe (pressing: positive), fx = horizontal force on the probe against +x \
              (resisting the scan: positive), so `normal_force` recovers N; also N itself and the \
              slope p'. The profile is an expression of x (`profile: \"25*(1 - cos(pi*x/250))\"`), \
              or a table (`profile_x`, `profile_z`, linear), or a CSV file (`profile_file` with \
              columns x and z). Slopes of an expression by central differences.\n\
              Modes: pressing or free, chosen at major steps; zero crossings of δ (onset) and of \
              k_e·δ + c_e·δ' (release, where the damper would pull) end the step there, so contact \
              starts and ends at its located time instead of inside a step. Friction's direction is a \
              plain function of the sliding velocity (no mode: a sticking probe would chatter).\n\
              Bounds: N >= 0 at major steps; N = 0 out of contact.",
        inputs: &[
            PortDoc { name: "x", doc: "probe position along the surface" },
            PortDoc { name: "z", doc: "probe height" },
            PortDoc { name: "vx", doc: "probe velocity along x" },
            PortDoc { name: "vz", doc: "probe velocity along z" },
        ],
        outputs: &[
            PortDoc { name: "fx", doc: "horizontal force against +x [N]" },
            PortDoc { name: "fz", doc: "vertical force on the probe [N]" },
            PortDoc { name: "fn", doc: "true normal force [N]" },
            PortDoc { name: "slope", doc: "surface slope p'(x)" },
        ],
        params: &[
            param(
                "profile",
                Required,
                "surface height as an expression of x (or profile_x/profile_z, or profile_file)",
            ),
            param("profile_x", Required, "table breakpoints (instead of `profile`)").kind(ParamKind::Numbers),
            param("profile_z", Required, "table heights").kind(ParamKind::Numbers),
            param("profile_file", Required, "CSV with columns x and z (instead of `profile`)"),
            crate::tables::MAX_FILE_MIB,
            param("stiffness", Required, "k_e [N per length unit]").kind(ParamKind::Number),
            param("damping", Number(0.0), "c_e [N per (length unit/s)]"),
            param("mu", Number(0.0), "Coulomb friction coefficient"),
        ],
        build: build_contact,
    },
    BlockType {
        name: "feed_drive",
        category: "force",
        summary: "Current-controlled ball-screw axis Je·x'' + Be·x' = u − d.",
        doc: "The contact-force paper's eq. 13, x the axis position. Give Je and Be directly, or the \
              physical parameters: Je = J/(Ka·Kt·rg), Be = B/(Ka·Kt·rg), with Ka [A/V] the current \
              amplifier gain, Kt [N·m/A] the torque constant, J [kg·m²] and B [N·m·s] the inertia and \
              viscous friction at the motor, rg [mm/rad] the screw lead per radian. Then x is in mm, \
              u and d in V, Je in V/(mm/s²), Be in V/(mm/s); d = Td/(Ka·Kt) is a load torque seen \
              as a voltage. `d` is an input port when `disturbance_input: true`, else 0.\n\
              Bounds: Je, Be > 0: |x'| <= |x'(0)| + sup|u − d|/Be.",
        inputs: &[
            PortDoc { name: "u", doc: "command voltage [V]" },
            PortDoc { name: "d", doc: "disturbance [V] (with disturbance_input: true)" },
        ],
        outputs: &[PortDoc { name: "x", doc: "position" }, PortDoc { name: "v", doc: "velocity" }],
        params: &[
            param("je", Required, "equivalent inertia Je (or give j, ka, kt, rg)").kind(ParamKind::Number),
            param("be", Required, "equivalent damping Be (or give b, ka, kt, rg)").kind(ParamKind::Number),
            param("j", Required, "motor-side inertia J").kind(ParamKind::Number).unit("kg·m²"),
            param("b", Required, "motor-side viscous friction B").kind(ParamKind::Number).unit("N·m·s"),
            param("ka", Required, "amplifier gain Ka").kind(ParamKind::Number).unit("A/V"),
            param("kt", Required, "torque constant Kt").kind(ParamKind::Number).unit("N·m/A"),
            param("rg", Required, "screw lead per radian rg").kind(ParamKind::Number).unit("mm/rad"),
            param("initial", Numbers(&[0.0, 0.0]), "[x(0), x'(0)]"),
            param("disturbance_input", Flag(false), "add the input port d"),
        ],
        build: build_feed_drive,
    },
    BlockType {
        name: "reference_filter",
        category: "force",
        summary: "Second-order reference filter with smooth first and second derivatives.",
        doc: "p'' = ωn²·(u − p) − 2ζωn·p'. Outputs p (the filtered reference), its derivative p' \
              and second derivative p'' (which depends on u directly). Use it to give controllers \
              that need xr', xr'' (sliding mode) smooth derivatives of a reference.\n\
              Stable region: ωn > 0, ζ > 0; unit DC gain.",
        inputs: &[PortDoc { name: "u", doc: "raw reference" }],
        outputs: &[
            PortDoc { name: "x", doc: "filtered reference" },
            PortDoc { name: "dx", doc: "its derivative" },
            PortDoc { name: "ddx", doc: "its second derivative" },
        ],
        params: &[
            param("omega", Required, "natural frequency ωn").kind(ParamKind::Number).unit("rad/s"),
            param("zeta", Number(1.0), "damping ratio"),
            param("initial", Number(0.0), "p(0)"),
        ],
        build: build_reference_filter,
    },
];

/// m x'' + b x' + k x = e, continuous.
#[derive(Clone)]
pub struct Impedance {
    m: f64,
    b: f64,
    k: f64,
}

impl Block for Impedance {
    rust_type!(Impedance);
    fn num_states(&self) -> usize {
        2
    }
    fn output(&mut self, io: &mut Io) {
        io.set(0, io.x[0]);
    }
    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        let held = io.num_inputs() > 1 && io.u(1) != 0.0;
        dx[0] = if held { 0.0 } else { io.x[1] };
        dx[1] = if held { 0.0 } else { (io.u(0) - self.b * io.x[1] - self.k * io.x[0]) / self.m };
    }
}

/// A discrete filter whose state stands still and output holds while its
/// `hold` input (port 1) is nonzero.
#[derive(Clone)]
pub struct Holdable {
    filter: DiscreteLti,
    last: f64,
}

impl Block for Holdable {
    rust_type!(Holdable);
    /// The filter's model while not held (the hold input enters nowhere).
    fn discrete_lti(&self) -> Option<ctlgraph_solver::StateSpace> {
        let ss = self.filter.discrete_lti()?;
        let widen = |m: &[f64], rows: usize| -> Vec<f64> { (0..rows).flat_map(|r| [m[r], 0.0]).collect() };
        Some(ctlgraph_solver::StateSpace { m: 2, b: widen(&ss.b, ss.n), d: widen(&ss.d, ss.p), ..ss })
    }

    fn initialize(&mut self, x0: &mut [f64]) {
        self.filter.initialize(x0);
        self.last = 0.0;
    }
    fn output(&mut self, io: &mut Io) {
        if io.u(1) == 0.0 {
            self.filter.output(io);
            self.last = io.output(0)[0];
        } else {
            io.set(0, self.last);
        }
    }
    fn update(&mut self, io: &mut Io) {
        if io.u(1) == 0.0 {
            self.filter.update(io);
        }
    }
}

/// Numerator and denominator (descending powers of z) of the discrete
/// impedance X/E for period `t`.
pub fn discrete_impedance(m: f64, b: f64, k: f64, t: f64, bilinear: bool) -> (Vec<f64>, Vec<f64>) {
    if bilinear {
        let c = 2.0 / t;
        (vec![1.0, 2.0, 1.0], vec![m * c * c + b * c + k, 2.0 * k - 2.0 * m * c * c, m * c * c - b * c + k])
    } else {
        let (mt, bt) = (m / (t * t), b / t);
        (vec![1.0, 0.0, 0.0], vec![mt + bt + k, -2.0 * mt - bt, mt])
    }
}

fn build_impedance(p: &mut Params) -> Result<Built, Diagnostic> {
    let (m, b, k) = (p.positive("m")?, p.positive("b")?, p.positive("k")?);
    let bilinear = p.choice("method", &["bilinear", "backward_euler"])? == "bilinear";
    let hold = p.flag("hold_input")?;
    let (st, period) = p.continuous_or_discrete()?;
    let mut iface = Interface::new(st).input("e", Width::Fixed(1), period.is_some());
    if hold {
        iface = iface.input("hold", Width::Fixed(1), period.is_some());
    }
    let iface = iface.output("x", Width::Fixed(1));
    match period {
        None => Ok(Built::new(Impedance { m, b, k }, iface)),
        Some(period) => {
            let (num, den) = discrete_impedance(m, b, k, period, bilinear);
            let filter = DiscreteLti::new(tf2ss(&num, &den).map_err(|e| p.error("m", e))?);
            if hold { Ok(Built::new(Holdable { filter, last: 0.0 }, iface)) } else { Ok(Built::new(filter, iface)) }
        }
    }
}

/// The normal force of eq. 1–4 (see the block doc).
pub fn normal_force(fx: f64, fz: f64, climbing: bool, mu_u: f64, mu_d: f64) -> f64 {
    if fz <= 0.0 {
        return 0.0;
    }
    let rho = fx / fz;
    if climbing {
        let theta = ((rho - mu_u) / (rho * mu_u + 1.0)).atan();
        fz / (theta.cos() - mu_u * theta.sin())
    } else {
        let theta = ((mu_d - rho) / (rho * mu_d + 1.0)).atan();
        fz / (theta.cos() + mu_d * theta.sin())
    }
}

#[derive(Clone)]
pub struct NormalForce {
    mu_u: f64,
    mu_d: f64,
    by_slope: bool,
}

impl Block for NormalForce {
    rust_type!(NormalForce);
    fn updates(&self) -> bool {
        false
    }
    fn output(&mut self, io: &mut Io) {
        let selector = io.u(2);
        let climbing = if self.by_slope { selector > 0.0 } else { selector >= 0.5 };
        io.set(0, normal_force(io.u(0), io.u(1), climbing, self.mu_u, self.mu_d));
    }
}

fn build_normal_force(p: &mut Params) -> Result<Built, Diagnostic> {
    let mu_u = p.number_where("mu_u", None, |v| (0.0..1.0).contains(&v), "in [0, 1)")?;
    let mu_d = p.number_where("mu_d", Some(mu_u), |v| (0.0..1.0).contains(&v), "in [0, 1)")?;
    let by_slope = p.choice("select", &["climbing", "slope"])? == "slope";
    let iface = Interface::new(p.sample_time()?)
        .piecewise_constant()
        .input("fx", Width::Fixed(1), true)
        .input("fz", Width::Fixed(1), true)
        .input(if by_slope { "slope" } else { "climbing" }, Width::Fixed(1), true)
        .output("fn", Width::Fixed(1));
    Ok(Built::new(NormalForce { mu_u, mu_d, by_slope }, iface))
}

/// A surface height profile and its slope.
#[derive(Clone)]
enum Profile {
    Expr { expr: Expr, step: f64 },
    Table(crate::tables::Table),
}

impl Profile {
    fn height(&self, x: f64) -> f64 {
        match self {
            Profile::Expr { expr, .. } => expr.eval(&[x]),
            Profile::Table(t) => t.eval(x),
        }
    }

    fn slope(&self, x: f64) -> f64 {
        let h = match self {
            Profile::Expr { step, .. } => *step,
            Profile::Table(_) => 1e-9 * x.abs().max(1.0),
        };
        (self.height(x + h) - self.height(x - h)) / (2.0 * h)
    }
}

/// Contact forces of a probe on the profile (see the block doc).
#[derive(Clone)]
pub struct Contact {
    profile: Profile,
    stiffness: f64,
    damping: f64,
    mu: f64,
    /// The mode: pressing (δ > 0 and k_e·δ + c_e·δ' > 0) or free.
    pressing: bool,
}

impl Contact {
    fn new(profile: Profile, stiffness: f64, damping: f64, mu: f64) -> Self {
        Contact { profile, stiffness, damping, mu, pressing: false }
    }

    /// Penetration δ, its rate δ' and the slope p' at probe position and velocity.
    fn penetration(&self, x: f64, z: f64, vx: f64, vz: f64) -> (f64, f64, f64) {
        let slope = self.profile.slope(x);
        let norm = (1.0 + slope * slope).sqrt();
        ((self.profile.height(x) - z) / norm, (slope * vx - vz) / norm, slope)
    }

    /// (fx, fz, N, slope) for probe position and velocity, the mode chosen
    /// from them.
    pub fn forces(&self, x: f64, z: f64, vx: f64, vz: f64) -> (f64, f64, f64, f64) {
        self.forces_in_mode(x, z, vx, vz, None)
    }

    /// As [`Contact::forces`]; with `pressing` given, in that mode (frozen
    /// inside a solver step: pressing, N = k_e·δ + c_e·δ' whatever its sign).
    fn forces_in_mode(&self, x: f64, z: f64, vx: f64, vz: f64, pressing: Option<bool>) -> (f64, f64, f64, f64) {
        let (depth, rate, slope) = self.penetration(x, z, vx, vz);
        let push = self.stiffness * depth + self.damping * rate;
        let pressing = pressing.unwrap_or(depth > 0.0 && push > 0.0);
        let n = if pressing { push } else { 0.0 };
        let norm = (1.0 + slope * slope).sqrt();
        // Unit normal (out of the surface) and tangent (along +x).
        let (nx, nz) = (-slope / norm, 1.0 / norm);
        let (tx, tz) = (1.0 / norm, slope / norm);
        let v_t = vx * tx + vz * tz;
        let friction = -self.mu * n * crate::math::sign(v_t);
        let (force_x, force_z) = (n * nx + friction * tx, n * nz + friction * tz);
        (-force_x, force_z, n, slope)
    }
}

impl Block for Contact {
    rust_type!(Contact);
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.pressing = false;
    }

    fn output(&mut self, io: &mut Io) {
        let (x, z, vx, vz) = (io.u(0), io.u(1), io.u(2), io.u(3));
        let frozen = (!io.may_switch()).then_some(self.pressing);
        let (fx, fz, n, slope) = self.forces_in_mode(x, z, vx, vz, frozen);
        if frozen.is_none() {
            self.pressing = n > 0.0;
        }
        io.set(0, fx);
        io.set(1, fz);
        io.set(2, n);
        io.set(3, slope);
    }

    fn num_zero_crossings(&self) -> usize {
        2
    }

    /// The onset and release of contact: δ, and k_e·δ + c_e·δ' (where the
    /// damper would start to pull).
    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        let (depth, rate, _) = self.penetration(io.u(0), io.u(1), io.u(2), io.u(3));
        g[0] = depth;
        g[1] = self.stiffness * depth + self.damping * rate;
    }
}

fn build_profile(p: &mut Params) -> Result<Profile, Diagnostic> {
    if let Some(v) = p.raw("profile") {
        let (text, pos) = match &v.kind {
            Kind::Str(s) => (s.clone(), v.pos.clone()),
            Kind::Num(n) => (n.to_string(), v.pos.clone()),
            _ => return Err(p.error("profile", "expected an expression of x")),
        };
        let scope = VarScope { vars: &["x"], params: p.scope() };
        let expr = Expr::parse(&text, &scope).map_err(|e| expr_diagnostic(&e, &pos))?;
        return Ok(Profile::Expr { expr, step: 1e-6 });
    }
    let outside = crate::tables::Outside::Clamp;
    if p.has("profile_x") {
        let (xs, zs) = (p.vector("profile_x")?, p.vector("profile_z")?);
        let table = crate::tables::Table::new(xs, zs, outside).map_err(|m| p.error("profile_z", m))?;
        return Ok(Profile::Table(table));
    }
    if p.has("profile_file") {
        let path = p.path("profile_file")?;
        let limit = crate::tables::data_file_limit(p)?;
        let (xs, zs) = crate::tables::read_columns(&path, "x", "z", limit).map_err(|m| p.error("profile_file", m))?;
        let table = crate::tables::Table::new(xs, zs, outside).map_err(|m| p.error("profile_file", m))?;
        return Ok(Profile::Table(table));
    }
    Err(p.block_error("needs a surface: `profile` (an expression of x), `profile_x`/`profile_z`, or `profile_file`"))
}

fn build_contact(p: &mut Params) -> Result<Built, Diagnostic> {
    let profile = build_profile(p)?;
    let stiffness = p.positive("stiffness")?;
    let damping = p.number_where("damping", None, |v| v >= 0.0 && v.is_finite(), "a damping >= 0")?;
    let mu = p.number_where("mu", None, |v| (0.0..1.0).contains(&v), "in [0, 1)")?;
    let mut iface = Interface::new(SampleTime::Continuous);
    for name in ["x", "z", "vx", "vz"] {
        iface = iface.input(name, Width::Fixed(1), true);
    }
    for name in ["fx", "fz", "fn", "slope"] {
        iface = iface.output(name, Width::Fixed(1));
    }
    Ok(Built::new(Contact::new(profile, stiffness, damping, mu), iface))
}

/// Je x'' + Be x' = u − d.
#[derive(Clone)]
pub struct FeedDrive {
    je: f64,
    be: f64,
    x0: [f64; 2],
    disturbance: bool,
}

impl Block for FeedDrive {
    rust_type!(FeedDrive);
    fn num_states(&self) -> usize {
        2
    }
    fn initialize(&mut self, x0: &mut [f64]) {
        x0.copy_from_slice(&self.x0);
    }
    fn output(&mut self, io: &mut Io) {
        io.set(0, io.x[0]);
        io.set(1, io.x[1]);
    }
    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        let d = if self.disturbance { io.u(1) } else { 0.0 };
        dx[0] = io.x[1];
        dx[1] = (io.u(0) - d - self.be * io.x[1]) / self.je;
    }
}

fn build_feed_drive(p: &mut Params) -> Result<Built, Diagnostic> {
    let (je, be) = if p.has("je") || p.has("be") {
        (p.positive("je")?, p.positive("be")?)
    } else {
        let (ka, kt, rg) = (p.positive("ka")?, p.positive("kt")?, p.positive("rg")?);
        let scale = ka * kt * rg;
        (p.positive("j")? / scale, p.positive("b")? / scale)
    };
    let init = p.vector("initial")?;
    let [x, v] = init[..] else { return Err(p.error("initial", "expected [x(0), x'(0)]")) };
    let disturbance = p.flag("disturbance_input")?;
    let mut iface = Interface::new(SampleTime::Continuous).input("u", Width::Fixed(1), false);
    if disturbance {
        iface = iface.input("d", Width::Fixed(1), false);
    }
    let iface = iface.output("x", Width::Fixed(1)).output("v", Width::Fixed(1));
    Ok(Built::new(FeedDrive { je, be, x0: [x, v], disturbance }, iface))
}

/// p'' = ωn²(u − p) − 2ζωn p'.
#[derive(Clone)]
pub struct ReferenceFilter {
    omega: f64,
    zeta: f64,
    initial: f64,
}

impl ReferenceFilter {
    fn accel(&self, u: f64, x: &[f64]) -> f64 {
        self.omega * self.omega * (u - x[0]) - 2.0 * self.zeta * self.omega * x[1]
    }
}

impl Block for ReferenceFilter {
    rust_type!(ReferenceFilter);
    fn num_states(&self) -> usize {
        2
    }
    fn initialize(&mut self, x0: &mut [f64]) {
        x0[0] = self.initial;
        x0[1] = 0.0;
    }
    fn output(&mut self, io: &mut Io) {
        io.set(0, io.x[0]);
        io.set(1, io.x[1]);
        let a = self.accel(io.u(0), io.x);
        io.set(2, a);
    }
    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        dx[0] = io.x[1];
        dx[1] = self.accel(io.u(0), io.x);
    }
}

fn build_reference_filter(p: &mut Params) -> Result<Built, Diagnostic> {
    let omega = p.positive("omega")?;
    let zeta = p.number_where("zeta", None, |v| v > 0.0 && v.is_finite(), "positive")?;
    let initial = p.number("initial")?;
    let iface = Interface::new(SampleTime::Continuous)
        .input("u", Width::Fixed(1), true)
        .output("x", Width::Fixed(1))
        .output("dx", Width::Fixed(1))
        .output("ddx", Width::Fixed(1));
    Ok(Built::new(ReferenceFilter { omega, zeta, initial }, iface))
}

#[cfg(test)]
mod tests;
