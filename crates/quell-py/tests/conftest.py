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


@pytest.fixture(scope="session")
def reference_points():
    """y and u of the paper's example from an independent solver (crates/quell/tests/data/, see its README)."""
    path = REFERENCE / "paper_example_points.csv"
    if not path.is_file():
        pytest.fail(f"{path} is missing from the repository")
    import numpy as np

    return np.loadtxt(path, delimiter=",", skiprows=1)
