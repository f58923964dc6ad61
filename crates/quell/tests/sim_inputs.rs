//! The loops check what they are given (signals, horizons, tolerances, sample time, noise, the
//! divergence bound) and return an error naming the key instead of panicking or running with a
//! missing component; both loops judge divergence on the same signals with the same bound; each
//! loop reports the statistics it has.

use std::ops::ControlFlow;

mod common;

use quell::scenario::PAPER_EXAMPLE;
use quell::sim::{MeasurementNoise, Outcome, Run, RunSettings, RunStats, SimError, Stats};
use quell::{Design, Scenario, Signal};

fn paper() -> (Scenario, Design) {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = s.design().unwrap();
    (s, d)
}

fn go(_: f64) -> ControlFlow<()> {
    ControlFlow::Continue(())
}

/// The key an input error names.
fn key(e: SimError) -> String {
    match e {
        SimError::Input(e) => e.key,
        other => panic!("expected an input error, got {other}"),
    }
}

fn continuous_key(g: &Signal, w: &Signal, settings: RunSettings) -> String {
    let (_, d) = paper();
    key(Run::new(&d, g, w, settings).simulate(go).expect_err("an input error"))
}

fn sampled_key(g: &Signal, w: &Signal, settings: RunSettings) -> String {
    let (_, d) = paper();
    key(Run::new(&d, g, w, settings).simulate(go).expect_err("an input error"))
}

#[test]
fn wrong_number_of_signal_components_is_an_error_in_both_loops() {
    let (s, _) = paper();
    let short = Signal { components: s.reference.components[..1].to_vec() };
    let long = Signal { components: [s.disturbance.components.clone(), s.disturbance.components.clone()].concat() };
    let cont = RunSettings::continuous(1.0, 0.1, 1e-9, 1e-9);
    let samp = RunSettings::sampled(1.0, 0.1, 1e-3);
    assert_eq!(continuous_key(&short, &s.disturbance, cont.clone()), "reference.components");
    assert_eq!(sampled_key(&short, &s.disturbance, samp.clone()), "reference.components");
    assert_eq!(continuous_key(&s.reference, &long, cont), "disturbance.components");
    assert_eq!(sampled_key(&s.reference, &long, samp.clone()), "disturbance.components");
    let (_, d) = paper();
    let e = Run::new(&d, &short, &s.disturbance, samp).simulate(go).unwrap_err().to_string();
    assert_eq!(e, "reference.components: expected 2 components (one per output, m = 2 columns of plant.B), found 1");
}

#[test]
fn non_finite_signal_parameters_are_errors() {
    let (s, _) = paper();
    let mut g = s.reference.clone();
    g.components[0].harmonics[0].amplitude = f64::INFINITY;
    let k = continuous_key(&g, &s.disturbance, RunSettings::continuous(1.0, 0.1, 1e-9, 1e-9));
    assert_eq!(k, "reference.components[0].harmonics[0].amplitude");
    let mut w = s.disturbance.clone();
    w.components[1].bias = f64::NAN;
    assert_eq!(sampled_key(&s.reference, &w, RunSettings::sampled(1.0, 0.1, 1e-3)), "disturbance.components[1].bias");
}

/// A continuous horizon shorter than the integrator resolves is refused by its key: t_end = 1e-15
/// (and down to the least subnormal) had ended as "the solver's step size underflowed", exit 1
/// (helper tryout, 2026-12-05); from 1e-10 on it runs.
#[test]
fn a_horizon_below_the_integrators_resolution_is_refused() {
    let (s, d) = paper();
    let (g, w) = (&s.reference, &s.disturbance);
    let settings = |t: f64| RunSettings::continuous(t, t, 1e-9, 1e-9);
    for t in [1e-15, 1e-300, 5e-324, 9.9e-11] {
        assert_eq!(continuous_key(g, w, settings(t)), "simulation.t_end", "t_end = {t:e}");
    }
    let e = Run::new(&d, g, w, settings(1e-15)).simulate(go).unwrap_err().to_string();
    assert!(
        e.starts_with("simulation.t_end: expected t_end ≥ 1e-10 s in the continuous loop (its integrator resolves time to 1e-14 of max(1, |t|), so a shorter horizon leaves too few distinguishable steps), found 1e-15; "),
        "{e}"
    );
    let r = Run::new(&d, g, w, settings(1e-10)).simulate(go).unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
}

/// A shortest delay whose steps cannot hold the longest delay's history within the run's memory
/// budget is refused by its key before the run: the paper's loop with delays [1e-6, 3] needs 3e6
/// records of 1,800 bytes (twice that with the ring's doubling), 10 GB against the 1 GiB cap. (A
/// CSTR with [1e-7, 0.1] min had run 2.2 s into 808 MB and failed at the cap, blamed on a blow-up:
/// helper tryout, 2026-12-05.) The τ it offers passes.
#[test]
fn a_delay_too_short_for_the_history_of_the_longest_is_refused_by_its_key() {
    let (s, _) = paper();
    let with_budget = |d: [f64; 2], max_steps: Option<usize>| {
        let text = PAPER_EXAMPLE.replace("delays = [1.0, 3.0]", &format!("delays = [{:?}, {:?}]", d[0], d[1]));
        let s = Scenario::from_toml(&text).unwrap();
        let d = s.design().unwrap();
        let mut settings = RunSettings { t_end: 5.0, output_step: 1.0, ..RunSettings::of(&s) };
        settings.set_max_steps(max_steps).unwrap();
        // The checks alone (Run::check): a run at τ = 1e-5 would take 5e5 steps.
        Run::new(&d, &s.reference, &s.disturbance, settings).check().map_err(|e| e.to_string())
    };
    let with_delays = |d: [f64; 2]| with_budget(d, None);
    let e = with_delays([1e-6, 3.0]).unwrap_err();
    // 2 · 3/1e-6 records · 8·(8·27 + 9) bytes, in MiB.
    let mib = (2.0 * 3e6 * 1800.0 / 1048576.0f64).round();
    let head = format!("plant.delays[0]: τ = 1e-6 s caps the integrator's steps at τ while the delay history holds the last τ_max = 3 s: at least 3.0e6 records of 1800 bytes, {mib} MB with the ring's doubling, beyond the run's memory budget of 1024 MB; expected 0 (no delay) or τ ≥ ");
    assert!(e.starts_with(&head), "{e}\n{head}");
    let offered: f64 = e[head.len()..].split(' ').next().unwrap().parse().unwrap();
    assert!(with_delays([offered, 3.0]).is_ok(), "τ = {offered}");
    assert!(with_delays([0.5 * offered, 3.0]).is_err());
    // A step budget given below the 3e6 records ends the run first: it may start.
    assert!(with_budget([1e-6, 3.0], Some(1000)).is_ok());
    let _ = s;
}

