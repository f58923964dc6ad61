//! Internal-model filters (Sections IV–V, eqs. (10), (15)): controllable pairs (G, l) from chosen
//! Hurwitz poles, stacked block-diagonally into (G_g, L_g) and (G_ω, L_ω).
//!
//! Any controllable (G, l) with G Hurwitz serves the method; the realization only sets the size of
//! the regressor ξ̂ and so the meaning of μ (the adaptive law (33) is a gradient law in ξ̂'s
//! coordinates: its rate is μ_i λ_max(Ω_i), with Ω_i quadratic in ξ̂).

use std::fmt;

use nalgebra::{Complex, DMatrix};

use crate::linalg::{blkdiag, companion, poly_from_roots};

/// How the filters (G, l) of eqs. (10), (15) are realized (`design.regressor_scaling`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RegressorScaling {
    /// The paper's companion form, l = e_q: ξ̂'s first entry is 1/∏(s − p_j) of the signal, with DC
    /// gain 1/∏|p_j| (≈ 1.3e3 for poles −0.05, −0.1, −0.15), and entry k is s^(k−1) times it; the
    /// size of ξ̂, and with it the adaptive law's rate for a given μ, depends on the filter poles.
    /// What a file without the key means, so every scenario written before keeps its meaning.
    #[default]
    Paper,
    /// The same filter run at its own time scale ω₀ = (∏|p_j|)^(1/q): G = ω₀·companion(∏(s − p_j/ω₀)),
    /// l = ω₀ e_q, i.e. ξ̂_k = ω₀^(q−k+1) s^(k−1) / ∏(s − p_j). Entry 1 has unit DC gain and entry k
    /// is entry 1 times (s/ω₀)^(k−1), so near the poles' time scale (where the signals' frequencies
    /// are) every entry has the size of the signal, whatever the poles.
    Normalized,
}

impl RegressorScaling {
    /// Every scaling with its name in `design.regressor_scaling`.
    pub const ALL: [(RegressorScaling, &'static str); 2] =
        [(RegressorScaling::Paper, "paper"), (RegressorScaling::Normalized, "normalized")];

    /// The scenario key's value.
    pub fn name(self) -> &'static str {
        Self::ALL.iter().find(|(s, _)| *s == self).map_or("paper", |(_, n)| n)
    }

    /// The scaling named `name`, or the message for `design.regressor_scaling`.
    pub fn from_name(name: &str) -> Result<RegressorScaling, String> {
        Self::ALL.iter().find(|(_, n)| *n == name).map(|(s, _)| *s).ok_or_else(|| {
            format!(
                "expected \"paper\" (the paper's companion form, l = e_q) or \"normalized\" (unit DC gain, every entry at the filter's time scale), found \"{name}\""
            )
        })
    }

    /// What μ_i means under this scaling, for the design report.
    pub fn mu_meaning(self) -> &'static str {
        match self {
            RegressorScaling::Paper => {
                "ξ̂ is the paper's companion form (l = e_q): its size is the signals' divided by ∏|p_j| of each filter, so μ_i's effect depends on the filter poles; μ_i λ_max(Ω̄_i) below is the rate it gives"
            }
            RegressorScaling::Normalized => {
                "ξ̂ is normalized (unit DC gain, every entry at its filter's time scale): it has the size of the signals, so μ_i is a rate per squared signal unit (μ_i·|g|²·|G_ii|² ≈ μ_i λ_max(Ω̄_i), per unit of the plant's time)"
            }
        }
    }
}

