//! C code generation: the real-time [`Controller`] as dependency-free C99 for microcontrollers and
//! PLCs (`quell export`; docs/deployment.md).
//!
//! [`generate`] discretizes the design exactly as [`Controller::new`] does (it builds that
//! controller and reads its matrices, so the validation and the numbers are the same) and writes
//! `<prefix>_controller.h` and `<prefix>_controller.c`: every matrix a `static const` array, the
//! state one struct of fixed-size arrays, no dynamic memory, no libm, no global mutable state. The
//! step performs the arithmetic of [`Controller::step`] in the same order, so in `double` on a
//! machine without fused multiply-adds in its C code (x86-64; C99 forbids contracting across
//! statements, and `-std=c99` turns gcc's contraction off) the two give the same bits.

mod c;
mod fmu;

pub use fmu::{earlier_fmu_warning, generate_fmu, time_unit_warning, FmiVersion, Fmu};

use thiserror::Error;

use crate::controller::{Controller, ControllerError};
use crate::design::Design;
use crate::settings::TimeUnit;

pub use crate::controller::Precision;

impl Precision {
    /// The C type.
    pub fn c_type(self) -> &'static str {
        match self {
            Precision::F64 => "double",
            Precision::F32 => "float",
        }
    }
    /// Bytes of one number.
    pub fn bytes(self) -> usize {
        match self {
            Precision::F64 => 8,
            Precision::F32 => 4,
        }
    }
}

impl std::str::FromStr for Precision {
    type Err = ExportError;
    fn from_str(s: &str) -> Result<Precision, ExportError> {
        Precision::from_name(s).ok_or_else(|| ExportError::Precision { found: s.to_string() })
    }
}

/// What to generate besides the controller itself.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExportOptions {
    /// Prefix of every name (`<prefix>_step`, `<PREFIX>_M`, the files), so that several
    /// controllers can live in one firmware. A C identifier.
    pub prefix: String,
    pub precision: Precision,
    /// The scenario's name, for the header comment.
    pub scenario_name: Option<String>,
    /// The plant's signal names (`[plant]` `inputs`, `outputs`), for the FMU variables'
    /// descriptions; the variables keep their names `y[i]`, `u_f[i]`, … whatever they are.
    pub names: crate::scenario::SignalNames,
}

/// What T_s is measured in, as the generated comments say it: "the plant model's unit of time",
/// with the unit's name first when the plant gives one other than seconds.
fn time_unit_text(design: &Design) -> String {
    format!("{}, the plant model's unit of time", design.plant().time_unit.name())
}

impl Default for ExportOptions {
    fn default() -> Self {
        ExportOptions {
            prefix: "quell".to_string(),
            precision: Precision::F64,
            scenario_name: None,
            names: Default::default(),
        }
    }
}

/// The generated header and source, and their memory figures.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CCode {
    /// `<prefix>_controller.h` and its text.
    pub header_name: String,
    pub header: String,
    /// `<prefix>_controller.c` and its text.
    pub source_name: String,
    pub source: String,
    /// Bytes of the `static const` data (flash).
    pub constant_bytes: usize,
    /// `sizeof(<prefix>_state)` (RAM), where a number is aligned to its size.
    pub state_bytes: usize,
    /// The caution of [`precision_warning`] for this design and precision.
    pub precision_warning: Option<String>,
}

/// Above this many bytes of state (RAM) or constants (flash) an export is warned about
/// ([`CCode::size_warning`]): 1 MiB, more than most microcontrollers have.
pub const LARGE_EXPORT_BYTES: usize = 1 << 20;

impl CCode {
    /// Every caution on this export: its size ([`CCode::size_warning`]) and its precision
    /// ([`precision_warning`]).
    pub fn warnings(&self) -> impl Iterator<Item = String> {
        [self.size_warning(), self.precision_warning.clone()].into_iter().flatten()
    }

    /// A warning when the controller needs more than [`LARGE_EXPORT_BYTES`] of RAM or of flash:
    /// its state is mostly the delay lines, τ_i/T_s past samples each, so a delay given in the
    /// wrong unit or a very short sample time shows here first.
    pub fn size_warning(&self) -> Option<String> {
        let mb = |bytes: usize| bytes as f64 / (1u64 << 20) as f64;
        (self.state_bytes > LARGE_EXPORT_BYTES || self.constant_bytes > LARGE_EXPORT_BYTES).then(|| {
            format!(
                "the controller needs {:.1} MiB of RAM (its state, mostly the delay lines of τ_i/T_s past samples each) and {:.1} MiB of flash (its constants), more than most embedded targets have; a longer sample time shrinks the delay lines in proportion (or check the unit of plant.delays)",
                mb(self.state_bytes),
                mb(self.constant_bytes)
            )
        })
    }
}

