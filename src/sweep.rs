//! Designed sets of runs (`ctlgraph sweep`): grids, lists and random draws
//! of parameters, times a range of seeds; every case run in parallel and
//! tabulated with its checks' measured values; shards for batch schedulers
//! and their merge.
//!
//! The table is deterministic: cases are numbered before they run, rows are
//! written in case order, numbers in shortest round-trip form, so the same
//! command gives the same bytes whatever the number of jobs or shards.

use crate::accel::Runner;
use crate::record::Number;
use crate::suite::{Failure, run_checks_by};
use ctlgraph_blocks::noise::Stream;
use ctlgraph_core::checks::CheckResult;
use ctlgraph_core::{Diagnostic, ParsedGraph};
use rayon::prelude::*;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// One `--vary` argument.
#[derive(Clone, Debug, PartialEq)]
pub enum Vary {
    /// `NAME=LO..HI:N`: N evenly spaced values, both ends included.
    Grid { name: String, lo: f64, hi: f64, n: usize },
    /// `NAME=v1,v2,…`.
    List { name: String, values: Vec<f64> },
    /// `NAME=LO..HI` with `--random N`: uniform draws.
    Range { name: String, lo: f64, hi: f64 },
}

impl Vary {
    pub fn parse(arg: &str) -> Result<Vary, Diagnostic> {
        let bad = |why: &str| {
            Diagnostic::plain(format!("--vary {arg}: {why}"))
                .with_hint("NAME=LO..HI:N (grid), NAME=v1,v2,v3 (list), or NAME=LO..HI with --random N")
        };
        let (name, spec) = arg.split_once('=').ok_or_else(|| bad("expected NAME=…"))?;
        let name = name.trim().to_string();
        let number = |s: &str| -> Result<f64, Diagnostic> {
            let v: f64 = s.trim().parse().map_err(|_| bad(&format!("`{}` is not a number", s.trim())))?;
            if v.is_finite() { Ok(v) } else { Err(bad("values must be finite")) }
        };
        if let Some((lo, rest)) = spec.split_once("..") {
            let (hi, n) = match rest.split_once(':') {
                Some((hi, n)) => (hi, Some(n)),
                None => (rest, None),
            };
            let (lo, hi) = (number(lo)?, number(hi)?);
            if lo >= hi || !(hi - lo).is_finite() {
                return Err(bad("need LO < HI with a finite span"));
            }
            return Ok(match n {
                Some(n) => {
                    let n: usize = n.trim().parse().map_err(|_| bad("N must be a whole number"))?;
                    if !(2..=100_000).contains(&n) {
                        return Err(bad("a grid needs 2 <= N <= 100000 points"));
                    }
                    Vary::Grid { name, lo, hi, n }
                }
                None => Vary::Range { name, lo, hi },
            });
        }
        let values = spec.split(',').map(number).collect::<Result<Vec<_>, _>>()?;
        Ok(Vary::List { name, values })
    }

    pub fn name(&self) -> &str {
        match self {
            Vary::Grid { name, .. } | Vary::List { name, .. } | Vary::Range { name, .. } => name,
        }
    }
}

/// What to run.
#[derive(Clone, Debug)]
pub struct SweepSpec {
    pub vary: Vec<Vary>,
    /// Random draws of the `Range` parameters (grid and list values are
    /// crossed with them).
    pub random: Option<usize>,
    /// Seeds A..=B: every parameter case is run with each.
    pub seeds: Option<(u64, u64)>,
    /// Seed of the random draws.
    pub draw_seed: u64,
    /// `(k, n)`: run only the cases with index ≡ k (mod n).
    pub shard: Option<(usize, usize)>,
}

/// One run: its index in the whole sweep, parameter values, seed.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    pub index: usize,
    pub values: Vec<f64>,
    pub seed: Option<u64>,
}

/// The most cases one sweep may have.
pub const MAX_CASES: usize = 10_000_000;

