//! Ctrl-C (SIGINT), and SIGTERM and SIGHUP alike (a batch system's time limit, a closed terminal),
//! for the long commands. The first signal asks the work to stop and the results so far to be
//! written; a second one before writing has begun quits at once with nothing written; once writing
//! has begun further signals wait for it (the first is answered with a note), so no file is cut
//! short and no temporary is left.

use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::Arc;

/// Phases of a command, for the handler.
const RUNNING: u8 = 0;
const INTERRUPTED: u8 = 1;
const QUITTING: u8 = 2;
const WRITING: u8 = 3;
/// Writing, and the user told that a signal now waits for it.
const WRITING_TOLD: u8 = 4;

/// The installed handler's state.
pub struct Interrupt {
    phase: Arc<AtomicU8>,
    stop: Arc<AtomicBool>,
}

impl Interrupt {
    /// Installs the handler; `twice` is the message of a second signal before writing began.
    pub fn install(twice: &'static str) -> Self {
        let (phase, stop) = (Arc::new(AtomicU8::new(RUNNING)), Arc::new(AtomicBool::new(false)));
        let (handler_phase, handler_stop) = (phase.clone(), stop.clone());
        let _ = keeping_ignored_sigint(|| {
            ctrlc::set_handler(move || {
                handler_stop.store(true, Ordering::SeqCst);
                match on_signal(&handler_phase) {
                    Some(Said::Quit) => {
                        eprintln!("error: {twice}");
                        std::process::exit(1);
                    }
                    // A large signals.csv takes seconds: say why the signal seems to do nothing.
                    Some(Said::Writing) => eprintln!(
                        "note: writing the results; stopping now would leave them incomplete, so quell finishes writing first"
                    ),
                    None => {}
                }
            })
        });
        Interrupt { phase, stop }
    }

    /// Installs a handler for a command with nothing to write: the first signal quits with
    /// `message` and exit status 1 (a result that is not complete), not the shell's 130.
    pub fn quit_with(message: &'static str) {
        let _ = keeping_ignored_sigint(|| {
            ctrlc::set_handler(move || {
                eprintln!("error: {message}");
                std::process::exit(1);
            })
        });
    }

    /// True once a signal asked the work to stop.
    pub fn interrupted(&self) -> bool {
        self.stop.load(Ordering::SeqCst)
    }

    /// The flag a signal sets (what `quell::study::sweep` polls).
    pub fn stop_flag(&self) -> &AtomicBool {
        &self.stop
    }

    /// The same flag, shared: what [`quell::cancel::with_stop`] takes.
    pub fn shared_flag(&self) -> Arc<AtomicBool> {
        self.stop.clone()
    }

    /// From here on signals are ignored until the files are written (unless a second one is
    /// already quitting the process).
    pub fn start_writing(&self) {
        if self.phase.swap(WRITING, Ordering::SeqCst) == QUITTING {
            loop {
                std::thread::park();
            }
        }
    }
}

/// What a signal makes the handler say.
#[derive(Debug, PartialEq)]
enum Said {
    /// A second signal before writing began: quit with nothing written.
    Quit,
    /// The first signal while writing: it waits for the files.
    Writing,
}

/// Moves `phase` on for a signal: the first asks the work to stop (nothing said), a second before
/// writing quits, the first during writing is answered once, later ones silently.
fn on_signal(phase: &AtomicU8) -> Option<Said> {
    let to = |from, to| phase.compare_exchange(from, to, Ordering::SeqCst, Ordering::SeqCst).is_ok();
    if to(RUNNING, INTERRUPTED) {
        None
    } else if to(INTERRUPTED, QUITTING) {
        Some(Said::Quit)
    } else if to(WRITING, WRITING_TOLD) {
        Some(Said::Writing)
    } else {
        None
    }
}

/// Ignores SIGXFSZ, so that a write past the file-size limit (`ulimit -f`) fails as a full disk
/// does, with "File too large" and exit status 1, keeping the earlier results, instead of killing
/// quell mid-write with no word (as Python, which ignores it too, already did).
pub fn ignore_file_size_signal() {
    // SAFETY: sets a disposition, no handler code.
    #[cfg(unix)]
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
}

/// Runs `install` (which handles SIGINT, SIGTERM and SIGHUP) and, where SIGINT was ignored when it
/// ran, ignores it again: a shell without job control starts `quell sweep … &` with SIGINT ignored,
/// so that Ctrl-C at the terminal spares background work, and the handler took that back (POSIX
/// keeps an ignored signal ignored across exec for that reason). SIGTERM and SIGHUP stay handled.
fn keeping_ignored_sigint<T>(install: impl FnOnce() -> T) -> T {
    #[cfg(unix)]
    {
        // SAFETY: sigaction with a null new action only reads the disposition into `old`, a
        // zeroed plain C struct; signal(SIGINT, SIG_IGN) sets a disposition, no handler code.
        let ignored = unsafe {
            let mut old: libc::sigaction = std::mem::zeroed();
            libc::sigaction(libc::SIGINT, std::ptr::null(), &mut old) == 0 && old.sa_sigaction == libc::SIG_IGN
        };
        let installed = install();
        if ignored {
            unsafe {
                libc::signal(libc::SIGINT, libc::SIG_IGN);
            }
        }
        installed
    }
    #[cfg(not(unix))]
    install()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signals_move_the_phases_on() {
        let phase = AtomicU8::new(RUNNING);
        assert_eq!(on_signal(&phase), None);
        assert_eq!(on_signal(&phase), Some(Said::Quit));
        assert_eq!(on_signal(&phase), None, "quitting already");
        // Once writing has begun, the first signal is answered and the next ones are not.
        let phase = AtomicU8::new(INTERRUPTED);
        phase.store(WRITING, Ordering::SeqCst);
        assert_eq!(on_signal(&phase), Some(Said::Writing));
        assert_eq!(on_signal(&phase), None);
        assert_eq!(phase.load(Ordering::SeqCst), WRITING_TOLD);
    }
}
