//! Scenario files (TOML): parsing and validation at the boundary into typed values.
//!
//! A scenario holds the plant (1), the designer's choices ([`DesignSpec`]), the reference g(t)
//! (Assumption 2), the disturbance ω(t) (Assumption 3) and the simulation settings. The format is
//! documented by `examples/paper.toml` (the paper's Section VIII example, [`PAPER_EXAMPLE`]); every
//! error names the offending key, see `docs/errors.md`.
//!
//! [`Scenario::from_toml`] checks the file's structure, types, shapes (through [`Plant::new`]),
//! signals, simulation settings and the internal-model order of each signal component. Counts of
//! poles and gains, Hurwitz poles, μ and β are checked by [`Design::new`]; [`load_and_design`] runs
//! both.

pub mod exosystem;
mod names;
pub(crate) mod read;
mod write;

use std::path::Path;
use std::str::FromStr;

use nalgebra::{Complex, DMatrix, DVector};
use thiserror::Error;

use crate::controller::Precision;
use crate::design::{Design, DesignError, DesignSpec, ObserverChoice, RegressorScaling};
use crate::plant::{Plant, PlantError};
use crate::settings::TimeUnit;
use crate::settings::{self, KeyError, Method};
use crate::signal::{check_signals, Component, Harmonic, Signal};
use exosystem::Exosystem;
pub use names::{check_names, SignalNames};
pub(crate) use read::kind;
pub(crate) use read::syntax_message;
use read::{err, Table, Value};
pub use write::{design_table, plant_table, pole_list, signal_table, truth_table, with_design};
pub(crate) use write::{pole_lists, poles_value};

/// The paper's example (Section VIII) as a scenario file: `examples/paper.toml`.
pub const PAPER_EXAMPLE: &str = include_str!("../../../../examples/paper.toml");

/// A scenario error: the offending key and what was expected and found.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{key}: {message}")]
pub struct ScenarioError {
    /// Full key path (`plant.A[1]`, `design.channel_poles[0][1]`), `syntax` for TOML syntax
    /// errors, or the file's path for I/O errors.
    pub key: String,
    pub message: String,
    /// The value has the wrong type (a string where a number goes, a table where an array does):
    /// Python raises these as `TypeError`.
    pub wrong_type: bool,
}

impl ScenarioError {
    /// The error on `key`, of a value (not of its type).
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        ScenarioError { key: key.into(), message: message.into(), wrong_type: false }
    }

    /// The document read as a scenario is a study: the error is on a study's top-level key
    /// (`scenario`, `grid`, `tune`, …) that no scenario has.
    pub fn is_a_study(&self) -> bool {
        self.key != "simulation" && crate::study::TOP_KEYS.contains(&self.key.as_str())
    }
}

/// A validated scenario.
#[derive(Debug, Clone)]
pub struct Scenario {
    pub name: Option<String>,
    pub plant: Plant,
    /// `[plant]` `inputs`, `outputs`, `states`: the plant's signal names, where given.
    pub names: SignalNames,
    pub design: DesignSpec,
    /// g(t), one component per output.
    pub reference: Signal,
    /// ω(t), one component per column of D (empty when k = 0).
    pub disturbance: Signal,
    pub simulation: Simulation,
    /// Measurement noise on y: white at the sample rate (sampled-data runs), or band-limited with
    /// `bandwidth` (both loops).
    pub noise: Option<Noise>,
    /// `[truth]`: the simulated plant when it differs from the design model `plant` (any of A, B, C,
    /// D, Q, delays, x0 given, the rest `plant`'s); the design always uses `plant`.
    pub truth: Option<Plant>,
    /// `[truth]` `actuator_delays` and `u_max`: what the true plant's actuator does to u_f (the
    /// design knows nothing of it).
    pub actuator: Option<Actuator>,
}

/// Simulation settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Simulation {
    /// Final time, > 0.
    pub t_end: f64,
    /// Output rows at t = k·output_step, 0 < output_step ≤ t_end.
    pub output_step: f64,
    /// Whether the scenario gave `output_step`; otherwise it is [`default_output_step`]'s, which a
    /// change of t_end or sample time recomputes, and which no sample time offered must divide.
    pub output_step_given: bool,
    /// Solver tolerances, > 0.
    pub rtol: f64,
    pub atol: f64,
    /// Sampling period of the discrete controller; `None` for the continuous-time controller.
    pub sample_time: Option<f64>,
    /// The continuous loop's integrator (`method = "auto" | "explicit" | "imex"`; absent: auto).
    pub method: Method,
    /// The discrete controller's arithmetic (`precision = "f64" | "f32"`; absent: f64), with a
    /// `sample_time` only: f32 emulates a single-precision build ([`crate::sim::RunSettings::precision`]).
    pub precision: Precision,
}

