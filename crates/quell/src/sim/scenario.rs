//! A scenario's closed loop as its `[simulation]` says: the continuous loop (the delay equation),
//! or with a `sample_time` the sampled-data loop with the discrete controller (and `[noise]`), on the
//! scenario's true plant ([`Scenario::true_plant`]) with the design of its `[plant]`. `quell run`,
//! `quell.simulate` and every study run start here.

use super::{Integrator, Loop, Run, RunSettings};
use crate::design::Design;
use crate::scenario::Scenario;

impl RunSettings {
    /// The scenario's `[simulation]`: the sampled-data loop when it gives a `sample_time`, else the
    /// continuous loop (default divergence bound, step budget derived from the problem); either with
    /// the scenario's `[noise]` and the actuator of its `[truth]`.
    pub fn of(s: &Scenario) -> Self {
        let sim = &s.simulation;
        let mode = match sim.sample_time {
            Some(sample_time) => Loop::Sampled { sample_time },
            None => Loop::Continuous(Integrator { method: sim.method, ..Integrator::new(sim.rtol, sim.atol) }),
        };
        RunSettings {
            noise: s.noise.clone(),
            actuator: s.actuator.clone(),
            output_step_given: sim.output_step_given,
            precision: sim.precision,
            ..RunSettings::new(sim.t_end, sim.output_step, mode)
        }
    }
}

