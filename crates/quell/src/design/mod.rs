//! The design layer: from a [`Plant`] and the designer's choices ([`DesignSpec`]) to every gain the
//! controller needs ([`Design`]), with the paper's assumptions checked on the way.

pub mod assumptions;
pub mod decouple;
pub mod internal_model;
pub mod place;
pub mod warnings;

use nalgebra::{Complex, DMatrix};
use thiserror::Error;

pub use assumptions::{controllability, observability, RankTest};
pub use decouple::{
    close, falb_wolovich, falb_wolovich_given, relative_degree_measures, relative_degrees, FalbWolovich,
    RelativeDegree, CLOSE_FACTOR, TOL,
};
pub use internal_model::{filter_pair, internal_model, RegressorScaling};
pub use place::{acker, place, PlaceError};
pub use warnings::{warnings, DesignWarning, ILL_CONDITIONED_DECOUPLER};

use crate::linalg::{
    eigenvalues, fmt_complex, fmt_complex_list, fmt_number, numerical_rank, poly_from_roots, singular_extremes,
    unstable, EigenError,
};
use crate::plant::{Plant, PlantError};
use crate::settings::TimeUnit;

/// How the Luenberger observer gain L of eq. (6) is chosen.
#[derive(Debug, Clone, PartialEq)]
pub enum ObserverChoice {
    /// L given (n×m).
    Gain(DMatrix<f64>),
    /// L = place(Aᵀ, Cᵀ, poles)ᵀ, so that eig(A − LC) = poles.
    Poles(Vec<Complex<f64>>),
}

/// The designer's choices. Pole lists hold every pole (a complex pair appears as both conjugates).
#[derive(Debug, Clone, PartialEq)]
pub struct DesignSpec {
    pub observer: ObserverChoice,
    /// Per output i: the σ_i poles λ_ij of G_ii(s).
    pub channel_poles: Vec<Vec<Complex<f64>>>,
    /// Per reference component: the q_gi poles of the filter (G_gi, l_gi), eq. (10).
    pub reference_filter_poles: Vec<Vec<Complex<f64>>>,
    /// Per disturbance component: the q_ωα poles of the filter (G_ωα, l_ωα), eq. (15).
    pub disturbance_filter_poles: Vec<Vec<Complex<f64>>>,
    /// Adaptation gains μ_i ≥ 0, eq. (33).
    pub mu: Vec<f64>,
    /// H(s) = 1/(β s + 1), β > 0.
    pub beta: f64,
    /// σ_i given by the designer (`design.relative_degrees`) instead of decided by eq. (7); `None`
    /// lets eq. (7) decide. Accepted unless the plant clearly contradicts it
    /// ([`decouple::falb_wolovich_given`]).
    pub relative_degrees: Option<Vec<usize>>,
    /// How the internal-model filters are realized, and so the size of ξ̂ and the meaning of μ
    /// (`design.regressor_scaling`; [`RegressorScaling::Paper`] by default).
    pub regressor_scaling: RegressorScaling,
    /// Per reference component: its size s_gi > 0 (its expected peak, in its own units), which
    /// divides l_gi and so ξ̂'s block of that component (`design.reference_sizes`; empty: 1 each,
    /// the paper's form). Sizes make ξ̂ dimensionless: an output in mm and another in rad then
    /// give Ω̄ no spread from their units.
    pub reference_sizes: Vec<f64>,
    /// Per disturbance component: its size s_ωα > 0, as [`DesignSpec::reference_sizes`]
    /// (`design.disturbance_sizes`; empty: 1 each).
    pub disturbance_sizes: Vec<f64>,
}

/// Channel i's decoupled transfer function G_ii(s) = q_i0 / ∏_j (s − λ_ij).
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelTf {
    pub poles: Vec<Complex<f64>>,
    /// Ascending coefficients [a_0, …, a_{σ−1}] of the monic denominator; a_0 = q_i0.
    pub den: Vec<f64>,
}

impl ChannelTf {
    /// G_ii(s) with these poles (σ_i of them), denominator ∏_j (s − λ_ij).
    pub fn new(poles: &[Complex<f64>]) -> ChannelTf {
        ChannelTf { poles: poles.to_vec(), den: poly_from_roots(poles) }
    }
    /// Relative degree σ_i.
    pub fn sigma(&self) -> usize {
        self.den.len()
    }
    /// Numerator q_i0 (= a_0, unit DC gain).
    pub fn q0(&self) -> f64 {
        self.den[0]
    }
    /// G_ii(s).
    pub fn eval(&self, s: Complex<f64>) -> Complex<f64> {
        let den = self.den.iter().rev().fold(Complex::new(1.0, 0.0), |acc, &a| acc * s + a);
        Complex::new(self.q0(), 0.0) / den
    }
}

/// Every matrix the controller needs, and the checks that were passed to get them.
///
/// Built only by [`Design::new`]; the fields are private and read through accessors named as in
/// the paper, so the derived parts (A_f = A − BK, B_f = BF, N = L_ω D⁺, the eigenvalues) always
/// agree with the gains they come from:
///
/// ```compile_fail
/// # let s = quell::Scenario::from_toml(quell::scenario::PAPER_EXAMPLE).unwrap();
/// let mut design = quell::Design::new(&s.plant, &s.design).unwrap();
/// design.K[(0, 0)] = 1.0; // private: K cannot drift from A_f = A − BK
/// ```
#[derive(Debug, Clone)]
pub struct Design {
    plant: Plant,
    L: DMatrix<f64>,
    K: DMatrix<f64>,
    F: DMatrix<f64>,
    A_f: DMatrix<f64>,
    B_f: DMatrix<f64>,
    B_star: DMatrix<f64>,
    cond_B_star: f64,
    degrees: Vec<RelativeDegree>,
    channels: Vec<ChannelTf>,
    G_g: DMatrix<f64>,
    L_g: DMatrix<f64>,
    G_w: DMatrix<f64>,
    L_w: DMatrix<f64>,
    N: DMatrix<f64>,
    cond_D: f64,
    mu: Vec<f64>,
    beta: f64,
    regressor_scaling: RegressorScaling,
    reference_sizes: Vec<f64>,
    disturbance_sizes: Vec<f64>,
    controllability: RankTest,
    observability: RankTest,
    observer_eigenvalues: Vec<Complex<f64>>,
    decoupled_eigenvalues: Vec<Complex<f64>>,
    /// The plant's zeros that passed [`check_zero_dynamics`] only by refinement: stable, but within
    /// the rounding margin of the imaginary axis ([`warnings`] reports them).
    near_axis_zeros: Vec<Complex<f64>>,
    /// κ₂ of A − LC's and A − BK's eigenvectors, computed once when first asked (an eigen-
    /// decomposition each: seconds for n in the hundreds).
    observer_kappa: std::sync::OnceLock<f64>,
    decoupled_kappa: std::sync::OnceLock<f64>,
}

