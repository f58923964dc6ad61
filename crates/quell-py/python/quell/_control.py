"""The python-control side of quell: a design's loops as labelled ``control.StateSpace`` objects, a
``TransferFunction`` as a plant, and a result as ``control.TimeResponseData``. python-control is
imported only when one of these is called."""

import numpy as np


def _labels(name, count):
    return [f"{name}[{i + 1}]" for i in range(count)]


def _refuse_shared(system, inputs, outputs):
    """A ScenarioError naming a signal of `system` that is both an input and an output: wired by
    name (``control.interconnect``), python-control would connect the output to that input (an
    observer whose estimate of v was named as the measurement ``v_hat`` had its loop's poles at
    -12.9, -3, -1.2 instead of -4, -3, -2)."""
    shared = [name for name in outputs if name in inputs]
    if shared:
        from ._errors import ScenarioError

        error = ScenarioError(
            f"plant.outputs: {system}'s output {shared[0]!r} is also one of its inputs' names, so "
            "python-control, wiring by name, would feed it back into that input; rename the plant's "
            "signals (plant.inputs, plant.outputs, plant.states, or the inputs=/outputs=/states= "
            "keywords) so that no name is both"
        )
        error.key = "plant.outputs"
        raise error


def decoupled_system(design):
    """The delay-free decoupled plant of Proposition 1 with x̂ = x: ẋ = A_f x + B_f u_d, y = C x,
    from the (delayed) adaptive commands u_d to y. Its transfer matrix is diagonal, channel i's
    entry G_ii(s) = q_i0 / ∏_j (s − λ_ij)."""
    import control

    plant = design.plant
    m = plant.m
    _refuse_shared("the decoupled plant", _labels("u_d", m), plant.outputs)
    return control.ss(
        design.A_f,
        design.B_f,
        plant.C,
        np.zeros((m, m)),
        inputs=_labels("u_d", m),
        outputs=plant.outputs,
        states=plant.states,
        name="decoupled",
    )


def observer_system(design):
    """The Luenberger observer (6) as a system from the plant's input and output to the estimate:
    x̂' = (A − L C) x̂ + B u_f + L y, inputs u_f and y, outputs x̂ (all n states)."""
    import control

    plant = design.plant
    n, m = plant.n, plant.m
    A, B, C, L = plant.A, plant.B, plant.C, design.L
    estimates = [_hat(name) for name in plant.states]
    shared = [name for name in plant.outputs if name in plant.inputs]
    if shared:
        from ._errors import ScenarioError

        error = ScenarioError(
            f"plant.outputs: output {shared[0]!r} is also an input's name; the observer takes the "
            "inputs u_f and the outputs y as its inputs, and python-control would merge the two into "
            "one signal (leaving y unconnected), so rename one of them (plant.inputs or "
            "plant.outputs, or the inputs=/outputs= keywords)"
        )
        error.key = "plant.outputs"
        raise error
    _refuse_shared("the observer", plant.inputs + plant.outputs, estimates)
    return control.ss(
        A - L @ C,
        np.hstack([B, L]),
        np.eye(n),
        np.zeros((n, 2 * m)),
        inputs=plant.inputs + plant.outputs,
        outputs=estimates,
        states=estimates,
        name="observer",
    )


def _hat(state):
    """The estimate's name of a state: x[j] gives x_hat[j], any other name gains a _hat."""
    return "x_hat" + state[1:] if state.startswith("x[") else state + "_hat"


