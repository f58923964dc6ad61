//! `quell sweep`: every run of a study file (or one shard of them), in parallel, into runs.csv,
//! summary.json and sweep.png/.svg; `--merge` joins the shards' directories into one.

use std::path::{Path, PathBuf};
use std::time::Instant;

use quell::study::{self, Outcome, Row, Shard, Study, StudyMeta, Summary, SweepOptions, MAX_JOBS};

use crate::interrupt::Interrupt;
use crate::journal::{self, Journal, JOURNAL};
use crate::output::{check_not_busy, prepare_out, write_atomic};
use crate::Failure;

#[derive(clap::Args)]
#[command(override_usage = "quell sweep [OPTIONS] <STUDY>\n       quell sweep --merge <DIR>... [--out <OUT>]")]
pub struct SweepArgs {
    /// Study file (TOML): scenario, max_steps, [simulation], [grid], [monte_carlo], [runaway], [settle]
    /// (docs/studies.md).
    #[arg(required_unless_present = "merge", conflicts_with = "merge")]
    study: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "quell-sweep")]
    out: PathBuf,
    /// Only the runs with index ≡ I (mod N): machine I of N, counting from 0.
    #[arg(long, value_name = "I/N", allow_hyphen_values = true)]
    shard: Option<String>,
    /// Join the output directories of every shard of one study into --out.
    #[arg(long, num_args = 1.., value_name = "DIR")]
    merge: Vec<PathBuf>,
    /// Worker threads (default: one per core). A merge runs nothing, so it takes none.
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = parse_jobs, conflicts_with = "merge")]
    jobs: Option<usize>,
    /// Skip sweep.png/.svg.
    #[arg(long)]
    no_plots: bool,
    /// Run a study of more than 10⁷ runs or 10⁵ grid points (not with --merge, which runs nothing).
    #[arg(long, conflicts_with = "merge")]
    yes: bool,
    /// Resume the interrupted sweep in --out: keep its rows and run the others (the same study
    /// file and --shard).
    #[arg(long, conflicts_with = "merge")]
    resume: bool,
}

/// The files a sweep writes into --out (besides its figures).
const OUTPUTS: &[&str] = &["runs.csv", "summary.json", "sweep.png", "sweep.svg", JOURNAL];

/// The study file at `path`; a refusal starts with the path once (a file that cannot be read is
/// already named by the error's key).
pub(crate) fn read_study(path: &Path) -> Result<Study, Failure> {
    Study::from_path(path).map_err(|e| {
        let shown = path.display().to_string();
        let mut message = if e.key == shown { e.to_string() } else { format!("{shown}: {e}") };
        // The library says the file is a scenario; here, the command that runs it.
        if quell::study::is_scenario_section(&e.key) {
            message.push_str(&format!("\nrun the scenario itself with `quell run {shown}`"));
        }
        Failure::Input(message)
    })
}

