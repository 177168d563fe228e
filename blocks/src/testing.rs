//! Property testing of blocks (feature `testing`): proptest strategies for
//! the documented stable parameter regions, bounded test inputs, and a
//! harness that runs one block — a library block or your own — on such
//! inputs.
//!
//! ```ignore
//! use ctlgraph_blocks::testing::{self, Harness};
//! proptest::proptest! {
//!     #[test]
//!     fn my_block_is_bounded(u in testing::signal(2.0), gain in 0.1..5.0f64) {
//!         let reg = my_registry();   // the library plus your block types
//!         let trace = Harness::new(&reg, "my_block", &format!("k: {gain}"))
//!             .input(&u)
//!             .run(5.0)
//!             .unwrap();
//!         for y in trace.column("y").unwrap() { proptest::prop_assert!(y.abs() <= gain * u.bound()); }
//!     }
//! }
//! ```

pub mod conformance;

use ctlgraph_core::Registry;
use ctlgraph_core::trace::{Trace, simulate};
use nalgebra::Complex;
use proptest::prelude::*;
use std::f64::consts::PI;

/// A bounded test input: `bias + Σ aᵢ sin(2π fᵢ t + φᵢ) + Σ hⱼ·step(t − tⱼ)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Signal {
    pub bias: f64,
    /// (amplitude, frequency [Hz], phase [rad])
    pub sines: Vec<(f64, f64, f64)>,
    /// (height, time)
    pub steps: Vec<(f64, f64)>,
}

impl Signal {
    /// A constant.
    pub fn constant(v: f64) -> Signal {
        Signal { bias: v, sines: Vec::new(), steps: Vec::new() }
    }

    /// The value at `t`.
    pub fn eval(&self, t: f64) -> f64 {
        let sines: f64 = self.sines.iter().map(|&(a, f, p)| a * (2.0 * PI * f * t + p).sin()).sum();
        let steps: f64 = self.steps.iter().filter(|&&(_, at)| t >= at).map(|&(h, _)| h).sum();
        self.bias + sines + steps
    }

    /// A bound on |signal| for all t.
    pub fn bound(&self) -> f64 {
        self.bias.abs()
            + self.sines.iter().map(|s| s.0.abs()).sum::<f64>()
            + self.steps.iter().map(|s| s.0.abs()).sum::<f64>()
    }

    /// The signal as an expression of `t` for an `fcn` block. Steps are
    /// written with `max(0, sign(t − tⱼ))`, 1 from tⱼ on.
    pub fn expr(&self) -> String {
        let mut s = format!("{:e}", self.bias);
        for &(a, f, p) in &self.sines {
            s.push_str(&format!(" + {a:e}*sin({:e}*t + {p:e})", 2.0 * PI * f));
        }
        for &(h, at) in &self.steps {
            s.push_str(&format!(" + {h:e}*max(0, sign(t - {at:e}))"));
        }
        s
    }
}

/// Bounded signals with |u| <= `bound`: a bias, up to three sines below
/// 20 Hz and up to two steps in the first 4 s.
pub fn signal(bound: f64) -> impl Strategy<Value = Signal> {
    let parts = (
        -1.0..1.0f64,
        prop::collection::vec((0.0..1.0f64, 0.05..20.0f64, 0.0..(2.0 * PI)), 0..=3),
        prop::collection::vec((-1.0..1.0f64, 0.0..4.0f64), 0..=2),
    );
    parts.prop_map(move |(bias, sines, steps)| {
        let raw = Signal { bias, sines, steps };
        let scale = if raw.bound() > 0.0 { bound / raw.bound() } else { 0.0 };
        Signal {
            bias: raw.bias * scale,
            sines: raw.sines.iter().map(|&(a, f, p)| (a * scale, f, p)).collect(),
            steps: raw.steps.iter().map(|&(h, t)| (h * scale, t)).collect(),
        }
    })
}

/// A limit pair `lower <= upper` within ±`range`.
pub fn limits(range: f64) -> impl Strategy<Value = (f64, f64)> {
    (-range..range, 0.0..range).prop_map(|(lo, span)| (lo, lo + span))
}

/// A stable continuous SISO system in zeros-poles-gain form: 1–4 distinct
/// poles with real parts in [−20, −0.5] (one conjugate pair at most), up to
/// as many real zeros in [−20, 20], gain in [−5, 5].
#[derive(Clone, Debug, PartialEq)]
pub struct StableZpk {
    pub zeros: Vec<f64>,
    pub poles: Vec<Complex<f64>>,
    pub gain: f64,
}

