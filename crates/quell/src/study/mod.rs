//! Studies: many runs of one scenario. A study file names a scenario, a grid of scenario values
//! (the cartesian product of `[grid]`), Monte Carlo draws of the true plant at every grid point
//! (`[monte_carlo]`), the settling band (`[settle]`) and the per-channel tuning (`[tune]`).
//!
//! Every run is reproducible on its own: [`Study::spec_with_nominal`] builds run `index`'s [`RunSpec`] from the
//! study alone (its seed from the study seed and the run's draw index, see [`run_seed`]), and
//! [`run_one`] carries it out. [`sweep`] runs them in parallel (rayon), or every `count`-th of them
//! for a [`Shard`]; [`Summary`] aggregates the rows per grid point. The format is documented in
//! `docs/studies.md`; every error names the key, see `docs/errors.md`.

mod output;
mod path;
mod summary;
mod sweep;
mod tune;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::scenario::read::Value;
use crate::scenario::{kind, syntax_message, Scenario, PAPER_EXAMPLE};
pub use crate::sim::settle::Settle;
use crate::sim::Peaks;
pub use output::{
    csv_field, csv_number, header, read_runs_csv, runs_csv_bounds, write_run_row, write_runs_csv, write_runs_header,
    RunsFile,
};
pub use path::{KeyPath, Shape};
pub use summary::{quantile, AxisMeta, ChannelQuantiles, PointSummary, Quantiles, StudyMeta, Summary, QUANTILES};
pub use sweep::{run_one, run_one_until, run_seed, sweep, Outcome, Row, RunSpec, Shard, Sweep, SweepOptions};
pub use tune::{
    joint_better, tune, tune_cautions, tune_stiff_warnings, Objective, OnPoint, SearchedWithin, Tie, TuneCurve,
    TuneOptions, TunePoint, TuneResult, TuneSpec, JOINT_ROUNDS,
};

/// A study-file error: the key path in the study file (`grid."design.mu[0]"[2]`) and what was
/// expected and found.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{key}: {message}")]
pub struct StudyError {
    pub key: String,
    pub message: String,
    /// The value has the wrong TOML type (a string for a number): Python raises it as a
    /// `TypeError`, as it does [`crate::ScenarioError::wrong_type`].
    pub wrong_type: bool,
}

/// A study a sweep can run: one without `[tune]`, which only tuning reads (`quell tune`, Python's
/// `quell.tune`); a sweep would carry out its grid and draws and ignore it.
pub fn check_sweep(study: &Study) -> Result<(), StudyError> {
    match study.tune {
        Some(_) => Err(err(
            "tune",
            "read by tuning only (quell tune, or quell.tune from Python), which a sweep would ignore: tune the file, or remove [tune] to sweep its grid and draws",
        )),
        None => Ok(()),
    }
}

fn err(key: impl Into<String>, message: impl Into<String>) -> StudyError {
    StudyError { key: key.into(), message: message.into(), wrong_type: false }
}

/// `v` at `key` is not of the type `expected` names: "expected …, found a string".
pub(crate) fn found(key: impl Into<String>, expected: &str, v: &toml::Value) -> StudyError {
    StudyError { wrong_type: true, ..err(key, format!("expected {expected}, found {}", kind(v))) }
}

/// The scenario reader's errors (`scenario::read`) name study keys when it reads a study.
impl From<crate::ScenarioError> for StudyError {
    fn from(e: crate::ScenarioError) -> Self {
        StudyError { key: e.key, message: e.message, wrong_type: e.wrong_type }
    }
}

/// Runs above which a front end asks for confirmation before a sweep starts.
pub const CONFIRM_RUNS: u64 = 10_000_000;

/// Grid points above which a front end that writes summary.json asks for confirmation too: it
/// summarizes every point, about 3 kB of file and 2.4 kB of memory each with two channels (a 700 ×
/// 700 grid of 490,000 one-draw runs, under [`CONFIRM_RUNS`], took 1 GB and wrote 1.5 GB; hostile
/// review, 2026-12-06).
pub const CONFIRM_POINTS: usize = 100_000;

/// Worker threads a sweep or tuning may ask for (`jobs`): far more than any machine's
/// cores, few enough that starting them is quick (10⁴ threads took over a minute).
pub const MAX_JOBS: usize = 1024;

/// Runs a study may have at most: 10⁹ runs are ~200 GB of rows and, at ~60 ms each, ~700
/// CPU-days; beyond, a study file is refused when it is read (before anything is allocated).
pub const MAX_RUNS: u64 = 1_000_000_000;

/// One axis of the grid: a scenario key path and the values it takes.
#[derive(Debug, Clone, PartialEq)]
pub struct GridAxis {
    /// The key path as written (`design.mu[0]`).
    pub key: String,
    path: KeyPath,
    pub values: Vec<toml::Value>,
}

/// How a Monte Carlo draw perturbs every entry x of a value; ξ ~ N(0, 1), υ ~ U(−1, 1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Law {
    /// x (1 + r ξ).
    Relative(f64),
    /// x (1 + r υ): within ±r·|x| of x, the sign kept for r < 1 (a delay stays a delay).
    RelativeUniform(f64),
    /// x + σ ξ.
    Normal(f64),
    /// x + a υ.
    Uniform(f64),
}

const LAWS: &str = "{ relative = r } (x·(1 + r·ξ), ξ ~ N(0, 1)), { relative_uniform = r } (x·(1 + U(−r, r))), { normal = σ } (x + σ·ξ) or { uniform = a } (x + U(−a, a))";

/// A Monte Carlo perturbation of one scenario value.
#[derive(Debug, Clone, PartialEq)]
pub struct Perturbation {
    pub key: String,
    path: KeyPath,
    pub law: Law,
}

/// `[monte_carlo]`: draws per grid point and the perturbations of each draw.
#[derive(Debug, Clone, PartialEq)]
pub struct MonteCarlo {
    pub runs: usize,
    pub seed: u64,
    pub perturbations: Vec<Perturbation>,
}

/// `[runaway]`: early ends for the Monte Carlo draws of a continuous loop, relative to the
/// *nominal run* of their grid point (its scenario without draws). A loop that blows up turns
/// stiff (the adaptive law's rate μ_i Ω_i grows with the square of the regressor) long before a
/// state reaches the divergence bound, so without these rules it spends the step budget instead
/// (docs/studies.md, "Runaway").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Runaway {
    /// The plant state x, the observer state x̂ (bounded at least as x is) or the parameters η̂
    /// beyond `peak` times its peak in the nominal run: the run is `stopped`.
    #[serde(deserialize_with = "off_from_null")]
    pub peak: f64,
    /// More than `steps` times the nominal run's solver steps: the run is `failed` ("step budget").
    #[serde(deserialize_with = "off_from_null")]
    pub steps: f64,
}

/// A rule turned off (+∞) is written `null` in summary.json (JSON has no infinity): read back as +∞,
/// so that the shards of such a study merge.
fn off_from_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
}

impl Default for Runaway {
    fn default() -> Self {
        Runaway { peak: 100.0, steps: 3.0 }
    }
}

const RUNAWAY_KEYS: &[&str] = &["peak", "steps"];

/// How many grid points [`Study::fast_rate_caution`] checks before a sweep at most (each a design
/// and the loop's eigenvalues, about 0.1 ms on the paper's example).
pub const FAST_RATE_POINTS: usize = 64;

/// How long [`Study::fast_rate_caution`] checks grid points at most, after the first.
pub const FAST_RATE_CHECK_TIME: std::time::Duration = std::time::Duration::from_millis(250);

/// What a grid point's nominal run did: the scale [`Runaway`] compares a draw with.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Nominal {
    /// Solver steps.
    pub steps: usize,
    /// The peaks of its watched signals.
    pub peaks: Peaks,
    /// The breakpoints t = Σ k_i τ_i its loop lands on ([`crate::sim::Run::breakpoints`]): a draw
    /// whose delays differ lands on more, each a step the nominal run did not take.
    #[serde(default)]
    pub breakpoints: usize,
    /// Its adaptive law was expected stiff ([`crate::sim::Run::expects_stiff`]): the step rule
    /// holds a draw expected stiff to its steps only then.
    #[serde(default)]
    pub expects_stiff: bool,
    /// Its divergence bound on ξ̂ ([`crate::sim::Run::divergence_bounds`]), which the peak rule keeps
    /// for ξ̂ in place of a multiple of its peak (ξ̂ is not bounded by [`Runaway::peak`]); computed
    /// once per grid point, so that a draw need not compute the averaged law it rests on.
    #[serde(default = "unbounded", deserialize_with = "off_from_null")]
    pub xi_bound: f64,
}

