//! The applications gallery (`examples/apps/`, `docs/applications.md`): every application's
//! scenario runs as written (its `[truth]`, sampled-data loop at the exported controller's rate) and
//! its tail errors stay within the bounds its page states; its exported C is what `quell export`
//! writes today, compiles with gcc and is the Rust controller; its study runs (a few draws) and its
//! summary holds. The supply vessel's thrust limits and measurement noise are checked against
//! independent computations.
#![allow(non_snake_case)]

mod c_harness;

use std::ops::ControlFlow;
use std::path::PathBuf;

use c_harness::{CController, TempDir};
use quell::auto::{auto_design, Targets};
use quell::export::{generate, ExportOptions, Precision};
use quell::scenario::Scenario;
use quell::sim::{Outcome, Run, SimResult};
use quell::study::{sweep, Shard, Study, StudyMeta, Summary, SweepOptions};
use quell::Controller;

/// An application of the gallery: its folder, the prefix of its exported C and the tail bounds its
/// page states (max |e_i| over the last 10 % of the horizon, per channel).
struct App {
    dir: &'static str,
    prefix: &'static str,
    tail_bounds: &'static [f64],
}

/// examples/apps/supply-vessel/README.md: measured 0.106 m, 0.044 m, 2.0e-3 rad over
/// t ∈ [540, 600] s (2026-12-03); the bounds are the page's, about 1.5× the measured values (a change in the
/// sampled loop's arithmetic moves them by far less; a change in the physics or the design by more).
const VESSEL: App = App { dir: "supply-vessel", prefix: "supply", tail_bounds: &[0.15, 0.07, 3e-3] };
/// examples/apps/dc-motor/README.md: measured 1.045e-3 rad over t ∈ [54, 60] s; bound 1.25×.
const MOTOR: App = App { dir: "dc-motor", prefix: "motor", tail_bounds: &[1.3e-3] };
/// examples/apps/active-suspension/README.md: measured 1.5e-8 m over t ∈ [27, 30] s, still
/// shrinking (the adaptive law converges exponentially on an exact internal model); the page
/// states "below 0.1 µm" against the passive bus's 47 mm.
const SUSPENSION: App = App { dir: "active-suspension", prefix: "suspension", tail_bounds: &[1e-7] };

const APPS: [App; 3] = [VESSEL, MOTOR, SUSPENSION];

fn folder(app: &App) -> PathBuf {
    PathBuf::from(format!("{}/../../examples/apps/{}", env!("CARGO_MANIFEST_DIR"), app.dir))
}

fn scenario_text(app: &App) -> String {
    std::fs::read_to_string(folder(app).join("scenario.toml")).unwrap()
}

fn run(s: &Scenario) -> SimResult {
    Run::of(s, &s.design().unwrap()).simulate(|_| ControlFlow::Continue(())).unwrap()
}

/// Runs the scenario to completion and returns max |e_i| over the last 10 % of the horizon.
fn tail_errors(s: &Scenario) -> (SimResult, Vec<f64>) {
    let r = run(s);
    assert_eq!(r.outcome, Some(Outcome::Completed), "{:?}", s.name);
    let e = r.summary().iter().map(|c| c.figures.tail_max_e).collect();
    (r, e)
}

fn assert_within(app: &App, e: &[f64]) {
    for (i, (e, b)) in e.iter().zip(app.tail_bounds).enumerate() {
        assert!(e <= b, "{} channel {}: tail max |e| = {e:e} > {b:e}", app.dir, i + 1);
    }
}

#[test]
fn every_app_holds_its_stated_tail_errors() {
    for app in &APPS {
        let s = Scenario::from_toml(&scenario_text(app)).unwrap();
        assert!(s.truth_differs(), "{}: the scenario simulates a true plant the design does not know", app.dir);
        assert!(s.simulation.sample_time.is_some(), "{}: the sampled-data loop at the controller's rate", app.dir);
        let (_, e) = tail_errors(&s);
        assert_within(app, &e);
    }
}

