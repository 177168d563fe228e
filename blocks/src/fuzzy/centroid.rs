//! The centroid of a Mamdani output's aggregate μ, sampled on the output's
//! uniform grid x_j = lo + j·dx, j = 0 … L, and taken piecewise linear
//! between the samples (scikit-fuzzy's trapezoids). Two ways to the same
//! number: from the samples (`centroid_on_grid`), and — when the output's
//! terms are a triangular partition — in closed form from the term
//! strengths, without sampling anything (`PartitionCentroid`).
//!
//! Both end in the same formula. Per segment, area = dx·(μ_j + μ_{j+1})/2
//! and moment = dx/2·[(μ_j + μ_{j+1})·x_j + dx·(μ_j + 2μ_{j+1})/3]; summed
//! over the grid, each inner sample weighs dx in the area and dx·x_j in the
//! moment, the end ones half that with a correction of ±dx²/6. With
//! S0 = Σ μ_j, S1 = Σ j·μ_j:
//!
//!   centroid = lo + dx·(S1 + μ_0/6 − μ_L·(L/2 + 1/6)) / (S0 − (μ_0 + μ_L)/2)

use super::fis::{Aggregation, Implication};
use super::partition::{Partition, nearest_whole};
use super::terms::Variable;
use std::ops::Range;

/// The centroid from the samples of μ in `range` of the grid (μ is zero
/// outside): two running sums without weight arrays, four lanes each so
/// the loop vectorises. `None` when the area is zero.
pub(super) fn centroid_on_grid(mu: &[f64], range: Range<usize>, lo: f64, hi: f64) -> Option<f64> {
    let last = mu.len() - 1;
    let first_value = if range.start == 0 { mu[0] } else { 0.0 };
    let last_value = if range.end == mu.len() { mu[last] } else { 0.0 };
    let from = range.start as f64;
    let samples = &mu[range];
    let (mut s0, mut s1) = ([0.0f64; 4], [0.0f64; 4]);
    let chunks = samples.chunks_exact(4);
    let tail = chunks.remainder();
    let mut index = [0.0, 1.0, 2.0, 3.0];
    for c in chunks {
        for k in 0..4 {
            s0[k] += c[k];
            s1[k] += index[k] * c[k];
            index[k] += 4.0;
        }
    }
    let (mut sum, mut moment) = ((s0[0] + s0[1]) + (s0[2] + s0[3]), (s1[0] + s1[1]) + (s1[2] + s1[3]));
    for (k, &v) in tail.iter().enumerate() {
        sum += v;
        moment += index[k] * v;
    }
    // Σ j·μ_j with j = from + local index.
    let l = last as f64;
    trapezoid_centroid(sum, from * sum + moment, first_value, last_value, lo, (hi - lo) / l, l)
}

/// The formula of the module's doc from S0 = Σ μ_j, S1 = Σ j·μ_j and the
/// end samples μ_0, μ_L on the grid from `lo` by `dx` = (hi − lo)/L;
/// `None` when the area is zero.
fn trapezoid_centroid(s0: f64, s1: f64, first: f64, last: f64, lo: f64, dx: f64, l: f64) -> Option<f64> {
    let moment = s1 + first / 6.0 - last * (l / 2.0 + 1.0 / 6.0);
    let area = s0 - 0.5 * (first + last);
    (area > 0.0).then(|| lo + dx * moment / area)
}

