//! The generated C controller: it compiles warning-free as C99, uses no dynamic memory,
//! no libm and no writable globals, and it is the same controller as the Rust `Controller`.
//! gcc and binutils (nm) are required.
#![allow(non_snake_case)]

mod c_harness;
mod common;

use c_harness::{tool, write_code, CController, TempDir, STRICT};
use common::{paper_signals, Rng};
use quell::export::{generate, generate_fmu, CCode, ExportError, ExportOptions, FmiVersion, Precision};
use quell::scenario::Scenario;
use quell::sim::{Loop, Outcome, Run, RunSettings, SampledController, SimResult, Watched};
use quell::{Controller, ControllerError, Design};

fn example(name: &str) -> (Scenario, Design) {
    let path = format!("{}/../../examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let s = Scenario::from_path(std::path::Path::new(&path)).unwrap();
    let d = s.design().unwrap();
    (s, d)
}

fn options(prefix: &str, precision: Precision) -> ExportOptions {
    ExportOptions { prefix: prefix.into(), precision, scenario_name: Some("test".into()), ..ExportOptions::default() }
}

fn export(d: &Design, T: f64, prefix: &str, precision: Precision) -> CCode {
    generate(d, T, &options(prefix, precision)).unwrap()
}

/// max_k ‖a(k) − b(k)‖_∞ / max_k ‖b(k)‖_∞ over two runs stored row after row.
fn relative_deviation(a: &[f64], b: &[f64]) -> f64 {
    let dev = a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    let peak = b.iter().fold(0.0f64, |m, y| m.max(y.abs()));
    dev / peak
}

/// Beyond the strict flags, those firmware projects commonly add; the code must pass them too.
const EXTRA: &[&str] = &[
    "-Wconversion",
    "-Wdouble-promotion",
    "-Wshadow",
    "-Wcast-qual",
    "-Wstrict-prototypes",
    "-Wmissing-prototypes",
    "-Wundef",
    "-Wvla",
];

#[test]
fn generated_code_is_warning_free_c99_without_malloc_libm_or_writable_globals() {
    let (_, d) = example("paper");
    for precision in [Precision::F64, Precision::F32] {
        let code = export(&d, 1e-3, "quell", precision);
        let dir = TempDir::new("strict");
        write_code(&code, &dir.0);
        for opt in ["-O0", "-O2"] {
            let mut args: Vec<&str> = STRICT.iter().chain(EXTRA).copied().collect();
            args.extend([opt, "-c", "quell_controller.c", "-o", "c.o"]);
            tool("gcc", &args, &dir.0);
            // Undefined symbols: none but what GCC requires of every environment (it may turn the
            // zeroing and copying loops into calls); no libm, no malloc.
            let undefined = tool("nm", &["-u", "c.o"], &dir.0);
            for sym in undefined.split_whitespace().filter(|s| *s != "U") {
                assert!(["memset", "memcpy", "memmove"].contains(&sym), "{precision:?} {opt}: refers to {sym}");
            }
            // Every object is read-only or code: no .data or .bss symbol.
            let symbols = tool("nm", &["c.o"], &dir.0);
            for line in symbols.lines() {
                let kind = line.split_whitespace().nth(1).unwrap_or("");
                assert!(!["d", "D", "b", "B", "C"].contains(&kind), "{precision:?} {opt}: writable symbol: {line}");
            }
            if opt == "-O0" {
                // The header's byte count of constants = the sizes of the static const objects.
                let sized = tool("nm", &["-S", "c.o"], &dir.0);
                let bytes: usize = sized
                    .lines()
                    .filter_map(|l| {
                        let f: Vec<&str> = l.split_whitespace().collect();
                        (f.len() == 4 && f[2] == "r").then(|| usize::from_str_radix(f[1], 16).unwrap())
                    })
                    .sum();
                assert_eq!(bytes, code.constant_bytes, "{precision:?}: constants");
                assert!(code.header.contains(&format!("{} bytes of constants", code.constant_bytes)));
            }
        }
        // The header's state figure is sizeof(quell_state).
        let c = CController::build(&code, "quell", precision, (2, 8, 3), "-O0");
        assert_eq!(c.state_size, code.state_bytes, "{precision:?}: state");
        assert!(code.header.contains(&format!("{} bytes of state", code.state_bytes)));
    }
}

/// The FMU's C (FMI 2.0 and 3.0, double and float) is warning-free C99 under -Wall -Wextra
/// -pedantic: the sources the archive holds, compiled against the headers it ships (2.0) or the
/// importer supplies (3.0: the FMI 3.0.2 headers quell builds its binaries with).
#[test]
fn fmu_sources_are_warning_free_c99() {
    let (_, d) = example("three-channel");
    for version in [FmiVersion::V2, FmiVersion::V3] {
        for precision in [Precision::F64, Precision::F32] {
            let dir = TempDir::new("fmu-strict");
            fmu_sources(&d, precision, version, &dir);
            let mut args: Vec<&str> = STRICT.to_vec();
            args.extend(["-O2", "-c", "ctrl_fmu.c", "-o", "fmu.o"]);
            tool("gcc", &args, &dir.0);
        }
    }
}

/// Writes into `dir` the sources of `d`'s FMU at T_s = 0.05 with the prefix `ctrl` (those the
/// archive holds, and for 3.0 the FMI 3.0.2 headers the importer supplies); returns its GUID.
fn fmu_sources(d: &Design, precision: Precision, version: FmiVersion, dir: &TempDir) -> String {
    use std::io::Read as _;
    const FMI3: [(&str, &str); 3] = [
        ("fmi3Functions.h", include_str!("../src/export/fmi3/fmi3Functions.h")),
        ("fmi3FunctionTypes.h", include_str!("../src/export/fmi3/fmi3FunctionTypes.h")),
        ("fmi3PlatformTypes.h", include_str!("../src/export/fmi3/fmi3PlatformTypes.h")),
    ];
    let fmu = generate_fmu(d, 0.05, &options("ctrl", precision), None, version).unwrap();
    let mut archive = zip::ZipArchive::new(std::io::Cursor::new(&fmu.bytes)).unwrap();
    for i in 0..archive.len() {
        let mut file = archive.by_index(i).unwrap();
        if let Some(name) = file.name().unwrap().strip_prefix("sources/").map(str::to_string) {
            let mut text = String::new();
            file.read_to_string(&mut text).unwrap();
            std::fs::write(dir.0.join(name), text).unwrap();
        }
    }
    if version == FmiVersion::V3 {
        for (name, text) in FMI3 {
            std::fs::write(dir.0.join(name), text).unwrap();
        }
    }
    let md = &fmu.model_description;
    let key = if version == FmiVersion::V3 { "instantiationToken=\"" } else { "guid=\"" };
    let start = md.find(key).unwrap() + key.len();
    md[start..start + md[start..].find('"').unwrap()].to_string()
}

/// The C API and both FMUs given NULL pointers, and the FMUs called out of their life cycle (a
/// step after Terminate, the start time changed while stepping, a NaN start time): each call is
/// refused with its status and, where there is an instance to log through, a reason; nothing
/// crashes. They had segfaulted on NULL, and accepted Exit after Terminate, a start time moved
/// from 2 s to 1002 s while stepping, and a NaN start time.
#[test]
fn null_arguments_and_calls_out_of_order_are_refused() {
    let (_, d) = example("three-channel");
    let checks = r#"
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
static char last[512];
static int fails;
#define EXPECT(call, status, text)                                                                 \
    do {                                                                                           \
        last[0] = 0;                                                                               \
        int got_ = (int)(call);                                                                    \
        if (got_ != (int)(status) || !strstr(last, text)) {                                        \
            printf("line %d: %s gave %d, logged \"%s\"; expected %d, \"%s\"\n", __LINE__, #call, got_, \
                   last, (int)(status), text);                                                     \
            fails++;                                                                               \
        }                                                                                          \
    } while (0)
"#;
    let fmi2 = r#"
#include "fmi2Functions.h"
#include "ctrl_controller.h"
static void logger(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c, fmi2String f, ...)
{
    va_list ap;
    (void)e; (void)n; (void)s; (void)c;
    va_start(ap, f);
    vsnprintf(last, sizeof last, f, ap);
    va_end(ap);
}
int main(void)
{
    const fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2ValueReference vr[1] = {0};
    fmi2Real value[1] = {0}, nan = strtod("nan", NULL);
    ctrl_state s;
    double y[CTRL_M] = {0}, u[CTRL_M];
    /* The C API. */
    ctrl_init(NULL);
    ctrl_command(NULL, u);
    ctrl_init(&s);
    ctrl_command(&s, NULL);
    EXPECT(ctrl_step(NULL, y, y, u), 4, "");
    EXPECT(ctrl_step(&s, NULL, y, u), 4, "");
    EXPECT(ctrl_step(&s, y, NULL, u), 4, "");
    EXPECT(ctrl_step(&s, y, y, NULL), 4, "");
    EXPECT(ctrl_step(&s, y, y, u), 0, "");
    /* No instance. */
    EXPECT(fmi2SetupExperiment(NULL, 0, 0, 0, 0, 0), fmi2Error, "");
    EXPECT(fmi2EnterInitializationMode(NULL), fmi2Error, "");
    EXPECT(fmi2ExitInitializationMode(NULL), fmi2Error, "");
    EXPECT(fmi2Terminate(NULL), fmi2Error, "");
    EXPECT(fmi2Reset(NULL), fmi2Error, "");
    EXPECT(fmi2GetReal(NULL, vr, 1, value), fmi2Error, "");
    EXPECT(fmi2SetReal(NULL, vr, 1, value), fmi2Error, "");
    EXPECT(fmi2DoStep(NULL, 0, 0.05, fmi2True), fmi2Error, "");
    EXPECT(fmi2GetRealStatus(NULL, fmi2LastSuccessfulTime, value), fmi2Error, "");
    fmi2FreeInstance(NULL);
    fmi2Component c = fmi2Instantiate("c", fmi2CoSimulation, GUID, "", &cb, fmi2False, fmi2False);
    if (!c)
        return 2;
    EXPECT(fmi2GetReal(c, NULL, 1, value), fmi2Error, "fmi2GetReal: a NULL array for 1 values");
    EXPECT(fmi2SetReal(c, vr, 1, NULL), fmi2Error, "fmi2SetReal: a NULL array for 1 values");
    EXPECT(fmi2GetReal(c, NULL, 0, NULL), fmi2OK, "");
    EXPECT(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, NULL), fmi2Error, "a NULL value pointer");
    EXPECT(fmi2SetupExperiment(c, 0, 0, nan, 0, 0), fmi2Error, "fmi2SetupExperiment: startTime = nan; the start time must be finite");
    EXPECT(fmi2ExitInitializationMode(c), fmi2Error, "fmi2ExitInitializationMode: not allowed when the FMU is instantiated (after Instantiate or Reset); only when it is in initialization mode");
    /* At 1e17 doubles are 16 s apart: every sample's time was 1e17 and the steps went on. */
    EXPECT(fmi2SetupExperiment(c, 0, 0, 1e17, 0, 0), fmi2Error, "fmi2SetupExperiment: startTime = 1e+17 s: doubles there are 16 s apart, more than a thousandth of T_s = 0.05 s, so the samples' times would blur; start below 2.74878e+11 s in magnitude (0 is usual)");
    EXPECT(fmi2SetupExperiment(c, 0, 0, 2e11, 0, 0), fmi2OK, "");
    EXPECT(fmi2SetupExperiment(c, 0, 0, 2, fmi2True, 1), fmi2Error, "fmi2SetupExperiment: stopTime = 1 s is before startTime = 2 s");
    EXPECT(fmi2SetupExperiment(c, 0, 0, 2, fmi2True, 2.15), fmi2OK, "");
    EXPECT(fmi2EnterInitializationMode(c), fmi2OK, "");
    EXPECT(fmi2SetupExperiment(c, 0, 0, 0, 0, 0), fmi2Error, "the start time is set before initialization only");
    EXPECT(fmi2ExitInitializationMode(c), fmi2OK, "");
    /* FMI 2.0: past a defined stopTime the FMU returns fmi2Error (it had stepped on). */
    EXPECT(fmi2DoStep(c, 2, 0.2, fmi2True), fmi2Error, "fmi2DoStep: the step to t + h = 2.2 s passes stopTime = 2.15 s set at initialization; stop there, or set a later stopTime");
    /* A step of 1e12 samples ran for days: more than 1e8 samples are refused. */
    EXPECT(fmi2DoStep(c, 2, 5e10, fmi2True), fmi2Error, "fmi2DoStep: communication step h = 5e+10 s is 1000000000000 samples of T_s = 0.05 s; at most 1e+08 are taken in one step: take several shorter steps");
    EXPECT(fmi2DoStep(c, 2, 0, fmi2True), fmi2Error, "fmi2DoStep: communication step h = 0 s: expected h > 0, a whole number of samples of T_s = 0.05 s");
    EXPECT(fmi2DoStep(c, 2, 0.1, fmi2True), fmi2OK, "");
    EXPECT(fmi2SetupExperiment(c, 0, 0, 1000, 0, 0), fmi2Error, "the start time is set before initialization only");
    EXPECT(fmi2EnterInitializationMode(c), fmi2Error, "fmi2EnterInitializationMode: not allowed when the FMU is in step mode");
    EXPECT(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, value), fmi2OK, "");
    if (value[0] != 2.1)
        printf("time %g after a step from 2 s, not 2.1\n", value[0]), fails++;
    EXPECT(fmi2Terminate(c), fmi2OK, "");
    EXPECT(fmi2Terminate(c), fmi2Error, "fmi2Terminate: not allowed when the FMU is terminated");
    EXPECT(fmi2ExitInitializationMode(c), fmi2Error, "not allowed when the FMU is terminated (Reset, then initialize again)");
    EXPECT(fmi2DoStep(c, 2.1, 0.05, fmi2True), fmi2Error, "fmi2DoStep: the FMU is not in step mode");
    EXPECT(fmi2Reset(c), fmi2OK, "");
    EXPECT(fmi2EnterInitializationMode(c), fmi2OK, "");
    EXPECT(fmi2ExitInitializationMode(c), fmi2OK, "");
    EXPECT(fmi2DoStep(c, 0, 0.05, fmi2True), fmi2OK, "");
    fmi2FreeInstance(c);
    /* At a start of 1e11 s a relative tolerance of 1e-9 was 100 s: a step 1 s off its sample and
     * one past the stop time were taken. */
    c = fmi2Instantiate("c", fmi2CoSimulation, GUID, "", &cb, fmi2False, fmi2False);
    if (!c)
        return 2;
    EXPECT(fmi2SetupExperiment(c, 0, 0, 1e11, fmi2True, 1e11 + 0.1), fmi2OK, "");
    EXPECT(fmi2EnterInitializationMode(c), fmi2OK, "");
    EXPECT(fmi2ExitInitializationMode(c), fmi2OK, "");
    EXPECT(fmi2DoStep(c, 1e11 + 1, 0.05, fmi2True), fmi2Error, "fmi2DoStep: at t = 100000000001 s, but the controller's next sample is at 100000000000 s");
    EXPECT(fmi2DoStep(c, 1e11, 0.1, fmi2True), fmi2OK, "");
    EXPECT(fmi2DoStep(c, 1e11 + 0.1, 0.05, fmi2True), fmi2Error, "fmi2DoStep: the step to t + h = 100000000000.15 s passes stopTime = 100000000000.1 s");
    fmi2FreeInstance(c);
    /* From a Unix-epoch start, two masters run 20,000 steps: one adds h to t (drifting by its
     * rounding: refused from step 10,487 under a tolerance of T_s/100), one computes t = t0 + n h
     * and h = t_next - t (0.0500001192, refused as no whole number of samples). */
    for (int accumulate = 0; accumulate < 2; accumulate++) {
        c = fmi2Instantiate("c", fmi2CoSimulation, GUID, "", &cb, fmi2False, fmi2False);
        if (!c)
            return 2;
        EXPECT(fmi2SetupExperiment(c, 0, 0, 1.7e9, 0, 0), fmi2OK, "");
        EXPECT(fmi2EnterInitializationMode(c), fmi2OK, "");
        EXPECT(fmi2ExitInitializationMode(c), fmi2OK, "");
        double t = 1.7e9;
        for (int n = 0; n < 20000; n++) {
            const double next = accumulate ? t + 0.05 : 1.7e9 + (n + 1) * 0.05;
            const double h = accumulate ? 0.05 : next - t;
            if (fmi2DoStep(c, t, h, fmi2True) != fmi2OK) {
                printf("master %d refused at step %d, t = %.17g: %s\n", accumulate, n, t, last);
                fails++;
                break;
            }
            t = next;
        }
        fmi2FreeInstance(c);
    }
    /* Inputs of +-1e99 alternating overflow the state within some steps: every step reported OK
     * has finite outputs, and the step that fails leaves NaN (they had been the stack's contents,
     * with fmi2OK), at one sample a step and at ten, where samples before the failing one are taken. */
    for (int many = 0; many < 2; many++) {
        const double h = many ? 0.5 : 0.05;
        c = fmi2Instantiate("c", fmi2CoSimulation, GUID, "", &cb, fmi2False, fmi2False);
        if (!c)
            return 2;
        EXPECT(fmi2EnterInitializationMode(c), fmi2OK, "");
        EXPECT(fmi2ExitInitializationMode(c), fmi2OK, "");
        /* Value references: y = 0 .. M - 1, then g, u_f (from 2M) and u. */
        fmi2ValueReference ys[CTRL_M], outs[2 * CTRL_M];
        fmi2Real out[2 * CTRL_M], spike[CTRL_M];
        for (unsigned i = 0; i < 2 * CTRL_M; i++)
            outs[i] = 2 * CTRL_M + i;
        for (unsigned i = 0; i < CTRL_M; i++)
            ys[i] = i;
        char why[512] = "";
        int failed = 0;
        for (int n = 0; n < 100000 && !failed; n++) {
            for (unsigned i = 0; i < CTRL_M; i++)
                spike[i] = (n + i) % 2 ? 1e99 : -1e99;
            EXPECT(fmi2SetReal(c, ys, CTRL_M, spike), fmi2OK, "");
            last[0] = 0;
            failed = fmi2DoStep(c, n * h, h, fmi2True) != fmi2OK;
            snprintf(why, sizeof why, "%s", last);
            EXPECT(fmi2GetReal(c, outs, 2 * CTRL_M, out), fmi2OK, "");
            for (int i = 0; i < 2 * CTRL_M; i++)
                if (failed ? out[i] == out[i] : out[i] - out[i] != 0)
                    printf("h = %g, step %d (%s): output %d is %g\n", h, n, failed ? "failed" : "OK", i, out[i]), fails++;
        }
        const char *said = many ? "fmi2DoStep: the controller's" : "fmi2DoStep: the controller's outputs at the next sample, t = ";
        if (!failed || !strstr(why, said))
            printf("h = %g: no step failed on an overflowing state (%s)\n", h, why), fails++;
        /* A retry is told the earlier step failed (it had been told of drift: the failed step's
         * samples were counted); Reset starts over. */
        last[0] = 0;
        if (fmi2DoStep(c, 0.0, h, fmi2True) == fmi2OK || !strstr(last, "an earlier step failed"))
            printf("h = %g: a retry after the failure was not refused as failed (%s)\n", h, last), fails++;
        EXPECT(fmi2Reset(c), fmi2OK, "");
        EXPECT(fmi2EnterInitializationMode(c), fmi2OK, "");
        EXPECT(fmi2ExitInitializationMode(c), fmi2OK, "");
        EXPECT(fmi2DoStep(c, 0.0, h, fmi2True), fmi2OK, "");
        fmi2FreeInstance(c);
    }
    return fails;
}
"#;
    let fmi3 = r#"
