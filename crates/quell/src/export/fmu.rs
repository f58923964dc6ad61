//! FMI 2.0 co-simulation FMU of the generated C controller (docs/deployment.md).
//!
//! The archive holds `modelDescription.xml`, the controller's C ([`super::generate`]) with a
//! wrapper implementing the FMI functions and the FMI 2.0.1 headers under `sources/`, and, when a
//! C compiler is given, the shared library under `binaries/<platform>/`. Inputs are `y[i]` and
//! `g[i]`, outputs `u_f[i]` (the plant input (5)) and `u[i]` (the adaptive command (25)).
//!
//! Timing: the controller samples at `k T_s` from the start time. `fmi2DoStep(t, h)` takes the
//! samples in `[t, t + h)` with the inputs last set (held over the step, so `h = T_s` gives exactly
//! the sampled loop) and then reports the outputs of the next sample: `u_f(k)` does not depend on
//! `y(k)` or `g(k)` (no direct feedthrough), so after `fmi2DoStep` to `t_k` the outputs are the
//! `u_f(k)` and `u(k)` that the controller holds over `[t_k, t_k+1)`, the values
//! [`Controller::step`](crate::controller::Controller::step) returns at sample `k`. `h` must be a
//! whole number of samples.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;
use std::process::Command;

use super::c::fill;
use super::{generate, CCode, ExportError, ExportOptions};
use crate::design::Design;

/// The FMI 2.0.1 headers (2-clause BSD, Modelica Association), as packaged in FMPy 0.3.32's
/// `fmpy/c-code/`; shipped in every FMU's `sources/` so the sources compile on their own.
const FMI2_HEADERS: [(&str, &str); 3] = [
    ("fmi2Functions.h", include_str!("fmi2/fmi2Functions.h")),
    ("fmi2FunctionTypes.h", include_str!("fmi2/fmi2FunctionTypes.h")),
    ("fmi2TypesPlatform.h", include_str!("fmi2/fmi2TypesPlatform.h")),
];

/// An FMU archive and what it holds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Fmu {
    /// `<prefix>.fmu`; the prefix is the FMI model identifier.
    pub file_name: String,
    /// The zip archive.
    pub bytes: Vec<u8>,
    /// `modelDescription.xml`.
    pub model_description: String,
    /// FMI platform of the binary (`linux64`, `darwin64`, `win64`), or none for a source-only FMU.
    pub platform: Option<&'static str>,
    /// The controller's C inside it.
    pub code: CCode,
}

/// The FMI 2.0 platform of the machine running this code and its shared-library extension.
fn host_platform() -> Option<(&'static str, &'static str)> {
    match (std::env::consts::OS, std::env::consts::ARCH) {
        ("linux", "x86_64") => Some(("linux64", "so")),
        ("macos", "x86_64") => Some(("darwin64", "dylib")),
        ("windows", "x86_64") => Some(("win64", "dll")),
        _ => None,
    }
}

/// Generates the FMU of `design` at `sample_time`: the controller of [`generate`], wrapped. With a
/// `compiler` (a C99 compiler taking gcc's flags: `gcc`, `cc`, `clang`) the archive also holds the
/// binary for this machine's platform, compiled with `-std=c99 -O2 -ffp-contract=off` so that in
/// f64 it computes the bits of [`Controller::step`](crate::controller::Controller::step).
pub fn generate_fmu(
    design: &Design,
    sample_time: f64,
    options: &ExportOptions,
    compiler: Option<&str>,
) -> Result<Fmu, ExportError> {
    let code = generate(design, sample_time, options)?;
    let p = options.prefix.as_str();
    let m = design.plant().m();
    let wrapper_name = format!("{p}_fmu.c");
    let mut sources: Vec<(String, String)> =
        vec![(code.header_name.clone(), code.header.clone()), (code.source_name.clone(), code.source.clone())];
    let guid = guid(&[&code.header, &code.source]);
    let wrapper = fill(
        WRAPPER,
        &[
            ("guid", &guid),
            ("version", env!("CARGO_PKG_VERSION")),
            ("p", p),
            ("P", &p.to_ascii_uppercase()),
            ("R", options.precision.c_type()),
        ],
    );
    sources.push((wrapper_name.clone(), wrapper));
    sources.extend(FMI2_HEADERS.iter().map(|(n, t)| (n.to_string(), t.to_string())));
    let model_description = model_description(options, m, sample_time, &guid, &[&wrapper_name, &code.source_name]);

    let binary = match compiler {
        None => None,
        Some(cc) => {
            let (platform, ext) = host_platform().ok_or_else(|| ExportError::Compiler {
                compiler: cc.to_string(),
                message: format!(
                    "FMI 2.0 names no platform for {}-{}; export a source-only FMU (no compiler) and build it there",
                    std::env::consts::OS,
                    std::env::consts::ARCH
                ),
            })?;
            let so = compile(cc, &sources, &[&wrapper_name, &code.source_name], &format!("{p}.{ext}"))?;
            Some((platform, format!("binaries/{platform}/{p}.{ext}"), so))
        }
    };

    let mut files: Vec<(String, Vec<u8>)> =
        vec![("modelDescription.xml".into(), model_description.clone().into_bytes())];
    files.extend(sources.into_iter().map(|(n, t)| (format!("sources/{n}"), t.into_bytes())));
    let platform = binary.as_ref().map(|b| b.0);
    files.extend(binary.map(|(_, path, so)| (path, so)));
    let bytes = zip(&files).map_err(|e| ExportError::Archive { message: e.to_string() })?;
    Ok(Fmu { file_name: format!("{p}.fmu"), bytes, model_description, platform, code })
}