/// Every case of the sweep in index order (before sharding): the grid and
/// list values crossed (the first `--vary` varying slowest), crossed with
/// the random draws, crossed with the seeds.
pub fn cases(spec: &SweepSpec) -> Result<Vec<Case>, Diagnostic> {
    let mut names: Vec<&str> = Vec::new();
    for v in &spec.vary {
        if names.contains(&v.name()) {
            return Err(Diagnostic::plain(format!("--vary {}: given twice", v.name())));
        }
        names.push(v.name());
    }
    let ranges: Vec<(usize, f64, f64)> = spec
        .vary
        .iter()
        .enumerate()
        .filter_map(|(i, v)| match v {
            Vary::Range { lo, hi, .. } => Some((i, *lo, *hi)),
            _ => None,
        })
        .collect();
    match (ranges.is_empty(), spec.random) {
        (false, None) => {
            return Err(Diagnostic::plain("a range without `:N` needs --random N (or write LO..HI:N for a grid)"));
        }
        (true, Some(_)) => return Err(Diagnostic::plain("--random N needs at least one --vary NAME=LO..HI")),
        _ => {}
    }
    let fixed: Vec<Vec<f64>> = spec
        .vary
        .iter()
        .map(|v| match v {
            Vary::Grid { lo, hi, n, .. } => (0..*n).map(|k| lo + (hi - lo) * k as f64 / (*n - 1) as f64).collect(),
            Vary::List { values, .. } => values.clone(),
            Vary::Range { .. } => vec![f64::NAN],
        })
        .collect();
    let draws = spec.random.unwrap_or(1);
    let seeds: Vec<Option<u64>> = match spec.seeds {
        Some((a, b)) => (a..=b).map(Some).collect(),
        None => vec![None],
    };
    let total = fixed.iter().map(Vec::len).try_fold(draws * seeds.len(), |acc, n| acc.checked_mul(n));
    if total.is_none_or(|n| n > MAX_CASES) {
        return Err(Diagnostic::plain(format!("the sweep has more than {MAX_CASES} cases")));
    }
    let mut rng = Stream::new(spec.draw_seed);
    let mut out = Vec::with_capacity(total.unwrap_or(0));
    let mut combo = vec![0usize; fixed.len()];
    loop {
        let base: Vec<f64> = combo.iter().enumerate().map(|(i, &k)| fixed[i][k]).collect();
        for _ in 0..draws {
            let mut values = base.clone();
            for &(i, lo, hi) in &ranges {
                values[i] = lo + (hi - lo) * rng.uniform();
            }
            for &seed in &seeds {
                out.push(Case { index: out.len(), values: values.clone(), seed });
            }
        }
        // Next grid combination, the last parameter fastest.
        let Some(i) = (0..combo.len()).rev().find(|&i| combo[i] + 1 < fixed[i].len()) else { break };
        combo[i] += 1;
        combo[i + 1..].iter_mut().for_each(|k| *k = 0);
    }
    Ok(out)
}

/// The outcome of one case.
#[derive(Clone, Debug)]
pub struct Row {
    pub case: Case,
    pub result: Result<Vec<CheckResult>, String>,
    pub wall: f64,
    /// The recorded signals, for the cases asked to keep them.
    pub trace: Option<crate::record::Trace>,
}

/// What to keep of each case's signals besides its checks.
pub struct Keep<'a> {
    /// Write every case's signals to `DIR/case-NNNNNN.csv`.
    pub traces_dir: Option<&'a Path>,
    /// Keep the trace in memory for these cases (a family plot).
    pub in_memory: &'a (dyn Fn(&Case) -> bool + Sync),
}

impl Row {
    pub fn status(&self) -> &'static str {
        match &self.result {
            Err(_) => "failed",
            Ok(r) if r.iter().any(|c| !c.passed) => "checks failed",
            Ok(_) => "ok",
        }
    }
}

