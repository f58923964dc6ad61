//! Benchmark of the DOP853 method-of-steps integrator on a small DDE:
//! u'(t) = −u(t − 1/3) − u(t − 1/5), history 0, u(0) = 1, on [0, 10].

use criterion::{criterion_group, criterion_main, Criterion};
use quell::sim::dde::{solve, DelaySystem, Options, Past};
use std::hint::black_box;
use std::ops::ControlFlow;

struct TwoDelays {
    delays: [f64; 2],
    buf: [f64; 1],
}

impl DelaySystem for TwoDelays {
    fn dim(&self) -> usize {
        1
    }
    fn n_delayed(&self) -> usize {
        1
    }
    fn delays(&self) -> &[f64] {
        &self.delays
    }
    fn rhs(&mut self, t: f64, _y: &[f64], past: &Past<'_>, dy: &mut [f64]) {
        past.eval_into(t - self.delays[0], 0, &mut self.buf);
        let a = self.buf[0];
        past.eval_into(t - self.delays[1], 0, &mut self.buf);
        dy[0] = -a - self.buf[0];
    }
}

fn bench(c: &mut Criterion) {
    for tol in [1e-6, 1e-10] {
        let opts = Options { rtol: tol, atol: tol, ..Options::default() };
        c.bench_function(&format!("dde_2delays_0_10_tol{tol:e}"), |b| {
            b.iter(|| {
                let mut sys = TwoDelays { delays: [1.0 / 3.0, 0.2], buf: [0.0] };
                let mut last = 0.0;
                let stats = solve(&mut sys, 0.0, &[1.0], &[0.0], 10.0, 0.1, &opts, |_, y| {
                    last = y[0];
                    ControlFlow::Continue(())
                })
                .unwrap();
                black_box((stats, last))
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
