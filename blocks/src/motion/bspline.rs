//! Cubic B-spline curves fitted by least squares (Piegl & Tiller, *The
//! NURBS Book*, 2nd ed.: chord-length parameters eq. 9.5, knots by
//! averaging eq. 9.8 / 9.68–9.69, the fit eq. 9.63–9.67; basis functions and
//! their derivatives A2.1–A2.3). Evaluation allocates nothing.

use nalgebra::{DMatrix, DVector};

const DEGREE: usize = 3;

/// A cubic B-spline curve in `dim` dimensions.
#[derive(Clone, Debug, PartialEq)]
pub struct BSpline {
    pub dim: usize,
    pub knots: Vec<f64>,
    /// Control points, `dim` numbers each.
    pub control: Vec<f64>,
}

/// The chord-length parameters of `points` (`dim` numbers each) in [0, 1].
pub fn chord_parameters(points: &[f64], dim: usize) -> Result<Vec<f64>, String> {
    let m = points.len() / dim;
    let mut u = vec![0.0; m];
    for k in 1..m {
        let d: f64 = (0..dim).map(|c| (points[k * dim + c] - points[(k - 1) * dim + c]).powi(2)).sum();
        u[k] = u[k - 1] + d.sqrt();
    }
    let total = u[m - 1];
    if total <= 0.0 || !total.is_finite() {
        return Err("the points do not span a curve (all equal, or not finite)".into());
    }
    for (k, v) in u.iter_mut().enumerate() {
        *v = if k == m - 1 { 1.0 } else { *v / total };
    }
    if u.windows(2).any(|w| w[1] <= w[0]) {
        return Err("two consecutive points are equal".into());
    }
    Ok(u)
}

impl BSpline {
    /// The least-squares cubic through `points` (`dim` numbers each) at
    /// parameters `params` (increasing, from 0 to 1) with `n_control`
    /// control points (4 … number of points; equal: interpolation). The
    /// end points are met exactly.
    pub fn fit(points: &[f64], dim: usize, params: &[f64], n_control: usize) -> Result<BSpline, String> {
        let m1 = points.len() / dim; // m + 1 points
        if m1 < DEGREE + 1 || !(DEGREE + 1..=m1).contains(&n_control) || params.len() != m1 {
            return Err(format!("a cubic needs 4 to {m1} control points for {m1} points, given {n_control}"));
        }
        let (m, n, p) = (m1 - 1, n_control - 1, DEGREE);
        let mut knots = vec![0.0; n + p + 2];
        for k in knots.iter_mut().skip(n + 1) {
            *k = 1.0;
        }
        if n == m {
            // Interpolation: averaging (eq. 9.8).
            for j in 1..=n - p {
                knots[j + p] = params[j..j + p].iter().sum::<f64>() / p as f64;
            }
        } else {
            // Approximation (eq. 9.68–9.69).
            let d = (m + 1) as f64 / (n - p + 1) as f64;
            for j in 1..=n - p {
                let i = (j as f64 * d).floor() as usize;
                let alpha = j as f64 * d - i as f64;
                knots[p + j] = (1.0 - alpha) * params[i - 1] + alpha * params[i];
            }
        }
        let mut spline = BSpline { dim, knots, control: vec![0.0; n_control * dim] };
        let (first, last) = (&points[..dim], &points[m * dim..]);
        spline.control[..dim].copy_from_slice(first);
        spline.control[n * dim..].copy_from_slice(last);
        if n >= 2 {
            // Interior control points: (NᵀN) P = Nᵀ R over points 1 … m − 1.
            let mut basis = DMatrix::<f64>::zeros(m - 1, n - 1);
            let mut rhs = DMatrix::<f64>::zeros(m - 1, dim);
            for k in 1..m {
                let mut all = vec![0.0; n + 1];
                spline.basis_all(params[k], &mut all);
                for i in 1..n {
                    basis[(k - 1, i - 1)] = all[i];
                }
                for c in 0..dim {
                    rhs[(k - 1, c)] = points[k * dim + c] - all[0] * first[c] - all[n] * last[c];
                }
            }
            let normal = basis.transpose() * &basis;
            let projected = basis.transpose() * rhs;
            let lu = normal.lu();
            for c in 0..dim {
                let column: DVector<f64> = projected.column(c).into_owned();
                let solved =
                    lu.solve(&column).ok_or("the fit is singular: fewer control points, or spread the points")?;
                for i in 1..n {
                    spline.control[i * dim + c] = solved[i - 1];
                }
            }
        }
        Ok(spline)
    }