/// Runs `cases` of the graph `text` (named `file`) on `jobs` threads, by
/// `runner`; returns the rows finished, in case order (all of them unless
/// `stop` was raised, e.g. by Ctrl-C). `done` is called after each case.
#[allow(clippy::too_many_arguments)]
pub fn run(
    runner: &Runner,
    text: &str,
    file: &Path,
    names: &[String],
    cases: &[Case],
    jobs: usize,
    keep: &Keep,
    stop: &AtomicBool,
    done: &(dyn Fn() + Sync),
) -> Result<Vec<Row>, Failure> {
    // Parsed and compiled once: a broken file is one error, not a table of
    // them, and each case is compiled on this model's structure.
    let parsed = ParsedGraph::parse(text, file.display().to_string().into())?;
    let registry = crate::registry();
    let base = crate::compile_flat(&parsed.flatten(&[])?, &registry)?;
    let simulate = |case: &Case| {
        let sets: Vec<(String, String)> =
            names.iter().zip(&case.values).map(|(n, v)| (n.clone(), format!("{v:e}"))).collect();
        let mut flat = parsed.flatten(&sets)?;
        if let Some(seed) = case.seed {
            flat.sim.seed = seed;
        }
        let model = crate::recompile_flat(&base, &flat, &registry)?;
        run_checks_by(runner, model, &sets, case.seed, None)
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.max(1))
        .build()
        .map_err(|e| Failure::Run(format!("cannot start {jobs} jobs: {e}")))?;
    let mut rows: Vec<Row> = pool.install(|| {
        cases
            .par_iter()
            .filter_map(|case| {
                if stop.load(Ordering::Relaxed) {
                    return None;
                }
                let start = std::time::Instant::now();
                let outcome = simulate(case);
                let wall = start.elapsed().as_secs_f64();
                let (result, trace) = match outcome {
                    Ok((trace, checks)) => {
                        let written = keep.traces_dir.map(|dir| write_trace(dir, case.index, &trace)).transpose();
                        match written {
                            Ok(_) => (Ok(checks), (keep.in_memory)(case).then_some(trace)),
                            Err(e) => (Err(e), None),
                        }
                    }
                    Err(e) => (Err(e.to_string()), None),
                };
                done();
                Some(Row { case: case.clone(), result, wall, trace })
            })
            .collect()
    });
    rows.sort_by_key(|r| r.case.index);
    Ok(rows)
}

