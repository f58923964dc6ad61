//! Per-channel tuning of μ (`quell tune`): the channels are decoupled (Proposition 1), so μ is
//! tuned by m one-dimensional searches over μ_i, the others held at the scenario's values, and the
//! joint run with every tuned μ_i is checked to reproduce each channel's figure.

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::sweep::{execute, Outcome, Row, RunSpec};
use super::{err, found, number, Study, StudyError};
use crate::scenario::Scenario;
use crate::sim::ChannelFigures;

/// What a search minimizes for channel i.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// settle_t_i (a run that never settles scores +∞).
    SettleT,
    /// RMS of e_i over the last 10 % of the horizon.
    TailRmsE,
    /// max |e_i| over the last 10 % of the horizon.
    TailMaxE,
}

impl Objective {
    /// The name in the study file and the runs.csv column it reads.
    pub fn name(self) -> &'static str {
        match self {
            Objective::SettleT => "settle_t",
            Objective::TailRmsE => "tail_rms_e",
            Objective::TailMaxE => "tail_max_e",
        }
    }

    fn of(self, c: &ChannelFigures) -> f64 {
        match self {
            Objective::SettleT => c.settle_t.unwrap_or(f64::INFINITY),
            Objective::TailRmsE => c.tail_rms_e,
            Objective::TailMaxE => c.tail_max_e,
        }
    }
}

/// `[tune]` of a study file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TuneSpec {
    pub objective: Objective,
    /// Per channel, [μ_min, μ_max] with 0 < μ_min ≤ μ_max.
    pub bounds: Vec<[f64; 2]>,
    /// Per channel, the limit on max |u_i|, the adaptive command (25) (+∞ without one).
    pub max_u: Vec<f64>,
    /// Per channel, the actuator limit on max |u_f,i|, the plant input (5) (+∞ without one).
    pub max_uf: Vec<f64>,
    /// Log-spaced values per channel before refining (≥ 2).
    pub points: usize,
    /// Golden-section steps around the best of them.
    pub refine: usize,
}

/// A limit on `what` > 0 at `key`; inf is none.
fn limit(key: String, x: &toml::Value, what: &str) -> Result<f64, StudyError> {
    let what = format!("a limit on {what} > 0 (inf for none)");
    if x.as_float() == Some(f64::INFINITY) {
        return Ok(f64::INFINITY);
    }
    match number(&key, x, &what)? {
        x if x > 0.0 => Ok(x),
        x => Err(err(key, format!("expected {what}, found {}", crate::settings::fmt_short(x)))),
    }
}

const TUNE_KEYS: &[&str] = &["objective", "mu", "max_u", "max_uf", "points", "refine"];
const OBJECTIVES: &str = "\"settle_t\", \"tail_rms_e\" or \"tail_max_e\"";

impl TuneSpec {
    /// Channel i's log-spaced starting points; through the logarithms where μ_max/μ_min overflows
    /// (a range such as [1e-300, 1e300] gave μ = inf past its first point).
    fn log_grid(&self, i: usize) -> impl Iterator<Item = f64> {
        let ([lo, hi], points) = (self.bounds[i], self.points);
        // A fixed μ_i (μ_min = μ_max) is one evaluation, not `points` identical ones.
        let points = if lo == hi { 1 } else { points };
        let ratio = hi / lo;
        (0..points).map(move |k| {
            let x = k as f64 / (points - 1).max(1) as f64;
            if ratio.is_finite() {
                lo * ratio.powf(x)
            } else if k == 0 {
                lo
            } else if k + 1 == points {
                hi
            } else {
                (lo.ln() + x * (hi.ln() - lo.ln())).exp().clamp(lo, hi)
            }
        })
    }

    /// The limits on channel i that a run's figures `f` break, one phrase each (`max |u_f,1| =
    /// 4.0706e0 beyond tune.max_uf[0] = 4`): only limits that are set (finite) and exceeded.
    pub fn broken_limits(&self, i: usize, f: &ChannelFigures, prefix: &str) -> Vec<String> {
        let c = i + 1;
        [
            ("max_u", format!("max |u_{c}|"), f.max_u, self.max_u[i]),
            ("max_uf", format!("max |u_f,{c}|"), f.max_uf, self.max_uf[i]),
        ]
        .into_iter()
        .filter(|&(_, _, value, limit)| value > limit)
        .map(|(key, what, value, limit)| {
            format!("{what} = {value:.4e} beyond {prefix}{key}[{i}] = {}", crate::settings::fmt_short(limit))
        })
        .collect()
    }

    pub(super) fn parse(t: &toml::Table, s: &Scenario) -> Result<TuneSpec, StudyError> {
        super::unknown_keys("tune", t, TUNE_KEYS)?;
        let m = s.plant.m();
        let objective = match t.get("objective") {
            None => Objective::SettleT,
            Some(toml::Value::String(o)) => match o.as_str() {
                "settle_t" => Objective::SettleT,
                "tail_rms_e" => Objective::TailRmsE,
                "tail_max_e" => Objective::TailMaxE,
                _ => return Err(err("tune.objective", format!("expected {OBJECTIVES}, found \"{o}\""))),
            },
            Some(v) => return Err(found("tune.objective", OBJECTIVES, v)),
        };
        let per_channel = |key: &str, v: &toml::Value| -> Result<Vec<toml::Value>, StudyError> {
            match v {
                toml::Value::Array(a) if a.len() == m => Ok(a.clone()),
                toml::Value::Array(a) => Err(err(
                    key,
                    format!("expected {} (one per channel), found {}", crate::settings::entries(m), a.len()),
                )),
                v => Ok(vec![v.clone(); m]),
            }
        };
        let bounds = match t.get("mu") {
            None => return Err(err("tune.mu", "missing; required: the search interval [μ_min, μ_max] of every channel, e.g. [[1.0, 200.0], [1.0, 200.0]] (or one [μ_min, μ_max] for all)")),
            Some(v) => {
                // One [lo, hi] for every channel, or one per channel.
                let shared = matches!(v, toml::Value::Array(a) if a.len() == 2 && a.iter().all(|x| x.is_integer() || x.is_float()));
                let list = if shared { vec![v.clone(); m] } else { per_channel("tune.mu", v)? };
                list.iter()
                    .enumerate()
                    .map(|(i, b)| {
                        // One pair for every channel is named as the key itself.
                        let key = if shared { "tune.mu".to_string() } else { format!("tune.mu[{i}]") };
                        let pair = b.as_array().filter(|a| a.len() == 2).ok_or_else(|| match b.as_array() {
                            Some(a) => err(&key, format!("expected [μ_min, μ_max], found an array of {}", crate::settings::entries(a.len()))),
                            None => found(&key, "[μ_min, μ_max]", b),
                        })?;
                        let (lo, hi) = (number(&key, &pair[0], "a finite number")?, number(&key, &pair[1], "a finite number")?);
                        if !(lo > 0.0 && lo <= hi) {
                            return Err(err(key, format!("expected 0 < μ_min ≤ μ_max (the search is on a log scale), found [{}, {}]", crate::settings::fmt_short(lo), crate::settings::fmt_short(hi))));
                        }
                        Ok([lo, hi])
                    })
                    .collect::<Result<Vec<_>, _>>()?
            }
        };
        let limits = |name: &str, what: &str| -> Result<Vec<f64>, StudyError> {
            match t.get(name) {
                None => Ok(vec![f64::INFINITY; m]),
                Some(v) => per_channel(&format!("tune.{name}"), v)?
                    .iter()
                    .enumerate()
                    .map(|(i, x)| limit(format!("tune.{name}[{i}]"), x, what))
                    .collect(),
            }
        };
        let (max_u, max_uf) =
            (limits("max_u", "max |u_i|")?, limits("max_uf", "max |u_f,i| (the plant input as asked)")?);
        let count = |key: &str, d: usize, min: u64| -> Result<usize, StudyError> {
            match t.get(key) {
                None => Ok(d),
                Some(toml::Value::Integer(i)) if *i >= min as i64 && *i <= 10_000 => Ok(*i as usize),
                Some(v) => Err(err(format!("tune.{key}"), format!("expected an integer in [{min}, 10000], found {v}"))),
            }
        };
        Ok(TuneSpec {
            objective,
            bounds,
            max_u,
            max_uf,
            points: count("points", 13, 2)?,
            refine: count("refine", 8, 0)?,
        })
    }
}

