//! Motion planning for machining paths (the mirror-milling paper, §2.1):
//! the jerk-limited S-shaped feed profile and the feed limits a path's
//! curvature imposes.

pub mod bspline;
pub mod interpolator;
pub mod sync;

use crate::table::*;
use ctlgraph_core::expr::Expr;
use ctlgraph_core::params::VarScope;
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, SampleTime, Width};

pub const TYPES: &[BlockType] =
    &[S_CURVE, BSPLINE_PATH, interpolator::PATH_INTERPOLATOR, MIRROR_OFFSET, sync::MIRROR_FEED_PLAN];

const BSPLINE_PATH: BlockType = BlockType {
    name: "bspline_path",
    category: "motion",
    summary: "A cubic B-spline path fitted by least squares to points; P(u), P'(u), P''(u) at the input u.",
    doc: "Fits a cubic B-spline to the points Q_k (2-D or 3-D) by least squares with chord-length \
          parameters and knots by averaging (Piegl & Tiller, The NURBS Book, eq. 9.5, 9.68–9.69, \
          9.63–9.67; the mirror-milling paper's refs): the end points are met exactly, \
          `control_points` = the number of points interpolates. Points come inline (`points`, a list of \
          [x, y] or [x, y, z]) from expressions of `v` sampled evenly over `range` (`curve`, e.g. an \
          arc `[\"400*cos(v)\", \"400*sin(v)\", \"0\"]`), or from the `columns` of a CSV file (`csv`, \
          one point per row). Outputs at the input u in [0, 1] (clamped): \
          the point P(u) and its derivatives P'(u), P''(u) with respect to u.\n\
          With `axis_points` or `axis_curve` (as many points as the path), a second curve O(u) through a \
          second point on the tool axis is fitted with the same parameters and knots, so tip and axis \
          stay paired at every u (the paper's P_i and O_i); its outputs o, do, ddo are added.",
    inputs: &[PortDoc { name: "u", doc: "path parameter in [0, 1]" }],
    outputs: &[
        PortDoc { name: "p", doc: "P(u), width 2 or 3" },
        PortDoc { name: "dp", doc: "P'(u) = dP/du" },
        PortDoc { name: "ddp", doc: "P''(u)" },
        PortDoc { name: "o", doc: "O(u) (with axis_points or axis_curve)" },
        PortDoc { name: "do", doc: "O'(u)" },
        PortDoc { name: "ddo", doc: "O''(u)" },
    ],
    params: &[
        param("points", Required, "the points, a list of [x, y] or [x, y, z] (or give curve)").kind(ParamKind::Matrix),
        param("curve", Required, "expressions of v, one per coordinate (instead of points)").kind(ParamKind::Words),
        param("range", Numbers(&[0.0, 1.0]), "[v_start, v_end] for curve"),
        param("samples", Number(50.0), "points sampled from curve, 4 … 100000"),
        param("control_points", Described("min(points, 20)"), "control points, 4 … number of points")
            .kind(ParamKind::Number),
        param("csv", Required, "a CSV file with the points, one per row (instead of points or curve)"),
        param("columns", Described("[x, y, z]"), "the CSV's coordinate columns, 2 or 3").kind(ParamKind::Words),
        param("max_file_mib", Number(256.0), "largest CSV file read, in MiB"),
        param("axis_points", Required, "points on the tool axis, one per path point").kind(ParamKind::Matrix),
        param("axis_csv", Required, "a CSV file with the axis points (same columns)"),
        param("axis_curve", Required, "expressions of v for the axis points (same range and samples)")
            .kind(ParamKind::Words),
    ],
    build: build_bspline_path,
};

#[derive(Clone)]
pub struct BSplinePath {
    path: bspline::BSpline,
    axis: Option<bspline::BSpline>,
    out: Vec<f64>,
}

impl Block for BSplinePath {
    rust_type!(BSplinePath);
    fn updates(&self) -> bool {
        false
    }

