//! A scenario's closed loop as its `[simulation]` says: the continuous loop (the delay equation),
//! or with a `sample_time` the sampled-data loop with the discrete controller (and `[noise]`), on the
//! scenario's true plant ([`Scenario::true_plant`]) with the design of its `[plant]`. `quell run`,
//! `quell.simulate` and every study run go through [`simulate`]. This module sits above both
//! [`crate::scenario`] and [`crate::sim`], which do not know each other.

use std::ops::ControlFlow;

use crate::design::Design;
use crate::scenario::Scenario;
use crate::sim::{self, RunSettings, SampledSettings, SimError, SimResult};

/// Which loop a run uses, with its settings.
#[derive(Debug, Clone, PartialEq)]
pub enum LoopSettings {
    Continuous(RunSettings),
    Sampled(SampledSettings),
}

impl LoopSettings {
    /// The scenario's `[simulation]`: the sampled-data loop when it gives a `sample_time`, else the
    /// continuous loop (default divergence bound, no step budget).
    pub fn of(s: &Scenario) -> Self {
        let sim = &s.simulation;
        match sim.sample_time {
            Some(sample_time) => LoopSettings::sampled(s, sample_time),
            None => LoopSettings::Continuous(RunSettings::new(sim.t_end, sim.output_step, sim.rtol, sim.atol)),
        }
    }

    /// Records the plant state x and the observer state x̂ too (in either loop), or not.
    pub fn record_states(&mut self, on: bool) {
        match self {
            LoopSettings::Continuous(st) => st.record_states = on,
            LoopSettings::Sampled(st) => st.record_states = on,
        }
    }

    /// The sampled-data loop at `sample_time` (in place of the scenario's), with its `[noise]`.
    pub fn sampled(s: &Scenario, sample_time: f64) -> Self {
        let sim = &s.simulation;
        LoopSettings::Sampled(SampledSettings {
            noise: s.noise.clone(),
            ..SampledSettings::new(sim.t_end, sim.output_step, sample_time)
        })
    }
}

/// Simulates scenario `s` with its design `design` (of `s.plant`) in the loop `settings` names, on
/// the true plant; `on_progress` as for [`sim::simulate`].
pub fn simulate(
    s: &Scenario,
    design: &Design,
    settings: &LoopSettings,
    on_progress: impl FnMut(f64) -> ControlFlow<()>,
) -> Result<SimResult, SimError> {
    let (truth, g, w) = (s.true_plant(), &s.reference, &s.disturbance);
    match settings {
        LoopSettings::Continuous(st) => sim::simulate_with_truth(design, truth, g, w, st, on_progress),
        LoopSettings::Sampled(st) => sim::simulate_sampled_with_truth(design, truth, g, w, st, on_progress),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::PAPER_EXAMPLE;
    use crate::sim::{Peaks, RunStats};

    fn scenario(extra: &str) -> Scenario {
        let text = PAPER_EXAMPLE.replace("t_end = 100.0", "t_end = 2.0");
        Scenario::from_toml(&format!("{text}\n{extra}")).unwrap()
    }

    fn run(s: &Scenario, settings: &LoopSettings) -> SimResult {
        simulate(s, &s.design().unwrap(), settings, |_| ControlFlow::Continue(())).unwrap()
    }

    #[test]
    fn the_scenario_chooses_the_loop_and_the_truth_is_simulated() {
        let nominal = scenario("");
        let continuous = run(&nominal, &LoopSettings::of(&nominal));
        assert!(matches!(continuous.stats, RunStats::Continuous { .. }));
        // A sample time in [simulation] (here through the override) selects the sampled-data loop.
        let sampled = run(&nominal, &LoopSettings::sampled(&nominal, 0.01));
        assert!(
            matches!(sampled.stats, RunStats::Sampled { controller_steps: 201, sample_time } if sample_time == 0.01)
        );
        // [truth] changes the simulated plant: x0 = [1, 0, 0] moves y(0) = C x0 + Q ω(0) by C[:, 0] = [2, 2].
        let truth = scenario("[truth]\nx0 = [1.0, 0.0, 0.0]");
        for settings in [LoopSettings::of(&truth), LoopSettings::sampled(&truth, 0.01)] {
            let (a, b) = (run(&nominal, &settings), run(&truth, &settings));
            assert_eq!([b.y[0] - a.y[0], b.y[1] - a.y[1]], [2.0, 2.0], "{settings:?}");
        }
    }

    #[test]
    fn runaway_bounds_end_a_continuous_run_at_the_first_signal_beyond_its_bound() {
        let s = scenario("");
        let LoopSettings::Continuous(st) = LoopSettings::of(&s) else { unreachable!() };
        let full = run(&s, &LoopSettings::Continuous(st));
        let peaks = full.peaks;
        assert!(peaks.0.iter().all(|&p| p > 0.0 && p.is_finite()), "{peaks:?}");
        // Bounds at the run's own peaks let it complete; half of x̂'s peak ends it where x̂ first
        // exceeds that, with the value reported.
        let within = run(&s, &LoopSettings::Continuous(RunSettings { runaway: Some(peaks), ..st }));
        assert_eq!(within.outcome, Some(sim::Outcome::Completed));
        assert_eq!(within.y, full.y);
        let mut half = Peaks([f64::INFINITY; 4]);
        half.0[1] = 0.5 * peaks.0[1];
        let ended = run(&s, &LoopSettings::Continuous(RunSettings { runaway: Some(half), ..st }));
        let Some(sim::Outcome::Diverged { t, signal, value }) = ended.outcome else { panic!("{:?}", ended.outcome) };
        assert!(signal.starts_with("x_hat[") && value.abs() > half.0[1], "{signal} = {value}");
        assert!(t < 2.0 && ended.peaks.0[1] <= half.0[1], "t = {t}, recorded peaks {:?}", ended.peaks);
        assert_eq!(ended.y[..], full.y[..ended.y.len()], "the run is the same up to then");
    }
}
