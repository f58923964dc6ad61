//! Scenario files: the paper's example parses to the paper's numbers, and every row of
//! `docs/errors.md` has a test here that checks the key, a telling fragment of the message, and that
//! the documented message is the one the code produces.
#![allow(non_snake_case)]

use std::path::Path;

use nalgebra::{Complex, DMatrix};
use proptest::prelude::*;
use quell::scenario::exosystem::Exosystem;
use quell::scenario::{load_and_design, LoadError, Noise, Simulation, PAPER_EXAMPLE};
use quell::sim::Method;
use quell::{Component, Harmonic, ObserverChoice, Scenario};

const DOCS: &str = include_str!("../../../docs/errors.md");

/// The paper's example with each `(from, to)` replaced once; `from` must occur in it.
fn with(edits: &[(&str, &str)]) -> String {
    let mut text = PAPER_EXAMPLE.to_string();
    for (from, to) in edits {
        assert!(text.contains(from), "edit target not in the example: {from}");
        text = text.replacen(from, to, 1);
    }
    text
}

/// Loads `text` through the whole path (scenario, then design) and checks the error: its key, a
/// fragment of its message, and that `docs/errors.md` shows the message exactly.
fn check(text: &str, key: &str, fragment: &str) {
    check_upto(text, key, fragment, None);
}

/// Like [`check`], but `docs/errors.md` need only show the message up to `stop` (for numbers that
/// depend on a numerical method's tolerance).
fn check_upto(text: &str, key: &str, fragment: &str, stop: Option<&str>) {
    let e = match load_and_design(text) {
        Ok(_) => panic!("expected an error at {key}, but the scenario loaded"),
        Err(e) => e,
    };
    let full = e.to_string();
    if let LoadError::Scenario(s) = &e {
        assert_eq!(s.key, key, "{full}");
    }
    assert!(full.starts_with(&format!("{key}: ")), "key {key}: {full}");
    assert!(full.contains(fragment), "fragment {fragment:?} not in: {full}");
    let shown = match stop.and_then(|s| full.find(s)) {
        Some(i) => &full[..i],
        None => &full,
    };
    assert!(DOCS.contains(shown), "docs/errors.md does not show this message:\n{full}");
}

const A_LINE: &str = "A = [[-3.2, -1.7, -3.0], [2.8, 1.3, 4.0], [0.3, 0.3, -0.5]]";
const B_LINE: &str = "B = [[-2.0, 1.0], [2.0, -1.0], [1.0, 0.0]]\n";
const C_LINE: &str = "C = [[2.0, 2.0, 0.0], [2.0, 1.0, 2.0]]";
const D_LINE: &str = "D = [[1.0, -3.0], [2.0, 1.0], [3.0, 1.0]]\n";
const Q_LINE: &str = "Q = [[1.0, 2.0], [1.0, 0.0]]\n";
const DELAYS: &str = "delays = [1.0, 3.0]";
const X0: &str = "x0 = [0.0, 0.0, 0.0]";
const L_LINE: &str = "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619], [2.7762, -1.1783]]";
const CHANNEL: &str = "channel_poles = [[-6.0, -2.0], [-4.0]]";
const REF_FILTER: &str = "reference_filter_poles = [[-1.0, -6.0], [-9.0]]";
const DIST_FILTER: &str = "disturbance_filter_poles = [[-1.0, -3.0], [-1.0, -2.0, -3.0]]";
const MU: &str = "mu = [20.0, 30.0]";
const BETA: &str = "beta = 1.0 ";
const REFERENCE: &str = "[reference]                                            # g(t), m components\ncomponents = [ { harmonics = [{ amplitude = 3.0, frequency = 2.0, phase = 0.0 }] }, { bias = 2.0 } ]\n";
const REF_COMPONENTS: &str =
    "components = [ { harmonics = [{ amplitude = 3.0, frequency = 2.0, phase = 0.0 }] }, { bias = 2.0 } ]";
const DISTURBANCE: &str = "[disturbance]                                          # omega(t), k components\ncomponents = [ { harmonics = [{ amplitude = 1.0, frequency = 1.0 }] },\n               { bias = 1.0, harmonics = [{ amplitude = 2.0, frequency = 2.0 }] } ]\n";
const T_END: &str = "t_end = 100.0";
const OUTPUT_STEP: &str = "output_step = 0.1 ";
const SAMPLED: &str = "# sample_time = 0.001";

fn m(rows: &[&[f64]]) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), rows[0].len(), |r, c| rows[r][c])
}

fn real(p: &[f64]) -> Vec<Complex<f64>> {
    p.iter().map(|&x| Complex::new(x, 0.0)).collect()
}

// ----------------------------------------------------------------------------------------------
// Known answers

#[test]
fn paper_example_parses_into_the_papers_numbers() {
    let s = Scenario::from_toml(PAPER_EXAMPLE).unwrap();
    assert_eq!(s.name.as_deref(), Some("paper-example"));
    let p = &s.plant;
    assert_eq!(p.A, m(&[&[-3.2, -1.7, -3.0], &[2.8, 1.3, 4.0], &[0.3, 0.3, -0.5]]));
    assert_eq!(p.B, m(&[&[-2.0, 1.0], &[2.0, -1.0], &[1.0, 0.0]]));
    assert_eq!(p.C, m(&[&[2.0, 2.0, 0.0], &[2.0, 1.0, 2.0]]));
    assert_eq!(p.D, m(&[&[1.0, -3.0], &[2.0, 1.0], &[3.0, 1.0]]));
    assert_eq!(p.Q, m(&[&[1.0, 2.0], &[1.0, 0.0]]));
    assert_eq!(p.delays, vec![1.0, 3.0]);
    assert_eq!(p.x0.as_slice(), &[0.0, 0.0, 0.0]);
    let d = &s.design;
    assert_eq!(d.observer, ObserverChoice::Gain(m(&[&[-8.0988, 4.4574], &[10.6506, -5.0619], &[2.7762, -1.1783]])));
    assert_eq!(d.channel_poles, vec![real(&[-6.0, -2.0]), real(&[-4.0])]);
    assert_eq!(d.reference_filter_poles, vec![real(&[-1.0, -6.0]), real(&[-9.0])]);
    assert_eq!(d.disturbance_filter_poles, vec![real(&[-1.0, -3.0]), real(&[-1.0, -2.0, -3.0])]);
    assert_eq!(d.mu, vec![20.0, 30.0]);
    assert_eq!(d.beta, 1.0);
    // g(t) = [3 sin 2t, 2], ω(t) = [sin t, 1 + 2 sin 2t].
    for t in [0.0, 0.3, 1.7, 42.0] {
        let (mut g, mut w) = ([0.0; 2], [0.0; 2]);
        s.reference.eval_into(t, &mut g).unwrap();
        s.disturbance.eval_into(t, &mut w).unwrap();
        assert_eq!(g, [3.0 * (2.0 * t).sin(), 2.0]);
        assert_eq!(w, [t.sin(), 1.0 + 2.0 * (2.0 * t).sin()]);
    }
    assert_eq!(
        s.simulation,
        Simulation {
            t_end: 100.0,
            output_step: 0.1,
            output_step_given: true,
            rtol: 1e-9,
            atol: 1e-9,
            sample_time: None,
            method: Method::Auto,
            precision: quell::controller::Precision::F64,
        }
    );
    assert_eq!(s.noise, None);
}

