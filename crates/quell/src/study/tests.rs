//! Study-file parsing: every mistake names its key; expansion, seeds, draws and quantiles.

use super::*;

fn study(text: &str) -> Result<Study, StudyError> {
    Study::from_toml(text, None)
}

/// The error of a study with `text`, as `key: message`.
fn error(text: &str) -> String {
    study(text).expect_err("the study must be refused").to_string()
}

/// A law on a value the scenario leaves infinite is refused, but not where a grid gives it finite
/// values (the draws perturb those; the refusal had broken such a study; diff review).
#[test]
fn a_law_on_an_infinite_value_is_refused_unless_a_grid_sets_it() {
    let law = "[monte_carlo]\nruns = 2\n\"truth.u_max\" = { relative = 0.1 }\n";
    assert!(error(law).contains("truth.u_max in the paper's example is infinite (no limit)"));
    let gridded = format!("[grid]\n\"truth.u_max\" = [[30.0, 30.0], [50.0, 50.0]]\n{law}");
    assert_eq!(study(&gridded).unwrap().len(), 4);
}

#[test]
fn paper_example_by_default() {
    let s = study("").unwrap();
    assert_eq!((s.points(), s.draws(), s.len(), s.m), (1, 1, 1, 2));
    assert_eq!(s.scenario_source, "the paper's example");
    assert!(!s.truth_differs());
}

#[test]
fn grid_is_a_product_with_the_first_axis_slowest() {
    let s = study("[grid]\n\"design.mu[0]\" = [5.0, 10.0, 20.0]\n\"design.beta\" = [1.0, 2.0]\n").unwrap();
    assert_eq!(s.points(), 6);
    let idx: Vec<Vec<usize>> = (0..6).map(|p| s.grid_index(p)).collect();
    assert_eq!(idx, [[0, 0], [0, 1], [1, 0], [1, 1], [2, 0], [2, 1]]);
    let spec = s.spec_with_nominal(3).unwrap();
    assert_eq!(spec.scenario["design"]["mu"][0].as_float(), Some(10.0));
    assert_eq!(spec.scenario["design"]["beta"].as_float(), Some(2.0));
    assert_eq!(spec.scenario["design"]["mu"][1].as_float(), Some(30.0));
}

#[test]
fn whole_vectors_and_matrices_are_grid_keys() {
    let s = study("[grid]\n\"design.mu\" = [[20, 30], [25, 25]]\n\"plant.x0\" = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]]\n")
        .unwrap();
    assert_eq!(s.points(), 4);
    assert_eq!(s.spec_with_nominal(3).unwrap().scenario["plant"]["x0"][0].as_float(), Some(0.1));
    assert_eq!(s.spec_with_nominal(3).unwrap().grid[0].1.to_string(), "[25, 25]");
}