#[test]
fn the_active_suspension_holds_the_body_where_the_passive_one_moves_47_mm() {
    // The passive bus on the same road, from the source's transfer function (Control Tutorials,
    // "Suspension: System Modeling"): X1/W = (b1 s + K1)(b2 s + K2)/Δ(s), with
    // Δ = (M1 s² + b1 s + K1)(M2 s² + (b1 + b2) s + K1 + K2) − (b1 s + K1)², at s = 2πi (1 Hz);
    // written out here as an independent check of the scenario's state-space matrices.
    let (M1, M2, K1, K2, b1, b2) = (2500.0f64, 320.0, 80_000.0, 500_000.0, 350.0, 15_020.0);
    let s = nalgebra::Complex::new(0.0, 2.0 * std::f64::consts::PI);
    let delta = (s * s * M1 + s * b1 + K1) * (s * s * M2 + s * (b1 + b2) + K1 + K2) - (s * b1 + K1).powi(2);
    let passive = ((s * b1 + K1) * (s * b2 + K2) / delta).norm() * 0.020;
    assert!((passive - 0.04724).abs() < 1e-5, "passive body amplitude {passive} m");
    // The same transfer function from the scenario's [plant] (W in mm): C (sI − A)⁻¹ D · 1000.
    let sc = Scenario::from_toml(&scenario_text(&SUSPENSION)).unwrap();
    let (A, D, C) = (&sc.plant.A, &sc.plant.D, &sc.plant.C);
    let sI_A = nalgebra::DMatrix::<nalgebra::Complex<f64>>::from_fn(4, 4, |i, j| {
        let a = nalgebra::Complex::new(-A[(i, j)], 0.0);
        if i == j {
            a + s
        } else {
            a
        }
    });
    let x = sI_A.lu().solve(&D.column(0).map(|d| nalgebra::Complex::new(d, 0.0))).unwrap();
    let model = (0..4).map(|j| x[j] * C[(0, j)]).sum::<nalgebra::Complex<f64>>().norm() * 1000.0 * 0.020;
    // Relative 1e-9: the two evaluations of one rational function differ by rounding only.
    assert!((model - passive).abs() <= 1e-9 * passive, "scenario {model} m against the source's {passive} m");
}

/// The scenario's automatic design with the `[design]` keys `auto` removed, and `targets`.
fn auto_of(app: &App, auto: &[&str], targets: Targets) -> Scenario {
    let mut doc: toml::Table = scenario_text(app).parse().unwrap();
    let design = doc.get_mut("design").and_then(|d| d.as_table_mut()).unwrap();
    for key in auto {
        assert!(design.remove(*key).is_some(), "{}: design.{key}", app.dir);
    }
    let a = auto_design(&doc, &targets).unwrap();
    assert!(a.verification.passed, "{}: {:?}", app.dir, a.verification);
    a.scenario
}

/// Every pole a design gives: the observer's, the channels', the filters'.
fn poles_mut(d: &mut quell::DesignSpec) -> Vec<&mut nalgebra::Complex<f64>> {
    let observer: Vec<_> = match &mut d.observer {
        quell::design::ObserverChoice::Poles(p) => p.iter_mut().collect(),
        _ => vec![],
    };
    let lists = d.channel_poles.iter_mut().chain(&mut d.reference_filter_poles).chain(&mut d.disturbance_filter_poles);
    observer.into_iter().chain(lists.flatten()).collect()
}

