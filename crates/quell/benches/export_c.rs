//! The generated C controller's step (`quell export`, gcc -O2), called in-process, next to
//! `Controller::step` on the same design and inputs: the paper's example (n = 3, m = 2, q = 8) at
//! T_s = 1 ms. gcc is required.
#![allow(non_snake_case)]

#[path = "../tests/c_harness/mod.rs"]
mod c_harness;

use std::hint::black_box;

use c_harness::CController;
use criterion::{criterion_group, criterion_main, Criterion};
use quell::export::{generate, ExportOptions, Precision};
use quell::scenario::{Scenario, PAPER_EXAMPLE};
use quell::Controller;

type Step<R> = unsafe extern "C" fn(*mut u64, *const R, *const R, *mut R);

fn step(c: &mut Criterion) {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = s.design().unwrap();
    let mut rust = Controller::new(&d, 1e-3).unwrap();
    let (y, g) = ([0.3, -0.2], [1.0, 2.0]);
    c.bench_function("export_c/rust_step_paper", |b| b.iter(|| rust.step(black_box(&y), black_box(&g)).unwrap()[0]));

    let options = |precision| ExportOptions { precision, ..ExportOptions::default() };
    let code = generate(&d, 1e-3, &options(Precision::F64)).unwrap();
    let mut ctrl = CController::build(&code, "quell", Precision::F64, (2, 8, 3), "-O2");
    // SAFETY: `quell_step` of an f64 export has this signature; the buffers hold M = 2 numbers.
    let step64: Step<f64> = unsafe { ctrl.function("quell_step") };
    let state = ctrl.state_ptr();
    let mut u_f = [0.0f64; 2];
    c.bench_function("export_c/c_step_paper_f64_O2", |b| {
        b.iter(|| {
            unsafe { step64(state, black_box(&y).as_ptr(), black_box(&g).as_ptr(), u_f.as_mut_ptr()) };
            u_f[0]
        })
    });

    let code = generate(&d, 1e-3, &options(Precision::F32)).unwrap();
    let mut ctrl = CController::build(&code, "quell", Precision::F32, (2, 8, 3), "-O2");
    // SAFETY: as above, in float.
    let step32: Step<f32> = unsafe { ctrl.function("quell_step") };
    let state = ctrl.state_ptr();
    let (y, g, mut u_f) = ([0.3f32, -0.2], [1.0f32, 2.0], [0.0f32; 2]);
    c.bench_function("export_c/c_step_paper_f32_O2", |b| {
        b.iter(|| {
            unsafe { step32(state, black_box(&y).as_ptr(), black_box(&g).as_ptr(), u_f.as_mut_ptr()) };
            u_f[0]
        })
    });
}

criterion_group!(benches, step);
criterion_main!(benches);
