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
use super::partition::Partition;
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
    let sums = Sums { s0: sum, s1: from * sum + moment, first: first_value, last: last_value };
    sums.centroid(lo, hi, last as f64)
}

/// S0 = Σ μ_j, S1 = Σ j·μ_j and the end samples μ_0, μ_L.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    s0: f64,
    s1: f64,
    first: f64,
    last: f64,
}

impl Sums {
    /// Adds μ_j = μ_a + δ·(j − a) for j = a … b − 1 (a < b, whole
    /// numbers), and notes the end samples when the run reaches them (L =
    /// `last`).
    fn add(&mut self, a: f64, b: f64, at_a: f64, per_point: f64, last: f64) {
        let n = b - a;
        // Σ i and Σ i² over i = 0 … n − 1: exact (whole numbers below 2⁵³,
        // divisions without remainder) up to n ≈ 200 000, beyond the
        // block's 100 000 points; past that, rounded to 1e-16.
        let t1 = 0.5 * n * (n - 1.0);
        let t2 = t1 * (2.0 * n - 1.0) / 3.0;
        let sum = n * at_a + per_point * t1;
        self.s0 += sum;
        self.s1 += a * sum + at_a * t1 + per_point * t2;
        if a == 0.0 {
            self.first = at_a;
        }
        if b == last + 1.0 {
            self.last = at_a + per_point * (n - 1.0);
        }
    }

    /// The formula of the module's doc; `None` when the area is zero.
    fn centroid(&self, lo: f64, hi: f64, last: f64) -> Option<f64> {
        let moment = self.s1 + self.first / 6.0 - self.last * (last / 2.0 + 1.0 / 6.0);
        let area = self.s0 - 0.5 * (self.first + self.last);
        (area > 0.0).then(|| lo + (hi - lo) / last * moment / area)
    }
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
/// part cross (max aggregation). On a piece μ_j = μ_a + δ·(j − a) for the
/// grid points j = a … b − 1 it covers, so its contributions to S0 and S1
/// are sums of i and i² over 0 … n − 1, n = b − a: a handful of operations
/// per piece instead of a pass over the grid per term. The result equals the
/// sampled one up to rounding (the grid's samples are the same linear
/// functions evaluated point by point; tested to 1e-12 of the universe).
#[derive(Clone, Debug)]
pub(super) struct PartitionCentroid {
    /// Per pair of neighbouring peaks, the cell between them.
    cells: Vec<Cell>,
    /// Index L of the last grid point.
    last: f64,
    lo: f64,
    hi: f64,
    implication: Implication,
    aggregation: Aggregation,
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
                ceil(at(p)).min(last)
            }
        };
        let cells = peaks
            .windows(2)
            .map(|p| Cell {
                at: at(p[0]),
                span: at(p[1]) - at(p[0]),
                per_point: 1.0 / (at(p[1]) - at(p[0])),
                first: first(p[0]),
                end: first(p[1]),
            })
            .collect();
        Some(PartitionCentroid { cells, last, lo: v.lo, hi: v.hi, implication, aggregation })
    }

    /// The centroid of the aggregate of the terms at `strength` (one per
    /// term); `None` when it is zero everywhere.
    pub(super) fn centroid(&self, strength: &[f64]) -> Option<f64> {
        let mut sums = Sums::default();
        for (cell, w) in self.cells.iter().zip(strength.windows(2)) {
            if w[0] > 0.0 || w[1] > 0.0 {
                self.add_cell(cell, w[0], w[1], &mut sums);
            }
        }
        sums.centroid(self.lo, self.hi, self.last)
    }

    /// Adds the grid points of `cell`, where its falling and rising terms
    /// have strengths `wa` and `wb`.
    fn add_cell(&self, cell: &Cell, wa: f64, wb: f64, sums: &mut Sums) {
        let Cell { at, span, per_point, first, end } = *cell;
        if first >= end {
            return;
        }
        // s = (j − at)/span: a piece up to s = `to` covers the grid points
        // from the last piece's end to the first at or after `to`.
        let mut from = first;
        for (to, c0, c1) in self.pieces(wa, wb) {
            let b = if to < 1.0 { ceil(at + to * span).clamp(from, end) } else { end };
            if b > from {
                sums.add(from, b, c0 + c1 * (from - at) * per_point, c1 * per_point, self.last);
            }
            from = b;
        }
    }

    /// μ on the cell as pieces μ = c0 + c1·s, each up to s = `to`, in order
    /// (some may be empty).
    ///
    /// Min/max: f = min(w_a, 1 − s) is w_a up to 1 − w_a, then 1 − s; g =
    /// min(w_b, s) is s up to w_b, then w_b. f falls and g rises, so μ is f
    /// up to their crossing s* and g after it: w_a, then 1 − s from 1 − w_a
    /// to s*, then s from s* to w_b, then w_b.
    fn pieces(&self, wa: f64, wb: f64) -> [(f64, f64, f64); 4] {
        const EMPTY: (f64, f64, f64) = (1.0, 0.0, 0.0);
        match (self.implication, self.aggregation) {
            // (Min with sum aggregation never gets here: see `new`.)
            (Implication::Min, _) => {
                let crossing = self.crossing(wa, wb);
                [
                    (if 1.0 - wa < crossing { 1.0 - wa } else { crossing }, wa, 0.0),
                    (crossing, 1.0, -1.0),
                    (if wb > crossing { wb } else { crossing }, 0.0, 1.0),
                    (1.0, wb, 0.0),
                ]
            }
            (Implication::Product, Aggregation::Max) => {
                [(self.crossing(wa, wb), wa, -wa), (1.0, 0.0, wb), EMPTY, EMPTY]
            }
            (Implication::Product, Aggregation::Sum) => [(1.0, wa, wb - wa), EMPTY, EMPTY, EMPTY],
        }
    }

    /// Where the falling part (term k) meets the rising part (term k+1):
    /// min(w_a, 1 − s) = min(w_b, s) (at value min(w_a, w_b, ½)), or
    /// w_a·(1 − s) = w_b·s.
    fn crossing(&self, wa: f64, wb: f64) -> f64 {
        match self.implication {
            Implication::Min if wa <= wb && wa <= 0.5 => wa,
            Implication::Min if wb <= wa && wb <= 0.5 => 1.0 - wb,
            Implication::Min => 0.5,
            Implication::Product => wa / (wa + wb),
        }
    }
}

