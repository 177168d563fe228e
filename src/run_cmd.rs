//! `ctlgraph run`: simulate one graph, write its CSV, plot and report, and
//! print the summary. A run that ends early — a numeric fault, Ctrl-C, a
//! step or wall-time budget — still writes its outputs, whole, for what was
//! simulated, so the user can look at what led there.

use crate::interrupt;
use crate::progress::Progress;
use ctlgraph::accel::{Accelerate, AcceleratedRun, Cost, ROWS_PER_BATCH};
use ctlgraph::html::Report;
use ctlgraph::record::{CsvFile, Number, Recorder, Trace, write_atomic};
use ctlgraph::report::{RunInfo, to_json};
use ctlgraph::suite::Failure;
use ctlgraph_core::flatten::parse_set;
use ctlgraph_core::{Diagnostic, RunStats, Simulator};
use std::path::Path;
use std::time::Instant;

/// `--accelerate[=on|require|off]`, shared by run, test, prop and sweep.
#[derive(clap::Args, Clone, Copy)]
pub(crate) struct AccelerateArg {
    /// Run the graph's generated step, built once with cargo and cached (overrides
    /// `simulation.accelerate`): `on` (the bare flag) runs interpreted with a note when it
    /// cannot, `require` makes that an error, `off` interprets.
    #[arg(long, value_name = "on|require|off", num_args = 0..=1, default_missing_value = "on",
          require_equals = true, value_parser = Accelerate::parse)]
    pub accelerate: Option<Accelerate>,
}

/// What `run` writes besides the summary line, and its budgets.
pub(crate) struct RunOptions<'a> {
    pub out: Option<&'a Path>,
    pub plot: Option<&'a Path>,
    pub stop_time: Option<f64>,
    pub report: Option<&'a Path>,
    pub html: Option<&'a Path>,
    pub seed: Option<u64>,
    pub max_steps: Option<u64>,
    pub max_wall: Option<f64>,
    /// `--accelerate`, when given (else the graph's `simulation.accelerate`).
    pub accelerate: Option<Accelerate>,
}

/// Block-steps (major steps × blocks) above which a run is announced as
/// long: about a minute at the 50 ns per block-step the scaling bench
/// measures.
const LONG_RUN_BLOCK_STEPS: f64 = 1e9;

/// Why a run ended before its stop time without a numeric fault.
#[derive(Clone, Copy)]
enum Cut {
    Interrupted,
    MaxSteps(u64),
    MaxWall(f64),
}

pub(crate) fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> Failure + '_ {
    move |e| Failure::Run(format!("cannot write {}: {e}", path.display()))
}

/// Refuses option values and output paths that cannot work, before
/// anything is compiled or written.
fn validate(graph: &Path, opts: &RunOptions) -> Result<(), Failure> {
    if let Some(t) = opts.stop_time.filter(|t| !(*t > 0.0 && t.is_finite())) {
        return Err(Diagnostic::plain(format!("--stop-time {t}: must be a positive number")).into());
    }
    if let Some(w) = opts.max_wall.filter(|w| !(*w > 0.0 && w.is_finite())) {
        return Err(Diagnostic::plain(format!("--max-wall {w}: must be a positive number of seconds")).into());
    }
    if opts.max_steps == Some(0) {
        return Err(Diagnostic::plain("--max-steps 0: a run takes at least one step").into());
    }
    if let Some(plot) = opts.plot.filter(|p| !p.extension().is_some_and(|e| e.eq_ignore_ascii_case("svg"))) {
        return Err(Diagnostic::plain(format!("--plot {}: ctlgraph draws SVG", plot.display()))
            .with_hint("name the file .svg (rsvg-convert or a browser turns it into PNG)")
            .into());
    }
    // An output must not overwrite the graph or another output.
    let outputs: Vec<(&str, &Path)> =
        [("--out", opts.out), ("--plot", opts.plot), ("--report", opts.report), ("--html", opts.html)]
            .into_iter()
            .filter_map(|(f, p)| p.map(|p| (f, p)))
            .collect();
    for (i, (flag, p)) in outputs.iter().enumerate() {
        if same_file(p, graph) {
            return Err(Diagnostic::plain(format!("{flag} {}: that is the graph file", p.display())).into());
        }
        if let Some((other, _)) = outputs[..i].iter().find(|(_, q)| same_file(p, q) && p != &Path::new("-")) {
            return Err(Diagnostic::plain(format!("{flag} {}: also given to {other}", p.display())).into());
        }
    }
    Ok(())
}