#[test]
fn study_mistakes_name_their_key() {
    let cases: &[(&str, &str)] = &[
        ("[grid]\n\"design.beta\" = [1.0]\n\"design.beta\" = [2.0]", "syntax: line 3, column 1: duplicate key `\"design.beta\"`: a key may be given once in a table, keep one (the study file is not valid TOML)"),
        ("[grid]\n\"reference.components[0].harmonics[0].frequency\" = [2.0, 1e15]", "grid.\"reference.components[0].harmonics[0].frequency\"[1]: with reference.components[0].harmonics[0].frequency = 1e15 the scenario is not valid: reference.components[0].harmonics[0].frequency: ω = 1e15 rad/s needs at least"),
        ("[simulation]\nsample_time = 0.001\n[grid]\n\"plant.delays[0]\" = [1.0, 1.0005]", "grid.\"plant.delays[0]\"[1]: with plant.delays[0] = 1.0005 the scenario is not valid: simulation.sample_time: channel 1's delay τ = 1.0005 s is not a whole number of samples"),
        ("sceanrio = \"x.toml\"", "sceanrio: unknown key (did you mean `scenario`?); valid keys at the top level"),
        ("[runaway]\npaek = 50", "runaway.paek: unknown key (did you mean `peak`?); valid keys in [runaway]: peak, steps"),
        ("scenario = 3", "scenario: expected the scenario file's path (a string) or a scenario table, found an integer"),
        ("scenario = \"/nonexistent/x.toml\"", "scenario: cannot read the scenario file \"/nonexistent/x.toml\" (No such file or directory (os error 2))"),
        ("[grid]\n\"simulation.precision\" = [\"f64\", \"f32\"]", "grid.\"simulation.precision\": the precision is not a grid key"),
        ("[grid]\n\"design.nu\" = [1.0]", "grid.\"design.nu\": design.nu is not a value of the scenario (design has no nu)"),
        // A misspelt key of a known table names the nearest (names of three letters or more).
        ("[grid]\n\"truth.delay[0]\" = [0.2]", "grid.\"truth.delay[0]\": truth.delay[0] is not a value of the scenario (the scenario has no truth) (did you mean truth.delays?); grid and Monte Carlo keys"),
        ("[grid]\n\"design.betta\" = [1.0]", "grid.\"design.betta\": design.betta is not a value of the scenario (design has no betta) (did you mean design.beta?)"),
        ("[grid]\n\"design.mu[2]\" = [1.0]", "grid.\"design.mu[2]\": design.mu[2] is not a value of the scenario (design.mu has no [2] (it has 2 entries))"),
        ("[grid]\n\"design.mu\" = [[1.0, 2.0, 3.0]]", "grid.\"design.mu\"[0]: expected a vector of 2 numbers (the shape of design.mu in the paper's example), found a vector of 3 numbers"),
        ("[grid]\n\"plant.A\" = [[[1.0]]]", "grid.\"plant.A\"[0]: expected a 3×3 matrix"),
        // A key the scenario leaves to its default is not said to be in the scenario.
        ("[grid]\n\"truth.A\" = [[[1.0, 2.0]]]", "grid.\"truth.A\"[0]: expected a 3×3 matrix (the shape truth.A takes by default in the paper's example, which leaves it out), found a 1×2 matrix"),
        ("[grid]\n\"design.mu[0]\" = []", "grid.\"design.mu[0]\": expected a non-empty list of values, found an empty array"),
        ("[grid]\n\"design.mu[0]\" = 5.0", "grid.\"design.mu[0]\": expected a list of values (e.g. [5.0, 10.0]), found a floating-point number"),
        ("[grid]\n\"design.mu[0]\" = [5.0, \"x\"]", "grid.\"design.mu[0]\"[1]: expected a number (the shape of design.mu[0]), found a string"),
        ("[grid]\n\"design.mu[0]\" = [5.0, -1.0]", "grid.\"design.mu[0]\"[1]: with design.mu[0] = -1.0 the scenario is not valid: design.mu[0]"),
        ("[grid]\n\"name\" = [1.0]", "grid.\"name\": name in the paper's example is a string, not a number, vector or matrix"),
        ("[grid]\n\"design.mu[x]\" = [1.0]", "grid.\"design.mu[x]\": `design.mu[x]` is not a key path"),
        // An optional key the scenario leaves out: give it there first.
        ("[grid]\n\"simulation.sample_time\" = [0.001, 0.01]", "grid.\"simulation.sample_time\": simulation.sample_time is not a value of the scenario (simulation has no sample_time): simulation.sample_time is optional and the scenario leaves it out; give it a value in the scenario file"),
        // The components' sizes, 1 each where the scenario leaves them out (a review found the message
        // said only that design has no reference_sizes).
        ("[grid]\n\"design.reference_sizes[0]\" = [1.0, 10.0]", "grid.\"design.reference_sizes[0]\": design.reference_sizes[0] is not a value of the scenario (design has no reference_sizes): design.reference_sizes is optional and the scenario leaves it out; give it a value in the scenario file"),
        ("[simulation]\nt_end = -1.0", "simulation.t_end: expected a final time > 0, found -1"),
        ("[simulation]\nsteps = 3", "simulation.steps: unknown key; valid keys in [simulation]"),
        ("[simulation]\nmethod = \"imx\"", "simulation.method: expected \"auto\" (DOP853"),
        ("[grid]\n\"simulation.method\" = [\"auto\", \"imex\"]", "grid.\"simulation.method\": the integrator is not a grid key"),
        ("scenario = \"\"", "scenario: expected the scenario file's path, found an empty string"),
        ("[grid]\n\"reference.components[0].bias\" = [0.5]", "grid.\"reference.components[0].bias\": reference.components[0].bias is not a value of the scenario (reference.components[0] has no bias): reference.components[0].bias is optional and the scenario leaves it out; give it a value in the scenario file"),
        ("max_steps = 0", "max_steps: expected a step budget per run (an integer ≥ 1), found 0"),
        ("max_steps = 100\n[simulation]\nsample_time = 0.01\n[grid]\n\"simulation.sample_time\" = [0.01, 0.02]", "max_steps: a step budget applies to the continuous loop"),
        ("[monte_carlo]\nruns = 2\n\"truth.u_max\" = { normal = 1.0 }", "monte_carlo.\"truth.u_max\": truth.u_max in "),
        // A component that is not there is named so, not called optional.
        ("[grid]\n\"reference.components[5].bias\" = [0.5]", "grid.\"reference.components[5].bias\": reference.components[5].bias is not a value of the scenario (reference.components has no [5] (it has 2 entries)); grid and Monte Carlo keys"),
        // Ignored in a sampled-data study, as a sampled run refuses a budget (hostile review); a grid
        // over the sample time needs the scenario's, so its runs are all sampled too.
        ("max_steps = 100\n[simulation]\nsample_time = 0.01", "max_steps: a step budget applies to the continuous loop; this study's runs are sampled-data (simulation.sample_time = 0.01)"),
        ("[runaway]\npeak = 0.5", "runaway.peak: expected a factor ≥ 1 (or inf to turn the rule off), found 0.5"),
        ("[runaway]\nsteps = 0", "runaway.steps: expected a factor ≥ 1 (or inf to turn the rule off), found 0"),
        ("[runaway]\nsteps = nan", "runaway.steps: expected a factor ≥ 1 (or inf to turn the rule off), found NaN"),
        ("[runaway]\npeak = \"big\"", "runaway.peak: expected a factor ≥ 1 (or inf to turn the rule off), found a string"),
        ("[runaway]\nbound = 3", "runaway.bound: unknown key; valid keys in [runaway]: peak, steps"),
        ("runaway = 3", "runaway: expected a table, found an integer"),
        ("[settle]\nrelative = -0.1", "settle.relative: expected a band ≥ 0, found -0.1"),
        ("[settle]\nrelative = 0.0", "settle: both settle.relative and settle.absolute are 0"),
        ("[settle]\nband = 0.1", "settle.band: unknown key; valid keys in [settle]: relative, absolute"),
        ("[tune]\nobjective = \"settle_t\"", "tune.mu: missing; required: the search interval"),
        ("[tune]\nmu = [[1.0, 2.0]]", "tune.mu: expected 2 entries (one per channel), found 1"),
        ("[tune]\nmu = [[1.0, 10.0], [2.0]]", "tune.mu[1]: expected [μ_min, μ_max], found an array of 1 entry"),
        ("[tune]\nmu = [0.0, 10.0]", "tune.mu: expected 0 < μ_min ≤ μ_max (the search is on a log scale), found [0, 10]"),
        ("[tune]\nmu = [1.0, 10.0]\nobjective = \"fast\"", "tune.objective: expected \"settle_t\", \"tail_rms_e\" or \"tail_max_e\", found \"fast\""),
        ("[tune]\nmu = [1.0, 10.0]\nmax_u = [1.0, -2.0]", "tune.max_u[1]: expected a limit on max |u_i| > 0 (inf for none), found -2"),
        ("[tune]\nmu = [1.0, 10.0]\npoints = 1", "tune.points: expected an integer in [2, 10000], found 1"),
        ("[grid", "syntax: line 1, column 6: unclosed table"),
    ];
    each_names_its_key(cases);
}

