"""Every public class, function and method of the quell package has a numpydoc docstring (a
summary, and the sections Parameters, Returns, Raises and Examples where they apply), every
property a description, and every docstring's examples run as doctests (doctest is the
independent side: the printed values must be what the code returns)."""

import doctest
import inspect

import numpy as np
import pytest

import quell


def _public():
    """(qualified name, object, kind) of every public class, function, method and property."""
    out = []
    for name in quell.__all__:
        obj = getattr(quell, name)
        if name.startswith("__"):
            continue
        if inspect.isclass(obj):
            out.append((name, obj, "class"))
            for member, value in vars(obj).items():
                # A controller's state is public API (a checkpoint), under pickle's names.
                if member.startswith("_") and member not in ("__getstate__", "__setstate__"):
                    continue
                if isinstance(value, property) or inspect.isgetsetdescriptor(value) or inspect.isdatadescriptor(value):
                    out.append((f"{name}.{member}", value, "property"))
                elif callable(value) or isinstance(value, (staticmethod, classmethod)):
                    out.append((f"{name}.{member}", getattr(obj, member), "method"))
        elif callable(obj):
            out.append((name, obj, "function"))
    return out


PUBLIC = _public()
IDS = [name for name, _, _ in PUBLIC]


def _parameters(obj):
    """Its parameters other than self (None when Python cannot tell)."""
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return None
    return [p for p in sig.parameters.values() if p.name not in ("self", "cls")]


def _constructor_parameters(cls):
    try:
        return [p for p in inspect.signature(cls).parameters.values() if p.name not in ("self", "cls", "args", "kwargs")]
    except (TypeError, ValueError):
        return []


@pytest.mark.parametrize("name, obj, kind", PUBLIC, ids=IDS)
def test_numpydoc_sections(name, obj, kind):
    doc = inspect.getdoc(obj) or ""
    assert doc.strip(), f"{name} has no docstring"
    if kind == "property":
        return
    sections = {line.strip() for line, under in zip(doc.splitlines(), doc.splitlines()[1:]) if set(under.strip()) == {"-"}}
    assert "Examples" in sections, f"{name}: no Examples section"
    if kind == "class":
        is_error = issubclass(obj, Exception)
        if not is_error and _constructor_parameters(obj):
            assert {"Parameters", "Raises"} <= sections, f"{name}: constructor without Parameters/Raises"
        return
    assert {"Returns", "Raises"} <= sections, f"{name}: {sections}"
    params = _parameters(obj)
    if params:
        assert "Parameters" in sections, f"{name}: no Parameters section"
        text = doc.split("Parameters", 1)[1]
        for p in params:
            if p.kind is p.VAR_KEYWORD:
                continue
            assert f"{p.name} :" in text or f"{p.name}," in text, f"{name}: parameter {p.name} undocumented"


@pytest.mark.parametrize("name, obj, kind", [p for p in PUBLIC if p[2] != "property"], ids=[n for n, _, k in PUBLIC if k != "property"])
def test_examples_run(name, obj, kind, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # examples that write files write here
    pytest.importorskip("matplotlib").use("Agg")
    doc = inspect.getdoc(obj)
    test = doctest.DocTestParser().get_doctest(doc, {"quell": quell, "np": np}, name, None, 0)
    assert test.examples, f"{name}: no >>> examples"
    runner = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS)
    out = []
    runner.run(test, out=out.append)
    assert runner.failures == 0, "".join(out)
