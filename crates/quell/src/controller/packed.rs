//! Symmetric q×q matrices (Ω_i of eq. (33)) in packed upper-triangular storage, q(q+1)/2 entries,
//! row by row: (0,0), (0,1), …, (0,q−1), (1,1), ….

/// Number of stored entries of a packed symmetric q×q matrix.
pub fn len(q: usize) -> usize {
    q * (q + 1) / 2
}

/// The H filter's rate and the adaptive law's product in one pass over packed Ω (eq. (33)):
/// d_omega = (ΔΔᵀ − Ω)/β and out = Ω x.
pub fn filter_rate_and_apply(
    delta: &[f64],
    omega: &[f64],
    inv_beta: f64,
    x: &[f64],
    d_omega: &mut [f64],
    out: &mut [f64],
) {
    let q = x.len();
    assert!(
        delta.len() == q && omega.len() == len(q) && d_omega.len() == len(q) && out.len() == q,
        "filter_rate_and_apply: dimension mismatch"
    );
    out.fill(0.0);
    let mut k = 0;
    for i in 0..q {
        // Packed row i holds Ω[i][i..q].
        let n = q - i;
        let (row, d_row) = (&omega[k..k + n], &mut d_omega[k..k + n]);
        let (dl, xl, ol) = (&delta[i..], &x[i..], &mut out[i..]);
        let (di, xi) = (dl[0], xl[0]);
        let mut acc = 0.0;
        for ((((w, dw), dj), xj), o) in row.iter().zip(d_row.iter_mut()).zip(dl).zip(xl).zip(ol.iter_mut()) {
            *dw = (di * dj - w) * inv_beta;
            acc += w * xj;
            *o += w * xi;
        }
        // The diagonal entry went into both sums.
        ol[0] += acc - row[0] * xi;
        k += n;
    }
}

/// tr Ω of a packed q×q matrix.
pub fn trace(omega: &[f64], q: usize) -> f64 {
    let (mut sum, mut k) = (0.0, 0);
    for i in 0..q {
        sum += omega[k];
        k += q - i;
    }
    sum
}

/// Calls `f(entry, Δ_i Δ_j)` for every packed entry of the rank-one matrix Δ Δᵀ.
#[inline]
pub fn outer_for_each(delta: &[f64], omega: &mut [f64], mut f: impl FnMut(&mut f64, f64)) {
    let mut rest = omega;
    for (i, &di) in delta.iter().enumerate() {
        let (row, tail) = std::mem::take(&mut rest).split_at_mut(delta.len() - i);
        rest = tail;
        for (o, dj) in row.iter_mut().zip(&delta[i..]) {
            f(o, di * dj);
        }
    }
}

/// out_ij = a·Ω_ij + b·Δ_i Δ_j for every packed entry.
#[inline]
pub fn outer_update(delta: &[f64], omega: &[f64], out: &mut [f64], a: f64, b: f64) {
    let q = delta.len();
    assert!(omega.len() == len(q) && out.len() == len(q), "outer_update: dimension mismatch");
    let mut k = 0;
    for (i, &di) in delta.iter().enumerate() {
        let bdi = b * di;
        for ((o, w), dj) in out[k..k + q - i].iter_mut().zip(&omega[k..k + q - i]).zip(&delta[i..]) {
            *o = a * w + bdi * dj;
        }
        k += q - i;
    }
}

/// Unpacks into a dense q×q matrix, row-major.
pub fn unpack(omega: &[f64], q: usize, dense: &mut [f64]) {
    let mut k = 0;
    for i in 0..q {
        for j in i..q {
            dense[i * q + j] = omega[k];
            dense[j * q + i] = omega[k];
            k += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn filter_rate_and_product_by_hand() {
        // Ω = [[2, 1, 0], [1, 3, -1], [0, -1, 4]], x = Δ = [1, 2, 3], β = 2 (by hand):
        // Ωx = [4, 4, 10]; (ΔΔᵀ − Ω)/β = [[-0.5, 0.5, 1.5], [·, 0.5, 3.5], [·, ·, 2.5]].
        let omega = [2.0, 1.0, 0.0, 3.0, -1.0, 4.0];
        let (mut rate, mut ox) = ([0.0; 6], [0.0; 3]);
        filter_rate_and_apply(&[1.0, 2.0, 3.0], &omega, 0.5, &[1.0, 2.0, 3.0], &mut rate, &mut ox);
        assert_eq!(ox, [4.0, 4.0, 10.0]);
        assert_eq!(rate, [-0.5, 0.5, 1.5, 0.5, 3.5, 2.5]);
        assert_eq!(len(3), 6);
    }
}
