//! Multi-harmonic signals: each component is `bias + Σ amplitude·sin(frequency·t + phase)`.
//! They model the reference g(t) (Assumption 2) and the disturbance ω(t) (Assumption 3).

use nalgebra::{DMatrix, DVector};

use crate::plant::{Plant, MAX_ENTRY};
use crate::settings::KeyError;

/// One sinusoid `amplitude·sin(frequency·t + phase)`, frequency in rad/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Harmonic {
    pub amplitude: f64,
    pub frequency: f64,
    pub phase: f64,
}

/// One scalar component: a bias plus harmonics.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Component {
    pub bias: f64,
    pub harmonics: Vec<Harmonic>,
}

/// A vector signal, one [`Component`] per entry.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Signal {
    pub components: Vec<Component>,
}

/// `v` within ±[`MAX_ENTRY`], as a signal's amplitudes and biases and the noise's standard deviations
/// must be (the loop's states scale with them); else the error on `key`, expecting `what` ≤ the
/// bound and asking to rescale `units`.
pub(crate) fn moderate(key: &str, what: &str, v: f64, units: &str) -> Result<(), KeyError> {
    if v.abs() <= MAX_ENTRY {
        return Ok(());
    }
    Err(KeyError::new(
        key,
        format!(
            "expected {what} ≤ {MAX_ENTRY:e}, found {v:e}; the loop's states scale with it and their products \
             overflow double precision — rescale {units}"
        ),
    ))
}

/// sin x, within a few ulps of `f64::sin` and inlinable (the signals are evaluated at every stage of
/// the integrator): [`sin_kernel`] for |x| ≤ 1e6, `f64::sin` beyond and for NaN and ±∞.
#[inline]
pub(crate) fn sin(x: f64) -> f64 {
    if in_kernel_range(x) {
        sin_kernel(x)
    } else {
        x.sin()
    }
}

/// Whether [`sin_kernel`]'s argument reduction is exact at x: |x| ≤ 1e6 (false for NaN and ±∞).
#[inline(always)]
fn in_kernel_range(x: f64) -> bool {
    x.abs() <= 1e6
}

/// sin x where [`in_kernel_range`], without branches (so a loop of them vectorizes): Cody–Waite
/// reduction x = k·π/2 + r, |r| ≤ π/4, with π/2 in three parts of which the first two have 33
/// significant bits (k·P1, k·P2 exact for |k| < 2²⁰), then the Taylor series of sin r and cos r to
/// degrees 17 and 18 (truncation below 1e-19).
#[inline(always)]
fn sin_kernel(x: f64) -> f64 {
    const P1: f64 = 1.5707963267341256;
    const P2: f64 = 6.077100506303966e-11;
    const P3: f64 = 2.0222662487959506e-21;
    const TWO_OVER_PI: f64 = std::f64::consts::FRAC_2_PI;
    // Adding and subtracting 1.5·2⁵² rounds to the nearest integer (ties to even) for |v| < 2⁵¹.
    const ROUND: f64 = 6755399441055744.0;
    let v = x * TWO_OVER_PI + ROUND;
    let k = v - ROUND;
    // v's mantissa holds 2⁵¹ + k, so its low two bits are k mod 4: the quadrant.
    let quadrant = v.to_bits() & 3;
    let r = ((x - k * P1) - k * P2) - k * P3;
    // Both series in r² by Estrin's scheme (pairs, then pairs of pairs: a short dependency chain).
    let (r2, r4) = (r * r, r * r * r * r);
    let r8 = r4 * r4;
    let pair = |a: f64, b: f64| a + r2 * b;
    // sin r = r (1 + Σ_{n=1..8} (−1)ⁿ r²ⁿ/(2n+1)!).
    let s_lo = pair(-1.0 / 6.0, 1.0 / 120.0) + r4 * pair(-1.0 / 5040.0, 1.0 / 362_880.0);
    let s_hi = pair(-1.0 / 39_916_800.0, 1.0 / 6_227_020_800.0)
        + r4 * pair(-1.0 / 1_307_674_368_000.0, 1.0 / 355_687_428_096_000.0);
    let sin_r = r + r * r2 * (s_lo + r8 * s_hi);
    // cos r = 1 + Σ_{n=1..9} (−1)ⁿ r²ⁿ/(2n)!.
    let c_lo = pair(-0.5, 1.0 / 24.0) + r4 * pair(-1.0 / 720.0, 1.0 / 40_320.0);
    let c_hi = pair(-1.0 / 3_628_800.0, 1.0 / 479_001_600.0)
        + r4 * (pair(-1.0 / 87_178_291_200.0, 1.0 / 20_922_789_888_000.0) + r4 * (-1.0 / 6_402_373_705_728_000.0));
    let cos_r = 1.0 + r2 * (c_lo + r8 * c_hi);
    // Quadrants 0..3: sin r, cos r, −sin r, −cos r (without branches: the quadrant is not predictable).
    let value = if quadrant & 1 == 0 { sin_r } else { cos_r };
    f64::from_bits(value.to_bits() ^ ((quadrant >> 1) << 63))
}