#[test]
fn horizons_and_tolerances_are_checked() {
    let (s, _) = paper();
    let (g, w) = (&s.reference, &s.disturbance);
    let cont =
        |t_end, output_step, rtol, atol| continuous_key(g, w, RunSettings::continuous(t_end, output_step, rtol, atol));
    for t_end in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert_eq!(cont(t_end, 0.1, 1e-9, 1e-9), "simulation.t_end", "t_end = {t_end}");
    }
    for h in [0.0, -0.1, f64::NAN, 2.0] {
        assert_eq!(cont(1.0, h, 1e-9, 1e-9), "simulation.output_step", "output_step = {h}");
    }
    assert_eq!(cont(1e9, 1e-3, 1e-9, 1e-9), "simulation.output_step", "1e12 rows");
    for tol in [0.0, -1e-9, f64::NAN, f64::INFINITY] {
        assert_eq!(cont(1.0, 0.1, tol, 1e-9), "simulation.rtol", "rtol = {tol}");
        assert_eq!(cont(1.0, 0.1, 1e-9, tol), "simulation.atol", "atol = {tol}");
    }
    // rtol below 100 ε cannot be met in double precision, and from 1 on it allows errors as large
    // as the signals; atol has no such floor (a tiny atol is pure relative control, in units only
    // the user knows).
    for rtol in [1e-300, 1e-30, 2.2e-14, 1.0, 10.0] {
        assert_eq!(cont(1.0, 0.1, rtol, 1e-9), "simulation.rtol", "rtol = {rtol}");
    }
    assert_eq!(quell::settings::MIN_RTOL, 100.0 * f64::EPSILON);
    // The bound as the message prints it (2.22045e-14, rounded up) is accepted.
    for (rtol, atol) in [(quell::settings::MIN_RTOL, 1e-9), (2.22045e-14, 1e-9), (0.5, 1e-9), (1e-9, 1e-300)] {
        let r = Run::new(&paper().1, g, w, RunSettings::continuous(1e-3, 1e-3, rtol, atol)).simulate(go);
        assert!(r.is_ok(), "rtol = {rtol}, atol = {atol}: {:?}", r.err());
    }
    // Too small an atol fails the run at the first delay's breakpoint (1 s), and its explanation
    // names atol beside rtol (it blamed rtol alone, and loosening rtol did not help).
    let r = Run::new(&paper().1, g, w, RunSettings::continuous(1.5, 0.5, 1e-9, 1e-100)).simulate(go).unwrap();
    let why = r.outcome.as_ref().and_then(|o| o.explain("max_steps", quell::TimeUnit::default())).unwrap();
    assert!(why.starts_with("the solver's step size underflowed at t = 1 s"), "{why}");
    assert!(why.contains("or simulation.atol is too small for a signal that leaves zero"), "{why}");
    let samp = |t_end, h, ts| sampled_key(g, w, RunSettings::sampled(t_end, h, ts));
    assert_eq!(samp(f64::NAN, 0.1, 1e-3), "simulation.t_end");
    assert_eq!(samp(1.0, 2.0, 1e-3), "simulation.output_step");
    assert_eq!(samp(1.0, 0.1, f64::NAN), "simulation.sample_time");
    assert_eq!(samp(1e3, 0.1, 1e-12), "simulation.sample_time", "1e15 controller steps");
    // A sample time beyond t_end is named as such (it was sent to the output step, whose offer of
    // 1000 s then broke the horizon).
    assert_eq!(samp(100.0, 0.1, 1000.0), "simulation.sample_time", "T_s > t_end");
    assert_eq!(samp(1.0, 0.15, 0.1), "simulation.output_step", "1.5 samples per output");
}

