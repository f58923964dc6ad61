//! The entry functions the seeded fuzz tests (`tests/fuzz_study.rs`, `tests/fuzz_export.rs`) and
//! the cargo-fuzz targets (`fuzz/fuzz_targets/*.rs`, which include this file by path) share. Each
//! takes one input, must not panic, and returns what was refused, so that both can check it.
#![allow(dead_code)] // each user takes a part

use std::path::Path;

use quell::export::{generate, generate_fmu, ExportOptions, FmiVersion, Precision};
use quell::study::{Study, StudyError};
use quell::{Design, Scenario};

/// A study file's text: read (with `dir` for a `scenario = "file"` key), then its size and the grid
/// indices of its last point computed.
pub fn study(text: &str, dir: Option<&Path>) -> Result<(), StudyError> {
    let study = Study::from_toml(text, dir)?;
    let _ = (study.len(), study.grid_index(study.points().saturating_sub(1)));
    Ok(())
}

/// A scenario file's text: read and validated, then designed, and with a `sample_time` the
/// controller built (the exact discretization and the delay lines). The first refusal's message.
pub fn scenario(text: &str) -> Result<(), String> {
    let scenario = Scenario::from_toml(text).map_err(|e| e.to_string())?;
    let design = scenario.design().map_err(|e| e.to_string())?;
    if let Some(sample_time) = scenario.simulation.sample_time {
        quell::Controller::new(&design, sample_time).map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// Export options drawn from bytes: sample time, prefix, precision, scenario name, FMU or not.
#[derive(Debug, Clone)]
pub struct ExportCase {
    pub sample_time: f64,
    pub prefix: String,
    pub precision: String,
    pub scenario_name: Option<String>,
    pub fmu: bool,
}

/// Sample times at the edges: NaN, infinities, zero, negative, subnormal, huge, and ordinary ones.
const SAMPLE_TIMES: [f64; 12] =
    [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 0.0, -0.01, 5e-324, 1e-300, 1e300, f64::MAX, 0.01, 0.5, 1e-3];
/// Pieces of prefixes and names: comment breakers, C keywords, unicode, separators, long runs.
const PIECES: [&str; 16] =
    ["motor", "_", "1", "*/", "/*", "//", "\n", "\"", "\\", "é", "☃", "\u{202e}", " ", "int", "", "-"];

/// The bytes a case is drawn from, one at a time (0 once they run out).
struct Draw<'a>(std::slice::Iter<'a, u8>);

impl Draw<'_> {
    fn next(&mut self) -> usize {
        self.0.next().copied().unwrap_or(0) as usize
    }

    /// `count` pieces, runs of letters and other characters.
    fn text(&mut self, count: usize) -> String {
        (0..count)
            .map(|_| match self.next() % 20 {
                k @ 0..16 => PIECES[k].to_string(),
                16 => "a".repeat(self.next() * 2),
                k => char::from_u32(0x20 + (self.next() * 97 + k) as u32 % 0x2FF).map_or("?".into(), String::from),
            })
            .collect()
    }
}

impl ExportCase {
    /// Each byte chooses one part of the case, in turn; missing bytes choose the first option.
    pub fn from_bytes(data: &[u8]) -> ExportCase {
        let mut d = Draw(data.iter());
        let sample_time = match d.next() % 3 {
            0 => SAMPLE_TIMES[d.next() % SAMPLE_TIMES.len()],
            1 => f64::from_bits((0..8).fold(0u64, |acc, _| acc << 8 | d.next() as u64)),
            _ => 0.01 * (1 + d.next()) as f64,
        };
        let prefix = match d.next() % 4 {
            0 => "motor1".to_string(),
            _ => {
                let count = 1 + d.next() % 6;
                d.text(count)
            }
        };
        let precision = ["f64", "f32", "f16", "", "F64", "double"][d.next() % 6].to_string();
        let scenario_name = (d.next() % 2 == 0).then(|| {
            let count = d.next() % 8;
            d.text(count)
        });
        ExportCase { sample_time, prefix, precision, scenario_name, fmu: d.next() % 4 == 0 }
    }
}

/// `case` exported from `design` (the C pair, and the FMU, FMI 2.0 or 3.0, without compiling when `case.fmu`). A
/// refusal is its message, which must name the option at fault: `prefix:`, `precision:`, or the
/// sample time (`simulation.sample_time` or `sample_time`). On success the header's comments are
/// well formed: every `/*` closes before the next one opens.
pub fn export(design: &Design, case: &ExportCase) -> Result<(), String> {
    let precision: Precision = case.precision.parse().map_err(|e: quell::export::ExportError| e.to_string())?;
    let options = ExportOptions {
        prefix: case.prefix.clone(),
        precision,
        scenario_name: case.scenario_name.clone(),
        ..ExportOptions::default()
    };
    let code = if case.fmu {
        // Both versions, chosen without another draw so that the seeded sequences stay as they were.
        let version = if case.prefix.len().is_multiple_of(2) { FmiVersion::V2 } else { FmiVersion::V3 };
        generate_fmu(design, case.sample_time, &options, None, version).map(|f| f.code)
    } else {
        generate(design, case.sample_time, &options)
    }
    .map_err(|e| e.to_string())?;
    for text in [&code.header, &code.source] {
        let mut rest = text.as_str();
        while let Some(open) = rest.find("/*") {
            let after = &rest[open + 2..];
            let close = after.find("*/").unwrap_or_else(|| panic!("a comment never closes in:\n{text}"));
            assert!(!after[..close].contains("/*"), "a comment opens inside another in:\n{text}");
            rest = &after[close + 2..];
        }
    }
    Ok(())
}

/// Whether a refusal of [`export`] names the option at fault.
pub fn names_an_export_option(message: &str) -> bool {
    ["prefix:", "precision:", "sample_time", "sample time"].iter().any(|key| message.contains(key))
}

/// A tiny LCG: the same cases on every run of a seeded test.
pub struct Lcg(pub u64);

impl Lcg {
    pub fn below(&mut self, n: usize) -> usize {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 33) as usize) % n.max(1)
    }
}

/// Values that replace a right-hand side: edges of floating point, wrong types, unicode.
const VALUES: [&str; 16] = [
    "1e308",
    "-1e308",
    "-1",
    "0",
    "nan",
    "inf",
    "-inf",
    "9223372036854775807",
    "-9223372036854775808",
    "1e-320",
    "\"x\"",
    "true",
    "[]",
    "{}",
    "\"\u{202e}é☃\"",
    "[[1.0, \"a\"], [true]]",
];

/// `text` with one to three lines changed: deleted, its value replaced by one of [`VALUES`], or a
/// deeply nested array or a stray unicode key inserted before it.
pub fn mutate(text: &str, rng: &mut Lcg) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for _ in 0..1 + rng.below(3) {
        let i = rng.below(lines.len());
        match rng.below(5) {
            0 => {
                lines.remove(i);
            }
            1 | 2 => {
                if let Some(eq) = lines[i].find('=') {
                    let value = VALUES[rng.below(VALUES.len())];
                    lines[i] = format!("{} {value}", &lines[i][..=eq]);
                }
            }
            3 => {
                let depth = 1 + rng.below(200);
                lines.insert(i, format!("deep = {}1.0{}", "[".repeat(depth), "]".repeat(depth)));
            }
            _ => lines.insert(i, format!("\"ключ.{}\" = {}", rng.below(9), VALUES[rng.below(VALUES.len())])),
        }
        if lines.is_empty() {
            break;
        }
    }
    lines.join("\n")
}
