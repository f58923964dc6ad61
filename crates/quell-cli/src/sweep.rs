//! `quell sweep`: every run of a study file (or one shard of them), in parallel, into runs.csv,
//! summary.json and sweep.png/.svg; `--merge` joins the shards' directories into one.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::Arc;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use quell::study::{self, Outcome, Row, Shard, Study, StudyMeta, Summary, SweepOptions};

use crate::output::{prepare_dir, write_atomic};
use crate::Failure;

#[derive(clap::Args)]
pub struct SweepArgs {
    /// Study file (TOML): scenario, [simulation], [grid], [monte_carlo], [settle].
    #[arg(required_unless_present = "merge", conflicts_with = "merge")]
    study: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "quell-sweep")]
    out: PathBuf,
    /// Only the runs with index ≡ I (mod N): machine I of N, counting from 0.
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
    /// Join the output directories of every shard of one study into --out.
    #[arg(long, num_args = 1.., value_name = "DIR")]
    merge: Vec<PathBuf>,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "N")]
    jobs: Option<usize>,
    /// Skip sweep.png/.svg.
    #[arg(long)]
    no_plots: bool,
    /// Run a study of more than 10⁷ runs.
    #[arg(long)]
    yes: bool,
}

/// Phases for the Ctrl-C handler.
const RUNNING: u8 = 0;
const STOPPING: u8 = 1;

pub fn sweep(args: &SweepArgs) -> Result<(), Failure> {
    if !args.merge.is_empty() {
        return merge(&args.merge, &args.out, !args.no_plots);
    }
    let path = args.study.as_deref().expect("clap requires a study without --merge");
    let study = Study::from_path(path).map_err(|e| Failure::Input(format!("{}: {e}", path.display())))?;
    let shard = match &args.shard {
        None => Shard::ALL,
        Some(s) => Shard::parse(s).map_err(|e| Failure::Input(format!("--shard: {e}")))?,
    };
    let runs = study.len();
    if runs > study::CONFIRM_RUNS && !args.yes {
        return Err(Failure::Input(format!(
            "{}: the study has {runs} runs ({} grid points × {} draws), more than {:e}; check the grid, or pass --yes to run it (rows take ~200 bytes of memory each)",
            path.display(),
            study.points(),
            study.draws(),
            study::CONFIRM_RUNS as f64
        )));
    }
    let pool = thread_pool(args.jobs)?;
    prepare_dir(&args.out).map_err(|e| {
        Failure::Input(format!("--out {}: cannot write there ({e}); choose a writable directory", args.out.display()))
    })?;

    // Ctrl-C: the first stops the sweep (runs under way are abandoned) and the rows done are
    // written; a second quits at once.
    let stop = Arc::new(AtomicBool::new(false));
    let phase = Arc::new(AtomicU8::new(RUNNING));
    {
        let (stop, phase) = (stop.clone(), phase.clone());
        let _ = ctrlc::set_handler(move || {
            stop.store(true, Ordering::SeqCst);
            if phase.swap(STOPPING, Ordering::SeqCst) == STOPPING {
                eprintln!("error: interrupted twice; stopped without writing files");
                std::process::exit(1);
            }
        });
    }
    let n = shard.len(usize::try_from(runs).unwrap_or(usize::MAX));
    let bar = progress_bar(n as u64);
    let on_row = |_: &Row| bar.inc(1);
    let started = Instant::now();
    let result =
        pool.install(|| study::sweep(&study, &SweepOptions { shard, stop: Some(&stop), on_row: Some(&on_row) }));
    bar.finish_and_clear();
    let seconds = started.elapsed().as_secs_f64();
    let meta = StudyMeta::new(&study, shard);
    write_all(&args.out, &meta, &result.rows, result.partial, !args.no_plots)?;
    report(&result.rows, n, seconds, pool.current_num_threads(), &args.out);
    if result.partial {
        return Err(Failure::Run(format!(
            "interrupted after {} of {n} runs; those rows are in {} (marked partial)",
            result.rows.len(),
            args.out.join("runs.csv").display()
        )));
    }
    Ok(())
}

pub(crate) fn thread_pool(jobs: Option<usize>) -> Result<rayon::ThreadPool, Failure> {
    if jobs == Some(0) {
        return Err(Failure::Input("--jobs: expected at least 1 worker thread, found 0".into()));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.unwrap_or(0))
        .build()
        .map_err(|e| Failure::Run(format!("cannot start the worker threads: {e}")))
}

