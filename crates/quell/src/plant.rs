//! The plant (1): ẋ = A x + B u_f + D ω(t), y = C x + Q ω(t), driven through the decoupling law (5)
//! u_f = −K x̂ + F u_d with u_d,i(t) = u_i(t − τ_i): the delays τ_i act on the adaptive command u only,
//! the feedback −K x̂ acts without delay. A delay or a limit on the whole u_f is a different plant,
//! simulated with `[truth]`'s actuator ([`crate::settings::Actuator`]).

use nalgebra::{DMatrix, DVector};
use thiserror::Error;

use crate::settings::TimeUnit;

/// Largest magnitude of a plant entry. The design forms products of two entries summed over n
/// terms (A², c_i A B, A − BK) and squared Frobenius norms (the rank tests' tolerances); with every
/// entry at most 1e150 these stay below n·1e300, finite for any n < 1e8 (f64::MAX ≈ 1.8e308).
pub const MAX_ENTRY: f64 = 1e150;

/// A plant checked for consistent shapes, finite entries of magnitude ≤ [`MAX_ENTRY`] and
/// non-negative delays.
#[derive(Debug, Clone, PartialEq)]
pub struct Plant {
    /// State matrix, n×n.
    pub A: DMatrix<f64>,
    /// Input matrix, n×m.
    pub B: DMatrix<f64>,
    /// Output matrix, m×n.
    pub C: DMatrix<f64>,
    /// Disturbance-to-state matrix, n×k.
    pub D: DMatrix<f64>,
    /// Disturbance-to-output matrix, m×k (used only by the simulated plant).
    pub Q: DMatrix<f64>,
    /// Delays τ_i ≥ 0 of the adaptive command, one per channel: u_d,i(t) = u_i(t − τ_i) in (5).
    pub delays: Vec<f64>,
    /// Initial state x(0).
    pub x0: DVector<f64>,
    /// The controller's initial estimate x̂(0) of it, the observer's state (6) at t = 0 and after a
    /// reset (`plant.xhat0`; 0 unless given): a plant that starts away from 0 is otherwise met by
    /// an observer that starts at 0.
    pub xhat0: DVector<f64>,
    /// The unit of time A, the delays and every time and frequency of a run are in: a label
    /// ([`TimeUnit`]); seconds unless given.
    pub time_unit: TimeUnit,
}

/// Why a set of matrices is not a plant. `name` is the matrix's name (`"A"`, `"B"`, …).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PlantError {
    #[error("{name}: expected a {expected_rows}×{expected_cols} matrix, found {rows}×{cols}")]
    Shape { name: &'static str, expected_rows: usize, expected_cols: usize, rows: usize, cols: usize },
    #[error("{name}[{row}][{col}]: expected a finite number, found {}", crate::settings::fmt_short(*.value))]
    NonFinite { name: &'static str, row: usize, col: usize, value: f64 },
    #[error(
        "{name}[{row}][{col}]: expected a magnitude ≤ {max:e}, found {value:e}; products and norms of such \
         entries overflow double precision — rescale the plant's units",
        max = MAX_ENTRY
    )]
    TooLarge { name: &'static str, row: usize, col: usize, value: f64 },
    #[error("delays[{index}]: expected a finite delay ≥ 0, found {}", crate::settings::fmt_short(*.value))]
    BadDelay { index: usize, value: f64 },
    #[error("{name}: expected {} (one per {per}), found {found}", crate::settings::entries(*.expected))]
    Length { name: &'static str, per: &'static str, expected: usize, found: usize },
    #[error("A: the plant needs at least one state, input and output (n, m ≥ 1); found n = {n}, m = {m}")]
    Empty { n: usize, m: usize },
}