/// Whether two paths name one file (as written, or once resolved).
pub(crate) fn same_file(a: &Path, b: &Path) -> bool {
    a == b || a.canonicalize().ok().is_some_and(|x| b.canonicalize().ok() == Some(x))
}

/// The warning for a run expected to take long, if it is.
pub(crate) fn long_run_warning(sim: &Simulator) -> Option<String> {
    let steps = sim.expected_major_steps();
    let blocks = sim.model().meta.len();
    (steps * blocks.max(1) as f64 > LONG_RUN_BLOCK_STEPS).then(|| {
        format!(
            "this run takes about {} major steps with {blocks} block{} (minutes or more): \
             Ctrl-C stops it and keeps what was simulated; --max-steps and --max-wall bound it",
            Number(steps),
            if blocks == 1 { "" } else { "s" }
        )
    })
}

pub(crate) fn run(graph: &Path, opts: RunOptions, sets: &[String]) -> Result<(), Failure> {
    let interrupted = interrupt::flag();
    validate(graph, &opts)?;
    // `--out -`: the CSV goes to stdout, the summary to stderr.
    let to_stdout = opts.out.is_some_and(|p| p == Path::new("-"));
    let sets = sets.iter().map(|s| parse_set(s)).collect::<Result<Vec<_>, _>>()?;
    let flat = ctlgraph::load_seeded(graph, &sets, opts.seed)?;
    let model = ctlgraph::compile_flat(&flat, &ctlgraph::registry())?;
    let seed = model.sim.seed;
    let mut sim = Simulator::new(model, opts.stop_time);
    let mut engine = engine(opts.accelerate, &sim, graph, &sets, opts.seed, opts.stop_time)?;
    if let Some(w) = long_run_warning(&sim) {
        eprintln!("warning: {w}");
    }
    // Checks whose window lies after the stop time (a shortened run) cannot
    // measure anything: they are skipped, and said so.
    let (checks, skipped): (Vec<_>, Vec<_>) =
        sim.model().checks.iter().cloned().partition(|c| c.window_problem(sim.stop_time()).is_none());
    let headers = sim.model().headers();
    let mut csv = match opts.out.filter(|_| !to_stdout) {
        Some(path) => Some(CsvFile::create(path, &headers).map_err(io_error(path))?),
        None => None,
    };
    let keep_trace = opts.plot.is_some() || opts.html.is_some() || !checks.is_empty() || to_stdout;
    let mut trace = keep_trace.then(|| Trace::for_run(sim.model(), sim.expected_major_steps()));
    let mut recorder = Recorder::new(sim.model());
    let mut progress = Progress::new(sim.stop_time());
    let (max_steps, max_wall) = (opts.max_steps.unwrap_or(u64::MAX), opts.max_wall.unwrap_or(f64::INFINITY));
    let mut steps = 0u64;
    let mut cut = None;
    let mut last_step = 0.0;
    let start = Instant::now();
    let mut emit = |row: &[f64]| {
        if let Some(c) = csv.as_mut() {
            c.write_row(row);
        }
        if let Some(tr) = trace.as_mut() {
            tr.push(row);
        }
    };
    let mut sink = |t, signals: &[f64]| {
        recorder.sample(t, signals, &mut emit);
        last_step = t;
        steps += 1;
        if steps.is_multiple_of(1024) {
            progress.tick(t);
            if start.elapsed().as_secs_f64() > max_wall {
                cut = Some(Cut::MaxWall(max_wall));
            }
        }
        if steps > max_steps {
            cut = Some(Cut::MaxSteps(max_steps));
        }
        if interrupted.load(std::sync::atomic::Ordering::Relaxed) {
            cut = Some(Cut::Interrupted);
        }
        cut.is_none()
    };
    let result = match engine.accelerated.as_mut() {
        // The library records the rows itself and hands them over in
        // batches; interrupts, the wall budget and progress are looked at
        // per batch, the step budget in the library.
        Some(run) => {
            let mut row = Vec::new();
            let result = run.run_rows(max_steps, ROWS_PER_BATCH, &mut |batch| {
                // Column by column into the trace, row by row into the CSV.
                if let Some(c) = csv.as_mut() {
                    row.resize(batch.width(), 0.0);
                    for r in 0..batch.rows() {
                        batch.row_into(r, &mut row);
                        c.write_row(&row);
                    }
                }
                if let Some(tr) = trace.as_mut() {
                    tr.push_columns(batch);
                }
                last_step = batch.last_time().unwrap_or(last_step);
                progress.tick(last_step);
                if start.elapsed().as_secs_f64() > max_wall {
                    cut = Some(Cut::MaxWall(max_wall));
                }
                if interrupted.load(std::sync::atomic::Ordering::Relaxed) {
                    cut = Some(Cut::Interrupted);
                }
                cut.is_none()
            });
            if matches!(result, Ok(false)) && cut.is_none() {
                cut = Some(Cut::MaxSteps(max_steps));
            }
            result
        }
        None => {
            let result = sim.run_while(&mut sink);
            recorder.flush(&mut emit);
            result
        }
    };
    progress.finish();
    let wall = start.elapsed().as_secs_f64();
    let cost = engine.acceleration.as_ref().and_then(|a| a.as_ref().ok().copied());
    let reached = match &engine.accelerated {
        Some(run) => Reached { time: run.time(), stats: run.stats(), warnings: run.warnings(), cost },
        None => Reached { time: sim.time(), stats: sim.stats(), warnings: sim.warnings().to_vec(), cost },
    };
    // A run that reached its stop time has no cut, even if one was asked
    // for at its last step.
    let cut = if matches!(result, Ok(false)) { cut } else { None };
    let finished = matches!(result, Ok(true));
    let results: Vec<_> = match (finished, &trace) {
        (true, Some(tr)) => checks.iter().map(|c| tr.check(c)).collect(),
        _ => Vec::new(),
    };
    let error = match (&result, cut) {
        (Err(e), _) => Some(e.to_string()),
        (_, Some(cut)) => Some(cut_message(cut, &sim, &reached)),
        _ => None,
    };
    let status = match (&result, cut) {
        (Err(_), _) => "failed",
        (_, Some(Cut::Interrupted)) => "interrupted",
        (_, Some(_)) => "stopped",
        _ if results.iter().any(|c| !c.passed) => "checks failed",
        _ => "ok",
    };
    // The outputs: whole files, for what was simulated (up to the last
    // complete major step when the run ended early).
    if opts.report.is_some() || opts.html.is_some() {
        let bytes = std::fs::read(graph).unwrap_or_default();
        let info = RunInfo {
            graph: &graph.display().to_string(),
            graph_bytes: &bytes,
            method: sim.method(),
            stats: reached.stats,
            seed,
            stop: sim.stop_time(),
            simulated: reached.time,
            wall_seconds: wall,
            status,
            error: error.clone(),
            warnings: &reached.warnings,
            checks: &results,
            columns: &sim.model().columns,
            blocks: &sim.model().meta,
            parameters: &sim.model().parameters,
            overrides: &sets,
            acceleration: engine.acceleration.clone(),
        };
        let json = to_json(&info);
        if let Some(path) = opts.report {
            let text = serde_json::to_string_pretty(&json).unwrap_or_default();
            write_atomic(path, text.as_bytes()).map_err(io_error(path))?;
        }
        if let (Some(path), Some(tr)) = (opts.html, &trace) {
            let page =
                ctlgraph::html::render(&Report { run: &json, trace: tr, flat: &flat, model: sim.model(), notes: &[] });
            write_atomic(path, page.as_bytes()).map_err(io_error(path))?;
        }
    }
    if let (Some(c), Some(path)) = (csv, opts.out) {
        c.commit().map_err(io_error(path))?;
        if let Some(units) = ctlgraph::record::units_csv(sim.model()) {
            let sidecar = ctlgraph::record::units_path(path);
            write_atomic(&sidecar, units.as_bytes()).map_err(io_error(&sidecar))?;
        }
    }
    if let (Some(tr), Some(path)) = (&trace, opts.plot) {
        let title = sim.model().name.clone().unwrap_or_else(|| graph.display().to_string());
        let model = sim.model();
        let svg = ctlgraph::plot::render_svg(tr, &title, &model.scopes, &model.columns).map_err(Failure::Run)?;
        write_atomic(path, svg.as_bytes()).map_err(io_error(path))?;
    }
    let report = summary(graph, &sim, &reached, wall, &results, &skipped, finished);
    if let (true, Some(tr)) = (to_stdout, &trace) {
        let _ = std::io::Write::write_all(&mut std::io::stdout(), ctlgraph::record::trace_csv(tr).as_bytes());
        eprint!("{report}");
    } else {
        print!("{report}");
    }
    let written = [opts.out.filter(|_| !to_stdout), opts.plot, opts.report, opts.html].into_iter().flatten().count();
    let kept = if written > 0 { format!("; the outputs hold the run to t = {last_step}") } else { String::new() };
    match (result, cut) {
        (Err(e), _) => Err(Failure::Run(format!("{e}{kept}"))),
        (_, Some(Cut::Interrupted)) => {
            Err(Failure::Interrupted(format!("{}{kept}", cut_message(Cut::Interrupted, &sim, &reached))))
        }
        (_, Some(c)) => Err(Failure::Run(format!("{}{kept}", cut_message(c, &sim, &reached)))),
        _ => {
            let failed = results.iter().filter(|r| !r.passed).count();
            if failed > 0 {
                return Err(Failure::Run(format!("{failed} of {} checks failed", results.len())));
            }
            Ok(())
        }
    }
}

