//! Tests of the DOP853 method-of-steps DDE integrator (`quell::bench_api::dde`).

mod common;

use common::exact_unit;
use quell::bench_api::dde::{breakpoints, solve, DelaySystem, Method, Options, Past, SolveError, Stats};
use serde_json::Value;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ops::ControlFlow;

// ---------------------------------------------------------------------------------------------
// Allocation counting (per thread, so parallel tests do not interfere).

struct Counting;

thread_local! {
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocs() -> usize {
    ALLOCS.with(|c| c.get())
}

// ---------------------------------------------------------------------------------------------
// Linear constant-delay systems y' = A0 y + Σ A_i y(t − τ_i).

struct Linear {
    n: usize,
    a0: Vec<f64>,
    a: Vec<Vec<f64>>,
    delays: Vec<f64>,
    buf: Vec<f64>,
}

impl Linear {
    fn new(a0: Vec<Vec<f64>>, terms: Vec<(f64, Vec<Vec<f64>>)>) -> Self {
        let n = a0.len();
        let flat = |m: Vec<Vec<f64>>| m.into_iter().flatten().collect::<Vec<_>>();
        let (delays, a): (Vec<_>, Vec<_>) = terms.into_iter().map(|(d, m)| (d, flat(m))).unzip();
        Linear { n, a0: flat(a0), a, delays, buf: vec![0.0; n] }
    }
}

impl DelaySystem for Linear {
    fn dim(&self) -> usize {
        self.n
    }
    fn n_delayed(&self) -> usize {
        self.n
    }
    fn delays(&self) -> &[f64] {
        &self.delays
    }
    fn rhs(&mut self, t: f64, y: &[f64], past: &Past<'_>, dy: &mut [f64]) {
        let n = self.n;
        for (i, d) in dy.iter_mut().enumerate() {
            *d = (0..n).map(|j| self.a0[i * n + j] * y[j]).sum();
        }
        for (d, a) in self.delays.iter().zip(&self.a) {
            past.eval_into(t - d, 0, &mut self.buf);
            for (i, dyi) in dy.iter_mut().enumerate() {
                *dyi += (0..n).map(|j| a[i * n + j] * self.buf[j]).sum::<f64>();
            }
        }
    }
}

fn matrix(v: &Value) -> Vec<Vec<f64>> {
    v.as_array().unwrap().iter().map(|r| r.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()).collect()
}

fn vector(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

/// Runs `sys` with `method` and collects every output.
fn run_with<S: DelaySystem>(
    sys: &mut S,
    y0: &[f64],
    history: &[f64],
    t_end: f64,
    dt: f64,
    tol: f64,
    method: Method,
) -> (Vec<(f64, Vec<f64>)>, Stats) {
    let opts = Options { rtol: tol, atol: tol, method, ..Options::default() };
    let mut out = Vec::new();
    let stats = solve(sys, 0.0, y0, history, t_end, dt, &opts, |t, y| {
        out.push((t, y.to_vec()));
        ControlFlow::Continue(())
    })
    .expect("solve failed");
    (out, stats)
}

/// All seven linear cases of `tests/data/dde_cases.json`, one harness, rtol = atol = 1e-10.
///
/// Per-case tolerance on |y − y_ref| / max(1, |y_ref|) (the scaling matters only for
/// `matlab_ddex1_wille_baker_ex3`, whose values reach ~190):
/// * ddepl_constant_1delay (history 0, jump to y0 = 1 at t = 0): 1e-8
/// * ddepl_constant_2delays (history 0, jump to 1): 1e-8
/// * paul_1_1_1_neg_unit (history = y0 = 1): 1e-8
/// * matlab_ddex1_wille_baker_ex3 (history = y0 = [1,1,1]; growth to ~190 by t = 5): 1e-8
/// * ddepl_constant_1delay_long (history 0, jump to 1; to t = 100): 1e-8
/// * statefb_input_delay_pc_docstring_tau0p1 / _tau0p2 (history = y0 = [1,0]): 1e-8
///
/// Then the same cases with [`Method::Implicit`] (these systems have no implicit block, so this is
/// the explicit part of ARK4(3)6L[2]SA with its cubic Hermite history), to 1e-7: a 4th-order
/// method at a local tolerance of 1e-10 accumulates a global error one to two orders above it over
/// the cases' few hundred steps.
#[test]
fn reference_cases() {
    for (method, bound) in [(Method::Auto, 1e-8), (Method::Implicit, 1e-7)] {
        reference_cases_with(method, bound);
    }
}

fn reference_cases_with(method: Method, bound: f64) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/dde_cases.json");
    let text = std::fs::read_to_string(path).expect("read dde_cases.json");
    let cases: Value = serde_json::from_str(&text).unwrap();
    let cases = cases.as_array().unwrap();
    assert_eq!(cases.len(), 7);
    for case in cases {
        let name = case["name"].as_str().unwrap();
        let y0 = vector(&case["y0"]);
        let hist_text = case["history"].as_str().unwrap();
        // The histories are all constant: either 0 before t0 with a jump to y0, or equal to y0.
        let history = if hist_text.starts_with("phi(t) = 0 for t < 0") {
            vec![0.0; y0.len()]
        } else if hist_text.contains("for t <= 0") {
            y0.clone()
        } else {
            panic!("{name}: unrecognised history {hist_text:?}");
        };
        let terms = case["delayed_terms"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| (d["delay"].as_f64().unwrap(), matrix(&d["A"])))
            .collect();
        let mut sys = Linear::new(matrix(&case["A0"]), terms);
        let t_end = vector(&case["tspan"])[1];
        // All reference times are multiples of 0.05: compare at dense outputs.
        let dt = 0.05;
        let (out, stats) = run_with(&mut sys, &y0, &history, t_end, dt, 1e-10, method);
        let ts = vector(&case["reference"]["t"]);
        let ys = matrix(&case["reference"]["y"]);
        let mut worst: f64 = 0.0;
        for (t, yr) in ts.iter().zip(&ys) {
            let k = (t / dt).round() as usize;
            let (to, y) = &out[k];
            assert!((to - t).abs() < 1e-9, "{name}: output {k} at {to}, expected {t}");
            for (a, b) in y.iter().zip(yr) {
                let e = (a - b).abs() / b.abs().max(1.0);
                worst = worst.max(e);
                assert!(e < bound, "{method:?} {name}: t = {t}: {a} vs {b} (scaled error {e:e})");
            }
        }
        println!(
            "{method:?} {name}: max scaled error {worst:.2e} ({} steps, {} rejected, {} rhs, {} breakpoints)",
            stats.steps, stats.rejected, stats.rhs_evals, stats.breakpoints
        );
    }
}

#[test]
fn closed_form_method_of_steps() {
    let mut sys = Linear::new(vec![vec![0.0]], vec![(1.0, vec![vec![-1.0]])]);
    let (out, stats) = run_with(&mut sys, &[1.0], &[1.0], 3.0, 0.01, 1e-10, Method::Auto);
    assert_eq!(out.len(), 301);
    let mut worst: f64 = 0.0;
    for (t, y) in &out {
        let e = (y[0] - exact_unit(*t)).abs();
        worst = worst.max(e);
        assert!(e < 1e-9, "t = {t}: {} vs {}", y[0], exact_unit(*t));
    }
    assert!((out[300].0 - 3.0).abs() < 1e-12);
    assert_eq!(stats.breakpoints, 2, "breakpoints 1 and 2 are landed on");
    println!("closed form: max error {worst:.2e}, {stats:?}");
}

/// Jump in the history at t0 (history 0, y(0) = 1): u = 1 on [0,1], 2 − t on [1,2],
/// −(3(t−2) − (t²−4)/2) on [2,3]. Accuracy right after the breakpoints t = 1, 2 shows they
/// are landed on and that the delayed value switches side exactly there.
#[test]
fn history_jump_breakpoints() {
    let exact = |t: f64| {
        if t <= 1.0 {
            1.0
        } else if t <= 2.0 {
            2.0 - t
        } else {
            -(3.0 * (t - 2.0) - (t * t - 4.0) / 2.0)
        }
    };
    let mut sys = Linear::new(vec![vec![0.0]], vec![(1.0, vec![vec![-1.0]])]);
    let (out, stats) = run_with(&mut sys, &[1.0], &[0.0], 3.0, 1e-3, 1e-10, Method::Auto);
    let mut worst: f64 = 0.0;
    for (t, y) in &out {
        let e = (y[0] - exact(*t)).abs();
        worst = worst.max(e);
        assert!(e < 1e-10, "t = {t}: {} vs {}", y[0], exact(*t));
    }
    assert_eq!(stats.breakpoints, 2);
    println!("history jump: max error {worst:.2e}, {stats:?}");

    // The same with t0 = 0.1, where t0 + τ − τ ≠ t0 in floating point.
    let mut sys = Linear::new(vec![vec![0.0]], vec![(1.0, vec![vec![-1.0]])]);
    let opts = Options { rtol: 1e-10, atol: 1e-10, ..Options::default() };
    let mut worst_shift: f64 = 0.0;
    solve(&mut sys, 0.1, &[1.0], &[0.0], 3.1, 1e-3, &opts, |t, y| {
        worst_shift = worst_shift.max((y[0] - exact(t - 0.1)).abs());
        ControlFlow::Continue(())
    })
    .unwrap();
    assert!(worst_shift < 1e-10, "t0 = 0.1: max error {worst_shift:e}");

    // Two incommensurate delays: every generated breakpoint is landed on.
    let delays = [1.0 / 3.0, 0.2];
    let bps = breakpoints(0.0, &delays, 1.0);
    assert!(bps.len() >= 8 && bps.windows(2).all(|w| w[1] > w[0]));
    assert!(bps.iter().any(|b| (b - 8.0 / 15.0).abs() < 1e-12));
    let mut sys = Linear::new(vec![vec![0.0]], vec![(delays[0], vec![vec![-1.0]]), (delays[1], vec![vec![-1.0]])]);
    let (_, stats) = run_with(&mut sys, &[1.0], &[0.0], 1.0, 0.1, 1e-10, Method::Auto);
    assert_eq!(stats.breakpoints, bps.len());
}

/// Plain ODE with finite-time blow-up: y' = y², y(0) = 1 explodes at t = 1.
struct Blowup;

impl DelaySystem for Blowup {
    fn dim(&self) -> usize {
        1
    }
    fn n_delayed(&self) -> usize {
        0
    }
    fn delays(&self) -> &[f64] {
        &[]
    }
    fn rhs(&mut self, _t: f64, y: &[f64], _past: &Past<'_>, dy: &mut [f64]) {
        dy[0] = y[0] * y[0];
    }
}

#[test]
fn step_size_underflow_at_blowup() {
    let opts = Options { rtol: 1e-10, atol: 1e-10, ..Options::default() };
    let r = solve(&mut Blowup, 0.0, &[1.0], &[], 2.0, 0.1, &opts, |_, _| ControlFlow::Continue(()));
    match r {
        Err(SolveError::StepSizeTooSmall { t, h, .. }) => {
            println!("blow-up: stopped at t = {t}, h = {h:e}");
            assert!((t - 1.0).abs() < 1e-6, "t = {t}");
            assert!(h < 1e-12);
        }
        other => panic!("expected StepSizeTooSmall, got {other:?}"),
    }
}

/// An RHS that turns NaN ends with an error instead of propagating NaN or looping.
struct GoesNan;

impl DelaySystem for GoesNan {
    fn dim(&self) -> usize {
        1
    }
    fn n_delayed(&self) -> usize {
        1
    }
    fn delays(&self) -> &[f64] {
        &[0.5]
    }
    fn rhs(&mut self, t: f64, _y: &[f64], past: &Past<'_>, dy: &mut [f64]) {
        past.eval_into(t - 0.5, 0, dy);
        if t > 0.75 {
            dy[0] = f64::NAN;
        }
    }
}

#[test]
fn non_finite_rhs_is_an_error() {
    let mut seen_nan = false;
    let r = solve(&mut GoesNan, 0.0, &[1.0], &[1.0], 2.0, 0.05, &Options::default(), |_, y| {
        seen_nan |= !y[0].is_finite();
        ControlFlow::Continue(())
    });
    assert!(matches!(r, Err(SolveError::StepSizeTooSmall { t, .. }) if (t - 0.75).abs() < 1e-6), "{r:?}");
    assert!(!seen_nan);
}

#[test]
fn early_stop() {
    let mut sys = Linear::new(vec![vec![0.0]], vec![(1.0, vec![vec![-1.0]])]);
    let mut count = 0;
    let stats = solve(&mut sys, 0.0, &[1.0], &[1.0], 100.0, 0.5, &Options::default(), |t, _| {
        count += 1;
        if t >= 1.0 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    })
    .unwrap();
    assert_eq!(count, 3);
    // Stopped right after the step containing t = 1: a handful of steps, not a run to 100.
    assert!(stats.steps < 20, "{stats:?}");
}

/// x' = −x(t − 1) + sin t to t = 10 000: the history holds at most about max_delay / min_step
/// records, and the step loop stops allocating (same allocation count at t_end = 1000 and 10 000).
struct Forced {
    buf: [f64; 1],
}

impl DelaySystem for Forced {
    fn dim(&self) -> usize {
        1
    }
    fn n_delayed(&self) -> usize {
        1
    }
    fn delays(&self) -> &[f64] {
        &[1.0]
    }
    fn rhs(&mut self, t: f64, _y: &[f64], past: &Past<'_>, dy: &mut [f64]) {
        past.eval_into(t - 1.0, 0, &mut self.buf);
        dy[0] = -self.buf[0] + t.sin();
    }
}

#[test]
fn history_stays_bounded_and_no_allocation() {
    let opts = Options { rtol: 1e-10, atol: 1e-10, ..Options::default() };
    let measure = |t_end: f64| {
        let mut sys = Forced { buf: [0.0] };
        let before = allocs();
        let mut last = 0.0;
        let stats = solve(&mut sys, 0.0, &[1.0], &[1.0], t_end, 10.0, &opts, |_, y| {
            last = y[0];
            ControlFlow::Continue(())
        })
        .unwrap();
        (allocs() - before, stats, last)
    };
    let (a_short, s_short, _) = measure(1000.0);
    let (a_long, s_long, last) = measure(10_000.0);
    println!("long run: {s_long:?}, allocations {a_long} (t_end = 1000: {a_short}), y(10000) = {last}");
    assert!(last.is_finite() && last.abs() < 10.0);
    assert_eq!(a_short, a_long, "the step loop allocates");
    // Step records within one delay: 1 / (smallest step), plus the pruning margin.
    let mean_records_per_delay = s_long.steps as f64 / 10_000.0;
    assert!(
        (s_long.max_history_len as f64) <= 2.0 * mean_records_per_delay + 5.0,
        "history held {} records; {:.1} steps per unit time",
        s_long.max_history_len,
        mean_records_per_delay
    );
    assert_eq!(s_short.max_history_len, s_long.max_history_len);
}

/// No delays: a plain ODE (harmonic oscillator), full-state dense output with n_delayed = 0.
struct Oscillator;

impl DelaySystem for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn n_delayed(&self) -> usize {
        0
    }
    fn delays(&self) -> &[f64] {
        &[]
    }
    fn rhs(&mut self, _t: f64, y: &[f64], _past: &Past<'_>, dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = -y[0];
    }
}

