//! The C text: `static const` arrays of the discretized matrices, the state struct and the step.

use std::fmt::Write;

use super::{CCode, ExportError, ExportOptions, Precision};
use crate::controller::Controller;
use crate::design::Design;
use crate::linalg::fmt_complex;

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

/// Builds both files; the constants are checked (finite; in float's range for f32) first.
pub(super) fn write(design: &Design, ctrl: &Controller, o: &ExportOptions) -> Result<CCode, ExportError> {
    let view = ctrl.discretized();
    let eq = view.eq;
    let (n, m, q, nz) = (eq.n, eq.m, eq.q, eq.nz);
    let (p, P) = (o.prefix.as_str(), o.prefix.to_ascii_uppercase());
    let R = o.precision.c_type();
    let T = ctrl.sample_time();
    let sigma: Vec<usize> = eq.channels.iter().map(|ch| ch.sigma).collect();
    let delays: Vec<usize> = view.channels.iter().map(|ch| ch.3).collect();
    let (sigma_sum, sigma_max) = (sigma.iter().sum::<usize>(), sigma.iter().copied().max().unwrap_or(1));
    let delay_max = delays.iter().copied().max().unwrap_or(0);

    // Row-major entries of rows r0.. and columns c0.. of a matrix.
    let block = |M: &nalgebra::DMatrix<f64>, (r0, c0): (usize, usize), (r, c): (usize, usize)| {
        (r0..r0 + r).flat_map(|i| (c0..c0 + c).map(move |j| M[(i, j)])).collect::<Vec<f64>>()
    };
    let dim = |s: &str| format!("{P}_{s}");
    let mut constants = vec![
        Constant {
            name: "PhiGamma_z".into(),
            dims: vec![dim("NZ"), format!("{P}_NZ + 3 * {P}_M")],
            cols: nz + 3 * m,
            values: block(view.PhiGamma_z, (0, 0), (nz, nz + 3 * m)),
            comment: Some("Core (observers (6), (14), (20) with (5) substituted) at ZOH: z(k+1) = [Phi_z Gamma_z] [z(k); y(k); g(k); u_d(k)].".into()),
        },
        Constant {
            name: "K_neg".into(),
            dims: vec![dim("M"), dim("N")],
            cols: n,
            values: block(&eq.K_neg, (0, 0), (m, n)),
            comment: Some("Plant input (5): u_f = -K x_hat + F u_d.".into()),
        },
        Constant {
            name: "F".into(),
            dims: vec![dim("M"), dim("M")],
            cols: m,
            values: block(&eq.F, (0, 0), (m, m)),
            comment: None,
        },
    ];
    for (i, (Phi, gamma, _, _)) in view.channels.iter().enumerate() {
        let s = sigma[i];
        constants.push(Constant {
            name: format!("Phi_{}", i + 1),
            dims: vec![format!("{}", s * s)],
            cols: s,
            values: block(Phi, (0, 0), (s, s)),
            comment: Some(format!(
                "Channel {}'s G_ii filter bank (sigma = {s}) at ZOH: W <- Phi W + gamma [u_{}(k - d), xi^T(k - d)]; Phi row-major.",
                i + 1,
                i + 1
            )),
        });
        constants.push(Constant {
            name: format!("gamma_{}", i + 1),
            dims: vec![format!("{s}")],
            cols: s,
            values: gamma.to_vec(),
            comment: None,
        });
    }
    constants.push(Constant {
        name: "q0".into(),
        dims: vec![dim("M")],
        cols: m,
        values: eq.channels.iter().map(|ch| ch.q0).collect(),
        comment: Some("Per channel: G_ii's numerator q_i0, the adaptive law's c_i = T_s mu_i (33).".into()),
    });
    constants.push(Constant {
        name: "c".into(),
        dims: vec![dim("M")],
        cols: m,
        values: view.channels.iter().map(|ch| ch.2).collect(),
        comment: None,
    });
    constants.push(Constant {
        name: "a".into(),
        dims: vec![],
        cols: 1,
        values: vec![view.a],
        comment: Some(format!(
            "H(s) = 1/(beta s + 1) at ZOH: x <- a x + b v, a = exp(-T_s/beta), b = 1 - a (beta = {}).",
            eq.beta
        )),
    });
    constants.push(Constant { name: "b".into(), dims: vec![], cols: 1, values: vec![1.0 - view.a], comment: None });

    let number = |x: f64| match o.precision {
        Precision::F64 => format!("{x:?}"),
        Precision::F32 => format!("{:?}f", x as f32),
    };
    for c in &constants {
        for (k, &x) in c.values.iter().enumerate() {
            let what = || {
                let at = if c.dims.is_empty() {
                    String::new()
                } else if c.dims.len() == 1 {
                    format!("[{k}]")
                } else {
                    format!("[{}][{}]", k / c.cols, k % c.cols)
                };
                format!("{p}_{}{at}", c.name)
            };
            if !x.is_finite() {
                return Err(ExportError::NotFinite { what: what(), value: x, sample_time: T });
            }
            if o.precision == Precision::F32 && x.abs() > f32::MAX as f64 {
                return Err(ExportError::F32Range { what: what(), value: x });
            }
        }
    }

    let w = o.precision.bytes();
    let constant_bytes = w * constants.iter().map(|c| c.values.len()).sum::<usize>() + 4 * m;
    let state_numbers = nz + sigma_sum * (q + 1) + m * q + m * q * (q + 1) / 2 + m * q + m + (delay_max + 1) * (m + q);
    let state_bytes = (w * state_numbers + 4).div_ceil(w) * w;

    let name = o.scenario_name.as_deref().map(comment_safe);
    let eigen = |z: &[nalgebra::Complex<f64>]| z.iter().map(fmt_complex).collect::<Vec<_>>().join(", ");
    let delay_text = (0..m)
        .map(|i| format!("channel {}: {} s = {} samples", i + 1, design.plant().delays[i], delays[i]))
        .collect::<Vec<_>>()
        .join("; ");

    // The sizes, one aligned block.
    let defines = [
        ("N", n.to_string(), "plant states"),
        ("M", m.to_string(), "channels: outputs y, references g, inputs u_f"),
        ("Q", q.to_string(), "regressor xi_hat = [xi_g; xi_w] and each eta_i"),
        ("SAMPLE_TIME", number(T), "T_s in seconds"),
        ("NZ", nz.to_string(), "state sizes: core [xi_g; xi_w; x_hat]"),
        ("SIGMA_SUM", sigma_sum.to_string(), "filter-bank rows, sigma_1 + ... + sigma_m"),
        ("SIGMA_MAX", sigma_max.to_string(), "largest relative degree"),
        ("DELAY_MAX", delay_max.to_string(), "longest input delay in samples"),
        ("INPUT_BOUND", number(o.precision.input_bound()), "largest |y_i|, |g_i| a step takes"),
    ]
    .iter()
    .map(|(k, v, c)| format!("#define {:<w$} {v:<12} /* {c} */", format!("{P}_{k}"), w = P.len() + 12))
    .collect::<Vec<_>>()
    .join("\n");
    let fields = [
        (format!("{R} z[{P}_NZ];"), "core: observers (14), (20), (6)"),
        (format!("{R} W[{P}_SIGMA_SUM][{P}_Q + 1];"), "G_ii filter banks, channel by channel"),
        (format!("{R} Y[{P}_M][{P}_Q];"), "H filter memories Y_i (33)"),
        (
            format!("{R} Omega[{P}_M][{P}_Q * ({P}_Q + 1) / 2];"),
            "H filter memories Omega_i (33), upper triangle by rows",
        ),
        (format!("{R} eta[{P}_M][{P}_Q];"), "adaptive parameters eta_i (33)"),
        (format!("{R} u[{P}_M];"), "adaptive command u(k) (25)"),
        (format!("{R} line[{P}_DELAY_MAX + 1][{P}_M + {P}_Q];"), "delay line of rows [u(k), xi_hat^T(k)]"),
        ("uint32_t head;".to_string(), "row of line holding sample k"),
    ];
    let width = fields.iter().map(|(f, _)| f.len()).max().unwrap_or(0);
    let fields = fields.iter().map(|(f, c)| format!("    {f:<width$} /* {c} */")).collect::<Vec<_>>().join("\n");
    // Header.
    let mut h = String::new();
    let _ = write!(
        h,
        "/* {p}_controller.h: direct adaptive output-feedback controller (C. V. Tu, N. Dudarenko, eqs.
 * (5), (6), (14), (20), (25), (33)), discretized exactly for a zero-order hold.
 *
 * Generated by quell {version}{from}. Do not edit: after a design
 * change, regenerate with
 *     quell export SCENARIO --sample-time {T:?} --prefix {p} --precision {prec}
 *
 * Sample time T_s = {T:?} s: call {p}_step once per sample (docs/deployment.md).
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
extern \"C\" {{
#endif

{defines}

/* Everything that changes; {p}_init zeroes it. */
typedef struct {{
{fields}
}} {p}_state;

/* The Controller's zero state (also to restart it). */
void {p}_init({p}_state *s);
/* One sample: reads y(k) and g(k), writes the plant input u_f(k) = -K x_hat + F u_d (5), to hold
 * until the next sample, and returns 0. An entry of y or g that is NaN or beyond +-{P}_INPUT_BOUND
 * (a sensor fault) is refused: it returns 1 and leaves the state and u_f untouched; hold the
 * previous input. It returns 2 when u_f or u is no longer finite (inputs the design cannot follow
 * overflowed the state), and keeps returning 2: hold a safe input and call {p}_init
 * (docs/deployment.md). Needs IEEE arithmetic (no -ffast-math). */
int {p}_step({p}_state *s, const {R} y[{P}_M], const {R} g[{P}_M], {R} u_f[{P}_M]);
/* The adaptive command u(k) (25) of the last step, undelayed. */
void {p}_command(const {p}_state *s, {R} u[{P}_M]);

#ifdef __cplusplus
}}
#endif

