//! Milling: the regenerative cutting force of an end mill (the milling
//! paper's eq. 1–7, in Altintas' conventions).
//!
//! The regenerative delay is not inside the block: the vibration one tooth
//! period earlier comes in on its own ports, from `transport_delay` blocks
//! of delay 60/(N·rpm), so the delay is visible in the diagram (as in the
//! paper's Fig. 2).

pub mod lobes;

use crate::table::*;
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Crossing, Diagnostic, Interface, Io, Params, SampleTime, Width};
use std::f64::consts::{PI, TAU};

pub const TYPES: &[BlockType] = &[BlockType {
    name: "milling_force",
    category: "machining",
    summary: "Regenerative cutting force of an N-tooth end mill on X and Y (Altintas' model).",
    doc: "Angles in Altintas' convention: the immersion angle φ is measured clockwise from +Y, the feed is \
          along +X, tooth j (j = 0 … N−1) is at φj(t) = Ω·t + φ0 + 2πj/N, Ω = 2π·rpm/60. Tooth j cuts \
          while φst <= φj mod 2π < φex (δ(φj) = 1). Chip thickness (paper eq. 1–4):\n\
          \x20 h_j = max(0, ft·sin φj + (x − x_τ)·sin φj + (y − y_τ)·cos φj)·δ(φj),\n\
          x_τ, y_τ the tool's displacement one tooth period τ = 60/(N·rpm) earlier (wire them from \
          `transport_delay` blocks with that delay); the clip at 0 is the tooth leaving the material. \
          As in the paper the surface is the one the previous tooth left (single regeneration). A \
          moderately unstable cut settles on a chatter limit cycle, the teeth leaving the cut for \
          part of each pass; far beyond the stability limit the vibration keeps growing, since a \
          tooth that jumped out does not meet the older surface it would meet in a real cut. \
          Forces (eq. 5–6): Ft,j = Kt·ap·h_j, Fr,j = Kr·Ft,j,\n\
          \x20 Fx = Σ_j (−Ft,j·cos φj − Fr,j·sin φj),   Fy = Σ_j (Ft,j·sin φj − Fr,j·cos φj),\n\
          the force on the tool. Units: Kt [N/mm²], ap, ft, x, y [mm] give N. Immersion: `milling: up` \
          (φst = 0, φex = arccos(1 − 2·ae/D)) or `down` (φst = arccos(2·ae/D − 1), φex = π) with \
          `immersion` = ae/D, or `entry`/`exit` in degrees. Over a tooth period with no vibration the \
          mean forces are Altintas' (N·ap·ft/8π)·[Kt·cos 2φ − Krc·(2φ − sin 2φ)] and \
          (N·ap·ft/8π)·[Kt·(2φ − sin 2φ) + Krc·cos 2φ] taken from φst to φex \
          (Krc = Kr·Kt; for cuts within 0°–180°, where the static chip ft·sin φ >= 0).\n\
          Events: the teeth's entry and exit instants are time events (the force jumps there: major \
          steps land on them); with `zero_crossing: true` (default) each cutting tooth's chip sign is a \
          mode chosen at major steps and frozen in minor steps, and h_j = 0 crossings end the step there.\n\
          Bounds: |Fx|, |Fy| <= N·Kt·ap·(1 + Kr)·max h_j, and h_j <= ft + |x − x_τ| + |y − y_τ|.",
    inputs: &[
        PortDoc { name: "x", doc: "tool displacement along X (feed) [mm]" },
        PortDoc { name: "y", doc: "tool displacement along Y [mm]" },
        PortDoc { name: "x_delayed", doc: "x one tooth period earlier, x(t − τ)" },
        PortDoc { name: "y_delayed", doc: "y one tooth period earlier, y(t − τ)" },
    ],
    outputs: &[
        PortDoc { name: "fx", doc: "cutting force on the tool along X [N]" },
        PortDoc { name: "fy", doc: "cutting force on the tool along Y [N]" },
        PortDoc { name: "h", doc: "chip thickness per tooth, width N (with tooth_outputs: true)" },
        PortDoc { name: "ft_tooth", doc: "tangential force per tooth, width N (with tooth_outputs: true)" },
        PortDoc { name: "fr_tooth", doc: "radial force per tooth, width N (with tooth_outputs: true)" },
    ],
    params: &[
        param("teeth", Required, "number of teeth N, 1 … 64").kind(ParamKind::Number),
        param("rpm", Required, "spindle speed, > 0").kind(ParamKind::Number).unit("rev/min"),
        param("kt", Required, "tangential cutting coefficient Kt, >= 0").kind(ParamKind::Number).unit("N/mm²"),
        param("kr", Required, "radial-to-tangential ratio Kr = Fr/Ft, >= 0 (or give krc)").kind(ParamKind::Number),
        param("krc", Required, "radial coefficient instead of kr: Kr = krc/kt").kind(ParamKind::Number).unit("N/mm²"),
        param("ap", Required, "axial depth of cut, >= 0").kind(ParamKind::Number).unit("mm"),
        param("ft", Required, "feed per tooth ft, >= 0").kind(ParamKind::Number).unit("mm"),
        param("milling", Word("up"), "up | down (with immersion)").options(&["up", "down"]),
        param("immersion", Number(1.0), "radial immersion ae/D in (0, 1]"),
        param("entry", Required, "entry angle φst, instead of milling/immersion").kind(ParamKind::Number).unit("deg"),
        param("exit", Required, "exit angle φex, entry < exit <= entry + 360").kind(ParamKind::Number).unit("deg"),
        param("phase", Number(0.0), "angle φ0 of tooth 0 at t = 0").unit("deg"),
        param("zero_crossing", Flag(true), "watch h_j = 0 (false: a plain max(0, ·))"),
        param("tooth_outputs", Flag(false), "add the outputs h, ft_tooth, fr_tooth per tooth"),
    ],
    build: build_milling_force,
}];