pub fn sweep(args: &SweepArgs) -> Result<(), Failure> {
    if !args.merge.is_empty() {
        if let Some(s) = &args.shard {
            return Err(Failure::Input(format!(
                "--shard {s}: --merge joins every shard into one directory, so it takes no --shard; remove it"
            )));
        }
        return merge(&args.merge, &args.out, !args.no_plots);
    }
    let (study, shard, n) = planned(args)?;
    let meta = StudyMeta::new(&study, shard);
    if !args.resume {
        unfinished_in_the_way(&args.out, &meta, RESUME)?;
    }
    let (kept, done) = if args.resume { resumed(&args.out, &meta, n, &study)? } else { (Vec::new(), Vec::new()) };
    if args.resume && kept.len() == n {
        return finish_resumed(&args.out, &meta, &kept, !args.no_plots);
    }
    let pool = thread_pool(args.jobs, n - kept.len())?;
    prepare_out(&args.out, OUTPUTS)?;
    let journal = Journal::create(&args.out, &meta, &kept)
        .map_err(|e| Failure::Input(format!("--out {}: {e}; choose another output directory", args.out.display())))?;

    // Ctrl-C or SIGTERM: the first stops the sweep (runs under way are abandoned) and the rows done
    // are written; a second before writing begins quits at once.
    let interrupt = Interrupt::install(
        "interrupted twice; stopped without writing runs.csv: the rows done are in runs.partial.csv, which --resume reads",
    );
    let stop = || interrupt.stop_flag().load(std::sync::atomic::Ordering::Relaxed);
    if let Some(w) = study.fast_rate_caution(&stop) {
        eprintln!("⚠ warning: {w}");
    }
    let bar = crate::progress_bar(n as u64, "sweeping {bar:40} {pos}/{len} runs, {elapsed_precise} elapsed, ETA {eta}");
    bar.inc(kept.len() as u64);
    let on_row = |row: &Row| {
        journal.append(row);
        bar.inc(1);
    };
    let started = Instant::now();
    let options = SweepOptions { shard, stop: Some(interrupt.stop_flag()), on_row: Some(&on_row), done: &done };
    let result = pool.install(|| study::sweep(&study, &options));
    bar.finish_and_clear();
    interrupt.start_writing();
    let seconds = started.elapsed().as_secs_f64();
    let (ran, mut rows) = (result.rows.len(), kept);
    if let Some(w) = study.explicit_stiff_caution(&result.rows) {
        eprintln!("⚠ warning: {w}");
    }
    rows.extend(result.rows);
    rows.sort_by_key(|r| r.run);
    // A complete sweep's files (still in --out: nothing has been written over them) only a
    // complete sweep replaces, resumed or not; only where the journal holds the rows, as one whose
    // writes failed leaves runs.csv to hold them. Read on interruption alone, not at every start
    // (a large grid's summary.json is hundreds of MB).
    if result.partial && journal.whole() && marked_summary(&args.out).is_some_and(|m| !m.partial) {
        return Err(kept_earlier(&args.out, rows.len(), n));
    }
    write_all(&args.out, &meta, (&rows, result.partial), !args.no_plots, || {
        if let Err(e) = journal.remove() {
            eprintln!(
                "⚠ warning: {}: {e}; runs.csv holds its rows, so it may be removed",
                args.out.join(JOURNAL).display()
            );
        }
    })?;
    report(&rows, ran, n, seconds, pool.current_num_threads(), &args.out);
    if args.resume {
        eprintln!("resumed: {} rows kept, {ran} runs run", rows.len() - ran);
    }
    if result.partial {
        return Err(Failure::Run(format!(
            "interrupted after {} of {n} runs; those rows are in {} (marked partial; `--resume` runs the others)",
            rows.len(),
            args.out.join("runs.csv").display()
        )));
    }
    Ok(())
}

/// The study of `args`, checked, with its shard and that shard's number of runs: refused when the
/// study cannot be swept or is over [`study::CONFIRM_RUNS`] runs or [`study::CONFIRM_POINTS`] grid
/// points without `--yes`.
fn planned(args: &SweepArgs) -> Result<(Study, Shard, usize), Failure> {
    let path = args.study.as_deref().expect("clap requires a study without --merge");
    let study = read_study(path)?;
    quell::study::check_sweep(&study).map_err(|e| Failure::Input(format!("{}: {e}", path.display())))?;
    // Before a resumed sweep's early finish too, which writes the same files.
    crate::output::not_the_study_inputs(path, study.scenario_path.as_deref(), &args.out, OUTPUTS)?;
    let shard = match &args.shard {
        None => Shard::ALL,
        Some(s) => Shard::parse(s).map_err(|e| Failure::Input(format!("--shard: {e}")))?,
    };
    let runs = study.len();
    if runs > study::CONFIRM_RUNS && !args.yes {
        return Err(Failure::Input(format!(
            "{}: the study has {runs} runs ({} × {}), more than {:e}; check the grid, or pass --yes to run it (rows take ~200 bytes of memory each)",
            path.display(),
            quell::study::count(study.points(), "grid point"),
            quell::study::count(study.draws(), "draw"),
            study::CONFIRM_RUNS as f64
        )));
    }
    if study.points() > study::CONFIRM_POINTS && !args.yes {
        return Err(Failure::Input(format!(
            "{}: the study has {}, more than {:e}, and summary.json summarizes each (~3 kB of file and ~2.4 kB of memory a point with two channels); check the grid, or pass --yes to run it",
            path.display(),
            quell::study::count(study.points(), "grid point"),
            study::CONFIRM_POINTS as f64
        )));
    }
    let n = shard.len(usize::try_from(runs).unwrap_or(usize::MAX));
    if n == 0 {
        eprintln!(
            "⚠ warning: shard {}/{} has no runs: the study has {runs}, fewer than the shards; its files are written empty, as --merge needs every shard",
            shard.index, shard.count
        );
    }
    Ok((study, shard, n))
}

