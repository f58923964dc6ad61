//! Ring buffer of dense-output step records for the delayed state prefix.

/// Number of dense-output coefficients per component (7th-order polynomial).
pub(super) const NCOEF: usize = 8;

/// Dense history of the accepted steps: for each step its start time, its length and the
/// [`NCOEF`] dense-output coefficients of the first `nd` components. Kept in a ring whose
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

    /// Appends a record for the step [t, t + h] and returns its coefficient slot
    /// (coefficient-major: `slot[r * nd + c]`) for the caller to fill.
    pub(super) fn push(&mut self, t: f64, h: f64) -> &mut [f64] {
        if self.len == self.cap {
            self.grow();
        }
        let p = self.phys(self.len);
        self.len += 1;
        self.max_len = self.max_len.max(self.len);
        self.start[p] = t;
        self.step[p] = h;
        let w = NCOEF * self.nd;
        &mut self.coef[p * w..(p + 1) * w]
    }

    /// Doubles the capacity, unrolling the ring so that the head is at 0.
    fn grow(&mut self) {
        let new_cap = self.cap * 2;
        let w = NCOEF * self.nd;
        let mut start = vec![0.0; new_cap];
        let mut step = vec![0.0; new_cap];
        let mut coef = vec![0.0; new_cap * w];
        for i in 0..self.len {
            let p = self.phys(i);
            start[i] = self.start[p];
            step[i] = self.step[p];
            coef[i * w..(i + 1) * w].copy_from_slice(&self.coef[p * w..(p + 1) * w]);
        }
        self.start = start;
        self.step = step;
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

    /// Components `first..first + out.len()` of the dense output at a point from [`History::locate`].
    #[inline]
    pub(super) fn eval_at(&self, (p, theta): (usize, f64), first: usize, out: &mut [f64]) {
        assert!(
            first + out.len() <= self.nd,
            "Past::eval_into: components {}..{} requested, only {} are delayed",
            first,
            first + out.len(),
            self.nd
        );
        let nd = self.nd;
        let rec = &self.coef[p * NCOEF * nd..(p + 1) * NCOEF * nd];
        let c = |r: usize| &rec[r * nd + first..r * nd + first + out.len()];
        horner(c(0), c(1), c(2), c(3), c(4), c(5), c(6), c(7), theta, out);
    }
}

/// Evaluates the DOP853 dense output (`contd8` in `dop853.f`) at θ ∈ [0, 1] for all components of
/// a coefficient-major record (`c[r * len + i]`, len = `out.len()`).
#[inline]
pub(super) fn dense_eval(c: &[f64], theta: f64, out: &mut [f64]) {
    let len = out.len();
    let row = |r: usize| &c[r * len..(r + 1) * len];
    horner(row(0), row(1), row(2), row(3), row(4), row(5), row(6), row(7), theta, out);
}

/// out_i = c0 + θ(c1 + s(c2 + θ(c3 + s(c4 + θ(c5 + s(c6 + θ c7)))))), s = 1 − θ, per component.
#[inline]
#[allow(clippy::too_many_arguments)]
fn horner(
    c0: &[f64],
    c1: &[f64],
    c2: &[f64],
    c3: &[f64],
    c4: &[f64],
    c5: &[f64],
    c6: &[f64],
    c7: &[f64],
    theta: f64,
    out: &mut [f64],
) {
    let s1 = 1.0 - theta;
    let n = out.len();
    let (c0, c1, c2, c3, c4, c5, c6, c7) =
        (&c0[..n], &c1[..n], &c2[..n], &c3[..n], &c4[..n], &c5[..n], &c6[..n], &c7[..n]);
    for i in 0..n {
        let par = c4[i] + theta * (c5[i] + s1 * (c6[i] + theta * c7[i]));
        out[i] = c0[i] + theta * (c1[i] + s1 * (c2[i] + theta * (c3[i] + s1 * par)));
    }
}