/// One evaluation of a channel's search.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TunePoint {
    pub mu: f64,
    /// The objective, `None` when the run did not complete, never settled, or broke the limit.
    pub objective: Option<f64>,
    pub outcome: Outcome,
    /// Why the run did not complete, as runs.csv's `reason` (empty when it completed).
    #[serde(default)]
    pub reason: String,
    /// Channel i's figures (when completed).
    pub figures: Option<ChannelFigures>,
}

/// Channel i's search: every evaluation in order of μ, and the chosen one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TuneCurve {
    /// 0-based here; 1-based in tune.json, as in tune.csv and `quell run`'s summary.json.
    #[serde(with = "one_based")]
    pub channel: usize,
    pub curve: Vec<TunePoint>,
    /// The feasible point with the smallest μ among those whose objective ties with the best
    /// (within 5 %, or at the integrator's tolerance; `least_mu_within_tolerance`); `None` if no μ in
    /// the bounds was feasible.
    pub chosen: Option<TunePoint>,
    /// The least objective of the curve and the bound up to which an objective ties with it, which
    /// `chosen` is within; `None` with no feasible point.
    #[serde(default)]
    pub tie: Option<Tie>,
}

/// What ties with the best of a curve: within 5 % of it or three times the integrator's tolerance
/// on e_i (error objectives), within one output step (settling times).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Tie {
    /// The least objective among the curve's feasible points.
    pub least: f64,
    /// The μ_i of that point.
    pub mu: f64,
    /// Objectives up to this tie with it.
    pub bound: f64,
}

impl TuneCurve {
    /// Why no μ was chosen, the keys named after `prefix` (`"tune."` in a study file, `""` for
    /// Python's arguments): the limits the tuning was given and the objective, and when no run
    /// completed, the first run's reason (a step budget, a divergence) in place of the limits.
    /// `clip`: the scenario's true actuator limit on this input ([`Study::u_max`], ∞ for none),
    /// which the message names as a likely cause (a run may never settle while clipped) where some
    /// run asked beyond it, or ended without figures to tell (a motor whose least demand, 19.3 V,
    /// stayed under its 20 V drive had been told so as well). `steady`: the peak of u_f,i the
    /// steady state needs ([`Study::steady_input_peak`]); beyond `max_uf` no poles bring the
    /// input under it, which the message says in place of slower poles.
    pub fn why_none(&self, spec: &TuneSpec, prefix: &str, (clip, steady): (f64, f64)) -> String {
        let (i, c) = (self.channel, self.channel + 1);
        let failed = self.curve.iter().find(|p| p.outcome != Outcome::Completed);
        if let (Some(first), false) = (failed, self.curve.iter().any(|p| p.outcome == Outcome::Completed)) {
            let n = self.curve.len();
            return format!(
                "no μ in {prefix}mu[{i}] completed: none of the {n} runs did (at μ = {}: {}, {})",
                crate::settings::fmt_short(first.mu),
                first.outcome.as_str(),
                first.reason
            );
        }
        let evaluated = self.curve.len();
        let mut wanted: Vec<String> = vec![];
        // Per limit set, the least reached by the runs the limit alone rejected (completed, with a
        // finite objective): raising the limit to that figure admits one. Runs that never settled
        // do not count (their peak admitted none: a servo's 2.559 where 3.226 was needed).
        let (mut reached, mut flat_peaks): (Vec<String>, Vec<String>) = (vec![], vec![]);
        let completed: Vec<(f64, ChannelFigures)> = self
            .curve
            .iter()
            .filter_map(|p| Some((p.mu, p.figures?)))
            .filter(|(_, f)| spec.objective.of(f).is_finite())
            .collect();
        for (key, what, limit, value) in [
            (
                "max_u",
                format!("max |u_{c}|"),
                spec.max_u[i],
                (|f: &ChannelFigures| f.max_u) as fn(&ChannelFigures) -> f64,
            ),
            ("max_uf", format!("max |u_f,{c}|"), spec.max_uf[i], |f: &ChannelFigures| f.max_uf),
        ] {
            if !limit.is_finite() {
                continue;
            }
            wanted.push(format!("{what} ≤ {prefix}{key}[{i}]"));
            let name = format!("{prefix}{key}[{i}]");
            let peaks: Vec<(f64, f64)> = completed.iter().map(|(mu, f)| (value(f), *mu)).collect();
            if let Some((text, flat)) = limit_reached(&peaks, (&what, &name, limit), spec.objective.name()) {
                reached.push(text);
                if flat {
                    flat_peaks.push(name);
                }
            }
        }
        wanted.push(format!("a finite {}", spec.objective.name()));
        let limits = if wanted.len() > 1 { ", raise the limits" } else { "" };
        let reached = if reached.is_empty() { String::new() } else { format!(" ({})", reached.join("; ")) };
        let clipped = |p: &TunePoint| p.figures.is_none_or(|f| f.max_uf > clip);
        let clipping = if clip.is_finite() && self.curve.iter().any(clipped) {
            "; the scenario's true actuator limits (truth.u_max, u_min) clip u_f and the method has no anti-windup, so a clipped loop may never settle: a run of the scenario reports how often it clips"
        } else {
            ""
        };
        if !flat_peaks.is_empty() {
            let remedy = self.flat_remedy(spec, prefix, steady);
            return format!(
                "none of the {evaluated} μ evaluated in {prefix}mu[{i}] completed with {}{reached}; raise {}, or {remedy}{clipping}",
                wanted.join(" and "),
                flat_peaks.join(" and ")
            );
        }
        if let Some(steady) = self.steady_beyond(spec, steady) {
            return format!(
                "none of the {evaluated} μ evaluated in {prefix}mu[{i}] completed with {}{reached}; raise {prefix}max_uf[{i}], or {steady}{clipping}",
                wanted.join(" and ")
            );
        }
        format!(
            "none of the {evaluated} μ evaluated in {prefix}mu[{i}] completed with {}{reached}; widen the bounds, evaluate more of them ({prefix}points){limits} or lengthen {}t_end{clipping}",
            wanted.join(" and "),
            if prefix.is_empty() { "" } else { "simulation." }
        )
    }

    /// "upper" or "lower" when the chosen μ, or the least objective's μ it ties with, is the
    /// largest or the smallest evaluated (an end of the bounds): the best may lie beyond it, and a
    /// wider range would tell.
    pub fn at_bound(&self) -> Option<&'static str> {
        let chosen = self.chosen.as_ref()?.mu;
        [Some(chosen), self.tie.map(|t| t.mu)].into_iter().flatten().find_map(|mu| self.end_at(mu))
    }

    fn end_at(&self, mu: f64) -> Option<&'static str> {
        let (lo, hi) =
            self.curve.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.mu), b.max(p.mu)));
        match self.curve.len() > 1 {
            true if mu >= hi => Some("upper"),
            true if mu <= lo => Some("lower"),
            _ => None,
        }
    }

    /// [`TuneCurve::at_bound`] in words, `key` naming the bounds (`tune.mu[0]`): which μ is at
    /// which end, and to widen the range. A search whose least objective lay at its upper end, the
    /// chosen μ just inside tying with it, had said nothing (a reactor's settling time kept falling
    /// to 23.8 min at μ = 1000 where the range ended at 100 with 36.1).
    pub fn bound_note(&self, key: &str) -> Option<String> {
        let end = self.at_bound()?;
        let chosen = self.chosen.as_ref()?.mu;
        // Six significant digits, as the line around it gives μ.
        let short = |mu: f64| crate::settings::fmt_short(crate::settings::significant(mu, 6));
        // The same objective at every μ that completed: μ changes nothing there, and the end was
        // chosen by the tie (μ from 1e-300 to 1e-100 had been told the best may lie beyond).
        let scored: Vec<(f64, f64)> = self.curve.iter().filter_map(|p| Some((p.mu, p.objective?))).collect();
        let (lo, hi) = scored.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.1), b.max(p.1)));
        if scored.len() > 1 && hi <= lo * (1.0 + 1e-9) {
            let (mu_lo, mu_hi) = scored.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.0), b.max(p.0)));
            return Some(format!(
                "the objective is the same at every μ that completed ({} of them, from {} to {}): μ changes nothing there over this horizon (no adaptation to speak of, or one long done), and the μ chosen is the tie's; search μ where the adaptation acts (the design report's adaptation rate μ λ_max against the horizon)",
                scored.len(),
                short(mu_lo),
                short(mu_hi)
            ));
        }
        Some(match self.end_at(chosen) {
            Some(_) => format!("the chosen μ, {}, is at the {end} end of {key}: the best may lie beyond, widen the range", short(chosen)),
            None => format!(
                "the least objective, at μ = {}, is at the {end} end of {key} (the chosen μ, {}, ties with it): the best may lie beyond, widen the range",
                short(self.tie.map_or(chosen, |t| t.mu)),
                short(chosen)
            ),
        })
    }
}

