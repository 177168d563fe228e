//! Exact zero-order-hold stepping of a continuous LTI system: with the
//! input held constant over a step of length Δ,
//!
//! ```text
//! x(t + Δ) = Φ(Δ)·x(t) + Γ(Δ)·u,   [Φ Γ; 0 I] = exp([A B; 0 0]·Δ)
//! ```
//!
//! (Franklin, Powell & Workman, *Digital Control of Dynamic Systems*, §4.3;
//! the same as scipy's `cont2discrete(method='zoh')`).
//!
//! The matrix exponential is computed here rather than with nalgebra's
//! `Matrix::exp` because that allocates on every call, and a step whose
//! length differs from the last (a source's switching time between two grid
//! points) needs a new one inside the step loop, which must not allocate.
//! Method: scaling and squaring of the Taylor series (Moler & Van Loan,
//! "Nineteen dubious ways…", method 3), scaled to a 1-norm of at most 1/2,
//! where 20 terms leave a truncation error below 1e-25.

use crate::StateSpace;
use crate::lti::affine_single_input;

/// Steps whose lengths agree to this relative tolerance share Φ and Γ.
/// Floating-point grid times jitter in the last bits (k/n − (k−1)/n is not
/// exactly 1/n), by up to about 1e-8 relative at 1e10 steps; the true step
/// is the nominal one, so reusing its matrices is the more exact choice.
pub const SAME_STEP: f64 = 1e-6;

/// Φ and Γ for one step length.
#[derive(Clone, Debug)]
struct Transition {
    dt: f64,
    phi: Vec<f64>,
    gamma: Vec<f64>,
}

/// A system advanced exactly under a held input. Keeps the transitions of
/// the two most recent step lengths (the grid's, and an event's), and
/// recomputes one without allocating when a third is asked for.
#[derive(Clone, Debug)]
pub struct Zoh {
    ss: StateSpace,
    cache: [Transition; 2],
    /// Which cache entry the next new step length replaces.
    oldest: usize,
    /// How many exponentials have been computed (the cache's misses).
    computed: u64,
    // Work space for the exponential: k×k with k = n + m.
    scaled: Vec<f64>,
    term: Vec<f64>,
    sum: Vec<f64>,
    product: Vec<f64>,
    x_next: Vec<f64>,
}

impl Zoh {
    pub fn new(ss: StateSpace) -> Self {
        let (n, m) = (ss.n, ss.m);
        let k = n + m;
        let empty = Transition { dt: f64::NAN, phi: vec![0.0; n * n], gamma: vec![0.0; n * m] };
        Zoh {
            cache: [empty.clone(), empty],
            oldest: 0,
            computed: 0,
            scaled: vec![0.0; k * k],
            term: vec![0.0; k * k],
            sum: vec![0.0; k * k],
            product: vec![0.0; k * k],
            x_next: vec![0.0; n],
            ss,
        }
    }

    pub fn system(&self) -> &StateSpace {
        &self.ss
    }

    /// How many matrix exponentials were computed so far: one per step
    /// length not found in the cache.
    pub fn exponentials_computed(&self) -> u64 {
        self.computed
    }

    /// `x ← Φ(dt)·x + Γ(dt)·u`.
    #[inline]
    pub fn step(&mut self, dt: f64, x: &mut [f64], u: &[f64]) {
        let (n, m) = (self.ss.n, self.ss.m);
        let slot = self.transition(dt);
        let Transition { phi, gamma, .. } = &self.cache[slot];
        match (n, m) {
            // One input and a few states (a transfer function's usual
            // realisation): sizes known to the compiler, the loops unrolled.
            (1, 1) => step_single_input::<1>(phi, gamma, x, u[0]),
            (2, 1) => step_single_input::<2>(phi, gamma, x, u[0]),
            (3, 1) => step_single_input::<3>(phi, gamma, x, u[0]),
            (4, 1) => step_single_input::<4>(phi, gamma, x, u[0]),
            _ => {
                for i in 0..n {
                    let mut v = 0.0;
                    for j in 0..n {
                        v += phi[i * n + j] * x[j];
                    }
                    for j in 0..m {
                        v += gamma[i * m + j] * u[j];
                    }
                    self.x_next[i] = v;
                }
                // A loop, not copy_from_slice: for a few states a memmove call costs more.
                for (xi, &v) in x.iter_mut().zip(&self.x_next) {
                    *xi = v;
                }
            }
        }
    }

