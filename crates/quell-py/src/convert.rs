//! Python values in, checked Rust values out (and numpy arrays back): a value of the wrong type is
//! a `TypeError`, a value of the right type that is not valid (shape, NaN) a `QuellError` subclass;
//! both name the argument, what was expected and what was found.

use numpy::ndarray::Array2;
use numpy::{PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyComplex, PyDict, PyIterator, PyList, PyString, PyTuple};
use quell::nalgebra::{Complex, DMatrix};

use crate::errors::{type_error, Kind};

/// Python's name for the type of `obj` ("list", "str", "numpy.ndarray").
pub fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "object".into())
}

/// [`type_name`] with its article, for "found an int", "found a list".
pub fn a_type(obj: &Bound<'_, PyAny>) -> String {
    let name = type_name(obj);
    let article = if name.starts_with(['a', 'e', 'i', 'o', 'u', 'A', 'E', 'I', 'O', 'U']) { "an" } else { "a" };
    format!("{article} {name}")
}

/// `obj` as a Python int: an int, or anything with `__index__` (numpy's integer scalars, which
/// quell's own frames return), but not a bool; `None` otherwise (the caller's `TypeError`).
pub fn as_int<'py>(obj: &Bound<'py, PyAny>) -> Option<Bound<'py, pyo3::types::PyInt>> {
    if obj.is_instance_of::<pyo3::types::PyBool>() {
        return None;
    }
    let index = obj.py().import("operator").ok()?.call_method1("index", (obj,)).ok()?;
    index.cast_into::<pyo3::types::PyInt>().ok()
}

/// `obj` as a float64 numpy array: any array-like of real numbers (ints, floats, numpy arrays).
/// Something that is not an array-like of numbers is a `TypeError`; rows of unequal length are
/// `kind`'s error.
fn real_array<'py>(obj: &Bound<'py, PyAny>, name: &str, kind: Kind) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let py = obj.py();
    let np = py.import("numpy")?;
    if obj.is_none() || obj.is_instance_of::<PyDict>() {
        return Err(type_error(name, "an array-like of real numbers", obj));
    }
    unreadable_nesting(&np, obj, name, kind)?;
    let arr = np.call_method1("asarray", (obj,)).map_err(|e| {
        // A Ctrl-C (or SystemExit) met while numpy reads a lazy array-like is the user's, not a
        // bad value: it goes on as it is.
        if !e.is_instance_of::<pyo3::exceptions::PyException>(py) {
            return e;
        }
        kind.err(
            py,
            format!(
                "{name}: expected an array-like of real numbers, found {} that numpy cannot read as an array ({e})",
                a_type(obj)
            ),
        )
    })?;
    let mut dtype = arr.getattr("dtype")?;
    let mut code: String = dtype.getattr("kind")?.extract()?;
    // Python ints beyond int64 (10**30) make an object array; within a float64's range they are
    // the numbers they are, as numpy reads them into float64.
    let floats = match code == "O" && all_ints_or_floats(&arr)? {
        // A Ctrl-C met here goes on too ([`real_array`]'s first reading).
        true => match np.call_method1("asarray", (obj, "float64")) {
            Ok(floats) => Some(floats),
            Err(e) if !e.is_instance_of::<pyo3::exceptions::PyException>(py) => return Err(e),
            Err(_) => None,
        },
        false => None,
    };
    let arr = match floats {
        Some(floats) => {
            (dtype, code) = (floats.getattr("dtype")?, "f".to_string());
            floats
        }
        None => arr,
    };
    if !matches!(code.as_str(), "i" | "u" | "f") {
        let found = match code.as_str() {
            "c" => "complex numbers".to_string(),
            "b" => "booleans".to_string(),
            "U" | "S" => "strings".to_string(),
            // Python ints beyond a float64's range make an object array too.
            "O" if arr
                .call_method0("ravel")?
                .try_iter()?
                .flatten()
                .any(|x| x.is_instance_of::<pyo3::types::PyInt>() && x.extract::<f64>().is_err()) =>
            {
                "an integer beyond a float64's range (±1.8e308)".to_string()
            }
            "O" if arr.getattr("ndim")?.extract::<usize>()? == 0 => a_type(obj),
            "O" => "entries that are not all numbers".to_string(),
            _ => format!("an array of dtype {}", dtype.str()?),
        };
        return Err(PyTypeError::new_err(format!("{name}: expected real numbers, found {found}")));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        no_bools(obj, &arr, name)?;
    }
    Ok(arr.call_method1("astype", ("float64",))?.cast_into::<PyArrayDyn<f64>>()?)
}

