//! `ctlgraph sweep` and `ctlgraph sweep merge`: the command-line side of
//! [`ctlgraph::sweep`] (argument checks, progress, Ctrl-C, output files).

use crate::progress::CaseProgress;
use crate::run_cmd::io_error;
use ctlgraph::record::write_atomic;
use ctlgraph::suite::Failure;
use ctlgraph_core::Diagnostic;
use std::path::{Path, PathBuf};

/// `ctlgraph sweep GRAPH …` options.
#[derive(clap::Args)]
pub(crate) struct SweepArgs {
    /// NAME=LO..HI:N (grid of N), NAME=v1,v2,… (list), or NAME=LO..HI with --random (repeatable).
    #[arg(long, value_name = "SPEC")]
    vary: Vec<String>,
    /// Draw this many random values of every NAME=LO..HI.
    #[arg(long, value_name = "N")]
    random: Option<usize>,
    /// Run every case with each seed A..B (inclusive).
    #[arg(long, value_name = "A..B")]
    seeds: Option<String>,
    /// Seed of the random draws.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "J")]
    jobs: Option<usize>,
    /// Run only the cases with index ≡ K (mod N): one task of a job array.
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
    /// The results table (CSV), required.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Add each case's wall time (the only column that varies between runs).
    #[arg(long)]
    timing: bool,
    /// Write each case's recorded signals to DIR/case-NNNNNN.csv.
    #[arg(long, value_name = "DIR")]
    traces: Option<PathBuf>,
    /// Overlay the recorded signals of (up to 50 evenly chosen) cases in one SVG.
    #[arg(long, value_name = "FILE.svg")]
    plot: Option<PathBuf>,
    /// Plot a check's measured value: histogram, line over a 1-parameter grid,
    /// or heat map over a 2-parameter grid; the check by name or a prefix of its text.
    #[arg(long, value_name = "CHECK")]
    plot_metric: Option<String>,
    /// Where --plot-metric draws (default: metric.svg beside --out).
    #[arg(long, value_name = "FILE.svg")]
    metric_svg: Option<PathBuf>,
    #[command(flatten)]
    accelerate: crate::run_cmd::AccelerateArg,
}

/// Parses `A..B` (seeds) or `K/N` (shard) as a pair of whole numbers.
fn pair<T: std::str::FromStr>(flag: &str, arg: &str, sep: &str) -> Result<(T, T), Failure> {
    let bad = || Failure::from(Diagnostic::plain(format!("{flag} {arg}: expected two whole numbers like 1{sep}4")));
    let (a, b) = arg.split_once(sep).ok_or_else(bad)?;
    Ok((a.trim().parse().map_err(|_| bad())?, b.trim().parse().map_err(|_| bad())?))
}

