//! Arbitrary UTF-8 text as a scenario file: parsing and validation must return a value or a
//! `ScenarioError`, never panic; a valid scenario then goes through `Design::new`, which must return
//! a `Design` or a `DesignError`, and with a `sample_time` through `Controller::new` (the exact
//! discretization and the delay lines), which must return a controller or a `ControllerError`.
//! Nothing is caught: any panic is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;
use quell::Scenario;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(scenario) = Scenario::from_toml(text) {
        if let (Ok(design), Some(sample_time)) = (scenario.design(), scenario.simulation.sample_time) {
            let _ = quell::Controller::new(&design, sample_time);
        }
    }
});