/// An output step that is not a whole number of samples names both ways out, and each of them runs:
/// the paper's delays (1 s, 3 s) are whole at T = 0.04 s, where 0.1 s is 2.5 samples; the multiple
/// offered is 0.12 s (3 samples) and the sample time 0.025 s (whole in 1 s and 3 s as well; the
/// longest divisor below 0.04 s, 0.1/3 s, has no short decimal form and its rows would not print
/// as 0.1, 0.2, …).
#[test]
fn an_output_step_between_samples_gets_fixes_that_run() {
    let (s, d) = paper();
    let (g, w) = (&s.reference, &s.disturbance);
    let err = Run::new(&d, g, w, RunSettings::sampled(1.0, 0.1, 0.04)).simulate(go).expect_err("2.5 samples");
    let message = err.to_string();
    assert!(message.contains("e.g. 0.12 s") && message.contains("e.g. 0.025 s"), "{message}");
    let (divisor, multiple) = quell::sim::output_step_fixes(&d, 0.04, 0.1);
    let divisor = divisor.unwrap();
    assert!((multiple - 0.12).abs() < 1e-15 && divisor == 0.025, "{multiple} {divisor}");
    // Where the longest divisor is short, it is the one offered: 1 s / 8 below 0.13 s, not a round 0.1 s.
    assert_eq!(quell::sim::output_step_fixes(&d, 0.13, 1.0).0, Some(0.125));
    for (h, ts) in [(multiple, 0.04), (0.1, divisor)] {
        let r = Run::new(&d, g, w, RunSettings::sampled(1.0, h, ts)).simulate(go);
        assert!(r.is_ok(), "output_step {h}, sample_time {ts}: {:?}", r.err());
    }
    // At T = 3.0000003e-7 (whole in both delays, 3 s at 9,999,999 samples) 0.1 s is 333333.3 samples;
    // the longest sample time below that divides 0.1, 0.1/333334, puts 3 s at 10,000,020 samples,
    // beyond a delay line's 1e7: the offer was refused by the delays' check, whose own offer was
    // 3.0000003e-7 again. Both fixes now pass every check.
    let (divisor, multiple) = quell::sim::output_step_fixes(&d, 3.0000003e-7, 0.1);
    let divisor = divisor.unwrap();
    for (h, ts) in [(multiple, 3.0000003e-7), (0.1, divisor)] {
        let r = Run::new(&d, g, w, RunSettings::sampled(0.3, h, ts)).check();
        assert!(r.is_ok(), "output_step {h}, sample_time {ts}: {:?}", r.err());
    }
}

/// The recorded signals are budgeted in bytes, not only in rows: the SI supply vessel (m = 3,
/// q = 12: 52 numbers a row, 416 bytes; 64 with x and x̂) at 1e7 rows would keep 3.9 GiB, beyond
/// the 2 GiB budget, where the paper's example (27 numbers a row) keeps 1.8 GiB at 9e6 rows and
/// passes (at 1e7, 2.01 GiB, it would not). The error names output_step with the bytes, and the output step it proposes fits
/// (checked here from the row's width, not from the message's arithmetic); the states widen the
/// row and lower the rows allowed. Both loops check it before they start.
/// A harmonic needs at least two integrator steps a period: ω·t_end/π beyond 1e10 steps (a
/// frequency typed in the wrong unit) is refused before the continuous loop starts, naming it, with
/// the largest ω that passes; the sampled loop (which aliases it) accepts it.
#[test]
fn a_harmonic_faster_than_any_run_can_resolve_is_refused_naming_it() {
    let (s, d) = paper();
    let check = |w: &Signal, settings: RunSettings| Run::new(&d, &s.reference, w, settings).check();
    let continuous = || RunSettings::continuous(100.0, 0.1, 1e-9, 1e-9);
    let mut w = s.disturbance.clone();
    w.components[1].harmonics[0].frequency = 1e15;
    let e = match check(&w, continuous()) {
        Err(SimError::Input(e)) => e,
        other => panic!("expected an input error, got {other:?}"),
    };
    assert_eq!(e.key, "disturbance.components[1].harmonics[0].frequency");
    assert!(
        e.message.starts_with("ω = 1e15 rad/s needs at least ω·t_end/π = 3.183e16 integrator steps"),
        "{}",
        e.message
    );
    let docs = include_str!("../../../docs/errors.md");
    assert!(docs.contains(&format!("{}: {}", e.key, e.message)), "docs/errors.md does not show: {}", e.message);
    let largest: f64 =
        e.message.split("expected ω ≤ ").nth(1).and_then(|r| r.split(' ').next()).unwrap().parse().unwrap();
    let bound = std::f64::consts::PI * 1e10 / 100.0;
    assert!(largest <= bound && largest > 0.99 * bound, "{largest}");
    w.components[1].harmonics[0].frequency = largest;
    assert!(check(&w, continuous()).is_ok());
    // The horizon it names for ω = 1e15 (π·1e10/ω, rounded down) passes too.
    let horizon: f64 =
        e.message.split("simulation.t_end ≤ ").nth(1).and_then(|r| r.split(' ').next()).unwrap().parse().unwrap();
    w.components[1].harmonics[0].frequency = 1e15;
    assert!(horizon <= std::f64::consts::PI * 1e-5 && horizon > 0.99 * std::f64::consts::PI * 1e-5, "{horizon}");
    let short = RunSettings::continuous(horizon, horizon / 10.0, 1e-9, 1e-9);
    assert!(check(&w, short).is_ok(), "t_end = {horizon}");
    w.components[1].harmonics[0].frequency = 1e15;
    assert!(check(&w, RunSettings::sampled(100.0, 0.1, 1e-3)).is_ok());
}