#endif /* {P}_CONTROLLER_H */
",
        version = env!("CARGO_PKG_VERSION"),
        from = name.as_ref().map(|s| format!(" from scenario \"{s}\"")).unwrap_or_default(),
        prec = o.precision.name(),
        qg = design.q_g(),
        qw = design.q_w(),
        obs = eigen(design.observer_eigenvalues()),
        dec = eigen(design.decoupled_eigenvalues()),
        defines = defines,
        fields = fields,
    );

    // Source: the constants, then the functions.
    let mut c = String::new();
    let _ =
        writeln!(c, "/* {p}_controller.c: generated by quell {}; see {p}_controller.h. */", env!("CARGO_PKG_VERSION"));
    let _ = writeln!(c, "#include \"{p}_controller.h\"");
    for k in &constants {
        let _ = writeln!(c);
        if let Some(text) = &k.comment {
            let _ = writeln!(c, "/* {text} */");
        }
        let dims: String = k.dims.iter().map(|d| format!("[{d}]")).collect();
        let rows: Vec<String> =
            k.values.chunks(k.cols).map(|r| r.iter().map(|&x| number(x)).collect::<Vec<_>>().join(", ")).collect();
        let init = match (k.dims.len(), rows.len()) {
            (0, _) => rows.join(""),
            (1, _) => format!("{{{}}}", rows.join(", ")),
            _ => format!("{{\n    {{{}}},\n}}", rows.join("},\n    {")),
        };
        let _ = writeln!(c, "static const {R} {p}_{}{dims} = {init};", k.name);
    }
    let delay_list = delays.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(", ");
    let _ = writeln!(c, "\n/* Delay lines: d_i = tau_i / T_s samples. */");
    let _ = writeln!(c, "static const uint32_t {p}_delay[{P}_M] = {{{delay_list}}};");
    let mut calls = String::new();
    let mut row = 0;
    for (i, &s) in sigma.iter().enumerate() {
        let _ = writeln!(
            calls,
            "    u_d[{i}] = {p}_channel(s, {i}u, {s}u, {p}_Phi_{k}, {p}_gamma_{k}, {row}u, y[{i}] - g[{i}]);",
            k = i + 1
        );
        row += s;
    }
    c.push_str(&FUNCTIONS.replace("{calls}", calls.trim_end()).replace("{p}", p).replace("{P}", &P).replace("{R}", R));
    pair_layout_id(&mut h, &mut c, p, &P);

    Ok(CCode {
        header_name: format!("{p}_controller.h"),
        header: h,
        source_name: format!("{p}_controller.c"),
        source: c,
        constant_bytes,
        state_bytes,
    })
}

