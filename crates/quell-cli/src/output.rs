//! Writing results: every file goes to a temporary name in the output directory and is renamed
//! into place, so a reader never sees a half-written file.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use quell::sim::SimResult;

use crate::{decimal, Failure};

pub use quell::files::write_atomic_all;
use quell::files::Staged;

/// A failed write as exit 2 when the target is not a regular file (the user named the wrong path:
/// [`write_atomic`] leaves devices, FIFOs and links alone), otherwise exit 1.
pub fn write_failure(message: String, e: &io::Error) -> Failure {
    if e.kind() == io::ErrorKind::InvalidInput {
        Failure::Input(message)
    } else {
        Failure::Run(message)
    }
}

/// The directory of the [`all_or_nothing`] under way and the files written into it, staged until
/// its work has succeeded. Files outside it are written at once: the unit tests of this binary run
/// on threads of one process, and a test writing its own directory had its file staged into
/// another test's batch, then missing.
static BATCH: std::sync::Mutex<Option<(PathBuf, Vec<Staged>)>> = std::sync::Mutex::new(None);

/// One [`all_or_nothing`] at a time (the command makes one; tests on several threads more).
static ONE_BATCH: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn batch() -> std::sync::MutexGuard<'static, Option<(PathBuf, Vec<Staged>)>> {
    BATCH.lock().unwrap_or_else(|e| e.into_inner())
}

/// Writes a file atomically ([`quell::files::write_atomic`]); within [`all_or_nothing`] it is
/// staged, and renamed into place only once the whole work has succeeded.
pub fn write_atomic(path: &Path, contents: impl FnOnce(&mut dyn io::Write) -> io::Result<()>) -> io::Result<()> {
    let staged = Staged::write(path, contents)?;
    match batch().as_mut() {
        Some((dir, files)) if path.starts_with(&*dir) => {
            files.push(staged);
            Ok(())
        }
        _ => staged.persist(),
    }
}

/// Runs `work`, which writes files into `dir` ([`write_atomic`]), so that its files replace the old
/// ones together or not at all: each is staged under its temporary name, and only when `work` has
/// succeeded are they all renamed into place and the figures of `dir` that `stale` claims and
/// `work` did not write removed. A failed write (a full disk) leaves the earlier outputs as they
/// were: a run whose figures failed for lack of space had replaced signals.csv, summary.json and
/// design.json and removed the figures. The file `last` marks a complete set: the old one is
/// removed before the renames and the new one renamed after the others, so a process killed among
/// them (an out-of-memory kill) leaves a directory without it, not an old summary.json beside a new
/// signals.csv.
pub fn all_or_nothing(
    dir: &Path,
    last: &str,
    stale: impl Fn(&str) -> bool,
    work: impl FnOnce() -> io::Result<()>,
) -> io::Result<()> {
    let _one = ONE_BATCH.lock().unwrap_or_else(|e| e.into_inner());
    *batch() = Some((dir.to_path_buf(), Vec::new()));
    let done = work();
    let mut staged = batch().take().map(|(_, files)| files).unwrap_or_default();
    done?;
    let written: Vec<PathBuf> = staged.iter().map(|s| s.path().to_path_buf()).collect();
    let mark = dir.join(last);
    staged.sort_by_key(|s| s.path() == mark);
    match fs::remove_file(&mark) {
        Err(e) if e.kind() != io::ErrorKind::NotFound => return Err(e),
        _ => {}
    }
    staged.into_iter().try_for_each(Staged::persist)?;
    remove_figures(dir, stale, &written)
}

/// Removes the figures (`<stem>.png`, `<stem>.svg`) in `dir` whose stem `ours` claims, but for those
/// in `keep`: an earlier command's figures must not stand beside new data.
pub fn remove_figures(dir: &Path, ours: impl Fn(&str) -> bool, keep: &[PathBuf]) -> io::Result<()> {
    for entry in fs::read_dir(dir)? {
        let path = entry?.path();
        let figure = matches!(path.extension().and_then(|e| e.to_str()), Some("png" | "svg"));
        if figure && path.file_stem().and_then(|s| s.to_str()).is_some_and(&ours) && !keep.contains(&path) {
            match fs::remove_file(&path) {
                Err(e) if e.kind() != io::ErrorKind::NotFound => return Err(e),
                _ => {}
            }
        }
    }
    Ok(())
}

/// Proves `dir` writable by creating and removing a uniquely named probe file in it.
fn probe(dir: &Path) -> io::Result<()> {
    tempfile::Builder::new().prefix(".quell-write-test.").suffix(".tmp").tempfile_in(dir)?.close()
}

