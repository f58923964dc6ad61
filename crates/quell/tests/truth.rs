//! `[truth]`: the simulated plant differs from the design model. A truth equal to the plant
//! reproduces the run bit for bit, a small mismatch changes it continuously (half the mismatch, half
//! the change), and the sampled-data loop with a truth tracks the continuous loop with that truth
//! (two independent discretizations of the same physics).
#![allow(non_snake_case)]

use std::ops::ControlFlow;

use quell::scenario::{Scenario, PAPER_EXAMPLE};
use quell::sim::{Outcome, Run, RunSettings, SimResult};

/// The paper's example with `truth` appended as its [truth] table.
fn scenario(truth: &str) -> Scenario {
    let text =
        if truth.is_empty() { PAPER_EXAMPLE.to_string() } else { format!("{PAPER_EXAMPLE}\n[truth]\n{truth}\n") };
    Scenario::from_toml(&text).unwrap()
}

fn continuous(s: &Scenario, t_end: f64, tol: f64) -> SimResult {
    let d = s.design().unwrap();
    let settings = RunSettings { actuator: s.actuator.clone(), ..RunSettings::continuous(t_end, 0.1, tol, tol) };
    let r = Run::new(&d, &s.reference, &s.disturbance, settings)
        .truth(s.true_plant())
        .simulate(|_| ControlFlow::Continue(()))
        .unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    r
}

fn sampled(s: &Scenario, t_end: f64, T: f64) -> SimResult {
    let d = s.design().unwrap();
    let settings = RunSettings { actuator: s.actuator.clone(), ..RunSettings::sampled(t_end, 0.1, T) };
    let r = Run::new(&d, &s.reference, &s.disturbance, settings)
        .truth(s.true_plant())
        .simulate(|_| ControlFlow::Continue(()))
        .unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    r
}

/// sup over the samples of |y − y_ref|, both channels.
fn change(a: &SimResult, b: &SimResult) -> f64 {
    a.y.iter().zip(&b.y).fold(0.0, |m: f64, (p, q)| m.max((p - q).abs()))
}

const PLANT_AS_TRUTH: &str = "A = [[-3.2, -1.7, -3.0], [2.8, 1.3, 4.0], [0.3, 0.3, -0.5]]
B = [[-2.0, 1.0], [2.0, -1.0], [1.0, 0.0]]
C = [[2.0, 2.0, 0.0], [2.0, 1.0, 2.0]]
D = [[1.0, -3.0], [2.0, 1.0], [3.0, 1.0]]
Q = [[1.0, 2.0], [1.0, 0.0]]
delays = [1.0, 3.0]
x0 = [0.0, 0.0, 0.0]";

#[test]
fn truth_equal_to_the_plant_reproduces_the_run_bit_for_bit() {
    let (nominal, twin) = (scenario(""), scenario(PLANT_AS_TRUTH));
    assert!(twin.truth.is_some() && !twin.truth_differs());
    let (a, b) = (continuous(&nominal, 20.0, 1e-9), continuous(&twin, 20.0, 1e-9));
    assert_eq!((&a.t, &a.y, &a.u, &a.eta), (&b.t, &b.y, &b.u, &b.eta));
    let (a, b) = (sampled(&nominal, 20.0, 1e-3), sampled(&twin, 20.0, 1e-3));
    assert_eq!((&a.t, &a.y, &a.u, &a.eta), (&b.t, &b.y, &b.u, &b.eta));
}

