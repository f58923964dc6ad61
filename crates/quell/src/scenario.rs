//! Scenario files (TOML): parsing and validation at the boundary into typed values.
//! STUB: owned by the scenario helper.

use thiserror::Error;

/// A scenario error: the offending key and what was expected and found.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{key}: {message}")]
pub struct ScenarioError {
    pub key: String,
    pub message: String,
}

/// A validated scenario.
#[derive(Debug, Clone)]
pub struct Scenario {}
