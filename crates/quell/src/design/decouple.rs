//! Falb–Wolovich decoupling by state feedback (Section III, eq. (7), Proposition 1).

use nalgebra::{Complex, DMatrix, RowDVector};

use super::DesignError;
use crate::linalg::{cond, poly_from_roots};

/// Relative tolerance for deciding c_i A^{l−1} B ≠ 0 in eq. (7), relative to ‖c_i‖‖A‖^{l−1}‖B‖.
/// Data rounded to six significant digits (relative error 5e-7 per entry) must not change σ_i,
/// so the threshold sits above that and far below any gain a decoupler could invert sensibly.
pub const RELATIVE_DEGREE_TOL: f64 = 1e-5;

/// B* is treated as singular above this condition number.
pub const MAX_COND_B_STAR: f64 = 1e12;

/// Relative degrees σ_i (eq. (7)): the least l with c_i A^{l−1} B ≠ 0, decided with
/// [`RELATIVE_DEGREE_TOL`]. `None` for an output that no input reaches (c_i A^{l−1} B ≈ 0 for all l ≤ n).
pub fn relative_degrees(A: &DMatrix<f64>, B: &DMatrix<f64>, C: &DMatrix<f64>) -> Vec<Option<usize>> {
    let n = A.nrows();
    let (nA, nB) = (A.norm(), B.norm());
    (0..C.nrows())
        .map(|i| {
            let ci = C.row(i).clone_owned();
            let mut row: RowDVector<f64> = ci.clone(); // c_i A^{l−1}
            let mut scale = ci.norm() * nB; // ‖c_i‖‖A‖^{l−1}‖B‖
            for l in 1..=n {
                if (&row * B).norm() > RELATIVE_DEGREE_TOL * scale {
                    return Some(l);
                }
                row = &row * A;
                scale *= nA;
            }
            None
        })
        .collect()
}

/// Proposition 1's result: the decoupling gains and the closed loop they give.
#[derive(Debug, Clone)]
pub struct FalbWolovich {
    pub sigma: Vec<usize>,
    pub B_star: DMatrix<f64>,
    pub C_star: DMatrix<f64>,
    /// K = (B*)⁻¹ C*.
    pub K: DMatrix<f64>,
    /// F = (B*)⁻¹ diag(q_i0).
    pub F: DMatrix<f64>,
    /// q_i0 = ∏_j (−λ_ij), the numerator of G_ii(s).
    pub q0: Vec<f64>,
    /// Condition number of B*.
    pub cond_B_star: f64,
}

/// Falb–Wolovich decoupler (Proposition 1) for per-channel poles `channel_poles[i]` (σ_i each, closed
/// under conjugation; the caller checks that). Errors when an output is unreachable, a channel has the
/// wrong number of poles, or B* is singular.
pub fn falb_wolovich(
    A: &DMatrix<f64>,
    B: &DMatrix<f64>,
    C: &DMatrix<f64>,
    channel_poles: &[Vec<Complex<f64>>],
) -> Result<FalbWolovich, DesignError> {
    let (m, n) = (C.nrows(), A.nrows());
    if channel_poles.len() != m {
        return Err(DesignError::Count {
            key: "design.channel_poles",
            per: "output",
            expected: m,
            got: channel_poles.len(),
        });
    }
    let mut sigma = Vec::with_capacity(m);
    for (channel, s) in relative_degrees(A, B, C).into_iter().enumerate() {
        let s = s.ok_or(DesignError::NoRelativeDegree { channel })?;
        let got = channel_poles[channel].len();
        if got != s {
            return Err(DesignError::ChannelPoleCount { channel, sigma: s, got });
        }
        sigma.push(s);
    }
    let mut B_star = DMatrix::zeros(m, B.ncols());
    let mut C_star = DMatrix::zeros(m, n);
    let mut q0 = Vec::with_capacity(m);
    for i in 0..m {
        // q = [q_i0, …, q_i(σ−1)] of ∏(s − λ_ij) (eq. for G_ii(s)).
        let q = poly_from_roots(&channel_poles[i]);
        let mut row: RowDVector<f64> = C.row(i).clone_owned(); // c_i A^z
        let mut c_star = RowDVector::zeros(n);
        for &qz in &q {
            c_star += qz * &row;
            row = &row * A;
        }
        // row is now c_i A^{σ_i}; B* uses c_i A^{σ_i − 1} B.
        c_star += &row;
        let prev = C.row(i) * A.pow((sigma[i] - 1) as u32);
        B_star.set_row(i, &(prev * B));
        C_star.set_row(i, &c_star);
        q0.push(q[0]);
    }
    let cond_B_star = cond(&B_star);
    let inv = match B_star.clone().try_inverse() {
        Some(inv) if cond_B_star <= MAX_COND_B_STAR => inv,
        _ => return Err(DesignError::NotDecouplable { cond: cond_B_star }),
    };
    let K = &inv * &C_star;
    let F = &inv * DMatrix::from_diagonal(&nalgebra::DVector::from_vec(q0.clone()));
    Ok(FalbWolovich { sigma, B_star, C_star, K, F, q0, cond_B_star })
}