/// The nominal runs carried out so far, by grid point ([`Study::nominal`]).
#[derive(Debug, Default)]
struct NominalRuns(std::sync::Mutex<std::collections::HashMap<usize, Option<Nominal>>>);

impl NominalRuns {
    fn lock(&self) -> std::sync::MutexGuard<'_, std::collections::HashMap<usize, Option<Nominal>>> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Clone for NominalRuns {
    fn clone(&self) -> Self {
        NominalRuns(std::sync::Mutex::new(self.lock().clone()))
    }
}

/// No bound (a nominal run written before [`Nominal::xi_bound`]).
fn unbounded() -> f64 {
    f64::INFINITY
}

/// A parsed and checked study.
#[derive(Debug, Clone)]
pub struct Study {
    /// The scenario document with the study's `[simulation]` overrides applied.
    base: toml::Table,
    /// Where the scenario came from, for messages (`paper.toml`, or `the paper's example`).
    pub scenario_source: String,
    /// The scenario file read (its path joined to the study file's directory); `None` for the
    /// paper's example or a scenario table. A command's outputs must not replace it.
    pub scenario_path: Option<PathBuf>,
    pub grid: Vec<GridAxis>,
    /// Grid points: the product of the axes' lengths (1 without a grid), counted once when read.
    points: usize,
    pub monte_carlo: Option<MonteCarlo>,
    pub settle: Settle,
    pub tune: Option<TuneSpec>,
    /// The solver's step budget per continuous run (`max_steps`); `None`: each run's own default,
    /// derived from its problem ([`crate::sim::default_max_steps`]).
    pub max_steps: Option<usize>,
    /// `[runaway]` (defaults: [`Runaway::default`]).
    pub runaway: Runaway,
    /// Channels m of the scenario.
    pub m: usize,
    /// The scenario's true actuator, as it parsed it ([`Study::u_max`]).
    actuator: Option<crate::settings::Actuator>,
    fingerprint: u64,
    /// The study as one self-contained document: `scenario` the scenario table, `[simulation]`'s
    /// overrides applied to it.
    document: toml::Table,
    /// Per grid point reached, in a study with Monte Carlo draws, its nominal run (`None`:
    /// sampled-data, or it did not complete), carried out at the point's first
    /// [`Study::spec_with_nominal`]; kept by point, not for every point (a shard of 10⁹ points
    /// reaches a few).
    nominal: Option<NominalRuns>,
}

/// A study's top-level keys; every one but `simulation` is unknown to a scenario.
pub(crate) const TOP_KEYS: &[&str] =
    &["scenario", "max_steps", "runaway", "simulation", "grid", "monte_carlo", "settle", "tune"];

const SETTLE_KEYS: &[&str] = &["relative", "absolute"];

/// A finite number at `key`: the scenario reader's check, with `what` in its refusal.
fn number(key: &str, v: &toml::Value, what: &str) -> Result<f64, StudyError> {
    Ok(Value { key, value: v }.finite(what)?)
}

fn non_negative(key: &str, v: &toml::Value, what: &str) -> Result<f64, StudyError> {
    let x = number(key, v, what)?;
    if x >= 0.0 {
        Ok(x)
    } else {
        Err(err(key, format!("expected {what}, found {}", crate::settings::fmt_short(x))))
    }
}

/// A factor of `[runaway]`: ≥ 1, or `inf` (the rule off).
fn factor(key: &str, v: &toml::Value) -> Result<f64, StudyError> {
    const WHAT: &str = "a factor ≥ 1 (or inf to turn the rule off)";
    match v {
        toml::Value::Float(x) if *x >= 1.0 => Ok(*x),
        toml::Value::Integer(i) if *i >= 1 => Ok(*i as f64),
        toml::Value::Float(x) => Err(err(key, format!("expected {WHAT}, found {}", crate::settings::fmt_short(*x)))),
        toml::Value::Integer(i) => Err(err(key, format!("expected {WHAT}, found {i}"))),
        _ => Err(found(key, WHAT, v)),
    }
}

fn unsigned(key: &str, v: &toml::Value, what: &str) -> Result<u64, StudyError> {
    match v {
        toml::Value::Integer(i) if *i >= 0 => Ok(*i as u64),
        toml::Value::Integer(i) => Err(err(key, format!("expected {what}, found {i}"))),
        // `runs = 1e12` is a float in TOML: show the value, and the integer to write.
        toml::Value::Float(f) if f.fract() == 0.0 && (0.0..9e18).contains(f) => {
            let shown = if *f >= 1e6 { format!("{f:e}") } else { format!("{f:.1}") };
            let message = format!(
                "expected {what}, found {shown}, a floating-point number; write it as an integer, {}",
                *f as u64
            );
            Err(err(key, message))
        }
        _ => Err(found(key, what, v)),
    }
}

fn table<'a>(key: &str, v: &'a toml::Value) -> Result<&'a toml::Table, StudyError> {
    v.as_table().ok_or_else(|| found(key, "a table", v))
}

/// Every key of `t` (the table at `at`, "" for the document) is one of `valid`: the scenario
/// reader's check, with its did-you-mean hint.
fn unknown_keys(at: &str, t: &toml::Table, valid: &[&str]) -> Result<(), StudyError> {
    if let Some(e) = t.keys().find_map(|k| misplaced_top_key(at, k, valid)) {
        return Err(e);
    }
    crate::scenario::read::Table::new(at, t, valid)?;
    Ok(())
}

/// Whether `key` is a top-level key of a scenario that a study does not take.
pub fn is_scenario_section(key: &str) -> bool {
    !TOP_KEYS.contains(&key) && crate::scenario::section_keys("").is_some_and(|keys| keys.contains(&key))
}

/// A top-level key of the study (`scenario`, `max_steps`) found in table `at`: written below a
/// `[table]` header, TOML puts it in that table (`max_steps = 5` after `[monte_carlo]` was read
/// as a perturbation and refused as "expected a distribution").
fn misplaced_top_key(at: &str, key: &str, valid: &[&str]) -> Option<StudyError> {
    (!at.is_empty() && matches!(key, "scenario" | "max_steps") && !valid.contains(&key)).then(|| {
        err(
            format!("{at}.{key}"),
            format!("`{key}` is a key of the study file's top level, but written below the [{at}] header TOML puts it in that table; move it above the file's first [table] header"),
        )
    })
}

/// Grid point `point`'s index on each axis of `lens` values (the first axis varies slowest).
pub(crate) fn axis_indices(point: usize, lens: &[usize]) -> Vec<usize> {
    let mut rest = point;
    let mut idx = vec![0; lens.len()];
    for (i, &len) in lens.iter().enumerate().rev() {
        idx[i] = rest % len.max(1);
        rest /= len.max(1);
    }
    idx
}

/// A key of `[truth]` that may be perturbed before the scenario gives it: every one.
use crate::scenario::TRUTH_KEYS;

/// `truth.u_max` of `doc` as numbers (integers too), +∞ per input where it is not given.
fn upper_limits(doc: &toml::Table, m: usize) -> Vec<f64> {
    let number = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
    match doc.get("truth").and_then(|t| t.get("u_max")).and_then(toml::Value::as_array) {
        Some(upper) => upper.iter().map(|u| number(u).unwrap_or(f64::INFINITY)).collect(),
        None => vec![f64::INFINITY; m],
    }
}

/// Where the scenario leaves `truth.u_min` to its default (−u_max) and a run's axes or draws set
/// some of it, the entries they do not set (`is_set` of the key path) follow that run's own u_max,
/// as the scenario's default does: filled before the values are applied, they had kept the nominal
/// −u_max beside a grid or a draw over u_max (review, 2026-12-08).
fn lower_limits_follow(doc: &mut toml::Table, is_set: impl Fn(&str) -> bool) {
    if is_set("truth.u_min") {
        return;
    }
    let Some(n) = doc.get("truth").and_then(|t| t.get("u_min")).and_then(toml::Value::as_array).map(Vec::len) else {
        return;
    };
    let upper = upper_limits(doc, n);
    let Some(toml::Value::Array(lower)) = doc.get_mut("truth").and_then(|t| t.get_mut("u_min")) else { return };
    for (i, (l, u)) in lower.iter_mut().zip(upper).enumerate() {
        if !is_set(&format!("truth.u_min[{i}]")) {
            *l = toml::Value::Float(-u);
        }
    }
}

