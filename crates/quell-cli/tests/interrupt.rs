//! Ctrl-C during a long run: exit status 1, the time on stderr, and complete output files of what
//! was computed (every file is written to a temporary name and renamed into place).

mod fault_support;

use std::process::{Command, Stdio};
use std::time::Duration;

use fault_support::{check_outputs, paper_with, scratch_dir};

fn sigint(pid: u32) {
    let status = Command::new("kill").args(["-INT", &pid.to_string()]).status().expect("run kill");
    assert!(status.success(), "kill -INT {pid} failed");
}

/// Runs the paper's example to t = 1e5 s (~40 s of work in release) into `dir/out`, sends
/// `signals` (e.g. `-INT`), 20 ms apart, and checks that it stopped at a sample with exit status 1
/// and complete files.
fn interrupt_long_run(tag: &str, signals: &[&str]) {
    let dir_tmp = scratch_dir(tag);
    let dir = dir_tmp.path();
    let scenario = paper_with(dir, &[("t_end = 100.0", "t_end = 100000.0")]);
    let out = dir.join("out");
    // The first signal must reach the run after it has recorded a sample. On a loaded machine the
    // process may not get there within the first wait; the run then (rightly) quits on a second
    // signal without writing files, or does not stop at a sample, so wait longer and try again.
    let mut wait = Duration::from_millis(500);
    let (output, stderr) = loop {
        let child = Command::new(env!("CARGO_BIN_EXE_quell"))
            .arg("run")
            .arg(&scenario)
            .arg("--out")
            .arg(&out)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start quell");
        std::thread::sleep(wait);
        for (k, signal) in signals.iter().enumerate() {
            // A second signal while the files are being written must not leave half files either.
            if k > 0 {
                std::thread::sleep(Duration::from_millis(20));
            }
            let _ = Command::new("kill").args([*signal, &child.id().to_string()]).status();
        }
        let output = child.wait_with_output().expect("wait for quell");
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        if !stderr.contains("interrupted at t = ") && wait < Duration::from_secs(8) {
            wait *= 2;
            continue;
        }
        break (output, stderr);
    };

    assert_eq!(output.status.code(), Some(1), "stderr: {stderr}");
    let t =
        fault_support::time_in(&stderr, "interrupted at t = ").unwrap_or_else(|| panic!("no time on stderr: {stderr}"));
    assert!(t > 0.0 && t < 100000.0, "t = {t}");
    let summary = check_outputs(&out);
    assert_eq!(summary["outcome"]["status"], "interrupted", "{summary}");
    let t_summary = summary["outcome"]["t"].as_f64().expect("outcome.t");
    assert!((t_summary - t).abs() < 1e-2, "summary t = {t_summary}, stderr t = {t}");
}

#[test]
fn ctrl_c_leaves_complete_files() {
    interrupt_long_run("interrupt", &["-INT", "-INT"]);
}

#[test]
fn sigterm_is_handled_like_ctrl_c() {
    // A batch system's time limit (Slurm sends SIGTERM) killed the run with nothing written.
    interrupt_long_run("sigterm", &["-TERM"]);
}

#[test]
fn ctrl_c_stops_a_run_recorded_only_at_its_ends() {
    // A run of 1e6 s recorded only at its ends: the next recorded sample is minutes of solving
    // away. The run reports its progress every 256 steps between samples too, so the first Ctrl-C
    // stops it (it had needed a second one, which quit without writing).
    let dir_tmp = scratch_dir("interrupt-sparse");
    let dir = dir_tmp.path();
    let scenario = paper_with(dir, &[("t_end = 100.0", "t_end = 1e6"), ("output_step = 0.1", "output_step = 1e6")]);
    let mut child = Command::new(env!("CARGO_BIN_EXE_quell"))
        .arg("run")
        .arg(&scenario)
        .arg("--no-plots")
        .arg("--out")
        .arg(dir.join("out"))
        .stderr(Stdio::piped())
        .spawn()
        .expect("start quell");
    std::thread::sleep(Duration::from_millis(500));
    sigint(child.id());
    let started = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("poll") {
            break status;
        }
        assert!(started.elapsed() < Duration::from_secs(10), "the first Ctrl-C did not stop the run");
        std::thread::sleep(Duration::from_millis(20));
    };
    let output = child.wait_with_output().expect("stderr");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(status.code(), Some(1), "{stderr}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["outcome"]["status"], "interrupted", "{summary}");
    assert!(summary["outcome"]["t"].as_f64().unwrap() < 1e6, "{summary}");
}

