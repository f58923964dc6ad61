"""The python-control round trip, checked with python-control's own functions (poles, frequency
response, forced_response, minreal): a design's decoupled plant and observer as labelled
StateSpace objects, a TransferFunction as a plant, and a result as TimeResponseData."""

import control
import numpy as np
import pytest

import quell
from conftest import EXAMPLES

# Decoupling and the observer's unbiasedness are exact in exact arithmetic; K, F and L come from
# O(10) operations on matrices with entries of O(10), so a relative 1e-9 leaves rounding (~1e-13)
# several orders of room and still fails on any wrong gain, sign or index.
TOL = 1e-9
POINTS = [0.3j, 1.0j, 2.0 + 1.0j, -0.5 + 4.0j]


def designs():
    return [
        ("paper", quell.paper_example().design()),
        ("three-channel", quell.Scenario.load(EXAMPLES / "three-channel.toml").design()),
    ]


@pytest.mark.parametrize("name, d", designs())
def test_decoupled_system_is_diagonal_with_the_channel_transfer_functions(name, d):
    sys = d.decoupled_system()
    m, n = d.plant.m, d.plant.n
    assert isinstance(sys, control.StateSpace)
    assert sys.input_labels == [f"u_d[{i + 1}]" for i in range(m)]
    assert sys.output_labels == [f"y[{i + 1}]" for i in range(m)]
    assert sys.state_labels == [f"x[{j + 1}]" for j in range(n)]
    np.testing.assert_allclose(np.sort_complex(sys.poles()), np.sort_complex(d.decoupled_eigenvalues), rtol=TOL, atol=TOL)
    for s in POINTS:
        H = sys(s)  # python-control's transfer matrix at s
        scale = np.max(np.abs(H))
        for i, ch in enumerate(d.channels):
            G_ii = ch["q0"] / np.prod(s - np.asarray(ch["poles"]))
            assert abs(H[i, i] - G_ii) <= TOL * scale, (name, s, i)
            off = np.delete(H[i], i)
            assert np.all(np.abs(off) <= TOL * scale), (name, s, i, off)


def test_forced_response_of_a_channel_is_its_transfer_function():
    """control.forced_response of the decoupled plant with a step on u_d[1] only: y[1] is the step
    response of G_11 = q0 / ∏(s − λ) (python-control again, from the channel's poles) and y[2] stays
    zero: the loop with η̂ frozen is m separate channels."""
    d = quell.paper_example().design()
    sys = d.decoupled_system()
    t = np.linspace(0.0, 5.0, 501)
    u = np.zeros((2, t.size))
    u[0] = 1.0
    resp = control.forced_response(sys, T=t, U=u)
    ch = d.channels[0]
    G = control.tf([ch["q0"]], np.real(np.poly(ch["poles"])))
    ref = control.forced_response(G, T=t, U=u[0])
    np.testing.assert_allclose(resp.outputs[0], ref.outputs, rtol=0, atol=1e-9 * np.max(np.abs(ref.outputs)))
    assert np.max(np.abs(resp.outputs[1])) <= 1e-9 * np.max(np.abs(ref.outputs))


@pytest.mark.parametrize("name, d", designs())
def test_observer_system_has_the_observer_poles_and_is_unbiased(name, d):
    obs = d.observer_system()
    p = d.plant
    n, m = p.n, p.m
    assert obs.input_labels == [f"u_f[{i + 1}]" for i in range(m)] + [f"y[{i + 1}]" for i in range(m)]
    assert obs.output_labels == [f"x_hat[{j + 1}]" for j in range(n)]
    np.testing.assert_allclose(np.sort_complex(obs.poles()), np.sort_complex(d.observer_eigenvalues), rtol=TOL, atol=TOL)
    # Driven by the plant's own y, the estimate equals the state for any input: X̂(s) = X(s).
    plant_y = control.ss(p.A, p.B, p.C, np.zeros((m, m)))
    plant_x = control.ss(p.A, p.B, np.eye(n), np.zeros((n, m)))
    for s in POINTS:
        O = obs(s)
        x_hat = O[:, :m] + O[:, m:] @ plant_y(s)
        x = plant_x(s)
        np.testing.assert_allclose(x_hat, x, rtol=0, atol=TOL * np.max(np.abs(x)))


