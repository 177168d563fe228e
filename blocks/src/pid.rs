//! The PID controller: parallel form with a filtered derivative, output
//! limits with anti-windup, continuous or discrete, and optional gain
//! input ports for gain scheduling.

use crate::table::*;
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};

pub const TYPES: &[BlockType] = &[BlockType {
    name: "pid",
    category: "control",
    summary: "PID controller: parallel form, filtered derivative, limits with anti-windup.",
    doc: "u = sat(kp·e + I + D) with\n\
          \x20 I' = ki·e (+ anti-windup),  D = kd·N·(e − x_f),  x_f' = N·(e − x_f),\n\
          i.e. C(s) = kp + ki/s + kd·N·s/(s + N). The integrator holds ∫ki·e (not ∫e), so changing ki \
          through its port does not make the output jump. Anti-windup while the output is limited: \
          `clamping` stops integrating when ki·e would drive the output further into the limit (decided at each major step and held through the solver's stages, so an adaptive solver does not chatter on the limit); \
          `back_calculation` adds kb·(u − v) to I' (v the unlimited output); `none` does neither.\n\
          Discrete (sample_time T > 0): I(k+1) = I(k) + T·(ki·e(k) + anti-windup) (forward Euler, \
          Simulink's default), and the filter by backward Euler, x_f(k) = (x_f(k−1) + N·T·e(k))/(1 + N·T), \
          which is stable for every N·T.\n\
          `gain_inputs: [kp, ki]` adds input ports of those names whose values replace the parameters \
          at every step (gain scheduling, fuzzy tuning).\n\
              Bounds: lower <= u <= upper for any gains, input and anti-windup mode; with ki = 0 and limits infinite, |u| <= (kp + 2·kd·N)·sup|e|.",
    inputs: &[
        PortDoc { name: "e", doc: "control error (scalar)" },
        PortDoc { name: "kp, ki, kd", doc: "only those listed in `gain_inputs`" },
    ],
    outputs: &[PortDoc { name: "u", doc: "control signal (scalar)" }],
    params: &[
        param("kp", Number(1.0), "proportional gain"),
        param("ki", Number(0.0), "integral gain").unit("1/s"),
        param("kd", Number(0.0), "derivative gain").unit("s"),
        param("n", Number(100.0), "derivative filter coefficient N").unit("rad/s"),
        param("lower", Number(f64::NEG_INFINITY), "lower output limit"),
        param("upper", Number(f64::INFINITY), "upper output limit"),
        param("anti_windup", Word("clamping"), "clamping | back_calculation | none").options(&[
            "clamping",
            "back_calculation",
            "none",
        ]),
        param("kb", Number(1.0), "back-calculation gain").unit("1/s"),
        param("initial", Number(0.0), "initial integrator output I(0)"),
        param("gain_inputs", Described("[]"), "gains read from input ports each step: any of kp, ki, kd")
            .kind(ParamKind::Words),
        param("sample_time", Number(0.0), "0 continuous, T > 0 discrete").kind(ParamKind::SampleTime),
    ],
    build: build_pid,
}];

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AntiWindup {
    Clamping,
    BackCalculation { kb: f64 },
    None,
}

/// Gains, limits and anti-windup, shared by both forms.
#[derive(Clone, Debug)]
pub struct PidLaw {
    pub kp: f64,
    pub ki: f64,
    pub kd: f64,
    pub n: f64,
    pub lower: f64,
    pub upper: f64,
    pub anti_windup: AntiWindup,
    /// Input port of kp, ki, kd when they come from a port.
    pub gain_ports: [Option<usize>; 3],
}

impl PidLaw {
    #[inline(always)]
    fn gains(&self, io: &Io) -> [f64; 3] {
        let g = [self.kp, self.ki, self.kd];
        if self.gain_ports == [None; 3] {
            return g; // fixed gains, the common case: one test, not one per gain
        }
        std::array::from_fn(|i| self.gain_ports[i].map_or(g[i], |p| io.u(p)))
    }

    /// The integrator's input: ki·e with anti-windup, given the unlimited
    /// output `v` and the limited `u`.
    #[inline(always)]
    fn integrand(&self, ki_e: f64, v: f64, u: f64) -> f64 {
        match self.anti_windup {
            AntiWindup::None => ki_e,
            AntiWindup::BackCalculation { kb } => ki_e + kb * (u - v),
            AntiWindup::Clamping => {
                // At or beyond a limit and integrating further into it.
                let pushing = (v >= self.upper && ki_e > 0.0) || (v <= self.lower && ki_e < 0.0);
                if pushing { 0.0 } else { ki_e }
            }
        }
    }
}

