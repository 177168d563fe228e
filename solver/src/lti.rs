//! Linear time-invariant systems in state-space form, and the realisation
//! of transfer functions.

use crate::poly;
use nalgebra::Complex;
use std::fmt;

/// `x' = A x + B u`, `y = C x + D u` (or the same as a difference equation
/// for discrete systems), with row-major dense matrices: `n` states,
/// `m` inputs, `p` outputs. Evaluation allocates nothing.
#[derive(Clone, Debug, PartialEq)]
pub struct StateSpace {
    pub n: usize,
    pub m: usize,
    pub p: usize,
    pub a: Vec<f64>,
    pub b: Vec<f64>,
    pub c: Vec<f64>,
    pub d: Vec<f64>,
}

/// Why a system could not be built.
#[derive(Clone, Debug, PartialEq)]
pub enum LtiError {
    /// The numerator's degree exceeds the denominator's.
    Improper { num_degree: usize, den_degree: usize },
    /// The denominator is the zero polynomial.
    ZeroDenominator,
    /// Matrix shapes do not fit together.
    Shape(String),
    /// Roots not in conjugate pairs.
    Roots(String),
    /// A polynomial of higher degree than [`MAX_ORDER`].
    TooHigh { degree: usize },
}

/// The highest order a transfer function may have. Beyond it the companion
/// realisation is numerically useless (its coefficients span hundreds of
/// decades) and the dense step costs O(n²).
pub const MAX_ORDER: usize = 100;

impl fmt::Display for LtiError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LtiError::Improper { num_degree, den_degree } => write!(
                f,
                "improper transfer function: numerator degree {num_degree} exceeds denominator degree {den_degree}"
            ),
            LtiError::ZeroDenominator => f.write_str("the denominator is zero"),
            LtiError::Shape(s) | LtiError::Roots(s) => f.write_str(s),
            LtiError::TooHigh { degree } => write!(
                f,
                "order {degree} is above the limit of {MAX_ORDER}: realise a large model as a state_space \
                 (balanced, from your modelling tool) or as a cascade of smaller transfer functions"
            ),
        }
    }
}

impl std::error::Error for LtiError {}

impl StateSpace {
    /// Builds a system from row-major matrices, checking their shapes.
    pub fn new(a: Vec<Vec<f64>>, b: Vec<Vec<f64>>, c: Vec<Vec<f64>>, d: Vec<Vec<f64>>) -> Result<Self, LtiError> {
        let n = a.len();
        let rect = |m: &[Vec<f64>], name: &str| -> Result<usize, LtiError> {
            let cols = m.first().map_or(0, Vec::len);
            if m.iter().any(|r| r.len() != cols) {
                return Err(LtiError::Shape(format!("{name}: rows have different lengths")));
            }
            Ok(cols)
        };
        if rect(&a, "A")? != n {
            return Err(LtiError::Shape(format!("A must be square, got {n} rows of {}", rect(&a, "A")?)));
        }
        let m = rect(&b, "B")?;
        if b.len() != n {
            return Err(LtiError::Shape(format!("B must have {n} rows (one per state), got {}", b.len())));
        }
        let p = c.len();
        if rect(&c, "C")? != n && p > 0 {
            return Err(LtiError::Shape(format!("C must have {n} columns (one per state)")));
        }
        let m = if n == 0 { rect(&d, "D")? } else { m };
        if d.len() != p || rect(&d, "D")? != m {
            return Err(LtiError::Shape(format!("D must be {p}×{m} (outputs × inputs)")));
        }
        let flat = |m: Vec<Vec<f64>>| m.into_iter().flatten().collect::<Vec<_>>();
        Ok(StateSpace { n, m, p, a: flat(a), b: flat(b), c: flat(c), d: flat(d) })
    }

    /// Whether any output depends directly on the input (D ≠ 0).
    pub fn has_feedthrough(&self) -> bool {
        self.d.iter().any(|&v| v != 0.0)
    }

