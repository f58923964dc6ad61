"""The plant input u_f = -K x_hat + F u_d (eq. (5)) as a result of quell.simulate: recomputed here with
numpy from the design's K and F, the recorded observer state x_hat and the recorded command u read at
t - tau_i by interpolation (u = 0 before t = 0)."""

import numpy as np
import pytest

import quell


def delayed(t, u, tau):
    """u(t - tau) by linear interpolation in the recorded samples; 0 before t = 0."""
    return np.where(t - tau >= 0.0, np.interp(t - tau, t, u), 0.0)


@pytest.mark.parametrize("sample_time", [None, 0.01])
def test_u_f_is_minus_K_x_hat_plus_F_u_delayed(sample_time):
    s = quell.paper_example()
    d = s.design()
    r = quell.simulate(s, t_end=20.0, output_step=0.05, sample_time=sample_time, states=True)
    assert r.x.shape == r.x_hat.shape == (len(r), 3)
    taus = s.plant.delays
    u_d = np.column_stack([delayed(r.t, r.u[:, i], tau) for i, tau in enumerate(taus)])
    want = u_d @ d.F.T - r.x_hat @ d.K.T
    # The delays (1 s, 3 s) are whole numbers of output steps, so the interpolation reads recorded
    # samples; the continuous loop reads the same dense output from its history: agreement to
    # rounding, 1e-10 of the peak (the sampled loop's is exact to 1e-12).
    peak = np.abs(want).max()
    np.testing.assert_allclose(r.u_f, want, rtol=0, atol=1e-10 * peak)
    assert np.abs(r.u_f - r.u).max() > 1.0, "u_f is not the command u"
    # summary() and to_pandas() carry u_f (and the states when recorded).
    # The summary's peak counts every solver (controller) step between the rows too: at least the
    # rows' peak, and within 1 % of it here, where the rows (0.05 s) are denser than the steps.
    rows, peaks = np.abs(r.u_f).max(axis=0), np.array([c["max_uf"] for c in r.summary()])
    assert np.all(peaks >= rows) and np.all(peaks <= 1.01 * rows), (peaks, rows)
    df = r.to_pandas()
    np.testing.assert_array_equal(df[["uf1", "uf2"]].to_numpy(), r.u_f)
    np.testing.assert_array_equal(df[["xhat1", "xhat2", "xhat3"]].to_numpy(), r.x_hat)


def test_states_are_recorded_only_when_asked():
    r = quell.simulate(quell.paper_example(), t_end=1.0)
    assert r.x is None and r.x_hat is None and r.u_f.shape == (len(r), 2)
    assert "x1" not in r.to_pandas().columns


def test_an_actuator_limit_clips_u_f_and_is_counted():
    """Scenario(actuator={"u_max": ...}) is [truth]'s u_max: the recorded plant input is u_f clipped
    to ±u_max (computed here from the unclipped design run's formula), and
    result.limited_fraction is the share of samples at the limit (summary.json's key; None without
    a limit)."""
    from test_api import DISTURBANCE, L, PAPER_DESIGN, REFERENCE

    p = quell.paper_example().plant
    u_max = [5.0, 8.0]
    free = quell.Scenario(p, REFERENCE, DISTURBANCE, t_end=20.0, observer_gain=L, **PAPER_DESIGN)
    limited = quell.Scenario(p, REFERENCE, DISTURBANCE, t_end=20.0, observer_gain=L, actuator={"u_max": u_max},
                             **PAPER_DESIGN)
    assert quell.simulate(free).limited_fraction is None
    r = quell.simulate(limited, states=True)
    d = limited.design()
    u_d = np.column_stack([delayed(r.t, r.u[:, i], tau) for i, tau in enumerate(p.delays)])
    want = np.clip(u_d @ d.F.T - r.x_hat @ d.K.T, -np.array(u_max), np.array(u_max))
    np.testing.assert_allclose(r.u_f, want, rtol=0, atol=1e-9 * max(u_max))
    at_limit = (np.abs(r.u_f) >= np.array(u_max) * (1 - 1e-12)).mean(axis=0)
    assert r.limited_fraction == pytest.approx(list(at_limit), abs=2.0 / len(r))
    assert 0.0 < min(r.limited_fraction) and max(r.limited_fraction) < 1.0
    with pytest.raises(quell.ScenarioError, match=r'^actuator: unknown key "umax"'):
        quell.Scenario(p, REFERENCE, DISTURBANCE, observer_gain=L, actuator={"umax": u_max}, **PAPER_DESIGN)


