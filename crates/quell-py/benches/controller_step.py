"""Benchmark (not a test): the cost of quell.Controller.step from Python, and of quell.simulate.

    target/py-venv/bin/python crates/quell-py/benches/controller_step.py

Controller.step for the paper's example at T_s = 1 ms, with y and g as float64 numpy vectors (the
fast path) and as Python lists; the best of 7 repeats of 100,000 calls (timeit's advice: the
minimum is the figure least disturbed by other processes). Target: under 2 µs per call. Then
quell.simulate of the paper's example (100 s, rtol = atol = 1e-9), best of 7, against the same run
in Rust (`cargo bench -p quell --bench paper`).
"""

import timeit

import numpy as np

import quell

scenario = quell.paper_example()
design = scenario.design()
ctrl = quell.Controller(design, sample_time=1e-3)
y, g = np.array([0.1, 1.9]), np.array([0.0, 2.0])
yl, gl = [0.1, 1.9], [0.0, 2.0]
N = 100_000


def per_call(stmt):
    return min(timeit.repeat(stmt, number=N, repeat=7)) / N * 1e9


print(f"Controller.step(numpy y, g): {per_call(lambda: ctrl.step(y, g)):7.0f} ns per call")
print(f"Controller.step(list y, g):  {per_call(lambda: ctrl.step(yl, gl)):7.0f} ns per call")
print(f"Python call of a no-op:      {per_call(lambda: None):7.0f} ns per call (the floor)")
quell.simulate(scenario)
best = min(timeit.repeat(lambda: quell.simulate(scenario), number=1, repeat=7))
print(f"quell.simulate(paper_example()): {best * 1e3:.1f} ms (best of 7)")
