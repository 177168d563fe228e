//! The discrete Kalman filter (Kalman, "A New Approach to Linear Filtering
//! and Prediction Problems", 1960), in the filter form of Simulink's
//! Kalman Filter block: the estimate at a sample uses that sample's
//! measurement.

mod riccati;

use crate::{SAMPLE_TIME_REQUIRED, table::*};
use ctlgraph_core::dense::{Mat, solve_in_place};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};
use riccati::steady_state_covariance;

pub const TYPES: &[BlockType] = &[BlockType {
    name: "kalman_filter",
    category: "estimation",
    summary: "Discrete linear Kalman filter: the state estimate x̂ and the innovation.",
    doc: "For the plant x(k+1) = A x(k) + B u(k) + w(k), y(k) = C x(k) + D u(k) + v(k), with w and \
          v white, zero-mean, of covariances Q and R, at every sample k:\n\
          \x20 innovation e = y − C x̂⁻ − D u,  S = C P⁻ Cᵀ + R,  K = P⁻ Cᵀ S⁻¹\n\
          \x20 x̂ = x̂⁻ + K e   (output: the estimate x̂(k|k) from this sample's measurement)\n\
          \x20 P = (I − K C) P⁻ (I − K C)ᵀ + K R Kᵀ   (Joseph's form: stays symmetric and positive)\n\
          \x20 then the prediction x̂⁻ = A x̂ + B u,  P⁻ = A P Aᵀ + Q\n\
          starting from x̂⁻ = x0 and P⁻ = P0. `gain: steady_state` uses instead the constant gain of \
          the stationary P⁻, the solution of the discrete algebraic Riccati equation \
          P⁻ = A P⁻ Aᵀ − A P⁻ Cᵀ (C P⁻ Cᵀ + R)⁻¹ C P⁻ Aᵀ + Q (solved once, by the structured doubling \
          algorithm), for a detectable (A, C). Without B the block has no input u.",
    inputs: &[
        PortDoc { name: "u", doc: "width = columns of B; only with B" },
        PortDoc { name: "y", doc: "the measurement, width = rows of C" },
    ],
    outputs: &[
        PortDoc { name: "xhat", doc: "x̂(k|k), width n = rows of A" },
        PortDoc { name: "innovation", doc: "e = y − C x̂⁻ − D u, width = rows of C" },
    ],
    params: &[
        param("A", Required, "n×n").kind(ParamKind::Matrix),
        param("B", Described("none"), "n×m; without it, no input u").kind(ParamKind::Matrix),
        param("C", Required, "p×n").kind(ParamKind::Matrix),
        param("D", Described("0"), "p×m (with B)").kind(ParamKind::Matrix),
        param("Q", Required, "n×n process noise covariance, symmetric, positive semidefinite").kind(ParamKind::Matrix),
        param("R", Required, "p×p measurement noise covariance, symmetric, positive definite").kind(ParamKind::Matrix),
        param("P0", Described("Q"), "n×n covariance of x0's error").kind(ParamKind::Matrix),
        param("x0", Number(0.0), "the initial prediction x̂⁻(0): a number or n numbers").kind(ParamKind::Numbers),
        param("gain", Word("time_varying"), "time_varying | steady_state").options(&["time_varying", "steady_state"]),
        SAMPLE_TIME_REQUIRED,
    ],
    build: build_kalman,
}];

#[derive(Clone)]
pub struct KalmanFilter {
    a: Mat,
    b: Option<Mat>,
    c: Mat,
    d: Option<Mat>,
    q: Mat,
    r: Mat,
    p0: Mat,
    x0: Vec<f64>,
    /// Kᵀ of the stationary filter (`gain: steady_state`), else `None`.
    steady_gain_t: Option<Mat>,
    /// The prediction for the present sample: x̂⁻ and P⁻.
    x_pred: Vec<f64>,
    p_pred: Mat,
    /// Working space, sized at build: the corrected estimate and
    /// covariance, the innovation, Kᵀ, C P⁻, S and two n×n products.
    x_filt: Vec<f64>,
    p_filt: Mat,
    innovation: Vec<f64>,
    gain_t: Mat,
    cp: Mat,
    s: Mat,
    work: Mat,
    work2: Mat,
}

