//! `docs/architecture.md` names only what exists: every file or folder it cites in backticks, and
//! every `quell::module` it names, is checked against the tree, so the map cannot drift from the code.

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The backticked spans of a Markdown text.
fn code_spans(text: &str) -> Vec<&str> {
    text.split('`').skip(1).step_by(2).filter(|s| !s.is_empty()).collect()
}

/// A span that names a file or folder: it has a slash or a file extension, and no spaces or `::`.
fn is_path(span: &str) -> bool {
    let ext = [".rs", ".md", ".py", ".pyi", ".toml", ".c", ".h", ".json", ".csv"];
    !span.contains(' ') && !span.contains("::") && (span.contains('/') || ext.iter().any(|e| span.ends_with(e)))
}

/// Every file below `dir` (skipping build outputs) whose name is `name`.
fn find(dir: &Path, name: &str, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        let file = entry.file_name();
        if path.is_dir() {
            if file != "target" && file != ".git" {
                find(&path, name, out);
            }
        } else if file == name {
            out.push(path);
        }
    }
}

/// A path span resolves when it exists from the repository root, from one of the crates' roots,
/// or (a bare file name such as `hermite.rs`) when exactly that file name exists under `crates/`.
fn resolves(span: &str) -> bool {
    let root = root();
    let bases = [root.clone(), root.join("crates/quell"), root.join("crates/quell-cli"), root.join("crates/quell-py")];
    if bases.iter().any(|b| b.join(span.trim_end_matches('/')).exists()) {
        return true;
    }
    if !span.contains('/') {
        let mut hits = Vec::new();
        find(&root.join("crates"), span, &mut hits);
        return !hits.is_empty();
    }
    false
}

/// `quell::a::b` names a module `a` (then `b`) under `crates/quell/src`, or an item re-exported there.
fn module_exists(span: &str) -> bool {
    let src = root().join("crates/quell/src");
    let parts: Vec<&str> = span.trim_start_matches("quell::").split("::").collect();
    let mut dir = src.clone();
    for (k, part) in parts.iter().enumerate() {
        let part = part.trim_end_matches("()");
        let (file, folder) = (dir.join(format!("{part}.rs")), dir.join(part));
        if folder.join("mod.rs").exists() || folder.is_dir() {
            dir = folder;
        } else if file.exists() {
            dir = dir.join(part);
        } else {
            // Not a module: an item of the module reached so far (or of the crate root).
            let module = if k == 0 {
                src.join("lib.rs")
            } else if dir.is_dir() {
                dir.join("mod.rs")
            } else {
                dir.with_extension("rs")
            };
            let text = std::fs::read_to_string(&module).unwrap_or_default();
            return text.contains(part);
        }
    }
    true
}

#[test]
fn architecture_names_only_what_exists() {
    let text = std::fs::read_to_string(root().join("docs/architecture.md")).unwrap();
    let spans = code_spans(&text);
    let paths: Vec<&str> = spans.iter().copied().filter(|s| is_path(s)).collect();
    let modules: Vec<&str> = spans.iter().copied().filter(|s| s.starts_with("quell::")).collect();
    assert!(paths.len() >= 15, "docs/architecture.md names only {} paths", paths.len());
    let missing: Vec<_> = paths.iter().filter(|p| !resolves(p)).collect();
    assert!(missing.is_empty(), "docs/architecture.md names paths that do not exist: {missing:?}");
    let unknown: Vec<_> = modules.iter().filter(|m| !module_exists(m)).collect();
    assert!(unknown.is_empty(), "docs/architecture.md names modules or items that do not exist: {unknown:?}");
}

/// The text of every `.rs` file of the library, concatenated.
fn library_source() -> String {
    fn walk(dir: &Path, out: &mut String) {
        for entry in std::fs::read_dir(dir).unwrap().flatten() {
            let path = entry.path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push_str(&std::fs::read_to_string(&path).unwrap());
            }
        }
    }
    let mut text = String::new();
    walk(&root().join("crates/quell/src"), &mut text);
    text
}

/// True when `word` is a Rust identifier.
fn identifier(word: &str) -> bool {
    word.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && word.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// A span that names a Rust item of the library: `Name` or `Name::member`, with `Name` in
/// CamelCase (a type or trait), or `snake_name` (a function or constant such as `mat_vec`).
fn is_item(span: &str) -> bool {
    let parts: Vec<&str> = span.split("::").collect();
    !span.starts_with("quell::")
        && (1..=2).contains(&parts.len())
        && parts.iter().all(|p| identifier(p))
        && (parts.len() == 2 || parts[0].contains('_') || parts[0].starts_with(|c: char| c.is_ascii_uppercase()))
}

/// `Name` is defined (struct, enum, trait, type, fn or const), and `Name::member` has a function
/// or an enum variant `member`.
fn item_exists(source: &str, span: &str) -> bool {
    let defined = |name: &str| {
        ["struct", "enum", "trait", "type", "fn", "const", "static"].iter().any(|k| {
            source.contains(&format!("{k} {name}<"))
                || source.contains(&format!("{k} {name} "))
                || source.contains(&format!("{k} {name}("))
                || source.contains(&format!("{k} {name}:"))
        })
    };
    match span.split_once("::") {
        None => defined(span),
        Some((ty, member)) => {
            defined(ty)
                && (source.contains(&format!("fn {member}("))
                    || source.contains(&format!("fn {member}<"))
                    || [" {", "(", ",", " =", "\n"].iter().any(|end| source.contains(&format!("    {member}{end}"))))
        }
    }
}

#[test]
fn architecture_names_only_items_that_exist() {
    let text = std::fs::read_to_string(root().join("docs/architecture.md")).unwrap();
    let source = library_source();
    let items: Vec<&str> = code_spans(&text).into_iter().filter(|s| is_item(s)).collect();
    assert!(items.len() >= 15, "docs/architecture.md names only {} items", items.len());
    let unknown: Vec<_> = items.iter().filter(|i| !item_exists(&source, i)).collect();
    assert!(unknown.is_empty(), "docs/architecture.md names items the library does not define: {unknown:?}");
}

#[test]
fn architecture_maps_every_module_of_the_library() {
    let text = std::fs::read_to_string(root().join("docs/architecture.md")).unwrap();
    let lib = std::fs::read_to_string(root().join("crates/quell/src/lib.rs")).unwrap();
    let modules: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.trim().strip_prefix("pub mod ").or_else(|| l.trim().strip_prefix("mod ")))
        .filter_map(|l| l.strip_suffix(';'))
        .collect();
    assert!(modules.len() >= 10, "lib.rs declares only {modules:?}");
    let missing: Vec<_> = modules.iter().filter(|m| !text.contains(&format!("`quell::{m}`"))).collect();
    assert!(missing.is_empty(), "docs/architecture.md does not place these modules: {missing:?}");
}

#[test]
fn the_checker_catches_a_missing_path() {
    assert!(!resolves("crates/quell/src/no_such_module.rs"));
    assert!(!resolves("no_such_file.rs"));
    assert!(resolves("crates/quell/src/plant.rs"));
    assert!(!module_exists("quell::no_such_module"));
    assert!(module_exists("quell::sim"));
    let source = library_source();
    assert!(is_item("Run::of") && is_item("mat_vec") && is_item("Controller") && !is_item("quell::sim"));
    assert!(!is_item("plant") && !is_item("crates/quell/src/plant.rs"));
    assert!(item_exists(&source, "Run::of") && item_exists(&source, "RunStats::Sampled"));
    assert!(!item_exists(&source, "Run::no_such_method") && !item_exists(&source, "NoSuchType"));
}
