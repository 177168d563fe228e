//! Sweep throughput: the tutorial PID loop over a 20 × 20 grid of kp and
//! kd (400 cases), on one and on two worker threads, side by side; and the
//! cases on one thread compiled each from its text (what a sweep did
//! before cases were compiled on the structure) beside the sweep's way
//! (parsed once, each case's blocks built on the first's structure); and
//! the FLADRC scenario over 200 noise seeds on two jobs, interpreted and
//! accelerated (`--accelerate`: one step library for every case).
//!
//!     cargo bench --bench sweep

use criterion::{Criterion, criterion_group, criterion_main};
use ctlgraph::accel::{Accelerate, Runner};
use ctlgraph::sweep::{self, Keep, SweepSpec, Vary};
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// The command line's allocator (src/main.rs), so the benches measure what it does.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench(c: &mut Criterion) {
    let file = Path::new("graphs/tutorial/pid_loop.yaml");
    let text = std::fs::read_to_string(file).expect("the tutorial graph");
    let vary = vec![Vary::parse("kp=1..4:20").expect("grid"), Vary::parse("kd=0..0.3:20").expect("grid")];
    let names: Vec<String> = vary.iter().map(|v| v.name().to_string()).collect();
    let spec = SweepSpec { vary, random: None, seeds: None, draw_seed: 0, shard: None };
    let cases = sweep::cases(&spec).expect("cases");
    let never = |_: &sweep::Case| false;
    let keep = Keep { traces_dir: None, in_memory: &never };
    let stop = AtomicBool::new(false);
    let mut group = c.benchmark_group("pid_loop_sweep_400_cases");
    group.sample_size(20);
    for jobs in [1, 2] {
        group.bench_function(format!("jobs_{jobs}"), |b| {
            b.iter(|| {
                sweep::run(&Runner::Interpreted, &text, file, &names, &cases, jobs, &keep, &stop, &|| {})
                    .expect("runs")
                    .len()
            })
        });
    }
    group.finish();

    let file = Path::new("graphs/fladrc/fladrc.yaml");
    let fladrc = std::fs::read_to_string(file).expect("the FLADRC graph");
    let seeds = SweepSpec { vary: Vec::new(), random: None, seeds: Some((1, 200)), draw_seed: 0, shard: None };
    let seed_cases = sweep::cases(&seeds).expect("cases");
    let model = ctlgraph::compile_file(file, &[]).expect("compiles");
    let (accelerated, _) = Runner::choose(Accelerate::Require, &model, file, &fladrc).expect("the step library builds");
    let table = |runner: &Runner| sweep::run(runner, &fladrc, file, &[], &seed_cases, 2, &keep, &stop, &|| {});
    let (by_interpreter, by_library) = (table(&Runner::Interpreted).expect("runs"), table(&accelerated).expect("runs"));
    let checks = |rows: &[sweep::Row]| rows.iter().map(|r| r.result.clone()).collect::<Vec<_>>();
    assert_eq!(
        checks(&by_interpreter),
        checks(&by_library),
        "the accelerated sweep measures what the interpreted one does"
    );
    let mut group = c.benchmark_group("fladrc_sweep_200_seeds");
    group.sample_size(10);
    for (name, runner) in [("interpreted", &Runner::Interpreted), ("accelerated", &accelerated)] {
        group.bench_function(name, |b| b.iter(|| table(runner).expect("runs").len()));
    }
    group.finish();

    let mut group = c.benchmark_group("pid_loop_400_cases_compiled");
    group.sample_size(20);
    let sets = |case: &sweep::Case| -> Vec<(String, String)> {
        names.iter().zip(&case.values).map(|(n, v)| (n.clone(), format!("{v:e}"))).collect()
    };
    let run = |model| ctlgraph::suite::run_checks(model, None).expect("runs").1.len();
    group.bench_function("each_from_its_text", |b| {
        b.iter(|| {
            let registry = ctlgraph::registry();
            let compile = |case| {
                let flat = ctlgraph_core::load_str(&text, "pid_loop.yaml".into(), &sets(case)).expect("loads");
                ctlgraph::compile_flat(&flat, &registry).expect("compiles")
            };
            cases.iter().map(|case| run(compile(case))).sum::<usize>()
        })
    });
    group.bench_function("on_the_structure", |b| {
        b.iter(|| {
            let registry = ctlgraph::registry();
            let parsed = ctlgraph_core::ParsedGraph::parse(&text, "pid_loop.yaml".into()).expect("parses");
            let base = ctlgraph::compile_flat(&parsed.flatten(&[]).expect("loads"), &registry).expect("compiles");
            let compile = |case| {
                let flat = parsed.flatten(&sets(case)).expect("loads");
                ctlgraph::recompile_flat(&base, &flat, &registry).expect("compiles")
            };
            cases.iter().map(|case| run(compile(case))).sum::<usize>()
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
