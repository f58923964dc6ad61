//! A deterministic fuzz test of the export options, in the normal test suite: 3000 cases drawn
//! from a seeded generator (sample times NaN, ±∞, 0, negative, subnormal, huge or random bit
//! patterns; prefixes and scenario names with comment breakers, quotes, newlines, unicode, C
//! keywords and long runs; precisions valid or not; with and without the FMU) exported from the
//! paper's design must never panic; a refusal names the option at fault, and generated code has
//! well-formed comments (`fuzz_entry::export`).

use std::panic::{catch_unwind, AssertUnwindSafe};

mod fuzz_entry;

use fuzz_entry::{export, names_an_export_option, ExportCase};

#[test]
fn random_export_options_never_panic_and_refusals_name_the_option() {
    let design = quell::Scenario::from_toml(quell::scenario::PAPER_EXAMPLE).unwrap().design().unwrap();
    let mut state: u64 = 2026;
    let (mut refused, mut cases) = (0, 0);
    for case in 0..3000 {
        let bytes: Vec<u8> = (0..48)
            .map(|_| {
                state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
                (state >> 56) as u8
            })
            .collect();
        let options = ExportCase::from_bytes(&bytes);
        let result = catch_unwind(AssertUnwindSafe(|| export(&design, &options)));
        let Ok(result) = result else { panic!("case {case} panicked on {options:?}") };
        cases += 1;
        if let Err(message) = result {
            refused += 1;
            assert!(names_an_export_option(&message), "case {case}: {message:?} names no option for {options:?}");
        }
    }
    eprintln!("{cases} export option sets, {refused} refused");
    // Both sides are exercised: the generator makes valid and invalid options alike.
    assert!(refused > cases / 4 && cases - refused >= 10, "{refused} of {cases} refused");
}
