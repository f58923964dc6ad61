//! Simulation of the closed loop: the delay-equation integrator, the continuous and the
//! sampled-data loops, the divergence check they share, and the one result type.

pub mod closed_loop;
pub mod dde;
pub mod divergence;
pub mod noise;
pub mod result;
pub mod sampled;
pub mod settle;

use crate::controller::ControllerError;
use crate::design::Design;
use crate::settings::{self, KeyError};
use crate::signal::{check_signals, Signal};

pub use crate::settings::MeasurementNoise;
pub use closed_loop::{
    default_max_steps, loop_rate, simulate, simulate_with_truth, ContinuousLoop, RunSettings, BUDGET_MIN_STEPS,
    BUDGET_STEPS_PER_RATE, MAX_HISTORY_BYTES,
};
pub use divergence::{Peaks, Watched, DIVERGENCE_BOUND};
pub use result::{ChannelSummary, Outcome, RunStats, Sample, SimResult};
pub use sampled::{
    simulate_sampled, simulate_sampled_with, simulate_sampled_with_truth, SampledController, SampledSettings,
};
pub use settle::{Settle, Settling};

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

/// A true plant (`[truth]`) must have the design plant's dimensions n, m, k.
pub(crate) fn check_truth(design: &Design, truth: &crate::plant::Plant) -> Result<(), KeyError> {
    let p = design.plant();
    for (name, a, b) in [
        ("A", &truth.A, &p.A),
        ("B", &truth.B, &p.B),
        ("C", &truth.C, &p.C),
        ("D", &truth.D, &p.D),
        ("Q", &truth.Q, &p.Q),
    ] {
        if a.shape() != b.shape() {
            return Err(KeyError::new(
                format!("truth.{name}"),
                format!(
                    "expected {}×{} (the shape of plant.{name}), found {}×{}",
                    b.nrows(),
                    b.ncols(),
                    a.nrows(),
                    a.ncols()
                ),
            ));
        }
    }
    if truth.delays.len() != p.delays.len() || truth.x0.len() != p.x0.len() {
        let (name, a, b) = if truth.delays.len() != p.delays.len() {
            ("delays", truth.delays.len(), p.delays.len())
        } else {
            ("x0", truth.x0.len(), p.x0.len())
        };
        return Err(KeyError::new(
            format!("truth.{name}"),
            format!("expected {b} entries (as plant.{name}), found {a}"),
        ));
    }
    truth.validate().map_err(|e| KeyError::new("truth", e.to_string()))
}
