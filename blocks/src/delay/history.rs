//! A signal's past as the transport delays keep it: samples at every major
//! step, and at a breakpoint two samples at one time (the left limit, then
//! the value after), interpolated by a polynomial through the nearest
//! samples that never reaches across a breakpoint.

/// Which limit to take where the time asked for is a breakpoint's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Left,
    Right,
}

/// The input's past: times and values in a ring buffer that doubles when
/// full, up to a limit.
#[derive(Clone)]
pub struct History {
    width: usize,
    times: Vec<f64>,
    values: Vec<f64>,
    /// Index of the oldest sample and the number held.
    head: usize,
    len: usize,
    limit: usize,
    /// Samples before this index (logical) are searched past; speeds up
    /// the monotone queries of a run.
    cursor: usize,
    /// Degree of the interpolating polynomial (1, 3 or 5).
    degree: usize,
    /// The newest sample is a left limit whose right value is still to come.
    left_pending: bool,
    /// The buffer hit its limit: why the output became NaN.
    pub overflow: Option<String>,
}

/// The most samples a stencil takes (degree 5).
const MAX_POINTS: usize = 6;

impl History {
    pub fn new(width: usize, capacity: usize, limit: usize, degree: usize) -> Self {
        let capacity = capacity.clamp(MAX_POINTS + 2, limit.max(MAX_POINTS + 2));
        History {
            width,
            times: vec![0.0; capacity],
            values: vec![0.0; capacity * width],
            head: 0,
            len: 0,
            limit,
            cursor: 0,
            degree: degree.clamp(1, MAX_POINTS - 1),
            left_pending: false,
            overflow: None,
        }
    }

    /// The same history for another width (before a run).
    pub fn with_width(&self, width: usize) -> Self {
        History::new(width, self.times.len(), self.limit, self.degree)
    }

