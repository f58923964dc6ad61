//! Scenario values at the edges of floating point (1e±300 entries, poles, gains, signals) must give
//! a design or a clear error, quickly: no panic and no endless eigenvalue/SVD iteration.

use std::time::{Duration, Instant};

use quell::scenario::PAPER_EXAMPLE;
use quell::Scenario;

/// The paper's example with one textual replacement.
fn edited(from: &str, to: &str) -> String {
    assert!(PAPER_EXAMPLE.contains(from), "no `{from}` in the paper example");
    PAPER_EXAMPLE.replacen(from, to, 1)
}

/// Parses and designs; returns the error message if any. Panics if it takes over a second.
fn outcome(text: &str) -> Result<(), String> {
    let started = Instant::now();
    let r = Scenario::from_toml(text)
        .map_err(|e| e.to_string())
        .and_then(|s| s.design().map(|_| ()).map_err(|e| e.to_string()));
    let took = started.elapsed();
    assert!(took < Duration::from_secs(1), "took {took:?}: {r:?}");
    r
}

const EDITS: &[(&str, &str)] = &[
    ("A = [[-3.2,", "A = [[-3.2e300,"),
    ("A = [[-3.2, -1.7,", "A = [[-3.2, -1.7e300,"),
    ("A = [[-3.2,", "A = [[-3.2e-300,"),
    ("B = [[-2.0,", "B = [[-2.0e300,"),
    ("B = [[-2.0,", "B = [[-2.0e-300,"),
    ("C = [[2.0, 2.0, 0.0]", "C = [[2.0e300, 2.0, 0.0]"),
    ("C = [[2.0, 2.0, 0.0]", "C = [[2.0e-300, 2.0, 0.0]"),
    ("D = [[1.0,", "D = [[1.0e300,"),
    ("D = [[1.0,", "D = [[1.0e-300,"),
    ("Q = [[1.0,", "Q = [[1.0e300,"),
    ("observer_gain = [[-8.0988,", "observer_gain = [[-8.0988e300,"),
    ("channel_poles = [[-6.0, -2.0], [-4.0]]", "channel_poles = [[-6.0e300, -2.0], [-4.0]]"),
    ("channel_poles = [[-6.0, -2.0], [-4.0]]", "channel_poles = [[-6.0e-300, -2.0], [-4.0]]"),
    ("channel_poles = [[-6.0, -2.0], [-4.0]]", "channel_poles = [[[-1e-300, 1e300]], [-4.0]]"),
    ("channel_poles = [[-6.0, -2.0], [-4.0]]", "channel_poles = [[-6.0e150, -2.0e150], [-4.0e300]]"),
    ("reference_filter_poles = [[-1.0, -6.0], [-9.0]]", "reference_filter_poles = [[-1.0e300, -6.0e300], [-9.0]]"),
    ("reference_filter_poles = [[-1.0, -6.0], [-9.0]]", "reference_filter_poles = [[-1.0e-300, -6.0e-300], [-9.0]]"),
    (
        "disturbance_filter_poles = [[-1.0, -3.0], [-1.0, -2.0, -3.0]]",
        "disturbance_filter_poles = [[-1.0e300, -3.0], [-1.0e300, -2.0e300, -3.0e300]]",
    ),
    ("mu = [20.0, 30.0]", "mu = [1e300, 30.0]"),
    ("beta = 1.0", "beta = 1e-300"),
    ("beta = 1.0", "beta = 1e300"),
    ("amplitude = 3.0, frequency = 2.0", "amplitude = 3e300, frequency = 2e300"),
    ("amplitude = 3.0, frequency = 2.0", "amplitude = 3e-300, frequency = 2e-300"),
    ("delays = [1.0, 3.0]", "delays = [1e300, 3.0]"),
    ("delays = [1.0, 3.0]", "delays = [1e-300, 3.0]"),
    ("t_end = 100.0", "t_end = 1e300"),
    ("output_step = 0.1", "output_step = 1e-300"),
];

#[test]
fn extreme_values_give_a_design_or_an_error_quickly() {
    for (from, to) in EDITS {
        let r = outcome(&edited(from, to));
        println!("{to}: {r:?}");
    }
}

