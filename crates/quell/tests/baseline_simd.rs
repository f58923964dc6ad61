//! The solver's baseline compilation (no AVX2), which machines without AVX2 and runs with
//! `QUELL_NO_AVX2` set use: on a machine with AVX2 the other test binaries exercise the AVX2 one.
//! One test, so that the variable is set before anything in this process decides.

mod common;

use std::ops::ControlFlow;

use common::*;
use quell::sim::dde::{solve, DelaySystem, Options, Past};
use quell::simd::avx2_in_use;

/// x' = −x(t − 1), x = 1 for t ≤ 0.
struct UnitDelay;

impl DelaySystem for UnitDelay {
    fn dim(&self) -> usize {
        1
    }
    fn n_delayed(&self) -> usize {
        1
    }
    fn delays(&self) -> &[f64] {
        &[1.0]
    }
    fn rhs(&mut self, t: f64, _y: &[f64], past: &Past<'_>, dy: &mut [f64]) {
        past.eval_into(t - 1.0, 0, dy);
        dy[0] = -dy[0];
    }
}

#[test]
fn baseline_compilation_meets_the_accuracy_bounds() {
    // This process runs this one test only, so no other thread reads the environment meanwhile.
    std::env::set_var("QUELL_NO_AVX2", "1");
    assert!(!avx2_in_use());

    // The method-of-steps polynomials on [0, 3], to 1e-9 (as tests/dde.rs).
    let opts = Options { rtol: 1e-10, atol: 1e-10, ..Options::default() };
    let mut worst: f64 = 0.0;
    solve(&mut UnitDelay, 0.0, &[1.0], &[1.0], 3.0, 0.01, &opts, |t, y| {
        worst = worst.max((y[0] - exact_unit(t)).abs());
        ControlFlow::Continue(())
    })
    .unwrap();
    assert!(worst < 1e-9, "closed form: max error {worst:e}");

    // The paper's example against the independent solver (1e-6) and its convergence.
    let r = run_paper(paper_spec(), 100.0, 0.1, 1e-10);
    assert_matches_reference_points(&r);
    let (e1, e2) = (r.max_abs_error(0, 90.0, 100.0).unwrap(), r.max_abs_error(1, 90.0, 100.0).unwrap());
    assert!(e1 < 0.05 && e2 < 0.005, "tail errors {e1} {e2}");
}
