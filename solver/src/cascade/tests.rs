use super::*;
use crate::freq::{at_frequency, c64, evaluate, poles};

/// The product's value at s, factor by factor.
fn product_at(num: &[Vec<f64>], den: &[Vec<f64>], gain: f64, s: c64) -> c64 {
    let ev = |p: &[f64]| p.iter().fold(c64::new(0.0, 0.0), |acc, &c| acc * s + c64::new(c, 0.0));
    let prod = |fs: &[Vec<f64>]| fs.iter().fold(c64::new(1.0, 0.0), |acc, f| acc * ev(f));
    prod(num) * gain / prod(den)
}

/// The milling paper's H-infinity controller, eq. 12, as printed.
fn eq12() -> (Vec<Vec<f64>>, Vec<Vec<f64>>, f64) {
    let num = vec![vec![1.0, 1200.0], vec![1.0, 225.4, 3.169e7], vec![1.0, 225.0, 3.2e7]];
    let den = vec![vec![1.0, 1000.0], vec![1.0, 4042.0], vec![1.0, 231.3, 3.193e7], vec![1.0, 4.681e4, 6.43e8]];
    (num, den, -5.2485e8)
}

#[test]
fn series_is_the_product_of_the_responses() {
    let g1 = tf2ss(&[2.0, 1.0], &[1.0, 3.0, 5.0]).unwrap();
    let g2 = tf2ss(&[0.5, 4.0], &[1.0, 7.0]).unwrap();
    let g = g1.series(&g2).unwrap();
    assert_eq!((g.n, g.m, g.p), (3, 1, 1));
    for s in [c64::new(0.0, 0.0), c64::new(0.0, 2.0), c64::new(-1.0, 10.0)] {
        let (a, b) = (evaluate(&g, s), evaluate(&g1, s) * evaluate(&g2, s));
        assert!((a - b).norm() < 1e-12 * b.norm(), "{s}: {a} vs {b}");
    }
    // Two outputs cannot drive one input.
    let two =
        StateSpace::new(vec![vec![-1.0]], vec![vec![1.0]], vec![vec![1.0], vec![2.0]], vec![vec![0.0], vec![0.0]])
            .unwrap();
    assert!(two.series(&g2).is_err());
}

#[test]
fn the_papers_controller_matches_python_control() {
    // python-control 0.10.2, F = tf(expanded num, expanded den): dcgain(F) and F(jω).
    let (num, den, k) = eq12();
    let f = factored_tf2ss(&num, &den, k).unwrap();
    assert_eq!(f.n, 6);
    let dc = at_frequency(&f, 0.0, None);
    assert!((dc.re + 7696.308442383507).abs() < 1e-9 * 7696.3 && dc.im.abs() < 1e-9, "{dc}");
    for (w, mag, deg) in [
        (1000.0, 6653.066429149861, 157.14746726498922),
        (5657.0, 145.49211950789652, -159.16254094776352),
        (20000.0, 9799.08742215955, -155.2768203512227),
    ] {
        let v = at_frequency(&f, w, None);
        assert!((v.norm() - mag).abs() < 1e-9 * mag, "{w}: |F| = {}", v.norm());
        assert!((v.arg().to_degrees() - deg).abs() < 1e-7, "{w}: arg F = {}", v.arg().to_degrees());
    }
    // The poles are the denominator factors' roots.
    let p = poles(&f).unwrap();
    for root in [-1000.0, -4042.0] {
        assert!(p.iter().any(|z| (z.re - root).abs() < 1e-6 * root.abs() && z.im == 0.0), "{root} in {p:?}");
    }
    let quad = |b: f64, c: f64| c64::new(-b / 2.0, (c - b * b / 4.0).sqrt());
    for z in [quad(231.3, 3.193e7), quad(4.681e4, 6.43e8)] {
        assert!(p.iter().any(|q| (q - z).norm() < 1e-8 * z.norm()), "{z} in {p:?}");
    }
}

