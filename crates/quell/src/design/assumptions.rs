//! Assumption 1: controllability of (A, B) and observability of (A, C) by numerically sound rank tests.
//! STUB: owned by the pole-placement helper.

use nalgebra::DMatrix;

/// Outcome of a rank test: the numerical rank found and the tolerance used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RankTest {
    pub rank: usize,
    pub n: usize,
    pub tol: f64,
}

impl RankTest {
    /// Full rank (rank = n).
    pub fn full(&self) -> bool {
        self.rank == self.n
    }
}

/// Controllability of (A, B): the dimension of the controllable subspace, numerically.
pub fn controllability(A: &DMatrix<f64>, B: &DMatrix<f64>) -> RankTest {
    let n = A.nrows();
    let mut M = DMatrix::zeros(n, n * B.ncols());
    let mut P = B.clone();
    for i in 0..n { M.view_mut((0, i * B.ncols()), (n, B.ncols())).copy_from(&P); P = A * P; }
    RankTest { rank: crate::linalg::numerical_rank(&M), n, tol: 0.0 }
}

/// Observability of (A, C), by duality with [`controllability`] of (Aᵀ, Cᵀ).
pub fn observability(A: &DMatrix<f64>, C: &DMatrix<f64>) -> RankTest {
    controllability(&A.transpose(), &C.transpose())
}
