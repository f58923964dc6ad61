"""Design properties, each checked by numpy/SciPy on the returned matrices: eig(A − BK) holds the channel poles, the decoupled transfer matrix
C (sI − A_f)⁻¹ B_f is diagonal with G_ii(s) = q_i0 / ∏(s − λ_ij), N D = L_ω, eig(A − LC) as asked."""

from pathlib import Path

import numpy as np
import pytest

import quell

S = [0.3j, 1.0j, 2.0 + 1.0j, 10.0j, -0.5 + 3.0j]   # sample frequencies, away from every pole


def paper_design():
    return quell.paper_example().design()


def test_decoupled_eigenvalues():
    d = paper_design()
    A, B = d.plant.A, d.plant.B
    eig = np.sort_complex(np.linalg.eigvals(A - B @ d.K))
    np.testing.assert_allclose(eig, np.sort_complex(d.decoupled_eigenvalues), atol=1e-9)
    np.testing.assert_allclose(d.A_f, A - B @ d.K, atol=1e-14)
    np.testing.assert_allclose(d.B_f, B @ d.F, atol=1e-14)
    # The Σσ_i = 3 = n channel poles are all of eig(A − BK) here (no zeros).
    np.testing.assert_allclose(eig, [-6, -4, -2], atol=1e-9)


@pytest.mark.parametrize("s", S)
def test_decoupled_transfer_matrix_is_diagonal(s):
    d = paper_design()
    C, n = d.plant.C, d.plant.n
    G = C @ np.linalg.solve(s * np.eye(n) - d.A_f, d.B_f)
    for i, ch in enumerate(d.channels):
        G_ii = ch["q0"] / np.prod([s - p for p in ch["poles"]])
        assert abs(G[i, i] - G_ii) <= 1e-10 * abs(G_ii)
    off = G - np.diag(np.diag(G))
    assert np.abs(off).max() <= 1e-10 * np.abs(np.diag(G)).max()


def test_unit_dc_gain_and_channel_denominators():
    d = paper_design()
    for ch, poles in zip(d.channels, [[-6, -2], [-4]]):
        np.testing.assert_allclose(np.sort_complex(ch["poles"]), np.sort_complex(poles))
        # Ascending coefficients of ∏(s − λ): numpy's np.poly is descending.
        np.testing.assert_allclose(ch["denominator"], np.poly(poles)[::-1][:-1].real)
        assert ch["q0"] == pytest.approx(ch["denominator"][0])


def test_disturbance_observer_gain():
    d = paper_design()
    np.testing.assert_allclose(d.N @ d.plant.D, d.L_w, atol=1e-12)
    # Minimum norm: N's rows lie in the column space of D (N = L_ω D⁺).
    D = d.plant.D
    P = D @ np.linalg.pinv(D)
    np.testing.assert_allclose(d.N @ P, d.N, atol=1e-12)


def test_internal_models_have_the_filter_poles():
    d = paper_design()
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(d.G_g).real), [-9, -6, -1], atol=1e-12)
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(d.G_w).real), [-3, -3, -2, -1, -1], atol=1e-6)
    assert d.G_g.shape == (3, 3) and d.L_g.shape == (3, 2) and d.G_w.shape == (5, 5) and d.L_w.shape == (5, 2)
    assert d.q == 8 and d.sigma == [2, 1]


def test_observer_poles_placed():
    p = quell.paper_example().plant
    d = quell.design(p, channel_poles=[[-6, -2], [-4]], reference_filter_poles=[[-1, -6], [-9]],
                     disturbance_filter_poles=[[-1, -3], [-1, -2, -3]], mu=[20, 30], beta=1.0,
                     observer_poles=[-2, -3, -4])
    eig = np.sort(np.linalg.eigvals(p.A - d.L @ p.C).real)
    np.testing.assert_allclose(eig, [-4, -3, -2], atol=1e-9)
    np.testing.assert_allclose(np.sort_complex(d.observer_eigenvalues), [-4, -3, -2], atol=1e-9)


def test_complex_channel_poles_both_forms():
    """A conjugate pair as Python complex numbers or as [re, im] gives the same design."""
    p = quell.paper_example().plant
    kw = dict(reference_filter_poles=[[-1, -6], [-9]], disturbance_filter_poles=[[-1, -3], [-1, -2, -3]],
              mu=[20, 30], beta=1.0, observer_poles=[-2, -3, -4])
    a = quell.design(p, channel_poles=[[-1 + 2j, -1 - 2j], [-4]], **kw)
    b = quell.design(p, channel_poles=[[[-1, 2]], [-4]], **kw)
    np.testing.assert_array_equal(a.K, b.K)
    eig = np.linalg.eigvals(p.A - p.B @ a.K)
    np.testing.assert_allclose(np.sort_complex(eig), np.sort_complex([-1 + 2j, -1 - 2j, -4]), atol=1e-9)