/// `[monte_carlo]`'s mistakes, as [`study_mistakes_name_their_key`].
#[test]
fn monte_carlo_mistakes_name_their_key() {
    each_names_its_key(&[
            ("[monte_carlo]\nseed = 1", "monte_carlo.runs: missing"),
            ("[monte_carlo]\nruns = 5\nseed = 1", "monte_carlo: expected at least one scenario key with a distribution, found only runs and seed, so every draw would repeat the nominal run; add one such as"),
            ("[monte_carlo]\nrun = 5", "monte_carlo.runs: missing (`run` is no key of [monte_carlo]: did you mean `runs`?); required"),
            ("[monte_carlo]\nruns = 2\nsed = 1", "monte_carlo.\"sed\": unknown key (did you mean `seed`?); [monte_carlo] takes runs, seed and scenario key paths with a distribution"),
            ("[monte_carlo]\nruns = 0", "monte_carlo.runs: expected the number of draws per grid point (an integer ≥ 1), found 0"),
            ("[monte_carlo]\nruns = -3", "monte_carlo.runs: expected the number of draws per grid point (an integer ≥ 1), found -3"),
            ("[monte_carlo]\nruns = 1e12", "monte_carlo.runs: expected the number of draws per grid point (an integer ≥ 1), found 1e12, a floating-point number; write it as an integer, 1000000000000"),
            ("[monte_carlo]\nruns = 2.0", "monte_carlo.runs: expected the number of draws per grid point (an integer ≥ 1), found 2.0, a floating-point number; write it as an integer, 2"),
            ("[monte_carlo]\nruns = 2\nseed = 1.5", "monte_carlo.seed: expected a seed (an integer ≥ 0), found a floating-point number"),
            ("[monte_carlo]\nruns = 2\n\"plant.A\" = { gaussian = 0.1 }", "monte_carlo.\"plant.A\".gaussian: unknown distribution; expected one of { relative = r }"),
            ("[monte_carlo]\nruns = 2\n\"plant.A\" = { relative = -0.1 }", "monte_carlo.\"plant.A\".relative: expected a finite spread ≥ 0, found -0.1"),
            ("[monte_carlo]\nruns = 2\n\"plant.A\" = { normal = inf }", "monte_carlo.\"plant.A\".normal: expected a finite spread ≥ 0, found inf"),
            ("[monte_carlo]\nruns = 2\n\"plant.A\" = 0.1", "monte_carlo.\"plant.A\": expected a distribution"),
            ("[monte_carlo]\nruns = 2\n\"plant.A\" = { relative = 0.1, uniform = 0.1 }", "monte_carlo.\"plant.A\": expected exactly one distribution"),
            ("[monte_carlo]\nruns = 2\n\"plant.E\" = { relative = 0.1 }", "monte_carlo.\"plant.E\": plant.E is not a value of the scenario (plant has no E)"),
    ]);
}

/// Each study text of `cases` is refused with a message that starts as expected.
fn each_names_its_key(cases: &[(&str, &str)]) {
    for (text, expected) in cases {
        let got = error(text);
        assert!(got.starts_with(expected), "study:\n{text}\nexpected: {expected}\ngot:      {got}");
    }
}

/// A study's `[simulation]` method reaches every run (and its nominal run): the paper's example,
/// not stiff, is integrated by the implicit–explicit pair in every step when it says "imex".
#[test]
fn the_study_simulation_method_applies_to_its_runs() {
    let s = study("[simulation]\nt_end = 2.0\nmethod = \"imex\"\n[grid]\n\"design.beta\" = [1.0, 2.0]\n").unwrap();
    let spec = s.spec_with_nominal(1).unwrap();
    assert_eq!(spec.scenario["simulation"]["method"].as_str(), Some("imex"));
    let r = spec.simulate().unwrap();
    let crate::sim::RunStats::Continuous(stats) = r.stats else { panic!("{:?}", r.stats) };
    assert!(stats.steps > 0 && stats.implicit_steps == stats.steps, "{stats:?}");
}

#[test]
fn truth_defaults_to_the_plant_and_a_draw_on_it_differs() {
    let s = study("[monte_carlo]\nruns = 2\n\"plant.delays\" = { uniform = 0.0 }\n").unwrap();
    assert!(!s.truth_differs());
    assert_eq!(s.spec_with_nominal(1).unwrap().scenario["plant"]["delays"][1].as_float(), Some(3.0));
}

/// Draw d's seed depends on the study seed and d only: the same at every grid point, and the
/// specs do not depend on the order they are built in.
#[test]
fn seeds_come_from_the_study_seed_and_the_draw() {
    let s = study("[grid]\n\"design.mu[0]\" = [5.0, 10.0]\n[monte_carlo]\nruns = 3\nseed = 7\n\"design.beta\" = { relative = 0.1 }\n").unwrap();
    assert_eq!(s.len(), 6);
    let later = s.spec_with_nominal(5).unwrap();
    let specs: Vec<RunSpec> = s.specs_with_nominal().collect();
    assert_eq!(specs[5], later);
    for d in 0..3 {
        assert_eq!(specs[d].seed, run_seed(7, d));
        assert_eq!(specs[d].seed, specs[3 + d].seed);
        assert_eq!(specs[d].scenario["design"]["beta"], specs[3 + d].scenario["design"]["beta"]);
    }
    assert_ne!(specs[0].seed, specs[1].seed);
    assert_ne!(run_seed(7, 0), run_seed(8, 0));
}