    /// This system as one of `N` states and one input, stepped without
    /// dispatching on its sizes; `None` when those are not its sizes.
    pub fn single_input<const N: usize>(self) -> Option<ZohSingleInput<N>> {
        (self.ss.n == N && self.ss.m == 1 && N > 0).then_some(ZohSingleInput(self))
    }

    /// Φ(dt) and Γ(dt) as (n×n, n×m) row-major matrices.
    #[inline]
    pub fn matrices(&mut self, dt: f64) -> (&[f64], &[f64]) {
        let slot = self.transition(dt);
        (&self.cache[slot].phi, &self.cache[slot].gamma)
    }

    /// The cache entry for `dt`, computed if neither entry has it.
    /// Inlined (the step loop asks every step); a miss is the cold path.
    #[inline]
    fn transition(&mut self, dt: f64) -> usize {
        match self.cache.iter().position(|c| (c.dt - dt).abs() <= SAME_STEP * dt) {
            Some(slot) => slot,
            None => self.replace_oldest(dt),
        }
    }

    /// Computes Φ and Γ for `dt` into the older cache entry.
    #[cold]
    fn replace_oldest(&mut self, dt: f64) -> usize {
        let slot = self.oldest;
        self.oldest = 1 - slot;
        self.computed += 1;
        self.exponential(dt);
        let (n, m, k) = (self.ss.n, self.ss.m, self.ss.n + self.ss.m);
        let c = &mut self.cache[slot];
        c.dt = dt;
        for i in 0..n {
            c.phi[i * n..(i + 1) * n].copy_from_slice(&self.sum[i * k..i * k + n]);
            c.gamma[i * m..(i + 1) * m].copy_from_slice(&self.sum[i * k + n..(i + 1) * k]);
        }
        slot
    }

    /// `sum ← exp([A B; 0 0]·dt)`.
    fn exponential(&mut self, dt: f64) {
        let (n, m, k) = (self.ss.n, self.ss.m, self.ss.n + self.ss.m);
        self.scaled.iter_mut().for_each(|v| *v = 0.0);
        for i in 0..n {
            for j in 0..n {
                self.scaled[i * k + j] = self.ss.a[i * n + j] * dt;
            }
            for j in 0..m {
                self.scaled[i * k + n + j] = self.ss.b[i * m + j] * dt;
            }
        }
        let norm = (0..k).map(|j| (0..k).map(|i| self.scaled[i * k + j].abs()).sum::<f64>()).fold(0.0, f64::max);
        let squarings = if norm > 0.5 { (norm / 0.5).log2().ceil() as i32 } else { 0 };
        let scale = 0.5f64.powi(squarings);
        self.scaled.iter_mut().for_each(|v| *v *= scale);
        // Taylor: sum = I + S + S²/2! + …, term = S^j/j!.
        for (i, (s, t)) in self.sum.iter_mut().zip(self.term.iter_mut()).enumerate() {
            let identity = if i % (k + 1) == 0 { 1.0 } else { 0.0 };
            (*s, *t) = (identity, identity);
        }
        for j in 1..=20 {
            multiply(&self.term, &self.scaled, &mut self.product, k);
            let inv = 1.0 / j as f64;
            let mut largest = 0.0f64;
            for ((t, p), s) in self.term.iter_mut().zip(&self.product).zip(self.sum.iter_mut()) {
                *t = p * inv;
                *s += *t;
                largest = largest.max(t.abs());
            }
            if largest == 0.0 {
                break;
            }
        }
        for _ in 0..squarings {
            multiply(&self.sum, &self.sum, &mut self.product, k);
            std::mem::swap(&mut self.sum, &mut self.product);
        }
    }
}

/// `c ← a·b` for k×k row-major matrices.
fn multiply(a: &[f64], b: &[f64], c: &mut [f64], k: usize) {
    c.iter_mut().for_each(|v| *v = 0.0);
    for i in 0..k {
        for l in 0..k {
            let ail = a[i * k + l];
            if ail != 0.0 {
                for j in 0..k {
                    c[i * k + j] += ail * b[l * k + j];
                }
            }
        }
    }
}

/// A [`Zoh`] whose sizes, N states and one input, were checked once
/// ([`Zoh::single_input`]), so that a step dispatches on nothing: for
/// generated code, which knows each block's sizes when it is written.
#[derive(Clone, Debug)]
pub struct ZohSingleInput<const N: usize>(Zoh);

