//! MIMO pole placement: K such that eig(A − B K) equals the requested poles.
//!
//! * Multi-input (numerical rank(B) = r > 1): the robust eigenstructure-assignment method 0 of
//!   Kautsky, Nichols & Van Dooren (1985), "Robust pole assignment in linear state feedback",
//!   Int. J. Control 41(5) — the "KNV0" iteration also used by SciPy's `place_poles` and
//!   MATLAB's `place`. Eigenvectors are chosen one at a time in their admissible subspaces to
//!   make the eigenvector matrix X as well conditioned as possible (maximise |det X| over unit
//!   columns). Complex-conjugate pairs are updated as a unit (u ± i v) by the exact
//!   |det X|-maximising rank-2 step, in the manner of Tits & Yang (1996), "Globally convergent
//!   algorithms for robust pole assignment by state feedback", IEEE TAC 41(10). Repeated poles
//!   (at most r copies) get independent eigenvectors from the same admissible space.
//! * The fallback when KNV0's gain fails the check (seen for a pole repeated exactly r times on
//!   block-structured plants, tests/properties.rs): a seeded generic K₀ makes A − B K₀ cyclic,
//!   then single-input placement on (A − B K₀, B v) for a generic combination v of the inputs;
//!   K = K₀ + v k (Wonham 1967; Kailath, *Linear Systems*, §7.2). A repeated pole then has one
//!   Jordan block (of size ≤ r).
//! * Single-input (r = 1): Ackermann's formula evaluated in the orthogonal controller-Hessenberg
//!   (staircase) coordinates, where the controllability matrix is triangular and need not be
//!   inverted.
//!
//! A pole requested more than r times is refused ([`PlaceError::Multiplicity`], as SciPy's
//! `place_poles` and python-control's `place` refuse it): the closed loop would need a Jordan
//! block, whose eigenvalues no gain in floating point can be verified to meet.
//!
//! Every gain is verified a posteriori against A − B K as actually formed, and an error is
//! returned instead of an inaccurate K (see [`place`] for the rule): faer's eigenvalues where the
//! spectrum is well conditioned; eigenvalues refined with residuals in twice the working
//! precision (and the characteristic polynomial) where it is not, e.g. the observer of a
//! 12-state chain; the characteristic polynomial and faer's eigenvalues for the fallback.

use nalgebra::{Complex, ComplexField, DMatrix, DVector};
use thiserror::Error;

use super::assumptions::{balanced, columns_to, staircase, staircase_tol};
use crate::plant::{check_entries, check_shape, PlantError};

type C64 = Complex<f64>;

/// Relative tolerance under which two requested poles count as the same (repeated) pole and a
/// complex pole's conjugate partner is recognised.
const SAME_POLE_RTOL: f64 = 1e-8;
/// Relative tolerance of the final check, relative to max(1, |p|).
const VERIFY_RTOL: f64 = 1e-6;
/// Newton steps of [`refine`] per eigenvalue.
const REFINE_STEPS: usize = 12;
/// Largest n for which eigenvalues are refined ([`refined_error`], O(n⁴): about a second at n = 64).
const REFINE_MAX_N: usize = 64;
/// Maximum number of KNV0 sweeps.
const KNV_MAX_SWEEPS: usize = 60;
/// KNV0 sweeps between recomputations of X⁻¹ from X.
const KNV_REFRESH: usize = 4;
/// Residual factor up to which the admissible space from (A − λ I)⁻¹ B is kept ([`admissible`]).
const ADMISSIBLE_RTOL: f64 = 100.0;
/// Number of seeded (K₀, v) candidates tried by [`cyclic`].
const CYCLIC_TRIES: usize = 8;

/// Why no gain was returned.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PlaceError {
    #[error(
        "(A, B) is not controllable: numerical rank of the controllability staircase is {rank}, \
         need {n}; uncontrollable modes cannot be moved by feedback — check B or remove them"
    )]
    Uncontrollable { rank: usize, n: usize },
    /// B without one row per state of A (C given for B, say).
    #[error(
        "B: expected n = {n} rows (one per state of A) and a column per input, found {rows}×{cols}; \
         for an observer gain L, place the dual: L = place(Aᵀ, Cᵀ, poles)ᵀ"
    )]
    InputRows { n: usize, rows: usize, cols: usize },
    #[error("expected {expected} poles (one per state), found {found}; give exactly one pole per state")]
    WrongCount { expected: usize, found: usize },
    /// A pole requested more than rank(B) times (see [`place`]).
    #[error(
        "pole {} is requested {multiplicity} times, more than rank(B) = {rank} (rank C for observer \
         poles): the closed loop (A − BK; A − LC for observer poles) would need a Jordan block of \
         size ≥ {}, whose eigenvalues move by about δ^(1/size) under a change δ of that matrix, so \
         no gain can be verified to 1e-6; spread the \
         repeated poles (e.g. −1, −1.1, −1.2 for −1 three times) to at most {} of one pole, \
         as control.place requires",
        crate::linalg::fmt_complex(.pole),
        .multiplicity.div_ceil(*.rank),
        crate::settings::count(*.rank, "copy", "copies")
    )]
    Multiplicity { pole: Complex<f64>, multiplicity: usize, rank: usize },
    #[error(
        "pole {} has no complex-conjugate partner in the list; complex poles must come in \
         conjugate pairs so that K is real — add its conjugate",
        crate::linalg::fmt_complex(.pole)
    )]
    NotConjugateClosed { pole: Complex<f64> },
    #[error("pole {} is not a finite number; request finite poles", crate::linalg::fmt_complex(.pole))]
    NonFinite { pole: Complex<f64> },
    #[error("matrix {which} contains NaN or infinite entries; fix the model")]
    NonFiniteSystem { which: &'static str },
    /// A not square, B without A's rows, or an entry beyond [`MAX_ENTRY`](crate::plant::MAX_ENTRY).
    #[error("{0}")]
    Matrix(PlantError),
    #[error(
        "the computed gain would miss the requested poles: verified error {max_error:e} exceeds \
         1e-6 (relative to max(1, |p|)); the problem is too ill-conditioned for these poles — \
         move them apart or closer to the open-loop eigenvalues"
    )]
    Inaccurate { max_error: f64 },
    /// The stop flag of [`crate::cancel::with_stop`] was set during the placement.
    #[error("interrupted during pole placement")]
    Interrupted,
}

/// One requested real pole or conjugate pair (stored with positive imaginary part).
#[derive(Debug, Clone, Copy)]
enum Slot {
    Real(f64),
    Pair(C64),
}

/// Pole placement like MATLAB's and python-control's `place`: returns the real `m × n` gain `K`
/// with eig(A − B K) = `poles` (as a multiset).
///
/// `poles` must hold exactly n finite values, closed under complex conjugation, each repeated at
/// most r = rank(B) times, and (A, B) must be controllable. With r > 1: KNV method 0 (Kautsky,
/// Nichols & Van Dooren 1985), a diagonalisable closed loop with a well-conditioned eigenvector
/// matrix. For r = 1 (distinct poles): Ackermann's formula in orthogonal Hessenberg coordinates —
/// see the module docs.
///
/// A pole repeated more than r times is [`PlaceError::Multiplicity`], as in SciPy's
/// `place_poles` and python-control's `place`: its eigenvectors cannot be independent, so A − B K
/// would need a Jordan block of size j ≥ ⌈k/r⌉, whose eigenvalues a change δ of A − B K moves by
/// about δ^(1/j). The rounding of K alone is such a change (δ ≈ ε‖B‖‖K‖), so the closed loop
/// actually formed misses the poles by far more than 1e-6 (a 4-fold −1 with r = 2 on the
/// Wood–Berry column: gains ≈ 5e3, eigenvalues 7e-3 off), and the loop is fragile under any
/// model error; distinct poles near the repeated one give a verifiable, diagonalisable loop.
///
/// The result is checked on A − B K as formed, else [`PlaceError::Inaccurate`] is returned rather
/// than a wrong K. Verified error ≤ 1e-6, by the spectrum's conditioning:
///
/// | closed loop | verified error |
/// |---|---|
/// | κ₂(X)·nε‖A − BK‖_F ≤ 1e-7·max(1, min\|p\|) | faer's eigenvalues matched to the poles, max \|λ − p\|/max(1, \|p\|), plus that first-order bound on faer's own error |
/// | κ₂(X) larger (e.g. a 12-state chain observer) | the same, each eigenvalue first refined by Newton's method with residuals in twice the working precision; and the characteristic polynomial as below (alone, for a repeated pole: a semisimple cluster) |
/// | the cyclic fallback (X unknown; a repeated pole is a Jordan block of size j ≤ r) | characteristic polynomial vs ∏(s − p), coefficient-wise relative to ∏(s + max(1, \|p\|)), and faer's eigenvalues matched to the poles: what an eigenvalue solver shows of the formed loop, (ε‖A − BK‖)^(1/j) off at best |
///
/// How fragile the placed closed loop is: [`eigenvector_condition`].
///
/// An observer gain follows by duality: `L = place(Aᵀ, Cᵀ, p)ᵀ` gives eig(A − L C) = p.
///
/// A not square, B without A's rows, or an entry beyond [`MAX_ENTRY`](crate::plant::MAX_ENTRY) is [`PlaceError::Matrix`].
///
/// Where (A, B) as given fails (uncontrollable to the staircase's tolerance, or inaccurate), the
/// placement is made again on its balanced pair with B's columns at A's size, (D⁻¹AD, D⁻¹B S) (D
/// and S diagonal, of powers of two; K = S K′ D⁻¹, the closed loop formed exactly similar), as the
/// rank test takes it: states in units 1e7 apart had been refused, and balancing every plant would
/// move the gains of multi-input placements, which depend on the coordinates.
pub fn place(A: &DMatrix<f64>, B: &DMatrix<f64>, poles: &[Complex<f64>]) -> Result<DMatrix<f64>, PlaceError> {
    let as_given = placed(A, B, poles);
    let Err(e @ (PlaceError::Uncontrollable { .. } | PlaceError::Inaccurate { .. })) = as_given else {
        return as_given;
    };
    let (Ab, Bb, _, d) = balanced(A, B, &DMatrix::zeros(0, A.nrows()));
    // B's columns at A's size too, as the rank test takes them: a C in units 1e-15 had passed that
    // test and failed here.
    let (Bs, S) = columns_to(Ab.norm(), &Bb);
    if d.iter().chain(&S).all(|&x| x == 1.0) {
        return Err(e);
    }
    let Ok(K) = placed(&Ab, &Bs, poles) else { return Err(e) };
    // Ab − Bs K = Ab − Bb (S K): K_b = S K for (D⁻¹AD, D⁻¹B), and K_b D⁻¹ for (A, B).
    let diag = |v: Vec<f64>| DMatrix::from_diagonal(&nalgebra::DVector::from_vec(v));
    Ok(diag(S) * K * diag(d.iter().map(|x| 1.0 / x).collect()))
}

