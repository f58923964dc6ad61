"""Bad arguments from Python: a TypeError for a wrong type and a QuellError subclass (all
ValueErrors) for a bad value, naming the argument, never a Rust panic (pyo3_runtime.PanicException derives from BaseException,
so `except Exception` would not even catch it)."""

import itertools
import re

import numpy as np
import pytest

import quell

A = [[-3.2, -1.7, -3.0], [2.8, 1.3, 4.0], [0.3, 0.3, -0.5]]
B = [[-2.0, 1.0], [2.0, -1.0], [1.0, 0.0]]
C = [[2.0, 2.0, 0.0], [2.0, 1.0, 2.0]]


@pytest.mark.parametrize(
    "kwargs,exc,fragment",
    [
        (dict(A=[[1, 2]], B=[[1]], C=[[1]]), quell.ScenarioError, r"^A: expected 1×1 \(n×n\), found 1×2; A must be square$"),
        (dict(A=[[np.nan]], B=[[1]], C=[[1]]), quell.ScenarioError, r"^A\[0\]\[0\]: expected a finite number, found NaN"),
        (dict(A=A, B=B, C=C, delays=[1.0, np.inf]), quell.ScenarioError, r"^delays\[1\]: expected a finite number"),
        (dict(A="abc", B=B, C=C), TypeError, r"^A: expected real numbers, found strings"),
        (dict(A=[[1, 2], [3]], B=B, C=C), quell.ScenarioError, r"^A: expected an array-like of real numbers"),
        (dict(A=[[1 + 1j]], B=[[1]], C=[[1]]), TypeError, r"^A: expected real numbers, found complex numbers"),
        (dict(A=A, B=[1, 2, 3], C=C), quell.ScenarioError, r"^B: expected a matrix \(2-D array"),
        (dict(A=A, B=B, C=C, delays=[1.0]), quell.ScenarioError, r"^delays: expected 2 entries"),
        (dict(A=A, B=B, C=C, delays=[1.0, -3.0]), quell.ScenarioError, r"^delays\[1\]: expected a finite delay ≥ 0"),
        (dict(A=A, B=B), TypeError, r"^C: missing"),
        (dict(A=A, B=B, C=C, D=[[1], [1], [1]], Q=[[1, 2], [1, 2]]), quell.ScenarioError, r"^Q: expected 2×1 \(m×k\), found 2×2; m = 2 \(columns of B\), k = 1 \(columns of D\)$"),
        (dict(A=A, B=B, C=[[2.0, 2.0]]), quell.ScenarioError, r"^C: expected 2×3 \(m×n\), found 1×2; m = 2 \(columns of B\), n = 3 \(rows of A\); the method decouples the plant into one channel per input, so it needs as many outputs as inputs \(a square plant\): choose m outputs to track, or add inputs$"),
        (dict(A=A, B=B, C=C, x0=[0, 0]), quell.ScenarioError, r"^x0: expected 3 entries \(one per state, n = 3 rows of A\), found 2$"),
        (dict(A=object(), B=B, C=C), TypeError, r"^A: expected real numbers, found an object"),
        (dict(A=[[None]], B=[[1]], C=[[1]]), TypeError, r"^A: expected real numbers, found entries that are not all numbers"),
    ],
)
def test_plant_arguments(kwargs, exc, fragment):
    with pytest.raises(exc, match=fragment):
        quell.Plant(**kwargs)


PLANT = quell.paper_example().plant
DESIGN = dict(channel_poles=[[-6, -2], [-4]], reference_filter_poles=[[-1, -6], [-9]],
              disturbance_filter_poles=[[-1, -3], [-1, -2, -3]], mu=[20, 30], beta=1.0, observer_poles=[-2, -3, -4])