#include "fmi3Functions.h"
static void logger(fmi3InstanceEnvironment e, fmi3Status s, fmi3String c, fmi3String message)
{
    (void)e; (void)s; (void)c;
    snprintf(last, sizeof last, "%s", message);
}
int main(void)
{
    fmi3ValueReference vr[1] = {0};
    fmi3Float64 value[1] = {0}, t, nan = strtod("nan", NULL);
    fmi3Boolean event, terminate, early;
    EXPECT(fmi3EnterInitializationMode(NULL, 0, 0, 0, 0, 0), fmi3Error, "");
    EXPECT(fmi3ExitInitializationMode(NULL), fmi3Error, "");
    EXPECT(fmi3Terminate(NULL), fmi3Error, "");
    EXPECT(fmi3Reset(NULL), fmi3Error, "");
    EXPECT(fmi3GetFloat64(NULL, vr, 1, value, 1), fmi3Error, "");
    EXPECT(fmi3SetFloat64(NULL, vr, 1, value, 1), fmi3Error, "");
    EXPECT(fmi3DoStep(NULL, 0, 0.05, fmi3True, &event, &terminate, &early, &t), fmi3Error, "");
    fmi3FreeInstance(NULL);
    fmi3Instance c = fmi3InstantiateCoSimulation("c", GUID, "", 0, 0, 0, 0, NULL, 0, NULL, logger, NULL);
    if (!c)
        return 2;
    EXPECT(fmi3GetFloat64(c, NULL, 1, value, 1), fmi3Error, "fmi3GetFloat64: a NULL array for 1 values");
    EXPECT(fmi3SetFloat64(c, vr, 1, NULL, 1), fmi3Error, "fmi3SetFloat64: a NULL array for 1 values");
    EXPECT(fmi3EnterInitializationMode(c, 0, 0, nan, 0, 0), fmi3Error, "startTime = nan; the start time must be finite");
    EXPECT(fmi3ExitInitializationMode(c), fmi3Error, "only when it is in initialization mode");
    EXPECT(fmi3EnterInitializationMode(c, 0, 0, 2, 0, 0), fmi3OK, "");
    EXPECT(fmi3ExitInitializationMode(c), fmi3OK, "");
    EXPECT(fmi3DoStep(c, 2, 0.05, fmi3True, NULL, &terminate, &early, &t), fmi3Error, "fmi3DoStep: a NULL output pointer");
    EXPECT(fmi3DoStep(c, 2, 5e10, fmi3True, &event, &terminate, &early, &t), fmi3Error, "at most 1e+08 are taken in one step");
    EXPECT(fmi3DoStep(c, 2, 0, fmi3True, &event, &terminate, &early, &t), fmi3Error, "expected h > 0, a whole number of samples");
    EXPECT(fmi3DoStep(c, 2, 0.05, fmi3True, &event, &terminate, &early, &t), fmi3OK, "");
    EXPECT(fmi3EnterInitializationMode(c, 0, 0, 50, 0, 0), fmi3Error, "the start time is set before initialization only");
    EXPECT(fmi3Terminate(c), fmi3OK, "");
    EXPECT(fmi3ExitInitializationMode(c), fmi3Error, "not allowed when the FMU is terminated");
    EXPECT(fmi3DoStep(c, 2.05, 0.05, fmi3True, &event, &terminate, &early, &t), fmi3Error, "not in step mode");
    if (t != 2.05)
        printf("lastSuccessfulTime %g, not 2.05\n", t), fails++;
    fmi3FreeInstance(c);
    return fails;
}
"#;
    for (version, driver) in [(FmiVersion::V2, fmi2), (FmiVersion::V3, fmi3)] {
        let dir = TempDir::new("fmu-hostile");
        let guid = fmu_sources(&d, Precision::F64, version, &dir);
        let main = format!("#define GUID \"{guid}\"\n{checks}{driver}");
        std::fs::write(dir.0.join("main.c"), main).unwrap();
        let args = [
            "-std=c99",
            "-O1",
            "-D_POSIX_C_SOURCE=200809L",
            "main.c",
            "ctrl_fmu.c",
            "ctrl_controller.c",
            "-o",
            "hostile",
        ];
        tool("gcc", &args, &dir.0);
        // tool() fails the test with the driver's report when a check failed or it crashed.
        tool(&dir.0.join("hostile").display().to_string(), &[], &dir.0);
    }
}

