//! What the default budgets cost a run (docs/running.md, "Every run is bounded"): the step budget
//! `sim::default_max_steps` (the averaged law Ω̄_i of every channel and the loop's rates) against
//! 100 s of the paper's example at rtol = atol = 1e-9 given its budget, which skips it.

use std::ops::ControlFlow;

use criterion::{criterion_group, criterion_main, Criterion};
use quell::scenario::{Scenario, PAPER_EXAMPLE};
use quell::sim::{default_max_steps, Integrator, Run, RunSettings};
use quell::Design;

fn budget(c: &mut Criterion) {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = Design::new(&s.plant, &s.design).unwrap();
    let integrator = Integrator::new(1e-9, 1e-9);
    let mut g = c.benchmark_group("default_budget");
    g.sample_size(20);
    g.bench_function("default_max_steps_paper", |b| b.iter(|| default_max_steps(&Run::of(&s, &d), &integrator)));
    let mut given = RunSettings::continuous(100.0, 0.1, 1e-9, 1e-9);
    given.set_max_steps(Some(default_max_steps(&Run::of(&s, &d), &integrator))).unwrap();
    g.bench_function("run_paper_100s_budget_given", |b| {
        b.iter(|| Run::of(&s, &d).settings(given.clone()).simulate(|_| ControlFlow::Continue(())).unwrap())
    });
    g.finish();
}

criterion_group!(benches, budget);
criterion_main!(benches);