fn progress_bar(len: u64) -> ProgressBar {
    let bar = ProgressBar::new(len);
    if std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::stderr());
        if let Ok(style) =
            ProgressStyle::with_template("sweeping {bar:40} {pos}/{len} runs, {elapsed_precise} elapsed, ETA {eta}")
        {
            bar.set_style(style);
        }
    } else {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar
}

/// One line per outcome and the rate, to stderr.
fn report(rows: &[Row], n: usize, seconds: f64, jobs: usize, out: &Path) {
    let count = |o: Outcome| rows.iter().filter(|r| r.outcome == o).count();
    eprintln!(
        "{} of {n} runs: {} completed, {} diverged, {} failed; {seconds:.2} s on {jobs} thread{} ({:.2} ms per run); wrote {}",
        rows.len(),
        count(Outcome::Completed),
        count(Outcome::Diverged),
        count(Outcome::Failed),
        if jobs == 1 { "" } else { "s" },
        1e3 * seconds / rows.len().max(1) as f64,
        out.display()
    );
}

/// runs.csv, summary.json and (for a 1-D or 2-D grid) sweep.png/.svg.
fn write_all(dir: &Path, meta: &StudyMeta, rows: &[Row], partial: bool, plots: bool) -> Result<(), Failure> {
    let failed = |e: std::io::Error| Failure::Run(format!("writing {}: {e}", dir.display()));
    write_atomic(&dir.join("runs.csv"), |w| study::write_runs_csv(w, meta, rows, partial)).map_err(failed)?;
    let summary = Summary::new(meta.clone(), rows, partial);
    write_atomic(&dir.join("summary.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &summary)?;
        writeln!(w)
    })
    .map_err(failed)?;
    if plots {
        crate::plot::plot_sweep(dir, &summary).map_err(failed)?;
    }
    Ok(())
}

/// Reads one shard's directory: its summary's study identity and its rows.
fn read_shard(dir: &Path) -> Result<(StudyMeta, Vec<Row>, bool), Failure> {
    let bad = |what: &str, e: String| Failure::Input(format!("--merge {}: {what}: {e}", dir.display()));
    let text = std::fs::read_to_string(dir.join("summary.json")).map_err(|e| bad("summary.json", e.to_string()))?;
    let summary: Summary = serde_json::from_str(&text)
        .map_err(|e| bad("summary.json", format!("not a summary written by `quell sweep` ({e})")))?;
    let csv = std::fs::read_to_string(dir.join("runs.csv")).map_err(|e| bad("runs.csv", e.to_string()))?;
    let runs = study::read_runs_csv(&csv, &summary.study).map_err(|e| bad("runs.csv", e))?;
    Ok((summary.study, runs.rows, runs.partial || summary.partial))
}

/// `--merge DIR…`: the shards of one study (same fingerprint, every shard I/N once, none
/// partial) into one directory whose rows are those of an unsharded sweep.
fn merge(dirs: &[PathBuf], out: &Path, plots: bool) -> Result<(), Failure> {
    let mut shards = Vec::new();
    for dir in dirs {
        shards.push((dir, read_shard(dir)?));
    }
    let (first_dir, first) = (shards[0].0, shards[0].1 .0.clone());
    let count = first.shard.count;
    let mut seen = vec![None; count];
    for (dir, (meta, _, partial)) in &shards {
        let here = format!("--merge {}", dir.display());
        if meta.fingerprint != first.fingerprint {
            return Err(Failure::Input(format!(
                "{here}: comes from a different study than {} (fingerprint {} vs {}); merge only the shards of one study file",
                first_dir.display(),
                meta.fingerprint,
                first.fingerprint
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
                "{here}: is partial (its sweep was interrupted); run `quell sweep STUDY --shard {}/{count}` again into it",
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
    if let Some(missing) = seen.iter().position(Option::is_none) {
        return Err(Failure::Input(format!(
            "--merge: shard {missing}/{count} is missing; give the output directory of every shard 0/{count} … {}/{count}",
            count - 1
        )));
    }
    let mut rows: Vec<Row> = shards.into_iter().flat_map(|(_, (_, rows, _))| rows).collect();
    rows.sort_by_key(|r| r.run);
    if rows.len() as u64 != first.runs {
        return Err(Failure::Input(format!(
            "--merge: the shards hold {} runs, but the study has {}; rerun the incomplete shards",
            rows.len(),
            first.runs
        )));
    }
    let meta = StudyMeta { shard: Shard::ALL, ..first.clone() };
    prepare_dir(out).map_err(|e| {
        Failure::Input(format!("--out {}: cannot write there ({e}); choose a writable directory", out.display()))
    })?;
    write_all(out, &meta, &rows, false, plots)?;
    eprintln!("merged {} shards: {} runs into {}", count, rows.len(), out.display());
    Ok(())
}