/// The exact centroid of an output whose terms are a triangular partition,
/// for min or product implication with max aggregation, or product with
/// sum (min with sum clips each rule's term separately: not a function of
/// the term strengths).
///
/// Between neighbouring peaks p_k and p_{k+1}, with s = (x − p_k)/(p_{k+1} − p_k),
/// only terms k and k+1 are nonzero, with memberships 1 − s and s; clipped
/// (min) or scaled (product) by their strengths w_k and w_{k+1}, and
/// aggregated, μ is linear in s between at most three breakpoints: the two
/// clipping kinks 1 − w_k and w_{k+1}, and where the falling and the rising
/// part cross (max aggregation). So on a cell's grid points i = 0 … n − 1
/// μ is α + β·i piece by piece, and a piece's sums Σ μ_i and Σ i·μ_i are
/// α·Δn + β·ΔT1 and α·ΔT1 + β·ΔT2, with T1(b) = Σ_{i<b} i and T2(b) =
/// Σ_{i<b} i² at its ends: a handful of operations per piece instead of a
/// pass over the grid per term. The grid's two end points, which the
/// trapezoid rule weighs by half, are evaluated apart, in x as `Mf::eval`
/// does (on an outer peak a term is exactly 0 or 1 there). The result
/// equals the sampled one up to rounding, relative to the samples (tested
/// to 1e-12 of the universe, with strengths down to 1e-18).
#[derive(Clone, Debug)]
pub(super) struct PartitionCentroid {
    /// Per pair of neighbouring peaks, the cell between them.
    pub(super) cells: Vec<Cell>,
    /// The cells holding the grid's first and last points, and s there
    /// (the trapezoid rule weighs the end samples by half).
    pub(super) ends: [(usize, f64); 2],
    /// Index L of the last grid point.
    pub(super) last: f64,
    pub(super) lo: f64,
    pub(super) hi: f64,
    /// The grid's step, (hi − lo)/L.
    pub(super) dx: f64,
    pub(super) implication: Implication,
    pub(super) aggregation: Aggregation,
}

impl PartitionCentroid {
    /// `None` unless `v`'s terms are a triangular partition covering its
    /// universe and the methods are one of the three above.
    pub(super) fn new(v: &Variable, points: usize, implication: Implication, aggregation: Aggregation) -> Option<Self> {
        if (implication, aggregation) == (Implication::Min, Aggregation::Sum) || points < 2 {
            return None;
        }
        let peaks = Partition::of(v)?.peaks;
        let last = (points - 1) as f64;
        let step = (v.hi - v.lo) / last;
        let at = |p: f64| (p - v.lo) / step;
        let first = |p: f64| {
            if p <= v.lo {
                0.0
            } else if p >= v.hi {
                last + 1.0
            } else {
                at(p).ceil().min(last)
            }
        };
        // The grid's end points are taken apart, in x as `Mf::eval` takes
        // them: on an outer peak (the usual universe) a term is exactly 0
        // or 1 there, where s from the grid index is only near it. So the
        // cells hold the inner points 1 … L − 1.
        let edges: Vec<(f64, f64)> = peaks.windows(2).map(|p| (first(p[0]), first(p[1]))).collect();
        let holding = |j: f64, x: f64| {
            let k = edges.iter().position(|&(a, b)| a <= j && j < b)?;
            // Exactly 0 and 1 on the peaks (0/a and a/a).
            Some((k, (x - peaks[k]) / (peaks[k + 1] - peaks[k])))
        };
        let ends = [holding(0.0, v.lo)?, holding(last, v.hi)?];
        let cells = peaks
            .windows(2)
            .zip(edges)
            .map(|(p, (start, end))| {
                let (a, span) = (at(p[0]), at(p[1]) - at(p[0]));
                let (start, end) = (start.max(1.0), end.min(last));
                let (len, offset, per_point) = ((end - start).max(0.0), start - a, 1.0 / span);
                let (s_first, rises) = (offset * per_point, len > 0.0 && end - 1.0 > a);
                let len_sums = sums_below(len);
                let below = (0..=len as usize).map(|n| Below::new(n as f64, len_sums, s_first, per_point)).collect();
                let (top, offset_less_half) = (len as i32, offset - 0.5);
                Cell { start, len, top, offset_less_half, span, per_point, s_first, len_sums, below, rises }
            })
            .collect();
        let dx = (v.hi - v.lo) / last;
        Some(PartitionCentroid { cells, ends, last, lo: v.lo, hi: v.hi, dx, implication, aggregation })
    }