/// `--jobs N`: 1 ≤ N ≤ [`MAX_JOBS`]; clap prints the message after the flag's name.
pub(crate) fn parse_jobs(text: &str) -> Result<usize, String> {
    let bad = || format!("expected a number of worker threads from 1 to {MAX_JOBS} (omit --jobs for one per core)");
    match text.trim().parse::<i128>() {
        Ok(n) if (1..=MAX_JOBS as i128).contains(&n) => Ok(n as usize),
        _ => Err(bad()),
    }
}

/// A pool of `jobs` threads (default one per core), never more than the `runs` it is to carry out.
pub(crate) fn thread_pool(jobs: Option<usize>, runs: usize) -> Result<rayon::ThreadPool, Failure> {
    let threads = jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.min(runs).max(1))
        .build()
        .map_err(|e| Failure::Run(format!("cannot start the worker threads: {e}")))
}

/// One line per outcome and the rate, to stderr.
fn report(rows: &[Row], ran: usize, n: usize, seconds: f64, jobs: usize, out: &Path) {
    let count = |o: Outcome| rows.iter().filter(|r| r.outcome == o).count();
    eprintln!(
        "{} of {n} runs: {} completed, {} diverged, {} failed, {} stopped by [runaway]; {seconds:.2} s on {jobs} thread{}{}; wrote {}",
        rows.len(),
        count(Outcome::Completed),
        count(Outcome::Diverged),
        count(Outcome::Failed),
        count(Outcome::Stopped),
        if jobs == 1 { "" } else { "s" },
        // Per run of this process (a resumed sweep's kept rows took no time here); beside it a
        // run's own time on its thread, which the wall time per run divides among the threads (a
        // tryout read "110 ms per run" on 2 threads as the cost of a run that took 182 ms).
        match ran {
            0 => String::new(),
            k => format!(
                " ({:.2} ms of wall time per run; a run took {:.2} ms on its thread, the mean of runs.csv's wall_ms)",
                1e3 * seconds / k as f64,
                rows.iter().map(|r| r.wall_ms).sum::<f64>() / rows.len().max(1) as f64
            ),
        },
        out.display()
    );
}