def test_checks_report():
    c = paper_design().checks
    assert c["controllability_rank"] == 3 and c["observability_rank"] == 3
    assert 1 <= c["cond_B_star"] < 1e3
    assert c["max_re_decoupled_eigenvalue"] == pytest.approx(-2, abs=1e-9)
    assert c["max_re_observer_eigenvalue"] < 0


def test_checks_are_the_cli_checks(tmp_path, quell_bin):
    """design.checks holds every figure of `quell design --json`'s checks, with the same values;
    cond_B_star is the equilibrated (scale-free) one: B* scaled row and column by diagonal
    matrices leaves it as it is, where numpy's cond(B*) changes (a ship's 1.0002 against 34.7)."""
    import json, subprocess
    path = tmp_path / "paper.toml"
    path.write_text(quell.paper_example().to_toml())
    out = subprocess.run([quell_bin, "design", str(path), "--json"], capture_output=True, text=True, check=True)
    cli = json.loads(out.stdout)["checks"]
    c = paper_design().checks
    assert set(cli) <= set(c), sorted(set(cli) - set(c))
    for key, value in cli.items():
        assert c[key] == value, key
    assert c["tolerance"] == 1e-5 and len(c["relative_degree_measures"]) == 2
    # Outputs and inputs in other units: B* becomes D1 B* D2, numpy's cond grows, ours does not.
    B = np.array([[1.0, 0.5], [0.3, 2.0]])
    D1, D2 = np.diag([1e3, 1e-2]), np.diag([5.0, 1e-4])
    kw = dict(channel_poles=[[-1], [-2]], reference_filter_poles=[[-0.5], [-0.5]], mu=[1, 1], beta=1.0, observer_poles=[-3, -4])
    one = quell.design(quell.Plant(np.zeros((2, 2)), B, np.eye(2)), **kw)
    scaled = quell.design(quell.Plant(np.zeros((2, 2)), B @ D2, D1), **kw)
    np.testing.assert_allclose(scaled.B_star, D1 @ B @ D2, rtol=1e-12)
    assert np.linalg.cond(scaled.B_star) > 1e3 * np.linalg.cond(B)
    c = one.checks
    assert scaled.checks["cond_B_star"] == pytest.approx(c["cond_B_star"], rel=1e-6)


def test_relative_degrees_given():
    """design(relative_degrees=...) overrides eq. (7); the paper's σ = (2, 1) gives the decided K,
    a contradicting σ is DesignError naming the channel, a non-integer names the entry."""
    p = quell.paper_example().plant
    kw = dict(channel_poles=[[-6, -2], [-4]], reference_filter_poles=[[-1, -6], [-9]],
              disturbance_filter_poles=[[-1, -3], [-1, -2, -3]], mu=[20, 30], beta=1.0, observer_poles=[-2, -3, -4])
    given = quell.design(p, relative_degrees=[2, 1], **kw)
    np.testing.assert_array_equal(given.K, quell.design(p, **kw).K)
    assert list(given.sigma) == [2, 1]
    with pytest.raises(quell.DesignError, match=r"^relative_degrees\[0\]: σ_1 = 1 contradicts the plant"):
        quell.design(p, relative_degrees=[1, 1], **dict(kw, channel_poles=[[-6], [-4]]))
    with pytest.raises(quell.DesignError, match=r"^relative_degrees\[1\]: expected an integer ≥ 1, found 0"):
        quell.design(p, relative_degrees=[2, 0], **kw)
    for bad in ([2, 1.0], [2, True]):
        with pytest.raises(TypeError, match=r"^relative_degrees\[1\]: expected an integer ≥ 1, found a (float|bool)"):
            quell.design(p, relative_degrees=bad, **kw)


TANK = Path(__file__).resolve().parents[2] / "quell" / "tests" / "data" / "quadruple-tank.toml"


