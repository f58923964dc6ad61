"""Every run is bounded: a diverging continuous run started from Python (the paper's plant with
A x 1.3 and tau_2 = 2.6 s as the true plant; without a budget it held 15 GB by t = 35 s) ends by the
default budgets, derived from the problem, in seconds and bounded memory, its samples kept."""

import json
import subprocess
import sys
import time

import pytest

import quell

TRUTH = """
[truth]
A = [[-4.16, -2.21, -3.9], [3.64, 1.69, 5.2], [0.39, 0.39, -0.65]]
delays = [1.0, 2.6]
"""

# The child's own peak resident set (ru_maxrss, KiB on Linux) before and after the run.
RUN = """
import json, resource, sys, quell
s = quell.Scenario.from_toml(quell.paper_example().to_toml() + sys.argv[1])
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
r = quell.simulate(s, check=False)
grown = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) * 1024
print(json.dumps({"outcome": r.outcome, "steps": r.stats["steps"], "last_t": float(r.t[-1]), "grown": grown}))
"""

def diverging():
    return quell.Scenario.from_toml(quell.paper_example().to_toml() + TRUTH)


def test_a_diverging_run_ends_within_its_default_budgets_in_a_subprocess():
    started = time.monotonic()
    done = subprocess.run([sys.executable, "-c", RUN, TRUTH], capture_output=True, text=True, timeout=120)
    elapsed = time.monotonic() - started
    assert done.returncode == 0, done.stderr
    r = json.loads(done.stdout)
    # Step budget N = 10,000 + 100 (rho t_end + t_end / tau_min) = 110,000 (rho = 9, the filter pole
    # -9; t_end = 100 s; tau_min = 1 s). The history may hold 8 N tau_max / t_end = 26,400 records
    # (tau_max = 3 s) of (8 * 27 + 9) * 8 = 1,800 bytes (27 delayed states), twice that for the
    # ring's doubling: 95,040,000 bytes. The runaway crowds its steps into its last seconds and
    # ends by that bound (docs/running.md, "Every run is bounded").
    max_bytes = 2 * 26_400 * 1_800
    assert r["outcome"]["status"] == "history_too_large" and r["outcome"]["max_bytes"] == max_bytes
    assert 10.0 < r["outcome"]["t"] < 100.0 and r["last_t"] <= r["outcome"]["t"]
    assert r["steps"] < 110_000
    # Measured 0.5 s and 79 MiB of growth (a completed run of the paper's example: 15 MiB). The
    # memory bound is the history's plus 16 MiB for the rest of a run; it fails under the 1 GiB cap
    # alone, which let this run reach 110,000 steps with 74,234 records (127 MiB). The time leaves a
    # factor ~40 for a loaded machine and still fails if the budgets are lost.
    assert elapsed < 20.0, f"{elapsed:.1f} s"
    assert r["grown"] <= max_bytes + (16 << 20), f"peak resident set grew {r['grown'] >> 20} MiB"


def test_max_steps_changes_the_budget_and_check_raises_with_the_samples():
    with pytest.raises(quell.SimulationError, match="more than 2000 steps") as e:
        quell.simulate(diverging(), max_steps=2000)
    assert e.value.result.outcome["max_steps"] == 2000 and len(e.value.result) > 0
    for bad in (0, -3):
        with pytest.raises(quell.ScenarioError, match="max_steps: expected a step budget"):
            quell.simulate(diverging(), max_steps=bad)
    for bad in (1.5, "many", True):
        with pytest.raises(TypeError, match=r"max_steps: expected an int \(a step budget\) or None, found a (float|str|bool)"):
            quell.simulate(diverging(), max_steps=bad)
    with pytest.raises(quell.ScenarioError, match="max_steps: a step budget applies to the continuous loop"):
        quell.simulate(diverging(), sample_time=0.01, max_steps=10)


def test_a_result_holds_its_record_once():
    """A SimResult held the run's record twice, as the library's vectors and as numpy copies: a
    1.08 GB record grew Python to 2.09 GB where the CLI took 1.10 GB. The numpy arrays now own the
    vectors. 1e6 rows of the paper's example (27 numbers: 216 MB) grow the child by the record, the
    history (~7 MB) and the interpreter's imports, well under twice the record."""
    edit = "\n".join(["", "[simulation]", "t_end = 100.0", "output_step = 0.0001", "rtol = 1e-9", "atol = 1e-9", ""])
    text = quell.paper_example().to_toml().split("[simulation]")[0] + edit
    code = RUN.replace("quell.paper_example().to_toml() + sys.argv[1]", "sys.argv[1]")
    done = subprocess.run([sys.executable, "-c", code, text], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    r = json.loads(done.stdout)
    record = 1_000_001 * 27 * 8
    assert r["outcome"]["status"] == "completed"
    assert r["grown"] < 1.3 * record, f"grew {r['grown'] >> 20} MiB for a record of {record >> 20} MiB"


def test_a_run_ended_by_its_budget_names_a_rate_far_faster_than_the_loop():
    """As `quell run` and a study's row: observer poles at −1e4 … −1.5e4 on the paper's loop (1,700×
    the next rate) end a run on its step budget, and the error names the observer's rate."""
    import pathlib
    text = (pathlib.Path(__file__).resolve().parents[3] / "examples" / "paper.toml").read_text()
    gain = "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619], [2.7762, -1.1783]]"
    assert gain in text
    s = quell.Scenario.from_toml(text.replace(gain, "observer_poles = [-1e4, -1.2e4, -1.5e4]"))
    with pytest.raises(quell.SimulationError, match=r"the observer \(A − LC\) sets the loop's fastest rate, 1\.500e4/s, 1700× the next fastest"):
        quell.simulate(s, max_steps=2000)