    /// `dx = A x + B u` (also the next state of a discrete system).
    #[inline]
    pub fn derivative(&self, x: &[f64], u: &[f64], dx: &mut [f64]) {
        for (i, d) in dx.iter_mut().enumerate().take(self.n) {
            *d = row_times(&self.a, self.n, i, x) + row_times(&self.b, self.m, i, u);
        }
    }

    /// [`StateSpace::derivative`] of a single-input system, u a number (the
    /// same sums: Σ over one term is that term). `x` holds exactly the n
    /// states (dispatched on as in [`StateSpace::output_state_only_scalar`]).
    #[inline(always)]
    pub fn derivative_single_input(&self, x: &[f64], u: f64, dx: &mut [f64]) {
        debug_assert_eq!(x.len(), self.n, "x holds the n states");
        let (a, b) = (&self.a, &self.b);
        match x.len() {
            1 => dx[..1].copy_from_slice(&affine_single_input::<1>(a, b, x, u, -0.0)),
            2 => dx[..2].copy_from_slice(&affine_single_input::<2>(a, b, x, u, -0.0)),
            3 => dx[..3].copy_from_slice(&affine_single_input::<3>(a, b, x, u, -0.0)),
            4 => dx[..4].copy_from_slice(&affine_single_input::<4>(a, b, x, u, -0.0)),
            _ => self.derivative_single_input_general(x, u, dx),
        }
    }

    /// The general loop of [`StateSpace::derivative_single_input`], out of
    /// line so that the unrolled sizes' path saves no registers for it.
    #[inline(never)]
    fn derivative_single_input_general(&self, x: &[f64], u: f64, dx: &mut [f64]) {
        let n = self.n;
        for (i, d) in dx.iter_mut().enumerate().take(n) {
            *d = row_times(&self.a, n, i, x) + self.b[i] * u;
        }
    }

    /// `y = C x + D u`.
    #[inline]
    pub fn output(&self, x: &[f64], u: &[f64], y: &mut [f64]) {
        for (i, yi) in y.iter_mut().enumerate().take(self.p) {
            *yi = row_times(&self.c, self.n, i, x) + row_times(&self.d, self.m, i, u);
        }
    }

    /// `y = C x` only, for systems without feedthrough (callable before the
    /// input of this step is known).
    #[inline]
    pub fn output_state_only(&self, x: &[f64], y: &mut [f64]) {
        for (i, yi) in y.iter_mut().enumerate().take(self.p) {
            *yi = row_times(&self.c, self.n, i, x);
        }
    }

    /// [`StateSpace::output_state_only`] of a single-output system. `x`
    /// holds exactly the n states: the sizes' dispatch is on `x.len()`, a
    /// constant where the caller knows it (a generated step).
    #[inline(always)]
    pub fn output_state_only_scalar(&self, x: &[f64]) -> f64 {
        debug_assert_eq!(x.len(), self.n, "x holds the n states");
        match x.len() {
            1 => dot::<1>(&self.c, x),
            2 => dot::<2>(&self.c, x),
            3 => dot::<3>(&self.c, x),
            4 => dot::<4>(&self.c, x),
            _ => row_times(&self.c, self.n, 0, x),
        }
    }
}

/// `M·x + g·u` for N states and one input (M row-major N×N), with N known
/// to the compiler so the loops unroll: a transfer function's usual
/// realisation. The general loops' sums, in the same order, from `start`:
/// the value their sum starts at (0, or −0 as a float `sum` does — the two
/// differ only in the sign of a zero result).
#[inline]
pub(crate) fn affine_single_input<const N: usize>(m: &[f64], g: &[f64], x: &[f64], u: f64, start: f64) -> [f64; N] {
    let now: [f64; N] = std::array::from_fn(|j| x[j]);
    let (m, g) = (&m[..N * N], &g[..N]);
    std::array::from_fn(|i| {
        let mut v = start;
        for j in 0..N {
            v += m[i * N + j] * now[j];
        }
        v + g[i] * u
    })
}

