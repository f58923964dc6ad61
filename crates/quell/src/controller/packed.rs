//! Symmetric q×q matrices (Ω_i of eq. (33)) in packed upper-triangular storage, q(q+1)/2 entries,
//! row by row: (0,0), (0,1), …, (0,q−1), (1,1), …. The continuous loop integrates Ω_i as part of its
//! state, where this halves those states; the real-time controller keeps a full, exactly symmetric Ω_i
//! (see `adapt` in `controller/discrete.rs`).

/// Number of stored entries of a packed symmetric q×q matrix.
#[inline(always)]
pub(crate) const fn len(q: usize) -> usize {
    q * (q + 1) / 2
}

/// Calls `$fixed::<Q>$args` for q = 1…12 (unrolled, every (Ω x)_i in its own register) and
/// `$rows$args` otherwise.
macro_rules! by_size {
    ($q:expr, $fixed:ident, $rows:ident, $args:tt) => {
        by_size!(@ $q, $fixed, $rows, $args, 1 2 3 4 5 6 7 8 9 10 11 12)
    };
    (@ $q:expr, $fixed:ident, $rows:ident, $args:tt, $($n:literal)*) => {
        match $q {
            $($n => $fixed::<$n> $args,)*
            _ => $rows $args,
        }
    };
}

/// The continuous H filter's rate and the adaptive law's product (eq. (33)) over packed Ω:
/// d_omega = (ΔΔᵀ − Ω)/β and out = Ω x.
pub(crate) fn filter_rate_and_apply(
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
    #[inline(always)]
    fn rate(q: usize, delta: &[f64], omega: &[f64], inv_beta: f64, d_omega: &mut [f64]) {
        // Slices of the known length, so that a constant q leaves no bounds checks.
        let (delta, omega, d_omega) = (&delta[..q], &omega[..len(q)], &mut d_omega[..len(q)]);
        let mut k = 0;
        for i in 0..q {
            for j in i..q {
                d_omega[k + j - i] = (delta[i] * delta[j] - omega[k + j - i]) * inv_beta;
            }
            k += q - i;
        }
    }
    #[inline(always)]
    fn fixed<const Q: usize>(delta: &[f64], omega: &[f64], inv_beta: f64, x: &[f64], d: &mut [f64], out: &mut [f64]) {
        rate(Q, delta, omega, inv_beta, d);
        apply_fixed::<Q>(omega, x, out);
    }
    fn rows(delta: &[f64], omega: &[f64], inv_beta: f64, x: &[f64], d: &mut [f64], out: &mut [f64]) {
        let q = x.len();
        rate(q, delta, omega, inv_beta, d);
        apply_rows(q, omega, x, out);
    }
    by_size!(q, fixed, rows, (delta, omega, inv_beta, x, d_omega, out))
}

