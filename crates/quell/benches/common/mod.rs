//! The integrator bench's delay equation, shared by `dde.rs` and `workload.rs`.

use std::ops::ControlFlow;

use quell::sim::dde::{solve, DelaySystem, Options, Past, Stats};

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
