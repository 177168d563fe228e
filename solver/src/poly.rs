//! Real polynomials in descending powers (`[1, 3, 2]` is s² + 3s + 2),
//! the convention of MATLAB's `tf` and of our graph files.

use nalgebra::Complex;

/// The polynomial without its leading zero coefficients.
pub fn trim_leading_zeros(p: &[f64]) -> &[f64] {
    let first = p.iter().position(|&c| c != 0.0).unwrap_or(p.len());
    &p[first..]
}

/// The product of polynomial factors (`[1.0]` for none; an empty factor,
/// the zero polynomial, gives the zero polynomial).
pub fn product(factors: &[Vec<f64>]) -> Vec<f64> {
    factors.iter().fold(vec![1.0], |acc, f| {
        let mut out = vec![0.0; (acc.len() + f.len()).max(1) - 1];
        for (i, a) in acc.iter().enumerate() {
            for (j, b) in f.iter().enumerate() {
                out[i + j] += a * b;
            }
        }
        out
    })
}

/// The monic real polynomial with the given roots. Complex roots must come
/// in conjugate pairs; the imaginary residue is checked, not silently dropped.
pub fn from_roots(roots: &[Complex<f64>]) -> Result<Vec<f64>, String> {
    let mut coeffs = vec![Complex::new(1.0, 0.0)];
    for &r in roots {
        coeffs.push(Complex::new(0.0, 0.0));
        for i in (1..coeffs.len()).rev() {
            let prev = coeffs[i - 1];
            coeffs[i] -= r * prev;
        }
    }
    let scale = coeffs.iter().map(|c| c.norm()).fold(1.0, f64::max);
    if let Some(c) = coeffs.iter().find(|c| c.im.abs() > 1e-9 * scale) {
        return Err(format!(
            "complex roots must come in conjugate pairs (a coefficient has imaginary part {:e})",
            c.im
        ));
    }
    Ok(coeffs.iter().map(|c| c.re).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_to_coefficients() {
        let p = from_roots(&[Complex::new(-1.0, 0.0), Complex::new(-2.0, 0.0)]).unwrap();
        assert_eq!(p, vec![1.0, 3.0, 2.0]);
        let q = from_roots(&[Complex::new(-1.0, 2.0), Complex::new(-1.0, -2.0)]).unwrap();
        assert_eq!(q, vec![1.0, 2.0, 5.0]);
        assert!(from_roots(&[Complex::new(0.0, 1.0)]).is_err());
    }

    #[test]
    fn products_of_factors() {
        // (s + 1)(s + 2)(2s − 1) = 2s³ + 5s² + s − 2; no factors: 1; a zero factor: zero.
        assert_eq!(product(&[vec![1.0, 1.0], vec![1.0, 2.0], vec![2.0, -1.0]]), vec![2.0, 5.0, 1.0, -2.0]);
        assert_eq!(product(&[]), vec![1.0]);
        assert!(product(&[vec![1.0, 1.0], vec![], vec![3.0]]).iter().all(|&c| c == 0.0));
    }
}