/// The page's design is the automatic one: every key equal, μ, β and the poles to 1e-9 relative.
/// μ is computed from the eigenvalues of the averaged Ω̄, which follow the placed gains; those move
/// at rounding level (about 1e-12 relative) when the placement's floating-point operations change
/// order. The poles and β are chosen to ten significant digits since the pages were written (the
/// pages keep their 16).
fn assert_same_design(auto: &quell::DesignSpec, page: &quell::DesignSpec) {
    let close = |a: f64, b: f64, what: &str| {
        assert!((a - b).abs() <= 1e-9 * b.abs(), "automatic {what} {a} against the page's {b}")
    };
    assert_eq!(auto.mu.len(), page.mu.len());
    for (a, b) in auto.mu.iter().zip(&page.mu) {
        close(*a, *b, "μ");
    }
    close(auto.beta, page.beta, "β");
    let mut auto = auto.clone();
    auto.mu.clone_from(&page.mu);
    auto.beta = page.beta;
    let mut page_copy = page.clone();
    let (a, b) = (poles_mut(&mut auto), poles_mut(&mut page_copy));
    assert_eq!(a.len(), b.len());
    for (a, b) in a.into_iter().zip(b) {
        close(a.re, b.re, "pole (real part)");
        close(a.im, b.im, "pole (imaginary part)");
        *a = *b;
    }
    assert_eq!(&auto, page);
}

#[test]
fn the_keys_each_page_says_are_automatic_are_what_quell_design_auto_chooses() {
    // dc-motor: every key, default targets.
    let keys = ["observer_poles", "channel_poles", "reference_filter_poles", "disturbance_filter_poles", "mu", "beta"];
    let auto = auto_of(&MOTOR, &keys, Targets::default());
    assert_same_design(&auto.design, &Scenario::from_toml(&scenario_text(&MOTOR)).unwrap().design);
    // active-suspension: the road filter, β and μ with --convergence-time 5.
    let keys = ["disturbance_filter_poles", "mu", "beta"];
    let auto = auto_of(&SUSPENSION, &keys, Targets { convergence_time: Some(5.0), ..Targets::default() });
    assert_same_design(&auto.design, &Scenario::from_toml(&scenario_text(&SUSPENSION)).unwrap().design);
    // supply-vessel: the filters and β (μ stays the page's: the automatic μ would adapt beyond the
    // stiffness threshold, where the automatic design no longer goes; README). The verification is
    // not asserted: it judges the page's μ against 1 % of each reference, tighter than the page's bounds.
    let mut doc: toml::Table = scenario_text(&VESSEL).parse().unwrap();
    let design = doc.get_mut("design").and_then(|d| d.as_table_mut()).unwrap();
    for key in ["reference_filter_poles", "disturbance_filter_poles", "beta"] {
        assert!(design.remove(key).is_some(), "supply-vessel: design.{key}");
    }
    let (auto, page) = (auto_design(&doc, &Targets::default()).unwrap().scenario.design, vessel_with_truth("").design);
    // Within the ten digits the poles and β are chosen to.
    let poles = |d: &quell::DesignSpec| -> Vec<f64> {
        d.reference_filter_poles.iter().chain(&d.disturbance_filter_poles).flatten().map(|p| p.re).collect()
    };
    for (a, b) in poles(&auto).iter().zip(poles(&page)).chain([(&auto.beta, page.beta)]) {
        assert!((a - b).abs() <= 1e-9 * b.abs(), "filter pole or β {a} against the page's {b}");
    }
    assert_eq!(poles(&auto).len(), poles(&page).len());
}

/// max_k |a(k) − b(k)| / max_k |b(k)| over two runs stored row after row.
fn relative_deviation(a: &[f64], b: &[f64]) -> f64 {
    let dev = a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    let peak = b.iter().fold(0.0f64, |m, y| m.max(y.abs()));
    dev / peak
}