    /// The centroid of the aggregate of the terms at `strength` (one per
    /// term); `None` when it is zero everywhere.
    pub(super) fn centroid(&self, strength: &[f64]) -> Option<f64> {
        // One dispatch on the methods per call, not one per cell.
        match (self.implication, self.aggregation) {
            (Implication::Min, _) => self.centroid_of::<MinMax>(strength),
            (Implication::Product, Aggregation::Max) => self.centroid_of::<ProductMax>(strength),
            (Implication::Product, Aggregation::Sum) => self.centroid_of::<ProductSum>(strength),
        }
    }

    /// The universe's midpoint: the output when no rule fires.
    pub(super) fn midpoint(&self) -> f64 {
        (self.lo + self.hi) / 2.0
    }

    fn centroid_of<M: Method>(&self, strength: &[f64]) -> Option<f64> {
        // S0 = Σ μ_j and S1 = Σ j·μ_j; whether some sample is nonzero is
        // decided from the strengths, not from S0.
        let (mut s0, mut s1, mut positive) = (0.0, 0.0, false);
        for ((cell, &wa), &wb) in self.cells.iter().zip(strength).zip(&strength[1..]) {
            if wa > 0.0 || wb > 0.0 {
                positive |= (wa > 0.0 && cell.len > 0.0) || (wb > 0.0 && cell.rises);
                let (z0, z1) = M::sums(cell, wa, wb);
                s0 += z0;
                s1 += cell.start * z0 + z1;
            }
        }
        let at_end = |(k, s): (usize, f64)| M::at(strength[k], strength[k + 1], s);
        let (first, last) = (at_end(self.ends[0]), at_end(self.ends[1]));
        if !(positive || first > 0.0 || last > 0.0) {
            return None;
        }
        let (s0, s1) = (s0 + first + last, s1 + self.last * last);
        trapezoid_centroid(s0, s1, first, last, self.lo, self.dx, self.last)
    }
}

/// μ on a cell whose falling and rising terms have strengths w_a and w_b
/// (not both zero): its sums over the cell's points (`Cell::sums` of its
/// pieces c0 + c1·s, each as (s where it ends, c0, c1), the last running
/// to the cell's end), and its value at one s.
trait Method {
    fn sums(cell: &Cell, wa: f64, wb: f64) -> (f64, f64);
    fn at(wa: f64, wb: f64, s: f64) -> f64;
}

/// f = min(w_a, 1 − s) is w_a up to 1 − w_a, then 1 − s; g = min(w_b, s)
/// is s up to w_b, then w_b. f falls and g rises, so μ = max(f, g) is f up
/// to their crossing and g after it. Unless both strengths pass ½, one of
/// the two slopes is hidden: μ is w_a up to w_a, then s up to w_b, then w_b
/// (w_a ≤ w_b), or w_a up to 1 − w_a, then 1 − s up to 1 − w_b, then w_b —
/// three pieces, one form for the cells of one strength zero (most of the
/// active ones) and of two. With both past ½, μ falls to ½ at s = ½ and
/// rises again: four pieces.
struct MinMax;

impl Method for MinMax {
    #[inline(always)]
    fn sums(cell: &Cell, wa: f64, wb: f64) -> (f64, f64) {
        // One strength zero (most active cells): its piece is empty or zero,
        // so the slope runs from the cell's start or to its end, with no
        // point dropped by rounding there: one lookup.
        let whole = cell.len_sums;
        if wa == 0.0 {
            let b = cell.below(wb);
            return (b.rise.0 + wb * (whole.0 - b.n.0), b.rise.1 + wb * (whole.1 - b.n.1));
        }
        if wb == 0.0 {
            let b = cell.below(1.0 - wa);
            return (wa * b.n.0 + b.fall.0, wa * b.n.1 + b.fall.1);
        }
        if wa > 0.5 && wb > 0.5 {
            return cell.sums([(1.0 - wa, wa, 0.0), (0.5, 1.0, -1.0), (wb, 0.0, 1.0), (1.0, wb, 0.0)]);
        }
        // w_a up to the slope's start, w_b from its end; the slope's sums
        // are the difference of two looked up.
        let (b1, b2, slope) = if wa <= wb {
            let (b1, b2) = (cell.below(wa), cell.below(wb));
            (b1, b2, (b2.rise.0 - b1.rise.0, b2.rise.1 - b1.rise.1))
        } else {
            let (b1, b2) = (cell.below(1.0 - wa), cell.below(1.0 - wb));
            (b1, b2, (b1.fall.0 - b2.fall.0, b1.fall.1 - b2.fall.1))
        };
        let z0 = wa * b1.n.0 + slope.0 + wb * (whole.0 - b2.n.0);
        let z1 = wa * b1.n.1 + slope.1 + wb * (whole.1 - b2.n.1);
        (z0, z1)
    }