def test_plant_from_a_transfer_function_is_its_minimal_realization():
    # (s + 1) / ((s + 1)(s − 1)(s + 3)): an unstable plant with a cancelling pair; minreal leaves 2 states.
    G = control.tf([1.0, 1.0], np.poly([-1.0, 1.0, -3.0]))
    plant = quell.Plant(G, delays=[0.2])
    assert (plant.n, plant.m) == (2, 1)
    realized = control.ss(plant.A, plant.B, plant.C, 0)
    for s in POINTS:
        expected = 1.0 / ((s - 1.0) * (s + 3.0))
        assert abs(realized(s) - expected) <= 1e-12 * abs(expected)
    # A StateSpace keeps its own realization.
    ss = control.ss(np.array([[0.0, 1.0], [2.0, -1.0]]), np.array([[0.0], [1.0]]), np.array([[1.0, 0.0]]), 0)
    np.testing.assert_array_equal(quell.Plant(ss).A, ss.A)


def test_state_keys_are_refused_with_a_transfer_function():
    """D, x0 and states refer to the plant's states, which a transfer function's realization
    chooses: a D given with one had been applied in the realization's coordinates (a disturbance's
    DC gain 5e8 where 2 was meant; helper tryout, 2026-12-07). The same D with the StateSpace it was
    written for is taken."""
    A = np.array([[0.0, 1.0], [2.0, -1.0]])
    B, C = np.array([[0.0], [1.0]]), np.array([[1.0, 0.0]])
    G = control.ss2tf(control.ss(A, B, C, 0))
    for name, value in [("D", [[1.0], [0.0]]), ("x0", [1.0, 0.0]), ("states", ["p", "v"])]:
        with pytest.raises(quell.ScenarioError, match=f"^{name}: refers to the plant's states, but with a control.TransferFunction"):
            quell.Plant(G, **{name: value})
    plant = quell.Plant(control.ss(A, B, C, 0), D=[[1.0], [0.0]], Q=[[0.0]])
    np.testing.assert_array_equal(plant.D, [[1.0], [0.0]])
    # Zeros name no state: taken.
    assert quell.Plant(G, x0=np.zeros(2), D=np.zeros((2, 1)), Q=[[0.0]]).n == 2


def test_a_transfer_function_that_cancels_an_unstable_pole_is_refused():
    # (s − 1.00001) / ((s − 1)(s + 2)(s + 3)): python-control's minreal cancels the pole at +1
    # against the zero 1e-5 away (its default tolerance), which would leave a stable,
    # minimum-phase model; the same plant as a StateSpace is refused by the design's zero dynamics.
    # The unstable pole and its zero are named; an exact unstable cancellation is refused too.
    for num, pole, zero in [([1.0, -1.00001], "1", "1.00001"), ([1.0, -1.0], "1", "1")]:
        G = control.tf(num, np.poly([1.0, -2.0, -3.0]))
        with pytest.raises(quell.ScenarioError, match=f"the pole {pole} in the closed right half-plane and the zero {zero} ") as e:
            quell.Plant(G, delays=[0.1])
        # The argument is the key, as for the library's own checks of sys (dt, below).
        assert e.value.key == "sys"
    # A pair on the imaginary axis is refused whichever side of it the roots' rounding puts the
    # pole: here −2.1e-15 ± 2j (it had been cancelled, hiding the undamped mode) and +1.1e-16 ± 2j,
    # and a triple pair ±3j, whose computed roots spread to −2.8e-7 ± 3j.
    cases = [([1.0, 0.0, 4.0], np.poly([2j, -2j, -1.0, -3.0, -4.0]).real),
             ([1.0, 0.0, 4.0], np.poly([2j, -2j, -1.0]).real),
             (np.poly([3j, -3j]).real, np.poly([3j, -3j] * 3 + [-1.0]).real)]
    for num, den in cases:
        with pytest.raises(quell.ScenarioError, match=r"the pole \S+j (in the closed right half-plane|on the imaginary axis) "):
            quell.Plant(control.tf(num, den), delays=[0.1])
    # A stable cancelled pair stays cancelled (the realization above).
    assert quell.Plant(control.tf([1.0, 2.0], np.poly([1.0, -2.0, -3.0])), delays=[0.1]).n == 2