#[test]
#[allow(non_snake_case)]
fn ctrl_c_during_a_large_design_quits_at_once() {
    // A 500-state plant whose 500 observer poles two outputs must place: seconds of pole placement
    // (which KNV0 then refuses). Ctrl-C quits at once with status 1, as for an unfinished run (not
    // the shell's 130, docs/errors.md), and says that nothing was printed.
    let n = 500;
    let mut state: u64 = 1;
    let mut next = || {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let rows = |m: &[Vec<f64>]| {
        let row = |r: &Vec<f64>| format!("[{}]", r.iter().map(|x| format!("{x:e}")).collect::<Vec<_>>().join(", "));
        format!("[{}]", m.iter().map(row).collect::<Vec<_>>().join(", "))
    };
    let mut A = vec![vec![0.0; n]; n];
    for (r, row) in A.iter_mut().enumerate() {
        for (c, a) in row.iter_mut().enumerate() {
            *a = if r == c { -1.0 - 0.05 * r as f64 } else { 0.02 * next() };
        }
    }
    let B: Vec<Vec<f64>> = (0..n).map(|_| vec![next(), next()]).collect();
    let C: Vec<Vec<f64>> = (0..2).map(|j| B.iter().map(|b| b[j]).collect()).collect();
    let poles: Vec<String> = (0..n).map(|j| format!("{:e}", -1.3 - 0.05 * j as f64)).collect();
    let text = format!(
        "[plant]\nA = {}\nB = {}\nC = {}\ndelays = [0.0, 0.0]\n[design]\nobserver_poles = [{}]\n\
         channel_poles = [[-2.0], [-3.0]]\nreference_filter_poles = [[-1.0], [-1.0]]\nmu = [1.0, 1.0]\nbeta = 1.0\n\
         [reference]\ncomponents = [{{ bias = 1.0 }}, {{ bias = 1.0 }}]\n",
        rows(&A),
        rows(&B),
        rows(&C),
        poles.join(", ")
    );
    let tmp = scratch_dir("design-interrupt");
    let file = tmp.path().join("large.toml");
    std::fs::write(&file, text).unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_quell"))
        .arg("design")
        .arg(&file)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start quell");
    std::thread::sleep(Duration::from_millis(1000));
    let sent = std::time::Instant::now();
    sigint(child.id());
    let output = child.wait_with_output().expect("wait for quell");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("interrupted during the design; nothing was printed"), "{stderr}");
    assert!(output.stdout.is_empty());
    // The handler quits at once; the bound is for a machine at load 12, where the process may
    // wait seconds for a core.
    assert!(sent.elapsed() < Duration::from_secs(10), "quit {:?} after the signal", sent.elapsed());
}

