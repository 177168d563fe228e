//! The milling paper's stability-lobe diagram, by simulation and by the
//! analytic zeroth-order prediction (Altintas & Budak): sweeps
//! graphs/milling/lobes.yaml over spindle speed × axial depth with
//! ctlgraph's sweep, marks every case that chatters, without and with the
//! H∞ controller, draws docs/milling-lobes.svg and prints the comparison
//! table of docs/milling.md.
//!
//!     cargo run --release --example milling_lobes
//!
//! The tool and cutter are read from graphs/milling/lib/milling_process.yaml
//! and the controller's frequency response is the linear model of
//! graphs/milling/lib/hinf_controller.yaml, so the analytic lobes use the
//! graphs' own values.

use ctlgraph::blocks::milling::lobes::{LobePoint, critical_depth_at, lobes};
use ctlgraph::blocks::milling::{Cutter, engagement};
use ctlgraph::core::linearize::{Selection, linearize};
use ctlgraph::solver::freq::{self, c64};
use ctlgraph::sweep::{Case, Keep, SweepSpec, Vary};
use plotters::prelude::*;
use std::path::Path;
use std::sync::atomic::AtomicBool;

type Res<T> = Result<T, Box<dyn std::error::Error>>;

const GRAPH: &str = "graphs/milling/lobes.yaml";
const RPM: (f64, f64, usize) = (5000.0, 20000.0, 61);
const DEPTH: (f64, f64, usize) = (0.1, 5.0, 50);
const OUT: &str = "docs/milling-lobes.svg";

/// The tool's two modes and the cutter, from the process subsystem's parameters.
struct Tool {
    cutter: Cutter,
    /// (ω [rad/s], ζ, k [N/mm]) of X and Y.
    x: (f64, f64, f64),
    y: (f64, f64, f64),
}

impl Tool {
    fn load() -> Res<Tool> {
        let flat = ctlgraph::core::load(Path::new("graphs/milling/lib/milling_process.yaml"), &[])?;
        let get = |name: &str| {
            flat.parameters.iter().find(|(n, _)| n == name).map(|(_, v)| *v).ok_or(format!("no parameter {name}"))
        };
        // The subsystem's cutting block mills up (`milling: up`).
        let (entry, exit) = engagement(true, get("immersion")?);
        let cutter = Cutter {
            teeth: get("teeth")? as usize,
            omega: 0.0, // the lobes give the speed
            kt: get("kt")?,
            kr: get("kr")?,
            ap: get("ap")?,
            feed: get("ft")?,
            entry,
            exit,
            phase: 0.0,
        };
        Ok(Tool { cutter, x: (get("wx")?, get("zx")?, get("kx")?), y: (get("wy")?, get("zy")?, get("ky")?) })
    }
}

/// (ω²/k)/(ω² − ωc² + 2iζωωc) [mm/N].
fn mode((w, zeta, k): (f64, f64, f64), wc: f64) -> c64 {
    c64::new(w * w / k, 0.0) / c64::new(w * w - wc * wc, 2.0 * zeta * w * wc)
}

/// The controller u = F(s)·x [N/mm]: the linear model of its subsystem.
fn controller() -> Res<ctlgraph::solver::StateSpace> {
    let text = "blocks:\n  x: { type: constant, value: 0 }\n  \
                hinf: { type: subsystem, file: lib/hinf_controller.yaml }\nwires:\n  - x -> hinf.x\n";
    let model = ctlgraph::compile_str(text, "graphs/milling/controller-frf.yaml", &[])?;
    let sel = Selection { input: Some("x".into()), output: Some("hinf/F".into()), ..Selection::default() };
    Ok(linearize(model, &sel)?.system)
}