#[test]
fn plain_ode_dense_output() {
    let (out, stats) = run_with(&mut Oscillator, &[1.0, 0.0], &[], 20.0, 0.07, 1e-11, Method::Auto);
    assert_eq!(out.len(), (20.0f64 / 0.07).floor() as usize + 1);
    let mut worst: f64 = 0.0;
    for (t, y) in &out {
        worst = worst.max((y[0] - t.cos()).abs()).max((y[1] + t.sin()).abs());
    }
    println!("oscillator: max error {worst:.2e}, {stats:?}");
    assert!(worst < 1e-9);
    assert_eq!(stats.max_history_len, 0);
}

/// y' = 0, no delays: only the output schedule is at work.
struct Still;

impl DelaySystem for Still {
    fn dim(&self) -> usize {
        1
    }
    fn n_delayed(&self) -> usize {
        0
    }
    fn delays(&self) -> &[f64] {
        &[]
    }
    fn rhs(&mut self, _t: f64, _y: &[f64], _past: &Past<'_>, dy: &mut [f64]) {
        dy[0] = 0.0;
    }
}

/// The outputs of a run: how many, and the last time.
fn output_grid(t_end: f64, dt: f64) -> (usize, f64) {
    let opts = Options { rtol: 1e-6, atol: 1e-6, ..Options::default() };
    let (mut count, mut last) = (0, f64::NAN);
    solve(&mut Still, 0.0, &[1.0], &[], t_end, dt, &opts, |t, _| {
        (count, last) = (count + 1, t);
        ControlFlow::Continue(())
    })
    .expect("y' = 0 solves");
    (count, last)
}

