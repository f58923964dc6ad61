//! The adaptive loop in steady state, from the design and the signals alone (averaging).
//!
//! With x̂ − x independent of u (observer (6)) and the decoupler in place, the regressor ξ̂ is a
//! linear image of g and ω only: ξ̂_g = (sI − G_g)⁻¹ L_g g (14) and, from (20) with x̂ in place of x,
//! ξ̂_ω = (sI − G_ω)⁻¹ T(s) ω with T(s) = N L [C (sI − A + LC)⁻¹ (D − LQ) + Q] (N D = L_ω only when
//! x̂ = x). For signals that are sums of sines and biases every filtered signal is a sum of
//! phasors, so the time averages that set the adaptive law's pace follow in closed form:
//!
//! * Ω̄_i = mean of Δ_iᵀ Δ_i (eq. (33), Δ_i = G_ii(s)[ξ̂ᵀ(t − τ_i)]): what Ω_i = H[Δ_iᵀ Δ_i]
//!   settles to, up to a ripple at the sum and difference frequencies that H attenuates;
//! * Ȳ_i = mean of Δ_iᵀ ε̂_i with ε̂_i = δ_i of the loop without adaptive command (u = 0): the
//!   augmented error does not depend on η̂, so η̂_i → η*_i = Ω̄_i⁺ Ȳ_i;
//! * the averaged law η̃' = −μ_i Ω̄_i η̃ with η̃(0) = η*_i (η̂(0) = 0) and e_i ≈ Δ_i η̃ give the RMS
//!   tracking error at time t: √(η̃(t)ᵀ Ω̄_i η̃(t) + r_i²), r_i the part of δ_i no η explains.

use nalgebra::{Complex, DMatrix, DVector};

use crate::design::Design;
use crate::signal::Signal;

type C64 = Complex<f64>;

/// One frequency of the signals (0 for the biases) and the phasors of g and ω there:
/// a·sin(wt + φ) = Re(−j a e^{jφ} e^{jwt}); a constant b is the real phasor b at w = 0.
#[derive(Debug, Clone)]
pub(crate) struct Tone {
    pub(crate) w: f64,
    pub(crate) g: DVector<C64>,
    pub(crate) omega: DVector<C64>,
}

/// Every distinct frequency of g and ω with their phasors, ascending.
pub(crate) fn tones(reference: &Signal, disturbance: &Signal) -> Vec<Tone> {
    let (m, k) = (reference.len(), disturbance.len());
    let mut tones: Vec<Tone> = Vec::new();
    let mut add = |w: f64, which: usize, index: usize, phasor: C64| {
        // Frequencies a few ulps apart (0.2617993877991494 and 0.26179938779914946) are one tone:
        // over any horizon they stay in phase.
        let at = match tones.iter().position(|t| (t.w - w).abs() <= 1e-12 * t.w.max(w)) {
            Some(at) => at,
            None => {
                tones.push(Tone { w, g: DVector::zeros(m), omega: DVector::zeros(k) });
                tones.len() - 1
            }
        };
        let v = if which == 0 { &mut tones[at].g } else { &mut tones[at].omega };
        v[index] += phasor;
    };
    for (which, signal) in [reference, disturbance].into_iter().enumerate() {
        for (index, c) in signal.components.iter().enumerate() {
            if c.bias != 0.0 {
                add(0.0, which, index, C64::new(c.bias, 0.0));
            }
            for h in &c.harmonics {
                let phasor = if h.frequency == 0.0 {
                    C64::new(h.amplitude * h.phase.sin(), 0.0)
                } else {
                    C64::new(0.0, -h.amplitude) * C64::from_polar(1.0, h.phase)
                };
                add(h.frequency, which, index, phasor);
            }
        }
    }
    tones.sort_by(|a, b| a.w.total_cmp(&b.w));
    tones
}

pub(crate) fn complex(M: &DMatrix<f64>) -> DMatrix<C64> {
    M.map(|x| C64::new(x, 0.0))
}

/// (jwI − M)⁻¹ B; M must have no eigenvalue at jw (Hurwitz matrices here).
pub(crate) fn resolvent(M: &DMatrix<f64>, w: f64, B: &DMatrix<C64>) -> DMatrix<C64> {
    if M.nrows() == 0 || B.ncols() == 0 {
        return DMatrix::zeros(M.nrows(), B.ncols());
    }
    let mut S = -complex(M);
    for i in 0..M.nrows() {
        S[(i, i)] += C64::new(0.0, w);
    }
    S.lu().solve(B).unwrap_or_else(|| DMatrix::from_element(B.nrows(), B.ncols(), C64::new(f64::NAN, 0.0)))
}

/// (jwI − M)⁻¹ b for one column b.
fn resolvent_vec(M: &DMatrix<f64>, w: f64, b: DVector<C64>) -> DVector<C64> {
    let n = b.len();
    resolvent(M, w, &DMatrix::from_column_slice(n, 1, b.as_slice())).column(0).into_owned()
}

/// |v|∞ of a phasor vector.
fn largest(v: &DVector<C64>) -> f64 {
    v.iter().map(|v| v.norm()).fold(0.0, f64::max)
}

