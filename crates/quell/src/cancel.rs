//! Cooperative cancellation of long library calls that take no stop flag of their own (a design of
//! a large plant, whose pole placement iterates for seconds). A front end runs the call inside
//! [`with_stop`] with the flag its Ctrl-C handler sets; the long loops poll it on this thread and
//! return their `Interrupted` error ([`crate::DesignError::Interrupted`]).

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::Arc;
use std::time::Duration;

thread_local! {
    static STOP: RefCell<Option<Arc<AtomicBool>>> = const { RefCell::new(None) };
}

/// The flag was set: the call was asked to stop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Interrupted;

/// Runs `f` on this thread with `stop` as its stop flag (the previous one, if any, is restored
/// afterwards, also when `f` panics).
pub fn with_stop<R>(stop: Arc<AtomicBool>, f: impl FnOnce() -> R) -> R {
    struct Restore(Option<Arc<AtomicBool>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let previous = self.0.take();
            STOP.with(|s| *s.borrow_mut() = previous);
        }
    }
    let _restore = Restore(STOP.with(|s| s.borrow_mut().replace(stop)));
    f()
}

/// `Err(Interrupted)` once the stop flag of the enclosing [`with_stop`] is set (never outside one).
pub fn check() -> Result<(), Interrupted> {
    let stopped = STOP.with(|s| s.borrow().as_ref().is_some_and(|f| f.load(Ordering::Relaxed)));
    if stopped {
        Err(Interrupted)
    } else {
        Ok(())
    }
}

/// The stop flag of the enclosing [`with_stop`], if any.
pub(crate) fn current() -> Option<Arc<AtomicBool>> {
    STOP.with(|s| s.borrow().clone())
}

/// How often [`detached`] looks at the stop flag while it waits.
const WAIT_POLL: Duration = Duration::from_millis(10);

/// Runs `f` on a worker thread under `stop` (its own polls see the flag) and waits for it,
/// looking at the flag every [`WAIT_POLL`]. Once the flag is set it returns `Err(Interrupted)`
/// at once and leaves the worker to finish alone: the worker stops at its next poll, and what it
/// computed is dropped, shared with nobody. For calls with phases that cannot poll (a faer
/// eigendecomposition of a 500 × 500 matrix runs for a second); a panic in `f` is resumed here.
pub(crate) fn detached<R: Send + 'static>(
    stop: Arc<AtomicBool>,
    f: impl FnOnce() -> R + Send + 'static,
) -> Result<R, Interrupted> {
    let (send, receive) = mpsc::channel();
    let flag = stop.clone();
    let worker = std::thread::spawn(move || {
        // The receiver is gone when the caller was interrupted: nothing to deliver.
        let _ = send.send(with_stop(flag, f));
    });
    loop {
        match receive.recv_timeout(WAIT_POLL) {
            Ok(r) => return Ok(r),
            Err(RecvTimeoutError::Disconnected) => match worker.join() {
                Err(panic) => std::panic::resume_unwind(panic),
                Ok(()) => unreachable!("the worker sends its result before it ends"),
            },
            Err(RecvTimeoutError::Timeout) if stop.load(Ordering::Relaxed) => return Err(Interrupted),
            Err(RecvTimeoutError::Timeout) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detached_returns_at_once_when_stopped_and_the_result_otherwise() {
        let stop = Arc::new(AtomicBool::new(false));
        assert_eq!(detached(stop.clone(), || 6 * 7), Ok(42));
        // The worker waits for a message sent only after `detached` has returned: were it waited
        // for, it would give up after 30 s and `detached` would return Ok.
        let (send, receive) = mpsc::channel::<()>();
        let setter = {
            let stop = stop.clone();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_millis(50));
                stop.store(true, Ordering::SeqCst);
            })
        };
        let r = detached(stop.clone(), move || receive.recv_timeout(Duration::from_secs(30)).is_ok());
        assert_eq!(r, Err(Interrupted));
        let _ = send.send(());
        setter.join().unwrap();
        // The worker runs under the flag: its own polls see it.
        assert_eq!(detached(Arc::new(AtomicBool::new(false)), check), Ok(Ok(())));
        let set = Arc::new(AtomicBool::new(true));
        assert!(matches!(detached(set, || 1), Ok(1) | Err(Interrupted)));
    }

    #[test]
    #[should_panic(expected = "worker panicked")]
    fn a_panic_in_the_worker_is_resumed() {
        let _ = detached(Arc::new(AtomicBool::new(false)), || panic!("worker panicked"));
    }

    #[test]
    fn the_flag_is_seen_inside_with_stop_only_and_restored() {
        let flag = Arc::new(AtomicBool::new(true));
        assert_eq!(check(), Ok(()));
        assert_eq!(with_stop(flag.clone(), check), Err(Interrupted));
        let inner = Arc::new(AtomicBool::new(false));
        with_stop(flag, || {
            assert_eq!(with_stop(inner, check), Ok(()));
            assert_eq!(check(), Err(Interrupted));
        });
        assert_eq!(check(), Ok(()));
    }
}
