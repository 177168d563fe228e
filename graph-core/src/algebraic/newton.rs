//! Solving an algebraic loop's cut equations F(z) = z: Newton's method on
//! the residual r(z) = F(z) − z with a forward-difference Jacobian and a
//! backtracking line search (Dennis and Schnabel, "Numerical Methods for
//! Unconstrained Optimization and Nonlinear Equations", 1983, §6.3), and
//! where Newton stalls (a singular Jacobian, no decrease along its step),
//! Anderson-accelerated fixed-point iteration (Walker and Ni, "Anderson
//! acceleration for fixed-point iterations", SIAM J. Numer. Anal. 49,
//! 2011), the iteration PathSim uses for its loops. All working space is
//! allocated at build: a solve allocates nothing.

use crate::block::Port;
use crate::dense::{Mat, solve_in_place};

/// Newton iterations before falling back to Anderson's.
const NEWTON_ITERATIONS: usize = 50;
/// Halvings of a Newton step in the line search.
const HALVINGS: usize = 12;
/// Anderson iterations, and how many past differences each combines.
const ANDERSON_ITERATIONS: usize = 200;
const ANDERSON_DEPTH: usize = 5;

/// The loop's equations: F at the unknowns z, into f (same layout).
pub(super) trait Equations {
    fn evaluate(&mut self, unknowns: &[Port], z: &[f64], f: &mut [f64]);
}

/// The solver's state and working space.
#[derive(Clone)]
pub(super) struct Newton {
    /// Where the unknowns lie in the loop's buffer, end to end in z.
    unknowns: Vec<Port>,
    tolerance: f64,
    /// The last major step's solution: where each solve starts.
    warm: Vec<f64>,
    z: Vec<f64>,
    f: Vec<f64>,
    r: Vec<f64>,
    trial: Vec<f64>,
    f_trial: Vec<f64>,
    jacobian: Mat,
    step: Mat,
    /// Anderson's past differences of the residual and of F (ring buffers).
    df: Vec<Vec<f64>>,
    dg: Vec<Vec<f64>>,
    normal: Mat,
    gamma: Mat,
    failure: Option<String>,
}

impl Newton {
    pub(super) fn new(unknowns: Vec<Port>, tolerance: f64) -> Newton {
        let n: usize = unknowns.iter().map(|p| p.width).sum();
        let v = || vec![0.0; n];
        Newton {
            unknowns,
            tolerance,
            warm: v(),
            z: v(),
            f: v(),
            r: v(),
            trial: v(),
            f_trial: v(),
            jacobian: Mat::zeros(n, n),
            step: Mat::zeros(n, 1),
            df: vec![v(); ANDERSON_DEPTH],
            dg: vec![v(); ANDERSON_DEPTH],
            normal: Mat::zeros(ANDERSON_DEPTH, ANDERSON_DEPTH),
            gamma: Mat::zeros(ANDERSON_DEPTH, 1),
            failure: None,
        }
    }

    pub(super) fn reset(&mut self) {
        self.warm.iter_mut().for_each(|v| *v = 0.0);
        self.failure = None;
    }

    /// Keeps the solution the buffer holds as the next solve's start.
    pub(super) fn remember(&mut self, buffer: &[f64]) {
        gather(&self.unknowns, buffer, &self.unknowns, &mut self.warm);
    }

    /// Why the last solve failed, if it did.
    pub(super) fn failure(&self) -> Option<&str> {
        self.failure.as_deref()
    }

    /// Whether the residual at z (in `r`) is within the tolerance.
    fn converged(&self, z: &[f64], r: &[f64]) -> bool {
        let size = z.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        norm(r) <= self.tolerance * (1.0 + size)
    }

    /// Solves F(z) = z from the remembered solution. On success the
    /// equations were last evaluated at the solution (the loop's buffer
    /// holds its signals); on failure the reason is kept.
    pub(super) fn solve(&mut self, eq: &mut impl Equations) -> bool {
        self.z.copy_from_slice(&self.warm);
        eq.evaluate(&self.unknowns, &self.z, &mut self.f);
        residual(&self.f, &self.z, &mut self.r);
        let solved = self.converged(&self.z, &self.r) || self.newton(eq) || self.anderson(eq);
        if solved {
            self.failure = None;
        } else {
            self.failure = Some(format!(
                "no solution found: residual {:.3e} after {NEWTON_ITERATIONS} Newton and {ANDERSON_ITERATIONS} \
                 Anderson iterations (tolerance {:.1e})",
                norm(&self.r),
                self.tolerance
            ));
        }
        solved
    }