impl Component {
    /// The frequencies of its harmonics that are there: nonzero, of nonzero amplitude.
    pub fn frequencies(&self) -> impl Iterator<Item = f64> + '_ {
        self.harmonics.iter().filter(|h| h.frequency > 0.0 && h.amplitude != 0.0).map(|h| h.frequency)
    }

    /// Value at time `t`.
    pub fn eval(&self, t: f64) -> f64 {
        self.harmonics.iter().fold(self.bias, |acc, h| acc + h.amplitude * sin(h.frequency * t + h.phase))
    }

    /// Largest |value| over all t: |bias| + Σ|amplitude| (the supremum, approached when the
    /// frequencies are incommensurate, exact with one harmonic), or, where every frequency is a
    /// whole multiple of one base frequency, the maximum over that
    /// period: a square wave's first five odd harmonics (4/(πk) each) peak at 1.18, where the sum
    /// says 2.28, and a tail bound of 1 % of the sum passed tails of up to 1.9 % of the real peak.
    /// A harmonic of frequency 0 is the constant a·sin φ, part of the bias (`amplitude = 50,
    /// frequency = 0` is g ≡ 0, whose peak had read 50; helper tryout, 2026-12-06).
    pub fn peak(&self) -> f64 {
        self.extreme(|v| v.abs())
    }

    /// The mean over all t: the bias and the harmonics of frequency 0 (the constants a·sin φ).
    pub fn mean(&self) -> f64 {
        let still = self.harmonics.iter().filter(|h| h.frequency == 0.0);
        still.fold(self.bias, |acc, h| acc + h.amplitude * h.phase.sin())
    }

    /// (min, max) of the value over all t, as [`Component::peak`] finds its largest |value|
    /// (−∞ … ∞ bounds become the sums where the frequencies are not whole multiples of one).
    pub fn range(&self) -> (f64, f64) {
        (-self.extreme(|v| -v), self.extreme(|v| v))
    }

    /// The supremum of `of(value)` over all t, for `of` = |·|, the identity or its negation:
    /// `of(constant)` + Σ|amplitude|, or the maximum over the common period ([`Component::peak`]).
    fn extreme(&self, of: impl Fn(f64) -> f64) -> f64 {
        let moving = self.harmonics.iter().filter(|h| h.frequency != 0.0);
        let sum = moving.fold(of(self.mean()), |acc, h| acc + h.amplitude.abs());
        let active: Vec<&Harmonic> =
            self.harmonics.iter().filter(|h| h.amplitude != 0.0 && h.frequency > 0.0).collect();
        match active.len() {
            0 | 1 => sum,
            _ => self.period_peak(&active, &of).map_or(sum, |p| p.min(sum)),
        }
    }

    /// The maximum of `of(value)` over one period 2π/ω₀ where every frequency of `active` is k·ω₀
    /// for a whole k ≤ [`PEAK_MAX_INDEX`] (ω₀ = ω_min/d, d ≤ 16, each ratio whole to [`WHOLE_RATIO`]),
    /// found on 64 samples per period of the highest harmonic and refined by golden section around
    /// the largest; `None` otherwise.
    fn period_peak(&self, active: &[&Harmonic], of: &dyn Fn(f64) -> f64) -> Option<f64> {
        let lowest = active.iter().map(|h| h.frequency).fold(f64::INFINITY, f64::min);
        let whole = |x: f64| (x - x.round()).abs() <= WHOLE_RATIO * x.max(1.0);
        let base = (1..=16)
            .map(|d| lowest / f64::from(d))
            .find(|&w| active.iter().all(|h| whole(h.frequency / w) && h.frequency / w <= PEAK_MAX_INDEX))?;
        let top = active.iter().map(|h| (h.frequency / base).round()).fold(1.0, f64::max);
        let samples = (64.0 * top) as usize;
        let step = std::f64::consts::TAU / base / samples as f64;
        let at = |t: f64| of(self.eval(t));
        let best = (0..samples).map(|k| k as f64 * step).max_by(|a, b| at(*a).total_cmp(&at(*b)))?;
        // Golden section on the bracket around the best sample, where |value| is unimodal.
        let (mut lo, mut hi) = (best - step, best + step);
        let r = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..60 {
            let (a, b) = (hi - r * (hi - lo), lo + r * (hi - lo));
            if at(a) < at(b) {
                lo = a;
            } else {
                hi = b;
            }
        }
        Some(at(best).max(at(0.5 * (lo + hi))))
    }
}

