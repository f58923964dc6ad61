//! Arbitrary UTF-8 text as a scenario file: parsing and validation must return a value or a
//! `ScenarioError`, never panic; a valid scenario then goes through `Design::new`, which must return
//! a `Design` or a `DesignError`, and with a `sample_time` through `Controller::new` (the exact
//! discretization and the delay lines), which must return a controller or a `ControllerError`.
//! The same text as a study file (grid and Monte Carlo keys applied to the paper's example or to
//! the file it names) must give a study or a `StudyError`; the first and last runs' specifications
//! are then built. Nothing is caught: any panic is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;
use quell::Scenario;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(study) = quell::study::Study::from_toml(text, None) {
        if !study.is_empty() {
            let _ = (study.spec(0), study.spec((study.len() - 1).min(usize::MAX as u64) as usize));
        }
    }
    if let Ok(scenario) = Scenario::from_toml(text) {
        if let (Ok(design), Some(sample_time)) = (scenario.design(), scenario.simulation.sample_time) {
            let _ = quell::Controller::new(&design, sample_time);
        }
    }
});