@pytest.mark.parametrize(
    "change,fragment",
    [
        (dict(channel_poles=[-6, -2, -4]), "put each one's poles in brackets"),

        (dict(channel_poles=[[[-2, 0]], [-4]]), "has imaginary part 0"),
        (dict(channel_poles=[[[-2, -1]], [-4]]), "write it as"),
        (dict(channel_poles=[[-1 + 2j, -3], [-4]]), "no complex-conjugate partner"),
        (dict(channel_poles=[[np.nan, -2], [-4]]), "expected a finite number"),
        (dict(mu=[20]), r"^mu: expected 2 entries"),
        (dict(mu=[[20, 30]]), r"^mu: expected a 1-D array"),
        (dict(beta=0.0), r"^beta: expected a finite β > 0"),
        (dict(observer_gain=[[1, 2]]), r"^observer_gain, observer_poles: both are given"),
        (dict(observer_poles=None), r"^observer_gain: missing; give exactly one of observer_gain"),
        (dict(observer_poles=[-2, -3]), r"^observer_poles"),
    ],
)
def test_design_arguments(change, fragment):
    with pytest.raises(quell.DesignError, match=fragment):
        quell.design(PLANT, **dict(DESIGN, **change))


@pytest.mark.parametrize(
    "change,fragment",
    [
        (dict(channel_poles=[["a"], [-4]]), r"^channel_poles\[0\]\[0\]: expected a pole: .*, found a str"),
        (dict(beta="one"), r"^beta: expected a real number, found a str"),
        (dict(mu="ab"), r"^mu: expected real numbers, found strings"),
        (dict(channel_poles=3.0), r"^channel_poles: expected one list of poles per channel or component, .* found a float"),
    ],
)
def test_design_arguments_of_the_wrong_type(change, fragment):
    with pytest.raises(TypeError, match=fragment):
        quell.design(PLANT, **dict(DESIGN, **change))


def test_design_needs_a_plant():
    with pytest.raises(TypeError, match="plant: expected a quell.Plant, found a list"):
        quell.design([[1]], **DESIGN)


def test_scenario_arguments():
    ref = [{"bias": 1.0}, {"bias": 2.0}]
    kw = dict(DESIGN)
    with pytest.raises(quell.ScenarioError, match=r'^reference\[0\]\["bais"\]: unknown key \(did you mean `bias`\?\)'):
        quell.Scenario(PLANT, [{"bais": 1.0}, {"bias": 2.0}], quell.paper_example().disturbance, **kw)
    with pytest.raises(quell.ScenarioError, match="disturbance: missing"):
        quell.Scenario(PLANT, ref, **kw)
    with pytest.raises(quell.ScenarioError, match=r"^t_end: expected a final time > 0"):
        quell.Scenario(PLANT, ref, quell.paper_example().disturbance, t_end=-1, **kw)
    with pytest.raises(TypeError, match=r"^rtol: expected a real number, found a str"):
        quell.Scenario(PLANT, ref, quell.paper_example().disturbance, rtol="tight", **kw)
    with pytest.raises(TypeError, match=r'^reference\[0\]\["bias"\]: expected a real number, found a complex'):
        quell.Scenario(PLANT, [{"bias": 1j}, {"bias": 2.0}], quell.paper_example().disturbance, **kw)
    with pytest.raises(quell.ScenarioError, match=r"^mue: unknown keyword \(did you mean `mu`\?\)") as caught:
        quell.Scenario(PLANT, ref, quell.paper_example().disturbance, mue=[1, 2], **kw)
    assert caught.value.key == "mue"
    # A misspelt simulation keyword was called an unknown [design] key, with no hint.
    with pytest.raises(quell.ScenarioError, match=r"^t_ned: unknown keyword \(did you mean `t_end`\?\); quell.Scenario takes plant, reference, disturbance, the keywords name, t_end") as caught:
        quell.Scenario(PLANT, ref, quell.paper_example().disturbance, t_ned=5, **kw)
    assert caught.value.key == "t_ned"
    with pytest.raises(TypeError, match="scenario: expected a quell.Scenario"):
        quell.simulate("paper.toml")


JUNK = [None, "x", 1j, [], [[]], [[1, 2], [3]], {"a": 1}, object(), np.array([np.nan]), float("inf"), -1, 1e308, [[1e308, -1e308]]]


