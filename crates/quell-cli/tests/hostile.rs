//! Hostile and extreme inputs to the CLI: each case once crashed, hung, corrupted an output or gave
//! a silently wrong result; now each is a clear error (exit 2 naming the flag, key or path) or a
//! correct result.

use std::fs;
use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use tempfile::TempDir;

fn quell(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quell")).args(args).output().expect("the quell binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Exit status 2 and `fragment` in stderr.
fn refused(o: &Output, fragment: &str) {
    assert_eq!(o.status.code(), Some(2), "{}", stderr(o));
    assert!(stderr(o).contains(fragment), "expected {fragment:?} in:\n{}", stderr(o));
}

fn paper() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper.toml").display().to_string()
}

/// A study of the paper's example over `grid` (TOML lines), 1 s long, written into `dir`.
fn study(dir: &Path, name: &str, extra: &str) -> String {
    let text = format!("scenario = {:?}\n[simulation]\nt_end = 1.0\n{extra}", paper());
    let path = dir.join(name);
    fs::write(&path, text).unwrap();
    path.display().to_string()
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

#[test]
fn study_size_jobs_and_shard_flags_are_refused_with_their_message() {
    let tmp = TempDir::new().unwrap();
    let (dir, out) = (tmp.path(), tmp.path().join("out").display().to_string());
    // 1e12 draws with --yes aborted allocating 8 TB; near 2⁶³ it panicked.
    for runs in ["1000000000000", "9223372036854775807"] {
        let s = study(dir, "huge.toml", &format!("[monte_carlo]\nruns = {runs}\n"));
        refused(
            &quell(&["sweep", &s, "--yes", "--out", &out]),
            &format!("monte_carlo.runs: expected at most 1e9 draws (a study may have at most 1e9 runs), found {runs}"),
        );
    }
    // The refusal without --yes gives the exact count (it printed a saturated one).
    let s = study(
        dir,
        "big.toml",
        "[grid]\n\"design.beta\" = [1.0, 2.0]\n[monte_carlo]\nruns = 300000000\n\"truth.A\" = { relative = 0.05 }\n",
    );
    refused(
        &quell(&["sweep", &s, "--out", &out]),
        "the study has 600000000 runs (2 grid points × 300000000 draws), more than 1e7",
    );

    // --jobs 10000 on a 3-run study ran past 60 s; -1 got clap's "unexpected argument".
    let s = study(dir, "three.toml", "[grid]\n\"design.beta\" = [1.0, 2.0, 3.0]\n");
    for jobs in ["10000", "-1", "0", "1e3"] {
        refused(
            &quell(&["sweep", &s, "--jobs", jobs, "--out", &out]),
            &format!("invalid value '{jobs}' for '--jobs <N>': expected a number of worker threads from 1 to 1024"),
        );
    }
    // The most threads, on 3 runs: only 3 are started, so it is as quick as ever (the runs take
    // ~0.1 s; the bound is slack for a loaded machine).
    let started = Instant::now();
    let o = quell(&["sweep", &s, "--jobs", "1024", "--no-plots", "--out", &out]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(started.elapsed() < Duration::from_secs(20), "{:?}", started.elapsed());
    assert!(stderr(&o).contains("on 3 threads"), "{}", stderr(&o));
    refused(&quell(&["tune", &s, "--jobs", "-1"]), "invalid value '-1' for '--jobs <N>'");

    // --shard -1/2 got clap's "unexpected argument"; with --merge it was ignored.
    refused(&quell(&["sweep", &s, "--shard", "-1/2", "--out", &out]), "--shard: expected I/N with 0 ≤ I < N");
    refused(
        &quell(&["sweep", "--merge", &out, "--shard", "0/2", "--out", &out]),
        "--shard 0/2: --merge joins every shard into one directory, so it takes no --shard",
    );
}

#[test]
fn merge_checks_every_shards_run_indices_and_its_output_folder() {
    let tmp = TempDir::new().unwrap();
    let dir = tmp.path();
    let s = study(dir, "study.toml", "[grid]\n\"design.beta\" = [1.0, 2.0, 3.0, 4.0]\n");
    let at = |name: &str| dir.join(name).display().to_string();
    for i in 0..2 {
        let o = quell(&["sweep", &s, "--shard", &format!("{i}/2"), "--no-plots", "--out", &at(&format!("s{i}"))]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let good = fs::read_to_string(dir.join("s1/runs.csv")).unwrap();

    // Shard 0's rows under shard 1's summary (a copied runs.csv) merged with run 0 twice and run 1
    // missing.
    fs::copy(dir.join("s0/runs.csv"), dir.join("s1/runs.csv")).unwrap();
    refused(
        &quell(&["sweep", "--merge", &at("s0"), &at("s1"), "--out", &at("m")]),
        &format!(
            "--merge {}: row 1 of runs.csv is run 0, but shard 1/2 holds runs 1 + k·2 and the next of them is 1",
            at("s1")
        ),
    );
    // A runs.csv cut at a line end: named, with what is missing.
    let mut lines: Vec<&str> = good.lines().collect();
    lines.pop();
    fs::write(dir.join("s1/runs.csv"), lines.join("\n") + "\n").unwrap();
    refused(
        &quell(&["sweep", "--merge", &at("s0"), &at("s1"), "--out", &at("m")]),
        &format!("--merge {}: runs.csv holds 1 rows, but shard 1/2 has 2 runs (is runs.csv truncated?)", at("s1")),
    );
    fs::write(dir.join("s1/runs.csv"), &good).unwrap();
    // An edited summary.json: a shard index beyond the count panicked (index out of bounds); a
    // study field that differs from the first shard's passed when that shard came second.
    let summary = fs::read_to_string(dir.join("s1/summary.json")).unwrap();
    let edit = |from: &str, to: &str| {
        assert!(summary.contains(from), "{from} in {summary}");
        fs::write(dir.join("s1/summary.json"), summary.replacen(from, to, 1)).unwrap();
    };
    edit("\"index\": 1", "\"index\": 7");
    refused(
        &quell(&["sweep", "--merge", &at("s0"), &at("s1"), "--out", &at("m")]),
        &format!("--merge {}: summary.json: study.shard is 7/2: expected an index from 0 to count − 1", at("s1")),
    );
    edit("\"time_unit\": \"s\"", "\"time_unit\": \"min\"");
    for order in [[at("s0"), at("s1")], [at("s1"), at("s0")]] {
        let o = quell(&["sweep", "--merge", &order[0], &order[1], "--out", &at("m")]);
        refused(&o, "'s study.time_unit differs from ");
    }
    fs::write(dir.join("s1/summary.json"), &summary).unwrap();
    // A shard of a huge split: merging it allocated a table of 2^64 − 1 shards (capacity overflow,
    // exit 101; 2^32 aborted on the allocation).
    for n in ["18446744073709551615", "4294967296"] {
        let o = quell(&["sweep", &s, "--shard", &format!("0/{n}"), "--no-plots", "--out", &at("huge")]);
        assert!(o.status.success(), "{}", stderr(&o));
        refused(
            &quell(&["sweep", "--merge", &at("huge"), "--out", &at("m")]),
            &format!("--merge: shard 1/{n} is missing; give the output directory of every shard 0/{n} … "),
        );
    }
    // A NaN among a completed run's figures (it merged, and the summary's quantiles shifted).
    let header_and_rows: Vec<String> = good.lines().map(str::to_string).collect();
    let mut fields: Vec<String> = header_and_rows[1].split(',').map(str::to_string).collect();
    let column = header_and_rows[0].split(',').position(|h| h == "max_uf1").unwrap();
    assert_eq!(fields[5], "completed");
    fields[column] = "NaN".into();
    fs::write(
        dir.join("s1/runs.csv"),
        format!("{}\n{}\n{}\n", header_and_rows[0], fields.join(","), header_and_rows[2..].join("\n")),
    )
    .unwrap();
    refused(
        &quell(&["sweep", "--merge", &at("s0"), &at("s1"), "--out", &at("m")]),
        "runs.csv: line 2: max_uf1: expected a finite number in a completed run's row, found `NaN`",
    );
    fs::write(dir.join("s1/runs.csv"), &good).unwrap();
    // Merging into one of the shards replaced it.
    let before = fs::read_to_string(dir.join("s0/runs.csv")).unwrap();
    refused(
        &quell(&["sweep", "--merge", &at("s0"), &at("s1"), "--out", &at("s0")]),
        "is one of the --merge directories",
    );
    assert_eq!(fs::read_to_string(dir.join("s0/runs.csv")).unwrap(), before);
    let o = quell(&["sweep", "--merge", &at("s0"), &at("s1"), "--out", &at("m"), "--no-plots"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn output_path_problems_are_all_exit_2_naming_the_path() {
    let tmp = TempDir::new().unwrap();
    let dir = tmp.path();
    let s = study(dir, "study.toml", "[grid]\n\"design.beta\" = [1.0, 2.0]\n");
    // An existing file as --out.
    let file = dir.join("a-file");
    fs::write(&file, "x").unwrap();
    refused(
        &quell(&["sweep", &s, "--out", &file.display().to_string()]),
        &format!("--out {}: {} is a regular file, not a directory", file.display(), file.display()),
    );
    // A directory where runs.csv goes: was exit 1 after every run was done.
    let out = dir.join("out");
    fs::create_dir_all(out.join("runs.csv")).unwrap();
    refused(
        &quell(&["sweep", &s, "--out", &out.display().to_string()]),
        &format!("--out {}: {} is a directory, not a regular file", out.display(), out.join("runs.csv").display()),
    );
    // A dangling symbolic link where runs.csv goes: was exit 1 after every run, all work lost.
    #[cfg(unix)]
    {
        let linked = dir.join("linked");
        fs::create_dir_all(&linked).unwrap();
        std::os::unix::fs::symlink(dir.join("nowhere.csv"), linked.join("runs.csv")).unwrap();
        refused(
            &quell(&["sweep", &s, "--out", &linked.display().to_string()]),
            &format!("{} is a symbolic link, not a regular file", linked.join("runs.csv").display()),
        );
        assert!(!linked.join("summary.json").exists(), "nothing was written");
    }
    fs::create_dir_all(out.join("signals.csv")).unwrap();
    refused(&quell(&["run", &paper(), "--out", &out.display().to_string()]), "signals.csv is a directory");
    // A directory where a figure goes: was exit 1 after the run (or the sweep), its results lost.
    for (command, figure) in [("run", "channel2.svg"), ("sweep", "sweep.png")] {
        let out = dir.join(format!("figure-{command}"));
        fs::create_dir_all(out.join(figure)).unwrap();
        let input = if command == "run" { paper() } else { s.clone() };
        refused(&quell(&[command, &input, "--out", &out.display().to_string()]), &format!("{figure} is a directory"));
    }
}

#[test]
fn figures_of_an_earlier_run_do_not_stay_beside_new_data() {
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().join("out");
    fs::create_dir_all(&out).unwrap();
    // A three-channel run's figures, and a sweep's.
    for name in ["channel1.png", "channel1.svg", "channel3.png", "channel3.svg", "sweep.png", "notes.png"] {
        fs::write(out.join(name), "old").unwrap();
    }
    let scenario = tmp.path().join("short.toml");
    fs::write(&scenario, fs::read_to_string(paper()).unwrap().replacen("t_end = 100.0", "t_end = 2.0", 1)).unwrap();
    let o = quell(&["run", &scenario.display().to_string(), "--no-plots", "--out", &out.display().to_string()]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Plots skipped: no channel figure is left; files that are not a run's are kept.
    assert_eq!(names(&out), ["design.json", "notes.png", "signals.csv", "summary.json", "sweep.png"]);
    let o = quell(&["run", &scenario.display().to_string(), "--out", &out.display().to_string()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(names(&out).contains(&"channel2.svg".to_string()) && !names(&out).contains(&"channel3.png".to_string()));
    // A sweep whose grid has no figure (three axes) removes an earlier sweep.png (in a directory
    // of its own: a run's is refused, `cli.rs`' a_directory_holding_another_commands_output_is_refused).
    let out = tmp.path().join("swept");
    fs::create_dir_all(&out).unwrap();
    fs::write(out.join("sweep.png"), "old").unwrap();
    let s = study(
        tmp.path(),
        "study.toml",
        "[grid]\n\"design.beta\" = [1.0]\n\"design.mu[0]\" = [10.0]\n\"design.mu[1]\" = [10.0]\n",
    );
    let o = quell(&["sweep", &s, "--out", &out.display().to_string()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!names(&out).contains(&"sweep.png".to_string()), "{:?}", names(&out));
    assert!(stderr(&o).contains("no sweep.png: a grid of 3 keys has no figure"), "{}", stderr(&o));
}

/// A FIFO with no writer as the scenario blocked `quell design` for ever; it is refused at once.
/// A 17 MB scenario (an array of twelve million ones in design.mu) is refused before the TOML
/// parser takes its 95 bytes a byte (a 24 MB one aborted at 2 GB, with a backtrace).
#[cfg(unix)]
#[test]
fn a_pipe_or_an_oversized_file_is_refused_at_once() {
    let dir = TempDir::new().unwrap();
    let fifo = dir.path().join("scenario.toml");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    // Should the check regress, a writer ends the wait after 10 s, so the test fails, not hangs.
    let writer = fifo.clone();
    std::thread::spawn(move || {
        std::thread::sleep(Duration::from_secs(10));
        let _ = fs::OpenOptions::new().write(true).open(writer);
    });
    let started = Instant::now();
    let o = quell(&["design", fifo.to_str().unwrap()]);
    refused(&o, "a pipe or socket, not a file");
    assert!(started.elapsed() < Duration::from_secs(10), "{:?}", started.elapsed());
    let big = dir.path().join("big.toml");
    let ones = vec!["1"; 8_500_000].join(",");
    fs::write(&big, fs::read_to_string(paper()).unwrap().replace("mu = [20.0, 30.0]", &format!("mu = [{ones}]")))
        .unwrap();
    assert!(fs::metadata(&big).unwrap().len() > 16 << 20);
    let o = quell(&["design", big.to_str().unwrap()]);
    refused(&o, "longer than 16 MiB");
}

#[cfg(unix)]
#[test]
fn an_endless_input_file_is_refused_naming_its_path() {
    // /dev/zero as a scenario or study was read for ever (4 GB in 15 s); a device is no file (a
    // terminal had blocked the read; hostile review, 2026-12-06).
    for command in ["run", "sweep", "tune", "design", "export"] {
        let args = [command, "/dev/zero"];
        let started = Instant::now();
        let o = quell(&args);
        refused(&o, "/dev/zero: cannot read the");
        assert!(stderr(&o).contains("a device, not a file"), "{}", stderr(&o));
        // The path once (a study's refusal used to read "/dev/zero: /dev/zero: cannot read …").
        assert_eq!(stderr(&o).matches("/dev/zero:").count(), 1, "{}", stderr(&o));
        assert!(started.elapsed() < Duration::from_secs(20), "{args:?}: {:?}", started.elapsed());
    }
}

#[test]
fn long_prefixes_are_written_or_refused_naming_the_flag() {
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().display().to_string();
    // 190 characters: <prefix>_controller.h is 203 bytes, within a file name's 255, but its
    // temporary name (the stem and 13 more) was not: exit 1 without naming the flag.
    let prefix = format!("p{}", "x".repeat(189));
    let o = quell(&["export", &paper(), "--sample-time", "0.001", "--prefix", &prefix, "--out", &out]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(names(tmp.path()), [format!("{prefix}_controller.c"), format!("{prefix}_controller.h")]);
    let prefix = format!("p{}", "x".repeat(240));
    let o = quell(&["export", &paper(), "--sample-time", "0.001", "--prefix", &prefix, "--out", &out]);
    refused(&o, "--prefix: expected at most 200 characters, found 241");
}

#[test]
fn tune_refuses_a_grid_or_draws() {
    let tmp = TempDir::new().unwrap();
    let s = study(
        tmp.path(),
        "t.toml",
        "[grid]\n\"design.beta\" = [1.0, 2.0]\n[tune]\nobjective = \"tail_rms_e\"\nmu = [1.0, 100.0]\n",
    );
    refused(
        &quell(&["tune", &s, "--out", &tmp.path().join("o").display().to_string()]),
        "grid: tuning runs the scenario alone, so [grid] would be ignored",
    );
}

#[test]
fn the_report_prints_eta_with_significant_digits() {
    // ‖η̂‖ was printed with four decimals, so a converged η̂ of 1e-6 read 0.0000; now in scientific
    // notation, which parses back to the positive value.
    let tmp = TempDir::new().unwrap();
    let scenario = tmp.path().join("slow.toml");
    let text = fs::read_to_string(paper()).unwrap().replacen("t_end = 100.0", "t_end = 2.0", 1);
    fs::write(&scenario, text).unwrap();
    let o = quell(&[
        "run",
        &scenario.display().to_string(),
        "--no-plots",
        "--out",
        &tmp.path().join("o").display().to_string(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let line = String::from_utf8_lossy(&o.stdout).lines().find(|l| l.starts_with("channel 1:")).unwrap().to_string();
    let eta = line.split("‖η̂‖ = ").nth(1).unwrap().split(',').next().unwrap();
    assert!(eta.contains('e'), "{line}");
    let value: f64 = eta.trim().parse().unwrap();
    assert!(value > 0.0, "{line}");
}

/// A numeric flag's value that starts with '-' and a letter ("-inf") reaches the flag's own check,
/// which names it, instead of clap's "unexpected argument '-i'"; a value that is no number says
/// what a number looks like.
#[test]
fn negative_and_malformed_numbers_are_named_by_their_flag() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out").display().to_string();
    let s = study(dir.path(), "s.toml", "[grid]\n\"design.mu[0]\" = [20.0]\n");
    let p = paper();
    for (args, fragment) in [
        (vec!["run", &p, "--sample-time", "-inf", "--out", &out], "--sample-time: expected a finite sample time > 0"),
        (vec!["run", &p, "--max-steps", "-inf", "--out", &out], "'--max-steps <N>': expected a step budget"),
        (vec!["export", &p, "--sample-time", "-inf", "--out", &out], "--sample-time"),
        (
            vec!["design", &p, "--auto", "--convergence-time", "-inf"],
            "--convergence-time: expected a finite number > 0, found -inf",
        ),
        (
            vec!["design", &p, "--auto", "--u-limit", "-inf"],
            "--u-limit: expected limits > 0 (inf for none on an input), found -inf",
        ),
        (vec!["sweep", &s, "--jobs", "-inf", "--out", &out], "'--jobs <N>': expected a number of worker threads"),
        (
            vec!["run", &p, "--sample-time", " 0.001", "--out", &out],
            "expected a decimal number such as 0.001 or 1e-3, found \" 0.001\"",
        ),
    ] {
        let o = quell(&args);
        refused(&o, fragment);
        assert!(!stderr(&o).contains("unexpected argument"), "{args:?}: {}", stderr(&o));
    }
}

/// The FMU's compiler as a user names it: a relative path (from the caller's directory, not the
/// temporary one the build runs in), `$CC` with flags as make reads it, a blank `$CC` as unset; a
/// `$CC` that cannot run is named as `$CC`, not as a flag the user never gave.
#[test]
fn the_fmu_compiler_is_found_as_a_shell_would() {
    let cc = ["/usr/bin/cc", "/usr/bin/gcc"].into_iter().find(|p| Path::new(p).exists()).expect("a C compiler");
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(cc, dir.path().join("mycc")).unwrap();
    let export = |out: &str, compiler: Option<&str>, env_cc: Option<&str>| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_quell"));
        cmd.current_dir(dir.path()).args(["export", &paper(), "--sample-time", "0.01", "--fmu", "--out", out]);
        if let Some(c) = compiler {
            cmd.args(["--compiler", c]);
        }
        match env_cc {
            Some(v) => cmd.env("CC", v),
            None => cmd.env_remove("CC"),
        };
        cmd.output().unwrap()
    };
    for (out, compiler, env_cc) in
        [("a", Some("./mycc"), None), ("b", None, Some("./mycc -O1")), ("c", None, Some("  "))]
    {
        let o = export(out, compiler, env_cc);
        assert_eq!(o.status.code(), Some(0), "{compiler:?} {env_cc:?}: {}", stderr(&o));
        assert!(stderr(&o).contains("(FMI 2.0 co-simulation, binary for"), "{}", stderr(&o));
    }
    refused(&export("d", None, Some("./no-such-cc")), "error: $CC = \"./no-such-cc\": cannot run it");
    refused(&export("e", Some("./no-such-cc"), None), "error: --compiler \"./no-such-cc\": cannot run it");
}

/// `--merge` runs nothing: `--jobs` and `--yes` with it are refused (exit 2) rather than ignored.
#[test]
fn merge_refuses_the_flags_of_a_run() {
    let dir = tempfile::tempdir().unwrap();
    let shard = dir.path().display().to_string();
    for flag in [vec!["--jobs", "3"], vec!["--yes"]] {
        let mut args = vec!["sweep", "--merge", &shard];
        args.extend(flag.iter());
        let o = quell(&args);
        refused(&o, "cannot be used with");
        assert!(stderr(&o).contains(flag[0]) && stderr(&o).contains("--merge"), "{}", stderr(&o));
    }
}

/// Two commands writing one `--out` at once: while the first holds the directory's lock the second
/// is refused (exit 2) before any work, rather than mixing its files with the first's (two
/// `quell run`s did in 7 of 20 trials, two exports a header of one beside the other's source). Once
/// the lock is released the same command writes there.
#[test]
fn a_second_command_writing_the_same_out_is_refused_while_the_first_holds_it() {
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().join("out");
    fs::create_dir(&out).unwrap();
    let o = out.display().to_string();
    let held = fs::File::open(&out).unwrap();
    held.try_lock().unwrap();
    let busy = format!(
        "--out {o}: another quell command is writing there now; wait for it to finish or choose another output directory"
    );
    refused(&quell(&["run", &paper(), "--out", &o, "--no-plots"]), &busy);
    refused(&quell(&["export", &paper(), "--sample-time", "0.001", "--out", &o]), &busy);
    let s = study(tmp.path(), "two.toml", "[grid]\n\"design.beta\" = [1.0, 2.0]\n");
    refused(&quell(&["sweep", &s, "--out", &o, "--no-plots"]), &busy);
    assert!(names(&out).is_empty(), "{:?}", names(&out));
    // A running sweep's journal is not one to finish with --resume (that advice had come first).
    fs::write(out.join("runs.partial.csv"), "").unwrap();
    refused(&quell(&["sweep", &s, "--out", &o, "--no-plots"]), &busy);
    fs::remove_file(out.join("runs.partial.csv")).unwrap();
    drop(held);
    let ran = quell(&["run", &paper(), "--out", &o, "--no-plots"]);
    assert_eq!(ran.status.code(), Some(0), "{}", stderr(&ran));
    assert_eq!(names(&out), ["design.json", "signals.csv", "summary.json"]);
}

/// `--merge` given a path that is no sweep's directory (missing, a file, a run's directory) says
/// what to give: it had printed the system's "No such file or directory" alone.
#[test]
fn a_merge_of_what_is_not_a_sweeps_directory_says_what_to_give() {
    let tmp = TempDir::new().unwrap();
    let file = tmp.path().join("afile");
    fs::write(&file, "x").unwrap();
    let out = tmp.path().join("merged").display().to_string();
    // A directory `quell run` wrote: its summary.json is no sweep's.
    let run_dir = tmp.path().join("a-run");
    let ran = quell(&["run", &paper(), "--out", &run_dir.display().to_string(), "--no-plots"]);
    assert_eq!(ran.status.code(), Some(0), "{}", stderr(&ran));
    for dir in [tmp.path().join("nonexistent"), file, run_dir] {
        let d = dir.display().to_string();
        refused(&quell(&["sweep", "--merge", &d, "--out", &out]), &format!("--merge {d}: summary.json: "));
        refused(
            &quell(&["sweep", "--merge", &d, "--out", &out]),
            "; give the output directory of a `quell sweep` (its --out), which holds summary.json and runs.csv",
        );
    }
}

/// A closed stderr (`quell run … 2>&1 | head -1`, or a parent that closes the pipe) is no reason to
/// fail: std's `eprintln!` panicked there (exit 101, no output directory). Every command here
/// prints to stderr before and after its work: a run, a study and an export.
#[test]
fn a_closed_stderr_loses_the_messages_not_the_work() {
    let tmp = TempDir::new().unwrap();
    let dir = tmp.path();
    let sweep = study(dir, "grid.toml", "[grid]\n\"design.beta\" = [1.0, 2.0]\n");
    let out = |name: &str| dir.join(name).display().to_string();
    let (run, swept, exported, paper) = (out("run"), out("swept"), out("exported"), paper());
    let cases: [(Vec<&str>, &str, &str); 3] = [
        (vec!["run", &paper, "--no-plots", "--out", &run], &run, "signals.csv"),
        (vec!["sweep", &sweep, "--no-plots", "--out", &swept], &swept, "runs.csv"),
        (vec!["export", &paper, "--sample-time", "0.01", "--out", &exported], &exported, "quell_controller.c"),
    ];
    for (args, out, file) in cases {
        let mut child = Command::new(env!("CARGO_BIN_EXE_quell"))
            .args(&args)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stderr.take());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(0), "{args:?}");
        assert!(Path::new(out).join(file).is_file(), "{args:?}: {:?}", names(Path::new(out)));
    }
}

/// A write past the file-size limit (`ulimit -f`) fails as a full disk does: exit 1 naming the
/// file and "File too large", the earlier run's files kept and no temporary file left (SIGXFSZ had
/// killed quell with status 153 and no word; hostile review, 2026-12-06).
#[test]
#[cfg(unix)]
fn a_write_past_the_file_size_limit_is_an_error_not_a_kill() {
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("run");
    let o = quell(&["run", &paper(), "--out", out.to_str().unwrap(), "--no-plots", "--t-end", "5"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let before = fs::read(out.join("signals.csv")).unwrap();
    // 200 blocks of 512 bytes: the 100 s run's signals.csv (about 300 kB) does not fit.
    let limited = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -f 200 && exec {} run {} --out {} --no-plots",
            env!("CARGO_BIN_EXE_quell"),
            paper(),
            out.display()
        ))
        .output()
        .unwrap();
    assert_eq!(limited.status.code(), Some(1), "{}", stderr(&limited));
    assert!(stderr(&limited).contains("File too large"), "{}", stderr(&limited));
    assert_eq!(fs::read(out.join("signals.csv")).unwrap(), before);
    assert_eq!(names(&out), ["design.json", "signals.csv", "summary.json"]);
}

/// One shard of a 10⁹-point grid runs in the memory of its runs: the summary had kept a slot for
/// every grid point (24 GB: aborted under `ulimit -v`; hostile review, 2026-12-06). Three axes of
/// 999 values (997,002,999 points, under the 10⁹ runs a study may have), run 5 of them alone,
/// under a 2 GB address-space limit.
#[test]
#[cfg(unix)]
fn a_shard_of_a_billion_point_grid_runs_in_its_own_memory() {
    let dir = TempDir::new().unwrap();
    let values = |a: f64, b: f64| (0..999).map(|i| format!("{}", a + i as f64 * (b - a) / 998.0)).collect::<Vec<_>>();
    let grid = format!(
        "[grid]\n\"design.mu[0]\" = [{}]\n\"design.mu[1]\" = [{}]\n\"design.beta\" = [{}]\n",
        values(10.0, 50.0).join(", "),
        values(10.0, 50.0).join(", "),
        values(0.5, 2.0).join(", ")
    );
    let file = study(dir.path(), "huge.toml", &grid);
    let out = dir.path().join("shard");
    let limited = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v 2000000 && exec {} sweep {file} --out {} --no-plots --yes --shard 5/997002999",
            env!("CARGO_BIN_EXE_quell"),
            out.display()
        ))
        .output()
        .unwrap();
    assert_eq!(limited.status.code(), Some(0), "{}", stderr(&limited));
    let rows = fs::read_to_string(out.join("runs.csv")).unwrap();
    assert_eq!(rows.lines().filter(|l| !l.starts_with('#')).count(), 2, "{rows}");
    assert!(rows.contains("\n5,5,0,"), "{rows}");
}

/// A command whose output would replace its own input is refused, the input kept: a scenario named
/// signals.csv run into its own directory had been replaced by its signals (hostile review,
/// 2026-12-06); so for a study named runs.csv and a scenario named like an export's header.
#[test]
fn an_output_that_would_replace_the_input_is_refused() {
    let dir = TempDir::new().unwrap();
    let d = dir.path().to_str().unwrap();
    let text = fs::read_to_string(paper()).unwrap();
    for (name, args) in [
        ("signals.csv", vec!["run", "--no-plots", "--t-end", "1"]),
        ("quell_controller.h", vec!["export", "--sample-time", "0.001"]),
    ] {
        let input = dir.path().join(name);
        fs::write(&input, &text).unwrap();
        let mut all = args.clone();
        all.extend([input.to_str().unwrap(), "--out", d]);
        let o = quell(&all);
        refused(&o, &format!("its {name} would replace the input file"));
        assert_eq!(fs::read_to_string(&input).unwrap(), text, "{name}");
    }
    let study = dir.path().join("runs.csv");
    fs::write(&study, format!("scenario = {:?}\n[simulation]\nt_end = 1.0\n", paper())).unwrap();
    let o = quell(&["sweep", study.to_str().unwrap(), "--out", d, "--no-plots"]);
    refused(&o, "its runs.csv would replace the input file");
    // Nor the scenario a study names (a sweep had replaced a scenario called summary.json with its
    // summary, and a tune one called tune.json; hostile review, 2026-12-07).
    for (name, command, extra) in
        [("summary.json", "sweep", ""), ("tune.json", "tune", "[tune]\nobjective = \"settle_t\"\nmu = [2.0, 200.0]\n")]
    {
        let scenario = dir.path().join(name);
        fs::write(&scenario, &text).unwrap();
        let study = dir.path().join(format!("{command}-study.toml"));
        fs::write(&study, format!("scenario = {name:?}\n[simulation]\nt_end = 1.0\n{extra}")).unwrap();
        let o = quell(&[command, study.to_str().unwrap(), "--out", d, "--no-plots"]);
        refused(&o, &format!("its {name} would replace the input file"));
        assert_eq!(fs::read_to_string(&scenario).unwrap(), text, "{name}");
    }
    // Nor by a resumed sweep whose journal holds every run, which finishes without running any
    // (it had written its summary over the scenario; review, 2026-12-07).
    let elsewhere = TempDir::new().unwrap();
    let study = dir.path().join("sweep-study.toml");
    let o = quell(&["sweep", study.to_str().unwrap(), "--out", elsewhere.path().to_str().unwrap(), "--no-plots"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    fs::copy(elsewhere.path().join("runs.csv"), dir.path().join("runs.partial.csv")).unwrap();
    let o = quell(&["sweep", study.to_str().unwrap(), "--out", d, "--no-plots", "--resume"]);
    refused(&o, "its summary.json would replace the input file");
    assert_eq!(fs::read_to_string(dir.path().join("summary.json")).unwrap(), text);
}

/// A record too large for memory under `--sample-time` is named as such: it had been told
/// "0.1 s is not a whole number of samples of 0.1 s (1.000000 samples)" (hostile review).
#[test]
fn a_sampled_record_too_large_is_named_by_its_size() {
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("o");
    let args = ["run", &paper(), "--t-end", "1000000", "--output-step", "0.1", "--sample-time", "0.1", "--no-plots"];
    let o = quell(&[&args[..], &["--out", out.to_str().unwrap()]].concat());
    refused(&o, "rows of 216 bytes");
    assert!(!stderr(&o).contains("whole number of samples"), "{}", stderr(&o));
}
