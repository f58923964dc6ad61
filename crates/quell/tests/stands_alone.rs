//! A clone of the repository passes its tests on its own: no test, script or CI step reads a path
//! outside it (the reference data lives in `tests/data/`, with its sources in `tests/data/README.md`).

use std::path::{Path, PathBuf};

/// Every file under `dir` whose name ends in one of `exts` (or has no extension, for scripts).
fn files(dir: &Path, exts: &[&str], out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files(&path, exts, out);
        } else if path.extension().is_none_or(|e| exts.iter().any(|x| e == *x)) {
            out.push(path);
        }
    }
}

#[test]
fn no_test_or_script_reads_outside_the_repository() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut paths = Vec::new();
    for dir in ["crates/quell/tests", "crates/quell-cli/tests", "crates/quell-py/tests", "scripts", ".ci"] {
        files(&root.join(dir), &["rs", "py", "sh", "toml"], &mut paths);
    }
    assert!(paths.len() > 20, "found only {} files to check under {}", paths.len(), root.display());
    // Spelled in two pieces so that this file does not match itself.
    let (outside, machine) = (["../", "shared/"].concat(), ["/wo", "rk/"].concat());
    let offenders: Vec<_> = paths
        .iter()
        .filter(|p| std::fs::read_to_string(p).is_ok_and(|s| s.contains(&outside) || s.contains(&machine)))
        .collect();
    assert!(offenders.is_empty(), "these read beside the repository: {offenders:?}");
}

#[test]
fn the_reference_data_is_committed() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    for name in ["paper_example_points.csv", "dde_cases.json", "README.md"] {
        assert!(data.join(name).is_file(), "tests/data/{name} is missing");
    }
}
