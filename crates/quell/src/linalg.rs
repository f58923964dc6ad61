//! Small dense linear-algebra helpers shared by the design layer.

use nalgebra::{Complex, DMatrix};

/// Coefficients `[a_0, …, a_{q−1}]` of the monic polynomial ∏(s − p_j) = s^q + a_{q−1}s^{q−1} + … + a_0.
/// The poles must be closed under conjugation (callers check); imaginary round-off is dropped.
pub fn poly_from_roots(poles: &[Complex<f64>]) -> Vec<f64> {
    // c holds the monic polynomial's coefficients, ascending, with the leading 1 last.
    let mut c = vec![Complex::new(1.0, 0.0)];
    for &p in poles {
        c.insert(0, Complex::new(0.0, 0.0));
        for i in 0..c.len() - 1 {
            let next = c[i + 1];
            c[i] -= p * next;
        }
    }
    c.pop();
    c.into_iter().map(|z| z.re).collect()
}

/// Companion matrix of the monic polynomial with ascending coefficients `a` (length q): ones on the
/// superdiagonal, last row −[a_0, …, a_{q−1}]. With input vector e_q, the transfer function to
/// the first state is 1 / (s^q + a_{q−1}s^{q−1} + … + a_0).
pub fn companion(a: &[f64]) -> DMatrix<f64> {
    let q = a.len();
    DMatrix::from_fn(q, q, |r, c| {
        if r + 1 == q {
            -a[c]
        } else if c == r + 1 {
            1.0
        } else {
            0.0
        }
    })
}

/// Block-diagonal matrix of the given blocks.
pub fn blkdiag(blocks: &[DMatrix<f64>]) -> DMatrix<f64> {
    let rows = blocks.iter().map(|b| b.nrows()).sum();
    let cols = blocks.iter().map(|b| b.ncols()).sum();
    let mut M = DMatrix::zeros(rows, cols);
    let (mut r, mut c) = (0, 0);
    for b in blocks {
        M.view_mut((r, c), (b.nrows(), b.ncols())).copy_from(b);
        r += b.nrows();
        c += b.ncols();
    }
    M
}

/// Eigenvalues of a real square matrix, sorted by real part then imaginary part; `None` when the
/// Schur iteration does not converge. nalgebra's unbounded `complex_eigenvalues` can loop forever
/// on tight clusters (repeated poles), so this bounds the iteration and retries once on M − (tr M/n)·I,
/// which moves the cluster away from the shifts that stall.
pub fn eigenvalues(M: &DMatrix<f64>) -> Option<Vec<Complex<f64>>> {
    let n = M.nrows();
    if n == 0 {
        return Some(Vec::new());
    }
    if !M.iter().all(|v| v.is_finite()) {
        return None;
    }
    let mean = M.trace() / n as f64;
    for shift in [0.0, mean] {
        let S = M - DMatrix::identity(n, n) * shift;
        if let Some(schur) = S.try_schur(f64::EPSILON, 1000 * n) {
            let mut ev: Vec<Complex<f64>> = schur.complex_eigenvalues().iter().map(|z| z + shift).collect();
            ev.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
            return Some(ev);
        }
    }
    None
}

/// Condition number σ_max/σ_min in the 2-norm (∞ for a singular or empty matrix).
pub fn cond(M: &DMatrix<f64>) -> f64 {
    let s = M.singular_values();
    let (max, min) = (s.max(), s.min());
    if min > 0.0 && !s.is_empty() {
        max / min
    } else {
        f64::INFINITY
    }
}

/// Numerical rank: the number of singular values above `max(rows, cols)·eps·σ_max`.
pub fn numerical_rank(M: &DMatrix<f64>) -> usize {
    if M.is_empty() {
        return 0;
    }
    let s = M.singular_values();
    let tol = M.nrows().max(M.ncols()) as f64 * f64::EPSILON * s.max();
    s.iter().filter(|&&v| v > tol).count()
}

