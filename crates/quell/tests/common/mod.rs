//! Shared fixtures for the integration tests: the paper's example (Section VIII) and random systems.
#![allow(non_snake_case, dead_code)]

use std::ops::ControlFlow;

use quell::nalgebra::{Complex, DMatrix};
use quell::sim::{Outcome, Run, RunSettings, SimResult};
use quell::{Component, Design, DesignSpec, Harmonic, ObserverChoice, Plant, Signal};

pub fn re(x: f64) -> Complex<f64> {
    Complex::new(x, 0.0)
}

pub fn mat(r: usize, c: usize, v: &[f64]) -> DMatrix<f64> {
    DMatrix::from_row_slice(r, c, v)
}

/// The paper's plant, Section VIII (x0 = 0).
pub fn paper_plant() -> Plant {
    Plant::new(
        mat(3, 3, &[-3.2, -1.7, -3.0, 2.8, 1.3, 4.0, 0.3, 0.3, -0.5]),
        mat(3, 2, &[-2.0, 1.0, 2.0, -1.0, 1.0, 0.0]),
        mat(2, 3, &[2.0, 2.0, 0.0, 2.0, 1.0, 2.0]),
        mat(3, 2, &[1.0, -3.0, 2.0, 1.0, 3.0, 1.0]),
        mat(2, 2, &[1.0, 2.0, 1.0, 0.0]),
        vec![1.0, 3.0],
        None,
    )
    .expect("the paper's plant is well formed")
}

/// The paper's printed observer gain L (Section VIII).
pub fn paper_L() -> DMatrix<f64> {
    mat(3, 2, &[-8.0988, 4.4574, 10.6506, -5.0619, 2.7762, -1.1783])
}

/// The paper's design choices, Section VIII.
pub fn paper_spec() -> DesignSpec {
    DesignSpec {
        observer: ObserverChoice::Gain(paper_L()),
        channel_poles: vec![vec![re(-6.0), re(-2.0)], vec![re(-4.0)]],
        reference_filter_poles: vec![vec![re(-1.0), re(-6.0)], vec![re(-9.0)]],
        disturbance_filter_poles: vec![vec![re(-1.0), re(-3.0)], vec![re(-1.0), re(-2.0), re(-3.0)]],
        mu: vec![20.0, 30.0],
        beta: 1.0,
        relative_degrees: None,
        regressor_scaling: Default::default(),
        reference_sizes: Vec::new(),
        disturbance_sizes: Vec::new(),
    }
}

/// The paper's reference g(t) and disturbance ω(t), Section VIII.
pub fn paper_signals() -> (Signal, Signal) {
    let h = |amplitude, frequency| Harmonic { amplitude, frequency, phase: 0.0 };
    let c = |bias, harmonics| Component { bias, harmonics };
    (
        Signal { components: vec![c(0.0, vec![h(3.0, 2.0)]), c(2.0, vec![])] },
        Signal { components: vec![c(0.0, vec![h(1.0, 1.0)]), c(1.0, vec![h(2.0, 2.0)])] },
    )
}

/// The continuous closed loop on the paper's plant and signals, rtol = atol = `tol`; it must complete.
pub fn run_paper(spec: DesignSpec, t_end: f64, output_step: f64, tol: f64) -> SimResult {
    let d = Design::new(&paper_plant(), &spec).unwrap();
    let (g, w) = paper_signals();
    let r = Run::new(&d, &g, &w, RunSettings::continuous(t_end, output_step, tol, tol))
        .simulate(|_| ControlFlow::Continue(()))
        .unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    r
}

/// Checks a 100 s run sampled every 0.1 s against `tests/data/paper_example_points.csv`:
/// y and u from an independent solver at 1e-12 (accurate to ~1e-8), to 1e-6.
pub fn assert_matches_reference_points(r: &SimResult) {
    let csv =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/paper_example_points.csv")).unwrap();
    let mut rows = 0;
    for line in csv.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|s| s.trim().parse().unwrap()).collect();
        let k = (v[0] / 0.1).round() as usize;
        assert!((r.t[k] - v[0]).abs() < 1e-12);
        for i in 0..2 {
            let (y, u) = (r.y[k * 2 + i], r.u[k * 2 + i]);
            assert!((y - v[1 + i]).abs() < 1e-6, "t = {}: y{} = {y}, reference {}", v[0], i + 1, v[1 + i]);
            assert!((u - v[3 + i]).abs() < 1e-6, "t = {}: u{} = {u}, reference {}", v[0], i + 1, v[3 + i]);
        }
        rows += 1;
    }
    assert_eq!(rows, 7);
}

