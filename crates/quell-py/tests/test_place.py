"""quell.place against python-control's and SciPy's place on their own test cases. The problem
data (not the code) comes from python-control's control/tests/statefbk_test.py (testPlace,
testPlace_varga_continuous) and SciPy's scipy/signal/tests/test_ltisys.py (TestPlacePoles).
Placed eigenvalues, computed by numpy from A − BK, must equal the requested poles as a multiset."""

import control
import numpy as np
import pytest
import scipy.signal

import quell


def assert_same_multiset(placed, wanted, tol):
    """Each wanted pole matched to its own placed eigenvalue, within tol·max(1, |pole|)."""
    placed = list(np.asarray(placed, dtype=complex))
    for p in np.asarray(wanted, dtype=complex):
        i = int(np.argmin([abs(z - p) for z in placed]))
        assert abs(placed[i] - p) <= tol * max(1.0, abs(p)), f"pole {p} not placed: {placed}"
        placed.pop(i)
    assert not placed


SCIPY_A = np.array([1.380, -0.2077, 6.715, -5.676, -0.5814, -4.290, 0, 0.6750,
                    1.067, 4.273, -6.654, 5.893, 0.0480, 4.273, 1.343, -2.104]).reshape(4, 4)
SCIPY_B = np.array([0, 5.679, 1.136, 1.136, 0, 0, -3.146, 0]).reshape(4, 2)
CAR_A = np.array([0, 7, 0, 0, 0, 0, 0, 7 / 3.0, 0, 0, 0, 0, 0, 0, 0, 0]).reshape(4, 4)
CAR_B = np.array([0, 0, 0, 0, 1, 0, 0, 1]).reshape(4, 2)
CAR5_A = np.array([0, 7, 0, 0, 0, 0, 0, 7 / 3.0, 0, 0, 0, 0, 0, 0, 0, 0,
                   0, 0, 0, 5, 0, 0, 0, 0, 9]).reshape(5, 5)
CAR5_B = np.array([0, 0, 0, 0, 1, 0, 0, 1, 2, 3]).reshape(5, 2)
FULL_B = np.array([0, 5.679, 1.136, 1.136, 0, 0, -3.146, 0, 1, 2, 3, 4, 5, 6, 7, 8]).reshape(4, 4)

CASES = {
    # SciPy TestPlacePoles.test_real (KNV paper, example 1 of section 4)
    "scipy_real": (SCIPY_A, SCIPY_B, [-0.2, -0.5, -5.0566, -8.6659]),
    # SciPy test_complex1 (linearized car model, Jaulin)
    "scipy_complex1": (CAR_A, CAR_B, [-3, -1, -2 - 1j, -2 + 1j]),
    # SciPy test_complex2, both pole sets
    "scipy_complex2": (CAR5_A, CAR5_B, [-2, -3 + 1j, -3 - 1j, -1 + 1j, -1 - 1j]),
    "scipy_complex2_odd": (CAR5_A, CAR5_B, [-2, -3, -4, -1 + 1j, -1 - 1j]),
    # SciPy test_tricky_B: B with n columns (unique K), then one column
    "scipy_full_B": (SCIPY_A, FULL_B, [-0.2, -0.5, -5.0566, -8.6659]),
    "scipy_full_B_complex": (SCIPY_A, FULL_B, [-2 + 1j, -2 - 1j, -3, -2]),
    "scipy_one_column": (SCIPY_A, FULL_B[:, :1], [-2 + 1j, -2 - 1j, -3, -2]),
    # python-control testPlace
    "control_place": (SCIPY_A, SCIPY_B, [-0.5 + 1j, -0.5 - 1j, -5.0566, -8.6659]),
    # python-control bug #177
    "control_bug_177": (np.array([[0.0, 1.0], [100.0, 0.0]]), np.array([[0.0], [1.0]]), [-20 + 10j, -20 - 10j]),
    # Poles repeated rank(B) = 2 times: both place them (a semisimple closed loop)
    "repeated_at_rank_b": (SCIPY_A, SCIPY_B, [-1.0, -1.0, -2.0, -2.0]),
}

# A pole repeated more often than rank(B): the closed loop would need a Jordan block.
BEYOND_RANK_B = {
    # python-control testPlace_varga_continuous (a double pole, one input; control.place_varga's case)
    "control_varga_repeated": (np.array([[1.0, -2.0], [3.0, -4.0]]), np.array([[5.0], [7.0]]), [-2.0, -2.0], 2, 1),
    "double_integrator": (np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0]]), [-1.0, -1.0], 2, 1),
    # Four copies with rank(B) = 2 (gains ≈ 5e3 with eigenvalues 7e-3 off were returned for such a case)
    "scipy_four_fold": (SCIPY_A, SCIPY_B, [-1.0] * 4, 4, 2),
    "car5_triple": (CAR5_A, CAR5_B, [-1.0, -1.0, -1.0, -2.0, -3.0], 3, 2),
}