/// Whether each case chattered (uncontrolled, controlled), by the graph's
/// two checks; a case whose run failed (the vibration overflowed) chattered.
fn simulate() -> Res<Vec<(f64, f64, bool, bool)>> {
    let grid = |name: &str, (lo, hi, n): (f64, f64, usize)| Vary::Grid { name: name.into(), lo, hi, n };
    let spec = SweepSpec {
        vary: vec![grid("rpm", RPM), grid("ap", DEPTH)],
        random: None,
        seeds: None,
        draw_seed: 0,
        shard: None,
    };
    let cases: Vec<Case> = ctlgraph::sweep::cases(&spec)?;
    let names = vec!["rpm".to_string(), "ap".to_string()];
    let text = std::fs::read_to_string(GRAPH)?;
    let jobs = std::thread::available_parallelism().map_or(1, |n| n.get());
    let keep = Keep { traces_dir: None, in_memory: &|_| false };
    eprintln!("{} cases on {jobs} threads …", cases.len());
    let rows = ctlgraph::sweep::run(
        &ctlgraph::accel::Runner::Interpreted,
        &text,
        Path::new(GRAPH),
        &names,
        &cases,
        jobs,
        &keep,
        &AtomicBool::new(false),
        &|| {},
    )
    .map_err(|e| e.to_string())?;
    Ok(rows
        .iter()
        .map(|row| {
            let (open, hinf) = match &row.result {
                Ok(checks) => (!checks[0].passed, !checks[1].passed),
                Err(_) => (true, true),
            };
            (row.case.values[0], row.case.values[1], open, hinf)
        })
        .collect())
}

/// The simulated boundary at `rpm`: midway between the deepest stable
/// depth below the first chattering one and that one (`None`: no chatter).
fn simulated_boundary(cases: &[(f64, f64, bool, bool)], rpm: f64, controlled: bool) -> Option<f64> {
    let step = (DEPTH.1 - DEPTH.0) / (DEPTH.2 - 1) as f64;
    cases
        .iter()
        .filter(|c| c.0 == rpm && if controlled { c.3 } else { c.2 })
        .map(|c| c.1)
        .min_by(f64::total_cmp)
        .map(|first| (first - step / 2.0).max(0.0))
}

