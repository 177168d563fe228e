//! Frequency-domain analysis of a single-input single-output linear model:
//! its response G(jω) (or G(e^{jωT}) when discrete), poles, and the loop
//! figures a control engineer reads off a Bode plot — gain and phase
//! margins with their frequencies, delay margin, peak sensitivity, and
//! bandwidth. Conventions are python-control's (`stability_margins`,
//! `bandwidth`): the model is a loop transfer L closed with negative
//! feedback; of several crossings, the margins closest to instability are
//! reported. Linear algebra (complex LU, eigenvalues) is faer's.

use crate::StateSpace;
use faer::Mat;
pub use faer::c64;
use faer::linalg::solvers::Solve;

#[cfg(test)]
mod tests;

/// A model's response at s (continuous) or z (discrete): C (sI − A)⁻¹ B + D.
/// Infinite when sI − A is singular (a pole at s).
pub fn evaluate(ss: &StateSpace, s: c64) -> c64 {
    let n = ss.n;
    let d = c64::new(ss.d[0], 0.0);
    if n == 0 {
        return d;
    }
    let m = Mat::<c64>::from_fn(n, n, |i, j| {
        let a = c64::new(-ss.a[i * n + j], 0.0);
        if i == j { a + s } else { a }
    });
    let lu = m.partial_piv_lu();
    let mut x = Mat::<c64>::from_fn(n, 1, |i, _| c64::new(ss.b[i * ss.m], 0.0));
    lu.solve_in_place(&mut x);
    let cx: c64 = (0..n).map(|i| x[(i, 0)] * ss.c[i]).sum();
    if cx.re.is_finite() && cx.im.is_finite() { cx + d } else { c64::new(f64::INFINITY, 0.0) }
}

/// The response at angular frequency `w` [rad/s]: s = jω, or z = e^{jωT}
/// for a model discrete with sample time T.
pub fn at_frequency(ss: &StateSpace, w: f64, sample_time: Option<f64>) -> c64 {
    match sample_time {
        None => evaluate(ss, c64::new(0.0, w)),
        Some(t) => evaluate(ss, c64::from_polar(1.0, w * t)),
    }
}

/// Eigenvalues of A (the model's poles), sorted by real part, then
/// imaginary part. `None` if the eigenvalue iteration fails to converge.
pub fn poles(ss: &StateSpace) -> Option<Vec<c64>> {
    if ss.n == 0 {
        return Some(Vec::new());
    }
    let mut balanced = ss.a.clone();
    balance(&mut balanced, ss.n);
    let a = Mat::<f64>::from_fn(ss.n, ss.n, |i, j| balanced[i * ss.n + j]);
    let mut p = a.eigenvalues().ok()?;
    p.sort_by(|x, y| x.re.total_cmp(&y.re).then(x.im.total_cmp(&y.im)));
    Some(p)
}

/// Balances a row-major n×n matrix in place by a diagonal similarity
/// D⁻¹AD with powers of two (exact: the eigenvalues do not change), so that
/// each row and column have comparable norms — Parlett & Reinsch (1969),
/// the step LAPACK's dgeev takes first. Without it the eigenvalues of a
/// discretised observer (entries from 10⁻⁴ to 10⁵) come out wrong in the
/// seventh digit.
fn balance(a: &mut [f64], n: usize) {
    let mut converged = false;
    while !converged {
        converged = true;
        for i in 0..n {
            let (mut c, mut r) = (0.0, 0.0);
            for j in (0..n).filter(|&j| j != i) {
                c += a[j * n + i].abs();
                r += a[i * n + j].abs();
            }
            if c == 0.0 || r == 0.0 || !(c + r).is_finite() {
                continue;
            }
            let (sum, mut f) = (c + r, 1.0);
            while c < r / 2.0 {
                f *= 2.0;
                c *= 4.0;
            }
            while c > r * 2.0 {
                f /= 2.0;
                c /= 4.0;
            }
            if (c + r) / f < 0.95 * sum {
                converged = false;
                for j in 0..n {
                    a[i * n + j] /= f;
                    a[j * n + i] *= f;
                }
            }
        }
    }
}

