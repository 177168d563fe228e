//! Random sources: band-limited white noise (Simulink semantics), uniform
//! and Gaussian noise. Reproducible: each block's stream is seeded from the
//! graph's `simulation.seed`, the block's full name and its own `seed`, so
//! adding a block elsewhere changes no other block's noise; a stream
//! restarts with the run.

use crate::{ACTIVE, Y_SCALAR, table::*};
use ctlgraph_core::registry::{BlockType, Built};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{Rng, SeedableRng};

const SEED: ctlgraph_core::ParamDoc =
    param("seed", Number(0.0), "mixed with the graph seed and the block name into this block's stream");
const SAMPLE_TIME: ctlgraph_core::ParamDoc =
    param("sample_time", Required, "period T > 0 at which a new value is drawn and then held")
        .kind(ParamKind::SampleTime);

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "band_limited_white_noise",
        category: "sources",
        summary: "White noise of a given power density, sampled and held (Simulink's block).",
        doc: "y = sqrt(power / T)·n(k), n(k) ~ N(0, 1) drawn every T seconds and held. The output \
              approximates continuous white noise of power spectral density `power` for dynamics \
              much slower than 1/T; its variance is power/T. Choose T at least ten times smaller \
              than the fastest time constant it excites.",
        inputs: &[],
        outputs: Y_SCALAR,
        params: &[param("power", Number(0.1), "noise power (PSD height)").unit("units²·s"), SAMPLE_TIME, SEED, ACTIVE],
        build: build_band_limited,
    },
    BlockType {
        name: "uniform_noise",
        category: "sources",
        summary: "Uniformly distributed noise in [mean − amplitude, mean + amplitude], sampled and held.",
        doc: "y(k) = mean + amplitude·(2·v(k) − 1), v(k) ~ U[0, 1) drawn every T seconds and held; \
              variance amplitude²/3.",
        inputs: &[],
        outputs: Y_SCALAR,
        params: &[
            param("amplitude", Number(1.0), "half-width of the interval, >= 0"),
            param("mean", Number(0.0), "centre of the interval"),
            SAMPLE_TIME,
            SEED,
            ACTIVE,
        ],
        build: build_uniform,
    },
    BlockType {
        name: "gaussian_noise",
        category: "sources",
        summary: "Normally distributed noise, sampled and held.",
        doc: "y(k) = mean + sqrt(variance)·n(k), n(k) ~ N(0, 1) by the Box–Muller transform, drawn \
              every T seconds and held.",
        inputs: &[],
        outputs: Y_SCALAR,
        params: &[
            param("variance", Number(1.0), ">= 0"),
            param("mean", Number(0.0), "mean value"),
            SAMPLE_TIME,
            SEED,
            ACTIVE,
        ],
        build: build_gaussian,
    },
];

/// A seeded stream of uniform and standard normal numbers.
#[derive(Clone)]
pub struct Stream {
    seed: u64,
    rng: ChaCha8Rng,
    spare: Option<f64>,
}

impl Stream {
    pub fn new(seed: u64) -> Self {
        Stream { seed, rng: ChaCha8Rng::seed_from_u64(seed), spare: None }
    }

    /// Back to the start of the stream.
    pub fn restart(&mut self) {
        *self = Stream::new(self.seed);
    }