impl Simulation {
    /// The same settings for the continuous loop: no sample time, and so no precision of its own.
    pub fn continuous(&self) -> Simulation {
        Simulation { sample_time: None, precision: Precision::F64, ..*self }
    }
}

impl Default for Simulation {
    fn default() -> Self {
        Simulation {
            t_end: 100.0,
            output_step: 0.1,
            output_step_given: false,
            rtol: settings::DEFAULT_TOLERANCE,
            atol: settings::DEFAULT_TOLERANCE,
            sample_time: None,
            method: Method::Auto,
            precision: Precision::F64,
        }
    }
}

pub use crate::settings::Actuator;
/// Measurement noise on y.
pub use crate::settings::MeasurementNoise as Noise;
pub use crate::settings::{MAX_OUTPUT_SAMPLES, MAX_SAMPLING_STEPS};

impl From<KeyError> for ScenarioError {
    fn from(e: KeyError) -> Self {
        ScenarioError::new(e.key, e.message)
    }
}

/// Why a scenario file gives no design: the file itself, or the design it asks for.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum LoadError {
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    #[error(transparent)]
    Design(#[from] DesignError),
}

/// Parses and validates a scenario, then designs every gain: the whole path from file to [`Design`].
pub fn load_and_design(text: &str) -> Result<(Scenario, Design), LoadError> {
    let scenario = Scenario::from_toml(text)?;
    let design = scenario.design()?;
    Ok((scenario, design))
}

const TOP_KEYS: &[&str] = &["name", "plant", "design", "reference", "disturbance", "simulation", "noise", "truth"];
const PLANT_KEYS: &[&str] =
    &["A", "B", "C", "D", "Q", "delays", "x0", "xhat0", "inputs", "outputs", "states", "time_unit"];
/// The keys of `[truth]`.
pub(crate) const TRUTH_KEYS: &[&str] = &["A", "B", "C", "D", "Q", "delays", "x0", "actuator_delays", "u_max", "u_min"];
/// The keys of `[design]`.
pub const DESIGN_KEYS: &[&str] = &[
    "observer_gain",
    "observer_poles",
    "channel_poles",
    "reference_filter_poles",
    "disturbance_filter_poles",
    "mu",
    "beta",
    "relative_degrees",
    "regressor_scaling",
    "reference_sizes",
    "disturbance_sizes",
    "reference_filter_orders",
    "disturbance_filter_orders",
];
const SIGNAL_KEYS: &[&str] = &["components"];
const COMPONENT_KEYS: &[&str] = &["bias", "harmonics"];
const HARMONIC_KEYS: &[&str] = &["amplitude", "frequency", "phase"];
/// The most rows the default output step gives (t_end / output_step): [`default_output_step`].
const DEFAULT_MAX_ROWS: f64 = 1e6;

const SIMULATION_KEYS: &[&str] = &["t_end", "output_step", "rtol", "atol", "sample_time", "method", "precision"];
const NOISE_KEYS: &[&str] = &["std", "seed", "bandwidth"];

/// The keys a scenario's table `section` takes (`"design"`, `"truth"`, …; `""` for the top level),
/// or `None` for a name that is no table of the scenario.
pub(crate) fn section_keys(section: &str) -> Option<&'static [&'static str]> {
    Some(match section {
        "" => TOP_KEYS,
        "plant" => PLANT_KEYS,
        "truth" => TRUTH_KEYS,
        "design" => DESIGN_KEYS,
        "simulation" => SIMULATION_KEYS,
        "noise" => NOISE_KEYS,
        _ => return None,
    })
}

impl FromStr for Scenario {
    type Err = ScenarioError;
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Scenario::from_toml(text)
    }
}

impl Scenario {
    /// Reads and validates a scenario file; I/O errors carry the path as key.
    pub fn from_path(path: &Path) -> Result<Scenario, ScenarioError> {
        Scenario::from_document(&read_document(path)?)
    }

    /// Parses and validates a scenario.
    pub fn from_toml(text: &str) -> Result<Scenario, ScenarioError> {
        Scenario::from_document(&parse_document(text)?)
    }

