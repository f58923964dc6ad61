//! Assumptions 2 and 3: each reference or disturbance component is the output of an exosystem, and
//! its internal-model filter needs at least as many poles as that exosystem has states.

use nalgebra::Complex;

use crate::signal::Component;

/// The exosystem of one component: distinct nonzero harmonics and whether there is a constant part.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Exosystem {
    /// Distinct positive frequencies whose summed harmonics do not cancel.
    pub harmonics: usize,
    /// A nonzero constant part (bias plus any zero-frequency harmonics).
    pub constant: bool,
}

impl Exosystem {
    /// The exosystem of `c`: 2 states per distinct positive frequency with nonzero amplitude, 1 for
    /// a nonzero constant. Harmonics at one frequency are summed as phasors, so
    /// sin t − sin t counts as nothing; a sum is zero when it is below 1e-12 of the amplitudes in it.
    pub fn of(c: &Component) -> Exosystem {
        // Constant part: bias + Σ a sin(φ) over zero-frequency harmonics.
        let (mut constant, mut scale) = (c.bias, c.bias.abs());
        // Per frequency (its bits: ±0 are taken apart above) the phasor sum and the amplitudes'; a
        // map, not a search of the groups: 480,000 harmonics had taken minutes.
        let mut groups: std::collections::HashMap<u64, (Complex<f64>, f64)> = Default::default();
        for h in &c.harmonics {
            if h.frequency == 0.0 {
                constant += h.amplitude * h.phase.sin();
                scale += h.amplitude.abs();
                continue;
            }
            let g = groups.entry(h.frequency.to_bits()).or_default();
            g.0 += Complex::from_polar(h.amplitude, h.phase);
            g.1 += h.amplitude.abs();
        }
        let nonzero = |value: f64, scale: f64| value.abs() > 1e-12 * scale;
        Exosystem {
            harmonics: groups.values().filter(|(p, s)| nonzero(p.norm(), *s)).count(),
            constant: nonzero(constant, scale),
        }
    }

    /// The exosystem's dimension: the least internal-model order that can reproduce the component.
    pub fn dim(&self) -> usize {
        2 * self.harmonics + usize::from(self.constant)
    }

    /// "2 harmonics + bias", "1 harmonic", "bias", "zero".
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        match self.harmonics {
            0 => {}
            1 => parts.push("1 harmonic".to_string()),
            h => parts.push(format!("{h} harmonics")),
        }
        if self.constant {
            parts.push("bias".to_string());
        }
        if parts.is_empty() {
            "zero".to_string()
        } else {
            parts.join(" + ")
        }
    }
}