/// The plant's state at one tone when its output follows the reference against the disturbance,
/// y = C x + Q ω = g, whatever input v reaches it (after its delays): the solution of Rosenbrock's
/// system [jwI − A, −B; C, 0] [x; v] = [D ω; g − Q ω]. What x is while the loop tracks, and an
/// unmeasured state that C does not bound (σ_min(C)) can be far larger than y. `None` where the
/// system, rows and columns equilibrated, is singular to working precision, σ_min < √ε σ_max (a
/// zero of the plant at jw, or damped within rounding of it: its steady state is reached only over
/// 1/|Re z|, and at −1e-11 ± j a tone at 1 rad/s had raised x's bound to 5e13), or the solution is
/// not finite.
pub(crate) fn tracking_state(p: &crate::plant::Plant, tone: &Tone) -> Option<DVector<C64>> {
    let (n, m) = (p.n(), p.m());
    let mut S = DMatrix::<C64>::zeros(n + m, n + m);
    S.view_mut((0, 0), (n, n)).copy_from(&-complex(&p.A));
    for i in 0..n {
        S[(i, i)] += C64::new(0.0, tone.w);
    }
    S.view_mut((0, n), (n, m)).copy_from(&-complex(&p.B));
    S.view_mut((n, 0), (m, n)).copy_from(&complex(&p.C));
    let mut rhs = DVector::<C64>::zeros(n + m);
    rhs.rows_mut(0, n).copy_from(&(complex(&p.D) * &tone.omega));
    rhs.rows_mut(n, m).copy_from(&(&tone.g - complex(&p.Q) * &tone.omega));
    // Judged with S's rows and columns equilibrated, so that the units do not decide.
    let sv = crate::linalg::equilibrated(S.clone()).singular_values();
    let singular = sv.min() < f64::EPSILON.sqrt() * sv.max();
    if singular || !sv.min().is_finite() {
        return None;
    }
    let x = S.lu().solve(&rhs)?.rows(0, n).into_owned();
    x.iter().all(|v| v.re.is_finite() && v.im.is_finite()).then_some(x)
}

/// The weight of a product's mean: mean(Re(X e^{jwt}) Re(Y e^{jwt})) = weight · Re(X Ȳ).
fn weight(w: f64) -> f64 {
    if w == 0.0 {
        1.0
    } else {
        0.5
    }
}

/// The disturbance observer's input gain T(jw) = N L [C (jwI − A + LC)⁻¹ (D − LQ) + Q]
/// (q_ω × k); equal to N D = L_ω when the observer reproduces x. A component of ω that reaches no
/// output at w (the steady input that holds y = 0 against it alone is zero) has a zero column: the innovation it
/// drives is then exactly zero, where its rounding (1e-19 for a missile's gust bias) had counted
/// as an excited direction of Ω̄ and asked for μ = 1.6e38 (helper tryout, 2026-12-08).
pub fn disturbance_observer_gain(design: &Design, w: f64) -> DMatrix<C64> {
    let p = design.plant();
    let (L, N) = (design.L(), design.N());
    let A_o = &p.A - L * &p.C;
    let E = complex(&(&p.D - L * &p.Q));
    let mut T = complex(&(N * L)) * (complex(&p.C) * resolvent(&A_o, w, &E) + complex(&p.Q));
    for j in crate::diagnostics::effort::unreached(p, w) {
        T.column_mut(j).fill(C64::new(0.0, 0.0));
    }
    T
}

/// How faithfully the disturbance observer (20) passes one frequency of ω: with T = L_ω (I + E),
/// E(jw) the error of the estimate of ω that T passes (k × k, in ω's coordinates), the relative
/// error ‖W⁻¹ E W e_α‖ of each component α with energy at w, W = diag(peak of each component of
/// ω), largest over those α: each estimated component's error against its own size, so that ω's
/// units do not move it (W E W⁻¹ is the same in any), nor the states' where the loop stays the
/// same. A component of ω that is 0 throughout has no size to hold an error against and is left
/// out. Measured as ‖(T − L_ω) e_α‖ / ‖L_ω e_α‖, in ξ̂_ω's units, one component × 1e2 had moved it
/// from 1.4 to 13,446; measured by ω's effect on the states, a velocity in mm/s had.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Fidelity {
    /// rad/s (0: the biases).
    pub frequency: f64,
    pub relative_error: f64,
}

/// The excitation one frequency gives channel i's Ω̄_i: the smaller nonzero eigenvalue of its
/// rank-2 part (the larger one of its rank-1 part at w = 0). Ω̄_i is the sum of these parts, so a
/// frequency whose excitation is tiny leaves a direction of η̂_i that converges slowly.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Excitation {
    /// rad/s (0: the biases).
    pub frequency: f64,
    pub excitation: f64,
}

