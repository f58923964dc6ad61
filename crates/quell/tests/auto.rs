//! The automatic design (`quell::auto`) on seeded random plants of several shapes: stable and
//! unstable, σ_i from 1 to 4, with and without zero dynamics, m = 1 to 3, at time scales from 1 ms
//! to 1000 s and in three unit systems. Asserted: the design passes its verification, and the complete
//! scenario it writes, read back from TOML and run again, keeps every channel's tail error
//! (last 10 % of the horizon) within 1 % of its reference's peak.
#![allow(non_snake_case)]

mod common;

use std::ops::ControlFlow;

use common::{companion, poly_from_roots, Rng};
use quell::auto::{auto_design, AutoError, Targets, EFFORT_GROWTH, SAMPLED_CANCELLATION, TAIL_BOUND};
use quell::diagnostics::{diagnose, disturbance_zeros, FIDELITY_LIMIT};
use quell::nalgebra::{Complex, DMatrix};
use quell::scenario::Scenario;
use quell::sim::Run;

fn rows(M: &DMatrix<f64>) -> String {
    let r: Vec<String> = M
        .row_iter()
        .map(|r| format!("[{}]", r.iter().map(|v| format!("{v:e}")).collect::<Vec<_>>().join(", ")))
        .collect();
    format!("[{}]", r.join(", "))
}

/// The plants' units: outputs, references and the disturbance in `y` of the base unit (D in the
/// matching unit), inputs in `u`. (A disturbance in units unrelated to the outputs' scales ξ̂_ω against ξ̂_g by their ratio,
/// and Ω̄_i's conditioning by its square: docs/tuning.md.)
#[derive(Clone, Copy)]
struct Units {
    y: f64,
    u: f64,
}

const BASE: Units = Units { y: 1.0, u: 1.0 };

/// Reference frequencies for m channels in (0.3–1.5)·scale rad/s, redrawn until every gap between
/// them, the disturbance's 0.7·scale and 0 spans at least one beat over the horizon 80/scale
/// (gap ≥ 2π/80·scale): closer harmonics cannot be told apart within the horizon (docs/tuning.md).
fn separated_frequencies(rng: &mut Rng, m: usize) -> Vec<f64> {
    loop {
        let ws: Vec<f64> = (0..m).map(|_| rng.uniform(0.3, 1.5)).collect();
        let mut all = ws.clone();
        all.extend([0.0, 0.7]);
        all.sort_by(f64::total_cmp);
        if all.windows(2).all(|w| w[1] - w[0] >= 2.0 * std::f64::consts::PI / 80.0) {
            return ws;
        }
    }
}

/// A plant of m channels, channel i with relative degree sigma[i] and zeros[i] (stable), poles in
/// [−3, 1]·scale (unstable ones allowed), mixed by a well-conditioned similarity; g_i a sine at
/// (0.3–1.5)·scale rad/s ([`separated_frequencies`]) plus a bias, one input disturbance (Q = 0) at
/// 0.7·scale rad/s with a bias. The time axis is scaled by `scale` (delays and horizon by 1/scale);
/// outputs and references are in units of `units.y`, inputs of `units.u`.
fn scenario(rng: &mut Rng, sigma: &[usize], zeros: &[Vec<f64>], scale: f64, units: Units) -> String {
    let m = sigma.len();
    let sizes: Vec<usize> = sigma.iter().zip(zeros).map(|(s, z)| s + z.len()).collect();
    let n: usize = sizes.iter().sum();
    let (mut A, mut B, mut C) = (DMatrix::zeros(n, n), DMatrix::zeros(n, m), DMatrix::zeros(m, n));
    let mut at = 0;
    for i in 0..m {
        let ni = sizes[i];
        let poles: Vec<Complex<f64>> =
            (0..ni).map(|j| Complex::new(rng.uniform(-3.0, 1.0) - 0.2 * j as f64, 0.0)).collect();
        A.view_mut((at, at), (ni, ni)).copy_from(&companion(&poly_from_roots(&poles)));
        B[(at + ni - 1, i)] = 1.0;
        let mut num = poly_from_roots(&zeros[i].iter().map(|&z| Complex::new(z, 0.0)).collect::<Vec<_>>());
        num.push(1.0);
        for (j, v) in num.iter().enumerate() {
            C[(i, at + j)] = *v;
        }
        at += ni;
    }
    let T = DMatrix::<f64>::identity(n, n) + rng.matrix(n, n) * (0.2 / n as f64);
    let Ti = T.clone().try_inverse().unwrap();
    // Time scaling t → t/scale: A, B and D × scale, so that every transfer function is
    // G(s/scale), with the gains of the 1 s plant at the scaled frequencies.
    let A = &T * A * &Ti * scale;
    let B = &T * B * scale;
    let C = C * &Ti * units.y;
    let B = B / units.u;
    // The disturbance measured in the outputs' units: ω × units.y, D / units.y.
    let D = rng.matrix(n, 1) * scale / units.y;
    let delays: Vec<String> = (0..m).map(|_| format!("{:e}", rng.uniform(0.0, 0.5) / scale)).collect();
    let frequencies = separated_frequencies(rng, m);
    let refs: Vec<String> = frequencies
        .iter()
        .map(|w| {
            format!(
                "{{ bias = {:e}, harmonics = [{{ amplitude = {:e}, frequency = {:e} }}] }}",
                rng.uniform(-1.0, 1.0) * units.y,
                rng.uniform(0.5, 2.0) * units.y,
                w * scale
            )
        })
        .collect();
    format!(
        "[plant]\nA = {}\nB = {}\nC = {}\nD = {}\nQ = {}\ndelays = [{}]\n[design]\n\
         [reference]\ncomponents = [{}]\n\
         [disturbance]\ncomponents = [{{ bias = {:e}, harmonics = [{{ amplitude = {:e}, frequency = {:e} }}] }}]\n\
         [simulation]\nt_end = {:e}\noutput_step = {:e}\nrtol = 1e-7\natol = 1e-9\n",
        rows(&A),
        rows(&B),
        rows(&C),
        rows(&D),
        rows(&DMatrix::zeros(m, 1)),
        delays.join(", "),
        refs.join(", "),
        0.3 * units.y,
        0.5 * units.y,
        0.7 * scale,
        80.0 / scale,
        0.05 / scale
    )
}

/// A plant shape: its name, σ_i and the zeros of each channel.
type Shape = (&'static str, Vec<usize>, Vec<Vec<f64>>);

/// The plant shapes of the family: relative degrees and zeros per channel (Σσ_i < n: zero dynamics).
fn shapes() -> Vec<Shape> {
    vec![
        ("σ=[1]", vec![1], vec![vec![]]),
        ("σ=[2]", vec![2], vec![vec![]]),
        ("σ=[3]", vec![3], vec![vec![]]),
        ("σ=[4]", vec![4], vec![vec![]]),
        ("σ=[2], zero −1", vec![2], vec![vec![-1.0]]),
        ("σ=[1, 1]", vec![1, 1], vec![vec![], vec![]]),
        ("σ=[1, 2]", vec![1, 2], vec![vec![], vec![]]),
        ("σ=[2, 1], zero −1.5", vec![2, 1], vec![vec![-1.5], vec![]]),
        ("σ=[1, 2, 1], zero −2", vec![1, 2, 1], vec![vec![], vec![], vec![-2.0]]),
    ]
}

/// Unit systems cycled through the family: base units; outputs in mm with inputs in kV; outputs
/// in km with inputs in mA.
const UNITS: [Units; 3] = [BASE, Units { y: 1e3, u: 1e-3 }, Units { y: 1e-3, u: 1e3 }];

/// The automatic design of one random plant (`design`: lines for its `[design]`, empty for none):
/// its verification must pass and the complete scenario
/// it writes, read back from TOML and run again, must keep every channel's tail error (last 10 %
/// of the horizon) within 1 % of its reference's peak. Err: what failed.
fn case(seed: u64, shape: usize, scale: f64, units: Units, design: &str) -> Result<Vec<f64>, String> {
    let (name, sigma, zeros) = &shapes()[shape];
    let mut rng = Rng(seed);
    let text = scenario(&mut rng, sigma, zeros, scale, units).replace("[design]\n", &format!("[design]\n{design}"));
    let doc: toml::Table = text.parse().unwrap();
    let what = format!("{name}, scale {scale:e}, units y×{:e} u×{:e}, seed {seed}", units.y, units.u);
    let auto = auto_design(&doc, &Targets::default()).map_err(|e| format!("{what}: {e}"))?;
    if !auto.verification.passed {
        return Err(format!("{what}: verification {:?}", auto.verification));
    }
    let s = Scenario::from_toml(&auto.scenario.to_toml()).unwrap();
    let design = s.design().unwrap();
    let r = Run::of(&s, &design).simulate(|_| ControlFlow::Continue(())).unwrap();
    let t_end = s.simulation.t_end;
    s.reference
        .components
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let ratio = r.max_abs_error(i, 0.9 * t_end, t_end).unwrap_or(f64::NAN) / (TAIL_BOUND * c.peak());
            if ratio <= 1.0 {
                Ok(ratio)
            } else {
                Err(format!("{what}: channel {} of the written scenario: tail max|e| / bound = {ratio:e}", i + 1))
            }
        })
        .collect()
}

/// The time scales of the family: 1 ms to 1000 s (signals, plant and horizon scaled together).
const SCALES: [f64; 7] = [1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3];

/// Runs `count` plants per time scale (shapes and units cycling with the seed) with `design` as
/// their `[design]` lines; the failures, each with what failed, and the worst tail ratio.
fn family(scales: &[f64], count: u64, first_seed: u64, design: &str) -> (Vec<String>, f64) {
    let shapes = shapes().len() as u64;
    let mut failures = Vec::new();
    let mut worst: f64 = 0.0;
    for (k, &scale) in scales.iter().enumerate() {
        for j in 0..count {
            let seed = first_seed + 100 * k as u64 + j;
            let shape = ((j + k as u64) % shapes) as usize;
            match case(seed, shape, scale, UNITS[(j % 3) as usize], design) {
                Ok(ratios) => worst = ratios.into_iter().fold(worst, f64::max),
                Err(e) => failures.push(e),
            }
        }
    }
    (failures, worst)
}

/// 63 plants: every shape once per time scale from 1 ms to 1000 s (units cycling), from an empty
/// `[design]` (so the normalized regressor): every one meets the tail bound (1 % of the
/// reference's peak over the last 10 % of the horizon), and so does the scenario it writes.
#[test]
fn random_plants_from_1_ms_to_1000_s_in_three_unit_systems_meet_the_tail_bound() {
    let (failures, worst) = family(&SCALES, 9, 1, "");
    assert!(failures.is_empty(), "{} of 63 plants failed:\n{}", failures.len(), failures.join("\n"));
    println!("worst tail max|e| / bound over 63 plants: {worst:.3}");
}

/// The wider family (189 plants, other seeds): the failure rate stays at most 2 % (measured:
/// 2 of 189, both σ = [1, 2, 1] with a zero, tails 2.2× and 8.8× the bound, each horizon 1.4 and
/// 1.6 beats of its closest frequencies so that the failed verification proposes a longer t_end;
/// the other 187 at most 0.94 of the bound; docs/tuning.md). Prints its count and figures.
#[test]
#[ignore = "about 2 minutes; the 63-plant test above runs in the normal suite"]
fn the_wider_family_fails_at_most_2_percent() {
    let (failures, worst) = family(&SCALES, 27, 50, "");
    println!("{} of 189 plants failed; worst tail max|e| / bound of the others: {worst:.3}", failures.len());
    failures.iter().for_each(|f| println!("{f}"));
    assert!(failures.len() * 50 <= 189, "{} of 189 plants failed:\n{}", failures.len(), failures.join("\n"));
}

/// The paper's form of the regressor, given, is kept, and away from the 1 s scale it fails most
/// plants of the same family (the reason the automatic design chooses the normalized one):
/// measured 45 of 63, every plant at time scales 1 ms, 10 ms, 100 ms, 100 s and 1000 s (diverged
/// regressor, step budget, or tail 3–100× the bound; docs/tuning.md); asserted: more than half.
#[test]
#[ignore = "about 4 minutes (stiff runs)"]
fn the_papers_regressor_fails_away_from_1_s() {
    let (failures, _) = family(&SCALES, 9, 1, "regressor_scaling = \"paper\"\n");
    assert!(failures.len() * 2 > 63, "only {} of 63 plants failed", failures.len());
}

/// A Targets::u_limit bounds the plant input u_f (5), as the verifying run records it: an
/// unreachable limit fails the verification, and the reported max |u_f,i| is the one of the written
/// scenario's run (its summary: rows and step ends; u_f there, not the adaptive command u); a loose
/// limit changes nothing.
#[test]
fn the_actuator_limit_bounds_the_recorded_plant_input() {
    let text = scenario(&mut Rng(7), &[2], &[vec![]], 1.0, BASE);
    let doc: toml::Table = text.parse().unwrap();
    let free = auto_design(&doc, &Targets::default()).unwrap();
    assert!(free.verification.passed);
    let rerun = |a: &quell::auto::AutoDesign| {
        let s = Scenario::from_toml(&a.scenario.to_toml()).unwrap();
        let r = Run::of(&s, &s.design().unwrap()).simulate(|_| ControlFlow::Continue(())).unwrap();
        let figures = r.summary()[0].figures;
        // The peaks count the step ends between rows too (at least the rows' peak).
        assert!(figures.max_uf >= r.u_f.iter().fold(0.0f64, |m, v| m.max(v.abs())));
        (figures.max_uf, figures.max_u)
    };
    let (u_f, u) = rerun(&free);
    // The same run, the same steps: equal to rounding.
    assert!((free.verification.max_uf[0] - u_f).abs() <= 1e-12 * u_f, "{:?} vs {u_f}", free.verification);
    assert!(u_f != u, "u_f {u_f} and u {u} must differ for this check to tell them apart");
    let loose = auto_design(&doc, &Targets { u_limit: vec![10.0 * u_f], ..Targets::default() }).unwrap();
    assert!(loose.verification.passed && loose.scenario.design.mu == free.scenario.design.mu);
    // inf is no limit on that input (as truth.u_max's inf is): the free design.
    let none = auto_design(&doc, &Targets { u_limit: vec![f64::INFINITY], ..Targets::default() }).unwrap();
    assert!(none.verification.passed && none.scenario.design.mu == free.scenario.design.mu);
    let tight = auto_design(&doc, &Targets { u_limit: vec![1e-3 * u_f], ..Targets::default() }).unwrap();
    assert!(!tight.verification.passed, "{:?}", tight.verification);
    let (u_f, _) = rerun(&tight);
    assert!((tight.verification.max_uf[0] - u_f).abs() <= 1e-12 * u_f && u_f > 1e-3 * free.verification.max_uf[0]);
}

/// A limit the channel poles alone meet is met: a ball and beam with a 0.45 drive and `--u-limit
/// 0.45` had been refused (0.516 at best) because the relaxation slowed the channel poles only
/// together with an observer already slowed as far as the loop tolerates; channels ×¼ with the
/// observer phase 1 kept ask 0.333, the steady-state input itself (helper tryout, 2026-12-06).
#[test]
fn an_actuator_limit_met_by_the_channel_poles_alone_is_met() {
    let doc: toml::Table = data("ball-beam.toml").parse().unwrap();
    let a = auto_design(&doc, &Targets { u_limit: vec![0.45], ..Targets::default() }).unwrap();
    let v = &a.verification;
    assert!(v.passed && v.max_uf[0] <= 0.45, "{v:?}");
    // The steady state alone asks 0.3333 (phasor sum of the bias's 0.0952 and the harmonic's 0.2381,
    // `quell design`'s steady-input section): the kept candidate is within 1 % of that floor.
    assert!(v.max_uf[0] <= 1.01 * (0.02 / 0.21 + 0.2 * 0.25 / 0.21), "{v:?}");
    let kept = v.candidates.iter().find(|c| c.chosen).unwrap();
    let slowest_observer = v.candidates.iter().map(|c| c.speed.observer).fold(1.0, f64::min);
    assert!(kept.speed.observer > slowest_observer, "{v:?}");
}

/// Targets out of range are refused before any choice or simulation, naming the field: a
/// convergence time that is not a finite positive number or beyond t_end, limits of another count
/// than 1 or m, or not positive.
#[test]
fn targets_out_of_range_are_refused_naming_the_field() {
    let doc = without_design(&data("batch-reactor.toml"));
    let refused = |targets: Targets| auto_design(&doc, &targets).map(|_| ()).unwrap_err().to_string();
    for t in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = refused(Targets { convergence_time: Some(t), ..Targets::default() });
        assert_eq!(e, format!("convergence_time: expected a finite number > 0, found {t}"));
    }
    // Beyond the horizon: the report explained μ by a time the verifying run never reached.
    let e = refused(Targets { convergence_time: Some(1e300), ..Targets::default() });
    assert!(
        e.starts_with("convergence_time: expected a time within simulation.t_end = ")
            && e.ends_with("found 1e300; ask for an earlier convergence or lengthen simulation.t_end"),
        "{e}"
    );
    for (limits, found) in [(vec![1.0; 3], "found 3"), (vec![0.0], "found 0"), (vec![1.0, f64::NAN], "found NaN")] {
        let e = refused(Targets { u_limit: limits, ..Targets::default() });
        assert!(e.starts_with("u_limit: expected") && e.contains(found), "{e}");
    }
    for (error, found) in [(-0.1, "-0.1"), (0.6, "0.6"), (f64::NAN, "NaN"), (1.0, "1")] {
        let e = refused(Targets { delay_error: Some(error), ..Targets::default() });
        assert_eq!(e, format!("delay_error: expected a relative error from 0 (no check) to 0.5, e.g. 0.1 for the delays ±10 %, found {found}"));
    }
}