/// The relative move of the closed loop's poles, κ₂·ε with ε float's rounding, above which an f32
/// export is cautioned ([`precision_warning`]): 1 %.
pub const F32_POLE_SHIFT: f64 = 1e-2;

/// For an f32 export, the caution that rounding the controller's matrices to float (ε = 6e-8) can
/// move the observer's or the decoupled channels' poles by κ₂·ε of themselves, κ₂ the larger
/// eigenvector condition number of A − LC and A − BK, where that exceeds [`F32_POLE_SHIFT`]: a
/// disk servo's observer (κ₂ = 2.75e6) gave a u_f 18 % of its peak away from the f64 export's
/// (y within 7e-5); the paper's example (κ₂ 27) stays within 2e-5. `None` for f64.
pub fn precision_warning(design: &Design, precision: Precision) -> Option<String> {
    if precision != Precision::F32 {
        return None;
    }
    let PoleShift { shift, kappa, what, .. } = f32_pole_shift(design);
    (shift > F32_POLE_SHIFT).then(|| {
        format!(
            "precision: f32 rounds the controller's matrices to about 6e-8, and {what} has eigenvector condition number κ₂ = {kappa:.2e}, so its poles can move by about κ₂·6e-8 = {} of themselves (a disk servo's f32 u_f departed 18 % of its peak from the f64 export's at κ₂ = 2.75e6); export f64, or choose poles nearer the plant's own (a smaller κ₂); a sampled run at simulation.precision = \"f32\" measures how far the loop departs",
            fmt_shift(shift)
        )
    })
}

/// How far f32's rounding (ε/2 = 6e-8) can move the design's poles, relative to themselves:
/// κ₂·6e-8 for the larger eigenvector condition number κ₂ of A − LC and A − BK (∞ for a defective
/// one), with κ₂, the same matrix's equilibrated κ₂ and which matrix it is ([`PoleShift`]).
///
/// κ₂ here is taken in the states' coordinates as given, not equilibrated as the design's
/// fragility measures are: a heuristic, kept because it cautions the designs whose f32 export was
/// measured to depart (the disk servo, κ₂ 2.75e6: u_f 15 % of its peak off f64's; the magnetic
/// bearing, 3.9e7: 92 %) and not the paper's (27: 2e-5). f32's rounding itself is the same in any
/// diagonal scaling of the states (the disk servo's departure stayed 13–18 % while this κ₂ spread
/// from 3.0e5 to 2.5e9), and the equilibrated κ₂ (7.2e4 and 114 for those two) does not predict it:
/// the mechanism is not the poles' conditioning alone.
pub fn f32_pole_shift(design: &Design) -> PoleShift {
    let (p, (L, K)) = (design.plant(), (design.L(), design.K()));
    let parts = [
        (
            crate::design::place::closed_loop_condition(&p.A.transpose(), &p.C.transpose(), &L.transpose()),
            design.observer_eigenvector_condition(),
            "A − LC (the observer)",
        ),
        (
            crate::design::place::closed_loop_condition(&p.A, &p.B, K),
            design.decoupled_eigenvector_condition(),
            "A − BK (the decoupled channels)",
        ),
    ];
    // A NaN κ₂ (a defective eigenvector matrix) counts as infinite.
    let worst = |k: f64| if k.is_nan() { f64::INFINITY } else { k };
    let [a, b] = parts;
    let (kappa, scale_free, what) = if worst(a.0) >= worst(b.0) { a } else { b };
    PoleShift { shift: worst(kappa) * f64::from(f32::EPSILON) / 2.0, kappa, scale_free, what }
}

/// [`f32_pole_shift`]'s answer: the relative shift κ₂·6e-8, κ₂ as given, the same matrix's
/// equilibrated κ₂ ([`Design::observer_eigenvector_condition`]: ∞ only for a defective one, in any
/// units of the states), and which matrix it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoleShift {
    pub shift: f64,
    pub kappa: f64,
    pub scale_free: f64,
    pub what: &'static str,
}

/// A relative pole shift as "92 %", "1.5×" or "1.3e5×" ("∞" for a defective eigenvector matrix;
/// "134837.8×" had been printed).
pub fn fmt_shift(shift: f64) -> String {
    if !shift.is_finite() {
        "∞".to_string()
    } else if shift >= 10.0 {
        let v = crate::settings::significant(shift, 2);
        if v >= 1e4 {
            format!("{v:e}×")
        } else {
            format!("{v}×")
        }
    } else if shift >= 1.0 {
        format!("{shift:.1}×")
    } else if shift >= 0.01 {
        format!("{:.0} %", 100.0 * shift)
    } else {
        format!("{} %", crate::settings::fmt_short(crate::settings::significant(100.0 * shift, 2)))
    }
}