#[test]
fn paper_example_file_reads_from_path_and_from_str() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper.toml");
    let a = Scenario::from_path(&path).unwrap();
    let b: Scenario = PAPER_EXAMPLE.parse().unwrap();
    assert_eq!(a.plant, b.plant);
    assert_eq!(a.design, b.design);
}

#[test]
fn fuzz_seeds_parse() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/scenario");
    let mut seeds = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.file_name().unwrap().to_string_lossy().starts_with("seed-") {
            Scenario::from_path(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            seeds += 1;
        }
    }
    assert!(seeds >= 4);
}

#[test]
fn pole_pairs_expand_into_both_conjugates() {
    let s = Scenario::from_toml(&with(&[
        (CHANNEL, "channel_poles = [[[-1.5, 2.0]], [-4.0]]"),
        (L_LINE, "observer_poles = [-2.0, [-3.0, 0.5]]"),
    ]))
    .unwrap();
    assert_eq!(s.design.channel_poles[0], vec![Complex::new(-1.5, 2.0), Complex::new(-1.5, -2.0)]);
    assert_eq!(
        s.design.observer,
        ObserverChoice::Poles(vec![Complex::new(-2.0, 0.0), Complex::new(-3.0, 0.5), Complex::new(-3.0, -0.5)])
    );
}

#[test]
fn integers_are_accepted_where_floats_are_expected() {
    let s = Scenario::from_toml(&with(&[
        (A_LINE, "A = [[-3, -1, -3], [2, 1, 4], [0, 0, -1]]"),
        (DELAYS, "delays = [1, 3]"),
        (MU, "mu = [20, 30]"),
        (BETA, "beta = 1 "),
        (CHANNEL, "channel_poles = [[-6, [-2, 1]], [-4]]"),
        (T_END, "t_end = 100"),
        (
            REF_COMPONENTS,
            "components = [ { harmonics = [{ amplitude = 3, frequency = 2, phase = 0 }] }, { bias = 2 } ]",
        ),
    ]))
    .unwrap();
    assert_eq!(s.plant.A[(1, 2)], 4.0);
    assert_eq!(s.plant.delays, vec![1.0, 3.0]);
    assert_eq!(s.design.mu, vec![20.0, 30.0]);
    assert_eq!(s.design.beta, 1.0);
    assert_eq!(s.design.channel_poles[0][1], Complex::new(-2.0, 1.0));
    assert_eq!(s.simulation.t_end, 100.0);
    assert_eq!(s.reference.components[1].bias, 2.0);
}

#[test]
fn defaults_for_optional_keys() {
    let s = Scenario::from_toml(&with(&[
        (X0, ""),
        ("name = \"paper-example\"", ""),
        ("[simulation]\nt_end = 100.0\noutput_step = 0.1     # rows of signals.csv at t = k * output_step\nrtol = 1e-9\natol = 1e-9\n", ""),
    ]))
    .unwrap();
    assert_eq!(s.name, None);
    assert_eq!(s.plant.x0.as_slice(), &[0.0; 3]);
    assert_eq!(s.simulation, Simulation::default());
    // output_step defaults to t_end/1000 here (the_default_output_step_is_scale_free).
    let s = Scenario::from_toml(&with(&[(T_END, "t_end = 0.05"), (OUTPUT_STEP, "")])).unwrap();
    assert!((s.simulation.output_step - 5e-5).abs() < 1e-18);
    // Phase defaults to 0, bias to 0, harmonics to none.
    assert_eq!(
        s.disturbance.components[0],
        Component { bias: 0.0, harmonics: vec![Harmonic { amplitude: 1.0, frequency: 1.0, phase: 0.0 }] }
    );
}

#[test]
fn no_disturbance_means_k_zero() {
    for (d, q) in [("", ""), ("D = []\n", "Q = []\n")] {
        let s = Scenario::from_toml(&with(&[(D_LINE, d), (Q_LINE, q), (DISTURBANCE, ""), (DIST_FILTER, "")])).unwrap();
        assert_eq!(s.plant.k(), 0);
        assert_eq!(s.plant.D.shape(), (3, 0));
        assert_eq!(s.plant.Q.shape(), (2, 0));
        assert!(s.disturbance.is_empty());
        assert!(s.design.disturbance_filter_poles.is_empty());
    }
}

#[test]
fn sampled_data_run_with_noise() {
    let text = with(&[(SAMPLED, "sample_time = 0.001")]) + "[noise]\nstd = [0.03, 0]\nseed = 7\n";
    let s = Scenario::from_toml(&text).unwrap();
    assert_eq!(s.simulation.sample_time, Some(0.001));
    assert_eq!(s.noise, Some(Noise::white(vec![0.03, 0.0], 7)));
}

#[test]
fn exosystem_dimension_counts_distinct_nonzero_harmonics_and_constant() {
    let h = |amplitude, frequency, phase| Harmonic { amplitude, frequency, phase };
    let c = |bias, harmonics| Component { bias, harmonics };
    let dim = |c: &Component| Exosystem::of(c).dim();
    assert_eq!(dim(&c(0.0, vec![])), 0);
    assert_eq!(dim(&c(2.0, vec![])), 1);
    assert_eq!(dim(&c(1.0, vec![h(2.0, 2.0, 0.0)])), 3);
    // Two harmonics at one frequency are one harmonic; a zero amplitude is none.
    assert_eq!(dim(&c(0.0, vec![h(1.0, 2.0, 0.0), h(2.0, 2.0, 1.0)])), 2);
    assert_eq!(dim(&c(0.0, vec![h(0.0, 3.0, 0.0)])), 0);
    // sin t + sin(t + π) = 0.
    assert_eq!(dim(&c(0.0, vec![h(1.0, 1.0, 0.0), h(1.0, 1.0, std::f64::consts::PI)])), 0);
    // A zero-frequency harmonic a·sin(φ) is a constant.
    assert_eq!(dim(&c(0.0, vec![h(1.0, 0.0, 1.0)])), 1);
    assert_eq!(dim(&c(0.0, vec![h(1.0, 0.0, 0.0)])), 0);
    assert_eq!(Exosystem::of(&c(1.0, vec![h(1.0, 1.0, 0.0), h(1.0, 2.0, 0.0)])).describe(), "2 harmonics + bias");
}

#[test]
fn error_display_is_key_colon_message() {
    let e = Scenario::from_toml(&with(&[(DELAYS, "delays = \"1, 3\"")])).unwrap_err();
    assert_eq!(e.to_string(), format!("{}: {}", e.key, e.message), "Display is key: message");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    /// Any edit of the example gives a scenario or an error with a key, never a panic.
    #[test]
    fn edits_never_panic(at in 0usize..PAPER_EXAMPLE.len(), len in 0usize..8, insert in "[\\[\\]{}=,.\"a-z0-9\\- \n]{0,6}") {
        let mut text = PAPER_EXAMPLE.to_string();
        let mut at = at;
        while !text.is_char_boundary(at) { at -= 1; }
        let mut end = (at + len).min(text.len());
        while !text.is_char_boundary(end) { end -= 1; }
        text.replace_range(at..end, &insert);
        if let Err(e) = Scenario::from_toml(&text) {
            prop_assert!(!e.key.is_empty() && !e.message.is_empty());
        }
    }
}

// ----------------------------------------------------------------------------------------------
// One test per row of docs/errors.md, in the same order.

#[test]
fn syntax_error() {
    check(&with(&[(C_LINE, "C = [[2.0, 2.0, 0.0], [2.0, 1.0, 2.0]")]), "syntax", "line 6, column");
}

