//! Motion planning for machining paths (the mirror-milling paper, §2.1):
//! the jerk-limited S-shaped feed profile and the feed limits a path's
//! curvature imposes.

use crate::param;
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, SampleTime, Width};

pub const TYPES: &[BlockType] = &[BlockType {
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
        param("length", None, "path length L, > 0"),
        param("feed", None, "maximum feed F, > 0"),
        param("accel", None, "maximum tangential acceleration A, > 0"),
        param("jerk", None, "maximum tangential jerk J, > 0"),
        param("start", Some("0"), "start time [s]"),
        param("radius", None, "path radius of curvature ρ, for the curvature limits below"),
        param("tc", None, "interpolation period Tc [s] (with chord_error)"),
        param("chord_error", None, "chord (sagitta) error limit δ (with radius, tc)"),
        param("accel_normal", None, "normal acceleration limit An (with radius)"),
        param("jerk_normal", None, "normal jerk limit Jn (with radius)"),
        param("omega", None, "tool-axis angular speed limit ω [rad/s] (with radius)"),
    ],
    build: build_s_curve,
}];

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
struct SCurveBlock {
    profile: SCurve,
    start: f64,
    /// Absolute event times.
    events: Vec<f64>,
}

impl Block for SCurveBlock {
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
}

fn build_s_curve(p: &mut Params) -> Result<Built, Diagnostic> {
    let length = p.positive("length")?;
    let mut feed = p.positive("feed")?;
    let (accel, jerk) = (p.positive("accel")?, p.positive("jerk")?);
    let start = p.number_where("start", Some(0.0), f64::is_finite, "a finite time [s]")?;
    let optional = |p: &mut Params, key: &str| if p.has(key) { p.positive(key).map(Some) } else { Ok(None) };
    let radius = optional(p, "radius")?;
    let (tc, chord_error) = (optional(p, "tc")?, optional(p, "chord_error")?);
    let (accel_normal, jerk_normal, omega) =
        (optional(p, "accel_normal")?, optional(p, "jerk_normal")?, optional(p, "omega")?);
    let needs_radius = [("tc", tc), ("chord_error", chord_error), ("accel_normal", accel_normal)]
        .into_iter()
        .chain([("jerk_normal", jerk_normal), ("omega", omega)])
        .find(|(_, v)| v.is_some());
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
    Ok(Built::new(SCurveBlock { profile, start, events }, iface))
}

#[cfg(test)]
mod tests;
