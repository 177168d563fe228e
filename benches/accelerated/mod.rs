//! The graph's step as `--accelerate` runs it: generated, built by cargo
//! into the step cache (on the first run only) and loaded, so that the
//! benches time what a user's accelerated run does, interface included.

use ctlgraph::accel::AcceleratedRun;
use ctlgraph_core::Model;

/// A run of the graph `text` (named `file`), compiled into `model`, in its
/// step library.
pub fn accelerated(model: &Model, text: &str, file: &str) -> AcceleratedRun {
    let (lib, cost) = ctlgraph::accel::library(model).expect("the step library builds (cargo on PATH)");
    eprintln!("{file}: {cost}");
    lib.create(text, file, &[], None, None).expect("the library runs the graph")
}

/// Where the recorded column `name` is in an accelerated run's rows
/// (after the time).
pub fn row_column(model: &Model, name: &str) -> usize {
    1 + model.columns.iter().take_while(|c| c.name != name).map(|c| c.width).sum::<usize>()
}

/// `run` from t = 0 as `--accelerate` runs a graph — recorded in the
/// library, the rows handed over a batch at a time (`run_rows`) — for
/// `rows` major steps at most: the sum of row column `column`, added in
/// the rows' order (as a sink adds it step by step), and its last value.
pub fn sum_column(run: &mut AcceleratedRun, column: usize, rows: u64) -> (f64, f64) {
    run.reset();
    let (mut sum, mut last) = (0.0, 0.0);
    let ran = run.run_rows(rows.saturating_sub(1), ctlgraph::accel::ROWS_PER_BATCH, &mut |batch| {
        for &v in batch.column(column) {
            sum += v;
            last = v;
        }
        true
    });
    ran.expect("the accelerated run");
    (sum, last)
}
