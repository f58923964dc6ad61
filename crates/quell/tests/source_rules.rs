//! Rules on the sources themselves, checked by reading them:
//! - no function of `crates/*/src` is longer than [`MAX_LINES`] lines unless its `fn` line says why
//!   (`// long: REASON`);
//! - no comment of any source file (sources, tests, benchmarks, Python, fuzz targets, scripts)
//!   points outside the repository (to an issue tracker, to notes or conversations that are not in
//!   it, or to what the code used to be);
//! - the library (`crates/quell/src`) names no command-line flag: its errors and docs speak of the
//!   library's keys, and each front end maps those to its own words;
//! - the crate docs of `lib.rs` name every public module and crate-root item in a section with an
//!   example.

use std::path::{Path, PathBuf};

/// Longest function body, in lines from the `fn` line to its closing brace.
const MAX_LINES: usize = 80;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every `.rs` file below `dir`.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The `.rs` files of every crate's `src/`.
fn sources() -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(root().join("crates")).unwrap().flatten() {
        let src = entry.path().join("src");
        if src.is_dir() {
            rust_files(&src, &mut out);
        }
    }
    assert!(out.len() > 30, "found only {} source files under {}", out.len(), root().display());
    out.sort();
    out
}

/// `text` with every comment, string and character literal blanked to spaces (newlines kept), so
/// that braces can be matched on what remains.
fn code_only(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = b.to_vec();
    let blank = |out: &mut Vec<u8>, from: usize, to: usize| {
        for c in &mut out[from..to] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
    };
    let mut i = 0;
    while i < b.len() {
        let start = i;
        if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            let mut depth = 0;
            while i < b.len() {
                if b[i..].starts_with(b"/*") {
                    depth += 1;
                    i += 2;
                } else if b[i..].starts_with(b"*/") {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if (b[i] == b'r' || b[i..].starts_with(b"br"))
            && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'))
            && {
                let j = i + if b[i] == b'b' { 2 } else { 1 };
                let hashes = b[j..].iter().take_while(|&&c| c == b'#').count();
                b.get(j + hashes) == Some(&b'"')
            }
        {
            let j = i + if b[i] == b'b' { 2 } else { 1 };
            let hashes = b[j..].iter().take_while(|&&c| c == b'#').count();
            let mut close = vec![b'"'];
            close.extend(std::iter::repeat_n(b'#', hashes));
            i = j + hashes + 1;
            while i < b.len() && !b[i..].starts_with(&close) {
                i += 1;
            }
            i += close.len();
        } else if b[i] == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
        } else if b[i] == b'\'' {
            // A character literal ('{', '\n', '\u{7b}'), or a lifetime ('a), which is left alone.
            if b.get(i + 1) == Some(&b'\\') {
                i += 2;
                while i < b.len() && b[i] != b'\'' {
                    i += 1;
                }
                i += 1;
            } else if let Some(len) = text[i + 1..].chars().next().map(char::len_utf8) {
                if b.get(i + 1 + len) == Some(&b'\'') {
                    i += len + 2;
                } else {
                    i += 1;
                    continue;
                }
            } else {
                i += 1;
            }
        } else {
            i += 1;
            continue;
        }
        let end = i.min(b.len());
        blank(&mut out, start, end);
        i = end;
    }
    String::from_utf8(out).expect("blanking keeps UTF-8 (only ASCII bytes and whole literals change)")
}

/// A function longer than [`MAX_LINES`]: where it starts and how long it is.
#[derive(Debug)]
struct Long {
    file: String,
    line: usize,
    name: String,
    lines: usize,
}

/// Functions of `text` longer than [`MAX_LINES`] whose `fn` line gives no `// long: REASON`.
fn long_functions(file: &str, text: &str) -> Vec<Long> {
    let code = code_only(text);
    let lines: Vec<&str> = code.lines().collect();
    let raw: Vec<&str> = text.lines().collect();
    // Byte offset of each line's start.
    let mut starts = vec![0];
    starts.extend(code.match_indices('\n').map(|(k, _)| k + 1));
    let mut found = Vec::new();
    for (l, line) in lines.iter().enumerate() {
        let Some(at) = find_fn(line) else { continue };
        let name: String =
            line[at + 3..].trim_start().chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        // The body opens at the first `{` after the signature, unless a `;` ends a declaration first.
        let from = starts[l] + at;
        let Some(open) = code[from..].find(['{', ';']).map(|k| from + k) else { continue };
        if code.as_bytes()[open] == b';' {
            continue;
        }
        let mut depth = 0usize;
        let mut close = None;
        for (k, c) in code[open..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        close = Some(open + k);
                        break;
                    }
                }
                _ => {}
            }
        }
        let close = close.unwrap_or_else(|| panic!("{file}:{}: unbalanced braces after fn {name}", l + 1));
        let last = starts.partition_point(|&s| s <= close) - 1;
        let length = last - l + 1;
        let reason = raw[l].split("// long:").nth(1).is_some_and(|r| !r.trim().is_empty());
        if length > MAX_LINES && !reason {
            found.push(Long { file: file.to_string(), line: l + 1, name, lines: length });
        }
    }
    found
}