/// Channel i in steady state.
#[derive(Debug, Clone)]
pub struct ChannelAverage {
    /// Ω̄_i (q × q, symmetric positive semidefinite).
    pub omega: DMatrix<f64>,
    /// Eigenvalues of Ω̄_i, ascending: 0 for the q − r directions the signals leave unexcited,
    /// then the r excited ones (counted whatever ξ̂'s units and the signals' amplitudes).
    pub lambda: Vec<f64>,
    /// The excited eigenvalues' eigenvectors (q × r), in the order of `lambda`'s last r.
    vectors: DMatrix<f64>,
    /// Ȳ_i.
    pub y: DVector<f64>,
    /// RMS of δ_i without adaptive command (the error η̂_i has to remove).
    pub open_loop_rms: f64,
    /// RMS of the part of δ_i that no η explains (0 when the internal models are exact).
    pub residual_rms: f64,
    pub excitation: Vec<Excitation>,
}

impl ChannelAverage {
    /// λ_min(Ω̄_i).
    pub fn lambda_min(&self) -> f64 {
        self.lambda.first().copied().unwrap_or(0.0)
    }
    /// λ_max(Ω̄_i).
    pub fn lambda_max(&self) -> f64 {
        self.lambda.last().copied().unwrap_or(0.0)
    }

    /// The excited directions: (k, λ_k), column k of `vectors` with its eigenvalue ([`spectrum`]
    /// decides which they are, whatever the units of ξ̂'s entries).
    fn excited_modes(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.lambda[self.lambda.len() - self.vectors.ncols()..].iter().copied().enumerate()
    }

    /// The eigenvalues of the excited directions.
    pub fn excited(&self) -> impl Iterator<Item = f64> + '_ {
        self.excited_modes().map(|(_, l)| l)
    }

    /// The directions that matter: the excited eigenvalues λ_k with the energy (v_kᵀ Ȳ)²/λ_k that
    /// the error carries along them at t = 0 (η̃(0) = η*).
    fn modes(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.excited_modes().map(move |(k, l)| {
            let c = self.vectors.column(k).dot(&self.y);
            (l, c * c / l)
        })
    }

    /// η*_i = Ω̄_i⁺ Ȳ_i over the excited directions: what η̂_i settles to (module docs).
    pub fn eta_star(&self) -> DVector<f64> {
        self.excited_modes().fold(DVector::zeros(self.y.len()), |eta, (k, l)| {
            let v = self.vectors.column(k);
            eta + v * (v.dot(&self.y) / l)
        })
    }

    /// The averaged law's RMS tracking error at time t for adaptation gain μ:
    /// √(Σ_k e_k exp(−2μλ_k t) + r²) (`ChannelAverage::modes`).
    pub fn predicted_error(&self, mu: f64, t: f64) -> f64 {
        let sum: f64 = self.modes().map(|(l, e)| e * (-2.0 * mu * l * t).exp()).sum();
        (sum + self.residual_rms.powi(2)).sqrt()
    }

    /// The slowest eigenvalue that carries at least `share` of the initial error energy: the λ
    /// whose rate μλ decides when the error falls below √share of its start.
    pub fn slowest_relevant(&self, share: f64) -> f64 {
        let total: f64 = self.modes().map(|(_, e)| e).sum();
        self.modes().filter(|(_, e)| *e >= share * total).map(|(l, _)| l).fold(f64::INFINITY, f64::min)
    }
}

/// The steady state of a design's adaptive loop for the given signals.
#[derive(Debug, Clone)]
pub struct Averaged {
    pub channels: Vec<ChannelAverage>,
    /// Per nonzero-energy frequency of ω.
    pub fidelity: Vec<Fidelity>,
    /// max_j Σ_tones |ξ̂_j|: a bound of the steady-state regressor's entries, the size ξ̂ has in its
    /// own units (1e9 for forces in newtons in the paper's form).
    pub xi_peak: f64,
    /// Σ_tones (max(|g|∞/σ_min(C), |x_g|∞) + |[x; x̂]|∞ driven by ω without adaptive command), x_g
    /// the state of y = g against ω (Rosenbrock's system at each tone): the size the plant's and
    /// the observer's states have in their own units (7e12 for a heat store in joules; an
    /// unmeasured state in units 1e9 smaller than the outputs' is 1e9 while y follows g).
    pub x_peak: f64,
}

