//! The continuous closed loop on the paper's example (Section VIII): convergence, channel
//! independence (the paper's main claim), agreement with an independent solver and across tolerances.
#![allow(non_snake_case)]

mod common;

use common::*;
use std::ops::ControlFlow;

use quell::nalgebra::DVector;
use quell::sim::{Outcome, Run, RunSettings, SimResult};
use quell::Design;

#[test]
fn paper_example_converges() {
    // max |e_1| on [90, 100] < 0.05 and max |e_2| < 0.005 (an independent solution gives
    // ≈ 0.027 and 0.002).
    let r = run_paper(paper_spec(), 100.0, 0.1, 1e-9);
    let (e1, e2) = (r.max_abs_error(0, 90.0, 100.0).unwrap(), r.max_abs_error(1, 90.0, 100.0).unwrap());
    assert!(e1 < 0.05 && e2 < 0.005, "tail errors {e1} {e2}");
    assert_eq!(r.len(), 1001);
}

#[test]
fn paper_example_matches_independent_reference() {
    // quell at rtol = atol = 1e-10 must match the independent solver's points to 1e-6.
    assert_matches_reference_points(&run_paper(paper_spec(), 100.0, 0.1, 1e-10));
}

#[test]
fn tolerance_1e9_agrees_with_1e12() {
    // The run at rtol = atol = 1e-9 agrees with the same run at 1e-12 to 1e-7 (y, u and η̂
    // at every output sample).
    let a = run_paper(paper_spec(), 100.0, 0.1, 1e-9);
    let b = run_paper(paper_spec(), 100.0, 0.1, 1e-12);
    for (name, x, y) in [("y", &a.y, &b.y), ("u", &a.u, &b.u), ("eta", &a.eta, &b.eta)] {
        let dev = x.iter().zip(y.iter()).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max);
        assert!(dev < 1e-7, "{name}: max deviation {dev:e}");
    }
}

#[test]
fn channel_independence_mu1_leaves_channel_2_unchanged() {
    // The paper's main claim: with the decoupler in place, channel
    // 2's trajectory does not depend on μ_1. Both runs at 1e-12, so the solver's error is ~1e-10 and
    // the 1e-8 bound tests the claim, not the solver.
    let base = run_paper(paper_spec(), 60.0, 0.1, 1e-12);
    let mut spec = paper_spec();
    spec.mu[0] = 5.0;
    let other = run_paper(spec, 60.0, 0.1, 1e-12);
    let col = |r: &SimResult, s: &Vec<f64>| r.column(s, 2, 1).collect::<Vec<_>>();
    let dev = |a: Vec<f64>, b: Vec<f64>| a.iter().zip(&b).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max);
    assert!(dev(col(&base, &base.y), col(&other, &other.y)) < 1e-8);
    assert!(dev(col(&base, &base.u), col(&other, &other.u)) < 1e-8);
    // ... while channel 1 does change (the test can fail).
    assert!(dev(base.column(&base.y, 2, 0).collect(), other.column(&other.y, 2, 0).collect()) > 1e-3);
}

/// u_f(t_k) recomputed from the recorded x̂ and u with the design's K and F (eq. (5)): −K x̂(t_k) +
/// F [u_1(t_k − τ_1), …], u before t = 0 being 0, the delays whole numbers `shift` of rows. Returns
/// the largest deviation from the recorded u_f and the largest |u_f|.
fn plant_input_deviation(r: &SimResult, d: &Design, shift: &[usize]) -> (f64, f64) {
    let (m, n) = (r.m, r.n);
    let (mut dev, mut peak) = (0.0f64, 0.0f64);
    for k in 0..r.len() {
        let x_hat = DVector::from_column_slice(&r.x_hat[k * n..(k + 1) * n]);
        let u_d =
            DVector::from_iterator(m, (0..m).map(|i| if k >= shift[i] { r.u[(k - shift[i]) * m + i] } else { 0.0 }));
        let want = d.F() * u_d - d.K() * x_hat;
        for i in 0..m {
            dev = dev.max((r.u_f[k * m + i] - want[i]).abs());
            peak = peak.max(want[i].abs());
        }
    }
    (dev, peak)
}

