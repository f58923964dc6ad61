//! Simulation of the closed loop: the delay-equation integrator, the continuous and the
//! sampled-data loops, the divergence check they share, and the one result type.

pub mod closed_loop;
pub mod dde;
pub mod divergence;
pub mod noise;
pub mod result;
pub mod sampled;

use crate::controller::ControllerError;
use crate::design::Design;
use crate::settings::{self, KeyError};
use crate::signal::{check_signals, Signal};

pub use crate::settings::MeasurementNoise;
pub use closed_loop::{simulate, ContinuousLoop, RunSettings};
pub use divergence::{Watched, DIVERGENCE_BOUND};
pub use result::{ChannelSummary, Outcome, RunStats, SimResult};
pub use sampled::{simulate_sampled, simulate_sampled_with, SampledController, SampledSettings};

/// Why a run cannot start: a setting or signal out of range (named by its scenario key), or a
/// controller that cannot run at the sample time.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    #[error(transparent)]
    Input(#[from] KeyError),
    #[error(transparent)]
    Controller(#[from] ControllerError),
}

/// The checks both loops make: the horizon, the divergence bound, and the signals against the
/// design's plant (m reference components, k disturbance components, finite parameters).
fn check_run(
    design: &Design,
    reference: &Signal,
    disturbance: &Signal,
    t_end: f64,
    output_step: f64,
    divergence_bound: f64,
) -> Result<(), KeyError> {
    settings::check_horizon(t_end, output_step)?;
    divergence::check_bound(divergence_bound)?;
    check_signals(design.plant(), reference, disturbance)
}
