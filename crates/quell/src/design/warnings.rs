//! Fragile gains: a design that passed every check but whose closed-loop poles a small model error
//! can move far (a large eigenvector condition number, eigenvalues off the requested poles; a
//! placed pole repeated beyond the rank of C is refused by [`super::place()`]). Reported as warnings, with the figures and what
//! to do, by `quell design`, `design.json`, `quell run` and Python (`warnings.warn`).

use nalgebra::{Complex, DMatrix};
use serde::Serialize;

use super::{Design, DesignSpec, ObserverChoice};
use crate::linalg::numerical_rank;

/// κ₂ of the eigenvector matrix above which a closed loop counts as fragile: a relative model error
/// of 1e-8 could then move its poles by their own size.
pub const FRAGILE_CONDITION: f64 = 1e8;
/// Relative distance of eig(A − LC) from the requested poles above which the placement is reported.
pub const FRAGILE_ERROR: f64 = 1e-8;

/// Scale-free condition number of B* (Proposition 1) above which the decoupler is reported: K and F
/// invert B*, so a relative error ε in the plant's input gains reaches the decoupled channels as
/// about κ·ε, the size of the channels themselves for ε = 2 % at κ = 50. Skogestad's LV column
/// (κ = 142 by the cosines then in use) diverged in 7 of 10 draws with truth.B 2 % off. κ is B*'s
/// equilibrated ([`crate::Design::cond_B_star`]), near the least over the inputs' and outputs'
/// units, which for a 2×2 is set by its relative gain λ (2λ − 1 + √((2λ − 1)² − 1)): an
/// ill-conditioning the units make is not reported (Ogunnaike–Ray's column, 193 by the cosines,
/// is 7.5 equilibrated), one the plant makes is (the LV column's λ = 35 at steady state: 138).
pub const ILL_CONDITIONED_DECOUPLER: f64 = 50.0;

/// One fragile part of a design.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DesignWarning {
    /// The scenario key whose choice is fragile.
    pub key: &'static str,
    /// Largest number of copies of one requested pole, and the rank C it cannot exceed.
    pub multiplicity: usize,
    pub rank: usize,
    /// max |λ − p| / max(1, |p|) over eig(A − LC) matched to the requested poles (`null`: not placed).
    pub verified_error: Option<f64>,
    /// κ₂ of the closed loop's eigenvector matrix (∞, `null` in JSON, for a Jordan block).
    pub eigenvector_condition: f64,
    pub message: String,
}

/// The fragile parts of `design`, made from `spec`.
pub fn warnings(design: &Design, spec: &DesignSpec) -> Vec<DesignWarning> {
    let mut out = Vec::new();
    let p = design.plant();
    let kappa = design.observer_eigenvector_condition();
    let rank = numerical_rank(&p.C);
    let (multiplicity, error) = match &spec.observer {
        ObserverChoice::Poles(poles) => (
            super::place::most_repeated(poles).map_or(0, |(_, k)| k),
            Some(super::place::matching_error(design.observer_eigenvalues(), poles)),
        ),
        ObserverChoice::Gain(_) => (1, None),
    };
    if let (ObserverChoice::Gain(_), true) = (&spec.observer, fragile(kappa)) {
        // A gain given: no requested poles to be off from (a "?" had stood for their error).
        out.push(DesignWarning {
            key: "design.observer_gain",
            multiplicity,
            rank,
            verified_error: None,
            eigenvector_condition: kappa,
            message: format!(
                "design.observer_gain: fragile observer gain: eig(A − LC) has eigenvector condition number κ₂ = {kappa:.2e}: a relative model error ε can move the observer poles by about κ₂·ε·‖A − LC‖; give a gain whose A − LC has distinct eigenvalues not far faster than the plant's, or give design.observer_poles instead"
            ),
        });
    } else if fragile(kappa) || error.is_some_and(|e| e > FRAGILE_ERROR) {
        out.push(DesignWarning {
            key: "design.observer_poles",
            multiplicity,
            rank,
            verified_error: error,
            eigenvector_condition: kappa,
            message: format!(
                "design.observer_poles: fragile observer gain: eig(A − LC) is off the requested poles by {} (relative) and its eigenvector condition number is κ₂ = {kappa:.2e}: a relative model error ε can move the observer poles by about κ₂·ε·‖A − LC‖; {}",
                error.map_or("?".to_string(), |e| format!("{e:.1e}")),
                if multiplicity > 1 || !kappa.is_finite() {
                    format!("give distinct poles (at most {} of one; spread a repeated pole by ±10 %), not far faster than the plant", crate::settings::count(rank, "copy", "copies"))
                } else {
                    // Distinct poles already (a finite κ₂): what is left is their speed against the plant's.
                    "the poles are distinct, so move them nearer the plant's own eigenvalues (slower, or less spread): a gain far faster than the plant needs large entries".to_string()
                },
            ),
        });
    }
    let kappa = design.decoupled_eigenvector_condition();
    if fragile(kappa) {
        out.push(DesignWarning {
            key: "design.channel_poles",
            multiplicity: 0,
            rank: numerical_rank(&p.B),
            verified_error: None,
            eigenvector_condition: kappa,
            message: format!(
                "design.channel_poles: fragile decoupler: A − BK has eigenvector condition number κ₂ = {kappa:.2e}, so a model error moves its poles (the channel poles and the plant's zeros) by about κ₂·ε·‖A − BK‖; give distinct channel poles, apart from the plant's zeros"
            ),
        });
    }
    out.extend(plant_warnings(design));
    let cond = design.cond_B_star();
    if cond > ILL_CONDITIONED_DECOUPLER {
        out.push(DesignWarning {
            key: "plant.B",
            multiplicity: 0,
            rank: numerical_rank(&p.B),
            verified_error: None,
            eigenvector_condition: f64::NAN,
            message: format!(
                "plant.B: ill-conditioned decoupler: B* (Proposition 1) has scale-free condition number {cond:.2e}, and K, F invert it, so a relative error ε in the plant's input gains reaches the decoupled channels as about {cond:.0}·ε ({:.0} % at ε = 1 %); check the loop's robustness with a study over truth.B (docs/studies.md), or pair inputs and outputs whose leading responses differ more",
                cond
            ),
        });
    }
    out
}