#[test]
fn plant_input_is_recorded_as_minus_K_x_hat_plus_F_delayed_u() {
    // The continuous loop, with true delays that differ from the design's (τ = [1, 3] designed,
    // [1.05, 3] true: u_f is the input the true plant receives) and x0 ≠ 0. The delays are whole
    // numbers of output steps, so u(t − τ) is a recorded sample; the loop reads it from the
    // integrator's history, the same dense output, so both agree to rounding (1e-10 of the peak).
    let d = Design::new(&paper_plant(), &paper_spec()).unwrap();
    let (g, w) = paper_signals();
    let mut truth = paper_plant();
    truth.delays = vec![1.05, 3.0];
    truth.x0 = DVector::from_column_slice(&[0.5, -0.2, 0.1]);
    let st = RunSettings { record_states: true, ..RunSettings::continuous(20.0, 0.05, 1e-9, 1e-9) };
    let r = Run::new(&d, &g, &w, st).truth(&truth).simulate(|_| ControlFlow::Continue(())).unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    assert_eq!((r.x.len(), r.x_hat.len()), (3 * r.len(), 3 * r.len()));
    // Row 0: x = x0 as given.
    assert_eq!(r.x[..3], [0.5, -0.2, 0.1]);
    let (dev, peak) = plant_input_deviation(&r, &d, &[21, 60]);
    assert!(peak > 1.0 && dev <= 1e-10 * peak, "max deviation {dev:e}, peak {peak}");
    // With the design's delays instead the check fails: the test tells the delays apart.
    let (dev, _) = plant_input_deviation(&r, &d, &[20, 60]);
    assert!(dev > 1e-3 * peak, "{dev:e}");

    // The sampled-data loop: u_f(k) = −K x̂(k) + F u(k − d_i) exactly (d = τ / T_s samples).
    let st = RunSettings { record_states: true, ..RunSettings::sampled(20.0, 0.01, 0.01) };
    let r = Run::new(&d, &g, &w, st).simulate(|_| ControlFlow::Continue(())).unwrap();
    let (dev, peak) = plant_input_deviation(&r, &d, &[100, 300]);
    assert!(peak > 1.0 && dev <= 1e-12 * peak, "sampled: max deviation {dev:e}, peak {peak}");
}

/// Under a true actuator limit, `u_f` holds what the plant received, u_f clipped, and `max_uf` what
/// the controller asked for, −K x̂ + F u_d before the clip: the figure an actuator limit is checked
/// against (a tuning's limit of 5 V had been met by every μ, the clip holding u_f at 5). Recomputed
/// from the recorded x̂ and u as above; the limit 10 clips u_f,1 of the paper's loop (its peak about
/// 15), and the loop completes. Both loops.
#[test]
fn a_clipped_plant_input_reports_what_the_controller_asked_for() {
    let d = Design::new(&paper_plant(), &paper_spec()).unwrap();
    let (g, w) = paper_signals();
    let limit = 10.0;
    let actuator =
        Some(quell::settings::Actuator { delays: vec![0.0; 2], limits: vec![limit, f64::INFINITY], lower: None });
    let loops = [
        (RunSettings::continuous(20.0, 0.05, 1e-9, 1e-9), [20, 60], 1e-9),
        (RunSettings::sampled(20.0, 0.01, 0.01), [100, 300], 1e-12),
    ];
    for (settings, shift, tol) in loops {
        let st = RunSettings { record_states: true, actuator: actuator.clone(), ..settings };
        let r = Run::new(&d, &g, &w, st).simulate(|_| ControlFlow::Continue(())).unwrap();
        assert_eq!(r.outcome, Some(Outcome::Completed));
        let (m, n) = (r.m, r.n);
        let mut demand = 0.0f64;
        for k in 0..r.len() {
            let x_hat = DVector::from_column_slice(&r.x_hat[k * n..(k + 1) * n]);
            let u_d = DVector::from_iterator(
                m,
                (0..m).map(|i| if k >= shift[i] { r.u[(k - shift[i]) * m + i] } else { 0.0 }),
            );
            let want = (d.F() * u_d - d.K() * x_hat)[0];
            let got = r.u_f[k * m];
            assert!((got - want.clamp(-limit, limit)).abs() <= tol * limit, "row {k}: u_f,1 = {got}, clip({want})");
            demand = demand.max(want.abs());
        }
        let max_uf = r.summary()[0].figures.max_uf;
        assert!(demand > 1.2 * limit, "the limit clips: the controller asked for {demand}");
        // The rows' demand, and at most 2 % more between them (a step end on the same trajectory).
        assert!(max_uf >= demand * (1.0 - 1e-9) && max_uf <= 1.02 * demand, "max_uf {max_uf}, rows' demand {demand}");
        assert!(r.limited_fraction()[0] > 0.0 && r.limited_fraction()[1] == 0.0);
    }
}