def test_a_range_that_is_not_symmetric_clips_each_side_at_its_own_limit():
    """actuator={"u_min": ...} is [truth]'s u_min: u_f clipped to [u_min, u_max] (computed here from
    the controller's own formula, as above), the panel's dashed lines at both ends, and a pickled
    result keeps them; a positive u_min is refused naming the key."""
    import pickle

    import matplotlib

    matplotlib.use("Agg")
    from test_api import DISTURBANCE, L, PAPER_DESIGN, REFERENCE

    p = quell.paper_example().plant
    lower, upper = np.array([-10.0, -float("inf")]), np.array([30.0, 6.0])
    s = quell.Scenario(p, REFERENCE, DISTURBANCE, t_end=20.0, observer_gain=L,
                       actuator={"u_max": list(upper), "u_min": list(lower)}, **PAPER_DESIGN)
    r = pickle.loads(pickle.dumps(quell.simulate(s, states=True)))
    d = s.design()
    u_d = np.column_stack([delayed(r.t, r.u[:, i], tau) for i, tau in enumerate(p.delays)])
    want = np.clip(u_d @ d.F.T - r.x_hat @ d.K.T, lower, upper)
    np.testing.assert_allclose(r.u_f, want, rtol=0, atol=1e-9 * 30.0)
    assert r.u_f[:, 0].min() == -10.0 and r.u_f[:, 0].max() < 30.0, "input 1 clipped below only"
    assert r.u_f[:, 1].min() < -6.0, "input 2 has no lower limit"
    panel = r.plot(channel=1).axes[3]
    levels = sorted(line.get_ydata()[0] for line in panel.get_lines() if line.get_linestyle() == "--")
    assert levels == [-10.0, 30.0]
    assert "truth.u_min[0], u_max[0] = -10, 30" in [t.get_text() for t in panel.get_legend().get_texts()]
    # Clipped below only, at −10, where max|u_f| asked (12.5) is within u_max: still said.
    assert "; the controller asked for |u_f| up to " in panel.get_title(), panel.get_title()
    with pytest.raises(quell.ScenarioError, match=r"^truth.u_min\[1\]: expected a lower limit < 0"):
        quell.Scenario(p, REFERENCE, DISTURBANCE, observer_gain=L, actuator={"u_min": [-1.0, 0.5]}, **PAPER_DESIGN)


def test_the_plot_shows_the_actuator_limit_or_how_far_u_f_stays_from_it():
    """u_f's panel draws ±u_max where u_f comes within a tenth of the limit, and gives the peak's share
    of it in the title otherwise (a pickled result keeps its limits)."""
    import pickle

    import matplotlib

    matplotlib.use("Agg")
    from test_api import DISTURBANCE, L, PAPER_DESIGN, REFERENCE

    p = quell.paper_example().plant
    s = quell.Scenario(p, REFERENCE, DISTURBANCE, t_end=5.0, observer_gain=L, actuator={"u_max": [5.0, 1e4]},
                       **PAPER_DESIGN)
    r = pickle.loads(pickle.dumps(quell.simulate(s)))
    near = r.plot(channel=1).axes[3]
    levels = sorted(line.get_ydata()[0] for line in near.get_lines() if line.get_linestyle() == "--")
    assert levels == [-5.0, 5.0]
    assert "±truth.u_max[0] = 5" in [t.get_text() for t in near.get_legend().get_texts()]
    far = r.plot(channel=2).axes[3]
    share = 100 * np.abs(r.u_f[:, 1]).max() / 1e4
    # The share to two significant digits, also below 0.1 % (it read "0.0 %" there).
    title = far.get_title()
    assert title.endswith(" % of truth.u_max"), title
    shown = float(title.rsplit("; peak ", 1)[1].split(" %")[0])
    assert abs(shown / share - 1) < 0.05, (shown, share)
    assert not [line for line in far.get_lines() if line.get_linestyle() == "--"]


def test_legends_go_where_they_hide_the_least():
    """Every panel's legend used the upper right, where the paper's η̂ traces run; then "best",
    which still hid a digester's η1_3 transient behind eleven entries (helper tryout, 2026-12-06):
    the η̂ legend of a whole figure now stands beside its panel and covers none of its points."""
    import matplotlib

    matplotlib.use("Agg")
    result = quell.simulate(quell.paper_example(), t_end=20.0)
    fig = result.plot(channel=1)
    eta_ax = fig.axes[4]
    legend = eta_ax.get_legend()
    fig.canvas.draw()
    box = legend.get_window_extent()
    panel = eta_ax.get_window_extent()
    assert box.x0 > panel.x1, (box, panel)
    inside = sum(
        box.contains(*xy) for line in eta_ax.get_lines() for xy in eta_ax.transData.transform(line.get_xydata())
    )
    assert inside == 0
    # Within the figure: tight_layout made room for it (nothing cut at the right edge).
    assert box.x1 <= fig.bbox.x1, (box, fig.bbox)
    # The same legend in the upper right of the panel covers η̂ points (59 over these 20 s).
    eta_ax.legend(loc="upper right", fontsize="small", ncol=3)
    fig.canvas.draw()
    corner = eta_ax.get_legend().get_window_extent()
    in_corner = sum(
        corner.contains(*xy) for line in eta_ax.get_lines() for xy in eta_ax.transData.transform(line.get_xydata())
    )
    assert in_corner > 0, in_corner
    # Other panels keep matplotlib's "best" place.
    assert fig.axes[1].get_legend()._loc in (0, "best")


