//! Shared by the fault tests (`interrupt.rs`, `divergence.rs`): scratch directories, scenario
//! variants of the paper's example, and checks that the output files are complete.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// A fresh, empty directory under the system's temporary directory, removed when dropped.
pub fn scratch_dir(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new().prefix(&format!("quell-test-{name}-")).tempdir().expect("create scratch dir")
}

/// `examples/paper.toml` with textual replacements, written to `dir/scenario.toml`.
pub fn paper_with(dir: &Path, edits: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/paper.toml"))
        .expect("read examples/paper.toml");
    for (from, to) in edits {
        assert!(text.contains(from), "examples/paper.toml has no `{from}`");
        text = text.replacen(from, to, 1);
    }
    let path = dir.join("scenario.toml");
    std::fs::write(&path, text).expect("write scenario");
    path
}

/// The number right after `prefix` in `text` (`interrupted at t = 12.300` → 12.3).
pub fn time_in(text: &str, prefix: &str) -> Option<f64> {
    let rest = &text[text.find(prefix)? + prefix.len()..];
    let end = rest.find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e')).unwrap_or(rest.len());
    rest[..end].trim_end_matches('.').parse().ok()
}

/// Checks `signals.csv`, `design.json` and `summary.json` in `out`: present, complete (every CSV
/// row has the header's column count and parses, JSON parses), and no temporary file left.
/// Returns the summary.
pub fn check_outputs(out: &Path) -> serde_json::Value {
    let leftovers: Vec<String> = std::fs::read_dir(out)
        .expect("read output dir")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.') && n.contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left in {}: {leftovers:?}", out.display());

    let csv = std::fs::read_to_string(out.join("signals.csv")).expect("signals.csv");
    assert!(csv.ends_with('\n'), "signals.csv does not end with a newline");
    let mut lines = csv.lines();
    let columns = lines.next().expect("signals.csv header").split(',').count();
    let mut rows = 0;
    let mut last_t = f64::NEG_INFINITY;
    for (i, line) in lines.enumerate() {
        let fields: Vec<&str> = line.split(',').collect();
        assert_eq!(fields.len(), columns, "signals.csv row {} has {} fields, header {columns}", i + 1, fields.len());
        for f in &fields {
            assert!(f.parse::<f64>().is_ok(), "signals.csv row {}: `{f}` is not a number", i + 1);
        }
        let t: f64 = fields[0].parse().unwrap_or(f64::NAN);
        assert!(t > last_t, "signals.csv row {}: t = {t} after {last_t}", i + 1);
        last_t = t;
        rows += 1;
    }
    assert!(rows > 0, "signals.csv has no rows");

    let read_json = |name: &str| -> serde_json::Value {
        let text = std::fs::read_to_string(out.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        serde_json::from_str(&text).unwrap_or_else(|e| panic!("{name} does not parse: {e}"))
    };
    let _ = read_json("design.json");
    let summary = read_json("summary.json");
    assert_eq!(summary["samples"].as_u64(), Some(rows as u64), "summary.samples vs rows of signals.csv");
    summary
}