    pub fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
        self.cursor = 0;
        self.left_pending = false;
        self.overflow = None;
    }

    fn slot(&self, i: usize) -> usize {
        (self.head + i) % self.times.len()
    }

    fn time(&self, i: usize) -> f64 {
        self.times[self.slot(i)]
    }

    fn value(&self, i: usize, k: usize) -> f64 {
        self.values[self.slot(i) * self.width + k]
    }

    /// Appends the left limit (t, u) of a breakpoint; the next [`History::push`]
    /// at the same time gives its right value.
    pub fn push_left(&mut self, t: f64, u: impl Fn(usize) -> f64, keep_from: f64) {
        if self.left_pending {
            // A second cause at the same time (a host's input at a sample
            // hit): the first left limit is the one before both.
            return;
        }
        self.append(t, u, keep_from);
        self.left_pending = true;
    }

    /// Appends the sample (t, u), first dropping samples older than
    /// `keep_from` except the stencil's worth before it. A sample at the
    /// time of the newest replaces it (the same major step again, at a
    /// restart), unless the newest is a left limit: the two are then a
    /// breakpoint. Returns whether that breakpoint is a jump.
    pub fn push(&mut self, t: f64, u: impl Fn(usize) -> f64, keep_from: f64) -> bool {
        let pair = std::mem::take(&mut self.left_pending) && self.len > 0 && t == self.time(self.len - 1);
        if !pair && self.len > 0 && t <= self.time(self.len - 1) {
            self.len -= 1;
        }
        let jumped = pair && (0..self.width).any(|k| u(k) != self.value(self.len - 1, k));
        self.append(t, u, keep_from);
        jumped
    }

    fn append(&mut self, t: f64, u: impl Fn(usize) -> f64, keep_from: f64) {
        while self.len > self.degree + 2 && self.time(self.degree + 1) <= keep_from {
            self.head = (self.head + 1) % self.times.len();
            self.len -= 1;
            self.cursor = self.cursor.saturating_sub(1);
        }
        if self.len == self.times.len() && !self.grow() {
            return;
        }
        let s = self.slot(self.len);
        self.times[s] = t;
        for k in 0..self.width {
            self.values[s * self.width + k] = u(k);
        }
        self.len += 1;
    }

    /// Doubles the buffer (unrolled so the oldest sample is first again).
    fn grow(&mut self) -> bool {
        let capacity = self.times.len();
        if capacity >= self.limit {
            self.overflow = Some(format!(
                "its history is full: {capacity} samples cover {:.6} s, less than the delay needs; \
                 raise `max_buffer` or the solver's step",
                self.time(self.len - 1) - self.time(0)
            ));
            return false;
        }
        let new_capacity = (2 * capacity).min(self.limit);
        let mut times = vec![0.0; new_capacity];
        let mut values = vec![0.0; new_capacity * self.width];
        for i in 0..self.len {
            times[i] = self.time(i);
            for k in 0..self.width {
                values[i * self.width + k] = self.value(i, k);
            }
        }
        (self.times, self.values, self.head) = (times, values, 0);
        true
    }

    /// Whether samples `i` and `i + 1` are a breakpoint's two limits.
    fn is_break(&self, i: usize) -> bool {
        self.time(i) == self.time(i + 1)
    }

    /// The interpolated input at `t` into `out` (NaN after an overflow),
    /// the `side` limit where `t` is a breakpoint's time.
    ///
    /// Inside the history: the Lagrange polynomial of the history's degree
    /// through the samples nearest to `t` between the breakpoints around
    /// it (fewer where fewer lie there). Before the oldest sample: its
    /// value. Past the newest (a delay shorter than the step): the line
    /// through the last two, as Simulink extrapolates.
    pub fn at(&mut self, t: f64, side: Side, out: &mut [f64]) {
        if self.overflow.is_some() || self.len == 0 {
            let v = if self.overflow.is_some() { f64::NAN } else { 0.0 };
            out.iter_mut().for_each(|o| *o = v);
            return;
        }
        let last = self.len - 1;
        if self.len == 1 || t <= self.time(0) {
            let i = if t <= self.time(0) { 0 } else { last };
            for (k, o) in out.iter_mut().enumerate() {
                *o = self.value(i, k);
            }
            return;
        }
        // The interval [time(i), time(i + 1)] holding t: past a breakpoint
        // at t for the right limit, before it for the left.
        let mut i = self.cursor.min(last - 1);
        while i > 0 && (self.time(i) > t || (side == Side::Left && self.time(i) == t)) {
            i -= 1;
        }
        while i + 1 < last && (self.time(i + 1) < t || (side == Side::Right && self.time(i + 1) == t)) {
            i += 1;
        }
        self.cursor = i;
        if self.is_break(i) {
            // t sits on a breakpoint at the edge of the history: its limit.
            let j = if side == Side::Left { i } else { i + 1 };
            for (k, o) in out.iter_mut().enumerate() {
                *o = self.value(j, k);
            }
            return;
        }
        if t > self.time(last) || self.degree == 1 {
            let (t0, t1) = (self.time(i), self.time(i + 1));
            let th = (t - t0) / (t1 - t0);
            for (k, o) in out.iter_mut().enumerate() {
                let (y0, y1) = (self.value(i, k), self.value(i + 1, k));
                *o = y0 + th * (y1 - y0);
            }
            return;
        }
        let mut weights = [0.0; MAX_POINTS];
        for (k, o) in out.iter_mut().enumerate() {
            let (a, b) = self.stencil(i, t, k);
            for j in a..=b {
                let tj = self.time(j);
                let mut w = 1.0;
                for m in (a..=b).filter(|&m| m != j) {
                    let tm = self.time(m);
                    w *= (t - tm) / (tj - tm);
                }
                weights[j - a] = w;
            }
            *o = (a..=b).map(|j| weights[j - a] * self.value(j, k)).sum();
        }
    }

    /// The samples `a..=b` to interpolate element `k` with in interval
    /// `i`: `degree + 1` of them, added one at a time, never across a
    /// breakpoint or past the history's ends.
    ///
    /// Each sample is taken on the side nearer to `t` unless the divided
    /// difference that side would add is more than [`ENO_BIAS`] times the
    /// other's: a jump the driver did not see (an `fcn` stepping, a
    /// solver stepping over a switch) makes the differences across it grow
    /// like h⁻ᵈ, so the stencil turns away from it and the polynomial does
    /// not overshoot next to it (essentially non-oscillatory interpolation,
    /// Harten, Engquist, Osher & Chakravarthy, J. Comput. Phys. 71, 1987,
    /// with Shu's bias to the central stencil, J. Sci. Comput. 5, 1990,
    /// which keeps the central error constant where the input is smooth).
    fn stencil(&self, i: usize, t: f64, k: usize) -> (usize, usize) {
        let (mut a, mut b) = (i, i + 1);
        while b - a < self.degree {
            let left = a > 0 && !self.is_break(a - 1);
            let right = b + 1 < self.len && !self.is_break(b);
            match (left, right) {
                (true, true) => {
                    let (dl, dr) = (self.divided_difference(a - 1, b, k), self.divided_difference(a, b + 1, k));
                    let left_nearer = t - self.time(a - 1) <= self.time(b + 1) - t;
                    let take_left = if left_nearer { dl <= ENO_BIAS * dr } else { dr > ENO_BIAS * dl };
                    if take_left { a -= 1 } else { b += 1 }
                }
                (false, true) => b += 1,
                (true, false) => a -= 1,
                (false, false) => break,
            }
        }
        (a, b)
    }

    /// |u[t_a, …, t_b]| of element `k`: the divided difference of order
    /// b − a (Newton's table, in place).
    fn divided_difference(&self, a: usize, b: usize, k: usize) -> f64 {
        let mut d = [0.0; MAX_POINTS];
        for j in a..=b {
            d[j - a] = self.value(j, k);
        }
        for order in 1..=b - a {
            for j in (order..=b - a).rev() {
                d[j] = (d[j] - d[j - 1]) / (self.time(a + j) - self.time(a + j - order));
            }
        }
        d[b - a].abs()
    }
}

