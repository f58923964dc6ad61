//! Scenario values at the edges of floating point (1e±300 entries, poles, gains, signals): each
//! gives an error of the right kind, naming its key, or a design (and run) with its property. The
//! decisions are tabled in docs/errors.md ("Values at the edges of floating point"); in short,
//! plant entries beyond 1e150 and rates spanning more than 1/√ε, signal amplitudes and biases
//! beyond 1e150 and sampled adaptation steps T_s μ beyond 1e150 are refused, tiny plant entries are
//! decided like zeros, and μ, delays and frequencies are accepted, with the loop reporting what it
//! can and cannot run.
#![allow(non_snake_case)]

use std::ops::ControlFlow;

use quell::design::{controllability, RATE_SPAN};
use quell::nalgebra::Complex;
use quell::scenario::{load_and_design, LoadError, PAPER_EXAMPLE};
use quell::sim::{Outcome, Run, RunSettings};
use quell::{Design, DesignError, Scenario};

/// The paper's example with one textual replacement.
fn edited(from: &str, to: &str) -> String {
    assert!(PAPER_EXAMPLE.contains(from), "no `{from}` in the paper example");
    PAPER_EXAMPLE.replacen(from, to, 1)
}

/// Loads and designs the paper's example with one edit.
fn load(from: &str, to: &str) -> Result<(Scenario, Design), LoadError> {
    load_and_design(&edited(from, to))
}

/// The scenario error's key (the file is refused before any design).
fn scenario_key(from: &str, to: &str) -> String {
    match load(from, to) {
        Err(LoadError::Scenario(e)) => e.key,
        other => panic!("{to}: expected a scenario error, got {:?}", other.map(|_| ()).map_err(|e| e.to_string())),
    }
}

/// The design error.
fn design_error(from: &str, to: &str) -> DesignError {
    match load(from, to) {
        Err(LoadError::Design(e)) => e,
        other => panic!("{to}: expected a design error, got {:?}", other.map(|_| ()).map_err(|e| e.to_string())),
    }
}

/// A pole outside the span of rates, on `key`, with the range the other lists leave it.
fn out_of_span(e: &DesignError, key: &str, pole: Complex<f64>) -> bool {
    matches!(e, DesignError::PoleOutOfSpan { key: k, pole: p, min_decay, max_magnitude }
        if k == key && *p == pole && (pole.norm() > *max_magnitude || -pole.re < *min_decay)
            && max_magnitude / min_decay <= RATE_SPAN * RATE_SPAN)
}

const CHANNEL: &str = "channel_poles = [[-6.0, -2.0], [-4.0]]";
const REF_FILTER: &str = "reference_filter_poles = [[-1.0, -6.0], [-9.0]]";
const DIST_FILTER: &str = "disturbance_filter_poles = [[-1.0, -3.0], [-1.0, -2.0, -3.0]]";
const L_LINE: &str = "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619], [2.7762, -1.1783]]";

#[test]
fn plant_entries_beyond_1e150_are_refused_naming_the_entry() {
    // Were "(A, B) is not controllable … tolerance inf" (A, B), "not observable" (C), "rank D = 1"
    // (D) and a design (Q).
    for (from, to, key) in [
        ("A = [[-3.2,", "A = [[-3.2e300,", "plant.A[0][0]"),
        ("A = [[-3.2, -1.7,", "A = [[-3.2, -1.7e300,", "plant.A[0][1]"),
        ("B = [[-2.0,", "B = [[-2.0e300,", "plant.B[0][0]"),
        ("C = [[2.0, 2.0, 0.0]", "C = [[2.0e300, 2.0, 0.0]", "plant.C[0][0]"),
        ("D = [[1.0,", "D = [[1.0e300,", "plant.D[0][0]"),
        ("Q = [[1.0,", "Q = [[1.0e300,", "plant.Q[0][0]"),
        ("x0 = [0.0,", "x0 = [1e151,", "plant.x0[0]"),
    ] {
        assert_eq!(scenario_key(from, to), key, "{to}");
    }
}

