//! Simulation of the closed loop: the delay-equation integrator, the continuous loop and the one
//! result type.

pub mod closed_loop;
pub mod dde;
pub mod noise;
pub mod result;
pub mod sampled;

/// A state value that counts as divergence: anything but |v| ≤ `bound` (so NaN, ±∞, and every value
/// when the bound itself is NaN).
pub(crate) fn runaway(v: f64, bound: f64) -> bool {
    !matches!(v.abs().partial_cmp(&bound), Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal))
}

/// Divergence-message name of plant state x_j (j from 0).
pub(crate) fn plant_state_name(j: usize) -> String {
    format!("x[{}] (plant state)", j + 1)
}

/// Divergence-message name of entry j (from 0) of η̂ = [η̂_1; …; η̂_m], each of length q.
pub(crate) fn eta_name(j: usize, q: usize) -> String {
    format!("eta{}[{}] (adaptive parameters)", j / q + 1, j % q + 1)
}

pub use closed_loop::{simulate, ContinuousLoop, RunSettings};
pub use result::{ChannelSummary, Outcome, SimResult};
pub use sampled::{simulate_sampled, MeasurementNoise, SampledError, SampledSettings};
