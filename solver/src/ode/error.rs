//! Why integration could not continue, said so that a run can name the
//! time, the state and the cause.

use std::fmt;

/// Why integration could not continue.
#[derive(Clone, Debug, PartialEq)]
pub enum SolverError {
    /// The adaptive step shrank below what floating point can resolve at
    /// `t`; `state` is the component with the largest scaled error at the
    /// last rejected step (the one that forced the step down), if any.
    StepTooSmall { t: f64, step: f64, state: Option<usize> },
    /// The error estimate was not finite (the state blew up) at `t`;
    /// `state` is the first component that was not.
    NonFinite { t: f64, state: Option<usize> },
    /// The Newton matrix `I − d·h·J` is singular at `t`.
    Singular { t: f64 },
    /// The method is not in this build (the `implicit` feature is off).
    NotBuilt { method: &'static str },
}

impl fmt::Display for SolverError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SolverError::StepTooSmall { t, step, .. } => write!(
                f,
                "step size {step:e} too small at t = {t}: the system is too stiff or discontinuous for the tolerances"
            ),
            SolverError::NonFinite { t, state: Some(i) } => write!(f, "state {i} is not finite at t = {t}"),
            SolverError::NonFinite { t, state: None } => write!(f, "state is not finite at t = {t}"),
            SolverError::Singular { t } => write!(f, "the Newton matrix is singular at t = {t}"),
            SolverError::NotBuilt { method } => {
                write!(f, "`{method}` is not in this build of ctlgraph-solver (its feature `implicit` is off)")
            }
        }
    }
}

impl std::error::Error for SolverError {}

impl SolverError {
    /// The state component the error points at, when there is one.
    pub fn state(&self) -> Option<usize> {
        match *self {
            SolverError::StepTooSmall { state, .. } | SolverError::NonFinite { state, .. } => state,
            SolverError::Singular { .. } | SolverError::NotBuilt { .. } => None,
        }
    }
}
