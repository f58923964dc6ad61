//! The memory that study runs under way hold together. Each run's own limits bound it (its record,
//! [`crate::settings::MAX_RECORD_BYTES`], and its delay history, [`super::MAX_HISTORY_BYTES`]), but
//! `jobs` runs at once would multiply them. So a study run reserves its bound ([`super::Run::memory_bound`])
//! from [`RUNS`] before it starts and gives it back when its row is made: runs wait for memory
//! rather than take the machine's, and a run's outcome never depends on how many ran beside it.

use std::sync::{Condvar, LazyLock, Mutex, PoisonError};
use std::time::Duration;

/// The least the study runs of a process may reserve together (4 GiB), whatever the machine: one
/// run at both of its own limits (3 GiB) fits.
pub const MIN_RUNS_MEMORY_BYTES: usize = 4 << 30;

/// Most bytes the study runs of a process reserve together: half the machine's memory
/// (`/proc/meminfo`'s MemTotal), at least [`MIN_RUNS_MEMORY_BYTES`] (also where the memory is not
/// known). 12 GiB on a 24 GiB machine: 130 runs of the paper's example at once (95 MB each, the
/// bound of its delay history), 350 Monte Carlo draws (37 MB); a fixed 4 GiB would have held a
/// machine of many cores to 45 and 116.
pub fn runs_memory_bytes() -> usize {
    RUNS.capacity
}

/// Half of MemTotal in bytes, from `/proc/meminfo` (Linux); `None` elsewhere.
fn half_the_machine() -> Option<usize> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: usize = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib.saturating_mul(1024) / 2)
}

/// How often a run waiting for memory checks its stop signal.
const STOP_CHECK: Duration = Duration::from_millis(50);

/// A budget of bytes that threads reserve and give back ([`Gate::hold`]).
pub(crate) struct Gate {
    capacity: usize,
    held: Mutex<usize>,
    freed: Condvar,
}

/// The study runs' budget ([`runs_memory_bytes`]).
pub(crate) static RUNS: LazyLock<Gate> =
    LazyLock::new(|| Gate::new(half_the_machine().unwrap_or(0).max(MIN_RUNS_MEMORY_BYTES)));

/// Bytes reserved from the runs' budget ([`super::Run::reserve_memory`]), given back when dropped.
pub struct Held<'a> {
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
    fn the_budget_is_half_the_machine_and_at_least_the_floor() {
        // On Linux MemTotal is known: half of it, within what machines have (256 MiB to 64 TiB).
        if cfg!(target_os = "linux") {
            let half = half_the_machine().expect("/proc/meminfo's MemTotal");
            assert!((128 << 20..32usize << 40).contains(&half), "{half}");
            assert_eq!(runs_memory_bytes(), half.max(MIN_RUNS_MEMORY_BYTES));
        }
        assert!(runs_memory_bytes() >= MIN_RUNS_MEMORY_BYTES);
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
