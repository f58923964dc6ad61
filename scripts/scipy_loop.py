#!/usr/bin/env python3
"""The continuous closed loop of a quell scenario, integrated independently with SciPy.

A second implementation of the loop `quell run` integrates (plant (1), decoupling law (5), Luenberger
observer (6), internal-model observers (14) and (20), control law (25), adaptive law (33) with the
delayed, filtered regressor and command), written from the paper's equations with numpy and scipy
only. It takes the design's matrices (K, F, L, N, G_g, L_g, G_ω, G_ii(s), μ, β) from quell's design
JSON, and the plant, signals and simulation settings from the scenario file; everything else is its
own:

- the disturbance observer in the paper's coordinates: φ' = G_ω φ + (G_ω N − N A_f) x̂ − N B_f u_d,
  ξ̂_ω = φ + N x̂ (quell integrates ξ̂_ω itself);
- G_ii(s) realized by `scipy.signal.tf2ss` (quell uses the companion form of the denominator);
- Ω_i stored as a full q×q matrix (quell packs its triangle);
- the delays by the method of steps: `solve_ivp` over segments no longer than the shortest delay,
  cut at the loop's breakpoints (sums of the delays), each segment reading u_i(t − τ_i) and
  ξ̂(t − τ_i) from the dense output of the segments before it (zero before t = 0).

Usage (the design JSON from `quell design --json SCENARIO > design.json`):

    python scripts/scipy_loop.py SCENARIO.toml design.json [--out signals.csv] [--t-end T]
        [--rtol R] [--atol A] [--method DOP853|RK45] [--truth-relative r --seed s]

`--truth-relative r` multiplies every entry of the simulated plant's A by 1 + r·N(0, 1) (the law of
a study's `"truth.A" = { relative = r }`); the design keeps the nominal A. The output has the
columns t, y, g, e, u, uf and η̂ of quell's signals.csv. Needs Python ≥ 3.11 (tomllib).

A scenario's `[truth]` (another simulated plant, actuator limits or delays) is not modelled: such a
scenario is refused rather than run as its design model. The rows are `solve_ivp`'s dense output.
On an automatic F-16 short-period design at rtol = atol = 1e-10 (a helper tryout, 2026-12-06) two
or three rows in 6,000 were off by up to 8.5e-6 of u_f's peak (η̂ by 3e-7) where their neighbours
agree with quell to 1e-9 and quell's three methods and tolerances agree with each other to 3e-9;
a run with `max_step` 0.01 had its stray rows elsewhere. Not explained: compare such runs over
their medians, or at more than one tolerance, before reading a difference as quell's.
"""

from __future__ import annotations

import argparse
import bisect
import json
import math
import sys
import time
from dataclasses import dataclass
from typing import Callable, List, Optional

import numpy as np
import scipy.integrate
import scipy.signal


@dataclass
class Harmonics:
    """bias + Σ amplitude·sin(frequency·t + phase), one entry per component."""

    bias: np.ndarray
    # Per harmonic: its component, amplitude, frequency (rad/s), phase.
    component: np.ndarray
    amplitude: np.ndarray
    frequency: np.ndarray
    phase: np.ndarray

    @classmethod
    def of(cls, components: list) -> "Harmonics":
        rows = [(i, h) for i, c in enumerate(components) for h in c.get("harmonics", [])]
        return cls(
            bias=np.array([float(c.get("bias", 0.0)) for c in components]),
            component=np.array([i for i, _ in rows], dtype=int),
            amplitude=np.array([float(h["amplitude"]) for _, h in rows]),
            frequency=np.array([float(h["frequency"]) for _, h in rows]),
            phase=np.array([float(h.get("phase", 0.0)) for _, h in rows]),
        )

    def __call__(self, t: float) -> np.ndarray:
        v = self.bias.copy()
        np.add.at(v, self.component, self.amplitude * np.sin(self.frequency * t + self.phase))
        return v


