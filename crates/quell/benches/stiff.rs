//! Stiffness in the adaptive law (33): solver steps and time of the continuous loop as μ grows, on
//! the paper's example (t = 100 s, rtol = atol = 1e-9) and on the quadruple-tank process of
//! Johansson (2000) in its own units (t = 600 s, rtol = atol = 1e-6; `tests/data/quadruple-tank.toml`)
//! and on a supply vessel in SI units (t = 600 s, rtol = atol = 1e-7; `tests/data/supply-vessel.toml`).
//!
//! First prints a table of steps per μ factor and method (`Auto`: DOP853 switching to the implicit
//! ARK4(3)6L[2]SA while the adaptive law is stiff; `Explicit`: DOP853 throughout, where it finishes in
//! reasonable time), then times `Auto` at μ_s, 10 μ_s, 100 μ_s and 1000 μ_s, μ_s the factor at which
//! the loop turns stiff by the design report's pace estimate (the fastest channel's μ_i λ_max(Ω̄_i)
//! at `STIFF_RATIO` = 100 times the loop's fastest other rate ρ).

use std::ops::ControlFlow;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use quell::bench_api::dde::{self, Method, Options};
use quell::bench_api::ContinuousLoop;
use quell::scenario::{Scenario, PAPER_EXAMPLE};
use quell::sim::{Run, RunSettings};
use quell::Design;

const QUADRUPLE_TANK: &str = include_str!("../tests/data/quadruple-tank.toml");
const SUPPLY_VESSEL: &str = include_str!("../tests/data/supply-vessel.toml");

/// A plant, its horizon and tolerance.
struct Case {
    name: &'static str,
    scenario: Scenario,
    t_end: f64,
    tol: f64,
}

impl Case {
    fn new(name: &'static str, toml: &str) -> Case {
        let scenario = Scenario::from_toml(toml).unwrap();
        let (t_end, tol) = (scenario.simulation.t_end, scenario.simulation.rtol);
        Case { name, scenario, t_end, tol }
    }

    /// The design with every μ_i multiplied by `factor`.
    fn design(&self, factor: f64) -> Design {
        let mut spec = self.scenario.design.clone();
        spec.mu.iter_mut().for_each(|mu| *mu *= factor);
        Design::new(&self.scenario.plant, &spec).unwrap()
    }

    /// The run's solver statistics and last output sample, or the error.
    fn run(&self, design: &Design, method: Method) -> Result<(dde::Stats, Vec<f64>), dde::SolveError> {
        let s = &self.scenario;
        let mut sys = ContinuousLoop::new(design, &s.reference, &s.disturbance).unwrap();
        let y0 = sys.initial_state(&s.plant.x0).unwrap();
        let history = vec![0.0; dde::DelaySystem::n_delayed(&sys)];
        // As the closed loop sets it: the automatic method keeps an adaptive law at 3ρ or more on the
        // implicit method from DOP853's first step beyond its bound.
        let settings = RunSettings::continuous(self.t_end, self.t_end / 100.0, self.tol, self.tol);
        let run = Run::new(design, &s.reference, &s.disturbance, settings);
        let opts = Options {
            rtol: self.tol,
            atol: self.tol,
            method,
            max_steps: 1_000_000,
            expect_stiff: run.expects_stiff(),
            // As the closed loop caps its steps (the loop's fastest rate; on `Explicit` the
            // adaptive law's too).
            rate: quell::sim::step_rate(&run, method),
            ..Options::default()
        };
        let mut last = Vec::new();
        let stats = dde::solve(&mut sys, 0.0, &y0, &history, self.t_end, self.t_end / 100.0, &opts, |_, y| {
            last.clear();
            last.extend_from_slice(y);
            ControlFlow::Continue(())
        })?;
        Ok((stats, last))
    }
}

/// μ_s: the factor of the scenario's μ at which the fastest channel's adaptation rate reaches
/// `STIFF_RATIO` times ρ (the pace estimate of `quell design`).
fn stiff_factor(case: &Case) -> f64 {
    let s = &case.scenario;
    let d = s.design().unwrap();
    let e = quell::diagnostics::estimate(&d, s.true_plant(), &s.reference, &s.disturbance, case.t_end);
    let fastest = e.iter().map(|c| c.adaptation_rate).fold(0.0, f64::max);
    quell::diagnostics::STIFF_RATIO * e[0].loop_rate / fastest
}

/// Prints the table over μ_s/10 … 1e4 μ_s, checks the target (steps at 1000 μ_s at most 3× those at
/// μ_s) and returns μ_s.
fn table(case: &Case) -> f64 {
    let onset = stiff_factor(case);
    let mut auto_steps = Vec::new();
    for k in -1..=4 {
        let f = onset * 10f64.powi(k);
        let d = case.design(f);
        for method in [Method::Auto, Method::Explicit] {
            // DOP853 alone takes about μλ_max t / 3 steps: over 1e6 beyond 10 μ_s.
            if method == Method::Explicit && k > 1 {
                continue;
            }
            let start = Instant::now();
            let run = case.run(&d, method);
            let ms = start.elapsed().as_secs_f64() * 1e3;
            match run {
                Ok((s, _)) => {
                    eprintln!(
                        "{} μ×{f:e} {method:?}: {} steps ({} implicit, {} switches), {} rejected, {} RHS, {ms:.1} ms",
                        case.name, s.steps, s.implicit_steps, s.switches, s.rejected, s.rhs_evals
                    );
                    if method == Method::Auto {
                        auto_steps.push((f, s.steps));
                    }
                }
                Err(e) => eprintln!("{} μ×{f:e} {method:?}: {e} ({ms:.1} ms)", case.name),
            }
        }
    }
    let steps_at = |f: f64| auto_steps.iter().find(|&&(g, _)| g == f).map(|&(_, s)| s as f64);
    if let (Some(s0), Some(s3)) = (steps_at(onset), steps_at(onset * 1e3)) {
        eprintln!("{}: μ_s = μ × {onset:e}; steps at 1000 μ_s / at μ_s = {:.2}", case.name, s3 / s0);
        assert!(s3 <= 3.0 * s0, "{}: steps grew {:.2}× from μ_s to 1000 μ_s", case.name, s3 / s0);
    }
    onset
}

fn stiff(c: &mut Criterion) {
    for case in [
        Case::new("paper", PAPER_EXAMPLE),
        Case::new("quadruple_tank", QUADRUPLE_TANK),
        Case::new("supply_vessel", SUPPLY_VESSEL),
    ] {
        let onset = table(&case);
        let mut g = c.benchmark_group(format!("stiff_{}", case.name));
        g.sample_size(10);
        if case.name == "paper" {
            // The non-stiff run: the automatic method's only extra work is the stiffness watch.
            let d = case.design(1.0);
            for method in [Method::Explicit, Method::Auto] {
                g.bench_with_input(BenchmarkId::new(format!("{method:?}"), 1), &d, |b, d| {
                    b.iter(|| case.run(d, method).unwrap())
                });
            }
        }
        for k in 0..4 {
            let factor = onset * 10f64.powi(k);
            let d = case.design(factor);
            g.bench_with_input(BenchmarkId::new("auto", format!("{}x_mu_s", 10u32.pow(k as u32))), &d, |b, d| {
                b.iter(|| case.run(d, Method::Auto).unwrap())
            });
        }
        g.finish();
    }
}

criterion_group!(benches, stiff);
criterion_main!(benches);