/// What numpy would read wrongly or for ever in `obj` ([`walk`]): masked entries, which numpy reads
/// as their data, and nested lists of more than [`MAX_NESTED_ENTRIES`] entries; `kind`'s error
/// naming `name`.
fn unreadable_nesting(np: &Bound<'_, PyModule>, obj: &Bound<'_, PyAny>, name: &str, kind: Kind) -> PyResult<()> {
    let py = obj.py();
    let ma = np.getattr("ma")?;
    let Nested { masked, entries } =
        walk(obj, (&ma, &ma.getattr("MaskedArray")?), &mut std::collections::HashMap::new(), 0)?;
    if entries > MAX_NESTED_ENTRIES {
        return Err(kind.err(
            py,
            format!("{name}: expected an array-like of at most {MAX_NESTED_ENTRIES:e} numbers, found {entries:e} entries (a sequence that long, or rows shared at every level)"),
        ));
    }
    if masked > 0 {
        let entries = if masked == 1 { "entry" } else { "entries" };
        return Err(kind.err(
            py,
            format!("{name}: expected real numbers, found a masked array with {masked} masked {entries}, whose values numpy would pass on as they are; fill them (`.filled(value)`) or pass `.data` if those values are meant"),
        ));
    }
    Ok(())
}

/// What nested lists and tuples hold, as numpy would read them ([`walk`]).
#[derive(Clone, Copy, Default)]
struct Nested {
    /// Masked entries: a masked array's (`np.ma.masked` is one), and those of the masked arrays
    /// within a list or tuple of rows, which numpy reads as their data too.
    masked: usize,
    /// Entries numpy would read, a row shared k times counted k times.
    entries: f64,
}

/// Entries beyond which nested lists are refused before numpy reads them: rows shared at every
/// level, `a = [a, a]` forty times, are 2^40 entries, which numpy walked for ever.
const MAX_NESTED_ENTRIES: f64 = 1e9;

/// [`Nested`] of `obj`, each list or tuple walked once (`memo`: its result, or a default while it
/// is walked, so that one holding itself ends; numpy refuses that one itself), nesting deeper than
/// numpy's 64 dimensions left to numpy, which refuses it.
fn walk(
    obj: &Bound<'_, PyAny>,
    (ma, masked_array): (&Bound<'_, PyAny>, &Bound<'_, PyAny>),
    memo: &mut std::collections::HashMap<usize, Nested>,
    depth: usize,
) -> PyResult<Nested> {
    if obj.is_instance_of::<pyo3::types::PyFloat>() || obj.is_instance_of::<pyo3::types::PyInt>() {
        return Ok(Nested { masked: 0, entries: 1.0 });
    }
    if obj.is_instance(masked_array)? {
        let masked = ma.call_method1("count_masked", (obj,))?.extract()?;
        return Ok(Nested { masked, entries: obj.getattr("size")?.extract::<f64>().unwrap_or(1.0) });
    }
    if depth >= 64 || !(obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>()) {
        // Another sequence counts as its length (range(10**12) had numpy allocate until the
        // process aborted); an array's own size is numpy's to read.
        let sequence = !(obj.is_instance_of::<PyString>() || obj.hasattr("__array__").unwrap_or(false));
        let entries = obj.len().ok().filter(|_| sequence).map_or(1.0, |n| n as f64);
        return Ok(Nested { masked: 0, entries });
    }
    let id = obj.as_ptr() as usize;
    if let Some(known) = memo.get(&id) {
        return Ok(*known);
    }
    memo.insert(id, Nested::default());
    let mut total = Nested::default();
    for item in obj.try_iter()? {
        let inner = walk(&item?, (ma, masked_array), memo, depth + 1)?;
        total = Nested { masked: total.masked + inner.masked, entries: total.entries + inner.entries };
    }
    memo.insert(id, total);
    Ok(total)
}

/// Whether every entry of the object array `arr` is a Python int or float (bools are ints here;
/// [`no_bools`] refuses them afterwards).
fn all_ints_or_floats(arr: &Bound<'_, PyAny>) -> PyResult<bool> {
    for x in arr.call_method0("ravel")?.try_iter()? {
        let x = x?;
        if !(x.is_instance_of::<pyo3::types::PyInt>() || x.is_instance_of::<pyo3::types::PyFloat>()) {
            return Ok(false);
        }
    }
    Ok(true)
}