#[test]
fn duplicate_key() {
    check(
        &with(&[(DELAYS, "delays = [1.0, 3.0]\ndelays = [1.0, 2.0]")]),
        "syntax",
        "duplicate key `delays`: a key may",
    );
}

#[test]
fn unknown_top_level_key() {
    check(
        &with(&[("name = ", "nmae = ")]),
        "nmae",
        "unknown key (did you mean `name`?); valid keys at the top level: name, plant, design",
    );
}

#[test]
fn unknown_key_in_table() {
    check(&with(&[(DELAYS, "delay = [1.0, 3.0]")]), "plant.delay", "did you mean `delays`?");
    // A discrete-time model's sample time is no misspelt D: the plant is continuous-time.
    check(&with(&[(DELAYS, "delays = [1.0, 3.0]\ndt = 0.01")]), "plant.dt", "a plant here is continuous-time");
}

#[test]
fn unknown_key_nested() {
    check(
        &with(&[("amplitude = 3.0, frequency", "amplitude = 3.0, freq")]),
        "reference.components[0].harmonics[0].freq",
        "valid keys in [reference.components[0].harmonics[0]]: amplitude, frequency, phase",
    );
}

#[test]
fn missing_table() {
    check(&with(&[(REFERENCE, "")]), "reference", "missing; required");
}

#[test]
fn missing_key() {
    check(&with(&[(B_LINE, "")]), "plant.B", "missing; required: the n×m input matrix");
}

#[test]
fn wrong_type() {
    check(&with(&[(DELAYS, "delays = \"1, 3\"")]), "plant.delays", "expected an array of numbers, found a string");
}

#[test]
fn wrong_type_of_entry() {
    check(&with(&[("[[-3.2, -1.7,", "[[-3.2, \"-1.7\",")]), "plant.A[0][1]", "expected a number, found a string");
}

#[test]
fn matrix_without_rows() {
    check(&with(&[(C_LINE, "C = [2.0, 2.0, 0.0]")]), "plant.C", "put each row in brackets");
}

#[test]
fn ragged_matrix() {
    check(&with(&[("[2.8, 1.3, 4.0]", "[2.8, 1.3]")]), "plant.A[1]", "expected 3 entries (n, the number of rows");
    // Row 0 of C is the short one: C's rows have n entries, n from A (row 1, which is right, had
    // been blamed "as in row 0").
    check(
        &with(&[(C_LINE, "C = [[2.0, 2.0], [2.0, 1.0, 2.0]]")]),
        "plant.C[0]",
        "expected 3 entries (n, from plant.A), found 2",
    );
    // B's columns set m: its rows are checked against the length the others have.
    check(
        &with(&[(B_LINE, "B = [[-2.0], [2.0, -1.0], [1.0, 0.0]]\n")]),
        "plant.B[0]",
        "(as in every other row), found 1",
    );
}

/// A ragged matrix is blamed on the row that is wrong: against the length another key fixes (Q's
/// k from D, the observer gain's m from B, a `[truth]` matrix's from its `[plant]` counterpart),
/// else against the length most rows have, and row 0's only where no length is more common.
#[test]
fn a_ragged_matrix_names_the_row_that_differs() {
    let error = |text: &str| match Scenario::from_toml(text) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("a ragged matrix was accepted:\n{text}"),
    };
    let cases = [
        (with(&[(Q_LINE, "Q = [[1.0], [1.0, 0.0]]\n")]), "plant.Q[0]: expected 2 entries (k, from plant.D), found 1"),
        (
            with(&[(L_LINE, "observer_gain = [[-8.0988], [10.6506, -5.0619], [2.7762, -1.1783]]")]),
            "design.observer_gain[0]: expected 2 entries (m, from plant.B), found 1",
        ),
        (
            format!("{PAPER_EXAMPLE}\n[truth]\nC = [[2.0, 2.0], [2.0, 1.0, 2.0]]\n"),
            "truth.C[0]: expected 3 entries (as plant.C), found 2",
        ),
        (
            with(&[(A_LINE, "A = [[-3.2, -1.7], [2.8, 1.3, 4.0], [0.3, 0.3, -0.5]]")]),
            "plant.A[0]: expected 3 entries (n, the number of rows of plant.A: A is n×n), found 2",
        ),
        // D sets k: one row of three against two rows of two is the odd one, wherever it is.
        (
            with(&[(D_LINE, "D = [[1.0, -3.0, 0.0], [2.0, 1.0], [3.0, 1.0]]\n")]),
            "plant.D[0]: expected 2 entries (as in every other row), found 3",
        ),
        // No length more common than every other: row 0's, as before.
        (
            with(&[(D_LINE, "D = [[1.0], [2.0, 1.0], [3.0, 1.0, 0.0]]\n")]),
            "plant.D[1]: expected 1 entry (as in row 0; every row of a matrix has the same length), found 2",
        ),
    ];
    for (text, expected) in cases {
        assert_eq!(error(&text), expected);
    }
    // Four rows, two of one length: "2 of its 4 rows", the first other row named.
    let four = "[[1.0, 0.0], [1.0], [0.0, 1.0], [1.0, 2.0, 3.0]]";
    let text = with(&[(
        A_LINE,
        "A = [[-1.0, 0.0, 0.0, 0.0], [0.0, -1.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [0.0, 0.0, 0.0, -1.0]]",
    )]);
    let e = error(&text.replace(B_LINE, &format!("B = {four}\n")));
    assert_eq!(
        e,
        "plant.B[1]: expected 2 entries (as in 2 of its 4 rows; every row of a matrix has the same length), found 1"
    );
}

#[test]
fn non_square_A() {
    check(
        &with(&[(A_LINE, "A = [[-3.2, -1.7], [2.8, 1.3], [0.3, 0.3]]")]),
        "plant.A",
        "expected 3×3 (n×n), found 3×2; A must be square",
    );
}

#[test]
fn wrong_shape() {
    check(&with(&[(C_LINE, "C = [[2.0, 2.0], [2.0, 1.0]]")]), "plant.C", "expected 2×3 (m×n), found 2×2");
    // Three outputs for two inputs: the square plant the method needs is named.
    check(
        &with(&[(C_LINE, "C = [[2.0, 2.0, 0.0], [2.0, 1.0, 2.0], [1.0, 0.0, 0.0]]")]),
        "plant.C",
        "found 3×3; m = 2 (columns of plant.B), n = 3 (rows of plant.A); the method decouples the plant into one channel per input, so it needs as many outputs as inputs",
    );
}

/// B written one row per input (its transpose) and D likewise: the expected size is the n rows
/// (B's own columns cannot tell m there), and the transpose is named.
#[test]
fn a_transposed_matrix_is_named_as_such() {
    check(
        &with(&[(B_LINE, "B = [[-2.0, 2.0, 1.0], [1.0, -1.0, 0.0]]\n")]),
        "plant.B",
        "expected 3 rows (n = 3, the rows of plant.A), found 2×3; it looks transposed: write it as 3×2",
    );
    check(
        &with(&[(D_LINE, "D = [[1.0, 2.0, 3.0], [-3.0, 1.0, 1.0]]\n")]),
        "plant.D",
        "expected 3 rows (n = 3, the rows of plant.A), found 2×3; it looks transposed: write it as 3×2",
    );
    // C as n×m: the transpose, not a square plant, is what is wrong.
    check(
        &with(&[(C_LINE, "C = [[2.0, 2.0], [2.0, 1.0], [0.0, 2.0]]")]),
        "plant.C",
        "found 3×2; m = 2 (columns of plant.B), n = 3 (rows of plant.A); it looks transposed: write it as 2×3",
    );
}

