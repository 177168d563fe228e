//! How compile time and the cost of a step grow with the graph: a chain of
//! n gains (each feeding the next) and a fan-out of n gains from one
//! source, n = 10 … 100 000, each ending in an integrator so the
//! whole graph is live. Criterion reports per run: compile (parse, expand,
//! sort, lay out) and 100 RK4 steps; divide the step time by 100·n for ns
//! per block-step. The chain of no gains (the source into the integrator,
//! n = 0) times the step's fixed part, so that the cost of a gain beyond
//! it is (step(n) − step(0))/n. The chain is also written by hand
//! (`chain_by_hand`): what a loop with no interpreter costs at each n.
//!
//!     cargo bench --bench scaling

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use ctlgraph_core::Simulator;
use std::fmt::Write;
use std::hint::black_box;

/// The command line's allocator (src/main.rs), so the benches measure what it does.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

mod graphs;
use graphs::{HEADER, chain};

const STEPS: usize = 100;

/// `u → {g1 … gn}`, each gain into its own integrator.
fn fan_out(n: usize) -> String {
    let mut g = String::from(HEADER);
    for i in 1..=n {
        writeln!(g, "  g{i}: {{ type: gain, k: 1.0 }}\n  x{i}: {{ type: integrator }}").unwrap();
    }
    g.push_str("wires:\n");
    for i in 1..=n {
        writeln!(g, "  - u -> g{i}\n  - g{i} -> x{i}").unwrap();
    }
    g
}

fn bench(c: &mut Criterion) {
    for (shape, build) in [("chain", chain as fn(usize) -> String), ("fan_out", fan_out)] {
        let mut group = c.benchmark_group(format!("{shape}_compile"));
        group.sample_size(10);
        for n in [10, 1_000, 100_000] {
            let text = build(n);
            group.bench_with_input(BenchmarkId::from_parameter(n), &text, |b, text| {
                b.iter(|| black_box(ctlgraph::compile_str(text, "scaling.yaml", &[]).expect("compiles").signal_len))
            });
        }
        group.finish();
        let mut group = c.benchmark_group(format!("{shape}_{STEPS}_steps"));
        group.sample_size(10);
        // The chain of none, u → x: the step's fixed part.
        let sizes: &[usize] = if shape == "chain" { &[0, 10, 1_000, 100_000] } else { &[10, 1_000, 100_000] };
        for &n in sizes {
            let model = ctlgraph::compile_str(&build(n), "scaling.yaml", &[]).expect("compiles");
            let mut sim = Simulator::new(model, None);
            group.bench_function(BenchmarkId::from_parameter(n), |b| {
                b.iter(|| {
                    sim.reset();
                    for _ in 0..STEPS {
                        sim.outputs().expect("finite");
                        sim.advance().expect("steps");
                    }
                    black_box(sim.states()[0])
                })
            });
        }
        group.finish();
    }
    // The chain written by hand, RK4 as the graph's solver takes it, to see
    // what a loop with no interpreter does per block-step as n grows.
    let mut group = c.benchmark_group(format!("chain_by_hand_{STEPS}_steps"));
    group.sample_size(10);
    for n in [0, 10, 1_000, 100_000] {
        let model = ctlgraph::compile_str(&chain(n), "scaling.yaml", &[]).expect("compiles");
        let mut sim = Simulator::new(model, None);
        for _ in 0..STEPS {
            sim.outputs().expect("finite");
            sim.advance().expect("steps");
        }
        let gains = black_box(vec![1.0; n]);
        let (graph, by_hand) = (sim.states()[0], chain_by_hand(&gains));
        assert!((graph - by_hand).abs() < 1e-12, "n = {n}: graph x = {graph} vs hand {by_hand}");
        group.bench_function(BenchmarkId::from_parameter(n), |b| b.iter(|| black_box(chain_by_hand(&gains))));
    }
    group.finish();
}

/// `chain(n)` by hand: x' = g_n(…g_1(sin 2πt)), RK4 at h = 0.01 for
/// `STEPS` steps; returns x. Each stage evaluates the n gains in turn (a
/// chain of dependent multiplications, as the graph's); the sine is taken
/// at t + h/2 and t + h once each (the graph's source keeps its last value
/// too).
fn chain_by_hand(gains: &[f64]) -> f64 {
    const H: f64 = 0.01;
    let w = 2.0 * std::f64::consts::PI;
    let through = |u: f64| gains.iter().fold(u, |y, &k| k * y);
    let (mut x, mut u_start) = (0.0, 0.0f64.sin());
    for step in 0..STEPS {
        let t = step as f64 * H;
        let (u_mid, u_end) = ((w * (t + 0.5 * H)).sin(), (w * ((step + 1) as f64 * H)).sin());
        let (k1, k2, k3, k4) = (through(u_start), through(u_mid), through(u_mid), through(u_end));
        x += H / 6.0 * (k1 + 2.0 * (k2 + k3) + k4);
        u_start = u_end;
    }
    x
}

criterion_group!(benches, bench);
criterion_main!(benches);
