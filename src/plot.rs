//! SVG plots of recorded signals (plotters, SVG backend, no system fonts):
//! one panel per recorded name, stacked over a shared time axis, each with
//! its own y range, grid and legend.

use crate::record::Trace;
use plotters::prelude::*;

/// At most this many points per series reach the SVG; longer series are
/// reduced to per-bucket minima and maxima so peaks survive.
const MAX_POINTS: usize = 2000;
const PANEL_HEIGHT: u32 = 220;
const WIDTH: u32 = 1000;

/// Renders `trace` as an SVG document titled `title`.
pub fn render_svg(trace: &Trace, title: &str) -> Result<String, String> {
    let groups = groups(trace);
    if groups.is_empty() {
        return Err("nothing recorded to plot".into());
    }
    let height = 60 + PANEL_HEIGHT * groups.len() as u32;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let root = root.titled(title, ("sans-serif", 22)).map_err(|e| e.to_string())?;
        let panels = root.split_evenly((groups.len(), 1));
        let t = trace.t();
        let (t0, t1) = (t[0], *t.last().unwrap_or(&t[0]));
        let t1 = if t1 > t0 { t1 } else { t0 + 1.0 };
        for ((name, cols), panel) in groups.iter().zip(&panels) {
            let (lo, hi) = y_range(trace, cols);
            let mut chart = ChartBuilder::on(panel)
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(70)
                .build_cartesian_2d(t0..t1, lo..hi)
                .map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .x_desc("t [s]")
                .y_desc(name.as_str())
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(|e| e.to_string())?;
            for (k, &c) in cols.iter().enumerate() {
                let color = Palette99::pick(k).to_rgba();
                let points = reduce(t, &trace.columns[c]);
                chart
                    .draw_series(LineSeries::new(points, color.stroke_width(2)))
                    .map_err(|e| e.to_string())?
                    .label(trace.headers[c].as_str())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(|e| e.to_string())?;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

/// Columns grouped into panels: elements of a vector (`x[1]`, `x[2]`)
/// share the panel `x`, and names with a common stem before `_`
/// (`y_fladrc`, `y_fpid`) share the panel `y` — that is how comparisons are
/// recorded.
fn groups(trace: &Trace) -> Vec<(String, Vec<usize>)> {
    let base = |h: &str| h.split('[').next().unwrap_or(h).to_string();
    let stem = |b: &str| b.split_once('_').map(|(s, _)| s.to_string());
    let bases: Vec<String> = trace.headers.iter().skip(1).map(|h| base(h)).collect();
    let mut out: Vec<(String, Vec<usize>)> = Vec::new();
    for (k, b) in bases.iter().enumerate() {
        let shared =
            stem(b).filter(|s| bases.iter().filter(|o| *o != b && stem(o).as_deref() == Some(s.as_str())).count() > 0);
        let panel = shared.unwrap_or_else(|| b.clone());
        match out.iter_mut().find(|(p, _)| *p == panel) {
            Some((_, cols)) => cols.push(k + 1),
            None => out.push((panel, vec![k + 1])),
        }
    }
    out
}

fn y_range(trace: &Trace, cols: &[usize]) -> (f64, f64) {
    let values = cols.iter().flat_map(|&c| trace.columns[c].iter().copied()).filter(|v| v.is_finite());
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = if hi > lo { 0.05 * (hi - lo) } else { lo.abs().max(1.0) * 0.1 };
    (lo - pad, hi + pad)
}

/// Min/max per bucket, in time order, for long series; then points that
/// stay within a thousandth of the series' range of the last point kept
/// are dropped (plateaus and held discrete signals become single segments,
/// and the SVG has no pile-ups of points on one pixel).
fn reduce(t: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    let points = bucket_extremes(t, y);
    let (lo, hi) = points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.1), hi.max(p.1)));
    let tol = if hi > lo { 1e-3 * (hi - lo) } else { 0.0 };
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(points.len());
    for (i, &p) in points.iter().enumerate() {
        let last = out.last().map_or(f64::NAN, |q: &(f64, f64)| q.1);
        let next = points.get(i + 1).map_or(f64::NAN, |q| q.1);
        let flat = (p.1 - last).abs() <= tol && (next - last).abs() <= tol;
        if !flat {
            out.push(p);
        }
    }
    if let Some(&end) = points.last().filter(|&&end| out.last() != Some(&end)) {
        out.push(end);
    }
    out
}

fn bucket_extremes(t: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    if y.len() <= MAX_POINTS {
        return t.iter().copied().zip(y.iter().copied()).collect();
    }
    let bucket = y.len().div_ceil(MAX_POINTS / 2);
    let mut out = Vec::with_capacity(MAX_POINTS + 2);
    for start in (0..y.len()).step_by(bucket) {
        let end = (start + bucket).min(y.len());
        let (mut imin, mut imax) = (start, start);
        for i in start..end {
            if y[i] < y[imin] {
                imin = i;
            }
            if y[i] > y[imax] {
                imax = i;
            }
        }
        let (a, b) = if imin <= imax { (imin, imax) } else { (imax, imin) };
        out.push((t[a], y[a]));
        if b != a {
            out.push((t[b], y[b]));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comparisons_share_a_panel() {
        let headers = ["t", "r", "y_a", "y_b", "v[1]", "v[2]", "d_x"].map(String::from).to_vec();
        let g = groups(&Trace::new(headers));
        let names: Vec<(&str, usize)> = g.iter().map(|(n, c)| (n.as_str(), c.len())).collect();
        assert_eq!(names, [("r", 1), ("y", 2), ("v", 2), ("d_x", 1)]);
    }

    #[test]
    fn reduction_keeps_extremes() {
        let t: Vec<f64> = (0..100_000).map(|i| i as f64).collect();
        let mut y = vec![0.0; t.len()];
        y[54_321] = 9.0;
        y[77_777] = -4.0;
        let r = reduce(&t, &y);
        assert!(r.len() <= MAX_POINTS + 2);
        assert!(r.contains(&(54_321.0, 9.0)) && r.contains(&(77_777.0, -4.0)));
        assert!(r.len() < 12, "plateaus keep only their ends: {}", r.len());
        assert!(r.windows(2).all(|w| w[0].0 <= w[1].0));
    }
}