#[test]
fn wrong_shape_of_Q() {
    check(&with(&[(Q_LINE, "Q = [[1.0], [1.0]]\n")]), "plant.Q", "expected 2×2 (m×k), found 2×1");
}

#[test]
fn empty_plant() {
    check(&with(&[(A_LINE, "A = []")]), "plant.A", "at least one state");
}

#[test]
fn non_finite_entry() {
    check(&with(&[("[0.3, 0.3, -0.5]", "[0.3, nan, -0.5]")]), "plant.A[2][1]", "expected a finite number, found NaN");
}

#[test]
fn entry_too_large() {
    check(
        &with(&[("[0.3, 0.3, -0.5]", "[0.3, 0.3, -5e200]")]),
        "plant.A[2][2]",
        "expected a magnitude ≤ 1e150, found -5e200",
    );
}

#[test]
fn infinite_entry() {
    check(&with(&[(MU, "mu = [20.0, inf]")]), "design.mu[1]", "expected a finite number, found inf");
}

#[test]
fn negative_delay() {
    check(&with(&[(DELAYS, "delays = [1.0, -3.0]")]), "plant.delays[1]", "expected a finite delay ≥ 0, found -3");
}

#[test]
fn delay_count() {
    check(&with(&[(DELAYS, "delays = [1.0]")]), "plant.delays", "expected 2 entries (one per input");
}

#[test]
fn x0_count() {
    check(&with(&[(X0, "x0 = [0.0, 0.0]")]), "plant.x0", "expected 3 entries (one per state");
}

#[test]
fn missing_D_with_disturbance() {
    check(&with(&[(D_LINE, "")]), "plant.D", "[disturbance] has 2 components");
}

#[test]
fn missing_Q_with_D() {
    check(&with(&[(Q_LINE, "")]), "plant.Q", "write zeros");
}

#[test]
fn missing_disturbance_with_D() {
    check(&with(&[(DISTURBANCE, "")]), "disturbance", "or remove plant.D and plant.Q");
}

#[test]
fn signal_name_count() {
    check(&with(&[(X0, "x0 = [0.0, 0.0, 0.0]\noutputs = [\"a\", \"b\", \"c\"]")]), "plant.outputs", "(one per output)");
}

#[test]
fn duplicate_signal_name() {
    let names = "states = [\"level\", \"flow\", \"level\"]";
    check(&with(&[(X0, &format!("{X0}\n{names}"))]), "plant.states[2]", "names another signal too");
}

#[test]
fn empty_signal_name() {
    check(&with(&[(X0, &format!("{X0}\ninputs = [\"valve\", \" \"]"))]), "plant.inputs[1]", "give every input a name");
}

#[test]
fn signal_name_not_a_string() {
    check(&with(&[(X0, &format!("{X0}\ninputs = [1, 2]"))]), "plant.inputs[0]", "expected a string");
}

#[test]
fn control_character_in_a_name() {
    check(
        &with(&[(X0, &format!("{X0}\noutputs = [\"gap\\n#error\", \"b\"]"))]),
        "plant.outputs[0]",
        "remove the control character",
    );
    let named = PAPER_EXAMPLE.replacen("name = \"paper-example\"", "name = \"a\\u0000b\"", 1);
    let e = Scenario::from_toml(&named).unwrap_err();
    assert_eq!(e.key, "name", "{e}");
    // Unicode's noncharacters: U+FFFE and U+FFFF are not XML, and an FMU's model description with
    // one was refused by its importer (hostile review).
    for c in ["\\uFFFE", "\\uFFFF", "\\uFDD0", "\\U0010FFFF"] {
        let named = PAPER_EXAMPLE.replacen("name = \"paper-example\"", &format!("name = \"ctl{c}\""), 1);
        let e = Scenario::from_toml(&named).unwrap_err();
        assert!(e.key == "name" && e.to_string().ends_with("remove the noncharacter"), "{e}");
        let e = Scenario::from_toml(&with(&[(X0, &format!("{X0}\noutputs = [\"a{c}\", \"b\"]"))])).unwrap_err();
        assert!(e.key == "plant.outputs[0]" && e.to_string().ends_with("remove the noncharacter"), "{e}");
    }
    // Other characters beyond ASCII are names like any.
    let named =
        PAPER_EXAMPLE.replacen("name = \"paper-example\"", "name = \"Regelkreis \\uFFFD\\u00e9\\U0001F600\"", 1);
    assert!(Scenario::from_toml(&named).is_ok());
}

#[test]
fn unknown_time_unit() {
    check(
        &with(&[(X0, &format!("{X0}\ntime_unit = \"mins\""))]),
        "plant.time_unit",
        "(did you mean \"min\" (minutes)?)",
    );
}

#[test]
fn disturbance_component_count() {
    check(
        &with(&[("components = [ { harmonics = [{ amplitude = 1.0, frequency = 1.0 }] },\n", "components = [\n")]),
        "disturbance.components",
        "expected 2 components (one per column of plant.D, k = 2), found 1",
    );
}

#[test]
fn reference_component_count() {
    check(&with(&[(", { bias = 2.0 } ]", " ]")]), "reference.components", "expected 2 components (one per output");
}

#[test]
fn signal_too_large() {
    check(
        &with(&[("amplitude = 3.0, frequency = 2.0", "amplitude = 3e300, frequency = 2.0")]),
        "reference.components[0].harmonics[0].amplitude",
        "expected a magnitude ≤ 1e150, found 3e300; the loop's states scale with it",
    );
}

#[test]
fn negative_frequency() {
    check(
        &with(&[("frequency = 2.0, phase", "frequency = -2.0, phase")]),
        "reference.components[0].harmonics[0].frequency",
        "expected a frequency ≥ 0",
    );
}

#[test]
fn missing_amplitude() {
    check(
        &with(&[("amplitude = 1.0, frequency = 1.0", "frequency = 1.0")]),
        "disturbance.components[0].harmonics[0].amplitude",
        "missing",
    );
}

#[test]
fn both_observer_choices() {
    check(&with(&[(L_LINE, &format!("{L_LINE}\nobserver_poles = [-2.0, -3.0, -4.0]"))]), "design", "give exactly one");
}

#[test]
fn neither_observer_choice() {
    check(&with(&[(L_LINE, "")]), "design.observer_gain", "give exactly one of design.observer_gain");
}

#[test]
fn filter_orders_without_auto() {
    check(
        &with(&[(CHANNEL, &format!("{CHANNEL}\nreference_filter_orders = [2, 1]"))]),
        "design.reference_filter_orders",
        "read only by the automatic design (`auto_design`)",
    );
}

#[test]
fn real_pole_written_as_pair() {
    check(
        &with(&[(CHANNEL, "channel_poles = [[-6.0, [-2.0, 0.0]], [-4.0]]")]),
        "design.channel_poles[0][1]",
        "write a real pole as a number",
    );
}

#[test]
fn pair_with_negative_imaginary_part() {
    check(
        &with(&[(CHANNEL, "channel_poles = [[[-2.0, -1.0]], [-4.0]]")]),
        "design.channel_poles[0][0]",
        "write it as [-2, 1]",
    );
}

