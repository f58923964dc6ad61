//! **quell**: direct adaptive output-feedback control of unstable MIMO linear plants with
//! distinct input delays and unknown multi-harmonic references and disturbances.
//!
//! Data flows one way:
//! [`scenario`] file → validated [`Scenario`] → [`Design`] (every gain, [`design`]) →
//! controller equations ([`controller`]) + plant → one [`sim::SimResult`].
//!
//! Equation numbers refer to C. V. Tu, N. Dudarenko, "Direct adaptive output-feedback control for
//! unstable linear multidimensional systems with distinct input delays" (2026).
#![allow(non_snake_case)]

pub use nalgebra;

pub mod controller;
pub mod design;
pub mod linalg;
pub mod plant;
pub mod scenario;
pub mod signal;
pub mod sim;

pub use controller::{Controller, ControllerError};
pub use design::{place, Design, DesignError, DesignSpec, ObserverChoice};
pub use plant::{Plant, PlantError};
pub use scenario::{Scenario, ScenarioError};
pub use signal::{Component, Harmonic, Signal};
