//! The common shape of a fuzzy controller, evaluated without visiting every
//! membership: each input's terms a triangular partition (term k rises from
//! peak k−1 to peak k and falls to peak k+1, the end ones half triangles),
//! and the rules a table: each an AND of one plain term per input.
//!
//! An input inside a partition lies between two neighbouring peaks, so only
//! those two terms can be nonzero, and which they are is arithmetic (no
//! comparison per term); with n inputs only the 2ⁿ cells of the table at
//! those terms can fire. The memberships are computed with the same
//! expressions as `Mf::eval`, so the fired strengths are the general
//! path's to the bit.

use super::fis::{AndMethod, Connective, Rule, conclude};
use super::partition::Partition;
use super::terms::Variable;

/// The rule table over the inputs' partitions.
#[derive(Clone, Debug)]
pub struct RuleGrid {
    pub(super) partitions: Vec<Partition>,
    /// Cell of term indices (k_0, k_1, …) at Σ k_i·stride_i; its rules are
    /// rules[cells[c]..cells[c + 1]].
    pub(super) strides: Vec<usize>,
    pub(super) cells: Vec<usize>,
    pub(super) rules: Vec<usize>,
    pub(super) product: bool,
    /// Per input, the located term and its two memberships (work buffer).
    located: Vec<(usize, f64, f64)>,
}

impl RuleGrid {
    /// `None` unless there are inputs, every input is a partition and every
    /// rule an AND of one plain term of each input (and the table has at
    /// most 2¹⁶ cells).
    pub fn new(inputs: &[Variable], rules: &[Rule], and: AndMethod) -> Option<Self> {
        if inputs.is_empty() {
            return None;
        }
        let partitions = inputs.iter().map(Partition::of).collect::<Option<Vec<_>>>()?;
        let mut strides = Vec::with_capacity(inputs.len());
        let mut size = 1usize;
        for v in inputs {
            strides.push(size);
            size = size.checked_mul(v.terms.len()).filter(|&s| s <= 1 << 16)?;
        }
        let mut by_cell: Vec<Vec<usize>> = vec![Vec::new(); size];
        for (r, rule) in rules.iter().enumerate() {
            let mut seen = vec![false; inputs.len()];
            let mut cell = 0;
            for &(i, k, negated) in &rule.antecedents {
                if negated || seen[i] || rule.connective != Connective::And {
                    return None;
                }
                seen[i] = true;
                cell += k * strides[i];
            }
            if seen.contains(&false) {
                return None;
            }
            by_cell[cell].push(r);
        }
        let mut cells = vec![0];
        for c in &by_cell {
            cells.push(cells[cells.len() - 1] + c.len());
        }
        let located = vec![(0, 0.0, 0.0); inputs.len()];
        let rules = by_cell.concat();
        Some(RuleGrid { partitions, strides, cells, rules, product: and == AndMethod::Product, located })
    }

    /// Writes (rule, strength) of the rules in the 2ⁿ cells around `x`
    /// (clipped to the universes already) to `fired` and returns how many
    /// have nonzero strength — those come first.
    pub fn fire(&mut self, x: &[f64], fired: &mut [(usize, f64)]) -> usize {
        let mut n = 0;
        let (cells, rules) = (&self.cells, &self.rules);
        Self::corners(&mut self.located, &self.partitions, &self.strides, self.product, x, |cell, strength| {
            for &r in &rules[cells[cell]..cells[cell + 1]] {
                // Written always; the count moves only for nonzero strength.
                fired[n] = (r, strength);
                n += usize::from(strength > 0.0);
            }
        });
        n
    }

    /// What `fire` and then gathering the fired rules' conclusions by term
    /// give, without the list of fired rules: each corner cell's strength
    /// goes straight to the terms its rules conclude, `conclusions[c]` for
    /// cell c (flat term indices, in rule order), strongest or summed.
    /// Rules of zero strength change nothing (w ≥ 0: max(w, 0) = w + 0 = w).
    pub fn fire_into_terms(&mut self, x: &[f64], conclusions: &TermsByCell, sum: bool, strength: &mut [f64]) {
        Self::corners(&mut self.located, &self.partitions, &self.strides, self.product, x, |cell, s| {
            let (from, to) = conclusions.cells[cell];
            for &t in &conclusions.terms[from..to] {
                conclude(&mut strength[t], s, sum);
            }
        });
    }

    /// The rules' conclusions as term indices, by cell (see `fire_into_terms`).
    pub fn terms_by_cell(&self, conclusions_of: impl Fn(usize) -> Vec<usize>) -> TermsByCell {
        let mut by = TermsByCell { cells: Vec::new(), terms: Vec::new() };
        for c in 0..self.cells.len() - 1 {
            let from = by.terms.len();
            for &r in &self.rules[self.cells[c]..self.cells[c + 1]] {
                by.terms.extend(conclusions_of(r));
            }
            by.cells.push((from, by.terms.len()));
        }
        by
    }

    /// Calls `visit(cell, strength)` for the 2ⁿ cells around `x`, in the
    /// order of the corners' bits (input 0 the lowest).
    fn corners(
        located: &mut [(usize, f64, f64)],
        partitions: &[Partition],
        strides: &[usize],
        product: bool,
        x: &[f64],
        mut visit: impl FnMut(usize, f64),
    ) {
        // Two inputs (the common controller): the four corners written out,
        // in the general loop's order and with its arithmetic.
        if let ([p0, p1], [s0, s1], [x0, x1]) = (partitions, strides, x) {
            let ((k0, a0, b0), (k1, a1, b1)) = (p0.locate(*x0), p1.locate(*x1));
            // A plain comparison: memberships are never NaN.
            let and = |u: f64, v: f64| {
                if product {
                    u * v
                } else if u < v {
                    u
                } else {
                    v
                }
            };
            visit(k0 * s0 + k1 * s1, and(a0, a1));
            visit((k0 + 1) * s0 + k1 * s1, and(b0, a1));
            visit(k0 * s0 + (k1 + 1) * s1, and(a0, b1));
            visit((k0 + 1) * s0 + (k1 + 1) * s1, and(b0, b1));
            return;
        }
        for ((l, p), &xi) in located.iter_mut().zip(partitions).zip(x) {
            *l = p.locate(xi);
        }
        for corner in 0..1usize << located.len() {
            let (mut cell, mut strength) = (0, if product { 1.0 } else { f64::INFINITY });
            for (i, &(k, at_k, at_next)) in located.iter().enumerate() {
                let up = corner >> i & 1;
                let mu = if up == 1 { at_next } else { at_k };
                cell += (k + up) * strides[i];
                strength = if product { strength * mu } else { strength.min(mu) };
            }
            visit(cell, strength);
        }
    }
}

/// Per cell of a rule table, the term indices its rules conclude:
/// `terms[from..to]` for the cell's (from, to).
#[derive(Clone, Debug)]
pub struct TermsByCell {
    pub(super) cells: Vec<(usize, usize)>,
    pub(super) terms: Vec<usize>,
}