    fn at(wa: f64, wb: f64, s: f64) -> f64 {
        // Plain comparisons: no NaN to handle.
        let falling = if wa < 1.0 - s { wa } else { 1.0 - s };
        let rising = if wb < s { wb } else { s };
        if falling > rising { falling } else { rising }
    }
}

/// w_a·(1 − s) up to where it meets w_b·s, then w_b·s.
struct ProductMax;

impl Method for ProductMax {
    #[inline(always)]
    fn sums(cell: &Cell, wa: f64, wb: f64) -> (f64, f64) {
        cell.sums([(wa / (wa + wb), wa, -wa), (1.0, 0.0, wb)])
    }

    fn at(wa: f64, wb: f64, s: f64) -> f64 {
        let (falling, rising) = (wa * (1.0 - s), wb * s);
        if falling > rising { falling } else { rising }
    }
}

/// w_a·(1 − s) + w_b·s: one piece.
struct ProductSum;

impl Method for ProductSum {
    #[inline(always)]
    fn sums(cell: &Cell, wa: f64, wb: f64) -> (f64, f64) {
        cell.sums([(1.0, wa, wb - wa)])
    }

    fn at(wa: f64, wb: f64, s: f64) -> f64 {
        wa * (1.0 - s) + wb * s
    }
}

/// The inner grid points between two neighbouring peaks p and q: `len` of
/// them from index `start` (the first at or after p, and at least 1), at
/// s = (i + offset)/span for the i-th, span = (q − p)/dx. Edges are found
/// once, so neighbouring cells agree on which grid points are whose.
#[derive(Clone, Debug)]
pub(super) struct Cell {
    pub(super) start: f64,
    pub(super) len: f64,
    /// `len` as an index.
    pub(super) top: i32,
    /// offset − ½ (`below` rounds to the nearest whole number).
    pub(super) offset_less_half: f64,
    pub(super) span: f64,
    /// 1/span: how much s moves per grid point.
    pub(super) per_point: f64,
    /// s at the first point.
    pub(super) s_first: f64,
    /// `sums_below(len)`.
    pub(super) len_sums: (f64, f64, f64),
    /// [`Below`] n = 0 … len: looked up, not computed, in `below` (a few
    /// floating-point operations and a division fewer per breakpoint, in
    /// the evaluation's longest chain); 56 bytes a point, 5.6 MB an output
    /// at the block's largest resolution.
    below: Box<[Below]>,
    /// Whether some point lies past p (where the rising term is nonzero).
    pub(super) rises: bool,
}

impl Cell {
    /// (Σ μ_i, Σ i·μ_i) over the cell's points i = 0 … n − 1 for μ in
    /// `pieces` (see `Method`). Piece by piece, μ = α + β·i over the points
    /// from the last piece's end to its own, so its sums are α·Δn + β·ΔT1
    /// and α·ΔT1 + β·ΔT2 with T1, T2 the sums of i and i² below an end: an
    /// empty piece adds exactly zero, and a piece of small values small
    /// sums (no cancelling between pieces).
    #[inline(always)]
    fn sums<const P: usize>(&self, pieces: [(f64, f64, f64); P]) -> (f64, f64) {
        let (mut z0, mut z1) = (0.0, 0.0);
        let mut from = (0.0, 0.0, 0.0);
        for (p, (to, c0, c1)) in pieces.into_iter().enumerate() {
            let end = if p + 1 < P { self.below(to).n } else { self.len_sums };
            let (n, t1, t2) = (end.0 - from.0, end.1 - from.1, end.2 - from.2);
            // μ = c0 + c1·s with s = s_first + i·per_point: α + β·i.
            let (a, b) = (c0 + c1 * self.s_first, c1 * self.per_point);
            z0 += a * n + b * t1;
            z1 += a * t1 + b * t2;
            from = end;
        }
        (z0, z1)
    }