/// A numpy bool scalar (`np.True_`), which converts to a float as 1.0.
pub(crate) fn is_numpy_bool(obj: &Bound<'_, PyAny>) -> bool {
    obj.getattr("dtype").and_then(|d| d.getattr("kind")).is_ok_and(|k| k.eq("b").unwrap_or(false))
}

/// A bool among a list's numbers (numpy reads `[True, 1.5]` as `[1.0, 1.5]`) is a TypeError naming
/// its index, as a bool given for a number is.
fn no_bools(obj: &Bound<'_, PyAny>, arr: &Bound<'_, PyAny>, name: &str) -> PyResult<()> {
    let np = obj.py().import("numpy")?;
    let entries = np.call_method1("asarray", (obj, "object"))?.call_method0("ravel")?;
    let shape: Vec<usize> = arr.getattr("shape")?.extract()?;
    for (flat, x) in entries.try_iter()?.enumerate() {
        let x = x?;
        // A Python float or int is no numpy bool: asking it for `dtype` raised an AttributeError
        // per entry (11 s for ten million delays before their count was refused).
        let plain = x.is_instance_of::<pyo3::types::PyFloat>() || x.is_instance_of::<pyo3::types::PyInt>();
        if x.is_instance_of::<PyBool>() || (!plain && is_numpy_bool(&x)) {
            let (mut rest, mut at) = (flat, vec![0; shape.len()]);
            for (i, d) in shape.iter().enumerate().rev() {
                (at[i], rest) = (rest % d.max(&1), rest / d.max(&1));
            }
            let index: String = at.iter().map(|i| format!("[{i}]")).collect();
            return Err(type_error(&format!("{name}{index}"), "a real number", &x));
        }
    }
    Ok(())
}

fn shape_text(shape: &[usize]) -> String {
    match shape {
        [] => "a scalar".into(),
        [n] => format!("a 1-D array of shape ({n},)"),
        s => format!(
            "a {}-D array of shape ({})",
            s.len(),
            s.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(", ")
        ),
    }
}

fn finite(name: &str, index: &[usize], v: f64, kind: Kind, py: Python<'_>) -> PyResult<f64> {
    if v.is_finite() {
        return Ok(v);
    }
    let at: String = index.iter().map(|i| format!("[{i}]")).collect();
    Err(kind.err(py, format!("{name}{at}: expected a finite number, found {v}")))
}

/// A real matrix (2-D array-like: a list of rows, or a numpy array) with finite entries.
pub fn matrix(obj: &Bound<'_, PyAny>, name: &str, kind: Kind) -> PyResult<DMatrix<f64>> {
    let py = obj.py();
    let arr = real_array(obj, name, kind)?;
    if arr.ndim() != 2 {
        return Err(kind.err(
            py,
            format!(
                "{name}: expected a matrix (2-D array, e.g. [[1.0, 0.0], [0.0, 1.0]]), found {}; write each row in brackets",
                shape_text(arr.shape())
            ),
        ));
    }
    let view = arr.readonly();
    let a = view.as_array();
    let (r, c) = (a.shape()[0], a.shape()[1]);
    let mut M = DMatrix::zeros(r, c);
    for i in 0..r {
        for j in 0..c {
            M[(i, j)] = finite(name, &[i, j], a[[i, j]], kind, py)?;
        }
    }
    Ok(M)
}

/// A real vector (1-D array-like; a number counts as one entry) with finite entries.
pub fn vector(obj: &Bound<'_, PyAny>, name: &str, kind: Kind) -> PyResult<Vec<f64>> {
    one_dimensional(obj, name, kind, false)
}

/// Limits: one number (for every input) or a 1-D array-like of them, each finite or +∞ (no limit
/// on that input), as the CLI's `--u-limit 40,inf` takes them; NaN and −∞ are `kind`'s error naming
/// the entry (a limit ≤ 0 is the target's own check).
pub fn limits(obj: &Bound<'_, PyAny>, name: &str, kind: Kind) -> PyResult<Vec<f64>> {
    one_dimensional(obj, name, kind, true)
}