/// [`place`] on (A, B) as given.
fn placed(A: &DMatrix<f64>, B: &DMatrix<f64>, poles: &[Complex<f64>]) -> Result<DMatrix<f64>, PlaceError> {
    let slots = checked_slots(A, B, poles)?;
    let n = A.nrows();
    if n == 0 {
        return Ok(DMatrix::zeros(B.ncols(), 0));
    }
    let s = unit_time_scale(poles);
    // B to unit size too, by a power of two b: a slow plant's B is as small as its A (a supply
    // vessel in s × 1e5 had B ≈ 1e-16 beside A/s ≈ 1, and its rank test failed).
    let b = B.amax();
    let b = if s != 1.0 && b > 0.0 { 2f64.powi(-(b.log2().ceil() as i32)) } else { 1.0 };
    let (As, Bs) = (A / s, B * b);
    let within = |M: &DMatrix<f64>| M.iter().all(|x| x.abs() <= crate::plant::MAX_ENTRY);
    if s != 1.0 && within(&As) && within(&Bs) {
        // eig(A − BK) = p ⇔ eig(A/s − (bB)(K/(sb))) = p/s, exactly for powers of two s and b.
        let scaled: Vec<C64> = poles.iter().map(|p| p / s).collect();
        return placed(&As, &Bs, &scaled).map(|K| K * (s * b)).map_err(|e| e.rescaled(s));
    }

    let tol = staircase_tol(A, B);
    let st = staircase(A, B, tol);
    if st.rank < n {
        return Err(PlaceError::Uncontrollable { rank: st.rank, n });
    }
    let r = st.blocks[0]; // numerical rank of B, decided with the same tolerance

    let expanded = expand(&slots);
    if let Some((pole, multiplicity)) = most_repeated(&expanded).filter(|&(_, k)| k > r) {
        return Err(PlaceError::Multiplicity { pole, multiplicity, rank: r });
    }

    // Reduce B to full column rank: B ≈ U_r Σ_r V_rᵀ, place with B_r = U_r Σ_r, K = V_r K_r.
    let svd = B
        .clone()
        .try_svd(true, true, f64::EPSILON, 10_000)
        .ok_or(PlaceError::Inaccurate { max_error: f64::INFINITY })?;
    let (Some(U), Some(Vt)) = (svd.u.as_ref(), svd.v_t.as_ref()) else {
        return Err(PlaceError::Inaccurate { max_error: f64::INFINITY });
    };
    let mut Br = U.columns(0, r).into_owned();
    for j in 0..r {
        let s = svd.singular_values[j];
        Br.column_mut(j).scale_mut(s);
    }
    let Vr = Vt.rows(0, r).transpose();

    // Closed-loop eigenvectors in real form (columns u, v for a pair u ± i v): for r = 1 those of
    // the distinct poles, for r > 1 KNV0's choice.
    if r == 1 {
        let Kr = single_input(A, &Br, &slots)?;
        let X = eigenvectors_single_input(A, &Br, &slots)?;
        let K = Vr * Kr;
        verify(A, B, &K, &expanded, Some(&X))?;
        return Ok(K);
    }
    // KNV0, and if its gain fails the check, the cyclic single-input path; the better verified
    // gain is kept.
    let (Kr, X) = knv0(A, &Br, &slots)?;
    let K = &Vr * Kr;
    match verify(A, B, &K, &expanded, Some(&X)) {
        Ok(()) => Ok(K),
        Err(knv_error) => {
            let K = &Vr * cyclic(A, &Br, &slots, &expanded)?;
            verify(A, B, &K, &expanded, None).map(|()| K).map_err(|e| match (&e, &knv_error) {
                (PlaceError::Inaccurate { max_error: a }, PlaceError::Inaccurate { max_error: b }) if b < a => {
                    knv_error
                }
                _ => e,
            })
        }
    }
}

/// Every check of [`place`]'s arguments that needs no factorization; the poles as slots.
fn checked_slots(A: &DMatrix<f64>, B: &DMatrix<f64>, poles: &[C64]) -> Result<Vec<Slot>, PlaceError> {
    let n = A.nrows();
    let m = B.ncols();
    check_shape("A", A, n, n).map_err(PlaceError::Matrix)?;
    if B.nrows() != n {
        return Err(PlaceError::InputRows { n, rows: B.nrows(), cols: m });
    }
    if poles.len() != n {
        return Err(PlaceError::WrongCount { expected: n, found: poles.len() });
    }
    if let Some(&pole) = poles.iter().find(|p| !(p.re.is_finite() && p.im.is_finite())) {
        return Err(PlaceError::NonFinite { pole });
    }
    let slots = classify(poles)?;
    if A.iter().any(|x| !x.is_finite()) {
        return Err(PlaceError::NonFiniteSystem { which: "A" });
    }
    if B.iter().any(|x| !x.is_finite()) {
        return Err(PlaceError::NonFiniteSystem { which: "B" });
    }
    check_entries("A", A).and_then(|()| check_entries("B", B)).map_err(PlaceError::Matrix)?;
    Ok(slots)
}

/// The power of two s with max |p|/s in (½, 1] when every pole is slower than 1 (else 1): the
/// time scale [`place`] works in. Its tolerances are relative to max(1, |p|), so poles of a slow
/// plant in seconds (the Wood–Berry column with its time in s ×3·10⁷: −2e-8 … −4e-8) were all
/// "the same pole" and every check absolute; in units of s they are what they are in minutes.
fn unit_time_scale(poles: &[C64]) -> f64 {
    let fastest = poles.iter().map(|p| p.norm()).fold(0.0, f64::max);
    if fastest > 0.0 && fastest < 1.0 {
        2f64.powi(fastest.log2().ceil() as i32)
    } else {
        1.0
    }
}

impl PlaceError {
    /// The error of the problem at time scale `s` ([`unit_time_scale`]) in the caller's: its
    /// poles times s.
    fn rescaled(self, s: f64) -> PlaceError {
        match self {
            PlaceError::Multiplicity { pole, multiplicity, rank } => {
                PlaceError::Multiplicity { pole: pole * s, multiplicity, rank }
            }
            PlaceError::NotConjugateClosed { pole } => PlaceError::NotConjugateClosed { pole: pole * s },
            PlaceError::NonFinite { pole } => PlaceError::NonFinite { pole: pole * s },
            other => other,
        }
    }
}

/// Pair up complex poles with their conjugates; real poles are those with zero imaginary part.
fn classify(poles: &[C64]) -> Result<Vec<Slot>, PlaceError> {
    let mut used = vec![false; poles.len()];
    let mut slots = Vec::with_capacity(poles.len());
    for i in 0..poles.len() {
        if used[i] {
            continue;
        }
        used[i] = true;
        let p = poles[i];
        if p.im == 0.0 {
            slots.push(Slot::Real(p.re));
            continue;
        }
        let target = p.conj();
        let scale = p.norm().max(1.0);
        let partner = (0..poles.len())
            .filter(|&j| !used[j] && poles[j].im != 0.0 && poles[j].im.signum() != p.im.signum())
            .map(|j| (j, (poles[j] - target).norm()))
            .filter(|&(_, d)| d <= SAME_POLE_RTOL * scale)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        let Some((j, _)) = partner else {
            return Err(PlaceError::NotConjugateClosed { pole: p });
        };
        used[j] = true;
        let q = poles[j];
        let re = 0.5 * (p.re + q.re);
        let im = 0.5 * (p.im.abs() + q.im.abs());
        slots.push(Slot::Pair(C64::new(re, im)));
    }
    Ok(slots)
}

/// The n poles in column order of the eigenvector matrix (a pair gives λ, λ̄).
fn expand(slots: &[Slot]) -> Vec<C64> {
    let mut out = Vec::new();
    for s in slots {
        match *s {
            Slot::Real(l) => out.push(C64::new(l, 0.0)),
            Slot::Pair(l) => {
                out.push(l);
                out.push(l.conj());
            }
        }
    }
    out
}

/// Whether a and b count as one pole, relative to the larger or to `unit` ([`unit_time_scale`]).
fn same_pole(a: C64, b: C64, unit: f64) -> bool {
    (a - b).norm() <= SAME_POLE_RTOL * a.norm().max(b.norm()).max(unit)
}

