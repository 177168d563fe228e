//! Linguistic variables: a universe and its terms' membership functions,
//! and the N-term shorthand (`terms: 7`) that builds a uniform partition.

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