impl StableZpk {
    /// G(s).
    pub fn eval(&self, s: Complex<f64>) -> Complex<f64> {
        let num: Complex<f64> = self.zeros.iter().map(|&z| s - z).product();
        let den: Complex<f64> = self.poles.iter().map(|&p| s - p).product();
        num * self.gain / den
    }

    /// DC gain G(0).
    pub fn dc_gain(&self) -> f64 {
        self.eval(Complex::new(0.0, 0.0)).re
    }

    /// Residue of G at its i-th (simple) pole.
    fn residue(&self, i: usize) -> Complex<f64> {
        let p = self.poles[i];
        let num: Complex<f64> = self.zeros.iter().map(|&z| p - z).product();
        let den: Complex<f64> = self.poles.iter().enumerate().filter(|(j, _)| *j != i).map(|(_, &q)| p - q).product();
        num * self.gain / den
    }

    /// The exact unit-step response G(0) + Σ rᵢ/pᵢ·e^{pᵢt}.
    pub fn step_response(&self, t: f64) -> f64 {
        let mut y = self.eval(Complex::new(0.0, 0.0));
        for (i, &p) in self.poles.iter().enumerate() {
            y += self.residue(i) / p * (p * t).exp();
        }
        y.re
    }

    /// The L1 norm bound ‖g‖₁ <= |D| + Σ |rᵢ|/|Re pᵢ| of the impulse
    /// response: |y| <= ‖g‖₁·sup|u| for every bounded input (BIBO).
    pub fn l1_bound(&self) -> f64 {
        let direct = if self.zeros.len() == self.poles.len() { self.gain.abs() } else { 0.0 };
        direct + (0..self.poles.len()).map(|i| self.residue(i).norm() / -self.poles[i].re).sum::<f64>()
    }

    /// The slowest time constant 1/min|Re p|.
    pub fn slowest(&self) -> f64 {
        1.0 / self.poles.iter().map(|p| -p.re).fold(f64::INFINITY, f64::min)
    }

    /// Parameters of a `zpk` block.
    pub fn params(&self) -> String {
        let zeros: Vec<String> = self.zeros.iter().map(|z| format!("{z:e}")).collect();
        let poles: Vec<String> = self
            .poles
            .iter()
            .filter(|p| p.im >= 0.0)
            .map(|p| if p.im == 0.0 { format!("{:e}", p.re) } else { format!("[{:e}, {:e}]", p.re, p.im) })
            .collect();
        format!("zeros: [{}], poles: [{}], gain: {:e}", zeros.join(", "), poles.join(", "), self.gain)
    }
}

pub fn stable_zpk() -> impl Strategy<Value = StableZpk> {
    let real_poles = prop::collection::vec(-20.0..-0.5f64, 0..=2);
    let pair = prop::option::of((-10.0..-0.5f64, 0.5..15.0f64));
    (real_poles, pair, prop::collection::vec(-20.0..20.0f64, 0..=3), -5.0..5.0f64).prop_filter_map(
        "distinct poles, no more zeros than poles",
        |(reals, pair, zeros, gain)| {
            let mut poles: Vec<Complex<f64>> = reals.iter().map(|&r| Complex::new(r, 0.0)).collect();
            if let Some((re, im)) = pair {
                poles.push(Complex::new(re, im));
                poles.push(Complex::new(re, -im));
            }
            let distinct = poles.iter().enumerate().all(|(i, a)| poles[..i].iter().all(|b| (a - b).norm() > 0.3));
            let zeros: Vec<f64> = zeros.into_iter().filter(|z| poles.iter().all(|p| (p - z).norm() > 0.3)).collect();
            let zeros = zeros[..zeros.len().min(poles.len())].to_vec();
            (!poles.is_empty() && distinct).then_some(StableZpk { zeros, poles, gain })
        },
    )
}

/// A Schur-stable denominator in descending powers of z: real roots in
/// (−0.95, 0.95), and a complex pair of radius < 0.95 at most.
pub fn schur_polynomial() -> impl Strategy<Value = Vec<f64>> {
    (prop::collection::vec(-0.95..0.95f64, 0..=2), prop::option::of((0.0..0.95f64, 0.0..PI))).prop_filter_map(
        "at least one root",
        |(reals, pair)| {
            let mut roots: Vec<Complex<f64>> = reals.iter().map(|&r| Complex::new(r, 0.0)).collect();
            if let Some((r, angle)) = pair {
                roots.push(Complex::from_polar(r, angle));
                roots.push(Complex::from_polar(r, -angle));
            }
            if roots.is_empty() {
                return None;
            }
            ctlgraph_solver::poly::from_roots(&roots).ok()
        },
    )
}

