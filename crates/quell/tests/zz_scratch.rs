mod common;
use common::*;
use quell::sim::*;
use quell::{Design, Harmonic, Signal};
use std::ops::ControlFlow;
#[test]
fn scratch() {
    let h = |amplitude, frequency| Harmonic { amplitude, frequency, phase: 0.0 };
    let c = |bias, harmonics| quell::Component { bias, harmonics };
    let g = Signal { components: vec![c(0.0, vec![h(3.0, 2.0)]), c(2.0, vec![])] };
    let w = Signal { components: vec![c(0.0, vec![h(1.0, 1.0)]), c(1.0, vec![h(2.0, 2.0)])] };
    let d = Design::new(&paper_plant(), &paper_spec()).unwrap();
    let mode = std::env::var("MODE").unwrap_or_default();
    let n: u32 = std::env::var("N").ok().and_then(|s| s.parse().ok()).unwrap_or(20);
    let t = std::time::Instant::now();
    for _ in 0..n {
        if mode == "s" {
            let set = SampledSettings {
                t_end: 100.0,
                output_step: 0.1,
                sample_time: 1e-3,
                noise: None,
                divergence_bound: 1e9,
            };
            simulate_sampled(&d, &g, &w, &set, |_| ControlFlow::Continue(())).unwrap();
        } else {
            let r = simulate(&d, &g, &w, &RunSettings::new(100.0, 0.1, 1e-9, 1e-9), |_| ControlFlow::Continue(()));
            if n == 1 {
                eprintln!("{:?}", r.stats);
            }
        }
    }
    eprintln!("{mode}: {:?} per run", t.elapsed() / n);
}