/// The sampled loop watches its states at every controller step, not only at the rows: on a true
/// plant with the delays 4× the design's, rows 50 s apart had named the divergence at t = 34.6 s,
/// by a controller input of 1.1e100, where rows 0.1 s apart named a plant state at 11.2 s (helper
/// tryout, 2026-12-06). Both now end at the same controller step, on the same signal.
#[test]
fn a_sampled_run_diverges_at_the_same_step_whatever_its_output_step() {
    let d = Design::new(&paper_plant(), &paper_spec()).unwrap();
    let (g, w) = paper_signals();
    let mut truth = paper_plant();
    truth.delays = vec![4.0, 12.0];
    let ended = |output_step: f64| {
        let r = Run::new(&d, &g, &w, RunSettings::sampled(200.0, output_step, 0.01))
            .truth(&truth)
            .simulate(|_| ControlFlow::Continue(()))
            .unwrap();
        match r.outcome {
            Some(Outcome::Diverged { t, signal, .. }) => (t, signal, r.stats.steps()),
            other => panic!("output step {output_step}: {other:?}"),
        }
    };
    let (fine, coarse) = (ended(0.1), ended(50.0));
    assert_eq!(fine, coarse);
    assert!(fine.0 < 20.0 && fine.1.contains("state"), "{fine:?}");
}

/// A sample time that divides the output step to the whole-number tolerance but not exactly (1/30 s
/// to ten digits: the delays' nearest valid sample time as a message prints it) records its rows at
/// k·output_step, the last at t_end, as the continuous loop does: they had fallen at k·T, 0.0999999999,
/// 0.1999999999, …, 9.999999999, and settling times read off them printed so.
#[test]
fn sampled_rows_fall_on_the_output_grid() {
    let d = Design::new(&paper_plant(), &paper_spec()).unwrap();
    let (g, w) = paper_signals();
    let r = Run::new(&d, &g, &w, RunSettings::sampled(10.0, 0.1, 0.03333333333))
        .simulate(|_| ControlFlow::Continue(()))
        .unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    // Each row's time is the decimal k/10, as it parses.
    let expected: Vec<f64> = (0..=100).map(|k| format!("{}.{}", k / 10, k % 10).parse().unwrap()).collect();
    assert_eq!(r.t, expected);
}

/// The peaks of u, u_f and e count the solver's step ends (continuous loop) and every controller
/// step (sampled), not only the rows: the paper's example with rows 10 s apart reports max |u_i|,
/// max |u_f,i| and max |e_i| ([`SimResult::peak_error`]) within 2 % of what rows 1 ms apart read (the same trajectory: the output step does
/// not move the steps, whose ends are ~0.15 s apart, ±1.2 % of a 2 rad/s peak), where those 11
/// rows alone read up to 40 % less (e: 85 %); and never above it (a step end is a point of that trajectory;
/// 1e-6 for the fine rows' own sampling). Sampled, rows 1 s apart report the peaks of rows at every
/// sample exactly. The fine rows' peak equals the summary's.
#[test]
fn the_input_peaks_count_what_falls_between_rows_and_states_are_recorded_only_when_asked() {
    let d = Design::new(&paper_plant(), &paper_spec()).unwrap();
    let (g, w) = paper_signals();
    let figures = |r: &SimResult| {
        r.summary()
            .iter()
            .enumerate()
            .map(|(i, c)| [c.figures.max_u, c.figures.max_uf, r.peak_error(i).unwrap()])
            .collect::<Vec<_>>()
    };
    let rows_peak =
        |r: &SimResult, column: &[f64], i: usize| r.column(column, 2, i).fold(0.0, |a: f64, v| a.max(v.abs()));
    let fine = run_paper(paper_spec(), 100.0, 0.001, 1e-9);
    let coarse = run_paper(paper_spec(), 100.0, 10.0, 1e-9);
    for (i, (f, c)) in figures(&fine).iter().zip(figures(&coarse)).enumerate() {
        assert_eq!(f[1], rows_peak(&fine, &fine.u_f, i), "the fine rows hold the peak");
        for k in 0..3 {
            let rows = rows_peak(&coarse, [&coarse.u, &coarse.u_f, &coarse.e][k], i);
            println!("channel {i} {}: fine {:.4}, coarse {:.4}, its rows {rows:.4}", ["u", "u_f", "e"][k], f[k], c[k]);
            assert!(c[k] >= 0.98 * f[k] && c[k] <= f[k] * (1.0 + 1e-6), "channel {i}: {c:?} against {f:?}");
        }
        assert!(c[1] != c[0], "u_f is not the command u: {c:?}");
    }
    assert!(fine.x.is_empty() && fine.x_hat.is_empty() && !fine.has_states());
    let sampled = |output_step: f64| {
        let r =
            Run::new(&d, &g, &w, RunSettings::sampled(20.0, output_step, 0.01)).simulate(|_| ControlFlow::Continue(()));
        figures(&r.unwrap())
    };
    assert_eq!(sampled(1.0), sampled(0.01));
}

