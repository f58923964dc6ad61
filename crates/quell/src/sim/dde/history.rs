//! Ring buffer of dense-output step records for the delayed state prefix.

/// Number of dense-output coefficients per component (7th-order polynomial).
pub(super) const NCOEF: usize = 8;

/// The nodes z_0..z_6 of a degree-7 polynomial in Newton form over θ = (t − start)/h:
/// p(θ) = c_0 + (θ − z_0)(c_1 + (θ − z_1)(c_2 + … + (θ − z_6) c_7)).
pub(super) type Nodes = [f64; NCOEF - 1];

/// Dense history of the accepted steps: for each step its start time, its length, the Newton nodes
/// of its polynomial and the [`NCOEF`] coefficients of the first `nd` components. Kept in a ring whose
/// capacity only grows (doubling) until the pruned length stabilises, so a long run does not
/// allocate once the ring is large enough to span the largest delay.
pub(super) struct History {
    nd: usize,
    cap: usize,
    head: usize,
    len: usize,
    max_len: usize,
    start: Vec<f64>,
    step: Vec<f64>,
    nodes: Vec<Nodes>,
    coef: Vec<f64>,
    /// The last records found (logical indices), tried before a binary search: each delay's queries
    /// move forward slowly, so consecutive lookups for one delay mostly land in the same record.
    hints: [std::cell::Cell<usize>; 2],
}

impl History {
    pub(super) fn new(nd: usize, cap: usize) -> Self {
        let cap = cap.max(4);
        History {
            nd,
            cap,
            head: 0,
            len: 0,
            max_len: 0,
            start: vec![0.0; cap],
            step: vec![0.0; cap],
            nodes: vec![[0.0; NCOEF - 1]; cap],
            coef: vec![0.0; cap * NCOEF * nd],
            hints: Default::default(),
        }
    }

    #[inline]
    fn phys(&self, i: usize) -> usize {
        let p = self.head + i;
        if p >= self.cap {
            p - self.cap
        } else {
            p
        }
    }

    pub(super) fn len(&self) -> usize {
        self.len
    }

    pub(super) fn max_len(&self) -> usize {
        self.max_len
    }

    /// Appends a record for the step [t, t + h] with Newton nodes `nodes` and returns its
    /// coefficient slot (coefficient-major: `slot[r * nd + c]`) for the caller to fill.
    pub(super) fn push(&mut self, t: f64, h: f64, nodes: &Nodes) -> &mut [f64] {
        if self.len == self.cap {
            self.grow();
        }
        let p = self.phys(self.len);
        self.len += 1;
        self.max_len = self.max_len.max(self.len);
        self.start[p] = t;
        self.step[p] = h;
        self.nodes[p] = *nodes;
        let w = NCOEF * self.nd;
        &mut self.coef[p * w..(p + 1) * w]
    }

    /// Doubles the capacity, unrolling the ring so that the head is at 0.
    fn grow(&mut self) {
        let new_cap = self.cap * 2;
        let w = NCOEF * self.nd;
        let mut start = vec![0.0; new_cap];
        let mut step = vec![0.0; new_cap];
        let mut nodes = vec![[0.0; NCOEF - 1]; new_cap];
        let mut coef = vec![0.0; new_cap * w];
        for i in 0..self.len {
            let p = self.phys(i);
            start[i] = self.start[p];
            step[i] = self.step[p];
            nodes[i] = self.nodes[p];
            coef[i * w..(i + 1) * w].copy_from_slice(&self.coef[p * w..(p + 1) * w]);
        }
        self.start = start;
        self.step = step;
        self.nodes = nodes;
        self.coef = coef;
        self.cap = new_cap;
        self.head = 0;
    }

