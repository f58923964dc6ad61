"""Every run is bounded: a diverging continuous run started from Python (the paper's plant with
A x 1.3 and tau_2 = 2.6 s as the true plant; without a budget it held 15 GB by t = 35 s) ends by the
default step budget, derived from the problem, in seconds and bounded memory, its samples kept."""

import json
import resource
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

RUN = """
import json, sys, quell
s = quell.Scenario.from_toml(quell.paper_example().to_toml() + sys.argv[1])
r = quell.simulate(s, check=False)
print(json.dumps({"outcome": r.outcome, "steps": r.stats["steps"], "last_t": float(r.t[-1])}))
"""


def diverging():
    return quell.Scenario.from_toml(quell.paper_example().to_toml() + TRUTH)


def test_a_diverging_run_ends_within_its_default_budget_in_a_subprocess():
    started = time.monotonic()
    done = subprocess.run([sys.executable, "-c", RUN, TRUTH], capture_output=True, text=True, timeout=120)
    elapsed = time.monotonic() - started
    # ru_maxrss of the largest waited-for child, in KiB on Linux.
    rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024
    assert done.returncode == 0, done.stderr
    r = json.loads(done.stdout)
    # 10,000 + 100 (rho t_end + t_end / tau_min), rho = 9 (the filter pole -9), t_end = 100 s,
    # tau_min = 1 s.
    assert r["outcome"]["status"] == "too_many_steps" and r["outcome"]["max_steps"] == 110_000
    assert 10.0 < r["outcome"]["t"] < 100.0 and r["last_t"] <= r["outcome"]["t"]
    assert r["steps"] == 110_001
    # 110,000 steps of at most ~30 us and a history of at most as many 1.8 kB records: a factor ~5
    # of margin for a loaded machine, and the bounds still fail if the budget is lost.
    assert elapsed < 20.0, f"{elapsed:.1f} s"
    assert rss < 1 << 30, f"peak resident set {rss >> 20} MB"


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