    /// Validates a parsed scenario document (what [`Scenario::from_toml`] does after parsing the
    /// text); studies edit documents by key path and validate them here.
    pub fn from_document(doc: &toml::Table) -> Result<Scenario, ScenarioError> {
        Scenario::from_document_with(doc, |partial, _| partial.complete())
    }

    /// [`Scenario::from_document`] with `[design]` completed by `complete` from the keys given
    /// ([`PartialDesign`]) and the rest of the scenario (its `design` is a placeholder then):
    /// the automatic design ([`crate::auto`]) chooses the keys a scenario leaves out.
    pub fn from_document_with<E: From<ScenarioError>>(
        doc: &toml::Table,
        complete: impl FnOnce(PartialDesign, &Scenario) -> Result<DesignSpec, E>,
    ) -> Result<Scenario, E> {
        let root = Table::new("", doc, TOP_KEYS)?;

        let name = root.get("name", |v| {
            let name = v.string()?;
            names::control_character(&name).map_or(Ok(name), |message| Err(err(v.key, message)))
        })?;
        const PLANT: &str = "the [plant] table (A, B, C, delays; D and Q with a [disturbance])";
        // The plant is read after the signals (D's columns are the disturbance's components), but
        // a file without it (an empty one) is told so first.
        root.require("plant", PLANT, |_| Ok(()))?;
        let reference = root.require("reference", "the [reference] table: g(t), one component per output", signal)?;
        let disturbance = root.get("disturbance", signal)?;
        let (plant, names) = root.require("plant", PLANT, |v| plant(v, disturbance.as_ref()))?;
        let (truth, actuator) = root.get("truth", |v| truth(v, &plant))?.unzip();
        let actuator = actuator.flatten();
        let partial = root.require(
            "design",
            &format!("the [design] table (observer, channel poles, filter poles, mu, beta), or {AUTO_DESIGN} to choose them all"),
            |v| partial_design(v, plant.m()),
        )?;
        let components = reference.components.iter().chain(disturbance.iter().flat_map(|d| &d.components));
        let fastest = components.flat_map(Component::frequencies).fold(0.0, f64::max);
        let simulation = match root.get("simulation", |v| simulation(v, fastest))? {
            Some(simulation) => simulation,
            None => {
                let t_end = Simulation::default().t_end;
                Simulation { output_step: default_output_step(t_end, fastest, None), ..Simulation::default() }
            }
        };
        let noise = root.get("noise", noise)?;

        let (m, k) = (plant.m(), plant.k());
        let disturbance = match disturbance {
            None if k > 0 && reference.len() == m => {
                return Err(err(
                    "disturbance",
                    format!("missing; plant.D has {k} columns (k = {k} disturbance components), so a [disturbance] table with {k} components is required; or remove plant.D and plant.Q"),
                ).into())
            }
            d => d.unwrap_or_default(),
        };
        check_signals(&plant, &reference, &disturbance).map_err(ScenarioError::from)?;
        let mut scenario = Scenario {
            name,
            plant,
            names,
            design: PartialDesign::placeholder(),
            reference,
            disturbance,
            simulation,
            noise,
            truth,
            actuator,
        };
        scenario.design = complete(partial, &scenario)?;
        scenario.check_after_design()?;
        Ok(scenario)
    }

    /// The checks that need `[design]`: each signal component's internal-model order, and noise
    /// (band-limited in a continuous run).
    fn check_after_design(&self) -> Result<(), ScenarioError> {
        let (design, simulation) = (&self.design, &self.simulation);
        internal_model_order(
            "reference",
            &self.reference,
            "design.reference_filter_poles",
            &design.reference_filter_poles,
        )?;
        internal_model_order(
            "disturbance",
            &self.disturbance,
            "design.disturbance_filter_poles",
            &design.disturbance_filter_poles,
        )?;
        if let Some(noise) = &self.noise {
            noise.check(self.plant.m())?;
            if simulation.sample_time.is_none() {
                noise.check_continuous()?;
            }
        }
        Ok(())
    }

    /// The plant that is simulated: `[truth]`, or the design model `plant` without one.
    pub fn true_plant(&self) -> &Plant {
        self.truth.as_ref().unwrap_or(&self.plant)
    }

    /// The plant input that exact tracking and rejection cost in steady state on the simulated
    /// plant, against its actuator limits ([`crate::diagnostics::steady_input`]).
    pub fn steady_input(&self) -> crate::diagnostics::SteadyInput {
        let m = self.plant.B.ncols();
        let names = (&self.names.inputs(m)[..], &self.names.outputs(m)[..]);
        crate::diagnostics::steady_input(
            self.true_plant(),
            (&self.reference, &self.disturbance),
            self.actuator.as_ref(),
            names,
        )
    }