/// Where the keyword `fn` of a function item starts on a (blanked) line, if one does.
fn find_fn(line: &str) -> Option<usize> {
    let at = line.find("fn ")?;
    let before = &line[..at];
    let prefix_ok = before.split_whitespace().all(|w| {
        ["pub", "const", "async", "unsafe", "extern", "default"].contains(&w)
            || w.starts_with("pub(")
            || w.starts_with('"')
    });
    (prefix_ok && (at == 0 || line.as_bytes()[at - 1] == b' ')).then_some(at)
}

fn relative(path: &Path) -> String {
    path.strip_prefix(root()).unwrap_or(path).display().to_string()
}

/// Long functions being split by their owners as this test lands: (file, fn, owner). Each is a
/// TODO of that owner; the entry goes when the function is split.
const BEING_SPLIT: &[(&str, &str, &str)] = &[];

#[test]
fn no_function_is_longer_than_80_lines_without_a_reason() {
    let mut long = Vec::new();
    for path in sources() {
        let text = std::fs::read_to_string(&path).unwrap();
        long.extend(long_functions(&relative(&path), &text));
    }
    long.retain(|f| !BEING_SPLIT.iter().any(|(file, name, _)| f.file == *file && f.name == *name));
    let list: Vec<String> =
        long.iter().map(|f| format!("{}:{} fn {} ({} lines)", f.file, f.line, f.name, f.lines)).collect();
    assert!(
        list.is_empty(),
        "functions over {MAX_LINES} lines; split them, or say why on the fn line with `// long: REASON`:\n{}",
        list.join("\n")
    );
}

#[test]
fn every_function_being_split_is_still_long() {
    // An entry whose function was split (or renamed) would excuse a later long function of that name.
    let stale: Vec<String> = BEING_SPLIT
        .iter()
        .filter(|(file, name, _)| {
            let text = std::fs::read_to_string(root().join(file)).unwrap_or_default();
            !long_functions(file, &text).iter().any(|f| f.name == *name)
        })
        .map(|(file, name, owner)| format!("{file} fn {name} ({owner})"))
        .collect();
    assert!(stale.is_empty(), "no longer over {MAX_LINES} lines; remove from BEING_SPLIT:\n{}", stale.join("\n"));
}

