//! Seeded measurement noise: white Gaussian samples (SplitMix64 with the Box–Muller transform), so
//! runs are reproducible without a random-number dependency, and band-limited noise as a sum of
//! random-phase sines that both loops evaluate at any t.

use crate::hash::{mix64, GOLDEN_GAMMA};
use crate::settings::MeasurementNoise;
use crate::signal::{Component, Harmonic, Signal};

/// Sines per output of the band-limited noise: enough for a near-Gaussian amplitude distribution
/// (the sum of 64 independent random-phase sines has excess kurtosis −1.5/64 ≈ −0.02).
pub const NOISE_SINES: usize = 64;

/// Band-limited noise n(t) with the standard deviations of `noise`, `None` without a bandwidth:
/// per output, [`NOISE_SINES`] sines with frequencies uniform on (0, bandwidth] cycles per unit of
/// time (Hz for a plant in seconds) and phases uniform
/// on [0, 2π) drawn from the seed, each of amplitude std·√(2/N), so the mean square over time is
/// std² and the spectrum is empty above the bandwidth (random-phase multisine; Pintelon &
/// Schoukens, *System Identification*, 2nd ed., Sec. 2.4). Output i draws from seed + i.
pub fn band_limited(noise: &MeasurementNoise) -> Option<Signal> {
    let bandwidth = noise.bandwidth?;
    let w_max = 2.0 * std::f64::consts::PI * bandwidth;
    let amplitude = (2.0 / NOISE_SINES as f64).sqrt();
    let components = noise
        .std
        .iter()
        .enumerate()
        .map(|(i, &std)| {
            let mut rng = Gaussian::new(noise.seed.wrapping_add(i as u64));
            let harmonics = (0..NOISE_SINES)
                .map(|_| Harmonic {
                    amplitude: std * amplitude,
                    frequency: w_max * rng.uniform(),
                    phase: 2.0 * std::f64::consts::PI * rng.uniform(),
                })
                .collect();
            Component { bias: 0.0, harmonics }
        })
        .collect();
    Some(Signal { components })
}

/// A reproducible stream of standard normal samples.
#[derive(Debug, Clone)]
pub(crate) struct Gaussian {
    state: u64,
    spare: Option<f64>,
}

impl Gaussian {
    /// A stream from `seed`.
    pub(crate) fn new(seed: u64) -> Self {
        Gaussian { state: seed, spare: None }
    }

    /// SplitMix64 (Steele, Lea, Flood 2014): 64 random bits.
    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN_GAMMA);
        mix64(self.state)
    }

    /// Uniform on (0, 1].
    pub(crate) fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// One N(0, 1) sample.
    pub(crate) fn sample(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let r = (-2.0 * u1.ln()).sqrt();
        let theta = 2.0 * std::f64::consts::PI * u2;
        self.spare = Some(r * theta.sin());
        r * theta.cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moments_match_standard_normal() {
        // Sample mean and variance of 200,000 draws: standard errors 1/√N ≈ 0.0022 and √(2/N) ≈ 0.0032;
        // bounds of 5 standard errors.
        let mut g = Gaussian::new(7);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| g.sample()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.011, "mean {mean}");
        assert!((var - 1.0).abs() < 0.016, "variance {var}");
        assert_ne!(Gaussian::new(1).sample(), Gaussian::new(2).sample());
    }

    /// The stream is SplitMix64's: from seed 0 its published first outputs (Vigna's
    /// `splitmix64.c`), so noise drawn from a seed stays the same.
    #[test]
    fn the_stream_is_splitmix64() {
        let mut g = Gaussian::new(0);
        assert_eq!(
            [g.next_u64(), g.next_u64(), g.next_u64()],
            [0xe220_a839_7b1d_cdaf, 0x6e78_9e6a_a1b9_65f4, 0x06c4_5d18_8009_454f]
        );
    }
}
