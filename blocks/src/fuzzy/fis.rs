//! The fuzzy inference engine: rules, Mamdani and zero-order Sugeno
//! inference over the variables of `terms`. Everything that does not
//! depend on the inputs (output membership values on the sampled universe)
//! is computed once; `eval` writes into preallocated buffers and allocates
//! nothing.

use super::centroid::{PartitionCentroid, centroid_on_grid};
use super::grid::{RuleGrid, TermsByCell};
pub use super::terms::{Mf, Variable, standard_names, uniform_triangles};
use std::ops::Range;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Connective {
    And,
    Or,
}

/// `if (in is term) and/or … then (out is term) …`.
#[derive(Clone, Debug, PartialEq)]
pub struct Rule {
    /// (input index, term index, negated)
    pub antecedents: Vec<(usize, usize, bool)>,
    pub connective: Connective,
    /// (output index, term index)
    pub consequents: Vec<(usize, usize)>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AndMethod {
    Min,
    Product,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OrMethod {
    Max,
    /// Probabilistic sum a + b − ab.
    ProbOr,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Implication {
    Min,
    Product,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Aggregation {
    Max,
    Sum,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Defuzzification {
    Centroid,
    Bisector,
    MeanOfMaximum,
    SmallestOfMaximum,
    LargestOfMaximum,
}

/// Inference settings (MATLAB's defaults: min, max, min, max, centroid).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Methods {
    pub and: AndMethod,
    pub or: OrMethod,
    pub implication: Implication,
    pub aggregation: Aggregation,
    pub defuzzification: Defuzzification,
    /// Points on each output universe (Mamdani).
    pub resolution: usize,
}

impl Methods {
    /// Whether the implied sets depend on the rules only through their
    /// terms' strengths: all but sum aggregation of min implication.
    pub(super) fn by_term(&self) -> bool {
        !(self.aggregation == Aggregation::Sum && self.implication == Implication::Min)
    }
}

impl Default for Methods {
    fn default() -> Self {
        Methods {
            and: AndMethod::Min,
            or: OrMethod::Max,
            implication: Implication::Min,
            aggregation: Aggregation::Max,
            defuzzification: Defuzzification::Centroid,
            resolution: 201,
        }
    }
}

/// A compiled fuzzy inference system.
#[derive(Clone, Debug)]
pub struct Fis {
    pub inputs: Vec<Variable>,
    pub outputs: Vec<Variable>,
    pub rules: Vec<Rule>,
    pub methods: Methods,
    pub sugeno: bool,
    /// Per output: the sampled universe, each term's membership on it and
    /// the index range where that is nonzero.
    grids: Vec<Vec<f64>>,
    term_grids: Vec<Vec<Vec<f64>>>,
    supports: Vec<Vec<Range<usize>>>,
    /// Per output: its centroid in closed form, when its terms are a
    /// triangular partition and the methods allow (see `centroid`).
    pub(super) exact: Vec<Option<PartitionCentroid>>,
    /// Where each input's term memberships start in `membership`.
    offsets: Vec<usize>,
    /// Rules that fire only when one given membership is nonzero (an AND
    /// of plain antecedents: any zero makes the product or minimum zero),
    /// by that membership's index; and the rules always evaluated.
    sparse: Vec<Vec<usize>>,
    dense: Vec<usize>,
    /// When the inputs are triangular partitions and the rules a table:
    /// the rules that can fire found by arithmetic (see `grid`).
    pub(super) grid: Option<RuleGrid>,
    /// With the table, when outputs need only their terms' strengths: each
    /// cell's conclusions as indices into `term_strength`.
    pub(super) grid_terms: Option<TermsByCell>,
    // Work buffers.
    membership: Vec<f64>,
    clipped: Vec<f64>,
    /// (rule, strength) of the rules with nonzero strength this call: the
    /// first `n_fired` entries.
    fired: Vec<(usize, f64)>,
    n_fired: usize,
    /// Per output term (output o's from `term_offsets[o]`), the strength of
    /// its conclusion this call: the strongest (max aggregation) or the sum
    /// (sum) of the fired rules' concluding it — the one pass over the fired
    /// rules that all outputs share. Each rule's conclusions as indices into
    /// it: `conclusions[conclusion_ranges[r]]`.
    term_strength: Vec<f64>,
    pub(super) term_offsets: Vec<usize>,
    pub(super) conclusions: Vec<usize>,
    pub(super) conclusion_ranges: Vec<Range<usize>>,
    /// Zero between calls (each call clears the range it wrote).
    aggregate: Vec<f64>,
}

impl Fis {
    pub fn new(
        inputs: Vec<Variable>,
        outputs: Vec<Variable>,
        rules: Vec<Rule>,
        methods: Methods,
        sugeno: bool,
    ) -> Self {
        let m = methods.resolution.max(2);
        // The last point is the upper edge itself, as numpy's linspace makes
        // it: lo + (hi − lo)·1 can land an ulp past hi, outside a right
        // shoulder term (Tri(a, hi, hi) is 0 beyond hi).
        let point =
            |v: &Variable, j: usize| if j == m - 1 { v.hi } else { v.lo + (v.hi - v.lo) * j as f64 / (m - 1) as f64 };
        let grids: Vec<Vec<f64>> = outputs.iter().map(|v| (0..m).map(|j| point(v, j)).collect()).collect();
        let term_grids: Vec<Vec<Vec<f64>>> = outputs
            .iter()
            .zip(&grids)
            .map(|(v, g)| v.terms.iter().map(|(_, mf)| g.iter().map(|&x| mf.eval(x)).collect()).collect())
            .collect();
        let supports =
            term_grids.iter().map(|terms: &Vec<Vec<f64>>| terms.iter().map(|mu| support(mu)).collect()).collect();
        let offsets: Vec<usize> = inputs
            .iter()
            .scan(0, |next, v| {
                let at = *next;
                *next += v.terms.len();
                Some(at)
            })
            .collect();
        let n_memberships = inputs.iter().map(|v| v.terms.len()).sum();
        let (mut sparse, mut dense) = (vec![Vec::new(); n_memberships], Vec::new());
        for (r, rule) in rules.iter().enumerate() {
            let key = rule.antecedents.iter().find(|a| !a.2).filter(|_| rule.connective == Connective::And);
            match key {
                Some(&(i, k, _)) => sparse[offsets[i] + k].push(r),
                None => dense.push(r),
            }
        }
        let term_offsets: Vec<usize> = std::iter::once(0)
            .chain(outputs.iter().scan(0, |next, v| {
                *next += v.terms.len();
                Some(*next)
            }))
            .collect();
        let (mut conclusions, mut conclusion_ranges) = (Vec::new(), Vec::with_capacity(rules.len()));
        for rule in &rules {
            let start = conclusions.len();
            conclusions.extend(rule.consequents.iter().map(|&(o, t)| term_offsets[o] + t));
            conclusion_ranges.push(start..conclusions.len());
        }
        let closed_form = !sugeno && methods.defuzzification == Defuzzification::Centroid;
        let exact = outputs
            .iter()
            .map(|v| PartitionCentroid::new(v, m, methods.implication, methods.aggregation).filter(|_| closed_form))
            .collect();
        let grid = RuleGrid::new(&inputs, &rules, methods.and);
        let by_term = !sugeno && methods.by_term();
        let grid_terms = grid
            .as_ref()
            .filter(|_| by_term)
            .map(|g| g.terms_by_cell(|r| conclusions[conclusion_ranges[r].clone()].to_vec()));
        Fis {
            grid,
            grid_terms,
            exact,
            clipped: vec![0.0; inputs.len()],
            membership: vec![0.0; n_memberships],
            fired: vec![(0, 0.0); rules.len()],
            n_fired: 0,
            term_strength: vec![0.0; term_offsets[outputs.len()]],
            term_offsets,
            conclusions,
            conclusion_ranges,
            aggregate: vec![0.0; m],
            offsets,
            sparse,
            dense,
            inputs,
            outputs,
            rules,
            methods,
            sugeno,
            grids,
            term_grids,
            supports,
        }
    }

    /// The same system with the rule table's shortcut off (the reference
    /// it is tested against).
    #[cfg(test)]
    pub(super) fn without_rule_grid(mut self) -> Self {
        self.grid = None;
        self
    }

    /// The same system with every output aggregated on its grid (the
    /// reference the closed-form centroid is tested against).
    #[cfg(test)]
    pub(super) fn on_the_grid(mut self) -> Self {
        self.exact.iter_mut().for_each(|e| *e = None);
        self
    }

    /// Whether output `o`'s centroid is computed in closed form (see `centroid`).
    pub fn has_exact_centroid(&self, o: usize) -> bool {
        self.exact.get(o).is_some_and(Option::is_some)
    }

    /// Whether the rules that fire are found from a table (see `grid`).
    pub fn uses_rule_grid(&self) -> bool {
        self.grid.is_some()
    }

    /// Evaluates the system: inputs are clipped to their universes.
    pub fn eval(&mut self, x: &[f64], y: &mut [f64]) {
        for (c, (v, &xi)) in self.clipped.iter_mut().zip(self.inputs.iter().zip(x)) {
            *c = xi.clamp(v.lo, v.hi);
        }
        let by_term = !self.sugeno && self.methods.by_term();
        if by_term {
            self.term_strength.iter_mut().for_each(|w| *w = 0.0);
        }
        if let (Some(grid), Some(terms)) = (&mut self.grid, &self.grid_terms) {
            let sum = self.methods.aggregation == Aggregation::Sum;
            grid.fire_into_terms(&self.clipped, terms, sum, &mut self.term_strength);
            self.n_fired = 0;
        } else {
            self.n_fired = match &mut self.grid {
                Some(grid) => grid.fire(&self.clipped, &mut self.fired),
                None => self.fire_by_memberships(),
            };
            if by_term {
                self.gather_term_strengths();
            }
        }
        for (o, yo) in y.iter_mut().enumerate().take(self.outputs.len()) {
            *yo = match (&self.exact[o], by_term) {
                // The closed-form centroid from the term strengths.
                (Some(exact), true) => {
                    let strength = &self.term_strength[self.term_offsets[o]..self.term_offsets[o + 1]];
                    exact.centroid(strength).unwrap_or(exact.midpoint())
                }
                _ if self.sugeno => self.sugeno_output(o),
                _ => self.mamdani_output(o),
            };
        }
    }

    /// `term_strength` (zeroed) from the fired rules.
    fn gather_term_strengths(&mut self) {
        let sum = self.methods.aggregation == Aggregation::Sum;
        for &(r, s) in &self.fired[..self.n_fired] {
            for &t in &self.conclusions[self.conclusion_ranges[r].clone()] {
                conclude(&mut self.term_strength[t], s, sum);
            }
        }
    }

    /// Computes every membership, then the strengths of the rules that can
    /// fire given which are nonzero; returns how many fired (first in
    /// `fired`).
    fn fire_by_memberships(&mut self) -> usize {
        for (i, v) in self.inputs.iter().enumerate() {
            for (k, (_, mf)) in v.terms.iter().enumerate() {
                self.membership[self.offsets[i] + k] = mf.eval(self.clipped[i]);
            }
        }
        // Which rules fire follows no pattern a branch predictor could
        // learn: every candidate is written, and the count moves only for
        // those with nonzero strength.
        let mut n = 0;
        let candidates = self.membership.iter().zip(&self.sparse).filter(|&(&m, _)| m > 0.0).flat_map(|(_, r)| r);
        for &r in candidates.chain(&self.dense) {
            let s = self.strength(&self.rules[r]);
            self.fired[n] = (r, s);
            n += usize::from(s > 0.0);
        }
        n
    }

    /// The firing strength of `rule` at the current memberships.
    fn strength(&self, rule: &Rule) -> f64 {
        let mu = |&(i, k, negated): &(usize, usize, bool)| {
            let m = self.membership[self.offsets[i] + k];
            if negated { 1.0 - m } else { m }
        };
        let mut terms = rule.antecedents.iter().map(mu);
        let first = terms.next().unwrap_or(0.0);
        match (rule.connective, self.methods.and, self.methods.or) {
            (Connective::And, AndMethod::Min, _) => terms.fold(first, f64::min),
            (Connective::And, AndMethod::Product, _) => terms.fold(first, |a, m| a * m),
            (Connective::Or, _, OrMethod::Max) => terms.fold(first, f64::max),
            (Connective::Or, _, OrMethod::ProbOr) => terms.fold(first, |a, m| a + m - a * m),
        }
    }

    /// The (term, strength) conclusions of the fired rules on output `o`
    /// (terms numbered within the output).
    fn conclusions(&self, o: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let Fis { fired, n_fired, conclusions, conclusion_ranges, term_offsets, .. } = self;
        concluding(&fired[..*n_fired], conclusions, conclusion_ranges, term_offsets[o]..term_offsets[o + 1])
    }

    /// Weighted average of the consequents' constants.
    fn sugeno_output(&self, o: usize) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for (term, s) in self.conclusions(o) {
            let z = match self.outputs[o].terms[term].1 {
                Mf::Const(z) => z,
                _ => 0.0,
            };
            num += s * z;
            den += s;
        }
        if den > 0.0 { num / den } else { (self.outputs[o].lo + self.outputs[o].hi) / 2.0 }
    }

    /// Aggregates the implied output sets on the grid, then defuzzifies.
    /// Per term T, max_r imp(w_r, μ_T) = imp(max_r w_r, μ_T) over the rules
    /// concluding T (implication is monotone) and Σ_r w_r·μ_T = (Σ_r w_r)·μ_T,
    /// so the grid is visited once per firing term, not once per rule; only
    /// sum aggregation of min implication needs the rules one by one. (When
    /// the output's terms are a triangular partition, `eval` takes the
    /// centroid in closed form from the term strengths instead: `centroid`.)
    fn mamdani_output(&mut self, o: usize) -> f64 {
        let by_term = self.methods.by_term();
        let midpoint = (self.outputs[o].lo + self.outputs[o].hi) / 2.0;
        let Fis {
            fired,
            n_fired,
            conclusions,
            conclusion_ranges,
            term_offsets,
            term_strength,
            aggregate,
            term_grids,
            supports,
            methods,
            outputs,
            grids,
            ..
        } = self;
        let (terms, supports, fired) = (&term_grids[o], &supports[o], &fired[..*n_fired]);
        let output_terms = term_offsets[o]..term_offsets[o + 1];
        let strength = &term_strength[output_terms.clone()];
        let (imp, agg) = (methods.implication, methods.aggregation);
        let v = &outputs[o];
        // The implied sets are zero outside their term's support: only the
        // union of the firing terms' supports is written and read.
        let (mut from, mut to) = (usize::MAX, 0);
        let mut apply = |t: usize, w: f64| {
            let s = supports[t].clone();
            (from, to) = (from.min(s.start), to.max(s.end));
            imply_and_aggregate(&mut aggregate[s.clone()], &terms[t][s], w, imp, agg);
        };
        if by_term {
            for (t, &w) in strength.iter().enumerate() {
                if w > 0.0 {
                    apply(t, w);
                }
            }
        } else {
            for (t, s) in concluding(fired, conclusions, conclusion_ranges, output_terms) {
                apply(t, s);
            }
        }
        if from >= to {
            return midpoint;
        }
        let touched = from..to;
        let y = if methods.defuzzification == Defuzzification::Centroid {
            centroid_on_grid(aggregate, touched.clone(), v.lo, v.hi).unwrap_or(midpoint)
        } else {
            defuzzify(&grids[o], aggregate, methods.defuzzification).unwrap_or(midpoint)
        };
        aggregate[touched].iter_mut().for_each(|a| *a = 0.0);
        y
    }
}

/// The (term within the output, strength) conclusions of the `fired`
/// rules on the output whose terms are `terms` in the flat numbering of
/// `conclusions` (rule r's are `conclusions[ranges[r]]`).
fn concluding<'a>(
    fired: &'a [(usize, f64)],
    conclusions: &'a [usize],
    ranges: &'a [Range<usize>],
    terms: Range<usize>,
) -> impl Iterator<Item = (usize, f64)> + 'a {
    let (first, end) = (terms.start, terms.end);
    fired.iter().flat_map(move |&(r, s)| {
        let of_rule = conclusions[ranges[r].clone()].iter();
        of_rule.filter(move |&&t| first <= t && t < end).map(move |&t| (t - first, s))
    })
}

/// A term's strength `w` after a rule of strength `s` concludes it: the
/// sum or the larger (a plain comparison: strengths are finite).
#[inline]
pub(super) fn conclude(w: &mut f64, s: f64, sum: bool) {
    *w = if sum {
        *w + s
    } else if s > *w {
        s
    } else {
        *w
    };
}

/// The index range outside which `mu` is zero (empty when it is zero
/// everywhere).
fn support(mu: &[f64]) -> Range<usize> {
    match (mu.iter().position(|&m| m != 0.0), mu.iter().rposition(|&m| m != 0.0)) {
        (Some(first), Some(last)) => first..last + 1,
        _ => 0..0,
    }
}

/// `aggregate ← agg(aggregate, imp(w, μ))` pointwise, written with plain
/// comparisons (no NaN handling: memberships are finite) so the loop
/// compiles to packed min/max.
fn imply_and_aggregate(aggregate: &mut [f64], mu: &[f64], w: f64, imp: Implication, agg: Aggregation) {
    let pairs = aggregate.iter_mut().zip(mu);
    match (imp, agg) {
        (Implication::Min, Aggregation::Max) => pairs.for_each(|(a, &m)| {
            let v = if w < m { w } else { m };
            *a = if v > *a { v } else { *a };
        }),
        (Implication::Product, Aggregation::Max) => pairs.for_each(|(a, &m)| {
            let v = w * m;
            *a = if v > *a { v } else { *a };
        }),
        (Implication::Min, Aggregation::Sum) => pairs.for_each(|(a, &m)| *a += if w < m { w } else { m }),
        (Implication::Product, Aggregation::Sum) => pairs.for_each(|(a, &m)| *a += w * m),
    }
}

/// Defuzzifies a sampled membership function; `None` when it is zero
/// everywhere. Centroid and bisector treat it as piecewise linear between
/// the samples (scikit-fuzzy's convention: exact areas of trapezoids).
pub fn defuzzify(x: &[f64], mu: &[f64], method: Defuzzification) -> Option<f64> {
    let peak = mu.iter().copied().fold(0.0, f64::max);
    if peak <= 0.0 {
        return None;
    }
    let segments = || x.windows(2).zip(mu.windows(2)).map(|(xs, ms)| (xs[0], xs[1], ms[0], ms[1]));
    let area = |x1: f64, x2: f64, y1: f64, y2: f64| 0.5 * (x2 - x1) * (y1 + y2);
    match method {
        Defuzzification::Centroid => {
            let (mut moment, mut total) = (0.0, 0.0);
            for (x1, x2, y1, y2) in segments() {
                if y1 + y2 > 0.0 {
                    let a = area(x1, x2, y1, y2);
                    moment += a * (x1 + (x2 - x1) * (y1 + 2.0 * y2) / (3.0 * (y1 + y2)));
                    total += a;
                }
            }
            Some(moment / total)
        }
        Defuzzification::Bisector => {
            let total: f64 = segments().map(|(x1, x2, y1, y2)| area(x1, x2, y1, y2)).sum();
            let mut left = 0.0;
            for (x1, x2, y1, y2) in segments() {
                let a = area(x1, x2, y1, y2);
                if left + a >= total / 2.0 && a > 0.0 {
                    // Solve ∫ from x1 to u of the linear μ = the missing area.
                    let need = total / 2.0 - left;
                    let m = (y2 - y1) / (x2 - x1);
                    return Some(if m == 0.0 {
                        x1 + need / y1
                    } else {
                        x1 + ((y1 * y1 + 2.0 * m * need).sqrt() - y1) / m
                    });
                }
                left += a;
            }
            x.last().copied()
        }
        Defuzzification::MeanOfMaximum | Defuzzification::SmallestOfMaximum | Defuzzification::LargestOfMaximum => {
            let at_peak = || x.iter().zip(mu).filter(|&(_, &m)| m == peak).map(|(&xv, _)| xv);
            match method {
                Defuzzification::SmallestOfMaximum => at_peak().next(),
                Defuzzification::LargestOfMaximum => at_peak().next_back(),
                _ => {
                    let (sum, n) = at_peak().fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
                    Some(sum / n as f64)
                }
            }
        }
    }
}
