"""The real-time Controller's core against scipy.signal.cont2discrete (ZOH) of the same matrices.

The core is the linear part of the controller, z = [ξ̂_g; ξ̂_ω; x̂] driven by v = [y; g; u_d]:
reference observer (14) ξ̂_g' = G_g ξ̂_g + L_g g, disturbance observer (20) in the coordinates
ξ̂_ω = φ + N x̂: ξ̂_ω' = G_ω ξ̂_ω + N L (y − C x̂), and the observer (6) with the decoupling law (5)
substituted: x̂' = (A_f − LC) x̂ + L y + B_f u_d; the plant input is u_f = −K x̂ + F u_d. These are
assembled here from the Design's matrices, discretized by SciPy, and run beside the Controller on
random y, g; u_d(k) = u(k − τ_i/T_s) comes from the Controller's own commands."""

import numpy as np
import pytest
import scipy.signal

import quell


def core(d):
    n, m = d.plant.n, d.plant.m
    qg, qw = d.G_g.shape[0], d.G_w.shape[0]
    nz = qg + qw + n
    C, L, N = d.plant.C, d.L, d.N
    A = np.zeros((nz, nz))
    B = np.zeros((nz, 3 * m))
    A[:qg, :qg] = d.G_g
    B[:qg, m : 2 * m] = d.L_g
    A[qg : qg + qw, qg : qg + qw] = d.G_w
    A[qg : qg + qw, qg + qw :] = -N @ L @ C
    B[qg : qg + qw, :m] = N @ L
    A[qg + qw :, qg + qw :] = d.A_f - L @ C
    B[qg + qw :, :m] = L
    B[qg + qw :, 2 * m :] = d.B_f
    return A, B


@pytest.mark.parametrize("T", [0.01, 0.05])
def test_core_matches_cont2discrete(T):
    d = quell.paper_example().design()
    n, m = d.plant.n, d.plant.m
    A, B = core(d)
    Phi, Gamma, *_ = scipy.signal.cont2discrete((A, B, np.eye(len(A)), np.zeros((len(A), B.shape[1]))), T, method="zoh")
    ctrl = quell.Controller(d, sample_time=T)
    delays = np.rint(d.plant.delays / T).astype(int)
    rng = np.random.default_rng(11)
    steps = 4 * int(delays.max()) + 50
    z = np.zeros(len(A))
    u_hist = np.zeros((steps, m))
    worst = 0.0
    for k in range(steps):
        y, g = rng.normal(size=m), rng.normal(size=m)
        u_f = ctrl.step(y, g)
        u_hist[k] = ctrl.command()
        u_d = np.array([u_hist[k - delays[i], i] if k >= delays[i] else 0.0 for i in range(m)])
        expected_u_f = -d.K @ z[-n:] + d.F @ u_d
        np.testing.assert_allclose(u_f, expected_u_f, rtol=1e-9, atol=1e-12)
        z = Phi @ z + Gamma @ np.concatenate([y, g, u_d])
        got = np.concatenate([ctrl.xi_hat(), ctrl.x_hat()])
        worst = max(worst, np.abs(got - z).max() / max(1.0, np.abs(z).max()))
    # Same matrices, two implementations of expm and of the recursion: rounding only.
    assert worst < 1e-10
    assert np.abs(u_hist).max() > 0  # the adaptive law was active, so u_d was not trivially zero


def test_reset_and_shapes():
    d = quell.paper_example().design()
    ctrl = quell.Controller(d, sample_time=1e-3)
    y, g = np.array([0.1, 1.9]), np.array([0.0, 2.0])
    first = [ctrl.step(y, g).copy() for _ in range(5)]
    assert ctrl.eta().shape == (2, d.q) and ctrl.command().shape == (2,)
    ctrl.reset()
    assert not ctrl.eta().any() and not ctrl.x_hat().any()
    again = [ctrl.step([0.1, 1.9], (0.0, 2.0)).copy() for _ in range(5)]   # lists and tuples work too
    np.testing.assert_array_equal(first, again)
    assert ctrl.sample_time == 1e-3


