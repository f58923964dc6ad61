"""The API's names, and that its ways of saying the same thing agree."""

import pathlib
import subprocess
import sys
import warnings

import numpy as np
import pytest

import quell

from conftest import EXAMPLES

PAPER_DESIGN = dict(
    channel_poles=[[-6, -2], [-4]],
    reference_filter_poles=[[-1, -6], [-9]],
    disturbance_filter_poles=[[-1, -3], [-1, -2, -3]],
    mu=[20, 30],
    beta=1.0,
)
A = [[-3.2, -1.7, -3.0], [2.8, 1.3, 4.0], [0.3, 0.3, -0.5]]
B = [[-2.0, 1.0], [2.0, -1.0], [1.0, 0.0]]
C = [[2.0, 2.0, 0.0], [2.0, 1.0, 2.0]]
D = [[1.0, -3.0], [2.0, 1.0], [3.0, 1.0]]
Q = [[1.0, 2.0], [1.0, 0.0]]
L = [[-8.0988, 4.4574], [10.6506, -5.0619], [2.7762, -1.1783]]
REFERENCE = [{"harmonics": [{"amplitude": 3.0, "frequency": 2.0}]}, {"bias": 2.0}]
DISTURBANCE = [{"harmonics": [{"amplitude": 1.0, "frequency": 1.0}]},
               {"bias": 1.0, "harmonics": [{"amplitude": 2.0, "frequency": 2.0}]}]


def paper_from_values(**overrides):
    plant = quell.Plant(A, B, C, D, Q=Q, delays=[1.0, 3.0])
    kw = dict(PAPER_DESIGN, observer_gain=L, t_end=100.0, output_step=0.1, rtol=1e-9, atol=1e-9)
    kw.update(overrides)
    return quell.Scenario(plant, reference=REFERENCE, disturbance=DISTURBANCE, name="paper-example", **kw)


def test_scenario_from_values_is_the_paper_file():
    a, b = paper_from_values(), quell.paper_example()
    assert a.to_toml() == b.to_toml()
    assert np.array_equal(quell.simulate(a).y, quell.simulate(b).y)


def test_scenario_round_trips_through_toml():
    for path in sorted(EXAMPLES.glob("*.toml")):
        s = quell.Scenario.load(path)
        back = quell.Scenario.from_toml(s.to_toml())
        assert back.to_toml() == s.to_toml(), path
        assert back.reference == s.reference and back.simulation == s.simulation and back.noise == s.noise
    assert quell.Scenario.load(EXAMPLES / "paper.toml").to_toml() == quell.paper_example().to_toml()


def test_the_observer_starts_at_xhat0():
    """Plant(xhat0=...): the controller's initial estimate, kept by the scenario's TOML and pickling;
    a run starts its x̂ there (recorded with states=True), as the real-time Controller does."""
    import pickle

    x0 = [0.5, -0.3, 0.2]
    plant = quell.Plant(A, B, C, D, Q=Q, delays=[1.0, 3.0], x0=x0, xhat0=x0)
    assert list(plant.xhat0) == x0 and pickle.loads(pickle.dumps(plant)) == plant
    assert plant != quell.Plant(A, B, C, D, Q=Q, delays=[1.0, 3.0], x0=x0)
    s = quell.Scenario(plant, reference=REFERENCE, disturbance=DISTURBANCE, **dict(PAPER_DESIGN, observer_gain=L, t_end=1.0))
    assert "xhat0 = [0.5, -0.3, 0.2]" in s.to_toml()
    assert list(quell.Scenario.from_toml(s.to_toml()).plant.xhat0) == x0
    r = quell.simulate(s, states=True)
    np.testing.assert_array_equal(r.x_hat[0], x0)
    c = quell.Controller(s.design(), 0.01)
    np.testing.assert_array_equal(c.x_hat(), x0)
    with pytest.raises(quell.ScenarioError, match=r"^xhat0: expected 3 entries"):
        quell.Plant(A, B, C, D, Q=Q, delays=[1.0, 3.0], xhat0=[1.0])


