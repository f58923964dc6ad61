//! Writing results: every file goes to a temporary name in the output directory and is renamed
//! into place, so a reader never sees a half-written file.

use std::fs;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use quell::sim::SimResult;

/// Writes a file atomically: `contents` fills `path.tmp`, which is then renamed to `path`.
pub fn write_atomic(path: &Path, contents: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> io::Result<()> {
    let tmp = tmp_name(path);
    let result = (|| {
        let mut w = BufWriter::new(fs::File::create(&tmp)?);
        contents(&mut w)?;
        w.into_inner().map_err(|e| e.into_error())?.sync_all()
    })();
    match result {
        Ok(()) => fs::rename(&tmp, path),
        Err(e) => {
            let _ = fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// The temporary name beside `path`, keeping its extension: `.stem.tmp.ext`.
pub fn tmp_name(path: &Path) -> PathBuf {
    let stem = path.file_stem().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    match path.extension() {
        Some(ext) => path.with_file_name(format!(".{stem}.tmp.{}", ext.to_string_lossy())),
        None => path.with_file_name(format!(".{stem}.tmp")),
    }
}

/// Creates `dir` and proves it writable, before any work is done.
pub fn prepare_dir(dir: &Path) -> io::Result<()> {
    fs::create_dir_all(dir)?;
    let probe = dir.join(".quell-write-test.tmp");
    fs::write(&probe, b"")?;
    fs::remove_file(probe)
}

/// `signals.csv`: t, y1..ym, g1..gm, e1..em, u1..um, eta1_1..etam_q.
pub fn write_signals(path: &Path, r: &SimResult) -> io::Result<()> {
    write_atomic(path, |w| {
        let (m, q) = (r.m, r.q);
        let mut header = vec!["t".to_string()];
        for name in ["y", "g", "e", "u"] {
            header.extend((1..=m).map(|i| format!("{name}{i}")));
        }
        for i in 1..=m {
            header.extend((1..=q).map(|j| format!("eta{i}_{j}")));
        }
        writeln!(w, "{}", header.join(","))?;
        for k in 0..r.len() {
            write!(w, "{}", r.t[k])?;
            for sig in [&r.y, &r.g, &r.e, &r.u] {
                for &v in &sig[k * m..(k + 1) * m] {
                    write!(w, ",{}", Num(v))?;
                }
            }
            for &v in &r.eta[k * m * q..(k + 1) * m * q] {
                write!(w, ",{}", Num(v))?;
            }
            writeln!(w)?;
        }
        Ok(())
    })
}

/// Writes a JSON value, pretty-printed.
pub fn write_json(path: &Path, value: &serde_json::Value) -> io::Result<()> {
    write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value)?;
        writeln!(w)
    })
}

/// A number as plain decimal where that is short, scientific otherwise; always round-trips.
struct Num(f64);

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || (1e-4..1e15).contains(&a) || !a.is_finite() {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}
