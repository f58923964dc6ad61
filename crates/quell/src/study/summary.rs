//! Aggregation per grid point: quantiles of each channel's figures over the draws, and the
//! fractions that diverged, failed or were stopped (summary.json).

use serde::{Deserialize, Serialize};

use super::sweep::{Outcome, Row, Shard};
use super::Study;

/// The quantile levels of summary.json and of the plots' bands.
pub const QUANTILES: [f64; 5] = [0.05, 0.25, 0.5, 0.75, 0.95];

/// The levels of [`Quantiles`]' fields, in order: min, [`QUANTILES`], max.
const LEVELS: [f64; 7] = [0.0, QUANTILES[0], QUANTILES[1], QUANTILES[2], QUANTILES[3], QUANTILES[4], 1.0];

/// Quantile `p` of sorted data by linear interpolation between order statistics (Hyndman and Fan's
/// type 7, the default of NumPy and R): h = (n − 1) p, x[⌊h⌋] + (h − ⌊h⌋)(x[⌊h⌋+1] − x[⌊h⌋]).
/// `None` for no data.
pub fn quantile(sorted: &[f64], p: f64) -> Option<f64> {
    let n = sorted.len();
    if n == 0 {
        return None;
    }
    let h = (n - 1) as f64 * p.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(n - 1);
    let (a, b, frac) = (sorted[lo], sorted[hi], h - lo as f64);
    // Equal neighbours (also both +∞) give the value itself, never ∞ − ∞; a level that falls on a
    // value is that value (the median of 15 settling times, 7 of them "never", is the 8th: 0·∞ had
    // made it NaN, and the figure called it missing).
    Some(if a == b || frac == 0.0 { a } else { a + frac * (b - a) })
}

/// Quantiles of one figure over a grid point's completed runs. `null` in JSON where there is no
/// data, or where a settling time's quantile falls among runs that never settled.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Quantiles {
    pub min: Option<f64>,
    pub p05: Option<f64>,
    pub p25: Option<f64>,
    pub p50: Option<f64>,
    pub p75: Option<f64>,
    pub p95: Option<f64>,
    pub max: Option<f64>,
}

impl Quantiles {
    /// Of `values` (+∞ counts as "never", shown as `None`).
    pub fn of(mut values: Vec<f64>) -> Quantiles {
        values.sort_by(f64::total_cmp);
        let [min, p05, p25, p50, p75, p95, max] = LEVELS.map(|p| quantile(&values, p).filter(|v| v.is_finite()));
        Quantiles { min, p05, p25, p50, p75, p95, max }
    }

    /// The value at level `p` of [`QUANTILES`] (or 0 / 1 for min / max).
    pub fn at(&self, p: f64) -> Option<f64> {
        let Quantiles { min, p05, p25, p50, p75, p95, max } = *self;
        let p = p.clamp(0.0, 1.0);
        LEVELS.iter().position(|l| (l - p).abs() < 1e-12).and_then(|i| [min, p05, p25, p50, p75, p95, max][i])
    }
}

/// One channel's figures at a grid point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelQuantiles {
    pub tail_max_e: Quantiles,
    pub tail_rms_e: Quantiles,
    pub max_u: Quantiles,
    pub max_uf: Quantiles,
    pub settle_t: Quantiles,
    /// Of the completed runs, the fraction that never settled; `None` (`null`) when none completed.
    pub never_settled: Option<f64>,
}

/// One grid point of summary.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PointSummary {
    pub point: usize,
    /// The grid values, as written.
    pub grid: Vec<String>,
    /// Runs of this point carried out (all draws, unless the sweep was sharded or interrupted).
    pub runs: usize,
    pub completed: usize,
    pub diverged_fraction: f64,
    pub failed_fraction: f64,
    /// Ended by a rule of `[runaway]` ([`super::Outcome::Stopped`]); 0 in a summary written before it.
    #[serde(default)]
    pub stopped_fraction: f64,
    pub channels: Vec<ChannelQuantiles>,
}

/// One grid axis in summary.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AxisMeta {
    pub key: String,
    pub values: Vec<String>,
}

/// What identifies a study's sweep: enough to merge shards and plot without the study file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyMeta {
    /// [`Study::fingerprint`] in hex.
    pub fingerprint: String,
    pub scenario: String,
    pub grid: Vec<AxisMeta>,
    /// Draws per grid point.
    pub draws: usize,
    pub seed: Option<u64>,
    /// Runs of the whole study.
    pub runs: u64,
    /// Channels.
    pub m: usize,
    /// Whether some run's true plant differs from the design model (`[truth]`, or a grid or draw
    /// on a `truth.` key).
    pub truth_differs: bool,
    /// The runaway rules the draws were run with ([`Study::runaway`]).
    #[serde(default)]
    pub runaway: super::Runaway,
    pub shard: Shard,
    /// The symbol of the scenario's unit of time (`[plant] time_unit`; "s" when not given).
    #[serde(default = "seconds")]
    pub time_unit: String,
    /// The outputs' names (`[plant] outputs`), for the figures' titles; empty when not given.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub outputs: Vec<String>,
    /// The inputs' names (`[plant] inputs`), for the plant input's panels; empty when not given.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub inputs: Vec<String>,
    /// runs.csv's columns after `wall_ms`: the values each draw gave ([`super::Study::drawn_columns`]);
    /// empty without Monte Carlo (and in a summary written before 2026-12-07).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub drawn: Vec<String>,
}

