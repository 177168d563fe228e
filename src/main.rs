//! The `ctlgraph` command line. Exit codes: 0 success; 1 the run failed;
//! 2 the input is invalid (file, YAML, schema, graph, arguments).

use clap::{Parser, Subcommand};
use ctlgraph::record::{CsvFile, Recorder, Trace, write_atomic};
use ctlgraph::report::{RunInfo, to_json};
use ctlgraph_core::flatten::parse_set;
use ctlgraph_core::{Diagnostic, Model, Simulator};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

#[derive(Parser)]
#[command(name = "ctlgraph", version, about = "Declarative control graphs: block diagrams as YAML, simulated headless")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a graph; write CSV, SVG plot and JSON report on request.
    Run {
        graph: PathBuf,
        /// Write the recorded signals as CSV (header `t`, then the recorded names).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Draw the recorded signals as an SVG plot.
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Override a graph parameter (repeatable): --set w0=2000.
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
        /// Stop at this time instead of the graph's `simulation.stop`.
        #[arg(long, value_name = "T")]
        stop_time: Option<f64>,
        /// Write a machine-readable run report (JSON).
        #[arg(long)]
        report: Option<PathBuf>,
    },
    /// Validate a graph and print its execution order with sample times.
    Check {
        graph: PathBuf,
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
    },
    /// Print the graph as Graphviz dot.
    Dot {
        graph: PathBuf,
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
    },
    /// List the block library, or document one block type.
    Blocks { r#type: Option<String> },
}

/// A failure and its exit code.
enum Failure {
    Invalid(Diagnostic),
    Run(String),
}

impl From<Diagnostic> for Failure {
    fn from(d: Diagnostic) -> Self {
        Failure::Invalid(d)
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run { graph, out, plot, sets, stop_time, report } => {
            run(&graph, out.as_deref(), plot.as_deref(), &sets, stop_time, report.as_deref())
        }
        Command::Check { graph, sets } => check(&graph, &sets),
        Command::Dot { graph, sets } => compile(&graph, &sets).map(|m| print!("{}", ctlgraph::dot::to_dot(&m))),
        Command::Blocks { r#type } => blocks(r#type.as_deref()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Invalid(d)) => {
            eprintln!("error: {d}");
            ExitCode::from(2)
        }
        Err(Failure::Run(message)) => {
            eprintln!("error: {message}");
            ExitCode::from(1)
        }
    }
}

fn compile(graph: &Path, sets: &[String]) -> Result<Model, Failure> {
    let sets = sets.iter().map(|s| parse_set(s)).collect::<Result<Vec<_>, _>>()?;
    Ok(ctlgraph::compile_file(graph, &sets)?)
}

fn check(graph: &Path, sets: &[String]) -> Result<(), Failure> {
    let model = compile(graph, sets)?;
    println!("{}: ok", graph.display());
    println!("execution order:");
    let width = model.meta.iter().map(|m| m.name.len()).max().unwrap_or(0);
    for (i, m) in model.meta.iter().enumerate() {
        println!("  {:>3}  {:<width$}  {:<26}  {}", i + 1, m.name, m.type_name, m.sample_time);
    }
    let solver = model.sim.method;
    println!(
        "{} blocks, {} continuous states, {} signal values, {} sample rate(s); solver {}, stop {} s",
        model.meta.len(),
        model.n_states,
        model.signal_len,
        model.clocks.len(),
        solver.name(),
        model.sim.stop
    );
    Ok(())
}

fn blocks(ty: Option<&str>) -> Result<(), Failure> {
    let reg = ctlgraph::registry();
    let Some(name) = ty else {
        let mut categories: Vec<&str> = reg.types().map(|t| t.category).collect();
        categories.sort();
        categories.dedup();
        for cat in categories {
            println!("{cat}:");
            for t in reg.types().filter(|t| t.category == cat) {
                println!("  {:<28} {}", t.name, t.summary);
            }
        }
        println!("\n`ctlgraph blocks TYPE` documents one type.");
        return Ok(());
    };
    let Some(t) = reg.get(name) else {
        return Err(Diagnostic::plain(format!("no block type `{name}`")).suggest(name, reg.names()).into());
    };
    println!("{} ({})\n\n{}\n\n{}\n", t.name, t.category, t.summary, t.doc);
    for (title, ports) in [("inputs", t.inputs), ("outputs", t.outputs)] {
        println!("{title}:");
        if ports.is_empty() {
            println!("  (none)");
        }
        for p in ports {
            println!("  {:<14} {}", p.name, p.doc);
        }
    }
    println!("parameters:");
    if t.params.is_empty() {
        println!("  (none)");
    }
    for p in t.params {
        let default = p.default.map_or("required".to_string(), |d| format!("default {d}"));
        println!("  {:<14} {:<18} {}", p.name, default, p.doc);
    }
    Ok(())
}