impl Averaged {
    /// Ω̄_i, Ȳ_i and the rest for every channel of `design` under g = `reference`, ω = `disturbance`.
    pub fn new(design: &Design, reference: &Signal, disturbance: &Signal) -> Averaged {
        let p = design.plant();
        let (m, n, q) = (p.m(), p.n(), design.q());
        let tones = tones(reference, disturbance);
        // The loop without adaptive command: z = [x; x̂], z' = M z + [D; LQ] ω, y = C x + Q ω.
        let (L, K) = (design.L(), design.K());
        let mut M = DMatrix::zeros(2 * n, 2 * n);
        M.view_mut((0, 0), (n, n)).copy_from(&p.A);
        M.view_mut((0, n), (n, n)).copy_from(&(-(&p.B * K)));
        M.view_mut((n, 0), (n, n)).copy_from(&(L * &p.C));
        M.view_mut((n, n), (n, n)).copy_from(&(design.A_f() - L * &p.C));
        let mut E = DMatrix::zeros(2 * n, p.k());
        E.view_mut((0, 0), (n, p.k())).copy_from(&p.D);
        E.view_mut((n, 0), (n, p.k())).copy_from(&(L * &p.Q));
        let mut C_z = DMatrix::zeros(m, 2 * n);
        C_z.view_mut((0, 0), (m, n)).copy_from(&p.C);
        // Per tone: ξ̂ (q) and δ without adaptive command (m).
        let (mut fidelity, omega_sizes) = (Vec::new(), OmegaSizes::new(design, disturbance));
        let (mut x_peak, smallest_gain) = (0.0, crate::sim::smallest_gain(&p.C));
        let per_tone: Vec<(f64, DVector<C64>, DVector<C64>)> = tones
            .iter()
            .map(|tone| {
                let T = disturbance_observer_gain(design, tone.w);
                fidelity.extend(fidelity_at(&omega_sizes, tone, &T));
                let xi_g = resolvent_vec(design.G_g(), tone.w, complex(design.L_g()) * &tone.g);
                let xi_w = resolvent_vec(design.G_w(), tone.w, &T * &tone.omega);
                let mut xi = DVector::zeros(q);
                xi.rows_mut(0, design.q_g()).copy_from(&xi_g);
                xi.rows_mut(design.q_g(), design.q_w()).copy_from(&xi_w);
                let z = resolvent_vec(&M, tone.w, complex(&E) * &tone.omega);
                let y = complex(&C_z) * &z + complex(&p.Q) * &tone.omega;
                let tracking = tracking_state(p, tone).map_or(0.0, |x| largest(&x));
                x_peak += (largest(&tone.g) / smallest_gain).max(tracking) + largest(&z);
                (tone.w, xi, y - &tone.g)
            })
            .collect();
        let channels = (0..m).map(|i| channel(design, i, &per_tone)).collect();
        let xi_peak = (0..q).map(|j| per_tone.iter().map(|(_, xi, _)| xi[j].norm()).sum::<f64>()).fold(0.0, f64::max);
        Averaged { channels, fidelity, xi_peak, x_peak }
    }
}

/// What [`Fidelity`] holds the estimate's error against: L_ω⁺, which reads I + E = L_ω⁺ T from T,
/// and each component's peak.
struct OmegaSizes {
    L_w_pinv: DMatrix<C64>,
    peaks: Vec<f64>,
}

impl OmegaSizes {
    fn new(design: &Design, disturbance: &Signal) -> OmegaSizes {
        let L_w = design.L_w();
        let pinv = if L_w.is_empty() {
            DMatrix::zeros(L_w.ncols(), L_w.nrows())
        } else {
            L_w.clone().pseudo_inverse(f64::EPSILON * L_w.norm()).unwrap_or_else(|_| L_w.transpose())
        };
        OmegaSizes { L_w_pinv: complex(&pinv), peaks: disturbance.components.iter().map(|c| c.peak()).collect() }
    }
}

/// Fidelity of the disturbance observer at one tone, over the components of ω with energy there.
fn fidelity_at(sizes: &OmegaSizes, tone: &Tone, T: &DMatrix<C64>) -> Option<Fidelity> {
    let peaks = &sizes.peaks;
    let E = &sizes.L_w_pinv * T - DMatrix::<C64>::identity(peaks.len(), peaks.len());
    tone.omega
        .iter()
        .enumerate()
        .filter(|(_, a)| a.norm() > 0.0)
        .map(|(alpha, _)| {
            let sized = (0..peaks.len()).filter(|&beta| peaks[beta] > 0.0);
            sized.map(|beta| (E[(beta, alpha)].norm() * peaks[alpha] / peaks[beta]).powi(2)).sum::<f64>().sqrt()
        })
        .reduce(f64::max)
        .map(|relative_error| Fidelity { frequency: tone.w, relative_error })
}

/// Channel i's averages from the tones' ξ̂ and δ phasors.
fn channel(design: &Design, i: usize, tones: &[(f64, DVector<C64>, DVector<C64>)]) -> ChannelAverage {
    let q = design.q();
    let tau = design.plant().delays[i];
    let G = &design.channels()[i];
    let mut y = DVector::zeros(q);
    let (mut open_loop, mut excitation) = (0.0, Vec::new());
    // Ω̄ = F Fᵀ, F's columns √c·u and √c·v of each tone (a bias's v is 0 and left out).
    let mut factor: Vec<DVector<f64>> = Vec::new();
    for (w, xi, delta) in tones {
        let a = xi * (G.eval(C64::new(0.0, *w)) * C64::from_polar(1.0, -w * tau));
        let (u, v) = (a.map(|z| z.re), a.map(|z| z.im));
        let c = weight(*w);
        y += (&u * delta[i].re + &v * delta[i].im) * c;
        open_loop += c * delta[i].norm_sqr();
        excitation.push(Excitation { frequency: *w, excitation: c * tone_excitation(&u, &v, *w == 0.0) });
        factor.extend([&u, &v].into_iter().filter(|x| x.iter().any(|&e| e != 0.0)).map(|x| x * c.sqrt()));
    }
    let F = DMatrix::from_fn(q, factor.len(), |r, k| factor[k][r]);
    let omega = &F * F.transpose();
    let (lambda, vectors) = spectrum(&F);
    let mut avg =
        ChannelAverage { omega, lambda, vectors, y, open_loop_rms: open_loop.sqrt(), residual_rms: 0.0, excitation };
    let explained: f64 = avg.modes().map(|(_, e)| e).sum();
    avg.residual_rms = (open_loop - explained).max(0.0).sqrt();
    avg
}