#[test]
fn tiny_plant_entries_are_decided_as_zeros_would_be() {
    // a11 = −3.2e-300 ≈ 0: the paper's L no longer stabilizes A − LC; the eigenvalues in the error
    // sum to trace(A − LC) with a11 = 0, computed here directly.
    let e = design_error("A = [[-3.2,", "A = [[-3.2e-300,");
    let DesignError::ObserverUnstable { key: "design.observer_gain", eigenvalues } = &e else { panic!("{e}") };
    let (_, paper) = load_and_design(PAPER_EXAMPLE).unwrap();
    let p = paper.plant();
    let trace = (&p.A - paper.L() * &p.C).trace() + 3.2;
    let sum: f64 = eigenvalues.iter().map(|z| z.re).sum();
    assert!((sum - trace).abs() < 1e-9 && eigenvalues.iter().any(|z| z.re > 0.0), "{e}");
    // b11 = −2e-300: rank 2 of 3, as for b11 = 0 exactly.
    let e = design_error("B = [[-2.0,", "B = [[-2.0e-300,");
    assert!(matches!(e, DesignError::Uncontrollable { rank: 2, n: 3, .. }), "{e}");
    let mut B = p.B.clone();
    B[(0, 0)] = 0.0;
    assert_eq!(controllability(&p.A, &B).unwrap().rank, 2);
    // c11 = 2e-300: c_1 = [0, 2, 0] gives c_1 B = [4, −2] ≠ 0, so σ_1 = 1 and channel 1 takes 1 pole.
    let e = design_error("C = [[2.0, 2.0, 0.0]", "C = [[2.0e-300, 2.0, 0.0]");
    assert!(matches!(e, DesignError::ChannelPoleCount { channel: 0, sigma: 1, got: 2, .. }), "{e}");
    // d11 = 1e-300: a design, with N D = L_ω (eq. (20)).
    let (_, d) = load("D = [[1.0,", "D = [[1.0e-300,").unwrap();
    let residual = (d.N() * &d.plant().D - d.L_w()).norm();
    assert!(residual <= 1e-12 * (1.0 + d.N().norm() * d.plant().D.norm()), "‖N D − L_ω‖ = {residual:e}");
}

#[test]
fn an_observer_gain_that_overflows_is_an_overflow_error() {
    // Was "faer's QR iteration did not converge, which should not happen for finite input".
    let e = design_error("observer_gain = [[-8.0988,", "observer_gain = [[-8.0988e300,");
    assert!(
        matches!(e, DesignError::Eigenvalues { key: "design.observer_gain", of: "A − LC", reason }
            if reason.contains("give a smaller design.observer_gain")),
        "{e}"
    );
}

#[test]
fn poles_and_beta_beyond_the_span_of_rates_are_refused() {
    let c = |re: f64, im: f64| Complex::new(re, im);
    for (from, to, key, pole) in [
        (CHANNEL, "channel_poles = [[-6.0e300, -2.0], [-4.0]]", "design.channel_poles[0]", c(-6e300, 0.0)),
        (CHANNEL, "channel_poles = [[-6.0e-300, -2.0], [-4.0]]", "design.channel_poles[0]", c(-6e-300, 0.0)),
        (CHANNEL, "channel_poles = [[[-1e-300, 1e300]], [-4.0]]", "design.channel_poles[0]", c(-1e-300, -1e300)),
        (CHANNEL, "channel_poles = [[-6.0e150, -2.0e150], [-4.0e300]]", "design.channel_poles[1]", c(-4e300, 0.0)),
        (
            REF_FILTER,
            "reference_filter_poles = [[-1.0e300, -6.0e300], [-9.0]]",
            "design.reference_filter_poles[0]",
            c(-6e300, 0.0),
        ),
        (
            REF_FILTER,
            "reference_filter_poles = [[-1.0e-300, -6.0e-300], [-9.0]]",
            "design.reference_filter_poles[0]",
            c(-1e-300, 0.0),
        ),
        (
            DIST_FILTER,
            "disturbance_filter_poles = [[-1.0e300, -3.0], [-1.0e300, -2.0e300, -3.0e300]]",
            "design.disturbance_filter_poles[1]",
            c(-3e300, 0.0),
        ),
        (L_LINE, "observer_poles = [-1e300, -2.0, -3.0]", "design.observer_poles", c(-1e300, 0.0)),
        (L_LINE, "observer_poles = [-1e-300, -2e-300, -3e-300]", "design.observer_poles", c(-1e-300, 0.0)),
        (L_LINE, "observer_poles = [-1e300, -2e300, -3e300]", "design.observer_poles", c(-3e300, 0.0)),
        (L_LINE, "observer_poles = [[-1.0, 1e300], -3.0]", "design.observer_poles", c(-1.0, -1e300)),
        (L_LINE, "observer_poles = [[-1e-300, 1e-300], -3.0]", "design.observer_poles", c(-1e-300, -1e-300)),
        (L_LINE, "observer_poles = [-1e150, -1e-150, -1.0]", "design.observer_poles", c(-1e-150, 0.0)),
    ] {
        let e = design_error(from, to);
        assert!(out_of_span(&e, key, pole), "{to}: {e}");
    }
    for beta in [1e-300, 1e300] {
        let e = design_error("beta = 1.0", &format!("beta = {beta:e}"));
        // Given the paper's poles (|p| from 1 to 9), 1/β must lie in [9/2^26, 2^26], so β in [2^-26, 2^26/9].
        assert!(
            matches!(e, DesignError::BetaOutOfSpan { value, min, max }
                if value == beta && min == 1.0 / RATE_SPAN && max == RATE_SPAN / 9.0),
            "{e}"
        );
    }
    // Just inside the span: a channel pole 2^26 times the slowest decay rate (1, of the filters and
    // 1/β) is designed.
    assert!(load(CHANNEL, &format!("channel_poles = [[-{RATE_SPAN:e}, -2.0], [-4.0]]")).is_ok());
    assert!(load(CHANNEL, &format!("channel_poles = [[-{:e}, -2.0], [-4.0]]", 1.01 * RATE_SPAN)).is_err());
}