#[test]
fn output_is_deterministic_and_records_the_design() {
    let (s, d) = example("paper");
    let o = ExportOptions { scenario_name: s.name.clone(), ..ExportOptions::default() };
    let a = generate(&d, 1e-3, &o).unwrap();
    let b = generate(&s.design().unwrap(), 1e-3, &o).unwrap();
    assert_eq!(a, b);
    // Whitespace-normalized, so that the alignment of the #defines does not matter.
    let h = &a.header.split_whitespace().collect::<Vec<_>>().join(" ");
    for text in [
        "scenario \"paper-example\"",
        "Sample time T_s = 0.001, in seconds, the plant model's unit of time.",
        concat!("quell ", env!("CARGO_PKG_VERSION")),
        "channel 1: tau = 1 = 1000 samples; channel 2: tau = 3 = 3000 samples",
        "Memory: 1696 bytes of constants (static const), 241240 bytes of state",
        "#define QUELL_M 2",
        "#define QUELL_N 3",
        "#define QUELL_Q 8",
        "#define QUELL_SAMPLE_TIME 0.001",
        "int quell_step(quell_state *s, const double y[QUELL_M], const double g[QUELL_M], double u_f[QUELL_M]);",
        "void quell_command(const quell_state *s, double u[QUELL_M]);",
        "void quell_init(quell_state *s);",
    ] {
        assert!(h.contains(text), "header lacks {text:?}:\n{h}");
    }
    for z in d.observer_eigenvalues().iter().chain(d.decoupled_eigenvalues()) {
        assert!(h.contains(&quell::fmt_complex(z)), "eigenvalue {z} missing");
    }
    assert!(a.header.is_ascii() && a.source.is_ascii());
    // f32: float everywhere, every literal suffixed.
    let f = export(&d, 1e-3, "quell", Precision::F32);
    assert!(f.header.contains("const float y[QUELL_M]") && !f.source.contains("double"));
    assert!(f.state_bytes < a.state_bytes && f.constant_bytes < a.constant_bytes);
}