/// Shows a progress bar on a terminal once a run has taken a while.
struct Progress {
    bar: Option<indicatif::ProgressBar>,
    enabled: bool,
    start: Instant,
    stop: f64,
}

impl Progress {
    fn new(stop: f64) -> Self {
        let enabled = std::io::stderr().is_terminal() && std::env::var_os("CI").is_none();
        Progress { bar: None, enabled, start: Instant::now(), stop }
    }

    fn tick(&mut self, t: f64) {
        if !self.enabled {
            return;
        }
        if self.bar.is_none() && self.start.elapsed() > Duration::from_secs(2) {
            let bar = indicatif::ProgressBar::new(1000);
            bar.set_style(
                indicatif::ProgressStyle::with_template("{bar:40} {percent:>3}% t = {msg} s, eta {eta}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            self.bar = Some(bar);
        }
        if let Some(bar) = &self.bar {
            bar.set_position((1000.0 * t / self.stop) as u64);
            bar.set_message(format!("{t:.4}"));
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

fn run(
    graph: &Path,
    out: Option<&Path>,
    plot: Option<&Path>,
    sets: &[String],
    stop_time: Option<f64>,
    report: Option<&Path>,
) -> Result<(), Failure> {
    if let Some(t) = stop_time.filter(|t| !(*t > 0.0 && t.is_finite())) {
        return Err(Diagnostic::plain(format!("--stop-time {t}: must be a positive number")).into());
    }
    let model = compile(graph, sets)?;
    let seed = model.sim.seed;
    let mut sim = Simulator::new(model, stop_time);
    let headers = sim.model().headers();
    let mut csv = match out {
        Some(path) => Some(
            CsvFile::create(path, &headers)
                .map_err(|e| Failure::Run(format!("cannot write {}: {e}", path.display())))?,
        ),
        None => None,
    };
    let mut trace = plot.map(|_| Trace::new(headers.clone()));
    let mut recorder = Recorder::new(sim.model());
    let mut progress = Progress::new(sim.stop_time());
    let mut steps = 0u64;
    let start = Instant::now();
    let mut emit = |row: &[f64]| {
        if let Some(c) = csv.as_mut() {
            c.write_row(row);
        }
        if let Some(tr) = trace.as_mut() {
            tr.push(row);
        }
    };
    let result = sim.run(&mut |t, signals| {
        recorder.sample(t, signals, &mut emit);
        steps += 1;
        if steps.is_multiple_of(1024) {
            progress.tick(t);
        }
    });
    recorder.flush(&mut emit);
    progress.finish();
    let wall = start.elapsed().as_secs_f64();
    if let Some(path) = report {
        let bytes = std::fs::read(graph).unwrap_or_default();
        let info = RunInfo {
            graph: &graph.display().to_string(),
            graph_bytes: &bytes,
            method: sim.method(),
            stats: sim.stats(),
            seed,
            stop: sim.stop_time(),
            simulated: sim.time(),
            wall_seconds: wall,
            error: result.as_ref().err().map(ToString::to_string),
        };
        let text = serde_json::to_string_pretty(&to_json(&info)).unwrap_or_default();
        write_atomic(path, text.as_bytes())
            .map_err(|e| Failure::Run(format!("cannot write {}: {e}", path.display())))?;
    }
    result.map_err(|e| Failure::Run(e.to_string()))?;
    if let (Some(c), Some(path)) = (csv, out) {
        c.commit().map_err(|e| Failure::Run(format!("cannot write {}: {e}", path.display())))?;
    }
    if let (Some(tr), Some(path)) = (trace, plot) {
        let title = sim.model().name.clone().unwrap_or_else(|| graph.display().to_string());
        let svg = ctlgraph::plot::render_svg(&tr, &title).map_err(Failure::Run)?;
        write_atomic(path, svg.as_bytes())
            .map_err(|e| Failure::Run(format!("cannot write {}: {e}", path.display())))?;
    }
    let simulated = sim.time();
    let wall_text = if wall < 1.0 { format!("{:.2} ms", wall * 1e3) } else { format!("{wall:.3} s") };
    println!(
        "{}: {} steps, {simulated} s simulated in {wall_text} wall ({:.1}x real time)",
        graph.display(),
        sim.stats().major_steps,
        simulated / wall.max(1e-9)
    );
    Ok(())
}