/// Writes a case's signals to `dir/case-NNNNNN.csv` (whole or not at all).
fn write_trace(dir: &Path, index: usize, trace: &crate::record::Trace) -> Result<(), String> {
    let path = dir.join(format!("case-{index:06}.csv"));
    crate::record::write_atomic(&path, crate::record::trace_csv(trace).as_bytes())
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// The results table: `case`, the parameters, `seed`, each check's
/// measured value and pass flag (named as the graph names them), `status`,
/// `error`, `cases` (the sweep's total, for merging shards) and, with
/// `timing`, the wall time in seconds (the one column that varies).
pub fn table(names: &[String], checks: &[String], rows: &[Row], total: usize, timing: bool) -> String {
    let mut w = csv::WriterBuilder::new().from_writer(Vec::new());
    let mut header: Vec<String> = vec!["case".into()];
    header.extend(names.iter().cloned());
    header.push("seed".into());
    for c in checks {
        header.push(c.clone());
        header.push(format!("{c} passed"));
    }
    header.extend(["status", "error", "cases"].map(String::from));
    if timing {
        header.push("wall_s".into());
    }
    let _ = w.write_record(&header);
    for r in rows {
        let mut rec: Vec<String> = vec![r.case.index.to_string()];
        rec.extend(r.case.values.iter().map(|&v| Number(v).to_string()));
        rec.push(r.case.seed.map(|s| s.to_string()).unwrap_or_default());
        for (k, _) in checks.iter().enumerate() {
            match &r.result {
                Ok(results) => {
                    let c = &results[k];
                    rec.push(Number(c.measured).to_string());
                    rec.push(c.passed.to_string());
                }
                Err(_) => rec.extend([String::new(), String::new()]),
            }
        }
        rec.push(r.status().into());
        rec.push(r.result.as_ref().err().cloned().unwrap_or_default());
        rec.push(total.to_string());
        if timing {
            rec.push(format!("{:.6}", r.wall));
        }
        let _ = w.write_record(&rec);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// Per check: how many cases measured it, passes, mean and the 5th, 50th
/// and 95th percentiles of the measured value (nearest rank).
pub fn summary(checks: &[String], rows: &[Row]) -> Vec<String> {
    let mut lines = Vec::new();
    let failed = rows.iter().filter(|r| r.result.is_err()).count();
    lines.push(format!("{} case(s): {} ran, {failed} failed to run", rows.len(), rows.len() - failed));
    for (k, name) in checks.iter().enumerate() {
        let mut values: Vec<f64> = rows
            .iter()
            .filter_map(|r| r.result.as_ref().ok().map(|c| c[k].measured))
            .filter(|v| v.is_finite())
            .collect();
        let passed = rows.iter().filter(|r| r.result.as_ref().is_ok_and(|c| c[k].passed)).count();
        if values.is_empty() {
            lines.push(format!("  {name}: no finite values"));
            continue;
        }
        values.sort_by(f64::total_cmp);
        let pct = |p: f64| values[(((p / 100.0) * values.len() as f64).ceil() as usize).clamp(1, values.len()) - 1];
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        lines.push(format!(
            "  {name}: passed {passed}/{}, mean {}, p5 {}, p50 {}, p95 {}",
            rows.len(),
            short(mean),
            short(pct(5.0)),
            short(pct(50.0)),
            short(pct(95.0))
        ));
    }
    lines
}

/// Six significant digits, shortest form.
fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return v.to_string();
    }
    let scale = 10f64.powi(5 - v.abs().log10().floor() as i32);
    let rounded = (v * scale).round() / scale;
    if (1e-3..1e6).contains(&rounded.abs()) { rounded.to_string() } else { format!("{v:.5e}") }
}

/// Merges shard tables: same header everywhere, every case of the sweep
/// exactly once; rows in case order.
pub fn merge(tables: &[(String, String)]) -> Result<String, String> {
    let mut header: Option<csv::StringRecord> = None;
    let mut rows: Vec<(usize, csv::StringRecord)> = Vec::new();
    let mut total: Option<usize> = None;
    for (name, text) in tables {
        let mut r = csv::ReaderBuilder::new().from_reader(text.as_bytes());
        let h = r.headers().map_err(|e| format!("{name}: {e}"))?.clone();
        let cases_col = h
            .iter()
            .position(|c| c == "cases")
            .ok_or_else(|| format!("{name}: not a sweep table (no `cases` column)"))?;
        match &header {
            None => header = Some(h.clone()),
            Some(first) if *first != h => return Err(format!("{name}: its columns differ from the first table's")),
            _ => {}
        }
        for (line, rec) in r.records().enumerate() {
            let rec = rec.map_err(|e| format!("{name}: {e}"))?;
            let field = |i: usize| rec.get(i).unwrap_or("");
            let index: usize = field(0).parse().map_err(|_| format!("{name}:{}: bad case index", line + 2))?;
            let n: usize = field(cases_col).parse().map_err(|_| format!("{name}:{}: bad case count", line + 2))?;
            if *total.get_or_insert(n) != n {
                return Err(format!(
                    "{name}:{}: from a sweep of {n} cases, the others have {}",
                    line + 2,
                    total.unwrap_or(0)
                ));
            }
            rows.push((index, rec));
        }
    }
    let header = header.ok_or("nothing to merge")?;
    rows.sort_by_key(|(i, _)| *i);
    let total = total.unwrap_or(0);
    for (expected, (index, _)) in rows.iter().enumerate() {
        if *index != expected {
            let what = if *index < expected { "twice" } else { "missing" };
            let case = if *index < expected { *index } else { expected };
            return Err(format!("case {case} is {what} (the sweep has {total} cases)"));
        }
    }
    if rows.len() != total {
        return Err(format!("cases {}..{} are missing (the sweep has {total} cases)", rows.len(), total - 1));
    }
    let mut w = csv::WriterBuilder::new().from_writer(Vec::new());
    let _ = w.write_record(&header);
    for (_, rec) in &rows {
        let _ = w.write_record(rec);
    }
    String::from_utf8(w.into_inner().map_err(|e| e.to_string())?).map_err(|e| e.to_string())
}

/// The check `wanted` names: its exact name, else the one whose name starts
/// with it (it must be unique).
pub fn find_check(checks: &[String], wanted: &str) -> Result<usize, Diagnostic> {
    if let Some(k) = checks.iter().position(|c| c == wanted) {
        return Ok(k);
    }
    let matches: Vec<usize> = (0..checks.len()).filter(|&k| checks[k].starts_with(wanted)).collect();
    match matches.as_slice() {
        [k] => Ok(*k),
        [] => Err(Diagnostic::plain(format!("--plot-metric {wanted}: the graph has no such check"))
            .suggest(wanted, checks.iter().map(String::as_str))
            .or_hint(format!("checks: {}", checks.join("; ")))),
        _ => Err(Diagnostic::plain(format!("--plot-metric {wanted}: more than one check starts so; give more of it"))),
    }
}
