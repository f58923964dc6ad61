//! runs.csv: one row per run, written and read back exactly (numbers in Rust's shortest
//! round-trip form), so merged shards equal one unsharded sweep.

use std::io::{self, Write};

use super::summary::StudyMeta;
use super::sweep::{Outcome, Row};
use crate::sim::ChannelFigures;

/// The header: `run,point,draw,seed,<grid keys>,outcome,reason,tail_max_e1..m,tail_rms_e1..m,
/// max_u1..m,max_uf1..m,settle_t1..m,steps,wall_ms,<drawn values>`.
pub fn header(meta: &StudyMeta) -> Vec<String> {
    let mut h: Vec<String> = ["run", "point", "draw", "seed"].map(String::from).to_vec();
    h.extend(meta.grid.iter().map(|a| a.key.clone()));
    h.extend(["outcome", "reason"].map(String::from));
    for name in ["tail_max_e", "tail_rms_e", "max_u", "max_uf", "settle_t"] {
        h.extend((1..=meta.m).map(|i| format!("{name}{i}")));
    }
    h.extend(["steps", "wall_ms"].map(String::from));
    h.extend(meta.drawn.iter().cloned());
    h
}

/// Fields of a row of `meta`'s runs.csv (`None`: more than a usize holds, from an edited m).
fn fields(meta: &StudyMeta) -> Option<usize> {
    meta.m.checked_mul(5)?.checked_add(8 + meta.grid.len())?.checked_add(meta.drawn.len())
}

/// The longest line and the most lines a runs.csv of `meta`'s shard can hold, for
/// [`crate::files::read_lines_within`]: every number within 32 bytes, each grid value as summary.json
/// writes it (quoted, its quotes doubled), a reason within 64 KiB; the header, the rows and a
/// `# partial` line and two blank ones.
pub fn runs_csv_bounds(meta: &StudyMeta) -> (usize, usize) {
    // Counted, not built: an edited m of 1e15 is the reader's to refuse (`header_length`).
    let fields = fields(meta).unwrap_or(usize::MAX);
    let keys: usize =
        meta.grid.iter().map(|a| 2 * a.key.len() + 3).chain(meta.drawn.iter().map(|d| 2 * d.len() + 3)).sum();
    let grid: usize = meta.grid.iter().map(|a| a.values.iter().map(|v| 2 * v.len() + 3).max().unwrap_or(0)).sum();
    let line = fields.saturating_mul(32).saturating_add(keys.max(grid)).saturating_add(64 << 10);
    let rows = meta.shard.len(usize::try_from(meta.runs).unwrap_or(usize::MAX));
    (line, rows.saturating_add(4))
}

/// A number in a CSV output (runs.csv, tune.csv), as signals.csv writes its numbers: the shortest
/// digits that read back to it, in plain decimal from 1e-4 to below 1e15 (and 0, inf, NaN), in
/// exponent form outside (`{}` alone wrote μ = 1e20 as 21 digits and 1e-300 as 300 zeros).
pub fn csv_number(v: f64) -> String {
    // −0 is written 0.
    let v = if v == 0.0 { 0.0 } else { v };
    let a = v.abs();
    if a == 0.0 || (1e-4..1e15).contains(&a) || !a.is_finite() {
        v.to_string()
    } else {
        format!("{v:e}")
    }
}

/// A CSV field, quoted when it holds a comma, quote or line break (RFC 4180).
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The line that ends an interrupted sweep's runs.csv.
const PARTIAL: &str = "# partial:";

/// Writes runs.csv: the header, `rows` in the order given, and for a partial sweep a last line
/// `# partial: …` (read it with `pandas.read_csv(…, comment="#")`).
pub fn write_runs_csv(w: &mut dyn Write, meta: &StudyMeta, rows: &[Row], partial: bool) -> io::Result<()> {
    write_runs_header(w, meta)?;
    for r in rows {
        write_run_row(w, meta, r)?;
    }
    if partial {
        writeln!(w, "{PARTIAL} {} of the shard's runs were carried out before the sweep was interrupted", rows.len())?;
    }
    Ok(())
}