#[test]
fn the_checks_of_controller_new_with_the_same_messages() {
    let (_, d) = example("paper");
    for T in [0.3, 0.0, f64::NAN, -1.0, 1e-300] {
        let want = Controller::new(&d, T).unwrap_err();
        let got = generate(&d, T, &ExportOptions::default()).unwrap_err();
        assert_eq!(got.to_string(), want.to_string());
        assert!(matches!(got, ExportError::Controller(_)), "{got:?}");
    }
    match generate(&d, 0.3, &ExportOptions::default()) {
        Err(ExportError::Controller(ControllerError::DelayNotMultiple { nearest: Some(nearest), .. })) => {
            // The suggestion is valid: it exports.
            assert!(generate(&d, nearest, &ExportOptions::default()).is_ok());
        }
        other => panic!("unexpected {other:?}"),
    }
    for bad in ["", "1abc", "_q", "a-b", "ä", "a b"] {
        let e = generate(&d, 1e-3, &options(bad, Precision::F64)).unwrap_err();
        assert_eq!(e, ExportError::Prefix { found: bad.into() });
        assert!(e.to_string().starts_with("prefix: expected a C identifier"), "{e}");
    }
    // A constant beyond float's range: c_1 = T_s μ_1 = 1e97 with μ_1 = 1e100.
    let paper = std::fs::read_to_string(format!("{}/../../examples/paper.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let text = paper.replace("mu = [20.0, 30.0]", "mu = [1e100, 30.0]");
    let big = Scenario::from_toml(&text).unwrap().design().unwrap();
    // μ_1 = 1e300: T_s μ_1 = 1e297 > 1e150, where the adaptation gain would round to 0; the
    // controller, and so the generator, refuses it.
    let huge =
        Scenario::from_toml(&paper.replace("mu = [20.0, 30.0]", "mu = [1e300, 30.0]")).unwrap().design().unwrap();
    let e = generate(&huge, 1e-3, &ExportOptions::default()).unwrap_err();
    assert!(matches!(&e, ExportError::Controller(ControllerError::AdaptationStepTooLarge { channel: 0, .. })), "{e:?}");
    let e = generate(&big, 1e-3, &options("quell", Precision::F32)).unwrap_err();
    assert!(matches!(&e, ExportError::F32Range { what, .. } if what == "quell_c[0]"), "{e:?}");
    assert!(e.to_string().starts_with("precision f32: quell_c[0] = 1e97") && e.to_string().ends_with("use f64"), "{e}");
    assert!(generate(&big, 1e-3, &options("quell", Precision::F64)).is_ok());
    // A discretization that overflows: T_s = 1e100 s (the case used before, a reference filter pole
    // at -6e300, is now refused by the design: its rates may span at most 1/√ε).
    let wild =
        Scenario::from_toml(&text.replace("[[-1.0, -6.0], [-9.0]]", "[[-1.0, -6e300], [-9.0]]")).unwrap().design();
    assert!(
        matches!(&wild, Err(quell::DesignError::PoleOutOfSpan { key, .. }) if key == "design.reference_filter_poles[0]")
    );
    // Controller::new refuses it, and so the generator.
    let e = generate(&big, 1e100, &ExportOptions::default()).unwrap_err();
    assert!(matches!(&e, ExportError::Controller(ControllerError::NotFinite { .. })), "{e:?}");
    assert!(e.to_string().starts_with("simulation.sample_time: the observers' [Φ_z Γ_z]"), "{e}");
    assert_eq!(e.to_string(), Controller::new(&big, 1e100).unwrap_err().to_string());
}

/// Drives the Rust and the C controller with the same inputs; returns the relative deviations of
/// u_f, u and η̂ (see `relative_deviation`).
fn compare(d: &Design, T: f64, c: &mut CController, inputs: impl Iterator<Item = (Vec<f64>, Vec<f64>)>) -> [f64; 3] {
    let mut rust = Controller::new(d, T).unwrap();
    let (mut a, mut b) = ([vec![], vec![], vec![]], [vec![], vec![], vec![]]);
    for (y, g) in inputs {
        a[0].extend_from_slice(c.step(&y, &g));
        b[0].extend_from_slice(rust.step(&y, &g).unwrap());
        a[1].extend_from_slice(c.command());
        b[1].extend_from_slice(rust.command());
        a[2].extend_from_slice(c.eta());
        b[2].extend_from_slice(rust.eta());
    }
    [0, 1, 2].map(|i| relative_deviation(&a[i], &b[i]))
}

/// Uniform random y, g in [−2, 2) for `steps` samples.
fn random_inputs(m: usize, steps: usize, seed: u64) -> impl Iterator<Item = (Vec<f64>, Vec<f64>)> {
    let mut rng = Rng(seed);
    (0..steps).map(move |_| {
        let y = (0..m).map(|_| rng.uniform(-2.0, 2.0)).collect();
        let g = (0..m).map(|_| rng.uniform(-2.0, 2.0)).collect();
        (y, g)
    })
}

#[test]
fn same_controller_as_rust_on_random_sequences() {
    // 100,000 steps of random y, g, at -O0 and -O2; and the other examples' shapes (σ up to 2, m = 3,
    // complex filter poles, one channel). Bound: 1e-12 relative to the run's peak (and the same
    // bits on x86-64).
    let (_, paper) = example("paper");
    for opt in ["-O0", "-O2"] {
        let code = export(&paper, 1e-3, "quell", Precision::F64);
        let mut c = CController::build(&code, "quell", Precision::F64, (2, 8, 3), opt);
        let dev = compare(&paper, 1e-3, &mut c, random_inputs(2, 100_000, 1));
        println!("paper {opt}: u_f {:.1e}, u {:.1e}, eta {:.1e}", dev[0], dev[1], dev[2]);
        assert!(dev.iter().all(|&e| e <= 1e-12), "paper {opt}: {dev:?}");
        // On x86-64 (SSE2, no contraction into FMA) the C sums in the Controller's order, so the
        // bits are the same. The paper's sampled run needs that: with y replayed rather than fed
        // back, the controller alone amplifies a difference about 2x every 3 s.
        #[cfg(target_arch = "x86_64")]
        assert_eq!(dev, [0.0; 3], "Controller::step's arithmetic changed: make export/c.rs sum in its order again");
        // And again after <p>_init: the zero state is the Controller's.
        c.reset();
        let again = compare(&paper, 1e-3, &mut c, random_inputs(2, 5_000, 2));
        assert!(again.iter().all(|&e| e <= 1e-12), "after init: {again:?}");
    }
    // Random y is no plant's answer: these two controllers, adapting to it at their full rate, grow
    // without bound after about 20,000 and 15,000 steps (NaN at 68,931 and 14,849), so they run
    // for fewer steps.
    for (name, T, steps) in [("three-channel", 0.01, 20_000), ("siso-complex", 0.005, 10_000)] {
        let (_, d) = example(name);
        let (m, q, n) = (d.plant().m(), d.q(), d.plant().n());
        let mut c = CController::build(&export(&d, T, "ex", Precision::F64), "ex", Precision::F64, (m, q, n), "-O2");
        let dev = compare(&d, T, &mut c, random_inputs(m, steps, 3));
        println!("{name}: u_f {:.1e}, u {:.1e}, eta {:.1e}", dev[0], dev[1], dev[2]);
        assert!(dev.iter().all(|&e| e <= 1e-12), "{name}: {dev:?}");
    }
    // No delay at all: a delay line of one row, read where it is written.
    let text = std::fs::read_to_string(format!("{}/../../examples/paper.toml", env!("CARGO_MANIFEST_DIR")))
        .unwrap()
        .replace("delays = [1.0, 3.0]", "delays = [0.0, 0.0]");
    let d = Scenario::from_toml(&text).unwrap().design().unwrap();
    let code = export(&d, 1e-3, "quell", Precision::F64);
    assert!(code.header.contains("QUELL_DELAY_MAX   0 "), "{}", code.header);
    let mut c = CController::build(&code, "quell", Precision::F64, (2, 8, 3), "-O2");
    let dev = compare(&d, 1e-3, &mut c, random_inputs(2, 20_000, 4));
    assert!(dev.iter().all(|&e| e <= 1e-12), "no delay: {dev:?}");
    // An initial estimate x̂(0) (plant.xhat0): <p>_init starts there as Controller::new and reset
    // do (its first u_f = −K x̂(0) + F u_d tells it), and only then is it written.
    let text = text.replace("x0 = [0.0, 0.0, 0.0]", "x0 = [0.0, 0.0, 0.0]\nxhat0 = [0.5, -0.3, 0.2]");
    let d = Scenario::from_toml(&text).unwrap().design().unwrap();
    let code = export(&d, 1e-3, "quell", Precision::F64);
    assert!(code.source.contains("s->z[QUELL_Q + i] = quell_xhat0[i];"), "{}", code.source);
    let mut c = CController::build(&code, "quell", Precision::F64, (2, 8, 3), "-O2");
    for seed in [5, 6] {
        let dev = compare(&d, 1e-3, &mut c, random_inputs(2, 5_000, seed));
        assert!(dev.iter().all(|&e| e <= 1e-12), "x̂(0): {dev:?}");
        c.reset();
    }
}

/// The Rust controller, recording the y and g it is given.
struct Recorder {
    ctrl: Controller,
    inputs: Vec<(Vec<f64>, Vec<f64>)>,
}

impl SampledController for Recorder {
    fn step(&mut self, y: &[f64], g: &[f64]) -> Result<&[f64], ControllerError> {
        self.inputs.push((y.to_vec(), g.to_vec()));
        self.ctrl.step(y, g)
    }
    fn command(&self) -> &[f64] {
        self.ctrl.command()
    }
    fn watched(&self) -> Watched<'_> {
        self.ctrl.watched()
    }
}

/// The paper's sampled-data run: 100 s at T_s = 1 ms (100,001 samples), output every 0.1 s.
fn paper_run(ctrl: &mut impl SampledController, d: &Design) -> SimResult {
    let (g, w) = paper_signals();
    let settings = RunSettings::sampled(100.0, 0.1, 1e-3);
    let r = Run::new(d, &g, &w, settings).controller(ctrl).simulate(|_| std::ops::ControlFlow::Continue(())).unwrap();
    assert_eq!(r.outcome, Some(Outcome::Completed));
    r
}

#[test]
fn same_controller_as_rust_on_the_paper_sampled_run() {
    // The y, g that the Rust controller sees in the paper's sampled-data run, replayed into the C
    // one: u_f, u and η̂ agree to 1e-12 relative to their peaks over all 100,001 steps.
    let (_, d) = example("paper");
    let mut rec = Recorder { ctrl: Controller::new(&d, 1e-3).unwrap(), inputs: vec![] };
    paper_run(&mut rec, &d);
    assert_eq!(rec.inputs.len(), 100_001);
    for opt in ["-O0", "-O2"] {
        let mut c =
            CController::build(&export(&d, 1e-3, "quell", Precision::F64), "quell", Precision::F64, (2, 8, 3), opt);
        let dev = compare(&d, 1e-3, &mut c, rec.inputs.iter().cloned());
        println!("paper sampled run {opt}: u_f {:.1e}, u {:.1e}, eta {:.1e}", dev[0], dev[1], dev[2]);
        assert!(dev.iter().all(|&e| e <= 1e-12), "{opt}: {dev:?}");
    }
}

/// Relative deviations of y, e, u and η̂ of run `a` from run `b`, each against its peak in `b`.
fn run_deviation(a: &SimResult, b: &SimResult) -> [f64; 4] {
    assert_eq!(a.t, b.t);
    [(&a.y, &b.y), (&a.e, &b.e), (&a.u, &b.u), (&a.eta, &b.eta)].map(|(x, y)| relative_deviation(x, y))
}

#[test]
fn closed_loop_with_the_c_controller_and_f32_tail_bounds() {
    // The sampled-data loop with the generated C (f64, -O2) in place of the Rust controller gives
    // the signals of the sampled-data `Run` (what `quell run --sample-time` runs) to 1e-12; in f32 the
    // paper's tail bounds still hold (max |e1| < 0.05, max |e2| < 0.005 on [90, 100]).
    let (_, d) = example("paper");
    let (g, w) = paper_signals();
    let rust = Run::new(&d, &g, &w, RunSettings::sampled(100.0, 0.1, 1e-3))
        .simulate(|_| std::ops::ControlFlow::Continue(()))
        .unwrap();
    let mut c64 =
        CController::build(&export(&d, 1e-3, "quell", Precision::F64), "quell", Precision::F64, (2, 8, 3), "-O2");
    let r64 = paper_run(&mut c64, &d);
    let dev = run_deviation(&r64, &rust);
    println!("closed loop, C f64 vs Rust: y {:.1e}, e {:.1e}, u {:.1e}, eta {:.1e}", dev[0], dev[1], dev[2], dev[3]);
    assert!(dev.iter().all(|&e| e <= 1e-12), "{dev:?}");

    let mut c32 =
        CController::build(&export(&d, 1e-3, "quell", Precision::F32), "quell", Precision::F32, (2, 8, 3), "-O2");
    let r32 = paper_run(&mut c32, &d);
    let (e1, e2) = (r32.max_abs_error(0, 90.0, 100.0).unwrap(), r32.max_abs_error(1, 90.0, 100.0).unwrap());
    let (f1, f2) = (rust.max_abs_error(0, 90.0, 100.0).unwrap(), rust.max_abs_error(1, 90.0, 100.0).unwrap());
    let dev = run_deviation(&r32, &rust);
    println!("f32: tail max |e1| = {e1:.5}, |e2| = {e2:.5} (f64: {f1:.5}, {f2:.5})");
    println!(
        "f32 vs f64: y {:.1e}, e {:.1e}, u {:.1e}, eta {:.1e} (relative to the f64 peaks)",
        dev[0], dev[1], dev[2], dev[3]
    );
    assert!(e1 < 0.05 && e2 < 0.005, "f32 tail errors {e1} {e2}");
}

/// The f32 emulation of a sampled run (`simulation.precision = "f32"`: constants, inputs and states
/// rounded to float, the observers' update and u_f computed in float, the adaptive law's operations
/// in double) departs from the f64 run about as far as the compiled f32 C does in the same loop, in
/// y and in u_f: within a factor of 4 either way, on the paper's example (u_f about 2e-4 of its peak
/// emulated, 8e-5 compiled) and on the disk servo of `tests/data` (18.8 % and 18.2 %). The factor:
/// the emulation leaves the adaptive law's operations' own rounding out (the C departed 0.4–2.8× as
/// far on six plants, docs/deployment.md).
#[test]
fn the_emulated_f32_loop_departs_as_far_as_the_compiled_f32_c() {
    let go = |_| std::ops::ControlFlow::Continue(());
    let manifest = env!("CARGO_MANIFEST_DIR");
    let cases = [("../../examples/paper.toml", 1e-3, (2, 8, 3)), ("tests/data/hdd-servo.toml", 0.0025, (1, 8, 4))];
    for (file, T, dims) in cases {
        let s = Scenario::from_path(std::path::Path::new(&format!("{manifest}/{file}"))).unwrap();
        let d = s.design().unwrap();
        let sampled = RunSettings { mode: Loop::Sampled { sample_time: T }, ..RunSettings::of(&s) };
        let double = Run::of(&s, &d).settings(sampled.clone()).simulate(go).unwrap();
        let f32_settings = RunSettings { precision: Precision::F32, ..sampled.clone() };
        let emulated = Run::of(&s, &d).settings(f32_settings).simulate(go).unwrap();
        let mut c32 = CController::build(&export(&d, T, "quell", Precision::F32), "quell", Precision::F32, dims, "-O2");
        let compiled = Run::of(&s, &d).settings(sampled).controller(&mut c32).simulate(go).unwrap();
        for r in [&double, &emulated, &compiled] {
            assert_eq!(r.outcome, Some(Outcome::Completed), "{file}");
        }
        for (name, [emulated, compiled, double]) in
            [("y", [&emulated.y, &compiled.y, &double.y]), ("u_f", [&emulated.u_f, &compiled.u_f, &double.u_f])]
        {
            let (emu, real) = (relative_deviation(emulated, double), relative_deviation(compiled, double));
            println!("{file} {name}: emulated f32 {emu:.2e}, compiled f32 {real:.2e} (relative to the f64 peak)");
            assert!(emu > 0.0 && (0.25..=4.0).contains(&(emu / real)), "{file} {name}: {emu:e} against {real:e}");
        }
    }
}

#[test]
fn two_controllers_link_into_one_program() {
    // Different prefixes (here also different precisions and designs) share no external name.
    let (_, paper) = example("paper");
    let (_, siso) = example("siso-complex");
    let dir = TempDir::new("two");
    write_code(&export(&paper, 1e-3, "roll", Precision::F64), &dir.0);
    write_code(&export(&siso, 0.005, "pitch", Precision::F32), &dir.0);
    let main = r#"#include "roll_controller.h"
#include "pitch_controller.h"
static roll_state a;
static pitch_state b;
int main(void)
{
    const double y[ROLL_M] = {0.1, 0.2}, g[ROLL_M] = {1.0, 2.0};
    const float yf[PITCH_M] = {0.1f}, gf[PITCH_M] = {1.0f};
    double u[ROLL_M];
    float v[PITCH_M];
    roll_init(&a);
    pitch_init(&b);
    for (int k = 0; k < 100; k++) {
        roll_step(&a, y, g, u);
        pitch_step(&b, yf, gf, v);
    }
    return (u[0] == u[0] && v[0] == v[0]) ? 0 : 1;
}
"#;
    std::fs::write(dir.0.join("main.c"), main).unwrap();
    let mut args: Vec<&str> = STRICT.to_vec();
    args.extend(["-O2", "main.c", "roll_controller.c", "pitch_controller.c", "-o", "two"]);
    tool("gcc", &args, &dir.0);
    tool(&dir.0.join("two").display().to_string(), &[], &dir.0);
    // Also as one translation unit (a unity build): the static names carry the prefix too.
    std::fs::write(
        dir.0.join("unity.c"),
        "#include \"roll_controller.c\"\n#include \"pitch_controller.c\"\n#include \"main.c\"\n",
    )
    .unwrap();
    let mut args: Vec<&str> = STRICT.to_vec();
    args.extend(["-O2", "unity.c", "-o", "unity"]);
    tool("gcc", &args, &dir.0);
    tool(&dir.0.join("unity").display().to_string(), &[], &dir.0);
}

/// The Cortex-M4F build of docs/deployment.md (f32, hard float): warning-free, no writable data, no
/// library calls but memset/memcpy, and in particular no software double-precision routine
/// (`__aeabi_d*`): every operation runs on the single-precision FPU. Prints `arm-none-eabi-size`.
/// Run with `cargo test -p quell --release --test export_c cortex_m4f -- --ignored --nocapture`.
#[test]
#[ignore = "needs arm-none-eabi-gcc (Debian's gcc-arm-none-eabi)"]
fn cortex_m4f_f32_build() {
    let (_, d) = example("paper");
    let code = export(&d, 1e-3, "quell", Precision::F32);
    let dir = TempDir::new("m4f");
    write_code(&code, &dir.0);
    for opt in ["-O2", "-Os"] {
        let mut args: Vec<&str> = STRICT.iter().chain(EXTRA).copied().collect();
        args.extend([opt, "-mcpu=cortex-m4", "-mthumb", "-mfloat-abi=hard", "-mfpu=fpv4-sp-d16"]);
        args.extend(["-c", "quell_controller.c", "-o", "m4f.o"]);
        tool("arm-none-eabi-gcc", &args, &dir.0);
        let undefined = tool("arm-none-eabi-nm", &["-u", "m4f.o"], &dir.0);
        for sym in undefined.split_whitespace().filter(|s| *s != "U") {
            assert!(["memset", "memcpy", "memmove"].contains(&sym), "{opt}: refers to {sym}");
        }
        let size = tool("arm-none-eabi-size", &["m4f.o"], &dir.0);
        println!("{opt}:\n{size}");
        let fields: Vec<&str> = size.lines().nth(1).unwrap().split_whitespace().collect();
        assert_eq!((fields[1], fields[2]), ("0", "0"), "{opt}: data and bss must be empty");
    }
    println!("state: {} bytes (RAM), constants: {} bytes", code.state_bytes, code.constant_bytes);
}

/// Steps for an instruction count under callgrind (repeatable on a loaded machine, unlike time):
/// 100,000 steps each of `Controller::step` and of the f64 and f32 C (-O2), prefixes `c64` and
/// `c32`. docs/deployment.md has the command and the figures.
#[test]
#[ignore = "a workload for callgrind, not a check"]
fn step_cost() {
    let (_, d) = example("paper");
    let mut rust = Controller::new(&d, 1e-3).unwrap();
    let mut c64 = CController::build(&export(&d, 1e-3, "c64", Precision::F64), "c64", Precision::F64, (2, 8, 3), "-O2");
    let mut c32 = CController::build(&export(&d, 1e-3, "c32", Precision::F32), "c32", Precision::F32, (2, 8, 3), "-O2");
    let mut sum = 0.0;
    for (y, g) in random_inputs(2, 100_000, 5) {
        sum += rust.step(&y, &g).unwrap()[0] + c64.step(&y, &g)[0] + c32.step(&y, &g)[0];
    }
    assert!(sum.is_finite());
}

/// The Cortex-M4F f32 build run on an emulated Cortex-M4 (QEMU's mps2-an386, semihosting) computes
/// the same floats as the host's f32 build, bit for bit: 20,000 steps of pseudo-random y, g
/// (`c_harness/drive.c`). With `closed_loop_with_the_c_controller_and_f32_tail_bounds` this carries
/// the f32 results over to the target. Needs arm-none-eabi-gcc and qemu-system-arm (Debian's
/// gcc-arm-none-eabi, qemu-system-arm); run with
/// `cargo test -p quell --release --test export_c cortex_m4f -- --ignored --nocapture`.
#[test]
#[ignore = "needs arm-none-eabi-gcc and qemu-system-arm"]
fn cortex_m4f_under_qemu_matches_the_host_bit_for_bit() {
    let (_, d) = example("paper");
    let dir = TempDir::new("qemu");
    write_code(&export(&d, 1e-3, "quell", Precision::F32), &dir.0);
    std::fs::write(dir.0.join("drive.c"), include_str!("c_harness/drive.c")).unwrap();
    std::fs::write(dir.0.join("mps2.ld"), include_str!("c_harness/mps2.ld")).unwrap();
    let mut host: Vec<&str> = STRICT.to_vec();
    host.extend(["-O2", "drive.c", "quell_controller.c", "-o", "host"]);
    tool("gcc", &host, &dir.0);
    let want = tool(&dir.0.join("host").display().to_string(), &[], &dir.0);

    let cpu = ["-mcpu=cortex-m4", "-mthumb", "-mfloat-abi=hard", "-mfpu=fpv4-sp-d16"];
    let mut args: Vec<&str> = STRICT.to_vec();
    args.extend(cpu);
    args.extend(["-O2", "-c", "quell_controller.c", "-o", "c.o"]);
    tool("arm-none-eabi-gcc", &args, &dir.0);
    // The bare-metal harness (GNU asm, its own memset/memcpy) at -O1, so that gcc does not turn
    // those loops back into calls to themselves.
    let mut args = vec!["-std=gnu99", "-O1", "-ffreestanding"];
    args.extend(cpu);
    args.extend(["-c", "drive.c", "-o", "d.o"]);
    tool("arm-none-eabi-gcc", &args, &dir.0);
    let mut args = vec!["-nostdlib", "-T", "mps2.ld"];
    args.extend(cpu);
    args.extend(["d.o", "c.o", "-lgcc", "-o", "m4f.elf"]);
    tool("arm-none-eabi-gcc", &args, &dir.0);
    let run = std::process::Command::new("qemu-system-arm")
        .args([
            "-M",
            "mps2-an386",
            "-nographic",
            "-semihosting-config",
            "enable=on,target=native",
            "-kernel",
            "m4f.elf",
        ])
        .current_dir(&dir.0)
        .output()
        .expect("qemu-system-arm runs");
    assert!(run.status.success(), "qemu: {}", String::from_utf8_lossy(&run.stderr));
    // Semihosting's SYS_WRITE0 goes to QEMU's stderr.
    let got = String::from_utf8_lossy(&run.stderr);
    println!("{got}");
    assert_eq!(got, want);
    assert_eq!(want.lines().count(), 11);
}

/// Compiles `files` with the strict flags into `dir/name`; `Err(stderr)` when gcc refuses.
fn try_compile(dir: &std::path::Path, files: &[&str], name: &str) -> Result<(), String> {
    let mut args: Vec<&str> = STRICT.to_vec();
    args.extend(["-O1"]);
    args.extend(files);
    args.extend(["-o", name]);
    let out = std::process::Command::new("gcc").args(&args).current_dir(dir).output().expect("run gcc");
    if out.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).into_owned())
    }
}

