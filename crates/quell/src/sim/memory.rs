//! The memory that study runs under way hold together. Each run's own limits bound it (its record,
//! [`crate::settings::MAX_RECORD_BYTES`], and its delay history, [`super::MAX_HISTORY_BYTES`]), but
//! `jobs` runs at once would multiply them. So a study run reserves its bound ([`super::Run::memory_bound`])
//! from [`RUNS`] before it starts and gives it back when its row is made: runs wait for memory
//! rather than take the machine's, and a run's outcome never depends on how many ran beside it.

use std::sync::{Condvar, Mutex, PoisonError};
use std::time::Duration;

/// Most bytes the study runs of a process reserve together (4 GiB): one run at both of its own
/// limits (3 GiB) fits, and the paper's Monte Carlo runs (~37 MB each) run a hundred at once.
pub const RUNS_MEMORY_BYTES: usize = 4 << 30;

/// How often a run waiting for memory checks its stop signal.
const STOP_CHECK: Duration = Duration::from_millis(50);

/// A budget of bytes that threads reserve and give back ([`Gate::hold`]).
pub(crate) struct Gate {
    capacity: usize,
    held: Mutex<usize>,
    freed: Condvar,
}

/// The study runs' budget ([`RUNS_MEMORY_BYTES`]).
pub(crate) static RUNS: Gate = Gate::new(RUNS_MEMORY_BYTES);

/// Bytes reserved from a [`Gate`], given back when dropped.
pub(crate) struct Held<'a> {
    gate: &'a Gate,
    bytes: usize,
}

impl Gate {
    pub(crate) const fn new(capacity: usize) -> Gate {
        Gate { capacity, held: Mutex::new(0), freed: Condvar::new() }
    }

    /// Waits until `bytes` fit beside what others hold, then holds them until the [`Held`] is
    /// dropped. More than the capacity is held as the whole capacity: such a run waits for all others
    /// and runs alone. `None` when `stop` returns true while waiting.
    pub(crate) fn hold(&self, bytes: usize, stop: &dyn Fn() -> bool) -> Option<Held<'_>> {
        let bytes = bytes.min(self.capacity);
        let mut held = self.held.lock().unwrap_or_else(PoisonError::into_inner);
        while *held + bytes > self.capacity {
            if stop() {
                return None;
            }
            held = self.freed.wait_timeout(held, STOP_CHECK).unwrap_or_else(PoisonError::into_inner).0;
        }
        *held += bytes;
        Some(Held { gate: self, bytes })
    }

    /// Bytes held now.
    #[cfg(test)]
    pub(crate) fn held(&self) -> usize {
        *self.held.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

impl Drop for Held<'_> {
    fn drop(&mut self) {
        *self.gate.held.lock().unwrap_or_else(PoisonError::into_inner) -= self.bytes;
        self.gate.freed.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

    #[test]
    fn holders_never_exceed_the_capacity_and_an_oversized_one_runs_alone() {
        // Eight threads hold 40, 40, … and one 250 of a gate of 100: at most two of 40 at once, the
        // 250 alone (held as 100); each records what the gate held while it held its share.
        let gate = Gate::new(100);
        let (most, alone) = (AtomicUsize::new(0), AtomicBool::new(true));
        std::thread::scope(|s| {
            for k in 0..8 {
                let (gate, most, alone) = (&gate, &most, &alone);
                s.spawn(move || {
                    let bytes = if k == 3 { 250 } else { 40 };
                    let held = gate.hold(bytes, &|| false).expect("no stop");
                    let now = gate.held();
                    most.fetch_max(now, Ordering::Relaxed);
                    if k == 3 && now != 100 {
                        alone.store(false, Ordering::Relaxed);
                    }
                    std::thread::sleep(Duration::from_millis(20));
                    drop(held);
                });
            }
        });
        assert!(most.load(Ordering::Relaxed) <= 100, "held {}", most.load(Ordering::Relaxed));
        assert!(alone.load(Ordering::Relaxed), "the oversized holder shared the gate");
        assert_eq!(gate.held(), 0, "everything given back");
    }

    #[test]
    fn a_stop_ends_the_wait() {
        let gate = Gate::new(10);
        let _first = gate.hold(10, &|| false).expect("free");
        let started = std::time::Instant::now();
        assert!(gate.hold(1, &|| started.elapsed() > Duration::from_millis(120)).is_none());
        assert_eq!(gate.held(), 10);
    }
}
