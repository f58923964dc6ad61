//! FMI 2.0 and 3.0 co-simulation FMUs of the generated C controller (docs/deployment.md).
//!
//! The archive holds `modelDescription.xml`, the controller's C ([`super::generate`]) with a
//! wrapper implementing the FMI functions under `sources/`, and, when a C compiler is given, the
//! shared library under `binaries/<platform>/`. Inputs are `y[i]` and `g[i]`, outputs `u_f[i]` (the
//! plant input (5)) and `u[i]` (the adaptive command (25)); FMI 3.0 adds the independent variable
//! `time`. Both versions share one wrapper core (`fmu_core.c.in`); each adds its API layer.
//!
//! Timing: the controller samples at `k T_s` from the start time. `fmi2DoStep(t, h)` (`fmi3DoStep`)
//! takes the samples in `[t, t + h)` with the inputs last set (held over the step, so `h = T_s`
//! gives exactly the sampled loop) and then reports the outputs of the next sample: `u_f(k)` does
//! not depend on `y(k)` or `g(k)` (no direct feedthrough), so after the step to `t_k` the outputs
//! are the `u_f(k)` and `u(k)` that the controller holds over `[t_k, t_k+1)`, the values
//! [`Controller::step`](crate::controller::Controller::step) returns at sample `k`. `h` must be a
//! whole number of samples.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;
use std::process::Command;

use super::c::fill;
use super::{generate, CCode, ExportError, ExportOptions};
use crate::design::Design;
use crate::settings::TimeUnit;

/// The FMI 2.0.1 headers (2-clause BSD, Modelica Association), as packaged in FMPy 0.3.32's
/// `fmpy/c-code/`; shipped in every FMI 2.0 FMU's `sources/` so the sources compile on their own.
const FMI2_HEADERS: [(&str, &str); 3] = [
    ("fmi2Functions.h", include_str!("fmi2/fmi2Functions.h")),
    ("fmi2FunctionTypes.h", include_str!("fmi2/fmi2FunctionTypes.h")),
    ("fmi2TypesPlatform.h", include_str!("fmi2/fmi2TypesPlatform.h")),
];

/// The FMI 3.0.2 headers (2-clause BSD, Modelica Association; the fmi-standard repository's tag
/// v3.0.2). FMI 3.0 (section 2.5) has the importer supply them, so they build the binary but are
/// not shipped in `sources/`.
const FMI3_HEADERS: [(&str, &str); 3] = [
    ("fmi3Functions.h", include_str!("fmi3/fmi3Functions.h")),
    ("fmi3FunctionTypes.h", include_str!("fmi3/fmi3FunctionTypes.h")),
    ("fmi3PlatformTypes.h", include_str!("fmi3/fmi3PlatformTypes.h")),
];

/// The wrapper's part common to both versions: the state between communication points, reading
/// and setting variables, and the step over whole samples.
const CORE: &str = include_str!("fmu_core.c.in");

/// The FMI standard an FMU follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FmiVersion {
    /// FMI 2.0 (the widest support: Simulink, OpenModelica, Dymola, FMPy).
    #[default]
    V2,
    /// FMI 3.0 (Float64 variables, the independent variable `time`, no clocks or event mode).
    V3,
}

