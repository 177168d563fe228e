//! Online estimation: recursive least squares with a forgetting factor,
//! for ARX/FIR models y(k) = φ(k)ᵀθ + e(k) (the contact-force paper's
//! identification of md, bd, kd, eq. 8–10).

use crate::table::*;
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};

pub const TYPES: &[BlockType] = &[BlockType {
    name: "rls",
    category: "estimation",
    summary: "Recursive least squares with forgetting: θ̂ from regressors φ and output y.",
    doc: "At each sample: e = y − φᵀθ̂, K = Pφ/(λ + φᵀPφ), θ̂ += K·e, P = (P − KφᵀP)/λ, with \
          P(0) = p0·I and θ̂(0) = `initial`. λ = 1 is ordinary least squares; λ < 1 forgets old data \
          with time constant about T/(1 − λ). Build φ from delayed signals (unit_delay, mux) for an \
          ARX model. Outputs θ̂ (after the update of the previous sample: no direct feedthrough) \
          and the a-priori prediction error e.\n\
          Stable region: 0 < λ <= 1, p0 > 0, persistently exciting φ; then θ̂ converges to the \
          true parameters of a noise-free model.",
    inputs: &[PortDoc { name: "phi", doc: "regressor vector, width n" }, PortDoc { name: "y", doc: "measured output" }],
    outputs: &[
        PortDoc { name: "theta", doc: "estimate, width n" },
        PortDoc { name: "error", doc: "a-priori prediction error y − φᵀθ̂" },
    ],
    params: &[
        param("n", Required, "number of parameters").kind(ParamKind::Number),
        param("lambda", Number(1.0), "forgetting factor, 0 < λ <= 1"),
        param("p0", Number(1e4), "initial covariance P(0) = p0·I"),
        param("initial", Number(0.0), "θ̂(0): a number or n numbers").kind(ParamKind::Numbers),
        crate::SAMPLE_TIME_REQUIRED,
    ],
    build: build_rls,
}];

/// The RLS estimator; all buffers allocated once.
#[derive(Clone)]
pub struct Rls {
    lambda: f64,
    p0: f64,
    initial: Vec<f64>,
    theta: Vec<f64>,
    p: Vec<f64>,
    k: Vec<f64>,
    p_phi: Vec<f64>,
    phi: Vec<f64>,
    error: f64,
}

impl Rls {
    pub fn new(n: usize, lambda: f64, p0: f64, initial: Vec<f64>) -> Self {
        let mut rls = Rls {
            lambda,
            p0,
            theta: initial.clone(),
            initial,
            p: vec![0.0; n * n],
            k: vec![0.0; n],
            p_phi: vec![0.0; n],
            phi: vec![0.0; n],
            error: 0.0,
        };
        rls.reset();
        rls
    }

    fn reset(&mut self) {
        let n = self.theta.len();
        self.theta.copy_from_slice(&self.initial);
        self.p.iter_mut().enumerate().for_each(|(i, v)| *v = if i % (n + 1) == 0 { self.p0 } else { 0.0 });
        self.error = 0.0;
    }

    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// One update with regressor `phi` and measurement `y`.
    pub fn step(&mut self, phi: &[f64], y: f64) {
        let n = self.theta.len();
        for i in 0..n {
            self.p_phi[i] = (0..n).map(|j| self.p[i * n + j] * phi[j]).sum();
        }
        let denom = self.lambda + phi.iter().zip(&self.p_phi).map(|(a, b)| a * b).sum::<f64>();
        self.error = y - phi.iter().zip(&self.theta).map(|(a, b)| a * b).sum::<f64>();
        for i in 0..n {
            self.k[i] = self.p_phi[i] / denom;
            self.theta[i] += self.k[i] * self.error;
        }
        // P = (P − K (Pφ)ᵀ)/λ; P symmetric, so φᵀP = (Pφ)ᵀ.
        for i in 0..n {
            for j in 0..n {
                self.p[i * n + j] = (self.p[i * n + j] - self.k[i] * self.p_phi[j]) / self.lambda;
            }
        }
    }
}

