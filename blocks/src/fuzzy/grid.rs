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

use super::fis::{AndMethod, Connective, Rule, Variable};
use super::partition::Partition;

/// The rule table over the inputs' partitions.
#[derive(Clone, Debug)]
pub struct RuleGrid {
    partitions: Vec<Partition>,
    /// Cell of term indices (k_0, k_1, …) at Σ k_i·stride_i; its rules are
    /// rules[cells[c]..cells[c + 1]].
    strides: Vec<usize>,
    cells: Vec<usize>,
    rules: Vec<usize>,
    product: bool,
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
        for ((l, p), &xi) in self.located.iter_mut().zip(&self.partitions).zip(x) {
            *l = p.locate(xi);
        }
        let mut n = 0;
        let mut take = |cell: usize, strength: f64| {
            for &r in &self.rules[self.cells[cell]..self.cells[cell + 1]] {
                // Written always; the count moves only for nonzero strength.
                fired[n] = (r, strength);
                n += usize::from(strength > 0.0);
            }
        };
        // Two inputs (the common controller): the four corners written out,
        // in the general loop's order and with its arithmetic.
        if let ([(k0, a0, b0), (k1, a1, b1)], [s0, s1]) = (&self.located[..], &self.strides[..]) {
            let and = |u: f64, v: f64| if self.product { u * v } else { u.min(v) };
            take(k0 * s0 + k1 * s1, and(*a0, *a1));
            take((k0 + 1) * s0 + k1 * s1, and(*b0, *a1));
            take(k0 * s0 + (k1 + 1) * s1, and(*a0, *b1));
            take((k0 + 1) * s0 + (k1 + 1) * s1, and(*b0, *b1));
            return n;
        }
        for corner in 0..1usize << self.located.len() {
            let (mut cell, mut strength) = (0, if self.product { 1.0 } else { f64::INFINITY });
            for (i, &(k, at_k, at_next)) in self.located.iter().enumerate() {
                let up = corner >> i & 1;
                let mu = if up == 1 { at_next } else { at_k };
                cell += (k + up) * self.strides[i];
                strength = if self.product { strength * mu } else { strength.min(mu) };
            }
            take(cell, strength);
        }
        n
    }
}
