//! ODE integrators: fixed-step Euler, Heun and classic RK4, the adaptive
//! Dormand–Prince 5(4) pair with embedded error control, and the implicit,
//! L-stable TR-BDF2 for stiff systems (module `trbdf2`).
//!
//! The caller owns the time line. Each call to [`Integrator::advance`] moves
//! the state from `t` towards a limit `t_limit` (the next sample hit, event or
//! stop time) and never past it: the fixed-step methods take exactly one step
//! to `t_limit`, the adaptive method takes one accepted step and lands
//! *exactly* on `t_limit` when it reaches it. All work buffers are allocated
//! in [`Integrator::new`]; stepping allocates nothing.
//!
//! After every step, [`Integrator::interpolate`] evaluates a dense output
//! over it (Dormand–Prince's own continuous extension, cubic Hermite for
//! the others), which the simulator uses to locate zero crossings.

#[cfg(feature = "implicit")]
mod trbdf2;
#[cfg(feature = "implicit")]
use trbdf2::Work as ImplicitWork;

/// Without the implicit method there is no work space for it (an
/// `Option` of this is always `None`).
#[cfg(not(feature = "implicit"))]
#[derive(Clone)]
enum ImplicitWork {}

#[cfg(not(feature = "implicit"))]
impl ImplicitWork {
    fn reset(&mut self) {
        match *self {}
    }
}

mod error;
pub use error::SolverError;

/// A system of first-order ODEs `x' = f(t, x)`.
///
/// `&mut self` because evaluating `f` for a block diagram means computing the
/// outputs of its continuous blocks, which write into the diagram's signal
/// buffer.
pub trait OdeSystem {
    /// Writes `f(t, x)` into `dx` (same length as `x`).
    fn derivatives(&mut self, t: f64, x: &[f64], dx: &mut [f64]);

    /// [`OdeSystem::derivatives`] for a step's first evaluation, at exactly
    /// the `t` and `x` that [`Integrator::advance`] was given (before any
    /// other evaluation in that call): a system that already holds what f
    /// needs there may skip recomputing it.
    fn derivatives_at_start(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        self.derivatives(t, x, dx);
    }
}

/// Integration method and its options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Forward Euler, order 1, fixed step.
    Euler { step: f64 },
    /// Heun's method (explicit trapezoid), order 2, fixed step.
    Heun { step: f64 },
    /// Classic Runge–Kutta, order 4, fixed step.
    Rk4 { step: f64 },
    /// Dormand–Prince 5(4) with local extrapolation (MATLAB's `ode45`).
    /// Error per component is scaled by `atol + rtol·max(|x|, |x_new|)` and
    /// the RMS of the scaled errors must not exceed 1.
    DormandPrince {
        rtol: f64,
        atol: f64,
        max_step: f64,
        /// First trial step; `None` picks one (Hairer, Nørsett & Wanner, II.4).
        initial_step: Option<f64>,
    },
    /// TR-BDF2 (Bank et al. 1985; Hosea & Shampine 1996, MATLAB's
    /// `ode23tb`): a trapezoidal stage then a BDF2 stage, order 2,
    /// L-stable, for stiff systems. Newton iterations with a
    /// finite-difference Jacobian and a dense LU (faer), both reused across
    /// steps while Newton converges. Error control as for Dormand–Prince.
    Trbdf2 { rtol: f64, atol: f64, max_step: f64, initial_step: Option<f64> },
}

impl Method {
    /// The largest step the simulator may ask for in one major step.
    pub fn max_step(&self) -> f64 {
        match *self {
            Method::Euler { step } | Method::Heun { step } | Method::Rk4 { step } => step,
            Method::DormandPrince { max_step, .. } | Method::Trbdf2 { max_step, .. } => max_step,
        }
    }

    /// The `max_step` an adaptive method takes when the graph gives none,
    /// for a run to `stop`: dopri5 samples at least 200 times per run (so
    /// continuous sources are resolved), trbdf2 10 times (its steps are
    /// meant to grow).
    pub fn default_max_step(&self, stop: f64) -> f64 {
        match self {
            Method::DormandPrince { .. } => stop / 200.0,
            Method::Trbdf2 { .. } => stop / 10.0,
            fixed => fixed.max_step(),
        }
    }

    /// The same method with another `max_step` (adaptive methods only).
    pub fn with_max_step(self, h: f64) -> Self {
        match self {
            Method::DormandPrince { rtol, atol, initial_step, .. } => {
                Method::DormandPrince { rtol, atol, max_step: h, initial_step }
            }
            Method::Trbdf2 { rtol, atol, initial_step, .. } => Method::Trbdf2 { rtol, atol, max_step: h, initial_step },
            fixed => fixed,
        }
    }