/// A value the rules chose and the design refuses is said to be the rules' (with what to give by
/// hand), unlike the same value given in the file: x' = −x + u tracking a square wave's first 200
/// odd harmonics of 0.1 rad/s needs 400 filter poles, which even ×1.1 apart span 3e16, beyond the
/// design's span of rates.
#[test]
fn a_value_the_rules_chose_and_the_design_refuses_is_named_as_theirs() {
    let harmonics: Vec<String> = (0..200)
        .map(|k| format!("{{ amplitude = {}, frequency = {} }}", 1.0 / (2 * k + 1) as f64, 0.1 * (2 * k + 1) as f64))
        .collect();
    let text = format!(
        "[plant]\nA = [[-1.0]]\nB = [[1.0]]\nC = [[1.0]]\ndelays = [0.1]\n[design]\n[reference]\ncomponents = [ {{ harmonics = [{}] }} ]\n[simulation]\nt_end = 1000.0\n",
        harmonics.join(", ")
    );
    // The normalized form given (the rules would realize so many harmonics modally, and refuse to
    // verify a regressor of q = 400: `a_regressor_too_large_to_verify_is_not_simulated`).
    let text = text.replace("[design]\n", "[design]\nregressor_scaling = \"normalized\"\n");
    let doc: toml::Table = text.parse().unwrap();
    let e = auto_design(&doc, &Targets::default()).map(|_| ()).unwrap_err();
    let message = e.to_string();
    assert!(matches!(&e, AutoError::Rules { key, .. } if key == "design.reference_filter_poles"), "{e:?}");
    assert!(
        message.starts_with("design.reference_filter_poles[0]: pole")
            && message.contains("out of the design's span of rates"),
        "{message}"
    );
    assert!(
        message.contains("no usable value here: many harmonics or frequencies far apart call for filter poles by hand"),
        "{message}"
    );
    assert!(message.ends_with("; give design.reference_filter_poles in [design] (docs/tuning.md)"), "{message}");
    // A key the file gives is the file's error, as without --auto.
    let given: toml::Table = text.replace("[design]\n", "[design]\nbeta = -1.0\n").parse().unwrap();
    let e = auto_design(&given, &Targets::default()).map(|_| ()).unwrap_err();
    assert!(!matches!(e, AutoError::Rules { .. }) && e.to_string().starts_with("design.beta"), "{e:?}");
}

/// A sampled-data scenario starts the rules from channel and observer poles slow enough for its
/// sample time (with sizes of 1, the regressor in its signals' units: sized, the maglev's
/// continuous design is slow enough for 0.5 ms already): the maglev (tests/data/maglev.toml, ±57 /s, 1 ms delay) gets an observer for
/// ρ = 686 /s in the continuous loop, too fast for 0.5 ms (T_s·ρ = 0.34); with
/// simulation.sample_time = 0.0005 the rules halve the poles to T_s·ρ ≤ 0.2. That start drives
/// u_f 195× its continuous loop's peak (1059 V against 5.4 V; it had passed so, and the run's own
/// comparison then sent the user back to the automatic design), the next slower one still 3.7×, so
/// it is slowed until the sampled run stays within twice its continuous u_f; over the 5 s of the
/// file that slower loop misses the tail bound, and its observer ×4, verified by runs, meets it
/// (the failed verification had named a horizon of 13 s instead); over 13 s the slowed loop passes
/// as it is.
#[test]
fn a_sampled_scenario_gets_poles_slow_enough_for_its_sample_time() {
    let rho = |a: &quell::auto::AutoDesign| {
        quell::sim::loop_rate(&a.design, a.design.plant(), [&a.scenario.reference, &a.scenario.disturbance])
    };
    let t_s = 5e-4;
    let unit_sized = |text: &str| with_unit_sizes(toml::from_str(text).unwrap());
    let continuous = auto_design(&unit_sized(&data("maglev.toml")), &Targets::default()).unwrap();
    assert!(continuous.verification.passed, "{:?}", continuous.verification);
    assert!(t_s * rho(&continuous) > quell::sim::COARSE_SAMPLE, "ρ = {}", rho(&continuous));
    let text = data("maglev.toml").replace("[simulation]\n", &format!("[simulation]\nsample_time = {t_s}\n"));
    let short = auto_design(&unit_sized(&text), &Targets::default()).unwrap();
    assert!(short.verification.passed, "{:?}", short.verification);
    let (first, kept) = (&short.verification.candidates[0], short.verification.candidates.iter().find(|c| c.chosen));
    assert!(!first.tail_max_e.iter().zip(&short.verification.bound).all(|(e, b)| e <= b), "{first:?}");
    assert_eq!(kept.unwrap().speed.observer, 4.0 * first.speed.observer, "{kept:?}");
    let why = &short.choices.iter().find(|c| c.key == "design.observer_poles").unwrap().why;
    assert!(
        why.contains(
            "; the relaxation started from ×4 of the proposal's observer: the proposal's run missed its tail bound ("
        ),
        "{why}"
    );
    let go = |_| ControlFlow::Continue(());
    let r = Run::of(&short.scenario, &short.design).simulate(go).unwrap();
    let tail = r.summary()[0].figures.tail_max_e;
    assert!(tail <= short.verification.bound[0], "{tail}");
    let longer = text.replace("t_end = 5.0", "t_end = 13.0");
    let sampled = auto_design(&unit_sized(&longer), &Targets::default()).unwrap();
    assert_eq!(sampled.scenario.simulation.sample_time, Some(t_s));
    assert!(sampled.verification.passed, "{:?}", sampled.verification);
    assert!(t_s * rho(&sampled) <= quell::sim::COARSE_SAMPLE, "ρ = {}", rho(&sampled));
    // The observer's poles are halved for the sample time, then slowed for the sampled run's u_f:
    // the reason gives the whole factor over the rules' poles.
    let kept = sampled.verification.candidates.iter().find(|c| c.chosen).unwrap().speed;
    assert!(kept.observer <= 0.125, "{kept:?}");
    let why = &sampled.choices.iter().find(|c| c.key == "design.observer_poles").unwrap().why;
    assert!(why.contains("of that for simulation.sample_time = 0.0005 s (T_s·ρ = "), "{why}");
    // The disturbance observer's error quoted last is the kept poles' (the faster proposal's had
    // been left as the last word).
    let kept_error =
        quell::diagnostics::Averaged::new(&sampled.design, &sampled.scenario.reference, &sampled.scenario.disturbance)
            .fidelity
            .iter()
            .map(|f| f.relative_error)
            .fold(0.0, f64::max);
    assert!(why.ends_with(&format!("; its error is then {kept_error:.2e} at worst")), "{why}");
    let slowed = format!("×{} of the rules' poles in all: the sampled-data verifying runs of the faster proposals drove u_f beyond twice their continuous loop's (the last: y[1] by ", kept.observer);
    assert!(why.contains(&slowed), "{why}");
    // The kept design's sampled run against its continuous loop, on their own rows.
    let r = Run::of(&sampled.scenario, &sampled.design).simulate(go).unwrap();
    let mut s = sampled.scenario.clone();
    s.simulation.sample_time = None;
    let c = Run::of(&s, &sampled.design).simulate(go).unwrap();
    assert!(r.max_uf(0) <= 2.0 * c.max_uf(0), "u_f {} against {}", r.max_uf(0), c.max_uf(0));
    let signals = [&sampled.scenario.reference, &sampled.scenario.disturbance];
    assert!(quell::sim::coarse_sample_warning(&sampled.design, signals, t_s, None).is_none());
}

/// Each verifying simulation reports its progress: run number, candidate speed, t rising to t_end;
/// the callback can stop the design (AutoError::Interrupted), as can a stop flag around the call.
#[test]
fn the_verifying_simulations_report_progress_and_can_be_stopped() {
    let doc = without_design(&data("batch-reactor.toml"));
    let mut seen: Vec<quell::auto::Progress> = Vec::new();
    let a = quell::auto::auto_design_with(&doc, &Targets::default(), &mut |p| {
        seen.push(*p);
        std::ops::ControlFlow::Continue(())
    })
    .unwrap();
    let runs: std::collections::BTreeSet<usize> = seen.iter().map(|p| p.run).collect();
    assert_eq!(runs, (1..=a.verification.runs).collect(), "{runs:?}");
    for w in seen.windows(2).filter(|w| w[0].run == w[1].run) {
        assert!(w[0].t <= w[1].t && w[1].t <= w[1].t_end && w[0].speed == w[1].speed, "{w:?}");
    }
    assert!(seen.iter().any(|p| p.run == 1 && p.t == p.t_end), "the first run reached t_end");
    let mut calls = 0;
    let stopped = quell::auto::auto_design_with(&doc, &Targets::default(), &mut |_| {
        calls += 1;
        if calls > 10 {
            std::ops::ControlFlow::Break(())
        } else {
            std::ops::ControlFlow::Continue(())
        }
    });
    assert!(matches!(stopped, Err(AutoError::Interrupted)), "{:?}", stopped.map(|_| ()));
    let flag = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(true));
    let stopped = quell::cancel::with_stop(flag, || auto_design(&doc, &Targets::default()));
    // (The first design's placement polls the same flag, and may be the one that stops.)
    let interrupted =
        matches!(stopped, Err(AutoError::Interrupted | AutoError::Design(quell::DesignError::Interrupted)));
    assert!(interrupted, "{:?}", stopped.map(|_| ()));
    // Set while a verifying simulation runs (the batch reactor over 1e5 s: seconds a run), the
    // flag stops that simulation (Python's Ctrl-C).
    let mut long = doc.clone();
    long["simulation"].as_table_mut().unwrap().insert("t_end".into(), toml::Value::Float(1e5));
    let flag = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let setter = {
        let flag = flag.clone();
        std::thread::spawn(move || {
            std::thread::sleep(std::time::Duration::from_millis(300));
            flag.store(true, std::sync::atomic::Ordering::Relaxed);
        })
    };
    let started = std::time::Instant::now();
    let stopped = quell::cancel::with_stop(flag, || auto_design(&long, &Targets::default()));
    setter.join().unwrap();
    assert!(matches!(stopped, Err(AutoError::Interrupted)), "{:?}", stopped.map(|_| ()));
    assert!(started.elapsed() < std::time::Duration::from_secs(3), "{:?}", started.elapsed());
}

/// A first proposal whose verifying run ends before t_end is a failed verification with its report
/// and advice (it was an error in Rust's debug format, and the report was lost): the CSTR
/// (tests/data/cstr.toml, unstable at +2.83 /min) sampled every 0.05 min diverges at t ≈ 37.
#[test]
fn a_first_proposal_that_diverges_is_a_failed_verification_with_advice() {
    let text = data("cstr.toml").replace("[simulation]\n", "[simulation]\nsample_time = 0.05\n");
    let a = auto_design(&without_design(&text), &Targets::default()).unwrap();
    let v = &a.verification;
    assert!(!v.passed && !v.tails_met() && v.tail_max_e.iter().all(|e| e.is_infinite()), "{v:?}");
    assert_eq!(v.advice.len(), 1, "{:?}", v.advice);
    let advice = &v.advice[0];
    assert!(advice.starts_with("the first proposal's verifying simulation ended before t_end = "), "{advice}");
    assert!(advice.contains(": diverged at t = "), "{advice}");
    assert!(advice.contains("the sample time 0.05 min") && !advice.contains("Diverged {"), "{advice}");
}

