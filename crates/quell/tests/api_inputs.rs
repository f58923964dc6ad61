//! The public functions outside `controller/` return an error, never panic, on inputs of the wrong
//! shape or scale. Each case is one a library caller can reach: a panic, a hang or a wrong answer
//! there would be a defect.
#![allow(non_snake_case)]

use quell::design::{controllability, observability, place, PlaceError};
use quell::nalgebra::{Complex, DMatrix};
use quell::PlantError;

fn poles(p: &[f64]) -> Vec<Complex<f64>> {
    p.iter().map(|&x| Complex::new(x, 0.0)).collect()
}

/// A controllable and observable 3-state pair: a chain with B = e₃, C = e₁ᵀ.
fn chain() -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let A = DMatrix::from_row_slice(3, 3, &[0.0, 1.0, 0.0, 0.0, 0.0, 1.0, -1.0, -2.0, -3.0]);
    let B = DMatrix::from_row_slice(3, 1, &[0.0, 0.0, 1.0]);
    let C = DMatrix::from_row_slice(1, 3, &[1.0, 0.0, 0.0]);
    (A, B, C)
}

fn shape(name: &'static str, expected: (usize, usize), found: (usize, usize)) -> PlantError {
    PlantError::Shape { name, expected_rows: expected.0, expected_cols: expected.1, rows: found.0, cols: found.1 }
}

#[test]
fn place_refuses_wrong_shapes() {
    let (A, B, _) = chain();
    let p = poles(&[-1.0, -2.0, -3.0]);
    let A32 = A.rows(0, 2).into_owned().transpose(); // 3×2
    assert_eq!(place(&A32, &B, &p), Err(PlaceError::Matrix(shape("A", (3, 3), (3, 2)))));
    let B2 = B.rows(0, 2).into_owned();
    assert_eq!(place(&A, &B2, &p), Err(PlaceError::InputRows { n: 3, rows: 2, cols: 1 }));
    // The shapes are checked before the pole count, which depends on them.
    assert_eq!(place(&A32, &B, &p[..2]), Err(PlaceError::Matrix(shape("A", (3, 3), (3, 2)))));
    // Still placed with the right shapes.
    assert!(place(&A, &B, &p).is_ok());
}

#[test]
fn place_refuses_entries_that_overflow() {
    // Was "(A, B) is not controllable … rank 0": the staircase tolerance overflowed to inf.
    let (mut A, B, _) = chain();
    A[(2, 0)] = -1e300;
    let e = place(&A, &B, &poles(&[-1.0, -2.0, -3.0])).unwrap_err();
    assert_eq!(e, PlaceError::Matrix(PlantError::TooLarge { name: "A", row: 2, col: 0, value: -1e300 }));
    assert!(e.to_string().contains("rescale the plant's units"), "{e}");
}

#[test]
fn rank_tests_refuse_wrong_shapes() {
    let (A, B, C) = chain();
    let A23 = A.rows(0, 2).into_owned();
    assert_eq!(controllability(&A23, &B), Err(shape("A", (2, 2), (2, 3))));
    assert_eq!(controllability(&A, &B.rows(0, 2).into_owned()), Err(shape("B", (3, 1), (2, 1))));
    assert_eq!(observability(&A23, &C), Err(shape("A", (2, 2), (2, 3))));
    assert_eq!(observability(&A, &C.columns(0, 2).into_owned()), Err(shape("C", (1, 3), (1, 2))));
    // The right shapes still give the rank.
    assert!(controllability(&A, &B).unwrap().full() && observability(&A, &C).unwrap().full());
}

#[test]
fn rank_tests_refuse_non_finite_and_huge_entries() {
    // NaN gave rank 0 ("nothing can be certified"), 1e300 gave "rank 0, tolerance inf": both read
    // as an uncontrollable plant.
    let (mut A, B, mut C) = chain();
    A[(0, 1)] = f64::NAN;
    assert!(matches!(controllability(&A, &B), Err(PlantError::NonFinite { name: "A", row: 0, col: 1, .. })));
    let (A, mut B, _) = chain();
    B[(2, 0)] = 2e300;
    assert_eq!(controllability(&A, &B), Err(PlantError::TooLarge { name: "B", row: 2, col: 0, value: 2e300 }));
    C[(0, 0)] = -1e151;
    assert_eq!(observability(&A, &C), Err(PlantError::TooLarge { name: "C", row: 0, col: 0, value: -1e151 }));
    // At the bound the test still decides, with a finite tolerance.
    C[(0, 0)] = 1e150;
    let t = observability(&A, &C).unwrap();
    assert!(t.tol.is_finite() && t.tol > 0.0, "{t:?}");
}