    /// Whether the method chooses its own step sizes.
    pub fn is_adaptive(&self) -> bool {
        matches!(self, Method::DormandPrince { .. } | Method::Trbdf2 { .. })
    }

    /// Short name, as written in graph files.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Euler { .. } => "euler",
            Method::Heun { .. } => "heun",
            Method::Rk4 { .. } => "rk4",
            Method::DormandPrince { .. } => "dopri5",
            Method::Trbdf2 { .. } => "trbdf2",
        }
    }
}

/// Work counters, reported in run reports. `repr(C)`: an accelerated
/// run's library hands them to the program as they are.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted steps.
    pub steps: u64,
    /// Steps rejected by error control (adaptive method only).
    pub rejected: u64,
    /// Evaluations of `f` (finite-difference Jacobian columns included).
    pub evaluations: u64,
    /// Jacobians computed (implicit method only).
    pub jacobians: u64,
    /// LU factorisations of the Newton matrix (implicit method only).
    pub factorizations: u64,
    /// Newton iterations that failed to converge (implicit method only).
    pub newton_failures: u64,
}

// Dormand–Prince 5(4) tableau (Dormand & Prince 1980; Hairer, Nørsett &
// Wanner, Solving ODEs I, table II.5.2).
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
// Difference between the 5th- and 4th-order weights.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// Dense output of Dormand–Prince (Hairer, Nørsett & Wanner I, II.6; the
// coefficients of Shampine 1986 used by their DOPRI5 code).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// Error-control settings of the adaptive methods.
#[derive(Clone, Copy)]
struct Tolerance {
    rtol: f64,
    atol: f64,
    max_step: f64,
    initial_step: Option<f64>,
}

/// Fits a trial step `h` from `t` to the limit: it lands exactly on
/// `t_limit` when it reaches it, or nearly (a sliver of a step left over
/// would waste a whole step later). Returns whether it lands and where the
/// step ends. `worst` is the component to blame if the step is too small.
fn trial_step(t: f64, t_limit: f64, h: &mut f64, worst: Option<usize>) -> Result<(bool, f64), SolverError> {
    let span = t_limit - t;
    let landing = span - *h < 0.01 * *h; // within 1 % of the limit, or past it
    if landing {
        *h = span;
    }
    if t + *h == t {
        return Err(SolverError::StepTooSmall { t, step: *h, state: worst });
    }
    Ok((landing, if landing { t_limit } else { t + *h }))
}

/// The next step after an accepted one of size `h` whose error ratio gave
/// `factor`. A step cut short to land on a limit says nothing about the
/// step the dynamics allow: keep the larger proposal.
fn next_step(h: f64, factor: f64, max_step: f64, landed: bool, previous: f64) -> f64 {
    let proposal = (h * factor).min(max_step);
    if landed { proposal.max(previous) } else { proposal }
}

/// RMS of `err` scaled by `atol + rtol·max(|a|, |b|)` per component, and
/// the component with the largest scaled error.
fn scaled_rms(err: impl Iterator<Item = f64>, a: &[f64], b: &[f64], rtol: f64, atol: f64) -> (f64, usize) {
    let (mut sum, mut largest, mut worst) = (0.0, 0.0, 0);
    for (i, e) in err.enumerate() {
        let scale = atol + rtol * a[i].abs().max(b[i].abs());
        let r = (e / scale) * (e / scale);
        sum += r;
        if r > largest {
            (largest, worst) = (r, i);
        }
    }
    ((sum / a.len() as f64).sqrt(), worst)
}

/// A stepper with preallocated stage buffers for a system of fixed size.
#[derive(Clone)]
pub struct Integrator {
    method: Method,
    k: [Vec<f64>; 7],
    tmp: Vec<f64>,
    x_new: Vec<f64>,
    /// Next trial step of the adaptive method (0 = not chosen yet).
    h_next: f64,
    /// `k[0]` holds `f(t, x)` from the last accepted step (first same as last).
    fsal_valid: bool,
    /// The component with the largest scaled error at the last error
    /// estimate or failed Newton iteration: when the step collapses, the
    /// state that drove it there.
    worst: Option<usize>,
    stats: Stats,
    /// The last step, for dense output: its start state and time, its length.
    x0: Vec<f64>,
    t0: f64,
    h: f64,
    /// Hermite methods: whether `k[6]` holds `f` at the end of the last step.
    f1_valid: bool,
    /// Work space of the implicit method (`None` for explicit ones).
    implicit: Option<Box<ImplicitWork>>,
}

