"""Python-native behaviour: pickling (the standard library's pickle is the independent side: the
object must come back equal, and equal to one built from the same values), equality, and reprs in
Python's syntax."""

import pickle

import numpy as np

import quell
from conftest import EXAMPLES


def test_plants_pickle_and_compare():
    with_disturbance = quell.paper_example().plant
    without = quell.Plant([[0.0, 1.0], [2.0, -1.0]], [[0.0], [1.0]], [[1.0, 0.0]], delays=[0.25], x0=[0.1, 0.0])
    for p in (with_disturbance, without):
        back = pickle.loads(pickle.dumps(p))
        assert back == p and back is not p
        for name in ("A", "B", "C", "D", "Q", "delays", "x0"):
            np.testing.assert_array_equal(getattr(back, name), getattr(p, name))
    assert without != with_disturbance
    assert without != quell.Plant([[0.0, 1.0], [2.0, -1.0]], [[0.0], [1.0]], [[1.0, 0.0]], delays=[0.5])
    assert without != "a plant"


def test_scenarios_pickle_and_compare():
    for s in (quell.paper_example(), quell.Scenario.load(EXAMPLES / "three-channel.toml")):
        back = pickle.loads(pickle.dumps(s))
        assert back == s
        np.testing.assert_array_equal(back.design().K, s.design().K)
    assert quell.paper_example() != quell.Scenario.load(EXAMPLES / "three-channel.toml")


def test_a_pickle_beyond_a_files_16_mib_loads():
    """A file may hold 16 MiB of TOML; a pickle's text is the package's own and is not held to it
    (a scenario or study that large, a 1,000-state plant's, had pickled but not loaded). A 17 MiB
    comment stands in for the size: the same text read as a file's is refused."""
    import pytest

    big = "# " + "x" * (17 << 20) + "\n"
    s = quell.paper_example()
    assert quell.Scenario._restore(s.to_toml() + big, False) == s
    with pytest.raises(quell.ScenarioError, match="16 MiB"):
        quell.Scenario.from_toml(s.to_toml() + big)
    study = quell.Study(s, grid={"design.beta": [1.0, 2.0]})
    assert quell.Study._restore(study.to_toml() + big) == study
    with pytest.raises(quell.ScenarioError, match="16 MiB"):
        quell.Study.from_toml(study.to_toml() + big)
    assert pickle.loads(pickle.dumps(study)) == study
    with pytest.raises(quell.ScenarioError, match="^a pickled quell object whose text is not TOML"):
        quell.Scenario._restore("[[[", False)


def test_reprs_are_python():
    s = quell.paper_example()
    r = quell.simulate(s, t_end=0.2)
    texts = [repr(x) for x in (s, s.plant, s.design(), r, quell.Controller(s.design(), 1e-3))]
    assert not any("Some(" in t or "None)" in t and "=None" not in t for t in texts), texts
    assert repr(s).startswith("Scenario(name='paper-example',") and "sample_time=None" in repr(s)
    assert repr(r).endswith("outcome={'status': 'completed'})")


def test_plot_takes_axes_and_figsize():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import pytest

    r = quell.simulate(quell.paper_example(), t_end=1.0)
    fig = r.plot(channel=2, figsize=(4, 5))
    assert tuple(fig.get_size_inches()) == (4.0, 5.0) and len(fig.axes) == 6
    own, one = plt.subplots()
    assert r.plot(channel=1, ax=one) is own
    (y1,) = [line for line in one.lines if line.get_label() == "y1"]
    np.testing.assert_array_equal(y1.get_ydata(), r.y[:, 0])  # y1 drawn on the given axes
    own4, four = plt.subplots(2, 2)
    assert r.plot(ax=four) is own4 and four[1, 1].get_title().startswith("Channel 1: adjustable")
    # On four axes u_f shares the third on a second y axis (its own scale), drawn from r.u_f.
    twin = [a for a in own4.axes if a not in four.flat]
    assert len(twin) == 1 and twin[0].get_ylabel() == "u_f"
    np.testing.assert_array_equal(twin[0].lines[0].get_ydata(), r.u_f[:, 0])
    with pytest.raises(TypeError, match="channel: expected an int"):
        r.plot(channel="2")
    with pytest.raises(TypeError, match="ax: expected one matplotlib Axes, four, five or six"):
        r.plot(ax=[one, one])
    with pytest.raises(TypeError, match="fig and ax: expected one of them or neither"):
        r.plot(fig=own, ax=one)
    with pytest.raises(quell.ScenarioError, match="fig: expected an empty Figure .* found one with 1 Axes"):
        r.plot(fig=own)  # drawn over its Axes before
    plt.close("all")