#[test]
fn sections_keep_the_coefficients_as_written() {
    // The spread of the realisation's nonzero coefficients (A, B, C, D): the cascade's are
    // within 1e15 (1.1e14), the expanded companion form's 6.4e26.
    let (num, den, k) = eq12();
    let f = factored_tf2ss(&num, &den, k).unwrap();
    let companion =
        tf2ss(&poly::product(&num).iter().map(|c| c * k).collect::<Vec<_>>(), &poly::product(&den)).unwrap();
    let spread = |ss: &StateSpace| {
        let a: Vec<f64> =
            ss.a.iter().chain(&ss.b).chain(&ss.c).chain(&ss.d).map(|v| v.abs()).filter(|v| *v > 0.0).collect();
        a.iter().copied().fold(0.0, f64::max) / a.iter().copied().fold(f64::INFINITY, f64::min)
    };
    assert!(spread(&f) < 1e15, "cascade: {:e}", spread(&f));
    assert!(spread(&companion) > 1e26, "companion: {:e}", spread(&companion));
}

#[test]
fn factors_that_fit_nowhere_fall_back_to_the_expanded_form() {
    // (s² + 1)/((s + 1)(s + 2)): the quadratic zero fits no first-order section.
    let (num, den) = (vec![vec![1.0, 0.0, 1.0]], vec![vec![1.0, 1.0], vec![1.0, 2.0]]);
    let g = factored_tf2ss(&num, &den, 3.0).unwrap();
    for w in [0.0, 0.5, 1.0, 4.0] {
        let s = c64::new(0.0, w);
        let (a, b) = (evaluate(&g, s), product_at(&num, &den, 3.0, s));
        assert!((a - b).norm() < 1e-12 * b.norm().max(1.0), "{w}: {a} vs {b}");
    }
    // Constants, a zero at the origin (no DC scaling) and a leading zero coefficient.
    let (num, den) = (vec![vec![0.0, 2.0], vec![1.0, 0.0]], vec![vec![1.0, 5.0], vec![1.0, 1.0, 9.0]]);
    let g = factored_tf2ss(&num, &den, -0.5).unwrap();
    for w in [0.0, 0.5, 3.0, 40.0] {
        let s = c64::new(0.0, w);
        let (a, b) = (evaluate(&g, s), product_at(&num, &den, -0.5, s));
        assert!((a - b).norm() < 1e-12 * b.norm().max(1.0), "{w}: {a} vs {b}");
    }
}

#[test]
fn improper_and_degenerate_products_are_reported() {
    let err = factored_tf2ss(&[vec![1.0, 1.0], vec![1.0, 2.0]], &[vec![1.0, 3.0]], 1.0);
    assert_eq!(err, Err(LtiError::Improper { num_degree: 2, den_degree: 1 }));
    assert_eq!(factored_tf2ss(&[vec![1.0]], &[vec![0.0, 0.0]], 1.0), Err(LtiError::ZeroDenominator));
    // A zero numerator factor: the zero system.
    let z = factored_tf2ss(&[vec![0.0]], &[vec![1.0, 1.0]], 2.0).unwrap();
    assert_eq!(evaluate(&z, c64::new(0.0, 1.0)), c64::new(0.0, 0.0));
    // No factors at all: the gain.
    let k = factored_tf2ss(&[], &[], 4.0).unwrap();
    assert_eq!((k.n, k.d[0]), (0, 4.0));
}