/// The output grid counts whole output steps to a relative tolerance, as the sampled loop counts
/// samples. 8388898.2 s / 0.9 s is 9320998 exactly in decimal, but in binary it is
/// 9320997.999999998: 2e-9 below, more than an absolute 1e-9 of a step, so the old rule ⌊(span +
/// 1e-9·dt)/dt⌋ dropped the row at t_end (9.3e6 rows, within the 1e7 rows a run may write). The
/// known answer is the decimal ratio; at the ms scale (0.3 s / 0.1 ms is 2999.9999999999995 in
/// binary) both rules agree, and a span that is not whole (1.05 / 0.1) ends on the last whole step.
#[test]
fn output_grid_counts_whole_steps_to_a_relative_tolerance() {
    let (t_end, dt): (f64, f64) = (8388898.2, 0.9);
    assert!(t_end / dt < 9320998.0 && ((t_end + 1e-9 * dt) / dt).floor() == 9320997.0, "the case discriminates");
    assert_eq!(output_grid(t_end, dt), (9320998 + 1, t_end));
    assert_eq!(output_grid(0.3, 1e-4), (3000 + 1, 0.3));
    let (count, last) = output_grid(1.05, 0.1);
    assert_eq!(count, 10 + 1);
    assert!((last - 1.0).abs() <= 1e-15, "{last}");
}