/// Gives `doc` the value that `path` names when the scenario leaves it to a default: `truth.<X>`
/// defaults to `plant.<X>`, `plant.x0` (or `truth.x0`) and `truth.actuator_delays` to zeros,
/// `truth.u_max` to +∞ per input and `truth.u_min` to −u_max (a grid over a drive's limit had needed the scenario to give one
/// first). Other paths are left alone.
fn fill_default(doc: &mut toml::Table, path: &KeyPath) {
    let section = path.section();
    let key = path.to_string();
    let name = key.split(['.', '[']).nth(1).unwrap_or("");
    if !TRUTH_KEYS.contains(&name) || !(section == "truth" || (section == "plant" && name == "x0")) {
        return;
    }
    let plant = doc.get("plant").and_then(toml::Value::as_table);
    let n = plant.and_then(|p| p.get("A")).and_then(toml::Value::as_array).map_or(0, Vec::len);
    let from_plant = plant.and_then(|p| p.get(name)).cloned();
    let zeros = || toml::Value::Array(vec![toml::Value::Float(0.0); n]);
    let inputs = plant.and_then(|p| p.get("B")).and_then(toml::Value::as_array);
    let m = inputs.and_then(|b| b.first()).and_then(toml::Value::as_array).map_or(0, Vec::len);
    let per_input = |v: f64| toml::Value::Array(vec![toml::Value::Float(v); m]);
    if section == "plant" {
        if from_plant.is_none() {
            if let Some(toml::Value::Table(p)) = doc.get_mut("plant") {
                p.insert("x0".into(), zeros());
            }
        }
        return;
    }
    let value = match (name, from_plant) {
        ("actuator_delays", _) => per_input(0.0),
        ("u_max", _) => per_input(f64::INFINITY),
        // −u_max, the symmetric range the scenario had ([`lower_limits_follow`] keeps it so).
        ("u_min", _) => toml::Value::Array(upper_limits(doc, m).into_iter().map(|u| toml::Value::Float(-u)).collect()),
        (_, Some(v)) => v,
        ("x0", None) => zeros(),
        (_, None) => return,
    };
    let truth = doc.entry("truth").or_insert_with(|| toml::Value::Table(toml::Table::new()));
    if let toml::Value::Table(t) = truth {
        t.entry(name).or_insert(value);
    }
}

impl Study {
    /// Reads a study file; its `scenario` is relative to the file's directory.
    pub fn from_path(path: &Path) -> Result<Study, StudyError> {
        let text = crate::settings::read_input(path)
            .map_err(|e| err(path.display().to_string(), format!("cannot read the study file: {e}")))?;
        Study::from_toml(&text, path.parent())
    }