    fn output(&mut self, io: &mut Io) {
        let u = io.input(0)[0];
        let dim = self.path.dim;
        for (k, curve) in [Some(&self.path), self.axis.as_ref()].into_iter().flatten().enumerate() {
            curve.eval(u, &mut self.out);
            for d in 0..3 {
                io.output(3 * k + d).copy_from_slice(&self.out[d * dim..(d + 1) * dim]);
            }
        }
    }
}

/// Points (`dim` numbers each, flattened) from `{prefix}points` inline,
/// `{prefix}curve` expressions of `v`, or the `columns` of the CSV file
/// `{prefix}csv`; `None` when none is given.
fn read_points(p: &mut Params, prefix: &str) -> Result<Option<(Vec<f64>, usize)>, Diagnostic> {
    let (points_key, curve_key, csv_key) =
        (format!("{prefix}points"), format!("{prefix}curve"), format!("{prefix}csv"));
    let (points_key, curve_key, csv_key) = (points_key.as_str(), curve_key.as_str(), csv_key.as_str());
    let given: Vec<&str> = [points_key, curve_key, csv_key].into_iter().filter(|k| p.has(k)).collect();
    if given.len() > 1 {
        return Err(p.error(given[1], format!("give one of `{points_key}`, `{curve_key}`, `{csv_key}`")));
    }
    if p.has(csv_key) {
        let path = p.path(csv_key)?;
        let columns: Vec<String> = match p.has("columns") {
            true => p.strings("columns")?.iter().map(|s| s.to_string()).collect(),
            false => vec!["x".into(), "y".into(), "z".into()],
        };
        if !(2..=3).contains(&columns.len()) {
            return Err(p.error("columns", "name 2 or 3 columns, one per coordinate"));
        }
        let limit = crate::tables::data_file_limit(p)?;
        let mut coords = Vec::new();
        for name in &columns[1..] {
            let (first, other) =
                crate::tables::read_columns(&path, &columns[0], name, limit).map_err(|m| p.error(csv_key, m))?;
            if coords.is_empty() {
                coords.push(first);
            }
            coords.push(other);
        }
        let n = coords[0].len();
        let points = (0..n).flat_map(|k| coords.iter().map(move |c| c[k])).collect();
        return Ok(Some((points, columns.len())));
    }
    match (p.has(points_key), p.has(curve_key)) {
        (true, _) => {
            let rows = p.matrix(points_key)?;
            let dim = rows.first().map_or(0, Vec::len);
            if !(2..=3).contains(&dim) || rows.iter().any(|r| r.len() != dim) {
                return Err(p.error(points_key, "every point needs 2 or 3 coordinates, all alike"));
            }
            Ok(Some((rows.concat(), dim)))
        }
        (false, true) => {
            let exprs: Vec<String> = p.strings(curve_key)?.iter().map(|s| s.to_string()).collect();
            if !(2..=3).contains(&exprs.len()) {
                return Err(p.error(curve_key, "give 2 or 3 expressions of v, one per coordinate"));
            }
            let range = p.vector("range")?;
            if range.len() != 2 || range[0] >= range[1] || range.iter().any(|v| !v.is_finite()) {
                return Err(p.error("range", "expected [v_start, v_end] with v_start < v_end"));
            }
            let samples = p.count("samples", 100_000)?;
            if samples < 4 {
                return Err(p.error("samples", "a cubic needs at least 4 points"));
            }
            let scope = VarScope { vars: &["v"], params: p.scope() };
            let mut compiled = Vec::new();
            for text in &exprs {
                let e = Expr::parse(text, &scope).map_err(|e| {
                    let d = p.error(curve_key, format!("`{text}`: {e}"));
                    Diagnostic { hint: e.hint.clone(), ..d }
                })?;
                compiled.push(e);
            }
            let mut points = Vec::with_capacity(samples * exprs.len());
            for k in 0..samples {
                let v = range[0] + (range[1] - range[0]) * k as f64 / (samples - 1) as f64;
                points.extend(compiled.iter().map(|e| e.eval(&[v])));
            }
            Ok(Some((points, exprs.len())))
        }
        (false, false) => Ok(None),
    }
}