/// The plant's part: a decoupler that does not decouple ([`decoupling_error`]) and zeros within
/// rounding of the imaginary axis ([`Design::near_axis_zeros`]).
fn plant_warnings(design: &Design) -> Vec<DesignWarning> {
    let p = design.plant();
    let mut out = Vec::new();
    if let Some((error, s_at)) = decoupling_error(design).filter(|(e, _)| *e > COUPLING) {
        out.push(DesignWarning {
            key: "design.relative_degrees",
            multiplicity: 0,
            rank: numerical_rank(&p.B),
            verified_error: Some(error),
            eigenvector_condition: f64::NAN,
            message: format!(
                "design.relative_degrees: the decoupler does not decouple this plant: at s = {} /{} the closed loop C (sI − A + BK)⁻¹ B F differs from diag(G_ii(s)) by {error:.1e} of its diagonal (σ = {:?}); eq. (7)'s cosines (taken on the balanced realization) read a non-zero c_i A^(l−1) B as zero where it is small beside the plant's other gains: give design.relative_degrees with the smaller σ_i if that gain is real, or write the states in comparable units",
                crate::linalg::fmt_complex(&s_at),
                p.time_unit.symbol(),
                design.sigma(),
            ),
        });
    }
    let near = design.near_axis_zeros();
    if !near.is_empty() {
        let unit = p.time_unit;
        let slowest = near.iter().map(|z| -z.re).fold(f64::INFINITY, f64::min);
        out.push(DesignWarning {
            key: "plant.C",
            multiplicity: 0,
            rank: numerical_rank(&p.C),
            verified_error: None,
            eigenvector_condition: f64::NAN,
            message: format!(
                "plant.C: zeros of (A, B, C) within rounding of the imaginary axis, [{}] (per {unit}): stable, but decoupling cancels them, so A − BK keeps modes that decay only over 1/|Re z| = {} {unit}, the steady plant input at frequencies near them grows as 1/|z − jω| (the report's steady input), and a model error of that size puts them in the right half-plane; measure other outputs, or check the model's zeros",
                crate::linalg::fmt_complex_list(near),
                crate::settings::fmt_short(crate::settings::significant(1.0 / slowest, 3)),
            ),
        });
    }
    out
}

/// The closed loop's departure from diag(G_ii) above which [`warnings`] says the decoupler does
/// not decouple: far above its rounding (the examples' 1e-15 … 1e-10), far below what a σ_i misread
/// leaves (a channel 5 % coupled, its diagonal 30 % off).
pub const COUPLING: f64 = 1e-6;

