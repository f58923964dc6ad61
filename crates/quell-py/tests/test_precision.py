"""`precision=`: the sampled-data loop with the discrete controller's arithmetic as a
single-precision build's (`quell export --precision f32`), emulated; `simulation.precision` in files."""
import numpy as np
import pytest

import quell


def test_f32_departs_from_f64_by_rounding_and_says_how_far():
    s = quell.paper_example()
    double = quell.simulate(s, t_end=20.0, sample_time=1e-3)
    single = quell.simulate(s, t_end=20.0, sample_time=1e-3, precision="f32")
    # Rounding's magnitude: the paper's y departs by about 3e-5 of its peak (tests/export_c.rs holds
    # the emulation to the compiled f32 C), far below the 1e-3 bound and never exactly 0.
    gap = np.abs(single.y - double.y).max() / np.abs(double.y).max()
    assert 0 < gap < 1e-3, gap
    assert quell.simulate(s, t_end=20.0, sample_time=1e-3, precision="f64") == double
    assert quell.simulate(s, t_end=20.0, sample_time=1e-3, precision=None) == double


def test_a_bad_precision_is_refused_naming_the_argument():
    s = quell.paper_example()
    with pytest.raises(quell.ScenarioError, match='precision: expected "f64" or "f32", found "f16"') as e:
        quell.simulate(s, sample_time=1e-3, precision="f16")
    assert e.value.key == "simulation.precision"
    with pytest.raises(quell.ScenarioError, match="precision: f32 is the discrete controller's") as e:
        quell.simulate(s, precision="f32")
    assert e.value.key == "simulation.precision"
    with pytest.raises(TypeError, match="precision"):
        quell.simulate(s, sample_time=1e-3, precision=32)


def test_the_file_key_is_read_and_written():
    text = quell.paper_example().to_toml()
    s = quell.Scenario.from_toml(text.replace("[simulation]\n", '[simulation]\nsample_time = 0.001\nprecision = "f32"\n', 1))
    assert s.simulation["precision"] == "f32"
    assert 'precision = "f32"' in s.to_toml()
    assert quell.simulate(s, t_end=2.0) == quell.simulate(s, t_end=2.0, precision="f32")
    assert quell.simulate(s, t_end=2.0) != quell.simulate(s, t_end=2.0, precision="f64")
    # The continuous loop of the same file has no precision of its own.
    assert quell.simulate(s, t_end=2.0, continuous=True).stats["loop"] == "continuous"
    with pytest.raises(quell.ScenarioError, match="give simulation.sample_time too"):
        quell.Scenario.from_toml(text.replace("[simulation]\n", '[simulation]\nprecision = "f32"\n', 1))


def test_the_scenario_keyword():
    p = quell.paper_example()
    s = quell.Scenario(p.plant, p.reference, p.disturbance, t_end=2.0, sample_time=1e-3, precision="f32",
                       **p.design().choices)
    assert s.simulation["precision"] == "f32"
    r = quell.simulate(s)
    assert r.stats["precision"] == "f32"
    assert r == quell.simulate(s, precision="f32") != quell.simulate(s, precision="f64")
    with pytest.raises(TypeError, match="precision"):
        quell.Scenario(p.plant, p.reference, p.disturbance, sample_time=1e-3, precision=32, **p.design().choices)


def test_export_takes_the_scenarios_precision(tmp_path):
    # A scenario whose runs are f32 exports float unless precision= says otherwise, as the CLI does.
    p = quell.paper_example()
    s = quell.Scenario(p.plant, p.reference, p.disturbance, sample_time=1e-3, precision="f32", **p.design().choices)
    quell.export(s, out=tmp_path / "a")
    assert "const float y[QUELL_M]" in (tmp_path / "a" / "quell_controller.h").read_text()
    quell.export(s, out=tmp_path / "b", precision="f64")
    assert "const double y[QUELL_M]" in (tmp_path / "b" / "quell_controller.h").read_text()


def test_an_f32_export_of_a_scenario_measures_its_loop(tmp_path):
    """As `quell export --precision f32`: the scenario's loop in f32 against f64 before writing. The
    disk servo's f32 u_f departs 0.182 of its peak as compiled C (docs/deployment.md), which the
    warning's emulated figure reproduces within the 0.4–2.8× measured; the paper's example exports
    with no such warning, and a bare Design (no scenario to run) is not measured."""
    from conftest import REFERENCE

    servo = quell.Scenario.load(REFERENCE / "hdd-servo.toml")
    with pytest.warns(UserWarning, match=r"^precision f32 \(emulated") as record:
        quell.export(servo, 0.0025, out=tmp_path / "servo", precision="f32")
    line = next(str(w.message) for w in record if str(w.message).startswith("precision f32"))
    uf = float(line.split("u_f[1] by ")[1].split(",")[0])
    assert 0.182 / 2.8 <= uf <= 0.182 / 0.4, line
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        quell.export(quell.paper_example(), 1e-3, out=tmp_path / "paper", precision="f32")
        quell.export(quell.paper_example().design(), 1e-3, out=tmp_path / "design", precision="f32")