/// A build that assumes no NaN or infinity (gcc's -ffast-math, -Ofast, -ffinite-math-only) would
/// compile the checks of y, g, u and u_f out, so the source refuses it, naming the flags: an FMU
/// built with `--compiler "gcc -ffast-math"` had accepted a NaN input (hostile review, 2026-12-07).
/// The same source compiles without them (the other tests).
#[test]
fn a_build_without_ieee_arithmetic_is_refused() {
    let (_, d) = example("paper");
    let dir = TempDir::new("fast-math");
    write_code(&export(&d, 1e-3, "quell", Precision::F64), &dir.0);
    for flag in ["-ffast-math", "-Ofast", "-ffinite-math-only"] {
        let e = try_compile(&dir.0, &[flag, "-c", "quell_controller.c"], "fast.o").expect_err(flag);
        assert!(e.contains("build without -ffast-math, -Ofast or -ffinite-math-only"), "{flag}: {e}");
    }
    try_compile(&dir.0, &["-c", "quell_controller.c"], "ieee.o").expect("compiles with IEEE arithmetic");
}

#[test]
fn a_header_and_source_of_different_exports_do_not_compile_together() {
    // A failed write could leave a new header beside an old source; the pair compiled cleanly and
    // indexed out of bounds at run time. Now the header's LAYOUT_ID must be the source's own.
    let (_, d) = example("paper");
    let old = export(&d, 1e-3, "quell", Precision::F64);
    let new = export(&d, 2e-3, "quell", Precision::F64);
    let dir = TempDir::new("pair");
    write_code(&new, &dir.0);
    try_compile(&dir.0, &["-c", "quell_controller.c"], "matched.o").expect("a matched pair compiles");
    std::fs::write(dir.0.join("quell_controller.c"), &old.source).unwrap();
    let e = try_compile(&dir.0, &["-c", "quell_controller.c"], "mismatched.o")
        .expect_err("a mismatched pair must not compile");
    assert!(e.contains("quell_header_matches_source"), "gcc names the check: {e}");
    // An application compiled with the old header and linked with the new source: it had linked
    // (the names were the same) and crashed in quell_init; the linked names now differ.
    let app = "#include \"quell_controller.h\"\nint main(void) { static quell_state s; quell_init(&s); return 0; }\n";
    std::fs::write(dir.0.join("app.c"), app).unwrap();
    std::fs::write(dir.0.join("quell_controller.h"), &old.header).unwrap();
    try_compile(&dir.0, &["-c", "app.c"], "app.o").expect("the application compiles with its header");
    std::fs::write(dir.0.join("quell_controller.h"), &new.header).unwrap();
    std::fs::write(dir.0.join("quell_controller.c"), &new.source).unwrap();
    try_compile(&dir.0, &["-c", "quell_controller.c"], "new.o").expect("the new pair compiles");
    let e = try_compile(&dir.0, &["app.o", "new.o", "-lm"], "app").expect_err("a stale header must not link");
    assert!(e.contains("undefined reference to `quell_init_"), "the linker names the function: {e}");
}