impl Block for Rls {
    rust_type!(Rls);
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.reset();
    }
    fn output(&mut self, io: &mut Io) {
        io.set_all(0, &self.theta);
        io.set(1, self.error);
    }
    fn update(&mut self, io: &mut Io) {
        // Taking the buffer out (no allocation) lets `step` borrow self.
        let mut phi = std::mem::take(&mut self.phi);
        phi.copy_from_slice(io.input(0));
        self.step(&phi, io.u(1));
        self.phi = phi;
    }
}

fn build_rls(p: &mut Params) -> Result<Built, Diagnostic> {
    let n = p.count("n", 100)?;
    let lambda = p.number_where("lambda", None, |v| v > 0.0 && v <= 1.0, "in (0, 1]")?;
    let p0 = p.number_where("p0", None, |v| v > 0.0 && v.is_finite(), "positive")?;
    let initial = p.vector("initial")?;
    let initial = crate::continuous::initial_vector(&initial, n).map_err(|m| p.error("initial", m))?;
    let st = p.discrete_sample_time()?;
    let iface = Interface::new(st)
        .input("phi", Width::Fixed(n), false)
        .input("y", Width::Fixed(1), false)
        .output("theta", Width::Fixed(n))
        .output("error", Width::Fixed(1));
    Ok(Built::new(Rls::new(n, lambda, p0, initial), iface))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifies_an_arx_model() {
        // y(k) = 1.5 y(k−1) − 0.7 y(k−2) + 0.5 u(k−1), u a deterministic
        // rich signal: θ = [1.5, −0.7, 0.5] exactly, no noise.
        let mut rls = Rls::new(3, 1.0, 1e6, vec![0.0; 3]);
        let (mut y1, mut y2, mut u1) = (0.0, 0.0, 0.0);
        for k in 0..400 {
            let u = (0.37 * k as f64).sin() + (1.3 * k as f64).cos();
            let y = 1.5 * y1 - 0.7 * y2 + 0.5 * u1;
            rls.step(&[y1, y2, u1], y);
            (y2, y1, u1) = (y1, y, u);
        }
        for (got, want) in rls.theta().iter().zip([1.5, -0.7, 0.5]) {
            assert!((got - want).abs() < 1e-6, "{got} vs {want}");
        }
    }

    #[test]
    fn forgetting_tracks_a_parameter_change() {
        let mut rls = Rls::new(1, 0.95, 1e3, vec![0.0]);
        for k in 0..600 {
            let phi = 1.0 + 0.5 * (0.3 * k as f64).sin();
            let gain = if k < 300 { 2.0 } else { 3.0 };
            rls.step(&[phi], gain * phi);
        }
        assert!((rls.theta()[0] - 3.0).abs() < 1e-6);
    }

    #[test]
    fn the_block_outputs_the_estimate_and_error_before_each_update() {
        // n = 1, P0 = 1, λ = 1, θ0 = 0.5; φ = 2, y = 3:
        // e = 3 − 1 = 2, K = P0 φ/(λ + φ P0 φ) = 2/5, θ = 0.5 + 0.8 = 1.3, P = (1 − 0.8)/1 = 0.2.
        use ctlgraph_core::block::Port;
        let (ins, outs) = (
            [Port { offset: 0, width: 1 }, Port { offset: 1, width: 1 }],
            [Port { offset: 2, width: 1 }, Port { offset: 3, width: 1 }],
        );
        let mut rls = Rls::new(1, 1.0, 1.0, vec![0.5]);
        rls.step(&[9.0], 9.0);
        rls.initialize(&mut []);
        let mut signals = [2.0, 3.0, f64::NAN, f64::NAN];
        let mut step = |rls: &mut Rls| {
            let mut io = Io::new(0.0, false, &[], &mut signals, &ins, &outs);
            rls.output(&mut io);
            rls.update(&mut io);
            [signals[2], signals[3]]
        };
        assert_eq!(step(&mut rls), [0.5, 0.0]);
        let [theta, error] = step(&mut rls);
        assert!((theta - 1.3).abs() < 1e-15 && (error - 2.0).abs() < 1e-15, "{theta} {error}");
        // The second update: Pφ = 0.4, K = 0.4/1.8, P = 0.2 − 0.4·0.4/1.8 = 1/9.
        assert!((rls.p[0] - 1.0 / 9.0).abs() < 1e-15, "{}", rls.p[0]);
    }
}