/// Only a prefix is delayed: x1' = −x1(t − 1), x2' = x1 (x1 = 1 for t ≤ 0, x2(0) = 0), so
/// x2 = ∫ x1 = t − t²/2 + (t−1)³/6 − (t−2)⁴/24 on [0, 3] (terms active past 1 and 2).
struct Prefix {
    buf: [f64; 1],
}

impl DelaySystem for Prefix {
    fn dim(&self) -> usize {
        2
    }
    fn n_delayed(&self) -> usize {
        1
    }
    fn delays(&self) -> &[f64] {
        &[1.0]
    }
    fn rhs(&mut self, t: f64, y: &[f64], past: &Past<'_>, dy: &mut [f64]) {
        past.eval_into(t - 1.0, 0, &mut self.buf);
        dy[0] = -self.buf[0];
        dy[1] = y[0];
    }
}

#[test]
fn delayed_prefix_only() {
    let x2 = |t: f64| {
        let mut v = t - t * t / 2.0;
        if t > 1.0 {
            v += (t - 1.0).powi(3) / 6.0;
        }
        if t > 2.0 {
            v -= (t - 2.0).powi(4) / 24.0;
        }
        v
    };
    let (out, stats) = run_with(&mut Prefix { buf: [0.0] }, &[1.0, 0.0], &[1.0], 3.0, 0.01, 1e-10, Method::Auto);
    let mut worst: f64 = 0.0;
    for (t, y) in &out {
        worst = worst.max((y[0] - exact_unit(*t)).abs()).max((y[1] - x2(*t)).abs());
    }
    println!("prefix: max error {worst:.2e}, {stats:?}");
    assert!(worst < 1e-9);
}

