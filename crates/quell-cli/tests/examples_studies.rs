//! Every study file in examples/studies/ parses (their runs are the documented commands of
//! docs/studies.md; the benchmark alone is 10,000 runs).

use quell::study::Study;

#[test]
fn example_studies_parse() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/studies");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let study = Study::from_path(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(!study.is_empty());
            seen += 1;
        }
    }
    assert_eq!(seen, 4);
}