def test_truth_differs_from_the_design_model():
    """[truth]: the simulated plant; the design (and so scenario.design()) keeps [plant]."""
    true_plant = quell.Plant(A, B, C, D, Q=Q, delays=[1.0, 3.2])
    s = paper_from_values(truth=true_plant, t_end=20.0)
    assert s.truth is not None and list(s.truth.delays) == [1.0, 3.2]
    assert list(s.plant.delays) == [1.0, 3.0]
    back = quell.Scenario.from_toml(s.to_toml())
    assert list(back.truth.delays) == [1.0, 3.2]
    nominal = quell.simulate(paper_from_values(t_end=20.0))
    mismatched = quell.simulate(s)
    np.testing.assert_array_equal(s.design().K, quell.paper_example().design().K)
    assert not np.array_equal(nominal.y, mismatched.y)
    assert quell.paper_example().truth is None


def test_truth_as_a_dict_takes_the_rest_from_the_plant_and_a_plant_must_match_it():
    """truth={"A": ...} is `[truth] A = ...`: delays, D, Q and x0 from [plant], as the TOML file
    does. A Plant is the whole true plant: one built without D (k = 0) would have taken the
    design's D silently, and its delays (default 0) removed the loop's delays; it is refused by
    name when its D or its unit of time differs from the plant's."""
    A_true = (1.01 * np.array(A)).tolist()
    s = paper_from_values(truth={"A": A_true}, t_end=20.0)
    text = quell.paper_example().to_toml().replace("t_end = 100.0", "t_end = 20.0") + f"\n[truth]\nA = {A_true}\n"
    from_file = quell.Scenario.from_toml(text)
    assert list(s.truth.delays) == [1.0, 3.0]
    np.testing.assert_array_equal(s.truth.D, D)
    np.testing.assert_array_equal(quell.simulate(s).y, quell.simulate(from_file).y)
    with pytest.raises(quell.ScenarioError, match=r"truth: the Plant has k = 0 disturbance inputs .* where plant has k = 2"):
        paper_from_values(truth=quell.Plant(A_true, B, C))
    with pytest.raises(quell.ScenarioError, match="truth: the Plant's time_unit is min where plant's is s"):
        paper_from_values(truth=quell.Plant(A_true, B, C, D, Q=Q, delays=[1.0, 3.0], time_unit="min"))
    # Another size is named as such (it had been reported as k = 0 against k = 2).
    with pytest.raises(quell.ScenarioError, match=r"truth: the Plant has n = 2 states and m = 2 inputs where plant has n = 3 and m = 2"):
        paper_from_values(truth=quell.Plant(np.eye(2), np.eye(2), np.eye(2)))
    # One actuator limit, given once: truth's and actuator's together had the actuator's win.
    with pytest.raises(quell.ScenarioError, match=r'actuator\["u_max"\] and truth\["u_max"\]: both given'):
        paper_from_values(truth={"u_max": [12.0, 18.0]}, actuator={"u_max": [5.0, 5.0]})


def test_scenario_accessors():
    s = quell.paper_example()
    assert s.name == "paper-example"
    assert s.plant.n == 3 and s.plant.m == 2 and s.plant.k == 2
    np.testing.assert_array_equal(s.plant.A, A)
    np.testing.assert_array_equal(s.plant.delays, [1.0, 3.0])
    assert s.reference[1] == {"bias": 2.0, "harmonics": []}
    assert s.simulation == {"t_end": 100.0, "output_step": 0.1, "rtol": 1e-9, "atol": 1e-9, "sample_time": None,
                            "method": "auto", "precision": "f64"}
    assert s.noise is None
    # scenario.design() is the Design of quell.design on the same plant and choices.
    d1 = s.design()
    d2 = quell.design(s.plant, observer_gain=L, **PAPER_DESIGN)
    for name in ["K", "F", "L", "N", "A_f", "B_f", "G_g", "L_g", "G_w", "L_w"]:
        np.testing.assert_array_equal(getattr(d1, name), getattr(d2, name), err_msg=name)
    assert d1.sigma == d2.sigma == [2, 1]


def test_complex_poles_in_scenarios():
    a = paper_from_values(channel_poles=[[-1 + 2j, -1 - 2j], [-4]])
    b = paper_from_values(channel_poles=[[[-1, 2]], [-4]])
    assert a.to_toml() == b.to_toml()
    with pytest.raises(quell.DesignError, match="no complex-conjugate partner"):
        paper_from_values(channel_poles=[[-1 + 2j, -3], [-4]])


