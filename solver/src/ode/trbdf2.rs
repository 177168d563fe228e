//! TR-BDF2, the implicit one-step method of MATLAB's `ode23tb`, after Bank,
//! Coughran, Fichtner, Grosse, Rose & Smith (1985) and Hosea & Shampine,
//! "Analysis and implementation of TR-BDF2", Appl. Numer. Math. 20 (1996).
//!
//! With γ = 2 − √2 and d = γ/2, one step from (tₙ, yₙ) of size h solves
//!
//! - trapezoidal stage: z − d·h·f(tₙ + γh, z) = yₙ + d·h·fₙ
//! - BDF2 stage: y − d·h·f(tₙ + h, y) = [z − (1 − γ)²·yₙ] / (γ(2 − γ))
//!
//! (both with the same Newton matrix I − d·h·J, since (1 − γ)/(2 − γ) = γ/2).
//! The local error is estimated as
//! h·(−3γ² + 4γ − 2)/(6(2 − γ))·[fₙ/γ − f_z/(γ(1 − γ)) + fₙ₊₁/(1 − γ)],
//! a divided difference of f that is exact for the method's leading error
//! term C·h³·y''', and is filtered through (I − d·h·J)⁻¹ (Shampine's
//! device, as Radau5 and the Rosenbrock codes do) so stiff components that
//! are correctly damped do not force tiny steps.
//!
//! Newton is the simplified iteration: J is a forward-difference Jacobian
//! at the start of some step, reused with its LU while iterations converge;
//! a failed iteration first refreshes J (if old), then quarters the step.

use super::{Integrator, OdeSystem, SolverError, Stats, Tolerance, next_step, scaled_rms, trial_step};
use crate::dense_lu::DenseLu;

const GAMMA: f64 = 2.0 - std::f64::consts::SQRT_2;
const D: f64 = GAMMA / 2.0;
/// Leading error constant times 2 (see the module docs).
const ERR: f64 = (-3.0 * GAMMA * GAMMA + 4.0 * GAMMA - 2.0) / (6.0 * (2.0 - GAMMA));
/// Newton iterations per stage before giving up.
const MAX_NEWTON: usize = 6;
/// Newton stops when the estimated remaining error is below this fraction
/// of the error tolerance.
const NEWTON_TOL: f64 = 0.03;

/// The Newton matrix and its factors, with the scratch a solve needs.
#[derive(Clone)]
struct Linear {
    lu: DenseLu,
    /// Jacobian, column-major.
    jac: Vec<f64>,
    /// Step size the LU was factored for (0: none).
    lu_h: f64,
    /// Whether `jac` was computed at the start of the current step.
    jac_fresh: bool,
    delta: Vec<f64>,
}

/// Work space of the implicit method, allocated once.
#[derive(Clone)]
pub(crate) struct Work {
    lin: Linear,
    /// f at the start of the current step (at the end of the last one).
    pub(crate) f0: Vec<f64>,
    /// f at the start of the last step, for the dense output.
    pub(crate) f_prev: Vec<f64>,
    fz: Vec<f64>,
    f1: Vec<f64>,
    z: Vec<f64>,
    y: Vec<f64>,
    rhs: Vec<f64>,
    xp: Vec<f64>,
}

impl Work {
    pub(crate) fn new(n: usize) -> Self {
        let v = || vec![0.0; n];
        Work {
            lin: Linear { lu: DenseLu::new(n), jac: vec![0.0; n * n], lu_h: 0.0, jac_fresh: false, delta: v() },
            f0: v(),
            f_prev: v(),
            fz: v(),
            f1: v(),
            z: v(),
            y: v(),
            rhs: v(),
            xp: v(),
        }
    }

    /// Forgets the Jacobian and its factors.
    pub(crate) fn reset(&mut self) {
        self.lin.lu_h = 0.0;
        self.lin.jac_fresh = false;
    }
}

impl Integrator {
    /// One accepted TR-BDF2 step from `t` towards `t_limit` (see the module docs).
    pub(super) fn trbdf2(
        &mut self,
        sys: &mut dyn OdeSystem,
        t: f64,
        t_limit: f64,
        x: &mut [f64],
        tol: Tolerance,
    ) -> Result<f64, SolverError> {
        let Some(mut w) = self.implicit.take() else {
            unreachable!("Integrator::new allocates the implicit work space for trbdf2")
        };
        let result = self.trbdf2_step(sys, &mut w, t, t_limit, x, tol);
        self.implicit = Some(w);
        result
    }