/// `simulation.method` reaches the integrator. The paper's example is not stiff at μ = [20, 30], so
/// DOP853 (order 8) and the implicit–explicit ARK4(3)6L\[2\]SA (order 4, implicit in η̂) integrate
/// the same loop with different error estimates: each must match the independent solver's points
/// (1e-12; accurate to ~1e-8) to the reference bound 1e-6, and the two must agree with each other
/// over every sample of y and u to 1e-6 of the output's peak (each is within about
/// 100·rtol·peak of the exact solution at rtol = 1e-9, the bound the 1e-9 vs 1e-12 test above uses).
#[test]
fn the_scenario_method_chooses_the_integrator_and_explicit_and_imex_agree() {
    use quell::scenario::{Scenario, PAPER_EXAMPLE};
    use quell::sim::{Method, RunStats};
    let run = |name: &str| {
        let text = PAPER_EXAMPLE.replacen("atol = 1e-9\n", &format!("atol = 1e-9\nmethod = \"{name}\"\n"), 1);
        let s = Scenario::from_toml(&text).unwrap();
        assert_eq!(s.simulation.method.name(), name);
        let r = Run::of(&s, &s.design().unwrap()).simulate(|_| ControlFlow::Continue(())).unwrap();
        assert_eq!(r.outcome, Some(Outcome::Completed), "{name}");
        assert_matches_reference_points(&r);
        r
    };
    let (explicit, imex) = (run("explicit"), run("imex"));
    let implicit_steps = |r: &SimResult| match r.stats {
        RunStats::Continuous(s) => (s.implicit_steps, s.steps),
        RunStats::Sampled { .. } => unreachable!(),
    };
    assert_eq!(implicit_steps(&explicit).0, 0);
    let (implicit, steps) = implicit_steps(&imex);
    assert!(implicit == steps && steps > 0, "imex: {implicit} of {steps} steps implicit");
    let peak = explicit.y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (what, a, b) in [("y", &explicit.y, &imex.y), ("u", &explicit.u, &imex.u)] {
        let dev = a.iter().zip(b.iter()).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / peak;
        assert!(dev < 1e-6, "{what}: explicit and imex differ by {dev:e} of the peak");
    }
    // Absent, the key means the automatic method, which on this loop never switches.
    let auto = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    assert_eq!(auto.simulation.method, Method::Auto);
}

/// The paper's example in other units of time: t → αt, so A, B, D, every pole and μ divide by α
/// and the delays, β, t_end and the output step multiply by it (observer poles −2, −3, −4 and the
/// normalized regressor, whose ξ̂ does not depend on the filters' time scale: the paper's l = e_q
/// would scale ξ̂ by α^q). The loop is then the same one in other units: y, u, u_f and η̂ at αt are
/// those at t.
fn paper_in_time_units(alpha: f64, tol: f64) -> (Design, SimResult) {
    paper_in_units(alpha, 1.0, 1.0, tol)
}

