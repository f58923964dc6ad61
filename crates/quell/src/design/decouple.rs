//! Falb–Wolovich decoupling by state feedback (Section III, eq. (7), Proposition 1).

use nalgebra::{Complex, DMatrix, DVector, RowDVector};

use super::assumptions::balanced;
use super::{ChannelTf, DesignError};
use crate::linalg::singular_extremes;
use crate::plant::{check, PlantError};

/// The design layer's one tolerance τ. Every "is it zero?" and "is it singular?" decision is made
/// on a scale-free measure in [0, 1] (it does not grow with ‖A‖^(l−1), nor change with the units of
/// the inputs, outputs or disturbances, and the first two are taken on the balanced realization
/// (the states balanced by powers of two, as LAPACK's dgebal), so that the states' units hardly
/// move them) and compared with τ:
///
/// | decision | measure | passes when |
/// |---|---|---|
/// | c_i A^(l−1) B ≠ 0, eq. (7) | largest cosine between c_i A^(l−1) and a column of B | ≥ τ |
/// | B* nonsingular, Proposition 1 | smallest singular value of B* with rows c_i A^(σ_i−1) and columns of B at unit norm (entries are those cosines) | ≥ τ |
/// | N = L_ω D⁺ well posed, eq. (20) | smallest singular value of D with unit columns | ≥ τ |
///
/// τ = 1e-5: data rounded to six significant digits (relative error 5e-7 per entry) moves an exactly
/// zero cosine by about 1e-6, a factor 10 below τ. A row of the scaled B* has norm at most √m times
/// its largest cosine, so a σ_i decided on a cosine just above τ leaves a B* the second test judges
/// by the same τ (for m = 1 the two tests coincide). A measure within [`CLOSE_FACTOR`] of τ is reported as close.
pub const TOL: f64 = 1e-5;

/// A decision is close when its measure lies within this factor of [`TOL`] (either side).
pub const CLOSE_FACTOR: f64 = 100.0;

/// True when `measure` is within [`CLOSE_FACTOR`] of [`TOL`].
pub fn close(measure: f64) -> bool {
    (TOL / CLOSE_FACTOR..=TOL * CLOSE_FACTOR).contains(&measure)
}

/// The decision of eq. (7) for one output: σ_i and the measure at each l = 1, …, n.
#[derive(Debug, Clone, PartialEq)]
pub struct RelativeDegree {
    /// σ_i as eq. (7) decides it, the least l whose measure is ≥ [`TOL`]; `None` when no l ≤ n passes.
    pub decided: Option<usize>,
    /// σ_i as the designer gave it (`design.relative_degrees`), which the design then uses.
    pub given: Option<usize>,
    /// measures[l − 1] = max_j |c_i A^(l−1) b_j| / (‖c_i A^(l−1)‖ ‖b_j‖), for l = 1, …, n.
    pub measures: Vec<f64>,
}

impl RelativeDegree {
    /// The σ_i the design uses: the given one, else the decided one.
    pub fn used(&self) -> Option<usize> {
        self.given.or(self.decided)
    }
    /// The measures behind the σ_i in use (l ≤ σ_i, or all of them when no l passed).
    pub fn deciding(&self) -> &[f64] {
        &self.measures[..self.used().unwrap_or(self.measures.len())]
    }
    /// True when a deciding measure is close to [`TOL`] (see [`close`]).
    pub fn is_close(&self) -> bool {
        self.deciding().iter().any(|&m| close(m))
    }
}

/// B with unit-norm columns (a zero column stays zero).
pub(crate) fn unit_columns(B: &DMatrix<f64>) -> DMatrix<f64> {
    let mut Bn = B.clone();
    for mut c in Bn.column_iter_mut() {
        let nrm = c.norm();
        if nrm > 0.0 {
            c /= nrm;
        }
    }
    Bn
}

