//! A fixed amount of each benchmark's work, for instruction counts under callgrind (repeatable on a
//! loaded machine, where criterion's timings are not):
//! `valgrind --tool=callgrind target/release/deps/workload-* WORK N` with WORK one of
//! `continuous` (the paper's 100 s run at 1e-9), `sampled` (100 s at T_s = 1 ms), `step`
//! (`Controller::step` on the paper's design) or `dde` (the integrator bench at 1e-10), run N times.

mod common;

use common::solve_two_delays;
use std::hint::black_box;
use std::ops::ControlFlow;

use quell::scenario::{Scenario, PAPER_EXAMPLE};
use quell::sim::{simulate, simulate_sampled, RunSettings, SampledSettings};
use quell::{Controller, Design};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    let work = args.first().map_or("continuous", String::as_str);
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1);
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    let d = Design::new(&s.plant, &s.design).unwrap();
    for _ in 0..n {
        match work {
            "continuous" => {
                let settings = RunSettings::new(100.0, 0.1, 1e-9, 1e-9);
                black_box(
                    simulate(&d, &s.reference, &s.disturbance, &settings, |_| ControlFlow::Continue(())).unwrap(),
                );
            }
            "sampled" => {
                let settings = SampledSettings {
                    t_end: 100.0,
                    output_step: 0.1,
                    sample_time: 1e-3,
                    noise: None,
                    divergence_bound: 1e9,
                };
                black_box(
                    simulate_sampled(&d, &s.reference, &s.disturbance, &settings, |_| ControlFlow::Continue(()))
                        .unwrap(),
                );
            }
            "step" => {
                let mut ctrl = Controller::new(&d, 1e-3).unwrap();
                let (y, g) = ([0.3, -0.2], [1.0, 2.0]);
                for _ in 0..100_000 {
                    black_box(ctrl.step(black_box(&y), black_box(&g))[0]);
                }
            }
            "dde" => {
                black_box(solve_two_delays(1e-10));
            }
            _ => {}
        }
    }
}
