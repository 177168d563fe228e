//! Rows between major steps (`simulation: { output: { refine: N } }` or
//! `{ every: DT }`): the step's continuous states from the solver's dense
//! output (Dormand–Prince's continuous extension, cubic Hermite for the
//! other methods, the exact transition for held LTI blocks), the
//! continuous blocks' outputs computed there as in a minor step, discrete
//! outputs held. The solution is the one the major steps give; only the
//! recorder sees more rows.

use super::{Held, Minor, Simulator};
use crate::flatten::OutputTimes;
use ctlgraph_solver::{Integrator, OdeSystem, Zoh};
use std::ops::Range;

/// What a back-end computes at a row: the solver's system (for the dense
/// output) that also gives the continuous blocks' outputs at a row's
/// (t, x) — all states, held LTI blocks' included — as in a minor step.
pub(crate) trait RowSystem: OdeSystem {
    /// Where the step (or the solver's part of it) ends: the left-limit
    /// flag of the evaluations at and past it.
    fn set_step_end(&mut self, t_end: f64);
    fn row_outputs(&mut self, t: f64, x: &[f64]);
    fn signals(&self) -> &[f64];
    /// Held LTI block `j`'s input, latched at the step's start.
    fn latched(&self, j: usize) -> &[f64];
}

/// What the rows inside the last step need.
#[derive(Clone)]
pub(crate) struct Dense {
    times: OutputTimes,
    /// The last step: where it started, where the solver's own step ended
    /// (an event may have ended the major step before), and where the
    /// major step is.
    t0: f64,
    t_solver: f64,
    t1: f64,
    /// All states at the step's start, and the integrated ones at the
    /// solver's end (the dense output's ends).
    x_start: Vec<f64>,
    x_solver: Vec<f64>,
    /// Work space: the states at a row.
    x_row: Vec<f64>,
    /// Per held LTI block, its states and its transition over a row's
    /// offset into the step.
    held: Vec<(Range<usize>, Zoh)>,
    /// `every`: the index k of the next grid time k·DT to record.
    next_k: u64,
}

impl Dense {
    /// For `n` states of which `n_integrated` are integrated, and the held
    /// LTI blocks' states and transitions; `None` when no rows are asked
    /// between steps.
    pub(crate) fn new(
        times: OutputTimes,
        n: usize,
        n_integrated: usize,
        held: Vec<(Range<usize>, Zoh)>,
    ) -> Option<Self> {
        if times == OutputTimes::Steps {
            return None;
        }
        Some(Dense {
            times,
            t0: 0.0,
            t_solver: 0.0,
            t1: 0.0,
            x_start: vec![0.0; n],
            x_solver: vec![0.0; n_integrated],
            x_row: vec![0.0; n],
            held,
            next_k: 0,
        })
    }

    pub(crate) fn reset(&mut self) {
        self.next_k = 0;
    }

    /// At a step's start.
    pub(crate) fn start(&mut self, t0: f64, x: &[f64]) {
        self.t0 = t0;
        self.x_start.copy_from_slice(x);
    }

    /// Where the solver's step ended, before an event may cut it short.
    pub(crate) fn solver_end(&mut self, t: f64, x: &[f64]) {
        self.t_solver = t;
        self.x_solver.copy_from_slice(x);
    }

    pub(crate) fn end(&mut self, t1: f64) {
        self.t1 = t1;
    }

    /// The grid time k·DT (with `every`) that a major step at `t` gives,
    /// if one; for the other modes, `t` itself.
    pub(crate) fn major_row(&mut self, t: f64) -> Option<f64> {
        let OutputTimes::Every(dt) = self.times else { return Some(t) };
        let g = self.next_k as f64 * dt;
        if (t - g).abs() <= 1e-9 * dt {
            self.next_k += 1;
            Some(g)
        } else {
            None
        }
    }

    /// The next row's time strictly inside the last step, if any.
    fn next_row(&mut self, row: u32) -> Option<f64> {
        let (t0, t1) = (self.t0, self.t1);
        match self.times {
            OutputTimes::Steps => None,
            OutputTimes::Refine(n) => (row + 1 < n).then(|| t0 + f64::from(row + 1) / f64::from(n) * (t1 - t0)),
            OutputTimes::Every(dt) => {
                let g = self.next_k as f64 * dt;
                // A grid time at the step's end is the major step's row.
                (g < t1 - 1e-9 * dt).then(|| {
                    self.next_k += 1;
                    g
                })
            }
        }
    }

    /// Hands `sink` the rows inside the step just taken: the integrated
    /// states from the solver's dense output (`integ`, over `sys`), the
    /// held ones by their transitions under their latched inputs, the
    /// outputs by `sys`. Returns false when the sink asked to stop.
    pub(crate) fn rows(
        &mut self,
        integ: &mut Integrator,
        sys: &mut impl RowSystem,
        sink: &mut dyn FnMut(f64, &[f64]) -> bool,
    ) -> bool {
        let mut go_on = true;
        let mut row = 0;
        let n = self.x_solver.len();
        while let Some(t) = self.next_row(row) {
            row += 1;
            sys.set_step_end(self.t_solver);
            if n > 0 {
                integ.interpolate(sys, t, &self.x_solver, &mut self.x_row[..n]);
            }
            for (j, (states, zoh)) in self.held.iter_mut().enumerate() {
                self.x_row[states.clone()].copy_from_slice(&self.x_start[states.clone()]);
                zoh.step(t - self.t0, &mut self.x_row[states.clone()], sys.latched(j));
            }
            sys.set_step_end(self.t1);
            sys.row_outputs(t, &self.x_row);
            go_on &= sink(t, sys.signals());
        }
        go_on
    }
}

/// The interpreter's rows: its minor system over the row visits, and the
/// held blocks' latched inputs.
struct Rows<'a> {
    sys: Minor<'a>,
    held: &'a [Held],
    inputs: &'a [f64],
}

impl OdeSystem for Rows<'_> {
    fn derivatives(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        self.sys.derivatives(t, x, dx);
    }
}

impl RowSystem for Rows<'_> {
    fn set_step_end(&mut self, t_end: f64) {
        self.sys.t_end = t_end;
    }

    fn row_outputs(&mut self, t: f64, x: &[f64]) {
        self.sys.outputs(t, x);
    }

    fn signals(&self) -> &[f64] {
        self.sys.signals
    }

    fn latched(&self, j: usize) -> &[f64] {
        &self.inputs[self.held[j].latched.clone()]
    }
}

impl Simulator {
    /// Hands `sink` the rows inside the step just taken; returns false when
    /// the sink asked to stop.
    #[inline(always)]
    pub(super) fn dense_rows(&mut self, sink: &mut dyn FnMut(f64, &[f64]) -> bool) -> bool {
        if self.state.dense.is_none() { true } else { self.rows_of_dense_output(sink) }
    }

    fn rows_of_dense_output(&mut self, sink: &mut dyn FnMut(f64, &[f64]) -> bool) -> bool {
        let s = &mut self.state;
        let Some(dense) = &mut s.dense else { return true };
        let sys = Minor {
            model: &self.model,
            blocks: &mut s.blocks,
            signals: &mut s.signals,
            continuous: &self.row_visits,
            at_start: None,
            stateful: &self.stateful,
            integrands: &self.integrands,
            computed_at: &mut self.computed_at,
            t_end: 0.0,
        };
        let mut rows = Rows { sys, held: &self.held, inputs: &s.held_inputs };
        dense.rows(&mut s.clockwork.integ, &mut rows, sink)
    }
}