/// Eq. (7) for every output, on the normalized iterates r_l = c_i A^(l−1) / ‖c_i A^(l−1)‖: the
/// measure at l is max_j |r_l b̂_j| with b̂_j the unit columns of B (see [`TOL`]). An error when A
/// is not square, B has not A's rows or C not A's columns, or an entry is non-finite or beyond
/// [`MAX_ENTRY`](crate::plant::MAX_ENTRY).
pub fn relative_degree_measures(
    A: &DMatrix<f64>,
    B: &DMatrix<f64>,
    C: &DMatrix<f64>,
) -> Result<Vec<RelativeDegree>, PlantError> {
    let n = A.nrows();
    check("A", A, n, n)?;
    check("B", B, n, B.ncols())?;
    check("C", C, C.nrows(), n)?;
    let (A, B, C, _) = balanced(A, B, C);
    Ok(cosines(&A, &B, &C))
}

/// [`relative_degree_measures`] on a realization already balanced: the cosines are the states'
/// coordinates' (one state in a unit 1e6 times another's had left no relative degree at all), the
/// balanced ones nearly not.
fn cosines(A: &DMatrix<f64>, B: &DMatrix<f64>, C: &DMatrix<f64>) -> Vec<RelativeDegree> {
    let n = A.nrows();
    let Bn = unit_columns(B);
    (0..C.nrows())
        .map(|i| {
            let mut row: RowDVector<f64> = C.row(i).clone_owned();
            let mut measures = Vec::with_capacity(n);
            for _ in 0..n {
                let nrm = row.norm();
                if nrm == 0.0 || !nrm.is_finite() {
                    measures.resize(n, 0.0);
                    break;
                }
                row /= nrm;
                measures.push((&row * &Bn).amax());
                row = &row * A;
            }
            let decided = measures.iter().position(|&m| m >= TOL).map(|l| l + 1);
            RelativeDegree { decided, given: None, measures }
        })
        .collect()
}

/// Relative degrees σ_i (eq. (7)), decided as in [`relative_degree_measures`]. `None` for an output
/// that no input reaches (every measure below [`TOL`] for l ≤ n). Errors as there.
pub fn relative_degrees(
    A: &DMatrix<f64>,
    B: &DMatrix<f64>,
    C: &DMatrix<f64>,
) -> Result<Vec<Option<usize>>, PlantError> {
    Ok(relative_degree_measures(A, B, C)?.into_iter().map(|d| d.decided).collect())
}

/// Proposition 1's result: the decoupling gains and the closed loop they give.
#[derive(Debug, Clone)]
pub struct FalbWolovich {
    /// G_ii(s) = q_i0 / ∏_j (s − λ_ij) per channel: the record of σ_i (its order) and q_i0.
    pub channels: Vec<ChannelTf>,
    pub B_star: DMatrix<f64>,
    pub C_star: DMatrix<f64>,
    /// K = (B*)⁻¹ C*.
    pub K: DMatrix<f64>,
    /// F = (B*)⁻¹ diag(q_i0).
    pub F: DMatrix<f64>,
    /// Condition number of B* with its rows and columns scaled to unit norm in turn until they stay
    /// (scale-free: invariant under the states' coordinates and the units of inputs and outputs).
    pub cond_B_star: f64,
    /// Smallest singular value of B* scaled as in [`TOL`] (the rows c_i A^(σ_i−1) and the columns
    /// of B to unit norm: its entries are cosines), ≥ [`TOL`].
    pub smallest_B_star: f64,
    /// The decision of eq. (7) for each output.
    pub degrees: Vec<RelativeDegree>,
}

impl FalbWolovich {
    /// Relative degrees σ_i in use, eq. (7).
    pub fn sigma(&self) -> Vec<usize> {
        self.channels.iter().map(ChannelTf::sigma).collect()
    }

    /// K_0 = B*⁻¹ [c_i A^σ_i]: Proposition 1's K with every channel pole at 0. On the zero
    /// dynamics' subspace, ker [c_i A^j]_{j<σ_i}, it acts as every K of Proposition 1 does, without
    /// the size fast channel poles give K. (B* was inverted for K; its inverse is formed again.)
    pub fn zero_pole_gain(&self, A: &DMatrix<f64>, C: &DMatrix<f64>) -> DMatrix<f64> {
        let mut rows = DMatrix::zeros(self.channels.len(), A.nrows());
        for (i, tf) in self.channels.iter().enumerate() {
            let mut row: RowDVector<f64> = C.row(i).clone_owned();
            for _ in 0..tf.sigma() {
                row = &row * A;
            }
            rows.set_row(i, &row);
        }
        self.B_star.clone().try_inverse().map_or_else(|| self.K.clone(), |inv| inv * rows)
    }
}

