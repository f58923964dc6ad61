"""Studies from Python objects: quell.Study(scenario, grid=..., monte_carlo=...) is the study file
with the same tables (the CLI's rows are the independent side), the drawn values follow their laws
(SciPy's Kolmogorov–Smirnov test and the law's bounds), and a re-run is quell.simulate of the
scenario rebuilt by hand with the drawn values."""

import pickle
import subprocess

import numpy as np
import pandas as pd
import pytest

import quell

from conftest import EXAMPLES
from test_study import same_rows

GRID = {"design.mu[0]": [10.0, 40.0]}
DRAWS = {"runs": 3, "seed": 5, "truth.delays[1]": {"relative_uniform": 0.02}, "truth.A": {"relative": 0.01}}
FILE = """
scenario = "{scenario}"
[simulation]
t_end = 10.0
rtol = 1e-6
atol = 1e-6
[grid]
"design.mu[0]" = [10.0, 40.0]
[monte_carlo]
runs = 3
seed = 5
"truth.delays[1]" = {{ relative_uniform = 0.02 }}
"truth.A" = {{ relative = 0.01 }}
"""


def objects_study():
    return quell.Study(
        quell.paper_example(),
        grid=GRID,
        monte_carlo=DRAWS,
        simulation={"t_end": 10.0, "rtol": 1e-6, "atol": 1e-6},
    )


@pytest.fixture(scope="module")
def swept():
    return objects_study().sweep(jobs=2)


def test_a_study_from_objects_is_the_study_file(tmp_path, quell_bin, swept):
    path = tmp_path / "study.toml"
    path.write_text(FILE.format(scenario=(EXAMPLES / "paper.toml").as_posix()))
    from_file = quell.Study.load(path)
    study = objects_study()
    assert len(study) == 6 and (study.points, study.draws, study.m) == (2, 3, 2)
    # The same runs: each run's scenario (grid value and draws applied) is the file's.
    assert [s.scenario() for s in quell.sweep_runs(study)] == [s.scenario() for s in quell.sweep_runs(from_file)]
    out = tmp_path / "out"
    subprocess.run([quell_bin, "sweep", path, "--out", out, "--no-plots"], check=True, capture_output=True)
    cli = pd.read_csv(out / "runs.csv", comment="#")
    frame = swept.frame
    same_rows(frame[list(cli.columns)], cli)
    # The drawn values are runs.csv's last columns: one per drawn number.
    drawn = ["truth.delays[1]"] + [f"truth.A[{i}][{j}]" for i in range(3) for j in range(3)]
    assert list(frame.columns) == list(cli.columns) and list(cli.columns[-10:]) == drawn
    assert list(quell.sweep(study, jobs=1).columns) == list(frame.columns)


def test_a_draw_of_a_key_the_grid_sets_in_part_keeps_the_grid_column(tmp_path, quell_bin):
    """The grid sets truth.delays[1], the draws perturb the whole truth.delays around it: the grid's
    column keeps the grid's values (runs.csv's), and each drawn number is `… (drawn)` (the draw of
    delays[1] had overwritten the grid column, so the frame's rows differed from runs.csv's)."""
    grid = {"truth.delays[1]": [1.95, 2.05]}
    draws = {"runs": 2, "seed": 11, "truth.delays": {"relative_uniform": 0.02}}
    study = quell.Study(quell.paper_example(), grid=grid, monte_carlo=draws, simulation={"t_end": 2.0})
    frame = study.sweep(jobs=1).frame
    path = tmp_path / "study.toml"
    path.write_text(
        f'scenario = "{(EXAMPLES / "paper.toml").as_posix()}"\n[simulation]\nt_end = 2.0\n'
        '[grid]\n"truth.delays[1]" = [1.95, 2.05]\n'
        '[monte_carlo]\nruns = 2\nseed = 11\n"truth.delays" = { relative_uniform = 0.02 }\n'
    )
    out = tmp_path / "out"
    subprocess.run([quell_bin, "sweep", path, "--out", out, "--no-plots"], check=True, capture_output=True)
    cli = pd.read_csv(out / "runs.csv", comment="#")
    same_rows(frame[list(cli.columns)], cli)
    assert list(frame["truth.delays[1]"]) == [1.95, 1.95, 2.05, 2.05]
    drawn = ["truth.delays[0] (drawn)", "truth.delays[1] (drawn)"]
    assert list(frame.columns) == list(cli.columns) and list(cli.columns[-2:]) == drawn
    # The drawn delay is the grid's times 1 ± 2 %, and the run's own scenario holds it.
    ratio = frame["truth.delays[1] (drawn)"] / frame["truth.delays[1]"]
    assert ((ratio - 1).abs() <= 0.02).all() and (ratio != 1).all(), ratio
    spec = study.spec(3)
    assert spec.drawn == {k: frame.iloc[3][k] for k in drawn}
    assert spec.scenario().truth.delays[1] == frame.iloc[3]["truth.delays[1] (drawn)"]