    /// Parses and checks a study; `dir` is where a relative `scenario` path is looked up
    /// (`None`: the working directory). Every grid value and perturbation is applied to the
    /// scenario and checked (parse, design and the checks its run makes before it starts) before
    /// this returns.
    pub fn from_toml(text: &str, dir: Option<&Path>) -> Result<Study, StudyError> {
        if let Some(e) = crate::settings::input_too_long(text.len()) {
            return Err(err("syntax", format!("the study text is {e}")));
        }
        let doc: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            err("syntax", format!("{} (the study file is not valid TOML)", syntax_message(text, &e)))
        })?;
        Study::from_table(&doc, dir)
    }

    /// Checks a parsed study document (what [`Study::from_toml`] does after parsing). Its
    /// `scenario` is a file's path (looked up in `dir`) or the scenario document itself, a table.
    pub fn from_table(doc: &toml::Table, dir: Option<&Path>) -> Result<Study, StudyError> {
        unknown_keys("", doc, TOP_KEYS).map_err(|mut e| {
            // A scenario's own sections where a study's keys belong: the file is a scenario.
            if is_scenario_section(&e.key) {
                e.message.push_str("; this is a scenario, not a study: a study names a scenario (scenario = \"paper.toml\") and what to vary ([grid], [monte_carlo]; docs/studies.md)");
            }
            e
        })?;
        let (mut base, scenario_source, scenario_path) = base_scenario(doc, dir)?;
        let scenario = apply_simulation(doc, &mut base, &scenario_source)?;
        let grid = read_grid(doc)?;
        let monte_carlo = match doc.get("monte_carlo") {
            None => None,
            Some(mc) => Some(monte_carlo(&base, table("monte_carlo", mc)?, &scenario_source)?),
        };
        if let (Some(mc), Some(t_s)) = (&monte_carlo, scenario.simulation.sample_time) {
            let own = doc.get("simulation").and_then(|s| s.get("sample_time")).is_some();
            check_drawn_delays(mc, (t_s, own), scenario.plant.time_unit)?;
        }
        if let Some(mc) = &monte_carlo {
            check_infinite_laws(mc, &base, &grid, &scenario_source)?;
        }
        let tune = match doc.get("tune") {
            None => None,
            Some(t) => Some(TuneSpec::parse(table("tune", t)?, &scenario)?),
        };
        let points = study_size(&grid, monte_carlo.as_ref())?;
        // Refused before any run: without a grid nothing changes the scenario's checks, and a grid
        // value that fails as the scenario does is not to blame.
        let base_error = base_run_error(doc, &scenario, &scenario_source);
        match &base_error {
            Some((_, e)) if grid.is_empty() => return Err(e.clone()),
            _ => check_grid(&grid, &base, &scenario_source, base_error.as_ref())?,
        }
        let nominal = monte_carlo.is_some().then(Default::default);
        let max_steps = read_max_steps(doc, &scenario)?;
        let mut document = doc.clone();
        document.remove("simulation");
        document.insert("scenario".into(), toml::Value::Table(base.clone()));
        Ok(Study {
            fingerprint: fingerprint(doc, &base),
            base,
            scenario_source,
            scenario_path,
            grid,
            points,
            monte_carlo,
            settle: read_settle(doc)?,
            tune,
            max_steps,
            runaway: read_runaway(doc)?,
            m: scenario.plant.m(),
            actuator: scenario.actuator.clone(),
            document,
            nominal,
        })
    }

    /// The study as one self-contained document, its scenario inline: [`Study::from_table`] reads
    /// it back to the same study (same runs, same fingerprint) on any machine.
    pub fn to_table(&self) -> &toml::Table {
        &self.document
    }

    /// Grid points: the product of the axes' lengths (1 without a grid).
    pub fn points(&self) -> usize {
        self.points
    }

    /// Draws per grid point (1 without Monte Carlo).
    pub fn draws(&self) -> usize {
        self.monte_carlo.as_ref().map_or(1, |mc| mc.runs)
    }

    /// Runs: points × draws (at most [`MAX_RUNS`], checked when the study is read).
    pub fn len(&self) -> u64 {
        self.points() as u64 * self.draws() as u64
    }

    /// True when the study has no runs (never: a grid axis and `runs` are never empty).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The study's fingerprint: a hash of its scenario, overrides, grid, draws and settle band.
    pub fn fingerprint(&self) -> u64 {
        self.fingerprint
    }

    /// Index of each axis at grid point `point`; the first axis varies slowest.
    pub fn grid_index(&self, point: usize) -> Vec<usize> {
        axis_indices(point, &self.grid.iter().map(|a| a.values.len()).collect::<Vec<_>>())
    }

    /// The scenario document of run `index`: the grid point's values, then the draw's
    /// perturbations, applied to the base scenario.
    fn document(&self, point: usize, seed: Option<u64>) -> toml::Table {
        let mut doc = self.base.clone();
        for (axis, &i) in self.grid.iter().zip(&self.grid_index(point)) {
            fill_default(&mut doc, &axis.path);
            axis.path.set(&mut doc, axis.values[i].clone()).expect("checked when the study was read");
        }
        if let (Some(mc), Some(seed)) = (&self.monte_carlo, seed) {
            let mut rng = crate::sim::noise::Gaussian::new(seed);
            for p in &mc.perturbations {
                fill_default(&mut doc, &p.path);
                let v = p.path.get_mut(&mut doc).expect("checked when the study was read");
                path::for_each_number(v, &mut |x| {
                    *x = match p.law {
                        Law::Relative(r) => *x * (1.0 + r * rng.sample()),
                        Law::RelativeUniform(r) => *x * (1.0 + r * (2.0 * rng.uniform() - 1.0)),
                        Law::Normal(s) => *x + s * rng.sample(),
                        Law::Uniform(a) => *x + a * (2.0 * rng.uniform() - 1.0),
                    }
                });
            }
        }
        if self.base.get("truth").and_then(|t| t.get("u_min")).is_none() {
            // As the paths read, not as written (`truth.u_min[00]` had been undone; review).
            let keys: Vec<String> = (self.grid.iter().map(|a| a.path.canonical()))
                .chain(self.monte_carlo.iter().flat_map(|mc| mc.perturbations.iter().map(|p| p.path.canonical())))
                .collect();
            lower_limits_follow(&mut doc, |key| keys.iter().any(|k| k == key));
        }
        doc
    }

    /// The names of runs.csv's last columns, the values a draw gives ([`drawn_values`] of the
    /// perturbed keys); none without Monte Carlo.
    pub fn drawn_columns(&self) -> Vec<String> {
        // A draw fills the keys it perturbs that the scenario leaves to their defaults.
        let first = self.document(0, self.place(0).2);
        drawn_values(&self.drawn_keys(), &self.grid_keys(), &first).into_iter().map(|(n, _)| n).collect()
    }

    /// The keys the Monte Carlo draws perturb, in the study's order.
    pub fn drawn_keys(&self) -> Vec<String> {
        self.monte_carlo.as_ref().map_or_else(Vec::new, |mc| mc.perturbations.iter().map(|p| p.key.clone()).collect())
    }

    /// The grid's keys, as written.
    fn grid_keys(&self) -> Vec<String> {
        self.grid.iter().map(|a| a.key.clone()).collect()
    }

    /// The drawn values of a run's scenario document `scenario` ([`Study::run_document`]), as
    /// [`RunSpec::drawn`] gives them for the run's row.
    pub fn drawn(&self, scenario: &toml::Table) -> Vec<Option<f64>> {
        drawn_values(&self.drawn_keys(), &self.grid_keys(), scenario).into_iter().map(|(_, v)| Some(v)).collect()
    }

    /// Run `index`'s grid point, draw and seed (`None` without Monte Carlo).
    fn place(&self, index: usize) -> (usize, usize, Option<u64>) {
        let draws = self.draws();
        let (point, draw) = (index / draws, index % draws);
        (point, draw, self.monte_carlo.as_ref().map(|mc| run_seed(mc.seed, draw)))
    }

    /// Run `index`'s scenario document (as its [`RunSpec::scenario`], without the nominal run a
    /// spec needs), or `None` if `index ≥ self.len()`.
    pub fn run_document(&self, index: usize) -> Option<toml::Table> {
        let (point, _, seed) = self.place(index);
        ((index as u64) < self.len()).then(|| self.document(point, seed))
    }

    /// Run `index`'s specification, or `None` if `index ≥ self.len()` (as `slice::get`), with its
    /// grid point's nominal run: the first call for a point of a study with draws *simulates* that
    /// run ([`Study::nominal`], once per point), so it costs a whole run; later calls are cheap.
    pub fn spec_with_nominal(&self, index: usize) -> Option<RunSpec> {
        self.spec_with_nominal_until(index, &|| false)
    }

    /// [`Study::spec_with_nominal`] whose nominal run `stop` ends early (checked as it goes, and
    /// while it waits for memory): `None` then as well, and nothing of that run is kept, so a later
    /// call carries it out again.
    pub fn spec_with_nominal_until(&self, index: usize, stop: &dyn Fn() -> bool) -> Option<RunSpec> {
        if index as u64 >= self.len() {
            return None;
        }
        let (point, draw, seed) = self.place(index);
        let grid_index = self.grid_index(point);
        Some(RunSpec {
            run: index,
            point,
            draw,
            seed: seed.unwrap_or(0),
            grid: self.grid.iter().zip(&grid_index).map(|(a, &i)| (a.key.clone(), a.values[i].clone())).collect(),
            scenario: self.document(point, seed),
            settle: self.settle,
            max_steps: self.max_steps,
            runaway: self.runaway,
            nominal: self.nominal_until(point, stop).ok()?,
            drawn_keys: self.drawn_keys(),
        })
    }

    /// The nominal run of grid point `point` (its scenario without draws), carried out once, when
    /// the study has draws and the point's loop is continuous; `None` when it has not, or when the
    /// nominal run does not complete (its draws then have no [`Runaway`] rules).
    pub fn nominal(&self, point: usize) -> Option<Nominal> {
        self.nominal_until(point, &|| false).unwrap_or(None)
    }

    /// [`Study::nominal`] that `stop` ends early: `Err(())` then, and nothing is kept. Threads
    /// that reach a point at once may each carry out its nominal run (the same run: the first kept),
    /// rather than wait on one they could not interrupt.
    fn nominal_until(&self, point: usize, stop: &dyn Fn() -> bool) -> Result<Option<Nominal>, ()> {
        let Some(kept) = &self.nominal else { return Ok(None) };
        if let Some(nominal) = kept.lock().get(&point) {
            return Ok(*nominal);
        }
        let keep = |nominal: Option<Nominal>| Ok(*kept.lock().entry(point).or_insert(nominal));
        let Ok(s) = Scenario::from_document(&self.document(point, None)) else { return keep(None) };
        if s.simulation.sample_time.is_some() {
            return keep(None);
        }
        let nominal = match sweep::simulate(&s, self.max_steps, &|_| None, stop) {
            Ok(run) => match run.result.outcome {
                Some(crate::sim::Outcome::Interrupted { .. }) => return Err(()),
                Some(crate::sim::Outcome::Completed) => Some(Nominal {
                    steps: run.result.stats.steps(),
                    peaks: run.result.peaks,
                    breakpoints: run.shape.breakpoints,
                    expects_stiff: run.shape.expects_stiff,
                    xi_bound: s
                        .design()
                        .map_or(f64::INFINITY, |d| crate::sim::Run::of(&s, &d).divergence_bounds().0[2]),
                }),
                _ => None,
            },
            Err(_) => None,
        };
        keep(nominal)
    }

    /// Every run's specification, in index order (what `quell.sweep_runs` yields), each with its
    /// nominal run ([`Study::spec_with_nominal`]: one simulation per grid point of a study with draws).
    pub fn specs_with_nominal(&self) -> impl Iterator<Item = RunSpec> + '_ {
        (0..self.len() as usize).map_while(|i| self.spec_with_nominal(i))
    }

    /// The caution for a study's runs forced onto DOP853 (`simulation.method = "explicit"`) on an
    /// adaptive law it makes stiff ([`Row::explicit_stiff`], set as each run starts, draws and
    /// grid points alike): how many of `rows` were, and the first one's run, grid values and the
    /// caution of [`crate::sim::explicit_stiff_warning`] for it (one design). `None` when none was.
    pub fn explicit_stiff_caution(&self, rows: &[Row]) -> Option<String> {
        let stiff = rows.iter().filter(|r| r.explicit_stiff).count();
        let first = rows.iter().filter(|r| r.explicit_stiff).min_by_key(|r| r.run)?;
        let s = Scenario::from_document(&self.spec_with_nominal(first.run)?.scenario).ok()?;
        let design = s.design().ok()?;
        let w = crate::sim::explicit_stiff_warning(&crate::sim::Run::of(&s, &design), crate::sim::EXPLICIT_IN_FILE)?;
        let values = self.point_values(first.point);
        let at = match (values.is_empty(), self.draws() > 1) {
            (true, false) => String::new(),
            (true, true) => format!(", draw {}", first.draw),
            (false, false) => format!(", {values}"),
            (false, true) => format!(", {values}, draw {}", first.draw),
        };
        let completed = rows.iter().filter(|r| r.explicit_stiff && r.outcome == Outcome::Completed).count();
        let consequence = match completed {
            0 => "none completed".to_string(),
            c if c == stiff => "all completed".to_string(),
            c => format!("{c} completed"),
        };
        Some(format!(
            "{stiff} of the {} runs carried out ran on DOP853 at a stiff adaptive law, {consequence}: DOP853 keeps its steps within that law's rate; the first, run {}{at}: {w}",
            rows.len(),
            first.run
        ))
    }

    /// Grid point `point`'s values, `key = value, …` (empty without a grid).
    fn point_values(&self, point: usize) -> String {
        let values: Vec<String> = (self.grid.iter().zip(self.grid_index(point)))
            .map(|(a, i)| format!("{} = {}", a.key, sweep::grid_text(&a.values[i])))
            .collect();
        values.join(", ")
    }

    /// The caution before a sweep whose runs a rate far faster than the loop makes costly
    /// ([`crate::sim::fast_rate_warning`]: more than 10⁶ steps a run, or a delay history beyond
    /// its budget), from the nominal scenarios of its first grid points (draws aside: a draw
    /// perturbs, it does not set a time scale), at most [`FAST_RATE_POINTS`] of them and for at
    /// most [`FAST_RATE_CHECK_TIME`] (each costs a design: 0.85 s at 200 states), until `stop`:
    /// how many of those, and the first one's values and caution. `None` when none is. A grid
    /// over design.beta reaching 1e-7 had said nothing before its runs, each of which spends its
    /// budget or the history's cap.
    pub fn fast_rate_caution(&self, stop: &dyn Fn() -> bool) -> Option<String> {
        let warning = |point: usize| {
            let s = Scenario::from_document(&self.document(point, None)).ok()?;
            let design = s.design().ok()?;
            crate::sim::fast_rate_warning(&crate::sim::Run::of(&s, &design))
        };
        let started = std::time::Instant::now();
        let (mut checked, mut flagged) = (0, Vec::new());
        while checked < self.points().min(FAST_RATE_POINTS)
            && (checked == 0 || started.elapsed() < FAST_RATE_CHECK_TIME)
            && !stop()
        {
            flagged.extend(warning(checked).map(|w| (checked, w)));
            checked += 1;
        }
        let (count, (first, w)) = (flagged.len(), flagged.into_iter().next()?);
        Some(match (self.grid.is_empty(), checked < self.points()) {
            (true, _) => format!("every run: {w}"),
            (false, more) => format!(
                "{count} of the {}{checked} grid points{}: the first, {}: {w}",
                if more { "first " } else { "" },
                if more { " checked" } else { "" },
                self.point_values(first)
            ),
        })
    }

    /// The peak of the plant input u_f,i that the steady state y = g needs on the first grid
    /// point's scenario ([`crate::diagnostics::steady_input`]), a bound no μ or poles lower; 0 where
    /// that scenario cannot be read.
    pub fn steady_input_peak(&self, i: usize) -> f64 {
        let s = Scenario::from_document(&self.document(0, None)).ok();
        s.and_then(|s| s.steady_input().peak.get(i).copied()).unwrap_or(0.0)
    }

    /// The scenario's unit of time (`[plant] time_unit`, checked when the study was read).
    pub fn time_unit(&self) -> crate::settings::TimeUnit {
        let given = self.base.get("plant").and_then(|p| p.get("time_unit")).and_then(toml::Value::as_str);
        given.and_then(|u| crate::settings::TimeUnit::from_name(u).ok()).unwrap_or_default()
    }

    /// The outputs' names the scenario gives (`[plant] outputs`); empty without them.
    pub fn outputs(&self) -> Vec<String> {
        self.plant_names("outputs")
    }

    /// The inputs' names (`[plant] inputs`); empty when not given.
    pub fn inputs(&self) -> Vec<String> {
        self.plant_names("inputs")
    }

    /// `[plant]`'s list of names `key`, empty when not given.
    fn plant_names(&self, key: &str) -> Vec<String> {
        let names = self.base.get("plant").and_then(|p| p.get(key)).and_then(toml::Value::as_array);
        names.map_or_else(Vec::new, |a| a.iter().filter_map(|n| n.as_str().map(str::to_string)).collect())
    }

    /// The largest |u_f,i| the scenario's true actuator passes unclipped (`truth.u_max[i]`, or
    /// −`truth.u_min[i]` where smaller), ∞ for none.
    pub fn u_max(&self, i: usize) -> f64 {
        self.actuator.as_ref().filter(|a| i < a.limits.len()).map_or(f64::INFINITY, |a| a.magnitude_limit(i))
    }

    /// Input i's true actuator limits as keys with their values (`truth.u_max[0] = 10`), where the
    /// scenario has an actuator.
    pub fn limits_text(&self, i: usize) -> Option<String> {
        self.actuator.as_ref().filter(|a| i < a.limits.len()).map(|a| a.limits_text(i))
    }

    /// Whether some run's true plant differs from the design model: the scenario's `[truth]`
    /// differs from `[plant]`, a grid value of a `truth.` key differs from the plant's, or a draw
    /// perturbs a `truth.` key with a spread > 0.
    pub fn truth_differs(&self) -> bool {
        let plant_twin = |p: &KeyPath| KeyPath::parse(&p.to_string().replacen("truth", "plant", 1)).ok();
        let mut plant_doc = self.base.clone();
        let differs = |path: &KeyPath, v: &toml::Value| {
            let twin = plant_twin(path);
            if let Some(t) = &twin {
                fill_default(&mut plant_doc, t);
            }
            twin.and_then(|t| t.get(&plant_doc).ok().map(|p| !path::same_numbers(p, v))).unwrap_or(true)
        };
        let mut differs = differs;
        if let Some(toml::Value::Table(truth)) = self.base.get("truth") {
            for (k, v) in truth {
                if let Ok(p) = KeyPath::parse(&format!("truth.{k}")) {
                    if differs(&p, v) {
                        return true;
                    }
                }
            }
        }
        for axis in self.grid.iter().filter(|a| a.path.section() == "truth") {
            if axis.values.iter().any(|v| differs(&axis.path, v)) {
                return true;
            }
        }
        self.monte_carlo.as_ref().is_some_and(|mc| {
            mc.perturbations.iter().any(|p| {
                p.path.section() == "truth"
                    && !matches!(
                        p.law,
                        Law::Relative(0.0) | Law::RelativeUniform(0.0) | Law::Normal(0.0) | Law::Uniform(0.0)
                    )
            })
        })
    }

    /// The scenario document with the study's `[simulation]` overrides, before any grid value.
    pub(crate) fn base(&self) -> &toml::Table {
        &self.base
    }
}

