//! End-to-end tests of the `quell` binary: exit codes, messages, and the files `quell run` writes.
//! Every scenario in `examples/` is run here, so none of them rots.
#![allow(non_snake_case)]

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use quell::scenario::Scenario;
use serde_json::Value;
use tempfile::TempDir;

fn quell(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quell")).args(args).output().expect("the quell binary runs")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn examples_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn paper() -> String {
    examples_dir().join("paper.toml").display().to_string()
}

/// A fresh directory under the system's temp dir, removed when dropped.
fn temp_dir(tag: &str) -> TempDir {
    tempfile::Builder::new().prefix(&format!("quell-cli-test-{tag}-")).tempdir().unwrap()
}

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())))
        .unwrap_or_else(|e| panic!("{}: not JSON: {e}", path.display()))
}

fn matrix(v: &Value) -> Vec<Vec<f64>> {
    v.as_array()
        .expect("a matrix is an array of rows")
        .iter()
        .map(|r| r.as_array().expect("a row is an array").iter().map(|x| x.as_f64().unwrap()).collect())
        .collect()
}

fn assert_matrix_close(name: &str, got: &[Vec<f64>], want: &[&[f64]], tol: f64) {
    assert_eq!(got.len(), want.len(), "{name}: rows");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert_eq!(g.len(), w.len(), "{name}[{i}]: columns");
        for (j, (a, b)) in g.iter().zip(w.iter()).enumerate() {
            assert!((a - b).abs() <= tol, "{name}[{i}][{j}] = {a}, expected {b}");
        }
    }
}

/// Runs a command that must fail with exit 2 before printing anything on stdout; returns stderr.
fn input_error(args: &[&str]) -> String {
    let o = quell(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "quell {args:?}: exit status; stderr: {err}");
    assert!(o.stdout.is_empty(), "quell {args:?}: stdout should be empty, got {:?}", stdout(&o));
    assert!(!err.trim().is_empty(), "quell {args:?}: no message on stderr");
    err
}

/// `quell design` on the paper's example with one line of text replaced; returns stderr.
fn design_with_edit(tag: &str, from: &str, to: &str) -> String {
    let text = fs::read_to_string(paper()).unwrap();
    assert!(text.contains(from), "paper.toml no longer contains {from:?}");
    let dir = temp_dir(tag);
    let file = dir.path().join("scenario.toml");
    fs::write(&file, text.replacen(from, to, 1)).unwrap();
    let err = input_error(&["design", file.to_str().unwrap()]);
    assert_eq!(err.trim().lines().count(), 1, "one message expected, got: {err}");
    err
}

// ---------------------------------------------------------------------------------------------
// Help

#[test]
fn help_exits_0() {
    for args in [&["--help"][..], &["run", "--help"], &["design", "--help"]] {
        let o = quell(args);
        assert_eq!(o.status.code(), Some(0), "quell {args:?}: {}", stderr(&o));
        assert!(stdout(&o).contains("Usage"), "quell {args:?}: {}", stdout(&o));
    }
}

// ---------------------------------------------------------------------------------------------
// quell design