def test_drawn_values_follow_their_laws():
    """2,000 draws (specifications only, nothing simulated): the relative-uniform delay lies in
    3·[0.9, 1.1] and passes SciPy's KS test against U(2.7, 3.3) at the 0.1 % level; the
    relative-normal entry of A passes it against N(a, (0.05·a)²)."""
    stats = pytest.importorskip("scipy.stats")
    study = quell.Study(
        quell.paper_example(),
        monte_carlo={"runs": 2000, "seed": 9, "truth.delays[1]": {"relative_uniform": 0.1},
                     "truth.A[1][2]": {"relative": 0.05}},
    )
    specs = list(quell.sweep_runs(study))
    tau = np.array([s.drawn["truth.delays[1]"] for s in specs])
    a = np.array([s.drawn["truth.A[1][2]"] for s in specs])
    assert tau.min() >= 2.7 and tau.max() <= 3.3
    assert tau.min() < 2.71 and tau.max() > 3.29  # the whole interval is reached
    assert stats.kstest(tau, stats.uniform(loc=2.7, scale=0.6).cdf).pvalue > 1e-3
    assert stats.kstest(a, stats.norm(loc=4.0, scale=0.2).cdf).pvalue > 1e-3
    # A drawn value is the value the run's scenario holds.
    s = specs[7].scenario()
    assert s.truth.delays[1] == tau[7] and s.truth.A[1, 2] == a[7]
    assert list(s.truth.delays)[0] == 1.0


def test_the_worst_row_rerun_is_simulate_with_the_drawn_values(swept):
    frame = swept.frame
    worst = swept.worst("tail_max_e")
    tail = frame[["tail_max_e1", "tail_max_e2"]].max(axis=1)
    assert worst["run"] == frame["run"][tail.idxmax()] and (frame["outcome"] == "completed").all()
    rerun = swept.rerun_worst("tail_max_e")
    # Independently: the paper's scenario with the worst row's grid value and drawn truth.
    p = quell.paper_example().plant
    A = np.array([[worst[f"truth.A[{i}][{j}]"] for j in range(3)] for i in range(3)])
    truth = quell.Plant(A, p.B, p.C, p.D, p.Q, delays=[1.0, worst["truth.delays[1]"]])
    d = quell.paper_example().design()
    scenario = quell.Scenario(
        p, quell.paper_example().reference, quell.paper_example().disturbance, truth=truth,
        t_end=10.0, rtol=1e-6, atol=1e-6, output_step=0.1, observer_gain=d.L,
        channel_poles=[[-6, -2], [-4]], reference_filter_poles=[[-1, -6], [-9]],
        disturbance_filter_poles=[[-1, -3], [-1, -2, -3]], mu=[worst["design.mu[0]"], 30.0], beta=1.0,
    )
    expected = quell.simulate(scenario)
    np.testing.assert_array_equal(rerun.y, expected.y)  # bit for bit: the same run
    np.testing.assert_array_equal(rerun.u_f, expected.u_f)
    assert [c["tail_max_e"] for c in rerun.summary()] == [worst["tail_max_e1"], worst["tail_max_e2"]]
    # One channel's column, and the run index of rerun.
    assert swept.worst("max_u2")["run"] == frame["run"][frame["max_u2"].idxmax()]
    np.testing.assert_array_equal(swept.rerun(-1).y, swept.rerun(5).y)


