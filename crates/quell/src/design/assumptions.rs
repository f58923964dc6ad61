//! Assumption 1: controllability of (A, B) and observability of (A, C) by numerically sound rank
//! tests.
//!
//! The rank of the controllability matrix `[B AB A²B …]` is a poor numerical test: its columns
//! grow like the powers of A and its rank decision is made on a matrix whose condition number
//! can exceed 1/eps even for perfectly controllable pairs. Instead we reduce (A, B) to the
//! controllability *staircase form* by orthogonal similarity transformations (Van Dooren 1981,
//! "The generalized eigenstructure problem in linear system theory"; SLICOT AB01OD/AB01ND), and
//! decide each block rank by an SVD against a tolerance scaled to the data.

use nalgebra::DMatrix;

use crate::plant::{check, PlantError};

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

/// Result of the staircase reduction: `At = Zᵀ A Z`, `Bt = Zᵀ B` with `Z` orthogonal.
///
/// The leading `rank × rank` part of `At` is block upper Hessenberg with diagonal block sizes
/// `blocks`, `Bt` is zero below its first `blocks[0]` rows, and the trailing `(n − rank)` rows of
/// `At` are zero in the leading `rank` columns (the uncontrollable part).
#[derive(Debug, Clone)]
pub(crate) struct Staircase {
    pub At: DMatrix<f64>,
    pub Bt: DMatrix<f64>,
    pub Z: DMatrix<f64>,
    pub blocks: Vec<usize>,
    pub rank: usize,
}

/// Default rank tolerance for the staircase: `10 · n · eps · max(‖A‖_F, ‖B‖_F)` (the same order
/// as MATLAB's `ctrbf` default `10·n·‖A‖₁·eps`), so it scales with the data.
pub(crate) fn staircase_tol(A: &DMatrix<f64>, B: &DMatrix<f64>) -> f64 {
    let n = A.nrows().max(1) as f64;
    10.0 * n * f64::EPSILON * A.norm().max(B.norm())
}

/// The left singular structure of a coupling block (k × c): its singular values (descending) and
/// a k × k orthogonal Q, kept as Householder reflections (a QR of the thin left singular vectors
/// U), whose first min(k, c) columns are U up to signs, so that Qᵀ blk = [R Σ Vᵀ; 0] with R upper
/// triangular. Applying Q costs O(k·c) per column instead of a k × k product. `None` for a block
/// that is not finite or an SVD that does not converge.
fn left_svd(blk: &DMatrix<f64>) -> Option<(nalgebra::linalg::QR<f64, nalgebra::Dyn, nalgebra::Dyn>, Vec<f64>)> {
    if blk.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let svd = blk.clone().try_svd(true, false, f64::EPSILON, 10_000)?;
    let sv: Vec<f64> = svd.singular_values.iter().copied().collect();
    Some((svd.u?.qr(), sv))
}

/// Orthogonal controllability staircase reduction of (A, B) with rank tolerance `tol`.
///
/// Each step takes the current coupling block (first `B`, then the sub-diagonal block of the
/// transformed `A`), computes its SVD, keeps the `r` singular values above `tol`, and rotates the
/// remaining state coordinates so that the block becomes `[R; 0]` with `R` of full row rank `r`.
/// It stops when `r = 0` (the rest is uncontrollable) or all `n` states are reached.
pub(crate) fn staircase(A: &DMatrix<f64>, B: &DMatrix<f64>, tol: f64) -> Staircase {
    let n = A.nrows();
    assert_eq!(A.ncols(), n, "A must be square, got {}×{}", A.nrows(), A.ncols());
    assert_eq!(B.nrows(), n, "B must have {n} rows (as A), got {}", B.nrows());
    let mut At = A.clone();
    let mut Bt = B.clone();
    let mut Z = DMatrix::<f64>::identity(n, n);
    let mut blocks = Vec::new();
    let mut offset = 0usize;
    let mut prev = 0usize;
    while offset < n {
        let nk = n - offset;
        let blk: DMatrix<f64> =
            if blocks.is_empty() { Bt.clone() } else { At.view((offset, prev), (nk, offset - prev)).into_owned() };
        if blk.ncols() == 0 {
            break;
        }
        let Some((U, sv)) = left_svd(&blk) else {
            break;
        };
        let r = sv.iter().filter(|&&s| s > tol).count();
        if r == 0 {
            break;
        }
        // Apply diag(I_offset, Q) as a similarity on A, from the left on B, accumulate in Z
        // (M Q = (Qᵀ Mᵀ)ᵀ for the columns).
        let mut rows_a = At.view((offset, 0), (nk, n)).into_owned();
        U.q_tr_mul(&mut rows_a);
        At.view_mut((offset, 0), (nk, n)).copy_from(&rows_a);
        let mut cols_a = At.view((0, offset), (n, nk)).transpose();
        U.q_tr_mul(&mut cols_a);
        At.view_mut((0, offset), (n, nk)).copy_from(&cols_a.transpose());
        let mut rows_b = Bt.view((offset, 0), (nk, Bt.ncols())).into_owned();
        U.q_tr_mul(&mut rows_b);
        Bt.view_mut((offset, 0), (nk, Bt.ncols())).copy_from(&rows_b);
        let mut cols_z = Z.view((0, offset), (n, nk)).transpose();
        U.q_tr_mul(&mut cols_z);
        Z.view_mut((0, offset), (n, nk)).copy_from(&cols_z.transpose());
        // The coupling block is now [R; 0] up to the neglected singular values: make it exact.
        if blocks.is_empty() {
            let m = Bt.ncols();
            Bt.view_mut((offset + r, 0), (nk - r, m)).fill(0.0);
        } else {
            let w = offset - prev;
            At.view_mut((offset + r, prev), (nk - r, w)).fill(0.0);
        }
        blocks.push(r);
        prev = offset;
        offset += r;
    }
    Staircase { At, Bt, Z, blocks, rank: offset }
}