/// How near a whole number a ratio of frequencies must be for [`Component::peak`] to take them as
/// harmonics of one: relative 2e-6, so frequencies written to six digits count (k·2π/24 as
/// 0.261799, 0.523599, …: their ratios are whole to 1.5e-6, and with 1e-9 the peak had been the
/// sum of amplitudes, 26 % above the true one). Two frequencies that close but not commensurate
/// drift apart by 2e-6 of a radian per radian of the higher: a tenth of a radian after 8,000 of its
/// periods.
const WHOLE_RATIO: f64 = 2e-6;

/// The highest harmonic index [`Component::peak`] samples a common period for (a component of
/// commensurate frequencies beyond it keeps the sum of amplitudes).
const PEAK_MAX_INDEX: f64 = 4096.0;

impl Signal {
    /// Checks that the signal has `expected` components (`per` says why, for the message), finite
    /// parameters, amplitudes and biases of magnitude ≤ [`MAX_ENTRY`] and frequencies ≥ 0; `key` names the signal (`reference`, `disturbance`).
    pub fn check(&self, key: &str, expected: usize, per: &str) -> Result<(), KeyError> {
        if self.len() != expected {
            return Err(KeyError::new(
                format!("{key}.components"),
                format!(
                    "expected {expected} component{} ({per}), found {}",
                    if expected == 1 { "" } else { "s" },
                    self.len()
                ),
            ));
        }
        let finite = |field: String, v: f64| match v.is_finite() {
            true => Ok(()),
            false => Err(KeyError::new(
                format!("{key}.components{field}"),
                format!("expected a finite number, found {}", crate::settings::fmt_short(v)),
            )),
        };
        // Amplitudes and biases scale the loop's states like plant entries do (the sum of a channel's,
        // their products with D, Q and the gains): bounded by the same MAX_ENTRY.
        let moderate = |field: String, v: f64| {
            moderate(&format!("{key}.components{field}"), "a magnitude", v, "the signal's units")
        };
        for (i, c) in self.components.iter().enumerate() {
            finite(format!("[{i}].bias"), c.bias)?;
            moderate(format!("[{i}].bias"), c.bias)?;
            for (j, h) in c.harmonics.iter().enumerate() {
                for (name, v) in [("amplitude", h.amplitude), ("frequency", h.frequency), ("phase", h.phase)] {
                    finite(format!("[{i}].harmonics[{j}].{name}"), v)?;
                }
                moderate(format!("[{i}].harmonics[{j}].amplitude"), h.amplitude)?;
                if h.frequency < 0.0 {
                    let key = format!("{key}.components[{i}].harmonics[{j}].frequency");
                    return Err(KeyError::new(key, negative_frequency(h.frequency)));
                }
                // At frequency 0 a harmonic is the constant a·sin(φ): with φ = 0 (a whole number of
                // π) nothing, which a reference identically 0 had passed its verification with
                // (helper tryout, 2026-12-07).
                if h.frequency == 0.0 && h.amplitude != 0.0 && (h.phase.sin()).abs() <= 1e-12 {
                    return Err(KeyError::new(
                        format!("{key}.components[{i}].harmonics[{j}].frequency"),
                        format!("found 0 with phase {}, which makes this harmonic the constant amplitude·sin(phase) = 0: give its frequency (> 0, rad per unit of the plant's time), or a constant as the component's bias", crate::settings::fmt_short(h.phase)),
                    ));
                }
            }
        }
        Ok(())
    }