/// The draws follow their laws: sample moments of 4,000 draws of β = 1 within 5 standard errors
/// (mean: σ/√N; variance: σ²√(2/N) for the normal, and for the uniform σ² √((9/5 − 1)/N)).
#[test]
fn draws_follow_their_laws() {
    let n = 4000;
    let moments = |law: &str| {
        let s = study(&format!("[monte_carlo]\nruns = {n}\nseed = 3\n\"design.beta\" = {law}\n")).unwrap();
        let xs: Vec<f64> =
            (0..n).map(|i| s.spec_with_nominal(i).unwrap().scenario["design"]["beta"].as_float().unwrap()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        (mean, var, xs)
    };
    let nf = n as f64;
    let (mean, var, _) = moments("{ relative = 0.1 }");
    assert!((mean - 1.0).abs() < 5.0 * 0.1 / nf.sqrt(), "mean {mean}");
    assert!((var - 0.01).abs() < 5.0 * 0.01 * (2.0 / nf).sqrt(), "variance {var}");
    let (mean, var, _) = moments("{ normal = 0.2 }");
    assert!((mean - 1.0).abs() < 5.0 * 0.2 / nf.sqrt(), "mean {mean}");
    assert!((var - 0.04).abs() < 5.0 * 0.04 * (2.0 / nf).sqrt(), "variance {var}");
    let (mean, var, xs) = moments("{ uniform = 0.3 }");
    let v: f64 = 0.09 / 3.0;
    assert!((mean - 1.0).abs() < 5.0 * v.sqrt() / nf.sqrt(), "mean {mean}");
    assert!((var - v).abs() < 5.0 * v * (0.8 / nf).sqrt(), "variance {var}");
    assert!(xs.iter().all(|x| (x - 1.0).abs() <= 0.3));
}

/// Every entry of a matrix is perturbed on its own.
#[test]
fn a_relative_draw_perturbs_every_entry() {
    let s = study("[monte_carlo]\nruns = 1\n\"plant.A\" = { relative = 0.05 }\n").unwrap();
    let a = &s.spec_with_nominal(0).unwrap().scenario["plant"]["A"];
    let nominal = [[-3.2, -1.7, -3.0], [2.8, 1.3, 4.0], [0.3, 0.3, -0.5]];
    for (r, row) in nominal.iter().enumerate() {
        for (c, &x) in row.iter().enumerate() {
            let y = a[r][c].as_float().unwrap();
            assert!(y != x && (y / x - 1.0).abs() < 0.05 * 6.0, "A[{r}][{c}] = {y}");
        }
    }
}

/// NumPy's default quantile (method "linear"): numpy.quantile([1, 2, 3, 4], [0, .25, .5, .9, 1])
/// = [1, 1.75, 2.5, 3.7, 4]; numpy.quantile([3, 1, 2], .5) = 2.
#[test]
fn quantiles_match_numpy() {
    let x = [1.0, 2.0, 3.0, 4.0];
    let q: Vec<f64> = [0.0, 0.25, 0.5, 0.9, 1.0].iter().map(|&p| quantile(&x, p).unwrap()).collect();
    for (a, b) in q.iter().zip([1.0, 1.75, 2.5, 3.7, 4.0]) {
        assert!((a - b).abs() < 1e-15, "{q:?}");
    }
    assert_eq!(Quantiles::of(vec![3.0, 1.0, 2.0]).p50, Some(2.0));
    assert_eq!(quantile(&[], 0.5), None);
    let settle = Quantiles::of(vec![1.0, 2.0, f64::INFINITY, f64::INFINITY]);
    assert_eq!((settle.p25, settle.p50, settle.max), (Some(1.75), None, None));
    // The median of 15 settling times, 7 never (+∞): the 8th, 94.8 (numpy.quantile gives NaN from
    // 0·∞; the level falls on a value, which is the quantile). 8 settled of 16: between the 8th
    // and the first ∞, none.
    let mut times: Vec<f64> = (1..=8).map(|k| 87.0 + f64::from(k) * 0.975).collect();
    times.extend([f64::INFINITY; 7]);
    assert_eq!(Quantiles::of(times.clone()).p50, Some(94.8));
    times.push(f64::INFINITY);
    assert_eq!(Quantiles::of(times).p50, None);
}

#[test]
fn shards_partition_the_runs() {
    assert_eq!(Shard::parse("1/3").unwrap(), Shard { index: 1, count: 3 });
    assert!(Shard::parse("3/3").unwrap_err().starts_with("shard index 3 ≥ N = 3"));
    assert!(Shard::parse("0/0").unwrap_err().starts_with("expected N ≥ 1"));
    assert!(Shard::parse("a/2").is_err() && Shard::parse("2").is_err());
    for runs in [0, 1, 7, 10] {
        let mut all: Vec<usize> = (0..3).flat_map(|i| Shard { index: i, count: 3 }.runs(runs)).collect();
        assert_eq!((0..3).map(|i| Shard { index: i, count: 3 }.len(runs)).sum::<usize>(), runs);
        all.sort();
        assert_eq!(all, (0..runs).collect::<Vec<_>>());
    }
}

/// A top-level key written below a table header lands in that table: said so, with the fix; and
/// `max_steps` under a scenario's `[simulation]` names where the step budget goes.
#[test]
fn a_top_level_key_below_a_table_header_is_named_as_misplaced() {
    for (table, body) in
        [("monte_carlo", "runs = 2\n"), ("grid", "\"design.beta\" = [1.0]\n"), ("settle", "relative = 0.1\n")]
    {
        let e = error(&format!("[{table}]\n{body}max_steps = 5\n"));
        assert_eq!(
            e,
            format!("{table}.max_steps: `max_steps` is a key of the study file's top level, but written below the [{table}] header TOML puts it in that table; move it above the file's first [table] header")
        );
    }
    let e = error("[simulation]\nmax_steps = 5\n");
    assert!(e.contains("simulation.max_steps: unknown key (the step budget is a run option, not a scenario key: the max-steps option of quell run, max_steps= of quell.simulate, or max_steps at a study file's top level)"), "{e}");
}

/// Two axes of 200,000 values each (4e10 runs) are refused by their size before any value is
/// designed: checking every value first (about 0.1 ms each) took 40 s before the size refused them,
/// and 300,000 each ran past a minute.
#[test]
fn a_grid_too_large_is_refused_before_its_values_are_checked() {
    let values: Vec<String> = (0..200_000).map(|i| format!("{}", 1.0 + i as f64 * 1e-6)).collect();
    let values = values.join(", ");
    let started = std::time::Instant::now();
    let e = error(&format!("[grid]\n\"design.mu[0]\" = [{values}]\n\"design.mu[1]\" = [{values}]\n"));
    assert!(e.starts_with("grid: the study has 40000000000 runs (40000000000 grid points (200000 × 200000)"), "{e}");
    // Reading 5 MB of TOML and forming the axes: well under a second; 10 s leaves room for load.
    assert!(started.elapsed() < std::time::Duration::from_secs(10), "{:?}", started.elapsed());
}

#[test]
fn studies_beyond_max_runs_are_refused_when_read_with_their_true_size() {
    // 1e12 draws aborted allocating 8 TB, and 2⁶³ − 1 panicked ("capacity overflow"); both are
    // refused before anything is allocated, with the number the file gives.
    for runs in ["1000000000000", "9223372036854775807"] {
        let e = error(&format!("[monte_carlo]\nruns = {runs}"));
        assert_eq!(
            e,
            format!("monte_carlo.runs: expected at most 1e9 draws (a study may have at most 1e9 runs), found {runs}; reduce the draws, or split the study into several files with different seeds")
        );
    }
    // Within the draws' limit, beyond it with the grid: the exact product, not a saturated count.
    let e = error(
        "[grid]\n\"design.beta\" = [1.0, 2.0, 3.0]\n[monte_carlo]\nruns = 600000000\n\"truth.A\" = { relative = 0.05 }",
    );
    assert!(
        e.starts_with(
            "monte_carlo.runs: the study has 1800000000 runs (3 grid points (3) × 600000000 draws), more than the 1e9"
        ),
        "{e}"
    );
    // A grid alone: 10 axes of 10 values are 1e10 points.
    let axes: String = [
        "design.mu[0]",
        "design.mu[1]",
        "design.beta",
        "plant.x0[0]",
        "plant.x0[1]",
        "plant.x0[2]",
        "truth.x0[0]",
        "truth.x0[1]",
        "truth.x0[2]",
        "simulation.t_end",
    ]
    .iter()
    .map(|k| {
        let values: Vec<String> = (1..=10).map(|v| format!("{}.0", v)).collect();
        format!("\"{k}\" = [{}]\n", values.join(", "))
    })
    .collect();
    let e = error(&format!("[grid]\n{axes}"));
    assert!(e.starts_with("grid: the study has 10000000000 runs (10000000000 grid points (10 × 10 × 10 × 10 × 10 × 10 × 10 × 10 × 10 × 10) × 1 draw)"), "{e}");
    // At the limit: read, and its length is exact.
    let s = study(
        "[grid]\n\"design.beta\" = [1.0, 2.0]\n[monte_carlo]\nruns = 500000000\n\"truth.A\" = { relative = 0.05 }",
    )
    .unwrap();
    assert_eq!(s.len(), MAX_RUNS);
}

#[test]
fn two_spellings_of_one_grid_value_are_refused() {
    // design.mu[00] is design.mu[0]; design.mu holds design.mu[1]. Both were accepted, and runs.csv
    // recorded for one key a value the other had overwritten.
    for (a, b) in [("design.mu[0]", "design.mu[00]"), ("design.mu", "design.mu[1]"), ("design.mu[1]", "design.mu")] {
        let value = |k: &str| if k == "design.mu" { "[[10.0, 20.0]]" } else { "[10.0]" };
        let e = error(&format!("[grid]\n\"{a}\" = {}\n\"{b}\" = {}", value(a), value(b)));
        assert_eq!(
            e,
            format!("grid.\"{b}\": names the same value as grid.\"{a}\" (or a part of it), so one would overwrite the other and runs.csv would record a value that was not used; keep one of the two keys")
        );
    }
    // Neighbours that do not overlap stay accepted.
    assert!(study("[grid]\n\"design.mu[0]\" = [10.0]\n\"design.mu[1]\" = [10.0]").is_ok());
}

#[test]
fn tune_refuses_a_grid_or_draws_it_would_ignore() {
    let tune = "[tune]\nobjective = \"tail_rms_e\"\nmu = [1.0, 100.0]\n";
    for (table, key) in [
        ("[grid]\n\"design.beta\" = [1.0, 2.0]\n", "grid"),
        ("[monte_carlo]\nruns = 2\n\"truth.A\" = { relative = 0.05 }\n", "monte_carlo"),
    ] {
        let s = study(&format!("{table}{tune}")).unwrap();
        let e = super::tune(&s, &Default::default()).expect_err("refused").to_string();
        assert!(
            e.starts_with(&format!("{key}: tuning runs the scenario alone, so [{key}] would be ignored; remove it")),
            "{e}"
        );
    }
}

/// A limit of inf is none on that channel, as an absent key is (truth.u_max's inf reads the same).
#[test]
fn an_infinite_tune_limit_is_no_limit_on_its_channel() {
    let s = study("[tune]\nmu = [1.0, 100.0]\nmax_uf = [8.0, inf]\nmax_u = inf\n").unwrap();
    let t = s.tune.expect("[tune]");
    assert_eq!((t.max_uf, t.max_u), (vec![8.0, f64::INFINITY], vec![f64::INFINITY; 2]));
    assert!(error("[tune]\nmu = [1.0, 100.0]\nmax_uf = [8.0, -inf]\n").starts_with("tune.max_uf[1]: expected a limit"));
}

#[cfg(unix)]
#[test]
fn an_endless_input_file_is_refused_naming_its_path() {
    // /dev/zero was read for ever (4 GB in 15 s), then 16 MiB of it; a terminal blocked the read
    // past Ctrl-C: a device is refused before it is opened.
    let zero = Path::new("/dev/zero");
    let e = Study::from_path(zero).expect_err("refused").to_string();
    assert_eq!(
        e,
        "/dev/zero: cannot read the study file: a device, not a file; give the path of a scenario or study file"
    );
    let e = crate::Scenario::from_path(zero).expect_err("refused").to_string();
    assert!(e.starts_with("/dev/zero: cannot read the file: a device, not a file"), "{e}");
    let e = error("scenario = \"/dev/zero\"");
    assert!(e.starts_with("scenario: cannot read the scenario file \"/dev/zero\" (a device, not a file"), "{e}");
}

/// A study whose `scenario` names a study (itself, or another) says so, not only that
/// `scenario` is an unknown key of a scenario.
#[test]
fn a_study_as_the_scenario_of_a_study_is_named_a_study() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("self.toml"), "scenario = \"self.toml\"\n").unwrap();
    std::fs::write(dir.path().join("outer.toml"), "scenario = \"inner.toml\"\n").unwrap();
    std::fs::write(dir.path().join("inner.toml"), "[monte_carlo]\nruns = 2\n").unwrap();
    for (file, named, key) in [("self.toml", "self.toml", "scenario"), ("outer.toml", "inner.toml", "monte_carlo")] {
        let e = Study::from_path(&dir.path().join(file)).expect_err("refused");
        assert_eq!(e.key, "scenario");
        assert!(e.message.starts_with(&format!("{named}: {key}: unknown key")), "{e}");
        assert!(
            e.message.ends_with(&format!("; {named} is a study, not a scenario: set `scenario` to a scenario file (with [plant] and [design]) or a scenario table")),
            "{e}"
        );
    }
}