fn seconds() -> String {
    "s".into()
}

impl StudyMeta {
    /// The study's identity as swept by `shard`.
    pub fn new(study: &Study, shard: Shard) -> StudyMeta {
        StudyMeta {
            fingerprint: format!("{:016x}", study.fingerprint()),
            scenario: study.scenario_source.clone(),
            grid: study
                .grid
                .iter()
                .map(|a| AxisMeta {
                    key: a.key.clone(),
                    values: a.values.iter().map(super::sweep::grid_text).collect(),
                })
                .collect(),
            draws: study.draws(),
            seed: study.monte_carlo.as_ref().map(|mc| mc.seed),
            runs: study.len(),
            m: study.m,
            truth_differs: study.truth_differs(),
            runaway: study.runaway,
            shard,
            time_unit: study.time_unit().symbol().into(),
            outputs: study.outputs(),
            inputs: study.inputs(),
            drawn: study.drawn_columns(),
        }
    }

    /// "Channel i" (from 1), with the output's name when the scenario gives one: "Channel 1 (xD)".
    pub fn channel(&self, i: usize) -> String {
        match self.outputs.get(i) {
            Some(name) => format!("Channel {} ({name})", i + 1),
            None => format!("Channel {}", i + 1),
        }
    }

    /// "Input i" (from 1), with the input's name when the scenario gives one: "Input 1 (L)". The
    /// plant input u_f's figures are the inputs', which a plant need not pair with its outputs.
    pub fn input(&self, i: usize) -> String {
        match self.inputs.get(i) {
            Some(name) => format!("Input {} ({name})", i + 1),
            None => format!("Input {}", i + 1),
        }
    }

    /// Grid points.
    pub fn points(&self) -> usize {
        self.grid.iter().map(|a| a.values.len()).product()
    }
}

/// summary.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub study: StudyMeta,
    /// True when the sweep was interrupted: not every run of the shard is in runs.csv.
    pub partial: bool,
    pub runs_done: usize,
    pub points: Vec<PointSummary>,
}

impl Summary {
    /// Aggregates `rows` (any order) per grid point.
    pub fn new(study: StudyMeta, rows: &[Row], partial: bool) -> Summary {
        // By the points the rows reach, not a slot for every point (a shard of a 10⁹-point grid
        // had asked for 24 GB here).
        let mut by_point: std::collections::BTreeMap<usize, Vec<&Row>> = Default::default();
        for r in rows.iter().filter(|r| r.point < study.points()) {
            by_point.entry(r.point).or_default().push(r);
        }
        let points = by_point
            .iter()
            .map(|(&point, rs)| {
                let done: Vec<&Row> = rs.iter().copied().filter(|r| r.outcome == Outcome::Completed).collect();
                let frac = |o: Outcome| rs.iter().filter(|r| r.outcome == o).count() as f64 / rs.len() as f64;
                let channels = (0..study.m)
                    .map(|i| {
                        let col = |f: &dyn Fn(&crate::sim::ChannelFigures) -> f64| {
                            Quantiles::of(done.iter().map(|r| f(&r.channels[i])).collect())
                        };
                        let never = done.iter().filter(|r| r.channels[i].settle_t.is_none()).count();
                        ChannelQuantiles {
                            tail_max_e: col(&|c| c.tail_max_e),
                            tail_rms_e: col(&|c| c.tail_rms_e),
                            max_u: col(&|c| c.max_u),
                            max_uf: col(&|c| c.max_uf),
                            settle_t: col(&|c| c.settle_t.unwrap_or(f64::INFINITY)),
                            never_settled: (!done.is_empty()).then(|| never as f64 / done.len() as f64),
                        }
                    })
                    .collect();
                PointSummary {
                    point,
                    grid: rs[0].grid.clone(),
                    runs: rs.len(),
                    completed: done.len(),
                    diverged_fraction: frac(Outcome::Diverged),
                    failed_fraction: frac(Outcome::Failed),
                    stopped_fraction: frac(Outcome::Stopped),
                    channels,
                }
            })
            .collect();
        Summary { study, partial, runs_done: rows.len(), points }
    }
}
