//! The true plant's physics beyond the model (1): an actuator delay on the whole input u_f, input
//! limits and band-limited measurement noise, in both loops.
//!
//! The independent side: a scalar loop whose adaptive command is identically zero (g = 0, k = 0:
//! ξ̂ = 0, so u = 0 and the loop is observer-based state feedback), integrated here by classical
//! RK4 with cubic Hermite interpolation of the delayed x̂; and the sampled-data loop, a second
//! discretization, converging to the continuous one at first order in T_s.

use std::ops::ControlFlow;

use quell::scenario::{Actuator, Noise, Scenario, PAPER_EXAMPLE};
use quell::signal::Signal;
use quell::sim::{band_limited, Outcome, Run, RunSettings, SimResult, NOISE_SINES};

/// ẋ = x + u_p, y = x (unstable), channel pole −2 (K = 3, F = 2), observer pole −5 (l = 6), g = 0.
const SCALAR: &str = r#"
[plant]
A = [[1.0]]
B = [[1.0]]
C = [[1.0]]
delays = [0.3]
x0 = [0.5]
[design]
observer_gain = [[6.0]]
channel_poles = [[-2.0]]
reference_filter_poles = [[-1.0]]
mu = [10.0]
beta = 1.0
[reference]
components = [ { bias = 0.0 } ]
[simulation]
t_end = 4.0
"#;

fn go(_: f64) -> ControlFlow<()> {
    ControlFlow::Continue(())
}

fn continuous(s: &Scenario, t_end: f64, actuator: Option<Actuator>, noise: Option<Noise>) -> SimResult {
    let d = s.design().unwrap();
    let settings = RunSettings { actuator, noise, ..RunSettings::continuous(t_end, 0.1, 1e-10, 1e-10) };
    let r = Run::new(&d, &s.reference, &s.disturbance, settings).truth(s.true_plant()).simulate(go).unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    r
}