/// A 0-based index written 1-based.
mod one_based {
    use serde::{de::Error, Deserialize, Deserializer, Serializer};

    pub(super) fn serialize<S: Serializer>(i: &usize, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u64(*i as u64 + 1)
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<usize, D::Error> {
        match usize::deserialize(d)? {
            0 => Err(D::Error::custom("channel: expected a 1-based channel number, found 0")),
            n => Ok(n - 1),
        }
    }
}

/// The tuned μ, each channel's curve, and the joint run's check.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TuneResult {
    pub objective: Objective,
    pub channels: Vec<TuneCurve>,
    /// The tuned μ (the scenario's μ_i where a channel had no feasible point).
    pub mu: Vec<f64>,
    /// The run with every μ_i tuned at once (`None` when the tuning was stopped before it).
    pub joint: Option<Row>,
    /// Per channel: the joint run's objective minus the search's, and whether it is within the
    /// reproduction tolerance (see `tolerance` in the source).
    pub joint_difference: Vec<Option<f64>>,
    pub reproduced: Vec<bool>,
    /// Per channel, whether the joint run keeps max |u_i| and max |u_f,i| within `max_u`, `max_uf`:
    /// the objective decouples (Proposition 1) but u_f = −K x̂ + F u_d (5) mixes every channel's
    /// command, so limits met in each search can be broken together. `None` (null) without a joint
    /// run: a tuning stopped before it has checked nothing.
    #[serde(default)]
    pub within_limits: Vec<Option<bool>>,
    /// True when stopped ([`TuneOptions::stop`]) before every evaluation and the joint run were
    /// carried out: the curves hold the points evaluated so far and `chosen` is the best of them.
    #[serde(default)]
    pub partial: bool,
    /// The limits the last round's searches kept, where a joint run had broken the file's
    /// ([`tune`]); `None` (absent) where the first round's joint run kept them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub searched_within: Option<SearchedWithin>,
}

/// The tightened limits of [`TuneResult::searched_within`] and the file's, per channel (+∞ for
/// none).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SearchedWithin {
    pub max_u: Vec<f64>,
    pub max_uf: Vec<f64>,
    pub file_max_u: Vec<f64>,
    pub file_max_uf: Vec<f64>,
}

impl TuneResult {
    /// Channel i's limits that the joint run broke, one phrase each, the keys named after
    /// `prefix` (none without a joint run).
    pub fn joint_broken(&self, spec: &TuneSpec, i: usize, prefix: &str) -> Vec<String> {
        self.joint.as_ref().and_then(|j| j.completed().get(i)).map_or(vec![], |f| spec.broken_limits(i, f, prefix))
    }

    /// When the joint run with every tuned μ_i breaks a limit each search met: which, and what
    /// to do (`quell tune` exits 2 with it, Python warns); `None` otherwise, and where a channel
    /// has no feasible μ (said first: its scenario's μ is no tuned one).
    pub fn joint_limits_caution(&self, spec: &TuneSpec, prefix: &str) -> Option<String> {
        if self.channels.iter().any(|c| c.chosen.is_none()) {
            return None;
        }
        let broken: Vec<String> = (0..self.within_limits.len())
            .filter(|&i| self.within_limits[i] == Some(false))
            .map(|i| {
                let what = self.joint_broken(spec, i, prefix);
                let what = if what.is_empty() { "its run has no figures".to_string() } else { what.join(", ") };
                format!("channel {}: {what}", i + 1)
            })
            .collect();
        (!broken.is_empty()).then(|| format!(
            "the tuned μ together break limits in the joint run ({}); each search met every limit with the other channels' μ at the scenario's, but u_f = −K x̂ + F u_d mixes every channel's command, and searches run again within limits tightened by the joint run's excess (up to {JOINT_ROUNDS} rounds, while the excess shrinks and every channel keeps a feasible μ) did not bring it within them: tune with a grid over the μ together (docs/studies.md)",
            broken.join("; ")
        ))
    }

    /// Where the searches ran again within tightened limits ([`TuneResult::searched_within`]):
    /// which limits they kept, keys named after `prefix`; `None` otherwise.
    pub fn searched_note(&self, prefix: &str) -> Option<String> {
        let within = self.searched_within.as_ref()?;
        let fmt = crate::settings::fmt_4;
        let tightened: Vec<String> =
            [("max_u", &within.max_u, &within.file_max_u), ("max_uf", &within.max_uf, &within.file_max_uf)]
                .into_iter()
                .flat_map(|(key, searched, file)| {
                    (searched.iter().zip(file).enumerate())
                        .filter(|(_, (s, f))| s < f)
                        .map(move |(i, (s, f))| format!("{prefix}{key}[{i}] = {} as {}", fmt(*f), fmt(*s)))
                })
                .collect();
        let kept = if self.within_limits.iter().all(|w| *w == Some(true)) {
            "keeps the file's limits"
        } else {
            "still breaks them"
        };
        Some(format!(
            "each channel's search met its limits, but their joint run broke them (u_f = −K x̂ + F u_d mixes every channel's command); the searches ran again keeping {} (each broken limit × limit / the joint run's figure, {} rounds at most), and the joint run {kept}",
            tightened.join(", "),
            JOINT_ROUNDS
        ))
    }

    /// Per channel whose joint run does not reproduce its search's objective (the channels'
    /// searches interact): a caution; none for a partial tuning.
    pub fn unreproduced_cautions(&self) -> Vec<String> {
        let cautions = self.channels.iter().zip(self.joint_difference.iter().zip(&self.reproduced));
        // A joint run that does better than its search is no caution: the interaction helped.
        cautions
            .filter(|(c, (d, ok))| !**ok && !joint_better(**d) && c.chosen.is_some() && !self.partial)
            .map(|(c, (d, _))| {
                let by = d.map_or("it has no figure".to_string(), |d| format!("difference {d:.3e}"));
                format!(
                    "channel {}: the joint run with every tuned μ does not reproduce the objective its search found ({by}): each channel was searched with the others' μ at the scenario's, and the tuned μ together interact; check the joint run, or tune with a grid over the μ together (docs/studies.md)",
                    c.channel + 1
                )
            })
            .collect()
    }
}

/// Whether a joint run's objective beat its search's (`difference` = joint − search < 0): the
/// channels' interaction helped, which is said, not cautioned.
pub fn joint_better(difference: Option<f64>) -> bool {
    difference.is_some_and(|d| d < 0.0)
}

/// A callback on each evaluation: the channel and its point.
pub type OnPoint<'a> = dyn Fn(usize, &TunePoint) + Sync + 'a;

/// How [`tune`] runs.
#[derive(Clone, Copy, Default)]
pub struct TuneOptions<'a> {
    /// Set (e.g. by Ctrl-C) to stop: evaluations under way are abandoned, no new one starts, and
    /// the result keeps the points evaluated so far, marked [`TuneResult::partial`].
    pub stop: Option<&'a AtomicBool>,
    /// Called after each evaluation with its channel (from the worker threads).
    pub on_point: Option<&'a OnPoint<'a>>,
}

