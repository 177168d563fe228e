//! The stationary Kalman filter: its covariance from the discrete
//! algebraic Riccati equation.

use ctlgraph_core::dense::{Mat, inverse};

/// The stationary prediction covariance P of the filter's Riccati
/// equation P = A P Aᵀ − A P Cᵀ (C P Cᵀ + R)⁻¹ C P Aᵀ + Q, by the
/// structured doubling algorithm (SDA: Chu, Fan, Lin and Wang,
/// "Structure-preserving algorithms for periodic discrete-time algebraic
/// Riccati equations", Int. J. Control 77, 2004) on the dual control
/// equation: Â = Aᵀ,
/// G = Cᵀ R⁻¹ C, H = Q, and W = I + G H,
/// Â ← Â W⁻¹ Â,  G ← G + Â W⁻¹ G Âᵀ,  H ← H + Âᵀ H W⁻¹ Â;
/// H converges quadratically to P when (A, C) is detectable.
pub fn steady_state_covariance(a: &Mat, c: &Mat, q: &Mat, r: &Mat) -> Result<Mat, String> {
    let n = a.rows;
    let r_inv = inverse(r).ok_or("R is singular")?;
    let mut ak = a.transpose();
    let mut g = c.transpose().times(&r_inv).times(c);
    let mut h = q.clone();
    for _ in 0..100 {
        let mut w = Mat::identity(n);
        w.add(&g.times(&h));
        let w_inv = inverse(&w).ok_or("the doubling iteration met a singular matrix: is (A, C) detectable?")?;
        let aw = ak.times(&w_inv);
        let mut g_next = aw.times(&g).times(&ak.transpose());
        g_next.add(&g);
        let mut h_next = ak.transpose().times(&h).times(&w_inv).times(&ak);
        h_next.add(&h);
        let a_next = aw.times(&ak);
        let change = h_next.data.iter().zip(&h.data).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        let size = h_next.data.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if !size.is_finite() {
            break;
        }
        (ak, g, h) = (a_next, g_next, h_next);
        if change <= 1e-14 * size {
            h.symmetrise();
            return Ok(h);
        }
    }
    Err("the Riccati equation has no stationary solution reached by doubling: is (A, C) detectable and (A, Q) stabilisable?"
        .into())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scalar random walk x⁺ = x + w, y = x + v has the stationary
    /// prediction variance P = (q + √(q² + 4qr))/2.
    #[test]
    fn the_random_walk_has_its_closed_form_variance() {
        for (q, r) in [(1.0, 1.0), (1e-6, 1.0), (4.0, 0.01)] {
            let one = Mat::identity(1);
            let p = steady_state_covariance(&one, &one, &Mat::from_rows(&[vec![q]]), &Mat::from_rows(&[vec![r]]));
            let want = (q + (q * q + 4.0 * q * r).sqrt()) / 2.0;
            let p = p.unwrap().data[0];
            assert!((p - want).abs() <= 1e-13 * want, "q = {q}, r = {r}: {p} vs {want}");
        }
    }

    /// A position-velocity plant against SciPy 1.17.1:
    /// `solve_discrete_are(A.T, C.T, Q, R)` (values recorded).
    #[test]
    fn a_two_state_plant_matches_scipy() {
        let a = Mat::from_rows(&[vec![1.0, 0.1], vec![0.0, 0.95]]);
        let c = Mat::from_rows(&[vec![1.0, 0.0]]);
        let q = Mat::from_rows(&[vec![1e-4, 0.0], vec![0.0, 1e-2]]);
        let r = Mat::from_rows(&[vec![0.04]]);
        let p = steady_state_covariance(&a, &c, &q, &r).unwrap();
        let scipy = [0.01280633271174234, 0.01660516877371214, 0.01660516877371214, 0.05423116677942821];
        for (got, want) in p.data.iter().zip(scipy) {
            assert!((got - want).abs() <= 1e-13 * want, "{got} vs SciPy {want}");
        }
    }

    /// (A, C) not detectable (an unstable state C does not see): refused.
    #[test]
    fn an_undetectable_pair_has_no_stationary_solution() {
        let a = Mat::from_rows(&[vec![1.2, 0.0], vec![0.0, 0.5]]);
        let c = Mat::from_rows(&[vec![0.0, 1.0]]);
        let q = Mat::identity(2);
        assert!(steady_state_covariance(&a, &c, &q, &Mat::identity(1)).is_err());
    }
}
