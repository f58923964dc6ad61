mod common;
use common::*;
use std::ops::ControlFlow;
use quell::sim::*;
use quell::{Design, Harmonic, Signal};
#[test]
fn scratch() {
    let h = |amplitude, frequency| Harmonic { amplitude, frequency, phase: 0.0 };
    let c = |bias, harmonics| quell::Component { bias, harmonics };
    let g = Signal { components: vec![c(0.0, vec![h(3.0, 2.0)]), c(2.0, vec![])] };
    let w = Signal { components: vec![c(0.0, vec![h(1.0, 1.0)]), c(1.0, vec![h(2.0, 2.0)])] };
    let d = Design::new(&paper_plant(), &paper_spec()).unwrap();
    for tol in [1e-9, 1e-12] {
        let t = std::time::Instant::now();
        let r = simulate(&d, &g, &w, &RunSettings::new(100.0, 0.1, tol, tol), |_| ControlFlow::Continue(()));
        eprintln!("tol {tol}: {:?} in {:?}; tail {} {}", r.stats, t.elapsed(), r.max_abs_error(0, 90.0, 100.0), r.max_abs_error(1, 90.0, 100.0));
        let s = r.summary(); eprintln!("{s:?}");
    }
    let cont = simulate(&d, &g, &w, &RunSettings::new(100.0, 0.1, 1e-10, 1e-10), |_| ControlFlow::Continue(()));
    for ts in [0.5e-3, 1e-3, 5e-3, 10e-3, 50e-3, 100e-3, 0.2, 0.25, 0.5] {
        let t = std::time::Instant::now();
        let set = SampledSettings { t_end: 100.0, output_step: if ts <= 0.1 { 0.1 } else { ts }, sample_time: ts, noise: None, divergence_bound: 1e9 };
        let r = simulate_sampled(&d, &g, &w, &set, |_| ControlFlow::Continue(())).unwrap();
        let el = t.elapsed();
        let mut devs = vec![];
        if ts <= 0.1 { for i in 0..2 {
            let peak = cont.column(&cont.y, 2, i).fold(0.0, |m: f64, v| m.max(v.abs()));
            let dev = r.column(&r.y, 2, i).zip(cont.column(&cont.y, 2, i)).fold(0.0, |m: f64, (p, q)| m.max((p - q).abs()));
            devs.push(dev / peak);
        }}
        eprintln!("Ts {ts}: {:?} tail {:.4} {:.4} dev {:?} {:?}", r.outcome, r.max_abs_error(0, 90.0, 100.0), r.max_abs_error(1, 90.0, 100.0), devs, el);
    }
}