#[test]
fn every_apps_exported_c_is_current_compiles_and_is_the_rust_controller() {
    for app in &APPS {
        let s = Scenario::from_toml(&scenario_text(app)).unwrap();
        let d = s.design().unwrap();
        let T = s.simulation.sample_time.unwrap();
        // The committed files are what `quell export scenario.toml --prefix P` writes today.
        let options = ExportOptions {
            prefix: app.prefix.into(),
            precision: Precision::F64,
            scenario_name: s.name.clone(),
            names: s.names.clone(),
        };
        let code = generate(&d, T, &options).unwrap();
        let dir = folder(app).join("c");
        let committed = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap();
        assert!(
            committed(&code.header_name) == code.header && committed(&code.source_name) == code.source,
            "{}: c/ is stale: run `quell export examples/apps/{}/scenario.toml --out examples/apps/{}/c --prefix {}`",
            app.dir,
            app.dir,
            app.dir,
            app.prefix
        );
        // The committed files, compiled with gcc (-std=c99 -Wall -Wextra -Werror -pedantic -O2),
        // against the Rust controller on the y and g of the app's own run (one recorded sample
        // per controller step: any sequence serves to compare two implementations).
        let tmp = TempDir::new(app.prefix);
        for name in [&code.header_name, &code.source_name] {
            std::fs::copy(dir.join(name), tmp.0.join(name)).unwrap();
        }
        let (m, q, n) = (d.plant().m(), d.q(), d.plant().n());
        let mut c = CController::build_in(tmp, app.prefix, Precision::F64, (m, q, n), "-O2");
        let mut rust = Controller::new(&d, T).unwrap();
        let r = run(&s);
        let (mut a, mut b) = ([vec![], vec![], vec![]], [vec![], vec![], vec![]]);
        for k in 0..r.t.len() {
            let (y, g) = (&r.y[k * m..(k + 1) * m], &r.g[k * m..(k + 1) * m]);
            a[0].extend_from_slice(c.step(y, g));
            b[0].extend_from_slice(rust.step(y, g).unwrap());
            a[1].extend_from_slice(c.command());
            b[1].extend_from_slice(rust.command());
            a[2].extend_from_slice(c.eta());
            b[2].extend_from_slice(rust.eta());
        }
        let dev = [0, 1, 2].map(|i| relative_deviation(&a[i], &b[i]));
        println!(
            "{}: C against Rust over {} steps: u_f {:.1e}, u {:.1e}, η̂ {:.1e}",
            app.dir,
            r.t.len(),
            dev[0],
            dev[1],
            dev[2]
        );
        // 1e-12 relative to the peaks, as for the paper's controller (tests/export_c.rs); on x86-64
        // the C sums in the Controller's order and the bits agree.
        assert!(dev.iter().all(|&e| e <= 1e-12), "{}: u_f, u, η̂ deviate by {dev:?}", app.dir);
    }
}

