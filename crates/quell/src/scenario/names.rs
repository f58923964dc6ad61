//! The names of a plant's signals (`[plant]` `inputs`, `outputs`, `states`): labels for the front
//! ends (Python's `control.StateSpace` round trip, the CLI's channel lines); no computation reads
//! them.

use super::read::{err, Table};
use super::ScenarioError;

/// The names of a plant's inputs u_f, outputs y and states x of (1); `None` where none were given.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SignalNames {
    /// One per input (m).
    pub inputs: Option<Vec<String>>,
    /// One per output (m).
    pub outputs: Option<Vec<String>>,
    /// One per state (n).
    pub states: Option<Vec<String>>,
}

fn or_default(given: &Option<Vec<String>>, symbol: &str, count: usize) -> Vec<String> {
    given.clone().unwrap_or_else(|| (1..=count).map(|i| format!("{symbol}[{i}]")).collect())
}

impl SignalNames {
    /// The inputs' names: as given, or `u_f[1]` … `u_f[m]`.
    pub fn inputs(&self, m: usize) -> Vec<String> {
        or_default(&self.inputs, "u_f", m)
    }

    /// The outputs' names: as given, or `y[1]` … `y[m]`.
    pub fn outputs(&self, m: usize) -> Vec<String> {
        or_default(&self.outputs, "y", m)
    }

    /// The states' names: as given, or `x[1]` … `x[n]`.
    pub fn states(&self, n: usize) -> Vec<String> {
        or_default(&self.states, "x", n)
    }

    /// Whether no signal has a name.
    pub fn is_empty(&self) -> bool {
        self.inputs.is_none() && self.outputs.is_none() && self.states.is_none()
    }

    /// `inputs`, `outputs` and `states` of `[plant]`, for a plant of n states and m channels.
    pub(super) fn read(t: &Table<'_>, n: usize, m: usize) -> Result<SignalNames, ScenarioError> {
        let list = |name: &str, count: usize, per: &str| {
            t.get(name, |v| v.array("an array of names (strings)", |s| s.string()))?
                .map(|names| check_names(&t.key(name), &names, count, per).map(|()| names))
                .transpose()
        };
        Ok(SignalNames {
            inputs: list("inputs", m, "input")?,
            outputs: list("outputs", m, "output")?,
            states: list("states", n, "state")?,
        })
    }

    /// Writes the names given into a `[plant]` table (nothing when none are).
    pub fn write(&self, t: &mut toml::Table) {
        for (key, names) in [("inputs", &self.inputs), ("outputs", &self.outputs), ("states", &self.states)] {
            if let Some(names) = names {
                t.insert(key.into(), toml::Value::Array(names.iter().cloned().map(toml::Value::String).collect()));
            }
        }
    }
}

/// The message for a name holding a control character (a line break, a tab, NUL), which would break
/// the lines and columns it labels, or a Unicode noncharacter (U+FFFE, U+FFFF, U+FDD0–U+FDEF and
/// the last two of every plane), which no text may carry (U+FFFE and U+FFFF are not XML: an FMU's
/// model description with one is refused by every importer); `None` for a printable name.
pub(crate) fn control_character(name: &str) -> Option<String> {
    let noncharacter = |c: char| matches!(c as u32, 0xFDD0..=0xFDEF) || (c as u32 & 0xFFFE) == 0xFFFE;
    name.chars().find(|&c| c.is_control() || noncharacter(c)).map(|c| {
        let what = if c.is_control() { "control character" } else { "noncharacter" };
        format!("expected printable characters, found {name:?} (with {c:?}); a name labels lines, columns and files: remove the {what}")
    })
}

/// Checks the names of `count` signals (`per`: "input", "output", "state") at `key`: one per
/// signal, none empty, no two alike.
pub fn check_names(key: &str, names: &[String], count: usize, per: &str) -> Result<(), ScenarioError> {
    // The count first: a million copies of one name were reported as a duplicate.
    if names.len() != count {
        return Err(err(key, format!("expected {count} names (one per {per}), found {}", names.len())));
    }
    for (i, name) in names.iter().enumerate() {
        if name.trim().is_empty() {
            return Err(err(
                format!("{key}[{i}]"),
                format!("expected a name, found {name:?}; give every {per} a name"),
            ));
        }
        if let Some(message) = control_character(name) {
            return Err(err(format!("{key}[{i}]"), message));
        }
        if names[..i].contains(name) {
            return Err(err(
                format!("{key}[{i}]"),
                format!("{name:?} names another signal too; give each signal its own name"),
            ));
        }
    }
    Ok(())
}
