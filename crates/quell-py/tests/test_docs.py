"""The `>>>` examples of docs/python.md run as doctests: the page shows what the package does."""

import doctest

from conftest import ROOT


def test_python_md_examples_run():
    result = doctest.testfile(
        str(ROOT / "docs" / "python.md"), module_relative=False, optionflags=doctest.NORMALIZE_WHITESPACE
    )
    assert result.attempted >= 10 and result.failed == 0, result