/// How much larger the divided difference on the nearer side may be before
/// the stencil turns to the other side (Shu's bias factor).
const ENO_BIAS: f64 = 2.0;

#[cfg(test)]
mod tests {
    use super::*;

    fn sampled(degree: usize, times: &[f64], f: impl Fn(f64) -> f64) -> History {
        let mut h = History::new(1, 8, 1_000_000, degree);
        for &t in times {
            h.push(t, |_| f(t), f64::NEG_INFINITY);
        }
        h
    }

    fn at(h: &mut History, t: f64, side: Side) -> f64 {
        let mut out = [0.0];
        h.at(t, side, &mut out);
        out[0]
    }

    #[test]
    fn a_polynomial_of_the_degree_is_reproduced_on_uneven_samples() {
        let times: Vec<f64> = (0..40).map(|i| 0.1 * i as f64 + 0.03 * (i as f64 * 1.7).sin()).collect();
        for degree in [1, 3, 5] {
            let f = |t: f64| (0..=degree).map(|p| (p as f64 + 1.0) * t.powi(p as i32)).sum::<f64>();
            let mut h = sampled(degree, &times, f);
            for q in 0..290 {
                let t = 0.0131 * q as f64; // up to 3.8, inside the samples
                let got = at(&mut h, t, Side::Right);
                assert!((got - f(t)).abs() <= 1e-9 * f(t).abs(), "degree {degree} at {t}: {got} vs {}", f(t));
            }
        }
    }

    #[test]
    fn no_stencil_reaches_across_a_breakpoint() {
        // y = t before 1, 10 + t² after: the polynomial pieces are exact on each side.
        let mut h = History::new(1, 8, 1_000_000, 3);
        for i in 0..=10 {
            let t = 0.1 * i as f64;
            if i == 10 {
                h.push_left(1.0, |_| 1.0, f64::NEG_INFINITY);
                assert!(h.push(1.0, |_| 11.0, f64::NEG_INFINITY), "a jump");
            } else {
                h.push(t, |_| t, f64::NEG_INFINITY);
            }
        }
        for i in 11..20 {
            let t = 0.1 * i as f64;
            h.push(t, |_| 10.0 + t * t, f64::NEG_INFINITY);
        }
        for q in 0..190 {
            let t = 0.01 * q as f64 + 0.001;
            let exact = if t < 1.0 { t } else { 10.0 + t * t };
            assert!((at(&mut h, t, Side::Right) - exact).abs() < 1e-12, "at {t}");
        }
        assert_eq!((at(&mut h, 1.0, Side::Left), at(&mut h, 1.0, Side::Right)), (1.0, 11.0));
        assert!((at(&mut h, 0.999_999, Side::Right) - 0.999_999).abs() < 1e-12);
    }

    #[test]
    fn a_jump_between_samples_that_no_breakpoint_marks_does_not_overshoot() {
        // A step of 2 at 1.7358 sampled unevenly (as a solver steps over an
        // `fcn`'s switch): away from the interval holding it the stencils
        // turn away and are exact; inside it the value stays between the sides.
        let times: Vec<f64> = (0..60).map(|i| 0.037 * i as f64 + 0.011 * (i as f64 * 2.3).sin()).collect();
        let step = |t: f64| if t >= 1.7358 { 2.0 } else { 0.0 };
        for degree in [3, 5] {
            let mut h = sampled(degree, &times, step);
            let jump = times.windows(2).position(|w| w[1] >= 1.7358).unwrap();
            for q in 0..2000 {
                let t = 0.001 * q as f64;
                let got = at(&mut h, t, Side::Right);
                if t < times[jump] || t > times[jump + 1] {
                    assert!((got - step(t)).abs() < 1e-12, "degree {degree} at {t}: {got}");
                } else {
                    assert!((-1e-12..=2.0 + 1e-12).contains(&got), "degree {degree} at {t}: {got}");
                }
            }
        }
    }

    #[test]
    fn a_restart_at_one_time_replaces_and_a_continuous_breakpoint_is_no_jump() {
        let mut h = History::new(1, 8, 100, 1);
        h.push(0.0, |_| 1.0, f64::NEG_INFINITY);
        h.push(1.0, |_| 2.0, f64::NEG_INFINITY);
        h.push(1.0, |_| 3.0, f64::NEG_INFINITY);
        assert_eq!(at(&mut h, 0.5, Side::Right), 2.0);
        h.push_left(2.0, |_| 4.0, f64::NEG_INFINITY);
        assert!(!h.push(2.0, |_| 4.0, f64::NEG_INFINITY));
    }

    #[test]
    fn samples_older_than_needed_are_dropped_but_a_stencil_is_kept() {
        let mut h = History::new(1, 8, 8, 3);
        for i in 0..1000 {
            let t = i as f64;
            h.push(t, |_| t * t * t, t - 2.5);
        }
        assert!(h.overflow.is_none());
        assert!((at(&mut h, 997.5, Side::Right) - 997.5f64.powi(3)).abs() < 1e-6);
    }
}