fn build_bspline_path(p: &mut Params) -> Result<Built, Diagnostic> {
    let Some((points, dim)) = read_points(p, "")? else {
        return Err(p.block_error("give the path as `points` or `curve`"));
    };
    let n_points = points.len() / dim;
    let n_control = p.count_or("control_points", n_points.min(20), n_points)?;
    if n_control < 4 {
        return Err(p.error("control_points", "a cubic needs at least 4"));
    }
    let params = bspline::chord_parameters(&points, dim).map_err(|m| p.error("points", m))?;
    let path = bspline::BSpline::fit(&points, dim, &params, n_control).map_err(|m| p.error("control_points", m))?;
    let axis = match read_points(p, "axis_")? {
        None => None,
        Some((axis, axis_dim)) => {
            if axis_dim != dim || axis.len() != points.len() {
                return Err(p.error("axis_points", format!("give {n_points} points of {dim} coordinates, as the path")));
            }
            Some(bspline::BSpline::fit(&axis, dim, &params, n_control).map_err(|m| p.error("axis_points", m))?)
        }
    };
    let mut iface = Interface::new(SampleTime::Inherited).input("u", Width::Fixed(1), true).piecewise_constant();
    let names: &[&str] = if axis.is_some() { &["p", "dp", "ddp", "o", "do", "ddo"] } else { &["p", "dp", "ddp"] };
    for name in names {
        iface = iface.output(name, Width::Fixed(dim));
    }
    Ok(Built::new(BSplinePath { path, axis, out: vec![0.0; 3 * dim] }, iface))
}

const MIRROR_OFFSET: BlockType = BlockType {
    name: "mirror_offset",
    category: "motion",
    summary: "The support head's point across a wall from the tool tip (mirror milling, eq. 3).",
    doc: "q = p + (H − d)·n/|n|: the point on the far side of a wall of thickness H, along the tool axis \
          n through the tool tip p, when the cut is d deep (the mirror-milling paper's eq. 3: the support \
          head stays opposite the cutter on the remaining thickness). p, n and q are 3-vectors in one \
          frame; n need not be a unit vector (a zero n gives NaN, and the run stops naming the block).",
    inputs: &[
        PortDoc { name: "p", doc: "tool-tip point, width 3" },
        PortDoc { name: "n", doc: "tool-axis direction, width 3, pointing through the wall" },
    ],
    outputs: &[PortDoc { name: "q", doc: "support-head point, width 3" }],
    params: &[
        param("thickness", Required, "wall thickness H, > 0").kind(ParamKind::Number),
        param("depth", Number(0.0), "depth of cut d, 0 <= d < H"),
    ],
    build: build_mirror_offset,
};

#[derive(Clone)]
pub struct MirrorOffset {
    offset: f64,
}

impl Block for MirrorOffset {
    rust_type!(MirrorOffset);
    fn updates(&self) -> bool {
        false
    }

    fn output(&mut self, io: &mut Io) {
        let (p, n) = (io.input(0), io.input(1));
        let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let k = if norm > 0.0 { self.offset / norm } else { f64::NAN };
        let q = [p[0] + k * n[0], p[1] + k * n[1], p[2] + k * n[2]];
        io.output(0).copy_from_slice(&q);
    }

    fn diagnose(&self) -> Option<String> {
        Some("the tool axis n has zero length".into())
    }
}

fn build_mirror_offset(p: &mut Params) -> Result<Built, Diagnostic> {
    let thickness = p.positive("thickness")?;
    let depth = p.number_where("depth", None, |d| (0.0..thickness).contains(&d), "in [0, thickness)")?;
    let iface = Interface::new(SampleTime::Inherited)
        .input("p", Width::Fixed(3), true)
        .input("n", Width::Fixed(3), true)
        .output("q", Width::Fixed(3))
        .piecewise_constant();
    Ok(Built::new(MirrorOffset { offset: thickness - depth }, iface))
}