/// `relative_uniform = r` keeps a delay within ±r of its nominal: 4,000 draws of τ_2 = 3 s at
/// r = 0.1 all lie in [2.7, 3.3], with the moments of 3·(1 + U(−0.1, 0.1)) (mean 3, variance
/// 0.3²/3) within 5 standard errors (as in `draws_follow_their_laws`).
#[test]
fn a_relative_uniform_draw_stays_within_its_fraction() {
    let n = 4000;
    let s =
        study(&format!("[monte_carlo]\nruns = {n}\nseed = 11\n\"truth.delays[1]\" = {{ relative_uniform = 0.1 }}\n"))
            .unwrap();
    assert!(s.truth_differs());
    let xs: Vec<f64> =
        (0..n).map(|i| s.spec_with_nominal(i).unwrap().scenario["truth"]["delays"][1].as_float().unwrap()).collect();
    assert!(xs.iter().all(|x| (2.7..=3.3).contains(x)), "{:?}", xs.iter().cloned().fold(f64::NAN, f64::max));
    let nf = n as f64;
    let mean = xs.iter().sum::<f64>() / nf;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (nf - 1.0);
    let v: f64 = 0.09 / 3.0;
    assert!((mean - 3.0).abs() < 5.0 * v.sqrt() / nf.sqrt(), "mean {mean}");
    assert!((var - v).abs() < 5.0 * v * (0.8 / nf).sqrt(), "variance {var}");
    // The delay of channel 1 is not drawn.
    assert!((0..10).all(|i| s.spec_with_nominal(i).unwrap().scenario["truth"]["delays"][0].as_float() == Some(1.0)));
}

