//! Walking a parsed TOML document with the full key path at hand, so every error names the key
//! (`plant.A[1][2]`, `reference.components[0].harmonics[1].frequency`).

use nalgebra::{Complex, DMatrix};

use super::ScenarioError;

pub(super) fn err(key: impl Into<String>, message: impl Into<String>) -> ScenarioError {
    ScenarioError::new(key, message)
}

/// "a string", "an integer", … for "found …" in messages.
pub(crate) fn kind(v: &toml::Value) -> &'static str {
    match v {
        toml::Value::String(_) => "a string",
        toml::Value::Integer(_) => "an integer",
        toml::Value::Float(_) => "a floating-point number",
        toml::Value::Boolean(_) => "a boolean",
        toml::Value::Datetime(_) => "a date-time",
        toml::Value::Array(a) if a.is_empty() => "an empty array",
        toml::Value::Array(_) => "an array",
        toml::Value::Table(_) => "a table",
    }
}

fn child(parent: &str, name: &str) -> String {
    if parent.is_empty() {
        name.to_string()
    } else {
        format!("{parent}.{name}")
    }
}

/// Where a run option that is not a scenario key is given instead (a user writing
/// `max_steps = …` under `[simulation]` was shown only the valid keys).
fn not_a_scenario_key(name: &str) -> Option<&'static str> {
    match name {
        "max_steps" => Some("the step budget is a run option, not a scenario key: the max-steps option of quell run, max_steps= of quell.simulate, or max_steps at a study file's top level"),
        "states" => Some("recording x and x̂ is a run option, not a scenario key: the states option of quell run, states=True of quell.simulate"),
        "continuous" => Some("a run option, not a scenario key: the continuous option of quell run, continuous=True of quell.simulate; or leave simulation.sample_time out"),
        "dt" | "Ts" | "ts" | "sample_period" => Some("a plant here is continuous-time, x' = Ax + Bu: convert a discrete-time model (python-control's dt, MATLAB's Ts) first, e.g. with MATLAB's d2c (the inverse of the zero-order hold); the controller's sample time is simulation.sample_time"),
        _ => None,
    }
}

/// A table whose keys have all been checked against the valid ones.
pub(crate) struct Table<'a> {
    key: String,
    table: &'a toml::Table,
}

/// One value and its key path.
#[derive(Clone, Copy)]
pub(crate) struct Value<'a, 'k> {
    pub key: &'k str,
    pub value: &'a toml::Value,
}

impl<'a> Table<'a> {
    /// Wraps `table` (found at `key`, "" for the document), rejecting any key not in `valid`.
    pub(crate) fn new(key: &str, table: &'a toml::Table, valid: &[&str]) -> Result<Self, ScenarioError> {
        for name in table.keys() {
            if !valid.contains(&name.as_str()) {
                let place = if key.is_empty() { "at the top level".to_string() } else { format!("in [{key}]") };
                // A known non-key first: `dt` is not a misspelt `D`.
                let hint = not_a_scenario_key(name)
                    .map(|w| format!(" ({w})"))
                    .or_else(|| {
                        crate::settings::nearest(name, valid.iter().copied()).map(|v| format!(" (did you mean `{v}`?)"))
                    })
                    .unwrap_or_default();
                return Err(err(
                    child(key, name),
                    format!("unknown key{hint}; valid keys {place}: {}", valid.join(", ")),
                ));
            }
        }
        Ok(Table { key: key.to_string(), table })
    }

    /// The full key path of `name` in this table.
    pub(crate) fn key(&self, name: &str) -> String {
        child(&self.key, name)
    }

    /// Calls `f` with the value of `name` and its key path, if present.
    pub(crate) fn get<T>(
        &self,
        name: &str,
        f: impl FnOnce(Value<'a, '_>) -> Result<T, ScenarioError>,
    ) -> Result<Option<T>, ScenarioError> {
        match self.table.get(name) {
            None => Ok(None),
            Some(value) => {
                let key = self.key(name);
                f(Value { key: &key, value }).map(Some)
            }
        }
    }

    /// Like [`Table::get`], but a missing key is an error; `what` says what the key holds.
    pub(crate) fn require<T>(
        &self,
        name: &str,
        what: &str,
        f: impl FnOnce(Value<'a, '_>) -> Result<T, ScenarioError>,
    ) -> Result<T, ScenarioError> {
        self.get(name, f)?.ok_or_else(|| err(self.key(name), format!("missing; required: {what}")))
    }
}