#[test]
fn ctrl_c_stops_the_automatic_designs_verification_and_writes_nothing() {
    // The paper with an empty [design] over 2e5 s: each verifying simulation takes seconds. Ctrl-C
    // stops it at once: status 1, the reason, and no --write file.
    let dir_tmp = scratch_dir("interrupt-auto");
    let dir = dir_tmp.path();
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/paper.toml")).unwrap();
    let (start, end) = (text.find("[design]").unwrap(), text.find("[reference]").unwrap());
    let text = format!("{}[design]\n{}", &text[..start], &text[end..]).replacen("t_end = 100.0", "t_end = 2e5", 1);
    let (scenario, written) = (dir.join("empty.toml"), dir.join("auto.toml"));
    std::fs::write(&scenario, text).unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_quell"))
        .args(["design", scenario.to_str().unwrap(), "--auto", "--write", written.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start quell");
    std::thread::sleep(Duration::from_millis(700));
    sigint(child.id());
    let started = std::time::Instant::now();
    let output = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(started.elapsed() < Duration::from_secs(5), "Ctrl-C took {:?}", started.elapsed());
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("interrupted during the automatic design's verifying simulations"), "{stderr}");
    assert!(!written.exists());
}

/// A run started with SIGINT ignored (a shell without job control starts `quell … &` so, that
/// Ctrl-C at the terminal spares background work) keeps ignoring it, and SIGTERM still stops it
/// with its files written. The handler took SIGINT back, and such a sweep stopped.
#[test]
fn an_ignored_sigint_stays_ignored_and_sigterm_still_stops_the_run() {
    use std::os::unix::process::CommandExt;
    let dir_tmp = scratch_dir("ignored-sigint");
    let dir = dir_tmp.path();
    let scenario = paper_with(dir, &[("t_end = 100.0", "t_end = 100000.0")]);
    let out = dir.join("out");
    let mut command = Command::new(env!("CARGO_BIN_EXE_quell"));
    command.arg("run").arg(&scenario).arg("--out").arg(&out).stdout(Stdio::piped()).stderr(Stdio::piped());
    // SAFETY: between fork and exec only signal(2), which is async-signal-safe.
    unsafe {
        command.pre_exec(|| {
            libc::signal(libc::SIGINT, libc::SIG_IGN);
            Ok(())
        });
    }
    let mut child = command.spawn().expect("start quell");
    std::thread::sleep(Duration::from_millis(1500));
    sigint(child.id());
    std::thread::sleep(Duration::from_millis(1500));
    assert!(child.try_wait().expect("poll quell").is_none(), "SIGINT, ignored at start, stopped the run");
    let _ = Command::new("kill").args(["-TERM", &child.id().to_string()]).status();
    let output = child.wait_with_output().expect("wait for quell");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "stderr: {stderr}");
    assert!(stderr.contains("interrupted at t = "), "{stderr}");
    assert_eq!(check_outputs(&out)["outcome"]["status"], "interrupted");
}

/// A signal while the FMU's compiler runs stops it with the processes it started and removes its
/// temporary directory; quell exits 1 saying so and writes nothing (the compiler had run on,
/// orphaned, and its directory of sources had stayed in the temporary directory; hostile review,
/// 2026-12-06).
#[test]
#[cfg(unix)]
fn a_signal_during_the_fmu_build_stops_the_compiler_and_leaves_nothing() {
    use std::os::unix::fs::PermissionsExt as _;
    let dir_tmp = scratch_dir("fmu-signal");
    let dir = dir_tmp.path();
    let temporary = dir.join("tmp");
    std::fs::create_dir(&temporary).unwrap();
    let (pid_file, compiler) = (dir.join("cc.pid"), dir.join("slow-cc"));
    // A compiler that runs a child without exec, writing the child's pid when it has started.
    std::fs::write(&compiler, format!("#!/bin/sh\nsleep 60 &\necho $! > {}\nwait\n", pid_file.display())).unwrap();
    std::fs::set_permissions(&compiler, std::fs::Permissions::from_mode(0o755)).unwrap();
    let scenario = paper_with(dir, &[]);
    let out = dir.join("out");
    let child = Command::new(env!("CARGO_BIN_EXE_quell"))
        .args(["export", scenario.to_str().unwrap(), "--sample-time", "0.05", "--fmu", "--compiler"])
        .arg(&compiler)
        .arg("--out")
        .arg(&out)
        .env("TMPDIR", &temporary)
        .stderr(Stdio::piped())
        .spawn()
        .expect("start quell");
    let waited = std::time::Instant::now();
    while !pid_file.exists() || std::fs::read_to_string(&pid_file).unwrap().trim().is_empty() {
        assert!(waited.elapsed() < Duration::from_secs(30), "the compiler never started");
        std::thread::sleep(Duration::from_millis(20));
    }
    let status = Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap();
    assert!(status.success());
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("interrupted while the compiler built the FMU; it was stopped and nothing was written"),
        "{stderr}"
    );
    let pid = std::fs::read_to_string(&pid_file).unwrap().trim().to_string();
    let alive = || Command::new("kill").args(["-0", &pid]).stderr(Stdio::null()).status().unwrap().success();
    let start = std::time::Instant::now();
    while alive() && start.elapsed() < Duration::from_secs(5) {
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(!alive(), "the compiler's child {pid} still runs");
    assert_eq!(std::fs::read_dir(&temporary).unwrap().count(), 0, "a temporary directory was left");
    assert!(!out.join("quell.fmu").exists() && !out.join("quell_controller.c").exists());
}