/// The run of `study`'s scenario (no grid, no draws) with μ = `mu`; `None` when `stop` interrupted it.
fn run_with(study: &Study, mu: &[f64], stop: &dyn Fn() -> bool) -> Option<Row> {
    let mut doc = study.base().clone();
    let mu_value = toml::Value::Array(mu.iter().map(|&x| toml::Value::Float(x)).collect());
    super::KeyPath::parse("design.mu").expect("a key path").set(&mut doc, mu_value).expect("a scenario has design.mu");
    let settle = study.settle;
    let spec = RunSpec {
        run: 0,
        point: 0,
        draw: 0,
        seed: 0,
        grid: Vec::new(),
        scenario: doc,
        settle,
        max_steps: study.max_steps,
        runaway: study.runaway,
        nominal: None,
        drawn_keys: Vec::new(),
    };
    execute(&spec, stop)
}

/// How close the joint run's objective must be to the search's: for error figures, relative 1e-3
/// plus 100 (rtol·ĝ + atol), the solver's local error bound on e_i (ĝ = |bias| + Σ|amplitude|
/// bounds |g_i|) with a factor 100 for its accumulation over the horizon; in a sampled loop, which
/// has no solver, 1e-9·ĝ in its place (a building's joint tail of 3.4e-14 against its search's
/// 1.8e-7 had "reproduced" it within the continuous loop's tolerance; helper tryout); for settling
/// times, one output step (they are read off the recorded samples).
fn tolerance(obj: Objective, value: f64, s: &Scenario, i: usize) -> f64 {
    let sim = &s.simulation;
    let floor = match sim.sample_time {
        Some(_) => 1e-9 * reference_bound(s, i),
        None => 100.0 * tolerance_scale(s, i),
    };
    match obj {
        Objective::SettleT => sim.output_step * (1.0 + 1e-9),
        _ => 1e-3 * value.abs() + floor,
    }
}

/// ĝ = |bias| + Σ|amplitude|, which bounds |g_i|.
fn reference_bound(s: &Scenario, i: usize) -> f64 {
    let c = &s.reference.components[i];
    c.bias.abs() + c.harmonics.iter().map(|h| h.amplitude.abs()).sum::<f64>()
}

/// rtol·ĝ + atol, the integrator's tolerance on e_i (ĝ = |bias| + Σ|amplitude| bounds |g_i|).
fn tolerance_scale(s: &Scenario, i: usize) -> f64 {
    s.simulation.rtol * reference_bound(s, i) + s.simulation.atol
}

/// The cautions before a tuning's searches (`quell tune` and Python's `tune` print them): those of
/// [`tune_stiff_warnings`], those of a `max_uf` above `[truth] u_max`, then
/// [`Study::fast_rate_caution`] of its scenario.
pub fn tune_cautions(study: &Study) -> Vec<String> {
    let stiff = tune_stiff_warnings(study).into_iter();
    stiff.chain(limit_above_the_clip(study)).chain(study.fast_rate_caution(&|| false)).collect()
}

/// Per input whose `tune.max_uf` is above the scenario's `[truth] u_max`: a μ within the tuning's
/// limit may still ask more than the true actuator gives, and be clipped (a ball and beam tuned to
/// max_uf = 1 under a 0.6 drive chose a μ asking 0.95, clipped at 1.8 % of its samples, with
/// nothing said; helper tryout, 2026-12-06).
pub(crate) fn limit_above_the_clip(study: &Study) -> Vec<String> {
    let Some(spec) = study.tune.as_ref() else { return vec![] };
    let fmt = crate::settings::fmt_short;
    (spec.max_uf.iter().enumerate().map(|(i, &wanted)| (i, (wanted, study.u_max(i)))))
        .filter(|&(_, (wanted, clip))| wanted > clip)
        .map(|(i, (wanted, clip))| {
            format!(
                "tune.max_uf[{i}] = {} is above the true actuator's {}: a μ within the tuning's limit may ask more than the actuator gives and be clipped (the method has no anti-windup); give tune.max_uf[{i}] at most {} to keep u_f within it",
                fmt(wanted),
                study.limits_text(i).unwrap_or_default(),
                fmt(clip)
            )
        })
        .collect()
}

/// For a tuning forced onto DOP853 (`simulation.method = "explicit"`), per channel whose search runs
/// a μ that makes the adaptive law stiff, the caution of [`crate::sim::explicit_stiff_warning`]
/// there: channel i's search varies μ_i over its bounds with the other μ_j at the scenario's, so
/// each channel's two ends are checked (2m designs). Empty otherwise, or without a valid `[tune]`
/// (which [`tune`] then refuses).
pub fn tune_stiff_warnings(study: &Study) -> Vec<String> {
    let Some(spec) = study.tune.as_ref() else { return vec![] };
    let Ok(s) = Scenario::from_document(study.base()) else { return vec![] };
    if s.simulation.method != crate::sim::Method::Explicit || spec.bounds.len() != s.design.mu.len() {
        return vec![];
    }
    let at_end = |i: usize, end: f64| {
        let mut at = s.clone();
        at.design.mu[i] = end;
        let design = at.design().ok()?;
        let run = crate::sim::Run::of(&at, &design);
        let w = crate::sim::explicit_stiff_warning(&run, crate::sim::EXPLICIT_IN_FILE)?;
        let mu: Vec<String> = at.design.mu.iter().map(|&v| crate::settings::fmt_short(v)).collect();
        Some(format!("channel {}'s search runs μ = [{}]: {w}", i + 1, mu.join(", ")))
    };
    spec.bounds.iter().enumerate().filter_map(|(i, b)| at_end(i, b[1]).or_else(|| at_end(i, b[0]))).collect()
}

/// The `[tune]` table of a study that tuning can run: present, and no grid or draws it would ignore.
fn tune_spec(study: &Study) -> Result<&TuneSpec, StudyError> {
    let spec = study
        .tune
        .as_ref()
        .ok_or_else(|| err("tune", "missing; `quell tune` needs a [tune] table (objective, mu bounds, max_u)"))?;
    // Tuning searches μ on the scenario alone; a grid or draws in the file would be ignored.
    for (key, present) in [("grid", !study.grid.is_empty()), ("monte_carlo", study.monte_carlo.is_some())] {
        if present {
            return Err(err(
                key,
                format!("tuning runs the scenario alone, so [{key}] would be ignored; remove it (or tune a copy of the study without it, and sweep the tuned μ with `quell sweep`)"),
            ));
        }
    }
    Ok(spec)
}

/// Objectives within this share of the least are a tie ([`least_mu_within_tolerance`]).
const TIE_SHARE: f64 = 0.05;
/// Tails up to this many times the integrator's tolerance on e_i are a tie: its global error is a
/// few times its local tolerance (examples/siso-complex.toml over 200 s at rtol = 1e-9: tails of
/// 1.5e-9 on DOP853 and 4.6e-9 on the implicit method at μ = 316, whose true tail is 4.5e-13).
const TIE_TOLERANCES: f64 = 3.0;

/// The point a search chooses from `curve` (sorted by μ): the smallest μ whose objective is a tie
/// with the least, v ≤ max((1 + [`TIE_SHARE`])·v_min, [`TIE_TOLERANCES`]·s), s the scale of the
/// integrator's tolerance on e_i, rtol·ĝ + atol (ĝ = |bias| + Σ|amplitude|); for settling times,
/// within one output step of the least. Among figures the integrator cannot tell apart (a converged
/// tail at its tolerance, or within a few per cent), the slowest adaptation is the least stiff and
/// the least sensitive to noise. A flat objective (examples/siso-complex.toml over 200 s: tails of
/// 1.5e-9 and 1.53e-9 at μ = 1000 and 316, rtol = 1e-9) had been decided by rounding. The joint
/// check's own tolerance, 100 times that scale, is too wide for a tie: it took a tail 160 times the
/// least's.
fn least_mu_within_tolerance<'c>(
    curve: &'c [TunePoint],
    objective: Objective,
    scenario: &Scenario,
    i: usize,
) -> Option<(&'c TunePoint, Tie)> {
    let best = curve.iter().filter(|p| p.objective.is_some()).min_by(|a, b| key(a).total_cmp(&key(b)))?;
    let least = key(best);
    let bound = match objective {
        Objective::SettleT => least + tolerance(objective, least, scenario, i),
        _ => ((1.0 + TIE_SHARE) * least).max(TIE_TOLERANCES * tolerance_scale(scenario, i)),
    };
    let chosen = curve.iter().find(|p| p.objective.is_some_and(|v| v <= bound))?;
    Some((chosen, Tie { least, mu: best.mu, bound }))
}

