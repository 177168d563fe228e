//! Small dense matrices, for the few rows of a Kalman filter or of an
//! algebraic loop's Newton step: products into working space that
//! allocate nothing in a step, and Gaussian elimination. Written here
//! rather than taken from faer or nalgebra: the core and the block library
//! build without them (faer comes with the optional implicit solver), and
//! these matrices are a few rows.

/// A row-major matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct Mat {
    pub rows: usize,
    pub cols: usize,
    pub data: Vec<f64>,
}

impl Mat {
    pub fn zeros(rows: usize, cols: usize) -> Mat {
        Mat { rows, cols, data: vec![0.0; rows * cols] }
    }

    pub fn identity(n: usize) -> Mat {
        let mut m = Mat::zeros(n, n);
        (0..n).for_each(|i| m.data[i * n + i] = 1.0);
        m
    }

    /// From a list of rows (all as long as the first).
    pub fn from_rows(rows: &[Vec<f64>]) -> Mat {
        let cols = rows.first().map_or(0, Vec::len);
        Mat { rows: rows.len(), cols, data: rows.iter().flatten().copied().collect() }
    }

    #[inline]
    pub fn at(&self, i: usize, j: usize) -> f64 {
        self.data[i * self.cols + j]
    }

    #[inline]
    pub fn at_mut(&mut self, i: usize, j: usize) -> &mut f64 {
        &mut self.data[i * self.cols + j]
    }

    pub fn row(&self, i: usize) -> &[f64] {
        &self.data[i * self.cols..(i + 1) * self.cols]
    }

    /// self = a·b (self already a.rows × b.cols).
    pub fn set_product(&mut self, a: &Mat, b: &Mat) {
        for i in 0..a.rows {
            for j in 0..b.cols {
                *self.at_mut(i, j) = (0..a.cols).map(|k| a.at(i, k) * b.at(k, j)).sum();
            }
        }
    }

    /// self = a·bᵀ (self already a.rows × b.rows).
    pub fn set_product_transposed(&mut self, a: &Mat, b: &Mat) {
        for i in 0..a.rows {
            for j in 0..b.rows {
                *self.at_mut(i, j) = a.row(i).iter().zip(b.row(j)).map(|(x, y)| x * y).sum();
            }
        }
    }

    pub fn add(&mut self, other: &Mat) {
        self.data.iter_mut().zip(&other.data).for_each(|(a, b)| *a += b);
    }

    /// (M + Mᵀ)/2: rounding keeps a covariance from drifting unsymmetric.
    pub fn symmetrise(&mut self) {
        for i in 0..self.rows {
            for j in 0..i {
                let m = 0.5 * (self.at(i, j) + self.at(j, i));
                *self.at_mut(i, j) = m;
                *self.at_mut(j, i) = m;
            }
        }
    }

    pub fn transpose(&self) -> Mat {
        let mut t = Mat::zeros(self.cols, self.rows);
        for i in 0..self.rows {
            for j in 0..self.cols {
                *t.at_mut(j, i) = self.at(i, j);
            }
        }
        t
    }

    pub fn times(&self, b: &Mat) -> Mat {
        let mut m = Mat::zeros(self.rows, b.cols);
        m.set_product(self, b);
        m
    }

    pub fn is_symmetric(&self) -> bool {
        let scale = self.data.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        (0..self.rows).all(|i| (0..i).all(|j| (self.at(i, j) - self.at(j, i)).abs() <= 1e-12 * scale))
    }

    /// Whether a symmetric matrix is positive definite (its Cholesky
    /// factorisation succeeds).
    pub fn is_positive_definite(&self) -> bool {
        let n = self.rows;
        let mut l = Mat::zeros(n, n);
        for j in 0..n {
            let d = self.at(j, j) - (0..j).map(|k| l.at(j, k) * l.at(j, k)).sum::<f64>();
            // Not positive, or NaN.
            if d.is_nan() || d <= 0.0 {
                return false;
            }
            *l.at_mut(j, j) = d.sqrt();
            for i in j + 1..n {
                let v = self.at(i, j) - (0..j).map(|k| l.at(i, k) * l.at(j, k)).sum::<f64>();
                *l.at_mut(i, j) = v / l.at(j, j);
            }
        }
        true
    }
}

/// Solves a·X = b for X in place of b by Gaussian elimination with
/// partial pivoting, overwriting a; false when a is singular to working
/// precision. Allocates nothing.
pub fn solve_in_place(a: &mut Mat, b: &mut Mat) -> bool {
    let n = a.rows;
    for col in 0..n {
        let pivot = (col..n).max_by(|&i, &j| a.at(i, col).abs().total_cmp(&a.at(j, col).abs())).unwrap_or(col);
        let p = a.at(pivot, col);
        if p == 0.0 || !p.is_finite() {
            return false;
        }
        if pivot != col {
            for j in 0..n {
                a.data.swap(pivot * n + j, col * n + j);
            }
            for j in 0..b.cols {
                b.data.swap(pivot * b.cols + j, col * b.cols + j);
            }
        }
        for i in col + 1..n {
            let f = a.at(i, col) / p;
            for j in col..n {
                let v = a.at(col, j);
                *a.at_mut(i, j) -= f * v;
            }
            for j in 0..b.cols {
                let v = b.at(col, j);
                *b.at_mut(i, j) -= f * v;
            }
        }
    }
    for col in (0..n).rev() {
        for j in 0..b.cols {
            let s: f64 = (col + 1..n).map(|k| a.at(col, k) * b.at(k, j)).sum();
            *b.at_mut(col, j) = (b.at(col, j) - s) / a.at(col, col);
        }
    }
    true
}

/// The inverse of a square matrix, if it has one.
pub fn inverse(a: &Mat) -> Option<Mat> {
    let mut x = Mat::identity(a.rows);
    solve_in_place(&mut a.clone(), &mut x).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_with_pivoting() {
        let mut a = Mat::from_rows(&[vec![0.0, 2.0], vec![3.0, 1.0]]);
        let mut b = Mat::from_rows(&[vec![4.0], vec![5.0]]);
        assert!(solve_in_place(&mut a, &mut b));
        assert!((b.data[0] - 1.0).abs() < 1e-15 && (b.data[1] - 2.0).abs() < 1e-15);
        assert!(!solve_in_place(&mut Mat::zeros(2, 2), &mut Mat::zeros(2, 1)));
    }
}
