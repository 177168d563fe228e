//! Transfer functions written as products of factors, realised as a
//! cascade of low-order sections.
//!
//! Expanding a product like the milling paper's controller (eq. 12, order 6,
//! poles from 1e3 to 2.5e4 rad/s) and realising it in companion form gives
//! an A matrix of condition number 2.5e25: its states mean nothing and a
//! solver's rounding error is amplified accordingly. A cascade keeps each
//! factor's coefficients as written: one section per denominator factor,
//! each numerator factor paired with a section that has room for it (the
//! usual pairing of a zero with the pole nearest it is the user's order of
//! writing), every section scaled to unit DC gain and the whole gain
//! applied at the output, so no coefficient is a product of all the
//! factors' (eq. 12's coefficients spread over 1e14 instead of 6e26).

use crate::lti::{LtiError, MAX_ORDER, StateSpace, tf2ss};
use crate::poly;

impl StateSpace {
    /// The series connection `next ∘ self`: `self`'s outputs drive `next`'s
    /// inputs. States are `self`'s, then `next`'s:
    ///
    /// ```text
    /// A = [A1 0; B2·C1 A2],  B = [B1; B2·D1],  C = [D2·C1  C2],  D = D2·D1
    /// ```
    pub fn series(&self, next: &StateSpace) -> Result<StateSpace, LtiError> {
        if self.p != next.m {
            return Err(LtiError::Shape(format!("series: {} outputs cannot drive {} inputs", self.p, next.m)));
        }
        let (n1, n2, m, p, q) = (self.n, next.n, self.m, next.p, self.p);
        let n = n1 + n2;
        // (r × q)·(q × c) products of row-major matrices.
        let mul = |x: &[f64], y: &[f64], r: usize, c: usize| -> Vec<f64> {
            (0..r * c).map(|k| (0..q).map(|l| x[(k / c) * q + l] * y[l * c + k % c]).sum()).collect()
        };
        let (b2c1, b2d1, d2c1, d2d1) = (
            mul(&next.b, &self.c, n2, n1),
            mul(&next.b, &self.d, n2, m),
            mul(&next.d, &self.c, p, n1),
            mul(&next.d, &self.d, p, m),
        );
        let mut a = vec![0.0; n * n];
        for i in 0..n1 {
            a[i * n..i * n + n1].copy_from_slice(&self.a[i * n1..(i + 1) * n1]);
        }
        for i in 0..n2 {
            let row = (n1 + i) * n;
            a[row..row + n1].copy_from_slice(&b2c1[i * n1..(i + 1) * n1]);
            a[row + n1..row + n].copy_from_slice(&next.a[i * n2..(i + 1) * n2]);
        }
        let b = [self.b.as_slice(), &b2d1].concat();
        let mut c = vec![0.0; p * n];
        for i in 0..p {
            c[i * n..i * n + n1].copy_from_slice(&d2c1[i * n1..(i + 1) * n1]);
            c[i * n + n1..(i + 1) * n].copy_from_slice(&next.c[i * n2..(i + 1) * n2]);
        }
        Ok(StateSpace { n, m, p, a, b, c, d: d2d1 })
    }
}

/// `gain · Π num[i](s) / Π den[j](s)`, each factor in descending powers,
/// as a cascade of sections. Numerator factors are placed highest degree
/// first, each in the first denominator section (in the order written)
/// with room left. A single factor over a single factor, a zero numerator
/// factor, or a numerator
/// factor that fits no section (a quadratic zero factor over first-order
/// poles only), is realised from the expanded polynomials in companion
/// form, as [`tf2ss`] does.
pub fn factored_tf2ss(num: &[Vec<f64>], den: &[Vec<f64>], gain: f64) -> Result<StateSpace, LtiError> {
    let trimmed = |fs: &[Vec<f64>]| fs.iter().map(|f| poly::trim_leading_zeros(f).to_vec()).collect::<Vec<_>>();
    let (num, den) = (trimmed(num), trimmed(den));
    if den.iter().any(Vec::is_empty) {
        return Err(LtiError::ZeroDenominator);
    }
    let degree = |fs: &[Vec<f64>]| fs.iter().map(|f| f.len().saturating_sub(1)).sum::<usize>();
    let (nn, nd) = (degree(&num), degree(&den));
    if nd.max(nn) > MAX_ORDER {
        return Err(LtiError::TooHigh { degree: nd.max(nn) });
    }
    if nn > nd {
        return Err(LtiError::Improper { num_degree: nn, den_degree: nd });
    }
    // A zero numerator factor makes the zero system, which the expanded form gives.
    let cascade = (num.len() > 1 || den.len() > 1) && !num.iter().any(Vec::is_empty);
    let Some(sections) = cascade.then(|| pair(&num, &den)).flatten() else {
        let scaled: Vec<f64> = poly::product(&num).iter().map(|c| c * gain).collect();
        return tf2ss(&scaled, &poly::product(&den));
    };
    let mut total = gain;
    let mut cascade: Option<StateSpace> = None;
    for (zeros, poles) in sections {
        let (mut n, d) = (poly::product(&zeros), poles);
        // Unit DC gain per section where it is finite and nonzero.
        let (n0, d0) = (n[n.len() - 1], d[d.len() - 1]);
        if n0 != 0.0 && d0 != 0.0 {
            n.iter_mut().for_each(|c| *c *= d0 / n0);
            total *= n0 / d0;
        }
        let section = tf2ss(&n, &d)?;
        cascade = Some(match cascade {
            None => section,
            Some(before) => before.series(&section)?,
        });
    }
    let mut ss = cascade.unwrap_or_else(|| tf2ss(&[1.0], &[1.0]).expect("a unit gain"));
    ss.c.iter_mut().chain(ss.d.iter_mut()).for_each(|v| *v *= total);
    Ok(ss)
}

/// One section: its numerator factors and its denominator.
type Section = (Vec<Vec<f64>>, Vec<f64>);

/// Each denominator factor with the numerator factors placed in it, or
/// `None` when a numerator factor fits in no section.
fn pair(num: &[Vec<f64>], den: &[Vec<f64>]) -> Option<Vec<Section>> {
    let mut sections: Vec<Section> = den.iter().map(|d| (Vec::new(), d.clone())).collect();
    let mut room: Vec<usize> = den.iter().map(|d| d.len() - 1).collect();
    let mut order: Vec<usize> = (0..num.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(num[i].len()));
    let mut constant = 1.0;
    for i in order {
        let deg = num[i].len() - 1;
        if deg == 0 {
            constant *= num[i][0];
            continue;
        }
        let s = room.iter().position(|&r| r >= deg)?;
        room[s] -= deg;
        sections[s].0.push(num[i].clone());
    }
    if let Some(first) = sections.first_mut() {
        first.0.push(vec![constant]);
    } else if constant != 1.0 {
        sections.push((vec![vec![constant]], vec![1.0]));
    }
    Some(sections)
}

#[cfg(test)]
mod tests;