/// The pole requested most often and how many times (`None` for no poles).
pub(crate) fn most_repeated(poles: &[C64]) -> Option<(C64, usize)> {
    // The first of equally repeated poles (λ before λ̄ of a pair): max_by_key keeps the last.
    let unit = unit_time_scale(poles);
    poles.iter().rev().map(|&p| (p, poles.iter().filter(|&&q| same_pole(p, q, unit)).count())).max_by_key(|&(_, k)| k)
}

/// The fallback placement when KNV0's gain fails the check. A generic feedback K₀ makes
/// A − B K₀ cyclic, and then (A − B K₀, B v) is controllable for a generic v, so the single-input
/// placement k of [`single_input`] on it gives A − B (K₀ + v k) with the requested characteristic
/// polynomial (the classical proof of pole assignability, e.g. Wonham 1967; Kailath, *Linear
/// Systems*, §7.2). K₀ and v come from fixed seeds (deterministic): [`CYCLIC_TRIES`] candidates,
/// the first with K₀ = 0; the one whose characteristic polynomial is closest to ∏(s − p) is
/// returned (verified by the caller).
fn cyclic(A: &DMatrix<f64>, B: &DMatrix<f64>, slots: &[Slot], poles: &[C64]) -> Result<DMatrix<f64>, PlaceError> {
    let (n, r) = (A.nrows(), B.ncols());
    let pole_scale = poles.iter().map(|p| p.norm()).fold(1.0, f64::max);
    let gain_scale = A.norm().max(pole_scale) / B.norm();
    let mut best: Option<(f64, DMatrix<f64>)> = None;
    for t in 0..CYCLIC_TRIES {
        crate::cancel::check().map_err(|_| PlaceError::Interrupted)?;
        let K0 = if t == 0 {
            DMatrix::zeros(r, n)
        } else {
            DMatrix::from_vec(r, n, generic_coeffs(1000 + 2 * t, r * n)) * gain_scale
        };
        let mut v = DMatrix::from_vec(r, 1, generic_coeffs(1001 + 2 * t, r));
        v /= v.norm();
        let A0 = A - B * &K0;
        let Ok(k) = single_input(&A0, &(B * &v), slots) else {
            continue;
        };
        let Kr = K0 + v * k;
        let error = char_poly_error(&(A - B * &Kr), poles);
        if error.is_finite() && best.as_ref().is_none_or(|(e, _)| error < *e) {
            best = Some((error, Kr));
        }
    }
    best.map(|(_, K)| K).ok_or(PlaceError::Inaccurate { max_error: f64::INFINITY })
}

/// Single-input placement for `b` (n × 1): Ackermann's formula k = e_nᵀ C⁻¹ p(A) evaluated in
/// the orthogonal Hessenberg coordinates of the staircase (Zᵀ A Z = H, Zᵀ b = β e₁), where the
/// controllability matrix C is upper triangular, so e_nᵀ C⁻¹ = e_nᵀ / (β ∏ h_{i+1,i}).
/// Ackermann's placement for one input (`b` a single column), as MATLAB's and python-control's
/// `acker`: any spectrum, repeated poles included (A − b K is then one Jordan block per repeated
/// pole, fragile: [`eigenvector_condition`] is ∞). Checked on the characteristic polynomial,
/// coefficient-wise relative to ∏(s + max(1, |p|)), to 1e-6; a textbook observer with every pole
/// at one value is such a case, which [`place`] refuses as `control.place` does.
pub fn acker(A: &DMatrix<f64>, b: &DMatrix<f64>, poles: &[Complex<f64>]) -> Result<DMatrix<f64>, PlaceError> {
    let n = A.nrows();
    check_shape("A", A, n, n).and_then(|()| check_shape("B", b, n, 1)).map_err(PlaceError::Matrix)?;
    if poles.len() != n {
        return Err(PlaceError::WrongCount { expected: n, found: poles.len() });
    }
    if let Some(&pole) = poles.iter().find(|p| !(p.re.is_finite() && p.im.is_finite())) {
        return Err(PlaceError::NonFinite { pole });
    }
    let slots = classify(poles)?;
    if A.iter().chain(b.iter()).any(|x| !x.is_finite()) {
        return Err(PlaceError::NonFiniteSystem { which: "A or B" });
    }
    check_entries("A", A).and_then(|()| check_entries("B", b)).map_err(PlaceError::Matrix)?;
    let K = single_input(A, b, &slots)?;
    let error = char_poly_error(&(A - b * &K), &expand(&slots));
    if error <= VERIFY_RTOL {
        Ok(K)
    } else {
        Err(PlaceError::Inaccurate { max_error: if error.is_finite() { error } else { f64::INFINITY } })
    }
}

fn single_input(A: &DMatrix<f64>, b: &DMatrix<f64>, slots: &[Slot]) -> Result<DMatrix<f64>, PlaceError> {
    let n = A.nrows();
    let st = staircase(A, b, staircase_tol(A, b));
    if st.rank < n {
        return Err(PlaceError::Uncontrollable { rank: st.rank, n });
    }
    let H = &st.At;
    // w = e_nᵀ p(H), built factor by factor; after j factors only the last j + 1 entries are
    // non-zero. Divide by one sub-diagonal entry per factor to keep the scale moderate.
    let mut w = DMatrix::<f64>::zeros(1, n);
    w[(0, n - 1)] = 1.0;
    let mut denom_left: Vec<f64> = (1..n).map(|i| H[(i, i - 1)]).collect();
    denom_left.push(st.Bt[(0, 0)]);
    let mut next_div = denom_left.into_iter();
    let mut divide = |w: &mut DMatrix<f64>| {
        if let Some(d) = next_div.next() {
            *w /= d;
        }
    };
    for s in slots {
        match *s {
            Slot::Real(l) => {
                let wh = &w * H;
                w = wh - &w * l;
                divide(&mut w);
            }
            Slot::Pair(l) => {
                let wh = &w * H;
                let whh = &wh * H;
                w = whh - wh * (2.0 * l.re) + &w * l.norm_sqr();
                divide(&mut w);
                divide(&mut w);
            }
        }
    }
    if w.iter().any(|x| !x.is_finite()) {
        return Err(PlaceError::Inaccurate { max_error: f64::INFINITY });
    }
    Ok(w * st.Z.transpose())
}