    /// The first point n with s ≥ `to` (0 … len), and Σ i, Σ i² over the
    /// points below it: whole numbers held in f64, exact below 2⁵³ (n up
    /// to about 200 000, beyond the block's 100 001 points).
    #[inline(always)]
    fn below(&self, to: f64) -> &Below {
        // The ceiling of the position, as the nearest whole number to it
        // plus ½ (|position| < 2³¹: `to` is in [0, 1], span below 2·10⁵). A
        // point exactly on the end may fall on either side: the pieces
        // meet there.
        let n = nearest_whole(to * self.span - self.offset_less_half);
        &self.below[n.clamp(0, self.top) as usize]
    }
}

/// What a cell's points sum to on either side of point n: `n` = (n, Σ i,
/// Σ i²) over i < n; `rise` = (Σ s_i, Σ i·s_i) over i < n (the rising
/// term's slope up to a kink at n); `fall` = (Σ (1 − s_i), Σ i·(1 − s_i))
/// over i ≥ n (the falling term's slope from a kink at n). A slope
/// between two kinks is the difference of two.
#[derive(Clone, Copy, Debug)]
struct Below {
    n: (f64, f64, f64),
    rise: (f64, f64),
    fall: (f64, f64),
}

impl Below {
    fn new(n: f64, whole: (f64, f64, f64), s_first: f64, per_point: f64) -> Self {
        let below = sums_below(n);
        // μ = α + β·i, summed as α·Σ1 + β·Σi and α·Σi + β·Σi².
        let sums =
            |(alpha, beta): (f64, f64), (n, t1, t2): (f64, f64, f64)| (alpha * n + beta * t1, alpha * t1 + beta * t2);
        let past = (whole.0 - below.0, whole.1 - below.1, whole.2 - below.2);
        Below { n: below, rise: sums((s_first, per_point), below), fall: sums((1.0 - s_first, -per_point), past) }
    }
}

/// n, Σ i and Σ i² over i = 0 … n − 1 (n whole, exact as above).
fn sums_below(n: f64) -> (f64, f64, f64) {
    let t1 = 0.5 * n * (n - 1.0);
    (n, t1, t1 * (2.0 * n - 1.0) / 3.0)
}

#[cfg(test)]
mod tests {
    use super::super::fis::*;
    use super::{PartitionCentroid, centroid_on_grid};

    /// The centroid from two running sums over a range of the uniform grid
    /// equals scikit-fuzzy's trapezoid centroid (`defuzzify`) over the whole
    /// grid, for samples touching either end or neither, at several
    /// resolutions.
    #[test]
    fn centroid_on_the_grid_equals_the_trapezoid_centroid() {
        use rand_chacha::ChaCha8Rng;
        use rand_chacha::rand_core::{Rng, SeedableRng};
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut uniform = move || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        for case in 0..300 {
            let m = [2, 3, 7, 101, 201][case % 5];
            let (lo, hi) = (-3.0 + uniform(), 1.0 + 4.0 * uniform());
            let x: Vec<f64> = (0..m).map(|j| lo + (hi - lo) * j as f64 / (m - 1) as f64).collect();
            let (a, b) = ((uniform() * m as f64) as usize % m, (uniform() * m as f64) as usize % m);
            let range = match case % 3 {
                0 => 0..m,
                1 => 0..a.max(1),
                _ => a.min(b)..a.max(b) + 1,
            };
            let mut mu = vec![0.0; m];
            for j in range.clone() {
                mu[j] = uniform();
            }
            let want = defuzzify(&x, &mu, Defuzzification::Centroid);
            let got = centroid_on_grid(&mu, range.clone(), lo, hi);
            match (want, got) {
                (Some(w), Some(g)) => assert!((w - g).abs() < 1e-12 * (hi - lo), "case {case}, {range:?}: {g} vs {w}"),
                (w, g) => assert_eq!(w.is_some(), g.is_some(), "case {case}"),
            }
        }
    }