/// Where the run got to, whichever ran it, and what preparing an
/// accelerated run cost.
struct Reached {
    time: f64,
    stats: RunStats,
    warnings: Vec<String>,
    cost: Option<Cost>,
}

/// What runs the graph: its step library, or (when `accelerated` is
/// `None`) the interpreter.
struct Engine {
    accelerated: Option<AcceleratedRun>,
    /// When acceleration was asked for: what preparing the step cost, or
    /// why the run is interpreted.
    acceleration: Option<Result<Cost, String>>,
}

/// The engine `--accelerate` (or the graph's own setting) asks for; a run
/// that cannot be accelerated is interpreted after a note why (under
/// `require`, that reason is the error).
fn engine(
    flag: Option<Accelerate>,
    sim: &Simulator,
    graph: &Path,
    sets: &[(String, String)],
    seed: Option<u64>,
    stop: Option<f64>,
) -> Result<Engine, Failure> {
    let (runner, note) = ctlgraph::suite::runner_for(flag, sim.model(), graph)?;
    if let Some(why) = &note {
        eprintln!("note: running interpreted, not accelerated: {why}");
    }
    let accelerated = runner
        .start(sets, seed, stop)
        .map_err(|why| Failure::Run(format!("the accelerated step cannot run the graph: {why}")))?;
    let acceleration = runner.cost().map(Ok).or(note.map(Err));
    Ok(Engine { accelerated, acceleration })
}