/// Deterministic, generic coefficients for initial eigenvector choices (a tiny LCG).
fn generic_coeffs(seed: usize, len: usize) -> Vec<f64> {
    let mut state = (seed as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(0x2545_F491_4F6C_DD1D);
    (0..len)
        .map(|_| {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        })
        .collect()
}

/// A = Q H Qᵀ (H upper Hessenberg), Qᵀ B, and B's orthonormal bases [U0 U1] (B = U0 Z_b), in
/// the scalar type of the poles: each admissible space then costs O(n² m), not an n × n SVD.
struct Reduced<T: ComplexField> {
    A: DMatrix<T>,
    Q: DMatrix<T>,
    H: DMatrix<T>,
    QtB: DMatrix<T>,
    U0: DMatrix<T>,
    U1: DMatrix<T>,
}

impl Reduced<f64> {
    fn new(A: &DMatrix<f64>, B: &DMatrix<f64>, U0: &DMatrix<f64>, U1: &DMatrix<f64>) -> Self {
        let (Q, H) = A.clone().hessenberg().unpack();
        let QtB = Q.transpose() * B;
        Reduced { A: A.clone(), Q, H, QtB, U0: U0.clone(), U1: U1.clone() }
    }

    fn complex(&self) -> Reduced<C64> {
        let c = |M: &DMatrix<f64>| M.map(|x| C64::new(x, 0.0));
        Reduced { A: c(&self.A), Q: c(&self.Q), H: c(&self.H), QtB: c(&self.QtB), U0: c(&self.U0), U1: c(&self.U1) }
    }
}

/// Orthonormal basis (n × m) of {x : U1ᵀ (A − λ I) x = 0} = {x : (A − λ I) x ∈ range B}: the
/// eigenvectors for λ that some feedback can assign (Kautsky, Nichols & Van Dooren 1985,
/// Theorem 3). For λ not an eigenvalue of A this is range (A − λ I)⁻¹ B, solved on the Hessenberg
/// form and orthonormalised, and kept when its residual ‖(I − U0 U0ᴴ)(A − λ I) S‖_F is at most
/// [`ADMISSIBLE_RTOL`]·n·ε·‖A − λ I‖_F; otherwise (λ at or near an eigenvalue of A) the null
/// space of U1ᵀ (A − λ I) from an SVD.
fn admissible<T>(r: &Reduced<T>, lambda: T) -> Result<DMatrix<T>, PlaceError>
where
    T: ComplexField<RealField = f64> + Copy,
{
    let n = r.A.nrows();
    let k = r.U1.ncols(); // n − m
    if k == 0 {
        return Ok(DMatrix::<T>::identity(n, n));
    }
    let size = r.A.norm() + lambda.modulus() * (n as f64).sqrt();
    let mut Y = r.QtB.clone();
    if hessenberg_solve(&r.H, lambda, &mut Y) {
        let S = &r.Q * Y.qr().q();
        let R = &r.A * &S - &S * lambda;
        let residual = (&R - &r.U0 * (r.U0.adjoint() * &R)).norm();
        if residual <= ADMISSIBLE_RTOL * n as f64 * f64::EPSILON * size && S.iter().all(|x| x.is_finite()) {
            return Ok(S);
        }
    }
    crate::cancel::check().map_err(|_| PlaceError::Interrupted)?;
    let Y = pencil_kernel(&r.H, &r.QtB, lambda).ok_or(PlaceError::Inaccurate { max_error: f64::INFINITY })?;
    Ok(&r.Q * Y.qr().q())
}

/// The y-parts of the kernel of [G, H − λ I] (n × (m + n), H upper Hessenberg, G = Qᵀ B): the
/// y with (H − λ I) y ∈ range G, for any λ, an eigenvalue of H too. For (H, G) controllable the
/// pencil has full row rank n for every λ, so its kernel has dimension m and a kernel vector
/// (u, y) is determined by y (y = 0 forces G u = 0, u = 0). Givens rotations from the right,
/// row by row from the last, reduce it to [0, R] with R upper triangular, O(n² m) (m + 1
/// rotations per row: G's columns and H's sub-diagonal); the first m columns of their product Z
/// span the kernel. `None` when R is singular (an uncontrollable λ) or not finite.
fn pencil_kernel<T>(H: &DMatrix<T>, G: &DMatrix<T>, lambda: T) -> Option<DMatrix<T>>
where
    T: ComplexField<RealField = f64> + Copy,
{
    let (n, m) = G.shape();
    let mut M = DMatrix::<T>::zeros(n, m + n);
    M.columns_mut(0, m).copy_from(G);
    M.columns_mut(m, n).copy_from(H);
    for i in 0..n {
        M[(i, m + i)] -= lambda;
    }
    // Each rotation: the column pair (p, t) and [[a, b], [c, d]] with col_p′ = a col_p + c col_t,
    // col_t′ = b col_p + d col_t.
    let mut rotations: Vec<(usize, usize, [T; 4])> = Vec::with_capacity(n * (m + 1));
    let size = M.norm();
    for i in (0..n).rev() {
        let t = m + i;
        let left = (0..m).chain((i > 0).then_some(t - 1));
        for p in left {
            let (xp, xt) = (M[(i, p)], M[(i, t)]);
            if xp.modulus() == 0.0 {
                continue;
            }
            let r = (xp.modulus_squared() + xt.modulus_squared()).sqrt();
            let inv = T::from_real(1.0 / r);
            let g = [xt * inv, xp.conjugate() * inv, -xp * inv, xt.conjugate() * inv];
            let (head, tail) = M.as_mut_slice().split_at_mut(t * n);
            let (cp, ct) = (&mut head[p * n..p * n + i + 1], &mut tail[..i + 1]);
            for (a, b) in cp.iter_mut().zip(ct.iter_mut()) {
                let (x, y) = (*a, *b);
                *a = g[0] * x + g[2] * y;
                *b = g[1] * x + g[3] * y;
            }
            M[(i, p)] = T::zero();
            rotations.push((p, t, g));
        }
        // A pivot at rounding level (or NaN) is a rank-deficient pencil.
        let pivot = M[(i, t)].modulus();
        if pivot.is_nan() || pivot <= f64::EPSILON * size {
            return None;
        }
    }
    // Z e_j = G₁(G₂(…(G_K e_j))): the rotations in reverse on [I_m; 0].
    let mut Z = DMatrix::<T>::zeros(m + n, m);
    Z.view_mut((0, 0), (m, m)).fill_with_identity();
    for &(p, t, g) in rotations.iter().rev() {
        for j in 0..m {
            let (x, y) = (Z[(p, j)], Z[(t, j)]);
            Z[(p, j)] = g[0] * x + g[1] * y;
            Z[(t, j)] = g[2] * x + g[3] * y;
        }
    }
    let Y = Z.rows(m, n).into_owned();
    Y.iter().all(|x| x.is_finite()).then_some(Y)
}

/// Solves (H − λ I) Y = R in place (R becomes Y) for upper Hessenberg H: Gaussian elimination with
/// partial pivoting between adjacent rows, O(n²) per column of R (the rows of H − λ I are kept as
/// the contiguous columns of its transpose). False when the elimination meets a zero pivot or a
/// non-finite value.
fn hessenberg_solve<T>(H: &DMatrix<T>, lambda: T, R: &mut DMatrix<T>) -> bool
where
    T: ComplexField<RealField = f64> + Copy,
{
    let n = H.nrows();
    let mut Ut = H.transpose(); // column j of Ut is row j of H
    for i in 0..n {
        Ut[(i, i)] -= lambda;
    }
    for j in 0..n.saturating_sub(1) {
        if Ut[(j, j + 1)].modulus() > Ut[(j, j)].modulus() {
            Ut.swap_columns(j, j + 1);
            R.swap_rows(j, j + 1);
        }
        let pivot = Ut[(j, j)];
        if pivot.modulus() == 0.0 {
            return false;
        }
        let f = Ut[(j, j + 1)] / pivot;
        let (row_j, mut row_next) = Ut.columns_range_pair_mut(j, j + 1);
        row_next.rows_range_mut(j..).axpy(-f, &row_j.rows_range(j..), T::one());
        row_next[j] = T::zero();
        for c in 0..R.ncols() {
            let v = R[(j, c)];
            R[(j + 1, c)] -= f * v;
        }
    }
    // Ut is now lower triangular: (Ut)ᵀ Y = R.
    Ut.tr_solve_lower_triangular_mut(R) && R.iter().all(|x| x.is_finite())
}

/// Admissible space of one slot.
enum Space {
    Real(DMatrix<f64>),
    Pair(DMatrix<C64>),
}

/// The admissible space of every slot ([`admissible`]) and its column in X.
fn spaces(
    A: &DMatrix<f64>,
    B: &DMatrix<f64>,
    U0: &DMatrix<f64>,
    U1: &DMatrix<f64>,
    slots: &[Slot],
) -> Result<Vec<(Space, usize)>, PlaceError> {
    let real = Reduced::new(A, B, U0, U1);
    let complex = slots.iter().any(|s| matches!(s, Slot::Pair(_))).then(|| real.complex());
    let mut out = Vec::with_capacity(slots.len());
    let mut c = 0;
    for s in slots {
        match (*s, &complex) {
            (Slot::Pair(l), Some(cr)) => {
                out.push((Space::Pair(admissible(cr, l)?), c));
                c += 2;
            }
            (Slot::Real(l), _) | (Slot::Pair(C64 { re: l, .. }), None) => {
                out.push((Space::Real(admissible(&real, l)?), c));
                c += 1;
            }
        }
    }
    Ok(out)
}

/// The eigenvector matrix X of KNV0 (real form) with X⁻¹, kept by rank-k updates, and log |det X|.
struct Basis {
    X: DMatrix<f64>,
    inv: DMatrix<f64>,
    log_det: f64,
}

impl Basis {
    fn new(X: DMatrix<f64>) -> Option<Basis> {
        let lu = X.clone().lu();
        let log_det = lu.u().diagonal().iter().map(|d| d.abs().ln()).sum();
        let inv = lu.try_inverse()?;
        Some(Basis { X, inv, log_det })
    }

    /// Orthonormal basis (n × k) of the complement of every column but c … c + k − 1: rows
    /// c … c + k − 1 of X⁻¹ are orthogonal to the other columns (X⁻¹ X = I), orthonormalised.
    fn normal(&self, c: usize, k: usize) -> DMatrix<f64> {
        self.inv.rows(c, k).transpose().qr().q()
    }

    /// Columns c … c + k − 1 of X replaced by `new` (n × k) and X⁻¹ by the Sherman–Morrison–Woodbury
    /// formula, O(n² k): with P = X⁻¹ new and S its rows c … c + k − 1 (det S = det X′ / det X),
    /// X′⁻¹ = X⁻¹ − (P − E) S⁻¹ Eᵀ X⁻¹, E = [e_c … e_{c+k−1}]. Nothing changes when S is singular.
    fn replace(&mut self, c: usize, new: &DMatrix<f64>) {
        let k = new.ncols();
        let mut P = &self.inv * new;
        let S = P.rows(c, k).into_owned();
        let det = S.determinant();
        let Some(S_inv) = S.try_inverse().filter(|_| det != 0.0 && det.is_finite()) else {
            return;
        };
        for j in 0..k {
            P[(c + j, j)] -= 1.0;
        }
        let rows = self.inv.rows(c, k).into_owned();
        self.inv.gemm(-1.0, &(P * S_inv), &rows, 1.0);
        self.X.columns_mut(c, k).copy_from(new);
        self.log_det += det.abs().ln();
    }
}

/// KNV method 0 for B of full column rank m > 1: the eigenvector matrix X from
/// [`well_conditioned_eigenvectors`], then the gain that gives A − B K = X Λ X⁻¹ ([`gain`]).
fn knv0(A: &DMatrix<f64>, B: &DMatrix<f64>, slots: &[Slot]) -> Result<(DMatrix<f64>, DMatrix<f64>), PlaceError> {
    let inputs = InputSplit::new(B);
    let spaces = spaces(A, B, &inputs.U0, &inputs.U1, slots)?;
    let X = well_conditioned_eigenvectors(A.nrows(), B.ncols(), &spaces)?;
    let K = gain(A, &inputs, &X, slots)?;
    Ok((K, X))
}

/// The full QR decomposition of B (n × m, full column rank) that KNV's conditions are written in:
/// B = [U0 U1] [Z; 0], U0 (n × m) spanning range B, U1 (n × (n − m)) its orthogonal complement,
/// Z (m × m) upper triangular and invertible.
struct InputSplit {
    U0: DMatrix<f64>,
    U1: DMatrix<f64>,
    Z: DMatrix<f64>,
}

impl InputSplit {
    fn new(B: &DMatrix<f64>) -> InputSplit {
        let (n, m) = B.shape();
        let mut padded = DMatrix::<f64>::zeros(n, m + n);
        padded.view_mut((0, 0), (n, m)).copy_from(B);
        let qr = padded.qr();
        let Q = qr.q();
        InputSplit {
            U0: Q.columns(0, m).into_owned(),
            U1: Q.columns(m, n - m).into_owned(),
            Z: qr.r().view((0, 0), (m, m)).into_owned(),
        }
    }
}

/// The KNV0 sweeps: X = [… x … u v …] in real form (a pair's eigenvector is u + i v), each column
/// in its slot's admissible space, made as well conditioned as possible by maximising |det X| over
/// unit columns. A real pole's vector is replaced by the admissible unit vector closest to the
/// normal of the other columns (KNV0). A pair's vector is replaced by the admissible unit vector
/// u + i v that maximises |det X| with the other columns fixed — a rank-2 update in the manner of
/// Tits & Yang (1996): with W the 2-dimensional complement of the other columns and
/// z = Wᵀ (u + i v), det Wᵀ[u v] = Im(z̄₁ z₂), a Hermitian quadratic form in the coefficients.
/// The normals come from X⁻¹, updated with each replaced column ([`Basis`]), so a sweep costs
/// O(n³) rather than one QR of X per column. At most [`KNV_MAX_SWEEPS`], until log |det X| settles.
fn well_conditioned_eigenvectors(n: usize, m: usize, spaces: &[(Space, usize)]) -> Result<DMatrix<f64>, PlaceError> {
    let fail = PlaceError::Inaccurate { max_error: f64::INFINITY };
    let mut basis = Basis::new(initial_vectors(n, m, spaces)).ok_or(fail.clone())?;
    for sweep in 0..KNV_MAX_SWEEPS {
        crate::cancel::check().map_err(|_| PlaceError::Interrupted)?;
        let old = basis.log_det;
        for (space, c) in spaces {
            knv_step(&mut basis, space, *c);
        }
        if sweep % KNV_REFRESH == KNV_REFRESH - 1 {
            // Rounding accumulates in the updated X⁻¹: start again from X.
            basis = Basis::new(basis.X).ok_or(fail.clone())?;
        }
        if (basis.log_det - old).abs() <= 1e-10 {
            break;
        }
    }
    Ok(basis.X)
}

/// The gain with A − B K = M = X Λ X⁻¹ (Λ in real form, [`real_form`]): since every column of X is
/// admissible, U1ᵀ (A − M) = 0, so B K = A − M is solvable and K = Z⁻¹ U0ᵀ (A − M).
fn gain(A: &DMatrix<f64>, inputs: &InputSplit, X: &DMatrix<f64>, slots: &[Slot]) -> Result<DMatrix<f64>, PlaceError> {
    let fail = PlaceError::Inaccurate { max_error: f64::INFINITY };
    let XL = X * real_form(slots);
    // M = XL X⁻¹  ⇔  Xᵀ Mᵀ = XLᵀ.
    let Mt = X.transpose().lu().solve(&XL.transpose()).ok_or(fail.clone())?;
    let rhs = inputs.U0.transpose() * (A - Mt.transpose());
    inputs.Z.solve_upper_triangular(&rhs).ok_or(fail)
}

/// Generic unit vectors from each admissible space, the starting X of [`well_conditioned_eigenvectors`].
fn initial_vectors(n: usize, m: usize, spaces: &[(Space, usize)]) -> DMatrix<f64> {
    let mut X = DMatrix::<f64>::zeros(n, n);
    for (i, (space, c)) in spaces.iter().enumerate() {
        let re = DMatrix::from_vec(m, 1, generic_coeffs(2 * i, m));
        match space {
            Space::Real(S) => {
                let x = S * re;
                X.set_column(*c, &(&x / x.norm()).column(0));
            }
            Space::Pair(S) => {
                let im = DMatrix::from_vec(m, 1, generic_coeffs(2 * i + 1, m));
                let x = (S * re.zip_map(&im, C64::new)).column(0).into_owned();
                set_pair(&mut X, *c, &(&x / C64::new(x.norm(), 0.0)));
            }
        }
    }
    X
}

/// One KNV0 update of the vector(s) at column c (see [`well_conditioned_eigenvectors`]).
fn knv_step(basis: &mut Basis, space: &Space, c: usize) {
    match space {
        Space::Real(S) => {
            let w = basis.normal(c, 1);
            let x = S * (S.transpose() * w);
            let nrm = x.norm();
            if nrm > 1e-12 {
                basis.replace(c, &(x / nrm));
            }
        }
        Space::Pair(S) => {
            let W = basis.normal(c, 2).map(|x| C64::new(x, 0.0));
            let G = W.transpose() * S; // 2 × m
            let H = G.row(0).adjoint() * G.row(1);
            let Hh = (&H - H.adjoint()) * C64::new(0.0, -0.5);
            let Some(eig) = Hh.try_symmetric_eigen(f64::EPSILON, 10_000) else {
                return;
            };
            let (best, val) = eig
                .eigenvalues
                .iter()
                .enumerate()
                .map(|(j, v)| (j, v.abs()))
                .fold((0, -1.0), |acc, e| if e.1 > acc.1 { e } else { acc });
            if val > 1e-14 {
                let x = S * eig.eigenvectors.column(best);
                let x = &x / C64::new(x.norm(), 0.0);
                let mut new = DMatrix::<f64>::zeros(x.len(), 2);
                set_pair(&mut new, 0, &x);
                basis.replace(c, &new);
            }
        }
    }
}

/// Λ in real block-diagonal form, in the column order of the slots: λ for a real pole,
/// [[a, b], [−b, a]] for a pair a ± i b (A x = λ x with x = u + i v ⇔
/// A [u v] = [u v] [[a, b], [−b, a]]). Λ is normal.
fn real_form(slots: &[Slot]) -> DMatrix<f64> {
    let n = slots.iter().map(|s| if let Slot::Pair(_) = s { 2 } else { 1 }).sum();
    let mut L = DMatrix::<f64>::zeros(n, n);
    let mut c = 0;
    for s in slots {
        match *s {
            Slot::Real(l) => {
                L[(c, c)] = l;
                c += 1;
            }
            Slot::Pair(l) => {
                L[(c, c)] = l.re;
                L[(c, c + 1)] = l.im;
                L[(c + 1, c)] = -l.im;
                L[(c + 1, c + 1)] = l.re;
                c += 2;
            }
        }
    }
    L
}

/// Closed-loop eigenvectors of a single-input placement with distinct poles, in real form: each
/// admissible space {x : U1ᵀ (A − λ I) x = 0} is one-dimensional.
fn eigenvectors_single_input(A: &DMatrix<f64>, b: &DMatrix<f64>, slots: &[Slot]) -> Result<DMatrix<f64>, PlaceError> {
    let n = A.nrows();
    let inputs = InputSplit::new(b);
    let mut X = DMatrix::<f64>::zeros(n, n);
    for (space, c) in spaces(A, b, &inputs.U0, &inputs.U1, slots)? {
        match space {
            Space::Real(S) => X.set_column(c, &S.column(0)),
            Space::Pair(S) => set_pair(&mut X, c, &S.column(0).into_owned()),
        }
    }
    Ok(X)
}

/// Store the pair's eigenvector u + i v as columns c (u) and c + 1 (v).
fn set_pair(X: &mut DMatrix<f64>, c: usize, x: &DVector<C64>) {
    X.set_column(c, &x.map(|z| z.re));
    X.set_column(c + 1, &x.map(|z| z.im));
}

/// The a-posteriori check of every gain [`place`] returns, on M = A − B K as actually formed. The
/// verified error must be ≤ [`VERIFY_RTOL`]; the test depends on how well conditioned the
/// closed-loop spectrum is:
///
/// * Well conditioned (X the closed loop's eigenvectors — KNV0's, or single input with distinct
///   poles — and floor = κ₂(X)·nε‖M‖_F / max(1, min|p|) ≤ [`VERIFY_RTOL`]/10):
///   the eigenvalues of M from faer ([`crate::linalg::eigenvalues`]) matched to the requested
///   multiset, error = the largest |λ − p| / max(1, |p|) + floor (the first-order Bauer–Fike
///   bound on faer's own error).
/// * Ill conditioned (X known, floor above [`VERIFY_RTOL`]/10; e.g. the observer of a 12-state
///   chain, κ₂(X) ≈ 1e15, where faer's eigenvalues are off by ≈ 1.4e-7 and Bauer–Fike with κ₂(X)
///   by far more): each matched eigenvalue is refined by Newton's method with residuals in twice
///   the working precision ([`refined_error`]), which recovers it to about the accuracy the formed
///   M defines it (where compared, to 16 digits of its 60-digit value; every one of the 111 such
///   cases the tests accept is within 1e-6 by 60-digit eigenvalues, `scripts/mp_eigenvalues.py`);
///   error = the larger of that and the characteristic-polynomial error: that of M (orthogonal
///   Hessenberg reduction, then the Hessenberg determinant recursion) against ∏(s − p),
///   coefficient-wise relative to ∏(s + max(1, |p|)). A repeated pole (a semisimple cluster) in
///   this class is judged by the characteristic polynomial alone. Above n = [`REFINE_MAX_N`] the
///   refinement (O(n⁴)) is not attempted and the first-order bound decides.
/// * The cyclic fallback (X unknown; a repeated pole is a Jordan block of size j ≤ r, whose
///   eigenvalues are only computable to ≈ (ε‖M‖)^(1/j)): the larger of the characteristic-polynomial
///   error and faer's eigenvalues matched to the poles (no bound added), so that no eigenvalue
///   solver shows the formed loop farther than 1e-6 (relative) from the poles.
fn verify(
    A: &DMatrix<f64>,
    B: &DMatrix<f64>,
    K: &DMatrix<f64>,
    poles: &[C64],
    X: Option<&DMatrix<f64>>,
) -> Result<(), PlaceError> {
    let error = verified_error(A, B, K, poles, X);
    if error <= VERIFY_RTOL {
        Ok(())
    } else {
        Err(PlaceError::Inaccurate { max_error: if error.is_finite() { error } else { f64::INFINITY } })
    }
}

/// The error [`verify`] compares with [`VERIFY_RTOL`] (∞ when A − B K is not finite).
fn verified_error(
    A: &DMatrix<f64>,
    B: &DMatrix<f64>,
    K: &DMatrix<f64>,
    poles: &[C64],
    X: Option<&DMatrix<f64>>,
) -> f64 {
    let M = A - B * K;
    if M.iter().any(|x| !x.is_finite()) {
        return f64::INFINITY;
    }
    let coefficients = || char_poly_error(&M, poles);
    let Some(X) = X else {
        let Ok(eigs) = crate::linalg::eigenvalues(&M) else {
            return f64::INFINITY;
        };
        return coefficients().max(matching_error(&eigs, poles));
    };
    let scale = poles.iter().map(|p| p.norm()).fold(f64::INFINITY, f64::min).max(1.0);
    let floor = crate::linalg::cond(X) * M.nrows() as f64 * f64::EPSILON * M.norm() / scale;
    let well_conditioned = floor <= 0.1 * VERIFY_RTOL;
    if !well_conditioned && most_repeated(poles).is_some_and(|(_, k)| k > 1) {
        // A repeated pole is an ill-conditioned (semisimple) multiple eigenvalue: judged as a
        // cluster by the characteristic polynomial.
        return coefficients();
    }
    let Ok(eigs) = crate::linalg::eigenvalues(&M) else {
        return f64::INFINITY;
    };
    if well_conditioned || M.nrows() > REFINE_MAX_N {
        // Beyond REFINE_MAX_N the O(n⁴) refinement is not attempted: the first-order bound stands.
        matching_error(&eigs, poles) + floor
    } else {
        refined_error(&M, eigs, poles).max(coefficients())
    }
}

/// [`matching_error`] with each matched eigenvalue of M refined to (nearly) the accuracy the
/// formed M defines it, for ill-conditioned spectra where a QR-computed eigenvalue is off by
/// ≈ κ·ε‖M‖ (a factor 2–10 either side of the truth near 1e-6, checked against 60-digit
/// eigenvalues). Each eigenvalue λ of the balanced M_b = D⁻¹ M D (exact,
/// [`crate::linalg::balance`]) that faer matched to a pole is refined by Newton's method on
/// (M_b − λ I) v = 0, v_k = 1 (Dongarra, Moler & Wilkinson 1983, "Improving the accuracy of
/// computed eigenvalues and eigenvectors", SIAM J. Numer. Anal. 20), with the residual in twice
/// the working precision ([`residual`]). Error: the largest (|λ − p| + |last step|) / max(1, |p|);
/// ∞ when a refinement does not converge or two poles end at the same eigenvalue. `eigs`: M's
/// eigenvalues ([`crate::linalg::eigenvalues`]).
fn refined_error(M: &DMatrix<f64>, mut free: Vec<C64>, poles: &[C64]) -> f64 {
    let n = M.nrows();
    let Mb = crate::linalg::balance(M);
    let mut refined: Vec<(C64, f64)> = Vec::with_capacity(n);
    let mut worst: f64 = 0.0;
    for &p in poles {
        let Some((lambda, step)) = take_nearest(&mut free, p).and_then(|l| refine(&Mb, l)) else {
            return f64::INFINITY;
        };
        if coincides(&refined, lambda, step) {
            return f64::INFINITY;
        }
        refined.push((lambda, step));
        worst = worst.max(((lambda - p).norm() + step) / p.norm().max(1.0));
    }
    if worst.is_nan() {
        f64::INFINITY
    } else {
        worst
    }
}

/// True when every eigenvalue of M (`eigs`, computed by [`crate::linalg::eigenvalues`]), refined
/// as in [`refined_error`], converges to a distinct value λ with Re λ + |last step| < 0: M is
/// Hurwitz to the accuracy with which the formed M defines its eigenvalues, whatever ‖M‖. False
/// when a refinement does not converge (e.g. a Jordan block), two end at the same eigenvalue, or
/// n > [`REFINE_MAX_N`].
pub(crate) fn refined_left_half_plane(M: &DMatrix<f64>, eigs: &[C64]) -> bool {
    if M.nrows() > REFINE_MAX_N {
        return false;
    }
    let Mb = crate::linalg::balance(M);
    let mut refined: Vec<(C64, f64)> = Vec::with_capacity(eigs.len());
    for &l in eigs {
        let Some((lambda, step)) = refine(&Mb, l) else {
            return false;
        };
        if coincides(&refined, lambda, step) || lambda.re + step >= 0.0 {
            return false;
        }
        refined.push((lambda, step));
    }
    true
}

/// True when λ (refined, last step `step`) is, within the steps, one already in `refined`.
fn coincides(refined: &[(C64, f64)], lambda: C64, step: f64) -> bool {
    refined.iter().any(|&(mu, s)| (mu - lambda).norm() <= 2.0 * (s + step) + 4.0 * f64::EPSILON * mu.norm())
}

/// Newton's method for the eigenpair of M near λ₀ (see [`refined_error`]): returns the refined λ
/// and the size of its last step, or `None` if it did not converge in [`REFINE_STEPS`].
fn refine(M: &DMatrix<f64>, lambda0: C64) -> Option<(C64, f64)> {
    let n = M.nrows();
    let Mc = M.map(|x| C64::new(x, 0.0));
    let shifted = |l: C64| &Mc - DMatrix::<C64>::identity(n, n) * l;
    let svd = shifted(lambda0).try_svd(false, true, f64::EPSILON, 10_000)?;
    let mut v: DVector<C64> = svd.v_t?.row(n - 1).adjoint();
    let k = v.icamax();
    v /= v[k];
    let mut lambda = lambda0;
    for _ in 0..REFINE_STEPS {
        let r = residual(M, lambda, &v);
        let mut J = DMatrix::<C64>::zeros(n + 1, n + 1);
        J.view_mut((0, 0), (n, n)).copy_from(&shifted(lambda));
        J.view_mut((0, n), (n, 1)).copy_from(&(-&v));
        J[(n, k)] = C64::new(1.0, 0.0);
        let mut rhs = DVector::<C64>::zeros(n + 1);
        rhs.rows_mut(0, n).copy_from(&(-r));
        let d = J.lu().solve(&rhs)?;
        v += d.rows(0, n);
        v[k] = C64::new(1.0, 0.0);
        lambda += d[n];
        let step = d[n].norm();
        if !(lambda.re.is_finite() && lambda.im.is_finite()) {
            return None;
        }
        if step <= 4.0 * f64::EPSILON * lambda.norm().max(f64::MIN_POSITIVE) {
            return Some((lambda, step));
        }
    }
    None
}

/// r = (M − λ I) v with every dot product in compensated arithmetic (Ogita, Rump & Oishi 2005,
/// Dot2: as if computed in twice the working precision, then rounded).
fn residual(M: &DMatrix<f64>, lambda: C64, v: &DVector<C64>) -> DVector<C64> {
    let n = M.nrows();
    let dot2 = |terms: &mut dyn Iterator<Item = (f64, f64)>| {
        let (mut s, mut c) = (0.0f64, 0.0f64);
        for (a, b) in terms {
            let h = a * b;
            let e = a.mul_add(b, -h); // a·b = h + e exactly
            let t = s + h;
            let z = t - s;
            c += (s - (t - z)) + (h - z) + e; // s + h = t + that exactly
            s = t;
        }
        s + c
    };
    DVector::from_fn(n, |i, _| {
        let (vr, vi) = (v[i].re, v[i].im);
        // (λ v)_i = (λ.re v.re − λ.im v.im) + i (λ.re v.im + λ.im v.re)
        let re_shift = [(-lambda.re, vr), (lambda.im, vi)];
        let im_shift = [(-lambda.re, vi), (-lambda.im, vr)];
        let re = dot2(&mut (0..n).map(|j| (M[(i, j)], v[j].re)).chain(re_shift));
        let im = dot2(&mut (0..n).map(|j| (M[(i, j)], v[j].im)).chain(im_shift));
        C64::new(re, im)
    })
}

/// Largest |λ − p| / max(s, |p|), s the poles' [`unit_time_scale`] (1 within [`place`]), after
/// matching each requested pole p, in order, to the nearest eigenvalue not yet matched (a greedy
/// matching: it can only overstate the error).
pub(crate) fn matching_error(eigs: &[C64], poles: &[C64]) -> f64 {
    let mut free: Vec<C64> = eigs.to_vec();
    let (mut worst, unit): (f64, f64) = (0.0, unit_time_scale(poles));
    for &p in poles {
        let Some(l) = take_nearest(&mut free, p) else {
            return f64::INFINITY;
        };
        worst = worst.max((l - p).norm() / p.norm().max(unit));
    }
    worst
}

/// Removes the eigenvalue nearest p from `free` and returns it (`None` when `free` is empty).
fn take_nearest(free: &mut Vec<C64>, p: C64) -> Option<C64> {
    let (j, _) = free.iter().map(|&l| (l - p).norm()).enumerate().min_by(|a, b| a.1.total_cmp(&b.1))?;
    Some(free.swap_remove(j))
}

/// The coefficient error of [`verify`]'s ill-conditioned test for M = A − B K (∞ if M is not
/// finite).
fn char_poly_error(M: &DMatrix<f64>, poles: &[C64]) -> f64 {
    if M.iter().any(|x| !x.is_finite()) {
        return f64::INFINITY;
    }
    let got = hessenberg_char_poly(M);
    let want = poly_from_roots(poles);
    let scale = poly_from_roots(&poles.iter().map(|p| C64::new(-p.norm().max(1.0), 0.0)).collect::<Vec<_>>());
    let e = (0..got.len()).map(|k| (got[k] - want[k]).abs() / scale[k]).fold(0.0, f64::max);
    if e.is_finite() {
        e
    } else {
        f64::INFINITY
    }
}

/// Coefficients of ∏(s − r), lowest degree first, with the leading 1.
fn poly_from_roots(roots: &[C64]) -> Vec<f64> {
    let mut c = crate::linalg::poly_from_roots(roots);
    c.push(1.0);
    c
}

/// Characteristic polynomial of M (lowest degree first): orthogonal Hessenberg reduction, then
/// the recurrence over leading principal submatrices of the Hessenberg matrix H:
/// p_k(s) = (s − h_kk) p_{k−1}(s) − Σ_{i<k} h_ik (h_{i+1,i} ⋯ h_{k,k−1}) p_{i−1}(s).
fn hessenberg_char_poly(M: &DMatrix<f64>) -> Vec<f64> {
    let n = M.nrows();
    let H = M.clone().hessenberg().h();
    let mut p: Vec<Vec<f64>> = vec![vec![1.0]];
    for k in 0..n {
        // (s − h_kk) p_{k−1}
        let prev = &p[k];
        let mut next = vec![0.0; k + 2];
        for (j, &c) in prev.iter().enumerate() {
            next[j + 1] += c;
            next[j] -= H[(k, k)] * c;
        }
        let mut prod = 1.0;
        for i in (0..k).rev() {
            prod *= H[(i + 1, i)];
            let f = H[(i, k)] * prod;
            for (j, &c) in p[i].iter().enumerate() {
                next[j] -= f * c;
            }
        }
        p.push(next);
    }
    p.pop().unwrap_or_else(|| vec![1.0])
}

/// Condition number κ₂(X) = σ_max(X)/σ_min(X) of the eigenvector matrix X of the closed loop
/// A − B K: the factor by which Bauer–Fike amplifies a perturbation of A − B K into its
/// eigenvalues (MATLAB's `place` reports the same kind of figure). ∞ when A − B K is defective
/// (a Jordan block: no basis of eigenvectors exists) or not finite.
///
/// X is built from faer's eigendecomposition of A − B K, its eigenvalues grouped by
/// `linalg::clusters` (the copies of one repeated eigenvalue): a simple eigenvalue's
/// column is faer's eigenvector, to unit length; for a cluster of k copies
/// around its mean μ, the k right singular vectors of M − μI for its k smallest singular values
/// (an orthonormal basis of the eigenspace, the best-conditioned choice within it), all of the
/// balanced matrix and mapped back (as `closed_loop_condition` does). The cluster is
/// declared defective (result ∞) when the largest of those k singular values exceeds
/// √ε·‖M‖_F, i.e. when μ has fewer than k independent eigenvectors to half the working precision.
///
/// Shapes that do not agree (A n×n, B n×m, K m×n) are [`PlantError::Shape`], naming the first.
pub fn eigenvector_condition(A: &DMatrix<f64>, B: &DMatrix<f64>, K: &DMatrix<f64>) -> Result<f64, PlantError> {
    let (n, m) = (A.nrows(), B.ncols());
    check_shape("A", A, n, n)?;
    check_shape("B", B, n, m)?;
    check_shape("K", K, m, n)?;
    Ok(closed_loop_condition(A, B, K))
}

/// [`eigenvector_condition`] for shapes known to agree (a [`crate::Design`]'s): κ₂ of A − B K as
/// given, which bounds an eigenvalue solver's error on it (normwise, so in these coordinates).
///
/// The eigenvectors are those of the balanced D⁻¹(A − B K)D, mapped back by D (exact: D is of
/// powers of 2), as LAPACK's `dgeev` balances by default. faer's eigenvalues of a badly scaled
/// matrix as given can be far off: a quadrotor's A − B K (entries from 1e-13 to 4.8e8) had its
/// 4-fold poles −628.32, −942.48 and −1413.72 split by up to 0.1 (numpy's, balanced: 1e-12), so
/// each fell into two clusters of two, read as defective, and κ₂ was ∞ where it is 1.4e7. Where
/// the balanced matrix reads defective, the matrix as given decides ([`balanced_eigenvectors`]).
pub(crate) fn closed_loop_condition(A: &DMatrix<f64>, B: &DMatrix<f64>, K: &DMatrix<f64>) -> f64 {
    balanced_eigenvectors(&(A - B * K), true).map_or(f64::INFINITY, |X| condition(&X))
}

/// κ₂ of A − B K's eigenvector matrix with its rows and columns equilibrated
/// ([`crate::linalg::equilibrated`]): the same for A − B K in any units of its states (a diagonal
/// similarity scales X's rows), which a relative error in the model's entries, or f32's rounding
/// of them, does not see either (the disk servo's f32 u_f departed 13–18 % of its peak from f64's
/// under state scalings whose κ₂ as given spread from 3.0e5 to 2.5e9; this κ₂ stayed 7.3e4).
/// ∞ for a defective or non-finite A − B K, 1 for n = 0.
pub(crate) fn scale_free_condition(A: &DMatrix<f64>, B: &DMatrix<f64>, K: &DMatrix<f64>) -> f64 {
    // Balanced first (exactly, by powers of two): eigenvectors of D⁻¹MD are D⁻¹ times M's, whose
    // rows the equilibration rescales anyway, but computed in units 1e12 apart their small rows
    // carry the solver's error relative to the large ones (κ₂ 3.7 read as 13.8).
    balanced_eigenvectors(&(A - B * K), false).map_or(f64::INFINITY, |X| condition(&crate::linalg::equilibrated(X)))
}

/// An eigenvector matrix of `M` from its balanced D⁻¹MD ([`crate::linalg::balancing`]), in M's
/// coordinates (`given`: its columns D v, a cluster's orthonormalized there) or the balanced ones;
/// where the balanced matrix reads defective, from M itself: balancing scales rounding-sized
/// entries too, and an aircraft's decoupled loop with a double channel pole (‖M‖ = 1.6e3, the
/// pole's coupling 4e-15) read as a Jordan block after it (coupling 1.5e-7 beside ‖D⁻¹MD‖ = 5.5),
/// as it does not before (helper tryout, 2026-12-07). `None` where both read it defective.
fn balanced_eigenvectors(M: &DMatrix<f64>, given: bool) -> Option<DMatrix<C64>> {
    let (balanced, d) = crate::linalg::balancing(M);
    eigenvectors(balanced, given.then_some(&d)).or_else(|| eigenvectors(M.clone(), None))
}

/// σ_max/σ_min of X (∞ for a singular X, 1 for an empty one: a loop of no states).
fn condition(X: &DMatrix<C64>) -> f64 {
    if X.is_empty() {
        1.0
    } else {
        crate::linalg::singular_extremes(X).1
    }
}

/// The eigenvector matrix X of M = A − B K as [`eigenvector_condition`] builds it; `None` for a
/// defective or non-finite M. With `scale` (D), the columns are those of D X, each simple one to
/// unit length and each cluster's orthonormalized, the best-conditioned choice in D's coordinates.
fn eigenvectors(M: DMatrix<f64>, scale: Option<&DVector<f64>>) -> Option<DMatrix<C64>> {
    let n = M.nrows();
    let size = M.norm();
    if !size.is_finite() {
        return None;
    }
    if n == 0 {
        return Some(DMatrix::zeros(0, 0));
    }
    let F = faer::Mat::<f64>::from_fn(n, n, |r, c| M[(r, c)]);
    let evd = F.eigen().ok()?;
    let eigs: Vec<C64> = (0..n).map(|j| evd.S().column_vector()[j]).collect();
    let U = evd.U();
    let Mc = M.map(|x| C64::new(x, 0.0));
    let mut X = DMatrix::<C64>::zeros(n, n);
    let mut c = 0;
    for cluster in crate::linalg::clusters(&eigs, size) {
        let k = cluster.len();
        let scaled = |r: usize| scale.map_or(1.0, |d| d[r]);
        if k == 1 {
            // A simple eigenvalue's eigenvector, from the same decomposition, to unit length.
            let v = DVector::<C64>::from_fn(n, |r, _| U[(r, cluster[0])] * scaled(r));
            let norm = v.norm();
            if !(norm.is_finite() && norm > 0.0) {
                return None;
            }
            X.set_column(c, &(v / C64::new(norm, 0.0)));
            c += 1;
            continue;
        }
        let mu = cluster.iter().map(|&j| eigs[j]).sum::<C64>() / k as f64;
        let shifted = &Mc - DMatrix::<C64>::identity(n, n) * mu;
        let svd = shifted.try_svd(false, true, f64::EPSILON, 10_000)?;
        let Vt = svd.v_t.as_ref()?;
        // Singular values sorted descending: the last k belong to the (near) null space.
        if svd.singular_values[n - k] > f64::EPSILON.sqrt() * size {
            return None;
        }
        let mut basis = Vt.rows(n - k, k).adjoint();
        if scale.is_some() {
            for (r, mut row) in basis.row_iter_mut().enumerate() {
                row *= C64::new(scaled(r), 0.0);
            }
            basis = basis.qr().q();
        }
        X.view_mut((0, c), (n, k)).copy_from(&basis);
        c += k;
    }
    Some(X)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The kernel from Givens rotations spans the same space as the null space of U1ᵀ (H − λ I)
    /// from an SVD (the independent computation this replaced), at λ exactly an eigenvalue of an
    /// upper triangular H (real and, with a 2 × 2 block, complex): the largest principal-angle
    /// sine between the two, ‖(I − P_svd) Y‖₂, is rounding-sized (1e-10 allows ‖H‖ ≈ 30 times
    /// n = 40 times a condition factor of the pencil of 10⁴ on ε ≈ 2e-16).
    #[test]
    fn the_pencil_kernel_is_the_admissible_space_at_an_eigenvalue() {
        let (n, m) = (40, 3);
        let coeffs = generic_coeffs(7, n * n + n * m);
        let mut H = DMatrix::from_fn(n, n, |r, c| if r <= c { coeffs[r * n + c] } else { 0.0 });
        for i in 0..n {
            H[(i, i)] = -1.0 - i as f64;
        }
        // A 2 × 2 block at rows 10, 11 with eigenvalues −5 ± 2i.
        (H[(10, 10)], H[(10, 11)], H[(11, 10)], H[(11, 11)]) = (-5.0, 2.0, -2.0, -5.0);
        let G = DMatrix::from_fn(n, m, |r, c| coeffs[n * n + r * m + c]);
        let check = |H: &DMatrix<C64>, G: &DMatrix<C64>, lambda: C64| {
            let Y = pencil_kernel(H, G, lambda).expect("controllable");
            let Y = Y.qr().q();
            let mut padded = DMatrix::<C64>::zeros(n + m, n + m);
            padded.view_mut((0, 0), (n, m)).copy_from(G);
            padded.view_mut((0, m), (n, n)).copy_from(&(H - DMatrix::<C64>::identity(n, n) * lambda));
            let Vt = padded.svd(false, true).v_t.unwrap();
            let kernel = Vt.rows(n, m).adjoint().rows(m, n).into_owned().qr().q();
            let off = &Y - &kernel * (kernel.adjoint() * &Y);
            let sine = off.singular_values().max();
            assert!(sine < 1e-10, "λ = {lambda}: principal-angle sine {sine:e}");
        };
        let (Hc, Gc) = (H.map(|x| C64::new(x, 0.0)), G.map(|x| C64::new(x, 0.0)));
        for lambda in [C64::new(-1.0, 0.0), C64::new(-23.0, 0.0), C64::new(-5.0, 2.0), C64::new(-0.5, 0.1)] {
            check(&Hc, &Gc, lambda);
        }
        // Real arithmetic at a real eigenvalue, as `admissible` calls it.
        let Y = pencil_kernel(&H, &G, -7.0).expect("controllable");
        let R = (&H - DMatrix::<f64>::identity(n, n) * -7.0) * &Y;
        let Q = G.clone().qr().q();
        let outside = (&R - &Q * (Q.transpose() * &R)).norm();
        assert!(outside < 1e-12 * H.norm(), "(H − λ I) Y leaves range G by {outside:e}");
        // An uncontrollable λ: with G zero the pencil is H − λ I, singular at an eigenvalue.
        assert!(pencil_kernel(&H, &DMatrix::zeros(n, m), -3.0).is_none());
    }

    /// The scale-free κ₂ is 1 for a symmetric matrix in any units of its states: D⁻¹ S D has the
    /// eigenvectors D⁻¹ Q, Q orthogonal, whose rows equilibrate back to Q's (closed form), while κ₂
    /// as given grows with D's spread. And it does not move under a diagonal similarity of a
    /// non-normal matrix with dense eigenvectors, whatever the spread (12 decades here; 1e-8 allows
    /// the equilibration's stop at 1e-12 and the eigenvectors' rounding at κ₂·ε). A triangular
    /// eigenvector matrix's equilibration can drift with the scaling (as a triangular B*'s does).
    #[test]
    fn the_scale_free_condition_ignores_the_states_units() {
        let n = 5;
        let c = generic_coeffs(3, n * n);
        let S = DMatrix::from_fn(n, n, |r, k| c[r * n + k] + c[k * n + r]);
        let d: Vec<f64> = (0..n).map(|i| 10f64.powi(3 * i as i32 - 6)).collect();
        let D = DMatrix::from_diagonal(&DVector::from_vec(d.clone()));
        let Di = DMatrix::from_diagonal(&DVector::from_vec(d.iter().map(|x| 1.0 / x).collect()));
        let (I, Z) = (DMatrix::identity(n, n), DMatrix::zeros(n, n));
        let scaled = &Di * &S * &D;
        assert!((scale_free_condition(&scaled, &I, &Z) - 1.0).abs() < 1e-8);
        assert!(closed_loop_condition(&scaled, &I, &Z) > 1e6);
        let A = DMatrix::from_fn(n, n, |r, k| c[r * n + k] + 0.3 * c[(r * n + k + 7) % (n * n)]);
        let kappa = scale_free_condition(&A, &I, &Z);
        let moved = scale_free_condition(&(&Di * &A * &D), &I, &Z);
        assert!((moved / kappa - 1.0).abs() < 1e-8, "{kappa} against {moved}");
        assert!(kappa > 1.5, "a non-normal test matrix: {kappa}");
    }

    /// Repeated poles in badly scaled states are not defective: M = S (I₄ ⊗ P) S⁻¹ with
    /// S = I₄ ⊗ diag(1, 1e4, 1e8) and P = V Λ V⁻¹ (Λ = the quadrotor's −628.32, −942.48, −1413.72),
    /// so each pole is 4-fold with four independent eigenvectors e_b ⊗ w_j, w_j = diag(s) v_j,
    /// mutually orthogonal across b. Any orthonormal basis of each eigenspace then gives κ₂ of the
    /// 3×3 [ŵ₁ ŵ₂ ŵ₃] (columns to unit length), an SVD of three vectors away from any eigensolver.
    /// Without balancing, faer's eigenvectors of M as given put κ₂ at 3.1e14 against 2.8e8.
    #[test]
    fn repeated_poles_in_badly_scaled_states_keep_a_finite_condition() {
        let V = DMatrix::from_row_slice(3, 3, &[1.0, 0.4, -0.2, 0.3, 1.0, 0.5, -0.6, 0.2, 1.0]);
        let lambda = DMatrix::from_diagonal(&DVector::from_vec(vec![-628.32, -942.48, -1413.72]));
        let P = &V * lambda * V.clone().try_inverse().unwrap();
        let s = [1.0, 1e4, 1e8];
        let (n, blocks) = (12, 4);
        let mut M = DMatrix::zeros(n, n);
        for b in 0..blocks {
            for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
                M[(3 * b + r, 3 * b + c)] = s[r] * P[(r, c)] / s[c];
            }
        }
        // Mix the blocks by a permutation that keeps the states' scales interleaved.
        let order: Vec<usize> = (0..n).map(|i| (i % blocks) * 3 + i / blocks).collect();
        let M = DMatrix::from_fn(n, n, |r, c| M[(order[r], order[c])]);
        let mut W = DMatrix::from_fn(3, 3, |r, c| s[r] * V[(r, c)]);
        for mut col in W.column_iter_mut() {
            let norm = col.norm();
            col /= norm;
        }
        let sv = W.singular_values();
        let expected = sv.max() / sv.min();
        let kappa = closed_loop_condition(&M, &DMatrix::identity(n, n), &DMatrix::zeros(n, n));
        assert!((kappa / expected - 1.0).abs() < 1e-6, "κ₂ {kappa:e} against {expected:e}");
        assert!(expected > 1e3, "badly scaled, as meant: {expected:e}");
    }

    /// A double channel pole whose coupling is rounding (an aircraft's decoupled loop from an
    /// automatic design, helper tryout 2026-12-07: −3.681835933 twice, semisimple: numpy's two
    /// smallest singular values of M − λI are 2.9e-14 and 3.8e-18 beside ‖M‖ = 1.6e3) is not a
    /// Jordan block: it read κ₂ = ∞ after balancing, which lifted the 4e-15 coupling to 1.5e-7
    /// beside ‖D⁻¹MD‖ = 5.5. numpy's `cond(eig(M)[1])` is 1.3e3–1.6e3 (its basis within the double
    /// pole's eigenspace is arbitrary, as is the rounding of M's entries it is given); κ₂ as given
    /// depends on that basis, so within a factor 10 of it.
    #[test]
    fn a_semisimple_double_pole_is_not_read_as_defective_after_balancing() {
        let M = DMatrix::from_row_slice(
            4,
            4,
            &[
                -3.6818359330000003,
                4.440892098500626e-15,
                -6.505213034913027e-19,
                0.0,
                1.009692559149214,
                -3.3038076823718194,
                -0.0003613681287169975,
                3.153739639880436,
                -36.48815089446127,
                985.7761291594495,
                -0.898256940049032,
                -1301.9230657735366,
                1.009692559149214,
                0.3780282506281804,
                -0.0003613681287169978,
                -0.5280962931195642,
            ],
        );
        let (I, Z) = (DMatrix::identity(4, 4), DMatrix::zeros(4, 4));
        let given = closed_loop_condition(&M, &I, &Z);
        assert!((128.0..=12_800.0).contains(&given), "κ₂ as given {given:e} against numpy's 1280");
        assert!(scale_free_condition(&M, &I, &Z).is_finite());
    }
}
