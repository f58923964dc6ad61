//! The paper's example (Section VIII), 100 s of the continuous closed loop at rtol = atol = 1e-9
//! (speed target: under 10 ms on one core), and the sampled-data loop at T_s = 1 ms.

use std::ops::ControlFlow;

use criterion::{criterion_group, criterion_main, Criterion};
use quell::scenario::{Scenario, PAPER_EXAMPLE};
use quell::sim::{Run, RunSettings};
use quell::Design;

fn paper(c: &mut Criterion) {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = Design::new(&s.plant, &s.design).unwrap();
    let settings = RunSettings::continuous(100.0, 0.1, 1e-9, 1e-9);
    let r =
        Run::new(&d, &s.reference, &s.disturbance, settings.clone()).simulate(|_| ControlFlow::Continue(())).unwrap();
    eprintln!("paper example: {:?}", r.stats);
    let mut g = c.benchmark_group("paper_example");
    g.sample_size(20);
    g.bench_function("continuous_100s_rtol1e-9", |b| {
        b.iter(|| {
            Run::new(&d, &s.reference, &s.disturbance, settings.clone())
                .simulate(|_| ControlFlow::Continue(()))
                .unwrap()
        })
    });
    let sampled = RunSettings { divergence_bound: 1e9, ..RunSettings::sampled(100.0, 0.1, 1e-3) };
    g.bench_function("sampled_100s_Ts1ms", |b| {
        b.iter(|| {
            Run::new(&d, &s.reference, &s.disturbance, sampled.clone()).simulate(|_| ControlFlow::Continue(())).unwrap()
        })
    });
    g.finish();
}

/// The cost of a solver step at a loose and a tight tolerance (the Monte Carlo study's 1e-6, the
/// examples' 1e-9): the run's time over its accepted steps, printed with the steps.
fn per_step(c: &mut Criterion) {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = Design::new(&s.plant, &s.design).unwrap();
    let mut g = c.benchmark_group("paper_per_step");
    g.sample_size(20);
    for tol in [1e-6, 1e-9] {
        let settings = RunSettings::continuous(100.0, 0.1, tol, tol);
        let run = || {
            Run::new(&d, &s.reference, &s.disturbance, settings.clone())
                .simulate(|_| ControlFlow::Continue(()))
                .unwrap()
        };
        eprintln!("paper example at rtol = atol = {tol:e}: {:?}", run().stats);
        g.bench_function(format!("continuous_100s_rtol{tol:e}"), |b| b.iter(run));
    }
    g.finish();
}

criterion_group!(benches, paper, per_step);
criterion_main!(benches);