#[test]
fn observer_poles_inside_the_rounding_margin_are_judged_by_their_refined_values() {
    // A double integrator with a large coupling (‖A − LC‖_F ≈ 1e6): observer poles at −1e-3 and
    // −2e-3 lie inside the Hurwitz margin √ε·‖A − LC‖_F ≈ 1.5e-2, which grows with ‖A − LC‖. They
    // were refused ("not Hurwitz") although placed and verified; refined in twice the working
    // precision they are −1e-3 and −2e-3 (the requested poles: the independent side, to 1e-9
    // absolute, far below their distance 1e-3 from the imaginary axis), so the design stands.
    let text = "[plant]\nA = [[0.0, 1e6], [0.0, 0.0]]\nB = [[0.0], [1.0]]\nC = [[1.0, 0.0]]\ndelays = [0.0]\n\
                [design]\nobserver_poles = [-1e-3, -2e-3]\nchannel_poles = [[-1e-3, -2e-3]]\n\
                reference_filter_poles = [[-1e-3]]\nmu = [1.0]\nbeta = 1e3\n\
                [reference]\ncomponents = [{ bias = 1.0 }]\n";
    let (_, d) = load_and_design(text).unwrap_or_else(|e| panic!("{e}"));
    let eigs = d.observer_eigenvalues();
    for (got, want) in eigs.iter().zip([-2e-3, -1e-3]) {
        assert!((got.re - want).abs() < 1e-9 && got.im.abs() < 1e-9, "{eigs:?}");
    }
}

#[test]
fn a_triple_observer_pole_is_refused() {
    // Three copies of −2 with rank C = 2 would need a Jordan block (eigenvalues only accurate to
    // ≈ (ε‖A − LC‖)^(1/2)): refused naming the pole, its multiplicity and the rank.
    let e = design_error(L_LINE, "observer_poles = [-2.0, -2.0, -2.0]");
    let want = quell::PlaceError::Multiplicity { pole: Complex::new(-2.0, 0.0), multiplicity: 3, rank: 2 };
    assert_eq!(e, DesignError::ObserverPoles(want));
    let docs = include_str!("../../../docs/errors.md");
    assert!(docs.contains(&e.to_string()), "docs/errors.md does not show: {e}");
}

/// The continuous and the sampled-data (T_s = 1 ms) loop over 10 s; the continuous one with at most
/// 10⁵ steps so that a stiff loop ends (TooManySteps) instead of crawling.
fn runs(s: &Scenario, d: &Design) -> (Outcome, Result<quell::sim::SimResult, quell::sim::SimError>) {
    let mut settings = RunSettings::continuous(10.0, 0.1, 1e-9, 1e-9);
    settings.set_max_steps(Some(100_000)).unwrap();
    let cont =
        Run::new(d, &s.reference, &s.disturbance, settings.clone()).simulate(|_| ControlFlow::Continue(())).unwrap();
    let sampled = Run::new(d, &s.reference, &s.disturbance, RunSettings::sampled(10.0, 0.1, 0.001))
        .simulate(|_| ControlFlow::Continue(()));
    (cont.outcome.unwrap(), sampled)
}