// ---------------------------------------------------------------------------------------------
// A stiff linear DDE with a closed form: η' = −λ (η − sin t) (the implicit block), x' = −η(t − τ).

/// η(0) = η0 with the constant history η0 before 0, x(0) = 0.
struct Relax {
    lambda: f64,
    eta0: f64,
    delays: [f64; 1],
    buf: [f64; 1],
}

const TAU: f64 = 0.5;

impl Relax {
    /// With η0 = 1 the solution has an initial layer e^{−λt}; with `layer` false η0 = −λ/(λ² + 1), the
    /// slow solution's value at 0, and there is none. A layer far thinner than the steps that follow
    /// it reaches x through the delay at t = τ as a near-jump in x' that no breakpoint marks, and the
    /// step across it integrates the jump with weight b_1 h; so the stiff cases start on the slow
    /// solution, as the loop does (Ω(0) = 0, η̂(0) = 0).
    fn new(lambda: f64, layer: bool) -> Self {
        let eta0 = if layer { 1.0 } else { -lambda / (lambda * lambda + 1.0) };
        Relax { lambda, eta0, delays: [TAU], buf: [0.0] }
    }

    /// η(t) = λ(λ sin t − cos t)/(λ² + 1) + C e^{−λt}, C = η0 + λ/(λ² + 1); x(t) = −η0 t for t ≤ τ and
    /// −η0 τ − ∫_0^{t−τ} η beyond.
    fn exact(&self, t: f64) -> [f64; 2] {
        let l = self.lambda;
        let d = l * l + 1.0;
        let (c, eta0) = (self.eta0 + l / d, self.eta0);
        let eta = |t: f64| l * (l * t.sin() - t.cos()) / d + c * (-l * t).exp();
        let integral = |u: f64| l * (l * (1.0 - u.cos()) - u.sin()) / d + c * (-(-l * u).exp_m1()) / l;
        let x = if t <= TAU { -eta0 * t } else { -eta0 * TAU - integral(t - TAU) };
        [eta(t), x]
    }
}