    /// Uniform in [0, 1), 53 random bits.
    pub fn uniform(&mut self) -> f64 {
        (self.rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal by the Box–Muller transform (both values used).
    pub fn normal(&mut self) -> f64 {
        if let Some(v) = self.spare.take() {
            return v;
        }
        let u1 = 1.0 - self.uniform(); // (0, 1]: ln is finite
        let u2 = self.uniform();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (2.0 * std::f64::consts::PI * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }
}

#[derive(Clone, Copy)]
enum Law {
    Normal { mean: f64, std: f64 },
    Uniform { mean: f64, amplitude: f64 },
}

/// Draws at each sample hit (in `update`) and holds the value.
#[derive(Clone)]
pub struct Noise {
    law: Law,
    stream: Stream,
    value: f64,
}

impl Noise {
    fn draw(&mut self) -> f64 {
        match self.law {
            Law::Normal { mean, std } => mean + std * self.stream.normal(),
            Law::Uniform { mean, amplitude } => mean + amplitude * (2.0 * self.stream.uniform() - 1.0),
        }
    }
}

impl Block for Noise {
    rust_type!(Noise);
    fn initialize(&mut self, _x0: &mut [f64]) {
        self.stream.restart();
        self.value = self.draw();
    }
    fn output(&mut self, io: &mut Io) {
        io.set(0, self.value);
    }
    fn update(&mut self, _io: &mut Io) {
        self.value = self.draw();
    }
}

fn noise(p: &mut Params, law: Law) -> Result<Built, Diagnostic> {
    let st = p.discrete_sample_time()?;
    let extra = p.number_where("seed", None, |v| v >= 0.0 && v.fract() == 0.0, "a whole number >= 0")?;
    let stream = Stream::new(p.stream_seed(extra as u64));
    let block = Noise { law, stream, value: 0.0 };
    crate::sources::windowed(p, Built::new(block, Interface::new(st).output("y", Width::Fixed(1))))
}

fn build_band_limited(p: &mut Params) -> Result<Built, Diagnostic> {
    let power = p.number_where("power", None, |v| v >= 0.0 && v.is_finite(), "a power >= 0")?;
    let (_, t, _) = p.discrete_clock()?;
    noise(p, Law::Normal { mean: 0.0, std: (power / t).sqrt() })
}

fn build_uniform(p: &mut Params) -> Result<Built, Diagnostic> {
    let amplitude = p.number_where("amplitude", None, |v| v >= 0.0 && v.is_finite(), "an amplitude >= 0")?;
    let mean = p.number("mean")?;
    noise(p, Law::Uniform { mean, amplitude })
}

fn build_gaussian(p: &mut Params) -> Result<Built, Diagnostic> {
    let variance = p.number_where("variance", None, |v| v >= 0.0 && v.is_finite(), "a variance >= 0")?;
    let mean = p.number("mean")?;
    noise(p, Law::Normal { mean, std: variance.sqrt() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_stream_has_unit_variance_and_restarts() {
        let mut s = Stream::new(42);
        let xs: Vec<f64> = (0..200_000).map(|_| s.normal()).collect();
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (xs.len() - 1) as f64;
        // Standard errors: 1/sqrt(n) = 0.0022 for the mean, sqrt(2/n) = 0.0032 for the variance.
        assert!(mean.abs() < 0.01 && (var - 1.0).abs() < 0.015, "mean {mean}, variance {var}");
        s.restart();
        assert_eq!(s.normal(), xs[0]);
        let u: Vec<f64> = (0..100_000).map(|_| s.uniform()).collect();
        assert!(u.iter().all(|v| (0.0..1.0).contains(v)));
        let mu = u.iter().sum::<f64>() / u.len() as f64;
        assert!((mu - 0.5).abs() < 0.005);
    }

    /// The block's output at successive sample hits, from `initialize` on.
    fn outputs(block: &mut Noise, hits: usize) -> Vec<f64> {
        let out = [ctlgraph_core::block::Port { offset: 0, width: 1 }];
        let mut signal = [f64::NAN];
        block.initialize(&mut []);
        (0..hits)
            .map(|_| {
                let mut io = Io::new(0.0, false, &[], &mut signal, &[], &out);
                block.output(&mut io);
                block.update(&mut io);
                signal[0]
            })
            .collect()
    }

    #[test]
    fn the_laws_scale_and_shift_the_stream_and_a_run_restarts_it() {
        let mut reference = Stream::new(7);
        let normal: Vec<f64> = (0..4).map(|_| 2.0 + 3.0 * reference.normal()).collect();
        let law = Law::Normal { mean: 2.0, std: 3.0 };
        let mut block = Noise { law, stream: Stream::new(7), value: 0.0 };
        block.stream.normal();
        assert_eq!(outputs(&mut block, 4), normal);
        assert_eq!(outputs(&mut block, 4), normal);
        reference.restart();
        let uniform: Vec<f64> = (0..4).map(|_| 1.0 + 0.5 * (2.0 * reference.uniform() - 1.0)).collect();
        let law = Law::Uniform { mean: 1.0, amplitude: 0.5 };
        let mut block = Noise { law, stream: Stream::new(7), value: 0.0 };
        assert_eq!(outputs(&mut block, 4), uniform);
        assert!(uniform.iter().all(|u| (0.5..1.5).contains(u)));
    }
}
