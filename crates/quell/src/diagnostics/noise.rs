//! A run under measurement noise against the same scenario without it: whose tail is it?
//!
//! Under `[noise]` a tail that misses its bound may be the noise's alone, which no advice on the
//! design (the observer's poles, μ, t_end) reduces: an active suspension read with 0.5 mm of
//! band-limited noise ended at 0.95 mm, was told to move its observer poles to the zeros of
//! (A, D, C), and following that made its noise-free tail 2,400× larger and its force 40 % higher.
//! So such a run is run again without the noise ([`noise_advice`]).

use super::{tail_within_bound, TAIL_BOUND};
use crate::design::Design;
use crate::sim::{Outcome, SimResult};

/// A scenario without its `[noise]`, and its run ([`super::sampled::side_run`]).
pub(crate) type Quiet = (crate::Scenario, SimResult);

/// Scenario `s` without its `[noise]` and its run, where that completes or diverges; `None` for a
/// scenario without noise. The noise line and the sampled comparison share it.
pub(crate) fn without_noise(s: &crate::Scenario, design: &Design) -> Option<Quiet> {
    s.noise.as_ref()?;
    let quiet = crate::Scenario { noise: None, ..s.clone() };
    let r = super::sampled::side_run(&quiet, design).ok()?;
    matches!(r.outcome, None | Some(Outcome::Completed | Outcome::Diverged { .. })).then_some((quiet, r))
}

/// For a completed run of scenario `s` under `[noise]` whose tail misses its bound on some channel
/// ([`TAIL_BOUND`] of its scale), the same run without the noise (a continuous loop within
/// [`super::sampled::COMPARISON_STEPS`] steps); one line per channel whose tail is within the bound
/// there, with both tails, naming it the noise's. Empty otherwise.
pub fn noise_advice(s: &crate::Scenario, design: &Design, result: &SimResult) -> Vec<String> {
    let missed = (0..result.m).any(|i| !tail_within_bound(result, i));
    let quiet = if missed { without_noise(s, design) } else { None };
    noise_tail(result, quiet.as_ref()).map_or_else(Vec::new, |n| n.channels.into_iter().map(|(_, line)| line).collect())
}

/// What [`noise_advice`] found: the channels (0-based) whose tail is the noise's, each with its
/// line, and whether they are all the channels that missed their bound.
pub(crate) struct NoiseTail {
    pub channels: Vec<(usize, String)>,
    pub all: bool,
}

/// [`noise_advice`] on `result` against `quiet`, the same run without the noise.
pub(crate) fn noise_tail(result: &SimResult, quiet: Option<&Quiet>) -> Option<NoiseTail> {
    let (_, clean) = quiet?;
    if !matches!(result.outcome, None | Some(Outcome::Completed))
        || !matches!(clean.outcome, None | Some(Outcome::Completed))
    {
        return None;
    }
    let missed: Vec<usize> = (0..result.m).filter(|&i| !tail_within_bound(result, i)).collect();
    let tail = |r: &SimResult, i: usize| r.tail_max_abs_error(i).unwrap_or(f64::NAN);
    let channels: Vec<(usize, String)> = (missed.iter().copied().filter(|&i| tail_within_bound(clean, i)))
        .map(|i| {
            (i, format!(
                "channel {}'s tail max|e| = {:.2e} is the measurement noise's: {:.2e} without [noise], within its bound ({:.0} % of its scale); any advice on this channel is the noise-free run's (none where that run needs none), since none on the design's poles, μ or t_end reduces the noise's part (its level and bandwidth, and how much of it the observer and the adaptive law pass, set it)",
                i + 1,
                tail(result, i),
                tail(clean, i),
                100.0 * TAIL_BOUND
            ))
        })
        .collect();
    let all = channels.len() == missed.len();
    (!channels.is_empty()).then_some(NoiseTail { channels, all })
}

/// From this ratio of a noisy run's max|u_f,i| to the same run's without the noise, the noise is
/// named as what drives the plant input (`diagnose_run`'s advice).
pub const NOISE_EFFORT: f64 = 3.0;

/// Per input whose max|u_f,i| under `[noise]` is [`NOISE_EFFORT`] or more times its peak in the
/// same run without it (`quiet`), both completed: the noise drives the actuator though the tails
/// may meet their bounds, which no tail-based advice sees. A two-link arm read with 1e-4 rad of
/// encoder noise peaked at 34.5 N·m against 2.5 without, and its run said nothing (helper tryout,
/// 2026-12-07); the automatic design for its sample time passed the same noise at 2.0.
pub(crate) fn noise_effort(result: &SimResult, quiet: Option<&Quiet>) -> Vec<String> {
    let Some((_, clean)) = quiet else { return Vec::new() };
    let completed = |r: &SimResult| matches!(r.outcome, None | Some(Outcome::Completed));
    if !completed(result) || !completed(clean) {
        return Vec::new();
    }
    let sampled = matches!(result.stats, crate::sim::RunStats::Sampled { .. });
    (0..result.m)
        .filter_map(|i| {
            let (noisy, without) = (result.max_uf(i), clean.max_uf(i));
            (noisy >= NOISE_EFFORT * without && without > 0.0).then(|| {
                format!(
                    "the measurement noise drives u_f[{}] to {}, {}× its peak without [noise] ({}): the observer and the channels pass it to the input through gains that grow with their speed (L, K); slower design.observer_poles and design.channel_poles, nearer the signals' rates, pass less of it{}, or reduce the noise (a sensor filter, noise.std)",
                    i + 1,
                    crate::settings::fmt_4(noisy),
                    crate::settings::fmt_ratio(noisy / without),
                    crate::settings::fmt_4(without),
                    if sampled { " (the automatic design chooses them for a scenario's simulation.sample_time)" } else { "" }
                )
            })
        })
        .collect()
}