/// x' = −x(t − 1), x = 1 for t ≤ 0: the method-of-steps polynomials on [0, 3].
pub fn exact_unit(t: f64) -> f64 {
    let mut x = 1.0 - t;
    if t > 1.0 {
        x += (t - 1.0).powi(2) / 2.0;
    }
    if t > 2.0 {
        x -= (t - 2.0).powi(3) / 6.0;
    }
    x
}

/// A small deterministic generator (SplitMix64) for seeded random test systems.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    pub fn matrix(&mut self, r: usize, c: usize) -> DMatrix<f64> {
        DMatrix::from_fn(r, c, |_, _| self.uniform(-1.0, 1.0))
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() * n as f64) as usize
    }
}

/// Largest |μ − p| / max(1, |p|) over a greedy nearest matching of the multisets `want` and `got`.
pub fn multiset_mismatch(want: &[Complex<f64>], got: &[Complex<f64>]) -> f64 {
    assert_eq!(want.len(), got.len(), "want {want:?}, got {got:?}");
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for (i, p) in want.iter().enumerate() {
        for (j, e) in got.iter().enumerate() {
            pairs.push(((p - e).norm(), i, j));
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut used_i, mut used_j) = (vec![false; want.len()], vec![false; got.len()]);
    let mut worst: f64 = 0.0;
    for (d, i, j) in pairs {
        if !used_i[i] && !used_j[j] {
            used_i[i] = true;
            used_j[j] = true;
            worst = worst.max(d / want[i].norm().max(1.0));
        }
    }
    worst
}

/// Proposition 1 / eq. (8), checked by evaluating C (sI − A_f)⁻¹ B_f at four points s off the
/// spectrum: it must equal diag{q_i0 / ∏_j (s − λ_ij)}. Error relative to ‖C‖‖(sI − A_f)⁻¹‖‖B_f‖,
/// the size of the product, which bounds the rounding of the solve. Returns the worst such error.
pub fn decoupling_error(C: &DMatrix<f64>, A_f: &DMatrix<f64>, B_f: &DMatrix<f64>, poles: &[Vec<Complex<f64>>]) -> f64 {
    let n = A_f.nrows();
    let c = |M: &DMatrix<f64>| M.map(|v| Complex::new(v, 0.0));
    let (Cc, Bc) = (c(C), c(B_f));
    let mut worst: f64 = 0.0;
    for s in [Complex::new(0.3, 1.1), Complex::new(0.0, 2.0), Complex::new(5.0, 0.0), Complex::new(-0.2, 7.0)] {
        let M = DMatrix::<Complex<f64>>::identity(n, n) * s - c(A_f);
        let Minv = M.try_inverse().expect("s is not an eigenvalue");
        let G = &Cc * &Minv * &Bc;
        let scale = Cc.norm() * Minv.norm() * Bc.norm();
        for i in 0..C.nrows() {
            for j in 0..C.nrows() {
                let want = if i == j {
                    let q0: Complex<f64> = poles[i].iter().map(|p| -p).product();
                    q0 / poles[i].iter().map(|p| s - p).product::<Complex<f64>>()
                } else {
                    Complex::new(0.0, 0.0)
                };
                worst = worst.max((G[(i, j)] - want).norm() / scale);
            }
        }
    }
    worst
}

/// Coefficients [a_0, …, a_{q−1}] of the monic polynomial ∏(s − r_j) = s^q + a_{q−1}s^{q−1} + … + a_0
/// (the leading 1 left out), multiplied out factor by factor; the roots closed under conjugation.
pub fn poly_from_roots(roots: &[Complex<f64>]) -> Vec<f64> {
    let mut c = vec![Complex::new(1.0, 0.0)]; // ascending, leading coefficient last
    for r in roots {
        let mut next = vec![Complex::new(0.0, 0.0); c.len() + 1];
        for (i, ci) in c.iter().enumerate() {
            next[i + 1] += ci;
            next[i] -= r * ci;
        }
        c = next;
    }
    c.pop();
    c.iter().map(|z| z.re).collect()
}

/// The companion matrix of s^q + a_{q−1}s^{q−1} + … + a_0 (ascending `a`): ones on the
/// superdiagonal, last row −a; its characteristic polynomial is that one.
pub fn companion(a: &[f64]) -> DMatrix<f64> {
    let q = a.len();
    let mut M = DMatrix::zeros(q, q);
    for r in 0..q.saturating_sub(1) {
        M[(r, r + 1)] = 1.0;
    }
    for (c, &ac) in a.iter().enumerate() {
        M[(q - 1, c)] = -ac;
    }
    M
}

/// Eigenvalues by nalgebra's Schur form (bounded iterations: its implicit double-shift QR has
/// no exceptional shifts and can stall on tight clusters; shifting by the mean eigenvalue first
/// resolves the all-equal case).
///
/// M is first scaled by an exact diagonal similarity (Osborne's iteration in the 2-norm, factors
/// rounded to powers of 2): gains of 1e14 next to O(1) entries otherwise give the QR iteration a
/// backward error of ε‖M‖ that swamps the eigenvalues the gain was built to place.
pub fn eigenvalues(M: &DMatrix<f64>) -> Vec<Complex<f64>> {
    let n = M.nrows();
    if n == 0 {
        return Vec::new(); // nalgebra's Schur form needs a row
    }
    let M = balanced(M);
    let sigma = M.trace() / n.max(1) as f64;
    let shifted = &M - DMatrix::<f64>::identity(n, n) * sigma;
    let schur = shifted.try_schur(f64::EPSILON, 100_000).expect("nalgebra Schur did not converge");
    schur.complex_eigenvalues().iter().map(|z| z + sigma).collect()
}

/// The test's own exact diagonal similarity of [`eigenvalues`] (Osborne, powers of 2).
pub fn balanced(M: &DMatrix<f64>) -> DMatrix<f64> {
    let n = M.nrows();
    let mut M = M.clone();
    for _ in 0..100 {
        let mut changed = false;
        for i in 0..n {
            let off = |v: f64, j: usize| if j == i { 0.0 } else { v * v };
            let col = M.column(i).iter().enumerate().map(|(j, &v)| off(v, j)).sum::<f64>().sqrt();
            let row = M.row(i).iter().enumerate().map(|(j, &v)| off(v, j)).sum::<f64>().sqrt();
            if col > 0.0 && row > 0.0 {
                let f = (row / col).sqrt().log2().round().exp2();
                if f != 1.0 {
                    M.column_mut(i).scale_mut(f);
                    M.row_mut(i).scale_mut(1.0 / f);
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    M
}

/// Eigenvalues by faer's multishift QR (with aggressive early deflation, which resolves the tight
/// clusters of repeated poles that nalgebra's Schur iteration leaves ≈ 100 (ε‖M‖)^(1/k) off), on
/// the test's own balanced matrix ([`balanced`]).
pub fn eigenvalues_faer(M: &DMatrix<f64>) -> Vec<Complex<f64>> {
    let n = M.nrows();
    let B = balanced(M);
    let F = faer::Mat::<f64>::from_fn(n, n, |r, c| B[(r, c)]);
    F.eigenvalues().expect("faer's QR converges").iter().map(|z| Complex::new(z.re, z.im)).collect()
}

/// examples/three-channel.toml with its unmeasured state x₂ in units 1e9 smaller (x₂ → 1e9 x₂:
/// row 2 of A, B, D times 1e9, column 2 of A over 1e9) and no disturbance: the same loop in other
/// units (a unit hunt's case).
pub fn three_channel_x2_in_nano_units() -> String {
    std::fs::read_to_string(format!("{}/../../examples/three-channel.toml", env!("CARGO_MANIFEST_DIR")))
        .unwrap()
        .replace("[0.0, 1.0, 0.0, 0.0], [1.0, -1.0, 0.5, 0.0]", "[0.0, 1e-9, 0.0, 0.0], [1e9, -1.0, 5e8, 0.0]")
        .replace("[0.0, 0.4, -0.3, -1.0]", "[0.0, 4e-10, -0.3, -1.0]")
        .replace("[1.0, 0.5, 0.0], [0.0, 1.0, 0.0]", "[1e9, 5e8, 0.0], [0.0, 1.0, 0.0]")
        .replace("D = [[0.0], [1.0]", "D = [[0.0], [1e9]")
        .replace("{ bias = 0.5, harmonics = [{ amplitude = 0.5, frequency = 1.0 }] } ]", "{ bias = 0.0 } ]")
}