    /// Whether the simulated plant differs from the design model (its matrices, delays, x0 or
    /// its actuator).
    pub fn truth_differs(&self) -> bool {
        self.truth.as_ref().is_some_and(|t| *t != self.plant) || self.actuator.as_ref().is_some_and(|a| !a.is_ideal())
    }

    /// [`Design::new`] for this scenario's plant and choices.
    pub fn design(&self) -> Result<Design, DesignError> {
        Design::new(&self.plant, &self.design)
    }
}

/// Parses a scenario file's TOML (syntax only), errors with line and column under the key `syntax`.
pub fn parse_document(text: &str) -> Result<toml::Table, ScenarioError> {
    if let Some(e) = crate::settings::input_too_long(text.len()) {
        return Err(err("syntax", format!("the text is {e}")));
    }
    text.parse().map_err(|e: toml::de::Error| {
        err("syntax", format!("{} (the file is not valid TOML)", syntax_message(text, &e)))
    })
}

/// Reads a scenario file's TOML document, at most [`crate::settings::MAX_INPUT_BYTES`] of it; I/O
/// errors carry the path as key.
pub fn read_document(path: &Path) -> Result<toml::Table, ScenarioError> {
    parse_document(&read_text(path)?)
}

/// A scenario file's text, the error naming the file when it cannot be read.
pub fn read_text(path: &Path) -> Result<String, ScenarioError> {
    crate::settings::read_input(path).map_err(|e| err(path.display().to_string(), format!("cannot read the file: {e}")))
}

/// `[plant]`: matrices and delays, shapes checked by [`Plant::new`] with errors mapped to keys, and
/// the signals' names.
fn plant(v: Value, disturbance: Option<&Signal>) -> Result<(Plant, SignalNames), ScenarioError> {
    let t = v.table(PLANT_KEYS)?;
    // A ragged matrix's rows are checked against n and k where those are known (C's n from A).
    let A = t.require("A", "the n×n state matrix", |v| v.matrix(square(v.value)))?;
    let n = A.nrows();
    let B = t.require("B", "the n×m input matrix", |v| v.matrix(None))?;
    let C = t.require("C", "the m×n output matrix", |v| v.matrix(Some((n, "n, from plant.A"))))?;
    let D = t.get("D", |v| v.matrix(None))?;
    let k_of_D = D.as_ref().map(DMatrix::ncols).filter(|&k| k > 0);
    let Q = t.get("Q", |v| v.matrix(k_of_D.map(|k| (k, "k, from plant.D"))))?;
    let delays = t.require("delays", "one input delay τ_i ≥ 0 per input", |v| v.numbers())?;
    let x0 = t.get("x0", |v| v.numbers())?.map(DVector::from_vec);
    let xhat0 = t.get("xhat0", |v| v.numbers())?.map(DVector::from_vec);
    let m = B.ncols();
    let k_signal = disturbance.map_or(0, Signal::len);
    // `D = []` (no rows) means no disturbance columns, like an absent D.
    let D = match D {
        Some(D) if D.nrows() > 0 => D,
        None if k_signal > 0 => {
            return Err(err(
                t.key("D"),
                format!(
                    "missing; [disturbance] has {}, so plant.D (n×k, disturbance to state) is required",
                    crate::settings::count(k_signal, "component", "components")
                ),
            ))
        }
        _ => DMatrix::zeros(n, 0),
    };
    let k = D.ncols();
    let Q = match Q {
        Some(Q) if Q.nrows() > 0 => Q,
        None if k > 0 => {
            return Err(err(
                t.key("Q"),
                format!("missing; plant.D has {}, so plant.Q ({m}×{k}, m×k, disturbance to output) is required; write zeros if ω does not reach y directly", crate::settings::count(k, "column", "columns")),
            ))
        }
        _ => DMatrix::zeros(m, 0),
    };
    let time_unit = t.get("time_unit", |v| TimeUnit::from_name(&v.string()?).map_err(|message| err(v.key, message)))?;
    let plant =
        Plant::new(A, B, C, D, Q, delays, x0).and_then(|p| p.with_xhat0(xhat0)).map_err(|e| plant_error(e, n, m, k))?;
    Ok((plant.with_time_unit(time_unit.unwrap_or_default()), SignalNames::read(&t, n, m)?))
}

