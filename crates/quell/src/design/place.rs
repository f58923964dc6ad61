//! MIMO pole placement: K such that eig(A − B K) equals the requested poles.
//! STUB: owned by the pole-placement helper.

use nalgebra::{Complex, DMatrix};
use thiserror::Error;

/// Why no gain was returned.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PlaceError {
    #[error("(A, B) is not controllable: numerical rank of the controllability staircase is {rank}, need {n}")]
    Uncontrollable { rank: usize, n: usize },
    #[error("expected {expected} poles (one per state), got {found}")]
    WrongCount { expected: usize, found: usize },
    #[error("pole {pole} has no complex-conjugate partner in the list; complex poles come in conjugate pairs")]
    NotConjugateClosed { pole: Complex<f64> },
    #[error("pole {pole} is requested {multiplicity} times, but rank(B) = {max} allows at most {max}")]
    Multiplicity { pole: Complex<f64>, multiplicity: usize, max: usize },
    #[error("pole {pole} is not a finite number")]
    NonFinite { pole: Complex<f64> },
}

/// Pole placement like MATLAB's and python-control's `place`.
pub fn place(A: &DMatrix<f64>, B: &DMatrix<f64>, poles: &[Complex<f64>]) -> Result<DMatrix<f64>, PlaceError> {
    let _ = (A, B, poles);
    todo!("pole placement")
}
