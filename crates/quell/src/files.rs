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
    Staged::write(path, contents)?.persist()
}

/// A file written to its temporary name ([`write_atomic`]) and not yet renamed into place: a
/// caller that writes several files renames them once every one is written ([`Staged::persist`]),
/// or drops them all (each temporary file is then removed), so that a failed write leaves the old
/// files together, never a new one beside an old one.
#[derive(Debug)]
pub struct Staged {
    tmp: NamedTempFile,
    path: PathBuf,
}

impl Staged {
    /// Writes `contents` to the temporary name of `path`.
    pub fn write(path: &Path, contents: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> io::Result<Staged> {
        Ok(Staged { tmp: stage(path, contents)?, path: path.to_path_buf() })
    }

    /// Renames the file into place.
    pub fn persist(self) -> io::Result<()> {
        self.tmp.persist(&self.path).map_err(|e| naming(&self.path, e.error))?;
        Ok(())
    }

    /// The path it is renamed to.
    pub fn path(&self) -> &Path {
        &self.path
    }
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
    let staged = files
        .iter()
        .map(|(path, bytes)| Staged::write(path, |w| w.write_all(bytes)))
        .collect::<io::Result<Vec<_>>>()?;
    staged.into_iter().try_for_each(Staged::persist)
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
    remove_stale(dir, |name| {
        name.len() == prefix.len() + 6 + suffix.len() && name.starts_with(&prefix) && name.ends_with(&suffix)
    });
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(&suffix);
    // tempfile creates 0600; ask for 0666 less the umask, the mode `File::create` gives an output.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut tmp = builder.tempfile_in(dir).map_err(|e| naming(path, e))?;
    // Held until the file is renamed or removed: a temporary file nobody holds is stale.
    tmp.as_file().lock().map_err(|e| naming(path, e))?;
    let mut w = BufWriter::new(tmp.as_file_mut());
    contents(&mut w).map_err(|e| naming(path, e))?;
    w.into_inner().map_err(|e| e.into_error()).and_then(|f| f.sync_all()).map_err(|e| naming(path, e))?;
    Ok(tmp)
}

/// A temporary file older than this and not locked was left by a process that was killed.
const STALE_AFTER: std::time::Duration = std::time::Duration::from_secs(2);

/// Removes the temporary files in `dir` whose names `ours` claims that a killed process left:
/// older than [`STALE_AFTER`] and locked by no one. A run killed while writing a 460 MB
/// signals.csv left it behind, and every later kill added one. Best effort: what cannot be read or
/// removed stays.
fn remove_stale(dir: &Path, ours: impl Fn(&str) -> bool) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        let ours = ours(name);
        // A regular file only, not followed through a link: opening a pipe of that name to test its
        // lock blocked run, export and sweep for good.
        let file = || entry.file_type().is_ok_and(|t| t.is_file());
        let old =
            || entry.metadata().and_then(|m| m.modified()).is_ok_and(|t| t.elapsed().is_ok_and(|a| a > STALE_AFTER));
        if ours && file() && old() {
            // Unlocked: its writer is gone (a live writer holds the lock until the rename).
            if std::fs::File::open(entry.path()).is_ok_and(|f| f.try_lock().is_ok()) {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
}

/// An exclusive lock on an output directory, held while a command writes its files there;
/// released when dropped (or when the process ends, however it ends).
#[derive(Debug)]
pub struct DirLock(#[allow(dead_code)] std::fs::File);

/// Locks the existing directory `dir` for writing, so that two commands writing the same
/// directory do not mix their files (two runs into one output directory left a signals.csv of one
/// beside a summary.json of the other in 7 of 20 trials; two exports, a header of one beside the
/// other's source). `Ok(Some)` once held; an error of kind `WouldBlock` while another process
/// holds it; `Ok(None)` where the system cannot lock a directory, whose files are then written
/// unlocked, as they were. An advisory lock (`flock` on the directory itself): no file is left.
pub fn lock_dir(dir: &Path) -> io::Result<Option<DirLock>> {
    let Ok(file) = std::fs::File::open(dir) else { return Ok(None) };
    match file.try_lock() {
        Ok(()) => Ok(Some(DirLock(file))),
        Err(std::fs::TryLockError::WouldBlock) => Err(io::Error::new(
            io::ErrorKind::WouldBlock,
            format!(
                "another command is writing in {} now; wait for it to finish or choose another directory",
                dir.display()
            ),
        )),
        Err(std::fs::TryLockError::Error(_)) => Ok(None),
    }
}

/// Removes every temporary file of [`write_atomic`] (`.stem.XXXXXX.tmp.ext`) in `dir` that a
/// killed process left (older than 2 s, locked by no one), whatever file it was
/// meant to become: a write removes only its own name's, so a run killed while drawing a third
/// channel's figure, followed by runs of two channels or without figures, had kept it for good.
pub fn remove_stale_temporaries(dir: &Path) {
    remove_stale(dir, is_temporary);
}

/// Whether `name` has the form of [`stage`]'s temporary files: `.`, a stem, `.`, six letters or
/// digits, `.tmp`, then nothing or one extension.
fn is_temporary(name: &str) -> bool {
    let Some((head, tail)) = name.strip_prefix('.').and_then(|rest| rest.rsplit_once(".tmp")) else {
        return false;
    };
    let extension = tail.is_empty() || tail.strip_prefix('.').is_some_and(|e| !e.is_empty() && !e.contains('.'));
    let random = head.len() >= 7
        && head.as_bytes()[head.len() - 7] == b'.'
        && head[head.len() - 6..].bytes().all(|b| b.is_ascii_alphanumeric());
    extension && random
}

/// Opens an earlier output at `path` for reading, refused (`InvalidInput`) unless it is a regular
/// file (followed through links): opening a pipe waits for a writer, and a device such as
/// /dev/zero never ends (a sweep's runs.csv replaced by either had hung its resumption or taken
/// 9 GB). Checked before opening (opening a device can act on it: a terminal, a tape), then opened
/// without waiting (`O_NONBLOCK`, which a regular file's reads ignore) and checked again, so a
/// pipe swapped in between cannot block either.
pub fn open_regular(path: &Path) -> io::Result<std::fs::File> {
    let regular = |meta: std::fs::Metadata| {
        if meta.is_file() {
            return Ok(());
        }
        let what = if meta.is_dir() { "directory" } else { "device, FIFO or socket" };
        Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("is a {what}, not a regular file as the command that wrote it leaves"),
        ))
    };
    regular(std::fs::metadata(path)?)?;
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(&mut options, libc::O_NONBLOCK);
    let file = options.open(path)?;
    regular(file.metadata()?)?;
    Ok(file)
}

/// An earlier output's text ([`open_regular`]). Not capped: a sweep of ten million runs writes
/// a runs.csv of gigabytes, which resuming or merging it reads back.
pub fn read_regular(path: &Path) -> io::Result<String> {
    io::read_to_string(open_regular(path)?)
}

/// [`read_regular`] of a text of lines, refused (`InvalidData`, naming the line) at its first line
/// longer than `max_line` bytes (its line break included) or beyond `max_lines` lines, before the rest is read: a damaged
/// runs.csv (2 GB of NULs on one line) had taken 4.2 GB to be refused.
pub fn read_lines_within(path: &Path, max_line: usize, max_lines: usize) -> io::Result<String> {
    use io::{BufRead, Read};
    let mut reader = io::BufReader::new(open_regular(path)?);
    let (mut text, mut line) = (String::new(), Vec::new());
    let limit = u64::try_from(max_line).unwrap_or(u64::MAX).saturating_add(1);
    for n in 1.. {
        line.clear();
        if (&mut reader).take(limit).read_until(b'\n', &mut line)? == 0 {
            break;
        }
        let bad = |what: String| Err(io::Error::new(io::ErrorKind::InvalidData, format!("line {n}: {what}")));
        if line.len() > max_line {
            return bad(format!("longer than {max_line} bytes, the most a line of this file can hold"));
        }
        if n > max_lines {
            return bad(format!("more than the {max_lines} lines this file can hold"));
        }
        // Checked whole, so that a character cut by the limit is not taken for bad text.
        match std::str::from_utf8(&line) {
            Ok(l) => text.push_str(l),
            Err(e) => return bad(format!("not UTF-8 text ({e})")),
        }
    }
    Ok(text)
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

/// An output directory must be a directory or nothing yet (created then): refused
/// (`InvalidInput`) when `dir` names a regular file, a device, a FIFO or a socket, so that the
/// message says so rather than the system's "File exists". A symbolic link to a directory is one.
pub fn check_dir(dir: &Path) -> io::Result<()> {
    let refuse = |why: String| Err(io::Error::new(io::ErrorKind::InvalidInput, why));
    match std::fs::metadata(dir) {
        Ok(meta) if !meta.is_dir() => {
            let what = if meta.is_file() { "regular file" } else { "device, FIFO or socket" };
            refuse(format!("{} is a {what}, not a directory", dir.display()))
        }
        // A link to nowhere: creating the directory fails with "File exists", which says nothing.
        // A loop of links (ELOOP) is not a missing directory to create.
        Err(e) if dir.is_symlink() => {
            let target = std::fs::read_link(dir).map_or_else(|_| "?".into(), |t| t.display().to_string());
            if is_link_loop(&e) {
                return refuse(format!(
                    "{} is a symbolic link to {target} that leads back to itself (a loop of links); give a directory",
                    dir.display()
                ));
            }
            refuse(format!(
                "{} is a symbolic link to {target}, which does not exist (create that directory)",
                dir.display()
            ))
        }
        _ => Ok(()),
    }
}

/// Whether `e` is ELOOP, "too many levels of symbolic links".
fn is_link_loop(e: &io::Error) -> bool {
    #[cfg(unix)]
    let eloop = Some(libc::ELOOP);
    #[cfg(not(unix))]
    let eloop = None;
    eloop.is_some() && e.raw_os_error() == eloop
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    /// Lines within their bounds are read whole; the first line too long, or one line too many, is
    /// refused naming it, having read no more than that line.
    #[test]
    fn a_text_of_lines_is_refused_at_its_first_line_out_of_bounds() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("runs.csv");
        fs::write(&path, "head\nab\ncde\n").unwrap();
        assert_eq!(read_lines_within(&path, 5, 3).unwrap(), "head\nab\ncde\n");
        let e = read_lines_within(&path, 5, 2).unwrap_err();
        assert_eq!(e.to_string(), "line 3: more than the 2 lines this file can hold");
        fs::write(&path, format!("head\n{}\n", "\0".repeat(1 << 20))).unwrap();
        let e = read_lines_within(&path, 5, 3).unwrap_err();
        assert_eq!(
            (e.kind(), e.to_string()),
            (io::ErrorKind::InvalidData, "line 2: longer than 5 bytes, the most a line of this file can hold".into())
        );
        // A character the limit cuts in two: too long, not bad text (diff review).
        fs::write(&path, format!("head\n{}\n", "yé".repeat(40))).unwrap();
        let e = read_lines_within(&path, 6, 3).unwrap_err();
        assert_eq!(e.to_string(), "line 2: longer than 6 bytes, the most a line of this file can hold");
    }

    /// A loop of links is named as one (it had been "a symbolic link to b, which does not exist
    /// (create that directory)"; helper tryout, 2026-12-06).
    #[test]
    #[cfg(unix)]
    fn a_loop_of_links_is_named_as_one() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        std::os::unix::fs::symlink(&b, &a).unwrap();
        std::os::unix::fs::symlink(&a, &b).unwrap();
        let e = check_dir(&a).unwrap_err().to_string();
        assert!(e.ends_with("that leads back to itself (a loop of links); give a directory"), "{e}");
    }