const S_CURVE: BlockType = BlockType {
    name: "s_curve",
    category: "motion",
    summary: "Jerk-limited (seven-segment, S-shaped) feed profile over a path of given length.",
    doc: "Moves a path length L from rest to rest in the least time with |f| <= F, |a| <= A, |j| <= J \
          (feed, tangential acceleration and jerk): jerk +J, 0, −J while accelerating, a cruise at the \
          peak feed, then −J, 0, +J (the double-S profile; Biagiotti & Melchiorri, Trajectory Planning \
          for Automatic Machines and Robots, §3.4). With the time to accelerate from rest to feed v, \
          T(v) = 2·sqrt(v/J) for v <= A²/J (A not reached) and v/A + A/J above, the peak feed is F when \
          the path is long enough (L >= F·T(F)), else the v with v·T(v) = L.\n\
          With `radius` ρ (a path of constant curvature, as the paper's arcs), F is first lowered to the \
          curvature limits the paper's §2.1 names (its eq. 6 is an image lost from the text; these are \
          the standard forms): the chord of one interpolation period Tc may leave the arc by at most \
          δ, f <= (2/Tc)·sqrt(ρ² − (ρ − δ)²); normal acceleration f²/ρ <= An; normal jerk f³/ρ² <= Jn; \
          the tool axis, turning with the path's normal, at angular speed f/ρ <= ω. Each is skipped \
          when its parameter is not given.\n\
          Outputs: feed f(t), tangential acceleration a(t), travelled length s(t) (0 before `start`, \
          L after the end). The segment boundaries are time events.",
    inputs: &[],
    outputs: &[
        PortDoc { name: "f", doc: "feed (path speed) [length/s]" },
        PortDoc { name: "a", doc: "tangential acceleration [length/s²]" },
        PortDoc { name: "s", doc: "path length travelled [length]" },
    ],
    params: &[
        param("length", Required, "path length L, > 0").kind(ParamKind::Number),
        param("feed", Required, "maximum feed F, > 0").kind(ParamKind::Number),
        param("accel", Required, "maximum tangential acceleration A, > 0").kind(ParamKind::Number),
        param("jerk", Required, "maximum tangential jerk J, > 0").kind(ParamKind::Number),
        param("start", Number(0.0), "start time").unit("s"),
        param("radius", Required, "path radius of curvature ρ, for the curvature limits below").kind(ParamKind::Number),
        param("tc", Required, "interpolation period Tc (with chord_error)").kind(ParamKind::Number).unit("s"),
        param("chord_error", Required, "chord (sagitta) error limit δ (with radius, tc)").kind(ParamKind::Number),
        param("accel_normal", Required, "normal acceleration limit An (with radius)").kind(ParamKind::Number),
        param("jerk_normal", Required, "normal jerk limit Jn (with radius)").kind(ParamKind::Number),
        param("omega", Required, "tool-axis angular speed limit ω (with radius)").kind(ParamKind::Number).unit("rad/s"),
    ],
    build: build_s_curve,
};

/// A number for a report: six decimals at most.
pub(crate) fn shown(v: f64) -> f64 {
    (v * 1e6).round() / 1e6
}

/// The curvature limits on the feed for a path of radius `radius`; each
/// `None` limit is skipped. See the block's doc.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CurvatureLimits {
    pub radius: f64,
    /// (Tc, δ).
    pub chord: Option<(f64, f64)>,
    pub accel_normal: Option<f64>,
    pub jerk_normal: Option<f64>,
    pub omega: Option<f64>,
}

impl CurvatureLimits {
    /// The largest feed all limits allow (infinite when none is given).
    pub fn feed_limit(&self) -> f64 {
        let r = self.radius;
        let chord = self.chord.map(|(tc, d)| 2.0 / tc * (r * r - (r - d) * (r - d)).sqrt());
        let normal = self.accel_normal.map(|an| (an * r).sqrt());
        let jerk = self.jerk_normal.map(|jn| (jn * r * r).cbrt());
        let omega = self.omega.map(|w| w * r);
        [chord, normal, jerk, omega].into_iter().flatten().fold(f64::INFINITY, f64::min)
    }
}

