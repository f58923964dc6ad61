"""Shared paths and fixtures. The tests check quell against independent references (SciPy,
python-control, closed forms, the reference data in crates/quell/tests/data/) and against the CLI, never against its own output."""

import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
REFERENCE = ROOT / "crates" / "quell" / "tests" / "data"
EXAMPLES = ROOT / "examples"


@pytest.fixture(scope="session")
def quell_bin():
    """The `quell` CLI built by `cargo test --workspace --release` (scripts/test sets QUELL_BIN)."""
    path = pathlib.Path(os.environ.get("QUELL_BIN", ROOT / "target" / "release" / "quell"))
    if not path.is_file():
        pytest.fail(f"the quell CLI is not at {path}; run `cargo build --release -p quell-cli` or set QUELL_BIN")
    return path


@pytest.fixture
def python_child():
    """Starts `python -c code` and waits for its 'ready' line. The child's SIGINT is set to its default
    first: a runner started in the background without job control (`cmd &` in a script) ignores SIGINT,
    its children inherit that, and Python then installs no KeyboardInterrupt for a test to send."""
    import signal
    import subprocess
    import sys

    def start(code):
        child = subprocess.Popen(
            [sys.executable, "-c", code],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        assert child.stdout.readline().strip() == "ready"
        return child

    return start


@pytest.fixture(scope="session")
def reference_points():
    """y and u of the paper's example from an independent solver (crates/quell/tests/data/, see its README)."""
    path = REFERENCE / "paper_example_points.csv"
    if not path.is_file():
        pytest.fail(f"{path} is missing from the repository")
    import numpy as np

    return np.loadtxt(path, delimiter=",", skiprows=1)
