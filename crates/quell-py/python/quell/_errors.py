"""The exceptions quell raises. Messages are the library's own: the key or argument, what was
expected and what was found. A wrong type is Python's ``TypeError``; these are for wrong values
and failed runs."""


def a_type(obj):
    """The type of ``obj`` with its article, for messages: "an int", "a list"."""
    name = type(obj).__name__
    return ("an " if name[:1].lower() in "aeiou" else "a ") + name


class QuellError(Exception):
    """Base of every error quell raises on purpose (a wrong type is a ``TypeError`` instead).

    Examples
    --------
    >>> try:
    ...     quell.simulate(quell.paper_example(), t_end=-1.0)
    ... except quell.QuellError as e:
    ...     print(type(e).__name__, str(e))
    ScenarioError t_end: expected a final time > 0, found -1
    """


class ScenarioError(QuellError, ValueError):
    """A plant, scenario, simulation setting or study that is not valid.

    Attributes
    ----------
    key : str or None
        The scenario or study key path (``plant.A[1]``, ``simulation.t_end``,
        ``grid."design.mu[0]"[1]``) when the error comes from one; the message names the Python
        argument (``t_end``) when the value came from one.

    Examples
    --------
    >>> try:
    ...     quell.Plant([[1.0, 2.0]], [[1.0]], [[1.0]])
    ... except quell.ScenarioError as e:
    ...     print(e)
    A: expected 1×1 (n×n), found 1×2; A must be square
    """

    key = None


class DesignError(QuellError, ValueError):
    """The designer's choices are not valid, or no design exists for the plant (the paper's
    assumptions fail).

    Examples
    --------
    >>> plant = quell.paper_example().plant
    >>> try:
    ...     quell.design(plant, channel_poles=[[-6, -2], [-4]], reference_filter_poles=[[-1, -6], [-9]],
    ...                  disturbance_filter_poles=[[-1, -3], [-1, -2, -3]], mu=[20, 30], beta=0.0,
    ...                  observer_poles=[-2, -3, -4])
    ... except quell.DesignError as e:
    ...     print(str(e)[:29])
    beta: expected a finite β > 0
    """


class ControllerError(QuellError, ValueError):
    """A measurement or reference that :meth:`quell.Controller.step` refuses (wrong length, not finite,
    beyond ±1e100), or a controller state that overflowed (until ``reset``). The state is kept.

    Examples
    --------
    >>> c = quell.Controller(quell.paper_example().design(), 1e-3)
    >>> try:
    ...     c.step([0.0], [0.0, 0.0])
    ... except quell.ControllerError as e:
    ...     print(e)
    y: expected 2 entries (one per output), found 1
    """


class ExportError(QuellError, ValueError):
    """An argument of :func:`quell.export` that is not valid (``prefix``, ``precision``), or a C
    compiler that cannot build the FMU's binary (``compiler``).

    Examples
    --------
    >>> try:
    ...     quell.export(quell.paper_example().design(), 1e-3, prefix="9lives")
    ... except quell.ExportError as e:
    ...     print(str(e)[:22])
    prefix: expected a C i
    """


class SimulationError(QuellError, RuntimeError):
    """A run that did not reach t_end: it diverged, the solver's step underflowed, or it spent its
    step budget.

    Attributes
    ----------
    t : float
        The time it stopped.
    signal : str or None
        The diverging signal (None for a solver failure).
    value : float or None
        Its value.
    result : SimResult
        Every sample computed up to then.

    Examples
    --------
    >>> s = quell.Scenario.from_toml(quell.paper_example().to_toml()
    ...     + "[truth]\\nA = [[-4.16, -2.21, -3.9], [3.64, 1.69, 5.2], [0.39, 0.39, -0.65]]\\n")
    >>> try:
    ...     quell.simulate(s, max_steps=500)
    ... except quell.SimulationError as e:
    ...     print(e.result.outcome["status"], e.t == e.result.outcome["t"])
    too_many_steps True
    """

    t = None
    signal = None
    value = None
    result = None