@pytest.mark.parametrize(
    "y,g,fragment",
    [
        ([1.0, 2.0, 3.0], [0.0, 0.0], "y: expected 2 entries"),
        ([1.0], [0.0, 0.0], "y: expected 2 entries"),
        ([np.nan, 1.0], [0.0, 0.0], r"y\[0\]: expected a finite number"),
        ([0.0, 0.0], [np.inf, 0.0], r"g\[0\]: expected a finite number"),
        ([0.0, 0.0], "ab", "g: expected real numbers"),
        ([[0.0, 0.0]], [0.0, 0.0], "y: expected a 1-D array"),
        (np.array([1, 2], dtype=np.int32), [0.0, 0.0], None),
        (np.array([1.0, 2.0, 3.0, 4.0])[::2], [0.0, 0.0], None),
    ],
)
def test_step_arguments(y, g, fragment):
    ctrl = quell.Controller(quell.paper_example().design(), sample_time=1e-3)
    if fragment is None:
        assert ctrl.step(y, g).shape == (2,)
    else:
        # A QuellError for values, a TypeError for strings (TypeError is not a ValueError).
        with pytest.raises((quell.ControllerError, TypeError), match=fragment):
            ctrl.step(y, g)


def test_sample_time_must_divide_the_delays():
    d = quell.paper_example().design()
    with pytest.raises(quell.ScenarioError, match="not a whole number of samples"):
        quell.Controller(d, sample_time=0.0007)
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(quell.ScenarioError, match="sample_time"):
            quell.Controller(d, sample_time=bad)
    with pytest.raises(TypeError, match="sample_time: expected a real number, found a str"):
        quell.Controller(d, sample_time="1ms")


def test_a_spike_is_refused_and_the_state_kept():
    """A finite spike of 1e300 made u_f NaN for ever; now any entry beyond ±1e100 is refused
    (ValueError naming it) and the next steps are those of a controller that never saw it."""
    d = quell.paper_example().design()
    a, b = quell.Controller(d, sample_time=1e-3), quell.Controller(d, sample_time=1e-3)
    for k in range(300):
        y, g = [0.3 * np.sin(k * 1e-2), -0.1], [1.0, 2.0]
        if k == 150:
            for bad_y, bad_g, key in (([1e300, 0.0], g, r"y\[0\] = 1e300"), (y, [0.0, -1e160], r"g\[1\] = -1e160")):
                with pytest.raises(ValueError, match=key + r" is beyond ±1e100 \(or not finite\)"):
                    a.step(bad_y, bad_g)
        np.testing.assert_array_equal(a.step(y, g), b.step(y, g))


@pytest.mark.parametrize("y", [[True, False], (False, 1.0), np.array([True, False]), [np.True_, 0.0]])
def test_step_refuses_booleans_as_plant_does(y):
    ctrl = quell.Controller(quell.paper_example().design(), sample_time=1e-3)
    with pytest.raises(TypeError, match="y: .*booleans"):
        ctrl.step(y, [0.0, 0.0])
    with pytest.raises(TypeError, match="booleans"):
        quell.Plant([[True]], [[1.0]], [[1.0]])


def test_a_faulted_controller_is_not_pickled_into_a_checkpoint_that_cannot_load():
    """A state past floating point (StateNotFinite; a PMSM's controller got there from five spikes
    just within the input bound, here from a finite state of 1e300 entries): such a controller had
    pickled, and the pickle then failed to load (its NaN state refused), so a host loop's
    checkpoint taken at the fault was lost. Pickling and copying it are refused with what to do;
    after reset() it pickles and the copy steps as it does."""
    import copy
    import pickle

    c = quell.Controller(quell.paper_example().design(), sample_time=1e-2)
    c.step([0.5, 0.0], [1.0, 2.0])
    huge = c.__getstate__()
    huge[:] = 1e300  # finite, and Ω_i stays symmetric
    c.__setstate__(huge)
    with pytest.raises(quell.ControllerError, match="no longer finite"):
        c.step([0.5, 0.0], [1.0, 2.0])
    assert not np.isfinite(c.__getstate__()).all()
    for save in (pickle.dumps, copy.copy, copy.deepcopy):
        with pytest.raises(quell.ControllerError, match=r"no longer finite .*reset\(\) it first"):
            save(c)
    c.reset()
    again = pickle.loads(pickle.dumps(c))
    assert np.array_equal(again.step([0.5, 0.0], [1.0, 2.0]), c.step([0.5, 0.0], [1.0, 2.0]))


def test_a_state_of_another_shape_is_named_by_its_dimensions():
    """A 2-D state had been refused as "expected an array of real numbers, found a ndarray"
    (helper tryout, 2026-12-06): it names the dimensions; the 1-D state still loads."""
    c = quell.Controller(quell.paper_example().design(), sample_time=1e-2)
    state = c.__getstate__()
    with pytest.raises(TypeError, match=r"^state: expected a 1-D array of real numbers .*, found a 2-D array$"):
        c.__setstate__(state.reshape(2, -1))
    c.__setstate__(state)
    assert np.array_equal(c.__getstate__(), state)
