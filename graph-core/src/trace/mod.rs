//! Recording: picking the recorded columns out of the signal buffer at
//! major steps (with decimation), and keeping them in memory — what plots
//! are drawn from and checks are evaluated on.

mod batch;

pub use batch::{ColumnBatch, Columns};

use crate::checks::{Check, CheckResult};
use crate::compile::Model;
use crate::sim::{RunStats, SimError, Simulator};

/// Runs a model to its stop time (or `stop`) and returns the recorded
/// signals in memory.
pub fn simulate(model: Model, stop: Option<f64>) -> Result<Trace, SimError> {
    simulate_with_stats(model, stop).map(|(trace, _)| trace)
}

/// [`simulate`], with the run's step, solver and event counts.
pub fn simulate_with_stats(model: Model, stop: Option<f64>) -> Result<(Trace, RunStats), SimError> {
    let mut sim = Simulator::new(model, stop);
    let expected = sim.expected_major_steps();
    let trace = record(sim.shared_model().as_ref(), expected, |sink| sim.run_while(sink))?;
    Ok((trace, sim.stats()))
}

/// The trace of a run of `model` made by `run`, which hands its sink the
/// signals at every major step (as [`Simulator::run_while`]): the
/// recording of [`simulate`] for any back-end.
/// `expected_steps` ([`Simulator::expected_major_steps`]) sizes the trace
/// up front.
pub fn record(
    model: &Model,
    expected_steps: f64,
    run: impl FnOnce(&mut dyn FnMut(f64, &[f64]) -> bool) -> Result<bool, SimError>,
) -> Result<Trace, SimError> {
    let mut recorder = Recorder::new(model);
    let mut trace = Trace::for_run(model, expected_steps);
    run(&mut |t, signals| {
        recorder.sample(t, signals, &mut |row| trace.push(row));
        true
    })?;
    recorder.flush(&mut |row| trace.push(row));
    Ok(trace)
}

/// Where each recorded value is in the signal buffer, element by element,
/// in the order of a row after its time.
pub fn gather_offsets(model: &Model) -> Vec<usize> {
    model.columns.iter().flat_map(|c| c.offset..c.offset + c.width).collect()
}

/// Turns signal buffers into rows `[t, col1, col2, …]`, every `every`-th
/// major step plus the last one. Allocates only in `new`.
#[derive(Clone)]
pub struct Recorder {
    /// Where each recorded value is in the signal buffer, element by
    /// element: a row is a gather, with no copy of a run-time length (a
    /// call to memcpy) per column.
    gather: Vec<usize>,
    every: usize,
    /// Major steps until the next logged one (a countdown, not a
    /// division by `every` per step).
    skip: usize,
    row: Vec<f64>,
    row_written: bool,
}

impl Recorder {
    pub fn new(model: &Model) -> Self {
        let gather = gather_offsets(model);
        Recorder {
            every: model.record_every.max(1),
            skip: 0,
            row: vec![0.0; 1 + gather.len()],
            gather,
            row_written: true,
        }
    }

    /// How many values a row has: the time and the recorded columns.
    pub fn width(&self) -> usize {
        self.row.len()
    }

    /// Offers the signals of one major step; `out` receives the row when
    /// this step is logged.
    #[inline]
    pub fn sample(&mut self, t: f64, signals: &[f64], out: &mut impl FnMut(&[f64])) {
        self.fill(t, signals);
        if self.due() {
            out(&self.row);
        }
    }

    /// [`Recorder::sample`] appending the row to `batch` without staging
    /// it, by `write_row` — the gather of [`gather_offsets`] as a generated
    /// step writes it, with constant offsets: what an accelerated run
    /// records.
    #[inline(always)]
    pub fn sample_onto(
        &mut self,
        t: f64,
        signals: &[f64],
        batch: &mut ColumnBatch,
        write_row: impl FnOnce(f64, &[f64], &mut ColumnBatch),
    ) {
        if self.due() {
            write_row(t, signals, batch);
        } else {
            // Kept for `flush`, should this be the last step.
            self.fill(t, signals);
        }
    }