    #[test]
    #[cfg(unix)]
    fn a_directory_behind_a_dangling_link_is_named_as_missing() {
        let dir = tempfile::tempdir().unwrap();
        let link = dir.path().join("dangle");
        std::os::unix::fs::symlink("nowhere/x", &link).unwrap();
        let e = check_dir(&link).unwrap_err().to_string();
        assert!(
            e.ends_with("dangle is a symbolic link to nowhere/x, which does not exist (create that directory)"),
            "{e}"
        );
        fs::create_dir_all(dir.path().join("nowhere/x")).unwrap();
        assert!(check_dir(&link).is_ok());
    }

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
    #[cfg(unix)]
    fn an_earlier_output_that_is_a_pipe_is_refused_without_waiting_for_a_writer() {
        // A pipe is refused without waiting for its writer, which never comes (open_regular
        // checks, opens without waiting and checks again, so that a pipe swapped in between
        // cannot block either). On another thread, so that a regression fails after ten seconds
        // instead of hanging the suite.
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("runs.csv");
        let name = std::ffi::CString::new(fifo.as_os_str().as_encoded_bytes()).unwrap();
        assert_eq!(unsafe { libc::mkfifo(name.as_ptr(), 0o600) }, 0);
        let (sent, received) = std::sync::mpsc::channel();
        std::thread::spawn(move || sent.send(read_regular(&fifo).map_err(|e| (e.kind(), e.to_string()))));
        let (kind, e) = received.recv_timeout(std::time::Duration::from_secs(10)).expect("waited").unwrap_err();
        assert_eq!(kind, io::ErrorKind::InvalidInput);
        assert!(e.contains("FIFO"), "{e}");
        fs::write(dir.path().join("summary.json"), "{}").unwrap();
        assert_eq!(read_regular(&dir.path().join("summary.json")).unwrap(), "{}");
    }

