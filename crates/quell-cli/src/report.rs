//! The design, as text for people and as JSON for programs (`quell design [--json]`, `design.json`).

use std::fmt::Write;

use quell::fmt_eigenvalues;
use quell::nalgebra::{Complex, DMatrix};
use quell::Design;
use serde_json::{json, Value};

fn matrix(M: &DMatrix<f64>) -> Value {
    Value::Array(M.row_iter().map(|r| json!(r.iter().collect::<Vec<_>>())).collect())
}

fn eigs(e: &[Complex<f64>]) -> Value {
    Value::Array(e.iter().map(|z| json!([z.re, z.im])).collect())
}

/// The design as one JSON object: matrices as arrays of rows, eigenvalues as `[re, im]`.
pub fn design_json(d: &Design) -> Value {
    json!({
        "n": d.plant().n(),
        "m": d.plant().m(),
        "k": d.plant().k(),
        "q": d.q(),
        "sigma": d.sigma(),
        // The design model's input delays τ_i (the controller's u_d(t) = u(t − τ)) in its unit of
        // time: with K, F and a run's x̂ and u they give u_f (5) again.
        "delays": d.plant().delays,
        "time_unit": d.plant().time_unit.symbol(),
        "K": matrix(d.K()),
        "F": matrix(d.F()),
        "L": matrix(d.L()),
        "N": matrix(d.N()),
        "A_f": matrix(d.A_f()),
        "B_f": matrix(d.B_f()),
        "B_star": matrix(d.B_star()),
        "G_g": matrix(d.G_g()),
        "L_g": matrix(d.L_g()),
        "G_w": matrix(d.G_w()),
        "L_w": matrix(d.L_w()),
        "channels": d.channels().iter().map(|c| json!({
            "poles": eigs(&c.poles),
            "denominator": c.den,
            "q0": c.q0(),
        })).collect::<Vec<_>>(),
        "mu": d.mu(),
        "beta": d.beta(),
        "observer_eigenvalues": eigs(d.observer_eigenvalues()),
        "decoupled_eigenvalues": eigs(d.decoupled_eigenvalues()),
        // κ₂ of the closed-loop eigenvector matrices; null when defective (a Jordan block).
        "observer_eigenvector_condition": finite(d.observer_eigenvector_condition()),
        "decoupled_eigenvector_condition": finite(d.decoupled_eigenvector_condition()),
        "checks": d.checks(),
    })
}

/// `M` row by row, each entry right-aligned in one column width with a space before it: with five
/// decimals, or in scientific notation when an entry would lose its digits there (a magnitude
/// from 1e5, or one below 1e-3 that is not rounding next to the largest, |v| > 1e-9·max: SI-scale
/// plants).
fn fmt_matrix(out: &mut String, name: &str, M: &DMatrix<f64>) {
    let _ = writeln!(out, "{name} ({}×{}):", M.nrows(), M.ncols());
    let largest = M.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let scientific = M.iter().any(|v| v.abs() >= 1e5 || (v.abs() > 1e-9 * largest && v.abs() < 1e-3));
    let cell = |v: &f64| if scientific { format!("{v:.4e}") } else { format!("{v:.5}") };
    let width = M.iter().map(|v| cell(v).chars().count() + 1).max().unwrap_or(0).max(11);
    for r in M.row_iter() {
        let row: Vec<String> = r.iter().map(|v| format!("{:>width$}", cell(v))).collect();
        let _ = writeln!(out, "  [{} ]", row.join(""));
    }
}

/// G_ii(s) as `q0 / (s+a)(s+b)…`, its real numbers to 12 significant digits (a product of poles
/// −1.1 … printed as 2131.7999999999997).
fn tf(c: &quell::design::ChannelTf) -> String {
    let short = crate::run::short;
    let poly: Vec<String> = c
        .poles
        .iter()
        .map(|p| match p.im {
            0.0 if p.re <= 0.0 => format!("(s+{})", short(-p.re)),
            0.0 => format!("(s−{})", short(p.re)),
            _ => format!("(s−({:.4}{:+.4}i))", p.re, p.im),
        })
        .collect();
    format!("{} / {}", short(c.q0()), poly.join(""))
}

