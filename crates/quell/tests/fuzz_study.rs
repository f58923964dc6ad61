//! A deterministic fuzz test of study files, in the normal test suite: the example studies mutated
//! by a seeded generator (a line deleted, a value swapped for a huge, negative, NaN, infinite,
//! wrongly typed or unicode one, deep nesting, a stray key) must never panic; a refused file names
//! a key (`StudyError::key`, never empty) and says why.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

mod fuzz_entry;

use fuzz_entry::{mutate, Lcg};

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
