//! The FLADRC paper's scenario (graphs/fladrc: 2 s at h = 1e-4, 20 001
//! samples) run by ctlgraph beside the same loops written by hand in plain
//! Rust: the fuzzy-tuned LADRC and the plain LADRC, plant advanced by its
//! exact zero-order-hold transition, every block's equation evaluated in
//! the graph's order. Reported per run of the scenario; the README's table
//! divides by 20 001 samples. `ladrc_fused_blocks` runs the LADRC graph's
//! own blocks without the interpreter (computing what it computes, to the
//! bit): the price of the blocks' code apart from the interpreter's.
//! `fladrc_compiled` and `ladrc_compiled` run the graphs' generated steps
//! (`ctlgraph codegen`, built by the `ctlgraph-compiled-graphs` crate);
//! `fladrc_accelerated` and `ladrc_accelerated` the same steps as
//! `--accelerate` builds, loads and runs them.
//!
//!     cargo bench --bench fladrc

use criterion::{Criterion, criterion_group, criterion_main};
use ctlgraph_blocks::fuzzy::fis::{Connective, Fis, Methods, Rule, Variable, uniform_triangles};
use ctlgraph_compiled_graphs::{graphs_fladrc_fladrc, graphs_fladrc_ladrc};
use ctlgraph_core::codegen::{Compiled, GeneratedStep};
use ctlgraph_core::{Model, Simulator};
use nalgebra::Matrix3;
use std::hint::black_box;
use std::path::Path;

mod accelerated;
mod fused_ladrc;
mod paired;
use ctlgraph::accel::AcceleratedRun;
use fused_ladrc::{Fused, H, Noise, SAMPLES};
use paired::Paired;

/// The command line's allocator (src/main.rs), so the benches measure what it does.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Plant 1.639e4 / (s² + 154.8 s + 2.242e4), controllable canonical form.
const PLANT: ([f64; 2], f64) = ([154.8, 2.242e4], 1.639e4);
const B0: f64 = 1.64e4;
const BETA: [f64; 3] = [3.0e3, 1.0e6, 1.0e9];
const DELTA: f64 = 1.0e4;
const H0: f64 = 5.0 * H;

/// x(k+1) = Φ x(k) + Γ u(k) for the plant, from exp([A B; 0 0]·h) (what an
/// engineer would take from a library: nalgebra's Padé matrix exponential).
fn plant_zoh() -> ([[f64; 2]; 2], [f64; 2]) {
    let ([a1, a2], _) = PLANT;
    let m = Matrix3::new(-a1, -a2, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0) * H;
    let e = m.exp();
    ([[e[(0, 0)], e[(0, 1)]], [e[(1, 0)], e[(1, 1)]]], [e[(0, 2)], e[(1, 2)]])
}

fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Han's fst with c = x1 + h0·x2.
fn fst(x1: f64, x2: f64) -> f64 {
    let d = DELTA * H0;
    let d0 = H0 * d;
    let c = x1 + H0 * x2;
    let a0 = (d * d + 8.0 * DELTA * c.abs()).sqrt();
    let a = if c.abs() > d0 { x2 + (a0 - d) / 2.0 * sign(c) } else { x2 + c / H0 };
    if a.abs() > d { -DELTA * sign(a) } else { -DELTA * a / d }
}

/// The paper's 7×7 rule tables (rows e1 NB..PB, columns e2 NB..PB), terms
/// numbered NB = 0 … PB = 6.
const K1: [[u8; 7]; 7] = [
    [6, 6, 5, 5, 4, 3, 3],
    [6, 6, 5, 4, 4, 3, 2],
    [5, 5, 5, 4, 3, 2, 2],
    [5, 5, 4, 3, 2, 1, 1],
    [4, 4, 3, 2, 2, 1, 1],
    [4, 3, 2, 1, 1, 1, 0],
    [3, 3, 1, 1, 1, 0, 0],
];
const K2: [[u8; 7]; 7] = [
    [4, 2, 0, 0, 0, 1, 4],
    [4, 2, 0, 1, 1, 2, 3],
    [3, 2, 1, 1, 2, 2, 3],
    [3, 2, 2, 2, 2, 2, 3],
    [3, 3, 3, 3, 3, 3, 3],
    [6, 2, 4, 4, 4, 4, 6],
    [6, 5, 5, 5, 4, 4, 6],
];
const GRID: usize = 201;
/// Inputs the fuzzy system's bench cycles through.
const INPUTS: usize = 1024;