def test_no_panic_on_junk():
    """Every entry point with junk in every position: only Python exceptions of the documented kinds."""
    d = quell.paper_example().design()
    calls = [
        lambda a, b: quell.Plant(a, b, C),
        lambda a, b: quell.Plant(A, B, C, a, b),
        lambda a, b: quell.place(a, B, b),
        lambda a, b: quell.place(A, a, b),
        lambda a, b: quell.design(PLANT, **dict(DESIGN, channel_poles=a, mu=b)),
        lambda a, b: quell.design(PLANT, **dict(DESIGN, observer_poles=None, observer_gain=a, beta=b)),
        lambda a, b: quell.Controller(d, a),
        lambda a, b: quell.Controller(d, 1e-3).step(a, b),
        lambda a, b: quell.simulate(quell.paper_example(), t_end=a, rtol=b),
        lambda a, b: quell.Scenario(PLANT, a, b, **DESIGN),
        lambda a, b: quell.Scenario.from_toml(a),
    ]
    for call, a, b in itertools.product(calls, JUNK, JUNK[:5]):
        try:
            call(a, b)
        except (ValueError, TypeError, quell.QuellError):
            pass


def test_types_are_named_with_their_article_and_a_huge_int_is_a_value_error():
    """"found an int", not "a int"; an int is a real number, so one beyond a float64's range is a
    ValueError that says so, not a TypeError."""
    s = quell.paper_example()
    with pytest.raises(TypeError, match=r"^study: expected a quell.Study or the path of a study file, found an int$"):
        quell.sweep(3)
    with pytest.raises(ValueError, match=r"^sample_time: expected a real number within a float64's range \(±1.8e308\), found an integer of 401 digits"):
        quell.Controller(s.design(), 10**400)
    # A QuellError with the file's key (a plain ValueError before, which `except QuellError` missed).
    with pytest.raises(quell.ScenarioError, match=r"^t_end: expected a real number within a float64's range") as e:
        quell.simulate(s, t_end=10**400)
    assert e.value.key == "simulation.t_end"


def test_huge_ints_bools_and_bad_pairs_in_lists_are_named():
    """An int too long for str() (over 4,300 digits) still gets its digit count; in a pole list it
    is the same ValueError; a bool among a list's numbers (numpy would read True as 1.0) is a
    TypeError naming its index; a NaN inside a [re, im] pair names the pair's entry."""
    s = quell.paper_example()
    with pytest.raises(ValueError, match=r"found an integer of about 5001 digits$"):
        quell.Controller(s.design(), 7 * 10**5000)
    with pytest.raises(ValueError, match=r"^poles\[1\]: expected a real number within a float64's range"):
        quell.place([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], [-1, 10**400])
    with pytest.raises(TypeError, match=r"^A\[0\]\[0\]: expected a real number, found a bool$"):
        quell.place([[True, 1.0], [0.0, 0.0]], [[0.0], [1.0]], [-1, -2])
    with pytest.raises(TypeError, match=r"^poles\[2\]\[0\]: expected a real number, found a bool$"):
        quell.place(np.eye(3), np.eye(3)[:, :1] + 1, [-1, -2, [True, 1.0]])
    with pytest.raises(quell.DesignError, match=r"^poles\[2\]\[1\]: expected a finite number, found NaN$"):
        quell.place(np.eye(3), np.eye(3)[:, :1] + 1, [-1, -2, [-1.0, float("nan")]])
    with pytest.raises(quell.DesignError, match=r"^B: expected n = 3 rows \(one per state of A\).*found 1×3; .*place\(Aᵀ, Cᵀ, poles\)ᵀ$"):
        quell.place(np.eye(3), [[1.0, 0.0, 0.0]], [-1, -2, -3])
    # numpy's bools too: np.True_ would be a pole at +1.
    with pytest.raises(TypeError, match=r"^poles\[0\]: expected a pole.*found a bool"):
        quell.place(np.eye(2), [[0.0], [1.0]], [np.True_, -2.0])
    with pytest.raises(TypeError, match=r"^poles\[0\]: expected a pole"):
        quell.place(np.eye(2), [[0.0], [1.0]], np.array([True, False]))