    /// A linear exosystem generating the signal exactly: w' = S w, value = H w, w(0) = w0
    /// (one state per nonzero bias; two per harmonic, [sin, cos] of frequency·t + phase).
    pub fn exosystem(&self) -> (DMatrix<f64>, DMatrix<f64>, DVector<f64>) {
        let dim: usize = self.components.iter().map(|c| (c.bias != 0.0) as usize + 2 * c.harmonics.len()).sum();
        let (mut S, mut H, mut w0) = (DMatrix::zeros(dim, dim), DMatrix::zeros(self.len(), dim), DVector::zeros(dim));
        let mut at = 0;
        for (a, c) in self.components.iter().enumerate() {
            if c.bias != 0.0 {
                H[(a, at)] = c.bias;
                w0[at] = 1.0;
                at += 1;
            }
            for h in &c.harmonics {
                // d/dt [sin θ, cos θ] = ω [cos θ, −sin θ], θ = ω t + φ.
                S[(at, at + 1)] = h.frequency;
                S[(at + 1, at)] = -h.frequency;
                H[(a, at)] = h.amplitude;
                w0[at] = h.phase.sin();
                w0[at + 1] = h.phase.cos();
                at += 2;
            }
        }
        (S, H, w0)
    }

    /// Number of components.
    pub fn len(&self) -> usize {
        self.components.len()
    }

    /// True when the signal has no components.
    pub fn is_empty(&self) -> bool {
        self.components.is_empty()
    }

    /// Writes the value at `t` into `out`; allocates nothing. An `out` that is not
    /// [`Signal::len`] long is an error naming `out`.
    pub fn eval_into(&self, t: f64, out: &mut [f64]) -> Result<(), KeyError> {
        check_out(out, self.len())?;
        self.eval_into_unchecked(t, out);
        Ok(())
    }

    /// [`Signal::eval_into`] for an `out` known to be [`Signal::len`] long (the sampled loop's, every
    /// sample).
    pub(crate) fn eval_into_unchecked(&self, t: f64, out: &mut [f64]) {
        for (o, c) in out.iter_mut().zip(&self.components) {
            *o = c.eval(t);
        }
    }
}

/// `out` has `len` entries, one per component.
fn check_out(out: &[f64], len: usize) -> Result<(), KeyError> {
    match out.len() == len {
        true => Ok(()),
        false => Err(KeyError::new(
            "out",
            format!("expected {} (one per component), found {}", crate::settings::entries(len), out.len()),
        )),
    }
}

/// The message for a negative frequency ω (the scenario reader's and [`Signal::check`]'s).
pub(crate) fn negative_frequency(w: f64) -> String {
    format!("expected a frequency ≥ 0 (rad per unit of the plant's time), found {}; write a·sin(−ωt + φ) as a·sin(ωt + π − φ)", crate::settings::fmt_short(w))
}