/// The design for people: the checks passed, σ, every gain and the eigenvalues achieved.
pub fn design_text(d: &Design) -> String {
    let p = d.plant();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "plant: n = {}, m = {}, k = {}, delays τ = {:?}, regressor q = {} (q_g = {}, q_ω = {})",
        p.n(),
        p.m(),
        p.k(),
        p.delays,
        d.q(),
        d.q_g(),
        d.q_w()
    );
    assumption_checks(&mut s, d);
    relative_degrees(&mut s, d);
    for (i, c) in d.channels().iter().enumerate() {
        let _ = writeln!(s, "  G_{0}{0}(s) = {1}   (μ_{0} = {2})", i + 1, tf(c), crate::run::short(d.mu()[i]));
    }
    let _ = writeln!(s, "  H(s) = 1/({} s + 1)\n", crate::run::short(d.beta()));
    for (name, M) in [
        ("K", d.K()),
        ("F", d.F()),
        ("L", d.L()),
        ("B*", d.B_star()),
        ("G_g", d.G_g()),
        ("L_g", d.L_g()),
        ("G_ω", d.G_w()),
        ("L_ω", d.L_w()),
        ("N", d.N()),
    ] {
        fmt_matrix(&mut s, name, M);
    }
    let _ = writeln!(s, "\neig(A − LC) = {}", fmt_eigenvalues(d.observer_eigenvalues()));
    let _ = writeln!(s, "eig(A − BK) = {}", fmt_eigenvalues(d.decoupled_eigenvalues()));
    let _ = writeln!(
        s,
        "eigenvector condition numbers κ₂(X): A − LC {}, A − BK {}",
        fmt_condition(d.observer_eigenvector_condition()),
        fmt_condition(d.decoupled_eigenvector_condition())
    );
    s
}

/// The paper's assumptions and the design's conditions, each with the figure that passed.
fn assumption_checks(s: &mut String, d: &Design) {
    let p = d.plant();
    let max_re = |e: &[Complex<f64>]| e.iter().map(|e| e.re).fold(f64::MIN, f64::max);
    let _ = writeln!(s, "\nassumption checks:");
    for (what, test) in [("(A, B) controllable:", d.controllability()), ("(A, C) observable:  ", d.observability())] {
        let _ = writeln!(s, "  ✓ {what} numerical rank {} of {} (tol {:.1e})", test.rank, p.n(), test.tol);
    }
    let _ = writeln!(
        s,
        "  ✓ decouplable: B* nonsingular, scale-free condition number {:.3e} (smallest singular value ≥ τ = {:.0e})",
        d.cond_B_star(),
        quell::design::TOL
    );
    let _ = writeln!(
        s,
        "  ✓ A_f = A − BK Hurwitz (stable zero dynamics): max Re λ = {:.5}",
        max_re(d.decoupled_eigenvalues())
    );
    let _ = writeln!(s, "  ✓ observer A − LC Hurwitz: max Re λ = {:.5}", max_re(d.observer_eigenvalues()));
    if p.k() == 0 {
        let _ =
            writeln!(s, "  ✓ no disturbance input (k = 0): the disturbance observer (20) has nothing to reconstruct");
    } else {
        let _ = writeln!(
            s,
            "  ✓ rank D = k = {} (N D = L_ω solvable), D with unit columns has condition number {:.3e}",
            p.k(),
            d.cond_D()
        );
    }
}

