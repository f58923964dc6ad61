#!/usr/bin/env python3
"""Writes a seeded scenario of a large plant (n states, two inputs and outputs) for timing designs.

    python3 scripts/large_plant.py 400 > g400.toml
    python3 scripts/large_plant.py 400 --poles plant > g400-at-eigenvalues.toml

The plant is the one `crates/quell/benches/design.rs` builds (same generator, same numbers):
A = diag(-1 - 0.05 r) + 0.02 U on and above the diagonal (U uniform in [-1/2, 1/2), from a 64-bit
LCG), so the eigenvalues of A are exactly its diagonal; B has two such random columns, C = B^T.
The observer poles are -1.025 - 0.05 j, between the plant's (`--poles between`, the default) or the
plant's own eigenvalues (`--poles plant`, the case where pole placement meets eigenvalues of A).
Standard library only.
"""

import argparse

MASK = (1 << 64) - 1


def uniform(state):
    """The generator's next state and a value in [-1/2, 1/2): Knuth's MMIX LCG, top 53 bits."""
    state = (state * 6364136223846793005 + 1442695040888963407) & MASK
    return state, (state >> 11) / float(1 << 53) - 0.5


def plant(n):
    """A (n x n, row-major), B (n x 2), C (2 x n), drawn in this order."""
    state, A = 1, [[0.0] * n for _ in range(n)]
    for r in range(n):
        for c in range(r, n):
            state, u = uniform(state)
            A[r][c] = -1.0 - 0.05 * r + 0.02 * u if r == c else 0.02 * u
    B = []
    for _ in range(n):
        state, b0 = uniform(state)
        state, b1 = uniform(state)
        B.append([b0, b1])
    return A, B, [[b[j] for b in B] for j in range(2)]


def matrix(M):
    return "[" + ", ".join("[" + ", ".join(repr(x) for x in row) + "]" for row in M) + "]"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("n", type=int, help="number of states (2 to 500)")
    parser.add_argument("--poles", choices=["between", "plant"], default="between")
    args = parser.parse_args()
    if not 2 <= args.n <= 500:
        parser.error(f"n: expected 2 to 500 states, found {args.n}")
    A, B, C = plant(args.n)
    if args.poles == "plant":
        poles = [A[r][r] for r in range(args.n)]
    else:
        poles = [-1.025 - 0.05 * j for j in range(args.n)]
    print("[plant]")
    print(f"A = {matrix(A)}")
    print(f"B = {matrix(B)}")
    print(f"C = {matrix(C)}")
    print("delays = [0.0, 0.0]")
    print("[design]")
    print(f"observer_poles = [{', '.join(repr(p) for p in poles)}]")
    print("channel_poles = [[-2.0], [-3.0]]")
    print("reference_filter_poles = [[-1.0], [-1.0]]")
    print("mu = [1.0, 1.0]")
    print("beta = 1.0")
    print("[reference]")
    print("components = [{ bias = 1.0 }, { bias = 1.0 }]")


if __name__ == "__main__":
    main()