/// A study whose scenario is a table is the study of that scenario's file, and its document reads
/// back to the same study (same fingerprint, same specifications).
#[test]
fn a_study_document_is_self_contained() {
    let text = "[simulation]\nt_end = 5.0\n[grid]\n\"design.beta\" = [1.0, 2.0]\n[monte_carlo]\nruns = 2\nseed = 4\n\"truth.A\" = { relative = 0.01 }\n";
    let from_file = study(text).unwrap();
    let mut doc: toml::Table = text.parse().unwrap();
    doc.insert("scenario".into(), toml::Value::Table(PAPER_EXAMPLE.parse().unwrap()));
    let from_table = Study::from_table(&doc, None).unwrap();
    let back = Study::from_table(from_file.to_table(), None).unwrap();
    for s in [&from_table, &back] {
        assert_eq!(s.fingerprint(), from_file.fingerprint());
        assert_eq!(s.to_table(), from_file.to_table());
        assert_eq!(s.spec_with_nominal(3).unwrap().scenario, from_file.spec_with_nominal(3).unwrap().scenario);
    }
    assert_eq!(from_file.to_table()["scenario"]["simulation"]["t_end"].as_float(), Some(5.0));
    assert!(!from_file.to_table().contains_key("simulation"));
    let e = error("[scenario]\nname = \"x\"");
    assert!(e.starts_with("scenario: the study's scenario: plant: missing"), "{e}");
}

#[test]
fn study_runs_wait_for_the_memory_that_other_runs_hold() {
    // This test holds all of the study runs' budget but 1 MiB; a run of the paper's example needs
    // ~95 MB (its delay history's budget, Run::memory_bound): it must wait, and run once the
    // memory is given back.
    use std::sync::atomic::{AtomicUsize, Ordering};
    let s = study("[grid]\n\"simulation.t_end\" = [5.0]\n").unwrap();
    let gate = &crate::sim::memory::RUNS;
    let held = gate.hold(crate::sim::runs_memory_bytes() - (1 << 20), &|| false).expect("no stop");
    let rows = AtomicUsize::new(0);
    let on_row = |_: &Row| {
        rows.fetch_add(1, Ordering::SeqCst);
    };
    std::thread::scope(|scope| {
        let worker = scope.spawn(|| sweep(&s, &SweepOptions { on_row: Some(&on_row), ..Default::default() }));
        std::thread::sleep(std::time::Duration::from_millis(300));
        assert_eq!(rows.load(Ordering::SeqCst), 0, "a run started without its memory");
        drop(held);
        let done = worker.join().expect("the sweep");
        assert_eq!(done.rows.len(), 1);
        assert_eq!(done.rows[0].outcome, Outcome::Completed, "{:?}", done.rows[0]);
        // Its wall_ms is the run's own time, not the 300 ms it waited (a 5 s run: ~1 ms).
        assert!(done.rows[0].wall_ms < 250.0, "wall_ms {}", done.rows[0].wall_ms);
    });
}

#[test]
fn a_stop_ends_a_nominal_run_under_way() {
    // Draws need their point's nominal run first; at t_end = 1e5 s it takes ~10 s. Ctrl-C 0.1 s in
    // waited for it to finish (11.8 s measured): it now ends within the run's next progress check,
    // the sweep is partial, and nothing of the nominal run is kept.
    use std::sync::atomic::{AtomicBool, Ordering};
    let s = study("[grid]\n\"simulation.t_end\" = [1e5]\n\"simulation.output_step\" = [10.0]\n[monte_carlo]\nruns = 2\n\"plant.x0\" = { normal = 0.1 }\n").unwrap();
    let stop = AtomicBool::new(false);
    let started = std::time::Instant::now();
    let done = std::thread::scope(|scope| {
        let worker = scope.spawn(|| sweep(&s, &SweepOptions { stop: Some(&stop), ..Default::default() }));
        std::thread::sleep(std::time::Duration::from_millis(100));
        stop.store(true, Ordering::Relaxed);
        worker.join().expect("the sweep")
    });
    let took = started.elapsed().as_secs_f64();
    assert!(done.partial && done.rows.is_empty(), "{done:?}");
    assert!(took < 3.0, "the sweep took {took:.1} s after its stop");
    assert!(s.nominal.as_ref().is_some_and(|kept| kept.lock().is_empty()), "an interrupted nominal run was kept");
}

/// `u_max`: the scenario's true actuator limits u_f where some truth.u_max is finite.
#[test]
fn a_scenario_with_finite_actuator_limits_clips() {
    let clips = |s: &Study| (0..2).any(|i| s.u_max(i).is_finite());
    assert!(!clips(&study("").unwrap()));
    let with = |u_max: &str| {
        let text = format!("{}\n[truth]\nu_max = {u_max}\n", crate::scenario::PAPER_EXAMPLE);
        let mut doc = toml::Table::new();
        doc.insert("scenario".into(), toml::Value::Table(text.parse().unwrap()));
        clips(&Study::from_table(&doc, None).unwrap())
    };
    assert!(with("[30.0, inf]") && with("[30, inf]"));
    assert!(!with("[inf, inf]"));
}

#[test]
fn a_run_check_the_scenario_fails_is_refused_before_any_run_and_named_as_its_own() {
    // T_s = 0.7 ms does not divide the paper's delays (1 s, 2 s): without a grid the study had run
    // every draw to a failed row and exited 0; with a grid over μ the error named μ's value.
    let bad = "[simulation]\nt_end = 10.0\nsample_time = 0.0007\n";
    for text in [
        bad.to_string(),
        format!("{bad}[grid]\n\"design.mu[0]\" = [10.0, 20.0]\n"),
        format!("{bad}[monte_carlo]\nruns = 2\n\"truth.A\" = {{ relative = 0.01 }}\n"),
    ] {
        let e = study(&text).expect_err("refused");
        assert_eq!(e.key, "simulation.sample_time", "{e}");
        assert!(e.message.contains("nearest valid sample time"), "{e}");
    }
    // A scenario of its own whose sample time the grid replaces by valid ones is a valid study.
    let s = study(
        "[simulation]\nt_end = 10.0\nsample_time = 0.0007\n[grid]\n\"simulation.sample_time\" = [0.001, 0.002]\n",
    );
    assert_eq!(s.map(|s| s.points()), Ok(2));
    // A grid value that fails on its own still names itself.
    let e = error(
        "[simulation]\nt_end = 10.0\nsample_time = 0.001\n[grid]\n\"simulation.sample_time\" = [0.001, 0.0007]\n",
    );
    assert!(e.starts_with("grid.\"simulation.sample_time\"[1]: with simulation.sample_time = 0.0007"), "{e}");
}

