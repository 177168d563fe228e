//! `simulation: { output: … }`: which times a run records — its major
//! steps (the default), or more from the solver's dense output.

use crate::diag::Diagnostic;
use crate::yaml::{self, Yaml};

/// The times a run hands to its recorder.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OutputTimes {
    /// Every major step (the solver's steps, sample hits and events).
    Steps,
    /// `refine: N`: each step's end and N − 1 times evenly inside it, from
    /// the solver's dense output (Simulink's Refine factor). The solution
    /// is the same; only the recorded rows are more.
    Refine(u32),
    /// `every: DT`: only the times k·DT, from the dense output inside
    /// steps (a major step that falls on one gives its own values).
    Every(f64),
}

/// The largest refine factor: more rows per step than this no plot or
/// check needs, and a mistyped number could exhaust memory.
pub const MAX_REFINE: u32 = 1000;

/// Reads `output:` (`None`: the default) with `num` evaluating numbers.
pub(super) fn output_times(
    value: Option<&Yaml>,
    num: impl Fn(&Yaml, &str) -> Result<f64, Diagnostic>,
    stop: f64,
) -> Result<OutputTimes, Diagnostic> {
    let Some(value) = value else { return Ok(OutputTimes::Steps) };
    let entries = value.expect_map("`simulation.output`")?;
    super::check_keys(entries, &["refine", "every"], "simulation.output")?;
    match (yaml::lookup(entries, "refine"), yaml::lookup(entries, "every")) {
        (Some(_), Some(every)) => Err(Diagnostic::at(&every.pos, "`output` takes `refine` or `every`, not both")
            .with_hint("refine: N adds rows inside each step; every: DT records a fixed grid only")),
        (Some(v), None) => {
            let n = num(v, "`output.refine`")?;
            if n.fract() != 0.0 || !(1.0..=f64::from(MAX_REFINE)).contains(&n) {
                return Err(Diagnostic::at(
                    &v.pos,
                    format!("`output.refine` must be a whole number from 1 to {MAX_REFINE}, got {n}"),
                ));
            }
            Ok(OutputTimes::Refine(n as u32))
        }
        (None, Some(v)) => {
            let dt = num(v, "`output.every`")?;
            if !(dt > 0.0 && dt.is_finite()) {
                return Err(Diagnostic::at(&v.pos, format!("`output.every` must be a positive number, got {dt}")));
            }
            if stop / dt > crate::flatten::MAX_STEPS {
                return Err(Diagnostic::at(
                    &v.pos,
                    format!(
                        "`output.every: {dt}` would record {:e} rows (limit {:e})",
                        stop / dt,
                        crate::flatten::MAX_STEPS
                    ),
                ));
            }
            Ok(OutputTimes::Every(dt))
        }
        (None, None) => Ok(OutputTimes::Steps),
    }
}