/// The output directories this process has locked ([`quell::files::lock_dir`]), held until it
/// exits.
static LOCKED: std::sync::Mutex<Vec<quell::files::DirLock>> = std::sync::Mutex::new(Vec::new());

/// The file that marks the output directory of each command that owns one (`quell export` writes
/// into any directory: its two files are named by their prefix).
const MARKS: [(&str, &str); 4] = [
    ("signals.csv", "quell run"),
    ("runs.csv", "quell sweep"),
    (crate::journal::JOURNAL, "quell sweep"),
    ("tune.json", "quell tune"),
];

/// Creates `--out` and proves it writable ([`probe`]), and that none of the `files` to be written
/// there is anything but a regular file or nothing (a directory, a symbolic link, a FIFO, a device:
/// [`quell::files::check_target`]), before any work is done: every output-path problem is bad input
/// (exit 2) naming the path. Then locks it for the rest of the command: a second command writing
/// the same directory meanwhile is refused (exit 2) rather than mixing its files with these, as is
/// a directory that holds another command's output ([`MARKS`]).
pub fn prepare_out(dir: &Path, files: &[&str]) -> Result<(), Failure> {
    let bad = |e: String| Failure::Input(format!("--out {}: {e}; choose another output directory", dir.display()));
    quell::files::check_dir(dir).map_err(|e| bad(e.to_string()))?;
    fs::create_dir_all(dir).and_then(|()| probe(dir)).map_err(|e| bad(format!("cannot write there ({e})")))?;
    if let Some(e) = files.iter().map(|f| quell::files::check_target(&dir.join(f))).find_map(Result::err) {
        return Err(bad(e.to_string()));
    }
    // Run, sweep and tune each own their directory: a sweep's summary.json had replaced a run's
    // beside its signals.csv and figures.
    let owner = |file: &str| MARKS.iter().find(|(mark, _)| *mark == file).map(|(_, command)| *command);
    if let Some(ours) = files.iter().find_map(|f| owner(f)) {
        if let Some((mark, command)) = MARKS.iter().find(|(mark, command)| *command != ours && dir.join(mark).exists())
        {
            return Err(bad(format!(
                "it holds the output of `{command}` ({mark}), which this command's files would mix with"
            )));
        }
    }
    let lock = quell::files::lock_dir(dir).map_err(|_| busy(dir))?;
    LOCKED.lock().unwrap_or_else(|e| e.into_inner()).extend(lock);
    // No other quell writes here now: what temporary files a killed one left can go.
    quell::files::remove_stale_temporaries(dir);
    Ok(())
}

/// Whether `a` and `b` name one existing file (their canonical paths: links and `..` resolved).
pub fn same_file(a: &Path, b: &Path) -> bool {
    a.canonicalize().is_ok_and(|a| b.canonicalize().is_ok_and(|b| a == b))
}

/// Refuses to write `files` into `dir` where one of them is the `input` file the command reads
/// (its canonical path): the output would replace it (`quell run selfd/signals.csv --out selfd`
/// had replaced the scenario with its own signals; hostile review, 2026-12-06).
pub fn not_the_input(input: &Path, dir: &Path, files: &[&str]) -> Result<(), Failure> {
    match files.iter().find(|f| same_file(input, &dir.join(f))) {
        Some(f) => Err(Failure::Input(format!(
            "--out {}: its {f} would replace the input file {} this command reads; choose another output directory, or move the input",
            dir.display(),
            input.display()
        ))),
        None => Ok(()),
    }
}

/// [`not_the_input`] for a study's command: neither the study file nor the scenario file it
/// names may be replaced (a study whose scenario was `summary.json`, swept with `--out` its own
/// directory, had its scenario replaced by the sweep's summary; hostile review, 2026-12-07).
pub fn not_the_study_inputs(study: &Path, scenario: Option<&Path>, dir: &Path, files: &[&str]) -> Result<(), Failure> {
    not_the_input(study, dir, files)?;
    scenario.map_or(Ok(()), |scenario| not_the_input(scenario, dir, files))
}

/// The refusal of `--out dir` while another quell command writes there.
fn busy(dir: &Path) -> Failure {
    Failure::Input(format!(
        "--out {}: another quell command is writing there now; wait for it to finish or choose another output directory",
        dir.display()
    ))
}