    /// Damped Newton from z (with F and r evaluated there).
    fn newton(&mut self, eq: &mut impl Equations) -> bool {
        let n = self.z.len();
        for _ in 0..NEWTON_ITERATIONS {
            let before = norm(&self.r);
            if !before.is_finite() {
                return false;
            }
            // J = ∂F/∂z − I by forward differences, column by column.
            for j in 0..n {
                let h = f64::EPSILON.sqrt() * self.z[j].abs().max(1.0);
                self.trial.copy_from_slice(&self.z);
                self.trial[j] += h;
                eq.evaluate(&self.unknowns, &self.trial, &mut self.f_trial);
                for i in 0..n {
                    let d = (self.f_trial[i] - self.f[i]) / h;
                    *self.jacobian.at_mut(i, j) = if i == j { d - 1.0 } else { d };
                }
            }
            self.step.data.iter_mut().zip(&self.r).for_each(|(s, r)| *s = -r);
            if !solve_in_place(&mut self.jacobian, &mut self.step) {
                return false;
            }
            let mut lambda = 1.0;
            let mut accepted = false;
            for _ in 0..HALVINGS {
                for i in 0..n {
                    self.trial[i] = self.z[i] + lambda * self.step.data[i];
                }
                eq.evaluate(&self.unknowns, &self.trial, &mut self.f_trial);
                residual(&self.f_trial, &self.trial, &mut self.r);
                if norm(&self.r) <= (1.0 - 1e-4 * lambda) * before {
                    accepted = true;
                    break;
                }
                lambda *= 0.5;
            }
            if !accepted {
                // Back to z, F and r where the iteration stood.
                eq.evaluate(&self.unknowns, &self.z, &mut self.f);
                residual(&self.f, &self.z, &mut self.r);
                return false;
            }
            std::mem::swap(&mut self.z, &mut self.trial);
            std::mem::swap(&mut self.f, &mut self.f_trial);
            if self.converged(&self.z, &self.r) {
                return true;
            }
        }
        false
    }

    /// Anderson-accelerated iteration z ← F(z) from z (F and r there):
    /// each new z is F's value less the combination of the last
    /// differences of F that best cancels the residual (least squares,
    /// by its normal equations, lightly regularised).
    fn anderson(&mut self, eq: &mut impl Equations) -> bool {
        let n = self.z.len();
        for k in 0..ANDERSON_ITERATIONS {
            // The differences kept so far.
            let depth = k.min(ANDERSON_DEPTH);
            // z_next = F(z) − ΔG γ, γ = argmin |r − ΔF γ|.
            self.trial.copy_from_slice(&self.f);
            if depth > 0 {
                self.normal.rows = depth;
                self.normal.cols = depth;
                self.gamma.rows = depth;
                let scale = self.df[..depth].iter().map(|d| dot(d, d)).fold(0.0, f64::max);
                for a in 0..depth {
                    for b in 0..depth {
                        let reg = if a == b { 1e-12 * scale } else { 0.0 };
                        *self.normal.at_mut(a, b) = dot(&self.df[a], &self.df[b]) + reg;
                    }
                    *self.gamma.at_mut(a, 0) = dot(&self.df[a], &self.r);
                }
                if solve_in_place(&mut self.normal, &mut self.gamma) {
                    for a in 0..depth {
                        let g = self.gamma.data[a];
                        for i in 0..n {
                            self.trial[i] -= g * self.dg[a][i];
                        }
                    }
                }
            }
            eq.evaluate(&self.unknowns, &self.trial, &mut self.f_trial);
            // The newest differences replace the oldest.
            let slot = k % ANDERSON_DEPTH;
            for i in 0..n {
                let r_next = self.f_trial[i] - self.trial[i];
                self.df[slot][i] = r_next - self.r[i];
                self.dg[slot][i] = self.f_trial[i] - self.f[i];
                self.r[i] = r_next;
            }
            std::mem::swap(&mut self.z, &mut self.trial);
            std::mem::swap(&mut self.f, &mut self.f_trial);
            if !norm(&self.r).is_finite() {
                return false;
            }
            if self.converged(&self.z, &self.r) {
                return true;
            }
        }
        false
    }
}

fn residual(f: &[f64], z: &[f64], r: &mut [f64]) {
    for ((r, f), z) in r.iter_mut().zip(f).zip(z) {
        *r = f - z;
    }
}

/// The largest magnitude (NaN if any element is NaN).
fn norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| if x.is_nan() || m.is_nan() { f64::NAN } else { m.max(x.abs()) })
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Where unknown port `port` starts in z.
fn position(unknowns: &[Port], port: &Port) -> Option<usize> {
    let mut start = 0;
    for u in unknowns {
        if u.offset == port.offset {
            return Some(start);
        }
        start += u.width;
    }
    None
}