/// runs.csv, summary.json and (for a 1-D or 2-D grid) sweep.png/.svg.
fn write_all(
    dir: &Path,
    meta: &StudyMeta,
    (rows, partial): (&[Row], bool),
    plots: bool,
    written: impl FnOnce(),
) -> Result<(), Failure> {
    let failed = |e: std::io::Error| Failure::Run(format!("writing {}: {e}", dir.display()));
    write_atomic(&dir.join("runs.csv"), |w| study::write_runs_csv(w, meta, rows, partial)).map_err(failed)?;
    // From here on runs.csv holds every run: a failure says so.
    let failed = |e: std::io::Error| {
        Failure::Run(format!("writing {}: {e}; runs.csv, written before it, holds every run", dir.display()))
    };
    let summary = Summary::new(meta.clone(), rows, partial);
    crate::output::write_json(&dir.join("summary.json"), &summary).map_err(failed)?;
    // The data are whole: the journal can go before the figures (one that failed had left it,
    // and the next sweep had called the directory unfinished).
    written();
    // A figure of an earlier sweep (plots now skipped, or a grid that has none) must not stand
    // beside the new rows.
    crate::output::remove_figures(dir, |stem| stem == "sweep", &[]).map_err(failed)?;
    if plots && !crate::plot::plot_sweep(dir, &summary, rows).map_err(failed)? {
        eprintln!(
            "no sweep.png: a grid of {} keys has no figure (one is drawn for none, one or two); runs.csv has every run",
            meta.grid.len()
        );
    }
    Ok(())
}

/// Checks that a shard's rows are exactly its runs (index ≡ I mod N, each once, all of them), so
/// a truncated runs.csv or one copied from another shard is named instead of merged.
fn check_shard_rows(dir: &Path, shard: Shard, rows: &[Row], total: usize) -> Result<(), Failure> {
    let here = format!("--merge {}", dir.display());
    let expected = shard.len(total);
    let mut runs = shard.runs(total);
    for (k, row) in rows.iter().enumerate() {
        match runs.next() {
            Some(run) if run == row.run => {}
            Some(run) => {
                return Err(Failure::Input(format!(
                    "{here}: row {} of runs.csv is run {}, but shard {}/{} holds runs {} + k·{} and the next of them is {run}; its runs.csv was edited or comes from another shard: rerun `quell sweep STUDY --shard {}/{}` into it",
                    k + 1,
                    row.run,
                    shard.index,
                    shard.count,
                    shard.index,
                    shard.count,
                    shard.index,
                    shard.count
                )))
            }
            None => break,
        }
    }
    if rows.len() != expected {
        return Err(Failure::Input(format!(
            "{here}: runs.csv holds {} rows, but shard {}/{} has {expected} runs (is runs.csv truncated?); rerun `quell sweep STUDY --shard {}/{}` into it",
            rows.len(),
            shard.index,
            shard.count,
            shard.index,
            shard.count
        )));
    }
    Ok(())
}

/// How an unfinished sweep in `--out` is finished, said to a new sweep into it, and to a merge.
const RESUME: &str = "add --resume";
const RESUME_BEFORE_MERGE: &str = "run `quell sweep STUDY --resume` into it";

/// The refusal of a new sweep into `dir`, which holds a journal: the rows of a sweep killed outright
/// are only there, and the new sweep would replace it. It names the way on for this study's
/// journal (`resume`: "add --resume", or how a merge gets there), another study's or shard's, and
/// a file that is not a journal.
fn journal_in_the_way(dir: &Path, meta: &StudyMeta, resume: &str) -> Failure {
    let here = format!("--out {}", dir.display());
    Failure::Input(match journal::read(dir, meta) {
        Ok(Some((old, _))) if same_sweep(&old, meta) => format!(
            "{here}: holds the journal {JOURNAL} of a sweep of this study that did not finish; {resume} to finish it (it keeps the rows done), or remove {JOURNAL} to start over"
        ),
        Ok(_) => format!(
            "{here}: holds the journal {JOURNAL} of an unfinished sweep of another study or shard; finish it with that study file and --shard (--resume), or remove {JOURNAL} to start over here, or choose another --out"
        ),
        Err(e) => format!("{here}: {JOURNAL}: {e}; remove it to start over here, or choose another --out"),
    })
}