/// `[truth]`: each given matrix has its `[plant]` counterpart's shape, the rest is `plant`'s; and the
/// actuator when `actuator_delays`, `u_max` or `u_min` is given (the others defaulting to 0, ∞ and
/// −u_max).
fn truth(v: Value, plant: &Plant) -> Result<(Plant, Option<Actuator>), ScenarioError> {
    let t = v.table(TRUTH_KEYS)?;
    let m = plant.m();
    let delays = t.get("actuator_delays", |v| v.numbers())?;
    let limits = t.get("u_max", |v| v.limits(f64::INFINITY))?;
    let lower = t.get("u_min", |v| v.limits(f64::NEG_INFINITY))?;
    let actuator = (delays.is_some() || limits.is_some() || lower.is_some()).then(|| Actuator {
        delays: delays.unwrap_or_else(|| vec![0.0; m]),
        limits: limits.unwrap_or_else(|| vec![f64::INFINITY; m]),
        lower,
    });
    if let Some(a) = &actuator {
        a.check(m)?;
    }
    let matrix = |name: &str, like: &DMatrix<f64>| -> Result<DMatrix<f64>, ScenarioError> {
        let from = format!("as plant.{name}");
        let Some(M) = t.get(name, |v| v.matrix(Some((like.ncols(), from.as_str()))))? else { return Ok(like.clone()) };
        // `[]` stands for a matrix without columns, as in [plant].
        let M = if M.nrows() == 0 && like.ncols() == 0 { like.clone() } else { M };
        if M.shape() != like.shape() {
            return Err(err(
                t.key(name),
                format!(
                    "expected {}×{} (the shape of plant.{name}: the true plant has the design model's dimensions), found {}×{}",
                    like.nrows(),
                    like.ncols(),
                    M.nrows(),
                    M.ncols()
                ),
            ));
        }
        Ok(M)
    };
    let vector = |name: &str, like: &[f64]| -> Result<Vec<f64>, ScenarioError> {
        let Some(x) = t.get(name, |v| v.numbers())? else { return Ok(like.to_vec()) };
        if x.len() != like.len() {
            return Err(err(
                t.key(name),
                format!("expected {} (as plant.{name}), found {}", crate::settings::entries(like.len()), x.len()),
            ));
        }
        Ok(x)
    };
    let (n, k) = (plant.n(), plant.k());
    let truth = Plant::new(
        matrix("A", &plant.A)?,
        matrix("B", &plant.B)?,
        matrix("C", &plant.C)?,
        matrix("D", &plant.D)?,
        matrix("Q", &plant.Q)?,
        vector("delays", &plant.delays)?,
        Some(DVector::from_vec(vector("x0", plant.x0.as_slice())?)),
    )
    .map_err(|e| {
        let e = plant_error(e, n, m, k);
        err(e.key.replacen("plant.", "truth.", 1), e.message)
    })?;
    Ok((truth.with_time_unit(plant.time_unit), actuator))
}

/// A [`PlantError`] as a scenario error on key `plant.<name>` ([`PlantError::explained`]).
fn plant_error(e: PlantError, n: usize, m: usize, k: usize) -> ScenarioError {
    let (key, message) = e.explained((n, m, k), "plant.");
    err(key, message)
}

/// A's row length: n, its number of rows (A is n×n), for [`Value::matrix`].
fn square(value: &toml::Value) -> Option<(usize, &'static str)> {
    value.as_array().map(|rows| (rows.len(), "n, the number of rows of plant.A: A is n×n"))
}

/// `[design]` as written, every key optional: [`PartialDesign::complete`] requires the keys of a
/// hand-made design, an automatic design ([`crate::auto`]) chooses the missing ones.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PartialDesign {
    pub observer: Option<ObserverChoice>,
    pub channel_poles: Option<Vec<Vec<Complex<f64>>>>,
    pub reference_filter_poles: Option<Vec<Vec<Complex<f64>>>>,
    pub disturbance_filter_poles: Option<Vec<Vec<Complex<f64>>>>,
    pub mu: Option<Vec<f64>>,
    pub beta: Option<f64>,
    pub relative_degrees: Option<Vec<usize>>,
    /// `None`: [`RegressorScaling::Paper`].
    pub regressor_scaling: Option<RegressorScaling>,
    /// Each reference component's size ([`DesignSpec::reference_sizes`]); `None`: 1 each.
    pub reference_sizes: Option<Vec<f64>>,
    /// Each disturbance component's size ([`DesignSpec::disturbance_sizes`]); `None`: 1 each.
    pub disturbance_sizes: Option<Vec<f64>>,
    /// Filter orders per reference component, for an automatic design in place of the poles.
    pub reference_filter_orders: Option<Vec<usize>>,
    /// Filter orders per disturbance component, for an automatic design in place of the poles.
    pub disturbance_filter_orders: Option<Vec<usize>>,
}