impl<'a> Value<'a, '_> {
    fn found(&self, expected: &str) -> ScenarioError {
        ScenarioError { wrong_type: true, ..err(self.key, format!("expected {expected}, found {}", kind(self.value))) }
    }

    /// A sub-table, checked against its valid keys.
    pub(crate) fn table(&self, valid: &[&str]) -> Result<Table<'a>, ScenarioError> {
        match self.value {
            toml::Value::Table(t) => Table::new(self.key, t, valid),
            _ => Err(self.found("a table")),
        }
    }

    /// A string.
    pub(crate) fn string(&self) -> Result<String, ScenarioError> {
        match self.value {
            toml::Value::String(s) => Ok(s.clone()),
            _ => Err(self.found("a string")),
        }
    }

    /// A finite number; integers are accepted.
    pub(crate) fn number(&self) -> Result<f64, ScenarioError> {
        match self.value {
            toml::Value::Float(_) | toml::Value::Integer(_) => self.finite("a finite number"),
            _ => Err(self.found("a number")),
        }
    }

    /// A finite number (integers accepted), refused as "expected `what`, found …".
    pub(crate) fn finite(&self, what: &str) -> Result<f64, ScenarioError> {
        let x = match self.value {
            toml::Value::Float(x) => *x,
            toml::Value::Integer(i) => *i as f64,
            _ => return Err(self.found(what)),
        };
        if x.is_finite() {
            Ok(x)
        } else {
            Err(err(self.key, format!("expected {what}, found {}", crate::settings::fmt_short(x))))
        }
    }

    /// A non-negative integer.
    pub(crate) fn unsigned(&self) -> Result<u64, ScenarioError> {
        match self.value {
            toml::Value::Integer(i) => {
                u64::try_from(*i).map_err(|_| err(self.key, format!("expected an integer ≥ 0, found {i}")))
            }
            _ => Err(self.found("an integer ≥ 0")),
        }
    }

    /// An integer ≥ 1; `what` names it.
    pub(crate) fn positive(&self, what: &str) -> Result<usize, ScenarioError> {
        match self.value {
            toml::Value::Integer(i) if *i >= 1 => {
                usize::try_from(*i).map_err(|_| err(self.key, format!("expected {what}, an integer ≥ 1, found {i}")))
            }
            toml::Value::Integer(i) => Err(err(self.key, format!("expected {what}, an integer ≥ 1, found {i}"))),
            _ => Err(self.found(&format!("{what}, an integer ≥ 1"))),
        }
    }

    /// An array, with each element's key path `key[i]`; `what` describes the expected array.
    pub(crate) fn array<T>(
        &self,
        what: &str,
        mut f: impl FnMut(Value<'a, '_>) -> Result<T, ScenarioError>,
    ) -> Result<Vec<T>, ScenarioError> {
        match self.value {
            toml::Value::Array(items) => items
                .iter()
                .enumerate()
                .map(|(i, value)| {
                    let key = format!("{}[{i}]", self.key);
                    f(Value { key: &key, value })
                })
                .collect(),
            _ => Err(self.found(what)),
        }
    }

    /// An array of finite numbers.
    pub(crate) fn numbers(&self) -> Result<Vec<f64>, ScenarioError> {
        self.array("an array of numbers", |v| v.number())
    }

    /// An array of numbers that may be `none`, `inf` or `-inf`, the infinity that stands for no
    /// limit (upper limits `inf`, lower limits `-inf`; NaN and the other infinity are refused).
    pub(crate) fn limits(&self, none: f64) -> Result<Vec<f64>, ScenarioError> {
        let (what, each) = if none > 0.0 {
            ("an array of numbers (inf for no limit)", "a finite number or inf (no limit)")
        } else {
            ("an array of numbers (-inf for no limit)", "a finite number or -inf (no limit)")
        };
        self.array(what, |v| match v.value {
            toml::Value::Float(x) if *x == none => Ok(*x),
            toml::Value::Float(_) | toml::Value::Integer(_) => v.finite(each),
            _ => v.number(),
        })
    }

    /// A matrix written as an array of rows of equal length. `[]` is a matrix with no rows.
    /// `width`: the row length another key fixes and where it comes from (`(6, "n, from
    /// plant.A")`), which a ragged matrix's rows are checked against ([`ragged_row`]).
    pub(crate) fn matrix(&self, width: Option<(usize, &str)>) -> Result<DMatrix<f64>, ScenarioError> {
        const FORM: &str = "a matrix (an array of rows, e.g. [[1.0, 0.0], [0.0, 1.0]])";
        if let toml::Value::Array(items) = self.value {
            if items.first().is_some_and(|v| matches!(v, toml::Value::Integer(_) | toml::Value::Float(_))) {
                return Err(err(
                    self.key,
                    format!("expected {FORM}, found an array of numbers; put each row in brackets"),
                ));
            }
        }
        let rows = self.array(FORM, |row| row.array("a row (an array of numbers)", |v| v.number()))?;
        if let Some(e) = ragged_row(self.key, &rows, width) {
            return Err(e);
        }
        let cols = rows.first().map_or(0, Vec::len);
        Ok(DMatrix::from_fn(rows.len(), cols, |r, c| rows[r][c]))
    }

    /// One pole: a number (real) or `[re, im]` with im > 0 (the pair re ± i·im), appended to `out`.
    fn pole(&self, out: &mut Vec<Complex<f64>>) -> Result<(), ScenarioError> {
        const FORM: &str = "a pole: a number (real pole) or [re, im] with im > 0 (the pair re ± i·im)";
        match self.value {
            toml::Value::Integer(_) | toml::Value::Float(_) => {
                out.push(Complex::new(self.number()?, 0.0));
                Ok(())
            }
            toml::Value::Array(items) if items.len() == 2 => {
                let parts = self.numbers()?;
                let (re, im) = (parts[0], parts[1]);
                if im > 0.0 {
                    out.push(Complex::new(re, im));
                    out.push(Complex::new(re, -im));
                    Ok(())
                } else if im == 0.0 {
                    Err(err(
                        self.key,
                        format!("[{re}, {im}] has imaginary part 0; write a real pole as a number ({re}), and a complex pair as [re, im] with im > 0"),
                    ))
                } else {
                    Err(err(
                        self.key,
                        format!("[{re}, {im}] has imaginary part {im} < 0; a pair [re, im] means re ± i·im, so write it as [{re}, {}]", -im),
                    ))
                }
            }
            toml::Value::Array(items) => {
                Err(err(self.key, format!("expected {FORM}, found an array of {} entries", items.len())))
            }
            _ => Err(self.found(FORM)),
        }
    }

    /// A list of poles, complex pairs expanded into both conjugates.
    pub(crate) fn poles(&self) -> Result<Vec<Complex<f64>>, ScenarioError> {
        let mut out = Vec::new();
        self.array("a list of poles (an array of numbers or [re, im] pairs)", |p| p.pole(&mut out))?;
        Ok(out)
    }

    /// One list of poles per channel or signal component.
    pub(crate) fn pole_lists(&self, per: &str) -> Result<Vec<Vec<Complex<f64>>>, ScenarioError> {
        if let toml::Value::Array(items) = self.value {
            if items.first().is_some_and(|v| matches!(v, toml::Value::Integer(_) | toml::Value::Float(_))) {
                return Err(err(
                    self.key,
                    format!("expected one list of poles per {per} (e.g. [[-6.0, -2.0], [-4.0]]), found a flat array of numbers; put each {per}'s poles in brackets"),
                ));
            }
        }
        self.array(&format!("one list of poles per {per}"), |p| p.poles())
    }
}

