"""The plant's unit of time (`[plant] time_unit`, `Plant(..., time_unit=)`): a label carried from a
file or a keyword to the plant, the result, pickles, the scenario file written back and the plotted
t axis, that changes no number; a unit not known is a ScenarioError naming the argument."""

import pickle

import numpy as np
import pytest

import quell


def paper_in(unit):
    text = quell.paper_example().to_toml()
    return text.replace("[plant]\n", f'[plant]\ntime_unit = "{unit}"\n', 1)


def test_a_files_unit_reaches_the_plant_the_result_and_pickles_and_changes_no_number():
    s = quell.Scenario.from_toml(paper_in("minutes"))
    assert s.plant.time_unit == "min" and s.design().plant.time_unit == "min"
    assert 'time_unit = "min"' in s.to_toml() and quell.Scenario.from_toml(s.to_toml()) == s
    r = quell.simulate(s, t_end=2.0)
    plain = quell.simulate(quell.paper_example(), t_end=2.0)
    assert r.time_unit == "min" and plain.time_unit == "s"
    assert np.array_equal(r.y, plain.y) and np.array_equal(r.u_f, plain.u_f)
    back = pickle.loads(pickle.dumps(r))
    assert back == r and back.time_unit == "min"
    assert pickle.loads(pickle.dumps(s.plant)) == s.plant


def test_a_plant_keyword_sets_the_unit_and_a_scenario_from_values_writes_it():
    p = quell.paper_example().plant
    hours = quell.Plant(p.A, p.B, p.C, p.D, p.Q, delays=p.delays, time_unit="h")
    assert hours.time_unit == "h" and p.time_unit == "s" and hours != p
    text = quell.paper_example().to_toml().replace("[plant]\n", '[plant]\ntime_unit = "h"\n', 1)
    assert quell.Scenario.from_toml(text).plant == hours
    assert quell.Plant(p.A, p.B, p.C, time_unit="us").time_unit == "µs"


@pytest.mark.parametrize(
    "given, error, message",
    [
        ("mins", quell.ScenarioError, 'time_unit: expected one of "µs" (microseconds), "ms" (milliseconds), "s" (seconds), "min" (minutes), "h" (hours), "d" (days), found "mins" (did you mean "min" (minutes)?)'),
        (60, TypeError, 'time_unit: expected a str such as "min", found an int'),
    ],
)
def test_a_unit_not_known_names_the_argument(given, error, message):
    p = quell.paper_example().plant
    with pytest.raises(error) as e:
        quell.Plant(p.A, p.B, p.C, time_unit=given)
    assert str(e.value) == message


def test_the_plot_labels_t_in_the_unit():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    r = quell.simulate(quell.Scenario.from_toml(paper_in("ms")), t_end=1.0)
    fig = r.plot()
    assert fig.axes[-1].get_xlabel() == "t, ms"
    import matplotlib.pyplot as plt

    plt.close(fig)