/// The Mamdani system written for this one case: uniform triangles, min
/// AND and implication, max aggregation, centroid of the piecewise-linear
/// aggregate on 201 points (its moment and area are linear in the samples,
/// so each is one dot product with weights computed once).
struct Fuzzy {
    /// Per output term, its membership on the output grid.
    terms: [[f64; GRID]; 7],
    /// Per term, the grid indices [a, b) where it is nonzero.
    support: [(usize, usize); 7],
    moment: [f64; GRID],
    area: [f64; GRID],
}

impl Fuzzy {
    fn new(lo: f64, hi: f64) -> Self {
        let x: Vec<f64> = (0..GRID).map(|j| lo + (hi - lo) * j as f64 / (GRID - 1) as f64).collect();
        let step = (hi - lo) / 6.0;
        let mut terms = [[0.0; GRID]; 7];
        for (t, row) in terms.iter_mut().enumerate() {
            let peak = if t == 6 { hi } else { lo + t as f64 * step };
            for (j, m) in row.iter_mut().enumerate() {
                *m = (1.0 - (x[j] - peak).abs() / step).max(0.0);
            }
        }
        let (mut moment, mut area) = ([0.0; GRID], [0.0; GRID]);
        for j in 0..GRID - 1 {
            let dx = x[j + 1] - x[j];
            area[j] += 0.5 * dx;
            area[j + 1] += 0.5 * dx;
            moment[j] += 0.5 * dx * (x[j] + dx / 3.0);
            moment[j + 1] += 0.5 * dx * (x[j] + 2.0 * dx / 3.0);
        }
        let support = terms.map(|mu| {
            let a = mu.iter().position(|&m| m > 0.0).unwrap_or(0);
            (a, mu.iter().rposition(|&m| m > 0.0).map_or(a, |b| b + 1))
        });
        Fuzzy { terms, support, moment, area }
    }

    /// Memberships of the two adjacent terms an input falls between.
    fn fuzzify(x: f64) -> (usize, f64) {
        let pos = (x.clamp(-0.1, 0.1) + 0.1) / (0.2 / 6.0);
        let i = (pos.floor() as usize).min(5);
        (i, pos - i as f64)
    }

    fn output(&self, table: &[[u8; 7]; 7], (i, fi): (usize, f64), (j, fj): (usize, f64)) -> f64 {
        let mut w = [0.0f64; 7];
        for (a, ma) in [(i, 1.0 - fi), (i + 1, fi)] {
            for (b, mb) in [(j, 1.0 - fj), (j + 1, fj)] {
                let t = table[a][b] as usize;
                w[t] = w[t].max(ma.min(mb));
            }
        }
        // Each term is zero outside a third of the grid: aggregate and
        // integrate only where the firing terms are not.
        let mut mu = [0.0f64; GRID];
        let (mut from, mut to) = (GRID, 0);
        for (t, &wt) in w.iter().enumerate() {
            if wt > 0.0 {
                let (a, b) = self.support[t];
                (from, to) = (from.min(a), to.max(b));
                for (m, &term) in mu[a..b].iter_mut().zip(&self.terms[t][a..b]) {
                    let v = if wt < term { wt } else { term };
                    *m = if v > *m { v } else { *m };
                }
            }
        }
        // Four running sums each, so the dot products vectorise.
        let (mut moment, mut area) = ([0.0f64; 4], [0.0f64; 4]);
        let (m, a, u) = (&self.moment[from..to], &self.area[from..to], &mu[from..to]);
        let (mc, ac, uc) = (m.chunks_exact(4), a.chunks_exact(4), u.chunks_exact(4));
        let tail = mc.remainder().iter().zip(ac.remainder()).zip(uc.remainder());
        let (tail_m, tail_a) = tail.fold((0.0, 0.0), |(sm, sa), ((m, a), u)| (sm + m * u, sa + a * u));
        for ((m, a), u) in mc.zip(ac).zip(uc) {
            for k in 0..4 {
                moment[k] += m[k] * u[k];
                area[k] += a[k] * u[k];
            }
        }
        let moment = moment.iter().sum::<f64>() + tail_m;
        let area = area.iter().sum::<f64>() + tail_a;
        moment / area
    }
}