#[test]
fn huge_mu_is_designed_and_the_sampled_controller_refuses_it() {
    // μ = 1e300: the design is accepted (μ alone is not a rate; μ·tr Ω is), the continuous law is
    // infinitely stiff and the integrator says so. The sampled law (I + cΩ)δ = c(Y − Ωη̂) is
    // nonexpansive for every μ ≥ 0, but with c = T_s μ = 1e297 the product cΩ overflows (adaptation
    // off): Controller::new refuses T_s μ > 1e150.
    let (s, d) = load("mu = [20.0, 30.0]", "mu = [1e300, 30.0]").unwrap();
    assert_eq!(d.mu(), &[1e300, 30.0]);
    let (cont, sampled) = runs(&s, &d);
    assert!(matches!(cont, Outcome::StepSizeTooSmall { .. } | Outcome::TooManySteps { .. }), "{cont:?}");
    assert!(matches!(
        sampled,
        Err(quell::sim::SimError::Controller(quell::ControllerError::AdaptationStepTooLarge { channel: 0, .. }))
    ));
    // μ = 1e150 (T_s μ = 1e147): the implicit step sets η̂ to the least-squares fit of the regressor
    // seen so far, as an infinitely fast law would; barely excited just after the delay, that fit
    // is huge, and the run ends at the divergence bound naming η̂, every recorded value finite
    // (no step rounds to NaN: pivots lost to rounding leave their direction still).
    let (s, d) = load("mu = [20.0, 30.0]", "mu = [1e150, 30.0]").unwrap();
    let r = runs(&s, &d).1.unwrap();
    match &r.outcome {
        Some(Outcome::Diverged { signal, value, .. }) => {
            assert!(signal.starts_with("eta1_") && value.is_finite(), "{signal} = {value}")
        }
        other => assert_eq!(other, &Some(Outcome::Completed)),
    }
    assert!(r.eta.iter().chain(&r.u_f).all(|v| v.is_finite()));
}

#[test]
fn signals_at_the_edges_are_refused_or_run() {
    // An amplitude or bias beyond 1e150 is bad input, naming its key (was a Diverged run, exit 1).
    assert_eq!(
        scenario_key("amplitude = 3.0, frequency = 2.0", "amplitude = 3e300, frequency = 2.0"),
        "reference.components[0].harmonics[0].amplitude"
    );
    assert_eq!(scenario_key("{ bias = 2.0 }", "{ bias = -2e151 }"), "reference.components[1].bias");
    assert_eq!(scenario_key("bias = 1.0, harmonics", "bias = 1e200, harmonics"), "disturbance.components[1].bias");
    // The design does not depend on the signals.
    let (_, paper) = load_and_design(PAPER_EXAMPLE).unwrap();
    for to in ["amplitude = 1e150, frequency = 2e300", "amplitude = 3e-300, frequency = 2e-300"] {
        let (s, d) = load("amplitude = 3.0, frequency = 2.0", to).unwrap();
        assert_eq!(d.K(), paper.K(), "{to}");
        if to.contains("2e300") {
            // 2e300 rad/s would need ω·t_end/π = 6e300 integrator steps: an input error naming the
            // frequency (it ran into the history's memory budget); the sampled loop's regressor
            // passes the divergence bound at its first output sample.
            let settings = RunSettings::continuous(10.0, 0.1, 1e-9, 1e-9);
            let cont = Run::new(&d, &s.reference, &s.disturbance, settings).simulate(|_| ControlFlow::Continue(()));
            let key = "reference.components[0].harmonics[0].frequency";
            assert!(matches!(&cont, Err(quell::sim::SimError::Input(e)) if e.key == key), "{:?}", cont.err());
            let sampled = Run::new(&d, &s.reference, &s.disturbance, RunSettings::sampled(10.0, 0.1, 0.001))
                .simulate(|_| ControlFlow::Continue(()))
                .unwrap();
            assert!(matches!(sampled.outcome, Some(Outcome::Diverged { t, .. }) if t <= 0.1), "{:?}", sampled.outcome);
        } else {
            let (cont, sampled) = runs(&s, &d);
            let sampled = sampled.unwrap().outcome.unwrap();
            assert_eq!((cont, sampled), (Outcome::Completed, Outcome::Completed));
        }
    }
}

