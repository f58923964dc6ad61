//! `Controller::step` for the paper's example (n = 3, m = 2, q = 8; issue 4's target: under 300 ns)
//! and its scaling in m ∈ {2, 4, 8} and q ∈ {8, 16, 32}.
#![allow(non_snake_case)]

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use quell::nalgebra::{Complex, DMatrix};
use quell::scenario::{Scenario, PAPER_EXAMPLE};
use quell::{Controller, Design, DesignSpec, ObserverChoice, Plant};

/// A decouplable m-channel plant (n = m, B = C = I, σ_i = 1) with q_g = q (q/m filter poles per
/// reference component) and no disturbance, for scaling runs.
fn synthetic(m: usize, q: usize) -> Design {
    let A = DMatrix::from_fn(m, m, |i, j| if i == j { 0.5 } else { 0.1 * ((i * 7 + j * 3) % 5) as f64 - 0.2 });
    let plant = Plant::new(
        A,
        DMatrix::identity(m, m),
        DMatrix::identity(m, m),
        DMatrix::zeros(m, 0),
        DMatrix::zeros(m, 0),
        vec![0.01; m],
        None,
    )
    .unwrap();
    let per = q / m;
    let spec = DesignSpec {
        observer: ObserverChoice::Poles((0..m).map(|i| Complex::new(-2.0 - i as f64, 0.0)).collect()),
        channel_poles: (0..m).map(|i| vec![Complex::new(-3.0 - 0.1 * i as f64, 0.0)]).collect(),
        reference_filter_poles: (0..m)
            .map(|_| (0..per).map(|j| Complex::new(-1.0 - j as f64, 0.0)).collect())
            .collect(),
        disturbance_filter_poles: vec![],
        mu: vec![10.0; m],
        beta: 1.0,
        relative_degrees: None,
    };
    Design::new(&plant, &spec).unwrap()
}

fn step(c: &mut Criterion) {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = Design::new(&s.plant, &s.design).unwrap();
    let mut ctrl = Controller::new(&d, 1e-3).unwrap();
    let (y, g) = ([0.3, -0.2], [1.0, 2.0]);
    c.bench_function("step/paper_n3_m2_q8", |b| b.iter(|| ctrl.step(black_box(&y), black_box(&g))[0]));

    let mut group = c.benchmark_group("step_scaling");
    for m in [2, 4, 8] {
        for q in [8, 16, 32] {
            let d = synthetic(m, q);
            let mut ctrl = Controller::new(&d, 1e-3).unwrap();
            let (y, g) = (vec![0.1; m], vec![1.0; m]);
            group.bench_with_input(BenchmarkId::new(format!("m{m}"), q), &q, |b, _| {
                b.iter(|| ctrl.step(black_box(&y), black_box(&g))[0])
            });
        }
    }
    group.finish();
}

criterion_group!(benches, step);
criterion_main!(benches);