/// max_{i,j} |G(s)_ij − δ_ij G_ii(s)| / max_i |G_ii(s)| over three points s at the channel poles'
/// scale, G(s) = C (sI − A_f)⁻¹ B_f: a transfer matrix, so the same in any state coordinates (the
/// check eq. (7)'s coordinate-bound cosines cannot make). With the worst point; `None` where every
/// point is singular or not finite.
fn decoupling_error(design: &Design) -> Option<(f64, Complex<f64>)> {
    let (A_f, B_f, C) = (design.A_f(), design.B_f(), &design.plant().C);
    let n = A_f.nrows();
    let r = design
        .channels()
        .iter()
        .flat_map(|c| c.poles.iter())
        .map(|p| p.norm())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let c = |M: &DMatrix<f64>| M.map(|v| Complex::new(v, 0.0));
    let (Ac, Bc, Cc) = (c(A_f), c(B_f), c(C));
    [Complex::new(0.5 * r, r), Complex::new(0.0, 1.3 * r), Complex::new(2.0 * r, 0.7 * r)]
        .into_iter()
        .filter_map(|s| {
            let X = (DMatrix::identity(n, n) * s - &Ac).lu().solve(&Bc)?;
            let G = &Cc * X;
            let diag: Vec<Complex<f64>> = design.channels().iter().map(|tf| tf.eval(s)).collect();
            let scale = diag.iter().map(|d| d.norm()).fold(0.0, f64::max);
            let worst = (0..G.nrows())
                .flat_map(|i| (0..G.ncols()).map(move |j| (i, j)))
                .map(|(i, j)| (G[(i, j)] - if i == j { diag[i] } else { Complex::new(0.0, 0.0) }).norm())
                .fold(0.0, f64::max)
                / scale;
            worst.is_finite().then_some((worst, s))
        })
        .max_by(|a, b| a.0.total_cmp(&b.0))
}