#[test]
fn design_text_on_paper_example() {
    let o = quell(&["design", &paper()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("σ = [2, 1]"), "{out}");
    for line in ["[    9.26000    9.26000    7.10000 ]", "[    5.00000    2.50000    5.00000 ]"] {
        assert!(out.contains(line), "K row {line:?} missing from:\n{out}");
    }
    for line in ["[    6.00000    0.00000 ]", "[    0.00000    4.00000 ]"] {
        assert!(out.contains(line), "F row {line:?} missing from:\n{out}");
    }
    assert!(out.contains("K (2×3)") && out.contains("F (2×2)"), "{out}");
}

/// The design report says what the controller needs on hardware before any sampled run or export:
/// the longest sample time (T_s·ρ ≤ 0.2; the paper's ρ = 9 /s is its fastest filter pole, so
/// 0.2/9 = 0.0222 s, and 0.02 s makes its delays of 1 and 3 s whole) and how far f32 moves the
/// poles (κ₂·6e-8). A disk servo's observer (κ₂ = 2.75e6, 16 % of itself in f32) is told to stay in
/// f64: an automatic maglev design with κ₂ = 1.5e7 had learnt it only at `quell export --precision
/// f32` (helper tryout, 2026-12-06).
#[test]
fn the_design_report_says_what_deployment_needs() {
    let o = quell(&["design", &paper()]);
    let out = stdout(&o);
    assert!(out.contains("\ndeployment (a sampled-data controller, docs/deployment.md):\n  sample time: T_s ≤ 0.0222 s (T_s·ρ ≤ 0.2), e.g. 0.02 s, which makes plant.delays whole and divides simulation.output_step; ρ = 9 /s, the loop's fastest rate (a bound the sampled loop needs, not one that suffices: a sampled run compares itself with its continuous loop and says where it departs)\n"), "{out}");
    assert!(
        out.contains(
            "  precision: f32 moves the poles by at most 0.00016 % (κ₂ = 2.75e1 × 6e-8): its poles allow f32, but the rounding its states accumulate over a run is not bounded by this: quell run --sample-time T_s --precision f32 measures it, as quell export --precision f32 does before it writes"
        ),
        "{out}"
    );
    let o = quell(&["design", "--json", &paper()]);
    let d: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(d["deployment"]["loop_rate"], 9.0);
    assert!((d["deployment"]["sample_time_at_most"].as_f64().unwrap() - 0.2 / 9.0).abs() < 1e-15);
    let hdd = Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/hdd-servo.toml");
    let out = stdout(&quell(&["design", hdd.to_str().unwrap()]));
    assert!(out.contains("  precision: f32 could move the poles of A − LC (the observer) by about 16 % (κ₂ = 2.75e6 × 6e-8, κ₂ in the states' coordinates as given; equilibrated, 7.25e4): export in f64 (the default)"), "{out}");
    // Distinct poles whose κ₂ as given f64 cannot resolve (an electro-hydraulic servo's pressure in
    // Pa beside positions in m) are not called defective (helper tryout, 2026-12-07).
    let hydraulic = Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/hydraulic-servo.toml");
    let out = stdout(&quell(&["design", hydraulic.to_str().unwrap()]));
    assert!(out.contains("  precision: A − LC (the observer)'s eigenvector matrix is too ill-conditioned in the states' coordinates as given for f64 to resolve (its poles are distinct: equilibrated κ₂ = 1.24e6)"), "{out}");
    assert!(!out.contains("defective"), "{out}");
    // Delays of 1.5 and 2.5 µs are whole at 0.5 µs, far below the bound: 100 s / 5e-7 s = 2e8
    // samples, which the report counts, and the delays, not that sample time, are the remedy.
    let dir = temp_dir("deployment-us");
    let text = fs::read_to_string(paper()).unwrap().replace("delays = [1.0, 3.0]", "delays = [1.5e-6, 2.5e-6]");
    let us = dir.path().join("us.toml");
    fs::write(&us, text).unwrap();
    let out = stdout(&quell(&["design", us.to_str().unwrap()]));
    assert!(out.contains("sample time: T_s ≤ 0.0222 s (T_s·ρ ≤ 0.2), but the longest that makes plant.delays whole is 5e-7 s (2.0e8 samples over t_end = 100 s): round plant.delays to whole multiples (0 included) of a sample time near the bound"), "{out}");
    // Where that sample time is a run of fewer than 1e7 samples it is offered: delays of 0.1 and
    // 0.3 ms are whole at 0.1 ms, 1e6 samples over 100 s.
    let text = fs::read_to_string(paper()).unwrap().replace("delays = [1.0, 3.0]", "delays = [1e-4, 3e-4]");
    fs::write(&us, text).unwrap();
    let out = stdout(&quell(&["design", us.to_str().unwrap()]));
    assert!(out.contains("e.g. 0.0001 s, which makes plant.delays whole"), "{out}");
}

#[test]
fn design_json_on_paper_example() {
    let o = quell(&["design", "--json", &paper()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let d: Value = serde_json::from_slice(&o.stdout).expect("stdout is one JSON object");
    for key in ["sigma", "K", "F", "L", "N", "observer_eigenvalues", "decoupled_eigenvalues"] {
        assert!(d.get(key).is_some(), "key {key} missing");
    }
    assert_eq!(d["sigma"], serde_json::json!([2, 1]));
    // Proposition 1 for the paper's A, B, C (docs/paper-example.md), not the printed K, F.
    assert_matrix_close("K", &matrix(&d["K"]), &[&[9.26, 9.26, 7.1], &[5.0, 2.5, 5.0]], 1e-9);
    assert_matrix_close("F", &matrix(&d["F"]), &[&[6.0, 0.0], &[0.0, 4.0]], 1e-9);
    assert_matrix_close("L", &matrix(&d["L"]), &[&[-8.0988, 4.4574], &[10.6506, -5.0619], &[2.7762, -1.1783]], 0.0);

    // Eigenvalues are [re, im] pairs; A − BK has exactly the channel poles {−6, −4, −2}.
    let eig = |key: &str| -> Vec<(f64, f64)> {
        d[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|z| {
                let z = z.as_array().expect("an eigenvalue is [re, im]");
                assert_eq!(z.len(), 2);
                (z[0].as_f64().unwrap(), z[1].as_f64().unwrap())
            })
            .collect()
    };
    let mut dec = eig("decoupled_eigenvalues");
    dec.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert_eq!(dec.len(), 3);
    for ((re, im), want) in dec.iter().zip([-6.0, -4.0, -2.0]) {
        assert!((re - want).abs() < 1e-9 && im.abs() < 1e-9, "eig(A − BK) ∋ {re}{im:+}i, expected {want}");
    }
    // κ₂ of the eigenvector matrices with rows and columns equilibrated: X = numpy.linalg.eig(M)[1]
    // for the paper's A − BK and (A − LC)ᵀ (the observer's by duality), then X's rows and columns
    // scaled to unit norm in turn 500 times, numpy.linalg.cond(X) (NumPy 2.4): 21.18 and 25.67
    // (4 digits; as given, without the scaling, 19.21 and 27.45).
    let kappa = |key: &str| d[key].as_f64().unwrap_or_else(|| panic!("{key} is a number"));
    assert!(
        (kappa("decoupled_eigenvector_condition") / 21.18 - 1.0).abs() < 1e-3,
        "{}",
        d["decoupled_eigenvector_condition"]
    );
    assert!(
        (kappa("observer_eigenvector_condition") / 25.67 - 1.0).abs() < 1e-3,
        "{}",
        d["observer_eigenvector_condition"]
    );
    let obs = eig("observer_eigenvalues");
    assert_eq!(obs.len(), 3);
    assert!(obs.iter().all(|(re, _)| *re < 0.0), "observer not Hurwitz: {obs:?}");

    // N D = L_ω, with D read from the scenario.
    let scenario = Scenario::from_path(Path::new(&paper())).unwrap();
    let D = &scenario.plant.D;
    let N = matrix(&d["N"]);
    let L_w = matrix(&d["L_w"]);
    assert_eq!(N.len(), L_w.len());
    assert_eq!(N[0].len(), D.nrows());
    for (i, row) in N.iter().enumerate() {
        for j in 0..D.ncols() {
            let nd: f64 = row.iter().enumerate().map(|(l, x)| x * D[(l, j)]).sum();
            assert!((nd - L_w[i][j]).abs() < 1e-9, "(N D)[{i}][{j}] = {nd}, L_ω = {}", L_w[i][j]);
        }
    }
}

/// The design report's pace of the adaptive law: the quadruple tank's filters at its own time scale
/// in the paper's form make both channels stiff (μ λ_max ≈ 2.7e6/s against ρ = 0.2/s), the
/// normalized form does not; the paper's example is not stiff. The figures themselves are checked
/// against the simulated Ω_i in `quell::diagnostics::estimate`'s tests.
#[test]
fn design_reports_the_adaptation_pace() {
    let tank = Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/quadruple-tank.toml");
    let text = std::fs::read_to_string(&tank).unwrap();
    let dir = temp_dir("pace");
    let normalized = dir.path().join("tank-normalized.toml");
    std::fs::write(&normalized, text.replace("beta = 10.0", "beta = 10.0\nregressor_scaling = \"normalized\""))
        .unwrap();
    for (file, scaling, stiff) in [
        (tank.to_str().unwrap(), "paper", true),
        (normalized.to_str().unwrap(), "normalized", false),
        (&paper(), "paper", false),
    ] {
        let o = quell(&["design", "--json", file]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let d: Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(d["regressor_scaling"], scaling);
        assert!(d["mu_meaning"].as_str().unwrap().contains("μ"));
        for (c, mu) in d["adaptation"].as_array().unwrap().iter().zip(d["mu"].as_array().unwrap()) {
            assert_eq!(c["stiff"], stiff, "{file}: {c}");
            let (rate, lambda) = (c["adaptation_rate"].as_f64().unwrap(), c["lambda_max_omega"].as_f64().unwrap());
            assert!((rate - mu.as_f64().unwrap() * lambda).abs() <= 1e-12 * rate, "{c}");
        }
        let text = stdout(&quell(&["design", file]));
        assert!(text.contains(&format!("regressor_scaling = \"{scaling}\"")), "{text}");
        assert_eq!(text.contains("⚠ stiff"), stiff, "{text}");
    }
}

/// The adaptation report's advice, which the run's diagnostics share: signals that excite nothing
/// (no flag, no "raise μ"; once a panic on an empty factor of Ω̄), a horizon too short for μ (raise
/// μ: following it clears the flag), a direction that no horizon within 1000× t_end converges
/// (the SI vessel: it was told to lengthen t_end to 2e17 s), and a direction that carries no error
/// (the paper with one disturbance component 1e-6 of its size: no flag); μ = 0 is named as no
/// adaptation.
#[test]
fn design_advice_names_the_cause_of_slow_adaptation() {
    let dir = temp_dir("slow");
    let text = fs::read_to_string(paper()).unwrap();
    let (start, end) = (text.find("[reference]").unwrap(), text.find("[simulation]").unwrap());
    let signals = |reference: &str, disturbance: &str| {
        format!(
            "{}[reference]\ncomponents = {reference}\n[disturbance]\ncomponents = {disturbance}\n{}",
            &text[..start],
            &text[end..]
        )
    };
    let zero = signals("[{ bias = 0.0 }, { bias = 0.0 }]", "[{ bias = 0.0 }, { bias = 0.0 }]");
    let sine = "[{ harmonics = [{ amplitude = 3.0, frequency = 2.0 }] }, { bias = 2.0 }]";
    let short = signals(sine, "[{ bias = 0.0 }, { bias = 0.0 }]").replace("t_end = 100.0", "t_end = 1.0");
    let faint = text.replace(
        "harmonics = [{ amplitude = 1.0, frequency = 1.0 }]",
        "harmonics = [{ amplitude = 1.0e-6, frequency = 1.0 }]",
    );
    let write = |name: &str, body: &str| {
        let path = dir.path().join(name);
        fs::write(&path, body).unwrap();
        path
    };
    let report = |path: &Path| {
        let o = quell(&["design", path.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        stdout(&o)
    };
    let zero_path = write("zero.toml", &zero);
    let zero = report(&zero_path);
    assert!(zero.contains("there is nothing to adapt to") && !zero.contains("weakly excited"), "{zero}");
    assert!(!zero.contains("raise design.mu") && !zero.contains("inf"), "{zero}");
    let run =
        quell(&["run", zero_path.to_str().unwrap(), "--no-plots", "--out", dir.path().join("run").to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
    assert!(stdout(&run).contains("no direction is excited") && !stdout(&run).contains("0 excited directions"));
    let short_report = report(&write("short.toml", &short));
    let advice =
        short_report.lines().find(|l| l.contains("→ design.mu[0]")).unwrap_or_else(|| panic!("{short_report}"));
    let raised: f64 =
        advice.split("raise design.mu[0] to ").nth(1).and_then(|r| r.split(' ').next()).unwrap().parse().unwrap();
    let followed =
        report(&write("followed.toml", &short.replace("mu = [20.0, 30.0]", &format!("mu = [{raised}, 30.0]"))));
    let channel_1 = followed.lines().find(|l| l.contains("channel 1: μ")).unwrap();
    assert!(!channel_1.contains("weakly excited"), "μ = {raised}: {followed}");
    let vessel = report(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/vessel-si.toml"));
    assert!(vessel.contains("past 1000× t_end: excite that direction more") && !vessel.contains("e17 s"), "{vessel}");
    let faint = report(&write("faint.toml", &faint));
    assert!(faint.contains("(excited rank 5 of 8)") && !faint.contains("weakly excited"), "{faint}");
    // μ = 0 turns a channel's adaptation off: said, where its convergence time reads ∞.
    let off = report(&write("off.toml", &text.replace("mu = [20.0, 30.0]", "mu = [20.0, 0.0]")));
    let channel_2 = off.lines().find(|l| l.contains("channel 2: μ")).unwrap();
    assert!(channel_2.contains("≈ ∞  (μ = 0: the channel does not adapt, η̂ keeps its start)"), "{off}");
    let channel_1 = off.lines().find(|l| l.contains("channel 1: μ")).unwrap();
    assert!(!channel_1.contains("μ = 0"), "{off}");
}

#[test]
fn design_missing_file_exits_2() {
    let err = input_error(&["design", "no/such/scenario.toml"]);
    assert!(err.contains("no/such/scenario.toml") && err.contains("cannot read"), "{err}");
}

/// `quell design` has no `--sample-time`: its message names the key alone (`quell run`'s names the
/// flag that overrides it as well).
#[test]
fn design_names_the_sample_time_key_without_a_flag_it_lacks() {
    let err = design_with_edit("sample-time", "[simulation]\n", "[simulation]\nsample_time = -0.001\n");
    assert!(err.starts_with("error: simulation.sample_time: expected"), "{err}");
}

#[test]
fn design_syntax_error_exits_2() {
    let err = design_with_edit("syntax", "delays = [1.0, 3.0]", "delays = [1.0 3.0]");
    assert!(err.contains("syntax: line "), "{err}");
}

#[test]
fn design_unknown_key_exits_2() {
    let err = design_with_edit("unknown", "delays = [1.0, 3.0]", "delay = [1.0, 3.0]");
    assert!(err.contains("plant.delay: unknown key") && err.contains("did you mean `delays`"), "{err}");
}

#[test]
fn a_study_given_as_a_scenario_is_named_a_study_with_the_command_that_runs_it() {
    let study = format!("{}/../../examples/studies/mismatch.toml", env!("CARGO_MANIFEST_DIR"));
    for command in ["run", "design"] {
        let err = input_error(&[command, &study]);
        assert!(err.contains("scenario: unknown key"), "{err}");
        assert!(
            err.contains(&format!("is a study, not a scenario: run it with `quell sweep {study} --out DIR`")),
            "{err}"
        );
    }
    // A study with [tune] is pointed to `quell tune`, and `quell sweep` refuses the [tune] it would
    // ignore.
    let tune = format!("{}/../../examples/studies/tune.toml", env!("CARGO_MANIFEST_DIR"));
    let err = input_error(&["run", &tune]);
    assert!(err.contains(&format!("is a study, not a scenario: run it with `quell tune {tune} --out DIR`")), "{err}");
    let err = input_error(&["sweep", &tune, "--out", "/nonexistent/never-written"]);
    assert!(err.contains(&format!("{tune}: tune: read by tuning only")), "{err}");
}

#[test]
fn a_study_naming_itself_as_its_scenario_is_named_a_study() {
    let dir = temp_dir("selfref");
    let study = dir.path().join("selfref.toml");
    fs::write(&study, "scenario = \"selfref.toml\"\n").unwrap();
    for command in ["sweep", "tune"] {
        let err = input_error(&[command, study.to_str().unwrap(), "--out", "/nonexistent/never-written"]);
        assert!(err.contains("scenario: selfref.toml: scenario: unknown key"), "{err}");
        assert!(err.contains("selfref.toml is a study, not a scenario: set `scenario` to a scenario file"), "{err}");
    }
}

#[test]
fn a_scenario_given_as_a_study_is_named_a_scenario_with_the_command_that_runs_it() {
    for command in ["sweep", "tune"] {
        let err = input_error(&[command, &paper(), "--out", "/nonexistent/never-written"]);
        assert!(err.contains("name: unknown key"), "{err}");
        assert!(
            err.contains("is a scenario, not a study") && err.contains(&format!("`quell run {}`", paper())),
            "{err}"
        );
    }
}

#[test]
fn design_wrong_shape_exits_2() {
    let err = design_with_edit("shape", "C = [[2.0, 2.0, 0.0], [2.0, 1.0, 2.0]]", "C = [[2.0, 2.0], [2.0, 1.0]]");
    assert!(err.contains("plant.C: expected 2×3"), "{err}");
}

#[test]
fn design_wrong_channel_pole_count_exits_2() {
    let err = design_with_edit("poles", "channel_poles = [[-6.0, -2.0], [-4.0]]", "channel_poles = [[-6.0], [-4.0]]");
    assert!(err.contains("design.channel_poles[0]") && err.contains("relative degree 2"), "{err}");
}

#[test]
fn design_unstable_observer_exits_2() {
    let err = design_with_edit(
        "observer",
        "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619], [2.7762, -1.1783]]",
        "observer_gain = [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]",
    );
    assert!(err.contains("design.observer_gain") && err.contains("not Hurwitz"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// quell run

fn csv_header(m: usize, q: usize) -> String {
    let mut h = vec!["t".to_string()];
    for s in ["y", "g", "e", "u", "uf"] {
        h.extend((1..=m).map(|i| format!("{s}{i}")));
    }
    for i in 1..=m {
        h.extend((1..=q).map(|j| format!("eta{i}_{j}")));
    }
    h.join(",")
}

/// Names in `dir` that look like the writers' temporary files (`.name.tmp…`).
fn leftovers(dir: &Path) -> Vec<String> {
    fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.') && n.contains(".tmp"))
        .collect()
}

#[test]
fn run_paper_example_writes_every_file() {
    let dir = temp_dir("run-paper");
    let o = quell(&["run", "--out", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // The report's convergence line: g and ω have the modes 0, ±1j and ±2j rad/s, five of the q = 8
    // regressor directions, so Ω̄_i is singular and the excited directions' time is the one given.
    let report = stdout(&o);
    assert_eq!(report.matches("1/(μλ_min) = ∞ (Ω̄ singular)").count(), 2, "{report}");
    assert_eq!(report.matches("the 5 excited directions").count(), 2, "{report}");

    // signals.csv: the header, and one row per t = k·0.1, k = 0..=1000.
    let csv = fs::read_to_string(dir.path().join("signals.csv")).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    assert_eq!(header, csv_header(2, 8));
    let cols = header.split(',').count();
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 1001);
    for (k, row) in rows.iter().enumerate() {
        let fields: Vec<f64> =
            row.split(',').map(|s| s.parse().unwrap_or_else(|e| panic!("row {k}: {s:?}: {e}"))).collect();
        assert_eq!(fields.len(), cols, "row {k}");
        assert!((fields[0] - k as f64 * 0.1).abs() < 1e-9, "row {k}: t = {}", fields[0]);
        assert!(fields.iter().all(|v| v.is_finite()), "row {k}: {row}");
    }

    // design.json is what `quell design --json` prints for the same scenario.
    let design = quell(&["design", "--json", &paper()]);
    assert_eq!(design.status.code(), Some(0));
    let printed: Value = serde_json::from_slice(&design.stdout).unwrap();
    assert_eq!(read_json(&dir.path().join("design.json")), printed);

    // summary.json: per-channel figures and solver statistics; the paper's loop converges.
    let s = read_json(&dir.path().join("summary.json"));
    assert_eq!(s["outcome"]["status"], "completed", "{s}");
    let channels = s["channels"].as_array().unwrap();
    assert_eq!(channels.len(), 2);
    for c in channels {
        for key in ["tail_max_e", "tail_rms_e", "max_u", "max_uf", "final_eta_norm"] {
            assert!(c[key].as_f64().is_some_and(f64::is_finite), "channels[].{key}: {c}");
        }
    }
    assert_eq!(s["stats"]["loop"], "continuous", "{s}");
    for key in ["steps", "rejected_steps", "rhs_evaluations", "breakpoints", "max_history_len"] {
        assert!(s["stats"][key].as_u64().is_some(), "stats.{key}: {s}");
    }
    let (steps, evals) = (s["stats"]["steps"].as_u64().unwrap(), s["stats"]["rhs_evaluations"].as_u64().unwrap());
    assert!(steps > 0 && evals >= 11 * steps, "DOP853 takes at least 11 evaluations a step: {s}");
    // Not stiff: DOP853 throughout, and no stretch at its bound.
    assert!(s["stats"]["implicit_steps"] == 0 && s["stats"]["switches"] == 0, "{s}");
    assert!(s["stats"].get("thrashed").is_none(), "{s}");
    let e1 = channels[0]["tail_max_e"].as_f64().unwrap();
    let e2 = channels[1]["tail_max_e"].as_f64().unwrap();
    assert!(e1 < 0.05, "tail max|e1| = {e1}");
    assert!(e2 < 0.005, "tail max|e2| = {e2}");

    // Plots: a PNG and an SVG per channel.
    for c in 1..=2 {
        let png = fs::read(dir.path().join(format!("channel{c}.png"))).unwrap();
        assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"), "channel{c}.png is not a PNG");
        assert!(png.len() > 10_000, "channel{c}.png has only {} bytes", png.len());
        let svg = fs::read_to_string(dir.path().join(format!("channel{c}.svg"))).unwrap();
        let head = svg.trim_start();
        assert!(head.starts_with("<svg") || head.starts_with("<?xml"), "channel{c}.svg starts with {:?}", &head[..20]);
        assert!(svg.len() > 10_000 && svg.trim_end().ends_with("</svg>"), "channel{c}.svg is truncated");
        // The actuator signal u_f (5) has its panel beside the adaptive command u's (25).
        for label in ["adaptive command (25)".to_string(), "plant input u_f (5)".into(), format!("uf{c}")] {
            assert!(svg.contains(&label), "channel{c}.svg has no series {label:?}");
        }
        // The time axis's ticks read 0, 20, …, 100, like the value axes' (not "20.0"); the axis
        // reaches a little past t_end, where the η̂ panel's legend sits beside the data.
        let ticks: Vec<&str> = svg.split("</text>").filter_map(|t| t.rsplit('>').next()).map(str::trim).collect();
        assert!(ticks.contains(&"40") && ticks.contains(&"100") && !ticks.contains(&"40.0"), "{ticks:?}");
    }
    assert!(leftovers(dir.path()).is_empty(), "temporary files left: {:?}", leftovers(dir.path()));
    assert!(!dir.path().join("channel3.png").exists());
}

#[test]
fn run_no_plots_writes_no_images() {
    let dir = temp_dir("no-plots");
    let o = quell(&["run", &paper(), "--no-plots", "--out", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for f in ["signals.csv", "design.json", "summary.json"] {
        assert!(dir.path().join(f).is_file(), "{f} missing");
    }
    assert!(!dir.path().join("channel1.png").exists() && !dir.path().join("channel1.svg").exists());
}

#[test]
fn run_out_unwritable_exits_2_before_work() {
    let dir = temp_dir("out-file");
    let file = dir.path().join("a-file");
    fs::write(&file, b"not a directory").unwrap();
    let under_file = file.join("sub");
    for out in [Path::new("/proc/forbidden"), file.as_path(), under_file.as_path()] {
        let o = quell(&["run", "--out", out.to_str().unwrap()]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "--out {}: {err}", out.display());
        assert!(err.contains("--out"), "--out {}: {err}", out.display());
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        // Before any work: no simulation summary.
        assert!(!stdout(&o).contains("channel 1:") && !err.contains("wrote"), "{err}");
    }
    assert_eq!(fs::read(&file).unwrap(), b"not a directory", "the file used as --out was changed");
}

#[test]
fn run_sample_time_not_dividing_a_delay_exits_2() {
    let dir = temp_dir("ts-03");
    let out = dir.path().join("out");
    let err = input_error(&["run", "--sample-time", "0.3", "--out", out.to_str().unwrap()]);
    assert!(err.contains("channel 1"), "{err}");
    // 1/3 s makes the delays (1 s, 3 s) whole but not the output step (0.1 s), whose check then
    // refused it; 0.1 s makes both whole.
    assert!(
        err.contains("nearest valid sample time that also divides simulation.output_step = 0.1 s (a run's rows fall on samples) is 0.1 s"),
        "{err}"
    );
    assert!(!out.join("signals.csv").exists());
}

#[test]
fn run_sample_time_flag_the_output_step_is_not_a_multiple_of_names_both() {
    // paper.toml records every 0.1 s. `--sample-time 0.2` stopped with "simulation.output_step:
    // expected a whole multiple of sample_time", a key the user had not touched, and no way out.
    let dir = temp_dir("ts-output-step");
    let out = dir.path().join("out");
    for (flag, ratio, divisor, multiple) in
        [("0.2", "0.500000", "0.1 s", "0.2 s"), ("0.04", "2.500000", "0.025 s", "0.12 s")]
    {
        let err = input_error(&["run", "--sample-time", flag, "--no-plots", "--out", out.to_str().unwrap()]);
        assert!(err.starts_with(&format!("error: --sample-time {flag}: simulation.output_step = 0.1 s")), "{err}");
        // The nearest fixes, by hand: 0.1 / ceil(0.1 / T) divides 0.1 (0.1/3 has no short decimal
        // form, so the longest round divisor below 0.04, 0.025); T·round(0.1 / T) is a multiple.
        assert!(err.contains(&format!("({ratio} samples")) && err.contains(&format!("e.g. {divisor}")), "{err}");
        assert!(err.contains(&format!("multiple of the sample time, e.g. {multiple}")), "{err}");
        assert!(!out.exists(), "--out was touched");
    }
    // An output step given by --output-step is named as the flag's (it had read "from the scenario file").
    let err = input_error(&[
        "run",
        "--sample-time",
        "0.2",
        "--output-step",
        "0.3",
        "--no-plots",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        err.starts_with("error: --sample-time 0.2: simulation.output_step (--output-step) = 0.3 s is not"),
        "{err}"
    );
    // A divisor of the output step is accepted (0.025 s: 4 samples a row, delays 40 and 120 samples).
    let o = quell(&["run", "--sample-time", "0.025", "--no-plots", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// The values a message offers after "e.g. ", in order (as typed back, without the unit).
fn offered(message: &str) -> Vec<String> {
    message.split("e.g. ").skip(1).filter_map(|r| r.split(' ').next()).map(str::to_string).collect()
}

/// Delays that no sample time makes whole together with the output step (1.0000001 and 3.0000003 s
/// beside 0.1 s; 1/60 min written to six digits beside 0.5 min in the tryout): `quell design`
/// offers the delays' sample time with the output step to set beside it, `quell run
/// --sample-time` at it offers that output step alone (it had offered 0.1/⌈0.1/T⌉, which the
/// delays' check refused), and the two run.
#[test]
fn run_sample_time_flag_offers_the_output_step_where_no_divisor_makes_the_delays_whole() {
    let dir = temp_dir("ts-no-divisor");
    let text = fs::read_to_string(paper()).unwrap().replace("delays = [1.0, 3.0]", "delays = [1.0000001, 3.0000003]");
    let file = dir.path().join("delays.toml");
    fs::write(&file, text).unwrap();
    let (file, out) = (file.to_str().unwrap(), dir.path().join("out"));
    let out = out.to_str().unwrap();
    let report = stdout(&quell(&["design", file]));
    let line = report.lines().find(|l| l.contains("sample time: T_s")).unwrap_or_else(|| panic!("{report}"));
    assert!(line.contains("and none within the bound also divides simulation.output_step = 0.1 s"), "{line}");
    let [t_s, step] = &offered(line)[..] else { panic!("{line}") };
    let err = input_error(&["run", file, "--sample-time", t_s, "--no-plots", "--out", out]);
    assert!(!err.contains("give a --sample-time") && err.contains("that divides it makes plant.delays whole"), "{err}");
    assert_eq!(offered(&err), [step.as_str()], "{err}");
    let o =
        quell(&["run", file, "--sample-time", t_s, "--output-step", step, "--t-end", "2", "--no-plots", "--out", out]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

#[test]
fn design_of_a_12_state_chain_observer_is_accepted_with_its_fragility() {
    // The observer of a 12-state integrator chain with poles −2, −2.7, …, −9.7 was refused: "A − LC
    // is not Hurwitz (eigenvalues −9.7, …, −2.0)". Now designed (exit 0), eig(A − LC) shown at the
    // requested poles (to the 6 decimals printed) and the fragility (κ₂ ≫ 1e8) reported.
    let n = 12;
    let rows = |f: &dyn Fn(usize, usize) -> f64, r: usize, c: usize| {
        let row = |i| format!("[{}]", (0..c).map(|j| format!("{:.1}", f(i, j))).collect::<Vec<_>>().join(", "));
        format!("[{}]", (0..r).map(row).collect::<Vec<_>>().join(", "))
    };
    let poles: Vec<String> = (0..n).map(|j| format!("{:.1}", -2.0 - 0.7 * j as f64)).collect();
    let channel: Vec<String> = (0..n).map(|j| format!("{:.1}", -1.0 - 0.5 * j as f64)).collect();
    let text = format!(
        "[plant]\nA = {}\nB = {}\nC = {}\ndelays = [0.0]\n[design]\nobserver_poles = [{}]\nchannel_poles = [[{}]]\n\
         reference_filter_poles = [[-1.0]]\nmu = [1.0]\nbeta = 1.0\n[reference]\ncomponents = [{{ bias = 1.0 }}]\n",
        rows(&|r, c| if c == r + 1 { 1.0 } else { 0.0 }, n, n),
        rows(&|r, _| if r + 1 == n { 1.0 } else { 0.0 }, n, 1),
        rows(&|_, c| if c == 0 { 1.0 } else { 0.0 }, 1, n),
        poles.join(", "),
        channel.join(", "),
    );
    let dir = temp_dir("chain12");
    let file = dir.path().join("chain.toml");
    fs::write(&file, text).unwrap();
    let o = quell(&["design", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("fragile observer gain") && out.contains("κ₂ = "), "{out}");
    for p in &poles {
        assert!(out.contains(&format!("{p}00000")), "pole {p} not among eig(A − LC) in:\n{out}");
    }
}

#[test]
fn run_negative_sample_time_exits_2() {
    let dir = temp_dir("ts-neg");
    let out = dir.path().join("out");
    // `--sample-time -1` is a usage error (clap reads -1 as a flag); `=-1` reaches the check.
    for args in [&["run", "--sample-time", "-1"][..], &["run", "--sample-time=-1"], &["run", "--sample-time=0"]] {
        let mut args = args.to_vec();
        args.extend(["--out", out.to_str().unwrap()]);
        let err = input_error(&args);
        assert!(err.contains("sample-time") || err.contains("-1"), "quell {args:?}: {err}");
    }
    let err = input_error(&["run", "--sample-time=-1", "--out", out.to_str().unwrap()]);
    assert!(err.contains("--sample-time") && err.contains("> 0"), "{err}");
    assert!(!out.join("signals.csv").exists());
}

#[test]
fn run_missing_scenario_exits_2() {
    let dir = temp_dir("missing");
    let out = dir.path().join("out");
    let err = input_error(&["run", "no/such/scenario.toml", "--out", out.to_str().unwrap()]);
    assert!(err.contains("no/such/scenario.toml"), "{err}");
    assert!(!out.exists(), "--out was created for a scenario that does not load");
}

// ---------------------------------------------------------------------------------------------
// examples/

/// A sampled-data run reports its controller steps, not solver figures it does not have.
#[test]
fn sampled_summary_reports_controller_steps() {
    let dir = temp_dir("sampled-summary");
    let o = quell(&["run", "--no-plots", "--sample-time", "0.001", "--out", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let s = read_json(&dir.path().join("summary.json"));
    assert_eq!(s["stats"]["loop"], "sampled", "{s}");
    // 100 s at 1 ms: samples k = 0, …, 100,000.
    assert_eq!(s["stats"]["controller_steps"], 100_001, "{s}");
    assert_eq!(s["stats"]["sample_time"], 0.001, "{s}");
    assert!(s["stats"].get("rhs_evaluations").is_none(), "{s}");
    assert!(stderr(&o).contains("100001 controller steps"), "{}", stderr(&o));
}

/// The bound that example `name`'s tail error on channel `i` (summary.json's `tail_max_e`: max |e_i|
/// over the last 10 % of the horizon) must meet.
fn tail_bound(name: &str, scenario: &Scenario, i: usize) -> f64 {
    // The paper's example (Section VIII) claims asymptotic tracking; an independent solution of it
    // (crates/quell/tests/data/paper_example_points.csv's setup, tolerance 1e-12) has max |e| ≈ 0.027 and
    // 0.002 on [90, 100]. 0.05 and 0.005 leave about 2× for what the variants change (T_s = 1 ms:
    // O(T_s); L placed from the poles, which the printed L has to 1e-4) and still fail a loop that has
    // not converged by then (errors of the order of the reference, 2–3).
    let paper = [0.05, 0.005];
    match name {
        "paper" | "paper-observer-poles" | "paper-sampled" => paper[i],
        // Measurement noise of standard deviation σ_i on y_i reaches e_i only through the controller,
        // which must not amplify it: allow σ_i (0.03, 0.02) on top of the noise-free bound.
        "paper-noise" => paper[i] + scenario.noise.as_ref().unwrap().std[i],
        // Every other example is written to have settled by the last 10 % of its horizon (see each
        // file's comment): max |e_i| there must lie inside a 1 % band of the reference's peak |g_i|
        // (|bias| + Σ|amplitude|), half the usual 2 % settling band.
        _ => 0.01 * scenario.reference.components[i].peak(),
    }
}

/// Every scenario in `examples/` designs, runs to completion and meets its tail-error bound
/// ([`tail_bound`]).
#[test]
fn every_example_runs() {
    let mut files: Vec<PathBuf> = fs::read_dir(examples_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 5, "examples/: {files:?}");
    for file in &files {
        let name = file.file_stem().unwrap().to_string_lossy().into_owned();
        let dir = temp_dir(&format!("example-{name}"));
        let path = file.to_str().unwrap();

        let d = quell(&["design", path]);
        assert_eq!(d.status.code(), Some(0), "quell design {name}: {}", stderr(&d));

        let o = quell(&["run", path, "--out", dir.path().to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "quell run {name}: {}", stderr(&o));
        let s = read_json(&dir.path().join("summary.json"));
        assert_eq!(s["outcome"]["status"], "completed", "{name}: {s}");
        let scenario = Scenario::from_path(file).unwrap();
        let m = scenario.plant.m();
        assert_eq!(s["channels"].as_array().map(Vec::len), Some(m), "{name}: {s}");
        for i in 0..m {
            let (e, bound) = (s["channels"][i]["tail_max_e"].as_f64().unwrap(), tail_bound(&name, &scenario, i));
            assert!(e < bound, "{name}: tail max |e{}| = {e}, bound {bound}", i + 1);
        }
        for c in 1..=m {
            assert!(dir.path().join(format!("channel{c}.png")).is_file(), "{name}: channel{c}.png missing");
        }
        let header = fs::read_to_string(dir.path().join("signals.csv")).unwrap();
        let q = read_json(&dir.path().join("design.json"))["q"].as_u64().unwrap() as usize;
        assert_eq!(header.lines().next(), Some(csv_header(m, q).as_str()), "{name}");
        assert!(leftovers(dir.path()).is_empty(), "{name}: temporary files left");
    }
}

#[test]
fn a_jordan_observer_design_reports_an_infinite_eigenvector_condition() {
    // An observer gain with A − LC one Jordan block at −2 (to rounding): no eigenvector basis
    // (κ₂ = ∞: JSON null, and the text says defective).
    let text = fs::read_to_string(paper()).unwrap();
    let from = "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619], [2.7762, -1.1783]]";
    assert!(text.contains(from));
    let dir = temp_dir("jordan-observer");
    let file = dir.path().join("scenario.toml");
    // The gain of observer poles −2 three times (no longer placed: more copies than rank C).
    let defective = "observer_gain = [[2.1835647604859867, 0.0909233030206551], [0.10817297900137368, -0.5832415670642072], [0.6473140958320828, -0.29104025897591335]]";
    fs::write(&file, text.replacen(from, defective, 1)).unwrap();
    let o = quell(&["design", "--json", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let d: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(d["observer_eigenvector_condition"].is_null(), "{}", d["observer_eigenvector_condition"]);
    assert!(d["decoupled_eigenvector_condition"].as_f64().is_some_and(|k| k.is_finite() && k >= 1.0));
    let o = quell(&["design", file.to_str().unwrap()]);
    assert!(stdout(&o).contains("A − LC ∞ (defective"), "{}", stdout(&o));
}

#[test]
fn run_states_records_x_and_x_hat_and_x_gives_y() {
    // `--states` adds x1..x3, xhat1..xhat3; the recorded x must give the recorded y through the
    // paper's y = C x + Q ω with ω = [sin t, 1 + 2 sin 2t] evaluated here (1e-9: the CSV's
    // shortest round-trip numbers are exact, the rest is rounding of three products).
    let dir = temp_dir("run-states");
    let o = quell(&["run", "--states", "--no-plots", "--out", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let csv = fs::read_to_string(dir.path().join("signals.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next().unwrap(), format!("{},x1,x2,x3,xhat1,xhat2,xhat3", csv_header(2, 8)));
    for row in lines {
        let f: Vec<f64> = row.split(',').map(|s| s.parse().unwrap()).collect();
        let (t, y, x) = (f[0], [f[1], f[2]], &f[f.len() - 6..f.len() - 3]);
        let w = [t.sin(), 1.0 + 2.0 * (2.0 * t).sin()];
        let want = [2.0 * x[0] + 2.0 * x[1] + w[0] + 2.0 * w[1], 2.0 * x[0] + x[1] + 2.0 * x[2] + w[0]];
        for i in 0..2 {
            assert!(
                (y[i] - want[i]).abs() <= 1e-9 * (1.0 + want[i].abs()),
                "t = {t}: y{} = {}, C x + Q ω = {}",
                i + 1,
                y[i],
                want[i]
            );
        }
    }
}

/// The paper's example with its whole [design] table left out.
fn paper_without_design(dir: &TempDir) -> PathBuf {
    let text = fs::read_to_string(examples_dir().join("paper.toml")).unwrap();
    let start = text.find("[design]").unwrap();
    let end = start + text[start..].find("[reference]").unwrap();
    let path = dir.path().join("no-design.toml");
    fs::write(&path, format!("{}[design]\n{}", &text[..start], &text[end..])).unwrap();
    path
}

#[test]
fn design_auto_writes_a_complete_scenario_that_meets_the_tail_bound() {
    let dir = temp_dir("auto");
    let input = paper_without_design(&dir);
    // Without --auto the missing keys are an input error that names --auto.
    let o = quell(&["run", input.to_str().unwrap(), "--out", dir.path().join("x").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--auto"), "{}", stderr(&o));
    let out = dir.path().join("auto.toml");
    let o = quell(&["design", input.to_str().unwrap(), "--auto", "--write", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    for key in ["design.observer_poles", "design.channel_poles", "design.mu", "design.beta", "verification"] {
        assert!(stdout(&o).contains(key), "the report explains {key}:\n{}", stdout(&o));
    }
    // The chosen design's pace as `quell design` prints it (it had been left out, so a stiff or
    // unexcited channel was seen only by designing the written file again).
    let paced = quell(&["design", out.to_str().unwrap()]);
    let pace = stdout(&paced);
    let section = |text: &str| {
        text.split("\nadaptation (averaged").nth(1).map(|r| r.split("\n\n").next().unwrap_or(r).to_string())
    };
    assert!(section(&stdout(&o)).is_some() && section(&stdout(&o)) == section(&pace), "{}", stdout(&o));
    // Two inputs: each candidate's peaks input by input, as the relaxation's effort rule judges
    // them (the first proposal's line holds one peak per input).
    let report = stdout(&o);
    let first = report.lines().skip_while(|l| !l.contains("candidates (")).nth(1).unwrap_or_else(|| panic!("{report}"));
    assert!(report.contains("worst tail/bound, max|u_f,i|, solver steps"), "{report}");
    let peaks: Vec<f64> = first
        .split('[')
        .nth(1)
        .and_then(|r| r.split(']').next())
        .unwrap_or_else(|| panic!("{first}"))
        .split(", ")
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(peaks.len(), 2, "{first}");
    // The written scenario is complete, and running it (an independent run of the file) meets
    // the bound the verification promised: tail max |e_i| ≤ 1 % of the reference's peak (3 and 2).
    let s = Scenario::from_path(&out).unwrap();
    assert_eq!(s.plant, Scenario::from_path(&examples_dir().join("paper.toml")).unwrap().plant);
    // It is the input, comments included, with the [design] filled in.
    let (given, written) = (fs::read_to_string(&input).unwrap(), fs::read_to_string(&out).unwrap());
    assert!(given.contains("# g(t), m components"), "{given}");
    for line in given.lines().filter(|l| *l != "[design]") {
        assert!(written.contains(line), "the input's line {line:?} is kept:\n{written}");
    }
    let run_dir = dir.path().join("run");
    let o = quell(&["run", out.to_str().unwrap(), "--out", run_dir.to_str().unwrap(), "--no-plots"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let summary = read_json(&run_dir.join("summary.json"));
    for (c, peak) in summary["channels"].as_array().unwrap().iter().zip([3.0, 2.0]) {
        let tail = c["tail_max_e"].as_f64().unwrap();
        assert!(tail <= 0.01 * peak, "tail max|e| {tail} against 1 % of {peak}");
    }
    // Every channel has its diagnostics, with the keys scripts read.
    for d in summary["diagnostics"].as_array().unwrap() {
        for key in ["lambda_min_omega", "lambda_max_omega", "convergence_time", "adaptation_rate"] {
            assert!(d.get(key).is_some(), "{key} in {d}");
        }
    }
    // --write without --auto, and a bad target, are input errors.
    let o = quell(&["design", input.to_str().unwrap(), "--write", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--write: only with --auto"), "{}", stderr(&o));
    let o = quell(&["design", input.to_str().unwrap(), "--auto", "--convergence-time", "-1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--convergence-time: expected a finite number > 0, found -1"), "{}", stderr(&o));
    // --u-limit takes one limit or one per input (the paper's two), comma-separated.
    for (limits, message) in [
        ("1e3,1e3,1e3", "--u-limit: expected one actuator limit, or one per input (2), found 3"),
        ("1e3,-1", "--u-limit: expected limits > 0 (inf for none on an input), found -1"),
    ] {
        let o = quell(&["design", input.to_str().unwrap(), "--auto", "--u-limit", limits]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains(message), "{}", stderr(&o));
    }
    let o = quell(&["design", input.to_str().unwrap(), "--auto", "--u-limit", "1e3,1e3", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = &serde_json::from_str::<serde_json::Value>(&stdout(&o)).unwrap()["verification"];
    assert!(v["max_uf"].as_array().unwrap().iter().all(|u| u.as_f64().unwrap() <= 1e3), "{v}");
    // A limit far below the steady state's input, every tone beyond 10× its tail bound, is an
    // infeasible target after the first run: exit 2, the limit as written (it printed as 300
    // digits), nothing written.
    let out = dir.path().join("limited.toml");
    let o =
        quell(&["design", input.to_str().unwrap(), "--auto", "--u-limit", "1e-300", "--write", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(
            "--u-limit: the steady state alone asks more than the actuator limit (u_f[1]: 11.63 against 1e-300, "
        ),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    // One just below u_f,2's steady 21.68, which no candidate meets while the tails do: exit 2
    // after the runs, with their figures in four digits and a limit that admits the peak.
    let o = quell(&["design", input.to_str().unwrap(), "--auto", "--u-limit", "20", "--write", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("no candidate keeps max|u_f,i| within the actuator limit 20"), "{}", stderr(&o));
    let err = stderr(&o);
    let peaks = err.split(", max|u_f| [").nth(1).and_then(|r| r.split("] against the limit 20)").next());
    let four_digits =
        |v: &str| v.len() == 7 && v.as_bytes()[1] == b'.' && v[5..].starts_with('e') && v.parse::<f64>().is_ok();
    assert!(peaks.is_some_and(|p| p.split(", ").all(four_digits) && p.split(", ").count() == 2), "{err}");
    assert!(stderr(&o).contains("raise the actuator limit (--u-limit) to at least 22,"), "{}", stderr(&o));
    assert!(!out.exists());
}

/// `--write` to a file that cannot be written is refused before the automatic design runs, as
/// `--out` is for the other commands: exit 2, nothing on stdout, one line naming the flag, the
/// path, why and what to do.
#[test]
fn design_auto_write_unwritable_exits_2_before_work() {
    let dir = temp_dir("auto-write");
    let input = paper_without_design(&dir);
    let file = dir.path().join("a-file");
    fs::write(&file, b"not a directory").unwrap();
    // A directory or a device is refused before the verifying runs (/dev/null was refused after
    // all eleven of them).
    let cases = [
        (dir.path().join("missing/x.toml"), "cannot write in".to_string()),
        (file.join("x.toml"), "cannot write in".into()),
        (PathBuf::from("/proc/x.toml"), "cannot write in /proc".into()),
        (dir.path().to_path_buf(), format!("{} is a directory, not a regular file", dir.path().display())),
        (PathBuf::from("/dev/null"), "/dev/null is a device, FIFO or socket, not a regular file".into()),
    ];
    for (out, why) in cases {
        let err = input_error(&["design", input.to_str().unwrap(), "--auto", "--write", out.to_str().unwrap()]);
        assert!(err.contains(&format!("--write {}: {why}", out.display())), "{err}");
        assert!(err.contains("choose a file in an existing, writable directory"), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    assert!(!dir.path().join("missing").exists(), "--write's directory was created");
    assert_eq!(fs::read(&file).unwrap(), b"not a directory");
    // --write naming the input itself (here through another path to it) would replace the file
    // and the design it holds: refused, the input untouched.
    let before = fs::read(&input).unwrap();
    let same = input.parent().unwrap().join(".").join(input.file_name().unwrap());
    let err = input_error(&["design", input.to_str().unwrap(), "--auto", "--write", same.to_str().unwrap()]);
    assert!(err.contains("it is the scenario being designed") && err.contains("write to another file"), "{err}");
    assert_eq!(fs::read(&input).unwrap(), before);
}

#[test]
fn design_refuses_a_pole_repeated_beyond_rank_c_and_warns_of_a_defective_gain() {
    // Three copies of −5 for the observer of a plant with two outputs: A − LC would need a Jordan
    // block (rank C = 2 eigenvectors at most for one eigenvalue): refused, exit 2.
    let dir = temp_dir("fragile");
    let text = fs::read_to_string(paper()).unwrap();
    let gain = "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619], [2.7762, -1.1783]]";
    let file = dir.path().join("jordan.toml");
    fs::write(&file, text.replacen(gain, "observer_poles = [-5.0, -5.0, -5.0]", 1)).unwrap();
    let err = input_error(&["design", file.to_str().unwrap()]);
    assert!(
        err.contains("design.observer_poles: pole -5.000000 is requested 3 times, more than rank(C) = 2: the observer A − LC would need")
            && err.contains("spread the repeated poles"),
        "{err}"
    );
    // The gain such a placement gave (A − LC one Jordan block at −5, to rounding), given as L:
    // designed, with a warning giving κ₂ = ∞.
    let defective = "observer_gain = [[-56.982899739126566, -6.529670548858569], [62.29597186698538, 7.78904549447498], [33.05238335010353, 3.622075673762282]]";
    fs::write(&file, text.replacen(gain, defective, 1)).unwrap();
    let o = quell(&["design", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0));
    // A gain given has no requested poles to be off from (a "?" had stood for their error).
    assert!(stdout(&o).contains("⚠ warning: design.observer_gain: fragile observer gain: eig(A − LC) has eigenvector condition number κ₂ = inf: a relative model error ε can move the observer poles"), "{}", stdout(&o));
    assert!(
        stdout(&o).contains("  precision: A − LC (the observer) has a defective eigenvector matrix (κ₂ = ∞)"),
        "{}",
        stdout(&o)
    );
    let o = quell(&["design", file.to_str().unwrap(), "--json"]);
    let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert!(v["warnings"][0]["eigenvector_condition"].is_null(), "{}", v["warnings"]);
    // The paper's printed gain: no warning.
    let o = quell(&["design", &paper(), "--json"]);
    let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["warnings"], serde_json::json!([]));
}

/// `--method` chooses the continuous loop's integrator. The paper's example is not stiff, so
/// `explicit` (DOP853 throughout) is what `auto` does: the same files bit for bit; `imex`
/// (ARK4(3)6L[2]SA, order 4) takes other steps, and its outputs agree with DOP853's to 1e-6 of
/// the peak output (both at rtol = atol = 1e-9, each within ~100·rtol of the exact solution).
#[test]
fn method_flag_chooses_the_integrator() {
    let dir = temp_dir("method");
    let scenario = dir.path().join("short.toml");
    fs::write(&scenario, fs::read_to_string(paper()).unwrap().replace("t_end = 100.0", "t_end = 10.0")).unwrap();
    let run = |method: Option<&str>| {
        let out = dir.path().join(method.unwrap_or("default"));
        let mut args = vec!["run", scenario.to_str().unwrap(), "--no-plots", "--out", out.to_str().unwrap()];
        args.extend(method.map(|m| ["--method", m]).into_iter().flatten());
        let o = quell(&args);
        assert!(o.status.success(), "{method:?}: {}", stderr(&o));
        let csv = fs::read_to_string(out.join("signals.csv")).unwrap();
        let stats = &read_json(&out.join("summary.json"))["stats"];
        // summary.json says which method took the steps: imex all of them, DOP853 none.
        let implicit = if method == Some("imex") { stats["steps"].clone() } else { 0.into() };
        assert!(stats["implicit_steps"] == implicit && stats["switches"] == 0, "{method:?}: {stats}");
        (csv, stats["steps"].as_u64().unwrap())
    };
    let (auto, explicit, imex) = (run(None), run(Some("explicit")), run(Some("imex")));
    assert_eq!(auto, explicit, "auto is DOP853 on a loop that is not stiff");
    assert_ne!(imex.1, explicit.1, "imex takes its own steps");
    let numbers = |csv: &str| -> Vec<Vec<f64>> {
        csv.lines().skip(1).map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect()
    };
    let (a, b) = (numbers(&explicit.0), numbers(&imex.0));
    // Columns t, y1, y2: the outputs.
    let peak = a.iter().flat_map(|r| r[1..3].iter()).fold(0.0f64, |m, v| m.max(v.abs()));
    let dev = a.iter().zip(&b).flat_map(|(r, s)| (1..3).map(move |j| (r[j] - s[j]).abs())).fold(0.0f64, f64::max);
    assert!(a.len() == b.len() && dev < 1e-6 * peak, "explicit and imex differ by {dev:e}, peak {peak}");
}

/// DOP853 forced on a stiff adaptive law (μ × 5: channel 2 at 4.7ρ) is cautioned before the run,
/// naming the setting as it was given: the flag, or the file's key; so is a rate far faster than
/// the loop (β = 1e-7), by its key.
#[test]
fn costly_runs_are_cautioned_before_they_start_naming_the_setting() {
    let dir = temp_dir("explicit-stiff");
    let stiff = fs::read_to_string(paper()).unwrap().replace("t_end = 100.0", "t_end = 0.5");
    let stiff = stiff.replace("mu = [20.0, 30.0]", "mu = [100.0, 150.0]");
    let (flag, key) = (dir.path().join("flag.toml"), dir.path().join("key.toml"));
    fs::write(&flag, &stiff).unwrap();
    fs::write(&key, stiff.replace("[simulation]\n", "[simulation]\nmethod = \"explicit\"\n")).unwrap();
    for (file, extra, set_by) in [
        (&flag, &["--method", "explicit"][..], "--method explicit"),
        (&key, &[][..], "simulation.method = \"explicit\""),
    ] {
        let out = dir.path().join("out");
        let mut args = vec!["run", file.to_str().unwrap(), "--no-plots", "--out", out.to_str().unwrap()];
        args.extend(extra);
        let o = quell(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let caution = format!("⚠ warning: {set_by} on a stiff adaptive law: μλ_max = ");
        assert!(stderr(&o).contains(&caution), "{set_by}: {}", stderr(&o));
    }
    let o = quell(&["run", flag.to_str().unwrap(), "--no-plots", "--out", dir.path().join("auto").to_str().unwrap()]);
    assert!(o.status.success() && !stderr(&o).contains("stiff adaptive law"), "{}", stderr(&o));
    // β = 1e-7: 1/β sets every method's steps, which the caution says before the run (here ended
    // by a budget of 10 steps).
    let fast = dir.path().join("fast.toml");
    fs::write(&fast, fs::read_to_string(paper()).unwrap().replace("beta = 1.0 ", "beta = 1e-7 ")).unwrap();
    let out = dir.path().join("fast");
    let o = quell(&["run", fast.to_str().unwrap(), "--no-plots", "--max-steps", "10", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("⚠ warning: 1/design.beta sets the loop's fastest rate, 1.000e7/s"), "{}", stderr(&o));
}

#[test]
fn bad_method_flag_exits_2_naming_the_flag_and_the_names() {
    let dir = temp_dir("bad-method");
    let out = dir.path().join("out");
    let o = quell(&["run", "--no-plots", "--method", "implict", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("error: --method: expected \"auto\"") && e.contains("found \"implict\" (did you mean \"imex\"?)"),
        "{e}"
    );
    let o = quell(&["run", "--no-plots", "--sample-time", "0.01", "--method", "imex", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--method: the integrator applies to the continuous loop only"), "{}", stderr(&o));
    assert!(!out.exists(), "nothing is written before the input is checked");
}

/// `--precision f32` runs the sampled loop with the controller's arithmetic emulated in float: its
/// signals differ from the f64 run's by rounding's magnitude (the paper's y within 1e-3 of its peak,
/// not bit for bit), and the run says how far. A bad name, a continuous run or `--continuous`
/// beside it exit 2 naming the flag, with nothing written.
#[test]
fn precision_flag_runs_the_f32_controller_and_says_how_far_it_departs() {
    let dir = temp_dir("precision");
    let run = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["run", "--no-plots", "--t-end", "20", "--out", out.to_str().unwrap()];
        args.extend(extra);
        (quell(&args), out)
    };
    let (o64, d64) = run("f64", &["--sample-time", "0.001"]);
    let (o32, d32) = run("f32", &["--sample-time", "0.001", "--precision", "f32"]);
    assert!(o64.status.success() && o32.status.success(), "{}", stderr(&o32));
    assert!(
        stdout(&o32).contains("precision f32 (emulated:") && !stdout(&o64).contains("precision f32"),
        "{}",
        stdout(&o32)
    );
    let column = |dir: &Path, name: &str| -> Vec<f64> {
        let text = fs::read_to_string(dir.join("signals.csv")).unwrap();
        let mut lines = text.lines();
        let at = lines.next().unwrap().split(',').position(|h| h == name).unwrap();
        lines.map(|l| l.split(',').nth(at).unwrap().parse().unwrap()).collect()
    };
    let (a, b) = (column(&d32, "y1"), column(&d64, "y1"));
    let gap = a.iter().zip(&b).fold(0.0f64, |g, (x, y)| g.max((x - y).abs()));
    let peak = b.iter().fold(0.0f64, |p, y| p.max(y.abs()));
    assert!(gap > 0.0 && gap < 1e-3 * peak, "{gap} of {peak}");
    for (extra, said) in [
        (
            &["--sample-time", "0.001", "--precision", "f16"][..],
            "error: simulation.precision (--precision): expected \"f64\" or \"f32\", found \"f16\"",
        ),
        (
            &["--precision", "f32"][..],
            "error: simulation.precision (--precision): f32 is the discrete controller's arithmetic",
        ),
        (&["--continuous", "--precision", "f32"][..], "cannot be used with"),
    ] {
        let (o, out) = run("refused", extra);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(said), "{extra:?}: {}", stderr(&o));
        assert!(!out.exists(), "nothing is written before the input is checked");
    }
}

/// `--continuous` runs the continuous loop of a file that sets simulation.sample_time: signals.csv
/// byte for byte that of the same file without the key, where the plain run is the sampled loop;
/// with `--sample-time` it is refused (exit 2); and the `--method` error's advice, followed,
/// runs (the apps and servo-ms set a sample time, so their continuous loop had no flag).
#[test]
fn continuous_flag_runs_the_continuous_loop_of_a_sampled_file() {
    let dir = temp_dir("continuous");
    let text = fs::read_to_string(paper()).unwrap().replace("t_end = 100.0", "t_end = 2.0");
    let sampled_text = text.replacen("[simulation]\n", "[simulation]\nsample_time = 0.01\n", 1);
    assert_ne!(sampled_text, text);
    let (plain, sampled) = (dir.path().join("plain.toml"), dir.path().join("sampled.toml"));
    fs::write(&plain, &text).unwrap();
    fs::write(&sampled, &sampled_text).unwrap();
    let run = |file: &Path, extra: &[&str], name: &str| {
        let out = dir.path().join(name);
        let mut args = vec!["run", file.to_str().unwrap(), "--no-plots", "--out", out.to_str().unwrap()];
        args.extend(extra);
        let o = quell(&args);
        (o, out)
    };
    let (o, reference) = run(&plain, &[], "reference");
    assert!(o.status.success(), "{}", stderr(&o));
    let (o, sampled_out) = run(&sampled, &[], "sampled");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(read_json(&sampled_out.join("summary.json"))["stats"]["controller_steps"].is_u64());
    let (o, continuous) = run(&sampled, &["--continuous"], "continuous");
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = |d: &Path| fs::read_to_string(d.join("signals.csv")).unwrap();
    assert_eq!(csv(&continuous), csv(&reference));
    assert_ne!(csv(&sampled_out), csv(&reference));
    let (o, both) = run(&sampled, &["--continuous", "--sample-time", "0.01"], "both");
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--continuous") && stderr(&o).contains("--sample-time"), "{}", stderr(&o));
    assert!(!both.exists());
    let (o, _) = run(&sampled, &["--method", "imex"], "method");
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("run the continuous loop with --continuous"), "{}", stderr(&o));
    let (o, followed) = run(&sampled, &["--method", "imex", "--continuous"], "followed");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(read_json(&followed.join("summary.json"))["stats"]["steps"].is_u64());
}

/// `[plant]` signal names label the channel lines (`channel 1 (pitch): …`) and change no file:
/// signals.csv is byte for byte that of the same scenario without names.
#[test]
fn signal_names_label_the_channel_lines_and_change_no_file() {
    let dir = temp_dir("names");
    let text = fs::read_to_string(paper()).unwrap().replace("t_end = 100.0", "t_end = 2.0");
    let named_text = text.replacen("[plant]\n", "[plant]\noutputs = [\"pitch\", \"roll\"]\n", 1);
    assert_ne!(named_text, text, "the example has a [plant] line");
    let mut csv = Vec::new();
    for (tag, body) in [("plain", &text), ("named", &named_text)] {
        let file = dir.path().join(format!("{tag}.toml"));
        fs::write(&file, body).unwrap();
        let out = dir.path().join(tag);
        let o = quell(&["run", file.to_str().unwrap(), "--out", out.to_str().unwrap(), "--no-plots"]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let summary = stdout(&o);
        let first = if tag == "named" { "channel 1 (pitch): tail max|e|" } else { "channel 1: tail max|e|" };
        assert!(
            summary.contains(first)
                && summary.contains(if tag == "named" { "channel 2 (roll): " } else { "channel 2: " }),
            "{summary}"
        );
        csv.push(fs::read(out.join("signals.csv")).unwrap());
    }
    assert!(csv[0] == csv[1], "signals.csv differs with names");
}

/// A sampled-data run (or export) at a sample time coarse for the design is warned of, with the
/// one that is not: the paper's fastest rate is its reference filter's pole −9, so T_s·9 > 0.2
/// (T_s > 0.0222 s) warns and 0.02 s does not; the export warns alike.
#[test]
fn a_coarse_sample_time_is_warned_of() {
    let dir = temp_dir("coarse");
    let out = dir.path().join("out");
    let warned = |args: &[&str]| {
        let o = quell(args);
        // A coarse sampled-data run may also fail (exit 1); the warning comes before it.
        assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
        stderr(&o).lines().find(|l| l.contains("simulation.sample_time (--sample-time): T_s")).map(str::to_owned)
    };
    let run = |t: &str| {
        let args = ["run", "--no-plots", "--sample-time", t, "--out", out.to_str().unwrap()];
        warned(&args)
    };
    let w = run("0.05").expect("T_s = 0.05 s warns");
    assert!(
        w.starts_with("⚠ warning: ") && w.contains("is 0.45× the loop's fastest time constant 1/ρ (ρ = 9 /s"),
        "{w}"
    );
    let suggested: f64 = w.split("choose T_s ≤ ").nth(1).and_then(|r| r.split(' ').next()).unwrap().parse().unwrap();
    assert!(suggested <= 0.2 / 9.0 && suggested > 0.99 * 0.2 / 9.0, "{suggested}");
    // The bound does not divide the delays (1 s and 3 s); the example given does, and runs quietly.
    assert!(w.contains("(T_s·ρ ≤ 0.2), e.g. 0.02 s, which makes plant.delays whole"), "{w}");
    assert_eq!(run("0.02"), None);
    let c = dir.path().join("c");
    let export = ["export", &paper(), "--sample-time", "0.05", "--out", c.to_str().unwrap()];
    assert!(warned(&export).is_some());
}

/// `quell tune` whose tuned μ together break a limit each search met (the CSTR's u_f,1; the library
/// test `a_limit_each_search_meets_can_be_broken_together`) says so and exits 2.
#[test]
fn tune_exits_2_when_the_joint_run_breaks_a_limit() {
    let dir = temp_dir("tune-joint");
    let cstr = Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/cstr.toml");
    let study = dir.path().join("tune.toml");
    let text = format!(
        "scenario = {:?}\n[tune]\nobjective = \"settle_t\"\nmu = [0.2, 100.0]\nmax_u = [1.0, 6.45]\nmax_uf = [10.6, 1.0]\npoints = 9\nrefine = 6\n",
        cstr.canonicalize().unwrap().display().to_string()
    );
    fs::write(&study, text).unwrap();
    let out = dir.path().join("out");
    let o = quell(&["tune", study.to_str().unwrap(), "--out", out.to_str().unwrap(), "--no-plots"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    // Only the limit broken is named (max_u[0] = 1 is met), with the joint run's figure.
    let report = stdout(&o);
    let line = report.lines().find(|l| l.starts_with("channel 1: mu = ")).unwrap_or_else(|| panic!("{report}"));
    assert!(
        line.contains(", but BREAKS max |u_f,1| = ") && line.ends_with(" beyond tune.max_uf[0] = 10.6 there"),
        "{line}"
    );
    assert!(!line.contains("max |u_1|"), "{line}");
    assert!(report.starts_with("objective: settle_t, in minutes\n"), "the CSTR's unit: {report}");
    let err = stderr(&o);
    assert!(err.contains("the tuned μ together break limits in the joint run (channel 1: max |u_f,1| = "), "{err}");
    assert!(err.contains(" beyond tune.max_uf[0] = 10.6)"), "{err}");
    // The joint figure is the one the error names: tune.json's joint run.
    let json = read_json(&out.join("tune.json"));
    let joint = json["joint"]["channels"][0]["max_uf"].as_f64().unwrap();
    assert!(joint > 10.6 && err.contains(&format!("max |u_f,1| = {joint:.4e} beyond")), "{joint} {err}");
    // tune.csv says why a completed evaluation has no objective: the limit it broke.
    let csv = fs::read_to_string(out.join("tune.csv")).unwrap();
    assert!(
        csv.lines().any(|l| l.contains(",completed,\"max |u_f,1| = ") && l.contains("beyond tune.max_uf[0] = 10.6\",")),
        "{csv}"
    );
    assert_eq!(json["within_limits"], serde_json::json!([false, true]));
}

#[test]
fn design_refuses_a_scenario_whose_run_cannot_start() {
    // The scenario's own sample time does not divide τ_1 = 1 s: `quell run` and `quell export`
    // refuse it (exit 2), so `quell design` does too instead of reporting a design that cannot run.
    let err = design_with_edit("design-sample-time", "# sample_time = 0.001", "sample_time = 0.3");
    assert!(err.starts_with("error: simulation.sample_time"), "{err}");
    assert!(err.contains("channel 1's delay τ = 1 s is not a whole number of samples"), "{err}");
    // The delays' offer, 0.33333333333 s (the controller's alone, `quell export`'s), does not divide
    // the output step 0.1 s; the run's does, and says so.
    assert!(
        err.contains("the nearest valid sample time that also divides simulation.output_step = 0.1 s (a run's rows fall on samples) is 0.1 s"),
        "{err}"
    );
}

/// `[plant] time_unit` labels what states a time: the figures' t axis, the reports' rates and
/// times, summary.json, and the generated header's T_s; the numbers are those of the same plant
/// without the key (Wood–Berry's column, written in minutes).
#[test]
fn the_plant_time_unit_labels_figures_reports_and_the_header() {
    let dir = temp_dir("time-unit");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/wood-berry.toml");
    let minutes = fs::read_to_string(&data).unwrap().replace("t_end = 600.0", "t_end = 30.0");
    assert!(minutes.contains("time_unit = \"min\"") && minutes.contains("t_end = 30.0"));
    let seconds = minutes.replace("time_unit = \"min\"\n", "");
    let mut csv = Vec::new();
    for (tag, body) in [("min", &minutes), ("s", &seconds)] {
        let file = dir.path().join(format!("{tag}.toml"));
        fs::write(&file, body).unwrap();
        let out = dir.path().join(tag);
        let o = quell(&["run", file.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(0), "{err}");
        let svg = fs::read_to_string(out.join("channel1.svg")).unwrap();
        assert!(svg.contains(&format!("\nt, {tag}\n</text>")), "the t axis is labelled in {tag}");
        // The titles name the output and the input where the scenario does.
        assert!(
            svg.contains("Channel 1 (x_D): output and reference") && svg.contains("Input 1 (reflux): plant input u_f")
        );
        assert_eq!(read_json(&out.join("summary.json"))["time_unit"], tag);
        let report = stdout(&o);
        assert!(report.contains("adaptation rate μλ_max = ") && report.contains(&format!("/{tag}")), "{report}");
        assert!(report.contains(&format!("enters the band at t = 29 {tag} only in the last 5 %")), "{report}");
        csv.push(fs::read(out.join("signals.csv")).unwrap());
        let design = quell(&["design", file.to_str().unwrap()]);
        assert!(stdout(&design).contains(&format!("t_end = 30 {tag})")), "{}", stdout(&design));
        // The column adapts at 10ρ: the report says `auto` will take η̂ implicitly (the paper's
        // example, at 0.37ρ and 0.95ρ, is not flagged).
        let flag = "(≥ 3ρ: the automatic method takes η̂ implicitly from DOP853's stability bound)";
        assert_eq!(stdout(&design).matches(flag).count(), 2, "{}", stdout(&design));
        assert!(!stdout(&quell(&["design", &paper()])).contains(flag));
    }
    assert!(csv[0] == csv[1], "signals.csv differs with the unit");
    let c = dir.path().join("c");
    let file = dir.path().join("min.toml");
    let o = quell(&["export", file.to_str().unwrap(), "--sample-time", "0.5", "--out", c.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("(T_s = 0.5 min, double;"), "{}", stderr(&o));
    let header = fs::read_to_string(c.join("quell_controller.h")).unwrap();
    assert!(header.contains("Sample time T_s = 0.5, in minutes, the plant model's unit of time."), "{header}");
    let e = quell(&["run", file.to_str().unwrap(), "--sample-time", "0.7", "--out", c.to_str().unwrap()]);
    assert_eq!(e.status.code(), Some(2));
    assert!(stderr(&e).contains("τ = 1 min is not a whole number of samples of T_s = 0.7 min"), "{}", stderr(&e));
    let e = quell(&[
        "run",
        file.to_str().unwrap(),
        "--sample-time",
        "0.5",
        "--method",
        "imex",
        "--out",
        c.to_str().unwrap(),
    ]);
    assert!(stderr(&e).contains("the sampled-data loop at T_s = 0.5 min"), "{}", stderr(&e));
}

/// A plant without a disturbance input (k = 0): the report says so instead of checking rank D = 0
/// with condition number 1, and the automatic observer is the slowest candidate for that reason
/// (it said "the zeros of (A, D, C) kept … its error is 0.00e0").
#[test]
fn a_plant_without_a_disturbance_is_reported_as_such() {
    let dir = temp_dir("no-disturbance");
    let file = dir.path().join("k0.toml");
    let scenario = "[plant]\nA = [[-1.0]]\nB = [[1.0]]\nC = [[1.0]]\ndelays = [0.1]\n[design]\n[reference]\ncomponents = [ { bias = 1.0, harmonics = [{ amplitude = 0.5, frequency = 1.0 }] } ]\n[simulation]\nt_end = 40.0\nrtol = 1e-6\natol = 1e-6\n";
    fs::write(&file, scenario).unwrap();
    let o = quell(&["design", "--auto", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("✓ no disturbance input (k = 0)") && !text.contains("rank D"), "{text}");
    assert!(
        text.contains("the plant has no disturbance input (k = 0)") && !text.contains("zeros of (A, D, C) kept"),
        "{text}"
    );
}

#[test]
fn sample_time_flag_makes_the_scenario_a_sampled_one_for_white_noise() {
    // White noise (no bandwidth) is valid only in a sampled-data scenario. The flag "overrides
    // simulation.sample_time", so a file without the key but with the flag is one: it was refused
    // with "noise.bandwidth: missing … or set simulation.sample_time".
    let dir = temp_dir("noise-flag");
    let text = fs::read_to_string(examples_dir().join("paper-noise.toml")).unwrap();
    let without: String = text.lines().filter(|l| !l.starts_with("sample_time")).map(|l| format!("{l}\n")).collect();
    let file = dir.path().join("pn.toml");
    fs::write(&file, without.replace("t_end = 100.0", "t_end = 2.0")).unwrap();
    let file = file.display().to_string();
    let refused = quell(&["run", &file, "--no-plots", "--out", &dir.path().join("a").display().to_string()]);
    assert_eq!(refused.status.code(), Some(2), "{}", stderr(&refused));
    assert!(stderr(&refused).contains("noise.bandwidth: missing"), "{}", stderr(&refused));
    let out = dir.path().join("b");
    let ran = quell(&["run", &file, "--sample-time", "0.001", "--no-plots", "--out", &out.display().to_string()]);
    assert_eq!(ran.status.code(), Some(0), "{}", stderr(&ran));
    // The same samples as the file with the key: the flag and the key are one setting.
    let keyed = dir.path().join("keyed.toml");
    fs::write(&keyed, text.replace("t_end = 100.0", "t_end = 2.0")).unwrap();
    let out_keyed = dir.path().join("c");
    let ran_keyed =
        quell(&["run", &keyed.display().to_string(), "--no-plots", "--out", &out_keyed.display().to_string()]);
    assert_eq!(ran_keyed.status.code(), Some(0), "{}", stderr(&ran_keyed));
    assert_eq!(fs::read(out.join("signals.csv")).unwrap(), fs::read(out_keyed.join("signals.csv")).unwrap());
    let c = dir.path().join("code");
    let exported = quell(&["export", &file, "--sample-time", "0.001", "--out", &c.display().to_string()]);
    assert_eq!(exported.status.code(), Some(0), "{}", stderr(&exported));
}

/// `--auto` verifies its candidates on the true plant, through its actuator: where the limit clips,
/// the report says so per input, as `quell run` does (it had printed max|u_f| = 150 and nothing
/// more). A two-zone thermal plant in hours, heaters limited to 150 kW.
#[test]
fn design_auto_says_when_the_true_actuator_clipped() {
    let dir = temp_dir("auto-clipped");
    let file = dir.path().join("thermal.toml");
    fs::write(
        &file,
        r#"name = "two-zone-thermal"
[plant]
time_unit = "h"
A = [[-0.5, 0.2], [0.2, -0.4]]
B = [[0.1, 0.0], [0.0, 0.08]]
C = [[1.0, 0.0], [0.0, 1.0]]
D = [[0.3], [0.2]]
Q = [[0.0], [0.0]]
delays = [0.1, 0.25]
[design]
[reference]
components = [ { bias = 20.0 }, { bias = 18.0 } ]
[disturbance]
components = [ { bias = 5.0, harmonics = [{ amplitude = 8.0, frequency = 0.2617993877991494 }] } ]
[simulation]
t_end = 240.0
output_step = 0.05
rtol = 1e-8
atol = 1e-8
[truth]
A = [[-0.55, 0.22], [0.18, -0.42]]
delays = [0.15, 0.3]
u_max = [150.0, 150.0]
"#,
    )
    .unwrap();
    let o = quell(&["design", file.to_str().unwrap(), "--auto"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report = stdout(&o);
    for i in [1, 2] {
        let line =
            report.lines().find(|l| l.starts_with(&format!("  input {i}: clipped by truth.u_max[{}] at ", i - 1)));
        let share: f64 = line.expect(&report).split(" at ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
        assert!(share > 0.0 && share < 5.0, "{share}");
    }
}

/// The true actuator's limit is on the u_f panel: dashed at ±u_max where u_f comes within a tenth
/// of it, and as the peak's share of it in the title where it does not (summary.json's max|u_f|).
#[test]
fn run_figures_show_the_actuator_limit_or_how_far_u_f_stays_from_it() {
    let dir = temp_dir("u-max-figure");
    let body = fs::read_to_string(paper()).unwrap().replace("t_end = 100.0", "t_end = 20.0");
    let file = dir.path().join("limited.toml");
    // 1e7 puts the peak at 1.5e-4 % of the limit, which read "0.0 %" at one decimal.
    fs::write(&file, format!("{body}\n[truth]\nu_max = [1e7, 10.0]\n")).unwrap();
    let out = dir.path().join("out");
    let o = quell(&["run", file.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let summary = read_json(&out.join("summary.json"));
    let peak = summary["channels"][0]["max_uf"].as_f64().unwrap();
    assert!(peak > 0.0 && peak < 1e3, "{peak}");
    let svg1 = fs::read_to_string(out.join("channel1.svg")).unwrap();
    // Two significant digits of the share (1.5e-4 %, to the rounding of two digits: 3.4 %).
    let title = svg1.split("what the actuator delivers; peak ").nth(1).expect("the share in the title");
    let share: f64 = title.split(" % of truth.u_max").next().unwrap().parse().unwrap();
    let exact = 100.0 * peak / 1e7;
    assert!((share - exact).abs() <= 0.034 * exact && !svg1.contains("±truth.u_max"), "{share} against {exact}");
    let svg2 = fs::read_to_string(out.join("channel2.svg")).unwrap();
    assert!(svg2.contains("±truth.u_max[1] = 10") && !svg2.contains("% of truth.u_max"));
    // Input 2's limit clips (u_f,2 asks for about 21): the title says how much it asked for, as
    // summary.json's max_uf; input 1's never clipped.
    let asked = summary["channels"][1]["max_uf"].as_f64().unwrap();
    assert!(asked > 10.0 && svg2.contains("the controller asked for up to "), "{asked}");
    assert!(!svg1.contains("the controller asked for"));
}

/// A range that is not symmetric (`[truth] u_min`): input 1 of the paper's loop (u_f,1 from −12.5 to
/// 14.9 over 20 s unclipped) held within −10 … 30 is clipped below only; the clipping line names
/// both keys, the figure draws a dashed line at each end and says how much the controller asked for.
#[test]
fn a_range_that_is_not_symmetric_is_drawn_and_named_at_both_ends() {
    let dir = temp_dir("u-min");
    let body = fs::read_to_string(paper()).unwrap().replace("t_end = 100.0", "t_end = 20.0");
    let file = dir.path().join("heater.toml");
    fs::write(&file, format!("{body}\n[truth]\nu_max = [30.0, inf]\nu_min = [-10.0, -inf]\n")).unwrap();
    let out = dir.path().join("out");
    let o = quell(&["run", file.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report = stdout(&o);
    assert!(report.contains("input 1: clipped by truth.u_min[0] … u_max[0] at "), "{report}");
    assert!(!report.contains("input 2: clipped"), "{report}");
    let signals = fs::read_to_string(out.join("signals.csv")).unwrap();
    let header: Vec<&str> = signals.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|c| *c == "uf1").unwrap();
    let uf1: Vec<f64> = signals.lines().skip(1).map(|l| l.split(',').nth(col).unwrap().parse().unwrap()).collect();
    assert!(uf1.iter().all(|u| (-10.0..=30.0).contains(u)) && uf1.contains(&-10.0));
    let svg1 = fs::read_to_string(out.join("channel1.svg")).unwrap();
    assert!(
        svg1.contains("truth.u_min[0], u_max[0] = -10, 30") && svg1.contains("the controller asked for |u_f| up to ")
    );
    let svg2 = fs::read_to_string(out.join("channel2.svg")).unwrap();
    assert!(!svg2.contains("truth.u_m"), "input 2 has no limit");
}

/// A run that fails under the true actuator's limits says how much they clipped before the failure
/// (the clipping is likely why): the paper's loop with |u_f| ≤ 2 on both inputs.
#[test]
fn a_failed_run_says_how_much_the_actuator_clipped() {
    let dir = temp_dir("clip-fail");
    let file = dir.path().join("clipped.toml");
    fs::write(&file, format!("{}\n[truth]\nu_max = [2.0, 2.0]\n", fs::read_to_string(paper()).unwrap())).unwrap();
    let out = dir.path().join("out");
    let o = quell(&["run", file.to_str().unwrap(), "--out", out.to_str().unwrap(), "--no-plots"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let report = stdout(&o);
    let summary = read_json(&out.join("summary.json"));
    for i in [1, 2] {
        let share = 100.0 * summary["limited_fraction"][i - 1].as_f64().unwrap();
        let line = format!("input {i}: clipped by truth.u_max[{}] at {share:.1} % of the recorded samples", i - 1);
        assert!(share > 0.0 && report.contains(&line), "{line}\n{report}");
    }
}

/// A run that diverges before its second row (a true plant starting at x1 = 1e150: diverged at
/// t = 1e-6) has one point per curve, which a line does not draw: each panel shows it as a dot
/// (they had stayed empty), the log panel's |e1(0)| = 2e150 among them.
#[test]
fn a_run_that_ends_before_its_second_row_is_drawn_as_points() {
    let dir = temp_dir("one-row");
    let file = dir.path().join("huge-x0.toml");
    fs::write(&file, format!("{}\n[truth]\nx0 = [1e150, 0.0, 0.0]\n", fs::read_to_string(paper()).unwrap())).unwrap();
    let out = dir.path().join("out");
    let o = quell(&["run", file.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(fs::read_to_string(out.join("signals.csv")).unwrap().lines().count(), 2, "a header and one row");
    let svg = fs::read_to_string(out.join("channel1.svg")).unwrap();
    // y, g, e, u, u_f, the 8 entries of η̂_1 and |e|: 14 curves of one point.
    assert_eq!(svg.matches("<circle").count(), 14, "{}", &svg[..svg.len().min(400)]);
}

#[test]
fn design_auto_on_a_fully_specified_scenario_says_nothing_was_chosen() {
    // The heading "the keys chosen, and why" stood over an empty list.
    let o = quell(&["design", &paper(), "--auto"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        text.starts_with("automatic design: the scenario gives every key, so none was chosen\nverification"),
        "{text}"
    );
}

#[test]
fn design_report_prints_channel_numbers_in_short_form() {
    // The SI supply vessel: q_i0 = 0.1 · 0.12 printed as 0.012 (a product that rounds, as
    // 2131.7999999999997 did elsewhere, is cut at 12 digits) and μ = 1e-11 (it printed as
    // 0.00000000001).
    let vessel = concat!(env!("CARGO_MANIFEST_DIR"), "/../quell/tests/data/supply-vessel.toml");
    let o = quell(&["design", vessel]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stdout(&o).contains("  G_11(s) = 0.012 / (s+0.1)(s+0.12)   (μ_1 = 1e-11)\n"), "{}", stdout(&o));
    assert!(stdout(&o).contains("  H(s) = 1/(1.25 s + 1)\n"), "{}", stdout(&o));
}

/// A run on `[truth]` says so before its figures (a completed run on a mismatched plant did not
/// mention the truth at all); a run on the model does not.
#[test]
fn a_run_on_the_truth_says_so_first() {
    let dir = temp_dir("truth-note");
    let text = fs::read_to_string(paper()).unwrap();
    let truth = format!(
        "{text}\n[truth]\nA = [[-3.52, -1.87, -3.3], [3.08, 1.43, 4.4], [0.33, 0.33, -0.55]]\nu_max = [50.0, 50.0]\n"
    );
    let path = dir.path().join("truth.toml");
    fs::write(&path, truth.replace("t_end = 100.0", "t_end = 5.0")).unwrap();
    let o = quell(&["run", path.to_str().unwrap(), "--no-plots", "--out", dir.path().join("o").to_str().unwrap()]);
    let err = stderr(&o);
    // A × 1.1 entry by entry: ‖ΔA‖/‖A‖ = 0.1.
    assert!(
        err.starts_with("simulating the true plant ([truth]), not the design model: truth.A is 10 % off plant.A (‖ΔA‖/‖A‖), truth.u_max [50, 50] clipping u_f\n"),
        "{err}"
    );
    let model = dir.path().join("model.toml");
    fs::write(&model, text.replace("t_end = 100.0", "t_end = 5.0")).unwrap();
    let o = quell(&["run", model.to_str().unwrap(), "--no-plots", "--out", dir.path().join("m").to_str().unwrap()]);
    assert!(!stderr(&o).contains("[truth]"), "{}", stderr(&o));
}

/// design.json carries what u_f (5) is made of: K, F and the design model's delays τ_i, so that
/// u_f(t) = −K x̂(t) + F u(t − τ) is recomputed from it and a `--states` run's signals.csv alone
/// (a tryout could not: the delays were missing). On the paper's example (τ = 1 s and 3 s, rows
/// every 0.1 s, so every delayed command is a row), to 1e-12 of u_f's peak: the same products in
/// another order, over numbers written to round-trip.
#[test]
fn design_json_and_signals_give_the_plant_input_again() {
    let dir = temp_dir("uf-again");
    let out = dir.path().join("out");
    let o = quell(&["run", "--states", "--no-plots", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let d = read_json(&out.join("design.json"));
    assert_eq!(d["delays"], serde_json::json!([1.0, 3.0]));
    assert_eq!(d["time_unit"], "s");
    let rows = |m: &Value| -> Vec<Vec<f64>> {
        m.as_array()
            .unwrap()
            .iter()
            .map(|r| r.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect())
            .collect()
    };
    let (K, F, tau) = (
        rows(&d["K"]),
        rows(&d["F"]),
        d["delays"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect::<Vec<_>>(),
    );
    let text = fs::read_to_string(out.join("signals.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let table: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    let step = table[1][0] - table[0][0];
    let (mut worst, mut peak) = (0.0f64, 0.0f64);
    for (k, row) in table.iter().enumerate() {
        for i in 0..2 {
            let x_hat: f64 = (0..3).map(|j| K[i][j] * row[col(&format!("xhat{}", j + 1))]).sum();
            let u_d: f64 = (0..2)
                .map(|j| {
                    let back = (tau[j] / step).round() as usize;
                    F[i][j] * if k >= back { table[k - back][col(&format!("u{}", j + 1))] } else { 0.0 }
                })
                .sum();
            let u_f = row[col(&format!("uf{}", i + 1))];
            worst = worst.max((u_f - (u_d - x_hat)).abs());
            peak = peak.max(u_f.abs());
        }
    }
    assert!(peak > 1.0 && worst <= 1e-12 * peak, "u_f recomputed off by {worst:e} of a peak {peak}");
}

/// `quell design --auto` verifies on the file's method; on DOP853 (`method = "explicit"`) a design
/// whose law it makes stiff (Wood–Berry's column: μ at 10ρ) is cautioned, as `quell run` of the
/// written file would be.
#[test]
fn an_automatic_design_verified_on_dop853_at_a_stiff_mu_is_cautioned() {
    let dir = temp_dir("auto-explicit");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/wood-berry.toml");
    let text = fs::read_to_string(data).unwrap();
    let (head, rest) = text.split_once("\n[design]\n").unwrap();
    let rest = &rest[rest.find("[[reference.components]]").unwrap()..];
    let file = dir.path().join("column.toml");
    let body = format!("{head}\n[design]\n\n{rest}");
    fs::write(&file, body.replace("\n[simulation]\n", "\n[simulation]\nmethod = \"explicit\"\n")).unwrap();
    let o = quell(&["design", file.to_str().unwrap(), "--auto"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let caution =
        "⚠ warning: the chosen design was verified on DOP853: simulation.method = \"explicit\" on a stiff adaptive law";
    assert_eq!(stderr(&o).matches(caution).count(), 1, "once: {}", stderr(&o));
    fs::write(&file, body).unwrap();
    let o = quell(&["design", file.to_str().unwrap(), "--auto"]);
    assert!(o.status.success() && !stderr(&o).contains("stiff adaptive law"), "{}", stderr(&o));
}

/// `--t-end` and `--output-step` set simulation.t_end and .output_step: the same signals.csv, byte
/// for byte, as the scenario with those keys written in; a bad value names the key and the flag,
/// and a bad value in the file is not blamed on a flag.
#[test]
fn t_end_and_output_step_flags_are_the_scenario_keys() {
    let dir = temp_dir("t-end-flags");
    let paper = examples_dir().join("paper.toml");
    let text = fs::read_to_string(&paper).unwrap();
    let start = text.find("[simulation]").unwrap() + "[simulation]".len();
    let edited = dir.path().join("short.toml");
    let with_keys = format!("{}\nt_end = 5.0\noutput_step = 0.5{}", &text[..start], &text[start..]);
    fs::write(&edited, with_keys.replace("\nt_end = 100.0", "").replace("\noutput_step = 0.1", "")).unwrap();
    let (by_flags, by_file) = (dir.path().join("flags"), dir.path().join("file"));
    let o = quell(&[
        "run",
        paper.to_str().unwrap(),
        "--t-end",
        "5",
        "--output-step",
        "0.5",
        "--no-plots",
        "--out",
        by_flags.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = quell(&["run", edited.to_str().unwrap(), "--no-plots", "--out", by_file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let signals = fs::read_to_string(by_flags.join("signals.csv")).unwrap();
    assert_eq!(signals.lines().count(), 1 + 11, "rows at 0, 0.5, …, 5");
    assert!(signals.lines().last().unwrap().starts_with("5,"), "{signals}");
    assert_eq!(signals, fs::read_to_string(by_file.join("signals.csv")).unwrap());

    let o = quell(&["run", paper.to_str().unwrap(), "--t-end", "nan", "--out", by_flags.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("error: simulation.t_end (--t-end): expected a finite number, found NaN"),
        "{}",
        stderr(&o)
    );
    let o = quell(&["run", paper.to_str().unwrap(), "--output-step", "50", "--t-end", "1", "--out", "unused"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("simulation.output_step (--output-step): expected an output step ≤ t_end = 1, found 50")
    );
    // The file's output step against a --t-end: the flag named, and the fix.
    let o = quell(&["run", paper.to_str().unwrap(), "--t-end", "0.05", "--out", "unused"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("found 0.1 (the file's output_step, against --t-end: give --output-step too)"),
        "{}",
        stderr(&o)
    );
    // --continuous discards the file's sample time before a --t-end shorter than it is checked.
    let sampled = examples_dir().join("paper-sampled.toml");
    let args = ["run", sampled.to_str().unwrap(), "--continuous", "--t-end", "0.0005", "--output-step", "0.0005"];
    let o = quell(&[&args[..], &["--no-plots", "--out", by_flags.to_str().unwrap()]].concat());
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let bad_file = dir.path().join("bad.toml");
    fs::write(&bad_file, text.replace("t_end = 100.0", "t_end = -3.0")).unwrap();
    let o = quell(&["run", bad_file.to_str().unwrap(), "--output-step", "0.5", "--out", "unused"]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("simulation.t_end: expected a final time > 0, found -3") && !e.contains("--t-end"), "{e}");
}

/// A flag that overrides a `[simulation]` key does not hide a bad value of it in the file (a
/// `sample_time = true` that `quell design` refused had run under `--sample-time`): refused, exit
/// 2, named as the file's, not the flag's.
#[test]
fn a_flag_does_not_hide_a_bad_value_in_the_file() {
    let dir = temp_dir("bad-file-value");
    let text = fs::read_to_string(examples_dir().join("paper.toml")).unwrap();
    for (key, bad, flags) in [
        ("sample_time", "true", ["run", "--sample-time", "0.1"]),
        ("sample_time", "-1.0", ["export", "--sample-time", "0.1"]),
        ("t_end", "\"abc\"", ["run", "--t-end", "2"]),
        ("output_step", "[1, 2]", ["run", "--output-step", "0.5"]),
    ] {
        let file = dir.path().join(format!("{key}.toml"));
        let edited = text
            .replace("\nt_end = 100.0", "\nt_end = 3.0")
            .replace("[simulation]", &format!("[simulation]\n{key} = {bad}"));
        let edited = match key {
            "t_end" => edited.replace("\nt_end = 3.0", ""),
            "output_step" => edited.replace("\noutput_step = 0.1", "\n"),
            _ => edited,
        };
        fs::write(&file, edited).unwrap();
        let out = dir.path().join("out");
        let mut args = vec![flags[0], file.to_str().unwrap(), "--out", out.to_str().unwrap()];
        args.extend(&flags[1..]);
        let o = quell(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let want = format!("error: {}: simulation.{key}: expected ", file.display());
        assert!(stderr(&o).starts_with(&want), "{args:?}: {}", stderr(&o));
        assert!(!out.exists(), "{args:?}: nothing written");
    }
}

/// Run, sweep and tune each own their output directory: one holding another's output is refused
/// (exit 2) with nothing changed (a sweep had replaced a run's summary.json beside its
/// signals.csv); the same command again, and an export beside any of them, still write there.
#[test]
fn a_directory_holding_another_commands_output_is_refused() {
    let dir = temp_dir("mixed-out");
    let out = dir.path().join("out");
    let paper = examples_dir().join("paper.toml");
    let study = dir.path().join("study.toml");
    fs::write(
        &study,
        format!(
            "scenario = {:?}\n[simulation]\nt_end = 1.0\n[grid]\n\"design.mu[0]\" = [1.0]\n",
            paper.to_str().unwrap()
        ),
    )
    .unwrap();
    let run = ["run", "--t-end", "1", "--no-plots", "--out", out.to_str().unwrap()];
    let o = quell(&run);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let summary = fs::read(out.join("summary.json")).unwrap();
    let o = quell(&["sweep", study.to_str().unwrap(), "--no-plots", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains(&format!(
            "--out {}: it holds the output of `quell run` (signals.csv), which this command's files would mix with; choose another output directory",
            out.display()
        )),
        "{}",
        stderr(&o)
    );
    assert_eq!(fs::read(out.join("summary.json")).unwrap(), summary);
    assert!(!out.join("runs.csv").exists());
    let o = quell(&run);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = quell(&["export", paper.to_str().unwrap(), "--sample-time", "0.01", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let swept = dir.path().join("swept");
    let o = quell(&["sweep", study.to_str().unwrap(), "--no-plots", "--out", swept.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = quell(&["run", "--t-end", "1", "--no-plots", "--out", swept.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("holds the output of `quell sweep` (runs.csv)"), "{}", stderr(&o));
    // A sweep killed before its runs.csv leaves its journal, which marks the directory as well.
    let killed = dir.path().join("killed");
    fs::create_dir_all(&killed).unwrap();
    fs::write(killed.join("runs.partial.csv"), "run,point\n").unwrap();
    let o = quell(&["run", "--t-end", "1", "--no-plots", "--out", killed.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("holds the output of `quell sweep` (runs.partial.csv)"), "{}", stderr(&o));
}

/// A report that cannot be written to stdout (a full disk under `> design.json`) is a failure,
/// exit 1 and named; a closed pipe (`| head`) is not.
#[test]
fn a_report_cut_short_on_stdout_fails_and_a_closed_pipe_does_not() {
    use std::process::Stdio;
    let full = fs::OpenOptions::new().write(true).open("/dev/full").expect("/dev/full opens");
    let o = Command::new(env!("CARGO_BIN_EXE_quell"))
        .args(["design", &paper(), "--json"])
        .stdout(Stdio::from(full))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("cannot write to standard output (No space left on device"), "{}", stderr(&o));
    // A reader that stops at once: the pipe closes under the report.
    let mut child = Command::new(env!("CARGO_BIN_EXE_quell"))
        .args(["design", &paper()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// A run whose signals.csv would pass 1 GB is warned of before it starts, with the size and the
/// flag that writes less (a servo at an output step of 5e-7 s had written 2.4 GB without a word);
/// here a step budget of 10 ends it at once.
#[test]
fn a_run_whose_signals_would_take_gigabytes_is_warned_of() {
    let dir = temp_dir("big-csv");
    let out = dir.path().display().to_string();
    let args =
        ["run", &paper(), "--output-step", "1e-5", "--t-end", "50", "--max-steps", "10", "--no-plots", "--out", &out];
    let o = quell(&args);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    // 5e6 + 1 rows of 1 + 5·2 + 2·8 = 27 numbers, about 20 bytes each.
    assert!(
        stderr(&o).starts_with("⚠ warning: signals.csv will hold 5.000e6 rows of 27 numbers, about 2.7 GB; a longer simulation.output_step (--output-step) writes less"),
        "{}",
        stderr(&o)
    );
    let o = quell(&["run", &paper(), "--t-end", "1", "--no-plots", "--out", &out]);
    assert!(!stderr(&o).contains("will hold"), "{}", stderr(&o));
    // One refused for the memory its rows take is refused before its --out is made.
    let fresh = dir.path().join("fresh").display().to_string();
    let o = quell(&["run", &paper(), "--output-step", "1.005e-5", "--no-plots", "--out", &fresh]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("GiB of recorded signals") && !Path::new(&fresh).exists(), "{}", stderr(&o));
}

/// The whole loop's advice follows the channels' figures, unindented: it had been printed as if
/// it were the last channel's (helper tryout, 2026-12-06). The disk servo has two such lines (its
/// disturbance observer, u_f's cancellation) and no channel advice of its own.
#[test]
fn the_whole_loops_advice_is_not_the_last_channels() {
    let dir = temp_dir("loop-advice");
    let hdd = Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/hdd-servo.toml");
    let o = quell(&["run", hdd.to_str().unwrap(), "--no-plots", "--out", dir.path().join("o").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    let lines: Vec<&str> = out.lines().collect();
    let last_channel = lines.iter().rposition(|l| l.starts_with("channel ")).expect("a channel line");
    let whole: Vec<usize> = (0..lines.len()).filter(|&k| lines[k].starts_with("advice (the whole loop): ")).collect();
    assert!(whole.len() >= 2, "{out}");
    assert!(whole.iter().all(|&k| k > last_channel), "{out}");
    assert!(lines[whole[0]].contains("the disturbance observer passes ω"), "{out}");
}

/// A --delay-error asked for and met by no candidate is an infeasible target, as an unmet
/// --u-limit is: exit 2 and nothing written (it had exited 0 with the design written; helper
/// tryout, 2026-12-07). The paper's plant holds at ±3 %, not ±30 %; at ±3 % the design is written.
#[test]
fn an_unmet_delay_error_writes_nothing_and_exits_2() {
    let dir = temp_dir("delay-unmet");
    let input = paper_without_design(&dir);
    let out = dir.path().join("out.toml");
    let o =
        quell(&["design", input.to_str().unwrap(), "--auto", "--delay-error", "0.3", "--write", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("error: --delay-error 0.3: the automatic design does not hold at ±30 % (its delay check: the tail bound and the effort"), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(
            "by up to 3 %, not at 30 %: know the delays that well); nothing written; ask for a smaller --delay-error"
        ),
        "{}",
        stderr(&o)
    );
    assert!(
        stdout(&o).contains("  delays (the --delay-error 0.3 asked for is a condition of writing the design): "),
        "{}",
        stdout(&o)
    );
    assert!(!out.exists());
    let o = quell(&[
        "design",
        input.to_str().unwrap(),
        "--auto",
        "--delay-error",
        "0.03",
        "--write",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(out.exists());
}

/// The automatic design's delay lines (helper tryout, 2026-12-06): plant delays all 0 say that
/// nothing was checked (no line had read as a check skipped), and with a `[truth]` whose delays
/// are not the model's the summary says whose delays it scaled.
#[test]
fn the_delay_check_says_when_it_has_nothing_to_check_and_whose_delays_it_scaled() {
    let dir = temp_dir("delay-lines");
    let input = paper_without_design(&dir);
    let text = fs::read_to_string(&input).unwrap();
    let zero = dir.path().join("zero.toml");
    fs::write(&zero, text.replace("delays = [1.0, 3.0]", "delays = [0.0, 0.0]")).unwrap();
    let o = quell(&["design", zero.to_str().unwrap(), "--auto"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stdout(&o).contains("\n  delays: all 0, so no delay error was checked\n"), "{}", stdout(&o));
    let truth = dir.path().join("truth.toml");
    fs::write(&truth, format!("{text}\n[truth]\ndelays = [1.02, 2.9]\n")).unwrap();
    let o = quell(&["design", truth.to_str().unwrap(), "--auto"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("  delays (not a condition of passing; --delay-error E slows the chosen channel poles until ±E holds) (the errors are of [truth]'s delays, not the model's [1, 3]): "),
        "{out}"
    );
    assert!(out.contains("×1.1 (τ = [1.122, 3.19] s)"), "{out}");
    // A run that completed says what it missed (the summary had blamed the tail bound where only
    // u_f had grown past twice the verified run's).
    let flagged: Vec<&str> = out.lines().filter(|l| l.contains("worst tail") && l.contains(" ⚠")).collect();
    assert!(!flagged.is_empty(), "{out}");
    for line in &flagged {
        let missed = line.rsplit_once(" ⚠ ").expect("what it missed").1;
        assert!(missed.split(", ").all(|m| ["tail", "effort", "u_limit"].contains(&m)), "{line}");
    }
    // The summary names what the last level's runs missed, each once, or that all held.
    let summary = out.lines().find(|l| l.starts_with("  delays (not a condition")).expect("the summary");
    let runs: Vec<&str> = out.lines().filter(|l| l.starts_with("    ×")).collect();
    let last_level = &runs[runs.len() - 2..];
    let missed = |code: &str| {
        last_level.iter().any(|l| l.rsplit_once(" ⚠ ").is_some_and(|(_, m)| m.split(", ").any(|x| x == code)))
    };
    if summary.contains(" hold with the true input delays ") {
        assert!(!last_level.iter().any(|l| l.contains(" ⚠")), "{out}");
    } else {
        assert!(summary.contains("with the true input delays") && summary.contains(", the runs miss "), "{summary}");
        assert_eq!(summary.contains("the tail bound"), missed("tail"), "{out}");
        assert_eq!(summary.contains("the effort (max|u_f| within 2× the verified run's)"), missed("effort"), "{out}");
    }
}

/// A regulated channel (g = 0) settles within 2 % of its own peak error, which the summary says
/// (a two-area power system's 0.098 pu tail "settled (2 % band)", five times its load step; helper
/// tryout, 2026-12-06); a tracking channel's band is the reference's. Both times to four digits.
#[test]
fn a_regulated_channels_settling_band_says_whose_peak_it_is() {
    let text = fs::read_to_string(examples_dir().join("three-channel.toml")).unwrap();
    let tracked = "components = [ { harmonics = [{ amplitude = 1.0, frequency = 0.5 }] },";
    assert!(text.contains(tracked));
    let dir = temp_dir("regulated");
    let file = dir.path().join("scenario.toml");
    fs::write(&file, text.replacen(tracked, "components = [ { bias = 0.0 },", 1)).unwrap();
    let out = dir.path().join("out");
    let o = quell(&["run", file.to_str().unwrap(), "--out", out.to_str().unwrap(), "--no-plots"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stdout(&o);
    let line = |i: usize| err.lines().find(|l| l.starts_with(&format!("channel {i}:"))).unwrap_or_default().to_string();
    assert!(
        line(1)
            .contains("settled (2 % band of its peak error, at least 1e-10 of the loop's signals, g being 0) at t = "),
        "{err}"
    );
    assert!(line(2).contains("settled (2 % band) at t = "), "{err}");
    // The time to four significant digits, as the other figures (31.86666666667 h had been printed).
    for i in 1..=2 {
        let at = line(i).split(") at t = ").nth(1).unwrap().split(' ').next().unwrap().to_string();
        let digits = at.trim_start_matches(['0', '.']).chars().filter(char::is_ascii_digit).count();
        assert!(digits <= 4 && at.parse::<f64>().is_ok(), "{at}");
    }
}

/// A sampled run that diverges under its noise and completes without it is told so before the
/// sampling's advice, which is for the noise-free loop (a bicycle under 0.2 mrad of noise had
/// been told only to sample faster, and diverged as fast there; helper tryout, 2026-12-06).
#[test]
fn a_run_the_noise_drives_away_is_told_so() {
    let dir = temp_dir("noise-drives");
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/whipple-bicycle-noise.toml");
    let out = dir.path().join("out");
    let args = ["--t-end", "3", "--output-step", "0.0005", "--sample-time", "0.0005", "--no-plots", "--out"];
    let o = quell(&[&["run", file.to_str().unwrap()][..], &args[..], &[out.to_str().unwrap()]].concat());
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let text = stdout(&o);
    let noise = text
        .find("advice: the run diverged under its [noise] and completes without it at the same sample time")
        .expect(&text);
    let sampling = text.find("advice: the sampled-data loop at T_s = 0.0005 s").expect(&text);
    assert!(noise < sampling, "{text}");
}

/// A sampled scenario's automatic design (the Pelican arm of `tests/data` at 1 ms, without its
/// noise and design): the observer's reason gives its whole factor over the rules' poles, the
/// sampled-data start's and the relaxation's (it had read "r_o = 473.86 …; then ×0.25 of that" at
/// ×1/64 of it), and the delay check runs the delays off by its factor exactly, in fractions of a
/// sample (2 ms × 1.1 at 1 ms had been rounded to 3 ms, +50 %; helper tryout, 2026-12-07).
#[test]
fn a_sampled_automatic_design_says_its_whole_factors() {
    let text =
        fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/pelican-arm-noise.toml"))
            .unwrap();
    let (start, end) = (text.find("[design]").unwrap(), text.find("[reference]").unwrap());
    let noise = text.find("[noise]").unwrap();
    let scenario = format!("{}[design]\n{}", &text[..start], &text[end..noise]);
    let dir = temp_dir("arm-auto");
    let path = dir.path().join("arm.toml");
    fs::write(&path, scenario).unwrap();
    let o = quell(&["design", path.to_str().unwrap(), "--auto"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report = stdout(&o);
    let observer = report.lines().skip_while(|l| !l.starts_with("  design.observer_poles = ")).nth(1).unwrap();
    assert!(
        observer.contains("; then ×0.015625 of that in all: ×0.0625 in the first candidate (see the verification's candidates) and ×0.25 in the relaxation"),
        "{observer}"
    );
    assert!(report.contains("    ×1.1 (τ = [0.0022, 0.0044] s): "), "{report}");
}

/// A passing automatic design whose report calls μ too small for the horizon (the averaged law's
/// estimate, beyond the stiffness cap) is told that its verifying run at this t_end met the tail
/// bound, which decides: a piezo stage (`quell/tests/data/piezo-stage.toml`, 739 Hz, SI units) had
/// been told in the same output to lengthen t_end (helper tryout, 2026-12-07).
#[test]
fn a_passing_design_called_too_slow_for_its_horizon_is_told_the_run_decides() {
    let piezo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/piezo-stage.toml");
    let o = quell(&["design", piezo.to_str().unwrap(), "--auto"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report = stdout(&o);
    assert!(report.contains("is too small for the horizon"), "{report}");
    let note = report
        .lines()
        .find(|l| l.starts_with("note: the design report's \"too small for the horizon\""))
        .expect(&report);
    let worst: f64 = note.split("(the worst tail ").nth(1).and_then(|r| r.split(' ').next()).unwrap().parse().unwrap();
    assert!(worst <= 1.0, "{note}");
}

/// Under --u-limit, the design report's advice to raise μ (the averaged law's pace) is noted as
/// unchecked against the limit: a mixing tank (`quell/tests/data/mixing-tank.toml`, minutes)
/// verified within 0.051 and 0.1 was told to raise μ₂ to 18, which breaks them. A run of the
/// written scenario with that μ (another path than the automatic design's) shows why.
#[test]
fn a_raise_of_mu_under_an_actuator_limit_is_noted_as_unchecked() {
    let dir = temp_dir("ulimit-note");
    let tank = Path::new(env!("CARGO_MANIFEST_DIR")).join("../quell/tests/data/mixing-tank.toml");
    let out = dir.path().join("tank-auto.toml");
    let o = quell(&[
        "design",
        tank.to_str().unwrap(),
        "--auto",
        "--u-limit",
        "0.051,0.1",
        "--write",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = stdout(&o);
    let raise = text.split_once("raise design.mu[1] to ").expect("the report's raise").1;
    let mu2: f64 = raise.split_once(' ').unwrap().0.parse().unwrap();
    assert!(text.contains("note: the design report's advice to raise design.mu is the averaged law's pace and knows no actuator limit"), "{text}");
    let written = fs::read_to_string(&out).unwrap();
    let line = written.lines().find(|l| l.starts_with("mu = [")).unwrap();
    let mu1 = line.trim_start_matches("mu = [").split(',').next().unwrap();
    let raised = dir.path().join("raised.toml");
    fs::write(&raised, written.replace(line, &format!("mu = [{mu1}, {mu2}]"))).unwrap();
    let run = dir.path().join("run");
    let o = quell(&["run", raised.to_str().unwrap(), "--out", run.to_str().unwrap(), "--no-plots"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let summary = read_json(&run.join("summary.json"));
    let peaks: Vec<f64> =
        summary["channels"].as_array().unwrap().iter().map(|c| c["max_uf"].as_f64().unwrap()).collect();
    assert!(peaks[0] > 0.051 || peaks[1] > 0.1, "μ₂ = {mu2}: max|u_f| {peaks:?} within the limits");
}
