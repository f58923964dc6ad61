//! The C text: `static const` arrays of the discretized matrices, the state struct and the step.

use std::fmt::Write;

use nalgebra::DMatrix;

use super::{CCode, ExportError, ExportOptions, Precision};
use crate::controller::{Controller, Discretized};
use crate::design::Design;
use crate::linalg::fmt_eigenvalues;
use crate::settings::TimeUnit;

/// One `static const` array (or scalar, with no `dims`) of the generated source.
struct Constant {
    /// Name after the prefix, e.g. `Phi_z`.
    name: String,
    /// C dimensions, e.g. `["QUELL_NZ", "QUELL_NZ"]`; a matrix is written row by row.
    dims: Vec<String>,
    /// Length of the last dimension (entries per written row).
    cols: usize,
    values: Vec<f64>,
    /// One-line comment above it, or none.
    comment: Option<String>,
}

impl Constant {
    fn new(name: impl Into<String>, dims: Vec<String>, cols: usize, values: Vec<f64>) -> Constant {
        Constant { name: name.into(), dims, cols, values, comment: None }
    }
    fn with_comment(self, comment: impl Into<String>) -> Constant {
        Constant { comment: Some(comment.into()), ..self }
    }
    /// The C name of entry `k`, e.g. `quell_Phi_1[4]` or `quell_F[1][0]`.
    fn entry(&self, p: &str, k: usize) -> String {
        let at = match self.dims.len() {
            0 => String::new(),
            1 => format!("[{k}]"),
            _ => format!("[{}][{}]", k / self.cols, k % self.cols),
        };
        format!("{p}_{}{at}", self.name)
    }
}

/// The sizes of one export, read once from the discretized controller.
struct Layout {
    n: usize,
    m: usize,
    q: usize,
    nz: usize,
    /// σ_i per channel.
    sigma: Vec<usize>,
    /// d_i = τ_i / T_s per channel, in samples.
    delays: Vec<usize>,
}

impl Layout {
    fn new(view: &Discretized) -> Layout {
        let eq = view.eq;
        Layout {
            n: eq.n,
            m: eq.m,
            q: eq.q,
            nz: eq.nz,
            sigma: eq.channels.iter().map(|ch| ch.sigma()).collect(),
            delays: view.channels.iter().map(|ch| ch.delay_samples).collect(),
        }
    }
    fn sigma_sum(&self) -> usize {
        self.sigma.iter().sum()
    }
    fn sigma_max(&self) -> usize {
        self.sigma.iter().copied().max().unwrap_or(1)
    }
    fn delay_max(&self) -> usize {
        self.delays.iter().copied().max().unwrap_or(0)
    }
    /// The fields of `<prefix>_state`, in order: the one description both the struct's text and
    /// its size come from.
    fn state_fields(&self) -> [Field; 8] {
        let (m, q, nz) = (self.m, self.q, self.nz);
        let real = |name: &'static str, dims: &'static str, count: usize, comment: &'static str| Field {
            integer: false,
            name,
            dims,
            count,
            comment,
        };
        [
            real("z", "[{P}_NZ]", nz, "core: observers (14), (20), (6)"),
            real(
                "W",
                "[{P}_SIGMA_SUM][{P}_Q + 1]",
                self.sigma_sum() * (q + 1),
                "G_ii filter banks, channel by channel",
            ),
            real("Y", "[{P}_M][{P}_Q]", m * q, "H filter memories Y_i (33)"),
            real(
                "Omega",
                "[{P}_M][{P}_Q * ({P}_Q + 1) / 2]",
                m * q * (q + 1) / 2,
                "H filter memories Omega_i (33), upper triangle by rows",
            ),
            real("eta", "[{P}_M][{P}_Q]", m * q, "adaptive parameters eta_i (33)"),
            real("u", "[{P}_M]", m, "adaptive command u(k) (25)"),
            real(
                "line",
                "[{P}_DELAY_MAX + 1][{P}_M + {P}_Q]",
                (self.delay_max() + 1) * (m + q),
                "delay line of rows [u(k), xi_hat^T(k)]",
            ),
            Field { integer: true, name: "head", dims: "", count: 1, comment: "row of line holding sample k" },
        ]
    }
}

/// One field of the state struct: `count` numbers of the real type, or one `uint32_t`.
struct Field {
    integer: bool,
    name: &'static str,
    /// C dimensions, with `{P}` for the upper-case prefix.
    dims: &'static str,
    count: usize,
    comment: &'static str,
}