impl KalmanFilter {
    /// The inputs u (empty without B) and y.
    fn inputs<'a>(&self, io: &'a Io) -> (&'a [f64], &'a [f64]) {
        if self.b.is_some() { (io.input(0), io.input(1)) } else { (&[], io.input(0)) }
    }

    /// The correction at this sample: the innovation, Kᵀ and x̂ (into the
    /// working space; the prediction is left as it is).
    fn correct(&mut self, u: &[f64], y: &[f64]) {
        let (n, p) = (self.a.rows, self.c.rows);
        for (i, &yi) in y.iter().enumerate().take(p) {
            let mut e = yi - self.c.row(i).iter().zip(&self.x_pred).map(|(c, x)| c * x).sum::<f64>();
            if let Some(d) = &self.d {
                e -= d.row(i).iter().zip(u).map(|(d, u)| d * u).sum::<f64>();
            }
            self.innovation[i] = e;
        }
        match &self.steady_gain_t {
            Some(k) => self.gain_t.data.copy_from_slice(&k.data),
            None => {
                // C P⁻ (p×n), S = (C P⁻) Cᵀ + R, then S Kᵀ = C P⁻ (S and P⁻ symmetric).
                self.cp.set_product(&self.c, &self.p_pred);
                self.s.set_product_transposed(&self.cp, &self.c);
                self.s.add(&self.r);
                self.gain_t.data.copy_from_slice(&self.cp.data);
                // S = C P⁻ Cᵀ + R is positive definite by construction (R is).
                solve_in_place(&mut self.s, &mut self.gain_t);
            }
        }
        for i in 0..n {
            let correction: f64 = (0..p).map(|j| self.gain_t.at(j, i) * self.innovation[j]).sum();
            self.x_filt[i] = self.x_pred[i] + correction;
        }
    }

    /// P = (I − K C) P⁻ (I − K C)ᵀ + K R Kᵀ, symmetrised.
    fn correct_covariance(&mut self) {
        let (n, p) = (self.a.rows, self.c.rows);
        // work = I − K C
        for i in 0..n {
            for k in 0..n {
                let kc: f64 = (0..p).map(|j| self.gain_t.at(j, i) * self.c.at(j, k)).sum();
                *self.work.at_mut(i, k) = if i == k { 1.0 } else { 0.0 } - kc;
            }
        }
        self.work2.set_product(&self.work, &self.p_pred);
        self.p_filt.set_product_transposed(&self.work2, &self.work);
        for i in 0..n {
            for k in 0..n {
                let mut krk = 0.0;
                for j in 0..p {
                    for l in 0..p {
                        krk += self.gain_t.at(j, i) * self.r.at(j, l) * self.gain_t.at(l, k);
                    }
                }
                *self.p_filt.at_mut(i, k) += krk;
            }
        }
        self.p_filt.symmetrise();
    }
}

impl Block for KalmanFilter {
    rust_type!(KalmanFilter);
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.x_pred.copy_from_slice(&self.x0);
        self.p_pred.data.copy_from_slice(&self.p0.data);
    }
    fn output(&mut self, io: &mut Io) {
        let (u, y) = self.inputs(io);
        self.correct(u, y);
        io.set_all(0, &self.x_filt);
        io.set_all(1, &self.innovation);
    }
    fn update(&mut self, io: &mut Io) {
        let (u, y) = self.inputs(io);
        self.correct(u, y);
        if self.steady_gain_t.is_none() {
            self.correct_covariance();
            // P⁻ = A P Aᵀ + Q
            self.work.set_product(&self.a, &self.p_filt);
            self.p_pred.set_product_transposed(&self.work, &self.a);
            self.p_pred.add(&self.q);
            self.p_pred.symmetrise();
        }
        // x̂⁻ = A x̂ + B u
        for i in 0..self.a.rows {
            let mut x = self.a.row(i).iter().zip(&self.x_filt).map(|(a, x)| a * x).sum::<f64>();
            if let Some(b) = &self.b {
                x += b.row(i).iter().zip(u).map(|(b, u)| b * u).sum::<f64>();
            }
            self.x_pred[i] = x;
        }
    }
}