/// The study's scenario document, where it came from (for messages): the paper's example, a
/// file's path (relative to `dir`) or the scenario table itself, and the file's path where it is one.
fn base_scenario(doc: &toml::Table, dir: Option<&Path>) -> Result<(toml::Table, String, Option<PathBuf>), StudyError> {
    match doc.get("scenario") {
        None => {
            Ok((PAPER_EXAMPLE.parse().expect("the paper's example is valid TOML"), "the paper's example".into(), None))
        }
        Some(toml::Value::String(s)) if s.is_empty() => Err(err(
            "scenario",
            "expected the scenario file's path, found an empty string; name the file (scenario = \"paper.toml\"), or leave the key out for the paper's example",
        )),
        Some(toml::Value::String(s)) => {
            let p = dir.map_or_else(|| PathBuf::from(s), |d| d.join(s));
            // Where a relative path was looked for: beside the study file, or (a study given as
            // text) the working directory; an absolute one is where it says.
            let relative = match (Path::new(s).is_absolute(), dir) {
                (true, _) => "",
                (false, Some(_)) => "; the path is relative to the study file",
                (false, None) => "; the path is relative to the working directory (the study was given as text)",
            };
            let text = crate::settings::read_input(&p).map_err(|e| {
                err("scenario", format!("cannot read the scenario file {:?} ({e}){relative}", p.display().to_string()))
            })?;
            let base = text.parse().map_err(|e: toml::de::Error| {
                err("scenario", format!("{s} is not valid TOML: {}", syntax_message(&text, &e)))
            })?;
            Ok((base, s.clone(), Some(p)))
        }
        Some(toml::Value::Table(t)) => Ok((t.clone(), "the study's scenario".into(), None)),
        Some(v) => Err(found("scenario", "the scenario file's path (a string) or a scenario table", v)),
    }
}

