//! Rows between major steps (`simulation: { output: { refine: N } }` or
//! `{ every: DT }`): the step's continuous states from the solver's dense
//! output (Dormand–Prince's continuous extension, cubic Hermite for the
//! other methods, the exact transition for held LTI blocks), the
//! continuous blocks' outputs computed there as in a minor step, discrete
//! outputs held. The solution is the one the major steps give; only the
//! recorder sees more rows.

use super::visit::Visit;
use super::{Minor, Simulator};
use crate::flatten::OutputTimes;
use ctlgraph_solver::Zoh;

/// What the rows inside the last step need.
#[derive(Clone)]
pub(super) struct Dense {
    times: OutputTimes,
    /// The continuous blocks a row recomputes (not the plain integrators,
    /// copied; not event-only blocks, constant between events).
    visits: Vec<Visit>,
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
    /// Per held LTI block, its transition over a row's offset into the step.
    held: Vec<Zoh>,
    /// `every`: the index k of the next grid time k·DT to record.
    next_k: u64,
}

impl Dense {
    pub(super) fn new(sim: &Simulator, times: OutputTimes, visits: Vec<Visit>) -> Option<Self> {
        if times == OutputTimes::Steps {
            return None;
        }
        let (n, n_integrated) = (sim.state.x.len(), sim.state.clockwork.n_integrated);
        Some(Dense {
            times,
            visits,
            t0: 0.0,
            t_solver: 0.0,
            t1: 0.0,
            x_start: vec![0.0; n],
            x_solver: vec![0.0; n_integrated],
            x_row: vec![0.0; n],
            held: sim.held.iter().map(|h| h.zoh.clone()).collect(),
            next_k: 0,
        })
    }

    pub(super) fn reset(&mut self) {
        self.next_k = 0;
    }

    /// At a step's start.
    pub(super) fn start(&mut self, t0: f64, x: &[f64]) {
        self.t0 = t0;
        self.x_start.copy_from_slice(x);
    }

    /// Where the solver's step ended, before an event may cut it short.
    pub(super) fn solver_end(&mut self, t: f64, x: &[f64]) {
        self.t_solver = t;
        self.x_solver.copy_from_slice(x);
    }

    pub(super) fn end(&mut self, t1: f64) {
        self.t1 = t1;
    }

    /// The grid time k·DT (with `every`) that a major step at `t` gives,
    /// if one; for the other modes, `t` itself.
    pub(super) fn major_row(&mut self, t: f64) -> Option<f64> {
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
        let mut go_on = true;
        let mut row = 0;
        while let Some(t) = dense.next_row(row) {
            row += 1;
            let n = s.clockwork.n_integrated;
            let mut sys = Minor {
                model: &self.model,
                blocks: &mut s.blocks,
                signals: &mut s.signals,
                continuous: &dense.visits,
                at_start: None,
                stateful: &self.stateful,
                integrands: &self.integrands,
                computed_at: &mut self.computed_at,
                t_end: dense.t_solver,
            };
            if n > 0 {
                s.clockwork.integ.interpolate(&mut sys, t, &dense.x_solver, &mut dense.x_row[..n]);
            }
            for (h, zoh) in self.held.iter().zip(&mut dense.held) {
                let states = h.states.clone();
                dense.x_row[states.clone()].copy_from_slice(&dense.x_start[states.clone()]);
                zoh.step(t - dense.t0, &mut dense.x_row[states], &s.held_inputs[h.latched.clone()]);
            }
            sys.t_end = dense.t1;
            sys.outputs(t, &dense.x_row);
            go_on &= sink(t, &s.signals);
        }
        go_on
    }
}
