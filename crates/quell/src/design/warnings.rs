//! Fragile gains: a design that passed every check but whose closed-loop poles a small model error
//! can move far (a placed pole repeated beyond the rank of C, a large eigenvector condition
//! number, eigenvalues off the requested poles). Reported as warnings, with the figures and what
//! to do, by `quell design`, `design.json`, `quell run` and Python (`warnings.warn`).

use nalgebra::Complex;
use serde::Serialize;

use super::{Design, DesignSpec, ObserverChoice};
use crate::linalg::{fmt_complex, numerical_rank};

/// κ₂ of the eigenvector matrix above which a closed loop counts as fragile: a relative model error
/// of 1e-8 could then move its poles by their own size.
pub const FRAGILE_CONDITION: f64 = 1e8;
/// Relative distance of eig(A − LC) from the requested poles above which the placement is reported.
pub const FRAGILE_ERROR: f64 = 1e-8;

/// One fragile part of a design.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DesignWarning {
    /// The scenario key whose choice is fragile.
    pub key: &'static str,
    /// Largest number of copies of one requested pole, and the rank it should not exceed.
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
    let (multiplicity, repeated, error) = match &spec.observer {
        ObserverChoice::Poles(poles) => {
            let (k, pole) = most_repeated(poles);
            (k, Some(pole), Some(matching_error(design.observer_eigenvalues(), poles)))
        }
        ObserverChoice::Gain(_) => (1, None, None),
    };
    if multiplicity > rank || fragile(kappa) || error.is_some_and(|e| e > FRAGILE_ERROR) {
        let why = match repeated.filter(|_| multiplicity > rank) {
            Some(pole) => format!(
                "pole {} is requested {multiplicity} times, more than rank C = {rank}, so A − LC has a Jordan block; ",
                fmt_complex(&pole)
            ),
            None => String::new(),
        };
        out.push(DesignWarning {
            key: "design.observer_poles",
            multiplicity,
            rank,
            verified_error: error,
            eigenvector_condition: kappa,
            message: format!(
                "design.observer_poles: fragile observer gain: {why}eig(A − LC) is off the requested poles by {} (relative) and its eigenvector condition number is κ₂ = {kappa:.2e}: a relative model error ε can move the observer poles by about κ₂·ε·‖A − LC‖; give distinct poles (at most {rank} copies of one; spread a repeated pole by ±10 %), not far faster than the plant",
                error.map_or("?".to_string(), |e| format!("{e:.1e}")),
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
    out
}

/// κ₂ above [`FRAGILE_CONDITION`], or NaN.
fn fragile(kappa: f64) -> bool {
    kappa.is_nan() || kappa > FRAGILE_CONDITION
}

/// The pole requested most often and its count (relative tolerance 1e-8).
fn most_repeated(poles: &[Complex<f64>]) -> (usize, Complex<f64>) {
    let same = |a: Complex<f64>, b: Complex<f64>| (a - b).norm() <= 1e-8 * a.norm().max(b.norm()).max(1.0);
    poles
        .iter()
        .map(|&p| (poles.iter().filter(|&&q| same(p, q)).count(), p))
        .max_by_key(|(k, _)| *k)
        .unwrap_or((0, Complex::new(0.0, 0.0)))
}

/// max |λ − p| / max(1, |p|) over a greedy nearest matching of eigenvalues to requested poles.
fn matching_error(eigs: &[Complex<f64>], poles: &[Complex<f64>]) -> f64 {
    let mut free = eigs.to_vec();
    let mut worst: f64 = 0.0;
    for &p in poles {
        let Some((j, d)) = free.iter().map(|&l| (l - p).norm()).enumerate().min_by(|a, b| a.1.total_cmp(&b.1)) else {
            return f64::INFINITY;
        };
        free.swap_remove(j);
        worst = worst.max(d / p.norm().max(1.0));
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::{Scenario, PAPER_EXAMPLE};

    fn with_observer(poles: &str) -> (Design, DesignSpec) {
        let text = PAPER_EXAMPLE.replace(
            "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619], [2.7762, -1.1783]]",
            &format!("observer_poles = {poles}"),
        );
        let s = Scenario::from_toml(&text).unwrap();
        (s.design().unwrap(), s.design)
    }

    #[test]
    fn distinct_observer_poles_give_no_warning() {
        let (d, spec) = with_observer("[-2.0, -3.0, -4.0]");
        assert!(warnings(&d, &spec).is_empty(), "{:?}", warnings(&d, &spec));
    }

    #[test]
    fn a_pole_repeated_beyond_rank_c_is_reported_with_its_figures() {
        // Three copies of −5 with rank C = 2: A − LC must have a Jordan block (at most 2
        // independent eigenvectors for one eigenvalue with 2 outputs), so κ₂ is ∞ or huge and the
        // computed eigenvalues scatter by ≈ ε^(1/2) or more around −5.
        let (d, spec) = with_observer("[-5.0, -5.0, -5.0]");
        let w = warnings(&d, &spec);
        let o = w.iter().find(|w| w.key == "design.observer_poles").expect("a warning on the observer");
        assert_eq!((o.multiplicity, o.rank), (3, 2));
        assert!(o.eigenvector_condition > FRAGILE_CONDITION, "{o:?}");
        assert!(
            o.message.contains("requested 3 times, more than rank C = 2") && o.message.contains("give distinct poles"),
            "{}",
            o.message
        );
    }
}