#[test]
fn the_recorded_signals_are_budgeted_in_bytes() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/supply-vessel.toml")).unwrap();
    let s = Scenario::from_toml(&text).unwrap();
    let d = s.design().unwrap();
    let (t_end, rows) = (600.0, 1e7);
    let check =
        |d: &Design, s: &Scenario, settings: RunSettings| Run::new(d, &s.reference, &s.disturbance, settings).check();
    let e = match check(&d, &s, RunSettings::continuous(t_end, t_end / rows, 1e-7, 1e-7)) {
        Err(SimError::Input(e)) => e,
        other => panic!("expected an input error, got {other:?}"),
    };
    assert_eq!(e.key, "simulation.output_step");
    assert!(e.message.contains("rows of 416 bytes (t, y, g, e, u, u_f, η̂) = 3.874 GiB"), "{}", e.message);
    let docs = include_str!("../../../docs/errors.md");
    assert!(docs.contains(&format!("{}: {}", e.key, e.message)), "docs/errors.md does not show: {}", e.message);
    let proposed: f64 = e.message.rsplit("≥ ").next().unwrap().parse().unwrap();
    let budget = 2.0 * 1024f64.powi(3);
    assert!(t_end / proposed * 416.0 <= budget && t_end / (0.99 * proposed) * 416.0 > budget, "{proposed}");
    assert!(check(&d, &s, RunSettings::continuous(t_end, proposed, 1e-7, 1e-7)).is_ok());
    let states = RunSettings { record_states: true, ..RunSettings::continuous(t_end, proposed, 1e-7, 1e-7) };
    assert!(check(&d, &s, states).is_err(), "x and x̂ make a row 512 bytes");
    // The sampled loop at T_s = output_step = 0.1 ms: 6e6 rows, 2.3 GiB.
    match check(&d, &s, RunSettings::sampled(t_end, 1e-4, 1e-4)) {
        Err(SimError::Input(e)) => assert!(e.message.contains("GiB of recorded signals"), "{}", e.message),
        other => panic!("expected an input error, got {other:?}"),
    }
    let (p, pd) = paper();
    assert!(check(&pd, &p, RunSettings::continuous(100.0, 100.0 / 9e6, 1e-9, 1e-9)).is_ok());
    assert!(check(&pd, &p, RunSettings::continuous(100.0, 100.0 / rows, 1e-9, 1e-9)).is_err());
}

#[test]
fn noise_and_divergence_bound_are_checked() {
    let (s, _) = paper();
    let (g, w) = (&s.reference, &s.disturbance);
    let noisy = |std: Vec<f64>| RunSettings {
        noise: Some(MeasurementNoise::white(std, 1)),
        ..RunSettings::sampled(1.0, 0.1, 1e-3)
    };
    assert_eq!(sampled_key(g, w, noisy(vec![0.1])), "noise.std");
    assert_eq!(sampled_key(g, w, noisy(vec![0.1, -0.1])), "noise.std[1]");
    assert_eq!(sampled_key(g, w, noisy(vec![f64::NAN, 0.1])), "noise.std[0]");
    // Beyond the signals' 1e150, as an amplitude is: the run had started and diverged at t = 0.1.
    assert_eq!(sampled_key(g, w, noisy(vec![1e200, 0.0])), "noise.std[0]");
    for bound in [f64::NAN, 0.0, -1.0] {
        let cont = RunSettings { divergence_bound: bound, ..RunSettings::continuous(1.0, 0.1, 1e-9, 1e-9) };
        assert_eq!(continuous_key(g, w, cont), "divergence_bound");
        let samp = RunSettings { divergence_bound: bound, ..RunSettings::sampled(1.0, 0.1, 1e-3) };
        assert_eq!(sampled_key(g, w, samp), "divergence_bound");
    }
}

#[test]
fn both_loops_watch_the_same_signals() {
    // With a bound of 1, an observer state passes it soon after the start (x̂ follows x, and
    // |y_2| ≈ |g_2| = 2). The sampled loop used to watch only x and η̂; now both name the same
    // observer state, at nearly the same time (the controller at 1 ms approximates the continuous one).
    let (s, d) = paper();
    let (g, w) = (&s.reference, &s.disturbance);
    let cont = RunSettings { divergence_bound: 1.0, ..RunSettings::continuous(100.0, 0.01, 1e-9, 1e-9) };
    let samp = RunSettings { divergence_bound: 1.0, ..RunSettings::sampled(100.0, 0.01, 1e-3) };
    let a = Run::new(&d, g, w, cont).simulate(go).unwrap().outcome;
    let b = Run::new(&d, g, w, samp).simulate(go).unwrap().outcome;
    let (Some(Outcome::Diverged { t: ta, signal: sa, .. }), Some(Outcome::Diverged { t: tb, signal: sb, .. })) =
        (&a, &b)
    else {
        panic!("expected both to diverge: {a:?}, {b:?}");
    };
    assert!(sa.starts_with("xhat") || sa.starts_with("xihat"), "{sa}");
    assert_eq!(sa, sb);
    assert!((ta - tb).abs() <= 0.02 + 1e-9, "continuous at {ta}, sampled at {tb}");
}

/// A scenario's run names a diverged entry as signals.csv names its column (x1, xhat2, counted
/// from 1) and, for x and x̂, by the state's name in `[plant] states` too: the run had said
/// "x_hat[6] (observer state)", which read as 0-based beside the file's 0-based keys and not as
/// the state the user named (a two-area load-frequency loop's dPv2; helper tryout).
#[test]
fn a_scenarios_divergence_names_the_state_by_its_column_and_name() {
    let names = ["level", "flow", "heat"];
    let with_names = PAPER_EXAMPLE
        .replace("x0 = [0.0, 0.0, 0.0]", &format!("x0 = [0.0, 0.0, 0.0]\nstates = [\"{}\"]", names.join("\", \"")));
    let short = |text: &str| Scenario::from_toml(&text.replace("t_end = 100.0", "t_end = 30.0")).unwrap();
    let signal = |s: &Scenario, settings: RunSettings| {
        let d = s.design().unwrap();
        match Run::of(s, &d).settings(settings).simulate(go).unwrap().outcome {
            Some(Outcome::Diverged { signal, .. }) => signal,
            other => panic!("{other:?}"),
        }
    };
    // The paper's loop sampled at 0.5 s blows up, x1 first.
    let sampled = RunSettings::sampled(30.0, 0.5, 0.5);
    let (plain, named) = (short(PAPER_EXAMPLE), short(&with_names));
    assert_eq!(signal(&plain, sampled.clone()), "x1 (plant state)");
    assert_eq!(signal(&named, sampled), "x1 (plant state level)");
    // An observer state past a runaway bound of 0.1: its column and its state's name agree.
    let inf = f64::INFINITY;
    let runaway = RunSettings { runaway: Some(quell::sim::Peaks([inf, 0.1, inf, inf])), ..RunSettings::of(&named) };
    let x_hat = signal(&named, runaway.clone());
    let j: usize = x_hat.split(' ').next().and_then(|c| c.strip_prefix("xhat")).and_then(|j| j.parse().ok()).unwrap();
    assert_eq!(x_hat, format!("xhat{j} (observer state {})", names[j - 1]));
    assert_eq!(signal(&plain, runaway), format!("xhat{j} (observer state)"));
}

