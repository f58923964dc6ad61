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
    // Small sizes get a copy with q a constant: unrolled, with Ω x accumulated in registers.
    macro_rules! specialized {
        ($($n:literal)*) => {
            match q {
                $($n => filter_rate_and_apply_fixed::<$n>(
                    delta.try_into().expect("checked"), omega, inv_beta, x.try_into().expect("checked"),
                    d_omega, out.try_into().expect("checked"),
                ),)*
                _ => filter_rate_and_apply_rows(delta, omega, inv_beta, x, d_omega, out),
            }
        };
    }
    specialized!(1 2 3 4 5 6 7 8 9 10 11 12)
}

/// [`filter_rate_and_apply`] for a fixed q.
#[inline(always)]
fn filter_rate_and_apply_fixed<const Q: usize>(
    delta: &[f64; Q],
    omega: &[f64],
    inv_beta: f64,
    x: &[f64; Q],
    d_omega: &mut [f64],
    out: &mut [f64; Q],
) {
    let (omega, d_omega) = (&omega[..Q * (Q + 1) / 2], &mut d_omega[..Q * (Q + 1) / 2]);
    let mut k = 0;
    for i in 0..Q {
        for j in i..Q {
            d_omega[k + j - i] = (delta[i] * delta[j] - omega[k + j - i]) * inv_beta;
        }
        k += Q - i;
    }
    // (Ω x)_i = Σ_j Ω_ij x_j over full rows, each in its own accumulator.
    let at = const { full_index::<Q>() };
    for (o, row) in out.iter_mut().zip(&at) {
        *o = row.iter().zip(x).map(|(&p, xj)| omega[p] * xj).sum();
    }
}

/// at[i][j] = the packed index of Ω_ij (= Ω_ji).
const fn full_index<const Q: usize>() -> [[usize; Q]; Q] {
    let mut at = [[0; Q]; Q];
    let mut i = 0;
    while i < Q {
        let mut j = 0;
        while j < Q {
            let (r, c) = if i <= j { (i, j) } else { (j, i) };
            // Rows 0..r hold Q + (Q − 1) + … + (Q − r + 1) entries.
            at[i][j] = r * Q - r * (r.saturating_sub(1)) / 2 + (c - r);
            j += 1;
        }
        i += 1;
    }
    at
}

/// [`filter_rate_and_apply`] for any q, row by row over the packed triangle.
fn filter_rate_and_apply_rows(
    delta: &[f64],
    omega: &[f64],
    inv_beta: f64,
    x: &[f64],
    d_omega: &mut [f64],
    out: &mut [f64],
) {
    let q = x.len();
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
    use proptest::prelude::*;

    proptest! {
        /// Both the size-specialized (q ≤ 12) and the row-wise (q > 12) paths against the dense
        /// definition: (ΔΔᵀ − Ω)/β entrywise and Ω x, to 1e-14 relative to Σ|Ω_ij x_j| (a few ulps of
        /// a sum of q terms, accumulated in different orders).
        #[test]
        fn filter_rate_and_apply_matches_dense(q in 1usize..=16, seed in any::<u64>(), inv_beta in 0.1f64..10.0) {
            let mut state = seed | 1;
            let mut next = move || {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
            };
            let delta: Vec<f64> = (0..q).map(|_| next()).collect();
            let x: Vec<f64> = (0..q).map(|_| next()).collect();
            let omega: Vec<f64> = (0..len(q)).map(|_| next()).collect();
            let (mut rate, mut ox) = (vec![0.0; len(q)], vec![0.0; q]);
            filter_rate_and_apply(&delta, &omega, inv_beta, &x, &mut rate, &mut ox);
            let mut dense = vec![0.0; q * q];
            unpack(&omega, q, &mut dense);
            let mut k = 0;
            for i in 0..q {
                let (mut want, mut scale) = (0.0, 0.0);
                for j in 0..q {
                    want += dense[i * q + j] * x[j];
                    scale += (dense[i * q + j] * x[j]).abs();
                }
                prop_assert!((ox[i] - want).abs() <= 1e-14 * scale.max(1e-300), "q {q}: (Ωx)_{i} {} vs {want}", ox[i]);
                for j in i..q {
                    let want = (delta[i] * delta[j] - dense[i * q + j]) * inv_beta;
                    prop_assert!((rate[k] - want).abs() <= 1e-15 * want.abs().max(1.0), "q {q}: rate ({i},{j})");
                    k += 1;
                }
            }
        }
    }

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