    /// The closed-form centroid of a triangular partition's aggregate equals the
    /// centroid of the aggregate sampled point by point (`Mf::eval` on the
    /// grid, then `centroid_on_grid`) to 1e-12 of the universe: uneven peaks,
    /// universes inside the outer peaks or up to them, resolutions from 2 to
    /// 1001, any set of firing terms with strengths at 0, ½, 1 and below 1e-9
    /// among them (or all of them below 1e-9), for each method pair it covers.
    #[test]
    fn closed_form_centroid_equals_the_sampled_one() {
        use rand_chacha::ChaCha8Rng;
        use rand_chacha::rand_core::{Rng, SeedableRng};
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let mut uniform = move || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        let methods = [
            (Implication::Min, Aggregation::Max),
            (Implication::Product, Aggregation::Max),
            (Implication::Product, Aggregation::Sum),
        ];
        let mut worst: f64 = 0.0;
        for case in 0..3000 {
            let n = [2, 3, 5, 7, 9][case % 5];
            let m = [2, 3, 7, 101, 201, 1001][case / 5 % 6];
            let (imp, agg) = methods[case / 30 % 3];
            let mut peaks: Vec<f64> = (0..n).map(|_| 10.0 * uniform() - 5.0).collect();
            peaks.sort_by(f64::total_cmp);
            let (lo, hi) = match case % 4 {
                0 => (peaks[0], peaks[n - 1]),
                // Up to half way into the outer cells (so that lo < hi with two terms).
                _ => {
                    let mut inset = |a: f64, b: f64| 0.49 * (b - a) * uniform();
                    (peaks[0] + inset(peaks[0], peaks[1]), peaks[n - 1] - inset(peaks[n - 2], peaks[n - 1]))
                }
            };
            let terms = (0..n)
                .map(|k| (format!("T{k}"), Mf::Tri(peaks[k.saturating_sub(1)], peaks[k], peaks[(k + 1).min(n - 1)])))
                .collect();
            let v = Variable { name: "y".into(), lo, hi, terms };
            let exact = PartitionCentroid::new(&v, m, imp, agg).expect("a partition");
            // One case in seven all small: the sums must scale with them.
            let scale = if case % 7 == 3 { 1e-9 } else { 1.0 };
            let strength: Vec<f64> = (0..n)
                .map(|_| {
                    scale
                        * match (uniform() * 7.0) as usize {
                            0 | 1 => 0.0,
                            2 => 1.0,
                            3 => 0.5,
                            // Memberships this small come from inputs just off a peak.
                            4 => 1e-9 * uniform(),
                            _ => uniform() * if agg == Aggregation::Sum { 2.0 } else { 1.0 },
                        }
                })
                .collect();
            let x = |j: usize| if j == m - 1 { hi } else { lo + (hi - lo) * j as f64 / (m - 1) as f64 };
            let mu: Vec<f64> = (0..m)
                .map(|j| {
                    let implied = v.terms.iter().zip(&strength).map(|((_, mf), &w)| match imp {
                        Implication::Min => w.min(mf.eval(x(j))),
                        Implication::Product => w * mf.eval(x(j)),
                    });
                    match agg {
                        Aggregation::Max => implied.fold(0.0, f64::max),
                        Aggregation::Sum => implied.sum(),
                    }
                })
                .collect();
            let (want, got) = (centroid_on_grid(&mu, 0..m, lo, hi), exact.centroid(&strength));
            match (want, got) {
                (Some(w), Some(g)) => {
                    worst = worst.max((w - g).abs() / (hi - lo));
                    assert!((w - g).abs() < 1e-12 * (hi - lo), "case {case} {imp:?}/{agg:?} {strength:?}: {g} vs {w}");
                }
                (w, g) => assert_eq!(w.is_some(), g.is_some(), "case {case}: {strength:?}, {mu:?}"),
            }
        }
        assert!(worst > 0.0 && worst < 1e-13, "largest difference {worst:e} of the universe");
    }
}
