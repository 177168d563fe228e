//! A dense LU factorisation with partial pivoting that allocates once: the
//! matrix, permutation and scratch live in the struct, so refactoring and
//! solving in a step loop allocate nothing. The numerics are faer's.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::perm::PermRef;
use faer::{MatMut, MatRef, Par};

/// An `n × n` matrix (column-major) and, after [`DenseLu::factor`], its LU
/// factors in place.
pub struct DenseLu {
    n: usize,
    a: Vec<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    scratch: MemBuffer,
}

/// A copy with the same matrix and factors (the scratch is allocated anew:
/// it holds nothing between calls).
impl Clone for DenseLu {
    fn clone(&self) -> Self {
        DenseLu { a: self.a.clone(), perm: self.perm.clone(), perm_inv: self.perm_inv.clone(), ..DenseLu::new(self.n) }
    }
}

impl DenseLu {
    pub fn new(n: usize) -> Self {
        let req = StackReq::any_of(&[
            factor::lu_in_place_scratch::<usize, f64>(n, n, Par::Seq, Default::default()),
            solve::solve_in_place_scratch::<usize, f64>(n, 1, Par::Seq),
        ]);
        DenseLu { n, a: vec![0.0; n * n], perm: vec![0; n], perm_inv: vec![0; n], scratch: MemBuffer::new(req) }
    }

    /// The matrix to factor, column-major: element (i, j) at `j·n + i`.
    pub fn matrix_mut(&mut self) -> &mut [f64] {
        &mut self.a
    }

    /// Factors the matrix in place; returns false when a pivot is zero or
    /// not finite (the matrix is singular to working precision).
    pub fn factor(&mut self) -> bool {
        let n = self.n;
        let mat = MatMut::from_column_major_slice_mut(&mut self.a, n, n);
        factor::lu_in_place(
            mat,
            &mut self.perm,
            &mut self.perm_inv,
            Par::Seq,
            MemStack::new(&mut self.scratch),
            Default::default(),
        );
        (0..n).all(|i| {
            let d = self.a[i * n + i];
            d != 0.0 && d.is_finite()
        })
    }

    /// Solves `A x = b` in place with the factors from [`DenseLu::factor`].
    pub fn solve(&mut self, b: &mut [f64]) {
        let n = self.n;
        let lu = MatRef::from_column_major_slice(&self.a, n, n);
        // Safety of the permutation: `perm`/`perm_inv` were written by
        // `lu_in_place` as inverse permutations of 0..n.
        let perm = PermRef::new_checked(&self.perm, &self.perm_inv, n);
        let rhs = MatMut::from_column_major_slice_mut(b, n, 1);
        solve::solve_in_place(lu, lu, perm, rhs, Par::Seq, MemStack::new(&mut self.scratch));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_pivoting_system() {
        // [[0, 2], [3, 1]] x = [4, 5] has x = [1, 2]; the zero pivot forces a row swap.
        let mut lu = DenseLu::new(2);
        lu.matrix_mut().copy_from_slice(&[0.0, 3.0, 2.0, 1.0]);
        assert!(lu.factor());
        let mut b = [4.0, 5.0];
        lu.solve(&mut b);
        assert!((b[0] - 1.0).abs() < 1e-15 && (b[1] - 2.0).abs() < 1e-15, "{b:?}");
    }

    #[test]
    fn reports_a_singular_matrix() {
        let mut lu = DenseLu::new(2);
        lu.matrix_mut().copy_from_slice(&[1.0, 2.0, 2.0, 4.0]);
        assert!(!lu.factor());
    }
}