/// The implicit method's work space, when `method` is it.
fn implicit_work(method: Method, n: usize) -> Option<Box<ImplicitWork>> {
    #[cfg(feature = "implicit")]
    return matches!(method, Method::Trbdf2 { .. }).then(|| Box::new(ImplicitWork::new(n)));
    #[cfg(not(feature = "implicit"))]
    {
        let _ = (method, n);
        None
    }
}

impl Integrator {
    /// Allocates the stage buffers for `n` states.
    pub fn new(method: Method, n: usize) -> Self {
        Integrator {
            method,
            k: std::array::from_fn(|_| vec![0.0; n]),
            tmp: vec![0.0; n],
            x_new: vec![0.0; n],
            h_next: 0.0,
            fsal_valid: false,
            worst: None,
            stats: Stats::default(),
            x0: vec![0.0; n],
            t0: 0.0,
            h: 0.0,
            f1_valid: false,
            implicit: implicit_work(method, n),
        }
    }

    pub fn method(&self) -> Method {
        self.method
    }

    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Forgets step-size history and statistics, for a new run from the
    /// start (keeps the buffers).
    pub fn reset(&mut self) {
        self.h_next = 0.0;
        self.fsal_valid = false;
        self.worst = None;
        self.stats = Stats::default();
        self.h = 0.0;
        if let Some(w) = &mut self.implicit {
            w.reset();
        }
    }

    /// Tells the adaptive method that `f` changed discontinuously at the
    /// current time (a sample hit or an event), so the derivative cached from
    /// the previous step must not be reused.
    pub fn invalidate(&mut self) {
        self.fsal_valid = false;
    }

    /// Advances `x` from `t` towards `t_limit` and returns the new time.
    ///
    /// Fixed-step methods take one step of size `t_limit - t` (the caller
    /// keeps it at most the configured step). The adaptive method takes one
    /// accepted step, no longer than `max_step`, and returns `t_limit` itself
    /// (bit for bit) when it lands there.
    pub fn advance(
        &mut self,
        sys: &mut dyn OdeSystem,
        t: f64,
        t_limit: f64,
        x: &mut [f64],
    ) -> Result<f64, SolverError> {
        if x.is_empty() || t_limit <= t {
            return Ok(t_limit.max(t));
        }
        self.x0.copy_from_slice(x);
        self.t0 = t;
        self.f1_valid = false;
        let t_new = match self.method {
            Method::Euler { .. } => {
                self.euler(sys, t, t_limit, x);
                t_limit
            }
            Method::Heun { .. } => {
                self.heun(sys, t, t_limit, x);
                t_limit
            }
            Method::Rk4 { .. } => {
                self.rk4(sys, t, t_limit, x);
                t_limit
            }
            Method::DormandPrince { rtol, atol, max_step, initial_step } => {
                self.dopri5(sys, t, t_limit, x, Tolerance { rtol, atol, max_step, initial_step })?
            }
            #[cfg(feature = "implicit")]
            Method::Trbdf2 { rtol, atol, max_step, initial_step } => {
                self.trbdf2(sys, t, t_limit, x, Tolerance { rtol, atol, max_step, initial_step })?
            }
            #[cfg(not(feature = "implicit"))]
            Method::Trbdf2 { .. } => return Err(SolverError::NotBuilt { method: "trbdf2" }),
        };
        if !self.method.is_adaptive() {
            self.stats.steps += 1;
        }
        self.h = t_new - t;
        Ok(t_new)
    }