#[test]
fn a_scenario_name_with_comment_delimiters_stays_inside_the_comment() {
    // `/*` inside the header's comment is a nested comment (-Werror=comment), and `*/` ended it.
    let (_, d) = example("paper");
    let o = ExportOptions { scenario_name: Some("a /* b */ c */ /*/".into()), ..ExportOptions::default() };
    let code = generate(&d, 1e-3, &o).unwrap();
    let h = &code.header;
    let comment = &h[..h.find("*/\n#ifndef").expect("the header comment ends before the guard")];
    assert_eq!(comment.matches("/*").count(), 1, "one comment opener:\n{comment}");
    assert!(!comment[..comment.len() - 1].contains("*/"), "no early end:\n{comment}");
    let dir = TempDir::new("name");
    write_code(&code, &dir.0);
    try_compile(&dir.0, &["-c", "quell_controller.c"], "c.o").unwrap();
}

#[test]
fn the_c_step_refuses_a_spike_and_keeps_its_state_in_double_and_float() {
    // (Also: a state whose delay-line row is out of range returns 3, check 11.) A finite spike (1e160 in double, 1e22 in float) made u_f NaN for ever. The generated step now
    // returns 1 for any entry beyond QUELL_INPUT_BOUND (1e100; 1e12 in float) or NaN, leaving the
    // state and u_f as they were: after it, u_f equals that of a controller that never saw it.
    let (_, d) = example("paper");
    for (precision, spike, bound) in [(Precision::F64, "1e160", "1e100"), (Precision::F32, "1e22f", "1000000000000.0f")]
    {
        let code = export(&d, 1e-3, "quell", precision);
        let h = code.header.split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(h.contains(&format!("#define QUELL_INPUT_BOUND {bound}")), "{h}");
        let R = precision.c_type();
        let main = format!(
            r#"#include "quell_controller.h"
static quell_state a, b;
int main(void)
{{
    {R} y[QUELL_M], g[QUELL_M] = {{1, 2}}, ua[QUELL_M], ub[QUELL_M], bad[QUELL_M], nan[QUELL_M];
    volatile {R} zero = 0;
    quell_init(&a);
    quell_init(&b);
    for (int k = 0; k < 6000; k++) {{
        y[0] = ({R})(0.3 * (k % 100) / 100.0);
        y[1] = ({R})(-0.2 * (k % 37) / 37.0);
        if (k % 1000 == 500) {{
            bad[0] = {spike};
            bad[1] = y[1];
            nan[0] = y[0];
            nan[1] = zero / zero;
            ua[0] = 7;
            if (quell_step(&a, bad, g, ua) != 1 || quell_step(&a, y, bad, ua) != 1 || quell_step(&a, nan, g, ua) != 1)
                return 2;
            if (ua[0] != 7)
                return 3;
        }}
        if (quell_step(&a, y, g, ua) != 0 || quell_step(&b, y, g, ub) != 0)
            return 4;
        for (int i = 0; i < QUELL_M; i++)
            if (ua[i] != ub[i] || ua[i] != ua[i])
                return 5;
    }}
    /* At the bound: accepted; afterwards every step either gives a finite u_f (0) or, once the
     * state overflowed, says so (2) until quell_init, after which it is a fresh controller. */
    y[0] = QUELL_INPUT_BOUND;
    y[1] = -QUELL_INPUT_BOUND;
    if (quell_step(&a, y, g, ua) != 0)
        return 6;
    y[0] = 0;
    y[1] = 0;
    int failed = 0;
    for (int k = 0; k < 6000; k++) {{
        const {R} kept[QUELL_M] = {{ua[0], ua[1]}};
        int r = quell_step(&a, y, g, ua);
        if (r == 0 && failed)
            return 7;
        failed |= r == 2;
        /* A state no longer finite leaves u_f as it was (it wrote NaN into it). */
        if (r == 2 && (ua[0] != kept[0] || ua[1] != kept[1]))
            return 10;
        for (int i = 0; i < QUELL_M; i++)
            if (r == 0 && !(ua[i] - ua[i] == 0)) /* NaN or infinite */
                return 8;
    }}
    quell_init(&a);
    quell_init(&b);
    for (int k = 0; k < 100; k++)
        if (quell_step(&a, g, y, ua) != 0 || quell_step(&b, g, y, ub) != 0 || ua[0] != ub[0] || ua[1] != ub[1])
            return 9;
    /* A state quell_init did not make (its delay-line row out of range, as in a stack variable
     * never initialized) is refused with 3 before it is read or written: no write out of bounds,
     * u_f untouched. */
    a.head = QUELL_DELAY_MAX + 1u;
    ua[0] = 7;
    if (quell_step(&a, y, g, ua) != 3 || ua[0] != 7)
        return 11;
    return 0;
}}
"#
        );
        let dir = TempDir::new("spike");
        write_code(&code, &dir.0);
        std::fs::write(dir.0.join("main.c"), main).unwrap();
        try_compile(&dir.0, &["main.c", "quell_controller.c"], "spike").unwrap_or_else(|e| panic!("{e}"));
        let status = std::process::Command::new(dir.0.join("spike")).status().expect("run");
        assert_eq!(status.code(), Some(0), "{precision:?}: the driver's check {:?} failed", status.code());
    }
}