/// [`paper_in_time_units`] with the state also in other units: x → s x, so B, D and x(0) multiply
/// by s and C divides by it; y, u, u_f and η̂ are unchanged. And with the outputs, the reference
/// and the disturbance in other units, y → o y, ω → o ω: C multiplies by o and D divides by it, g
/// and ω's amplitudes multiply by o, and so do u, ξ̂ (normalized) and F⁻¹; Ω by o², so μ divides
/// by o²; u_f and η̂ are unchanged.
fn paper_in_units(alpha: f64, s: f64, o: f64, tol: f64) -> (Design, SimResult) {
    let p = paper_plant();
    let delays = p.delays.iter().map(|d| d * alpha).collect();
    let (B, C, D, x0) = (&p.B * (s / alpha), &p.C * (o / s), &p.D * (s / o / alpha), &p.x0 * s);
    let p = quell::Plant::new(&p.A / alpha, B, C, D, p.Q.clone(), delays, Some(x0)).unwrap();
    let poles = |v: &[f64]| v.iter().map(|&x| re(x / alpha)).collect::<Vec<_>>();
    let spec = quell::DesignSpec {
        observer: quell::ObserverChoice::Poles(poles(&[-2.0, -3.0, -4.0])),
        channel_poles: vec![poles(&[-6.0, -2.0]), poles(&[-4.0])],
        reference_filter_poles: vec![poles(&[-1.0, -6.0]), poles(&[-9.0])],
        disturbance_filter_poles: vec![poles(&[-1.0, -3.0]), poles(&[-1.0, -2.0, -3.0])],
        mu: vec![20.0 / alpha / (o * o), 30.0 / alpha / (o * o)],
        beta: alpha,
        relative_degrees: None,
        regressor_scaling: quell::design::RegressorScaling::Normalized,
        reference_sizes: Vec::new(),
        disturbance_sizes: Vec::new(),
    };
    let d = Design::new(&p, &spec).unwrap();
    let (mut g, mut w) = paper_signals();
    for h in g.components.iter_mut().chain(&mut w.components).flat_map(|c| &mut c.harmonics) {
        h.frequency /= alpha;
    }
    for c in g.components.iter_mut().chain(&mut w.components) {
        c.bias *= o;
        c.harmonics.iter_mut().for_each(|h| h.amplitude *= o);
    }
    let r = Run::new(&d, &g, &w, RunSettings::continuous(100.0 * alpha, 0.1 * alpha, tol, tol))
        .simulate(|_| ControlFlow::Continue(()))
        .unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed), "α = {alpha}, state × {s}");
    (d, r)
}

/// The divergence bound is set in the state's own scale: the paper's loop with its states in 1e9
/// and 1e-9 times their units completes (with a bound of 1e9 in the state's coordinates the first
/// stopped as "diverged" at t = 0.1 s, x̂_2 = 1.3e9) and is the same loop: y, u_f and η̂ agree with the unscaled run to 3e-5
/// of each column's peak, the bound of the units-of-time test below (each run's own error at 1e-9
/// is up to 3.1e-6 of a peak there; the scaled states change the error test's weights, so the
/// two runs' errors differ: measured up to 2.5e-6).
#[test]
fn the_loop_with_states_in_other_units_is_the_same_loop() {
    let (_, reference) = paper_in_units(1.0, 1.0, 1.0, 1e-9);
    for s in [1e9, 1e-9] {
        let (_, r) = paper_in_units(1.0, s, 1.0, 1e-9);
        for (got, want, width) in [(&r.y, &reference.y, 2), (&r.u_f, &reference.u_f, 2), (&r.eta, &reference.eta, 16)] {
            for j in 0..width {
                let peak = reference.column(want, width, j).fold(0.0f64, |p, v| p.max(v.abs()));
                let gap = r
                    .column(got, width, j)
                    .zip(reference.column(want, width, j))
                    .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                println!("state × {s:e}: column {j} of {width}: gap {:.1e} of its peak", gap / peak);
                assert!(gap <= 3e-5 * peak, "state × {s:e}: column {j}: {gap:e} against the peak {peak:e}");
            }
        }
    }
}

/// A plant whose states, outputs and reference are all 1e9 times larger (a heat store in joules,
/// its reference 7e12 J: stopped as "diverged" at x = 3e9 J, 0.04 % of it, before the bound on x
/// and x̂ counted the signals' size) completes and is the same loop: y/1e9, u_f and η̂ agree with
/// the unscaled run to 3e-5 of each column's peak (the bound of the states' test above).
#[test]
fn the_loop_with_signals_in_other_units_is_the_same_loop() {
    let (_, reference) = paper_in_units(1.0, 1.0, 1.0, 1e-9);
    let o = 1e9;
    let (_, r) = paper_in_units(1.0, o, o, 1e-9);
    for (got, want, width, unit) in
        [(&r.y, &reference.y, 2, o), (&r.u_f, &reference.u_f, 2, 1.0), (&r.eta, &reference.eta, 16, 1.0)]
    {
        for j in 0..width {
            let peak = reference.column(want, width, j).fold(0.0f64, |p, v| p.max(v.abs()));
            let gap = r
                .column(got, width, j)
                .zip(reference.column(want, width, j))
                .fold(0.0f64, |m, (a, b)| m.max((a / unit - b).abs()));
            assert!(gap <= 3e-5 * peak, "column {j} of {width}: {gap:e} against the peak {peak:e}");
        }
    }
}