    fn trbdf2_step(
        &mut self,
        sys: &mut dyn OdeSystem,
        w: &mut Work,
        t: f64,
        t_limit: f64,
        x: &mut [f64],
        tol: Tolerance,
    ) -> Result<f64, SolverError> {
        let Tolerance { rtol, atol, max_step, initial_step } = tol;
        if !self.fsal_valid {
            self.stats.evaluations += 1;
            sys.derivatives_at_start(t, x, &mut w.f0);
            self.fsal_valid = true;
            // Derivatives jumped (an event or a sample hit): the old
            // Jacobian may describe another mode.
            w.reset();
        }
        if self.h_next <= 0.0 {
            self.h_next = match initial_step {
                Some(h) => h,
                None => {
                    self.k[0].copy_from_slice(&w.f0);
                    self.initial_step(sys, t, x, rtol, atol, max_step)
                }
            };
        }
        if w.lin.lu_h == 0.0 && !w.lin.jac_fresh {
            jacobian(&mut self.stats, sys, w, t, x, rtol, atol);
        }
        let mut h = self.h_next.min(max_step);
        loop {
            let (landing, t_new) = trial_step(t, t_limit, &mut h, self.worst)?;
            if w.lin.lu_h != h && !factor(&mut self.stats, &mut w.lin, h) {
                return Err(SolverError::Singular { t });
            }
            // Trapezoidal stage from the explicit guess z = x + γh·f0.
            for i in 0..x.len() {
                w.rhs[i] = x[i] + D * h * w.f0[i];
                w.z[i] = x[i] + GAMMA * h * w.f0[i];
            }
            let mut converged =
                newton(&mut self.stats, sys, &mut w.lin, t + GAMMA * h, h, &mut w.z, &mut w.fz, &w.rhs, rtol, atol);
            if converged.is_ok() {
                // BDF2 stage from the line through (t, x) and (t + γh, z).
                let a = 1.0 / (GAMMA * (2.0 - GAMMA));
                let b = (1.0 - GAMMA) * (1.0 - GAMMA) * a;
                for i in 0..x.len() {
                    w.rhs[i] = a * w.z[i] - b * x[i];
                    w.y[i] = w.z[i] + (1.0 - GAMMA) / GAMMA * (w.z[i] - x[i]);
                }
                converged = newton(&mut self.stats, sys, &mut w.lin, t_new, h, &mut w.y, &mut w.f1, &w.rhs, rtol, atol);
            }
            if let Err(unsettled) = converged {
                self.worst = Some(unsettled);
                self.stats.newton_failures += 1;
                if w.lin.jac_fresh {
                    h *= 0.25;
                } else {
                    jacobian(&mut self.stats, sys, w, t, x, rtol, atol);
                }
                w.lin.lu_h = 0.0;
                continue;
            }
            // Error estimate, filtered through the Newton matrix.
            for i in 0..x.len() {
                w.lin.delta[i] =
                    h * ERR * (w.f0[i] / GAMMA - w.fz[i] / (GAMMA * (1.0 - GAMMA)) + w.f1[i] / (1.0 - GAMMA));
            }
            w.lin.lu.solve(&mut w.lin.delta);
            let (err, largest) = scaled_rms(w.lin.delta.iter().copied(), x, &w.y, rtol, atol);
            if !err.is_finite() {
                let state = (0..x.len()).find(|&i| !w.y[i].is_finite() || !w.lin.delta[i].is_finite());
                return Err(SolverError::NonFinite { t, state });
            }
            self.worst = Some(largest);
            if err <= 1.0 {
                let factor = if err == 0.0 { 5.0 } else { (0.9 * err.powf(-1.0 / 3.0)).clamp(0.2, 5.0) };
                // Keep the step (and its LU) when it would grow only a little.
                let factor = if (1.0..1.2).contains(&factor) { 1.0 } else { factor };
                self.h_next = next_step(h, factor, max_step, landing, self.h_next);
                x.copy_from_slice(&w.y);
                // f at the new point is the BDF2 stage's last evaluation.
                std::mem::swap(&mut w.f_prev, &mut w.f0);
                std::mem::swap(&mut w.f0, &mut w.f1);
                w.lin.jac_fresh = false;
                self.stats.steps += 1;
                return Ok(t_new);
            }
            self.stats.rejected += 1;
            h *= (0.9 * err.powf(-1.0 / 3.0)).clamp(0.2, 0.9);
        }
    }
}

