//! What the benches share with `workload.rs`: the integrator bench's delay equation and the
//! controller bench's synthetic designs.
#![allow(non_snake_case, dead_code)] // each bench uses a part

use std::ops::ControlFlow;

use quell::bench_api::dde::{solve, DelaySystem, Options, Past, Stats};
use quell::nalgebra::{Complex, DMatrix};
use quell::{Design, DesignSpec, ObserverChoice, Plant};

/// u'(t) = −u(t − 1/3) − u(t − 1/5).
pub struct TwoDelays {
    pub delays: [f64; 2],
    pub buf: [f64; 1],
}

impl TwoDelays {
    pub fn new() -> Self {
        TwoDelays { delays: [1.0 / 3.0, 0.2], buf: [0.0] }
    }
}

impl DelaySystem for TwoDelays {
    fn dim(&self) -> usize {
        1
    }
    fn n_delayed(&self) -> usize {
        1
    }
    fn delays(&self) -> &[f64] {
        &self.delays
    }
    fn rhs(&mut self, t: f64, _y: &[f64], past: &Past<'_>, dy: &mut [f64]) {
        past.eval_into(t - self.delays[0], 0, &mut self.buf);
        let a = self.buf[0];
        past.eval_into(t - self.delays[1], 0, &mut self.buf);
        dy[0] = -a - self.buf[0];
    }
}

/// The bench's run: history 0, u(0) = 1, on [0, 10], output every 0.1 at tolerance `tol`; the
/// statistics and u(10).
pub fn solve_two_delays(tol: f64) -> (Stats, f64) {
    let opts = Options { rtol: tol, atol: tol, ..Options::default() };
    let mut last = 0.0;
    let stats = solve(&mut TwoDelays::new(), 0.0, &[1.0], &[0.0], 10.0, 0.1, &opts, |_, y| {
        last = y[0];
        ControlFlow::Continue(())
    })
    .unwrap();
    (stats, last)
}

/// A decouplable m-channel plant (n = m, B = C = I, σ_i = 1) with q_g = q (q/m filter poles per
/// reference component) and no disturbance, for scaling runs.
pub fn synthetic(m: usize, q: usize) -> Design {
    let A = DMatrix::from_fn(m, m, |i, j| if i == j { 0.5 } else { 0.1 * ((i * 7 + j * 3) % 5) as f64 - 0.2 });
    let plant = Plant::new(
        A,
        DMatrix::identity(m, m),
        DMatrix::identity(m, m),
        DMatrix::zeros(m, 0),
        DMatrix::zeros(m, 0),
        vec![0.01; m],
        None,
    )
    .unwrap();
    let per = q / m;
    let spec = DesignSpec {
        observer: ObserverChoice::Poles((0..m).map(|i| Complex::new(-2.0 - i as f64, 0.0)).collect()),
        channel_poles: (0..m).map(|i| vec![Complex::new(-3.0 - 0.1 * i as f64, 0.0)]).collect(),
        reference_filter_poles: (0..m)
            .map(|_| (0..per).map(|j| Complex::new(-1.0 - j as f64, 0.0)).collect())
            .collect(),
        disturbance_filter_poles: vec![],
        mu: vec![10.0; m],
        beta: 1.0,
        relative_degrees: None,
        regressor_scaling: Default::default(),
        reference_sizes: Vec::new(),
        disturbance_sizes: Vec::new(),
    };
    Design::new(&plant, &spec).unwrap()
}