    /// Evaluates the dense output of the last step at `t` (inside it) into
    /// `out`; `x1` is the state the step ended with. Dormand–Prince uses its
    /// fourth-order continuous extension; the other methods a cubic Hermite
    /// interpolant through both ends and their derivatives (one extra
    /// evaluation of `f` at the end, made on first use).
    pub fn interpolate(&mut self, sys: &mut dyn OdeSystem, t: f64, x1: &[f64], out: &mut [f64]) {
        let h = self.h;
        if h <= 0.0 {
            out.copy_from_slice(x1);
            return;
        }
        let th = ((t - self.t0) / h).clamp(0.0, 1.0);
        if let Method::DormandPrince { .. } = self.method {
            // After acceptance k[0] holds k7 and k[6] the step's k1.
            let k = &self.k;
            for i in 0..out.len() {
                let (y0, dy) = (self.x0[i], x1[i] - self.x0[i]);
                let r3 = h * k[6][i] - dy;
                let r4 = dy - h * k[0][i] - r3;
                let r5 = h * (D1 * k[6][i] + D3 * k[2][i] + D4 * k[3][i] + D5 * k[4][i] + D6 * k[5][i] + D7 * k[0][i]);
                out[i] = y0 + th * (dy + (1.0 - th) * (r3 + th * (r4 + (1.0 - th) * r5)));
            }
            return;
        }
        let (f0, f1): (&[f64], &[f64]) = match &self.implicit {
            #[cfg(feature = "implicit")]
            Some(w) => (&w.f_prev, &w.f0),
            #[cfg(not(feature = "implicit"))]
            Some(w) => match **w {},
            None => {
                if !self.f1_valid {
                    self.stats.evaluations += 1;
                    sys.derivatives(self.t0 + h, x1, &mut self.k[6]);
                    self.f1_valid = true;
                }
                (&self.k[0], &self.k[6])
            }
        };
        let (t2, t3) = (th * th, th * th * th);
        let (h00, h10, h01, h11) = (2.0 * t3 - 3.0 * t2 + 1.0, t3 - 2.0 * t2 + th, 3.0 * t2 - 2.0 * t3, t3 - t2);
        for i in 0..out.len() {
            out[i] = h00 * self.x0[i] + h10 * h * f0[i] + h01 * x1[i] + h11 * h * f1[i];
        }
    }

    /// A later stage: f at `t` and the stage's point in `tmp`.
    fn eval(&mut self, sys: &mut dyn OdeSystem, stage: usize, t: f64) {
        self.stats.evaluations += 1;
        sys.derivatives(t, &self.tmp, &mut self.k[stage]);
    }

    /// The first stage, at the point `advance` was given.
    fn eval_start(&mut self, sys: &mut dyn OdeSystem, t: f64, x: &[f64]) {
        self.stats.evaluations += 1;
        sys.derivatives_at_start(t, x, &mut self.k[0]);
    }

    // The fixed-step methods take the step from `t` to `t_end`, and
    // evaluate its last stage at `t_end` itself, the time the next major
    // step has (t + (t_end − t) may differ from it in the last bit), so
    // that a source asked for both computes once.

    fn euler(&mut self, sys: &mut dyn OdeSystem, t: f64, t_end: f64, x: &mut [f64]) {
        let h = t_end - t;
        self.eval_start(sys, t, x);
        for (xi, ki) in x.iter_mut().zip(&self.k[0]) {
            *xi += h * ki;
        }
    }

    fn heun(&mut self, sys: &mut dyn OdeSystem, t: f64, t_end: f64, x: &mut [f64]) {
        let h = t_end - t;
        self.eval_start(sys, t, x);
        self.stage(x, h, &[(0, 1.0)]);
        self.eval(sys, 1, t_end);
        for i in 0..x.len() {
            x[i] += 0.5 * h * (self.k[0][i] + self.k[1][i]);
        }
    }

    fn rk4(&mut self, sys: &mut dyn OdeSystem, t: f64, t_end: f64, x: &mut [f64]) {
        let h = t_end - t;
        self.eval_start(sys, t, x);
        self.stage(x, h, &[(0, 0.5)]);
        self.eval(sys, 1, t + 0.5 * h);
        self.stage(x, h, &[(1, 0.5)]);
        self.eval(sys, 2, t + 0.5 * h);
        self.stage(x, h, &[(2, 1.0)]);
        self.eval(sys, 3, t_end);
        let n = x.len();
        let (k0, k1, k2, k3) = (&self.k[0][..n], &self.k[1][..n], &self.k[2][..n], &self.k[3][..n]);
        for i in 0..n {
            x[i] += h / 6.0 * (k0[i] + 2.0 * k1[i] + 2.0 * k2[i] + k3[i]);
        }
    }

    /// `tmp = x + h · Σ a_j k_j`.
    fn stage(&mut self, x: &[f64], h: f64, terms: &[(usize, f64)]) {
        if let [(j, a)] = *terms {
            // One term (Heun, RK4): zipped, no bounds checks; 0 + a·k as the loop below adds it.
            for ((t, &xi), &kj) in self.tmp.iter_mut().zip(x).zip(&self.k[j]) {
                *t = xi + h * (0.0 + a * kj);
            }
            return;
        }
        for i in 0..x.len() {
            let mut s = 0.0;
            for &(j, a) in terms {
                s += a * self.k[j][i];
            }
            self.tmp[i] = x[i] + h * s;
        }
    }