impl<'a> Run<'a> {
    /// Scenario `s` with its design `design` (of `s.plant`) on its true plant, with its reference,
    /// disturbance and settings ([`RunSettings::of`]), its states named as `[plant] states` names
    /// them ([`Run::state_names`]).
    pub fn of(s: &'a Scenario, design: &'a Design) -> Self {
        Run::new(design, &s.reference, &s.disturbance, RunSettings::of(s))
            .truth(s.true_plant())
            .state_names(s.names.states.as_deref())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::PAPER_EXAMPLE;
    use crate::sim::{default_max_steps, Integrator, Loop, Outcome, Peaks, RunStats, SimResult, Stats};
    use std::ops::ControlFlow;

    fn scenario(extra: &str) -> Scenario {
        let text = PAPER_EXAMPLE.replace("t_end = 100.0", "t_end = 2.0");
        Scenario::from_toml(&format!("{text}\n{extra}")).unwrap()
    }

    fn run(s: &Scenario, settings: &RunSettings) -> SimResult {
        Run::of(s, &s.design().unwrap()).settings(settings.clone()).simulate(|_| ControlFlow::Continue(())).unwrap()
    }

    fn sampled_at(s: &Scenario, sample_time: f64) -> RunSettings {
        RunSettings { mode: Loop::Sampled { sample_time }, ..RunSettings::of(s) }
    }

    #[test]
    fn the_scenario_chooses_the_loop_and_the_truth_is_simulated() {
        let nominal = scenario("");
        let continuous = run(&nominal, &RunSettings::of(&nominal));
        assert!(matches!(continuous.stats, RunStats::Continuous { .. }));
        // A sample time in [simulation] (here through the override) selects the sampled-data loop.
        let sampled = run(&nominal, &sampled_at(&nominal, 0.01));
        assert!(
            matches!(sampled.stats, RunStats::Sampled { controller_steps: 201, sample_time, .. } if sample_time == 0.01)
        );
        // [truth] changes the simulated plant: x0 = [1, 0, 0] moves y(0) = C x0 + Q ω(0) by C[:, 0] = [2, 2].
        let truth = scenario("[truth]\nx0 = [1.0, 0.0, 0.0]");
        for settings in [RunSettings::of(&truth), sampled_at(&truth, 0.01)] {
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
        // poles 6, the observer's 4, ω ≤ 2 rad/s, 1/β = 1), τ_min = 1 s, t_end = 100 s, at the
        // budget's own tolerance 1e-9 and an adaptation rate of 8.5/s, under 100 ρ (not stiff):
        // 10,000 + 100·(9·100 + 100/1) = 110,000.
        let integrator = Integrator::new(1e-9, 1e-9);
        let budget = default_max_steps(&Run::of(&s, &d), &integrator);
        assert_eq!(budget, 110_000);
        // With the history's memory at the 1 GiB cap, the step budget, the step size's underflow or
        // the divergence bound ends it (since the implicit steps' filtered error estimate, the
        // underflow at t = 40.3 s: the loop stiffens faster than its signals grow; since the implicit
        // solves run along packed rows, whose rounding differs, x_2 crossing 1e9 at t = 41.3 s).
        let capped = Integrator { max_history_bytes: Some(crate::sim::MAX_HISTORY_BYTES), ..integrator };
        let st = RunSettings { mode: Loop::Continuous(capped), ..RunSettings::of(&s) };
        let r = Run::of(&s, &d).settings(st).simulate(|_| ControlFlow::Continue(())).unwrap();
        let t = match r.outcome {
            Some(Outcome::TooManySteps { t, max_steps }) => {
                assert_eq!((max_steps, r.stats.steps()), (budget, budget + 1));
                t
            }
            Some(Outcome::StepSizeTooSmall { t } | Outcome::Diverged { t, .. }) => {
                assert!(r.stats.steps() <= budget, "{:?}", r.stats);
                t
            }
            other => panic!("{other:?}"),
        };
        // It ends where it turned stiff, with its samples up to then.
        assert!(t > 10.0 && t < 100.0 && r.t.last().is_some_and(|&l| l <= t && l > t - 0.2), "t = {t}");
        // By default the history's memory is bounded too, from the step budget: 8·110,000·τ_max/t_end
        // = 26,400 records of (8·27 + 9)·8 bytes, twice that for the ring's doubling. The runaway
        // crowds its steps into its last seconds and ends there, earlier.
        let r = Run::of(&s, &d).simulate(|_| ControlFlow::Continue(())).unwrap();
        let Some(Outcome::HistoryTooLarge { t: t_memory, max_bytes }) = r.outcome else { panic!("{:?}", r.outcome) };
        assert_eq!(max_bytes, 2 * 26_400 * (8 * 27 + 9) * 8);
        assert!(t_memory > 10.0 && t_memory <= t && r.stats.steps() < budget, "t = {t_memory}, {:?}", r.stats);
        // A budget given instead of the default; a sampled-data run has none.
        let mut st = RunSettings::of(&s);
        st.set_max_steps(Some(2_000)).unwrap();
        let r = Run::of(&s, &d).settings(st).simulate(|_| ControlFlow::Continue(())).unwrap();
        assert!(matches!(r.outcome, Some(Outcome::TooManySteps { max_steps: 2_000, .. })), "{:?}", r.outcome);
        let err = sampled_at(&s, 0.01).set_max_steps(Some(10)).unwrap_err();
        assert_eq!(err.key, "max_steps");
    }

    #[test]
    fn the_memory_budget_ends_a_run_whose_history_would_exceed_it() {
        let s = Scenario::from_toml(&format!("{PAPER_EXAMPLE}\n{DIVERGING_TRUTH}")).unwrap();
        let d = s.design().unwrap();
        let bytes = 2 << 20;
        let sim = &s.simulation;
        let integrator = Integrator { max_history_bytes: Some(bytes), ..Integrator::new(sim.rtol, sim.atol) };
        let st = RunSettings { mode: Loop::Continuous(integrator), ..RunSettings::of(&s) };
        let r = Run::of(&s, &d).settings(st).simulate(|_| ControlFlow::Continue(())).unwrap();
        let Some(Outcome::HistoryTooLarge { t, max_bytes }) = r.outcome else { panic!("{:?}", r.outcome) };
        assert!(max_bytes == bytes && t > 1.0 && t < 100.0, "t = {t}");
        // The history held at most half the budget's records (the ring may double): nd = 27 delayed
        // components of the paper's loop (ξ̂, x̂: 11; η̂: 16), 8·27 + 9 numbers a record.
        let RunStats::Continuous(Stats { max_history_len, .. }) = r.stats else { unreachable!() };
        let record = (8 * 27 + 9) * 8;
        assert!(max_history_len <= bytes / (2 * record) && max_history_len + 1 >= bytes / (2 * record));
    }

    #[test]
    fn runaway_bounds_end_a_continuous_run_at_the_first_signal_beyond_its_bound() {
        let s = scenario("");
        let st = RunSettings::of(&s);
        let full = run(&s, &st);
        let peaks = full.peaks;
        assert!(peaks.0.iter().all(|&p| p > 0.0 && p.is_finite()), "{peaks:?}");
        // Bounds at the run's own peaks let it complete; half of x̂'s peak ends it where x̂ first
        // exceeds that, with the value reported.
        let within = run(&s, &RunSettings { runaway: Some(peaks), ..st.clone() });
        assert_eq!(within.outcome, Some(Outcome::Completed));
        assert_eq!(within.y, full.y);
        let mut half = Peaks([f64::INFINITY; 4]);
        half.0[1] = 0.5 * peaks.0[1];
        let ended = run(&s, &RunSettings { runaway: Some(half), ..st });
        let Some(Outcome::Diverged { t, signal, value }) = ended.outcome else { panic!("{:?}", ended.outcome) };
        assert!(signal.starts_with("xhat") && value.abs() > half.0[1], "{signal} = {value}");
        assert!(t < 2.0 && ended.peaks.0[1] <= half.0[1], "t = {t}, recorded peaks {:?}", ended.peaks);
        assert_eq!(ended.y[..], full.y[..ended.y.len()], "the run is the same up to then");
    }
}