/// The automatic design as the library's messages name it ([`crate::auto::auto_design`]); a front
/// end replaces this phrase by its own words for it.
pub const AUTO_DESIGN: &str = "the automatic design (`auto_design`)";
/// How to get an automatic design, for the messages on a missing key.
const AUTO_HINT: &str = "or let the automatic design (`auto_design`) choose it";

impl PartialDesign {
    /// The choices of a hand-made design: every key but relative_degrees required, no filter orders.
    pub fn complete(self) -> Result<DesignSpec, ScenarioError> {
        fn required<T>(v: Option<T>, key: &str, what: &str) -> Result<T, ScenarioError> {
            v.ok_or_else(|| err(format!("design.{key}"), format!("missing; required: {what}; {AUTO_HINT}")))
        }
        for (key, orders) in [
            ("reference_filter_orders", &self.reference_filter_orders),
            ("disturbance_filter_orders", &self.disturbance_filter_orders),
        ] {
            if orders.is_some() {
                return Err(err(
                    format!("design.{key}"),
                    format!(
                        "filter orders are read only by {AUTO_DESIGN}, which writes the poles; give design.{} instead",
                        key.replace("orders", "poles")
                    ),
                ));
            }
        }
        let observer = self.observer.ok_or_else(|| {
            err(
                "design.observer_gain",
                format!("missing; give exactly one of design.observer_gain (the gain L, n×m) and design.observer_poles (the n poles of A − LC); {AUTO_HINT}"),
            )
        })?;
        Ok(DesignSpec {
            observer,
            channel_poles: required(
                self.channel_poles,
                "channel_poles",
                "one list of σ_i poles per output, e.g. [[-6.0, -2.0], [-4.0]]",
            )?,
            reference_filter_poles: required(
                self.reference_filter_poles,
                "reference_filter_poles",
                "one list of filter poles per reference component, e.g. [[-1.0, -6.0], [-9.0]]",
            )?,
            disturbance_filter_poles: self.disturbance_filter_poles.unwrap_or_default(),
            mu: required(self.mu, "mu", "one adaptation gain μ_i ≥ 0 per channel")?,
            beta: required(self.beta, "beta", "β > 0 of H(s) = 1/(βs + 1)")?,
            relative_degrees: self.relative_degrees,
            regressor_scaling: self.regressor_scaling.unwrap_or_default(),
            reference_sizes: self.reference_sizes.unwrap_or_default(),
            disturbance_sizes: self.disturbance_sizes.unwrap_or_default(),
        })
    }

    /// A design spec with nothing in it, held by a scenario only while its design is completed.
    fn placeholder() -> DesignSpec {
        DesignSpec {
            observer: ObserverChoice::Poles(Vec::new()),
            channel_poles: Vec::new(),
            reference_filter_poles: Vec::new(),
            disturbance_filter_poles: Vec::new(),
            mu: Vec::new(),
            beta: 1.0,
            relative_degrees: None,
            regressor_scaling: RegressorScaling::Paper,
            reference_sizes: Vec::new(),
            disturbance_sizes: Vec::new(),
        }
    }
}