/// Controllability of (A, B): the dimension of the controllable subspace, numerically.
///
/// Computed from the orthogonal staircase form (see the module docs) with tolerance
/// `tol = 10 · n · eps · max(‖A‖_F, ‖B‖_F)`; `rank` is the number of states reached by the
/// staircase, i.e. the numerical dimension of the controllable subspace. An error, not a rank,
/// when A is not square, B has not A's rows, or an entry is non-finite or beyond
/// [`MAX_ENTRY`](crate::plant::MAX_ENTRY) (where ‖·‖_F and the tolerance overflow, so that no
/// rank could be certified).
pub fn controllability(A: &DMatrix<f64>, B: &DMatrix<f64>) -> Result<RankTest, PlantError> {
    let n = A.nrows();
    check("A", A, n, n)?;
    check("B", B, n, B.ncols())?;
    Ok(rank_test(A, B))
}

/// Observability of (A, C), by duality with [`controllability`] of (Aᵀ, Cᵀ); errors as there,
/// with C required to have A's columns.
pub fn observability(A: &DMatrix<f64>, C: &DMatrix<f64>) -> Result<RankTest, PlantError> {
    let n = A.nrows();
    check("A", A, n, n)?;
    check("C", C, C.nrows(), n)?;
    Ok(rank_test(&A.transpose(), &C.transpose()))
}

/// The staircase rank test of (A, B), whose shapes and entries have been checked, on the pair
/// [`conditioned`] for it. `tol` is the tolerance of that pair.
fn rank_test(A: &DMatrix<f64>, B: &DMatrix<f64>) -> RankTest {
    let (A, B) = conditioned(A, B);
    let tol = staircase_tol(&A, &B);
    RankTest { rank: staircase(&A, &B, tol).rank, n: A.nrows(), tol }
}

/// (A, B) in the units the rank test takes: each column of B scaled by the power of two that
/// brings its norm nearest ‖A‖_F/√m ([`columns_to`]), then the states [`balanced`], then B's columns
/// again. All exact in floating point and keeping the controllable subspace's dimension, while the
/// tolerance [`staircase_tol`] takes the larger norm and the staircase's orthogonal steps mix the
/// states: inputs in units 1e4 times larger (a supply vessel's) or a C in units 1e15 had been
/// called uncontrollable or unobservable, as had any plant whose states were rescaled over 8
/// decades.
pub(crate) fn conditioned(A: &DMatrix<f64>, B: &DMatrix<f64>) -> (DMatrix<f64>, DMatrix<f64>) {
    let (B, _) = columns_to(A.norm(), B);
    let (A, B, _, _) = balanced(A, &B, &DMatrix::zeros(0, A.nrows()));
    let (B, _) = columns_to(A.norm(), &B);
    (A, B)
}