    fn dopri5(
        &mut self,
        sys: &mut dyn OdeSystem,
        t: f64,
        t_limit: f64,
        x: &mut [f64],
        tol: Tolerance,
    ) -> Result<f64, SolverError> {
        let Tolerance { rtol, atol, max_step, initial_step } = tol;
        if !self.fsal_valid {
            self.eval_start(sys, t, x);
            self.fsal_valid = true;
        }
        if self.h_next <= 0.0 {
            self.h_next = match initial_step {
                Some(h) => h,
                None => self.initial_step(sys, t, x, rtol, atol, max_step),
            };
        }
        let mut h = self.h_next.min(max_step);
        loop {
            let (landing, t_new) = trial_step(t, t_limit, &mut h, self.worst)?;
            self.stage(x, h, &[(0, A21)]);
            self.eval(sys, 1, t + C2 * h);
            self.stage(x, h, &[(0, A31), (1, A32)]);
            self.eval(sys, 2, t + C3 * h);
            self.stage(x, h, &[(0, A41), (1, A42), (2, A43)]);
            self.eval(sys, 3, t + C4 * h);
            self.stage(x, h, &[(0, A51), (1, A52), (2, A53), (3, A54)]);
            self.eval(sys, 4, t + C5 * h);
            self.stage(x, h, &[(0, A61), (1, A62), (2, A63), (3, A64), (4, A65)]);
            self.eval(sys, 5, t_new);
            self.stage(x, h, &[(0, A71), (2, A73), (3, A74), (4, A75), (5, A76)]);
            self.x_new.copy_from_slice(&self.tmp);
            self.stats.evaluations += 1;
            sys.derivatives(t_new, &self.x_new, &mut self.k[6]);

            let k = &self.k;
            let (err, largest) = scaled_rms(
                (0..x.len()).map(|i| {
                    h * (E1 * k[0][i] + E3 * k[2][i] + E4 * k[3][i] + E5 * k[4][i] + E6 * k[5][i] + E7 * k[6][i])
                }),
                x,
                &self.x_new,
                rtol,
                atol,
            );
            if !err.is_finite() {
                let state = (0..x.len()).find(|&i| !self.x_new[i].is_finite() || !self.k[6][i].is_finite());
                return Err(SolverError::NonFinite { t, state });
            }
            self.worst = Some(largest);
            if err <= 1.0 {
                let factor = if err == 0.0 { 5.0 } else { (0.9 * err.powf(-0.2)).clamp(0.2, 5.0) };
                self.h_next = next_step(h, factor, max_step, landing, self.h_next);
                x.copy_from_slice(&self.x_new);
                self.k.swap(0, 6);
                self.stats.steps += 1;
                return Ok(t_new);
            }
            self.stats.rejected += 1;
            h *= (0.9 * err.powf(-0.2)).clamp(0.2, 1.0);
        }
    }

    /// Starting step size after Hairer, Nørsett & Wanner I, II.4 (the
    /// algorithm MATLAB and SciPy use), from `k[0] = f(t, x)`.
    fn initial_step(&mut self, sys: &mut dyn OdeSystem, t: f64, x: &[f64], rtol: f64, atol: f64, max_step: f64) -> f64 {
        let n = x.len() as f64;
        let (mut d0, mut d1) = (0.0, 0.0);
        for i in 0..x.len() {
            let sc = atol + rtol * x[i].abs();
            d0 += (x[i] / sc).powi(2);
            d1 += (self.k[0][i] / sc).powi(2);
        }
        let (d0, d1) = ((d0 / n).sqrt(), (d1 / n).sqrt());
        let h0 = if d0 < 1e-5 || d1 < 1e-5 { 1e-6 } else { 0.01 * d0 / d1 };
        let h0 = h0.min(max_step);
        self.stage(x, h0, &[(0, 1.0)]);
        self.eval(sys, 1, t + h0);
        let mut d2 = 0.0;
        for i in 0..x.len() {
            let sc = atol + rtol * x[i].abs();
            d2 += ((self.k[1][i] - self.k[0][i]) / sc).powi(2);
        }
        let d2 = (d2 / n).sqrt() / h0;
        let h1 = if d1.max(d2) <= 1e-15 { (h0 * 1e-3).max(1e-6) } else { (0.01 / d1.max(d2)).powf(0.2) };
        (100.0 * h0).min(h1).min(max_step)
    }
}

#[cfg(test)]
mod stiff_tests;
#[cfg(test)]
mod tests;
