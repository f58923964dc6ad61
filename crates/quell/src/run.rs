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
    /// continuous loop (default divergence bound, no step budget); either with the scenario's
    /// `[noise]` and the actuator of its `[truth]`.
    pub fn of(s: &Scenario) -> Self {
        let sim = &s.simulation;
        match sim.sample_time {
            Some(sample_time) => LoopSettings::sampled(s, sample_time),
            None => LoopSettings::Continuous(RunSettings {
                noise: s.noise.clone(),
                actuator: s.actuator.clone(),
                ..RunSettings::new(sim.t_end, sim.output_step, sim.rtol, sim.atol)
            }),
        }
    }

    /// Records the plant state x and the observer state x̂ too (in either loop), or not.
    pub fn record_states(&mut self, on: bool) {
        match self {
            LoopSettings::Continuous(st) => st.record_states = on,
            LoopSettings::Sampled(st) => st.record_states = on,
        }
    }

    /// The continuous loop's step budget (`None`: [`sim::default_max_steps`], derived from the
    /// problem). A sampled-data run takes t_end / sample_time controller steps, known before it
    /// starts; a budget for it is an error naming `max_steps`.
    pub fn set_max_steps(&mut self, max_steps: Option<usize>) -> Result<(), crate::settings::KeyError> {
        match (self, max_steps) {
            (LoopSettings::Continuous(st), _) => st.max_steps = max_steps,
            (LoopSettings::Sampled(_), None) => {}
            (LoopSettings::Sampled(st), Some(_)) => {
                return Err(crate::settings::KeyError::new(
                    "max_steps",
                    format!(
                        "a step budget applies to the continuous loop; this sampled-data run takes t_end / sample_time = {:.0} controller steps, known before it starts: leave max_steps out",
                        (st.t_end / st.sample_time).floor() + 1.0
                    ),
                ))
            }
        }
        Ok(())
    }

    /// The sampled-data loop at `sample_time` (in place of the scenario's), with its `[noise]` and
    /// actuator.
    pub fn sampled(s: &Scenario, sample_time: f64) -> Self {
        let sim = &s.simulation;
        LoopSettings::Sampled(SampledSettings {
            noise: s.noise.clone(),
            actuator: s.actuator.clone(),
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

    /// The paper's plant with A × 1.3 and τ_2 = 2.6 s as the true plant: the loop blows up.
    const DIVERGING_TRUTH: &str =
        "[truth]\nA = [[-4.16, -2.21, -3.9], [3.64, 1.69, 5.2], [0.39, 0.39, -0.65]]\ndelays = [1.0, 2.6]";

    #[test]
    fn the_default_step_budget_follows_the_problem_and_ends_a_runaway() {
        let s = Scenario::from_toml(&format!("{PAPER_EXAMPLE}\n{DIVERGING_TRUTH}")).unwrap();
        let d = s.design().unwrap();
        // ρ = 9 (the reference filter pole −9 is the fastest rate; |eig(1.3 A)| ≤ 3.9, the channel
        // poles 6, the observer's 4, ω ≤ 2 rad/s, 1/β = 1), τ_min = 1 s, t_end = 100 s:
        // 10,000 + 100·(9·100 + 100/1) = 110,000.
        let budget = sim::default_max_steps(&d, s.true_plant(), [&s.reference, &s.disturbance], 100.0);
        assert_eq!(budget, 110_000);
        let r = simulate(&s, &d, &LoopSettings::of(&s), |_| ControlFlow::Continue(())).unwrap();
        let Some(sim::Outcome::TooManySteps { t, max_steps }) = r.outcome else { panic!("{:?}", r.outcome) };
        assert_eq!((max_steps, r.stats.steps()), (budget, budget + 1));
        // It ends where it turned stiff, with its samples up to then.
        assert!(t > 10.0 && t < 100.0 && r.t.last().is_some_and(|&l| l <= t && l > t - 0.2), "t = {t}");
        // A budget given instead of the default; a sampled-data run has none.
        let mut st = LoopSettings::of(&s);
        st.set_max_steps(Some(2_000)).unwrap();
        let r = simulate(&s, &d, &st, |_| ControlFlow::Continue(())).unwrap();
        assert!(matches!(r.outcome, Some(sim::Outcome::TooManySteps { max_steps: 2_000, .. })), "{:?}", r.outcome);
        let err = LoopSettings::sampled(&s, 0.01).set_max_steps(Some(10)).unwrap_err();
        assert_eq!(err.key, "max_steps");
    }

    #[test]
    fn the_memory_budget_ends_a_run_whose_history_would_exceed_it() {
        let s = Scenario::from_toml(&format!("{PAPER_EXAMPLE}\n{DIVERGING_TRUTH}")).unwrap();
        let d = s.design().unwrap();
        let LoopSettings::Continuous(st) = LoopSettings::of(&s) else { unreachable!() };
        let bytes = 2 << 20;
        let st = RunSettings { max_history_bytes: bytes, ..st };
        let r = simulate(&s, &d, &LoopSettings::Continuous(st), |_| ControlFlow::Continue(())).unwrap();
        let Some(sim::Outcome::HistoryTooLarge { t, max_bytes }) = r.outcome else { panic!("{:?}", r.outcome) };
        assert!(max_bytes == bytes && t > 1.0 && t < 100.0, "t = {t}");
        // The history held at most half the budget's records (the ring may double): nd = 27 delayed
        // components of the paper's loop (ξ̂, x̂: 11; η̂: 16), 8·27 + 9 numbers a record.
        let RunStats::Continuous { max_history_len, .. } = r.stats else { unreachable!() };
        let record = (8 * 27 + 9) * 8;
        assert!(max_history_len <= bytes / (2 * record) && max_history_len + 1 >= bytes / (2 * record));
    }

    #[test]
    fn runaway_bounds_end_a_continuous_run_at_the_first_signal_beyond_its_bound() {
        let s = scenario("");
        let LoopSettings::Continuous(st) = LoopSettings::of(&s) else { unreachable!() };
        let full = run(&s, &LoopSettings::Continuous(st.clone()));
        let peaks = full.peaks;
        assert!(peaks.0.iter().all(|&p| p > 0.0 && p.is_finite()), "{peaks:?}");
        // Bounds at the run's own peaks let it complete; half of x̂'s peak ends it where x̂ first
        // exceeds that, with the value reported.
        let within = run(&s, &LoopSettings::Continuous(RunSettings { runaway: Some(peaks), ..st.clone() }));
        assert_eq!(within.outcome, Some(sim::Outcome::Completed));
        assert_eq!(within.y, full.y);
        let mut half = Peaks([f64::INFINITY; 4]);
        half.0[1] = 0.5 * peaks.0[1];
        let ended = run(&s, &LoopSettings::Continuous(RunSettings { runaway: Some(half), ..st.clone() }));
        let Some(sim::Outcome::Diverged { t, signal, value }) = ended.outcome else { panic!("{:?}", ended.outcome) };
        assert!(signal.starts_with("x_hat[") && value.abs() > half.0[1], "{signal} = {value}");
        assert!(t < 2.0 && ended.peaks.0[1] <= half.0[1], "t = {t}, recorded peaks {:?}", ended.peaks);
        assert_eq!(ended.y[..], full.y[..ended.y.len()], "the run is the same up to then");
    }
}