/// The nonzero eigenvalue that a tone's part u uᵀ + v vᵀ of Ω̄ adds (the larger one at w = 0, where
/// v = 0; else the smaller): those of [[u·u, u·v], [u·v, v·v]], the larger mean + half, the smaller
/// its determinant over the larger, the determinant a sum of squares of 2×2 minors
/// (Cauchy–Binet), where mean − half would cancel to rounding once u's entries span many orders.
fn tone_excitation(u: &DVector<f64>, v: &DVector<f64>, at_zero: bool) -> f64 {
    let (uu, uv, vv) = (u.dot(u), u.dot(v), v.dot(v));
    let large = 0.5 * (uu + vv) + (0.25 * (uu - vv).powi(2) + uv * uv).sqrt();
    let q = u.len();
    let minors = (0..q).flat_map(|a| (a + 1..q).map(move |b| (a, b)));
    let det: f64 = minors.map(|(a, b)| (u[a] * v[b] - u[b] * v[a]).powi(2)).sum();
    match (at_zero, large > 0.0) {
        (true, _) => large,
        (false, true) => det / large,
        (false, false) => 0.0,
    }
}

/// The eigenvalues of Ω̄ = F Fᵀ, ascending, with the eigenvectors of its r excited ones (q × r),
/// from the factor F (q × c: a column for each tone's real and imaginary part). The units of ξ̂'s
/// entries scale F's rows, and the signals' amplitudes its columns (one tone's, when one component
/// has energy there), so both are taken out:
///
/// * r is the rank of G = D_r⁻¹ F D_c⁻¹ (D_r F's row norms, D_c the column norms of D_r⁻¹F): its
///   singular values above 10^(−6.5) of the largest (eigenvalues of G Gᵀ above 1e-13 of the
///   largest: the phasors' rounding);
/// * the eigenpairs are those of R Rᵀ, F's rows sorted by norm and F = Q R (Householder), by
///   one-sided Jacobi on Rᵀ, the r largest: this keeps small eigenvalues to their relative accuracy
///   where F's rows or columns span many orders (Demmel & Veselić, "Jacobi's method is more
///   accurate than QR", SIAM J. Matrix Anal. Appl. 13, 1992). A symmetric QR eigensolver on Ω̄
///   itself loses every eigenvalue below ε·λ_max: forces in newtons beside positions in metres put
///   half the excited directions there.
fn spectrum(F: &DMatrix<f64>) -> (Vec<f64>, DMatrix<f64>) {
    let q = F.nrows();
    let mut lambda = vec![0.0; q];
    let r = unit_free_rank(F);
    if r == 0 {
        return (lambda, DMatrix::zeros(q, 0));
    }
    let (R, Q, rows) = sorted_qr(F);
    let mut J = R.transpose();
    let mut V = DMatrix::identity(J.ncols(), J.ncols());
    one_sided_jacobi(&mut J, &mut V);
    let mut order: Vec<(f64, usize)> = (0..J.ncols()).map(|c| (J.column(c).norm_squared(), c)).collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0));
    let QV = Q * V;
    let mut vectors = DMatrix::zeros(q, r);
    for (k, &(l, c)) in order[order.len() - r..].iter().enumerate() {
        lambda[q - r + k] = l;
        for (at, &row) in rows.iter().enumerate() {
            vectors[(row, k)] = QV[(at, c)];
        }
    }
    (lambda, vectors)
}

/// The rank of F with its rows, then its columns, scaled to unit norm ([`spectrum`]).
/// Signals beyond what a run accepts (a frequency of 2e300 rad/s) make F's entries infinite or NaN:
/// nothing is counted then (nalgebra's SVD of a NaN matrix does not end).
fn unit_free_rank(F: &DMatrix<f64>) -> usize {
    if F.is_empty() || !F.iter().all(|x| x.is_finite()) {
        return 0;
    }
    let inverse = |x: f64| if x > 0.0 { 1.0 / x } else { 0.0 };
    let mut G = F.clone();
    G.row_iter_mut().for_each(|mut r| r *= inverse(r.norm()));
    G.column_iter_mut().for_each(|mut c| c *= inverse(c.norm()));
    // Unit rows and columns: the QR iteration converges in a few sweeps; the cap only bounds it.
    let Some(svd) = nalgebra::SVD::try_new(G, false, false, f64::EPSILON, 10_000) else { return 0 };
    let top = svd.singular_values.iter().copied().fold(0.0, f64::max);
    svd.singular_values.iter().filter(|&&s| s > 10f64.powf(-6.5) * top).count()
}

/// Householder QR of M with its rows sorted by norm, largest first (row-wise stable for graded
/// rows, Powell & Reid): R, the thin Q of the sorted rows, and the sort.
fn sorted_qr(M: &DMatrix<f64>) -> (DMatrix<f64>, DMatrix<f64>, Vec<usize>) {
    let mut rows: Vec<usize> = (0..M.nrows()).collect();
    rows.sort_by(|&a, &b| M.row(b).norm().total_cmp(&M.row(a).norm()));
    let qr = M.select_rows(&rows).qr();
    (qr.r(), qr.q(), rows)
}

