"""`method=`: the continuous loop's integrator from Python (`quell.simulate`, `quell.Scenario`,
`quell.Study(simulation=)`), checked against the independent solver's points of the paper's example
(crates/quell/tests/data/, accurate to about 1e-8) and against each other."""

import numpy as np
import pytest

import quell


@pytest.mark.parametrize("method", ["explicit", "imex"])
def test_each_method_matches_the_independent_reference(method, reference_points):
    # Both integrate to rtol = atol = 1e-9; the reference bound of the Rust tests is 1e-6.
    r = quell.simulate(quell.paper_example(), method=method)
    k = np.rint(reference_points[:, 0] / 0.1).astype(int)
    np.testing.assert_allclose(r.y[k], reference_points[:, 1:3], rtol=0, atol=1e-6)
    np.testing.assert_allclose(r.u[k], reference_points[:, 3:5], rtol=0, atol=1e-6)


def test_explicit_and_imex_agree_and_take_their_own_steps():
    # Not stiff at the paper's μ: DOP853 (order 8) and ARK4(3)6L[2]SA (order 4) at 1e-9 agree to
    # 1e-6 of the peak output (each within ~100·rtol·peak of the exact solution).
    s = quell.paper_example()
    explicit, imex = quell.simulate(s, t_end=20.0, method="explicit"), quell.simulate(s, t_end=20.0, method="imex")
    assert np.abs(explicit.y - imex.y).max() < 1e-6 * np.abs(explicit.y).max()
    assert explicit.stats["steps"] != imex.stats["steps"]
    # The stats say which method took the steps: all of imex's, none of DOP853's, no switch.
    assert imex.stats["implicit_steps"] == imex.stats["steps"] and explicit.stats["implicit_steps"] == 0
    assert imex.stats["switches"] == explicit.stats["switches"] == 0 and explicit.stats["thrashed"] is None
    assert explicit.stats["loop"] == "continuous"
    # "auto" (the default) is DOP853 on a loop that is not stiff: the same result bit for bit.
    assert quell.simulate(s, t_end=20.0) == explicit == quell.simulate(s, t_end=20.0, method="auto")


def test_scenario_method_round_trips_through_toml():
    p = quell.paper_example()
    s = quell.Scenario(p.plant, p.reference, p.disturbance, t_end=2.0, method="imex", **p.design().choices)
    assert s.simulation["method"] == "imex"
    assert 'method = "imex"' in s.to_toml()
    back = quell.Scenario.from_toml(s.to_toml())
    assert back.simulation == s.simulation
    assert quell.simulate(back) == quell.simulate(s, method="imex")
    assert "method" not in p.to_toml() and p.simulation["method"] == "auto"


def test_study_simulation_method_applies_to_every_run():
    study = quell.Study(quell.paper_example(), simulation={"t_end": 2.0, "method": "imex"})
    assert study.spec(0).simulate() == quell.simulate(quell.paper_example(), t_end=2.0, method="imex")
    with pytest.raises(quell.ScenarioError, match=r'^simulation\["method"\]: expected "auto".* found "imx" '
                                                   r'\(did you mean "imex"\?\)'):
        quell.Study(quell.paper_example(), simulation={"method": "imx"})


@pytest.mark.parametrize("where", ["simulate", "Scenario"])
def test_bad_method_is_a_type_error_or_a_scenario_error_naming_the_argument(where):
    p = quell.paper_example()

    def call(method):
        if where == "simulate":
            return quell.simulate(p, t_end=1.0, method=method)
        return quell.Scenario(p.plant, p.reference, p.disturbance, method=method, **p.design().choices)

    with pytest.raises(TypeError, match=r'^method: expected a str: "auto", "explicit" or "imex", found an int'):
        call(1)
    with pytest.raises(quell.ScenarioError, match=r'^method: expected "auto" \(DOP853.*found "IMEX" '
                                                   r'\(did you mean "imex"\?\)') as info:
        call("IMEX")
    assert isinstance(info.value, quell.QuellError) and info.value.key == "simulation.method"
    with pytest.raises(quell.ScenarioError, match='found "implicit" \\(did you mean "imex"\\?\\)'):
        call("implicit")