/// The change in y is differentiable in the mismatch, so halving a small mismatch halves it: the
/// ratio of the changes is 2 up to the second-order term (≈ 1 + ε‖second derivative‖/‖first‖,
/// a few per cent at these ε) and the solver's error (rtol = 1e-10, far below the changes of 1e-4
/// and more). Bounds [1.8, 2.2].
#[test]
fn halving_a_small_mismatch_roughly_halves_the_change() {
    let nominal = continuous(&scenario(""), 30.0, 1e-10);
    let ratio = |truth: &dyn Fn(f64) -> String, eps: f64, run: &dyn Fn(&Scenario) -> SimResult, base: &SimResult| {
        let (full, half) =
            (change(&run(&scenario(&truth(eps))), base), change(&run(&scenario(&truth(eps / 2.0))), base));
        assert!(full > 1e-5, "the mismatch changes the run: {full}");
        full / half
    };
    let a_scaled = |eps: f64| {
        let A = [[-3.2, -1.7, -3.0], [2.8, 1.3, 4.0], [0.3, 0.3, -0.5]];
        let rows: Vec<String> = A
            .iter()
            .map(|r| format!("[{}]", r.iter().map(|x| format!("{:?}", x * (1.0 + eps))).collect::<Vec<_>>().join(", ")))
            .collect();
        format!("A = [{}]", rows.join(", "))
    };
    let delays = |eps: f64| format!("delays = [{:?}, {:?}]", 1.0 + eps, 3.0 - eps);
    let cont = |s: &Scenario| continuous(s, 30.0, 1e-10);
    for (name, truth, eps) in [("truth.A", &a_scaled as &dyn Fn(f64) -> String, 2e-3), ("truth.delays", &delays, 4e-3)]
    {
        let r = ratio(truth, eps, &cont, &nominal);
        assert!((1.8..=2.2).contains(&r), "{name}, continuous: ratio {r}");
    }
    // The sampled-data loop, with delays in whole samples of T = 1 ms and in fractions of one
    // (0.6 and 0.3 of a sample: the moved command is held over part of each sample).
    let T = 1e-3;
    let nominal = sampled(&scenario(""), 30.0, T);
    let samp = |s: &Scenario| sampled(s, 30.0, T);
    for (name, truth, eps) in [
        ("truth.A", &a_scaled as &dyn Fn(f64) -> String, 2e-3),
        ("truth.delays", &delays, 4.0 * T),
        ("truth.delays (fractions of a sample)", &delays, 0.6 * T),
    ] {
        let r = ratio(truth, eps, &samp, &nominal);
        assert!((1.8..=2.2).contains(&r), "{name}, sampled: ratio {r}");
    }
}

/// Both loops with the same truth (A 5 % off, delays 0.1 s off and not whole samples, so the
/// controller's delays are wrong) are two independent discretizations of one delay equation: the sampled-data loop's
/// deviation from the continuous one is first order in T (halving T from 2 ms to 1 ms halves it,
/// ratio in [1.8, 2.2], as it does without a truth), and at 1 ms it is below 10 % of the signal's
/// peak while the truth moves the run far more than that.
#[test]
fn sampled_loop_with_truth_converges_to_the_continuous_one() {
    // The true delays a quarter and a half of a sample off the grid at 2 ms and 1 ms: rounded to
    // whole samples they would be 0.5 ms off at both, and the deviation would not halve. Then with
    // actuator delays in fractions of a sample too (0.55 and 0.35 of one at 2 ms), so that the
    // plant's input switches three times within a sample.
    let truth = "A = [[-3.36, -1.785, -3.15], [2.94, 1.365, 4.2], [0.315, 0.315, -0.525]]\ndelays = [1.1005, 2.9003]";
    for truth in [truth.to_string(), format!("{truth}\nactuator_delays = [0.0131, 0.0247]")] {
        converges(&scenario(&truth));
    }
}

/// The deviations of the sampled loop (2 ms, 1 ms) from the continuous one with `s`'s truth halve
/// and are small beside the truth's own change of the run.
fn converges(s: &Scenario) {
    assert!(s.truth_differs());
    let cont = continuous(s, 60.0, 1e-10);
    let (coarse, fine) = (sampled(s, 60.0, 2e-3), sampled(s, 60.0, 1e-3));
    for (name, pick) in
        [("y", (|r: &SimResult| r.y.clone()) as fn(&SimResult) -> Vec<f64>), ("u", |r: &SimResult| r.u.clone())]
    {
        let reference = pick(&cont);
        for i in 0..2 {
            let dev = |r: &SimResult| {
                let v = pick(r);
                v.iter().zip(&reference).skip(i).step_by(2).fold(0.0, |m: f64, (p, q)| m.max((p - q).abs()))
            };
            let peak = reference.iter().skip(i).step_by(2).fold(0.0, |m: f64, v| m.max(v.abs()));
            let (d2, d1) = (dev(&coarse), dev(&fine));
            assert!((1.8..=2.2).contains(&(d2 / d1)), "{name}{}: deviations {d2} (2 ms), {d1} (1 ms)", i + 1);
            assert!(d1 < 0.1 * peak, "{name}{}: deviation {d1} vs peak {peak}", i + 1);
        }
    }
    let nominal = continuous(&scenario(""), 60.0, 1e-10);
    assert!(
        change(&cont, &nominal) > 5.0 * change(&fine, &cont),
        "{} vs {}",
        change(&cont, &nominal),
        change(&fine, &cont)
    );
}