#[test]
fn a_non_finite_state_is_divergence_even_without_a_bound() {
    // The paper's example sampled at T_s = 0.5 s is unstable; with no bound (+∞) the state grows
    // until it overflows, or until y passes the controller's measurement bound (1e100, which it
    // refuses), and either counts as divergence.
    let (s, d) = paper();
    let settings = RunSettings { divergence_bound: f64::INFINITY, ..RunSettings::sampled(5000.0, 0.5, 0.5) };
    let r = Run::new(&d, &s.reference, &s.disturbance, settings).simulate(go).unwrap();
    let Some(Outcome::Diverged { t, value, signal }) = r.outcome else { panic!("{:?}", r.outcome) };
    let refused = signal.ends_with("(controller input)") && value.abs() > quell::controller::MAX_MEASUREMENT;
    assert!(!value.is_finite() || refused, "{signal} = {value} at t = {t}");
    assert!(t > 14.5 && t < 5000.0, "t = {t}");
}

/// A state the outputs do not read, in units 1e9 smaller than theirs, is as large as tracking makes
/// it, not diverged: examples/three-channel.toml with x₂ = 1e9 x₁' (x₂ in nano-units) and no
/// disturbance. y₁ = x₁ follows sin(0.5 t), so x₂ settles to 1e9 × 0.5 cos(0.5 t), a peak of 5e8
/// (closed form), half the divergence bound of 1e9 that a bound raised only by |x(0)|, 1/σ_min(C)
/// and ω's response kept: the run had ended as diverged at t = 2.1 s, x₂ = 1.02e9 (unit hunt).
#[test]
fn an_unmeasured_state_in_small_units_is_not_called_diverged_while_it_tracks() {
    let s = Scenario::from_toml(&common::three_channel_x2_in_nano_units()).unwrap();
    assert_eq!(s.plant.A[(1, 0)], 1e9, "the rewrite took");
    let d = s.design().unwrap();
    let r = Run::of(&s, &d).settings(RunSettings { record_states: true, ..RunSettings::of(&s) }).simulate(go).unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    let n = s.plant.n();
    let tail = r.t.iter().enumerate().filter(|(_, &t)| t >= 80.0).map(|(k, _)| r.x[k * n + 1].abs());
    let peak = tail.fold(0.0, f64::max);
    // The loop tracks to about 1e-5 of g by then (the example's tails); 1 % of the peak is loose.
    assert!((peak / 5e8 - 1.0).abs() < 1e-2, "x₂'s tail peak {peak:e} against 5e8");
}

#[test]
fn each_loop_reports_its_own_statistics() {
    let (s, d) = paper();
    let (g, w) = (&s.reference, &s.disturbance);
    let r = Run::new(&d, g, w, RunSettings::sampled(10.0, 0.1, 1e-3)).simulate(go).unwrap();
    // Samples k = 0, …, 10,000.
    assert_eq!(
        r.stats,
        RunStats::Sampled { controller_steps: 10_001, sample_time: 1e-3, precision: quell::controller::Precision::F64 }
    );
    let r = Run::new(&d, g, w, RunSettings::continuous(10.0, 0.1, 1e-9, 1e-9)).simulate(go).unwrap();
    let RunStats::Continuous(Stats { steps, rhs_evals: rhs_evaluations, breakpoints, .. }) = r.stats else {
        panic!("{:?}", r.stats)
    };
    // DOP853 evaluates the right-hand side at least 11 times per accepted step (12 stages, the
    // first shared with the previous step's last).
    assert!(steps > 0 && rhs_evaluations >= 11 * steps, "{:?}", r.stats);
    // Delays 1 and 3 s: breakpoints at every whole second in (0, 10).
    assert_eq!(breakpoints, 9, "{:?}", r.stats);
    // A run that stops early keeps the statistics up to then: μ_1 = 1e300 makes the adaptive law
    // infinitely stiff from t = 1 s, where the step size underflows.
    let fast = PAPER_EXAMPLE.replace("mu = [20.0, 30.0]", "mu = [1e300, 30.0]");
    assert_ne!(fast, PAPER_EXAMPLE);
    let stiff = Scenario::from_toml(&fast).unwrap().design().unwrap();
    let r = Run::new(&stiff, g, w, RunSettings::continuous(10.0, 0.1, 1e-9, 1e-9)).simulate(go).unwrap();
    assert!(matches!(r.outcome, Some(Outcome::StepSizeTooSmall { .. })));
    assert!(matches!(r.stats, RunStats::Continuous(stats) if stats.rhs_evals > 0), "{:?}", r.stats);
}

