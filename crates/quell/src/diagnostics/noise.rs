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
    let tail = |r: &SimResult, i: usize| {
        let (from, to) = (r.tail_from().unwrap_or(0.0), r.t.last().copied().unwrap_or(0.0));
        r.max_abs_error(i, from, to).unwrap_or(f64::NAN)
    };
    let channels: Vec<(usize, String)> = (missed.iter().copied().filter(|&i| tail_within_bound(clean, i)))
        .map(|i| {
            (i, format!(
                "channel {}'s tail max|e| = {:.2e} is the measurement noise's: {:.2e} without [noise], within its bound ({:.0} % of its scale); the advice below is the noise-free run's, since none on the design's poles, μ or t_end reduces the noise's part (its level and bandwidth, and how much of it the observer and the adaptive law pass, set it)",
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
