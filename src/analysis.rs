//! Linear analysis of a graph file: its linear model around an operating
//! point ([`ctlgraph_core::linearize`]), frequency response, stability
//! margins, bandwidth and poles ([`ctlgraph_solver::freq`]), as values,
//! CSV, JSON and an SVG Bode plot.

use crate::plot::PALETTE;
use ctlgraph_core::checks::metrics::{LOOP_FIGURES, LoopFigure};
use ctlgraph_core::linearize::{AnalysisError, Linearization, Selection, linearize};
use ctlgraph_solver::freq::{self, Margins};
use plotters::prelude::*;
use serde_json::{Value, json};
use std::path::Path;

/// Loads, compiles and linearises a graph file; `sel` fields left empty
/// are taken from the file's `analysis:` section.
pub fn linearize_file(path: &Path, sets: &[(String, String)], sel: &Selection) -> Result<Linearization, AnalysisError> {
    let model = ctlgraph_core::compile(&ctlgraph_core::load(path, sets)?, &crate::registry())?;
    let sel = merged(sel, model.analysis.as_ref());
    linearize(model, &sel)
}

/// [`linearize_file`] for the analyses that need a transfer (a Bode plot,
/// margins, the matrices B, C, D): refused when neither the command line
/// nor the file names its signals, and when no path leads from the input
/// to the output — figures of the whole model (no input: B = C = 0, gain
/// margin ∞) would look like results and mean nothing.
pub fn linearize_transfer(
    path: &Path,
    sets: &[(String, String)],
    sel: &Selection,
) -> Result<Linearization, AnalysisError> {
    let model = ctlgraph_core::compile(&ctlgraph_core::load(path, sets)?, &crate::registry())?;
    let sel = merged(sel, model.analysis.as_ref());
    if sel.input.is_none() && sel.output.is_none() && sel.open.is_none() {
        let on = model.on_loops();
        let loops: Vec<&str> = (0..on.len()).filter(|&i| on[i]).map(|i| model.meta[i].name.as_str()).collect();
        let hint = match loops.as_slice() {
            [] => "the graph has no feedback loop: name a transfer with --input SIGNAL --output SIGNAL".to_string(),
            some => format!(
                "signals on the graph's loops, to open one with --open: {}{}",
                some.iter().take(12).map(|s| format!("`{s}`")).collect::<Vec<_>>().join(", "),
                if some.len() > 12 { ", …" } else { "" }
            ),
        };
        let message = format!(
            "{}: nothing to analyse: give --input and --output, or --open, or an `analysis:` section in the file",
            path.display()
        );
        return Err(AnalysisError::Invalid(ctlgraph_core::Diagnostic::plain(message).with_hint(hint)));
    }
    let lin = linearize(model, &sel)?;
    if no_path(&lin.system) {
        let message = format!(
            "{}: no path leads from `{}` to `{}`: the transfer is zero at this operating point",
            path.display(),
            lin.input,
            lin.output
        );
        return Err(AnalysisError::Invalid(
            ctlgraph_core::Diagnostic::plain(message).with_hint("check the signals' names and the wiring between them"),
        ));
    }
    Ok(lin)
}

/// Whether a single-input, single-output system's transfer is identically
/// zero: D and every Markov parameter C·Aᵏ·B (k < n) vanish.
fn no_path(ss: &ctlgraph_solver::StateSpace) -> bool {
    if ss.d.iter().any(|&d| d != 0.0) {
        return false;
    }
    let n = ss.n;
    let mut v: Vec<f64> = ss.b.iter().take(n).copied().collect();
    for _ in 0..n {
        if (0..n).map(|i| ss.c[i] * v[i]).sum::<f64>() != 0.0 {
            return false;
        }
        v = (0..n).map(|i| (0..n).map(|j| ss.a[i * n + j] * v[j]).sum()).collect();
    }
    true
}

/// The selection given, completed from the file's `analysis:` section
/// (a command line that names any signal replaces the whole section).
pub fn merged(given: &Selection, file: Option<&Selection>) -> Selection {
    let names_any = given.input.is_some() || given.output.is_some() || given.open.is_some();
    match file {
        Some(f) if !names_any => Selection { at: if given.at > 0.0 { given.at } else { f.at }, ..f.clone() },
        _ => given.clone(),
    }
}

/// Magnitude (absolute) and unwrapped phase (degrees) over a frequency grid [rad/s].
#[derive(Clone, Debug)]
pub struct Bode {
    pub w: Vec<f64>,
    pub magnitude: Vec<f64>,
    pub phase_deg: Vec<f64>,
}