#[test]
fn a_runs_memory_bound_is_its_record_and_its_history_or_delay_lines() {
    // The paper's example over 100 s, a row each 0.1 s: 1,001 rows of 27 numbers (t, y, g, e, u,
    // u_f and 2 × 8 η̂) = 216,216 bytes. Continuous: the default step budget 110,000 (running.md:
    // 10,000 + 100·(ρ t_end + t_end/τ_min), ρ = 9, τ_min = 1) gives H = 8·110,000·3/100 = 26,400
    // history records of (8·27 + 9)·8 = 1,800 bytes (27 delayed states: n + q + m·q = 3 + 8 + 16),
    // twice for the ring: 95,040,000 bytes. Sampled at 1 ms: 3/0.001 + 2 = 3,002 samples of
    // 8·m·(q + 3) = 176 bytes = 528,352 bytes.
    let (s, d) = paper();
    let (g, w) = (&s.reference, &s.disturbance);
    let continuous = Run::new(&d, g, w, RunSettings::continuous(100.0, 0.1, 1e-9, 1e-9));
    assert_eq!(continuous.memory_bound(), 216_216 + 95_040_000);
    let sampled = Run::new(&d, g, w, RunSettings::sampled(100.0, 0.1, 1e-3));
    assert_eq!(sampled.memory_bound(), 216_216 + 528_352);
    // With the states x and x̂ a row holds 2n = 6 numbers more.
    let mut states = RunSettings::continuous(100.0, 0.1, 1e-9, 1e-9);
    states.record_states = true;
    assert_eq!(Run::new(&d, g, w, states).memory_bound(), 1_001 * 33 * 8 + 95_040_000);
}

#[test]
fn a_history_at_its_cap_is_not_told_to_raise_the_step_budget() {
    // The quadruple tank forced to `explicit` ends at the 1 GiB cap (t = 55.8 s, 755k steps): raising
    // the step budget, which the message advised, cannot raise a cap; the stiff loop wants `auto`.
    let cap = quell::sim::MAX_HISTORY_BYTES;
    let at_cap = Outcome::HistoryTooLarge { t: 55.8, max_bytes: cap }.explain("max_steps", quell::TimeUnit::default());
    let at_cap = at_cap.expect("a run that did not complete");
    assert!(at_cap.starts_with("the delay history would have exceeded 1024 MB by t = 55.8 s (the memory budget's cap"));
    assert!(at_cap.contains("simulation.method = \"auto\"") && !at_cap.contains("max_steps"), "{at_cap}");
    let below =
        Outcome::HistoryTooLarge { t: 39.4, max_bytes: 90 << 20 }.explain("max_steps", quell::TimeUnit::default());
    assert!(below.expect("not completed").contains("it scales with max_steps, raise that if the run is sound"));
}

/// Rows are at the decimal k·output_step (3 × 0.1 reads 0.3, the product 0.30000000000000004), and
/// both loops end on the same last row, t_end itself, when t_end lies within the whole-number
/// tolerance below a multiple (99.99999999 at 0.1: the sampled loop ended at 100.0, past t_end).
#[test]
fn both_loops_record_the_same_decimal_times_and_end_at_t_end() {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = s.design().unwrap();
    for t_end in [2.0, 1.99999999999] {
        let runs = [RunSettings::continuous(t_end, 0.1, 1e-6, 1e-6), RunSettings::sampled(t_end, 0.1, 0.001)];
        let times: Vec<Vec<f64>> = runs
            .into_iter()
            .map(|st| Run::of(&s, &d).settings(st).simulate(|_| ControlFlow::Continue(())).unwrap().t)
            .collect();
        assert_eq!(times[0], times[1], "t_end = {t_end}");
        let t = &times[0];
        assert_eq!(t.len(), 21);
        for (k, &tk) in t[..20].iter().enumerate() {
            // Rust's parser rounds the decimal string correctly: an independent k·0.1.
            assert_eq!(tk, format!("{}.{}", k / 10, k % 10).parse::<f64>().unwrap(), "row {k}");
        }
        assert_eq!(t[20], t_end);
    }
}

/// The coarse-sample warning's example sample time is one a run accepts with the file's output
/// step: the paper's loop (ρ = 9/s) asks T_s ≤ 0.0222 s; 0.02 s makes both delays whole but is
/// 2.5 samples of an output step of 0.05 s (the run then refused it), 0.01 s is both.
#[test]
fn the_coarse_sample_warning_offers_a_sample_time_that_divides_the_output_step() {
    let (s, d) = paper();
    let signals = [&s.reference, &s.disturbance];
    let alone = quell::sim::coarse_sample_warning(&d, signals, 0.05, None).unwrap();
    assert!(alone.contains("e.g. 0.02 s, which makes plant.delays whole, or"), "{alone}");
    let w = quell::sim::coarse_sample_warning(&d, signals, 0.05, Some(0.05)).unwrap();
    assert!(w.contains("e.g. 0.01 s, which makes plant.delays whole and divides simulation.output_step"), "{w}");
    let (g, o) = (&s.reference, &s.disturbance);
    assert!(Run::new(&d, g, o, RunSettings::sampled(1.0, 0.05, 0.02)).check().is_err());
    let r = Run::new(&d, g, o, RunSettings::sampled(1.0, 0.05, 0.01)).check();
    assert!(r.is_ok(), "{:?}", r.err());
    // β = 1e-5 and 1e-7: ρ = 1/β is printed as it is (it read 99900 for 1e5), and where no sample
    // time within the bound keeps the delay lines within their limit none is offered (one 15
    // times the bound was).
    for (beta, rho, bound) in [(1e-5, "ρ = 100000 /s", "T_s ≤ 2e-6 s"), (1e-7, "ρ = 1e7 /s", "T_s ≤ 2e-8 s")] {
        let mut spec = s.design.clone();
        spec.beta = beta;
        let fast = quell::Design::new(&s.plant, &spec).unwrap();
        let w = quell::sim::coarse_sample_warning(&fast, signals, 0.001, Some(0.1)).unwrap();
        assert!(w.contains(rho) && w.contains(&format!("{bound} (T_s·ρ ≤ 0.2), or slower poles")), "{w}");
    }
    // Where the signals' highest frequency sets ρ (a 6 rad/s disturbance harmonic against the
    // paper's 9/s filter pole, within twice it), slower poles are not offered as a remedy.
    let mut fast = s.clone();
    fast.disturbance.components[0].harmonics[0].frequency = 6.0;
    let rates = quell::sim::loop_rates(&d, &s.plant, [&fast.reference, &fast.disturbance]);
    assert!(rates.iter().all(|&(_, r)| r <= 9.0 + 1e-9) && 9.0 <= 2.0 * 6.0, "{rates:?}");
    let w = quell::sim::coarse_sample_warning(&d, [&fast.reference, &fast.disturbance], 0.05, None).unwrap();
    assert!(w.contains("slower poles lower ρ little") && !w.contains("or slower poles"), "{w}");
}

