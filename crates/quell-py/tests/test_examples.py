"""examples/python/*.py run and produce what they say (the figures, the same eigenvalues)."""

import os
import subprocess
import sys

import numpy as np

from conftest import ROOT

EXAMPLES = ROOT / "examples" / "python"


def run(script, *args, cwd):
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run([sys.executable, EXAMPLES / script, *args], check=True, capture_output=True,
                          text=True, cwd=cwd, env=env).stdout


def test_paper_example_draws_figs_1_and_2(tmp_path):
    out = run("paper_example.py", str(tmp_path), cwd=tmp_path)
    assert "relative degrees sigma = [2, 1]" in out
    for name in ("fig1.png", "fig2.png"):
        data = (tmp_path / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000


def test_with_python_control(tmp_path):
    out = run("with_python_control.py", cwd=tmp_path)
    lines = {l.split(":")[0].strip(): l for l in out.splitlines()}
    assert "[-6. -4. -2.]" in lines["poles of the decoupled plant"]
    eig = [lines[name].split("=")[1].split("]")[0] for name in ("quell.place", "control.place")]
    assert eig[0] == eig[1]
    tail = np.array(lines["tail max |e| per channel"].split("[")[1].split("]")[0].split(), dtype=float)
    assert tail[0] < 0.05 and tail[1] < 0.005
