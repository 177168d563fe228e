//! The machine-readable run report (`--report FILE.json`).

use ctlgraph_core::RunStats;
use ctlgraph_core::checks::CheckResult;
use ctlgraph_solver::Method;
use serde_json::{Value, json};
use sha2::{Digest, Sha256};

/// What a report says about one run.
pub struct RunInfo<'a> {
    pub graph: &'a str,
    pub graph_bytes: &'a [u8],
    pub method: Method,
    pub stats: RunStats,
    pub seed: u64,
    pub stop: f64,
    pub simulated: f64,
    pub wall_seconds: f64,
    /// `ok`, `checks failed`, `failed` (a numeric fault), `interrupted`
    /// (SIGINT, SIGTERM) or `stopped` (a step or wall-time budget).
    pub status: &'a str,
    pub error: Option<String>,
    pub warnings: &'a [String],
    pub checks: &'a [CheckResult],
    pub columns: &'a [ctlgraph_core::compile::Column],
    /// The compiled blocks (for which were stepped by exact ZOH).
    pub blocks: &'a [ctlgraph_core::compile::BlockMeta],
    /// The graph's parameters as resolved for this run.
    pub parameters: &'a [(String, f64)],
    /// The `--set` overrides as given.
    pub overrides: &'a [(String, String)],
    /// Under `--accelerate`: what preparing the step cost, or why the run
    /// was interpreted.
    pub acceleration: Option<Result<crate::accel::Cost, String>>,
}

/// SHA-256 of the graph file, lowercase hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}

fn solver_json(method: Method) -> Value {
    match method {
        Method::Euler { step } | Method::Heun { step } | Method::Rk4 { step } => {
            json!({ "method": method.name(), "step": step })
        }
        Method::DormandPrince { rtol, atol, max_step, initial_step }
        | Method::Trbdf2 { rtol, atol, max_step, initial_step } => json!({
            "method": method.name(), "rtol": rtol, "atol": atol, "max_step": max_step,
            "initial_step": initial_step,
        }),
    }
}

pub fn to_json(info: &RunInfo) -> Value {
    let s = info.stats;
    json!({
        "ctlgraph_version": env!("CARGO_PKG_VERSION"),
        "graph": { "file": info.graph, "sha256": sha256_hex(info.graph_bytes) },
        "command_line": std::env::args().collect::<Vec<_>>(),
        "overrides": info.overrides.iter().map(|(n, v)| json!({ "name": n, "value": v })).collect::<Vec<_>>(),
        "parameters": info.parameters.iter().map(|(n, v)| json!({ "name": n, "value": v })).collect::<Vec<_>>(),
        "solver": solver_json(info.method),
        // Continuous LTI blocks advanced by their exact zero-order-hold
        // transition instead of being integrated (`solver.exact_lti`).
        "exact_zoh": info.blocks.iter().filter(|b| b.exact_zoh).map(|b| b.name.as_str()).collect::<Vec<_>>(),
        "statistics": {
            "major_steps": s.major_steps,
            "solver_steps": s.solver.steps,
            "rejected_steps": s.solver.rejected,
            "derivative_evaluations": s.solver.evaluations,
            "jacobian_evaluations": s.solver.jacobians,
            "lu_factorizations": s.solver.factorizations,
            "newton_failures": s.solver.newton_failures,
            "events": s.events,
        },
        "seed": info.seed,
        "stop_time": info.stop,
        "simulated_time": info.simulated,
        "wall_time_seconds": info.wall_seconds,
        "acceleration": match &info.acceleration {
            None => Value::Null,
            Some(Ok(crate::accel::Cost::Built(s))) => json!({ "step": "built", "seconds": s }),
            Some(Ok(crate::accel::Cost::Loaded(s))) => json!({ "step": "loaded", "seconds": s }),
            Some(Err(why)) => json!({ "step": null, "interpreted_because": why }),
        },
        "checks": info.checks.iter().map(|c| json!({
            "name": c.name, "measured": c.measured, "op": c.op.symbol(), "bound": c.bound, "passed": c.passed,
        })).collect::<Vec<_>>(),
        "status": info.status,
        "error": info.error,
        "warnings": info.warnings,
        "columns": info.columns.iter().map(|c| json!({ "name": c.name, "width": c.width, "unit": c.unit })).collect::<Vec<_>>(),
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn sha256_of_abc() {
        assert_eq!(super::sha256_hex(b"abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    }
}