#[test]
fn pole_of_wrong_form() {
    check(
        &with(&[(REF_FILTER, "reference_filter_poles = [[[-1.0, 2.0, 3.0]], [-9.0]]")]),
        "design.reference_filter_poles[0][0]",
        "found an array of 3 entries",
    );
}

#[test]
fn flat_pole_lists() {
    check(
        &with(&[(CHANNEL, "channel_poles = [-6.0, -2.0, -4.0]")]),
        "design.channel_poles",
        "put each output's poles in brackets",
    );
}

#[test]
fn reference_internal_model_order() {
    check(
        &with(&[("{ bias = 2.0 }", "{ bias = 2.0, harmonics = [{ amplitude = 1.0, frequency = 5.0 }] }")]),
        "design.reference_filter_poles[1]",
        "reference component 2 (1 harmonic + bias) needs at least 3 filter poles (internal-model order); got 1",
    );
}

#[test]
fn disturbance_internal_model_order() {
    check(
        &with(&[(DIST_FILTER, "disturbance_filter_poles = [[-1.0, -3.0], [-1.0, -2.0]]")]),
        "design.disturbance_filter_poles[1]",
        "disturbance component 2 (1 harmonic + bias) needs at least 3 filter poles",
    );
}

#[test]
fn t_end_not_positive() {
    check(&with(&[(T_END, "t_end = 0")]), "simulation.t_end", "expected a final time > 0, found 0");
}

#[test]
fn output_step_not_positive() {
    check(&with(&[(OUTPUT_STEP, "output_step = -0.1 ")]), "simulation.output_step", "expected an output step > 0");
}

#[test]
fn output_step_beyond_t_end() {
    check(
        &with(&[(T_END, "t_end = 0.05")]),
        "simulation.output_step",
        "expected an output step ≤ t_end = 0.05, found 0.1",
    );
}

/// Without `output_step` the default is 1, 2 or 5 × 10^k within t_end/1000 and twenty rows a
/// period of the fastest harmonic (the paper's 2 rad/s: 0.157), at most 10⁶ rows, a whole number
/// of samples with a sample time: the same in any unit of time (a fixed 0.1 had recorded 2 rows of
/// a loop in ms written in s and 600,001 of one in s written in ms), and a model in a unit 1e6 times
/// shorter than its scale (t_end = 6e8) is not refused for 6e9 rows.
#[test]
fn the_default_output_step_is_scale_free() {
    let step = |edits: &[(&str, &str)], frequencies: f64| {
        let mut edits = edits.to_vec();
        edits.push((OUTPUT_STEP, ""));
        let text = with(&edits).replace("     # rows of signals.csv at t = k * output_step", "");
        let text = text
            .replace("frequency = 2.0", &format!("frequency = {:e}", 2.0 * frequencies))
            .replace("frequency = 1.0", &format!("frequency = {:e}", frequencies));
        Scenario::from_toml(&text).unwrap_or_else(|e| panic!("{edits:?}: {e}")).simulation.output_step
    };
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b;
    assert_eq!(step(&[], 1.0), 0.1);
    assert!(close(step(&[(T_END, "t_end = 0.05")], 1.0), 5e-5));
    assert_eq!(step(&[(T_END, "t_end = 1e5")], 1.0), 0.1);
    assert_eq!(step(&[(T_END, "t_end = 6e8")], 1.0), 600.0);
    // The paper's loop in ms, in µs, in h (t_end and every frequency rescaled): its 0.1 s.
    for (t_end, per) in [("1e5", 1e-3), ("1e8", 1e-6), ("0.027777777777777776", 3600.0)] {
        let h = step(&[(T_END, &format!("t_end = {t_end}"))], per);
        let want = 0.1 / per;
        let nice = [1.0, 2.0, 5.0].iter().any(|m| {
            let decade = 10f64.powf((h / m).log10().round());
            close(h, m * decade)
        });
        assert!(nice && h <= want * (1.0 + 1e-12) && h > want / 2.5, "t_end {t_end}: {h} against {want}");
        assert!(per != 1e-3 || close(h, 100.0), "{h}");
    }
    // With a sample time, the least whole multiple of it at or beyond 0.1.
    assert!(close(step(&[(T_END, "t_end = 100.0\nsample_time = 0.003")], 1.0), 0.102));
    // With no harmonics, t_end/1000.
    let text = with(&[(OUTPUT_STEP, "")]).replace("     # rows of signals.csv at t = k * output_step", "");
    let flat = text.replace("harmonics = [{ amplitude = 3.0, frequency = 2.0, phase = 0.0 }]", "bias = 0.5");
    let flat = flat.replace("{ harmonics = [{ amplitude = 1.0, frequency = 1.0 }] }", "{ bias = 0.3 }");
    let flat = flat.replace(", harmonics = [{ amplitude = 2.0, frequency = 2.0 }]", "");
    let s = Scenario::from_toml(&flat.replace(T_END, "t_end = 3000.0")).unwrap();
    assert!(s.reference.components.iter().all(|c| c.harmonics.is_empty()), "{flat}");
    assert_eq!(s.simulation.output_step, 2.0);
}

#[test]
fn output_step_too_many_samples() {
    check(
        &with(&[(OUTPUT_STEP, "output_step = 1e-6 ")]),
        "simulation.output_step",
        "t_end / output_step = 1.000e8 rows of signals.csv; at most 1e7 are kept; choose output_step ≥ 1e-5, or a shorter simulation.t_end",
    );
}

#[test]
fn tolerance_not_positive() {
    check(&with(&[("rtol = 1e-9", "rtol = 0.0")]), "simulation.rtol", "expected a relative tolerance > 0");
}

#[test]
fn tolerance_out_of_range() {
    let expected = "expected a relative tolerance from 100 ε = 2.22045e-14";
    check(&with(&[("rtol = 1e-9", "rtol = 1e-30")]), "simulation.rtol", expected);
}

#[test]
fn method_unknown() {
    check(
        &with(&[("atol = 1e-9\n", "atol = 1e-9\nmethod = \"imx\"\n")]),
        "simulation.method",
        "or \"imex\" (ARK4(3)6L[2]SA throughout, implicit in η̂), found \"imx\" (did you mean \"imex\"?)",
    );
}

#[test]
fn method_named_as_the_enum() {
    // The library's `Method::Implicit` is "imex" in files: the name says that only η̂ is implicit.
    check(
        &with(&[("atol = 1e-9\n", "atol = 1e-9\nmethod = \"Implicit\"\n")]),
        "simulation.method",
        "found \"Implicit\" (did you mean \"imex\"?)",
    );
}

#[test]
fn precision_unknown() {
    let sampled = with(&[(SAMPLED, "sample_time = 0.001\nprecision = \"f16\"")]);
    check(&sampled, "simulation.precision", "expected \"f64\" or \"f32\", found \"f16\"");
}

#[test]
fn precision_without_a_sample_time() {
    check(
        &with(&[("atol = 1e-9\n", "atol = 1e-9\nprecision = \"f32\"\n")]),
        "simulation.precision",
        "f32 is the discrete controller's arithmetic: give simulation.sample_time too",
    );
}

#[test]
fn sample_time_not_positive() {
    check(&with(&[(SAMPLED, "sample_time = -0.001")]), "simulation.sample_time", "expected a sampling period > 0");
}

#[test]
fn sample_time_too_many_steps() {
    check(
        &with(&[(SAMPLED, "sample_time = 1e-9")]),
        "simulation.sample_time",
        "t_end / sample_time = 1.000e11 controller steps; at most 1e10 are run; choose sample_time ≥ 1e-8",
    );
}