def test_a_huge_int_inside_a_dict_argument_is_a_keyed_scenario_error():
    """10**400 in a grid, a simulation dict or a signal dict was Python's bare OverflowError ("int
    too large to convert to float"), naming nothing: it is a ScenarioError naming the entry."""
    s = quell.paper_example()
    cases = [
        (lambda: quell.Study(s, grid={"design.mu[0]": [10**400]}), 'grid["design.mu[0]"][0]'),
        (lambda: quell.Study(s, simulation={"t_end": 10**400}, grid={"design.beta": [1.0]}), 'simulation["t_end"]'),
    ]
    for make, name in cases:
        with pytest.raises(quell.ScenarioError) as e:
            make()
        assert str(e.value).startswith(name + ": expected a real number within a float64's range"), str(e.value)
        assert "401 digits" in str(e.value)


def test_oversized_texts_surrogates_and_long_lists_are_refused_by_what_is_wrong():
    """A lone surrogate in a scenario text is a ScenarioError naming `text` (it was Python's
    UnicodeEncodeError); a text beyond 16 MiB is refused before it is parsed (TOML parsing took
    ~95 bytes a byte: 24 MB aborted the interpreter at 2 GB); ten million delays are refused by
    their count (each float was asked for a numpy dtype, 11 s); a million names by their count, not
    as a duplicate; a bool entry among numbers is still named."""
    with pytest.raises(quell.ScenarioError, match=r"^text: expected text that UTF-8 can hold, found a lone surrogate"):
        quell.Scenario.from_toml('name = "\ud800"')
    big = quell.paper_example().to_toml().replace("mu = [20.0, 30.0]", "mu = [" + ",".join(["1"] * 8_500_000) + "]")
    assert len(big) > 16 << 20
    with pytest.raises(quell.ScenarioError, match=r"longer than 16 MiB"):
        quell.Scenario.from_toml(big)
    with pytest.raises(quell.ScenarioError, match=r"^delays: expected 2 entries .* found 10000000"):
        quell.Plant(A, B, C, delays=[1.0] * 10_000_000)
    with pytest.raises(quell.ScenarioError, match=r"^inputs: expected 2 names \(one per \w+\), found 1000000"):
        quell.Plant(A, B, C, inputs=["a"] * 1_000_000)
    with pytest.raises(TypeError, match=r"^delays\[1\]: expected a real number, found a bool"):
        quell.Plant(A, B, C, delays=[1.0, True])


def test_a_path_given_as_toml_text_is_named_with_the_function_that_reads_it(tmp_path):
    """A scenario's or study's path passed where its TOML text goes had a bare syntax error ("line 1,
    column 50: key with no value") that named neither the argument nor the path."""
    path = tmp_path / "plant"
    path.write_text(quell.paper_example().to_toml())
    for call, given, load in [
        (quell.Scenario.from_toml, "examples/paper.toml", "quell.Scenario.load(path)"),
        (quell.Scenario.from_toml, str(path), "quell.Scenario.load(path)"),
        (quell.Study.from_toml, "studies/monte-carlo-A.toml", "quell.Study.load(path)"),
        (quell.auto_design, "examples/paper.toml", "open(path).read()"),
    ]:
        with pytest.raises(quell.ScenarioError, match=f"^text: expected TOML text, found a file's path, \"{re.escape(given)}\"; read the file with {re.escape(load)}") as e:
            call(given)
        assert e.value.key == "text"