def test_a_discrete_or_improper_transfer_function_is_refused_by_name():
    # A discrete-time tf kept its poles as continuous ones (z = −0.5 became s = −0.5).
    with pytest.raises(quell.ScenarioError, match=r"expected a continuous-time system \(dt = 0\), found dt = 0.1"):
        quell.Plant(control.tf([1.0], [1.0, 0.5], 0.1))
    # Improper, biproper and static: each is named as not strictly proper (a biproper one had been
    # told to pass disturbance matrices, from the realization's feedthrough D).
    for num, den in (([1.0, 2.0, 3.0], [1.0, 3.0]), ([1.0, 2.0], [1.0, 1.0]), ([2.0], [1.0])):
        degrees = f"a numerator of degree {len(num) - 1} and a denominator of degree {len(den) - 1}"
        with pytest.raises(quell.ScenarioError, match=f"{degrees}: a plant \\(1\\) is strictly proper .*numerator's degree must be below the denominator's"):
            quell.Plant(control.tf(num, den))
    # A biproper discrete one is named as discrete, not as biproper (the properness check had run
    # first, steering to the wrong fix); likewise dt = True.
    for dt in (0.1, True):
        with pytest.raises(quell.ScenarioError, match=r"^sys: expected a continuous-time system \(dt = 0\)") as e:
            quell.Plant(control.tf([1.0, 0.0], [1.0, -0.5], dt))
        assert e.value.key == "sys"
    # A coefficient that is not finite is named on sys (NaN in a denominator had leaked numpy's
    # LinAlgError; in a numerator it was blamed on C[0][0], an argument not given).
    for num, den, part in (([1.0], [1.0, np.nan], "denominator"), ([1.0], [1.0, np.inf, 1.0], "denominator"),
                           ([np.nan], [1.0, 1.0], "numerator")):
        with pytest.raises(quell.ScenarioError, match=f"^sys: the transfer function has a {part} that is not finite") as e:
            quell.Plant(control.tf(num, den))
        assert e.value.key == "sys"
    # B or C beside a system is named on B.
    sys = control.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]])
    with pytest.raises(quell.ScenarioError, match="^B: the first argument is a state-space system") as e:
        quell.Plant(sys, [[1.0]], [[1.0]])
    assert e.value.key == "B"
    # A frequency response is not a model of the plant's state.
    with pytest.raises(TypeError, match="A: expected a matrix, a control.StateSpace or a control.TransferFunction, found a FrequencyResponseData"):
        quell.Plant(control.frd(control.tf([1.0], [1.0, 1.0]), [1.0, 2.0, 3.0]))


def test_a_mimo_transfer_function_without_slycot_is_a_scenario_error():
    # Wood–Berry's 2×2 column: python-control realizes a MIMO transfer function only with slycot;
    # without it its own exception (a NotImplementedError) must not leak past quell.Plant.
    G = control.tf([[[12.8], [-18.9]], [[6.6], [-19.4]]], [[[16.7, 1.0], [21.0, 1.0]], [[10.9, 1.0], [14.4, 1.0]]])
    try:
        import slycot  # noqa: F401
    except ImportError:
        with pytest.raises(quell.ScenarioError, match="sys: python-control cannot realize this 2x2 transfer function"):
            quell.Plant(G, delays=[1.0, 3.0])
    else:
        assert quell.Plant(G, delays=[1.0, 3.0]).m == 2


def test_result_to_control_is_outputs_by_time_with_labels():
    result = quell.simulate(quell.paper_example(), t_end=2.0)
    resp = result.to_control()
    assert isinstance(resp, control.TimeResponseData)
    np.testing.assert_array_equal(resp.time, result.t)
    assert resp.outputs.shape == (2, len(result.t))
    np.testing.assert_array_equal(resp.outputs, result.y.T)
    np.testing.assert_array_equal(resp.inputs, result.u.T)
    assert resp.output_labels == ["y[1]", "y[2]"] and resp.input_labels == ["u[1]", "u[2]"]
    frame = resp.to_pandas()  # python-control's own conversion reads the labels
    np.testing.assert_array_equal(frame["y[2]"].to_numpy(), result.y[:, 1])
    assert resp.nstates == 0  # no states recorded
    # python-control takes time in seconds: the title says the plant's unit.
    assert resp.title == "quell simulation (t in s)"
    # With states=True the plant states come along (they were dropped), from the plant's x0.
    with_states = quell.simulate(quell.paper_example(), t_end=2.0, states=True)
    resp = with_states.to_control()
    assert resp.states.shape == (3, len(with_states.t)) and resp.state_labels == ["x[1]", "x[2]", "x[3]"]
    np.testing.assert_array_equal(resp.states, with_states.x.T)
    np.testing.assert_array_equal(resp.states[:, 0], quell.paper_example().plant.x0)


