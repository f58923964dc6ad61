//! `Controller::step` for the paper's example (n = 3, m = 2, q = 8; target: under 300 ns a step),
//! on the inputs of its own sampled run, and its scaling in m ∈ {2, 4, 8} and q ∈ {8, 16, 32} on
//! constant inputs (which make the adaptive step implicit: the factorization's q³ shows).
#![allow(non_snake_case)]

mod common;

use common::synthetic;
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use quell::scenario::{Scenario, PAPER_EXAMPLE};
use quell::sim::{Run, RunSettings};
use quell::{Controller, Design};

/// One step; constant y and g are no plant's answer, and the controller adapting to them at its
/// full rate grows until its state is not finite (after some 10⁵ steps): then it restarts.
fn stepped(ctrl: &mut Controller, y: &[f64], g: &[f64]) -> f64 {
    match ctrl.step(y, g) {
        Ok(u) => u[0],
        Err(_) => {
            ctrl.reset();
            0.0
        }
    }
}

fn step(c: &mut Criterion) {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = Design::new(&s.plant, &s.design).unwrap();
    let mut ctrl = Controller::new(&d, 1e-3).unwrap();
    // The y and g of the paper's sampled loop at T_s = 1 ms over its first 20 s, replayed in a
    // cycle from a reset controller: the arithmetic of a real run (its adaptive step stays below
    // c·tr Ω = 0.05, the O(q²) one), where constant inputs drive Ω and the step elsewhere.
    let run = Run::new(&d, &s.reference, &s.disturbance, RunSettings::sampled(20.0, 1e-3, 1e-3))
        .simulate(|_| std::ops::ControlFlow::Continue(()))
        .unwrap();
    let inputs: Vec<(Vec<f64>, Vec<f64>)> =
        (0..run.len()).map(|k| (run.y[2 * k..2 * k + 2].to_vec(), run.g[2 * k..2 * k + 2].to_vec())).collect();
    let mut k = 0;
    c.bench_function("step/paper_n3_m2_q8", |b| {
        b.iter(|| {
            if k == inputs.len() {
                (k, _) = (0, ctrl.reset());
            }
            k += 1;
            stepped(&mut ctrl, black_box(&inputs[k - 1].0), black_box(&inputs[k - 1].1))
        })
    });

    let mut group = c.benchmark_group("step_scaling");
    for m in [2, 4, 8] {
        for q in [8, 16, 32] {
            let d = synthetic(m, q);
            let mut ctrl = Controller::new(&d, 1e-3).unwrap();
            let (y, g) = (vec![0.1; m], vec![1.0; m]);
            group.bench_with_input(BenchmarkId::new(format!("m{m}"), q), &q, |b, _| {
                b.iter(|| stepped(&mut ctrl, black_box(&y), black_box(&g)))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, step);
criterion_main!(benches);