/// The app's study with `runs` Monte Carlo draws per grid point instead of the file's.
fn small_study(app: &App, runs: usize) -> Summary {
    let path = folder(app).join("study.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let line = text.lines().find(|l| l.starts_with("runs = ")).unwrap();
    let study = Study::from_toml(&text.replace(line, &format!("runs = {runs}")), path.parent()).unwrap();
    let all = sweep(&study, &SweepOptions::default());
    assert!(!all.partial);
    Summary::new(StudyMeta::new(&study, Shard::ALL), &all.rows, false)
}

/// Asserts that every run of every grid point completed with each channel's tail max |e| and
/// max |u_f| at most the bounds given.
fn assert_summary(app: &App, s: &Summary, points: usize, tail: &[f64], uf: &[f64]) {
    assert_eq!(s.points.len(), points, "{}", app.dir);
    for p in &s.points {
        assert_eq!(p.completed, p.runs, "{} point {:?}", app.dir, p.grid);
        for (i, c) in p.channels.iter().enumerate() {
            let (e, u) = (c.tail_max_e.max.unwrap(), c.max_uf.max.unwrap());
            assert!(
                e <= tail[i],
                "{} point {:?} channel {}: tail max |e| {e:e} > {:e}",
                app.dir,
                p.grid,
                i + 1,
                tail[i]
            );
            assert!(u <= uf[i], "{} point {:?} channel {}: max |u_f| {u:e} > {:e}", app.dir, p.grid, i + 1, uf[i]);
        }
    }
}

#[test]
fn every_apps_study_runs_and_its_summary_holds() {
    // The first draws of the full studies (seeded per draw, so the same runs); bounds are the pages'
    // figures for the whole study (max over all draws) with 1.5× margin.
    // Vessel, 20 draws: tail max |e| at most 0.219 m, 0.129 m, 2.9e-3 rad; |u_f| at most 2.0 MN,
    // 1.4 MN, 10.2 MN·m.
    let s = small_study(&VESSEL, 3);
    assert_summary(&VESSEL, &s, 1, &[0.33, 0.19, 4.4e-3], &[3.0e6, 2.1e6, 1.5e7]);
    // Motor, J ∈ {0.01, 0.015, 0.02} × 10 draws: tail at most 1.75e-3 rad; max |u_f| is what the
    // controller asked for before the drive's 24 V limit (truth.u_max) clipped it: at most 184 V.
    let s = small_study(&MOTOR, 2);
    assert_summary(&MOTOR, &s, 3, &[2.2e-3], &[280.0]);
    // Suspension, force delay ∈ {0, 4, 7} ms × 10 draws: tail at most 9.3e-4 m; |u_f| at most
    // 1.15 MN (a 7 ms draw's burst).
    let s = small_study(&SUSPENSION, 2);
    assert_summary(&SUSPENSION, &s, 3, &[1.1e-3], &[1.8e6]);
}

/// The vessel's scenario with `extra` lines added to its `[truth]` table.
fn vessel_with_truth(extra: &str) -> Scenario {
    let text = scenario_text(&VESSEL).replace("[truth]\n", &format!("[truth]\n{extra}\n"));
    Scenario::from_toml(&text).unwrap()
}

#[test]
fn vessel_thrust_limits_clip_what_the_recorded_thrust_shows() {
    // Limits above every peak: the clip never acts, so the run is the unlimited one bit for bit.
    // u_f is held over each 0.1 s controller sample and recorded every 0.5 s, so the peaks are
    // taken from a run recorded at every sample (the held values themselves).
    let every_sample = |extra: &str| {
        let text = scenario_text(&VESSEL)
            .replace("[truth]\n", &format!("[truth]\n{extra}\n"))
            .replace("output_step = 0.5", "output_step = 0.1");
        tail_errors(&Scenario::from_toml(&text).unwrap()).0
    };
    let free_every = every_sample("");
    let peaks: Vec<f64> = free_every.summary().iter().map(|c| c.figures.max_uf).collect();
    let above = peaks.iter().map(|p| format!("{:e}", 1.01 * p)).collect::<Vec<_>>().join(", ");
    let r = every_sample(&format!("u_max = [{above}]"));
    assert_eq!(r.y, free_every.y);
    assert_eq!(r.limited_fraction(), vec![0.0; 3]);
    let (free, _) = tail_errors(&vessel_with_truth(""));

    // Limits at about 80 % of the peaks (README: 1.3 MN, 0.9 MN, 7 MN·m against 1.61 MN, 1.12 MN,
    // 8.6 MN·m): the loop completes with the page's tail bounds, the applied thrust never exceeds
    // a limit, and limited_fraction is the share of recorded samples whose thrust sits at the
    // limit, counted here from the recorded u_f.
    let u_max = [1.3e6, 0.9e6, 7e6];
    let (r, e) = tail_errors(&vessel_with_truth("u_max = [1.3e6, 0.9e6, 7e6]"));
    assert_within(&VESSEL, &e);
    let fraction = r.limited_fraction();
    println!("limits at 80 %: clipped fractions {fraction:?}, tail {e:?}");
    for (i, lim) in u_max.iter().enumerate() {
        let column: Vec<f64> = r.column(&r.u_f, 3, i).collect();
        assert!(column.iter().all(|v| v.abs() <= *lim), "input {}: thrust beyond its limit", i + 1);
        let at_limit = column.iter().filter(|v| v.abs() == *lim).count() as f64 / column.len() as f64;
        assert_eq!(fraction[i], at_limit, "input {}", i + 1);
        // README: a few per mille to a few per cent of the samples, all in the move.
        assert!(fraction[i] > 0.002 && fraction[i] < 0.05, "input {}: {}", i + 1, fraction[i]);
    }
    // The limit slows the move: the overshoot grows (README, "Thrust limits": 13.1 m to 14.1 m).
    let top = |r: &SimResult| r.column(&r.y, 3, 0).fold(f64::MIN, f64::max);
    assert!(top(&r) > top(&free) + 0.5, "overshoot {} m against {} m unlimited", top(&r), top(&free));

    // At 75 % (1.2 MN, 0.8 MN, 6 MN·m): with the earlier observer gain the observer, driven by
    // the commanded u_f, wound up and the loop diverged at t = 79.5 s; with today's gain it
    // completes within the page's tail bounds (README, "Thrust limits").
    let (r, e) = tail_errors(&vessel_with_truth("u_max = [1.2e6, 0.8e6, 6e6]"));
    assert_within(&VESSEL, &e);
    assert!(r.limited_fraction().iter().all(|f| *f > 0.0));
}

#[test]
fn vessel_measurement_noise_moves_the_tail_in_proportion_to_its_size() {
    // Band-limited noise (1 Hz) of std σ and 2σ with the same seed: n(t) scales exactly, and once
    // η̂ has settled the loop is nearly linear, so the noise's share of y in the tail (y with noise
    // minus y without) doubles. Independent of the loop's figures: a property of the linear part.
    let noisy = |k: f64| {
        let std = [0.05 * k, 0.05 * k, 5e-4 * k].map(|v| format!("{v:e}")).join(", ");
        let text = format!("{}\n[noise]\nstd = [{std}]\nseed = 1\nbandwidth = 1.0\n", scenario_text(&VESSEL));
        tail_errors(&Scenario::from_toml(&text).unwrap())
    };
    let (clean, _) = tail_errors(&vessel_with_truth(""));
    let ((one, e1), (two, e2)) = (noisy(1.0), noisy(2.0));
    let tail = |r: &SimResult, i: usize| -> Vec<f64> {
        let from = 0.9 * r.t.last().unwrap();
        r.t.iter().zip(r.column(&r.y, 3, i)).filter(|(t, _)| **t >= from).map(|(_, y)| y).collect()
    };
    for i in 0..3 {
        let rms = |r: &SimResult| {
            let d: Vec<f64> = tail(r, i).iter().zip(tail(&clean, i)).map(|(a, b)| a - b).collect();
            (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt()
        };
        let ratio = rms(&two) / rms(&one);
        println!("channel {}: noise share of y in the tail, 2σ over σ: {ratio:.3}", i + 1);
        // 2 within 5 % (measured 1.96–1.99): what η̂'s own response to the noise may add.
        assert!((ratio - 2.0).abs() < 0.1, "channel {}: noise share grows by {ratio} for twice the noise", i + 1);
    }
    // README: σ = 0.2 m, 0.2 m, 2e-3 rad gives 0.45 m, 0.24 m, 4.0e-3 rad; here σ/4 and σ/2 stay
    // below those figures.
    for (e, b) in e1.iter().zip([0.45, 0.24, 4.0e-3]).chain(e2.iter().zip([0.45, 0.24, 4.0e-3])) {
        assert!(*e < b, "tail {e} with noise");
    }
}

/// Why the automatic design finds no passing μ for the vessel, measured on its design model (no
/// `[truth]`, the continuous loop) with μ, the filters, β and the scaling left to `auto_design`.
/// With the page's channel poles −0.1, −0.12 rad/s, G_ii(s) = 0.012/((s + 0.1)(s + 0.12)) passes the
/// 0.8 rad/s wave to Δ_i with gain 0.018 (closed form below): the wave's directions of Ω̄ are
/// 3e-4 of what they would be at unit gain and the verification misses the 1 % bound. With the
/// channel poles automatic too (−1.6, −2.4: from 2r, r = 0.8 rad/s) it passes, in newtons, and
/// the written scenario, run again, keeps every tail within 1 % of its reference; the cost is the
/// thrust, 18–26× the page's peaks (1.6 MN, 1.1 MN, 8.1 MN·m; asserted: more than 10×), which is
/// why the page keeps its slow poles.
/// The vessel page's own scenario (10 Hz controller, the true plant with 0.2 s on u_f) with an
/// empty `[design]`: the automatic design's poles start slow enough for T_s = 0.1 s (its continuous
/// first proposal diverged there, ξ̂ at t = 5 s) and its sampled verification on the true plant
/// passes; the written scenario, run again, keeps every tail within 1 % of its reference's peak.
#[test]
fn the_vessels_automatic_design_passes_on_its_own_sampled_scenario() {
    let mut doc: toml::Table = scenario_text(&VESSEL).parse().unwrap();
    doc.insert("design".into(), toml::Value::Table(toml::Table::new()));
    let a = auto_design(&doc, &Targets::default()).unwrap();
    assert!(a.verification.passed, "{:?}", a.verification);
    let s = Scenario::from_toml(&a.scenario.to_toml()).unwrap();
    assert_eq!(s.simulation.sample_time, Some(0.1));
    let r = run(&s);
    assert_eq!(r.outcome, Some(quell::sim::Outcome::Completed));
    let t_end = s.simulation.t_end;
    for (i, c) in s.reference.components.iter().enumerate() {
        let tail = r.max_abs_error(i, 0.9 * t_end, t_end).unwrap();
        assert!(tail <= 0.01 * c.peak(), "channel {}: {tail:e}", i + 1);
    }
}

#[test]
fn the_vessels_slow_channel_poles_pass_once_its_components_are_sized() {
    let gain = 0.012 / ((0.8f64.powi(2) + 0.1f64.powi(2)).sqrt() * (0.8f64.powi(2) + 0.12f64.powi(2)).sqrt());
    assert!((gain - 0.0184).abs() < 1e-3, "{gain}");
    let model = |keep_channel_poles: bool, sizes: bool| -> toml::Table {
        let mut doc: toml::Table = scenario_text(&VESSEL).parse().unwrap();
        doc.remove("truth");
        doc["simulation"].as_table_mut().unwrap().remove("sample_time");
        let design = doc.get_mut("design").and_then(|d| d.as_table_mut()).unwrap();
        design.retain(|k, _| k == "observer_poles" || (keep_channel_poles && k == "channel_poles"));
        if !sizes {
            let ones = |n| toml::Value::Array(vec![toml::Value::Float(1.0); n]);
            design.insert("reference_sizes".into(), ones(3));
            design.insert("disturbance_sizes".into(), ones(3));
        }
        doc
    };
    // In newtons and metres, in_own_units, the slow poles' automatic μ misses 1 %.
    let in_own_units = auto_design(&model(true, false), &Targets::default()).unwrap();
    assert!(!in_own_units.verification.passed, "{:?}", in_own_units.verification);
    for keep in [true, false] {
        let a = auto_design(&model(keep, true), &Targets::default()).unwrap();
        assert!(a.verification.passed, "{:?}", a.verification);
        assert_eq!(a.design.disturbance_sizes(), [1e5, 1e5, 1e6]);
        let s = Scenario::from_toml(&a.scenario.to_toml()).unwrap();
        let r = run(&s);
        let t_end = s.simulation.t_end;
        for (i, c) in s.reference.components.iter().enumerate() {
            let tail = r.max_abs_error(i, 0.9 * t_end, t_end).unwrap();
            assert!(tail <= 0.01 * c.peak(), "channel {}: {tail:e}", i + 1);
        }
        let peaks: Vec<f64> = (0..3).map(|i| r.column(&r.u_f, 3, i).fold(0.0f64, |m, v| m.max(v.abs()))).collect();
        println!("channel poles kept: {keep}; μ {:?}; tails within 1 %; max|u_f| {peaks:?}", a.design.mu());
    }
}
