//! The `simulation:` section: stop time, solver and its options, seed,
//! recorded times, acceleration — read and checked into a [`SimConfig`].

use super::output::{self, OutputTimes};
use super::{MAX_STEPS, check_keys};
use crate::diag::{Diagnostic, Pos};
use crate::params::eval_number;
use crate::yaml::{self, Key, Kind, Yaml};
use ctlgraph_solver::Method;

/// Simulation settings of the top-level graph.
#[derive(Clone, Debug, PartialEq)]
pub struct SimConfig {
    pub stop: f64,
    pub method: Method,
    pub seed: u64,
    pub zero_crossing: ZeroCrossing,
    /// `solver: { exact_lti: … }` (default true): continuous LTI blocks
    /// driven by piecewise-constant signals are stepped by their exact
    /// zero-order-hold transition under fixed-step methods.
    pub exact_lti: bool,
    /// Whether `max_step` was left to its default, which then follows the
    /// run's effective stop time (`--stop-time`), not the file's.
    pub default_max_step: bool,
    /// `output:` — the times recorded.
    pub output: OutputTimes,
    /// `accelerate:` — whether runs use the generated step.
    pub accelerate: Accelerate,
    /// `algebraic_loops:` — what a loop of feedthrough blocks does.
    pub algebraic_loops: AlgebraicLoops,
}

/// `simulation: { algebraic_loops: … }`: a loop of direct-feedthrough
/// blocks is solved at every evaluation (Newton's method on its cut
/// signals), silently or with a warning naming it, or refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum AlgebraicLoops {
    Solve,
    /// Solve and say so once (the default, as Simulink's).
    #[default]
    Warn,
    Error,
}

/// `simulation: { accelerate: … }` and `--accelerate`: whether a run uses
/// the graph's generated step, built into a library (ctlgraph's `accel`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Accelerate {
    /// Interpreted (`false`, `off`; the default).
    #[default]
    Off,
    /// Accelerated when it can be, else interpreted with a note why (`true`, `on`).
    On,
    /// Accelerated, or an error (`require`).
    Require,
}

impl Accelerate {
    /// `on`/`true`, `require`, `off`/`false`.
    pub fn parse(value: &str) -> Result<Accelerate, String> {
        match value {
            "on" | "true" => Ok(Accelerate::On),
            "require" => Ok(Accelerate::Require),
            "off" | "false" => Ok(Accelerate::Off),
            other => Err(format!("`{other}`: expected on, require or off")),
        }
    }
}

/// `solver: { zero_crossing: … }`: whether the simulator locates the zero
/// crossings blocks declare (see [`crate::block::Block::zero_crossings`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ZeroCrossing {
    /// Blocks switch mode only at major steps, found where they fall
    /// (the default of fixed-step methods, as in Simulink).
    Off,
    /// Crossings are located and end the step; chattering (a pile-up of
    /// events at nearly one time, or a Zeno point) stops the run with an
    /// error naming the block.
    On,
    /// As `On`, but a chattering block's crossings are ignored from then on
    /// and the run reports it.
    Adaptive,
}

/// The keys of `simulation:`, of its `solver:`, and the solver methods
/// (also what `ctlgraph schema` describes).
pub const SIM_KEYS: [&str; 6] = ["stop", "solver", "seed", "output", "accelerate", "algebraic_loops"];
pub const SOLVER_KEYS: [&str; 8] =
    ["method", "step", "rtol", "atol", "max_step", "initial_step", "zero_crossing", "exact_lti"];
pub const METHODS: [&str; 5] = ["dopri5", "trbdf2", "rk4", "heun", "euler"];

