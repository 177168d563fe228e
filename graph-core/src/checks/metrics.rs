//! Performance metrics of a recorded signal over a time window.
//!
//! A signal is its samples at the major steps, joined by straight lines:
//! window edges are interpolated, integrals are exact for that
//! piecewise-linear signal, crossing times are interpolated.

/// The metrics `checks:` can use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    SettlingTime,
    RiseTime,
    Overshoot,
    FinalValue,
    Max,
    Min,
    MaxAbs,
    Mean,
    Rms,
    Iae,
    Ise,
    Itae,
}

/// Name, metric, and the arguments it takes before the optional window.
pub const METRICS: [(&str, Metric, &[&str]); 13] = [
    ("settling_time", Metric::SettlingTime, &["target", "band"]),
    ("rise_time", Metric::RiseTime, &["target"]),
    ("overshoot", Metric::Overshoot, &["target"]),
    ("final_value", Metric::FinalValue, &[]),
    ("max", Metric::Max, &[]),
    ("min", Metric::Min, &[]),
    ("max_abs", Metric::MaxAbs, &[]),
    ("peak", Metric::MaxAbs, &[]),
    ("mean", Metric::Mean, &[]),
    ("rms", Metric::Rms, &[]),
    ("iae", Metric::Iae, &[]),
    ("ise", Metric::Ise, &[]),
    ("itae", Metric::Itae, &[]),
];

/// Figures of the loop the graph's `analysis:` section selects, which
/// checks read by name (`phase_margin > 45`); computed from the graph's
/// linear model around its initial operating point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoopFigure {
    PhaseMargin,
    GainMarginDb,
    DelayMargin,
    PeakSensitivity,
    CrossoverFrequency,
    Bandwidth,
    ClosedLoopBandwidth,
}

/// Name in checks, figure, what it is.
pub const LOOP_FIGURES: [(&str, LoopFigure, &str); 7] = [
    ("phase_margin", LoopFigure::PhaseMargin, "phase margin [deg] (+inf without a gain crossover)"),
    ("gain_margin_db", LoopFigure::GainMarginDb, "gain margin [dB] (+inf without a phase crossover)"),
    ("delay_margin", LoopFigure::DelayMargin, "delay margin [s]: phase margin over crossover frequency"),
    ("peak_sensitivity", LoopFigure::PeakSensitivity, "Ms = max |1/(1 + L)|"),
    ("crossover_frequency", LoopFigure::CrossoverFrequency, "gain crossover frequency [rad/s]"),
    ("bandwidth", LoopFigure::Bandwidth, "−3 dB bandwidth of the analysed transfer [rad/s]"),
    ("closed_loop_bandwidth", LoopFigure::ClosedLoopBandwidth, "−3 dB bandwidth of L/(1 + L) [rad/s]"),
];

impl LoopFigure {
    pub fn from_name(name: &str) -> Option<LoopFigure> {
        LOOP_FIGURES.iter().find(|(n, _, _)| *n == name).map(|&(_, f, _)| f)
    }
}

impl Metric {
    pub fn from_name(name: &str) -> Option<(Metric, &'static [&'static str])> {
        METRICS.iter().find(|(n, _, _)| *n == name).map(|&(_, m, a)| (m, a))
    }
}

/// The signal restricted to [t0, t1] as points, edges interpolated.
fn window(t: &[f64], y: &[f64], t0: f64, t1: f64) -> Vec<(f64, f64)> {
    let mut pts = Vec::new();
    if t.is_empty() || t1 < t0 {
        return pts;
    }
    let (t0, t1) = (t0.max(t[0]), t1.min(t[t.len() - 1]));
    pts.push((t0, interpolate(t, y, t0)));
    for (&ti, &yi) in t.iter().zip(y) {
        if ti > t0 && ti < t1 {
            pts.push((ti, yi));
        }
    }
    if t1 > t0 {
        pts.push((t1, interpolate(t, y, t1)));
    }
    pts
}

/// y at time `at` (linear between samples; the later sample at a repeated time).
pub fn interpolate(t: &[f64], y: &[f64], at: f64) -> f64 {
    let i = t.partition_point(|&x| x <= at);
    match i {
        0 => y[0],
        i if i >= t.len() => y[t.len() - 1],
        i if t[i] == t[i - 1] => y[i],
        i => y[i - 1] + (y[i] - y[i - 1]) * (at - t[i - 1]) / (t[i] - t[i - 1]),
    }
}

/// ∫ f·g over a segment where both are linear (Simpson is exact here).
fn product_integral(h: f64, fa: f64, fb: f64, ga: f64, gb: f64) -> f64 {
    h / 6.0 * (2.0 * fa * ga + fa * gb + fb * ga + 2.0 * fb * gb)
}

/// Splits each segment where y changes sign, so |y| is linear on pieces.
fn pieces(pts: &[(f64, f64)]) -> Vec<((f64, f64), (f64, f64))> {
    let mut out = Vec::with_capacity(pts.len());
    for w in pts.windows(2) {
        let ((ta, ya), (tb, yb)) = (w[0], w[1]);
        if ya * yb < 0.0 {
            let tz = ta + (tb - ta) * ya / (ya - yb);
            out.push(((ta, ya), (tz, 0.0)));
            out.push(((tz, 0.0), (tb, yb)));
        } else {
            out.push(((ta, ya), (tb, yb)));
        }
    }
    out
}