/// Why no design exists for a plant and a set of choices. Messages name the scenario key.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DesignError {
    #[error("plant: (A, B) is not controllable (Assumption 1): numerical rank {rank} of {n} (tolerance {tol:.1e}); every mode must be reachable from the inputs{scaling}")]
    Uncontrollable { rank: usize, n: usize, tol: f64, scaling: String },
    #[error("plant: (A, C) is not observable (Assumption 1): numerical rank {rank} of {n} (tolerance {tol:.1e}); every mode must show in the outputs{scaling}")]
    Unobservable { rank: usize, n: usize, tol: f64, scaling: String },
    #[error("design.observer_poles: {}", as_observer(.0))]
    ObserverPoles(PlaceError),
    #[error("plant.{0}")]
    Plant(#[from] PlantError),
    #[error("design.observer_gain[{row}][{col}]: expected a finite number, found {}", crate::settings::fmt_short(*.value))]
    ObserverGainNonFinite { row: usize, col: usize, value: f64 },
    #[error("design.observer_gain: expected a {n}×{m} matrix, found {rows}×{cols}{}", if .rows == .m && .cols == .n && .n != .m { " (its transpose's shape: a gain placed on the dual system, as place(Aᵀ, Cᵀ, poles) gives, is Lᵀ; give its transpose)" } else { "" })]
    ObserverGainShape { n: usize, m: usize, rows: usize, cols: usize },
    #[error("{key}: A − LC is not Hurwitz (eigenvalues {}); {}", fmt_complex_list(.eigenvalues), if *.key == "design.observer_gain" { "choose L with a stable observer, or give design.observer_poles instead" } else { "choose observer poles with larger decay rates" })]
    ObserverUnstable { key: &'static str, eigenvalues: Vec<Complex<f64>> },
    #[error("{key}: A − LC could not be confirmed Hurwitz: its eigenvalues computed as {} include {} within the rounding margin √ε·‖A − LC‖_F = {} of the imaginary axis, and refining them in twice the working precision did not settle their sign (eigenvector condition number κ₂ = {}: a relative error ε in A − LC can move its poles by about κ₂·ε·‖A − LC‖); {}", fmt_complex_list(.eigenvalues), fmt_complex_list(.in_margin), fmt_number(*.margin), fmt_number(*.kappa), if *.key == "design.observer_gain" { "choose L with a better-conditioned stable observer, or give design.observer_poles instead" } else { "choose observer poles with larger decay rates, distinct and not far faster than the plant" })]
    ObserverUnconfirmed {
        key: &'static str,
        eigenvalues: Vec<Complex<f64>>,
        in_margin: Vec<Complex<f64>>,
        margin: f64,
        kappa: f64,
    },
    #[error("plant.C: output {} is reached by no input: c_i A^(l-1) B = 0 for every l ≤ n (largest cosine between c_i A^(l-1) and a column of B, the states balanced: {largest:.1e}, below τ = {tol:.0e}), so the plant cannot be decoupled; check plant.C[{channel}] (its row)", .channel + 1, tol = TOL)]
    NoRelativeDegree { channel: usize, largest: f64 },
    #[error("design.channel_poles[{channel}]: channel {} has relative degree {sigma}, so it needs {sigma} pole{}; found {got}{}", .channel + 1, if *.sigma == 1 { "" } else { "s" }, match .pairs { 0 => String::new(), 1 => " (a pair [re, im] is two poles, re ± i·im)".into(), p => format!(" ({p} pairs [re, im], each two poles, re ± i·im)") })]
    ChannelPoleCount { channel: usize, sigma: usize, got: usize, pairs: usize },
    #[error("plant: not decouplable (Proposition 1): B* is singular: with rows c_i A^(σ_i-1) and the columns of B scaled to unit norm its smallest singular value is {smallest:.3e}, below τ = {tol:.0e} (condition number {cond:.3e}); the outputs' leading responses to the inputs (c_i A^(σ_i−1) B, σ = {sigma:?}) are (nearly) dependent; measure outputs whose leading responses differ (another sensor, or other combinations of the states), pair the outputs with other inputs, or, where the design report calls a σ_i decision close, give design.relative_degrees", tol = TOL)]
    NotDecouplable { smallest: f64, cond: f64, sigma: Vec<usize> },
    #[error("plant: unstable zero dynamics: A − BK keeps the plant's {} zero{} (its eigenvalues besides the {placed} channel poles that Proposition 1 places), and {} not in the open left half-plane: {} (per {unit}); the plant is non-minimum-phase with these outputs (a transmission zero of (A, B, C) in the closed right half-plane) and decoupling cancels its zeros, so it cannot be decoupled stably; {}{}measure outputs whose zeros lie in the left half-plane (a boost converter's inductor current in place of its output voltage; another sensor placement), or control this plant by another method", .zeros.len(), if .zeros.len() == 1 { "" } else { "s" }, if .unstable.len() == 1 { "this one is" } else { "these are" }, fmt_complex_list(.unstable), if *.mirrored { "each of them mirrors a pole of A across the imaginary axis, an all-pass factor such as a Padé approximation of a delay: a delay is plant.delays (the method predicts over it exactly), so give the plant without that factor and the delay there; otherwise " } else { "" }, if .unstable.iter().any(|z| z.norm() == 0.0) { "a zero at s = 0 is a mode the plant integrates that no output sees (a rotor's speed measured without its angle, a level's inflow without the level): measure the integrated quantity itself, or " } else { "" })]
    UnstableZeroDynamics {
        placed: usize,
        zeros: Vec<Complex<f64>>,
        unstable: Vec<Complex<f64>>,
        unit: TimeUnit,
        /// Every unstable zero z in the open right half-plane mirrors an eigenvalue −z̄ of A (to
        /// 1e-4 of |z|): an all-pass factor, as a Padé approximation of a delay.
        mirrored: bool,
    },
    #[error("design.relative_degrees[{index}]: expected a relative degree 1 ≤ σ_i ≤ n = {n}, found {value}")]
    RelativeDegreeRange { index: usize, value: usize, n: usize },
    #[error("design.relative_degrees[{channel}]: σ_{} = {given} contradicts the plant: c_{0} A^({}) B is clearly non-zero (largest cosine between c_{0} A^({1}) and a column of B, the states balanced: {measure:.2e}, above {cf}·τ = {bound:.0e}), so channel {0} has relative degree at most {l}; give σ_{0} ≤ {l}, or remove design.relative_degrees to let eq. (7) decide", .channel + 1, .l - 1, cf = CLOSE_FACTOR, bound = TOL * CLOSE_FACTOR)]
    RelativeDegreeTooHigh { channel: usize, given: usize, l: usize, measure: f64 },
    #[error("design.relative_degrees[{channel}]: σ_{} = {given} contradicts the plant: c_{0} A^({}) B is clearly zero (largest cosine between c_{0} A^({1}) and a column of B, the states balanced: {measure:.2e}, below τ/{cf} = {bound:.0e}), so no input reaches output {0} at l = {given}; give a larger σ_{0}, or remove design.relative_degrees to let eq. (7) decide", .channel + 1, .given - 1, cf = CLOSE_FACTOR, bound = TOL / CLOSE_FACTOR)]
    RelativeDegreeTooLow { channel: usize, given: usize, measure: f64 },
    #[error("design.relative_degrees: Σσ_i = {sum} exceeds n = {n}; for a decouplable plant the Σσ_i rows c_i A^j (j < σ_i) are independent, so Σσ_i ≤ n; give smaller relative degrees, or remove design.relative_degrees to let eq. (7) decide")]
    RelativeDegreeSum { sum: usize, n: usize },
    #[error("{key}: expected {} (one per {per}), found {got}", crate::settings::entries(*.expected))]
    Count { key: &'static str, per: &'static str, expected: usize, got: usize },
    #[error("{key}: pole {} is not in the open left half-plane; {what} poles must be Hurwitz (real part < 0)", fmt_complex(.pole))]
    NotHurwitz { key: String, what: &'static str, pole: Complex<f64> },
    #[error("{key}: pole {} has no complex-conjugate partner in the list", fmt_complex(.pole))]
    NotConjugateClosed { key: String, pole: Complex<f64> },
    #[error("{key}: the list is empty; give at least one pole")]
    NoPoles { key: String },
    #[error("{key}: the filter's polynomial ∏(s − p_j) over its {count} poles has a coefficient of magnitude {}, beyond {}: too large for the internal model's matrices (11), (16) in double precision; give fewer poles (two per harmonic, one per bias) or slower ones", crate::settings::fmt_short(*.coefficient), crate::settings::fmt_short(crate::plant::MAX_ENTRY))]
    FilterTooLarge { key: String, count: usize, coefficient: f64 },
    #[error("{key}: pole {} is repeated; design.regressor_scaling = \"modal\" realizes each pole or pair as its own block, and equal blocks driven alike are not controllable; give distinct poles (e.g. one resonator −a ± jω per harmonic), or choose \"normalized\"", fmt_complex(.pole))]
    RepeatedModalPole { key: String, pole: Complex<f64> },
    #[error("plant.A: n = {n} states; a design is limited to n ≤ {MAX_STATES} (quell::design::MAX_STATES): its eigen-decompositions and pole placement grow as n³ (seconds at n = {MAX_STATES}, minutes beyond 1000); reduce the model first (e.g. balanced truncation to the modes that matter)")]
    TooManyStates { n: usize },
    #[error("design.mu[{index}]: expected a finite adaptation gain ≥ 0, found {}", crate::settings::fmt_short(*.value))]
    BadMu { index: usize, value: f64 },
    #[error("design.beta: expected a finite β > 0 (H(s) = 1/(βs + 1)), found {}", crate::settings::fmt_short(*.value))]
    BadBeta { value: f64 },
    #[error("{key}[{index}]: expected a size from 1e-150 to 1e150 (the component's expected peak, in its own units), found {}", crate::settings::fmt_short(*.value))]
    BadSize { key: &'static str, index: usize, value: f64 },
    #[error("{key}: pole {} is out of the design's span of rates: given the other pole lists and 1/β, expected decay rate −Re p ≥ {} and magnitude ≤ {}; {SPAN_WHY}", fmt_complex(.pole), fmt_number(*.min_decay), fmt_number(*.max_magnitude))]
    PoleOutOfSpan { key: String, pole: Complex<f64>, min_decay: f64, max_magnitude: f64 },
    #[error("design.beta: β = {} is out of the design's span of rates: given its poles, expected {} ≤ β ≤ {}; {SPAN_WHY}", fmt_number(*.value), fmt_number(*.min), fmt_number(*.max))]
    BetaOutOfSpan { value: f64, min: f64, max: f64 },
    #[error("{key}: the eigenvalues of {of} could not be computed: {reason}")]
    Eigenvalues { key: &'static str, of: &'static str, reason: &'static str },
    #[error("plant.D: rank D = {rank} < k = {k}, so N D = L_ω (eq. (20)) has no solution; disturbances must enter through independent directions")]
    DisturbanceRank { rank: usize, k: usize },
    #[error("plant.D: the disturbance directions are nearly parallel: D with unit columns has smallest singular value {smallest:.3e}, below τ = {tol:.0e} (condition number {cond:.3e}), so N = L_ω D⁺ (eq. (20)) would be huge (‖N‖ ≈ {norm_N:.1e}); merge the nearly parallel disturbance components into one", tol = TOL)]
    DisturbanceConditioning { smallest: f64, cond: f64, norm_N: f64 },
    /// The stop flag of [`crate::cancel::with_stop`] was set (e.g. by Ctrl-C) during the design.
    #[error("interrupted during the design")]
    Interrupted,
}

/// A pole placement's message as the observer's dual placement meets it: rank(C) and A − LC where
/// the message for either speaks of rank(B) and A − BK ("more than rank(B) = 2 (rank C for
/// observer poles)" for repeated observer poles).
fn as_observer(e: &PlaceError) -> String {
    match e {
        PlaceError::Multiplicity { rank, .. } => e
            .to_string()
            .replace(&format!("rank(B) = {rank} (rank C for observer poles)"), &format!("rank(C) = {rank}"))
            .replace("the closed loop (A − BK; A − LC for observer poles)", "the observer A − LC"),
        _ => e.to_string(),
    }
}

/// Largest ratio between two rates of one design: a pole's magnitude |p| (or 1/β, the pole of H)
/// against a decay rate |Re p| (or 1/β). A pole slower than √ε times the fastest lies inside the
/// margin √ε·‖M‖ within which the Hurwitz checks (`linalg::unstable`) cannot tell it from the imaginary
/// axis, and the loop's integrator would need about 1/√ε steps for it to settle.
pub const RATE_SPAN: f64 = 67_108_864.0; // 1/√ε = 2^26

/// The most states a design takes: the eigen-decompositions, rank tests and pole placement of
/// [`Design::new`] cost O(n³) (a few CPU seconds at n = 500; a pole placement that fails and tries
/// its fallback takes longest), so a larger model is refused at once rather than computed for minutes.
pub const MAX_STATES: usize = 500;

/// From this many states on, [`Design::new`] under a stop flag runs on a worker thread it can
/// leave (a design of n = 100 takes about 0.1 s; below, the thread would cost more than it saves).
pub const DETACHED_MIN_STATES: usize = 100;

const SPAN_WHY: &str = "every pole's magnitude and 1/β may exceed every decay rate −Re p (and 1/β) by at \
                        most 1/√ε ≈ 6.7e7: a slower pole lies within the rounding margin of the imaginary axis \
                        that the stability checks use; bring the poles and β to a common time scale";

/// Checks a pole list: not empty (when `nonempty`), finite, closed under conjugation, Hurwitz.
fn check_poles(key: String, what: &'static str, poles: &[Complex<f64>], nonempty: bool) -> Result<(), DesignError> {
    if nonempty && poles.is_empty() {
        return Err(DesignError::NoPoles { key });
    }
    for &p in poles {
        if !(p.re.is_finite() && p.im.is_finite()) || p.re >= 0.0 {
            return Err(DesignError::NotHurwitz { key, what, pole: p });
        }
        let partners = |z: Complex<f64>| poles.iter().filter(|&&x| (x - z).norm() <= 1e-12 * (1.0 + z.norm())).count();
        if p.im != 0.0 && partners(p.conj()) != partners(p) {
            return Err(DesignError::NotConjugateClosed { key, pole: p });
        }
    }
    Ok(())
}

impl Design {
    /// Designs every gain in the paper's order and checks each condition on the way: the choices
    /// (Section VIII), Assumption 1, the observer (6), the decoupler of Proposition 1 with stable
    /// zero dynamics, the internal models (11), (16) and the disturbance observer gain (20).
    ///
    /// Inside [`crate::cancel::with_stop`] a plant of [`DETACHED_MIN_STATES`] states or more is
    /// designed on a worker thread that the call leaves when the flag is set, so that a stop request returns
    /// [`DesignError::Interrupted`] within milliseconds even during an eigendecomposition.
    pub fn new(plant: &Plant, spec: &DesignSpec) -> Result<Design, DesignError> {
        match crate::cancel::current() {
            Some(stop) if plant.n() >= DETACHED_MIN_STATES => {
                let (plant, spec) = (plant.clone(), spec.clone());
                crate::cancel::detached(stop, move || Design::build(&plant, &spec))
                    .unwrap_or(Err(DesignError::Interrupted))
            }
            _ => Design::build(plant, spec),
        }
    }

    /// [`Design::new`] on this thread, polling the stop flag between its phases.
    fn build(plant: &Plant, spec: &DesignSpec) -> Result<Design, DesignError> {
        let poll = || crate::cancel::check().map_err(|_| DesignError::Interrupted);
        // The fields of a plant are public: check it again (Plant::new did, but a literal does not).
        plant.validate()?;
        if plant.n() > MAX_STATES {
            return Err(DesignError::TooManyStates { n: plant.n() });
        }
        check_spec(plant, spec)?;
        let (controllability, observability) = assumption_1(plant)?;
        poll()?;
        // The decoupling and its zero dynamics before the observer: a non-minimum-phase plant is
        // refused for what no observer fixes (a random 30-state plant had been told that its
        // observer "would miss the requested poles" by 2.9e234; helper tryout, 2026-12-07).
        let fw =
            falb_wolovich_given(&plant.A, &plant.B, &plant.C, &spec.channel_poles, spec.relative_degrees.as_deref())?;
        let A_f = &plant.A - &plant.B * &fw.K;
        let B_f = &plant.B * &fw.F;
        poll()?;
        let decoupled_eigenvalues = eigenvalues(&A_f).map_err(|e| eigen_error("plant", "A − BK", e))?;
        poll()?;
        let near_axis_zeros = check_zero_dynamics(plant, &fw)?;
        poll()?;
        let (L, observer_eigenvalues) = observer(plant, &spec.observer)?;
        let reference_sizes = sizes_or_ones(&spec.reference_sizes, plant.m());
        let disturbance_sizes = sizes_or_ones(&spec.disturbance_sizes, plant.k());
        let (G_g, L_g) = internal_model(&spec.reference_filter_poles, &reference_sizes, spec.regressor_scaling);
        let (G_w, L_w) = internal_model(&spec.disturbance_filter_poles, &disturbance_sizes, spec.regressor_scaling);
        let (N, cond_D) = disturbance_observer_gain(&plant.D, &L_w)?;
        Ok(Design {
            plant: plant.clone(),
            L,
            K: fw.K,
            F: fw.F,
            A_f,
            B_f,
            B_star: fw.B_star,
            cond_B_star: fw.cond_B_star,
            degrees: fw.degrees,
            channels: fw.channels,
            G_g,
            L_g,
            G_w,
            L_w,
            N,
            cond_D,
            mu: spec.mu.clone(),
            beta: spec.beta,
            regressor_scaling: spec.regressor_scaling,
            reference_sizes,
            disturbance_sizes,
            controllability,
            observability,
            observer_eigenvalues,
            decoupled_eigenvalues,
            near_axis_zeros,
            observer_kappa: std::sync::OnceLock::new(),
            decoupled_kappa: std::sync::OnceLock::new(),
        })
    }

    /// This design with the observer (6) placed at `poles` instead: L and eig(A − LC) anew, every
    /// other gain kept (the observer is designed apart from K, F and the internal models).
    pub fn with_observer_poles(&self, poles: &[Complex<f64>]) -> Result<Design, DesignError> {
        let (L, observer_eigenvalues) = observer(&self.plant, &ObserverChoice::Poles(poles.to_vec()))?;
        Ok(Design { L, observer_eigenvalues, observer_kappa: std::sync::OnceLock::new(), ..self.clone() })
    }

    /// The plant the design is for.
    pub fn plant(&self) -> &Plant {
        &self.plant
    }
    /// Observer gain L, eq. (6).
    pub fn L(&self) -> &DMatrix<f64> {
        &self.L
    }
    /// Decoupling state feedback K = (B*)⁻¹ C* (Proposition 1).
    pub fn K(&self) -> &DMatrix<f64> {
        &self.K
    }
    /// Decoupling input gain F = (B*)⁻¹ diag(q_i0) (Proposition 1).
    pub fn F(&self) -> &DMatrix<f64> {
        &self.F
    }
    /// A_f = A − BK (Proposition 1).
    pub fn A_f(&self) -> &DMatrix<f64> {
        &self.A_f
    }
    /// B_f = BF (Proposition 1).
    pub fn B_f(&self) -> &DMatrix<f64> {
        &self.B_f
    }
    /// B*, row i = c_i A^(σ_i − 1) B (Proposition 1).
    pub fn B_star(&self) -> &DMatrix<f64> {
        &self.B_star
    }
    /// Condition number of B* in the 2-norm, its rows and columns equilibrated (scale-free:
    /// [`decouple::FalbWolovich::cond_B_star`]).
    pub fn cond_B_star(&self) -> f64 {
        self.cond_B_star
    }
    /// Relative degrees σ_i, eq. (7): the order of each channel's G_ii(s).
    pub fn sigma(&self) -> Vec<usize> {
        self.channels.iter().map(ChannelTf::sigma).collect()
    }
    /// The decision of eq. (7) for each output: σ_i and the scale-free measures behind it.
    pub fn relative_degree_decisions(&self) -> &[RelativeDegree] {
        &self.degrees
    }
    /// G_ii(s), one per channel.
    pub fn channels(&self) -> &[ChannelTf] {
        &self.channels
    }
    /// Reference internal model G_g, eq. (11).
    pub fn G_g(&self) -> &DMatrix<f64> {
        &self.G_g
    }
    /// Reference internal model L_g, eq. (11).
    pub fn L_g(&self) -> &DMatrix<f64> {
        &self.L_g
    }
    /// Disturbance internal model G_ω, eq. (16).
    pub fn G_w(&self) -> &DMatrix<f64> {
        &self.G_w
    }
    /// Disturbance internal model L_ω, eq. (16).
    pub fn L_w(&self) -> &DMatrix<f64> {
        &self.L_w
    }
    /// Disturbance observer gain N with N D = L_ω (eq. (20)), the minimum-norm N = L_ω D⁺.
    pub fn N(&self) -> &DMatrix<f64> {
        &self.N
    }
    /// Condition number of D with unit columns (the measure of the tolerance policy, [`TOL`]).
    pub fn cond_D(&self) -> f64 {
        self.cond_D
    }
    /// Adaptation gains μ_i, eq. (33).
    pub fn mu(&self) -> &[f64] {
        &self.mu
    }
    /// β of H(s) = 1/(βs + 1).
    pub fn beta(&self) -> f64 {
        self.beta
    }
    /// How the internal-model filters are realized ([`RegressorScaling`]).
    pub fn regressor_scaling(&self) -> RegressorScaling {
        self.regressor_scaling
    }
    /// Each reference component's size s_gi, which divides its block of ξ̂ (1 where the design
    /// gives none).
    pub fn reference_sizes(&self) -> &[f64] {
        &self.reference_sizes
    }
    /// Each disturbance component's size s_ωα, which divides its block of ξ̂ (1 where the design
    /// gives none).
    pub fn disturbance_sizes(&self) -> &[f64] {
        &self.disturbance_sizes
    }
    /// Whether any component's size differs from 1 (`design.reference_sizes` or
    /// `design.disturbance_sizes`): ξ̂ is then dimensionless.
    pub fn has_sizes(&self) -> bool {
        self.reference_sizes.iter().chain(&self.disturbance_sizes).any(|&s| s != 1.0)
    }
    /// Assumption 1: the controllability rank test.
    pub fn controllability(&self) -> &RankTest {
        &self.controllability
    }
    /// Assumption 1: the observability rank test.
    pub fn observability(&self) -> &RankTest {
        &self.observability
    }
    /// The assumption checks passed, one figure each ([`AssumptionChecks`]): the design report's
    /// `checks` in JSON, and Python's `Design.checks`.
    pub fn checks(&self) -> AssumptionChecks {
        let max_re = |e: &[Complex<f64>]| e.iter().map(|z| z.re).fold(f64::NEG_INFINITY, f64::max);
        let decisions = self.relative_degree_decisions();
        AssumptionChecks {
            controllability_rank: self.controllability.rank,
            controllability_tol: self.controllability.tol,
            observability_rank: self.observability.rank,
            observability_tol: self.observability.tol,
            cond_B_star: self.cond_B_star,
            cond_D: self.cond_D,
            tolerance: TOL,
            relative_degree_measures: decisions.iter().map(|r| r.deciding().to_vec()).collect(),
            relative_degree_close: decisions.iter().map(RelativeDegree::is_close).collect(),
            relative_degrees_given: decisions.iter().map(|r| r.given).collect(),
            max_re_decoupled_eigenvalue: max_re(self.decoupled_eigenvalues()),
            max_re_observer_eigenvalue: max_re(self.observer_eigenvalues()),
            disturbance_rank: self.plant.k(),
        }
    }
    /// eig(A − LC), sorted.
    pub fn observer_eigenvalues(&self) -> &[Complex<f64>] {
        &self.observer_eigenvalues
    }
    /// eig(A − BK), sorted.
    pub fn decoupled_eigenvalues(&self) -> &[Complex<f64>] {
        &self.decoupled_eigenvalues
    }
    /// The plant's zeros (A − BK's zero dynamics) that are stable within only the rounding margin
    /// √ε‖Z‖ of the imaginary axis.
    pub fn near_axis_zeros(&self) -> &[Complex<f64>] {
        &self.near_axis_zeros
    }
    /// κ₂ of the eigenvector matrix of A − LC (by duality), its rows and columns equilibrated so
    /// that the states' units do not move it (for distinct eigenvalues; the basis of a repeated
    /// one's eigenspace depends on them, by up to about 15 %): how much a relative error in the
    /// model's entries moves the observer poles; ∞ for a Jordan design.
    /// [`place::eigenvector_condition`] gives κ₂ in the coordinates as given.
    pub fn observer_eigenvector_condition(&self) -> f64 {
        let p = &self.plant;
        *self
            .observer_kappa
            .get_or_init(|| place::scale_free_condition(&p.A.transpose(), &p.C.transpose(), &self.L.transpose()))
    }
    /// κ₂ of the eigenvector matrix of A − BK = A_f, equilibrated as
    /// [`Design::observer_eigenvector_condition`]'s; ∞ for a Jordan design.
    pub fn decoupled_eigenvector_condition(&self) -> f64 {
        *self.decoupled_kappa.get_or_init(|| place::scale_free_condition(&self.plant.A, &self.plant.B, &self.K))
    }
    /// Dimension q_g of the reference regressor ξ̂_g.
    pub fn q_g(&self) -> usize {
        self.G_g.nrows()
    }
    /// Dimension q_ω of the disturbance regressor ξ̂_ω.
    pub fn q_w(&self) -> usize {
        self.G_w.nrows()
    }
    /// Dimension q = q_g + q_ω of the regressor ξ̂ and of each η̂_i.
    pub fn q(&self) -> usize {
        self.q_g() + self.q_w()
    }
}

/// `sizes`, or `count` ones where none are given.
fn sizes_or_ones(sizes: &[f64], count: usize) -> Vec<f64> {
    if sizes.is_empty() {
        vec![1.0; count]
    } else {
        sizes.to_vec()
    }
}

/// The designer's choices: one entry per channel / component, μ_i ≥ 0, β > 0, every pole list
/// Hurwitz and closed under conjugation.
fn check_spec(plant: &Plant, spec: &DesignSpec) -> Result<(), DesignError> {
    let (m, k) = (plant.m(), plant.k());
    let count = |key, per, expected, got| {
        if expected == got {
            Ok(())
        } else {
            Err(DesignError::Count { key, per, expected, got })
        }
    };
    count("design.channel_poles", "output", m, spec.channel_poles.len())?;
    count(
        "design.reference_filter_poles",
        "reference component, i.e. one per output",
        m,
        spec.reference_filter_poles.len(),
    )?;
    count(
        "design.disturbance_filter_poles",
        "disturbance component, i.e. one per column of plant.D",
        k,
        spec.disturbance_filter_poles.len(),
    )?;
    count("design.mu", "channel", m, spec.mu.len())?;
    for (key, per, sizes, components) in [
        ("design.reference_sizes", "reference component, or none for 1 each", &spec.reference_sizes, m),
        ("design.disturbance_sizes", "disturbance component, or none for 1 each", &spec.disturbance_sizes, k),
    ] {
        if !sizes.is_empty() {
            count(key, per, components, sizes.len())?;
        }
        let sane = |v: f64| (1.0 / crate::plant::MAX_ENTRY..=crate::plant::MAX_ENTRY).contains(&v);
        if let Some((index, &value)) = sizes.iter().enumerate().find(|(_, v)| !sane(**v)) {
            return Err(DesignError::BadSize { key, index, value });
        }
    }
    if let Some((index, &value)) = spec.mu.iter().enumerate().find(|(_, v)| !(v.is_finite() && **v >= 0.0)) {
        return Err(DesignError::BadMu { index, value });
    }
    if !(spec.beta.is_finite() && spec.beta > 0.0) {
        return Err(DesignError::BadBeta { value: spec.beta });
    }
    for (i, p) in spec.channel_poles.iter().enumerate() {
        check_poles(format!("design.channel_poles[{i}]"), "channel", p, false)?;
    }
    for (i, p) in spec.reference_filter_poles.iter().enumerate() {
        check_poles(format!("design.reference_filter_poles[{i}]"), "internal-model filter", p, true)?;
    }
    for (i, p) in spec.disturbance_filter_poles.iter().enumerate() {
        check_poles(format!("design.disturbance_filter_poles[{i}]"), "internal-model filter", p, true)?;
    }
    if let ObserverChoice::Poles(p) = &spec.observer {
        check_poles("design.observer_poles".into(), "observer", p, false)?;
    }
    check_rate_span(spec)?;
    check_filters(spec)
}

/// Each internal-model filter's poles as its realization needs them. The companion forms hold
/// ∏(s − p_j)'s coefficients, at most [`crate::plant::MAX_ENTRY`]: 44 poles at −1e7 overflowed
/// them to ∞, and every later eigenvalue computation ran on a non-finite matrix (checked after the
/// span of rates, which names a single absurd pole better). The modal form
/// (`design.regressor_scaling = "modal"`) needs them distinct: two equal blocks driven alike are
/// not controllable (poles closer than 1e-8 of their size count as equal).
fn check_filters(spec: &DesignSpec) -> Result<(), DesignError> {
    let lists = [
        ("reference_filter_poles", &spec.reference_filter_poles),
        ("disturbance_filter_poles", &spec.disturbance_filter_poles),
    ];
    for (name, list) in lists {
        for (i, poles) in list.iter().enumerate() {
            let key = format!("design.{name}[{i}]");
            if spec.regressor_scaling == RegressorScaling::Modal {
                let repeated = |(j, p): &(usize, &Complex<f64>)| {
                    poles[..*j].iter().any(|z| (z - *p).norm() <= 1e-8 * z.norm().max(p.norm()))
                };
                if let Some((_, &pole)) = poles.iter().enumerate().find(repeated) {
                    return Err(DesignError::RepeatedModalPole { key, pole });
                }
                continue;
            }
            let magnitude = |a: f64| if a.is_nan() { f64::INFINITY } else { a.abs() };
            let coefficient = poly_from_roots(poles).into_iter().fold(0.0, |m: f64, a| m.max(magnitude(a)));
            if coefficient > crate::plant::MAX_ENTRY {
                return Err(DesignError::FilterTooLarge { key, count: poles.len(), coefficient });
            }
        }
    }
    Ok(())
}

/// The choices' rates (every requested pole, and 1/β) span at most [`RATE_SPAN`]: the fastest
/// magnitude is at most RATE_SPAN times the slowest decay rate. Otherwise the rate farthest (by
/// ratio) from the median magnitude is named, with the range that the other lists leave it.
fn check_rate_span(spec: &DesignSpec) -> Result<(), DesignError> {
    // (key, pole or None for β, magnitude, decay rate)
    let mut rates: Vec<(String, Option<Complex<f64>>, f64, f64)> = Vec::new();
    let mut lists: Vec<(String, &[Complex<f64>])> = Vec::new();
    for (name, list) in [
        ("channel_poles", &spec.channel_poles),
        ("reference_filter_poles", &spec.reference_filter_poles),
        ("disturbance_filter_poles", &spec.disturbance_filter_poles),
    ] {
        lists.extend(list.iter().enumerate().map(|(i, p)| (format!("design.{name}[{i}]"), &p[..])));
    }
    if let ObserverChoice::Poles(p) = &spec.observer {
        lists.push(("design.observer_poles".into(), p));
    }
    for (key, poles) in lists {
        rates.extend(poles.iter().map(|&p| (key.clone(), Some(p), p.norm(), -p.re)));
    }
    rates.push(("design.beta".into(), None, 1.0 / spec.beta, 1.0 / spec.beta));
    // The fastest magnitude and the slowest decay rate outside the list `skip`.
    let span = |skip: &str| {
        let others = || rates.iter().filter(move |r| r.0 != skip);
        (others().map(|r| r.2).fold(0.0, f64::max), others().map(|r| r.3).fold(f64::INFINITY, f64::min))
    };
    let (fastest, slowest) = span("");
    if fastest <= RATE_SPAN * slowest {
        return Ok(());
    }
    let mut magnitudes: Vec<f64> = rates.iter().map(|r| r.2).collect();
    magnitudes.sort_by(f64::total_cmp);
    let median = magnitudes[magnitudes.len() / 2];
    let extremity = |r: &(String, Option<Complex<f64>>, f64, f64)| (r.2 / median).max(median / r.3);
    let blamed = (0..rates.len()).max_by(|&i, &j| extremity(&rates[i]).total_cmp(&extremity(&rates[j]))).unwrap_or(0);
    let (fast, slow) = span(&rates[blamed].0);
    let (min_decay, max_magnitude) = (fast / RATE_SPAN, slow * RATE_SPAN);
    Err(match &rates[blamed] {
        (key, Some(pole), ..) => DesignError::PoleOutOfSpan { key: key.clone(), pole: *pole, min_decay, max_magnitude },
        _ => DesignError::BetaOutOfSpan { value: spec.beta, min: 1.0 / max_magnitude, max: 1.0 / min_decay },
    })
}

/// Assumption 1: (A, B) controllable and (A, C) observable, by the staircase rank tests.
fn assumption_1(plant: &Plant) -> Result<(RankTest, RankTest), DesignError> {
    let n = plant.n();
    let ctrb = controllability(&plant.A, &plant.B)?;
    if !ctrb.full() {
        // A scaling verdict names no modes: every one would look hidden.
        let mut scaling = badly_scaled(&plant.A, &plant.B, "B", ctrb.tol);
        if scaling.is_empty() {
            scaling = hidden_modes(&plant.A.transpose(), &plant.B.transpose(), n - ctrb.rank, "no input reaches");
        }
        return Err(DesignError::Uncontrollable { rank: ctrb.rank, n, tol: ctrb.tol, scaling });
    }
    let obsv = observability(&plant.A, &plant.C)?;
    if !obsv.full() {
        let mut scaling = badly_scaled(&plant.A.transpose(), &plant.C.transpose(), "C", obsv.tol);
        if scaling.is_empty() {
            scaling = hidden_modes(&plant.A, &plant.C, n - obsv.rank, "no output shows");
        }
        return Err(DesignError::Unobservable { rank: obsv.rank, n, tol: obsv.tol, scaling });
    }
    Ok((ctrb, obsv))
}

/// The `count` eigenvalues λ of A (`At` = A with M = C for observability, Aᵀ with M = Bᵀ for
/// controllability) whose PBH matrix [At − λI; M] is nearest to losing rank, by its smallest
/// singular value relative to the matrix's norm: the modes the rank test found hidden, named for
/// the message (a pendulum measured by its angle alone: its cart's modes at 0 show in no output). ""
/// where the eigenvalues cannot be computed.
fn hidden_modes(At: &DMatrix<f64>, M: &DMatrix<f64>, count: usize, verb: &str) -> String {
    let Ok(lambdas) = eigenvalues(At) else { return String::new() };
    let n = At.nrows();
    let norm = At.norm() + M.norm();
    let nearness = |l: &Complex<f64>| {
        let mut P = nalgebra::DMatrix::<Complex<f64>>::zeros(n + M.nrows(), n);
        P.view_mut((0, 0), (n, n)).copy_from(&At.map(|a| Complex::new(a, 0.0)));
        for i in 0..n {
            P[(i, i)] -= l;
        }
        P.view_mut((n, 0), (M.nrows(), n)).copy_from(&M.map(|a| Complex::new(a, 0.0)));
        P.singular_values().min() / norm.max(f64::MIN_POSITIVE)
    };
    // One SVD per eigenvalue (a comparison sort had made two per comparison).
    let mut near: Vec<(f64, Complex<f64>)> = lambdas.iter().map(|l| (nearness(l), *l)).collect();
    near.sort_by(|a, b| a.0.total_cmp(&b.0));
    let lambdas: Vec<Complex<f64>> = near.into_iter().take(count).map(|(_, l)| l).collect();
    if lambdas.is_empty() {
        return String::new();
    }
    let modes = if count == 1 { "the mode" } else { "the modes" };
    format!("; {verb} {modes} at {}", fmt_complex_list(&lambdas))
}

/// Where the rank test's tolerance erases couplings of the plant, the verdict says more about its
/// scaling than its structure: in the pair the test takes (B or C scaled to A's size, the states
/// balanced: [`assumptions::conditioned`]), a nonzero entry of A or of `M` (B, or Cᵀ) at or below
/// the tolerance (the paper's plant with A[2][2] = −1e15: a tolerance of 6.7 beside couplings of
/// 0.3). The text appended to the error, or "".
fn badly_scaled(A: &DMatrix<f64>, M: &DMatrix<f64>, name: &str, tol: f64) -> String {
    let (A, M) = assumptions::conditioned(A, M);
    // Couplings only: a diagonal entry (a near-integrator's 1e-20) is no scaling matter, and the
    // modes hidden behind it are named instead.
    let couplings = A.iter().enumerate().filter(|(k, _)| k % A.nrows() != k / A.nrows()).map(|(_, x)| x);
    let erased = couplings.chain(M.iter()).map(|x| x.abs()).filter(|&x| x > 0.0 && x <= tol);
    let Some(small) = erased.reduce(f64::min) else { return String::new() };
    let largest = A.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    format!(
        "; but the tolerance follows A's largest entries ({}, with the states balanced and {name} scaled to A) and counts couplings as small as {} as zero: the plant's numbers span too many decades for a rank test in double precision, balanced or not, so rewrite the model so that its couplings are of comparable size (e.g. leave a fast mode out) before concluding",
        fmt_number(largest),
        fmt_number(small)
    )
}

/// The observer gain L of eq. (6), given or placed by duality (L = place(Aᵀ, Cᵀ, p)ᵀ), and
/// eig(A − LC), which must be Hurwitz.
fn observer(plant: &Plant, choice: &ObserverChoice) -> Result<(DMatrix<f64>, Vec<Complex<f64>>), DesignError> {
    let (n, m) = (plant.n(), plant.m());
    let (A, C) = (&plant.A, &plant.C);
    let (L, key) = match choice {
        ObserverChoice::Gain(L) => {
            if L.nrows() != n || L.ncols() != m {
                return Err(DesignError::ObserverGainShape { n, m, rows: L.nrows(), cols: L.ncols() });
            }
            if let Some(i) = L.iter().position(|v| !v.is_finite()) {
                return Err(DesignError::ObserverGainNonFinite { row: i % n, col: i / n, value: L[i] });
            }
            (L.clone(), "design.observer_gain")
        }
        ObserverChoice::Poles(p) => (
            place(&A.transpose(), &C.transpose(), p)
                // One output: a repeated pole is placed as `acker` does (a fragile-gain warning
                // follows), as a textbook observer with every pole at one value asks.
                .or_else(|e| match e {
                    PlaceError::Multiplicity { rank: 1, .. } => acker(&A.transpose(), &C.transpose(), p),
                    e => Err(e),
                })
                .map_err(|e| match e {
                    PlaceError::Interrupted => DesignError::Interrupted,
                    e => DesignError::ObserverPoles(e),
                })?
                .transpose(),
            "design.observer_poles",
        ),
    };
    let A_o = A - &L * C;
    let eigs = eigenvalues(&A_o).map_err(|e| eigen_error(key, "A − LC", e))?;
    check_observer_hurwitz(plant, key, &L, &A_o, eigs.clone())?;
    Ok((L, eigs))
}

/// A − LC must be Hurwitz. Every computed eigenvalue left of the rounding margin −√ε·‖A − LC‖_F
/// ([`unstable`]) passes at once. Otherwise the margin, which grows with ‖A − LC‖ (≈ 15 for the
/// observer of a 12-state chain with poles −2 … −9.7, whose ‖A − LC‖_F ≈ 1e9), decides nothing by
/// itself: each eigenvalue is refined in twice the working precision
/// ([`place::refined_left_half_plane`]) and judged by its refined value and error. A computed
/// eigenvalue with a real part ≥ 0 is [`DesignError::ObserverUnstable`]; one whose sign refining
/// cannot settle is [`DesignError::ObserverUnconfirmed`], with κ₂ of the eigenvectors.
fn check_observer_hurwitz(
    plant: &Plant,
    key: &'static str,
    L: &DMatrix<f64>,
    A_o: &DMatrix<f64>,
    eigs: Vec<Complex<f64>>,
) -> Result<(), DesignError> {
    let in_margin = unstable(&eigs, A_o.norm());
    if in_margin.is_empty() || place::refined_left_half_plane(A_o, &eigs) {
        return Ok(());
    }
    if eigs.iter().any(|z| z.re >= 0.0) {
        return Err(DesignError::ObserverUnstable { key, eigenvalues: eigs });
    }
    let kappa = place::closed_loop_condition(&plant.A.transpose(), &plant.C.transpose(), &L.transpose());
    let margin = f64::EPSILON.sqrt() * A_o.norm().max(1.0);
    Err(DesignError::ObserverUnconfirmed { key, eigenvalues: eigs, in_margin, margin, kappa })
}

/// The zero dynamics of the decoupled loop (Proposition 1): A − BK places the Σσ_i channel poles
/// on the observable part of (A − BK, C), spanned by the rows c_i A^j, j < σ_i; its other
/// n − Σσ_i eigenvalues are the plant's zeros. They are the eigenvalues of A − BK restricted to
/// the invariant subspace ker [c_i A^j] (an orthonormal basis W: zeros = eig(Wᵀ (A − BK) W)), so
/// they are judged without the placed, possibly repeated, channel poles. Each must be Hurwitz.
///
/// The restriction does not depend on the channel poles (K's terms in c_i A^j, j < σ_i, vanish on
/// ker), so it is formed with K_0 = B*⁻¹ [c_i A^σ_i] (every channel pole at 0): fast channel poles
/// make K large, and the rounding of A − BK with them would blur stable zeros (a disk drive's
/// lightly damped −14.5 ± 16532i rad/s at channel poles of −3770 rad/s). A zero inside the rounding
/// margin [`unstable`] is refined in twice the working precision and judged by its refined value,
/// as the observer's eigenvalues are.
/// The least damping −Re z/|z| of a zero the refinement may settle as stable: below it the zero is
/// on the imaginary axis to the rounding of its computation (a disk drive's −14.5 ± 16532i has 9e-4).
const AXIS_DAMPING: f64 = 1e-12;
/// A zero within this many ε·‖Z‖ of the origin is at s = 0 to the rounding of its computation.
const ORIGIN_ROUNDING: f64 = 1e3;

fn check_zero_dynamics(plant: &Plant, fw: &FalbWolovich) -> Result<Vec<Complex<f64>>, DesignError> {
    let n = plant.n();
    let sigma = fw.sigma();
    let placed: usize = sigma.iter().sum();
    let Z = zero_dynamics_matrix((&plant.A, &plant.B, &plant.C), fw);
    if Z.ncols() == 0 {
        return Ok(vec![]);
    }
    let zeros = eigenvalues(&Z).map_err(|e| eigen_error("plant", "the zero dynamics of A − BK", e))?;
    let bad = unstable(&zeros, Z.norm());
    // A zero on the imaginary axis comes out at Re ≈ ±1e-17 |z|: damping beyond AXIS_DAMPING is
    // needed to count as stable (s² + 1.69 had passed as "max Re λ = 0.00000" and its run grew).
    // A zero within rounding of the origin has no damping to judge (one exactly at 0, computed as
    // −1e-17, had passed, and its run's u_f grew without end).
    // Within rounding of the origin on Z's scale, or on A's, from which Z is formed (n·ε·‖A‖: a
    // 1×1 Z of 2.4e-14 from a power system's A of norm 1.8e3 is a zero at 0; one of −2.2e-16 from a
    // two-area power system's tie-line integrator, ‖A‖ = 18, had passed as a stable zero, and its
    // tie-line power drifted without end). Z's refinement cannot tell such a zero's sign: the
    // rounding is in forming Z, not in its eigenvalues.
    let origin = f64::EPSILON * (ORIGIN_ROUNDING * Z.norm()).max(n as f64 * plant.A.norm());
    let damped = |z: &Complex<f64>| z.re < -AXIS_DAMPING * z.norm() && z.norm() > origin;
    let settled = || zeros.iter().all(damped) && place::refined_left_half_plane(&Z, &zeros);
    if bad.is_empty() || settled() {
        Ok(bad)
    } else {
        debug_assert_eq!(zeros.len(), n - placed);
        // At the origin to rounding: reported as 0, not as its computed −3e-16.
        let at = |z: &Complex<f64>| if z.norm() <= origin { Complex::new(0.0, 0.0) } else { *z };
        let zeros = zeros.iter().map(at).collect();
        let unstable: Vec<Complex<f64>> = bad.iter().map(at).collect();
        Err(DesignError::UnstableZeroDynamics {
            placed,
            zeros,
            mirrored: mirrors_poles(&plant.A, &unstable),
            unstable,
            unit: plant.time_unit,
        })
    }
}

/// Relative distance within which a zero z mirrors an eigenvalue −z̄ of A ([`mirrors_poles`]): a
/// Padé approximation of order 5 has its zeros computed 1e-5 off their mirrors (python-control's
/// own zeros too), so a millionth had missed it.
const MIRROR_TOLERANCE: f64 = 1e-4;

/// Every zero of `unstable` is in the open right half-plane and mirrors an eigenvalue of `A`
/// across the imaginary axis (−z̄ within [`MIRROR_TOLERANCE`]·|z|): the zeros of an all-pass
/// factor, which a Padé approximation of a delay multiplies a plant by (a pendulum given as
/// G(s)·pade(0.05 s, 2) had been told only to measure other outputs; helper tryout, 2026-12-07).
fn mirrors_poles(A: &DMatrix<f64>, unstable: &[Complex<f64>]) -> bool {
    let Ok(poles) = eigenvalues(A) else { return false };
    let mirrored = |z: &Complex<f64>| {
        let image = Complex::new(-z.re, z.im);
        z.re > 0.0 && poles.iter().any(|p| (p - image).norm() <= MIRROR_TOLERANCE * z.norm())
    };
    !unstable.is_empty() && unstable.iter().all(mirrored)
}

/// Wᵀ (A − B K_0) W on the zero dynamics' subspace (W its orthonormal basis, [`zero_dynamics_basis`];
/// K_0 [`FalbWolovich::zero_pole_gain`]): its eigenvalues are the zeros of the square (A, B, C).
fn zero_dynamics_matrix((A, B, C): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>), fw: &FalbWolovich) -> DMatrix<f64> {
    let W = zero_dynamics_basis(A, C, &fw.sigma());
    W.transpose() * (A - B * fw.zero_pole_gain(A, C)) * &W
}

/// The zeros of a square (A, B, C) that Proposition 1 decouples (every output reached, B*
/// invertible), as the eigenvalues of its zero dynamics; `None` otherwise. For (A, D, C) when CD is
/// singular (a disturbance entering with the input of a relative-degree-2 plant), the zeros the
/// disturbance observer's poles can hold.
pub fn decoupling_zeros(A: &DMatrix<f64>, B: &DMatrix<f64>, C: &DMatrix<f64>) -> Option<Vec<Complex<f64>>> {
    let sigma: Vec<usize> = relative_degrees(A, B, C).ok()?.into_iter().collect::<Option<_>>()?;
    let at_zero: Vec<Vec<Complex<f64>>> = sigma.iter().map(|&s| vec![Complex::new(0.0, 0.0); s]).collect();
    let fw = falb_wolovich(A, B, C, &at_zero).ok()?;
    eigenvalues(&zero_dynamics_matrix((A, B, C), &fw)).ok()
}

/// Orthonormal basis (n × (n − Σσ_i)) of the kernel of the rows c_i A^j, j < σ_i, each row scaled
/// to unit norm: the unobservable subspace of the decoupled loop.
fn zero_dynamics_basis(A: &DMatrix<f64>, C: &DMatrix<f64>, sigma: &[usize]) -> DMatrix<f64> {
    let n = A.nrows();
    let placed: usize = sigma.iter().sum();
    let mut T = DMatrix::zeros(n, n); // padded to square so the SVD returns all of V
    let mut r = 0;
    for (i, &s) in sigma.iter().enumerate() {
        let mut row = C.row(i).clone_owned();
        for _ in 0..s {
            let nrm = row.norm();
            if nrm > 0.0 {
                row /= nrm;
            }
            T.set_row(r, &row);
            row = &row * A;
            r += 1;
        }
    }
    let svd = T.svd(false, true);
    let Vt = svd.v_t.expect("requested");
    // Singular values are sorted descending: the last n − Σσ_i right vectors span the kernel.
    Vt.rows(placed, n - placed).transpose()
}

/// N = L_ω D⁺, the minimum-norm solution of N D = L_ω (eq. (20)), and the condition number of D
/// with unit columns, whose smallest singular value must be ≥ τ ([`TOL`]); rank D = k is required.
fn disturbance_observer_gain(D: &DMatrix<f64>, L_w: &DMatrix<f64>) -> Result<(DMatrix<f64>, f64), DesignError> {
    let (n, k) = (D.nrows(), D.ncols());
    let rank = numerical_rank(D);
    if rank < k {
        return Err(DesignError::DisturbanceRank { rank, k });
    }
    if k == 0 {
        return Ok((DMatrix::zeros(0, n), 1.0));
    }
    let pinv = D
        .clone()
        .pseudo_inverse(f64::EPSILON * n as f64 * D.norm())
        .map_err(|_| DesignError::DisturbanceRank { rank, k })?;
    let N = L_w * pinv;
    let unit = decouple::unit_columns(D);
    let (smallest, cond_D) = singular_extremes(&unit);
    if smallest < TOL {
        return Err(DesignError::DisturbanceConditioning { smallest, cond: cond_D, norm_N: N.norm() });
    }
    Ok((N, cond_D))
}

/// The error for eigenvalues that could not be computed, with the reason a user can act on.
fn eigen_error(key: &'static str, of: &'static str, e: EigenError) -> DesignError {
    let reason = match (e, key) {
        (EigenError::NonFinite, "design.observer_gain") => {
            "the matrix overflows double precision (its Frobenius norm is beyond 1.8e308); give a smaller design.observer_gain"
        }
        (EigenError::NonFinite, _) => {
            "the matrix overflows double precision (its Frobenius norm is beyond 1.8e308); rescale the plant's units"
        }
        (EigenError::NoConvergence, _) => {
            "faer's QR iteration did not converge, which should not happen for finite input; please report the scenario"
        }
    };
    DesignError::Eigenvalues { key, of, reason }
}

/// [`Design::checks`]: the figures behind the assumption checks.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct AssumptionChecks {
    /// Assumption 1: the ranks of the controllability and observability matrices and their
    /// tolerances ([`RankTest`]).
    pub controllability_rank: usize,
    pub controllability_tol: f64,
    pub observability_rank: usize,
    pub observability_tol: f64,
    /// Proposition 1: cond₂(B*) with its rows and columns equilibrated (scale-free, so not
    /// `numpy.linalg.cond` of B* itself).
    pub cond_B_star: f64,
    /// cond₂(D) with unit columns.
    pub cond_D: f64,
    /// The tolerance [`TOL`] of the scale-free decisions.
    pub tolerance: f64,
    /// Per output, eq. (7)'s measures up to σ_i, whether one lies within a factor 100 of the
    /// tolerance, and σ_i where `design.relative_degrees` gave it.
    pub relative_degree_measures: Vec<Vec<f64>>,
    pub relative_degree_close: Vec<bool>,
    pub relative_degrees_given: Vec<Option<usize>>,
    /// The largest real parts of eig(A − BK) and eig(A − LC).
    pub max_re_decoupled_eigenvalue: f64,
    pub max_re_observer_eigenvalue: f64,
    /// rank D: the disturbance components k.
    pub disturbance_rank: usize,
}
