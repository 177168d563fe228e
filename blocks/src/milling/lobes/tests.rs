//! The zeroth-order lobes against closed forms, the block's own force
//! equations, and an independent NumPy computation.

use super::*;

fn cutter(entry: f64, exit: f64) -> Cutter {
    Cutter { teeth: 3, omega: 1.0, kt: 796.0, kr: 0.212, ap: 1.0, feed: 0.0, entry, exit, phase: 0.0 }
}

/// A single mode 1/k · ω²/(ω² − ωc² + 2iζωωc) [mm/N].
fn mode(w: f64, zeta: f64, k: f64, wc: f64) -> c64 {
    c64::new(w * w / k, 0.0) / c64::new(w * w - wc * wc, 2.0 * zeta * w * wc)
}

#[test]
fn slotting_factors_in_closed_form() {
    // From 0 to π: αxx = αyy = −π·Kr, αxy = −π, αyx = π.
    let a = directional_factors(0.0, PI, 0.212);
    let want = [[-PI * 0.212, -PI], [PI, -PI * 0.212]];
    for (row, want_row) in a.iter().zip(&want) {
        for (v, w) in row.iter().zip(want_row) {
            assert!((v - w).abs() < 1e-12, "{a:?}");
        }
    }
}

#[test]
fn factors_are_the_pitch_average_of_the_blocks_force() {
    // A constant displacement change (dx, dy) without feed: the block's
    // force averaged over a tooth pitch is (N·ap·Kt/4π)·α·(dx, dy).
    let c = Cutter { feed: 0.0, ap: 1.5, ..cutter(0.3, 2.1) };
    let (dx, dy) = (0.01, -0.004);
    let a = directional_factors(c.entry, c.exit, c.kr);
    // Midpoint rule over the cut (the force is zero outside it).
    let n = 20_000;
    let (mut fx, mut fy) = (0.0, 0.0);
    let width = (c.exit - c.entry) / n as f64;
    for i in 0..n {
        let sc = (c.entry + width * (i as f64 + 0.5)).sin_cos();
        let [_, _, x, y] = c.tooth_force(sc, c.chip(sc, dx, dy));
        fx += x * width;
        fy += y * width;
    }
    // One tooth's mean over a turn, times N: the N-tooth sum's mean over a pitch.
    let (fx, fy) = (fx / TAU * c.teeth as f64, fy / TAU * c.teeth as f64);
    let scale = c.teeth as f64 * c.ap * c.kt / (4.0 * PI);
    assert!((fx - scale * (a[0][0] * dx + a[0][1] * dy)).abs() < 1e-8 * fx.abs(), "{fx}");
    assert!((fy - scale * (a[1][0] * dx + a[1][1] * dy)).abs() < 1e-8 * fy.abs(), "{fy}");
}

#[test]
fn single_mode_slotting_minimum_is_tlustys() {
    // Φyy = 0 and slotting: a_lim = 2π/(N·Kt·αxx·Re Φxx), lowest where
    // Re Φxx = −1/(4kζ(1+ζ)): a_min = 8kζ(1+ζ)/(N·Kt·Kr).
    let c = cutter(0.0, PI);
    let (w, zeta, k) = (5000.0, 0.03, 2.0e4);
    let freqs: Vec<f64> = (0..20_000).map(|i| w * (1.0 + 0.2 * i as f64 / 20_000.0)).collect();
    let curves = lobes(&c, |wc| (mode(w, zeta, k, wc), c64::new(0.0, 0.0)), &freqs, 4);
    let lowest = curves.iter().flatten().map(|p| p.depth).fold(f64::INFINITY, f64::min);
    let want = 8.0 * k * zeta * (1.0 + zeta) / (3.0 * 796.0 * 0.212);
    assert!((lowest - want).abs() < 1e-6 * want, "{lowest} vs {want}");
    // One root only, and each lobe's speeds fall as the lobe number rises.
    assert!(curves.iter().all(|curve| curve.iter().all(|p| p.root == 1)));
    let top = |lobe| curves.iter().flatten().filter(|p| p.lobe == lobe).map(|p| p.rpm).fold(0.0, f64::max);
    assert!(top(0) > top(1) && top(1) > top(2) && top(2) > top(3));
    // Between lobes the boundary rises above the minimum; at the bottom of
    // lobe 1 it touches it.
    let bottom = curves.iter().flatten().filter(|p| p.lobe == 1).min_by(|a, b| a.depth.total_cmp(&b.depth)).unwrap();
    let at = critical_depth_at(&curves, bottom.rpm).unwrap();
    assert!((at - want).abs() < 1e-3 * want, "{at}");
}

#[test]
fn two_modes_match_numpy() {
    // Up-milling at ae/D = 0.7, the milling graphs' tool; reference values
    // from NumPy 2: the eigenvalues of α·diag(Φxx, Φyy), Λ = −1/eig (a
    // different route from the quadratic here).
    let c = cutter(0.0, (1.0f64 - 1.4).acos());
    let a = directional_factors(c.entry, c.exit, c.kr);
    let numpy = [-1.3379708764332765, -1.7937871172659174, 2.170839228458852, 0.4974700911396256];
    for (v, w) in a.iter().flatten().zip(numpy) {
        assert!((v - w).abs() < 1e-12);
    }
    // (ωc, a_lim, ε, lobe-1 rpm) of the root that can chatter.
    let cases = [
        (5800.0, 2.6654404783637973, 1.8004498032618337, 14349.979732529717),
        (6000.0, 7.4709156070407206, 1.1432349741765462, 16158.525299363599),
    ];
    for (wc, depth, eps, rpm) in cases {
        let roots = eigenvalues(&a, mode(5657.0, 0.0199, 2.0e4, wc), mode(5629.0, 0.02, 2.0e4, wc));
        let found: Vec<(f64, f64)> = roots.iter().filter_map(|&l| critical_depth(&c, l)).collect();
        assert_eq!(found.len(), 1, "{roots:?}");
        let (d, e) = found[0];
        assert!((d - depth).abs() < 1e-9 * depth && (e - eps).abs() < 1e-9, "{d} {e}");
        let curves = lobes(&c, |w| (mode(5657.0, 0.0199, 2.0e4, w), mode(5629.0, 0.02, 2.0e4, w)), &[wc], 2);
        let lobe1 = curves.iter().flatten().find(|p| p.lobe == 1).unwrap();
        assert!((lobe1.rpm - rpm).abs() < 1e-9 * rpm && lobe1.chatter == wc);
    }
}

#[test]
fn no_lobe_no_depth() {
    assert_eq!(critical_depth_at(&[], 1000.0), None);
    let p = LobePoint { rpm: 1000.0, depth: 1.0, chatter: 1.0, lobe: 0, root: 0 };
    let q = LobePoint { rpm: 2000.0, depth: 3.0, ..p };
    assert_eq!(critical_depth_at(&[vec![p, q]], 1500.0), Some(2.0));
    assert_eq!(critical_depth_at(&[vec![p, q]], 2500.0), None);
}