/// Evaluates a metric. `args` are the metric's own arguments followed by
/// the optional window start and end.
pub fn evaluate(metric: Metric, t: &[f64], y: &[f64], args: &[f64]) -> f64 {
    let own = match metric {
        Metric::SettlingTime => 2,
        Metric::RiseTime | Metric::Overshoot => 1,
        _ => 0,
    };
    let t_end = t.last().copied().unwrap_or(0.0);
    let t0 = args.get(own).copied().unwrap_or(t.first().copied().unwrap_or(0.0));
    let t1 = args.get(own + 1).copied().unwrap_or(t_end);
    let pts = window(t, y, t0, t1);
    if pts.is_empty() {
        return f64::NAN;
    }
    let span = pts[pts.len() - 1].0 - pts[0].0;
    let ys = pts.iter().map(|p| p.1);
    match metric {
        Metric::FinalValue => pts[pts.len() - 1].1,
        Metric::Max => ys.fold(f64::NEG_INFINITY, f64::max),
        Metric::Min => ys.fold(f64::INFINITY, f64::min),
        Metric::MaxAbs => ys.map(f64::abs).fold(0.0, f64::max),
        Metric::Mean => integral(&pts, |_, a, b, h| h * (a + b) / 2.0) / span,
        Metric::Rms => (integral(&pts, |_, a, b, h| product_integral(h, a, b, a, b)) / span).sqrt(),
        Metric::Ise => integral(&pts, |_, a, b, h| product_integral(h, a, b, a, b)),
        Metric::Iae => pieces(&pts).iter().map(|&((ta, a), (tb, b))| (tb - ta) * (a.abs() + b.abs()) / 2.0).sum(),
        Metric::Itae => pieces(&pts)
            .iter()
            .map(|&((ta, a), (tb, b))| product_integral(tb - ta, ta - pts[0].0, tb - pts[0].0, a.abs(), b.abs()))
            .sum(),
        Metric::SettlingTime => settling_time(&pts, args[0], args[1]),
        Metric::RiseTime => rise_time(&pts, args[0]),
        Metric::Overshoot => overshoot(&pts, args[0]),
    }
}

fn integral(pts: &[(f64, f64)], segment: impl Fn(f64, f64, f64, f64) -> f64) -> f64 {
    pts.windows(2).map(|w| segment(w[0].0, w[0].1, w[1].1, w[1].0 - w[0].0)).sum()
}

/// Time from the window start until the signal enters |y − target| <=
/// band·|target| (band itself when the target is 0) for good; infinite if
/// it is outside at the end.
fn settling_time(pts: &[(f64, f64)], target: f64, band: f64) -> f64 {
    let tol = if target == 0.0 { band } else { band * target.abs() };
    let outside = |y: f64| (y - target).abs() > tol;
    let Some(last) = pts.iter().rposition(|p| outside(p.1)) else { return 0.0 };
    if last == pts.len() - 1 {
        return f64::INFINITY;
    }
    // Interpolate where the segment (last, last+1) enters the band.
    let ((ta, ya), (tb, yb)) = (pts[last], pts[last + 1]);
    let edge = if ya > target { target + tol } else { target - tol };
    let t_in = if yb == ya { tb } else { ta + (tb - ta) * (edge - ya) / (yb - ya) };
    t_in - pts[0].0
}

/// First time the signal reaches `level` going from its start value.
fn first_crossing(pts: &[(f64, f64)], level: f64, rising: bool) -> f64 {
    let reached = |y: f64| if rising { y >= level } else { y <= level };
    if reached(pts[0].1) {
        return pts[0].0;
    }
    for w in pts.windows(2) {
        let ((ta, ya), (tb, yb)) = (w[0], w[1]);
        if reached(yb) {
            return ta + (tb - ta) * (level - ya) / (yb - ya);
        }
    }
    f64::INFINITY
}

/// 10 %–90 % rise time of the step from the window's start value to `target`.
fn rise_time(pts: &[(f64, f64)], target: f64) -> f64 {
    let y0 = pts[0].1;
    let rising = target >= y0;
    let t10 = first_crossing(pts, y0 + 0.1 * (target - y0), rising);
    let t90 = first_crossing(pts, y0 + 0.9 * (target - y0), rising);
    t90 - t10
}

/// Overshoot in percent of the step from the window's start value to `target`.
fn overshoot(pts: &[(f64, f64)], target: f64) -> f64 {
    let y0 = pts[0].1;
    let step = target - y0;
    if step == 0.0 {
        return 0.0;
    }
    let beyond = if step > 0.0 {
        pts.iter().map(|p| p.1 - target).fold(0.0, f64::max)
    } else {
        pts.iter().map(|p| target - p.1).fold(0.0, f64::max)
    };
    100.0 * beyond / step.abs()
}

#[cfg(test)]
mod tests;
