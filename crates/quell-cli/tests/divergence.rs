//! Faults during a run: divergence and step-size underflow stop with exit status 1, name the time
//! (and, for divergence, the signal) on stderr, and still write the files up to that time.

mod fault_support;

use std::process::Command;

use fault_support::{check_outputs, paper_with, scratch_dir, time_in};

/// Runs `quell ARGS OUT SCENARIO` (ARGS ending in `--out`); returns the output and its stderr.
fn run_quell(args: &[&str], out: &std::path::Path, scenario: &std::path::Path) -> (std::process::Output, String) {
    let output =
        Command::new(env!("CARGO_BIN_EXE_quell")).args(args).arg(out).arg(scenario).output().expect("run quell");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    (output, stderr)
}

#[test]
fn diverging_sampled_run_exits_1_and_keeps_the_files() {
    // The paper's example sampled at T_s = 0.5 s is unstable: x1 passes 1e9 at t = 15 s.
    let dir_tmp = scratch_dir("diverge");
    let dir = dir_tmp.path();
    let scenario = paper_with(dir, &[("output_step = 0.1 ", "output_step = 0.5 ")]);
    let out = dir.join("out");
    let (output, stderr) = run_quell(&["run", "--no-plots", "--sample-time", "0.5", "--out"], &out, &scenario);
    assert_eq!(output.status.code(), Some(1), "stderr: {stderr}");
    let t = time_in(&stderr, "diverged at t = ").unwrap_or_else(|| panic!("no time on stderr: {stderr}"));
    assert!((5.0..50.0).contains(&t), "t = {t}");
    assert!(stderr.contains("x1 (plant state)"), "the signal is not named: {stderr}");

    let summary = check_outputs(&out);
    assert_eq!(summary["outcome"]["status"], "diverged", "{summary}");
    assert_eq!(summary["outcome"]["signal"], "x1 (plant state)");
    // The rows stop before the divergent sample.
    let csv = std::fs::read_to_string(out.join("signals.csv")).unwrap_or_default();
    let last: f64 = csv.lines().last().and_then(|l| l.split(',').next()).and_then(|s| s.parse().ok()).unwrap_or(-1.0);
    assert!(last < t && last >= t - 0.5 - 1e-9, "last row t = {last}, divergence at {t}");
}

/// The diverged entry is named by its column of signals.csv (x1, with --states a column of the
/// file) and by the state's name in `[plant] states`, on stderr and in summary.json: it had read
/// "x_hat[6] (observer state)", which beside the file's 0-based keys read as the seventh state.
#[test]
fn a_diverged_state_is_named_by_its_column_and_its_name() {
    let dir_tmp = scratch_dir("diverge-named");
    let dir = dir_tmp.path();
    let scenario = paper_with(
        dir,
        &[
            ("output_step = 0.1 ", "output_step = 0.5 "),
            ("x0 = [0.0, 0.0, 0.0]", "x0 = [0.0, 0.0, 0.0]\nstates = [\"level\", \"flow\", \"heat\"]"),
        ],
    );
    let out = dir.join("out");
    let args = ["run", "--no-plots", "--states", "--sample-time", "0.5", "--out"];
    let (output, stderr) = run_quell(&args, &out, &scenario);
    assert_eq!(output.status.code(), Some(1), "stderr: {stderr}");
    assert!(stderr.contains(": x1 (plant state level) = "), "{stderr}");
    let summary = check_outputs(&out);
    assert_eq!(summary["outcome"]["signal"], "x1 (plant state level)");
    let csv = std::fs::read_to_string(out.join("signals.csv")).unwrap_or_default();
    let header: Vec<&str> = csv.lines().next().unwrap_or_default().split(',').collect();
    assert!(header.contains(&"x1") && header.contains(&"xhat1"), "{header:?}");
}