def test_worst_counts_a_run_without_figures_as_worst():
    study = quell.Study(quell.paper_example(), simulation={"t_end": 2.0}, grid={"design.beta": [1.0, 2.0]})
    result = study.sweep(jobs=1)
    frame = result.frame.copy()
    frame.loc[1, "tail_max_e1"] = np.nan  # as a diverged run's row
    doctored = quell.StudyResult(study, frame)
    assert result.worst("tail_max_e1")["run"] == frame["tail_max_e1"].idxmax() and doctored.worst("tail_max_e")["run"] == 1
    # A diverged row keeps the actuator peaks it reached, but ranks as the worst by them too (a
    # small peak of a run stopped early had ranked it below completed runs).
    # Every run completed: `reason` is still a text column (it had read as float, all NaN).
    assert result.frame["reason"].dtype == object and not result.frame["reason"].str.contains("runaway").any()
    frame = result.frame.copy()
    smaller = int(frame["max_uf1"].idxmin())
    frame.loc[smaller, "outcome"] = "diverged"
    assert quell.StudyResult(study, frame).worst("max_uf")["run"] == smaller
    with pytest.raises(quell.ScenarioError, match=r"metric: expected one of tail_max_e, .* found 'tail_max_err'"):
        result.worst("tail_max_err")
    with pytest.raises(TypeError, match="metric: expected a str"):
        result.worst(1)
    with pytest.raises(IndexError, match=r"run: expected a run index from 0 to 1 \(the study has 2 runs; from −2 to −1 counting from the end, as in a list\), found 2"):
        result.rerun(2)
    with pytest.raises(TypeError, match=r"run: expected an int \(a run index\), found a float"):
        result.rerun(1.0)


def test_study_arguments_are_named_as_python_spells_them():
    s = quell.paper_example()
    cases = [
        (dict(grid={"design.mu[0]": [5.0, -1.0]}), r'^grid\["design.mu\[0\]"\]\[1\]: with design.mu\[0\] = -1.0'),
        (dict(grid={"design.nu": [1.0]}), r'^grid\["design.nu"\]: design.nu is not a value of the scenario'),
        (dict(monte_carlo={"seed": 1}), r'^monte_carlo\["runs"\]: missing'),
        (dict(monte_carlo={"runs": 2, "truth.A": {"cauchy": 1.0}}), r'^monte_carlo\["truth.A"\]\["cauchy"\]: unknown distribution'),
        (dict(settle={"band": 0.1}), r'^settle\["band"\]: unknown key'),
        (dict(runaway={"peak": 0.5}), r'^runaway\["peak"\]: expected a factor ≥ 1'),
        (dict(simulation={"t_end": -1.0}), r'^simulation\["t_end"\]: expected a final time > 0'),
        (dict(max_steps=0), r"^max_steps: expected a step budget per run \(an integer ≥ 1\), found 0"),
    ]
    for kwargs, message in cases:
        with pytest.raises(quell.ScenarioError, match=message) as info:
            quell.Study(s, **kwargs)
        assert info.value.key is not None and "[" not in info.value.key.split(".")[0]
    for kwargs, message in [
        (dict(grid=[1.0]), r"^grid: expected a dict \(scenario key path: list of values\), found a list"),
        (dict(monte_carlo={1: 2}), r"^monte_carlo: expected str keys"),
        (dict(max_steps=1.5), r"^max_steps: expected an int \(a step budget per run\), found a float"),
    ]:
        with pytest.raises(TypeError, match=message):
            quell.Study(s, **kwargs)
    with pytest.raises(TypeError, match=r"^scenario: expected a quell.Scenario, found a str"):
        quell.Study("paper.toml")


def test_studies_and_results_pickle_and_compare(swept, tmp_path):
    study = objects_study()
    back = pickle.loads(pickle.dumps(study))
    assert back == study and back.to_toml() == study.to_toml() and len(back) == 6
    assert [s.to_json() for s in quell.sweep_runs(back)] == [s.to_json() for s in quell.sweep_runs(study)]
    assert study != quell.Study(quell.paper_example())
    result = pickle.loads(pickle.dumps(swept))
    assert result == swept and result is not swept
    pd.testing.assert_frame_equal(result.frame, swept.frame)
    spec = study.spec(4)
    assert pickle.loads(pickle.dumps(spec)) == spec and pickle.loads(pickle.dumps(spec)).drawn == spec.drawn
    assert spec.drawn == dict(swept.frame.iloc[4][list(spec.drawn)])