/// `text` for a C comment: escaped (one line, ASCII), with `/*` and `*/` broken by a backslash so
/// the comment neither ends nor nests early.
fn comment_safe(text: &str) -> String {
    text.escape_default().to_string().replace("/*", "/\\*").replace("*/", "*\\/")
}

/// A check that a header and a source were generated together: the header defines
/// `<P>_LAYOUT_ID`, a hash of both texts, and the source declares an array of size −1 unless the
/// header's id is its own, so a mismatched pair (a failed or partial update) does not compile.
fn pair_layout_id(h: &mut String, c: &mut String, p: &str, P: &str) {
    let id = crate::study::fnv1a(format!("{h}{c}").as_bytes());
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
    for (unsigned i = 0; i < {P}_NZ; i++)
        s->z[i] = 0;
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
    /* Adaptive step (33), implicit in rho I with rho = tr Omega >= lambda_max(Omega), explicit in
     * the rest: eta <- eta + c (Y - Omega eta) / (1 + c rho), c = T_s mu_i; nonexpansive for any c. */
    const {R} gain = c / (1 + c * trace);
    for (unsigned j = 0; j < {P}_Q; j++)
        eta[j] += gain * (Y[j] - Omega_eta[j]);
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
    {R} *now = s->line[s->head];
    {R} zv[{P}_NZ + 3 * {P}_M]; /* [z(k); y(k); g(k); u_d(k)], u_d(k) = [u_1(k - d_1), ...] */
    {R} *u_d = zv + {P}_NZ + 2 * {P}_M;

    /* Refuse a NaN or a spike beyond the bound before anything changes (false for NaN). */
    for (unsigned i = 0; i < {P}_M; i++)
        if (!(y[i] >= -{P}_INPUT_BOUND && y[i] <= {P}_INPUT_BOUND && g[i] >= -{P}_INPUT_BOUND && g[i] <= {P}_INPUT_BOUND))
            return 1;

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
        u_f[i] = {p}_dot({p}_F[i], u_d, {P}_M, {p}_dot({p}_K_neg[i], s->z + {P}_Q, {P}_N, 0));
    /* Core at ZOH: z(k + 1) = [Phi_z Gamma_z] [z(k); y(k); g(k); u_d(k)]. */
    for (unsigned i = 0; i < {P}_NZ; i++)
        zv[i] = s->z[i];
    for (unsigned i = 0; i < {P}_M; i++) {
        zv[{P}_NZ + i] = y[i];
        zv[{P}_NZ + {P}_M + i] = g[i];
    }
    for (unsigned i = 0; i < {P}_NZ; i++)
        s->z[i] = {p}_dot({p}_PhiGamma_z[i], zv, {P}_NZ + 3 * {P}_M, 0);
    s->head = s->head == {P}_DELAY_MAX ? 0 : s->head + 1;
    /* x - x is 0 unless x is infinite or NaN. */
    for (unsigned i = 0; i < {P}_M; i++)
        if (!(u_f[i] - u_f[i] == 0 && s->u[i] - s->u[i] == 0))
            return 2;
    return 0;
}

void {p}_command(const {p}_state *s, {R} u[{P}_M])
{
    for (unsigned i = 0; i < {P}_M; i++)
        u[i] = s->u[i];
}
"#;
