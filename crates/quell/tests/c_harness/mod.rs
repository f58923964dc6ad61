//! Compiles generated C controllers with the system C compiler and loads them in-process.
//!
//! The generated code is built into a shared library together with a small shim that converts
//! between `double` and the controller's type and reads η̂ out of the state; `libloading` opens it.
//! In-process calls (a few ns each) let the sampled-data loop call the C controller every sample,
//! which a harness over stdin/stdout (two pipe transfers per sample) would make slow and fiddly.
//! gcc is required: a machine without it fails these tests with a message saying so.
#![allow(dead_code, non_snake_case)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

use libloading::Library;
use quell::export::{CCode, Precision};
use quell::sim::{SampledController, Watched};
use quell::ControllerError;

/// Strict C99 with the common warnings, as errors.
pub const STRICT: &[&str] = &["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"];

/// A fresh directory under the system's temp dir, removed when dropped.
pub struct TempDir(pub PathBuf);

impl TempDir {
    pub fn new(tag: &str) -> TempDir {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::SeqCst);
        let dir = std::env::temp_dir().join(format!("quell-export-{}-{tag}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        TempDir(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Writes the header and source into `dir`.
pub fn write_code(code: &CCode, dir: &Path) -> PathBuf {
    std::fs::write(dir.join(&code.header_name), &code.header).unwrap();
    let source = dir.join(&code.source_name);
    std::fs::write(&source, &code.source).unwrap();
    source
}

/// Runs a tool (gcc, nm, size) and returns its stdout; panics with its stderr on failure.
pub fn tool(program: &str, args: &[&str], dir: &Path) -> String {
    let out = Command::new(program).args(args).current_dir(dir).output().unwrap_or_else(|e| {
        panic!("cannot run `{program}` ({e}); these tests need the system C toolchain (gcc, binutils) on PATH")
    });
    assert!(
        out.status.success(),
        "`{program} {}` failed:\n{}{}",
        args.join(" "),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The shim: `<p>_t_size`, `<p>_t_init` and `<p>_t_step` (step, then command, η̂ and the core
/// state z = [ξ̂; x̂], in doubles).
fn shim(prefix: &str, precision: Precision) -> String {
    let (P, R) = (prefix.to_ascii_uppercase(), precision.c_type());
    format!(
        r#"#include <stddef.h>
#include "{prefix}_controller.h"
size_t {prefix}_t_size(void);
void {prefix}_t_init(void *s);
void {prefix}_t_step(void *s, const double *y, const double *g, double *u_f, double *u, double *eta, double *z);
size_t {prefix}_t_size(void) {{ return sizeof({prefix}_state); }}
void {prefix}_t_init(void *s) {{ {prefix}_init(({prefix}_state *)s); }}
void {prefix}_t_step(void *s, const double *y, const double *g, double *u_f, double *u, double *eta, double *z)
{{
    {R} yy[{P}_M], gg[{P}_M], uf[{P}_M], uu[{P}_M];
    {prefix}_state *st = ({prefix}_state *)s;
    for (unsigned i = 0; i < {P}_M; i++) {{
        yy[i] = ({R})y[i];
        gg[i] = ({R})g[i];
    }}
    {prefix}_step(st, yy, gg, uf);
    {prefix}_command(st, uu);
    for (unsigned i = 0; i < {P}_M; i++) {{
        u_f[i] = uf[i];
        u[i] = uu[i];
        for (unsigned j = 0; j < {P}_Q; j++)
            eta[i * {P}_Q + j] = st->eta[i][j];
    }}
    for (unsigned j = 0; j < {P}_NZ; j++)
        z[j] = st->z[j];
}}
"#
    )
}

type StepFn = unsafe extern "C" fn(*mut u64, *const f64, *const f64, *mut f64, *mut f64, *mut f64, *mut f64);
type InitFn = unsafe extern "C" fn(*mut u64);
type SizeFn = unsafe extern "C" fn() -> usize;

/// A generated controller, compiled with `flags` and loaded.
pub struct CController {
    _lib: Library,
    _dir: TempDir,
    step_fn: StepFn,
    init_fn: InitFn,
    state: Vec<u64>,
    pub state_size: usize,
    u_f: Vec<f64>,
    u: Vec<f64>,
    eta: Vec<f64>,
    /// [ξ̂; x̂] after the last step; q of it is ξ̂.
    z: Vec<f64>,
    q: usize,
}

impl CController {
    /// Compiles `code` (generated with `prefix` and `precision`) with gcc and `opt` (e.g. "-O2");
    /// the design has m channels, regressor size q and n plant states.
    pub fn build(
        code: &CCode,
        prefix: &str,
        precision: Precision,
        (m, q, n): (usize, usize, usize),
        opt: &str,
    ) -> CController {
        let dir = TempDir::new(&format!("{prefix}{opt}"));
        write_code(code, &dir.0);
        CController::build_in(dir, prefix, precision, (m, q, n), opt)
    }

    /// Compiles `<prefix>_controller.c` as found in `dir`.
    pub fn build_in(
        dir: TempDir,
        prefix: &str,
        precision: Precision,
        (m, q, n): (usize, usize, usize),
        opt: &str,
    ) -> CController {
        std::fs::write(dir.0.join("shim.c"), shim(prefix, precision)).unwrap();
        let lib = dir.0.join("libctrl.so");
        let mut args: Vec<&str> = STRICT.to_vec();
        let (source, lib_s) = (format!("{prefix}_controller.c"), lib.display().to_string());
        args.extend([opt, "-shared", "-fPIC", "-o", &lib_s, &source, "shim.c"]);
        tool("gcc", &args, &dir.0);
        // SAFETY: the library is the code just compiled; its initializers do nothing.
        let library = unsafe { Library::new(&lib) }.expect("load the compiled controller");
        let sym = |name: &str| format!("{prefix}_t_{name}");
        // SAFETY: the shim defines these symbols with exactly these signatures.
        let (step_fn, init_fn, size_fn) = unsafe {
            (
                *library.get::<StepFn>(sym("step").as_bytes()).unwrap(),
                *library.get::<InitFn>(sym("init").as_bytes()).unwrap(),
                *library.get::<SizeFn>(sym("size").as_bytes()).unwrap(),
            )
        };
        // SAFETY: no arguments.
        let state_size = unsafe { size_fn() };
        let mut c = CController {
            _lib: library,
            _dir: dir,
            step_fn,
            init_fn,
            state: vec![0; state_size.div_ceil(8)],
            state_size,
            u_f: vec![0.0; m],
            u: vec![0.0; m],
            eta: vec![0.0; m * q],
            z: vec![0.0; q + n],
            q,
        };
        c.reset();
        c
    }

    /// `<p>_init`.
    pub fn reset(&mut self) {
        // SAFETY: the buffer holds sizeof(state) bytes, 8-aligned.
        unsafe { (self.init_fn)(self.state.as_mut_ptr()) }
    }

    /// `<p>_step`, returning u_f(k).
    pub fn step(&mut self, y: &[f64], g: &[f64]) -> &[f64] {
        assert!(y.len() == self.u.len() && g.len() == self.u.len());
        // SAFETY: every buffer has the length the compiled code reads or writes (m, m·q, q + n).
        unsafe {
            (self.step_fn)(
                self.state.as_mut_ptr(),
                y.as_ptr(),
                g.as_ptr(),
                self.u_f.as_mut_ptr(),
                self.u.as_mut_ptr(),
                self.eta.as_mut_ptr(),
                self.z.as_mut_ptr(),
            )
        }
        &self.u_f
    }

    /// A function of the compiled code, e.g. `<p>_step` itself.
    ///
    /// # Safety
    /// `F` must be the function's true signature.
    pub unsafe fn function<F: Copy>(&self, name: &str) -> F {
        // SAFETY: the caller's promise; the library outlives `self`'s use of the pointer.
        unsafe { *self._lib.get::<F>(name.as_bytes()).unwrap() }
    }

    /// The state buffer, for calling the compiled functions directly.
    pub fn state_ptr(&mut self) -> *mut u64 {
        self.state.as_mut_ptr()
    }

    /// u(k) of the last step (`<p>_command`).
    pub fn command(&self) -> &[f64] {
        &self.u
    }

    /// η̂ after the last step, concatenated.
    pub fn eta(&self) -> &[f64] {
        &self.eta
    }
}

impl SampledController for CController {
    fn step(&mut self, y: &[f64], g: &[f64]) -> Result<&[f64], ControllerError> {
        Ok(CController::step(self, y, g))
    }
    fn command(&self) -> &[f64] {
        &self.u
    }
    fn watched(&self) -> Watched<'_> {
        Watched { x: &[], xi_hat: &self.z[..self.q], x_hat: &self.z[self.q..], eta: &self.eta }
    }
}
