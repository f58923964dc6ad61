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

pub use closed_loop::{simulate, ContinuousLoop, RunSettings};
pub use result::{ChannelSummary, Outcome, SimResult};
pub use sampled::{simulate_sampled, MeasurementNoise, SampledError, SampledSettings};