    /// Drops records that no query at or after `t_keep` can reach, keeping one extra record
    /// before `t_keep` as a margin against rounding in the delayed arguments.
    pub(super) fn prune(&mut self, t_keep: f64) {
        while self.len >= 3 && self.start[self.phys(2)] <= t_keep {
            self.head = self.phys(1);
            self.len -= 1;
            for hint in &self.hints {
                hint.set(hint.get().saturating_sub(1));
            }
        }
    }

    /// The record holding `s` (the one with the largest start ≤ s, by binary search; extrapolates
    /// slightly outside the stored span) and θ = (s − start)/h there. The ring must not be empty.
    #[inline]
    pub(super) fn locate(&self, s: f64) -> (usize, f64) {
        debug_assert!(self.len > 0);
        let holds = |i: usize| {
            i < self.len && self.start[self.phys(i)] <= s && (i + 1 == self.len || self.start[self.phys(i + 1)] > s)
        };
        for hint in &self.hints {
            let i = hint.get();
            if holds(i) {
                let p = self.phys(i);
                return (p, (s - self.start[p]) / self.step[p]);
            }
        }
        let (mut lo, mut hi) = (0usize, self.len);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if self.start[self.phys(mid)] <= s {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        let i = lo.saturating_sub(1);
        // Keep the two most recent distinct records.
        self.hints[1].set(self.hints[0].get());
        self.hints[0].set(i);
        let p = self.phys(i);
        (p, (s - self.start[p]) / self.step[p])
    }

    /// For each (first, out): components `first..first + out.len()` of the dense output at a point from
    /// [`History::locate`].
    #[inline]
    pub(super) fn eval_at(&self, (p, theta): (usize, f64), ranges: &mut [(usize, &mut [f64])]) {
        for (first, out) in ranges.iter() {
            assert!(
                first + out.len() <= self.nd,
                "Past::eval_into: components {}..{} requested, only {} are delayed",
                first,
                first + out.len(),
                self.nd
            );
        }
        let nd = self.nd;
        let rec = &self.coef[p * NCOEF * nd..(p + 1) * NCOEF * nd];
        newton(rec, nd, &self.nodes[p], theta, ranges);
    }
}

/// Evaluates a coefficient-major record (`c[r * stride + i]`) with Newton nodes `z` at θ: for each
/// (first, out), components `first..first + out.len()`.
#[inline]
pub(super) fn newton(c: &[f64], stride: usize, z: &Nodes, theta: f64, ranges: &mut [(usize, &mut [f64])]) {
    // A few components are cheaper inline than through the AVX2 dispatch.
    if ranges.iter().map(|(_, out)| out.len()).sum::<usize>() >= 8 {
        newton_wide(c, stride, z, theta, ranges)
    } else {
        newton_inline(c, stride, z, theta, ranges)
    }
}

with_avx2! {
    /// [`newton`] for many components.
    fn newton_wide(c: &[f64], stride: usize, z: &Nodes, theta: f64, ranges: &mut [(usize, &mut [f64])]) {
        newton_inline(c, stride, z, theta, ranges)
    }
}

#[inline(always)]
fn newton_inline(c: &[f64], stride: usize, z: &Nodes, theta: f64, ranges: &mut [(usize, &mut [f64])]) {
    let d = z.map(|z| theta - z);
    // p = lo + (d0 d1 d2 d3)·hi: two independent nestings of four, half the dependency chain.
    let d0123 = d[0] * d[1] * d[2] * d[3];
    for (first, out) in ranges.iter_mut() {
        let (n, first) = (out.len(), *first);
        let row = |r: usize| &c[r * stride + first..r * stride + first + n];
        let (c0, c1, c2, c3, c4, c5, c6, c7) = (row(0), row(1), row(2), row(3), row(4), row(5), row(6), row(7));
        for i in 0..n {
            let lo = c0[i] + d[0] * (c1[i] + d[1] * (c2[i] + d[2] * c3[i]));
            let hi = c4[i] + d[4] * (c5[i] + d[5] * (c6[i] + d[6] * c7[i]));
            out[i] = lo + d0123 * hi;
        }
    }
}
