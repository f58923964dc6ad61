//! `quell sweep` end to end: sharded and merged equals unsharded, exit codes and messages for
//! bad study files and bad merges, Ctrl-C leaves complete rows marked partial.

use std::fs;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::Duration;

fn quell(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quell")).args(args).output().expect("the quell binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn scratch(tag: &str) -> tempfile::TempDir {
    tempfile::Builder::new().prefix(&format!("quell-sweep-test-{tag}-")).tempdir().unwrap()
}

fn write_study(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    fs::write(&p, text).unwrap();
    p.display().to_string()
}

const STUDY: &str = r#"
scenario = "paper.toml"
[simulation]
t_end = 10.0
rtol = 1e-6
atol = 1e-6
[grid]
"design.mu[0]" = [10.0, 40.0]
"design.beta" = [1.0, 2.0]
[monte_carlo]
runs = 2
seed = 5
"plant.x0" = { normal = 0.2 }
"#;

fn paper_into(dir: &Path) {
    fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper.toml"), dir.join("paper.toml")).unwrap();
}

/// runs.csv without the wall_ms column (the only one that depends on the machine).
fn rows_without_wall_time(dir: &Path) -> Vec<String> {
    let text = fs::read_to_string(dir.join("runs.csv")).unwrap();
    // Found by name: the drawn values follow it. (No field of these studies is quoted.)
    let at = text.lines().next().unwrap().split(',').position(|h| h == "wall_ms").unwrap();
    let without =
        |l: &str| l.split(',').enumerate().filter(|&(i, _)| i != at).map(|(_, f)| f).collect::<Vec<_>>().join(",");
    text.lines().map(|l| if l.starts_with('#') { l.to_string() } else { without(l) }).collect()
}

#[test]
fn sharded_and_merged_equals_unsharded() {
    let dir_tmp = scratch("shards");
    let dir = dir_tmp.path();
    paper_into(dir);
    let study = write_study(dir, "study.toml", STUDY);
    let out = |name: &str| dir.join(name).display().to_string();
    let o = quell(&["sweep", &study, "--out", &out("all"), "--jobs", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("8 of 8 runs: 8 completed"), "{}", stderr(&o));
    for name in ["runs.csv", "summary.json", "sweep.png", "sweep.svg"] {
        assert!(dir.join("all").join(name).is_file(), "{name}");
    }
    for i in 0..3 {
        let o = quell(&[
            "sweep",
            &study,
            "--shard",
            &format!("{i}/3"),
            "--out",
            &out(&format!("s{i}")),
            "--no-plots",
            "--jobs",
            "1",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let o = quell(&["sweep", "--merge", &out("s2"), &out("s0"), &out("s1"), "--out", &out("merged")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (all, merged) = (rows_without_wall_time(&dir.join("all")), rows_without_wall_time(&dir.join("merged")));
    assert_eq!(all.len(), 9);
    assert_eq!(all, merged);
    let summary = |d: &str| {
        let v: serde_json::Value =
            serde_json::from_str(&fs::read_to_string(dir.join(d).join("summary.json")).unwrap()).unwrap();
        v["points"].as_array().unwrap().len()
    };
    assert_eq!(summary("all"), 4);
    assert_eq!(summary("merged"), 4);

    // With the runaway rules off (+∞, which summary.json writes as null) the shards merge too.
    let off = write_study(dir, "off.toml", &format!("{STUDY}[runaway]\npeak = inf\nsteps = inf\n"));
    for i in 0..2 {
        let o = quell(&["sweep", &off, "--shard", &format!("{i}/2"), "--out", &out(&format!("off{i}")), "--no-plots"]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let o = quell(&["sweep", "--merge", &out("off0"), &out("off1"), "--out", &out("off-merged")]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(rows_without_wall_time(&dir.join("off-merged")), all);

    // Merging a shard twice, leaving one out, or mixing studies is refused with exit code 2.
    let o = quell(&["sweep", "--merge", &out("s0"), &out("s0"), &out("s1"), "--out", &out("bad")]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("shard 0/3 is given twice"), "{}", stderr(&o));
    let o = quell(&["sweep", "--merge", &out("s0"), &out("s1"), "--out", &out("bad")]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("shard 2/3 is missing"), "{}", stderr(&o));
    let other = write_study(dir, "other.toml", &STUDY.replace("seed = 5", "seed = 6"));
    let o = quell(&["sweep", &other, "--shard", "1/3", "--out", &out("o1"), "--no-plots"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = quell(&["sweep", "--merge", &out("s0"), &out("o1"), &out("s2"), "--out", &out("bad")]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("comes from a different study than"), "{}", stderr(&o));
}

#[test]
fn bad_study_files_exit_2_naming_the_key() {
    let dir_tmp = scratch("bad");
    let dir = dir_tmp.path();
    paper_into(dir);
    let cases: &[(&str, &[&str], &str)] = &[
        ("[grid]\n\"design.nu\" = [1.0]\n", &[], "grid.\"design.nu\": design.nu is not a value of the scenario"),
        (
            "[monte_carlo]\nruns = 2\n\"truth.A\" = { cauchy = 1.0 }\n",
            &[],
            "monte_carlo.\"truth.A\".cauchy: unknown distribution",
        ),
        ("", &["--shard", "3/3"], "--shard: shard index 3 ≥ N = 3"),
        (
            "",
            &["--jobs", "0"],
            "invalid value '0' for '--jobs <N>': expected a number of worker threads from 1 to 1024",
        ),
        (
            "[grid]\n\"design.beta\" = [1.0, 2.0]\n[monte_carlo]\nruns = 6000000\n\"truth.A\" = { relative = 0.05 }\n",
            &[],
            "more than 1e7; check the grid, or pass --yes",
        ),
        // 317 × 316 grid points of one run each: under 1e7 runs, but each point's summary costs
        // kilobytes (a 700 × 700 grid had taken 1 GB and written 1.5 GB without asking).
        (&grid_of(317, 316), &[], "the study has 100172 grid points, more than 1e5, and summary.json summarizes each"),
    ];
    for (k, (text, flags, expected)) in cases.iter().enumerate() {
        let study = write_study(dir, &format!("s{k}.toml"), text);
        let out = dir.join(format!("o{k}")).display().to_string();
        let mut args = vec!["sweep", study.as_str(), "--out", out.as_str()];
        args.extend_from_slice(flags);
        let o = quell(&args);
        assert_eq!(o.status.code(), Some(2), "{text}: {}", stderr(&o));
        assert!(stderr(&o).contains(expected), "{text}\nexpected: {expected}\ngot: {}", stderr(&o));
        assert!(!dir.join(format!("o{k}")).exists(), "nothing is written for a bad study");
    }
}

/// A `[grid]` of `a` values of design.mu[0] by `b` of design.mu[1].
fn grid_of(a: usize, b: usize) -> String {
    let values = |n: usize| (1..=n).map(|k| format!("{k}.0")).collect::<Vec<_>>().join(", ");
    format!("[grid]\n\"design.mu[0]\" = [{}]\n\"design.mu[1]\" = [{}]\n", values(a), values(b))
}

#[test]
fn ctrl_c_writes_the_rows_done_marked_partial() {
    let dir_tmp = scratch("interrupt");
    let dir = dir_tmp.path();
    // 4,000 runs of 100 s: minutes of work, interrupted after a second.
    let study = write_study(
        dir,
        "study.toml",
        "[simulation]\nrtol = 1e-6\natol = 1e-6\n[monte_carlo]\nruns = 4000\n\"plant.x0\" = { normal = 0.1 }\n",
    );
    let out = dir.join("out");
    let child = Command::new(env!("CARGO_BIN_EXE_quell"))
        .args(["sweep", &study, "--no-plots", "--out"])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .expect("start quell");
    std::thread::sleep(Duration::from_millis(1500));
    let status = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(status.success());
    let output = child.wait_with_output().unwrap();
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    assert!(err.contains("interrupted after"), "{err}");
    let csv = fs::read_to_string(out.join("runs.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines.last().unwrap().starts_with("# partial: "), "{}", lines.last().unwrap());
    let header_fields = lines[0].split(',').count();
    assert!(lines.len() > 2 && lines.len() < 4002, "{} lines", lines.len());
    for l in &lines[1..lines.len() - 1] {
        assert_eq!(l.split(',').count(), header_fields, "every row is whole: {l}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["partial"], true);
    assert_eq!(summary["runs_done"].as_u64().unwrap() as usize, lines.len() - 2);
    // A new sweep into it, of this study or another, would replace the rows --resume can finish
    // (it did, silently; helper tryout, 2026-12-06): refused, exit 2, the files left as they were.
    let other = write_study(dir, "other.toml", "[simulation]\nt_end = 1.0\n[grid]\n\"design.mu[0]\" = [10.0]\n");
    for study in [&study, &other] {
        let again = quell(&["sweep", study, "--no-plots", "--out", out.to_str().unwrap()]);
        assert_eq!(again.status.code(), Some(2), "{}", stderr(&again));
        let done = lines.len() - 2;
        let want = format!("holds an unfinished sweep ({done} of its runs done, summary.json's partial): add --resume to finish it with its study file (and its --shard), or remove runs.csv and summary.json to start over, or choose another --out");
        assert!(stderr(&again).contains(&want), "{}", stderr(&again));
        assert_eq!(fs::read_to_string(out.join("runs.csv")).unwrap(), csv);
    }
    // So is a merge of complete shards into it (it had replaced the rows; hostile review).
    let shard = dir.join("shard");
    let o = quell(&["sweep", &other, "--shard", "0/1", "--no-plots", "--out", shard.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let merged = quell(&["sweep", "--merge", shard.to_str().unwrap(), "--no-plots", "--out", out.to_str().unwrap()]);
    assert_eq!(merged.status.code(), Some(2), "{}", stderr(&merged));
    assert!(stderr(&merged).contains("holds an unfinished sweep ("), "{}", stderr(&merged));
    assert!(
        stderr(&merged).contains(": run `quell sweep STUDY --resume` into it to finish it with its study file"),
        "{}",
        stderr(&merged)
    );
    assert_eq!(fs::read_to_string(out.join("runs.csv")).unwrap(), csv);
    // Without a readable summary.json (a kill between the two renames, or a damaged file),
    // runs.csv's last line tells (a garbled summary.json had let the rows be replaced).
    fs::write(out.join("summary.json"), "garbage").unwrap();
    let again = quell(&["sweep", &other, "--no-plots", "--out", out.to_str().unwrap()]);
    assert_eq!(again.status.code(), Some(2), "{}", stderr(&again));
    assert!(
        stderr(&again).contains("holds an unfinished sweep (runs.csv ends with \"# partial: "),
        "{}",
        stderr(&again)
    );
    assert_eq!(fs::read_to_string(out.join("runs.csv")).unwrap(), csv);
}

/// runs.csv's last columns are the values each draw gave, by key and index. A sweep interrupted
/// before runs.csv held them (its summary.json without `drawn`, its rows without the columns) is
/// resumed, not refused as another study's, and its kept rows get their values: the rows then
/// equal an uninterrupted sweep's.
#[test]
fn the_drawn_values_are_columns_and_an_older_sweep_resumes_with_them() {
    let dir_tmp = scratch("drawn");
    let dir = dir_tmp.path();
    let text =
        "[simulation]\nt_end = 2.0\n[monte_carlo]\nruns = 6\nseed = 3\n\"truth.delays[1]\" = { uniform = 0.5 }\n";
    let study = write_study(dir, "study.toml", text);
    let out = |name: &str| dir.join(name).display().to_string();
    let full = quell(&["sweep", &study, "--no-plots", "--out", &out("full")]);
    assert!(full.status.success(), "{}", stderr(&full));
    let csv = fs::read_to_string(dir.join("full/runs.csv")).unwrap();
    assert!(csv.lines().next().unwrap().ends_with(",wall_ms,truth.delays[1]"), "{csv}");
    // The paper's τ₂ = 3 ± 0.5, drawn anew each run.
    let taus: Vec<f64> = csv.lines().skip(1).map(|l| l.rsplit(',').next().unwrap().parse().unwrap()).collect();
    assert!(taus.iter().all(|t| (t - 3.0).abs() <= 0.5) && taus.windows(2).all(|w| w[0] != w[1]), "{taus:?}");
    // The same directory as the previous version would have left it after three runs.
    fs::create_dir(dir.join("old")).unwrap();
    let old_rows: Vec<String> = csv.lines().take(4).map(|l| l.rsplit_once(',').unwrap().0.to_string()).collect();
    fs::write(
        dir.join("old/runs.csv"),
        format!(
            "{}\n# partial: 3 of the shard's runs were carried out before the sweep was interrupted\n",
            old_rows.join("\n")
        ),
    )
    .unwrap();
    let mut summary: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.join("full/summary.json")).unwrap()).unwrap();
    assert!(summary["study"].as_object_mut().unwrap().remove("drawn").is_some());
    summary["partial"] = serde_json::Value::Bool(true);
    fs::write(dir.join("old/summary.json"), summary.to_string()).unwrap();
    let resumed = quell(&["sweep", &study, "--no-plots", "--out", &out("old"), "--resume"]);
    assert!(resumed.status.success(), "{}", stderr(&resumed));
    assert!(stderr(&resumed).contains("resumed: 3 rows kept, 3 runs run"), "{}", stderr(&resumed));
    assert_eq!(rows_without_wall_time(&dir.join("old")), rows_without_wall_time(&dir.join("full")));
    // Shards of the two versions are refused, in either order, naming the older one (merging had
    // depended on their order and filled the older's columns with blanks; diff review).
    for (shard, name) in [("0/2", "s0"), ("1/2", "s1")] {
        let o = quell(&["sweep", &study, "--no-plots", "--shard", shard, "--out", &out(name)]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let csv = fs::read_to_string(dir.join("s1/runs.csv")).unwrap();
    let stripped: Vec<&str> = csv.lines().map(|l| l.rsplit_once(',').unwrap().0).collect();
    fs::write(dir.join("s1/runs.csv"), stripped.join("\n") + "\n").unwrap();
    let mut summary: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.join("s1/summary.json")).unwrap()).unwrap();
    summary["study"].as_object_mut().unwrap().remove("drawn");
    fs::write(dir.join("s1/summary.json"), summary.to_string()).unwrap();
    for pair in [["s0", "s1"], ["s1", "s0"]] {
        let o = quell(&["sweep", "--merge", &out(pair[0]), &out(pair[1]), "--out", &out("m"), "--no-plots"]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        let older = format!("{} was written by a quell before 2026-12-07", out("s1"));
        assert!(stderr(&o).contains(&older), "{}", stderr(&o));
    }
}

/// An interrupted sweep resumed with `--resume` ends with the rows of an uninterrupted one (every
/// run is reproducible from its index), having run only the others; a complete directory has
/// nothing to resume, and another study's rows are refused (exit 2).
#[test]
fn an_interrupted_sweep_resumed_equals_an_uninterrupted_one() {
    let dir_tmp = scratch("resume");
    let dir = dir_tmp.path();
    let text = "[simulation]\nt_end = 20.0\nrtol = 1e-6\natol = 1e-6\n[monte_carlo]\nruns = 3000\nseed = 3\n\"plant.x0\" = { normal = 0.1 }\n";
    let study = write_study(dir, "study.toml", text);
    let out = |name: &str| dir.join(name).display().to_string();
    let full = quell(&["sweep", &study, "--no-plots", "--out", &out("full")]);
    assert!(full.status.success(), "{}", stderr(&full));
    let child = Command::new(env!("CARGO_BIN_EXE_quell"))
        .args(["sweep", &study, "--no-plots", "--out", &out("part")])
        .stderr(Stdio::piped())
        .spawn()
        .expect("start quell");
    std::thread::sleep(Duration::from_millis(700));
    let _ = Command::new("kill").args(["-INT", &child.id().to_string()]).status();
    let part = child.wait_with_output().unwrap();
    // A machine fast enough to finish first leaves nothing to resume: the check below still holds.
    let interrupted = part.status.code() == Some(1);
    let csv = fs::read_to_string(dir.join("part/runs.csv")).unwrap();
    let done = csv.lines().filter(|l| !l.starts_with('#')).count() - 1;
    let resumed = quell(&["sweep", &study, "--no-plots", "--out", &out("part"), "--resume"]);
    let err = stderr(&resumed);
    assert!(resumed.status.success(), "{err}");
    if interrupted {
        assert!(err.contains(&format!("resumed: {done} rows kept, {} runs run", 3000 - done)), "{err}");
    }
    assert_eq!(rows_without_wall_time(&dir.join("part")), rows_without_wall_time(&dir.join("full")));
    let summary: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.join("part/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["partial"], false);
    let again = quell(&["sweep", &study, "--no-plots", "--out", &out("part"), "--resume"]);
    assert!(again.status.success() && stderr(&again).contains("nothing to resume"), "{}", stderr(&again));
    let other = write_study(dir, "other.toml", &text.replace("seed = 3", "seed = 4"));
    let refused = quell(&["sweep", &other, "--no-plots", "--out", &out("part"), "--resume"]);
    assert_eq!(refused.status.code(), Some(2), "{}", stderr(&refused));
    assert!(stderr(&refused).contains("its rows come from another study or shard"), "{}", stderr(&refused));
}

/// An interrupted sweep into the directory of another, complete sweep keeps that sweep's files
/// and leaves its own rows in the journal, which `--resume` finishes and which then replaces them
/// (an interrupted sweep had replaced another study's 3,000 rows with its few hundred; hostile
/// review, 2026-12-06).
#[test]
fn an_interrupted_sweep_keeps_the_complete_one_it_would_replace() {
    let dir_tmp = scratch("keep");
    let dir = dir_tmp.path();
    let out = dir.join("out");
    let other = write_study(dir, "other.toml", "[simulation]\nt_end = 1.0\n[grid]\n\"design.mu[0]\" = [10.0, 20.0]\n");
    let o = quell(&["sweep", &other, "--no-plots", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (csv, summary) = (fs::read(out.join("runs.csv")).unwrap(), fs::read(out.join("summary.json")).unwrap());
    // 3,000 runs on one thread: seconds of work, interrupted at 0.7 s, then again when resumed.
    let text = "[simulation]\nt_end = 20.0\nrtol = 1e-6\natol = 1e-6\n[monte_carlo]\nruns = 3000\nseed = 3\n\"plant.x0\" = { normal = 0.1 }\n";
    let study = write_study(dir, "study.toml", text);
    for resume in [false, true] {
        let mut args = vec!["sweep", &study, "--no-plots", "--jobs", "1", "--out", out.to_str().unwrap()];
        args.extend(resume.then_some("--resume"));
        let child =
            Command::new(env!("CARGO_BIN_EXE_quell")).args(&args).stderr(Stdio::piped()).spawn().expect("start quell");
        std::thread::sleep(Duration::from_millis(700));
        let _ = Command::new("kill").args(["-INT", &child.id().to_string()]).status();
        let part = child.wait_with_output().unwrap();
        let err = stderr(&part);
        assert_eq!(part.status.code(), Some(1), "resume {resume}: {err}");
        assert!(err.contains("runs.csv and summary.json there are the earlier sweep's, kept"), "{err}");
        assert_eq!(fs::read(out.join("runs.csv")).unwrap(), csv);
        assert_eq!(fs::read(out.join("summary.json")).unwrap(), summary);
        assert!(out.join("runs.partial.csv").is_file());
    }
    // A new sweep is told of the journal; --resume finishes it and replaces the files.
    let again = quell(&["sweep", &other, "--no-plots", "--out", out.to_str().unwrap()]);
    assert_eq!(again.status.code(), Some(2), "{}", stderr(&again));
    let resumed = quell(&["sweep", &study, "--no-plots", "--out", out.to_str().unwrap(), "--resume"]);
    assert!(resumed.status.success(), "{}", stderr(&resumed));
    let rows = fs::read_to_string(out.join("runs.csv")).unwrap();
    assert_eq!(rows.lines().count(), 3001, "{}", &rows[..200.min(rows.len())]);
    assert!(!out.join("runs.partial.csv").exists());
}

/// A sweep killed outright (SIGKILL: the out-of-memory killer, a batch system past its grace
/// period) writes neither runs.csv nor summary.json, but its journal holds every run that finished:
/// `--resume` keeps those and ends with the rows of an uninterrupted sweep. A last line cut by the
/// kill is dropped (its run is run again); the journal is removed once runs.csv is written. Before
/// the journal, such a directory was empty and `--resume` refused it.
#[test]
fn a_killed_sweep_resumes_from_its_journal() {
    let dir_tmp = scratch("kill");
    let dir = dir_tmp.path();
    let text = "[simulation]\nt_end = 20.0\nrtol = 1e-6\natol = 1e-6\n[monte_carlo]\nruns = 3000\nseed = 5\n\"plant.x0\" = { normal = 0.1 }\n";
    let study = write_study(dir, "study.toml", text);
    let out = |name: &str| dir.join(name).display().to_string();
    // A new sweep of `study` into `killed` without --resume: refused (exit 2) with `message`.
    let refused_plainly = |study: &str, message: &str| {
        let o = quell(&["sweep", study, "--no-plots", "--out", &out("killed")]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains(message), "{}", stderr(&o));
    };
    let full = quell(&["sweep", &study, "--no-plots", "--out", &out("full")]);
    assert!(full.status.success(), "{}", stderr(&full));
    assert!(!dir.join("full/runs.partial.csv").exists());
    let mut child = Command::new(env!("CARGO_BIN_EXE_quell"))
        .args(["sweep", &study, "--no-plots", "--out", &out("killed")])
        .stderr(Stdio::null())
        .spawn()
        .expect("start quell");
    std::thread::sleep(Duration::from_millis(700));
    child.kill().unwrap();
    let killed = !child.wait().unwrap().success();
    let journal = dir.join("killed/runs.partial.csv");
    if killed {
        assert!(!dir.join("killed/runs.csv").exists() && !dir.join("killed/summary.json").exists());
        let text = fs::read_to_string(&journal).unwrap();
        assert!(text.starts_with("# quell sweep journal: {"), "{}", &text[..80.min(text.len())]);
        // A row cut short by the kill.
        fs::write(&journal, format!("{text}12,0,12,")).unwrap();
        // Merging it is refused, naming the resume (it had said "summary.json: No such file").
        let merged = quell(&["sweep", "--merge", &out("killed"), "--out", &out("merged"), "--no-plots"]);
        assert_eq!(merged.status.code(), Some(2), "{}", stderr(&merged));
        assert!(
            stderr(&merged).contains("holds the journal runs.partial.csv of a sweep that did not finish"),
            "{}",
            stderr(&merged)
        );
        // A new sweep into it without --resume is refused, the journal kept (it had replaced it).
        let before = fs::read(&journal).unwrap();
        refused_plainly(&study, "of a sweep of this study that did not finish; add --resume to finish it");
        assert_eq!(fs::read(&journal).unwrap(), before);
        // Another study's journal: --resume would refuse it too, so the message does not offer it.
        let other =
            write_study(dir, "other.toml", &fs::read_to_string(&study).unwrap().replace("seed = 5", "seed = 6"));
        refused_plainly(&other, "of another study or shard; finish it with that study file");
    }
    let resumed = quell(&["sweep", &study, "--no-plots", "--out", &out("killed"), "--resume"]);
    assert!(resumed.status.success(), "{}", stderr(&resumed));
    assert_eq!(rows_without_wall_time(&dir.join("killed")), rows_without_wall_time(&dir.join("full")));
    assert!(!journal.exists());
    // Killed while writing its files, after the journal had every row (runs.csv or summary.json
    // missing, a temporary file left): the resume writes them from the journal. It had said
    // "nothing to resume" and left the directory without them.
    let late = dir.join("late");
    fs::create_dir(&late).unwrap();
    let summary: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.join("full/summary.json")).unwrap()).unwrap();
    let rows = fs::read_to_string(dir.join("full/runs.csv")).unwrap();
    fs::write(late.join("runs.partial.csv"), format!("# quell sweep journal: {}\n{rows}", summary["study"])).unwrap();
    let resumed = quell(&["sweep", &study, "--no-plots", "--out", &out("late"), "--resume"]);
    assert!(resumed.status.success(), "{}", stderr(&resumed));
    assert!(stderr(&resumed).contains("the journal held every run of the study (3000)"), "{}", stderr(&resumed));
    assert_eq!(rows_without_wall_time(&late), rows_without_wall_time(&dir.join("full")));
    assert!(late.join("summary.json").exists() && !late.join("runs.partial.csv").exists());
    // A journal holding a run twice: the way to start over is named whole (it had said "run the
    // sweep again without --resume", which the journal then refused, sending the user back).
    let twice = dir.join("twice");
    fs::create_dir(&twice).unwrap();
    let first_row = rows.lines().nth(1).unwrap();
    let journal_text = format!(
        "# quell sweep journal: {}\n{}\n{first_row}\n{first_row}\n",
        summary["study"],
        rows.lines().next().unwrap()
    );
    fs::write(twice.join("runs.partial.csv"), journal_text).unwrap();
    let refused = quell(&["sweep", &study, "--no-plots", "--out", &out("twice"), "--resume"]);
    assert_eq!(refused.status.code(), Some(2), "{}", stderr(&refused));
    assert!(
        stderr(&refused).contains("runs.partial.csv's run 0 is not a run of shard 0/1 or is there twice (the file was edited?); to start over, remove runs.partial.csv, runs.csv and summary.json from it and run the sweep without --resume"),
        "{}",
        stderr(&refused)
    );
    // A journal that is not one is named, not taken, with or without --resume.
    fs::write(&journal, "run,point\n").unwrap();
    refused_plainly(&study, "; remove it to start over here, or choose another --out");
    let refused = quell(&["sweep", &study, "--no-plots", "--out", &out("killed"), "--resume"]);
    assert_eq!(refused.status.code(), Some(2), "{}", stderr(&refused));
    assert!(
        stderr(&refused).contains("runs.partial.csv: line 1: expected `# quell sweep journal: `"),
        "{}",
        stderr(&refused)
    );
}

#[test]
fn tune_writes_the_chosen_mu_and_each_curve() {
    let dir_tmp = scratch("tune");
    let dir = dir_tmp.path();
    let text = "[simulation]\nt_end = 40.0\nrtol = 1e-6\natol = 1e-6\n[tune]\nobjective = \"tail_rms_e\"\nmu = [2.0, 200.0]\nmax_u = 22.0\npoints = 5\nrefine = 2\n";
    let study = write_study(dir, "tune.toml", text);
    let out = dir.join("out").display().to_string();
    let o = quell(&["tune", &study, "--out", &out]);
    assert!(o.status.success(), "{}", stderr(&o));
    let printed = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(printed.contains("channel 1: mu = ") && printed.contains("joint run reproduces it"), "{printed}");
    let csv = fs::read_to_string(dir.join("out/tune.csv")).unwrap();
    // Each channel's 5 points and 2 refinements, and channel 2's own μ = 30, off its grid (channel
    // 1's 20 is on it), from the scenario's run.
    assert_eq!(csv.lines().count(), 1 + 2 * (5 + 2) + 1);
    assert_eq!(csv.lines().filter(|l| l.starts_with("2,30,")).count(), 1, "{csv}");
    assert_eq!(csv.lines().filter(|l| l.ends_with(",true")).count(), 2, "one chosen μ per channel");
    let json: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.join("out/tune.json")).unwrap()).unwrap();
    assert_eq!(json["mu"].as_array().unwrap().len(), 2);
    // Channels are numbered from 1 in tune.json as in tune.csv (tune.json counted from 0).
    let numbers: Vec<u64> =
        json["channels"].as_array().unwrap().iter().map(|c| c["channel"].as_u64().unwrap()).collect();
    assert_eq!(numbers, [1, 2]);
    // Each channel's tie: the least objective of its curve, and a bound the chosen one is within.
    for c in json["channels"].as_array().unwrap() {
        let least =
            c["curve"].as_array().unwrap().iter().filter_map(|p| p["objective"].as_f64()).fold(f64::INFINITY, f64::min);
        let (tie, chosen) = (&c["tie"], c["chosen"]["objective"].as_f64().unwrap());
        assert!(tie["least"].as_f64() == Some(least) && chosen <= tie["bound"].as_f64().unwrap(), "{c}");
        let at = c["curve"].as_array().unwrap().iter().find(|p| p["mu"] == tie["mu"]).expect("the least's μ");
        assert_eq!(at["objective"], tie["least"], "{c}");
    }
    assert!(csv.lines().nth(1).unwrap().starts_with("1,") && csv.lines().last().unwrap().starts_with("2,"), "{csv}");
    assert!(dir.join("out/tune.png").is_file() && dir.join("out/tune.svg").is_file());

    // No [tune], and a limit no μ meets: exit code 2, naming the key.
    let o = quell(&["tune", &write_study(dir, "none.toml", ""), "--out", &out]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("tune: missing"), "{}", stderr(&o));
    let o =
        quell(&["tune", &write_study(dir, "tight.toml", &text.replace("max_u = 22.0", "max_u = 1.0")), "--out", &out]);
    assert_eq!(o.status.code(), Some(2));
    // Only the limits the file gives are named (it has no max_uf).
    let err = stderr(&o);
    assert!(
        err.contains("channel 1: none of the 5 μ evaluated in tune.mu[0] completed with max |u_1| ≤ tune.max_u[0] and a finite tail_rms_e (the least max |u_1| of the runs with a finite tail_rms_e is "),
        "{err}"
    );
    assert!(
        err.contains(
            "above tune.max_u[0] = 1); widen the bounds, evaluate more of them (tune.points), raise the limits"
        ),
        "{err}"
    );
    assert!(!err.contains("max_uf"), "{err}");
    // The least peak named, taken as the limit (1.001× for its four digits), admits a μ.
    let least: f64 =
        err.split("a finite tail_rms_e is ").nth(1).and_then(|r| r.split(' ').next()).unwrap().parse().unwrap();
    assert!(least > 1.0 && least < 22.0, "{err}");
    let admitted = text.replace("max_u = 22.0", &format!("max_u = {}", 1.001 * least));
    let a = quell(&[
        "tune",
        &write_study(dir, "admitted.toml", &admitted),
        "--out",
        &format!("{out}-admitted"),
        "--no-plots",
    ]);
    assert_eq!(a.status.code(), Some(0), "{}", stderr(&a));
    // No run completing (a step budget of 20): the reason, not limits the file never set; tune.csv
    // has it per evaluation, as runs.csv does.
    let budget = write_study(dir, "budget.toml", &format!("max_steps = 20\n{}", text.replace("max_u = 22.0\n", "")));
    let b = quell(&["tune", &budget, "--out", &format!("{out}-budget"), "--no-plots"]);
    let err = stderr(&b);
    assert_eq!(b.status.code(), Some(2), "{err}");
    assert!(err.contains("no μ in tune.mu[0] completed: none of the 5 runs did (at μ = 2: failed, the solver needed more than 20 steps"), "{err}");
    assert!(err.contains("raise the study's max_steps") && !err.contains("max_u"), "{err}");
    let rows = fs::read_to_string(format!("{out}-budget/tune.csv")).unwrap();
    assert!(rows.starts_with("channel,mu,objective,outcome,reason,"), "{rows}");
    // Each channel's 5 points, and channel 2's own μ = 30 (off its grid), from the scenario's run.
    assert_eq!(rows.matches(",failed,\"the solver needed more than 20 steps").count(), 11, "{rows}");
    // stdout does not present the scenario's μ, kept where nothing was feasible, as tuned.
    let printed = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(!printed.contains("tuned mu"), "{printed}");
    let last = printed.lines().last().unwrap_or_default();
    assert!(
        last.starts_with("mu = [20.000000, ") && last.ends_with("the scenario's mu, unchanged; no feasible mu)"),
        "{printed}"
    );
}

#[test]
fn ctrl_c_or_sigterm_during_tune_writes_the_points_evaluated_marked_partial() {
    for signal in ["-INT", "-TERM"] {
        let dir_tmp = scratch("tune-interrupt");
        let dir = dir_tmp.path();
        // 2 × 2000 evaluations of the paper's 100 s: minutes of work, interrupted after 1.5 s.
        let text = "[simulation]\nrtol = 1e-6\natol = 1e-6\n[tune]\nobjective = \"tail_rms_e\"\nmu = [2.0, 200.0]\npoints = 2000\n";
        let study = write_study(dir, "tune.toml", text);
        let out = dir.join("out");
        let child = Command::new(env!("CARGO_BIN_EXE_quell"))
            .args(["tune", &study, "--out"])
            .arg(&out)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start quell");
        std::thread::sleep(Duration::from_millis(1500));
        assert!(Command::new("kill").args([signal, &child.id().to_string()]).status().unwrap().success());
        let sent = std::time::Instant::now();
        let output = child.wait_with_output().unwrap();
        // Runs under way are abandoned at their next recorded sample (milliseconds); the bound
        // leaves room for the plots and a machine at load 12.
        assert!(sent.elapsed() < Duration::from_secs(30), "{signal}: quit {:?} after the signal", sent.elapsed());
        let err = stderr(&output);
        assert_eq!(output.status.code(), Some(1), "{signal}: {err}");
        assert!(err.contains("interrupted after") && err.contains("(marked partial)"), "{err}");
        let csv = fs::read_to_string(out.join("tune.csv")).unwrap();
        let lines: Vec<&str> = csv.lines().collect();
        let last = lines.last().unwrap();
        assert!(last.starts_with("# partial: "), "{last}");
        let rows = &lines[1..lines.len() - 1];
        assert!(rows.len() < 4000, "{} rows", rows.len());
        assert!(last.starts_with(&format!("# partial: {} evaluations", rows.len())), "{last}");
        let fields = lines[0].split(',').count();
        assert!(rows.iter().all(|l| l.split(',').count() == fields), "every row is whole");
        let json: serde_json::Value =
            serde_json::from_str(&fs::read_to_string(out.join("tune.json")).unwrap()).unwrap();
        assert_eq!(json["partial"], true);
        assert!(json["joint"].is_null());
        let evaluated: usize =
            json["channels"].as_array().unwrap().iter().map(|c| c["curve"].as_array().unwrap().len()).sum();
        assert_eq!(evaluated, rows.len());
        assert!(out.join("tune.svg").is_file());
        let leftovers: Vec<_> = fs::read_dir(&out)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
            .collect();
        assert!(leftovers.is_empty(), "temporaries left: {leftovers:?}");
    }
}

/// Sweeps `study` (on the paper's example) into `out` of a new directory; that directory and
/// sweep.svg's text.
fn sweep_figure(tag: &str, study: &str) -> (tempfile::TempDir, String) {
    let dir = scratch(tag);
    let study = write_study(dir.path(), "study.toml", study);
    let out = dir.path().join("out");
    let o = quell(&["sweep", &study, "--out", &out.display().to_string()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let svg = fs::read_to_string(out.join("sweep.svg")).unwrap();
    (dir, svg)
}

/// A settling-time panel where some draws never settled says how many at most and draws their
/// bands to the top of the axis (the upper quantiles are "never"): the bands had vanished and left
/// a median that looked certain where a quarter of a column's draws never settled (helper tryout,
/// 2026-12-06). The paper's loop over 90 s, where it settles near the horizon; the note's share is
/// summary.json's largest `never_settled`, and only the settling-time panels carry it.
#[test]
fn a_settling_time_panel_counts_the_draws_that_never_settled() {
    let study = "[simulation]\nt_end = 90.0\nrtol = 1e-6\natol = 1e-6\n[grid]\n\"design.mu[0]\" = [20.0, 40.0]\n[monte_carlo]\nruns = 4\nseed = 5\n\"truth.A\" = { relative = 0.02 }\n";
    let (dir, svg) = sweep_figure("never-settled", study);
    let summary: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.path().join("out/summary.json")).unwrap()).unwrap();
    let points = summary["points"].as_array().unwrap();
    let never =
        |i: usize| points.iter().map(|p| p["channels"][i]["never_settled"].as_f64().unwrap()).fold(0.0, f64::max);
    let shares: Vec<f64> = (0..2).map(never).filter(|&f| f > 0.0).collect();
    assert!(!shares.is_empty(), "the study should have draws that never settled: {summary}");
    assert_eq!(svg.matches("never settled:").count(), shares.len(), "one note per settling-time panel with some");
    for f in shares {
        let note = format!("up to {:.1} % of a point&apos;s completed draws never settled:", 100.0 * f);
        assert!(svg.contains(&note), "{note}");
    }
}

/// A heat map's cell whose runs did not all complete counts them under its median (a cell where 1
/// run of 6 completed had been drawn as the map's best, with nothing to tell it from a full one;
/// helper tryout, 2026-12-06): the paper's loop with τ₂ of the true plant at 3.0 s (the design's:
/// every draw completes) and 3.3 s (some do not). Full cells are not counted.
#[test]
fn a_heat_map_cell_counts_its_completed_runs() {
    let study = "[simulation]\nt_end = 40.0\nrtol = 1e-6\natol = 1e-6\n[grid]\n\"design.mu[0]\" = [20.0, 40.0]\n\"truth.delays[1]\" = [3.0, 3.3]\n[monte_carlo]\nruns = 4\nseed = 2\n\"truth.A\" = { relative = 0.05 }\n";
    let (dir, svg) = sweep_figure("heat-count", study);
    let summary: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.path().join("out/summary.json")).unwrap()).unwrap();
    let points = summary["points"].as_array().unwrap();
    let label = |p: &serde_json::Value| format!("{}/{}", p["completed"], p["runs"]);
    // The SVG writes each text on a line of its own.
    let shown = |text: &str| svg.lines().any(|l| l.trim() == text);
    let (short, full): (Vec<_>, Vec<_>) = points.iter().partition(|p| p["completed"] != p["runs"]);
    assert!(!short.is_empty() && !full.is_empty(), "{points:?}");
    for p in &short {
        assert!(shown(&label(p)), "{} not in the map", label(p));
    }
    for p in &full {
        assert!(!shown(&label(p)), "a full cell is not counted: {}", label(p));
    }
    assert!(svg.contains("(k/n: completed of a cell&apos;s runs)"));
}

/// A study of draws without a grid (Monte Carlo) plots each figure's distribution over the draws,
/// ending at the share of draws that have a value.
#[test]
fn a_study_without_a_grid_plots_the_distribution_over_its_draws() {
    let study = "[simulation]\nt_end = 20.0\nrtol = 1e-6\natol = 1e-6\n[monte_carlo]\nruns = 6\nseed = 3\n\"truth.A\" = { relative = 0.02 }\n";
    let (dir, svg) = sweep_figure("draws", study);
    assert_eq!(svg.matches("fraction of draws ≤ value").count(), 4 * 2, "four figures, two channels");
    assert!(
        svg.contains("max |u_f| (plant input, as asked)") && svg.contains("of 6 draws have a value"),
        "the panels' labels"
    );
    assert!(dir.path().join("out/sweep.png").is_file());
}

/// A figure whose values span two decades along the grid is drawn on a log axis (the paper's
/// channel 1: tail RMS e 2.6 at μ_1 = 1, 7e-7 at 100).
#[test]
fn values_spanning_decades_are_drawn_on_a_log_axis() {
    let study = "[simulation]\nrtol = 1e-6\natol = 1e-6\n[grid]\n\"design.mu[0]\" = [1.0, 100.0]\n";
    let (_dir, svg) = sweep_figure("log-axis", study);
    assert_eq!(svg.matches("tail RMS e (log scale)").count(), 1, "channel 1's panel only");
}

/// A 1-D sweep where some runs did not complete adds a row of panels: the share of each grid
/// value's runs that diverged and that failed (the delay margin of the paper's loop: τ₂ = 4.5 s
/// against the designed 3 diverges), which the figures' empty panels had only hinted at; where all
/// completed, the figure keeps its four rows. sweep.png is 300 px a row.
#[test]
fn a_sweep_where_runs_diverge_plots_their_share_per_grid_value() {
    let png_height = |dir: &tempfile::TempDir| {
        let bytes = fs::read(dir.path().join("out/sweep.png")).unwrap();
        u32::from_be_bytes(bytes[20..24].try_into().unwrap())
    };
    let study = |delays: &str| {
        format!("[simulation]\nt_end = 40.0\nrtol = 1e-6\natol = 1e-6\n[grid]\n\"truth.delays[1]\" = {delays}\n")
    };
    let (dir, svg) = sweep_figure("outcomes", &study("[3.0, 4.5]"));
    assert!(svg.contains("Runs that did not complete, per grid value") && svg.contains("diverged"), "the panel");
    assert_eq!(png_height(&dir), 5 * 300);
    let (dir, svg) = sweep_figure("all-completed", &study("[2.9, 3.0]"));
    assert!(!svg.contains("Runs that did not complete"));
    assert_eq!(png_height(&dir), 4 * 300);
}

/// The settling-time panels of sweep.png/.svg are labelled in the scenario's unit of time
/// (`[plant] time_unit`), also after a merge of shards (the unit travels in their summaries).
#[test]
fn the_settling_time_axis_is_in_the_plants_unit_of_time() {
    let dir_tmp = scratch("time-unit");
    let dir = dir_tmp.path();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/wood-berry.toml");
    fs::copy(data, dir.join("wood-berry.toml")).unwrap();
    let study = "scenario = \"wood-berry.toml\"\n[simulation]\nt_end = 60.0\n[grid]\n\"design.mu[0]\" = [10.0, 30.0]\n";
    let study = write_study(dir, "study.toml", study);
    let out = |name: &str| dir.join(name).display().to_string();
    for shard in ["0/2", "1/2"] {
        let o = quell(&["sweep", &study, "--out", &out(&format!("part{}", &shard[..1])), "--shard", shard]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let o = quell(&["sweep", "--merge", &out("part0"), &out("part1"), "--out", &out("merged")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let svg = fs::read_to_string(dir.join("merged/sweep.svg")).unwrap();
    assert!(svg.contains("settling time, min") && !svg.contains("settling time, s"), "the panels' titles");
    // Each channel has a panel of the plant input's peak (5), what the actuator must deliver.
    assert_eq!(svg.matches("max |u_f| (plant input, as asked)").count(), 2 * 2, "title and y label, two channels");
}

/// The sweep's figures title each channel with its output's name, as `quell run`'s do ("Channel 1
/// (pitch)"; they said "Channel 1"), from `[plant] outputs`, which summary.json now carries; the
/// plant input's panels with the input's ("Input 1 (Vp)"; they said "Channel 1 (pitch)").
#[test]
fn sweep_figures_name_the_outputs() {
    let tmp = scratch("names");
    let dir = tmp.path();
    let heli = Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/quanser-heli.toml");
    fs::copy(heli, dir.join("heli.toml")).unwrap();
    for (name, grid) in [
        ("one.toml", "\"design.beta\" = [1.0, 2.0]\n"),
        ("two.toml", "\"design.beta\" = [1.0, 2.0]\n\"design.mu[0]\" = [1.0, 2.0]\n"),
    ] {
        let study = write_study(
            dir,
            name,
            &format!("scenario = \"heli.toml\"\n[simulation]\nt_end = 2.0\nrtol = 1e-6\natol = 1e-6\n[grid]\n{grid}"),
        );
        let out = dir.join(format!("out-{name}"));
        let o = quell(&["sweep", &study, "--out", out.to_str().unwrap()]);
        assert!(o.status.success(), "{}", stderr(&o));
        let svg = fs::read_to_string(out.join("sweep.svg")).unwrap();
        assert!(
            svg.contains("Channel 1 (pitch)") && svg.contains("Channel 2 (yaw)"),
            "{name}: no output names in sweep.svg"
        );
        let summary: serde_json::Value =
            serde_json::from_str(&fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
        assert_eq!(summary["study"]["outputs"], serde_json::json!(["pitch", "yaw"]));
        // The plant input's panels are the inputs', which the heli names apart from its outputs.
        assert_eq!(summary["study"]["inputs"], serde_json::json!(["Vp", "Vy"]));
        // (The 2-D grid's figure maps the tail error alone.)
        let one_d = name == "one.toml";
        assert_eq!(svg.contains("Input 1 (Vp): max |u_f|"), one_d, "{name}");
        assert!(!svg.contains("Channel 1 (pitch): max |u_f|"), "{name}");
    }
}

#[test]
fn a_shard_without_runs_says_so_and_still_merges() {
    // Eight runs in twelve shards: shard 10/12 has none. It was written empty without a word.
    let dir = scratch("empty-shard");
    paper_into(dir.path());
    let study = write_study(dir.path(), "study.toml", STUDY);
    let mut dirs = Vec::new();
    for i in 0..12 {
        let out = dir.path().join(format!("s{i}")).display().to_string();
        let o = quell(&["sweep", &study, "--shard", &format!("{i}/12"), "--out", &out, "--no-plots"]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let warned = stderr(&o).contains(&format!(
            "⚠ warning: shard {i}/12 has no runs: the study has 8, fewer than the shards; its files are written empty, as --merge needs every shard"
        ));
        assert_eq!(warned, i >= 8, "shard {i}: {}", stderr(&o));
        dirs.push(out);
    }
    let merged = dir.path().join("merged").display().to_string();
    let mut args = vec!["sweep", "--merge"];
    args.extend(dirs.iter().map(String::as_str));
    args.extend(["--out", &merged, "--no-plots"]);
    let o = quell(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(rows_without_wall_time(Path::new(&merged)).len(), 1 + 8);
}

/// A study forced onto DOP853 is cautioned where a run's adaptive law is stiff, as `quell run
/// --method explicit` is: here μ × 5 puts channel 2 at 4.7ρ (the paper's μ at
/// 0.95ρ). The same study on the default method, or at the paper's μ alone, is not.
#[test]
fn a_study_forced_onto_dop853_with_a_stiff_point_is_cautioned() {
    let dir_tmp = scratch("explicit-stiff");
    let dir = dir_tmp.path();
    paper_into(dir);
    let study = |method: &str, mus: &str| {
        let text =
            format!("scenario = \"paper.toml\"\n[simulation]\nt_end = 0.5\n{method}\n[grid]\n\"design.mu\" = {mus}\n");
        let path = write_study(dir, "study.toml", &text);
        let out = tempfile::tempdir_in(dir).unwrap();
        let o = quell(&["sweep", &path, "--out", &out.path().display().to_string(), "--no-plots"]);
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o)
    };
    let cautioned = study("method = \"explicit\"", "[[20.0, 30.0], [100.0, 150.0]]");
    assert!(
        cautioned.contains("⚠ warning: 1 of the 2 runs carried out ran on DOP853 at a stiff adaptive law, all completed: DOP853 keeps its steps within that law's rate; the first, run 1, design.mu = [100.0, 150.0]: simulation.method = \"explicit\" on a stiff adaptive law"),
        "{cautioned}"
    );
    for (method, mus) in [("", "[[20.0, 30.0], [100.0, 150.0]]"), ("method = \"explicit\"", "[[20.0, 30.0]]")] {
        let quiet = study(method, mus);
        assert!(!quiet.contains("stiff adaptive law"), "{method} {mus}: {quiet}");
    }
}

/// A grid point whose β puts a rate far beyond the loop's is cautioned before the sweep's runs
/// (over 0.5 s, before the first delay, the run itself stays cheap: the caution is the point).
#[test]
fn a_sweep_over_a_rate_far_faster_than_the_loop_is_cautioned_before_its_runs() {
    let dir_tmp = scratch("fast-rate");
    let dir = dir_tmp.path();
    paper_into(dir);
    let path = write_study(
        dir,
        "study.toml",
        "scenario = \"paper.toml\"\n[simulation]\nt_end = 0.5\n[grid]\n\"design.beta\" = [0.01, 1e-7]\n",
    );
    let out = dir.join("out").display().to_string();
    let o = quell(&["sweep", &path, "--out", &out, "--no-plots"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("⚠ warning: 1 of the 2 grid points: the first, design.beta = 1e-7: 1/design.beta sets the loop's fastest rate, 1.000e7/s"),
        "{}",
        stderr(&o)
    );
}

/// A tuning forced onto DOP853 whose searches run a μ that makes the adaptive law stiff is
/// cautioned before them (channel 1's search reaches μ = [2000, 30]: 37ρ); up to the paper's μ it
/// is not, and a search whose other channel is stiff at the scenario's μ is (μ₂ = 1000 while μ₁ is
/// searched over [2, 20]).
#[test]
fn a_tuning_on_dop853_reaching_a_stiff_mu_is_cautioned() {
    let dir_tmp = scratch("tune-explicit");
    let dir = dir_tmp.path();
    let text = "[simulation]\nt_end = 0.5\nmethod = \"explicit\"\n[tune]\nobjective = \"tail_rms_e\"\nmu = [2.0, 2000.0]\npoints = 2\nrefine = 0\n";
    let tune = |text: &str| {
        let study = write_study(dir, "tune.toml", text);
        let o = quell(&["tune", &study, "--out", &dir.join("out").display().to_string(), "--no-plots"]);
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o)
    };
    let err = tune(text);
    assert!(
        err.contains("⚠ warning: channel 1's search runs μ = [2000, 30]: simulation.method = \"explicit\" on a stiff adaptive law"),
        "{err}"
    );
    // Channel 2's search reaches μ = [20, 2000] as well: a caution each.
    assert!(err.contains("⚠ warning: channel 2's search runs μ = [20, 2000]: "), "{err}");
    assert!(!tune(&text.replace("2000.0", "20.0")).contains("stiff adaptive law"));
    let scenario = fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper.toml")).unwrap();
    fs::write(dir.join("stiff.toml"), scenario.replace("mu = [20.0, 30.0]", "mu = [20.0, 1000.0]")).unwrap();
    let other = format!(
        "scenario = \"stiff.toml\"\n{}",
        text.replace("mu = [2.0, 2000.0]", "mu = [[2.0, 20.0], [1000.0, 1000.0]]")
    );
    assert!(tune(&other).contains("⚠ warning: channel 1's search runs μ = [20, 1000]: "));
}

/// A linear grid has a tick at each of its values, ends included: from 2.7 to 3.3 in steps of 0.1
/// the last point had no label (3.3 / 0.1 rounds below 33, and six ticks were asked for seven
/// values).
#[test]
fn a_linear_grid_is_labelled_at_every_value() {
    let study = "[simulation]\nt_end = 2.0\nrtol = 1e-6\natol = 1e-6\n[grid]\n\"truth.delays[1]\" = [2.7, 2.8, 2.9, 3.0, 3.1, 3.2, 3.3]\n";
    let (_dir, svg) = sweep_figure("linear-ticks", study);
    // plotters writes a label's text on a line of its own.
    let labels: Vec<&str> = svg.lines().map(str::trim).collect();
    for v in ["2.7", "2.8", "2.9", "3.1", "3.2", "3.3"] {
        assert_eq!(labels.iter().filter(|l| **l == v).count(), 8, "the tick label {v} in each of the 8 panels");
    }
}

/// `quell` with `args`, killed after 60 s (a read of a pipe had blocked for ever): its output, or
/// a panic saying it hung.
fn quell_within(args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_quell"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the quell binary runs");
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("quell {args:?} did not finish in 60 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// A sweep's files edited or replaced (helper review, 2026-12-06) are refused with exit 2 naming
/// what is wrong: an m of 1e15 in summary.json (it had aborted asking for 24 PB), a row whose point
/// or grid value is not its run index's (merged as they stood), and a runs.csv or journal that is a
/// pipe or /dev/zero (they had hung or taken 9 GB).
#[cfg(unix)]
#[test]
fn edited_or_replaced_sweep_files_are_refused_not_read() {
    let dir_tmp = scratch("edited");
    let dir = dir_tmp.path();
    paper_into(dir);
    let study = write_study(dir, "study.toml", STUDY);
    let out = |name: &str| dir.join(name).display().to_string();
    let o = quell(&["sweep", &study, "--out", &out("all"), "--no-plots"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let copy = |name: &str| {
        fs::create_dir(dir.join(name)).unwrap();
        for f in ["runs.csv", "summary.json"] {
            fs::copy(dir.join("all").join(f), dir.join(name).join(f)).unwrap();
        }
        dir.join(name)
    };
    let refused = |what: &str, o: Output, fragment: &str| {
        assert_eq!(o.status.code(), Some(2), "{what}: {}", stderr(&o));
        assert!(stderr(&o).contains(fragment), "{what}: {}", stderr(&o));
    };
    let m = copy("m");
    let summary =
        fs::read_to_string(m.join("summary.json")).unwrap().replacen("\"m\": 2", "\"m\": 1000000000000000", 1);
    fs::write(m.join("summary.json"), summary).unwrap();
    refused(
        "m",
        quell_within(&["sweep", "--merge", &out("m"), "--out", &out("x")]),
        "line 1: expected the header of a study of 2 grid keys, m = 1000000000000000 channels and 3 drawn values, found 23 fields; was the file edited",
    );
    // Row 2 (run 1: point 0, draw 1) given point 3; row 3 (run 2: point 1) given μ_1 = 99.
    let runs = fs::read_to_string(dir.join("all/runs.csv")).unwrap();
    let edit = |row: usize, field: usize, value: &str| {
        let mut lines: Vec<String> = runs.lines().map(str::to_string).collect();
        let mut fields: Vec<&str> = lines[row].split(',').collect();
        fields[field] = value;
        lines[row] = fields.join(",");
        lines.join("\n") + "\n"
    };
    fs::write(copy("point").join("runs.csv"), edit(2, 1, "3")).unwrap();
    refused(
        "point",
        quell_within(&["sweep", "--merge", &out("point"), "--out", &out("x")]),
        "line 3: point: expected 0 for run 1 (2 draws a grid point), found 3; was the file edited?",
    );
    fs::write(copy("grid").join("runs.csv"), edit(3, 4, "99.0")).unwrap();
    refused(
        "grid value",
        quell_within(&["sweep", "--merge", &out("grid"), "--out", &out("x")]),
        "line 4: design.mu[0]: expected `10.0` for run 2 (2 draws a grid point), found `99.0`",
    );
    let fifo = copy("fifo");
    fs::remove_file(fifo.join("runs.csv")).unwrap();
    assert!(Command::new("mkfifo").arg(fifo.join("runs.csv")).status().unwrap().success());
    refused(
        "pipe",
        quell_within(&["sweep", "--merge", &out("fifo"), "--out", &out("x")]),
        "runs.csv: is a device, FIFO or socket, not a regular file",
    );
    let zero = copy("zero");
    fs::remove_file(zero.join("summary.json")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", zero.join("summary.json")).unwrap();
    refused(
        "device",
        quell_within(&["sweep", "--merge", &out("zero"), "--out", &out("x")]),
        "summary.json: is a device, FIFO or socket, not a regular file",
    );
    // A journal that is a pipe, met by a new sweep into its directory and by --resume.
    fs::create_dir(dir.join("journal")).unwrap();
    assert!(Command::new("mkfifo").arg(dir.join("journal/runs.partial.csv")).status().unwrap().success());
    let journal = out("journal");
    for resume in [false, true] {
        let mut args = vec!["sweep", &study, "--out", &journal, "--no-plots"];
        args.extend(resume.then_some("--resume"));
        refused("journal", quell_within(&args), "is a device, FIFO or socket, not a regular file");
    }
}
