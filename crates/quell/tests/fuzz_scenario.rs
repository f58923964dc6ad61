//! The cargo-fuzz targets' seeds and the `scenario` target's entry, in the normal test suite:
//! every committed seed (`fuzz/corpus/*/seed-*`) goes through its target's entry function, and
//! 1500 mutations of the scenario seeds and the example scenarios (a line deleted, a value swapped
//! for a huge, negative, NaN, infinite, wrongly typed or unicode one, deep nesting, a stray key)
//! go through `fuzz_entry::scenario` (read, design, and the sampled controller built). None may
//! panic; a refusal says what is wrong. A finding of the fuzzer is added here as a seed file.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

mod fuzz_entry;

use fuzz_entry::{mutate, Lcg};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The committed seeds of one target's corpus, with their text.
fn seeds(target: &str) -> Vec<(PathBuf, String)> {
    let dir = root().join("fuzz/corpus").join(target);
    let mut out: Vec<(PathBuf, String)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.file_name().is_some_and(|n| n.to_string_lossy().starts_with("seed-")))
        .map(|p| (p.clone(), std::fs::read_to_string(&p).unwrap()))
        .collect();
    out.sort();
    assert!(!out.is_empty(), "no seeds in {}", dir.display());
    out
}

/// `fuzz_entry::scenario` on `text`, which must return (not panic); the refusal, if any.
fn scenario(text: &str, what: &dyn std::fmt::Display) -> Option<String> {
    let result = catch_unwind(AssertUnwindSafe(|| fuzz_entry::scenario(text)));
    let Ok(result) = result else { panic!("{what} panicked on:\n{text}") };
    let refusal = result.err()?;
    assert!(refusal.contains(": ") && refusal.len() > 10, "{what}: a refusal that says nothing: {refusal:?}");
    Some(refusal)
}

#[test]
fn every_committed_seed_goes_through_its_target() {
    for (path, text) in seeds("scenario") {
        scenario(&text, &path.display());
    }
    // The study seeds are valid studies (a fuzzer starts best from inputs that go deep).
    let dir: Option<&Path> = None;
    for (path, text) in seeds("study") {
        let result = catch_unwind(AssertUnwindSafe(|| fuzz_entry::study(&text, dir)));
        let Ok(result) = result else { panic!("{} panicked", path.display()) };
        result.unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
}

#[test]
fn mutated_scenario_files_never_panic_and_refusals_say_why() {
    let mut bases: Vec<String> = seeds("scenario").into_iter().map(|(_, text)| text).collect();
    for name in ["paper.toml", "three-channel.toml", "siso-complex.toml", "paper-sampled.toml"] {
        bases.push(std::fs::read_to_string(root().join("examples").join(name)).unwrap());
    }
    let mut rng = Lcg(21);
    let (mut refused, mut cases) = (0, 0);
    for case in 0..1500 {
        let text = mutate(&bases[case % bases.len()], &mut rng);
        cases += 1;
        refused += usize::from(scenario(&text, &format_args!("case {case}")).is_some());
    }
    eprintln!("{cases} mutated scenario files, {refused} refused");
    // Both sides are exercised: some mutations leave a valid scenario, most break it.
    assert!(refused > cases / 2 && cases - refused >= 20, "{refused} of {cases} refused");
}
