//! The `ctlgraph` command line. Exit codes: 0 success; 1 the run failed;
//! 2 the input is invalid (file, YAML, schema, graph, arguments).

mod analysis_cmd;
mod check_cmd;
mod codegen_cmd;
mod fmu_cmd;
mod interrupt;
mod library_cmd;
mod progress;
mod report_cmd;
mod run_cmd;
mod sweep_cmd;
mod watch_cmd;

use clap::{Parser, Subcommand};
use ctlgraph::accel::Accelerate;
use ctlgraph::prop::{PropConfig, PropOutcome, Vary};
use ctlgraph::suite::Failure;
use ctlgraph_core::flatten::parse_set;
use ctlgraph_core::{Diagnostic, Model};
use progress::CaseProgress;
use run_cmd::AccelerateArg;
use run_cmd::RunOptions;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;
use sweep_cmd::{SweepArgs, sweep, sweep_merge};

/// Loading and compiling a graph allocate a little per YAML node and per
/// block; mimalloc makes a 100 000-block graph compile ~1.4x faster than
/// the system allocator does (README, Performance). The step loop does not
/// allocate, so simulation speed does not depend on it.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(name = "ctlgraph", version, about = "Declarative control graphs: block diagrams as YAML, simulated headless")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum SweepMerge {
    /// Merge shard tables into one, checking that every case is there exactly once.
    Merge {
        /// The shard tables.
        #[arg(required = true)]
        tables: Vec<PathBuf>,
        /// The merged table.
        #[arg(long)]
        out: PathBuf,
    },
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a graph; write CSV, SVG plot and JSON report on request.
    #[command(
        after_help = "Example:\n  ctlgraph run graphs/tutorial/pid_loop.yaml --out out/pid.csv --plot out/pid.svg --set kp=3"
    )]
    Run {
        /// The graph file (YAML).
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
        #[arg(long, value_name = "T", allow_negative_numbers = true)]
        stop_time: Option<f64>,
        /// Write a machine-readable run report (JSON).
        #[arg(long)]
        report: Option<PathBuf>,
        /// Write a self-contained HTML report: diagram, interactive plots, checks, solver, provenance.
        #[arg(long, value_name = "FILE.html")]
        html: Option<PathBuf>,
        /// Override `simulation.seed` (noise realisations).
        #[arg(long)]
        seed: Option<u64>,
        /// End the run after this many major steps (exit 1; the outputs hold what was simulated).
        #[arg(long, value_name = "N")]
        max_steps: Option<u64>,
        /// End the run after this many seconds of wall time (exit 1; the outputs hold what was simulated).
        #[arg(long, value_name = "SECONDS")]
        max_wall: Option<f64>,
        #[command(flatten)]
        accelerate: AccelerateArg,
    },
    /// Run every graph with `checks:` under the given files or folders.
    #[command(after_help = "Example:\n  ctlgraph test graphs/tutorial graphs/fladrc/compare.yaml")]
    Test {
        /// Graph files or folders (default: graphs/).
        paths: Vec<PathBuf>,
        #[command(flatten)]
        accelerate: AccelerateArg,
    },
    /// Property-test a graph: vary parameters, run its checks, shrink failures.
    #[command(
        after_help = "Example:\n  ctlgraph prop graphs/tutorial/pid_loop.yaml --vary kp=1..4 --vary kd=0..0.3 --cases 128"
    )]
    Prop {
        /// The graph file (YAML); it needs `checks:`.
        graph: PathBuf,
        /// A parameter and its range (repeatable): --vary w0=500..2000.
        #[arg(long, value_name = "NAME=LO..HI", required = true)]
        vary: Vec<String>,
        /// Also draw the simulation seed.
        #[arg(long)]
        vary_seed: bool,
        /// Number of parameter sets to draw.
        #[arg(long, default_value_t = 64)]
        cases: u32,
        /// Seed of the drawing (same seed, same cases).
        #[arg(long, default_value_t = 0)]
        seed: u64,
        #[command(flatten)]
        accelerate: AccelerateArg,
    },
    /// Run a designed set of cases (grid, list, random draws, seeds) in parallel and tabulate their checks.
    #[command(
        args_conflicts_with_subcommands = true,
        after_help = "Examples:\n  ctlgraph sweep graphs/tutorial/pid_loop.yaml --vary kp=1..4:20 --vary kd=0..0.3:20 --out grid.csv\n  \
                      ctlgraph sweep graphs/fladrc/compare.yaml --seeds 1..200 --out seeds.csv --shard 0/4\n  \
                      ctlgraph sweep merge seeds-*.csv --out seeds.csv"
    )]
    Sweep {
        #[command(subcommand)]
        merge: Option<SweepMerge>,
        /// The graph file.
        graph: Option<PathBuf>,
        #[command(flatten)]
        args: SweepArgs,
    },
    /// Validate a graph and print its execution order with sample times.
    #[command(after_help = "Example:\n  ctlgraph check graphs/fladrc/fladrc.yaml --set delta=400")]
    Check {
        /// The graph file (YAML).
        graph: PathBuf,
        /// Override a graph parameter (repeatable).
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
    },
    /// The HTML report of an earlier run, from its CSV (`run --out`) and JSON report (`run --report`).
    #[command(after_help = "Example:\n  ctlgraph run graphs/fladrc/compare.yaml --out run.csv --report run.json\n  \
                      ctlgraph report run.csv --json run.json --html report.html")]
    Report {
        /// The recorded signals (CSV written by `run --out`).
        csv: PathBuf,
        /// The run's JSON report (written by `run --report`): graph, parameters set, seed, checks, statistics.
        #[arg(long, value_name = "FILE.json")]
        json: PathBuf,
        /// Where to write the HTML report.
        #[arg(long, value_name = "FILE.html")]
        html: PathBuf,
    },
    /// Write the graph's step as Rust that calls its blocks directly (docs/compiled-step.md), or its sampled controller as C99 (`--target c`).
    #[command(after_help = "Examples:\n  ctlgraph codegen graphs/fladrc/ladrc.yaml --out src/ladrc_step.rs\n  \
                      ctlgraph codegen --target c graphs/fladrc/ladrc.yaml --subsystem ctrl --out ladrc_c --verify\n\n\
                      Rust: the module defines `Step`; run it with `ctlgraph_core::codegen::Compiled::<Step>::new(&model, None)`. \
                      Any graph: every solver, zero crossings, rows between steps; inports hold their given values.\n\
                      C: NAME.h and NAME.c for the blocks of a subsystem (or of the whole graph) that run at sample times; \
                      --verify runs the graph and checks the C on the recorded inputs of every sample (README, \"C for a target\").")]
    Codegen {
        /// The graph file (YAML).
        graph: PathBuf,
        /// What to generate.
        #[arg(long, value_parser = ["rust", "c"], default_value = "rust")]
        target: String,
        /// Rust: the module's file (standard output when omitted). C: the folder for NAME.h and NAME.c.
        #[arg(long, value_name = "FILE.rs|DIR")]
        out: Option<PathBuf>,
        /// C: the top-level subsystem block that is the controller (default: the whole graph).
        #[arg(long, value_name = "BLOCK")]
        subsystem: Option<String>,
        /// C: the prefix of the files, types and functions (default: the subsystem's or the graph file's name).
        #[arg(long, value_name = "NAME")]
        name: Option<String>,
        /// C: the floating-point type.
        #[arg(long = "float", value_parser = ["double", "single"], default_value = "double")]
        float: String,
        /// C: run the graph and compare the compiled C with it at every sample (SIL; exit 1 on a difference above the bound).
        #[arg(long)]
        verify: bool,
        /// C, with --verify: also cross-compile for this CPU and run under QEMU (PIL).
        #[arg(long, value_parser = ["cortex-m4"], value_name = "CPU")]
        target_cpu: Option<String>,
        /// C, with --verify: the largest |difference| accepted (default 0 for double: bit for bit; for single 1e-2 x the largest |output|).
        #[arg(long, value_name = "TOL")]
        tolerance: Option<f64>,
        /// Override a graph parameter (repeatable).
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
    },
    /// Write the graph as a co-simulation FMU (FMI 3.0, or 2.0) for FMPy, Simulink, Dymola, OpenModelica and other importers.
    #[command(after_help = "Examples:\n  ctlgraph fmu graphs/tutorial/controller_io.yaml --out controller.fmu\n  \
                      ctlgraph fmu graphs/fladrc/ladrc.yaml --out ladrc.fmu --fmi 2\n\n\
                      Inputs are the graph's top-level inports, outputs its outports (without any: its recorded \
                      signals), parameters its `parameters:` (fixed after initialisation). The FMU's binary runs the \
                      graph with ctlgraph itself; it is built once with cargo and cached (README, \"As an FMU\").")]
    Fmu {
        /// The graph file (YAML).
        graph: PathBuf,
        /// The FMU to write.
        #[arg(long, value_name = "NAME.fmu")]
        out: PathBuf,
        /// The FMI version.
        #[arg(long, value_parser = ["3", "2"], default_value = "3")]
        fmi: String,
        /// Override a graph parameter (repeatable): the FMU's parameter starts from it.
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
    },
    /// Print the graph as Graphviz dot.
    #[command(
        after_help = "Example (needs Graphviz):\n  ctlgraph dot graphs/tutorial/pid_loop.yaml | dot -Tsvg > pid_loop.svg"
    )]
    Dot {
        /// The graph file (YAML).
        graph: PathBuf,
        /// Override a graph parameter (repeatable).
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
    },
    /// Draw the block diagram as SVG (no external program needed).
    #[command(after_help = "Examples:\n  ctlgraph diagram graphs/tutorial/subsystem.yaml --svg subsystem.svg\n  \
                      ctlgraph diagram graphs/fladrc/compare.yaml --svg compare.svg --expand")]
    Diagram {
        /// The graph file (YAML).
        graph: PathBuf,
        /// Where to write the SVG.
        #[arg(long, value_name = "FILE.svg")]
        svg: PathBuf,
        /// Draw each subsystem's blocks instead of one box per subsystem.
        #[arg(long)]
        expand: bool,
        /// Override a graph parameter (repeatable).
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
    },
    /// The linear model around an operating point: A, B, C, D with states named by block.
    #[command(after_help = "Examples:\n  ctlgraph linearize graphs/tutorial/pid_loop.yaml --open ctrl.u\n  \
                      ctlgraph linearize graphs/tutorial/pid_loop.yaml --input ctrl.u --output plant --out lin.json")]
    Linearize {
        #[command(flatten)]
        select: analysis_cmd::SelectArgs,
        /// Write the model, its state names and poles as JSON.
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
    },
    /// Frequency response and loop figures: gain, phase and delay margins, peak sensitivity, bandwidth.
    #[command(
        after_help = "Example:\n  ctlgraph bode graphs/tutorial/pid_loop.yaml --open ctrl.u --svg bode.svg --csv bode.csv"
    )]
    Bode {
        #[command(flatten)]
        select: analysis_cmd::SelectArgs,
        #[command(flatten)]
        grid: analysis_cmd::GridArgs,
    },
    /// Poles of the linear model, with natural frequencies and damping.
    #[command(after_help = "Example:\n  ctlgraph poles graphs/tutorial/pid_loop.yaml")]
    Poles {
        #[command(flatten)]
        select: analysis_cmd::SelectArgs,
    },
    /// List the block library, or document one block type.
    #[command(
        after_help = "Example:\n  ctlgraph blocks transport_delay\n  ctlgraph blocks --markdown > docs/blocks.md"
    )]
    Blocks {
        /// A block type to document (all types when omitted).
        r#type: Option<String>,
        /// Print the whole reference as Markdown (docs/blocks.md is this output).
        #[arg(long, conflicts_with = "type")]
        markdown: bool,
    },
    /// Run the graph, then again on every save of it or of a file it reads, until Ctrl-C.
    #[command(
        after_help = "Example:\n  ctlgraph watch graphs/tutorial/pid_loop.yaml --plot out/pid.svg --html out/pid.html --serve 8350\n\n\
                      Prints the summary and the checks after every run and rewrites the outputs. With --serve, \
                      http://127.0.0.1:PORT/ shows the HTML report and reloads it after every run (port 0: any free port)."
    )]
    Watch {
        /// The graph file (YAML).
        graph: PathBuf,
        /// Write the recorded signals as CSV after every run.
        #[arg(long, value_name = "FILE.csv")]
        out: Option<PathBuf>,
        /// Draw the recorded signals as SVG after every run.
        #[arg(long, value_name = "FILE.svg")]
        plot: Option<PathBuf>,
        /// Write the HTML report after every run.
        #[arg(long, value_name = "FILE.html")]
        html: Option<PathBuf>,
        /// Serve the HTML report on 127.0.0.1:PORT, reloading itself after every run.
        #[arg(long, value_name = "PORT")]
        serve: Option<u16>,
        /// Override a graph parameter (repeatable).
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
    },
    /// Serve graph files to an editor: the Language Server Protocol over stdio (diagnostics, hover, completion, definition, symbols).
    #[command(
        after_help = "Run by the editor, not by hand: README, \"Editing graphs\", has the settings for VS Code, Neovim and Helix."
    )]
    Lsp,
    /// Print the JSON Schema of graph files, for editors' YAML support (validation, completion, hover).
    #[command(after_help = "Example:\n  ctlgraph schema --out ctlgraph.schema.json\n\n\
                      Then, as the first line of a graph file:\n  \
                      # yaml-language-server: $schema=ctlgraph.schema.json\n\
                      (README, \"Editing graphs\"). Draft-07, generated from the block library.")]
    Schema {
        /// Where to write it (standard output when omitted).
        #[arg(long, value_name = "FILE.json")]
        out: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    interrupt::quiet_on_closed_pipe();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run { graph, out, plot, sets, stop_time, report, html, seed, max_steps, max_wall, accelerate } => {
            run_cmd::run(
                &graph,
                RunOptions {
                    out: out.as_deref(),
                    plot: plot.as_deref(),
                    stop_time,
                    report: report.as_deref(),
                    html: html.as_deref(),
                    seed,
                    max_steps,
                    max_wall,
                    accelerate: accelerate.accelerate,
                },
                &sets,
            )
        }
        Command::Test { paths, accelerate } => test(paths, accelerate.accelerate),
        Command::Prop { graph, vary, vary_seed, cases, seed, accelerate } => {
            prop(&graph, PropConfig { vary: Vec::new(), vary_seed, cases, seed }, &vary, accelerate.accelerate)
        }
        Command::Sweep { merge: Some(SweepMerge::Merge { tables, out }), .. } => sweep_merge(&tables, &out),
        Command::Sweep { merge: None, graph: Some(graph), args } => sweep(&graph, args),
        Command::Sweep { merge: None, graph: None, .. } => {
            Err(Diagnostic::plain("sweep needs a graph file (or `sweep merge TABLES --out FILE`)").into())
        }
        Command::Check { graph, sets } => check_cmd::check(&graph, &sets),
        Command::Linearize { select, out } => analysis_cmd::linearize(select, out.as_deref()),
        Command::Bode { select, grid } => analysis_cmd::bode(select, grid),
        Command::Poles { select } => analysis_cmd::poles(select),
        Command::Codegen { graph, target, out, sets, subsystem, name, float, verify, target_cpu, tolerance } => {
            codegen_cmd::codegen(codegen_cmd::Args {
                graph: &graph,
                c: target == "c",
                out: out.as_deref(),
                subsystem: subsystem.as_deref(),
                name: name.as_deref(),
                single: float == "single",
                verify,
                target_cpu: target_cpu.as_deref(),
                tolerance,
                sets: &sets,
            })
        }
        Command::Fmu { graph, out, fmi, sets } => fmu_cmd::fmu(&graph, &out, &fmi, &sets),
        Command::Dot { graph, sets } => compile(&graph, &sets).map(|m| print!("{}", ctlgraph::dot::to_dot(&m))),
        Command::Diagram { graph, svg, expand, sets } => diagram(&graph, &svg, expand, &sets),
        Command::Report { csv, json, html } => report_cmd::report(&csv, &json, &html),
        Command::Blocks { markdown: true, .. } => {
            print!("{}", ctlgraph::reference::markdown(&ctlgraph::registry()));
            Ok(())
        }
        Command::Blocks { r#type, .. } => library_cmd::blocks(r#type.as_deref()),
        Command::Schema { out } => library_cmd::schema(out.as_deref()),
        Command::Lsp => ctlgraph::lsp::serve_stdio().map_err(Failure::Run),
        Command::Watch { graph, out, plot, html, serve, sets } => watch_cmd::watch(watch_cmd::Args {
            graph: &graph,
            out: out.as_deref(),
            plot: plot.as_deref(),
            html: html.as_deref(),
            serve,
            sets: &sets,
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Invalid(d)) => {
            eprintln!("error: {d}");
            ExitCode::from(2)
        }
        Err(Failure::Run(message)) if message.is_empty() => ExitCode::from(1),
        Err(Failure::Run(message)) => {
            eprintln!("error: {message}");
            ExitCode::from(1)
        }
        Err(Failure::Interrupted(message)) => {
            eprintln!("{message}");
            ExitCode::from(130)
        }
    }
}

/// `text` written to `out` whole (or not at all), or printed without it.
fn write_or_print(out: Option<&Path>, text: &str) -> Result<(), Failure> {
    match out {
        Some(path) => ctlgraph::record::write_atomic(path, text.as_bytes())
            .map_err(|e| Failure::Run(format!("{}: {e}", path.display()))),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

fn compile(graph: &Path, sets: &[String]) -> Result<Model, Failure> {
    let sets = sets.iter().map(|s| parse_set(s)).collect::<Result<Vec<_>, _>>()?;
    Ok(ctlgraph::compile_file(graph, &sets)?)
}

fn diagram(graph: &Path, svg: &Path, expand: bool, sets: &[String]) -> Result<(), Failure> {
    let sets = sets.iter().map(|s| parse_set(s)).collect::<Result<Vec<_>, _>>()?;
    let flat = ctlgraph_core::load(graph, &sets)?;
    let model = ctlgraph_core::compile(&flat, &ctlgraph::registry())?;
    let d = ctlgraph::diagram::build(&flat, &model, expand);
    ctlgraph::record::write_atomic(svg, ctlgraph::diagram::to_svg(&d).as_bytes())
        .map_err(|e| Failure::Run(format!("{}: {e}", svg.display())))?;
    println!("{}: {} boxes, {} wires", svg.display(), d.nodes.len(), d.wires.len());
    Ok(())
}

fn test(paths: Vec<PathBuf>, accelerate: Option<Accelerate>) -> Result<(), Failure> {
    let paths = if paths.is_empty() { vec![PathBuf::from("graphs")] } else { paths };
    let graphs = ctlgraph::suite::discover(&paths)?;
    let start = Instant::now();
    let outcomes = ctlgraph::suite::run_all(&graphs, accelerate);
    let (mut passed, mut failed, mut broken, mut invalid) = (0, 0, 0, false);
    for o in &outcomes {
        println!("{}", o.path.display());
        match &o.accelerated {
            Some(Ok(cost)) => println!("  accelerated ({cost})"),
            Some(Err(why)) => println!("  note: running interpreted, not accelerated: {why}"),
            None => {}
        }
        match &o.result {
            Ok(results) => {
                for r in results {
                    println!("  {r}");
                    if r.passed { passed += 1 } else { failed += 1 }
                }
            }
            Err(e) => {
                println!("  ERROR  {}", e.to_string().replace('\n', "\n         "));
                broken += 1;
                invalid |= matches!(e, Failure::Invalid(_));
            }
        }
    }
    println!(
        "{} graph(s), {} check(s): {passed} passed, {failed} failed{} ({:.2} s)",
        outcomes.len(),
        passed + failed,
        if broken > 0 { format!(", {broken} graph(s) did not run") } else { String::new() },
        start.elapsed().as_secs_f64()
    );
    if outcomes.is_empty() {
        println!(
            "no graphs with `checks:` under {}",
            paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
        );
    }
    match (invalid, failed + broken) {
        (true, _) => Err(Failure::Invalid(Diagnostic::plain("some graphs are invalid (see above)"))),
        (false, 0) => Ok(()),
        (false, _) => Err(Failure::Run(String::new())),
    }
}

fn prop(graph: &Path, mut cfg: PropConfig, vary: &[String], accelerate: Option<Accelerate>) -> Result<(), Failure> {
    cfg.vary = vary.iter().map(|v| Vary::parse(v)).collect::<Result<Vec<_>, _>>()?;
    let (runner, note) = ctlgraph::suite::runner_for(accelerate, &ctlgraph::compile_file(graph, &[])?, graph)?;
    if let Some(why) = note {
        eprintln!("note: running interpreted, not accelerated: {why}");
    }
    let (cases, vary_seed) = (cfg.cases, cfg.vary_seed);
    let ranges: Vec<String> = cfg.vary.iter().map(|v| format!("{} in [{}, {}]", v.name, v.lo, v.hi)).collect();
    let bar = CaseProgress::new(cases as usize);
    let outcome = ctlgraph::prop::run(&runner, graph, &cfg, &|| bar.tick());
    bar.finish();
    match outcome? {
        PropOutcome::Held { cases } => {
            let seeds = if vary_seed { " and random seeds" } else { "" };
            println!("{}: checks hold in {cases} cases for {}{seeds}", graph.display(), ranges.join(", "));
            Ok(())
        }
        PropOutcome::Failed { minimal, reason, after, shrink_steps } => {
            println!(
                "{}: a check fails (case {after} of {cases}); shrunk in {shrink_steps} steps to:",
                graph.display()
            );
            for (n, v) in &minimal.values {
                println!("  {n} = {v}");
            }
            if let Some(s) = minimal.seed {
                println!("  seed = {s}");
            }
            match reason {
                Ok(results) => results.iter().filter(|r| !r.passed).for_each(|r| println!("  {r}")),
                Err(e) => println!("  {e}"),
            }
            println!("reproduce: {}", minimal.command(graph));
            Err(Failure::Run(String::new()))
        }
    }
}