/// Checks the reference g (one component per output) and the disturbance ω (one per column of D)
/// for `plant`.
pub(crate) fn check_signals(plant: &Plant, reference: &Signal, disturbance: &Signal) -> Result<(), KeyError> {
    let (m, k) = (plant.m(), plant.k());
    reference.check("reference", m, &format!("one per output, m = {m} columns of plant.B"))?;
    disturbance.check("disturbance", k, &format!("one per column of plant.D, k = {k}"))
}

/// The harmonics of several signals in flat arrays, so that all their sines are one vectorizable pass
/// (the closed loop evaluates g and ω at every stage of the integrator). Same values as
/// [`Signal::eval_into`].
#[derive(Debug, Clone)]
pub(crate) struct SignalBank {
    /// Per output entry.
    bias: Vec<f64>,
    /// Per harmonic: its output entry, frequency, phase and amplitude.
    entry: Vec<usize>,
    frequency: Vec<f64>,
    phase: Vec<f64>,
    amplitude: Vec<f64>,
    /// Scratch: the angles and their sines.
    angle: Vec<f64>,
    sine: Vec<f64>,
}

impl SignalBank {
    /// The components of `signals`, concatenated.
    pub(crate) fn new(signals: &[&Signal]) -> SignalBank {
        let components = || signals.iter().flat_map(|s| &s.components);
        let harmonics = || components().enumerate().flat_map(|(e, c)| c.harmonics.iter().map(move |h| (e, h)));
        let h = harmonics().count();
        SignalBank {
            bias: components().map(|c| c.bias).collect(),
            entry: harmonics().map(|(e, _)| e).collect(),
            frequency: harmonics().map(|(_, h)| h.frequency).collect(),
            phase: harmonics().map(|(_, h)| h.phase).collect(),
            amplitude: harmonics().map(|(_, h)| h.amplitude).collect(),
            angle: vec![0.0; h],
            sine: vec![0.0; h],
        }
    }

    /// Number of output entries (the signals' components together).
    pub(crate) fn len(&self) -> usize {
        self.bias.len()
    }

    /// Writes the concatenated signals at `t` into `out`, [`SignalBank::len`] long (the continuous
    /// loop's, at every stage of the integrator); allocates nothing.
    pub(crate) fn eval_into_unchecked(&mut self, t: f64, out: &mut [f64]) {
        out.copy_from_slice(&self.bias);
        for ((a, f), p) in self.angle.iter_mut().zip(&self.frequency).zip(&self.phase) {
            *a = f * t + p;
        }
        sines(&self.angle, &mut self.sine);
        for ((&e, a), s) in self.entry.iter().zip(&self.amplitude).zip(&self.sine) {
            out[e] += a * s;
        }
    }
}