/// True when every eigenvalue has real part below −`margin`.
pub fn hurwitz(eigs: &[Complex<f64>], margin: f64) -> bool {
    eigs.iter().all(|e| e.re < -margin)
}

/// A number for a message: six decimals in the usual range, scientific notation for very large or
/// very small magnitudes (so that 1e300 does not print as 301 digits).
pub fn fmt_number(x: f64) -> String {
    let a = x.abs();
    if a != 0.0 && a.is_finite() && !(1e-4..1e6).contains(&a) {
        format!("{x:.6e}")
    } else {
        format!("{x:.6}")
    }
}

/// A complex number for a message, `re` or `re±im·i`, each part as in [`fmt_number`].
pub fn fmt_complex(z: &Complex<f64>) -> String {
    if z.im == 0.0 {
        fmt_number(z.re)
    } else {
        let im = fmt_number(z.im.abs());
        format!("{}{}{im}i", fmt_number(z.re), if z.im < 0.0 { '-' } else { '+' })
    }
}

/// Exact zero-order-hold discretization of x' = A x + B v over a sample time T:
/// x_{k+1} = Φ x_k + Γ v_k with Φ = e^{AT}, Γ = ∫_0^T e^{As} ds B, both read off
/// exp([[A, B], [0, 0]]·T) (Van Loan's block method).
pub fn zoh(A: &DMatrix<f64>, B: &DMatrix<f64>, T: f64) -> (DMatrix<f64>, DMatrix<f64>) {
    let (n, m) = (A.nrows(), B.ncols());
    let mut M = DMatrix::zeros(n + m, n + m);
    M.view_mut((0, 0), (n, n)).copy_from(&(A * T));
    M.view_mut((0, n), (n, m)).copy_from(&(B * T));
    let E = M.exp();
    (E.view((0, 0), (n, n)).into_owned(), E.view((0, n), (n, m)).into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poly_of_paper_filter_poles() {
        // (s + 1)(s + 6) = s² + 7s + 6: the paper's G_g1 = [[0, 1], [−6, −7]] (Section VIII).
        let a = poly_from_roots(&[Complex::new(-1.0, 0.0), Complex::new(-6.0, 0.0)]);
        assert_eq!(a, vec![6.0, 7.0]);
        assert_eq!(companion(&a), DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -6.0, -7.0]));
        // (s + 1)(s + 2)(s + 3) = s³ + 6s² + 11s + 6: the paper's third G_ω block.
        let a = poly_from_roots(&[-1.0, -2.0, -3.0].map(|r| Complex::new(r, 0.0)));
        assert_eq!(a, vec![6.0, 11.0, 6.0]);
        // (s − (−1 + 2i))(s − (−1 − 2i)) = s² + 2s + 5.
        let a = poly_from_roots(&[Complex::new(-1.0, 2.0), Complex::new(-1.0, -2.0)]);
        assert_eq!(a, vec![5.0, 2.0]);
    }

    #[test]
    fn zoh_of_first_order_lag() {
        // x' = −x/β + v/β held over T: Φ = e^{−T/β}, Γ = 1 − e^{−T/β} (closed form).
        let (beta, T) = (0.7, 0.05);
        let (P, G) = zoh(&DMatrix::from_element(1, 1, -1.0 / beta), &DMatrix::from_element(1, 1, 1.0 / beta), T);
        assert!((P[(0, 0)] - (-T / beta).exp()).abs() < 1e-15);
        assert!((G[(0, 0)] - (1.0 - (-T / beta).exp())).abs() < 1e-15);
        // Double integrator: Φ = [[1, T], [0, 1]], Γ = [T²/2, T] (closed form).
        let (P, G) =
            zoh(&DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]), &DMatrix::from_row_slice(2, 1, &[0.0, 1.0]), T);
        assert!((&P - DMatrix::from_row_slice(2, 2, &[1.0, T, 0.0, 1.0])).norm() < 1e-15);
        assert!((&G - DMatrix::from_row_slice(2, 1, &[T * T / 2.0, T])).norm() < 1e-15);
    }
}