/// Simplified Newton for `v − d·h·f(tv, v) = rhs` from the guess in `v`.
/// On convergence `fv` holds f at the final `v`; on failure the error is the
/// component with the largest scaled update (the one that did not settle).
#[allow(clippy::too_many_arguments)]
fn newton(
    stats: &mut Stats,
    sys: &mut dyn OdeSystem,
    lin: &mut Linear,
    tv: f64,
    h: f64,
    v: &mut [f64],
    fv: &mut [f64],
    rhs: &[f64],
    rtol: f64,
    atol: f64,
) -> Result<(), usize> {
    let (mut previous, mut unsettled) = (f64::INFINITY, 0);
    for iteration in 0..MAX_NEWTON {
        stats.evaluations += 1;
        sys.derivatives(tv, v, fv);
        for i in 0..v.len() {
            lin.delta[i] = rhs[i] - v[i] + D * h * fv[i];
        }
        lin.lu.solve(&mut lin.delta);
        let (norm, worst) = scaled_rms(lin.delta.iter().copied(), v, v, rtol, atol);
        if !norm.is_finite() {
            return Err(lin.delta.iter().position(|d| !d.is_finite()).unwrap_or(worst));
        }
        for i in 0..v.len() {
            v[i] += lin.delta[i];
        }
        // A contraction with rate θ leaves at most ‖δ‖·θ/(1 − θ) to go.
        let done = if iteration == 0 {
            norm <= 1e-3 * NEWTON_TOL
        } else {
            let rate = norm / previous;
            if rate >= 0.9 {
                return Err(worst);
            }
            norm * rate / (1.0 - rate) <= NEWTON_TOL
        };
        if done {
            stats.evaluations += 1;
            sys.derivatives(tv, v, fv);
            return Ok(());
        }
        previous = norm;
        unsettled = worst;
    }
    Err(unsettled)
}

/// Forward-difference Jacobian of f at (t, x), from `w.f0 = f(t, x)`.
fn jacobian(stats: &mut Stats, sys: &mut dyn OdeSystem, w: &mut Work, t: f64, x: &[f64], rtol: f64, atol: f64) {
    let n = x.len();
    w.xp.copy_from_slice(x);
    // Below |x| ≈ atol/rtol absolute error control dominates: perturb on
    // that scale there.
    let floor = (atol / rtol.max(f64::EPSILON)).max(1e-300);
    for j in 0..n {
        w.xp[j] = x[j] + f64::EPSILON.sqrt() * x[j].abs().max(floor);
        let dx = w.xp[j] - x[j];
        stats.evaluations += 1;
        sys.derivatives(t, &w.xp, &mut w.f1);
        for i in 0..n {
            w.lin.jac[j * n + i] = (w.f1[i] - w.f0[i]) / dx;
        }
        w.xp[j] = x[j];
    }
    stats.jacobians += 1;
    w.lin.jac_fresh = true;
}

/// Factors I − d·h·J; false when singular.
fn factor(stats: &mut Stats, lin: &mut Linear, h: f64) -> bool {
    let n = lin.delta.len();
    for (k, (m, j)) in lin.lu.matrix_mut().iter_mut().zip(&lin.jac).enumerate() {
        *m = if k % (n + 1) == 0 { 1.0 } else { 0.0 } - D * h * j;
    }
    stats.factorizations += 1;
    lin.lu_h = h;
    lin.lu.factor()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constants_in_closed_form() {
        // With γ = 2 − √2: −3γ² + 4γ − 2 = 8√2 − 12 and 6(2 − γ) = 6√2, so the error
        // constant is 4/3 − √2; d = 1 − 1/√2; and (1 − γ)/(2 − γ) = d (one Newton matrix).
        let sqrt2 = std::f64::consts::SQRT_2;
        assert!((ERR - (4.0 / 3.0 - sqrt2)).abs() < 1e-15, "{ERR}");
        assert!((D - (1.0 - 1.0 / sqrt2)).abs() < 1e-15);
        assert!(((1.0 - GAMMA) / (2.0 - GAMMA) - D).abs() < 1e-15);
    }
}
