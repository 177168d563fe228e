//! Property tests (proptest): saturations never leave their limits, stable
//! transfer functions give bounded outputs that settle at their DC gain.

use ctlgraph::record::Trace;
use nalgebra::Complex;
use proptest::prelude::*;

fn run(yaml: &str) -> Trace {
    let model = ctlgraph::compile_str(yaml, "prop.yaml", &[]).unwrap_or_else(|d| panic!("{d}\n{yaml}"));
    ctlgraph::simulate(model, None).unwrap_or_else(|e| panic!("{e}\n{yaml}"))
}

fn list(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| format!("{x:e}")).collect();
    format!("[{}]", items.join(", "))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn saturation_output_is_the_clamped_input(
        lower in -5.0..5.0f64, span in 0.0..5.0f64, amplitude in 0.0..20.0f64,
        frequency in 0.1..50.0f64, bias in -10.0..10.0f64,
    ) {
        let upper = lower + span;
        let yaml = format!(
            "simulation: {{ stop: 1.0, solver: {{ method: rk4, step: 1.0e-3 }} }}\n\
             blocks:\n  u: {{ type: sine, amplitude: {amplitude:e}, frequency: {frequency:e}, bias: {bias:e} }}\n  \
             s: {{ type: saturation, lower: {lower:e}, upper: {upper:e} }}\nwires: [u -> s]\nrecord: [u, s]\n");
        let trace = run(&yaml);
        for (u, y) in trace.column("u").unwrap().iter().zip(trace.column("s").unwrap()) {
            prop_assert!(*y >= lower && *y <= upper, "{y} outside [{lower}, {upper}]");
            prop_assert_eq!(*y, u.clamp(lower, upper));
        }
    }

    #[test]
    fn rate_limited_output_never_slews_faster_than_allowed(
        rising in 0.1..100.0f64, falling in -100.0..-0.1f64, amplitude in 0.0..10.0f64, frequency in 0.1..20.0f64,
    ) {
        let yaml = format!(
            "simulation: {{ stop: 1.0, solver: {{ method: rk4, step: 1.0e-3 }} }}\n\
             blocks:\n  u: {{ type: pulse, amplitude: {amplitude:e}, period: {p:e} }}\n  \
             r: {{ type: rate_limiter, rising: {rising:e}, falling: {falling:e} }}\nwires: [u -> r]\nrecord: [r]\n",
            p = 1.0 / frequency);
        let trace = run(&yaml);
        let (t, y) = (trace.t(), trace.column("r").unwrap());
        for i in 1..t.len() {
            let dt = t[i] - t[i - 1];
            let rate = (y[i] - y[i - 1]) / dt;
            prop_assert!(dt <= 0.0 || (rate <= rising * (1.0 + 1e-9) && rate >= falling * (1.0 + 1e-9)), "rate {rate}");
        }
    }
}

/// A random stable system: 1–4 distinct poles in the open left half-plane
/// (real ones, or one conjugate pair), up to as many real zeros, a gain.
#[derive(Debug, Clone)]
struct Stable {
    poles: Vec<Complex<f64>>,
    zeros: Vec<f64>,
    gain: f64,
}

fn stable_system() -> impl Strategy<Value = Stable> {
    let real_poles = prop::collection::vec(-20.0..-0.5f64, 0..=2);
    let pair = prop::option::of((-10.0..-0.5f64, 0.5..15.0f64));
    (real_poles, pair, prop::collection::vec(-20.0..20.0f64, 0..=3), -5.0..5.0f64).prop_filter_map(
        "need distinct poles and no more zeros than poles",
        |(reals, pair, zeros, gain)| {
            let mut poles: Vec<Complex<f64>> = reals.iter().map(|&r| Complex::new(r, 0.0)).collect();
            if let Some((re, im)) = pair {
                poles.push(Complex::new(re, im));
                poles.push(Complex::new(re, -im));
            }
            let distinct = poles.iter().enumerate().all(|(i, a)| poles[..i].iter().all(|b| (a - b).norm() > 0.3));
            let zeros: Vec<f64> = zeros.into_iter().filter(|z| poles.iter().all(|p| (p - z).norm() > 0.3)).collect();
            (!poles.is_empty() && distinct && zeros.len() <= poles.len()).then(|| Stable {
                zeros: zeros[..zeros.len().min(poles.len())].to_vec(),
                poles,
                gain,
            })
        },
    )
}

impl Stable {
    fn eval(&self, s: Complex<f64>) -> Complex<f64> {
        let num: Complex<f64> = self.zeros.iter().map(|&z| s - z).product();
        let den: Complex<f64> = self.poles.iter().map(|&p| s - p).product();
        num * self.gain / den
    }

