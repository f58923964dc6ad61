//! Simulation of the closed loop: the delay-equation integrator and the continuous loop.

pub mod dde;
