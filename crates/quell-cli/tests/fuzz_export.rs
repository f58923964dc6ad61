//! Hostile export options through the command-line parser, from a seeded generator: every case
//! ends with status 0 or 2 (never a panic's 101), and a refusal names the flag or option at fault.

use std::process::Command;

/// Values for each flag: edges of floating point, signs, words, comment breakers, unicode.
const SAMPLE_TIMES: [&str; 10] = ["0.01", "nan", "inf", "-0.01", "0", "1e-320", "-inf", "abc", "", "0.01.0"];
const PREFIXES: [&str; 8] = ["motor1", "*/x", "a/*b", "1abc", "", "é", "a b", "_x"];
const PRECISIONS: [&str; 4] = ["f64", "f32", "f16", "F64"];

#[test]
fn hostile_export_flags_exit_0_or_2_naming_the_flag() {
    let dir = tempfile::Builder::new().prefix("quell-fuzz-export-").tempdir().unwrap();
    let scenario = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper.toml");
    let mut state: u64 = 7;
    let mut pick = |n: usize| {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (state >> 33) as usize % n
    };
    for case in 0..40 {
        let (t, p, q) = (
            SAMPLE_TIMES[pick(SAMPLE_TIMES.len())],
            PREFIXES[pick(PREFIXES.len())],
            PRECISIONS[pick(PRECISIONS.len())],
        );
        let long = "p".repeat(250);
        let prefix = if pick(8) == 0 { long.as_str() } else { p };
        let out = dir.path().join(format!("out{case}"));
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_quell"));
        cmd.arg("export").arg(&scenario).args(["--sample-time", t, "--prefix", prefix, "--precision", q, "--out"]);
        cmd.arg(&out);
        if pick(4) == 0 {
            cmd.args(["--fmu", "--compiler", "none"]);
        }
        let o = cmd.output().expect("the quell binary runs");
        let err = String::from_utf8_lossy(&o.stderr);
        let args = format!("case {case}: --sample-time {t:?} --prefix {prefix:?} --precision {q:?}");
        match o.status.code() {
            Some(0) => assert!(out.join(format!("{prefix}_controller.h")).is_file(), "{args}"),
            Some(2) => assert!(
                ["--sample-time", "sample_time", "--prefix", "prefix", "--precision", "precision"]
                    .iter()
                    .any(|flag| err.contains(flag)),
                "{args}: the refusal names no flag: {err}"
            ),
            code => panic!("{args}: status {code:?}: {err}"),
        }
        assert!(!err.contains("panicked"), "{args}: {err}");
    }
}
