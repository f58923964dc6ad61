"""Every parameter of every public function, constructor and method, given an argument of the wrong
type (an `object()`), raises TypeError naming the parameter and the type found. The parameters come
from `inspect.signature` (the native functions' own text signatures), so a new parameter without a
case here fails `test_every_parameter_has_a_case`."""

import inspect

import numpy as np

import pytest

import quell

from test_api import A, B, C, D, DISTURBANCE, L, PAPER_DESIGN, Q, REFERENCE

WRONG = object()


def _valid():
    """Per callable: (the callable, valid keyword arguments)."""
    s = quell.paper_example()
    design = s.design()
    study = quell.Study(s, simulation={"t_end": 1.0})
    result = quell.simulate(s, t_end=1.0)
    swept = study.sweep(jobs=1)
    plant = quell.Plant(A, B, C, D, Q, delays=[1.0, 3.0])
    tuning = dict(scenario=s, mu=[5.0, 80.0], objective="tail_rms_e", max_u=100.0, max_uf=[1e6, 1e6], points=2,
                  refine=0, settle={}, max_steps=1000, simulation={"t_end": 1.0}, jobs=1)
    tuned = quell.tune(**tuning)
    return {
        "Plant": (quell.Plant, dict(A=A, B=B, C=C, D=D, Q=Q, delays=[1.0, 3.0], x0=[0, 0, 0], inputs=["a", "b"],
                                    outputs=["c", "d"], states=["x", "y", "z"], time_unit="min", xhat0=[0, 0, 0])),
        "design": (quell.design, dict(plant=plant, observer_gain=L, observer_poles=None, relative_degrees=[2, 1],
                                      regressor_scaling="paper", reference_sizes=[3.0, 2.0],
                                      disturbance_sizes=[1.0, 3.0], **PAPER_DESIGN)),
        "place": (quell.place, dict(A=A, B=B, poles=[-1, -2, -3])),
        "auto_design": (quell.auto_design, dict(text=s.to_toml(), reference=None, disturbance=None, convergence_time=10.0,
                                                u_limit=100.0, delay_error=0.0, time_scale=2.0)),
        "Scenario": (quell.Scenario, dict(plant=plant, reference=REFERENCE, disturbance=DISTURBANCE, name="x",
                                          t_end=1.0, output_step=0.1, rtol=1e-6, atol=1e-6, sample_time=None,
                                          method="auto", precision="f64", noise={"std": [0.0, 0.0]}, truth=plant,
                                          actuator={"u_max": [1e3, 1e3]},
                                          observer_gain=L, **PAPER_DESIGN)),
        "Scenario.from_toml": (quell.Scenario.from_toml, dict(text=s.to_toml(), sample_time=0.01)),
        "Scenario.load": (quell.Scenario.load, dict(path="paper.toml", sample_time=0.01)),
        "simulate": (quell.simulate, dict(scenario=s, t_end=1.0, output_step=0.1, rtol=1e-6, atol=1e-6,
                                          sample_time=None, continuous=False, method="imex", max_steps=1000,
                                          states=False, check=True, precision="f64")),
        "SimResult.plot": (result.plot, dict(channel=1, ax=None, figsize=(4, 3), fig=None)),
        "Controller": (quell.Controller, dict(design=design, sample_time=1e-3)),
        "Controller.step": (quell.Controller(design, 1e-3).step, dict(y=[0.0, 0.0], g=[0.0, 0.0])),
        "export": (quell.export, dict(source=design, sample_time=1e-3, out="out", prefix="q", precision="f64",
                                      fmu=True, fmi_version=3, compiler="none", check=True)),
        "Study": (quell.Study, dict(scenario=s, grid={}, monte_carlo={"runs": 1}, settle={}, max_steps=100,
                                    runaway={}, simulation={})),
        "Study.load": (quell.Study.load, dict(path="study.toml")),
        "Study.from_toml": (quell.Study.from_toml, dict(text="", dir=".")),
        "Study.spec": (study.spec, dict(run=0)),
        "Study.sweep": (study.sweep, dict(jobs=1, yes=False)),
        "StudyResult": (quell.StudyResult, dict(study=study, frame=swept.frame)),
        "StudyResult.rerun": (swept.rerun, dict(run=0)),
        "StudyResult.worst": (swept.worst, dict(metric="tail_max_e")),
        "StudyResult.rerun_worst": (swept.rerun_worst, dict(metric="tail_max_e")),
        "RunSpec": (quell.RunSpec, dict(json=study.spec(0).to_json(), drawn=[])),
        "sweep": (quell.sweep, dict(study=study, jobs=1, yes=False)),
        "sweep_runs": (quell.sweep_runs, dict(study=study)),
        "run_one": (quell.run_one, dict(spec=study.spec(0))),
        "tune": (quell.tune, tuning),
        "TuneResult": (quell.TuneResult, dict(json=tuned.to_json())),
    }