impl PlantError {
    /// The error as (key, message) for a plant of `n` states, `m` channels and `k` disturbance
    /// components, its matrices named with `prefix` (`"plant."` in a scenario, `""` for a
    /// program's arguments): a wrong shape names what n, m and k were taken from.
    pub fn explained(&self, (n, m, k): (usize, usize, usize), prefix: &str) -> (String, String) {
        let entry = |name: &str, row: usize, col: usize| {
            if name == "x0" || name == "xhat0" {
                format!("{prefix}{name}[{row}]")
            } else {
                format!("{prefix}{name}[{row}][{col}]")
            }
        };
        match *self {
            PlantError::Shape { name, expected_rows, expected_cols, rows, cols } => {
                shape_message(name, (expected_rows, expected_cols), (rows, cols), (n, m, k), prefix)
            }
            PlantError::NonFinite { name, row, col, value } => (
                entry(name, row, col),
                format!("expected a finite number, found {}", crate::settings::fmt_short(value)),
            ),
            PlantError::TooLarge { name, row, col, .. } => {
                let full = self.to_string();
                (entry(name, row, col), full.split_once(": ").map_or(full.as_str(), |(_, m)| m).to_string())
            }
            PlantError::BadDelay { index, value } => (
                format!("{prefix}delays[{index}]"),
                format!("expected a finite delay ≥ 0, found {}", crate::settings::fmt_short(value)),
            ),
            PlantError::Length { name, per, expected, found } => {
                let of = if name == "x0" || name == "xhat0" {
                    format!("n = {n} rows of {prefix}A")
                } else {
                    format!("m = {m} columns of {prefix}B")
                };
                (
                    format!("{prefix}{name}"),
                    format!("expected {} (one per {per}, {of}), found {found}", crate::settings::entries(expected)),
                )
            }
            PlantError::Empty { n, m } => (
                format!("{prefix}{}", if n == 0 { "A" } else { "B" }),
                format!("the plant needs at least one state, input and output (n, m ≥ 1); found n = {n}, m = {m}"),
            ),
        }
    }
}

/// [`PlantError::Shape`] as (key, message): what n, m and k were taken from, and a transpose that
/// would fit.
fn shape_message(
    name: &str,
    (expected_rows, expected_cols): (usize, usize),
    (rows, cols): (usize, usize),
    (n, m, k): (usize, usize, usize),
    prefix: &str,
) -> (String, String) {
    let (dims, symbols): (&str, &[char]) = match name {
        "A" => ("n×n", &[]),
        "B" => ("n×m", &['n']),
        "C" => ("m×n", &['m', 'n']),
        "D" => ("n×k", &['n']),
        "Q" => ("m×k", &['m', 'k']),
        _ => ("", &[]),
    };
    let defs: Vec<String> = symbols
        .iter()
        .map(|s| match s {
            'n' => format!("n = {n} (rows of {prefix}A)"),
            'm' => format!("m = {m} (columns of {prefix}B)"),
            _ => format!("k = {k} (columns of {prefix}D)"),
        })
        .collect();
    // A matrix written with its rows as columns (one row per input of B): its transpose
    // fits (for B and D, whose columns set m and k, any transpose with n rows does).
    let own_columns = matches!(name, "B" | "D");
    let transposed =
        name != "A" && rows != expected_rows && cols == expected_rows && (own_columns || rows == expected_cols);
    // C with a different number of outputs than B has inputs: the method pairs them.
    let square = if name == "C" && rows != expected_rows && !transposed {
        "; the method decouples the plant into one channel per input, so it needs as many outputs as inputs (a square plant): choose m outputs to track, or add inputs"
    } else {
        ""
    };
    // B's columns set m and D's set k: with its rows wrong, only n is known independently.
    let rows_only = own_columns && rows != expected_rows;
    let (expected, hint) = if rows_only {
        (format!("{expected_rows} rows (n = {n}, the rows of {prefix}A)"), String::new())
    } else if name == "A" {
        (format!("{expected_rows}×{expected_cols} ({dims})"), "; A must be square".to_string())
    } else {
        (format!("{expected_rows}×{expected_cols} ({dims})"), format!("; {}{square}", defs.join(", ")))
    };
    let transposed =
        if transposed { format!("; it looks transposed: write it as {cols}×{rows}") } else { String::new() };
    (format!("{prefix}{name}"), format!("expected {expected}, found {rows}×{cols}{hint}{transposed}"))
}

/// `M` is `rows × cols`.
pub(crate) fn check_shape(name: &'static str, M: &DMatrix<f64>, rows: usize, cols: usize) -> Result<(), PlantError> {
    if M.nrows() != rows || M.ncols() != cols {
        return Err(PlantError::Shape {
            name,
            expected_rows: rows,
            expected_cols: cols,
            rows: M.nrows(),
            cols: M.ncols(),
        });
    }
    Ok(())
}

