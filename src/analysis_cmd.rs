//! `ctlgraph linearize`, `bode` and `poles`: linear analysis of a graph
//! file from the command line (the computations are `ctlgraph::analysis`).

use crate::run_cmd::io_error;
use ctlgraph::analysis::{self, Figures};
use ctlgraph::record::write_atomic;
use ctlgraph::suite::Failure;
use ctlgraph_core::Diagnostic;
use ctlgraph_core::flatten::parse_set;
use ctlgraph_core::linearize::{AnalysisError, Linearization, Selection};
use ctlgraph_solver::freq;
use std::path::{Path, PathBuf};

/// [`analysis::linearize_file`] or [`analysis::linearize_transfer`].
type Linearizer = fn(&Path, &[(String, String)], &Selection) -> Result<Linearization, AnalysisError>;

/// What to analyse (the graph's `analysis:` section when no signal is named).
#[derive(clap::Args)]
pub(crate) struct SelectArgs {
    /// The graph file (YAML).
    graph: PathBuf,
    /// Signal where the perturbation is added: `block.port`, `block`, `name[k]`.
    #[arg(long, value_name = "SIGNAL")]
    input: Option<String>,
    /// Signal measured.
    #[arg(long, value_name = "SIGNAL")]
    output: Option<String>,
    /// Cut the loop at this signal; alone, the loop transfer L there (negative feedback).
    #[arg(long, value_name = "SIGNAL")]
    open: Option<String>,
    /// Operating point: the state the run reaches at this time [s].
    #[arg(long, value_name = "T", default_value_t = 0.0)]
    at: f64,
    /// Override a graph parameter (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
}

impl SelectArgs {
    /// The linear model of the whole graph, or of the transfer selected.
    fn linearize(&self) -> Result<Linearization, Failure> {
        self.linearize_with(analysis::linearize_file)
    }

    /// The transfer selected (refused when nothing is, or nothing connects it).
    fn linearize_transfer(&self) -> Result<Linearization, Failure> {
        self.linearize_with(analysis::linearize_transfer)
    }

    fn linearize_with(&self, linearize: Linearizer) -> Result<Linearization, Failure> {
        let sets = self.sets.iter().map(|s| parse_set(s)).collect::<Result<Vec<_>, _>>()?;
        let sel = Selection {
            input: self.input.clone(),
            output: self.output.clone(),
            open: self.open.clone(),
            at: self.at,
            pos: None,
        };
        linearize(&self.graph, &sets, &sel).map_err(|e| match e {
            AnalysisError::Invalid(d) => Failure::Invalid(d),
            AnalysisError::Run(e) => Failure::Run(format!("reaching the operating point: {e}")),
        })
    }
}

/// A number to seven significant digits, shortest form, no negative zero
/// (the JSON output has every digit).
fn sig(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 { "0".into() } else { v.to_string() };
    }
    let rounded: f64 = format!("{v:.6e}").parse().unwrap_or(v);
    if (1e-4..1e7).contains(&rounded.abs()) { rounded.to_string() } else { format!("{rounded:e}") }
}

fn describe(graph: &Path, lin: &Linearization) -> String {
    let what = if lin.loop_transfer {
        format!("loop transfer at `{}` (negative feedback)", lin.input)
    } else if lin.input.is_empty() {
        "the whole model".to_string()
    } else {
        format!("from `{}` to `{}`", lin.input, lin.output)
    };
    let model = match lin.sample_time {
        Some(t) => format!("; discrete model at the sample time T = {} s (continuous part by zero-order hold)", sig(t)),
        None => String::new(),
    };
    format!("{}: {what}, around t = {}{model}", graph.display(), lin.at)
}

fn print_warnings(lin: &Linearization) {
    for w in &lin.warnings {
        println!("warning: {w}");
    }
}

fn matrix(name: &str, m: &[f64], rows: usize, cols: usize) {
    println!("{name} =");
    for r in 0..rows {
        let row: Vec<String> = m[r * cols..(r + 1) * cols].iter().map(|v| format!("{:>14}", sig(*v))).collect();
        println!("  [{}]", row.join(" "));
    }
}

pub(crate) fn linearize(args: SelectArgs, out: Option<&Path>) -> Result<(), Failure> {
    let lin = args.linearize_transfer()?;
    let ss = &lin.system;
    println!("{}", describe(&args.graph, &lin));
    println!("states: {}", if lin.states.is_empty() { "(none)".into() } else { lin.states.join(", ") });
    matrix("A", &ss.a, ss.n, ss.n);
    matrix("B", &ss.b, ss.n, 1);
    matrix("C", &ss.c, 1, ss.n);
    matrix("D", &ss.d, 1, 1);
    println!("exact (own matrices): {}", list(&lin.exact));
    println!("by perturbation: {}", list(&lin.perturbed));
    print_warnings(&lin);
    if let Some(path) = out {
        let text = serde_json::to_string_pretty(&analysis::to_json(&lin, None)).unwrap_or_default();
        write_atomic(path, text.as_bytes()).map_err(io_error(path))?;
    }
    Ok(())
}