/// The cutter's geometry and coefficients; everything the force needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Cutter {
    pub teeth: usize,
    /// Spindle speed Ω [rad/s].
    pub omega: f64,
    pub kt: f64,
    pub kr: f64,
    pub ap: f64,
    pub feed: f64,
    /// Entry and exit angles [rad], 0 <= entry < exit <= entry + 2π.
    pub entry: f64,
    pub exit: f64,
    /// φ0 [rad].
    pub phase: f64,
}

impl Cutter {
    /// The tooth period τ = 2π/(N·Ω) [s], the regenerative delay.
    pub fn tooth_period(&self) -> f64 {
        TAU / (self.teeth as f64 * self.omega)
    }

    /// φj(t) [rad], not reduced modulo 2π.
    pub fn angle(&self, j: usize, t: f64) -> f64 {
        self.omega * t + self.phase + TAU * j as f64 / self.teeth as f64
    }

    /// The instant tooth `j` enters the cut in revolution `k`. Entry and
    /// exit instants are computed only here, so that the simulator's
    /// event times and the block's own test of which side of an event it
    /// is on use the same floating-point numbers.
    fn entry_time(&self, j: usize, k: f64) -> f64 {
        (self.entry - self.phase - TAU * j as f64 / self.teeth as f64 + TAU * k) / self.omega
    }

    fn exit_time(&self, j: usize, k: f64) -> f64 {
        self.entry_time(j, k) + (self.exit - self.entry) / self.omega
    }

    /// The revolution of tooth `j`'s latest entry at `t`. Within rounding
    /// of an entry instant it may be one off either way; away from them it
    /// is exact. A cut shorter than a turn then needs only this revolution
    /// and the next: one below, the tooth had long left the cut before the
    /// entry; one above, the entry is the next event.
    fn revolution(&self, j: usize, t: f64) -> f64 {
        ((self.angle(j, t) - self.entry) / TAU).floor()
    }

    /// A cut all the way round: every exit is the next entry, so there are
    /// no edges (and no instants an ulp apart to step between).
    fn full_turn(&self) -> bool {
        self.exit - self.entry >= TAU
    }

    /// Whether tooth `j` is in the cut at `io.t` (the side of an entry or
    /// exit instant as [`Io::reached`] says).
    fn cutting(&self, j: usize, io: &Io) -> bool {
        if self.full_turn() {
            return true;
        }
        let k = self.revolution(j, io.t);
        [k + 1.0, k]
            .into_iter()
            .find(|&c| io.reached(self.entry_time(j, c)))
            .is_some_and(|c| !io.reached(self.exit_time(j, c)))
    }

    /// A tooth's chip thickness before the clip, at the angle whose
    /// (sin, cos) is `sc`, for displacement changes over a tooth period
    /// `dx`, `dy`.
    pub fn chip(&self, (s, c): (f64, f64), dx: f64, dy: f64) -> f64 {
        (self.feed + dx) * s + dy * c
    }