class Loop:
    """The closed loop's right-hand side and its state layout:
    [x, x̂, ξ̂_g, φ, then per channel W_i (σ_i × (1 + q)), Y_i (q), Ω_i (q × q), η̂_i (q)]."""

    def __init__(self, scenario: dict, design: dict, A_true: Optional[np.ndarray] = None):
        P = scenario["plant"]
        arr = lambda v: np.atleast_2d(np.array(v, dtype=float))  # noqa: E731
        self.A, self.B, self.C = arr(P["A"]), arr(P["B"]), arr(P["C"])
        self.D, self.Q = arr(P["D"]), arr(P["Q"])
        self.A_true = self.A if A_true is None else A_true
        self.x0 = np.array(P.get("x0", np.zeros(self.A.shape[0])), dtype=float)
        self.tau = np.array(P["delays"], dtype=float)
        self.g = Harmonics.of(scenario["reference"]["components"])
        self.w = Harmonics.of(scenario["disturbance"]["components"])
        # [g; ω] = bias + S sin(frequency·t + phase), every harmonic in one call.
        self.signal_bias = np.concatenate((self.g.bias, self.w.bias))
        self.frequency = np.concatenate((self.g.frequency, self.w.frequency))
        self.phase = np.concatenate((self.g.phase, self.w.phase))
        rows = np.concatenate((self.g.component, len(self.g.bias) + self.w.component))
        self.signal_sum = np.zeros((len(self.signal_bias), len(rows)))
        self.signal_sum[rows, np.arange(len(rows))] = np.concatenate((self.g.amplitude, self.w.amplitude))
        self.K, self.F, self.L, self.N = (arr(design[k]) for k in ("K", "F", "L", "N"))
        self.G_g, self.L_g, self.G_w = arr(design["G_g"]), arr(design["L_g"]), arr(design["G_w"])
        self.mu = np.array(design["mu"], dtype=float)
        self.beta = float(design["beta"])
        n, m = self.B.shape
        q_g, q_w = self.G_g.shape[0], self.G_w.shape[0]
        self.n, self.m, self.q_g, self.q = n, m, q_g, q_g + q_w
        A_f, B_f = self.A - self.B @ self.K, self.B @ self.F
        # The linear part over core = [x, x̂, ξ̂_g, φ] and inputs v = [g; ω; u_d], with
        # u_f = −K x̂ + F u_d (5) and y = C x + Q ω substituted: core' = M core + E v.
        k, A_t, Z = self.D.shape[1], self.A_true, np.zeros
        BK = self.B @ self.K
        M = np.block(
            [
                [A_t, -BK, Z((n, q_g)), Z((n, q_w))],  # plant (1)
                [self.L @ self.C, self.A - BK - self.L @ self.C, Z((n, q_g)), Z((n, q_w))],  # observer (6)
                [Z((q_g, n)), Z((q_g, n)), self.G_g, Z((q_g, q_w))],  # reference observer (14)
                # Disturbance observer (20): φ' = G_ω φ + (G_ω N − N A_f) x̂ − N B_f u_d.
                [Z((q_w, n)), self.G_w @ self.N - self.N @ A_f, Z((q_w, q_g)), self.G_w],
            ]
        )
        E = np.block(
            [
                [Z((n, m)), self.D, B_f],
                [Z((n, m)), self.L @ self.Q, B_f],
                [self.L_g, Z((q_g, k)), Z((q_g, m))],
                [Z((q_w, m)), Z((q_w, k)), -self.N @ B_f],
            ]
        )
        self.M, self.E, self.n_core = M, E, 2 * n + q_g + q_w
        # ξ̂ = [ξ̂_g; φ + N x̂] = R core.
        self.R = np.block(
            [[Z((q_g, n)), Z((q_g, n)), np.eye(q_g), Z((q_g, q_w))], [Z((q_w, n)), self.N, Z((q_w, q_g)), np.eye(q_w)]]
        )
        # G_ii(s) = q_i0 / den_i(s), realized by SciPy (den in decreasing powers of s).
        self.filters = []
        for ch in design["channels"]:
            den = np.concatenate(([1.0], np.array(ch["denominator"], dtype=float)[::-1]))
            a, b, c, _ = scipy.signal.tf2ss([float(ch["q0"])], den)
            self.filters.append((a, b[:, 0], c[0]))
        # Offsets of the state's blocks.
        at = 0
        self.at = {}
        for name, size in [("x", n), ("xh", n), ("xg", q_g), ("phi", q_w)]:
            self.at[name] = (at, at + size)
            at += size
        self.ch = []
        for a, _, _ in self.filters:
            s, q = a.shape[0], self.q
            blocks = {}
            for name, size in [("W", s * (1 + q)), ("Y", q), ("Om", q * q), ("eta", q)]:
                blocks[name] = (at, at + size)
                at += size
            self.ch.append(blocks)
        self.dim = at

    def initial_state(self) -> np.ndarray:
        s0 = np.zeros(self.dim)
        s0[slice(*self.at["x"])] = self.x0
        return s0

    def regressor(self, s: np.ndarray) -> np.ndarray:
        """ξ̂ = [ξ̂_g; φ + N x̂]."""
        return self.R @ s[: self.n_core]

    def commands(self, s: np.ndarray) -> np.ndarray:
        """u_i = −η̂_iᵀ ξ̂ (25)."""
        xi = self.regressor(s)
        return np.array([-(s[slice(*c["eta"])] @ xi) for c in self.ch])

    def delayed(self, t: float, s: np.ndarray, past: Callable[[float], np.ndarray]):
        """u_d = [u_i(t − τ_i)] and the rows ξ̂(t − τ_i); zero before t = 0."""
        u_d = np.zeros(self.m)
        xi_d = []
        for i, (c, tau) in enumerate(zip(self.ch, self.tau)):
            r = s if tau == 0.0 else (past(t - tau) if t - tau > 0.0 else None)
            if r is None:
                xi_d.append(np.zeros(self.q))
                continue
            xi = self.regressor(r)
            u_d[i] = -(r[slice(*c["eta"])] @ xi)
            xi_d.append(xi)
        return u_d, xi_d

    def plant_input(self, s: np.ndarray, u_d: np.ndarray) -> np.ndarray:
        """u_f = −K x̂ + F u_d (5)."""
        return -self.K @ s[slice(*self.at["xh"])] + self.F @ u_d

    def rhs(self, t: float, s: np.ndarray, past: Callable[[float], np.ndarray]) -> np.ndarray:
        n, nc, q = self.n, self.n_core, self.q
        gw = self.signal_bias + self.signal_sum @ np.sin(self.frequency * t + self.phase)  # [g; ω]
        u_d, xi_d = self.delayed(t, s, past)
        ds = np.empty_like(s)
        ds[:nc] = self.M @ s[:nc] + self.E @ np.concatenate((gw, u_d))
        delta = self.C @ s[:n] + self.Q @ gw[self.m :] - gw[: self.m]  # δ = y − g
        for i, (c, (a, b, cc)) in enumerate(zip(self.ch, self.filters)):
            # G_ii(s) on the row [u_i(t − τ_i), ξ̂ᵀ(t − τ_i)]: W' = a W + b ⊗ row, output cc W.
            W = s[c["W"][0] : c["W"][1]].reshape(a.shape[0], 1 + q)
            row = np.concatenate(((u_d[i],), xi_d[i]))
            ds[c["W"][0] : c["W"][1]] = (a @ W + np.outer(b, row)).ravel()
            out = cc @ W
            eps, Delta = delta[i] - out[0], out[1:]  # ε̂_i and Δ_i (33)
            Y, Om = s[c["Y"][0] : c["Y"][1]], s[c["Om"][0] : c["Om"][1]].reshape(q, q)
            ds[c["Y"][0] : c["Y"][1]] = (Delta * eps - Y) / self.beta
            ds[c["Om"][0] : c["Om"][1]] = (np.outer(Delta, Delta) - Om).ravel() / self.beta
            ds[c["eta"][0] : c["eta"][1]] = self.mu[i] * (Y - Om @ s[c["eta"][0] : c["eta"][1]])
        return ds