/// runs.csv writes grid values in their shortest round-trip form (studies.md), as its figures: 1e300
/// had been written as 301 digits, 10.0 keeps its `.0` (a float, as pandas reads it), and lists keep
/// their brackets.
#[test]
fn grid_values_are_written_in_their_shortest_form() {
    let text = |toml: &str| super::sweep::grid_text(&toml.parse::<toml::Table>().unwrap()["v"]);
    assert_eq!(text("v = 1e300"), "1e300");
    assert_eq!(text("v = 10.0"), "10.0");
    assert_eq!(text("v = 0.00001"), "1e-5");
    assert_eq!(text("v = [1.5, 3.0]"), "[1.5, 3.0]");
    assert_eq!(text("v = -inf"), "-inf");
    assert_eq!(text("v = 7"), "7");
    assert_eq!(text("v = 1e300").parse::<f64>(), Ok(1e300));
    // summary.json's grid names each value as runs.csv does (it wrote 1e-7 as "0.0000001").
    let study = study("[grid]\n\"design.beta\" = [1e-7, 0.01]\n").unwrap();
    let meta = super::StudyMeta::new(&study, super::Shard::ALL);
    assert_eq!(meta.grid[0].values, ["1e-7", "0.01"]);
}

/// A sampled-data study that draws a delay of the model is refused before any run, naming the
/// draw: every draw had failed its run's check (not whole samples) and the sweep exited 0. The same
/// draw in the continuous loop is a study, and so are the true plant's delays in the sampled loop,
/// which takes them in fractions of a sample: three draws of truth.delays run, each with delays
/// off the sample grid, each to its end, and no two alike.
#[test]
fn a_sampled_study_draws_no_delay_of_the_model() {
    for key in ["plant.delays", "plant.delays[1]"] {
        let text = format!(
            "[simulation]\nt_end = 5.0\nsample_time = 0.01\n[monte_carlo]\nruns = 3\n\"{key}\" = {{ uniform = 0.2 }}\n"
        );
        let e = error(&text);
        assert!(e.starts_with(&format!("monte_carlo.\"{key}\": a model delay drawn from a continuous law")), "{e}");
        assert!(e.contains("simulation.sample_time = 0.01 s"), "{e}");
        assert!(e.contains("draw the true plant's delay instead (truth.delays"), "{e}");
        assert!(e.contains("(leave simulation.sample_time out of the study)"), "{e}");
    }
    // A sample time from the scenario is not the study's to leave out (a study had been told to).
    let file = format!("{}/../../examples/paper-sampled.toml", env!("CARGO_MANIFEST_DIR"));
    let e = error(&format!("scenario = \"{file}\"\n[monte_carlo]\nruns = 3\n\"plant.delays\" = {{ uniform = 0.2 }}\n"));
    assert!(e.contains("(a study of a copy of the scenario without its simulation.sample_time, which a study's [simulation] cannot remove)"), "{e}");
    let continuous = "[simulation]\nt_end = 5.0\n[monte_carlo]\nruns = 3\n\"plant.delays\" = { uniform = 0.2 }\n";
    assert!(Study::from_toml(continuous, None).is_ok());
    // The true plant's delays may be drawn: a sampled run takes fractions of a sample there.
    for key in ["truth.delays", "truth.delays[1]", "truth.actuator_delays[0]"] {
        let text = format!(
            "[simulation]\nt_end = 5.0\nsample_time = 0.01\n[monte_carlo]\nruns = 3\n\"{key}\" = {{ uniform = 0.2 }}\n"
        );
        assert!(Study::from_toml(&text, None).is_ok(), "{key}");
    }
    let s = study("[simulation]\nt_end = 5.0\nsample_time = 0.01\n[monte_carlo]\nruns = 3\n\"truth.delays\" = { uniform = 0.2 }\n").unwrap();
    let mut tails = Vec::new();
    for i in 0..3 {
        let spec = s.spec_with_nominal(i).unwrap();
        let delays = spec.scenario["truth"]["delays"].as_array().unwrap().iter().map(|v| v.as_float().unwrap());
        assert!(delays.into_iter().all(|tau| ((tau / 0.01) - (tau / 0.01).round()).abs() > 1e-6), "{spec:?}");
        let row = crate::study::sweep::run_one(&spec);
        assert_eq!((row.outcome, row.steps), (crate::study::sweep::Outcome::Completed, 501u64), "{}", row.reason);
        tails.push(row.channels[0].tail_max_e);
    }
    assert!(tails[0] != tails[1] && tails[1] != tails[2] && tails[0] != tails[2], "{tails:?}");
}

/// A study's t_end that its scenario's own output_step does not fit is named as the study's
/// combination, with the remedy in the study (it had read as the scenario file's mistake); a
/// scenario value wrong on its own stays the scenario's.
#[test]
fn a_study_key_against_a_scenario_key_names_the_study() {
    let e = error("[simulation]\nt_end = 0.05\n[grid]\n\"design.beta\" = [1.0]\n");
    assert_eq!(
        e,
        "simulation.output_step: expected an output step ≤ t_end = 0.05, found 0.1 (output_step from the paper's example, with the study's simulation.t_end); set simulation.output_step in the study's [simulation] too"
    );
    assert!(study("[simulation]\nt_end = 0.05\noutput_step = 0.01\n[grid]\n\"design.beta\" = [1.0]\n").is_ok());
    // Only the key the bound is against is named, not every key the study sets.
    let e = error("[simulation]\nt_end = 0.05\nrtol = 1e-7\nmethod = \"imex\"\n[grid]\n\"design.beta\" = [1.0]\n");
    assert!(e.ends_with("(output_step from the paper's example, with the study's simulation.t_end); set simulation.output_step in the study's [simulation] too"), "{e}");
    let mut bad: toml::Table = PAPER_EXAMPLE.parse().unwrap();
    bad["simulation"].as_table_mut().unwrap().insert("output_step".into(), toml::Value::Float(-1.0));
    let mut doc: toml::Table = "[simulation]\nrtol = 1e-7\n[grid]\n\"design.beta\" = [1.0]\n".parse().unwrap();
    doc.insert("scenario".into(), toml::Value::Table(bad));
    let e = Study::from_table(&doc, None).unwrap_err().to_string();
    assert!(
        e.starts_with("scenario: the study's scenario: simulation.output_step: expected an output step > 0"),
        "{e}"
    );
}

