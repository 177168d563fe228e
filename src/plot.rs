//! SVG plots of recorded signals (plotters, SVG backend, no system fonts):
//! the graph's `scopes:` panels, or without them one panel per recorded
//! name, stacked over a shared time axis, each with its own y range, grid,
//! legend and unit.

use crate::record::Trace;
use ctlgraph_core::compile::Column;
use ctlgraph_core::scope::Scope;
use plotters::prelude::*;

/// At most this many points per series reach the SVG; longer series are
/// reduced to per-bucket minima and maxima so peaks survive.
const MAX_POINTS: usize = 2000;

/// Okabe & Ito's colour-blind-safe palette (2008), yellow last: blue,
/// vermillion, bluish green, orange, sky blue, reddish purple, black, yellow.
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(204, 121, 167),
    RGBColor(0, 0, 0),
    RGBColor(240, 228, 66),
];

/// A tick label in its shortest form: `250`, not `250.0`; `0`, not `-0.0`.
pub(crate) fn tick(v: &f64) -> String {
    let v = if v.abs() < 1e-12 { 0.0 } else { *v };
    let text = format!("{v:.6}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text.is_empty() || text == "-" { "0".into() } else { text.to_string() }
}
const PANEL_HEIGHT: u32 = 220;
const WIDTH: u32 = 1000;

/// One panel to draw: its trace columns and how to draw them.
pub struct Panel {
    pub title: Option<String>,
    /// Indices into the trace's columns (never 0, the time).
    pub columns: Vec<usize>,
    /// The y axis' label, with its unit.
    pub y_desc: String,
    pub y_limits: Option<[f64; 2]>,
    pub window: Option<[f64; 2]>,
    pub band: Option<[f64; 2]>,
}

/// The panels of `scopes`, or without them one per recorded name
/// (comparisons and vector elements sharing one).
pub fn panels(trace: &Trace, scopes: &[Scope], columns: &[Column]) -> Vec<Panel> {
    if scopes.is_empty() { default_panels(trace, columns) } else { scope_panels(trace, scopes, columns) }
}

/// Renders `trace` as an SVG document titled `title`: the panels of
/// `scopes`, or one per recorded name; `columns` give the units.
pub fn render_svg(trace: &Trace, title: &str, scopes: &[Scope], columns: &[Column]) -> Result<String, String> {
    let panels = panels(trace, scopes, columns);
    if panels.is_empty() {
        return Err("nothing recorded to plot".into());
    }
    let title_space = |p: &Panel| if p.title.is_some() { 24 } else { 0 };
    let height = 60 + panels.iter().map(|p| PANEL_HEIGHT + title_space(p)).sum::<u32>();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut rest = root.titled(title, ("sans-serif", 22)).map_err(|e| e.to_string())?;
        let t = trace.t();
        for p in &panels {
            let (area, below) = rest.split_vertically(PANEL_HEIGHT + title_space(p));
            rest = below;
            draw_panel(&area, trace, t, p)?;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    trace: &Trace,
    t: &[f64],
    p: &Panel,
) -> Result<(), String> {
    let (t0, t1) = match p.window {
        Some([a, b]) => (a, b),
        None => (t[0], *t.last().unwrap_or(&t[0])),
    };
    let t1 = if t1 > t0 { t1 } else { t0 + 1.0 };
    // The samples in the window, and one on each side so lines reach its edges.
    let first = t.partition_point(|&x| x < t0).saturating_sub(1);
    let last = (t.partition_point(|&x| x <= t1) + 1).min(t.len());
    let (lo, hi) = match p.y_limits {
        Some([a, b]) => (a, b),
        None => y_range(p.columns.iter().map(|&c| &trace.columns[c][first..last]), p.band),
    };
    // The axis code works with hi − lo: keep it finite (values near ±f64::MAX).
    let (lo, hi) = if (hi - lo).is_finite() { (lo, hi) } else { (lo.max(f64::MIN / 4.0), hi.min(f64::MAX / 4.0)) };
    let mut builder = ChartBuilder::on(area);
    builder.margin(12).x_label_area_size(36).y_label_area_size(70);
    if let Some(title) = &p.title {
        builder.caption(title, ("sans-serif", 17));
    }
    let mut chart = builder.build_cartesian_2d(t0..t1, lo..hi).map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("t [s]")
        .y_desc(p.y_desc.as_str())
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| e.to_string())?;
    if let Some([a, b]) = p.band {
        let shade = RGBColor(60, 160, 60).mix(0.12);
        chart
            .draw_series([Rectangle::new([(t0, a), (t1, b)], shade.filled())])
            .map_err(|e| e.to_string())?
            .label(format!("band [{a}, {b}]"))
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 18, y + 5)], shade.filled()));
    }
    for (k, &c) in p.columns.iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()].to_rgba();
        let points = reduce(&t[first..last], &trace.columns[c][first..last]);
        chart
            .draw_series(LineSeries::new(points, color.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(trace.headers[c].as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
    }
    let entries = p.columns.len() + usize::from(p.band.is_some());
    let corner = quiet_corner(trace, t, p, (first, last), ([t0, t1], [lo, hi]), entries);
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(corner)
        .draw()
        .map_err(|e| e.to_string())?;
    Ok(())
}

/// The corner of the panel where the legend covers the least of the drawn
/// lines (their length inside it, in panel fractions): the legend is about
/// a fifth of the width wide and one text line per entry high. Lines, not
/// samples: an adaptive run samples a flat stretch of a two-level signal
/// sparsely, and a corner it crosses between two samples is not empty.
fn quiet_corner(
    trace: &Trace,
    t: &[f64],
    p: &Panel,
    (first, last): (usize, usize),
    ([t0, t1], [lo, hi]): ([f64; 2], [f64; 2]),
    entries: usize,
) -> SeriesLabelPosition {
    let (w, h) = (0.22, (0.1 * entries as f64 + 0.05).min(0.9));
    let corners = [
        (SeriesLabelPosition::UpperRight, 1.0 - w, 1.0 - h),
        (SeriesLabelPosition::UpperLeft, 0.0, 1.0 - h),
        (SeriesLabelPosition::LowerRight, 1.0 - w, 0.0),
        (SeriesLabelPosition::LowerLeft, 0.0, 0.0),
    ];
    let at = |k: usize, c: usize| [(t[k] - t0) / (t1 - t0), (trace.columns[c][k] - lo) / (hi - lo)];
    let covered = |x0: f64, y0: f64| -> f64 {
        p.columns
            .iter()
            .flat_map(|&c| (first..last.saturating_sub(1)).map(move |k| (at(k, c), at(k + 1, c))))
            .map(|(a, b)| length_inside(a, b, [x0, x0 + w], [y0, y0 + h]))
            .sum()
    };
    // The first corner of the least ink (`min_by` keeps the first of equals).
    corners
        .into_iter()
        .map(|(corner, x0, y0)| (corner, covered(x0, y0)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(SeriesLabelPosition::UpperRight, |(corner, _)| corner)
}

/// The length of the segment from `a` to `b` inside the box `x` × `y`
/// (Liang–Barsky clipping); 0 for a segment with a value not finite.
fn length_inside(a: [f64; 2], b: [f64; 2], x: [f64; 2], y: [f64; 2]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    if !(a.iter().chain(&b).all(|v| v.is_finite())) {
        return 0.0;
    }
    let (mut enter, mut leave) = (0.0f64, 1.0f64);
    for (p, q) in [(-d[0], a[0] - x[0]), (d[0], x[1] - a[0]), (-d[1], a[1] - y[0]), (d[1], y[1] - a[1])] {
        if p == 0.0 {
            if q < 0.0 {
                return 0.0;
            }
        } else if p < 0.0 {
            enter = enter.max(q / p);
        } else {
            leave = leave.min(q / p);
        }
    }
    if enter < leave { (leave - enter) * d[0].hypot(d[1]) } else { 0.0 }
}

/// `label [unit]`, or the label alone — also when the label already ends
/// in that unit, as a scope's `y_label: "position [mm]"` does.
fn with_unit(label: &str, unit: Option<&str>) -> String {
    match unit {
        Some(u) if !label.trim_end().ends_with(&format!("[{u}]")) => format!("{label} [{u}]"),
        _ => label.to_string(),
    }
}

/// The unit the named records share, if they all have the same one.
fn common_unit<'a>(names: impl Iterator<Item = &'a str>, columns: &'a [Column]) -> Option<&'a str> {
    let mut units = names.map(|n| columns.iter().find(|c| c.name == n).and_then(|c| c.unit.as_deref()));
    let first = units.next()??;
    units.all(|u| u == Some(first)).then_some(first)
}

/// Trace columns of record `name` (all elements of a vector).
pub(crate) fn trace_columns(trace: &Trace, name: &str) -> Vec<usize> {
    let base = |h: &str| h.split('[').next().unwrap_or(h).to_string();
    (1..trace.headers.len()).filter(|&i| base(&trace.headers[i]) == name).collect()
}

fn scope_panels(trace: &Trace, scopes: &[Scope], columns: &[Column]) -> Vec<Panel> {
    scopes
        .iter()
        .map(|s| {
            let names = || s.signals.iter().map(|(n, _)| n.as_str());
            let label = s.y_label.clone().unwrap_or_else(|| names().collect::<Vec<_>>().join(", "));
            let unit = s.unit.as_deref().or_else(|| common_unit(names(), columns));
            Panel {
                title: s.title.clone(),
                columns: names().flat_map(|n| trace_columns(trace, n)).collect(),
                y_desc: with_unit(&label, unit),
                y_limits: s.y_limits,
                window: s.window,
                band: s.band,
            }
        })
        .collect()
}

fn default_panels(trace: &Trace, columns: &[Column]) -> Vec<Panel> {
    let base = |h: &str| h.split('[').next().unwrap_or(h).to_string();
    groups(trace)
        .into_iter()
        .map(|(name, cols)| {
            let records: Vec<String> = cols.iter().map(|&c| base(&trace.headers[c])).collect();
            let unit = common_unit(records.iter().map(String::as_str), columns);
            Panel {
                title: None,
                y_desc: with_unit(&name, unit),
                columns: cols,
                y_limits: None,
                window: None,
                band: None,
            }
        })
        .collect()
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

/// The series' finite range (and the band's), padded by 5 %.
fn y_range<'a>(series: impl Iterator<Item = &'a [f64]>, band: Option<[f64; 2]>) -> (f64, f64) {
    let values = series.flat_map(|y| y.iter().copied()).chain(band.into_iter().flatten());
    let (lo, hi) =
        values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    // Halved before subtracting, so ranges near ±f64::MAX do not overflow.
    let half_span = 0.5 * hi - 0.5 * lo;
    let pad = if half_span > 0.0 { 0.1 * half_span } else { lo.abs().max(1.0) * 0.1 };
    ((lo - pad).max(f64::MIN), (hi + pad).min(f64::MAX))
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
    fn a_segment_is_measured_inside_a_box() {
        let unit = ([0.0, 1.0], [0.0, 1.0]);
        assert!((length_inside([-1.0, 0.5], [2.0, 0.5], unit.0, unit.1) - 1.0).abs() < 1e-12);
        assert!((length_inside([0.0, 0.0], [1.0, 1.0], unit.0, unit.1) - 2f64.sqrt()).abs() < 1e-12);
        assert_eq!(length_inside([2.0, 0.0], [3.0, 1.0], unit.0, unit.1), 0.0);
        assert_eq!(length_inside([0.5, 0.5], [0.5, 0.5], unit.0, unit.1), 0.0);
        assert_eq!(length_inside([0.0, f64::NAN], [1.0, 0.5], unit.0, unit.1), 0.0);
    }

    /// The lower-left corner holds no sample, but a line crosses it (a
    /// drop below the axis between two samples); each other corner holds
    /// one isolated sample and no line. The legend goes where no line is.
    #[test]
    fn the_legend_avoids_a_corner_a_line_crosses_between_samples() {
        let t = vec![0.0, 0.2, 0.8, 0.9, 1.0];
        let nan = f64::NAN;
        let trace = Trace {
            headers: ["t", "a", "b"].map(String::from).to_vec(),
            columns: vec![t.clone(), vec![0.3, -0.5, nan, nan, nan], vec![nan, 0.9, 0.9, 0.1, nan]],
            loop_figures: None,
        };
        let panel =
            Panel { title: None, columns: vec![1, 2], y_desc: String::new(), y_limits: None, window: None, band: None };
        let corner = quiet_corner(&trace, &t, &panel, (0, t.len()), ([0.0, 1.0], [0.0, 1.0]), 1);
        assert!(!matches!(corner, SeriesLabelPosition::LowerLeft), "{corner:?}");
    }

    #[test]
    fn an_axis_label_names_its_unit_once() {
        assert_eq!(with_unit("position", Some("mm")), "position [mm]");
        assert_eq!(with_unit("position [mm]", Some("mm")), "position [mm]");
        assert_eq!(with_unit("position [m]", Some("mm")), "position [m] [mm]");
        assert_eq!(with_unit("u", None), "u");
    }

    #[test]
    fn comparisons_share_a_panel() {
        let headers = ["t", "r", "y_a", "y_b", "v[1]", "v[2]", "d_x"].map(String::from).to_vec();
        let g = groups(&Trace::new(headers));
        let names: Vec<(&str, usize)> = g.iter().map(|(n, c)| (n.as_str(), c.len())).collect();
        assert_eq!(names, [("r", 1), ("y", 2), ("v", 2), ("d_x", 1)]);
    }

    #[test]
    fn the_legend_goes_where_the_curves_are_not() {
        // A ramp from lower left to upper right leaves the upper left and
        // lower right empty; the first empty corner in the order tried wins.
        let mut trace = Trace::new(vec!["t".into(), "y".into()]);
        for k in 0..=100 {
            trace.push(&[k as f64 / 100.0, k as f64 / 100.0]);
        }
        let panel =
            Panel { title: None, columns: vec![1], y_desc: "y".into(), y_limits: None, window: None, band: None };
        let corner = quiet_corner(&trace, trace.t(), &panel, (0, 101), ([0.0, 1.0], [0.0, 1.0]), 1);
        assert!(matches!(corner, SeriesLabelPosition::UpperLeft), "{corner:?}");
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(
            [tick(&250.0), tick(&-0.0), tick(&0.25), tick(&-1e-13), tick(&1.5e-3)],
            ["250", "0", "0.25", "0", "0.0015"]
        );
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
