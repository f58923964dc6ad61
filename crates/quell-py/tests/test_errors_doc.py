"""The bad-input cases of docs/errors.md, through Python: each is the paper's example with one
edit (the same edits as crates/quell/tests/scenario.rs), and each must raise ScenarioError or
DesignError (ValueError subclasses) with the key and the message that docs/errors.md shows, never a
Rust panic."""

import re

import pytest

import quell

from conftest import EXAMPLES, ROOT

DOCS = (ROOT / "docs" / "errors.md").read_text()
PAPER = (EXAMPLES / "paper.toml").read_text()

A_LINE = "A = [[-3.2, -1.7, -3.0], [2.8, 1.3, 4.0], [0.3, 0.3, -0.5]]"
B_LINE = "B = [[-2.0, 1.0], [2.0, -1.0], [1.0, 0.0]]\n"
C_LINE = "C = [[2.0, 2.0, 0.0], [2.0, 1.0, 2.0]]"
D_LINE = "D = [[1.0, -3.0], [2.0, 1.0], [3.0, 1.0]]\n"
Q_LINE = "Q = [[1.0, 2.0], [1.0, 0.0]]\n"
DELAYS = "delays = [1.0, 3.0]"
X0 = "x0 = [0.0, 0.0, 0.0]"
L_LINE = "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619], [2.7762, -1.1783]]"
CHANNEL = "channel_poles = [[-6.0, -2.0], [-4.0]]"
REF_FILTER = "reference_filter_poles = [[-1.0, -6.0], [-9.0]]"
DIST_FILTER = "disturbance_filter_poles = [[-1.0, -3.0], [-1.0, -2.0, -3.0]]"
MU = "mu = [20.0, 30.0]"
BETA = "beta = 1.0 "
REFERENCE = (
    "[reference]                                            # g(t), m components\n"
    "components = [ { harmonics = [{ amplitude = 3.0, frequency = 2.0, phase = 0.0 }] }, { bias = 2.0 } ]\n"
)
DISTURBANCE = (
    "[disturbance]                                          # omega(t), k components\n"
    "components = [ { harmonics = [{ amplitude = 1.0, frequency = 1.0 }] },\n"
    "               { bias = 1.0, harmonics = [{ amplitude = 2.0, frequency = 2.0 }] } ]\n"
)
T_END = "t_end = 100.0"
OUTPUT_STEP = "output_step = 0.1 "
SAMPLED = "# sample_time = 0.001"
NOISE = "[noise]\nstd = [0.03, 0.02]\n"


def edit(*edits, append=""):
    text = PAPER
    for old, new in edits:
        assert old in text, f"edit target not in the example: {old}"
        text = text.replace(old, new, 1)
    return text + append