#[test]
fn truth_mistakes_name_their_key() {
    let cases = [
        (
            "B = [[1.0, 0.0], [0.0, 1.0]]",
            "truth.B: expected 3×2 (the shape of plant.B: the true plant has the design model's dimensions), found 2×2",
        ),
        ("delays = [1.0]", "truth.delays: expected 2 entries (as plant.delays), found 1"),
        ("delays = [1.0, -3.0]", "truth.delays[1]: expected a finite delay ≥ 0, found -3"),
        ("x0 = [0.0]", "truth.x0: expected 3 entries (as plant.x0), found 1"),
        ("E = [[1.0]]", "truth.E: unknown key"),
        ("u_max = [1.0]", "truth.u_max: expected 2 entries (one per input), found 1"),
        (
            "actuator_delays = [-0.1, 0.0]",
            "truth.actuator_delays[0]: expected a finite delay ≥ 0 (in the plant model's unit of time), found -0.1",
        ),
        ("u_max = [1.0, 0.0]", "truth.u_max[1]: expected a limit > 0 (inf for none), found 0"),
        ("u_min = [-1.0]", "truth.u_min: expected 2 entries (one per input), found 1"),
        (
            "u_min = [-1.0, 0.5]",
            "truth.u_min[1]: expected a lower limit < 0 (-inf for none), found 0.5; u_f is the deviation",
        ),
        ("u_min = [-1.0, 0.0]", "truth.u_min[1]: expected a lower limit < 0 (-inf for none), found 0;"),
        ("u_min = [-1.0, inf]", "truth.u_min[1]: expected a finite number or -inf (no limit), found inf"),
        ("u_max = [-inf, 1.0]", "truth.u_max[0]: expected a finite number or inf (no limit), found -inf"),
    ];
    for (truth, expected) in cases {
        let e = Scenario::from_toml(&format!("{PAPER_EXAMPLE}\n[truth]\n{truth}\n")).unwrap_err().to_string();
        assert!(e.starts_with(expected), "{truth}\nexpected: {expected}\ngot:      {e}");
    }
    // The actuator's delays need not be whole (a_fractional_actuator_delay_…), nor the truth's
    // (the_truths_delays_need_not_be_whole_samples): half a sample of each runs.
    let d = scenario("").design().unwrap();
    let s = scenario("delays = [1.0005, 3.0]\nactuator_delays = [0.0005, 0.0]");
    let settings = RunSettings { actuator: s.actuator.clone(), ..RunSettings::sampled(1.0, 0.1, 1e-3) };
    let r = Run::new(&d, &s.reference, &s.disturbance, settings)
        .truth(s.true_plant())
        .simulate(|_| ControlFlow::Continue(()));
    assert_eq!(r.unwrap().outcome, Some(Outcome::Completed));
    // Called directly with a plant of other dimensions.
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/siso-complex.toml")).unwrap();
    let other = Scenario::from_toml(&text).unwrap();
    let e = Run::new(&d, &s.reference, &s.disturbance, RunSettings::continuous(1.0, 0.1, 1e-6, 1e-6))
        .truth(&other.plant)
        .simulate(|_| ControlFlow::Continue(()))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("truth.A: expected 3×3 (the shape of plant.A)"), "{e}");
}