/// The whole scenario by hand: the sum of y over the samples (what the
/// timing keeps alive) and y at the end. `sigma` is the noise's standard
/// deviation (0 for the agreement check).
fn hand_written(fuzzy: Option<&Fuzzy>, sigma: f64, (phi, gamma): ([[f64; 2]; 2], [f64; 2])) -> (f64, f64) {
    let (mut r1, mut r2) = (0.0, 0.0);
    let mut z = [0.0f64; 3];
    let mut x = [0.0f64; 2];
    let mut noise = Noise(1);
    let mut held_noise = 0.0;
    let mut sink = 0.0;
    let mut y = 0.0;
    for k in 0..=SAMPLES {
        let r = 1.0;
        let d = if k >= 6000 { 0.5 } else { 0.0 } + if (12_000..16_000).contains(&k) { held_noise } else { 0.0 };
        let (e1, e2) = (r1 - z[0], r2 - z[1]);
        let (a1, a2) = match fuzzy {
            Some(f) => {
                let (f1, f2) = (Fuzzy::fuzzify(e1), Fuzzy::fuzzify(e2));
                (5.0 * (1.0 + f.output(&K1, f1, f2)), 0.08 * (1.0 + f.output(&K2, f1, f2)))
            }
            None => (5.0, 0.08),
        };
        let u = a1 * e1 + a2 * e2 - z[2] / B0;
        y = PLANT.1 * x[1];
        sink += y;
        if k == SAMPLES {
            break;
        }
        let f = fst(r1 - r, r2);
        r1 += H * r2;
        r2 += H * f;
        let e = z[0] - y;
        let dz = [z[1] - BETA[0] * e, z[2] - BETA[1] * e + B0 * u, -BETA[2] * e];
        for (zi, di) in z.iter_mut().zip(dz) {
            *zi += H * di;
        }
        if k % 40 == 0 {
            held_noise = sigma * noise.normal();
        }
        let v = u + d;
        x = [phi[0][0] * x[0] + phi[0][1] * x[1] + gamma[0] * v, phi[1][0] * x[0] + phi[1][1] * x[1] + gamma[1] * v];
    }
    (sink, y)
}

fn model(file: &str, sets: &[(&str, &str)]) -> Model {
    let sets: Vec<(String, String)> = sets.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
    ctlgraph::compile_file(Path::new(file), &sets).expect("graph compiles")
}

fn simulator(file: &str, sets: &[(&str, &str)]) -> (Simulator, usize) {
    let model = model(file, sets);
    let y = model.columns.iter().find(|c| c.name == "y").expect("y recorded").offset;
    (Simulator::new(model, None), y)
}

/// The graph's run: the same sum of y over the samples, and y at the end.
fn graph((sim, y): &mut (Simulator, usize)) -> (f64, f64) {
    sim.reset();
    let mut sink = 0.0;
    let mut last = 0.0;
    sim.run(&mut |_, s| {
        sink += s[*y];
        last = s[*y];
    })
    .expect("runs");
    (sink, last)
}

fn generated<G: GeneratedStep>(file: &str) -> (Compiled<G>, usize) {
    let model = model(file, &[]);
    let y = model.columns.iter().find(|c| c.name == "y").expect("y recorded").offset;
    (Compiled::new(&model, None).expect("generated for this graph"), y)
}

/// The generated step's run, as `graph`.
fn compiled<G: GeneratedStep>((run, y): &mut (Compiled<G>, usize)) -> (f64, f64) {
    run.reset();
    let mut sink = 0.0;
    let mut last = 0.0;
    run.run(|_, s| {
        sink += s[*y];
        last = s[*y];
    })
    .expect("runs");
    (sink, last)
}

