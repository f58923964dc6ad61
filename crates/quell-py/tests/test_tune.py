"""quell.tune: the same searches as the CLI's `quell tune` on the same study (its tune.csv, read by
pandas, is the independent side: another front end, through a file), closed forms (the coarse
points are log-spaced between the bounds), the sweep (an evaluation's figures are those a sweep of
the same μ gives), argument errors naming the Python argument, and Ctrl-C keeping the points so
far; plus Ctrl-C during quell.run_one."""

import copy
import json
import pickle
import signal
import subprocess
import textwrap
import time

import numpy as np
import pytest

import quell
from conftest import EXAMPLES, REFERENCE

pd = pytest.importorskip("pandas")


def unstable_first_order():
    """Not the paper's plant: x' = 0.5 x + u_f(t − 0.05), y = x, tracking 1 + 0.5 sin t."""
    p = quell.Plant([[0.5]], [[1.0]], [[1.0]], delays=[0.05])
    return quell.Scenario(p, [{"bias": 1.0, "harmonics": [{"amplitude": 0.5, "frequency": 1.0}]}], t_end=20.0,
                          channel_poles=[[-2.0]], reference_filter_poles=[[-1.0, -2.0, -3.0]], mu=[10.0], beta=1.0,
                          observer_poles=[-5.0])


