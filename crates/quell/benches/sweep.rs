//! The studies' speed target: 10,000 runs of the paper's example (t_end = 100 s,
//! rtol = atol = 1e-6, Monte Carlo on truth.A at 5 %) in at most 30 s on 2 cores. Criterion times
//! the first 200 runs of that study (the same draws as examples/studies/monte-carlo-A.toml) on 1
//! and on 2 worker threads; the per-run figure times 10,000 is the whole study's time. The
//! throughput line ("elem/s") is runs per second: docs/performance.md sets it against an
//! independent SciPy implementation of the loop (scripts/scipy_loop.py).

use criterion::{criterion_group, criterion_main, Criterion};
use quell::study::{sweep, Study, SweepOptions};

const STUDY: &str = "[simulation]\nt_end = 100.0\nrtol = 1e-6\natol = 1e-6\n[monte_carlo]\nruns = 200\nseed = 1\n\"truth.A\" = { relative = 0.05 }\n";

fn monte_carlo(c: &mut Criterion) {
    let study = Study::from_toml(STUDY, None).unwrap();
    let mut g = c.benchmark_group("sweep_mc_truth_A_5pc_200_runs");
    g.sample_size(10);
    g.throughput(criterion::Throughput::Elements(200));
    for jobs in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(jobs).build().unwrap();
        g.bench_function(format!("jobs_{jobs}"), |b| {
            b.iter(|| pool.install(|| sweep(&study, &SweepOptions::default())).rows.len())
        });
    }
    g.finish();
}

criterion_group!(benches, monte_carlo);
criterion_main!(benches);
