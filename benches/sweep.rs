//! Sweep throughput: the tutorial PID loop over a 20 × 20 grid of kp and
//! kd (400 cases), on one and on two worker threads, side by side.
//!
//!     cargo bench --bench sweep

use criterion::{Criterion, criterion_group, criterion_main};
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
            b.iter(|| sweep::run(&text, file, &names, &cases, jobs, &keep, &stop, &|| {}).expect("runs").len())
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