/// The numbers a message offers: each after "e.g. " or "valid sample time is ", in order.
fn offered(message: &str) -> Vec<f64> {
    let starts = ["e.g. ", "valid sample time is ", "valid one is "].into_iter().flat_map(|p| message.match_indices(p));
    let mut at: Vec<(usize, f64)> = starts
        .filter_map(|(i, p)| {
            let rest = &message[i + p.len()..];
            Some((i, rest.split(' ').next()?.parse().ok()?))
        })
        .collect();
    at.sort_by_key(|&(i, _)| i);
    at.into_iter().map(|(_, x)| x).collect()
}

/// Delays that no sample time makes whole together with the output step (1.0000001 and 3.0000003
/// s beside 0.1 s, as 1/60 min written to six digits beside 0.5 min): every message offers a
/// sample time and output step that the others accept, and says that none does both at the
/// file's output step. The three had sent a user round: the design report's 0.00833335 min (delays
/// whole) was refused by the output step's check for 0.008333333333333 min (dividing 0.5 min),
/// which the delays' check refused for 0.00833335 min again (helper tryout).
#[test]
fn sample_time_offers_agree_where_none_makes_delays_and_output_step_whole() {
    let text = PAPER_EXAMPLE.replace("delays = [1.0, 3.0]", "delays = [1.0000001, 3.0000003]");
    let s = Scenario::from_toml(&text).unwrap();
    let d = s.design().unwrap();
    let signals = [&s.reference, &s.disturbance];
    let h = s.simulation.output_step;
    let accepted = |t_s: f64, h: f64| {
        let r = Run::of(&s, &d).settings(RunSettings::sampled(2.0, h, t_s)).check();
        assert!(r.is_ok(), "sample_time {t_s}, output_step {h}: {:?}", r.err());
    };
    let refused = |t_s: f64| match Run::of(&s, &d).settings(RunSettings::sampled(2.0, h, t_s)).check() {
        Err(e) => e.to_string(),
        Ok(()) => panic!("sample time {t_s} accepted beside output_step {h}"),
    };
    // The design report (quell design): the sample time for the delays, and the output step to
    // set with it.
    let (need, _) = quell::sim::sample_time_need(&d, signals, (s.simulation.t_end, Some(h)));
    assert!(
        need.contains(
            "which makes plant.delays whole, and none within the bound also divides simulation.output_step = 0.1 s"
        ),
        "{need}"
    );
    let [t_s, multiple] = offered(&need)[..] else { panic!("{need}") };
    accepted(t_s, multiple);
    // The coarse-sample warning offers the same.
    let w = quell::sim::coarse_sample_warning(&d, signals, 0.05, Some(h)).unwrap();
    assert_eq!(offered(&w), [t_s, multiple], "{w}");
    // That sample time at the file's output step: only the output step to change is offered.
    let e = refused(t_s);
    assert!(e.starts_with("simulation.output_step: ") && e.contains("no sample time near"), "{e}");
    assert_eq!(quell::sim::output_step_fixes(&d, t_s, h).0, None);
    let [fix] = offered(&e)[..] else { panic!("{e}") };
    accepted(t_s, fix);
    // A sample time that divides the output step but not the delays: the delays' sample time, with
    // the output step to set beside it.
    let e = refused(h / (h / t_s).round());
    assert!(e.contains("none near it also divides simulation.output_step = 0.1 s"), "{e}");
    let [nearest, fix] = offered(&e)[..] else { panic!("{e}") };
    accepted(nearest, fix);
}

/// A sample time whose delay lines would be too long is offered one that divides the output step
/// too: the paper's at 3e-8 s (τ = 1 s is 3.3e7 samples, beyond 1e7) had been offered
/// 3.0000003e-7 s, which the output step of 0.1 s then refused; the offer runs.
#[test]
fn a_sample_time_offered_for_delay_lines_too_long_divides_the_output_step() {
    let (s, d) = paper();
    let h = s.simulation.output_step;
    let settings = |t_s: f64| RunSettings { output_step_given: true, ..RunSettings::sampled(2.0, h, t_s) };
    let e = Run::of(&s, &d).settings(settings(3e-8)).check().unwrap_err().to_string();
    assert!(e.contains("a delay line holds at most"), "{e}");
    let [offer] = offered(&e)[..] else { panic!("{e}") };
    let r = Run::of(&s, &d).settings(settings(offer)).check();
    assert!(r.is_ok(), "{offer}: {:?}", r.err());
}

