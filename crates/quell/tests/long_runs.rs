//! Long runs of the paper's example.
//! Ignored by default; run with
//!
//! ```text
//! cargo test --release -p quell --test long_runs -- --ignored --nocapture
//! ```
//!
//! The figures they print are recorded in `docs/long-runs.md`.

use std::ops::ControlFlow;

use quell::scenario::PAPER_EXAMPLE;
use quell::sim::{MeasurementNoise, Outcome, Run, RunSettings, RunStats, SimResult};
use quell::{Design, Scenario};

fn paper() -> (Scenario, Design) {
    let s = Scenario::from_toml(PAPER_EXAMPLE).expect("paper example parses");
    let d = s.design().expect("paper example designs");
    (s, d)
}

fn continuous(t_end: f64, output_step: f64) -> SimResult {
    let (s, d) = paper();
    let settings = RunSettings::continuous(t_end, output_step, 1e-9, 1e-9);
    let r = Run::new(&d, &s.reference, &s.disturbance, settings).simulate(|_| ControlFlow::Continue(())).unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    r
}

/// max |v| over a row-major signal, with a check that every entry is finite.
fn max_abs(signal: &[f64], what: &str) -> f64 {
    assert!(signal.iter().all(|v| v.is_finite()), "{what} has a non-finite entry");
    signal.iter().fold(0.0, |a, v| a.max(v.abs()))
}

/// η̂ (all channels) at the sample nearest to `t`.
fn eta_at(r: &SimResult, t: f64) -> &[f64] {
    let k = r.t.iter().position(|&s| s >= t - 1e-9).expect("time inside the run");
    let w = r.m * r.q;
    &r.eta[k * w..(k + 1) * w]
}

#[test]
#[ignore = "long run (~5 s in release); cargo test --release -p quell --test long_runs -- --ignored"]
fn paper_example_to_10000_s() {
    let short = continuous(100.0, 0.1);
    let long = continuous(10_000.0, 0.1);
    assert_eq!(long.len(), 100_001);

    // Tracking error: the tail at 10,000 s is no worse than at 100 s (margin 1e-6 absolute).
    for i in 0..long.m {
        let early = long.max_abs_error(i, 90.0, 100.0).unwrap();
        let late = long.max_abs_error(i, 9_900.0, 10_000.0).unwrap();
        println!("e{}: max |e| on [90, 100] = {early:.3e}, on [9900, 10000] = {late:.3e}", i + 1);
        assert!(late <= early + 1e-6, "channel {}: tail error grew from {early} to {late}", i + 1);
    }

    // η̂ does not drift: its change between 1,000 s and 10,000 s is tiny against its size.
    let (a, b) = (eta_at(&long, 1_000.0), eta_at(&long, 10_000.0));
    let drift = a.iter().zip(b).fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
    let size = max_abs(b, "eta");
    println!("eta: max_j |eta_j(10000) - eta_j(1000)| = {drift:.3e} (max |eta_j| = {size:.3})");
    assert!(drift < 1e-6, "eta drifted by {drift} between 1000 s and 10000 s");
    // After 1,000 s, no component moves more than it did then (drift bounded, not growing).
    let (c, d) = (eta_at(&long, 5_000.0), eta_at(&long, 9_000.0));
    let late_drift = c.iter().zip(d).fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
    println!("eta: max_j |eta_j(9000) - eta_j(5000)| = {late_drift:.3e}");

    // Every signal finite and bounded.
    let (y, u, eta) = (max_abs(&long.y, "y"), max_abs(&long.u, "u"), max_abs(&long.eta, "eta"));
    println!("max |y| = {y:.3}, max |u| = {u:.3}, max |eta| = {eta:.3}");
    assert!(y < 100.0 && u < 100.0 && eta < 100.0);
    // The bounds are those of the first 100 s: nothing grows later.
    let (u0, eta0) = (max_abs(&short.u, "u"), max_abs(&short.eta, "eta"));
    assert!(u <= u0 * 1.01 + 1e-9, "max |u| {u} vs {u0} in the first 100 s");
    assert!(eta <= eta0 * 1.01 + 1e-9, "max |eta| {eta} vs {eta0} in the first 100 s");

    // Memory: the dense history holds the last max τ seconds only, so its peak length does not
    // grow with the horizon.
    let history = |r: &SimResult| match r.stats {
        RunStats::Continuous(stats) => stats.max_history_len,
        RunStats::Sampled { .. } => unreachable!("a continuous run"),
    };
    let (h100, h10k) = (history(&short), history(&long));
    println!(
        "solver: max_history_len {h100} (100 s) vs {h10k} (10,000 s); steps {} vs {}",
        short.stats.steps(),
        long.stats.steps()
    );
    assert!(h10k <= 2 * h100 + 16, "history grew from {h100} to {h10k} records");
}

#[test]
#[ignore = "long run (~2 s in release); cargo test --release -p quell --test long_runs -- --ignored"]
fn sampled_with_measurement_noise_1000_s() {
    // T_s = 1 ms, white noise on y with σ = 1 % of the outputs' amplitude (g peaks at 3 and 2).
    let (s, d) = paper();
    let settings = RunSettings {
        noise: Some(MeasurementNoise::white(vec![0.03, 0.02], 1)),
        divergence_bound: 1e9,
        ..RunSettings::sampled(1_000.0, 0.1, 0.001)
    };
    let r = Run::new(&d, &s.reference, &s.disturbance, settings)
        .simulate(|_| ControlFlow::Continue(()))
        .expect("sampled run starts");
    assert_eq!(r.outcome, Some(Outcome::Completed));
    assert_eq!(r.len(), 10_001);

    let (y, u, eta) = (max_abs(&r.y, "y"), max_abs(&r.u, "u"), max_abs(&r.eta, "eta"));
    println!("noise: max |y| = {y:.3}, max |u| = {u:.3}, max |eta| = {eta:.3}");
    assert!(y < 100.0 && u < 100.0 && eta < 100.0);
    let (a, b) = (eta_at(&r, 100.0), eta_at(&r, 1_000.0));
    let drift = a.iter().zip(b).fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
    println!("noise: max_j |eta_j(1000) - eta_j(100)| = {drift:.3e}");
    for i in 0..r.m {
        let early = r.max_abs_error(i, 90.0, 100.0).unwrap();
        let tail = r.max_abs_error(i, 900.0, 1_000.0).unwrap();
        let rms = r.summary()[i].figures.tail_rms_e;
        println!(
            "noise: e{}: max |e| on [90, 100] = {early:.3e}, on [900, 1000] = {tail:.3e}, RMS on [900, 1000] = {rms:.3e}",
            i + 1
        );
        // Noise keeps the error from vanishing, but it stays at the noise level.
        assert!(tail < 0.05, "channel {}: tail error {tail}", i + 1);
    }
}
