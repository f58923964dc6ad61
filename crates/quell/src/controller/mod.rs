//! The controller's equations, in one place, shared by the continuous simulation
//! (`sim/closed_loop.rs`) and the real-time controller.
//!
//! The controller has three parts:
//! - the **core**, a linear system with state z = [ξ̂_g; ξ̂_ω; x̂] driven by v = [y; g; u_d]: the
//!   reference observer (14), the disturbance observer (20) and the Luenberger observer (6) with the
//!   decoupling law (5) substituted; the regressor ξ̂ = [ξ̂_g; ξ̂_ω] is its first q states and the plant
//!   input is u_f = −K x̂ + F u_d (5). The disturbance observer is realized in the coordinates
//!   ξ̂_ω = φ + N x̂ instead of φ: differentiating (20) with (6) gives ξ̂_ω' = G_ω ξ̂_ω + N L (y − C x̂),
//!   the same signal without the N x̂ product and without u_d: ξ̂ does not depend on u;
//! - per channel, the **filters** of the adaptive law (33): G_ii(s) applied to the row
//!   [u_i(t − τ_i), ξ̂ᵀ(t − τ_i)] (state W_i, σ_i × (1 + q)) and H(s) = 1/(βs + 1) giving Y_i and Ω_i;
//! - the **adaptive law** (33) η̂_i' = μ_i (Y_i − Ω_i η̂_i) and the control law (25) u_i = −η̂_iᵀ ξ̂.

pub(crate) mod discrete;
pub(crate) mod packed;

pub use discrete::{
    Controller, ControllerError, MAX_ADAPTATION_STEP, MAX_DELAY_LINE_BYTES, MAX_DELAY_SAMPLES, MAX_MEASUREMENT,
};
pub(crate) use discrete::{Discretized, SinglePrecision};

use nalgebra::DMatrix;

use crate::design::{ChannelTf, Design};
use crate::linalg::companion;

/// Floating-point arithmetic of the discrete controller: the Rust [`Controller`]'s, or a
/// single-precision build's (the export's `Precision::F32`), which a sampled-data run emulates
/// (`simulation.precision`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// `double`: the Rust [`Controller`]'s arithmetic.
    #[default]
    F64,
    /// `float`: for microcontrollers whose FPU is single precision (Cortex-M4F, M33).
    F32,
}

impl Precision {
    /// The name of the key `precision`: `f64` or `f32`.
    pub fn name(self) -> &'static str {
        match self {
            Precision::F64 => "f64",
            Precision::F32 => "f32",
        }
    }
    /// Largest |y_i|, |g_i| the step takes: [`MAX_MEASUREMENT`] in double, 1e12 in float (float's
    /// products of two signals stay below 1e24 · gains, far from its 3.4e38).
    pub fn input_bound(self) -> f64 {
        match self {
            Precision::F64 => MAX_MEASUREMENT,
            Precision::F32 => 1e12,
        }
    }
    /// The precision named `f64` or `f32`.
    pub fn from_name(name: &str) -> Option<Precision> {
        [Precision::F64, Precision::F32].into_iter().find(|p| p.name() == name)
    }
}

/// Matrices of the controller's linear parts, built once from a [`Design`].
#[derive(Debug, Clone)]
pub(crate) struct Equations {
    /// Plant order n, channels m, regressor size q (= q_g + q_ω).
    pub n: usize,
    pub m: usize,
    pub q: usize,
    /// Core state dimension n + q_g + q_ω.
    pub nz: usize,
    /// Core dynamics z' = A_z z + B_z [y; g; u_d], z = [ξ̂_g; ξ̂_ω; x̂]:
    /// ξ̂_g' = G_g ξ̂_g + L_g g,  ξ̂_ω' = G_ω ξ̂_ω + N L (y − C x̂),
    /// x̂' = (A_f − LC) x̂ + L y + B_f u_d.
    pub A_z: DMatrix<f64>,
    pub B_z: DMatrix<f64>,
    /// u_f = −K x̂ + F u_d (5), stored as −K.
    pub K_neg: DMatrix<f64>,
    pub F: DMatrix<f64>,
    /// Per channel: G_ii(s) = q_i0 / den_i(s) realized as w' = A_i w + e_σ v, output q_i0·w_1.
    pub channels: Vec<ChannelFilter>,
    /// H(s) = 1/(βs + 1).
    pub beta: f64,
}

/// Channel i's G_ii(s) realization and adaptation gain.
#[derive(Debug, Clone)]
pub(crate) struct ChannelFilter {
    /// G_ii(s) as designed, the one record of σ_i and q_i0.
    pub tf: ChannelTf,
    /// Companion matrix of den_i (σ_i × σ_i).
    pub A: DMatrix<f64>,
    /// μ_i.
    pub mu: f64,
    /// τ_i.
    pub delay: f64,
}