def breakpoints(delays: np.ndarray, t_end: float, order: int = 4) -> List[float]:
    """Segment ends: every sum of at most `order` positive delays up to t_end, and multiples of the
    shortest delay (so that a segment reads only the segments before it)."""
    taus = sorted({float(d) for d in delays if d > 0.0})
    points = {t_end}
    if not taus:
        return [t_end]
    sums = {0.0}
    for _ in range(order):
        sums = sums | {s + d for s in sums for d in taus if s + d < t_end}
    points |= {s for s in sums if s > 0.0}
    k = 1
    while k * taus[0] < t_end:
        points.add(k * taus[0])
        k += 1
    ends = sorted(points)
    # Drop ends within rounding of the one before (τ₂ = 3τ₁ reached two ways).
    kept = [ends[0]]
    for e in ends[1:]:
        if e - kept[-1] > 1e-12 * max(1.0, e):
            kept.append(e)
    return kept


class History:
    """Dense output of the segments integrated so far."""

    def __init__(self):
        self.starts: List[float] = []
        self.solutions: list = []

    def add(self, t0: float, sol) -> None:
        self.starts.append(t0)
        self.solutions.append(sol)

    def __call__(self, t: float) -> np.ndarray:
        i = max(bisect.bisect_right(self.starts, t) - 1, 0)
        return self.solutions[i](t)


@dataclass
class Result:
    t: np.ndarray
    states: np.ndarray  # one row per output time
    rhs_evaluations: int
    steps: int
    history: History


def default_output_step(scenario: dict, t_end: float) -> float:
    """The scenario format's default output step (docs/errors.md, `output_step_not_positive`): the
    longest 1, 2 or 5 × 10^k within t_end/1000 and 2π/(20 ω_max), at least t_end/1e6."""
    freqs = [h.get("frequency", 0.0) for part in ("reference", "disturbance")
             for c in scenario.get(part, {}).get("components", []) for h in c.get("harmonics", [])
             if h.get("amplitude", 0.0) != 0.0]
    fastest = max([f for f in freqs if f > 0.0], default=0.0)
    want = min(t_end / 1000.0, 2 * math.pi / (20.0 * fastest) if fastest > 0.0 else math.inf)
    decade = 10.0 ** math.floor(math.log10(want))
    step = next((m * decade for m in (5.0, 2.0, 1.0) if m * decade <= want * (1 + 1e-12)), decade)
    return max(step, t_end / 1e6)