pub(crate) fn sweep(graph: &Path, a: SweepArgs) -> Result<(), Failure> {
    use ctlgraph::sweep::{self, SweepSpec, Vary};
    let Some(out) = a.out.clone() else {
        return Err(Diagnostic::plain("sweep needs --out FILE.csv for the results table").into());
    };
    let text = ctlgraph_core::files::read_text(graph, ctlgraph_core::files::MAX_GRAPH_FILE)
        .map_err(|e| Diagnostic::plain(format!("{}: cannot read: {e}", graph.display())))?;
    let vary = a.vary.iter().map(|v| Vary::parse(v)).collect::<Result<Vec<_>, _>>()?;
    let seeds = a.seeds.as_deref().map(|s| pair::<u64>("--seeds", s, "..")).transpose()?;
    if let Some((lo, hi)) = seeds.filter(|(lo, hi)| lo > hi) {
        return Err(Diagnostic::plain(format!("--seeds {lo}..{hi}: empty range")).into());
    }
    let shard = a.shard.as_deref().map(|s| pair::<usize>("--shard", s, "/")).transpose()?;
    if let Some((k, n)) = shard.filter(|&(k, n)| n == 0 || k >= n) {
        return Err(Diagnostic::plain(format!("--shard {k}/{n}: need 0 <= K < N")).into());
    }
    if vary.is_empty() && seeds.is_none() {
        return Err(Diagnostic::plain("nothing to sweep: give --vary and/or --seeds").into());
    }
    let spec = SweepSpec { vary, random: a.random, seeds, draw_seed: a.seed, shard };
    let all = sweep::cases(&spec)?;
    let total = all.len();
    let mine: Vec<_> = match shard {
        Some((k, n)) => all.into_iter().filter(|c| c.index % n == k).collect(),
        None => all,
    };
    let names: Vec<String> = spec.vary.iter().map(|v| v.name().to_string()).collect();
    let model = ctlgraph::compile_file(graph, &[])?;
    let checks: Vec<String> = model.checks.iter().map(|c| c.name.clone()).collect();
    let (runner, note) = ctlgraph::suite::runner_for(a.accelerate.accelerate, &model, graph)?;
    if let Some(why) = note {
        eprintln!("note: running interpreted, not accelerated: {why}");
    }

    let stop = std::sync::atomic::AtomicBool::new(false);
    let bar = CaseProgress::new(mine.len());
    let interrupted = crate::interrupt::flag();
    let done = || {
        bar.tick();
        if interrupted.load(std::sync::atomic::Ordering::Relaxed) {
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
        }
    };
    let jobs = a.jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if let Some(dir) = &a.traces {
        std::fs::create_dir_all(dir).map_err(io_error(dir))?;
    }
    let metric = a.plot_metric.as_deref().map(|m| sweep::find_check(&checks, m)).transpose()?;
    // Up to 50 cases, evenly spread over the indices, for the family plot.
    let every = mine.len().div_ceil(50).max(1);
    let in_memory = |c: &sweep::Case| a.plot.is_some() && c.index.is_multiple_of(every);
    let keep = sweep::Keep { traces_dir: a.traces.as_deref(), in_memory: &in_memory };
    let rows = sweep::run(&runner, &text, graph, &names, &mine, jobs, &keep, &stop, &done)?;
    bar.finish();
    let table = sweep::table(&names, &checks, &rows, total, a.timing);
    write_atomic(&out, table.as_bytes()).map_err(io_error(&out))?;
    if let Some(path) = &a.plot {
        let svg = ctlgraph::sweep_plot::family(&rows, &graph.display().to_string()).map_err(Failure::Run)?;
        write_atomic(path, svg.as_bytes()).map_err(io_error(path))?;
    }
    if let Some(k) = metric {
        let path = a.metric_svg.clone().unwrap_or_else(|| out.with_file_name("metric.svg"));
        let svg = ctlgraph::sweep_plot::metric(&rows, &spec.vary, k, &checks[k]).map_err(Failure::Run)?;
        write_atomic(&path, svg.as_bytes()).map_err(io_error(&path))?;
    }
    for line in sweep::summary(&checks, &rows) {
        println!("{line}");
    }
    if let Some(cost) = runner.cost() {
        println!("accelerated ({cost})");
    }
    if rows.len() < mine.len() {
        return Err(Failure::Interrupted(format!(
            "interrupted: {} of {} cases written to {}",
            rows.len(),
            mine.len(),
            out.display()
        )));
    }
    Ok(())
}

pub(crate) fn sweep_merge(tables: &[PathBuf], out: &Path) -> Result<(), Failure> {
    let mut texts = Vec::new();
    for t in tables {
        let text =
            std::fs::read_to_string(t).map_err(|e| Diagnostic::plain(format!("{}: cannot read: {e}", t.display())))?;
        texts.push((t.display().to_string(), text));
    }
    let merged = ctlgraph::sweep::merge(&texts).map_err(|m| Failure::from(Diagnostic::plain(m)))?;
    write_atomic(out, merged.as_bytes()).map_err(io_error(out))?;
    println!("{} table(s) merged into {}", tables.len(), out.display());
    Ok(())
}