/// The refusal of a new sweep into `dir`, which holds the rows of an interrupted sweep: a journal
/// ([`journal_in_the_way`]), a summary.json marked partial (a Ctrl-C's or a batch system's time
/// limit's rows had been overwritten without a word), or, where summary.json cannot be read (a kill
/// between the two renames), a runs.csv that ends with `# partial: …`; `--resume` can finish them
/// (`resume` says how: [`RESUME`], or [`RESUME_BEFORE_MERGE`]).
fn unfinished_in_the_way(dir: &Path, meta: &StudyMeta, resume: &str) -> Result<(), Failure> {
    if dir.join(JOURNAL).exists() {
        check_not_busy(dir)?;
        return Err(journal_in_the_way(dir, meta, resume));
    }
    let refuse = |what: String| {
        Err(Failure::Input(format!(
            "--out {}: holds an unfinished sweep ({what}): {resume} to finish it with its study file (and its --shard), or remove runs.csv and summary.json to start over, or choose another --out",
            dir.display()
        )))
    };
    if let Some(m) = marked_summary(dir) {
        return match m.partial {
            true => refuse(format!("{} of its runs done, summary.json's partial", m.runs_done)),
            false => Ok(()),
        };
    }
    match last_line(&dir.join("runs.csv")) {
        Some(line) if line.starts_with("# partial:") => refuse(format!("runs.csv ends with {line:?}")),
        _ => Ok(()),
    }
}

/// An interrupted sweep's end where `out` held a complete sweep's files: they stay until a sweep
/// completes, its `done` rows of `n` in the journal (an interrupted sweep had replaced another
/// study's 3,000 rows with its 328; hostile review, 2026-12-06).
fn kept_earlier(out: &Path, done: usize, n: usize) -> Failure {
    Failure::Run(format!(
        "interrupted after {done} of {n} runs; those rows are in {} (`--resume` runs the others, and then replaces the earlier sweep's files); runs.csv and summary.json there are the earlier sweep's, kept",
        out.join(JOURNAL).display()
    ))
}

/// The fields wanted of summary.json.
#[derive(serde::Deserialize)]
struct Marked {
    partial: bool,
    runs_done: usize,
}

/// Whether the summary.json in `dir` is partial and its runs done, read as a stream (a 3e5-point
/// grid's is 800 MB); `None` where there is none or it cannot be read.
fn marked_summary(dir: &Path) -> Option<Marked> {
    let file = quell::files::open_regular(&dir.join("summary.json")).ok()?;
    serde_json::from_reader(std::io::BufReader::new(file)).ok()
}

/// A resumed sweep whose rows were all done (killed while it wrote its files: the journal holds
/// every row, the files may not): its files written from them, the journal removed.
fn finish_resumed(out: &Path, meta: &StudyMeta, kept: &[Row], plots: bool) -> Result<(), Failure> {
    let n = kept.len();
    if !out.join(JOURNAL).exists() {
        eprintln!("nothing to resume: {} holds every run of the study ({n})", out.display());
        return Ok(());
    }
    let mut removed = Ok(());
    write_all(out, meta, (kept, false), plots, || removed = std::fs::remove_file(out.join(JOURNAL)))?;
    removed.map_err(|e| Failure::Run(format!("{JOURNAL}: {e}")))?;
    eprintln!("resumed: the journal held every run of the study ({n}); wrote {}", out.display());
    Ok(())
}

/// The last line of the file at `path` (from its last 4 KiB), or `None` when it cannot be read.
fn last_line(path: &Path) -> Option<String> {
    use std::io::{Read, Seek, SeekFrom};
    let mut file = quell::files::open_regular(path).ok()?;
    let len = file.metadata().ok()?.len();
    file.seek(SeekFrom::Start(len.saturating_sub(4096))).ok()?;
    let mut tail = Vec::new();
    file.read_to_end(&mut tail).ok()?;
    let text = String::from_utf8_lossy(&tail);
    text.trim_end().lines().last().map(str::to_string)
}

