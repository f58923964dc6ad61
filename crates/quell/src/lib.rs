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
//! # The public API, with an example each
//!
//! **[`scenario`]**: a scenario file read and checked at the boundary into a [`Scenario`] (plant,
//! design choices, reference, disturbance, settings); every error names its key.
//!
//! ```
//! use quell::scenario::{Scenario, PAPER_EXAMPLE};
//!
//! let s = Scenario::from_toml(PAPER_EXAMPLE)?;
//! assert_eq!((s.plant.n(), s.plant.m(), s.plant.k()), (3, 2, 2));
//! let e = Scenario::from_toml(&PAPER_EXAMPLE.replace("t_end = 100.0", "t_end = -1.0")).unwrap_err();
//! assert!(e.to_string().starts_with("simulation.t_end"), "{e}");
//! // Written back, it reads as the same scenario.
//! assert_eq!(Scenario::from_toml(&s.to_toml())?.plant, s.plant);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **[`plant`]** and **[`signal`]**: the plant (1) as [`Plant`] (A, B, C, D, Q, delays τ_i, and
//! the [`TimeUnit`] they are written in, a label), the reference g(t) and disturbance ω(t) as a
//! [`Signal`] of [`Component`]s (m for g, k for ω), each a bias and [`Harmonic`]s.
//!
//! ```
//! use quell::nalgebra::dmatrix;
//! use quell::{Component, Harmonic, Plant, Signal, TimeUnit};
//!
//! // x' = −x + u(t − 0.2) + ω, y = x, in minutes.
//! let plant = Plant::new(dmatrix![-1.0], dmatrix![1.0], dmatrix![1.0], dmatrix![1.0], dmatrix![0.0], vec![0.2], None)?
//!     .with_time_unit(TimeUnit::from_name("min")?);
//! assert_eq!((plant.n(), plant.time_unit.symbol()), (1, "min"));
//! let g = Signal { components: vec![Component { bias: 1.0, harmonics: vec![Harmonic { amplitude: 0.5, frequency: 2.0, phase: 0.0 }] }] };
//! assert_eq!(g.components[0].eval(0.0), 1.0);
//! assert_eq!(g.components[0].peak(), 1.5);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **[`design`]**: every gain of the controller from the plant and the choices, [`Design::new`]
//! (the decoupler of Proposition 1 with σ_i from eq. (7), the observer (6), the internal models
//! (11), (16) and N of eq. (20)), the paper's assumptions checked on the way; [`place()`] for pole
//! placement.
//!
//! ```
//! use quell::scenario::{Scenario, PAPER_EXAMPLE};
//! use quell::Design;
//!
//! let s = Scenario::from_toml(PAPER_EXAMPLE)?;
//! let design = Design::new(&s.plant, &s.design)?;
//! assert_eq!(design.sigma(), vec![2, 1]);
//! // G_11(s) = q_10 / ((s + 6)(s + 2)) with unit DC gain: q_10 = 12.
//! assert_eq!(design.channels()[0].q0(), 12.0);
//! // The decoupled loop A − BK has exactly the channel poles.
//! let mut re: Vec<f64> = design.decoupled_eigenvalues().iter().map(|z| z.re).collect();
//! re.sort_by(f64::total_cmp);
//! assert!(re.iter().zip([-6.0, -4.0, -2.0]).all(|(a, b)| (a - b).abs() < 1e-9));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **[`controller`]**: the real-time [`Controller`], discretized exactly for a zero-order hold;
//! [`Controller::step`] takes y(k), g(k) and returns the plant input u_f(k) (5) without allocating.
//!
//! ```
//! use quell::scenario::{Scenario, PAPER_EXAMPLE};
//! use quell::Controller;
//!
//! let design = Scenario::from_toml(PAPER_EXAMPLE)?.design()?;
//! let mut ctrl = Controller::new(&design, 1e-3)?;
//! let u_f = ctrl.step(&[0.1, 1.9], &[0.0, 2.0])?.to_vec();
//! assert_eq!(u_f.len(), 2);
//! // A reading beyond the bound is refused and the state kept.
//! assert!(ctrl.step(&[f64::NAN, 0.0], &[0.0, 0.0]).is_err());
//! // A delay that is not a whole number of samples is an error naming the key.
//! let e = Controller::new(&design, 0.3).unwrap_err();
//! assert!(e.to_string().starts_with("simulation.sample_time"), "{e}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **[`sim`]**: the one front door for a run, [`sim::Run`] with [`sim::RunSettings`]: the
//! continuous loop (the delay equation) or the sampled-data loop, on the design's plant or a true
//! one; one [`sim::SimResult`] whose [`sim::Outcome`] says how the run ended, and whose
//! [`sim::ChannelFigures`] (tail error, peak inputs, settling time) every output reports.
//!
//! ```
//! use std::ops::ControlFlow;
//! use quell::scenario::{Scenario, PAPER_EXAMPLE};
//! use quell::sim::{Outcome, Run, RunSettings, Settle};
//!
//! let s = Scenario::from_toml(PAPER_EXAMPLE)?;
//! let design = s.design()?;
//! let sampled = RunSettings::sampled(2.0, 0.1, 0.01);
//! let r = Run::of(&s, &design).settings(sampled).simulate(|_| ControlFlow::Continue(()))?;
//! assert_eq!((r.len(), r.outcome.clone()), (21, Some(Outcome::Completed)));
//! let f = &r.figures(&Settle::default())[0];
//! assert!(f.tail_rms_e <= f.tail_max_e && f.max_uf > 0.0); // an RMS never exceeds the max
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **[`export`]**: the same controller as dependency-free C99 ([`export::generate`]) and as an FMI
//! 2.0 or 3.0 co-simulation FMU ([`export::generate_fmu`]).
//!
//! ```
//! use quell::export::{generate, ExportOptions};
//! use quell::scenario::{Scenario, PAPER_EXAMPLE};
//!
//! let design = Scenario::from_toml(PAPER_EXAMPLE)?.design()?;
//! let code = generate(&design, 0.01, &ExportOptions::default())?;
//! assert_eq!(code.header_name, "quell_controller.h");
//! assert!(code.header.contains("int quell_step(quell_state *s"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **[`files`]**: the atomic writes of every output file, the CLI's and `quell.export`'s
//! ([`files::write_atomic`], [`files::write_atomic_all`]): a temporary name beside the file, then a
//! rename, so that a reader never sees a half-written file nor a new file beside an old one.
//!
//! ```
//! use quell::files::write_atomic_all;
//!
//! let dir = std::env::temp_dir().join(format!("quell-files-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//! let (header, source) = (dir.join("a.h"), dir.join("a.c"));
//! write_atomic_all(&[(header.clone(), b"/* h */".as_slice()), (source.clone(), b"/* c */".as_slice())])?;
//! assert_eq!(std::fs::read(&source)?, b"/* c */");
//! assert_eq!(std::fs::read_dir(&dir)?.count(), 2); // no temporary file left
//! std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), std::io::Error>(())
//! ```
//!
//! **[`study`]**: many runs of one scenario, a grid of values and Monte Carlo draws of the true
//! plant ([`study::Study`], [`study::sweep`]), aggregated per grid point ([`study::Summary`]), and
//! the per-channel tuning of μ_i ([`study::tune`]).
//!
//! ```
//! use quell::study::{sweep, Study, SweepOptions};
//!
//! // The paper's example (no scenario named), 1 s, at two values of μ_1.
//! let text = "[simulation]\nt_end = 1.0\nrtol = 1e-6\natol = 1e-6\n[grid]\n\"design.mu[0]\" = [10.0, 20.0]\n";
//! let study = Study::from_toml(text, None)?;
//! assert_eq!(study.len(), 2);
//! let rows = sweep(&study, &SweepOptions::default()).rows;
//! assert_eq!(rows.len(), 2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **[`diagnostics`]**: why a channel converges slowly, from the averaged adaptive law (33) and the
//! run ([`diagnostics::diagnose`]).
//!
//! ```
//! use std::ops::ControlFlow;
//! use quell::scenario::{Scenario, PAPER_EXAMPLE};
//! use quell::sim::{Run, RunSettings};
//!
//! let s = Scenario::from_toml(PAPER_EXAMPLE)?;
//! let design = s.design()?;
//! let r = Run::of(&s, &design).settings(RunSettings::sampled(2.0, 0.1, 0.01)).simulate(|_| ControlFlow::Continue(()))?;
//! let d = quell::diagnostics::diagnose(&design, &s.reference, &s.disturbance, &r);
//! assert_eq!(d.channels.len(), 2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **[`averaged`]**: the adaptive loop in steady state from the design and the signals alone
//! ([`averaged::Averaged`]): Ω̄_i and η*_i of the law (33) averaged over g and ω, and the RMS error
//! the averaged law predicts at time t; [`diagnostics`] and [`auto`] stand on it.
//!
//! ```
//! use quell::averaged::Averaged;
//! use quell::scenario::{Scenario, PAPER_EXAMPLE};
//!
//! let s = Scenario::from_toml(PAPER_EXAMPLE)?;
//! let design = s.design()?;
//! let c = &Averaged::new(&design, &s.reference, &s.disturbance).channels[0];
//! assert!(c.lambda_min() >= -1e-12 * c.lambda_max()); // Ω̄_1, a mean of squares, is PSD
//! // At t = 0 (η̂ = 0) the averaged law's error is the loop's error without adaptive command.
//! let start = c.predicted_error(20.0, 0.0);
//! assert!((start - c.open_loop_rms).abs() <= 1e-9 * c.open_loop_rms, "{start} vs {}", c.open_loop_rms);
//! assert!(c.predicted_error(20.0, 100.0) < start);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **[`auto`]**: every design key a scenario leaves out chosen from the plant's time scales and the
//! signals' frequencies, verified by simulation ([`auto::auto_design`]).
//!
//! ```
//! use quell::auto::{auto_design, Targets};
//!
//! // A first-order unstable plant with a 0.1 s input delay and no design keys at all.
//! let text = "[plant]\nA = [[0.5]]\nB = [[1.0]]\nC = [[1.0]]\nD = [[1.0]]\nQ = [[0.0]]\ndelays = [0.1]\n\
//!             [design]\n[reference]\ncomponents = [{ bias = 1.0 }]\n\
//!             [disturbance]\ncomponents = [{ harmonics = [{ amplitude = 0.2, frequency = 1.0 }] }]\n\
//!             [simulation]\nt_end = 20.0\n";
//! let auto = auto_design(&text.parse()?, &Targets::default())?;
//! assert!(auto.verification.passed);
//! assert_eq!(auto.scenario.design.mu.len(), 1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **[`settings`]**: the run settings' limits and checks, shared by the scenario reader and both
//! loops; a value out of range is a [`settings::KeyError`] naming its scenario key.
//!
//! ```
//! use quell::scenario::{Scenario, PAPER_EXAMPLE};
//! use quell::sim::{Run, SimError};
//!
//! let mut s = Scenario::from_toml(PAPER_EXAMPLE)?;
//! s.simulation.output_step = 0.0;
//! let d = s.design()?;
//! let Err(SimError::Input(e)) = Run::of(&s, &d).check() else { panic!("output_step = 0 accepted") };
//! assert_eq!(e.key, "simulation.output_step");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **[`cancel`]**: a stop flag for a long library call that takes none of its own (the design of
//! a large plant): [`Design::new`] inside [`cancel::with_stop`] returns
//! [`DesignError::Interrupted`] once a front's Ctrl-C handler has set the flag.
//!
//! ```
//! use std::sync::atomic::AtomicBool;
//! use std::sync::Arc;
//! use quell::scenario::{Scenario, PAPER_EXAMPLE};
//! use quell::{cancel, Design, DesignError};
//!
//! let s = Scenario::from_toml(PAPER_EXAMPLE)?;
//! let stop = Arc::new(AtomicBool::new(true)); // as the handler leaves it
//! let r = cancel::with_stop(stop, || Design::new(&s.plant, &s.design));
//! assert!(matches!(r, Err(DesignError::Interrupted)), "{r:?}");
//! assert!(cancel::check().is_ok()); // outside `with_stop` nothing stops
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **The crate root** re-exports what most callers name: the types above, the design's choices
//! written in code ([`DesignSpec`], [`ObserverChoice`]) rather than read from a file, each
//! module's error ([`PlantError`], [`DesignError`], [`ControllerError`], [`ScenarioError`]), pole
//! placement ([`place()`], [`PlaceError`]), and how quell writes a number in its messages
//! ([`fmt_number`], [`fmt_complex`], [`fmt_complex_list`], [`fmt_eigenvalues`]). Matrices and complex numbers are
//! [`nalgebra`]'s, re-exported so that a caller's version always matches.
//!
//! ```
//! use quell::nalgebra::{dmatrix, Complex};
//! use quell::{fmt_complex_list, fmt_eigenvalues, fmt_number, place, DesignSpec, Design, ObserverChoice, Plant, PlaceError};
//!
//! // The double integrator x1' = x2, x2' = u: K = [2, 3] puts eig(A − BK) at −1 and −2, the roots
//! // of s² + 3s + 2 = s² + k₂s + k₁.
//! let (A, B) = (dmatrix![0.0, 1.0; 0.0, 0.0], dmatrix![0.0; 1.0]);
//! let K = place(&A, &B, &[Complex::new(-1.0, 0.0), Complex::new(-2.0, 0.0)])?;
//! assert!((K[(0, 0)] - 2.0).abs() < 1e-9 && (K[(0, 1)] - 3.0).abs() < 1e-9, "{K}");
//! let e = place(&A, &B, &[Complex::new(-1.0, 0.0)]).unwrap_err();
//! assert_eq!(e, PlaceError::WrongCount { expected: 2, found: 1 });
//!
//! // x' = 0.5x + u(t − 0.1) + ω, y = x: every choice written in code (σ = 1, a bias reference,
//! // a disturbance of one harmonic), the observer pole placed.
//! let plant = Plant::new(dmatrix![0.5], dmatrix![1.0], dmatrix![1.0], dmatrix![1.0], dmatrix![0.0], vec![0.1], None)?;
//! let real = |p: &[f64]| p.iter().map(|&x| Complex::new(x, 0.0)).collect::<Vec<_>>();
//! let spec = DesignSpec {
//!     observer: ObserverChoice::Poles(real(&[-5.0])),
//!     channel_poles: vec![real(&[-2.0])],
//!     reference_filter_poles: vec![real(&[-1.0])],
//!     disturbance_filter_poles: vec![real(&[-1.0, -2.0])],
//!     mu: vec![10.0],
//!     beta: 1.0,
//!     relative_degrees: None,
//!     regressor_scaling: Default::default(),
//!     reference_sizes: Vec::new(),
//!     disturbance_sizes: Vec::new(),
//! };
//! let design = Design::new(&plant, &spec)?;
//! assert_eq!(design.sigma(), vec![1]);
//! assert_eq!(fmt_complex_list(design.observer_eigenvalues()), "-5.000000");
//! assert_eq!((fmt_number(0.25), fmt_number(1e300)), ("0.250000".to_string(), "1.000000e300".to_string()));
//! // A computed double pole's rounding residue (2.3e-13i on −7539.8) is not printed.
//! assert_eq!(fmt_eigenvalues(&[Complex::new(-7539.8, 2.3e-13)]), "-7539.800000");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Equation numbers refer to C. V. Tu, N. Dudarenko, "Direct adaptive output-feedback control for
//! unstable linear multidimensional systems with distinct input delays" (2026).
#![allow(non_snake_case)]
#![warn(unreachable_pub)]