VALID = _valid()
# The keyword arguments of `Scenario(**design)` that are the design's.
DESIGN_KEYS = ["channel_poles", "reference_filter_poles", "disturbance_filter_poles", "mu", "beta", "observer_gain"]
CASES = [(name, param) for name, (f, kwargs) in VALID.items() for param in kwargs]


def test_every_parameter_has_a_case():
    """The cases cover each parameter of each public callable (and every public callable)."""
    for name, (f, kwargs) in VALID.items():
        params = [p for p in inspect.signature(f).parameters.values() if p.kind is not p.VAR_KEYWORD]
        missing = {p.name for p in params} - set(kwargs)
        assert not missing, (name, missing)
    callables = {n for n in quell.__all__ if callable(getattr(quell, n)) and not n.endswith("Error")}
    covered = {n for n in VALID if "." not in n} | {"paper_example"}  # paper_example takes nothing
    # Classes without a public constructor: built by the library only.
    assert callables - covered == {"Design", "SimResult"}, callables - covered


@pytest.mark.parametrize("name, param", CASES, ids=[f"{n}-{p}" for n, p in CASES])
def test_a_wrong_type_is_a_type_error_naming_the_parameter(name, param, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    f, kwargs = VALID[name]
    if param in ("ax", "fig", "figsize"):
        pytest.importorskip("matplotlib").use("Agg")
    with pytest.raises(TypeError) as info:
        f(**dict(kwargs, **{param: WRONG}))
    # "param: expected …, found an object", in the exception's own message (not only in a note, as
    # PyO3's reports of the parameters it extracts itself had it).
    text = str(info.value)
    assert param in text and "expected" in text and "found an object" in text, text
    message = text
    if name == "Scenario" and param in DESIGN_KEYS:
        assert message.startswith(param), message


def test_values_of_the_right_type_are_quell_errors():
    """A bad value (right type) is a QuellError subclass, which is also a ValueError."""
    s = quell.paper_example()
    calls = [
        lambda: quell.Plant(A, B, C, delays=[1.0, -1.0]),
        lambda: quell.design(quell.paper_example().plant, observer_gain=L, **dict(PAPER_DESIGN, beta=-1.0)),
        lambda: quell.place(A, B, [1, 2]),
        lambda: quell.simulate(s, t_end=-1.0),
        lambda: quell.simulate(s, max_steps=0),
        lambda: quell.Controller(s.design(), 0.0),
        lambda: quell.Controller(s.design(), 1e-3).step([0.0], [0.0, 0.0]),
        lambda: quell.export(s.design(), 1e-3, prefix="1 bad"),
        lambda: quell.Study(s, max_steps=0),
        lambda: quell.sweep(quell.Study(s), jobs=0),
        lambda: quell.Scenario(quell.paper_example().plant, REFERENCE, DISTURBANCE, observer_gain=L, **dict(PAPER_DESIGN, mu=[1.0])).design(),
    ]
    for i, call in enumerate(calls):
        with pytest.raises(quell.QuellError, match=r"\S") as info:  # a non-empty message
            try:
                call()
            except quell.QuellError:
                raise
            except Exception as e:
                raise AssertionError(f"call {i}: {e!r}") from e
            else:
                raise AssertionError(f"call {i} raised nothing")
        assert isinstance(info.value, ValueError)
    # The last names the keyword argument, not the file's key (design.mu).
    assert str(info.value).startswith("mu: "), info.value


def test_messages_name_the_python_argument():
    """Errors of calls with Python arguments name the argument (`sample_time`, `mu[0]`,
    `reference[0]["harmonics"][0]["frequency"]`), not the scenario file's key or a CLI flag; `.key`
    keeps the file's key for ScenarioErrors."""
    s = quell.paper_example()
    plant = s.plant

    def scenario(**kw):
        args = dict(dict(PAPER_DESIGN, observer_gain=L), **kw)
        ref = args.pop("reference", REFERENCE)
        return quell.Scenario(plant, ref, DISTURBANCE, **args)

    cases = [
        (lambda: quell.simulate(s, sample_time=0.0007), "sample_time: "),
        (lambda: quell.simulate(s, rtol=-1.0), "rtol: "),
        (lambda: quell.simulate(s, output_step=1e-3, t_end=1e-4), "output_step: "),
        (lambda: quell.Controller(s.design(), 0.0007), "sample_time: "),
        (lambda: quell.export(s.design(), 0.0007, fmu=True, compiler="none"), "sample_time: "),
        (lambda: scenario(noise={"std": [1.0]}), 'noise["std"]: '),
        (lambda: scenario(reference=[{"harmonics": [{"amplitude": 1.0, "frequency": -2.0}]}, {"bias": 2.0}]),
         'reference[0]["harmonics"][0]["frequency"]: '),
        (lambda: scenario(mu=[20.0, -1.0]).design(), "mu[1]: "),
        (lambda: scenario(channel_poles=[[-6, 2], [-4]]).design(), "channel_poles[0]"),
        (lambda: scenario(sample_time=-1.0), "sample_time: "),
    ]
    for call, start in cases:
        with pytest.raises(quell.QuellError) as info:
            call()
        text = str(info.value)
        assert text.startswith(start), (start, text)
        assert "--" not in text and not text.split(":")[0].startswith(("simulation.", "design.")), text


def test_numpy_integers_are_ints():
    # quell's own frames return numpy integers (a run's index); every int argument takes them
    # (anything with __index__), and a numpy bool or float stays a TypeError.
    ex = quell.paper_example()
    st = quell.Study(ex, grid={"design.mu[0]": [10.0, 40.0]}, simulation={"t_end": 2.0}, max_steps=np.int64(10**6))
    res = st.sweep(jobs=np.int32(1))
    worst = res.worst("tail_max_e")["run"]
    assert isinstance(worst, np.integer)
    assert res.rerun(worst).outcome["status"] == "completed"
    r = quell.simulate(ex, t_end=1.0, max_steps=np.uint16(5000))
    r.plot(channel=np.int64(2))
    choices = {k: v for k, v in ex.design().choices.items() if k != "relative_degrees"}
    assert quell.design(ex.plant, relative_degrees=np.array([2, 1]), **choices).plant.m == 2
    for bad in (np.True_, np.float64(1.0)):
        with pytest.raises(TypeError, match="max_steps: expected an int"):
            quell.simulate(ex, t_end=1.0, max_steps=bad)


def test_a_wrong_type_inside_a_signal_is_a_type_error_in_pythons_words():
    """A str amplitude or a dict where the list of harmonics goes: TypeError (a ScenarioError
    before, worded in TOML's terms: "an array of harmonics (inline tables), found a table"), with
    the argument's path and `.key`, the scenario key."""
    plant = quell.paper_example().plant
    bad_amplitude = [{"harmonics": [{"amplitude": "1", "frequency": 1.0}]}, {"bias": 2.0}]
    with pytest.raises(TypeError, match=r'^reference\[0\]\["harmonics"\]\[0\]\["amplitude"\]: expected a number, found a str$') as info:
        quell.Scenario(plant, bad_amplitude, DISTURBANCE, observer_gain=L, **PAPER_DESIGN)
    assert info.value.key == "reference.components[0].harmonics[0].amplitude"
    not_a_list = [{"harmonics": {"amplitude": 1.0, "frequency": 1.0}}, {"bias": 2.0}]
    with pytest.raises(TypeError, match=r'^reference\[0\]\["harmonics"\]: expected a list of harmonics \(dicts\), found a dict$'):
        quell.Scenario(plant, not_a_list, DISTURBANCE, observer_gain=L, **PAPER_DESIGN)
    # A value of the right type stays a ScenarioError.
    with pytest.raises(quell.ScenarioError, match=r'frequency'):
        quell.Scenario(plant, [{"harmonics": [{"amplitude": 1.0, "frequency": -1.0}]}, {"bias": 2.0}], DISTURBANCE, observer_gain=L, **PAPER_DESIGN)


def test_an_integer_beyond_a_float_is_named_as_such():
    """mu=[10**400, 1] read "found entries that are not all numbers": the entry is a number, too
    large for a float64."""
    with pytest.raises(TypeError, match=r"^mu: expected real numbers, found an integer beyond a float64's range"):
        quell.design(quell.paper_example().plant, observer_gain=L, **dict(PAPER_DESIGN, mu=[10**400, 1]))
    with pytest.raises(TypeError, match="found entries that are not all numbers"):
        quell.design(quell.paper_example().plant, observer_gain=L, **dict(PAPER_DESIGN, mu=[None, 1]))
    # Beyond int64 but within a float64's range, an int is the number it is (numpy makes an
    # object array of it): "found entries that are not all numbers" before.
    d = quell.design(quell.paper_example().plant, observer_gain=L, **dict(PAPER_DESIGN, mu=[10**30, 1]))
    assert list(d.mu) == [1e30, 1.0]
    assert quell.Plant([[10**30, 0], [0, 1]], [[1.0], [0.0]], [[1.0, 0.0]]).A[0, 0] == 1e30


def test_a_huge_int_is_named_as_such_where_one_number_or_an_int_is_expected(tmp_path):
    """u_limit=10**400 read "found an int" (an int is what a limit may be) and fmi_version=10**400
    "expected 2 or 3 (an int), found an int": both now say the integer is out of range."""
    text = quell.paper_example().to_toml()
    with pytest.raises(TypeError, match=r"^u_limit: expected real numbers, found an integer beyond a float64's range"):
        quell.auto_design(text, u_limit=10**400)
    scenario = quell.paper_example()
    with pytest.raises(quell.ExportError, match=r"^fmi_version: expected 2 or 3, found an integer of 401 digits$"):
        quell.export(scenario, 0.05, out=tmp_path, fmu=True, fmi_version=10**400)
    assert not any(tmp_path.iterdir())