/// A run that ends early on a true plant far from the model (the paper's with τ₂ = 9 s against
/// 3 s: its step size underflows at t = 43 s as it blows up) is told so first, with the keys that differ, before the model's own advice; the same scenario
/// without the mismatch completes with no such line.
#[test]
fn a_run_that_diverges_on_a_mismatched_truth_names_the_mismatch_first() {
    let s = scenario("delays = [1.0, 9.0]");
    let d = s.design().unwrap();
    let r = Run::of(&s, &d).simulate(|_| ControlFlow::Continue(())).unwrap();
    assert!(!matches!(r.outcome, Some(Outcome::Completed) | None), "{:?}", r.outcome);
    let advice = quell::diagnostics::diagnose_run(&s, &d, &r).advice;
    assert!(
        advice[0].starts_with("the run ended early (")
            && advice[0].contains("on a true plant that differs from the design model: truth.delays [1, 9] s against plant.delays [1, 3]; the run did not simulate the design model"),
        "{advice:?}"
    );
    let nominal = scenario("");
    let r = Run::of(&nominal, &d).simulate(|_| ControlFlow::Continue(())).unwrap();
    assert!(quell::diagnostics::diagnose_run(&nominal, &d, &r).advice.iter().all(|a| !a.contains("true plant")));
    // τ₂ = 3.3 s: the run completes, its tails (7e-2, 8e-2) miss the 1 % bounds (3e-2, 2e-2), and
    // the mismatch is named as a possible floor beside the model's advice.
    let near = scenario("delays = [1.0, 3.3]");
    let r = Run::of(&near, &d).simulate(|_| ControlFlow::Continue(())).unwrap();
    assert!(matches!(r.outcome, Some(Outcome::Completed) | None), "{:?}", r.outcome);
    let advice = quell::diagnostics::diagnose_run(&near, &d, &r).advice;
    assert!(
        advice[0].starts_with("the run simulates a true plant that differs from the design model (truth.delays [1, 3.3] s against plant.delays [1, 3]): part of the tail may be the mismatch's"),
        "{advice:?}"
    );
}

/// An actuator delay that is not a whole number of samples, τ_a = (d + f)·T_s, switches the plant's
/// input within each sample: over [kT, kT + fT) the older value, then the newer. Checked against
/// the closed form of a scalar plant x' = a x + b u_p (Åström & Wittenmark's fractional delay):
/// x(k+1) = e^{aT} x(k) + (b/a)[(e^{aT} − e^{a(1−f)T}) u_p(k) + (e^{a(1−f)T} − 1) u_p(k+1)], with
/// u_p(k) the recorded plant input at kT (the older value) and u_p(k+1) the next, which is the
/// newer value of sample k; to 1e-12 of the state's peak (rounding over the products).
#[test]
fn a_fractional_actuator_delay_is_held_within_the_sample() {
    let (a, b, T) = (0.5f64, 2.0f64, 1e-3f64);
    let text = format!(
        "[plant]\nA = [[{a}]]\nB = [[{b}]]\nC = [[1.0]]\nD = [[1.0]]\nQ = [[0.0]]\ndelays = [0.0]\nx0 = [0.5]\n[design]\nobserver_poles = [-3.0]\nchannel_poles = [[-2.0]]\nreference_filter_poles = [[-1.0, -2.0]]\ndisturbance_filter_poles = [[-1.0]]\nmu = [1.0]\nbeta = 1.0\n[reference]\ncomponents = [{{ harmonics = [{{ amplitude = 1.0, frequency = 3.0 }}] }}]\n[disturbance]\ncomponents = [{{ bias = 0.0 }}]\n[simulation]\nt_end = 0.5\noutput_step = {T}\nsample_time = {T}\n[truth]\nactuator_delays = [0.0013]\n"
    );
    let s = Scenario::from_toml(&text).unwrap();
    let d = s.design().unwrap();
    let settings = RunSettings { record_states: true, ..RunSettings::of(&s) };
    let r = Run::of(&s, &d).settings(settings).simulate(|_| ControlFlow::Continue(())).unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    let f = 0.3;
    let (phi, mid) = ((a * T).exp(), (a * (1.0 - f) * T).exp());
    let peak = r.x.iter().fold(0.0f64, |p, x| p.max(x.abs()));
    assert!(peak > 1e-3, "{peak}");
    for k in 0..r.t.len() - 1 {
        let expected = phi * r.x[k] + b / a * ((phi - mid) * r.u_f[k] + (mid - 1.0) * r.u_f[k + 1]);
        assert!((r.x[k + 1] - expected).abs() <= 1e-12 * peak, "k = {k}: {} against {expected}", r.x[k + 1]);
    }
    // Held whole over each sample instead, the same inputs miss the states: the split matters.
    let whole = (0..r.t.len() - 1).map(|k| (r.x[k + 1] - phi * r.x[k] - b / a * (phi - 1.0) * r.u_f[k]).abs());
    assert!(whole.fold(0.0, f64::max) > 1e-6 * peak);
}