def test_every_scenario_error_has_the_key_or_argument_it_names():
    """`.key` was None where the message named an argument (a NaN in Plant's A, jobs=0)."""
    with pytest.raises(quell.ScenarioError, match=r"^A\[0\]\[0\]: expected a finite number, found NaN") as caught:
        quell.Plant([[np.nan, 1.0], [2.0, -1.0]], [[1.0], [0.0]], [[1.0, 0.0]])
    assert caught.value.key == "A[0][0]"
    study = quell.Study(quell.paper_example(), grid={"design.mu[0]": [1.0]})
    with pytest.raises(quell.ScenarioError, match=r"^jobs: expected a number of threads") as caught:
        study.sweep(jobs=0)
    assert caught.value.key == "jobs"


def test_a_name_that_is_not_valid_unicode_and_a_feedthrough_are_named_with_their_entry():
    """A lone surrogate is a str that cannot be written to UTF-8 files: a ScenarioError saying so
    (it was "expected a str (a signal name), found a str"). python-control's nonzero feedthrough is
    named by its entry with a short number (1e-300 had printed 300 digits)."""
    A, B, C = [[0.0, 1.0], [-2.0, -3.0]], [[1.0, 0.0], [0.0, 1.0]], [[1.0, 0.0], [0.0, 1.0]]
    with pytest.raises(quell.ScenarioError, match=r"^inputs\[0\]: expected a str \(a signal name\) of valid Unicode, found a str with a lone surrogate"):
        quell.Plant(A, B, C, inputs=["\ud800", "b"])
    control = pytest.importorskip("control")
    # (1e-300 is now rounding's, accepted: test_python_control_shapes_get_hints_in_its_own_terms.)
    D = [[0.0, 0.0], [0.0, 0.1 + 0.2]]
    with pytest.raises(quell.ScenarioError, match=r"^sys\.D\[1\]\[1\]: .*expected 0 \(within rounding, [0-9.e-]+\), found 0\.300000; ") as e:
        quell.Plant(control.ss(A, B, C, D))
    assert len(str(e.value)) < 400


def test_masked_entries_are_refused_not_read_as_data():
    """numpy.asarray reads a masked array as its data, the masked entries' values included: a
    plant with a masked entry of A (a missing measurement, say) is refused, naming how many; a
    masked array with nothing masked is its data."""
    A_masked = np.ma.masked_array(A, mask=[[False, True, False], [False] * 3, [False] * 3])
    with pytest.raises(quell.ScenarioError, match=r"^A: expected real numbers, found a masked array with 1 masked entry,"):
        quell.Plant(A=A_masked, B=B, C=C)
    unmasked = quell.Plant(A=np.ma.masked_array(A), B=B, C=C)
    np.testing.assert_array_equal(unmasked.A, A)
    # Within a list of rows too (numpy reads those rows as their data), and numpy's masked constant.
    rows = [np.ma.masked_array(A[0], mask=[True, False, True]), A[1], A[2]]
    with pytest.raises(quell.ScenarioError, match=r"^A: expected real numbers, found a masked array with 2 masked entries,"):
        quell.Plant(A=rows, B=B, C=C)
    with pytest.raises(quell.ScenarioError, match=r"^C: .* with 1 masked entry,"):
        quell.Plant(A=A, B=B, C=(C[0], [C[1][0], np.ma.masked, C[1][2]]))
    np.testing.assert_array_equal(quell.Plant(A=[np.ma.masked_array(r) for r in A], B=B, C=C).A, A)


