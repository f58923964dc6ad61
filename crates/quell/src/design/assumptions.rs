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
    let _ = (A, B);
    todo!()
}

/// Observability of (A, C), by duality with [`controllability`] of (Aᵀ, Cᵀ).
pub fn observability(A: &DMatrix<f64>, C: &DMatrix<f64>) -> RankTest {
    controllability(&A.transpose(), &C.transpose())
}