def phasors(signal, w):
    """Per component the phasor of its part at frequency w: a sin(w t + phi) -> a e^{j phi} (any one
    convention for g and omega alike), a bias b -> b at w = 0."""
    out = []
    for c in signal:
        z = complex(c["bias"]) if w == 0.0 else 0j
        for h in c["harmonics"]:
            if h["frequency"] == w:
                z += h["amplitude"] * np.exp(1j * h["phase"])
        out.append(z)
    return np.array(out)


def test_the_steady_state_input_is_the_plants_inverse_and_what_the_converged_run_applies():
    """steady_input() against numpy's transfer matrices P(jw) = C (jwI - A)^-1 B and
    P_d(jw) = C (jwI - A)^-1 D + Q: U = P^-1 (G - P_d W) per frequency (the paper's plant has no
    eigenvalue at 0, 1 or 2 rad/s); and against the paper's run, whose u_f over the last two common
    periods (4 pi s) of 100 s has that RMS and that peak."""
    s = quell.paper_example()
    p = s.plant
    A, B, C, D, Q = (np.asarray(M) for M in (p.A, p.B, p.C, p.D, p.Q))
    steady = s.steady_input()
    assert [t["frequency"] for t in steady["tones"]] == [0.0, 1.0, 2.0]
    for t in steady["tones"]:
        w = t["frequency"]
        R = np.linalg.solve(1j * w * np.eye(len(A)) - A, np.hstack([B, D]))
        P, Pd = C @ R[:, : B.shape[1]], C @ R[:, B.shape[1]:] + Q
        G, W = phasors(s.reference, w), phasors(s.disturbance, w)
        U = np.linalg.solve(P, G - Pd @ W)
        # Two 3x3 complex solves of entries <= 10: 1e-12 of the amplitudes' size.
        np.testing.assert_allclose(t["amplitude"], np.abs(U), rtol=0, atol=1e-12 * np.abs(U).max())
        np.testing.assert_allclose(t["for_reference"], np.abs(np.linalg.solve(P, G)), rtol=0, atol=1e-12 * np.abs(U).max())
        np.testing.assert_allclose(t["disturbance_output"], np.abs(Pd @ W), rtol=1e-12)
    # 1 and 2 rad/s are commensurate: the peak is the maximum over the common period 2 pi, below
    # the sum of the amplitudes.
    sums = [sum(t["amplitude"][i] for t in steady["tones"]) for i in range(2)]
    assert all(p < 0.95 * total for p, total in zip(steady["peak"], sums)), (steady["peak"], sums)
    r = quell.simulate(s, output_step=0.01)
    tail = r.t >= r.t[-1] - 4 * np.pi
    rms = np.sqrt(np.mean(r.u_f[tail] ** 2, axis=0))
    # At 100 s the run's u_f is within about 0.3 % of its steady state, and the 4 pi window holds
    # two common periods up to one output step: RMS and peak agree to 0.5 %.
    np.testing.assert_allclose(rms, steady["rms"], rtol=5e-3)
    np.testing.assert_allclose(np.abs(r.u_f[tail]).max(axis=0), steady["peak"], rtol=5e-3)
    assert steady["advice"] == []


@pytest.mark.parametrize("sample_time", [None, 0.01])
def test_a_clipped_plant_input_reports_what_the_controller_asked_for(sample_time):
    """Under [truth] u_max the u_f column holds what the plant received, at most the limit, and
    max_uf what the controller asked for, -K x_hat + F u_d before the clip (recomputed here as above,
    at the rows): a limit checked against the clipped u_f is never exceeded."""
    text = quell.paper_example().to_toml() + "\n[truth]\nu_max = [10.0, inf]\n"
    s = quell.Scenario.from_toml(text)
    d = s.design()
    r = quell.simulate(s, t_end=20.0, output_step=0.05, sample_time=sample_time, states=True)
    assert r.outcome["status"] == "completed"
    u_d = np.column_stack([delayed(r.t, r.u[:, i], tau) for i, tau in enumerate(s.plant.delays)])
    asked = (u_d @ d.F.T - r.x_hat @ d.K.T)[:, 0]
    # 1e-9 of the limit: the continuous loop reads u(t - tau) from its dense history (the rows here).
    assert np.abs(r.u_f[:, 0] - np.clip(asked, -10.0, 10.0)).max() <= 1e-9 * 10.0
    peak = np.abs(asked).max()
    max_uf = r.summary()[0]["max_uf"]
    assert peak > 12.0 and peak * (1 - 1e-9) <= max_uf <= 1.02 * peak, (peak, max_uf)
    assert r.limited_fraction[0] > 0.0
    # The figure's u_f panel says how much the controller asked for, as max_uf.
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    titles = [ax.get_title() for ax in r.plot(channel=1).axes]
    assert any(t.endswith(f"; the controller asked for up to {max_uf:.4g}") for t in titles), titles
    plt.close("all")
