//! **quell**: direct adaptive output-feedback control of unstable MIMO linear plants with
//! distinct input delays and unknown multi-harmonic references and disturbances.
//!
//! Data flows one way:
//! [`scenario`] file → validated [`Scenario`] → [`Design`] (every gain, [`design`]) →
//! controller equations ([`controller`]) + plant → one [`sim::SimResult`] (a [`sim::Run`], from a
//! scenario by [`sim::Run::of`]). Run settings, their
//! limits and checks ([`settings`]) are shared by the scenario reader and the loops.
//!
//! ```
//! use std::ops::ControlFlow;
//! use quell::scenario::{Scenario, PAPER_EXAMPLE};
//! use quell::sim::{Run, RunSettings};
//! use quell::{Controller, Design};
//!
//! // The paper's example (Section VIII): every gain from the formulas, assumptions checked.
//! let s = Scenario::from_toml(PAPER_EXAMPLE)?;
//! let design = Design::new(&s.plant, &s.design)?;
//! assert_eq!(design.sigma(), vec![2, 1]);
//!
//! // The continuous closed loop with its input delays, 20 s of it.
//! let settings = RunSettings::continuous(20.0, 0.1, 1e-9, 1e-9);
//! let run = Run::new(&design, &s.reference, &s.disturbance, settings).simulate(|_| ControlFlow::Continue(()))?;
//! assert_eq!(run.len(), 201);
//!
//! // The same controller for a real plant, sampled every millisecond.
//! let mut ctrl = Controller::new(&design, 1e-3)?;
//! let u_f = ctrl.step(&[0.1, 1.9], &[0.0, 2.0])?;
//! assert_eq!(u_f.len(), 2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Equation numbers refer to C. V. Tu, N. Dudarenko, "Direct adaptive output-feedback control for
//! unstable linear multidimensional systems with distinct input delays" (2026).
#![allow(non_snake_case)]

pub use nalgebra;

#[macro_use]
pub mod simd;

pub mod auto;
pub mod cancel;
pub mod controller;
pub mod design;
pub mod diagnostics;
pub mod export;
pub mod linalg;
pub mod plant;
pub mod scenario;
pub mod settings;
pub mod signal;
pub mod sim;
pub mod study;

pub use controller::{Controller, ControllerError};
pub use design::{place, Design, DesignError, DesignSpec, ObserverChoice, PlaceError};
pub use plant::{Plant, PlantError};
pub use scenario::{Scenario, ScenarioError};
pub use signal::{Component, Harmonic, Signal};