impl DelaySystem for Relax {
    fn dim(&self) -> usize {
        2
    }
    fn n_delayed(&self) -> usize {
        1
    }
    fn delays(&self) -> &[f64] {
        &self.delays
    }
    fn rhs(&mut self, t: f64, y: &[f64], past: &Past<'_>, dy: &mut [f64]) {
        dy[0] = -self.lambda * (y[0] - t.sin());
        past.eval_into(t - TAU, 0, &mut self.buf);
        dy[1] = -self.buf[0];
    }
    fn implicit(&self) -> std::ops::Range<usize> {
        0..1
    }
    fn implicit_rate(&self, _y: &[f64]) -> f64 {
        self.lambda
    }
    fn solve_implicit(&mut self, t: f64, c: f64, z: &mut [f64]) -> bool {
        // z_0 = r + c λ (sin t − z_0).
        z[0] = (z[0] + c * self.lambda * t.sin()) / (1.0 + c * self.lambda);
        true
    }
}

/// Largest |y − exact| over the outputs of a run to t = 10 at rtol = atol = 1e-8.
fn relax_error(lambda: f64, layer: bool, method: Method) -> (f64, Stats) {
    let mut sys = Relax::new(lambda, layer);
    let eta0 = sys.eta0;
    let (out, stats) = run_with(&mut sys, &[eta0, 0.0], &[eta0], 10.0, 0.05, 1e-8, method);
    let exact = Relax::new(lambda, layer);
    eprintln!("λ = {lambda:e}, {method:?}: {stats:?}");
    let worst =
        out.iter().flat_map(|(t, y)| y.iter().zip(exact.exact(*t)).map(|(a, b)| (a - b).abs())).fold(0.0, f64::max);
    eprintln!("  max error {worst:e}");
    (worst, stats)
}

/// The implicit path (automatic, and implicit throughout) against the closed form at λ from mild to
/// 1e9, and both paths where both run.
/// Solutions are O(1); at rtol = atol = 1e-8 over ~10² steps the global error stays below 1e-6
/// (measured 1e-8…1e-7). Once stiff, the step count is set by the smooth solution, not by λ: from
/// λ = 1e3 to 1e9 the implicit steps grow less than 1.5×, where DOP853 alone would need ~λ·10/6
/// steps. The automatic method's DOP853 steps before its switch are at most the switch's patience
/// (1,000 steps at the stability bound; at λ = 1e3 DOP853 thrashes, and it switches sooner).
#[test]
fn stiff_closed_form() {
    for lambda in [1.0, 10.0, 100.0] {
        for method in [Method::Explicit, Method::Implicit, Method::Auto] {
            let (err, stats) = relax_error(lambda, true, method);
            assert!(err < 1e-6, "λ = {lambda}, {method:?}: error {err:e} ({stats:?})");
        }
    }
    let (_, onset) = relax_error(1e3, false, Method::Auto);
    assert!(onset.switches >= 1 && onset.implicit_steps > 0, "{onset:?}");
    for lambda in [1e3, 1e5, 1e7, 1e9] {
        let (err, stats) = relax_error(lambda, false, Method::Auto);
        assert!(err < 1e-6, "λ = {lambda:e}: error {err:e} ({stats:?})");
        assert!(
            stats.implicit_steps as f64 <= 1.5 * onset.implicit_steps as f64,
            "λ = {lambda:e}: {stats:?} vs {onset:?}"
        );
        assert!(stats.steps - stats.implicit_steps <= 1_000, "λ = {lambda:e}: {stats:?}");
        // The implicit method throughout, from the first step (no DOP853 stretch before a switch).
        let (err, stats) = relax_error(lambda, false, Method::Implicit);
        assert!(err < 1e-6, "λ = {lambda:e}, Implicit: error {err:e} ({stats:?})");
        assert!(stats.steps as f64 <= 1.5 * onset.steps as f64, "λ = {lambda:e}, Implicit: {stats:?} vs {onset:?}");
    }
}