/// The first wrong row of a ragged matrix (rows of different lengths) as an error on `key[i]`:
/// against `width` where another key fixes the length (C's n from plant.A: a C whose row 0 alone
/// was short had been blamed on its right row 1), else against the length most rows have, row 0's
/// where no length is more common than every other. `None` when every row has the same length.
fn ragged_row(key: &str, rows: &[Vec<f64>], width: Option<(usize, &str)>) -> Option<ScenarioError> {
    let first = rows.first()?.len();
    if rows.iter().all(|r| r.len() == first) {
        return None;
    }
    let count = |len: usize| rows.iter().filter(|r| r.len() == len).count();
    let (cols, why) = match width {
        Some((cols, from)) => (cols, from.to_string()),
        None => {
            let (len, most) = rows.iter().map(|r| (r.len(), count(r.len()))).max_by_key(|&(_, c)| c)?;
            let ties = rows.iter().any(|r| r.len() != len && count(r.len()) == most);
            match (ties || most < 2, most + 1 == rows.len()) {
                (true, _) => (first, "as in row 0; every row of a matrix has the same length".to_string()),
                (false, true) => (len, "as in every other row".to_string()),
                (false, false) => {
                    (len, format!("as in {most} of its {} rows; every row of a matrix has the same length", rows.len()))
                }
            }
        }
    };
    let (i, row) = rows.iter().enumerate().find(|(_, r)| r.len() != cols)?;
    let expected = crate::settings::entries(cols);
    Some(err(format!("{key}[{i}]"), format!("expected {expected} ({why}), found {}", row.len())))
}