#[test]
fn relative_degrees_and_the_decoupler_refuse_wrong_shapes() {
    use quell::design::{falb_wolovich, relative_degree_measures, relative_degrees};
    let s = quell::Scenario::from_toml(quell::scenario::PAPER_EXAMPLE).unwrap();
    let (A, B, C) = (&s.plant.A, &s.plant.B, &s.plant.C);
    // These panicked in a matrix product ("Gemv: dimensions mismatch").
    let C2 = C.columns(0, 2).into_owned();
    assert_eq!(relative_degrees(A, B, &C2), Err(shape("C", (2, 3), (2, 2))));
    let B2 = B.rows(0, 2).into_owned();
    assert_eq!(relative_degrees(A, &B2, C), Err(shape("B", (3, 2), (2, 2))));
    let A32 = A.columns(0, 2).into_owned();
    assert_eq!(relative_degree_measures(&A32, B, C).map(|_| ()), Err(shape("A", (3, 3), (3, 2))));
    assert_eq!(relative_degrees(A, B, C).unwrap(), vec![Some(2), Some(1)]);
    // One input for two outputs was "output 2 is reached by no input".
    let poles = &s.design.channel_poles;
    let B1 = B.columns(0, 1).into_owned();
    let e = falb_wolovich(A, &B1, C, poles).map(|_| ()).unwrap_err();
    assert_eq!(e, quell::DesignError::Plant(shape("C", (1, 3), (2, 3))));
}

#[test]
fn design_and_runs_refuse_inputs_built_in_rust_with_wrong_lengths() {
    // A probe over the public API with a DesignSpec, a true plant, signals and settings built
    // directly (not read from a file): each is an error naming its key, none panics.
    use quell::sim::{MeasurementNoise, Run, RunSettings, SimError};
    use quell::{Design, DesignError};
    use std::ops::ControlFlow;
    let s = quell::Scenario::from_toml(quell::scenario::PAPER_EXAMPLE).unwrap();
    let count = |f: &dyn Fn(&mut quell::DesignSpec)| {
        let mut spec = s.design.clone();
        f(&mut spec);
        match Design::new(&s.plant, &spec) {
            Err(DesignError::Count { key, expected, got, .. }) => (key, expected, got),
            other => panic!("{:?}", other.map(|_| ())),
        }
    };
    assert_eq!(count(&|d| d.mu = vec![1.0]), ("design.mu", 2, 1));
    assert_eq!(count(&|d| d.channel_poles.push(poles(&[-1.0]))), ("design.channel_poles", 2, 3));
    assert_eq!(count(&|d| drop(d.reference_filter_poles.pop())), ("design.reference_filter_poles", 2, 1));
    assert_eq!(count(&|d| d.disturbance_filter_poles.clear()), ("design.disturbance_filter_poles", 2, 0));
    assert_eq!(count(&|d| d.relative_degrees = Some(vec![1])), ("design.relative_degrees", 2, 1));

    let d = s.design().unwrap();
    let go = ControlFlow::Continue;
    let run = RunSettings::continuous(1.0, 0.1, 1e-9, 1e-9);
    let key = |r: Result<quell::sim::SimResult, SimError>| match r {
        Err(SimError::Input(e)) => e.key,
        other => panic!("{:?}", other.map(|r| r.outcome)),
    };
    let mut truth = s.plant.clone();
    truth.x0 = quell::nalgebra::DVector::zeros(2);
    assert_eq!(
        key(Run::new(&d, &s.reference, &s.disturbance, run.clone()).truth(&truth).simulate(|_| go(()))),
        "truth.x0"
    );
    let mut truth = s.plant.clone();
    truth.x0[0] = 1e200;
    assert_eq!(
        key(Run::new(&d, &s.reference, &s.disturbance, run.clone()).truth(&truth).simulate(|_| go(()))),
        "truth"
    );
    // A true delay that forces more than 1e10 integrator steps (steps are at most min τ long).
    let mut truth = s.plant.clone();
    truth.delays[0] = 1e-300;
    assert_eq!(
        key(Run::new(&d, &s.reference, &s.disturbance, run.clone()).truth(&truth).simulate(|_| go(()))),
        "truth.delays[0]"
    );
    let mut reference = s.reference.clone();
    reference.components.pop();
    assert_eq!(key(Run::new(&d, &reference, &s.disturbance, run.clone()).simulate(|_| go(()))), "reference.components");
    // A negative frequency (refused by the scenario reader) ran when the Signal was built in Rust.
    let mut reference = s.reference.clone();
    reference.components[0].harmonics[0].frequency = -2.0;
    assert_eq!(
        key(Run::new(&d, &reference, &s.disturbance, run).simulate(|_| go(()))),
        "reference.components[0].harmonics[0].frequency"
    );
    let mut sampled = RunSettings::sampled(1.0, 0.1, 0.001);
    sampled.noise = Some(MeasurementNoise::white(vec![0.1], 0));
    assert_eq!(key(Run::new(&d, &s.reference, &s.disturbance, sampled).simulate(|_| go(()))), "noise.std");
    let sampled = RunSettings::sampled(1.0, 0.15, 0.1);
    assert_eq!(key(Run::new(&d, &s.reference, &s.disturbance, sampled).simulate(|_| go(()))), "simulation.output_step");
}

