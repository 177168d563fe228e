//! Paired timing, for the ratios the README quotes. A ratio of two
//! medians measured one after the other carries the machine's drift
//! between the two measurements (on the shared development machine, runs
//! of unchanged code moved a ratio by a third). Here every timed run of
//! the subject (the graph) comes right after a timed run of its reference
//! (the hand-written loop), so each criterion sample gives a ratio from
//! one moment; the median of those ratios is written beside criterion's
//! estimates (`<target>/criterion/<group>/<id>/paired_ratio.json`), where
//! `examples/perf_table.rs` reads it. Criterion's own estimate for the
//! benchmark stays the subject's time alone.

use criterion::Bencher;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Per-sample ratios of one paired benchmark.
pub struct Paired {
    group: &'static str,
    id: &'static str,
    reference: &'static str,
    ratios: Vec<f64>,
}

impl Paired {
    /// Benchmark `group/id`, paired with `group/reference`.
    pub fn new(group: &'static str, id: &'static str, reference: &'static str) -> Self {
        Paired { group, id, reference, ratios: Vec::new() }
    }

    /// Times `subject` right after `reference` in every iteration, both
    /// timed; criterion sees the subject's time, the ratio is kept.
    pub fn run<S, R>(&mut self, b: &mut Bencher, mut subject: impl FnMut() -> S, mut reference: impl FnMut() -> R) {
        b.iter_custom(|iters| {
            let (mut spent, mut spent_reference) = (Duration::ZERO, Duration::ZERO);
            for _ in 0..iters {
                let start = Instant::now();
                black_box(reference());
                let middle = Instant::now();
                black_box(subject());
                spent += middle.elapsed();
                spent_reference += middle - start;
            }
            self.ratios.push(spent.as_secs_f64() / spent_reference.as_secs_f64());
            spent
        });
    }

    /// Writes the median of the last `samples` ratios (criterion's samples
    /// come after its warm-up, which also calls the routine). Nothing when
    /// the benchmark did not measure: filtered out, or run by `--test` or
    /// `--profile-time` (a profiler's run, whose timings mean nothing).
    pub fn save(&self, samples: usize) {
        let not_measuring = std::env::args().any(|a| a == "--test" || a == "--profile-time");
        if not_measuring || self.ratios.len() < samples {
            return;
        }
        let mut last: Vec<f64> = self.ratios[self.ratios.len() - samples..].to_vec();
        last.sort_by(f64::total_cmp);
        let mid = last.len() / 2;
        let median = if last.len() % 2 == 1 { last[mid] } else { 0.5 * (last[mid - 1] + last[mid]) };
        let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| PathBuf::from("target"), PathBuf::from);
        let dir = target.join("criterion").join(self.group).join(self.id);
        let json = format!(
            "{{\"median_ratio\":{median},\"samples\":{},\"reference\":\"{}/{}\"}}\n",
            last.len(),
            self.group,
            self.reference
        );
        if let Err(e) = std::fs::create_dir_all(&dir).and_then(|()| std::fs::write(dir.join("paired_ratio.json"), json))
        {
            eprintln!("warning: could not save the paired ratio of {}/{}: {e}", self.group, self.id);
        }
    }
}