/// Two inputs, one delayed by a fraction of a sample beyond a whole one and clipped, the other by
/// whole samples: on a diagonal plant (x_i' = a_i x_i + b_i u_p,i) each state follows its own
/// closed form, the fractional one's switching within the sample and the whole one's not, with the
/// recorded (clipped) inputs; to 1e-12 of each state's peak.
#[test]
fn fractional_and_whole_actuator_delays_mix_under_a_limit() {
    let (a, b, T) = ([0.5f64, -0.8], [2.0f64, 1.5], 1e-3f64);
    let text = format!(
        "[plant]\nA = [[{}, 0.0], [0.0, {}]]\nB = [[{}, 0.0], [0.0, {}]]\nC = [[1.0, 0.0], [0.0, 1.0]]\nD = [[1.0], [1.0]]\nQ = [[0.0], [0.0]]\ndelays = [0.0, 0.0]\nx0 = [0.5, -0.3]\n[design]\nobserver_poles = [-3.0, -4.0]\nchannel_poles = [[-2.0], [-2.5]]\nreference_filter_poles = [[-1.0, -2.0], [-1.0, -2.0]]\ndisturbance_filter_poles = [[-1.0]]\nmu = [1.0, 1.0]\nbeta = 1.0\n[reference]\ncomponents = [{{ harmonics = [{{ amplitude = 1.0, frequency = 3.0 }}] }}, {{ harmonics = [{{ amplitude = 0.5, frequency = 2.0 }}] }}]\n[disturbance]\ncomponents = [{{ bias = 0.0 }}]\n[simulation]\nt_end = 0.5\noutput_step = {T}\nsample_time = {T}\n[truth]\nactuator_delays = [0.0013, 0.002]\nu_max = [0.2, inf]\n",
        a[0], a[1], b[0], b[1]
    );
    let s = Scenario::from_toml(&text).unwrap();
    let d = s.design().unwrap();
    let settings = RunSettings { record_states: true, ..RunSettings::of(&s) };
    let r = Run::of(&s, &d).settings(settings).simulate(|_| ControlFlow::Continue(())).unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    // The limit clipped input 1 at some samples, so the check covers the clip.
    let top = r.u_f.iter().step_by(2).fold(0.0f64, |m, u| m.max(u.abs()));
    assert!(top == 0.2, "input 1 never reached its limit: {top}");
    let f = [0.3, 0.0];
    for i in 0..2 {
        let (phi, mid) = ((a[i] * T).exp(), (a[i] * (1.0 - f[i]) * T).exp());
        let x = |k: usize| r.x[k * 2 + i];
        let u = |k: usize| r.u_f[k * 2 + i];
        let peak = (0..r.t.len()).fold(0.0f64, |p, k| p.max(x(k).abs()));
        for k in 0..r.t.len() - 1 {
            // Whole (f = 0): u(k) over the whole sample; fractional: u(k), then u(k + 1).
            let later = if f[i] > 0.0 { u(k + 1) } else { u(k) };
            let expected = phi * x(k) + b[i] / a[i] * ((phi - mid) * u(k) + (mid - 1.0) * later);
            assert!(
                (x(k + 1) - expected).abs() <= 1e-12 * peak,
                "x{}: k = {k}: {} against {expected}",
                i + 1,
                x(k + 1)
            );
        }
    }
}