/// Falb–Wolovich decoupler (Proposition 1) for per-channel poles `channel_poles[i]` (σ_i each, closed
/// under conjugation; the caller checks that), with σ_i decided by eq. (7). Errors when an output is
/// unreachable, a channel has the wrong number of poles, or B* is singular.
pub fn falb_wolovich(
    A: &DMatrix<f64>,
    B: &DMatrix<f64>,
    C: &DMatrix<f64>,
    channel_poles: &[Vec<Complex<f64>>],
) -> Result<FalbWolovich, DesignError> {
    falb_wolovich_given(A, B, C, channel_poles, None)
}

/// [`falb_wolovich`] with σ_i optionally given (`design.relative_degrees`, each in 1..=n) instead of
/// decided. A given σ_i is used unless the plant clearly contradicts it: some l < σ_i has measure
/// above [`CLOSE_FACTOR`]·τ (c_i A^(l−1) B is clearly non-zero), or l = σ_i has measure < τ/[`CLOSE_FACTOR`]
/// (c_i A^(σ_i−1) B is clearly zero). Within that band, where eq. (7) itself reports a close decision,
/// the designer's word decides; B* is then judged as always (smallest scaled singular value ≥ τ).
pub fn falb_wolovich_given(
    A: &DMatrix<f64>,
    B: &DMatrix<f64>,
    C: &DMatrix<f64>,
    channel_poles: &[Vec<Complex<f64>>],
    given: Option<&[usize]>,
) -> Result<FalbWolovich, DesignError> {
    let (m, n) = (B.ncols(), A.nrows());
    check("A", A, n, n)?;
    check("B", B, n, m)?;
    check("C", C, m, n)?; // as many outputs as inputs
    if channel_poles.len() != m {
        return Err(DesignError::Count {
            key: "design.channel_poles",
            per: "output",
            expected: m,
            got: channel_poles.len(),
        });
    }
    if let Some(g) = given.filter(|g| g.len() != m) {
        return Err(DesignError::Count { key: "design.relative_degrees", per: "output", expected: m, got: g.len() });
    }
    // Eq. (7)'s cosines and B*'s on the balanced realization, balanced once.
    let (Ab, Bb, Cb, _) = balanced(A, B, C);
    let mut degrees = cosines(&Ab, &Bb, &Cb);
    let mut sum = 0;
    for (channel, d) in degrees.iter_mut().enumerate() {
        let s = relative_degree_in_use(d, channel, given.map(|g| g[channel]), n)?;
        let got = channel_poles[channel].len();
        if got != s {
            let pairs = channel_poles[channel].iter().filter(|p| p.im > 0.0).count();
            return Err(DesignError::ChannelPoleCount { channel, sigma: s, got, pairs });
        }
        sum += s;
    }
    if sum > n {
        return Err(DesignError::RelativeDegreeSum { sum, n });
    }
    let channels: Vec<ChannelTf> = channel_poles.iter().map(|p| ChannelTf::new(p)).collect();
    let (B_star, C_star) = decoupling_rows(A, B, C, &channels);
    let (smallest, cond) = singular_extremes(&cosine_B_star(&Ab, &Bb, &Cb, &channels));
    let inv = match B_star.clone().try_inverse() {
        Some(inv) if smallest >= TOL => inv,
        _ => {
            let sigma = channels.iter().map(ChannelTf::sigma).collect();
            return Err(DesignError::NotDecouplable { smallest, cond, sigma });
        }
    };
    let cond_B_star = equilibrated_condition(&B_star);
    let K = &inv * &C_star;
    let q0 = DVector::from_iterator(m, channels.iter().map(ChannelTf::q0));
    let F = &inv * DMatrix::from_diagonal(&q0);
    Ok(FalbWolovich { channels, B_star, C_star, K, F, cond_B_star, smallest_B_star: smallest, degrees })
}