def test_method_is_refused_for_a_sampled_data_run():
    with pytest.raises(quell.ScenarioError, match=r"^method: the integrator applies to the continuous loop only"):
        quell.simulate(quell.paper_example(), t_end=1.0, sample_time=1e-3, method="imex")
    with pytest.raises(quell.ScenarioError, match=r"pass continuous=True"):
        quell.simulate(quell.paper_example(), t_end=1.0, sample_time=1e-3, method="imex")


def test_continuous_runs_the_continuous_loop_of_a_sampled_scenario():
    """continuous=True on a scenario that sets simulation.sample_time: the same samples as the same
    scenario without it (bit for bit), where the plain call runs the sampled-data loop; with
    sample_time it is refused naming the argument, and a non-bool is a TypeError."""
    text = quell.paper_example().to_toml().replace("t_end = 100.0", "t_end = 2.0")
    sampled = quell.Scenario.from_toml(text.replace("[simulation]\n", "[simulation]\nsample_time = 0.01\n", 1))
    plain = quell.Scenario.from_toml(text)
    assert sampled.simulation["sample_time"] == 0.01
    reference = quell.simulate(plain)
    assert "controller_steps" in quell.simulate(sampled).stats
    continuous = quell.simulate(sampled, continuous=True, method="imex")
    assert "steps" in continuous.stats
    np.testing.assert_array_equal(quell.simulate(sampled, continuous=True).y, reference.y)
    with pytest.raises(quell.ScenarioError, match=r"^continuous: True asks for the continuous loop") as info:
        quell.simulate(sampled, continuous=True, sample_time=0.01)
    assert info.value.key == "continuous"
    with pytest.raises(TypeError, match=r"^continuous: expected a bool"):
        quell.simulate(sampled, continuous="yes")


def test_a_sweep_over_a_rate_far_faster_than_the_loop_is_cautioned_before_its_runs():
    # β = 1e-7 puts 1/β at 1e7/s; over 0.5 s (before the first delay) the run stays cheap.
    p = quell.paper_example()
    study = quell.Study(p, grid={"design.beta": [0.01, 1e-7]}, simulation={"t_end": 0.5})
    with pytest.warns(UserWarning, match=r"^1 of the 2 grid points: the first, design.beta = 1e-7: 1/design.beta sets "):
        quell.sweep(study, jobs=1)


def test_dop853_forced_on_a_stiff_law_is_cautioned_naming_where_it_was_set():
    # μ × 5 puts channel 2 at 4.7ρ: DOP853's steps may sit at its stability bound there. Over 3.5 s,
    # beyond the delays (a horizon within one is cautioned of itself).
    p = quell.paper_example()
    choices = dict(p.design().choices, mu=[100.0, 150.0])
    stiff = quell.Scenario(p.plant, p.reference, p.disturbance, t_end=3.5, **choices)
    with pytest.warns(UserWarning, match=r'^method="explicit" on a stiff adaptive law: μλ_max = '):
        quell.simulate(stiff, method="explicit")
    in_file = quell.Scenario(p.plant, p.reference, p.disturbance, t_end=3.5, method="explicit", **choices)
    with pytest.warns(UserWarning, match=r'^simulation.method = "explicit" on a stiff adaptive law'):
        quell.simulate(in_file)
    # A study: how many runs were stiff, and the first one's run and grid values.
    study = quell.Study(p, grid={"design.mu": [[20.0, 30.0], [100.0, 150.0]]},
                        simulation={"t_end": 3.5, "method": "explicit"})
    with pytest.warns(UserWarning, match=r'^1 of the 2 runs carried out ran on DOP853 at a stiff adaptive law, .*; '
                                         r'the first, run 1, design.mu = \[100.0, 150.0\]: simulation.method = '
                                         r'"explicit" on a stiff'):
        quell.sweep(study, jobs=1)
    # A run of the study simulated again is cautioned as quell.simulate is.
    with pytest.warns(UserWarning, match=r'^simulation.method = "explicit" on a stiff adaptive law'):
        study.spec(1).simulate()
    # Nothing is said on the default method, nor at the paper's μ.
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        quell.simulate(stiff)
        quell.sweep(quell.Study(p, simulation={"t_end": 3.5, "method": "explicit"}), jobs=1)
        study.spec(0).simulate()