/// The graph's accelerated run as `--accelerate` runs it, the same sum of
/// y and y at the end (`y` its column in the rows).
fn accelerated_run(run: &mut AcceleratedRun, y: usize) -> (f64, f64) {
    accelerated::sum_column(run, y, u64::MAX)
}

/// The graph `file`'s accelerated run, and y's column in its rows.
fn library(file: &str) -> (AcceleratedRun, usize) {
    let model = model(file, &[]);
    let text = std::fs::read_to_string(file).expect("the graph");
    (accelerated::accelerated(&model, &text, file), accelerated::row_column(&model, "y"))
}

fn bench(c: &mut Criterion) {
    let zoh = plant_zoh();
    let fuzzy = Fuzzy::new(-0.2, 0.2);
    for (file, f) in [("graphs/fladrc/fladrc.yaml", Some(&fuzzy)), ("graphs/fladrc/ladrc.yaml", None)] {
        // Same equations, same order: the two agree before they are timed
        // (noise off, so that the two random streams do not matter).
        let (by_graph, _) = graph(&mut simulator(file, &[("noise_power", "0")]));
        let (by_hand, _) = hand_written(f, 0.0, zoh);
        let rel = (by_graph - by_hand).abs() / by_hand.abs();
        assert!(rel < 1e-12, "{file}: graph Σy = {by_graph} vs hand {by_hand}");
    }
    let mut fused = Fused::new(&model("graphs/fladrc/ladrc.yaml", &[]));
    let (by_fused, by_graph) =
        (fused.run(0.0).0, graph(&mut simulator("graphs/fladrc/ladrc.yaml", &[("noise_power", "0")])).0);
    assert_eq!(by_fused, by_graph, "the fused blocks compute what the interpreter does, to the bit");
    let mut fladrc_compiled = generated::<graphs_fladrc_fladrc::Step>("graphs/fladrc/fladrc.yaml");
    let mut ladrc_compiled = generated::<graphs_fladrc_ladrc::Step>("graphs/fladrc/ladrc.yaml");
    let (mut fladrc_library, mut ladrc_library) =
        (library("graphs/fladrc/fladrc.yaml"), library("graphs/fladrc/ladrc.yaml"));
    for (by_compiled, by_library, file) in [
        (
            compiled(&mut fladrc_compiled),
            accelerated_run(&mut fladrc_library.0, fladrc_library.1),
            "graphs/fladrc/fladrc.yaml",
        ),
        (
            compiled(&mut ladrc_compiled),
            accelerated_run(&mut ladrc_library.0, ladrc_library.1),
            "graphs/fladrc/ladrc.yaml",
        ),
    ] {
        let by_graph = graph(&mut simulator(file, &[]));
        assert_eq!(by_compiled, by_graph, "{file}: the generated step computes what the interpreter does, to the bit");
        assert_eq!(by_library, by_graph, "{file}: the accelerated run computes what the interpreter does, to the bit");
    }
    let sigma = (1.44e-5f64 / 0.004).sqrt();
    const GROUP: &str = "fladrc_scenario_20k_samples";
    const CRITERION_SAMPLES: usize = 30;
    let mut group = c.benchmark_group(GROUP);
    group.sample_size(CRITERION_SAMPLES);
    let mut paired = [
        Paired::new(GROUP, "fladrc_ctlgraph", "fladrc_hand_written"),
        Paired::new(GROUP, "ladrc_ctlgraph", "ladrc_hand_written"),
        Paired::new(GROUP, "ladrc_fused_blocks", "ladrc_hand_written"),
        Paired::new(GROUP, "fladrc_compiled", "fladrc_hand_written"),
        Paired::new(GROUP, "ladrc_compiled", "ladrc_hand_written"),
        Paired::new(GROUP, "fladrc_accelerated", "fladrc_hand_written"),
        Paired::new(GROUP, "ladrc_accelerated", "ladrc_hand_written"),
    ];
    let (fladrc_by_hand, ladrc_by_hand) =
        (|| hand_written(Some(&fuzzy), sigma, zoh), || hand_written(None, sigma, zoh));
    let mut sim = simulator("graphs/fladrc/fladrc.yaml", &[]);
    group.bench_function("fladrc_hand_written", |b| b.iter(|| black_box(fladrc_by_hand())));
    group.bench_function("fladrc_ctlgraph", |b| paired[0].run(b, || graph(&mut sim), fladrc_by_hand));
    group.bench_function("fladrc_compiled", |b| paired[3].run(b, || compiled(&mut fladrc_compiled), fladrc_by_hand));
    group.bench_function("fladrc_accelerated", |b| {
        paired[5].run(b, || accelerated_run(&mut fladrc_library.0, fladrc_library.1), fladrc_by_hand)
    });
    let mut sim = simulator("graphs/fladrc/ladrc.yaml", &[]);
    group.bench_function("ladrc_hand_written", |b| b.iter(|| black_box(ladrc_by_hand())));
    group.bench_function("ladrc_ctlgraph", |b| paired[1].run(b, || graph(&mut sim), ladrc_by_hand));
    group.bench_function("ladrc_fused_blocks", |b| paired[2].run(b, || fused.run(sigma), ladrc_by_hand));
    group.bench_function("ladrc_compiled", |b| paired[4].run(b, || compiled(&mut ladrc_compiled), ladrc_by_hand));
    group.bench_function("ladrc_accelerated", |b| {
        paired[6].run(b, || accelerated_run(&mut ladrc_library.0, ladrc_library.1), ladrc_by_hand)
    });
    group.finish();
    paired.iter().for_each(|p| p.save(CRITERION_SAMPLES));
    // The fuzzy system alone, one evaluation, hand-written and as a block.
    let mut group = c.benchmark_group("fuzzy_7x7_two_outputs");
    // Inputs from a table (the same sweep as before: steps of 0.0137
    // wrapped into [0, 0.1)), so that the harness's own work per call is a
    // load, not an `fmod` (a libm call, about 10 ns timed with each
    // evaluation).
    let inputs: Vec<[f64; 2]> = (0..INPUTS).map(|k| (k as f64 * 0.0137) % 0.1).map(|e| [e, -0.5 * e]).collect();
    let mut k = 0;
    let mut next = move || {
        k = (k + 1) % INPUTS;
        black_box(inputs[k])
    };
    group.bench_function("hand_written", |b| {
        b.iter(|| {
            let [e1, e2] = next();
            let (f1, f2) = (Fuzzy::fuzzify(e1), Fuzzy::fuzzify(e2));
            black_box(fuzzy.output(&K1, f1, f2) + fuzzy.output(&K2, f1, f2))
        })
    });
    let mut fis = paper_fis();
    let mut y = [0.0; 2];
    group.bench_function("ctlgraph_fis", |b| {
        b.iter(|| {
            fis.eval(&next(), &mut y);
            black_box(y[0] + y[1])
        })
    });
    group.finish();
}

/// The graph's fuzzy block as the library builds it (the rule tables above).
fn paper_fis() -> Fis {
    const NAMES: [&str; 7] = ["NB", "NM", "NS", "ZO", "PS", "PM", "PB"];
    let var = |lo: f64, hi: f64| Variable { name: String::new(), lo, hi, terms: uniform_triangles(lo, hi, &NAMES) };
    let mut rules = Vec::new();
    for (o, table) in [K1, K2].iter().enumerate() {
        for (i, row) in table.iter().enumerate() {
            for (j, &t) in row.iter().enumerate() {
                let (antecedents, consequents) = (vec![(0, i, false), (1, j, false)], vec![(o, t as usize)]);
                rules.push(Rule { antecedents, connective: Connective::And, consequents });
            }
        }
    }
    let (inputs, outputs) = (vec![var(-0.1, 0.1), var(-0.1, 0.1)], vec![var(-0.2, 0.2), var(-0.2, 0.2)]);
    Fis::new(inputs, outputs, rules, Methods::default(), false)
}

criterion_group!(benches, bench);
criterion_main!(benches);