/// A TOML syntax error as "line L, column C: what" (the parser's message; a duplicate key is
/// named, with what to do).
pub(crate) fn syntax_message(text: &str, e: &toml::de::Error) -> String {
    let message = e.message().trim_end();
    let Some(span) = e.span() else { return message.to_string() };
    let (line, col) = line_col(text, span.start);
    let key = text.get(span.clone()).map(str::trim).filter(|k| !k.is_empty());
    match key {
        Some(key) if message.starts_with("duplicate key") => {
            format!("line {line}, column {col}: duplicate key `{key}`: a key may be given once in a table, keep one")
        }
        // An integer beyond i64 (the parser says "invalid type: integer `…` as i128", or "u64
        // value was too large" up to u64::MAX).
        Some(number) if message.contains("as i128") || message.contains("value was too large") => {
            let before = text.get(..span.start).unwrap_or_default();
            let name = before.rsplit('\n').next().and_then(|l| l.split('=').next()).map(str::trim);
            let name = name.filter(|n| !n.is_empty()).map(|n| n.trim_matches('"'));
            let what = match name.and_then(crate::settings::integer_key) {
                Some(expected) => format!("expected {expected}; give a smaller one"),
                None => format!("write it as a float, e.g. {number}.0"),
            };
            let name = name.map_or(String::new(), |n| format!(" ({n})"));
            format!(
                "line {line}, column {col}{name}: the integer {number} is beyond TOML's integers (±9223372036854775807); {what}"
            )
        }
        _ => format!("line {line}, column {col}: {message}"),
    }
}

/// Line and column (1-based) of byte `offset` in `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before.rfind('\n').map_or(before, |i| &before[i + 1..]).chars().count() + 1;
    (line, col)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(text: &str) -> String {
        syntax_message(text, &text.parse::<toml::Table>().unwrap_err())
    }

    #[test]
    fn a_duplicate_key_is_named_with_its_line() {
        assert_eq!(
            message("[plant]\nA = [[1.0]]\nA = [[2.0]]\n"),
            "line 3, column 1: duplicate key `A`: a key may be given once in a table, keep one"
        );
        assert!(message("[plant]\n  mu = 1\n  mu = 2\n").starts_with("line 3, column 3: duplicate key `mu`: "));
    }

    #[test]
    fn an_integer_beyond_i64_is_named_with_its_key_and_a_fix() {
        // Was "invalid type: integer `99999999999999999999` as i128, expected any valid TOML value".
        assert_eq!(
            message("[simulation]\nt_end = 99999999999999999999\n"),
            "line 2, column 9 (t_end): the integer 99999999999999999999 is beyond TOML's integers (±9223372036854775807); write it as a float, e.g. 99999999999999999999.0"
        );
        // A count or a seed is an integer: no float advice for it (a float seed is refused).
        assert_eq!(
            message("[noise]\nseed = 99999999999999999999\n"),
            "line 2, column 8 (seed): the integer 99999999999999999999 is beyond TOML's integers (±9223372036854775807); expected a seed, an integer from 0 to 2**63 - 1; give a smaller one"
        );
        // From i64::MAX + 1 to u64::MAX the parser said "u64 value was too large".
        for n in ["9223372036854775808", "18446744073709551615"] {
            assert_eq!(
                message(&format!("[noise]\nseed = {n}\n")),
                format!("line 2, column 8 (seed): the integer {n} is beyond TOML's integers (±9223372036854775807); expected a seed, an integer from 0 to 2**63 - 1; give a smaller one")
            );
        }
        let fixed: toml::Table = "t_end = 99999999999999999999.0".parse().unwrap();
        assert_eq!(fixed["t_end"].as_float(), Some(1e20));
    }

    #[test]
    fn other_errors_keep_the_parsers_message_at_a_character_boundary() {
        // The column counts characters: μ is two bytes.
        let m = message("x = [1.0, \"μ\" 2]\n");
        assert!(m.starts_with("line 1, column 15: "), "{m}");
        assert!(m.contains("comma"), "{m}");
    }
}