    /// (Ft, Fr, Fx, Fy) of one tooth at the angle whose (sin, cos) is `sc`,
    /// cutting a chip `h`.
    pub fn tooth_force(&self, (s, c): (f64, f64), h: f64) -> [f64; 4] {
        let ft = self.kt * self.ap * h;
        let fr = self.kr * ft;
        [ft, fr, -ft * c - fr * s, ft * s - fr * c]
    }

    /// Altintas' mean forces (F̄x, F̄y) over a tooth period without vibration.
    pub fn mean_force(&self) -> (f64, f64) {
        let krc = self.kr * self.kt;
        let fx = |p: f64| self.kt * (2.0 * p).cos() - krc * (2.0 * p - (2.0 * p).sin());
        let fy = |p: f64| self.kt * (2.0 * p - (2.0 * p).sin()) + krc * (2.0 * p).cos();
        let scale = self.teeth as f64 * self.ap * self.feed / (8.0 * PI);
        (scale * (fx(self.exit) - fx(self.entry)), scale * (fy(self.exit) - fy(self.entry)))
    }
}

/// The block: the cutter and, per tooth, whether it is in the cut and
/// whether its chip is positive (the mode, frozen in minor steps).
#[derive(Clone)]
pub struct MillingForce {
    cutter: Cutter,
    zero_crossing: bool,
    tooth_outputs: bool,
    in_cut: Vec<bool>,
    chip_positive: Vec<bool>,
}

impl MillingForce {
    /// Tooth `j`'s chip before the clip at `io.t`, from the inputs, with
    /// the (sin, cos) of its angle.
    fn raw_chip(&self, j: usize, io: &Io) -> (f64, (f64, f64)) {
        let sc = self.cutter.angle(j, io.t).sin_cos();
        (self.cutter.chip(sc, io.u(0) - io.u(2), io.u(1) - io.u(3)), sc)
    }
}

impl Block for MillingForce {
    rust_type!(MillingForce);
    fn updates(&self) -> bool {
        false
    }

    fn output(&mut self, io: &mut Io) {
        let (mut fx, mut fy) = (0.0, 0.0);
        for j in 0..self.cutter.teeth {
            let cutting = self.cutter.cutting(j, io);
            let (raw, sc) = self.raw_chip(j, io);
            let raw = if cutting { raw } else { 0.0 };
            if io.may_switch() {
                self.in_cut[j] = cutting;
                self.chip_positive[j] = raw > 0.0;
            }
            // Frozen, a cutting tooth keeps its chip formula past h = 0
            // until the crossing ends the step.
            let h = if cutting && self.chip_positive[j] { raw } else { 0.0 };
            let [ft, fr, x, y] = self.cutter.tooth_force(sc, h);
            fx += x;
            fy += y;
            if self.tooth_outputs {
                io.set_at(2, j, h);
                io.set_at(3, j, ft);
                io.set_at(4, j, fr);
            }
        }
        io.set(0, fx);
        io.set(1, fy);
    }

    fn next_event(&self, t: f64) -> f64 {
        let mut next = f64::INFINITY;
        if self.cutter.full_turn() {
            return next;
        }
        for j in 0..self.cutter.teeth {
            let k = self.cutter.revolution(j, t);
            for c in [k, k + 1.0] {
                for e in [self.cutter.entry_time(j, c), self.cutter.exit_time(j, c)] {
                    if e > t {
                        next = next.min(e);
                    }
                }
            }
        }
        next
    }

    fn min_event_spacing(&self) -> f64 {
        // Entries are τ apart, exits too; an exit falls (φex − φst)/Ω
        // after an entry, modulo τ.
        if self.cutter.full_turn() {
            return f64::INFINITY;
        }
        let tau = self.cutter.tooth_period();
        let offset = ((self.cutter.exit - self.cutter.entry) / self.cutter.omega).rem_euclid(tau);
        if offset == 0.0 { tau } else { offset.min(tau - offset) }
    }