def test_state_space_signal_names_are_kept_through_to_the_loops_and_results():
    """A control.StateSpace's names reach the plant, the design's systems, the result's
    TimeResponseData and pickles; python-control's own generic names (u[0], …) are not names."""
    import pickle

    from test_api import A, B, C, D, DISTURBANCE, L, PAPER_DESIGN, Q, REFERENCE

    sys_ = control.ss(A, B, C, np.zeros((2, 2)), inputs=["thrust", "torque"], outputs=["height", "angle"],
                      states=["h", "v", "w"])
    plant = quell.Plant(sys_, D=D, Q=Q, delays=[1.0, 3.0])
    assert (plant.inputs, plant.outputs, plant.states) == (["thrust", "torque"], ["height", "angle"], ["h", "v", "w"])
    s = quell.Scenario(plant, REFERENCE, DISTURBANCE, t_end=1.0, observer_gain=L, **PAPER_DESIGN)
    for d in (s.design(), quell.design(plant, observer_gain=L, **PAPER_DESIGN)):
        dec, obs = d.decoupled_system(), d.observer_system()
        assert dec.output_labels == ["height", "angle"] and dec.state_labels == ["h", "v", "w"]
        assert obs.input_labels == ["thrust", "torque", "height", "angle"]
        assert obs.output_labels == ["h_hat", "v_hat", "w_hat"]
        # python-control finds the signals by name: the decoupled channel from u_d[1] to height.
        sub = dec[dec.find_output("height"), dec.find_input("u_d[1]")]
        assert abs(complex(sub(1j)) - d.channels[0]["q0"] / np.prod(1j - np.asarray(d.channels[0]["poles"]))) < 1e-9
    resp = quell.simulate(s, states=True).to_control()
    assert resp.output_labels == ["height", "angle"] and resp.state_labels == ["h", "v", "w"]
    for obj in (plant, s, s.design(), quell.simulate(s)):
        back = pickle.loads(pickle.dumps(obj))
        assert back == obj
    assert pickle.loads(pickle.dumps(s)).plant.outputs == ["height", "angle"]
    assert pickle.loads(pickle.dumps(quell.simulate(s))).to_control().output_labels == ["height", "angle"]
    # Names make plants differ; python-control's generic names are no names.
    unnamed = quell.Plant(control.ss(A, B, C, np.zeros((2, 2))), D=D, Q=Q, delays=[1.0, 3.0])
    assert unnamed != plant and unnamed == quell.Plant(A, B, C, D, Q, delays=[1.0, 3.0])
    assert unnamed.inputs == ["u_f[1]", "u_f[2]"] and unnamed.states == ["x[1]", "x[2]", "x[3]"]
    # Keywords name the signals of a plant from matrices, and override a system's.
    renamed = quell.Plant(sys_, D=D, Q=Q, delays=[1.0, 3.0], outputs=["z1", "z2"])
    assert renamed.outputs == ["z1", "z2"] and renamed.inputs == ["thrust", "torque"]
    with pytest.raises(quell.ScenarioError, match=r"outputs: expected 2 names \(one per channel\), found 3"):
        quell.Plant(A, B, C, outputs=["a", "b", "c"])
    with pytest.raises(quell.ScenarioError, match=r'states\[2\]: "a" names another signal too'):
        quell.Plant(A, B, C, states=["a", "b", "a"])
    with pytest.raises(TypeError, match=r"inputs\[1\]: expected a str \(a signal name\), found an int"):
        quell.Plant(A, B, C, inputs=["a", 2])
    with pytest.raises(TypeError, match=r"inputs: expected a list of 2 names \(str\), found a str"):
        quell.Plant(A, B, C, inputs="ab")