#[test]
fn extreme_observer_poles() {
    let observer = |poles: &str| {
        edited(
            "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619], [2.7762, -1.1783]]",
            &format!("observer_poles = {poles}"),
        )
    };
    for poles in [
        "[-1e300, -2.0, -3.0]",
        "[-1e-300, -2e-300, -3e-300]",
        "[-1e300, -2e300, -3e300]",
        "[[-1.0, 1e300], -3.0]",
        "[[-1e-300, 1e-300], -3.0]",
        "[-2.0, -2.0, -2.0]",
        "[-1e150, -1e-150, -1.0]",
    ] {
        let r = outcome(&observer(poles));
        println!("observer_poles = {poles}: {r:?}");
    }
}

#[test]
fn design_checks_a_plant_built_field_by_field() {
    // Plant's fields are public, so Design::new checks the shapes again instead of panicking.
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let mut plant = s.plant.clone();
    plant.C = quell::nalgebra::DMatrix::zeros(3, 3);
    let e = quell::Design::new(&plant, &s.design).unwrap_err().to_string();
    assert!(e.starts_with("plant.C: expected a 2×3 matrix"), "{e}");
    let mut plant = s.plant.clone();
    plant.delays.pop();
    let e = quell::Design::new(&plant, &s.design).unwrap_err().to_string();
    assert!(e.starts_with("plant.delays: expected 2 entries"), "{e}");
    let mut plant = s.plant.clone();
    plant.A[(1, 1)] = f64::NAN;
    let e = quell::Design::new(&plant, &s.design).unwrap_err().to_string();
    assert!(e.starts_with("plant.A[1][1]: expected a finite number"), "{e}");
}

#[test]
fn design_rejects_a_non_finite_observer_gain() {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let mut spec = s.design.clone();
    let quell::ObserverChoice::Gain(gain) = &mut spec.observer else { panic!("the paper gives L") };
    gain[(2, 1)] = f64::INFINITY;
    let e = quell::Design::new(&s.plant, &spec).unwrap_err().to_string();
    assert!(e.starts_with("design.observer_gain[2][1]: expected a finite number, found inf"), "{e}");
}

#[test]
fn decoupler_with_too_few_pole_lists_is_an_error() {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let p = &s.plant;
    let r = quell::design::falb_wolovich(&p.A, &p.B, &p.C, &s.design.channel_poles[..1]);
    assert!(matches!(r, Err(quell::DesignError::Count { expected: 2, got: 1, .. })));
}

#[test]
fn huge_delay_at_a_short_sample_time_is_an_error() {
    // 1e300 s of delay at T_s = 1 ms would need a delay line of 1e303 rows.
    let s = Scenario::from_toml(&edited("delays = [1.0, 3.0]", "delays = [1e300, 3.0]")).unwrap();
    let d = s.design().unwrap();
    let e = quell::Controller::new(&d, 0.001).unwrap_err().to_string();
    assert!(e.contains("a delay line holds at most"), "{e}");
    // And a sample time far below the delays, likewise.
    let d = Scenario::from_toml(PAPER_EXAMPLE).unwrap().design().unwrap();
    assert!(quell::Controller::new(&d, 1e-300).is_err());
}

#[test]
fn delay_below_rounding_level_stops_the_solver() {
    // Steps are at most min τ long; a delay of 1e-300 s would never advance t. The solver refuses
    // at t = 0 instead of looping.
    use quell::sim::{simulate, Outcome, RunSettings};
    let s = Scenario::from_toml(&edited("delays = [1.0, 3.0]", "delays = [1e-300, 3.0]")).unwrap();
    let d = s.design().unwrap();
    let started = Instant::now();
    let r = simulate(&d, &s.reference, &s.disturbance, &RunSettings::new(1.0, 0.1, 1e-9, 1e-9), |_| {
        std::ops::ControlFlow::Continue(())
    })
    .unwrap();
    assert!(started.elapsed() < Duration::from_secs(1));
    assert_eq!(r.outcome, Some(Outcome::StepSizeTooSmall { t: 0.0 }));
}
