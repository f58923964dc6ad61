"""The paper's example (Section VIII): design, simulate 100 s, and draw Figs. 1 and 2.

    python examples/python/paper_example.py [OUT_DIR]

writes OUT_DIR/fig1.png and fig2.png (default: the current directory): each channel's output and
reference, tracking error, adaptive command and adjustable parameters, as in the paper's figures.
"""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")

import quell  # noqa: E402

out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
out.mkdir(parents=True, exist_ok=True)

scenario = quell.paper_example()
design = scenario.design()
print("relative degrees sigma =", design.sigma)
print("K =\n", design.K)
print("eig(A - BK) =", design.decoupled_eigenvalues)

result = quell.simulate(scenario)
for i, channel in enumerate(result.summary(), start=1):
    print(f"channel {i}: tail max|e| = {channel['tail_max_e']:.3e}, max|u| = {channel['max_u']:.2f}")

for channel in (1, 2):
    fig = result.plot(channel=channel)
    fig.savefig(out / f"fig{channel}.png", dpi=80)
    print("wrote", out / f"fig{channel}.png")