fn cut_message(cut: Cut, sim: &Simulator, reached: &Reached) -> String {
    let at = format!("t = {} of {} s", reached.time, Number(sim.stop_time()));
    match cut {
        Cut::Interrupted => format!("interrupted at {at}"),
        Cut::MaxSteps(n) => format!("stopped at {at}: --max-steps {n} reached"),
        Cut::MaxWall(w) => format!("stopped at {at}: --max-wall {w} s reached"),
    }
}

/// The lines printed after a run: steps, time and speed, warnings, checks.
fn summary(
    graph: &Path,
    sim: &Simulator,
    reached: &Reached,
    wall: f64,
    results: &[ctlgraph_core::checks::CheckResult],
    skipped: &[ctlgraph_core::checks::Check],
    finished: bool,
) -> String {
    let simulated = reached.time;
    let wall_text = if wall < 1.0 { format!("{:.2} ms", wall * 1e3) } else { format!("{wall:.3} s") };
    let stats = reached.stats;
    let plural = |n: u64, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
    let events = if stats.events > 0 { format!(", {} located", plural(stats.events, "event")) } else { String::new() };
    // Below 10 µs of wall time the ratio would be noise.
    let ratio =
        if wall >= 1e-5 && simulated > 0.0 { format!(" ({:.1}x real time)", simulated / wall) } else { String::new() };
    let accelerated = reached.cost.map(|c| format!(", accelerated ({c})")).unwrap_or_default();
    let mut report = format!(
        "{}: {}{events}, {simulated} s simulated in {wall_text} wall{ratio}{accelerated}\n",
        graph.display(),
        plural(stats.major_steps, "step"),
    );
    for w in sim.model().warnings.iter().chain(&reached.warnings) {
        report.push_str(&format!("  warning: {w}\n"));
    }
    for r in results {
        report.push_str(&format!("  {r}\n"));
    }
    if !finished && !sim.model().checks.is_empty() {
        report.push_str("  checks not evaluated: the run ended before its stop time\n");
    }
    for c in skipped.iter().filter(|_| finished) {
        let why = c.window_problem(sim.stop_time()).unwrap_or_default();
        report.push_str(&format!("  skip  {}  ({why})\n", c.name));
    }
    report
}