/// True delays of the commands a fraction of a sample beyond whole ones, each input with its own
/// (τ₁ = 1.3 T against the model's T, τ₂ = 0.6 T against 0): on a diagonal plant
/// (x_i' = a_i x_i + b_i u_p,i) the plant's input over sample k is the recorded u_f,i(k) (which
/// reads u_i(k − c_i − 1), τ_i = (c_i + f_i) T) until kT + f_i T, then that plus
/// F_ii (u_i(k − c_i) − u_i(k − c_i − 1)), the command that has arrived since; each state follows
/// its closed form with the recorded commands and inputs and the design's F, to 1e-12 of its peak.
#[test]
fn a_fractional_true_delay_moves_the_command_within_the_sample() {
    let (a, b, T) = ([0.5f64, -0.8], [2.0f64, 1.5], 1e-3f64);
    let text = format!(
        "[plant]\nA = [[{}, 0.0], [0.0, {}]]\nB = [[{}, 0.0], [0.0, {}]]\nC = [[1.0, 0.0], [0.0, 1.0]]\nD = [[1.0], [1.0]]\nQ = [[0.0], [0.0]]\ndelays = [{T}, 0.0]\nx0 = [0.5, -0.3]\n[design]\nobserver_poles = [-3.0, -4.0]\nchannel_poles = [[-2.0], [-2.5]]\nreference_filter_poles = [[-1.0, -2.0], [-1.0, -2.0]]\ndisturbance_filter_poles = [[-1.0]]\nmu = [1.0, 1.0]\nbeta = 1.0\n[reference]\ncomponents = [{{ harmonics = [{{ amplitude = 1.0, frequency = 3.0 }}] }}, {{ harmonics = [{{ amplitude = 0.5, frequency = 2.0 }}] }}]\n[disturbance]\ncomponents = [{{ bias = 0.0 }}]\n[simulation]\nt_end = 0.5\noutput_step = {T}\nsample_time = {T}\n[truth]\ndelays = [{}, {}]\n",
        a[0], a[1], b[0], b[1], 1.3 * T, 0.6 * T
    );
    let s = Scenario::from_toml(&text).unwrap();
    let d = s.design().unwrap();
    let F = d.F();
    assert!(F[(0, 1)] == 0.0 && F[(1, 0)] == 0.0, "a diagonal plant decouples with a diagonal F: {F}");
    let settings = RunSettings { record_states: true, ..RunSettings::of(&s) };
    let r = Run::of(&s, &d).settings(settings).simulate(|_| ControlFlow::Continue(())).unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    let (c, f) = ([1usize, 0], [0.3, 0.6]);
    for i in 0..2 {
        let (phi, mid) = ((a[i] * T).exp(), (a[i] * (1.0 - f[i]) * T).exp());
        let x = |k: usize| r.x[k * 2 + i];
        let command = |k: usize, back: usize| if k >= back { r.u[(k - back) * 2 + i] } else { 0.0 };
        let peak = (0..r.t.len()).fold(0.0f64, |p, k| p.max(x(k).abs()));
        let mut moved = 0.0f64;
        for k in 0..r.t.len() - 1 {
            let early = r.u_f[k * 2 + i];
            let arrived = F[(i, i)] * (command(k, c[i]) - command(k, c[i] + 1));
            moved = moved.max(arrived.abs());
            let expected = phi * x(k) + b[i] / a[i] * ((phi - mid) * early + (mid - 1.0) * (early + arrived));
            assert!(
                (x(k + 1) - expected).abs() <= 1e-12 * peak,
                "x{}: k = {k}: {} against {expected}",
                i + 1,
                x(k + 1)
            );
        }
        // The commands moved within the samples, so the check covers the switch.
        assert!(moved > 1e-6 * peak, "x{}: {moved}", i + 1);
    }
}