/// A true plant with delays of its own need not have them in whole samples: the sampled loop holds
/// the moved command over part of a sample (the truth's delays had been refused with a sample time
/// that made them all whole, which a sampled study drawing them could never meet). The paper's
/// delays 1 s and 3 s with true ones of 1.2 s and 3.6 s at T_s = 0.5 s; a true delay past a delay
/// line's 1e7 samples is named with the sample time that holds it.
#[test]
fn the_truths_delays_need_not_be_whole_samples() {
    let text = format!("{PAPER_EXAMPLE}\n[truth]\ndelays = [1.2, 3.6]\n");
    let s = Scenario::from_toml(&text).unwrap();
    let d = s.design().unwrap();
    let run = |t_s: f64| Run::of(&s, &d).settings(RunSettings::sampled(5.0, 0.5, t_s)).check();
    assert!(run(0.5).is_ok(), "{:?}", run(0.5).err());
    let text = format!("{PAPER_EXAMPLE}\n[truth]\ndelays = [1e6, 3.0]\n");
    let s = Scenario::from_toml(&text).unwrap();
    let e = Run::of(&s, &d).settings(RunSettings::sampled(5.0, 0.5, 0.01)).check().unwrap_err().to_string();
    assert_eq!(e, "truth.delays[0]: τ = 1e6 s is 1e8 samples of T_s = 0.01 s; a sampled-data run's delay line holds at most 1e7: choose a simulation.sample_time of at least 0.1001 s (one that makes plant.delays whole samples) or a shorter delay");
}

/// A rejected step that landed on a breakpoint is not proposed again as it was: the paper's loop
/// in a unit of 5e-12 s had rejected a landing of 1.79e-14 s, shrunk it to 1.52e-14 s, landed on
/// 1.79e-14 s again, and so on for ever, deaf to Ctrl-C and SIGTERM (hostile review, 2026-12-06).
/// It now ends at the integrator's floor with the cause named, at once (0.02 s measured; a
/// minute is the watchdog).
#[test]
fn a_rejected_landing_is_not_tried_again_for_ever() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/paper-at-5e-12-s.toml");
    let s = Scenario::from_toml(&std::fs::read_to_string(path).unwrap()).unwrap();
    let (done, result) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let d = s.design().unwrap();
        let _ = done.send(Run::of(&s, &d).simulate(&mut go).map(|r| r.outcome));
    });
    let outcome = result.recv_timeout(std::time::Duration::from_secs(60)).expect("the run ended within a minute");
    let outcome = outcome.unwrap().expect("an outcome");
    assert!(matches!(outcome, Outcome::StepSizeTooSmall { t } if t > 3e-11 && t < 4e-11), "{outcome:?}");
    let why = outcome.explain("max_steps", quell::TimeUnit::Seconds).unwrap();
    assert!(why.contains(": below t = 1 the integrator resolves no step shorter than 1e-14 s"), "{why}");
}

/// A scenario that gives no output_step gets a default that follows its sample time, and asks
/// nothing of the sample time offered for the delays: without `output_step`, the paper's example at
/// T_s = 0.0303 s (its 1 s delay 33.0033 samples) is offered 1/33 s, which then runs (it had been
/// offered 0.0004 s, to divide the default 0.1212 s that 0.0303 itself had set).
#[test]
fn a_default_output_step_asks_nothing_of_the_sample_time_offered() {
    let text = PAPER_EXAMPLE
        .replace("output_step = 0.1     # rows of signals.csv at t = k * output_step", "")
        .replace("atol = 1e-9", "atol = 1e-9\nsample_time = 0.0303");
    let s = Scenario::from_toml(&text).unwrap();
    assert!(!s.simulation.output_step_given && (s.simulation.output_step - 0.1212).abs() < 1e-12);
    let d = s.design().unwrap();
    let e = Run::of(&s, &d).check().unwrap_err().to_string();
    assert!(e.contains("the nearest valid sample time is 0.030303030303"), "{e}");
    let t_s: f64 = e.rsplit("is ").next().unwrap().split(' ').next().unwrap().parse().unwrap();
    let s = Scenario::from_toml(&text.replace("sample_time = 0.0303", &format!("sample_time = {t_s}"))).unwrap();
    assert!(Run::of(&s, &d).check().is_ok());
}

/// The precision is the discrete controller's: a continuous run asked for f32 is refused before it
/// starts, naming the key.
#[test]
fn a_continuous_run_in_f32_is_refused_naming_the_key() {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = s.design().unwrap();
    let settings = RunSettings { precision: quell::controller::Precision::F32, ..RunSettings::of(&s) };
    let e = Run::of(&s, &d).settings(settings).simulate(|_| ControlFlow::Continue(())).unwrap_err();
    assert!(
        e.to_string().starts_with("simulation.precision: f32 applies to the discrete controller of a sampled-data run"),
        "{e}"
    );
}

/// A delay at least the horizon is cautioned before the run: the command never reaches the plant
/// (a delay of 1e300 s had run silently, the adaptive command identically 0 at the plant).
#[test]
fn a_delay_beyond_the_horizon_is_cautioned_before_the_run() {
    for (tau, shown, said) in [(300.0, "300", true), (1e300, "1e300", true), (3.0, "3", false)] {
        let s = Scenario::from_toml(&PAPER_EXAMPLE.replace("delays = [1.0, 3.0]", &format!("delays = [1.0, {tau:e}]")))
            .unwrap();
        let d = s.design().unwrap();
        let caution = quell::sim::delay_beyond_horizon(&Run::of(&s, &d)).unwrap_or_default();
        let expected = format!("plant.delays[1] = {shown} s is at least t_end = 100 s: channel 2's adaptive command never reaches the plant in this run");
        assert_eq!(caution.contains(&expected), said, "{tau}: {caution}");
    }
    // The actuator's delay holds back the whole input.
    let s = Scenario::from_toml(&format!("{PAPER_EXAMPLE}\n[truth]\nactuator_delays = [200.0, 0.0]\n")).unwrap();
    let d = s.design().unwrap();
    let caution = quell::sim::delay_beyond_horizon(&Run::of(&s, &d)).unwrap_or_default();
    assert!(caution.starts_with("truth.actuator_delays[0] = 200 s is at least t_end = 100 s: channel 1's whole input u_f never reaches the plant"), "{caution}");
}
