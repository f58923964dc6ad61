//! The sampled-data loop's plant input between two samples: the controller's u_f moved to the
//! true delays of the commands (`truth.delays`), then through the actuator (`truth.actuator_delays`,
//! `u_max`), held piecewise constant where a delay is not a whole number of samples.

use nalgebra::DMatrix;

use crate::controller::discrete::{self, MAX_DELAY_SAMPLES};
use crate::settings::{self, Actuator, KeyError, TimeUnit};

/// Breakpoints within a sample closer than this (a fraction of T_s) are one: a switch moved by
/// 1e-9 T_s changes the plant's state by as little (a midpoint may then fall on the wrong side of
/// a merged point, for that sliver of a sample).
const SAME_BREAKPOINT: f64 = 1e-9;

/// The last samples of an m-channel signal v, enough to read channel i at any delay up to the
/// longest given: v_i(k − d), 0 before k = 0.
struct PastSamples {
    /// Row k mod len: v(k).
    past: Vec<f64>,
    len: usize,
    m: usize,
}

impl PastSamples {
    fn new(m: usize, longest: usize) -> Self {
        PastSamples { past: vec![0.0; (longest + 1) * m], len: longest + 1, m }
    }

    /// Records v(k).
    fn push(&mut self, k: usize, v: &[f64]) {
        let row = k % self.len;
        self.past[row * self.m..(row + 1) * self.m].copy_from_slice(v);
    }

    /// v_i(k − d), 0 before k = 0.
    fn at(&self, k: usize, d: usize, i: usize) -> f64 {
        if k >= d {
            self.past[((k - d) % self.len) * self.m + i]
        } else {
            0.0
        }
    }
}

/// The plant's input over sample k, [kT, (k+1)T), piecewise constant on segments
/// [s_r T, s_{r+1} T) (one segment where every delay is whole). With the actuator's delay
/// τ_a,j = (a_j + g_j) T (a_j whole, 0 ≤ g_j < 1) and the true delays τ_i^true = (c_i + f_i) T of
/// the commands, input j at time t is
///
///   u_p,j(t) = sat_j(ũ_j(t − τ_a,j)),  ũ(t) = u_f(⌊t⌋) + F (u(t − τ^true) − u(⌊t⌋ − d)),
///
/// the controller's u_f = −K x̂ + F u(k − d) (formed at the model's whole delays d) with its
/// commands moved to the true delays, u and u_f held over each sample and 0 before k = 0. Every
/// read is a sample offset from k fixed before the run (the segment's midpoint's), so a step costs
/// sums only. The exact sampling of such an input is [`InputLine::segments`]' (Åström &
/// Wittenmark, Computer-Controlled Systems, §2.3, a delay that is not a whole number of samples).
pub(super) struct InputLine {
    m: usize,
    /// The segments' starts s_r in [0, 1), s_0 = 0.
    starts: Vec<f64>,
    /// u_f's offset for segment r, input j: [r·m + j].
    uf_offset: Vec<usize>,
    shift: Option<Shift>,
    actuator: Option<Actuator>,
    u_f: PastSamples,
    /// The plant's input on segment r: [r·m + j]; segment 0's is its input at the sample.
    pub(super) values: Vec<f64>,
    /// The same before the actuator's limit.
    pub(super) demand: Vec<f64>,
    /// Whether the limit clipped input j at the sample.
    pub(super) limited: Vec<bool>,
}

/// The commands moved to their true delays: u's offsets at the true and at the model's delay for
/// segment r, input j, command i ([(r·m + j)·m + i]).
struct Shift {
    F: DMatrix<f64>,
    u: PastSamples,
    at_true: Vec<usize>,
    at_model: Vec<usize>,
}

impl InputLine {
    /// The line for the model's delays `model` (whole samples, the controller's), the true delays
    /// `truth` (empty: the model's) and the true plant's `actuator` (`None`: ideal) at T.
    pub(super) fn new(
        (model, truth): (&[f64], &[f64]),
        F: &DMatrix<f64>,
        actuator: Option<&Actuator>,
        T: (f64, TimeUnit),
    ) -> Result<Self, KeyError> {
        let m = model.len();
        let d = split_delays("plant.delays", model, T)?.0;
        let (c, f) = if truth.is_empty() { (d.clone(), vec![0.0; m]) } else { split_delays("truth.delays", truth, T)? };
        let (a, g) = match actuator {
            Some(act) => split_delays("truth.actuator_delays", &act.delays, T)?,
            None => (vec![0; m], vec![0.0; m]),
        };
        let shifted = !truth.is_empty();
        let starts = segment_starts(&g, if shifted { &f } else { &[] }, F);
        let ends = starts.iter().skip(1).copied().chain([1.0]);
        let mids: Vec<f64> = starts.iter().zip(ends).map(|(s, e)| 0.5 * (s + e)).collect();
        // ⌊x⌋ for x in (−3, 1): the whole samples a read at x (in samples from kT) goes back.
        let back = |x: f64| (-x.floor()) as usize;
        let uf_offset: Vec<usize> =
            (mids.iter()).flat_map(|&mu| (0..m).map(move |j| (mu, j))).map(|(mu, j)| a[j] + back(mu - g[j])).collect();
        let shift = shifted.then(|| {
            let (mut at_true, mut at_model) = (Vec::new(), Vec::new());
            for (r, &mu) in mids.iter().enumerate() {
                for j in 0..m {
                    for i in 0..m {
                        at_true.push(a[j] + c[i] + back(mu - g[j] - f[i]));
                        at_model.push(uf_offset[r * m + j] + d[i]);
                    }
                }
            }
            let longest = at_true.iter().chain(&at_model).copied().max().unwrap_or(0);
            Shift { F: F.clone(), u: PastSamples::new(m, longest), at_true, at_model }
        });
        let segments = starts.len();
        Ok(InputLine {
            m,
            starts,
            u_f: PastSamples::new(m, uf_offset.iter().copied().max().unwrap_or(0)),
            uf_offset,
            shift,
            actuator: actuator.filter(|act| !act.is_ideal()).cloned(),
            values: vec![0.0; segments * m],
            demand: vec![0.0; segments * m],
            limited: vec![false; m],
        })
    }