fn data(name: &str) -> String {
    std::fs::read_to_string(format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// The document of a scenario file with its `[design]` emptied (every key left to `auto_design`).
/// `doc` with every component's size given as 1 (`design.reference_sizes`,
/// `design.disturbance_sizes`): the regressor in the signals' own units, as the automatic design
/// had it before it sized components whose peaks span three decades. For the tests of rules that
/// such a scenario exercised unsized (its advice on a failure, its actuator limits).
fn with_unit_sizes(mut doc: toml::Table) -> toml::Table {
    let count = |signal: &str| doc.get(signal).and_then(|s| s["components"].as_array()).map_or(0, |c| c.len());
    let ones = |n: usize| toml::Value::Array(vec![toml::Value::Float(1.0); n]);
    let (m, k) = (count("reference"), count("disturbance"));
    let design = doc.entry("design").or_insert_with(|| toml::Value::Table(toml::Table::new())).as_table_mut().unwrap();
    design.insert("reference_sizes".into(), ones(m));
    if k > 0 {
        design.insert("disturbance_sizes".into(), ones(k));
    }
    doc
}

fn without_design(text: &str) -> toml::Table {
    let mut doc: toml::Table = text.parse().unwrap();
    doc.insert("design".into(), toml::Value::Table(toml::Table::new()));
    doc
}

/// Rosenbrock's batch reactor with network delays and input disturbances at 3 and 5 rad/s
/// (tests/data/batch-reactor.toml). Its hand design's observer (poles −2…−5) makes the
/// disturbance observer pass ω badly: channel 1 keeps a tail error of about 0.35 (bound 0.015),
/// and the diagnostics say why in one line naming the knob and the published zeros of the plant
/// (−5.04 and −1.19, Skogestad & Postlethwaite). The automatic design keeps those zeros among
/// the observer poles, passes 5 rad/s with a relative error below the advice's threshold and meets
/// the tail bound.
#[test]
fn the_batch_reactors_slow_channel_is_diagnosed_and_the_automatic_design_avoids_it() {
    let text = data("batch-reactor.toml");
    let s = Scenario::from_toml(&text).unwrap();
    let d = s.design().unwrap();
    let r = Run::of(&s, &d).simulate(|_| ControlFlow::Continue(())).unwrap();
    let bound = TAIL_BOUND * s.reference.components[0].peak();
    assert!(r.max_abs_error(0, 90.0, 100.0).unwrap() > 10.0 * bound);
    let diag = diagnose(&d, &s.reference, &s.disturbance, &r);
    let at_5 = diag.observer_fidelity.iter().find(|f| f.frequency == 5.0).unwrap();
    assert!(at_5.relative_error > FIDELITY_LIMIT, "{at_5:?}");
    let advice = diag.channels[0].advice.join("\n");
    // The poles the advice names, read back from its text.
    let named: Vec<f64> = advice
        .split_once("(A, D, C), [")
        .and_then(|(_, rest)| rest.split_once(']'))
        .map(|(list, _)| list.split(", ").map(|v| v.parse().unwrap()).collect())
        .unwrap_or_default();
    let near = |z: f64| named.iter().any(|v| (v - z).abs() < 0.005);
    assert!(
        advice.contains("5 rad/s") && advice.contains("design.observer_poles") && near(-1.19) && near(-5.04),
        "{advice}"
    );
    // The published zeros, to their printed two decimals.
    let zeros = disturbance_zeros(&s.plant).unwrap();
    assert!((zeros[0].re + 1.19).abs() < 0.005 && (zeros[1].re + 5.04).abs() < 0.005, "{zeros:?}");

    let auto = auto_design(&without_design(&text), &Targets::default()).unwrap();
    assert!(auto.verification.passed, "{:?}", auto.verification);
    let poles = match &auto.scenario.design.observer {
        quell::ObserverChoice::Poles(p) => p.clone(),
        other => panic!("{other:?}"),
    };
    assert!(zeros.iter().all(|z| poles.iter().any(|p| (p - z).norm() <= 1e-12 * z.norm())), "{poles:?}");
    let r = Run::of(&auto.scenario, &auto.design).simulate(|_| ControlFlow::Continue(())).unwrap();
    let diag = diagnose(&auto.design, &auto.scenario.reference, &auto.scenario.disturbance, &r);
    let at_5 = diag.observer_fidelity.iter().find(|f| f.frequency == 5.0).unwrap();
    assert!(at_5.relative_error <= FIDELITY_LIMIT, "{at_5:?}");
    for (i, c) in auto.scenario.reference.components.iter().enumerate() {
        assert!(r.max_abs_error(i, 90.0, 100.0).unwrap() <= TAIL_BOUND * c.peak());
    }
    // 3 rad/s (ω's first component) stays beyond the threshold with the zeros among the poles
    // (0.34 at the kept observer: its placed eigenvectors decide with two outputs), and costs
    // nothing: every tail meets the bound (checked above), so the run gets no advice on the observer.
    let at_3 = diag.observer_fidelity.iter().find(|f| f.frequency == 3.0).unwrap();
    assert!(at_3.relative_error > FIDELITY_LIMIT && diag.advice.is_empty(), "{at_3:?} {:?}", diag.advice);
}

/// A hard-disk head positioner in SI units at its own millisecond time scale: a voice-coil arm
/// (position in m, velocity in m/s; viscous pole 200 /s, force constant over mass 4e3 m/s² per A),
/// a 50 µs computation delay, following a track with 1 µm of repeatable runout at the 7200 rpm
/// spindle's 120 Hz (754 rad/s) around a 2 µm offset, against a 60 Hz (377 rad/s) acceleration
/// disturbance measured as the displacement it would cause (D = 377² /s², ω in m). From an empty
/// `[design]` the automatic design must pass its verification within 0.5 s and the written
/// scenario, run again, must keep the tail error within 1 % of the track's 3 µm peak (30 nm).
#[test]
fn a_disk_drive_servo_at_the_millisecond_scale_meets_the_tail_bound_from_an_empty_design() {
    let text = "[plant]\nA = [[0.0, 1.0], [0.0, -200.0]]\nB = [[0.0], [4.0e3]]\nC = [[1.0, 0.0]]\n\
        D = [[0.0], [1.42129e5]]\nQ = [[0.0]]\ndelays = [5e-5]\n[design]\n\
        [reference]\ncomponents = [{ bias = 2e-6, harmonics = [{ amplitude = 1e-6, frequency = 754.0 }] }]\n\
        [disturbance]\ncomponents = [{ bias = 5e-7, harmonics = [{ amplitude = 5e-7, frequency = 377.0 }] }]\n\
        [simulation]\nt_end = 0.5\noutput_step = 1e-4\nrtol = 1e-7\natol = 1e-15\n";
    let auto = auto_design(&text.parse().unwrap(), &Targets::default()).unwrap();
    assert!(auto.verification.passed, "{:?}", auto.verification);
    let s = Scenario::from_toml(&auto.scenario.to_toml()).unwrap();
    let r = Run::of(&s, &s.design().unwrap()).simulate(|_| ControlFlow::Continue(())).unwrap();
    let tail = r.max_abs_error(0, 0.45, 0.5).unwrap();
    assert!(tail <= TAIL_BOUND * 3e-6, "tail max|e| = {tail:e} m against 30 nm");
    println!("tail max|e| = {tail:e} m; {:?}", auto.choices.iter().map(|c| (&c.key, &c.value)).collect::<Vec<_>>());
}

/// The quadruple tank (tests/data/quadruple-tank.toml) from an empty `[design]`: its signals'
/// closest frequencies are 0.01 rad/s apart (0, 0.01, 0.02 and 0.03 rad/s), one beat 2π/0.01 =
/// 628 s, longer than the 600 s horizon. The automatic design must not pass such a horizon off as
/// converged: its verification fails and says why, proposing a t_end of at least two beats
/// (computed here from the frequencies, not read from the code). The proposal is then held to its
/// word: with t_end set to the proposed value the automatic design passes, and the scenario it
/// writes, read back and run again, keeps both channels' tails within 1 % of their references'
/// peaks.
#[test]
fn the_quadruple_tanks_short_horizon_is_refused_with_the_t_end_that_works() {
    let text = data("quadruple-tank.toml");
    let doc = without_design(&text);
    refused_then_passes_at_the_proposed_t_end(doc, 0.01);
}

/// The shipped examples with hand-tuned designs (examples/paper.toml, three-channel.toml,
/// siso-complex.toml): the automatic design from their `[design]` emptied does at least as well
/// on every channel, judged by the hand design's own run (tail max |e_i| over the last 10 % of the
/// horizon), not by figures of an earlier automatic design. siso-complex was 12× worse while the
/// filters' slowest pole was 20/t_end (ξ̂'s start-up transient decaying at 0.33/s, below the
/// reference's 0.5 rad/s).
#[test]
fn the_automatic_design_does_at_least_as_well_as_the_hand_tuned_examples() {
    for name in ["paper.toml", "three-channel.toml", "siso-complex.toml"] {
        let text = std::fs::read_to_string(format!("{}/../../examples/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
        let tails = |s: &Scenario, design: &quell::Design| -> Vec<f64> {
            let r = Run::of(s, design).simulate(|_| ControlFlow::Continue(())).unwrap();
            let t_end = s.simulation.t_end;
            (0..s.plant.m()).map(|i| r.max_abs_error(i, 0.9 * t_end, t_end).unwrap()).collect()
        };
        let hand = Scenario::from_toml(&text).unwrap();
        let hand_tails = tails(&hand, &hand.design().unwrap());
        let auto = auto_design(&without_design(&text), &Targets::default()).unwrap();
        assert!(auto.verification.passed, "{name}: {:?}", auto.verification);
        let auto_tails = tails(&auto.scenario, &auto.design);
        for (i, (a, h)) in auto_tails.iter().zip(&hand_tails).enumerate() {
            assert!(a <= h, "{name} channel {}: automatic tail {a:e} against the hand design's {h:e}", i + 1);
        }
        println!("{name}: automatic {auto_tails:?}, hand {hand_tails:?}");
    }
}

/// The shipped examples' automatic designs run no slower than their hand designs: the verifying
/// run's accepted solver steps (rtol = atol = 1e-9: paper.toml's, and the default in the others;
/// the written scenario keeps them) at most the hand design's, counted on a fresh run of each. Before the
/// relaxation (the rules' first proposal kept) paper took 6 509 steps against 1 547 and
/// siso-complex 2 277 against 1 019: this failed there.
#[test]
fn the_automatic_design_takes_no_more_solver_steps_than_the_hand_tuned_examples() {
    for name in ["paper.toml", "three-channel.toml", "siso-complex.toml"] {
        let text = std::fs::read_to_string(format!("{}/../../examples/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
        let steps = |s: &Scenario, design: &quell::Design| -> usize {
            Run::of(s, design).simulate(|_| ControlFlow::Continue(())).unwrap().stats.steps()
        };
        let hand = Scenario::from_toml(&text).unwrap();
        let hand_steps = steps(&hand, &hand.design().unwrap());
        let auto = auto_design(&without_design(&text), &Targets::default()).unwrap();
        assert!(auto.verification.passed, "{name}: {:?}", auto.verification);
        let s = Scenario::from_toml(&auto.scenario.to_toml()).unwrap();
        let auto_steps = steps(&s, &s.design().unwrap());
        assert!(
            auto_steps <= hand_steps,
            "{name}: automatic {auto_steps} steps against the hand design's {hand_steps}"
        );
        println!("{name}: automatic {auto_steps} steps (verification {}), hand {hand_steps}", auto.verification.steps);
    }
}

/// The supply vessel in SI units (tests/data/supply-vessel.toml, `[design]` emptied): thrust in N
/// and N·m. Without a limit the automatic design peaks at about 1.9e8 (the yaw moment); a limit of
/// 7e7 must be met by a slower design (its channel poles slower than the unlimited one's), whose
/// written scenario, run again, keeps every max |u_f,i| within the limit and every tail within 1 %
/// of its reference's peak; a limit of 1e7, below what any candidate reaches with the tail
/// bound, fails the verification with advice naming the limit and the smallest max |u_f| reached
/// (a figure of a candidate's run: at least the limit).
#[test]
fn the_actuator_limit_trades_pole_speed_for_thrust_on_the_supply_vessel() {
    let doc = with_unit_sizes(without_design(&data("supply-vessel.toml")));
    let fastest = |a: &quell::auto::AutoDesign| -> f64 {
        a.scenario.design.channel_poles.iter().flatten().map(|p| p.norm()).fold(0.0, f64::max)
    };
    let free = auto_design(&doc, &Targets::default()).unwrap();
    assert!(free.verification.passed, "{:?}", free.verification);
    let free_peak = free.verification.max_uf.iter().copied().fold(0.0, f64::max);
    let limit = 7e7;
    assert!(free_peak > limit, "the unlimited design's peak {free_peak:e} must exceed the limit for this test");
    let limited = auto_design(&doc, &Targets { u_limit: vec![limit], ..Targets::default() }).unwrap();
    assert!(limited.verification.passed, "{:?}", limited.verification);
    assert!(fastest(&limited) < fastest(&free), "{} against {}", fastest(&limited), fastest(&free));
    let s = Scenario::from_toml(&limited.scenario.to_toml()).unwrap();
    let r = Run::of(&s, &s.design().unwrap()).simulate(|_| ControlFlow::Continue(())).unwrap();
    let t_end = s.simulation.t_end;
    for (i, c) in s.reference.components.iter().enumerate() {
        let peak = r.column(&r.u_f, 3, i).fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(peak <= limit, "input {}: max|u_f| {peak:e} against the limit {limit:e}", i + 1);
        let tail = r.max_abs_error(i, 0.9 * t_end, t_end).unwrap();
        assert!(tail <= TAIL_BOUND * c.peak(), "channel {}: tail {tail:e}", i + 1);
    }
    let impossible = auto_design(&doc, &Targets { u_limit: vec![1e7], ..Targets::default() }).unwrap();
    assert!(!impossible.verification.passed, "{:?}", impossible.verification);
    let advice = impossible.verification.advice.join("\n");
    let reached = number_after(&advice, "the smallest max|u_f| reached is ", " ");
    assert!(advice.contains("actuator limit 1e7") && reached > 1e7 && reached < free_peak, "{advice}");
    println!("free peak {free_peak:e}; limited {:?}; impossible: {advice}", limited.verification.max_uf);
}

/// A limit below the steady state's own input is said to be so first, even where the closest
/// candidate met its tails a hair under that input (the bicycle model's 0.02449 rad against the
/// steady state's 0.02458 and a limit of 0.02: it had been told only to raise the limit or slow the
/// loop); more than 10 % below it, after the first run. The steady input is recomputed here: u =
/// B⁻¹((jωI − A) x − D w) per tone, y = x.
#[test]
fn a_limit_below_the_steady_input_is_said_first() {
    let text = data("bicycle-4ws.toml");
    let doc: toml::Table = text.parse().unwrap();
    let matrix = |key: &str| {
        let rows = doc["plant"][key].as_array().unwrap();
        let row = |r: &toml::Value| r.as_array().unwrap().iter().map(|v| v.as_float().unwrap()).collect::<Vec<f64>>();
        let rows: Vec<Vec<f64>> = rows.iter().map(row).collect();
        DMatrix::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
    };
    let (A, B, D) = (&matrix("A"), &matrix("B"), &matrix("D"));
    let inv = B.clone().try_inverse().unwrap();
    // The wind's bias (x = 0 for y = g = 0 on v_y, r's reference has no bias) and its 1.5 rad/s
    // tone, then the yaw-rate reference's 1.2566 rad/s tone with v_y = 0.
    let dc = (&inv * (-(D * 500.0)))[(0, 0)].abs();
    let wind = (&inv * (D * 300.0))[(0, 0)].abs();
    let w = 1.2566;
    let x = DMatrix::from_column_slice(2, 1, &[Complex::new(0.0, 0.0), Complex::new(0.1, 0.0)]);
    let jw = DMatrix::from_diagonal_element(2, 2, Complex::new(0.0, w)) - A.map(|a| Complex::new(a, 0.0));
    let yaw = (inv.map(|a| Complex::new(a, 0.0)) * (jw * x))[(0, 0)].norm();
    let steady = dc + wind + yaw;
    assert!((steady - 0.02458).abs() < 5e-6, "{steady}");
    // After the first run now: a loop within its tail bounds delivers at least 90 % of it (0.02212).
    match auto_design(&without_design(&text), &Targets { u_limit: vec![0.02], ..Targets::default() }) {
        Err(AutoError::Target { argument: "u_limit", message }) => assert!(
            message
                .starts_with("the steady state alone asks more than the actuator limit (delta_f: 0.02458 against 0.02"),
            "{message}"
        ),
        other => panic!("{other:?}"),
    }
    // Within 10 % of it the runs decide, and the advice names the steady state first.
    let a = auto_design(&without_design(&text), &Targets { u_limit: vec![0.023], ..Targets::default() }).unwrap();
    assert!(!a.verification.passed, "{:?}", a.verification);
    let advice = &a.verification.advice[0];
    assert!(
        advice.starts_with("the steady state alone asks more than the actuator limit (u_f,1 0.02458 against 0.023"),
        "{advice}"
    );
}

/// A single-zone house (Bacher & Madsen 2011, hours, kW): without an actuator limit the
/// relaxation once kept a candidate whose heater peaked at 3.8 MW (the first proposal's 2.6 kW)
/// with the sensor 3,500 °C off, for 12 % fewer steps. Now no candidate beyond
/// `EFFORT_GROWTH` × the first proposal's max |u_f| is kept, nor relaxed from; the kept design
/// run again from its written scenario stays within that and within the tail bound.
#[test]
fn the_relaxation_does_not_buy_solver_steps_with_actuator_effort() {
    let doc: toml::Table = data("house.toml").parse().unwrap();
    let a = auto_design(&doc, &Targets::default()).unwrap();
    assert!(a.verification.passed, "{:?}", a.verification);
    let first = a.verification.candidates[0].max_uf[0];
    let beyond: Vec<_> = a.verification.candidates.iter().filter(|c| c.max_uf[0] > EFFORT_GROWTH * first).collect();
    // The case needs a candidate beyond: one was tried, and the phase stopped there.
    assert_eq!(beyond.len(), 1, "{:?}", a.verification.candidates);
    assert!(!beyond[0].chosen);
    let s = Scenario::from_toml(&a.scenario.to_toml()).unwrap();
    let r = Run::of(&s, &s.design().unwrap()).simulate(|_| ControlFlow::Continue(())).unwrap();
    let peak = r.column(&r.u_f, 1, 0).fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(peak <= EFFORT_GROWTH * first, "max|u_f| {peak} against the first proposal's {first}");
    let t_end = s.simulation.t_end;
    let tail = r.max_abs_error(0, 0.9 * t_end, t_end).unwrap();
    assert!(tail <= TAIL_BOUND * s.reference.components[0].peak(), "tail {tail:e}");
    assert!(a.verification.relaxation.contains("beyond 2× the first proposal's"), "{}", a.verification.relaxation);
}

/// The Shell heavy-oil fractionator (Prett & Morari 1987, minutes; 3 outputs, 2 disturbances):
/// with more outputs than disturbances the observer's candidate "zeros" are those of
/// (A, D, (CD)⁺C), and where no candidate's disturbance observer comes near the diagnostics'
/// limit they are a guess. Holding them (error 3.99) the design missed every bound at 3,000 min and
/// asked for 180,000; with all-fast poles it meets them at 3,000 min.
#[test]
fn with_more_outputs_than_disturbances_a_hopeless_fidelity_takes_all_fast_observer_poles() {
    let doc: toml::Table = data("shell-fractionator.toml").parse().unwrap();
    let a = auto_design(&doc, &Targets::default()).unwrap();
    assert!(a.verification.passed, "{:?}", a.verification);
    let s = &a.scenario;
    let zeros = disturbance_zeros(&s.plant).expect("(A, D, (CD)⁺C) has zeros here");
    let poles = a.design.observer_eigenvalues();
    assert!(zeros.iter().all(|z| poles.iter().all(|p| (p - z).norm() > 1e-3 * z.norm())), "{poles:?} hold {zeros:?}");
    assert!(poles.iter().all(|p| p.im == 0.0 && p.re < -0.3), "{poles:?}");
}

/// Limits per input on the same vessel, in their own units: 1.5e7 N on surge and sway, 1e8 N·m on
/// yaw. The design that meets one limit of 1e8 (docs/tuning.md: 2.5e7 N, 2.0e7 N, 9.3e7 N·m) is
/// beyond the forces' limits, so the per-input design is a slower one; its written scenario, run
/// again, keeps each max |u_f,i| within its own limit and each tail within 1 % of its reference's
/// peak. Two limits for three inputs, or a limit that is not positive, are errors naming u_limit.
#[test]
fn per_input_actuator_limits_bind_each_input_in_its_own_units() {
    let doc = with_unit_sizes(without_design(&data("supply-vessel.toml")));
    let limits = vec![1.5e7, 1.5e7, 1e8];
    let one = auto_design(&doc, &Targets { u_limit: vec![1e8], ..Targets::default() }).unwrap();
    assert!(one.verification.passed && one.verification.max_uf[0] > limits[0], "{:?}", one.verification);
    let each = auto_design(&doc, &Targets { u_limit: limits.clone(), ..Targets::default() }).unwrap();
    assert!(each.verification.passed, "{:?}", each.verification);
    let s = Scenario::from_toml(&each.scenario.to_toml()).unwrap();
    let r = Run::of(&s, &s.design().unwrap()).simulate(|_| ControlFlow::Continue(())).unwrap();
    let t_end = s.simulation.t_end;
    for (i, c) in s.reference.components.iter().enumerate() {
        let peak = r.column(&r.u_f, 3, i).fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(peak <= limits[i], "input {}: max|u_f| {peak:e} against its limit {:e}", i + 1, limits[i]);
        let tail = r.max_abs_error(i, 0.9 * t_end, t_end).unwrap();
        assert!(tail <= TAIL_BOUND * c.peak(), "channel {}: tail {tail:e}", i + 1);
    }
    // Limits no candidate meets: the advice names the closest candidate's peaks and how far over.
    let impossible = auto_design(&doc, &Targets { u_limit: vec![1e6, 1e6, 1e8], ..Targets::default() }).unwrap();
    assert!(!impossible.verification.passed);
    let advice = impossible.verification.advice.join("\n");
    let over = number_after(&advice, "], ", "× its limit");
    assert!(advice.contains("its actuator limit [1e6, 1e6, 1e8]") && over > 1.0, "{advice}");
    // The limits it proposes are the peaks reached, rounded up, where they exceed their limits, and
    // the limits given elsewhere (a limit of 0.3 met had been offered its peak, 0.16, to "raise" it
    // to).
    let proposed = advice.split("to at least [").nth(1).and_then(|r| r.split(']').next()).unwrap_or_default();
    let proposed: Vec<f64> = proposed.split(", ").map(|v| v.parse().unwrap()).collect();
    let (reached, given) = (&impossible.verification.max_uf, [1e6, 1e6, 1e8]);
    let fits = |((p, r), l): ((&f64, &f64), &f64)| if r > l { p >= r && *p <= 1.1 * r } else { p == l };
    assert!(proposed.iter().zip(reached).zip(&given).all(fits), "{proposed:?} for {reached:?}");
    assert!(reached.iter().zip(&given).any(|(r, l)| r < l), "an input within its limit: {reached:?}");
    // The relaxation's note does not call the kept candidate within the limits.
    let note = &impossible.verification.relaxation;
    assert!(
        note.contains("kept")
            && note.ends_with(
                "none within the actuator limits: the closest to them (the least max|u_f,i| / limit at worst)"
            ),
        "{note}"
    );
    for (bad, found) in [(vec![1e7, 1e7], "found 2"), (vec![1e7, -1.0, 1e8], "found -1")] {
        let e = auto_design(&doc, &Targets { u_limit: bad, ..Targets::default() }).unwrap_err().to_string();
        assert!(e.starts_with("u_limit: expected") && e.contains(found), "{e}");
    }
    println!("one limit: {:?}; per input: {:?}", one.verification.max_uf, each.verification.max_uf);
}

/// The two-beat rule on a plant other than the quadruple tank: a stable SISO plant (poles −1, −2,
/// input delay 0.3 s) asked to track a bias plus two close harmonics, 1.0 and 1.2 rad/s (one beat
/// 2π/0.2 = 31.4 s), against a disturbance at 2.5 rad/s, over 20 s: 0.64 of a beat (measured: tail
/// max|e| 0.17 against the bound 0.03). The automatic design's verification fails and proposes a
/// t_end between two beats (computed here from the frequencies) and 1.1× that; with t_end set to
/// the proposal (63 s) the design passes, and the scenario it writes, read back and run again,
/// keeps the tail within 1 % of the reference's peak (measured 1.1e-2 against 3e-2).
#[test]
fn close_harmonics_of_a_stable_siso_plant_are_refused_with_the_t_end_that_works() {
    let text = "[plant]\nA = [[0.0, 1.0], [-2.0, -3.0]]\nB = [[0.0], [1.0]]\nC = [[1.0, 0.0]]\n\
        D = [[0.0], [1.0]]\nQ = [[0.0]]\ndelays = [0.3]\n[design]\n\
        [reference]\ncomponents = [{ bias = 1.0, harmonics = [{ amplitude = 1.0, frequency = 1.0 }, { amplitude = 1.0, frequency = 1.2 }] }]\n\
        [disturbance]\ncomponents = [{ harmonics = [{ amplitude = 0.5, frequency = 2.5 }] }]\n\
        [simulation]\nt_end = 20.0\noutput_step = 0.01\n";
    refused_then_passes_at_the_proposed_t_end(text.parse().unwrap(), 1.2 - 1.0);
}

/// The automatic design of `doc` fails its verification with advice proposing a t_end between two
/// beats of the closest frequencies (`gap` rad/s apart, computed by the caller) and 1.1× that (two
/// significant digits rounded up); at that t_end it passes, and the scenario it writes, read back
/// and run again, keeps every channel's tail within 1 % of its reference's peak.
fn refused_then_passes_at_the_proposed_t_end(doc: toml::Table, gap: f64) {
    let short = auto_design(&doc, &Targets::default()).unwrap();
    assert!(!short.verification.passed, "{:?}", short.verification);
    let advice = short.verification.advice.join("\n");
    let proposed = number_after(&advice, "lengthen simulation.t_end to at least ", " s");
    let two_beats = 2.0 * 2.0 * std::f64::consts::PI / gap;
    // The beats are named; the horizon proposed is the shortest estimate the design verified, at
    // most two beats (rounded up): the averaged law's may be shorter, and passes.
    assert!(advice.contains("the horizon is too short to tell the signals' two closest frequencies apart"), "{advice}");
    assert!(proposed <= 1.1 * two_beats, "{proposed} against {two_beats}: {advice}");

    let mut doc = doc;
    doc["simulation"].as_table_mut().unwrap().insert("t_end".into(), toml::Value::Float(proposed));
    let long = auto_design(&doc, &Targets::default()).unwrap();
    assert!(long.verification.passed && long.verification.advice.is_empty(), "{:?}", long.verification);
    let s = Scenario::from_toml(&long.scenario.to_toml()).unwrap();
    let r = Run::of(&s, &s.design().unwrap()).simulate(|_| ControlFlow::Continue(())).unwrap();
    for (i, c) in s.reference.components.iter().enumerate() {
        let tail = r.max_abs_error(i, 0.9 * proposed, proposed).unwrap();
        println!("channel {}: proposed t_end = {proposed} s (two beats {two_beats:.2} s), tail {tail:e}", i + 1);
        assert!(tail <= TAIL_BOUND * c.peak(), "channel {}: tail {tail:e} against {:e}", i + 1, TAIL_BOUND * c.peak());
    }
}

/// The number in `text` between `prefix` and the next `end`; panics naming what is missing.
fn number_after(text: &str, prefix: &str, end: &str) -> f64 {
    text.split_once(prefix)
        .and_then(|(_, rest)| rest.split_once(end))
        .and_then(|(v, _)| v.parse().ok())
        .unwrap_or_else(|| panic!("no number after {prefix:?}: {text}"))
}

/// Each choice's value is the key's value as the written scenario holds it (the report printed
/// complex observer poles by their real parts alone: random15.toml keeps plant zeros such as
/// −1.886 ± 0.073i, reported as −1.886 twice).
#[test]
fn each_choice_is_reported_as_the_written_scenario_holds_it() {
    for name in ["random15.toml", "maglev.toml", "wood-berry.toml"] {
        let doc = without_design(&data(name));
        let a = auto_design(&doc, &Targets::default()).unwrap();
        let written: toml::Table = a.scenario.to_toml().parse().unwrap();
        for c in &a.choices {
            let key = c.key.strip_prefix("design.").unwrap();
            let reported: toml::Table = format!("v = {}", c.value).parse().unwrap();
            assert_eq!(Some(&reported["v"]), written["design"].get(key), "{name}: {}", c.key);
        }
        if name == "random15.toml" {
            let poles = &written["design"]["observer_poles"];
            assert!(poles.as_array().unwrap().iter().any(|p| p.is_array()), "complex poles as [re, im] pairs: {poles}");
        }
    }
}

/// The verification reports the run's RMS error about the convergence time μ was chosen for
/// (over [0.9, 1.1]·t_c, t_c = t_end/20 by default) beside μ's aim, 0.2 % of each reference's
/// peak: the averaged law behind μ is optimistic where Ω̄ is poorly excited, and the report said
/// nothing when the run missed the time (Wood–Berry: 15× and 164× the aim at 30 min).
#[test]
fn the_error_at_the_convergence_time_is_reported_against_the_aim() {
    let a = auto_design(&without_design(&data("wood-berry.toml")), &Targets::default()).unwrap();
    let v = &a.verification;
    let t_c = a.scenario.simulation.t_end / 20.0;
    assert_eq!(v.convergence_time, t_c);
    let r = quell::sim::Run::of(&a.scenario, &a.design).simulate(|_| std::ops::ControlFlow::Continue(())).unwrap();
    for (i, g) in a.scenario.reference.components.iter().enumerate() {
        assert_eq!(v.aim_at_convergence[i], 0.002 * g.peak());
        // RMS of the recorded e_i with t in [0.9, 1.1]·t_c, computed here from the samples.
        let e: Vec<f64> =
            (0..r.t.len()).filter(|&k| r.t[k] >= 0.9 * t_c && r.t[k] <= 1.1 * t_c).map(|k| r.e[k * r.m + i]).collect();
        let rms = (e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt();
        assert!(
            e.len() > 10 && (v.rms_at_convergence[i] - rms).abs() <= 1e-12 * rms,
            "{} vs {rms}",
            v.rms_at_convergence[i]
        );
    }
    assert!(
        v.rms_at_convergence.iter().zip(&v.aim_at_convergence).any(|(r, a)| r > a),
        "the miss this test was written for"
    );
}

/// A first proposal far faster than its horizon is not verified: a DC motor in milliseconds (the
/// CTMS model: electrical pole at −1454 /ms) over 2000 ms. The plant's fastest eigenvalue sets the
/// time scale, the loop runs at ρ ≈ 1.7e4 /ms, ρ·t_end ≈ 3.5e7: the verifying run took two minutes
/// and ended on its 1 GiB memory budget (tryout, 2026-12-03). Now no simulation is started and the
/// advice names the rate, the eigenvalue and the keys to give.
#[test]
fn a_proposal_far_faster_than_its_horizon_is_not_simulated() {
    let text = r#"
[plant]
A = [[0.0, 1.0, 0.0], [0.0, -0.0010865, 0.0084872], [0.0, -9963.6, -1454.5]]
B = [[0.0], [0.0], [363.64]]
C = [[1.0, 0.0, 0.0]]
D = [[0.0], [0.30975], [0.0]]
Q = [[0.0]]
delays = [0.2]
time_unit = "ms"
[design]
[reference]
components = [ { bias = 1.0, harmonics = [{ amplitude = 0.5, frequency = 0.01 }] } ]
[disturbance]
components = [ { bias = 0.001 } ]
[simulation]
t_end = 2000.0
output_step = 1.0
"#;
    let a = auto_design(&toml::from_str(text).unwrap(), &Targets::default()).unwrap();
    let v = &a.verification;
    assert!(!v.passed && v.runs == 0 && v.steps == 0, "{v:?}");
    let advice = &v.advice[0];
    assert!(
        advice.contains("ρ·t_end = 3.5e7 time constants") && advice.contains("fastest eigenvalue (1.454e3/ms)"),
        "{advice}"
    );
    // The paper's loop (ρ = 9 /s over 100 s) is far from it, and verified as before.
    assert!(
        auto_design(&without_design(quell::scenario::PAPER_EXAMPLE), &Targets::default()).unwrap().verification.runs
            >= 1
    );
}

/// A regulated output (its reference 0 throughout: the paper's second component made 0) had a
/// tail bound of 1 % of 0, which no run meets, and the verification failed with a tail of 1e-8.
/// The bound is now 1 % of that channel's error peak in the first verifying run (the first
/// proposal's), the scale the run's diagnostics use, and the run settles (2 % of the error's peak).
#[test]
fn a_regulated_output_gets_a_bound_and_a_settling_time() {
    let text = quell::scenario::PAPER_EXAMPLE.replace("{ bias = 2.0 }", "{ bias = 0.0 }");
    assert!(text.contains("{ bias = 0.0 }"));
    let auto = auto_design(&without_design(&text), &Targets::default()).unwrap();
    let v = &auto.verification;
    assert!(v.bound[1] > 0.0 && v.tail_max_e[1] <= v.bound[1], "{:?} against {:?}", v.tail_max_e, v.bound);
    assert!(v.passed, "{v:?}");
    let r = Run::of(&auto.scenario, &auto.design).simulate(|_| ControlFlow::Continue(())).unwrap();
    assert!(r.summary()[1].figures.settle_t.is_some(), "{:?}", r.summary()[1]);
}

/// A scenario without a `[design]` table is an empty one to the automatic design (it refused it
/// with "design: missing"), and the table it writes is complete.
#[test]
fn a_scenario_without_a_design_table_is_designed_whole() {
    let mut doc: toml::Table = quell::scenario::PAPER_EXAMPLE.parse().unwrap();
    doc.remove("design");
    assert!(Scenario::from_document(&doc).unwrap_err().to_string().starts_with("design: missing"));
    let auto = auto_design(&doc, &Targets::default()).unwrap();
    assert!(auto.verification.passed);
    let written: toml::Table = auto.scenario.to_toml().parse().unwrap();
    assert!(Scenario::from_document(&written).is_ok());
}

/// Where the halving for the sample time costs the disturbance observer its fidelity (the Quanser
/// helicopter, tests/data/quanser-heli.toml, at 2 ms: the rules' observer passes ω within 0.035,
/// the one 16× slower with 0.49), the observer's reason says so and what would keep it.
#[test]
fn the_sampled_halving_says_when_it_costs_the_disturbance_observer() {
    let text = data("quanser-heli.toml").replace("[simulation]\n", "[simulation]\nsample_time = 0.002\n");
    let a = auto_design(&without_design(&text), &Targets::default()).unwrap();
    let why = &a.choices.iter().find(|c| c.key == "design.observer_poles").unwrap().why;
    let kept = quell::diagnostics::Averaged::new(&a.design, &a.scenario.reference, &a.scenario.disturbance)
        .fidelity
        .iter()
        .map(|f| f.relative_error)
        .fold(0.0, f64::max);
    assert!(kept > 0.3, "{kept}");
    assert!(
        why.contains("its error is 3.52e-2 at worst; ×0.0625 of that for simulation.sample_time = 0.002 s"),
        "{why}"
    );
    assert!(
        why.ends_with(&format!("; its error is then {kept:.2e} at worst: the sample time costs the disturbance observer's fidelity (the run's diagnostics say so where a tail misses its bound), which a shorter simulation.sample_time would keep")),
        "{why}"
    );
}

/// A design that fails because the horizon is shorter than its adaptation needs (a servo in ms,
/// tests/data/servo-ms.toml with sizes of 1 given: its slowest excited direction converges in
/// 1/(μλ) ≈ 1.3 s, the stiffness cap keeps μ, and 2 s leave a tail error of 14 % of the
/// reference's peak) gets advice with the horizon the averaged law calls for; with that horizon
/// the same rules pass. (Without the sizes its load torque, 1/67 of the reference, is sized after
/// the first run and the design passes in the 2 s: `a_disturbance_small_only_in_its_units_…`.)
#[test]
fn a_horizon_too_short_for_the_adaptation_gets_the_one_it_needs() {
    let text = data("servo-ms.toml");
    let a = auto_design(&with_unit_sizes(without_design(&text)), &Targets::default()).unwrap();
    assert!(!a.verification.passed);
    let advice = a.verification.advice.join("\n");
    let proposed = advice
        .split("lengthen simulation.t_end to at least ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|t| t.parse::<f64>().ok())
        .unwrap_or_else(|| panic!("no horizon proposed: {advice}"));
    assert!(advice.contains("channel 1: its slowest excited direction of Ω̄ converges in 1/(μλ) = "), "{advice}");
    // 3 × the predicted time over 0.9, well beyond the 2 s given.
    assert!((10_000.0..100_000.0).contains(&proposed), "{proposed}");
    let longer = text.replace("t_end = 2000.0", &format!("t_end = {proposed:?}"));
    let b = auto_design(&with_unit_sizes(without_design(&longer)), &Targets::default()).unwrap();
    assert!(b.verification.passed, "{:?}", b.verification);
    assert!(b.verification.advice.is_empty(), "{:?}", b.verification.advice);
}

/// Where halving the poles stops lowering the loop's rate (the disk drive's own 16.5 rad/ms mode
/// sets ρ = 18.85 /ms), the reason says T_s·ρ is still above the bound and which sample time would
/// meet it (0.2 / 18.85 = 0.0106 ms, with one a run accepts beside the 0.025 ms output step), not
/// that it is met.
#[test]
fn a_sample_time_the_poles_cannot_meet_is_said_to_be_missed() {
    let text = data("hdd-servo.toml").replace("output_step = 0.005", "output_step = 0.025\nsample_time = 0.025");
    let a = auto_design(&without_design(&text), &Targets::default()).unwrap();
    let why = &a.choices.iter().find(|c| c.key == "design.channel_poles").unwrap().why;
    assert!(
        why.contains("(T_s·ρ = 0.47, still above 0.2: ρ = 1.885e1/ms")
            && why.contains("a simulation.sample_time T_s ≤ 0.0106 ms (T_s·ρ ≤ 0.2), e.g. 0.005 ms, which makes plant.delays whole and divides simulation.output_step would meet it"),
        "{why}"
    );
}

/// Signals that excite nothing (every component zero) leave μ free: the design writes 1 and
/// passes (it was μ = inf, refused as a design key with a note on filter poles).
#[test]
fn signals_that_excite_nothing_leave_mu_at_one() {
    let paper = quell::scenario::PAPER_EXAMPLE;
    let (start, end) = (paper.find("[design]").unwrap(), paper.find("[simulation]").unwrap());
    let zero = "[design]\n[reference]\ncomponents = [{ bias = 0.0 }, { bias = 0.0 }]\n[disturbance]\ncomponents = [{ bias = 0.0 }, { bias = 0.0 }]\n";
    let doc: toml::Table = format!("{}{zero}{}", &paper[..start], &paper[end..]).parse().unwrap();
    let auto = auto_design(&doc, &Targets::default()).unwrap();
    assert_eq!(auto.scenario.design.mu, [1.0, 1.0]);
    assert!(auto.verification.passed, "{:?}", auto.verification);
}

/// A channel whose slowest direction no horizon converges (the SI vessel's, from an empty design:
/// 1/(μλ) ≈ 6e15 s) is advised to excite it, and no longer silences the advice on the others (the
/// verification failed with no advice at all); no horizon is proposed while one channel cannot
/// converge (4100 s was, which fails).
#[test]
fn a_channel_no_horizon_converges_is_told_to_excite_it() {
    let text = include_str!("data/vessel-si.toml");
    let (start, end) = (text.find("[design]").unwrap(), text.find("[reference]").unwrap());
    let doc: toml::Table = format!("{}[design]\n{}", &text[..start], &text[end..]).parse().unwrap();
    let auto = auto_design(&with_unit_sizes(doc), &Targets::default()).unwrap();
    assert!(!auto.verification.passed, "{:?}", auto.verification);
    let advice = auto.verification.advice.join("\n");
    assert!(advice.contains("channel 1: the averaged law predicts") && advice.contains("no horizon helps"), "{advice}");
    assert!(
        advice.contains("channel 2: its slowest excited direction of Ω̄ converges in"),
        "channel 2's line: {advice}"
    );
    assert!(!advice.contains("lengthen"), "{advice}");
}

/// The active suspension (examples/apps/active-suspension: a quarter bus, forces in N) in the
/// continuous loop with only the paper's form of the regressor given (sampled at the file's 1 kHz,
/// its first proposals drive u_f beyond twice their continuous loop's, 1.2e9 N against 3.5e8, and
/// the slower ones miss at every horizon). Its verification fails at 30 s; the advice names a
/// horizon the design repeated there passes (it proposed the averaged law's 1500 s unverified,
/// which failed), and a design asked for with that horizon (the advice followed literally) passes.
#[test]
fn a_failed_verification_names_a_horizon_it_has_verified() {
    let text = include_str!("../../../examples/apps/active-suspension/scenario.toml");
    let mut doc = with_unit_sizes(without_design(text));
    doc["simulation"].as_table_mut().unwrap().remove("sample_time");
    doc["design"].as_table_mut().unwrap().insert("regressor_scaling".into(), "paper".into());
    let short = auto_design(&doc, &Targets::default()).unwrap();
    assert!(!short.verification.passed, "{:?}", short.verification);
    let advice = short.verification.advice.join("\n");
    let proposed = number_after(&advice, "lengthen simulation.t_end to at least ", " s");
    assert!(advice.contains("the automatic design repeated with that horizon passes its verification"), "{advice}");
    doc["simulation"].as_table_mut().unwrap().insert("t_end".into(), toml::Value::Float(proposed));
    let long = auto_design(&doc, &Targets::default()).unwrap();
    assert!(long.verification.passed && long.verification.advice.is_empty(), "{:?}", long.verification);
}

/// Where every estimate misses, the largest doubled is tried: the VTOL (tests/data/vtol.toml) from
/// an empty design at 10 s misses at 63 s (two beats of 0.3 and 0.5 rad/s) and passes at 126 s;
/// the averaged law's 91,000 s, beyond 100× t_end, is not proposed (followed, it took minutes and
/// 1.2 GB).
#[test]
fn a_horizon_that_misses_is_doubled_and_none_beyond_the_cap_is_proposed() {
    let text = data("vtol.toml").replace("t_end = 200.0", "t_end = 10.0");
    let mut doc = without_design(&text);
    let short = auto_design(&doc, &Targets::default()).unwrap();
    let advice = short.verification.advice.join("\n");
    let proposed = number_after(&advice, "lengthen simulation.t_end to at least ", " s");
    assert!(
        advice.contains("126 s (63 s doubled 1×)") && advice.contains("shorter ones missed: 63 s (2 beats"),
        "{advice}"
    );
    assert_eq!(proposed, 126.0);
    doc["simulation"].as_table_mut().unwrap().insert("t_end".into(), toml::Value::Float(proposed));
    assert!(auto_design(&doc, &Targets::default()).unwrap().verification.passed);
}

/// The same suspension as a continuous loop, nothing given: the first proposal (observer poles to
/// −511 /s, κ₂ = 1.3e8) blows up on the heavier true bus within 0.08 s. The automatic design slows
/// its channel and observer poles and passes, saying why in their choices (it gave up with "give
/// some [design] keys by hand").
#[test]
fn a_first_proposal_that_blows_up_is_slowed_until_it_verifies() {
    let text =
        include_str!("../../../examples/apps/active-suspension/scenario.toml").replace("sample_time = 0.001", "");
    let a = auto_design(&with_unit_sizes(without_design(&text)), &Targets::default()).unwrap();
    assert!(a.verification.passed, "{:?}", a.verification);
    for key in ["design.channel_poles", "design.observer_poles"] {
        let why = &a.choices.iter().find(|c| c.key == key).unwrap().why;
        assert!(
            why.contains(
                "of the rules' poles in all: the verifying runs of the faster proposals ended early (the last: "
            ),
            "{why}"
        );
    }
    let slowest = |d: &quell::Design| d.observer_eigenvalues().iter().map(|p| p.norm()).fold(0.0, f64::max);
    assert!(slowest(&a.design) < 511.0 / 1.9, "{}", slowest(&a.design));
}

/// A loop that diverges slowly on its true plant (the paper's with B × 1.2 and a 0.3 s actuator
/// delay) is not told to lengthen the horizon (it was: "the horizon is too short"), but that its
/// error grows.
#[test]
fn a_slowly_diverging_loop_is_not_told_to_lengthen_the_horizon() {
    let paper = quell::scenario::PAPER_EXAMPLE;
    let (start, end) = (paper.find("[design]").unwrap(), paper.find("[reference]").unwrap());
    let truth = "[truth]\nB = [[-2.4, 1.2], [2.4, -1.2], [1.2, 0.0]]\nactuator_delays = [0.3, 0.3]\n";
    let text =
        format!("{}[design]\n{}{truth}", &paper[..start], &paper[end..]).replace("t_end = 100.0", "t_end = 20.0");
    let a = auto_design(&text.parse().unwrap(), &Targets::default()).unwrap();
    assert!(!a.verification.passed, "{:?}", a.verification);
    let advice = a.verification.advice.join("\n");
    assert!(advice.contains("'s error grows over the run") && !advice.contains("lengthen"), "{advice}");
}

/// With an actuator limit, the horizon the advice calls verified passes with that limit: the
/// repeat is the whole design, limits included (it checked the tails alone, and the paper at
/// 26 s with --u-limit 25 then failed on the limit).
#[test]
fn a_verified_horizon_holds_under_the_actuator_limit() {
    let paper = quell::scenario::PAPER_EXAMPLE;
    let (start, end) = (paper.find("[design]").unwrap(), paper.find("[reference]").unwrap());
    let text = format!("{}[design]\n{}", &paper[..start], &paper[end..]).replace("t_end = 100.0", "t_end = 5.0");
    let targets = Targets { u_limit: vec![25.0], ..Targets::default() };
    let mut doc: toml::Table = text.parse().unwrap();
    let short = auto_design(&doc, &targets).unwrap();
    let advice = short.verification.advice.join("\n");
    let proposed = number_after(&advice, "lengthen simulation.t_end to at least ", " s");
    assert!(advice.contains("passes its verification (within the actuator limits: "), "{advice}");
    doc["simulation"].as_table_mut().unwrap().insert("t_end".into(), toml::Value::Float(proposed));
    let long = auto_design(&doc, &targets).unwrap();
    assert!(long.verification.passed, "{proposed} s: {:?}", long.verification);
    assert!(long.verification.max_uf.iter().all(|&u| u <= 25.0), "{:?}", long.verification.max_uf);
}

/// Stopped during the search for a longer horizon (the servo in ms with sizes of 1 fails at 2000
/// ms), the design still returns its failed verification, with the search so far, not only
/// "interrupted".
#[test]
fn a_stop_during_the_horizon_search_keeps_the_failed_verification() {
    let doc = with_unit_sizes(without_design(&data("servo-ms.toml")));
    let mut stop_longer = |p: &quell::auto::Progress| {
        if p.t_end > 2000.0 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    };
    let a = quell::auto::auto_design_with(&doc, &Targets::default(), &mut stop_longer).unwrap();
    assert!(!a.verification.passed);
    let advice = a.verification.advice.join("\n");
    assert!(advice.contains("the search for a horizon that passes was interrupted at "), "{advice}");
    assert!(advice.contains("channel 1: its slowest excited direction of Ω̄ converges in"), "{advice}");
}

/// A square wave's first `count` odd harmonics of `w0` (amplitudes 1/k) as one reference of
/// x' = −x + u (0.1 s delay) over `t_end`, from an empty design.
fn square_wave(count: usize, w0: f64, t_end: f64) -> toml::Table {
    let harmonics: Vec<String> = (0..count)
        .map(|k| format!("{{ amplitude = {}, frequency = {} }}", 1.0 / (2 * k + 1) as f64, w0 * (2 * k + 1) as f64))
        .collect();
    format!(
        "[plant]\nA = [[-1.0]]\nB = [[1.0]]\nC = [[1.0]]\ndelays = [0.1]\n[design]\n[reference]\ncomponents = [ {{ harmonics = [{}] }} ]\n[simulation]\nt_end = {t_end:?}\n",
        harmonics.join(", ")
    )
    .parse()
    .unwrap()
}

/// Ω̄'s eigenvalue spread for the reference filter (G_g, L_g) of one component driven by its
/// harmonics: Σ_k (a_k²/2) Re(v_k v_kᴴ), v_k = (jω_k I − G_g)⁻¹ L_g (the time average of ξ̂ξ̂ᵀ
/// in closed form), as λ_min/λ_max.
fn regressor_spread(design: &quell::Design, harmonics: &[(f64, f64)]) -> f64 {
    let (G, L) = (design.G_g(), design.L_g());
    let q = G.nrows();
    let mut gram = DMatrix::<f64>::zeros(q, q);
    for &(a, w) in harmonics {
        let mut M = G.map(|x| Complex::new(-x, 0.0));
        for i in 0..q {
            M[(i, i)] += Complex::new(0.0, w);
        }
        let v = M.lu().solve(&L.map(|x| Complex::new(x, 0.0))).unwrap();
        gram += (&v * v.adjoint()).map(|z| z.re) * (a * a / 2.0);
    }
    let e = gram.symmetric_eigen().eigenvalues;
    e.min() / e.max()
}

/// Many harmonics in one component (docs/tuning.md): five odd harmonics of 0.1 rad/s over 1000 s.
/// As distinct real poles in the normalized companion form the regressor's λ_min/λ_max is 3.1e-9
/// and the design fails (tail 0.17 against 0.018); with a resonator −b ± jω per harmonic (the
/// modal form, which the rules choose from four harmonics in a component on) it is 6.8e-3 and the
/// design passes. The spread is computed here in closed form from the designs' (G_g, L_g).
#[test]
fn many_harmonics_are_tracked_with_a_resonator_each() {
    let doc = square_wave(5, 0.1, 1000.0);
    let harmonics: Vec<(f64, f64)> = (0..5).map(|k| (1.0 / (2 * k + 1) as f64, 0.1 * (2 * k + 1) as f64)).collect();
    let modal = auto_design(&doc, &Targets::default()).unwrap();
    assert_eq!(modal.scenario.design.regressor_scaling, quell::design::RegressorScaling::Modal);
    assert!(modal.verification.passed, "{:?}", modal.verification);
    let poles = &modal.scenario.design.reference_filter_poles[0];
    for &(_, w) in &harmonics {
        assert!(poles.iter().any(|p| (p.im - w).abs() < 1e-12 && p.re < 0.0), "{w}: {poles:?}");
    }
    let mut normalized_doc = doc.clone();
    normalized_doc["design"].as_table_mut().unwrap().insert("regressor_scaling".into(), "normalized".into());
    let normalized = auto_design(&normalized_doc, &Targets::default()).unwrap();
    assert!(!normalized.verification.passed, "{:?}", normalized.verification);
    let (m, n) = (regressor_spread(&modal.design, &harmonics), regressor_spread(&normalized.design, &harmonics));
    assert!(m > 1e-3 && n < 1e-7, "λ_min/λ_max: modal {m:.3e}, normalized {n:.3e}");
}

/// A regressor whose Ω entries exceed 10,000 is not simulated (a hundred harmonics of the CSTR, q =
/// 203, 41,412 entries, had not finished its verification in seven minutes): 150 harmonics of one
/// channel (q = 300, 45,150 entries) fail at once, with no run, naming q and what to do.
#[test]
fn a_regressor_too_large_to_verify_is_not_simulated() {
    let auto = auto_design(&square_wave(150, 0.001, 100_000.0), &Targets::default()).unwrap();
    let v = &auto.verification;
    assert!(!v.passed && v.runs == 0 && v.steps == 0, "{v:?}");
    assert_eq!(auto.design.q(), 300);
    let advice = v.advice.join("\n");
    assert!(
        advice.contains("the regressor has q = 300 states") && advice.contains("carry 45150 entries of Ω"),
        "{advice}"
    );
    assert!(advice.contains("track fewer harmonics"), "{advice}");
}

/// A file that gives μ keeps the paper's form (μ's meaning depends on it), now said in the
/// choices; with four harmonics in a component its verification fails, and the advice names the
/// modal form, which followed (the key added, μ kept) passes.
#[test]
fn a_given_mu_with_many_harmonics_is_told_of_the_modal_form() {
    let mut doc = square_wave(4, 0.1, 1000.0);
    doc["design"].as_table_mut().unwrap().insert("mu".into(), toml::Value::Array(vec![toml::Value::Float(10.0)]));
    let paper = auto_design(&doc, &Targets::default()).unwrap();
    let chose = paper.choices.iter().find(|c| c.key == "design.regressor_scaling").unwrap();
    assert!(chose.value == "\"paper\"" && chose.why.starts_with("the file gives μ"), "{chose:?}");
    assert!(!paper.verification.passed, "{:?}", paper.verification);
    let advice = paper.verification.advice.join("\n");
    assert!(
        advice.contains("a component has 4 harmonics") && advice.contains("design.regressor_scaling = \"modal\""),
        "{advice}"
    );
    // The design report beside a stiff μ names the modal form too (it had named only "normalized").
    let mut spec = paper.scenario.design.clone();
    spec.mu = vec![1e9];
    let stiff = quell::Design::new(&paper.scenario.plant, &spec).unwrap();
    let s = &paper.scenario;
    let estimates = quell::diagnostics::estimate(&stiff, &s.plant, &s.reference, &s.disturbance, 1000.0);
    assert!(
        estimates[0].advice.iter().any(|a| a.contains("adapts at") && a.contains("regressor_scaling = \"modal\"")),
        "{:?}",
        estimates[0].advice
    );
    doc["design"].as_table_mut().unwrap().insert("regressor_scaling".into(), "modal".into());
    let modal = auto_design(&doc, &Targets::default()).unwrap();
    assert!(modal.verification.passed, "{:?}", modal.verification);
}

/// A plant realized from its transfer function (python-control's `ss(tf(...))`, a companion form
/// whose entries span ten decades): the DC motor of the University of Michigan's Control Tutorials
/// (J = 3.2284e-6, b = 3.5077e-6, K = 0.0274, R = 4, L = 2.75e-6; poles 0, −59 and −1.45e6 /s).
/// Placing the observer from its fastest eigenvalue is ill-conditioned in this realization: it had
/// been refused (and the refusal had blamed many harmonics); it is placed on the balanced
/// realization (`tests/place.rs`), and the design is then told what its rates cost, not its
/// harmonics.
#[test]
fn a_companion_form_is_placed_and_told_its_rates_not_its_harmonics() {
    let text = r#"
[plant]
A = [[-1454546.5441054385, -86143521.68050542, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
B = [[1.0], [0.0], [0.0]]
C = [[0.0, 0.0, 3086281645.3728113]]
D = [[1.0], [0.0], [0.0]]
Q = [[0.0]]
delays = [0.001]
[design]
[reference]
components = [ { harmonics = [{ amplitude = 1.0, frequency = 2.0 }] } ]
[disturbance]
components = [ { bias = 0.5 } ]
[simulation]
t_end = 10.0
"#;
    let a = auto_design(&text.parse().unwrap(), &Targets::default()).unwrap();
    let advice = a.verification.advice.join("\n");
    assert!(!a.verification.passed && !advice.contains("many harmonics"), "{advice}");
    assert!(advice.contains("the rules' time scale follows the plant's fastest eigenvalue (1.454e6/s)"), "{advice}");
}

/// g and ω in units of very different sizes: the magnetic bearing's gaps of 1e-5 m against forces of
/// 20 N (tests/data/magnetic-bearing.toml, its [design] left to the rules). From an empty design the
/// automatic design sizes the components and passes. With sizes of 1 given, in Ω̄ the reference's
/// directions are excited 1.5e-11 of the disturbance's, so no μ below the stiffness threshold
/// converges them and no horizon passes. The advice had asked for "more excitation"; it now names
/// the sizes, or to express ω in larger units, by a factor s, and the same plant with D and Q times
/// s and ω over s, designed again, passes; a run of the file's design says the same.
#[test]
fn units_of_very_different_sizes_are_named_and_rescaling_passes() {
    // From an empty design the components are sized (peaks 1e-5 m and 20 N) and it passes at once.
    let doc = without_design(&data("magnetic-bearing.toml"));
    let sized = auto_design(&doc, &Targets::default()).unwrap();
    assert!(sized.verification.passed && sized.design.has_sizes(), "{:?}", sized.verification);
    let doc = with_unit_sizes(doc);
    let failed = auto_design(&doc, &Targets::default()).unwrap();
    assert!(!failed.verification.passed);
    let advice = failed.verification.advice.join("\n");
    assert!(
        advice.contains("express the disturbance in larger units: Ω̄'s directions at the reference's frequencies"),
        "{advice}"
    );
    assert!(!advice.contains("excite the slow directions better"), "{advice}");
    let s = number_after(&advice, "with s about ", " (the two parts");
    assert!((1e5..1e6).contains(&s), "{s}");
    // The advice followed: D and Q times s, every amplitude and bias of ω over s.
    let mut scaled = doc.clone();
    let plant = scaled["plant"].as_table_mut().unwrap();
    for key in ["D", "Q"] {
        for row in plant[key].as_array_mut().unwrap() {
            for v in row.as_array_mut().unwrap() {
                *v = toml::Value::Float(v.as_float().unwrap() * s);
            }
        }
    }
    for c in scaled["disturbance"]["components"].as_array_mut().unwrap() {
        let c = c.as_table_mut().unwrap();
        if let Some(b) = c.get_mut("bias") {
            *b = toml::Value::Float(b.as_float().unwrap() / s);
        }
        for h in c.get_mut("harmonics").and_then(|h| h.as_array_mut()).into_iter().flatten() {
            let a = &mut h.as_table_mut().unwrap()["amplitude"];
            *a = toml::Value::Float(a.as_float().unwrap() / s);
        }
    }
    let passed = auto_design(&scaled, &Targets::default()).unwrap();
    assert!(passed.verification.passed, "{:?}", passed.verification);
    // A run of the file's own design is told the same after its horizon advice.
    let s = Scenario::from_toml(&data("magnetic-bearing.toml")).unwrap();
    let d = s.design().unwrap();
    let r = Run::of(&s, &d).simulate(|_| ControlFlow::Continue(())).unwrap();
    let run_advice = quell::diagnostics::diagnose_run(&s, &d, &r).advice;
    assert!(run_advice.iter().any(|a| a.starts_with("express the disturbance in larger units")), "{run_advice:?}");
}

/// A sampled-data candidate whose run drives u_f beyond twice its continuous loop's is not
/// verified: the first proposal is slowed as one that ended early. A Wardle–Wood column sampled at 1 min
/// (`tests/data/wardle-wood-column.toml`) had passed with max|u_f| about 1e4 against about 20 in
/// its continuous loop (T_s·ρ = 0.034 met the sample-time rule), and the run's advice then sent the
/// user back to the automatic design. Now the kept design's sampled run and its continuous loop,
/// compared here on their own rows, agree within the departure bounds (y within half its peak,
/// u_f's peak within twice), and the poles' reasons say why they were slowed.
#[test]
fn a_sampled_candidate_that_departs_from_its_continuous_loop_is_slowed() {
    let text = data("wardle-wood-column.toml");
    let a = auto_design(&without_design(&text), &Targets::default()).unwrap();
    assert!(a.verification.passed, "{:?}", a.verification);
    let poles = &a.choices.iter().find(|c| c.key == "design.channel_poles").unwrap().why;
    assert!(poles.contains("drove u_f beyond twice their continuous loop's (the last: y[1] by "), "{poles}");
    let go = |_| ControlFlow::Continue(());
    let sampled = Run::of(&a.scenario, &a.design).simulate(go).unwrap();
    let mut s = a.scenario.clone();
    s.simulation.sample_time = None;
    let continuous = Run::of(&s, &a.design).simulate(go).unwrap();
    assert_eq!(sampled.t, continuous.t);
    let m = sampled.m;
    for i in 0..m {
        let (ys, yc) = (sampled.column(&sampled.y, m, i), continuous.column(&continuous.y, m, i));
        let peak = continuous.column(&continuous.y, m, i).fold(0.0f64, |a, v| a.max(v.abs()));
        let gap = ys.zip(yc).fold(0.0f64, |a, (s, c)| a.max((s - c).abs()));
        let (us, uc) = (sampled.max_uf(i), continuous.max_uf(i));
        assert!(
            gap <= 0.5 * peak && us <= 2.0 * uc,
            "channel {}: y gap {gap:e} of peak {peak:e}, u_f {us} against {uc}",
            i + 1
        );
        // The actuator effort of the continuous design (about 20), not the departed one's 1e4.
        assert!(us < 50.0, "{us}");
    }
    // Under measurement noise, which the two loops read at different instants, both are compared
    // without it (a noisy scenario had been verified with no comparison at all): the same design.
    let noisy = format!("{text}\n[noise]\nstd = [1e-4, 1e-4]\nseed = 3\n");
    let b = auto_design(&without_design(&noisy), &Targets::default()).unwrap();
    assert!(b.verification.passed, "{:?}", b.verification);
    let poles = &b.choices.iter().find(|c| c.key == "design.channel_poles").unwrap().why;
    assert!(poles.ends_with("; both without [noise])"), "{poles}");
    assert_eq!(b.design.K(), a.design.K());
}

/// A design the automatic design verified at its sample time is not sent back to it by the run's
/// comparison with the continuous loop: the verification checks u_f against the continuous loop's,
/// not y, and the active suspension's design (examples/apps, 1 kHz, its own true bus) departs in y
/// alone (by 100 % of the continuous peak, at 0.08× its u_f), so the run's line offers the sample
/// time that agrees or slower poles, not the automatic design (it had, circularly).
#[test]
fn a_verified_sampled_design_is_not_sent_back_to_the_automatic_design() {
    let text = include_str!("../../../examples/apps/active-suspension/scenario.toml");
    let a = auto_design(&with_unit_sizes(without_design(text)), &Targets::default()).unwrap();
    assert!(a.verification.passed, "{:?}", a.verification);
    let r = Run::of(&a.scenario, &a.design).simulate(|_| ControlFlow::Continue(())).unwrap();
    let advice = quell::diagnostics::sampled_advice(&a.scenario, &a.design, &r);
    let departs = advice.iter().find(|l| l.contains("departs from its continuous loop")).expect("a departure in y");
    assert!(departs.ends_with("or give slower design.channel_poles and design.observer_poles"), "{departs}");
    assert!(advice.iter().all(|l| !l.contains("automatic design")), "{advice:?}");
}

/// A stop during a sampled verifying run's comparison with its continuous loop ends the
/// automatic design as interrupted: the comparison's side run reports its progress as the
/// verifying run does (its t starts again from 0 within the same run), and a stop there had let
/// the candidate pass unchecked (and the CLI's Ctrl-C, which stops through the progress callback,
/// had not reached the side run at all).
#[test]
fn a_stop_during_the_continuous_comparison_interrupts_the_design() {
    let doc = without_design(&data("wardle-wood-column.toml"));
    let (mut last, mut restarted) = ((0, 0.0), false);
    let mut stop_in_the_side_run = |p: &quell::auto::Progress| {
        restarted |= p.run == last.0 && p.t < last.1;
        last = (p.run, p.t);
        if restarted {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    };
    let e =
        quell::auto::auto_design_with(&doc, &Targets::default(), &mut stop_in_the_side_run).map(|_| ()).unwrap_err();
    assert!(matches!(e, AutoError::Interrupted), "{e:?}");
    assert!(restarted, "the side run reported no progress");
}

/// An LCL-filtered grid inverter over 0.2 s (tests/data/lcl-inverter.toml): the plant's zeros of
/// (A, D, C) are the L1–Cf resonance −R1/(2L1) ± j(ω_r ± ω_grid) in the rotating frame (closed
/// form), which decay by only 2.5 e-folds over the run, so the run's own diagnostics would ask for
/// 30/|Re z| = 2.5 s where an observer holds them. The automatic design does not hold them: held,
/// the disturbance observer leaks 8 % of the d-axis bias (325 V) into the q-axis estimate, 4× that
/// component's size (6.5 V); with all-fast poles both estimates are small, an error of 1.0 of each
/// component's size. Judged in ξ̂_ω's units, which add the two components as numbers, holding them
/// had read 0.11, and that design failed its verification at 0.2 s (tails 0.28, 0.28 against 0.22,
/// 0.01); the all-fast one passes it, with tails of 3.5e-8 and 4.2e-9.
#[test]
fn an_lcl_inverters_slow_zeros_are_not_held_and_its_design_passes_at_its_horizon() {
    let doc = without_design(&data("lcl-inverter.toml"));
    let auto = auto_design(&doc, &Targets::default()).unwrap();
    assert!(auto.verification.passed, "{:?}", auto.verification);
    let (r1, l1, cf, w): (f64, f64, f64, f64) = (0.05, 2e-3, 10e-6, 2.0 * std::f64::consts::PI * 50.0);
    let (re, wr) = (-r1 / (2.0 * l1), (1.0 / (l1 * cf) - (r1 / (2.0 * l1)).powi(2)).sqrt());
    let zeros = disturbance_zeros(auto.design.plant()).unwrap();
    let held = auto.design.observer_eigenvalues();
    for im in [wr + w, wr - w] {
        let z = Complex::new(re, im);
        assert!(zeros.iter().any(|p| (p - z).norm() < 1e-6 * z.norm()), "{z} not among {zeros:?}");
        assert!(held.iter().all(|p| (p - z).norm() > 1e-3 * z.norm()), "{z} held: {held:?}");
    }
    // Held, the run's diagnostics would name them with 30/|Re z|.
    let holding = [zeros.clone(), vec![(-75369.6112).into(), (-150739.2224).into()]].concat();
    let rule = quell::diagnostics::slow_transient_advice(&auto.design.with_observer_poles(&holding).unwrap(), 0.2);
    let rule = rule.unwrap_or_default();
    assert!(rule.contains("lengthen simulation.t_end to 2.5 s"), "{rule}");
    let written: toml::Table = auto.scenario.to_toml().parse().unwrap();
    assert!(Scenario::from_document(&written).is_ok());
}

/// A design verified in the continuous loop whose u_f is the small difference of terms thousands
/// of times its peak is cautioned before it is sampled: the water network's design under a 15
/// (1000 m³/h) pump limit (tests/data/water-network.toml) passes its verification, and its
/// sampled loop diverges at T_s = 0.01 h (36 s) where the same design's continuous loop completes
/// its horizon: what the warning says. The
/// paper's example, whose terms are under 10× its peak, gets none.
#[test]
fn a_design_whose_input_cancels_thousands_of_times_is_cautioned_before_it_is_sampled() {
    let doc = without_design(&data("water-network.toml"));
    let targets = Targets { u_limit: vec![15.0], ..Targets::default() };
    let auto = auto_design(&doc, &targets).unwrap();
    assert!(auto.verification.passed, "{:?}", auto.verification);
    let warning = auto.cancellation_warning().expect("a caution");
    assert!(warning.contains("set simulation.sample_time and run the automatic design again"), "{warning}");
    let s = &auto.scenario;
    let continuous = Run::of(s, &auto.design).simulate(|_| ControlFlow::Continue(())).unwrap();
    assert_eq!(continuous.outcome, Some(quell::sim::Outcome::Completed));
    let settings = quell::sim::RunSettings {
        mode: quell::sim::Loop::Sampled { sample_time: 0.01 },
        ..quell::sim::RunSettings::of(s)
    };
    let sampled = Run::of(s, &auto.design).settings(settings).simulate(|_| ControlFlow::Continue(()));
    let outcome = sampled.unwrap().outcome;
    assert!(matches!(outcome, Some(quell::sim::Outcome::Diverged { .. })), "sampled at 0.01 h: {outcome:?}");
    let paper = without_design(
        &std::fs::read_to_string(format!("{}/../../examples/paper.toml", env!("CARGO_MANIFEST_DIR"))).unwrap(),
    );
    let paper = auto_design(&paper, &Targets::default()).unwrap();
    let ratio = paper.verification.uf_cancellation;
    assert!(ratio < SAMPLED_CANCELLATION && paper.cancellation_warning().is_none(), "{ratio}");
}

/// A regulated channel's bound (1 % of its error's peak: its reference is 0) is read at the rows
/// and between them, so the output step does not set it: a boiler's drum level passed its
/// verification with rows 0.1 min apart and failed with rows 1 min apart, the same run (its peak
/// between rows; helper tryout, 2026-12-06). A ball and beam holding r = 0 against a tilt: its
/// error peaks within the first 30 s, which rows 30 s apart miss (their bound was 2.5e-4 against
/// 2.3e-3).
#[test]
fn a_regulated_channels_bound_does_not_depend_on_the_output_step() {
    let regulated = |step: f64| -> toml::Table {
        let text = data("ball-beam.toml")
            .replace(
                "components = [ { bias = 0.1, harmonics = [{ amplitude = 0.2, frequency = 0.5 }] } ]",
                "components = [ { bias = 0.0 } ]",
            )
            .replace("output_step = 0.01", &format!("output_step = {step}"));
        assert!(text.contains("{ bias = 0.0 }") && text.contains(&format!("output_step = {step}")));
        text.split("\n[truth]\n").next().unwrap().parse().unwrap()
    };
    let bound = |step: f64| {
        let a = auto_design(&regulated(step), &Targets::default()).unwrap();
        (a.verification.bound[0], a.verification.passed)
    };
    let (fine, coarse) = (bound(0.01), bound(30.0));
    assert!(fine.1 && coarse.1, "{fine:?} {coarse:?}");
    // Both are the peak over the solver's step ends (finer than the rows 0.01 s apart here): the
    // same steps, so the same peak but for the rows, to 1e-6 (the peak is flat where it falls).
    assert!((fine.0 - coarse.0).abs() <= 1e-5 * fine.0, "{fine:?} {coarse:?}");
}

/// A steady state beyond the true actuator is named as the cause of a failed verification, first:
/// a ball and beam under a 0.3 drive whose reference and tilt ask 0.333 in steady state (0.0952
/// for the tilt and 0.2381 for the harmonic, as phasors apart in frequency) cannot track whatever
/// the poles (a heating plant asking 15 of a 12 drive had been told to slow its poles; helper
/// tryout, 2026-12-06). The same loop under a 0.45 drive passes and says nothing of it.
#[test]
fn a_steady_state_beyond_the_true_actuator_is_named_first() {
    let text = data("ball-beam.toml").replace("u_max = [0.45]", "u_max = [0.3]");
    assert!(text.contains("u_max = [0.3]"));
    let a = auto_design(&text.parse().unwrap(), &Targets::default()).unwrap();
    let v = &a.verification;
    assert!(!v.passed, "{v:?}");
    assert!(v.advice[0].starts_with("the steady state itself asks more than the true actuator gives (u_f,1 peaks at 0.3333 against truth.u_max[0] = 0.3;"), "{:?}", v.advice);
    let a = auto_design(&data("ball-beam.toml").parse().unwrap(), &Targets::default()).unwrap();
    assert!(a.verification.passed && !a.verification.advice.iter().any(|l| l.contains("the steady state itself")));
}

/// A failed verification whose disturbance observer passes ω poorly names it before asking for more
/// excitation: a B747's pitch channel already tracks a bias and two harmonics, and had been told
/// only to excite its slow directions with "references of several frequencies" while the observer
/// the rules found passed the gust's bias with error 0.94 (helper tryout, 2026-12-06).
#[test]
fn a_failed_design_with_a_poor_disturbance_observer_names_it() {
    // Sized (its pitch reference is 1/100 of its speed's), the automatic design passes; with sizes of 1
    // it fails, and says why.
    let doc: toml::Table = data("b747-longitudinal.toml").parse().unwrap();
    let sized = auto_design(&doc, &Targets::default()).unwrap();
    assert!(sized.design.has_sizes() && sized.verification.passed, "{:?}", sized.verification);
    let a = auto_design(&with_unit_sizes(doc), &Targets::default()).unwrap();
    let v = &a.verification;
    assert!(!v.passed, "{v:?}");
    let d = &a.design;
    let worst = quell::diagnostics::Averaged::new(d, &a.scenario.reference, &a.scenario.disturbance)
        .fidelity
        .iter()
        .map(|f| f.relative_error)
        .fold(0.0, f64::max);
    assert!(worst > FIDELITY_LIMIT, "{worst}");
    let advice = v.advice.join("\n");
    assert!(
        advice.contains(&format!(
            "look first at the disturbance observer, which passes ω at 0 rad/s with relative error {worst:.2}"
        )),
        "{advice}"
    );
}

/// A single-output plant whose modes span 0.0035 … 0.92 /min with a disturbance at 6.28 rad/min
/// (Schnider's propofol model, tests/data/propofol-schnider.toml, no observer poles given): every
/// observer candidate from r_0 = 6r = 37.7 /min up gives a gain the placement's check refuses
/// (verified error 2e-5), and the automatic design had given up, naming the plant's fastest
/// eigenvalue as r's source (it is the disturbance's frequency). It now seeks slower candidates
/// and verifies one: eig(A − LC) recomputed here from L (the test's own balanced QR) is the poles
/// it wrote to 1e-6 relative, all below r_0.
#[test]
fn an_observer_refused_from_r0_up_is_sought_slower() {
    let path = format!("{}/tests/data/propofol-schnider.toml", env!("CARGO_MANIFEST_DIR"));
    let doc: toml::Table = std::fs::read_to_string(path).unwrap().parse().unwrap();
    let auto = auto_design(&doc, &Targets::default()).unwrap();
    let chosen = auto.choices.iter().find(|c| c.key == "design.observer_poles").expect("the observer was chosen");
    assert!(chosen.why.contains("below r_0: every candidate from r_0 up was refused"), "{}", chosen.why);
    let p = &auto.scenario.plant;
    let mut eig = common::eigenvalues(&(&p.A - auto.design.L() * &p.C));
    let value: toml::Table = format!("v = {}", chosen.value).parse().unwrap();
    let mut wanted: Vec<Complex<f64>> =
        value["v"].as_array().unwrap().iter().map(|x| Complex::new(x.as_float().unwrap(), 0.0)).collect();
    assert_eq!(wanted.len(), 4);
    for v in [&mut eig, &mut wanted] {
        v.sort_by(|a, b| a.re.total_cmp(&b.re));
    }
    for (e, w) in eig.iter().zip(&wanted) {
        assert!((e - w).norm() <= 1e-6 * w.norm().max(1.0), "{eig:?} against {wanted:?}");
        assert!(w.norm() < 6.0 * 2.0 * std::f64::consts::PI, "{w} is not below r_0");
    }
}

/// The chosen design of the paper's plant with its delays off: 10 % either way misses the tail
/// bound (as the paper's own design does: its loop diverges at +10 %), so 3 % and then 1 % are
/// tried, and the tolerance is the first both ways met. The +10 % run, repeated here from the
/// written scenario with a `[truth]` table of those delays, ends as the check says.
#[test]
fn the_chosen_design_is_run_with_its_delays_off() {
    let text = quell::scenario::PAPER_EXAMPLE;
    let start = text.find("[design]").unwrap();
    let end = start + text[start..].find("[reference]").unwrap();
    let doc: toml::Table = format!("{}[design]\n{}", &text[..start], &text[end..]).parse().unwrap();
    let auto = auto_design(&doc, &Targets::default()).unwrap();
    let v = &auto.verification;
    let factors: Vec<f64> = v.delay_check.iter().map(|c| c.factor).collect();
    assert!(factors.len() >= 4 && factors.len().is_multiple_of(2), "{factors:?}");
    for (pair, level) in factors.chunks(2).zip([0.1, 0.03, 0.01]) {
        assert_eq!(pair, [1.0 + level, 1.0 - level]);
    }
    // Met: completed, every tail within its bound, u_f within twice the verified run's.
    // What missed is named (a report had blamed the tail where u_f had grown 6e4×).
    for c in &v.delay_check {
        let tail = c.tail_max_e.iter().zip(&v.bound).all(|(e, b)| e <= b);
        let effort = c.max_uf.iter().zip(&v.max_uf).all(|(u, u0)| *u <= 2.0 * u0);
        assert_eq!(c.met, c.ended.is_none() && tail && effort, "{c:?}");
        let expected: Vec<&str> = match c.ended {
            Some(_) => vec!["ended"],
            None => [("tail", tail), ("effort", effort)].iter().filter(|t| !t.1).map(|t| t.0).collect(),
        };
        assert_eq!(c.missed, expected, "{c:?}");
    }
    let met: Vec<bool> = v.delay_check.chunks(2).map(|p| p.iter().all(|c| c.met)).collect();
    // The ladder stops at the first level met both ways (or after the third).
    assert!(!met[0] && met[..met.len() - 1].iter().all(|m| !m), "{:?}", v.delay_check);
    let expected_tolerance = if *met.last().unwrap() { 1.0 - factors[factors.len() - 1] } else { 0.0 };
    assert!((v.delay_tolerance - expected_tolerance).abs() < 1e-12, "{} {expected_tolerance}", v.delay_tolerance);
    for c in &v.delay_check {
        assert_eq!(c.delays.len(), 2);
        assert!((c.delays[0] - c.factor).abs() < 1e-12 && (c.delays[1] - 3.0 * c.factor).abs() < 1e-12);
        assert!((c.error - (c.factor - 1.0).abs()).abs() < 1e-12, "{c:?}");
    }
    // The +10 % run again, from the scenario file the design writes, within 100× the verified
    // run's peaks (ξ̂ at its divergence bound, x̂ at least as x is), as a study's runaway rule.
    let verified = Run::of(&auto.scenario, &auto.design).simulate(&mut |_| ControlFlow::Continue(())).unwrap();
    let longer = format!("{}\n[truth]\ndelays = [1.1, 3.3000000000000003]\n", auto.scenario.to_toml());
    let s = Scenario::from_toml(&longer).unwrap();
    let d = s.design().unwrap();
    let mut bounds = verified.peaks.bounds(100.0);
    bounds.0[2] = Run::of(&s, &d).divergence_bounds().0[2];
    bounds.0[1] = bounds.0[1].max(bounds.0[0]);
    let settings = quell::sim::RunSettings { runaway: Some(bounds), ..quell::sim::RunSettings::of(&s) };
    let r = Run::of(&s, &d).settings(settings).simulate(&mut |_| ControlFlow::Continue(())).unwrap();
    // Ended by the runaway rule below the divergence bound: named as such, not as a divergence
    // (which the rule cannot tell from a transient that settles).
    let Some(quell::sim::Outcome::Diverged { signal, value, .. }) = &r.outcome else { panic!("{:?}", r.outcome) };
    assert!(value.abs() < quell::sim::RunSettings::of(&s).divergence_bound, "{value:e}");
    let said = v.delay_check[0].ended.as_deref().unwrap_or_default();
    assert!(
        said.starts_with(&format!("{signal} reached {value:.3e} at t = "))
            && said.contains("past 100× the verified run's peak of that signal"),
        "{said}"
    );
    // Without the rule it diverges later (it had filled the history budget first in some builds).
    let unbounded = Run::of(&s, &d).simulate(&mut |_| ControlFlow::Continue(())).unwrap();
    assert!(unbounded.t.last() > r.t.last(), "{:?} {:?}", unbounded.outcome, r.outcome);
    // delay_error = 0: no check.
    let none = auto_design(&doc, &Targets { delay_error: Some(0.0), ..Targets::default() }).unwrap();
    assert!(none.verification.delay_check.is_empty() && none.verification.delay_tolerance.is_nan());
}

/// Sampled at 0.05 s, a delay of 0.5 s (10 samples) is run off by its factor exactly, in
/// fractions of a sample where that is one (±3 %: 10.3 and 9.7 samples; they had been rounded to
/// whole samples, ±1 sample = ±10 %, so the levels below ±10 % ran nothing new); each run's error
/// is its factor's. With an actuator limit, a delayed run beyond it is not met, whatever its tail
/// (the paper's plant under 23: the +3 % run's max|u_f,2| passes it).
#[test]
fn a_delay_check_runs_its_factors_exactly_and_respects_the_actuator_limit() {
    let text = include_str!("../../../examples/siso-complex.toml");
    let start = text.find("[design]").unwrap();
    let end = start + text[start..].find("[reference]").unwrap();
    let sampled = format!("{}[design]\n{}", &text[..start], &text[end..])
        .replace("[simulation]\n", "[simulation]\nsample_time = 0.05\noutput_step = 0.1\n");
    let doc: toml::Table = sampled.parse().unwrap();
    let auto = auto_design(&doc, &Targets::default()).unwrap();
    let checks = &auto.verification.delay_check;
    assert!(checks.len() >= 2 && checks.len().is_multiple_of(2), "{checks:?}");
    let delays: Vec<f64> = checks.iter().map(|c| c.delays[0]).collect();
    assert!((delays[0] - 0.55).abs() < 1e-12 && (delays[1] - 0.45).abs() < 1e-12, "{delays:?}");
    for c in checks {
        assert!((c.delays[0] - 0.5 * c.factor).abs() < 1e-12, "{c:?}");
        assert!((c.error - (c.factor - 1.0).abs()).abs() < 1e-9, "{c:?}");
    }

    let paper = quell::scenario::PAPER_EXAMPLE;
    let start = paper.find("[design]").unwrap();
    let end = start + paper[start..].find("[reference]").unwrap();
    let doc: toml::Table = format!("{}[design]\n{}", &paper[..start], &paper[end..]).parse().unwrap();
    let limited = auto_design(&doc, &Targets { u_limit: vec![23.0], ..Targets::default() }).unwrap();
    for c in &limited.verification.delay_check {
        if c.max_uf.iter().any(|u| *u > 23.0) {
            assert!(!c.met && c.missed.contains(&"u_limit"), "{c:?}");
        }
    }
    assert!(
        limited.verification.delay_check.iter().any(|c| c.ended.is_none() && !c.met),
        "{:?}",
        limited.verification.delay_check
    );
}

/// The paper's example with y₁ in mm (C's and Q's first rows and g₁ × 1000): g₁'s peak is 1500×
/// the smallest reference peak (2), so the automatic design sizes the components, each larger one
/// brought to that size within √10 (1e3 for g₁, 1 for the rest): ξ̂ is the paper's own, and the
/// rules choose the paper's design, the same observer poles and β and μ within 1e-4 (the verifying
/// runs' absolute tolerance meets y₁ in other units), its tails within their bounds. The paper in
/// its own units gets no sizes (peaks 3, 2 and 1, 3). Before the sizes, the mm file's Ω̄₁ spread by
/// 6e6 (λ_min 0.13, λ_max 7.8e5) and its design failed its verification with a tail of 5.5e3 mm.
/// The DC motor of examples/apps with its load torque in kN·m (peaks 0.5 rad and 1.5e-5 kN·m) is
/// not sized: a disturbance small in its units is taken to be small in its effect (sized up, by an
/// earlier rule, its sampled verification diverged; unsized it passes).
#[test]
fn an_output_in_millimetres_gets_the_design_of_its_own_units() {
    let paper = without_design(quell::scenario::PAPER_EXAMPLE);
    let mut mm = paper.clone();
    let scale_row = |v: &mut toml::Value| {
        let row = v.as_array_mut().unwrap()[0].as_array_mut().unwrap();
        row.iter_mut().for_each(|x| *x = toml::Value::Float(x.as_float().unwrap() * 1000.0));
    };
    let plant = mm["plant"].as_table_mut().unwrap();
    scale_row(plant.get_mut("C").unwrap());
    scale_row(plant.get_mut("Q").unwrap());
    let text = toml::to_string(&mm).unwrap().replace("amplitude = 3.0", "amplitude = 3000.0");
    assert!(text.contains("amplitude = 3000.0"), "{text}");
    let mm: toml::Table = text.parse().unwrap();
    let (a, b) = (auto_design(&paper, &Targets::default()).unwrap(), auto_design(&mm, &Targets::default()).unwrap());
    assert!(a.verification.passed && b.verification.passed, "{:?}\n{:?}", a.verification, b.verification);
    assert!(!a.design.has_sizes() && !a.choices.iter().any(|c| c.key.ends_with("_sizes")));
    assert_eq!((b.design.reference_sizes(), b.design.disturbance_sizes()), (&[1e3, 1.0][..], &[1.0, 1.0][..]));
    let same = |x: &[Complex<f64>], y: &[Complex<f64>]| x.iter().zip(y).all(|(p, q)| (p - q).norm() <= 1e-9 * p.norm());
    assert!(same(a.design.observer_eigenvalues(), b.design.observer_eigenvalues()));
    assert_eq!(a.design.beta(), b.design.beta());
    for (x, y) in a.design.mu().iter().zip(b.design.mu()) {
        assert!((x - y).abs() <= 1e-4 * x, "μ {:?} against {:?}", a.design.mu(), b.design.mu());
    }
    // The sizes reach the file the design writes, and a run of it reads them back.
    let written = Scenario::from_toml(&b.scenario.to_toml()).unwrap();
    assert_eq!(written.design().unwrap().reference_sizes(), [1e3, 1.0]);
    let motor = include_str!("../../../examples/apps/dc-motor/scenario.toml")
        .replace("D = [[0.0], [-100.0], [0.0]]", "D = [[0.0], [-100000.0], [0.0]]")
        .replace("D = [[0.0], [-66.66666666666667], [0.0]]", "D = [[0.0], [-66666.66666666667], [0.0]]")
        .replace("bias = 0.01, harmonics = [{ amplitude = 0.005,", "bias = 1e-5, harmonics = [{ amplitude = 5e-6,");
    assert!(motor.contains("[-100000.0]") && motor.contains("[-66666.66666666667]") && motor.contains("bias = 1e-5"));
    let kn = auto_design(&without_design(&motor), &Targets::default()).unwrap();
    assert!(!kn.design.has_sizes() && kn.verification.passed, "{:?}", kn.verification);
}

/// The paper's example with ω in units 1000× larger (D and Q ×1000, ω's amplitudes and biases
/// ÷1000: the same plant): its components, 1000× below the references, were taken to be small in
/// their effect and left unsized, and the design failed its verification (tails 240× the bound;
/// Python tryout, 2026-12-07). After that first run the components are sized by their own peaks'
/// powers of ten (1 for g, 1e-3 for ω), which makes ξ̂ the paper's own: the design is the one of
/// the paper's own units (poles and β the same, μ within 1e-9, the verifying runs' tolerance), and
/// the sizes' reason says why.
#[test]
fn a_disturbance_small_only_in_its_units_is_sized_after_its_first_run() {
    let text = quell::scenario::PAPER_EXAMPLE;
    let paper = without_design(text);
    let scaled = text
        .replace(
            "D = [[1.0, -3.0], [2.0, 1.0], [3.0, 1.0]]",
            "D = [[1000.0, -3000.0], [2000.0, 1000.0], [3000.0, 1000.0]]",
        )
        .replace("Q = [[1.0, 2.0], [1.0, 0.0]]", "Q = [[1000.0, 2000.0], [1000.0, 0.0]]")
        .replace("{ amplitude = 1.0, frequency = 1.0", "{ amplitude = 0.001, frequency = 1.0")
        .replace("bias = 1.0, harmonics = [{ amplitude = 2.0,", "bias = 0.001, harmonics = [{ amplitude = 0.002,");
    for part in ["D = [[1000.0", "Q = [[1000.0", "amplitude = 0.001, frequency = 1.0", "bias = 0.001"] {
        assert!(scaled.contains(part), "{part}");
    }
    let (a, b) = (
        auto_design(&paper, &Targets::default()).unwrap(),
        auto_design(&without_design(&scaled), &Targets::default()).unwrap(),
    );
    assert!(a.verification.passed && b.verification.passed, "{:?}\n{:?}", a.verification, b.verification);
    let first = &b.verification.candidates[0];
    assert!(first.worst_tail(&b.verification.bound) > 10.0, "{first:?}");
    assert_eq!((b.design.reference_sizes(), b.design.disturbance_sizes()), (&[1.0, 1.0][..], &[1e-3, 1e-3][..]));
    // The retry runs the first proposal's speed: only one of the two is kept (both had been).
    let kept: Vec<usize> =
        (b.verification.candidates.iter().enumerate()).filter(|(_, c)| c.chosen).map(|(i, _)| i).collect();
    assert!(kept.len() == 1 && kept[0] > 0, "{kept:?}");
    let why = &b.choices.iter().find(|c| c.key == "design.disturbance_sizes").unwrap().why;
    assert!(
        why.starts_with("each component sized by its own peak's power of ten: the first proposal, which sized no component below the references"),
        "{why}"
    );
    let same =
        |x: &[Complex<f64>], y: &[Complex<f64>]| x.iter().zip(y).all(|(p, q)| (p - q).norm() <= 1e-12 * p.norm());
    assert!(same(a.design.observer_eigenvalues(), b.design.observer_eigenvalues()));
    assert!(same(a.design.decoupled_eigenvalues(), b.design.decoupled_eigenvalues()));
    assert_eq!(a.design.beta(), b.design.beta());
    for (x, y) in a.design.mu().iter().zip(b.design.mu()) {
        assert!((x - y).abs() <= 1e-9 * x, "μ {:?} against {:?}", a.design.mu(), b.design.mu());
    }
    // With y₁ in mm too the rules size g₁ (1e3) and, before, left ω to the observer's retry, which
    // failed (tails 242× the bound, max|u_f,1| 874; helper tryout, 2026-12-07): now every
    // component is sized by its own peak, and the design is the paper's again (μ within 1e-4, the
    // verifying runs' absolute tolerance meeting y₁ in other units).
    let mm = scaled
        .replace("C = [[2.0, 2.0, 0.0],", "C = [[2000.0, 2000.0, 0.0],")
        .replace("Q = [[1000.0, 2000.0],", "Q = [[1000000.0, 2000000.0],")
        .replace("amplitude = 3.0", "amplitude = 3000.0");
    for part in ["C = [[2000.0", "Q = [[1000000.0", "amplitude = 3000.0"] {
        assert!(mm.contains(part), "{part}");
    }
    let c = auto_design(&without_design(&mm), &Targets::default()).unwrap();
    assert!(c.verification.passed, "{:?}", c.verification);
    assert_eq!((c.design.reference_sizes(), c.design.disturbance_sizes()), (&[1e3, 1.0][..], &[1e-3, 1e-3][..]));
    assert!(same(a.design.observer_eigenvalues(), c.design.observer_eigenvalues()));
    for (x, y) in a.design.mu().iter().zip(c.design.mu()) {
        assert!((x - y).abs() <= 1e-4 * x, "μ {:?} against {:?}", a.design.mu(), c.design.mu());
    }
    // Asked to hold at ±30 % of the delays, the retry's design is relaxed as the paper's: the same
    // delay runs and slower candidates, told from the retry's (the delay relaxation had measured
    // its effort against the first proposal's, 874 where the retry asks 22).
    let asked = Targets { delay_error: Some(0.3), ..Targets::default() };
    let (a, b) = (auto_design(&paper, &asked).unwrap(), auto_design(&without_design(&scaled), &asked).unwrap());
    let runs = |x: &quell::auto::AutoDesign| {
        let v = &x.verification;
        let from = v.candidates.iter().position(|c| c.speed.sized).unwrap_or(0);
        (
            v.candidates[from..].iter().map(|c| (c.speed.channel, c.speed.observer, c.chosen)).collect::<Vec<_>>(),
            v.delay_tolerance,
        )
    };
    assert_eq!(runs(&a), runs(&b));
    assert!(
        b.verification.relaxation.ends_with("met it at none of the slower candidates tried (7 more verifying runs)"),
        "{}",
        b.verification.relaxation
    );
}

/// A drum boiler (Bell & Åström's, fuel and feedwater to pressure and level, `tests/data/
/// drum-boiler.toml`, seconds): with the observer the rules chose its level missed the tail
/// bound 10× (1.3e-4 m against 1.27e-5), its run's advice reading the disturbance observer as no
/// better up to 1000× faster; after that first run the observer's poles are doubled, each verified
/// by a run, and ×8 meets it (helper tryout, 2026-12-07). The written scenario, run on its own,
/// meets every bound.
#[test]
fn a_first_proposal_that_misses_gets_a_faster_observer_verified_by_runs() {
    let doc = without_design(&data("drum-boiler.toml"));
    let a = auto_design(&doc, &Targets::default()).unwrap();
    assert!(a.verification.passed, "{:?}", a.verification);
    let first = &a.verification.candidates[0];
    let bound = &a.verification.bound;
    assert!(first.worst_tail(bound) > 1.0, "{first:?}");
    let kept = a.verification.candidates.iter().find(|c| c.chosen).unwrap();
    assert!(kept.speed.observer > first.speed.observer, "{kept:?}");
    let why = &a.choices.iter().find(|c| c.key == "design.observer_poles").unwrap().why;
    assert!(
        why.contains(
            "; the relaxation started from ×8 of the proposal's observer: the proposal's run missed its tail bound"
        ),
        "{why}"
    );
    // The first proposal's reasons are kept (how r_o was chosen), and the relaxation line speaks
    // of the retry it started from, whose tail left no room (it had described phases never run).
    assert!(why.starts_with("n distinct real poles from −r_o to −2·r_o"), "{why}");
    let relaxation = &a.verification.relaxation;
    assert!(relaxation.starts_with("none: the retry's worst tail is "), "{relaxation}");
    assert_eq!(a.verification.candidates.iter().filter(|c| c.chosen).count(), 1);
    let written = Scenario::from_toml(&a.scenario.to_toml()).unwrap();
    let r = Run::of(&written, &written.design().unwrap()).simulate(|_| ControlFlow::Continue(())).unwrap();
    for (c, b) in r.summary().iter().zip(bound) {
        assert!(c.figures.tail_max_e <= *b, "{} against {b}", c.figures.tail_max_e);
    }
}

/// The point-kinetics reactor of `tests/data` with the channel and observer poles given by hand
/// (−5/s; −0.08, −0.2, −50/s): its automatic design passes its tail bound while the verifying
/// run's error peaks near 100× the reference's peak (relative power from −7 to +5 about 0.07), and
/// is warned of it, naming the given keys; under an actuator limit of 0.001, which only the rules'
/// own poles meet (their verified run peaks at 4.1e-4), the refusal names the keys the relaxation
/// kept, not only the limit to raise (helper tryout, 2026-12-07).
#[test]
fn given_poles_that_drive_the_error_far_beyond_the_reference_are_named() {
    let mut doc: toml::Table = data("point-kinetics.toml").parse().unwrap();
    let given: toml::Table = "channel_poles = [[-5.0]]\nobserver_poles = [-0.08, -0.2, -50.0]".parse().unwrap();
    doc.insert("design".into(), toml::Value::Table(given));
    let a = auto_design(&doc, &Targets::default()).unwrap();
    assert!(a.verification.passed);
    let peak_e = quell::sim::Run::of(&a.scenario, &a.design)
        .simulate(|_| ControlFlow::Continue(()))
        .unwrap()
        .peak_error(0)
        .unwrap();
    assert!(peak_e > 10.0 * 0.07, "{peak_e}");
    let warning = a.error_peaking_warning().expect("cautioned");
    assert!(warning.contains("leave the file's design.channel_poles and design.observer_poles out"), "{warning}");
    let limited = auto_design(&doc, &Targets { u_limit: vec![1e-3], ..Targets::default() }).unwrap();
    assert!(!limited.verification.passed);
    let e = limited.verification.advice.join("\n");
    assert!(e.contains("raise the actuator limit (u_limit) to at least"), "{e}");
    assert!(
        e.contains(
            "the file gives design.channel_poles and design.observer_poles, which the relaxation keeps as they are"
        ),
        "{e}"
    );
}

/// The irrigation canal of `tests/data` without disturbances and with an empty `[design]`: its
/// middle pool, at 0 and undriven, has nothing to adapt to. Its μ had been the bisection's floor,
/// 1e-12 of the cap, which the design report called too small; and its rounding-level error (8e-19)
/// had failed a bound of 1 % of its own peak. Now the verification passes and the report flags
/// no channel weakly excited.
#[test]
fn an_undriven_regulated_channel_passes_and_is_not_called_too_slow() {
    let text =
        std::fs::read_to_string(format!("{}/tests/data/irrigation-canal.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let keep = |l: &&str| {
        !["D =", "Q =", "observer_poles", "channel_poles", "reference_filter", "disturbance_filter", "mu =", "beta ="]
            .iter()
            .any(|k| l.starts_with(k))
    };
    let quiet: String = text.lines().filter(keep).map(|l| format!("{l}\n")).collect();
    let quiet =
        quiet[..quiet.find("[disturbance]").unwrap()].to_string() + &quiet[quiet.find("[simulation]").unwrap()..];
    let auto = auto_design(&quiet.parse().unwrap(), &Targets::default()).unwrap();
    assert!(auto.verification.passed, "{:?}", auto.verification);
    let s = &auto.scenario;
    let d = s.design().unwrap();
    let rates = quell::diagnostics::estimate(&d, &s.plant, &s.reference, &s.disturbance, s.simulation.t_end);
    assert!(rates.iter().all(|r| !r.weakly_excited), "{rates:?}");
}

/// A Crazyflie's automatic design (`tests/data`, Förster's mass and inertia, sampled at 2 ms) asks
/// the thrust for 1,400× its steady input in its transient: without an actuator limit the design
/// is cautioned to give one; with one, the input is verified within what the actuator gives and
/// the caution is not repeated (it had been); a refused design is not cautioned as "the chosen
/// design" (its failure advice speaks for it).
#[test]
fn the_input_peaking_caution_is_for_inputs_without_a_limit_on_a_passing_design() {
    let text =
        std::fs::read_to_string(format!("{}/tests/data/crazyflie-hover.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let doc: toml::Table = text.parse().unwrap();
    let free = auto_design(&doc, &Targets::default()).unwrap();
    let steady = free.scenario.steady_input().peak[0];
    let kept = free.verification.max_uf[0];
    assert!(free.verification.passed && kept >= 1000.0 * steady, "{kept} against {steady}");
    assert!(free.warnings().any(|w| w.contains("asks far more of the plant input") && w.contains("u_f,1")));
    let limited =
        auto_design(&doc, &Targets { u_limit: vec![0.41, 0.001, 0.001, 0.0005], ..Targets::default() }).unwrap();
    assert!(limited.verification.passed && limited.verification.max_uf[0] <= 0.41);
    assert!(limited.warnings().all(|w| !w.contains("asks far more")), "{:?}", limited.warnings().collect::<Vec<_>>());
    let refused =
        auto_design(&doc, &Targets { u_limit: vec![0.25, 0.001, 0.001, 0.0005], ..Targets::default() }).unwrap();
    assert!(!refused.verification.passed && refused.warnings().next().is_none());
}

/// Where the tail misses with μ at the stiffness threshold because Ω̄ is weakly excited
/// (λ_min/λ_max = 4e-6 on this haemodynamic model, minutes), the advice offers, beside the longer
/// horizon, a μ beyond the threshold that the automatic design's own run verified: it had told the
/// user only to run 7× longer, where a hand μ 5× the threshold's passed in the given 120 min
/// (helper tryout, 2026-12-07). The offered μ, set in the scenario and run on its own (another path
/// than the verifier's), meets both tail bounds within the given t_end.
#[test]
fn a_weakly_excited_loop_is_offered_a_mu_beyond_the_threshold_that_a_run_verifies() {
    let a = auto_design(&without_design(&data("bp-snp-dpm.toml")), &Targets::default()).unwrap();
    assert!(!a.verification.passed, "{:?}", a.verification);
    let advice = a.verification.advice.join("\n");
    let offer = advice.split_once("or keep t_end and set design.mu = [").expect("an offer").1;
    let mu: Vec<f64> = offer.split_once(']').unwrap().0.split(", ").map(|x| x.parse().unwrap()).collect();
    let at_threshold = a.scenario.design.mu.clone();
    assert!(mu.iter().zip(&at_threshold).any(|(m, t)| *m >= 3.9 * t), "{mu:?} against {at_threshold:?}");
    let mut s = a.scenario.clone();
    s.design.mu = mu;
    let r = Run::of(&s, &s.design().unwrap()).simulate(|_| ControlFlow::Continue(())).unwrap();
    let t_end = s.simulation.t_end;
    for (i, bound) in a.verification.bound.iter().enumerate() {
        let tail = r.max_abs_error(i, 0.9 * t_end, t_end).unwrap();
        assert!(tail <= *bound, "channel {}: tail {tail:e} against {bound:e}", i + 1);
    }
}

/// A delay long against the horizon is named when the verification fails: the same model with its
/// delays typed in seconds under `time_unit = "min"` (45 and 60) had been told only to run 7×
/// longer (helper tryout, 2026-12-07).
#[test]
fn a_delay_long_against_the_horizon_is_named_when_the_verification_fails() {
    let text = data("bp-snp-dpm.toml").replace("delays = [0.75, 1.0]", "delays = [45.0, 60.0]");
    let a = auto_design(&without_design(&text), &Targets::default()).unwrap();
    assert!(!a.verification.passed);
    let advice = a.verification.advice.join("\n");
    assert!(advice.contains("channel 1's input delay τ = 45 min is 37.5 % of the run (120 min): its command acts only from τ on, so the adaptation starts late; if τ is not in min (plant.time_unit), correct plant.delays[0] before anything below"), "{advice}");
    assert!(advice.contains("channel 2's input delay τ = 60 min is 50.0 % of the run"), "{advice}");
}

/// A run through a true actuator below what the steady state itself asks is told so first, as the
/// automatic design's failure is: the ball and beam's design (verified under its 0.45 drive) run
/// under 0.3, below the 0.3333 its reference and tilt ask in steady state (0.0952 + 0.2381, above),
/// had been told only that the clip bit (a ball on a plate whose run diverged through a 0.3 V clip;
/// helper tryout, 2026-12-07).
#[test]
fn a_run_through_an_actuator_below_the_steady_state_is_told_so_first() {
    let a = auto_design(&data("ball-beam.toml").parse().unwrap(), &Targets::default()).unwrap();
    assert!(a.verification.passed);
    let text = a.scenario.to_toml().replace("u_max = [0.45]", "u_max = [0.3]");
    assert!(text.contains("u_max = [0.3]"), "{text}");
    let s = Scenario::from_toml(&text).unwrap();
    let d = s.design().unwrap();
    let r = Run::of(&s, &d).simulate(|_| ControlFlow::Continue(())).unwrap();
    let advice = quell::diagnostics::model_error_advice(&s, &r).expect("a model error line");
    assert!(advice.starts_with("the steady state itself asks more than the true actuator gives (u_f,1 peaks at 0.3333 against truth.u_max[0] = 0.3;"), "{advice}");
    // Under the 0.45 drive it passes, and the line is not given.
    let r = Run::of(&a.scenario, &a.design).simulate(|_| ControlFlow::Continue(())).unwrap();
    assert!(!quell::diagnostics::model_error_advice(&a.scenario, &r).is_some_and(|l| l.contains("steady state itself")));
}

/// A delay error asked for is a target: a paper machine's headbox (delays of 1 and 2 min), whose
/// automatic design meets less than ±20 % by default, has its channel poles slowed until ±20 %
/// holds both ways when asked (`--delay-error 0.2`). Checked apart from the delay check: the
/// written scenario run plainly with its true delays 20 % longer and shorter completes within the
/// tail bound (max |e_i| over the last tenth, recomputed from the rows).
#[test]
fn an_asked_delay_error_slows_the_channel_poles() {
    let doc: toml::Table = data("headbox.toml").parse().unwrap();
    let default = auto_design(&doc, &Targets::default()).unwrap();
    assert!(default.verification.passed && default.verification.delay_tolerance < 0.2, "{:?}", default.verification);
    let asked = auto_design(&doc, &Targets { delay_error: Some(0.2), ..Targets::default() }).unwrap();
    let v = &asked.verification;
    assert!(v.passed && v.delay_tolerance >= 0.2 - 1e-12, "{v:?}");
    assert!(v.relaxation.contains("for the delay error of ±20 % asked for (delay_error), the channel poles halved"));
    let channel =
        |a: &quell::auto::AutoDesign| a.verification.candidates.iter().find(|c| c.chosen).unwrap().speed.channel;
    assert!(channel(&asked) < channel(&default), "{} {}", channel(&asked), channel(&default));
    for factor in [1.2, 0.8] {
        let text = format!("{}\n[truth]\ndelays = [{}, {}]\n", asked.scenario.to_toml(), factor, 2.0 * factor);
        let s = Scenario::from_toml(&text).unwrap();
        let r = Run::of(&s, &s.design().unwrap()).simulate(|_| ControlFlow::Continue(())).unwrap();
        assert_eq!(r.outcome, Some(quell::sim::Outcome::Completed));
        let t_end = *r.t.last().unwrap();
        for i in 0..r.m {
            let tail = (0..r.t.len()).filter(|&k| r.t[k] >= 0.9 * t_end).map(|k| r.e[k * r.m + i].abs());
            let tail = tail.fold(0.0f64, f64::max);
            assert!(tail <= v.bound[i], "×{factor}: channel {i}: {tail:e} against {:e}", v.bound[i]);
        }
    }
}

/// An actuator limit the steady state alone breaks, where every tone moves its output by more than
/// 10× its tail bound (so a loop within the bounds delivers at least 90 % of it), is refused after
/// the first verifying run, not after the relaxation's: x' = −x + u + ω, y = x, g = 1, ω = 0.5
/// asks u = g − ω = 0.5 in steady state (closed form), against a limit of 0.3. At 0.48 (within
/// 10 % of it) the runs decide, and fail.
#[test]
fn a_limit_the_steady_state_alone_breaks_is_refused_after_one_run() {
    let text = "[plant]\nA = [[-1.0]]\nB = [[1.0]]\nC = [[1.0]]\nD = [[1.0]]\nQ = [[0.0]]\ndelays = [0.5]\n[design]\n[reference]\ncomponents = [{ bias = 1.0 }]\n[disturbance]\ncomponents = [{ bias = 0.5 }]\n[simulation]\nt_end = 60.0\n";
    let doc: toml::Table = text.parse().unwrap();
    let runs = std::cell::Cell::new(0);
    let mut count = |p: &quell::auto::Progress| {
        runs.set(runs.get().max(p.run));
        ControlFlow::Continue(())
    };
    let targets = Targets { u_limit: vec![0.3], ..Targets::default() };
    match quell::auto::auto_design_with(&doc, &targets, &mut count) {
        Err(AutoError::Target { argument: "u_limit", message }) => assert!(
            message.starts_with("the steady state alone asks more than the actuator limit (u_f[1]: 0.5 against 0.3, g alone asking up to 1 and ω alone up to 0.5; "),
            "{message}"
        ),
        other => panic!("{other:?}"),
    }
    assert_eq!(runs.get(), 1);
    let near = auto_design(&doc, &Targets { u_limit: vec![0.48], ..Targets::default() }).unwrap();
    assert!(!near.verification.passed && near.verification.runs > 1, "{:?}", near.verification);
}

/// The plant check: a two-zone building (`tests/data/two-zone-building.toml`, hours) whose
/// relaxation's cheapest candidate, an observer at 1/128 of the rules' speed, diverges with the true
/// A ×1.1, keeps instead the cheapest candidate that holds with A ±10 % both ways. Checked apart
/// from the check's own runs (A scaled as a whole): ten Monte Carlo draws of A with every entry
/// ±10 % (relative normal) all complete, where the cheaper candidate had lost 14 of 20 (helper
/// tryout, 2026-12-07); the paper's kept design already holds, so its plant check changes nothing.
#[test]
fn a_kept_candidate_that_misses_with_the_plant_off_gives_way_to_one_that_holds() {
    let a = auto_design(&without_design(&data("two-zone-building.toml")), &Targets::default()).unwrap();
    let v = &a.verification;
    assert!(v.passed, "{v:?}");
    assert!(
        v.relaxation.contains("; then, the kept candidate missing with the true plant's A off by ±10 % (A ×1.1: "),
        "{}",
        v.relaxation
    );
    assert_eq!(v.plant_check.iter().map(|c| (c.factor, c.met)).collect::<Vec<_>>(), [(1.1, true), (0.9, true)]);
    let kept = v.candidates.iter().find(|c| c.chosen).unwrap();
    let cheapest = v.candidates.iter().filter(|c| c.worst_tail(&v.bound) <= 1.0).map(|c| c.steps).min().unwrap();
    assert!(kept.steps > cheapest, "{kept:?}");
    let study = "[simulation]\nt_end = 480.0\n[monte_carlo]\nruns = 10\nseed = 1\n\"truth.A\" = { relative = 0.1 }\n";
    let mut doc: toml::Table = study.parse().unwrap();
    doc.insert("scenario".into(), toml::Value::Table(a.scenario.to_toml().parse().unwrap()));
    let s = quell::study::Study::from_table(&doc, None).unwrap();
    let rows = quell::study::sweep(&s, &quell::study::SweepOptions::default()).rows;
    assert!(rows.iter().all(|r| r.outcome == quell::study::Outcome::Completed), "{rows:?}");
    let paper = auto_design(&without_design(quell::scenario::PAPER_EXAMPLE), &Targets::default()).unwrap();
    assert!(
        paper.verification.plant_check.iter().all(|c| c.met) && !paper.verification.relaxation.contains("A off by")
    );
    // The plant check's runs are not held to an actuator limit (A ×1.1 asks 31.6 kW of any design
    // against the kept run's 29.2): under 30 kW the same robust candidate is kept (the fragile one
    // had been, in silence; diff review, 2026-12-07), and a kept design that misses is warned of.
    let limited = Targets { u_limit: vec![30.0], ..Targets::default() };
    let b = auto_design(&without_design(&data("two-zone-building.toml")), &limited).unwrap();
    let speed = |x: &quell::auto::AutoDesign| x.verification.candidates.iter().find(|c| c.chosen).unwrap().speed;
    assert_eq!(speed(&b), speed(&a));
    assert!(
        b.verification.plant_check.iter().all(|c| c.met) && b.plant_warning().is_none(),
        "{:?}",
        b.verification.plant_check
    );
}

/// A time scale given (`--time-scale`, [`Targets::time_scale`]) places every chosen pole from it:
/// HIMAT's 30 rad/s servos set the rules' r, whose design asked 8 rad of elevon and failed its
/// verification in 31 s (helper tryout, 2026-12-07); from r = 2 rad/s (the short period's and the
/// signals' rates) it passes with channel poles from −4 /s, under 1 rad of either surface, and
/// holds with A ±10 %. Checked apart from the verification: the written scenario, run plainly,
/// meets every tail bound. A time scale that is not a rate > 0 is refused naming it.
#[test]
fn a_time_scale_given_places_the_poles_from_it() {
    let doc = without_design(&data("himat.toml"));
    let a = auto_design(&doc, &Targets { time_scale: Some(2.0), ..Targets::default() }).unwrap();
    let v = &a.verification;
    assert!(v.passed && v.max_uf.iter().all(|&u| u < 1.0), "{v:?}");
    assert!(v.plant_check.iter().all(|c| c.met), "{:?}", v.plant_check);
    let why = &a.choices.iter().find(|c| c.key == "design.channel_poles").unwrap().why;
    assert!(why.contains("real poles from −2r (r = 2.0000e0 rad/s: the time scale given (time_scale))"), "{why}");
    let written = Scenario::from_toml(&a.scenario.to_toml()).unwrap();
    let r = Run::of(&written, &written.design().unwrap()).simulate(|_| ControlFlow::Continue(())).unwrap();
    for (c, b) in r.summary().iter().zip(&v.bound) {
        assert!(c.figures.tail_max_e <= *b, "{} against {b}", c.figures.tail_max_e);
    }
    // From 1 rad/s it passes too, but misses with A ×1.1 (tails 355× the bound) at every candidate
    // tried: kept, and warned of.
    let slow = auto_design(&doc, &Targets { time_scale: Some(1.0), ..Targets::default() }).unwrap();
    assert!(slow.verification.passed && slow.verification.plant_check.iter().any(|c| !c.met));
    let warning =
        slow.warnings().find(|w| w.starts_with("the design misses with the true plant's A off by ±10 % (A ×1.1: "));
    assert!(warning.is_some_and(|w| w.contains("it leans on the model")), "{:?}", slow.warnings().collect::<Vec<_>>());
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        match auto_design(&doc, &Targets { time_scale: Some(bad), ..Targets::default() }) {
            Err(AutoError::Target { argument: "time_scale", message }) => {
                assert!(message.starts_with("expected a finite rate > 0 in rad per s, found "), "{message}")
            }
            other => panic!("{bad}: {other:?}"),
        }
    }
}
