//! Tests of the controllability / observability rank tests (staircase form).
#![allow(non_snake_case)]

use quell::design::assumptions::{controllability, observability};
use quell::nalgebra::{DMatrix, DVector};

fn diag(d: &[f64]) -> DMatrix<f64> {
    DMatrix::from_diagonal(&DVector::from_row_slice(d))
}

/// A fixed orthogonal matrix (Q of a QR of a deterministic full-rank matrix) to hide structure.
fn orthogonal(n: usize) -> DMatrix<f64> {
    let M = DMatrix::from_fn(n, n, |i, j| ((i * n + j) as f64 * 0.7 + 0.3).sin() + if i == j { 2.0 } else { 0.0 });
    M.qr().q()
}

#[test]
fn double_integrator_is_controllable_and_observable() {
    let A = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
    let B = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    let C = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
    let c = controllability(&A, &B).unwrap();
    assert_eq!((c.rank, c.n), (2, 2));
    assert!(c.full());
    assert!(observability(&A, &C).unwrap().full());
    // Measuring velocity only: position is unobservable (rank 1).
    let C_vel = DMatrix::from_row_slice(1, 2, &[0.0, 1.0]);
    assert_eq!(observability(&A, &C_vel).unwrap().rank, 1);
}

/// A = diag(1, 2), B = [1; 0]: the second mode is untouched by the input (rank 1); dually
/// C = [1, 0] does not see it.
#[test]
fn decoupled_mode_is_uncontrollable_and_unobservable() {
    let A = diag(&[1.0, 2.0]);
    let B = DMatrix::from_row_slice(2, 1, &[1.0, 0.0]);
    let c = controllability(&A, &B).unwrap();
    assert_eq!((c.rank, c.n), (1, 2));
    assert!(!c.full());
    let C = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
    assert_eq!(observability(&A, &C).unwrap().rank, 1);
}

/// Repeated eigenvalue with a single input: diag(3, 3) is never controllable from one input
/// (rank 1), but is from two independent inputs.
#[test]
fn repeated_eigenvalue_needs_two_inputs() {
    let A = diag(&[3.0, 3.0]);
    assert_eq!(controllability(&A, &DMatrix::from_row_slice(2, 1, &[1.0, 1.0])).unwrap().rank, 1);
    assert_eq!(controllability(&A, &DMatrix::identity(2, 2)).unwrap().rank, 2);
}

/// MIMO with hidden uncontrollable part: (A, B) = T (blockdiag(Ac, Au), [Bc; 0]) Tᵀ with T
/// orthogonal, Ac 4×4 controllable from 2 inputs, Au 2×2. Expected rank 4 of 6.
#[test]
fn hidden_uncontrollable_part_mimo() {
    let n = 6;
    let mut A = DMatrix::<f64>::zeros(n, n);
    let Ac = DMatrix::from_row_slice(4, 4, &[0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., -1., -2., -3., -4.]);
    A.view_mut((0, 0), (4, 4)).copy_from(&Ac);
    A.view_mut((4, 4), (2, 2)).copy_from(&DMatrix::from_row_slice(2, 2, &[-1.0, 5.0, -5.0, -1.0]));
    A[(0, 5)] = 0.7; // coupling from the uncontrollable to the controllable part is allowed
    let mut B = DMatrix::<f64>::zeros(n, 2);
    B[(3, 0)] = 1.0;
    B[(1, 1)] = 1.0;
    let T = orthogonal(n);
    let At = &T * &A * T.transpose();
    let Bt = &T * &B;
    assert_eq!(controllability(&At, &Bt).unwrap().rank, 4);
    // Dually: the observability of (Aᵀ, Bᵀ) has the same rank.
    assert_eq!(observability(&At.transpose(), &Bt.transpose()).unwrap().rank, 4);
}

/// The tolerance scales with the data: a coupling of relative size 1e-20 (far below eps) is
/// declared uncontrollable and one of relative size 1e-6 controllable — identically for the
/// system scaled by 1e-6, 1 and 1e6. An absolute tolerance could not do both.
#[test]
fn tolerance_is_scaled_to_the_data() {
    for scale in [1e-6, 1.0, 1e6] {
        for (delta, want) in [(1e-20, 1), (1e-6, 2)] {
            let A = diag(&[1.0, 2.0]) * scale;
            let B = DMatrix::from_row_slice(2, 1, &[1.0, delta]) * scale;
            let t = controllability(&A, &B).unwrap();
            assert_eq!(t.rank, want, "scale {scale}, δ {delta}: {t:?}");
            assert!(t.tol > 0.0 && (t.tol / scale) < 1e-12, "tolerance {} not relative", t.tol);
        }
    }
}

/// Units of the inputs (B) and of the outputs (C) do not move a verdict: the same couplings of
/// relative size 1e-20 and 1e-6 as above with B alone scaled by 1e-15 … 1e15, and the paper's
/// plant with C in units 1e15 and 1e-15 times its own (observable; the tolerance had taken ‖C‖
/// and called it unobservable), while its second mode stays unseen by a C that misses it.
#[test]
fn input_and_output_units_do_not_move_the_verdict() {
    for scale in [1e-15, 1e-3, 1.0, 1e3, 1e15] {
        for (delta, want) in [(1e-20, 1), (1e-6, 2)] {
            let B = DMatrix::from_row_slice(2, 1, &[1.0, delta]) * scale;
            let t = controllability(&diag(&[1.0, 2.0]), &B).unwrap();
            assert_eq!(t.rank, want, "B × {scale}, δ {delta}: {t:?}");
        }
        let A = DMatrix::from_row_slice(3, 3, &[-3.2, -1.7, -3.0, 2.8, 1.3, 4.0, 0.3, 0.3, -0.5]);
        let C = DMatrix::from_row_slice(2, 3, &[2.0, 2.0, 0.0, 2.0, 1.0, 2.0]) * scale;
        assert!(observability(&A, &C).unwrap().full(), "C × {scale}");
        let blind = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]) * scale;
        assert_eq!(observability(&diag(&[1.0, 2.0]), &blind).unwrap().rank, 1, "C × {scale}");
    }
}

