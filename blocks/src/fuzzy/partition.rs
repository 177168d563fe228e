//! A variable whose terms are a triangular partition: term k rises from
//! peak k−1 to peak k and falls to peak k+1, the end ones half triangles.
//! At any point at most two neighbouring terms are nonzero, and which they
//! are is arithmetic — what the rule table (`grid`) and the exact centroid
//! (`centroid`) build on.

use super::terms::{Mf, Variable};

/// A variable's partition: its peaks, strictly increasing.
#[derive(Clone, Debug)]
pub(super) struct Partition {
    pub(super) peaks: Vec<f64>,
    /// The mean spacing, for the first guess of where an input falls.
    per_step: f64,
}

impl Partition {
    /// `None` unless the terms are a triangular partition covering [lo, hi]:
    /// Tri(p_{k−1}, p_k, p_{k+1}) with p_{−1} = p_0 and p_n = p_{n−1}.
    pub(super) fn of(v: &Variable) -> Option<Self> {
        let corners = v.terms.iter().map(|(_, mf)| match *mf {
            Mf::Tri(a, b, c) => Some((a, b, c)),
            _ => None,
        });
        let corners = corners.collect::<Option<Vec<_>>>()?;
        let peaks: Vec<f64> = corners.iter().map(|c| c.1).collect();
        let n = peaks.len();
        let peak = |k: usize| peaks[k.min(n - 1)];
        let chained =
            corners.iter().enumerate().all(|(k, &(a, _, c))| a == peak(k.saturating_sub(1)) && c == peak(k + 1));
        let increasing = peaks.windows(2).all(|w| w[0] < w[1]);
        let covers = n >= 2 && peaks[0] <= v.lo && v.hi <= peaks[n - 1];
        (chained && increasing && covers)
            .then(|| Partition { per_step: (n - 1) as f64 / (peaks[n - 1] - peaks[0]), peaks })
    }

    /// The k with peak k ≤ x < peak k+1 (k ≤ n − 2), and the memberships of
    /// terms k and k+1 at x, as `Mf::eval` computes them.
    #[inline(always)]
    pub(super) fn locate(&self, x: f64) -> (usize, f64, f64) {
        let p = &self.peaks;
        let last = p.len() - 2;
        // The guess rounded (`as usize`, which saturates, costs several
        // instructions more): the loops below correct it by one if need be.
        let guess = nearest_whole((x - p[0]) * self.per_step - 0.5);
        let mut k = guess.clamp(0, last as i32) as usize;
        while k > 0 && x < p[k] {
            k -= 1;
        }
        while k < last && x >= p[k + 1] {
            k += 1;
        }
        // On a peak these are exactly 1 and 0 (a/a and 0/a), as `Mf::eval`
        // gives there by its own branch.
        let width = p[k + 1] - p[k];
        (k, (p[k + 1] - x) / width, (x - p[k]) / width)
    }
}

/// The whole number nearest to `x` (|x| < 2³¹; ties to even), without a
/// conversion instruction's saturating checks or a libm call (`f64::round`
/// and `ceil` are calls on baseline x86-64, without SSE4.1): adding
/// 1.5·2⁵² rounds, as there the doubles are one apart, and leaves the whole
/// number in the sum's low bits, two's complement.
#[inline(always)]
pub(super) fn nearest_whole(x: f64) -> i32 {
    const ROUND: f64 = 6_755_399_441_055_744.0;
    (x + ROUND).to_bits() as u32 as i32
}