def test_nested_lists_that_share_their_rows_are_refused_at_once():
    """Rows shared at every level (`a = [a, a]` forty times: 2^40 entries) had made the masked-entry
    walk, and numpy's own reading after it, run for ever; a list holding itself ends too."""
    import time

    a = [1.0]
    for _ in range(40):
        a = [a, a]
    start = time.monotonic()
    with pytest.raises(quell.ScenarioError, match=r"^A: expected an array-like of at most 1e9 numbers, found 1.099511627776e12 entries"):
        quell.Plant(A=a, B=B, C=C)
    # A sequence that long (range(10**12) had numpy allocate until the process aborted), and a
    # controller's input or state of that length (its allocation had aborted the interpreter).
    with pytest.raises(quell.ScenarioError, match=r"^A: expected an array-like of at most 1e9 numbers, found 1e12 entries \(a sequence"):
        quell.Plant(A=range(10**12), B=B, C=C)

    class Huge(list):
        def __len__(self):
            return 10**12

    c = quell.Controller(quell.paper_example().design(), 0.01)
    with pytest.raises(quell.ControllerError, match=r"^y: expected 2 entries \(one per output\), found 1000000000000"):
        c.step(Huge([0.0, 0.0]), [0.0, 0.0])
    with pytest.raises(quell.ControllerError, match="found 1000000000000"):
        c.__setstate__(range(10**12))
    looped = []
    looped.append(looped)
    with pytest.raises((quell.ScenarioError, TypeError)):
        quell.Plant(A=looped, B=B, C=C)
    assert time.monotonic() - start < 5


def test_a_keyboard_interrupt_while_reading_an_array_goes_on_as_it_is():
    """A Ctrl-C met while numpy reads a lazy array-like (here raised by its __getitem__) had been
    turned into a ScenarioError, so the program went on after the user asked it to stop."""

    class Lazy:
        def __len__(self):
            return 3

        def __getitem__(self, i):
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        quell.Plant(A=Lazy(), B=B, C=C)


def test_a_terminal_given_as_a_scenario_file_is_refused_not_read():
    """A terminal's path (a pty here) had blocked Scenario.load and Study.load past Ctrl-C: a
    device is refused before it is opened (hostile review, 2026-12-06)."""
    import os
    import pty

    leader, follower = pty.openpty()
    try:
        path = os.ttyname(follower)
        for load in (quell.Scenario.load, quell.Study.load):
            with pytest.raises(quell.ScenarioError, match="a device, not a file"):
                load(path)
    finally:
        os.close(leader)
        os.close(follower)


def test_a_tampered_result_pickle_is_refused_not_a_panic():
    """A SimResult's pickled state with sizes that do not agree (q = 100, m = 2**40) had raised a
    Rust PanicException in the summary (hostile review)."""
    r = quell.simulate(quell.paper_example(), t_end=1.0)
    restore, (state,) = r.__reduce__()
    assert restore(dict(state)).summary() == r.summary()
    for key, value in [("q", 100), ("m", 2**40), ("m", 0), ("n", 10**6)]:
        with pytest.raises(quell.ScenarioError, match=r"^state: not a pickled quell.SimResult \("):
            restore({**state, key: value}).summary()


def test_long_doubles_are_floats_and_self_holding_lists_are_refused():
    """numpy's long doubles, whose tolist() is themselves, had recursed until the stack overflowed
    (SIGSEGV) in every value taken as TOML (a study's grid, μ, a reference); a list that holds
    itself, or one 10⁴ levels deep, likewise. Long doubles are now the float64 they round to,
    complex ones a TypeError, and nesting past 32 levels a TypeError naming the argument."""
    s = quell.paper_example()
    study = quell.Study(s, grid={"design.mu[0]": [np.longdouble(3.0), np.float64(4.0)]})
    assert len(study) == 2 and "3.0, 4.0" in study.to_toml()
    grid = quell.Study(s, grid={"design.mu[0]": np.array([3.0, 5.0], dtype=np.longdouble)})
    assert len(grid) == 2
    disturbance = s.disturbance
    kw = dict(DESIGN, mu=[np.longdouble(1.5), 2])
    scenario = quell.Scenario(PLANT, [{"bias": np.longdouble(1.0)}, {"bias": 2.0}], disturbance, **kw)
    assert scenario.design().mu == [1.5, 2.0] and scenario.reference[0]["bias"] == 1.0
    with pytest.raises(TypeError, match=r"^grid\[\"design.mu\[0\]\"\]\[0\]: expected real numbers, found a complex"):
        quell.Study(s, grid={"design.mu[0]": [np.clongdouble(3.0)]})
    holds_itself = []
    holds_itself.append(holds_itself)
    deep = 1.0
    for _ in range(10_000):
        deep = [deep]
    for bad in (holds_itself, deep):
        with pytest.raises(TypeError, match=r"^grid: expected numbers, .* nested more than 32 deep"):
            quell.Study(s, grid={"design.mu[0]": bad})
    with pytest.raises(TypeError, match=r"nested more than 32 deep"):
        quell.Scenario(PLANT, [{"bias": deep}, {"bias": 2.0}], disturbance, **DESIGN)


