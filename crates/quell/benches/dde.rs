//! Benchmark of the DOP853 method-of-steps integrator on a small DDE:
//! u'(t) = −u(t − 1/3) − u(t − 1/5), history 0, u(0) = 1, on [0, 10].

mod common;

use common::solve_two_delays;
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    for tol in [1e-6, 1e-10] {
        c.bench_function(&format!("dde_2delays_0_10_tol{tol:e}"), |b| b.iter(|| black_box(solve_two_delays(tol))));
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
