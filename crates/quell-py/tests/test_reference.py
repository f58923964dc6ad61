"""quell.simulate against what does not come from quell.simulate: the CLI's signals.csv (the same
numbers, to the last printed digit) and the paper example's points from an independent solver."""

import subprocess

import numpy as np

import quell


def test_arrays_equal_signals_csv(quell_bin, tmp_path):
    """`quell run` prints every number in shortest round-trip form, so equality is exact."""
    subprocess.run([quell_bin, "run", "--out", tmp_path, "--no-plots"], check=True, capture_output=True)
    csv = tmp_path / "signals.csv"
    header = csv.read_text().splitlines()[0].split(",")
    table = np.loadtxt(csv, delimiter=",", skiprows=1)
    r = quell.simulate(quell.paper_example())
    frame = r.to_pandas()
    assert list(frame.columns) == header
    n, m, q = len(r), r.m, r.q
    assert table.shape == (n, 1 + 5 * m + m * q)
    assert np.array_equal(frame.to_numpy(), table)
    assert np.array_equal(r.t, table[:, 0])
    assert np.array_equal(r.y, table[:, 1 : 1 + m])
    assert np.array_equal(r.u_f, table[:, 1 + 4 * m : 1 + 5 * m])
    assert np.array_equal(r.eta.reshape(n, m * q), table[:, 1 + 5 * m :])


def test_paper_reference_points(reference_points):
    """y and u at t = 5 … 100 s within 1e-6 of the independent solver (accurate to ~1e-8), as the
    Rust suite requires; rtol = atol = 1e-10 so that quell's own error is far below the bound."""
    r = quell.simulate(quell.paper_example(), rtol=1e-10, atol=1e-10)
    for t, y1, y2, u1, u2 in reference_points:
        k = int(round(t / 0.1))
        assert abs(r.t[k] - t) < 1e-12
        np.testing.assert_allclose(r.y[k], [y1, y2], rtol=0, atol=1e-6)
        np.testing.assert_allclose(r.u[k], [u1, u2], rtol=0, atol=1e-6)


def test_paper_tail_bounds():
    """The paper's Figs. 1 and 2: the tracking errors vanish (max |e_1| < 0.05 and max |e_2| < 0.005 on [90, 100])."""
    r = quell.simulate(quell.paper_example())
    tail = r.t >= 90
    assert np.abs(r.e[tail, 0]).max() < 0.05
    assert np.abs(r.e[tail, 1]).max() < 0.005
    assert r.outcome == {"status": "completed"}
    assert r.stats["steps"] > 0 and r.stats["rhs_evaluations"] > r.stats["steps"]