/// The frequency response of `lin` at `points` frequencies from `from` to
/// `to` (log-spaced; the model's own range when not given).
pub fn bode(lin: &Linearization, range: Option<(f64, f64)>, points: usize) -> Bode {
    let (from, to) = range.unwrap_or_else(|| freq::auto_range(&lin.system, lin.sample_time));
    let w = freq::log_grid(from, to, points);
    let values: Vec<_> = w.iter().map(|&w| freq::at_frequency(&lin.system, w, lin.sample_time)).collect();
    Bode { magnitude: values.iter().map(|v| v.norm()).collect(), phase_deg: freq::unwrapped_phase_deg(&values), w }
}

/// Everything read off a loop transfer (or any transfer): margins, its own
/// −3 dB bandwidth and, for a loop, the closed loop's L/(1 + L).
#[derive(Clone, Copy, Debug)]
pub struct Figures {
    pub margins: Margins,
    pub bandwidth: f64,
    pub closed_loop_bandwidth: f64,
}

pub fn figures(lin: &Linearization) -> Figures {
    let (ss, st) = (&lin.system, lin.sample_time);
    let margins = freq::margins(ss, st);
    let (lo, hi) = freq::auto_range(ss, st);
    let (lo, hi) = match st {
        Some(t) => (lo / 1e3, std::f64::consts::PI / t),
        None => (lo / 1e3, hi * 1e3),
    };
    let g = |w: f64| freq::at_frequency(ss, w, st);
    // DC: s = 0, or z = 1.
    let dc = freq::evaluate(ss, if st.is_some() { 1.0.into() } else { 0.0.into() });
    let bandwidth = freq::bandwidth(g, dc, lo, hi);
    let closed = |w: f64| {
        let l = g(w);
        l / (l + 1.0)
    };
    // L(0) infinite (an integrator in the loop): the closed loop's DC gain is 1.
    let dc_closed = if dc.norm().is_finite() { dc / (dc + 1.0) } else { 1.0.into() };
    let closed_loop_bandwidth = freq::bandwidth(closed, dc_closed, lo, hi);
    Figures { margins, bandwidth, closed_loop_bandwidth }
}

/// The figures checks read, indexed by [`LoopFigure`], of the loop a
/// compiled model's `analysis:` section selects, around its initial
/// operating point. A run that fails at the operating point gives NaN
/// (checks on them fail); a selection that cannot be linearised is an
/// error in the graph.
pub fn loop_figures(model: ctlgraph_core::Model) -> Result<Vec<f64>, ctlgraph_core::Diagnostic> {
    let sel = model.analysis.clone().unwrap_or_default();
    let lin = match linearize(model, &sel) {
        Ok(lin) => lin,
        Err(AnalysisError::Invalid(d)) => return Err(d),
        Err(AnalysisError::Run(_)) => return Ok(vec![f64::NAN; LOOP_FIGURES.len()]),
    };
    let f = figures_remembered(&lin);
    let m = &f.margins;
    let mut values = vec![f64::NAN; LOOP_FIGURES.len()];
    for (_, figure, _) in LOOP_FIGURES {
        values[figure as usize] = match figure {
            LoopFigure::PhaseMargin => m.phase_margin,
            LoopFigure::GainMarginDb => 20.0 * m.gain_margin.log10(),
            LoopFigure::DelayMargin => m.delay_margin,
            LoopFigure::PeakSensitivity => m.peak_sensitivity,
            LoopFigure::CrossoverFrequency => m.gain_crossover_freq,
            LoopFigure::Bandwidth => f.bandwidth,
            LoopFigure::ClosedLoopBandwidth => f.closed_loop_bandwidth,
        };
    }
    Ok(values)
}

/// [`figures`] of `lin`, remembered by the linear model's exact bits: the
/// cases of a sweep, a `prop` run or a suite that differ in a seed or a
/// value off the loop linearise to the same matrices, and the frequency
/// responses behind the figures cost several times the run itself (the
/// 200-seed FLADRC sweep spent 72 % of its time on them). The same bits
/// give the same figures, so remembering changes no number.
fn figures_remembered(lin: &Linearization) -> Figures {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    /// Enough for the distinct loops of a sweep over loop parameters to
    /// stay bounded in memory; a full memo is emptied, not evicted.
    const KEPT: usize = 256;
    static MEMO: OnceLock<Mutex<HashMap<Vec<u64>, Figures>>> = OnceLock::new();
    let ss = &lin.system;
    let dims = [ss.n, ss.m, ss.p].map(|d| d as u64);
    let st = lin.sample_time.map_or(u64::MAX, f64::to_bits);
    let numbers = [&ss.a, &ss.b, &ss.c, &ss.d].into_iter().flatten().map(|v| v.to_bits());
    let key: Vec<u64> = dims.into_iter().chain([st]).chain(numbers).collect();
    let memo = MEMO.get_or_init(Default::default);
    if let Some(f) = memo.lock().ok().and_then(|m| m.get(&key).copied()) {
        return f;
    }
    let f = figures(lin);
    if let Ok(mut m) = memo.lock() {
        if m.len() >= KEPT {
            m.clear();
        }
        m.insert(key, f);
    }
    f
}