/// The ordering of points in a search: by objective, infeasible points (`None`) last.
fn key(p: &TunePoint) -> f64 {
    p.objective.unwrap_or(f64::INFINITY)
}

/// One channel's search at a time, over the scenario's μ with μ_i varied.
struct Search<'a> {
    study: &'a Study,
    scenario: &'a Scenario,
    /// The limits the searched channel keeps ([`tune`]'s round) and the file's, which it keeps
    /// on the other channels it guards.
    spec: &'a TuneSpec,
    file: &'a TuneSpec,
    base_mu: &'a [f64],
    /// Per channel j, whether the scenario's own μ keeps its limits: every search must then keep
    /// them too (a limit the scenario's μ already breaks is channel j's search to meet).
    guarded: Vec<bool>,
    opts: &'a TuneOptions<'a>,
}

impl Search<'_> {
    fn stopped(&self) -> bool {
        self.opts.stop.is_some_and(|s| s.load(Ordering::Relaxed))
    }

    /// The limits on input j that channel i's search breaks with figures `f`: its own tightened
    /// ones, said so (a reason had quoted "tune.max_uf[1] = 0.489", which the file never set), or
    /// the file's on the others it guards.
    fn broken(&self, i: usize, j: usize, f: &ChannelFigures) -> Vec<String> {
        if j != i {
            return self.file.broken_limits(j, f, "tune.");
        }
        let tightened = self.spec.max_u[i] != self.file.max_u[i] || self.spec.max_uf[i] != self.file.max_uf[i];
        let mut broken = self.spec.broken_limits(j, f, "tune.");
        if tightened {
            broken.iter_mut().for_each(|p| p.push_str(" (tightened from the file's for the joint run)"));
        }
        broken
    }

    /// Channel i's figures at μ_i = `mu_i`; `None` when stopped.
    fn score(&self, i: usize, mu_i: f64) -> Option<TunePoint> {
        if self.stopped() {
            return None;
        }
        let mut mu = self.base_mu.to_vec();
        mu[i] = mu_i;
        let point = self.point(i, mu_i, run_with(self.study, &mu, &|| self.stopped())?);
        if let Some(f) = self.opts.on_point {
            f(i, &point);
        }
        Some(point)
    }

    /// Channel i's point at μ_i = `mu_i` from its run's `row` (the other channels at the scenario's μ).
    fn point(&self, i: usize, mu_i: f64, row: Row) -> TunePoint {
        let figures = row.completed().get(i).copied();
        let (spec, objective) = (self.spec, self.spec.objective);
        // Every input's limits that the scenario's μ keeps: u_f = −K x̂ + F u_d (5) mixes the
        // channels' commands, so μ_i moves u_f,j too (a reactor's μ₁ = 100 took max |u_f,2| from
        // 0.159 to 0.199, beyond its 0.16, and the search had called it feasible).
        let kept = |j: usize| j == i || self.guarded[j];
        let broken: Vec<String> = (row.completed().iter().enumerate())
            .filter(|&(j, _)| kept(j))
            .flat_map(|(j, f)| self.broken(i, j, f))
            .collect();
        let objective = figures.filter(|_| broken.is_empty()).map(|c| objective.of(&c)).filter(|v| v.is_finite());
        // A completed run beyond a limit: the limit is why it has no objective.
        let mut reason = row.reason;
        if reason.is_empty() && figures.is_some() {
            reason = broken.join("; ");
        }
        // Within the limits but with no objective: say so (the row's reason was empty).
        if reason.is_empty() && figures.is_some() && objective.is_none() {
            reason = format!("no finite {} (never settled within the run)", spec.objective.name());
        }
        TunePoint { mu: mu_i, objective, outcome: row.outcome, reason, figures }
    }

    /// Golden-section search on log μ_i over the neighbours of the best point of `curve`, each
    /// evaluation appended to it; returns early when stopped.
    fn refine(&self, i: usize, curve: &mut Vec<TunePoint>) {
        let Some(best) = (0..curve.len()).min_by(|&a, &b| key(&curve[a]).total_cmp(&key(&curve[b]))) else { return };
        let [lo, hi] = self.spec.bounds[i];
        if curve[best].objective.is_none() || self.spec.refine == 0 || lo == hi {
            return;
        }
        let (mut a, mut b) = (curve[best.saturating_sub(1)].mu.ln(), curve[(best + 1).min(curve.len() - 1)].mu.ln());
        let mut eval = |log_mu: f64| {
            let p = self.score(i, log_mu.exp())?;
            let k = key(&p);
            curve.push(p);
            Some(k)
        };
        let r = (5f64.sqrt() - 1.0) / 2.0;
        let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
        let Some(mut fc) = eval(c) else { return };
        let Some(mut fd) = eval(d) else { return };
        for _ in 2..self.spec.refine {
            let next = if fc <= fd {
                (b, d, fd) = (d, c, fc);
                c = b - r * (b - a);
                eval(c).map(|f| fc = f)
            } else {
                (a, c, fc) = (c, d, fd);
                d = a + r * (b - a);
                eval(d).map(|f| fd = f)
            };
            if next.is_none() {
                return;
            }
        }
    }

    /// Channel i's curve (its points of `coarse`, refined) in order of μ, and its chosen point ([`least_mu_within_tolerance`]).
    fn curve(&self, i: usize, coarse: &[(usize, TunePoint)]) -> TuneCurve {
        let mut curve: Vec<TunePoint> = coarse.iter().filter(|(c, _)| *c == i).map(|(_, p)| p.clone()).collect();
        // In order of μ: the refinement brackets the best point by its neighbours.
        curve.sort_by(|a, b| a.mu.total_cmp(&b.mu));
        self.refine(i, &mut curve);
        curve.sort_by(|a, b| a.mu.total_cmp(&b.mu));
        let found = least_mu_within_tolerance(&curve, self.spec.objective, self.scenario, i);
        let (chosen, tie) = found.map_or((None, None), |(p, tie)| (Some(p.clone()), Some(tie)));
        TuneCurve { channel: i, curve, chosen, tie }
    }
}

/// Search rounds at most: the first within the file's limits, then within limits tightened where
/// the joint run broke them ([`tune`]).
pub const JOINT_ROUNDS: usize = 4;

/// Runs the m searches of `study.tune` (in parallel on rayon's current pool) and the joint check.
/// Where the joint run breaks a limit each search met (u_f mixes every channel's command), the
/// searches run again within that limit scaled by limit / joint figure, up to [`JOINT_ROUNDS`]
/// rounds while each breaks the limits by less and keeps every channel a feasible μ (else the
/// round before stands), the joint run always judged against the file's limits: a bioreactor's
/// 0.51125 against 0.5 had been told to lower the limit by the excess and tune again, which missed
/// the lowered limit (0.4915 > 0.48875) while meeting its own, three times by hand (helper
/// tryout, 2026-12-07).
/// When `opts.stop` is set the result holds what was evaluated by then, marked partial.
pub fn tune(study: &Study, opts: &TuneOptions<'_>) -> Result<TuneResult, StudyError> {
    let spec = tune_spec(study)?;
    let scenario = Scenario::from_document(study.base()).map_err(|e| err("scenario", e.to_string()))?;
    let mut searched = spec.clone();
    let mut result = search_and_join(study, (&scenario, spec, &searched), opts);
    for _ in 1..JOINT_ROUNDS {
        // Not where a channel has no feasible μ: its scenario's μ is no search's to tighten.
        let untuned = result.partial || result.channels.iter().any(|c| c.chosen.is_none());
        let Some(tighter) = tightened((&searched, spec), &result).filter(|_| !untuned) else { break };
        let mut next = search_and_join(study, (&scenario, spec, &tighter), opts);
        // A round that leaves a channel without a feasible μ (a limit tightened below what its
        // search can meet) is no better: the last round stands, with its caution.
        // Nor one whose joint run breaks the limits by as much or more: the rounds then do not help
        // (the excess came from another channel's μ, which the tightened limit does not bind).
        let lost = (result.channels.iter().zip(&next.channels)).any(|(a, b)| a.chosen.is_some() && b.chosen.is_none());
        if lost || next.partial || joint_excess(&next, spec) >= joint_excess(&result, spec) {
            break;
        }
        searched = tighter;
        next.searched_within = Some(SearchedWithin {
            max_u: searched.max_u.clone(),
            max_uf: searched.max_uf.clone(),
            file_max_u: spec.max_u.clone(),
            file_max_uf: spec.max_uf.clone(),
        });
        result = next;
    }
    Ok(result)
}