/// runs.csv's header line.
pub fn write_runs_header(w: &mut dyn Write, meta: &StudyMeta) -> io::Result<()> {
    writeln!(w, "{}", header(meta).iter().map(|h| csv_field(h)).collect::<Vec<_>>().join(","))
}

/// One row of runs.csv, its line ended.
pub fn write_run_row(w: &mut dyn Write, meta: &StudyMeta, r: &Row) -> io::Result<()> {
    // NaN (a stopped run's tail) is an empty cell.
    let opt = |v: Option<f64>| v.filter(|v| !v.is_nan()).map_or(String::new(), csv_number);
    let mut f: Vec<String> = vec![r.run.to_string(), r.point.to_string(), r.draw.to_string(), r.seed.to_string()];
    f.extend(r.grid.iter().map(|g| csv_field(g)));
    f.push(r.outcome.as_str().to_string());
    f.push(csv_field(&r.reason));
    let per = |get: &dyn Fn(&ChannelFigures) -> Option<f64>| {
        (0..meta.m).map(|i| opt(r.channels.get(i).and_then(get))).collect::<Vec<_>>()
    };
    f.extend(per(&|c| Some(c.tail_max_e)));
    f.extend(per(&|c| Some(c.tail_rms_e)));
    f.extend(per(&|c| Some(c.max_u)));
    f.extend(per(&|c| Some(c.max_uf)));
    f.extend(per(&|c| c.settle_t));
    f.push(r.steps.to_string());
    f.push(format!("{:.3}", r.wall_ms));
    f.extend((0..meta.drawn.len()).map(|i| opt(r.drawn.get(i).copied().flatten())));
    writeln!(w, "{}", f.join(","))
}

/// Splits one CSV line into fields (RFC 4180 quoting; no line breaks inside fields).
fn split(line: &str) -> Result<Vec<String>, String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut chars = line.chars().peekable();
    let mut quoted = false;
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (false, ',') => out.push(std::mem::take(&mut cur)),
            (false, '"') if cur.is_empty() => quoted = true,
            (true, '"') if chars.peek() == Some(&'"') => {
                chars.next();
                cur.push('"');
            }
            (true, '"') => quoted = false,
            (_, c) => cur.push(c),
        }
    }
    if quoted {
        return Err("a quoted field is not closed".into());
    }
    out.push(cur);
    Ok(out)
}

/// A row's outcome from its word and its reason ([`stopped_before_2026_12_06`]).
fn outcome(word: &str, reason: &str) -> Result<Outcome, String> {
    let outcome = match word {
        "completed" => Outcome::Completed,
        "diverged" => Outcome::Diverged,
        "failed" => Outcome::Failed,
        "stopped" => Outcome::Stopped,
        o => return Err(format!("outcome: expected completed, diverged, failed or stopped, found `{o}`")),
    };
    Ok(if stopped_before_2026_12_06(outcome, reason) { Outcome::Stopped } else { outcome })
}

/// A row written before runs a `[runaway]` rule ended had their own outcome: `diverged` (the peak
/// rule) or `failed` (the step rule), known by their reasons, which are unchanged; read as
/// `stopped`, so that a shard or a journal of then merges or resumes beside today's rows without
/// two names for one thing.
fn stopped_before_2026_12_06(outcome: Outcome, reason: &str) -> bool {
    match outcome {
        Outcome::Diverged => reason.contains("(over its entries; runaway.peak)"),
        Outcome::Failed => reason.starts_with("step budget: more than ") && reason.contains("runaway.steps"),
        _ => false,
    }
}

/// A runs.csv read back.
#[derive(Debug, Clone, PartialEq)]
pub struct RunsFile {
    pub rows: Vec<Row>,
    pub partial: bool,
}