# (docs/errors.md test name, scenario text, key, where docs/errors.md's example may stop)
CASES = [
    ("syntax_error", edit((C_LINE, "C = [[2.0, 2.0, 0.0], [2.0, 1.0, 2.0]")), "syntax", None),
    ("duplicate_key", edit((DELAYS, "delays = [1.0, 3.0]\ndelays = [1.0, 2.0]")), "syntax", None),
    ("unknown_top_level_key", edit(("name = ", "nmae = ")), "nmae", None),
    ("unknown_key_in_table", edit((DELAYS, "delay = [1.0, 3.0]")), "plant.delay", None),
    ("unknown_key_nested", edit(("amplitude = 3.0, frequency", "amplitude = 3.0, freq")),
     "reference.components[0].harmonics[0].freq", None),
    ("missing_table", edit((REFERENCE, "")), "reference", None),
    ("missing_key", edit((B_LINE, "")), "plant.B", None),
    ("wrong_type", edit((DELAYS, 'delays = "1, 3"')), "plant.delays", None),
    ("wrong_type_of_entry", edit(("[[-3.2, -1.7,", '[[-3.2, "-1.7",')), "plant.A[0][1]", None),
    ("matrix_without_rows", edit((C_LINE, "C = [2.0, 2.0, 0.0]")), "plant.C", None),
    ("ragged_matrix", edit(("[2.8, 1.3, 4.0]", "[2.8, 1.3]")), "plant.A[1]", None),
    ("non_square_A", edit((A_LINE, "A = [[-3.2, -1.7], [2.8, 1.3], [0.3, 0.3]]")), "plant.A", None),
    ("wrong_shape", edit((C_LINE, "C = [[2.0, 2.0], [2.0, 1.0]]")), "plant.C", None),
    ("wrong_shape_of_Q", edit((Q_LINE, "Q = [[1.0], [1.0]]\n")), "plant.Q", None),
    ("a_transposed_matrix_is_named_as_such", edit((B_LINE, "B = [[-2.0, 2.0, 1.0], [1.0, -1.0, 0.0]]\n")), "plant.B", None),
    ("empty_plant", edit((A_LINE, "A = []")), "plant.A", None),
    ("non_finite_entry", edit(("[0.3, 0.3, -0.5]", "[0.3, nan, -0.5]")), "plant.A[2][1]", None),
    ("entry_too_large", edit(("[0.3, 0.3, -0.5]", "[0.3, 0.3, -5e200]")), "plant.A[2][2]", None),
    ("infinite_entry", edit((MU, "mu = [20.0, inf]")), "design.mu[1]", None),
    ("negative_delay", edit((DELAYS, "delays = [1.0, -3.0]")), "plant.delays[1]", None),
    ("delay_count", edit((DELAYS, "delays = [1.0]")), "plant.delays", None),
    ("x0_count", edit((X0, "x0 = [0.0, 0.0]")), "plant.x0", None),
    ("missing_D_with_disturbance", edit((D_LINE, "")), "plant.D", None),
    ("missing_Q_with_D", edit((Q_LINE, "")), "plant.Q", None),
    ("missing_disturbance_with_D", edit((DISTURBANCE, "")), "disturbance", None),
    ("signal_name_count", edit((X0, X0 + '\noutputs = ["a", "b", "c"]')), "plant.outputs", None),
    ("duplicate_signal_name", edit((X0, X0 + '\nstates = ["level", "flow", "level"]')), "plant.states[2]", None),
    ("empty_signal_name", edit((X0, X0 + '\ninputs = ["valve", " "]')), "plant.inputs[1]", None),
    ("signal_name_not_a_string", edit((X0, X0 + "\ninputs = [1, 2]")), "plant.inputs[0]", None),
    ("unknown_time_unit", edit((X0, X0 + '\ntime_unit = "mins"')), "plant.time_unit", None),
    ("control_character_in_a_name", edit((X0, X0 + '\noutputs = ["gap\\n#error", "b"]')), "plant.outputs[0]", None),
    ("reference_component_count", edit((", { bias = 2.0 } ]", " ]")), "reference.components", None),
    ("disturbance_component_count",
     edit(("components = [ { harmonics = [{ amplitude = 1.0, frequency = 1.0 }] },\n", "components = [\n")),
     "disturbance.components", None),
    ("negative_frequency", edit(("frequency = 2.0, phase", "frequency = -2.0, phase")),
     "reference.components[0].harmonics[0].frequency", None),
    ("signal_too_large", edit(("amplitude = 3.0, frequency = 2.0", "amplitude = 3e300, frequency = 2.0")),
     "reference.components[0].harmonics[0].amplitude", None),
    ("missing_amplitude", edit(("amplitude = 1.0, frequency = 1.0", "frequency = 1.0")),
     "disturbance.components[0].harmonics[0].amplitude", None),
    ("reference_internal_model_order",
     edit(("{ bias = 2.0 }", "{ bias = 2.0, harmonics = [{ amplitude = 1.0, frequency = 5.0 }] }")),
     "design.reference_filter_poles[1]", None),
    ("disturbance_internal_model_order",
     edit((DIST_FILTER, "disturbance_filter_poles = [[-1.0, -3.0], [-1.0, -2.0]]")),
     "design.disturbance_filter_poles[1]", None),
    ("both_observer_choices", edit((L_LINE, L_LINE + "\nobserver_poles = [-2.0, -3.0, -4.0]")), "design", None),
    ("neither_observer_choice", edit((L_LINE, "")), "design.observer_gain", None),
    ("filter_orders_without_auto", edit((CHANNEL, CHANNEL + "\nreference_filter_orders = [2, 1]")),
     "design.reference_filter_orders", None),
    ("real_pole_written_as_pair", edit((CHANNEL, "channel_poles = [[-6.0, [-2.0, 0.0]], [-4.0]]")),
     "design.channel_poles[0][1]", None),
    ("pair_with_negative_imaginary_part", edit((CHANNEL, "channel_poles = [[[-2.0, -1.0]], [-4.0]]")),
     "design.channel_poles[0][0]", None),
    ("pole_of_wrong_form", edit((REF_FILTER, "reference_filter_poles = [[[-1.0, 2.0, 3.0]], [-9.0]]")),
     "design.reference_filter_poles[0][0]", None),
    ("flat_pole_lists", edit((CHANNEL, "channel_poles = [-6.0, -2.0, -4.0]")), "design.channel_poles", None),
    ("t_end_not_positive", edit((T_END, "t_end = 0")), "simulation.t_end", None),
    ("output_step_not_positive", edit((OUTPUT_STEP, "output_step = -0.1 ")), "simulation.output_step", None),
    ("output_step_beyond_t_end", edit((T_END, "t_end = 0.05")), "simulation.output_step", None),
    ("output_step_too_many_samples", edit((OUTPUT_STEP, "output_step = 1e-6 ")), "simulation.output_step", None),
    ("tolerance_not_positive", edit(("rtol = 1e-9", "rtol = 0.0")), "simulation.rtol", None),
    ("tolerance_out_of_range", edit(("rtol = 1e-9", "rtol = 1e-30")), "simulation.rtol", None),
    ("method_unknown", edit(("atol = 1e-9\n", 'atol = 1e-9\nmethod = "imx"\n')), "simulation.method", None),
    ("method_named_as_the_enum", edit(("atol = 1e-9\n", 'atol = 1e-9\nmethod = "Implicit"\n')),
     "simulation.method", None),
    ("precision_unknown", edit((SAMPLED, 'sample_time = 0.001\nprecision = "f16"')), "simulation.precision", None),
    ("precision_without_a_sample_time", edit(("atol = 1e-9\n", 'atol = 1e-9\nprecision = "f32"\n')),
     "simulation.precision", None),
    ("sample_time_not_positive", edit((SAMPLED, "sample_time = -0.001")), "simulation.sample_time", None),
    ("sample_time_too_many_steps", edit((SAMPLED, "sample_time = 1e-9")), "simulation.sample_time", None),
    # Python's remedy is the sample_time= argument (test_api), the file's the key.
    ("noise_without_bandwidth", edit(append=NOISE), "noise.bandwidth", ", or pass sample_time="),
    ("noise_bandwidth_not_positive", edit(append=NOISE + "bandwidth = 0\n"), "noise.bandwidth", None),
    ("noise_count", edit((SAMPLED, "sample_time = 0.001"), append="[noise]\nstd = [0.03]\n"), "noise.std", None),
    ("noise_negative", edit((SAMPLED, "sample_time = 0.001"), append="[noise]\nstd = [0.03, -0.02]\n"),
     "noise.std[1]", None),
    ("negative_seed", edit((SAMPLED, "sample_time = 0.001"), append=NOISE + "seed = -1\n"), "noise.seed", None),
    ("channel_pole_list_count", edit((CHANNEL, "channel_poles = [[-6.0, -2.0]]")), "design.channel_poles", None),
    ("reference_filter_list_count", edit((REF_FILTER, "reference_filter_poles = [[-1.0, -6.0]]")),
     "design.reference_filter_poles", None),
    ("disturbance_filter_list_count", edit((DIST_FILTER, "")), "design.disturbance_filter_poles", None),
    ("mu_count", edit((MU, "mu = [20.0]")), "design.mu", None),
    ("negative_mu", edit((MU, "mu = [20.0, -1.0]")), "design.mu[1]", None),
    ("regressor_sizes_are_checked", edit((MU, "mu = [20.0, 30.0]\nreference_sizes = [3.0]")),
     "design.reference_sizes", None),
    ("regressor_sizes_are_checked", edit((MU, "mu = [20.0, 30.0]\ndisturbance_sizes = [1.0, 0.0]")),
     "design.disturbance_sizes[1]", None),
    ("regressor_sizes_are_checked", edit((MU, "mu = [20.0, 30.0]\nreference_sizes = []")),
     "design.reference_sizes", None),
    ("beta_not_positive", edit((BETA, "beta = 0.0 ")), "design.beta", None),
    ("channel_pole_not_hurwitz", edit((CHANNEL, "channel_poles = [[-6.0, 2.0], [-4.0]]")),
     "design.channel_poles[0]", None),
    ("filter_pole_not_hurwitz", edit((REF_FILTER, "reference_filter_poles = [[[0.0, 2.0]], [-9.0]]")),
     "design.reference_filter_poles[0]", None),
    ("empty_filter_pole_list",
     edit(("[[-1.0, -3.0], [-1.0, -2.0, -3.0]]", "[[], [-1.0, -2.0, -3.0]]"),
          ("amplitude = 1.0, frequency = 1.0", "amplitude = 0.0, frequency = 1.0")),
     "design.disturbance_filter_poles[0]", None),
    ("pole_out_of_span", edit((CHANNEL, "channel_poles = [[-1e9, -2.0], [-4.0]]")), "design.channel_poles[0]", None),
    ("beta_out_of_span", edit((BETA, "beta = 1e-9 ")), "design.beta", None),
    ("channel_pole_count_vs_relative_degree", edit((CHANNEL, "channel_poles = [[-6.0], [-4.0]]")),
     "design.channel_poles[0]", None),
    ("regressor_scaling_unknown", edit((BETA, "beta = 1.0\nregressor_scaling = \"unit_dc\"\n")),
     "design.regressor_scaling", None),
    ("relative_degrees_count", edit((BETA, "beta = 1.0\nrelative_degrees = [2]\n")),
     "design.relative_degrees", None),
    ("relative_degree_not_an_integer", edit((BETA, "beta = 1.0\nrelative_degrees = [2, 1.5]\n")),
     "design.relative_degrees[1]", None),
    ("relative_degree_above_n", edit((BETA, "beta = 1.0\nrelative_degrees = [4, 1]\n")),
     "design.relative_degrees[0]", None),
    ("relative_degree_contradicts_plant",
     edit((BETA, "beta = 1.0\nrelative_degrees = [2, 2]\n"), (CHANNEL, "channel_poles = [[-6.0, -2.0], [-4.0, -5.0]]")),
     "design.relative_degrees[1]", None),
    ("observer_gain_shape", edit((L_LINE, "observer_gain = [[-8.0988, 4.4574], [10.6506, -5.0619]]")),
     "design.observer_gain", None),
    ("observer_gain_unstable", edit((L_LINE, "observer_gain = [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]")),
     "design.observer_gain", None),
    ("observer_pole_not_hurwitz", edit((L_LINE, "observer_poles = [-2.0, 3.0, -4.0]")),
     "design.observer_poles", None),
    ("observer_pole_count", edit((L_LINE, "observer_poles = [-2.0, -3.0]")), "design.observer_poles", None),
    ("uncontrollable_plant",
     edit((A_LINE, "A = [[-1.0, 0.0, 0.0], [0.0, -2.0, 0.0], [0.0, 0.0, 3.0]]"),
          (B_LINE, "B = [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]\n")),
     "plant", " (tolerance"),
]


