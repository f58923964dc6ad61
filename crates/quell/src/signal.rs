//! Multi-harmonic signals: each component is `bias + Σ amplitude·sin(frequency·t + phase)`.
//! They model the reference g(t) (Assumption 2) and the disturbance ω(t) (Assumption 3).

use nalgebra::{DMatrix, DVector};

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

impl Component {
    /// Value at time `t`.
    pub fn eval(&self, t: f64) -> f64 {
        self.harmonics.iter().fold(self.bias, |acc, h| acc + h.amplitude * (h.frequency * t + h.phase).sin())
    }

    /// Largest possible |value|: |bias| + Σ|amplitude|.
    pub fn peak(&self) -> f64 {
        self.harmonics.iter().fold(self.bias.abs(), |acc, h| acc + h.amplitude.abs())
    }
}

impl Signal {
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

    /// Writes the value at `t` into `out` (length [`Signal::len`]); allocates nothing.
    pub fn eval_into(&self, t: f64, out: &mut [f64]) {
        for (o, c) in out.iter_mut().zip(&self.components) {
            *o = c.eval(t);
        }
    }
}