/// Without an implicit block, [`Method::Auto`] is DOP853: the same steps and outputs bit for bit as
/// [`Method::Explicit`], never switching.
#[test]
fn auto_without_implicit_block_is_dop853() {
    let mut a = Linear::new(vec![vec![-1.0]], vec![(1.0, vec![vec![-2.0]])]);
    let mut b = Linear::new(vec![vec![-1.0]], vec![(1.0, vec![vec![-2.0]])]);
    let (out_a, sa) = run_with(&mut a, &[1.0], &[1.0], 20.0, 0.1, 1e-9, Method::Auto);
    let (out_b, sb) = run_with(&mut b, &[1.0], &[1.0], 20.0, 0.1, 1e-9, Method::Explicit);
    assert_eq!(sa, sb);
    assert_eq!(out_a, out_b);
    assert_eq!((sa.switches, sa.implicit_steps), (0, 0));
}

#[test]
fn the_dde_solver_refuses_inconsistent_arguments() {
    use std::ops::ControlFlow;
    /// y' = −y(t − τ), one state, delayed.
    struct Lag(Vec<f64>);
    impl DelaySystem for Lag {
        fn dim(&self) -> usize {
            1
        }
        fn n_delayed(&self) -> usize {
            1
        }
        fn delays(&self) -> &[f64] {
            &self.0
        }
        fn rhs(&mut self, t: f64, _: &[f64], past: &Past<'_>, dy: &mut [f64]) {
            past.eval_into(t - self.0[0], 0, dy);
            dy[0] = -dy[0];
        }
    }
    let go = |_: f64, _: &[f64]| ControlFlow::Continue(());
    let opts = Options::default();
    let input = |r: Result<_, SolveError>| match r {
        Err(SolveError::Input { argument, found, .. }) => (argument, found),
        other => panic!("{other:?}"),
    };
    // Each returns an error; none panics.
    assert_eq!(input(solve(&mut Lag(vec![1.0]), 0.0, &[1.0, 2.0], &[1.0], 1.0, 0.5, &opts, go)), ("y0", "2".into()));
    assert_eq!(input(solve(&mut Lag(vec![1.0]), 0.0, &[1.0], &[], 1.0, 0.5, &opts, go)), ("history", "0".into()));
    assert_eq!(
        input(solve(&mut Lag(vec![1.0]), 0.0, &[1.0], &[1.0], f64::NAN, 0.5, &opts, go)),
        ("t_end", "NaN".into())
    );
    assert_eq!(input(solve(&mut Lag(vec![-1.0]), 0.0, &[1.0], &[1.0], 1.0, 0.5, &opts, go)), ("delays()", "-1".into()));
    let e = solve(&mut Lag(vec![1.0]), 0.0, &[1.0, 2.0], &[1.0], 1.0, 0.5, &opts, go).unwrap_err();
    assert_eq!(e.to_string(), "dde::solve: y0: expected 1 entry (the system's dim()), found 2");
    // The right arguments: on [0, 1] with history 1, y(t) = 1 − t exactly (the method's order ≥ 1).
    let mut last = 0.0;
    solve(&mut Lag(vec![1.0]), 0.0, &[1.0], &[1.0], 1.0, 0.5, &opts, |_, y| {
        last = y[0];
        ControlFlow::Continue(())
    })
    .unwrap();
    assert!(last.abs() < 1e-12, "{last}");
}