impl ChannelFilter {
    /// σ_i.
    pub(crate) fn sigma(&self) -> usize {
        self.tf.sigma()
    }
    /// q_i0.
    pub(crate) fn q0(&self) -> f64 {
        self.tf.q0()
    }
}

impl Equations {
    /// Assembles the controller's matrices from a design.
    pub(crate) fn new(d: &Design) -> Equations {
        let p = d.plant();
        let (n, m) = (p.n(), p.m());
        let (q_g, q_w) = (d.q_g(), d.q_w());
        let (q, nz) = (q_g + q_w, n + q_g + q_w);
        let mut A_z = DMatrix::zeros(nz, nz);
        let mut B_z = DMatrix::zeros(nz, 3 * m);
        // Reference observer (14).
        A_z.view_mut((0, 0), (q_g, q_g)).copy_from(d.G_g());
        B_z.view_mut((0, m), (q_g, m)).copy_from(d.L_g());
        // Disturbance observer (20) in the coordinates ξ̂_ω = φ + N x̂.
        let NL = d.N() * d.L();
        A_z.view_mut((q_g, q_g), (q_w, q_w)).copy_from(d.G_w());
        A_z.view_mut((q_g, q), (q_w, n)).copy_from(&(-(&NL * &p.C)));
        B_z.view_mut((q_g, 0), (q_w, m)).copy_from(&NL);
        // Observer (6) with u_f = −K x̂ + F u_d: x̂' = (A − BK − LC) x̂ + L y + BF u_d.
        A_z.view_mut((q, q), (n, n)).copy_from(&(d.A_f() - d.L() * &p.C));
        B_z.view_mut((q, 0), (n, m)).copy_from(d.L());
        B_z.view_mut((q, 2 * m), (n, m)).copy_from(d.B_f());
        let channels = d
            .channels()
            .iter()
            .zip(d.mu())
            .zip(&p.delays)
            .map(|((tf, &mu), &delay)| ChannelFilter { tf: tf.clone(), A: companion(&tf.den), mu, delay })
            .collect();
        Equations { n, m, q, nz, A_z, B_z, K_neg: -d.K(), F: d.F().clone(), channels, beta: d.beta() }
    }

    /// Regressor ξ̂ = [ξ̂_g; ξ̂_ω]: the first q core states.
    pub(crate) fn regressor<'z>(&self, z: &'z [f64]) -> &'z [f64] {
        &z[..self.q]
    }

    /// Observer state x̂: the last n core states.
    pub(crate) fn x_hat<'z>(&self, z: &'z [f64]) -> &'z [f64] {
        &z[self.q..self.nz]
    }

    /// Plant input (5): u_f = −K x̂ + F u_d.
    pub(crate) fn plant_input(&self, z: &[f64], u_d: &[f64], u_f: &mut [f64]) {
        mat_vec(&self.K_neg, self.x_hat(z), u_f, false);
        mat_vec(&self.F, u_d, u_f, true);
    }

    /// Number of states of channel i's G_ii filter bank (σ_i rows, 1 + q columns).
    pub(crate) fn filter_len(&self, i: usize) -> usize {
        self.channels[i].sigma() * (1 + self.q)
    }
}

/// Control law (25): u_i = −η̂_iᵀ ξ̂.
pub(crate) fn command(eta: &[f64], xi: &[f64]) -> f64 {
    -dot(eta, xi)
}

/// Channel i's filter-bank outputs from its state W (σ × (1 + q), row-major): the filtered delayed
/// command G_ii[u_i(t − τ_i)] = q_i0·W₀₀ and the regressor row Δ_i = q_i0·(W₀₁, …, W₀q) (eq. (33)).
/// Returns ε̂_i = δ_i − G_ii[u_i(t − τ_i)] and writes Δ_i into `delta`.
pub(crate) fn swapping_error(ch: &ChannelFilter, W: &[f64], delta_i: f64, Delta: &mut [f64]) -> f64 {
    let q = Delta.len();
    let q0 = ch.q0();
    for (d, w) in Delta.iter_mut().zip(&W[1..=q]) {
        *d = q0 * w;
    }
    delta_i - q0 * W[0]
}

/// Dot product.
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// out = M x (or out += M x when `add`), on slices; allocates nothing. nalgebra's `gemv`, which sums
/// column by column in natural order: the order generated C ([`crate::export`]) follows, so the two
/// agree bit for bit. (A hand loop over four columns at a time took 5 % fewer instructions in
/// `Controller::step`, but rounds differently; `docs/performance.md`.)
pub(crate) fn mat_vec(M: &DMatrix<f64>, x: &[f64], out: &mut [f64], add: bool) {
    let (r, c) = M.shape();
    assert!(x.len() == c && out.len() == r, "mat_vec: dimension mismatch");
    let x = nalgebra::DVectorView::from_slice(x, c);
    let mut out = nalgebra::DVectorViewMut::from_slice(out, r);
    out.gemv(1.0, M, &x, if add { 1.0 } else { 0.0 });
}