def test_a_sampled_runs_held_commands_are_drawn_as_staircases():
    """u and u_f hold between samples when the sample time spans a row (T_s = 0.1 = the row
    spacing, the paper's delays 1 s and 3 s being whole numbers of samples); at T_s = 1 ms a row
    is a point sample of a finer staircase, and the continuous loop's u is not held."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import pytest

    s = quell.paper_example()
    with pytest.warns(UserWarning, match="sample_time: T_s = 0.1 s"):  # coarse for the design, and said so
        coarse = quell.simulate(s, t_end=1.0, sample_time=0.1)
    fine, continuous = (quell.simulate(s, t_end=1.0, sample_time=T) for T in (1e-3, None))
    assert coarse.commands_held and not fine.commands_held and not continuous.commands_held
    for r, style in ((coarse, "steps-post"), (continuous, "default")):
        fig = r.plot(channel=2)
        u_line, uf_line = fig.axes[2].lines[0], fig.axes[3].lines[0]
        assert u_line.get_drawstyle() == uf_line.get_drawstyle() == style
        np.testing.assert_array_equal(uf_line.get_ydata(), r.u_f[:, 1])
    plt.close("all")


def _simulate_in_worker(scenario):
    """Runs in another process: the scenario and the result both cross the process boundary."""
    return quell.simulate(scenario, t_end=2.0)


def test_designs_pickle_and_compare():
    import warnings

    from test_api import PAPER_DESIGN, paper_from_values

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the three-channel example's gains are fragile by design
        cases = [
            quell.paper_example().design(),
            quell.Scenario.load(EXAMPLES / "three-channel.toml").design(),
            quell.design(quell.paper_example().plant, observer_poles=[-5, -6 + 1j, -6 - 1j], relative_degrees=[2, 1], **PAPER_DESIGN),
        ]
    for d in cases:
        back = pickle.loads(pickle.dumps(d))
        assert back == d and back is not d
        # The gains are designed again from the plant and the choices: the same, entry for entry.
        for name in ("K", "F", "L", "N", "A_f", "B_f", "G_g", "L_g", "G_w", "L_w", "B_star"):
            np.testing.assert_array_equal(getattr(back, name), getattr(d, name), err_msg=name)
        assert back.sigma == d.sigma and back.mu == d.mu and back.beta == d.beta
    assert cases[0] != cases[2] and cases[0] != "a design"
    assert cases[2].choices["observer_poles"] == [-5.0, -6 + 1j, -6 - 1j]
    assert paper_from_values(mu=[20.0, 31.0]).design() != cases[0]


def test_results_pickle_and_compare():
    s = quell.paper_example()
    continuous = quell.simulate(s, t_end=3.0, states=True)
    sampled = quell.simulate(s, t_end=1.0, sample_time=1e-3)
    from test_budget import diverging

    diverged = quell.simulate(diverging(), max_steps=2000, check=False)
    assert diverged.outcome["status"] != "completed"
    for r in (continuous, sampled, diverged):
        back = pickle.loads(pickle.dumps(r))
        assert back == r and back is not r
        for name in ("t", "y", "g", "e", "u", "u_f", "eta", "x", "x_hat"):
            a, b = getattr(r, name), getattr(back, name)
            assert (a is None and b is None) or (np.array_equal(a, b) and not b.flags.writeable), name
        assert back.outcome == r.outcome and back.stats == r.stats
        assert back.summary() == r.summary() and back.diagnostics() == r.diagnostics()
    assert continuous != quell.simulate(s, t_end=3.0)  # without the states
    assert continuous != "a result"


def test_objects_cross_to_worker_processes():
    """multiprocessing (spawn: a fresh interpreter unpickles them) sends scenarios and gets
    results back, equal to the same runs here."""
    import multiprocessing

    scenarios = [quell.paper_example(), quell.Scenario.load(EXAMPLES / "three-channel.toml")]
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        results = pool.map(_simulate_in_worker, scenarios)
    assert results == [quell.simulate(s, t_end=2.0) for s in scenarios]


def _steps(c, ks):
    """u_f of controller c over samples ks, with sinusoidal y and g (the same for every controller)."""
    m = c.command().shape[0]
    return np.array([c.step(np.sin(0.01 * k * (1.0 + np.arange(m))), 1.0 + np.cos(0.003 * k + np.arange(m))) for k in ks])


def test_a_controller_pickles_and_copies_and_the_copy_continues_bit_for_bit():
    """The original stepped on is the independent side: after a pickle, copy.copy or copy.deepcopy
    in the middle of a run (delay lines part-way round, η̂ adapting) the copy's u_f equals the
    original's exactly (np.array_equal, no tolerance), for longer than the longest delay, on the
    paper's design and a three-channel one."""
    import copy

    for scenario, T in ((quell.paper_example(), 1e-2), (quell.Scenario.load(EXAMPLES / "three-channel.toml"), 5e-3)):
        design = scenario.design()
        c = quell.Controller(design, T)
        longest = round(max(scenario.plant.delays) / T)
        _steps(c, range(longest + 37))
        assert np.any(c.eta() != 0.0)
        copies = [pickle.loads(pickle.dumps(c, protocol=p)) for p in (2, pickle.HIGHEST_PROTOCOL)]
        copies += [copy.copy(c), copy.deepcopy(c)]
        for other in copies:
            assert other == c and other is not c
            assert np.array_equal(other.command(), c.command()) and np.array_equal(other.x_hat(), c.x_hat())
        ks = range(longest + 37, 3 * longest + 50)
        want = _steps(c, ks)
        for other in copies:
            assert np.array_equal(_steps(other, ks), want)
            assert np.array_equal(other.eta(), c.eta())
            assert other == c


