//! Internal-model filters (Sections IV–V, eqs. (10), (15)): companion pairs (G, l) from chosen
//! Hurwitz poles, stacked block-diagonally into (G_g, L_g) and (G_ω, L_ω).

use nalgebra::{Complex, DMatrix};

use crate::linalg::{blkdiag, companion, poly_from_roots};

/// (G, l) for poles p_1..p_q: G is the companion matrix of ∏(s − p_j) (ones on the superdiagonal,
/// last row −[a_0, …, a_{q−1}]) and l = e_q, the form of G_g and G_ω printed in Section VIII.
pub fn filter_pair(poles: &[Complex<f64>]) -> (DMatrix<f64>, DMatrix<f64>) {
    let q = poles.len();
    let G = companion(&poly_from_roots(poles));
    let mut l = DMatrix::zeros(q, 1);
    if q > 0 {
        l[(q - 1, 0)] = 1.0;
    }
    (G, l)
}

/// Block-diagonal (G, L) = (blkdiag G_i, blkdiag l_i) for one pole list per signal component
/// (eqs. (11), (16)): G is Σq_i × Σq_i, L is Σq_i × (number of components).
pub fn internal_model(poles: &[Vec<Complex<f64>>]) -> (DMatrix<f64>, DMatrix<f64>) {
    let (Gs, ls): (Vec<_>, Vec<_>) = poles.iter().map(|p| filter_pair(p)).unzip();
    (blkdiag(&Gs), blkdiag(&ls))
}
