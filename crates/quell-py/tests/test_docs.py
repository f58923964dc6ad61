"""The `>>>` examples of docs/python.md and docs/deployment.md run as doctests: the pages show what
the package does."""

import doctest

from conftest import ROOT


def test_python_md_examples_run():
    result = doctest.testfile(
        str(ROOT / "docs" / "python.md"), module_relative=False, optionflags=doctest.NORMALIZE_WHITESPACE
    )
    assert result.attempted >= 10 and result.failed == 0, result


def test_deployment_md_examples_run(tmp_path, monkeypatch):
    """The FMU example, run where its relative paths work: a temporary directory (it writes fmu2/
    and fmu3/) beside a link to the repository's examples/."""
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    monkeypatch.chdir(tmp_path)
    result = doctest.testfile(
        str(ROOT / "docs" / "deployment.md"), module_relative=False, optionflags=doctest.NORMALIZE_WHITESPACE
    )
    assert result.attempted >= 8 and result.failed == 0, result