/// Continuous PID: states [I, x_f] integrated by the solver. The clamping
/// decision is taken at major steps and held through the solver's stages:
/// decided per stage, it makes the right-hand side switch with the state,
/// and an adaptive solver chatters on the limit with ever smaller steps.
#[derive(Clone)]
pub struct ContinuousPid {
    law: PidLaw,
    initial: f64,
    /// Integration stopped by clamping anti-windup (decided at major steps).
    holding: bool,
}

impl ContinuousPid {
    /// (v, u, ki·e): unlimited and limited output.
    #[inline(always)]
    fn eval(&self, io: &Io) -> (f64, f64, f64) {
        let [kp, ki, kd] = self.law.gains(io);
        let e = io.u(0);
        let v = kp * e + io.x[0] + kd * self.law.n * (e - io.x[1]);
        (v, v.clamp(self.law.lower, self.law.upper), ki * e)
    }
}

impl Block for ContinuousPid {
    rust_type!(ContinuousPid);
    fn num_states(&self) -> usize {
        2
    }
    fn initialize(&mut self, x0: &mut [f64]) {
        x0[0] = self.initial;
        x0[1] = 0.0;
        self.holding = false;
    }
    #[inline(always)]
    fn output(&mut self, io: &mut Io) {
        let (_, u, _) = self.eval(io);
        io.set(0, u);
    }
    #[inline(always)]
    fn update(&mut self, io: &mut Io) {
        let (v, u, ki_e) = self.eval(io);
        self.holding =
            self.law.anti_windup == AntiWindup::Clamping && self.law.integrand(ki_e, v, u) == 0.0 && ki_e != 0.0;
    }
    #[inline(always)]
    fn derivatives(&mut self, io: &Io, dx: &mut [f64]) {
        let e = io.u(0);
        dx[0] = match self.law.anti_windup {
            AntiWindup::Clamping if self.holding => 0.0,
            // Clamping was decided at the major step: ki·e, no output needed.
            AntiWindup::Clamping => self.law.gains(io)[1] * e,
            _ => {
                let (v, u, ki_e) = self.eval(io);
                self.law.integrand(ki_e, v, u)
            }
        };
        dx[1] = self.law.n * (e - io.x[1]);
    }
}

/// Discrete PID: forward-Euler integral, backward-Euler derivative filter.
#[derive(Clone)]
pub struct DiscretePid {
    law: PidLaw,
    period: f64,
    initial: f64,
    integral: f64,
    filter: f64,
}

impl DiscretePid {
    /// (v, u, ki·e, new filter state).
    fn eval(&self, io: &Io) -> (f64, f64, f64, f64) {
        let [kp, ki, kd] = self.law.gains(io);
        let e = io.u(0);
        let nt = self.law.n * self.period;
        let filter = (self.filter + nt * e) / (1.0 + nt);
        let v = kp * e + self.integral + kd * self.law.n * (e - filter);
        (v, v.clamp(self.law.lower, self.law.upper), ki * e, filter)
    }
}

impl Block for DiscretePid {
    rust_type!(DiscretePid);
    /// Unsaturated, fixed gains: state [integral, filter], input e.
    /// With a = 1/(1 + N·T): filter⁺ = a·filter + (1 − a)·e,
    /// integral⁺ = integral + T·ki·e, u = integral − kd·N·a·filter + (kp + kd·N·a)·e.
    fn discrete_lti(&self) -> Option<ctlgraph_solver::StateSpace> {
        let l = &self.law;
        if l.gain_ports.iter().any(Option::is_some) {
            return None;
        }
        let a = 1.0 / (1.0 + l.n * self.period);
        let kdn = l.kd * l.n;
        Some(ctlgraph_solver::StateSpace {
            n: 2,
            m: 1,
            p: 1,
            a: vec![1.0, 0.0, 0.0, a],
            b: vec![self.period * l.ki, 1.0 - a],
            c: vec![1.0, -kdn * a],
            d: vec![l.kp + kdn * a],
        })
    }

