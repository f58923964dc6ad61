"""Studies from Python: quell.sweep as a DataFrame, and quell.sweep_runs/run_one mapped over a
dask LocalCluster of two worker processes, both compared with the rows of `quell sweep`."""

import concurrent.futures
import pickle
import subprocess

import numpy as np
import pandas as pd
import pytest

import quell

from conftest import EXAMPLES

STUDY = """
scenario = "{scenario}"
[simulation]
t_end = 20.0
rtol = 1e-6
atol = 1e-6
[grid]
"design.mu[0]" = [10.0, 40.0]
[monte_carlo]
runs = 2
seed = 7
"truth.A" = {{ relative = 0.02 }}
"""


@pytest.fixture(scope="module")
def study_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("study") / "study.toml"
    path.write_text(STUDY.format(scenario=(EXAMPLES / "paper.toml").as_posix()))
    return path


@pytest.fixture(scope="module")
def cli_rows(study_file, quell_bin, tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep")
    subprocess.run([quell_bin, "sweep", study_file, "--out", out, "--no-plots"], check=True, capture_output=True)
    return pd.read_csv(out / "runs.csv", comment="#")


def same_rows(a, b):
    """Equal in every column but the wall time, which is a measurement (missing values as None)."""
    a, b = (f.drop(columns="wall_ms").reset_index(drop=True) for f in (a, b))
    a, b = (f.astype(object).where(f.notna(), None) for f in (a, b))
    assert list(a.columns) == list(b.columns)
    pd.testing.assert_frame_equal(a, b, check_dtype=False)


def test_sweep_is_the_cli_rows(study_file, cli_rows):
    study = quell.Study.load(study_file)
    assert len(study) == 4 and study.columns == list(cli_rows.columns)
    frame = quell.sweep(study, jobs=2)
    # runs.csv's columns, the last the drawn values (one column per entry of truth.A).
    drawn = [f"truth.A[{i}][{j}]" for i in range(3) for j in range(3)]
    assert list(frame.columns) == study.columns and study.columns[-9:] == drawn
    same_rows(frame[study.columns], cli_rows)
    assert (frame["outcome"] == "completed").all()
    # A path works as well as a Study.
    same_rows(quell.sweep(study_file, jobs=1)[study.columns], cli_rows)


def test_run_specs_are_picklable(study_file):
    specs = list(quell.sweep_runs(quell.Study.load(study_file)))
    assert [s.run for s in specs] == [0, 1, 2, 3]
    assert specs[2].grid == {"design.mu[0]": 40.0} and specs[2].draw == 0
    back = pickle.loads(pickle.dumps(specs[3]))
    assert back.to_json() == specs[3].to_json()
    # The run's scenario carries its grid value and its draw of the true plant.
    s = specs[3].scenario()
    assert s.design().mu == [40.0, 30.0]
    assert s.truth is not None and not np.array_equal(s.truth.A, s.plant.A)


def test_threads_share_one_run_spec_iterator(study_file):
    """Two threads drawing from one sweep_runs() iterator get every spec once between them (the
    second had raised "Already borrowed" while the first's nominal run had the GIL released)."""
    specs = quell.sweep_runs(study_file)
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        taken = list(pool.map(lambda _: [s.run for s in specs], range(2)))
    assert sorted(taken[0] + taken[1]) == [0, 1, 2, 3] and len(specs) == 0, taken


def test_a_missing_figure_of_run_one_is_nan_as_in_runs_csv():
    """A run too short to settle: its settle_t is NaN (runs.csv's empty cell read back), so a
    DataFrame of such rows has a float column; None made it object-typed."""
    spec = quell.Study(quell.paper_example(), simulation={"t_end": 2.0}).spec(0)
    row = quell.run_one(spec)
    assert isinstance(row["settle_t1"], float) and np.isnan(row["settle_t1"]), row
    assert pd.DataFrame([row, row])["settle_t1"].dtype == np.float64


def test_dask_local_cluster_of_two_processes(study_file, cli_rows):
    distributed = pytest.importorskip("distributed")
    specs = list(quell.sweep_runs(study_file))
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            assert len(client.scheduler_info()["workers"]) == 2
            rows = client.gather(client.map(quell.run_one, specs))
    frame = pd.DataFrame(rows)
    same_rows(frame[list(cli_rows.columns)], cli_rows)
    # Each row has its draw's values, as quell.sweep's DataFrame has.
    drawn = [c for c in frame.columns if c.startswith("truth.A")]
    assert len(drawn) == 9
    pd.testing.assert_frame_equal(frame[drawn], quell.sweep(study_file)[drawn])


def test_study_errors_name_the_key(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(STUDY.format(scenario=(EXAMPLES / "paper.toml").as_posix()).replace('"design.mu[0]"', '"design.nu[0]"'))
    with pytest.raises(quell.ScenarioError) as info:
        quell.Study.load(bad)
    assert "design.nu[0]" in str(info.value)
    with pytest.raises(quell.ScenarioError, match="cannot read the study file"):
        quell.sweep(bad.with_name("missing.toml"))
    # A scenario file where a study belongs is said to be one (the CLI alone said so).
    for call in (quell.Study.load, lambda p: list(quell.sweep_runs(p))):
        with pytest.raises(quell.ScenarioError, match=r"^name: unknown key.*; this is a scenario, not a study: a study names a scenario"):
            call(EXAMPLES / "paper.toml")


def test_jobs_must_be_positive(study_file):
    with pytest.raises(quell.ScenarioError, match="jobs"):
        quell.sweep(study_file, jobs=0)


@pytest.mark.parametrize("jobs", [-1, 2**70, 1025])
def test_jobs_out_of_range_name_the_argument(study_file, jobs):
    # jobs=-1 raised a bare OverflowError.
    with pytest.raises(quell.ScenarioError, match=r"jobs: expected a number of threads from 1 to 1024"):
        quell.sweep(study_file, jobs=jobs)


@pytest.mark.parametrize("jobs", [True, 1.5, "2"])
def test_jobs_of_another_type_is_a_type_error(study_file, jobs):
    with pytest.raises(TypeError, match=r"jobs: expected an int \(a number of threads\) or None, found a (bool|float|str)"):
        quell.sweep(study_file, jobs=jobs)


def test_huge_studies_are_refused_not_allocated(tmp_path):
    # runs near 2**63 aborted the interpreter in quell.sweep, and len(Study) raised OverflowError.
    text = STUDY.format(scenario=(EXAMPLES / "paper.toml").as_posix())
    huge = tmp_path / "huge.toml"
    huge.write_text(text.replace("runs = 2", "runs = 9223372036854775807"))
    with pytest.raises(quell.ScenarioError, match=r"monte_carlo.runs: expected at most 1e9 draws"):
        quell.sweep(huge)
    big = tmp_path / "big.toml"
    big.write_text(text.replace("runs = 2", "runs = 6000000"))
    study = quell.Study.load(big)
    assert len(study) == 12_000_000
    with pytest.raises(quell.ScenarioError, match=r"the study has 12000000 runs .*pass yes=True"):
        quell.sweep(study)


def test_a_seed_beyond_64_bits_is_named_as_a_seed():
    # 2**70 was rounded to a float and refused as "a floating-point number".
    from test_api import paper_from_values

    with pytest.raises(quell.ScenarioError, match=r"noise\[\"seed\"\]: expected a seed, an integer from 0 to 2\*\*63 - 1, found 1180591620717411303424") as e:
        paper_from_values(sample_time=1e-3, noise={"std": [0.01, 0.01], "seed": 2**70})
    assert e.value.key == "noise.seed"


def test_a_count_beyond_64_bits_is_named_with_its_digits():
    """runs= and points= of 2**70 were rounded to a float: "found a floating-point number" and
    "found 1180591620717411300000.0"."""
    with pytest.raises(quell.ScenarioError, match=r'^monte_carlo\["runs"\]: expected an integer within 2\*\*63 - 1, found 1180591620717411303424$') as e:
        quell.Study(quell.paper_example(), monte_carlo={"runs": 2**70, "seed": 1, "truth.A": {"relative": 0.1}})
    assert e.value.key == "monte_carlo.runs"
    with pytest.raises(quell.ScenarioError, match=r"^points: expected an integer within 2\*\*63 - 1, found 1180591620717411303424$"):
        quell.tune(quell.paper_example(), mu=[1.0, 10.0], points=2**70)


def test_method_and_max_steps_refusals_carry_their_key():
    """docs/python.md: `.key` keeps the file's key, for simulate's own keywords too."""
    s = quell.paper_example()
    with pytest.raises(quell.ScenarioError, match=r"^method: the integrator applies to the continuous loop only") as e:
        quell.simulate(s, sample_time=0.01, method="imex")
    assert e.value.key == "simulation.method"
    with pytest.raises(quell.ScenarioError, match=r"^max_steps: a step budget applies to the continuous loop") as e:
        quell.simulate(s, sample_time=0.01, max_steps=100)
    assert e.value.key == "max_steps"
    with pytest.raises(quell.ScenarioError, match=r"^max_steps: expected a step budget") as e:
        quell.simulate(s, max_steps=0)
    assert e.value.key == "max_steps"


def test_a_study_with_tune_is_not_swept(tmp_path):
    """A sweep would ignore [tune]: it is refused, naming the key, as `quell sweep` refuses it."""
    study = tmp_path / "t.toml"
    (tmp_path / "paper.toml").write_text(quell.paper_example().to_toml())
    study.write_text('scenario = "paper.toml"\n[tune]\nobjective = "settle_t"\nmu = [1.0, 100.0]\n')
    with pytest.raises(quell.ScenarioError, match=r"^tune: read by tuning only") as e:
        quell.sweep(study)
    assert e.value.key == "tune"
    with pytest.raises(quell.ScenarioError, match=r"^tune: read by tuning only"):
        quell.sweep_runs(study)


@pytest.mark.parametrize("arguments, message, key", [
    ({"grid": {"design.beta": 1.0}}, r'^grid\["design.beta"\]: expected a list of values \(e.g. \[5.0, 10.0\]\), found a float$', 'grid."design.beta"'),
    ({"grid": {"design.beta": ["a"]}}, r'^grid\["design.beta"\]\[0\]: expected a number \(the shape of design.beta\), found a str$', 'grid."design.beta"[0]'),
    ({"monte_carlo": {"runs": "3"}}, r'^monte_carlo\["runs"\]: expected the number of draws per grid point \(an integer ≥ 1\), found a str$', "monte_carlo.runs"),
    ({"monte_carlo": {"runs": 3, "truth.A": 0.01}}, r'^monte_carlo\["truth.A"\]: expected a distribution, one of .*; found a float$', 'monte_carlo."truth.A"'),
    ({"settle": {"relative": "a"}}, r'^settle\["relative"\]: expected a band ≥ 0, found a str$', "settle.relative"),
])
def test_a_value_of_the_wrong_type_in_a_study_dict_is_a_type_error(arguments, message, key):
    """README: a wrong type is a TypeError. Inside Study's dicts it had been a ScenarioError,
    worded in TOML's terms ("found a floating-point number")."""
    with pytest.raises(TypeError, match=message) as e:
        quell.Study(quell.paper_example(), **arguments)
    assert e.value.key == key


def test_a_wrong_value_in_a_study_dict_is_still_a_scenario_error():
    with pytest.raises(quell.ScenarioError, match=r'^monte_carlo\["runs"\]: expected the number of draws per grid point \(an integer ≥ 1\), found 0$'):
        quell.Study(quell.paper_example(), monte_carlo={"runs": 0, "truth.A": {"relative": 0.1}})
    with pytest.raises(TypeError, match=r"^mu\[0\]: expected \[μ_min, μ_max\], found a str$"):
        quell.tune(quell.paper_example(), mu=["a", [1.0, 2.0]])