    #[test]
    fn a_killed_writers_temporary_file_is_removed_by_the_next_write() {
        // A run killed mid-write leaves its temporary file; the next write of that name removes it
        // when it is older than STALE_AFTER and unlocked, and leaves a live writer's (locked), a
        // fresh one's and other files.
        let dir = tempfile::tempdir().unwrap();
        let at = |name: &str| dir.path().join(name);
        let old = std::time::SystemTime::now() - 2 * STALE_AFTER;
        for name in [
            ".signals.AbC123.tmp.csv",
            ".signals.live00.tmp.csv",
            ".signals.toolong7.tmp.csv",
            ".design.AbC123.tmp.json",
        ] {
            fs::write(at(name), "partial").unwrap();
            fs::File::options().write(true).open(at(name)).unwrap().set_modified(old).unwrap();
        }
        fs::write(at(".signals.fresh0.tmp.csv"), "partial").unwrap();
        let live = fs::File::open(at(".signals.live00.tmp.csv")).unwrap();
        live.lock().unwrap();
        write_atomic(&at("signals.csv"), |w| w.write_all(b"t,y1")).unwrap();
        let mut left: Vec<String> =
            fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
        left.sort();
        assert_eq!(
            left,
            [
                ".design.AbC123.tmp.json",
                ".signals.fresh0.tmp.csv",
                ".signals.live00.tmp.csv",
                ".signals.toolong7.tmp.csv",
                "signals.csv"
            ]
        );
    }

