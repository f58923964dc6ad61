//! When a channel settles: the one definition that run summaries (`quell run`, `summary.json`,
//! Python), studies (`runs.csv`) and `quell tune` share.
//!
//! Channel i is *settled at* t_k when |e_i(t_j)| stays within its band for every recorded t_j ≥ t_k
//! up to the end of the run. A run that only enters the band in its last [`LATE_FRACTION`] of the
//! horizon has not shown that it stays there: its settling time is empty, with the reason.

use serde::{Deserialize, Serialize};

use super::divergence::beyond;
use super::result::max_or_nan;
use crate::settings::TimeUnit;

/// The part of the horizon at the end of a run where entering the band does not count as settling.
pub const LATE_FRACTION: f64 = 0.05;

/// The settling band of channel i: |e_i| ≤ max(relative · max_t |g_i(t)|, absolute); for a
/// reference that is 0 throughout (regulation), relative · max_t |e_i(t)| in its place.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Settle {
    pub relative: f64,
    pub absolute: f64,
}

impl Default for Settle {
    /// 2 % of the reference's peak, the textbook settling band.
    fn default() -> Self {
        Settle { relative: 0.02, absolute: 0.0 }
    }
}

impl Settle {
    /// The band for a channel of scale `scale` ([`crate::sim::SimResult::scale`]: its reference's
    /// peak, or a regulated output's error peak): max(relative · scale, absolute). A NaN scale (a
    /// NaN in g) makes the band NaN, so that nothing settles (`f64::max` would drop the NaN).
    pub fn band(&self, scale: f64) -> f64 {
        max_or_nan(self.relative * scale, self.absolute)
    }
}

/// How a channel's error met its band.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum Settling {
    /// Within the band from `t` to the end, and that stretch is longer than the last
    /// [`LATE_FRACTION`] of the horizon.
    Settled { t: f64 },
    /// Outside the band (or NaN) at the last sample: never settled.
    NotSettled,
    /// Within the band from `t` to the end, but only in the last [`LATE_FRACTION`] of the horizon.
    Late { t: f64 },
}

impl Settling {
    /// The settling time, `None` unless [`Settling::Settled`].
    pub fn time(&self) -> Option<f64> {
        match *self {
            Settling::Settled { t } => Some(t),
            _ => None,
        }
    }

    /// Why there is no settling time, times in `unit`; `None` when settled.
    pub fn reason(&self, unit: TimeUnit) -> Option<String> {
        match *self {
            Settling::Settled { .. } => None,
            Settling::NotSettled => Some("not settled: outside the band at the end of the run".into()),
            Settling::Late { t } => Some(format!(
                "not settled: enters the band at t = {} {unit} only in the last {:.0} % of the horizon (too late to tell an error that settles from one passing through)",
                crate::settings::fmt_time(t),
                100.0 * LATE_FRACTION
            )),
        }
    }
}