/// `quell_step(&s, buf, g, buf)`: u_f may be the array y (or g). y(k) is read into the core's
/// input before u_f is written; before, the core took u_f(k) for y(k) and the two runs parted by
/// up to 9.9 in u_f over 3,000 steps (the paper's example at T_s = 0.01). Bit for bit here.
#[test]
fn the_plant_input_may_be_written_over_the_measurement() {
    let (_, paper) = example("paper");
    let dir = TempDir::new("alias");
    write_code(&export(&paper, 0.01, "quell", Precision::F64), &dir.0);
    let main = r#"#include <math.h>
#include <stdio.h>
#include "quell_controller.h"
static quell_state a, b;
int main(void)
{
    quell_init(&a);
    quell_init(&b);
    for (int k = 0; k < 3000; k++) {
        const double t = 0.01 * k;
        double y[QUELL_M] = {0.3 * sin(t) + 0.1, 0.2 * cos(1.3 * t)}, g[QUELL_M] = {3.0 * sin(2.0 * t), 2.0};
        double u_f[QUELL_M], buf[QUELL_M] = {y[0], y[1]};
        if (quell_step(&a, y, g, u_f) != 0 || quell_step(&b, buf, g, buf) != 0)
            return 2;
        for (int i = 0; i < QUELL_M; i++)
            if (u_f[i] != buf[i]) {
                printf("step %d: u_f[%d] = %.17g apart %.17g\n", k, i, u_f[i], buf[i]);
                return 1;
            }
    }
    return 0;
}
"#;
    std::fs::write(dir.0.join("main.c"), main).unwrap();
    let mut args: Vec<&str> = STRICT.to_vec();
    args.extend(["-O2", "main.c", "quell_controller.c", "-lm", "-o", "alias"]);
    tool("gcc", &args, &dir.0);
    tool(&dir.0.join("alias").display().to_string(), &[], &dir.0);
}