/// A pole's natural frequency ωn [rad/s] and damping ζ; a discrete pole z
/// is first mapped to s = ln(z)/T.
pub fn natural_frequency_and_damping(pole: c64, sample_time: Option<f64>) -> (f64, f64) {
    let s = match sample_time {
        None => pole,
        Some(t) => pole.ln() / t,
    };
    let wn = s.norm();
    // z = 0 (a pure delay's pole) is infinitely fast and not oscillating.
    let zeta = if !wn.is_finite() {
        1.0
    } else if wn > 0.0 {
        -s.re / wn
    } else {
        -1.0
    };
    (wn, zeta)
}

/// `points` frequencies spaced evenly in log10 from `from` to `to`.
pub fn log_grid(from: f64, to: f64, points: usize) -> Vec<f64> {
    let (a, b) = (from.log10(), to.log10());
    let last = points.max(2) - 1;
    (0..=last).map(|k| 10f64.powf(a + (b - a) * k as f64 / last as f64)).collect()
}

/// A frequency range that shows the model's dynamics: two decades below
/// its slowest nonzero pole and above its fastest (1 rad/s around when it
/// has none), and at most the Nyquist frequency π/T when discrete.
pub fn auto_range(ss: &StateSpace, sample_time: Option<f64>) -> (f64, f64) {
    let speeds: Vec<f64> = poles(ss)
        .unwrap_or_default()
        .into_iter()
        .map(|p| natural_frequency_and_damping(p, sample_time).0)
        .filter(|w| *w > 1e-12 && w.is_finite())
        .collect();
    let slow = speeds.iter().copied().fold(f64::INFINITY, f64::min);
    let fast = speeds.iter().copied().fold(0.0, f64::max);
    let (mut lo, mut hi) = if speeds.is_empty() { (1e-2, 1e2) } else { (slow / 100.0, fast * 100.0) };
    if let Some(t) = sample_time {
        hi = hi.min(std::f64::consts::PI / t);
        lo = lo.min(hi / 1e4);
    }
    if hi <= lo {
        (lo, hi) = (hi / 100.0, hi);
    }
    (lo, hi)
}

/// Phase in degrees along a frequency grid, unwrapped (no jumps of 360°),
/// starting on the principal branch.
pub fn unwrapped_phase_deg(values: &[c64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(values.len());
    let mut offset = 0.0;
    let mut previous: Option<f64> = None;
    for v in values {
        let p = v.arg().to_degrees();
        if let Some(q) = previous {
            let jump = p + offset - q;
            offset -= 360.0 * (jump / 360.0).round();
        }
        let p = p + offset;
        out.push(p);
        previous = Some(p);
    }
    out
}

/// Stability margins of a loop transfer L, python-control's conventions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Margins {
    /// 1/|L| where L crosses the negative real axis (the crossing with
    /// |log GM| smallest); infinite when it never does.
    pub gain_margin: f64,
    /// Where the gain margin is read [rad/s] (NaN without one).
    pub gain_crossover_phase_freq: f64,
    /// 180° + ∠L where |L| = 1, in (−180°, 180°] (the crossing with the
    /// smallest |PM|); infinite when |L| never crosses 1.
    pub phase_margin: f64,
    /// The gain crossover frequency [rad/s] (NaN without one).
    pub gain_crossover_freq: f64,
    /// Phase margin over gain crossover frequency [s]: the smallest added
    /// delay that destabilises the loop (of all crossings).
    pub delay_margin: f64,
    /// Peak sensitivity max |1/(1 + L)| (1/Ms is the distance of L to −1).
    pub peak_sensitivity: f64,
    pub peak_sensitivity_freq: f64,
}

