//! Analytic stability lobes of milling, zeroth-order approximation
//! (Altintas & Budak, CIRP Annals 44/1, 1995; Altintas, *Manufacturing
//! Automation*, 2nd ed., §4.3): the time-varying directional factors of the
//! `milling_force` block averaged over a tooth pitch, which turns the
//! regenerative delay equation into an eigenvalue problem per chatter
//! frequency. A reference to compare simulated chatter against: it ignores
//! the teeth leaving the cut and the harmonics of the tooth passing.

use super::Cutter;
/// A complex number (num-complex's, as faer's `c64` is).
#[allow(non_camel_case_types)]
pub type c64 = nalgebra::Complex<f64>;
use std::f64::consts::{PI, TAU};

/// The average directional factors `[[αxx, αxy], [αyx, αyy]]` of a cut
/// from `entry` to `exit` [rad] with radial ratio `kr`:
///   αxx = ½[cos 2φ − 2Kr·φ + Kr·sin 2φ],  αxy = ½[−sin 2φ − 2φ + Kr·cos 2φ],
///   αyx = ½[−sin 2φ + 2φ + Kr·cos 2φ],    αyy = ½[−cos 2φ − 2Kr·φ − Kr·sin 2φ],
/// each taken from φst to φex; the mean force is (N·ap·Kt/4π)·α·Δ for a
/// displacement change Δ over a tooth period (the block's eq. 1–6).
pub fn directional_factors(entry: f64, exit: f64, kr: f64) -> [[f64; 2]; 2] {
    let between = |f: &dyn Fn(f64) -> f64| 0.5 * (f(exit) - f(entry));
    let (s, c) = (|p: f64| (2.0 * p).sin(), |p: f64| (2.0 * p).cos());
    [
        [between(&|p| c(p) - 2.0 * kr * p + kr * s(p)), between(&|p| -s(p) - 2.0 * p + kr * c(p))],
        [between(&|p| -s(p) + 2.0 * p + kr * c(p)), between(&|p| -c(p) - 2.0 * kr * p - kr * s(p))],
    ]
}

/// A point on the stability boundary: chatter at `chatter` [rad/s] starts
/// at axial depth `depth` [mm] when the spindle turns at `rpm`, on lobe
/// `lobe` (the number of whole chatter waves between two teeth) of
/// eigenvalue `root` (0 or 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LobePoint {
    pub rpm: f64,
    pub depth: f64,
    pub chatter: f64,
    pub lobe: usize,
    pub root: usize,
}

/// The eigenvalues Λ of det(I + Λ·α·Φ) = 0 at one chatter frequency, for
/// the tool's direct frequency responses `phi_xx`, `phi_yy` [mm/N] (no
/// cross terms): the roots of a0·Λ² + a1·Λ + 1 = 0 with
/// a0 = Φxx·Φyy·(αxx·αyy − αxy·αyx), a1 = αxx·Φxx + αyy·Φyy. A single-axis
/// tool (a0 = 0) has one finite root; the other is infinite.
pub fn eigenvalues(alpha: &[[f64; 2]; 2], phi_xx: c64, phi_yy: c64) -> [c64; 2] {
    let a0 = phi_xx * phi_yy * (alpha[0][0] * alpha[1][1] - alpha[0][1] * alpha[1][0]);
    let a1 = phi_xx * alpha[0][0] + phi_yy * alpha[1][1];
    // Without cancellation: q = −(a1 ± √(a1² − 4a0))/2 with the sign that
    // makes |q| large; the roots are q/a0 and 1/q.
    let root = (a1 * a1 - 4.0 * a0).sqrt();
    let q = if (a1 + root).norm() >= (a1 - root).norm() { -(a1 + root) * 0.5 } else { -(a1 - root) * 0.5 };
    [q / a0, c64::new(1.0, 0.0) / q]
}

/// The critical axial depth [mm] and the phase ε between the inner and
/// outer modulation of the eigenvalue Λ:
///   a_lim = −2π·ΛR·(1 + κ²)/(N·Kt),  κ = ΛI/ΛR,  ε = π − 2·atan κ.
/// `None` when a_lim <= 0 (or Λ is infinite): that root cannot chatter.
pub fn critical_depth(cutter: &Cutter, lambda: c64) -> Option<(f64, f64)> {
    let kappa = lambda.im / lambda.re;
    let depth = -TAU * lambda.re * (1.0 + kappa * kappa) / (cutter.teeth as f64 * cutter.kt);
    (depth.is_finite() && depth > 0.0).then(|| (depth, PI - 2.0 * kappa.atan()))
}

/// The stability lobes over the chatter frequencies `freqs` [rad/s] (in
/// increasing order) for lobes 0 … `lobes` − 1, as curves: each follows one
/// eigenvalue (matched to its nearest neighbour from one frequency to the
/// next) and one lobe over consecutive frequencies at which it can
/// chatter. At each frequency the tooth period T = (ε + 2πk)/ωc gives the
/// spindle speed 60/(N·T). `frf(ω)` is the tool's (Φxx, Φyy) at ω [mm/N].
pub fn lobes(cutter: &Cutter, frf: impl Fn(f64) -> (c64, c64), freqs: &[f64], lobes: usize) -> Vec<Vec<LobePoint>> {
    let alpha = directional_factors(cutter.entry, cutter.exit, cutter.kr);
    let mut curves: Vec<Vec<LobePoint>> = Vec::new();
    // The curve each (root, lobe) is extending, if it chattered at the last frequency.
    let mut open = vec![[None::<usize>; 2]; lobes];
    let mut last: Option<[c64; 2]> = None;
    for &wc in freqs {
        let (xx, yy) = frf(wc);
        let mut roots = eigenvalues(&alpha, xx, yy);
        if let Some([p, q]) = last {
            let near = |a: c64, b: c64| if (a - b).norm().is_nan() { f64::INFINITY } else { (a - b).norm() };
            if near(roots[0], q) + near(roots[1], p) < near(roots[0], p) + near(roots[1], q) {
                roots.swap(0, 1);
            }
        }
        last = Some(roots);
        for (root, lambda) in roots.into_iter().enumerate() {
            let found = critical_depth(cutter, lambda);
            for (lobe, slot) in open.iter_mut().enumerate() {
                let Some((depth, eps)) = found else {
                    slot[root] = None;
                    continue;
                };
                let period = (eps + TAU * lobe as f64) / wc;
                let point = LobePoint { rpm: 60.0 / (cutter.teeth as f64 * period), depth, chatter: wc, lobe, root };
                match slot[root] {
                    Some(i) => curves[i].push(point),
                    None => {
                        slot[root] = Some(curves.len());
                        curves.push(vec![point]);
                    }
                }
            }
        }
    }
    curves
}

/// The critical depth at spindle speed `rpm`: the lowest of the `curves`
/// ([`lobes`]) there, each interpolated linearly between its neighbouring
/// chatter frequencies. `None` where no curve passes.
pub fn critical_depth_at(curves: &[Vec<LobePoint>], rpm: f64) -> Option<f64> {
    curves
        .iter()
        .flat_map(|curve| curve.windows(2))
        .filter(|pair| (pair[0].rpm - rpm) * (pair[1].rpm - rpm) <= 0.0 && pair[0].rpm != pair[1].rpm)
        .map(|pair| {
            let (a, b) = (pair[0], pair[1]);
            a.depth + (b.depth - a.depth) * (rpm - a.rpm) / (b.rpm - a.rpm)
        })
        .min_by(f64::total_cmp)
}

#[cfg(test)]
mod tests;