/// Refuses `dir` while another quell command holds its lock, before what it holds is judged (a
/// running sweep's journal had been called one to `--resume`).
pub fn check_not_busy(dir: &Path) -> Result<(), Failure> {
    quell::files::lock_dir(dir).map(drop).map_err(|_| busy(dir))
}

/// Proves the output file given by `flag` writable before any work is done, as [`prepare_out`]
/// does for a directory: `path` is not a directory and its directory exists and is writable
/// ([`probe`]; it is not created). Each problem is bad input (exit 2) naming the flag and the path.
pub fn prepare_file(flag: &str, path: &Path) -> Result<(), Failure> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let why = if let Err(e) = quell::files::check_target(path) {
        e.to_string()
    } else if let Err(e) = probe(dir) {
        format!("cannot write in {} ({e})", dir.display())
    } else {
        return Ok(());
    };
    Err(Failure::Input(format!("{flag} {}: {why}; choose a file in an existing, writable directory", path.display())))
}

/// `signals.csv`: t, y1..ym, g1..gm, e1..em, u1..um, eta1_1..etam_q.
pub fn write_signals(path: &Path, r: &SimResult) -> io::Result<()> {
    write_atomic(path, |w| {
        let (m, q, n) = (r.m, r.q, r.n);
        let mut header = vec!["t".to_string()];
        for name in ["y", "g", "e", "u", "uf"] {
            header.extend((1..=m).map(|i| format!("{name}{i}")));
        }
        for i in 1..=m {
            header.extend((1..=q).map(|j| format!("eta{i}_{j}")));
        }
        let states = r.has_states();
        if states {
            for name in ["x", "xhat"] {
                header.extend((1..=n).map(|i| format!("{name}{i}")));
            }
        }
        writeln!(w, "{}", header.join(","))?;
        // Each signal with its width, in the header's order.
        let mut signals: Vec<(&[f64], usize)> =
            vec![(&r.y, m), (&r.g, m), (&r.e, m), (&r.u, m), (&r.u_f, m), (&r.eta, m * q)];
        if states {
            signals.extend([(&r.x[..], n), (&r.x_hat[..], n)]);
        }
        // Each row is laid out in one buffer and written at once.
        let (mut line, mut buffer) = (Vec::with_capacity(32 * header.len()), zmij::Buffer::new());
        for k in 0..r.len() {
            line.clear();
            decimal::push_display(&mut line, r.t[k], &mut buffer);
            for (sig, width) in &signals {
                for &v in &sig[k * width..(k + 1) * width] {
                    line.push(b',');
                    push_num(&mut line, v, &mut buffer);
                }
            }
            line.push(b'\n');
            w.write_all(&line)?;
        }
        Ok(())
    })
}

/// Writes a value as JSON, pretty-printed, with a final newline.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> io::Result<()> {
    write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value)?;
        writeln!(w)
    })
}