/// Puts the study's `[simulation]` into the scenario document `base`, and reads and designs the
/// result; an error in a value the study set names the study's key.
fn apply_simulation(doc: &toml::Table, base: &mut toml::Table, source: &str) -> Result<Scenario, StudyError> {
    let own = base.clone();
    if let Some(sim) = doc.get("simulation") {
        let sim = table("simulation", sim)?;
        let target = base.entry("simulation").or_insert_with(|| toml::Value::Table(toml::Table::new()));
        if let toml::Value::Table(t) = target {
            for (k, v) in sim {
                t.insert(k.clone(), v.clone());
            }
        }
    }
    let scenario = Scenario::from_document(base).map_err(|e| {
        let set_here = |key: &str| doc.get("simulation").and_then(|s| s.get(key)).is_some();
        match e.key.strip_prefix("simulation.") {
            Some(key) if set_here(key) => err(e.key.clone(), e.message),
            // The scenario's value, valid on its own, against one the study set (its output_step
            // beside the study's t_end): the study's keys, and the remedy in the study.
            Some(key) if doc.get("simulation").is_some() && Scenario::from_document(&own).is_ok() => {
                // The horizon where the study set it (the bounds on output_step and sample_time
                // are against t_end), else every key it set.
                let horizon = key != "t_end" && sim_keys(doc).any(|k| k == "t_end");
                let set: Vec<String> =
                    sim_keys(doc).filter(|k| !horizon || *k == "t_end").map(|k| format!("simulation.{k}")).collect();
                err(
                    e.key.clone(),
                    format!(
                        "{} ({key} from {source}, with the study's {}); set simulation.{key} in the study's [simulation] too",
                        e.message,
                        set.join(", ")
                    ),
                )
            }
            _ if e.is_a_study() => err(
                "scenario",
                format!(
                    "{source}: {e}; {source} is a study, not a scenario: set `scenario` to a scenario file (with [plant] and [design]) or a scenario table"
                ),
            ),
            _ => err("scenario", format!("{source}: {e}")),
        }
    })?;
    scenario.design().map_err(|e| err("scenario", format!("{source}: {e}")))?;
    Ok(scenario)
}

/// The keys the study's `[simulation]` sets.
fn sim_keys(doc: &toml::Table) -> impl Iterator<Item = &String> {
    doc.get("simulation").and_then(toml::Value::as_table).into_iter().flat_map(toml::Table::keys)
}

/// What every check a run of the study's own scenario makes before it starts refuses (a sample
/// time the delays refuse, a harmonic too fast for t_end), as the run's message and the study's
/// error: the study's `[simulation]` when it set the key, else its scenario.
fn base_run_error(doc: &toml::Table, scenario: &Scenario, source: &str) -> Option<(String, StudyError)> {
    let design = scenario.design().ok()?;
    let e = crate::sim::Run::of(scenario, &design).check().err()?.to_string();
    // The message leads with its key (the controller's as well as the settings').
    let error = match e.split_once(": ") {
        Some((key, message)) if key.starts_with("simulation.") && doc.get("simulation").is_some() => err(key, message),
        _ => err("scenario", format!("{source}: {e}")),
    };
    Some((e, error))
}

/// A sampled-data study draws no delay of the model: the controller's delay lines need
/// `plant.delays` in whole samples, which a delay drawn from a continuous law is with probability
/// zero, so every draw would fail its run's check (15 failed rows and exit 0, where a grid value
/// that is not whole samples is refused before any run). The true plant's delays
/// (`truth.delays`, `truth.actuator_delays`) may be drawn: a sampled run takes them in fractions of
/// a sample. `own`: whether the study's `[simulation]` sets the sample time (it cannot unset the
/// scenario's).
fn check_drawn_delays(
    mc: &MonteCarlo,
    (sample_time, own): (f64, bool),
    unit: crate::settings::TimeUnit,
) -> Result<(), StudyError> {
    let model = "plant.delays";
    let Some(p) = mc.perturbations.iter().find(|p| p.key == model || p.key.starts_with(&format!("{model}["))) else {
        return Ok(());
    };
    Err(err(
        format!("monte_carlo.\"{}\"", p.key),
        format!(
            "a model delay drawn from a continuous law is almost never a whole number of samples of simulation.sample_time = {} {unit}, which the controller's delay lines need, so every sampled run would fail; draw the true plant's delay instead (truth.delays: the controller keeps the model's, and a sampled run takes the truth's in fractions of a sample), draw it in the continuous loop ({}), or give whole-sample delays as [grid] values",
            crate::settings::fmt_short(sample_time),
            if own {
                "leave simulation.sample_time out of the study"
            } else {
                "a study of a copy of the scenario without its simulation.sample_time, which a study's [simulation] cannot remove"
            }
        ),
    ))
}

/// The `[simulation]` settings that take names, not numbers, and so are no grid keys: each with
/// what to do instead.
const NOT_GRID_KEYS: [(&str, &str); 2] = [
    (
        "simulation.method",
        "the integrator is not a grid key: grid values are numbers, and runs.csv compares designs and plants, not solvers; run the study once per method with [simulation] method = \"explicit\" or \"imex\"",
    ),
    (
        "simulation.precision",
        "the precision is not a grid key: grid values are numbers; run the study once per precision with [simulation] precision = \"f32\" (a sampled-data study's runs then compute as an f32 build would)",
    ),
];

/// `[grid]`: each key a scenario path, each value a non-empty list of values of its shape, no two
/// keys naming the same value.
fn read_grid(doc: &toml::Table) -> Result<Vec<GridAxis>, StudyError> {
    let mut grid: Vec<GridAxis> = Vec::new();
    let Some(g) = doc.get("grid") else { return Ok(grid) };
    for (key, values) in table("grid", g)? {
        if let Some(e) = misplaced_top_key("grid", key, &[]) {
            return Err(e);
        }
        let at = format!("grid.\"{key}\"");
        let path = KeyPath::parse(key).map_err(|m| err(&at, m))?;
        if let Some((_, why)) = NOT_GRID_KEYS.iter().find(|(k, _)| path.to_string() == *k) {
            return Err(err(&at, *why));
        }
        let values = match values {
            toml::Value::Array(v) if v.is_empty() => return Err(err(
                &at,
                "expected a non-empty list of values, found an empty array; give at least one value or remove the key",
            )),
            toml::Value::Array(v) => v.clone(),
            v => return Err(found(&at, "a list of values (e.g. [5.0, 10.0])", v)),
        };
        if let Some(other) = grid.iter().find(|a| a.path.overlaps(&path)) {
            return Err(err(
                &at,
                format!(
                    "names the same value as grid.\"{}\" (or a part of it), so one would overwrite the other and runs.csv would record a value that was not used; keep one of the two keys",
                    other.key
                ),
            ));
        }
        grid.push(GridAxis { key: key.clone(), path, values });
    }
    Ok(grid)
}

/// Every grid value applied to the scenario and checked ([`check_values`]): after the study's
/// size, which costs nothing, where these cost a design each (about 0.1 ms: two axes of 300,000
/// values, 9e10 runs, were still being checked a minute later before the size refused them).
fn check_grid(
    grid: &[GridAxis],
    base: &toml::Table,
    source: &str,
    base_error: Option<&(String, StudyError)>,
) -> Result<(), StudyError> {
    for axis in grid {
        let at = format!("grid.\"{}\"", axis.key);
        check_values(base, (&axis.path, &at), axis.values.iter().enumerate(), source, base_error)?;
    }
    Ok(())
}

/// `[settle]`: the band, not both parts 0.
fn read_settle(doc: &toml::Table) -> Result<Settle, StudyError> {
    let Some(s) = doc.get("settle") else { return Ok(Settle::default()) };
    let t = table("settle", s)?;
    unknown_keys("settle", t, SETTLE_KEYS)?;
    let d = Settle::default();
    let get = |k: &str, d: f64| t.get(k).map_or(Ok(d), |v| non_negative(&format!("settle.{k}"), v, "a band ≥ 0"));
    let s = Settle { relative: get("relative", d.relative)?, absolute: get("absolute", d.absolute)? };
    if s.relative == 0.0 && s.absolute == 0.0 {
        return Err(err(
            "settle",
            "both settle.relative and settle.absolute are 0, so no run could settle; give a band > 0",
        ));
    }
    Ok(s)
}