/// The grid points between two neighbouring peaks p and q: s = (j − at)/span
/// on the grid's index axis, with at = (p − lo)/dx and span = (q − p)/dx;
/// the first grid point at or after p and the first at or after q (0
/// before lo, L + 1 past hi). Edges are found once, so neighbouring cells
/// and pieces agree on which grid points are whose.
#[derive(Clone, Copy, Debug)]
struct Cell {
    at: f64,
    span: f64,
    /// 1/span: how much s moves per grid point.
    per_point: f64,
    first: f64,
    end: f64,
}

/// The smallest whole number at or above `v`, in f64 arithmetic: adding
/// and taking away 1.5·2⁵² leaves the nearest whole number (there the
/// doubles are one apart), one more if that is below `v`. Exact for
/// |v| < 2⁵¹; the callers clamp the result to the grid's indices (at most
/// 100 001), so a position far outside them lands on the same index.
/// Why not `f64::ceil`: on baseline x86-64 (no SSE4.1) it is a libm call
/// that costs more than the rest of a piece, and converting to an integer
/// and back is several instructions (Rust's `as` saturates); so the grid
/// indices here are whole numbers held in f64.
fn ceil(v: f64) -> f64 {
    const ROUND: f64 = 6_755_399_441_055_744.0;
    let nearest = (v + ROUND) - ROUND;
    if nearest < v { nearest + 1.0 } else { nearest }
}

#[cfg(test)]
mod tests {
    use super::ceil;

    /// The f64 ceiling agrees with libm's on whole numbers, just either
    /// side of them, negative grid positions and the largest grids.
    #[test]
    fn ceil_in_f64_arithmetic_is_the_ceiling() {
        let mut cases = vec![0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 1e-300, -1e-300, 200_000.0, 2f64.powi(50) - 0.5];
        for k in [-3.0f64, 0.0, 1.0, 7.0, 100.0, 100_000.0] {
            cases.extend([k, k.next_up(), k.next_down(), k + 0.25, k - 0.75]);
        }
        for v in cases {
            assert_eq!(ceil(v), v.ceil(), "ceil({v:e})");
        }
    }
}