/// A number as plain decimal where that is short (`{}`), scientific otherwise (`{:e}`); always
/// round-trips. The thresholds of `quell::study::csv_number`, written faster ([`decimal`]).
fn push_num(out: &mut Vec<u8>, v: f64, buffer: &mut zmij::Buffer) {
    // −0 (u = −η̂ᵀξ̂ at t = 0) is written 0.
    let v = if v == 0.0 { 0.0 } else { v };
    let a = v.abs();
    if a == 0.0 || (1e-4..1e15).contains(&a) || !a.is_finite() {
        decimal::push_display(out, v, buffer)
    } else {
        decimal::push_exp(out, v, buffer)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The files of a work that fails replace none of the old ones and leave no temporary file; a
    /// work that succeeds replaces them together and removes the stale figures it did not write.
    #[test]
    fn a_failed_work_keeps_every_old_file_and_a_finished_one_replaces_them_together() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        for name in ["signals.csv", "channel1.png", "channel2.png"] {
            fs::write(dir.join(name), "old").unwrap();
        }
        let write = |name: &str| write_atomic(&dir.join(name), |w| w.write_all(b"new"));
        let figure = |stem: &str| stem.starts_with("channel");
        let failed = all_or_nothing(dir, "summary.json", figure, || {
            write("signals.csv")?;
            write("channel1.png")?;
            Err(io::Error::new(io::ErrorKind::StorageFull, "channel2.png: No space left on device"))
        });
        assert!(failed.is_err());
        let mut names: Vec<String> =
            fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
        names.sort();
        assert_eq!(names, ["channel1.png", "channel2.png", "signals.csv"]);
        assert!(names.iter().all(|n| fs::read_to_string(dir.join(n)).unwrap() == "old"));
        all_or_nothing(dir, "summary.json", figure, || write("signals.csv").and_then(|()| write("channel1.png")))
            .unwrap();
        let mut names: Vec<String> =
            fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
        names.sort();
        assert_eq!(names, ["channel1.png", "signals.csv"]);
        assert!(names.iter().all(|n| fs::read_to_string(dir.join(n)).unwrap() == "new"));
        // Outside it a write is in place at once.
        write("design.json").unwrap();
        assert_eq!(fs::read_to_string(dir.join("design.json")).unwrap(), "new");
    }

    /// The mark of a complete set goes first and comes back last: where a rename fails midway (here
    /// signals.csv's, onto a directory made in its place), the directory holds no summary.json,
    /// neither the old one nor the new, so it does not vouch for files of two runs.
    #[test]
    fn the_mark_of_a_complete_set_is_removed_first_and_renamed_last() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        fs::write(dir.join("summary.json"), "old").unwrap();
        let write = |name: &str| write_atomic(&dir.join(name), |w| w.write_all(b"new"));
        let failed = all_or_nothing(
            dir,
            "summary.json",
            |_| false,
            || {
                write("summary.json")?;
                write("signals.csv")?;
                fs::create_dir(dir.join("signals.csv"))
            },
        );
        assert!(failed.is_err());
        assert!(!dir.join("summary.json").exists(), "{:?}", fs::read_to_string(dir.join("summary.json")));
        all_or_nothing(dir, "summary.json", |_| false, || write("summary.json")).unwrap();
        assert_eq!(fs::read_to_string(dir.join("summary.json")).unwrap(), "new");
    }

    /// signals.csv as `core::fmt` lays it out: `{}` for t and for |v| = 0, in [1e-4, 1e15) or not
    /// finite, `{:e}` otherwise.
    fn signals_by_core_fmt(r: &SimResult) -> String {
        let num = |v: f64| {
            let v = if v == 0.0 { 0.0 } else { v }; // −0 written 0
            let a = v.abs();
            if a == 0.0 || (1e-4..1e15).contains(&a) || !a.is_finite() {
                format!("{v}")
            } else {
                format!("{v:e}")
            }
        };
        let mut text = String::new();
        for k in 0..r.len() {
            text.push_str(&r.t[k].to_string());
            let (m, q, n) = (r.m, r.q, r.n);
            let mut signals = vec![(&r.y, m), (&r.g, m), (&r.e, m), (&r.u, m), (&r.u_f, m), (&r.eta, m * q)];
            if r.has_states() {
                signals.extend([(&r.x, n), (&r.x_hat, n)]);
            }
            for (sig, width) in signals {
                for &v in &sig[k * width..(k + 1) * width] {
                    text.push(',');
                    text.push_str(&num(v));
                }
            }
            text.push('\n');
        }
        text
    }

    #[test]
    fn signals_csv_has_core_fmt_bytes() {
        use quell::sim::{Run, Sample};
        use std::ops::ControlFlow;
        // A run of the paper's example with x and x̂ (values across many magnitudes, exact zeros,
        // negative zeros of u = −η̂ᵀξ̂ at the start), then rows of edge values.
        let s = quell::Scenario::from_toml(quell::scenario::PAPER_EXAMPLE).unwrap();
        let d = s.design().unwrap();
        let mut st = quell::sim::RunSettings::of(&s);
        (st.t_end, st.record_states) = (5.0, true);
        let mut r = Run::of(&s, &d).settings(st).simulate(|_| ControlFlow::Continue(())).unwrap();
        let edges =
            [5e-324, -0.0, 1e-4, 9.999999999999999e-5, 1e15, 999999999999999.9, 1e300, f64::NAN, -f64::INFINITY];
        let (m, q, n) = (r.m, r.q, r.n);
        for (k, &v) in edges.iter().enumerate() {
            let (y, eta, x) = (vec![v; m], vec![-v; m * q], vec![v * 0.5; n]);
            let t = [1e-7, 1e20, 0.1, 123.456, 5e-324, 1e15, 2.5, 1e-300, 7.0][k];
            r.push(&Sample { t, y: &y, g: &y, u: &y, u_f: &y, eta: &eta, states: Some((&x, &x)) });
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("signals.csv");
        write_signals(&path, &r).unwrap();
        let written = fs::read_to_string(&path).unwrap();
        let (_header, rows) = written.split_once('\n').unwrap();
        assert_eq!(rows, signals_by_core_fmt(&r));
    }
}