def test_simulate_shapes_and_overrides(tmp_path):
    s = quell.paper_example()
    r = quell.simulate(s, t_end=10.0)
    n = len(r)
    assert n == 101 and r.t.shape == (n,)
    for a in (r.y, r.g, r.e, r.u):
        assert a.shape == (n, 2)
    assert r.eta.shape == (n, 2, 8)
    np.testing.assert_array_equal(r.e, r.y - r.g)
    with pytest.raises(ValueError):
        r.y[0, 0] = 1.0  # results are read-only
    # ... and cannot be made writable: their flat base had stayed writable, so flags.writeable =
    # True went through and a write changed the stored result, its pickles and frames.
    for a in (r.t, r.y, r.u_f, r.eta):
        with pytest.raises(ValueError):
            a.flags.writeable = True
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # 1 ms is fine for the paper (T_s·ρ = 0.009)
        sampled = quell.simulate(s, t_end=10.0, sample_time=1e-3)
    assert sampled.stats == {"loop": "sampled", "controller_steps": 10001, "sample_time": 1e-3, "precision": "f64"}
    # A sample time coarse for the design (the paper's fastest rate: its filter pole −9) is a
    # UserWarning naming the argument, with the bound.
    with pytest.warns(UserWarning, match=r"^sample_time: T_s = 0.05 s is 0.45× the loop.*choose T_s ≤ 0.0222 s"):
        quell.simulate(s, t_end=2.0, sample_time=0.05)
    # ... and so are the controller and its export at that sample time.
    with pytest.warns(UserWarning, match=r"^sample_time: T_s = 0.05 s is 0.45× the"):
        quell.Controller(s.design(), 0.05)
    with pytest.warns(UserWarning, match=r"^sample_time: T_s = 0.05 s is 0.45× the"):
        quell.export(s, 0.05, out=str(tmp_path))
    # A controller beyond 1 MiB of RAM (the delay lines: 3 s at 10 µs) is a UserWarning too.
    with pytest.warns(UserWarning, match=r"^the controller needs [0-9.]+ MiB of RAM"):
        quell.export(s, 1e-5, out=str(tmp_path))
    with pytest.raises(quell.ScenarioError, match=r"^output_step: expected an output step ≤ t_end = 0.05") as e:
        quell.simulate(s, t_end=0.05)  # the argument's name, not the file's key
    assert e.value.key == "simulation.output_step"


def test_sample_time_errors_carry_the_scenario_key():
    """A refused sample_time= has .key "simulation.sample_time" whether the scenario's check
    refuses it (simulate at 1e-300: too many controller steps; -1) or the controller's (0.7: the
    delays 1 s and 3 s are not whole numbers of samples; Controller and export too), and the
    message names the argument."""
    s = quell.paper_example()
    calls = [lambda T=T: quell.simulate(s, t_end=2.0, sample_time=T) for T in (0.7, 1e-300, -1.0)] + [
        lambda: quell.Controller(s.design(), 0.7),
        lambda: quell.export(s.design(), 0.7),
    ]
    for i, call in enumerate(calls):
        with pytest.raises(quell.ScenarioError, match=r"^sample_time: ") as e:
            call()
        assert e.value.key == "simulation.sample_time", (i, str(e.value))


def test_plant_from_python_control():
    control = pytest.importorskip("control")
    sys_ = control.ss(A, B, C, np.zeros((2, 2)))
    p = quell.Plant(sys_, D=D, Q=Q, delays=[1.0, 3.0])
    np.testing.assert_array_equal(p.A, A)
    np.testing.assert_array_equal(p.D, D)
    with pytest.raises(quell.ScenarioError, match="feedthrough"):
        quell.Plant(control.ss(A, B, C, np.ones((2, 2))), delays=[1.0, 3.0])
    with pytest.raises(quell.ScenarioError, match="continuous-time"):
        quell.Plant(control.ss(A, B, C, np.zeros((2, 2)), 0.1), delays=[1.0, 3.0])
    with pytest.raises(quell.ScenarioError, match="keywords"):
        quell.Plant(sys_, B)


def test_plant_defaults():
    p = quell.Plant(A, B, C)
    assert p.k == 0 and p.D.shape == (3, 0) and p.Q.shape == (2, 0)
    np.testing.assert_array_equal(p.delays, [0.0, 0.0])
    np.testing.assert_array_equal(p.x0, [0.0, 0.0, 0.0])
    p = quell.Plant(A, B, C, D, delays=[1, 3], x0=[1, 2, 3])
    np.testing.assert_array_equal(p.Q, np.zeros((2, 2)))  # Q defaults to 0


