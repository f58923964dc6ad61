"""The exceptions quell raises. Messages are the library's own: the key or argument, what was
expected and what was found."""


class QuellError(Exception):
    """Base of every error quell raises on purpose."""


class ScenarioError(QuellError, ValueError):
    """A plant, scenario or simulation setting that is not valid. ``.key`` is the scenario key path
    when the error comes from a scenario (``plant.A[1]``, ``reference.components[0].bias``)."""

    key = None


class DesignError(QuellError, ValueError):
    """The designer's choices are not valid, or no design exists for the plant (the paper's
    assumptions fail)."""


class ExportError(QuellError, ValueError):
    """An argument of :func:`quell.export` that is not valid (``prefix``, ``precision``), or a C
    compiler that cannot build the FMU's binary (``compiler``)."""


class ControllerError(QuellError, ValueError):
    """A measurement or reference that :meth:`quell.Controller.step` refuses (wrong length, not finite,
    beyond ±1e100), or a controller state that overflowed (until ``reset``)."""


class SimulationError(QuellError, RuntimeError):
    """A run that did not reach t_end: it diverged or the solver's step underflowed.

    ``.t`` is the time, ``.signal`` the diverging signal (None for a solver failure), ``.value`` its
    value, and ``.result`` the SimResult with every sample computed up to then."""

    t = None
    signal = None
    value = None
    result = None