impl FmiVersion {
    /// `"2.0"` or `"3.0"`, as `fmiVersion` in the model description.
    pub fn name(self) -> &'static str {
        match self {
            FmiVersion::V2 => "2.0",
            FmiVersion::V3 => "3.0",
        }
    }

    /// The FMI platform of the machine running this code and its shared-library extension.
    fn host_platform(self) -> Option<(&'static str, &'static str)> {
        let ext = match std::env::consts::OS {
            "linux" => "so",
            "macos" => "dylib",
            "windows" => "dll",
            _ => return None,
        };
        let platform = match (self, std::env::consts::OS, std::env::consts::ARCH) {
            (FmiVersion::V2, "linux", "x86_64") => "linux64",
            (FmiVersion::V2, "macos", "x86_64") => "darwin64",
            (FmiVersion::V2, "windows", "x86_64") => "win64",
            (FmiVersion::V3, "linux", "x86_64") => "x86_64-linux",
            (FmiVersion::V3, "linux", "aarch64") => "aarch64-linux",
            (FmiVersion::V3, "macos", "x86_64") => "x86_64-darwin",
            (FmiVersion::V3, "macos", "aarch64") => "aarch64-darwin",
            (FmiVersion::V3, "windows", "x86_64") => "x86_64-windows",
            _ => return None,
        };
        Some((platform, ext))
    }

    /// The headers the wrapper compiles against, the API layer over [`CORE`], and whether the
    /// headers go into `sources/`.
    fn wrapper_parts(self) -> (&'static [(&'static str, &'static str); 3], &'static str, bool) {
        match self {
            FmiVersion::V2 => (&FMI2_HEADERS, include_str!("fmi2/fmu2.c.in"), true),
            FmiVersion::V3 => (&FMI3_HEADERS, include_str!("fmi3/fmu3.c.in"), false),
        }
    }
}

impl std::str::FromStr for FmiVersion {
    type Err = ExportError;
    fn from_str(s: &str) -> Result<FmiVersion, ExportError> {
        match s {
            "2" | "2.0" => Ok(FmiVersion::V2),
            "3" | "3.0" => Ok(FmiVersion::V3),
            _ => Err(ExportError::FmiVersion { found: s.to_string() }),
        }
    }
}

/// An FMU archive and what it holds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Fmu {
    /// `<prefix>.fmu`; the prefix is the FMI model identifier.
    pub file_name: String,
    /// The zip archive.
    pub bytes: Vec<u8>,
    /// `modelDescription.xml`.
    pub model_description: String,
    /// FMI platform of the binary (`linux64`; FMI 3.0: `x86_64-linux`), or none for a source-only FMU.
    pub platform: Option<&'static str>,
    /// The controller's C inside it.
    pub code: CCode,
    pub version: FmiVersion,
}

/// For an export of the C alone into `dir`, the warning on the FMU `<prefix>.fmu` an earlier
/// export left there, which this one does not rewrite: it may no longer match the code beside it
/// (another sample time, another design; hostile review, 2026-12-06). Not removed: it may be the
/// user's still (an f64 FMU beside f32 code for a microcontroller, or one whose binaries they
/// added). `rewrite` is how the front end writes it again (its FMU option); `None` where there is
/// no regular file of that name.
pub fn earlier_fmu_warning(dir: &std::path::Path, prefix: &str, rewrite: &str) -> Option<String> {
    let name = format!("{prefix}.fmu");
    std::fs::symlink_metadata(dir.join(&name)).is_ok_and(|m| m.is_file()).then(|| {
        format!("{name} beside this code is an earlier export's, not rewritten: it keeps the design and sample time it was written with ({rewrite} to write it with this code)")
    })
}

/// For an FMI 2.0 FMU of a plant not in seconds, the caution that FMI 2.0 has no unit of time: an
/// importer reads the FMU's times in seconds, so a master stepping at the sample time runs the
/// controller that many times slow or fast (a maglev written in ms, stepped at 0.1 s, 1000× slow;
/// helper tryout, 2026-12-06). FMI 3.0 declares the unit. `None` otherwise.
pub fn time_unit_warning(design: &Design, sample_time: f64, version: FmiVersion) -> Option<String> {
    let unit = design.plant().time_unit;
    let seconds = unit.seconds();
    (version == FmiVersion::V2 && seconds != 1.0).then(|| {
        let (factor, pace) = if seconds < 1.0 { (1.0 / seconds, "slow") } else { (seconds, "fast") };
        format!(
            "FMI 2.0 has no unit of time: an importer reads this FMU's times in seconds (its stepSize {sample_time}, the sample time), while the plant model's are in {}, so a master stepping {sample_time} s runs the controller {factor}× too {pace}; export it as FMI 3.0 (fmi_version), which declares the unit, or write the plant in seconds (docs/deployment.md, \"Units of time\")",
            unit.name()
        )
    })
}

