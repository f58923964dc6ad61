//! Coefficients of ARK4(3)6L\[2\]SA (Kennedy & Carpenter, "Additive Runge–Kutta schemes for
//! convection–diffusion–reaction equations", *Appl. Numer. Math.* 44 (2003), Table 5; as tabulated
//! in SUNDIALS ARKode, `ARKODE_ARK436L2SA_ERK_6_3_4` and `ARKODE_ARK436L2SA_DIRK_6_3_4`).
//!
//! An additive pair: an explicit 6-stage method (A_E) for the non-stiff part and an L-stable,
//! stiffly accurate ESDIRK (A_I, diagonal γ = 1/4, explicit first stage) for the stiff part, with
//! common nodes c, weights b (order 4, coupling conditions included) and embedded weights d
//! (order 3). The order conditions are checked in the tests below rather than trusted to the
//! transcription.

/// Number of stages.
pub(super) const STAGES: usize = 6;
/// The ESDIRK diagonal γ.
pub(super) const GAMMA: f64 = 0.25;

/// Nodes c_i.
pub(super) const C: [f64; STAGES] = [0.0, 0.5, 83.0 / 250.0, 31.0 / 50.0, 17.0 / 20.0, 1.0];

/// Weights b_j (4th order), shared by both parts; row 5 of A_I.
pub(super) const B: [f64; STAGES] =
    [82889.0 / 524892.0, 0.0, 15625.0 / 83664.0, 69875.0 / 102672.0, -2260.0 / 8211.0, 0.25];

/// b_j − d_j, d the embedded 3rd-order weights: the error estimate is h Σ_j (b_j − d_j) f(z_j).
pub(super) const E: [f64; STAGES] = {
    let d = [
        4586570599.0 / 29645900160.0,
        0.0,
        178811875.0 / 945068544.0,
        814220225.0 / 1159782912.0,
        -3700637.0 / 11593932.0,
        61727.0 / 225920.0,
    ];
    let mut e = [0.0; STAGES];
    let mut j = 0;
    while j < STAGES {
        e[j] = B[j] - d[j];
        j += 1;
    }
    e
};

/// The explicit part's a_ij (strictly lower triangular).
pub(super) const A_E: [[f64; STAGES]; STAGES] = [
    [0.0; STAGES],
    [0.5, 0.0, 0.0, 0.0, 0.0, 0.0],
    [13861.0 / 62500.0, 6889.0 / 62500.0, 0.0, 0.0, 0.0, 0.0],
    [
        -116923316275.0 / 2393684061468.0,
        -2731218467317.0 / 15368042101831.0,
        9408046702089.0 / 11113171139209.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        -451086348788.0 / 2902428689909.0,
        -2682348792572.0 / 7519795681897.0,
        12662868775082.0 / 11960479115383.0,
        3355817975965.0 / 11060851509271.0,
        0.0,
        0.0,
    ],
    [
        647845179188.0 / 3216320057751.0,
        73281519250.0 / 8382639484533.0,
        552539513391.0 / 3454668386233.0,
        3354512671639.0 / 8306763924573.0,
        4040.0 / 17871.0,
        0.0,
    ],
];

/// The implicit part's a_ij (lower triangular, a_ii = γ for i ≥ 1, a_00 = 0).
pub(super) const A_I: [[f64; STAGES]; STAGES] = [
    [0.0; STAGES],
    [0.25, 0.25, 0.0, 0.0, 0.0, 0.0],
    [8611.0 / 62500.0, -1743.0 / 31250.0, 0.25, 0.0, 0.0, 0.0],
    [5012029.0 / 34652500.0, -654441.0 / 2922500.0, 174375.0 / 388108.0, 0.25, 0.0, 0.0],
    [
        15267082809.0 / 155376265600.0,
        -71443401.0 / 120774400.0,
        730878875.0 / 902184768.0,
        2285395.0 / 8070912.0,
        0.25,
        0.0,
    ],
    [B[0], B[1], B[2], B[3], B[4], 0.25],
];

#[cfg(test)]
mod tests {
    use super::*;

    /// A rooted tree as the list of its root's subtrees.
    #[derive(Clone, Debug)]
    struct Tree(Vec<Tree>);

    impl Tree {
        fn order(&self) -> usize {
            1 + self.0.iter().map(Tree::order).sum::<usize>()
        }
        /// γ(t) = |t| Π γ(subtrees).
        fn density(&self) -> f64 {
            self.order() as f64 * self.0.iter().map(Tree::density).product::<f64>()
        }
    }