#[test]
fn the_loop_in_milliseconds_or_hours_is_the_same_loop() {
    let (d1, reference) = paper_in_time_units(1.0, 1e-12);
    let (_, own) = paper_in_time_units(1.0, 1e-9);
    let largest_gap = |r: &SimResult| {
        let columns = [
            (&r.y, &reference.y, 2),
            (&r.u, &reference.u, 2),
            (&r.u_f, &reference.u_f, 2),
            (&r.eta, &reference.eta, 16),
        ];
        let mut worst: f64 = 0.0;
        for (got, want, width) in columns {
            for j in 0..width {
                let peak = reference.column(want, width, j).fold(0.0f64, |p, v| p.max(v.abs())).max(1e-300);
                let gap = r
                    .column(got, width, j)
                    .zip(reference.column(want, width, j))
                    .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                worst = worst.max(gap / peak);
            }
        }
        worst
    };
    // The runs at 1e-9 differ from the one at 1e-12 by 3.1e-6 (seconds), 1.0e-5 (ms) and 4.7e-6
    // (hours) of a column's peak (this adaptive loop amplifies the local errors): the bound is 3×
    // the largest, far below what a unit slip (a forgotten α in a filter, β or a delay) would
    // cause, an error of the signals' own size.
    assert!(largest_gap(&own) < 3e-5, "{}", largest_gap(&own));
    let diag1 = quell::diagnostics::diagnose(&d1, &paper_signals().0, &paper_signals().1, &own);
    // α = 1e8 (years, near enough): its observer poles −2e-8 … −4e-8 were "one pole requested
    // three times" before the placement worked in the poles' own time scale.
    for alpha in [1e-3, 3600.0, 1e8] {
        let (d, r) = paper_in_time_units(alpha, 1e-9);
        assert_eq!(r.len(), reference.len());
        assert!(r.t.iter().zip(&reference.t).all(|(a, b)| (a / alpha - b).abs() <= 1e-12 * b.max(1.0)));
        let gap = largest_gap(&r);
        assert!(gap < 3e-5, "α = {alpha}: largest gap {gap:e} of a column's peak");
        // The same steps, to 2 % (3,887 in ms and 3,930 in hours against 3,890; at 1e-6, 2,365 and
        // 2,370 against 2,364): the filter banks' absolute tolerances follow their rows' units
        // (with `atol` alone the run in hours took 3,976 and 2,627 steps). What remains comes from
        // the initial step's absolute floor and rounding.
        let (steps, steps1) = (r.stats.steps() as f64, own.stats.steps() as f64);
        assert!((steps / steps1 - 1.0).abs() < 0.02, "α = {alpha}: {steps} steps against {steps1}");
        let loose = |a: f64| paper_in_time_units(a, 1e-6).1.stats.steps() as f64;
        assert!(
            (loose(alpha) / loose(1.0) - 1.0).abs() < 0.02,
            "α = {alpha} at 1e-6: {} against {}",
            loose(alpha),
            loose(1.0)
        );
        // The report in the new units: rates ÷ α, times × α (settling to one output step).
        let (mut g, mut w) = paper_signals();
        for h in g.components.iter_mut().chain(&mut w.components).flat_map(|c| &mut c.harmonics) {
            h.frequency /= alpha;
        }
        let diag = quell::diagnostics::diagnose(&d, &g, &w, &r);
        for (c, c1) in diag.channels.iter().zip(&diag1.channels) {
            assert!((c.adaptation_rate * alpha / c1.adaptation_rate - 1.0).abs() < 1e-9, "{c:?}");
            assert_eq!(c.excited_rank, c1.excited_rank);
            assert_eq!(c.advice.len(), c1.advice.len(), "{:?} against {:?}", c.advice, c1.advice);
        }
        for (s, s1) in r.summary().iter().zip(own.summary()) {
            let (t, t1) = (s.figures.settle_t.unwrap(), s1.figures.settle_t.unwrap());
            assert!((t / alpha - t1).abs() <= 0.1 + 1e-9, "α = {alpha}: settled at {t} against {t1}");
        }
    }
}