#[test]
fn delays_at_the_edges_are_accepted_and_the_loop_says_what_it_can_run() {
    // τ_1 = 1e300 s: the input never arrives within the horizon; the continuous loop runs (channel 1
    // open), a sampled-data controller cannot hold 1e303 samples.
    let (s, d) = load("delays = [1.0, 3.0]", "delays = [1e300, 3.0]").unwrap();
    let (cont, sampled) = runs(&s, &d);
    assert_eq!(cont, Outcome::Completed);
    assert!(matches!(
        sampled,
        Err(quell::sim::SimError::Controller(quell::ControllerError::DelayTooLong { channel: 0, .. }))
    ));
    // τ_1 = 1e-300 s: 0 samples at T_s = 1 ms, so the sampled loop runs; the integrator's steps are
    // at most min τ long, so the continuous loop would need 1e301 steps and a history of 3e300
    // records: an input error (was StepSizeTooSmall at t = 0, a failed run), naming the least τ
    // that passes every check of the run (the step limit's 1e-9 had been named first, and followed
    // it met the history's).
    let (s, d) = load("delays = [1.0, 3.0]", "delays = [1e-300, 3.0]").unwrap();
    let settings = RunSettings::continuous(10.0, 0.1, 1e-9, 1e-9);
    match Run::new(&d, &s.reference, &s.disturbance, settings.clone()).simulate(|_| ControlFlow::Continue(())) {
        Err(quell::sim::SimError::Input(e)) => {
            assert_eq!(e.key, "plant.delays[0]");
            let tau = e.message.split("expected 0 (no delay) or τ ≥ ").nth(1).and_then(|r| r.split(' ').next());
            let tau: f64 = tau.and_then(|t| t.parse().ok()).unwrap_or_else(|| panic!("{e}"));
            let (s, d) = load("delays = [1.0, 3.0]", &format!("delays = [{tau:e}, 3.0]")).unwrap();
            let run = Run::new(&d, &s.reference, &s.disturbance, settings.clone());
            assert!(run.check().is_ok(), "τ = {tau:e}: {:?}", run.check());
        }
        other => panic!("{:?}", other.map(|r| r.outcome)),
    }
    let sampled = Run::new(&d, &s.reference, &s.disturbance, RunSettings::sampled(10.0, 0.1, 0.001))
        .simulate(|_| ControlFlow::Continue(()));
    assert_eq!(sampled.unwrap().outcome, Some(Outcome::Completed));
    // At the limit (t_end / τ = 1e10) the continuous loop starts.
    let (s, d) = load("delays = [1.0, 3.0]", "delays = [1e-9, 3.0]").unwrap();
    let mut settings = RunSettings::continuous(10.0, 0.1, 1e-9, 1e-9);
    settings.set_max_steps(Some(10)).unwrap();
    let r =
        Run::new(&d, &s.reference, &s.disturbance, settings.clone()).simulate(|_| ControlFlow::Continue(())).unwrap();
    assert!(matches!(r.outcome, Some(Outcome::TooManySteps { .. })), "{:?}", r.outcome);
}