/// Finds the margins of `ss` as a loop transfer from a log grid over
/// [`auto_range`] widened by three decades each way (1000 points per
/// decade), every crossing and the sensitivity peak refined to machine
/// precision by bisection or golden-section search.
pub fn margins(ss: &StateSpace, sample_time: Option<f64>) -> Margins {
    let (lo, hi) = auto_range(ss, sample_time);
    let lo = lo / 1e3;
    let hi = match sample_time {
        Some(t) => std::f64::consts::PI / t,
        None => hi * 1e3,
    };
    let decades = (hi / lo).log10().ceil().max(1.0) as usize;
    let grid = log_grid(lo, hi, decades * 1000 + 1);
    let l = |w: f64| at_frequency(ss, w, sample_time);
    let values: Vec<c64> = grid.iter().map(|&w| l(w)).collect();

    // Gain crossovers: |L| − 1 changes sign.
    let mut phase_margin = f64::INFINITY;
    let mut gain_crossover_freq = f64::NAN;
    let mut delay_margin = f64::INFINITY;
    for k in 1..grid.len() {
        let (a, b) = (values[k - 1].norm() - 1.0, values[k].norm() - 1.0);
        if (a < 0.0) != (b < 0.0) {
            let w = bisect(|w| l(w).norm() - 1.0, grid[k - 1], grid[k]);
            let pm = (l(w).arg().to_degrees()).rem_euclid(360.0) - 180.0;
            if pm.abs() < phase_margin.abs() {
                (phase_margin, gain_crossover_freq) = (pm, w);
            }
            // A loop with negative phase margin is unstable already: no delay margin.
            let dm = if pm >= 0.0 { pm.to_radians() / w } else { 0.0 };
            delay_margin = delay_margin.min(dm);
        }
    }
    // Phase crossovers: Im L changes sign where Re L < 0.
    let mut gain_margin = f64::INFINITY;
    let mut gain_crossover_phase_freq = f64::NAN;
    for k in 1..grid.len() {
        let (a, b) = (values[k - 1].im, values[k].im);
        if (a < 0.0) != (b < 0.0) && a.is_finite() && b.is_finite() {
            let w = bisect(|w| l(w).im, grid[k - 1], grid[k]);
            let v = l(w);
            if v.re < 0.0 {
                let gm = 1.0 / v.norm();
                if gm.ln().abs() < gain_margin.ln().abs() {
                    (gain_margin, gain_crossover_phase_freq) = (gm, w);
                }
            }
        }
    }
    // Sensitivity peak: the smallest |1 + L| over the grid, refined.
    let distance = |w: f64| (l(w) + 1.0).norm();
    let (mut k_min, mut d_min) = (0, f64::INFINITY);
    for (k, v) in values.iter().enumerate() {
        let d = (v + 1.0).norm();
        if d < d_min {
            (k_min, d_min) = (k, d);
        }
    }
    let (a, b) = (grid[k_min.saturating_sub(1)], grid[(k_min + 1).min(grid.len() - 1)]);
    let w_peak = golden_minimum(distance, a, b);
    let d_peak = distance(w_peak).min(d_min);
    Margins {
        gain_margin,
        gain_crossover_phase_freq,
        phase_margin,
        gain_crossover_freq,
        delay_margin,
        peak_sensitivity: 1.0 / d_peak,
        peak_sensitivity_freq: if distance(w_peak) <= d_min { w_peak } else { grid[k_min] },
    }
}

/// The −3 dB bandwidth of G (python-control's `bandwidth`): the first
/// frequency where |G| falls 3 dB below its value at DC. Infinite if it
/// never does within `[from, to]`; NaN if the DC gain is zero or infinite.
pub fn bandwidth(g: impl Fn(f64) -> c64, dc: c64, from: f64, to: f64) -> f64 {
    let dc = dc.norm();
    if !(dc > 0.0 && dc.is_finite()) {
        return f64::NAN;
    }
    let target = dc / 10f64.powf(3.0 / 20.0);
    let grid = log_grid(from, to, ((to / from).log10().ceil().max(1.0) as usize) * 1000 + 1);
    for k in 1..grid.len() {
        if g(grid[k]).norm() < target {
            return bisect(|w| g(w).norm() - target, grid[k - 1], grid[k]);
        }
    }
    f64::INFINITY
}

/// A root of `f` between `a` and `b` (opposite signs) by bisection in log
/// frequency, to the last bit.
fn bisect(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
    let fa = f(a);
    for _ in 0..200 {
        let m = (a * b).sqrt();
        if m <= a || m >= b {
            break;
        }
        let fm = f(m);
        if fm == 0.0 {
            return m;
        }
        if (fm < 0.0) == (fa < 0.0) { a = m } else { b = m }
    }
    (a * b).sqrt()
}

/// The minimum of a unimodal `f` on [a, b] by golden-section search in
/// log frequency.
fn golden_minimum(f: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = (a.ln(), b.ln());
    for _ in 0..200 {
        if b - a <= 1e-15 * a.abs().max(1.0) {
            break;
        }
        let (c, d) = (b - r * (b - a), a + r * (b - a));
        if f(c.exp()) < f(d.exp()) { b = d } else { a = c }
    }
    ((a + b) / 2.0).exp()
}