#[test]
fn the_scanner_measures_a_function_by_its_braces() {
    // 3 + 79 body lines + 1 = 83 lines, with braces in a string, a char, a comment and a raw string.
    let body: String = (0..79).map(|k| format!("    let _x{k} = \"}}\"; // }}\n")).collect();
    let text = format!("fn f() {{\n    let _c = '{{';\n    let _r = r#\"}}\"#;\n{body}}}\nfn g() {{}}\n");
    let long = long_functions("t.rs", &text);
    assert_eq!(long.len(), 1, "{long:?}");
    assert_eq!((long[0].name.as_str(), long[0].line, long[0].lines), ("f", 1, 83));
    let excused = text.replacen("fn f() {", "fn f() { // long: one table", 1);
    assert!(long_functions("t.rs", &excused).is_empty());
    let lifetimes = "fn h<'a>(x: &'a str) -> &'a str {\n    x\n}\n";
    assert!(long_functions("t.rs", lifetimes).is_empty());
}

/// Phrases that point outside the repository: to an issue tracker, to notes or a conversation that
/// are not part of it, or to an earlier version of the code. Spelled in pieces so that this file
/// does not match itself.
fn outside_phrases() -> Vec<String> {
    [
        ["iss", "ue #"].concat(),
        ["the no", "tes"].concat(),
        ["paper's no", "tes"].concat(),
        ["was an as", "sert"].concat(),
        ["previous ses", "sion"].concat(),
        ["this ses", "sion"].concat(),
        ["the coordi", "nator"].concat(),
        ["the re", "viewer"].concat(),
        ["as disc", "ussed"].concat(),
    ]
    .into_iter()
    .collect()
}

/// True when `line` cites an issue by number (the word, a space, then digits).
fn cites_an_issue(line: &str) -> bool {
    let lower = line.to_lowercase();
    lower.match_indices(&["iss", "ue "].concat()).any(|(k, m)| {
        let after = &lower[k + m.len()..];
        after.starts_with(|c: char| c.is_ascii_digit())
    })
}

/// Every source file of the repository a reader meets: the crates' sources, tests, benchmarks and
/// Python package, the fuzz targets and the scripts (not build outputs or test data).
fn every_source_file() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
            let path = entry.path();
            let name = entry.file_name();
            if path.is_dir() {
                if !["target", "data", ".git", "__pycache__", ".venv"].contains(&name.to_str().unwrap_or("")) {
                    walk(&path, out);
                }
            } else if path
                .extension()
                .is_some_and(|e| ["rs", "py", "pyi", "c", "h", "in", "sh"].contains(&e.to_str().unwrap_or("")))
            {
                out.push(path);
            }
        }
    }
    let mut out = Vec::new();
    for dir in ["crates", "fuzz", "scripts", ".ci"] {
        walk(&root().join(dir), &mut out);
    }
    out.sort();
    out
}

#[test]
fn no_comment_points_outside_the_repository() {
    let phrases = outside_phrases();
    let mut offenders = Vec::new();
    let files = every_source_file();
    assert!(files.len() > sources().len() + 20, "found only {} files", files.len());
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        for (l, line) in text.lines().enumerate() {
            let lower = line.to_lowercase();
            if cites_an_issue(line) || phrases.iter().any(|p| lower.contains(p.as_str())) {
                offenders.push(format!("{}:{}: {}", relative(&path), l + 1, line.trim()));
            }
        }
    }
    assert!(offenders.is_empty(), "state the fact or the equation instead:\n{}", offenders.join("\n"));
}

/// Lines of the library allowed to name a flag, each with its reason.
const FLAG_LINES: &[(&str, &str, &str)] = &[(
    "crates/quell/src/export/c.rs",
    "quell export SCENARIO --sample-time {T} --prefix {p} --precision {prec}",
    "the generated header's own text: how to regenerate it, a line of C output kept byte for byte",
)];