/// `[design]`: the observer, channel and filter poles (or orders), μ and β, each optional here.
/// `m`: the plant's inputs, the observer gain's columns.
fn partial_design(v: Value, m: usize) -> Result<PartialDesign, ScenarioError> {
    let t = v.table(DESIGN_KEYS)?;
    let gain = t.get("observer_gain", |v| v.matrix(Some((m, "m, from plant.B"))))?;
    let poles = t.get("observer_poles", |v| v.poles())?;
    let observer = match (gain, poles) {
        (Some(L), None) => Some(ObserverChoice::Gain(L)),
        (None, Some(p)) => Some(ObserverChoice::Poles(p)),
        (Some(_), Some(_)) => {
            return Err(err(
                "design",
                "both observer_gain and observer_poles are given; give exactly one: the gain L (n×m), or the n poles of A − LC to place",
            ))
        }
        (None, None) => None,
    };
    let orders = |key: &str, per: &str| {
        t.get(key, |v| {
            v.array(&format!("one filter order ≥ 1 per {per}, e.g. [2, 1]"), |s| s.positive("a filter order"))
        })
    };
    Ok(PartialDesign {
        observer,
        channel_poles: t.get("channel_poles", |v| v.pole_lists("output"))?,
        reference_filter_poles: t.get("reference_filter_poles", |v| v.pole_lists("reference component"))?,
        disturbance_filter_poles: t.get("disturbance_filter_poles", |v| v.pole_lists("disturbance component"))?,
        mu: t.get("mu", |v| v.numbers())?,
        beta: t.get("beta", |v| v.number())?,
        relative_degrees: t.get("relative_degrees", |v| {
            v.array("one relative degree σ_i ≥ 1 per output, e.g. [2, 1]", |s| s.positive("a relative degree σ_i"))
        })?,
        regressor_scaling: t.get("regressor_scaling", |v| {
            RegressorScaling::from_name(&v.string()?).map_err(|message| err(v.key, message))
        })?,
        reference_sizes: t.get("reference_sizes", sizes)?,
        disturbance_sizes: t.get("disturbance_sizes", sizes)?,
        reference_filter_orders: orders("reference_filter_orders", "reference component")?,
        disturbance_filter_orders: orders("disturbance_filter_orders", "disturbance component")?,
    })
}

/// `design.reference_sizes` or `design.disturbance_sizes`: numbers, at least one (an empty list
/// would read as "1 each" and yet count as given, which keeps the automatic design from sizing).
fn sizes(v: Value) -> Result<Vec<f64>, ScenarioError> {
    let sizes = v.numbers()?;
    if sizes.is_empty() {
        return Err(err(v.key, "expected one size per component, found an empty list; leave the key out for 1 each"));
    }
    Ok(sizes)
}

/// `[reference]` or `[disturbance]`: `components = [{ bias, harmonics = [...] }, ...]`.
fn signal(v: Value) -> Result<Signal, ScenarioError> {
    let t = v.table(SIGNAL_KEYS)?;
    let components = t.require(
        "components",
        "an array of components, each { bias = …, harmonics = [{ amplitude = …, frequency = … }] }",
        |v| v.array("an array of components (inline tables)", component),
    )?;
    Ok(Signal { components })
}

fn component(v: Value) -> Result<Component, ScenarioError> {
    let t = v.table(COMPONENT_KEYS)?;
    Ok(Component {
        bias: t.get("bias", |v| v.number())?.unwrap_or(0.0),
        harmonics: t
            .get("harmonics", |v| v.array("an array of harmonics (inline tables)", harmonic))?
            .unwrap_or_default(),
    })
}

fn harmonic(v: Value) -> Result<Harmonic, ScenarioError> {
    let t = v.table(HARMONIC_KEYS)?;
    let amplitude = t.require("amplitude", "the amplitude a of a·sin(ωt + φ)", |v| v.number())?;
    let frequency =
        t.require("frequency", "the frequency ω ≥ 0 (rad per unit of the plant's time) of a·sin(ωt + φ)", |v| {
            let w = v.number()?;
            if w < 0.0 {
                return Err(err(v.key, crate::signal::negative_frequency(w)));
            }
            Ok(w)
        })?;
    let phase = t.get("phase", |v| v.number())?.unwrap_or(0.0);
    Ok(Harmonic { amplitude, frequency, phase })
}

/// A document's `[simulation]` `keys` each checked on its own (type and range; the bounds between
/// them are the whole scenario's): for a run that then overrides some of them (a sample time,
/// horizon or output step given apart from the file), which must not hide a bad value in it.
pub fn check_simulation(doc: &toml::Table, keys: &[&str]) -> Result<(), ScenarioError> {
    let Some(value) = doc.get("simulation") else { return Ok(()) };
    let t = Value { key: "simulation", value }.table(SIMULATION_KEYS)?;
    for (key, _) in settings::POSITIVE_SIMULATION.iter().filter(|(key, _)| keys.contains(key)) {
        t.get(key, |v| Ok(settings::check_positive(key, v.number()?)?))?;
    }
    Ok(())
}