/// A rest-to-rest double-S profile: seven segments of constant jerk.
#[derive(Clone, Debug, PartialEq)]
pub struct SCurve {
    /// Per segment: start time (from the profile's start), jerk, and the
    /// length, feed and acceleration at its start.
    segments: [(f64, f64, [f64; 3]); 7],
    pub duration: f64,
    pub length: f64,
    pub peak_feed: f64,
    pub peak_accel: f64,
}

impl SCurve {
    /// The time-optimal profile over `length` with feed, acceleration and
    /// jerk at most `feed`, `accel`, `jerk` (all positive).
    pub fn plan(length: f64, feed: f64, accel: f64, jerk: f64) -> SCurve {
        // The acceleration time to reach feed v from rest.
        let ramp = |v: f64| if v <= accel * accel / jerk { 2.0 * (v / jerk).sqrt() } else { v / accel + accel / jerk };
        let v = if feed * ramp(feed) <= length {
            feed
        } else if 2.0 * accel.powi(3) / (jerk * jerk) >= length {
            // L = 2·v^{3/2}/sqrt(J) with A not reached.
            (length * jerk.sqrt() / 2.0).powf(2.0 / 3.0)
        } else {
            // L = v²/A + v·A/J.
            accel / 2.0 * (-accel / jerk + (accel * accel / (jerk * jerk) + 4.0 * length / accel).sqrt())
        };
        let a = accel.min((v * jerk).sqrt());
        let (t_jerk, t_accel) = (a / jerk, v / a - a / jerk);
        let t_cruise = ((length - v * ramp(v)) / v).max(0.0);
        // Rounding leaves phases that should vanish a few ulps long (a
        // constant-acceleration phase exactly at v = A²/J): drop them, or
        // they would be events too close to step between.
        let snap = |d: f64| if d > 1e-9 * (t_jerk + t_accel.abs() + t_cruise) { d } else { 0.0 };
        let (t_accel, t_cruise) = (snap(t_accel), snap(t_cruise));
        let durations = [t_jerk, t_accel, t_jerk, t_cruise, t_jerk, t_accel, t_jerk];
        let jerks = [jerk, 0.0, -jerk, 0.0, -jerk, 0.0, jerk];
        let mut segments = [(0.0, 0.0, [0.0; 3]); 7];
        let (mut t, mut state) = (0.0, [0.0; 3]);
        for k in 0..7 {
            segments[k] = (t, jerks[k], state);
            state = advance(state, jerks[k], durations[k]);
            t += durations[k];
        }
        SCurve { segments, duration: t, length, peak_feed: v, peak_accel: a }
    }

    /// (s, f, a) at time `t` after the start: rest at 0 before, rest at the
    /// full length after the end (exactly `length`, not the rounded sum).
    pub fn at(&self, t: f64) -> [f64; 3] {
        if t <= 0.0 {
            return [0.0; 3];
        }
        if t >= self.duration {
            return [self.length, 0.0, 0.0];
        }
        let k = self.segments.iter().rposition(|seg| seg.0 <= t).unwrap_or(0);
        let (t0, jerk, state) = self.segments[k];
        advance(state, jerk, t - t0)
    }

    /// The segment boundaries (from the start), the profile's events.
    pub fn boundaries(&self) -> impl Iterator<Item = f64> + '_ {
        self.segments.iter().map(|s| s.0).skip(1).chain([self.duration])
    }
}

/// (s, f, a) after `dt` at constant `jerk`.
fn advance([s, f, a]: [f64; 3], jerk: f64, dt: f64) -> [f64; 3] {
    [s + f * dt + a * dt * dt / 2.0 + jerk * dt.powi(3) / 6.0, f + a * dt + jerk * dt * dt / 2.0, a + jerk * dt]
}