#[test]
fn the_library_names_no_command_line_flag() {
    let mut offenders = Vec::new();
    let mut files = Vec::new();
    rust_files(&root().join("crates/quell/src"), &mut files);
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        for (l, line) in text.lines().enumerate() {
            // `--name`: two dashes then a lower-case letter, not inside a longer run of dashes
            // (a rule `---`) or after a character that makes it arithmetic (`x--`).
            let b = line.as_bytes();
            let flag = (0..b.len().saturating_sub(2)).any(|k| {
                b[k] == b'-'
                    && b[k + 1] == b'-'
                    && b[k + 2].is_ascii_lowercase()
                    && (k == 0 || !(b[k - 1] == b'-' || b[k - 1].is_ascii_alphanumeric()))
            });
            let file = relative(&path);
            let allowed = FLAG_LINES.iter().any(|(f, text, _)| file == *f && line.contains(text));
            if flag && !allowed {
                offenders.push(format!("{}:{}: {}", relative(&path), l + 1, line.trim()));
            }
        }
    }
    assert!(
        offenders.is_empty(),
        "the library speaks of its keys, not of a front end's flags:\n{}",
        offenders.join("\n")
    );
}

/// The names `lib.rs` makes public at the crate root: its `pub mod NAME;` modules, and every name
/// of its `pub use PATH::NAME;` and `pub use PATH::{A, B};` re-exports.
fn public_root_names(lib: &str) -> (Vec<String>, Vec<String>) {
    let (mut modules, mut items) = (Vec::new(), Vec::new());
    for line in lib.lines().filter(|l| !l.starts_with(' ')) {
        if let Some(m) = line.strip_prefix("pub mod ").and_then(|m| m.strip_suffix(';')) {
            modules.push(m.to_string());
        } else if let Some(path) = line.strip_prefix("pub use ").and_then(|p| p.strip_suffix(';')) {
            let names = match path.split_once('{') {
                Some((_, list)) => list.trim_end_matches('}').split(',').map(str::trim).collect(),
                None => vec![path.rsplit("::").next().unwrap_or(path)],
            };
            items.extend(names.into_iter().filter(|n| !n.is_empty()).map(String::from));
        }
    }
    (modules, items)
}

/// The crate docs (`//!` of `lib.rs`) cut into sections, each from a line that opens with a bold
/// name (`**[`sim`]**: …`) to the next.
fn doc_sections(lib: &str) -> Vec<String> {
    let mut sections = vec![String::new()];
    for line in lib.lines().filter_map(|l| l.strip_prefix("//!")) {
        if line.trim_start().starts_with("**") {
            sections.push(String::new());
        }
        let last = sections.last_mut().expect("one section at least");
        last.push_str(line);
        last.push('\n');
    }
    sections
}

#[test]
fn the_crate_docs_list_every_public_module_and_root_item_with_an_example() {
    let lib = std::fs::read_to_string(root().join("crates/quell/src/lib.rs")).unwrap();
    let (modules, items) = public_root_names(&lib);
    assert!(modules.len() >= 10 && items.len() >= 15, "lib.rs: modules {modules:?}, items {items:?}");
    let sections = doc_sections(&lib);
    let shown = |name: &str| {
        let links = [format!("[`{name}`]"), format!("[`{name}()`]")];
        sections.iter().any(|s| s.contains("```") && links.iter().any(|l| s.contains(l.as_str())))
    };
    let missing: Vec<_> = modules.iter().chain(&items).filter(|n| !shown(n)).collect();
    assert!(
        missing.is_empty(),
        "name these in a section of lib.rs's crate docs that has an example (a ``` block): {missing:?}"
    );
}

#[test]
fn the_api_check_reads_modules_and_re_exports() {
    let lib = "pub mod a;\nmod b;\npub use x::{C, d};\npub use y::E;\npub mod z {\n    pub use q::F;\n}\n";
    assert_eq!(public_root_names(lib), (vec!["a".into()], vec!["C".into(), "d".into(), "E".into()]));
    let sections = doc_sections("//! intro\n//! **[`a`]**: one\n//! ```\n//! ```\n//! **[`C`]**: two\n");
    assert_eq!(sections.len(), 3);
    assert!(sections[1].contains("```") && !sections[2].contains("```"));
}