/// `--resume`: the rows the interrupted sweep of this study and shard (`meta`, of `n` runs) wrote
/// into `dir` (with their drawn values from `study` where it wrote none), and which runs of the
/// shard they are (by place k: run index + k·count).
fn resumed(dir: &Path, meta: &StudyMeta, n: usize, study: &Study) -> Result<(Vec<Row>, Vec<bool>), Failure> {
    let here = format!("--resume {}", dir.display());
    quell::files::check_dir(dir).map_err(|e| {
        Failure::Input(format!("{here}: {e}; resume into the --out directory of the interrupted sweep"))
    })?;
    // The journal, where there is one, is newer than runs.csv: it is removed once runs.csv is written.
    let (old, rows, source) = match journal::read(dir, meta) {
        Err(e) => {
            return Err(Failure::Input(format!("{here}: {JOURNAL}: {e}; remove it and run the sweep again without --resume")))
        }
        Ok(Some((old, rows))) => (old, rows, JOURNAL),
        Ok(None) if dir.join("summary.json").exists() => {
            let (old, rows, _) = read_sweep_dir(dir, "--resume")?;
            (old, rows, "runs.csv")
        }
        Ok(None) => {
            return Err(Failure::Input(format!(
                "{here}: holds neither the summary.json nor the {JOURNAL} of an earlier sweep (a sweep killed before its first run finished leaves none); resume into the --out of the interrupted sweep, or leave --resume out"
            )))
        }
    };
    // differing_key compares every key but the shard, the fingerprint included; a sweep from
    // before runs.csv held the drawn values has none: its rows get them from the study.
    let (old, mut rows) =
        (if old.drawn.is_empty() { StudyMeta { drawn: meta.drawn.clone(), ..old } } else { old }, rows);
    for row in rows.iter_mut().filter(|r| r.drawn.is_empty() && !meta.drawn.is_empty()) {
        row.drawn = study.run_document(row.run).map_or_else(Vec::new, |doc| study.drawn(&doc));
    }
    if !same_sweep(&old, meta) {
        return Err(Failure::Input(format!(
            "{here}: its rows come from another study or shard (fingerprint {}, shard {}/{}; this one: {}, {}/{}); resume with the same study file and --shard, or choose another --out",
            old.fingerprint, old.shard.index, old.shard.count, meta.fingerprint, meta.shard.index, meta.shard.count
        )));
    }
    let (shard, mut done) = (meta.shard, vec![false; n]);
    for row in &rows {
        let k = (row.run % shard.count == shard.index).then(|| row.run / shard.count).filter(|&k| k < n);
        match k {
            Some(k) if !done[k] => done[k] = true,
            _ => {
                // Starting over means removing what a new sweep would refuse to replace.
                return Err(Failure::Input(format!(
                    "{here}: {source}'s run {} is not a run of shard {}/{} or is there twice (the file was edited?); to start over, remove {JOURNAL}, runs.csv and summary.json from it and run the sweep without --resume",
                    row.run, shard.index, shard.count
                )));
            }
        }
    }
    Ok((rows, done))
}

/// A shard's directory for `--merge`: refused while it holds a journal (a shard killed outright, to
/// be resumed, not merged), else [`read_sweep_dir`].
fn shard_to_merge(dir: &Path) -> Result<SweepDir, Failure> {
    if dir.join(JOURNAL).exists() {
        return Err(Failure::Input(format!(
            "--merge {}: holds the journal {JOURNAL} of a sweep that did not finish; run `quell sweep STUDY --shard I/N --resume` into it (it keeps the rows done and runs the others), then merge",
            dir.display()
        )));
    }
    read_sweep_dir(dir, "--merge")
}

/// A sweep's directory read ([`read_sweep_dir`]): its summary's study identity, its rows and
/// whether it is partial.
type SweepDir = (StudyMeta, Vec<Row>, bool);

/// What a directory read as a sweep's must be.
const WHAT_TO_GIVE: &str =
    "give the output directory of a `quell sweep` (its --out), which holds summary.json and runs.csv";

