"""Signal names in scenario files (`[plant]` `inputs`, `outputs`, `states`): read, written back,
checked, carried to the objects python-control sees (python-control's own `find_output` is the
independent side), and changing no number; and a Scenario built from Python values keeps speaking
Python's words (argument names, not file keys) after a pickle."""

import pickle

import numpy as np
import pytest

import quell

control = pytest.importorskip("control")

NAMES = 'inputs = ["left", "right"]\noutputs = ["pitch", "roll"]\nstates = ["a", "b", "c"]\n'


def named_paper():
    text = quell.paper_example().to_toml()
    return text.replace("[plant]\n", "[plant]\n" + NAMES, 1)


def test_a_files_names_reach_python_control():
    s = quell.Scenario.from_toml(named_paper())
    assert (s.plant.inputs, s.plant.outputs, s.plant.states) == (["left", "right"], ["pitch", "roll"], ["a", "b", "c"])
    dec = s.design().decoupled_system()
    assert dec.output_labels == ["pitch", "roll"] and dec.state_labels == ["a", "b", "c"]
    # python-control finds the channel by its name: u_d[2] → roll is G_22 = q0 / Π(s − poles).
    d = s.design()
    sub = dec[dec.find_output("roll"), dec.find_input("u_d[2]")]
    expected = d.channels[1]["q0"] / np.prod(1j - np.asarray(d.channels[1]["poles"]))
    assert abs(complex(sub(1j)) - expected) < 1e-9  # round-off of a 3-state evaluation
    assert s.design().observer_system().output_labels == ["a_hat", "b_hat", "c_hat"]
    resp = quell.simulate(s, t_end=1.0).to_control()
    assert resp.output_labels == ["pitch", "roll"]


def test_names_round_trip_through_toml_and_pickle_and_change_no_number():
    s = quell.Scenario.from_toml(named_paper())
    assert quell.Scenario.from_toml(s.to_toml()) == s
    assert pickle.loads(pickle.dumps(s)) == s
    assert s != quell.paper_example()  # names make scenarios differ
    named, plain = quell.simulate(s, t_end=2.0), quell.simulate(quell.paper_example(), t_end=2.0)
    for signal in ("t", "y", "u", "u_f", "eta"):
        np.testing.assert_array_equal(getattr(named, signal), getattr(plain, signal))
    # A file without names writes none.
    assert "inputs =" not in quell.paper_example().to_toml()


def test_a_python_plants_names_are_written_into_the_scenario_file():
    p = quell.paper_example()
    plant = quell.Plant(p.plant.A, p.plant.B, p.plant.C, p.plant.D, p.plant.Q, delays=p.plant.delays,
                        outputs=["height", "angle"])
    s = quell.Scenario(plant, p.reference, p.disturbance, t_end=1.0, **p.design().choices)
    text = s.to_toml()
    assert 'outputs = ["height", "angle"]' in text and "inputs =" not in text
    back = quell.Scenario.from_toml(text)
    assert back.plant.outputs == ["height", "angle"] and back.plant.inputs == ["u_f[1]", "u_f[2]"]


@pytest.mark.parametrize("names, key, message", [
    ('outputs = ["a", "b", "c"]', "plant.outputs", "expected 2 names (one per output), found 3"),
    ('states = ["a", "b", "a"]', "plant.states[2]", '"a" names another signal too'),
    ('inputs = ["a", ""]', "plant.inputs[1]", 'expected a name, found ""'),
    ("inputs = [1, 2]", "plant.inputs[0]", "expected a string, found an integer"),
])
def test_bad_names_in_a_file_name_their_key(names, key, message):
    text = quell.paper_example().to_toml().replace("[plant]\n", f"[plant]\n{names}\n", 1)
    with pytest.raises(quell.ScenarioError) as info:
        quell.Scenario.from_toml(text)
    assert info.value.key == key and str(info.value).startswith(f"{key}: ") and message in str(info.value)


def test_an_empty_name_from_python_is_refused_naming_the_argument():
    p = quell.paper_example().plant
    with pytest.raises(quell.ScenarioError, match=r"^inputs\[0\]: expected a name, found \" \""):
        quell.Plant(p.A, p.B, p.C, inputs=[" ", "b"])


def test_a_pickled_scenario_from_python_values_still_names_the_arguments():
    """The same bad μ: a Scenario built from values names `mu[1]` before and after a pickle; one
    read from a file names the file's key `design.mu[1]`."""
    p = quell.paper_example()
    choices = dict(p.design().choices, mu=[20.0, -1.0])
    s = quell.Scenario(p.plant, p.reference, p.disturbance, **choices)
    for scenario in (s, pickle.loads(pickle.dumps(s))):
        with pytest.raises(quell.DesignError, match=r"^mu\[1\]: "):
            scenario.design()
        with pytest.raises(quell.DesignError, match=r"^mu\[1\]: "):
            quell.simulate(scenario, t_end=1.0)
    with pytest.raises(quell.DesignError, match=r"^design\.mu\[1\]: "):
        quell.Scenario.from_toml(s.to_toml()).design()


def test_an_output_named_as_an_input_is_refused_by_the_observer_system():
    # The observer's inputs are u_f and y: python-control would merge a shared name into one
    # signal (2 inputs, 1 label), and wiring by name would leave y unconnected.
    text = named_paper().replace('outputs = ["pitch", "roll"]', 'outputs = ["left", "roll"]')
    d = quell.Scenario.from_toml(text).design()
    with pytest.raises(quell.ScenarioError, match="output 'left' is also an input's name") as e:
        d.observer_system()
    assert e.value.key == "plant.outputs"
    assert d.decoupled_system().output_labels == ["left", "roll"]  # the other systems are unaffected


def test_a_name_both_input_and_output_of_a_loop_system_is_refused():
    """An output named as the estimate of a state (`v_hat` beside a state `v`), or as the decoupled
    plant's input `u_d[1]`, had been accepted: wired by name with control.interconnect, the
    estimate was fed back as the measurement (poles -12.9, -3, -1.2 instead of -4, -3, -2;
    hostile review, 2026-12-06). Refused naming the shared signal."""
    text = named_paper()
    states = quell.Scenario.from_toml(text).plant.states
    d = quell.Scenario.from_toml(text.replace('outputs = ["pitch", "roll"]', f'outputs = ["{states[0]}_hat", "roll"]')).design()
    with pytest.raises(quell.ScenarioError, match=rf"the observer's output '{states[0]}_hat' is also one of its inputs' names") as e:
        d.observer_system()
    assert e.value.key == "plant.outputs"
    d = quell.Scenario.from_toml(text.replace('outputs = ["pitch", "roll"]', 'outputs = ["u_d[1]", "roll"]')).design()
    with pytest.raises(quell.ScenarioError, match=r"the decoupled plant's output 'u_d\[1\]' is also one of its inputs' names"):
        d.decoupled_system()
