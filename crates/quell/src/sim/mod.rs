//! Simulation of the closed loop: the delay-equation integrator, the continuous loop and the one
//! result type.

pub mod closed_loop;
pub mod dde;
pub mod result;

pub use closed_loop::{simulate, ContinuousLoop, RunSettings};
pub use result::{ChannelSummary, Outcome, SimResult};