#[derive(Clone)]
pub struct SCurveBlock {
    profile: SCurve,
    start: f64,
    /// Absolute event times.
    events: Vec<f64>,
    /// The feed limit given, and the curvature limit when it was lower.
    feed: f64,
    curvature_limit: Option<f64>,
}

impl Block for SCurveBlock {
    rust_type!(SCurveBlock);
    fn updates(&self) -> bool {
        false
    }

    fn output(&mut self, io: &mut Io) {
        let [s, f, a] = self.profile.at(io.t - self.start);
        io.set(0, f);
        io.set(1, a);
        io.set(2, s);
    }

    fn next_event(&self, t: f64) -> f64 {
        self.events.iter().copied().find(|&e| e > t).unwrap_or(f64::INFINITY)
    }

    fn min_event_spacing(&self) -> f64 {
        self.events.windows(2).map(|w| w[1] - w[0]).filter(|d| *d > 0.0).fold(f64::INFINITY, f64::min)
    }

    fn build_report(&self) -> Option<String> {
        let p = &self.profile;
        let limited = match self.curvature_limit {
            Some(c) if c < self.feed => format!(" (the curvature limits lower `feed` {} to {})", self.feed, shown(c)),
            _ => String::new(),
        };
        Some(format!(
            "peak feed {}{limited}, peak acceleration {}, {} s from t = {}",
            shown(p.peak_feed),
            shown(p.peak_accel),
            shown(p.duration),
            self.start
        ))
    }
}

fn build_s_curve(p: &mut Params) -> Result<Built, Diagnostic> {
    let length = p.positive("length")?;
    let mut feed = p.positive("feed")?;
    let (accel, jerk) = (p.positive("accel")?, p.positive("jerk")?);
    let start = p.number_where("start", None, f64::is_finite, "a finite time [s]")?;
    let optional = |p: &mut Params, key: &str| if p.has(key) { p.positive(key).map(Some) } else { Ok(None) };
    let radius = optional(p, "radius")?;
    let (tc, chord_error) = (optional(p, "tc")?, optional(p, "chord_error")?);
    let (accel_normal, jerk_normal, omega) =
        (optional(p, "accel_normal")?, optional(p, "jerk_normal")?, optional(p, "omega")?);
    let needs_radius = [("tc", tc), ("chord_error", chord_error), ("accel_normal", accel_normal)]
        .into_iter()
        .chain([("jerk_normal", jerk_normal), ("omega", omega)])
        .find(|(_, v)| v.is_some());
    let given = feed;
    let mut curvature_limit = None;
    match (radius, needs_radius) {
        (None, Some((key, _))) => return Err(p.error(key, "a curvature limit needs the path's `radius`")),
        (Some(r), _) => {
            if tc.is_some() != chord_error.is_some() {
                let key = if tc.is_some() { "tc" } else { "chord_error" };
                return Err(p.error(key, "the chord-error limit needs both `tc` and `chord_error`"));
            }
            if let Some(d) = chord_error.filter(|&d| d >= r) {
                return Err(p.error("chord_error", format!("must be less than the radius {r}, got {d}")));
            }
            let limits = CurvatureLimits { radius: r, chord: tc.zip(chord_error), accel_normal, jerk_normal, omega };
            curvature_limit = Some(limits.feed_limit());
            feed = feed.min(limits.feed_limit());
        }
        (None, None) => {}
    }
    let profile = SCurve::plan(length, feed, accel, jerk);
    let mut events: Vec<f64> = profile.boundaries().map(|b| start + b).collect();
    events.insert(0, start);
    events.dedup();
    let iface = Interface::new(SampleTime::Continuous)
        .output("f", Width::Fixed(1))
        .output("a", Width::Fixed(1))
        .output("s", Width::Fixed(1));
    Ok(Built::new(SCurveBlock { profile, start, events, feed: given, curvature_limit }, iface))
}

#[cfg(test)]
mod tests;