/// `sizeof` of a struct of `fields` where a number is aligned to its size (`real_bytes` for the
/// real type, 4 for `uint32_t`): each field starts at a multiple of its size, the whole at a
/// multiple of the largest.
fn struct_bytes(fields: &[Field], real_bytes: usize) -> usize {
    let mut offset = 0usize;
    let mut align = 1;
    for f in fields {
        let size = if f.integer { 4 } else { real_bytes };
        offset = offset.next_multiple_of(size) + size * f.count;
        align = align.max(size);
    }
    offset.next_multiple_of(align)
}

/// Builds both files; the constants are checked (finite; in float's range for f32) first.
pub(super) fn write(design: &Design, ctrl: &Controller, o: &ExportOptions) -> Result<CCode, ExportError> {
    let view = ctrl.discretized();
    let layout = Layout::new(&view);
    let constants = constants(&view, &layout, &o.prefix.to_ascii_uppercase());
    check(&constants, o, (ctrl.sample_time(), design.plant().time_unit))?;
    let w = o.precision.bytes();
    let constant_bytes = w * constants.iter().map(|c| c.values.len()).sum::<usize>() + 4 * layout.m;
    let state_bytes = struct_bytes(&layout.state_fields(), w);
    let mut h = header(design, ctrl.sample_time(), &layout, o, (constant_bytes, state_bytes));
    let mut c = source(&constants, &layout, o);
    let p = o.prefix.as_str();
    pair_layout_id(&mut h, &mut c, p, &p.to_ascii_uppercase());
    Ok(CCode {
        header_name: format!("{p}_controller.h"),
        header: h,
        source_name: format!("{p}_controller.c"),
        source: c,
        constant_bytes,
        state_bytes,
        precision_warning: super::precision_warning(design, o.precision),
    })
}

/// Row-major entries of rows r0.. and columns c0.. of a matrix.
fn block(M: &DMatrix<f64>, (r0, c0): (usize, usize), (r, c): (usize, usize)) -> Vec<f64> {
    (r0..r0 + r).flat_map(|i| (c0..c0 + c).map(move |j| M[(i, j)])).collect()
}

/// Every `static const` array of the source, in order; `P` is the upper-case prefix.
fn constants(view: &Discretized, layout: &Layout, P: &str) -> Vec<Constant> {
    let eq = view.eq;
    let (n, m, nz) = (layout.n, layout.m, layout.nz);
    let dim = |s: &str| format!("{P}_{s}");
    let mut constants = vec![
        Constant::new("PhiGamma_z", vec![dim("NZ"), format!("{P}_NZ + 3 * {P}_M")], nz + 3 * m, block(view.PhiGamma_z, (0, 0), (nz, nz + 3 * m)))
            .with_comment("Core (observers (6), (14), (20) with (5) substituted) at ZOH: z(k+1) = [Phi_z Gamma_z] [z(k); y(k); g(k); u_d(k)]."),
        Constant::new("K_neg", vec![dim("M"), dim("N")], n, block(&eq.K_neg, (0, 0), (m, n)))
            .with_comment("Plant input (5): u_f = -K x_hat + F u_d."),
        Constant::new("F", vec![dim("M"), dim("M")], m, block(&eq.F, (0, 0), (m, m))),
    ];
    for (i, ch) in view.channels.iter().enumerate() {
        let (s, k) = (layout.sigma[i], i + 1);
        constants.push(Constant::new(format!("Phi_{k}"), vec![format!("{}", s * s)], s, block(ch.Phi, (0, 0), (s, s))).with_comment(
            format!("Channel {k}'s G_ii filter bank (sigma = {s}) at ZOH: W <- Phi W + gamma [u_{k}(k - d), xi^T(k - d)]; Phi row-major."),
        ));
        constants.push(Constant::new(format!("gamma_{k}"), vec![format!("{s}")], s, ch.gamma.to_vec()));
    }
    constants.push(
        Constant::new("q0", vec![dim("M")], m, eq.channels.iter().map(|ch| ch.q0()).collect())
            .with_comment("Per channel: G_ii's numerator q_i0, the adaptive law's c_i = T_s mu_i (33)."),
    );
    constants.push(Constant::new("c", vec![dim("M")], m, view.channels.iter().map(|ch| ch.c).collect()));
    constants.push(Constant::new("a", vec![], 1, vec![view.a]).with_comment(format!(
        "H(s) = 1/(beta s + 1) at ZOH: x <- a x + b v, a = exp(-T_s/beta), b = 1 - a (beta = {}).",
        eq.beta
    )));
    constants.push(Constant::new("b", vec![], 1, vec![view.b]));
    if view.xhat0.iter().any(|&x| x != 0.0) {
        constants.push(
            Constant::new("xhat0", vec![dim("N")], n, view.xhat0.to_vec())
                .with_comment("The observer's initial estimate x_hat(0) (plant.xhat0), set by init."),
        );
    }
    constants
}