/// `max_steps`: a step budget ≥ 1 (`None` when not given: each run's own default), for the
/// continuous loop: refused in a sampled-data study (a grid over `simulation.sample_time` needs
/// the scenario's, and its values are sample times), as a sampled run refuses one; it had been
/// ignored.
fn read_max_steps(doc: &toml::Table, scenario: &Scenario) -> Result<Option<usize>, StudyError> {
    const WHAT: &str = "a step budget per run (an integer ≥ 1)";
    let Some(v) = doc.get("max_steps") else { return Ok(None) };
    let n = match unsigned("max_steps", v, WHAT)? {
        0 => return Err(err("max_steps", format!("expected {WHAT}, found 0"))),
        n => usize::try_from(n).unwrap_or(usize::MAX),
    };
    match scenario.simulation.sample_time {
        Some(t_s) => Err(err(
            "max_steps",
            format!("a step budget applies to the continuous loop; this study's runs are sampled-data (simulation.sample_time = {}), whose controller steps are known before they start: leave max_steps out", crate::settings::fmt_short(t_s)),
        )),
        _ => Ok(Some(n)),
    }
}

/// `[runaway]`: its two factors ([`Runaway::default`] for those not given).
fn read_runaway(doc: &toml::Table) -> Result<Runaway, StudyError> {
    let Some(r) = doc.get("runaway") else { return Ok(Runaway::default()) };
    let t = table("runaway", r)?;
    unknown_keys("runaway", t, RUNAWAY_KEYS)?;
    let d = Runaway::default();
    let get = |k: &str, d: f64| t.get(k).map_or(Ok(d), |v| factor(&format!("runaway.{k}"), v));
    Ok(Runaway { peak: get("peak", d.peak)?, steps: get("steps", d.steps)? })
}

/// The study's fingerprint: FNV-1a of its scenario (with the `[simulation]` overrides) and of the
/// sections that decide its runs, stable across platforms and releases, so merged shards can be
/// checked to come from one study.
fn fingerprint(doc: &toml::Table, base: &toml::Table) -> u64 {
    let mut canonical = toml::to_string(base).unwrap_or_default();
    for key in ["grid", "monte_carlo", "settle", "max_steps", "runaway"] {
        if let Some(v) = doc.get(key) {
            canonical.push_str(&format!("\n[{key}]\n{v}"));
        }
    }
    crate::hash::fnv1a_64(canonical.bytes())
}

/// `n` and `noun`, plural unless n is 1 ("1 draw", "20 draws").
pub fn count(n: usize, noun: &str) -> String {
    format!("{n} {noun}{}", plural(n as u128))
}

/// The plural ending for a count of `n`.
fn plural(n: u128) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

/// The number of grid points, after checking that points × draws is at most [`MAX_RUNS`].
fn study_size(grid: &[GridAxis], mc: Option<&MonteCarlo>) -> Result<usize, StudyError> {
    let draws = mc.map_or(1, |mc| mc.runs as u128);
    let points = grid.iter().fold(1u128, |p, a| p.saturating_mul(a.values.len() as u128));
    let runs = points.saturating_mul(draws);
    if runs <= u128::from(MAX_RUNS) {
        return Ok(points as usize);
    }
    // Exact below 2¹²⁸, else the float of the saturated count says "at least".
    let figure = |x: u128| if x < 1_000_000_000_000 { x.to_string() } else { format!("{:.3e}", x as f64) };
    let lengths: Vec<String> = grid.iter().map(|a| a.values.len().to_string()).collect();
    Err(err(
        if mc.is_some() { "monte_carlo.runs" } else { "grid" },
        format!(
            "the study has {}{} runs ({} grid point{} ({}) × {draws} draw{}), more than the {MAX_RUNS:.0e} a study may have; reduce the grid values or draws, or split the study into several files",
            if runs == u128::MAX { "at least " } else { "" },
            figure(runs),
            figure(points),
            plural(points),
            lengths.join(" × "),
            plural(draws),
        ),
    ))
}

/// Optional scenario keys without a default: a study varies them only where the scenario gives them.
const OPTIONAL_KEYS: &[&str] =
    &["simulation.sample_time", "noise.std", "noise.bandwidth", "design.reference_sizes", "design.disturbance_sizes"];

/// Why `path` is not in the scenario (`why`), with what to do: for an [`OPTIONAL_KEYS`] key the
/// scenario leaves out, give it there; otherwise `hint` on key paths.
fn not_in_scenario(path: &KeyPath, why: &str, hint: &str) -> String {
    let key = path.to_string();
    let base = key.split('[').next().unwrap_or_default();
    // A misspelt key of a known table: the nearest valid one (truth.delay for truth.delays).
    let (section, name) =
        base.split_once('.').map_or(("", base), |(s, rest)| (s, rest.split('.').next().unwrap_or(rest)));
    let nearest = crate::scenario::section_keys(section)
        .filter(|keys| name.chars().count() > 2 && !keys.contains(&name))
        .and_then(|keys| crate::settings::nearest(name, keys.iter().copied()))
        .map(|n| {
            if section.is_empty() {
                format!(" (did you mean {n}?)")
            } else {
                format!(" (did you mean {section}.{n}?)")
            }
        })
        .unwrap_or_default();
    // A signal component's bias or a harmonic's phase, left out as 0 (`reference.components[0].bias`).
    let signal_default = (section == "reference" || section == "disturbance")
        && ["bias", "phase"].iter().any(|k| key.ends_with(&format!(".{k}")) && why.ends_with(&format!("has no {k}")));
    let optional = OPTIONAL_KEYS.iter().find(|k| base == **k || base.starts_with(&format!("{k}."))).copied();
    match optional.or(signal_default.then_some(key.as_str())) {
        Some(k) => format!("{path} is not a value of the scenario ({why}): {k} is optional and the scenario leaves it out; give it a value in the scenario file (any, e.g. the first of the study's), which the study then varies"),
        None => format!("{path} is not a value of the scenario ({why}){nearest}; {hint}"),
    }
}

/// Checks that each value, put at `path` in the scenario, has the scenario value's shape and gives
/// a scenario that parses and designs. `at` is the study key of the list. A value whose run fails
/// the check exactly as the study's own scenario does (`base_error`) gets that error.
fn check_values<'v>(
    base: &toml::Table,
    (path, at): (&KeyPath, &str),
    values: impl Iterator<Item = (usize, &'v toml::Value)>,
    source: &str,
    base_error: Option<&(String, StudyError)>,
) -> Result<(), StudyError> {
    let mut doc = base.clone();
    // Whose shape a value must have: the scenario's value, or the default it leaves the key to.
    let shape_of = match path.get(&doc) {
        Ok(_) => format!("the shape of {path} in {source}"),
        Err(_) => format!("the shape {path} takes by default in {source}, which leaves it out"),
    };
    fill_default(&mut doc, path);
    let current = path.get(&doc).map_err(|m| {
        err(at, not_in_scenario(path, &m, "grid and Monte Carlo keys are scenario key paths as error messages write them, e.g. design.mu[0] or truth.A"))
    })?;
    let Some(expected) = path::shape(current) else {
        return Err(err(at, format!("{path} in {source} is {}, not a number, vector or matrix", kind(current))));
    };
    for (i, v) in values {
        let key = format!("{at}[{i}]");
        // A million values take a minute (a design each): the stop flag of an enclosing
        // cancel::with_stop ends it (Python's Ctrl-C).
        crate::cancel::check().map_err(|_| err(&key, "interrupted while checking the grid's values"))?;
        match path::shape(v) {
            Some(found) if found == expected => {}
            Some(found) => return Err(err(key, format!("expected {expected} ({shape_of}), found {found}"))),
            None => return Err(found(key, &format!("{expected} (the shape of {path})"), v)),
        }
        let mut trial = doc.clone();
        path.set(&mut trial, v.clone()).expect("found above");
        // Parsed, designed and every check its run makes before it starts (a harmonic too fast to
        // resolve over t_end, a sample time the controller cannot take), so that a grid value
        // that cannot run is refused here rather than as failed rows.
        let checked = Scenario::from_document(&trial).map_err(|e| e.to_string()).and_then(|s| {
            let design = s.design().map_err(|e| e.to_string())?;
            crate::sim::Run::of(&s, &design).check().map_err(|e| e.to_string())
        });
        if let Err(e) = checked {
            if let Some((_, error)) = base_error.filter(|(message, _)| *message == e) {
                return Err(error.clone());
            }
            // As written, but 1e15 not as TOML's 1000000000000000.0.
            let shown = match v {
                toml::Value::Float(x) if x.abs() >= 1e6 || (*x != 0.0 && x.abs() < 1e-4) => format!("{x:e}"),
                v => v.to_string(),
            };
            return Err(err(key, format!("with {path} = {shown} the scenario is not valid: {e}")));
        }
    }
    Ok(())
}