/// The settling of one channel from its samples e(t_k) and its band: the first t_k after which
/// |e| ≤ band at every sample, judged by [`Settling`]'s rules. No samples: not settled.
pub fn settling(t: &[f64], e: &[f64], band: f64) -> Settling {
    let (Some(&t0), Some(&t1)) = (t.first(), t.last()) else {
        return Settling::NotSettled;
    };
    let k = match e.iter().rposition(|&v| beyond(v, band)) {
        None => 0,
        Some(k) if k + 1 >= t.len() => return Settling::NotSettled,
        Some(k) => k + 1,
    };
    let ts = t[k];
    if t1 - ts < LATE_FRACTION * (t1 - t0) || (k > 0 && k + 1 == t.len()) {
        Settling::Late { t: ts }
    } else {
        Settling::Settled { t: ts }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize, t_end: f64) -> Vec<f64> {
        (0..=n).map(|k| t_end * k as f64 / n as f64).collect()
    }

    #[test]
    fn a_decaying_error_settles_where_the_closed_form_says() {
        // e = exp(−t/2) on [0, 60] at 0.1 s; band 0.02 (2 % of a unit reference): |e| ≤ 0.02 from
        // t = 2 ln 50 = 7.824 s, so the first sample inside is t = 7.9 s.
        let t = grid(600, 60.0);
        let e: Vec<f64> = t.iter().map(|t| (-t / 2.0).exp()).collect();
        let band = Settle::default().band(1.0);
        assert_eq!(band, 0.02);
        let s = settling(&t, &e, band);
        assert!(matches!(s, Settling::Settled { t } if (t - 7.9).abs() < 1e-12), "{s:?}");
        assert_eq!(s.reason(TimeUnit::Seconds), None);
    }

    #[test]
    fn an_error_oscillating_across_the_band_does_not_settle_at_its_last_samples() {
        // 0.035·sin(3(t − 60)) around a 0.02 band on a 60 s run at 0.1 s: the last three samples
        // (|e| = 0.0198, 0.0103, 0) lie inside the band, so a rule that looked only at the last samples would report 59.8 s;
        // no stretch of the last 5 % stays inside.
        let t = grid(600, 60.0);
        let e: Vec<f64> = t.iter().map(|t| 0.035 * (3.0 * (t - 60.0)).sin()).collect();
        let s = settling(&t, &e, 0.02);
        assert!(matches!(s, Settling::Late { t } if (t - 59.8).abs() < 1e-9), "{s:?}");
        assert!(s.time().is_none() && s.reason(TimeUnit::Seconds).unwrap().contains("last 5 %"), "{s:?}");
        // Outside the band at the end: not settled.
        let outside: Vec<f64> = e.iter().map(|v| v + 1.0).collect();
        assert_eq!(settling(&t, &outside, 0.02), Settling::NotSettled);
    }

    #[test]
    fn the_late_limit_is_five_percent_of_the_horizon() {
        // A step into the band at t_s on [0, 100] with samples every 0.5 s: settled when the
        // stretch inside lasts at least 5 s.
        let t = grid(200, 100.0);
        for (ts, settled) in [(94.5, true), (95.0, true), (95.5, false)] {
            let e: Vec<f64> = t.iter().map(|&t| if t < ts { 1.0 } else { 0.0 }).collect();
            let s = settling(&t, &e, 0.1);
            assert_eq!(s.time().is_some(), settled, "t_s = {ts}: {s:?}");
            assert!(matches!(s, Settling::Settled { t } | Settling::Late { t } if t == ts), "{s:?}");
        }
    }

    #[test]
    fn a_regulated_output_settles_within_two_percent_of_its_errors_peak() {
        // g = 0 throughout, scale the error's peak 0.5: e = 0.5·exp(−t) on [0, 20]: band
        // 0.02 · 0.5 = 0.01, met from t = ln 50 = 3.912 (first sample 4.0).
        let t = grid(200, 20.0);
        let e: Vec<f64> = t.iter().map(|t| 0.5 * (-t).exp()).collect();
        let band = Settle::default().band(0.5);
        assert_eq!(band, 0.01);
        assert!(matches!(settling(&t, &e, band), Settling::Settled { t } if (t - 4.0).abs() < 1e-12));
        // An absolute band still holds alone when it is wider.
        assert_eq!(Settle { relative: 0.02, absolute: 0.1 }.band(0.5), 0.1);
    }

    #[test]
    fn nan_and_empty_never_settle_and_within_from_the_start_settles_at_t0() {
        let t = grid(10, 1.0);
        assert_eq!(settling(&[], &[], 1.0), Settling::NotSettled);
        assert_eq!(settling(&t, &[0.0; 11], 0.1), Settling::Settled { t: 0.0 });
        let mut e = vec![0.0; 11];
        e[10] = f64::NAN;
        assert_eq!(settling(&t, &e, 0.1), Settling::NotSettled);
        assert!(Settle::default().band(f64::NAN).is_nan());
        assert_eq!(settling(&t, &[0.0; 11], f64::NAN), Settling::NotSettled);
        // One sample only: the stretch is the whole (zero-length) horizon.
        assert_eq!(settling(&[0.0], &[0.0], 0.1), Settling::Settled { t: 0.0 });
    }
}