#[test]
fn noise_without_bandwidth() {
    check(&(PAPER_EXAMPLE.to_string() + "[noise]\nstd = [0.03, 0.02]\n"), "noise.bandwidth", "set noise.bandwidth");
}

#[test]
fn noise_bandwidth_not_positive() {
    check(
        &(PAPER_EXAMPLE.to_string() + "[noise]\nstd = [0.03, 0.02]\nbandwidth = 0\n"),
        "noise.bandwidth",
        "expected a bandwidth in cycles per unit of time (Hz for a plant in seconds) > 0, found 0",
    );
}

#[test]
fn noise_count() {
    check(
        &(with(&[(SAMPLED, "sample_time = 0.001")]) + "[noise]\nstd = [0.03]\n"),
        "noise.std",
        "expected 2 entries (one per output), found 1",
    );
}

#[test]
fn noise_negative() {
    check(
        &(with(&[(SAMPLED, "sample_time = 0.001")]) + "[noise]\nstd = [0.03, -0.02]\n"),
        "noise.std[1]",
        "expected a standard deviation ≥ 0",
    );
}

#[test]
fn negative_seed() {
    check(
        &(with(&[(SAMPLED, "sample_time = 0.001")]) + "[noise]\nstd = [0.03, 0.02]\nseed = -1\n"),
        "noise.seed",
        "expected an integer ≥ 0, found -1",
    );
}

#[test]
fn unreadable_file() {
    let e = Scenario::from_path(Path::new("no/such/scenario.toml")).unwrap_err();
    assert_eq!(e.key, "no/such/scenario.toml");
    assert!(e.message.starts_with("cannot read the file:"), "{e}");
    assert!(DOCS.contains("cannot read the file:"));
}

// Rows checked by Design::new before its Assumption-1 tests.

#[test]
fn channel_pole_list_count() {
    check(
        &with(&[(CHANNEL, "channel_poles = [[-6.0, -2.0]]")]),
        "design.channel_poles",
        "expected 2 entries (one per output), found 1",
    );
}

#[test]
fn reference_filter_list_count() {
    check(
        &with(&[(REF_FILTER, "reference_filter_poles = [[-1.0, -6.0]]")]),
        "design.reference_filter_poles",
        "expected 2 entries",
    );
}

#[test]
fn disturbance_filter_list_count() {
    check(&with(&[(DIST_FILTER, "")]), "design.disturbance_filter_poles", "expected 2 entries");
}

#[test]
fn mu_count() {
    check(&with(&[(MU, "mu = [20.0]")]), "design.mu", "expected 2 entries (one per channel), found 1");
}

#[test]
fn negative_mu() {
    check(&with(&[(MU, "mu = [20.0, -1.0]")]), "design.mu[1]", "expected a finite adaptation gain ≥ 0, found -1");
}

/// A component's size divides its block of ξ̂: one per component, each finite and > 0.
#[test]
fn regressor_sizes_are_checked() {
    let sized = |line: &str| format!("mu = [20.0, 30.0]\n{line}");
    check(
        &with(&[(MU, &sized("reference_sizes = [3.0]"))]),
        "design.reference_sizes",
        "expected 2 entries (one per reference component, or none for 1 each), found 1",
    );
    check(
        &with(&[(MU, &sized("disturbance_sizes = [1.0, 0.0]"))]),
        "design.disturbance_sizes[1]",
        "expected a size from 1e-150 to 1e150 (the component's expected peak, in its own units), found 0",
    );
    check_upto(
        &with(&[(MU, &sized("disturbance_sizes = [1.0, 1e-320]"))]),
        "design.disturbance_sizes[1]",
        "expected a size from 1e-150 to 1e150",
        Some(", found"),
    );
    check(
        &with(&[(MU, &sized("reference_sizes = []"))]),
        "design.reference_sizes",
        "expected one size per component, found an empty list; leave the key out for 1 each",
    );
}

#[test]
fn beta_not_positive() {
    check(&with(&[(BETA, "beta = 0.0 ")]), "design.beta", "expected a finite β > 0");
}

#[test]
fn channel_pole_not_hurwitz() {
    check(
        &with(&[(CHANNEL, "channel_poles = [[-6.0, 2.0], [-4.0]]")]),
        "design.channel_poles[0]",
        "pole 2.000000 is not in the open left half-plane",
    );
}

#[test]
fn filter_pole_not_hurwitz() {
    check(
        &with(&[(REF_FILTER, "reference_filter_poles = [[[0.0, 2.0]], [-9.0]]")]),
        "design.reference_filter_poles[0]",
        "internal-model filter poles must be Hurwitz",
    );
}

#[test]
fn empty_filter_pole_list() {
    // A component that is identically zero needs no internal model, but its list must not be empty.
    check(
        &with(&[
            ("[[-1.0, -3.0], [-1.0, -2.0, -3.0]]", "[[], [-1.0, -2.0, -3.0]]"),
            ("amplitude = 1.0, frequency = 1.0", "amplitude = 0.0, frequency = 1.0"),
        ]),
        "design.disturbance_filter_poles[0]",
        "the list is empty",
    );
}

#[test]
fn pole_out_of_span() {
    check(
        &with(&[(CHANNEL, "channel_poles = [[-1e9, -2.0], [-4.0]]")]),
        "design.channel_poles[0]",
        "out of the design's span of rates",
    );
}

#[test]
fn beta_out_of_span() {
    check(&with(&[(BETA, "beta = 1e-9 ")]), "design.beta", "expected 1.490116e-8 ≤ β ≤ 7.456540e6");
}

// Rows checked by Design::new after the controllability test (need `controllability`, `place`).

#[test]
fn channel_pole_count_vs_relative_degree() {
    check(
        &with(&[(CHANNEL, "channel_poles = [[-6.0], [-4.0]]")]),
        "design.channel_poles[0]",
        "channel 1 has relative degree 2, so it needs 2 poles; found 1",
    );
}

#[test]
fn regressor_scaling_unknown() {
    check(
        &with(&[(BETA, "beta = 1.0\nregressor_scaling = \"unit_dc\"\n")]),
        "design.regressor_scaling",
        "found \"unit_dc\"",
    );
}

#[test]
fn relative_degrees_count() {
    check(
        &with(&[(BETA, "beta = 1.0\nrelative_degrees = [2]\n")]),
        "design.relative_degrees",
        "expected 2 entries (one per output), found 1",
    );
}

#[test]
fn relative_degree_not_an_integer() {
    check(
        &with(&[(BETA, "beta = 1.0\nrelative_degrees = [2, 1.5]\n")]),
        "design.relative_degrees[1]",
        "expected a relative degree σ_i, an integer ≥ 1, found a floating-point number",
    );
    check(
        &with(&[(BETA, "beta = 1.0\nrelative_degrees = [2, 0]\n")]),
        "design.relative_degrees[1]",
        "expected a relative degree σ_i, an integer ≥ 1, found 0",
    );
}

#[test]
fn relative_degree_above_n() {
    check(
        &with(&[(BETA, "beta = 1.0\nrelative_degrees = [4, 1]\n")]),
        "design.relative_degrees[0]",
        "expected a relative degree 1 ≤ σ_i ≤ n = 3, found 4",
    );
}