/// The true actuator's keys are grid and Monte Carlo keys without a `[truth]` in the scenario, at
/// their defaults (no delay, no limit) elsewhere: a grid over a drive's limit had needed the
/// scenario to give one first (helper tryout, 2026-12-06). Within the limits the paper's u_f,2
/// reaches (21.7), a limit of 15 changes the run and one of ∞ is no limit.
#[test]
fn the_true_actuators_keys_vary_without_a_truth_table() {
    let s = study("[simulation]\nt_end = 20.0\n[grid]\n\"truth.u_max[1]\" = [15.0, inf]\n\"truth.actuator_delays[0]\" = [0.0, 0.1]\n").unwrap();
    let truth = |i: usize| s.spec_with_nominal(i).unwrap().scenario["truth"].clone();
    assert_eq!(
        truth(0)["u_max"].as_array().unwrap().iter().map(|v| v.as_float().unwrap()).collect::<Vec<_>>(),
        [f64::INFINITY, 15.0]
    );
    assert_eq!(
        truth(1)["actuator_delays"].as_array().unwrap().iter().map(|v| v.as_float().unwrap()).collect::<Vec<_>>(),
        [0.1, 0.0]
    );
    let rows: Vec<f64> =
        (0..4).map(|i| s.spec_with_nominal(i).unwrap().simulate().unwrap().summary()[1].figures.tail_max_e).collect();
    assert!(rows[0] != rows[2] && rows[1] != rows[3], "{rows:?}");
}

/// A grid over one entry of `truth.u_min` where the scenario leaves it to its default (−u_max)
/// leaves the other entries at −u_max of each run, integers in u_max included: they had been
/// frozen at the nominal −u_max beside an axis over u_max, and at −∞ where u_max was written as
/// integers; the axis's own entry is kept however its index is written (`[01]` had been undone;
/// review, 2026-12-08).
#[test]
fn the_lower_limits_no_axis_sets_follow_each_runs_upper_ones() {
    let text = format!("{}\n[truth]\nu_max = [20, 30]\n", crate::scenario::PAPER_EXAMPLE);
    let mut doc: toml::Table =
        "[grid]\n\"truth.u_min[01]\" = [-5.0]\n\"truth.u_max[0]\" = [2.0, 4.0]\n".parse().unwrap();
    doc.insert("scenario".into(), toml::Value::Table(text.parse().unwrap()));
    let s = Study::from_table(&doc, None).unwrap();
    let lower = |i: usize| -> Vec<f64> {
        let truth = &s.run_document(i).unwrap()["truth"];
        truth["u_min"].as_array().unwrap().iter().map(|v| v.as_float().unwrap()).collect()
    };
    assert_eq!((lower(0), lower(1)), (vec![-2.0, -5.0], vec![-4.0, -5.0]));
    // Without an axis over u_min, none is written: the scenario's default holds.
    let mut doc: toml::Table = "[grid]\n\"truth.u_max[0]\" = [2.0]\n".parse().unwrap();
    doc.insert("scenario".into(), toml::Value::Table(text.parse().unwrap()));
    let s = Study::from_table(&doc, None).unwrap();
    assert!(s.run_document(0).unwrap()["truth"].get("u_min").is_none());
}

/// runs.csv's last columns are the values each draw gave (a CLI sweep had only its seed, so which
/// plants diverged could be learnt only from Python): named by key and index, `… (drawn)` where
/// the grid sets the key too, each the number the run's own scenario holds and within its law
/// (τ₂ = 3 ± 10 % uniform, A[0][1] = −1.7 ± 0.01), and read back as written.
#[test]
fn runs_csv_holds_each_draws_values() {
    let s = study("[simulation]\nt_end = 1.0\n[grid]\n\"truth.delays[1]\" = [3.0, 3.3]\n[monte_carlo]\nruns = 2\nseed = 4\n\"truth.delays\" = { relative_uniform = 0.1 }\n\"truth.A[0][1]\" = { uniform = 0.01 }\n").unwrap();
    let meta = StudyMeta::new(&s, Shard::ALL);
    let drawn = ["truth.delays[0] (drawn)", "truth.delays[1] (drawn)", "truth.A[0][1]"];
    assert_eq!(meta.drawn, drawn);
    assert_eq!(header(&meta)[header(&meta).len() - 3..], drawn);
    let swept = sweep(&s, &SweepOptions::default());
    assert_eq!(swept.rows.len(), 4);
    for row in &swept.rows {
        let spec = s.spec_with_nominal(row.run).unwrap();
        let truth = &spec.scenario["truth"];
        let tau = truth["delays"].as_array().unwrap().iter().map(|v| v.as_float().unwrap()).collect::<Vec<_>>();
        let a01 = truth["A"][0][1].as_float().unwrap();
        assert_eq!(row.drawn, [Some(tau[0]), Some(tau[1]), Some(a01)]);
        let grid_tau = [3.0, 3.3][row.point];
        assert!((tau[1] / grid_tau - 1.0).abs() <= 0.1 && tau[1] != grid_tau, "{tau:?}");
        assert!((a01 + 1.7).abs() <= 0.01 && a01 != -1.7, "{a01}");
    }
    let mut text = Vec::new();
    write_runs_csv(&mut text, &meta, &swept.rows, false).unwrap();
    let text = String::from_utf8(text).unwrap();
    assert_eq!(
        read_runs_csv(&text, &meta).unwrap().rows,
        swept.rows.iter().map(|r| Row { explicit_stiff: false, ..r.clone() }).collect::<Vec<_>>()
    );
    // A file without them (edited, or another study's) is refused by its header's length.
    let cut: String = text.lines().map(|l| format!("{}\n", l.rsplitn(4, ',').last().unwrap())).collect();
    let e = read_runs_csv(&cut, &meta).unwrap_err();
    assert!(e.contains("and 3 drawn values"), "{e}");
}

/// A number drawn by two Monte Carlo keys is refused: perturbed twice and named twice in runs.csv
/// (diff review, 2026-12-07); distinct entries of one key are fine.
#[test]
fn overlapping_draw_keys_are_refused() {
    let e = error(
        "[monte_carlo]\nruns = 2\n\"truth.delays\" = { uniform = 0.1 }\n\"truth.delays[1]\" = { uniform = 0.1 }\n",
    );
    assert!(e.contains("overlaps monte_carlo.\"truth.delays\", which draws some of the same numbers"), "{e}");
    assert!(study(
        "[monte_carlo]\nruns = 2\n\"truth.delays[0]\" = { uniform = 0.1 }\n\"truth.delays[1]\" = { uniform = 0.1 }\n"
    )
    .is_ok());
}