/// Reads one sweep's directory (a shard for `--merge`, an interrupted sweep for `--resume`, the
/// `flag` its messages name): its summary's study identity, its rows and whether it is partial.
fn read_sweep_dir(dir: &Path, flag: &str) -> Result<SweepDir, Failure> {
    let bad = |what: &str, e: String| Failure::Input(format!("{flag} {}: {what}: {e}", dir.display()));
    // Not text: damaged, not edited; the shard's own run writes it anew.
    let unreadable = |what: &str, e: std::io::Error| match e.kind() {
        std::io::ErrorKind::InvalidData => {
            bad(what, format!("{e}: the file is damaged; run that shard again (its quell sweep --shard command)"))
        }
        // Not a sweep's directory at all: say what one holds.
        std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory => bad(what, format!("{e}; {WHAT_TO_GIVE}")),
        _ => bad(what, e.to_string()),
    };
    // Read as a stream: what is not a summary is refused at its first wrong byte, not once read.
    let file = quell::files::open_regular(&dir.join("summary.json")).map_err(|e| unreadable("summary.json", e))?;
    let summary: Summary = serde_json::from_reader(std::io::BufReader::new(file))
        .map_err(|e| bad("summary.json", format!("not a summary written by `quell sweep` ({e}); {WHAT_TO_GIVE}")))?;
    let (line, lines) = study::runs_csv_bounds(&summary.study);
    let csv =
        quell::files::read_lines_within(&dir.join("runs.csv"), line, lines).map_err(|e| unreadable("runs.csv", e))?;
    let shard = summary.study.shard;
    if shard.index >= shard.count {
        return Err(bad(
            "summary.json",
            format!(
                "study.shard is {}/{}: expected an index from 0 to count − 1; the file was not written by `quell sweep --shard`, or was edited",
                shard.index, shard.count
            ),
        ));
    }
    let runs = study::read_runs_csv(&csv, &summary.study).map_err(|e| bad("runs.csv", e))?;
    Ok((summary.study, runs.rows, runs.partial || summary.partial))
}

/// Whether rows written for `old` belong to the sweep of `meta`: the same study and shard.
fn same_sweep(old: &StudyMeta, meta: &StudyMeta) -> bool {
    old.shard == meta.shard && differing_key(old, meta).is_none()
}

/// The first key of `study` in summary.json, its shard aside (checked on its own), where `a` and
/// `b` differ, either holding it (a key one leaves out, `drawn` of a sweep before 2026-12-07, had
/// been seen from one side only: merging two shards depended on their order; diff review).
fn differing_key(a: &StudyMeta, b: &StudyMeta) -> Option<String> {
    let (a, b) = (serde_json::to_value(a).ok()?, serde_json::to_value(b).ok()?);
    let (a, b) = (a.as_object()?, b.as_object()?);
    a.keys().chain(b.keys()).find(|key| *key != "shard" && a.get(*key) != b.get(*key)).cloned()
}

/// Shard `index` of a split into `count` was not given to `--merge`.
fn missing_shard(index: usize, count: usize) -> Failure {
    Failure::Input(format!(
        "--merge: shard {index}/{count} is missing; give the output directory of every shard 0/{count} … {}/{count}",
        count - 1
    ))
}