#[test]
fn relative_degree_contradicts_plant() {
    // c_2 B = [0, 1] is clearly non-zero (cosine 1/(3·√2) = 0.236), so σ_2 = 2 is refused.
    check(
        &with(&[(BETA, "beta = 1.0\nrelative_degrees = [2, 2]\n"), (CHANNEL, "channel_poles = [[-6.0, -2.0], [-4.0, -5.0]]")]),
        "design.relative_degrees[1]",
        "σ_2 = 2 contradicts the plant: c_2 A^(0) B is clearly non-zero (largest cosine between c_2 A^(0) and a column of B, the states balanced: 2.89e-1",
    );
    // c_1 B = [0, 0] exactly, so σ_1 = 1 is refused.
    check(
        &with(&[(BETA, "beta = 1.0\nrelative_degrees = [1, 1]\n")]),
        "design.relative_degrees[0]",
        "σ_1 = 1 contradicts the plant: c_1 A^(0) B is clearly zero (largest cosine between c_1 A^(0) and a column of B, the states balanced: 0.00e0",
    );
}

#[test]
fn relative_degrees_given_round_trip_and_design_as_decided() {
    let text = with(&[(BETA, "beta = 1.0\nrelative_degrees = [2, 1]\n")]);
    let (s, d) = load_and_design(&text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.design.relative_degrees, Some(vec![2, 1]));
    let back = Scenario::from_toml(&s.to_toml()).unwrap();
    assert_eq!(back.design, s.design);
    assert!(s.to_toml().contains("relative_degrees = [2, 1]"), "{}", s.to_toml());
    // The paper's σ = (2, 1) given is the decided design, gain for gain.
    let (_, decided) = load_and_design(PAPER_EXAMPLE).unwrap();
    assert_eq!(d.K(), decided.K());
    assert_eq!(d.sigma(), decided.sigma());
    let given: Vec<_> = d.relative_degree_decisions().iter().map(|r| (r.decided, r.given)).collect();
    assert_eq!(given, vec![(Some(2), Some(2)), (Some(1), Some(1))]);
    assert!(decided.relative_degree_decisions().iter().all(|r| r.given.is_none()));
}

/// `[plant]` `inputs`, `outputs`, `states`: read in order, written back, and nothing else changes
/// (the same design, gain for gain); a file without them writes none and names its signals
/// `u_f[i]`, `y[i]`, `x[j]`.
#[test]
fn signal_names_round_trip_and_change_no_number() {
    let names = "inputs = [\"left\", \"right\"]\noutputs = [\"pitch\", \"roll\"]\nstates = [\"a\", \"b\", \"c\"]";
    let (s, d) = load_and_design(&with(&[(X0, &format!("{X0}\n{names}"))])).unwrap_or_else(|e| panic!("{e}"));
    let strings = |v: &[&str]| Some(v.iter().map(|x| x.to_string()).collect::<Vec<_>>());
    assert_eq!(s.names.inputs, strings(&["left", "right"]));
    assert_eq!(s.names.outputs, strings(&["pitch", "roll"]));
    assert_eq!(s.names.states, strings(&["a", "b", "c"]));
    let back = Scenario::from_toml(&s.to_toml()).unwrap();
    assert_eq!(back.names, s.names);
    let (paper, decided) = load_and_design(PAPER_EXAMPLE).unwrap();
    assert_eq!((d.K(), d.L(), d.F()), (decided.K(), decided.L(), decided.F()));
    assert!(paper.names.is_empty());
    let written = paper.to_toml();
    assert!(!["inputs", "outputs", "states"].iter().any(|k| written.contains(&format!("{k} ="))), "{written}");
    assert_eq!(paper.names.outputs(2), ["y[1]", "y[2]"]);
    assert_eq!(paper.names.inputs(2), ["u_f[1]", "u_f[2]"]);
    assert_eq!(paper.names.states(3), ["x[1]", "x[2]", "x[3]"]);
}