/// A deterministic GUID from the generated text (FNV-1a, 128 bits), so that the same design at the
/// same sample time gives the same FMU and an edited one a different GUID.
fn guid(texts: &[&str]) -> String {
    let h = format!("{:032x}", crate::hash::fnv1a_128(texts.iter().flat_map(|t| t.bytes())));
    format!("{{{}-{}-{}-{}-{}}}", &h[0..8], &h[8..12], &h[12..16], &h[16..20], &h[20..32])
}

/// XML text with `&`, `<`, `>` and `"` escaped.
fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// `modelDescription.xml`: value references 0..m-1 are y, m..2m-1 g, 2m..3m-1 u_f, 3m..4m-1 u.
fn model_description(o: &ExportOptions, m: usize, sample_time: f64, guid: &str, source_files: &[&str]) -> String {
    let name = xml_escape(o.scenario_name.as_deref().unwrap_or(&o.prefix));
    let mut x = String::new();
    let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        x,
        r#"<fmiModelDescription fmiVersion="2.0" modelName="{name}" guid="{guid}" description="Direct adaptive output-feedback controller (quell), sampled at T_s = {sample_time:?} s" generationTool="quell {}" variableNamingConvention="structured" numberOfEventIndicators="0">"#,
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(
        x,
        r#"  <CoSimulation modelIdentifier="{}" canHandleVariableCommunicationStepSize="true" canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="false">"#,
        o.prefix
    );
    let _ = writeln!(x, "    <SourceFiles>");
    for f in source_files {
        let _ = writeln!(x, r#"      <File name="{f}"/>"#);
    }
    let _ = writeln!(x, "    </SourceFiles>\n  </CoSimulation>");
    let _ = writeln!(x, r#"  <DefaultExperiment startTime="0" stepSize="{sample_time:?}"/>"#);
    let _ = writeln!(x, "  <ModelVariables>");
    let signals = [
        ("y", "input", "continuous", "measured output y_i, sampled at each sample instant"),
        ("g", "input", "continuous", "reference g_i, sampled at each sample instant"),
        ("u_f", "output", "discrete", "plant input u_f,i (5), held over a sample"),
        ("u", "output", "discrete", "adaptive command u_i (25), undelayed"),
    ];
    for (s, (var, causality, variability, what)) in signals.iter().enumerate() {
        for i in 0..m {
            let start = if *causality == "input" { r#" start="0""# } else { "" };
            let _ = writeln!(
                x,
                r#"    <ScalarVariable name="{var}[{}]" valueReference="{}" causality="{causality}" variability="{variability}" description="{what}"><Real{start}/></ScalarVariable>"#,
                i + 1,
                s * m + i
            );
        }
    }
    let _ = writeln!(x, "  </ModelVariables>\n  <ModelStructure>");
    // Outputs depend on no input at the same instant (no direct feedthrough); indices are 1-based.
    let unknowns =
        (2 * m + 1..=4 * m).map(|k| format!(r#"      <Unknown index="{k}" dependencies=""/>"#)).collect::<Vec<_>>();
    let _ = writeln!(x, "    <Outputs>\n{}\n    </Outputs>", unknowns.join("\n"));
    let _ = writeln!(x, "    <InitialUnknowns>\n{}\n    </InitialUnknowns>", unknowns.join("\n"));
    let _ = writeln!(x, "  </ModelStructure>\n</fmiModelDescription>");
    x
}

/// Compiles `units` of `sources` into the shared library `output` with `compiler`, in a temporary
/// directory; returns its bytes.
fn compile(compiler: &str, sources: &[(String, String)], units: &[&str], output: &str) -> Result<Vec<u8>, ExportError> {
    let fail = |message: String| ExportError::Compiler { compiler: compiler.to_string(), message };
    let dir = tempfile::tempdir().map_err(|e| fail(format!("cannot create a temporary directory ({e})")))?;
    for (name, text) in sources {
        std::fs::write(dir.path().join(name), text).map_err(|e| fail(format!("cannot write {name} ({e})")))?;
    }
    let out = dir.path().join(output);
    let mut cmd = Command::new(compiler);
    cmd.args(["-std=c99", "-O2", "-ffp-contract=off", "-shared", "-fPIC", "-fvisibility=hidden", "-o"]).arg(&out);
    cmd.args(units.iter().map(|u| dir.path().join(u))).current_dir(dir.path());
    let result = cmd.output().map_err(|e| fail(format!("cannot run it ({e}); install a C compiler or name one")))?;
    if !result.status.success() {
        let stderr = String::from_utf8_lossy(&result.stderr);
        let first: Vec<&str> = stderr.lines().take(12).collect();
        return Err(fail(format!("compiling the FMU failed ({}):\n{}", result.status, first.join("\n"))));
    }
    std::fs::read(&out).map_err(|e| fail(format!("cannot read {} ({e})", Path::new(output).display())))
}

/// The zip archive of `files` (deflated).
fn zip(files: &[(String, Vec<u8>)]) -> zip::result::ZipResult<Vec<u8>> {
    let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    for (name, bytes) in files {
        w.start_file(name.as_str(), options)?;
        w.write_all(bytes)?;
    }
    Ok(w.finish()?.into_inner())
}

/// The FMI 2.0 co-simulation functions over `{p}_controller.c`; `{p}`, `{P}`, `{R}`, `{guid}` and
/// `{version}` are filled in.
const WRAPPER: &str = r#"/* {p}_fmu.c: FMI 2.0 co-simulation interface of {p}_controller.c; generated by quell {version}.
 * Value references: y[i] = i - 1, g[i] = M + i - 1, u_f[i] = 2M + i - 1, u[i] = 3M + i - 1.
 * fmi2DoStep(t, h) takes the samples in [t, t + h) with the inputs last set, then reports the
 * outputs of the next sample (they do not depend on that sample's inputs). */
#include <string.h>
#include "fmi2Functions.h"
#include "{p}_controller.h"

#define {P}_FMU_GUID "{guid}"

typedef struct {
    {p}_state state;            /* the controller before sample k */
    {p}_state ahead;            /* scratch: state stepped once, to read sample k's outputs */
    fmi2Real input[2 * {P}_M];  /* y, then g: held from the last fmi2SetReal */
    fmi2Real output[2 * {P}_M]; /* u_f(k), then u(k) */
    fmi2Real start;             /* time of sample 0 */
    double k;                   /* samples taken (a whole number, exact in double up to 2^53) */
    fmi2CallbackFunctions functions;
    char *name;
} {p}_fmu;

static void {p}_log({p}_fmu *f, fmi2String name, fmi2Status status, const char *message, double a, double b)
{
    if (f->functions.logger)
        f->functions.logger(f->functions.componentEnvironment, name, status, "logStatusError", message, a, b);
}

/* Sample k's outputs: one step of a copy of the state (with any inputs: u_f(k) and u(k) do not
 * depend on y(k) or g(k)). */
static void {p}_outputs({p}_fmu *f)
{
    {R} zero[{P}_M], u_f[{P}_M], u[{P}_M];
    for (unsigned i = 0; i < {P}_M; i++)
        zero[i] = 0;
    f->ahead = f->state;
    {p}_step(&f->ahead, zero, zero, u_f);
    {p}_command(&f->ahead, u);
    for (unsigned i = 0; i < {P}_M; i++) {
        f->output[i] = u_f[i];
        f->output[{P}_M + i] = u[i];
    }
}

static void {p}_restart({p}_fmu *f)
{
    {p}_init(&f->state);
    for (unsigned i = 0; i < 2 * {P}_M; i++)
        f->input[i] = 0;
    f->k = 0;
    {p}_outputs(f);
}

static double {p}_abs(double x) { return x < 0 ? -x : x; }

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories, const fmi2String categories[])
{
    (void)c; (void)loggingOn; (void)nCategories; (void)categories;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn)
{
    (void)fmuResourceLocation; (void)visible; (void)loggingOn;
    if (!functions || !functions->allocateMemory || !functions->freeMemory)
        return NULL;
    fmi2String name = instanceName ? instanceName : "{p}";
    if (fmuType != fmi2CoSimulation || !fmuGUID || strcmp(fmuGUID, {P}_FMU_GUID) != 0) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, name, fmi2Error, "logStatusError",
                              fmuType != fmi2CoSimulation
                                  ? "this FMU is co-simulation only; instantiate it as fmi2CoSimulation"
                                  : "GUID %s does not match this FMU's " {P}_FMU_GUID "; its modelDescription.xml belongs to another build",
                              fmuGUID ? fmuGUID : "(null)");
        return NULL;
    }
    {p}_fmu *f = ({p}_fmu *)functions->allocateMemory(1, sizeof({p}_fmu));
    if (!f)
        return NULL;
    f->functions = *functions;
    size_t len = strlen(name);
    f->name = (char *)functions->allocateMemory(len + 1, 1);
    if (!f->name) {
        functions->freeMemory(f);
        return NULL;
    }
    memcpy(f->name, name, len + 1);
    f->start = 0;
    {p}_restart(f);
    return f;
}

void fmi2FreeInstance(fmi2Component c)
{
    {p}_fmu *f = ({p}_fmu *)c;
    if (!f)
        return;
    f->functions.freeMemory(f->name);
    f->functions.freeMemory(f);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
    (({p}_fmu *)c)->start = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { {p}_outputs(({p}_fmu *)c); return fmi2OK; }
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) { {p}_restart(({p}_fmu *)c); return fmi2OK; }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    {p}_fmu *f = ({p}_fmu *)c;
    for (size_t j = 0; j < nvr; j++) {
        if (vr[j] >= 4 * {P}_M) {
            {p}_log(f, f->name, fmi2Error, "fmi2GetReal: no variable has value reference %g (0 to %g)", vr[j], 4 * {P}_M - 1);
            return fmi2Error;
        }
        value[j] = vr[j] < 2 * {P}_M ? f->input[vr[j]] : f->output[vr[j] - 2 * {P}_M];
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[])
{
    {p}_fmu *f = ({p}_fmu *)c;
    for (size_t j = 0; j < nvr; j++) {
        if (vr[j] >= 2 * {P}_M) {
            {p}_log(f, f->name, fmi2Error, "fmi2SetReal: value reference %g is not an input (y and g are 0 to %g)", vr[j], 2 * {P}_M - 1);
            return fmi2Error;
        }
        if (!(value[j] - value[j] == 0)) {
            {p}_log(f, f->name, fmi2Error, "fmi2SetReal: input %g is %g; y and g must be finite", vr[j], value[j]);
            return fmi2Error;
        }
    }
    for (size_t j = 0; j < nvr; j++)
        f->input[vr[j]] = value[j];
    return fmi2OK;
}

static fmi2Status {p}_none(fmi2Component c, const char *what)
{
    {p}_fmu *f = ({p}_fmu *)c;
    if (f)
        {p}_log(f, f->name, fmi2Error, what, 0, 0);
    return fmi2Error;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
{ (void)vr; (void)value; return nvr ? {p}_none(c, "fmi2GetInteger: this FMU has no Integer variables") : fmi2OK; }
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[])
{ (void)vr; (void)value; return nvr ? {p}_none(c, "fmi2GetBoolean: this FMU has no Boolean variables") : fmi2OK; }
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{ (void)vr; (void)value; return nvr ? {p}_none(c, "fmi2GetString: this FMU has no String variables") : fmi2OK; }
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[])
{ (void)vr; (void)value; return nvr ? {p}_none(c, "fmi2SetInteger: this FMU has no Integer variables") : fmi2OK; }
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[])
{ (void)vr; (void)value; return nvr ? {p}_none(c, "fmi2SetBoolean: this FMU has no Boolean variables") : fmi2OK; }
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{ (void)vr; (void)value; return nvr ? {p}_none(c, "fmi2SetString: this FMU has no String variables") : fmi2OK; }

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s)
{ (void)s; return {p}_none(c, "fmi2GetFMUstate: not supported (canGetAndSetFMUstate is false)"); }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s)
{ (void)s; return {p}_none(c, "fmi2SetFMUstate: not supported (canGetAndSetFMUstate is false)"); }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s)
{ (void)s; return {p}_none(c, "fmi2FreeFMUstate: not supported (canGetAndSetFMUstate is false)"); }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size)
{ (void)s; (void)size; return {p}_none(c, "fmi2SerializedFMUstateSize: not supported (canSerializeFMUstate is false)"); }
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte bytes[], size_t size)
{ (void)s; (void)bytes; (void)size; return {p}_none(c, "fmi2SerializeFMUstate: not supported (canSerializeFMUstate is false)"); }
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *s)
{ (void)s; (void)bytes; (void)size; return {p}_none(c, "fmi2DeSerializeFMUstate: not supported (canSerializeFMUstate is false)"); }
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu, const fmi2ValueReference z[],
                                        size_t nz, const fmi2Real dz[], fmi2Real du[])
{ (void)u; (void)nu; (void)z; (void)nz; (void)dz; (void)du; return {p}_none(c, "fmi2GetDirectionalDerivative: not supported"); }
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[])
{ (void)vr; (void)order; (void)value; return nvr ? {p}_none(c, "fmi2SetRealInputDerivatives: not supported (the inputs are sampled)") : fmi2OK; }
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[])
{ (void)vr; (void)order; (void)value; return nvr ? {p}_none(c, "fmi2GetRealOutputDerivatives: not supported") : fmi2OK; }

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    {p}_fmu *f = ({p}_fmu *)c;
    const double T = {P}_SAMPLE_TIME, now = f->start + f->k * T;
    /* The same relative tolerance as the library's whole-number-of-samples test. */
    const double n = h / T, steps = n > 0 && n < 1e15 ? (double)(long long)(n + 0.5) : 0;
    if (steps < 1 || {p}_abs(n - steps) > 1e-9 * steps) {
        {p}_log(f, f->name, fmi2Error, "fmi2DoStep: communication step h = %g s is not a whole number of samples of T_s = %g s", h, T);
        return fmi2Error;
    }
    if ({p}_abs(t - now) > 1e-9 * (T + {p}_abs(now))) {
        {p}_log(f, f->name, fmi2Error, "fmi2DoStep: at t = %g s, but the controller's next sample is at %g s", t, now);
        return fmi2Error;
    }
    {R} y[{P}_M], g[{P}_M], u_f[{P}_M];
    for (unsigned i = 0; i < {P}_M; i++) {
        y[i] = ({R})f->input[i];
        g[i] = ({R})f->input[{P}_M + i];
    }
    for (double j = 0; j < steps; j++) {
        /* Inputs are the same at every j, so a refused reading (1) is refused at j = 0. */
        const int refused = {p}_step(&f->state, y, g, u_f);
        if (refused == 1) {
            {p}_log(f, f->name, fmi2Error, "fmi2DoStep: an input (y or g) is NaN or beyond +-%g; the step was refused", (double){P}_INPUT_BOUND, 0.0);
            return fmi2Error;
        }
        if (refused) {
            {p}_log(f, f->name, fmi2Error, "fmi2DoStep: the controller's state is no longer finite; call fmi2Reset", 0.0, 0.0);
            return fmi2Error;
        }
    }
    f->k += steps;
    {p}_outputs(f);
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) { return {p}_none(c, "fmi2CancelStep: fmi2DoStep never runs asynchronously"); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{ (void)s; (void)value; return {p}_none(c, "fmi2GetStatus: fmi2DoStep never returns fmi2Pending"); }
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    if (s == fmi2LastSuccessfulTime) {
        {p}_fmu *f = ({p}_fmu *)c;
        *value = f->start + f->k * {P}_SAMPLE_TIME;
        return fmi2OK;
    }
    (void)value;
    return {p}_none(c, "fmi2GetRealStatus: only fmi2LastSuccessfulTime");
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{ (void)s; (void)value; return {p}_none(c, "fmi2GetIntegerStatus: no integer status"); }
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{ (void)s; (void)value; return {p}_none(c, "fmi2GetBooleanStatus: no boolean status"); }
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{ (void)s; (void)value; return {p}_none(c, "fmi2GetStringStatus: no string status"); }
"#;

#[cfg(test)]
mod tests {
    use super::*;

    /// The GUID is FNV-1a (128 bits) of the texts in turn, as a braced 8-4-4-4-12 GUID: the
    /// published vectors of "a" (d228cb696f1a8caf78912b704e4a8964) and "foobar"
    /// (343e1662793c64bf6f0d3597ba446f18, here split over two texts), so exported FMUs keep their GUIDs.
    #[test]
    fn the_guid_is_fnv1a_128_of_the_texts() {
        assert_eq!(guid(&["a"]), "{d228cb69-6f1a-8caf-7891-2b704e4a8964}");
        assert_eq!(guid(&["foo", "bar"]), "{343e1662-793c-64bf-6f0d-3597ba446f18}");
    }
}
