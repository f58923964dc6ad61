//! Ctrl-C during a long library call that takes no progress callback (a design of a large plant):
//! the call runs on a worker thread with the GIL released under a stop flag
//! ([`quell::cancel::with_stop`]) while this thread checks Python's signals every
//! [`SIGNAL_CHECK`]; a KeyboardInterrupt sets the flag, waits for the call to notice it (at its next
//! poll, within a fraction of a second) and is raised.
//!
//! Python runs signal handlers in the main thread only, so a call made from a worker thread (a
//! `ThreadPoolExecutor` of simulations) never saw Ctrl-C and ran to its end. The package hooks
//! SIGINT on import (`quell/__init__.py`: it counts the Ctrl-C through [`note_interrupt`], then
//! calls Python's own handler), and every call watches that count as well ([`CtrlC`]).

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use pyo3::prelude::*;

/// Ctrl-Cs the package's SIGINT hook has seen.
static INTERRUPTS: AtomicU64 = AtomicU64::new(0);

/// Counts a Ctrl-C: every call under way, in any thread, raises KeyboardInterrupt at its next check.
#[pyfunction]
#[pyo3(name = "_note_interrupt")]
pub fn note_interrupt() {
    INTERRUPTS.fetch_add(1, Ordering::Relaxed);
}

/// A call's watch for Ctrl-C: Python's pending signals (in the main thread) and the Ctrl-Cs the
/// package's hook counted since the call began (in any thread).
pub struct CtrlC {
    since: u64,
}

impl CtrlC {
    pub fn new() -> CtrlC {
        CtrlC { since: INTERRUPTS.load(Ordering::Relaxed) }
    }

    /// The KeyboardInterrupt to raise, if Ctrl-C came.
    pub fn check(&self) -> PyResult<()> {
        Python::attach(|py| py.check_signals())?;
        if INTERRUPTS.load(Ordering::Relaxed) != self.since {
            return Err(pyo3::exceptions::PyKeyboardInterrupt::new_err("Ctrl-C (in another thread)"));
        }
        Ok(())
    }
}

/// How often the waiting thread runs Python's signal handlers.
pub const SIGNAL_CHECK: Duration = Duration::from_millis(50);

/// `work()` with Ctrl-C raising KeyboardInterrupt during it (see the module docs).
pub fn interruptible<R: Send>(py: Python<'_>, work: impl FnOnce() -> R + Send) -> PyResult<R> {
    interruptible_with(py, |stop| quell::cancel::with_stop(stop, work))
}

/// `work(stop)` on a worker thread with the GIL released, while this thread runs Python's signal
/// handlers every [`SIGNAL_CHECK`] until it ends (returning as soon as it does); a
/// KeyboardInterrupt sets `stop`, waits for `work` to notice it and is raised. For calls that
/// take their stop flag as an argument (a sweep's `SweepOptions`).
pub fn interruptible_with<R: Send>(py: Python<'_>, work: impl FnOnce(Arc<AtomicBool>) -> R + Send) -> PyResult<R> {
    match interruptible_keeping(py, work)? {
        (_, Some(e)) => Err(e),
        (result, None) => Ok(result),
    }
}

/// [`interruptible_with`] that keeps what `work` returned when stopped (a tuning's points so far),
/// beside the KeyboardInterrupt to raise.
pub fn interruptible_keeping<R: Send>(
    py: Python<'_>,
    work: impl FnOnce(Arc<AtomicBool>) -> R + Send,
) -> PyResult<(R, Option<PyErr>)> {
    interruptible_since(py, &CtrlC::new(), work)
}

/// [`interruptible_keeping`] that also answers the Ctrl-Cs `ctrl_c` has seen since it was made (a
/// call that waited its turn before starting, [`crate::study`]'s shared iterator).
pub fn interruptible_since<R: Send>(
    py: Python<'_>,
    ctrl_c: &CtrlC,
    work: impl FnOnce(Arc<AtomicBool>) -> R + Send,
) -> PyResult<(R, Option<PyErr>)> {
    let stop = Arc::new(AtomicBool::new(false));
    let mut interrupt = None;
    let result = py.detach(|| {
        std::thread::scope(|scope| {
            let flag = stop.clone();
            // The worker says when it is done: a sleep of SIGNAL_CHECK before looking had made
            // every call last 50 ms at least (a sweep's specs, 50 ms each; helper tryout).
            let (done, finished) = std::sync::mpsc::channel::<()>();
            let worker = scope.spawn(move || {
                let r = work(flag);
                let _ = done.send(());
                r
            });
            while let Err(std::sync::mpsc::RecvTimeoutError::Timeout) = finished.recv_timeout(SIGNAL_CHECK) {
                if interrupt.is_none() {
                    if let Err(e) = ctrl_c.check() {
                        stop.store(true, Ordering::Relaxed);
                        interrupt = Some(e);
                    }
                }
            }
            worker.join()
        })
    });
    match result {
        Ok(r) => Ok((r, interrupt)),
        Err(_) => {
            Err(interrupt
                .unwrap_or_else(|| pyo3::exceptions::PyRuntimeError::new_err("the call's worker thread panicked")))
        }
    }
}