pub use nalgebra;

#[macro_use]
mod simd;

pub mod auto;
pub mod averaged;
pub mod cancel;
pub mod controller;
pub mod design;
pub mod diagnostics;
pub mod export;
pub mod files;
mod hash;
mod linalg;
pub mod plant;
pub mod scenario;
pub mod settings;
pub mod signal;
pub mod sim;
pub mod study;

/// Not part of the API: the delay-equation integrator, the continuous loop as a delay system and
/// the AVX2 switch, for the integrator's own test suite (`tests/dde.rs`, which counts allocations
/// with its own global allocator, and `tests/baseline_simd.rs`, which needs a process of its own)
/// and the benchmarks in `benches/`.
#[doc(hidden)]
pub mod bench_api {
    pub mod dde {
        pub use crate::sim::dde::*;
    }
    pub use crate::sim::closed_loop::ContinuousLoop;
    pub use crate::simd::avx2_in_use;
}

pub use controller::{Controller, ControllerError};
pub use design::{place, Design, DesignError, DesignSpec, ObserverChoice, PlaceError};
/// How quell writes a number (and a complex number) in messages, reports and generated headers.
pub use linalg::{fmt_complex, fmt_complex_list, fmt_eigenvalues, fmt_number};
pub use plant::{Plant, PlantError};
pub use scenario::{Scenario, ScenarioError};
pub use settings::TimeUnit;
pub use signal::{Component, Harmonic, Signal};