/// `c·x` over the first N elements, N known to the compiler: the sum of
/// [`row_times`] in the same order (its float sum starts at −0, and
/// −0 + p = p for every p, so starting at the first product is the same).
#[inline]
fn dot<const N: usize>(c: &[f64], x: &[f64]) -> f64 {
    let (c, x) = (&c[..N], &x[..N]);
    let mut v = c[0] * x[0];
    for j in 1..N {
        v += c[j] * x[j];
    }
    v
}

/// Row `i` of a row-major matrix with `cols` columns times `v`, summed in
/// index order.
#[inline]
fn row_times(matrix: &[f64], cols: usize, i: usize, v: &[f64]) -> f64 {
    (0..cols).map(|j| matrix[i * cols + j] * v[j]).sum()
}

/// Realises `num(s)/den(s)` (descending powers) in controllable canonical
/// form, the realisation MATLAB's `tf2ss` returns:
///
/// ```text
/// A = [-a1 -a2 … -an; 1 0 … 0; …; 0 … 1 0],  B = [1 0 … 0]ᵀ,
/// C = [b1 − b0·a1, …, bn − b0·an],            D = b0
/// ```
///
/// after normalising `den` to be monic and padding `num` to its length.
pub fn tf2ss(num: &[f64], den: &[f64]) -> Result<StateSpace, LtiError> {
    let den = poly::trim_leading_zeros(den);
    if den.is_empty() {
        return Err(LtiError::ZeroDenominator);
    }
    let num = poly::trim_leading_zeros(num);
    let (nd, nn) = (den.len() - 1, num.len().saturating_sub(1));
    if nd.max(nn) > MAX_ORDER {
        return Err(LtiError::TooHigh { degree: nd.max(nn) });
    }
    if num.len() > den.len() {
        return Err(LtiError::Improper { num_degree: nn, den_degree: nd });
    }
    let lead = den[0];
    let a_coef: Vec<f64> = den[1..].iter().map(|v| v / lead).collect();
    let mut b_coef = vec![0.0; den.len()];
    for (i, v) in num.iter().enumerate() {
        b_coef[den.len() - num.len() + i] = v / lead;
    }
    let n = nd;
    let d0 = b_coef[0];
    let mut a = vec![0.0; n * n];
    for j in 0..n {
        a[j] = -a_coef[j];
    }
    for i in 1..n {
        a[i * n + (i - 1)] = 1.0;
    }
    let mut b = vec![0.0; n];
    if n > 0 {
        b[0] = 1.0;
    }
    let c: Vec<f64> = (0..n).map(|i| b_coef[i + 1] - d0 * a_coef[i]).collect();
    Ok(StateSpace { n, m: 1, p: 1, a, b, c, d: vec![d0] })
}