def test_a_systems_labels_are_checked_as_names():
    """A control.StateSpace's labels are checked at quell.Plant as the keywords' and a scenario
    file's names are (one check, quell::scenario::check_names): python-control itself keeps one of
    repeated labels (the independent side: its own input_labels) and accepts empty ones."""
    A, B, C = -np.diag([1.0, 2.0, 3.0]), np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]), np.eye(2, 3)
    repeated = control.ss(A, B, C, np.zeros((2, 2)), inputs=["a", "a"])
    assert repeated.input_labels == ["a"]  # python-control merged them: 2 inputs, 1 label
    with pytest.raises(quell.ScenarioError) as info:
        quell.Plant(repeated, delays=[0.0, 0.0])
    assert str(info.value) == (
        "sys.input_labels: expected 2 names (one per channel), found 1 (python-control keeps one of "
        "repeated labels); or name them with quell.Plant(sys, inputs=[...])"
    )
    empty = control.ss(A, B, C, np.zeros((2, 2)), outputs=["z", " "])
    with pytest.raises(quell.ScenarioError) as info:
        quell.Plant(empty, delays=[0.0, 0.0])
    assert str(info.value) == (
        'sys.output_labels[1]: expected a name, found " "; give every channel a name; '
        "or name them with quell.Plant(sys, outputs=[...])"
    )
    states = control.ss(A, B, C, np.zeros((2, 2)), states=["p", "", "q"])
    with pytest.raises(quell.ScenarioError, match=r'^sys.state_labels\[1\]: expected a name, found ""; give every state'):
        quell.Plant(states, delays=[0.0, 0.0])
    # The keyword that names a kind of signal overrides the system's labels, which are then not read.
    fixed = quell.Plant(repeated, delays=[0.0, 0.0], inputs=["a", "b"])
    assert fixed.inputs == ["a", "b"] and fixed.outputs == ["y[1]", "y[2]"]
    assert quell.Plant(empty, delays=[0.0, 0.0], outputs=["z", "w"]).outputs == ["z", "w"]


def test_a_plant_sent_to_python_control_with_its_own_names_comes_back_equal():
    # quell's default names given back explicitly are no names: the plant is == again (its TOML had
    # gained inputs = ["u_f[1]", …]).
    p = quell.paper_example().plant
    sys = control.ss(p.A, p.B, p.C, 0, inputs=p.inputs, outputs=p.outputs, states=p.states)
    back = quell.Plant(sys, D=p.D, Q=p.Q, delays=p.delays, time_unit=p.time_unit)
    assert back == p and back.inputs == p.inputs and back.states == p.states


def test_transfer_function_names_are_kept():
    G = control.tf([1.0], [1.0, 2.0, 1.0], inputs="force", outputs="position")
    p = quell.Plant(G, delays=[0.1])
    assert p.inputs == ["force"] and p.outputs == ["position"]


def test_a_python_control_plant_is_designed_automatically_without_toml():
    """auto_design takes a quell.Plant (here from control.ss) with the signals and Scenario's
    keywords: the same choices as the same scenario written as TOML text without [design], and a
    run within the tail bound. Text with signals beside it, or a Plant without a reference, is
    refused naming the argument."""
    paper = quell.paper_example()
    p = paper.plant
    sys = control.ss(p.A, p.B, p.C, np.zeros((2, 2)))
    plant = quell.Plant(sys, D=p.D, Q=p.Q, delays=p.delays)
    settings = {k: paper.simulation[k] for k in ("t_end", "output_step", "rtol", "atol")}
    s, report = quell.auto_design(plant, paper.reference, paper.disturbance, mu=[20.0, 30.0], **settings)
    assert report["passed"], report
    text = paper.to_toml()
    head, rest = text.split("[design]")
    _, from_text = quell.auto_design(head + "[design]\nmu = [20.0, 30.0]\n" + rest[rest.index("[[reference"):])
    assert [(c["key"], c["value"]) for c in report["choices"]] == [(c["key"], c["value"]) for c in from_text["choices"]]
    assert s.design().mu == [20.0, 30.0]
    tail = [c["tail_max_e"] for c in quell.simulate(s).summary()]
    assert tail[0] <= 0.01 * 3.0 and tail[1] <= 0.01 * 2.0, tail
    with pytest.raises(TypeError, match=r"^reference: expected None with TOML text"):
        quell.auto_design(text, paper.reference)
    with pytest.raises(TypeError, match=r"^t_end: expected None with TOML text"):
        quell.auto_design(text, t_end=5.0)
    with pytest.raises(quell.ScenarioError, match=r"^reference: missing; with a quell.Plant") as e:
        quell.auto_design(plant)
    assert e.value.key == "reference"
    with pytest.raises(quell.ScenarioError, match=r"t_ned: unknown keyword \(did you mean `t_end`\?\)"):
        quell.auto_design(plant, paper.reference, t_ned=5.0)