impl<const N: usize> ZohSingleInput<N> {
    /// `x ← Φ(dt)·x + Γ(dt)·u`, as [`Zoh::step`].
    #[inline]
    pub fn step(&mut self, dt: f64, x: &mut [f64; N], u: f64) {
        let (phi, gamma) = self.0.matrices(dt);
        step_single_input::<N>(phi, gamma, x, u);
    }

    pub fn zoh(&self) -> &Zoh {
        &self.0
    }
}

/// `x ← Φ·x + γ·u` for N states and one input (see [`affine_single_input`]).
#[inline]
fn step_single_input<const N: usize>(phi: &[f64], gamma: &[f64], x: &mut [f64], u: f64) {
    let next = affine_single_input::<N>(phi, gamma, x, u, 0.0);
    x[..N].copy_from_slice(&next);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tf2ss;
    use nalgebra::DMatrix;

    /// Φ and Γ agree with nalgebra's Padé exponential of the augmented
    /// matrix, for a lightly damped plant, a stiff one, and two inputs.
    #[test]
    fn transition_matches_pade_exponential() {
        let systems = [
            tf2ss(&[1.639e4], &[1.0, 154.8, 2.242e4]).unwrap(),
            tf2ss(&[1.0, 3.0], &[1.0, 1001.0, 1000.0, 0.5]).unwrap(),
            StateSpace::new(
                vec![vec![0.0, 1.0], vec![-4.0, -0.4]],
                vec![vec![0.0, 1.0], vec![1.0, -2.0]],
                vec![vec![1.0, 0.0]],
                vec![vec![0.0, 0.0]],
            )
            .unwrap(),
        ];
        for ss in systems {
            let (n, m) = (ss.n, ss.m);
            let mut zoh = Zoh::new(ss.clone());
            for dt in [1e-4, 0.05, 3.0] {
                let mut aug = DMatrix::zeros(n + m, n + m);
                for i in 0..n {
                    for j in 0..n {
                        aug[(i, j)] = ss.a[i * n + j] * dt;
                    }
                    for j in 0..m {
                        aug[(i, n + j)] = ss.b[i * m + j] * dt;
                    }
                }
                let e = aug.exp();
                let (phi, gamma) = zoh.matrices(dt);
                let scale = e.abs().max();
                for i in 0..n {
                    for j in 0..n {
                        assert!((phi[i * n + j] - e[(i, j)]).abs() <= 1e-12 * scale, "Φ[{i}][{j}] at {dt}");
                    }
                    for j in 0..m {
                        assert!((gamma[i * m + j] - e[(i, n + j)]).abs() <= 1e-12 * scale, "Γ[{i}][{j}] at {dt}");
                    }
                }
            }
        }
    }

    /// `step` is Φx + Γu with two inputs of unequal sizes, and a step length
    /// close to a cached one is not mistaken for it.
    #[test]
    fn step_applies_both_matrices_and_the_cache_tells_steps_apart() {
        let ss = StateSpace::new(
            vec![vec![0.0, 1.0], vec![-4.0, -0.4]],
            vec![vec![0.5, 1.0], vec![1.0, -2.0]],
            vec![vec![1.0, 0.0]],
            vec![vec![0.0, 0.0]],
        )
        .unwrap();
        let mut zoh = Zoh::new(ss.clone());
        let (x0, u) = ([0.3, -1.1], [0.7, -1.3]);
        for dt in [1e-4, 1.5e-4, 1e-4, 0.02] {
            let mut fresh = Zoh::new(ss.clone());
            let (phi, gamma) = fresh.matrices(dt);
            let mut x = x0;
            zoh.step(dt, &mut x, &u);
            for i in 0..2 {
                let want = phi[2 * i] * x0[0] + phi[2 * i + 1] * x0[1] + gamma[2 * i] * u[0] + gamma[2 * i + 1] * u[1];
                assert!((x[i] - want).abs() < 1e-15, "dt {dt}, x[{i}]: {} vs {want}", x[i]);
            }
            assert!((x[0] - x0[0]).abs() > 1e-6, "the state moved");
        }
        // 1e-4 and 1.5e-4 alternate in the two entries; 0.02 evicts one.
        assert_eq!(zoh.exponentials_computed(), 3);
        // A grid's steps jitter in the last bits: they share one exponential.
        let mut x = x0;
        for k in 1..=1000 {
            zoh.step(k as f64 / 1e4 - (k - 1) as f64 / 1e4, &mut x, &u);
        }
        assert_eq!(zoh.exponentials_computed(), 4);
    }

    #[test]
    fn one_input_systems_step_as_the_general_loop_does() {
        // Orders 1-4 take the fixed-size path, 5 the general loop: each is
        // x ← Φx + γu summed in index order, to the bit.
        for order in 1..=5 {
            let den: Vec<f64> = (0..=order).map(|k| [1.0, 7.0, 19.0, 25.0, 16.0, 4.0][k]).collect();
            let ss = tf2ss(&[2.0, 1.0], &den).unwrap();
            let mut zoh = Zoh::new(ss);
            let (phi, gamma) = {
                let (p, g) = zoh.matrices(0.01);
                (p.to_vec(), g.to_vec())
            };
            let mut x: Vec<f64> = (0..order).map(|i| 0.3 - 0.2 * i as f64).collect();
            for k in 0..20 {
                let u = (k as f64 * 0.7).sin();
                let mut want = vec![0.0; order];
                for (i, w) in want.iter_mut().enumerate() {
                    let mut v = 0.0;
                    for j in 0..order {
                        v += phi[i * order + j] * x[j];
                    }
                    *w = v + gamma[i] * u;
                }
                zoh.step(0.01, &mut x, &[u]);
                assert_eq!(x, want, "order {order}, step {k}");
            }
        }
    }

    #[test]
    fn a_single_input_zoh_steps_as_the_general_one_and_checks_its_sizes() {
        let ss = tf2ss(&[2.0, 1.0], &[1.0, 7.0, 19.0, 25.0]).unwrap();
        let mut general = Zoh::new(ss.clone());
        let mut sized = Zoh::new(ss.clone()).single_input::<3>().expect("3 states, one input");
        let (mut x, mut x_sized) = ([0.3, -0.1, 0.2], [0.3, -0.1, 0.2]);
        // The grid's step and an event's, alternating through the cache.
        for k in 0..20 {
            let (dt, u) = (if k % 5 == 4 { 0.004 } else { 0.01 }, (k as f64 * 0.7).sin());
            general.step(dt, &mut x, &[u]);
            sized.step(dt, &mut x_sized, u);
            assert_eq!(x, x_sized, "step {k}");
        }
        assert_eq!(sized.zoh().exponentials_computed(), general.exponentials_computed());
        assert!(Zoh::new(ss.clone()).single_input::<2>().is_none(), "3 states are not 2");
        let two_inputs = StateSpace::new(vec![vec![-1.0]], vec![vec![1.0, 2.0]], vec![vec![1.0]], vec![vec![0.0, 0.0]]);
        assert!(Zoh::new(two_inputs.unwrap()).single_input::<1>().is_none(), "two inputs are not one");
    }

    /// The FLADRC paper's plant 1.639e4/(s² + 154.8 s + 2.242e4) under a unit
    /// step, h = 1e-4: y(k) from scipy 1.17.1's
    /// `cont2discrete((A, B, C, D), 1e-4, method='zoh')` recursion (values
    /// recorded once), and the closed form of the step response.
    #[test]
    fn step_recursion_matches_scipy_cont2discrete() {
        let ss = tf2ss(&[1.639e4], &[1.0, 154.8, 2.242e4]).unwrap();
        let mut zoh = Zoh::new(ss.clone());
        let mut x = [0.0; 2];
        let mut y = Vec::new();
        for _ in 0..=1000 {
            let mut out = [0.0];
            ss.output_state_only(&x, &mut out);
            y.push(out[0]);
            zoh.step(1e-4, &mut x, &[1.0]);
        }
        let scipy = [
            (1, 8.152724777880825e-05),
            (10, 0.00777362103343098),
            (100, 0.4398193980033976),
            (1000, 0.7306878877488145),
        ];
        for (k, want) in scipy {
            assert!((y[k] - want).abs() < 1e-12, "y({k}) = {} vs scipy {want}", y[k]);
        }
        // Closed form: K(1 − e^{−ζωt}(cos ω_d t + ζω/ω_d sin ω_d t)).
        let (w2, two_zw) = (2.242e4f64, 154.8);
        let (zw, gain) = (two_zw / 2.0, 1.639e4 / w2);
        let wd = (w2 - zw * zw).sqrt();
        for (k, &yk) in y.iter().enumerate() {
            let t = k as f64 * 1e-4;
            let exact = gain * (1.0 - (-zw * t).exp() * ((wd * t).cos() + zw / wd * (wd * t).sin()));
            assert!((yk - exact).abs() < 1e-12, "t = {t}: {yk} vs {exact}");
        }
    }
}
