//! A sweep's journal, `runs.partial.csv` in its --out: every row as its run finishes, so that a
//! sweep killed outright (SIGKILL, the out-of-memory killer, a batch system past its grace period),
//! which writes neither runs.csv nor summary.json, loses only the runs under way; `--resume` reads
//! it. Its first line is `# quell sweep journal: ` and the study's identity (summary.json's
//! `study`, as JSON), then runs.csv's header and rows in the order the runs finished. The journal
//! is removed once runs.csv and summary.json hold every row.

use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

use quell::study::{self, Row, StudyMeta};

/// The journal's name in --out.
pub const JOURNAL: &str = "runs.partial.csv";

/// The journal's first line, before the study's identity.
const OPENING: &str = "# quell sweep journal: ";

/// An open journal: rows are appended and flushed one by one from the worker threads.
pub struct Journal {
    path: PathBuf,
    file: Mutex<BufWriter<File>>,
    meta: StudyMeta,
    /// A write failed: warned once, and the journal is given up (the sweep goes on; runs.csv is
    /// written at its end as ever).
    failed: AtomicBool,
}

impl Journal {
    /// A new journal in `dir` for the study `meta`, holding `kept` (the rows a resumed sweep keeps),
    /// written under a temporary name and renamed over an earlier journal, so that a kill while it
    /// is written loses none of them.
    pub fn create(dir: &Path, meta: &StudyMeta, kept: &[Row]) -> io::Result<Journal> {
        let path = dir.join(JOURNAL);
        let identity = serde_json::to_string(meta).map_err(io::Error::other)?;
        quell::files::write_atomic(&path, |w| {
            writeln!(w, "{OPENING}{identity}")?;
            study::write_runs_header(w, meta)?;
            kept.iter().try_for_each(|r| study::write_run_row(w, meta, r))
        })?;
        let file = OpenOptions::new().append(true).open(&path)?;
        let failed = AtomicBool::new(false);
        Ok(Journal { path, file: Mutex::new(BufWriter::new(file)), meta: meta.clone(), failed })
    }

    /// Appends `row` and flushes it to the file.
    pub fn append(&self, row: &Row) {
        if self.failed.load(Ordering::Relaxed) {
            return;
        }
        let mut file = self.file.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Err(e) = study::write_run_row(&mut *file, &self.meta, row).and_then(|()| file.flush()) {
            if !self.failed.swap(true, Ordering::Relaxed) {
                eprintln!(
                    "⚠ warning: {}: {e}; the sweep goes on without its journal (a kill now would lose its rows; runs.csv is written at the end as ever)",
                    self.path.display()
                );
            }
        }
    }

    /// Every row appended was written (no write failed).
    pub fn whole(&self) -> bool {
        !self.failed.load(Ordering::Relaxed)
    }

    /// Removes the journal once runs.csv and summary.json hold its rows.
    pub fn remove(self) -> io::Result<()> {
        drop(self.file);
        std::fs::remove_file(&self.path)
    }
}

/// The study identity and rows of the journal in `dir`, if there is one. A last line without its
/// line break (the kill came while it was written) is dropped; anything else that is not a
/// journal's content is an error naming the line.
pub fn read(dir: &Path, meta: &StudyMeta) -> Result<Option<(StudyMeta, Vec<Row>)>, String> {
    // Lines as long as a runs.csv's of the study being swept, or 64 MiB: the first line of any
    // study's journal (its identity, in JSON about twice the 16 MiB a study file may take in TOML).
    let line = study::runs_csv_bounds(meta).0.max(64 << 20);
    let text = match quell::files::read_lines_within(&dir.join(JOURNAL), line, usize::MAX) {
        Ok(text) => text,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e.to_string()),
    };
    let whole = match text.rfind('\n') {
        Some(end) => &text[..=end],
        None => "",
    };
    let (first, rest) = whole.split_once('\n').unwrap_or(("", ""));
    let meta: StudyMeta =
        first.strip_prefix(OPENING).and_then(|json| serde_json::from_str(json).ok()).ok_or_else(|| {
            format!("line 1: expected `{OPENING}` and a study's identity; the file was not written by `quell sweep`")
        })?;
    // runs.csv's reader numbers its lines from the header: one more here.
    let runs = study::read_runs_csv(rest, &meta).map_err(|e| renumbered(&e))?;
    Ok(Some((meta, runs.rows)))
}

/// `line N: …` of runs.csv's reader as the journal's line N + 1.
fn renumbered(e: &str) -> String {
    let Some((n, tail)) = e.strip_prefix("line ").and_then(|r| r.split_once(':')) else { return e.to_string() };
    n.parse::<usize>().map_or_else(|_| e.to_string(), |n| format!("line {}:{tail}", n + 1))
}