fn main() -> Res<()> {
    let tool = Tool::load()?;
    let f = controller()?;
    let wx = tool.x.0;
    let freqs: Vec<f64> = (0..40_000).map(|i| 0.6 * wx + (1.8 - 0.6) * wx * i as f64 / 40_000.0).collect();
    let open = lobes(&tool.cutter, |w| (mode(tool.x, w), mode(tool.y, w)), &freqs, 12);
    let closed = lobes(
        &tool.cutter,
        |w| {
            let g = mode(tool.x, w);
            (g / (c64::new(1.0, 0.0) - g * freq::at_frequency(&f, w, None)), mode(tool.y, w))
        },
        &freqs,
        12,
    );
    let cases = simulate()?;

    // The comparison table, every 1 000 rpm.
    println!("| spindle speed [rpm] | analytic a_lim [mm] | simulated [mm] | with H∞: analytic | simulated |");
    println!("|---|---|---|---|---|");
    let rpms: Vec<f64> = (0..RPM.2).map(|i| RPM.0 + (RPM.1 - RPM.0) * i as f64 / (RPM.2 - 1) as f64).collect();
    let show = |v: Option<f64>| v.map_or("> 5".to_string(), |v| format!("{v:.2}"));
    let mut errors = Vec::new();
    for &rpm in &rpms {
        let (a_open, s_open) = (critical_depth_at(&open, rpm), simulated_boundary(&cases, rpm, false));
        let (a_hinf, s_hinf) = (critical_depth_at(&closed, rpm), simulated_boundary(&cases, rpm, true));
        if let (Some(a), Some(s)) = (a_open, s_open)
            && a < DEPTH.1
        {
            errors.push((s - a) / a);
        }
        if rpm % 1000.0 == 0.0 {
            println!("| {rpm:.0} | {} | {} | {} | {} |", show(a_open), show(s_open), show(a_hinf), show(s_hinf));
        }
    }
    let mean = errors.iter().map(|e| e.abs()).sum::<f64>() / errors.len() as f64;
    let worst = errors.iter().map(|e| e.abs()).fold(0.0, f64::max);
    println!(
        "\nuncontrolled, simulated vs analytic boundary where it is below {} mm: mean |difference| {:.1} %, \
         largest {:.1} % over {} speeds",
        DEPTH.1,
        100.0 * mean,
        100.0 * worst,
        errors.len()
    );
    let lowest = |curves: &[Vec<LobePoint>]| {
        (0..=15_000)
            .map(|i| RPM.0 + (RPM.1 - RPM.0) * i as f64 / 15_000.0)
            .filter_map(|rpm| critical_depth_at(curves, rpm).map(|d| (d, rpm)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap_or((f64::NAN, f64::NAN))
    };
    let ((lo, at), (lc, atc)) = (lowest(&open), lowest(&closed));
    println!(
        "lowest analytic boundary: uncontrolled {lo:.3} mm at {at:.0} rpm, with H∞ {lc:.3} mm at {atc:.0} rpm ({:+.1} %)",
        100.0 * (lc - lo) / lo
    );
    // The paper's cut: compare.yaml's spindle speed at the process's depth.
    let compare = ctlgraph::core::load(Path::new("graphs/milling/compare.yaml"), &[])?;
    let rpm = compare.parameters.iter().find(|(n, _)| n == "rpm").ok_or("compare.yaml: no rpm")?.1;
    draw(&cases, &open, &closed, (rpm, tool.cutter.ap))?;
    println!("wrote {OUT}");
    Ok(())
}

/// Two panels, uncontrolled and with H∞: chattering cases as red cells, the
/// analytic boundaries as lines.
fn draw(
    cases: &[(f64, f64, bool, bool)],
    open: &[Vec<LobePoint>],
    closed: &[Vec<LobePoint>],
    scenario: (f64, f64),
) -> Res<()> {
    let root = SVGBackend::new(OUT, (1200, 480)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((1, 2));
    let (drpm, ddepth) = ((RPM.1 - RPM.0) / (RPM.2 - 1) as f64, (DEPTH.1 - DEPTH.0) / (DEPTH.2 - 1) as f64);
    let boundary = |curves: &[Vec<LobePoint>]| -> Vec<(f64, f64)> {
        (0..=1500)
            .map(|i| RPM.0 + (RPM.1 - RPM.0) * i as f64 / 1500.0)
            .filter_map(|rpm| critical_depth_at(curves, rpm).map(|d| (rpm, d.min(DEPTH.1 + 1.0))))
            .collect()
    };
    let titles = ["Uncontrolled", "H-infinity control on X (eq. 12)"];
    for (k, panel) in panels.iter().enumerate() {
        let mut chart = ChartBuilder::on(panel)
            .caption(titles[k], ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(RPM.0 - drpm / 2.0..RPM.1 + drpm / 2.0, 0.0..DEPTH.1 + ddepth / 2.0)?;
        chart
            .configure_mesh()
            .x_desc("spindle speed [rpm]")
            .y_desc("axial depth ap [mm]")
            .x_label_formatter(&|v| format!("{v:.0}"))
            .light_line_style(WHITE)
            .draw()?;
        let red = RGBColor(230, 120, 100);
        chart
            .draw_series(cases.iter().filter(|c| if k == 0 { c.2 } else { c.3 }).map(|c| {
                Rectangle::new(
                    [(c.0 - drpm / 2.0, c.1 - ddepth / 2.0), (c.0 + drpm / 2.0, c.1 + ddepth / 2.0)],
                    red.filled(),
                )
            }))?
            .label("simulated: chatter")
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], red.filled()));
        chart
            .draw_series(LineSeries::new(boundary(open), BLACK.stroke_width(2)))?
            .label("analytic, uncontrolled (zeroth order)")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 14, y)], BLACK.stroke_width(2)));
        if k == 1 {
            let blue = RGBColor(0, 114, 178);
            chart
                .draw_series(LineSeries::new(boundary(closed), blue.stroke_width(2)))?
                .label("analytic, with H-infinity")
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 14, y)], blue.stroke_width(2)));
        }
        chart
            .draw_series(std::iter::once(Cross::new(scenario, 6, BLACK.stroke_width(2))))?
            .label("the paper's cut (graphs/milling/compare.yaml)")
            .legend(|(x, y)| Cross::new((x + 7, y), 5, BLACK.stroke_width(2)));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
    }
    root.present()?;
    Ok(())
}