def test_a_reference_too_fast_for_a_line_is_drawn_under_y_as_the_cli_draws_it():
    """Over 5 s the paper's 2 rad/s reference is a line, dashed over y; over 2000 s (636 periods on
    the panel) its path runs hundreds of panel widths, and it is drawn first, solid and faint, so
    that y shows over it (the CLI's figure, docs/running.md)."""
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    for t_end, band in [(5.0, False), (2000.0, True)]:
        r = quell.simulate(quell.paper_example(), t_end=t_end)
        fig = r.plot(channel=1)
        lines = {line.get_label(): (k, line) for k, line in enumerate(fig.axes[0].get_lines())}
        (g_at, g), (y_at, _) = lines["g1 (reference)"], lines["y1"]
        assert (g_at < y_at, g.get_linestyle(), g.get_alpha()) == ((True, "-", 0.35) if band else (False, "--", None))
        matplotlib.pyplot.close(fig)


def test_to_pandas_and_plot():
    pytest.importorskip("pandas")
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    r = quell.simulate(quell.paper_example(), t_end=5.0)
    df = r.to_pandas()
    assert list(df.columns[:9]) == ["t", "y1", "y2", "g1", "g2", "e1", "e2", "u1", "u2"]
    assert df.columns[-1] == "eta2_8" and len(df) == len(r)
    fig = r.plot(channel=2)
    assert len(fig.axes) == 6
    # The last panel: max |e_2(s)| over s >= t, recomputed here, on a log axis.
    (tail,) = fig.axes[5].lines
    e = np.abs(r.e[:, 1])
    np.testing.assert_array_equal(tail.get_ydata(), [e[k:].max() for k in range(len(e))])
    assert fig.axes[5].get_yscale() == "log"
    # Without g and ω, from x0 = [1, 0, 0], the error decays far below 14 decades of its peak (to
    # 1e-90 by 300 s): the curve leaves the axis and the title says from when (the CLI's panel
    # likewise); from x0 = 0 the error is zero throughout, and the title says so.
    text = (EXAMPLES / "paper.toml").read_text()
    for old in ("amplitude = 3.0", "bias = 2.0", "amplitude = 1.0", "bias = 1.0", "amplitude = 2.0"):
        text = text.replace(old, old.split(" = ")[0] + " = 0.0")
    decaying = quell.Scenario.from_toml(text.replace("x0 = [0.0, 0.0, 0.0]", "x0 = [1.0, 0.0, 0.0]"))
    fig = quell.simulate(decaying, t_end=300.0, output_step=1.0).plot()
    assert "; below 1e-14 of its peak from t = " in fig.axes[5].get_title(), fig.axes[5].get_title()
    assert fig.axes[5].get_ylim()[0] > 0
    zero = quell.simulate(quell.Scenario.from_toml(text), t_end=2.0)
    assert not np.any(zero.e) and zero.plot().axes[5].get_title().endswith(": e ≡ 0")
    for bad in (3, 0, -1):
        with pytest.raises(quell.ScenarioError, match=rf"^channel: expected a channel number from 1 to 2, found {bad}$"):
            r.plot(channel=bad)
    for size in ((-1, 2), (4, 0), (float("nan"), 3)):
        with pytest.raises(quell.ScenarioError, match=r"^figsize: expected \(width, height\) in inches, both finite and > 0"):
            r.plot(figsize=size)
    # (300, 300) had taken 3.6 GB to draw (hostile review).
    with pytest.raises(quell.ScenarioError, match=r"^figsize: expected \(width, height\) of at most 100 inches each, found \(300, 300\)"):
        r.plot(figsize=(300, 300))
    # The titles name the output and the input where the plant does (Wood–Berry's column).
    wood_berry = quell.Scenario.load(pathlib.Path(__file__).parents[2] / "quell" / "tests" / "data" / "wood-berry.toml")
    fig = quell.simulate(wood_berry, t_end=5.0).plot(channel=1)
    assert fig.axes[0].get_title() == "Channel 1 (x_D): output and reference"
    assert fig.axes[3].get_title() == "Input 1 (reflux): plant input u_f (5), what the actuator delivers"


def test_optional_dependencies_are_imported_only_when_used():
    code = "import quell, sys; r = quell.simulate(quell.paper_example(), t_end=1.0); print(sorted(m for m in ('pandas', 'matplotlib', 'control', 'scipy') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout
    assert out.strip() == "[]"