/// [`vector`], or with `limits` [`limits`]: +∞ taken, and a single number named without an index.
fn one_dimensional(obj: &Bound<'_, PyAny>, name: &str, kind: Kind, limits: bool) -> PyResult<Vec<f64>> {
    let py = obj.py();
    let arr = real_array(obj, name, kind)?;
    if arr.ndim() > 1 {
        let expected = if limits { "a number or a 1-D array of numbers" } else { "a 1-D array of numbers" };
        return Err(kind.err(py, format!("{name}: expected {expected}, found {}", shape_text(arr.shape()))));
    }
    let unindexed = limits && arr.ndim() == 0;
    let view = arr.readonly();
    let checked = |(i, &v): (usize, &f64)| match v {
        f64::INFINITY if limits => Ok(v),
        _ if unindexed => finite(name, &[], v, kind, py),
        _ => finite(name, &[i], v, kind, py),
    };
    view.as_array().iter().enumerate().map(checked).collect()
}

/// A str argument, or a TypeError naming it; a str with a lone surrogate (`"\ud800"`, which UTF-8 cannot hold) is a ScenarioError naming
/// it, not Python's UnicodeEncodeError.
/// [`text`] meant as TOML: a single line without `=` that is not a comment or a table header, and
/// so not TOML, but ends in `.toml` or names a file, is taken for a path given where the text goes
/// (a bare syntax error had named neither the argument nor the path), and `load` (the function
/// that reads a file) is named.
pub fn toml_text(obj: &Bound<'_, PyAny>, name: &str, load: &str) -> PyResult<String> {
    let text = text(obj, name)?;
    let line = text.trim();
    let not_toml = !line.is_empty() && !line.contains(['\n', '=']) && !line.starts_with(['#', '[']);
    if not_toml && (line.to_ascii_lowercase().ends_with(".toml") || std::path::Path::new(line).is_file()) {
        return Err(crate::errors::keyed(
            obj.py(),
            crate::errors::Kind::Scenario,
            format!("{name}: expected TOML text, found a file's path, {line:?}; read the file with {load}"),
            Some(name.into()),
        ));
    }
    Ok(text)
}