fn list(names: &[String]) -> String {
    if names.is_empty() { "(none)".into() } else { names.join(", ") }
}

/// Frequency grid options of `bode`.
#[derive(clap::Args)]
pub(crate) struct GridArgs {
    /// Lowest frequency [rad/s] (default: two decades below the slowest pole).
    #[arg(long, value_name = "W")]
    from: Option<f64>,
    /// Highest frequency [rad/s] (default: two decades above the fastest pole).
    #[arg(long, value_name = "W")]
    to: Option<f64>,
    /// Number of log-spaced frequencies.
    #[arg(long, default_value_t = 400)]
    points: usize,
    /// Write magnitude and phase as CSV (w, f, magnitude, magnitude_db, phase_deg).
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Draw the Bode plot as SVG, crossovers marked.
    #[arg(long, value_name = "FILE")]
    svg: Option<PathBuf>,
    /// Write the model, poles and figures as JSON.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
}

pub(crate) fn bode(args: SelectArgs, grid: GridArgs) -> Result<(), Failure> {
    if !(2..=1_000_000).contains(&grid.points) {
        return Err(Diagnostic::plain(format!("--points {}: from 2 to 1000000", grid.points)).into());
    }
    let lin = args.linearize_transfer()?;
    let auto = freq::auto_range(&lin.system, lin.sample_time);
    let range = (grid.from.unwrap_or(auto.0), grid.to.unwrap_or(auto.1));
    if !(range.0 > 0.0 && range.1 > range.0 && range.1.is_finite()) {
        return Err(Diagnostic::plain(format!("--from {} --to {}: need 0 < from < to", range.0, range.1)).into());
    }
    let b = analysis::bode(&lin, Some(range), grid.points);
    let f = analysis::figures(&lin);
    println!("{}", describe(&args.graph, &lin));
    print_figures(&f, lin.loop_transfer);
    print_warnings(&lin);
    if let Some(path) = &grid.csv {
        write_atomic(path, analysis::bode_csv(&b).as_bytes()).map_err(io_error(path))?;
    }
    if let Some(path) = &grid.svg {
        let title = describe(&args.graph, &lin);
        let svg = analysis::bode_svg(&b, &f.margins, &title).map_err(Failure::Run)?;
        write_atomic(path, svg.as_bytes()).map_err(io_error(path))?;
    }
    if let Some(path) = &grid.out {
        let text = serde_json::to_string_pretty(&analysis::to_json(&lin, Some(&f))).unwrap_or_default();
        write_atomic(path, text.as_bytes()).map_err(io_error(path))?;
    }
    Ok(())
}

fn print_figures(f: &Figures, loop_transfer: bool) {
    let m = &f.margins;
    let at = |w: f64| if w.is_finite() { format!(" at {} rad/s", sig(w)) } else { String::new() };
    println!("  gain margin        {} dB{}", sig(20.0 * m.gain_margin.log10()), at(m.gain_crossover_phase_freq));
    println!("  phase margin       {} deg{}", sig(m.phase_margin), at(m.gain_crossover_freq));
    println!("  delay margin       {} s", sig(m.delay_margin));
    println!("  peak sensitivity   {}{}", sig(m.peak_sensitivity), at(m.peak_sensitivity_freq));
    // A loop transfer's own bandwidth says nothing; its closed loop's does.
    if f.bandwidth.is_finite() && !loop_transfer {
        println!("  bandwidth          {} rad/s", sig(f.bandwidth));
    }
    if f.closed_loop_bandwidth.is_finite() && loop_transfer {
        println!("  closed-loop bandwidth of L/(1+L)  {} rad/s", sig(f.closed_loop_bandwidth));
    }
}

pub(crate) fn poles(args: SelectArgs) -> Result<(), Failure> {
    let lin = args.linearize()?;
    println!("{}", describe(&args.graph, &lin));
    let poles =
        freq::poles(&lin.system).ok_or_else(|| Failure::Run("the eigenvalue iteration did not converge".into()))?;
    if poles.is_empty() {
        println!("  no states: no poles");
    }
    // Parts below 1e-12 of the largest pole are rounding (an integrator's 0).
    let scale = poles.iter().map(|p| p.norm()).fold(0.0, f64::max);
    let clean = |v: f64| if v.abs() <= 1e-12 * scale { 0.0 } else { v };
    println!("  {:<34} {:<18} damping", "pole", "wn [rad/s]");
    for p in poles.iter().filter(|p| p.im >= 0.0) {
        let p = ctlgraph_solver::freq::c64::new(clean(p.re), clean(p.im));
        let (wn, zeta) = freq::natural_frequency_and_damping(p, lin.sample_time);
        let value = if p.im > 0.0 { format!("{} ± {}j", sig(p.re), sig(p.im)) } else { sig(p.re) };
        println!("  {value:<34} {:<18} {}", sig(wn), sig(zeta));
    }
    print_warnings(&lin);
    Ok(())
}