/// Nor do the units of the states: the paper's plant with x → T x for T = diag(10^−e, 1, 10^e),
/// e up to 12 (A → T A T⁻¹, B → T B, C → C T⁻¹), stays controllable and observable (over 8
/// decades it had been called neither), and the hidden part of the MIMO plant above stays hidden
/// under T = diag(10^−6 … 10^6).
#[test]
fn state_units_do_not_move_the_verdict() {
    let A = DMatrix::from_row_slice(3, 3, &[-3.2, -1.7, -3.0, 2.8, 1.3, 4.0, 0.3, 0.3, -0.5]);
    let B = DMatrix::from_row_slice(3, 2, &[-2.0, 1.0, 2.0, -1.0, 1.0, 0.0]);
    let C = DMatrix::from_row_slice(2, 3, &[2.0, 2.0, 0.0, 2.0, 1.0, 2.0]);
    for e in [3, 6, 9, 12] {
        let t = 10f64.powi(e);
        for d in [[1.0 / t, 1.0, t], [t, 1.0 / t, 1.0]] {
            let (T, Ti) = (diag(&d), diag(&d.map(|x| 1.0 / x)));
            assert!(controllability(&(&T * &A * &Ti), &(&T * &B)).unwrap().full(), "T = {d:?}");
            assert!(observability(&(&T * &A * &Ti), &(&C * &Ti)).unwrap().full(), "T = {d:?}");
        }
    }
    let n = 6;
    let mut A = DMatrix::<f64>::zeros(n, n);
    let Ac = DMatrix::from_row_slice(4, 4, &[0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., -1., -2., -3., -4.]);
    A.view_mut((0, 0), (4, 4)).copy_from(&Ac);
    A.view_mut((4, 4), (2, 2)).copy_from(&DMatrix::from_row_slice(2, 2, &[-1.0, 5.0, -5.0, -1.0]));
    A[(0, 5)] = 0.7;
    let mut B = DMatrix::<f64>::zeros(n, 2);
    (B[(3, 0)], B[(1, 1)]) = (1.0, 1.0);
    let d = [1e-6, 1e-3, 1.0, 1e3, 1e6, 1e-4];
    let (T, Ti) = (diag(&d), diag(&d.map(|x| 1.0 / x)));
    assert_eq!(controllability(&(&T * &A * &Ti), &(&T * &B)).unwrap().rank, 4);
}

/// Rank of the controllability matrix [B AB … A^{n−1}B] by SVD with the same kind of relative
/// tolerance — the naive test the staircase replaces.
fn naive_rank(A: &DMatrix<f64>, B: &DMatrix<f64>) -> usize {
    let n = A.nrows();
    let m = B.ncols();
    let mut Ctrb = DMatrix::<f64>::zeros(n, n * m);
    let mut blk = B.clone();
    for k in 0..n {
        Ctrb.view_mut((0, k * m), (n, m)).copy_from(&blk);
        blk = A * blk;
    }
    let sv = Ctrb.singular_values();
    let tol = n as f64 * f64::EPSILON * sv[0];
    sv.iter().filter(|&&s| s > tol).count()
}

/// n = 10, A = diag(1, 2, 4, …, 512), b = ones, hidden by an orthogonal similarity. The pair is
/// controllable (distinct eigenvalues, every mode driven: PBH), robustly so — the distance to
/// uncontrollability is of order the smallest eigenvalue gap. The controllability matrix has
/// columns growing like 512^k, σ_max/σ_min ≫ 1/eps, and its numerical rank comes out < 10;
/// the staircase keeps every decision at the scale of ‖A‖ and finds 10.
#[test]
fn staircase_succeeds_where_controllability_matrix_fails() {
    let n = 10;
    let d: Vec<f64> = (0..n).map(|k| 2f64.powi(k as i32)).collect();
    let T = orthogonal(n);
    let A = &T * diag(&d) * T.transpose();
    let B = &T * DMatrix::<f64>::from_element(n, 1, 1.0);
    assert!(naive_rank(&A, &B) < n, "naive rank {}", naive_rank(&A, &B));
    let t = controllability(&A, &B).unwrap();
    assert_eq!(t.rank, n, "{t:?}");
    // Removing one mode's input makes it (exactly) uncontrollable; the staircase sees rank 9.
    let mut b = DMatrix::<f64>::from_element(n, 1, 1.0);
    b[3] = 0.0;
    assert_eq!(controllability(&A, &(&T * b)).unwrap().rank, n - 1);
}

#[test]
fn degenerate_inputs() {
    // Zero B: nothing is controllable; zero A with full B: everything is.
    assert_eq!(controllability(&diag(&[1.0, 2.0, 3.0]), &DMatrix::zeros(3, 2)).unwrap().rank, 0);
    assert_eq!(controllability(&DMatrix::zeros(3, 3), &DMatrix::identity(3, 3)).unwrap().rank, 3);
    // No inputs at all, and the empty system.
    assert_eq!(controllability(&diag(&[1.0]), &DMatrix::zeros(1, 0)).unwrap().rank, 0);
    let t = controllability(&DMatrix::zeros(0, 0), &DMatrix::zeros(0, 1)).unwrap();
    assert!(t.full() && t.n == 0);
}
