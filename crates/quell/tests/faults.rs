//! Faults during a continuous run end it with an [`Outcome`] that names the time (and, for
//! divergence, the signal), and the result keeps every sample computed before.

use std::ops::ControlFlow;

use quell::scenario::PAPER_EXAMPLE;
use quell::sim::{Outcome, Run, RunSettings};
use quell::Scenario;

#[test]
fn divergence_bound_stops_the_continuous_loop() {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = s.design().unwrap();
    // |g_2| = 2 alone exceeds a bound of 1 on the internal-model states soon after the start.
    let settings = RunSettings { divergence_bound: 1.0, ..RunSettings::continuous(100.0, 0.1, 1e-9, 1e-9) };
    let r = Run::new(&d, &s.reference, &s.disturbance, settings).simulate(|_| ControlFlow::Continue(())).unwrap();
    let Some(Outcome::Diverged { t, signal, value }) = r.outcome.clone() else {
        panic!("expected divergence, got {:?}", r.outcome);
    };
    assert!(t > 0.0 && t < 100.0, "t = {t}");
    assert!(value.abs() > 1.0 && !signal.is_empty(), "{signal} = {value}");
    // Named by its column of signals.csv (x1, xhat2, eta1_3; ξ̂ as xihat2), counted from 1.
    let column = signal.split(' ').next().unwrap_or_default();
    let stem = column.trim_end_matches(|c: char| c.is_ascii_digit() || c == '_');
    let stems = quell::sim::WATCHED.map(|(stem, _)| stem);
    let index = &column[stem.len()..];
    assert!(stems.contains(&stem) && !index.is_empty() && !index.starts_with('0'), "signal not named: {signal}");
    // Every sample before t was kept; the divergent one was not.
    assert!(!r.is_empty());
    assert!(r.t.last().is_some_and(|&last| last < t && last >= t - 0.1 - 1e-9));
    assert_eq!(r.y.len(), r.len() * r.m);
}

#[test]
fn a_nan_divergence_bound_is_refused() {
    // A bound of NaN would make every comparison false; it is refused, naming the setting (that a
    // non-finite state counts as divergence is `tests/sim_inputs.rs`).
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = s.design().unwrap();
    let settings = RunSettings { divergence_bound: f64::NAN, ..RunSettings::continuous(1.0, 0.1, 1e-9, 1e-9) };
    let e = Run::new(&d, &s.reference, &s.disturbance, settings).simulate(|_| ControlFlow::Continue(())).unwrap_err();
    assert!(e.to_string().starts_with("divergence_bound: expected a bound > 0"), "{e}");
}

#[test]
fn step_size_underflow_ends_the_run_with_the_time() {
    // μ_1 = 1e300 makes the adaptive law infinitely stiff: no step size meets the tolerances and
    // the solver must give up (not loop) and say when. (Tolerances below rounding level, which did
    // the same, are refused.)
    let fast = PAPER_EXAMPLE.replace("mu = [20.0, 30.0]", "mu = [1e300, 30.0]");
    let s = Scenario::from_toml(&fast).unwrap();
    let d = s.design().unwrap();
    let settings = RunSettings::continuous(10.0, 0.1, 1e-9, 1e-9);
    let r = Run::new(&d, &s.reference, &s.disturbance, settings).simulate(|_| ControlFlow::Continue(())).unwrap();
    let Some(Outcome::StepSizeTooSmall { t }) = r.outcome else { panic!("{:?}", r.outcome) };
    assert!((0.0..10.0).contains(&t), "t = {t}");
    // The samples up to then are kept: t = 0, 0.1, … ≤ t (η̂_1 moves from t = 1 s, the first delay).
    assert_eq!(r.len(), (t / 0.1 + 1e-9).floor() as usize + 1, "t = {t}");
    assert!(r.t.last().is_some_and(|&last| last <= t));
}

#[test]
fn interruption_keeps_the_samples_so_far() {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = s.design().unwrap();
    let settings = RunSettings::continuous(100.0, 0.1, 1e-9, 1e-9);
    let r = Run::new(&d, &s.reference, &s.disturbance, settings)
        .simulate(|t| if t >= 5.0 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) })
        .unwrap();
    assert!(matches!(r.outcome, Some(Outcome::Interrupted { t }) if (t - 5.0).abs() < 1e-9), "{:?}", r.outcome);
    assert_eq!(r.len(), 51);
}