/// Every constant finite, and in float's range for f32.
fn check(constants: &[Constant], o: &ExportOptions, (sample_time, unit): (f64, TimeUnit)) -> Result<(), ExportError> {
    for c in constants {
        for (k, &x) in c.values.iter().enumerate() {
            if !x.is_finite() {
                return Err(ExportError::NotFinite { what: c.entry(&o.prefix, k), value: x, sample_time, unit });
            }
            if o.precision == Precision::F32 && x.abs() > f32::MAX as f64 {
                return Err(ExportError::F32Range { what: c.entry(&o.prefix, k), value: x });
            }
        }
    }
    Ok(())
}

/// A number as a C literal of the export's type (`0.5`, `0.5f`), with the digits that read back
/// to the same value.
fn number(x: f64, precision: Precision) -> String {
    match precision {
        Precision::F64 => format!("{x:?}"),
        Precision::F32 => format!("{:?}f", x as f32),
    }
}

/// `template` with each `{key}` of `values` replaced, in one pass (a value is not searched again);
/// any other brace is kept.
pub(super) fn fill(template: &str, values: &[(&str, &str)]) -> String {
    let mut out = String::with_capacity(template.len());
    let mut rest = template;
    while let Some(open) = rest.find('{') {
        out.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        let key = after.find('}').map(|close| &after[..close]);
        match key.and_then(|k| values.iter().find(|(name, _)| *name == k)) {
            Some((name, value)) => {
                out.push_str(value);
                rest = &after[name.len() + 1..];
            }
            None => {
                out.push('{');
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// The header: what the controller is, its sizes, its state struct and the three functions.
fn header(
    design: &Design,
    T: f64,
    layout: &Layout,
    o: &ExportOptions,
    (constant_bytes, state_bytes): (usize, usize),
) -> String {
    let (p, P, R) = (o.prefix.as_str(), o.prefix.to_ascii_uppercase(), o.precision.c_type());
    let num = |x: f64| number(x, o.precision);
    let delay_text = (0..layout.m)
        .map(|i| format!("channel {}: tau = {} = {} samples", i + 1, design.plant().delays[i], layout.delays[i]))
        .collect::<Vec<_>>()
        .join("; ");
    let unit = super::time_unit_text(design);
    let sample_time_comment = format!("T_s, in {unit} (that of its A and delays)");
    // The sizes, one aligned block.
    let defines = [
        ("N", layout.n.to_string(), "plant states"),
        ("M", layout.m.to_string(), "channels: outputs y, references g, inputs u_f"),
        ("Q", layout.q.to_string(), "regressor xi_hat = [xi_g; xi_w] and each eta_i"),
        // A double in float builds too: the FMU counts time with it, and 0.1f is not 0.1.
        ("SAMPLE_TIME", number(T, Precision::F64), &sample_time_comment),
        ("NZ", layout.nz.to_string(), "state sizes: core [xi_g; xi_w; x_hat]"),
        ("SIGMA_SUM", layout.sigma_sum().to_string(), "filter-bank rows, sigma_1 + ... + sigma_m"),
        ("SIGMA_MAX", layout.sigma_max().to_string(), "largest relative degree"),
        ("DELAY_MAX", layout.delay_max().to_string(), "longest input delay in samples"),
        ("INPUT_BOUND", num(o.precision.input_bound()), "largest |y_i|, |g_i| a step takes"),
    ]
    .iter()
    .map(|(k, v, c)| format!("#define {:<w$} {v:<12} /* {c} */", format!("{P}_{k}"), w = P.len() + 12))
    .collect::<Vec<_>>()
    .join("\n");
    let fields: Vec<(String, &str)> = layout
        .state_fields()
        .iter()
        .map(|f| {
            (format!("{} {}{};", if f.integer { "uint32_t" } else { R }, f.name, f.dims.replace("{P}", &P)), f.comment)
        })
        .collect();
    let width = fields.iter().map(|(f, _)| f.len()).max().unwrap_or(0);
    let fields = fields.iter().map(|(f, c)| format!("    {f:<width$} /* {c} */")).collect::<Vec<_>>().join("\n");
    let from =
        o.scenario_name.as_deref().map(|s| format!(" from scenario \"{}\"", comment_safe(s))).unwrap_or_default();
    fill(
        HEADER,
        &[
            ("p", p),
            ("P", &P),
            ("R", R),
            ("version", env!("CARGO_PKG_VERSION")),
            ("from", &from),
            ("T", &format!("{T:?}")),
            ("unit", &unit),
            ("prec", o.precision.name()),
            ("n", &layout.n.to_string()),
            ("m", &layout.m.to_string()),
            ("q", &layout.q.to_string()),
            ("qg", &design.q_g().to_string()),
            ("qw", &design.q_w().to_string()),
            ("delay_text", &delay_text),
            ("obs", &fmt_eigenvalues(design.observer_eigenvalues())),
            ("dec", &fmt_eigenvalues(design.decoupled_eigenvalues())),
            ("constant_bytes", &constant_bytes.to_string()),
            ("state_bytes", &state_bytes.to_string()),
            ("defines", &defines),
            ("fields", &fields),
        ],
    )
}

/// The source: the constants, the delays, then the functions with one call per channel.
fn source(constants: &[Constant], layout: &Layout, o: &ExportOptions) -> String {
    let (p, P, R) = (o.prefix.as_str(), o.prefix.to_ascii_uppercase(), o.precision.c_type());
    let mut c = String::new();
    let _ =
        writeln!(c, "/* {p}_controller.c: generated by quell {}; see {p}_controller.h. */", env!("CARGO_PKG_VERSION"));
    let _ = writeln!(c, "#include \"{p}_controller.h\"");
    let _ = writeln!(c, "#include <float.h>");
    // The checks of y, g, u and u_f test for NaN and infinities, which these flags assume away
    // (gcc -ffast-math compiled an FMU's NaN check of its inputs out; hostile review, 2026-12-07).
    c.push_str(concat!(
        "#if defined(__FAST_MATH__) || (defined(__FINITE_MATH_ONLY__) && __FINITE_MATH_ONLY__)\n",
        "#error \"quell's checks of its inputs and state need NaN and infinities: build without -ffast-math, -Ofast or -ffinite-math-only\"\n",
        "#endif\n",
    ));
    for k in constants {
        let _ = writeln!(c);
        if let Some(text) = &k.comment {
            let _ = writeln!(c, "/* {text} */");
        }
        let dims: String = k.dims.iter().map(|d| format!("[{d}]")).collect();
        let rows: Vec<String> = k
            .values
            .chunks(k.cols)
            .map(|r| r.iter().map(|&x| number(x, o.precision)).collect::<Vec<_>>().join(", "))
            .collect();
        let init = match k.dims.len() {
            0 => rows.join(""),
            1 => format!("{{{}}}", rows.join(", ")),
            _ => format!("{{\n    {{{}}},\n}}", rows.join("},\n    {")),
        };
        let _ = writeln!(c, "static const {R} {p}_{}{dims} = {init};", k.name);
    }
    let delay_list = layout.delays.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(", ");
    let _ = writeln!(c, "\n/* Delay lines: d_i = tau_i / T_s samples. */");
    let _ = writeln!(c, "static const uint32_t {p}_delay[{P}_M] = {{{delay_list}}};");
    let mut calls = String::new();
    let mut row = 0;
    for (i, &s) in layout.sigma.iter().enumerate() {
        let _ = writeln!(
            calls,
            "    u_d[{i}] = {p}_channel(s, {i}u, {s}u, {p}_Phi_{k}, {p}_gamma_{k}, {row}u, y[{i}] - g[{i}]);",
            k = i + 1
        );
        row += s;
    }
    let eps = match o.precision {
        Precision::F64 => "DBL_EPSILON",
        Precision::F32 => "FLT_EPSILON",
    };
    let implicit_from = number(crate::controller::discrete::IMPLICIT_FROM, o.precision);
    // x̂(0) where the scenario gives one (plant.xhat0); else z stays 0.
    let xhat0 = match constants.iter().any(|k| k.name == "xhat0") {
        true => fill(
            "\n    for (unsigned i = 0; i < {P}_N; i++)\n        s->z[{P}_Q + i] = {p}_xhat0[i];",
            &[("p", p), ("P", &P)],
        ),
        false => String::new(),
    };
    let values = [
        ("calls", calls.trim_end()),
        ("p", p),
        ("P", &P),
        ("R", R),
        ("eps", eps),
        ("implicit_from", &implicit_from),
        ("xhat0", &xhat0),
    ];
    c.push_str(&fill(FUNCTIONS, &values));
    c
}

/// `text` for a C comment: escaped (one line, ASCII), with `/*` and `*/` broken by a backslash so
/// the comment neither ends nor nests early.
fn comment_safe(text: &str) -> String {
    text.escape_default().to_string().replace("/*", "/\\*").replace("*/", "*\\/")
}

/// A check that a header and a source were generated together: the header defines
/// `<P>_LAYOUT_ID`, a hash of both texts, and the source declares an array of size −1 unless the
/// header's id is its own, so a mismatched pair (a failed or partial update) does not compile; and
/// the functions' linked names carry the id, so that an application compiled with another export's
/// header fails to link rather than index past the state (it had linked, and crashed in
/// `<p>_init`; hostile review, 2026-12-06).
fn pair_layout_id(h: &mut String, c: &mut String, p: &str, P: &str) {
    let id = crate::hash::fnv1a_64(h.bytes().chain(c.bytes()));
    let opener = format!("#define {P}_CONTROLLER_H\n");
    let linked: String =
        ["init", "step", "command"].iter().map(|f| format!("#define {p}_{f} {p}_{f}_{id:016x}\n")).collect();
    *h = h.replacen(
        &opener,
        &format!("{opener}\n/* The linked names carry this export's layout id: an object compiled with another export's\n * header does not link with this source. */\n{linked}"),
        1,
    );
    let guard = format!("#endif /* {P}_CONTROLLER_H */");
    *h = h.replacen(
        &guard,
        &format!("/* Identifies this header's source: {p}_controller.c compiles only with it. */\n#define {P}_LAYOUT_ID 0x{id:016x}u\n\n{guard}"),
        1,
    );
    let include = format!("#include \"{p}_controller.h\"\n");
    *c = c.replacen(
        &include,
        &format!("{include}\n/* A header from another export fails here (size -1): regenerate both files together. */\ntypedef char {p}_header_matches_source[{P}_LAYOUT_ID == 0x{id:016x}u ? 1 : -1];\n"),
        1,
    );
}

/// The header; `{p}`, `{P}`, `{R}` are the prefix, its upper case and the type, the rest what
/// [`header`] fills in.
const HEADER: &str = r#"/* {p}_controller.h: direct adaptive output-feedback controller (C. V. Tu, N. Dudarenko, eqs.
 * (5), (6), (14), (20), (25), (33)), discretized exactly for a zero-order hold.
 *
 * Generated by quell {version}{from}. Do not edit: after a design
 * change, regenerate with
 *     quell export SCENARIO --sample-time {T} --prefix {p} --precision {prec}
 *
 * Sample time T_s = {T}, in {unit}.
 * Call {p}_step once per sample (docs/deployment.md).
 * Plant: n = {n} states, m = {m} channels; regressor q = {q} (q_g = {qg}, q_w = {qw}).
 * Input delays: {delay_text}.
 * Eigenvalues of the design (continuous time):
 *   observer A - L C:  {obs}
 *   decoupled A - B K: {dec}
 * Memory: {constant_bytes} bytes of constants (static const), {state_bytes} bytes of state
 *   (sizeof({p}_state) where a {R} is aligned to its size).
 * Arithmetic: {R} throughout. No dynamic memory, no libm, no global mutable state.
 */
#ifndef {P}_CONTROLLER_H
#define {P}_CONTROLLER_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

{defines}

/* Everything that changes; {p}_init zeroes it (x_hat to plant.xhat0 where the scenario gives one). */
typedef struct {
{fields}
} {p}_state;

/* The Controller's initial state: zero, but x_hat at plant.xhat0 where the scenario gives one (also
 * to restart it); nothing when s is NULL. */
void {p}_init({p}_state *s);
/* One sample: reads y(k) and g(k), writes the plant input u_f(k) = -K x_hat + F u_d (5), to hold
 * until the next sample, and returns 0; u_f may be the array y or g (both are read first). An
 * entry of y or g that is NaN or beyond +-{P}_INPUT_BOUND (a sensor fault) is refused: it returns 1 and leaves the state and u_f untouched; hold the
 * previous input. It returns 2 when u_f or u is no longer finite (inputs the design cannot follow
 * overflowed the state), leaving u_f untouched, and keeps returning 2: hold a safe input and call {p}_init
 * (docs/deployment.md). It returns 3, touching nothing, for a state {p}_init did not make (its
 * delay-line row out of range: never initialized, or corrupted), and 4, touching nothing, when s,
 * y, g or u_f is NULL. Needs IEEE arithmetic (no -ffast-math). */
int {p}_step({p}_state *s, const {R} y[{P}_M], const {R} g[{P}_M], {R} u_f[{P}_M]);
/* The adaptive command u(k) (25) of the last step, undelayed (nothing when s or u is NULL). */
void {p}_command(const {p}_state *s, {R} u[{P}_M]);

#ifdef __cplusplus
}
#endif

#endif /* {P}_CONTROLLER_H */
"#;

/// The functions of the source; `{p}`, `{P}` and `{R}` are the prefix, its upper case and the type.
const FUNCTIONS: &str = r#"
/* acc + sum_j M[j] x[j], in j order (every sum here runs in the Rust Controller's order, so that an
 * f64 export and the Controller give the same bits). */
static {R} {p}_dot(const {R} *M, const {R} *x, unsigned len, {R} acc)
{
    for (unsigned j = 0; j < len; j++)
        acc += M[j] * x[j];
    return acc;
}

void {p}_init({p}_state *s)
{
    if (!s)
        return;
    for (unsigned i = 0; i < {P}_NZ; i++)
        s->z[i] = 0;{xhat0}
    for (unsigned r = 0; r < {P}_SIGMA_SUM; r++)
        for (unsigned j = 0; j < {P}_Q + 1; j++)
            s->W[r][j] = 0;
    for (unsigned i = 0; i < {P}_M; i++) {
        for (unsigned j = 0; j < {P}_Q; j++) {
            s->Y[i][j] = 0;
            s->eta[i][j] = 0;
        }
        for (unsigned j = 0; j < {P}_Q * ({P}_Q + 1) / 2; j++)
            s->Omega[i][j] = 0;
        s->u[i] = 0;
    }
    for (uint32_t k = 0; k < {P}_DELAY_MAX + 1; k++)
        for (unsigned j = 0; j < {P}_M + {P}_Q; j++)
            s->line[k][j] = 0;
    s->head = 0;
}

/* Entry (j, t), j <= t, of a symmetric Q x Q matrix kept as its upper triangle row by row. */
static unsigned {p}_tri(unsigned j, unsigned t)
{
    return j * (2u * {P}_Q + 1u - j) / 2u + (t - j);
}

/* The implicit Euler step of the adaptive law (33): (I + c Omega) delta = c (Y - Omega eta), with
 * Omega_eta = Omega eta on entry, eta <- eta + delta. I + c Omega = U^T D U (U unit upper
 * triangular, no square root) in F, packed as Omega (d_j on the diagonal, U[j][t] after it): row j
 * is final once the rows before it are eliminated from it; U[j][t] = s (1/d_j), and row j is
 * eliminated from each later row l by s[l][t] -= (U[j][l] d_j) U[j][t]. A pivot rounded below its
 * bound 1 is taken as 1; one lost to rounding (below 64 Q eps of its diagonal) is stored as 0 with
 * its row of U, and that direction does not move. rhs = Omega_eta becomes delta. */
static void {p}_implicit_step(const {R} *Omega, {R} c, const {R} *Y, {R} *Omega_eta, {R} *eta)
{
    {R} F[{P}_Q * ({P}_Q + 1) / 2]; /* U^T D U of I + c Omega, packed as Omega */
    {R} *rhs = Omega_eta;
    for (unsigned j = 0; j < {P}_Q; j++)
        rhs[j] = c * (Y[j] - Omega_eta[j]);
    for (unsigned j = 0, k = 0; j < {P}_Q; j++)
        for (unsigned t = j; t < {P}_Q; t++, k++) {
            F[k] = c * Omega[k];
            if (t == j)
                F[k] += 1;
        }
    const {R} negligible = 64 * {P}_Q * {eps};
    for (unsigned j = 0; j < {P}_Q; j++) {
        const unsigned rj = {p}_tri(j, j);
        const {R} scale = c * Omega[rj] + 1;
        const int kept = F[rj] > negligible * scale;
        const {R} pivot = !kept ? 0 : F[rj] >= 1 ? F[rj] : 1;
        const {R} inverse = kept ? 1 / pivot : 0;
        F[rj] = pivot;
        for (unsigned t = j + 1u; t < {P}_Q; t++)
            F[rj + t - j] = kept ? F[rj + t - j] * inverse : 0;
        for (unsigned l = j + 1u; l < {P}_Q; l++) {
            const {R} wl = F[rj + l - j] * pivot;
            const unsigned rl = {p}_tri(l, l);
            for (unsigned t = l; t < {P}_Q; t++)
                F[rl + t - l] -= wl * F[rj + t - j];
        }
    }
    for (unsigned k = 0; k < {P}_Q; k++) {
        const unsigned rk = {p}_tri(k, k);
        const {R} zk = rhs[k];
        for (unsigned j = k + 1u; j < {P}_Q; j++)
            rhs[j] -= F[rk + j - k] * zk;
    }
    for (unsigned j = 0; j < {P}_Q; j++) {
        const {R} pivot = F[{p}_tri(j, j)];
        rhs[j] = pivot == 0 ? 0 : rhs[j] / pivot;
    }
    for (unsigned j = {P}_Q; j-- > 0;) {
        const unsigned rj = {p}_tri(j, j);
        for (unsigned t = j + 1u; t < {P}_Q; t++)
            rhs[j] -= F[rj + t - j] * rhs[t];
    }
    for (unsigned j = 0; j < {P}_Q; j++)
        eta[j] += rhs[j];
}

/* Channel i of the adaptive law (33) at sample k, from the row [u_i, xi_hat^T] of sample k - d_i:
 * the swapping error and regressor from W_i(k), the H filters Y_i and Omega_i, one step of eta_i,
 * then the G_ii filter bank W_i(k + 1). Returns u_i(k - d_i). */
static {R} {p}_channel({p}_state *s, unsigned i, unsigned sigma, const {R} *Phi, const {R} *gamma,
                       unsigned row, {R} delta)
{
    {R} (*W)[{P}_Q + 1] = s->W + row;
    {R} *Y = s->Y[i], *Omega = s->Omega[i], *eta = s->eta[i];
    const uint32_t d = {p}_delay[i];
    const {R} *past = s->line[s->head >= d ? s->head - d : s->head + ((uint32_t){P}_DELAY_MAX + 1u) - d];
    const {R} q0 = {p}_q0[i], c = {p}_c[i];
    {R} Delta[{P}_Q], Omega_eta[{P}_Q], next[{P}_SIGMA_MAX];
    {R} trace = 0;

    /* Swapping error eps = (y_i - g_i) - q_i0 W[0][0] and regressor Delta = q_i0 W[0][1..q]. */
    const {R} eps = delta - q0 * W[0][0];
    for (unsigned j = 0; j < {P}_Q; j++) {
        Delta[j] = q0 * W[0][1 + j];
        Omega_eta[j] = 0;
    }
    /* H filters at ZOH: Y <- a Y + b Delta eps, Omega <- a Omega + b (Delta Delta^T) (symmetric, kept
     * as its upper triangle row by row: row j is Omega[j][j], then Omega[j][t] for t > j), and in
     * the same pass tr Omega and Omega eta, each entry summed over the column index in order. */
    for (unsigned j = 0; j < {P}_Q; j++)
        Y[j] = {p}_a * Y[j] + {p}_b * Delta[j] * eps;
    for (unsigned j = 0, k = 0; j < {P}_Q; j++) {
        Omega[k] = {p}_a * Omega[k] + {p}_b * (Delta[j] * Delta[j]);
        trace += Omega[k];
        Omega_eta[j] += Omega[k] * eta[j];
        k++;
        for (unsigned t = j + 1; t < {P}_Q; t++, k++) {
            Omega[k] = {p}_a * Omega[k] + {p}_b * (Delta[j] * Delta[t]);
            Omega_eta[j] += Omega[k] * eta[t];
            Omega_eta[t] += Omega[k] * eta[j];
        }
    }
    /* Adaptive step (33) with c = T_s mu_i, nonexpansive for any c: up to c tr Omega = {implicit_from},
     * explicit Euler, eta <- eta + c (Y - Omega eta) (each direction contracts by 1 - c lambda, in
     * [1 - {implicit_from}, 1]); beyond, the implicit Euler step. */
    if (c * trace <= {implicit_from}) {
        for (unsigned j = 0; j < {P}_Q; j++)
            eta[j] += c * (Y[j] - Omega_eta[j]);
    } else {
        {p}_implicit_step(Omega, c, Y, Omega_eta, eta);
    }
    /* G_ii filter bank at ZOH, column by column: W <- Phi W + gamma [u_i(k - d_i), xi_hat^T(k - d_i)]. */
    for (unsigned col = 0; col < {P}_Q + 1; col++) {
        const {R} x = col == 0 ? past[i] : past[{P}_M + col - 1];
        for (unsigned r = 0; r < sigma; r++) {
            {R} acc = gamma[r] * x;
            for (unsigned t = 0; t < sigma; t++)
                acc += Phi[r * sigma + t] * W[t][col];
            next[r] = acc;
        }
        for (unsigned r = 0; r < sigma; r++)
            W[r][col] = next[r];
    }
    return past[i];
}

int {p}_step({p}_state *s, const {R} y[{P}_M], const {R} g[{P}_M], {R} u_f[{P}_M])
{
    if (!s || !y || !g || !u_f)
        return 4;
    /* A state {p}_init did not make: its row would index past the delay line. */
    if (s->head > {P}_DELAY_MAX)
        return 3;
    {R} *now = s->line[s->head];
    {R} zv[{P}_NZ + 3 * {P}_M]; /* [z(k); y(k); g(k); u_d(k)], u_d(k) = [u_1(k - d_1), ...] */
    {R} out[{P}_M];                /* u_f(k), copied to u_f once known to be finite */
    {R} *u_d = zv + {P}_NZ + 2 * {P}_M;

    /* Refuse a NaN or a spike beyond the bound before anything changes (false for NaN). */
    for (unsigned i = 0; i < {P}_M; i++)
        if (!(y[i] >= -{P}_INPUT_BOUND && y[i] <= {P}_INPUT_BOUND && g[i] >= -{P}_INPUT_BOUND && g[i] <= {P}_INPUT_BOUND))
            return 1;
    /* y(k) and g(k) into [z; y; g; u_d] before u_f is written: u_f may be the array y or g. */
    for (unsigned i = 0; i < {P}_M; i++) {
        zv[{P}_NZ + i] = y[i];
        zv[{P}_NZ + {P}_M + i] = g[i];
    }

    /* Control law (25) with eta_i(k): u_i(k) = -eta_i^T xi_hat(k), xi_hat = the first q core states;
     * the delay line records [u(k), xi_hat^T(k)]. */
    for (unsigned i = 0; i < {P}_M; i++) {
        {R} dot = 0;
        for (unsigned j = 0; j < {P}_Q; j++)
            dot += s->eta[i][j] * s->z[j];
        s->u[i] = -dot;
        now[i] = s->u[i];
    }
    for (unsigned j = 0; j < {P}_Q; j++)
        now[{P}_M + j] = s->z[j];
    /* The adaptive law (33), channel by channel. */
{calls}
    /* Plant input (5): u_f = -K x_hat + F u_d, x_hat = the last n core states. */
    for (unsigned i = 0; i < {P}_M; i++)
        out[i] = {p}_dot({p}_F[i], u_d, {P}_M, {p}_dot({p}_K_neg[i], s->z + {P}_Q, {P}_N, 0));
    /* Core at ZOH: z(k + 1) = [Phi_z Gamma_z] [z(k); y(k); g(k); u_d(k)]. */
    for (unsigned i = 0; i < {P}_NZ; i++)
        zv[i] = s->z[i];
    for (unsigned i = 0; i < {P}_NZ; i++)
        s->z[i] = {p}_dot({p}_PhiGamma_z[i], zv, {P}_NZ + 3 * {P}_M, 0);
    s->head = s->head == {P}_DELAY_MAX ? 0 : s->head + 1;
    /* x - x is 0 unless x is infinite or NaN. */
    for (unsigned i = 0; i < {P}_M; i++)
        if (!(out[i] - out[i] == 0 && s->u[i] - s->u[i] == 0))
            return 2;
    for (unsigned i = 0; i < {P}_M; i++)
        u_f[i] = out[i];
    return 0;
}

void {p}_command(const {p}_state *s, {R} u[{P}_M])
{
    if (!s || !u)
        return;
    for (unsigned i = 0; i < {P}_M; i++)
        u[i] = s->u[i];
}
"#;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fill_replaces_known_keys_once_and_keeps_other_braces() {
        let text = fill("{p}_f(void) { return {x}; } /* {P} */", &[("p", "{P}"), ("P", "Q")]);
        // The value "{P}" is not searched again; `{ return` and `{x}` are not keys.
        assert_eq!(text, "{P}_f(void) { return {x}; } /* Q */");
        assert_eq!(fill("{", &[("p", "a")]), "{");
        assert_eq!(fill("}{p}", &[("p", "a")]), "}a");
    }

    /// The layout id is FNV-1a (64 bits) of the header and the source as generated, here checked
    /// against an independent (Python) FNV-1a of the two texts: 0x3316624e6667060c.
    #[test]
    fn the_layout_id_is_fnv1a_of_both_texts() {
        let (mut h, mut c) = ("#endif /* P_CONTROLLER_H */\n".to_string(), "#include \"p_controller.h\"\n".to_string());
        pair_layout_id(&mut h, &mut c, "p", "P");
        assert!(h.contains("#define P_LAYOUT_ID 0x3316624e6667060cu\n"), "{h}");
        assert!(c.contains("P_LAYOUT_ID == 0x3316624e6667060cu ? 1 : -1"), "{c}");
        // With the guard's opener (FNV-1a of both texts: 0xe8a427ccc6c2a260, Python), the linked
        // names follow it, before any prototype.
        let (mut h, mut c) = (
            "#define P_CONTROLLER_H\n#endif /* P_CONTROLLER_H */\n".to_string(),
            "#include \"p_controller.h\"\n".to_string(),
        );
        pair_layout_id(&mut h, &mut c, "p", "P");
        assert!(h.starts_with("#define P_CONTROLLER_H\n\n/* The linked names"), "{h}");
        assert!(h.contains("#define p_step p_step_e8a427ccc6c2a260\n"), "{h}");
    }
}
