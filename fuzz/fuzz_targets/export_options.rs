//! Arbitrary bytes as export options (`fuzz_entry::ExportCase::from_bytes`: sample time, prefix,
//! precision, scenario name, FMU) applied to the paper's design: `fuzz_entry::export` must never
//! panic, a refusal must name the option at fault, and generated comments must be well formed.
#![no_main]

use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;

#[path = "../../crates/quell/tests/fuzz_entry/mod.rs"]
mod fuzz_entry;

fuzz_target!(|data: &[u8]| {
    static DESIGN: OnceLock<quell::Design> = OnceLock::new();
    let design = DESIGN.get_or_init(|| {
        quell::Scenario::from_toml(quell::scenario::PAPER_EXAMPLE).unwrap().design().unwrap()
    });
    let case = fuzz_entry::ExportCase::from_bytes(data);
    if let Err(message) = fuzz_entry::export(design, &case) {
        assert!(fuzz_entry::names_an_export_option(&message), "{message:?} names no option for {case:?}");
    }
});
