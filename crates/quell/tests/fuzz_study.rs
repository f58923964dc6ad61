//! A deterministic fuzz test of study files, in the normal test suite: the example studies mutated
//! by a seeded generator (a line deleted, a value swapped for a huge, negative, NaN, infinite,
//! wrongly typed or unicode one, deep nesting, a stray key) must never panic; a refused file names
//! a key (`StudyError::key`, never empty) and says why.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

mod fuzz_entry;

/// A tiny LCG: the same cases on every run.
struct Lcg(u64);

impl Lcg {
    fn below(&mut self, n: usize) -> usize {
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

fn mutate(text: &str, rng: &mut Lcg) -> String {
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

#[test]
fn mutated_study_files_never_panic_and_errors_name_a_key() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/studies");
    let bases: Vec<String> = ["decoupling.toml", "mismatch.toml", "monte-carlo-A.toml", "tune.toml"]
        .iter()
        .map(|f| std::fs::read_to_string(dir.join(f)).unwrap_or_else(|e| panic!("{f}: {e}")))
        .collect();
    let mut rng = Lcg(2026);
    let (mut refused, mut cases) = (0, 0);
    for case in 0..4000 {
        let text = mutate(&bases[case % bases.len()], &mut rng);
        let result = catch_unwind(AssertUnwindSafe(|| fuzz_entry::study(&text, Some(&dir))));
        let Ok(result) = result else { panic!("case {case} panicked on:\n{text}") };
        cases += 1;
        if let Err(e) = result {
            refused += 1;
            assert!(!e.key.trim().is_empty() && !e.message.trim().is_empty(), "case {case}: {e:?} for:\n{text}");
        }
    }
    eprintln!("{cases} mutated study files, {refused} refused");
    assert!(refused > cases / 2, "the mutations should mostly break the files: {refused} of {cases}");
}