@pytest.mark.parametrize("name", CASES)
def test_placed_eigenvalues(name):
    A, B, P = CASES[name]
    K = quell.place(A, B, P)
    assert K.shape == (B.shape[1], A.shape[0])
    # 1e-8 as SciPy's own tests; a double pole is only determined to ~sqrt(eps) by the eigenvalues.
    repeated = len(set(np.round(P, 12))) < len(P)
    assert_same_multiset(np.linalg.eigvals(A - B @ K), P, 1e-6 if repeated else 1e-8)


@pytest.mark.parametrize("name", CASES)
@pytest.mark.parametrize("reference", ["control.place", "scipy.signal.place_poles"])
def test_same_eigenvalues_as_the_references(name, reference):
    """Where python-control or SciPy place the poles too, all give the same spectrum. For one input
    K is unique, so the gains agree too (for several inputs each method picks its own K)."""
    A, B, P = CASES[name]
    try:
        if reference == "control.place":
            K_ref = control.place(A, B, P)
        else:
            K_ref = scipy.signal.place_poles(A, B, P).gain_matrix
    except ValueError:
        pytest.skip(f"{reference} refuses this case (a pole repeated more often than rank B)")
    K = quell.place(A, B, P)
    assert_same_multiset(np.linalg.eigvals(A - B @ K), np.linalg.eigvals(A - B @ K_ref), 1e-6)
    if B.shape[1] == 1:
        np.testing.assert_allclose(K, K_ref, rtol=1e-6, atol=1e-9 * np.abs(K_ref).max())


def test_complex_poles_as_pairs():
    """[re, im] means re ± i·im, as in scenario files."""
    A, B, _ = CASES["control_bug_177"]
    assert np.allclose(quell.place(A, B, [[-20, 10]]), quell.place(A, B, [-20 + 10j, -20 - 10j]))


@pytest.mark.parametrize(
    "A,B,P,fragment",
    [
        # SciPy test_errors: a complex pole without its conjugate
        (CAR_A, CAR_B, [-2 + 1j, -2 - 1j, -2 + 3j, -2], "conjugate"),
        # SciPy: A not square, B with the wrong number of rows
        (CAR_A[:, :3], CAR_B, [-2, -3, -4, -5], "A:"),
        (CAR_A, CAR_B[:3, :], [-2, -3, -4, -5], "B:"),
        (SCIPY_A, SCIPY_B, [-1, -2, -3], "expected 4 poles"),
    ],
)
def test_place_refusals(A, B, P, fragment):
    with pytest.raises(quell.DesignError, match=fragment):
        quell.place(A, B, P)


def test_triple_pole_with_two_inputs():
    """python-control's testPlace refuses three poles at one spot with rank B = 2; a placement with a
    Jordan block can still achieve it. quell either places it (eigenvalues then agree to the
    accuracy a 3-fold eigenvalue allows, ~eps^(1/3)) or refuses with a DesignError naming the poles."""
    A, B = SCIPY_A, SCIPY_B
    P = [-0.5, -0.5, -0.5, -8.6659]
    with pytest.raises(ValueError):
        control.place(A, B, P)
    try:
        K = quell.place(A, B, P)
    except quell.DesignError as e:
        assert str(e).startswith("poles: ")
    else:
        assert_same_multiset(np.linalg.eigvals(A - B @ K), P, 1e-4)


@pytest.mark.parametrize("name", BEYOND_RANK_B)
def test_a_pole_repeated_beyond_rank_b_is_refused_as_control_place_refuses_it(name):
    """quell.place refuses what control.place refuses (a pole repeated more than rank(B) times),
    with a DesignError (a ValueError, as control.place raises) naming the pole, its multiplicity
    and rank(B), and telling to spread the poles."""
    A, B, P, multiplicity, rank = BEYOND_RANK_B[name]
    with pytest.raises(ValueError, match="repeated more than rank"):
        control.place(A, B, P)
    with pytest.raises(quell.DesignError) as e:
        quell.place(A, B, P)
    assert isinstance(e.value, ValueError)
    text = str(e.value)
    assert text.startswith(f"poles: pole {max(set(P), key=P.count):.6f} is requested {multiplicity} times, more than rank(B) = {rank}"), text
    assert "spread the repeated poles" in text, text
    # Spread by 10 % of their size, both place them.
    spread = [p * (1 + 0.1 * P[:i].count(p)) for i, p in enumerate(P)]
    K, K_ref = quell.place(A, B, spread), control.place(A, B, spread)
    assert_same_multiset(np.linalg.eigvals(A - B @ K), spread, 1e-8)
    assert_same_multiset(np.linalg.eigvals(A - B @ K_ref), spread, 1e-6)