/// Every entry of `M` is finite and of magnitude ≤ [`MAX_ENTRY`]; the first offending entry in
/// row-major order is reported.
pub(crate) fn check_entries(name: &'static str, M: &DMatrix<f64>) -> Result<(), PlantError> {
    for r in 0..M.nrows() {
        for c in 0..M.ncols() {
            let value = M[(r, c)];
            if !value.is_finite() {
                return Err(PlantError::NonFinite { name, row: r, col: c, value });
            }
            if value.abs() > MAX_ENTRY {
                return Err(PlantError::TooLarge { name, row: r, col: c, value });
            }
        }
    }
    Ok(())
}

/// Shape, then entries.
pub(crate) fn check(name: &'static str, M: &DMatrix<f64>, rows: usize, cols: usize) -> Result<(), PlantError> {
    check_shape(name, M, rows, cols)?;
    check_entries(name, M)
}

impl Plant {
    /// This true plant's delays where they differ from the design `model`'s; none where they are
    /// the same (the delays a run adds to the model's).
    pub(crate) fn delays_beside(&self, model: &Plant) -> &[f64] {
        if self.delays == model.delays {
            &[]
        } else {
            &self.delays
        }
    }

    /// Builds a plant, checking every shape against n = rows(A), m = cols(B), k = cols(D).
    /// `x0 = None` means x(0) = 0.
    pub fn new(
        A: DMatrix<f64>,
        B: DMatrix<f64>,
        C: DMatrix<f64>,
        D: DMatrix<f64>,
        Q: DMatrix<f64>,
        delays: Vec<f64>,
        x0: Option<DVector<f64>>,
    ) -> Result<Self, PlantError> {
        let x0 = x0.unwrap_or_else(|| DVector::zeros(A.nrows()));
        let xhat0 = DVector::zeros(A.nrows());
        let plant = Plant { A, B, C, D, Q, delays, x0, xhat0, time_unit: TimeUnit::default() };
        plant.validate()?;
        Ok(plant)
    }

    /// The plant with the controller's initial estimate `xhat0` of its state (`None`: 0), checked as
    /// x0 is.
    pub fn with_xhat0(mut self, xhat0: Option<DVector<f64>>) -> Result<Self, PlantError> {
        if let Some(x) = xhat0 {
            self.xhat0 = x;
            self.validate()?;
        }
        Ok(self)
    }

    /// The plant with its unit of time `unit` (a label: nothing is rescaled).
    pub fn with_time_unit(mut self, unit: TimeUnit) -> Self {
        self.time_unit = unit;
        self
    }

    /// The checks of [`Plant::new`], for a plant built field by field (the fields are public).
    pub fn validate(&self) -> Result<(), PlantError> {
        let (n, m, k) = (self.A.nrows(), self.B.ncols(), self.D.ncols());
        if n == 0 || m == 0 {
            return Err(PlantError::Empty { n, m });
        }
        check("A", &self.A, n, n)?;
        check("B", &self.B, n, m)?;
        check("C", &self.C, m, n)?;
        check("D", &self.D, n, k)?;
        check("Q", &self.Q, m, k)?;
        if self.delays.len() != m {
            return Err(PlantError::Length { name: "delays", per: "input", expected: m, found: self.delays.len() });
        }
        if let Some((index, &value)) = self.delays.iter().enumerate().find(|(_, d)| !(d.is_finite() && **d >= 0.0)) {
            return Err(PlantError::BadDelay { index, value });
        }
        for (name, x) in [("x0", &self.x0), ("xhat0", &self.xhat0)] {
            if x.len() != n {
                return Err(PlantError::Length { name, per: "state", expected: n, found: x.len() });
            }
            check(name, &DMatrix::from_column_slice(n, 1, x.as_slice()), n, 1)?;
        }
        Ok(())
    }

    /// State dimension n.
    pub fn n(&self) -> usize {
        self.A.nrows()
    }
    /// Number of inputs = outputs = channels m.
    pub fn m(&self) -> usize {
        self.B.ncols()
    }
    /// Number of disturbance components k.
    pub fn k(&self) -> usize {
        self.D.ncols()
    }
}
