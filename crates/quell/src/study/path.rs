//! Scenario key paths (`design.mu[0]`, `truth.A`, `reference.components[0].harmonics[0].amplitude`),
//! the same paths error messages name, read and written on a parsed scenario document.

use std::fmt;

/// One step of a key path: a table key or an array index.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Step {
    Key(String),
    Index(usize),
}

/// A parsed key path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct KeyPath {
    text: String,
    steps: Vec<Step>,
}

impl fmt::Display for KeyPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

/// The nesting of a numeric value: a number, or an array of values.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Shape {
    Number,
    Array(Vec<Shape>),
}

impl fmt::Display for Shape {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Shape::Number => f.write_str("a number"),
            Shape::Array(items) => {
                // A matrix reads as rows×cols, a vector by its length.
                let inner: Vec<&Shape> = items.iter().collect();
                if let Some(Shape::Array(first)) = inner.first() {
                    if inner.iter().all(|s| matches!(s, Shape::Array(r) if r.len() == first.len() && r.iter().all(|e| *e == Shape::Number))) {
                        return write!(f, "a {}×{} matrix", items.len(), first.len());
                    }
                }
                if items.iter().all(|s| *s == Shape::Number) {
                    write!(f, "a vector of {} numbers", items.len())
                } else {
                    write!(f, "an array of {} entries (", items.len())?;
                    for (i, s) in items.iter().enumerate() {
                        write!(f, "{}{s}", if i > 0 { ", " } else { "" })?;
                    }
                    f.write_str(")")
                }
            }
        }
    }
}

/// The shape of `v` when it is a number or (nested) arrays of numbers, else `None`.
pub(super) fn shape(v: &toml::Value) -> Option<Shape> {
    match v {
        toml::Value::Integer(_) | toml::Value::Float(_) => Some(Shape::Number),
        toml::Value::Array(items) => items.iter().map(shape).collect::<Option<Vec<_>>>().map(Shape::Array),
        _ => None,
    }
}

/// Every number in `v`, in order, as a mutable reference (integers are turned into floats first).
pub(super) fn for_each_number(v: &mut toml::Value, f: &mut impl FnMut(&mut f64)) {
    match v {
        toml::Value::Integer(i) => {
            let mut x = *i as f64;
            f(&mut x);
            *v = toml::Value::Float(x);
        }
        toml::Value::Float(x) => f(x),
        toml::Value::Array(items) => items.iter_mut().for_each(|item| for_each_number(item, f)),
        _ => {}
    }
}

/// Whether two values hold the same numbers in the same nesting (an integer equals its float).
pub(super) fn same_numbers(a: &toml::Value, b: &toml::Value) -> bool {
    let num = |v: &toml::Value| match v {
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Float(x) => Some(*x),
        _ => None,
    };
    match (a, b) {
        (toml::Value::Array(x), toml::Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(x, y)| same_numbers(x, y))
        }
        _ => num(a).is_some() && num(a) == num(b),
    }
}

impl KeyPath {
    /// The path as its steps read, whatever the text it was parsed from (`truth.u_min[00]` and
    /// `truth.u_min[+0]` are `truth.u_min[0]`): what two paths are compared by.
    pub fn canonical(&self) -> String {
        let mut text = String::new();
        for step in &self.steps {
            match step {
                Step::Key(k) if text.is_empty() => text.push_str(k),
                Step::Key(k) => text = format!("{text}.{k}"),
                Step::Index(i) => text = format!("{text}[{i}]"),
            }
        }
        text
    }

