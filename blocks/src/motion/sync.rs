//! Synchronous feed planning for two robots on mirrored paths (the
//! mirror-milling paper's §2.2, eq. 9), done once when the block is built,
//! as the paper generates its NC programs offline.

use super::bspline::{BSpline, chord_parameters};
use super::interpolator::taylor_step;
use super::{SCurve, read_points, shown};
use crate::table::*;
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};

pub const MIRROR_FEED_PLAN: BlockType = BlockType {
    name: "mirror_feed_plan",
    category: "motion",
    summary: "Both robots' feeds on mirrored paths, planned offline: S-curve, Taylor interpolation, chord ratio (eq. 9).",
    doc: "The machining side's tool-tip path P and the support side's path S (as `bspline_path` takes \
          them: `points` or `curve`, and `support_points` or `support_curve`, one point of S per point \
          of P) are fitted as cubic B-splines with P's chord-length parameters, so a parameter u names a \
          pair of mirrored points. When the block is built: the machining feed f1(t) is the S-curve over \
          P's length under `feed`, `accel`, `jerk`; u_j follows every Tc by the Taylor step of eq. 8; \
          the feed ratio of eq. 9, λ_j = |S(u_{j+1}) − S(u_j)| / |P(u_{j+1}) − P(u_j)| (|S′|/|P′| where \
          P stands still), gives the support feed f2 = λ·f1, so both sides cover their paths in the \
          same periods and finish together. If f2 exceeds `support_feed` (or its rate of change \
          `support_accel`), the machining side's maximum feed is lowered and the plan made again — the \
          paper's loop — by the fraction `reduce`, or at once by the worst excess ratio when that asks \
          for more (the support feed scales with the machining feed). Outputs, every Tc: u, \
          f1, f2, λ, the points p = P(u) and q = S(u), and for the servos' feed-forward each side's \
          commanded velocity f·T and acceleration ḟ·T + f²·κN (T the unit tangent, κN = (P″ − (P″·T)·T) \
          / |P′|² the curvature vector; ḟ2 = λ·ḟ1 + f1·λ̇, λ̇ by central differences), held after the end. With `start`, \
          both sides hold their first points (at rest) until then — time for a real-time compensation \
          to settle before the motion.",
    inputs: &[],
    outputs: &[
        PortDoc { name: "u", doc: "path parameter" },
        PortDoc { name: "f1", doc: "machining feed" },
        PortDoc { name: "f2", doc: "support feed" },
        PortDoc { name: "lambda", doc: "feed ratio f2/f1" },
        PortDoc { name: "p", doc: "machining tool-tip point P(u)" },
        PortDoc { name: "q", doc: "support point S(u)" },
        PortDoc { name: "pv", doc: "machining velocity command f1·T (for feed-forward)" },
        PortDoc { name: "pa", doc: "machining acceleration command a1·T + f1²·κN" },
        PortDoc { name: "qv", doc: "support velocity command f2·T_S" },
        PortDoc { name: "qa", doc: "support acceleration command ḟ2·T_S + f2²·κN_S" },
    ],
    params: &[
        param("points", Required, "machining path points (or curve, range, samples as bspline_path)")
            .kind(ParamKind::Matrix),
        param("curve", Required, "expressions of v for the machining path").kind(ParamKind::Words),
        param("range", Numbers(&[0.0, 1.0]), "[v_start, v_end] for the curves"),
        param("samples", Number(50.0), "points sampled from the curves"),
        param("support_points", Required, "support path points, one per machining point (or support_curve)")
            .kind(ParamKind::Matrix),
        param("support_curve", Required, "expressions of v for the support path").kind(ParamKind::Words),
        param("csv", Required, "a CSV file with the machining points (columns as bspline_path)"),
        param("support_csv", Required, "a CSV file with the support points"),
        param("columns", Described("[x, y, z]"), "the CSVs' coordinate columns, 2 or 3").kind(ParamKind::Words),
        param("max_file_mib", Number(256.0), "largest CSV file read, in MiB"),
        param("control_points", Described("min(points, 20)"), "control points of both fits").kind(ParamKind::Number),
        param("feed", Required, "machining side's maximum feed, > 0").kind(ParamKind::Number),
        param("accel", Required, "machining side's maximum tangential acceleration, > 0").kind(ParamKind::Number),
        param("jerk", Required, "machining side's maximum tangential jerk, > 0").kind(ParamKind::Number),
        param("support_feed", Number(f64::INFINITY), "support side's maximum feed"),
        param("support_accel", Number(f64::INFINITY), "support side's maximum |df2/dt|"),
        param("reduce", Number(0.01), "fraction the machining feed limit is lowered by per re-plan, 1e-4 … 0.5"),
        param("sample_time", Required, "interpolation period Tc (required)").kind(ParamKind::SampleTime).unit("s"),
        param("start", Number(0.0), "time the motion begins, a whole number of periods Tc").unit("s"),
    ],
    build: build_mirror_feed_plan,
};

