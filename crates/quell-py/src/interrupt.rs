//! Ctrl-C during a long library call that takes no progress callback (a design of a large plant):
//! the call runs on a worker thread with the GIL released under a stop flag
//! ([`quell::cancel::with_stop`]) while this thread checks Python's signals every
//! [`SIGNAL_CHECK`]; a KeyboardInterrupt sets the flag, waits for the call to notice it (at its next
//! poll, within a fraction of a second) and is raised.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use pyo3::prelude::*;

/// How often the waiting thread runs Python's signal handlers.
const SIGNAL_CHECK: Duration = Duration::from_millis(50);

/// `work()` with Ctrl-C raising KeyboardInterrupt during it (see the module docs).
pub fn interruptible<R: Send>(py: Python<'_>, work: impl FnOnce() -> R + Send) -> PyResult<R> {
    interruptible_with(py, |stop| quell::cancel::with_stop(stop, work))
}

/// `work(stop)` on a worker thread with the GIL released, while this thread runs Python's signal
/// handlers every [`SIGNAL_CHECK`]; a KeyboardInterrupt sets `stop`, waits for `work` to notice it
/// and is raised. For calls that take their stop flag as an argument (a sweep's `SweepOptions`).
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
    let stop = Arc::new(AtomicBool::new(false));
    let mut interrupt = None;
    let result = py.detach(|| {
        std::thread::scope(|scope| {
            let flag = stop.clone();
            let worker = scope.spawn(move || work(flag));
            while !worker.is_finished() {
                std::thread::sleep(SIGNAL_CHECK);
                if interrupt.is_none() {
                    if let Err(e) = Python::attach(|py| py.check_signals()) {
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
