//! Why a run stops early, said so that the user can act on it.

use ctlgraph_solver::SolverError;
use std::fmt;

/// Why a run stopped early.
#[derive(Clone, Debug, PartialEq)]
pub enum SimError {
    /// A signal or state became NaN or infinite; `inputs` are the block's
    /// input values at that moment (vector elements as `u[k]`).
    NonFinite { t: f64, block: String, what: String, value: f64, inputs: Vec<(String, f64)> },
    /// The solver gave up; `culprit` is the block and state index that
    /// forced it, when the solver can tell (the state whose error estimate
    /// kept the step shrinking).
    Solver { t: f64, error: SolverError, culprit: Option<(String, usize)> },
    /// Time stopped advancing: a block asks for major steps closer together
    /// than floating point can tell apart.
    Stalled { t: f64, block: String },
    /// A block's zero crossings kept firing at (nearly) one instant: the
    /// model chatters (a Zeno or sliding behaviour).
    Chattering { t: f64, block: String, what: String },
    /// A program driving the run asked for something impossible (see
    /// [`super::Simulator::advance_to`]).
    Host(String),
    /// A run in an accelerated step library failed: its message, as the
    /// library's driver wrote it (from one of the other kinds).
    Reported(String),
}

/// A value as Rust prints it, but in exponent form when that would be a
/// long run of digits (a diverging state reaches 1e150).
fn readable(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-6..1e15).contains(&v.abs()) { format!("{v:e}") } else { v.to_string() }
}

impl fmt::Display for SimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SimError::NonFinite { t, block, what, value, inputs } => {
                write!(f, "t = {t}: block `{block}`: {what} is {value}")?;
                if !inputs.is_empty() {
                    let shown: Vec<String> =
                        inputs.iter().take(MAX_INPUTS_SHOWN).map(|(n, v)| format!("{n} = {}", readable(*v))).collect();
                    let more = inputs.len().saturating_sub(MAX_INPUTS_SHOWN);
                    let more = if more > 0 { format!(" and {more} more") } else { String::new() };
                    write!(f, " (inputs: {}{more})", shown.join(", "))?;
                }
                Ok(())
            }
            SimError::Solver { t, error, culprit: None } => write!(f, "t = {t}: solver: {error}"),
            SimError::Solver { t, error, culprit: Some((block, k)) } => {
                write!(f, "t = {t}: solver: {error}; the step is forced down by block `{block}` (state {k})")
            }
            SimError::Stalled { t, block } => write!(
                f,
                "t = {t}: time does not advance: block `{block}` asks for steps closer than the time resolution \
                 (a period or event spacing too small for the stop time)"
            ),
            SimError::Chattering { t, block, what } => write!(
                f,
                "t = {t}: block `{block}` chatters: {what}; \
                 hint: `solver: {{ zero_crossing: adaptive }}` ignores a chattering block's crossings, \
                 or reformulate (add hysteresis, a boundary layer)"
            ),
            SimError::Host(message) | SimError::Reported(message) => f.write_str(message),
        }
    }
}

impl std::error::Error for SimError {}

/// Input values a non-finite message lists (a wide vector input is cut short).
const MAX_INPUTS_SHOWN: usize = 8;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_and_tiny_inputs_are_shown_with_an_exponent() {
        let inputs = vec![("u1".into(), -1.3205514427584226e150), ("u2".into(), 2.5), ("u3".into(), 3e-9)];
        let e =
            SimError::NonFinite { t: 1.5, block: "b".into(), what: "output `y`".into(), value: f64::INFINITY, inputs };
        assert_eq!(
            e.to_string(),
            "t = 1.5: block `b`: output `y` is inf (inputs: u1 = -1.3205514427584226e150, u2 = 2.5, u3 = 3e-9)"
        );
    }
}