/// Reads a runs.csv written by [`write_runs_csv`] for `meta`; the message names the line.
pub fn read_runs_csv(text: &str, meta: &StudyMeta) -> Result<RunsFile, String> {
    let mut lines = text.lines().enumerate();
    header_length(text.lines().next(), meta)?;
    let expected = header(meta);
    match lines.next() {
        Some((_, h)) if split(h)? == expected => {}
        _ => return Err(format!("line 1: expected the header {}", expected.join(","))),
    }
    let lens: Vec<usize> = meta.grid.iter().map(|a| a.values.len()).collect();
    let mut rows = Vec::new();
    let mut partial = false;
    for (n, line) in lines {
        let at = |msg: String| format!("line {}: {msg}", n + 1);
        if line.starts_with(PARTIAL) {
            partial = true;
            continue;
        }
        // A blank line (an editor's at the end) holds no row.
        if line.trim().is_empty() {
            continue;
        }
        let f = split(line).map_err(at)?;
        if f.len() != expected.len() {
            return Err(at(format!("expected {} fields, found {}", expected.len(), f.len())));
        }
        let row = read_row(&f, meta, &expected).map_err(at)?;
        identity(&row, meta, &lens).map_err(at)?;
        rows.push(row);
    }
    Ok(RunsFile { rows, partial })
}