#[test]
fn eigenvector_condition_refuses_wrong_shapes() {
    use quell::design::place::eigenvector_condition;
    let (A, B, _) = chain();
    let A32 = A.columns(0, 2).into_owned();
    let K = DMatrix::from_row_slice(1, 3, &[1.0, 2.0, 3.0]);
    assert_eq!(eigenvector_condition(&A32, &B, &K), Err(shape("A", (3, 3), (3, 2))));
    assert_eq!(eigenvector_condition(&A, &B.rows(0, 2).into_owned(), &K), Err(shape("B", (3, 1), (2, 1))));
    assert_eq!(eigenvector_condition(&A, &B, &K.columns(0, 2).into_owned()), Err(shape("K", (1, 3), (1, 2))));
    // A − BK is a companion matrix with distinct eigenvalues: a finite κ ≥ 1.
    let kappa = eigenvector_condition(&A, &B, &K).unwrap();
    assert!(kappa.is_finite() && kappa >= 1.0, "{kappa}");
}

#[test]
fn signals_refuse_wrong_lengths() {
    let s = quell::Scenario::from_toml(quell::scenario::PAPER_EXAMPLE).unwrap();
    // Signal::eval_into wrote min(len, out.len()) entries without a word.
    let mut short = [0.0; 1];
    let e = s.reference.eval_into(0.5, &mut short).unwrap_err();
    assert_eq!((e.key.as_str(), e.message.as_str()), ("out", "expected 2 entries (one per component), found 1"));
    assert!(s.reference.eval_into(0.5, &mut [0.0; 3]).is_err());
    let mut g = [0.0; 2];
    s.reference.eval_into(0.5, &mut g).unwrap();
    assert_eq!(g, [3.0 * 1f64.sin(), 2.0]);
}

#[test]
fn a_study_run_index_beyond_the_study_is_none() {
    // An error, not a panic.
    let study = quell::study::Study::from_toml("[grid]\n\"design.mu[0]\" = [10.0, 40.0]\n", None).unwrap();
    assert_eq!(study.len(), 2);
    assert_eq!(study.spec_with_nominal(1).map(|s| s.run), Some(1));
    assert!(study.spec_with_nominal(2).is_none() && study.spec_with_nominal(usize::MAX).is_none());
    assert_eq!(study.specs_with_nominal().count(), 2);
}

#[test]
fn falb_wolovich_without_channels_is_an_error() {
    // m = 0 (B n×0, C 0×n): the B* of no channel has no SVD (nalgebra panicked on the empty matrix).
    let (A, _, _) = chain();
    let e = quell::design::falb_wolovich(&A, &DMatrix::zeros(3, 0), &DMatrix::zeros(0, 3), &[]);
    assert!(
        matches!(e, Err(quell::DesignError::NotDecouplable { smallest, cond, .. }) if smallest == 0.0 && cond == f64::INFINITY),
        "{e:?}"
    );
}
