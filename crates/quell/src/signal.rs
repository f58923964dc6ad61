//! Multi-harmonic signals: each component is `bias + Σ amplitude·sin(frequency·t + phase)`.
//! They model the reference g(t) (Assumption 2) and the disturbance ω(t) (Assumption 3).

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
        self.harmonics.iter().fold(self.bias, |acc, h| {
            acc + h.amplitude * (h.frequency * t + h.phase).sin()
        })
    }

    /// Largest possible |value|: |bias| + Σ|amplitude|.
    pub fn peak(&self) -> f64 {
        self.harmonics
            .iter()
            .fold(self.bias.abs(), |acc, h| acc + h.amplitude.abs())
    }
}

impl Signal {
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