/// The most the joint run of `result` asks of a limit of `spec`, as a multiple of it (≤ 1 within
/// them all; ∞ without a joint run's figures).
fn joint_excess(result: &TuneResult, spec: &TuneSpec) -> f64 {
    let Some(joint) = result.joint.as_ref() else { return f64::INFINITY };
    let figures = joint.completed();
    if figures.is_empty() {
        return f64::INFINITY;
    }
    (figures.iter().enumerate())
        .flat_map(|(i, f)| [f.max_u / spec.max_u[i], f.max_uf / spec.max_uf[i]])
        .fold(0.0, |a, r| if r.is_nan() { f64::INFINITY } else { a.max(r) })
}

/// The limits of `searched` scaled down where the joint run of `result` broke the file's (`spec`):
/// each broken limit × limit / the joint figure; `None` where it broke none (or has no figures).
fn tightened((searched, spec): (&TuneSpec, &TuneSpec), result: &TuneResult) -> Option<TuneSpec> {
    let joint = result.joint.as_ref()?.completed();
    let mut tighter = searched.clone();
    let mut changed = false;
    for (i, f) in joint.iter().enumerate().filter(|(i, _)| result.within_limits.get(*i) == Some(&Some(false))) {
        for (limit, value, file) in
            [(&mut tighter.max_u[i], f.max_u, spec.max_u[i]), (&mut tighter.max_uf[i], f.max_uf, spec.max_uf[i])]
        {
            if value > file && value.is_finite() {
                *limit *= file / value;
                changed = true;
            }
        }
    }
    changed.then_some(tighter)
}

/// One round of [`tune`]: the m searches within `searched`'s limits, the joint run judged against
/// `spec`'s (the file's).
fn search_and_join(
    study: &Study,
    (scenario, spec, searched): (&Scenario, &TuneSpec, &TuneSpec),
    opts: &TuneOptions<'_>,
) -> TuneResult {
    let base_mu = scenario.design.mu.clone();
    let m = base_mu.len();
    let stopped = || opts.stop.is_some_and(|s| s.load(Ordering::Relaxed));
    // The scenario's own run, where a limit is set: which of the file's limits every search must
    // keep (a tightened one is its own channel's search's to keep).
    let limited = spec.max_u.iter().chain(&spec.max_uf).any(|l| l.is_finite());
    // The scenario's own μ_i, inside channel i's bounds and off its grid, is a point of its curve
    // too: a quadrotor's tuning said "no feasible mu" of 7 points over three decades while the
    // scenario's μ₄ = 5204 kept max |u_f,4| = 2.86 within its 3 (helper tryout, 2026-12-07).
    let own: Vec<usize> = (0..m)
        .filter(|&i| {
            let [lo, hi] = searched.bounds[i];
            (lo..=hi).contains(&base_mu[i]) && searched.log_grid(i).all(|mu| (mu / base_mu[i] - 1.0).abs() > 1e-9)
        })
        .collect();
    let base = if limited || !own.is_empty() { run_with(study, &base_mu, &stopped) } else { None };
    let guarded = (0..m)
        .map(|j| {
            base.as_ref().and_then(|r| r.completed().get(j)).is_some_and(|f| spec.broken_limits(j, f, "").is_empty())
        })
        .collect();
    let search = Search { study, scenario, spec: searched, file: spec, base_mu: &base_mu, guarded, opts };
    let jobs: Vec<(usize, f64)> = (0..m).flat_map(|i| searched.log_grid(i).map(move |mu| (i, mu))).collect();
    let mut coarse: Vec<(usize, TunePoint)> =
        jobs.into_par_iter().filter_map(|(i, mu)| Some((i, search.score(i, mu)?))).collect();
    if let Some(row) = base.as_ref().filter(|_| !search.stopped()) {
        coarse.extend(own.iter().map(|&i| (i, search.point(i, base_mu[i], row.clone()))));
    }
    let channels: Vec<TuneCurve> = (0..m).into_par_iter().map(|i| search.curve(i, &coarse)).collect();
    let mu: Vec<f64> = channels.iter().zip(&base_mu).map(|(c, &m0)| c.chosen.as_ref().map_or(m0, |p| p.mu)).collect();
    let joint = if search.stopped() { None } else { run_with(study, &mu, &|| search.stopped()) };
    let (joint_difference, reproduced) = channels
        .iter()
        .map(|c| {
            let search = c.chosen.as_ref().and_then(|p| p.figures).map(|f| spec.objective.of(&f));
            let joint_value = joint.as_ref().and_then(|j| j.completed().get(c.channel)).map(|f| spec.objective.of(f));
            match (search, joint_value) {
                (Some(s), Some(j)) if s.is_finite() && j.is_finite() => {
                    (Some(j - s), (j - s).abs() <= tolerance(spec.objective, s, scenario, c.channel))
                }
                _ => (None, false),
            }
        })
        .unzip();
    let within_limits = (0..m)
        .map(|i| {
            let joint = joint.as_ref()?;
            Some(joint.completed().get(i).is_some_and(|f| f.max_u <= spec.max_u[i] && f.max_uf <= spec.max_uf[i]))
        })
        .collect();
    let partial = joint.is_none();
    TuneResult {
        objective: spec.objective,
        channels,
        mu,
        joint,
        joint_difference,
        reproduced,
        within_limits,
        partial,
        searched_within: None,
    }
}

impl TuneCurve {
    /// Where the steady state's own input `steady` is beyond `max_uf`: no μ, bounds, poles or
    /// horizon bring the input under it, so the remedy is to ask less of the loop.
    fn steady_beyond(&self, spec: &TuneSpec, steady: f64) -> Option<String> {
        let (i, c) = (self.channel, self.channel + 1);
        (steady > spec.max_uf[i]).then(|| {
            format!(
                "ask less of the loop (smaller references or disturbances): the steady state alone asks max |u_f,{c}| = {} for y = g (the design report's steady-state section), whatever μ and the poles",
                crate::settings::fmt_4(steady)
            )
        })
    }

    /// What [`TuneCurve::why_none`] offers where a limit's figure is the same at every μ: slower
    /// poles, or, beyond the steady state's own input `steady`, asking less of the loop (a bicycle
    /// model's steering, 0.02458 rad for y = g against a limit of 0.02, had been told to slow its
    /// poles); and a longer horizon where some μ never reached a finite objective (a longer one may
    /// admit it).
    fn flat_remedy(&self, spec: &TuneSpec, prefix: &str, steady: f64) -> String {
        let slower = self.steady_beyond(spec, steady).unwrap_or_else(|| {
            "slow the scenario's channel and observer poles (an automatic design with an actuator limit, u_limit, chooses poles within it)".to_string()
        });
        let unsettled = self.curve.iter().any(|p| p.figures.is_some_and(|f| !spec.objective.of(&f).is_finite()));
        if !unsettled {
            return slower;
        }
        format!(
            "{slower}, or lengthen {}t_end (some μ did not reach a finite {})",
            if prefix.is_empty() { "" } else { "simulation." },
            spec.objective.name()
        )
    }
}

/// Peaks within this ratio over a tuning's runs are the same at every μ.
const FLAT_PEAK: f64 = 1.01;