/// κ₂ of B* with its rows and its columns scaled to unit norm, in turn until they stay: invariant,
/// as B* itself is, under the states' coordinates, and under the units of the inputs and outputs
/// where B* has no zero pattern that lets the scaling drift (a triangular B* settles within a few
/// percent of one value: 1.106 against 1.202 for three-channel's inputs in units 1e12 apart); near
/// the least κ₂ over those scalings (a 2×2 [[a, b], [c, d]] ends as [[γ, σ], [σ, γ]] up to signs,
/// κ₂ = (γ + σ)/|γ − σ| with γ/σ = √|ad/bc|, that least). The cosines of [`TOL`] are not
/// invariant: one state in a unit 50× another's had moved them from κ₂ = 1.7 to 50.
fn equilibrated_condition(B_star: &DMatrix<f64>) -> f64 {
    singular_extremes(&crate::linalg::equilibrated(B_star.clone())).1
}

/// The σ_i channel `channel` uses: the `given` one unless the plant clearly contradicts it (see
/// [`falb_wolovich_given`]; recorded in `d.given`), else the one eq. (7) decided.
fn relative_degree_in_use(
    d: &mut RelativeDegree,
    channel: usize,
    given: Option<usize>,
    n: usize,
) -> Result<usize, DesignError> {
    let Some(s) = given else {
        let largest = d.measures.iter().copied().fold(0.0, f64::max);
        return d.decided.ok_or(DesignError::NoRelativeDegree { channel, largest });
    };
    if s == 0 || s > n {
        return Err(DesignError::RelativeDegreeRange { index: channel, value: s, n });
    }
    if let Some(l) = d.measures[..s - 1].iter().position(|&x| x > TOL * CLOSE_FACTOR) {
        let measure = d.measures[l];
        return Err(DesignError::RelativeDegreeTooHigh { channel, given: s, l: l + 1, measure });
    }
    if d.measures[s - 1] < TOL / CLOSE_FACTOR {
        let measure = d.measures[s - 1];
        return Err(DesignError::RelativeDegreeTooLow { channel, given: s, measure });
    }
    d.given = Some(s);
    Ok(s)
}

/// Proposition 1's rows for each channel: B* with row i = c_i A^(σ_i−1) B, C* with row
/// i = c_i A^(σ_i) + Σ_z q_iz c_i A^z (q_iz the coefficients of ∏_j (s − λ_ij)).
fn decoupling_rows(
    A: &DMatrix<f64>,
    B: &DMatrix<f64>,
    C: &DMatrix<f64>,
    channels: &[ChannelTf],
) -> (DMatrix<f64>, DMatrix<f64>) {
    let (m, n) = (channels.len(), A.nrows());
    let mut B_star = DMatrix::zeros(m, B.ncols());
    let mut C_star = DMatrix::zeros(m, n);
    for (i, tf) in channels.iter().enumerate() {
        let mut row: RowDVector<f64> = C.row(i).clone_owned(); // c_i A^z
        let mut c_star = RowDVector::zeros(n);
        let mut last = RowDVector::zeros(n); // c_i A^(σ_i − 1), the row of B*
        for &qz in &tf.den {
            c_star += qz * &row;
            last = row;
            row = &last * A;
        }
        // row is now c_i A^{σ_i}; B* uses c_i A^{σ_i − 1} B.
        c_star += &row;
        B_star.set_row(i, &(&last * B));
        C_star.set_row(i, &c_star);
    }
    (B_star, C_star)
}

/// The B* of the tolerance policy ([`TOL`]) on the realization given (the balanced one): entry
/// (i, j) the cosine between c_i A^(σ_i−1) and b_j.
fn cosine_B_star(A: &DMatrix<f64>, B: &DMatrix<f64>, C: &DMatrix<f64>, channels: &[ChannelTf]) -> DMatrix<f64> {
    // c_i A^(σ_i−1), and its products with B (row i of B*).
    let rows: Vec<(RowDVector<f64>, RowDVector<f64>)> = channels
        .iter()
        .enumerate()
        .map(|(i, tf)| (1..tf.sigma()).fold(C.row(i).clone_owned(), |row, _| &row * A))
        .map(|row| {
            let product = &row * B;
            (row, product)
        })
        .collect();
    DMatrix::from_fn(channels.len(), B.ncols(), |i, j| {
        let d = rows[i].0.norm() * B.column(j).norm();
        if d > 0.0 {
            rows[i].1[j] / d
        } else {
            0.0
        }
    })
}
