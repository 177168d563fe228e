//! The fuzzy inference engine: membership functions, rules, Mamdani and
//! zero-order Sugeno inference. Everything that does not depend on the
//! inputs (output membership values on the sampled universe) is computed
//! once; `eval` writes into preallocated buffers and allocates nothing.

/// A membership function (parameter order as MATLAB's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mf {
    /// trimf [a, b, c], a <= b <= c.
    Tri(f64, f64, f64),
    /// trapmf [a, b, c, d], a <= b <= c <= d.
    Trap(f64, f64, f64, f64),
    /// gaussmf [sigma, c].
    Gauss(f64, f64),
    /// gbellmf [a, b, c]: 1/(1 + |(x − c)/a|^(2b)).
    Bell(f64, f64, f64),
    /// A constant output of a zero-order Sugeno system.
    Const(f64),
}

impl Mf {
    /// Membership of `x`, with MATLAB's and scikit-fuzzy's conventions at
    /// the corners (trimf with a = b is 1 at x = a).
    pub fn eval(&self, x: f64) -> f64 {
        match *self {
            Mf::Tri(a, b, c) => {
                if x == b {
                    1.0
                } else if a < x && x < b {
                    (x - a) / (b - a)
                } else if b < x && x < c {
                    (c - x) / (c - b)
                } else {
                    0.0
                }
            }
            Mf::Trap(a, b, c, d) => {
                if x < a || x > d {
                    0.0
                } else if x <= b {
                    Mf::Tri(a, b, b).eval(x)
                } else if x >= c {
                    Mf::Tri(c, c, d).eval(x)
                } else {
                    1.0
                }
            }
            Mf::Gauss(sigma, c) => (-(x - c) * (x - c) / (2.0 * sigma * sigma)).exp(),
            Mf::Bell(a, b, c) => 1.0 / (1.0 + ((x - c) / a).abs().powf(2.0 * b)),
            Mf::Const(_) => 0.0,
        }
    }
}

/// A linguistic variable: universe and terms.
#[derive(Clone, Debug, PartialEq)]
pub struct Variable {
    pub name: String,
    pub lo: f64,
    pub hi: f64,
    pub terms: Vec<(String, Mf)>,
}

/// The standard names of N uniformly spaced terms.
pub fn standard_names(n: usize) -> Option<&'static [&'static str]> {
    match n {
        2 => Some(&["N", "P"]),
        3 => Some(&["N", "Z", "P"]),
        5 => Some(&["NB", "NS", "ZO", "PS", "PB"]),
        7 => Some(&["NB", "NM", "NS", "ZO", "PS", "PM", "PB"]),
        _ => None,
    }
}