def simulate(loop: Loop, t_end: float, output_step: float, rtol: float, atol: float, method: str = "DOP853") -> Result:
    """The loop on [0, t_end] by the method of steps; the state at t = k·output_step."""
    history = History()
    s = loop.initial_state()
    t0 = 0.0
    t_out = np.arange(0, int(math.floor(t_end / output_step + 1e-9)) + 1) * output_step
    rows = np.empty((len(t_out), loop.dim))
    rows[0] = s
    nfev = steps = 0
    for t1 in breakpoints(loop.tau, t_end):
        sol = scipy.integrate.solve_ivp(
            lambda t, y: loop.rhs(t, y, history),
            (t0, t1),
            s,
            method=method,
            rtol=rtol,
            atol=atol,
            dense_output=True,
        )
        if sol.status != 0:
            raise RuntimeError(f"solve_ivp failed at t = {sol.t[-1]}: {sol.message}")
        nfev += sol.nfev
        steps += len(sol.t) - 1
        history.add(t0, sol.sol)
        inside = (t_out > t0) & (t_out <= t1 + 1e-12 * t1)
        if inside.any():
            rows[inside] = sol.sol(np.minimum(t_out[inside], t1)).T
        s, t0 = sol.y[:, -1], t1
    return Result(t_out, rows, nfev, steps, history)


def signals(loop: Loop, res: Result) -> dict:
    """The columns of quell's signals.csv: y, g, e = y − g, u (25), u_f (5), η̂."""
    out = {"t": res.t}
    rows: dict = {"y": [], "g": [], "u": [], "uf": []}
    for t, s in zip(res.t, res.states):
        rows["y"].append(loop.C @ s[slice(*loop.at["x"])] + loop.Q @ loop.w(t))
        rows["g"].append(loop.g(t))
        rows["u"].append(loop.commands(s))
        u_d, _ = loop.delayed(t, s, res.history)
        rows["uf"].append(loop.plant_input(s, u_d))
    y, g, u, uf = (np.array(rows[k]) for k in ("y", "g", "u", "uf"))
    for name, v in (("y", y), ("g", g), ("e", y - g), ("u", u), ("uf", uf)):
        for i in range(loop.m):
            out[f"{name}{i + 1}"] = v[:, i]
    for i, c in enumerate(loop.ch):
        for j in range(loop.q):
            out[f"eta{i + 1}_{j + 1}"] = res.states[:, c["eta"][0] + j]
    return out


def main(argv: Optional[List[str]] = None) -> int:
    import tomllib

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenario")
    ap.add_argument("design", help="quell design --json SCENARIO > design.json")
    ap.add_argument("--out", help="write the signals here (CSV)")
    ap.add_argument("--t-end", type=float)
    ap.add_argument("--rtol", type=float)
    ap.add_argument("--atol", type=float)
    ap.add_argument("--method", default="DOP853", choices=["DOP853", "RK45"])
    ap.add_argument("--truth-relative", type=float, default=0.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--runs", type=int, default=1, help="repeat the run (with --truth-relative: new draws)")
    a = ap.parse_args(argv)
    with open(a.scenario, "rb") as f:
        scenario = tomllib.load(f)
    if "truth" in scenario:
        print(f"{a.scenario}: [truth] is not modelled here (it would run the design model instead); remove it to compare", file=sys.stderr)
        return 2
    with open(a.design) as f:
        design = json.load(f)
    sim = scenario.get("simulation", {})
    t_end = a.t_end if a.t_end is not None else float(sim.get("t_end", 100.0))
    output_step = float(sim["output_step"]) if "output_step" in sim else default_output_step(scenario, t_end)
    rtol = a.rtol if a.rtol is not None else float(sim.get("rtol", 1e-6))
    atol = a.atol if a.atol is not None else float(sim.get("atol", rtol))
    rng = np.random.default_rng(a.seed)
    A = np.array(scenario["plant"]["A"], dtype=float)
    for run in range(a.runs):
        A_true = A * (1.0 + a.truth_relative * rng.standard_normal(A.shape)) if a.truth_relative else None
        loop = Loop(scenario, design, A_true)
        start, cpu = time.perf_counter(), time.process_time()
        res = simulate(loop, t_end, output_step, rtol, atol, a.method)
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
        peak = float(np.max(np.abs(res.states[:, slice(*loop.at["x"])])))
        print(f"run {run}: {res.steps} steps, {res.rhs_evaluations} RHS, {wall:.3f} s wall, {cpu:.3f} s CPU, max|x| = {peak:.4g}")
    if a.out:
        cols = signals(loop, res)
        names = list(cols)
        np.savetxt(a.out, np.column_stack([cols[k] for k in names]), delimiter=",", header=",".join(names), comments="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