with_avx2! {
    /// out_i = sin x_i ([`sin`]): the branch-free kernel over all, then `f64::sin` where it does not
    /// apply.
    fn sines(x: &[f64], out: &mut [f64]) {
        let out = &mut out[..x.len()];
        for (o, &v) in out.iter_mut().zip(x) {
            *o = sin_kernel(v);
        }
        for (o, &v) in out.iter_mut().zip(x) {
            if !in_kernel_range(v) {
                *o = v.sin();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against `f64::sin` (glibc: < 1 ulp): 200,000 points spread over |x| ≤ 1e6 on a log scale, the
    /// multiples of π/4 (quadrant edges, where the reduction is tightest) and the fallback beyond 1e6.
    /// Bound: 2 ulp of max(|sin x|, 2⁻¹⁰), i.e. a few ulps relative, and absolute near the zeros
    /// where the reduction's absolute error (~1e-16) dominates.
    #[test]
    fn sin_matches_std() {
        let check = |x: f64| {
            let (got, want) = (sin(x), x.sin());
            let ulp = f64::EPSILON * want.abs().max(2f64.powi(-10));
            assert!((got - want).abs() <= 2.0 * ulp, "sin({x:e}) = {got:e}, std {want:e}");
        };
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..200_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            let x = 10f64.powf(-8.0 + 14.0 * u) * if state & 1 == 0 { 1.0 } else { -1.0 };
            check(x.clamp(-1e6, 1e6));
        }
        for k in -4000..=4000 {
            let x = k as f64 * std::f64::consts::FRAC_PI_4;
            check(x);
            check(x.next_up());
            check(x.next_down());
        }
        for x in [0.0, -0.0, 1e6, -1e6, 1e6 + 1.0, 3e9, -1e300] {
            check(x);
        }
        assert!(sin(f64::NAN).is_nan() && sin(f64::INFINITY).is_nan());
    }

    #[test]
    fn bank_matches_each_signal() {
        // The paper's g and ω plus a signal with a phase, a bias-only component, and a harmonic
        // beyond the kernel's range at t = 1e3 (frequency 1e4): the bank gives each signal's values,
        // concatenated, to rounding (the same operations in the same order: 1e-15 relative).
        let h = |amplitude, frequency, phase| Harmonic { amplitude, frequency, phase };
        let c = |bias, harmonics| Component { bias, harmonics };
        let g = Signal { components: vec![c(0.0, vec![h(3.0, 2.0, 0.0)]), c(2.0, vec![])] };
        let w = Signal { components: vec![c(0.0, vec![h(1.0, 1.0, 0.0)]), c(1.0, vec![h(2.0, 2.0, 0.0)])] };
        let x = Signal { components: vec![c(-0.5, vec![h(0.3, 7.5, 1.2), h(1.0, 1e4, -0.4)])] };
        let mut bank = SignalBank::new(&[&g, &w, &x]);
        assert_eq!(bank.len(), 5);
        let (mut out, mut each) = ([0.0; 5], [0.0; 5]);
        for t in [0.0, 0.37, 12.5, 99.9, 1e3] {
            bank.eval_into_unchecked(t, &mut out);
            g.eval_into(t, &mut each[..2]).unwrap();
            w.eval_into(t, &mut each[2..4]).unwrap();
            x.eval_into(t, &mut each[4..]).unwrap();
            for (a, b) in out.iter().zip(&each) {
                assert!((a - b).abs() <= 1e-15 * b.abs().max(1.0), "t = {t}: {out:?} vs {each:?}");
            }
        }
    }

    #[test]
    fn the_bank_is_the_signals_concatenated() {
        let s = crate::Scenario::from_toml(crate::scenario::PAPER_EXAMPLE).unwrap();
        let mut bank = SignalBank::new(&[&s.reference, &s.disturbance]);
        let mut gw = [0.0; 4];
        bank.eval_into_unchecked(0.5, &mut gw);
        assert_eq!(gw, [3.0 * 1f64.sin(), 2.0, 0.5f64.sin(), 1.0 + 2.0 * 1f64.sin()]);
    }

    /// The peak against closed forms: sin t + sin 2t peaks where cos t + 2 cos 2t = 0, cos t =
    /// (√33 − 1)/8, at sin t (1 + 2 cos t) = 1.76017…; a square wave's first five odd harmonics
    /// 4/(πk) sin(kt) peak at 1.18233 (the Gibbs overshoot; the series summed on 2e6 points of a
    /// period in numpy); incommensurate frequencies (1 and √2) keep the sum, as
    /// does one harmonic with a bias.
    #[test]
    #[allow(clippy::approx_constant)] // π/6, π/4, π/3 written to six digits, as users write them
    fn the_peak_is_the_largest_value_over_all_t() {
        let h = |amplitude: f64, frequency: f64| Harmonic { amplitude, frequency, phase: 0.0 };
        let c = (33f64.sqrt() - 1.0) / 8.0;
        let exact = (1.0 - c * c).sqrt() * (1.0 + 2.0 * c);
        let two = Component { bias: 0.0, harmonics: vec![h(1.0, 1.0), h(1.0, 2.0)] };
        assert!((two.peak() - exact).abs() < 1e-12, "{} against {exact}", two.peak());
        // The same scaled in time (0.02 and 0.04 rad/min): the same peak.
        let slow = Component { bias: 0.0, harmonics: vec![h(1.0, 0.02), h(1.0, 0.04)] };
        assert!((slow.peak() - exact).abs() < 1e-12, "{}", slow.peak());
        let square = Component {
            bias: 0.0,
            harmonics: (0..5)
                .map(|k| h(4.0 / (std::f64::consts::PI * (2 * k + 1) as f64), (2 * k + 1) as f64))
                .collect(),
        };
        assert!((square.peak() - 1.18233).abs() < 1e-5, "{}", square.peak());
        let apart = Component { bias: 0.0, harmonics: vec![h(1.0, 1.0), h(1.0, 2f64.sqrt())] };
        assert_eq!(apart.peak(), 2.0);
        let one = Component { bias: -1.0, harmonics: vec![h(0.5, 3.0)] };
        assert_eq!(one.peak(), 1.5);
        // A harmonic of frequency 0 is the constant a·sin φ: 50 sin 0 is nothing, 50 sin(π/2) and a
        // bias of −10 are 40, and a moving harmonic adds its amplitude.
        let still = |phase: f64| Harmonic { amplitude: 50.0, frequency: 0.0, phase };
        assert_eq!(Component { bias: 0.0, harmonics: vec![still(0.0)] }.peak(), 0.0);
        let half_pi = std::f64::consts::FRAC_PI_2;
        assert_eq!(Component { bias: -10.0, harmonics: vec![still(half_pi)] }.peak(), 40.0);
        assert_eq!(Component { bias: -10.0, harmonics: vec![still(half_pi), h(2.0, 1.0)] }.peak(), 42.0);
        // Harmonics of 2π/24 written to six decimals: their common period's peak, not the sum 3.5
        // (the largest of 1 + 1.5 sin t + 0.5 sin 2t + 0.3 sin 3t + 0.2 sin 4t, by the derivative's
        // roots in SciPy: 2.785963).
        let rounded = Component {
            bias: 1.0,
            harmonics: vec![h(1.5, 0.261799), h(0.5, 0.523599), h(0.3, 0.785398), h(0.2, 1.047198)],
        };
        assert!((rounded.peak() - 2.785963).abs() < 1e-5, "{}", rounded.peak());
    }

    /// The range's ends against independent answers: one harmonic about a bias is bias ± a; the
    /// four harmonics of 2π/24 about 1 reach −0.785973 (SciPy's `minimize_scalar` from the lowest
    /// of 4e6 samples of a period) and 2.785963; sin t + sin 2t is odd, so ± its peak; the ends of
    /// incommensurate frequencies are the sums.
    #[test]
    #[allow(clippy::approx_constant)] // π/6, π/4, π/3 written to six digits, as users write them
    fn the_range_holds_the_lowest_and_the_highest_value() {
        let h = |amplitude: f64, frequency: f64| Harmonic { amplitude, frequency, phase: 0.0 };
        assert_eq!(Component { bias: -1.0, harmonics: vec![h(0.5, 3.0)] }.range(), (-1.5, -0.5));
        let rounded = Component {
            bias: 1.0,
            harmonics: vec![h(1.5, 0.261799), h(0.5, 0.523599), h(0.3, 0.785398), h(0.2, 1.047198)],
        };
        let (lo, hi) = rounded.range();
        assert!((lo + 0.785973).abs() < 1e-5 && (hi - 2.785963).abs() < 1e-5, "{lo} {hi}");
        let two = Component { bias: 0.0, harmonics: vec![h(1.0, 1.0), h(1.0, 2.0)] };
        let (lo, hi) = two.range();
        assert!((lo + two.peak()).abs() < 1e-12 && (hi - two.peak()).abs() < 1e-12, "{lo} {hi}");
        let apart = Component { bias: 0.5, harmonics: vec![h(1.0, 1.0), h(1.0, 2f64.sqrt())] };
        assert_eq!(apart.range(), (-1.5, 2.5));
    }
}