    fn fill(&mut self, t: f64, signals: &[f64]) {
        self.row[0] = t;
        for (value, &i) in self.row[1..].iter_mut().zip(&self.gather) {
            *value = signals[i];
        }
    }

    /// Whether this major step is logged (the first, then every
    /// `every`-th); counts it.
    #[inline]
    fn due(&mut self) -> bool {
        // Every step logged (the usual): nothing to count, `skip` stays 0
        // and `row_written` true.
        if self.every == 1 {
            return true;
        }
        self.row_written = self.skip == 0;
        self.skip = if self.row_written { self.every - 1 } else { self.skip - 1 };
        self.row_written
    }

    /// Emits the last step if decimation skipped it, so every log ends at
    /// the stop time.
    pub fn flush(&mut self, out: &mut dyn FnMut(&[f64])) {
        if !self.row_written {
            out(&self.row);
            self.row_written = true;
        }
    }
}

/// The most rows [`Trace::for_run`] reserves: beyond, a column grows as
/// it fills (a run's expected steps are a floor for adaptive methods and a
/// long run may stop early).
pub const RESERVED_ROWS: usize = 1 << 22;

/// Recorded signals in memory, column-major.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trace {
    pub headers: Vec<String>,
    pub columns: Vec<Vec<f64>>,
    /// The analysed loop's figures, for checks that read them.
    pub loop_figures: Option<Vec<f64>>,
}

impl Trace {
    pub fn new(headers: Vec<String>) -> Self {
        let columns = vec![Vec::new(); headers.len()];
        Trace { headers, columns, loop_figures: None }
    }

    /// The trace of a run of `model` expected to take `expected_steps`
    /// major steps, its columns sized for them (up to [`RESERVED_ROWS`]):
    /// growing by doubling would copy every column about once more and
    /// touch twice the memory, which on long runs costs more than the
    /// recording itself.
    pub fn for_run(model: &Model, expected_steps: f64) -> Self {
        let rows = expected_steps / model.record_every.max(1) as f64 + 2.0;
        let rows = if rows.is_finite() { (rows as usize).min(RESERVED_ROWS) } else { 0 };
        let headers = model.headers();
        let columns = (0..headers.len()).map(|_| Vec::with_capacity(rows)).collect();
        Trace { headers, columns, loop_figures: model.loop_figures.clone() }
    }

    pub fn push(&mut self, row: &[f64]) {
        for (c, v) in self.columns.iter_mut().zip(row) {
            c.push(*v);
        }
    }

    /// Appends a batch's rows (from an accelerated run), a column at a
    /// time.
    pub fn push_columns(&mut self, batch: Columns) {
        for (c, column) in self.columns.iter_mut().enumerate().take(batch.width()) {
            column.extend_from_slice(batch.column(c));
        }
    }

    /// Time stamps.
    pub fn t(&self) -> &[f64] {
        &self.columns[0]
    }

    /// A graph check evaluated on these signals.
    pub fn check(&self, check: &Check) -> CheckResult {
        check.evaluate(&self.columns, self.loop_figures.as_deref())
    }

    /// A column by header name.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.headers.iter().position(|h| h == name).map(|i| self.columns[i].as_slice())
    }

    /// Linear interpolation of column `name` at time `t`.
    pub fn at(&self, name: &str, t: f64) -> Option<f64> {
        let (ts, ys) = (self.t(), self.column(name)?);
        let i = ts.partition_point(|&x| x <= t);
        Some(match i {
            0 => ys[0],
            i if i >= ts.len() => ys[ts.len() - 1],
            i if ts[i] == ts[i - 1] => ys[i],
            i => ys[i - 1] + (ys[i] - ys[i - 1]) * (t - ts[i - 1]) / (ts[i] - ts[i - 1]),
        })
    }
}
