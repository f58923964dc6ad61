//! Arbitrary UTF-8 text as a study file: `fuzz_entry::study` (read, then the first and last runs'
//! specifications built) must return a study or a `StudyError`, never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../../crates/quell/tests/fuzz_entry/mod.rs"]
mod fuzz_entry;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Err(e) = fuzz_entry::study(text, None) {
            assert!(!e.key.trim().is_empty(), "a refusal names no key: {e:?}");
        }
    }
});