    /// Parses `a.b[0][1].c`; the message says what is wrong.
    pub fn parse(text: &str) -> Result<KeyPath, String> {
        let mut steps = Vec::new();
        for (n, part) in text.split('.').enumerate() {
            let (name, mut rest) = part.split_at(part.find('[').unwrap_or(part.len()));
            if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                return Err(format!(
                    "`{text}` is not a key path: part {} (`{part}`) must start with a key name (letters, digits, _), e.g. design.mu[0]",
                    n + 1
                ));
            }
            steps.push(Step::Key(name.to_string()));
            while !rest.is_empty() {
                let close = rest.find(']').filter(|_| rest.starts_with('['));
                let index = close.and_then(|c| rest[1..c].parse::<usize>().ok());
                match (close, index) {
                    (Some(c), Some(i)) => {
                        steps.push(Step::Index(i));
                        rest = &rest[c + 1..];
                    }
                    // Digits too many for any index (a list holds fewer than 2⁶⁴ entries).
                    (Some(c), None) if rest[1..c].bytes().all(|b| b.is_ascii_digit()) && c > 1 => {
                        return Err(format!(
                        "`{text}`: the index [{}] is beyond any list's length; give the index of an entry that exists",
                        &rest[1..c]
                    ))
                    }
                    _ => {
                        return Err(format!(
                            "`{text}` is not a key path: `{rest}` should be an index in brackets, e.g. [0]"
                        ))
                    }
                }
            }
        }
        Ok(KeyPath { text: text.to_string(), steps })
    }

    /// True when one path names the other's value or a part of it (`design.mu` and
    /// `design.mu[0]`, or `design.mu[0]` and `design.mu[00]`): setting both would let one
    /// overwrite the other.
    pub fn overlaps(&self, other: &KeyPath) -> bool {
        let n = self.steps.len().min(other.steps.len());
        self.steps[..n] == other.steps[..n]
    }

    /// The first key (`plant`, `design`, `truth`, …).
    pub fn section(&self) -> &str {
        match &self.steps[0] {
            Step::Key(k) => k,
            Step::Index(_) => "",
        }
    }

    /// The value at this path in `doc`, or a message naming the longest part that exists.
    pub fn get<'a>(&self, doc: &'a toml::Table) -> Result<&'a toml::Value, String> {
        let mut at: Option<&toml::Value> = None;
        let mut walked = String::new();
        for step in &self.steps {
            let next = match (at, step) {
                (None, Step::Key(k)) => doc.get(k),
                (Some(toml::Value::Table(t)), Step::Key(k)) => t.get(k),
                (Some(toml::Value::Array(a)), Step::Index(i)) => a.get(*i),
                (Some(toml::Value::Array(a)), Step::Key(_)) => {
                    return Err(format!("{walked} is an array of {} entries; index it, e.g. {walked}[0]", a.len()))
                }
                (Some(toml::Value::Table(_)), Step::Index(_)) => {
                    return Err(format!("{walked} is a table, not an array"))
                }
                (Some(_), _) => return Err(format!("{walked} is a single value; it has no parts")),
                (None, Step::Index(_)) => None,
            };
            let part = match step {
                Step::Key(k) if walked.is_empty() => k.clone(),
                Step::Key(k) => format!(".{k}"),
                Step::Index(i) => format!("[{i}]"),
            };
            match next {
                Some(v) => {
                    walked.push_str(&part);
                    at = Some(v);
                }
                None => {
                    let len = match (at, step) {
                        (Some(toml::Value::Array(a)), Step::Index(_)) => format!(" (it has {} entries)", a.len()),
                        _ => String::new(),
                    };
                    let parent = if walked.is_empty() { "the scenario".to_string() } else { walked.clone() };
                    return Err(format!("{parent} has no {}{len}", part.trim_start_matches('.')));
                }
            }
        }
        at.ok_or_else(|| "empty key path".to_string())
    }

    /// Replaces the value at this path in `doc` (which [`KeyPath::get`] found).
    pub fn set(&self, doc: &mut toml::Table, value: toml::Value) -> Result<(), String> {
        *self.get_mut(doc)? = value;
        Ok(())
    }

    /// The value at this path, mutably.
    pub fn get_mut<'a>(&self, doc: &'a mut toml::Table) -> Result<&'a mut toml::Value, String> {
        self.get(doc)?;
        let mut steps = self.steps.iter();
        let Some(Step::Key(first)) = steps.next() else { unreachable!("a key path starts with a key") };
        let mut at = doc.get_mut(first).expect("checked by get");
        for step in steps {
            at = match (at, step) {
                (toml::Value::Table(t), Step::Key(k)) => t.get_mut(k).expect("checked by get"),
                (toml::Value::Array(a), Step::Index(i)) => &mut a[*i],
                _ => unreachable!("checked by get"),
            };
        }
        Ok(at)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc() -> toml::Table {
        "[plant]\nA = [[1, 2], [3, 4.5]]\ndelays = [1.0, 3.0]\n[design]\nmu = [20, 30]\nbeta = 1.0\n".parse().unwrap()
    }

    #[test]
    fn reads_and_writes_nested_values() {
        let mut d = doc();
        let p = KeyPath::parse("plant.A[1][0]").unwrap();
        assert_eq!(p.get(&d).unwrap().as_integer(), Some(3));
        p.set(&mut d, toml::Value::Float(7.5)).unwrap();
        assert_eq!(d["plant"]["A"][1][0].as_float(), Some(7.5));
        assert_eq!(shape(KeyPath::parse("plant.A").unwrap().get(&d).unwrap()).unwrap().to_string(), "a 2×2 matrix");
        assert_eq!(shape(&d["design"]["mu"]).unwrap().to_string(), "a vector of 2 numbers");
    }

    #[test]
    fn missing_parts_are_named() {
        let d = doc();
        let e = |s: &str| KeyPath::parse(s).unwrap().get(&d).unwrap_err();
        assert_eq!(e("design.mu[2]"), "design.mu has no [2] (it has 2 entries)");
        assert_eq!(e("design.nu"), "design has no nu");
        assert_eq!(e("truth.A"), "the scenario has no truth");
        assert_eq!(e("design.beta[0]"), "design.beta is a single value; it has no parts");
        assert!(KeyPath::parse("design.mu[x]").is_err());
        assert!(KeyPath::parse("design..mu").is_err());
        assert!(KeyPath::parse("design.mu[0").is_err());
    }
}