#[test]
fn horizons_at_the_edges_are_refused_with_a_short_suggestion() {
    // t_end = 1e300 printed a 294-digit output_step; a shorter horizon is offered too (a user who
    // gave t_end had been asked only for another output_step).
    for (from, to, suggestion) in [
        ("t_end = 100.0", "t_end = 1e300", "1.01e293, or a shorter simulation.t_end"),
        ("output_step = 0.1", "output_step = 1e-300", "1e-5, or a shorter simulation.t_end"),
    ] {
        let e = match load(from, to) {
            Err(LoadError::Scenario(e)) => e,
            other => panic!("{to}: {:?}", other.map(|_| ())),
        };
        assert_eq!(e.key, "simulation.output_step");
        assert!(e.message.ends_with(&format!("choose output_step ≥ {suggestion}")), "{e}");
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
    let e = quell::Controller::new(&d, 0.001).unwrap_err();
    assert!(matches!(e, quell::ControllerError::DelayTooLong { channel: 0, .. }), "{e}");
    // And a sample time far below the delays, likewise.
    let d = Scenario::from_toml(PAPER_EXAMPLE).unwrap().design().unwrap();
    assert!(quell::Controller::new(&d, 1e-300).is_err());
}

/// The delay lines are budgeted together, in bytes: the SI supply vessel (three channels, q = 12:
/// rows of 13 numbers) with its 1 s delays at T_s = 0.2 µs needs 5e6 + 1 rows a channel, each
/// within the 1e7 a line may hold, but 1.45 GiB together; the error proposes a sample time at
/// which they fit (checked here from the rows, not the message), and the controller is built
/// there.
#[test]
fn the_delay_lines_are_budgeted_together_in_bytes() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/supply-vessel.toml")).unwrap();
    let d = Scenario::from_toml(&text).unwrap().design().unwrap();
    let e = quell::Controller::new(&d, 2e-7).unwrap_err();
    let quell::ControllerError::DelayLinesTooLarge { rows, width, at_least, nearest, .. } = e else { panic!("{e}") };
    assert_eq!((rows, width), (3.0 * (5e6 + 1.0), 13));
    assert!(e.to_string().contains("(1.453 GiB); at most 1 GiB are kept"), "{e}");
    let docs = include_str!("../../../docs/errors.md");
    assert!(docs.contains(&e.to_string()), "docs/errors.md does not show: {e}");
    let budget = quell::controller::MAX_DELAY_LINE_BYTES;
    let rows_at = |t: f64| 3.0 * (1.0 / t + 1.0);
    assert!(rows_at(at_least) * 13.0 * 8.0 <= budget && rows_at(0.99 * at_least) * 13.0 * 8.0 > budget, "{at_least}");
    // 1 s is a whole number of samples of 1 / round(1 / at_least), and the one offered is such a
    // sample time, no shorter than at_least, that works as printed.
    let fits = 1.0 / (1.0 / at_least).floor();
    assert!(quell::Controller::new(&d, fits).is_ok(), "{fits}");
    // The shortest round sample time (1, 2, 2.5 or 5 × 10^e) from at_least = 2.91e-7 on that divides
    // 1 s: 5e-7 (it was 1/3436426 = 2.910000099e-7).
    let nearest = nearest.unwrap();
    assert_eq!(nearest, 5e-7);
    assert!(nearest >= at_least && (1.0 / nearest - (1.0 / nearest).round()).abs() < 1e-9 / nearest, "{nearest}");
    let printed: f64 = e.to_string().rsplit("such as ").next().unwrap().trim_end_matches(" s").parse().unwrap();
    assert!(quell::Controller::new(&d, printed).is_ok(), "{printed}");
}

/// An internal-model filter whose polynomial ∏(s − p_j) has a coefficient beyond 1e150 is refused
/// naming the list: 44 poles near −1e7 overflowed it to ∞, and the design report and every run
/// then hung in an eigenvalue iteration on the non-finite companion matrix, deaf to Ctrl-C. With
/// 22 such poles the largest coefficient is the constant term ∏|p_j| (each |p_j| ≫ the binomials),
/// here computed by hand.
#[test]
fn a_filter_polynomial_beyond_1e150_is_refused() {
    let poles = |count: usize| (0..count).map(|i| -1e7 * (1.0 + 0.01 * i as f64)).collect::<Vec<f64>>();
    let list = |p: &[f64]| p.iter().map(|v| format!("{v:?}")).collect::<Vec<_>>().join(", ");
    for count in [22, 44] {
        let p = poles(count);
        let e = design_error(REF_FILTER, &format!("reference_filter_poles = [[-1.0, -6.0], [{}]]", list(&p)));
        assert!(
            matches!(&e, DesignError::FilterTooLarge { key, count: c, .. } if key == "design.reference_filter_poles[1]" && *c == count),
            "{e:?}"
        );
        let constant: f64 = p.iter().map(|v| v.abs()).product();
        let DesignError::FilterTooLarge { coefficient, .. } = e else { unreachable!() };
        if count == 22 {
            assert!(
                constant > 1e150 && constant.is_finite() && (coefficient / constant - 1.0).abs() < 1e-12,
                "{coefficient} {constant}"
            );
        } else {
            assert!(coefficient.is_infinite() && constant.is_infinite());
            assert!(
                e.to_string().contains("over its 44 poles has a coefficient of magnitude inf, beyond 1e150"),
                "{e}"
            );
        }
    }
}