def state_space(sys):
    """A ``control.TransferFunction`` as a minimal ``control.StateSpace`` (pole-zero pairs cancelled
    by ``control.minreal``, then ``control.ss``, keeping ``dt``); anything else unchanged. A pair
    whose pole has Re p ≥ −√ε·|p| (on the axis to the roots' rounding) is refused: cancelling it
    hides an unstable or undamped mode (no controller can stabilize it through this input and
    output), and python-control's default tolerance also cancels pairs as far apart as 1e-5
    relative."""
    import control

    if not isinstance(sys, control.TransferFunction):
        return sys
    # Discrete first: a biproper z/(z - 0.5) had been told to be strictly proper.
    if sys.dt is not None and sys.dt is not False and (sys.dt is True or sys.dt != 0):
        raise _sys_error(
            f"sys: expected a continuous-time system (dt = 0), found dt = {sys.dt}; quell designs for "
            "continuous plants (sample the controller with Controller(design, sample_time)); a dead time "
            "is not dt: give it as the input delays, Plant(sys, delays=[...]) with a continuous sys"
        )
    for i in range(sys.noutputs):
        for j in range(sys.ninputs):
            for part, v in (("numerator", sys.num[i][j]), ("denominator", sys.den[i][j])):
                if not np.all(np.isfinite(np.asarray(v, dtype=float))):
                    where = f" (output {i + 1}, input {j + 1})" if sys.noutputs * sys.ninputs > 1 else ""
                    raise _sys_error(f"sys: the transfer function{where} has a {part} that is not finite "
                                     f"({np.asarray(v, dtype=float).tolist()}); give finite coefficients")
    for i in range(sys.noutputs):
        for j in range(sys.ninputs):
            num, den = (np.trim_zeros(np.atleast_1d(np.asarray(v, dtype=float)), "f") for v in (sys.num[i][j], sys.den[i][j]))
            if len(num) and len(num) >= len(den):
                where = f" (output {i + 1}, input {j + 1})" if sys.noutputs * sys.ninputs > 1 else ""
                raise _sys_error(
                    f"sys: the transfer function{where} has a numerator of degree {len(num) - 1} and a "
                    f"denominator of degree {len(den) - 1}: a plant (1) is strictly proper (no "
                    "feedthrough from u to y), so the numerator's degree must be below the denominator's"
                )
    eps = np.finfo(float).eps
    for i, j, p, z, k in _cancelled_pairs(sys):
        # On the axis within the roots' rounding, which grows as eps^(1/k) for a root of multiplicity
        # k: (s^2+4)/((s^2+4)(s+1)(s+3)(s+4)) has its pole at -2.1e-15+2j, which had been cancelled
        # while the same pair at lower order (+1.1e-16+2j) was refused, and a triple pair on the
        # axis came out at -2.8e-7+3j (hostile reviews, 2026-12-07).
        if p.real >= -max(np.sqrt(eps), 10.0 * eps ** (1.0 / k)) * abs(p):
            where = f" (output {i + 1}, input {j + 1})" if sys.noutputs * sys.ninputs > 1 else ""
            side = ("in the closed right half-plane" if p.real >= 0.0 else
                    "on the imaginary axis (to the rounding of its computed roots)")
            raise _sys_error(
                f"sys: the transfer function{where} has the pole {_num(p)} {side} "
                f"and the zero {_num(z)} (|p - z| = {abs(p - z):.3g}), which a minimal realization "
                "cancels: the unstable or undamped mode would be hidden, not gone; give the plant as a StateSpace "
                "(control.ss of a realization that keeps the mode) so that the design's checks see it"
            )
    try:
        reduced = control.minreal(sys, verbose=False)  # cancels pole-zero pairs (SISO: no slycot)
        realized = control.ss(reduced)
        # minreal drops the signal names: the realization gets the transfer function's.
        return control.ss(realized.A, realized.B, realized.C, realized.D, sys.dt,
                          inputs=sys.input_labels, outputs=sys.output_labels)
    # python-control's ControlMIMONotImplemented (no slycot) is a NotImplementedError.
    except (ImportError, TypeError, ValueError, NotImplementedError) as e:
        need = ("a MIMO realization needs slycot: install it, or pass a StateSpace"
                if sys.noutputs * sys.ninputs > 1 else
                "a plant (1) is strictly proper: the numerator's degree must be below the denominator's")
        raise _sys_error(
            f"sys: python-control cannot realize this {sys.noutputs}x{sys.ninputs} transfer function "
            f"as a state-space system ({e}); {need}"
        ) from e


def _sys_error(message):
    """A ``ScenarioError`` on the argument ``sys`` (its ``key``, as the library's own checks of
    ``sys`` give it)."""
    from ._errors import ScenarioError

    error = ScenarioError(message)
    error.key = "sys"
    return error


def _cancelled_pairs(sys):
    """The (output, input, pole, zero, k) pairs that ``control.minreal`` cancels, found with its own
    default tolerance (1000·max(ε, |z|·√ε)), with k the pole's multiplicity among the denominator's
    roots (those within 1e-3·|p| of it: a k-fold root's computed copies spread by about ε^(1/k))."""
    eps = np.finfo(float).eps
    pairs = []
    for i in range(sys.noutputs):
        for j in range(sys.ninputs):
            roots = np.roots(np.atleast_1d(sys.den[i][j]))
            poles = list(roots)
            for z in np.roots(np.atleast_1d(sys.num[i][j])):
                tol = 1000 * max(eps, abs(z) * np.sqrt(eps))
                near = [k for k, p in enumerate(poles) if abs(z - p) < tol]
                if near:
                    p = poles.pop(near[0])
                    k = int(np.sum(np.abs(roots - p) <= 1e-3 * max(abs(p), eps)))
                    pairs.append((i, j, p, z, max(k, 1)))
    return pairs


def _num(x):
    """A root as 1.00001 or 1 ± 2j."""
    return f"{x.real:.6g}" if x.imag == 0 else f"{x.real:.6g}{x.imag:+.6g}j"


def to_control(result, outputs, states):
    """A SimResult as ``control.TimeResponseData``: outputs y (m × samples) labelled with the
    plant's output names (``outputs``, by default y[i]), the adaptive commands u as inputs,
    labels u[i], and, where the run recorded them, the plant states x labelled ``states``; the
    title names the plant's unit of time, which python-control does not carry."""
    import control

    m, x = result.m, result.x
    recorded = {} if x is None else {"states": np.asarray(x).T, "state_labels": list(states)}
    return control.TimeResponseData(
        np.asarray(result.t),
        np.asarray(result.y).T,
        inputs=np.asarray(result.u).T,
        **recorded,
        output_labels=list(outputs),
        input_labels=_labels("u", m),
        issiso=m == 1,
        # python-control takes time in seconds: the unit of t is said where the plot shows it.
        title=f"quell simulation (t in {result.time_unit})",
        sysname="quell",
    )