/// κ₂ above [`FRAGILE_CONDITION`], or NaN.
fn fragile(kappa: f64) -> bool {
    kappa.is_nan() || kappa > FRAGILE_CONDITION
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::{Scenario, PAPER_EXAMPLE};

    fn with_observer_text(poles: &str) -> String {
        PAPER_EXAMPLE.replace(
            "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619], [2.7762, -1.1783]]",
            &format!("observer_poles = {poles}"),
        )
    }

    fn with_observer(poles: &str) -> (Design, DesignSpec) {
        let s = Scenario::from_toml(&with_observer_text(poles)).unwrap();
        (s.design().unwrap(), s.design)
    }

    #[test]
    fn distinct_observer_poles_give_no_warning() {
        let (d, spec) = with_observer("[-2.0, -3.0, -4.0]");
        assert!(warnings(&d, &spec).is_empty(), "{:?}", warnings(&d, &spec));
    }

    #[test]
    fn a_defective_observer_is_reported_with_its_figures() {
        // A gain L with A − LC one 3 × 3 Jordan block at −5 (to rounding; rank C = 2, so no
        // placement gives it, place refuses three copies of −5): κ₂ is ∞.
        let text = PAPER_EXAMPLE.replace(
            "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619], [2.7762, -1.1783]]",
            "observer_gain = [[-56.982899739126566, -6.529670548858569], [62.29597186698538, 7.78904549447498], [33.05238335010353, 3.622075673762282]]",
        );
        let s = Scenario::from_toml(&text).unwrap();
        let w = warnings(&s.design().unwrap(), &s.design);
        let o = w.iter().find(|w| w.key == "design.observer_gain").expect("a warning on the given gain");
        assert_eq!(o.eigenvector_condition, f64::INFINITY, "{o:?}");
        assert!(
            o.message.contains("κ₂ = inf") && o.message.contains("give a gain whose A − LC has distinct eigenvalues"),
            "{}",
            o.message
        );
        assert!(!o.message.contains('?'), "{}", o.message);
    }

    /// B = [[1, 0.99], [1, 1]] with C = I (tests/data/ill-conditioned-b.toml; σ = [1, 1], so
    /// B* = C B = B): equilibrated it is [[γ, σ], [σ, γ]] with γ/σ = √(ad/bc) = 1/√0.99, so
    /// κ = (γ + σ)/(γ − σ) = 398 by hand (the least over diagonal scalings, 2λ − 1 + √((2λ−1)² − 1)
    /// with the RGA's λ = 100); the paper's B* gets no warning, nor does it in other states (one in
    /// a unit 50× another's had read 50) or with an input and an output in other units.
    #[test]
    fn an_ill_conditioned_decoupler_is_reported_with_its_condition_number() {
        let text = include_str!("../../tests/data/ill-conditioned-b.toml");
        let r = (1.0f64 / 0.99).sqrt();
        let kappa = (r + 1.0) / (r - 1.0);
        let s = Scenario::from_toml(text).unwrap();
        let d = s.design().unwrap();
        assert!((d.cond_B_star() / kappa - 1.0).abs() < 1e-9, "{} {kappa}", d.cond_B_star());
        let w = warnings(&d, &s.design);
        let b = w.iter().find(|w| w.key == "plant.B").expect("a warning on B*");
        assert!(
            b.message.starts_with(&format!(
                "plant.B: ill-conditioned decoupler: B* (Proposition 1) has scale-free condition number {kappa:.2e}"
            )),
            "{}",
            b.message
        );
        let paper = with_observer("[-2.0, -3.0, -4.0]").0.cond_B_star();
        assert!(paper < ILL_CONDITIONED_DECOUPLER);
        for t in [50.0, 1e-3, 1e3] {
            // x₂ → t·x₂: A → T A T⁻¹, B → T B, C → C T⁻¹, D → T D; L from the observer poles.
            let text = with_observer_text("[-2.0, -3.0, -4.0]")
                .replace(
                    "A = [[-3.2, -1.7, -3.0], [2.8, 1.3, 4.0], [0.3, 0.3, -0.5]]",
                    &format!(
                        "A = [[-3.2, {:e}, -3.0], [{:e}, 1.3, {:e}], [0.3, {:e}, -0.5]]",
                        -1.7 / t,
                        2.8 * t,
                        4.0 * t,
                        0.3 / t
                    ),
                )
                .replace("[2.0, -1.0], [1.0, 0.0]]", &format!("[{:e}, {:e}], [1.0, 0.0]]", 2.0 * t, -t))
                .replace(
                    "C = [[2.0, 2.0, 0.0], [2.0, 1.0, 2.0]]",
                    &format!("C = [[2.0, {:e}, 0.0], [2.0, {:e}, 2.0]]", 2.0 / t, 1.0 / t),
                )
                .replace("[2.0, 1.0], [3.0, 1.0]]", &format!("[{:e}, {:e}], [3.0, 1.0]]", 2.0 * t, t));
            let s = Scenario::from_toml(&text).unwrap();
            let c = s.design().unwrap().cond_B_star();
            assert!((c / paper - 1.0).abs() < 1e-9, "x₂ × {t}: {c} against {paper}");
        }
        // Input 2 in units 1e3 larger (B's second column / 1e3) and output 1 in units 1e-3 (C's
        // first row and g₁ × 1e3, Q's first row too): B* = diag(1e3, 1) B* diag(1, 1e-3).
        let text = with_observer_text("[-2.0, -3.0, -4.0]")
            .replace("B = [[-2.0, 1.0], [2.0, -1.0], [1.0, 0.0]]", "B = [[-2.0, 1e-3], [2.0, -1e-3], [1.0, 0.0]]")
            .replace("C = [[2.0, 2.0, 0.0], [2.0, 1.0, 2.0]]", "C = [[2e3, 2e3, 0.0], [2.0, 1.0, 2.0]]")
            .replace("Q = [[1.0, 2.0], [1.0, 0.0]]", "Q = [[1e3, 2e3], [1.0, 0.0]]")
            .replace("amplitude = 3.0, frequency = 2.0", "amplitude = 3e3, frequency = 2.0");
        let c = Scenario::from_toml(&text).unwrap().design().unwrap().cond_B_star();
        assert!((c / paper - 1.0).abs() < 1e-9, "units: {c} against {paper}");
    }

    #[test]
    fn three_observer_poles_at_one_value_with_rank_c_2_are_refused() {
        let text = PAPER_EXAMPLE.replace(
            "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619], [2.7762, -1.1783]]",
            "observer_poles = [-5.0, -5.0, -5.0]",
        );
        let e = Scenario::from_toml(&text).unwrap().design().unwrap_err().to_string();
        assert!(
            e.starts_with("design.observer_poles: pole -5.000000 is requested 3 times, more than rank(C) = 2"),
            "{e}"
        );
    }
}