/// out = Ω x for a fixed q: (Ω x)_i = Σ_j Ω_ij x_j over the full row i in j order, each in its own
/// accumulator (the order of [`apply_rows`], so both paths round alike).
#[inline(always)]
fn apply_fixed<const Q: usize>(omega: &[f64], x: &[f64], out: &mut [f64]) {
    let (omega, x, out): (&[f64], &[f64; Q], &mut [f64; Q]) =
        (&omega[..Q * (Q + 1) / 2], x.try_into().expect("checked"), out.try_into().expect("checked"));
    let at = const { full_index::<Q>() };
    for (o, row) in out.iter_mut().zip(&at) {
        let mut acc = 0.0;
        for (&p, xj) in row.iter().zip(x) {
            acc += omega[p] * xj;
        }
        *o = acc;
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

/// out = Ω x for any q, in the order of [`apply_fixed`]: column i of the rows above the diagonal,
/// then row i from the diagonal on.
fn apply_rows(q: usize, omega: &[f64], x: &[f64], out: &mut [f64]) {
    for (i, o) in out.iter_mut().enumerate().take(q) {
        let (mut acc, mut k) = (0.0, i);
        // Ω_ji for j < i sits at k = (start of row j) + (i − j); the next row starts q − j further.
        for (j, xj) in x[..i].iter().enumerate() {
            acc += omega[k] * xj;
            k += q - j - 1;
        }
        for (w, xj) in omega[k..k + q - i].iter().zip(&x[i..]) {
            acc += w * xj;
        }
        *o = acc;
    }
}

/// Packed index of Ω_rc, r ≤ c.
#[inline(always)]
const fn at(q: usize, r: usize, c: usize) -> usize {
    r * q - r * r.saturating_sub(1) / 2 + (c - r)
}

/// The largest absolute row sum of Ω, a bound of its spectral radius (Gershgorin).
pub(crate) fn max_row_sum(omega: &[f64], q: usize) -> f64 {
    (0..q)
        .map(|i| (0..q).map(|j| omega[if i <= j { at(q, i, j) } else { at(q, j, i) }].abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// A lower estimate of λ_max(Ω), Ω positive semidefinite: the Rayleigh quotient xᵀΩx / xᵀx of
/// x = Ω^(k−1) x₀, x₀_j = 1 + j/q, k = `iterations`. It never exceeds λ_max (up to rounding) and
/// approaches it as (λ₂/λ₁)^(2(k−1)), where [`max_row_sum`] may exceed it by up to √q. `work`
/// holds 2q.
pub(crate) fn max_eigenvalue_below(omega: &[f64], q: usize, iterations: usize, work: &mut [f64]) -> f64 {
    let (x, y) = work[..2 * q].split_at_mut(q);
    for (j, v) in x.iter_mut().enumerate() {
        *v = 1.0 + j as f64 / q as f64;
    }
    let mut quotient = 0.0;
    for _ in 0..iterations {
        apply_rows(q, omega, x, y);
        let (xx, xy) = x.iter().zip(y.iter()).fold((0.0, 0.0), |(xx, xy), (a, b)| (xx + a * a, xy + a * b));
        quotient = xy / xx;
        let norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            break;
        }
        for (a, b) in x.iter_mut().zip(y.iter()) {
            *a = b / norm;
        }
    }
    if quotient.is_finite() {
        quotient.max(0.0)
    } else {
        0.0
    }
}

/// Solves (I + c Ω) x = b in place (`x` holds b on entry) by a Cholesky factorization into
/// `factor` (packed, q(q+1)/2 long): the implicit stage of the adaptive law η̂' = μ (Y − Ω η̂)
/// (eq. (33)) with c = h γ μ. `false`, x unspecified, when I + c Ω is not numerically positive
/// definite (Ω not positive semidefinite, or non-finite entries).
pub(crate) fn solve_shifted(omega: &[f64], c: f64, x: &mut [f64], factor: &mut [f64]) -> bool {
    let q = x.len();
    let (omega, r) = (&omega[..len(q)], &mut factor[..len(q)]);
    r.iter_mut().zip(omega).for_each(|(ri, oi)| *ri = c * oi);
    for i in 0..q {
        r[at(q, i, i)] += 1.0;
    }
    // Row by row, each row then taken out of the rows below it (right-looking): every inner loop
    // runs along a packed row, contiguous, where the inner products down two columns had strided
    // through the triangle (the cost of the implicit path at q = 75: 1.6 ms a step).
    for i in 0..q {
        let (done, rest) = r.split_at_mut(at(q, i, i) + q - i);
        let row = &mut done[at(q, i, i)..];
        // NaN fails this test too.
        if !(row[0] > 0.0 && row[0].is_finite()) {
            return false;
        }
        let d = row[0].sqrt();
        row[0] = d;
        row[1..].iter_mut().for_each(|v| *v /= d);
        let mut below = rest;
        for j in i + 1..q {
            let (target, next) = below.split_at_mut(q - j);
            let f = row[j - i];
            target.iter_mut().zip(&row[j - i..]).for_each(|(t, v)| *t -= f * v);
            below = next;
        }
    }
    // Rᵀ y = b (each solved entry taken out of those below), then R x = y.
    for i in 0..q {
        let row = &r[at(q, i, i)..at(q, i, i) + q - i];
        x[i] /= row[0];
        let xi = x[i];
        x[i + 1..].iter_mut().zip(&row[1..]).for_each(|(xj, v)| *xj -= v * xi);
    }
    for i in (0..q).rev() {
        let row = &r[at(q, i, i)..at(q, i, i) + q - i];
        let s: f64 = row[1..].iter().zip(&x[i + 1..]).map(|(v, xj)| v * xj).sum();
        x[i] = (x[i] - s) / row[0];
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Unpacks into a dense q×q matrix, row-major.
    fn unpack(omega: &[f64], q: usize, dense: &mut [f64]) {
        let mut k = 0;
        for i in 0..q {
            for j in i..q {
                dense[i * q + j] = omega[k];
                dense[j * q + i] = omega[k];
                k += 1;
            }
        }
    }

    /// A reproducible stream of uniform numbers in [−1, 1).
    fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed | 1;
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    proptest! {
        /// Both the size-specialized (q ≤ 12) and the row-wise (q > 12) paths against the dense
        /// definition: (ΔΔᵀ − Ω)/β entrywise and Ω x, to 1e-14 relative to Σ|Ω_ij x_j| (a few ulps of
        /// a sum of q terms, accumulated in different orders).
        #[test]
        fn filter_rate_and_apply_matches_dense(q in 1usize..=16, seed in any::<u64>(), inv_beta in 0.1f64..10.0) {
            let mut next = uniform(seed);
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

    proptest! {
        /// The unrolled and the general product sum in the same order, so they agree bit for bit.
        #[test]
        fn fixed_and_general_products_agree_exactly(seed in any::<u64>()) {
            let mut next = uniform(seed);
            macro_rules! each {
                ($($q:literal)*) => {$({
                    let omega: Vec<f64> = (0..len($q)).map(|_| next()).collect();
                    let x: Vec<f64> = (0..$q).map(|_| next()).collect();
                    let (mut fixed, mut rows) = ([0.0; $q], [0.0; $q]);
                    apply_fixed::<$q>(&omega, &x, &mut fixed);
                    apply_rows($q, &omega, &x, &mut rows);
                    prop_assert_eq!(fixed, rows);
                })*};
            }
            each!(1 2 3 4 5 6 7 8 9 10 11 12);
        }
    }

    proptest! {
        /// (I + cΩ) x = b for a random positive semidefinite Ω = G Gᵀ against the dense product, to
        /// 1e-12 relative to |b| + c|Ω||x| (the backward error of Cholesky is a few ulps times q).
        #[test]
        fn solve_shifted_solves_the_shifted_system(q in 1usize..=80, seed in any::<u64>(), e in -3i32..9) {
            let mut next = uniform(seed);
            let g: Vec<f64> = (0..q * q).map(|_| next()).collect();
            let mut dense = vec![0.0; q * q];
            for i in 0..q {
                for j in 0..q {
                    dense[i * q + j] = (0..q).map(|k| g[i * q + k] * g[j * q + k]).sum();
                }
            }
            let omega: Vec<f64> = (0..q).flat_map(|i| (i..q).map(move |j| (i, j))).map(|(i, j)| dense[i * q + j]).collect();
            let b: Vec<f64> = (0..q).map(|_| next()).collect();
            let c = 10f64.powi(e);
            let (mut x, mut factor) = (b.clone(), vec![0.0; len(q)]);
            prop_assert!(solve_shifted(&omega, c, &mut x, &mut factor));
            for i in 0..q {
                let (mut lhs, mut scale) = (x[i], b[i].abs() + x[i].abs());
                for j in 0..q {
                    lhs += c * dense[i * q + j] * x[j];
                    scale += (c * dense[i * q + j] * x[j]).abs();
                }
                prop_assert!((lhs - b[i]).abs() <= 1e-12 * scale, "q {q}, c {c}: row {i}: {lhs} vs {}", b[i]);
            }
            // Gershgorin bounds every eigenvalue, so in particular Ω's largest, |Ω g_1|/|g_1| ≤ bound
            // is a necessary check; the trace bounds λ_max of a PSD matrix from above too.
            let trace: f64 = (0..q).map(|i| dense[i * q + i]).sum();
            prop_assert!(max_row_sum(&omega, q) <= trace * q as f64 + 1e-12);
            prop_assert!(max_row_sum(&omega, q) >= trace / q as f64 - 1e-12);
        }
    }

    proptest! {
        /// The Rayleigh quotient never exceeds λ_max (nalgebra's symmetric eigenvalues, 1e-12
        /// relative) and is not negative, for random positive semidefinite Ω = G Gᵀ.
        #[test]
        fn the_power_steps_stay_below_the_largest_eigenvalue(q in 1usize..=40, seed in any::<u64>(), k in 1usize..=12) {
            let mut next = uniform(seed);
            let g: Vec<f64> = (0..q * q).map(|_| next()).collect();
            let dense = nalgebra::DMatrix::from_fn(q, q, |i, j| (0..q).map(|l| g[i * q + l] * g[j * q + l]).sum::<f64>());
            let omega: Vec<f64> = (0..q).flat_map(|i| (i..q).map(move |j| (i, j))).map(|(i, j)| dense[(i, j)]).collect();
            let lambda = dense.clone().symmetric_eigen().eigenvalues.max();
            let below = max_eigenvalue_below(&omega, q, k, &mut vec![0.0; 2 * q]);
            prop_assert!(below >= 0.0 && below <= lambda * (1.0 + 1e-12), "q {q}: {below} against λ_max {lambda}");
        }
    }

    /// A rank-one Ω = g gᵀ (the filter's ΔΔᵀ) has λ_max = |g|², the quotient of Ω x₀ (two
    /// steps); a diagonal with its next eigenvalue half the largest is within 1e-3 of it after
    /// eight (the error shrinks as (1/2)^(2(k − 1)).
    #[test]
    fn the_power_steps_find_a_dominant_eigenvalue() {
        let g = [0.3, -1.2, 2.0, 0.5];
        let omega: Vec<f64> = (0..4).flat_map(|i| (i..4).map(move |j| g[i] * g[j])).collect();
        let norm2: f64 = g.iter().map(|v| v * v).sum();
        let found = max_eigenvalue_below(&omega, 4, 2, &mut [0.0; 8]);
        assert!((found - norm2).abs() <= 1e-14 * norm2, "{found} against {norm2}");
        let diagonal = [0.2, 3.0, 1.5, 0.7, 0.1];
        let omega: Vec<f64> =
            (0..5).flat_map(|i| (i..5).map(move |j| if i == j { diagonal[i] } else { 0.0 })).collect();
        let found = max_eigenvalue_below(&omega, 5, 8, &mut [0.0; 10]);
        assert!((3.0 * (1.0 - 1e-3)..=3.0).contains(&found), "{found}");
    }

    #[test]
    fn solve_shifted_refuses_an_indefinite_matrix() {
        // Ω = [[0, 2], [2, 0]] has eigenvalue −2: I + Ω is indefinite.
        let (mut x, mut f) = ([1.0, 1.0], [0.0; 3]);
        assert!(!solve_shifted(&[0.0, 2.0, 0.0], 1.0, &mut x, &mut f));
        assert!(!solve_shifted(&[f64::NAN, 0.0, 1.0], 1.0, &mut x, &mut f));
        // (I + 0.5 [[2, 1], [1, 2]]) x = [3, 3] → x = [1.2, 1.2] by hand ([[2, .5], [.5, 2]] x = 3).
        let mut x = [3.0, 3.0];
        assert!(solve_shifted(&[2.0, 1.0, 2.0], 0.5, &mut x, &mut f));
        assert!((x[0] - 1.2).abs() < 1e-15 && (x[1] - 1.2).abs() < 1e-15, "{x:?}");
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