    fn initialize(&mut self, _x0: &mut [f64]) {
        self.integral = self.initial;
        self.filter = 0.0;
    }
    fn output(&mut self, io: &mut Io) {
        let (_, u, _, _) = self.eval(io);
        io.set(0, u);
    }
    fn update(&mut self, io: &mut Io) {
        let (v, u, ki_e, filter) = self.eval(io);
        self.integral += self.period * self.law.integrand(ki_e, v, u);
        self.filter = filter;
    }
    /// [`DiscretePid::eval`] in the output and again in the update (as
    /// the block does), then [`PidLaw::integrand`] for the anti-windup.
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let l = &self.law;
        c.equation("x_f = (x_f(k-1) + N T e)/(1 + N T);  v = kp e + I + kd N (e - x_f);  u = sat(v)");
        c.equation(match l.anti_windup {
            AntiWindup::Clamping => "I(k+1) = I + T ki e, held while ki e pushes v further past a limit (clamping)",
            AntiWindup::BackCalculation { .. } => "I(k+1) = I + T (ki e + kb (u - v)) (back-calculation)",
            AntiWindup::None => "I(k+1) = I + T ki e",
        });
        let integral = c.state("integral", &[self.initial]);
        let filter = c.state("filter", &[0.0]);
        let fixed = [l.kp, l.ki, l.kd];
        let g: Vec<String> = (0..3).map(|i| l.gain_ports[i].map_or(c.num(fixed[i]), |p| c.u(p).to_string())).collect();
        let (real, e) = (c.real(), c.u(0).to_string());
        let nt = c.num(l.n * self.period);
        let limited = if l.lower == f64::NEG_INFINITY && l.upper == f64::INFINITY {
            "v".to_string()
        } else {
            format!("{}(v, {}, {})", c.clamp(), c.num(l.lower), c.num(l.upper))
        };
        let eval = format!(
            "{real} xf = ({filter} + {nt} * {e}) / ({one} + {nt});\n\
             {real} v = {kp} * {e} + {integral} + {kd} * {n} * ({e} - xf);\n{real} u = {limited};",
            one = c.num(1.0),
            kp = g[0],
            kd = g[2],
            n = c.num(l.n),
        );
        c.output(format!("{eval}\n{} = u;", c.y(0)));
        let ki_e = format!("{} * {e}", g[1]);
        let integrand = match l.anti_windup {
            AntiWindup::None => "ki_e".to_string(),
            AntiWindup::BackCalculation { kb } => format!("ki_e + {} * (u - v)", c.num(kb)),
            AntiWindup::Clamping => format!(
                "((v >= {upper} && ki_e > {zero}) || (v <= {lower} && ki_e < {zero})) ? {zero} : ki_e",
                upper = c.num(l.upper),
                lower = c.num(l.lower),
                zero = c.num(0.0)
            ),
        };
        c.update(format!(
            "{eval}\n{real} ki_e = {ki_e};\n(void)u;\n(void)v;\n{integral} += {period} * ({integrand});\n{filter} = xf;",
            period = c.num(self.period)
        ));
        Ok(())
    }
}

fn build_pid(p: &mut Params) -> Result<Built, Diagnostic> {
    let (kp, ki, kd) = (p.number("kp")?, p.number("ki")?, p.number("kd")?);
    let n = p.number_where("n", None, |v| v > 0.0 && v.is_finite(), "a positive filter coefficient")?;
    let (lower, upper) = crate::nonlinear::limits(p, "lower", "upper")?;
    let kb = p.number("kb")?;
    let anti_windup = match p.choice("anti_windup", &["clamping", "back_calculation", "none"])? {
        "back_calculation" => AntiWindup::BackCalculation { kb },
        "none" => AntiWindup::None,
        _ => AntiWindup::Clamping,
    };
    let initial = p.number("initial")?;
    let (st, period) = p.continuous_or_discrete()?;
    let mut iface = Interface::new(st).input("e", Width::Fixed(1), true);
    let gain_ports = crate::gain_inputs(p, ["kp", "ki", "kd"], &mut iface)?;
    let law = PidLaw { kp, ki, kd, n, lower, upper, anti_windup, gain_ports };
    let iface = iface.output("u", Width::Fixed(1));
    Ok(match period {
        Some(period) => Built::new(DiscretePid { law, period, initial, integral: initial, filter: 0.0 }, iface),
        None => Built::new(ContinuousPid { law, initial, holding: false }, iface),
    })
}

#[cfg(test)]
mod tests;