def test_tune_gives_the_clis_evaluations_and_choice(quell_bin, tmp_path):
    study = tmp_path / "tune.toml"
    study.write_text(textwrap.dedent(f"""\
        scenario = "{EXAMPLES / 'paper.toml'}"
        [simulation]
        t_end = 10.0
        [tune]
        objective = "tail_rms_e"
        mu = [2.0, 200.0]
        max_u = 22.0
        points = 3
        refine = 2
        """))
    out = tmp_path / "out"
    run = subprocess.run([str(quell_bin), "tune", str(study), "--out", str(out), "--no-plots", "--jobs", "1"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    cli = pd.read_csv(out / "tune.csv")
    r = quell.tune(quell.paper_example(), mu=[2.0, 200.0], objective="tail_rms_e", max_u=22.0, points=3, refine=2,
                   simulation={"t_end": 10.0}, jobs=1)
    ours = r.frame
    assert list(ours.columns) == list(cli.columns)
    # The CLI writes every number in shortest round-trip form: the same computation is equal exactly.
    for column in ("channel", "mu", "objective", "tail_max_e", "tail_rms_e", "max_u", "max_uf", "chosen"):
        np.testing.assert_array_equal(ours[column].astype(float).to_numpy(), cli[column].astype(float).to_numpy(),
                                      err_msg=column)
    assert list(ours["outcome"]) == list(cli["outcome"])
    # Empty reasons are NaN in both (the frame had "" where tune.csv read by pandas has NaN).
    assert list(ours["reason"].isna()) == list(cli["reason"].isna())
    import json

    assert r.mu == json.loads((out / "tune.json").read_text())["mu"]
    assert r.objective == "tail_rms_e" and not r.partial and r.joint is not None
    assert ours.attrs == {"partial": False}


def test_coarse_points_are_log_spaced_and_the_best_is_the_least_mu_within_the_solvers_error():
    s = unstable_first_order()
    r = quell.tune(s, mu=[1.0, 100.0], objective="tail_rms_e", points=5, refine=0, jobs=1)
    frame = r.frame
    # Closed form of the log grid: μ_k = 1 · 100^(k/4); 1e-12 relative is a few ulps of powf.
    np.testing.assert_allclose(frame["mu"], [100.0 ** (k / 4) for k in range(5)], rtol=1e-12)
    feasible = frame.dropna(subset=["objective"])
    # docs/studies.md: the least μ whose objective ties with the least, within 5 % of it or at most
    # three times rtol·ĝ + atol, ĝ = 1 + 0.5 the reference's bound.
    sim = s.simulation
    least = feasible["objective"].min()
    bound = max(1.05 * least, 3 * (sim["rtol"] * 1.5 + sim["atol"]))
    within = feasible[feasible["objective"] <= bound]
    assert len(r.best) == 1 and r.best["mu"][0] == within["mu"].min()
    # `ties` says so: the least, where it is, and the bound (to rounding of the bound's product).
    tie = r.ties[0]
    assert tie["least"] == least and tie["mu"] == feasible.loc[feasible["objective"].idxmin(), "mu"]
    assert tie["bound"] == pytest.approx(bound, rel=1e-12)
    assert r.mu == [r.best["mu"][0]] and r.reproduced == [True] and r.within_limits == [True]
    # The figures of an evaluation are those a sweep of the same μ gives (another path: the
    # study's grid); the same computation, so equal to the last bit.
    mu = float(r.best["mu"][0])
    row = quell.Study(s, grid={"design.mu[0]": [mu]}).sweep(jobs=1).frame.iloc[0]
    for figure in ("tail_rms_e", "tail_max_e", "max_u", "max_uf"):
        assert row[f"{figure}1"] == r.best[figure][0], figure


def test_results_pickle_compare_and_rebuild_from_json():
    r = quell.tune(unstable_first_order(), mu=[1.0, 10.0], points=2, refine=0, jobs=1)
    assert pickle.loads(pickle.dumps(r)) == r and quell.TuneResult(r.to_json()) == r
    assert repr(r).startswith("TuneResult(objective='settle_t', mu=[") and len(r) == 2
    with pytest.raises(quell.ScenarioError, match="^json: not a quell tuning result"):
        quell.TuneResult("{}")
    # Malformed parts the first reading does not touch (a channel or a curve point of the wrong
    # kind) had raised AttributeError, or only later from .frame.
    data = json.loads(r.to_json())
    for path, bad in [(("channels",), [1]), (("channels", 0, "curve"), "x"), (("channels", 0, "curve", 0), 3),
                      (("objective",), 5), (("mu",), ["a"])]:
        broken = copy.deepcopy(data)
        *parents, last = path
        target = broken
        for key in parents:
            target = target[key]
        target[last] = bad
        with pytest.raises(quell.ScenarioError, match="^json: not a quell tuning result"):
            quell.TuneResult(json.dumps(broken))


def test_bad_arguments_are_named_as_python_spells_them():
    s = quell.paper_example()
    cases = [
        (dict(mu=[[1.0, 2.0]]), "mu: expected 2 entries (one per channel), found 1", "tune.mu"),
        # One pair for all channels is the argument itself; one of a list per channel, its entry.
        (dict(mu=[5.0, 1.0]), "mu: expected 0 < μ_min ≤ μ_max", "tune.mu"),
        (dict(mu=[[1.0, 2.0], [5.0, 1.0]]), "mu[1]: expected 0 < μ_min ≤ μ_max", "tune.mu[1]"),
        (dict(mu=[1.0, 2.0], objective="fast"), 'objective: expected "settle_t", "tail_rms_e" or "tail_max_e"',
         "tune.objective"),
        (dict(mu=[1.0, 2.0], max_u=[1.0, 0.0]), "max_u[1]: expected a limit on max |u_i| > 0 (inf for none), found 0",
         "tune.max_u[1]"),
        (dict(mu=[1.0, 2.0], points=1), "points: expected an integer in [2, 10000], found 1", "tune.points"),
    ]
    for kwargs, start, key in cases:
        with pytest.raises(quell.ScenarioError) as info:
            quell.tune(s, **kwargs)
        assert str(info.value).startswith(start), str(info.value)
        assert info.value.key == key
    with pytest.raises(TypeError, match="^points: expected an int, found a bool"):
        quell.tune(s, mu=[1.0, 2.0], points=True)
    with pytest.raises(quell.ScenarioError, match=r"^jobs: "):
        quell.tune(s, mu=[1.0, 2.0], jobs=0)


def interrupt(python_child, code, wait):
    """Runs `code` in a child Python (the `python_child` fixture), sends SIGINT `wait` seconds after it
    prints 'ready', and returns its stdout, stderr and the seconds from the signal to its exit."""
    child = python_child(code)
    time.sleep(wait)
    sent = time.perf_counter()
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=120)
    return out, err, time.perf_counter() - sent


def test_ctrl_c_stops_a_tuning_keeping_the_points_so_far(python_child):
    """Uninterrupted, this tuning takes minutes (2 × 400 runs of 200 s); interrupted after 3 s, the
    KeyboardInterrupt carries the evaluations made (a paper-example run of 200 s takes well under
    a second even at load 10) and arrives within the 10 s allowed for a loaded machine."""
    code = textwrap.dedent("""\
        import quell
        print('ready', flush=True)
        try:
            quell.tune(quell.paper_example(), mu=[1.0, 100.0], points=400, refine=0,
                       simulation={"t_end": 200.0}, jobs=1)
            print('finished')
        except KeyboardInterrupt as e:
            print('partial', e.result.partial, len(e.result), e.result.joint is None, flush=True)
            print('limits', e.result.within_limits, flush=True)
            print('said', str(e), len(e.result.frame), flush=True)
            print('attrs', e.result.frame.attrs, flush=True)
        """)
    out, err, seconds = interrupt(python_child, code, 3.0)
    assert "finished" not in out, out
    words = out.split()
    assert words[:2] == ["partial", "True"] and int(words[2]) >= 1 and words[3] == "True", (out, err)
    # No joint run: no limit was checked, and none is said broken (it had warned of broken limits).
    assert "limits [None, None]" in out and "break limits" not in err, (out, err)
    # Said as an interrupted sweep says it (it was a bare KeyboardInterrupt), with the frame's count.
    said = next(line for line in out.splitlines() if line.startswith("said "))
    kept = said.rsplit(" ", 1)[1]
    assert said == f"said interrupted after {kept} evaluations; they are in the exception's .result (partial) {kept}", said
    # The frame says so as a sweep's does (its attrs were empty).
    assert "attrs {'partial': True}" in out, out
    assert seconds < 10


def test_ctrl_c_stops_a_sweep_keeping_the_rows_so_far(python_child):
    """As a tuning: quell.sweep and Study.sweep interrupted after 3 s raise KeyboardInterrupt whose
    .result holds the runs carried out, marked partial (they were lost). 2000 runs of 200 s take
    minutes on one thread; each run well under a second."""
    for call, frame in (("quell.sweep(study, jobs=1)", "e.result"), ("study.sweep(jobs=1)", "e.result.frame")):
        code = textwrap.dedent(f"""\
            import quell
            study = quell.Study(quell.paper_example(), simulation={{"t_end": 200.0}},
                                monte_carlo={{"runs": 2000, "seed": 1, "plant.x0": {{"normal": 0.1}}}})
            print('ready', flush=True)
            try:
                {call}
                print('finished')
            except KeyboardInterrupt as e:
                f = {frame}
                print('partial', f.attrs["partial"], len(f), sorted(set(f["outcome"])), flush=True)
                print('said', str(e), getattr(e.result, "partial", True), flush=True)
            """)
        out, err, seconds = interrupt(python_child, code, 3.0)
        assert "finished" not in out, (call, out)
        words = out.split()
        assert words[:2] == ["partial", "True"] and 1 <= int(words[2]) < 2000, (call, out, err)
        # The exception says how many runs it kept and where (it had been a bare KeyboardInterrupt).
        said = f"said interrupted after {words[2]} of 2000 runs; their rows are in the exception's .result (partial) True"
        assert said in out, (call, out, err)
        assert seconds < 10, call


def test_ctrl_c_stops_run_one_and_a_specs_simulation(python_child):
    """A run of 10⁵ s (tens of seconds) stopped after 1 s raises KeyboardInterrupt within 10 s."""
    for call in ("quell.run_one(spec)", "spec.simulate()"):
        code = textwrap.dedent(f"""\
            import quell
            study = quell.Study(quell.paper_example(), simulation={{"t_end": 1e5, "output_step": 10.0}},
                                max_steps=10**9)
            spec = study.spec(0)
            print('ready', flush=True)
            {call}
            print('finished', flush=True)
            """)
        out, err, seconds = interrupt(python_child, code, 1.0)
        assert "KeyboardInterrupt" in err and "finished" not in out, (call, out, err)
        assert seconds < 10, call


def test_a_channel_without_a_feasible_mu_is_warned_of_and_flagged():
    """`quell tune` exits 2 when a channel has no feasible μ; quell.tune returned the scenario's μ
    in silence. It now warns, naming the channel, and `feasible` says which channels had one."""
    s = unstable_first_order()
    # The limit given is named, not max_uf, which was not.
    with pytest.warns(UserWarning, match=r"^channel 1: none of the [0-9]+ μ evaluated in mu\[0\] completed with max \|u_1\| ≤ max_u\[0\] and a finite tail_rms_e \(the least max \|u_1\| of the runs with a finite tail_rms_e is [0-9.]+(e-?[0-9]+)? \(at μ = [0-9.]+\), above max_u\[0\] = 1e-6\); widen the bounds, evaluate more of them \(points\), raise the limits or lengthen t_end;") as caught:
        r = quell.tune(s, mu=[1.0, 100.0], objective="tail_rms_e", max_u=1e-6, points=3, refine=0, jobs=1)
    assert len(caught) == 1 and "is the scenario's" in str(caught[0].message)
    assert r.feasible == [False] and len(r.best) == 0 and r.ties == [None]
    assert r.mu == [10.0]  # the scenario's μ
    # No run completing (a step budget of 3): the reason, per evaluation too.
    with pytest.warns(UserWarning, match=r"^channel 1: no μ in mu\[0\] completed: none of the 3 runs did \(at μ = 1: failed, the solver needed more than 3 steps"):
        budget = quell.tune(s, mu=[1.0, 100.0], objective="tail_rms_e", max_steps=3, points=3, refine=0, jobs=1)
    assert (budget.frame["outcome"] == "failed").all() and budget.frame["reason"].str.contains("max_steps").all()
    ok = quell.tune(s, mu=[1.0, 100.0], objective="tail_rms_e", points=3, refine=0, jobs=1)
    assert ok.feasible == [True]
    assert quell.TuneResult(r.to_json()).feasible == [False]


def test_a_choice_at_an_end_of_the_bounds_is_warned_of():
    """A μ chosen at an end of its bounds may not be the best: the best may lie beyond (the CLI
    says so on the channel's line). The tail error of this loop falls as μ grows over [1, 3], so
    the best is the upper end."""
    s = unstable_first_order()
    with pytest.warns(UserWarning, match=r"^channel 1: the chosen μ, 3(\.0)?, is at the upper end of mu\[0\]") as caught:
        r = quell.tune(s, mu=[1.0, 3.0], objective="tail_rms_e", points=3, refine=0, jobs=1)
    assert len(caught) == 1 and r.mu == [3.0]


def test_a_joint_run_that_breaks_a_limit_or_misses_its_search_is_warned_of():
    """What `quell tune` exits 2 with (the tuned μ together break a limit each search kept) and what
    its line calls "does NOT reproduce it" are Python warnings too: both had returned in silence.
    On the CSTR, μ₁ = 5.48 and μ₂ = 1.46 each keep max |u_f,2| ≤ 0.16 with the other μ at the
    scenario's, and together reach 0.17. The Wood–Berry column sampled at 0.5 min: its channels
    interact through the sampling, channel 1's joint tail twice its search's (6.3e-7), which the
    continuous loop's solver tolerance had passed as reproduced, and channel 2's joint tail ten
    times below its search's, which is said without a caution."""
    cstr = quell.Scenario.load(str(REFERENCE / "cstr.toml"))
    with pytest.warns(UserWarning, match=r"^the tuned μ together break limits in the joint run \(channel 2: max \|u_f,2\| = "):
        r = quell.tune(cstr, mu=[0.3, 100.0], objective="settle_t", max_uf=[11.0, 0.16], points=9, refine=6)
    assert r.within_limits == [True, False]
    # The joint run's figure, simulated independently, is beyond the limit the warning names.
    import re
    tuned = quell.Scenario.from_toml(re.sub(r"(?m)^mu = .*$", f"mu = {list(r.mu)}", cstr.to_toml()))
    assert tuned.design().choices["mu"] == list(r.mu)
    assert np.max(np.abs(quell.simulate(tuned).u_f[:, 1])) > 0.16
    wb = quell.Scenario.load(str(REFERENCE / "wood-berry.toml"))
    with pytest.warns(UserWarning, match=r"^channel 1: the joint run with every tuned μ does not reproduce") as caught:
        w = quell.tune(wb, mu=[5.0, 500.0], objective="tail_rms_e", simulation={"sample_time": 0.5})
    assert w.reproduced == [False, False]
    assert not [c for c in caught if str(c.message).startswith("channel 2: the joint run")]


def test_a_tuning_on_dop853_reaching_a_stiff_mu_is_cautioned():
    # Channel 1's search reaches μ = [2000, 30] (37ρ), where DOP853 sits at its bound.
    with pytest.warns(UserWarning, match=r'^channel 1\'s search runs μ = \[2000, 30\]: '
                                         r'simulation.method = "explicit" on a stiff adaptive law'):
        quell.tune(quell.paper_example(), mu=[2.0, 2000.0], objective="tail_rms_e", points=2, refine=0,
                   simulation={"t_end": 0.5, "method": "explicit"}, jobs=1)