/// σ, and for each channel a σ_i given by the designer or decided close to τ.
fn relative_degrees(s: &mut String, d: &Design) {
    let (tol, cf) = (quell::design::TOL, quell::design::CLOSE_FACTOR);
    let _ = writeln!(
        s,
        "\nrelative degrees σ = {:?} (c_i A^(l−1) B ≠ 0 when its largest cosine ≥ τ = {tol:.0e})",
        d.sigma()
    );
    for (i, r) in d.relative_degree_decisions().iter().enumerate() {
        let measures: Vec<String> = r.deciding().iter().map(|m| format!("{m:.2e}")).collect();
        let l = r.deciding().len();
        if let Some(given) = r.given {
            let decided = r.decided.map_or("none".to_string(), |s| s.to_string());
            let _ = writeln!(
                s,
                "  σ_{} = {given} given by design.relative_degrees, not decided (eq. (7) decides {decided}); cosines for l = 1…{l} are [{}]",
                i + 1,
                measures.join(", "),
            );
        } else if r.is_close() {
            let _ = writeln!(
                s,
                "  ⚠ close decision for output {}: cosines for l = 1…{l} are [{}], within ×{cf} of τ; check plant.C[{i}] (its row) and plant.B, or give design.relative_degrees",
                i + 1,
                measures.join(", "),
            );
        }
    }
}

/// A condition number as JSON: null when infinite (JSON has no ∞).
fn finite(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

fn fmt_condition(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.3e}")
    } else {
        "∞ (defective: a Jordan block, fragile under model error)".to_string()
    }
}

/// The fragile-gain warnings ([`quell::design::warnings`]) added to a design's JSON as `warnings`.
pub fn with_warnings(mut design: Value, warnings: &[quell::design::DesignWarning]) -> Value {
    if let Value::Object(map) = &mut design {
        map.insert("warnings".into(), json!(warnings));
    }
    design
}

/// The fragile-gain warnings as lines of text (empty when there are none).
pub fn warnings_text(warnings: &[quell::design::DesignWarning]) -> String {
    warnings.iter().map(|w| format!("⚠ warning: {}\n", w.message)).collect()
}

/// The warning of a sample time coarse for the design ([`quell::sim::coarse_sample_warning`]),
/// naming the flag that sets it, and a sample time that divides `output_step` when the loop records
/// at one; empty otherwise.
pub fn sample_time_text(
    scenario: &quell::Scenario,
    design: &quell::Design,
    sample_time: f64,
    output_step: Option<f64>,
) -> String {
    quell::sim::coarse_sample_warning(design, [&scenario.reference, &scenario.disturbance], sample_time, output_step)
        .map(|w| format!("⚠ warning: {}\n", crate::in_flags(w)))
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_in_a_double_real_eigenvalue_is_not_printed() {
        let e = [Complex::new(-3.875268, 4.55e-15), Complex::new(-3.875268, -4.55e-15), Complex::new(-1.0, 2.0)];
        assert_eq!(fmt_eigenvalues(&e), "-3.875268, -3.875268, -1.000000+2.000000i");
        // A small imaginary part that is not rounding stays.
        assert_eq!(fmt_eigenvalues(&[Complex::new(-1.0, 1e-6)]), "-1.000000+1.000000e-6i");
    }

    #[test]
    fn matrix_entries_keep_their_digits_and_a_space_between_them() {
        // The paper's K as before; an SI-scale matrix (a maglev's A − LC, a ship's B*) in
        // scientific notation: fixed decimals ran −80.83741 and −1475.00000 together and showed
        // 2.5e-6 as 0.00000.
        let mut out = String::new();
        fmt_matrix(&mut out, "K", &DMatrix::from_row_slice(1, 3, &[9.26, 9.26, 7.1]));
        assert_eq!(out, "K (1×3):\n  [    9.26000    9.26000    7.10000 ]\n");
        // Rounding next to the largest entry (the paper's F) stays fixed: 1.8e-15 reads 0.00000.
        let mut out = String::new();
        fmt_matrix(&mut out, "F", &DMatrix::from_row_slice(1, 2, &[6.0, 1.7763568394002505e-15]));
        assert_eq!(out, "F (1×2):\n  [    6.00000    0.00000 ]\n");
        let mut out = String::new();
        fmt_matrix(&mut out, "M", &DMatrix::from_row_slice(2, 2, &[-80.83741, -1475.0, 2.5e-6, 0.0]));
        assert_eq!(out, "M (2×2):\n  [  -8.0837e1  -1.4750e3 ]\n  [  2.5000e-6   0.0000e0 ]\n");
    }
}