/// The output step of a scenario that gives none: 1, 2 or 5 × 10^k, the longest within t_end/1000
/// and 2π/(20·ω_max) (twenty rows a period of the fastest harmonic, `fastest` rad per unit, of g
/// and ω), never more than 10⁶ rows; with a sample time T_s the least whole
/// multiple of it at or beyond that. Scale-free: a fixed 0.1 had recorded 2 rows of a loop in ms
/// written in s and 600,001 of one in s written in ms. The paper's 100 s at 2 rad/s: 0.1.
pub fn default_output_step(t_end: f64, fastest: f64, sample_time: Option<f64>) -> f64 {
    let period = if fastest > 0.0 { std::f64::consts::TAU / (20.0 * fastest) } else { f64::INFINITY };
    let want = (t_end / 1000.0).min(period);
    let decade = 10f64.powf(want.log10().floor());
    let step = [5.0, 2.0, 1.0].iter().map(|f| f * decade).find(|&h| h <= want * (1.0 + 1e-12)).unwrap_or(decade);
    let step = step.max(t_end / DEFAULT_MAX_ROWS);
    match sample_time {
        Some(T) if T > 0.0 && step.is_finite() => T * (step / T * (1.0 - 1e-12)).ceil().max(1.0),
        _ => step,
    }
}

/// `[simulation]`, with defaults for absent keys (the output step [`default_output_step`] for
/// the fastest harmonic `fastest` of g and ω); the ranges are [`settings`]' checks.
fn simulation(v: Value, fastest: f64) -> Result<Simulation, ScenarioError> {
    let t = v.table(SIMULATION_KEYS)?;
    let default = Simulation::default();
    let number = |key| t.get(key, |v| v.number());
    let t_end = number("t_end")?.unwrap_or(default.t_end);
    let sample_time = number("sample_time")?;
    let given = number("output_step")?;
    let output_step = given.unwrap_or_else(|| default_output_step(t_end, fastest, sample_time));
    // The sample time first: a default output step is a multiple of it, which a sample time beyond
    // t_end had made the error's subject (helper tryout, 2026-12-07).
    settings::check_positive("t_end", t_end)?;
    if let Some(T) = sample_time {
        settings::check_sample_time(t_end, T)?;
    }
    settings::check_horizon(t_end, output_step)?;
    let (rtol, atol) = (number("rtol")?.unwrap_or(default.rtol), number("atol")?.unwrap_or(default.atol));
    settings::check_tolerances(rtol, atol)?;
    let method = t
        .get("method", |v| Method::from_name(&v.string()?).map_err(|message| err(v.key, message)))?
        .unwrap_or_default();
    let precision = t
        .get("precision", |v| {
            let name = v.string()?;
            let found = Precision::from_name(&name);
            found.ok_or_else(|| err(v.key, format!("expected \"f64\" or \"f32\", found {name:?}")))
        })?
        .unwrap_or_default();
    if precision != Precision::F64 && sample_time.is_none() {
        return Err(err(
            "simulation.precision",
            "f32 is the discrete controller's arithmetic: give simulation.sample_time too, or leave precision out for the continuous loop, whose controller has none".to_string(),
        ));
    }
    let output_step_given = given.is_some();
    Ok(Simulation { t_end, output_step, output_step_given, rtol, atol, sample_time, method, precision })
}

/// `[noise]`: per-output standard deviations and a seed.
fn noise(v: Value) -> Result<Noise, ScenarioError> {
    let t = v.table(NOISE_KEYS)?;
    Ok(Noise {
        std: t.require("std", "one standard deviation ≥ 0 per output", |v| v.numbers())?,
        seed: t.get("seed", |v| v.unsigned())?.unwrap_or(0),
        bandwidth: t.get("bandwidth", |v| v.number())?,
    })
}

/// Assumptions 2/3: each component's filter has at least as many poles as its exosystem has states.
/// Skipped when the number of pole lists is wrong: [`Design::new`] reports that.
fn internal_model_order(
    what: &str,
    signal: &Signal,
    key: &str,
    poles: &[Vec<nalgebra::Complex<f64>>],
) -> Result<(), ScenarioError> {
    if poles.len() != signal.len() {
        return Ok(());
    }
    for (i, (c, p)) in signal.components.iter().zip(poles).enumerate() {
        let exo = Exosystem::of(c);
        if exo.dim() > p.len() {
            return Err(err(
                format!("{key}[{i}]"),
                format!(
                    "{what} component {} ({}) needs at least {} filter poles (internal-model order); got {}; add poles (a real pole counts 1, a pair [re, im] counts 2)",
                    i + 1,
                    exo.describe(),
                    exo.dim(),
                    p.len()
                ),
            ));
        }
    }
    Ok(())
}