/// `w` [rad/s], `f` [Hz], magnitude, magnitude in dB, phase in degrees.
pub fn bode_csv(b: &Bode) -> String {
    let mut text = String::from("w,f,magnitude,magnitude_db,phase_deg\n");
    for k in 0..b.w.len() {
        let n = crate::record::Number;
        text.push_str(&format!(
            "{},{},{},{},{}\n",
            n(b.w[k]),
            n(b.w[k] / std::f64::consts::TAU),
            n(b.magnitude[k]),
            n(20.0 * b.magnitude[k].log10()),
            n(b.phase_deg[k])
        ));
    }
    text
}

/// A two-panel Bode plot (magnitude in dB, phase in degrees, over ω on a
/// log axis) with the gain and phase crossovers marked and the margins in
/// the legend.
pub fn bode_svg(b: &Bode, m: &Margins, title: &str) -> Result<String, String> {
    let (w0, w1) = (b.w[0], *b.w.last().unwrap_or(&b.w[0]));
    let db: Vec<f64> = b.magnitude.iter().map(|v| 20.0 * v.log10()).collect();
    let finite = |v: &[f64]| {
        let f = v.iter().copied().filter(|x| x.is_finite());
        let (lo, hi) = f.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
        if lo < hi { (lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo)) } else { (lo - 1.0, hi + 1.0) }
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1000, 640)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        // The description is long (graph, loop, operating point, discrete
        // model): one line per clause, each at a size that fits the width.
        let mut root = root;
        for line in title_lines(title) {
            root = root.titled(line, ("sans-serif", title_size(line, 1000.0))).map_err(|e| e.to_string())?;
        }
        let (top, bottom) = root.split_vertically(300);
        let crossings = [
            (
                m.gain_crossover_freq,
                format!("phase margin {:.4}° at {:.4} rad/s", m.phase_margin, m.gain_crossover_freq),
            ),
            (
                m.gain_crossover_phase_freq,
                format!(
                    "gain margin {:.4} dB at {:.4} rad/s",
                    20.0 * m.gain_margin.log10(),
                    m.gain_crossover_phase_freq
                ),
            ),
        ];
        for (area, values, label, y_desc) in
            [(&top, &db, "|G| [dB]", "magnitude [dB]"), (&bottom, &b.phase_deg, "∠G [°]", "phase [°]")]
        {
            let (lo, hi) = finite(values);
            let mut chart = ChartBuilder::on(area)
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(70)
                .build_cartesian_2d((w0..w1).log_scale(), lo..hi)
                .map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .x_label_formatter(&log_tick)
                .y_label_formatter(&crate::plot::tick)
                .x_desc("ω [rad/s]")
                .y_desc(y_desc)
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(|e| e.to_string())?;
            let color = PALETTE[0].to_rgba();
            chart
                .draw_series(LineSeries::new(b.w.iter().copied().zip(values.iter().copied()), color.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
            for (k, (w, text)) in crossings.iter().enumerate() {
                if w.is_finite() && (w0..=w1).contains(w) {
                    let c = PALETTE[k + 1].to_rgba();
                    chart
                        .draw_series(LineSeries::new([(*w, lo), (*w, hi)], c.stroke_width(1)))
                        .map_err(|e| e.to_string())?
                        .label(text.as_str())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(1)));
                }
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::LowerLeft)
                .draw()
                .map_err(|e| e.to_string())?;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

/// A number for JSON: `null` for NaN and infinities (JSON has none).
/// A plot title's lines: its clauses, split at "; ".
fn title_lines(title: &str) -> impl Iterator<Item = &str> {
    title.split("; ").map(str::trim).filter(|l| !l.is_empty())
}

/// The font size (px, at most 22) at which `line` fits in `width` px with
/// a margin, taking a sans-serif character as 0.6 em wide on average
/// (a generous bound: digits and most lower-case letters are narrower).
fn title_size(line: &str, width: f64) -> f64 {
    let chars = line.chars().count().max(1) as f64;
    (0.95 * width / (0.6 * chars)).min(22.0)
}

/// A tick label of a log axis, to three significant digits: `0.01`,
/// `1000`, `1e-5` — not `9.999999999999999e-6`, the decade computed as
/// 10^-5 in floating point.
fn log_tick(v: &f64) -> String {
    if *v == 0.0 || !v.is_finite() {
        return v.to_string();
    }
    let decade = v.abs().log10().floor() as i32;
    let trim = |s: String| if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
    if (-3..5).contains(&decade) {
        let digits = (2 - decade).max(0) as usize;
        trim(format!("{v:.digits$}"))
    } else {
        let mantissa = v / 10f64.powi(decade);
        // 9.995 rounds to 10.0: carry into the next decade.
        let (mantissa, decade) =
            if mantissa.abs() >= 9.995 { (mantissa / 10.0, decade + 1) } else { (mantissa, decade) };
        format!("{}e{decade}", trim(format!("{mantissa:.2}")))
    }
}

fn num(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// The linear model, its poles and (when given) its loop figures as JSON.
pub fn to_json(lin: &Linearization, figures: Option<&Figures>) -> Value {
    let ss = &lin.system;
    let rows =
        |m: &[f64], r: usize, c: usize| -> Vec<Vec<f64>> { (0..r).map(|i| m[i * c..(i + 1) * c].to_vec()).collect() };
    let poles: Vec<Value> = freq::poles(ss)
        .unwrap_or_default()
        .iter()
        .map(|p| {
            let (wn, zeta) = freq::natural_frequency_and_damping(*p, lin.sample_time);
            json!({ "re": p.re, "im": p.im, "natural_frequency": wn, "damping": zeta })
        })
        .collect();
    let mut out = json!({
        "input": lin.input, "output": lin.output, "loop_transfer": lin.loop_transfer, "at": lin.at,
        "continuous": lin.sample_time.is_none(),
        "sample_time": lin.sample_time,
        "states": lin.states,
        "a": rows(&ss.a, ss.n, ss.n), "b": rows(&ss.b, ss.n, 1), "c": rows(&ss.c, 1, ss.n), "d": rows(&ss.d, 1, 1),
        "poles": poles,
        "exact": lin.exact, "perturbed": lin.perturbed, "warnings": lin.warnings,
    });
    if let Some(f) = figures {
        let m = &f.margins;
        out["margins"] = json!({
            "gain_margin": num(m.gain_margin), "gain_margin_db": num(20.0 * m.gain_margin.log10()),
            "phase_crossover_frequency": num(m.gain_crossover_phase_freq),
            "phase_margin_deg": num(m.phase_margin), "gain_crossover_frequency": num(m.gain_crossover_freq),
            "delay_margin": num(m.delay_margin),
            "peak_sensitivity": num(m.peak_sensitivity), "peak_sensitivity_frequency": num(m.peak_sensitivity_freq),
            "bandwidth": num(f.bandwidth), "closed_loop_bandwidth": num(f.closed_loop_bandwidth),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{log_tick, title_lines, title_size};

    #[test]
    fn log_axis_ticks_are_short() {
        let cases = [
            (9.999999999999999e-6, "1e-5"),
            (1e-7, "1e-7"),
            (2.5e-7, "2.5e-7"),
            (0.001, "0.001"),
            (0.01, "0.01"),
            (1.0, "1"),
            (1000.0, "1000"),
            (1e5, "1e5"),
            (99_950.0, "99950"),
            (9.9996e5, "1e6"),
        ];
        for (v, text) in cases {
            assert_eq!(log_tick(&v), text, "{v}");
        }
    }

    /// A discrete loop's description (175 characters) was one title line
    /// at 22 px, some 1 600 px wide on a 1 000 px plot: cut at both ends.
    #[test]
    fn a_long_bode_title_is_split_into_lines_that_fit() {
        let title = "graphs/tutorial/multirate.yaml: loop transfer at `ctrl` (negative feedback), around t = 0; \
                     discrete model at the sample time T = 0.001 s (continuous part by zero-order hold)";
        let lines: Vec<&str> = title_lines(title).collect();
        assert_eq!(lines.len(), 2);
        for line in lines {
            let size = title_size(line, 1000.0);
            assert!(line.chars().count() as f64 * 0.6 * size <= 950.0 + 1e-9, "{line} at {size}");
            assert!(size > 10.0, "{line} readable at {size} px");
        }
        assert_eq!(title_size("short", 1000.0), 22.0);
    }
}