/// A room heated by a 0 … 3 kW heater run at 1 kW (x' = (2 u − x)/600, x in °C from the operating
/// point, u in kW from 1 kW): u_f ranges over [−1, 2], `[truth] u_min` and `u_max`. `reference`
/// is g's component.
fn heater(reference: &str, range: &str) -> Scenario {
    // One filter pole for a bias, three for a bias and a harmonic.
    let poles = if reference.contains("harmonics") { "[-0.002, -0.003, -0.004]" } else { "[-0.002]" };
    let text = format!(
        "[plant]\nA = [[-0.0016666666666666668]]\nB = [[0.0033333333333333335]]\nC = [[1.0]]\ndelays = [30.0]\n[design]\nobserver_poles = [-0.02]\nchannel_poles = [[-0.005]]\nreference_filter_poles = [{poles}]\nmu = [1.0]\nbeta = 1.0\n[reference]\ncomponents = [{reference}]\n[simulation]\nt_end = 9000.0\noutput_step = 10.0\nsample_time = 10.0\n[truth]\n{range}\n"
    );
    Scenario::from_toml(&text).unwrap()
}

/// A range that is not symmetric: the heater cools the room by at most 2 °C (u_f ≥ −1 kW, the
/// steady gain being 2 °C/kW) and heats it by up to 4 °C. Its steady input for g = −3 °C is
/// −1.5 kW, within ±2 but below u_min: the steady-state advice says so (and not for ±2); the run
/// is clipped at −1 and never below, so y settles at −2 °C (the DC gain × u_min, to 1e-3); the
/// written scenario keeps the range, and a symmetric one writes no u_min.
#[test]
fn a_range_that_is_not_symmetric_clips_each_side_at_its_own_limit() {
    let cool = "{ bias = -3.0 }";
    let steady = heater(cool, "u_max = [2.0]\nu_min = [-1.0]").steady_input();
    // −3 °C / 2 °C/kW, to rounding.
    assert!(steady.range[0].iter().all(|u| (u + 1.5).abs() < 1e-12), "{:?}", steady.range);
    assert_eq!(steady.advice.len(), 1, "{:?}", steady.advice);
    assert!(
        steady.advice[0].starts_with("u_f[1]: the steady-state input (RMS 1.5, from -1.5 to -1.5) against the actuator range truth.u_min … u_max = -1 … 2 exceeds it: tracking g and rejecting ω exactly is impossible"),
        "{}",
        steady.advice[0]
    );
    assert!(heater(cool, "u_max = [2.0]").steady_input().advice.is_empty());
    // About the same mean, a wave of ±1 kW: the range −2.5 … −0.5 reaches within the limits, but a
    // clipped input cannot average −1.5, so it is as impossible (it had read "at its peaks").
    let wave = "{ bias = -3.0, harmonics = [{ amplitude = 0.33, frequency = 0.01 }] }";
    let steady = heater(wave, "u_max = [2.0]\nu_min = [-1.0]").steady_input();
    assert!((steady.mean[0] + 1.5).abs() < 1e-12 && steady.range[0][1] > -1.0, "{steady:?}");
    assert!(
        steady.advice[0].contains("exceeds it: tracking g and rejecting ω exactly is impossible"),
        "{:?}",
        steady.advice
    );
    let s = heater(cool, "u_max = [2.0]\nu_min = [-1.0]");
    let r = Run::of(&s, &s.design().unwrap()).simulate(|_| ControlFlow::Continue(())).unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    assert!(r.u_f.iter().all(|&u| (-1.0..=2.0).contains(&u)), "{:?}", r.u_f);
    assert!(r.u_f.contains(&-1.0) && r.limited[0] > 0, "u_f reaches u_min");
    assert!((r.y.last().unwrap() + 2.0).abs() < 1e-3, "y settles at 2 u_min: {}", r.y.last().unwrap());
    assert_eq!((r.u_min.clone(), r.u_max.clone()), (vec![-1.0], vec![2.0]));
    let written = Scenario::from_toml(&s.to_toml()).unwrap();
    assert_eq!(written.actuator, s.actuator);
    let symmetric = heater(cool, "u_max = [2.0]");
    assert!(!symmetric.to_toml().contains("u_min"));
    assert_eq!(symmetric.actuator.as_ref().unwrap().lower_limit(0), -2.0);
    // No upper limit, only a lower one: u_max defaults to ∞.
    let floor = heater(cool, "u_min = [-1.0]");
    assert_eq!(
        floor.actuator.as_ref().map(|a| (a.limits.clone(), a.lower_limit(0))),
        Some((vec![f64::INFINITY], -1.0))
    );
}