    /// The exact step response G(0) + Σ rᵢ/pᵢ·e^{pᵢt}.
    fn step_response(&self, t: f64) -> f64 {
        let mut y = self.eval(Complex::new(0.0, 0.0));
        for (i, &p) in self.poles.iter().enumerate() {
            y += self.residue(i) / p * (p * t).exp();
        }
        y.re
    }

    /// Residue of G at its i-th (simple) pole.
    fn residue(&self, i: usize) -> Complex<f64> {
        let p = self.poles[i];
        let num: Complex<f64> = self.zeros.iter().map(|&z| p - z).product();
        let den: Complex<f64> = self.poles.iter().enumerate().filter(|(j, _)| *j != i).map(|(_, &q)| p - q).product();
        num * self.gain / den
    }

    /// Step response y = G(0) + Σ rᵢ/pᵢ·e^{pᵢt} (rᵢ the residues of G; a
    /// direct feedthrough is part of G(0)), so |y| <= |G(0)| + Σ |rᵢ/pᵢ|.
    fn step_bound(&self) -> f64 {
        let mut bound = self.eval(Complex::new(0.0, 0.0)).norm();
        for (i, &p) in self.poles.iter().enumerate() {
            bound += (self.residue(i) / p).norm();
        }
        bound
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 40, ..ProptestConfig::default() })]

    #[test]
    fn stable_transfer_functions_follow_their_exact_step_response(sys in stable_system()) {
        let zeros: Vec<String> = sys.zeros.iter().map(|z| format!("{z:e}")).collect();
        let poles: Vec<String> = sys.poles.iter().filter(|p| p.im >= 0.0)
            .map(|p| if p.im == 0.0 { format!("{:e}", p.re) } else { format!("[{:e}, {:e}]", p.re, p.im) }).collect();
        let slowest = sys.poles.iter().map(|p| -p.re).fold(f64::INFINITY, f64::min);
        let stop = 14.0 / slowest;
        let yaml = format!(
            "simulation: {{ stop: {stop:e}, solver: {{ method: dopri5, rtol: 1.0e-9, atol: 1.0e-12 }} }}\n\
             blocks:\n  u: {{ type: step }}\n  \
             g: {{ type: zpk, zeros: [{}], poles: [{}], gain: {:e} }}\nwires: [u -> g]\nrecord: [g]\n",
            zeros.join(", "), poles.join(", "), sys.gain);
        let trace = run(&yaml);
        let y = trace.column("g").unwrap();
        let bound = sys.step_bound();
        for (&t, &v) in trace.t().iter().zip(y) {
            prop_assert!(v.is_finite() && v.abs() <= bound * (1.0 + 1e-6) + 1e-9, "|{v}| > bound {bound}");
            let exact = sys.step_response(t);
            prop_assert!((v - exact).abs() <= 1e-6 * bound.max(1.0), "t = {t}: {v} vs exact {exact}");
        }
        let dc = sys.eval(Complex::new(0.0, 0.0)).re;
        let last = *y.last().unwrap();
        // After 14 slowest time constants the transient is below e^-14 of the bound.
        prop_assert!((last - dc).abs() <= 1e-5 * bound.max(1.0), "y(end) = {last}, DC gain {dc}");
    }

    #[test]
    fn stable_discrete_transfer_functions_reach_their_dc_gain(
        a in -0.95..0.95f64, b in -0.9..0.9f64, c in -2.0..2.0f64,
    ) {
        // den (z − a)(z − b), num c·z: poles inside the unit circle.
        let den = [1.0, -(a + b), a * b];
        let yaml = format!(
            "simulation: {{ stop: 2.0, solver: {{ method: rk4, step: 0.01 }} }}\n\
             blocks:\n  u: {{ type: step }}\n  \
             g: {{ type: discrete_transfer_function, num: {}, den: {}, sample_time: 0.01 }}\n\
             wires: [u -> g]\nrecord: [g]\n", list(&[c, 0.0]), list(&den));
        let trace = run(&yaml);
        let y = trace.column("g").unwrap();
        let dc = c / (den.iter().sum::<f64>());
        // Geometric decay: after 200 samples at most 0.95^200 ≈ 3.5e-5 of the
        // transient remains; the l1 norm of the impulse response bounds |y|.
        let l1 = c.abs() / ((1.0 - a.abs()) * (1.0 - b.abs()));
        prop_assert!(y.iter().all(|v| v.abs() <= l1 * (1.0 + 1e-9)), "bounded by {l1}");
        prop_assert!((y.last().unwrap() - dc).abs() <= 1e-3 * l1.max(1.0), "{} vs {dc}", y.last().unwrap());
    }
}
