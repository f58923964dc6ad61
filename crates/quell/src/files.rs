//! Writing output files atomically (the CLI's results, `quell export`'s and Python's
//! `quell.export`'s code and FMU): every file goes to a temporary name in its directory and is
//! renamed into place, so a reader never sees a half-written file.

use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use tempfile::NamedTempFile;

/// Writes a file atomically: `contents` fills a uniquely named temporary file beside `path`
/// (`.stem.XXXXXX.tmp.ext`, so two runs sharing a directory never collide), which is then renamed
/// to `path`. On error the temporary file is removed.
pub fn write_atomic(path: &Path, contents: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> io::Result<()> {
    stage(path, contents)?.persist(path).map_err(|e| naming(path, e.error))?;
    Ok(())
}

/// `e` with the name of the file it happened on (`summary.json: No space left on device`), so a
/// message about a directory of outputs says which one failed; its kind is kept.
fn naming(path: &Path, e: io::Error) -> io::Error {
    let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    io::Error::new(e.kind(), format!("{name}: {e}"))
}

/// Writes several files so that none is renamed into place unless every one was written: each
/// goes to its temporary name first, then all are renamed (a failed write leaves the old files
/// together, never a new one beside an old one).
pub fn write_atomic_all(files: &[(PathBuf, &[u8])]) -> io::Result<()> {
    let staged =
        files.iter().map(|(path, bytes)| stage(path, |w| w.write_all(bytes))).collect::<io::Result<Vec<_>>>()?;
    for (tmp, (path, _)) in staged.into_iter().zip(files) {
        tmp.persist(path).map_err(|e| naming(path, e.error))?;
    }
    Ok(())
}

/// The temporary file of [`write_atomic`], written and synced, not yet renamed. Its name keeps at
/// most 32 bytes of the stem, so a file name near the system's limit (255 bytes) still has one.
fn stage(path: &Path, contents: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> io::Result<NamedTempFile> {
    check_target(path)?;
    let mut stem = path.file_stem().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let cut = (0..=stem.len().min(32)).rev().find(|&k| stem.is_char_boundary(k)).unwrap_or(0);
    stem.truncate(cut);
    let ext = path.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let (prefix, suffix) = (format!(".{stem}."), format!(".tmp{ext}"));
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(&suffix);
    // tempfile creates 0600; ask for 0666 less the umask, the mode `File::create` gives an output.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut tmp = builder.tempfile_in(dir).map_err(|e| naming(path, e))?;
    let mut w = BufWriter::new(tmp.as_file_mut());
    contents(&mut w).map_err(|e| naming(path, e))?;
    w.into_inner().map_err(|e| e.into_error()).and_then(|f| f.sync_all()).map_err(|e| naming(path, e))?;
    Ok(tmp)
}

/// The renaming replaces whatever `path` names: refused (`InvalidInput`) unless that is a regular
/// file or nothing, so that a device (`/dev/full`), a FIFO, a socket, a symbolic link or a
/// directory is never replaced by a file. Public so that a caller can check its targets before
/// the work that produces them.
pub fn check_target(path: &Path) -> io::Result<()> {
    let Ok(meta) = std::fs::symlink_metadata(path) else { return Ok(()) };
    let kind = meta.file_type();
    let what = if kind.is_file() {
        return Ok(());
    } else if kind.is_dir() {
        "directory"
    } else if kind.is_symlink() {
        "symbolic link"
    } else {
        "device, FIFO or socket"
    };
    Err(io::Error::new(
        io::ErrorKind::InvalidInput,
        format!(
            "{} is a {what}, not a regular file: the result would replace it; give the path of a regular file or a new one",
            path.display()
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    #[test]
    #[cfg(unix)]
    fn a_target_that_is_not_a_regular_file_is_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("real.toml");
        fs::write(&file, "old").unwrap();
        let link = dir.path().join("link.toml");
        std::os::unix::fs::symlink(&file, &link).unwrap();
        let sub = dir.path().join("sub");
        fs::create_dir(&sub).unwrap();
        for (path, what) in [(&link, "symbolic link"), (&sub, "directory"), (&PathBuf::from("/dev/null"), "device")] {
            let e = write_atomic(path, |w| w.write_all(b"new")).unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
            assert!(e.to_string().contains(what), "{e}");
        }
        // The link and what it points to are as they were; /dev/null is still a device.
        assert!(fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        assert_eq!(fs::read_to_string(&file).unwrap(), "old");
        assert!(!fs::symlink_metadata("/dev/null").unwrap().file_type().is_file());
        write_atomic(&file, |w| w.write_all(b"new")).unwrap();
        assert_eq!(fs::read_to_string(&file).unwrap(), "new");
    }

    #[test]
    fn two_writers_of_one_file_do_not_collide() {
        // A second writer of the same path starts and finishes while the first is mid-write (two
        // runs sharing an output directory). With one fixed temporary name the second truncated and
        // renamed the first's file, and the first's rename then failed.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("signals.csv");
        write_atomic(&path, |w| {
            w.write_all(b"first,")?;
            write_atomic(&path, |w| w.write_all(b"second"))?;
            assert_eq!(fs::read_to_string(&path)?, "second");
            w.write_all(b"complete")
        })
        .unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "first,complete");
        let names: Vec<String> =
            fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        assert_eq!(names, ["signals.csv"], "temporary files left");
    }

    #[cfg(unix)]
    #[test]
    fn an_output_gets_the_mode_a_created_file_gets() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let (written, created) = (dir.path().join("runs.csv"), dir.path().join("created.csv"));
        write_atomic(&written, |w| w.write_all(b"run")).unwrap();
        fs::File::create(&created).unwrap();
        let mode = |p: &Path| fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&written), mode(&created), "umask applied as by File::create, not tempfile's 0600");
    }

    /// The error names its file (a full disk while writing summary.json read "writing DIR: No space
    /// left on device") and keeps its kind.
    #[test]
    fn a_failed_write_leaves_neither_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("summary.json");
        let e = write_atomic(&path, |w| {
            w.write_all(b"{")?;
            Err(io::Error::other("disk full"))
        });
        let e = e.unwrap_err();
        assert_eq!((e.kind(), e.to_string()), (io::ErrorKind::Other, "summary.json: disk full".into()));
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