@pytest.mark.parametrize("name,text,key,stop", CASES, ids=[c[0] for c in CASES])
def test_documented_error(name, text, key, stop):
    with pytest.raises(quell.QuellError) as info:
        quell.Scenario.from_toml(text).design()
    e = info.value
    assert isinstance(e, (quell.ScenarioError, quell.DesignError)) and isinstance(e, ValueError)
    message = str(e)
    assert message.startswith(f"{key}: "), message
    if isinstance(e, quell.ScenarioError):
        assert e.key == key
    shown = message[: message.index(stop)] if stop and stop in message else message
    assert shown in DOCS, f"docs/errors.md does not show this message:\n{message}"


def test_unreadable_file():
    with pytest.raises(quell.ScenarioError) as info:
        quell.Scenario.load("no/such/scenario.toml")
    assert info.value.key == "no/such/scenario.toml"
    assert "cannot read the file:" in str(info.value)


def test_every_documented_scenario_row_is_run_here():
    """A row added to docs/errors.md's scenario tables needs a case here too."""
    tables = DOCS.split("## Faults during a run")[0]
    documented = set(re.findall(r"^\| `(\w+)` \|", tables, flags=re.M))
    assert documented == {c[0] for c in CASES} | {"unreadable_file"}


def test_faults_during_a_run():
    """The rows of 'Faults during a run' that concern the library: SimulationError with .t and
    .signal and the samples so far; absurd sample times are ScenarioErrors."""
    s = quell.paper_example()
    with pytest.raises(quell.SimulationError) as info:
        quell.simulate(s, sample_time=0.5, output_step=0.5)
    e = info.value
    assert isinstance(e, RuntimeError)
    assert "diverged" in str(e) and e.signal and e.t > 0
    assert not abs(e.value) <= 1e9  # beyond the divergence bound, or not finite
    assert e.result.outcome["status"] == "diverged" and len(e.result) > 0 and e.result.t[-1] <= e.t
    # Named by its column of signals.csv (counted from 1), and by the state's name where the
    # scenario gives one.
    assert e.signal == "x1 (plant state)", e.signal
    named = quell.Scenario.from_toml(edit((X0, X0 + '\nstates = ["level", "flow", "heat"]')))
    with pytest.raises(quell.SimulationError) as info:
        quell.simulate(named, sample_time=0.5, output_step=0.5)
    assert info.value.signal == "x1 (plant state level)" and ": x1 (plant state level) = " in str(info.value)
    # μ_1 = 1e300, an infinitely stiff adaptive law: the step size underflows at t = 1 s.
    fast = quell.Scenario.from_toml(s.to_toml().replace("mu = [20.0, 30.0]", "mu = [1e300, 30.0]"))
    assert fast.to_toml() != s.to_toml()
    with pytest.raises(quell.SimulationError) as info:
        quell.simulate(fast, t_end=2.0)
    assert "step size underflowed" in str(info.value) and info.value.signal is None
    unchecked = quell.simulate(fast, t_end=2.0, check=False)
    assert unchecked.outcome["status"] == "step_size_too_small"
    for rtol in [1e-300, 1e-15, 1.0]:
        with pytest.raises(quell.ScenarioError, match="^rtol: expected a relative tolerance from 100 ε") as info:
            quell.simulate(s, rtol=rtol, t_end=1.0)
        assert info.value.key == "simulation.rtol"
    for T, fragment in [(1e-300, "controller steps"), (float("nan"), "expected a finite number")]:
        with pytest.raises(quell.ScenarioError, match=fragment):
            quell.simulate(s, sample_time=T)