    fn num_zero_crossings(&self) -> usize {
        if self.zero_crossing { self.cutter.teeth } else { 0 }
    }

    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        for (j, g) in g.iter_mut().enumerate() {
            *g = if self.in_cut[j] { self.raw_chip(j, io).0 } else { 0.0 };
        }
    }

    fn crossing_direction(&self, k: usize) -> Crossing {
        if self.in_cut[k] { Crossing::Either } else { Crossing::Ignore }
    }

    fn not_linearizable(&self) -> Option<&'static str> {
        Some("the cutting force is periodic in time (time-varying), so it has no linear time-invariant model")
    }
}

/// The immersion angles [rad] from `milling`/`immersion` or `entry`/`exit`.
fn immersion_angles(p: &mut Params) -> Result<(f64, f64), Diagnostic> {
    if p.has("entry") || p.has("exit") {
        for (key, other) in [("milling", "entry"), ("immersion", "entry")] {
            if p.has(key) {
                return Err(p.error(key, format!("give either `{key}` or `{other}`/`exit`, not both")));
            }
        }
        let entry = p.number_where("entry", None, |v| (0.0..360.0).contains(&v), "an angle in [0, 360) degrees")?;
        let exit = p.number_where(
            "exit",
            None,
            |v| v > entry && v <= entry + 360.0,
            "an angle after `entry`, at most one turn later [deg]",
        )?;
        return Ok((entry.to_radians(), exit.to_radians()));
    }
    let mode = p.choice("milling", &["up", "down"])?;
    let a = p.number_where("immersion", None, |v| v > 0.0 && v <= 1.0, "ae/D in (0, 1]")?;
    Ok(engagement(mode == "up", a))
}

/// Entry and exit angles [rad] of up-milling (`up`) or down-milling at
/// radial immersion ae/D = `immersion`: a cut of arccos(1 − 2·ae/D)
/// starting at 0 (up) or ending at π (down).
pub fn engagement(up: bool, immersion: f64) -> (f64, f64) {
    let sweep = (1.0 - 2.0 * immersion).acos();
    if up { (0.0, sweep) } else { (PI - sweep, PI) }
}

fn build_milling_force(p: &mut Params) -> Result<Built, Diagnostic> {
    let whole = |v: f64| (1.0..=64.0).contains(&v) && v.fract() == 0.0;
    let teeth = p.number_where("teeth", None, whole, "a whole number from 1 to 64")? as usize;
    let rpm = p.positive("rpm")?;
    let non_negative = |v: f64| v >= 0.0 && v.is_finite();
    let kt = p.number_where("kt", None, non_negative, "a coefficient >= 0 [N/mm²]")?;
    let kr = match (p.has("kr"), p.has("krc")) {
        (true, true) => return Err(p.error("krc", "give either `kr` (a ratio) or `krc` (N/mm²), not both")),
        (_, false) => p.number_where("kr", None, non_negative, "a ratio >= 0")?,
        (false, true) => {
            let krc = p.number_where("krc", None, non_negative, "a coefficient >= 0 [N/mm²]")?;
            if kt == 0.0 {
                return Err(p.error("krc", "`krc` needs `kt` > 0 (Kr = krc/kt); give `kr` instead"));
            }
            krc / kt
        }
    };
    let ap = p.number_where("ap", None, non_negative, "a depth >= 0 [mm]")?;
    let feed = p.number_where("ft", None, non_negative, "a feed per tooth >= 0 [mm]")?;
    let (entry, exit) = immersion_angles(p)?;
    let phase = p.number_where("phase", None, f64::is_finite, "a finite angle [deg]")?.to_radians();
    let zero_crossing = p.flag("zero_crossing")?;
    let tooth_outputs = p.flag("tooth_outputs")?;
    let cutter = Cutter { teeth, omega: TAU * rpm / 60.0, kt, kr, ap, feed, entry, exit, phase };
    let mut iface = Interface::new(SampleTime::Continuous);
    for name in ["x", "y", "x_delayed", "y_delayed"] {
        iface = iface.input(name, Width::Fixed(1), true);
    }
    iface = iface.output("fx", Width::Fixed(1)).output("fy", Width::Fixed(1));
    if tooth_outputs {
        for name in ["h", "ft_tooth", "fr_tooth"] {
            iface = iface.output(name, Width::Fixed(teeth));
        }
    }
    let block = MillingForce {
        cutter,
        zero_crossing,
        tooth_outputs,
        in_cut: vec![false; teeth],
        chip_positive: vec![false; teeth],
    };
    Ok(Built::new(block, iface))
}

#[cfg(test)]
mod tests;