/// Between recorded rows a run reports its progress every `PROGRESS_EVERY` solver or controller
/// steps, so a caller can stop a run whose only rows are t = 0 and t_end (Ctrl-C had waited for
/// the end of such a run). Stopped at the first report after t = 0, each loop has taken exactly
/// that many steps.
#[test]
fn a_run_reports_progress_between_rows() {
    use quell::scenario::{Scenario, PAPER_EXAMPLE};
    use quell::sim::PROGRESS_EVERY;
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = s.design().unwrap();
    let every = PROGRESS_EVERY;
    for (settings, steps) in [
        (RunSettings::continuous(100.0, 100.0, 1e-9, 1e-9), every),
        // The sampled loop counts its steps from k = 0, which is a row.
        (RunSettings::sampled(100.0, 100.0, 1e-3), every + 1),
    ] {
        let mut calls = Vec::new();
        let r = Run::of(&s, &d)
            .settings(settings)
            .simulate(|t| {
                calls.push(t);
                if t > 0.0 {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            })
            .unwrap();
        assert_eq!(calls.len(), 2, "t = 0, then the first report between rows: {calls:?}");
        assert!(matches!(r.outcome, Some(Outcome::Interrupted { t }) if t == calls[1] && t < 100.0), "{:?}", r.outcome);
        assert_eq!(r.stats.steps(), steps);
        assert_eq!(r.len(), 1, "only the row at t = 0 was recorded");
    }
}

/// An output in other units, with its reference's size, runs the same loop: the paper's y₁ in mm
/// (C's and Q's first rows, g₁ × 1000, L's first column ÷ 1000) with `reference_sizes = [3000, 2]`
/// against the paper with [3, 2]. The sizes divide ξ̂'s blocks, so ξ̂ is the same in both, η̂₁ and
/// u_d₁ carry the factor 1000, and y₁/1000, y₂ and u_f (the plant's input, whose units did not
/// change) agree to 1e-6 of their peaks (both at rtol = atol = 1e-9 over 20 s; the error tests
/// see η̂₁ 1000× larger, so the two take different steps, each within about 1e-7 of the truth).
/// Without the sizes the mm loop is another one: Ω̄₁ spreads by 1e6 and y₁ departs (the test can
/// fail).
#[test]
fn an_output_in_millimetres_with_its_size_runs_the_same_loop() {
    let sized = |spec: &mut quell::DesignSpec, first: f64| spec.reference_sizes = vec![first, 2.0];
    let mut spec = paper_spec();
    sized(&mut spec, 3.0);
    let base = run_paper(spec, 20.0, 0.1, 1e-9);

    let p = paper_plant();
    let mut C = p.C.clone();
    let mut Q = p.Q.clone();
    C.row_mut(0).scale_mut(1000.0);
    Q.row_mut(0).scale_mut(1000.0);
    let mm = quell::Plant::new(p.A.clone(), p.B.clone(), C, p.D.clone(), Q, p.delays.clone(), None).unwrap();
    let mut L = paper_L();
    L.column_mut(0).scale_mut(1e-3);
    let (mut g, w) = paper_signals();
    g.components[0].harmonics[0].amplitude = 3000.0;
    let run = |spec: &quell::DesignSpec| {
        let d = Design::new(&mm, spec).unwrap();
        Run::new(&d, &g, &w, RunSettings::continuous(20.0, 0.1, 1e-9, 1e-9))
            .simulate(|_| ControlFlow::Continue(()))
            .unwrap()
    };
    let mut spec = paper_spec();
    spec.observer = quell::design::ObserverChoice::Gain(L);
    sized(&mut spec, 3000.0);
    let other = run(&spec);
    assert_eq!(other.outcome, Some(Outcome::Completed));
    let worst = |a: &SimResult, b: &SimResult, of: fn(&SimResult) -> &Vec<f64>, i: usize, scale: f64| {
        let peak = a.column(of(a), 2, i).fold(0.0f64, |p, v| p.max(v.abs()));
        let dev = a.column(of(a), 2, i).zip(b.column(of(b), 2, i)).map(|(x, y)| (x - y / scale).abs());
        dev.fold(0.0, f64::max) / peak
    };
    for (name, of, i, scale) in [
        ("y1", (|r| &r.y) as fn(&SimResult) -> &Vec<f64>, 0, 1000.0),
        ("y2", |r| &r.y, 1, 1.0),
        ("uf1", |r| &r.u_f, 0, 1.0),
        ("uf2", |r| &r.u_f, 1, 1.0),
        ("u1", |r| &r.u, 0, 1000.0),
    ] {
        let d = worst(&base, &other, of, i, scale);
        assert!(d <= 1e-6, "{name}: {d:e} of its peak");
    }
    spec.reference_sizes.clear();
    let without = run(&spec);
    let n = without.len().min(base.len());
    let dev = (0..n).map(|k| (without.y[2 * k] / 1000.0 - base.y[2 * k]).abs()).fold(0.0, f64::max);
    assert!(dev > 1e-2, "without the sizes y₁ should depart: {dev:e}");
}

/// `plant.xhat0`, the controller's initial estimate of the state. Without a disturbance the
/// observer's error obeys e' = (A − LC) e (6), so e(t) = exp((A − LC) t)(x0 − x̂0): held to that
/// closed form (nalgebra's matrix exponential, not the loop's) to 1e-7 of |x0| at 20 samples, with
/// x̂0 = 0 (the default) and x̂0 = x0, where the error stays 0. The sampled-data controller starts
/// and resets there, and the scenario writes it back.
#[test]
fn the_observer_starts_at_the_estimate_given() {
    let base = quell::scenario::PAPER_EXAMPLE
        .replace("D = [[1.0, -3.0], [2.0, 1.0], [3.0, 1.0]]\n", "")
        .replace("Q = [[1.0, 2.0], [1.0, 0.0]]\n", "")
        .replace("x0 = [0.0, 0.0, 0.0]", "")
        .replace("disturbance_filter_poles = [[-1.0, -3.0], [-1.0, -2.0, -3.0]]", "");
    let cut = base.find("[disturbance]").unwrap();
    let end = cut + base[cut..].find("[simulation]").unwrap();
    let base = format!("{}{}", &base[..cut], &base[end..]);
    let x0 = [0.5, -0.3, 0.2];
    for xhat0 in [[0.0; 3], x0] {
        let text = base.replacen("[plant]\n", &format!("[plant]\nx0 = {x0:?}\nxhat0 = {xhat0:?}\n"), 1);
        let s = quell::Scenario::from_toml(&text).unwrap();
        assert_eq!(s.plant.xhat0.as_slice(), xhat0);
        let d = s.design().unwrap();
        let st = RunSettings { record_states: true, ..RunSettings::continuous(2.0, 0.1, 1e-10, 1e-10) };
        let r = Run::new(&d, &s.reference, &s.disturbance, st).simulate(|_| ControlFlow::Continue(())).unwrap();
        assert_eq!(r.outcome, Some(Outcome::Completed));
        let a_lc = &d.plant().A - d.L() * &d.plant().C;
        let e0 = DVector::from_column_slice(&x0) - DVector::from_column_slice(&xhat0);
        for (k, &t) in r.t.iter().enumerate() {
            let want = (&a_lc * t).exp() * &e0;
            for i in 0..3 {
                let e = r.x[3 * k + i] - r.x_hat[3 * k + i];
                assert!((e - want[i]).abs() <= 1e-7 * 0.5, "t = {t}, e[{i}] = {e:e} against {:e}", want[i]);
            }
        }
        let mut c = quell::Controller::new(&d, 0.01).unwrap();
        assert_eq!(c.x_hat(), xhat0);
        c.step(&[0.1, 0.2], &[0.0, 1.0]).unwrap();
        c.reset();
        assert_eq!(c.x_hat(), xhat0);
        let back = quell::Scenario::from_toml(&s.to_toml()).unwrap();
        assert_eq!(back.plant.xhat0, s.plant.xhat0);
    }
    // The divergence bound scales with x̂(0) as with x(0): an estimate of 2e9 beside a true plant
    // that starts there (plant.x0 left at 0) is no divergence at t = 0 (diff review, 2026-12-07).
    let big = format!(
        "{}\n[truth]\nx0 = [2e9, 0.0, 0.0]\n",
        base.replacen("[plant]\n", "[plant]\nxhat0 = [2e9, 0.0, 0.0]\n", 1)
    );
    let s = quell::Scenario::from_toml(&big).unwrap();
    let d = s.design().unwrap();
    let st = RunSettings::continuous(1.0, 0.1, 1e-8, 1e-8);
    let r = Run::new(&d, &s.reference, &s.disturbance, st)
        .truth(s.true_plant())
        .simulate(|_| ControlFlow::Continue(()))
        .unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    let wrong = base.replacen("[plant]\n", "[plant]\nxhat0 = [0.1, 0.2]\n", 1);
    let e = quell::Scenario::from_toml(&wrong).unwrap_err().to_string();
    assert!(e.starts_with("plant.xhat0: expected 3 entries (one per state, n = 3 rows of plant.A), found 2"), "{e}");
}