    /// All rooted trees with at most `p` vertices (duplicates are harmless for the conditions).
    fn trees(p: usize) -> Vec<Tree> {
        let mut all = vec![Tree(vec![])];
        for _ in 1..p {
            let mut next = all.clone();
            for t in &all {
                for s in &all {
                    if t.order() + s.order() <= p {
                        let mut grown = t.0.clone();
                        grown.push(s.clone());
                        next.push(Tree(grown));
                    }
                }
            }
            all = next;
        }
        all
    }

    /// Every colouring of the non-root vertices by the two tableaus: the stage vectors Φ(t) of an
    /// additive method, Φ_i(t) = Π_subtrees Σ_j a^(colour)_ij Φ_j(subtree).
    fn phis(t: &Tree) -> Vec<[f64; STAGES]> {
        let mut acc = vec![[1.0; STAGES]];
        for sub in &t.0 {
            let mut next = Vec::new();
            for phi_sub in phis(sub) {
                for a in [&A_E, &A_I] {
                    let mut v = [0.0; STAGES];
                    for (i, vi) in v.iter_mut().enumerate() {
                        *vi = (0..STAGES).map(|j| a[i][j] * phi_sub[j]).sum();
                    }
                    for phi in &acc {
                        let mut p = *phi;
                        for i in 0..STAGES {
                            p[i] *= v[i];
                        }
                        next.push(p);
                    }
                }
            }
            acc = next;
        }
        acc
    }

    /// Largest violation of Σ_i w_i Φ_i(t) = 1/γ(t) over all coloured trees of order ≤ p.
    fn worst(w: &[f64; STAGES], p: usize) -> f64 {
        let mut worst: f64 = 0.0;
        for t in trees(p).iter().filter(|t| t.order() <= p) {
            for phi in phis(t) {
                let s: f64 = (0..STAGES).map(|i| w[i] * phi[i]).sum();
                worst = worst.max((s - 1.0 / t.density()).abs());
            }
        }
        worst
    }

    // The coefficients are ratios of integers of up to 14 digits, so each entry carries a relative
    // rounding of ~1e-16; sums of a few hundred products of them stay below 1e-13.
    const TOL: f64 = 1e-13;

    #[test]
    fn additive_pair_has_order_4_with_coupling_and_embedded_order_3() {
        assert!(worst(&B, 4) < TOL, "order 4: {}", worst(&B, 4));
        let d: [f64; STAGES] = std::array::from_fn(|j| B[j] - E[j]);
        assert!(worst(&d, 3) < TOL, "embedded order 3: {}", worst(&d, 3));
        // The embedded method is genuinely of order 3 only: an error estimate that vanished at order 4
        // would be useless.
        assert!(worst(&d, 4) > 1e-4);
    }

    #[test]
    fn nodes_are_row_sums_and_the_implicit_part_is_stiffly_accurate() {
        for i in 0..STAGES {
            let (se, si): (f64, f64) = (A_E[i].iter().sum(), A_I[i].iter().sum());
            assert!((se - C[i]).abs() < TOL && (si - C[i]).abs() < TOL, "row {i}: {se} {si} vs {}", C[i]);
            assert!(A_E[i][i..].iter().all(|&a| a == 0.0));
            if i > 0 {
                assert_eq!(A_I[i][i], GAMMA);
            }
        }
        assert_eq!(A_I[STAGES - 1], B);
    }

    /// R(z) = 1 + z bᵀ (I − z A_I)⁻¹ 1 of the implicit part, by forward substitution.
    fn stability(z: f64) -> f64 {
        let mut k = [0.0; STAGES];
        for i in 0..STAGES {
            // Stage value Y_i = 1 + z Σ_j a_ij Y_j.
            let rhs: f64 = 1.0 + z * (0..i).map(|j| A_I[i][j] * k[j]).sum::<f64>();
            k[i] = rhs / (1.0 - z * A_I[i][i]);
        }
        1.0 + z * (0..STAGES).map(|j| B[j] * k[j]).sum::<f64>()
    }

    #[test]
    fn implicit_part_is_l_stable_on_the_negative_axis() {
        // A-stable along the axis and R(−∞) = 0 (L-stable: a stiff mode is damped in one step).
        for e in 0..=12 {
            for m in [1.0, 2.0, 5.0] {
                let z = -m * 10f64.powi(e - 2);
                assert!(stability(z).abs() <= 1.0, "|R({z})| = {}", stability(z).abs());
            }
        }
        assert!(stability(-1e12).abs() < 1e-10);
        // Consistency: R(z) = e^z + O(z⁵).
        assert!((stability(-1e-2) - (-1e-2f64).exp()).abs() < 1e-11);
    }
}