/// Generates the FMI `version` FMU of `design` at `sample_time`: the controller of [`generate`],
/// wrapped. With a `compiler` (a C99 compiler taking gcc's flags: `gcc`, `cc`, `clang`) the archive
/// also holds the binary for this machine's platform, compiled with `-std=c99 -O2
/// -ffp-contract=off` so that in f64 it computes the bits of
/// [`Controller::step`](crate::controller::Controller::step).
pub fn generate_fmu(
    design: &Design,
    sample_time: f64,
    options: &ExportOptions,
    compiler: Option<&str>,
    version: FmiVersion,
) -> Result<Fmu, ExportError> {
    let code = generate(design, sample_time, options)?;
    let p = options.prefix.as_str();
    let m = design.plant().m();
    let wrapper_name = format!("{p}_fmu.c");
    let guid = guid(&[&code.header, &code.source]);
    let (headers, api, ship_headers) = version.wrapper_parts();
    let symbol = ascii_symbol(design.plant().time_unit);
    let (mantissa, scale) = crate::controller::discrete::Grid::new(sample_time).decimal();
    let (mantissa, scale) = (format!("{mantissa:?}"), format!("{scale:?}"));
    let values = [
        ("guid", guid.as_str()),
        ("version", env!("CARGO_PKG_VERSION")),
        ("fmi", version.name()),
        ("p", p),
        ("P", &p.to_ascii_uppercase()),
        ("R", options.precision.c_type()),
        ("unit", &symbol),
        ("t_mantissa", &mantissa),
        ("t_scale", &scale),
    ];
    let wrapper = fill(CORE, &values) + &fill(api, &values);
    let mut sources: Vec<(String, String)> = vec![
        (code.header_name.clone(), code.header.clone()),
        (code.source_name.clone(), code.source.clone()),
        (wrapper_name.clone(), wrapper),
    ];
    let units = [wrapper_name.as_str(), code.source_name.as_str()];
    let unit = super::time_unit_text(design);
    let model_description = match version {
        FmiVersion::V2 => model_description_2(options, m, (sample_time, &unit), &guid, &units),
        FmiVersion::V3 => model_description_3(options, m, (sample_time, &unit), &guid, design.plant().time_unit),
    };
    let header_files = headers.iter().map(|(n, t)| (n.to_string(), t.to_string()));

    let binary = match compiler {
        None => None,
        Some(cc) => {
            let (platform, ext) = version.host_platform().ok_or_else(|| ExportError::Compiler {
                compiler: cc.to_string(),
                message: format!(
                    "FMI {} names no platform for {}-{}; export a source-only FMU (no compiler) and build it there",
                    version.name(),
                    std::env::consts::OS,
                    std::env::consts::ARCH
                ),
            })?;
            let mut all = sources.clone();
            all.extend(header_files.clone());
            let so = compile(cc, &all, &units, &format!("{p}.{ext}"), COMPILE_TIMEOUT)?;
            Some((platform, format!("binaries/{platform}/{p}.{ext}"), so))
        }
    };
    if ship_headers {
        sources.extend(header_files);
    } else {
        sources.push(("buildDescription.xml".into(), build_description(p, &units)));
    }

    let mut files: Vec<(String, Vec<u8>)> =
        vec![("modelDescription.xml".into(), model_description.clone().into_bytes())];
    files.extend(sources.into_iter().map(|(n, t)| (format!("sources/{n}"), t.into_bytes())));
    let platform = binary.as_ref().map(|b| b.0);
    files.extend(binary.map(|(_, path, so)| (path, so)));
    let bytes = zip(&files).map_err(|e| ExportError::Archive { message: e.to_string() })?;
    Ok(Fmu { file_name: format!("{p}.fmu"), bytes, model_description, platform, code, version })
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

/// The variables of both versions, by value reference: 0..m-1 are y, m..2m-1 g, 2m..3m-1 u_f,
/// 3m..4m-1 u: (value reference, name, causality, variability, description). A description
/// names the plant's signal where `names` gives it: y_i, g_i and u_i the output i, u_f,i the input i.
fn variables(
    m: usize,
    names: &crate::scenario::SignalNames,
) -> impl Iterator<Item = (usize, String, &'static str, &'static str, String)> {
    const SIGNALS: [(&str, &str, &str, &str); 4] = [
        ("y", "input", "continuous", "measured output y_i, sampled at each sample instant"),
        ("g", "input", "continuous", "reference g_i, sampled at each sample instant"),
        ("u_f", "output", "discrete", "plant input u_f,i (5), held over a sample"),
        ("u", "output", "discrete", "adaptive command u_i (25), undelayed"),
    ];
    let (outputs, inputs) = (names.outputs.clone(), names.inputs.clone());
    SIGNALS.into_iter().enumerate().flat_map(move |(s, (var, causality, variability, what))| {
        let given = if var == "u_f" { inputs.clone() } else { outputs.clone() };
        (0..m).map(move |i| {
            let what = match given.as_ref().map(|g| &g[i]) {
                Some(name) => format!("{}: {what}", xml_escape(name)),
                None => what.to_string(),
            };
            (s * m + i, format!("{var}[{}]", i + 1), causality, variability, what)
        })
    })
}

/// The opening of `modelDescription.xml` up to the interface element's attributes.
/// `sample` is T_s and what it is measured in.
fn opening(o: &ExportOptions, version: FmiVersion, (sample_time, unit): (f64, &str), token: &str) -> String {
    let name = xml_escape(o.scenario_name.as_deref().unwrap_or(&o.prefix));
    let token = match version {
        FmiVersion::V2 => format!(r#"guid="{token}""#),
        FmiVersion::V3 => format!(r#"instantiationToken="{token}""#),
    };
    let events = if version == FmiVersion::V2 { r#" numberOfEventIndicators="0""# } else { "" };
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiModelDescription fmiVersion=\"{}\" modelName=\"{name}\" {token} description=\"Direct adaptive output-feedback controller (quell), sampled at T_s = {sample_time:?} ({})\" generationTool=\"quell {}\" variableNamingConvention=\"structured\"{events}>\n",
        version.name(),
        xml_escape(unit),
        env!("CARGO_PKG_VERSION")
    )
}

/// FMI 2.0 `modelDescription.xml` (value references of [`variables`]).
fn model_description_2(o: &ExportOptions, m: usize, sample: (f64, &str), guid: &str, source_files: &[&str]) -> String {
    let (mut x, sample_time) = (opening(o, FmiVersion::V2, sample, guid), sample.0);
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
    for (vr, name, causality, variability, what) in variables(m, &o.names) {
        let start = if causality == "input" { r#" start="0""# } else { "" };
        let _ = writeln!(
            x,
            r#"    <ScalarVariable name="{name}" valueReference="{vr}" causality="{causality}" variability="{variability}" description="{what}"><Real{start}/></ScalarVariable>"#
        );
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

/// The unit of time's symbol in ASCII, as the generated C's messages and the model description
/// carry it ("us" for µs).
fn ascii_symbol(time: TimeUnit) -> String {
    time.symbol().replace('µ', "u")
}

/// FMI 3.0 `modelDescription.xml`: the variables of [`variables`] as `Float64`, and the
/// independent variable `time` at value reference 4m, in the plant model's unit of time (declared
/// among the unit definitions as a multiple of the SI second, so an importer can convert).
fn model_description_3(o: &ExportOptions, m: usize, sample: (f64, &str), token: &str, time: TimeUnit) -> String {
    let (mut x, sample_time) = (opening(o, FmiVersion::V3, sample, token), sample.0);
    let _ = writeln!(
        x,
        r#"  <CoSimulation modelIdentifier="{}" canHandleVariableCommunicationStepSize="true" canBeInstantiatedOnlyOncePerProcess="false" hasEventMode="false"/>"#,
        o.prefix
    );
    let unit = ascii_symbol(time);
    let factor = if time.seconds() == 1.0 { String::new() } else { format!(r#" factor="{:?}""#, time.seconds()) };
    let _ = writeln!(x, r#"  <UnitDefinitions><Unit name="{unit}"><BaseUnit s="1"{factor}/></Unit></UnitDefinitions>"#);
    let _ = writeln!(x, r#"  <DefaultExperiment startTime="0" stepSize="{sample_time:?}"/>"#);
    let _ = writeln!(x, "  <ModelVariables>");
    let _ = writeln!(
        x,
        r#"    <Float64 name="time" valueReference="{}" causality="independent" variability="continuous" description="time" unit="{unit}"/>"#,
        4 * m
    );
    for (vr, name, causality, variability, what) in variables(m, &o.names) {
        let start = if causality == "input" { r#" start="0""# } else { "" };
        let _ = writeln!(
            x,
            r#"    <Float64 name="{name}" valueReference="{vr}" causality="{causality}" variability="{variability}" description="{what}"{start}/>"#
        );
    }
    let _ = writeln!(x, "  </ModelVariables>\n  <ModelStructure>");
    // Outputs depend on no input at the same instant (no direct feedthrough).
    for element in ["Output", "InitialUnknown"] {
        for vr in 2 * m..4 * m {
            let _ = writeln!(x, r#"    <{element} valueReference="{vr}" dependencies=""/>"#);
        }
    }
    let _ = writeln!(x, "  </ModelStructure>\n</fmiModelDescription>");
    x
}

/// FMI 3.0 `sources/buildDescription.xml`: the C99 units of the binary.
fn build_description(model_identifier: &str, units: &[&str]) -> String {
    let files: String = units.iter().map(|u| format!("      <SourceFile name=\"{u}\"/>\n")).collect();
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiBuildDescription fmiVersion=\"3.0\">\n  <BuildConfiguration modelIdentifier=\"{model_identifier}\">\n    <SourceFileSet language=\"C99\">\n{files}    </SourceFileSet>\n  </BuildConfiguration>\n</fmiBuildDescription>\n"
    )
}

/// How long a compiler may take before it is taken as hung (one that waits for input, a wrapper
/// stuck on a licence server): the generated code compiles in about a second.
const COMPILE_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(120);

/// Compiles `units` of `sources` into the shared library `output` with `compiler`, in a temporary
/// directory, killing it after `timeout`; returns the library's bytes.
fn compile(
    compiler: &str,
    sources: &[(String, String)],
    units: &[&str],
    output: &str,
    timeout: std::time::Duration,
) -> Result<Vec<u8>, ExportError> {
    let fail = |message: String| ExportError::Compiler { compiler: compiler.to_string(), message };
    let dir = tempfile::tempdir().map_err(|e| fail(format!("cannot create a temporary directory ({e})")))?;
    for (name, text) in sources {
        std::fs::write(dir.path().join(name), text).map_err(|e| fail(format!("cannot write {name} ({e})")))?;
    }
    let out = dir.path().join(output);
    // A compiler with flags ("gcc -m64", as make reads $CC) unless the whole text names a file; a
    // relative path names a file from the caller's directory, not the temporary one it runs in.
    let (program, flags): (&str, Vec<&str>) = if Path::new(compiler).is_file() {
        (compiler, vec![])
    } else {
        let mut words = compiler.split_whitespace();
        (words.next().unwrap_or(compiler), words.collect())
    };
    let program = match Path::new(program) {
        p if p.components().count() > 1 || p.starts_with(".") => std::path::absolute(p).unwrap_or_else(|_| p.into()),
        p => p.into(),
    };
    let mut cmd = Command::new(program);
    cmd.args(flags);
    cmd.args(["-std=c99", "-O2", "-ffp-contract=off", "-shared", "-fPIC", "-fvisibility=hidden", "-o"]).arg(&out);
    cmd.args(units.iter().map(|u| dir.path().join(u))).current_dir(dir.path());
    let result = run_within(cmd, timeout)
        .map_err(|e| match e.kind() {
            std::io::ErrorKind::Interrupted => ExportError::Interrupted,
            _ => ExportError::CompilerNotFound { compiler: compiler.to_string(), message: e.to_string() },
        })?
        .ok_or_else(|| {
            fail(format!(
                "it had not finished after {} s and was stopped: does it wait for input or a licence? Name a C compiler that runs unattended, such as gcc or clang",
                timeout.as_secs_f64()
            ))
        })?;
    if !result.status.success() {
        let stderr = String::from_utf8_lossy(&result.stderr);
        let first: Vec<&str> = stderr.lines().take(12).collect();
        let said =
            if first.is_empty() { "it printed nothing: is it a C compiler?".to_string() } else { first.join("\n") };
        return Err(fail(format!("compiling the FMU failed ({}):\n{said}", result.status)));
    }
    std::fs::read(&out).map_err(|e| {
        fail(format!(
            "it succeeded but wrote no {} ({e}): is it a C compiler that takes gcc's flags (-shared -fPIC -o)? Name one such as gcc or clang",
            Path::new(output).display()
        ))
    })
}

/// The most of a compiler's stdout and stderr kept, each.
const KEPT_OUTPUT: usize = 64 * 1024;

/// Runs `cmd` with stdin closed, its output captured, and waits at most `timeout`: `None` (the
/// process killed, with the processes it started) when it has not exited by then, and an
/// `Interrupted` error (killed likewise) once the stop flag ([`crate::cancel::check`]) is set: a
/// signal that ended quell had left the compiler running, orphaned, and its directory behind.
fn run_within(mut cmd: Command, timeout: std::time::Duration) -> std::io::Result<Option<std::process::Output>> {
    use std::io::Read;
    use std::process::Stdio;
    use std::time::{Duration, Instant};
    // Its own process group, so that a timeout kills the compiler's own children too (cc1, as, ld,
    // or a wrapper script's), which would otherwise run on holding the pipes.
    #[cfg(unix)]
    std::os::unix::process::CommandExt::process_group(&mut cmd, 0);
    let mut child = cmd.stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn()?;
    // Each pipe drained on its own thread, so that a talkative compiler never blocks on a full one;
    // its first [`KEPT_OUTPUT`] bytes kept (the message quotes the first lines), the rest read and
    // dropped (a compiler flooding its output had taken 8 GB).
    let (sent, received) = std::sync::mpsc::channel();
    let drain = |which: usize, pipe: Option<Box<dyn Read + Send>>| {
        let sent = sent.clone();
        std::thread::spawn(move || {
            let (mut bytes, mut chunk) = (Vec::new(), vec![0u8; 8192]);
            if let Some(mut p) = pipe {
                loop {
                    match p.read(&mut chunk) {
                        Ok(0) => break,
                        Ok(n) => {
                            let room = KEPT_OUTPUT.saturating_sub(bytes.len());
                            bytes.extend_from_slice(&chunk[..n.min(room)]);
                        }
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                        Err(_) => break,
                    }
                }
            }
            let _ = sent.send((which, bytes));
        });
    };
    drain(0, child.stdout.take().map(|p| Box::new(p) as Box<dyn Read + Send>));
    drain(1, child.stderr.take().map(|p| Box::new(p) as Box<dyn Read + Send>));
    let deadline = Instant::now() + timeout;
    let kill = |child: &mut std::process::Child| {
        #[cfg(unix)]
        if let Ok(group) = libc::pid_t::try_from(child.id()) {
            // SAFETY: killpg sends a signal to the group the child leads; no memory is touched.
            unsafe { libc::killpg(group, libc::SIGKILL) };
        }
        let _ = child.kill();
        let _ = child.wait();
    };
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if crate::cancel::check().is_err() => {
                kill(&mut child);
                return Err(std::io::Error::new(std::io::ErrorKind::Interrupted, "interrupted"));
            }
            Ok(None) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(10)),
            Ok(None) => {
                kill(&mut child);
                return Ok(None);
            }
            Err(e) => {
                kill(&mut child);
                return Err(e);
            }
        }
    };
    // The output, waited for until the deadline (a daemon the compiler left may hold the pipes).
    let mut output = [Vec::new(), Vec::new()];
    for _ in 0..2 {
        let left = deadline.saturating_duration_since(Instant::now()).max(Duration::from_secs(1));
        match received.recv_timeout(left) {
            Ok((which, bytes)) => output[which] = bytes,
            Err(_) => break,
        }
    }
    let [stdout, stderr] = output;
    Ok(Some(std::process::Output { status, stdout, stderr }))
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

    /// A compiler that never finishes is stopped at the timeout with an error that says so, and
    /// one that finishes is waited for, its output kept.
    #[cfg(unix)]
    #[test]
    fn a_hung_compiler_is_stopped_at_the_timeout() {
        use std::os::unix::fs::PermissionsExt as _;
        let dir = tempfile::tempdir().unwrap();
        let hung = dir.path().join("hung-cc");
        std::fs::write(&hung, "#!/bin/sh\nexec sleep 30\n").unwrap();
        std::fs::set_permissions(&hung, std::fs::Permissions::from_mode(0o755)).unwrap();
        let start = std::time::Instant::now();
        let sources = [("a.c".to_string(), "int a(void) { return 1; }\n".to_string())];
        let e = compile(hung.to_str().unwrap(), &sources, &["a.c"], "a.so", std::time::Duration::from_millis(300))
            .unwrap_err()
            .to_string();
        assert!(start.elapsed() < std::time::Duration::from_secs(10), "{:?}", start.elapsed());
        assert!(e.contains("had not finished after 0.3 s and was stopped"), "{e}");
        // A compiler's own children are stopped with it: a wrapper that runs its compiler without
        // exec (its pid written to a file) leaves nothing running.
        let wrapper = dir.path().join("wrapper-cc");
        let pid_file = dir.path().join("child.pid");
        std::fs::write(&wrapper, format!("#!/bin/sh\nsleep 30 &\necho $! > {}\nwait\n", pid_file.display())).unwrap();
        std::fs::set_permissions(&wrapper, std::fs::Permissions::from_mode(0o755)).unwrap();
        let e = compile(wrapper.to_str().unwrap(), &sources, &["a.c"], "a.so", std::time::Duration::from_millis(500));
        assert!(e.is_err());
        let pid = std::fs::read_to_string(&pid_file).unwrap().trim().to_string();
        let alive =
            || Command::new("kill").args(["-0", &pid]).stderr(std::process::Stdio::null()).status().unwrap().success();
        let start = std::time::Instant::now();
        while alive() && start.elapsed() < std::time::Duration::from_secs(5) {
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        assert!(!alive(), "the wrapper's child {pid} still runs");
        // A compiler flooding its output is kept to its first 64 KiB.
        let mut flood = Command::new("sh");
        flood.args(["-c", "head -c 10000000 /dev/zero >&2; exit 1"]);
        let done = run_within(flood, std::time::Duration::from_secs(60)).unwrap().unwrap();
        assert_eq!((done.status.success(), done.stderr.len()), (false, KEPT_OUTPUT));
        let mut echo = Command::new("sh");
        echo.args(["-c", "echo out; echo err >&2"]);
        let done = run_within(echo, std::time::Duration::from_secs(30)).unwrap().unwrap();
        assert!(done.status.success());
        assert_eq!((done.stdout.as_slice(), done.stderr.as_slice()), (&b"out\n"[..], &b"err\n"[..]));
    }
}