/// A matrix parameter of `rows`×`cols`, or an error at its key.
fn sized(p: &mut Params, key: &str, rows: usize, cols: usize) -> Result<Mat, Diagnostic> {
    let given = p.matrix(key)?;
    let m = Mat::from_rows(&given);
    let ragged = given.iter().any(|r| r.len() != m.cols);
    if ragged || m.rows != rows || m.cols != cols {
        return Err(p.error(key, format!("expected {rows}×{cols}, got {}×{}", m.rows, m.cols)));
    }
    if let Some(v) = m.data.iter().find(|v| !v.is_finite()) {
        return Err(p.error(key, format!("{v} in the matrix: every element must be finite")));
    }
    Ok(m)
}

fn covariance(p: &mut Params, key: &str, n: usize, definite: bool) -> Result<Mat, Diagnostic> {
    let m = sized(p, key, n, n)?;
    if !m.is_symmetric() {
        return Err(p.error(key, "a covariance is symmetric: this matrix is not"));
    }
    // Positive semidefinite: positive definite after a nudge of its scale.
    let scale = m.data.iter().fold(0.0f64, |s, v| s.max(v.abs())).max(f64::MIN_POSITIVE);
    let mut nudged = m.clone();
    if !definite {
        (0..n).for_each(|i| *nudged.at_mut(i, i) += 1e-12 * scale);
    }
    if !nudged.is_positive_definite() {
        let what = if definite { "positive definite" } else { "positive semidefinite" };
        return Err(p.error(key, format!("a covariance here must be {what}: this one is not")));
    }
    Ok(m)
}

fn build_kalman(p: &mut Params) -> Result<Built, Diagnostic> {
    let rows = p.matrix("A")?;
    let n = rows.len();
    if n == 0 {
        return Err(p.error("A", "needs at least one state"));
    }
    let a = sized(p, "A", n, n)?;
    let c_rows = p.matrix("C")?.len();
    let c = sized(p, "C", c_rows, n)?;
    let (b, d) = if p.has("B") {
        let m = p.matrix("B")?.first().map_or(0, Vec::len);
        let b = sized(p, "B", n, m)?;
        let d = if p.has("D") { Some(sized(p, "D", c_rows, m)?) } else { None };
        (Some(b), d)
    } else {
        if p.has("D") {
            return Err(p.error("D", "D multiplies the input u, which only B gives: add B or remove D"));
        }
        (None, None)
    };
    let q = covariance(p, "Q", n, false)?;
    let r = covariance(p, "R", c_rows, true)?;
    let p0 = if p.has("P0") { covariance(p, "P0", n, false)? } else { q.clone() };
    let x0 = p.vector("x0")?;
    let x0 = match x0.len() {
        1 => vec![x0[0]; n],
        len if len == n => x0,
        len => return Err(p.error("x0", format!("expected 1 or {n} numbers, got {len}"))),
    };
    let steady_gain_t = match p.choice("gain", &["time_varying", "steady_state"])? {
        "steady_state" => {
            let pp = steady_state_covariance(&a, &c, &q, &r).map_err(|m| p.error("gain", m))?;
            // Kᵀ = S⁻¹ C P with S = C P Cᵀ + R.
            let cp = c.times(&pp);
            let mut s = cp.times(&c.transpose());
            s.add(&r);
            let mut k_t = cp;
            solve_in_place(&mut s, &mut k_t);
            Some(k_t)
        }
        _ => None,
    };
    let (st, _, _) = p.discrete_clock()?;
    let mut iface = Interface::new(st);
    if let Some(b) = &b {
        let feeds = d.as_ref().is_some_and(|d| d.data.iter().any(|v| *v != 0.0));
        iface = iface.input("u", Width::Fixed(b.cols), feeds);
    }
    let iface = iface
        .input("y", Width::Fixed(c_rows), true)
        .output("xhat", Width::Fixed(n))
        .output("innovation", Width::Fixed(c_rows));
    let block = KalmanFilter {
        x_pred: x0.clone(),
        p_pred: p0.clone(),
        x_filt: vec![0.0; n],
        p_filt: Mat::zeros(n, n),
        innovation: vec![0.0; c_rows],
        gain_t: Mat::zeros(c_rows, n),
        cp: Mat::zeros(c_rows, n),
        s: Mat::zeros(c_rows, c_rows),
        work: Mat::zeros(n, n),
        work2: Mat::zeros(n, n),
        a,
        b,
        c,
        d,
        q,
        r,
        p0,
        x0,
        steady_gain_t,
    };
    Ok(Built::new(block, iface))
}