/// The shards to merge (each directory with its study identity, rows and whether partial), held
/// to the first's (`first_dir`, `first`): one study and one split, none partial, every shard once.
fn check_shards(shards: &[(&PathBuf, SweepDir)], (first_dir, first): (&Path, &StudyMeta)) -> Result<(), Failure> {
    let count = first.shard.count;
    let mut seen = vec![None; count];
    for (dir, (meta, _, partial)) in shards {
        let here = format!("--merge {}", dir.display());
        if meta.fingerprint != first.fingerprint {
            return Err(Failure::Input(format!(
                "{here}: comes from a different study than {} (fingerprint {} vs {}); merge only the shards of one study file",
                first_dir.display(),
                meta.fingerprint,
                first.fingerprint
            )));
        }
        if differing_key(meta, first).as_deref() == Some("drawn") {
            let older = if meta.drawn.is_empty() { dir } else { first_dir };
            return Err(Failure::Input(format!(
                "{here}: one of it and {} holds the drawn values' columns in runs.csv and the other not: {} was written by a quell before 2026-12-07; run that shard again (quell sweep STUDY --shard I/N) into it, then merge",
                first_dir.display(),
                older.display()
            )));
        }
        if let Some(key) = differing_key(meta, first) {
            return Err(Failure::Input(format!(
                "{here}: its summary.json's study.{key} differs from {}'s; merge only the shards of one study, as `quell sweep --shard` wrote them",
                first_dir.display()
            )));
        }
        if meta.shard.count != count {
            return Err(Failure::Input(format!(
                "{here}: is shard {}/{} but {} is one of {count} shards; merge the shards of one --shard I/N split",
                meta.shard.index,
                meta.shard.count,
                first_dir.display()
            )));
        }
        if *partial {
            return Err(Failure::Input(format!(
                "{here}: is partial (its sweep was interrupted); run `quell sweep STUDY --shard {}/{count} --resume` into it (it keeps the rows done and runs the others)",
                meta.shard.index
            )));
        }
        if let Some(other) = seen[meta.shard.index].replace(dir) {
            return Err(Failure::Input(format!(
                "{here}: shard {}/{count} is given twice (also {})",
                meta.shard.index,
                other.display()
            )));
        }
    }
    if let Some(index) = seen.iter().position(Option::is_none) {
        return Err(missing_shard(index, count));
    }
    Ok(())
}

/// `--merge DIR…`: the shards of one study (same fingerprint, every shard I/N once, none
/// partial) into one directory whose rows are those of an unsharded sweep.
fn merge(dirs: &[PathBuf], out: &Path, plots: bool) -> Result<(), Failure> {
    let same = |a: &Path, b: &Path| a.canonicalize().ok().is_some_and(|a| b.canonicalize().ok() == Some(a));
    if let Some(dir) = dirs.iter().find(|d| same(d, out)) {
        return Err(Failure::Input(format!(
            "--out {}: is one of the --merge directories ({}); merging into it would replace that shard's rows; choose a new output directory",
            out.display(),
            dir.display()
        )));
    }
    let mut shards = Vec::new();
    for dir in dirs {
        shards.push((dir, shard_to_merge(dir)?));
    }
    let (first_dir, first) = (shards[0].0, shards[0].1 .0.clone());
    let count = first.shard.count;
    // More shards than directories: one of the first len + 1 is missing. Named before the table of
    // shards is allocated, as a count from an edited file or a huge split may be beyond memory.
    if count > shards.len() {
        let given = |i: usize| shards.iter().any(|(_, (m, ..))| m.shard.index == i);
        return Err(missing_shard((0..=shards.len()).find(|&i| !given(i)).unwrap_or(0), count));
    }
    check_shards(&shards, (first_dir, &first))?;
    let total = usize::try_from(first.runs).unwrap_or(usize::MAX);
    for (dir, (meta, rows, _)) in &shards {
        check_shard_rows(dir, meta.shard, rows, total)?;
    }
    let mut rows: Vec<Row> = shards.into_iter().flat_map(|(_, (_, rows, _))| rows).collect();
    rows.sort_by_key(|r| r.run);
    let meta = StudyMeta { shard: Shard::ALL, ..first };
    // As for a new sweep: an interrupted sweep's rows there are refused, not replaced (a merge had
    // overwritten them, and the journal beside them then belonged to no result).
    unfinished_in_the_way(out, &meta, RESUME_BEFORE_MERGE)?;
    prepare_out(out, OUTPUTS)?;
    write_all(out, &meta, (&rows, false), plots, || ())?;
    let shards = if count == 1 { "shard" } else { "shards" };
    eprintln!("merged {count} {shards}: {} runs into {}", rows.len(), out.display());
    Ok(())
}