    /// A pipe (or a link) with a temporary file's name is not opened to test its lock, which
    /// blocked until a writer came; it is left where it is.
    #[cfg(unix)]
    #[test]
    fn a_pipe_named_as_a_stale_temporary_is_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join(".signals.Ab12Cd.tmp.csv");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
        assert!(made.success());
        let aged = std::process::Command::new("touch").args(["-h", "-d", "1 hour ago"]).arg(&fifo).status().unwrap();
        assert!(aged.success());
        let path = dir.path().to_path_buf();
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            write_atomic(&path.join("signals.csv"), |w| w.write_all(b"t,y1")).unwrap();
            tx.send(()).unwrap();
        });
        rx.recv_timeout(std::time::Duration::from_secs(20)).expect("writing beside a pipe blocked");
        assert!(fifo.exists());
    }

    #[test]
    fn every_stale_temporary_file_is_removed_whatever_it_was_meant_to_become() {
        // A 3-channel run killed while drawing, then a 2-channel one: channel3's temporary figure
        // is no name the new run writes. Left: a live writer's (locked), a fresh one, and files of
        // other forms (a user's hidden file, a name with ".tmp" elsewhere).
        let dir = tempfile::tempdir().unwrap();
        let at = |name: &str| dir.path().join(name);
        let old = std::time::SystemTime::now() - 2 * STALE_AFTER;
        let names = [
            ".channel3.F0BUOg.tmp.png",
            ".quell-write-test.Ab12Cd.tmp",
            ".signals.live00.tmp.csv",
            ".hidden",
            "notes.tmp.txt",
            ".x.ABCDE.tmp.csv",
        ];
        for name in names {
            fs::write(at(name), "partial").unwrap();
            fs::File::options().write(true).open(at(name)).unwrap().set_modified(old).unwrap();
        }
        fs::write(at(".summary.fresh0.tmp.json"), "partial").unwrap();
        let live = fs::File::open(at(".signals.live00.tmp.csv")).unwrap();
        live.lock().unwrap();
        remove_stale_temporaries(dir.path());
        let mut left: Vec<String> =
            fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
        left.sort();
        assert_eq!(
            left,
            [".hidden", ".signals.live00.tmp.csv", ".summary.fresh0.tmp.json", ".x.ABCDE.tmp.csv", "notes.tmp.txt"]
        );
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
