//! The automatic design (`quell::auto`) on seeded random plants of several shapes: stable and
//! unstable, σ_i from 1 to 4, with and without zero dynamics, m = 1 and 2. Asserted: the design passes its verification, and the complete
//! scenario it writes, read back from TOML and run again, keeps every channel's tail error
//! (last 10 % of the horizon) within 1 % of its reference's peak.
#![allow(non_snake_case)]

mod common;

use std::ops::ControlFlow;

use common::Rng;
use quell::auto::{auto_design, Targets};
use quell::linalg::{companion, poly_from_roots};
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

/// A plant of m channels, channel i with relative degree sigma[i] and zeros[i] (stable), poles in
/// [−3, 1]·scale (unstable ones allowed), mixed by a well-conditioned similarity; g_i a sine at
/// (0.3–1.5)·scale rad/s plus a bias, one input disturbance (Q = 0) at 0.7·scale rad/s with a bias.
/// The time axis is scaled by `scale` (delays and horizon by 1/scale).
fn scenario(rng: &mut Rng, sigma: &[usize], zeros: &[Vec<f64>], scale: f64) -> String {
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
    // Time scaling: A → scale·A (and B → scale^σ·B keeps the outputs' size comparable).
    let A = &T * A * &Ti * scale;
    let B = &T * B * scale.powi(sigma.iter().copied().max().unwrap() as i32);
    let C = C * &Ti;
    let D = rng.matrix(n, 1);
    let delays: Vec<String> = (0..m).map(|_| format!("{:e}", rng.uniform(0.0, 0.5) / scale)).collect();
    let refs: Vec<String> = (0..m)
        .map(|_| {
            format!(
                "{{ bias = {:e}, harmonics = [{{ amplitude = {:e}, frequency = {:e} }}] }}",
                rng.uniform(-1.0, 1.0),
                rng.uniform(0.5, 2.0),
                rng.uniform(0.3, 1.5) * scale
            )
        })
        .collect();
    format!(
        "[plant]\nA = {}\nB = {}\nC = {}\nD = {}\nQ = {}\ndelays = [{}]\n[design]\n\
         [reference]\ncomponents = [{}]\n\
         [disturbance]\ncomponents = [{{ bias = 0.3, harmonics = [{{ amplitude = 0.5, frequency = {:e} }}] }}]\n\
         [simulation]\nt_end = {:e}\noutput_step = {:e}\nrtol = 1e-7\natol = 1e-9\n",
        rows(&A),
        rows(&B),
        rows(&C),
        rows(&D),
        rows(&DMatrix::zeros(m, 1)),
        delays.join(", "),
        refs.join(", "),
        0.7 * scale,
        80.0 / scale,
        0.05 / scale
    )
}

fn check(seed: u64, sigma: &[usize], zeros: &[Vec<f64>], scale: f64) {
    let mut rng = Rng(seed);
    let text = scenario(&mut rng, sigma, zeros, scale);
    let doc: toml::Table = text.parse().unwrap();
    let auto = auto_design(&doc, &Targets::default()).unwrap_or_else(|e| panic!("seed {seed}: {e}\n{text}"));
    assert!(auto.verification.passed, "seed {seed}: {:?}\n{:#?}", auto.verification, auto.choices);
    // The written scenario, read back and run again.
    let s = Scenario::from_toml(&auto.scenario.to_toml()).unwrap();
    let design = s.design().unwrap();
    let r = Run::of(&s, &design).simulate(|_| ControlFlow::Continue(())).unwrap();
    let t_end = s.simulation.t_end;
    for (i, c) in s.reference.components.iter().enumerate() {
        let tail = r.max_abs_error(i, 0.9 * t_end, t_end).unwrap();
        assert!(tail <= 0.01 * c.peak(), "seed {seed}, channel {}: tail max|e| {tail:e} > 1 % of {}", i + 1, c.peak());
    }
}

#[test]
fn siso_stable_and_unstable_relative_degrees_one_to_four() {
    for (seed, sigma) in [(1, 1), (2, 2), (3, 3), (4, 4)] {
        check(seed, &[sigma], &[vec![]], 1.0);
    }
}

#[test]
fn two_channels_and_zero_dynamics() {
    check(33, &[2], &[vec![-1.0]], 1.0);
    check(34, &[1], &[vec![-2.0]], 1.0);
    check(37, &[1, 2], &[vec![], vec![]], 1.0);
}