def test_python_control_shapes_get_hints_in_its_own_terms():
    """Errors for a plant given as a python-control system speak of its terms (helper tryout,
    2026-12-07): a feedthrough-shaped D is named as quell's disturbance matrix, a third input that
    is a disturbance is split off by indexing, a rounding-level feedthrough is no feedthrough, a
    dt is not a dead time, and an observer gain placed on the dual system is named as transposed."""
    A = [[0.0, 1.0, 0.0], [2.0, -1.0, 0.0], [0.0, 0.0, -3.0]]
    B = [[0.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 1.0, 0.0]]
    C = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    sys = control.ss(A, B, C, np.zeros((2, 3)))
    with pytest.raises(quell.ScenarioError, match=r"^C: .*where sys's last 1 inputs are disturbances, give the first 2 alone and the rest as D: Plant\(sys\[:, :2\], D=sys.B\[:, 2:\]\)"):
        quell.Plant(sys)
    # The split the hint names is a valid plant, its disturbance entering where the third input did.
    split = quell.Plant(sys[:, :2], D=sys.B[:, 2:])
    np.testing.assert_array_equal(split.D, np.asarray(B)[:, 2:])
    square = control.ss(A, np.asarray(B)[:, :2], C, np.zeros((2, 2)))
    with pytest.raises(quell.ScenarioError, match=r"^D: .*D here is the disturbance matrix of the plant \(1\), n×k = 3×2 into ẋ, not python-control's feedthrough sys.D"):
        quell.Plant(square, D=np.zeros((2, 2)))
    # A feedthrough at rounding's size is none; a real one is refused, naming the tolerance.
    tiny = control.ss(A, np.asarray(B)[:, :2], C, [[1e-17, 0.0], [0.0, 0.0]])
    assert quell.Plant(tiny).n == 3
    with pytest.raises(quell.ScenarioError, match=r"^sys.D\[0\]\[0\]: python-control's D is the feedthrough .*expected 0 \(within rounding, "):
        quell.Plant(control.ss(A, np.asarray(B)[:, :2], C, [[1e-3, 0.0], [0.0, 0.0]]))
    with pytest.raises(quell.ScenarioError, match=r"a dead time is not dt: give it as the input delays, Plant\(sys, delays=\[\.\.\.\]\)"):
        quell.Plant(control.tf([1.0], [1.0, 0.0, -1.0], 0.05))
    # A gain placed on the dual system (control.place(A.T, C.T, p) is Lᵀ), passed as it is.
    plant = quell.Plant(square, D=np.asarray(B)[:, 2:])
    Lt = control.place(np.asarray(A).T, np.asarray(C).T, [-4.0, -5.0, -6.0])
    with pytest.raises(quell.DesignError, match=r"^observer_gain: expected a 3×2 matrix, found 2×3 \(its transpose's shape: .*give its transpose\)"):
        quell.design(plant, observer_gain=Lt, channel_poles=[[-1.0, -2.0], [-1.0]],
                     reference_filter_poles=[[-1.0], [-1.0]], disturbance_filter_poles=[[-1.0]], mu=[1.0, 1.0], beta=1.0)
    # Transposed, it designs.
    quell.design(plant, observer_gain=Lt.T, channel_poles=[[-1.0, -2.0], [-1.0]],
                 reference_filter_poles=[[-1.0], [-1.0]], disturbance_filter_poles=[[-1.0]], mu=[1.0, 1.0], beta=1.0)


def test_a_misspelt_auto_design_keyword_is_matched_against_its_own_arguments():
    p = quell.paper_example()
    for typo, meant in (("convergence_tim", "convergence_time"), ("u_limt", "u_limit"), ("delay_eror", "delay_error")):
        with pytest.raises(quell.ScenarioError, match=rf"^{typo}: unknown keyword \(did you mean `{meant}`\?\); quell.auto_design takes text, reference, disturbance, convergence_time, u_limit, delay_error, time_scale, the keywords"):
            quell.auto_design(p.plant, p.reference, p.disturbance, t_end=60.0, **{typo: 3.0})
        # With TOML text too (it had read as a keyword the text leaves out).
        with pytest.raises(quell.ScenarioError, match=rf"^{typo}: unknown keyword \(did you mean `{meant}`\?\)"):
            quell.auto_design(p.to_toml(), **{typo: 3.0})