#[test]
fn step_size_underflow_exits_1_with_the_time() {
    // μ_1 = 1e300, an infinitely stiff adaptive law: the error test fails at every step size until
    // the step underflows, which must end the run (not loop) with the time.
    let dir_tmp = scratch_dir("underflow");
    let dir = dir_tmp.path();
    let scenario = paper_with(dir, &[("mu = [20.0, 30.0]", "mu = [1e300, 30.0]")]);
    let out = dir.join("out");
    let (output, stderr) = run_quell(&["run", "--no-plots", "--out"], &out, &scenario);
    assert_eq!(output.status.code(), Some(1), "stderr: {stderr}");
    let t = time_in(&stderr, "step size underflowed at t = ").unwrap_or_else(|| panic!("no time on stderr: {stderr}"));
    assert!(t >= 0.0, "t = {t}");
    let summary = check_outputs(&out);
    assert_eq!(summary["outcome"]["status"], "step_size_too_small", "{summary}");
}

#[test]
fn absurd_sample_times_are_input_errors_not_crashes() {
    // 1e-300 s: too many controller steps. With 1e300 s of delay at 1 ms: a delay line of 1e303
    // rows. Both were panics (slice index, allocation) before; now exit 2 with the key.
    let dir_tmp = scratch_dir("absurd");
    let dir = dir_tmp.path();
    let quell = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_quell")).args(args).arg("--out").arg(dir.join("out")).output().expect("run")
    };
    let out = quell(&["run", "--no-plots", "--sample-time", "1e-300"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.starts_with("error: simulation.sample_time (--sample-time): "), "{stderr}");

    let scenario = paper_with(dir, &[("delays = [1.0, 3.0]", "delays = [1e300, 3.0]")]);
    let out = quell(&["run", "--no-plots", "--sample-time", "0.001", scenario.to_str().unwrap_or_default()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("a delay line holds at most"), "{stderr}");
}

/// A sample time from the file is named by its key alone; only one given as `--sample-time` is
/// named with the flag (a file's 0.3 s, which does not divide the delays, had been blamed on the
/// flag that was not used).
#[test]
fn a_sample_time_from_the_file_is_not_blamed_on_the_flag() {
    let dir_tmp = scratch_dir("file-sample-time");
    let dir = dir_tmp.path();
    let scenario = paper_with(dir, &[("[simulation]", "[simulation]\nsample_time = 0.3")]);
    let run = |extra: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_quell"))
            .args(["run", "--no-plots", scenario.to_str().unwrap_or_default()])
            .args(extra)
            .arg("--out")
            .arg(dir.join("out"))
            .output()
            .expect("run");
        assert_eq!(out.status.code(), Some(2));
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let from_file = run(&[]);
    assert!(from_file.starts_with("error: simulation.sample_time: channel 1's delay"), "{from_file}");
    let from_flag = run(&["--sample-time", "0.3"]);
    assert!(from_flag.starts_with("error: simulation.sample_time (--sample-time): channel 1's delay"), "{from_flag}");
}

/// A run that stopped early plots |e(t)| itself on its log panel, where the largest error from t on
/// is its last spike's everywhere (a flat line: the blow-up's onset could not be seen); a run that
/// completes keeps the largest error from t on.
#[test]
fn a_diverged_runs_log_panel_shows_the_growth() {
    let dir_tmp = scratch_dir("diverge-figure");
    let dir = dir_tmp.path();
    let scenario = paper_with(dir, &[("output_step = 0.1 ", "output_step = 0.5 ")]);
    let out = dir.join("out");
    let (output, stderr) = run_quell(&["run", "--sample-time", "0.5", "--out"], &out, &scenario);
    assert_eq!(output.status.code(), Some(1), "stderr: {stderr}");
    let svg = std::fs::read_to_string(out.join("channel1.svg")).unwrap();
    assert!(
        svg.contains("Channel 1: tracking error |e(t)|, log scale (the run stopped early: its growth)"),
        "the log panel's title"
    );
    assert!(!svg.contains("largest tracking error from t on"));
    // A sampled run's figure says so: its staircases cannot be seen at every sample time.
    assert!(
        svg.contains("Channel 1: output and reference, sampled at T_s = 0.5 s (diverged at t = "),
        "the first title"
    );
    let (output, stderr) = run_quell(&["run", "--t-end", "5", "--out"], &out, &scenario);
    assert_eq!(output.status.code(), Some(0), "stderr: {stderr}");
    let svg = std::fs::read_to_string(out.join("channel1.svg")).unwrap();
    assert!(svg.contains("largest tracking error from t on, log scale"));
    assert!(!svg.contains("sampled at"), "a continuous run's title");
}