/// The factor that brings each of `norms` (B's columns' or C's rows') to a/√count, 1/√count where
/// a = 0, so that those vectors together are of A's size ‖A‖_F = a; `None` for a zero norm, or one
/// the factor would overflow.
fn to_size(a: f64, norms: impl ExactSizeIterator<Item = f64>) -> Vec<Option<f64>> {
    let target = if a > 0.0 { a } else { 1.0 } / (norms.len().max(1) as f64).sqrt();
    norms.map(|x| (x > 0.0 && (target / x).is_finite()).then(|| target / x)).collect()
}

/// `B` with each nonzero column scaled by the power of two nearest [`to_size`]'s factor, so that
/// ‖B‖_F is about a whatever the inputs' units, and the factors (B S, S).
pub(crate) fn columns_to(a: f64, B: &DMatrix<f64>) -> (DMatrix<f64>, Vec<f64>) {
    let factors: Vec<f64> = to_size(a, B.column_iter().map(|b| b.norm()))
        .into_iter()
        .map(|f| f.map_or(1.0, |f| 2f64.powi((f.log2().round() as i32).clamp(-1000, 1000))))
        .collect();
    let mut B = B.clone();
    for (mut b, f) in B.column_iter_mut().zip(&factors) {
        b *= *f;
    }
    (B, factors)
}

/// Most sweeps over the states [`balanced`] makes (LAPACK's dgebal converges in a few).
const BALANCING_SWEEPS: usize = 100;

/// A realization (D⁻¹AD, D⁻¹B, CD) balanced by the diagonal D of powers of two, and D's diagonal.
pub(crate) type Balanced = (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, Vec<f64>);

/// (D⁻¹AD, D⁻¹B, CD, D's diagonal) for the diagonal D of powers of two that balances each state's
/// off-diagonal column of A with its column of C against its off-diagonal row of A with its row of
/// B (Parlett & Reinsch 1969, as LAPACK's dgebal; B and C counted as in SLICOT's TB01ID), exact in
/// floating point. B's columns and C's rows count at the size of A (‖A‖_F/√m each), so that the
/// inputs' and outputs' units do not move D. A state that no other drives or that drives none is
/// left as it is. `C` may have no rows.
pub(crate) fn balanced(A: &DMatrix<f64>, B: &DMatrix<f64>, C: &DMatrix<f64>) -> Balanced {
    let n = A.nrows();
    let (mut A, mut B, mut C) = (A.clone(), B.clone(), C.clone());
    let mut d = vec![1.0; n];
    // The weights that bring each column of B and each row of C to A's size, as given: fixed, since
    // weights taken afresh each sweep would undo the balancing's effect on B and C, and push D to
    // its limits (the paper's plant with A[0][0] = 1e15 had its couplings scaled to 1e-171).
    let weights = |norms: Vec<Option<f64>>| -> Vec<f64> { norms.into_iter().map(|w| w.unwrap_or(0.0)).collect() };
    let wb = weights(to_size(A.norm(), B.column_iter().map(|b| b.norm())));
    let wc = weights(to_size(A.norm(), C.row_iter().map(|c| c.norm())));
    for _ in 0..BALANCING_SWEEPS {
        let mut moved = false;
        for (i, di) in d.iter_mut().enumerate() {
            let off = |v: f64, j: usize| if j == i { 0.0 } else { v * v };
            let column = A.column(i).iter().enumerate().map(|(j, &v)| off(v, j)).sum::<f64>()
                + C.column(i).iter().zip(&wc).map(|(v, w)| (v * w).powi(2)).sum::<f64>();
            let row = A.row(i).iter().enumerate().map(|(j, &v)| off(v, j)).sum::<f64>()
                + B.row(i).iter().zip(&wb).map(|(v, w)| (v * w).powi(2)).sum::<f64>();
            let (c, r) = (column.sqrt(), row.sqrt());
            if !(c > 0.0 && r > 0.0 && (c + r).is_finite()) {
                continue;
            }
            let (mut f, mut cf, mut rf) = (1.0f64, c, r);
            while cf < rf / 2.0 && f < 2f64.powi(500) {
                (f, cf, rf) = (f * 2.0, cf * 2.0, rf / 2.0);
            }
            while cf >= rf * 2.0 && f > 2f64.powi(-500) {
                (f, cf, rf) = (f / 2.0, cf / 2.0, rf * 2.0);
            }
            if cf + rf < 0.95 * (c + r) {
                moved = true;
                A.column_mut(i).scale_mut(f);
                C.column_mut(i).scale_mut(f);
                A.row_mut(i).scale_mut(1.0 / f);
                B.row_mut(i).scale_mut(1.0 / f);
                *di *= f;
            }
        }
        if !moved {
            break;
        }
    }
    (A, B, C, d)
}