/// Hestenes' one-sided Jacobi: plane rotations from the right until G's columns are orthogonal to
/// working precision, accumulated in V (G V stays the input's G V). Then GᵀG = V diag(‖g_k‖²) Vᵀ.
fn one_sided_jacobi(G: &mut DMatrix<f64>, V: &mut DMatrix<f64>) {
    let n = G.ncols();
    for _sweep in 0..64 {
        let mut rotated = false;
        for p in 0..n {
            for k in p + 1..n {
                let (a, b, c) = (G.column(p).norm_squared(), G.column(k).norm_squared(), G.column(p).dot(&G.column(k)));
                if c.abs() <= f64::EPSILON * (a * b).sqrt() {
                    continue;
                }
                rotated = true;
                let zeta = (b - a) / (2.0 * c);
                let t = zeta.signum() / (zeta.abs() + zeta.hypot(1.0));
                let cs = 1.0 / t.hypot(1.0);
                let sn = cs * t;
                for M in [&mut *G, &mut *V] {
                    for i in 0..M.nrows() {
                        let (x, y) = (M[(i, p)], M[(i, k)]);
                        M[(i, p)] = cs * x - sn * y;
                        M[(i, k)] = sn * x + cs * y;
                    }
                }
            }
        }
        if !rotated {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Scenario;
    use crate::signal::{Component, Harmonic};

    /// A first-order plant with one sine reference: x' = −x + u_f, y = x, σ = 1, channel pole −2,
    /// reference filter poles −1, −3 for g = sin(2t), no disturbance, no delay.
    fn siso(delay: f64) -> Scenario {
        Scenario::from_toml(&format!(
            "[plant]\nA = [[-1.0]]\nB = [[1.0]]\nC = [[1.0]]\ndelays = [{delay}]\n\
             [design]\nobserver_poles = [-5.0]\nchannel_poles = [[-2.0]]\nreference_filter_poles = [[-1.0, -3.0]]\n\
             mu = [10.0]\nbeta = 1.0\n[reference]\ncomponents = [{{ harmonics = [{{ amplitude = 1.0, frequency = 2.0 }}] }}]\n"
        ))
        .unwrap()
    }

    #[test]
    fn frequencies_a_few_ulps_apart_are_one_tone() {
        // 2π/24 written two ways (a daily cycle in hours) and a distinct neighbour 1e-6 away.
        let h = |amplitude, frequency| Harmonic { amplitude, frequency, phase: 0.0 };
        let g = Signal { components: vec![Component { bias: 0.0, harmonics: vec![h(1.0, 0.2617993877991494)] }] };
        let w = Signal {
            components: vec![Component { bias: 0.0, harmonics: vec![h(1.0, 0.26179938779914946), h(1.0, 0.261799)] }],
        };
        let t = tones(&g, &w);
        assert_eq!(t.len(), 2, "{:?}", t.iter().map(|t| t.w).collect::<Vec<_>>());
        assert!(t[1].g[0].norm() == 1.0 && t[1].omega[0].norm() == 1.0);
    }

    #[test]
    fn omega_bar_is_the_closed_form_mean_for_one_sine() {
        // ξ̂_g = [1, s]ᵀ/((s + 1)(s + 3)) g, Δ = 2/(s + 2) ξ̂ᵀ. At s = 2j the entries' phasors are
        // a_1 = 2/((2j+1)(2j+3)(2j+2))·(−j), a_2 = 2j·a_1, so with |a_1|² = 4/(5·13·8),
        // Ω̄ = ½ Re(a aᴴ) = ½ |a_1|² [[1, 0], [0, 4]] (a_2 is a_1 turned by 90°).
        let s = siso(0.0);
        let avg = Averaged::new(&s.design().unwrap(), &s.reference, &s.disturbance);
        let a1 = 4.0 / (5.0 * 13.0 * 8.0);
        let expected = [[0.5 * a1, 0.0], [0.0, 2.0 * a1]];
        let c = &avg.channels[0];
        let expected =
            nalgebra::DMatrix::from_row_slice(2, 2, &[expected[0][0], expected[0][1], expected[1][0], expected[1][1]]);
        // Rounding of a 2×2 complex solve: 1e-15 absolute on entries of size ≈ 0.02.
        assert!((&c.omega - &expected).amax() <= 1e-15, "{}", c.omega);
        assert!((c.lambda_min() - 0.5 * a1).abs() <= 1e-15 && (c.lambda_max() - 2.0 * a1).abs() <= 1e-15);
        // δ without adaptive command is −g (no disturbance, x0 = 0): RMS 1/√2; the sine is in the
        // span of the two-dimensional regressor, so nothing is left unexplained.
        assert!((c.open_loop_rms - 0.5f64.sqrt()).abs() <= 1e-15, "{}", c.open_loop_rms);
        assert!(c.residual_rms <= 1e-7, "{}", c.residual_rms);
        assert!((c.predicted_error(10.0, 0.0) - c.open_loop_rms).abs() <= 1e-12);
        // The single tone's excitation is λ_min of its rank-2 part, here all of Ω̄.
        assert!((c.excitation[0].excitation - c.lambda_min()).abs() <= 1e-15);
        // A delay turns a by e^{−2jτ}: Ω̄ is unchanged.
        let d = Averaged::new(&siso(0.7).design().unwrap(), &s.reference, &s.disturbance);
        assert!((&d.channels[0].omega - &c.omega).norm() <= 1e-15);
    }
    /// The disturbance observer's fidelity does not depend on ω's units: the paper's example with
    /// its second disturbance component in units 100 and 1e-6 times smaller (D's and Q's column
    /// over the factor, its amplitudes times it) keeps every frequency's relative error to 1e-9
    /// (rounding of the n × n solves); measured in ξ̂_ω's units it had moved from 1.4 to 13,446.
    #[test]
    fn the_disturbance_observers_fidelity_ignores_the_units_of_omega() {
        let fidelity = |factor: f64| {
            let mut s = Scenario::from_toml(crate::scenario::PAPER_EXAMPLE).unwrap();
            let mut column = s.plant.D.column_mut(1);
            column /= factor;
            let mut column = s.plant.Q.column_mut(1);
            column /= factor;
            let c = &mut s.disturbance.components[1];
            c.bias *= factor;
            c.harmonics.iter_mut().for_each(|h| h.amplitude *= factor);
            let d = s.design().unwrap();
            Averaged::new(&d, &s.reference, &s.disturbance).fidelity
        };
        let nominal = fidelity(1.0);
        assert!(nominal.iter().any(|f| f.relative_error > 1e-3), "an observer that errs: {nominal:?}");
        for factor in [1e2, 1e-6] {
            for (a, b) in nominal.iter().zip(fidelity(factor)) {
                assert_eq!(a.frequency, b.frequency);
                assert!((b.relative_error / a.relative_error - 1.0).abs() < 1e-9, "×{factor}: {a:?} against {b:?}");
            }
        }
    }

    /// The state that tracking asks of a companion-form plant G(s) = (s² + 2ζs + 1)/(s³ + 4s² + s
    /// − 6) is x = [1, s, s²]ᵀ g/(s² + 2ζs + 1) at s = jw (closed form): [1, 0.5j, −0.25]/(0.75 + jζ)
    /// at w = 0.5, 1/(2ζ) at w = 1. With the zeros −ζ ± j within rounding of the axis (ζ = 1e-11)
    /// there is none to count (the run would reach it only over 1/ζ); at ζ = 1e-3, 500.
    #[test]
    fn the_tracking_state_is_the_closed_form_and_none_at_a_zero() {
        let plant = |zeta: f64| {
            let m = |r: usize, c: usize, v: &[f64]| DMatrix::from_row_slice(r, c, v);
            let A = m(3, 3, &[0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 6.0, -1.0, -4.0]);
            let (B, C) = (m(3, 1, &[0.0, 0.0, 1.0]), m(1, 3, &[1.0, 2.0 * zeta, 1.0]));
            crate::plant::Plant::new(A, B.clone(), C, B, m(1, 1, &[0.0]), vec![0.0], None).unwrap()
        };
        let tone = |w: f64| Tone { w, g: DVector::from_element(1, C64::new(1.0, 0.0)), omega: DVector::zeros(1) };
        let x = tracking_state(&plant(1e-11), &tone(0.5)).unwrap();
        let num = C64::new(0.75, 1e-11); // s² + 2ζs + 1 at s = 0.5j, ζ = 1e-11
        let want = [C64::new(1.0, 0.0), C64::new(0.0, 0.5), C64::new(-0.25, 0.0)].map(|v| v / num);
        for (a, b) in x.iter().zip(want) {
            assert!((a - b).norm() < 1e-12, "{x} against {want:?}");
        }
        assert!(tracking_state(&plant(1e-11), &tone(1.0)).is_none());
        let x = tracking_state(&plant(1e-3), &tone(1.0)).unwrap();
        assert!((largest(&x) / 500.0 - 1.0).abs() < 1e-9, "{x}");
    }

    /// F with its rows scaled by `s`, and Ω̄ = F Fᵀ.
    fn gram(F: &[[f64; 3]], s: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
        let F = DMatrix::from_fn(F.len(), 3, |r, c| s[r] * F[r][c]);
        let omega = &F * F.transpose();
        (F, omega)
    }

    #[test]
    fn a_graded_omega_keeps_its_small_eigenvalue_to_relative_accuracy() {
        // F = diag(1e8, 1e-5)·[[1, 2, 0], [3, 1, 5]]: λ_1 λ_2 = det Ω̄ = (1e8·1e-5)²·Σ minors² (Cauchy–Binet,
        // minors −5, 5, 10: 150) = 1.5e8 and λ_1 + λ_2 = tr Ω̄ = 5e16 + 3.5e-9, so λ_small = det/λ_large
        // = 3.0e-9 (λ_large = tr − λ_small, exact in f64 beside 5e16). A QR eigensolver on Ω̄ has an
        // absolute error near ε·5e16 ≈ 10 there and took it for unexcited. Jacobi on the graded
        // factor: a few ε relative (Demmel & Veselić); 1e-13 allows for Ω̄'s rounding of 5e3.
        let (F, omega) = gram(&[[1.0, 2.0, 0.0], [3.0, 1.0, 5.0]], &[1e8, 1e-5]);
        let (lambda, vectors) = spectrum(&F);
        let large = 5e16 + 3.5e-9;
        let small = 1.5e8 / large;
        assert_eq!(vectors.ncols(), 2);
        assert!((lambda[0] - small).abs() <= 1e-13 * small, "{lambda:?} against {small:e}");
        assert!((lambda[1] - large).abs() <= 1e-15 * large, "{lambda:?}");
        // Each vector: Ω̄ v = λ v in the graded norm (row a relative to its own scale s_a·‖Ω̄ row‖).
        for (v, l) in vectors.column_iter().zip(&lambda) {
            let res = &omega * v - v * *l;
            assert!(res[0].abs() <= 1e-14 * 5e16 * v.amax() && res[1].abs() <= 1e-13 * 5e3, "{res}");
        }
    }

    #[test]
    fn the_excited_rank_does_not_depend_on_a_tones_amplitude() {
        // Two tones with orthogonal columns c1 = (1, 1, 0) and c2 = a·(1, −1, 1): λ = 2 and 3a², rank
        // 2 for any amplitude a > 0 (a threshold of 1e-13·λ_max on Ω̄ dropped c2 below a ≈ 2.6e-7).
        // a = 1e-160 leaves Ω̄'s entries below the smallest normal double; F keeps them.
        for a in [1.0, 1e-3, 1e-7, 1e-30, 1e-100, 1e-160] {
            let F = DMatrix::from_column_slice(3, 2, &[1.0, 1.0, 0.0, a, -a, a]);
            let (lambda, vectors) = spectrum(&F);
            let mut expected = [2.0, 3.0 * a * a];
            expected.sort_by(f64::total_cmp);
            assert_eq!((vectors.ncols(), lambda[0]), (2, 0.0), "a = {a:e}: {lambda:?}");
            // Relative accuracy while 3a² is a normal double (to 1e-200); 3e-320 is subnormal.
            for (got, want) in lambda[1..].iter().zip(expected).filter(|(_, want)| *want > 1e-300) {
                assert!((got - want).abs() <= 1e-14 * want, "a = {a:e}: {lambda:?}");
            }
        }
    }

    #[test]
    fn a_tones_excitation_keeps_its_size_across_units() {
        // u = (1e8, 3e-5), v = (2e8, 1e-5): the one minor 1e8·1e-5 − 2e8·3e-5 = −5e3, so det = 2.5e7,
        // and λ_large = 5e16 + 1e-9 (the trace; λ_small is 1e-26 of it), λ_small = 5e-10. mean − half
        // gave rounding of 5e16 there, about ±8.
        let (u, v) = (DVector::from_vec(vec![1e8, 3e-5]), DVector::from_vec(vec![2e8, 1e-5]));
        let small = tone_excitation(&u, &v, false);
        assert!((small - 2.5e7 / 5e16).abs() <= 1e-14 * 5e-10, "{small:e}");
        assert!((tone_excitation(&u, &v, true) - 5e16).abs() <= 1e-15 * 5e16);
        assert_eq!(tone_excitation(&DVector::zeros(2), &DVector::zeros(2), false), 0.0);
        // Signals that are all zero leave F without a column; infinite ones make it NaN.
        let (lambda, vectors) = spectrum(&DMatrix::zeros(3, 0));
        assert_eq!((lambda, vectors.shape()), (vec![0.0; 3], (3, 0)));
        let (lambda, vectors) = spectrum(&DMatrix::from_element(3, 2, f64::NAN));
        assert_eq!((lambda, vectors.shape()), (vec![0.0; 3], (3, 0)));
    }

    #[test]
    fn the_excited_rank_does_not_depend_on_the_units_of_the_entries() {
        // F = S·[[1, 0], [0, 1], [1, 1]] (padded): rank 2 for any positive S. The nonzero eigenvalues
        // are those of FᵀF = [[a, b], [b, c]], a = s1² + s3², b = s3², c = s2² + s3², in closed form
        // without cancellation: det = s1²s2² + s1²s3² + s2²s3², λ_large = (a + c)/2 + √(((s1² − s2²)/2)²
        // + s3⁴), λ_small = det/λ_large.
        for s in [[1.0, 1.0, 1.0], [1e9, 1.0, 1e-6], [1e-6, 1e3, 1e9], [1.0, 1e-12, 1.0]] {
            let (F, _) = gram(&[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]], &s);
            let (lambda, vectors) = spectrum(&F);
            let [s1, s2, s3] = s.map(|x| x * x);
            let large = 0.5 * (s1 + s2) + s3 + ((0.5 * (s1 - s2)).powi(2) + s3 * s3).sqrt();
            let small = (s1 * s2 + s1 * s3 + s2 * s3) / large;
            assert_eq!((vectors.ncols(), lambda[0]), (2, 0.0), "{s:?}: {lambda:?}");
            assert!((lambda[1] - small).abs() <= 1e-13 * small, "{s:?}: {lambda:?} against {small:e}");
            assert!((lambda[2] - large).abs() <= 1e-14 * large, "{s:?}: {lambda:?} against {large:e}");
        }
    }
}