/// A finished plan: per period j, u, f1, f2, λ and the two points.
#[derive(Clone, Debug)]
pub struct SyncPlan {
    pub u: Vec<f64>,
    pub f1: Vec<f64>,
    pub f2: Vec<f64>,
    pub lambda: Vec<f64>,
    pub p: Vec<f64>,
    pub q: Vec<f64>,
    /// The commanded velocity and acceleration vectors of both sides, for
    /// the servos' feed-forward.
    pub pv: Vec<f64>,
    pub pa: Vec<f64>,
    pub qv: Vec<f64>,
    pub qa: Vec<f64>,
    /// The machining side's tangential acceleration.
    pub a1: Vec<f64>,
    pub dim: usize,
    /// The machining side's maximum feed the plan ended with, and the
    /// number of re-plans it took.
    pub feed: f64,
    pub replans: usize,
}

/// The most periods a plan may take (some 5½ hours at Tc = 2 ms).
const MAX_PERIODS: f64 = 1e7;

/// P's length, by Simpson's rule on |P′| over 2 000 intervals.
fn length(path: &BSpline) -> f64 {
    let (n, dim) = (2000, path.dim);
    let mut out = vec![0.0; 3 * dim];
    let mut speed = |u: f64| {
        path.eval(u, &mut out);
        norm(&out[dim..2 * dim])
    };
    let h = 1.0 / n as f64;
    let mut sum = speed(0.0) + speed(1.0);
    for k in 1..n {
        sum += speed(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    sum * h / 3.0
}

/// Limits of the plan: machining (feed, accel, jerk), support (feed,
/// accel), the re-plan fraction and Tc.
#[derive(Clone, Copy, Debug)]
pub struct SyncLimits {
    pub feed: f64,
    pub accel: f64,
    pub jerk: f64,
    pub support_feed: f64,
    pub support_accel: f64,
    pub reduce: f64,
    pub tc: f64,
}

/// Plans both sides (see the block's doc); an error when no machining feed
/// down to 1e-6 of the given one satisfies the support side.
pub fn plan(path: &BSpline, support: &BSpline, limits: SyncLimits) -> Result<SyncPlan, String> {
    let dim = path.dim;
    let total = length(path);
    let (mut a, mut b) = (vec![0.0; 3 * dim], vec![0.0; 3 * dim]);
    let (mut feed, mut replans) = (limits.feed, 0);
    loop {
        if feed < 1e-6 * limits.feed {
            return Err(format!("no machining feed down to {feed:e} keeps the support side within its limits"));
        }
        let profile = SCurve::plan(total, feed, limits.accel, limits.jerk);
        let periods = (profile.duration / limits.tc).ceil() + 1.0;
        if periods > MAX_PERIODS {
            return Err(format!(
                "at a machining feed of {feed:e} the plan would take {periods:e} periods of {} s (limit {MAX_PERIODS:e})",
                limits.tc
            ));
        }
        let periods = periods as usize;
        let mut plan = SyncPlan {
            u: Vec::with_capacity(periods + 1),
            f1: Vec::with_capacity(periods + 1),
            f2: Vec::new(),
            lambda: Vec::new(),
            p: Vec::new(),
            q: Vec::new(),
            pv: Vec::new(),
            pa: Vec::new(),
            qv: Vec::new(),
            qa: Vec::new(),
            a1: Vec::new(),
            dim,
            feed,
            replans,
        };
        let mut u = 0.0;
        for j in 0..=periods {
            let [_, f1, a1] = profile.at(j as f64 * limits.tc);
            plan.u.push(u);
            plan.f1.push(f1);
            plan.a1.push(a1);
            path.eval(u, &mut a);
            plan.p.extend_from_slice(&a[..dim]);
            support.eval(u, &mut b);
            plan.q.extend_from_slice(&b[..dim]);
            u = taylor_step(u, f1, a1, &a[dim..2 * dim], &a[2 * dim..], limits.tc);
        }
        let n = plan.u.len();
        for j in 0..n {
            let (dp, dq) = if j + 1 < n && plan.u[j + 1] > plan.u[j] {
                (distance(&plan.p, j, dim), distance(&plan.q, j, dim))
            } else {
                // Standing still: the ratio of the derivatives.
                path.eval(plan.u[j], &mut a);
                support.eval(plan.u[j], &mut b);
                (norm(&a[dim..2 * dim]), norm(&b[dim..2 * dim]))
            };
            let lambda = dq / dp;
            plan.lambda.push(lambda);
            plan.f2.push(lambda * plan.f1[j]);
        }
        // The support side's worst excess over its limits (1: none).
        let f2_peak = plan.f2.iter().copied().fold(0.0, f64::max);
        let rate_peak = plan.f2.windows(2).map(|w| (w[1] - w[0]).abs() / limits.tc).fold(0.0, f64::max);
        let excess = (f2_peak / limits.support_feed).max(rate_peak / limits.support_accel);
        if excess <= 1.0 + 1e-12 {
            feed_forward(&mut plan, path, support, limits.tc);
            return Ok(plan);
        }
        // Lower by `reduce`, or at once by the excess when that is more
        // (the feeds scale with the machining feed).
        feed *= (1.0 - limits.reduce).min(1.0 / excess);
        replans += 1;
    }
}

/// The commanded velocity f·T and acceleration ḟ·T + f²·κN of both sides
/// at every period: T = P′/|P′|, κN = (P″ − (P″·T)·T)/|P′|² (the
/// curvature vector); the support side's ḟ2 = λ·ḟ1 + f1·λ̇ with λ̇ by
/// central differences.
fn feed_forward(plan: &mut SyncPlan, path: &BSpline, support: &BSpline, tc: f64) {
    let (dim, n) = (plan.dim, plan.u.len());
    let mut d = vec![0.0; 3 * dim];
    for j in 0..n {
        let (before, after) = (j.saturating_sub(1), (j + 1).min(n - 1));
        // ḟ2 = λ·ḟ1 + f1·λ̇: exact where λ is constant, and zero at rest.
        let dlambda = (plan.lambda[after] - plan.lambda[before]) / ((after - before).max(1) as f64 * tc);
        let df2 = plan.lambda[j] * plan.a1[j] + plan.f1[j] * dlambda;
        for (curve, f, df, v, a) in [
            (path, plan.f1[j], plan.a1[j], &mut plan.pv, &mut plan.pa),
            (support, plan.f2[j], df2, &mut plan.qv, &mut plan.qa),
        ] {
            curve.eval(plan.u[j], &mut d);
            let (d1, d2) = (&d[dim..2 * dim], &d[2 * dim..]);
            let speed = norm(d1);
            let along: f64 = d1.iter().zip(d2).map(|(x, y)| x * y).sum::<f64>() / speed;
            for c in 0..dim {
                let t = d1[c] / speed;
                v.push(f * t);
                a.push(df * t + f * f * (d2[c] - along * t) / (speed * speed));
            }
        }
    }
}

fn distance(points: &[f64], j: usize, dim: usize) -> f64 {
    (0..dim).map(|c| (points[(j + 1) * dim + c] - points[j * dim + c]).powi(2)).sum::<f64>().sqrt()
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[derive(Clone)]
pub struct MirrorFeedPlan {
    plan: SyncPlan,
    tc: f64,
    /// The sample-time offset plus `start`: the time of the plan's period 0.
    begin: f64,
}

impl Block for MirrorFeedPlan {
    rust_type!(MirrorFeedPlan);
    fn updates(&self) -> bool {
        false
    }

    fn output(&mut self, io: &mut Io) {
        let plan = &self.plan;
        let j = (((io.t - self.begin) / self.tc).round().max(0.0) as usize).min(plan.u.len() - 1);
        let dim = plan.dim;
        io.set(0, plan.u[j]);
        io.set(1, plan.f1[j]);
        io.set(2, plan.f2[j]);
        io.set(3, plan.lambda[j]);
        io.output(4).copy_from_slice(&plan.p[j * dim..(j + 1) * dim]);
        io.output(5).copy_from_slice(&plan.q[j * dim..(j + 1) * dim]);
        for (k, v) in [&plan.pv, &plan.pa, &plan.qv, &plan.qa].into_iter().enumerate() {
            io.output(6 + k).copy_from_slice(&v[j * dim..(j + 1) * dim]);
        }
    }

    fn build_report(&self) -> Option<String> {
        let plan = &self.plan;
        let peak = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
        let replanned = match plan.replans {
            0 => "as given".to_string(),
            n => format!("lowered to {} in {n} re-plan(s) for the support side's limits", shown(plan.feed)),
        };
        Some(format!(
            "machining feed limit {replanned}; f1 peaks at {}, f2 at {}; {} periods of {} s",
            shown(peak(&plan.f1)),
            shown(peak(&plan.f2)),
            plan.u.len(),
            self.tc
        ))
    }
}

fn build_mirror_feed_plan(p: &mut Params) -> Result<Built, Diagnostic> {
    let Some((points, dim)) = read_points(p, "")? else {
        return Err(p.block_error("give the machining path as `points` or `curve`"));
    };
    let Some((support_points, support_dim)) = read_points(p, "support_")? else {
        return Err(p.block_error("give the support path as `support_points` or `support_curve`"));
    };
    if support_dim != dim || support_points.len() != points.len() {
        let n = points.len() / dim;
        return Err(p.error("support_points", format!("give {n} points of {dim} coordinates, one per machining point")));
    }
    let n_points = points.len() / dim;
    let n_control = p.count_or("control_points", n_points.min(20), n_points)?;
    let params = chord_parameters(&points, dim).map_err(|m| p.error("points", m))?;
    let fit = |pts: &[f64]| BSpline::fit(pts, dim, &params, n_control);
    let path = fit(&points).map_err(|m| p.error("control_points", m))?;
    let support = fit(&support_points).map_err(|m| p.error("support_points", m))?;
    let (st, tc, offset) = p.discrete_clock()?;
    let positive_or_inf = |v: f64| v > 0.0;
    let limits = SyncLimits {
        feed: p.positive("feed")?,
        accel: p.positive("accel")?,
        jerk: p.positive("jerk")?,
        support_feed: p.number_where("support_feed", None, positive_or_inf, "> 0")?,
        support_accel: p.number_where("support_accel", None, positive_or_inf, "> 0")?,
        reduce: p.number_where("reduce", None, |r| (1e-4..=0.5).contains(&r), "a fraction in [1e-4, 0.5]")?,
        tc,
    };
    let start = p.number_where("start", None, |s| (0.0..1e9).contains(&s), ">= 0 and < 1e9")?;
    let periods = start / tc;
    if (periods - periods.round()).abs() > 1e-9 * periods.max(1.0) {
        return Err(p.error("start", format!("{start} s is not a whole number of periods of {tc} s")));
    }
    let plan = plan(&path, &support, limits).map_err(|m| p.block_error(m))?;
    let mut iface = Interface::new(st);
    for name in ["u", "f1", "f2", "lambda"] {
        iface = iface.output(name, Width::Fixed(1));
    }
    for name in ["p", "q", "pv", "pa", "qv", "qa"] {
        iface = iface.output(name, Width::Fixed(dim));
    }
    Ok(Built::new(MirrorFeedPlan { plan, tc, begin: offset + periods.round() * tc }, iface))
}