#[test]
fn series_of_two_output_systems_by_hand() {
    // G1: x1' = −x1 + u, y1 = [x1; 2x1 + u];  G2: x2' = −3x2 + [1 2]·y1, y2 = [x2 + y1a; 4x2 + y1b].
    let g1 = StateSpace::new(vec![vec![-1.0]], vec![vec![1.0]], vec![vec![1.0], vec![2.0]], vec![vec![0.0], vec![1.0]])
        .unwrap();
    let g2 = StateSpace::new(
        vec![vec![-3.0]],
        vec![vec![1.0, 2.0]],
        vec![vec![1.0], vec![4.0]],
        vec![vec![1.0, 0.0], vec![0.0, 1.0]],
    )
    .unwrap();
    let g = g1.series(&g2).unwrap();
    assert_eq!((g.n, g.m, g.p), (2, 1, 2));
    // A = [A1 0; B2·C1 A2] = [−1 0; 1·1 + 2·2 −3], B = [B1; B2·D1] = [1; 2],
    // C = [D2·C1 C2] = [1 1; 2 4], D = D2·D1 = [0; 1].
    assert_eq!(g.a, vec![-1.0, 0.0, 5.0, -3.0]);
    assert_eq!(g.b, vec![1.0, 2.0]);
    assert_eq!(g.c, vec![1.0, 1.0, 2.0, 4.0]);
    assert_eq!(g.d, vec![0.0, 1.0]);
}

#[test]
fn zeros_fill_sections_by_their_room_and_the_order_limit_holds() {
    // Three first-order zeros over a quadratic and a first-order pole: two go to the quadratic.
    let (num, den) = (vec![vec![1.0, 1.0], vec![1.0, 2.0], vec![1.0, 3.0]], vec![vec![1.0, 1.0, 1.0], vec![1.0, 5.0]]);
    let g = factored_tf2ss(&num, &den, 2.0).unwrap();
    for w in [0.0, 0.7, 3.0] {
        let s = c64::new(0.0, w);
        let (a, b) = (evaluate(&g, s), product_at(&num, &den, 2.0, s));
        assert!((a - b).norm() < 1e-12 * b.norm(), "{w}: {a} vs {b}");
    }
    // A constant over nothing is that constant.
    let k = factored_tf2ss(&[vec![2.0]], &[], 1.5).unwrap();
    assert_eq!((k.n, k.d[0]), (0, 3.0));
    // Order 100 is allowed, 101 is not.
    let poles = |n: usize| vec![vec![1.0, 1.0]; n];
    assert_eq!(factored_tf2ss(&[], &poles(100), 1.0).map(|g| g.n), Ok(100));
    assert_eq!(factored_tf2ss(&[], &poles(101), 1.0).map(|g| g.n), Err(LtiError::TooHigh { degree: 101 }));
}

#[test]
fn series_blocks_are_the_matrix_products() {
    // Two states and two outputs feeding two inputs: every block of the series connection is a
    // product over the two signals between them, checked against a plain triple loop.
    let g1 = StateSpace::new(
        vec![vec![-1.0, 2.0], vec![0.5, -3.0]],
        vec![vec![1.0], vec![-2.0]],
        vec![vec![1.0, 3.0], vec![-1.0, 4.0]],
        vec![vec![0.5], vec![2.0]],
    )
    .unwrap();
    let g2 = StateSpace::new(
        vec![vec![-2.0, 1.0, 0.0], vec![0.0, -1.0, 1.0], vec![1.0, 0.0, -4.0]],
        vec![vec![1.0, 2.0], vec![3.0, -1.0], vec![0.0, 5.0]],
        vec![vec![1.0, -1.0, 2.0]],
        vec![vec![0.25, -0.5]],
    )
    .unwrap();
    let g = g1.series(&g2).unwrap();
    let mul = |x: &[f64], y: &[f64], r: usize, q: usize, c: usize| {
        let mut out = vec![0.0; r * c];
        for i in 0..r {
            for j in 0..c {
                for l in 0..q {
                    out[i * c + j] += x[i * q + l] * y[l * c + j];
                }
            }
        }
        out
    };
    let b2c1 = mul(&g2.b, &g1.c, 3, 2, 2);
    for i in 0..3 {
        assert_eq!(g.a[(2 + i) * 5..(2 + i) * 5 + 2], b2c1[i * 2..i * 2 + 2], "row {i}");
    }
    assert_eq!(g.b[2..], mul(&g2.b, &g1.d, 3, 2, 1)[..]);
    assert_eq!(g.c[..2], mul(&g2.d, &g1.c, 1, 2, 2)[..]);
    assert_eq!(g.d, mul(&g2.d, &g1.d, 1, 2, 1));
}