def test_sets_bytes_and_systems_inside_dict_arguments_are_type_errors():
    """Inside dict arguments a set (no order), bytes (not numbers), a generator or a
    python-control system were read as lists (b"ab" as u_max = [97, 98]) or leaked
    python-control's OSError; they are TypeErrors naming the entry, as at top level. Lists,
    tuples and numpy arrays are still read."""
    control = pytest.importorskip("control")
    s = quell.paper_example()
    sys = control.ss(s.plant.A, s.plant.B, s.plant.C, 0)
    design = s.design().choices
    make = lambda **kw: quell.Scenario(s.plant, s.reference, s.disturbance, **design, **kw)
    for value, found in [(b"ab", "bytes"), ({0.6, 0.3}, "set"), ((x for x in [1.0]), "generator"), (sys, "StateSpace")]:
        with pytest.raises(TypeError, match=r'^actuator\["u_max"\]: expected a number, string, list or dict, found an? ' + found):
            make(actuator={"u_max": value})
    with pytest.raises(TypeError, match=r'^truth\["A"\]: .*found a StateSpace'):
        make(truth={"A": sys})
    with pytest.raises(TypeError, match=r"^poles: expected a list of poles.*found a StateSpace"):
        quell.place(s.plant.A, s.plant.B, sys)
    with pytest.raises(TypeError, match="found a set"):
        quell.place(s.plant.A, s.plant.B, {-1.0, -2.0, -3.0})
    for good in [(0.6, 0.3), [0.6, 0.3], np.array([0.6, 0.3])]:
        assert "u_max = [0.6, 0.3]" in make(actuator={"u_max": good}).to_toml()


def test_a_sample_time_beyond_t_end_is_named_as_the_sample_time():
    """The default output step is a multiple of the sample time, so a sample time beyond t_end was
    refused as `output_step`, which the caller had not given."""
    s = quell.paper_example()
    with pytest.raises(quell.ScenarioError, match=r"^sample_time: expected a sample time ≤ t_end = 100, found 200") as e:
        quell.simulate(s, sample_time=200.0)
    assert e.value.key == "simulation.sample_time"


def test_a_file_scenario_names_its_keys_as_the_file_does(tmp_path):
    """A sampled run's own checks on a scenario read from a file name `simulation.sample_time`, as
    the CLI does; on a scenario built from arguments, or a sample time given to simulate, the
    argument `sample_time`."""
    text = quell.paper_example().to_toml().replace("[simulation]", "[simulation]\nsample_time = 0.3")
    s = quell.Scenario.from_toml(text)
    with pytest.raises(quell.ScenarioError, match=r"^simulation\.sample_time: channel 1's delay"):
        quell.simulate(s)
    # Another setting given to simulate does not make the file's key Python's argument.
    with pytest.raises(quell.ScenarioError, match=r"^simulation\.sample_time: channel 1's delay"):
        quell.simulate(s, t_end=50.0)
    with pytest.raises(quell.ScenarioError, match=r"^sample_time: channel 1's delay"):
        quell.simulate(quell.paper_example(), sample_time=0.3)


def test_auto_design_with_a_plant_names_the_python_argument():
    """auto_design(plant, …, beta=-1) had named the file's key `design.beta`; Scenario names
    `beta`, as docs/python.md says of messages on Python arguments."""
    p = quell.Plant([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], [[1.0, 0.0]])
    with pytest.raises((quell.ScenarioError, quell.DesignError), match=r"^beta: "):
        quell.auto_design(p, [{"bias": 1.0}], t_end=20.0, beta=-1.0)