/// Longest `prefix`: `<prefix>_controller.h` must fit a file name (255 bytes on common file
/// systems) with room for its temporary name while it is written.
pub const MAX_PREFIX: usize = 200;

/// Why no C code can be generated.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ExportError {
    /// The controller cannot run at this sample time (the checks of [`Controller::new`]).
    #[error(transparent)]
    Controller(#[from] ControllerError),
    #[error("prefix: expected a C identifier (a letter, then letters, digits or _), found {found:?}; e.g. motor1")]
    Prefix { found: String },
    #[error("prefix: expected at most {MAX_PREFIX} characters, found {length}; the file names <prefix>_controller.h/.c must fit the file system's 255 bytes")]
    PrefixLength { length: usize },
    #[error("precision: expected f64 or f32, found {found:?}")]
    Precision { found: String },
    #[error("simulation.sample_time: {what} is {value} after discretizing at T_s = {sample_time} {unit}; the exact discretization overflowed (the design's eigenvalues times T_s are beyond floating point); choose a shorter sample time or poles of smaller magnitude")]
    NotFinite { what: String, value: f64, sample_time: f64, unit: TimeUnit },
    #[error("precision f32: {what} = {value:e} is beyond the range of float (±3.4e38); use f64")]
    F32Range { what: String, value: f64 },
    #[error("fmi_version: expected 2 or 3, found {found:?}")]
    FmiVersion { found: String },
    #[error("compiler {compiler:?}: {message}")]
    Compiler { compiler: String, message: String },
    /// The compiler named cannot be started (not found, not executable): bad input, where
    /// `Compiler` is a compiler that ran and failed.
    #[error("compiler {compiler:?}: cannot run it ({message}); install a C compiler or name one (\"none\" writes the FMU with its sources only)")]
    CompilerNotFound { compiler: String, message: String },
    #[error("writing the FMU archive failed: {message}")]
    Archive { message: String },
    /// The stop flag ([`crate::cancel::with_stop`]) was set while the compiler ran: it was stopped
    /// with the processes it started.
    #[error("interrupted while the compiler built the FMU; it was stopped and nothing was written")]
    Interrupted,
}

/// The compiler an FMU build runs: `given` (the front end's choice), else `$CC` when set and not
/// blank, else `cc`; `None` for "none" (the FMU with its sources only). The second value says
/// whether it came from `$CC`, for messages that name where it came from.
pub fn compiler_choice(given: Option<String>) -> (Option<String>, bool) {
    let env = std::env::var("CC").ok().filter(|c| !c.trim().is_empty());
    let from_env = given.is_none() && env.is_some();
    let cc = given.or(env).unwrap_or_else(|| "cc".into());
    ((cc != "none").then_some(cc), from_env)
}

/// An export error's message, naming `$CC` where the compiler came from it (`compiler_choice`).
pub fn compiler_message(e: &ExportError, from_env: bool) -> String {
    let text = e.to_string();
    match e {
        ExportError::Compiler { .. } | ExportError::CompilerNotFound { .. } if from_env => {
            text.replacen("compiler ", "$CC = ", 1)
        }
        _ => text,
    }
}

/// Generates the C controller for `design` at `sample_time`: the same controller as
/// `Controller::new(design, sample_time)`, with the same errors.
pub fn generate(design: &Design, sample_time: f64, options: &ExportOptions) -> Result<CCode, ExportError> {
    let prefix = &options.prefix;
    let mut chars = prefix.chars();
    let identifier =
        chars.next().is_some_and(|c| c.is_ascii_alphabetic()) && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !identifier {
        return Err(ExportError::Prefix { found: prefix.clone() });
    }
    if prefix.len() > MAX_PREFIX {
        return Err(ExportError::PrefixLength { length: prefix.len() });
    }
    let ctrl = Controller::new(design, sample_time)?;
    c::write(design, &ctrl, options)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn precision_names_round_trip() {
        for p in [Precision::F64, Precision::F32] {
            assert_eq!(p.name().parse::<Precision>(), Ok(p));
        }
        let e = "f16".parse::<Precision>().unwrap_err().to_string();
        assert_eq!(e, "precision: expected f64 or f32, found \"f16\"");
    }
}
