"""Python-native behaviour: pickling (the standard library's pickle is the independent side: the
object must come back equal, and equal to one built from the same values), equality, and reprs in
Python's syntax."""

import pickle

import numpy as np

import quell
from conftest import EXAMPLES


def test_plants_pickle_and_compare():
    with_disturbance = quell.paper_example().plant
    without = quell.Plant([[0.0, 1.0], [2.0, -1.0]], [[0.0], [1.0]], [[1.0, 0.0]], delays=[0.25], x0=[0.1, 0.0])
    for p in (with_disturbance, without):
        back = pickle.loads(pickle.dumps(p))
        assert back == p and back is not p
        for name in ("A", "B", "C", "D", "Q", "delays", "x0"):
            np.testing.assert_array_equal(getattr(back, name), getattr(p, name))
    assert without != with_disturbance
    assert without != quell.Plant([[0.0, 1.0], [2.0, -1.0]], [[0.0], [1.0]], [[1.0, 0.0]], delays=[0.5])
    assert without != "a plant"


def test_scenarios_pickle_and_compare():
    for s in (quell.paper_example(), quell.Scenario.load(EXAMPLES / "three-channel.toml")):
        back = pickle.loads(pickle.dumps(s))
        assert back == s
        np.testing.assert_array_equal(back.design().K, s.design().K)
    assert quell.paper_example() != quell.Scenario.load(EXAMPLES / "three-channel.toml")


def test_reprs_are_python():
    s = quell.paper_example()
    r = quell.simulate(s, t_end=0.2)
    texts = [repr(x) for x in (s, s.plant, s.design(), r, quell.Controller(s.design(), 1e-3))]
    assert not any("Some(" in t or "None)" in t and "=None" not in t for t in texts), texts
    assert repr(s).startswith("Scenario(name='paper-example',") and "sample_time=None" in repr(s)
    assert repr(r).endswith("outcome={'status': 'completed'})")