def test_normalized_regressor_has_unit_dc_gain_and_unstiffens_the_quadruple_tank():
    """The tank's filters at its own time scale (poles −0.05, −0.1, −0.15): the paper's form has DC
    gain 1/∏|p_j| = 1/7.5e-4 from g to ξ̂'s first entry, the normalized form 1 (ξ̂ = −G⁻¹ L g for a
    constant g, solved here by numpy). The pre-run estimate flags the first stiff, not the second,
    and the normalized loop runs in a few hundred steps."""
    text = TANK.read_text()
    paper = quell.Scenario.from_toml(text)
    normalized = quell.Scenario.from_toml(text.replace("beta = 10.0", 'beta = 10.0\nregressor_scaling = "normalized"'))
    dp, dn = paper.design(), normalized.design()
    assert (dp.regressor_scaling, dn.regressor_scaling) == ("paper", "normalized")
    dc_paper = -np.linalg.solve(dp.G_g, dp.L_g)
    dc_normalized = -np.linalg.solve(dn.G_g, dn.L_g)
    expected = np.zeros((6, 2))
    expected[0, 0] = expected[3, 1] = 1.0
    # A 6×6 solve of a matrix with entries ≤ 0.3 in size: rounding far below 1e-12.
    np.testing.assert_allclose(dc_normalized, expected, atol=1e-12)
    np.testing.assert_allclose(dc_paper, expected / 7.5e-4, rtol=1e-12, atol=1e-9)
    for scenario, stiff in [(paper, True), (normalized, False)]:
        pace = scenario.adaptation()
        assert [c["stiff"] for c in pace] == [stiff, stiff]
        for c, mu in zip(pace, scenario.design().mu):
            assert c["adaptation_rate"] == pytest.approx(mu * c["lambda_max_omega"], rel=1e-14)
    r = quell.simulate(normalized)
    assert r.outcome["status"] == "completed"
    assert r.stats["steps"] < 1000


def test_bad_regressor_scaling_names_the_key():
    d = paper_design()
    kwargs = dict(channel_poles=[[-6.0, -2.0], [-4.0]], reference_filter_poles=[[-1.0, -6.0], [-9.0]],
                  disturbance_filter_poles=[[-1.0, -3.0], [-1.0, -2.0, -3.0]], mu=[20.0, 30.0], beta=1.0,
                  observer_poles=[-2.0, -3.0, -4.0])
    assert quell.design(d.plant, regressor_scaling="normalized", **kwargs).regressor_scaling == "normalized"
    with pytest.raises(quell.DesignError, match=r'^regressor_scaling: expected "paper" .* found "unit_dc"'):
        quell.design(d.plant, regressor_scaling="unit_dc", **kwargs)


def test_modal_regressor_is_a_resonator_per_harmonic_and_conditions_omega():
    """regressor_scaling="modal": G_g block diagonal, one 2×2 block [[−a, b], [−b, −a]] per pair
    −a ± jb with l = [0, 2a] (gains ≈ 1 at b when a ≪ b), checked with numpy's solves; and the
    regressor's time-averaged Gram Σ (a_k²/2) Re(v vᴴ), v = (jω_k I − G)⁻¹ l, for a square wave's
    five odd harmonics of 0.1 rad/s is far better conditioned with resonators at the harmonics
    than with the normalized companion form of real poles spread over them (as the automatic design
    spread them before: λ_min/λ_max about 3e-9)."""
    d = paper_design()
    ws = np.array([0.1, 0.3, 0.5, 0.7, 0.9])
    amps = 1.0 / np.array([1, 3, 5, 7, 9])
    b = 0.03
    resonators = [p for w in ws for p in (complex(-b, w), complex(-b, -w))]
    spread = list(-0.0667 * 1.37 ** np.arange(10))
    kwargs = dict(channel_poles=[[-6.0, -2.0], [-4.0]], disturbance_filter_poles=[[-1.0, -3.0], [-1.0, -2.0, -3.0]],
                  mu=[20.0, 30.0], beta=10.0, observer_poles=[-2.0, -3.0, -4.0])
    modal = quell.design(d.plant, reference_filter_poles=[resonators, [-9.0]], regressor_scaling="modal", **kwargs)
    normalized = quell.design(d.plant, reference_filter_poles=[spread, [-9.0]], regressor_scaling="normalized", **kwargs)
    assert modal.regressor_scaling == "modal"
    G, L = modal.G_g[:10, :10], modal.L_g[:10, 0]
    for k, w in enumerate(ws):
        block = G[2 * k:2 * k + 2, 2 * k:2 * k + 2]
        np.testing.assert_array_equal(block, [[-b, w], [-w, -b]])
        np.testing.assert_array_equal(L[2 * k:2 * k + 2], [0.0, 2 * b])
        # Its own resonance: gains 2w/√(b² + 4w²) and 2|p|/√(b² + 4w²), within b/w of 1.
        v = np.linalg.solve(1j * w * np.eye(2) - block, L[2 * k:2 * k + 2])
        np.testing.assert_allclose(np.abs(v), [2 * w / np.hypot(b, 2 * w), 2 * np.hypot(b, w) / np.hypot(b, 2 * w)],
                                   rtol=1e-12)
    assert np.count_nonzero(G - np.diag(np.diag(G))) == 10

    def spread_of(design):
        G, L = design.G_g[:10, :10], design.L_g[:10, 0]
        gram = sum(a * a / 2 * np.real(np.outer(v, v.conj()))
                   for a, w in zip(amps, ws) for v in [np.linalg.solve(1j * w * np.eye(10) - G, L)])
        e = np.linalg.eigvalsh(gram)
        return e[0] / e[-1]

    assert spread_of(modal) > 1e-3 > 1e-7 > spread_of(normalized)
    with pytest.raises(quell.DesignError, match=r"^reference_filter_poles\[0\]: pole .* is repeated"):
        quell.design(d.plant, reference_filter_poles=[[-1.0, -1.0], [-9.0]], regressor_scaling="modal", **kwargs)