/// Where a limit (`what`, its key `name`, its value) rejected every run with a finite objective
/// (`peaks`: (the figure, μ) per such run): how close they came, and whether the figure is the same
/// at every μ ([`FLAT_PEAK`]): μ does not set it then, so no bound on μ helps (a buck converter's
/// u_f of 0.0707 from μ = 10 to 1e5 had been told to widen them; helper tryout, 2026-12-06).
fn limit_reached(
    peaks: &[(f64, f64)],
    (what, name, limit): (&str, &str, f64),
    objective: &str,
) -> Option<(String, bool)> {
    let (v, mu) = peaks.iter().copied().min_by(|a, b| a.0.total_cmp(&b.0)).filter(|(v, _)| *v > limit)?;
    let most = peaks.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    let (four, short) = (crate::settings::fmt_4, crate::settings::fmt_short);
    if peaks.len() > 1 && most <= FLAT_PEAK * v {
        let (lo, hi) = peaks.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| (lo.min(p.1), hi.max(p.1)));
        let text = format!(
            "{what} is {} at every μ with a finite {objective} (from {} to {}), above {name} = {}: the poles and the signals set it, not μ",
            four(v),
            short(lo),
            short(hi),
            short(limit)
        );
        return Some((text, true));
    }
    // The smallest two μ within FLAT_PEAK of the least: the figure has stopped falling with μ
    // there, so smaller μ do not lower it (a power system's 0.351 p.u. peaked at 0.07 s, before
    // its 0.1 s delayed adaptive command acted, at every μ from 0.01 up; "widen the bounds" had
    // been offered; a mixing tank's 0.1120 at μ = 0.3 and 0.7 beside its least, 0.11199 at μ = 4,
    // had been offered it again, helper tryout, 2026-12-07).
    let mut by_mu = peaks.to_vec();
    by_mu.sort_by(|a, b| a.1.total_cmp(&b.1));
    // Every point up to the least's μ within FLAT_PEAK (not a least at the upper end, still falling).
    let level = by_mu.iter().filter(|p| p.1 <= mu).all(|p| p.0 <= FLAT_PEAK * v);
    if let [(_, mu0), (next, mu1), ..] = by_mu[..] {
        if level && next <= FLAT_PEAK * v {
            let text = format!(
                "{what} levels off at {} toward the smallest μ (at μ = {} and {}), above {name} = {}: the poles and the signals set it there, not μ",
                four(v),
                four(mu0),
                four(mu1),
                short(limit)
            );
            return Some((text, true));
        }
    }
    let text = format!(
        "the least {what} of the runs with a finite {objective} is {} (at μ = {}), above {name} = {}",
        four(v),
        four(mu),
        short(limit)
    );
    Some((text, false))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chosen μ at the largest or smallest evaluation is said to be at that end of the bounds;
    /// inside them, or with one evaluation only, it is not.
    /// μ_min = μ_max fixes μ_i: one evaluation, chosen, at no end of a range (a fixed μ had been run
    /// 15 times, then called at the lower end of its range, which might be widened).
    #[test]
    fn a_fixed_mu_is_evaluated_once() {
        let text = "[simulation]\nt_end = 5.0\nrtol = 1e-6\natol = 1e-6\n[tune]\nobjective = \"tail_rms_e\"\nmu = [[5.0, 5.0], [2.0, 20.0]]\npoints = 3\nrefine = 2\n";
        let study = Study::from_toml(text, None).unwrap();
        let r = tune(&study, &Default::default()).unwrap();
        assert_eq!(r.channels[0].curve.iter().map(|p| p.mu).collect::<Vec<_>>(), [5.0]);
        assert_eq!(r.channels[0].chosen.as_ref().map(|p| p.mu), Some(5.0));
        assert_eq!(r.channels[0].at_bound(), None);
        assert_eq!(r.channels[1].curve.len(), 3 + 2);
    }

    /// A completed evaluation at μ with objective 1.
    fn point(mu: f64) -> TunePoint {
        TunePoint { mu, objective: Some(1.0), outcome: Outcome::Completed, reason: String::new(), figures: None }
    }

    /// A least objective at an end of the bounds is named even where the chosen μ, tying with it,
    /// lies inside (a reactor's settling time fell to the upper end, 100, and the chosen 96.5 had
    /// said nothing).
    #[test]
    fn a_least_objective_at_an_end_is_named_where_the_chosen_mu_ties_inside() {
        let scored = |mu: f64, objective: f64| TunePoint { objective: Some(objective), ..point(mu) };
        let c = TuneCurve {
            channel: 1,
            curve: vec![scored(50.0, 40.0), scored(96.5, 36.1), scored(100.0, 36.05)],
            chosen: Some(point(96.5)),
            tie: Some(Tie { least: 36.05, mu: 100.0, bound: 36.15 }),
        };
        assert_eq!(c.at_bound(), Some("upper"));
        assert_eq!(
            c.bound_note("tune.mu[1]").unwrap(),
            "the least objective, at μ = 100, is at the upper end of tune.mu[1] (the chosen μ, 96.5, ties with it): the best may lie beyond, widen the range"
        );
        let inside = TuneCurve { tie: Some(Tie { least: 36.05, mu: 96.5, bound: 36.15 }), ..c.clone() };
        assert_eq!((inside.at_bound(), inside.bound_note("tune.mu[1]")), (None, None));
        let at_end = TuneCurve { chosen: Some(point(100.0)), ..c };
        assert_eq!(
            at_end.bound_note("mu[1]").unwrap(),
            "the chosen μ, 100, is at the upper end of mu[1]: the best may lie beyond, widen the range"
        );
    }

    /// A tuning stopped before its joint run has checked no limit: none is said broken (every
    /// channel's search had chosen a μ, and the result had read `within_limits` false, which
    /// Python warned of as broken limits in a joint run that never ran).
    #[test]
    fn a_tuning_stopped_before_its_joint_run_breaks_no_limit() {
        let spec = TuneSpec {
            objective: Objective::TailRmsE,
            bounds: vec![[1.0, 100.0]; 2],
            max_u: vec![f64::INFINITY; 2],
            max_uf: vec![f64::INFINITY; 2],
            points: 3,
            refine: 0,
        };
        let curve = |channel| TuneCurve { channel, curve: vec![point(10.0)], chosen: Some(point(10.0)), tie: None };
        let stopped = TuneResult {
            objective: Objective::TailRmsE,
            channels: vec![curve(0), curve(1)],
            mu: vec![10.0, 10.0],
            joint: None,
            joint_difference: vec![None, None],
            reproduced: vec![false, false],
            within_limits: vec![None, None],
            partial: true,
            searched_within: None,
        };
        assert_eq!(stopped.joint_limits_caution(&spec, ""), None);
        // Where the joint run broke one, it is named (here without figures to quote).
        let broken = TuneResult { within_limits: vec![Some(false), Some(true)], ..stopped };
        let caution = broken.joint_limits_caution(&spec, "").unwrap();
        assert!(caution.starts_with("the tuned μ together break limits in the joint run (channel 1: "), "{caution}");
        // A joint run worse than its search is cautioned, one better is not (the interaction helped).
        let differing = TuneResult { joint_difference: vec![Some(-1.8e-7), Some(2e-7)], partial: false, ..broken };
        let cautions = differing.unreproduced_cautions();
        assert!(cautions.len() == 1 && cautions[0].starts_with("channel 2: "), "{cautions:?}");
    }

    /// A sampled loop has no solver: its reproduction tolerance is 1e-3 of the figure plus
    /// 1e-9·ĝ, not the continuous loop's 100 (rtol·ĝ + atol) (the paper's ĝ = 3 on channel 1, at
    /// rtol = atol = 1e-9: 4e-7), within which a joint tail of 3.4e-14 had "reproduced" 1.8e-7.
    #[test]
    fn a_sampled_loops_tolerance_is_not_the_solvers() {
        let mut s = Scenario::from_toml(crate::scenario::PAPER_EXAMPLE).unwrap();
        let continuous = tolerance(Objective::TailRmsE, 1.8e-7, &s, 0);
        assert!((continuous - (1.8e-10 + 100.0 * (1e-9 * 3.0 + 1e-9))).abs() < 1e-20, "{continuous}");
        s.simulation.sample_time = Some(0.001);
        let sampled = tolerance(Objective::TailRmsE, 1.8e-7, &s, 0);
        assert!((sampled - (1.8e-10 + 3e-9)).abs() < 1e-20, "{sampled}");
        assert!(1.8e-7 - 3.4e-14 > sampled);
    }

    /// The same objective at every μ that completed is said to be so, not that the best may lie
    /// beyond an end (μ from 1e-300 to 1e300 on the paper's loop over 10 s: the same tail at every
    /// μ up to 1e-100, the chosen the lowest by the tie; helper tryout, 2026-12-06).
    #[test]
    fn a_flat_objective_is_named_not_an_end() {
        let failed = TunePoint { objective: None, outcome: Outcome::Failed, ..point(1e300) };
        let c = TuneCurve {
            channel: 0,
            curve: vec![point(1e-300), point(1e-100), failed],
            chosen: Some(point(1e-300)),
            tie: None,
        };
        assert_eq!(c.at_bound(), Some("lower"));
        assert_eq!(
            c.bound_note("tune.mu[0]").unwrap(),
            "the objective is the same at every μ that completed (2 of them, from 1e-300 to 1e-100): μ changes nothing there over this horizon (no adaptation to speak of, or one long done), and the μ chosen is the tie's; search μ where the adaptation acts (the design report's adaptation rate μ λ_max against the horizon)"
        );
    }

    #[test]
    fn a_choice_at_an_end_of_the_bounds_is_named() {
        let curve = |chosen: f64, mus: &[f64]| TuneCurve {
            channel: 0,
            curve: mus.iter().map(|&m| point(m)).collect(),
            chosen: Some(point(chosen)),
            tie: None,
        };
        assert_eq!(curve(100.0, &[1.0, 10.0, 100.0]).at_bound(), Some("upper"));
        assert_eq!(curve(1.0, &[10.0, 1.0, 100.0]).at_bound(), Some("lower"));
        assert_eq!(curve(10.0, &[1.0, 10.0, 100.0]).at_bound(), None);
        assert_eq!(curve(5.0, &[5.0]).at_bound(), None);
        assert_eq!(
            TuneCurve { channel: 0, curve: vec![point(1.0), point(2.0)], chosen: None, tie: None }.at_bound(),
            None
        );
    }

    /// The least peak a limit blocks is taken over the runs with a finite objective: a run that never
    /// settled (its max |u_f| 2.559, below the settled one's 3.226) would name a limit that admits
    /// nothing (a servo's tuning, from a tryout).
    #[test]
    fn the_least_peak_named_is_that_of_a_run_the_limit_alone_rejected() {
        let (curve, spec) = settle_tuning(
            vec![completed(1.0, figures(2.559, None)), completed(10.0, figures(3.226, Some(80.0)))],
            ([1.0, 10.0], 1.0),
        );
        let why = curve.why_none(&spec, "tune.", (f64::INFINITY, 0.0));
        assert!(
            why.contains("(the least max |u_f,1| of the runs with a finite settle_t is 3.226 (at μ = 10), above tune.max_uf[0] = 1)"),
            "{why}"
        );
        assert!(!why.contains("truth.u_max"), "{why}");
        // Through a clipping actuator the clipping is named too (tune.csv had only "never settled"),
        // where a run asked beyond it: not under a limit above every demand (3.226 here).
        assert!(curve
            .why_none(&spec, "tune.", (3.0, 0.0))
            .ends_with("a run of the scenario reports how often it clips"));
        assert!(!curve.why_none(&spec, "tune.", (3.5, 0.0)).contains("truth.u_max"));
        // The same max |u_f| at every μ (within 1 %): μ does not set it, so the bounds are not
        // what to widen.
        let flat = TuneCurve {
            curve: vec![completed(10.0, figures(0.07074, Some(1.0))), completed(1e5, figures(0.0708, Some(2.0)))],
            ..curve
        };
        let spec = TuneSpec { max_uf: vec![0.05], ..spec };
        assert_eq!(
            flat.why_none(&spec, "tune.", (f64::INFINITY, 0.0)),
            "none of the 2 μ evaluated in tune.mu[0] completed with max |u_f,1| ≤ tune.max_uf[0] and a finite settle_t (max |u_f,1| is 0.07074 at every μ with a finite settle_t (from 10 to 100000), above tune.max_uf[0] = 0.05: the poles and the signals set it, not μ); raise tune.max_uf[0], or slow the scenario's channel and observer poles (an automatic design with an actuator limit, u_limit, chooses poles within it)"
        );
    }

    /// Channel 1's curve `curve`, nothing chosen, and a settling-time tuning over `bounds` with the
    /// limit `max_uf` on max |u_f,1|.
    fn settle_tuning(curve: Vec<TunePoint>, (bounds, max_uf): ([f64; 2], f64)) -> (TuneCurve, TuneSpec) {
        let spec = TuneSpec {
            objective: Objective::SettleT,
            bounds: vec![bounds],
            max_u: vec![f64::INFINITY],
            max_uf: vec![max_uf],
            points: 2,
            refine: 0,
        };
        (TuneCurve { channel: 0, curve, chosen: None, tie: None }, spec)
    }

    /// A completed run's figures with this max |u_f| and settling time.
    fn figures(max_uf: f64, settle_t: Option<f64>) -> ChannelFigures {
        ChannelFigures { tail_max_e: 1e-3, tail_rms_e: 1e-3, max_u: 1.0, max_uf, settle_t }
    }

    /// A completed evaluation at μ with these figures.
    fn completed(mu: f64, f: ChannelFigures) -> TunePoint {
        TunePoint { mu, objective: None, outcome: Outcome::Completed, reason: String::new(), figures: Some(f) }
    }

    /// Where no μ can meet a limit, the bounds are not what to widen: a steady state beyond the
    /// limit is said (slower poles cannot help either), and so is a figure that levels off toward
    /// the smallest μ.
    #[test]
    fn a_limit_no_mu_meets_is_not_met_by_wider_bounds() {
        let (flat, spec) = settle_tuning(
            vec![completed(10.0, figures(0.07074, Some(1.0))), completed(1e5, figures(0.0708, Some(2.0)))],
            ([10.0, 1e5], 0.05),
        );
        // A steady state beyond the limit is said instead of slower poles, which cannot help.
        let steady = flat.why_none(&spec, "tune.", (f64::INFINITY, 0.0706));
        assert!(steady.ends_with("raise tune.max_uf[0], or ask less of the loop (smaller references or disturbances): the steady state alone asks max |u_f,1| = 0.0706 for y = g (the design report's steady-state section), whatever μ and the poles"), "{steady}");
        // Channel 1's curve through these (μ, max |u_f,1|, settle_t), all completed.
        let through = |points: &[(f64, f64, f64)]| TuneCurve {
            curve: points.iter().map(|&(mu, uf, t)| completed(mu, figures(uf, Some(t)))).collect(),
            ..flat.clone()
        };
        // A figure that levels off toward the smallest μ is not widened toward it either.
        let levels = through(&[(10.0, 0.07074, 1.0), (100.0, 0.0708, 1.5), (1e5, 0.12, 2.0)]);
        let levels = levels.why_none(&spec, "tune.", (f64::INFINITY, 0.0));
        assert!(
            levels.contains("max |u_f,1| levels off at 0.07074 toward the smallest μ (at μ = 10 and 100)")
                && levels.contains("or slow the scenario's channel and observer poles")
                && !levels.contains("widen"),
            "{levels}"
        );
        // Also where the least lies a little above the smallest μ, within 1 % of them (a mixing
        // tank's 0.11200, 0.11200, 0.11199 at μ = 0.3, 0.7, 4, rising beyond).
        let dip = through(&[(0.3, 0.11200, 1.0), (0.7, 0.11200, 1.0), (4.0, 0.11199, 1.0), (53.0, 0.2608, 1.0)]);
        let dip = dip.why_none(&spec, "tune.", (f64::INFINITY, 0.0));
        assert!(
            dip.contains("levels off at 0.112 toward the smallest μ (at μ = 0.3 and 0.7)") && !dip.contains("widen"),
            "{dip}"
        );
        // Not where the least lies at the upper end, past a rise (the review's counterexample).
        let falling =
            through(&[(1.0, 0.101, 1.0), (3.0, 0.1009, 1.0), (10.0, 0.5, 1.0), (30.0, 0.3, 1.0), (100.0, 0.1, 1.0)]);
        let falling = falling.why_none(&spec, "tune.", (f64::INFINITY, 0.0));
        assert!(!falling.contains("levels off") && falling.contains("widen the bounds"), "{falling}");
        // Where the figure varies with μ too (the least at one μ): not "widen the bounds".
        let varied = through(&[(10.0, 0.0707, 1.0), (1e5, 0.09, 2.0)]);
        let varied = varied.why_none(&spec, "tune.", (f64::INFINITY, 0.0706));
        assert!(
            varied.contains("; raise tune.max_uf[0], or ask less of the loop") && !varied.contains("widen"),
            "{varied}"
        );
    }
}
