//! A fixed amount of each benchmark's work, for instruction counts under callgrind (repeatable on a
//! loaded machine, where criterion's timings are not):
//! `valgrind --tool=callgrind target/release/deps/workload-* WORK N` with WORK one of
//! `continuous` (the paper's 100 s run at 1e-9; `continuous_1e-6` at 1e-6), `sampled` (100 s at T_s = 1 ms), `step`
//! (`Controller::step` on the paper's design) or `dde` (the integrator bench at 1e-10), run N times.

mod common;

use common::{solve_two_delays, synthetic};
use std::hint::black_box;
use std::ops::ControlFlow;

use quell::scenario::{Scenario, PAPER_EXAMPLE};
use quell::sim::{Run, RunSettings};
use quell::{Controller, Design};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    let work = args.first().map_or("continuous", String::as_str);
    let number = |i: usize, default: usize| args.get(i).and_then(|s| s.parse().ok()).unwrap_or(default);
    let n = number(if work == "step_scaling" { 3 } else { 1 }, 1);
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = Design::new(&s.plant, &s.design).unwrap();
    for _ in 0..n {
        match work {
            "continuous" | "continuous_1e-6" => {
                let tol = if work == "continuous" { 1e-9 } else { 1e-6 };
                let settings = RunSettings::continuous(100.0, 0.1, tol, tol);
                black_box(
                    Run::new(&d, &s.reference, &s.disturbance, settings.clone())
                        .simulate(|_| ControlFlow::Continue(()))
                        .unwrap(),
                );
            }
            "sampled" => {
                let settings = RunSettings { divergence_bound: 1e9, ..RunSettings::sampled(100.0, 0.1, 1e-3) };
                black_box(
                    Run::new(&d, &s.reference, &s.disturbance, settings.clone())
                        .simulate(|_| ControlFlow::Continue(()))
                        .unwrap(),
                );
            }
            "step" => steps(&d, &[0.3, -0.2], &[1.0, 2.0]),
            "step_scaling" => {
                let m = number(1, 2);
                steps(&synthetic(m, number(2, 8)), &vec![0.1; m], &vec![1.0; m]);
            }
            "dde" => {
                black_box(solve_two_delays(1e-10));
            }
            _ => {}
        }
    }
}

/// 100,000 controller steps at T_s = 1 ms with constant y and g.
fn steps(d: &Design, y: &[f64], g: &[f64]) {
    let mut ctrl = Controller::new(d, 1e-3).unwrap();
    for _ in 0..100_000 {
        black_box(ctrl.step(black_box(y), black_box(g)).unwrap()[0]);
    }
}
