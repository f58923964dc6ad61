"""quell: direct adaptive output-feedback control of unstable MIMO linear plants with distinct
input delays and unknown multi-harmonic references and disturbances.

It implements C. V. Tu and N. Dudarenko, "Direct adaptive output-feedback control for unstable
linear multidimensional systems with distinct input delays" (2026); equation numbers in the
docstrings refer to that paper.

>>> import quell
>>> scenario = quell.paper_example()                 # Section VIII
>>> result = quell.simulate(scenario)                # the continuous loop, 100 s
>>> result.outcome
{'status': 'completed'}
"""

from ._errors import ControllerError, DesignError, ExportError, QuellError, ScenarioError, SimulationError
from ._study import StudyResult
from ._tune import TuneResult
from ._quell import (
    Controller,
    Design,
    Plant,
    RunSpec,
    Scenario,
    SimResult,
    Study,
    __version__,
    auto_design,
    design,
    export,
    paper_example,
    place,
    run_one,
    simulate,
    sweep,
    sweep_runs,
    tune,
    _note_interrupt,
)



def _hook_ctrl_c():
    """Python runs signal handlers in the main thread only: a simulation, sweep or design called
    from a worker thread never saw Ctrl-C and ran to its end. Count each Ctrl-C for quell's calls
    in every thread, then do what Python does. A handler of the application's own is left alone."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return
    previous = signal.getsignal(signal.SIGINT)
    if previous is not signal.default_int_handler:
        return

    def on_ctrl_c(signum, frame):
        _note_interrupt()
        previous(signum, frame)

    signal.signal(signal.SIGINT, on_ctrl_c)


_hook_ctrl_c()

__all__ = [
    "Controller",
    "ControllerError",
    "Design",
    "DesignError",
    "ExportError",
    "Plant",
    "QuellError",
    "RunSpec",
    "Scenario",
    "ScenarioError",
    "SimResult",
    "SimulationError",
    "Study",
    "StudyResult",
    "TuneResult",
    "__version__",
    "auto_design",
    "design",
    "export",
    "paper_example",
    "place",
    "run_one",
    "simulate",
    "sweep",
    "sweep_runs",
    "tune",
]