/// Writes z into the unknowns' places in the buffer.
pub(super) fn scatter(unknowns: &[Port], z: &[f64], buffer: &mut [f64]) {
    let mut start = 0;
    for u in unknowns {
        buffer[u.offset..u.offset + u.width].copy_from_slice(&z[start..start + u.width]);
        start += u.width;
    }
}

/// Writes z's values for `ports` (some of the unknowns) into the buffer.
pub(super) fn scatter_ports(ports: &[Port], unknowns: &[Port], z: &[f64], buffer: &mut [f64]) {
    for p in ports {
        if let Some(start) = position(unknowns, p) {
            buffer[p.offset..p.offset + p.width].copy_from_slice(&z[start..start + p.width]);
        }
    }
}

/// Reads the buffer's values of `ports` (some of the unknowns) into their
/// places in `f`.
pub(super) fn gather(ports: &[Port], buffer: &[f64], unknowns: &[Port], f: &mut [f64]) {
    for p in ports {
        if let Some(start) = position(unknowns, p) {
            f[start..start + p.width].copy_from_slice(&buffer[p.offset..p.offset + p.width]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// F given as a closure over z alone.
    struct Fixed<F: FnMut(&[f64], &mut [f64])>(F, usize);

    impl<F: FnMut(&[f64], &mut [f64])> Equations for Fixed<F> {
        fn evaluate(&mut self, _: &[Port], z: &[f64], f: &mut [f64]) {
            self.1 += 1;
            (self.0)(z, f)
        }
    }

    fn solver(n: usize) -> Newton {
        Newton::new(vec![Port { offset: 0, width: n }], 1e-13)
    }

    #[test]
    fn a_linear_loop_takes_one_newton_step() {
        // y = u − k·y: z = F(z) = 3 − 4 z, root 0.6.
        let mut s = solver(1);
        let mut eq = Fixed(|z: &[f64], f: &mut [f64]| f[0] = 3.0 - 4.0 * z[0], 0);
        assert!(s.solve(&mut eq));
        assert!((s.z[0] - 0.6).abs() < 1e-15, "{}", s.z[0]);
        // The start, one Jacobian column, one trial.
        assert_eq!(eq.1, 3);
    }

    #[test]
    fn a_nonlinear_system_converges_to_its_root() {
        // z0 = cos(z1), z1 = 0.5·sin(z0) + 0.1·z0²: a root near (0.96, 0.50).
        let mut s = solver(2);
        let mut eq = Fixed(
            |z: &[f64], f: &mut [f64]| {
                f[0] = z[1].cos();
                f[1] = 0.5 * z[0].sin() + 0.1 * z[0] * z[0];
            },
            0,
        );
        assert!(s.solve(&mut eq));
        let (a, b) = (s.z[0], s.z[1]);
        assert!((a - b.cos()).abs() < 1e-13 && (b - 0.5 * a.sin() - 0.1 * a * a).abs() < 1e-13);
    }

    /// The fallback alone, on the contraction z = cos(z) in each of three
    /// coupled unknowns: the Dottie number 0.7390851332151607.
    #[test]
    fn anderson_iteration_finds_a_contractions_fixed_point() {
        let mut s = solver(3);
        let mut eq = Fixed(
            |z: &[f64], f: &mut [f64]| {
                f[0] = z[0].cos();
                f[1] = z[1].cos();
                f[2] = z[2].cos() + 0.1 * (z[0] - z[1]);
            },
            0,
        );
        eq.evaluate(&s.unknowns.clone(), &s.z.clone(), &mut s.f);
        residual(&s.f, &s.z, &mut s.r);
        assert!(s.anderson(&mut eq));
        for z in &s.z {
            assert!((z - 0.7390851332151607).abs() < 1e-12, "{:?}", s.z);
        }
        // Plain iteration needs ~70 evaluations to 1e-13; Anderson far fewer.
        assert!(eq.1 < 20, "{} evaluations", eq.1);
    }

    #[test]
    fn a_loop_without_a_solution_fails_and_says_how_close_it_came() {
        // z = z + 1 has no solution.
        let mut s = solver(1);
        let mut eq = Fixed(|z: &[f64], f: &mut [f64]| f[0] = z[0] + 1.0, 0);
        assert!(!s.solve(&mut eq));
        let why = s.failure().unwrap();
        assert!(why.contains("residual 1.000e0"), "{why}");
    }
}