pub fn text(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<String> {
    if !obj.is_instance_of::<PyString>() {
        return Err(type_error(name, "a str", obj));
    }
    obj.extract().map_err(|_| {
        let s: String = obj.str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let at = s.chars().position(|c| c == char::REPLACEMENT_CHARACTER).unwrap_or(0);
        crate::errors::keyed(
            obj.py(),
            crate::errors::Kind::Scenario,
            format!("{name}: expected text that UTF-8 can hold, found a lone surrogate (a half of a UTF-16 pair) at character {at}; remove it, or decode the file with errors=\"replace\""),
            None,
        )
    })
}

/// A bool argument (True, False or a numpy bool; not an int), or a TypeError naming it.
pub fn flag(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<bool> {
    obj.extract::<bool>().map_err(|_| type_error(name, "a bool (True or False)", obj))
}

/// Extractors for `#[pyo3(from_py_with = …)]` parameters that have a Python default (`states=False`,
/// `prefix="quell"`): PyO3 would report their wrong type in its own words, the argument's name only
/// in a note; these raise the project's TypeError naming it.
pub mod argument {
    use super::{flag, text};
    use pyo3::prelude::*;
    use std::borrow::Cow;

    pub fn states(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
        flag(obj, "states")
    }
    pub fn check(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
        flag(obj, "check")
    }
    pub fn continuous(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
        flag(obj, "continuous")
    }
    pub fn fmu(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
        flag(obj, "fmu")
    }
    pub fn yes(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
        flag(obj, "yes")
    }
    pub fn prefix(obj: &Bound<'_, PyAny>) -> PyResult<Cow<'static, str>> {
        text(obj, "prefix").map(Cow::Owned)
    }
}

/// A list (any iterable but a str) of str, or a TypeError naming the argument or the entry;
/// `expected` describes the list ("a list of 3 names (str)"), `entry` an entry ("a str (a name)").
pub fn strings(obj: &Bound<'_, PyAny>, name: &str, expected: &str, entry: &str) -> PyResult<Vec<String>> {
    if obj.is_instance_of::<PyString>() {
        return Err(type_error(name, expected, obj));
    }
    let items = obj.try_iter().map_err(|_| type_error(name, expected, obj))?;
    items
        .enumerate()
        .map(|(i, item)| {
            let item = item?;
            let at = format!("{name}[{i}]");
            item.extract().map_err(|_| match item.is_instance_of::<PyString>() {
                // A str that is not valid Unicode (a lone surrogate): the right type, a bad value.
                true => Kind::Scenario.err(
                    item.py(),
                    format!("{at}: expected {entry} of valid Unicode, found a str with a lone surrogate ({}); names are written to UTF-8 files", item.repr().map_or_else(|_| "?".into(), |r| r.to_string())),
                ),
                false => type_error(&at, entry, &item),
            })
        })
        .collect()
}

/// A path argument (a str or an `os.PathLike`), or a TypeError naming it.
pub fn path(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<std::path::PathBuf> {
    if obj.is_instance_of::<PyString>() || obj.hasattr("__fspath__")? {
        return obj.extract().map_err(|_| type_error(name, "a path (str or os.PathLike)", obj));
    }
    Err(type_error(name, "a path (str or os.PathLike)", obj))
}

/// A real number (an int, a float or a numpy scalar; not a bool). An int beyond a float64's range
/// is `kind`'s error (a `ValueError` and a `QuellError`) with `.key` = `key`.
pub fn number(obj: &Bound<'_, PyAny>, name: &str, kind: Kind, key: &str) -> PyResult<f64> {
    if obj.is_instance_of::<PyString>() || obj.is_instance_of::<PyComplex>() || obj.is_instance_of::<PyBool>() {
        return Err(type_error(name, "a real number", obj));
    }
    obj.extract::<f64>().map_err(|_| {
        // An int is a real number: one beyond a float64's range is a value error, not a type's.
        if obj.is_instance_of::<pyo3::types::PyInt>() {
            let message = format!(
                "{name}: expected a real number within a float64's range (±1.8e308), found an integer of {} digits",
                decimal_digits(obj)
            );
            crate::errors::keyed(obj.py(), kind, message, Some(key.to_owned()))
        } else {
            type_error(name, "a real number", obj)
        }
    })
}

/// The number of decimal digits of a Python int, also beyond the 4,300 that `str()` refuses to
/// write (from its bit length: ⌊(b − 1)·log10 2⌋ + 1 is exact but at powers of ten's edges, where it
/// may be one short; "about" covers it there).
pub fn decimal_digits(obj: &Bound<'_, PyAny>) -> String {
    if let Ok(n) = obj.str().and_then(|s| s.len()) {
        return (n - usize::from(obj.lt(0).unwrap_or(false))).to_string();
    }
    let bits: u64 = obj.call_method0("bit_length").and_then(|b| b.extract()).unwrap_or(0);
    format!("about {}", ((bits.max(1) - 1) as f64 * std::f64::consts::LOG10_2).floor() as u64 + 1)
}

/// Whether `obj` is a sequence an argument takes: a list, a tuple, a range, a numpy array of at
/// least one dimension, or an array-like with `__array__` (a pandas Series, a torch tensor). Other
/// iterables are refused: a set has no order, bytes are not numbers, an iterator is used up by
/// reading, and a python-control system passed inside a dict had leaked python-control's own
/// OSError from its `__getitem__` (helper tryout, 2026-12-07).
pub fn is_sequence(obj: &Bound<'_, PyAny>) -> bool {
    if let Ok(a) = obj.cast::<numpy::PyUntypedArray>() {
        return a.ndim() > 0;
    }
    obj.is_instance_of::<PyList>()
        || obj.is_instance_of::<PyTuple>()
        || obj.is_instance_of::<pyo3::types::PyRange>()
        || (obj.hasattr("__array__").unwrap_or(false) && obj.hasattr("__len__").unwrap_or(false))
}

/// The items of a list argument ([`is_sequence`]); anything else is a TypeError naming `name` and
/// the expected `form`.
fn items<'py>(obj: &Bound<'py, PyAny>, name: &str, form: &str) -> PyResult<Bound<'py, PyIterator>> {
    if !is_sequence(obj) {
        return Err(type_error(name, form, obj));
    }
    obj.try_iter().map_err(|_| type_error(name, form, obj))
}

/// A list of poles: real numbers, Python complex numbers (a conjugate pair both listed), or
/// `[re, im]` with im > 0 meaning the pair re ± i·im (as in scenario files).
pub fn poles(obj: &Bound<'_, PyAny>, name: &str, kind: Kind) -> PyResult<Vec<Complex<f64>>> {
    let py = obj.py();
    let form = "a list of poles (numbers, complex numbers, or [re, im] pairs meaning re ± i·im)";
    let items = items(obj, name, form)?;
    let mut out = Vec::new();
    for (i, item) in items.enumerate() {
        let item = item?;
        let key = format!("{name}[{i}]");
        let pole = "a pole: a number, a complex number or [re, im] with im > 0";
        let bad = |what: String| kind.err(py, format!("{key}: expected {pole}, found {what}"));
        if item.is_instance_of::<PyString>()
            || item.is_instance_of::<PyBool>()
            || is_numpy_bool(&item)
            || item.is_none()
        {
            return Err(type_error(&key, pole, &item));
        }
        let numpy_complex =
            item.getattr("dtype").and_then(|d| d.getattr("kind")).is_ok_and(|k| k.eq("c").unwrap_or(false));
        if item.is_instance_of::<PyComplex>() || numpy_complex {
            let re: f64 = item.getattr("real")?.extract()?;
            let im: f64 = item.getattr("imag")?.extract()?;
            out.push(Complex::new(finite(&key, &[], re, kind, py)?, finite(&key, &[], im, kind, py)?));
        } else if let Ok(re) = item.extract::<f64>() {
            out.push(Complex::new(finite(&key, &[], re, kind, py)?, 0.0));
        } else if item.is_instance_of::<pyo3::types::PyInt>() {
            // An int beyond a float64's range: the ValueError that says so.
            out.push(Complex::new(number(&item, &key, kind, &key)?, 0.0));
        } else {
            if item.try_iter().is_err() {
                return Err(type_error(&key, pole, &item));
            }
            // An error naming an entry of the pair stands ("poles[3][1]: expected a finite number");
            // a pair of the wrong type is not a pole.
            let pair = vector(&item, &key, kind).map_err(|e| {
                let names_entry = e.value(py).str().is_ok_and(|m| m.to_string().starts_with(&format!("{key}[")));
                if e.is_instance_of::<PyTypeError>(py) && !names_entry {
                    type_error(&key, pole, &item)
                } else {
                    e
                }
            })?;
            let [re, im] = pair[..] else {
                return Err(bad(format!("{} entries", pair.len())));
            };
            if im > 0.0 {
                out.extend([Complex::new(re, im), Complex::new(re, -im)]);
            } else if im == 0.0 {
                return Err(kind.err(py, format!("{key}: [{re}, {im}] has imaginary part 0; write a real pole as a number ({re}), and a complex pair as [re, im] with im > 0")));
            } else {
                return Err(kind.err(py, format!("{key}: [{re}, {im}] has imaginary part {im} < 0; a pair [re, im] means re ± i·im, so write it as [{re}, {}]", -im)));
            }
        }
    }
    Ok(out)
}

/// One list of poles per channel or signal component.
pub fn pole_lists(obj: &Bound<'_, PyAny>, name: &str, kind: Kind) -> PyResult<Vec<Vec<Complex<f64>>>> {
    let py = obj.py();
    let form = "one list of poles per channel or component, e.g. [[-6, -2], [-4]]";
    let items = items(obj, name, form)?;
    let mut out = Vec::new();
    for (i, item) in items.enumerate() {
        let item = item?;
        if item.extract::<f64>().is_ok() || item.is_instance_of::<PyComplex>() {
            return Err(kind.err(py, format!("{name}: expected one list of poles per channel or component (e.g. [[-6, -2], [-4]]), found a flat list of numbers; put each one's poles in brackets")));
        }
        out.push(poles(&item, &format!("{name}[{i}]"), kind)?);
    }
    Ok(out)
}

/// A matrix as a new numpy array.
pub fn to_numpy<'py>(py: Python<'py>, M: &DMatrix<f64>) -> Bound<'py, PyArray2<f64>> {
    PyArray2::from_owned_array(py, Array2::from_shape_fn((M.nrows(), M.ncols()), |(i, j)| M[(i, j)]))
}

/// Complex values as a numpy complex128 vector.
pub fn complex_numpy<'py>(py: Python<'py>, z: &[Complex<f64>]) -> PyResult<Bound<'py, PyAny>> {
    let values: Vec<Bound<'py, PyComplex>> = z.iter().map(|c| PyComplex::from_doubles(py, c.re, c.im)).collect();
    py.import("numpy")?.call_method1("array", (values, "complex128"))
}

/// A slice as a new numpy vector.
pub fn vec_numpy<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// The TOML document of a pickle's text (this package's own `to_toml`): parsed without the 16 MiB
/// a file may hold; a text that is not TOML is a tampered pickle's `ScenarioError`.
pub fn pickled_document(py: Python<'_>, text: &str) -> PyResult<toml::Table> {
    text.parse::<toml::Table>().map_err(|e| {
        crate::errors::Kind::Scenario
            .err(py, format!("a pickled quell object whose text is not TOML ({e}); pickle it again"))
    })
}