/// A controller too large for an embedded target is warned about: the paper's delays τ = 1 and 3 s
/// hold 1,000 and 3,000 samples at T_s = 1 ms (within 1 MiB), 100 times as many at 10 µs.
#[test]
fn a_controller_beyond_a_mebibyte_is_warned_about() {
    let (_, d) = example("paper");
    let small = export(&d, 1e-3, "quell", Precision::F64);
    assert!(small.state_bytes < quell::export::LARGE_EXPORT_BYTES && small.size_warning().is_none());
    let large = export(&d, 1e-5, "quell", Precision::F64);
    // The delay lines grow with 1/T_s: 100 times the samples, nearly 100 times the state.
    assert!(large.state_bytes > 90 * small.state_bytes, "{} vs {}", large.state_bytes, small.state_bytes);
    let w = large.size_warning().expect("a warning");
    assert!(
        w.starts_with(&format!("the controller needs {:.1} MiB of RAM", large.state_bytes as f64 / 1048576.0)),
        "{w}"
    );
}

/// An f32 export of a design whose closed loop is ill-conditioned is cautioned: the disk servo's
/// observer has κ₂ = 2.75e6, so rounding to float can move its poles by about κ₂·6e-8 = 16 %
/// (a tryout's f32 C controller gave a u_f 18 % of its peak away from the f64 one's); the paper's
/// (κ₂ = 27) is not, and no f64 export is.
#[test]
fn an_f32_export_of_an_ill_conditioned_design_is_cautioned() {
    let text = std::fs::read_to_string(format!("{}/tests/data/hdd-servo.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let hdd = Scenario::from_toml(&text).unwrap().design().unwrap();
    let w = export(&hdd, 0.0025, "quell", Precision::F32).precision_warning.expect("cautioned");
    assert!(w.contains("κ₂ = 2.75e6") && w.contains("= 16 % of themselves"), "{w}");
    assert_eq!(export(&hdd, 0.0025, "quell", Precision::F64).precision_warning, None);
    let (_, paper) = example("paper");
    assert_eq!(export(&paper, 1e-3, "quell", Precision::F32).precision_warning, None);
}
