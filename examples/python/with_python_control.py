"""quell beside python-control: build the plant from a control.ss, design and simulate it, and
compare quell.place with control.place on the same problem.

    python examples/python/with_python_control.py
"""

import control
import numpy as np

import quell

# The paper's plant (Section VIII) as a python-control system. Its D is the feedthrough u -> y,
# zero here; the plant's disturbance matrices D (n×k) and Q (m×k) are given to quell.Plant.
sys = control.ss(
    [[-3.2, -1.7, -3.0], [2.8, 1.3, 4.0], [0.3, 0.3, -0.5]],
    [[-2.0, 1.0], [2.0, -1.0], [1.0, 0.0]],
    [[2.0, 2.0, 0.0], [2.0, 1.0, 2.0]],
    np.zeros((2, 2)),
)
print("open-loop poles:", control.poles(sys))  # one is unstable
plant = quell.Plant(sys, D=[[1.0, -3.0], [2.0, 1.0], [3.0, 1.0]], Q=[[1.0, 2.0], [1.0, 0.0]], delays=[1.0, 3.0])

# Input delays of 1 s and 3 s, an unknown reference and disturbance: python-control has no design
# for this; quell decouples the channels and adapts to both.
scenario = quell.Scenario(
    plant,
    reference=[{"harmonics": [{"amplitude": 3.0, "frequency": 2.0}]}, {"bias": 2.0}],
    disturbance=[{"harmonics": [{"amplitude": 1.0, "frequency": 1.0}]},
                 {"bias": 1.0, "harmonics": [{"amplitude": 2.0, "frequency": 2.0}]}],
    channel_poles=[[-6, -2], [-4]],
    reference_filter_poles=[[-1, -6], [-9]],
    disturbance_filter_poles=[[-1, -3], [-1, -2, -3]],
    mu=[20, 30],
    beta=1.0,
    observer_poles=[-2, -3, -4],
    t_end=100.0,
)
design = scenario.design()
result = quell.simulate(scenario)
tail = result.t >= 90
print("tail max |e| per channel:", np.abs(result.e[tail]).max(axis=0))

# The decoupled loop A - BK as a python-control system: its poles are the channel poles.
decoupled = control.ss(design.A_f, design.B_f, sys.C, np.zeros((2, 2)))
print("poles of the decoupled plant:", np.sort(control.poles(decoupled).real))

# Pole placement: the same problem for both.
poles = [-1 + 1j, -1 - 1j, -5]
K_quell = quell.place(sys.A, sys.B, poles)
K_control = control.place(sys.A, sys.B, poles)
for name, K in [("quell.place", K_quell), ("control.place", K_control)]:
    eig = np.sort_complex(np.linalg.eigvals(sys.A - sys.B @ K))
    print(f"{name:>13}: eig(A - BK) = {np.round(eig, 10)}, |K| = {np.linalg.norm(K):.4f}")