/// N triangles with peaks evenly spaced over [lo, hi], each reaching to its
/// neighbours' peaks; the end ones are half triangles peaking at the edges.
pub fn uniform_triangles(lo: f64, hi: f64, names: &[&str]) -> Vec<(String, Mf)> {
    let n = names.len();
    let step = (hi - lo) / (n - 1) as f64;
    let peak = |i: usize| if i == n - 1 { hi } else { lo + i as f64 * step };
    (0..n)
        .map(|i| {
            let a = if i == 0 { lo } else { peak(i - 1) };
            let c = if i == n - 1 { hi } else { peak(i + 1) };
            (names[i].to_string(), Mf::Tri(a, peak(i), c))
        })
        .collect()
}

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
    /// Per output: the sampled universe, and each term's membership on it.
    grids: Vec<Vec<f64>>,
    term_grids: Vec<Vec<Vec<f64>>>,
    // Work buffers.
    membership: Vec<Vec<f64>>,
    strength: Vec<f64>,
    term_strength: Vec<f64>,
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
        let grids: Vec<Vec<f64>> = outputs
            .iter()
            .map(|v| (0..m).map(|j| v.lo + (v.hi - v.lo) * j as f64 / (m - 1) as f64).collect())
            .collect();
        let term_grids = outputs
            .iter()
            .zip(&grids)
            .map(|(v, g)| v.terms.iter().map(|(_, mf)| g.iter().map(|&x| mf.eval(x)).collect()).collect())
            .collect();
        let most_terms = outputs.iter().map(|v| v.terms.len()).max().unwrap_or(0);
        Fis {
            membership: inputs.iter().map(|v| vec![0.0; v.terms.len()]).collect(),
            strength: vec![0.0; rules.len()],
            term_strength: vec![0.0; most_terms],
            aggregate: vec![0.0; m],
            inputs,
            outputs,
            rules,
            methods,
            sugeno,
            grids,
            term_grids,
        }
    }

    /// Evaluates the system: inputs are clipped to their universes.
    pub fn eval(&mut self, x: &[f64], y: &mut [f64]) {
        for (i, v) in self.inputs.iter().enumerate() {
            let xi = x[i].clamp(v.lo, v.hi);
            for (k, (_, mf)) in v.terms.iter().enumerate() {
                self.membership[i][k] = mf.eval(xi);
            }
        }
        for (r, rule) in self.rules.iter().enumerate() {
            let mut acc: Option<f64> = None;
            for &(i, k, negated) in &rule.antecedents {
                let mu = if negated { 1.0 - self.membership[i][k] } else { self.membership[i][k] };
                acc = Some(match (acc, rule.connective) {
                    (None, _) => mu,
                    (Some(a), Connective::And) => match self.methods.and {
                        AndMethod::Min => a.min(mu),
                        AndMethod::Product => a * mu,
                    },
                    (Some(a), Connective::Or) => match self.methods.or {
                        OrMethod::Max => a.max(mu),
                        OrMethod::ProbOr => a + mu - a * mu,
                    },
                });
            }
            self.strength[r] = acc.unwrap_or(0.0);
        }
        for (o, yo) in y.iter_mut().enumerate().take(self.outputs.len()) {
            *yo = if self.sugeno { self.sugeno_output(o) } else { self.mamdani_output(o) };
        }
    }

    /// Weighted average of the consequents' constants.
    fn sugeno_output(&self, o: usize) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for (r, rule) in self.rules.iter().enumerate() {
            for &(out, term) in &rule.consequents {
                if out == o {
                    let z = match self.outputs[o].terms[term].1 {
                        Mf::Const(z) => z,
                        _ => 0.0,
                    };
                    num += self.strength[r] * z;
                    den += self.strength[r];
                }
            }
        }
        if den > 0.0 { num / den } else { (self.outputs[o].lo + self.outputs[o].hi) / 2.0 }
    }

    fn mamdani_output(&mut self, o: usize) -> f64 {
        let Fis { rules, strength, term_strength, aggregate, term_grids, grids, methods, outputs, .. } = self;
        let terms = &term_grids[o];
        aggregate.iter_mut().for_each(|a| *a = 0.0);
        let grouped = !(methods.aggregation == Aggregation::Sum && methods.implication == Implication::Min);
        if grouped {
            // max_r imp(w_r, μ_T) = imp(max_r w_r, μ_T) for rules sharing a
            // term T (implication is monotone); Σ_r w_r·μ_T = (Σ_r w_r)·μ_T.
            term_strength[..terms.len()].iter_mut().for_each(|w| *w = 0.0);
            for (r, rule) in rules.iter().enumerate() {
                for &(out, t) in &rule.consequents {
                    if out == o {
                        term_strength[t] = match methods.aggregation {
                            Aggregation::Max => term_strength[t].max(strength[r]),
                            Aggregation::Sum => term_strength[t] + strength[r],
                        };
                    }
                }
            }
            for (t, mu) in terms.iter().enumerate() {
                let w = term_strength[t];
                if w == 0.0 {
                    continue;
                }
                for (a, &m) in aggregate.iter_mut().zip(mu) {
                    let v = match methods.implication {
                        Implication::Min => w.min(m),
                        Implication::Product => w * m,
                    };
                    *a = match methods.aggregation {
                        Aggregation::Max => a.max(v),
                        Aggregation::Sum => *a + v,
                    };
                }
            }
        } else {
            for (r, rule) in rules.iter().enumerate() {
                for &(out, t) in &rule.consequents {
                    if out == o && strength[r] > 0.0 {
                        for (a, &m) in aggregate.iter_mut().zip(&terms[t]) {
                            *a += strength[r].min(m);
                        }
                    }
                }
            }
        }
        let v = &outputs[o];
        defuzzify(&grids[o], aggregate, methods.defuzzification).unwrap_or((v.lo + v.hi) / 2.0)
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