pub(super) fn sim_config(sim: Option<&Yaml>, scope: &[(String, f64)]) -> Result<SimConfig, Diagnostic> {
    let entries = match sim {
        Some(s) => s.expect_map("`simulation`")?,
        None => &[],
    };
    check_keys(entries, &SIM_KEYS, "simulation")?;
    let num = |v: &Yaml, what: &str| -> Result<f64, Diagnostic> {
        match &v.kind {
            Kind::Num(x) => Ok(*x),
            Kind::Str(s) => eval_number(s, &v.pos, scope),
            _ => Err(Diagnostic::at(&v.pos, format!("{what} must be a number, found {}", v.describe()))),
        }
    };
    let positive = |v: &Yaml, what: &str| -> Result<f64, Diagnostic> {
        let x = num(v, what)?;
        if x > 0.0 && x.is_finite() {
            Ok(x)
        } else {
            Err(Diagnostic::at(&v.pos, format!("{what} must be a positive number, got {x}")))
        }
    };
    let stop = match yaml::lookup(entries, "stop") {
        Some(v) => positive(v, "`simulation.stop`")?,
        None => 10.0,
    };
    let seed = match yaml::lookup(entries, "seed") {
        Some(v) => {
            let s = num(v, "`simulation.seed`")?;
            if s < 0.0 || s.fract() != 0.0 || s > 9.0e15 {
                return Err(Diagnostic::at(&v.pos, format!("`seed` must be a whole number >= 0, got {s}")));
            }
            s as u64
        }
        None => 0,
    };
    let (method_name, method_pos, solver_entries): (&str, Option<Pos>, &[(Key, Yaml)]) =
        match yaml::lookup(entries, "solver") {
            None => ("dopri5", None, &[]),
            Some(v) => match &v.kind {
                Kind::Str(s) => (s.as_str(), Some(v.pos.clone()), &[]),
                Kind::Map(m) => {
                    check_keys(m, &SOLVER_KEYS, "simulation.solver")?;
                    match yaml::lookup(m, "method") {
                        Some(mv) => (mv.expect_str("`solver.method`")?, Some(mv.pos.clone()), m.as_slice()),
                        None => ("dopri5", None, m.as_slice()),
                    }
                }
                _ => {
                    return Err(Diagnostic::at(&v.pos, "`solver` must be a method name or a mapping"));
                }
            },
        };
    let opt = |key: &str| -> Result<Option<f64>, Diagnostic> {
        yaml::lookup(solver_entries, key).map(|v| positive(v, &format!("`solver.{key}`"))).transpose()
    };
    let fixed_step = |name: &str| -> Result<f64, Diagnostic> {
        opt("step")?.ok_or_else(|| {
            let pos = method_pos.clone().unwrap_or_else(|| Pos::new("?".into(), 0, 0));
            Diagnostic::at(&pos, format!("the fixed-step method `{name}` needs a `step`"))
                .with_hint(format!("solver: {{ method: {name}, step: 1.0e-4 }}"))
        })
    };
    let adaptive_step = || -> Result<(), Diagnostic> {
        match yaml::lookup(solver_entries, "step") {
            Some(v) => Err(Diagnostic::at(
                &v.pos,
                format!("{method_name} chooses its own steps: use `max_step` (or a fixed-step method)"),
            )),
            None => Ok(()),
        }
    };
    let method = match method_name {
        "dopri5" | "ode45" => {
            adaptive_step()?;
            Method::DormandPrince {
                rtol: opt("rtol")?.unwrap_or(1e-6),
                atol: opt("atol")?.unwrap_or(1e-9),
                max_step: opt("max_step")?.unwrap_or(f64::NAN),
                initial_step: opt("initial_step")?,
            }
        }
        "trbdf2" | "ode23tb" => {
            adaptive_step()?;
            Method::Trbdf2 {
                rtol: opt("rtol")?.unwrap_or(1e-6),
                atol: opt("atol")?.unwrap_or(1e-9),
                max_step: opt("max_step")?.unwrap_or(f64::NAN),
                initial_step: opt("initial_step")?,
            }
        }
        "rk4" => Method::Rk4 { step: fixed_step("rk4")? },
        "heun" => Method::Heun { step: fixed_step("heun")? },
        "euler" => Method::Euler { step: fixed_step("euler")? },
        other => {
            let pos = method_pos.unwrap_or_else(|| Pos::new("?".into(), 0, 0));
            return Err(Diagnostic::at(&pos, format!("unknown solver method `{other}`"))
                .suggest(other, METHODS)
                .or_hint(format!("methods: {}", METHODS.join(", "))));
        }
    };
    if !method.is_adaptive() {
        for key in ["rtol", "atol", "max_step", "initial_step"] {
            if let Some(v) = yaml::lookup(solver_entries, key) {
                return Err(Diagnostic::at(
                    &v.pos,
                    format!("`{key}` applies to dopri5 and trbdf2, not to `{method_name}`"),
                ));
            }
        }
    }
    let zero_crossing = match yaml::lookup(solver_entries, "zero_crossing") {
        None if method.is_adaptive() => ZeroCrossing::On,
        None => ZeroCrossing::Off,
        Some(v) => match &v.kind {
            Kind::Bool(true) => ZeroCrossing::On,
            Kind::Bool(false) => ZeroCrossing::Off,
            Kind::Str(s) if s == "adaptive" => ZeroCrossing::Adaptive,
            _ => {
                return Err(Diagnostic::at(
                    &v.pos,
                    format!("`zero_crossing` must be true, false or adaptive, found {}", v.describe()),
                ));
            }
        },
    };
    let exact_lti = match yaml::lookup(solver_entries, "exact_lti") {
        None => true,
        Some(v) => match v.kind {
            Kind::Bool(b) => b,
            _ => {
                return Err(Diagnostic::at(
                    &v.pos,
                    format!("`exact_lti` must be true or false, found {}", v.describe()),
                )
                .with_hint("false integrates every continuous block with the solver, as Simulink does"));
            }
        },
    };
    if !method.is_adaptive() && stop / method.max_step() > MAX_STEPS {
        let pos =
            yaml::lookup(solver_entries, "step").map(|v| v.pos.clone()).unwrap_or_else(|| Pos::new("?".into(), 0, 0));
        return Err(Diagnostic::at(
            &pos,
            format!(
                "a step of {:e} s would take {:e} steps to reach the stop time {stop} s (limit {MAX_STEPS:e})",
                method.max_step(),
                stop / method.max_step()
            ),
        ));
    }
    let default_max_step = method.max_step().is_nan();
    let method = if default_max_step { method.with_max_step(method.default_max_step(stop)) } else { method };
    let output = output::output_times(yaml::lookup(entries, "output"), num, stop)?;
    let accelerate = match yaml::lookup(entries, "accelerate") {
        None => Accelerate::Off,
        Some(v) => match &v.kind {
            Kind::Bool(true) => Accelerate::On,
            Kind::Bool(false) => Accelerate::Off,
            Kind::Str(s) if s == "require" => Accelerate::Require,
            _ => {
                return Err(Diagnostic::at(
                    &v.pos,
                    format!("`accelerate` must be true, false or require, found {}", v.describe()),
                )
                .with_hint(
                    "true runs the generated step when it can (else interpreted, with a note); require insists",
                ));
            }
        },
    };
    let algebraic_loops = match yaml::lookup(entries, "algebraic_loops") {
        None => AlgebraicLoops::Warn,
        Some(v) => match v.expect_str("`algebraic_loops`")? {
            "solve" => AlgebraicLoops::Solve,
            "warn" => AlgebraicLoops::Warn,
            "error" => AlgebraicLoops::Error,
            other => {
                return Err(Diagnostic::at(
                    &v.pos,
                    format!("`algebraic_loops: {other}`: expected solve, warn or error"),
                )
                .suggest(other, ["solve", "warn", "error"])
                .or_hint("warn (the default) solves each loop and says so once; error refuses it"));
            }
        },
    };
    Ok(SimConfig {
        stop,
        method,
        seed,
        zero_crossing,
        exact_lti,
        default_max_step,
        output,
        accelerate,
        algebraic_loops,
    })
}
