//! Plots of a sweep: the family of recorded signals overlaid, and one
//! check's measured value over the cases — a histogram for random draws
//! and seeds, a line over a one-parameter grid, a heat map over a
//! two-parameter grid.

use crate::sweep::{Row, Vary};
use plotters::prelude::*;

const WIDTH: u32 = 1000;
const PANEL_HEIGHT: u32 = 220;

fn err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

/// Every recorded signal (one panel each) of the rows that kept a trace,
/// one thin line per case.
pub fn family(rows: &[Row], title: &str) -> Result<String, String> {
    let traces: Vec<&crate::record::Trace> = rows.iter().filter_map(|r| r.trace.as_ref()).collect();
    let Some(first) = traces.first() else { return Err("no case ran to plot".into()) };
    let names = &first.headers[1..];
    let mut svg = String::new();
    {
        let height = 60 + PANEL_HEIGHT * names.len() as u32;
        let root = SVGBackend::with_string(&mut svg, (WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let root = root.titled(&format!("{title}: {} cases", traces.len()), ("sans-serif", 20)).map_err(err)?;
        for (k, panel) in root.split_evenly((names.len(), 1)).iter().enumerate() {
            let col = k + 1;
            let (mut t0, mut t1, mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
            for tr in &traces {
                let (t, y) = (tr.t(), &tr.columns[col]);
                t0 = t0.min(t[0]);
                t1 = t1.max(*t.last().unwrap_or(&t[0]));
                for v in y.iter().filter(|v| v.is_finite()) {
                    lo = lo.min(*v);
                    hi = hi.max(*v);
                }
            }
            if !(lo.is_finite() && hi > lo) {
                (lo, hi) = (lo.min(0.0) - 1.0, hi.max(0.0) + 1.0);
            }
            let mut chart = ChartBuilder::on(panel)
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(70)
                .build_cartesian_2d(t0..t1.max(t0 + 1e-12), lo..hi)
                .map_err(err)?;
            chart.configure_mesh().x_desc("t [s]").y_desc(names[k].as_str()).draw().map_err(err)?;
            for tr in &traces {
                let points = tr.t().iter().copied().zip(tr.columns[col].iter().copied());
                chart.draw_series(LineSeries::new(points, RGBColor(0, 114, 178).mix(0.35))).map_err(err)?;
            }
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// Check `k`'s measured value over the cases (see the module doc).
pub fn metric(rows: &[Row], vary: &[Vary], k: usize, name: &str) -> Result<String, String> {
    let value = |r: &Row| r.result.as_ref().ok().map(|c| c[k].measured).filter(|v| v.is_finite());
    let grids: Vec<usize> = (0..vary.len()).filter(|&i| !matches!(vary[i], Vary::Range { .. })).collect();
    let random = vary.iter().any(|v| matches!(v, Vary::Range { .. }));
    let seeds = rows.iter().map(|r| r.case.seed).collect::<std::collections::BTreeSet<_>>().len() > 1;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, 520)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        match (grids.as_slice(), random || seeds) {
            ([i], false) => line(&root, rows, &value, *i, vary[*i].name(), name)?,
            ([i, j], false) => heat(&root, rows, &value, (*i, *j), (vary[*i].name(), vary[*j].name()), name)?,
            _ => histogram(&root, rows, &value, name)?,
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}

type Area<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;

fn bounds(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if !lo.is_finite() {
        (0.0, 1.0)
    } else if hi > lo {
        (lo, hi)
    } else {
        (lo - 0.5, hi + 0.5)
    }
}

fn histogram(root: &Area, rows: &[Row], value: &dyn Fn(&Row) -> Option<f64>, name: &str) -> Result<(), String> {
    let values: Vec<f64> = rows.iter().filter_map(value).collect();
    let (lo, hi) = bounds(values.iter().copied());
    let bins = ((values.len() as f64).sqrt().ceil() as usize).clamp(5, 50);
    let width = (hi - lo) / bins as f64;
    let mut counts = vec![0u32; bins];
    for v in &values {
        counts[(((v - lo) / width) as usize).min(bins - 1)] += 1;
    }
    let top = counts.iter().copied().max().unwrap_or(1);
    let mut chart = ChartBuilder::on(root)
        .caption(format!("{name}: {} cases", values.len()), ("sans-serif", 18))
        .margin(16)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(lo..hi, 0u32..top + 1)
        .map_err(err)?;
    chart.configure_mesh().x_desc("measured").y_desc("cases").draw().map_err(err)?;
    let bars = counts.iter().enumerate().map(|(b, &c)| {
        let x0 = lo + b as f64 * width;
        Rectangle::new([(x0, 0), (x0 + width, c)], RGBColor(0, 114, 178).mix(0.7).filled())
    });
    chart.draw_series(bars).map_err(err)?;
    Ok(())
}

fn line(
    root: &Area,
    rows: &[Row],
    value: &dyn Fn(&Row) -> Option<f64>,
    i: usize,
    param: &str,
    name: &str,
) -> Result<(), String> {
    let points: Vec<(f64, f64)> = rows.iter().filter_map(|r| value(r).map(|v| (r.case.values[i], v))).collect();
    let (x0, x1) = bounds(points.iter().map(|p| p.0));
    let (y0, y1) = bounds(points.iter().map(|p| p.1));
    let mut chart = ChartBuilder::on(root)
        .caption(name, ("sans-serif", 18))
        .margin(16)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart.configure_mesh().x_desc(param).y_desc("measured").draw().map_err(err)?;
    chart.draw_series(LineSeries::new(points.iter().copied(), RGBColor(0, 114, 178).stroke_width(2))).map_err(err)?;
    chart.draw_series(points.iter().map(|&p| Circle::new(p, 3, RGBColor(0, 114, 178).filled()))).map_err(err)?;
    Ok(())
}

fn heat(
    root: &Area,
    rows: &[Row],
    value: &dyn Fn(&Row) -> Option<f64>,
    (i, j): (usize, usize),
    (pi, pj): (&str, &str),
    name: &str,
) -> Result<(), String> {
    let xs: Vec<f64> = distinct(rows.iter().map(|r| r.case.values[i]));
    let ys: Vec<f64> = distinct(rows.iter().map(|r| r.case.values[j]));
    // Colour scale over the 5th to 95th percentile, so one outlier does not
    // flatten the map; values beyond take the end colours.
    let mut sorted: Vec<f64> = rows.iter().filter_map(value).collect();
    sorted.sort_by(f64::total_cmp);
    let pct = |p: f64| sorted.get(((p * sorted.len() as f64) as usize).min(sorted.len().saturating_sub(1))).copied();
    let (v0, v1) = bounds([pct(0.05), pct(0.95)].into_iter().flatten());
    let (left, right) = root.split_horizontally(WIDTH - 130);
    let mut chart = ChartBuilder::on(&left)
        .caption(format!("{name} over {pi} × {pj} (colours: 5th–95th percentile)"), ("sans-serif", 18))
        .margin(16)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(0..xs.len(), 0..ys.len())
        .map_err(err)?;
    let label = |vals: Vec<f64>| {
        move |k: &usize| vals.get(*k).map_or(String::new(), |v| format!("{}", (v * 1e4).round() / 1e4))
    };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(pi)
        .y_desc(pj)
        .x_label_formatter(&label(xs.clone()))
        .y_label_formatter(&label(ys.clone()))
        .draw()
        .map_err(err)?;
    let cells = rows.iter().map(|r| {
        let (a, b) = (index(&xs, r.case.values[i]), index(&ys, r.case.values[j]));
        let color = match value(r) {
            Some(v) => viridis((v - v0) / (v1 - v0)),
            None => RGBColor(200, 200, 200),
        };
        Rectangle::new([(a, b), (a + 1, b + 1)], color.filled())
    });
    chart.draw_series(cells).map_err(err)?;
    // Colour bar.
    let mut bar = ChartBuilder::on(&right)
        .margin_top(50)
        .margin_bottom(56)
        .y_label_area_size(60)
        .build_cartesian_2d(0..1, v0..v1)
        .map_err(err)?;
    bar.configure_mesh().disable_x_axis().disable_mesh().y_label_style(("sans-serif", 13)).draw().map_err(err)?;
    let steps = 64;
    let bands = (0..steps).map(|s| {
        let (a, b) = (v0 + (v1 - v0) * s as f64 / steps as f64, v0 + (v1 - v0) * (s + 1) as f64 / steps as f64);
        Rectangle::new([(0, a), (1, b)], viridis(s as f64 / steps as f64).filled())
    });
    bar.draw_series(bands).map_err(err)?;
    Ok(())
}

fn distinct(values: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut v: Vec<f64> = values.collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    v
}

fn index(sorted: &[f64], v: f64) -> usize {
    sorted.partition_point(|&x| x < v)
}

/// A five-stop approximation of matplotlib's viridis (perceptually
/// uniform, colour-blind safe) at `x` in [0, 1].
fn viridis(x: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] =
        [(68.0, 1.0, 84.0), (59.0, 82.0, 139.0), (33.0, 145.0, 140.0), (94.0, 201.0, 98.0), (253.0, 231.0, 37.0)];
    let x = if x.is_finite() { x.clamp(0.0, 1.0) } else { 0.0 } * 4.0;
    let k = (x.floor() as usize).min(3);
    let f = x - k as f64;
    let mix = |a: f64, b: f64| (a + (b - a) * f).round() as u8;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}