/// RK4 of x' = x + sat(−3 x̂(t − τ_a)), x̂' = x̂ − 3 x̂ + 6 (x + n(t) − x̂) (observer (6) with the
/// controller's undelayed u_f = −3 x̂), x(0) = 0.5, x̂(0) = 0, x̂ = 0 before 0; y at t = 0.1 k.
fn reference_rk4(tau_a: f64, (lower, upper): (f64, f64), noise: Option<&Signal>, t_end: f64) -> Vec<f64> {
    let h = 1e-4;
    let n_steps = (t_end / h).round() as usize;
    let lag = (tau_a / h).round() as usize;
    let nz = |t: f64| noise.map_or(0.0, |s| s.components[0].eval(t));
    let xh_rate = |t: f64, x: f64, xh: f64| -2.0 * xh + 6.0 * (x + nz(t) - xh);
    let (mut x, mut xh) = (0.5, 0.0);
    // x̂ and x̂' at the grid points, for the Hermite interpolant of x̂(t − τ_a).
    let (mut hist, mut rate) = (vec![0.0], vec![xh_rate(0.0, x, xh)]);
    let delayed = |hist: &[f64], rate: &[f64], k: usize, frac: f64| -> f64 {
        if lag == 0 {
            return f64::NAN;
        }
        if k < lag {
            return 0.0;
        }
        let j = k - lag;
        let (p0, p1, m0, m1) = (hist[j], hist[j + 1], rate[j] * h, rate[j + 1] * h);
        let s = frac;
        let (s2, s3) = (s * s, s * s * s);
        (2.0 * s3 - 3.0 * s2 + 1.0) * p0 + (s3 - 2.0 * s2 + s) * m0 + (-2.0 * s3 + 3.0 * s2) * p1 + (s3 - s2) * m1
    };
    let mut out = vec![x];
    for k in 0..n_steps {
        let t = k as f64 * h;
        let f = |frac: f64, x: f64, xh: f64| {
            let xd = if lag == 0 { xh } else { delayed(&hist, &rate, k, frac) };
            let u = (-3.0 * xd).clamp(lower, upper);
            (x + u, xh_rate(t + frac * h, x, xh))
        };
        let k1 = f(0.0, x, xh);
        let k2 = f(0.5, x + 0.5 * h * k1.0, xh + 0.5 * h * k1.1);
        let k3 = f(0.5, x + 0.5 * h * k2.0, xh + 0.5 * h * k2.1);
        let k4 = f(1.0, x + h * k3.0, xh + h * k3.1);
        x += h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
        xh += h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
        hist.push(xh);
        rate.push(xh_rate(t + h, x, xh));
        if (k + 1) % 1000 == 0 {
            out.push(x);
        }
    }
    out
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

#[test]
fn actuator_delay_limits_and_noise_match_an_independent_integration() {
    let s = Scenario::from_toml(SCALAR).unwrap();
    let noise = Noise { std: vec![0.05], seed: 3, bandwidth: Some(4.0) };
    let signal = band_limited(&noise).unwrap();
    // (τ_a, (u_min, u_max), noise): the delay alone, with a limit that clips, with the noise, and
    // a range that is not symmetric (u_f starts at −1.5 and clips at −0.3, a heater at 0.3 of its
    // range: none given).
    let inf = f64::INFINITY;
    let cases = [
        (0.2, (-inf, inf), false),
        (0.2, (-0.8, 0.8), false),
        (0.0, (-0.8, 0.8), true),
        (0.2, (-0.8, 0.8), true),
        (0.2, (-0.3, 0.8), false),
        (0.0, (-0.3, inf), true),
    ];
    for (tau_a, (lower, limit), noisy) in cases {
        let symmetric = lower == -limit;
        let act = Actuator { delays: vec![tau_a], limits: vec![limit], lower: (!symmetric).then(|| vec![lower]) };
        let r = continuous(&s, 4.0, Some(act), noisy.then(|| noise.clone()));
        let reference = reference_rk4(tau_a, (lower, limit), noisy.then_some(&signal), 4.0);
        // RK4 at h = 1e-4 with a kink where the limit starts or stops clipping: errors ~1e-9; the
        // solver runs at 1e-10. 1e-6 is far below the effect of each physics item (below).
        let err = max_diff(&r.y, &reference);
        assert!(err < 1e-6, "τ_a = {tau_a}, u_f in [{lower}, {limit}], noise {noisy}: max |Δy| = {err:e}");
        assert!(r.u_f.iter().all(|u| (lower..=limit).contains(u)), "the plant receives u_f within its range");
        assert_eq!((r.u_min.clone(), r.u_max.clone()), (vec![lower], vec![limit]));
        assert!(r.u.iter().all(|&u| u == 0.0), "g = 0 and k = 0 leave the adaptive command at 0");
        if limit.is_finite() {
            let fraction = r.limited_fraction()[0];
            assert!(fraction > 0.05 && fraction < 0.95, "the limit clips part of the time: {fraction}");
        }
    }
    // Each item changes y by far more than the tolerance above.
    let ideal = reference_rk4(0.0, (-inf, inf), None, 4.0);
    for (tau_a, limit, noisy) in cases {
        let other = reference_rk4(tau_a, limit, noisy.then_some(&signal), 4.0);
        assert!(max_diff(&ideal, &other) > 1e-2, "case ({tau_a}, {limit:?}, {noisy}) is visible");
    }
}

#[test]
fn band_limited_noise_has_its_standard_deviation_and_band() {
    let noise = Noise { std: vec![0.3, 0.0, 2.0], seed: 11, bandwidth: Some(50.0) };
    let s = band_limited(&noise).unwrap();
    assert_eq!(s.components.len(), 3);
    for (c, &std) in s.components.iter().zip(&noise.std) {
        assert_eq!(c.harmonics.len(), NOISE_SINES);
        // Every frequency within the band (rad/s).
        assert!(c.harmonics.iter().all(|h| h.frequency > 0.0 && h.frequency <= 2.0 * std::f64::consts::PI * 50.0));
        // Time-average of n² over 200 s (10,000 periods of the band edge), sampled at 1 kHz: the
        // cross terms of two sines at frequencies Δω apart average to O(1/(Δω T)); with 64 sines
        // drawn uniformly over 314 rad/s the closest pairs are ~0.1 rad/s apart, so 5 % on the
        // variance.
        let n = 200_000;
        let mean_square = (0..n).map(|k| c.eval(k as f64 * 1e-3).powi(2)).sum::<f64>() / n as f64;
        assert!((mean_square - std * std).abs() <= 0.05 * std * std, "{mean_square} vs {}", std * std);
    }
    // Seeded: the same seed gives the same noise, another seed another.
    assert_eq!(band_limited(&noise), Some(s.clone()));
    assert_ne!(band_limited(&Noise { seed: 12, ..noise }), Some(s));
    assert_eq!(band_limited(&Noise::white(vec![1.0], 0)), None);
}

/// The paper's example with an actuator delay of 0.1 s on u_f, a limit on input 2 and band-limited
/// noise: the sampled-data loop converges to the continuous loop at first order in T_s (halving T_s
/// halves the difference), with all three items honoured by both loops.
#[test]
fn sampled_loop_with_the_physics_converges_to_the_continuous_one() {
    let text = format!(
        "{PAPER_EXAMPLE}\n[truth]\nactuator_delays = [0.1, 0.1]\nu_max = [inf, 6.0]\n[noise]\nstd = [0.02, 0.02]\nbandwidth = 2.0\nseed = 5\n"
    )
    .replace("t_end = 100.0", "t_end = 10.0");
    let s = Scenario::from_toml(&text).unwrap();
    assert!(s.truth_differs());
    let d = s.design().unwrap();
    let cont = continuous(&s, 10.0, s.actuator.clone(), s.noise.clone());
    assert!(cont.limited[0] == 0 && cont.limited[1] > 0, "input 2 clips: {:?}", cont.limited);
    let sampled = |ts: f64| {
        let settings =
            RunSettings { actuator: s.actuator.clone(), noise: s.noise.clone(), ..RunSettings::sampled(10.0, 0.1, ts) };
        Run::new(&d, &s.reference, &s.disturbance, settings).truth(s.true_plant()).simulate(go).unwrap()
    };
    let (e1, e2) = (max_diff(&sampled(0.002).y, &cont.y), max_diff(&sampled(0.001).y, &cont.y));
    // First order: ratio 2; [1.6, 2.5] leaves room for the kinks of the limit.
    assert!(e2 < e1 && (1.6..2.5).contains(&(e1 / e2)), "T = 0.002: {e1:e}, T = 0.001: {e2:e}");
    // Without the physics the loops agree with each other but not with the run above.
    let plain = continuous(&s, 10.0, None, None);
    let effect = max_diff(&plain.y, &cont.y);
    assert!(effect > 5.0 * e1, "the physics changes y by {effect:e}, more than the discretization ({e1:e})");
}

#[test]
fn an_actuator_without_delay_or_clipping_reproduces_the_design_input() {
    // A limit nobody reaches switches on the explicit input path (u_p computed in the derivative)
    // and must reproduce the linear path's run to the solver's tolerance, with and without true
    // delays that differ from the design's.
    for truth in ["", "delays = [1.1, 2.9]"] {
        let text = format!("{PAPER_EXAMPLE}\n[truth]\n{truth}\n").replace("t_end = 100.0", "t_end = 20.0");
        let s = Scenario::from_toml(&text).unwrap();
        let base = continuous(&s, 20.0, None, None);
        let act = Actuator { delays: vec![0.0, 0.0], limits: vec![1e12, 1e12], lower: None };
        let explicit = continuous(&s, 20.0, Some(act), None);
        // rtol = atol = 1e-10 over 20 s of an unstable plant: 1e-6 absolute on y of order 1.
        assert!(max_diff(&base.y, &explicit.y) < 1e-6, "{truth}: {:e}", max_diff(&base.y, &explicit.y));
        assert_eq!(explicit.limited, vec![0, 0]);
    }
}

#[test]
fn the_breakpoints_counted_before_a_run_are_the_ones_it_lands_on() {
    // Run::breakpoints counts t = Σ k_i τ_i from the delays alone (the study's runaway budget needs
    // it before the run): the design's, the true plant's and the actuator's, which the solver then
    // lands on one by one.
    let text = format!("{PAPER_EXAMPLE}\n[truth]\ndelays = [1.1, 2.9]\n").replace("t_end = 100.0", "t_end = 20.0");
    let s = Scenario::from_toml(&text).unwrap();
    let d = s.design().unwrap();
    for actuator in [None, Some(Actuator { delays: vec![0.1, 0.05], limits: vec![f64::INFINITY, 8.0], lower: None })] {
        let settings = RunSettings { actuator, ..RunSettings::continuous(20.0, 0.1, 1e-8, 1e-8) };
        let run = || Run::new(&d, &s.reference, &s.disturbance, settings.clone()).truth(s.true_plant());
        let counted = run().breakpoints();
        let r = run().simulate(go).unwrap();
        let quell::sim::RunStats::Continuous(stats) = &r.stats else { panic!("a continuous run") };
        assert_eq!(counted, stats.breakpoints, "{:?}", settings.actuator);
        assert!(counted > 20, "{counted} breakpoints: the delays add few");
    }
}

#[test]
fn noise_far_beyond_the_loops_rate_is_refused_by_name() {
    // A bandwidth of 1e6 cycles/s on the paper's loop (ρ = 9 rad/s) ran until the history's memory
    // budget and ended "failed" as a blow-up does; it is an input error naming the key.
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = s.design().unwrap();
    let noise = |bandwidth: f64| Noise { std: vec![0.01, 0.01], seed: 1, bandwidth: Some(bandwidth) };
    let settings = |b| RunSettings { noise: Some(noise(b)), ..RunSettings::continuous(2.0, 0.1, 1e-6, 1e-6) };
    let e = Run::new(&d, &s.reference, &s.disturbance, settings(1e6)).simulate(go).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("noise.bandwidth: expected at most 143 Hz (100× the loop's fastest rate ρ = 9 rad/s, over 2π"),
        "{e}"
    );
    let r = Run::new(&d, &s.reference, &s.disturbance, settings(50.0)).simulate(go).unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
}
