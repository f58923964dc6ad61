//! Arbitrary UTF-8 text as a scenario file: `fuzz_entry::scenario` (read and validated, designed,
//! and with a `sample_time` the controller built) must return or refuse, never panic. Nothing is
//! caught: any panic is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../../crates/quell/tests/fuzz_entry/mod.rs"]
mod fuzz_entry;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = fuzz_entry::scenario(text);
    }
});