    /// The knot span holding `u` (A2.1).
    fn span(&self, u: f64) -> usize {
        let n = self.control.len() / self.dim - 1;
        if u >= self.knots[n + 1] {
            return n;
        }
        let (mut low, mut high) = (DEGREE, n + 1);
        let mut mid = (low + high) / 2;
        while u < self.knots[mid] || u >= self.knots[mid + 1] {
            if u < self.knots[mid] {
                high = mid
            } else {
                low = mid
            }
            mid = (low + high) / 2;
        }
        mid
    }

    /// Every basis function N_i,3(u), i = 0 … n (for the fit).
    fn basis_all(&self, u: f64, out: &mut [f64]) {
        let span = self.span(u);
        let ders = self.derivatives_of_basis(span, u);
        out.iter_mut().for_each(|v| *v = 0.0);
        for (r, v) in ders[0].iter().enumerate() {
            out[span - DEGREE + r] = *v;
        }
    }

    /// The nonzero basis functions at `u` and their first two derivatives
    /// (A2.3): `ders[k][r]` is the k-th derivative of N_{span−3+r}.
    fn derivatives_of_basis(&self, span: usize, u: f64) -> [[f64; 4]; 3] {
        let p = DEGREE;
        let k = &self.knots;
        let mut ndu = [[0.0; 4]; 4];
        let (mut left, mut right) = ([0.0; 4], [0.0; 4]);
        ndu[0][0] = 1.0;
        for j in 1..=p {
            left[j] = u - k[span + 1 - j];
            right[j] = k[span + j] - u;
            let mut saved = 0.0;
            for r in 0..j {
                ndu[j][r] = right[r + 1] + left[j - r];
                let temp = ndu[r][j - 1] / ndu[j][r];
                ndu[r][j] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            ndu[j][j] = saved;
        }
        let mut ders = [[0.0; 4]; 3];
        for j in 0..=p {
            ders[0][j] = ndu[j][p];
        }
        for r in 0..=p {
            let (mut s1, mut s2) = (0, 1);
            let mut a = [[0.0; 4]; 2];
            a[0][0] = 1.0;
            for kk in 1..=2usize {
                let mut d = 0.0;
                let rk = r as isize - kk as isize;
                let pk = p - kk;
                if r >= kk {
                    a[s2][0] = a[s1][0] / ndu[pk + 1][rk as usize];
                    d = a[s2][0] * ndu[rk as usize][pk];
                }
                let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
                let j2 = if r as isize - 1 <= pk as isize { kk - 1 } else { p - r };
                for j in j1..=j2 {
                    let idx = (rk + j as isize) as usize;
                    a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][idx];
                    d += a[s2][j] * ndu[idx][pk];
                }
                if r <= pk {
                    a[s2][kk] = -a[s1][kk - 1] / ndu[pk + 1][r];
                    d += a[s2][kk] * ndu[r][pk];
                }
                ders[kk][r] = d;
                std::mem::swap(&mut s1, &mut s2);
            }
        }
        for (kk, factor) in [(1, p as f64), (2, (p * (p - 1)) as f64)] {
            for v in &mut ders[kk] {
                *v *= factor;
            }
        }
        ders
    }

    /// C(u), C'(u), C''(u) into `out` (3·dim numbers); `u` is clamped to
    /// [0, 1].
    pub fn eval(&self, u: f64, out: &mut [f64]) {
        let u = if u.is_nan() { u } else { u.clamp(0.0, 1.0) };
        let span = self.span(u);
        let ders = self.derivatives_of_basis(span, u);
        let dim = self.dim;
        out[..3 * dim].iter_mut().for_each(|v| *v = 0.0);
        for (k, row) in ders.iter().enumerate() {
            for (r, n) in row.iter().enumerate() {
                let i = span - DEGREE + r;
                for c in 0..dim {
                    out[k * dim + c] += n * self.control[i * dim + c];
                }
            }
        }
    }
}