def test_stub_matches_the_module():
    """mypy's stubtest: the .pyi stub declares what the module has, with the same signatures."""
    config = pathlib.Path(__file__).with_name("mypy.ini")
    run = subprocess.run([sys.executable, "-m", "mypy.stubtest", "quell", "--mypy-config-file", str(config)],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr


def test_a_sample_time_given_to_load_reads_the_file_as_its_sampled_scenario(tmp_path):
    """White noise (no bandwidth) is valid only in a sampled-data scenario. `quell run
    --sample-time` made such a file without the key one; Python could not load it at all
    (`noise.bandwidth: missing`), so could not simulate it sampled. `sample_time=` of `load` and
    `from_toml` is the flag: the same samples as the file that sets the key."""
    keyed = (EXAMPLES / "paper-noise.toml").read_text().replace("t_end = 100.0", "t_end = 2.0")
    assert "\nsample_time = 0.001 " in keyed
    without = "\n".join(line for line in keyed.splitlines() if not line.startswith("sample_time"))
    path = tmp_path / "white.toml"
    path.write_text(without)
    # The message names the argument that makes it valid, not only the file's key.
    remedy = r"or pass sample_time=… \(simulation.sample_time in a file\) for white noise"
    with pytest.raises(quell.ScenarioError, match="noise.bandwidth: missing.*" + remedy):
        quell.Scenario.load(path)
    with pytest.raises(quell.ScenarioError, match=r'^noise\["bandwidth"\]: missing.*' + remedy):
        paper_from_values(noise={"std": [0.01, 0.01]})
    assert paper_from_values(noise={"std": [0.01, 0.01]}, sample_time=0.001).noise["bandwidth"] is None
    loaded = quell.Scenario.load(path, sample_time=0.001)
    parsed = quell.Scenario.from_toml(without, sample_time=0.001)
    reference = quell.Scenario.from_toml(keyed)
    assert loaded.simulation["sample_time"] == parsed.simulation["sample_time"] == 0.001
    a, b = quell.simulate(loaded), quell.simulate(reference)
    assert np.array_equal(a.y, b.y) and np.array_equal(a.u_f, b.u_f) and np.abs(a.y).max() > 0
    # A sample time the delays refuse is named as the argument at once (as `quell run
    # --sample-time` does); it had passed here and been refused at simulate as
    # simulation.sample_time. The paper's delays, 1 and 3 s, are 3.33 and 10 samples of 0.3 s.
    with pytest.raises(quell.ScenarioError, match=r"^sample_time=0.3: channel 1's delay τ = 1 s is not a whole number of samples") as caught:
        quell.Scenario.load(EXAMPLES / "paper.toml", sample_time=0.3)
    assert caught.value.key == "sample_time"
    # 0.25 s fits the delays; the file's output step (0.1 s) does not, and simulate may set another.
    quarter = quell.Scenario.load(EXAMPLES / "paper.toml", sample_time=0.25)
    assert quarter.simulation["sample_time"] == 0.25
    with pytest.warns(UserWarning, match="T_s = 0.25 s is 2.25× the loop's fastest time constant"):
        assert quell.simulate(quarter, t_end=2.0, output_step=0.5).t[-1] == 2.0
    # A bad sample time is the scenario's check's, naming the argument (it had named the file's key).
    for bad in (-1.0, 0.0, float("nan"), float("inf")):
        with pytest.raises(quell.ScenarioError, match=r"^sample_time=(-1|0|NaN|inf): ") as caught:
            quell.Scenario.from_toml(without, sample_time=bad)
        assert caught.value.key == "sample_time"

    # A bad sample time in the file is the file's, even where the argument overrides it (it had
    # been dropped silently: `quell design` refused the file that `load(sample_time=…)` ran).
    for bad in ("true", '"abc"', "nan", "-1.0", "0", "[1, 2]"):
        text = keyed.replace("\nsample_time = 0.001 ", f"\nsample_time = {bad} ")
        with pytest.raises(quell.ScenarioError, match=r"^simulation.sample_time: expected ") as caught:
            quell.Scenario.from_toml(text, sample_time=0.001)
        assert caught.value.key == "simulation.sample_time"

def test_an_export_into_a_directory_another_process_is_writing_is_refused(tmp_path):
    # quell export (CLI or Python) locks its output directory while it writes: two exports into one
    # directory had left a header of one beside the other's source.
    import fcntl
    import os
    fd = os.open(tmp_path, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        with pytest.raises(quell.ExportError, match=r"^out: another command is writing in .*; wait for it to finish"):
            quell.export(quell.paper_example(), 1e-3, out=str(tmp_path))
        assert list(tmp_path.iterdir()) == []
    finally:
        os.close(fd)
    # Released, the same export writes there.
    written = quell.export(quell.paper_example(), 1e-3, out=str(tmp_path))
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(pathlib.Path(w).name for w in written)
    assert len(written) == 2


def test_a_run_that_ends_before_its_second_row_is_drawn_as_points():
    """A true plant starting at x1 = 1e150 diverges at t = 1e-6, before the second row: each curve
    has one point, which a line does not draw (the panels had stayed empty); as the CLI's figure,
    each is a dot."""
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    text = (EXAMPLES / "paper.toml").read_text() + "\n[truth]\nx0 = [1e150, 0.0, 0.0]\n"
    with pytest.raises(quell.SimulationError, match="diverged at t = 1e-6 s") as e:
        quell.simulate(quell.Scenario.from_toml(text))
    r = e.value.result
    assert len(r.t) == 1, len(r.t)
    fig = r.plot(channel=1)
    for a in fig.axes:
        drawn = [line for line in a.get_lines() if len(line.get_xdata()) == 1]
        assert drawn and all(line.get_marker() == "o" for line in drawn), a.get_title()
    matplotlib.pyplot.close(fig)


def test_a_plot_of_many_parameters_names_their_range_in_the_title():
    """Beyond 14 entries of η̂_i the legend would hide the traces (q = 33 covered a third of them) and
    the palette repeats: as the CLI's figure, no legend, and the title names the range."""
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    wind = quell.Scenario.load(pathlib.Path(__file__).parents[2] / "quell" / "tests" / "data" / "wind-ipc-12h.toml")
    fig = quell.simulate(wind, t_end=0.2).plot(channel=1)
    eta = fig.axes[4]
    assert len(eta.lines) == 75 and eta.get_legend() is None
    assert eta.get_title().endswith(": adjustable parameters (33), η1_1 … η1_75 from dark blue to yellow"), eta.get_title()
    # The ramp the title names: every trace its own colour, in order.
    colours = [tuple(line.get_color()) for line in eta.lines]
    assert len(set(colours)) == 75 and colours[0] == matplotlib.colormaps["viridis"](0.0)
    matplotlib.pyplot.close(fig)


def test_up_to_fourteen_parameters_have_distinct_colours():
    """q = 11 … 14 had repeated matplotlib's ten colours (η_1 and η_11 both blue; helper tryout)."""
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    from quell._frames import eta_colour

    for q in (8, 12, 14):
        colours = [matplotlib.colors.to_rgba(eta_colour(j, q)) for j in range(q)]
        assert len(set(colours)) == q, q


def test_a_stopped_runs_log_panel_shows_the_growth():
    """A run that diverged plots |e(t)| on its log panel (the largest error from t on is its last
    spike's everywhere), as the CLI's figure; its values are |e| itself."""
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    text = (EXAMPLES / "paper.toml").read_text().replace("output_step = 0.1 ", "output_step = 0.5 ")
    with pytest.warns(UserWarning, match=r"^sample_time: T_s = 0.5 s is 4.50× the loop's fastest time constant"):
        r = quell.simulate(quell.Scenario.from_toml(text), sample_time=0.5, check=False)
    assert r.outcome["status"] == "diverged"
    fig = r.plot(channel=1)
    assert fig.axes[0].get_title().startswith("Channel 1: output and reference, sampled at T_s = 0.5 s (diverged at t = ")
    panel = fig.axes[5]
    assert panel.get_title() == "Channel 1: tracking error |e(t)|, log scale (the run stopped early: its growth)"
    (line,) = panel.lines
    e = np.abs(r.e[:, 0])
    np.testing.assert_array_equal(line.get_ydata(), e[e > 0])
    matplotlib.pyplot.close("all")


def test_a_default_output_step_follows_the_overrides():
    # A scenario without output_step: its default (t_end/1000, twenty rows a period of the fastest
    # harmonic, a whole number of samples) follows simulate()'s t_end and sample_time, as the
    # CLI's --t-end does (it had kept the file's 0.1 s: 6 rows over 0.5 s, and refused
    # sample_time=0.04 for an output step the user never set).
    text = (EXAMPLES / "paper.toml").read_text().replace("output_step = 0.1     # rows of signals.csv at t = k * output_step", "")
    s = quell.Scenario.from_toml(text)
    assert len(quell.simulate(s, t_end=0.5).t) == 1001
    sampled = quell.simulate(s, t_end=2.0, sample_time=0.04)
    assert len(sampled.t) == 51 and abs(sampled.t[1] - 0.04) < 1e-15
