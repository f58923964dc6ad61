"""quell's continuous loop against a second implementation written with SciPy (scripts/scipy_loop.py:
its own state layout, φ coordinates of the disturbance observer (20), SciPy's realization of G_ii(s),
full Ω_i, and the method of steps over `solve_ivp` with the earlier segments' dense output as the
delay history). It takes only the design's matrices from `quell design --json`.

Tolerance: both solvers run at rtol = atol = 1e-9, and each one's global error is then up to about
1.5e-7 of a signal's peak (measured against the SciPy loop at 1e-12: 1.3e-7 for quell, 1.5e-7 for
SciPy, on η̂ of the SISO case with μ = 1000; 2e-8 on the paper's example). The two are compared
over every sample of signals.csv to 1e-6 of each column's peak (or 1e-6 absolute below a peak of 1):
four times the largest difference seen (2.7e-7), far below any wiring error (a missing delay, a
wrong sign, a transposed gain moves a signal by a sizeable fraction of its peak)."""

import csv
import json
import os
import subprocess
import sys
import tomllib

import numpy as np
import pytest

from conftest import EXAMPLES, ROOT

sys.path.insert(0, str(ROOT / "scripts"))
import scipy_loop  # noqa: E402

AGREEMENT = 1e-6


def read_signals(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return {name: np.array([float(r[i]) for r in rows[1:]]) for i, name in enumerate(rows[0])}


def both(quell_bin, tmp_path, scenario_path, t_end, scipy_tol=1e-9):
    """quell's signals.csv and the SciPy loop's columns, over [0, t_end]; quell at 1e-9, SciPy at
    `scipy_tol`."""
    text = scenario_path.read_text()
    scenario = tomllib.loads(text)
    sim = dict(scenario.get("simulation", {}), t_end=t_end, rtol=1e-9, atol=1e-9)
    # The scenario with the shorter horizon and the tolerances: its [simulation] table rewritten.
    head = text.split("[simulation]")[0]
    lines = [f"{k} = {v!r}" if not isinstance(v, str) else f'{k} = "{v}"' for k, v in sim.items()]
    path = tmp_path / "scenario.toml"
    path.write_text(head + "[simulation]\n" + "\n".join(lines) + "\n")
    out = tmp_path / "run"
    subprocess.run([quell_bin, "run", path, "--no-plots", "--out", out], check=True, capture_output=True)
    design = subprocess.run([quell_bin, "design", "--json", path], check=True, capture_output=True, text=True)

    loop = scipy_loop.Loop(tomllib.loads(path.read_text()), json.loads(design.stdout))
    step = float(sim["output_step"]) if "output_step" in sim else scipy_loop.default_output_step(scenario, t_end)
    res = scipy_loop.simulate(loop, t_end, step, scipy_tol, scipy_tol)
    return read_signals(out / "signals.csv"), scipy_loop.signals(loop, res)


def assert_agree(quell, scipy, agreement=AGREEMENT):
    # The same instants k·h: quell's the double nearest the decimal, the SciPy loop's the product
    # k × h; each within half an ulp of the exact k·h, so within 1 ulp (2.2e-16) of each other.
    np.testing.assert_allclose(quell["t"], scipy["t"], rtol=2.3e-16, atol=0)
    for name, ours in scipy.items():
        theirs = quell[name]
        scale = max(1.0, float(np.max(np.abs(theirs))))
        worst = float(np.max(np.abs(theirs - ours)))
        assert worst <= agreement * scale, f"{name}: differs by {worst:.3e}, peak {scale:.3e}"


def test_paper_example_agrees_with_scipy_and_the_reference(quell_bin, tmp_path, reference_points):
    quell, scipy = both(quell_bin, tmp_path, EXAMPLES / "paper.toml", 20.0)
    assert_agree(quell, scipy)
    # The SciPy loop itself against the independent reference points (accurate to 1e-8) within
    # the horizon: y and u at t = 5, 10, 20 to 1e-6, as the Rust tests hold quell.
    for row in reference_points[reference_points[:, 0] <= 20.0]:
        k = int(round(row[0] / 0.1))
        got = [scipy[c][k] for c in ("y1", "y2", "u1", "u2")]
        assert np.allclose(got, row[1:], rtol=0, atol=1e-6), (row, got)


def test_siso_plant_with_complex_poles_agrees_with_scipy(quell_bin, tmp_path):
    # Not the paper's plant: one channel, τ = 0.5 s, complex filter and channel poles, μ = 1000.
    quell, scipy = both(quell_bin, tmp_path, EXAMPLES / "siso-complex.toml", 10.0)
    assert_agree(quell, scipy)


@pytest.mark.skipif(not os.environ.get("QUELL_LONG_TESTS"), reason="about 10 s; set QUELL_LONG_TESTS=1")
def test_paper_example_whole_run_agrees_with_scipy(quell_bin, tmp_path, reference_points):
    quell, scipy = both(quell_bin, tmp_path, EXAMPLES / "paper.toml", 100.0)
    assert_agree(quell, scipy)
    for row in reference_points:
        k = int(round(row[0] / 0.1))
        got = [scipy[c][k] for c in ("y1", "y2", "u1", "u2")]
        assert np.allclose(got, row[1:], rtol=0, atol=1e-6), (row, got)


def test_breakpoints_are_the_sums_of_the_delays():
    # τ = 1, 3 up to 10: every integer (sums and multiples of the shortest delay), once each.
    assert scipy_loop.breakpoints(np.array([1.0, 3.0]), 10.0) == [float(k) for k in range(1, 11)]
    # τ = 0.7, 1.1 up to 2: multiples of 0.7, 1.1, 1.4 = 2·0.7, 1.8 = 0.7 + 1.1, and the end.
    got = scipy_loop.breakpoints(np.array([0.7, 1.1]), 2.0)
    assert np.allclose(got, [0.7, 1.1, 1.4, 1.8, 2.0])


def test_the_script_writes_quells_columns(quell_bin, tmp_path):
    # The command line: the design JSON from `quell design --json`, a short run, the CSV's header
    # the same as signals.csv's (without x and x̂) and its first row the initial state (all zero
    # but the reference g(0) = [0, 2] and e = −g).
    design = tmp_path / "design.json"
    printed = subprocess.run([quell_bin, "design", "--json", EXAMPLES / "paper.toml"], check=True, capture_output=True, text=True)
    design.write_text(printed.stdout)
    out = tmp_path / "scipy.csv"
    assert scipy_loop.main([str(EXAMPLES / "paper.toml"), str(design), "--t-end", "0.5", "--out", str(out)]) == 0
    quell = tmp_path / "run"
    run = [quell_bin, "run", EXAMPLES / "paper.toml", "--no-plots", "--out", quell]
    subprocess.run(run, check=True, capture_output=True)
    assert out.read_text().splitlines()[0] == (quell / "signals.csv").read_text().splitlines()[0]
    cols = read_signals(out)
    assert len(cols["t"]) == 6 and cols["g2"][0] == 2.0 and cols["e2"][0] == -2.0 and cols["u1"][0] == 0.0


def test_a_scenario_with_truth_is_refused(tmp_path, capsys):
    # [truth] is not modelled by the script: it had run the design model silently (helper tryout,
    # 2026-12-06), so a comparison with quell's run of the true plant read as quell's error.
    scenario = tmp_path / "truth.toml"
    scenario.write_text((EXAMPLES / "paper.toml").read_text() + "\n[truth]\nu_max = [100.0, 100.0]\n")
    assert scipy_loop.main([str(scenario), str(tmp_path / "unread.json")]) == 2
    assert "[truth] is not modelled here" in capsys.readouterr().err