def test_controllers_compare_by_design_sample_time_and_state():
    d = quell.paper_example().design()
    a, b = quell.Controller(d, 1e-2), quell.Controller(d, 1e-2)
    assert a == a and a == b and a != "a controller"
    assert a != quell.Controller(d, 5e-3)  # another sample time
    other = quell.design(d.plant, **{**d.choices, "beta": 2.0})
    assert a != quell.Controller(other, 1e-2)  # another design, same state (zero) and length
    a.step([0.5, 0.0], [1.0, 2.0])
    assert a != b  # another state
    b.step([0.5, 0.0], [1.0, 2.0])
    assert a == b
    a.reset()
    assert a == quell.Controller(d, 1e-2)


def test_a_bad_state_is_refused_naming_the_entry():
    """The messages of docs/errors.md, through Python; a refused state leaves the controller as
    it was."""
    import pytest

    c = quell.Controller(quell.paper_example().design(), 1e-2)
    _steps(c, range(150))
    state = c.__getstate__()
    with pytest.raises(quell.ControllerError, match=r"^Controller.__setstate__: the state needs 3820 numbers for this design and sample time \(the layout of Controller.__getstate__\(\)\), found 10"):
        c.__setstate__(state[:10])
    bad = state.copy()
    bad[41] = np.nan
    with pytest.raises(quell.ControllerError, match=r"^Controller.__setstate__: state\[41\] \(channel 1's H filter Ω_i \(33\)\) = NaN: expected a finite number"):
        c.__setstate__(bad)
    with pytest.raises(TypeError, match="state: expected an array of real numbers, found a str"):
        c.__setstate__("state")
    # bytes iterate as ints: bytes(3820) had been taken as an all-zero state.
    for raw in (bytes(len(state)), bytearray(len(state))):
        with pytest.raises(TypeError, match=f"state: expected an array of real numbers, found a {type(raw).__name__}"):
            c.__setstate__(raw)
    assert np.array_equal(c.__getstate__(), state)
    # The methods are named as Python calls them, not as the Rust library's paths.
    with pytest.raises(quell.ControllerError, match=r"^Controller.step: y\[0\] = 1e200 is beyond ±1e100"):
        c.step([1e200, 0.0], [1.0, 2.0])
    assert np.array_equal(c.__getstate__(), state)
    # A checkpoint of another sample time does not fit.
    with pytest.raises(quell.ControllerError, match="the state needs"):
        quell.Controller(quell.paper_example().design(), 5e-3).__setstate__(state)


def test_a_diverged_runs_summary_has_no_tail():
    """The paper's loop sampled at T_s = 0.2 s diverges at t ≈ 36 s of 100: the last 10 % of the
    horizon was never reached, so the tail figures are None (summary.json's null), not the error
    over the last tenth of what ran (2.8e8 before); the peaks of what ran are kept."""
    import pytest

    with pytest.warns(UserWarning, match="sample_time"):
        r = quell.simulate(quell.paper_example(), sample_time=0.2, output_step=0.2, t_end=100.0, check=False)
    assert r.outcome["status"] == "diverged" and r.outcome["t"] < 90
    for c in r.summary():
        assert c["tail_max_e"] is None and c["tail_rms_e"] is None and c["settle_t"] is None, c
        assert c["settle_note"].startswith("no tail: the run stopped at t = ") and c["max_uf"] > 0
    # Its figure says where and why its curves end.
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    title = r.plot(channel=1).axes[0].get_title()
    assert title.endswith(f"(diverged at t = {r.outcome['t']:.7g} s: {r.outcome['signal']})"), title
    plt.close("all")
