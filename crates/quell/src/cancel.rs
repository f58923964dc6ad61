//! Cooperative cancellation of long library calls that take no stop flag of their own (a design of
//! a large plant, whose pole placement iterates for seconds). A front end runs the call inside
//! [`with_stop`] with the flag its Ctrl-C handler sets; the long loops poll it on this thread and
//! return their `Interrupted` error ([`crate::DesignError::Interrupted`]).

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

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

#[cfg(test)]
mod tests {
    use super::*;

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