/// A Hurwitz matrix A = K − P (K skew-symmetric, P symmetric positive
/// definite with eigenvalues >= 0.5): xᵀA x = −xᵀP x < 0, so every
/// eigenvalue has a negative real part. Row-major, `n`×`n`.
pub fn hurwitz_matrix(n: usize) -> impl Strategy<Value = Vec<Vec<f64>>> {
    (prop::collection::vec(-3.0..3.0f64, n * n), prop::collection::vec(-2.0..2.0f64, n * n)).prop_map(move |(k, l)| {
        // P = L Lᵀ + 0.5 I, K = (M − Mᵀ)/2 from the first draw.
        let mut a = vec![vec![0.0; n]; n];
        for i in 0..n {
            for j in 0..n {
                let skew = (k[i * n + j] - k[j * n + i]) / 2.0;
                let p: f64 = (0..n).map(|m| l[i * n + m] * l[j * n + m]).sum::<f64>() + if i == j { 0.5 } else { 0.0 };
                a[i][j] = skew - p;
            }
        }
        a
    })
}

/// Runs one block on test inputs. The block is named `b`; each input port
/// in order is driven by a [`Signal`]; every output port is recorded under
/// its port name.
pub struct Harness<'r> {
    registry: &'r Registry,
    block_type: String,
    params: String,
    inputs: Vec<Signal>,
    solver: String,
}

impl<'r> Harness<'r> {
    /// `params` is the inside of the block's YAML mapping, e.g. `"k: 2, sample_time: 0.01"`.
    pub fn new(registry: &'r Registry, block_type: &str, params: &str) -> Self {
        Harness {
            registry,
            block_type: block_type.to_string(),
            params: params.to_string(),
            inputs: Vec::new(),
            solver: "{ method: dopri5, rtol: 1.0e-8, atol: 1.0e-10, max_step: 0.01 }".into(),
        }
    }

    /// Drives the next input port with `signal`.
    pub fn input(mut self, signal: &Signal) -> Self {
        self.inputs.push(signal.clone());
        self
    }

    /// Overrides the solver (graph-file syntax, e.g. `"{ method: rk4, step: 1.0e-3 }"`).
    pub fn solver(mut self, solver: &str) -> Self {
        self.solver = solver.to_string();
        self
    }

    /// Simulates to `stop`; the error is the graph diagnostic or the
    /// simulation failure, as text.
    pub fn run(&self, stop: f64) -> Result<Trace, String> {
        let (inputs, outputs) = self.ports()?;
        let mut blocks = format!("  b: {{ type: {}, {} }}\n", self.block_type, self.params);
        let mut wires = Vec::new();
        for (i, s) in self.inputs.iter().enumerate() {
            let port = inputs.get(i).ok_or_else(|| format!("`{}` has no input #{}", self.block_type, i + 1))?;
            blocks.push_str(&format!("  in{i}: {{ type: fcn, inputs: 0, expr: \"{}\" }}\n", s.expr()));
            wires.push(format!("in{i} -> b.{port}"));
        }
        let text = format!(
            "simulation: {{ stop: {stop:e}, solver: {} }}\nblocks:\n{blocks}wires: [{}]\nrecord: [{}]\n",
            self.solver,
            wires.join(", "),
            outputs.iter().map(|o| format!("{o}: b.{o}")).collect::<Vec<_>>().join(", ")
        );
        let flat = ctlgraph_core::load_str(&text, "harness.yaml".into(), &[]).map_err(|d| d.to_string())?;
        let model = ctlgraph_core::compile(&flat, self.registry).map_err(|d| d.to_string())?;
        simulate(model, None).map_err(|e| e.to_string())
    }

    /// The block's ports, learned by building it once unwired.
    fn ports(&self) -> Result<(Vec<String>, Vec<String>), String> {
        let text = format!("blocks:\n  b: {{ type: {}, {} }}\n", self.block_type, self.params);
        let flat = ctlgraph_core::load_str(&text, "harness.yaml".into(), &[]).map_err(|d| d.to_string())?;
        let ty = self.registry.get(&self.block_type).ok_or_else(|| format!("no block type `{}`", self.block_type))?;
        let fb = &flat.blocks[0];
        let mut p =
            ctlgraph_core::Params::new("b", ty.name, &fb.spec.pos, &fb.spec.params, &fb.scope, &fb.dir, ty.params);
        let built = (ty.build)(&mut p).map_err(|d| d.to_string())?;
        Ok((
            built.iface.inputs.iter().map(|i| i.name.clone()).collect(),
            built.iface.outputs.iter().map(|o| o.name.clone()).collect(),
        ))
    }
}