    /// The segments [s_r, s_{r+1}) of a sample, in fractions of it.
    pub(super) fn segments(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.starts.iter().copied().zip(self.starts.iter().skip(1).copied().chain([1.0]))
    }

    /// Whether the true plant has an actuator that changes its input (a delay or a limit).
    pub(super) fn has_actuator(&self) -> bool {
        self.actuator.is_some()
    }

    /// Records u_f(k) and u(k) and sets each segment's plant input of sample k.
    pub(super) fn apply(&mut self, k: usize, u_f: &[f64], u: &[f64]) {
        self.u_f.push(k, u_f);
        if let Some(sh) = self.shift.as_mut() {
            sh.u.push(k, u);
        }
        let m = self.m;
        for (rj, &o) in self.uf_offset.iter().enumerate() {
            let j = rj % m;
            let mut v = self.u_f.at(k, o, j);
            if let Some(sh) = &self.shift {
                for i in 0..m {
                    let du = sh.u.at(k, sh.at_true[rj * m + i], i) - sh.u.at(k, sh.at_model[rj * m + i], i);
                    v += sh.F[(j, i)] * du;
                }
            }
            self.demand[rj] = v;
            self.values[rj] = match &self.actuator {
                Some(act) => {
                    let (held, clipped) = act.clip(j, v);
                    if rj < m {
                        self.limited[j] = clipped;
                    }
                    held
                }
                None => v,
            };
        }
    }
}

/// s_0 = 0 and every point within a sample where an input switches: the actuator's fractions g_j,
/// and with true delays of the commands (fractions f_i) (g_j + f_i) mod 1 where command i reaches
/// input j (F_ji ≠ 0), merged within [`SAME_BREAKPOINT`].
fn segment_starts(g: &[f64], f: &[f64], F: &DMatrix<f64>) -> Vec<f64> {
    let pairs = g.iter().enumerate().flat_map(|(j, &gj)| f.iter().enumerate().map(move |(i, &fi)| (j, i, gj + fi)));
    let through = pairs.filter(|&(j, i, _)| F[(j, i)] != 0.0).map(|(.., s)| s.fract());
    let mut points: Vec<f64> =
        g.iter().copied().chain(through).filter(|&s| s > SAME_BREAKPOINT && s < 1.0 - SAME_BREAKPOINT).collect();
    points.sort_by(f64::total_cmp);
    let mut starts = vec![0.0];
    for s in points {
        if s - starts[starts.len() - 1] > SAME_BREAKPOINT {
            starts.push(s);
        }
    }
    starts
}

/// Each delay as a whole number of samples of T and a fraction of one in [0, 1) (within rounding
/// of a whole number, none), or an error on `key[i]` for one beyond [`MAX_DELAY_SAMPLES`] samples.
pub(super) fn split_delays(
    key: &str,
    delays: &[f64],
    (T, unit): (f64, TimeUnit),
) -> Result<(Vec<usize>, Vec<f64>), KeyError> {
    (delays.iter().enumerate())
        .map(|(i, &tau)| {
            if discrete::whole(tau, T) {
                if let Some(d) = discrete::whole_multiple(tau, T) {
                    return Ok((d, 0.0));
                }
            }
            let samples = tau / T;
            if !(samples.is_finite() && samples <= MAX_DELAY_SAMPLES) {
                return Err(KeyError::new(
                    format!("{key}[{i}]"),
                    format!(
                        "τ = {} {unit} is {samples:e} samples of T_s = {} {unit}; a sampled-data run's delay line holds at most {MAX_DELAY_SAMPLES:e}: choose a simulation.sample_time of at least {} {unit} (one that makes plant.delays whole samples) or a shorter delay",
                        settings::fmt_short(tau),
                        settings::fmt_time(T),
                        settings::fmt_short(settings::significant(tau / MAX_DELAY_SAMPLES * 1.001, 4)),
                    ),
                ));
            }
            let d = samples.floor();
            Ok((d as usize, samples - d))
        })
        .collect::<Result<Vec<_>, _>>()
        .map(|v| v.into_iter().unzip())
}