/// One row's fields `f` (as many as the header `expected`) read back.
fn read_row(f: &[String], meta: &StudyMeta, expected: &[String]) -> Result<Row, String> {
    let (g, m) = (meta.grid.len(), meta.m);
    let num =
        |i: usize| f[i].parse::<f64>().map_err(|_| format!("{}: expected a number, found `{}`", expected[i], f[i]));
    let int =
        |i: usize| f[i].parse::<u64>().map_err(|_| format!("{}: expected an integer, found `{}`", expected[i], f[i]));
    let opt = |i: usize| if f[i].is_empty() { Ok(None) } else { num(i).map(Some) };
    // A completed run's figures are finite (NaN marks a run that stopped).
    let finite = |i: usize| {
        num(i).and_then(|x| match x.is_finite() {
            true => Ok(x),
            false => {
                Err(format!("{}: expected a finite number in a completed run's row, found `{}`", expected[i], f[i]))
            }
        })
    };
    let outcome = outcome(&f[4 + g], &f[5 + g])?;
    let first = 6 + g;
    // A completed run's figures are finite; a run that stopped has its peaks and empty (NaN)
    // tails; one that never started (an invalid draw) has none.
    let completed = outcome == Outcome::Completed;
    let figure = |i: usize| if completed { finite(i) } else { opt(i).map(|v| v.unwrap_or(f64::NAN)) };
    // A tail is a completed run's: one on a row that did not complete (written before 2026-12-03,
    // or an outcome edited) reads as none, so that the row says what its outcome says.
    let tail = |i: usize| if completed { finite(i) } else { opt(i).map(|_| f64::NAN) };
    let started = completed || (0..m).any(|i| !f[first + 2 * m + i].is_empty());
    let channels = (0..if started { m } else { 0 })
        .map(|i| {
            Ok(ChannelFigures {
                tail_max_e: tail(first + i)?,
                tail_rms_e: tail(first + m + i)?,
                max_u: figure(first + 2 * m + i)?,
                max_uf: figure(first + 3 * m + i)?,
                settle_t: opt(first + 4 * m + i)?,
            })
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(Row {
        run: int(0)? as usize,
        point: int(1)? as usize,
        draw: int(2)? as usize,
        seed: int(3)?,
        grid: f[4..4 + g].to_vec(),
        outcome,
        reason: f[5 + g].clone(),
        channels,
        steps: int(first + 5 * m)?,
        wall_ms: num(first + 5 * m + 1)?,
        drawn: (first + 5 * m + 2..f.len()).map(opt).collect::<Result<_, _>>()?,
        explicit_stiff: false,
    })
}

/// Checks the header line's number of fields against the study's m and grid before a header of m
/// channels is built (an edited m of 1e15 had asked for 24 PB).
fn header_length(line: Option<&str>, meta: &StudyMeta) -> Result<(), String> {
    let (g, m) = (meta.grid.len(), meta.m);
    let wanted = match meta.drawn.len() {
        0 => format!("the header of a study of {g} grid keys and m = {m} channels"),
        n => format!("the header of a study of {g} grid keys, m = {m} channels and {n} drawn values"),
    };
    let Some(line) = line.filter(|l| !l.is_empty()) else {
        return Err(format!("line 1: expected {wanted}, found an empty file"));
    };
    let found = split(line)?.len();
    match fields(meta) {
        Some(fields) if fields == found => Ok(()),
        _ => Err(format!(
            "line 1: expected {wanted}, found {found} fields; was the file edited, or is it another study's?"
        )),
    }
}

/// Whether two texts of a grid value are the same value: the same text, or the same numbers in
/// turn (a summary.json before 2026-12-05 wrote 1e-7 as 0.0000001, its runs.csv as 1e-7).
fn same_value(a: &str, b: &str) -> bool {
    let numbers = |t: &str| -> Option<Vec<f64>> {
        t.split(|c: char| matches!(c, '[' | ']' | ',') || c.is_whitespace())
            .filter(|w| !w.is_empty())
            .map(|w| w.parse().ok())
            .collect()
    };
    a == b || numbers(a).is_some_and(|x| numbers(b).is_some_and(|y| x == y))
}

/// Checks that a row's point, draw, seed and grid values are those its run index has in the
/// study `meta`, whose grid axes have `lens` values (an edited point or grid value had been merged
/// as it stood).
fn identity(row: &Row, meta: &StudyMeta, lens: &[usize]) -> Result<(), String> {
    if row.run as u64 >= meta.runs {
        return Err(format!("run: expected a run index below the study's {} runs, found {}", meta.runs, row.run));
    }
    let draws = meta.draws.max(1);
    let (point, draw) = (row.run / draws, row.run % draws);
    let seed = meta.seed.map_or(0, |s| super::sweep::run_seed(s, draw));
    let differs = |column: &str, want: String, found: String| {
        let per_point = crate::settings::count(draws, "draw", "draws");
        Err(format!(
            "{column}: expected {want} for run {} ({per_point} a grid point), found {found}; was the file edited?",
            row.run
        ))
    };
    if row.point != point {
        return differs("point", point.to_string(), row.point.to_string());
    }
    if row.draw != draw {
        return differs("draw", draw.to_string(), row.draw.to_string());
    }
    if row.seed != seed {
        return differs("seed", seed.to_string(), row.seed.to_string());
    }
    for ((axis, &i), value) in meta.grid.iter().zip(&super::axis_indices(point, lens)).zip(&row.grid) {
        match axis.values.get(i) {
            Some(want) if same_value(want, value) => {}
            want => return differs(&axis.key, format!("`{}`", want.map_or("", String::as_str)), format!("`{value}`")),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{csv_number, same_value};

    /// A grid value's text in summary.json and in runs.csv may differ in form, not in value.
    #[test]
    fn grid_values_compare_by_value() {
        assert!(same_value("1e-7", "0.0000001"));
        assert!(same_value("1e20", "100000000000000000000.0"));
        assert!(same_value("[1.0, 2.5]", "[1, 2.5]"));
        assert!(same_value("\"x\"", "\"x\""));
        assert!(!same_value("10.0", "99.0"));
        assert!(!same_value("[1.0, 2.0]", "[1.0]"));
        assert!(!same_value("\"x\"", "\"y\""));
    }

    #[test]
    fn csv_numbers_are_short_and_read_back() {
        for (v, text) in [
            (0.0, "0"),
            (-0.0, "0"),
            (0.5, "0.5"),
            (1e-4, "0.0001"),
            (9.9e-5, "9.9e-5"),
            (1e14, "100000000000000"),
            (1e15, "1e15"),
            (1e20, "1e20"),
            (-1e-300, "-1e-300"),
            (f64::INFINITY, "inf"),
        ] {
            assert_eq!(csv_number(v), text);
            assert_eq!(text.parse::<f64>().unwrap(), v, "{text} reads back");
        }
        assert_eq!(csv_number(f64::NAN), "NaN");
        // The shortest digits that read back, in either form.
        for v in [0.1 + 0.2, 1.0 / 3.0, 2.0f64.powi(-60), 6.02214076e23] {
            assert_eq!(csv_number(v).parse::<f64>().unwrap(), v);
        }
    }
}