/// `[plant] time_unit` labels the model: by symbol or name, written back by symbol (seconds, the
/// default, not at all), shared by `[truth]`, and no number of the design changes; the messages
/// that state times use it.
#[test]
fn time_unit_labels_the_model_and_changes_no_number() {
    use quell::TimeUnit;
    let minutes = with(&[(X0, &format!("{X0}\ntime_unit = \"minutes\""))]);
    let (s, d) =
        load_and_design(&format!("{minutes}\n[truth]\ndelays = [1.0, 3.5]\n")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((s.plant.time_unit, s.true_plant().time_unit), (TimeUnit::Minutes, TimeUnit::Minutes));
    let written = s.to_toml();
    assert_eq!(written.matches("time_unit = \"min\"").count(), 1, "in [plant] only:\n{written}");
    let back = Scenario::from_toml(&written).unwrap();
    assert_eq!((back.plant, back.truth), (s.plant.clone(), s.truth.clone()));
    let (paper, decided) = load_and_design(PAPER_EXAMPLE).unwrap();
    assert_eq!(paper.plant.time_unit, TimeUnit::Seconds);
    assert!(!paper.to_toml().contains("time_unit"));
    assert_eq!((d.K(), d.L(), d.F(), d.mu()), (decided.K(), decided.L(), decided.F(), decided.mu()));
    for (given, unit) in [
        ("us", TimeUnit::Microseconds),
        ("µs", TimeUnit::Microseconds),
        ("ms", TimeUnit::Milliseconds),
        ("s", TimeUnit::Seconds),
        ("seconds", TimeUnit::Seconds),
        ("h", TimeUnit::Hours),
        ("hours", TimeUnit::Hours),
        ("d", TimeUnit::Days),
    ] {
        assert_eq!(TimeUnit::from_name(given), Ok(unit), "{given}");
    }
    let e = quell::Controller::new(&d, 0.3).unwrap_err().to_string();
    assert!(e.contains("τ = 1 min is not a whole number of samples of T_s = 0.3 min"), "{e}");
    // The FMU's logged refusals state times in the model's unit too (they said "s").
    use quell::export::{generate_fmu, ExportOptions, FmiVersion};
    let fmu = generate_fmu(&d, 0.5, &ExportOptions::default(), None, FmiVersion::V2).unwrap();
    let mut archive = zip::ZipArchive::new(std::io::Cursor::new(&fmu.bytes)).unwrap();
    let wrapper = std::io::read_to_string(archive.by_name("sources/quell_fmu.c").unwrap()).unwrap();
    assert!(wrapper.contains("communication step h = %g min is not a whole number of samples of T_s = %g min"));
    assert!(
        wrapper.contains("at t = %.15g min, but the controller's next sample is at %.15g min")
            && !wrapper.contains("%g s")
            && !wrapper.contains("%.15g s")
    );
}

/// Without the key a file means the paper's form (G_g1 = [[0, 1], [−6, −7]], l = e_2, Section VIII);
/// `"normalized"` runs the same filter at ω₀ = √6: G = [[0, √6], [−√6, −7]], l = [0, √6]ᵀ (closed
/// form of `RegressorScaling::Normalized` for poles −1, −6). Both round-trip through the writer.
#[test]
fn regressor_scaling_round_trip_and_filters() {
    use quell::design::RegressorScaling;
    let (paper, d) = load_and_design(PAPER_EXAMPLE).unwrap();
    assert_eq!(paper.design.regressor_scaling, RegressorScaling::Paper);
    assert_eq!(d.G_g().view((0, 0), (2, 2)), m(&[&[0.0, 1.0], &[-6.0, -7.0]]));
    assert_eq!(d.L_g().view((0, 0), (2, 1)), m(&[&[0.0], &[1.0]]));
    let text = with(&[(BETA, "beta = 1.0\nregressor_scaling = \"normalized\"\n")]);
    let (s, d) = load_and_design(&text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.design.regressor_scaling, RegressorScaling::Normalized);
    let r6 = 6f64.sqrt();
    let (G, l) = (d.G_g().view((0, 0), (2, 2)).into_owned(), d.L_g().view((0, 0), (2, 1)).into_owned());
    // Rounding of √6 and of the monic polynomial's coefficients: a few ulps of 7.
    assert!((G - m(&[&[0.0, r6], &[-r6, -7.0]])).amax() <= 1e-14, "{}", d.G_g());
    assert!((l - m(&[&[0.0], &[r6]])).amax() <= 1e-15, "{}", d.L_g());
    for s in [paper, s] {
        let back = Scenario::from_toml(&s.to_toml()).unwrap();
        assert_eq!(back.design, s.design);
    }
}

#[test]
fn observer_gain_shape() {
    check(
        &with(&[(L_LINE, "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619]]")]),
        "design.observer_gain",
        "expected a 3×2 matrix, found 2×2",
    );
}

#[test]
fn observer_gain_unstable() {
    check(
        &with(&[(L_LINE, "observer_gain = [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]")]),
        "design.observer_gain",
        "A − LC is not Hurwitz",
    );
}

#[test]
fn observer_pole_not_hurwitz() {
    check(
        &with(&[(L_LINE, "observer_poles = [-2.0, 3.0, -4.0]")]),
        "design.observer_poles",
        "observer poles must be Hurwitz",
    );
}

#[test]
fn observer_pole_count() {
    check(
        &with(&[(L_LINE, "observer_poles = [-2.0, -3.0]")]),
        "design.observer_poles",
        "expected 3 poles (one per state), found 2",
    );
}

#[test]
fn uncontrollable_plant() {
    // The third state of diag(-1, -2, 3) is reached by no input.
    check_upto(
        &with(&[
            (A_LINE, "A = [[-1.0, 0.0, 0.0], [0.0, -2.0, 0.0], [0.0, 0.0, 3.0]]"),
            (B_LINE, "B = [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]\n"),
        ]),
        "plant",
        "(A, B) is not controllable (Assumption 1): numerical rank 2 of 3",
        Some(" (tolerance"),
    );
    // The mode the inputs miss is named (the PBH test: [A − 3I, B] loses rank at λ = 3 only).
    let text = with(&[
        (A_LINE, "A = [[-1.0, 0.0, 0.0], [0.0, -2.0, 0.0], [0.0, 0.0, 3.0]]"),
        (B_LINE, "B = [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]\n"),
    ]);
    let e = load_and_design(&text).map(|_| ()).unwrap_err().to_string();
    assert!(e.ends_with("every mode must be reachable from the inputs; no input reaches the mode at 3.000000"), "{e}");
    // Likewise the mode no output shows: C reads the first two states of diag(−1, −2, −4) only.
    let text = with(&[
        (A_LINE, "A = [[-1.0, 0.0, 0.0], [0.0, -2.0, 0.0], [0.0, 0.0, -4.0]]"),
        (B_LINE, "B = [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]\n"),
        (C_LINE, "C = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]"),
    ]);
    let e = load_and_design(&text).map(|_| ()).unwrap_err().to_string();
    assert!(e.ends_with("every mode must show in the outputs; no output shows the mode at -4.000000"), "{e}");
}

#[test]
fn paper_example_designs() {
    let (_, design) = load_and_design(PAPER_EXAMPLE).unwrap();
    assert_eq!(design.sigma(), vec![2, 1]);
}

/// An empty file, or one without its plant, is told the plant is missing first (it had been told
/// the reference, read first because the plant's D depends on the disturbance).
#[test]
fn a_file_without_a_plant_is_told_so_first() {
    for text in ["", "name = \"x\"\n", "[reference]\ncomponents = [{ bias = 1.0 }]\n"] {
        let e = Scenario::from_toml(text).unwrap_err();
        assert_eq!(e.key, "plant", "{text:?}: {e}");
        assert!(e.to_string().starts_with("plant: missing; required: the [plant] table (A, B, C, delays"), "{e}");
    }
}

/// A[2][2] = −1e15 in the paper's plant: the rank test's tolerance (7.0, from ‖A‖) exceeds the
/// couplings of the other states (every mode is reachable by the PBH test in numpy), so "rank 2 of
/// 3" is a scaling verdict: said so, with the fix; a plant really uncontrollable keeps the plain
/// message. (A[0][0] = 1e15 had given "rank 0 of 3" from a tolerance above every entry of B; with B
/// scaled to A's size it is controllable.)
#[test]
fn a_badly_scaled_plant_is_not_just_called_uncontrollable() {
    let text = with(&[(A_LINE, "A = [[-3.2, -1.7, -3.0], [2.8, 1.3, 4.0], [0.3, 0.3, -1e15]]")]);
    let e = load_and_design(&text).map(|_| ()).unwrap_err().to_string();
    assert!(e.starts_with("plant: (A, B) is not controllable (Assumption 1): numerical rank 2 of 3"), "{e}");
    assert!(e.contains("counts couplings as small as 0.750000 as zero: the plant's numbers span too many decades for a rank test in double precision"), "{e}");
    let text = with(&[(A_LINE, "A = [[1e15, -1.7, -3.0], [2.8, 1.3, 4.0], [0.3, 0.3, -0.5]]")]);
    let e = load_and_design(&text).map(|_| ()).unwrap_err().to_string();
    assert!(!e.contains("not controllable") && !e.contains("not observable"), "{e}");
    // A near-integrator (a diagonal 1e-20) is no coupling: the mode no input reaches is named.
    let A = "A = [[-1.0, 1.0, 0.0], [0.0, 1e-20, 0.0], [0.0, 0.0, -5.0]]";
    let B = "B = [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]\n";
    let e = load_and_design(&with(&[(A_LINE, A), (B_LINE, B)])).map(|_| ()).unwrap_err().to_string();
    assert!(e.ends_with("no input reaches the mode at -5.000000"), "{e}");
    let A = "A = [[-1.0, 0.0, 0.0], [0.0, -2.0, 0.0], [0.0, 0.0, -3.0]]";
    let B = "B = [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]\n";
    let e = load_and_design(&with(&[(A_LINE, A), (B_LINE, B)])).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("not controllable") && !e.contains("decades"), "{e}");
}

/// A harmonic at frequency 0 is the constant a·sin(φ): with φ = 0 it adds nothing, a mistake the
/// reader names (a reference written that way had been identically 0); with φ = π/2 it is the
/// constant a, as a bias is.
#[test]
fn a_harmonic_at_frequency_zero_that_adds_nothing_is_refused() {
    let with = |phase: &str| {
        quell::scenario::Scenario::from_toml(&PAPER_EXAMPLE.replace(
            "{ amplitude = 3.0, frequency = 2.0, phase = 0.0 }",
            &format!("{{ amplitude = 3.0, frequency = 0.0, phase = {phase} }}"),
        ))
    };
    let e = with("0.0").unwrap_err().to_string();
    assert!(
        e.starts_with(
            "reference.components[0].harmonics[0].frequency: found 0 with phase 0, which makes this harmonic"
        ) && e.contains("amplitude·sin(phase) = 0"),
        "{e}"
    );
    let s = with("1.5707963267948966").unwrap();
    assert!((s.reference.components[0].eval(7.0) - 3.0).abs() < 1e-12);
}