/// A misspelt `runs` or `seed` among `[monte_carlo]`'s key paths (`sed = 1`), named as such: no
/// scenario key path lacks a dot.
fn misspelt_draw_key(key: &str, at: &str) -> Result<(), StudyError> {
    match crate::settings::nearest(key, ["runs", "seed"]).filter(|_| !key.contains('.')) {
        Some(near) => Err(err(
            at,
            format!("unknown key (did you mean `{near}`?); [monte_carlo] takes runs, seed and scenario key paths with a distribution, e.g. \"truth.A\" = {{ relative = 0.05 }}"),
        )),
        None => Ok(()),
    }
}

/// `[monte_carlo]`: `runs`, `seed` and one perturbation law per scenario key path.
/// The law `{ name = size }` of the Monte Carlo key at `at`.
fn read_law(at: &str, v: &toml::Value) -> Result<Law, StudyError> {
    let law = table(at, v).map_err(|_| StudyError {
        wrong_type: true,
        ..err(at, format!("expected a distribution, one of {LAWS}; found {}", kind(v)))
    })?;
    let [(name, size)] = law.iter().collect::<Vec<_>>()[..] else {
        return Err(err(at, format!("expected exactly one distribution, one of {LAWS}; found {} keys", law.len())));
    };
    let size_key = format!("{at}.{name}");
    let size = non_negative(&size_key, size, "a finite spread ≥ 0")?;
    match name.as_str() {
        "relative" => Ok(Law::Relative(size)),
        "relative_uniform" => Ok(Law::RelativeUniform(size)),
        "normal" => Ok(Law::Normal(size)),
        "uniform" => Ok(Law::Uniform(size)),
        _ => Err(err(size_key, format!("unknown distribution; expected one of {LAWS}"))),
    }
}

/// A number drawn twice would be perturbed twice and named twice in runs.csv (diff review,
/// 2026-12-07): the key at `at` (`path`) may overlap none drawn before it.
fn drawn_once(before: &[Perturbation], path: &KeyPath, at: &str) -> Result<(), StudyError> {
    match before.iter().find(|p| p.path.overlaps(path)) {
        Some(other) => Err(err(
            at,
            format!("overlaps monte_carlo.\"{}\", which draws some of the same numbers; draw each number once: the whole key, or its entries, not both", other.key),
        )),
        None => Ok(()),
    }
}

fn monte_carlo(base: &toml::Table, t: &toml::Table, source: &str) -> Result<MonteCarlo, StudyError> {
    let runs = match t.get("runs") {
        None => {
            // A misspelt `runs` ([monte_carlo] run = 5) is a key too, no key path: name it.
            let misspelt = t.keys().find(|k| k.as_str() != "seed" && crate::settings::nearest(k, ["runs"]).is_some());
            let hint = misspelt
                .map(|k| format!(" (`{k}` is no key of [monte_carlo]: did you mean `runs`?)"))
                .unwrap_or_default();
            return Err(err(
                "monte_carlo.runs",
                format!("missing{hint}; required: the number of draws per grid point (an integer ≥ 1)"),
            ));
        }
        Some(v) => unsigned("monte_carlo.runs", v, "the number of draws per grid point (an integer ≥ 1)")?,
    };
    if runs == 0 {
        return Err(err("monte_carlo.runs", "expected the number of draws per grid point (an integer ≥ 1), found 0"));
    }
    if runs > MAX_RUNS {
        return Err(err(
            "monte_carlo.runs",
            format!("expected at most {MAX_RUNS:.0e} draws (a study may have at most {MAX_RUNS:.0e} runs), found {runs}; reduce the draws, or split the study into several files with different seeds"),
        ));
    }
    let seed = t.get("seed").map_or(Ok(0), |v| unsigned("monte_carlo.seed", v, "a seed (an integer ≥ 0)"))?;
    let mut perturbations = Vec::new();
    for (key, v) in t.iter().filter(|(k, _)| !matches!(k.as_str(), "runs" | "seed")) {
        if let Some(e) = misplaced_top_key("monte_carlo", key, &[]) {
            return Err(e);
        }
        let at = format!("monte_carlo.\"{key}\"");
        misspelt_draw_key(key, &at)?;
        let path = KeyPath::parse(key).map_err(|m| err(&at, m))?;
        let law = read_law(&at, v)?;
        let mut doc = base.clone();
        fill_default(&mut doc, &path);
        let current = path.get(&doc).map_err(|m| {
            err(
                &at,
                not_in_scenario(&path, &m, "Monte Carlo keys are scenario key paths, e.g. truth.A or truth.delays[1]"),
            )
        })?;
        if path::shape(current).is_none() {
            return Err(err(&at, format!("{path} in {source} is {}, not a number, vector or matrix", kind(current))));
        }
        if contains_integer_key(&path) {
            return Err(err(&at, format!("{path} is an integer setting; draws perturb real numbers only")));
        }
        drawn_once(&perturbations, &path, &at)?;
        perturbations.push(Perturbation { key: key.clone(), path, law });
    }
    // Draws reseed nothing else (not [noise]): without a law every draw repeats the nominal run.
    if perturbations.is_empty() {
        return Err(err(
            "monte_carlo",
            format!("expected at least one scenario key with a distribution, found only runs and seed, so every draw would repeat the nominal run; add one such as \"truth.A\" = {{ relative = 0.05 }} (laws: {LAWS}), or use [grid] for runs that differ by given values"),
        ));
    }
    Ok(MonteCarlo { runs: runs as usize, seed, perturbations })
}

/// A law on a value infinite in the scenario (`truth.u_max` left unlimited) where no grid axis sets
/// it: ∞ perturbed is ∞, so every draw would repeat the nominal run (it had, without a word).
fn check_infinite_laws(mc: &MonteCarlo, base: &toml::Table, grid: &[GridAxis], source: &str) -> Result<(), StudyError> {
    for p in &mc.perturbations {
        let mut doc = base.clone();
        fill_default(&mut doc, &p.path);
        let gridded = grid.iter().any(|a| a.path.overlaps(&p.path));
        if !gridded && p.path.get(&doc).is_ok_and(all_infinite) {
            return Err(err(
                format!("monte_carlo.\"{}\"", p.key),
                format!("{} in {source} is infinite (no limit), which no draw changes, so every draw would repeat the nominal run; give it a finite value in the scenario file to perturb it", p.path),
            ));
        }
    }
    Ok(())
}

/// Every number of `v` is ±∞ (and there is one).
fn all_infinite(v: &toml::Value) -> bool {
    match v {
        toml::Value::Float(x) => x.is_infinite(),
        toml::Value::Array(a) => !a.is_empty() && a.iter().all(all_infinite),
        _ => false,
    }
}

/// Scenario values that must stay integers.
fn contains_integer_key(path: &KeyPath) -> bool {
    path.to_string() == "noise.seed"
}

/// The values a run's draw gave each perturbed key of `keys` in its scenario `doc`, one per number
/// (flattened: `truth.A[0][1]`); the columns of a key the grid (`grid`'s keys) also sets, whole or
/// in part, are `… (drawn)` (`truth.delays[1] (drawn)` beside the grid's `truth.delays[1]`: a draw
/// of the whole `truth.delays` had overwritten that grid column).
pub fn drawn_values(keys: &[String], grid: &[String], doc: &toml::Table) -> Vec<(String, f64)> {
    fn flatten(name: String, v: &toml::Value, out: &mut Vec<(String, f64)>) {
        match v {
            toml::Value::Float(x) => out.push((name, *x)),
            toml::Value::Integer(i) => out.push((name, *i as f64)),
            toml::Value::Array(a) => a.iter().enumerate().for_each(|(i, x)| flatten(format!("{name}[{i}]"), x, out)),
            _ => {}
        }
    }
    let mut out = Vec::new();
    for key in keys {
        let Ok(path) = KeyPath::parse(key) else { continue };
        if let Ok(v) = path.get(doc) {
            let start = out.len();
            flatten(key.clone(), v, &mut out);
            if grid.iter().any(|g| KeyPath::parse(g).is_ok_and(|g| g.overlaps(&path))) {
                out[start..].iter_mut().for_each(|(name, _)| name.push_str(" (drawn)"));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests;