def test_component_sizes_divide_their_blocks_of_the_regressor():
    """reference_sizes / disturbance_sizes divide each component's block of ξ̂: (sI − G)⁻¹ L's
    column i is the paper's filter of component i over its size, checked against the closed form
    1/∏(s − p_j) of the companion form's first entry; the choices carry them through a pickle, and
    a size that is not > 0 is refused naming it."""
    import pickle
    d = paper_design()
    kwargs = dict(channel_poles=[[-6.0, -2.0], [-4.0]], reference_filter_poles=[[-1.0, -6.0], [-9.0]],
                  disturbance_filter_poles=[[-1.0, -3.0], [-1.0, -2.0, -3.0]], mu=[20.0, 30.0], beta=1.0,
                  observer_poles=[-2.0, -3.0, -4.0])
    sized = quell.design(d.plant, reference_sizes=[3000.0, 2.0], disturbance_sizes=[1.0, 3.0], **kwargs)
    assert sized.reference_sizes == [3000.0, 2.0] and sized.disturbance_sizes == [1.0, 3.0]
    plain = quell.design(d.plant, **kwargs)
    assert plain.reference_sizes == [1.0, 1.0] and "reference_sizes" not in plain.choices
    for s in S:
        for G, L, poles, sizes in [(sized.G_g, sized.L_g, [[-1.0, -6.0], [-9.0]], [3000.0, 2.0]),
                                   (sized.G_w, sized.L_w, [[-1.0, -3.0], [-1.0, -2.0, -3.0]], [1.0, 3.0])]:
            X = np.linalg.solve(s * np.eye(G.shape[0]) - G, L)
            for i, (row, size) in enumerate(zip([0, 2], sizes)):
                want = 1.0 / np.prod([s - p for p in poles[i]]) / size
                assert abs(X[row, i] - want) <= 1e-12 * abs(want)
    # ξ̂'s coordinates change, the decoupler and observer do not.
    np.testing.assert_array_equal(sized.K, plain.K)
    np.testing.assert_array_equal(sized.L, plain.L)
    again = pickle.loads(pickle.dumps(sized))
    assert again.reference_sizes == [3000.0, 2.0]
    np.testing.assert_array_equal(again.L_g, sized.L_g)
    with pytest.raises(quell.DesignError, match=r"^reference_sizes\[1\]: expected a finite number, found inf"):
        quell.design(d.plant, reference_sizes=[3.0, float("inf")], **kwargs)
    for bad, found in [(-2.0, "-2"), (1e-320, "1e-320")]:
        with pytest.raises(quell.DesignError, match=rf"^reference_sizes\[1\]: expected a size from 1e-150 to 1e150 .*found {found}"):
            quell.design(d.plant, reference_sizes=[3.0, bad], **kwargs)
    with pytest.raises(quell.DesignError, match=r"^reference_sizes: expected one size per component, found an empty list"):
        quell.design(d.plant, reference_sizes=[], **kwargs)
    with pytest.raises(quell.DesignError, match=r"^disturbance_sizes: expected 2 entries .*found 3"):
        quell.design(d.plant, disturbance_sizes=[1.0, 1.0, 1.0], **kwargs)