impl fmt::Display for RegressorScaling {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// (G, l) for poles p_1..p_q. [`RegressorScaling::Paper`]: G is the companion matrix of ∏(s − p_j)
/// (ones on the superdiagonal, last row −[a_0, …, a_{q−1}]) and l = e_q, the form of G_g and G_ω
/// printed in Section VIII. [`RegressorScaling::Normalized`]: that pair in the coordinates ξ̃_k = a_0 ξ_k / ω₀^(k−1)
/// with ω₀ = a_0^(1/q), i.e. G = ω₀·companion of the polynomial with roots p_j/ω₀ and l = ω₀ e_q.
pub fn filter_pair(poles: &[Complex<f64>], scaling: RegressorScaling) -> (DMatrix<f64>, DMatrix<f64>) {
    let q = poles.len();
    let mut l = DMatrix::zeros(q, 1);
    if q == 0 {
        return (DMatrix::zeros(0, 0), l);
    }
    let G = match scaling {
        RegressorScaling::Paper => {
            l[(q - 1, 0)] = 1.0;
            companion(&poly_from_roots(poles))
        }
        RegressorScaling::Normalized => {
            let w0 = time_scale(poles);
            let unit: Vec<Complex<f64>> = poles.iter().map(|p| p / w0).collect();
            l[(q - 1, 0)] = w0;
            companion(&poly_from_roots(&unit)) * w0
        }
    };
    (G, l)
}

/// ω₀ = (∏|p_j|)^(1/q), the geometric mean of the poles' magnitudes (a_0^(1/q) for the monic
/// ∏(s − p_j) of Hurwitz poles closed under conjugation), summed in logarithms so no product
/// overflows.
pub fn time_scale(poles: &[Complex<f64>]) -> f64 {
    (poles.iter().map(|p| p.norm().ln()).sum::<f64>() / poles.len() as f64).exp()
}

/// Block-diagonal (G, L) = (blkdiag G_i, blkdiag l_i) for one pole list per signal component
/// (eqs. (11), (16)): G is Σq_i × Σq_i, L is Σq_i × (number of components).
pub fn internal_model(poles: &[Vec<Complex<f64>>], scaling: RegressorScaling) -> (DMatrix<f64>, DMatrix<f64>) {
    let (Gs, ls): (Vec<_>, Vec<_>) = poles.iter().map(|p| filter_pair(p, scaling)).unzip();
    (blkdiag(&Gs), blkdiag(&ls))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Entry k of (sI − G)⁻¹ l against the closed form ω₀^(q−k+1) s^(k−1) / ∏(s − p_j) (and
    /// s^(k−1)/∏(s − p_j) for the paper's form), at DC and at s = jω₀ for the quadruple tank's poles.
    #[test]
    fn filters_have_their_closed_form_gains() {
        let poles: Vec<Complex<f64>> = [-0.05, -0.1, -0.15].iter().map(|&p| Complex::new(p, 0.0)).collect();
        let w0 = (0.05f64 * 0.1 * 0.15).cbrt();
        assert!((time_scale(&poles) - w0).abs() <= 1e-15);
        for scaling in [RegressorScaling::Paper, RegressorScaling::Normalized] {
            let (G, l) = filter_pair(&poles, scaling);
            for s in [Complex::new(0.0, 0.0), Complex::new(0.0, w0), Complex::new(0.0, 0.02)] {
                let mut M = -G.map(|x| Complex::new(x, 0.0));
                for i in 0..3 {
                    M[(i, i)] += s;
                }
                let x = M.lu().solve(&l.map(|x| Complex::new(x, 0.0))).unwrap();
                let den: Complex<f64> = poles.iter().map(|p| s - p).product();
                for k in 0..3 {
                    let scale = match scaling {
                        RegressorScaling::Paper => 1.0,
                        RegressorScaling::Normalized => w0.powi(3 - k as i32),
                    };
                    let expected = s.powi(k as i32) * scale / den;
                    // A 3×3 complex solve on entries of size ≤ 0.3: a few ulps of the largest.
                    assert!((x[k] - expected).norm() <= 1e-12 * expected.norm().max(1.0), "{scaling} s={s} k={k}");
                }
            }
        }
        // DC gains: 1/∏|p_j| ≈ 1333 in the paper's form, exactly 1 normalized.
        let dc = |scaling| {
            let (G, l) = filter_pair(&poles, scaling);
            -(G.lu().solve(&l).unwrap())[(0, 0)]
        };
        assert!((dc(RegressorScaling::Paper) - 1.0 / 7.5e-4).abs() <= 1e-9);
        assert!((dc(RegressorScaling::Normalized) - 1.0).abs() <= 1e-13);
    }

    #[test]
    fn names_round_trip_and_a_bad_name_lists_the_choices() {
        for (s, n) in RegressorScaling::ALL {
            assert_eq!(RegressorScaling::from_name(n), Ok(s));
            assert_eq!(s.name(), n);
        }
        let e = RegressorScaling::from_name("unit").unwrap_err();
        assert!(e.contains("\"paper\"") && e.contains("\"normalized\"") && e.contains("\"unit\""), "{e}");
    }
}