/// Numerator and denominator of `k · Π(s − zᵢ) / Π(s − pᵢ)`.
pub fn zpk2tf(zeros: &[Complex<f64>], poles: &[Complex<f64>], gain: f64) -> Result<(Vec<f64>, Vec<f64>), LtiError> {
    let num: Vec<f64> = poly::from_roots(zeros).map_err(LtiError::Roots)?.iter().map(|c| c * gain).collect();
    let den = poly::from_roots(poles).map_err(LtiError::Roots)?;
    Ok((num, den))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The single-input and single-output shortcuts the `transfer_function`
    /// block takes compute the general sums, to the bit.
    #[test]
    fn single_input_and_output_shortcuts_equal_the_general_sums() {
        // Orders 1–4 (the unrolled sizes) and 5 (the general loop).
        let systems = [
            (vec![4.0], vec![1.0, 2.5]),
            (vec![1.639e4], vec![1.0, 154.8, 2.242e4]),
            (vec![2.0, -3.0, 0.5], vec![1.0, 0.3, -2.0, 7.0]),
            (vec![1.0, 0.0, -2.0, 0.5], vec![1.0, 4.0, 6.5, 4.0, 1.2]),
            (vec![0.3, 1.0], vec![1.0, 1.0, 2.0, 3.0, 4.0, 5.0]),
        ];
        for (num, den) in systems {
            let ss = tf2ss(&num, &den).unwrap();
            for k in 0..50 {
                let x: Vec<f64> = (0..ss.n).map(|j| ((k * 7 + j * 13) % 17) as f64 / 3.0 - 2.5).collect();
                let u = (k as f64 - 25.0) / 7.0;
                let (mut general, mut single) = (vec![0.0; ss.n], vec![0.0; ss.n]);
                ss.derivative(&x, &[u], &mut general);
                ss.derivative_single_input(&x, u, &mut single);
                assert_eq!(
                    general.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    single.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
                );
                let mut y = [0.0];
                ss.output_state_only(&x, &mut y);
                assert_eq!(y[0].to_bits(), ss.output_state_only_scalar(&x).to_bits());
            }
            // Signed zeros too: a sum of −0 products is −0 both ways.
            for zero in [0.0, -0.0] {
                let (x, mut y) = (vec![zero; ss.n], [1.0]);
                ss.output_state_only(&x, &mut y);
                assert_eq!(y[0].to_bits(), ss.output_state_only_scalar(&x).to_bits(), "x = {x:?}");
                let (mut general, mut single) = (vec![1.0; ss.n], vec![1.0; ss.n]);
                ss.derivative(&x, &[zero], &mut general);
                ss.derivative_single_input(&x, zero, &mut single);
                let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&general), bits(&single), "x = {x:?}, u = {zero}");
            }
        }
    }

    /// Frequency response of a state-space SISO system at s = jω, via
    /// (jωI − A)⁻¹ by complex Gaussian elimination; cross-checks tf2ss.
    fn freq_response(ss: &StateSpace, w: f64) -> Complex<f64> {
        let n = ss.n;
        let mut m = nalgebra::DMatrix::<Complex<f64>>::zeros(n, n);
        for i in 0..n {
            for j in 0..n {
                m[(i, j)] = Complex::new(-ss.a[i * n + j], if i == j { w } else { 0.0 });
            }
        }
        let b = nalgebra::DVector::from_iterator(n, ss.b.iter().map(|&v| Complex::new(v, 0.0)));
        let x = m.lu().solve(&b).expect("regular");
        let cx: Complex<f64> = (0..n).map(|i| x[i] * ss.c[i]).sum();
        cx + ss.d[0]
    }

    fn tf_response(num: &[f64], den: &[f64], w: f64) -> Complex<f64> {
        let s = Complex::new(0.0, w);
        let ev = |p: &[f64]| p.iter().fold(Complex::new(0.0, 0.0), |acc, &c| acc * s + c);
        ev(num) / ev(den)
    }

    #[test]
    fn realisation_matches_transfer_function() {
        for (num, den) in [
            (vec![1.639e4], vec![1.0, 154.8, 2.242e4]),
            (vec![2.0, 3.0, 1.0], vec![4.0, 1.0, 5.0]),
            (vec![1.0, 0.0], vec![1.0, 2.0, 3.0, 4.0]),
        ] {
            let ss = tf2ss(&num, &den).unwrap();
            for w in [0.0, 0.3, 7.0, 150.0] {
                let (a, b) = (freq_response(&ss, w), tf_response(&num, &den, w));
                assert!((a - b).norm() <= 1e-10 * b.norm().max(1.0), "w={w}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn improper_and_zero_denominators_are_rejected() {
        assert_eq!(tf2ss(&[1.0, 0.0, 0.0], &[1.0, 1.0]), Err(LtiError::Improper { num_degree: 2, den_degree: 1 }));
        assert_eq!(tf2ss(&[1.0], &[0.0, 0.0]), Err(LtiError::ZeroDenominator));
    }

    #[test]
    fn static_gain_is_pure_feedthrough() {
        let ss = tf2ss(&[3.0], &[2.0]).unwrap();
        assert_eq!((ss.n, ss.d[0]), (0, 1.5));
    }

    #[test]
    fn state_space_shapes_are_checked() {
        let ok = StateSpace::new(
            vec![vec![0.0, 1.0], vec![-2.0, -3.0]],
            vec![vec![0.0], vec![1.0]],
            vec![vec![1.0, 0.0]],
            vec![vec![0.0]],
        );
        assert!(ok.is_ok());
        let bad = StateSpace::new(vec![vec![0.0, 1.0]], vec![vec![0.0]], vec![vec![1.0]], vec![vec![0.0]]);
        assert!(matches!(bad, Err(LtiError::Shape(_))));
    }

    #[test]
    fn derivative_and_output_are_the_matrix_products() {
        // Two states, two inputs, two outputs, every entry distinct:
        // A x + B u = [2·1 + 3·(−2) + 5·0.5 + 7·2, −1·1 + 4·(−2) + 0.5·0.5 − 2·2] = [12.5, −12.75],
        // C x + D u = [1 − 2·(−2) + 3·0.5, 0.5·1 + 6·(−2) + 0·0.5 − 1·2] = [6.5, −13.5].
        let ss = StateSpace::new(
            vec![vec![2.0, 3.0], vec![-1.0, 4.0]],
            vec![vec![5.0, 7.0], vec![0.5, -2.0]],
            vec![vec![1.0, -2.0], vec![0.5, 6.0]],
            vec![vec![3.0, 0.0], vec![0.0, -1.0]],
        )
        .unwrap();
        let (x, u) = ([1.0, -2.0], [0.5, 2.0]);
        let mut dx = [f64::NAN; 2];
        ss.derivative(&x, &u, &mut dx);
        assert_eq!(dx, [12.5, -12.75]);
        let mut y = [f64::NAN; 2];
        ss.output(&x, &u, &mut y);
        assert_eq!(y, [6.5, -13.5]);
        ss.output_state_only(&x, &mut y);
        assert_eq!(y, [5.0, -11.5]);
        assert!(ss.has_feedthrough());
        assert!(!tf2ss(&[1.0], &[1.0, 1.0]).unwrap().has_feedthrough());
    }

    #[test]
    fn zpk_expands_to_polynomials() {
        // 4 (s + 1) / ((s + 2)(s + 3)); a conjugate pair −1 ± 2j gives s² + 2 s + 5.
        let c = |re: f64, im: f64| Complex::new(re, im);
        let (num, den) = zpk2tf(&[c(-1.0, 0.0)], &[c(-2.0, 0.0), c(-3.0, 0.0)], 4.0).unwrap();
        assert_eq!((num, den), (vec![4.0, 4.0], vec![1.0, 5.0, 6.0]));
        let (num, den) = zpk2tf(&[], &[c(-1.0, 2.0), c(-1.0, -2.0)], 0.5).unwrap();
        assert_eq!((num, den), (vec![0.5], vec![1.0, 2.0, 5.0]));
    }

    #[test]
    fn errors_say_what_is_wrong() {
        let improper = LtiError::Improper { num_degree: 2, den_degree: 1 }.to_string();
        assert_eq!(improper, "improper transfer function: numerator degree 2 exceeds denominator degree 1");
        assert_eq!(LtiError::ZeroDenominator.to_string(), "the denominator is zero");
        assert!(LtiError::TooHigh { degree: 101 }.to_string().starts_with("order 101 is above the limit of 100"));
        assert!(matches!(tf2ss(&[1.0], &[1.0; 102]), Err(LtiError::TooHigh { degree: 101 })));
        assert_eq!(tf2ss(&[1.0], &[1.0; MAX_ORDER + 1]).map(|ss| ss.n), Ok(MAX_ORDER));
    }
}
